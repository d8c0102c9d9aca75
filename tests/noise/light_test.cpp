// Lit scenes: the scene's lights and sky and the preset's lobe models parse strictly; the
// reference's shadow rays (a lobe behind an opaque wall of kernels or a mesh gets next to
// nothing, one with nothing between it and the light all of it), a light moved to the other side
// flips which half of the bunny is brighter, the reference converges in samples, and the GPU
// methods refuse lit scenes with one line.
#include <cmath>
#include <cstdio>
#include <random>
#include <string>

#include <gtest/gtest.h>

#include "cli_run.h"
#include "noise/camera.h"
#include "noise/error.h"
#include "noise/impulses.h"
#include "noise/kernel.h"
#include "noise/mesh.h"
#include "noise/preset.h"
#include "noise/reference.h"
#include "noise/scene.h"
#include "shaders/spot_shared.hpp"
#include "splat/image_compare.h"
#include "splat/methods/baked/baked_vk.h"
#include "test_support.h"

namespace {

using namespace spot;
using namespace spot::test;

const std::string kSceneHead = R"({"version": 1, "mesh": "generated:sphere", "preset": "p.json",
  "camera": {"eye": [0, 0, 3], "target": [0, 0, 0]}, "image": {"width": 8, "height": 8},)";

noise::SceneDesc parse(const std::string& tail) {
    return noise::parseScene(kSceneHead + tail, "lit.json", ".");
}

/// The InputError message of parsing `tail`, or "" when it parses.
std::string parseError(const std::string& tail) {
    try {
        parse(tail);
    } catch (const InputError& e) {
        return e.what();
    }
    return "";
}

TEST(LitScene, ParsesLightsAndSky) {
    const noise::SceneDesc s = parse(R"("shading": {"mode": "lit"},
        "lights": [{"type": "directional", "direction": [0, 2, 0], "color": [1, 0.5, 0.25],
                    "intensity": 3, "shadows": false},
                   {"type": "point", "position": [1, 2, 3], "intensity": 10}],
        "sky": {"color": [0.5, 0.6, 0.7], "intensity": 0.4}})");
    ASSERT_EQ(s.shading.mode, noise::Shading::Mode::Lit);
    ASSERT_EQ(s.shading.lights.size(), 2u);
    const noise::Light& d = s.shading.lights[0];
    EXPECT_EQ(d.type, noise::Light::Type::Directional);
    EXPECT_EQ(d.direction, glm::vec3(0, 1, 0)); // normalized
    EXPECT_EQ(d.color, glm::vec3(1, 0.5f, 0.25f));
    EXPECT_EQ(d.intensity, 3.0f);
    EXPECT_FALSE(d.shadows);
    const noise::Light& p = s.shading.lights[1];
    EXPECT_EQ(p.type, noise::Light::Type::Point);
    EXPECT_EQ(p.position, glm::vec3(1, 2, 3));
    EXPECT_EQ(p.color, glm::vec3(1.0f)); // defaults
    EXPECT_TRUE(p.shadows);
    EXPECT_EQ(s.shading.sky.color, glm::vec3(0.5f, 0.6f, 0.7f));
    EXPECT_EQ(s.shading.sky.intensity, 0.4f);
    // Unlit and Lambert scenes may keep their lights (switching is one key); they ignore them.
    EXPECT_EQ(parse(R"("lights": [{"type": "point", "position": [0, 1, 0]}]})").shading.mode,
              noise::Shading::Mode::Unlit);
}

TEST(LitScene, RefusesBadLightsWithOneLine) {
    const std::pair<const char*, const char*> cases[] = {
        {R"("shading": {"mode": "lit"}})", "needs a light"},
        {R"("shading": {"mode": "lit"}, "sky": {"intensity": 0}})", "needs a light"},
        {R"("shading": {"mode": "lit", "ambient": 0.2}, "sky": {"intensity": 1}})", "lambert's"},
        {R"("shading": {"mode": "shiny"}})", "\"lit\""},
        {R"("lights": [{"type": "spot", "position": [0, 1, 0]}]})", "lights[0].type"},
        {R"("lights": [{"type": "point", "position": [0, 1, 0], "colour": [1, 1, 1]}]})",
         "unknown key \"lights[0].colour\""},
        {R"("lights": [{"type": "point", "position": [0, 1e39, 0]}]})", "lights[0].position[1]"},
        {R"("lights": [{"type": "point", "position": [0, 1, 0], "intensity": -1}]})",
         "lights[0].intensity = -1 is out of range"},
        {R"("lights": [{"type": "directional", "direction": [0, 0, 0]}]})", "must not be zero"},
        {R"("lights": [{"type": "directional", "direction": [0, 1, 0], "position": [0, 1, 0]}]})",
         "does not apply"},
        {R"("lights": [{"type": "point"}]})", "missing required key \"lights[0].position\""},
        {R"("lights": [{"type": "point", "position": [0, 1, 0], "shadows": 1}]})", "true or false"},
        {R"("lights": {"type": "point"}})", "must be an array"},
        {R"("sky": {"intensity": 1, "colour": [1, 1, 1]}})", "unknown key \"sky.colour\""},
        {R"("sky": {"color": [1, 1, 1]}})", "missing required key \"sky.intensity\""},
        {R"("sky": {"intensity": 2e6}})", "sky.intensity"},
    };
    for (const auto& [tail, expected] : cases) {
        const std::string message = parseError(tail);
        EXPECT_NE(message.find(expected), std::string::npos) << tail << "\n got: " << message;
        EXPECT_EQ(message.find('\n'), std::string::npos) << message;
        EXPECT_EQ(message.rfind("lit.json: ", 0), 0u) << message;
    }
    std::string nine = R"("lights": [)";
    for (int i = 0; i < 9; ++i)
        nine += std::string(i ? ", " : "") + R"({"type": "point", "position": [0, 1, 0]})";
    EXPECT_NE(parseError(nine + "]}").find("more than the limit of 8"), std::string::npos);
}

const std::string kPresetHead = R"({"version": 1, "kernel": {"lobes": [{"sigma": [0.1, 0.1, 0.5],)";

TEST(LitPreset, LobesChooseTheirModel) {
    const noise::PresetDesc a = noise::parsePreset(
        kPresetHead +
            R"("shading": "strand"}]}, "distribution": {"type": "poisson", "density_max": 10}})",
        "p.json");
    EXPECT_EQ(a.kernel.lobes[0].shading.model, noise::LobeShading::Model::Strand);
    EXPECT_EQ(a.kernel.lobes[0].shading.primary.shiftDeg, -6.0f); // the defaults
    const noise::PresetDesc b = noise::parsePreset(
        kPresetHead +
            R"("shading": {"model": "strand", "secondary": {"shift_deg": 12, "width_deg": 20,
            "strength": 0.8}}}]}, "distribution": {"type": "poisson", "density_max": 10}})",
        "p.json");
    EXPECT_EQ(b.kernel.lobes[0].shading.secondary.shiftDeg, 12.0f);
    EXPECT_EQ(b.kernel.lobes[0].shading.secondary.widthDeg, 20.0f);
    EXPECT_EQ(b.kernel.lobes[0].shading.secondary.strength, 0.8f);
    EXPECT_EQ(b.kernel.lobes[0].shading.primary.strength, 0.3f);
    const noise::PresetDesc c = noise::parsePreset(
        kPresetHead +
            R"("shading": "flake"}]}, "distribution": {"type": "poisson", "density_max": 10}})",
        "p.json");
    EXPECT_EQ(c.kernel.lobes[0].shading.model, noise::LobeShading::Model::Flake);
    const noise::PresetDesc d = noise::parsePreset(
        kPresetHead +
            R"("color": [1, 1, 1]}]}, "distribution": {"type": "poisson", "density_max": 10}})",
        "p.json");
    EXPECT_EQ(d.kernel.lobes[0].shading.model, noise::LobeShading::Model::Lambert);

    const std::pair<const char*, const char*> bad[] = {
        {R"("shading": "fuzzy"}]}, "distribution": {"type": "poisson", "density_max": 10}})",
         "kernel.lobes[0].shading = \"fuzzy\" is not one of"},
        {R"("shading": 3}]}, "distribution": {"type": "poisson", "density_max": 10}})",
         "must be a model's name or an object"},
        {R"("shading": {"model": "flake", "primary": {}}}]}, "distribution": {"type": "poisson", "density_max": 10}})",
         "belong to the \"strand\" model"},
        {R"("shading": {"model": "strand", "primary": {"width_deg": 0}}}]}, "distribution": {"type": "poisson", "density_max": 10}})",
         "kernel.lobes[0].shading.primary.width_deg = 0 is out of range"},
        {R"("shading": {"model": "strand", "primary": {"shift": 1}}}]}, "distribution": {"type": "poisson", "density_max": 10}})",
         "unknown key \"kernel.lobes[0].shading.primary.shift\""},
        {R"("shading": {"primary": {}}}]}, "distribution": {"type": "poisson", "density_max": 10}})",
         "missing required key \"kernel.lobes[0].shading.model\""},
    };
    for (const auto& [tail, expected] : bad) {
        std::string message;
        try {
            noise::parsePreset(kPresetHead + tail, "p.json");
        } catch (const InputError& e) {
            message = e.what();
        }
        EXPECT_NE(message.find(expected), std::string::npos) << tail << "\n got: " << message;
    }
}

/// A lit scene of isotropic lobes: one at the origin (the lobe the tests look at) and the
/// impulses `others`, lit by one directional light from +y, no sky.
struct LitLobes {
    noise::Kernel kernel =
        oneLobeKernel(glm::vec3(0.05f), glm::vec3(0.0f), 40.0f, glm::vec3(1.0f), 3.0f);
    noise::Shading shading;
    LitLobes() {
        shading.mode = noise::Shading::Mode::Lit;
        noise::Light light;
        light.direction = glm::vec3(0, 1, 0);
        light.intensity = 2.0f;
        shading.lights = {light};
    }
    /// The radiance of the lobe at the origin seen from +z along a few rays through it.
    double seen(const noise::Mesh& mesh, const std::vector<glm::vec3>& others) const {
        std::vector<noise::Impulse> impulses{impulseAt(glm::vec3(0.0f))};
        for (glm::vec3 p : others)
            impulses.push_back(impulseAt(p));
        const noise::ReferenceRenderer renderer(mesh, kernel, impulses, shading, glm::vec3(0.0f),
                                                glm::vec3(0.0f));
        double sum = 0.0;
        for (double x : {-0.04, 0.0, 0.03})
            for (double y : {-0.03, 0.0, 0.04})
                sum += renderer.radiance({{x, y, 2.0}, {0.0, 0.0, -1.0}}, 1.0).g;
        return sum;
    }
};

/// Impulses filling the square |x|, |z| <= half at height y, 0.05 apart.
std::vector<glm::vec3> wall(float y, float half, float x0 = 0.0f) {
    std::vector<glm::vec3> out;
    for (float x = -half; x <= half + 1e-6f; x += 0.05f)
        for (float z = -half; z <= half + 1e-6f; z += 0.05f)
            out.emplace_back(x0 + x, y, z);
    return out;
}

// A lobe's own shadow: the GPU looks it up in a table (noise::ownShadowTable) rather than
// integrating it; the lookup stays within 0.01 of the function (0.002 mean) over the depth
// scales fur and flakes have, and keeps its limits: no depth towards the light lets it all
// through, and a thick lobe lit from behind shows almost none of it.
TEST(LitOwnShadow, TheTableFollowsTheFunction) {
    namespace sh = shared::f32;
    for (const float support : {3.0f, 2.5f}) {
        const std::vector<float>& table = noise::ownShadowTable(support);
        std::mt19937 rng(7);
        std::uniform_real_distribution<float> u(0.0f, 1.0f);
        double sum = 0.0, worst = 0.0;
        const int n = 4000;
        for (int i = 0; i < n; ++i) {
            const float a = std::exp(-5.0f + 9.0f * u(rng)), b = std::exp(-5.0f + 9.0f * u(rng));
            const float c = -1.0f + 2.0f * u(rng);
            const double e = std::abs(noise::ownShadowLookup(table, a, b, c) -
                                      sh::spotOwnShadow(a, b, c, support, 3u));
            sum += e;
            worst = std::max(worst, e);
        }
        std::printf("support %.1f: own shadow table against the function: mean %.5f, max %.5f\n",
                    double(support), sum / n, worst);
        EXPECT_LT(sum / n, 0.002) << support;
        EXPECT_LT(worst, 0.01) << support;
        EXPECT_NEAR(noise::ownShadowLookup(table, 1.0f, 1e-6f, 0.3f), 1.0f, 1e-3f);
        EXPECT_LT(noise::ownShadowLookup(table, 50.0f, 50.0f, 1.0f), 0.01f);
        EXPECT_GT(noise::ownShadowLookup(table, 50.0f, 50.0f, -1.0f), 0.3f);
    }
}

TEST(LitReference, ALobeBehindAnOpaqueWallOfKernelsGetsAtMostTwoPercent) {
    const LitLobes scene;
    const noise::Mesh empty;
    const double alone = scene.seen(empty, {});
    ASSERT_GT(alone, 0.05); // it is lit and seen
    // A wall of kernels at y = 0.4 between the lobe and the light (and out of the view rays).
    const double shadowed = scene.seen(empty, wall(0.4f, 0.5f));
    std::printf("behind the wall: %.6f of the light\n", shadowed / alone);
    EXPECT_LE(shadowed, 0.02 * alone);
    // With the light's shadows off the wall changes nothing.
    LitLobes unshadowed;
    unshadowed.shading.lights[0].shadows = false;
    EXPECT_NEAR(unshadowed.seen(empty, wall(0.4f, 0.5f)), unshadowed.seen(empty, {}),
                1e-12 * alone);
    // The wall beside it (x from 1 to 2) is not between the lobe and the light: all of it.
    EXPECT_NEAR(scene.seen(empty, wall(0.4f, 0.5f, 1.5f)), alone, 1e-12 * alone);
    // A point light below a wall (at y = 0.3, the wall's support from 0.4 up), so the wall is
    // beyond it: all of it again.
    LitLobes point;
    point.shading.lights[0].type = noise::Light::Type::Point;
    point.shading.lights[0].position = glm::vec3(0.0f, 0.3f, 0.0f);
    const double near = point.seen(empty, {});
    EXPECT_NEAR(point.seen(empty, wall(0.55f, 0.5f)), near, 1e-12 * near);
    // Its light falls off as 1 / d^2: from y = 6 a quarter of what arrives from y = 3 (the lit
    // top of the lobe lies about 0.1 nearer: (2.9 / 5.9)^2 = 0.242).
    point.shading.lights[0].position = glm::vec3(0.0f, 3.0f, 0.0f);
    const double at3 = point.seen(empty, {});
    point.shading.lights[0].position = glm::vec3(0.0f, 6.0f, 0.0f);
    EXPECT_NEAR(point.seen(empty, {}) / at3, 0.25, 0.015);
}

TEST(LitReference, TheMeshCastsShadowsAndIsLit) {
    const LitLobes scene;
    const noise::Mesh empty;
    const double alone = scene.seen(empty, {});
    noise::Mesh roof = noise::makePlane(1.0f, 2); // y = 0, normal +y
    transformMesh(roof, glm::mat3(1.0f), glm::vec3(0.0f, 0.5f, 0.0f));
    EXPECT_EQ(scene.seen(roof, {}), 0.0);
    noise::Mesh aside = roof;
    transformMesh(aside, glm::mat3(1.0f), glm::vec3(2.0f, 0.0f, 0.0f));
    EXPECT_NEAR(scene.seen(aside, {}), alone, 1e-12 * alone);

    // The mesh's diffuse: a floor facing +y under a light at 60 degrees from the normal shows
    // base x intensity x cos 60; with a lobe above it, its shadow darkens the floor below.
    noise::Mesh floor = noise::makePlane(2.0f, 2);
    noise::Shading shading = scene.shading;
    shading.lights[0].direction =
        glm::vec3(std::sin(glm::radians(60.0f)), std::cos(glm::radians(60.0f)), 0.0f);
    const glm::vec3 base(0.5f, 0.25f, 0.1f);
    const noise::ReferenceRenderer bare(floor, scene.kernel, {}, shading, glm::vec3(0.0f), base);
    const noise::Ray down{{0.1, 3.0, 0.2}, {0.0, -1.0, 0.0}};
    EXPECT_NEAR(bare.radiance(down, 1.0).r, 0.5 * 2.0 * 0.5, 1e-6);
    // An opaque lobe (optical depth 50 through its centre) at (1, 0.5, 0), the light from
    // (1, 1, 0): the floor at x = 0.5 lies in its shadow, at x = -0.5 it does not; the view rays
    // straight down pass 0.5 (5 sigma) beside the lobe.
    const noise::Kernel big =
        oneLobeKernel(glm::vec3(0.1f), glm::vec3(0.0f), 200.0f, glm::vec3(1.0f), 3.0f);
    shading.lights[0].direction = glm::normalize(glm::vec3(1, 1, 0));
    const noise::ReferenceRenderer shadowed(floor, big, {impulseAt(glm::vec3(1.0f, 0.5f, 0.0f))},
                                            shading, glm::vec3(0.0f), base);
    EXPECT_LT(shadowed.radiance({{0.5, 3.0, 0.0}, {0.0, -1.0, 0.0}}, 1.0).r, 1e-9);
    EXPECT_NEAR(shadowed.radiance({{-0.5, 3.0, 0.0}, {0.0, -1.0, 0.0}}, 1.0).r,
                0.5 * 2.0 * std::sqrt(0.5), 1e-6);
}

TEST(LitReference, TheSkyDeliversItsRadianceToAnOpenUpwardSurface) {
    // A floor facing +y under the sky alone: (1/pi) of the integral of S cos over the
    // hemisphere is S, so the pixels converge to base x S; sampled, per pixel 256 directions
    // (stratified) come within a percent. A roof above takes every direction's light away.
    const noise::Mesh floor = noise::makePlane(2.0f, 2);
    noise::Shading shading;
    shading.mode = noise::Shading::Mode::Lit;
    shading.sky = {glm::vec3(0.5f, 1.0f, 2.0f), 0.8f};
    const glm::vec3 base(0.5f, 0.5f, 0.25f);
    const noise::Kernel kernel =
        oneLobeKernel(glm::vec3(0.1f), glm::vec3(0.0f), 1.0f, glm::vec3(1.0f), 3.0f);
    const noise::ReferenceRenderer open(floor, kernel, {}, shading, glm::vec3(0.0f), base);
    noise::Camera cam;
    cam.projection = noise::Projection::Orthographic;
    cam.eye = glm::dvec3(0.0, 3.0, 0.0);
    cam.target = glm::dvec3(0.0);
    cam.up = glm::dvec3(0.0, 0.0, -1.0);
    cam.orthoHeight = 1.0;
    cam.width = cam.height = 4;
    noise::ReferenceSettings settings;
    settings.spp = 256;
    const noise::Image image = open.render(cam, settings);
    for (const glm::vec3& p : image.pixels)
        for (int c = 0; c < 3; ++c)
            EXPECT_NEAR(p[c], base[c] * shading.sky.color[c] * 0.8f,
                        0.01 * base[c] * shading.sky.color[c] * 0.8f);
    noise::Mesh both = floor, roof = floor;
    transformMesh(roof, glm::mat3(1.0f), glm::vec3(0.0f, 0.5f, 0.0f));
    for (glm::uvec3 t : roof.triangles)
        both.triangles.push_back(t + glm::uvec3(std::uint32_t(floor.positions.size())));
    both.positions.insert(both.positions.end(), roof.positions.begin(), roof.positions.end());
    both.normals.insert(both.normals.end(), roof.normals.begin(), roof.normals.end());
    both.uvs.clear(); // not needed here, and no longer one per position
    both.tangents.clear();
    const noise::ReferenceRenderer covered(both, kernel, {}, shading, glm::vec3(0.0f), base);
    // The floor's middle seen from under the roof, lit from a sky direction 37 degrees from the
    // zenith (u1 = 0.8): the roof at 0.5 above blocks it; an open floor gets 2 S cos.
    const noise::Ray under{{0.0, 0.25, 0.0}, {0.0, -1.0, 0.0}};
    EXPECT_EQ(covered.radiance(under, 1.0, nullptr, nullptr, glm::dvec2(0.8, 0.6)).r, 0.0f);
    EXPECT_NEAR(open.radiance(under, 1.0, nullptr, nullptr, glm::dvec2(0.8, 0.6)).r,
                2.0 * 0.8 * base.r * 0.5 * 0.8, 1e-6);
}

/// fur-bunny (lit) at `size` pixels and `spp`, its key light turned by `flip` (1 or -1) across
/// the camera's right axis; returns the mean brightness of the left and right halves.
std::pair<double, double> bunnyHalves(double flip, int size, int spp) {
    noise::SceneDesc scene =
        noise::loadScene(std::string(SPOT_SOURCE_DIR) + "/presets/scenes/fur-bunny.json");
    const noise::Mesh mesh = noise::loadMeshOrGenerated(scene.mesh);
    const noise::PresetDesc preset = noise::loadPreset(scene.preset);
    noise::GeneratorOptions options;
    options.seed = scene.seed;
    const noise::ImpulseGenerator generator(mesh, preset, options);
    const auto impulses = generator.generate();
    noise::Camera cam = scene.camera;
    cam.width = cam.height = size;
    const glm::dvec3 right = noise::CameraRays(cam).right();
    // The key light from the camera's right (flip 1) or left (-1), a little from above.
    scene.shading.lights.resize(1);
    scene.shading.lights[0].direction =
        glm::vec3(glm::normalize(flip * glm::normalize(right) + glm::dvec3(0, 0.3, 0)));
    scene.shading.sky.intensity = 0.0f;
    const noise::ReferenceRenderer renderer(mesh, generator.kernel(), impulses, scene.shading,
                                            scene.background, scene.baseColor);
    noise::ReferenceSettings settings;
    settings.spp = spp;
    const noise::Image image = renderer.render(cam, settings);
    double left = 0.0, rightHalf = 0.0;
    for (int y = 0; y < size; ++y)
        for (int x = 0; x < size; ++x) {
            const glm::vec3 p = image.at(x, y);
            (x < size / 2 ? left : rightHalf) += p.r + p.g + p.b;
        }
    return {left, rightHalf};
}

TEST(LitReference, MovingTheLightAcrossFlipsTheBrighterHalfOfTheBunny) {
    const auto [leftA, rightA] = bunnyHalves(1.0, 32, 2);
    const auto [leftB, rightB] = bunnyHalves(-1.0, 32, 2);
    std::printf("light from the right: left %.3f right %.3f; from the left: left %.3f right %.3f\n",
                leftA, rightA, leftB, rightB);
    EXPECT_GT(rightA, 1.3 * leftA);
    EXPECT_GT(leftB, 1.3 * rightB);
}

TEST(ReferenceConvergence, LitSphereSamples64Versus256) {
    // A small lit scene, all of the model: fur strands on a sphere, a key light and a point
    // light with shadows, and the sky (sampled per pixel sample).
    const noise::Mesh sphere = noise::makeSphere(0.5f, 24, 48);
    noise::PresetDesc preset = uniformPreset(400.0f, 0.02f);
    preset.kernel.lobes[0].sigma = glm::vec3(0.3f, 0.3f, 1.5f);
    preset.kernel.lobes[0].offset = glm::vec3(0.0f, 0.0f, 1.5f);
    preset.kernel.lobes[0].extinction = 300.0f;
    preset.kernel.lobes[0].color = glm::vec3(0.6f, 0.4f, 0.2f);
    preset.kernel.lobes[0].shading.model = noise::LobeShading::Model::Strand;
    preset.tiltDeg = constantField(glm::vec3(40.0f), 1);
    const noise::ImpulseGenerator generator(sphere, preset, noise::GeneratorOptions{});
    const auto impulses = generator.generate();
    noise::Shading shading;
    shading.mode = noise::Shading::Mode::Lit;
    noise::Light key;
    key.direction = glm::normalize(glm::vec3(-1.0f, 1.0f, 0.6f));
    key.intensity = 2.0f;
    noise::Light point;
    point.type = noise::Light::Type::Point;
    point.position = glm::vec3(1.0f, -0.5f, 1.0f);
    point.intensity = 0.8f;
    shading.lights = {key, point};
    shading.sky = {glm::vec3(0.6f, 0.7f, 0.9f), 0.5f};
    const noise::ReferenceRenderer renderer(sphere, generator.kernel(), impulses, shading,
                                            glm::vec3(0.0f), glm::vec3(0.3f, 0.2f, 0.1f));
    noise::Camera cam;
    cam.eye = glm::dvec3(0.0, 0.3, 3.0);
    cam.target = glm::dvec3(0.0);
    cam.fovYDeg = 25.0;
    cam.width = cam.height = 24;
    noise::ReferenceSettings settings;
    settings.spp = 64;
    noise::ReferenceStats stats;
    const noise::Image a = renderer.render(cam, settings, {}, &stats);
    settings.spp = 256;
    const noise::Image b = renderer.render(cam, settings);
    const double p = splat::psnr(b, a);
    std::printf("lit sphere 24x24 (%zu lobes): 64 vs 256 spp PSNR %.2f dB, %.2f s at 64 spp, %llu "
                "shadow rays\n",
                stats.lobes, p, stats.seconds, static_cast<unsigned long long>(stats.shadowRays));
    RecordProperty("psnr_64_vs_256", std::to_string(p));
    EXPECT_GT(stats.shadowRays, 0u);
    EXPECT_GE(p, 40.0);
    double mean = 0.0; // not a dark image, where any two renders agree
    for (const glm::vec3& px : b.pixels)
        mean += (px.r + px.g + px.b) / 3.0;
    mean /= double(b.pixels.size());
    std::printf("mean %.3f\n", mean);
    EXPECT_GT(mean, 0.1);
}

TEST(LitScene, UnlitModeIgnoresTheLights) {
    // The same scene with and without lights, unlit: the same image, bit for bit.
    const noise::Kernel kernel =
        oneLobeKernel(glm::vec3(0.3f), glm::vec3(0.0f), 5.0f, glm::vec3(0.5f), 3.0f);
    noise::Shading unlit, withLights;
    withLights.lights.resize(2);
    withLights.sky.intensity = 1.0f;
    const noise::Mesh plane = noise::makePlane(2.0f, 2);
    const noise::ReferenceRenderer a(plane, kernel, {impulseAt(glm::vec3(0.0f))}, unlit,
                                     glm::vec3(0.1f), glm::vec3(0.3f));
    const noise::ReferenceRenderer b(plane, kernel, {impulseAt(glm::vec3(0.0f))}, withLights,
                                     glm::vec3(0.1f), glm::vec3(0.3f));
    noise::Camera cam;
    cam.eye = glm::dvec3(0.3, 2.0, 1.0);
    cam.target = glm::dvec3(0.0);
    cam.width = cam.height = 16;
    noise::ReferenceSettings settings;
    settings.spp = 4;
    EXPECT_EQ(a.render(cam, settings).pixels, b.render(cam, settings).pixels);
}

TEST(LitScene, GpuMethodsRefuseLitScenesWithOneLine) {
    const std::string scene =
        std::string(SPOT_SOURCE_DIR) + "/presets/scenes/fur-bunny.json";
    // The splatting methods and the ray-march render lit scenes (tests/splat/light_space_test.cpp).
    for (const char* method : {"instanced", "oit", "hybrid", "sorted", "raymarch"})
        EXPECT_TRUE(splat::method(method).rendersLit) << method;
    // baked renders lit scenes (its bake's shading grids; tests/splat/baked_test.cpp renders
    // them): its view check takes a lit view, and still refuses Lambert with one line.
    EXPECT_TRUE(splat::method("baked").rendersLit);
    splat::View view;
    view.shading.mode = noise::Shading::Mode::Lit;
    EXPECT_NO_THROW(splat::requireBakedView(view));
    view.shading.mode = noise::Shading::Mode::Lambert;
    try {
        splat::requireBakedView(view);
        ADD_FAILURE() << "baked took a Lambert view";
    } catch (const InputError& e) {
        EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos) << e.what();
    }
    // The reference renders it.
    const std::string out = std::string(SPOT_TEST_TMP_DIR) + "/lit-reference.exr";
    const CliResult r =
        runSpotshell("render --scene '" + scene +
                     "' --method reference --size 16x16 --spp 1 --out '" + out + "'");
    EXPECT_EQ(r.code, 0) << r.err;
    EXPECT_TRUE(std::filesystem::exists(out));
}

} // namespace
