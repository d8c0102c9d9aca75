/// @file generate_vk.h
/// @brief Impulses generated on the GPU from the surface cells, with the shared generation code
/// (shaders/spot_generate.h): the same impulses, in the same order, as noise::ImpulseGenerator.
#pragma once

#include <cstdint>
#include <functional>

#include "context_vk.h"
#include "noise/camera.h"
#include "noise/impulses.h"

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

class GpuGenerator {
public:
    /// Uploads what the generator reads (mesh, pieces, fields, parameters) once.
    GpuGenerator(Context& ctx, const noise::Mesh& mesh, const noise::ImpulseGenerator& generator);

    /// Generate the impulses of the cells accepted by `keep` (all when empty); culled cells
    /// generate nothing and cost nothing. `lod` is SpotGenParams::lod for this view (w = 0: no
    /// level of detail, the CPU generator's impulses exactly).
    GpuImpulses generate(const std::function<bool(const noise::SurfaceCell&)>& keep = {},
                         glm::vec4 lod = glm::vec4(0.0f));

private:
    Context& m_ctx;
    const noise::ImpulseGenerator& m_generator;
    Pipeline m_pipeline;
    Buffer m_params, m_pieces, m_triangles, m_positions, m_normals, m_tangents, m_uvs, m_fieldData;
};

} // namespace spot::splat
