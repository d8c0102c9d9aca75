/// @file splats_3dgs.h
/// @brief The noise as 3D Gaussian splats (3DGS): one splat per placed lobe, in the PLY layout
/// of the reference 3DGS implementation (Kerbl et al. 2023), its cameras.json, a reader that
/// refuses malformed files, and a CPU twin of a 3DGS rasteriser to measure the mapping.
///
/// A lobe is a volume: extinction a exp(-1/2 |A (x - c)|^2) (kernel.h's WorldLobe), emitting its
/// colour. A splat is a surface-like primitive: projected to the image, it covers a pixel with
/// alpha = opacity exp(-1/2 d^T Sigma2D^-1 d) and is alpha-composited front to back. Along a unit
/// direction v a lobe's optical depth at offset d from its centre's ray is
/// tau(v) exp(-1/2 d^T Sigma2D(v)^-1 d), tau(v) = a sqrt(2 pi) / |A v|, Sigma2D the covariance
/// Sigma = (A^T A)^-1 projected along v: the same footprint as a splat of covariance Sigma, but
/// the lobe covers 1 - exp(-tau(v) g) where the splat covers opacity g. The mappings
/// (docs/design.md, "Export to 3D Gaussian splats"):
///   - peak: opacity 1 - exp(-tau), covariance Sigma (right at the centre, too narrow for thick
///     lobes, whose coverage saturates and widens);
///   - coverage: opacity 1 - exp(-tau), covariance k^2 Sigma with k^2 = Ein(tau) / (1 - exp(-tau)),
///     Ein the entire exponential integral (shaders/spot_shared.h's spotEin, which the splatting's
///     widening shares): the splat then also covers the same area as the
///     lobe (the integral of its alpha over the image plane), for every view direction.
/// tau itself is view dependent: the view-independent choice is its mean over directions; `view`
/// takes it along the ray from one eye (exact for that camera only).
///
/// Colours: 3DGS stores display (sRGB-encoded) values as degree-0 spherical harmonics,
/// f_dc = (rgb - 0.5) / C0, C0 = 0.28209479; viewers composite them as they are.
#pragma once

#include <cstddef>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "camera.h"
#include "image.h"
#include "impulses.h"
#include "kernel.h"

namespace spot::noise {

struct Mesh;

/// The zeroth spherical-harmonic basis constant, 1 / (2 sqrt(pi)).
inline constexpr double kShC0 = 0.28209479177387814;
/// The most splats export writes or the reader accepts (a 3DGS scene of 100 M splats is 24 GB).
inline constexpr std::size_t kMaxSplats = 100'000'000;

/// One splat as the file stores it (world units; the activations undone by the viewer).
struct Splat3dgs {
    glm::vec3 position{0.0f};
    glm::vec3 dc{0.0f};        ///< f_dc_0..2: (sRGB colour - 0.5) / C0
    float opacityLogit = 0.0f; ///< opacity = 1 / (1 + exp(-opacityLogit))
    glm::vec3 logScale{0.0f};  ///< the standard deviations along the rotation's axes, natural log
    glm::vec4 rotation{1.0f, 0.0f, 0.0f, 0.0f}; ///< unit quaternion w x y z, local -> world
};

enum class SplatMapping { Peak, Coverage };

struct SplatOptions {
    SplatMapping mapping = SplatMapping::Coverage;
    /// Empty: tau is the mean over directions (view independent). Set: tau along the ray from
    /// this eye (world) to the lobe's centre.
    std::optional<glm::dvec3> eye;
};

/// The splat of one placed lobe (see the file comment). Sigmas below 1e-30 world units are
/// raised to it so the log stays finite; opacity is kept in [1e-6, 1 - 1e-6].
Splat3dgs lobeSplat(const WorldLobe& lobe, const SplatOptions& options);

/// Every lobe of every impulse, in impulse order (lobe order within). InputError when there
/// would be more than kMaxSplats or they would not fit in memory.
std::vector<Splat3dgs> noiseSplats(const Kernel& kernel, const std::vector<Impulse>& impulses,
                                   const SplatOptions& options);

/// The opaque base mesh as splats: one flat splat per triangle with the triangle's own
/// covariance (1/12 sum (v_i - m)(v_i - m)^T) widened by `spread`, a hundredth of its shortest
/// in-plane sigma thick, opacity 0.99, colour `color` (linear RGB). 1.2 measured best of 0.8 to
/// 2.5 on fur-bunny, fur-bunny-close and ring-sphere: wider ones hide the lobes that straddle the
/// surface (splats sort by their centres), narrower ones leave holes at the vertices.
std::vector<Splat3dgs> meshSplats(const Mesh& mesh, glm::vec3 color, double spread = 1.2);

/// A 3DGS file read back.
struct Splats3dgsFile {
    std::vector<Splat3dgs> splats;
    int shDegree = 0;             ///< from the number of f_rest_* properties (0, 1, 2 or 3)
    glm::vec3 lo{0.0f}, hi{0.0f}; ///< bounds of the positions (zero when empty)
};

/// Write `splats` as a binary little-endian PLY: one `vertex` element per splat, float
/// properties x y z nx ny nz (zeros) f_dc_0..2 opacity scale_0..2 rot_0..3 (SH degree 0: no
/// f_rest_*). InputError for a non-finite value or more than kMaxSplats; the size is checked
/// against the free disk space first. Written atomically.
void writeSplats3dgs(const std::filesystem::path& file, const std::vector<Splat3dgs>& splats,
                     const std::vector<std::string>& comments);

/// Read a 3DGS PLY (SH degree 0 to 3). InputError naming the file for anything else: not binary
/// little-endian, properties other than the layout above (or out of order, or not float),
/// other elements before the vertices, a truncated body, a non-finite value.
Splats3dgsFile readSplats3dgs(const std::filesystem::path& file);

/// The camera as the reference 3DGS implementation writes cameras.json: a list with one entry
/// {id, img_name, width, height, position, rotation (3x3 camera -> world, rows; camera axes
/// x right, y down, z forward), fx, fy}. InputError for an orthographic camera (3DGS cameras are
/// pinholes).
std::string camerasJson(const Camera& camera, const std::string& imageName);

/// A CPU twin of a 3DGS rasteriser: each splat's covariance projected with the perspective
/// Jacobian at its centre (culled nearer than 0.01 to the eye's plane, as viewers cull at their
/// near plane), widened by 0.3 px^2, sorted by view depth, alpha = min(0.99, opacity
/// exp(-1/2 d^T Sigma2D^-1 d)) at pixel centres (skipped below 1/255, beyond 3 sigma),
/// composited front to back in display values over `background` (linear RGB), as viewers do.
/// `antialiased`: the opacity is scaled by sqrt(det Sigma2D / det(Sigma2D + 0.3 I)), as
/// Mip-Splatting and viewers' "antialiased" modes do, so the widening keeps a splat's mass.
/// The result is linear RGB (display values decoded), so it compares with spotshell's images.
Image renderSplats(const std::vector<Splat3dgs>& splats, const Camera& camera, glm::vec3 background,
                   bool antialiased = true);

} // namespace spot::noise
