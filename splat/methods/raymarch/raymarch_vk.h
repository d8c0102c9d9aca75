/// @file raymarch_vk.h
/// @brief The `raymarch` method of docs/design.md section 4: the baseline the paper beats (paper
/// sec. 4, eq. 7-9). Each pixel's ray is marched through the shell, and at every step the kernels
/// of the 27 cells around the sample are summed. A Renderer of the registry (method_vk.h).
///
/// When the impulses change (ImpulseSet::version), prepare() redoes what depends only on them, in
/// a submit of its own, waited for:
///  1. prepare (compute): each impulse's lobes placed in the world (the splat renderer's
///     splat_prepare.comp, without EWA widening: a widened lobe could reach past the 3x3x3 cells
///     that the march searches).
///  2. bin (compute, raymarch_bin.comp): each impulse's shell cell (hash lookup), per cell the
///     range of impulses it holds, and each lobe's and impulse's box (SpotMarchBox). Read back;
///     on the host: the impulse order is checked, and every shell cell's sub-cells (kMarchSub^3 of
///     them) get the list of the impulses of the cell's 27 neighbours that may have density
///     there, each with the mask of its lobes that may (the lobe's box reaches the sub-cell, and
///     so does each of the three slabs |a_i . (x - c)| < k that hold its support: a flat or thin
///     lobe tilted across the axes reaches far fewer sub-cells than its box), in impulse order.
///     Without RenderSettings::cullImpulses a cell's one list holds every lobe of its 27
///     neighbours' impulses: the paper's baseline, literally. A list leaves out only lobes that
///     have exactly zero density in the sub-cell, and keeps the order of the sums, so it changes
///     no pixel (a test holds that, bit for bit, and the images are bit for bit those of the
///     march before the lists); it spares the march the lobes it would have found empty one
///     sample at a time, and it makes the loop guard's T (below) the longest list instead of the
///     densest neighbourhood, so the steps need fewer dispatches.
/// Every frame, recorded into the caller's command buffer with no host wait:
///  3. mesh (raster): the opaque base mesh's colour and ray distance (the scene's MeshPass).
///  4. march (compute, raymarch_march.comp): per ray, the shell segments by a cell walk (3D DDA)
///     over the shell's bounding box (the cells it keeps read from one bit per cell, 64 per 4^3
///     brick, once per brick), then N samples evenly spaced over the segments laid end to
///     end, front-to-back emission-absorption with alpha = 1 - exp(-sigma dt) (eq. 9's 0-order
///     attenuation). Lambert normals: the normalized negative gradient of the summed density of
///     all neighbouring lobes, as in the reference. The N steps are split over as many dispatches
///     as the loop guard needs (below, decided in prepare()); each continues from the radiance and
///     transmittance the previous one left, with the same arithmetic, so the split never changes
///     the image.
///  5. resolve (compute, raymarch_resolve.comp): with supersampling n the mesh pass and the march
///     run at n times the resolution (n x n rays per pixel through sub-pixel centres); each
///     output pixel is the mean of its n x n rays, each over the mesh colour behind it (a box
///     filter, the reference's), into result(). One ray per pixel aliases thin strands: they are
///     hit or missed as the camera moves, which the bench's temporal flicker shows.
/// The march and resolve pipelines are specialized (lobes per kernel, Lambert, culling, loop
/// counting, the walk's bits).
///
/// Persistent: the targets (per image size and supersampling), the world lobes and boxes (per
/// impulse capacity, grow-only), the shell and its hash table (per set of surface cells), the
/// lists (grow-only). A warm frame (same impulses, same size) allocates nothing and reads nothing
/// back. Memory grows with the surface: per shell cell 16 bytes of record, 500 of list starts
/// (one per sub-cell), 32 to 64 of hash table (more if the table had to grow to keep probes
/// short) and 12 of bins; per kernel its world lobes (64 bytes each) and boxes (32 per lobe and
/// 32), per listed (sub-cell, impulse) pair 4; per march pixel 44 bytes, per output pixel 16;
/// and one bit per cell of the shell's bounding box for the walk (at most 16 MiB: beyond, the
/// walk uses the hash table).
///
/// Not done here: per-cell occupied boxes to tighten the segments. The samples are spread over
/// the segments, so tighter segments would move every sample: another (better) renderer than the
/// paper's baseline, which this one is meant to be.
///
/// The loop guard. lavapipe silently stops a shader invocation after 65,535 loop iterations (the
/// image comes back wrong, with no error). Before the march is recorded, the host bounds the
/// iterations any invocation can run (raymarch_shared.glsl explains the accounting):
///
///     bound(N) = 1 + W (P + 3)  +  1 + N (S + P + 4 + T (L + 2))
///
/// with W the cells a ray can cross in the shell's bounding box (its extents in cells summed),
/// P the longest hash probe (slots past a key's home slot), S = kMarchMaxSegments, L the lobes per
/// kernel and T the longest list. (An impulse whose box does not hold the sample is skipped,
/// lobes and all, and so is a lobe outside its support, though the bound must assume every lobe
/// listed is summed; the lobe loop, unrolled by lavapipe for the specialized count, is charged
/// as a loop all the same.) The march is
/// split into dispatches of at most N' steps, N' the largest with bound(N') within the budget
/// (kMarchLoopBudget = 60,000 by default); a frame where not even one step fits (about 59,000
/// lobes in one list) is refused with an InputError that says why. The shader counts its own
/// loops with the same accounting when asked (countLoops: RaymarchStats::maxLoopIterations, the
/// most in one dispatch), so tests hold the bound against what really ran.
///
/// Results are deterministic: no float atomics, every pixel independent, sums in a fixed order.
/// Units: world units; pixel (x, y) of the image is pixel (x, y) of noise::CameraRays, sampled at
/// its centre (n = 1) or at the centres of its n x n sub-pixels.
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include <glm/glm.hpp>

#include "noise/camera.h"
#include "noise/cells.h"
#include "noise/image.h"
#include "shaders/spot_layout.hpp"
#include "splat/context_vk.h"
#include "splat/method_vk.h"
#include "splat/pass_vk.h"
#include "splat/passes/light_space_vk.h"

namespace spot::splat {

namespace gpu_march {
using glm::ivec4;
using glm::uvec4;
using glm::vec4;
#define SPOT_CONST inline constexpr
#include "shaders/raymarch_layout.glsl"
#undef SPOT_CONST
static_assert(sizeof(SpotMarchParams) == 64);
static_assert(sizeof(SpotMarchPush) == 112, "push constants: 128 bytes at most on lavapipe");
static_assert(sizeof(SpotMarchCell) == 16);
static_assert(sizeof(SpotMarchBox) == 32);
static_assert(kMarchSubCells == kMarchSub * kMarchSub * kMarchSub);
static_assert(kMarchEntryImpulse + 1 == 1u << kMarchEntryLobeShift);
static_assert(65535u * 64u <= kMarchEntryImpulse + 1, "every impulse index fits an entry");
} // namespace gpu_march

/// Loop iterations one march invocation may need by default (see the file comment).
inline constexpr std::uint32_t kRaymarchLoopBudget = gpu_march::kMarchLoopBudget;
/// Most steps per ray and rays per pixel side accepted.
inline constexpr int kRaymarchMaxSteps = 4096;
inline constexpr int kRaymarchMaxSupersample = 8;

/// What the last frame's guard decided and the shader counted (after the frame completed; the
/// stats' FrameCounters::extra gives the main ones to `render --stats` and the bench).
struct RaymarchStats {
    std::uint32_t loopBound = 0; ///< bound(steps per dispatch) for this frame (file comment)
    std::uint32_t maxLoopIterations = 0;   ///< counted by the shader (countLoops): the maximum
    std::uint32_t stepsPerDispatch = 0;    ///< steps each march dispatch takes (the last fewer)
    std::uint32_t maxStepsPerDispatch = 0; ///< the most the loop budget allows in one dispatch
    std::uint32_t dispatches = 0;          ///< march dispatches: ceil(steps / max per dispatch)
    std::uint32_t supersample = 1;         ///< n: n x n rays per pixel
    std::uint32_t shellCells = 0;          ///< cells of the dilated surface
    std::uint32_t maxNeighbourhoodImpulses = 0; ///< impulses of the densest 27 cells
    std::uint32_t maxListedImpulses = 0;        ///< T: the longest sub-cell list
    std::uint32_t lobesPerImpulse = 0;          ///< L
    std::uint32_t longestProbe = 0;             ///< P
    std::uint32_t walkCells = 0;                ///< W
    std::uint64_t listEntries = 0;              ///< (sub-cell, impulse) pairs listed
    std::uint32_t impulses = 0;                 ///< the impulse count the lists were built for
    bool binned = false;    ///< this frame's prepare() redid the lists (new impulses)
    double binMs = 0.0;     ///< then: GPU time of its prepare and bin passes
    double binHostMs = 0.0; ///< then: host time of the readback, checks and lists
};

/// What the march shader read in one frame, for the CPU twin (raymarchOnCpu).
struct RaymarchCapture {
    noise::Camera camera; ///< the output image's (the march's is n times larger)
    gpu_march::SpotMarchParams params{};
    gpu_march::SpotMarchPush push{};             ///< range.z: steps N; range.w: supersampling n
    std::uint32_t stepsPerDispatch = 1;          ///< the split of the march over dispatches
    std::uint32_t lobes = 1;                     ///< specialization: lobes per kernel
    bool lambert = false, cull = true;           ///< specialization: shading, box test
    std::vector<glm::uvec2> walkBits;            ///< the walk's bits per brick (empty: hashed)
    std::vector<glm::ivec4> table;               ///< hash slots (i, j, k, record or -1)
    std::vector<gpu_march::SpotMarchCell> cells; ///< shell cell records
    std::vector<std::uint32_t> starts;           ///< per list slot, its first entry; then the end
    std::vector<std::uint32_t> list;             ///< impulse indices
    std::vector<gpu::SpotWorldLobe> lobeData;    ///< world lobes, impulse-major
    std::vector<gpu_march::SpotMarchBox> boxes;  ///< per impulse
    std::vector<glm::vec4> base;                 ///< mesh pass colour per march pixel (row-major)
    std::vector<float> meshDistance;             ///< ray distance to the mesh per march pixel
    /// Loop iterations the GPU counted per march pixel (the most of any one dispatch); empty
    /// unless the frame counted (RaymarchRenderer::countLoops).
    std::vector<std::uint32_t> gpuLoops;
};

class RaymarchRenderer final : public Renderer {
public:
    /// `scene` must outlive the renderer.
    explicit RaymarchRenderer(const SceneGpu& scene);
    ~RaymarchRenderer() override;

    /// The impulses must come with the surface cells they were generated in (ImpulseSet::cells:
    /// impulses in cell order, each in the cell that generated it, as noise::ImpulseGenerator and
    /// GpuGenerator give them; the cell size must be at least the kernels' support radius, as the
    /// generator ensures). Throws InputError for a bad setting, impulses out of cell order or
    /// outside the cells, a frame beyond the memory budget, or a step count whose loop bound
    /// exceeds settings.loopBudget (the message names what would fit). For new impulses it
    /// submits and waits for work of its own and rewrites the lists the last frame read: call it
    /// once that frame completed (splat::Frame does).
    void prepare(const View& view, const ImpulseSet& impulses,
                 const RenderSettings& settings) override;
    void record(VkCommandBuffer cmd, PassTimer& timer) override;
    const Image& result() const override { return m_result; }
    /// kernelsDrawn: the impulses marched; extra: loop_bound, dispatches, steps_per_dispatch,
    /// listed_impulses (T), neighbourhood_impulses, shell_cells, walk_cells, longest_probe,
    /// binned (1 when this frame rebuilt the lists, with bin_ms and bin_host_ms), and
    /// max_loop_iterations when counting (countLoops).
    FrameCounters counters() const override;
    bool readsImpulsesInPrepare() const override { return true; }

    /// Count every invocation's loop iterations from the next frame on (RaymarchStats::
    /// maxLoopIterations, FrameCounters::extra max_loop_iterations, RaymarchCapture::gpuLoops):
    /// for tests, which hold the guard's bound against what ran; off by default (about 5% of a
    /// frame).
    void countLoops(bool on) { m_countLoops = on; }
    /// From the next frame on, walk the shell with the hash table even where the bounding box is
    /// small enough for the walk's bits (as it is beyond their limit): for tests, which hold the
    /// two walks to the same image.
    void walkByHash(bool on) { m_walkByHash = on; }

    /// After the frame completed.
    RaymarchStats stats() const;
    /// After the frame completed: what the march read, read back (allocates; for tests).
    RaymarchCapture capture();

private:
    struct Shell; ///< the dilated cells and their hash table (host and GPU), kept between frames
    struct Pipelines {
        Pipeline march, resolve;
    };
    const Shell& shellFor(const noise::SurfaceCells& cells);
    const Pipelines& pipelines(bool lambert, bool cull, bool count, bool walkBits);
    /// The impulses' lists for the march (the file comment's step 1), from scratch: the pieces
    /// below, in order.
    void bin(const ImpulseSet& impulses, const noise::Camera& marchCamera, bool cull);
    struct Lists;
    /// The bin pass on the GPU, waited for: world lobes, boxes and each shell cell's range of
    /// impulses. Returns its GPU milliseconds.
    double binOnGpu(const ImpulseSet& impulses, const Shell& shell,
                    const noise::Camera& marchCamera, const gpu_march::SpotMarchParams& params);
    /// The bins read back and checked (InputError for impulses out of the cells or out of order).
    Lists checkBins(const ImpulseSet& impulses, const Shell& shell) const;
    /// Each shell cell's 27 neighbours and how many impulses lie around it.
    void findNeighbours(const Shell& shell, const gpu_march::SpotMarchParams& params,
                        Lists& lists) const;
    /// The lists without culling: per cell, every impulse of its 27 neighbours.
    void listEveryImpulse(const Shell& shell, Lists& lists) const;
    /// The lists with culling: per sub-cell, the impulses (and lobes) whose box reaches it.
    void listCulled(const Shell& shell, const gpu_march::SpotMarchParams& params,
                    Lists& lists) const;
    /// The walk's bits per brick of the shell's box (empty when the box is too large).
    std::vector<glm::uvec2> walkBits(const Shell& shell, const Lists& lists) const;
    /// The lists into the grow-only buffers (InputError over a storage buffer or the budget).
    void uploadLists(const Shell& shell, const Lists& lists);
    void ensureImpulseBuffers(std::uint32_t capacity);
    void ensureTargets(std::uint32_t outWidth, std::uint32_t outHeight, std::uint32_t n);

    const SceneGpu& m_scene;
    Context& m_ctx;
    Pipeline m_prepare, m_bin;
    /// A lit frame: its light-space structure and the prepare that lights the world lobes anew
    /// each frame (the bins keep their geometry).
    std::unique_ptr<LightSpace> m_light;
    Pipeline m_prepareLit;
    std::map<std::tuple<bool, bool, bool, bool>, Pipelines> m_pipelines;
    bool m_countLoops = false, m_walkByHash = false;
    std::shared_ptr<Shell> m_shell;

    // Per impulse capacity (grow-only).
    std::uint32_t m_capacity = 0;
    Buffer m_worldLobes, m_boxes, m_lobeBoxes;
    Buffer m_prepareUnused; ///< the prepare pass's screen outputs, not written here
    // Per shell and impulse version: bins (readback), records, list starts and entries
    // (grow-only).
    Buffer m_params, m_bins, m_cells, m_starts, m_list, m_walkBits;
    std::vector<glm::uvec2> m_walkBitData; ///< empty: the box is too large, the walk hashes
    std::uint64_t m_version = 0; ///< the impulse version the lists were built for (0: none)
    bool m_listsCulled = true;
    const noise::SurfaceCells* m_listedCells = nullptr;
    RaymarchStats m_binStats; ///< the numbers of the last binning
    // Per image size and supersampling.
    std::uint32_t m_width = 0, m_height = 0, m_n = 0; ///< output size and n
    Image m_base, m_distance, m_depth, m_result;
    Buffer m_state, m_loops;

    // The frame prepared last.
    struct Prepared {
        gpu_splat::SpotSplatFrame meshFrame{};
        gpu_march::SpotMarchPush push{};
        glm::vec3 background{0.0f};
        const Pipelines* pipelines = nullptr;
        std::uint32_t dispatches = 0, stepsPerDispatch = 0, maxStepsPerDispatch = 0;
        std::uint64_t loopBound = 0;
        noise::Camera camera;
        bool lambert = false, cull = true, count = false, walkBits = false;
        bool binned = false;
        bool lit = false;
        ImpulseSet impulses;
        gpu_splat::SpotSplatFrame prepareFrame{};
    } m_frame;
};

/// A captured frame rendered on the CPU by the same march code (raymarch_shared.glsl compiled as
/// C++ in float): the GPU's exact algorithm, without lavapipe's loop limit. `loops`, when given,
/// receives each pixel's loop count (row-major).
noise::Image raymarchOnCpu(const RaymarchCapture& capture,
                           std::vector<std::uint32_t>* loops = nullptr);

/// bound(N) of the file comment, in 64 bits (it may pass 2^32 for absurd settings).
std::uint64_t raymarchLoopBound(std::uint64_t steps, std::uint64_t walkCells,
                                std::uint64_t longestProbe, std::uint64_t listedImpulses,
                                std::uint64_t lobesPerImpulse);

} // namespace spot::splat
