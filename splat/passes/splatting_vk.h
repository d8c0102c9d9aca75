/// @file splatting_vk.h
/// @brief The splatting renderers of docs/design.md section 4 (paper sec. 4, fig. 4):
/// `instanced`, `oit`, `hybrid` and `sorted`, over an opaque base mesh, behind the Renderer
/// interface of method_vk.h.
///
/// One frame, whatever the method:
///  1. prepare (compute, splat_prepare.comp): per impulse, its kernel's lobes placed in the world
///     (optionally EWA-widened by the pixel footprint, sigma = footprint / sqrt(12): the variance
///     of the box pixel filter the reference integrates), each lobe's screen form
///     (SpotScreenLobe: what a pixel needs, affine in the pixel, so no pixel pays for a matrix
///     product) and the kernel's oriented screen quad (the exact projected ellipses of its lobes,
///     bounded along their principal axis). A deterministic compaction lists the kernels whose
///     quad is not empty, in impulse order, and writes the indirect draw. `sorted` then sorts the
///     kept kernels back to front by the view depth of their centre of mass
///     (splat_sorted_keys.comp, then the radix sort of passes/radix_sort_vk.h).
///  2. mesh (raster): base colour (or the background), ray distance t to the mesh (R32F) and a
///     reversed float depth.
///  3. splat (raster, and compute for small kernels): one quad per kept kernel; per pixel the
///  kernel's colour and alpha along the
///     pixel's ray, through its lobes, up to the mesh (analytic optical depths, or N samples:
///     paper eq. 10). `instanced` draws the kernel opaque where alpha >= 0.5 with the depth test;
///     `oit` blends w x (premultiplied colour, alpha) additively and the optical depth into a
///     second target (McGuire and Bavoil 2013; paper eq. 11-12); `hybrid` also finds each pixel's
///     closest kernel with a 64-bit atomicMin (or, with ClosestKernel::DepthPass, in a pass of its
///     own over the same quads with a depth test before it); `sorted` blends each kernel, back to
///     front, over the base colour with premultiplied "over" (C = C_k + (1 - alpha_k) C): exact
///     compositing wherever kernels do not interpenetrate along a ray (the accuracy ceiling of
///     splatting, to show what OIT gives up). `oit`, `hybrid` (atomic) and `instanced` evaluate
///     the kernels whose quad covers at most RenderSettings::smallPixels pixel centres in a
///     compute pass instead (splat_small.comp): one invocation per kernel over its pixels, OIT
///     sums in 64-bit fixed point by integer atomics, added by the resolve.
///  4. resolve (compute): the final image (paper eq. 12 or 13) into result().
///
/// Every pipeline is specialized for its setting (lobes per kernel, analytic or N samples,
/// Lambert, projection, EWA, OIT weight, hybrid, counting, the small kernels' threshold): lavapipe
/// compiles each at its first use, and a shader carrying every path pays for the branches of all.
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
#include "splat/passes/radix_sort_vk.h"

namespace spot::splat {

enum class Method { Instanced, Oit, Hybrid, Sorted };

/// "instanced", "oit", "hybrid", "sorted".
const char* methodName(Method method);

/// The registry entry of a splatting method (its module under splat/methods/ gives the summary
/// and the settings it takes).
MethodInfo splattingMethod(Method method, std::string summary,
                           std::vector<const Setting*> settings);

class SplatRenderer final : public Renderer {
public:
    /// `scene` must outlive the renderer.
    SplatRenderer(const SceneGpu& scene, Method method);

    void prepare(const View& view, const ImpulseSet& impulses,
                 const RenderSettings& settings) override;
    void record(VkCommandBuffer cmd, PassTimer& timer) override;
    const Image& result() const override { return m_result; }
    FrameCounters counters() const override;

    Method method() const { return m_method; }
    /// Device memory the targets and buffers of a width x height frame of `capacity` impulses
    /// take (bytes), with `settings`.
    std::uint64_t frameBytes(int width, int height, std::uint32_t capacity,
                             const RenderSettings& settings) const;

private:
    /// What a pipeline is specialized for.
    struct Spec {
        std::uint32_t samples = 0;
        bool lambert = false, orthographic = false, ewa = true, hybridAtomic = false, count = false,
             closestPass = false;
        std::uint32_t weight = 0, resolve = 0;
        std::uint32_t smallPixels = 0; ///< the compute path's threshold (0: off)
        auto tie() const {
            return std::tie(samples, lambert, orthographic, ewa, hybridAtomic, count, closestPass,
                            weight, resolve, smallPixels);
        }
        bool operator<(const Spec& o) const { return tie() < o.tie(); }
    };
    struct Pipelines {
        Pipeline prepare, compact, splat, small, closest, sortKeys, resolve;
        Pipeline prepareClipped; ///< prepare's second dispatch (the kernels the first listed)
        Pipeline
            resolveList; ///< hybrid, instanced: the resolve's second dispatch (the listed pixels)
    };
    const Pipelines& pipelines(const Spec& spec, bool roofline);
    /// Whether a width x height frame's fixed-point sums fit one storage buffer binding (else
    /// `oit` and `hybrid` draw every kernel).
    bool fixedFits(std::uint64_t width, std::uint64_t height) const;
    /// Which targets a width x height frame with these settings needs beside the common ones.
    struct Targets {
        bool oit = false;    ///< the OIT accumulation and optical-depth images
        bool atomic = false; ///< the closest kernel by atomicMin (hybrid atomic, instanced)
        bool pass = false;   ///< the closest kernel by a depth pass (hybrid depth-pass)
        bool fixed = false;  ///< the compute path's fixed-point sums and tile flags
        bool list = false;   ///< the list of pixels with a closest kernel
    };
    Targets targets(std::uint64_t width, std::uint64_t height,
                    const RenderSettings& settings) const;
    /// GPU bytes of a width x height frame's targets with these settings (images, the closest
    /// kernels and their list, the fixed-point sums): what ensureTargets makes and frameBytes
    /// counts.
    std::uint64_t targetBytes(std::uint64_t width, std::uint64_t height,
                              const RenderSettings& settings) const;
    void ensureTargets(std::uint32_t width, std::uint32_t height, const RenderSettings& settings);
    void ensureBuffers(std::uint32_t capacity, const RenderSettings& settings);
    /// GPU bytes of the buffers sized per kernel (ensureBuffers), for one kernel: what
    /// ensureBuffers checks against the budget and frameBytes counts.
    std::uint64_t kernelBytes() const;

    // The passes record() records, in order (the class comment's steps).
    /// 1. Prepare and compaction, and the clears the frame's atomics need.
    void recordPrepareAndCompact(VkCommandBuffer cmd);
    /// 1b. `sorted`: the kept kernels back to front.
    void recordSort(VkCommandBuffer cmd);
    /// 2. The base mesh.
    void recordMesh(VkCommandBuffer cmd);
    /// 3a. `hybrid` with a depth pass: each pixel's closest kernel.
    void recordClosestPass(VkCommandBuffer cmd);
    /// 3. The kernels' quads, and the small kernels' compute pass.
    void recordSplat(VkCommandBuffer cmd);
    /// 4. The resolve into result().
    void recordResolve(VkCommandBuffer cmd);
    /// The colour targets the mesh pass clears and the splat pass draws into.
    std::vector<const Image*> attachments() const;
    void pushQuadDescriptors(VkCommandBuffer cmd, const Pipeline& pipeline, bool closest,
                             bool counters);
    void drawQuads(VkCommandBuffer cmd);

    const SceneGpu& m_scene;
    Context& m_ctx;
    Method m_method;
    std::map<std::pair<Spec, bool>, Pipelines> m_pipelines;
    std::unique_ptr<RadixSort> m_sort; ///< sorted only (made on first use)

    // Per image size.
    std::uint32_t m_width = 0, m_height = 0;
    Image m_base, m_distance, m_depth, m_accum, m_opticalDepth, m_closestKernel, m_closestDepth,
        m_result;
    Buffer m_closest;     ///< hybrid (atomic): uint64 per pixel
    Buffer m_closestList; ///< hybrid, instanced: SpotSplatList and a uint per pixel
    /// oit, hybrid with the compute path: the small kernels' fixed-point OIT sums
    /// (kSplatFixedChannels uint64 per pixel), zero between frames (the resolve clears what it
    /// reads); cleared once after it is made. The tiles' flags are cleared every frame.
    Buffer m_oitFixed;
    Buffer m_oitTiles; ///< with m_oitFixed: a uint per kSplatResolveTile^2 tile, non-zero where set
    bool m_oitFixedCleared = false;
    // Per impulse capacity.
    std::uint32_t m_capacity = 0;
    Buffer m_quadIndices;
    Buffer m_worldLobes, m_screenLobes, m_bounds, m_visible, m_small, m_draw, m_counters,
        m_sortKeys;
    Buffer m_clipList; ///< SpotSplatList and a uint per kernel: prepare's second dispatch
    RadixSortScratch m_sortScratch;

    // The frame prepared last.
    struct Prepared {
        gpu_splat::SpotSplatFrame frame{};
        View view;
        ImpulseSet impulses;
        RenderSettings settings;
        const Pipelines* pipelines = nullptr;
        bool sorted = false, instanced = false, closestPass = false, hybridAtomic = false;
        bool small = false; ///< the small kernels take the compute path
    } m_frame;
};

} // namespace spot::splat
