// The bench's bakes (editor/bench_bake.h): the cache key changes with everything that determines
// a bake, and a bake is made once, then found in the cache.
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <unistd.h>

#include <gtest/gtest.h>

#include "bench_bake.h"
#include "noise/error.h"
#include "noise/impulses.h"
#include "noise/mesh.h"
#include "noise/preset.h"
#include "noise/system.h"

namespace {

namespace fs = std::filesystem;
using namespace spot;

cmd::BenchBakeInputs inputs() {
    cmd::BenchBakeInputs in;
    in.mesh = "generated:sphere";
    in.preset = R"({"name": "fur"})";
    in.seed = 1;
    in.voxelSize = 0.01f;
    in.levels = 4;
    return in;
}

TEST(BenchBake, KeyChangesWithEveryInput) {
    const std::string key = cmd::benchBakeKey(inputs());
    EXPECT_EQ(key.size(), 16u);
    EXPECT_EQ(key.find_first_not_of("0123456789abcdef"), std::string::npos) << key;
    EXPECT_EQ(cmd::benchBakeKey(inputs()), key); // deterministic

    auto changed = [&](auto&& change) {
        cmd::BenchBakeInputs in = inputs();
        change(in);
        return cmd::benchBakeKey(in);
    };
    EXPECT_NE(changed([](auto& in) { in.voxelSize = std::nextafter(in.voxelSize, 1.0f); }), key);
    EXPECT_NE(changed([](auto& in) { in.voxelSize *= 2.0f; }), key);
    EXPECT_NE(changed([](auto& in) { in.levels = 1; }), key);
    EXPECT_NE(changed([](auto& in) { in.levels = 5; }), key);
    EXPECT_NE(changed([](auto& in) { in.seed = 2; }), key);
    EXPECT_NE(changed([](auto& in) { in.mesh = "generated:torus"; }), key);
    EXPECT_NE(changed([](auto& in) { in.preset = R"({"name": "fur2"})"; }), key);
    // Text moved from one field to the next is another input, not the same text.
    EXPECT_NE(changed([](auto& in) {
                  in.mesh += in.preset.substr(0, 1);
                  in.preset = in.preset.substr(1);
              }),
              key);
}

TEST(BenchBake, VoxelSizeForResolutionDividesTheLongestSide) {
    const noise::Mesh sphere = noise::loadMeshOrGenerated("generated:sphere");
    const double side = cmd::meshLongestSide(sphere);
    EXPECT_NEAR(side, 2.0, 0.01);
    EXPECT_FLOAT_EQ(cmd::voxelSizeForResolution(sphere, 128), float(side / 128.0));
    EXPECT_THROW(cmd::voxelSizeForResolution(noise::Mesh{}, 128), InputError);
    EXPECT_THROW(cmd::voxelSizeForResolution(sphere, 0), InputError);
}

TEST(BenchBake, BakedOnceThenFoundInTheCache) {
    const fs::path dir = fs::path(SPOT_TEST_TMP_DIR) / ("bench-bake-" + std::to_string(::getpid()));
    fs::remove_all(dir);
    fs::create_directories(dir);
    const noise::Mesh mesh = noise::loadMeshOrGenerated("generated:sphere");
    const fs::path presetFile = fs::path(SPOT_SOURCE_DIR) / "presets" / "fur.json";
    const noise::PresetDesc preset = noise::loadPreset(presetFile);
    noise::GeneratorOptions options;
    options.seed = 1;
    const noise::ImpulseGenerator generator(mesh, preset, options);

    cmd::BenchBakeInputs in;
    in.mesh = "generated:sphere";
    in.preset = readFileCapped(presetFile, 1 << 20);
    in.seed = 1;
    in.voxelSize = cmd::voxelSizeForResolution(mesh, 48); // coarse: a fraction of a second
    in.levels = 2;

    const cmd::BenchBake first = cmd::benchBake(dir, generator, in, preset.name);
    EXPECT_FALSE(first.cached);
    ASSERT_TRUE(fs::exists(first.file));
    EXPECT_GT(first.bytes, 0u);
    EXPECT_EQ(first.bytes, fs::file_size(first.file));
    EXPECT_TRUE(std::isfinite(first.seconds) && first.seconds > 0.0);
    EXPECT_NE(first.file.filename().string().find(cmd::benchBakeKey(in)), std::string::npos);

    const cmd::BenchBake again = cmd::benchBake(dir, generator, in, preset.name);
    EXPECT_TRUE(again.cached);
    EXPECT_EQ(again.file, first.file);
    EXPECT_EQ(again.bytes, first.bytes);
    EXPECT_EQ(again.seconds, first.seconds); // the bake's own time, recorded beside it

    // Another level count is another bake, in another file.
    cmd::BenchBakeInputs one = in;
    one.levels = 1;
    const cmd::BenchBake other = cmd::benchBake(dir, generator, one, preset.name);
    EXPECT_FALSE(other.cached);
    EXPECT_NE(other.file, first.file);
    EXPECT_LT(other.bytes, first.bytes);

    // A bake whose record is damaged is made again.
    fs::path record = first.file;
    record.replace_extension(".json");
    ASSERT_TRUE(fs::exists(record));
    std::ofstream(record) << "{ not json";
    EXPECT_FALSE(cmd::benchBake(dir, generator, in, preset.name).cached);
    EXPECT_TRUE(cmd::benchBake(dir, generator, in, preset.name).cached);
    fs::remove_all(dir);
}

} // namespace
