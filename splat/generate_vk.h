/// @file generate_vk.h
/// @brief Impulses generated on the GPU from the surface cells, with the shared generation code
/// (shaders/spot_generate.h): the same impulses, in the same order, as noise::ImpulseGenerator.
///
/// A generation is host work in prepare() (the cells chosen, each cell's candidates counted with
/// the CPU twin of the shared code, their offsets uploaded) and three compute passes that
/// record() puts into the caller's command buffer (shaders/spot_generate_layout.h: every
/// candidate decided, a deterministic scan of the accepted flags, the compaction). The impulse
/// count stays on the GPU, where the renderers read it; nothing waits on the host in between.
#pragma once

#include <cstdint>
#include <functional>
#include <deque>
#include <future>
#include <vector>

#include "context_vk.h"
#include "noise/camera.h"
#include "noise/generator_shared.h"
#include "noise/impulses.h"
#include "splat/method_vk.h"

namespace spot::splat {

struct GpuImpulses {
    Buffer impulses; ///< SpotImpulse[count] (shaders/spot_layout.h), host-visible
    std::uint32_t count = 0;
    /// Candidates of the cells, as the CPU generator counts them (of a jittered lattice the GPU
    /// examines only those that can pass: ImpulseSet::capacity).
    std::uint32_t candidates = 0;
    std::uint32_t cells = 0;      ///< cells generated (after culling)
    double milliseconds = 0.0;    ///< GPU time of the generation's passes
};

/// SpotGenParams::lod for a camera: cells smaller on screen than `pixels` are thinned. 0 pixels,
/// or an orthographic camera (no perspective shrinking to adapt to), turns the LOD off.
glm::vec4 lodParameters(const noise::Camera& camera, double pixels);

/// Impulses generated on the GPU, kept between frames: a frame regenerates them only when the
/// cells it needs or the level of detail changed. The buffers only grow (with a margin), so a
/// frame like the last allocates nothing.
class GpuGenerator {
public:
    /// Uploads what the generator reads (mesh, pieces, fields, parameters) once. `generator`
    /// (and its mesh) must outlive this object.
    GpuGenerator(Context& ctx, const noise::Mesh& mesh, const noise::ImpulseGenerator& generator);
    GpuGenerator(const GpuGenerator&) = delete;
    GpuGenerator& operator=(const GpuGenerator&) = delete;

    /// Host side of a frame's generation: the cells `keep` accepts (all when empty) and the
    /// level of detail `lod` (SpotGenParams::lod; w = 0: off). Returns true when they differ from
    /// those of the impulses generated last, so that record() must run in this frame; false when
    /// the last impulses stand. No frame that reads this generator may be in flight. Throws
    /// InputError for more candidates than fit (one storage buffer, or kGenMaxCandidates).
    bool prepare(const std::function<bool(const noise::SurfaceCell&)>& keep, glm::vec4 lod);
    /// Record the generation prepared last into `cmd` (marked on `timer` as "generate"). Once
    /// `cmd` has run, the impulses and their count are in impulses(), visible to every later
    /// command of `cmd` and to the host.
    void record(VkCommandBuffer cmd, PassTimer& timer);
    /// The impulses of the last generation, valid once its frame ran: host-visible buffers (also
    /// a transfer source); capacity is a bound of the count known on the host, the candidates
    /// the GPU examines (all of them for Poisson; for jittered, those whose lattice site lies in
    /// its triangle and cell), version changes with every generation.
    ImpulseSet impulses() const;
    /// After the frame that generated them: the impulse count of the last generation.
    std::uint32_t count() const;
    std::uint32_t candidates() const { return m_candidates; }
    std::uint32_t cells() const { return m_cellCount; }

    /// After the generator's fields changed (noise::ImpulseGenerator::setField, refreshFields):
    /// uploads the field data and parameters again (growing the buffer when needed, within the
    /// memory budget), remakes the candidates pipeline when a slot's kind, component count or the
    /// comb's presence changed (they are specialization constants), and makes the next prepare()
    /// regenerate. The cells' candidate counts stay (they depend on no field). No frame that
    /// reads this generator may be in flight.
    void refreshFields();
    /// Start making, ahead of its use, the candidates pipeline for the current fields with field
    /// `slot` (SPOT_FIELD_*) of kind `kind` and `components` components, so that a setField
    /// that gives the slot that kind later (the editor's first stroke on a slot swaps in its
    /// painted grid) does not compile in its frame, nor the partial generations after it (its
    /// partial twin is made too). The compiles run on threads of their own (seconds on
    /// lavapipe: the editor's brush arms at once); the generation that needs a pipeline waits for
    /// it. Keeps the pipelines of the last few kinds prepared.
    void prepareFieldKind(std::uint32_t slot, std::int32_t kind, std::int32_t components);
    /// refreshFields() when the fields changed only where the model cells `cells` (indices into
    /// the generator's cells) read them: the next prepare(), if it chooses the cells and level of
    /// detail of the last generation, decides only those cells' candidates again and keeps every
    /// other cell's impulses as they were (bit for bit); otherwise it regenerates everything.
    /// The last generation must have run (its frame submitted).
    void refreshFields(const std::vector<std::uint32_t>& cells);

    /// One-shot generation, waited for (tests and host-side users): prepare() (regenerating even
    /// when the cells and lod are those of the last generation), record(), submit, wait; the
    /// impulses copied into a host-visible buffer of the caller's. The generation also becomes
    /// the persistent one (impulses()).
    GpuImpulses generate(const std::function<bool(const noise::SurfaceCell&)>& keep = {},
                         glm::vec4 lod = glm::vec4(0.0f));

private:
    bool choose(const std::function<bool(const noise::SurfaceCell&)>& keep, glm::vec4 lod,
                bool force);
    /// The host side of a partial generation over the cells of the last one.
    void choosePartial();
    /// What the host knows of one model cell, found on first use (it depends on neither the view
    /// nor the level of detail).
    struct CellCandidates {
        std::uint32_t candidates = 0xffffffffu; ///< spotCellCandidates; all ones: not counted yet
        std::vector<std::uint16_t> inside; ///< jittered: the candidates that can pass, in order
    };
    const CellCandidates& cellCandidates(std::uint32_t cell);
    /// The candidates of a cell the GPU examines: all of them (Poisson) or those inside.
    std::uint32_t examined(const CellCandidates& c) const {
        return m_jittered ? std::uint32_t(c.inside.size()) : c.candidates;
    }
    const Pipeline& candidatePipeline();
    /// The same for a partial generation (made at the first).
    const Pipeline& partialPipeline();
    /// The candidates pipeline for a specializationKey(), of a full or a partial generation.
    Pipeline makeCandidatePipeline(const std::vector<std::int32_t>& key, bool partial = false);
    /// The same with the mesh's uv and tangent flags given (what a compile on another thread
    /// reads: nothing of the generator that may change meanwhile).
    Pipeline makeCandidatePipeline(const std::vector<std::int32_t>& key, bool partial, bool uv,
                                   bool tangents);
    /// What the candidates pipeline is specialized for: the comb flag, each slot's kind and
    /// component count.
    std::vector<std::int32_t> specializationKey() const;

    Context& m_ctx;
    const noise::Mesh& m_mesh;
    const noise::ImpulseGenerator& m_generator;
    /// The CPU twin of the shared code, over the same arrays the GPU reads (host-side counts).
    shared::f32::SharedGenerator m_shared;
    bool m_jittered = false;
    std::vector<CellCandidates> m_cellCandidates; ///< per model cell
    Pipeline m_candidatePipeline;                 ///< specialized for the preset; made on first use
    Pipeline m_partialPipeline;                   ///< the same for partial generations
    std::vector<std::int32_t> m_candidateKey;     ///< specializationKey() it was made for
    /// prepareFieldKind's pipelines (and their partial twins), made or being made on their
    /// threads, until their key is used (the oldest dropped past a few).
    struct Prepared {
        std::vector<std::int32_t> key;
        std::future<Pipeline> pipeline;
        std::future<Pipeline> partial;
    };
    std::deque<Prepared> m_prepared;
    Pipeline m_scanPipeline, m_scatterPipeline;
    Buffer m_params, m_pieces, m_triangles, m_positions, m_normals, m_tangents, m_uvs, m_fieldData;

    // The persistent generation.
    Buffer m_cells;    ///< SpotCell[], the chosen cells with candidates, offsets in info.z
    Buffer m_sites;    ///< jittered: uint[examined], each candidate's index in its cell
    Buffer m_scratch;  ///< SpotImpulse[examined]: every examined candidate's impulse
    Buffer m_flags;    ///< uint[examined]: accepted flags, then 1-based output indices
    Buffer m_impulses; ///< SpotImpulse[examined]: the impulses, compacted (host-visible)
    Buffer m_count;    ///< uint: the impulse count (host-visible)
    std::vector<std::uint32_t> m_cellKey; ///< indices of the cells last generated
    /// A partial generation (refreshFields(cells)): the model cells to decide again, pending
    /// until the next prepare(); then the chosen ones, as SpotCell[] with offsets among their own
    /// candidates (m_dirtyCells) and each one's offset in the whole generation (m_dirtyOffsets).
    std::vector<std::uint32_t> m_dirty;
    bool m_dirtyPending = false, m_partial = false;
    Buffer m_dirtyCells, m_dirtyOffsets;
    std::uint32_t m_dirtyCellCount = 0, m_dirtyExamined = 0;
    glm::vec4 m_lod{0.0f};
    bool m_valid = false; ///< a generation is prepared (false after a failed prepare)
    std::uint64_t m_version = 0;
    std::uint32_t m_candidates = 0, m_examined = 0, m_cellCount = 0, m_uploadedCells = 0;
};

} // namespace spot::splat
