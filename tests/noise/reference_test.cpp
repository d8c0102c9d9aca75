// The CPU reference: closed forms for single and separate lobes, the quadrature path, convergence
// in samples and in step, finite pixels in every shipped scene.
#include <cmath>
#include <filesystem>

#include <gtest/gtest.h>

#include "noise/camera.h"
#include "noise/impulses.h"
#include "noise/mesh.h"
#include "noise/preset.h"
#include "noise/reference.h"
#include "noise/scene.h"
#include "shaders/spot_shared.hpp"
#include "test_support.h"
#include "splat/image_compare.h"

namespace {

using namespace spot;
using namespace spot::test;

noise::Camera orthoCamera(int size) {
    noise::Camera cam;
    cam.projection = noise::Projection::Orthographic;
    cam.eye = glm::dvec3(0.0, 0.0, 5.0);
    cam.target = glm::dvec3(0.0);
    cam.orthoHeight = 2.0;
    cam.width = cam.height = size;
    return cam;
}

TEST(Reference, SingleLobeOrthographicMatchesTheClosedForm) {
    // Support 6 sigma: the truncated tail (exp(-18)) is far below the tolerance.
    const noise::Kernel kernel =
        oneLobeKernel({0.3f, 0.2f, 0.5f}, {20.0f, 35.0f, -10.0f}, 3.0f, glm::vec3(1.0f), 6.0f);
    const std::vector<noise::Impulse> impulses{impulseAt(glm::vec3(0.05f, -0.1f, 0.0f))};
    const noise::Mesh empty;
    const noise::ReferenceRenderer renderer(empty, kernel, impulses, noise::Shading{},
                                            glm::vec3(0.0f), glm::vec3(0.0f));
    const noise::WorldLobe lobe = noise::placeLobe(kernel, 0, impulses[0]);
    const noise::Camera cam = orthoCamera(48);
    const noise::CameraRays rays(cam);

    // Pixel centres: the integrator's radiance is 1 - exp(-tau) exactly.
    double worst = 0.0;
    for (int y = 0; y < cam.height; ++y)
        for (int x = 0; x < cam.width; ++x) {
            const noise::Ray r = rays.ray(x + 0.5, y + 0.5);
            const double expected = 1.0 - std::exp(-closedFormDepth(lobe, r.origin, r.dir));
            const glm::vec3 got = renderer.radiance(r, 1.0);
            for (int c = 0; c < 3; ++c)
                worst = std::max(worst, std::abs(double(got[c]) - expected));
        }
    EXPECT_LT(worst, 1e-4);

    // Supersampled pixels: the box-filtered pixel mean of the closed form (16x16 midpoint grid).
    noise::ReferenceSettings settings;
    settings.spp = 256;
    const noise::Image image = renderer.render(cam, settings);
    worst = 0.0;
    for (int y = 0; y < cam.height; ++y)
        for (int x = 0; x < cam.width; ++x) {
            double mean = 0.0;
            for (int j = 0; j < 16; ++j)
                for (int i = 0; i < 16; ++i) {
                    const noise::Ray r = rays.ray(x + (i + 0.5) / 16.0, y + (j + 0.5) / 16.0);
                    mean += 1.0 - std::exp(-closedFormDepth(lobe, r.origin, r.dir));
                }
            mean /= 256.0;
            worst = std::max(worst, std::abs(double(image.at(x, y).g) - mean));
        }
    EXPECT_LT(worst, 1e-4);
}

TEST(Reference, SeparateLobesCompositeFrontToBack) {
    noise::KernelDesc desc;
    noise::LobeDesc red, blue;
    red.sigma = blue.sigma = glm::vec3(0.1f);
    red.offset = glm::vec3(0.0f, 0.0f, 1.0f); // nearer the camera at +z
    red.extinction = 6.0f;
    red.color = glm::vec3(1.0f, 0.0f, 0.0f);
    blue.offset = glm::vec3(0.0f, 0.0f, -1.0f);
    blue.extinction = 9.0f;
    blue.color = glm::vec3(0.0f, 0.0f, 1.0f);
    desc.lobes = {red, blue};
    desc.supportSigma = 3.0f;
    const noise::Kernel kernel = noise::buildKernel(desc);
    const std::vector<noise::Impulse> impulses{impulseAt(glm::vec3(0.0f))};
    const noise::Mesh empty;
    const glm::vec3 background(0.2f, 0.3f, 0.4f);
    const noise::ReferenceRenderer renderer(empty, kernel, impulses, noise::Shading{}, background,
                                            glm::vec3(0.0f));
    for (double offset : {0.0, 0.05, 0.12}) {
        for (double direction : {-1.0, 1.0}) {
            noise::Ray r;
            r.origin = glm::dvec3(offset, 0.5 * offset, 5.0 * -direction);
            r.dir = glm::dvec3(0.0, 0.0, direction);
            const noise::WorldLobe first = noise::placeLobe(kernel, direction < 0 ? 0 : 1, impulses[0]);
            const noise::WorldLobe second = noise::placeLobe(kernel, direction < 0 ? 1 : 0, impulses[0]);
            // Truncated at 3 sigma: the chord's depth uses erf over the chord only.
            auto truncated = [&](const noise::WorldLobe& l) {
                const glm::dvec3 op = l.toLobe * (r.origin - l.centre), dp = l.toLobe * r.dir;
                double tPeak = 0.0;
                return l.extinction * shared::f64::spotLobeDepth(op, dp, 0.0, 1e9, 3.0, tPeak);
            };
            const double t1 = truncated(first), t2 = truncated(second);
            const glm::dvec3 expected = (1.0 - std::exp(-t1)) * glm::dvec3(first.color) +
                                        std::exp(-t1) * (1.0 - std::exp(-t2)) * glm::dvec3(second.color) +
                                        std::exp(-t1 - t2) * glm::dvec3(background);
            const glm::vec3 got = renderer.radiance(r, 1.0);
            for (int c = 0; c < 3; ++c)
                EXPECT_NEAR(got[c], expected[c], 1e-6) << "offset " << offset << " dir " << direction;
            if (offset == 0.0)
                EXPECT_GT(t1, 1.0); // the test must exercise real occlusion
        }
    }
}

TEST(Reference, OverlappingLobesOfOneColourAreExact) {
    // The quadrature path: exact optical depth per step, so one colour gives the exact result.
    noise::KernelDesc desc;
    noise::LobeDesc a, b;
    a.sigma = glm::vec3(0.2f, 0.1f, 0.3f);
    b.sigma = glm::vec3(0.15f, 0.25f, 0.1f);
    b.offset = glm::vec3(0.05f, 0.0f, 0.2f);
    b.rotationDeg = glm::vec3(30.0f, 10.0f, 0.0f);
    a.extinction = 4.0f;
    b.extinction = 7.0f;
    a.color = b.color = glm::vec3(0.3f, 0.6f, 0.9f);
    desc.lobes = {a, b};
    const noise::Kernel kernel = noise::buildKernel(desc);
    const std::vector<noise::Impulse> impulses{impulseAt(glm::vec3(0.0f))};
    const noise::Mesh empty;
    noise::ReferenceStats stats;
    for (auto mode : {noise::Shading::Mode::Unlit, noise::Shading::Mode::Lambert}) {
        noise::Shading shading;
        shading.mode = mode;
        shading.ambient = 1.0f; // lambert with full ambient: shading is exactly 1
        const noise::ReferenceRenderer renderer(empty, kernel, impulses, shading, glm::vec3(0.0f),
                                                glm::vec3(0.0f));
        noise::Ray r;
        r.origin = glm::dvec3(0.02, 0.01, 3.0);
        r.dir = glm::normalize(glm::dvec3(0.0, 0.01, -1.0));
        double tau = 0.0;
        for (int l = 0; l < 2; ++l) {
            const noise::WorldLobe w = noise::placeLobe(kernel, l, impulses[0]);
            double tPeak = 0.0;
            tau += w.extinction * shared::f64::spotLobeDepth(w.toLobe * (r.origin - w.centre),
                                                             w.toLobe * r.dir, 0.0, 1e9, 3.0, tPeak);
        }
        const glm::vec3 got = renderer.radiance(r, 1.0, &stats);
        for (int c = 0; c < 3; ++c)
            EXPECT_NEAR(got[c], (1.0 - std::exp(-tau)) * a.color[c], 1e-6);
    }
    EXPECT_GT(stats.quadratureSteps, 0u);
}

TEST(Reference, BaseMeshEndsTheRay) {
    const noise::Mesh plane = noise::makePlane(2.0f, 2); // y = 0, normal +y
    const noise::Kernel kernel = oneLobeKernel(glm::vec3(0.1f), glm::vec3(0.0f), 5.0f,
                                               glm::vec3(1.0f), 6.0f);
    // One lobe centred on the plane: only its upper half is seen from above.
    const std::vector<noise::Impulse> impulses{impulseAt(glm::vec3(0.0f))};
    const glm::vec3 base(0.2f, 0.5f, 0.1f);
    const noise::ReferenceRenderer renderer(plane, kernel, impulses, noise::Shading{},
                                            glm::vec3(1.0f, 0.0f, 1.0f), base);
    noise::Ray r;
    r.origin = glm::dvec3(0.0, 3.0, 0.0);
    r.dir = glm::dvec3(0.0, -1.0, 0.0);
    const noise::WorldLobe w = noise::placeLobe(kernel, 0, impulses[0]);
    const double half = 0.5 * closedFormDepth(w, r.origin, r.dir);
    const glm::vec3 got = renderer.radiance(r, 1.0);
    for (int c = 0; c < 3; ++c)
        EXPECT_NEAR(got[c], (1.0 - std::exp(-half)) + std::exp(-half) * base[c], 1e-5);
    // Beside the lobe the plane shows, and past the plane's edge the background.
    r.origin = glm::dvec3(0.7, 3.0, 0.0);
    EXPECT_NEAR(renderer.radiance(r, 1.0).g, base.g, 1e-6);
    r.origin = glm::dvec3(1.5, 3.0, 0.0);
    EXPECT_NEAR(renderer.radiance(r, 1.0).r, 1.0f, 1e-6);
}

struct Rendered {
    noise::Image image;
    noise::ReferenceStats stats;
};

Rendered renderScene(const std::string& name, int size, int spp, double stepScale) {
    const noise::SceneDesc scene = test::loadShippedScene(name);
    const noise::Mesh mesh = noise::loadMeshOrGenerated(scene.mesh);
    const noise::PresetDesc preset = noise::loadPreset(scene.preset);
    noise::GeneratorOptions options;
    options.seed = scene.seed;
    const noise::ImpulseGenerator generator(mesh, preset, options);
    const auto impulses = generator.generate();
    const noise::ReferenceRenderer renderer(mesh, generator.kernel(), impulses, scene.shading,
                                            scene.background, scene.baseColor);
    noise::Camera cam = scene.camera;
    cam.width = cam.height = size;
    noise::ReferenceSettings settings;
    settings.spp = spp;
    settings.stepScale = stepScale;
    settings.seed = 3;
    Rendered r;
    r.image = renderer.render(cam, settings, {}, &r.stats);
    return r;
}

TEST(ReferenceConvergence, FurBunnySamples64Versus256) {
    const Rendered a = renderScene("fur-bunny", 128, 64, 1.0);
    const Rendered b = renderScene("fur-bunny", 128, 256, 1.0);
    const double p = splat::psnr(b.image, a.image);
    EXPECT_GE(p, 40.0) << "64 vs 256 spp";
    RecordProperty("psnr_64_vs_256", std::to_string(p));
    std::printf("fur-bunny 128x128: 64 vs 256 spp PSNR %.2f dB\n", p);
}

TEST(ReferenceConvergence, QuadratureStepHalved) {
    // fur-bunny (unlit: quadrature only where strands overlap) and lichen-torus (lambert: every
    // chord by quadrature).
    for (const char* scene : {"fur-bunny", "lichen-torus"}) {
        const Rendered a = renderScene(scene, 96, 16, 1.0);
        const Rendered b = renderScene(scene, 96, 16, 0.5);
        EXPECT_GT(b.stats.quadratureSteps, a.stats.quadratureSteps) << scene;
        const double p = splat::psnr(b.image, a.image);
        EXPECT_GE(p, 45.0) << scene;
        std::printf("%s 96x96: step vs step/2 PSNR %.2f dB\n", scene, p);
    }
}

TEST(ReferenceScenes, NoNanOrInfInAnyShippedScene) {
    int scenes = 0;
    for (const auto& entry :
         std::filesystem::directory_iterator(std::string(SPOT_SOURCE_DIR) + "/presets/scenes")) {
        if (entry.path().extension() != ".json")
            continue;
        const Rendered r = renderScene(entry.path().stem().string(), 48, 2, 1.0);
        std::size_t bad = 0;
        double sum = 0.0;
        for (const glm::vec3& p : r.image.pixels) {
            bad += !std::isfinite(p.r + p.g + p.b);
            sum += p.r + p.g + p.b;
        }
        EXPECT_EQ(bad, 0u) << entry.path();
        EXPECT_GT(sum, 0.0) << entry.path(); // not a black image
        EXPECT_GT(r.stats.chords, 0u) << entry.path() << ": no kernel in view";
        ++scenes;
    }
    EXPECT_GE(scenes, 6);
}

} // namespace
