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
/// Lit scenes (Shading::Mode::Lit) take the quadrature path too: at each step's midpoint one
/// shadow ray per light (when its shadows are on) and one towards the sky give the exact
/// transmittance through every lobe (erf of each chord, as for primary rays) and the mesh (its
/// BVH; 0 on a hit); each lobe of the step scatters the arriving light through its model
/// (shaders/spot_light.h). The sky is integrated by sampling: one direction per camera sample,
/// stratified over a pixel's samples. The base mesh is diffuse, lit and shadowed the same way.
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

/// A light of a lit scene (scene key "lights"; docs/design.md, "Lighting").
struct Light {
    enum class Type { Directional, Point };
    Type type = Type::Directional;
    glm::vec3 direction{0.0f, 1.0f, 0.0f}; ///< directional: unit, world, towards the light
    glm::vec3 position{0.0f};              ///< point: world
    glm::vec3 color{1.0f};                 ///< linear RGB
    /// Directional: what arrives (colour x intensity). Point: radiant intensity, so
    /// colour x intensity / d^2 arrives at distance d (world units).
    float intensity = 1.0f;
    bool shadows = true; ///< attenuate by the transmittance to the light (kernels and mesh)
};

/// A lit scene's sky (scene key "sky"): a hemisphere about world +y of constant radiance
/// colour x intensity, nothing from below. It lights each lobe's diffuse part and the mesh,
/// always shadowed.
struct Sky {
    glm::vec3 color{1.0f};
    float intensity = 0.0f;
};

/// How lobes and the base mesh are shaded. Unlit: each lobe emits its colour, the mesh shows its
/// colour. Lambert: both scaled by ambient + (1 - ambient) max(0, n.l), n from the extinction
/// gradient, no shadows. Lit: every light and the sky, through each lobe's model (the preset's
/// kernel.lobes[i].shading, shaders/spot_light.h) and the mesh's diffuse, with shadows.
struct Shading {
    enum class Mode { Unlit, Lambert, Lit };
    /// A mode's name in scene files (shading.mode) and bench rows.
    static constexpr const char* modeName(Mode m) {
        return m == Mode::Lit ? "lit" : m == Mode::Lambert ? "lambert" : "unlit";
    }
    Mode mode = Mode::Unlit;
    glm::vec3 lightDir{0.0f, 1.0f, 0.0f}; ///< Lambert: unit, world, pointing towards the light
    float ambient = 0.3f;                 ///< Lambert: [0,1]
    std::vector<Light> lights;            ///< Lit (the other modes ignore them), at most kMaxLights
    Sky sky;                              ///< Lit

    /// Whether kernels shadow one another: lit, with a shadowed light or a sky. Then a kernel
    /// the camera does not see may still darken one it sees, so the camera culls no cell.
    bool castsShadows() const {
        if (mode != Mode::Lit)
            return false;
        bool any = sky.intensity > 0.0f;
        for (const Light& l : lights)
            any = any || (l.shadows && l.intensity > 0.0f);
        return any;
    }
};

/// Lights a scene may have: a bound for the GPU's light table.
inline constexpr int kMaxLights = 8;

struct ReferenceSettings {
    int spp = 16;            ///< samples per pixel, [1, 65536]
    double stepScale = 1.0;  ///< quadrature step multiplier; 0.5 halves every step
    std::uint32_t seed = 0;  ///< sample pattern seed
    /// Only these pixels of the camera's image (a tile: render --tile); empty: all of them. Each
    /// pixel is the same as in the whole image.
    PixelRect window;
};

struct ReferenceStats {
    double seconds = 0.0;
    std::size_t impulses = 0;
    std::size_t lobes = 0;
    std::uint64_t rays = 0;
    std::uint64_t chords = 0;          ///< lobe chords integrated
    std::uint64_t exactChords = 0;     ///< of which in closed form
    std::uint64_t quadratureSteps = 0;
    std::uint64_t shadowRays = 0;      ///< lit: rays towards a light or the sky
    std::size_t memoryBytes = 0;       ///< world lobes + BVHs
};

class ReferenceRenderer {
public:
    /// Places every lobe of every impulse in the world and builds the two BVHs. Checks the
    /// memory budget first.
    ReferenceRenderer(const Mesh& mesh, const Kernel& kernel, const std::vector<Impulse>& impulses,
                      const Shading& shading, glm::vec3 background, glm::vec3 baseColor);

    /// Radiance along one ray (linear RGB); `coverage`, when given, receives 1 - the
    /// transmittance through the detail and the mesh (1 where the mesh is hit). Lit scenes:
    /// `skySample` (in [0,1)^2) picks the sky direction every point along the ray is lit from
    /// (spotSkyDirection); render() stratifies it over a pixel's samples.
    glm::vec3 radiance(const Ray& ray, double stepScale, ReferenceStats* stats = nullptr,
                       double* coverage = nullptr, glm::dvec2 skySample = glm::dvec2(0.5)) const;

    /// Lit scenes: the transmittance from world point `p` along unit `dir` over [0, distance]
    /// (infinity for a directional light or the sky) through every lobe (exact: the erf of each
    /// chord) and the mesh (0 when it is hit). `stats` counts the ray.
    double transmittance(glm::dvec3 p, glm::dvec3 dir, double distance,
                         ReferenceStats* stats = nullptr) const;

    /// Render the camera's image, or its `settings.window` alone (an image of the window's size,
    /// its `crop` set). `progress(done, total)` is called from worker threads as rows finish (may
    /// be empty).
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
        glm::vec3 axis;           ///< lit: a strand's tangent, a flake's normal (world, unit)
        std::uint32_t kernelLobe; ///< its lobe in the kernel (the model, the highlights)
    };
    /// Lit: what one kernel lobe's model needs (shaders/spot_light.h's arguments).
    struct LobeModel {
        std::uint32_t model = 0;                 ///< kSpotShade*
        glm::dvec3 primary{0.0}, secondary{0.0}; ///< (shift, width) in radians, strength
    };
    /// Lit: a light as it arrives at point p: its direction and what reaches p unshadowed.
    struct Arrival {
        glm::dvec3 dir;      ///< unit, towards the light
        double distance;     ///< to the light; infinity for a directional one
        glm::dvec3 radiance; ///< colour x intensity (/ d^2 for a point light)
    };
    struct Chord;

    double hitMesh(const Ray& ray, glm::vec3& normal) const;
    glm::vec3 shade(glm::vec3 color, glm::dvec3 normal) const;
    Arrival arrive(const Light& light, glm::dvec3 p) const;
    /// Lit: the base mesh's colour at p (normal n, unit eye direction v): diffuse from every
    /// light and the sky direction `sky`, each shadowed.
    glm::dvec3 shadeMeshLit(glm::dvec3 p, glm::dvec3 n, glm::dvec3 v, glm::dvec3 sky,
                            ReferenceStats* stats) const;

    const Mesh& m_mesh;
    double m_support;
    Shading m_shading;
    glm::vec3 m_background, m_baseColor;
    std::size_t m_impulseCount;
    std::vector<Lobe> m_lobes;
    std::vector<LobeModel> m_models; ///< one per kernel lobe
    double m_epsilon = 0.0;          ///< lit: shadow rays leave the mesh this far along its normal
    Bvh m_lobeBvh;
    Bvh m_meshBvh;
};

/// Correlated multi-jittered sample `s` of `n` in the unit square for pattern `p` (Kensler 2013).
glm::dvec2 cmjSample(std::uint32_t s, std::uint32_t n, std::uint32_t p);

} // namespace spot::noise
