// The editor on an animated scene (a rigid glTF clip the test writes, spin_clip.h): the time and
// the timeline's playback, the brush picking the posed surface and painting the rest-space layer
// at the same skin point, the paint following the skin to other frames, and the script's `time`
// and `play`.
#include <algorithm>
#include <cmath>
#include <cstdio>

#include <gtest/gtest.h>

#include "edit_test_support.h"
#include "editor/edit_script.h"
#include "noise/error.h"
#include "spin_clip.h"

namespace {

using namespace spot;
using test::editOptions;

std::filesystem::path spinScene() {
    static const std::filesystem::path scene = test::writeSpinClip(test::tmpPath("spin-clip"));
    return scene;
}

glm::vec3 transformPoint(const glm::mat4& m, glm::vec3 p) {
    return glm::vec3(m * glm::vec4(p, 1.0f));
}

/// The middle of the posed sphere's span of hits along the image's middle row.
std::optional<glm::vec2> sphereCentrePixel(const edit::Session& s) {
    std::vector<float> xs;
    const float y = float(s.camera().height) * 0.5f;
    for (int x = 0; x < s.camera().width; ++x)
        if (s.pick(glm::vec2(float(x) + 0.5f, y)))
            xs.push_back(float(x) + 0.5f);
    if (xs.empty())
        return std::nullopt;
    return glm::vec2(0.5f * (xs.front() + xs.back()), y);
}

/// Pixels whose colour differs by more than `threshold` (linear, any channel), and their
/// centroid.
struct Difference {
    std::size_t count = 0;
    glm::vec2 centroid{0.0f};
    float spread = 0.0f; ///< the largest distance of a differing pixel from the centroid
};

Difference difference(const noise::Image& a, const noise::Image& b, float threshold = 0.02f) {
    Difference d;
    glm::dvec2 sum(0.0);
    std::vector<glm::vec2> at;
    for (int y = 0; y < a.height; ++y)
        for (int x = 0; x < a.width; ++x) {
            const std::size_t i = std::size_t(y) * std::size_t(a.width) + std::size_t(x);
            const glm::vec3 e = glm::abs(a.pixels[i] - b.pixels[i]);
            if (std::max({e.x, e.y, e.z}) > threshold) {
                at.emplace_back(float(x) + 0.5f, float(y) + 0.5f);
                sum += glm::dvec2(at.back());
            }
        }
    d.count = at.size();
    if (at.empty())
        return d;
    d.centroid = glm::vec2(sum / double(at.size()));
    for (const glm::vec2& p : at)
        d.spread = std::max(d.spread, glm::length(p - d.centroid));
    return d;
}

// The session loads the clip through AnimatedMesh: the noise on the rest pose, the frame posing
// it at the session's time (clamped to the clip); the timeline spans the clip at the scene's fps,
// and playback loops or stops at the end.
TEST(EditAnimated, TimeAndTimeline) {
    edit::Session s(spinScene(), editOptions());
    ASSERT_TRUE(s.animated());
    EXPECT_TRUE(s.frame().animated());
    const edit::Timeline line = s.timeline();
    EXPECT_DOUBLE_EQ(line.start, 0.0);
    EXPECT_DOUBLE_EQ(line.end, 2.0);
    EXPECT_DOUBLE_EQ(line.fps, 24.0);
    EXPECT_EQ(line.frame(line.end), 48);
    // The rest pose is the mesh as loaded (the sphere at the origin); the mesh as shown moves.
    const noise::Bounds b = s.mesh().bounds();
    EXPECT_NEAR(b.lo.x, -0.5f, 1e-3f);
    EXPECT_NEAR(b.hi.x, 0.5f, 1e-3f);
    s.setTime(2.0);
    EXPECT_NEAR(s.shownMesh().bounds().lo.x, 1.0f, 1e-3f);
    EXPECT_NEAR(s.mesh().bounds().lo.x, -0.5f, 1e-3f);

    s.setTime(5.0);
    EXPECT_DOUBLE_EQ(s.time(), 2.0) << "a time past the clip is clamped";
    s.setTime(-1.0);
    EXPECT_DOUBLE_EQ(s.time(), 0.0);
    EXPECT_THROW(s.setTime(std::nan("")), InputError);

    s.setTime(1.5);
    EXPECT_TRUE(s.advance(1.0)); // loops: 2.5 wraps to 0.5
    EXPECT_NEAR(s.time(), 0.5, 1e-12);
    s.setLoop(false);
    s.setTime(1.5);
    EXPECT_FALSE(s.advance(1.0)) << "without loop, playback stops at the end";
    EXPECT_DOUBLE_EQ(s.time(), 2.0);
    // 48 frame steps from the start reach the end exactly (not wrapped by rounding).
    s.setLoop(true);
    s.setTime(0.0);
    for (int i = 0; i < 48; ++i)
        s.advance(1.0 / 24.0);
    EXPECT_EQ(s.frameNumber(), 48);

    // The frames render (the deform passes every frame) without a validation error, and differ.
    noise::Image at0, at2;
    s.setTime(0.0);
    s.render(&at0);
    s.setTime(2.0);
    s.render(&at2);
    EXPECT_GT(difference(at0, at2).count, 1000u) << "the sphere did not move";
    test::expectNoValidationErrors(s.context());
}

// A mesh that does not move with the scene's wind: the scene animates (the impulses turn in the
// gusts), its timeline has no clip (10 s, and the time runs on past it), and the brush paints
// where it picks (the rest pose is the pose).
TEST(EditAnimated, WindOnlySceneHasATimeThatRunsOn) {
    const std::filesystem::path scene = test::tmpPath("wind-only.json");
    test::writeText(scene,
                    R"({"version": 1, "name": "wind", "mesh": "generated:sphere",
  "preset": ")" + (std::filesystem::path(SPOT_SOURCE_DIR) / "presets/fur.json").string() +
                        R"(", "camera": {"eye": [0, 0, 2.6], "target": [0, 0, 0], "fov_deg": 40},
  "image": {"width": 96, "height": 96}, "shading": {"mode": "unlit"},
  "wind": {"direction": [1, 0, 0], "strength": 0.8, "gust_frequency": 1.0}})");
    edit::Session s(scene, editOptions(96));
    ASSERT_TRUE(s.animated());
    EXPECT_FALSE(s.animation().animated());
    EXPECT_DOUBLE_EQ(s.timeline().start, 0.0);
    EXPECT_DOUBLE_EQ(s.timeline().end, edit::Timeline::kNoClipSeconds);
    noise::Image calm, gust;
    s.render(&calm);
    s.setTime(0.25);
    s.render(&gust);
    EXPECT_GT(difference(calm, gust).count, 50u) << "the wind does not move the fur";
    s.setTime(9.9);
    EXPECT_TRUE(s.advance(0.5));
    EXPECT_NEAR(s.time(), 10.4, 1e-12) << "no clip: the time runs on";
    EXPECT_NEAR(s.timeline().end, 10.4, 1e-12);
    const std::optional<edit::Hit> hit = s.pick({48.0f, 48.0f});
    ASSERT_TRUE(hit);
    EXPECT_EQ(hit->restPosition, hit->position);
    test::expectNoValidationErrors(s.context());
}

// The brush picks the surface as shown at the session's time and paints at rest: a stroke at
// t = 1, where the skin under it is more than a diameter from where it rests (moved 0.75 along x
// and turned 45 degrees), writes the density layer around the rest-pose point of the hit's
// (triangle, barycentrics) and nowhere near the posed point; the impulses under it at rest are
// erased. The paint then follows the skin: at t = 0, 1 and 2 the image changes only around the
// painted skin point as posed there (in view at all three: it faces the camera at t = 1).
TEST(EditAnimated, PaintAtAPoseStaysOnTheSkin) {
    edit::Session s(spinScene(), editOptions());
    s.setTime(1.0);
    const std::optional<glm::vec2> at = sphereCentrePixel(s);
    ASSERT_TRUE(at) << "the posed sphere is not in view";
    const std::optional<edit::Hit> hit = s.pick(*at);
    ASSERT_TRUE(hit);
    // The hit is on the posed sphere; its rest point is the same skin point at rest.
    const glm::mat4 pose = test::spinTransform(1.0);
    const glm::vec3 carried = transformPoint(pose, hit->restPosition);
    EXPECT_LT(glm::length(carried - hit->position), 1e-4f);
    EXPECT_NEAR(glm::length(hit->restPosition), 0.5f, 2e-3f) << "on the sphere at rest";
    const float apart = glm::length(hit->position - hit->restPosition);
    EXPECT_GT(apart, 1.0f) << "the pose must move the skin far for the test to mean something";

    // The images before painting, at three frames (the armed layer changes nothing).
    std::vector<noise::Image> before(3);
    for (int t = 0; t < 3; ++t) {
        s.setTime(double(t));
        s.render(&before[std::size_t(t)]);
    }
    s.setTime(1.0);
    const std::vector<noise::Impulse> restBefore = s.generator().generate();

    s.brush() = {};
    s.brush().kind = edit::BrushKind::DensityErase;
    s.brush().radiusPx = 14.0f;
    s.brush().strength = 1.0f;
    s.brush().falloff = edit::Falloff::Constant;
    const edit::EditCost cost = s.stroke({*at});
    EXPECT_EQ(cost.dabs, 1u);
    EXPECT_GT(cost.voxelsWritten, 0u);
    const noise::PaintedGrid* grid = s.grid(edit::Slot::Density);
    ASSERT_NE(grid, nullptr);
    const float radius = test::worldRadius(s, *hit, 14.0f);
    const float diagonal = std::sqrt(3.0f) * grid->voxelSize();
    std::size_t written = 0, nearRest = 0, nearPosed = 0;
    grid->forEachActive([&](glm::ivec3 ijk, glm::vec3) {
        const glm::vec3 p = grid->voxelPosition(ijk);
        ++written;
        nearRest += glm::length(p - hit->restPosition) <= radius + diagonal;
        nearPosed += glm::length(p - hit->position) <= radius + diagonal;
    });
    std::printf("paint at t = 1: %zu voxels written (radius %.4f, voxel %.4f); the posed point is "
                "%.3f from its rest point\n",
                written, radius, grid->voxelSize(), apart);
    EXPECT_GT(written, 10u);
    EXPECT_EQ(nearRest, written) << "every voxel written lies around the rest-pose point";
    EXPECT_EQ(nearPosed, 0u) << "nothing written at the posed location";

    // At rest: the impulses under the brush (facing the camera as carried back) are gone.
    const glm::vec3 restEye =
        glm::vec3(glm::inverse(pose) * glm::vec4(glm::vec3(s.camera().eye), 1));
    const auto under = [&](const std::vector<noise::Impulse>& impulses) {
        std::size_t n = 0;
        for (const noise::Impulse& i : impulses) {
            const glm::vec3 anchor = i.position - i.height * i.normal;
            n += glm::length(anchor - hit->restPosition) < radius - 2.0f * diagonal &&
                 glm::dot(i.normal, glm::normalize(restEye - anchor)) > 0.3f;
        }
        return n;
    };
    const std::size_t underBefore = under(restBefore), underAfter = under(s.generator().generate());
    std::printf("impulses under the brush at rest: %zu before, %zu after\n", underBefore,
                underAfter);
    EXPECT_GT(underBefore, 10u);
    EXPECT_EQ(underAfter, 0u);

    // The rendered density follows the skin: at each frame the image changes in one compact spot,
    // and that spot picks (at that frame) a skin point whose rest position is the painted one.
    for (int t = 0; t < 3; ++t) {
        SCOPED_TRACE(t);
        s.setTime(double(t));
        noise::Image after;
        s.render(&after);
        const Difference d = difference(before[std::size_t(t)], after);
        std::printf("t = %d: %zu pixels changed around (%.1f, %.1f), within %.1f pixels\n", t,
                    d.count, d.centroid.x, d.centroid.y, d.spread);
        EXPECT_GT(d.count, 20u) << "the erase does not show";
        EXPECT_LT(d.spread, 3.0f * 14.0f) << "the change is not one spot";
        const std::optional<edit::Hit> there = s.pick(d.centroid);
        ASSERT_TRUE(there);
        EXPECT_LT(glm::length(there->restPosition - hit->restPosition), radius)
            << "the erased spot is not the painted skin point";
    }
    test::expectNoValidationErrors(s.context());
}

// A comb stroke at a pose combs the fur as shown: the drag is carried back to rest by the hit
// triangle's rotation, so at the pose (t = 1: the sphere rolled 45 degrees about the view axis,
// where a drag taken at rest as it is on the screen would comb 45 degrees off) the impulses under
// the stroke point along the screen's drag (mean angle below 10 degrees), as at rest on a static
// mesh (EditSession.CombFollowsTheStroke).
TEST(EditAnimated, CombAtAPoseFollowsTheStrokeAsShown) {
    const std::filesystem::path rolled =
        test::writeSpinClip(test::tmpPath("roll-clip"), glm::vec3(0, 0, 1));
    edit::Session s(rolled, editOptions());
    s.setTime(1.0);
    const std::optional<glm::vec2> centre = sphereCentrePixel(s);
    ASSERT_TRUE(centre);
    s.brush().kind = edit::BrushKind::Comb;
    s.brush().radiusPx = 24.0f;
    s.brush().strength = 1.0f;
    s.brush().falloff = edit::Falloff::Constant;
    s.stroke({*centre - glm::vec2(28.0f, 0.0f), *centre + glm::vec2(28.0f, 0.0f)});
    const std::optional<edit::Hit> mid = s.pick(*centre);
    ASSERT_TRUE(mid);
    const float radius = test::worldRadius(s, *mid, 24.0f);
    noise::Deformer deformer(s.animation());
    deformer.pose(1.0);
    const std::vector<noise::Impulse> posed =
        deformer.move(s.generator().generate(), s.generator().cellSize());
    const glm::dvec3 forward = glm::normalize(s.camera().target - s.camera().eye);
    const glm::vec3 right(glm::normalize(glm::cross(forward, s.camera().up)));
    const glm::vec3 eye(s.camera().eye);
    double sum = 0.0;
    std::size_t n = 0;
    for (const noise::Impulse& i : posed) {
        const glm::vec3 anchor = i.position - i.height * i.normal;
        if (glm::length(anchor - mid->position) > 0.5f * radius ||
            glm::dot(i.normal, glm::normalize(eye - anchor)) < 0.3f)
            continue;
        const glm::vec3 want = glm::normalize(right - i.normal * glm::dot(right, i.normal));
        sum += std::acos(std::clamp(glm::dot(glm::normalize(i.comb), want), -1.0f, 1.0f));
        ++n;
    }
    ASSERT_GT(n, 10u);
    const double meanDeg = sum / double(n) * 180.0 / M_PI;
    std::printf("comb at t = 1: %zu impulses under the stroke, mean angle to the stroke as shown "
                "%.2f degrees\n",
                n, meanDeg);
    EXPECT_LT(meanDeg, 10.0);
    test::expectNoValidationErrors(s.context());
}

// Undo after painting at a pose restores the rest layer bit for bit, whatever the time.
TEST(EditAnimated, UndoAtAnotherTimeRestoresTheImpulses) {
    edit::Session s(spinScene(), editOptions());
    s.setTime(2.0);
    const std::optional<glm::vec2> at = sphereCentrePixel(s);
    ASSERT_TRUE(at);
    s.brush().kind = edit::BrushKind::DensityAdd;
    s.brush().strength = 0.0f;
    s.stroke({{5.0f, 5.0f}}); // paints nothing: the density becomes painted
    const std::vector<noise::Impulse> start = s.generator().generate();
    s.brush() = {};
    s.brush().kind = edit::BrushKind::DensityErase;
    s.stroke({*at, *at + glm::vec2(20.0f, 0.0f)});
    EXPECT_NE(s.generator().generate().size(), start.size());
    s.setTime(0.5);
    ASSERT_TRUE(s.undo());
    test::expectSameImpulses(start, s.generator().generate(), "after undo");
}

// The script's `time T` and `play N [loop on|off]`: parsed with their bounds, run on the session
// (play: N frames at the scene's fps, each rendered).
TEST(EditAnimated, ScriptTimeAndPlay) {
    const std::vector<edit::ScriptAction> a =
        edit::parseScript("time 1.25\nplay 12\nplay 3 loop off\n", "t.script");
    ASSERT_EQ(a.size(), 3u);
    EXPECT_EQ(a[0].type, edit::ScriptAction::Type::Time);
    EXPECT_DOUBLE_EQ(a[0].seconds, 1.25);
    EXPECT_EQ(a[1].type, edit::ScriptAction::Type::Play);
    EXPECT_EQ(a[1].count, 12);
    EXPECT_FALSE(a[1].loop.has_value());
    ASSERT_TRUE(a[2].loop.has_value());
    EXPECT_FALSE(*a[2].loop);
    for (const char* bad : {"time\n", "time soon\n", "play 0\n", "play 1.5\n",
                            "play 2 loop maybe\n", "play 2 twice\n", "time 1 2\n"}) {
        try {
            edit::parseScript(bad, "bad.script");
            ADD_FAILURE() << "accepted: " << bad;
        } catch (const InputError& e) {
            EXPECT_NE(std::string(e.what()).find("bad.script:1:"), std::string::npos) << e.what();
        }
    }

    edit::Session s(spinScene(), editOptions(96));
    edit::ScriptReport report = edit::runScript(
        s, edit::parseScript("time 0.5\nplay 12\n", "play.script"), "play.script", nullptr);
    EXPECT_NEAR(s.time(), 1.0, 1e-9);
    EXPECT_EQ(s.frameNumber(), 24);
    EXPECT_EQ(report.frames, 12);
    // Past the end: it loops by default, stops with `loop off`; a time outside is clamped.
    edit::runScript(s, edit::parseScript("time 1.5\nplay 24\n", "loop.script"), "loop.script",
                    nullptr);
    EXPECT_NEAR(s.time(), 0.5, 1e-9);
    edit::runScript(s, edit::parseScript("time 1.5\nplay 24 loop off\n", "stop.script"),
                    "stop.script", nullptr);
    EXPECT_DOUBLE_EQ(s.time(), 2.0);
    EXPECT_FALSE(s.loop());
    edit::runScript(s, edit::parseScript("time 99\n", "clamp.script"), "clamp.script", nullptr);
    EXPECT_DOUBLE_EQ(s.time(), 2.0);
    test::expectNoValidationErrors(s.context());

    // A static scene has no clip: its time runs on (the comb's wind would follow it), at the
    // scene's fps (24 by default), and nothing moves.
    edit::Session still(test::bunnyScene(), editOptions(64));
    EXPECT_FALSE(still.animated());
    noise::Image first, last;
    still.render(&first);
    report = edit::runScript(still, edit::parseScript("time 9.5\nplay 24\n", "still.script"),
                             "still.script", nullptr);
    EXPECT_NEAR(still.time(), 10.5, 1e-9) << "no clip: no wrap";
    EXPECT_EQ(report.frames, 24);
    still.render(&last);
    EXPECT_EQ(difference(first, last, 0.0f).count, 0u);
}

// `edit --script` with `time T` shows what `render --time T` renders (the same method, view
// and size), and `play` renders every frame it passes.
TEST(EditAnimated, ScriptTimeShowsWhatRenderRenders) {
    const std::string scene = spinScene().string();
    const std::string script = test::tmpPath("anim-time.script").string();
    const std::string edited = test::tmpPath("anim-edit.png").string();
    const std::string rendered = test::tmpPath("anim-render.png").string();
    test::writeText(script, "play 6\ntime 1.5\nscreenshot " + edited + "\n");
    std::string err;
    ASSERT_EQ(test::spotshell("edit --scene " + scene + " --script " + script, &err), 0) << err;
    ASSERT_EQ(test::spotshell("render --scene " + scene + " --time 1.5 --out " + rendered, &err), 0)
        << err;
    const noise::Image a = noise::readImage(edited), b = noise::readImage(rendered);
    ASSERT_EQ(a.width, b.width);
    ASSERT_EQ(a.height, b.height);
    const Difference d = difference(a, b, 1.0f / 255.0f);
    EXPECT_EQ(d.count, 0u) << "edit at t = 1.5 differs from render --time 1.5";
}

} // namespace

namespace spot {
namespace {

// The character Blender exports (examples/character/): the editor's timeline spans Blender's
// frames 1 to 25 (the clip starts at 1/24 s), a brush arms every slot in turn without compiling
// in the arming (the pipelines compile on their own threads; the armed kinds differ: the comb's
// tangent, the density's noise, the length's constant), and a stroke after them paints and
// regenerates as ever.
TEST(EditAnimated, TheCharactersTimelineArmingAndAStroke) {
    edit::Session s(std::filesystem::path(SPOT_SOURCE_DIR) / "examples/character/character-fur.json",
                    test::editOptions(96));
    ASSERT_TRUE(s.animated());
    const edit::Timeline line = s.timeline();
    EXPECT_EQ(line.frame(line.start), 1);
    EXPECT_EQ(line.frame(line.end), 25);
    for (const edit::BrushKind kind :
         {edit::BrushKind::Comb, edit::BrushKind::DensityErase, edit::BrushKind::Length}) {
        const edit::EditCost cost = s.setBrushKind(kind);
        EXPECT_TRUE(cost.armed);
        std::printf("arming %d on the character: %.3f ms\n", int(kind), cost.milliseconds);
    }
    s.setBrushKind(edit::BrushKind::DensityErase);
    const std::vector<noise::Impulse> before = s.generator().generate();
    const glm::vec2 centre(48.0f, 48.0f);
    ASSERT_TRUE(s.pick(centre)) << "the character is not in the middle of the view";
    s.brush().strength = 1.0f;
    const edit::EditCost cost = s.stroke({centre, centre + glm::vec2(6.0f, 0.0f)});
    EXPECT_GT(cost.voxelsWritten, 0u);
    noise::Image image;
    s.render(&image);
    EXPECT_LT(s.generator().generate().size(), before.size()) << "the stroke erased nothing";
    test::expectNoValidationErrors(s.context());
}

} // namespace
} // namespace spot
