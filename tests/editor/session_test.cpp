// The editor session on the furry bunny: what strokes do to the impulses (erase, comb), undo and
// redo, save and load, lobe edits, CPU and GPU agreement on painted fields, bounded undo memory.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>

#include <gtest/gtest.h>

#include "edit_test_support.h"
#include "noise/error.h"
#include "noise/preset.h"
#include "noise/shared_data.h"
#include "splat/generate_vk.h"

namespace {

using namespace spot;
using test::editOptions;

constexpr float kPi = 3.14159265358979f;

/// Whether an impulse's anchor faces the camera clearly (the brush skips back faces, and the
/// voxels' normals differ slightly from the impulses').
bool facing(const noise::Impulse& i, glm::vec3 eye) {
    const glm::vec3 anchor = i.position - i.height * i.normal;
    return glm::dot(i.normal, glm::normalize(eye - anchor)) > 0.3f;
}

glm::vec3 anchorOf(const noise::Impulse& i) {
    return i.position - i.height * i.normal;
}

// An erase stroke (strength 1, constant falloff) leaves no impulse under the brush; beyond its
// radius plus the trilinear lookup's reach the impulses are bit-identical.
TEST(EditSession, EraseLeavesNoImpulseUnderTheBrush) {
    edit::Session s(test::bunnyScene(), editOptions());
    // A first stroke that changes no value makes the density painted (an unchanged layer over
    // the noise), so the comparison below sees only the erase.
    s.brush().kind = edit::BrushKind::DensityAdd;
    s.brush().strength = 0.0f;
    s.stroke({{20.0f, 20.0f}});
    ASSERT_NE(s.grid(edit::Slot::Density), nullptr);
    const std::vector<noise::Impulse> before = s.generator().generate();

    const glm::vec2 at(128.0f, 120.0f);
    const std::optional<edit::Hit> hit = s.pick(at);
    ASSERT_TRUE(hit);
    s.brush() = {};
    s.brush().kind = edit::BrushKind::DensityErase;
    s.brush().radiusPx = 20.0f;
    s.brush().strength = 1.0f;
    s.brush().falloff = edit::Falloff::Constant;
    const edit::EditCost cost = s.stroke({at});
    EXPECT_EQ(cost.dabs, 1u);
    EXPECT_GT(cost.voxelsWritten, 0u);
    const std::vector<noise::Impulse> after = s.generator().generate();

    const float radius = test::worldRadius(s, *hit, 20.0f);
    const float voxel = s.grid(edit::Slot::Density)->voxelSize();
    const float reach =
        2.0f * std::sqrt(3.0f) * voxel; // trilinear lookup plus the near-surface band
    const glm::vec3 eye(s.camera().eye);
    std::size_t under = 0, underBefore = 0;
    std::vector<noise::Impulse> outsideBefore, outsideAfter;
    for (const noise::Impulse& i : before) {
        const float d = glm::length(anchorOf(i) - hit->position);
        underBefore += d < radius - reach && facing(i, eye);
        if (d > radius + reach)
            outsideBefore.push_back(i);
    }
    for (const noise::Impulse& i : after) {
        const float d = glm::length(anchorOf(i) - hit->position);
        under += d < radius - reach && facing(i, eye);
        if (d > radius + reach)
            outsideAfter.push_back(i);
    }
    std::printf("erase: radius %.4f world units (voxel %.4f), %zu impulses under the brush before, "
                "%zu after; %zu outside\n",
                radius, voxel, underBefore, under, outsideAfter.size());
    EXPECT_GT(underBefore, 20u) << "the brush must cover impulses for the test to mean something";
    EXPECT_EQ(under, 0u);
    test::expectSameImpulses(outsideBefore, outsideAfter, "outside the brush");
    test::expectNoValidationErrors(s.context());
}

// A comb stroke turns the impulses under it to the stroke's direction projected on the tangent
// plane (mean angle error below 10 degrees).
TEST(EditSession, CombFollowsTheStroke) {
    edit::Session s(test::bunnyScene(), editOptions());
    s.brush().kind = edit::BrushKind::Comb;
    s.brush().radiusPx = 24.0f;
    s.brush().strength = 1.0f;
    s.brush().falloff = edit::Falloff::Constant;
    const glm::vec2 from(100.0f, 120.0f), to(156.0f, 120.0f);
    s.stroke({from, to});
    ASSERT_NE(s.grid(edit::Slot::Comb), nullptr);
    const std::optional<edit::Hit> mid = s.pick(0.5f * (from + to));
    ASSERT_TRUE(mid);
    const float radius = test::worldRadius(s, *mid, 24.0f);
    // The stroke runs along the screen's +x: the camera's right vector in the world.
    const glm::dvec3 forward = glm::normalize(s.camera().target - s.camera().eye);
    const glm::vec3 right(glm::normalize(glm::cross(forward, s.camera().up)));
    const glm::vec3 eye(s.camera().eye);
    double sum = 0.0;
    std::size_t n = 0;
    for (const noise::Impulse& i : s.generator().generate()) {
        if (glm::length(anchorOf(i) - mid->position) > 0.5f * radius || !facing(i, eye))
            continue;
        const glm::vec3 want = glm::normalize(right - i.normal * glm::dot(right, i.normal));
        sum += std::acos(std::clamp(glm::dot(glm::normalize(i.comb), want), -1.0f, 1.0f));
        ++n;
    }
    ASSERT_GT(n, 10u);
    const double meanDeg = sum / double(n) * 180.0 / kPi;
    std::printf("comb: %zu impulses under the stroke, mean angle to the stroke %.2f degrees\n", n,
                meanDeg);
    EXPECT_LT(meanDeg, 10.0);
    test::expectNoValidationErrors(s.context());
}

// Undo restores the impulses, the grids and the preset bit for bit; redo re-applies.
TEST(EditSession, UndoRestoresBitIdenticalState) {
    edit::Session s(test::bunnyScene(), editOptions());
    const nlohmann::json json0 = s.presetJson();
    const std::vector<noise::Impulse> impulses0 = s.generator().generate();

    s.brush().kind = edit::BrushKind::DensityErase;
    s.brush().radiusPx = 18.0f;
    s.stroke({{110.0f, 110.0f}, {150.0f, 130.0f}});
    const auto density1 = test::voxels(s.grid(edit::Slot::Density));
    const std::vector<noise::Impulse> impulses1 = s.generator().generate();
    s.brush().kind = edit::BrushKind::DensityAdd;
    s.brush().strength = 0.7f;
    s.stroke({{120.0f, 100.0f}, {140.0f, 140.0f}});
    s.brush().kind = edit::BrushKind::Comb;
    s.stroke({{100.0f, 150.0f}, {160.0f, 150.0f}});
    s.set("distribution.density_max", 6000);
    const nlohmann::json json4 = s.presetJson();
    const auto density4 = test::voxels(s.grid(edit::Slot::Density));
    const auto comb4 = test::voxels(s.grid(edit::Slot::Comb));
    const std::vector<noise::Impulse> impulses4 = s.generator().generate();
    EXPECT_TRUE(s.dirty());
    EXPECT_EQ(s.undoSteps(), 4u);

    // Undoing a slot's first stroke arms it again when it is the brush's.
    s.setBrushKind(edit::BrushKind::DensityErase);
    ASSERT_TRUE(s.undo()); // the parameter
    ASSERT_TRUE(s.undo()); // the comb stroke (and the comb grid it created)
    EXPECT_EQ(s.grid(edit::Slot::Comb), nullptr);
    ASSERT_TRUE(s.undo()); // the second density stroke
    EXPECT_EQ(test::voxels(s.grid(edit::Slot::Density)), density1);
    test::expectSameImpulses(s.generator().generate(), impulses1, "after undoing to stroke 1");
    ASSERT_TRUE(s.undo()); // the first stroke, which made the density painted
    EXPECT_EQ(s.grid(edit::Slot::Density), nullptr);
    EXPECT_NE(s.armedLayer(edit::Slot::Density), nullptr);
    EXPECT_EQ(s.presetJson(), json0);
    test::expectSameImpulses(s.generator().generate(), impulses0, "after undoing everything");
    EXPECT_FALSE(s.undo());
    EXPECT_FALSE(s.dirty());

    for (int i = 0; i < 4; ++i)
        ASSERT_TRUE(s.redo());
    EXPECT_FALSE(s.redo());
    EXPECT_EQ(s.presetJson(), json4);
    EXPECT_EQ(test::voxels(s.grid(edit::Slot::Density)), density4);
    EXPECT_EQ(test::voxels(s.grid(edit::Slot::Comb)), comb4);
    test::expectSameImpulses(s.generator().generate(), impulses4, "after redoing everything");
    test::expectNoValidationErrors(s.context());
}

// Save writes the preset and its grids; both the generator and a new session loading them give
// the same impulses.
TEST(EditSession, SaveAndLoadRoundTrip) {
    const std::filesystem::path file = test::tmpPath("edit_roundtrip.json");
    std::filesystem::remove(file);
    std::vector<noise::Impulse> painted;
    {
        edit::Session s(test::bunnyScene(), editOptions());
        s.brush().kind = edit::BrushKind::DensityErase;
        s.brush().strength = 0.8f;
        s.stroke({{110.0f, 110.0f}, {150.0f, 130.0f}});
        s.brush().kind = edit::BrushKind::Comb;
        s.stroke({{100.0f, 150.0f}, {160.0f, 140.0f}});
        s.brush().kind = edit::BrushKind::Color;
        s.brush().color = glm::vec3(0.9f, 0.2f, 0.1f);
        s.stroke({{120.0f, 90.0f}, {130.0f, 160.0f}});
        s.brush().kind = edit::BrushKind::Length;
        s.stroke({{140.0f, 90.0f}, {140.0f, 160.0f}});
        s.brush().kind = edit::BrushKind::Tilt;
        s.stroke({{90.0f, 130.0f}, {170.0f, 130.0f}});
        EXPECT_TRUE(s.dirty());
        s.save(file);
        EXPECT_FALSE(s.dirty());
        painted = s.generator().generate();
    }
    ASSERT_TRUE(std::filesystem::exists(file));
    ASSERT_TRUE(std::filesystem::exists(test::tmpPath("edit_roundtrip.vdb")));

    const noise::SceneDesc scene = noise::loadScene(test::bunnyScene());
    const noise::Mesh mesh = noise::loadMeshOrGenerated(scene.mesh);
    noise::GeneratorOptions options;
    options.seed = scene.seed;
    const noise::ImpulseGenerator loaded(mesh, noise::loadPreset(file), options);
    test::expectSameImpulses(loaded.generate(), painted, "the saved preset, loaded");

    edit::SessionOptions o = editOptions();
    o.preset = file;
    edit::Session again(test::bunnyScene(), o);
    EXPECT_NE(again.grid(edit::Slot::Density), nullptr);
    test::expectSameImpulses(again.generator().generate(), painted,
                             "a session on the saved preset");
    EXPECT_FALSE(again.dirty());
}

// A lobe edit changes the rendered image (and undoing it restores the image).
// The viewport's right drag: the key light turns by the drag, its elevation kept off the poles,
// and an unlit session turns lit first with the default key light; the document is not edited.
TEST(EditSession, TurningTheKeyLightLightsTheSessionAndMovesTheLight) {
    edit::Session s(test::bunnyScene(), editOptions(64));
    ASSERT_TRUE(s.lit()); // fur-bunny is lit
    s.setLit(false);
    ASSERT_FALSE(s.lit());
    s.turnKeyLight(10.0f, 5.0f);
    ASSERT_TRUE(s.lit());
    s.setKeyLight(30.0f, 40.0f, 2.0f, true);
    s.turnKeyLight(-50.0f, 20.0f);
    edit::Session::KeyLight k = s.keyLight();
    EXPECT_NEAR(k.azimuthDeg, -20.0f, 1e-3f);
    EXPECT_NEAR(k.elevationDeg, 60.0f, 1e-3f);
    EXPECT_EQ(k.intensity, 2.0f);
    EXPECT_TRUE(k.shadows);
    s.turnKeyLight(350.0f, 100.0f); // azimuth wraps, elevation stops short of the pole
    k = s.keyLight();
    EXPECT_NEAR(k.azimuthDeg, -30.0f, 1e-3f);
    EXPECT_NEAR(k.elevationDeg, 89.0f, 1e-3f);
    EXPECT_THROW(s.turnKeyLight(std::nanf(""), 0.0f), InputError);
    EXPECT_FALSE(s.dirty());
}

TEST(EditSession, LobeEditChangesTheImage) {
    edit::Session s(test::bunnyScene(), editOptions(128));
    noise::Image before, after, undone;
    s.render(&before);
    const edit::EditCost cost = s.setLobe(2, "color", {0.0, 0.9, 0.1});
    EXPECT_TRUE(cost.generatorRebuilt);
    s.render(&after);
    s.undo();
    s.render(&undone);
    double changed = 0.0, restored = 0.0;
    for (std::size_t i = 0; i < before.pixels.size(); ++i) {
        changed += glm::length(after.pixels[i] - before.pixels[i]);
        restored += glm::length(undone.pixels[i] - before.pixels[i]);
    }
    changed /= double(before.pixels.size());
    restored /= double(before.pixels.size());
    std::printf("lobe edit: rebuilt in %.1f ms, mean pixel change %.4g, after undo %.4g\n",
                cost.milliseconds, changed, restored);
    EXPECT_GT(changed, 1e-3);
    EXPECT_LT(restored, 1e-6);
    test::expectNoValidationErrors(s.context());
}

// The painted fields give the same impulses on the GPU as on the CPU after strokes of every kind.
TEST(EditSession, PaintedFieldsSameOnCpuAndGpu) {
    edit::Session s(test::bunnyScene(), editOptions());
    s.brush().kind = edit::BrushKind::DensityErase;
    s.brush().strength = 0.6f;
    s.stroke({{110.0f, 110.0f}, {150.0f, 130.0f}});
    s.brush().kind = edit::BrushKind::Comb;
    s.stroke({{100.0f, 150.0f}, {160.0f, 140.0f}});
    s.brush().kind = edit::BrushKind::Tilt;
    s.stroke({{90.0f, 130.0f}, {170.0f, 130.0f}});
    s.brush().kind = edit::BrushKind::Length;
    s.brush().strength = -0.5f;
    s.stroke({{140.0f, 90.0f}, {140.0f, 160.0f}});
    s.brush().kind = edit::BrushKind::Color;
    s.brush().color = glm::vec3(0.2f, 0.3f, 0.9f);
    s.stroke({{120.0f, 90.0f}, {130.0f, 160.0f}});
    s.brush().kind = edit::BrushKind::Smooth;
    s.brush().smoothTarget = edit::Slot::Density;
    s.stroke({{110.0f, 110.0f}, {150.0f, 130.0f}});

    const std::vector<noise::Impulse> cpu = s.generator().generate();
    splat::GpuGenerator gpuGenerator(s.context(), s.mesh(), s.generator());
    const splat::GpuImpulses gpu = gpuGenerator.generate();
    ASSERT_EQ(gpu.count, cpu.size());
    const auto* g = static_cast<const gpu::SpotImpulse*>(gpu.impulses.mapped());
    double worst = 0.0;
    for (std::size_t i = 0; i < cpu.size(); ++i) {
        const noise::Impulse m = gpu::fromGpu(g[i]);
        ASSERT_EQ(m.cell, cpu[i].cell) << i;
        ASSERT_EQ(m.triangle, cpu[i].triangle) << i;
        worst = std::max(worst, double(glm::length(m.position - cpu[i].position)));
        EXPECT_NEAR(glm::length(m.scale - cpu[i].scale), 0.0f, 1e-4f * glm::length(cpu[i].scale));
        EXPECT_NEAR(glm::length(m.color - cpu[i].color), 0.0f, 1e-4f);
        EXPECT_GT(glm::dot(m.frame[2], cpu[i].frame[2]), 0.9999f);
    }
    EXPECT_LE(worst, 1e-5 * s.generator().cellSize());
    test::expectNoValidationErrors(s.context());
}

// 100 strokes and their undo: the history keeps them all within its budget; the session's bytes
// and the process's peak are reported.
TEST(EditSession, HundredStrokesKeepMemoryBounded) {
    edit::Session s(test::bunnyScene(), editOptions());
    s.brush().kind = edit::BrushKind::DensityErase;
    s.brush().radiusPx = 16.0f;
    s.brush().strength = 0.3f;
    const auto start = std::chrono::steady_clock::now();
    for (int i = 0; i < 100; ++i) {
        const float y = 110.0f + float(i % 10) * 3.0f, x = 110.0f + float(i / 10) * 2.0f;
        s.stroke({{x, y}, {x + 12.0f, y + 4.0f}});
    }
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    EXPECT_EQ(s.undoSteps(), 100u);
    const std::size_t bytes = s.memoryBytes(), undoBytes = s.undoBytes();
    int undone = 0;
    while (s.undo())
        ++undone;
    EXPECT_EQ(undone, 100);
    std::printf("100 strokes in %.2f s: session %zu bytes (undo %zu), peak RSS %.1f MiB\n", seconds,
                bytes, undoBytes, double(edit::peakResidentBytes()) / double(1 << 20));
    RecordProperty("session_bytes", std::to_string(bytes));
    EXPECT_LT(undoBytes, std::size_t(64) << 20);
    EXPECT_EQ(s.grid(edit::Slot::Density), nullptr);
}

} // namespace

namespace {

// Wind bends the combs with time, the same for the same time, and turning it off restores the
// document's impulses.
TEST(EditSession, WindIsDeterministicInTime) {
    edit::Session s(test::bunnyScene(), editOptions(64));
    const std::vector<noise::Impulse> still = s.generator().generate();
    s.setWind(true, 30.0f, 0.5f);
    s.setTime(0.25);
    s.render();
    const std::vector<noise::Impulse> a = s.generator().generate();
    s.setTime(1.25);
    s.render();
    const std::vector<noise::Impulse> b = s.generator().generate();
    s.setTime(0.25);
    s.render();
    test::expectSameImpulses(s.generator().generate(), a, "the same time again");
    ASSERT_EQ(a.size(), b.size());
    std::size_t moved = 0;
    for (std::size_t i = 0; i < a.size(); ++i)
        moved += glm::dot(a[i].comb, b[i].comb) < 0.999f;
    std::printf("wind: %zu of %zu combs moved between t = 0.25 s and 1.25 s\n", moved, a.size());
    EXPECT_GT(moved, a.size() / 2);
    s.setWind(false);
    test::expectSameImpulses(s.generator().generate(), still, "wind off");
    test::expectNoValidationErrors(s.context());
}

} // namespace

namespace {

/// A scene of the uniform preset on the unit sphere seen from +z, written to the test folder.
std::filesystem::path sphereScene() {
    const std::filesystem::path file = test::tmpPath("edit_sphere_scene.json");
    test::writeText(file, R"({"version": 1, "name": "edit-sphere", "mesh": "generated:sphere",
        "preset": ")" + (std::filesystem::path(SPOT_SOURCE_DIR) / "presets/uniform.json").string() +
                              R"(", "seed": 3,
        "camera": {"eye": [0, 0, 4], "target": [0, 0, 0], "up": [0, 1, 0], "fov_deg": 35},
        "image": {"width": 128, "height": 128}})");
    return file;
}

TEST(EditBrush, FalloffWeights) {
    using edit::Falloff;
    EXPECT_EQ(edit::falloffWeight(Falloff::Smooth, 0.0f), 1.0f);
    EXPECT_EQ(edit::falloffWeight(Falloff::Smooth, 0.5f), 0.5f);
    EXPECT_EQ(edit::falloffWeight(Falloff::Smooth, 1.0f), 0.0f);
    EXPECT_EQ(edit::falloffWeight(Falloff::Linear, 0.25f), 0.75f);
    EXPECT_EQ(edit::falloffWeight(Falloff::Constant, 0.999f), 1.0f);
    EXPECT_EQ(edit::falloffWeight(Falloff::Constant, 1.001f), 0.0f);
}

// X-mirror erases at the mirrored point too; front-faces-only spares the far side of the sphere
// even where the brush's radius reaches through it.
TEST(EditSession, MirrorAndFrontFaces) {
    edit::Session s(sphereScene(), editOptions(128));
    const glm::vec2 at(84.0f, 64.0f); // right of the centre: x > 0 on the sphere
    const std::optional<edit::Hit> hit = s.pick(at);
    ASSERT_TRUE(hit);
    EXPECT_GT(hit->position.x, 0.2f);
    EXPECT_NEAR(glm::length(hit->position), 1.0f, 0.01f);
    s.brush().kind = edit::BrushKind::DensityErase;
    s.brush().falloff = edit::Falloff::Constant;
    s.brush().radiusPx = 12.0f;
    s.brush().mirrorX = true;
    s.stroke({at});
    const float radius = test::worldRadius(s, *hit, 12.0f);
    const float reach = 2.0f * std::sqrt(3.0f) * s.grid(edit::Slot::Density)->voxelSize();
    const glm::vec3 mirrored(-hit->position.x, hit->position.y, hit->position.z);
    std::size_t under = 0, underMirror = 0, near = 0;
    for (const noise::Impulse& i : s.generator().generate()) {
        under += glm::length(anchorOf(i) - hit->position) < radius - reach;
        underMirror += glm::length(anchorOf(i) - mirrored) < radius - reach;
        near += glm::length(anchorOf(i) - hit->position) < radius + 0.5f;
    }
    EXPECT_EQ(under, 0u);
    EXPECT_EQ(underMirror, 0u);
    EXPECT_GT(near, 100u);

    // A brush wider than the sphere at its centre: the front half is erased, the back half stays.
    s.brush().mirrorX = false;
    s.brush().radiusPx = 200.0f;
    s.stroke({{64.0f, 64.0f}});
    std::size_t front = 0, back = 0;
    for (const noise::Impulse& i : s.generator().generate()) {
        const glm::vec3 p = anchorOf(i);
        front += p.z > 0.3f;
        back += p.z < -0.3f;
    }
    std::printf("front faces: %zu impulses left on the front, %zu on the back\n", front, back);
    EXPECT_EQ(front, 0u);
    EXPECT_GT(back, 1000u);
    test::expectNoValidationErrors(s.context());
}

} // namespace

namespace {

// Parameter edits: a rejected value leaves the session as it was; lobes can be added up to the
// kernel's limit and removed down to one; each edit is one undo step.
TEST(EditSession, ParameterEditsAreCheckedAndUndoable) {
    edit::Session s(test::bunnyScene(), editOptions(64));
    const nlohmann::json json0 = s.presetJson();
    EXPECT_THROW(s.set("distribution.density_max", -5), InputError);
    EXPECT_THROW(s.set("distribution.no_such_key", 1), InputError);
    EXPECT_THROW(s.set("nowhere.at_all", 1), InputError);
    EXPECT_THROW(s.setLobe(7, "sigma", {1, 1, 1}), InputError);
    EXPECT_EQ(s.presetJson(), json0);
    EXPECT_EQ(s.undoSteps(), 0u);
    EXPECT_FALSE(s.dirty());

    const edit::EditCost cost = s.set("variation.tilt_deg", 25);
    EXPECT_TRUE(cost.generatorRebuilt);
    EXPECT_EQ(s.preset().variation.tiltDeg, 25.0f);
    while (s.preset().kernel.lobes.size() < std::size_t(noise::kMaxLobes))
        s.addLobe(0);
    EXPECT_THROW(s.addLobe(0), InputError);
    s.removeLobe(1);
    EXPECT_EQ(s.preset().kernel.lobes.size(), std::size_t(noise::kMaxLobes - 1));
    s.render();
    while (s.undo()) {
    }
    EXPECT_EQ(s.presetJson(), json0);
    EXPECT_EQ(s.preset().kernel.lobes.size(), 3u);
    EXPECT_FALSE(s.dirty());
    test::expectNoValidationErrors(s.context());
}

} // namespace

namespace {

// Strokes regenerate only the cells whose impulses read the voxels they changed: after strokes,
// with and without frames in between, and an undo, the frame's impulses are still those the CPU
// generates for the visible cells.
TEST(EditSession, PartialRegenerationMatchesTheCpu) {
    edit::Session s(test::bunnyScene(), editOptions(128));
    s.brush().kind = edit::BrushKind::DensityErase;
    s.brush().radiusPx = 8.0f;
    s.brush().strength = 0.7f;
    s.stroke({{40.0f, 40.0f}}); // creates the grid (a rebuild)
    s.render();
    s.stroke({{55.0f, 60.0f}, {75.0f, 62.0f}});
    s.render();
    s.stroke({{60.0f, 70.0f}, {70.0f, 50.0f}});
    s.brush().kind = edit::BrushKind::DensityAdd;
    s.stroke({{50.0f, 66.0f}, {72.0f, 58.0f}}); // two strokes before the next frame
    splat::FrameStats stats = s.render();
    EXPECT_TRUE(stats.regenerated);
    std::printf("partial regeneration: %u of %u visible cells generated again\n",
                stats.cellsGenerated, stats.visibleCells);
    s.undo();
    stats = s.render();
    EXPECT_TRUE(stats.regenerated);

    const noise::CameraRays rays(s.camera());
    const std::vector<noise::Impulse> cpu = s.generator().generate(
        [&](const noise::SurfaceCell& cell) { return s.frame().cellVisible(rays, cell); });
    const splat::ImpulseSet set = s.frame().generator().impulses();
    ASSERT_EQ(s.frame().generator().count(), cpu.size());
    const auto* g = static_cast<const gpu::SpotImpulse*>(set.impulses->mapped());
    double worst = 0.0;
    for (std::size_t i = 0; i < cpu.size(); ++i) {
        const noise::Impulse m = gpu::fromGpu(g[i]);
        ASSERT_EQ(m.cell, cpu[i].cell) << i;
        ASSERT_EQ(m.triangle, cpu[i].triangle) << i;
        worst = std::max(worst, double(glm::length(m.position - cpu[i].position)));
    }
    EXPECT_LE(worst, 1e-5 * s.generator().cellSize());
    test::expectNoValidationErrors(s.context());
}

} // namespace

namespace {

// The window's pointer events: press, drags and release make one stroke in the event's view; a
// modifier at the press inverts the length brush (shrink).
TEST(EditSession, PointerEventsWithAModifierShrink) {
    edit::Session s(test::bunnyScene(), editOptions(128));
    noise::Camera view = s.camera();
    view.width = view.height = 256; // the window is larger than the session's image
    s.brush().kind = edit::BrushKind::Length;
    s.brush().radiusPx = 30.0f;
    s.brush().strength = 1.0f;
    s.brush().falloff = edit::Falloff::Constant;
    using P = edit::Session::PointerPhase;
    s.pointer(P::Press, {120.0f, 120.0f}, view, true);
    s.pointer(P::Drag, {130.0f, 124.0f}, view, true);
    s.pointer(P::Drag, {140.0f, 128.0f}, view, true);
    EXPECT_TRUE(s.stroking());
    s.pointer(P::Release, {140.0f, 128.0f}, view, true);
    EXPECT_FALSE(s.stroking());
    EXPECT_EQ(s.camera().width, 256);
    EXPECT_EQ(s.undoSteps(), 1u);
    const noise::PaintedGrid* scale = s.grid(edit::Slot::Scale);
    ASSERT_NE(scale, nullptr);
    std::size_t shrunk = 0, grown = 0;
    scale->forEachActive([&](glm::ivec3, glm::vec3 v) {
        shrunk += v.x < 0.02f * 0.999f;
        grown += v.x > 0.02f * 1.001f;
    });
    EXPECT_GT(shrunk, 10u);
    EXPECT_EQ(grown, 0u);
}

} // namespace

namespace {

/// What `session` writes when saved to `name` (the preset's text).
std::string savedText(edit::Session& session, const std::string& name) {
    const std::filesystem::path file = test::tmpPath(name);
    std::filesystem::remove(file);
    session.save(file);
    std::ifstream in(file);
    return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

} // namespace

// Arming a constant field's slot (tilt_deg 35) makes its empty paint layer and compiles the
// layered pipeline: the impulses stay bit for bit, the document is unchanged (not dirty, no undo
// step, saving writes the constant back and no .vdb). The first stroke then rebuilds nothing
// (it binds the layer), and undoing it returns to the armed state.
TEST(EditSession, ArmingAConstantFieldKeepsTheImpulses) {
    edit::SessionOptions o = editOptions();
    o.armBrush = false;
    edit::Session s(test::bunnyScene(), o);
    const nlohmann::json json0 = s.presetJson();
    const std::string saved0 = savedText(s, "edit_arm_unarmed.json");
    const std::vector<noise::Impulse> impulses0 = s.generator().generate();
    EXPECT_EQ(s.armedLayer(edit::Slot::Tilt), nullptr);

    const edit::EditCost arm = s.setBrushKind(edit::BrushKind::Tilt);
    std::printf("arming tilt_deg (constant): %.1f ms\n", arm.milliseconds);
    EXPECT_TRUE(arm.armed);
    // Paint layers: an empty layer is exact over any field, so arming binds nothing and rebuilds
    // nothing (a grid standing in for the constant was bound, with a rebuild, before layers).
    EXPECT_FALSE(arm.generatorRebuilt);
    ASSERT_NE(s.armedLayer(edit::Slot::Tilt), nullptr);
    EXPECT_EQ(s.grid(edit::Slot::Tilt), nullptr) << "armed is not painted";
    test::expectSameImpulses(s.generator().generate(), impulses0, "after arming tilt");
    EXPECT_FALSE(s.dirty());
    EXPECT_EQ(s.undoSteps(), 0u);
    EXPECT_EQ(s.presetJson(), json0);
    std::filesystem::remove(test::tmpPath("edit_arm_armed.vdb"));
    EXPECT_EQ(savedText(s, "edit_arm_armed.json"), saved0);
    EXPECT_FALSE(std::filesystem::exists(test::tmpPath("edit_arm_armed.vdb")));
    EXPECT_FALSE(s.armBrush().armed) << "arming twice does nothing";

    s.brush().radiusPx = 20.0f;
    const edit::EditCost first = s.beginStroke({120.0f, 120.0f});
    s.dragStroke({150.0f, 130.0f});
    s.endStroke();
    EXPECT_FALSE(first.generatorRebuilt) << "the armed layer is bound without a rebuild";
    EXPECT_NE(s.grid(edit::Slot::Tilt), nullptr);
    EXPECT_EQ(s.armedLayer(edit::Slot::Tilt), nullptr);
    EXPECT_TRUE(s.dirty());
    EXPECT_EQ(s.undoSteps(), 1u);
    EXPECT_TRUE(s.presetJson()["fields"]["tilt_deg"].contains("paint"));
    EXPECT_EQ(s.presetJson()["fields"]["tilt_deg"]["base"], json0["fields"]["tilt_deg"]);

    ASSERT_TRUE(s.undo());
    EXPECT_EQ(s.grid(edit::Slot::Tilt), nullptr);
    EXPECT_NE(s.armedLayer(edit::Slot::Tilt), nullptr) << "undo returns to the armed state";
    EXPECT_EQ(s.presetJson(), json0);
    EXPECT_FALSE(s.dirty());
    test::expectSameImpulses(s.generator().generate(), impulses0, "after undoing the stroke");
    ASSERT_TRUE(s.redo());
    ASSERT_TRUE(s.undo());
    // Armed and bound again: a stroke rebuilds nothing.
    const edit::EditCost again = s.beginStroke({120.0f, 120.0f});
    s.endStroke();
    EXPECT_FALSE(again.generatorRebuilt);
    ASSERT_TRUE(s.undo());
    ASSERT_TRUE(s.redo());
    EXPECT_NE(s.grid(edit::Slot::Tilt), nullptr);
    EXPECT_EQ(s.armedLayer(edit::Slot::Tilt), nullptr);
    test::expectNoValidationErrors(s.context());
}

// The bunny's density is a noise field: arming makes the empty layer over it; the impulses stay
// bit for bit, the document as it was. The first stroke binds the layer without a new
// generator: its impulses are those of the saved stroke (a session loading the saved preset),
// and undoing it gives back the noise's impulses.
TEST(EditSession, ArmingASampledFieldKeepsTheImpulses) {
    edit::SessionOptions o = editOptions();
    o.armBrush = false;
    edit::Session s(test::bunnyScene(), o);
    const std::string saved0 = savedText(s, "edit_arm_noise_unarmed.json");
    const std::vector<noise::Impulse> impulses0 = s.generator().generate();

    const edit::EditCost arm = s.armBrush(); // density-add: the density slot
    std::printf("arming the noise density: %.1f ms\n", arm.milliseconds);
    EXPECT_TRUE(arm.armed);
    EXPECT_FALSE(arm.generatorRebuilt) << "the layer is not bound before the stroke";
    ASSERT_NE(s.armedLayer(edit::Slot::Density), nullptr);
    test::expectSameImpulses(s.generator().generate(), impulses0, "after arming the density");
    EXPECT_FALSE(s.dirty());
    EXPECT_EQ(s.undoSteps(), 0u);
    EXPECT_EQ(savedText(s, "edit_arm_noise_armed.json"), saved0);

    s.brush().kind = edit::BrushKind::DensityErase;
    s.brush().radiusPx = 20.0f;
    const edit::EditCost first = s.beginStroke({120.0f, 120.0f});
    s.dragStroke({150.0f, 130.0f});
    s.endStroke();
    EXPECT_FALSE(first.generatorRebuilt);
    ASSERT_NE(s.grid(edit::Slot::Density), nullptr);
    const std::vector<noise::Impulse> stroked = s.generator().generate();
    const std::filesystem::path file = test::tmpPath("edit_arm_noise_stroked.json");
    s.save(file);
    edit::SessionOptions again = o;
    again.preset = file;
    edit::Session loaded(test::bunnyScene(), again);
    test::expectSameImpulses(loaded.generator().generate(), stroked,
                             "a session on the saved first stroke");

    ASSERT_TRUE(s.undo());
    EXPECT_EQ(s.grid(edit::Slot::Density), nullptr);
    EXPECT_NE(s.armedLayer(edit::Slot::Density), nullptr) << "undo returns to the armed state";
    test::expectSameImpulses(s.generator().generate(), impulses0, "after undoing the stroke");
    test::expectNoValidationErrors(s.context());
}

// Switching brushes keeps only the new brush's slot armed; the impulses never move.
TEST(EditSession, SwitchingBrushesDisarmsTheOtherSlots) {
    edit::Session s(test::bunnyScene(), editOptions()); // arms the density at the start
    EXPECT_TRUE(s.startArmCost().armed);
    ASSERT_NE(s.armedLayer(edit::Slot::Density), nullptr);
    const std::vector<noise::Impulse> impulses0 = s.generator().generate();
    for (const edit::BrushKind kind :
         {edit::BrushKind::Tilt, edit::BrushKind::Comb, edit::BrushKind::Length,
          edit::BrushKind::Color, edit::BrushKind::DensityErase}) {
        const edit::EditCost cost = s.setBrushKind(kind);
        const edit::Slot slot = edit::brushSlot(s.brush());
        EXPECT_TRUE(cost.armed) << edit::brushKindName(kind);
        for (int t = 0; t < edit::kSlotCount; ++t)
            EXPECT_EQ(s.armedLayer(edit::Slot(t)) != nullptr, edit::Slot(t) == slot)
                << edit::brushKindName(kind) << " slot " << t;
        test::expectSameImpulses(s.generator().generate(), impulses0, edit::brushKindName(kind));
    }
    EXPECT_FALSE(s.dirty());
    EXPECT_EQ(s.undoSteps(), 0u);
}

namespace {

// A stroke to a point 1e9 pixels away ends: the drag is clipped to the window.
TEST(EditSession, StrokeFarOutsideTheWindowEnds) {
    edit::Session s(test::bunnyScene(), editOptions(128));
    s.brush().kind = edit::BrushKind::DensityErase;
    s.brush().radiusPx = 8.0f;
    const auto start = std::chrono::steady_clock::now();
    const edit::EditCost cost = s.stroke({{64.0f, 64.0f}, {1e9f, 64.0f}, {64.0f, 1e9f}});
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    // At most the dabs along the window's width and height (spacing: a quarter radius).
    EXPECT_LE(cost.dabs, 2u * (128u + 16u) / 2u + 3u);
    EXPECT_GT(cost.dabs, 10u);
    EXPECT_LT(seconds, 60.0);
    EXPECT_THROW(s.stroke({{64.0f, 64.0f}, {INFINITY, 64.0f}}), InputError);
}

} // namespace

namespace {

bool sameImpulse(const noise::Impulse& a, const noise::Impulse& b) {
    return a.position == b.position && a.normal == b.normal && a.comb == b.comb &&
           a.frame == b.frame && a.scale == b.scale && a.color == b.color &&
           a.weight == b.weight && a.bend == b.bend && a.cell == b.cell &&
           a.triangle == b.triangle && a.barycentric == b.barycentric &&
           a.clumpStrength == b.clumpStrength && a.clumpDistance == b.clumpDistance;
}

// Paint layers over the procedural fields: an erase stroke on fur's noise density keeps every
// impulse outside the brush bit for bit and adds none; undo gives back the original impulses bit
// for bit; the noise under the layer stays editable after the stroke.
TEST(EditSession, EraseKeepsEveryImpulseOutsideTheBrush) {
    edit::Session s(test::bunnyScene(), editOptions());
    ASSERT_EQ(s.preset().density.kind, noise::FieldDesc::Kind::Noise) << "fur's density is noise";
    const std::vector<noise::Impulse> before = s.generator().generate();
    const glm::vec2 at(128.0f, 120.0f);
    const std::optional<edit::Hit> hit = s.pick(at);
    ASSERT_TRUE(hit);
    s.brush().kind = edit::BrushKind::DensityErase;
    s.brush().radiusPx = 20.0f;
    s.brush().strength = 1.0f;
    s.brush().falloff = edit::Falloff::Constant;
    EXPECT_EQ(s.stroke({at}).dabs, 1u);
    ASSERT_NE(s.layer(edit::Slot::Density), nullptr);
    EXPECT_TRUE(s.presetJson()["fields"]["density"].contains("base"));
    const std::vector<noise::Impulse> after = s.generator().generate();

    const float radius = test::worldRadius(s, *hit, 20.0f);
    const auto outside = [&](const noise::Impulse& i) {
        return glm::length(i.position - hit->position) > radius;
    };
    std::vector<noise::Impulse> outsideBefore, outsideAfter;
    for (const noise::Impulse& i : before)
        if (outside(i))
            outsideBefore.push_back(i);
    for (const noise::Impulse& i : after)
        if (outside(i))
            outsideAfter.push_back(i);
    // None new: `after` is `before` less some impulses (both in generation order).
    std::size_t j = 0;
    for (const noise::Impulse& i : after) {
        while (j < before.size() && !sameImpulse(before[j], i))
            ++j;
        ASSERT_LT(j, before.size()) << "an impulse the erase added";
        ++j;
    }
    std::printf("erase on the noise density: %zu impulses before, %zu after, %zu outside the "
                "brush (radius %.4f)\n",
                before.size(), after.size(), outsideAfter.size(), radius);
    EXPECT_LT(after.size() + 20, before.size()) << "the brush must remove impulses";
    ASSERT_EQ(outsideAfter.size(), outsideBefore.size());
    for (std::size_t k = 0; k < outsideAfter.size(); ++k)
        ASSERT_TRUE(sameImpulse(outsideAfter[k], outsideBefore[k])) << k;

    // The noise stays editable under the layer; the erased patch stays erased.
    s.set("fields.density.base.frequency", 6.0);
    EXPECT_EQ(s.preset().density.frequency, 6.0f);
    const std::vector<noise::Impulse> edited = s.generator().generate();
    std::size_t under = 0;
    const float voxel = s.grid(edit::Slot::Density)->voxelSize();
    for (const noise::Impulse& i : edited)
        under += glm::length(i.position - hit->position) < radius - 2.0f * std::sqrt(3.0f) * voxel &&
                 facing(i, glm::vec3(s.camera().eye));
    EXPECT_EQ(under, 0u);
    EXPECT_NE(edited.size(), after.size());

    ASSERT_TRUE(s.undo()); // the frequency
    ASSERT_TRUE(s.undo()); // the erase
    test::expectSameImpulses(s.generator().generate(), before, "after undoing the erase");
    test::expectNoValidationErrors(s.context());
}

} // namespace
