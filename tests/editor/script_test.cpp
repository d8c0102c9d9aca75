// Editor scripts: the parser names the bad line; `spotshell edit` fails with exit 2 before it
// writes anything, on a malformed script and on a corrupt or mismatched .vdb; a good script runs
// and writes its files.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>

#include <gtest/gtest.h>

#include "edit_test_support.h"
#include "editor/edit_script.h"
#include "noise/error.h"
#include "noise/image.h"
#include "splat/image_compare.h"

namespace {

using namespace spot;
namespace fs = std::filesystem;

std::string parseError(const std::string& text) {
    try {
        edit::parseScript(text, "t.script");
    } catch (const InputError& e) {
        return e.what();
    }
    return "";
}

TEST(EditScript, ParsesEveryAction) {
    const auto actions = edit::parseScript(
        "# a comment\n"
        "camera eye 1 0.7 2.3 target 0 0.45 0 fov 30\n"
        "method raymarch steps 16 supersample 2\n"
        "method hybrid\n"
        "brush comb radius 25 strength 0.5 falloff linear mirror x\n"
        "brush color color 1 0 0   # red\n"
        "stroke 10,20 30,40.5\n"
        "\n"
        "undo\nredo\n"
        "lobe 1 offset 0 0 1\nlobe 0 sigma 0.1 0.1 0.3\nlobe 2 extinction 500\nlobe 0 color 1 1 1\n"
        "lobe add 0\nlobe remove 3\n"
        "set distribution.density_max 4000\nset fields.tilt_deg "
        "{\"type\":\"constant\",\"value\":20}\n"
        "frames 3\nsave out.json\nscreenshot out.png\n",
        "t.script");
    ASSERT_EQ(actions.size(), 19u);
    using T = edit::ScriptAction::Type;
    EXPECT_EQ(actions[0].type, T::Camera);
    EXPECT_EQ(actions[0].line, 2);
    EXPECT_EQ(*actions[0].fovDeg, 30.0);
    EXPECT_EQ(actions[1].settings.steps, 16);
    EXPECT_EQ(actions[1].settings.supersample, 2);
    EXPECT_EQ(actions[3].brush.kind, edit::BrushKind::Comb);
    EXPECT_TRUE(actions[3].brush.mirrorX);
    EXPECT_EQ(actions[3].brush.falloff, edit::Falloff::Linear);
    EXPECT_EQ(actions[4].brush.color, glm::vec3(1.0f, 0.0f, 0.0f));
    EXPECT_EQ(actions[5].points.size(), 2u);
    EXPECT_EQ(actions[5].points[1], glm::vec2(30.0f, 40.5f));
    EXPECT_EQ(actions[5].line, 7);
    EXPECT_EQ(actions[8].name, "offset");
    EXPECT_EQ(actions[13].name, "remove");
    EXPECT_EQ(actions[15].value["value"], 20);
    EXPECT_EQ(actions[16].count, 3);
}

TEST(EditScript, BadLinesNameTheirLine) {
    EXPECT_EQ(parseError("frames 2\nbrush fluff\n").rfind("script t.script:2: unknown brush", 0),
              0u)
        << parseError("frames 2\nbrush fluff\n");
    EXPECT_NE(parseError("\n\nstroke 10;20\n").find("t.script:3:"), std::string::npos);
    EXPECT_NE(parseError("method warp\n").find("t.script:1: unknown method"), std::string::npos);
    EXPECT_NE(parseError("method raymarch steps 0\n").find("t.script:1:"), std::string::npos);
    EXPECT_NE(parseError("method hybrid steps 64\n")
                  .find("t.script:1: steps is a setting of raymarch, not of hybrid"),
              std::string::npos)
        << parseError("method hybrid steps 64\n");
    EXPECT_NE(parseError("frames many\n").find("t.script:1: frame count"), std::string::npos);
    EXPECT_NE(parseError("frames 2 3\n").find("unexpected '3'"), std::string::npos);
    EXPECT_NE(parseError("lobe 9 sigma 1 1 1\n").find("t.script:1:"), std::string::npos);
    EXPECT_NE(parseError("set a..b 1\n").find("t.script:1:"), std::string::npos);
    EXPECT_NE(parseError("set a.b {oops\n").find("not JSON"), std::string::npos);
    EXPECT_NE(parseError("screenshot x.tiff\n").find("must end in .png, .exr"), std::string::npos);
    EXPECT_NE(parseError("brush comb strength 2\n").find("outside [-1, 1]"), std::string::npos);
    EXPECT_NE(parseError("jump\n").find("unknown action 'jump'"), std::string::npos);
    // The line itself too, as written (comments and outer blanks dropped).
    EXPECT_NE(parseError("frames 2\n  brush   fluff  # soft\n").find("(the line: brush   fluff)"),
              std::string::npos)
        << parseError("frames 2\n  brush   fluff  # soft\n");
}

// A `method` line changes only the settings it gives: the command line's others stay (`method
// baked` keeps --bake), and the image is `render`'s with those settings. An error while the
// script runs names the line that caused it, with its text: a method whose settings are refused
// (baked without a bake) on its own line, not on the next that renders; a key of a `set` line
// that the preset does not have, without blaming the preset's file. The log prints long lines
// whole.
TEST(EditScript, MethodKeepsTheCommandLineAndErrorsNameTheLine) {
    const fs::path dir = test::tmpPath("edit_method_line");
    fs::remove_all(dir);
    fs::create_directories(dir);
    const fs::path bake = dir / "bunny.vdb";
    std::string err;
    ASSERT_EQ(test::spotshell("bake --scene " + test::bunnyScene().string() +
                                  " --resolution 48 --out " + bake.string(),
                              &err),
              0)
        << err;
    // The scene's own camera: the image is the scene's.
    const std::string longLine = "camera eye 1.1 0.75 2.3 target 0.0 0.45 0.0 fov 30";
    const fs::path script = dir / "method.script";
    test::writeText(script, "method hybrid\n" + longLine + "\nmethod baked peel-passes 2\n" +
                                "screenshot " + (dir / "edited.exr").string() + "\n");
    const test::CliResult e = test::runSpotshell("edit --scene " + test::bunnyScene().string() +
                                                 " --size 96x96 --method baked --bake " +
                                                 bake.string() + " --script " + script.string());
    ASSERT_EQ(e.code, 0) << e.err;
    EXPECT_NE(e.out.find("   2  " + longLine + " "), std::string::npos) << e.out;

    // The same bake and settings with `render`.
    ASSERT_EQ(test::spotshell("render --scene " + test::bunnyScene().string() +
                                  " --size 96x96 --method baked --bake " + bake.string() +
                                  " --peel-passes 2 --out " + (dir / "rendered.exr").string(),
                              &err),
              0)
        << err;
    EXPECT_GT(
        splat::psnr(noise::readImage(dir / "rendered.exr"), noise::readImage(dir / "edited.exr")),
        60.0);

    // Baked without a bake: line 2 is to blame, not line 3 (the first that renders after it).
    const fs::path noBake = dir / "nobake.script";
    test::writeText(noBake, "method hybrid\nmethod baked\nframes 1\n");
    EXPECT_EQ(test::spotshell("edit --scene " + test::bunnyScene().string() +
                                  " --size 64x64 --script " + noBake.string(),
                              &err),
              2);
    EXPECT_NE(err.find("nobake.script:2: "), std::string::npos) << err;
    EXPECT_NE(err.find("(the line: method baked)"), std::string::npos) << err;
    EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;

    const fs::path typo = dir / "typo.script";
    test::writeText(typo, "frames 1\nset distribution.densty_max 4000\n");
    EXPECT_EQ(test::spotshell("edit --scene " + test::bunnyScene().string() +
                                  " --size 64x64 --script " + typo.string(),
                              &err),
              2);
    EXPECT_NE(err.find("typo.script:2: set distribution.densty_max: unknown key"),
              std::string::npos)
        << err;
    EXPECT_NE(err.find("(the line: set distribution.densty_max 4000)"), std::string::npos) << err;
    EXPECT_EQ(err.find("fur.json"), std::string::npos) << "blames the preset's file: " << err;
}

// A malformed script fails with its line and exit 2 before anything is written, even the files
// of the good lines before it.
TEST(EditScript, MalformedScriptWritesNothing) {
    const fs::path dir = test::tmpPath("edit_malformed");
    fs::remove_all(dir);
    fs::create_directories(dir);
    const fs::path script = dir / "bad.script";
    test::writeText(script, "save " + (dir / "p.json").string() + "\nscreenshot " +
                                (dir / "a.png").string() + "\nbrush comb radius -3\n");
    std::string err;
    EXPECT_EQ(test::spotshell("edit --scene " + test::bunnyScene().string() + " --script " +
                                  script.string() + " --screenshot " + (dir / "b.png").string(),
                              &err),
              2);
    EXPECT_NE(err.find("bad.script:3: radius"), std::string::npos) << err;
    EXPECT_FALSE(fs::exists(dir / "p.json"));
    EXPECT_FALSE(fs::exists(dir / "a.png"));
    EXPECT_FALSE(fs::exists(dir / "b.png"));
}

// A script that paints, edits, undoes and saves; the saved preset renders with `spotshell render`
// and a corrupt .vdb, a grid of the wrong name and one of the wrong type fail with exit 2.
TEST(EditScript, RunsAndSavesAndRejectsBadGrids) {
    const fs::path dir = test::tmpPath("edit_run");
    fs::remove_all(dir);
    fs::create_directories(dir);
    const fs::path script = dir / "good.script";
    const fs::path saved = dir / "painted.json";
    test::writeText(script, "method hybrid\n"
                            "brush density-erase radius 20 strength 1 falloff constant\n"
                            "stroke 110,110 150,130\n"
                            "brush comb radius 25 mirror x\n"
                            "stroke 100,150 160,140\n"
                            "brush tilt strength 0.5\nstroke 90,130 170,130\nundo\nredo\n"
                            "lobe 0 color 0.9 0.1 0.1\n"
                            "set distribution.density_max 6000\n"
                            "seed 4\nwind on amplitude 25\n"
                            "frames 2\n"
                            "save " +
                                saved.string() +
                                "\n"
                                "screenshot " +
                                (dir / "shot.png").string() + "\n");
    std::string err;
    ASSERT_EQ(test::spotshell("edit --scene " + test::bunnyScene().string() + " --size 256x256 " +
                                  "--script " + script.string() + " --screenshot " +
                                  (dir / "end.exr").string(),
                              &err),
              0)
        << err;
    EXPECT_TRUE(fs::exists(saved));
    EXPECT_TRUE(fs::exists(dir / "painted.vdb"));
    EXPECT_TRUE(fs::exists(dir / "shot.png"));
    EXPECT_TRUE(fs::exists(dir / "end.exr"));
    EXPECT_EQ(test::spotshell("render --scene " + test::bunnyScene().string() + " --preset " +
                                  saved.string() + " --method hybrid --size 64x64 --out " +
                                  (dir / "render.png").string(),
                              &err),
              0)
        << err;

    const std::string text = [&] {
        std::ifstream in(saved);
        return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
    }();
    auto variant = [&](const std::string& name, const std::string& from, const std::string& to) {
        std::string t = text;
        const std::size_t at = t.find(from);
        EXPECT_NE(at, std::string::npos) << from;
        if (at != std::string::npos)
            t.replace(at, from.size(), to);
        const fs::path file = dir / name;
        test::writeText(file, t);
        return file;
    };
    const fs::path empty = dir / "empty.script";
    test::writeText(empty, "frames 1\n");
    auto expectFails = [&](const fs::path& preset, const std::string& message) {
        std::string e;
        EXPECT_EQ(test::spotshell("edit --scene " + test::bunnyScene().string() + " --preset " +
                                      preset.string() + " --script " + empty.string(),
                                  &e),
                  2)
            << e;
        EXPECT_NE(e.find(message), std::string::npos) << e;
        EXPECT_EQ(e.find('\n'), e.size() - 1) << "one line: " << e;
        EXPECT_EQ(test::spotshell("render --scene " + test::bunnyScene().string() + " --preset " +
                                      preset.string() + " --method hybrid --size 32x32 --out " +
                                      (dir / "never.png").string(),
                                  &e),
                  2)
            << e;
        EXPECT_FALSE(fs::exists(dir / "never.png"));
    };
    test::writeText(dir / "corrupt.vdb", "this is not a vdb file at all");
    expectFails(variant("corrupt.json", "painted.vdb", "corrupt.vdb"), "corrupt.vdb");
    // The paint layers' grids are named "<slot>.paint" (and "<slot>.paint.weight").
    expectFails(variant("wrongname.json", "\"grid\": \"density.paint\"",
                        "\"grid\": \"nothing\""),
                "nothing");
    // The density's value grid (scalar) where the comb's (3 components) is expected.
    expectFails(variant("wrongtype.json", "\"grid\": \"comb.paint\"",
                        "\"grid\": \"density.paint\""),
                "density");
}

TEST(EditScript, LightTurnsTheSessionLitAndMovesTheKeyLight) {
    const fs::path dir = test::tmpPath("edit_light");
    fs::remove_all(dir);
    fs::create_directories(dir);
    const fs::path script = dir / "light.script";
    // fur-bunny is lit: the script turns its lights off first.
    test::writeText(script, "method hybrid\n"
                            "light off\n"
                            "screenshot " + (dir / "unlit.exr").string() + "\n"
                            "light on azimuth -60 elevation 45 intensity 3 shadows on\n"
                            "screenshot " + (dir / "shadowed.exr").string() + "\n"
                            "light on shadows off\n"
                            "screenshot " + (dir / "open.exr").string() + "\n"
                            "light on azimuth 120\n"
                            "screenshot " + (dir / "moved.exr").string() + "\n"
                            "light off\n"
                            "screenshot " + (dir / "off.exr").string() + "\n");
    std::string err;
    ASSERT_EQ(test::spotshell("edit --scene " + test::bunnyScene().string() +
                                  " --size 64x64 --script " + script.string(),
                              &err),
              0)
        << err;
    const auto mean = [&](const char* name) {
        const noise::Image image = noise::readImage(dir / name);
        double sum = 0.0;
        for (const glm::vec3& p : image.pixels) {
            EXPECT_TRUE(std::isfinite(p.r + p.g + p.b)) << name;
            sum += p.r + p.g + p.b;
        }
        return sum / double(image.pixels.size());
    };
    const double shadowed = mean("shadowed.exr"), open = mean("open.exr");
    std::printf("mean unlit %.4f, lit %.4f, lit without shadows %.4f, light moved %.4f, off %.4f\n",
                mean("unlit.exr"), shadowed, open, mean("moved.exr"), mean("off.exr"));
    EXPECT_LT(shadowed, 0.8 * open); // its shadows take light away
    EXPECT_GT(shadowed, 0.0);
    // Moving the light changes the picture; turning it off gives the unlit one back.
    EXPECT_GT(splat::psnr(noise::readImage(dir / "open.exr"), noise::readImage(dir / "moved.exr")),
              0.0);
    EXPECT_LT(splat::psnr(noise::readImage(dir / "open.exr"), noise::readImage(dir / "moved.exr")),
              40.0);
    EXPECT_EQ(noise::readImage(dir / "unlit.exr").pixels, noise::readImage(dir / "off.exr").pixels);
    // Bad lines name their line.
    EXPECT_THROW(edit::parseScript("light bright\n", "s"), InputError);
    EXPECT_THROW(edit::parseScript("light on elevation 120\n", "s"), InputError);
    EXPECT_THROW(edit::parseScript("light off intensity 2\n", "s"), InputError);
    EXPECT_THROW(edit::parseScript("light on shadows maybe\n", "s"), InputError);
}

} // namespace

// The window's options without --window: one line, exit 2, nothing run.
TEST(EditScript, WindowOptionsNeedTheWindow) {
    const fs::path script = test::tmpPath("edit_window_options.script");
    test::writeText(script, "frames 1\n");
    for (const std::string option :
         {"--frames 3", "--orbit 5", "--resize 100x100", "--cycle-methods",
          "--window-screenshot w.png", "--render-scale 2", "--refine 4", "--panels all"}) {
        std::string err;
        EXPECT_EQ(test::spotshell("edit --scene " + test::bunnyScene().string() + " --script " +
                                      script.string() + " " + option,
                                  &err),
                  2)
            << option;
        const std::string name = option.substr(0, option.find(' '));
        EXPECT_NE(err.find(name + " needs the window"), std::string::npos) << err;
        EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;
    }
}

// A stroke to a point 1e9 pixels away ends (clipped to the window) and the script goes on.
TEST(EditScript, StrokeFarOutsideTheWindowEnds) {
    const fs::path script = test::tmpPath("edit_far_stroke.script");
    test::writeText(script, "brush density-erase radius 10\nstroke 64,64 1000000000,64\n"
                            "stroke 1000000000,1000000000 -1000000000,64\nframes 1\n");
    std::string err;
    EXPECT_EQ(test::spotshell("edit --scene " + test::bunnyScene().string() +
                                  " --size 128x128 --script " + script.string(),
                              &err),
              0)
        << err;
}
