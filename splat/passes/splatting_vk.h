/// @file splatting_vk.h
/// @brief What the four splatting methods (docs/design.md section 4; paper sec. 4, fig. 4) share:
/// `SplattingRenderer`, the base each method's renderer (splat/methods/<name>/) derives from. It
/// owns the targets and buffers every splatting frame has and records the passes they all run;
/// a method declares its own targets on the same FrameResources, builds its own pipelines and
/// records its own frame from these passes.
///
/// The passes, in a frame's order:
///  1. prepare (compute, splat_prepare.comp): per impulse, its kernel's lobes placed in the world
///     (optionally EWA-widened by the pixel footprint, sigma = footprint / sqrt(12): the variance
///     of the box pixel filter the reference integrates), each lobe's screen form
///     (SpotScreenLobe: what a pixel needs, affine in the pixel, so no pixel pays for a matrix
///     product) and the kernel's oriented screen quad (the exact projected ellipses of its lobes,
///     bounded along their principal axis). A deterministic compaction lists the kernels whose
///     quad is not empty, in impulse order, and writes the indirect draw; for the methods with a
///     compute path (instanced, oit, hybrid) it lists the small kernels apart.
///  2. mesh (raster): base colour (or the background), ray distance t to the mesh (R32F) and a
///     reversed float depth.
///  3. splat (raster, the method's): one quad per kept kernel, at its kernel's nearest depth,
///     tested against the mesh's; per pixel the kernel's colour and alpha along the pixel's ray,
///     through its lobes, up to the mesh (analytic optical depths, or N samples: paper eq. 10).
///     The small kernels' compute pass (splat_small.comp) evaluates those the compaction listed:
///     one invocation per kernel over its pixels.
///  4. resolve (compute, the method's): the final image into result().
///
/// Every pipeline is specialized for its setting (lobes per kernel, analytic or N samples,
/// Lambert, projection, EWA, OIT weight, counting, the small kernels' threshold): lavapipe
/// compiles each at its first use, and a shader carrying every path pays for the branches of all.
/// What changes the bindings a pass declares is a module of its own (shaders/CMakeLists.txt).
///
/// Results are deterministic: blending in a fixed primitive order, integer atomics only, a sort
/// without atomics.
/// Units: world units; pixel (x, y) of the image is pixel (x, y) of noise::CameraRays (top-left
/// origin), sampled at its centre (no supersampling: EWA does the filtering).
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <tuple>

#include "splat/context_vk.h"
#include "splat/method_vk.h"
#include "splat/pass_vk.h"
#include "splat/passes/light_space_vk.h"
#include "splat/passes/resources_vk.h"

namespace spot::splat {

/// The splatting methods the project ships (a name for tests and tools; the registry,
/// splat/methods/registry.h, is what lists the methods).
enum class Method { Instanced, Oit, Hybrid, Sorted };

/// "instanced", "oit", "hybrid", "sorted".
const char* methodName(Method method);

class SplattingRenderer;
/// The registry's renderer of a splatting method (made by its module, splat/methods/<name>/).
/// `scene` must outlive it.
std::unique_ptr<SplattingRenderer> makeSplattingRenderer(const SceneGpu& scene, Method method);

class SplattingRenderer : public Renderer {
public:
    void prepare(const View& view, const ImpulseSet& impulses,
                 const RenderSettings& settings) final;
    const Image& result() const final { return m_result; }
    FrameCounters counters() const final;

    /// The method's name, as in the registry.
    const std::string& name() const { return m_name; }
    /// Device memory the targets and buffers of a width x height frame of `capacity` impulses
    /// take (bytes), with `settings`.
    std::uint64_t frameBytes(int width, int height, std::uint32_t capacity,
                             const RenderSettings& settings) const;

protected:
    /// What a pipeline is specialized for.
    struct Spec {
        std::uint32_t samples = 0;
        bool lambert = false, orthographic = false, ewa = true, count = false, lit = false;
        std::uint32_t weight = 0;
        std::uint32_t smallPixels = 0; ///< the compute path's threshold (0: off)
        auto tie() const {
            return std::tie(samples, lambert, orthographic, ewa, count, weight, smallPixels, lit);
        }
        bool operator<(const Spec& o) const { return tie() < o.tie(); }
    };
    /// `name`: the method's, as in the registry; `smallPath`: it has the small kernels' compute
    /// path (the compaction lists them).
    SplattingRenderer(const SceneGpu& scene, std::string name, bool smallPath);

    // ---- What a method adds --------------------------------------------------------------
    /// The compute path's threshold for a frame (0: every kernel drawn).
    virtual std::uint32_t smallPixels(const RenderSettings& settings, Extent size) const = 0;
    /// Host side of its passes, once the common part of the frame (m_frame) is prepared: its
    /// pipelines (built or found in its cache) and what the frame's settings choose.
    virtual void preparePasses() = 0;
    /// Clears its buffers need before the splat pass (recorded before prepare's last barrier).
    virtual void recordClears(VkCommandBuffer) {}
    /// Called when the targets were made anew (a new size or set).
    virtual void targetsMade() {}
    /// Whether it draws RenderSettings::roofline frames (oit does).
    virtual bool drawsRoofline() const { return false; }

    /// Declares what `instanced` and `hybrid` share to composite each pixel's closest kernel:
    /// its key per pixel for the 64-bit atomicMin (uint64, where `atomic` says) and the
    /// resolve's list of the pixels that have one (SpotSplatList and a uint per pixel).
    void declareClosest(Buffer& closest, Buffer& list, FrameResources::Wanted atomic = {});

    // ---- Pipelines -------------------------------------------------------------------------
    Specialization specialization(const Spec& spec) const;
    /// The quads (splat_quad.vert): the bounds, the kept list and the lobes.
    GraphicsPipelineDesc quadPipeline(const Spec& spec) const;
    /// A splat pass: the quads at their kernel's nearest depth, tested against the mesh's depth
    /// (not written), so that pixels where the mesh hides the whole kernel are never shaded; the
    /// fragment shader reads the mesh distance and the counters (splatInputs).
    GraphicsPipelineDesc splatPipeline(const Spec& spec,
                                       std::span<const std::uint32_t> fragment) const;
    /// The small kernels' compute pass (`module`: the method's splat_small variant) with `extra`
    /// bindings beside the lobes, bounds, lists and mesh distance.
    Pipeline smallPipeline(const Spec& spec, std::span<const std::uint32_t> module,
                           const Bindings& extra) const;
    /// A resolve (`module`: the method's splat_resolve variant) reading `bindings` (the result
    /// is added); `listed` for its second dispatch.
    Pipeline resolvePipeline(const Spec& spec, std::span<const std::uint32_t> module,
                             Bindings bindings, bool listed) const;

    // ---- The passes ------------------------------------------------------------------------
    /// 1. Prepare and compaction, the clears the frame's atomics need (recordClears). A lit
    /// frame first builds its light-space structure (marked "light" on `timer`).
    void recordPrepareAndCompact(VkCommandBuffer cmd, PassTimer& timer);
    /// 2. The base mesh (base colour and depth stay attachments for a pass drawing over them).
    void recordMesh(VkCommandBuffer cmd);
    /// Pushes the quads' bindings plus `extra` for `pipeline` (from quadPipeline).
    void pushQuadDescriptors(VkCommandBuffer cmd, const Pipeline& pipeline, Descriptors& extra);
    /// Adds what a splat pass's fragment shader reads (splatPipeline): the mesh distance and the
    /// counters.
    Descriptors& splatInputs(Descriptors& d) const;
    /// One quad per kept kernel: the compaction's indexed indirect draw.
    void drawQuads(VkCommandBuffer cmd);
    /// The small kernels' dispatch with `extra` descriptors (after the quads' writes).
    void recordSmall(VkCommandBuffer cmd, const Pipeline& pipeline, Descriptors& extra);
    /// After the splat pass: `drawn` attachments to the general layout, and the pass's writes
    /// visible to the resolve.
    void finishSplat(VkCommandBuffer cmd, std::initializer_list<const Image*> drawn);
    /// 4. The resolve into result() over the image, reading `bindings`' images in the general
    /// layout; with `listed` (and its list) a second, indirect dispatch over the listed pixels.
    void recordResolve(VkCommandBuffer cmd, const Pipeline& resolve, Descriptors& bindings,
                       const Pipeline* listed = nullptr, const Buffer* list = nullptr);

    const SceneGpu& m_scene;
    Context& m_ctx;
    const std::string m_name;
    /// Per image size: the common targets below and the method's.
    FrameResources m_targets;
    /// Per impulse capacity: the buffers sized per kernel (the common ones and the method's).
    FrameResources m_kernels;

    Image m_base, m_distance, m_depth, m_result;
    Buffer m_worldLobes, m_screenLobes, m_bounds, m_visible, m_clipList, m_quadIndices;
    Buffer m_small; ///< the compute path's list (methods with one)
    Buffer m_draw;  ///< the quads' indirect draw, the small kernels' dispatch and their count
    Buffer m_counters;
    /// A lit frame's light-space structure (made at the first lit frame).
    std::unique_ptr<LightSpace> m_light;
    bool m_litLobes = false; ///< the world lobes hold a lit frame's second half (spot_layout.h)

    /// The frame prepared last.
    struct Frame {
        gpu_splat::SpotSplatFrame frame{};
        View view;
        ImpulseSet impulses;
        RenderSettings settings;
        Spec spec;
        std::uint32_t width = 0, height = 0;
        bool small() const { return spec.smallPixels > 0; } ///< the compute path runs
    } m_frame;

private:
    struct Common {
        Pipeline prepare, prepareClipped, compact;
    };
    /// Bytes of the buffers sized per kernel for `capacity` kernels, and the fixed ones.
    std::uint64_t kernelBytes(std::uint32_t capacity) const;
    void ensureKernels(std::uint32_t capacity);
    const bool m_smallPath;
    std::map<Spec, Common> m_common;
    const Common* m_commonPipelines = nullptr;
};

/// The registry entry of a splatting method (its module gives the summary and the settings it
/// takes).
MethodInfo splattingMethod(std::string name, std::string summary,
                           std::vector<const Setting*> settings);

} // namespace spot::splat
