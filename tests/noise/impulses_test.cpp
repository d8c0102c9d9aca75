// Impulses: uniform per unit of surface area, on the surface, deterministic on any thread count,
// thinned by the density field as expected.
#include <algorithm>
#include <cmath>
#include <cstring>

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include "noise/error.h"
#include "noise/impulses.h"
#include "noise/mesh.h"
#include "noise/surface.h"
#include "test_support.h"

namespace {

using namespace spot;

std::vector<noise::Impulse> generate(const noise::Mesh& mesh, const noise::PresetDesc& preset,
                                     std::uint32_t seed = 1, float cellSize = 0.0f) {
    noise::GeneratorOptions options;
    options.seed = seed;
    options.cellSize = cellSize;
    return noise::ImpulseGenerator(mesh, preset, options).generate();
}

/// Equal-area patches of a sphere centred at the origin: 8 bands of equal z-extent (Archimedes)
/// times 16 longitude sectors.
int spherePatch(glm::vec3 p) {
    const glm::vec3 d = glm::normalize(p);
    const int band = std::clamp(int((d.z + 1.0f) * 4.0f), 0, 7);
    const float phi = std::atan2(d.y, d.x) + float(M_PI);
    const int sector = std::clamp(int(phi / (2.0f * float(M_PI)) * 16.0f), 0, 15);
    return band * 16 + sector;
}

void expectUniformOnSphere(const std::vector<noise::Impulse>& impulses, const glm::mat3& rotation,
                           glm::vec3 centre, const char* what) {
    std::vector<double> counts(128, 0.0);
    const glm::mat3 inverse = glm::transpose(rotation);
    for (const noise::Impulse& m : impulses)
        counts[spherePatch(inverse * (m.position - centre))] += 1.0;
    const double chi2 = test::chiSquare(counts, std::vector<double>(128, 1.0 / 128.0));
    const double p = test::chiSquareP(chi2, 127);
    EXPECT_GT(p, 0.001) << what << ": chi2 " << chi2 << " over 127 dof with " << impulses.size()
                        << " impulses";
}

TEST(Impulses, UniformPerAreaOnASphere) {
    const noise::Mesh sphere = noise::makeSphere(1.0f, 96, 192);
    const auto impulses = generate(sphere, test::uniformPreset(2000.0f));
    // Poisson total: mean density_max * area.
    const double mean = 2000.0 * sphere.surfaceArea();
    EXPECT_NEAR(double(impulses.size()), mean, 4.0 * std::sqrt(mean));
    expectUniformOnSphere(impulses, glm::mat3(1.0f), glm::vec3(0.0f), "axis-aligned sphere");
}

TEST(Impulses, UniformPerAreaOnARotatedShiftedSphere) {
    noise::Mesh sphere = noise::makeSphere(1.0f, 96, 192);
    const glm::mat3 r = test::rotation(1.234f, {0.31f, -0.72f, 0.55f});
    const glm::vec3 t(0.0137f, -0.0291f, 0.0083f); // not a multiple of the cell size
    test::transformMesh(sphere, r, t);
    for (std::uint32_t seed : {7u, 8u}) {
        const auto impulses = generate(sphere, test::uniformPreset(2000.0f), seed);
        expectUniformOnSphere(impulses, r, t, "rotated sphere");
    }
}

TEST(Impulses, UniformPerAreaOnAPlaneWithTrianglesDifferingBy100x) {
    for (bool rotate : {false, true}) {
        noise::Mesh plane = test::mixedPlane();
        const glm::mat3 r = rotate ? test::rotation(0.61f, {0.2f, 0.9f, -0.4f}) : glm::mat3(1.0f);
        const glm::vec3 t = rotate ? glm::vec3(0.011f, 0.2f, -0.037f) : glm::vec3(0.0f);
        test::transformMesh(plane, r, t);
        const auto impulses = generate(plane, test::uniformPreset(10000.0f), 3);
        // 8 x 4 equal squares of the 2 x 1 rectangle.
        std::vector<double> counts(32, 0.0);
        const glm::mat3 inverse = glm::transpose(r);
        for (const noise::Impulse& m : impulses) {
            const glm::vec3 q = inverse * (m.position - t);
            ASSERT_NEAR(q.y, 0.0f, 1e-5f);
            const int i = std::clamp(int(q.x * 4.0f), 0, 7), j = std::clamp(int(q.z * 4.0f), 0, 3);
            counts[j * 8 + i] += 1.0;
        }
        const double chi2 = test::chiSquare(counts, std::vector<double>(32, 1.0 / 32.0));
        EXPECT_GT(test::chiSquareP(chi2, 31), 0.001) << "rotated " << rotate << " chi2 " << chi2;
        // The two halves (small and large triangles) get the same count on average.
        double left = 0.0;
        for (int j = 0; j < 4; ++j)
            for (int i = 0; i < 4; ++i)
                left += counts[j * 8 + i];
        const double n = double(impulses.size());
        EXPECT_NEAR(left, n / 2.0, 4.0 * std::sqrt(n / 4.0));
    }
}

TEST(Impulses, JitteredIsUniformAndHasTheRightDensity) {
    noise::Mesh sphere = noise::makeSphere(1.0f, 96, 192);
    const glm::mat3 r = test::rotation(0.4f, {1.0f, 2.0f, 3.0f});
    test::transformMesh(sphere, r, glm::vec3(0.0f));
    const auto impulses =
        generate(sphere, test::uniformPreset(2000.0f, 0.01f, noise::DistributionType::Jittered));
    const double mean = 2000.0 * sphere.surfaceArea();
    // A jittered lattice is less variable than Poisson: the total is very close to the mean.
    EXPECT_NEAR(double(impulses.size()) / mean, 1.0, 0.01);
    expectUniformOnSphere(impulses, r, glm::vec3(0.0f), "jittered sphere");
}

TEST(Impulses, RegularLatticeWithZeroJitter) {
    const noise::Mesh plane = noise::makePlane(2.0f, 8);
    noise::PresetDesc preset = test::uniformPreset(400.0f, 0.01f, noise::DistributionType::Jittered);
    preset.distribution.jitter = 0.0f;
    const auto impulses = generate(plane, preset);
    const double spacing = 1.0 / std::sqrt(400.0);
    EXPECT_NEAR(double(impulses.size()), 1600.0, 4.0 * 2.0 / spacing + 4.0); // +- border rows
    // Every impulse's nearest neighbour is one lattice spacing away: no duplicates, no gaps.
    for (std::size_t i = 0; i < impulses.size(); i += 7) {
        double nearest = 1e9;
        for (std::size_t j = 0; j < impulses.size(); ++j)
            if (j != i)
                nearest = std::min(nearest, double(glm::length(impulses[i].position -
                                                               impulses[j].position)));
        EXPECT_NEAR(nearest / spacing, 1.0, 1e-3) << i;
    }
}

TEST(Impulses, LieOnTheSurfaceWithZeroHeight) {
    noise::Mesh sphere = noise::makeSphere(1.0f, 48, 96);
    test::transformMesh(sphere, test::rotation(0.3f, {1, 1, 0}), glm::vec3(0.02f));
    for (auto type : {noise::DistributionType::Poisson, noise::DistributionType::Jittered}) {
        noise::GeneratorOptions options;
        options.seed = 5;
        const noise::ImpulseGenerator generator(sphere, test::uniformPreset(1500.0f, 0.01f, type),
                                                options);
        const double h = generator.cellSize();
        const auto impulses = generator.generate();
        ASSERT_GT(impulses.size(), 10000u);
        double worst = 0.0;
        for (const noise::Impulse& m : impulses) {
            const glm::uvec3 t = sphere.triangles[m.triangle];
            const glm::dvec3 a(sphere.positions[t.x]), b(sphere.positions[t.y]),
                c(sphere.positions[t.z]);
            const glm::dvec3 w = noise::closestPointBarycentric(glm::dvec3(m.position), a, b, c);
            const double d = glm::length(glm::dvec3(m.position) - (w.x * a + w.y * b + w.z * c));
            worst = std::max(worst, d);
            // The anchor cell holds the anchor point.
            ASSERT_EQ(generator.cells().cellOf(m.position), m.cell);
        }
        EXPECT_LE(worst, 0.01 * h) << "worst distance " << worst << " with h " << h;
    }
}

TEST(Impulses, HeightOffsetMovesAlongTheNormal) {
    const noise::Mesh plane = noise::makePlane(2.0f, 4);
    noise::PresetDesc preset = test::uniformPreset(500.0f);
    preset.distribution.heightOffset = 0.02f;
    preset.distribution.heightJitter = 0.005f;
    const auto impulses = generate(plane, preset);
    ASSERT_FALSE(impulses.empty());
    for (const noise::Impulse& m : impulses) {
        EXPECT_NEAR(m.position.y, m.height, 1e-6f);
        EXPECT_GE(m.height, 0.015f - 1e-6f);
        EXPECT_LE(m.height, 0.025f + 1e-6f);
    }
}

TEST(Impulses, LinearDensityGradientGivesTheExpectedCounts) {
    const noise::Mesh plane = noise::makePlane(2.0f, 16); // [-1, 1]^2 in xz
    noise::PresetDesc preset = test::uniformPreset(5000.0f);
    preset.density.kind = noise::FieldDesc::Kind::Gradient;
    preset.density.from = glm::vec3(-1.0f, 0.0f, 0.0f);
    preset.density.to = glm::vec3(1.0f, 0.0f, 0.0f);
    preset.density.lo = glm::vec3(0.0f);
    preset.density.hi = glm::vec3(1.0f);
    const auto impulses = generate(plane, preset, 11);
    double left = 0.0, right = 0.0;
    for (const noise::Impulse& m : impulses)
        (m.position.x < 0.0f ? left : right) += 1.0;
    // d(x) = (x + 1) / 2: mean 1/4 on the left half, 3/4 on the right, each half of area 2.
    const double muLeft = 5000.0 * 2.0 * 0.25, muRight = 5000.0 * 2.0 * 0.75;
    EXPECT_NEAR(left, muLeft, 3.0 * std::sqrt(muLeft));
    EXPECT_NEAR(right, muRight, 3.0 * std::sqrt(muRight));
    // Ratio 3 within 3 sigma (delta method on two Poisson counts).
    const double ratio = right / left;
    const double sigma = 3.0 * std::sqrt(1.0 / muLeft + 1.0 / muRight);
    EXPECT_NEAR(ratio, 3.0, 3.0 * sigma);
}

bool sameImpulses(const std::vector<noise::Impulse>& a, const std::vector<noise::Impulse>& b) {
    if (a.size() != b.size())
        return false;
    for (std::size_t i = 0; i < a.size(); ++i) {
        const noise::Impulse &x = a[i], &y = b[i];
        if (std::memcmp(&x.position, &y.position, sizeof x.position) ||
            std::memcmp(&x.frame, &y.frame, sizeof x.frame) ||
            std::memcmp(&x.scale, &y.scale, sizeof x.scale) ||
            std::memcmp(&x.color, &y.color, sizeof x.color) || x.weight != y.weight ||
            x.triangle != y.triangle || x.barycentric != y.barycentric || x.cell != y.cell)
            return false;
    }
    return true;
}

TEST(Impulses, DeterministicOnOneAndTwoThreads) {
    const noise::Mesh torus = noise::makeTorus(1.0f, 0.35f, 96, 32);
    noise::PresetDesc preset = test::uniformPreset(3000.0f);
    preset.variation.tiltDeg = 20.0f;
    preset.variation.spinDeg = 180.0f;
    preset.variation.scale = 0.3f;
    preset.variation.color = 0.2f;
    for (auto type : {noise::DistributionType::Poisson, noise::DistributionType::Jittered}) {
        preset.distribution.type = type;
        std::vector<noise::Impulse> one, two;
        {
            tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
            one = generate(torus, preset, 42);
        }
        {
            tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 2);
            two = generate(torus, preset, 42);
        }
        ASSERT_GT(one.size(), 1000u);
        EXPECT_TRUE(sameImpulses(one, two));
        // And a different seed gives different impulses.
        EXPECT_FALSE(sameImpulses(one, generate(torus, preset, 43)));
    }
}

TEST(Impulses, CellSizeBelowTheSupportRadiusIsRefused) {
    const noise::Mesh sphere = noise::makeSphere(1.0f, 16, 32);
    const noise::PresetDesc preset = test::uniformPreset(100.0f, 0.01f); // support 0.03
    EXPECT_THROW(generate(sphere, preset, 1, 0.02f), InputError);
    EXPECT_NO_THROW(generate(sphere, preset, 1, 0.05f));
    noise::GeneratorOptions options;
    EXPECT_NEAR(noise::ImpulseGenerator(sphere, preset, options).cellSize(), 0.03f, 1e-6f);
}

TEST(Impulses, CountsDoNotDependOnTheCellSize) {
    const noise::Mesh sphere = noise::makeSphere(1.0f, 64, 128);
    const double mean = 1000.0 * sphere.surfaceArea();
    for (float h : {0.03f, 0.07f, 0.2f}) {
        const auto impulses = generate(sphere, test::uniformPreset(1000.0f), 9, h);
        EXPECT_NEAR(double(impulses.size()), mean, 4.0 * std::sqrt(mean)) << "h " << h;
    }
}

TEST(Impulses, AbsurdDensityIsRefused) {
    const noise::Mesh sphere = noise::makeSphere(1.0f, 16, 32);
    EXPECT_THROW(generate(sphere, test::uniformPreset(1e8f)), InputError);
}

TEST(Impulses, FramesAreOrthonormalAndTiltedAsAsked) {
    const noise::Mesh sphere = noise::makeSphere(1.0f, 32, 64);
    noise::PresetDesc preset = test::uniformPreset(300.0f);
    preset.tiltDeg = test::constantField(glm::vec3(30.0f), 1);
    const auto impulses = generate(sphere, preset);
    ASSERT_FALSE(impulses.empty());
    for (const noise::Impulse& m : impulses) {
        EXPECT_NEAR(glm::determinant(m.frame), 1.0f, 1e-4f);
        EXPECT_NEAR(std::acos(std::clamp(glm::dot(m.frame[2], m.normal), -1.0f, 1.0f)),
                    glm::radians(30.0f), 1e-3f);
        EXPECT_NEAR(glm::dot(m.comb, m.normal), 0.0f, 1e-4f);
        EXPECT_NEAR(glm::length(m.comb), 1.0f, 1e-4f);
    }
}

} // namespace
