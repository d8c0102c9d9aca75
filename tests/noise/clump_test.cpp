// Clumps (shaders/spot_clump.h, docs/design.md section 3 "Clumps"): the centres are a
// deterministic point process uniform on the surface, the on-the-fly search finds the nearest
// one as an exhaustive search does, a clumped kernel's tip gathers towards its clump's axis while
// its root stays, and a preset whose clumps have no strength generates exactly the unclumped
// impulses.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>
#include <set>
#include <vector>

#include <gtest/gtest.h>

#include "noise/generator_shared.h"
#include "noise/impulses.h"
#include "noise/mesh.h"
#include "noise/preset.h"
#include "noise/shared_data.h"
#include "test_support.h"

namespace {

using namespace spot;
using Generator = shared::f32::SharedGenerator;

/// The shared generator's clump functions read nothing of the model.
Generator clumpFunctions() {
    static const shared::f32::GeneratorArrays none;
    return Generator(none);
}

noise::PresetDesc shippedPreset(const std::string& name) {
    return noise::loadPreset(std::string(SPOT_SOURCE_DIR) + "/presets/" + name + ".json");
}

/// An orthonormal basis (u, v) of the plane with unit normal n.
void planeBasis(glm::vec3 n, glm::vec3& u, glm::vec3& v) {
    u = glm::normalize(glm::cross(n, std::abs(n.x) < 0.9f ? glm::vec3(1, 0, 0) : glm::vec3(0, 1, 0)));
    v = glm::cross(n, u);
}

/// Every clump centre of the plane through p0 with normal n whose projection lies in the square
/// p0 + [0, 1]^2 of the plane's basis: the seeds of the slab |(x - p0).n| < G / 2, enumerated
/// cell by cell (not through the nearest search), as plane coordinates.
std::vector<glm::vec2> centresInSquare(glm::vec3 p0, glm::vec3 n, float grid, float relativeSize,
                                       float variation, std::uint32_t seed) {
    Generator g = clumpFunctions();
    glm::vec3 u, v;
    planeBasis(n, u, v);
    glm::vec3 lo(1e30f), hi(-1e30f);
    for (const glm::vec2 c : {glm::vec2(0, 0), glm::vec2(1, 0), glm::vec2(0, 1), glm::vec2(1, 1)}) {
        const glm::vec3 p = p0 + c.x * u + c.y * v;
        lo = glm::min(lo, p);
        hi = glm::max(hi, p);
    }
    const glm::ivec3 q0(glm::floor((lo - grid) / grid)), q1(glm::floor((hi + grid) / grid));
    const float m = relativeSize, mu = 1.0f / (m * m), a = 0.5f * variation;
    std::vector<glm::vec2> out;
    for (int z = q0.z; z <= q1.z; ++z)
        for (int y = q0.y; y <= q1.y; ++y)
            for (int x = q0.x; x <= q1.x; ++x) {
                const glm::ivec3 q(x, y, z);
                const std::uint32_t key = g.spotClumpCellKey(q, seed);
                for (std::uint32_t s = 0; s < Generator::kClumpMaxSeeds && float(s) < mu; ++s) {
                    glm::vec3 pos;
                    float w;
                    if (!g.spotClumpSeed(q, key, s, grid, mu, a, pos, w))
                        continue;
                    const glm::vec3 d = pos - p0;
                    if (!(std::abs(glm::dot(d, n)) < 0.5f * grid))
                        continue;
                    const glm::vec2 c(glm::dot(d, u), glm::dot(d, v));
                    if (c.x >= 0.0f && c.x < 1.0f && c.y >= 0.0f && c.y < 1.0f)
                        out.push_back(c);
                }
            }
    return out;
}

// The centres seen from a plane are mu / G^2 per unit area, uniform over the plane whatever its
// orientation against the clump grid (chi-square over 8 x 8 bins), and the same for the same
// seed.
TEST(Clumps, CentresAreDeterministicAndUniformOnAPlaneAtAnyOrientation) {
    const float grid = 0.025f;
    for (const glm::vec3 n : {glm::vec3(0, 0, 1), glm::normalize(glm::vec3(1, 2, 3)),
                              glm::normalize(glm::vec3(-0.3f, 0.9f, 0.2f))}) {
        for (const float m : {1.0f, 0.7f, 1.6f}) {
            const glm::vec3 p0(0.37f, -0.21f, 0.55f);
            const std::vector<glm::vec2> c = centresInSquare(p0, n, grid, m, 0.4f, 77);
            const double expected = 1.0 / double(grid * m * grid * m);
            EXPECT_NEAR(double(c.size()), expected, 4.0 * std::sqrt(expected))
                << "normal " << n.x << " " << n.y << " " << n.z << ", relative size " << m;
            std::vector<double> counts(64, 0.0);
            for (const glm::vec2 p : c)
                counts[std::min(int(p.x * 8.0f), 7) * 8 + std::min(int(p.y * 8.0f), 7)] += 1.0;
            const double chi2 = test::chiSquare(counts, std::vector<double>(64, 1.0 / 64.0));
            EXPECT_GT(test::chiSquareP(chi2, 63), 0.001)
                << "chi2 " << chi2 << " over 63 dof, " << c.size() << " centres, normal " << n.x
                << " " << n.y << " " << n.z << ", relative size " << m;
            // Deterministic: the same centres again; another seed, other centres.
            EXPECT_EQ(centresInSquare(p0, n, grid, m, 0.4f, 77), c);
            const std::vector<glm::vec2> other = centresInSquare(p0, n, grid, m, 0.4f, 78);
            std::size_t shared = 0;
            const std::set<std::pair<float, float>> mine = [&] {
                std::set<std::pair<float, float>> s;
                for (const glm::vec2 p : c)
                    s.insert({p.x, p.y});
                return s;
            }();
            for (const glm::vec2 p : other)
                shared += mine.count({p.x, p.y});
            EXPECT_LT(shared, c.size() / 100 + 1);
        }
    }
}

// The nearest (weighted) centre the bounded on-the-fly search finds is the one an exhaustive
// search over every seed of the slab finds, at the extremes of relative size and variation.
TEST(Clumps, NearestCentreMatchesAnExhaustiveSearch) {
    Generator g = clumpFunctions();
    const float grid = 0.05f;
    const glm::vec3 n = glm::normalize(glm::vec3(0.4f, -0.5f, 0.77f));
    glm::vec3 u, v;
    planeBasis(n, u, v);
    std::uint32_t state = 12345u;
    const auto uniform = [&] {
        state = shared::f32::spotHash(state + 0x9e3779b9u);
        return float(state >> 8) / 16777216.0f;
    };
    for (const float m : {0.5f, 1.0f, 2.0f})
        for (const float variation : {0.0f, 0.5f, 1.0f}) {
            const float mu = 1.0f / (m * m), a = 0.5f * variation;
            int mismatches = 0, queries = 0;
            const int cells = int(std::ceil(6.0f * m)) + 1;
            for (int i = 0; i < 60; ++i, ++queries) {
                const glm::vec3 p = glm::vec3(-0.3f, 0.8f, 0.1f) + 3.0f * (uniform() * u + uniform() * v);
                const auto found = g.spotNearestClump(p, n, grid, m, variation, 99);
                ASSERT_TRUE(found.found);
                // Exhaustive: every seed of the slab within 6 m G cells.
                const glm::ivec3 c(glm::floor(p / grid));
                float best = 1e30f;
                glm::vec3 centre(0.0f);
                for (int z = -cells; z <= cells; ++z)
                    for (int y = -cells; y <= cells; ++y)
                        for (int x = -cells; x <= cells; ++x) {
                            const glm::ivec3 q = c + glm::ivec3(x, y, z);
                            const std::uint32_t key = g.spotClumpCellKey(q, 99);
                            for (std::uint32_t s = 0; s < Generator::kClumpMaxSeeds && float(s) < mu; ++s) {
                                glm::vec3 pos;
                                float w;
                                if (!g.spotClumpSeed(q, key, s, grid, mu, a, pos, w))
                                    continue;
                                const float dn = glm::dot(pos - p, n);
                                if (!(std::abs(dn) < 0.5f * grid))
                                    continue;
                                const glm::vec3 t = pos - p - n * dn;
                                const float score = glm::dot(t, t) / (w * w);
                                if (score < best) {
                                    best = score;
                                    centre = p + t;
                                }
                            }
                        }
                mismatches += glm::length(centre - found.centre) > 1e-5f;
                EXPECT_NEAR(found.distance, glm::length(found.centre - p), 1e-6f);
            }
            EXPECT_EQ(mismatches, 0) << "relative size " << m << ", variation " << variation
                                     << ": " << mismatches << " of " << queries;
        }
}

// Seen from the surface of a sphere, the centres' directions are uniform (chi-square over 64
// equal-area patches), and about area / size^2 of them.
TEST(Clumps, CentresAreUniformOnASphere) {
    Generator g = clumpFunctions();
    const float size = 0.1f;
    std::map<std::uint32_t, glm::vec3> centres;
    const int n = 40000;
    for (int i = 0; i < n; ++i) {
        // A Fibonacci lattice: points about sqrt(4 pi / n) = 0.018 apart.
        const float z = 1.0f - (2.0f * float(i) + 1.0f) / float(n);
        const float r = std::sqrt(1.0f - z * z);
        const float phi = 2.39996323f * float(i);
        const glm::vec3 p(r * std::cos(phi), r * std::sin(phi), z);
        const auto c = g.spotNearestClump(p, p, size, 1.0f, 0.3f, 5);
        ASSERT_TRUE(c.found);
        centres.emplace(c.id, glm::normalize(c.centre));
    }
    std::vector<double> counts(64, 0.0);
    for (const auto& [id, d] : centres) {
        const int band = std::clamp(int((d.z + 1.0f) * 2.0f), 0, 3);
        const float phi = std::atan2(d.y, d.x) + float(M_PI);
        const int sector = std::clamp(int(phi / (2.0f * float(M_PI)) * 16.0f), 0, 15);
        counts[band * 16 + sector] += 1.0;
    }
    const double chi2 = test::chiSquare(counts, std::vector<double>(64, 1.0 / 64.0));
    EXPECT_GT(test::chiSquareP(chi2, 63), 0.001) << "chi2 " << chi2 << ", " << centres.size();
    const double expected = 4.0 * M_PI / (size * size);
    EXPECT_NEAR(double(centres.size()), expected, 0.15 * expected);
    std::printf("sphere: %zu clumps (area / size^2 = %.0f), chi2 %.1f over 63 dof\n",
                centres.size(), expected, chi2);
}

/// The distance from x to the line through c along unit d.
float lineDistance(glm::vec3 x, glm::vec3 c, glm::vec3 d) {
    const glm::vec3 r = x - c;
    return glm::length(r - d * glm::dot(r, d));
}

// fur-clumped on a sphere: every impulse keeps its root (position, anchor), the clumped ones'
// tips lie closer to their clump's axis (the line through the centre along the strand as it
// stood unclumped) than their roots do, and the same preset with no strength generates
// bit for bit what fur.json does.
TEST(Clumps, TipsGatherTowardsTheClumpAxisRootsStay) {
    const noise::Mesh sphere = noise::makeSphere(1.0f, 48, 96);
    noise::GeneratorOptions options;
    options.seed = 4;
    const noise::PresetDesc clumpedPreset = shippedPreset("fur-clumped");
    noise::PresetDesc unclumpedPreset = clumpedPreset;
    unclumpedPreset.clump = test::constantField(glm::vec3(0.0f), 1);
    const noise::ImpulseGenerator clumpedGen(sphere, clumpedPreset, options);
    const noise::ImpulseGenerator unclumpedGen(sphere, unclumpedPreset, options);
    const std::vector<noise::Impulse> clumped = clumpedGen.generate();
    const std::vector<noise::Impulse> unclumped = unclumpedGen.generate();
    const std::vector<noise::Impulse> fur =
        noise::ImpulseGenerator(sphere, shippedPreset("fur"), options).generate();
    ASSERT_EQ(clumped.size(), unclumped.size());
    ASSERT_EQ(fur.size(), unclumped.size());
    ASSERT_GT(clumped.size(), 50000u);
    const std::vector<gpu::SpotImpulse> a = gpu::toGpu(fur), b = gpu::toGpu(unclumped);
    EXPECT_EQ(std::memcmp(a.data(), b.data(), a.size() * sizeof(gpu::SpotImpulse)), 0)
        << "clumps without strength change the impulses";

    const gpu::SpotGenParams& params = clumpedGen.sharedParams();
    const float tip = params.clump.w;
    EXPECT_FLOAT_EQ(tip, 1.85f); // fur's top lobe: 1.5 + 0.35
    Generator g = clumpFunctions();
    double rootSum = 0.0, tipSum = 0.0, unclumpedTipSum = 0.0;
    std::size_t closer = 0, counted = 0, strengthened = 0;
    for (std::size_t i = 0; i < clumped.size(); ++i) {
        const noise::Impulse& c = clumped[i];
        const noise::Impulse& u = unclumped[i];
        ASSERT_EQ(c.position, u.position) << i;
        ASSERT_EQ(c.triangle, u.triangle) << i;
        ASSERT_EQ(c.barycentric, u.barycentric) << i;
        EXPECT_EQ(u.clumpStrength, 0.0f);
        EXPECT_EQ(u.clumpDistance, 0.0f);
        EXPECT_GE(c.clumpStrength, 0.0f);
        EXPECT_LE(c.clumpStrength, 1.0f);
        if (!(c.clumpStrength > 0.0f))
            continue;
        ++strengthened;
        const glm::vec3 anchor = c.position - c.height * c.normal;
        const auto clump = g.spotNearestClump(anchor, c.normal, params.clump.x, 1.0f,
                                              params.clump.y, params.clumpFlags.x);
        ASSERT_TRUE(clump.found);
        EXPECT_NEAR(c.clumpDistance, clump.distance, 1e-6f) << i;
        glm::mat3 rot;
        const glm::vec3 bentTip = shared::f32::spotBendLobe(glm::vec3(0.0f, 0.0f, tip), c.bend, rot);
        const glm::vec3 unbentTip = shared::f32::spotBendLobe(glm::vec3(0.0f, 0.0f, tip), u.bend, rot);
        const glm::vec3 tipNow = c.position + c.frame * (c.scale * bentTip);
        const glm::vec3 tipBefore = u.position + u.frame * (u.scale * unbentTip);
        const glm::vec3 axis = glm::normalize(tipBefore - u.position);
        const float root = lineDistance(c.position, clump.centre, axis);
        if (root < 0.1f * params.clump.x)
            continue; // at the centre: nothing to gather
        ++counted;
        const float now = lineDistance(tipNow, clump.centre, axis);
        rootSum += root;
        tipSum += now;
        unclumpedTipSum += lineDistance(tipBefore, clump.centre, axis);
        closer += now < root;
        // The kernel is turned and bent, not stretched: the lean keeps the root-to-tip
        // distance, the bend (at most a radian more over the length, on fur's own bend of at
        // most 0.23 radian) shortens the chord by at most 1 - 2 sin(0.62) / 1.23 = 6.2%.
        EXPECT_NEAR(glm::length(tipNow - c.position), glm::length(tipBefore - u.position),
                    0.065f * glm::length(tipBefore - u.position))
            << i;
    }
    ASSERT_GT(counted, clumped.size() / 2);
    EXPECT_EQ(strengthened, clumped.size()); // strength 0.85 +- 15%: never 0
    const double rootMean = rootSum / double(counted), tipMean = tipSum / double(counted);
    std::printf("%zu clumped impulses: mean distance to the clump's axis, roots %.4f, tips %.4f "
                "(unclumped tips %.4f), tips closer than roots for %.2f%%\n",
                counted, rootMean, tipMean, unclumpedTipSum / double(counted),
                100.0 * double(closer) / double(counted));
    EXPECT_LT(tipMean, 0.4 * rootMean);
    EXPECT_NEAR(unclumpedTipSum / double(counted), rootMean, 0.02 * rootMean);
    EXPECT_GT(double(closer), 0.97 * double(counted));
}

// The clump_size field thins or adds centres where it is read: twice the size, a quarter of the
// clumps, around the same surface.
TEST(Clumps, RelativeSizeScalesTheClumps) {
    Generator g = clumpFunctions();
    const glm::vec3 n(0.0f, 0.0f, 1.0f);
    for (const float m : {0.5f, 1.0f, 2.0f}) {
        std::set<std::uint32_t> ids;
        for (int y = 0; y < 200; ++y)
            for (int x = 0; x < 200; ++x)
                ids.insert(g.spotNearestClump(glm::vec3(0.005f * float(x), 0.005f * float(y), 0.3f),
                                              n, 0.05f, m, 0.0f, 3)
                               .id);
        const double expected = 1.0 / double(0.05f * m * 0.05f * m);
        std::printf("relative size %.1f: %zu clumps over a unit square (%.0f expected)\n", m,
                    ids.size(), expected);
        EXPECT_NEAR(double(ids.size()), expected, 0.2 * expected + 8.0);
    }
}

} // namespace
