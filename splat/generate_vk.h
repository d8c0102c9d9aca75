/// @file generate_vk.h
/// @brief Impulses generated on the GPU from the surface cells, with the shared generation code
/// (shaders/spot_generate.h): the same impulses, in the same order, as noise::ImpulseGenerator.
#pragma once

#include <cstdint>
#include <functional>

#include "context_vk.h"
#include "noise/camera.h"
#include "noise/impulses.h"
#include "splat/method_vk.h"

namespace spot::splat {

struct GpuImpulses {
    Buffer impulses;                ///< SpotImpulse[count] (shaders/spot_layout.h)
    std::uint32_t count = 0;
    std::uint32_t candidates = 0;   ///< examined before the density test
    std::uint32_t cells = 0;        ///< cells generated (after culling)
    double milliseconds = 0.0;      ///< GPU time of the three passes
};

/// SpotGenParams::lod for a camera: cells smaller on screen than `pixels` are thinned. 0 pixels,
/// or an orthographic camera (no perspective shrinking to adapt to), turns the LOD off.
glm::vec4 lodParameters(const noise::Camera& camera, double pixels);

/// Impulses generated on the GPU, kept between frames: a frame regenerates them only when the
/// cells it needs or the level of detail changed.
class GpuGenerator {
public:
    /// Uploads what the generator reads (mesh, pieces, fields, parameters) once. `generator`
    /// (and its mesh) must outlive this object.
    GpuGenerator(Context& ctx, const noise::Mesh& mesh, const noise::ImpulseGenerator& generator);

    /// Host side of a frame's generation: the cells `keep` accepts (all when empty) and the
    /// level of detail `lod` (SpotGenParams::lod; w = 0: off). Returns true when they differ from
    /// those of the impulses generated last, so that record() must run in this frame; false when
    /// the last impulses stand. Throws InputError for more candidates than fit.
    bool prepare(const std::function<bool(const noise::SurfaceCell&)>& keep, glm::vec4 lod);
    /// Record the generation prepared last (its passes marked on `timer` as "generate").
    void record(VkCommandBuffer cmd, PassTimer& timer);
    /// The impulses of the last generation (valid on the GPU once its frame ran).
    ImpulseSet impulses() const;
    /// After the frame that generated them: impulses, candidates and cells of the last generation.
    std::uint32_t count() const;
    std::uint32_t candidates() const { return m_candidates; }
    std::uint32_t cells() const { return m_cellCount; }

    /// One-shot generation, waited for (tests and host-side users): the impulses in a buffer of
    /// the caller's, and the GPU time.
    GpuImpulses generate(const std::function<bool(const noise::SurfaceCell&)>& keep = {},
                         glm::vec4 lod = glm::vec4(0.0f));

private:
    Context& m_ctx;
    const noise::ImpulseGenerator& m_generator;
    Pipeline m_pipeline;
    Buffer m_params, m_pieces, m_triangles, m_positions, m_normals, m_tangents, m_uvs, m_fieldData;
    // The persistent generation (TODO: recorded into the frame; for now generated in prepare()).
    GpuImpulses m_current;
    Buffer m_count;
    std::vector<std::uint32_t> m_cellKey; ///< indices of the cells last generated
    glm::vec4 m_lod{-1.0f};
    std::uint64_t m_version = 0;
    std::uint32_t m_candidates = 0, m_cellCount = 0;
};

} // namespace spot::splat
