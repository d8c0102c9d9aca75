/// @file reference.h
/// @brief The converged CPU reference: the emission-absorption integral (paper eq. 5-6) through
/// every lobe along each ray, supersampled. Every accuracy number is measured against it.
///
/// Along a ray the lobes' truncated supports give chords; chords that overlap no other are
/// integrated exactly (a lobe of optical depth tau and colour c adds T (1 - e^-tau) c and
/// multiplies T by e^-tau). Overlapping chords form a cluster integrated by quadrature: steps
/// of at most `stepScale` x 1/4 of the thinnest lobe's extent along the ray, the optical depth of
/// each lobe over each step exact (erf), the colour of a step the extinction-weighted mean of its
/// lobes' colours. The opaque base mesh ends the ray. With Lambert shading every chord takes the
/// quadrature path (the normal, from the density gradient, varies inside a lobe).
///
/// Pixel filter: a box over the pixel (the mean of the radiance over the pixel's area), sampled
/// with correlated multi-jittered patterns (Kensler 2013), decorrelated per pixel.
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <vector>

#include <glm/glm.hpp>

#include "bvh.h"
#include "camera.h"
#include "image.h"
#include "impulses.h"
#include "kernel.h"

namespace spot::noise {

struct Mesh;

struct Shading {
    enum class Mode { Unlit, Lambert };
    Mode mode = Mode::Unlit;
    glm::vec3 lightDir{0.0f, 1.0f, 0.0f}; ///< unit, world, pointing towards the light
    float ambient = 0.3f;                 ///< [0,1]: shade = ambient + (1 - ambient) max(0, n.l)
};

struct ReferenceSettings {
    int spp = 16;            ///< samples per pixel, [1, 65536]
    double stepScale = 1.0;  ///< quadrature step multiplier; 0.5 halves every step
    std::uint32_t seed = 0;  ///< sample pattern seed
};

struct ReferenceStats {
    double seconds = 0.0;
    std::size_t impulses = 0;
    std::size_t lobes = 0;
    std::uint64_t rays = 0;
    std::uint64_t chords = 0;          ///< lobe chords integrated
    std::uint64_t exactChords = 0;     ///< of which in closed form
    std::uint64_t quadratureSteps = 0;
    std::size_t memoryBytes = 0;       ///< world lobes + BVHs
};

class ReferenceRenderer {
public:
    /// Places every lobe of every impulse in the world and builds the two BVHs. Checks the
    /// memory budget first.
    ReferenceRenderer(const Mesh& mesh, const Kernel& kernel, const std::vector<Impulse>& impulses,
                      const Shading& shading, glm::vec3 background, glm::vec3 baseColor);

    /// Radiance along one ray (linear RGB); `coverage`, when given, receives 1 - the
    /// transmittance through the detail and the mesh (1 where the mesh is hit).
    glm::vec3 radiance(const Ray& ray, double stepScale, ReferenceStats* stats = nullptr,
                       double* coverage = nullptr) const;

    /// Render the camera's image. `progress(done, total)` is called from worker threads as rows
    /// finish (may be empty).
    Image render(const Camera& camera, const ReferenceSettings& settings,
                 const std::function<void(int, int)>& progress = {},
                 ReferenceStats* stats = nullptr) const;

    std::size_t lobeCount() const { return m_lobes.size(); }

private:
    struct Lobe {
        glm::dvec3 centre;
        glm::dmat3 toLobe;
        double extinction;
        glm::vec3 color;
    };
    struct Chord;

    double hitMesh(const Ray& ray, glm::vec3& normal) const;
    glm::vec3 shade(glm::vec3 color, glm::dvec3 normal) const;

    const Mesh& m_mesh;
    double m_support;
    Shading m_shading;
    glm::vec3 m_background, m_baseColor;
    std::size_t m_impulseCount;
    std::vector<Lobe> m_lobes;
    Bvh m_lobeBvh;
    Bvh m_meshBvh;
};

/// Correlated multi-jittered sample `s` of `n` in the unit square for pattern `p` (Kensler 2013).
glm::dvec2 cmjSample(std::uint32_t s, std::uint32_t n, std::uint32_t p);

} // namespace spot::noise
