// The header shared by C++ and GLSL: it compiles as GLSL, and its random numbers, samplers and
// frames have the statistics and invariants the generator relies on.
#include <cmath>
#include <cstdlib>
#include <limits>
#include <map>
#include <string>
#include <vector>

#include <boost/math/special_functions/gamma.hpp>
#include <gtest/gtest.h>

#include "shaders/spot_shared.hpp"

namespace {

namespace f32 = spot::shared::f32;
namespace f64 = spot::shared::f64;

/// Upper-tail p-value of a chi-square statistic with `dof` degrees of freedom.
double chiSquareP(double statistic, double dof) {
    return boost::math::gamma_q(dof / 2.0, statistic / 2.0);
}

TEST(SharedHeader, CompilesAsGlsl) {
    // The same file the build compiles; here also with the optimizer, so a problem the
    // front end lets through is still caught, and with its output checked to exist.
    const std::string out = std::string(SPOT_TEST_TMP_DIR) + "/shared_check.spv";
    std::remove(out.c_str());
    const std::string cmd = std::string(SPOT_GLSLANG) + " --quiet --target-env vulkan1.2 -Os -I" +
                            SPOT_SOURCE_DIR + "/shaders -o " + out + " " + SPOT_SOURCE_DIR +
                            "/shaders/shared_check.comp";
    ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
    FILE* f = std::fopen(out.c_str(), "rb");
    ASSERT_NE(f, nullptr);
    unsigned magic = 0;
    ASSERT_EQ(std::fread(&magic, 4, 1, f), 1u);
    std::fclose(f);
    EXPECT_EQ(magic, 0x07230203u); // SPIR-V magic number
}

TEST(SharedHeader, GlslRejectsABrokenHeader) {
    // The compile test above could pass vacuously if glslang accepted anything: a shader with a
    // C++-only construct must fail.
    const std::string src = std::string(SPOT_TEST_TMP_DIR) + "/broken.comp";
    FILE* f = std::fopen(src.c_str(), "w");
    ASSERT_NE(f, nullptr);
    std::fputs("#version 450\nlayout(local_size_x=1) in;\nvoid f(float& x) { x = 1.0; }\n"
               "void main() {}\n",
               f);
    std::fclose(f);
    const std::string cmd = std::string(SPOT_GLSLANG) + " --quiet --target-env vulkan1.2 -o " +
                            SPOT_TEST_TMP_DIR + "/broken.spv " + src + " > /dev/null 2>&1";
    EXPECT_NE(std::system(cmd.c_str()), 0);
}

TEST(SharedHeader, FloatAndDoubleInstancesAgreeOnIntegers) {
    for (unsigned i = 0; i < 1000; ++i) {
        EXPECT_EQ(f32::spotHash(i), f64::spotHash(i));
        EXPECT_EQ(f32::spotCellKey(int(i) - 500, 3, -7, 42u), f64::spotCellKey(int(i) - 500, 3, -7, 42u));
        EXPECT_EQ(double(f32::spotRand(i, 3u)), f64::spotRand(i, 3u)); // 24-bit values are exact
    }
}

TEST(SharedHeader, RandIsUniform) {
    constexpr int kBins = 64, kSamples = 640000;
    std::vector<int> bins(kBins, 0);
    double sum = 0.0;
    for (int i = 0; i < kSamples; ++i) {
        const float u = f32::spotRand(f32::spotImpulseKey(f32::spotCellKey(i % 97, i / 97, 1, 5u), 0u),
                                      f32::kRandDensity);
        ASSERT_GE(u, 0.0f);
        ASSERT_LT(u, 1.0f);
        bins[int(u * kBins)]++;
        sum += u;
    }
    double chi2 = 0.0;
    const double expected = double(kSamples) / kBins;
    for (int b : bins)
        chi2 += (b - expected) * (b - expected) / expected;
    EXPECT_GT(chiSquareP(chi2, kBins - 1), 0.001) << "chi2 " << chi2;
    EXPECT_NEAR(sum / kSamples, 0.5, 0.002);
}

TEST(SharedHeader, DifferentSeedsAndStreamsAreIndependent) {
    // Correlation between the density stream and the placement stream, and between two seeds.
    constexpr int n = 200000;
    double sxy = 0.0, sx = 0.0, sy = 0.0, sxx = 0.0, syy = 0.0;
    for (int i = 0; i < n; ++i) {
        const unsigned key = f32::spotImpulseKey(f32::spotCellKey(i, 0, 0, 1u), 3u);
        const double x = f32::spotRand(key, f32::kRandDensity);
        const double y = f32::spotRand(f32::spotImpulseKey(f32::spotCellKey(i, 0, 0, 2u), 3u),
                                       f32::kRandDensity);
        sxy += x * y;
        sx += x;
        sy += y;
        sxx += x * x;
        syy += y * y;
    }
    const double cov = sxy / n - (sx / n) * (sy / n);
    const double corr = cov / std::sqrt((sxx / n - sx * sx / n / n) * (syy / n - sy * sy / n / n));
    EXPECT_LT(std::abs(corr), 0.01);
}

TEST(SharedHeader, PoissonCountsHaveTheirDistribution) {
    for (double lambda : {0.3, 4.0, 37.5, 250.0}) {
        constexpr int n = 40000;
        std::map<unsigned, int> histogram;
        double sum = 0.0, sum2 = 0.0;
        for (int i = 0; i < n; ++i) {
            const unsigned k = f64::spotPoisson(lambda, f64::spotCellKey(i, 17, -3, 9u));
            histogram[k]++;
            sum += k;
            sum2 += double(k) * k;
        }
        const double mean = sum / n, var = sum2 / n - mean * mean;
        EXPECT_NEAR(mean, lambda, 4.0 * std::sqrt(lambda / n)) << "lambda " << lambda;
        EXPECT_NEAR(var / lambda, 1.0, 0.06) << "lambda " << lambda;
        // Chi-square against the Poisson pmf over bins with expected count >= 20.
        double chi2 = 0.0;
        int dof = -1;
        double restExpected = n, restObserved = n;
        for (unsigned k = 0; k < 2000; ++k) {
            const double pmf =
                std::exp(-lambda + k * std::log(lambda) - std::lgamma(double(k) + 1.0));
            const double e = n * pmf;
            if (e < 20.0)
                continue;
            const double o = histogram.count(k) ? histogram[k] : 0;
            chi2 += (o - e) * (o - e) / e;
            restExpected -= e;
            restObserved -= o;
            ++dof;
        }
        if (restExpected >= 20.0) {
            chi2 += (restObserved - restExpected) * (restObserved - restExpected) / restExpected;
            ++dof;
        }
        ASSERT_GT(dof, 0);
        EXPECT_GT(chiSquareP(chi2, dof), 0.001) << "lambda " << lambda << " chi2 " << chi2;
    }
}

TEST(SharedHeader, TriangleSamplesAreUniform) {
    // In barycentric space uniform on the triangle: each weight has mean 1/3, and the four
    // sub-triangles made by the edge midpoints each get a quarter.
    constexpr int n = 200000;
    int quarter[4] = {0, 0, 0, 0};
    glm::dvec3 mean(0.0);
    for (int i = 0; i < n; ++i) {
        const glm::dvec3 w = f64::spotSampleTriangle(f64::spotRand(unsigned(i), 0u),
                                                     f64::spotRand(unsigned(i), 1u));
        ASSERT_NEAR(w.x + w.y + w.z, 1.0, 1e-12);
        ASSERT_GE(std::min({w.x, w.y, w.z}), 0.0);
        mean += w;
        const int q = w.x > 0.5 ? 0 : w.y > 0.5 ? 1 : w.z > 0.5 ? 2 : 3;
        quarter[q]++;
    }
    mean /= double(n);
    for (int c = 0; c < 3; ++c)
        EXPECT_NEAR(mean[c], 1.0 / 3.0, 0.003);
    double chi2 = 0.0;
    for (int q : quarter)
        chi2 += (q - n / 4.0) * (q - n / 4.0) / (n / 4.0);
    EXPECT_GT(chiSquareP(chi2, 3), 0.001);
}

TEST(SharedHeader, KernelFrameIsARotationWithTheRequestedTilt) {
    for (int i = 0; i < 500; ++i) {
        const glm::dvec3 n = glm::normalize(glm::dvec3(f64::spotRand(i, 0) - 0.5,
                                                       f64::spotRand(i, 1) - 0.5,
                                                       f64::spotRand(i, 2) - 0.5));
        const glm::dvec3 comb(f64::spotRand(i, 3) - 0.5, f64::spotRand(i, 4) - 0.5,
                              f64::spotRand(i, 5) - 0.5);
        const double tilt = 1.4 * f64::spotRand(i, 6), spin = 6.0 * f64::spotRand(i, 7);
        const glm::dmat3 f = f64::spotKernelFrame(n, comb, glm::dvec3(1, 0, 0), tilt, spin);
        const glm::dmat3 should = glm::transpose(f) * f;
        for (int c = 0; c < 3; ++c)
            for (int r = 0; r < 3; ++r)
                EXPECT_NEAR(should[c][r], c == r ? 1.0 : 0.0, 1e-12);
        EXPECT_NEAR(glm::determinant(f), 1.0, 1e-12);
        EXPECT_NEAR(std::acos(std::clamp(glm::dot(f[2], n), -1.0, 1.0)), tilt, 1e-6);
        // The kernel z axis leans towards the comb direction.
        const glm::dvec3 combT = comb - n * glm::dot(comb, n);
        if (tilt > 0.05 && glm::length(combT) > 0.05)
            EXPECT_GT(glm::dot(f[2], combT), 0.0);
    }
    // A comb parallel to the normal falls back to the given tangent.
    const glm::dmat3 f = f64::spotKernelFrame(glm::dvec3(0, 0, 1), glm::dvec3(0, 0, 2),
                                              glm::dvec3(0, 1, 0), 0.0, 0.0);
    EXPECT_NEAR(f[0].y, 1.0, 1e-12);
}

TEST(SharedHeader, BendFollowsACircularArc) {
    glm::dmat3 rot;
    for (double kappa : {1e-9, 1e-3, 0.5, 2.0}) {
        const double z = 1.3;
        const glm::dvec3 c = f64::spotBendLobe(glm::dvec3(0.0, 0.0, z), kappa, rot);
        // Chord of an arc of length z and curvature kappa: 2 sin(kappa z / 2) / kappa.
        EXPECT_NEAR(glm::length(c), 2.0 * std::sin(kappa * z / 2.0) / kappa, 1e-9) << kappa;
        EXPECT_GE(c.x, 0.0);
        EXPECT_NEAR(glm::determinant(rot), 1.0, 1e-12);
        // The lobe's axis turns with the arc's tangent (sin, 0, cos)(kappa z).
        EXPECT_NEAR(glm::length((rot * glm::dvec3(0, 0, 1)) -
                                glm::dvec3(std::sin(kappa * z), 0.0, std::cos(kappa * z))),
                    0.0, 1e-12);
    }
}

TEST(SharedHeader, ErfcApproximationMeetsItsBound) {
    for (double x = -6.0; x <= 9.0; x += 0.001) {
        const double approx = f64::spotErfcApprox(x), exact = std::erfc(x);
        EXPECT_NEAR(approx / exact, 1.0, 2e-7) << x;
    }
}

TEST(SharedHeader, LobeLineGivesTheChordAndThePeak) {
    // A ray through a unit lobe truncated at k = 2, passing at distance 1.2 from its centre: the
    // peak where it passes nearest, perp2 = 1.44, and the chord where |o + t d| = k.
    const f64::rvec3 o(1.2, -5.0, 0.0), d(0.0, 2.0, 0.0);
    double tStar = 0.0, perp2 = 0.0, half = 0.0;
    ASSERT_TRUE(f64::spotLobeLine(o, d, 2.0, tStar, perp2, half));
    EXPECT_NEAR(tStar, 2.5, 1e-15);
    EXPECT_NEAR(perp2, 1.44, 1e-15);
    EXPECT_NEAR(half, std::sqrt(4.0 - 1.44) / 2.0, 1e-15);
    double ta = 0.0, tb = 0.0;
    ASSERT_TRUE(f64::spotLobeChord(o, d, 2.0, ta, tb));
    EXPECT_EQ(ta, tStar - half);
    EXPECT_EQ(tb, tStar + half);
    // A miss (perp2 >= k^2) and a degenerate direction: false, and zeros.
    EXPECT_FALSE(f64::spotLobeLine(o, d, 1.2, tStar, perp2, half));
    EXPECT_FALSE(f64::spotLobeChord(o, d, 1.2, ta, tb));
    EXPECT_EQ(ta, 0.0);
    EXPECT_EQ(tb, 0.0);
    EXPECT_FALSE(f64::spotLobeLine(o, f64::rvec3(0.0), 2.0, tStar, perp2, half));
    EXPECT_EQ(half, 0.0);
}

TEST(SharedHeader, PixelRayMapsTheImageCornersAndCentre) {
    // Pixel (0, 0) is the top-left corner: screen (-1, 1); (w, h) the bottom-right: (1, -1).
    const f64::rvec2 size(64.0, 48.0);
    EXPECT_EQ(f64::spotPixelToScreen(f64::rvec2(0.0, 0.0), size), f64::rvec2(-1.0, 1.0));
    EXPECT_EQ(f64::spotPixelToScreen(size, size), f64::rvec2(1.0, -1.0));
    EXPECT_EQ(f64::spotPixelToScreen(0.5 * size, size), f64::rvec2(0.0, 0.0));
    // The centre pixel's ray looks along forward; a corner's through the view's corner.
    const f64::rvec3 eye(1.0, 2.0, 3.0), forward(0.0, 0.0, -1.0), right(0.75, 0.0, 0.0),
        up(0.0, 0.5, 0.0);
    f64::rvec3 o, d;
    f64::spotPixelRay(eye, forward, right, up, false, size, 0.5 * size, o, d);
    EXPECT_EQ(o, eye);
    EXPECT_NEAR(glm::length(d - forward), 0.0, 1e-15);
    f64::spotPixelRay(eye, forward, right, up, false, size, f64::rvec2(0.0), o, d);
    EXPECT_NEAR(glm::length(d - glm::normalize(forward - right + up)), 0.0, 1e-15);
    f64::spotPixelRay(eye, forward, right, up, true, size, size, o, d);
    EXPECT_NEAR(glm::length(o - (eye + right - up)), 0.0, 1e-15);
    EXPECT_EQ(d, forward);
}

TEST(SharedHeader, GradientNormalFallsBackWhereTheGradientVanishes) {
    // The sum of the lobes' gradient terms points out of the strands: at a point beside one
    // lobe's centre, away from the centre.
    const f64::rmat3 A(2.0); // lobe space = 2 x world
    const f64::rvec3 u = A * f64::rvec3(0.3, 0.0, 0.0);
    const f64::rvec3 g = f64::spotLobeGradient(A, u, f64::spotLobeDensity(u, 3.0));
    const f64::rvec3 fallback(0.0, 0.0, 1.0);
    const f64::rvec3 n = f64::spotGradientNormal(g, fallback, 1e30);
    EXPECT_NEAR(glm::length(n - f64::rvec3(1.0, 0.0, 0.0)), 0.0, 1e-15);
    EXPECT_EQ(f64::spotGradientNormal(f64::rvec3(0.0), fallback, 1e30), fallback);
    EXPECT_EQ(f64::spotGradientNormal(f64::rvec3(1e31, 0.0, 0.0), fallback, 1e30), fallback);
    EXPECT_EQ(f64::spotGradientNormal(f64::rvec3(std::numeric_limits<double>::infinity(), 0.0, 0.0),
                                      fallback, std::numeric_limits<double>::infinity()),
              fallback);
}

} // namespace
