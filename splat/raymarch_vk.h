/// @file raymarch_vk.h
/// @brief The `raymarch` method of DESIGN section 4: the baseline the paper beats (paper sec. 4,
/// eq. 7-9). Each pixel's ray is marched through the shell, and at every step the kernels of the
/// 27 cells around the sample are summed.
///
/// One frame:
///  1. prepare (compute): each impulse's lobes placed in the world (the splat renderer's
///     splat_prepare.comp, without EWA widening: a widened lobe could reach past the 3x3x3 cells
///     that the march searches).
///  2. bin (compute, raymarch_bin.comp): each impulse's shell cell (hash lookup) and, per cell,
///     the range of impulses it holds. Read back; on the host: the impulse order is checked and
///     every shell cell gets the ranges of its 27 neighbours (at most 9 ranges: the three cells of
///     one column are contiguous in cell order). Then the loop guard (below).
///  3. mesh (raster): the opaque base mesh's colour and ray distance (splat_mesh.vert/frag).
///  4. march (compute, raymarch_march.comp): per ray, the shell segments by a cell walk (3D DDA)
///     over the shell's bounding box, then N samples evenly spaced over the segments laid end to
///     end, front-to-back emission-absorption with alpha = 1 - exp(-sigma dt) (eq. 9's 0-order
///     attenuation). Lambert normals: the normalized negative gradient of the summed density of
///     all neighbouring lobes, as in the reference. The N steps are split over as many dispatches
///     as the loop guard needs (below); each continues from the radiance and transmittance the
///     previous one left, with the same arithmetic, so the split never changes the image.
///  5. resolve (compute, raymarch_resolve.comp): with supersampling n the mesh pass and the march
///     run at n times the resolution (n x n rays per pixel through sub-pixel centres); each
///     output pixel is the mean of its n x n rays, each over the mesh colour behind it (a box
///     filter, the reference's). One ray per pixel aliases thin strands: they are hit or missed
///     as the camera moves, which the bench's temporal flicker shows.
///
/// The shell is the set of surface cells dilated by one cell (about 3x the surface cells); memory
/// grows with the surface: per shell cell 96 bytes of ranges, 32 to 64 bytes of hash table (more
/// if the table had to grow to keep probes short) and 12 bytes of bins; per kernel its world
/// lobes (64 bytes each).
///
/// Not done here: per-cell lists of the impulses whose support reaches each cell (instead of all
/// 27 neighbours' impulses, each tested against its box at every sample) and per-cell occupied
/// boxes to tighten the segments. Both would make a better renderer than the paper's baseline,
/// which this one is meant to be; the box test only skips work whose result is exactly zero.
///
/// The loop guard. lavapipe silently stops a shader invocation after 65,535 loop iterations (the
/// image comes back wrong, with no error). Before the march is dispatched, the host bounds the
/// iterations any invocation can run (raymarch_shared.glsl explains the accounting):
///
///     bound(N) = 1 + W (P + 3)  +  1 + N (S + P + 4 + T (L + 2))
///
/// with W the cells a ray can cross in the shell's bounding box (its extents in cells summed),
/// P the longest hash probe (slots past a key's home slot), S = kMarchMaxSegments, L the lobes per
/// kernel and T the most impulses any shell cell has in its 27 neighbours. (At each sample an
/// impulse whose box does not hold it is skipped, lobes and all: exact, and several times faster
/// than summing every lobe, though the bound must assume all are summed.) The march is split into
/// dispatches of at most N' steps, N' the largest with bound(N') within the budget
/// (kMarchLoopBudget = 60,000 by default); a frame where not even one step fits (about 59,000
/// lobes around one sample) is refused with an InputError that says why. The shader counts its
/// own loops with the same accounting (RaymarchStats::maxLoopIterations, the most in one
/// dispatch), so tests hold the bound against what really ran.
///
/// Results are deterministic: no float atomics, every pixel independent, sums in a fixed order.
/// Units: world units; pixel (x, y) of the image is pixel (x, y) of noise::CameraRays, sampled at
/// its centre (n = 1) or at the centres of its n x n sub-pixels.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <glm/glm.hpp>

#include "noise/camera.h"
#include "noise/cells.h"
#include "noise/image.h"
#include "noise/kernel.h"
#include "noise/reference.h"
#include "shaders/spot_layout.hpp"
#include "splat/context_vk.h"
#include "splat/pass_vk.h"

namespace spot::noise {
struct Mesh;
}

namespace spot::splat {

namespace gpu_march {
using glm::ivec4;
using glm::uvec4;
using glm::vec4;
#define SPOT_CONST inline constexpr
#include "shaders/raymarch_layout.glsl"
#undef SPOT_CONST
static_assert(sizeof(SpotMarchParams) == 96);
static_assert(sizeof(SpotMarchCell) == 96);
static_assert(sizeof(SpotMarchBox) == 32);
} // namespace gpu_march

/// Loop iterations one march invocation may need by default (see the file comment).
inline constexpr std::uint32_t kRaymarchLoopBudget = gpu_march::kMarchLoopBudget;
/// Most steps per ray and rays per pixel side accepted.
inline constexpr int kRaymarchMaxSteps = 4096;
inline constexpr int kRaymarchMaxSupersample = 8;

struct RaymarchSettings {
    /// N: samples along each ray, spread evenly over the ray's shell segments, in [1, 4096]. The
    /// march is split over as many dispatches as the loop budget needs (each step costs the lobes
    /// of the densest neighbourhood; RaymarchStats::maxStepsPerDispatch says how many fit in one).
    int steps = 32;
    /// n: n x n rays per pixel on a regular grid (sub-pixel centres), averaged: the box pixel
    /// filter of the reference. In [1, 8]; the cost grows with n^2.
    int supersample = 1;
    /// Largest loop bound one dispatch may reach. Tests raise it past lavapipe's 65,535 (all steps
    /// then go in one dispatch) to show what the guard prevents; anything above
    /// kMarchLavapipeLoopLimit gives truncated images on lavapipe.
    std::uint32_t loopBudget = kRaymarchLoopBudget;
    /// Skip the impulses whose box (SpotMarchBox) does not hold the sample. Exact: the image is
    /// the same without it (a test holds that), only slower.
    bool cullImpulses = true;
};

struct RaymarchStats {
    std::vector<std::pair<std::string, double>> passMs; ///< GPU time per pass, milliseconds
    double totalMs = 0.0;        ///< GPU time of the frame (both submits), milliseconds
    double hostMs = 0.0;         ///< CPU time between the submits (ranges, guard), milliseconds
    std::uint32_t loopBound = 0; ///< bound(steps per dispatch) for this frame (file comment)
    std::uint32_t maxLoopIterations = 0;     ///< counted by the shader: the maximum over pixels
    std::uint32_t stepsPerDispatch = 0;      ///< steps each march dispatch takes (the last fewer)
    std::uint32_t maxStepsPerDispatch = 0;   ///< the most the loop budget allows in one dispatch
    std::uint32_t dispatches = 0;            ///< march dispatches: ceil(steps / max per dispatch)
    std::uint32_t supersample = 1;           ///< n: n x n rays per pixel
    std::uint32_t shellCells = 0;            ///< cells of the dilated surface
    std::uint32_t maxNeighbourhoodLobes = 0; ///< L T: lobes summed at one sample at most
    std::uint32_t maxNeighbourhoodImpulses = 0; ///< T
    std::uint32_t lobesPerImpulse = 0;          ///< L
    std::uint32_t longestProbe = 0;          ///< P
    std::uint32_t walkCells = 0;             ///< W
    std::uint64_t frameBytes = 0;            ///< GPU memory the frame allocated
    std::uint64_t gpuMemoryBytes = 0;        ///< the context's peak allocation so far
};

/// What the march shader read in one frame, for the CPU twin (raymarchOnCpu).
struct RaymarchCapture {
    noise::Camera camera;                 ///< the output image's (the march's is n times larger)
    gpu_march::SpotMarchParams params{};  ///< range.z is the supersampling n
    std::uint32_t stepsPerDispatch = 1;   ///< the split of the march over dispatches
    std::vector<glm::ivec4> table;               ///< hash slots (i, j, k, record or -1)
    std::vector<gpu_march::SpotMarchCell> cells; ///< shell cell records
    std::vector<gpu::SpotWorldLobe> lobes;       ///< world lobes, impulse-major
    std::vector<gpu_march::SpotMarchBox> boxes;  ///< per impulse
    std::vector<glm::vec4> base;         ///< mesh pass colour per march pixel (row-major)
    std::vector<float> meshDistance;     ///< ray distance to the mesh per march pixel
    std::vector<std::uint32_t> gpuLoops; ///< loop iterations the GPU counted per march pixel (the
                                         ///< most of any one dispatch)
};

class RaymarchRenderer {
public:
    /// Uploads the mesh (may be empty) and the kernel's lobes, builds the pipelines. Throws
    /// InputError for a kernel without lobes or with more than 8.
    RaymarchRenderer(Context& ctx, const noise::Mesh& mesh, const noise::Kernel& kernel);

    /// Render one frame of `count` impulses (`impulses` holds gpu::SpotImpulse[], at least `count`,
    /// storage-buffer usage) generated in `cells` (the generator's surface cells: impulses in
    /// cell order, each in the cell that generated it, as noise::ImpulseGenerator and GpuGenerator
    /// give them; the cell size must be at least the kernels' support radius, as the generator
    /// ensures). Throws InputError for a bad setting, impulses out of cell order or outside the
    /// cells, a frame beyond the memory budget, or a step count whose loop bound exceeds
    /// settings.loopBudget (the message names the step count that fits). `capture`, when given,
    /// receives what the march read (slower: for tests).
    noise::Image render(const noise::Camera& camera, const noise::Shading& shading,
                        glm::vec3 background, glm::vec3 baseColor, const noise::SurfaceCells& cells,
                        const Buffer& impulses, std::uint32_t count,
                        const RaymarchSettings& settings, RaymarchStats* stats = nullptr,
                        RaymarchCapture* capture = nullptr);

private:
    struct Shell; ///< the dilated cells and their hash table (host and GPU), kept between frames
    const Shell& shellFor(const noise::SurfaceCells& cells);

    Context& m_ctx;
    std::uint32_t m_lobeCount = 0;
    float m_support = 3.0f;
    MeshPass m_meshPass;
    Buffer m_lobes;
    Pipeline m_prepare, m_bin, m_march, m_resolve;
    bool m_prepareOrthographic = false;
    Timestamps m_binTimes, m_marchTimes;
    std::shared_ptr<Shell> m_shell;
};

/// A captured frame rendered on the CPU by the same march code (raymarch_shared.glsl compiled as
/// C++ in float): the GPU's exact algorithm, without lavapipe's loop limit. `loops`, when given,
/// receives each pixel's loop count (row-major).
noise::Image raymarchOnCpu(const RaymarchCapture& capture,
                           std::vector<std::uint32_t>* loops = nullptr);

/// bound(N) of the file comment, in 64 bits (it may pass 2^32 for absurd settings).
std::uint64_t raymarchLoopBound(std::uint64_t steps, std::uint64_t walkCells,
                                std::uint64_t longestProbe, std::uint64_t neighbourhoodImpulses,
                                std::uint64_t lobesPerImpulse);

} // namespace spot::splat
