/// @file kernel.h
/// @brief Lobes and kernels (docs/design.md section 1; paper eq. 1, 3, 4).
///
/// A kernel is a sum of up to 8 lobes in kernel space (x = comb direction, y = bitangent,
/// z = surface normal; kernel units). Lobe l is g_l(p) = a_l exp(-1/2 |T_l^-1 p|^2) with the
/// affine T_l = M R S (offset, rotation, axis sigmas) stored as one 4x4 matrix, truncated at
/// `supportSigma` sigmas. An impulse places the kernel in the world with its frame F, scale S
/// (world units per kernel unit) and bend; `placeLobe` gives the resulting world-space lobe.
#pragma once

#include <vector>

#include <glm/glm.hpp>

#include "preset.h"

namespace spot::noise {

struct Impulse;

/// Smallest sigma a lobe may have, relative to the kernel's largest sigma: zero sigmas from a
/// preset are raised to this floor so every lobe stays invertible (its mass goes to ~0 instead of
/// producing Inf/NaN). 1e-6 keeps 1e4:1 anisotropy exact.
inline constexpr float kSigmaFloorRelative = 1e-6f;

struct Lobe {
    glm::mat4 transform{1.0f};  ///< T = M R S, lobe space -> kernel space (kernel units)
    glm::mat3 inverseLinear{1.0f}; ///< (R S)^-1, kernel space -> lobe space (linear part)
    glm::vec3 centre{0.0f};     ///< M's translation, kernel units
    glm::vec3 sigma{1.0f};      ///< after the floor, kernel units
    float extinction = 1.0f;    ///< peak extinction a, 1/world unit
    glm::vec3 color{1.0f};      ///< linear RGB
    LobeShading shading;        ///< lit scenes: the lobe's model (preset.h)
};

struct Kernel {
    std::vector<Lobe> lobes;
    float supportSigma = 3.0f;

    /// Radius (kernel units) of a ball about the kernel origin that holds every lobe's truncated
    /// support for any bend: the arc a bent centre moves on is no longer than the straight one.
    float supportRadius() const;
};

Kernel buildKernel(const KernelDesc& desc);

/// A lobe placed in the world by one impulse: density(x) = extinction * exp(-1/2 |A (x - c)|^2)
/// inside |A (x - c)| < supportSigma. Double precision: this is what the reference integrates.
struct WorldLobe {
    glm::dvec3 centre{0.0};
    glm::dmat3 toLobe{1.0}; ///< A, world -> lobe space (linear)
    double extinction = 0.0; ///< a * |w|, 1/world unit
    glm::vec3 color{1.0f};   ///< lobe colour * impulse colour
};

/// World lobe `lobeIndex` of `kernel` placed by `impulse` (frame, scale, bend, weight, colour).
WorldLobe placeLobe(const Kernel& kernel, int lobeIndex, const Impulse& impulse);

/// What lit shading takes from a kernel lobe (shaders/spot_light.h), the same for the reference
/// and the GPU: its model (kSpotShade*), a strand's tangent in kernel space (its longest axis,
/// turned from root to tip: towards kernel +z, then +x, then +y where it has no z), a flake's
/// normal (its shortest axis, 0..2), and the highlights as (shift, width in radians, strength).
struct LobeLitModel {
    std::uint32_t model = 0;
    glm::dvec3 tangent{0.0, 0.0, 1.0};
    int shortest = 0;
    glm::dvec3 primary{0.0}, secondary{0.0};
};
LobeLitModel lobeLitModel(const Lobe& lobe);
/// Lit shading's axis of lobe `lobeIndex` placed by `impulse` as `placed` (placeLobe's), a unit
/// world-space vector (docs/design.md, "Lighting"): a strand lobe's tangent (lobeLitModel's,
/// through spotPlacedAxis: tilt, spin, scale and bend, root to tip); a flake lobe's normal
/// (spotPlacedNormal of its shortest axis) turned to the side of the impulse's surface normal, so
/// that the flakes of one surface average to its side (the model is two-sided); zero for a
/// lambert lobe, whose normal is the extinction gradient. What the bake's shading grids hold.
glm::dvec3 placedShadingAxis(const Kernel& kernel, int lobeIndex, const Impulse& impulse,
                             const WorldLobe& placed);

/// A lobe's own shadow (spot_shared.h's spotOwnShadow, three rings) tabulated for lobes truncated
/// at `support` sigmas, laid out as shaders/spot_shadow.h says (kOwnShadowA x kOwnShadowB x
/// kOwnShadowC floats): what the GPU's lit lobes look up. Made once per support in a process
/// (about 50 ms on two cores), then shared.
const std::vector<float>& ownShadowTable(float support);
/// The table's trilinear lookup (what light_common.glsl's litOwnShadow does): within 0.006 of
/// spotOwnShadow over a and b in [e^-5, e^4].
float ownShadowLookup(const std::vector<float>& table, float a, float b, float c);

} // namespace spot::noise
