// The persistent frame (splat/frame_vk.h): a warm frame allocates nothing and repeats the image,
// impulses are regenerated only when the cells the camera may see (or the level of detail)
// change, the pixels come back only when asked, methods come from the registry by name, and the
// splat pass counts its fragments.
#include <cstring>
#include <string>

#include <gtest/gtest.h>

#include "noise/error.h"
#include "splat/frame_vk.h"
#include "splat/passes/light_space_vk.h"
#include "splat_test_support.h"

namespace {

using namespace spot;
using namespace spot::test;

bool sameBytes(const noise::Image& a, const noise::Image& b) {
    return a.width == b.width && a.height == b.height &&
           std::memcmp(a.pixels.data(), b.pixels.data(), a.pixels.size() * sizeof(glm::vec3)) == 0;
}

TEST(Frame, WarmFramesAllocateNothingAndRepeatTheImage) {
    const FrameSetup s = loadFrameSetup("fur-bunny", 64);
    splat::Context ctx(validated());
    splat::Frame frame(ctx, s.mesh, *s.generator);
    for (const splat::MethodInfo& method : splat::gpuMethods()) {
        if (method.takes(splat::settings::bake))
            continue; // needs a bake file: tests/splat/baked_test.cpp
        splat::RenderSettings settings;
        noise::Image first, second;
        frame.render(method.name, s.view(), settings, &first); // cold: allocates what it needs
        const std::uint64_t bytes = ctx.allocatedBytes();
        const splat::FrameStats warm = frame.render(method.name, s.view(), settings, &second);
        EXPECT_EQ(ctx.allocatedBytes(), bytes) << method.name << ": a warm frame allocated";
        EXPECT_FALSE(warm.regenerated) << method.name;
        EXPECT_GT(warm.kernelsGenerated, 1000u) << method.name;
        EXPECT_TRUE(sameBytes(first, second)) << method.name;
        EXPECT_GT(warm.gpuMs, 0.0) << method.name;
        EXPECT_GE(warm.wallMs, warm.gpuMs * 0.99) << method.name;
    }
    expectNoValidationErrors(ctx);
}

TEST(Frame, RegeneratesOnlyWhenTheVisibleCellsOrTheLevelOfDetailChange) {
    const FrameSetup s = loadFrameSetup("fur-bunny-close", 48);
    splat::Context ctx(validated());
    splat::Frame frame(ctx, s.mesh, *s.generator);
    splat::RenderSettings settings;
    splat::View view = s.view();
    const splat::FrameStats first = frame.render("oit", view, settings);
    EXPECT_TRUE(first.regenerated);
    EXPECT_FALSE(frame.render("oit", view, settings).regenerated);
    EXPECT_FALSE(frame.render("hybrid", view, settings).regenerated); // another method, same cells
    // The whole bunny in view: more cells visible, so new impulses.
    const FrameSetup whole = loadFrameSetup("fur-bunny", 48);
    const splat::FrameStats wide = frame.render("oit", whole.view(), settings);
    EXPECT_TRUE(wide.regenerated);
    EXPECT_GT(wide.visibleCells, first.visibleCells);
    EXPECT_GT(wide.kernelsGenerated, first.kernelsGenerated);
    // The level of detail thins by distance, so it depends on the eye: new impulses.
    settings.lodPixels = 4.0;
    EXPECT_TRUE(frame.render("oit", whole.view(), settings).regenerated);
    EXPECT_FALSE(frame.render("oit", whole.view(), settings).regenerated);
    expectNoValidationErrors(ctx);
}

// Lit with shadows, a kernel out of view may shadow one in view (a close-up's neighbours, lit
// from beside the frame), so the camera culls no cell; unlit, or with no shadow, it culls.
TEST(Frame, WhenKernelsCastShadowsCellsOutOfViewAreGenerated) {
    const FrameSetup s = loadFrameSetup("fur-bunny-close", 48);
    const std::uint32_t cells = std::uint32_t(s.generator->cells().cells.size());
    splat::Context ctx(validated());
    splat::Frame frame(ctx, s.mesh, *s.generator);
    splat::RenderSettings settings;
    splat::View view = s.view();
    const splat::FrameStats unlit = frame.render("hybrid", view, settings);
    EXPECT_LT(unlit.visibleCells, cells * 3 / 4) << "the close-up sees part of the bunny";
    view.shading.mode = noise::Shading::Mode::Lit;
    view.shading.lights = {noise::Light{}};
    view.shading.lights[0].direction = glm::normalize(glm::vec3(-0.6f, 0.8f, 0.45f));
    view.shading.lights[0].shadows = false;
    view.shading.sky.intensity = 0.0f;
    ASSERT_FALSE(view.shading.castsShadows());
    EXPECT_EQ(frame.render("hybrid", view, settings).visibleCells, unlit.visibleCells);
    view.shading.lights[0].shadows = true;
    const splat::FrameStats shadowed = frame.render("hybrid", view, settings);
    EXPECT_TRUE(shadowed.regenerated);
    EXPECT_EQ(shadowed.visibleCells, cells);
    EXPECT_GT(shadowed.kernelsGenerated, unlit.kernelsGenerated);
    view.shading.lights[0].shadows = false;
    view.shading.sky.intensity = 0.5f; // the sky is always shadowed
    EXPECT_EQ(frame.render("hybrid", view, settings).visibleCells, cells);
    expectNoValidationErrors(ctx);
}

bool builtLightSpace(const splat::FrameStats& stats) {
    for (const auto& [pass, ms] : stats.passMs)
        if (pass == "light place")
            return true;
    return false;
}

// The light-space structure depends on the impulses, the pose and the lights, not on the
// camera: a frame that changes none of them keeps the last one (the editor's orbit), with the
// image a fresh frame makes; a light that moves builds it again.
TEST(Frame, TheLightSpaceIsKeptWhileOnlyTheCameraMoves) {
    FrameSetup s = loadFrameSetup("fur-bunny", 40);
    const noise::SceneDesc lit =
        noise::loadScene(std::string(SPOT_SOURCE_DIR) + "/presets/scenes/fur-bunny.json");
    s.scene.shading = lit.shading;
    ASSERT_TRUE(s.scene.shading.castsShadows());
    splat::Context ctx(validated());
    splat::RenderSettings settings;
    for (const char* method : {"hybrid", "raymarch"}) {
        SCOPED_TRACE(method);
        splat::Frame frame(ctx, s.mesh, *s.generator);
        splat::View view = s.view();
        noise::Image first, again, orbited;
        EXPECT_TRUE(builtLightSpace(frame.render(method, view, settings, &first)));
        EXPECT_FALSE(builtLightSpace(frame.render(method, view, settings, &again)));
        EXPECT_TRUE(sameBytes(first, again));
        view.camera.eye = glm::vec3(-1.6f, 1.0f, 1.9f); // another side of the bunny
        EXPECT_FALSE(builtLightSpace(frame.render(method, view, settings, &orbited)));
        splat::Frame fresh(ctx, s.mesh, *s.generator);
        noise::Image expected;
        EXPECT_TRUE(builtLightSpace(fresh.render(method, view, settings, &expected)));
        EXPECT_TRUE(sameBytes(orbited, expected)) << "a kept structure changed the image";
        EXPECT_FALSE(sameBytes(orbited, first));
        view.shading.lights[0].direction = glm::normalize(glm::vec3(0.7f, 0.5f, -0.5f));
        EXPECT_TRUE(builtLightSpace(frame.render(method, view, settings)));
    }
    expectNoValidationErrors(ctx);
}

// The editor's strokes: under a LightSpaceHold, new impulses keep the last structure (its
// shadows lag), a moved light does not; the first frame after the hold builds it again.
TEST(Frame, AHoldKeepsTheLightSpaceForNewImpulsesButNotForAMovedLight) {
    FrameSetup s = loadFrameSetup("fur-bunny", 40);
    s.scene.shading =
        noise::loadScene(std::string(SPOT_SOURCE_DIR) + "/presets/scenes/fur-bunny.json")
            .shading;
    splat::Context ctx(validated());
    splat::Frame frame(ctx, s.mesh, *s.generator);
    splat::RenderSettings settings;
    splat::View view = s.view();
    EXPECT_TRUE(builtLightSpace(frame.render("hybrid", view, settings)));
    settings.lodPixels = 3.0; // thinned: new impulses
    {
        splat::LightSpaceHold hold;
        const splat::FrameStats held = frame.render("hybrid", view, settings);
        EXPECT_TRUE(held.regenerated);
        EXPECT_FALSE(builtLightSpace(held));
        settings.lodPixels = 2.0;
        EXPECT_FALSE(builtLightSpace(frame.render("hybrid", view, settings)));
        splat::View turned = view;
        turned.shading.lights[0].direction = glm::normalize(glm::vec3(0.7f, 0.5f, -0.5f));
        EXPECT_TRUE(builtLightSpace(frame.render("hybrid", turned, settings)));
        EXPECT_TRUE(builtLightSpace(frame.render("hybrid", view, settings)));
        settings.lodPixels = 3.0;
        EXPECT_FALSE(builtLightSpace(frame.render("hybrid", view, settings)));
    }
    EXPECT_TRUE(builtLightSpace(frame.render("hybrid", view, settings))); // the hold has ended
    EXPECT_FALSE(builtLightSpace(frame.render("hybrid", view, settings)));
    expectNoValidationErrors(ctx);
}

TEST(Frame, ReadsThePixelsBackOnlyWhenAsked) {
    const FrameSetup s = loadFrameSetup("fur-bunny", 64);
    splat::Context ctx(validated());
    splat::Frame frame(ctx, s.mesh, *s.generator);
    frame.render("hybrid", s.view(), {});
    frame.render("hybrid", s.view(), {});
    const std::uint64_t bytes = ctx.allocatedBytes();
    noise::Image image;
    frame.render("hybrid", s.view(), {}, &image);
    // The readback buffer exists only once pixels were asked for: one RGBA32F image.
    EXPECT_EQ(ctx.allocatedBytes() - bytes, 64u * 64u * 16u);
    EXPECT_EQ(image.width, 64);
    EXPECT_THROW(frame.render("no-such-method", s.view(), {}), InputError);
    expectNoValidationErrors(ctx);
}

TEST(Frame, FragmentEfficiencyOnFurBunny) {
    // Fragments the splat pass shades against the pixels where a kernel's alpha reaches 1/255,
    // summed over kernels: the oriented quads and the early test against the mesh keep it under 2
    // on the whole furry bunny (without the mesh test, the same quads shade about 2.5 times the
    // covered pixels: the kernels behind the bunny).
    const FrameSetup s = loadFrameSetup("fur-bunny", 128);
    splat::Context ctx(validated());
    splat::Frame frame(ctx, s.mesh, *s.generator);
    splat::RenderSettings settings;
    settings.countFragments = true;
    for (const char* method : {"oit", "hybrid", "sorted"}) {
        const splat::FrameStats stats = frame.render(method, s.view(), settings);
        const auto& c = stats.counters;
        EXPECT_GT(c.pixelsCovered, 10000u) << method;
        EXPECT_GE(c.fragmentsShaded, c.pixelsCovered) << method;
        EXPECT_LE(double(c.fragmentsShaded), 2.0 * double(c.pixelsCovered)) << method;
    }
    // Without counting, no counts.
    EXPECT_EQ(frame.render("oit", s.view(), {}).counters.fragmentsShaded, 0u);
    expectNoValidationErrors(ctx);
}

} // namespace
