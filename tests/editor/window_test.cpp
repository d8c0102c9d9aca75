// The editor's window (`spotshell edit`) as a user runs it, under a virtual display (xvfb-run):
// validation on, the scene it shows identical to `spotshell render`'s, the panels drawn over it,
// every registry method and a resize in one scripted run, and one clear error without a display;
// the real window driven by X events (xdotool) ends on the script's images. Also the navigation's
// camera math (edit_view.h), which needs no window.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <numbers>
#include <sstream>
#include <string>
#include <sys/wait.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include "cli_run.h"
#include "edit_quit.h"
#include "edit_view.h"
#include "editor/spin_clip.h"
#include "noise/camera.h"
#include "noise/image.h"
#include "noise/mesh.h"
#include "noise/scene.h"
#include "splat/context_vk.h"
#include "splat/image_compare.h"

namespace {

using spot::editor::OrbitView;

using Result = spot::test::CliResult;

std::string tmp(const std::string& name) {
    // Per process: ctest runs these tests in parallel processes.
    return std::string(SPOT_TEST_TMP_DIR) + "/window-" + std::to_string(::getpid()) + "-" + name;
}

/// `prefix` goes before the command (environment changes, xvfb-run).
Result run(const std::string& prefix, const std::string& args) {
    return spot::test::runSpotshell(args, prefix);
}

/// Validation on: any error fails the command (exit 1) and is printed.
const std::string kXvfb = "SPOT_VALIDATION=1 xvfb-run -a -s '-screen 0 1024x768x24'";

std::string scene() {
    return std::string(SPOT_SOURCE_DIR) + "/presets/scenes/fur-bunny.json";
}

/// Fraction of pixels whose display values (8-bit sRGB) differ by more than `tolerance` levels
/// in some channel.
double fractionDiffering(const spot::noise::Image& a, const spot::noise::Image& b, int tolerance) {
    std::size_t differing = 0;
    for (std::size_t i = 0; i < a.pixels.size(); ++i)
        for (int c = 0; c < 3; ++c) {
            const long da = std::lround(
                spot::noise::srgbEncode(std::clamp(a.pixels[i][c], 0.0f, 1.0f)) * 255.0f);
            const long db = std::lround(
                spot::noise::srgbEncode(std::clamp(b.pixels[i][c], 0.0f, 1.0f)) * 255.0f);
            if (std::abs(da - db) > tolerance) {
                ++differing;
                break;
            }
        }
    return double(differing) / double(std::max<std::size_t>(a.pixels.size(), 1));
}

/// The largest difference between two 8-bit images in display levels (0-255), or -1 when their
/// sizes differ.
int maxLevelDifference(const spot::noise::Image& a, const spot::noise::Image& b) {
    if (a.width != b.width || a.height != b.height)
        return -1;
    int most = 0;
    for (std::size_t i = 0; i < a.pixels.size(); ++i)
        for (int c = 0; c < 3; ++c) {
            const long da = std::lround(
                spot::noise::srgbEncode(std::clamp(a.pixels[i][c], 0.0f, 1.0f)) * 255.0f);
            const long db = std::lround(
                spot::noise::srgbEncode(std::clamp(b.pixels[i][c], 0.0f, 1.0f)) * 255.0f);
            most = std::max(most, int(std::abs(da - db)));
        }
    return most;
}

TEST(EditWindow, ShowsWhatRenderRenders) {
    // EXR: a PNG's straight colour clamps the lit bunny's bright edges (highlights above 1 at
    // partial coverage), where the window, which clamps once after compositing, does not.
    const std::string shot = tmp("edit.exr"), window = tmp("window.png"), ref = tmp("render.exr");
    const Result e =
        run(kXvfb, "edit --scene " + scene() + " --size 320x240 --frames 3 --screenshot " + shot +
                       " --window-screenshot " + window);
    ASSERT_EQ(e.code, 0) << e.err;
    EXPECT_EQ(e.err.find("validation error"), std::string::npos) << e.err;
    EXPECT_NE(e.out.find("edit: 3 frames"), std::string::npos) << e.out;
    EXPECT_NE(e.out.find("validation on: no errors"), std::string::npos) << e.out;
    const Result r = run("SPOT_VALIDATION=1",
                         "render --scene " + scene() + " --size 320x240 --out " +
                             ref); // both: --quality balanced
    ASSERT_EQ(r.code, 0) << r.err;

    const spot::noise::Image edited = spot::noise::readImage(shot);
    const spot::noise::Image rendered = spot::noise::readImage(ref);
    ASSERT_EQ(edited.width, 320);
    ASSERT_EQ(edited.height, 240);
    // The same renderer, view and size: the same pixels (PSNR +inf when identical).
    const double psnr = spot::splat::psnr(rendered, edited);
    EXPECT_GT(psnr, 60.0);
    // Fur, not an empty frame: most pixels away from the background colour (the scene's
    // [0.02, 0.02, 0.03]) where the bunny is, about a third of the frame.
    const spot::noise::Image background(320, 240, glm::vec3(0.02f, 0.02f, 0.03f));
    const double covered = fractionDiffering(background, edited, 4);
    EXPECT_GT(covered, 0.25) << "the bunny covers too little of the screenshot";
    EXPECT_LT(covered, 0.9);

    // The window as shown: the scene alone, sRGB-encoded by the blit (a window narrower than
    // 560 pixels starts with the panels' column hidden; nothing is drawn over the scene).
    const spot::noise::Image shown = spot::noise::readImage(window);
    ASSERT_EQ(shown.width, 320);
    ASSERT_EQ(shown.height, 240);
    EXPECT_EQ(fractionDiffering(edited, shown, 1), 0.0) << "something drawn over the scene";
    EXPECT_NE(e.out.find("in a 320x240 viewport (the panels hidden)"), std::string::npos) << e.out;
}

/// The size after `prefix` in `text` ("WxH"), or (0, 0).
glm::ivec2 sizeAfter(const std::string& text, const std::string& prefix) {
    const std::size_t at = text.find(prefix);
    glm::ivec2 size(0);
    if (at != std::string::npos)
        std::sscanf(text.c_str() + at + prefix.size(), "%dx%d", &size.x, &size.y);
    return size;
}

/// A virtual screen larger than any window here, so that its pointer (at the screen's centre)
/// is outside the window and the brush circle is not drawn over the scene.
const std::string kXvfbLarge = "SPOT_VALIDATION=1 xvfb-run -a -s '-screen 0 3000x2000x24'";

// The editor's layout: with every panel unfolded, at 800x600 and at the default size (1280x720),
// the panels sit in a column right of the viewport and cover none of it. The window as shown
// equals, over the viewport, the scene alone (--screenshot), which is `render`'s image at the
// viewport's size (the camera's aspect follows the viewport); the column right of it shows the
// panels. Shown here: tests/tmp/window-*-layout-*.png.
TEST(EditWindowLayout, NoPanelCoversTheViewport) {
    for (const std::string size : {"800x600", "1280x720"}) {
        SCOPED_TRACE(size);
        const std::string shot = tmp("layout-scene-" + size + ".png"),
                          window = tmp("layout-window-" + size + ".png"),
                          ref = tmp("layout-render-" + size + ".png");
        // 1280x720 is the window's size without --size.
        const std::string sizeOption = size == "1280x720" ? "" : " --size " + size;
        const Result e =
            run(kXvfbLarge, "edit --scene " + scene() + sizeOption +
                                " --method instanced --frames 2 --panels all --screenshot " + shot +
                                " --window-screenshot " + window);
        ASSERT_EQ(e.code, 0) << e.err;
        EXPECT_EQ(e.err.find("validation error"), std::string::npos) << e.err;
        const glm::ivec2 windowSize = sizeAfter(e.out, "edit: a ");
        const glm::ivec2 viewport = sizeAfter(e.out, "the scene in a ");
        EXPECT_EQ(std::to_string(windowSize.x) + "x" + std::to_string(windowSize.y), size);
        // The column takes 300 to 400 pixels at the right; the viewport is the rest.
        EXPECT_GE(windowSize.x - viewport.x, 300) << e.out;
        EXPECT_LE(windowSize.x - viewport.x, 400) << e.out;
        EXPECT_EQ(viewport.y, windowSize.y) << e.out;

        const spot::noise::Image edited = spot::noise::readImage(shot);
        const spot::noise::Image shown = spot::noise::readImage(window);
        ASSERT_EQ(edited.width, viewport.x);
        ASSERT_EQ(edited.height, viewport.y);
        ASSERT_EQ(shown.width, windowSize.x);
        ASSERT_EQ(shown.height, windowSize.y);
        // Over the viewport, the window shows the scene and nothing else: to the 8-bit level
        // (the blit's sRGB encoding against the PNG writer's), pixel by pixel.
        spot::noise::Image left(viewport.x, viewport.y),
            right(windowSize.x - viewport.x, windowSize.y);
        for (int y = 0; y < shown.height; ++y)
            for (int x = 0; x < shown.width; ++x) {
                const glm::vec3 c =
                    shown.pixels[std::size_t(y) * std::size_t(shown.width) + std::size_t(x)];
                if (x < viewport.x)
                    left.pixels[std::size_t(y) * std::size_t(viewport.x) + std::size_t(x)] = c;
                else
                    right.pixels[std::size_t(y) * std::size_t(right.width) +
                                 std::size_t(x - viewport.x)] = c;
            }
        EXPECT_LE(maxLevelDifference(left, edited), 1) << "something covers the viewport";
        // The column is not the scene's background: the panels are drawn there (text, widgets).
        const spot::noise::Image background(right.width, right.height,
                                            glm::vec3(0.02f, 0.02f, 0.03f));
        EXPECT_GT(fractionDiffering(background, right, 8), 0.5) << "no column of panels";
        // The scene is `render`'s at the viewport's size: the same camera, its aspect the
        // viewport's.
        const Result r =
            run("", "render --scene " + scene() + " --size " + std::to_string(viewport.x) + "x" +
                        std::to_string(viewport.y) + " --method instanced --out " + ref);
        ASSERT_EQ(r.code, 0) << r.err;
        EXPECT_GT(spot::splat::psnr(spot::noise::readImage(ref), edited), 60.0);
    }
}

TEST(EditWindowLayout, ColumnAndViewportFillTheWindow) {
    using spot::editor::windowLayout;
    for (int w : {1, 150, 320, 359, 360, 559, 560, 800, 1000, 1280, 1920, 4000})
        for (bool column : {false, true}) {
            const spot::editor::WindowLayout l = windowLayout(w, 600, column);
            EXPECT_EQ(l.viewportWidth + l.columnWidth, w) << w;
            EXPECT_EQ(l.viewportHeight(), 600);
            EXPECT_GE(l.viewportWidth, std::min(w, 160)) << w;
            if (!column)
                EXPECT_FALSE(l.columnShown());
            if (l.columnShown()) {
                EXPECT_GE(l.columnWidth, 200) << w;
                EXPECT_LE(l.columnWidth, 400) << w;
                // The column's pixels are not the viewport's.
                EXPECT_FALSE(l.inViewport(l.viewportWidth, 10.0)) << w;
                EXPECT_TRUE(l.inViewport(l.viewportWidth - 0.5, 10.0)) << w;
            }
        }
    EXPECT_EQ(windowLayout(800, 600, true).columnWidth, 300);
    EXPECT_EQ(windowLayout(1280, 720, true).columnWidth, 384);
    EXPECT_EQ(windowLayout(1920, 1080, true).columnWidth, 400);
}

TEST(EditWindow, EveryMethodAndAResize) {
    const std::string shot = tmp("cycle.png");
    // Two frames per method, in registry order; the window is resized after the first frame.
    const Result e =
        run(kXvfb, "edit --scene " + scene() +
                       " --size 240x180 --frames 10 "
                       "--cycle-methods --resize 300x200 --steps 8 --window-screenshot " +
                       shot);
    ASSERT_EQ(e.code, 0) << e.err;
    EXPECT_EQ(e.err.find("validation error"), std::string::npos) << e.err;
    // Not even a warning from the window's own work (the scene's readback for --screenshot, in
    // splat::Frame, reads the general layout: a performance warning, hence not checked there).
    EXPECT_NE(e.out.find("validation on: no errors, 0 warnings"), std::string::npos) << e.out;
    EXPECT_NE(e.out.find("(10 rendered)"), std::string::npos) << e.out;
    const spot::noise::Image last = spot::noise::readImage(shot);
    EXPECT_EQ(last.width, 300);
    EXPECT_EQ(last.height, 200);
}

TEST(EditWindow, RendersAtAQuarterOfThePixelsAndScalesUp) {
    const std::string shot = tmp("half.png"), window = tmp("half-window.png");
    const Result e = run(kXvfb, "edit --scene " + scene() +
                                    " --size 320x240 --frames 2 "
                                    "--render-scale 2 --screenshot " +
                                    shot + " --window-screenshot " + window);
    ASSERT_EQ(e.code, 0) << e.err;
    EXPECT_EQ(e.err.find("validation error"), std::string::npos) << e.err;
    // The window showed the scene rendered at 160x120; --screenshot is the viewport's size
    // whatever the render scale: `render`'s image at 320x240.
    EXPECT_NE(e.out.find("the last frame rendered at 160x120"), std::string::npos) << e.out;
    const spot::noise::Image edited = spot::noise::readImage(shot);
    EXPECT_EQ(edited.width, 320);
    EXPECT_EQ(edited.height, 240);
    const spot::noise::Image shown = spot::noise::readImage(window);
    EXPECT_EQ(shown.width, 320);
    EXPECT_EQ(shown.height, 240);
    const std::string ref = tmp("half-render.png");
    const Result r =
        run("", "render --scene " + scene() + " --size 320x240 --out " + ref); // both: balanced
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_GT(spot::splat::psnr(spot::noise::readImage(ref), edited), 60.0);
}

TEST(EditWindow, ScriptedOrbitRendersAtHalfResolutionWhileMoving) {
    const std::string still = tmp("still.png"), moving = tmp("moving.png");
    const Result a =
        run(kXvfb, "edit --scene " + scene() + " --size 200x160 --frames 2 --screenshot " + still);
    ASSERT_EQ(a.code, 0) << a.err;
    const Result b = run(kXvfb, "edit --scene " + scene() +
                                    " --size 200x160 --frames 4 --orbit 30 "
                                    "--screenshot " +
                                    moving);
    ASSERT_EQ(b.code, 0) << b.err;
    EXPECT_EQ(b.err.find("validation error"), std::string::npos) << b.err;
    const spot::noise::Image s = spot::noise::readImage(still), m = spot::noise::readImage(moving);
    EXPECT_EQ(s.width, 200);
    EXPECT_NE(a.out.find("the last frame rendered at 200x160"), std::string::npos) << a.out;
    // The camera moved 90 degrees around the bunny, rendered at half the size while moving; the
    // screenshot is the viewport's size all the same.
    EXPECT_NE(b.out.find("the last frame rendered at 100x80"), std::string::npos) << b.out;
    EXPECT_EQ(m.width, 200);
    EXPECT_EQ(m.height, 160);
    EXPECT_LT(spot::splat::psnr(s, m), 30.0) << "the camera did not move";
}

// --frames N --refine K closes after the N frames and the K refinement steps, however few the
// frames.
TEST(EditWindowSession, FramesWaitForTheRefinement) {
    const Result e = run(kXvfb, "edit --scene " + scene() +
                                    " --size 160x120 --method sorted "
                                    "--frames 2 --refine 6");
    ASSERT_EQ(e.code, 0) << e.err;
    EXPECT_NE(e.out.find("idle refinement: 6 steps"), std::string::npos) << e.out;
}

TEST(EditWindow, WithoutADisplayOneErrorLine) {
    const Result e = run("env -u DISPLAY", "edit --scene " + scene() + " --frames 1");
    EXPECT_EQ(e.code, 2) << e.err;
    EXPECT_EQ(std::count(e.err.begin(), e.err.end(), '\n'), 1) << e.err;
    EXPECT_EQ(e.err.rfind("spotshell: error: ", 0), 0u) << e.err;
    EXPECT_NE(e.err.find("DISPLAY"), std::string::npos) << e.err;
    EXPECT_NE(e.err.find("xvfb-run"), std::string::npos) << e.err;
}

TEST(EditWindow, UnknownMethodIsAnInputError) {
    const Result e = run("env -u DISPLAY", "edit --scene " + scene() + " --method nope");
    EXPECT_EQ(e.code, 2) << e.err;
    EXPECT_NE(e.err.find("instanced"), std::string::npos) << e.err;
}

TEST(EditWindow, UnknownPanelIsAnInputError) {
    const Result e = run("env -u DISPLAY", "edit --scene " + scene() + " --panels render,nope");
    EXPECT_EQ(e.code, 2) << e.err;
    EXPECT_NE(e.err.find("--panels: 'nope' is not a section"), std::string::npos) << e.err;
    EXPECT_EQ(std::count(e.err.begin(), e.err.end(), '\n'), 1) << e.err;
}

// --- the window on the session --------------------------------------------------------------

spot::noise::Camera startCameraForJitter() {
    spot::noise::Camera c;
    c.eye = glm::dvec3(0.0, 0.0, 4.0);
    c.target = glm::dvec3(0.0);
    c.fovYDeg = 30.0;
    c.width = 200;
    c.height = 100;
    return c;
}

std::string writeScript(const std::string& name, const std::string& text) {
    const std::string file = tmp(name);
    std::ofstream(file) << text;
    return file;
}

/// `edit` with a script in the window (validation on), its scene screenshot read back.
spot::noise::Image editInWindow(const std::string& script, const std::string& extra,
                                std::string* out = nullptr) {
    static int counter = 0;
    const std::string shot = tmp("scripted-" + std::to_string(::getpid()) + "-" + std::to_string(counter++) + ".exr");
    const Result e = run(kXvfb, "edit --scene " + scene() + " --size 200x160 --script " + script +
                                    " --window --frames 2 --screenshot " + shot + " " + extra);
    EXPECT_EQ(e.code, 0) << e.err;
    EXPECT_EQ(e.err.find("validation error"), std::string::npos) << e.err;
    EXPECT_NE(e.out.find("validation on: no errors"), std::string::npos) << e.out;
    if (out)
        *out = e.out;
    return spot::noise::readImage(shot);
}

const char* kPaint = "method hybrid\n"
                     "brush density-erase radius 25 strength 1 falloff constant\n"
                     "stroke 70,80 100,84 130,88\n"
                     "brush color radius 30 color 0.1 0.6 0.9\n"
                     "stroke 80,110 120,112\n"
                     "lobe 0 extinction 900\n";

// The script replayed in the window (its strokes as pointer events, one per frame, at the
// reduced resolution while painting) ends on the same image as the script without a window.
TEST(EditWindowSession, ScriptInTheWindowMatchesHeadless) {
    const std::string script = writeScript("same.script", kPaint);
    std::string out;
    const spot::noise::Image window = editInWindow(script, "", &out);
    EXPECT_NE(out.find("stroke to frame: median"), std::string::npos) << out;
    const std::string shot = tmp("headless.exr");
    const Result h =
        run("SPOT_VALIDATION=1", "edit --scene " + scene() + " --size 200x160 --script " + script +
                                     " --screenshot " + shot);
    ASSERT_EQ(h.code, 0) << h.err;
    const spot::noise::Image headless = spot::noise::readImage(shot);
    ASSERT_EQ(window.width, headless.width);
    EXPECT_GT(spot::splat::psnr(headless, window), 60.0);
}

// A stroke in the window changes the image where it paints (and only near there); undo in the
// window restores the image before it. Unlit: lit, the erased fur's shadow also leaves pixels far
// from the stroke, as it should.
TEST(EditWindowSession, StrokeChangesTheImageAndUndoRestoresIt) {
    const std::string before = writeScript("before.script", "method hybrid\nlight off\n");
    const std::string stroke =
        writeScript("stroke.script", "method hybrid\nlight off\n"
                                     "brush density-erase radius 20 strength 1 falloff "
                                     "constant\nstroke 80,80 120,80\n");
    const std::string undone =
        writeScript("undone.script", "method hybrid\nlight off\n"
                                     "brush density-erase radius 20 strength 1 falloff "
                                     "constant\nstroke 80,80 120,80\nundo\n");
    const spot::noise::Image a = editInWindow(before, "");
    const spot::noise::Image b = editInWindow(stroke, "");
    const spot::noise::Image c = editInWindow(undone, "");
    ASSERT_EQ(a.width, 200);
    ASSERT_EQ(b.width, 200);
    // Pixels that changed: inside the band the stroke covered (fur reaches a little beyond the
    // brush, hence the margin), none far from it.
    std::size_t near = 0, far = 0;
    for (int y = 0; y < a.height; ++y)
        for (int x = 0; x < a.width; ++x) {
            const std::size_t i = std::size_t(y) * std::size_t(a.width) + std::size_t(x);
            if (glm::length(a.pixels[i] - b.pixels[i]) < 1e-3f)
                continue;
            const double dx = std::max({0.0, 80.0 - x, x - 120.0}), dy = y - 80.0;
            (std::hypot(dx, dy) < 20.0 + 25.0 ? near : far) += 1;
        }
    EXPECT_GT(near, 200u) << "the stroke changed too little where it painted";
    EXPECT_LT(double(far), 0.05 * double(near)) << "the stroke changed pixels far from it";
    EXPECT_GT(spot::splat::psnr(a, c), 60.0) << "undo did not restore the image";
}

// Idle refinement: the average of 16 jittered `sorted` frames is closer to a supersampled `sorted`
// render (4x4 point-sampled pixels per pixel, EWA off, box-filtered: the image the refinement
// converges to) than the interactive frame it starts from (EWA on).
TEST(EditWindowSession, IdleRefinementConverges) {
    const std::string first = tmp("refine-first.exr"), refined = tmp("refine-16.exr"),
                      big = tmp("refine-reference.exr");
    const std::string common =
        "edit --scene " + scene() + " --size 160x120 --method sorted --lod 0";
    // The interactive frame as it is shown, with EWA filtering.
    const Result a = run(kXvfb, common + " --frames 1 --screenshot " + first);
    ASSERT_EQ(a.code, 0) << a.err;
    const Result b = run(kXvfb, common + " --frames 17 --refine 16 --screenshot " + refined);
    ASSERT_EQ(b.code, 0) << b.err;
    EXPECT_NE(b.out.find("idle refinement: 16 steps"), std::string::npos) << b.out;
    EXPECT_EQ(b.err.find("validation error"), std::string::npos) << b.err;
    const Result r = run("", "render --scene " + scene() +
                                 " --size 640x480 --method sorted --lod 0 --ewa off --out " + big);
    ASSERT_EQ(r.code, 0) << r.err;
    const spot::noise::Image large = spot::noise::readImage(big);
    spot::noise::Image reference(160, 120);
    for (int y = 0; y < 120; ++y)
        for (int x = 0; x < 160; ++x) {
            glm::vec3 sum(0.0f);
            for (int j = 0; j < 4; ++j)
                for (int i = 0; i < 4; ++i)
                    sum += large.pixels[std::size_t(4 * y + j) * 640 + std::size_t(4 * x + i)];
            reference.pixels[std::size_t(y) * 160 + std::size_t(x)] = sum / 16.0f;
        }
    const double before = spot::splat::psnr(reference, spot::noise::readImage(first));
    const double after = spot::splat::psnr(reference, spot::noise::readImage(refined));
    std::printf("PSNR against the 4x4-supersampled render: first frame %.2f dB, after 16 "
                "refinement steps %.2f dB\n",
                before, after);
    EXPECT_GT(after, before + 1.0) << "PSNR against the supersampled render: first frame " << before
                                   << " dB, refined " << after << " dB";
}

// The Kernel section (unfolded by --panels) shows a rendered preview of one kernel in the column,
// which follows a lobe edit.
TEST(EditWindowSession, KernelPreviewFollowsTheKernel) {
    const std::string plain = writeScript("plain.script", "method instanced\n");
    const std::string red = writeScript("red.script", "method instanced\nlobe 2 color 1 0 0\n");
    int x0 = -1, y0 = -1; // the preview's top left in the window
    auto shot = [&](const std::string& script, const std::string& name) {
        const std::string file = tmp(name);
        const Result e =
            run("SPOT_VALIDATION=1 xvfb-run -a -s '-screen 0 1280x1024x24'",
                "edit --scene " + scene() + " --size 1000x900 --script " + script +
                    " --window --frames 1 --panels kernel --window-screenshot " + file);
        EXPECT_EQ(e.code, 0) << e.err;
        // Where the Kernel section left room for it, in the column right of the viewport.
        const std::size_t at = e.out.find("drawn at (");
        EXPECT_NE(at, std::string::npos) << e.out;
        if (at != std::string::npos)
            std::sscanf(e.out.c_str() + at, "drawn at (%d, %d)", &x0, &y0);
        const glm::ivec2 viewport = sizeAfter(e.out, "the scene in a ");
        EXPECT_GE(x0, viewport.x) << "the preview is over the scene";
        return spot::noise::readImage(file);
    };
    const spot::noise::Image a = shot(plain, "preview-plain.png"), b = shot(red, "preview-red.png");
    ASSERT_EQ(a.width, 1000);
    ASSERT_GE(x0, 0);
    ASSERT_LE(x0 + 160, 1000);
    ASSERT_GE(y0, 0);
    ASSERT_LE(y0 + 160, 900);
    double redder = 0.0;
    std::size_t strand = 0; // pixels of the plain preview away from the background
    for (int y = y0; y < y0 + 160; ++y)
        for (int x = x0; x < x0 + 160; ++x) {
            const std::size_t i = std::size_t(y) * 1000 + std::size_t(x);
            redder += (b.pixels[i].r - b.pixels[i].g) - (a.pixels[i].r - a.pixels[i].g);
            strand += glm::length(a.pixels[i] - glm::vec3(0.02f, 0.02f, 0.03f)) > 0.05f;
        }
    EXPECT_GT(strand, 300u) << "no kernel in the preview";
    EXPECT_GT(redder, 20.0) << "the preview did not turn red with the lobe";
}

// --- the real window, driven by X events ------------------------------------------------------

/// A pointer gesture in window pixels: a press at the first point, motion through the others, a
/// release at the last.
using Gesture = std::vector<glm::ivec2>;

Gesture horizontal(int x0, int x1, int step, int y) {
    Gesture g;
    for (int x = x0; x <= x1; x += step)
        g.push_back({x, y});
    return g;
}

/// xdotool's commands for `gesture` with `button` held (and `modifier` held around it).
std::string xdotoolDrag(const Gesture& gesture, int button, const std::string& modifier) {
    std::string s = "xdotool mousemove --window $win " + std::to_string(gesture[0].x) + " " +
                    std::to_string(gesture[0].y) + "\n";
    s += "xdotool " + (modifier.empty() ? "" : "keydown " + modifier + " ") + "mousedown " +
         std::to_string(button) + "\n";
    for (std::size_t i = 1; i < gesture.size(); ++i)
        s += "xdotool mousemove --window $win " + std::to_string(gesture[i].x) + " " +
             std::to_string(gesture[i].y) + "\n";
    s += "xdotool mouseup " + std::to_string(button) +
         (modifier.empty() ? "" : " keyup " + modifier) + "\n";
    return s;
}

// The window as a user drives it: X events from xdotool under a virtual display, through GLFW's
// callbacks and the input mapping (edit_input.h), to the session. A shift-drag erases, ctrl+z
// undoes it, a middle drag orbits; F12 exports the view after each (the File panel's Export: the
// scene at the window's size, without the panels, whose timings change from run to run). The
// same actions as a script replayed in the window (its stroke through the same points, the orbit
// as the camera OrbitView computes for the same motion) give the same images, to the 8-bit
// level: the same pointer events reach the same session, and `instanced` renders the same
// impulses the same way every time.
TEST(EditWindowInput, XEventsDoWhatTheScriptDoes) {
    ASSERT_EQ(std::system("command -v xdotool >/dev/null 2>&1"), 0)
        << "xdotool is not installed (scripts/install-deps.sh installs it)";
    const std::string dir = tmp("xevents");
    std::filesystem::remove_all(dir);
    std::filesystem::create_directories(dir);
    const int width = 320, height = 240;
    // Over the bunny's body (a window this narrow starts with the panels' column hidden).
    const Gesture erase = horizontal(120, 220, 10, 130);
    const Gesture orbit = horizontal(160, 250, 15, 120);
    const spot::noise::SceneDesc desc = spot::noise::loadScene(scene());
    const std::string exported = desc.name + "-view.png";

    // The window, driven by X events: each step ends with F12 and waits for the export.
    std::string driver = "set -u\ncd '" + dir + "'\n" + "SPOT_VALIDATION=1 '" +
                         std::string(SPOT_SPOTSHELL) + "' edit --scene '" + scene() + "' --size " +
                         std::to_string(width) + "x" + std::to_string(height) +
                         " --method instanced --refine 0 >edit.log 2>&1 &\n"
                         "pid=$!\ntrap 'kill $pid 2>/dev/null' EXIT\n"
                         "win=$(timeout 120 xdotool search --sync --onlyvisible --name "
                         "'spotshell edit' | head -n1)\n"
                         "[ -n \"$win\" ] || { echo 'no window'; cat edit.log; exit 3; }\n"
                         "xdotool windowfocus --sync $win\n"
                         "capture() {\n"
                         "  xdotool key F12\n"
                         "  for i in $(seq 1 1200); do [ -f '" +
                         exported +
                         "' ] && break; kill -0 $pid || break; sleep 0.1; done\n"
                         "  mv '" +
                         exported +
                         "' \"$1.png\" || { echo \"no $1\"; cat edit.log; exit 4; }\n"
                         "}\n";
    driver += "xdotool mousemove --window $win " + std::to_string(erase[0].x) + " " +
              std::to_string(erase[0].y) + "\ncapture window-0\n";
    driver += xdotoolDrag(erase, 1, "shift") + "capture window-1\n";
    driver += "xdotool key ctrl+z\ncapture window-2\n";
    driver += xdotoolDrag(orbit, 2, "") + "capture window-3\n";
    driver += "kill $pid\nwait $pid\ncat edit.log\n";
    const std::string driverFile = dir + "/drive.sh";
    std::ofstream(driverFile) << driver;
    std::string driven;
    FILE* pipe = popen(
        ("xvfb-run -a -s '-screen 0 1024x768x24' bash '" + driverFile + "' 2>&1").c_str(), "r");
    ASSERT_NE(pipe, nullptr);
    std::array<char, 4096> buf{};
    while (std::fgets(buf.data(), int(buf.size()), pipe))
        driven += buf.data();
    ASSERT_EQ(pclose(pipe), 0) << driven;

    // The same actions as a script in the window.
    spot::editor::OrbitView view(desc.camera);
    for (std::size_t i = 1; i < orbit.size(); ++i)
        view.orbit(double(orbit[i].x - orbit[i - 1].x), double(orbit[i].y - orbit[i - 1].y),
                   double(height));
    std::string script = "screenshot " + dir + "/script-0.png\nbrush density-erase\nstroke";
    for (const glm::ivec2& p : erase)
        script += " " + std::to_string(p.x) + "," + std::to_string(p.y);
    script += "\nscreenshot " + dir + "/script-1.png\nundo\nscreenshot " + dir + "/script-2.png\n";
    char camera[256];
    std::snprintf(camera, sizeof camera, "camera eye %.17g %.17g %.17g target %.17g %.17g %.17g\n",
                  view.eye().x, view.eye().y, view.eye().z, view.target().x, view.target().y,
                  view.target().z);
    script += camera;
    script += "screenshot " + dir + "/script-3.png\n";
    const std::string scriptFile = writeScript("xevents.script", script);
    const Result scripted =
        run(kXvfb, "edit --scene " + scene() + " --size " + std::to_string(width) + "x" +
                       std::to_string(height) + " --method instanced --refine 0 --script " +
                       scriptFile + " --window --frames 1");
    ASSERT_EQ(scripted.code, 0) << scripted.err;

    std::ifstream log(dir + "/edit.log");
    const std::string editLog((std::istreambuf_iterator<char>(log)), {});
    EXPECT_EQ(editLog.find("validation error"), std::string::npos) << editLog;
    const char* steps[] = {"start", "shift-drag erase", "ctrl+z", "middle-drag orbit"};
    std::vector<spot::noise::Image> shown;
    for (int i = 0; i < 4; ++i) {
        const std::string w = dir + "/window-" + std::to_string(i) + ".png";
        ASSERT_TRUE(std::filesystem::exists(w)) << steps[i] << ": no export; the window's log:\n"
                                                << editLog;
        shown.push_back(spot::noise::readImage(w));
        const spot::noise::Image s =
            spot::noise::readImage(dir + "/script-" + std::to_string(i) + ".png");
        EXPECT_EQ(maxLevelDifference(shown.back(), s), 0) << steps[i];
    }
    // Each step did something: the erase changed the image, undo restored it, the orbit moved.
    EXPECT_GT(fractionDiffering(shown[0], shown[1], 4), 0.01) << "the erase changed nothing";
    EXPECT_EQ(maxLevelDifference(shown[0], shown[2]), 0) << "undo did not restore the start";
    EXPECT_GT(fractionDiffering(shown[0], shown[3], 4), 0.1) << "the orbit changed nothing";
}

// N hides the panels' column and shows it again, as a user presses it (X events): the view F12
// exports is the viewport's size, the window's whole width without the column.
TEST(EditWindowInput, NTogglesThePanelsColumn) {
    ASSERT_EQ(std::system("command -v xdotool >/dev/null 2>&1"), 0)
        << "xdotool is not installed (scripts/install-deps.sh installs it)";
    const std::string dir = tmp("ntoggle");
    std::filesystem::remove_all(dir);
    std::filesystem::create_directories(dir);
    const std::string exported = spot::noise::loadScene(scene()).name + "-view.png";
    const std::string driver =
        "set -u\ncd '" + dir + "'\n'" + std::string(SPOT_SPOTSHELL) + "' edit --scene '" + scene() +
        "' --size 800x600 --method instanced --refine 0 >edit.log 2>&1 &\n"
        "pid=$!\ntrap 'kill $pid 2>/dev/null' EXIT\n"
        "win=$(timeout 120 xdotool search --sync --onlyvisible --name 'spotshell edit' | "
        "head -n1)\n"
        "[ -n \"$win\" ] || { echo 'no window'; cat edit.log; exit 3; }\n"
        "xdotool windowfocus --sync $win\nxdotool mousemove --window $win 250 300\n"
        "capture() {\n"
        "  xdotool key F12\n"
        "  for i in $(seq 1 1200); do [ -f '" +
        exported +
        "' ] && break; kill -0 $pid || break; sleep 0.1; done\n"
        "  mv '" +
        exported +
        "' \"$1.png\" || { echo \"no $1\"; cat edit.log; exit 4; }\n"
        "}\n"
        "capture shown\nxdotool key n\ncapture hidden\nxdotool key n\ncapture again\n"
        "kill $pid\nwait $pid\n";
    std::ofstream(dir + "/drive.sh") << driver;
    std::string log;
    FILE* pipe = popen(
        ("xvfb-run -a -s '-screen 0 1024x768x24' bash '" + dir + "/drive.sh' 2>&1").c_str(), "r");
    ASSERT_NE(pipe, nullptr);
    std::array<char, 4096> buf{};
    while (std::fgets(buf.data(), int(buf.size()), pipe))
        log += buf.data();
    pclose(pipe);
    for (const char* step : {"shown", "hidden", "again"})
        ASSERT_TRUE(std::filesystem::exists(dir + "/" + step + ".png")) << step << "\n" << log;
    EXPECT_EQ(spot::noise::readImage(dir + "/shown.png").width, 500) << log;
    EXPECT_EQ(spot::noise::readImage(dir + "/hidden.png").width, 800) << log;
    EXPECT_EQ(spot::noise::readImage(dir + "/again.png").width, 500) << log;
}

// The timeline as a user drives it (X events) on an animated scene (a rigid clip written by the
// test, spin_clip.h: 2 s at 24 fps): space plays by the wall-clock time and space again pauses;
// a drag on the timeline's slider (the column's top row) to past its right end scrubs to the
// clip's end; the left arrow steps back a frame at a time. F12 exports the view after each step
// (its metadata says the time). The scrubbed and stepped frames are those a script's `time`
// shows in the window, to the 8-bit level.
TEST(EditWindowInput, SpacePlaysAndTheSliderScrubsTheTimeline) {
    ASSERT_EQ(std::system("command -v xdotool >/dev/null 2>&1"), 0)
        << "xdotool is not installed (scripts/install-deps.sh installs it)";
    const std::string dir = tmp("timeline");
    std::filesystem::remove_all(dir);
    const std::string spin = spot::test::writeSpinClip(dir + "/clip").string();
    ASSERT_FALSE(spin.empty());
    const std::string exported = "spin-view.png";
    std::string driver =
        "set -u\ncd '" + dir + "'\nSPOT_VALIDATION=1 '" + std::string(SPOT_SPOTSHELL) +
        "' edit --scene '" + spin +
        "' --size 800x600 --method instanced --refine 0 >edit.log 2>&1 &\n"
        "pid=$!\ntrap 'kill $pid 2>/dev/null' EXIT\n"
        "win=$(timeout 120 xdotool search --sync --onlyvisible --name 'spotshell edit' | "
        "head -n1)\n"
        "[ -n \"$win\" ] || { echo 'no window'; cat edit.log; exit 3; }\n"
        "xdotool windowfocus --sync $win\nxdotool mousemove --window $win 250 300\n"
        "capture() {\n"
        "  xdotool key F12\n"
        "  for i in $(seq 1 1200); do [ -f '" +
        exported +
        "' ] && break; kill -0 $pid || break; sleep 0.1; done\n"
        "  mv '" +
        exported +
        "' \"$1.png\" || { echo \"no $1\"; cat edit.log; exit 4; }\n"
        "}\n"
        "capture start\n"
        "xdotool key space\nsleep 1\nxdotool key space\ncapture played\n";
    // The slider: the column starts at x = 500 in an 800-pixel window; its top row is the Play
    // button, the slider below it, at y = 40. The button is held a moment at the end, as a hand
    // does (ImGui reads a release in the frame of the last motion as a release where it began),
    // and F12 waits a moment after the release (until ImGui has seen it, the slider has the keys).
    // Each step waits a moment, as a hand does: on a loaded machine a frame takes long, and a press
    // that reaches ImGui in the frame of the move onto the slider can miss it.
    std::string drag = "xdotool mousemove --window $win 600 40\nsleep 0.5\nxdotool mousedown 1\nsleep 0.5\n";
    for (const int x : {650, 700, 750, 795})
        drag += "xdotool mousemove --window $win " + std::to_string(x) + " 40\nsleep 0.3\n";
    drag += "sleep 1\nxdotool mouseup 1\n";
    driver += drag + "sleep 1\ncapture scrubbed\n";
    driver += "xdotool mousemove --window $win 250 300\n";
    for (int i = 0; i < 12; ++i)
        driver += "xdotool key Left\n";
    driver += "capture stepped\nkill $pid\nwait $pid\ncat edit.log\n";
    std::ofstream(dir + "/drive.sh") << driver;
    std::string driven;
    FILE* pipe = popen(
        ("xvfb-run -a -s '-screen 0 1024x768x24' bash '" + dir + "/drive.sh' 2>&1").c_str(), "r");
    ASSERT_NE(pipe, nullptr);
    std::array<char, 4096> buf{};
    while (std::fgets(buf.data(), int(buf.size()), pipe))
        driven += buf.data();
    ASSERT_EQ(pclose(pipe), 0) << driven;
    EXPECT_EQ(driven.find("validation error"), std::string::npos) << driven;

    // The same frames from a script's `time` in the window.
    const std::string script = writeScript("timeline.script", "time 2\nscreenshot " + dir +
                                                                  "/script-end.png\ntime 1.5\n"
                                                                  "screenshot " +
                                                                  dir + "/script-step.png\n");
    const Result scripted =
        run(kXvfb, "edit --scene " + spin + " --size 800x600 --method instanced --refine 0 " +
                       "--script " + script + " --window --frames 1");
    ASSERT_EQ(scripted.code, 0) << scripted.err;

    std::map<std::string, std::map<std::string, std::string>> meta;
    std::map<std::string, spot::noise::Image> shown;
    for (const char* step : {"start", "played", "scrubbed", "stepped"}) {
        const std::string file = dir + "/" + step + ".png";
        ASSERT_TRUE(std::filesystem::exists(file)) << step << "\n" << driven;
        shown[step] = spot::noise::readImage(file, &meta[step]);
        ASSERT_EQ(shown[step].width, 500) << step << ": the column is shown";
    }
    const auto time = [&](const char* step) { return std::stod(meta[step]["time"]); };
    std::printf("timeline: start t %s, played t %s (frame %s), scrubbed t %s, stepped t %s "
                "(frame %s)\n",
                meta["start"]["time"].c_str(), meta["played"]["time"].c_str(),
                meta["played"]["frame"].c_str(), meta["scrubbed"]["time"].c_str(),
                meta["stepped"]["time"].c_str(), meta["stepped"]["frame"].c_str());
    EXPECT_EQ(time("start"), 0.0);
    // About a second of play (each frame's wall-clock time), short of the clip's 2 s.
    EXPECT_GT(time("played"), 0.3);
    EXPECT_LT(time("played"), 2.0);
    EXPECT_GT(fractionDiffering(shown["start"], shown["played"], 4), 0.01)
        << "playing did not move the sphere";
    EXPECT_EQ(time("scrubbed"), 2.0) << "the slider's right end is the clip's end";
    EXPECT_EQ(time("stepped"), 1.5) << "12 frames back from frame 48 at 24 fps";
    EXPECT_EQ(meta["stepped"]["frame"], "36");
    EXPECT_EQ(
        maxLevelDifference(shown["scrubbed"], spot::noise::readImage(dir + "/script-end.png")), 0);
    EXPECT_EQ(
        maxLevelDifference(shown["stepped"], spot::noise::readImage(dir + "/script-step.png")), 0);
}

TEST(EditWindowSession, BadScriptLineInTheWindowIsAnInputError) {
    const std::string script = writeScript("bad.script", "method hybrid\nbrush comb radius -3\n");
    const Result e =
        run(kXvfb, "edit --scene " + scene() + " --script " + script + " --window --frames 2");
    EXPECT_EQ(e.code, 2) << e.err;
    EXPECT_NE(e.err.find("bad.script:2:"), std::string::npos) << e.err;
}

TEST(EditWindowSession, ClosingWithUnsavedChangesAsksFirst) {
    using spot::editor::QuitAnswer;
    using spot::editor::quitStep;
    // Nothing asked, nothing answered: the window stays.
    EXPECT_FALSE(quitStep(true, false, QuitAnswer::None).close);
    // Saved: closes at once.
    EXPECT_TRUE(quitStep(false, true, QuitAnswer::None).close);
    // Unsaved: stays open and asks.
    const auto ask = quitStep(true, true, QuitAnswer::None);
    EXPECT_FALSE(ask.close);
    EXPECT_TRUE(ask.ask);
    // The answers: save then close, close without saving, stay.
    const auto save = quitStep(true, false, QuitAnswer::Save);
    EXPECT_TRUE(save.close && save.save);
    const auto discard = quitStep(true, false, QuitAnswer::Discard);
    EXPECT_TRUE(discard.close && !discard.save);
    const auto cancel = quitStep(true, false, QuitAnswer::Cancel);
    EXPECT_FALSE(cancel.close || cancel.save || cancel.ask);
}

TEST(OrbitNavigation, JitterShiftsTheImageCentreBySubPixels) {
    spot::noise::Camera c = startCameraForJitter();
    const spot::noise::Camera j = spot::editor::jitteredCamera(c, 0.25, -0.5);
    // The world point that was at the image centre is now 0.25 pixels right and 0.5 up.
    const spot::noise::Ray ray = spot::noise::CameraRays(c).ray(100.0, 50.0);
    const glm::dvec3 p = ray.origin + 4.0 * ray.dir;
    const spot::noise::Ray moved = spot::noise::CameraRays(j).ray(100.25, 49.5);
    const glm::dvec3 q = moved.origin + glm::dot(p - moved.origin, moved.dir) * moved.dir;
    EXPECT_NEAR(glm::length(p - q), 0.0, 1e-6);
    for (int i = 0; i < 64; ++i) {
        const glm::dvec2 h = spot::editor::haltonJitter(i);
        EXPECT_GE(h.x, -0.5);
        EXPECT_LT(h.x, 0.5);
        EXPECT_GE(h.y, -0.5);
        EXPECT_LT(h.y, 0.5);
    }
}

// --- the context's presentation options ---------------------------------------------------

TEST(WindowContext, SwapchainAndSurfaceExtensionsWithoutAWindow) {
    spot::splat::ContextOptions o;
    o.validation = true;
    o.instanceExtensions = {"VK_KHR_surface"};
    o.swapchain = true;
    std::uint32_t asked = 0;
    o.canPresent = [&](VkInstance, VkPhysicalDevice, std::uint32_t) {
        ++asked;
        return true;
    };
    spot::splat::Context ctx(o);
    EXPECT_GT(asked, 0u);
    EXPECT_NE(vkGetDeviceProcAddr(ctx.device(), "vkCreateSwapchainKHR"), nullptr);
    EXPECT_EQ(ctx.validation().errors, 0u) << ctx.validation().firstError;
}

TEST(WindowContext, NoQueueThatCanPresentIsAClearError) {
    spot::splat::ContextOptions o;
    o.canPresent = [](VkInstance, VkPhysicalDevice, std::uint32_t) { return false; };
    try {
        spot::splat::Context ctx(o);
        FAIL() << "a context without a queue that can present";
    } catch (const std::exception& e) {
        EXPECT_NE(std::string(e.what()).find("can present"), std::string::npos) << e.what();
    }
}

TEST(WindowContext, AMissingInstanceExtensionIsNamed) {
    spot::splat::ContextOptions o;
    o.instanceExtensions = {"VK_SPOT_no_such_extension"};
    try {
        spot::splat::Context ctx(o);
        FAIL() << "an instance with an extension that does not exist";
    } catch (const std::exception& e) {
        EXPECT_NE(std::string(e.what()).find("instance extension is missing"), std::string::npos)
            << e.what();
    }
}

// --- navigation --------------------------------------------------------------------------

spot::noise::Camera startCamera() {
    spot::noise::Camera c;
    c.eye = glm::dvec3(0.0, 0.0, 4.0);
    c.target = glm::dvec3(0.0);
    c.fovYDeg = 30.0;
    return c;
}

TEST(OrbitNavigation, OrbitKeepsTargetAndDistance) {
    OrbitView v(startCamera());
    v.orbit(37.0, -12.0, 600.0);
    v.orbit(-5.0, 80.0, 600.0);
    EXPECT_NEAR(v.distance(), 4.0, 1e-9);
    EXPECT_NEAR(glm::length(v.target()), 0.0, 1e-12);
    // Dragging right by half the view height turns the eye a quarter turn to the left (-x).
    OrbitView w(startCamera());
    w.orbit(300.0, 0.0, 600.0);
    EXPECT_NEAR(w.eye().x, -4.0, 1e-9);
    EXPECT_NEAR(w.eye().z, 0.0, 1e-9);
    // Dragging down shows the scene from higher up, and never past the pole.
    OrbitView u(startCamera());
    u.orbit(0.0, 100.0, 600.0);
    EXPECT_GT(u.eye().y, 0.0);
    u.orbit(0.0, 5000.0, 600.0);
    EXPECT_LT(u.eye().y, 4.0);
    EXPECT_GT(std::hypot(u.eye().x, u.eye().z), 0.0);
    spot::noise::CameraRays rays(u.camera(64, 64)); // still a valid camera
    (void)rays;
}

TEST(OrbitNavigation, PanFollowsThePointerAtTheTargetDepth) {
    OrbitView v(startCamera());
    // The view is 2 * 4 * tan(15 deg) world units tall over 600 pixels.
    const double perPixel = 8.0 * std::tan(std::numbers::pi / 12.0) / 600.0;
    v.pan(60.0, -30.0, 600.0);
    EXPECT_NEAR(v.target().x, -60.0 * perPixel, 1e-12);
    EXPECT_NEAR(v.target().y, -30.0 * perPixel, 1e-12);
    EXPECT_NEAR(v.distance(), 4.0, 1e-12);
}

TEST(OrbitNavigation, DollyAndFrame) {
    OrbitView v(startCamera());
    v.dolly(2.0);
    EXPECT_NEAR(v.distance(), 4.0 * 0.85 * 0.85, 1e-12);
    v.dolly(-2.0);
    EXPECT_NEAR(v.distance(), 4.0, 1e-12);
    // A unit sphere at (1, 2, 3) in a 4:3 view: the vertical field of view is the narrower.
    v.frame({glm::dvec3(1.0, 2.0, 3.0), 1.0}, 4.0 / 3.0);
    EXPECT_NEAR(glm::length(v.target() - glm::dvec3(1.0, 2.0, 3.0)), 0.0, 1e-12);
    EXPECT_NEAR(v.distance(), 1.05 / std::sin(std::numbers::pi / 12.0), 1e-9);
    // The bounding sphere of a mesh holds every vertex.
    spot::noise::Mesh mesh = spot::noise::loadMeshOrGenerated("generated:torus");
    const spot::editor::BoundingSphere s = spot::editor::boundingSphere(mesh);
    for (const glm::vec3& p : mesh.positions)
        EXPECT_LE(glm::length(glm::dvec3(p) - s.center), s.radius + 1e-9);
    EXPECT_NEAR(s.radius, 1.35, 0.01);
}

} // namespace
