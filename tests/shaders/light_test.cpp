// The lit shading model of shaders/spot_light.h: each function against its closed form, worked
// by hand for chosen tangents, normals and lights, in float (the GPU's twin) and double (the
// reference), and the header compiles as GLSL.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>

#include <gtest/gtest.h>

#include "shaders/spot_light.hpp"

namespace {

namespace f32 = spot::shared::f32;
namespace f64 = spot::shared::f64;

/// Both instances as overloads (float and double arguments), so one template checks either.
namespace both {
using f32::spotHighlight, f64::spotHighlight;
using f32::spotLobeDiffuse, f64::spotLobeDiffuse;
using f32::spotLobeShade, f64::spotLobeShade;
using f32::spotPointFalloff, f64::spotPointFalloff;
using f32::spotSkyDirection, f64::spotSkyDirection;
using f32::spotStrandDiffuse, f64::spotStrandDiffuse;
using f32::spotStrandHalfAngle, f64::spotStrandHalfAngle;
constexpr unsigned kSpotShadeLambert = f64::kSpotShadeLambert;
constexpr unsigned kSpotShadeStrand = f64::kSpotShadeStrand;
constexpr unsigned kSpotShadeFlake = f64::kSpotShadeFlake;
static_assert(f32::kSpotShadeStrand == kSpotShadeStrand &&
              f32::kSpotShadeFlake == kSpotShadeFlake &&
              f32::kSpotShadeLambert == kSpotShadeLambert);
} // namespace both

constexpr double kPi = 3.14159265358979323846;
double deg(double d) {
    return d * kPi / 180.0;
}

/// The cases, written once for both instances: t = +x, l = (1,1,0)/sqrt2, v = (0,1,1)/sqrt2.
/// By hand: t.l = 1/sqrt2, so sin(t,l) = 1/sqrt2 and theta_i = 45 deg; t.v = 0, theta_r = 0;
/// theta_h = 22.5 deg. Highlights: primary (-6, 8, 0.3), secondary (9, 16, 0.5) in degrees.
template <typename real, typename vec3> struct Cases {
    static vec3 strand(vec3 c) {
        const double h = 22.5;
        const double g1 = 0.3 * std::exp(-0.5 * std::pow((h + 6.0) / 8.0, 2));
        const double g2 = 0.5 * std::exp(-0.5 * std::pow((h - 9.0) / 16.0, 2));
        const double s = std::sqrt(0.5);
        return vec3(real(s * (c.x + g1 + g2 * c.x)), real(s * (c.y + g1 + g2 * c.y)),
                    real(s * (c.z + g1 + g2 * c.z)));
    }
};

template <typename real, typename vec3> void checkModels(double tolerance) {
    const real s = real(std::sqrt(0.5));
    const vec3 t(1, 0, 0), l(s, s, 0), v(0, s, s), c(real(0.5), real(0.25), real(0.125));
    const vec3 primary(real(deg(-6.0)), real(deg(8.0)), real(0.3));
    const vec3 secondary(real(deg(9.0)), real(deg(16.0)), real(0.5));

    // The pieces.
    EXPECT_NEAR(both::spotStrandDiffuse(t, l), std::sqrt(0.5), tolerance);
    EXPECT_NEAR(both::spotStrandDiffuse(t, t), 0.0, tolerance); // light along the strand
    EXPECT_NEAR(both::spotStrandDiffuse(t, vec3(0, 1, 0)), 1.0, tolerance); // across it
    EXPECT_NEAR(both::spotStrandHalfAngle(t, l, v), deg(22.5), tolerance);
    EXPECT_NEAR(both::spotHighlight(real(deg(9.0)), secondary), 0.5, tolerance); // at its peak
    EXPECT_NEAR(both::spotHighlight(real(deg(9.0 + 16.0)), secondary), 0.5 * std::exp(-0.5),
                tolerance);

    // Strand: diffuse and both highlights, the primary white and the secondary tinted.
    const vec3 strand = both::spotLobeShade(both::kSpotShadeStrand, t, l, v, c, primary, secondary);
    const vec3 expected = Cases<real, vec3>::strand(c);
    for (int i = 0; i < 3; ++i)
        EXPECT_NEAR(strand[i], expected[i], tolerance) << "strand channel " << i;
    EXPECT_NEAR(strand.x, 0.4777581, 1e-6); // the number worked by hand (file comment)
    // With no highlights the strand is Kajiya-Kay's diffuse: c sin(t,l).
    const vec3 none(0, real(0.1), 0);
    const vec3 diffuse = both::spotLobeShade(both::kSpotShadeStrand, t, l, v, c, none, none);
    EXPECT_NEAR(diffuse.y, 0.25 * std::sqrt(0.5), tolerance);

    // Flake: n = -z; lit from l = (0, 0.6, 0.8) and seen from v (front: +z side) the normal
    // turns to +z and n.l = 0.8; seen from behind (-z) it stays -z and the light is behind it.
    const vec3 n(0, 0, -1), front(0, real(0.6), real(0.8)), back(0, 0, -1);
    EXPECT_NEAR(both::spotLobeShade(both::kSpotShadeFlake, n, front, v, c, primary, secondary).x,
                0.5 * 0.8, tolerance);
    EXPECT_NEAR(both::spotLobeShade(both::kSpotShadeFlake, n, front, back, c, primary, secondary).x,
                0.0, tolerance);
    EXPECT_NEAR(both::spotLobeShade(both::kSpotShadeFlake, -n, front, v, c, primary, secondary).x,
                0.5 * 0.8, tolerance); // two-sided: the sign of the axis does not matter

    // Lambert: one-sided max(0, n.l), n.l = 1/sqrt2 for n = +y.
    EXPECT_NEAR(
        both::spotLobeShade(both::kSpotShadeLambert, vec3(0, 1, 0), l, v, c, primary, secondary).z,
        0.125 * std::sqrt(0.5), tolerance);
    EXPECT_NEAR(
        both::spotLobeShade(both::kSpotShadeLambert, vec3(0, -1, 0), l, v, c, primary, secondary).z,
        0.0, tolerance);
    // The sky takes the diffuse part only.
    EXPECT_NEAR(both::spotLobeDiffuse(both::kSpotShadeStrand, t, l, v), std::sqrt(0.5), tolerance);

    // Point light: the inverse-square law.
    EXPECT_NEAR(both::spotPointFalloff(real(4.0), real(2.0)), 1.0, tolerance);

    // Sky directions: on the upper unit hemisphere; (0.5, 0.25) is y = 1/2 at azimuth 90 deg.
    const vec3 w = both::spotSkyDirection(real(0.5), real(0.25));
    EXPECT_NEAR(w.x, 0.0, tolerance);
    EXPECT_NEAR(w.y, 0.5, tolerance);
    EXPECT_NEAR(w.z, std::sqrt(0.75), tolerance);
    // The estimator 2 max(0, n.w) over a grid of uniforms integrates to 1 for n = +y (an
    // unshadowed upward surface receives the sky's radiance) and to 1/2 for a horizontal n.
    double up = 0.0, side = 0.0;
    constexpr int kGrid = 64;
    for (int i = 0; i < kGrid; ++i)
        for (int j = 0; j < kGrid; ++j) {
            const vec3 d = both::spotSkyDirection(real((i + 0.5) / kGrid), real((j + 0.5) / kGrid));
            EXPECT_NEAR(std::sqrt(double(dot(d, d))), 1.0, tolerance);
            up += 2.0 * std::max(0.0, double(d.y));
            side += 2.0 * std::max(0.0, double(d.x));
        }
    EXPECT_NEAR(up / (kGrid * kGrid), 1.0, 1e-3);
    EXPECT_NEAR(side / (kGrid * kGrid), 0.5, 2e-3);
}

// Double: the asin polynomial's 2e-8 (spotAsin) is the largest error; elsewhere 1e-15.
TEST(LightModel, ClosedFormsInDouble) {
    checkModels<double, glm::dvec3>(5e-8);
}

TEST(LightModel, ClosedFormsInFloat) {
    checkModels<float, glm::vec3>(2e-6);
}

TEST(LightModel, AsinIsWithinItsBound) {
    double worst = 0.0, worstFloat = 0.0;
    for (int i = -1000; i <= 1000; ++i) {
        const double x = i / 1000.0;
        worst = std::max(worst, std::abs(f64::spotAsin(x) - std::asin(x)));
        worstFloat = std::max(worstFloat, std::abs(double(f32::spotAsin(float(x))) - std::asin(x)));
    }
    EXPECT_LT(worst, 2.5e-8);
    EXPECT_LT(worstFloat, 5e-7);
    EXPECT_EQ(f64::spotAsin(1.0), f64::spotAsin(1.5)); // clamped
}

TEST(LightModel, PlacedAxesAreTheLobesAxesInTheWorld) {
    // Bent by kappa = 0.5 rad per kernel unit, a strand at height 1 has turned 0.5 rad towards +x.
    const glm::dvec3 bent = f64::spotPlacedAxis(glm::dvec3(0, 0, 1), glm::dvec3(0, 0, 1),
                                                glm::dmat3(1.0), glm::dvec3(1.0), 0.5);
    EXPECT_NEAR(bent.x, std::sin(0.5), 1e-12);
    EXPECT_NEAR(bent.y, 0.0, 1e-12);
    EXPECT_NEAR(bent.z, std::cos(0.5), 1e-12);
    // It is the tangent of the arc the bend puts the lobe centres on.
    glm::dmat3 rot;
    const double h = 1e-5;
    const glm::dvec3 arc = f64::spotBendLobe(glm::dvec3(0, 0, 1 + h), 0.5, rot) -
                           f64::spotBendLobe(glm::dvec3(0, 0, 1 - h), 0.5, rot);
    EXPECT_NEAR(glm::dot(glm::normalize(arc), bent), 1.0, 1e-9);

    // With a frame, an anisotropic scale and a rotated lobe: the tangent is the direction of
    // A^-1 e_k (the lobe's axis k as placed, A from spotPlaceLobe) and the flake normal, row k
    // of A, is perpendicular to the other two placed axes.
    const glm::dmat3 lobeRot =
        glm::dmat3(glm::dvec3(0.6, 0.8, 0), glm::dvec3(-0.8, 0.6, 0), glm::dvec3(0, 0, 1));
    const glm::dvec3 sigma(0.1, 0.4, 0.05);
    const glm::dmat3 lobeInv =
        glm::inverse(lobeRot * glm::dmat3(glm::dvec3(sigma.x, 0, 0), glm::dvec3(0, sigma.y, 0),
                                          glm::dvec3(0, 0, sigma.z)));
    const glm::dvec3 centre(0.1, 0.0, 0.8), scale(0.02, 0.03, 0.05);
    const double c = std::cos(0.3), s = std::sin(0.3);
    const glm::dmat3 frame(glm::dvec3(c, 0, -s), glm::dvec3(0, 1, 0), glm::dvec3(s, 0, c));
    glm::dvec3 placedCentre;
    const glm::dmat3 A =
        f64::spotPlaceLobe(lobeInv, centre, frame, scale, 0.4, glm::dvec3(1, 2, 3), placedCentre);
    const glm::dmat3 toWorld = glm::inverse(A);
    const glm::dvec3 tangent = f64::spotPlacedAxis(lobeRot[1], centre, frame, scale, 0.4);
    EXPECT_NEAR(std::abs(glm::dot(glm::normalize(toWorld[1]), tangent)), 1.0, 1e-12);
    const glm::dvec3 normal = f64::spotPlacedNormal(A, 2);
    EXPECT_NEAR(glm::length(normal), 1.0, 1e-12);
    EXPECT_NEAR(glm::dot(normal, toWorld[0]), 0.0, 1e-12);
    EXPECT_NEAR(glm::dot(normal, toWorld[1]), 0.0, 1e-12);
    // The float twin agrees.
    const glm::vec3 t32 = f32::spotPlacedAxis(glm::vec3(lobeRot[1]), glm::vec3(centre),
                                              glm::mat3(frame), glm::vec3(scale), 0.4f);
    for (int i = 0; i < 3; ++i)
        EXPECT_NEAR(t32[i], tangent[i], 1e-6);
}

TEST(LightModel, CompilesAsGlsl) {
    // The build compiles light_check.comp too; here with the optimizer, and the output checked.
    const std::string out = std::string(SPOT_TEST_TMP_DIR) + "/light_check.spv";
    std::remove(out.c_str());
    const std::string cmd = std::string(SPOT_GLSLANG) + " --quiet --target-env vulkan1.2 -Os -I" +
                            SPOT_SOURCE_DIR + "/shaders -o " + out + " " + SPOT_SOURCE_DIR +
                            "/shaders/light_check.comp";
    ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
    FILE* f = std::fopen(out.c_str(), "rb");
    ASSERT_NE(f, nullptr);
    unsigned magic = 0;
    ASSERT_EQ(std::fread(&magic, 4, 1, f), 1u);
    std::fclose(f);
    EXPECT_EQ(magic, 0x07230203u);
}

} // namespace
