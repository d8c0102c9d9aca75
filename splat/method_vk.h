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
#include "noise/kernel.h"
#include "noise/reference.h"
#include "splat/context_vk.h"
#include "splat/pass_vk.h"

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

/// How `hybrid` finds each pixel's closest kernel (docs/design.md section 4: "measure both
/// ways"). Both find the same kernel, so the images are identical; only the cost differs.
enum class ClosestKernel {
    Atomic,   ///< in the OIT pass itself: a 64-bit atomicMin of (distance bits, kernel index)
    DepthPass ///< a separate pass over the same quads with a depth test (splat_closest.frag)
};
enum class OitWeight {
    Constant,     ///< w = 1: a plain unordered blend ("no OIT", paper fig. 3.3)
    McGuireBavoil ///< MB13 eq. 7 with z = view depth in world units (see spotOitWeight)
};

/// Every method's settings, flat: a method reads the ones it uses and ignores the others (the
/// registry says which method uses which).
/// RenderSettings::smallPixels's default: kSplatSmallPixels (shaders/spot_splat.h; renderer_vk.cpp
/// holds them equal).
inline constexpr int kDefaultSmallPixels = 36;

struct RenderSettings {
    // Splatting (instanced, oit, hybrid, sorted).
    bool ewa = true;       ///< widen lobes by the pixel footprint (anti-aliasing)
    int kernelSamples = 0; ///< 0: analytic optical depths; N in [1, 2048]: paper eq. 10's N_s
    OitWeight weight = OitWeight::McGuireBavoil;       ///< oit, hybrid
    ClosestKernel closest = ClosestKernel::Atomic;     ///< hybrid
    /// oit, hybrid (atomic), instanced: a kernel whose quad's pixel box holds at most this many
    /// pixel centres is evaluated by a compute pass instead of drawn (lavapipe's cost per
    /// primitive dwarfs the few fragments of such a quad), and so is a thin quad (at most 3
    /// pixels wide) whose box holds at most kSplatMaxSmallPixels (lavapipe shades a quad in 4x4
    /// blocks, few of whose lanes a thin one fills: docs/design.md section 4); 0: every kernel is
    /// drawn. In [0, kSplatMaxSmallPixels]; the default is kSplatSmallPixels
    /// (shaders/spot_splat.h). oit and hybrid draw every kernel in frames over about 1830^2 pixels
    /// (their fixed-point sums, 40 bytes a pixel, would not fit one 128 MiB storage buffer
    /// binding).
    int smallPixels = kDefaultSmallPixels;
    /// The roofline instead of the method's splat pass: the same quads over the same pixels into
    /// the `oit` targets with a fragment shader that does nothing (the image is meaningless; the
    /// splat pass time is what lavapipe's rasterizer itself costs for this frame).
    bool roofline = false;
    /// Count the fragments each splat pass shades and the pixels where a kernel's alpha reaches
    /// 1/255 (FrameCounters); costs atomics in the fragment shader, so off unless measuring.
    bool countFragments = false;

    // Impulse generation (every method).
    double lodPixels = 0.0; ///< thin the kernels of cells smaller than this on screen (0: off)

    // Ray-march.
    int steps = 32;      ///< samples along each ray through the shell, [1, 4096]
    int supersample = 1; ///< n x n rays per pixel, box-filtered, [1, 8]
    /// Largest loop bound one march dispatch may reach (raymarch_vk.h); tests raise it past
    /// lavapipe's 65,535 to show what the guard prevents. 0: the default budget.
    std::uint32_t loopBudget = 0;
    bool cullImpulses = true; ///< skip impulses whose box misses the sample (exact)

    // Baked (baked_vk.h).
    std::string bakeFile; ///< the bake (noise/bake.h's OpenVDB file) the method renders
    int peelPasses = 4;   ///< depth-peeling layers of tetrahedra, [1, kBakedMaxPeelPasses]
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
    const Buffer& lobes() const { return m_lobes; } ///< gpu::SpotLobe[lobeCount()]
    const noise::Kernel& kernel() const { return m_kernel; }
    std::uint32_t lobeCount() const { return std::uint32_t(m_kernel.lobes.size()); }
    float support() const { return m_kernel.supportSigma; }

private:
    Context* m_ctx;
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

/// One GPU method of the registry.
struct MethodInfo {
    std::string name;    ///< as on the command line
    std::string summary; ///< one line for --help
    bool splatting = false; ///< reads RenderSettings' splatting fields
    bool marching = false;  ///< reads RenderSettings' ray-march fields
    std::function<std::unique_ptr<Renderer>(const SceneGpu&)> make;
    bool baked = false; ///< reads RenderSettings' bake fields (and needs a bake file)
};

/// Every GPU method, in the order `render --help` and the bench list them.
const std::vector<MethodInfo>& gpuMethods();
/// The method called `name`; InputError naming the methods there are.
const MethodInfo& gpuMethod(std::string_view name);
/// The method called `name`, or null.
const MethodInfo* findGpuMethod(std::string_view name);
/// "instanced, oit, hybrid, sorted, raymarch, baked".
std::string gpuMethodNames();

} // namespace spot::splat
