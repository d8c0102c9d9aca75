// Shots as pure functions (render --tile, --crop, --frames; spotshell assemble): the tile split,
// the options' parsing, bad input refused with one line and nothing written, and tiles joined
// into exactly the whole image's bytes for the reference and GPU methods, in PNG and EXR.
#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <unistd.h>
#include <vector>

#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>

#include "cli_run.h"
#include "noise/error.h"
#include "tiles.h"

namespace {

namespace fs = std::filesystem;
using namespace spot;

/// A fresh folder of its own under the test tmp folder.
fs::path freshDir(const std::string& name) {
    const fs::path dir = fs::path(SPOT_TEST_TMP_DIR) / (name + "-" + std::to_string(::getpid()));
    fs::remove_all(dir);
    fs::create_directories(dir);
    return dir;
}

std::string bunny() {
    return std::string(SPOT_SOURCE_DIR) + "/presets/scenes/fur-bunny.json";
}

/// The pixels of `file` as stored (its own channel format, unconverted), and its size.
struct Stored {
    int width = 0, height = 0, channels = 0;
    std::string format;
    std::vector<std::uint8_t> bytes;
};
Stored stored(const fs::path& file) {
    Stored s;
    OIIO::ImageSpec config;
    config.attribute("oiio:UnassociatedAlpha", 1);
    auto in = OIIO::ImageInput::open(file.string(), &config);
    if (!in)
        throw std::runtime_error("cannot open " + file.string());
    const OIIO::ImageSpec& spec = in->spec();
    s.width = spec.width;
    s.height = spec.height;
    s.channels = spec.nchannels;
    s.format = spec.format.c_str();
    s.bytes.resize(spec.image_bytes(true));
    if (!in->read_image(0, 0, 0, spec.nchannels, spec.format, s.bytes.data()))
        throw std::runtime_error("cannot read " + file.string());
    return s;
}

/// The rows of tiles 0..N-1 cover [0, H) in order, without gap or overlap; heights differ by at
/// most one row; every tile is full width.
TEST(FarmTiles, BandsCoverTheImageExactly) {
    for (const int height : {1, 2, 7, 64, 480, 2160})
        for (const long count : {1L, 2L, 3L, 4L, 7L, 16L, 64L}) {
            if (count > height)
                continue;
            int next = 0, lo = height, hi = 0;
            for (long i = 0; i < count; ++i) {
                const noise::PixelRect r = cli::tileRect(i, count, 640, height);
                EXPECT_EQ(r.x0, 0);
                EXPECT_EQ(r.x1, 640);
                EXPECT_EQ(r.y0, next) << "tile " << i << " of " << count << ", height " << height;
                EXPECT_FALSE(r.empty()) << "tile " << i << " of " << count;
                lo = std::min(lo, r.height());
                hi = std::max(hi, r.height());
                next = r.y1;
            }
            EXPECT_EQ(next, height) << count << " tiles of " << height << " rows";
            EXPECT_LE(hi - lo, 1) << count << " tiles of " << height << " rows";
        }
    EXPECT_EQ(cli::tileRect(1, 4, 640, 480), (noise::PixelRect{0, 120, 640, 240}));
    EXPECT_EQ(cli::tileRect(2, 3, 10, 10), (noise::PixelRect{0, 6, 10, 10}));
}

TEST(FarmTiles, ParsesTileAndCrop) {
    EXPECT_EQ(cli::parseTile("3/4", 640, 480), (noise::PixelRect{0, 360, 640, 480}));
    EXPECT_EQ(cli::parseCrop("10,20,30,40", 640, 480), (noise::PixelRect{10, 20, 30, 40}));
    EXPECT_EQ(cli::parseCrop("0,0,640,480", 640, 480), (noise::PixelRect{0, 0, 640, 480}));
    for (const char* bad : {"4/4", "-1/4", "0/0", "1/481", "1", "1/", "/4", "1/4x", "a/b", "1-4"})
        EXPECT_THROW(cli::parseTile(bad, 640, 480), InputError) << bad;
    for (const char* bad : {"0,0,641,480", "0,0,640,481", "-1,0,10,10", "10,0,10,10", "10,10,5,20",
                            "1,2,3", "1,2,3,4,5", "1,2,3,4x", ""})
        EXPECT_THROW(cli::parseCrop(bad, 640, 480), InputError) << bad;
}

/// Bad input: exit 2, one line on stderr, nothing written in the output's folder.
TEST(FarmCli, RefusesBadInputWritingNothing) {
    const fs::path dir = freshDir("farm-bad");
    const std::string tail = std::string(SPOT_SOURCE_DIR) + "/examples/animated/tail-fur.json";
    const std::string base = "render --method instanced --size 64x48 --scene ";
    const std::vector<std::pair<std::string, std::string>> cases = {
        {bunny(), "--tile 4/4"},
        {bunny(), "--tile 0/49"},
        {bunny(), "--tile 1"},
        {bunny(), "--crop 0,0,65,48"},
        {bunny(), "--crop 10,10,10,20"},
        {bunny(), "--tile 0/2 --crop 0,0,8,8"},
        {bunny(), "--frames 5-3 --out '" + (dir / "f.%04d.png").string() + "'"},
        {bunny(), "--frames 0-3:0 --out '" + (dir / "f.%04d.png").string() + "'"},
        {bunny(), "--frames 0-3"}, // an output without a frame number
        {tail, "--frames 0-49 --out '" + (dir / "f.%04d.png").string() + "'"}, // the clip: 0-48
        {tail, "--frames -1-2 --out '" + (dir / "f.%04d.png").string() + "'"},
    };
    for (const auto& [scene, options] : cases) {
        const std::string out = options.find("--out") == std::string::npos
                                    ? " --out '" + (dir / "out.png").string() + "'"
                                    : "";
        const test::CliResult r = test::runSpotshell(base + scene + " " + options + out);
        EXPECT_EQ(r.code, 2) << options << "\n" << r.err;
        EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << options << "\n" << r.err;
        EXPECT_TRUE(fs::is_empty(dir)) << options << " wrote a file";
    }
    // The clip's last frame is in it; --time past the clip is clamped, not refused.
    EXPECT_EQ(test::runSpotshell(base + tail + " --frames 48-48 --out '" +
                                 (dir / "f.%04d.png").string() + "'")
                  .code,
              0);
    EXPECT_EQ(
        test::runSpotshell(base + tail + " --time 100 --out '" + (dir / "t.png").string() + "'")
            .code,
        0);
}

/// Frames are numbered from the clip's start, as Blender numbers them: the character's clip,
/// exported from frames 1 to 25 at 24 fps (from 1/24 s), is frames 1 to 25 for --frames, as
/// for `info` and the editor's timeline; 0 and 26 are outside it.
TEST(FarmCli, FramesCountFromTheClipsStart) {
    const fs::path dir = freshDir("farm-start");
    const std::string scene =
        std::string(SPOT_SOURCE_DIR) + "/examples/character/character-fur.json";
    const std::string base = "render --method instanced --unlit --size 16x16 --scene " + scene +
                             " --out '" + (dir / "f.%04d.png").string() + "' --frames ";
    for (const char* outside : {"0-0", "26-26", "0-25"}) {
        const test::CliResult r = test::runSpotshell(base + outside);
        EXPECT_EQ(r.code, 2) << outside << "\n" << r.err;
        EXPECT_NE(r.err.find("frames 1-25 at 24 fps"), std::string::npos) << r.err;
    }
    EXPECT_TRUE(fs::is_empty(dir));
    const test::CliResult r = test::runSpotshell(base + "1-25:24");
    EXPECT_EQ(r.code, 0) << r.err;
    EXPECT_TRUE(fs::exists(dir / "f.0001.png"));
    EXPECT_TRUE(fs::exists(dir / "f.0025.png"));
}

/// Without a clip, camera keys alone bound --frames to their span (0.5 s to 1 s at 24 fps: frames
/// 12 to 24); a turntable turns forever, so it bounds nothing.
TEST(FarmCli, CameraKeysBoundTheFrames) {
    const fs::path dir = freshDir("farm-keys");
    const std::string common = std::string(R"("version": 1, "name": "keys", "mesh": ")") +
                               SPOT_SOURCE_DIR + R"(/presets/meshes/bunny.ply", "preset": ")" +
                               SPOT_SOURCE_DIR +
                               R"(/presets/fur.json", "image": {"width": 32, "height": 24},)";
    const fs::path keys = dir / "keys.json", turntable = dir / "turntable.json";
    std::ofstream(keys)
        << "{" << common
        << R"("camera": {"eye": [1.1, 0.75, 2.3], "target": [0, 0.45, 0], "keys": [)"
           R"({"time": 0.5, "eye": [1.1, 0.75, 2.3], "target": [0, 0.45, 0]},)"
           R"({"time": 1.0, "eye": [-1.1, 0.75, 2.3], "target": [0, 0.45, 0]}]}})";
    std::ofstream(turntable) << "{" << common
                             << R"("camera": {"eye": [1.1, 0.75, 2.3], "target": [0, 0.45, 0],)"
                                R"("turntable_deg_per_s": 30}})";
    const auto render = [&](const fs::path& scene, const std::string& frames) {
        return test::runSpotshell("render --method instanced --scene '" + scene.string() +
                                      "' --frames " + frames + " --out '" +
                                      (dir / "f.%04d.png").string() + "'",
                                  "LP_NUM_THREADS=2");
    };
    for (const char* outside : {"11-24", "12-25", "0-3"}) {
        const test::CliResult r = render(keys, outside);
        EXPECT_EQ(r.code, 2) << outside << "\n" << r.err;
        EXPECT_NE(r.err.find("the camera keys: frames 12-24"), std::string::npos) << r.err;
    }
    EXPECT_FALSE(fs::exists(dir / "f.0012.png"));
    EXPECT_EQ(render(keys, "12-24:12").code, 0);
    EXPECT_TRUE(fs::exists(dir / "f.0012.png") && fs::exists(dir / "f.0024.png"));
    EXPECT_EQ(render(turntable, "500-500").code, 0);
}

/// render --tile I/N for every I, assembled in a shuffled order, holds the whole render's stored
/// pixels byte for byte; a --crop tile holds the same pixels as the whole image's rect.
void expectTilesAssembleToWhole(const std::string& method, const std::string& ext,
                                const std::string& scene = bunny()) {
    const fs::path dir = freshDir("farm-" + method + ext + fs::path(scene).stem().string());
    const std::string base = "render --scene " + scene + " --size 96x64 --method " + method +
                             (method == "reference" ? " --spp 2" : "") + " ";
    const std::string env = "LP_NUM_THREADS=2";
    const fs::path whole = dir / ("whole" + ext);
    test::CliResult r = test::runSpotshell(base + "--out '" + whole.string() + "'", env);
    ASSERT_EQ(r.code, 0) << r.err;
    const int n = 3;
    std::vector<std::string> tiles;
    for (int i = 0; i < n; ++i) {
        const fs::path tile = dir / ("tile" + std::to_string(i) + ext);
        r = test::runSpotshell(base + "--tile " + std::to_string(i) + "/" + std::to_string(n) +
                                   " --out '" + tile.string() + "'",
                               env);
        ASSERT_EQ(r.code, 0) << r.err;
        tiles.push_back("'" + tile.string() + "'");
    }
    const fs::path joined = dir / ("joined" + ext);
    r = test::runSpotshell("assemble " + tiles[2] + " " + tiles[0] + " " + tiles[1] + " --out '" +
                           joined.string() + "'");
    ASSERT_EQ(r.code, 0) << r.err;
    const Stored a = stored(whole), b = stored(joined);
    EXPECT_EQ(a.width, b.width);
    EXPECT_EQ(a.height, b.height);
    EXPECT_EQ(a.channels, b.channels);
    EXPECT_EQ(a.format, b.format);
    EXPECT_TRUE(a.bytes == b.bytes)
        << method << ext << ": the assembled tiles differ from the whole";

    // A crop: the rect's bytes of the whole image.
    const fs::path crop = dir / ("crop" + ext);
    r = test::runSpotshell(base + "--crop 17,9,61,40 --out '" + crop.string() + "'", env);
    ASSERT_EQ(r.code, 0) << r.err;
    const Stored c = stored(crop);
    ASSERT_EQ(c.width, 44);
    ASSERT_EQ(c.height, 31);
    const std::size_t px = a.bytes.size() / std::size_t(a.width * a.height);
    bool same = true;
    for (int y = 0; y < c.height; ++y)
        same &=
            std::equal(c.bytes.begin() + std::ptrdiff_t(std::size_t(y * c.width) * px),
                       c.bytes.begin() + std::ptrdiff_t(std::size_t((y + 1) * c.width) * px),
                       a.bytes.begin() + std::ptrdiff_t(std::size_t((y + 9) * a.width + 17) * px));
    EXPECT_TRUE(same) << method << ext << ": the crop differs from the whole image's pixels";
}

TEST(FarmCli, TilesAssembleToTheWholeImageReference) {
    expectTilesAssembleToWhole("reference", ".png");
    expectTilesAssembleToWhole("reference", ".exr");
}
TEST(FarmCli, TilesAssembleToTheWholeImageInstanced) {
    expectTilesAssembleToWhole("instanced", ".png");
    expectTilesAssembleToWhole("instanced", ".exr");
}
TEST(FarmCli, TilesAssembleToTheWholeImageSorted) {
    expectTilesAssembleToWhole("sorted", ".exr");
}
TEST(FarmCli, TilesAssembleToTheWholeImageRaymarch) {
    expectTilesAssembleToWhole("raymarch", ".exr");
}
TEST(FarmCli, TilesAssembleToTheWholeImageOit) {
    expectTilesAssembleToWhole("oit", ".png");
}
TEST(FarmCli, TilesAssembleToTheWholeImageHybrid) {
    expectTilesAssembleToWhole("hybrid", ".exr");
}
/// Lit: the light-space passes and the shadows, the same in every tile.
TEST(FarmCli, TilesAssembleToTheWholeImageLit) {
    const std::string lit = std::string(SPOT_SOURCE_DIR) + "/presets/scenes/fur-bunny.json";
    expectTilesAssembleToWhole("sorted", ".exr", lit);
    expectTilesAssembleToWhole("raymarch", ".exr", lit);
}

/// Missing, overlapping and mismatched tiles: exit 2, one line, no output.
TEST(FarmCli, AssembleRefusesBadTiles) {
    const fs::path dir = freshDir("farm-assemble-bad");
    const auto render = [&](const std::string& options, const std::string& file) {
        const test::CliResult r =
            test::runSpotshell("render --scene " + bunny() + " --method instanced " + options +
                                   " --out '" + (dir / file).string() + "'",
                               "LP_NUM_THREADS=2");
        ASSERT_EQ(r.code, 0) << r.err;
    };
    render("--size 64x48 --tile 0/2", "a0.png");
    render("--size 64x48 --tile 1/2", "a1.png");
    render("--size 64x48 --tile 1/3", "b1.png");
    render("--size 64x40 --tile 1/2", "c1.png");
    render("--size 64x48 --tile 1/2", "a1.exr");
    render("--size 64x48", "whole.png");
    const auto p = [&](const char* f) { return "'" + (dir / f).string() + "'"; };
    const std::vector<std::string> cases = {
        p("a0.png"),                                         // missing tile 1
        p("a0.png") + " " + p("b1.png"),                     // overlapping rows (and some missing)
        p("a0.png") + " " + p("a1.png") + " " + p("a1.png"), // the same tile twice
        p("a0.png") + " " + p("c1.png"),                     // tiles of different sizes
        p("a0.png") + " " + p("a1.exr"),                     // another format
        p("a0.png") + " " + p("whole.png"),                  // not a tile
        p("a0.png") + " " + p("nothere.png"),                // no such file
    };
    for (const std::string& tiles : cases) {
        const test::CliResult r =
            test::runSpotshell("assemble " + tiles + " --out " + p("out.png"));
        EXPECT_EQ(r.code, 2) << tiles << "\n" << r.err;
        EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
        EXPECT_FALSE(fs::exists(dir / "out.png")) << tiles;
    }
    EXPECT_EQ(
        test::runSpotshell("assemble " + p("a1.png") + " " + p("a0.png") + " --out " + p("out.png"))
            .code,
        0);
}

} // namespace
