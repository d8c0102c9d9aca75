// The bake (noise/bake.h, docs/design.md section 5): level 0 against the analytic lobes, the
// coarse levels' optical depth and colour weighting, the distance grid, the file as OpenVDB
// itself (and vdb_print) reads it, bad files, the memory check, determinism across thread counts,
// and `spotshell bake` / `spotshell info --bake`.
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <optional>
#include <sstream>
#include <string>
#include <sys/resource.h>
#include <sys/wait.h>
#include <tuple>
#include <unistd.h>
#include <vector>

#include <glm/gtc/matrix_transform.hpp>
#include <gtest/gtest.h>
#include <openvdb/io/File.h>
#include <openvdb/openvdb.h>
#include <tbb/global_control.h>

#include "cli_run.h"
#include "noise/bake.h"
#include "noise/error.h"
#include "noise/impulses.h"
#include "noise/kernel.h"
#include "noise/mesh.h"
#include "noise/painted.h"
#include "shaders/spot_shared.hpp"
#include "test_support.h"

namespace fs = std::filesystem;
using namespace spot;
using namespace spot::noise;

namespace {

fs::path tmpDir() {
    const fs::path dir = fs::path(SPOT_TEST_TMP_DIR) / ("bake-" + std::to_string(::getpid()));
    fs::create_directories(dir);
    return dir;
}

/// A flat square of side `size` in the xz plane at height y = 0.0137 (off every cell boundary),
/// normal +y, two triangles.
Mesh square(float size) {
    Mesh m;
    m.name = "square";
    const float y = 0.0137f;
    m.positions = {{0.0f, y, 0.0f}, {size, y, 0.0f}, {0.0f, y, size}, {size, y, size}};
    m.triangles = {{0, 2, 1}, {1, 2, 3}};
    finalizeMesh(m);
    return m;
}

/// Every level's non-empty voxels as (ijk, density, colour), in tree order.
using VoxelList = std::vector<std::tuple<int, int, int, float, float, float, float>>;
VoxelList voxels(const BakedVolume& v, int level) {
    VoxelList out;
    v.forEachActive(level, [&](glm::ivec3 ijk, float d, glm::vec3 c) {
        out.emplace_back(ijk.x, ijk.y, ijk.z, d, c.x, c.y, c.z);
    });
    return out;
}

void expectSameGrids(const BakedVolume& a, const BakedVolume& b) {
    ASSERT_EQ(a.levels(), b.levels());
    for (int l = 0; l < a.levels(); ++l) {
        EXPECT_EQ(a.voxelSize(l), b.voxelSize(l));
        const VoxelList va = voxels(a, l), vb = voxels(b, l);
        ASSERT_EQ(va.size(), vb.size()) << "level " << l;
        EXPECT_TRUE(va == vb) << "level " << l << " differs";
    }
    EXPECT_EQ(a.hasShading(), b.hasShading());
    for (int l = 0; l < a.levels(); ++l) {
        std::size_t differ = 0;
        a.forEachActive(l, [&](glm::ivec3 ijk, float, glm::vec3) {
            differ +=
                a.tangent(l, ijk) != b.tangent(l, ijk) || a.normal(l, ijk) != b.normal(l, ijk);
        });
        EXPECT_EQ(differ, 0u) << "level " << l << "'s shading grids differ";
    }
    EXPECT_EQ(a.distanceCount(), b.distanceCount());
    std::size_t checked = 0, differ = 0;
    a.forEachActive(0, [&](glm::ivec3 ijk, float, glm::vec3) {
        for (int d = -3; d <= 3; ++d) {
            const glm::ivec3 q = ijk + glm::ivec3(d, 2 * d, -d);
            differ += a.distance(q) != b.distance(q);
            ++checked;
        }
    });
    EXPECT_EQ(differ, 0u) << "of " << checked << " distances";
    EXPECT_EQ(a.presetHash(), b.presetHash());
}

/// A generator of `preset` on a 0.2 x 0.2 square, and one of its surface cells near the middle.
struct OneCell {
    Mesh mesh = square(0.2f);
    PresetDesc preset;
    std::unique_ptr<ImpulseGenerator> generator;
    const SurfaceCell* cell = nullptr;
    explicit OneCell(PresetDesc p) : preset(std::move(p)) {
        generator = std::make_unique<ImpulseGenerator>(mesh, preset, GeneratorOptions{});
        const auto& cells = generator->cells().cells;
        cell = &*std::min_element(cells.begin(), cells.end(), [](const auto& a, const auto& b) {
            return glm::length(a.closestPoint - glm::vec3(0.1f, 0.0f, 0.1f)) <
                   glm::length(b.closestPoint - glm::vec3(0.1f, 0.0f, 0.1f));
        });
    }
    /// One impulse at the cell's surface point with a rotated frame and an anisotropic scale
    /// (each at most the preset's, so the kernel stays in the 3x3x3 cells).
    Impulse impulse() const {
        Impulse imp;
        imp.position = cell->closestPoint;
        imp.cell = cell->ijk;
        imp.frame = test::rotation(0.7f, glm::vec3(1.0f, 2.0f, 3.0f));
        imp.scale = glm::vec3(0.010f, 0.009f, 0.008f);
        imp.weight = 0.7f;
        imp.color = glm::vec3(0.2f, 0.5f, 0.9f);
        return imp;
    }
};

/// Extinction of lobe `lobe` (no rotation, no offset) of the impulse at `x`, written out from the
/// model (docs/design.md section 1) rather than through placeLobe: the frame's transpose takes x
/// into kernel axes, the scale and sigmas into lobe units.
double analyticLobe(const LobeDesc& lobe, float support, const Impulse& imp, glm::dvec3 x) {
    const glm::dvec3 d = glm::transpose(glm::dmat3(imp.frame)) * (x - glm::dvec3(imp.position));
    const glm::dvec3 u = d / (glm::dvec3(imp.scale) * glm::dvec3(lobe.sigma));
    const double r2 = glm::dot(u, u);
    if (r2 >= double(support) * double(support))
        return 0.0;
    return double(lobe.extinction) * double(imp.weight) * std::exp(-0.5 * r2);
}

BakeOptions options(float voxel, int levels) {
    BakeOptions o;
    o.voxelSize = voxel;
    o.levels = levels;
    o.presetHash = fnv1a64("{\"test\": true}");
    o.presetName = "test";
    return o;
}

/// One line, naming the file, containing `phrase`.
void expectBadFile(const fs::path& file, const std::string& phrase) {
    try {
        (void)readBakedGrids(file);
        ADD_FAILURE() << file << ": read without an error";
    } catch (const InputError& e) {
        const std::string m = e.what();
        EXPECT_EQ(m.find('\n'), std::string::npos) << m;
        EXPECT_NE(m.find(file.string()), std::string::npos) << m;
        EXPECT_NE(m.find(phrase), std::string::npos) << "expected '" << phrase << "' in: " << m;
    }
}

} // namespace

TEST(Bake, SingleLobeMatchesTheAnalyticDensityAtVoxelCentres) {
    PresetDesc p = test::uniformPreset(1000.0f, 0.01f);
    p.kernel.lobes[0].sigma = glm::vec3(0.5f, 1.0f, 2.0f);
    p.kernel.lobes[0].color = glm::vec3(1.0f);
    OneCell one(p);
    const Impulse imp = one.impulse();
    const float v = 0.004f;
    const BakedVolume bake =
        bakeImpulses(one.generator->cells(), one.generator->kernel(), {imp}, options(v, 1));
    ASSERT_EQ(bake.levels(), 1);

    // Every voxel centre within reach: analytic non-zero exactly where the bake stores a voxel,
    // and the same value to float rounding.
    const LobeDesc& lobe = p.kernel.lobes[0];
    const glm::ivec3 c = glm::ivec3(glm::floor(glm::dvec3(imp.position) / double(v)));
    const int reach = int(std::ceil(3.0 * 2.0 * 0.010 / v)) + 2;
    std::size_t expected = 0, compared = 0;
    double worst = 0.0;
    for (int z = -reach; z <= reach; ++z)
        for (int y = -reach; y <= reach; ++y)
            for (int x = -reach; x <= reach; ++x) {
                const glm::ivec3 ijk = c + glm::ivec3(x, y, z);
                const glm::dvec3 centre = bake.voxelCentre(0, ijk);
                EXPECT_EQ(centre, (glm::dvec3(ijk) + 0.5) * double(v));
                const double want = analyticLobe(lobe, p.kernel.supportSigma, imp, centre);
                const float got = bake.density(0, ijk);
                if (want == 0.0) {
                    // On the support's edge the two roundings may disagree; the value there is
                    // exp(-4.5) of the peak, so allow only that.
                    EXPECT_TRUE(got == 0.0f || got < 0.0112f * lobe.extinction * imp.weight)
                        << "voxel " << ijk.x << "," << ijk.y << "," << ijk.z << ": " << got;
                    continue;
                }
                ++expected;
                ASSERT_GT(got, 0.0f)
                    << "voxel " << ijk.x << "," << ijk.y << "," << ijk.z << " analytic " << want;
                worst = std::max(worst, std::abs(double(got) - want) / want);
                const glm::vec3 colour = bake.color(0, ijk);
                EXPECT_NEAR(colour.x, 0.2f, 1e-6f);
                EXPECT_NEAR(colour.y, 0.5f, 1e-6f);
                EXPECT_NEAR(colour.z, 0.9f, 1e-6f);
                ++compared;
            }
    EXPECT_GT(compared, 1000u);
    EXPECT_LE(worst, 1e-6) << "largest relative error over " << compared << " voxels";
    // Nothing stored beyond the analytic support (the edge's rounding aside).
    EXPECT_LE(bake.activeCount(0), expected + expected / 50 + 8)
        << bake.activeCount(0) << " stored, " << expected << " analytic";
    EXPECT_GE(bake.activeCount(0), expected);
}

TEST(Bake, CoarseLevelsKeepTheOpticalDepthAlongAxes) {
    OneCell one(test::uniformPreset(4000.0f, 0.01f));
    const std::vector<Impulse> impulses = one.generator->generate();
    ASSERT_GT(impulses.size(), 50u);
    const float v = 0.004f;
    BakeStats stats;
    const BakedVolume bake = bakeImpulses(one.generator->cells(), one.generator->kernel(), impulses,
                                          options(v, 4), {}, &stats);
    ASSERT_EQ(bake.levels(), 4);
    // The memory check's counts bound what was stored.
    EXPECT_EQ(stats.estimate.nonEmptyVoxels, bake.activeCount(0));
    EXPECT_GE(stats.estimate.distanceVoxels, bake.distanceCount());
    EXPECT_LE(stats.estimate.bytes, estimateBake(one.generator->cells(), options(v, 4)).bytes);
    ASSERT_EQ(stats.activeVoxels.size(), 4u);
    for (int level = 1; level < 4; ++level) {
        EXPECT_EQ(bake.voxelSize(level), 2.0f * bake.voxelSize(level - 1));
        EXPECT_GT(bake.activeCount(level), 0u);
        EXPECT_LT(bake.activeCount(level), bake.activeCount(level - 1));
        const double fine = double(bake.voxelSize(level - 1)), coarse = 2.0 * fine;
        for (int axis = 0; axis < 3; ++axis) {
            // Optical depth of each coarse column along `axis` (key: the other two coordinates),
            // against the mean of the 2x2 finer columns it covers.
            const int a = (axis + 1) % 3, b = (axis + 2) % 3;
            std::map<std::pair<int, int>, double> tauCoarse, tauFine;
            bake.forEachActive(level, [&](glm::ivec3 ijk, float d, glm::vec3) {
                tauCoarse[{ijk[a], ijk[b]}] += coarse * double(d);
            });
            bake.forEachActive(level - 1, [&](glm::ivec3 ijk, float d, glm::vec3) {
                tauFine[{ijk[a] >> 1, ijk[b] >> 1}] += 0.25 * fine * double(d);
            });
            ASSERT_EQ(tauCoarse.size(), tauFine.size()) << "level " << level << " axis " << axis;
            double worst = 0.0;
            for (const auto& [key, tau] : tauFine) {
                ASSERT_TRUE(tauCoarse.count(key));
                worst = std::max(worst, std::abs(tauCoarse[key] - tau) / tau);
            }
            EXPECT_LE(worst, 2e-6)
                << "level " << level << " axis " << axis << ", " << tauFine.size() << " columns";
        }
    }
}

TEST(Bake, ColourIsWeightedByExtinction) {
    // Two lobes about the same centre, red and thin, blue and wide: the colour at a point is
    // (sigma_r red + sigma_b blue) / (sigma_r + sigma_b), changing from red-ish in the middle to
    // blue at the rim.
    PresetDesc p = test::uniformPreset(1000.0f, 0.01f);
    LobeDesc red = p.kernel.lobes[0], blue = red;
    red.sigma = glm::vec3(0.6f);
    red.extinction = 300.0f;
    red.color = glm::vec3(1.0f, 0.0f, 0.0f);
    blue.sigma = glm::vec3(1.5f);
    blue.extinction = 100.0f;
    blue.color = glm::vec3(0.0f, 0.0f, 1.0f);
    p.kernel.lobes = {red, blue};
    OneCell one(p);
    Impulse imp = one.impulse();
    imp.color = glm::vec3(1.0f);
    const float v = 0.003f;
    const BakedVolume bake =
        bakeImpulses(one.generator->cells(), one.generator->kernel(), {imp}, options(v, 3));
    std::size_t compared = 0;
    float lowestRed = 1.0f, highestRed = 0.0f;
    bake.forEachActive(0, [&](glm::ivec3 ijk, float d, glm::vec3 colour) {
        const glm::dvec3 x = bake.voxelCentre(0, ijk);
        const double sr = analyticLobe(red, 3.0f, imp, x), sb = analyticLobe(blue, 3.0f, imp, x);
        if (sr + sb <= 0.0)
            return;
        EXPECT_NEAR(d, sr + sb, 1e-5 * (sr + sb));
        EXPECT_NEAR(colour.x, sr / (sr + sb), 1e-5);
        EXPECT_NEAR(colour.y, 0.0, 1e-7);
        EXPECT_NEAR(colour.z, sb / (sr + sb), 1e-5);
        lowestRed = std::min(lowestRed, colour.x);
        highestRed = std::max(highestRed, colour.x);
        ++compared;
    });
    EXPECT_GT(compared, 1000u);
    EXPECT_GT(highestRed, 0.6f);
    EXPECT_LT(lowestRed, 0.01f);
    // Coarse levels: the children's extinction-weighted mean colour, and the mean extinction
    // (alpha is never averaged).
    for (int level = 1; level < 3; ++level) {
        std::size_t checked = 0;
        bake.forEachActive(level, [&](glm::ivec3 ijk, float d, glm::vec3 colour) {
            double sum = 0.0;
            glm::dvec3 weighted(0.0);
            for (int k = 0; k < 8; ++k) {
                const glm::ivec3 child = 2 * ijk + glm::ivec3(k & 1, (k >> 1) & 1, k >> 2);
                const double s = bake.density(level - 1, child);
                sum += s;
                weighted += s * glm::dvec3(bake.color(level - 1, child));
            }
            EXPECT_NEAR(d, sum / 8.0, 1e-6 * sum);
            const glm::dvec3 want = weighted / sum;
            EXPECT_NEAR(colour.x, want.x, 1e-6);
            EXPECT_NEAR(colour.z, want.z, 1e-6);
            ++checked;
        });
        EXPECT_GT(checked, 10u) << "level " << level;
    }
}

TEST(Bake, DistanceIsTheCappedChebyshevDistanceToTheNearestNonEmptyVoxel) {
    PresetDesc p = test::uniformPreset(1000.0f, 0.01f);
    p.kernel.lobes[0].sigma = glm::vec3(0.5f, 1.0f, 2.0f);
    OneCell one(p);
    const BakedVolume bake = bakeImpulses(one.generator->cells(), one.generator->kernel(),
                                          {one.impulse()}, options(0.004f, 1));
    glm::ivec3 lo, hi;
    bake.activeBounds(0, lo, hi);
    ASSERT_LE(lo.x, hi.x);
    // An independent distance: repeated 26-neighbour dilation of a dense copy around the lobe.
    const int margin = int(kBakeDistanceCap) + 3;
    lo -= margin;
    hi += margin;
    const glm::ivec3 n = hi - lo + 1;
    const auto at = [&](glm::ivec3 q) { return (std::size_t(q.z) * n.y + q.y) * n.x + q.x; };
    std::vector<float> dist(std::size_t(n.x) * n.y * n.z, kBakeDistanceCap);
    bake.forEachActive(0, [&](glm::ivec3 ijk, float, glm::vec3) { dist[at(ijk - lo)] = 0.0f; });
    for (int k = 1; k < int(kBakeDistanceCap); ++k) {
        std::vector<float> next = dist;
        for (int z = 1; z < n.z - 1; ++z)
            for (int y = 1; y < n.y - 1; ++y)
                for (int x = 1; x < n.x - 1; ++x) {
                    if (dist[at({x, y, z})] < kBakeDistanceCap)
                        continue;
                    bool near = false;
                    for (int d = 0; d < 27 && !near; ++d)
                        near = dist[at({x + d % 3 - 1, y + (d / 3) % 3 - 1, z + d / 9 - 1})] ==
                               float(k - 1);
                    if (near)
                        next[at({x, y, z})] = float(k);
                }
        dist = std::move(next);
    }
    std::size_t differ = 0, zero = 0, capped = 0;
    for (int z = 0; z < n.z; ++z)
        for (int y = 0; y < n.y; ++y)
            for (int x = 0; x < n.x; ++x) {
                const float want = dist[at({x, y, z})],
                            got = bake.distance(lo + glm::ivec3(x, y, z));
                differ += want != got;
                zero += got == 0.0f;
                capped += got == kBakeDistanceCap;
            }
    EXPECT_EQ(differ, 0u);
    EXPECT_EQ(zero, bake.activeCount(0));
    EXPECT_GT(capped, 0u);
    // Stored: the voxels nearer than the cap; the background (the cap) everywhere else.
    EXPECT_EQ(bake.distanceCount(), std::size_t(n.x) * n.y * n.z - capped);
}

TEST(Bake, IdenticalOnOneAndTwoThreads) {
    OneCell one(test::uniformPreset(4000.0f, 0.01f));
    const std::vector<Impulse> impulses = one.generator->generate();
    const auto bakeOn = [&](int threads) {
        tbb::global_control limit(tbb::global_control::max_allowed_parallelism,
                                  std::size_t(threads));
        return bakeImpulses(one.generator->cells(), one.generator->kernel(), impulses,
                            options(0.003f, 3));
    };
    const BakedVolume a = bakeOn(1), b = bakeOn(2);
    expectSameGrids(a, b);
}

TEST(Bake, FileHasTheGridsClassesAndMetadataOpenVdbReads) {
    OneCell one(test::uniformPreset(4000.0f, 0.01f));
    const std::vector<Impulse> impulses = one.generator->generate();
    const float v = 0.004f;
    const BakedVolume bake =
        bakeImpulses(one.generator->cells(), one.generator->kernel(), impulses, options(v, 3));
    const fs::path file = tmpDir() / "three-levels.vdb";
    writeBakedGrids(file, bake);
    // No temporary file left beside it.
    for (const auto& entry : fs::directory_iterator(file.parent_path()))
        EXPECT_EQ(entry.path().filename().string().find(".tmp-"), std::string::npos)
            << entry.path();

    // OpenVDB itself, not the bake's reader.
    openvdb::initialize();
    openvdb::io::File in(file.string());
    in.open();
    std::vector<std::string> names;
    for (auto it = in.beginName(); it != in.endName(); ++it)
        names.push_back(*it);
    const std::vector<std::string> want = {
        "density",      "color",        "tangent",     "normal",       "density_lod1",
        "color_lod1",   "tangent_lod1", "normal_lod1", "density_lod2", "color_lod2",
        "tangent_lod2", "normal_lod2",  "distance"};
    std::vector<std::string> sortedNames = names, sortedWant = want;
    std::sort(sortedNames.begin(), sortedNames.end());
    std::sort(sortedWant.begin(), sortedWant.end());
    EXPECT_EQ(sortedNames, sortedWant);
    const openvdb::MetaMap::Ptr fileMeta = in.getMetadata();
    EXPECT_EQ(fileMeta->metaValue<openvdb::Int32>("spotshell_levels"), 3);
    EXPECT_EQ(fileMeta->metaValue<double>("spotshell_voxel_size"), double(v));
    EXPECT_EQ(fileMeta->metaValue<std::string>("spotshell_version"), SPOT_VERSION);
    char hash[17];
    std::snprintf(hash, sizeof hash, "%016llx",
                  static_cast<unsigned long long>(fnv1a64("{\"test\": true}")));
    EXPECT_EQ(fileMeta->metaValue<std::string>("spotshell_preset_hash"), hash);
    for (const std::string& name : names) {
        const openvdb::GridBase::Ptr grid = in.readGrid(name);
        const bool isColor = name.rfind("color", 0) == 0 || name.rfind("tangent", 0) == 0 ||
                             name.rfind("normal", 0) == 0; // the Vec3 grids
        const int level = name == "distance"                       ? 0
                          : name.find("_lod") != std::string::npos ? name.back() - '0'
                                                                   : 0;
        SCOPED_TRACE(name);
        EXPECT_EQ(grid->type(),
                  isColor ? openvdb::Vec3SGrid::gridType() : openvdb::FloatGrid::gridType());
        EXPECT_EQ(grid->getGridClass(),
                  name.rfind("density", 0) == 0 ? openvdb::GRID_FOG_VOLUME : openvdb::GRID_UNKNOWN);
        const double vl = double(v) * double(1 << level);
        EXPECT_NEAR(grid->voxelSize()[0], vl, 1e-12);
        EXPECT_NEAR(grid->voxelSize()[2], vl, 1e-12);
        // Voxel ijk's centre at (ijk + 1/2) x voxel: 2x2x2 voxels make the next level's one.
        const openvdb::Vec3d origin = grid->indexToWorld(openvdb::Vec3d(0.0));
        EXPECT_NEAR(origin.x(), 0.5 * vl, 1e-12);
        EXPECT_EQ(grid->metaValue<openvdb::Int32>("spotshell_level"), level);
        EXPECT_EQ(grid->metaValue<openvdb::Int32>("spotshell_levels"), 3);
        EXPECT_NEAR(grid->metaValue<double>("spotshell_voxel_size"), vl, 1e-12);
        EXPECT_EQ(grid->metaValue<std::string>("spotshell_preset_hash"), hash);
        EXPECT_EQ(grid->metaValue<std::string>("spotshell_version"), SPOT_VERSION);
        EXPECT_EQ(grid->metaValue<std::string>("spotshell_preset"), "test");
        if (!isColor && name != "distance")
            EXPECT_EQ(std::uint64_t(grid->activeVoxelCount()), bake.activeCount(level));
        if (name.rfind("tangent", 0) == 0 || name.rfind("normal", 0) == 0)
            EXPECT_FALSE(grid->metaValue<std::string>("spotshell_meaning").empty());
    }
    in.close();

    // The bake's reader gives back the same grids.
    const BakedVolume back = readBakedGrids(file);
    expectSameGrids(bake, back);
    EXPECT_EQ(back.presetName(), "test");
    EXPECT_EQ(back.version(), SPOT_VERSION);

    // vdb_print (libopenvdb-tools, which scripts/install-deps.sh installs) reads it too.
    const std::string out = (tmpDir() / "vdb_print.txt").string();
    const int rc = std::system(("vdb_print -l '" + file.string() + "' > '" + out + "' 2>&1").c_str());
    std::ifstream text(out);
    const std::string printed((std::istreambuf_iterator<char>(text)), {});
    ASSERT_EQ(rc, 0) << "vdb_print (libopenvdb-tools) failed or is not installed:\n" << printed;
    for (const std::string& name : want)
        EXPECT_NE(printed.find(name), std::string::npos) << name << " in:\n" << printed;
    EXPECT_NE(printed.find("class: fog volume"), std::string::npos) << printed;
}

// The shading grids (noise/bake.h): one strand lobe's voxels hold its tangent as placed
// (placedShadingAxis: unit, root to tip), one flake lobe's its normal turned to the surface's
// side, on every level (the extinction-weighted mean of one direction is that direction), and
// the other grid stays empty; a lambert lobe has neither. Two strand lobes crossing at a right
// angle hold their extinction-weighted sum. Read back from the file unchanged.
TEST(Bake, ShadingGridsHoldTheLobesAxesWeightedByExtinction) {
    const auto bakeOne = [](LobeShading::Model model, const Impulse* extra, OneCell& one,
                            std::vector<Impulse>& impulses) {
        impulses = {one.impulse()};
        if (extra)
            impulses.push_back(*extra);
        return bakeImpulses(one.generator->cells(), one.generator->kernel(), impulses,
                            options(0.002f, 3));
    };
    for (const auto model :
         {LobeShading::Model::Strand, LobeShading::Model::Flake, LobeShading::Model::Lambert}) {
        PresetDesc p = test::uniformPreset(1000.0f, 0.01f);
        p.kernel.lobes[0].sigma = glm::vec3(0.5f, 1.0f, 2.0f);
        p.kernel.lobes[0].shading.model = model;
        OneCell one(p);
        std::vector<Impulse> impulses;
        const BakedVolume bake = bakeOne(model, nullptr, one, impulses);
        ASSERT_TRUE(bake.hasShading());
        const WorldLobe placed = placeLobe(one.generator->kernel(), 0, impulses[0]);
        const glm::vec3 axis(placedShadingAxis(one.generator->kernel(), 0, impulses[0], placed));
        if (model == LobeShading::Model::Lambert)
            EXPECT_EQ(axis, glm::vec3(0.0f));
        else
            EXPECT_NEAR(glm::length(axis), 1.0f, 1e-6f);
        if (model == LobeShading::Model::Flake)
            EXPECT_GE(glm::dot(axis, impulses[0].normal), 0.0f) << "turned to the surface's side";
        const glm::vec3 wantTangent = model == LobeShading::Model::Strand ? axis : glm::vec3(0.0f);
        const glm::vec3 wantNormal = model == LobeShading::Model::Flake ? axis : glm::vec3(0.0f);
        for (int l = 0; l < bake.levels(); ++l) {
            float worst = 0.0f;
            std::size_t count = 0;
            bake.forEachActive(l, [&](glm::ivec3 ijk, float, glm::vec3) {
                worst = std::max({worst, glm::length(bake.tangent(l, ijk) - wantTangent),
                                  glm::length(bake.normal(l, ijk) - wantNormal)});
                ++count;
            });
            EXPECT_GT(count, 0u);
            EXPECT_LT(worst, 2e-6f) << "model " << int(model) << ", level " << l;
        }
        const fs::path file = tmpDir() / ("shading-" + std::to_string(int(model)) + ".vdb");
        writeBakedGrids(file, bake);
        expectSameGrids(bake, readBakedGrids(file));
    }

    // Two strands at a right angle through one point: sum_i sigma_i t_i / sum_i sigma_i.
    PresetDesc p = test::uniformPreset(1000.0f, 0.01f);
    p.kernel.lobes[0].sigma = glm::vec3(0.5f, 0.5f, 2.0f);
    p.kernel.lobes[0].shading.model = LobeShading::Model::Strand;
    OneCell one(p);
    Impulse crossing = one.impulse();
    crossing.frame = crossing.frame * glm::mat3(glm::rotate(glm::mat4(1.0f), 1.5707964f,
                                                            glm::vec3(1.0f, 0.0f, 0.0f)));
    crossing.weight = 0.3f;
    std::vector<Impulse> impulses;
    const BakedVolume bake = bakeOne(LobeShading::Model::Strand, &crossing, one, impulses);
    const Kernel& kernel = one.generator->kernel();
    const WorldLobe a = placeLobe(kernel, 0, impulses[0]), b = placeLobe(kernel, 0, impulses[1]);
    const glm::dvec3 ta = placedShadingAxis(kernel, 0, impulses[0], a);
    const glm::dvec3 tb = placedShadingAxis(kernel, 0, impulses[1], b);
    EXPECT_NEAR(glm::dot(ta, tb), 0.0, 1e-6);
    const float support = kernel.supportSigma;
    double worst = 0.0;
    std::size_t both = 0;
    bake.forEachActive(0, [&](glm::ivec3 ijk, float, glm::vec3) {
        const glm::dvec3 x = bake.voxelCentre(0, ijk);
        const auto sigma = [&](const WorldLobe& w) {
            return w.extinction *
                   shared::f64::spotLobeDensity(w.toLobe * (x - w.centre), double(support));
        };
        const double sa = sigma(a), sb = sigma(b);
        both += sa > 0.0 && sb > 0.0;
        const glm::dvec3 want = (sa * ta + sb * tb) / (sa + sb);
        worst = std::max(worst, glm::length(glm::dvec3(bake.tangent(0, ijk)) - want));
    });
    EXPECT_GT(both, 0u) << "voxels where the strands cross";
    EXPECT_LT(worst, 1e-5);
}

// A bake written before the shading grids (none of them) reads without them: hasShading() false,
// zero vectors, the other grids as they were. One with the tangent grids but a missing normal
// grid is refused with one line naming the grid.
TEST(Bake, OlderFilesWithoutShadingGridsReadWithoutThem) {
    PresetDesc p = test::uniformPreset(4000.0f, 0.01f);
    p.kernel.lobes[0].shading.model = LobeShading::Model::Strand;
    OneCell one(p);
    const BakedVolume bake = bakeImpulses(one.generator->cells(), one.generator->kernel(),
                                          one.generator->generate(), options(0.004f, 2));
    const fs::path dir = tmpDir();
    const fs::path good = dir / "with-shading.vdb";
    writeBakedGrids(good, bake);
    openvdb::initialize();
    const auto rewrite = [&](const fs::path& out,
                             const std::function<bool(const std::string&)>& drop) {
        openvdb::io::File f(good.string());
        f.open();
        const openvdb::GridPtrVecPtr all = f.getGrids();
        openvdb::GridPtrVec grids;
        for (const openvdb::GridBase::Ptr& g : *all)
            if (!drop(g->getName()))
                grids.push_back(g);
        const openvdb::MetaMap::Ptr meta = f.getMetadata();
        f.close();
        openvdb::io::File(out.string()).write(grids, *meta);
    };
    const fs::path older = dir / "older.vdb";
    rewrite(older, [](const std::string& name) {
        return name.rfind("tangent", 0) == 0 || name.rfind("normal", 0) == 0;
    });
    const BakedVolume back = readBakedGrids(older);
    EXPECT_TRUE(bake.hasShading());
    EXPECT_FALSE(back.hasShading());
    for (int l = 0; l < back.levels(); ++l) {
        EXPECT_TRUE(voxels(bake, l) == voxels(back, l)) << "level " << l;
        back.forEachActiveShaded(l, [&](glm::ivec3, float, glm::vec3, glm::vec3 t, glm::vec3 n) {
            EXPECT_EQ(t, glm::vec3(0.0f));
            EXPECT_EQ(n, glm::vec3(0.0f));
        });
    }
    const fs::path partial = dir / "partial.vdb";
    rewrite(partial, [](const std::string& name) { return name == "normal_lod1"; });
    expectBadFile(partial, "no grid \"normal_lod1\"");
}

TEST(Bake, BadFilesGiveOneClearError) {
    OneCell one(test::uniformPreset(4000.0f, 0.01f));
    const BakedVolume bake = bakeImpulses(one.generator->cells(), one.generator->kernel(),
                                          one.generator->generate(), options(0.004f, 2));
    const fs::path dir = tmpDir();
    const fs::path good = dir / "good.vdb";
    writeBakedGrids(good, bake);
    std::ifstream in(good, std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(in)), {});

    expectBadFile(dir / "missing.vdb", "no such bake file");
    const fs::path garbage = dir / "garbage.vdb";
    std::ofstream(garbage, std::ios::binary) << "this is not an OpenVDB file\n";
    expectBadFile(garbage, "cannot read");
    for (const double fraction : {0.5, 0.9, 0.99}) {
        const fs::path truncated =
            dir / ("truncated-" + std::to_string(int(fraction * 100)) + ".vdb");
        std::ofstream(truncated, std::ios::binary)
            .write(bytes.data(), std::streamsize(double(bytes.size()) * fraction));
        expectBadFile(truncated, "cannot read");
    }

    // Grids renamed or of the wrong type, with the bake's metadata otherwise intact.
    openvdb::initialize();
    const auto rewrite = [&](const fs::path& out,
                             const std::function<void(openvdb::GridPtrVec&)>& edit) {
        openvdb::io::File f(good.string());
        f.open();
        openvdb::GridPtrVec grids = *f.getGrids();
        const openvdb::MetaMap::Ptr meta = f.getMetadata();
        f.close();
        edit(grids);
        openvdb::io::File(out.string()).write(grids, *meta);
    };
    const fs::path renamed = dir / "renamed.vdb";
    rewrite(renamed, [](openvdb::GridPtrVec& grids) {
        for (auto& g : grids)
            if (g->getName() == "color_lod1")
                g->setName("colour_lod1");
    });
    expectBadFile(renamed, "no grid \"color_lod1\"");
    const fs::path wrongType = dir / "wrong-type.vdb";
    rewrite(wrongType, [](openvdb::GridPtrVec& grids) {
        for (auto& g : grids)
            if (g->getName() == "density") {
                openvdb::Vec3SGrid::Ptr v = openvdb::Vec3SGrid::create();
                v->setName("density");
                v->setTransform(g->transform().copy());
                g = v;
            }
    });
    expectBadFile(wrongType, "a bake needs a Tree_float_5_4_3");
    const fs::path moved = dir / "moved.vdb";
    rewrite(moved, [](openvdb::GridPtrVec& grids) {
        for (auto& g : grids)
            if (g->getName() == "distance")
                g->setTransform(openvdb::math::Transform::createLinearTransform(0.004));
    });
    expectBadFile(moved, "the transform is not the bake's");
    const fs::path painted = dir / "painted.vdb";
    PaintedGrid grid("density", 1, 0.01f, glm::vec3(0.0f));
    grid.set({1, 2, 3}, glm::vec3(0.5f));
    writePaintedGrids(painted, {&grid});
    expectBadFile(painted, "not a spotshell bake (no spotshell_levels metadata)");
}

// A bake records the shell it was baked on (noise::shellHash of the rest mesh and the cell
// size) and reads it back; a file written without one (older bakes) reads without one. The hash
// changes with any vertex, any triangle and the cell size.
TEST(Bake, RecordsTheMeshHashAndReadsOlderFilesWithoutOne) {
    OneCell one(test::uniformPreset(4000.0f, 0.01f));
    const std::uint64_t shell = shellHash(meshHash(one.mesh), one.generator->cellSize());
    BakeOptions with = options(0.004f, 2);
    with.meshHash = shell;
    const fs::path dir = tmpDir();
    writeBakedGrids(dir / "with-hash.vdb",
                    bakeImpulses(one.generator->cells(), one.generator->kernel(),
                                 one.generator->generate(), with));
    EXPECT_EQ(readBakedGrids(dir / "with-hash.vdb").meshHash(), std::optional(shell));
    writeBakedGrids(dir / "without-hash.vdb",
                    bakeImpulses(one.generator->cells(), one.generator->kernel(),
                                 one.generator->generate(), options(0.004f, 2)));
    EXPECT_FALSE(readBakedGrids(dir / "without-hash.vdb").meshHash().has_value());

    Mesh moved = one.mesh;
    moved.positions[1].x += 1e-6f;
    Mesh turned = one.mesh;
    std::swap(turned.triangles[0].y, turned.triangles[0].z);
    EXPECT_EQ(meshHash(one.mesh), meshHash(Mesh(one.mesh)));
    EXPECT_NE(meshHash(moved), meshHash(one.mesh));
    EXPECT_NE(meshHash(turned), meshHash(one.mesh));
    EXPECT_NE(shellHash(meshHash(one.mesh), 0.02f), shellHash(meshHash(one.mesh), 0.0200001f));
    // FNV-1a continued is FNV-1a of the concatenation.
    EXPECT_EQ(fnv1a64("def", fnv1a64("abc")), fnv1a64("abcdef"));
}

// A .vdb cut anywhere is refused with one line naming the file before OpenVDB reads a grid: each
// grid's byte range (its descriptor's offsets) is checked against the file's size, so no size is
// read from past the end (under AddressSanitizer OpenVDB asked for about 94 TB). Checked in a
// child whose address space is capped at 1 GiB above what it holds: a read that allocated a
// size from past the end would fail there with bad_alloc, not with the range check's line.
TEST(Bake, TruncatedFilesAreRefusedByTheirGridRanges) {
    OneCell one(test::uniformPreset(4000.0f, 0.01f));
    const fs::path dir = tmpDir();
    const fs::path good = dir / "cut-good.vdb";
    writeBakedGrids(good, bakeImpulses(one.generator->cells(), one.generator->kernel(),
                                       one.generator->generate(), options(0.004f, 3)));
    std::ifstream in(good, std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(in)), {});
    ASSERT_GT(bytes.size(), 1000u);
    std::vector<std::size_t> cuts = {bytes.size() - 1, bytes.size() - 100};
    for (int i = 1; i < 40; ++i)
        cuts.push_back(bytes.size() * std::size_t(i) / 40);
    std::vector<fs::path> files;
    for (const std::size_t cut : cuts) {
        files.push_back(dir / ("cut-" + std::to_string(cut) + ".vdb"));
        std::ofstream(files.back(), std::ios::binary).write(bytes.data(), std::streamsize(cut));
    }
    // Every cut after the header and the file's metadata falls in a grid's range or its
    // descriptor: the range check refuses it (a cut in the header is OpenVDB's "not a VDB file").
    int rangeChecked = 0;
    for (const fs::path& f : files) {
        try {
            (void)readBakedGrids(f);
            ADD_FAILURE() << f << ": read without an error";
        } catch (const InputError& e) {
            const std::string m = e.what();
            EXPECT_EQ(m.find('\n'), std::string::npos) << m;
            EXPECT_NE(m.find(f.string()), std::string::npos) << m;
            EXPECT_NE(m.find("cannot read"), std::string::npos) << m;
            EXPECT_EQ(m.find("bad_alloc"), std::string::npos) << m;
            rangeChecked += m.find("truncated or corrupt:") != std::string::npos;
        }
    }
    EXPECT_GE(rangeChecked, int(files.size()) - 4);

    const pid_t child = fork();
    ASSERT_GE(child, 0);
    if (child == 0) {
        std::ifstream status("/proc/self/status");
        std::string line;
        rlim_t held = 0;
        while (std::getline(status, line))
            if (line.rfind("VmSize:", 0) == 0)
                held = rlim_t(std::stoull(line.substr(7))) * 1024;
        const rlimit cap{held + (rlim_t(1) << 30), held + (rlim_t(1) << 30)};
        if (held == 0 || setrlimit(RLIMIT_AS, &cap) != 0)
            _exit(3);
        for (const fs::path& f : files) {
            try {
                (void)readBakedGrids(f);
                _exit(4);
            } catch (const InputError& e) {
                if (std::string(e.what()).find("bad_alloc") != std::string::npos)
                    _exit(5);
            } catch (...) {
                _exit(6);
            }
        }
        _exit(0);
    }
    int status = 0;
    ASSERT_EQ(waitpid(child, &status, 0), child);
    ASSERT_TRUE(WIFEXITED(status));
    EXPECT_EQ(WEXITSTATUS(status), 0);
}

TEST(Bake, NegativeDensityIsRefusedOnEveryLevel) {
    // A density is an extinction: a bake whose density grid (any level) holds a negative value,
    // or has a negative background, is refused with one line naming the file, the grid and the
    // voxel, not rendered.
    OneCell one(test::uniformPreset(4000.0f, 0.01f));
    const BakedVolume bake = bakeImpulses(one.generator->cells(), one.generator->kernel(),
                                          one.generator->generate(), options(0.004f, 3));
    const fs::path dir = tmpDir();
    const fs::path good = dir / "negative-good.vdb";
    writeBakedGrids(good, bake);
    EXPECT_NO_THROW((void)readBakedGrids(good));
    openvdb::initialize();
    const auto rewrite = [&](const fs::path& out, const std::string& grid,
                             const std::function<void(openvdb::FloatGrid&)>& edit) {
        openvdb::io::File f(good.string());
        f.open();
        openvdb::GridPtrVec grids = *f.getGrids();
        const openvdb::MetaMap::Ptr meta = f.getMetadata();
        f.close();
        bool found = false;
        for (auto& g : grids)
            if (g->getName() == grid) {
                edit(*openvdb::gridPtrCast<openvdb::FloatGrid>(g));
                found = true;
            }
        ASSERT_TRUE(found) << grid;
        openvdb::io::File(out.string()).write(grids, *meta);
    };
    for (int level = 0; level < 3; ++level) {
        const std::string name = bakedDensityName(level);
        const fs::path negative = dir / ("negative-" + name + ".vdb");
        rewrite(negative, name, [](openvdb::FloatGrid& g) {
            auto it = g.tree().beginValueOn();
            ASSERT_TRUE(bool(it));
            it.setValue(-0.25f);
        });
        expectBadFile(negative, "grid \"" + name + "\": negative density -0.25 at voxel (");
    }
    // An inactive voxel set to a negative value (it becomes active) and a negative background.
    const fs::path added = dir / "negative-added.vdb";
    rewrite(added, bakedDensityName(0),
            [](openvdb::FloatGrid& g) { g.tree().setValue(openvdb::Coord(-999, 7, 3), -1.0f); });
    expectBadFile(added, "negative density -1 at voxel (-999, 7, 3)");
    const fs::path background = dir / "negative-background.vdb";
    rewrite(background, bakedDensityName(1),
            [](openvdb::FloatGrid& g) { g.tree().root().setBackground(-0.5f, false); });
    expectBadFile(background, "negative background density -0.5");
}

TEST(Bake, OversizedRequestIsRefusedBeforeAllocating) {
    OneCell one(test::uniformPreset(4000.0f, 0.01f));
    const std::vector<Impulse> impulses = one.generator->generate();
    ::setenv("SPOT_MEMORY_LIMIT_MB", "64", 1);
    const auto start = std::chrono::steady_clock::now();
    try {
        // 0.00005 on a shell of ~0.09 x 0.26 x 0.26 world units: about 1e11 voxels.
        (void)bakeImpulses(one.generator->cells(), one.generator->kernel(), impulses,
                           options(0.00005f, 2));
        ADD_FAILURE() << "an oversized bake ran";
    } catch (const InputError& e) {
        const std::string m = e.what();
        EXPECT_NE(m.find("needs"), std::string::npos) << m;
        EXPECT_NE(m.find("MiB are available"), std::string::npos) << m;
        EXPECT_EQ(m.find('\n'), std::string::npos) << m;
    }
    ::unsetenv("SPOT_MEMORY_LIMIT_MB");
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    EXPECT_LT(seconds, 1.0) << "refused only after working";
    // A lattice beyond OpenVDB's coordinates, and bad options, are refused by the estimate.
    EXPECT_THROW((void)estimateBake(one.generator->cells(), options(1e-12f, 1)), InputError);
    EXPECT_THROW((void)estimateBake(one.generator->cells(), options(0.0f, 1)), InputError);
    EXPECT_THROW((void)estimateBake(one.generator->cells(), options(0.01f, 0)), InputError);
    EXPECT_THROW((void)estimateBake(one.generator->cells(), options(0.01f, kMaxBakeLevels + 1)),
                 InputError);
}

TEST(Bake, Fnv1aMatchesTheReferenceVectors) {
    EXPECT_EQ(fnv1a64(""), 0xcbf29ce484222325ull);
    EXPECT_EQ(fnv1a64("a"), 0xaf63dc4c8601ec8cull);
    EXPECT_EQ(fnv1a64("foobar"), 0x85944171f73967e8ull);
}

// ---- the command line ----

namespace {

using CliRun = spot::test::CliResult;

CliRun spotshell(const std::string& args, const std::string& env = "") {
    return spot::test::runSpotshell(args, env);
}

std::string scene(const std::string& name) {
    return std::string(SPOT_SOURCE_DIR) + "/presets/scenes/" + name + ".json";
}

void expectExit2(const std::string& args, const std::string& phrase, const std::string& env = "") {
    const CliRun r = spotshell(args, env);
    EXPECT_EQ(r.code, 2) << args << "\n" << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << args << "\n" << r.err;
    EXPECT_EQ(r.err.rfind("spotshell: error: ", 0), 0u) << r.err;
    EXPECT_NE(r.err.find(phrase), std::string::npos) << "expected '" << phrase << "' in: " << r.err;
}

} // namespace

TEST(BakeCli, BakesTheBunnyOnAnyThreadCountAndInfoReadsIt) {
    const fs::path dir = tmpDir();
    const std::string one = (dir / "bunny-t1.vdb").string(), two = (dir / "bunny-t2.vdb").string();
    const std::string common =
        "bake --scene " + scene("fur-bunny") + " --voxel-size 0.012 --levels 3";
    const CliRun r1 = spotshell(common + " --threads 1 --out " + one);
    ASSERT_EQ(r1.code, 0) << r1.err;
    EXPECT_EQ(r1.out.rfind("wrote " + one + " (3 levels", 0), 0u) << r1.out;
    const CliRun r2 = spotshell(common + " --threads 2 --out " + two);
    ASSERT_EQ(r2.code, 0) << r2.err;
    const BakedVolume a = readBakedGrids(one), b = readBakedGrids(two);
    expectSameGrids(a, b);
    EXPECT_GT(a.activeCount(0), 10000u);
    // The hash is of the preset file's text.
    std::ifstream preset(std::string(SPOT_SOURCE_DIR) + "/presets/fur.json", std::ios::binary);
    const std::string text((std::istreambuf_iterator<char>(preset)), {});
    EXPECT_EQ(a.presetHash(), fnv1a64(text));
    EXPECT_EQ(a.presetName(), "fur");

    // --resolution N: N voxels along the mesh's longest side.
    const std::string byResolution = (dir / "bunny-r60.vdb").string();
    const CliRun r3 =
        spotshell("bake --scene " + scene("fur-bunny") + " --resolution 60 --out " + byResolution);
    ASSERT_EQ(r3.code, 0) << r3.err;
    const Bounds bounds =
        loadMesh(std::string(SPOT_SOURCE_DIR) + "/presets/meshes/bunny.ply").bounds();
    const glm::vec3 size = bounds.size();
    EXPECT_NEAR(readBakedGrids(byResolution).voxelSize(0),
                std::max(size.x, std::max(size.y, size.z)) / 60.0f, 1e-7f);

    const CliRun info = spotshell("info --bake " + one);
    ASSERT_EQ(info.code, 0) << info.err;
    EXPECT_NE(info.out.find("level 2    voxel 0.048"), std::string::npos) << info.out;
    EXPECT_NE(info.out.find("preset     fur"), std::string::npos) << info.out;
    EXPECT_NE(info.out.find("shading    tangent, normal"), std::string::npos) << info.out;
}

TEST(BakeCli, BadRequestsAndBadFilesExitTwoWithOneLine) {
    const fs::path dir = tmpDir();
    const std::string out = (dir / "never.vdb").string();
    const std::string bunny = "bake --scene " + scene("fur-bunny") + " --out " + out;
    expectExit2(bunny + " --voxel-size 0.01 --resolution 100", "not both");
    expectExit2(bunny + " --levels 9", "--levels");
    expectExit2(bunny + " --voxel-size -1", "--voxel-size");
    expectExit2(bunny + " --voxel-size 0.0001", "MiB are available", "SPOT_MEMORY_LIMIT_MB=256");
    EXPECT_FALSE(fs::exists(out));
    const std::string garbage = (dir / "garbage-cli.vdb").string();
    std::ofstream(garbage) << "not a vdb";
    expectExit2("info --bake " + garbage, "cannot read");
    expectExit2("info --bake " + (dir / "absent.vdb").string(), "no such bake file");
    expectExit2("info", "give --mesh FILE, --bake FILE or --splats FILE");
}

TEST(BakeCli, NegativeDensityExitsTwoWithOneLine) {
    // `info` and `render --method baked` read the bake the same way: both refuse it.
    const fs::path dir = tmpDir();
    const std::string good = (dir / "negative-cli-good.vdb").string();
    const CliRun r = spotshell("bake --scene " + scene("fur-bunny") +
                               " --voxel-size 0.024 --levels 2 --out " + good);
    ASSERT_EQ(r.code, 0) << r.err;
    openvdb::initialize();
    const std::string bad = (dir / "negative-cli.vdb").string();
    {
        openvdb::io::File f(good);
        f.open();
        openvdb::GridPtrVec grids = *f.getGrids();
        const openvdb::MetaMap::Ptr meta = f.getMetadata();
        f.close();
        for (auto& g : grids)
            if (g->getName() == bakedDensityName(1)) {
                auto it = openvdb::gridPtrCast<openvdb::FloatGrid>(g)->tree().beginValueOn();
                ASSERT_TRUE(bool(it));
                it.setValue(-2.0f);
            }
        openvdb::io::File(bad).write(grids, *meta);
    }
    expectExit2("info --bake " + bad, "negative density -2");
    expectExit2("render --scene " + scene("fur-bunny") + " --size 32x32 --method baked --bake " +
                    bad + " --out " + (dir / "never.png").string(),
                "negative density -2");
}
