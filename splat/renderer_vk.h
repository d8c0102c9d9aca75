/// @file renderer_vk.h
/// @brief The splatting renderers of DESIGN section 4 (paper sec. 4, fig. 4): `instanced`,
/// `oit`, `hybrid` and `sorted`, over an opaque base mesh, headless on a Context.
///
/// One frame, whatever the method:
///  1. prepare (compute): per impulse, its kernel's lobes placed in the world (optionally
///     EWA-widened by the pixel footprint, sigma = footprint / sqrt(12): the variance of the box
///     pixel filter the reference integrates) and the kernel's pixel rectangle; a deterministic
///     compaction lists the kernels whose rectangle is not empty, in impulse order, and writes the
///     indirect draw. `sorted` then sorts the kept kernels back to front by the view depth of
///     their centre of mass (splat_sorted_keys.comp, then the radix sort of sort_vk.h).
///  2. mesh (raster): base colour (or the background), ray distance t to the mesh (R32F) and a
///     reversed float depth.
///  3. splat (raster): one quad per kept kernel; per pixel the kernel's colour and alpha along the
///     pixel's ray, through its lobes, up to the mesh (analytic optical depths, or N samples:
///     paper eq. 10). `instanced` draws the kernel opaque where alpha >= 0.5 with the depth test;
///     `oit` blends w x (premultiplied colour, alpha) additively and alpha into a revealage target
///     (McGuire and Bavoil 2013; paper eq. 11-12); `hybrid` also finds each pixel's closest
///     kernel with a 64-bit atomicMin (or, with ClosestKernel::DepthPass, in a pass of its own
///     over the same quads with a depth test before it); `sorted` blends each kernel, back to front, over the base
///     colour with premultiplied "over" (C = C_k + (1 - alpha_k) C): exact compositing wherever
///     kernels do not interpenetrate along a ray (the accuracy ceiling of splatting, to show what
///     OIT gives up).
///  4. resolve (compute): the final image (paper eq. 12 or 13), read back as linear float RGB.
///
/// Results are deterministic: blending in a fixed primitive order, integer atomics only, a sort
/// without atomics.
/// Units: world units; pixel (x, y) of the image is pixel (x, y) of noise::CameraRays (top-left
/// origin), sampled at its centre (no supersampling: EWA does the filtering).
#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include <glm/glm.hpp>

#include "noise/camera.h"
#include "noise/image.h"
#include "noise/kernel.h"
#include "noise/reference.h"
#include "splat/context_vk.h"
#include "splat/frame_vk.h"
#include "splat/sort_vk.h"

namespace spot::noise {
struct Mesh;
}

namespace spot::splat {

enum class Method { Instanced, Oit, Hybrid, Sorted };
/// How `hybrid` finds each pixel's closest kernel (DESIGN section 4: "measure both ways"). Both
/// find the same kernel, so the images are identical; only the cost differs.
enum class ClosestKernel {
    Atomic,   ///< in the OIT pass itself: a 64-bit atomicMin of (distance bits, kernel index)
    DepthPass ///< a separate pass over the same quads with a depth test (splat_closest.frag)
};
enum class OitWeight {
    Constant,     ///< w = 1: a plain unordered blend ("no OIT", paper fig. 3.3)
    McGuireBavoil ///< MB13 eq. 7 with z = view depth in world units (see spotOitWeight)
};

/// "instanced", "oit", "hybrid", "sorted".
const char* methodName(Method method);

struct SplatSettings {
    Method method = Method::Hybrid;
    bool ewa = true;       ///< widen lobes by the pixel footprint (anti-aliasing)
    int kernelSamples = 0; ///< 0: analytic optical depths; N in [1, 2048]: paper eq. 10's N_s
    /// The roofline instead of the method's splat pass: the same quads over the same pixels into
    /// the `oit` targets with a fragment shader that does nothing (the image is meaningless; the
    /// "splat" pass time is what lavapipe's rasterizer itself costs for this frame).
    bool roofline = false;
    OitWeight weight = OitWeight::McGuireBavoil;
    ClosestKernel closest = ClosestKernel::Atomic; ///< hybrid only
};

struct FrameStats {
    /// GPU time per pass, milliseconds: prepare (with the compaction), sort (`sorted` only), mesh,
    /// splat (every pass over the kernels' quads: the hybrid's closest-kernel depth pass too),
    /// resolve.
    std::vector<std::pair<std::string, double>> passMs;
    double totalMs = 0.0;             ///< GPU time of the frame, milliseconds
    std::uint32_t kernelsDrawn = 0;   ///< kernels with a non-empty pixel rectangle
    std::uint64_t gpuMemoryBytes = 0; ///< the context's peak allocation so far
};

class SplatRenderer {
public:
    /// Uploads the mesh (may be empty) and the kernel's lobes, builds the pipelines. Throws
    /// InputError for a kernel without lobes or with more than 8.
    SplatRenderer(Context& ctx, const noise::Mesh& mesh, const noise::Kernel& kernel);

    /// Render one frame of `count` impulses (`impulses` holds gpu::SpotImpulse[], at least
    /// `count` of them, storage-buffer usage). `background` shows where no mesh is hit;
    /// `baseColor` is the mesh's colour. Throws InputError for a bad setting, a too small buffer,
    /// or a frame that does not fit the context's memory budget.
    noise::Image render(const noise::Camera& camera, const noise::Shading& shading,
                        glm::vec3 background, glm::vec3 baseColor, const Buffer& impulses,
                        std::uint32_t count, const SplatSettings& settings,
                        FrameStats* stats = nullptr);

    /// Device memory one frame allocates (bytes), for `count` impulses at width x height with
    /// `method` (`sorted` adds its sort keys and the sort's scratch; the hybrid's depth pass its
    /// kernel index and depth targets).
    std::uint64_t frameBytes(int width, int height, std::uint32_t count,
                             Method method = Method::Hybrid,
                             ClosestKernel closest = ClosestKernel::Atomic) const;

private:
    Context& m_ctx;
    std::uint32_t m_lobeCount = 0;
    float m_support = 3.0f;
    MeshPass m_meshPass;
    Buffer m_lobes;
    Pipeline m_prepare, m_compact, m_instanced, m_oit, m_resolve, m_roofline, m_closest;
    Pipeline m_sortKeys, m_sorted;
    RadixSort m_sort;
    Timestamps m_timestamps;
};

} // namespace spot::splat
