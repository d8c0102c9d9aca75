// The editor's clump, clump-size and mask brushes (issue 44): a brush limited to the mask changes
// nothing outside it (bit-identical impulses there), the clump brush clumps only where it paints
// and undoes to the unclumped impulses, the mask overlay is a view, and scripts drive all of it.
#include <cmath>
#include <cstdio>
#include <fstream>

#include <gtest/gtest.h>

#include "edit_test_support.h"
#include "editor/edit_script.h"
#include "noise/error.h"
#include "noise/preset.h"
#include "shaders/spot_layout.hpp"

namespace {

using namespace spot;
using test::editOptions;

glm::vec3 anchorOf(const noise::Impulse& i) {
    return i.position - i.height * i.normal;
}

/// The impulses whose anchor passes `keep`, in generation order.
std::vector<noise::Impulse> where(const std::vector<noise::Impulse>& all,
                                  const std::function<bool(const noise::Impulse&)>& keep) {
    std::vector<noise::Impulse> out;
    for (const noise::Impulse& i : all)
        if (keep(i))
            out.push_back(i);
    return out;
}

/// A hard-edged procedural mask: 0 for x below `x0`, 1 from x0 + 1e-4 on.
nlohmann::json halfSpaceMask(float x0) {
    return {{"type", "gradient"},
            {"from", {x0, 0.0, 0.0}},
            {"to", {x0 + 1e-4, 0.0, 0.0}},
            {"values", {0.0, 1.0}}};
}

// An erase stroke across the mask's edge, limited to the masked side, keeps every impulse on the
// unmasked side bit for bit (beyond the trilinear lookup's reach of the edge) and erases on the
// masked side; limited to the unmasked side, the other way round. Undo restores everything.
TEST(EditMask, LimitedBrushChangesNothingOutsideTheMask) {
    edit::Session s(test::bunnyScene(), editOptions());
    const glm::vec2 at(128.0f, 120.0f);
    const std::optional<edit::Hit> hit = s.pick(at);
    ASSERT_TRUE(hit);
    const float x0 = hit->position.x;
    s.set("fields.mask", halfSpaceMask(x0));
    const std::vector<noise::Impulse> before = s.generator().generate();
    const std::size_t undoSteps = s.undoSteps();

    for (const edit::MaskLimit limit : {edit::MaskLimit::Masked, edit::MaskLimit::Unmasked}) {
        SCOPED_TRACE(edit::maskLimitName(limit));
        edit::BrushSettings b;
        b.kind = edit::BrushKind::DensityErase;
        b.radiusPx = 45.0f;
        b.strength = 1.0f;
        b.falloff = edit::Falloff::Constant;
        b.limit = limit;
        s.setBrush(b);
        s.stroke({at});
        const std::vector<noise::Impulse> after = s.generator().generate();
        // A voxel written has its surface point on the painted side: impulses farther than the
        // lookup's reach (a voxel along each axis, a voxel diagonal to the surface point) from
        // the edge read none of them.
        const float voxel = s.voxelSize();
        const float reach = 3.0f * voxel + 1e-4f;
        const bool maskedSide = limit == edit::MaskLimit::Masked;
        const auto protectedSide = [&](const noise::Impulse& i) {
            const float x = anchorOf(i).x;
            return maskedSide ? x < x0 - reach : x > x0 + reach;
        };
        const auto paintedSide = [&](const noise::Impulse& i) {
            const float x = anchorOf(i).x;
            return (maskedSide ? x > x0 + reach : x < x0 - reach) &&
                   glm::length(anchorOf(i) - hit->position) < 0.6f * test::worldRadius(s, *hit, 45.0f);
        };
        test::expectSameImpulses(where(after, protectedSide), where(before, protectedSide),
                                 "the side the limit protects");
        const std::size_t paintedBefore = where(before, paintedSide).size();
        const std::size_t paintedAfter = where(after, paintedSide).size();
        std::printf("limit %s: %zu impulses on the protected side kept bit for bit; on the painted "
                    "side near the dab %zu before, %zu after\n",
                    edit::maskLimitName(limit), where(after, protectedSide).size(), paintedBefore,
                    paintedAfter);
        EXPECT_GT(paintedBefore, 20u);
        EXPECT_LT(paintedAfter, paintedBefore / 4) << "the erase must work where it may paint";
        ASSERT_TRUE(s.undo());
        test::expectSameImpulses(s.generator().generate(), before, "after the undo");
    }
    EXPECT_EQ(s.undoSteps(), undoSteps);
    test::expectNoValidationErrors(s.context());
}

// The mask painted with the mask brush limits a later stroke the same way: a painted mask, then
// a tilt stroke limited to it over a larger area changes only the impulses that read the mask's
// painted voxels.
TEST(EditMask, PaintedMaskLimitsALaterStroke) {
    edit::Session s(test::bunnyScene(), editOptions());
    const glm::vec2 at(128.0f, 120.0f);
    const std::optional<edit::Hit> hit = s.pick(at);
    ASSERT_TRUE(hit);
    edit::BrushSettings mask;
    mask.kind = edit::BrushKind::Mask;
    mask.radiusPx = 12.0f;
    mask.falloff = edit::Falloff::Constant;
    s.setBrush(mask);
    const std::vector<noise::Impulse> start = s.generator().generate();
    s.stroke({at});
    ASSERT_NE(s.layer(edit::Slot::Mask), nullptr);
    // Painting the mask alone changes no impulse (no slot is limited to it).
    test::expectSameImpulses(s.generator().generate(), start, "after painting the mask");

    edit::BrushSettings tilt;
    tilt.kind = edit::BrushKind::Tilt;
    tilt.radiusPx = 40.0f;
    tilt.strength = 1.0f;
    tilt.limit = edit::MaskLimit::Masked;
    s.setBrush(tilt);
    s.stroke({at});
    const std::vector<noise::Impulse> after = s.generator().generate();
    ASSERT_EQ(after.size(), start.size());
    // The mask's voxels reach a mask radius plus a voxel diagonal; the tilt's written voxels
    // lie among them; impulses read voxels a voxel away along each axis.
    const float maskRadius = test::worldRadius(s, *hit, 12.0f);
    const float reach = maskRadius + 3.0f * s.voxelSize();
    std::size_t changed = 0, changedFar = 0;
    for (std::size_t i = 0; i < after.size(); ++i) {
        const bool differs = !test::sameImpulse(after[i], start[i]);
        changed += differs;
        changedFar += differs && glm::length(anchorOf(after[i]) - hit->position) > reach;
    }
    std::printf("a tilt stroke of radius 40 px limited to a mask of radius 12 px: %zu impulses "
                "changed, %zu of them beyond the mask\n",
                changed, changedFar);
    EXPECT_GT(changed, 10u);
    EXPECT_EQ(changedFar, 0u);
    test::expectNoValidationErrors(s.context());
}

// The clump brush on unclumped fur: only the impulses near the stroke get a clump strength (and
// their kernels turn), the others stay bit for bit; undo gives back the unclumped impulses; the
// clump-size brush then changes only what is near its own stroke; save and load give the same
// impulses.
TEST(EditClump, ClumpBrushClumpsOnlyWhereItPaints) {
    edit::Session s(test::bunnyScene(), editOptions());
    ASSERT_FALSE(s.preset().clumpDesc.on);
    const glm::vec2 at(128.0f, 120.0f);
    const std::optional<edit::Hit> hit = s.pick(at);
    ASSERT_TRUE(hit);
    const std::vector<noise::Impulse> before = s.generator().generate();
    edit::BrushSettings b;
    b.kind = edit::BrushKind::Clump;
    b.radiusPx = 25.0f;
    b.strength = 1.0f;
    s.setBrush(b);
    s.stroke({at, at + glm::vec2(20.0f, 0.0f)});
    ASSERT_TRUE(s.presetJson()["fields"]["clump"].contains("paint"));
    EXPECT_TRUE(s.preset().clumpDesc.on);
    const std::vector<noise::Impulse> after = s.generator().generate();
    ASSERT_EQ(after.size(), before.size());
    // The dabs lie along 20 pixels from the hit, each 25 pixels wide.
    const float reach = test::worldRadius(s, *hit, 45.0f) * 1.1f + 3.0f * s.voxelSize();
    std::size_t clumped = 0, far = 0, farChanged = 0;
    for (std::size_t i = 0; i < after.size(); ++i) {
        clumped += after[i].clumpStrength > 0.0f;
        if (after[i].clumpStrength > 0.0f) {
            EXPECT_EQ(after[i].position, before[i].position); // roots stay
            EXPECT_GT(after[i].clumpDistance, 0.0f);
        }
        const bool isFar = glm::length(anchorOf(after[i]) - hit->position) > reach;
        far += isFar;
        farChanged += isFar && !test::sameImpulse(after[i], before[i]);
    }
    std::printf("clump stroke: %zu impulses clumped, %zu far ones all kept (%zu changed)\n",
                clumped, far, farChanged);
    EXPECT_GT(clumped, 50u);
    EXPECT_GT(far, after.size() / 2);
    EXPECT_EQ(farChanged, 0u);

    // The clump-size brush: larger clumps under its stroke only. Clumps are 0.1 wide (the
    // default size) and a clump's seed thins out only where the relative size passes its rank,
    // so the stroke is wide and goes over the same place, the size there nearing 2.
    b.kind = edit::BrushKind::ClumpSize;
    b.radiusPx = 45.0f;
    s.setBrush(b);
    const glm::vec2 side(20.0f, 0.0f);
    s.stroke({at - side, at + side, at - side, at + side});
    const float sizeReach = test::worldRadius(s, *hit, 65.0f) * 1.1f + 3.0f * s.voxelSize();
    const std::vector<noise::Impulse> sized = s.generator().generate();
    std::size_t sizeChanged = 0, sizeChangedFar = 0;
    for (std::size_t i = 0; i < sized.size(); ++i) {
        const bool d = !test::sameImpulse(sized[i], after[i]);
        sizeChanged += d;
        sizeChangedFar += d && glm::length(anchorOf(sized[i]) - hit->position) > sizeReach;
    }
    std::printf("clump-size stroke: %zu impulses changed, %zu of them far\n", sizeChanged,
                sizeChangedFar);
    EXPECT_GT(sizeChanged, 10u);
    EXPECT_EQ(sizeChangedFar, 0u);

    // Saved and loaded, the same impulses.
    const std::filesystem::path file = test::tmpPath("clump-brush.json");
    s.save(file);
    {
        edit::SessionOptions o = editOptions();
        o.preset = file;
        edit::Session loaded(test::bunnyScene(), o);
        test::expectSameImpulses(loaded.generator().generate(), sized, "saved and loaded");
    }
    ASSERT_TRUE(s.undo());
    ASSERT_TRUE(s.undo());
    test::expectSameImpulses(s.generator().generate(), before, "undone to unclumped fur");
    EXPECT_FALSE(s.preset().clumpDesc.on);
    test::expectNoValidationErrors(s.context());
}

// A slot limited to the mask: the preset's clump strength applies only where the mask is set.
TEST(EditClump, ClumpFieldLimitedToTheMask) {
    edit::Session s(test::bunnyScene(), editOptions(128));
    const float x0 = 0.0f;
    s.set({{"fields.mask", halfSpaceMask(x0)},
           {"fields.clump", {{"base", 0.9}, {"mask", "inside"}}},
           {"clump", {{"size", 0.05}}}});
    std::size_t inside = 0, outside = 0;
    for (const noise::Impulse& i : s.generator().generate()) {
        const float x = anchorOf(i).x;
        if (x < x0)
            EXPECT_EQ(i.clumpStrength, 0.0f);
        else if (x > x0 + 1e-4f)
            EXPECT_EQ(i.clumpStrength, 0.9f);
        inside += i.clumpStrength > 0.0f;
        outside += i.clumpStrength == 0.0f;
    }
    EXPECT_GT(inside, 1000u);
    EXPECT_GT(outside, 1000u);
    // "outside" turns it round.
    s.set("fields.clump.mask", "outside");
    for (const noise::Impulse& i : s.generator().generate())
        if (anchorOf(i).x > x0 + 1e-4f)
            EXPECT_EQ(i.clumpStrength, 0.0f);
    test::expectNoValidationErrors(s.context());
}

// The overlay tints the impulses by the mask and is not an edit; off, the impulses are back.
TEST(EditMask, OverlayIsAViewNotAnEdit) {
    edit::Session s(test::bunnyScene(), editOptions(128));
    s.set("fields.mask", halfSpaceMask(0.0f));
    const std::vector<noise::Impulse> before = s.generator().generate();
    const std::size_t steps = s.undoSteps();
    const bool dirty = s.dirty();
    s.setMaskOverlay(true);
    noise::Image tinted;
    s.render(&tinted);
    const std::vector<noise::Impulse> shown = s.generator().generate();
    ASSERT_EQ(shown.size(), before.size());
    std::size_t redder = 0, same = 0;
    for (std::size_t i = 0; i < shown.size(); ++i) {
        const float x = anchorOf(shown[i]).x;
        if (x > 1e-4f)
            redder += shown[i].color.g < before[i].color.g && shown[i].color.r >= before[i].color.r * 0.99f;
        else if (x < 0.0f)
            same += test::sameImpulse(shown[i], before[i]);
    }
    EXPECT_GT(redder, 1000u);
    EXPECT_GT(same, 1000u);
    EXPECT_EQ(s.undoSteps(), steps);
    EXPECT_EQ(s.dirty(), dirty);
    s.setMaskOverlay(false);
    test::expectSameImpulses(s.generator().generate(), before, "overlay off");
    test::expectNoValidationErrors(s.context());
}

// The example script that paints a clump map (examples/clumps/paint-clumps.script) runs and
// saves a preset that loads back to the impulses of the session that saved it.
TEST(EditScript, PaintedClumpMapExampleRuns) {
    const std::filesystem::path dir = test::tmpPath("paint-clumps");
    std::filesystem::remove_all(dir);
    std::filesystem::create_directories(dir);
    const std::filesystem::path script =
        std::filesystem::path(SPOT_SOURCE_DIR) / "examples/clumps/paint-clumps.script";
    std::string text;
    {
        std::ifstream in(script);
        ASSERT_TRUE(in) << script;
        text.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
    }
    // Every file the script writes goes into the test's folder instead of the example's.
    const std::string from = "clumps/";
    ASSERT_NE(text.find("save " + from), std::string::npos);
    for (std::size_t at = text.find(from); at != std::string::npos; at = text.find(from, at)) {
        const std::string to = dir.string() + "/";
        text.replace(at, from.size(), to);
        at += to.size();
    }
    // The script's strokes are window points at the scene's size (256 x 256).
    edit::Session s(test::bunnyScene(), editOptions());
    const std::vector<edit::ScriptAction> actions = edit::parseScript(text, script.string());
    edit::runScript(s, actions, script.string(), nullptr);
    EXPECT_TRUE(s.preset().clumpDesc.on);
    ASSERT_NE(s.layer(edit::Slot::Clump), nullptr);
    ASSERT_NE(s.layer(edit::Slot::Mask), nullptr);
    EXPECT_TRUE(std::filesystem::exists(dir / "painted-clumps.vdb"));
    EXPECT_TRUE(std::filesystem::exists(dir / "painted-clumps.png"));
    EXPECT_TRUE(std::filesystem::exists(dir / "mask.png"));
    std::size_t clumped = 0;
    const std::vector<noise::Impulse> impulses = s.generator().generate();
    for (const noise::Impulse& i : impulses)
        clumped += i.clumpStrength > 0.0f;
    EXPECT_GT(clumped, 1000u);
    EXPECT_LT(clumped, impulses.size()); // a map, not everywhere
    edit::SessionOptions o = editOptions();
    o.preset = dir / "painted-clumps.json";
    edit::Session loaded(test::bunnyScene(), o);
    test::expectSameImpulses(loaded.generator().generate(), impulses, "the saved clump map");
    test::expectNoValidationErrors(s.context());
}

} // namespace
