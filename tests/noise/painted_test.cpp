// The painted sparse grid (noise/painted.h): voxel access, the trilinear sample, .vdb files and
// their errors, the `painted` field kind in presets and the generator, the command line.
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <sys/wait.h>
#include <unistd.h>

#include <gtest/gtest.h>
#include <openvdb/io/File.h>
#include <openvdb/openvdb.h>

#include "noise/error.h"
#include "noise/field.h"
#include "noise/impulses.h"
#include "noise/mesh.h"
#include "noise/painted.h"
#include "noise/preset.h"
#include "cli_run.h"
#include "test_support.h"

namespace {

using namespace spot;
using namespace spot::noise;
namespace fs = std::filesystem;

fs::path tmpDir(const std::string& name) {
    const fs::path dir =
        fs::path(SPOT_TEST_TMP_DIR) / ("painted-" + std::to_string(::getpid())) / name;
    fs::remove_all(dir);
    fs::create_directories(dir);
    return dir;
}

std::string slurp(const fs::path& file) {
    std::ifstream in(file, std::ios::binary);
    std::ostringstream s;
    s << in.rdbuf();
    return s.str();
}

void write(const fs::path& file, const std::string& text) {
    std::ofstream(file, std::ios::binary) << text;
}

/// The message of the InputError `f` throws ("" when it throws none).
template <typename F> std::string inputError(F&& f) {
    try {
        f();
    } catch (const InputError& e) {
        return e.what();
    }
    return "";
}

/// Trilinear interpolation written out independently of the shared header.
glm::vec3 trilinear(const PaintedGrid& g, glm::vec3 world) {
    const glm::vec3 q = world / g.voxelSize();
    const glm::vec3 b = glm::floor(q);
    const glm::vec3 t = q - b;
    const glm::ivec3 i(b);
    glm::vec3 sum(0.0f);
    for (int dz = 0; dz < 2; ++dz)
        for (int dy = 0; dy < 2; ++dy)
            for (int dx = 0; dx < 2; ++dx) {
                const float w =
                    (dx ? t.x : 1.0f - t.x) * (dy ? t.y : 1.0f - t.y) * (dz ? t.z : 1.0f - t.z);
                sum += w * g.get(i + glm::ivec3(dx, dy, dz));
            }
    return sum;
}

TEST(PaintedGrid, SetGetClearAndBackground) {
    PaintedGrid g("density", 1, 0.25f, glm::vec3(0.5f, 7.0f, 7.0f));
    EXPECT_EQ(g.name(), "density");
    EXPECT_EQ(g.components(), 1);
    EXPECT_EQ(g.voxelSize(), 0.25f);
    EXPECT_EQ(g.background(), glm::vec3(0.5f, 0.0f, 0.0f)); // scalars keep .x only
    const glm::ivec3 v(-3, 9, 100);
    EXPECT_FALSE(g.active(v));
    EXPECT_EQ(g.get(v), g.background());
    g.set(v, glm::vec3(0.75f, 1.0f, 1.0f));
    EXPECT_TRUE(g.active(v));
    EXPECT_EQ(g.get(v), glm::vec3(0.75f, 0.0f, 0.0f));
    EXPECT_EQ(g.activeCount(), 1u);
    g.clear(v);
    EXPECT_FALSE(g.active(v));
    EXPECT_EQ(g.get(v), g.background());
    EXPECT_EQ(g.activeCount(), 0u);

    EXPECT_EQ(g.nearestVoxel(glm::vec3(0.37f, -0.37f, 0.1f)), glm::ivec3(1, -1, 0));
    EXPECT_EQ(g.voxelPosition(glm::ivec3(2, -4, 1)), glm::vec3(0.5f, -1.0f, 0.25f));

    PaintedGrid c("comb", 3, 0.1f, glm::vec3(1.0f, 0.0f, 0.0f));
    c.set(glm::ivec3(0), glm::vec3(0.0f, 1.0f, 2.0f));
    c.set(glm::ivec3(-9, 0, 4), glm::vec3(3.0f, 4.0f, 5.0f));
    EXPECT_EQ(c.get(glm::ivec3(0)), glm::vec3(0.0f, 1.0f, 2.0f));
    std::vector<std::pair<glm::ivec3, glm::vec3>> seen;
    c.forEachActive([&](glm::ivec3 v, glm::vec3 x) { seen.emplace_back(v, x); });
    ASSERT_EQ(seen.size(), 2u);
    std::vector<std::pair<glm::ivec3, glm::vec3>> again;
    c.forEachActive([&](glm::ivec3 v, glm::vec3 x) { again.emplace_back(v, x); });
    EXPECT_EQ(seen, again);
    EXPECT_GT(c.memoryBytes(), 0u);

    // A clone is deep: changing it leaves the original alone.
    const std::shared_ptr<PaintedGrid> copy = c.clone();
    copy->set(glm::ivec3(0), glm::vec3(9.0f));
    EXPECT_EQ(c.get(glm::ivec3(0)), glm::vec3(0.0f, 1.0f, 2.0f));
    EXPECT_EQ(copy->get(glm::ivec3(0)), glm::vec3(9.0f));
    EXPECT_EQ(copy->activeCount(), 2u);

    EXPECT_NE(inputError([] { PaintedGrid("x", 2, 1.0f, glm::vec3(0.0f)); }), "");
    EXPECT_NE(inputError([] { PaintedGrid("x", 1, 0.0f, glm::vec3(0.0f)); }), "");
    EXPECT_NE(inputError([&] { c.set(glm::ivec3(1), glm::vec3(NAN)); }), "");
}

TEST(PaintedGrid, SampleIsTheTrilinearInterpolationOfGet) {
    for (const int components : {1, 3}) {
        SCOPED_TRACE(components);
        PaintedGrid g("g", components, 0.1f, glm::vec3(0.25f, 0.5f, 0.75f));
        std::uint32_t h = 1;
        const auto rnd = [&] {
            h = h * 1664525u + 1013904223u;
            return float(h >> 8) / float(1u << 24);
        };
        // Voxels on both sides of 0 and across leaf borders (leaves are 8^3).
        for (int i = 0; i < 4000; ++i)
            g.set(glm::ivec3(int(rnd() * 24) - 12, int(rnd() * 24) - 12, int(rnd() * 24) - 12),
                  glm::vec3(rnd(), rnd(), rnd()));
        // Exactly the voxel values at lattice points.
        for (int i = 0; i < 200; ++i) {
            const glm::ivec3 v(int(rnd() * 30) - 15, int(rnd() * 30) - 15, int(rnd() * 30) - 15);
            EXPECT_EQ(g.sample(g.voxelPosition(v)), g.get(v)) << v.x << " " << v.y << " " << v.z;
        }
        float worst = 0.0f;
        for (int i = 0; i < 2000; ++i) {
            const glm::vec3 p(rnd() * 3.0f - 1.5f, rnd() * 3.0f - 1.5f, rnd() * 3.0f - 1.5f);
            const glm::vec3 d = glm::abs(g.sample(p) - trilinear(g, p));
            worst = std::max({worst, d.x, d.y, d.z});
        }
        EXPECT_LE(worst, 1e-5f);
        // Far away: the background.
        EXPECT_EQ(g.sample(glm::vec3(1e6f, -1e6f, 3.0f)), g.background());
        // A change is seen by the next sample.
        const glm::ivec3 v(3, -2, 5);
        g.set(v, glm::vec3(0.125f));
        EXPECT_EQ(g.sample(g.voxelPosition(v)),
                  components == 1 ? glm::vec3(0.125f, 0.0f, 0.0f) : glm::vec3(0.125f));
    }
}

TEST(PaintedGrid, FlattenedTableIsSizedAndProbesAreShort) {
    PaintedGrid g("g", 1, 0.01f, glm::vec3(0.0f));
    for (int x = -200; x < 200; x += 3)
        for (int y = -200; y < 200; y += 5)
            g.set(glm::ivec3(x, y, (x * 7 + y * 3) % 50), glm::vec3(1.0f));
    std::vector<float> data(5, 0.0f); // the form is appended after what is there
    const gpu::SpotField f = g.flatten(data);
    EXPECT_EQ(f.kind.x, 5);
    EXPECT_EQ(f.data.x, 5u);
    const std::uint32_t size = f.data.y;
    EXPECT_EQ(size & (size - 1), 0u) << size;
    const std::uint32_t blocks = (std::uint32_t(data.size()) - f.data.w) / 512u;
    EXPECT_GE(size, 2 * blocks);
    EXPECT_LT(f.data.z, 32u);
    std::printf("%u leaves, table of %u, longest probe %u, %zu floats\n", blocks, size, f.data.z,
                data.size());
}

TEST(PaintedGrid, WriteThenReadRoundTripsBitForBit) {
    const fs::path dir = tmpDir("roundtrip");
    PaintedGrid density("density", 1, 0.05f, glm::vec3(1.0f));
    PaintedGrid comb("comb", 3, 0.05f, glm::vec3(0.0f, 1.0f, 0.0f));
    for (int i = -20; i < 20; ++i) {
        density.set(glm::ivec3(i, 2 * i, -i), glm::vec3(std::nextafter(0.3f + 0.01f * i, 1.0f)));
        comb.set(glm::ivec3(-i, i, 7), glm::vec3(0.1f * i, 1e-30f, -3.0f));
    }
    const fs::path file = dir / "paint.vdb";
    writePaintedGrids(file, {&density, &comb});
    for (const auto& entry : fs::directory_iterator(dir))
        EXPECT_EQ(entry.path().filename(), "paint.vdb") << "left behind: " << entry.path();

    for (const PaintedGrid* original : {&density, &comb}) {
        const PaintedGrid back = readPaintedGrid(file, original->name(), original->components());
        EXPECT_EQ(back.name(), original->name());
        EXPECT_EQ(back.voxelSize(), original->voxelSize());
        EXPECT_EQ(back.background(), original->background());
        ASSERT_EQ(back.activeCount(), original->activeCount());
        std::vector<std::pair<glm::ivec3, glm::vec3>> a, b;
        original->forEachActive([&](glm::ivec3 v, glm::vec3 x) { a.emplace_back(v, x); });
        back.forEachActive([&](glm::ivec3 v, glm::vec3 x) { b.emplace_back(v, x); });
        EXPECT_EQ(a, b);
        std::vector<float> fa, fb;
        original->flatten(fa);
        back.flatten(fb);
        ASSERT_EQ(fa.size(), fb.size());
        EXPECT_EQ(std::memcmp(fa.data(), fb.data(), fa.size() * sizeof(float)), 0);
    }
}

TEST(PaintedGrid, FailedWriteLeavesTheOldFile) {
    const fs::path dir = tmpDir("failed-write");
    PaintedGrid a("density", 1, 0.05f, glm::vec3(1.0f));
    a.set(glm::ivec3(1), glm::vec3(0.5f));
    const fs::path file = dir / "paint.vdb";
    writePaintedGrids(file, {&a});
    const std::string before = slurp(file);

    // Two grids of one name: refused before anything is written.
    PaintedGrid b("density", 1, 0.05f, glm::vec3(0.0f));
    EXPECT_NE(inputError([&] {
                  writePaintedGrids(file, {&a, &b});
              }).find("distinct"),
              std::string::npos);
    EXPECT_EQ(slurp(file), before);

    // The rename fails (the target is a folder that is not empty): the folder stays, no
    // temporary file is left.
    const fs::path folder = dir / "folder.vdb";
    fs::create_directories(folder / "inside");
    const std::string e = inputError([&] { writePaintedGrids(folder, {&a}); });
    EXPECT_NE(e.find("folder.vdb"), std::string::npos) << e;
    EXPECT_TRUE(fs::is_directory(folder / "inside"));
    // Into a folder that does not exist.
    EXPECT_NE(inputError([&] { writePaintedGrids(dir / "nowhere" / "x.vdb", {&a}); }), "");
    std::vector<std::string> names;
    for (const auto& entry : fs::directory_iterator(dir))
        names.push_back(entry.path().filename().string());
    std::sort(names.begin(), names.end());
    EXPECT_EQ(names, (std::vector<std::string>{"folder.vdb", "paint.vdb"}));
    EXPECT_EQ(slurp(file), before);
}

TEST(PaintedGrid, BadFilesGiveOneClearInputError) {
    const fs::path dir = tmpDir("bad");
    PaintedGrid density("density", 1, 0.05f, glm::vec3(1.0f));
    PaintedGrid colour("color", 3, 0.05f, glm::vec3(1.0f));
    for (int i = 0; i < 300; ++i) {
        density.set(glm::ivec3(i, i % 17, -i), glm::vec3(0.5f));
        colour.set(glm::ivec3(i, 0, 0), glm::vec3(0.5f));
    }
    const fs::path good = dir / "good.vdb";
    writePaintedGrids(good, {&density, &colour});
    const std::string bytes = slurp(good);

    const auto expectError = [](const std::string& message,
                                const std::vector<std::string>& phrases) {
        EXPECT_EQ(std::count(message.begin(), message.end(), '\n'), 0) << message;
        std::printf("%s\n", message.c_str());
        for (const std::string& p : phrases)
            EXPECT_NE(message.find(p), std::string::npos)
                << "expected '" << p << "' in: " << message;
    };
    expectError(inputError([&] { readPaintedGrid(dir / "missing.vdb", "density", 1); }),
                {"missing.vdb", "\"density\"", "no such file"});
    write(dir / "truncated.vdb", bytes.substr(0, bytes.size() / 2));
    expectError(inputError([&] { readPaintedGrid(dir / "truncated.vdb", "density", 1); }),
                {"truncated.vdb", "\"density\""});
    // Cut anywhere past the header: every cut is one clear line, stopped by the grids' byte
    // ranges before OpenVDB reads a size from past the end of the file.
    for (int k = 1; k < 16; ++k) {
        const std::size_t cut = bytes.size() * std::size_t(k) / 16;
        write(dir / "cut.vdb", bytes.substr(0, cut));
        const std::string message =
            inputError([&] { readPaintedGrid(dir / "cut.vdb", "color", 3); });
        EXPECT_NE(message.find("cut.vdb"), std::string::npos) << cut << ": " << message;
        EXPECT_EQ(message.find("bad_alloc"), std::string::npos) << cut << ": " << message;
        EXPECT_EQ(std::count(message.begin(), message.end(), '\n'), 0) << message;
    }
    write(dir / "short.vdb", bytes.substr(0, 10));
    expectError(inputError([&] { readPaintedGrid(dir / "short.vdb", "density", 1); }),
                {"short.vdb", "cannot read"});
    write(dir / "garbage.vdb", std::string(4096, '\x5a'));
    expectError(inputError([&] { readPaintedGrid(dir / "garbage.vdb", "density", 1); }),
                {"garbage.vdb", "cannot read"});
    expectError(inputError([&] { readPaintedGrid(good, "tilt", 1); }),
                {"good.vdb", "\"tilt\"", "no grid of that name", "\"density\"", "\"color\""});
    expectError(inputError([&] { readPaintedGrid(good, "color", 1); }),
                {"good.vdb", "\"color\"", "Tree_vec3s", "Tree_float"});
    expectError(inputError([&] { readPaintedGrid(good, "density", 3); }),
                {"good.vdb", "\"density\"", "Tree_float"});
    // Every prefix of the file fails cleanly (or, past the last grid's data, reads it whole).
    for (std::size_t n = 0; n < bytes.size(); n += std::max<std::size_t>(1, bytes.size() / 40)) {
        write(dir / "prefix.vdb", bytes.substr(0, n));
        try {
            readPaintedGrid(dir / "prefix.vdb", "density", 1);
        } catch (const InputError& e) {
            EXPECT_NE(std::string(e.what()).find("prefix.vdb"), std::string::npos);
        }
    }
}

/// Grids written with OpenVDB directly: what the editor never writes but a file may hold.
TEST(PaintedGrid, RefusesTransformsNonFiniteValuesAndAbsurdSizes) {
    openvdb::initialize();
    const fs::path dir = tmpDir("openvdb");
    const auto writeGrid = [&](const std::string& file, openvdb::GridBase::Ptr grid) {
        openvdb::io::File f((dir / file).string());
        f.write({grid});
        f.close();
        return dir / file;
    };
    const auto scalar = [](double voxel) {
        auto g = openvdb::FloatGrid::create(1.0f);
        g->setName("density");
        g->setTransform(openvdb::math::Transform::createLinearTransform(voxel));
        g->tree().setValueOn(openvdb::Coord(1, 2, 3), 0.5f);
        return g;
    };
    const auto expectPhrase = [](const std::string& e, const std::string& phrase) {
        EXPECT_NE(e.find(phrase), std::string::npos) << "expected '" << phrase << "' in: " << e;
        EXPECT_EQ(std::count(e.begin(), e.end(), '\n'), 0) << e;
    };

    // Accepted: a plain uniform scale, read back at that voxel size.
    const PaintedGrid ok = readPaintedGrid(writeGrid("ok.vdb", scalar(0.25)), "density", 1);
    EXPECT_EQ(ok.voxelSize(), 0.25f);
    EXPECT_EQ(ok.get(glm::ivec3(1, 2, 3)), glm::vec3(0.5f, 0.0f, 0.0f));

    auto rotated = scalar(0.25);
    rotated->transform().preRotate(0.3, openvdb::math::Y_AXIS);
    expectPhrase(
        inputError([&] { readPaintedGrid(writeGrid("rotated.vdb", rotated), "density", 1); }),
        "not a uniform scale");
    auto stretched = scalar(0.25);
    stretched->transform().preScale(openvdb::Vec3d(1.0, 2.0, 1.0));
    expectPhrase(
        inputError([&] { readPaintedGrid(writeGrid("stretched.vdb", stretched), "density", 1); }),
        "not a uniform scale");
    auto moved = scalar(0.25);
    moved->transform().postTranslate(openvdb::Vec3d(0.1, 0.0, 0.0));
    expectPhrase(inputError([&] { readPaintedGrid(writeGrid("moved.vdb", moved), "density", 1); }),
                 "not a uniform scale");

    auto nan = scalar(0.25);
    nan->tree().setValueOn(openvdb::Coord(-5, 0, 0), std::nanf(""));
    expectPhrase(inputError([&] { readPaintedGrid(writeGrid("nan.vdb", nan), "density", 1); }),
                 "NaN or infinite");
    auto inf = openvdb::Vec3SGrid::create(openvdb::Vec3s(0.0f));
    inf->setName("comb");
    inf->setTransform(openvdb::math::Transform::createLinearTransform(0.1));
    inf->tree().setValueOn(openvdb::Coord(0), openvdb::Vec3s(0.0f, INFINITY, 0.0f));
    expectPhrase(inputError([&] { readPaintedGrid(writeGrid("inf.vdb", inf), "comb", 3); }),
                 "NaN or infinite");

    // An active tile of 4096^3 voxels: a few bytes in the file, far more than a field may hold.
    auto huge = scalar(0.25);
    huge->tree().fill(openvdb::CoordBBox(openvdb::Coord(0), openvdb::Coord(4095)), 0.5f, true);
    expectPhrase(inputError([&] { readPaintedGrid(writeGrid("huge.vdb", huge), "density", 1); }),
                 "active voxels are more than a painted field may hold");
}

/// The cost of the flattened form for a grid painted over the whole bunny at a quarter of the fur
/// preset's cell size (docs/design.md section 3 quotes these numbers). Also writes the grid and a
/// fur preset and scene that read it (build/tests/tmp/painted-bunny/), for timing renders.
TEST(PaintedGrid, FlattenTheBunnyAtAQuarterCell) {
    const fs::path dir = fs::path(SPOT_TEST_TMP_DIR) / "painted-bunny";
    fs::create_directories(dir);
    const fs::path presets = fs::path(SPOT_SOURCE_DIR) / "presets";
    const Mesh bunny = loadMesh(presets / "meshes" / "bunny.ply");
    const ImpulseGenerator fur(bunny, loadPreset(presets / "fur.json"), GeneratorOptions{});
    const float voxel = fur.cellSize() / 4.0f;
    PaintedGrid density("density", 1, voxel, glm::vec3(0.8f));
    // Every voxel whose 8-voxel stencil a surface point reads: the corners around points spread
    // over each triangle at under a voxel apart.
    for (const glm::uvec3& t : bunny.triangles) {
        const glm::vec3 p0 = bunny.positions[t.x], p1 = bunny.positions[t.y],
                        p2 = bunny.positions[t.z];
        const float edge =
            std::max({glm::length(p1 - p0), glm::length(p2 - p0), glm::length(p2 - p1)});
        const int n = std::max(1, int(std::ceil(edge / (0.5f * voxel))));
        for (int i = 0; i <= n; ++i)
            for (int j = 0; i + j <= n; ++j) {
                const glm::vec3 p = p0 + (p1 - p0) * (float(i) / n) + (p2 - p0) * (float(j) / n);
                const glm::ivec3 b(glm::floor(p / voxel));
                for (int c = 0; c < 8; ++c)
                    density.set(b + glm::ivec3(c & 1, (c >> 1) & 1, c >> 2), glm::vec3(0.8f));
            }
    }
    const auto start = std::chrono::steady_clock::now();
    std::vector<float> data;
    const gpu::SpotField f = density.flatten(data);
    const double ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    const std::uint32_t leaves = std::uint32_t(data.size() - f.data.w) / 512u;
    EXPECT_LT(f.data.z, 32u);
    EXPECT_LE(data.size() * sizeof(float), kMaxPaintedBytes);
    std::printf(
        "bunny, voxel %.5g (cell %.5g / 4): %zu active voxels, %u leaves, table %u, "
        "longest probe %u, %.1f MiB field data, OpenVDB tree %.1f MiB, flattened in %.1f ms\n",
        voxel, fur.cellSize(), density.activeCount(), leaves, f.data.y, f.data.z,
        double(data.size() * sizeof(float)) / (1 << 20), double(density.memoryBytes()) / (1 << 20),
        ms);
    writePaintedGrids(dir / "paint.vdb", {&density});
    std::string preset = slurp(presets / "fur.json");
    const std::size_t at = preset.find("\"density\"");
    ASSERT_NE(at, std::string::npos);
    const std::size_t end = preset.find('}', at);
    const std::string constant = preset.substr(0, at) + "\"density\": 0.8" + preset.substr(end + 1);
    write(dir / "fur-constant.json", constant);
    write(dir / "fur-painted.json",
          preset.substr(0, at) +
              R"("density": {"type": "painted", "file": "paint.vdb", "grid": "density"})" +
              preset.substr(end + 1));
    std::string scene = slurp(presets / "scenes" / "fur-bunny.json");
    const std::string mesh = "../meshes/bunny.ply", furPath = "../fur.json";
    scene.replace(scene.find(mesh), mesh.size(), (presets / "meshes" / "bunny.ply").string());
    std::string painted = scene, constantScene = scene;
    painted.replace(painted.find(furPath), furPath.size(), "fur-painted.json");
    constantScene.replace(constantScene.find(furPath), furPath.size(), "fur-constant.json");
    write(dir / "scene-painted.json", painted);
    write(dir / "scene-constant.json", constantScene);
}

/// A preset over a sphere of radius 1 with the given fields JSON.
std::string presetJson(const std::string& fields) {
    return R"({"version": 1, "kernel": {"lobes": [{"sigma": [1, 1, 1], "extinction": 50}]},
              "distribution": {"type": "poisson", "density_max": 3000},
              "fields": )" +
           fields + "}";
}

TEST(PaintedField, PresetParsesAndRejectsBadForms) {
    const PresetDesc p = parsePreset(
        presetJson(R"({"density": {"type": "painted", "file": "p.vdb", "grid": "density"},
                       "scale": 0.01})"),
        "p.json");
    EXPECT_EQ(p.density.kind, FieldDesc::Kind::Painted);
    EXPECT_EQ(p.density.file, "p.vdb");
    EXPECT_EQ(p.density.grid, "density");
    const auto bad = [](const std::string& fields, const std::string& phrase) {
        const std::string e = inputError([&] { parsePreset(presetJson(fields), "p.json"); });
        EXPECT_NE(e.find(phrase), std::string::npos) << "expected '" << phrase << "' in: " << e;
    };
    bad(R"({"density": {"type": "painted", "file": "p.vdb"}})", "fields.density");
    bad(R"({"density": {"type": "painted", "grid": "density"}})", "file");
    bad(R"({"density": {"type": "painted", "file": "p.vdb", "grid": "d", "range": [0, 1]}})",
        "range");
    bad(R"({"density": {"type": "painted", "file": 3, "grid": "d"}})", "fields.density.file");
    bad(R"({"density": {"type": "paint"}})", "\"painted\"");
}

TEST(PaintedField, BindsFromTheFileOrTheLiveGrid) {
    const fs::path dir = tmpDir("bind");
    PaintedGrid comb("comb", 3, 0.1f, glm::vec3(1.0f, 0.0f, 0.0f));
    comb.set(glm::ivec3(0), glm::vec3(0.0f, 0.0f, 1.0f));
    writePaintedGrids(dir / "paint.vdb", {&comb});
    const Mesh mesh = makeSphere(1.0f, 8, 16);
    FieldDesc d;
    d.kind = FieldDesc::Kind::Painted;
    d.components = 3;
    d.file = "paint.vdb";
    d.grid = "comb";
    const auto field = makeField(d, mesh, dir, "test fields.comb");
    SurfacePoint sp;
    sp.position = glm::vec3(0.0f);
    EXPECT_EQ(field->eval(sp), glm::vec3(0.0f, 0.0f, 1.0f));
    const FieldRange r = field->range();
    EXPECT_EQ(r.lo, glm::vec3(0.0f));
    EXPECT_EQ(r.hi, glm::vec3(1.0f, 0.0f, 1.0f));

    FieldDesc wrong = d;
    wrong.components = 1;
    const std::string e = inputError([&] { makeField(wrong, mesh, dir, "test fields.tilt_deg"); });
    EXPECT_NE(e.find("test fields.tilt_deg"), std::string::npos) << e;
    EXPECT_NE(e.find("paint.vdb"), std::string::npos) << e;

    // The live grid wins over the file, and changes are seen.
    auto live = comb.clone();
    FieldDesc liveDesc = d;
    liveDesc.painted = live;
    const auto liveField = makeField(liveDesc, mesh, "/nonexistent", "test");
    live->set(glm::ivec3(0), glm::vec3(0.0f, 1.0f, 0.0f));
    EXPECT_EQ(liveField->eval(sp), glm::vec3(0.0f, 1.0f, 0.0f));
}

/// A density grid over the sphere: 1 everywhere except voxels with x index <= kZeroUpTo.
constexpr int kZeroUpTo = -4;
constexpr float kVoxel = 0.05f;

std::shared_ptr<PaintedGrid> halfZeroDensity() {
    auto g = std::make_shared<PaintedGrid>("density", 1, kVoxel, glm::vec3(1.0f));
    for (int x = -24; x <= kZeroUpTo; ++x)
        for (int y = -24; y <= 24; ++y)
            for (int z = -24; z <= 24; ++z)
                g->set(glm::ivec3(x, y, z), glm::vec3(0.0f));
    return g;
}

TEST(PaintedField, ZeroDensityRegionGeneratesNothingAndTheRestAsTheConstantField) {
    const Mesh mesh = makeSphere(1.0f, 48, 96);
    PresetDesc constant = test::uniformPreset(3000.0f, 0.01f);
    PresetDesc painted = constant;
    painted.density.kind = FieldDesc::Kind::Painted;
    painted.density.painted = halfZeroDensity();
    GeneratorOptions options;
    options.seed = 5;
    const std::vector<Impulse> a = ImpulseGenerator(mesh, constant, options).generate();
    const std::vector<Impulse> b = ImpulseGenerator(mesh, painted, options).generate();
    const float zeroEdge = kZeroUpTo * kVoxel; // the density is 0 for x <= here, 1 for x >= + voxel
    std::size_t inZero = 0, kept = 0;
    std::vector<const Impulse*> aOne, bOne;
    for (const Impulse& i : b) {
        const glm::vec3 anchor = i.position; // height offset 0
        if (anchor.x < zeroEdge - 0.01f * kVoxel)
            ++inZero;
    }
    EXPECT_EQ(inZero, 0u);
    for (const Impulse& i : a) {
        if (i.position.x > zeroEdge + 1.01f * kVoxel)
            aOne.push_back(&i);
        kept += i.position.x < zeroEdge - 0.01f * kVoxel;
    }
    for (const Impulse& i : b)
        if (i.position.x > zeroEdge + 1.01f * kVoxel)
            bOne.push_back(&i);
    EXPECT_GT(kept, 1000u); // the constant field has impulses in the painted-out region
    ASSERT_EQ(aOne.size(), bOne.size());
    for (std::size_t i = 0; i < aOne.size(); ++i) {
        ASSERT_EQ(aOne[i]->position, bOne[i]->position) << i;
        ASSERT_EQ(aOne[i]->cell, bOne[i]->cell) << i;
    }
    std::printf("constant: %zu impulses, painted: %zu; %zu in the zero region of the constant\n",
                a.size(), b.size(), kept);
}

TEST(PaintedField, GeneratorSetFieldAndRefresh) {
    const Mesh mesh = makeSphere(1.0f, 24, 48);
    const PresetDesc preset = test::uniformPreset(2000.0f, 0.01f);
    GeneratorOptions options;
    options.seed = 3;
    ImpulseGenerator gen(mesh, preset, options);
    const std::size_t all = gen.generate().size();
    EXPECT_EQ(gen.fieldDesc(SPOT_FIELD_DENSITY)->kind, FieldDesc::Kind::Constant);
    EXPECT_EQ(gen.fieldDesc(SPOT_FIELD_COMB), nullptr);

    auto grid = std::make_shared<PaintedGrid>("density", 1, 0.1f, glm::vec3(1.0f));
    FieldDesc d;
    d.kind = FieldDesc::Kind::Painted;
    d.components = 1;
    d.painted = grid;
    gen.setField(SPOT_FIELD_DENSITY, d);
    EXPECT_EQ(gen.fieldDesc(SPOT_FIELD_DENSITY)->kind, FieldDesc::Kind::Painted);
    EXPECT_EQ(gen.sharedParams().fields[SPOT_FIELD_DENSITY].kind.x, 5);
    EXPECT_EQ(gen.generate().size(), all); // background 1

    // Paint a region to 0 in place, then refresh: fewer impulses.
    for (int x = -12; x <= 0; ++x)
        for (int y = -12; y <= 12; ++y)
            for (int z = -12; z <= 12; ++z)
                grid->set(glm::ivec3(x, y, z), glm::vec3(0.0f));
    EXPECT_EQ(gen.generate().size(), all); // not refreshed yet
    gen.refreshFields();
    const std::size_t painted = gen.generate().size();
    EXPECT_LT(painted, all * 6 / 10);
    EXPECT_GT(painted, all * 4 / 10);

    // A slot of the wrong size, or a scale beyond the cell size, is refused and changes nothing.
    FieldDesc vec = d;
    vec.components = 3;
    EXPECT_NE(inputError([&] { gen.setField(SPOT_FIELD_DENSITY, vec); }), "");
    EXPECT_NE(inputError(
                  [&] { gen.setField(SPOT_FIELD_SCALE, test::constantField(glm::vec3(1.0f), 3)); }),
              "");
    EXPECT_EQ(gen.generate().size(), painted);
    // A comb set where there was none.
    gen.setField(SPOT_FIELD_COMB, test::constantField(glm::vec3(0.0f, 0.0f, 1.0f), 3));
    ASSERT_NE(gen.fieldDesc(SPOT_FIELD_COMB), nullptr);
    EXPECT_EQ(gen.sharedParams().flags.z, 1u);
}

// ---- The command line --------------------------------------------------------------------

using Result = spot::test::CliResult;

Result run(const std::string& args, const fs::path&) {
    return spot::test::runSpotshell(args, "SPOT_VALIDATION=1");
}

TEST(PaintedCli, ImpulsesAndRenderReadAPaintedPreset) {
    const fs::path dir = tmpDir("cli");
    const std::shared_ptr<PaintedGrid> density = halfZeroDensity();
    PaintedGrid color("color", 3, kVoxel, glm::vec3(0.8f, 0.5f, 0.3f));
    for (int i = -20; i < 20; ++i)
        color.set(glm::ivec3(i, 0, 20), glm::vec3(0.1f, 0.9f, 0.1f));
    writePaintedGrids(dir / "paint.vdb", {density.get(), &color});
    write(dir / "painted.json",
          presetJson(R"({"density": {"type": "painted", "file": "paint.vdb", "grid": "density"},
                         "color": {"type": "painted", "file": "paint.vdb", "grid": "color"},
                         "scale": 0.01})"));
    write(dir / "scene.json",
          R"({"version": 1, "mesh": "generated:sphere", "preset": "painted.json", "seed": 1,
              "camera": {"eye": [0, 0, 4], "target": [0, 0, 0], "up": [0, 1, 0], "fov_deg": 40},
              "image": {"width": 48, "height": 48}})");

    const Result i =
        run("impulses --mesh generated:sphere --preset " + (dir / "painted.json").string() +
                " --out " + (dir / "imp.ply").string(),
            dir);
    ASSERT_EQ(i.code, 0) << i.err;
    EXPECT_TRUE(fs::is_regular_file(dir / "imp.ply"));
    const Result r = run("render --scene " + (dir / "scene.json").string() +
                             " --method hybrid --out " + (dir / "render.png").string(),
                         dir);
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_TRUE(fs::is_regular_file(dir / "render.png"));

    // A broken .vdb: exit 2 and one line naming it.
    write(dir / "paint.vdb", "not a vdb file at all");
    for (const std::string& args :
         {"impulses --mesh generated:sphere --preset " + (dir / "painted.json").string() +
              " --out " + (dir / "imp2.ply").string(),
          "render --scene " + (dir / "scene.json").string() + " --method hybrid --out " +
              (dir / "render2.png").string()}) {
        const Result b = run(args, dir);
        EXPECT_EQ(b.code, 2) << args << "\n" << b.err;
        EXPECT_EQ(std::count(b.err.begin(), b.err.end(), '\n'), 1) << b.err;
        EXPECT_NE(b.err.find("paint.vdb"), std::string::npos) << b.err;
        EXPECT_NE(b.err.find("fields.density"), std::string::npos) << b.err;
    }
    EXPECT_FALSE(fs::exists(dir / "imp2.ply"));
}

} // namespace

namespace {

// A paint layer over a procedural field (noise/painted.h PaintLayer, spotFieldLayer): empty, the
// field is its base bit for bit; at a painted voxel's lattice point it is the documented blend
// (density: b m + (1 - b m) r; override: b (1 - w) + v w); the layer round-trips through a file.
TEST(PaintLayer, LayersOverTheBaseField) {
    const Mesh mesh = makeSphere(1.0f, 16, 32);
    FieldDesc noise;
    noise.kind = FieldDesc::Kind::Noise;
    noise.components = 1;
    noise.frequency = 3.0f;
    noise.lo = glm::vec3(0.2f, 0.0f, 0.0f);
    noise.hi = glm::vec3(0.9f, 0.0f, 0.0f);
    const auto base = makeField(noise, mesh, "", "test");
    auto density = std::make_shared<PaintLayer>("density.paint", 1, 0.1f, PaintMode::Density);
    FieldDesc layered = noise;
    layered.paint = FieldDesc::Paint{"", "", PaintMode::Density, density};
    const auto field = makeField(layered, mesh, "", "test");
    SurfacePoint sp;
    for (int i = 0; i < 200; ++i) {
        sp.position = glm::vec3(std::sin(float(i)), std::cos(float(i) * 1.3f), 0.01f * float(i));
        ASSERT_EQ(field->eval(sp), base->eval(sp)) << i;
    }
    const glm::ivec3 v(3, -2, 5);
    density->set(v, glm::vec4(0.25f, 0.0f, 0.0f, 0.5f));
    sp.position = density->value().voxelPosition(v);
    const float b = base->eval(sp).x, bm = b * 0.25f;
    EXPECT_EQ(field->eval(sp), glm::vec3(bm + (1.0f - bm) * 0.5f, 0.0f, 0.0f));
    const FieldRange r = field->range();
    EXPECT_LE(r.lo.x, bm);
    EXPECT_GE(r.hi.x, 0.9f);

    FieldDesc color;
    color.kind = FieldDesc::Kind::Constant;
    color.components = 3;
    color.value = glm::vec3(0.2f, 0.4f, 0.6f);
    auto over = std::make_shared<PaintLayer>("color.paint", 3, 0.1f, PaintMode::Override);
    over->set(v, glm::vec4(1.0f, 0.0f, 0.5f, 0.25f));
    color.paint = FieldDesc::Paint{"", "", PaintMode::Override, over};
    const auto colorField = makeField(color, mesh, "", "test");
    EXPECT_EQ(colorField->eval(sp), glm::vec3(0.2f, 0.4f, 0.6f) * 0.75f +
                                        glm::vec3(1.0f, 0.0f, 0.5f) * 0.25f);

    // Through a file: the two grids, read back as the layer.
    const fs::path dir = tmpDir("layer");
    writePaintedGrids(dir / "p.vdb", {&over->value(), &over->weight()});
    FieldDesc fromFile = color;
    fromFile.paint = FieldDesc::Paint{"p.vdb", "color.paint", PaintMode::Override, nullptr};
    EXPECT_EQ(makeField(fromFile, mesh, dir, "test")->eval(sp), colorField->eval(sp));
    // A weight outside [0, 1] is refused.
    over->set(v, glm::vec4(1.0f, 0.0f, 0.5f, 1.5f));
    writePaintedGrids(dir / "bad.vdb", {&over->value(), &over->weight()});
    fromFile.paint->file = "bad.vdb";
    const std::string e = inputError([&] { makeField(fromFile, mesh, dir, "test fields.color"); });
    EXPECT_NE(e.find("outside [0, 1]"), std::string::npos) << e;
}

} // namespace
