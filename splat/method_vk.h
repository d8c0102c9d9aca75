/// @file method_vk.h
/// @brief The one interface every GPU method sits behind (instanced, oit, hybrid, sorted,
/// raymarch, baked), the registry that names them, and what a frame hands to them.
///
/// A renderer is persistent: it owns its targets and buffers, made for one image size and
/// impulse capacity and reused by every frame like the last one (recreated when the size changes
/// or the capacity grows). A frame is two calls:
///  1. prepare(): host side only. Checks the settings, (re)creates what the size or capacity
///     needs, builds (or finds in its cache) the pipelines specialized for the settings, and does
///     whatever host work depends on a new impulse set (ImpulseSet::version). A warm frame, the
///     same size and impulses as the last one, allocates nothing here.
///  2. record(): records every pass into the caller's command buffer, with no host wait between
///     passes. The frame ends with the linear RGBA image in result().
/// The caller (splat::Frame, the editor) submits, waits, and reads the result back only when it
/// wants the pixels.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <glm/glm.hpp>

#include "noise/camera.h"
#include "noise/cells.h"
#include "noise/mesh.h"
#include "noise/image.h"
#include "noise/impulses.h"
#include "noise/kernel.h"
#include "noise/reference.h"
#include "splat/context_vk.h"
#include "splat/pass_vk.h"
#include "splat/settings.h"

namespace spot::noise {
struct Mesh;
}

namespace spot::splat {

/// What a frame shows: the camera and the scene's look (noise/scene.h's values).
struct View {
    noise::Camera camera;
    noise::Shading shading;
    glm::vec3 background{0.0f}; ///< linear RGB where no mesh is hit
    glm::vec3 baseColor{0.0f};  ///< linear RGB of the opaque base mesh
};

/// Impulses on the GPU for one frame (GpuGenerator's, or uploaded by a test).
struct ImpulseSet {
    const Buffer* impulses = nullptr; ///< gpu::SpotImpulse[capacity]; the first `count` are live
    /// uint32 at byte offset 0: the impulse count. Written on the GPU (by the generator, earlier
    /// in the same command buffer) or by the host; renderers read it on the GPU only.
    const Buffer* count = nullptr;
    std::uint32_t capacity = 0; ///< an upper bound of the count, known on the host
    /// Changes whenever the impulses change: renderers keep what depends only on the impulses
    /// (the ray-march's bins) while it stays the same.
    std::uint64_t version = 0;
    /// The surface cells the impulses were generated in, in cell order (the ray-march's shell).
    const noise::SurfaceCells* cells = nullptr;

    /// InputError, begun by `who`, unless the buffers are there and hold `capacity` impulses,
    /// at most `most` (what one frame can `verb`: "prepare", "place").
    void require(const char* who, std::uint32_t most, const char* verb) const;
};

/// GPU timestamps around a frame's passes: begin() once, then mark() at the end of each named
/// pass. Owned by whoever submits the frame.
class PassTimer {
public:
    PassTimer(Context& ctx, std::uint32_t maxPasses = 32);
    void begin(VkCommandBuffer cmd);
    /// The pass that started at the previous mark (or begin) ends here. A name given twice
    /// (a pass recorded in pieces) adds up.
    void mark(VkCommandBuffer cmd, const char* pass);
    /// After the submit completed: milliseconds per pass in recording order, and the total.
    std::vector<std::pair<std::string, double>> passMilliseconds() const;
    double totalMilliseconds() const;

private:
    Timestamps m_timestamps;
    std::uint32_t m_maxPasses;
    std::vector<std::string> m_names;
};

/// Counters a frame wrote on the GPU, read after it completed (zero where a method has none).
struct FrameCounters {
    std::uint32_t kernelsDrawn = 0;    ///< kernels that reached the splat pass
    std::uint64_t fragmentsShaded = 0; ///< RenderSettings::countFragments: splat fragments shaded
    std::uint64_t pixelsCovered = 0;   ///< ... pixels where a kernel's alpha >= 1/255, summed
    /// Method-specific numbers for the stats (the ray-march's loop bound and dispatches, ...).
    std::vector<std::pair<std::string, double>> extra;
};

/// The scene's GPU data every method reads: the base mesh (and its pass) and the kernel's lobes.
class SceneGpu {
public:
    /// Uploads the mesh (may be empty) and the kernel; InputError for 0 or more than 8 lobes.
    SceneGpu(Context& ctx, const noise::Mesh& mesh, const noise::Kernel& kernel);
    Context& context() const { return *m_ctx; }
    const MeshPass& meshPass() const { return m_meshPass; }
    /// The same, for the frame that poses an animated mesh into it (splat/deform_vk.h).
    MeshPass& posedMeshPass() { return m_meshPass; }
    const Buffer& lobes() const { return m_lobes; } ///< gpu::SpotLobe[lobeCount()]
    const noise::Kernel& kernel() const { return m_kernel; }
    std::uint32_t lobeCount() const { return std::uint32_t(m_kernel.lobes.size()); }
    float support() const { return m_kernel.supportSigma; }
    /// The mesh's bounds as handed in (at rest).
    const noise::Bounds& meshBounds() const { return m_meshBounds; }
    /// noise::meshHash of the mesh as handed in (a bake is checked against it).
    std::uint64_t meshHash() const { return m_meshHash; }

private:
    Context* m_ctx;
    std::uint64_t m_meshHash = 0;
    noise::Bounds m_meshBounds;
    noise::Kernel m_kernel;
    MeshPass m_meshPass;
    Buffer m_lobes;
};

class Renderer {
public:
    virtual ~Renderer() = default;
    /// Host side of a frame (file comment). Throws InputError for a bad setting, a frame beyond
    /// the memory budget, or impulses the method cannot take.
    virtual void prepare(const View& view, const ImpulseSet& impulses,
                         const RenderSettings& settings) = 0;
    /// Record the frame prepared last into `cmd`, marking each pass on `timer`. The result is
    /// in result() (kColorFormat, general layout, written by the last pass: a compute shader)
    /// once the frame completed.
    virtual void record(VkCommandBuffer cmd, PassTimer& timer) = 0;
    virtual const Image& result() const = 0;
    /// After the frame completed.
    virtual FrameCounters counters() const = 0;
    /// Whether prepare() needs the impulses on the GPU already (it reads them on the host when
    /// their version changes: the ray-march's bins). The caller then submits the generation on
    /// its own before prepare().
    virtual bool readsImpulsesInPrepare() const { return false; }
};

/// What a CPU method renders from: the scene on the host.
struct CpuScene {
    const noise::Mesh& mesh;
    const noise::Kernel& kernel;
    const std::vector<noise::Impulse>& impulses;
    View view;
    std::uint32_t seed = 0;
    int spp = 1; ///< the scene's samples per pixel (RenderSettings::spp 0 takes these)
};
/// What a CPU method rendered.
struct CpuFrame {
    noise::Image image;
    double seconds = 0.0;
    std::size_t kernels = 0;
    /// Numbers for --stats, in order (integers are written as such).
    std::vector<std::pair<std::string, double>> stats;
    std::string summary; ///< for render's closing line
};
/// Called with (done, total) as a CPU method progresses.
using Progress = std::function<void(int, int)>;

/// One method of the registry: its name, the settings it takes, and how it renders. A GPU method
/// makes a Renderer (driven by splat::Frame); a CPU method renders on the host from the scene's
/// impulses.
struct MethodInfo {
    std::string name;    ///< as on the command line
    std::string summary; ///< one line for --help
    /// The settings it takes; any other given to it is refused (render, the script's `method`).
    std::vector<const Setting*> settings;
    /// GPU methods: a renderer for `scene`.
    std::function<std::unique_ptr<Renderer>(const SceneGpu&)> make;
    /// CPU methods: the image of `scene`.
    std::function<CpuFrame(const CpuScene&, const RenderSettings&, const Progress&)> renderCpu;
    /// What render's closing line says of the settings (e.g. "32 steps, 2x2 rays per pixel, "),
    /// empty when nothing.
    std::function<std::string(const RenderSettings&)> summarize;

    /// Whether its frames draw the impulses' kernels (render's "N drawn"); `baked` marches its
    /// bake instead.
    bool drawsKernels = true;
    /// Whether it renders lit scenes (shading.mode "lit"); render refuses the others before the
    /// device starts (requireLitSupport).
    bool rendersLit = false;

    bool gpu() const { return bool(make); }
    bool takes(const Setting& setting) const;
    bool takes(std::string_view setting) const;
};

/// InputError unless `method` renders scenes shaded as `shading` (MethodInfo::rendersLit).
void requireLitSupport(const MethodInfo& method, const noise::Shading& shading);

/// Every method, reference included, in the order `render --help` and the bench list them.
const std::vector<MethodInfo>& methods();
/// The method called `name`; InputError naming the methods there are.
const MethodInfo& method(std::string_view name);
/// The method called `name`, or null.
const MethodInfo* findMethod(std::string_view name);
/// "reference, instanced, oit, hybrid, sorted, raymarch, baked".
std::string methodNames();
/// Every setting some method takes, once each, in the registry's order.
std::vector<const Setting*> allSettings();
/// The names of the methods that take `setting` ("oit, hybrid").
std::string methodsTaking(const Setting& setting);

/// The GPU methods alone (what splat::Frame and the editor draw with), in the registry's order.
const std::vector<MethodInfo>& gpuMethods();
/// The GPU method called `name`; InputError naming the methods there are.
const MethodInfo& gpuMethod(std::string_view name);
/// The GPU method called `name`, or null.
const MethodInfo* findGpuMethod(std::string_view name);
/// "instanced, oit, hybrid, sorted, raymarch, baked".
std::string gpuMethodNames();

} // namespace spot::splat
