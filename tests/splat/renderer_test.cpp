// The splatting renderers (instanced, oit, hybrid, sorted) against the closed form on one lobe and
// against the converged CPU reference on every shipped scene; the paper's claim (hybrid beats oit
// on the close-up fur) and the sorted method's (it beats oit where opaque kernels overlap);
// sorted's exact back-to-front compositing of stacked lobes; determinism; finite output for
// degenerate lobes; refused settings.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <map>
#include <random>
#include <memory>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "noise/camera.h"
#include "noise/error.h"
#include "noise/impulses.h"
#include "noise/mesh.h"
#include "noise/preset.h"
#include "noise/reference.h"
#include "noise/scene.h"
#include "shaders/spot_shared.hpp"
#include "splat/image_compare.h"
#include "splat/layout.h"
#include "splat/passes/splatting_vk.h"
#include "splat_test_support.h"

namespace {

using namespace spot;
using namespace spot::test;

// ---- One lobe against its closed form --------------------------------------------------------

// ---- The splatting math of spot_shared.h, on the CPU (float: the GPU's twin) --------------------

namespace sh = spot::shared::f32;

TEST(SplatShared, CameraRayMatchesCameraRays) {
    for (auto projection : {noise::Projection::Perspective, noise::Projection::Orthographic}) {
        noise::Camera cam = lobeCamera(projection, 40);
        cam.width = 64;
        const noise::CameraRays rays(cam);
        const glm::dvec3 f = glm::normalize(cam.target - cam.eye);
        const glm::dvec3 r = glm::normalize(glm::cross(f, cam.up));
        const glm::dvec3 u = glm::cross(r, f);
        const double halfH = projection == noise::Projection::Orthographic
                                 ? 0.5 * cam.orthoHeight
                                 : std::tan(0.5 * cam.fovYDeg * M_PI / 180.0);
        const double halfW = halfH * cam.width / cam.height;
        for (double py : {0.0, 7.5, 40.0})
            for (double px : {0.0, 31.25, 64.0}) {
                glm::vec3 o, d;
                sh::spotCameraRay(
                    glm::vec3(cam.eye), glm::vec3(f), glm::vec3(r * halfW), glm::vec3(u * halfH),
                    projection == noise::Projection::Orthographic,
                    float(2.0 * px / cam.width - 1.0), float(1.0 - 2.0 * py / cam.height), o, d);
                const noise::Ray ray = rays.ray(px, py);
                EXPECT_LT(glm::length(glm::dvec3(o) - ray.origin), 1e-5);
                EXPECT_LT(glm::length(glm::dvec3(d) - ray.dir), 1e-6);
            }
    }
}

TEST(SplatShared, EllipsoidRangeBoundsItsProjection) {
    // A tilted ellipsoid in front of a perspective eye: its projection's extent along x, found by
    // brute force over the ellipsoid's surface, equals the tangent-plane range.
    const glm::mat3 A = glm::inverse(glm::mat3(
        glm::vec3(0.3f, 0.1f, 0.0f), glm::vec3(-0.05f, 0.2f, 0.1f), glm::vec3(0.0f, 0.2f, 0.6f)));
    const glm::vec3 centre(0.4f, -0.2f, -3.0f), eye(0.0f), forward(0.0f, 0.0f, -1.0f),
        axis(1.0f, 0.0f, 0.0f);
    const float k = 2.0f;
    float lo, hi, zLo, zHi;
    ASSERT_TRUE(sh::spotEllipsoidRange(centre - eye, glm::inverse(A), k, axis, forward, false, lo,
                                       hi, zLo, zHi));
    float bruteLo = 1e9f, bruteHi = -1e9f, bruteZLo = 1e9f, bruteZHi = -1e9f;
    for (int i = 0; i <= 400; ++i)
        for (int j = 0; j < 800; ++j) {
            const float theta = float(M_PI) * i / 400.0f, phi = 2.0f * float(M_PI) * j / 800.0f;
            const glm::vec3 unit(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi),
                                 std::cos(theta));
            const glm::vec3 x = centre + glm::inverse(A) * (k * unit);
            const float z = glm::dot(x - eye, forward);
            bruteLo = std::min(bruteLo, glm::dot(x - eye, axis) / z);
            bruteHi = std::max(bruteHi, glm::dot(x - eye, axis) / z);
            bruteZLo = std::min(bruteZLo, z);
            bruteZHi = std::max(bruteZHi, z);
        }
    EXPECT_NEAR(lo, bruteLo, 1e-3f);
    EXPECT_NEAR(hi, bruteHi, 1e-3f);
    EXPECT_LE(lo, bruteLo + 1e-5f); // a bound, never inside
    EXPECT_GE(hi, bruteHi - 1e-5f);
    EXPECT_NEAR(zLo, bruteZLo, 1e-3f);
    EXPECT_NEAR(zHi, bruteZHi, 1e-3f);
    // Reaching the eye plane: unbounded.
    EXPECT_FALSE(sh::spotEllipsoidRange(glm::vec3(0.0f, 0.0f, -0.5f), glm::inverse(A), k, axis,
                                        forward, false, lo, hi, zLo, zHi));
}

TEST(SplatShared, LobeDepthQuantileInvertsTheDepth) {
    const glm::vec3 o(0.3f, -0.4f, 2.5f), d = glm::normalize(glm::vec3(0.1f, 0.2f, -1.0f));
    float tPeak = 0.0f;
    const float total = sh::spotLobeDepth(o, d, 0.0f, 100.0f, 3.0f, tPeak);
    ASSERT_GT(total, 0.1f);
    for (float fraction : {0.01f, 0.25f, 0.5f, 0.9f, 0.999f}) {
        const float t = sh::spotLobeDepthQuantile(o, d, 0.0f, 100.0f, 3.0f, fraction);
        EXPECT_NEAR(sh::spotLobeDepth(o, d, 0.0f, t, 3.0f, tPeak) / total, fraction, 2e-4f)
            << fraction;
    }
    for (float x : {-0.999f, -0.5f, 0.0f, 0.3f, 0.99f, 0.99999f})
        EXPECT_NEAR(std::erf(double(sh::spotErfinvApprox(x))), x, 2e-6) << x;
    // The emission shares: the median of a thin medium is its middle, of an opaque one ln 2 deep.
    EXPECT_NEAR(sh::spotEmissionQuantileFraction(1e-6f, 0.5f), 0.5f, 1e-5f);
    EXPECT_NEAR(sh::spotEmissionQuantileFraction(100.0f, 0.5f) * 100.0f, std::log(2.0f), 1e-4f);
}

TEST(SplatShared, ScreenLobeDepthMatchesTheExactLineIntegral) {
    // The splat shaders' form of a lobe's optical depth (w = o' x v, on = o'.v, v = A e with e the
    // ray direction at unit view depth; A&S erf, no branch) against the
    // double-precision erfc form of the same integral, on random anisotropic lobes, rays through
    // and beside them, clipped by a mesh before, inside and after the chord, and by the eye.
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    namespace f64 = spot::shared::f64;
    int checked = 0, clipped = 0;
    double worst = 0.0, worstOld = 0.0;
    for (int i = 0; i < 4000; ++i) {
        const glm::dmat3 A = glm::dmat3(u(rng), u(rng), u(rng), u(rng), u(rng), u(rng), u(rng),
                                        u(rng), u(rng)) *
                             (1.0 + 40.0 * std::abs(u(rng)));
        const glm::dvec3 centre(u(rng), u(rng), -3.0 + u(rng));
        const glm::dvec3 eye(0.1 * u(rng), 0.1 * u(rng), 0.0);
        // Ray direction scaled to unit view depth along -z; aimed near the centre.
        const glm::dvec3 target = centre + 0.3 * glm::dvec3(u(rng), u(rng), u(rng));
        glm::dvec3 e = target - eye;
        e /= -e.z;
        const double k = 3.0;
        const glm::dvec3 o = A * (eye - centre), v = A * e;
        double tPeak = 0.0;
        const double full = f64::spotLobeDepth(o, v, 0.0, 1e30, k, tPeak);
        if (!(full > 0.0))
            continue;
        // Clip: none, the mesh somewhere around the chord, or the eye inside the support.
        const double halfChord = std::sqrt(std::max(0.0, k * k - glm::dot(glm::cross(o, v), glm::cross(o, v)) /
                                                               glm::dot(v, v))) / glm::length(v);
        const double tEnd = i % 3 == 0 ? 1e30 : tPeak + halfChord * 1.2 * u(rng);
        const double exact = f64::spotLobeDepth(o, v, 0.0, tEnd, k, tPeak);
        float peak = 0.0f;
        const float fast = sh::spotScreenLobeDepth(glm::vec3(glm::cross(o, v)), glm::vec3(v),
                                                   float(glm::dot(o, v)), float(tEnd), float(k), peak);
        // Absolute against the lobe's whole-line depth: erf to 1.5e-7 and float rounding of the
        // inputs and the arithmetic. (The world-space float form, spotLobeDepth in float, reaches
        // 5.1e-6 on these rays; the screen form 4.7e-6.)
        const double scale = std::sqrt(2.0 * M_PI) / glm::length(v);
        const double error = std::abs(fast - exact) / scale;
        worst = std::max(worst, error);
        float oldPeak = 0.0f;
        const float old = sh::spotLobeDepth(glm::vec3(o), glm::vec3(v), 0.0f, float(tEnd), float(k), oldPeak);
        worstOld = std::max(worstOld, std::abs(old - exact) / scale);
        EXPECT_LT(error, 5e-6) << i << ": " << fast << " vs " << exact;
        EXPECT_NEAR(peak, tPeak, 1e-5 * (1.0 + std::abs(tPeak))) << i;
        ++checked;
        clipped += tEnd < 1e29;
    }
    EXPECT_GT(checked, 1000);
    EXPECT_GT(clipped, 500);
    EXPECT_LE(worst, worstOld); // at least as accurate as the world-space form it replaced
    std::printf("screen-form lobe depth: %d rays, %d clipped, worst error %.2e of the whole line "
                "(world-space float form %.2e)\n",
                checked, clipped, worst, worstOld);
}

TEST(SplatShared, OitWeights) {
    EXPECT_EQ(sh::spotOitWeight(3.0f, 0.5f, sh::kSpotWeightConstant), 1.0f);
    // MB13 eq. 7 at z = 5: alpha x 10 / (1e-5 + 1 + 2.44e-10).
    EXPECT_NEAR(sh::spotOitWeight(5.0f, 0.5f, sh::kSpotWeightMcGuireBavoil),
                0.5f * 10.0f / 1.00001f, 1e-5f);
    EXPECT_NEAR(sh::spotOitWeight(1e-3f, 1.0f, sh::kSpotWeightMcGuireBavoil), 3e3f,
                1e-2f); // clamped
    EXPECT_NEAR(sh::spotOitWeight(1e4f, 1.0f, sh::kSpotWeightMcGuireBavoil), 1e-2f, 1e-7f);
    EXPECT_LT(sh::spotOitWeight(4.0f, 1.0f, sh::kSpotWeightMcGuireBavoil),
              sh::spotOitWeight(2.0f, 1.0f, sh::kSpotWeightMcGuireBavoil));
    EXPECT_NEAR(sh::spotOneMinusExp(1e-6f), 1e-6f, 1e-12f);
    EXPECT_NEAR(sh::spotOneMinusExp(2.0f), 1.0f - std::exp(-2.0f), 1e-7f);
}

struct LobeCase {
    noise::Kernel kernel;
    std::vector<noise::Impulse> impulses;
    glm::vec3 color{0.9f, 0.6f, 0.3f};
    glm::vec3 background{0.1f, 0.2f, 0.3f};
};

/// A tilted anisotropic lobe; support 6 sigma so the truncation is far below the tolerances.
LobeCase isolatedLobe(float extinction) {
    LobeCase c;
    c.kernel = oneLobeKernel({0.3f, 0.2f, 0.5f}, {20.0f, 35.0f, -10.0f}, extinction, c.color, 6.0f);
    c.impulses = {impulseAt(glm::vec3(0.05f, -0.1f, 0.0f))};
    return c;
}

/// Closed-form alpha of the lobe at a continuous pixel position.
double lobeAlpha(const LobeCase& c, const noise::CameraRays& rays, double px, double py) {
    const noise::Ray r = rays.ray(px, py);
    return 1.0 - std::exp(-closedFormDepth(noise::placeLobe(c.kernel, 0, c.impulses[0]), r.origin,
                                           r.dir));
}

TEST(SplatRenderer, IsolatedLobeMatchesTheClosedForm) {
    const LobeCase c = isolatedLobe(3.0f);
    splat::Context ctx(validated());
    const noise::Mesh empty;
    SplatRig renderer(ctx, empty, c.kernel);
    const splat::Buffer impulses = upload(ctx, c.impulses);
    for (auto projection : {noise::Projection::Orthographic, noise::Projection::Perspective}) {
        const noise::Camera cam = lobeCamera(projection, 48);
        const noise::CameraRays rays(cam);
        // OIT, hybrid and sorted on a lone kernel reduce to the exact composite
        // C alpha + bg (1 - alpha), whatever the weight; without EWA at pixel centres, with EWA
        // against the box-filtered pixel (16x16 midpoint grid), whose variance EWA matches.
        for (splat::Method method :
             {splat::Method::Oit, splat::Method::Hybrid, splat::Method::Sorted}) {
            for (auto weight : {splat::OitWeight::Constant, splat::OitWeight::McGuireBavoil}) {
                for (bool ewa : {false, true}) {
                    SplatSettings s;
                    s.method = method;
                    s.weight = weight;
                    s.ewa = ewa;
                    splat::FrameStats stats;
                    const noise::Image image =
                        renderer.render(cam, noise::Shading{}, c.background, glm::vec3(0.0f),
                                        impulses, 1, s, &stats);
                    EXPECT_EQ(stats.counters.kernelsDrawn, 1u);
                    double worst = 0.0;
                    for (int y = 0; y < cam.height; ++y)
                        for (int x = 0; x < cam.width; ++x) {
                            double alpha = 0.0;
                            if (!ewa) {
                                alpha = lobeAlpha(c, rays, x + 0.5, y + 0.5);
                            } else {
                                for (int j = 0; j < 16; ++j)
                                    for (int i = 0; i < 16; ++i)
                                        alpha += lobeAlpha(c, rays, x + (i + 0.5) / 16.0,
                                                           y + (j + 0.5) / 16.0);
                                alpha /= 256.0;
                            }
                            for (int ch = 0; ch < 3; ++ch) {
                                const double expected =
                                    alpha * c.color[ch] + (1.0 - alpha) * c.background[ch];
                                worst = std::max(worst, std::abs(image.at(x, y)[ch] - expected));
                            }
                        }
                    // Float32 erfc (1.2e-7) and camera maths: 1e-4 at pixel centres. EWA's
                    // Gaussian against the box: the lobe spans ~10 pixels, 2e-3.
                    EXPECT_LT(worst, ewa ? 2e-3 : 1e-4)
                        << splat::methodName(method) << " weight " << int(weight) << " ewa " << ewa
                        << (projection == noise::Projection::Orthographic ? " ortho"
                                                                          : " perspective");
                }
            }
        }
        // N_s samples (paper eq. 10) converge to the analytic result.
        for (int samples : {64, 512}) {
            SplatSettings s;
            s.method = splat::Method::Oit;
            s.ewa = false;
            s.kernelSamples = samples;
            const noise::Image image = renderer.render(cam, noise::Shading{}, c.background,
                                                       glm::vec3(0.0f), impulses, 1, s);
            double worst = 0.0;
            for (int y = 0; y < cam.height; ++y)
                for (int x = 0; x < cam.width; ++x) {
                    const double alpha = lobeAlpha(c, rays, x + 0.5, y + 0.5);
                    worst = std::max(
                        worst, std::abs(image.at(x, y).r -
                                        (alpha * c.color.r + (1.0 - alpha) * c.background.r)));
                }
            EXPECT_LT(worst, samples == 64 ? 5e-3 : 2e-4) << samples << " samples";
        }
        // Instanced: opaque where the closed-form optical depth reaches the lobe's cover
        // threshold c = t e^-Ein(t) (t its peak depth along the view through its centre: the
        // opaque region then covers as much of the image as the lobe does), background elsewhere
        // (pixels within 3% of c are not judged).
        SplatSettings s;
        s.method = splat::Method::Instanced;
        s.ewa = false;
        const noise::Image image =
            renderer.render(cam, noise::Shading{}, c.background, glm::vec3(0.0f), impulses, 1, s);
        const noise::WorldLobe placed = noise::placeLobe(c.kernel, 0, c.impulses[0]);
        const glm::dvec3 view = projection == noise::Projection::Orthographic
                                    ? rays.forward()
                                    : glm::normalize(placed.centre - cam.eye);
        const double peak = placed.extinction * std::sqrt(2.0 * glm::pi<double>()) /
                            glm::length(placed.toLobe * view);
        const double threshold = spot::shared::f64::spotCoverThreshold(peak);
        ASSERT_GT(peak, threshold);
        int covered = 0, wrong = 0;
        for (int y = 0; y < cam.height; ++y)
            for (int x = 0; x < cam.width; ++x) {
                const noise::Ray r = rays.ray(x + 0.5, y + 0.5);
                const double depth = closedFormDepth(placed, r.origin, r.dir);
                if (std::abs(depth / threshold - 1.0) < 0.03)
                    continue;
                const glm::vec3 expected = depth > threshold ? c.color : c.background;
                covered += depth > threshold;
                wrong += glm::length(image.at(x, y) - expected) > 1e-5f;
            }
        EXPECT_GT(covered, 50);
        EXPECT_EQ(wrong, 0);
    }
    expectNoValidationErrors(ctx);
}

TEST(SplatRenderer, LongestMarchStaysWithinTheLoopBudget) {
    // lavapipe silently stops a shader after 65,535 loop iterations: the longest march allowed
    // (2048 samples x 8 lobes) must still reach the analytic result. Eight lobes of one colour,
    // so the analytic composite is exact whatever their overlap.
    noise::KernelDesc desc;
    for (int l = 0; l < 8; ++l) {
        noise::LobeDesc lobe;
        lobe.sigma = glm::vec3(0.15f + 0.02f * l, 0.2f, 0.1f + 0.03f * l);
        lobe.offset = glm::vec3(0.05f * l - 0.2f, 0.03f * l, 0.08f * l - 0.3f);
        lobe.rotationDeg = glm::vec3(10.0f * l, 0.0f, 5.0f * l);
        lobe.extinction = 1.5f;
        lobe.color = glm::vec3(0.8f, 0.5f, 0.2f);
        desc.lobes.push_back(lobe);
    }
    desc.supportSigma = 3.0f;
    const noise::Kernel kernel = noise::buildKernel(desc);
    splat::Context ctx(validated());
    const noise::Mesh empty;
    SplatRig renderer(ctx, empty, kernel);
    const splat::Buffer impulses = upload(ctx, {impulseAt(glm::vec3(0.0f))});
    const noise::Camera cam = lobeCamera(noise::Projection::Perspective, 32);
    SplatSettings s;
    s.method = splat::Method::Oit;
    s.ewa = false;
    const noise::Image analytic =
        renderer.render(cam, noise::Shading{}, glm::vec3(0.0f), glm::vec3(0.0f), impulses, 1, s);
    s.kernelSamples = 2048;
    const noise::Image marched =
        renderer.render(cam, noise::Shading{}, glm::vec3(0.0f), glm::vec3(0.0f), impulses, 1, s);
    double worst = 0.0, brightest = 0.0;
    for (std::size_t i = 0; i < analytic.pixels.size(); ++i) {
        worst = std::max(worst, double(glm::length(analytic.pixels[i] - marched.pixels[i])));
        brightest = std::max(brightest, double(analytic.pixels[i].r));
    }
    EXPECT_GT(brightest, 0.3); // a visible kernel
    EXPECT_LT(worst, 1e-3);
    expectNoValidationErrors(ctx);
}

TEST(SplatRenderer, MeshEndsTheKernelAndOccludesIt) {
    // A lobe centred on a plane seen from above: only its upper half shows, over the plane's
    // colour; past the plane's edge the background.
    const noise::Mesh plane = noise::makePlane(2.0f, 2); // y = 0, normal +y
    const noise::Kernel kernel =
        oneLobeKernel(glm::vec3(0.1f), glm::vec3(0.0f), 20.0f, glm::vec3(1.0f), 6.0f);
    const std::vector<noise::Impulse> imps{impulseAt(glm::vec3(0.0f))};
    splat::Context ctx(validated());
    SplatRig renderer(ctx, plane, kernel);
    const splat::Buffer impulses = upload(ctx, imps);
    const noise::Camera cam = topDownCamera();
    const glm::vec3 base(0.2f, 0.5f, 0.1f), background(1.0f, 0.0f, 1.0f);
    const noise::WorldLobe w = noise::placeLobe(kernel, 0, imps[0]);
    const noise::CameraRays rays(cam);
    const noise::Ray centre = rays.ray(16.0, 16.0); // the lobe's axis: a pixel corner
    const double half = 0.5 * closedFormDepth(w, centre.origin, centre.dir);
    for (splat::Method method :
         {splat::Method::Oit, splat::Method::Hybrid, splat::Method::Sorted}) {
        SplatSettings s;
        s.method = method;
        s.ewa = false;
        const noise::Image image =
            renderer.render(cam, noise::Shading{}, background, base, impulses, 1, s);
        // The four pixels around the axis are 0.0625 units off it; check one against its own ray.
        const noise::Ray r = rays.ray(16.5, 16.5);
        const double h = 0.5 * closedFormDepth(w, r.origin, r.dir);
        EXPECT_NEAR(image.at(16, 16).g, (1.0 - std::exp(-h)) + std::exp(-h) * base.g, 1e-4)
            << splat::methodName(method);
        EXPECT_GT(half, 1.0);                          // the test must exercise real occlusion
        EXPECT_NEAR(image.at(22, 16).g, base.g, 1e-6); // plane beside the lobe
        EXPECT_NEAR(image.at(31, 31).r, background.r, 1e-6); // past the plane's corner
    }
    expectNoValidationErrors(ctx);
}

/// A renderer's extra counter (0 when it has none of that name).
double extraCounter(const splat::FrameStats& stats, const std::string& name) {
    for (const auto& [key, value] : stats.counters.extra)
        if (key == name)
            return value;
    return 0.0;
}

TEST(SplatRenderer, InstancedHidesAKernelWhoseDepthIsAtTheMesh) {
    // Instanced splats are opaque at their kernel's depth (the mean of its lobes' peaks along the
    // ray, clamped to the mesh), so the mesh hides a kernel whose peaks lie behind it, even where
    // the part in front of the mesh is opaque enough (alpha over 0.5). A lobe centred just above
    // the plane shows; the same lobe just below it does not. On the raster path and on the compute
    // path of small kernels.
    const noise::Mesh plane = noise::makePlane(2.0f, 2); // y = 0, normal +y
    const noise::Kernel kernel =
        oneLobeKernel(glm::vec3(0.1f), glm::vec3(0.0f), 20.0f, glm::vec3(1.0f), 6.0f);
    splat::Context ctx(validated());
    SplatRig renderer(ctx, plane, kernel);
    const noise::Camera cam = topDownCamera();
    const glm::vec3 base(0.2f, 0.5f, 0.1f), background(1.0f, 0.0f, 1.0f);
    for (float height : {0.05f, -0.05f}) {
        const splat::Buffer impulses = upload(ctx, {impulseAt(glm::vec3(0.0f, height, 0.0f))});
        // The premise: in front of the plane the lobe's alpha passes 0.5 either way
        // (OIT: red = alpha + (1 - alpha) 0.2).
        SplatSettings oit;
        oit.method = splat::Method::Oit;
        oit.ewa = false;
        const noise::Image blended =
            renderer.render(cam, noise::Shading{}, background, base, impulses, 1, oit);
        EXPECT_GT(blended.at(16, 16).r, 0.2f + 0.8f * 0.5f) << height;
        for (int smallPixels : {0, int(splat::gpu_splat::kSplatMaxSmallPixels)}) {
            SplatSettings s;
            s.method = splat::Method::Instanced;
            s.ewa = false;
            s.smallPixels = smallPixels;
            splat::FrameStats stats;
            const noise::Image image =
                renderer.render(cam, noise::Shading{}, background, base, impulses, 1, s, &stats);
            EXPECT_EQ(extraCounter(stats, "kernels_small"), smallPixels > 0 ? 1.0 : 0.0);
            const glm::vec3 expected = height > 0.0f ? glm::vec3(1.0f) : base;
            EXPECT_LT(glm::length(image.at(16, 16) - expected), 1e-5f)
                << "height " << height << " smallPixels " << smallPixels;
            EXPECT_LT(glm::length(image.at(22, 16) - base), 1e-5f); // plane beside the lobe
        }
    }
    expectNoValidationErrors(ctx);
}

TEST(SplatRenderer, ClosedMeshCullsBackFacesWithTheSameImage) {
    // A closed, outward sphere seen from outside: the mesh pass culls its back faces, and every
    // method's image is that of the same sphere made open by one triangle behind the eye (nothing
    // culled). Where a ray may start inside the sphere (the eye inside it, or the near plane or
    // the orthographic eye plane cutting it), nothing is culled and the inside shows.
    const noise::Mesh sphere = noise::makeSphere(1.0f, 24, 48);
    noise::Mesh open = sphere;
    const auto n = std::uint32_t(open.positions.size());
    for (const glm::vec3 p : {glm::vec3(0.0f, 0.0f, 50.0f), glm::vec3(0.1f, 0.0f, 50.0f),
                              glm::vec3(0.0f, 0.1f, 50.0f)}) {
        open.positions.push_back(p);
        open.normals.push_back(glm::vec3(0.0f, 0.0f, 1.0f));
        open.uvs.push_back(glm::vec2(0.0f));
    }
    open.triangles.push_back({n, n + 1, n + 2});
    noise::finalizeMesh(open);
    const noise::Kernel kernel =
        oneLobeKernel(glm::vec3(0.2f), glm::vec3(0.0f), 4.0f, glm::vec3(1.0f, 0.6f, 0.2f), 4.0f);
    splat::Context ctx(validated());
    SplatRig closedRig(ctx, sphere, kernel), openRig(ctx, open, kernel);
    const splat::Buffer impulses = upload(ctx, {impulseAt(glm::vec3(0.1f, 0.2f, 0.95f))});
    const glm::vec3 base(0.2f, 0.5f, 0.1f), background(1.0f, 0.0f, 1.0f);
    const auto culls = [&](const SplatRig& rig, const noise::Camera& cam) {
        return rig.scene().meshPass().cullsBackFaces(
            splat::makeSplatFrame(cam, noise::Shading{}, base, 1, 1, kernel.supportSigma, 0, 0));
    };
    const noise::Camera outside = lobeCamera(noise::Projection::Perspective, 32);
    EXPECT_TRUE(culls(closedRig, outside));
    EXPECT_FALSE(culls(openRig, outside));
    for (splat::Method method : {splat::Method::Instanced, splat::Method::Oit,
                                 splat::Method::Hybrid, splat::Method::Sorted}) {
        SplatSettings s;
        s.method = method;
        const noise::Image a =
            closedRig.render(outside, noise::Shading{}, background, base, impulses, 1, s);
        const noise::Image b =
            openRig.render(outside, noise::Shading{}, background, base, impulses, 1, s);
        for (int y = 0; y < a.height; ++y)
            for (int x = 0; x < a.width; ++x)
                ASSERT_EQ(a.at(x, y), b.at(x, y)) << splat::methodName(method) << " " << x << "," << y;
        EXPECT_EQ(a.at(2, 2), background); // the test sees both the sphere and the background
        EXPECT_NE(a.at(16, 16), background);
    }
    noise::Camera inside = outside;
    inside.eye = glm::dvec3(0.0, 0.0, 0.5);
    inside.target = glm::dvec3(0.0, 0.0, -1.0);
    noise::Camera grazing = outside; // the eye just outside, the near plane cutting the sphere
    grazing.eye = glm::dvec3(0.0, 0.0, 1.0 + 0.5 * splat::kNearPlane);
    grazing.target = glm::dvec3(0.0);
    noise::Camera cut = inside; // orthographic rays start on the eye's plane, inside the sphere
    cut.projection = noise::Projection::Orthographic;
    cut.orthoHeight = 0.5;
    for (const noise::Camera& cam : {inside, grazing, cut}) {
        EXPECT_FALSE(culls(closedRig, cam));
        SplatSettings s;
        s.method = splat::Method::Oit;
        const noise::Image image =
            closedRig.render(cam, noise::Shading{}, background, base, impulses, 0, s);
        EXPECT_LT(glm::length(image.at(16, 16) - base), 1e-6f); // the sphere's inside
    }
    expectNoValidationErrors(ctx);
}

TEST(SplatRenderer, LobeReachingTheEyePlaneIsClippedToTheImage) {
    // A lobe whose support reaches behind the camera projects to no ellipse. Its quad is the box
    // of the image pixels whose ray line meets the support, not the whole image (a grazing view of
    // grass shaded 3.7 times the fragments it needed): a long lobe along the view axis, beside the
    // eye, its support from behind the eye to past its centre, shows in the image's left part
    // only. The image is still the closed form of the truncated lobe over the ray's half line
    // t >= 0.
    const double k = 3.0;
    const noise::Kernel kernel =
        oneLobeKernel({0.15f, 0.15f, 0.6f}, glm::vec3(0.0f), 3.0f, glm::vec3(1.0f), float(k));
    const std::vector<noise::Impulse> imps{impulseAt(glm::vec3(0.0f))};
    const glm::vec3 background(0.1f, 0.2f, 0.3f);
    splat::Context ctx(validated());
    const noise::Mesh empty;
    SplatRig renderer(ctx, empty, kernel);
    const splat::Buffer impulses = upload(ctx, imps);
    noise::Camera cam;
    cam.projection = noise::Projection::Perspective;
    cam.eye = glm::dvec3(0.8, 0.0, 1.0);
    cam.target = glm::dvec3(0.8, 0.0, 0.0);
    cam.fovYDeg = 100.0;
    cam.width = cam.height = 48;
    const noise::WorldLobe w = noise::placeLobe(kernel, 0, imps[0]);
    const glm::dmat3 toLobe(w.toLobe);
    const noise::CameraRays rays(cam);
    // The support reaches behind the eye plane (its depth range is 1 +- 1.8), and the eye is
    // outside it (else every pixel's line would meet it).
    ASSERT_GT(glm::length(toLobe * (cam.eye - glm::dvec3(w.centre))), k);
    int lineMeets = 0;
    double alphaSum = 0.0;
    glm::ivec2 lo(cam.width, cam.height), hi(-1, -1); // their box
    std::vector<double> alpha(std::size_t(cam.width * cam.height), 0.0);
    for (int y = 0; y < cam.height; ++y)
        for (int x = 0; x < cam.width; ++x) {
            const noise::Ray r = rays.ray(x + 0.5, y + 0.5);
            const glm::dvec3 op = toLobe * (r.origin - glm::dvec3(w.centre));
            const glm::dvec3 dp = toLobe * r.dir;
            const double dd = glm::dot(dp, dp), od = glm::dot(op, dp);
            const double perp2 = glm::dot(op, op) - od * od / dd;
            if (!(perp2 < k * k))
                continue;
            ++lineMeets;
            lo = glm::min(lo, glm::ivec2(x, y));
            hi = glm::max(hi, glm::ivec2(x, y));
            // Arc length s = (t - t*) |dp| over the chord |s| < h, from the eye (t = 0) on.
            const double h = std::sqrt(k * k - perp2);
            const double s0 = std::max(-h, (od / dd) * std::sqrt(dd)); // t = 0: s = -t* |dp|
            if (!(h > s0))
                continue;
            const double tau = w.extinction * std::exp(-0.5 * perp2) / std::sqrt(dd) *
                               std::sqrt(M_PI / 2.0) *
                               (std::erf(h / std::sqrt(2.0)) - std::erf(s0 / std::sqrt(2.0)));
            alpha[std::size_t(y * cam.width + x)] = 1.0 - std::exp(-tau);
            alphaSum += 1.0 - std::exp(-tau);
        }
    const int pixels = cam.width * cam.height;
    // The box's pixels, with the bound's padding of a pixel on each side.
    const glm::ivec2 boxSize = hi - lo + 1;
    const int padded = std::min(boxSize.x + 2, cam.width) * std::min(boxSize.y + 2, cam.height);
    ASSERT_GT(lineMeets, pixels / 10);
    ASSERT_LT(padded, 3 * pixels / 4);
    ASSERT_GT(alphaSum, 20.0); // a visible lobe
    for (splat::Method method : {splat::Method::Oit, splat::Method::Hybrid, splat::Method::Sorted}) {
        SplatSettings s;
        s.method = method;
        s.ewa = false;
        s.smallPixels = 0;
        s.countFragments = true;
        splat::FrameStats stats;
        const noise::Image image = renderer.render(cam, noise::Shading{}, background,
                                                   glm::vec3(0.0f), impulses, 1, s, &stats);
        EXPECT_EQ(stats.counters.kernelsDrawn, 1u) << splat::methodName(method);
        double worst = 0.0;
        for (int y = 0; y < cam.height; ++y)
            for (int x = 0; x < cam.width; ++x) {
                const double a = alpha[std::size_t(y * cam.width + x)];
                for (int ch = 0; ch < 3; ++ch)
                    worst = std::max(worst, std::abs(image.at(x, y)[ch] -
                                                     (a + (1.0 - a) * background[ch])));
            }
        EXPECT_LT(worst, 1e-4) << splat::methodName(method);
        // The box of the pixels whose line meets the support (measured: 1536 fragments, that box
        // being 32 x 48 pixels), not the whole image (2304).
        EXPECT_GE(stats.counters.fragmentsShaded, std::uint64_t(lineMeets)) << splat::methodName(method);
        EXPECT_LE(stats.counters.fragmentsShaded, std::uint64_t(padded)) << splat::methodName(method);
    }
    expectNoValidationErrors(ctx);
}

TEST(SplatRenderer, ClippedKernelAmongBoundedOnesIsBoundedByPrepareSecondDispatch) {
    // prepare bounds a kernel whose lobe reaches the eye plane in a second dispatch over the
    // kernels its first one listed (splat_prepare.comp). With that kernel third in the list,
    // after two that project to ellipses, it must render as it does alone: the second dispatch
    // has to take the listed kernel, not its own invocation index. Compared where the two others
    // alone leave the background, which must be where the clipped kernel shows.
    const noise::Kernel kernel =
        oneLobeKernel({0.15f, 0.15f, 0.6f}, glm::vec3(0.0f), 3.0f, glm::vec3(1.0f), 3.0f);
    const std::vector<noise::Impulse> clipped{impulseAt(glm::vec3(0.0f))};
    const std::vector<noise::Impulse> bounded{impulseAt({1.7f, 0.5f, -1.5f}),
                                              impulseAt({1.7f, -0.5f, -2.0f})};
    std::vector<noise::Impulse> all = bounded;
    all.push_back(clipped[0]);
    const glm::vec3 background(0.1f, 0.2f, 0.3f);
    splat::Context ctx(validated());
    const noise::Mesh empty;
    SplatRig renderer(ctx, empty, kernel);
    const splat::Buffer clippedBuffer = upload(ctx, clipped);
    const splat::Buffer boundedBuffer = upload(ctx, bounded);
    const splat::Buffer allBuffer = upload(ctx, all);
    noise::Camera cam; // as in LobeReachingTheEyePlaneIsClippedToTheImage
    cam.projection = noise::Projection::Perspective;
    cam.eye = glm::dvec3(0.8, 0.0, 1.0);
    cam.target = glm::dvec3(0.8, 0.0, 0.0);
    cam.fovYDeg = 100.0;
    cam.width = cam.height = 48;
    for (splat::Method method : {splat::Method::Oit, splat::Method::Hybrid, splat::Method::Sorted,
                                 splat::Method::Instanced}) {
        SplatSettings s;
        s.method = method;
        s.ewa = false;
        const auto draw = [&](const splat::Buffer& b, std::size_t n) {
            return renderer.render(cam, noise::Shading{}, background, glm::vec3(0.0f), b,
                                   std::uint32_t(n), s);
        };
        const noise::Image alone = draw(clippedBuffer, clipped.size());
        const noise::Image others = draw(boundedBuffer, bounded.size());
        const noise::Image together = draw(allBuffer, all.size());
        int compared = 0, shown = 0, othersShown = 0;
        double worst = 0.0;
        for (int y = 0; y < cam.height; ++y)
            for (int x = 0; x < cam.width; ++x) {
                if (glm::vec3(others.at(x, y)) != background) {
                    ++othersShown;
                    continue;
                }
                ++compared;
                shown += glm::length(glm::vec3(alone.at(x, y)) - background) > 1e-3f;
                worst = std::max(worst, double(glm::length(glm::vec3(together.at(x, y)) -
                                                           glm::vec3(alone.at(x, y)))));
            }
        const std::string name = splat::methodName(method);
        EXPECT_GT(othersShown, 20) << name; // the bounded kernels are in the image
        EXPECT_GT(shown, 100) << name;      // and the clipped one shows where they are not
        EXPECT_LT(worst, 1e-6) << name << " (" << compared << " pixels compared)";
    }
    expectNoValidationErrors(ctx);
}

TEST(SplatRenderer, SortedCompositesStackedKernelsBackToFront) {
    // Three semi-transparent lobes of different colours stacked along the view axis, overlapping
    // on screen but 4 units apart in depth (support 6 sigma = 1.8 units), so no ray crosses two
    // at once: the exact image is their closed-form alphas composited back to front over the
    // background. The impulses are listed neither front to back nor back to front; listed in
    // reverse they must give the same bytes. OIT must miss (or the scene would not tell).
    const noise::Kernel kernel =
        oneLobeKernel(glm::vec3(0.3f), glm::vec3(0.0f), 1.5f, glm::vec3(1.0f), 6.0f);
    std::vector<noise::Impulse> imps = {impulseAt({0.15f, 0.0f, -4.0f}),
                                        impulseAt({-0.15f, 0.1f, 0.0f}),
                                        impulseAt({0.0f, -0.15f, -8.0f})};
    imps[0].color = {0.9f, 0.1f, 0.1f};
    imps[1].color = {0.1f, 0.8f, 0.2f};
    imps[2].color = {0.2f, 0.3f, 1.0f};
    noise::Camera cam;
    cam.projection = noise::Projection::Orthographic;
    cam.eye = glm::dvec3(0.0, 0.0, 20.0);
    cam.target = glm::dvec3(0.0);
    cam.up = glm::dvec3(0.0, 1.0, 0.0);
    cam.orthoHeight = 2.5;
    cam.width = cam.height = 48;
    const noise::CameraRays rays(cam);
    const glm::vec3 background(0.05f, 0.1f, 0.15f);
    const int backToFront[3] = {2, 0, 1}; // z = -8, -4, 0 seen from z = 20

    splat::Context ctx(validated());
    const noise::Mesh empty;
    SplatRig renderer(ctx, empty, kernel);
    const splat::Buffer listed = upload(ctx, imps);
    const splat::Buffer reversed = upload(ctx, {imps[2], imps[1], imps[0]});
    SplatSettings s;
    s.ewa = false;
    auto worstError = [&](const noise::Image& image) {
        double worst = 0.0;
        for (int y = 0; y < cam.height; ++y)
            for (int x = 0; x < cam.width; ++x) {
                const noise::Ray r = rays.ray(x + 0.5, y + 0.5);
                glm::dvec3 expected(background);
                for (int i : backToFront) {
                    const double alpha =
                        1.0 - std::exp(-closedFormDepth(noise::placeLobe(kernel, 0, imps[i]),
                                                        r.origin, r.dir));
                    expected = alpha * glm::dvec3(imps[i].color) + (1.0 - alpha) * expected;
                }
                for (int ch = 0; ch < 3; ++ch)
                    worst = std::max(worst, std::abs(image.at(x, y)[ch] - expected[ch]));
            }
        return worst;
    };
    s.method = splat::Method::Sorted;
    const noise::Image sorted =
        renderer.render(cam, noise::Shading{}, background, glm::vec3(0.0f), listed, 3, s);
    const noise::Image sortedReversed =
        renderer.render(cam, noise::Shading{}, background, glm::vec3(0.0f), reversed, 3, s);
    s.method = splat::Method::Oit;
    const noise::Image oit =
        renderer.render(cam, noise::Shading{}, background, glm::vec3(0.0f), listed, 3, s);
    // The isolated lobe's tolerance: float32 erfc and camera maths.
    EXPECT_LT(worstError(sorted), 1e-4);
    EXPECT_EQ(std::memcmp(sorted.pixels.data(), sortedReversed.pixels.data(),
                          sorted.pixels.size() * sizeof(glm::vec3)),
              0);
    EXPECT_GT(worstError(oit), 0.05);
    expectNoValidationErrors(ctx);
}

TEST(SplatRenderer, SortedReportsItsSortPass) {
    const LobeCase c = isolatedLobe(3.0f);
    splat::Context ctx(validated());
    const noise::Mesh empty;
    SplatRig renderer(ctx, empty, c.kernel);
    const splat::Buffer impulses = upload(ctx, c.impulses);
    const noise::Camera cam = lobeCamera(noise::Projection::Perspective, 32);
    for (splat::Method method : {splat::Method::Oit, splat::Method::Sorted}) {
        SplatSettings s;
        s.method = method;
        for (std::uint32_t count : {0u, 1u}) {
            splat::FrameStats stats;
            const auto start = std::chrono::steady_clock::now();
            const noise::Image image = renderer.render(cam, noise::Shading{}, c.background,
                                                       glm::vec3(0.0f), impulses, count, s, &stats);
            const double wallMs = std::chrono::duration<double, std::milli>(
                                      std::chrono::steady_clock::now() - start)
                                      .count();
            std::vector<std::string> names;
            for (const auto& [name, ms] : stats.passMs) {
                names.push_back(name);
                // Spans between consecutive slots: a slot written out of order gives a negative
                // one; one never written, whatever the driver left there.
                EXPECT_TRUE(std::isfinite(ms)) << name;
                EXPECT_GE(ms, 0.0) << name;
                if (name == "resolve") // a dispatch over every pixel, whatever the kernels
                    EXPECT_GT(ms, 0.0);
            }
            const std::vector<std::string> expected =
                method == splat::Method::Sorted
                    ? std::vector<std::string>{"prepare", "sort", "mesh", "splat", "resolve"}
                    : std::vector<std::string>{"prepare", "mesh", "splat", "resolve"};
            EXPECT_EQ(names, expected);
            // The GPU time lies within the host's wait for it: a wrong tick period (units) or
            // timestamps of another frame would break this. 1% for two clocks on a real GPU.
            EXPECT_GT(stats.gpuMs, 0.0);
            EXPECT_LE(stats.gpuMs, wallMs * 1.01) << "GPU ms against the render call's wall ms";
            EXPECT_EQ(stats.counters.kernelsDrawn, count);
            if (count == 0) // nothing but the background
                EXPECT_EQ(image.at(16, 16), c.background);
        }
    }
    // Per kernel, sorted adds its sort keys and the sort's scratch to what oit needs.
    const splat::SceneGpu scene(ctx, empty, c.kernel);
    const auto sorted = splat::makeSplattingRenderer(scene, splat::Method::Sorted);
    const auto oit = splat::makeSplattingRenderer(scene, splat::Method::Oit);
    EXPECT_GT(sorted->frameBytes(64, 64, 1000, {}) - sorted->frameBytes(64, 64, 0, {}),
              oit->frameBytes(64, 64, 1000, {}) - oit->frameBytes(64, 64, 0, {}));
    expectNoValidationErrors(ctx);
}

// ---- The shipped scenes against the reference ------------------------------------------------

constexpr int kSceneSize = 128;
constexpr int kReferenceSpp = 64;

/// Reference renders, computed once per test process (the scene test uses all six).
const noise::Image& referenceImage(const std::string& name) {
    return test::referenceImage(name, kSceneSize, kReferenceSpp);
}

struct Configuration {
    const char* label;
    SplatSettings settings;
};

std::vector<Configuration> configurations() {
    SplatSettings instanced, oit, oitConstant, hybrid, hybridSamples, sorted;
    instanced.method = splat::Method::Instanced;
    oit.method = splat::Method::Oit;
    oitConstant.method = splat::Method::Oit;
    oitConstant.weight = splat::OitWeight::Constant;
    hybrid.method = splat::Method::Hybrid;
    hybridSamples.method = splat::Method::Hybrid;
    hybridSamples.kernelSamples = 16;
    sorted.method = splat::Method::Sorted;
    return {{"instanced", instanced},      {"oit", oit},
            {"oit-constant", oitConstant}, {"hybrid", hybrid},
            {"hybrid-N16", hybridSamples}, {"sorted", sorted}};
}

struct Measured {
    double psnr = 0.0, flip = 0.0, ms = 0.0;
    std::uint32_t kernels = 0;
    noise::Image image;
    std::vector<float> flipMap;
};

Measured measure(splat::Context& ctx, const SceneSetup& s, const noise::Image& reference,
                 const SplatSettings& settings) {
    SplatRig renderer(ctx, s.mesh, s.kernel);
    const splat::Buffer impulses = upload(ctx, s.impulses);
    splat::FrameStats stats;
    Measured out;
    out.image =
        renderer.render(s.scene.camera, s.scene.shading, s.scene.background, s.scene.baseColor,
                        impulses, std::uint32_t(s.impulses.size()), settings, &stats);
    const splat::ImageMetrics m = splat::compareImages(reference, out.image, &out.flipMap);
    out.psnr = m.psnr;
    out.flip = m.flip;
    out.ms = stats.gpuMs;
    out.kernels = stats.counters.kernelsDrawn;
    if (std::getenv("SPOT_SPLAT_TEST_PASSES"))
        for (const auto& [pass, ms] : stats.passMs)
            std::printf("    %s %.2f ms\n", pass.c_str(), ms);
    return out;
}

/// The render, the reference and the FLIP map, into the test's temporary folder (on failure, or
/// always when SPOT_SPLAT_TEST_IMAGES is set).
void writeImages(const std::string& scene, const std::string& label, const Measured& m,
                 const noise::Image& reference) {
    const std::filesystem::path dir = SPOT_TEST_TMP_DIR;
    noise::writeImage(dir / ("splat-" + scene + "-" + label + ".png"), m.image);
    noise::writeImage(dir / ("splat-" + scene + "-reference.png"), reference);
    noise::writeImage(dir / ("splat-" + scene + "-" + label + "-flip.png"),
                      splat::heatMap(m.flipMap, m.image.width, m.image.height));
    std::printf("wrote %s\n", (dir / ("splat-" + scene + "-" + label + "*.png")).c_str());
}

/// Tolerances per scene and configuration: about 0.5 dB below the PSNR and 10% above the mean
/// FLIP measured at 128x128 against the reference at 64 spp (lavapipe, Mesa 22.3). Measured:
///
///   scene               instanced   oit         oit-constant hybrid      hybrid-N16  sorted
///   fur-bunny-close     26.03 .1462 29.83 .1188 29.11 .1262 31.92 .1121 33.89 .0713 32.06 .1095
///   fur-bunny           25.41 .0903 32.14 .0664 32.94 .0632 32.54 .0691 32.88 .0655 33.19 .0769
///   fur-bunny-far       32.08 .0159 44.16 .0041 44.22 .0042 44.18 .0042 44.14 .0042 44.53 .0053
///   grass-plane-grazing 26.86 .1021 38.74 .0567 38.59 .0595 39.04 .0548 39.32 .0537 41.77 .0365
///   lichen-torus        25.37 .1826 26.20 .1826 25.48 .2022 26.04 .1860 26.74 .1776 25.41 .1985
///   ring-sphere         20.22 .1945 27.77 .0982 27.99 .0824 27.94 .0942 28.13 .0821 28.41 .0786
///
/// Where they stand: instanced cannot show semi-transparency nor sub-pixel strands (its proxies
/// are all or nothing at alpha 0.5); lichen (Lambert, overlapping semi-transparent blobs) is the
/// weakest for every method because a splat sees only its own kernel's density, so its shading
/// normal misses the neighbours' (the reference's normal is the gradient of all overlapping
/// lobes): unlit, the same scene measures 30.4 dB / 0.053 with oit. Sorted, exact compositing of
/// whole kernels, has the best PSNR everywhere but on lichen (whose blobs interpenetrate: one
/// kernel drawn wholly over another is wrong there too). Its FLIP is worse than oit's on
/// fur-bunny and fur-bunny-far: a uniform brightening of the fur (+0.014 in linear red on
/// fur-bunny) from EWA, not from the order: a strand far thinner than a pixel, widened to the
/// pixel with its mass kept, covers more than its area (1 - exp(-tau s) > s (1 - exp(-tau)) for
/// a width ratio s < 1), so the light tips hide more of the dark roots than they should; OIT's
/// average of all the kernels at a pixel happens to offset it. Without EWA, supersampled 2x, the
/// bias drops to +0.003 and sorted leads on both metrics (SortedBeatsOitWhereStrandsAreResolved).
struct Tolerance {
    const char* scene;
    double minPsnr[6]; // in the order of configurations()
    double maxFlip[6];
};

// clang-format off
const Tolerance kTolerances[] = {
    {"fur-bunny-close",     {25.5, 29.3, 28.6, 31.4, 33.4, 31.5}, {0.161, 0.131, 0.139, 0.124, 0.079, 0.121}},
    {"fur-bunny",           {24.9, 31.6, 32.4, 32.0, 32.4, 32.6}, {0.100, 0.074, 0.070, 0.077, 0.073, 0.085}},
    {"fur-bunny-far",       {31.5, 43.6, 43.7, 43.6, 43.6, 44.0}, {0.018, 0.005, 0.005, 0.005, 0.005, 0.006}},
    {"grass-plane-grazing", {26.3, 38.2, 38.0, 38.5, 38.8, 41.2}, {0.113, 0.063, 0.066, 0.061, 0.060, 0.041}},
    {"lichen-torus",        {24.8, 25.7, 24.9, 25.5, 26.2, 24.9}, {0.201, 0.201, 0.223, 0.205, 0.196, 0.219}},
    {"ring-sphere",         {19.7, 27.2, 27.4, 27.4, 27.6, 27.9}, {0.214, 0.109, 0.091, 0.104, 0.091, 0.087}},
};
// clang-format on

TEST(SplatRendererScenes, EveryMethodOnEveryShippedSceneAgainstTheReference) {
    splat::Context ctx(validated());
    const std::vector<Configuration> configs = configurations();
    std::map<std::string, std::map<std::string, Measured>> table;
    for (const Tolerance& tol : kTolerances) {
        const SceneSetup s = loadSetup(tol.scene, kSceneSize);
        const noise::Image& reference = referenceImage(tol.scene);
        for (std::size_t c = 0; c < configs.size(); ++c) {
            Measured m = measure(ctx, s, reference, configs[c].settings);
            std::printf("%-20s %-13s PSNR %6.2f dB  FLIP %.4f  %7.2f ms  %6u kernels\n", tol.scene,
                        configs[c].label, m.psnr, m.flip, m.ms, m.kernels);
            EXPECT_GE(m.psnr, tol.minPsnr[c]) << tol.scene << " " << configs[c].label;
            EXPECT_LE(m.flip, tol.maxFlip[c]) << tol.scene << " " << configs[c].label;
            EXPECT_GT(m.kernels, 0u) << tol.scene;
            if (m.psnr < tol.minPsnr[c] || m.flip > tol.maxFlip[c] ||
                std::getenv("SPOT_SPLAT_TEST_IMAGES"))
                writeImages(tol.scene, configs[c].label, m, reference);
            m.image = {};
            m.flipMap.clear();
            table[tol.scene][configs[c].label] = m;
        }
    }
    // The paper's claim (sec. 4, fig. 3-4): compositing the closest kernel over the OIT result
    // fixes the close-up of opaque strands (measured: 31.92 dB / 0.112 against 29.83 / 0.119;
    // eq. 13 taken literally, with the closest kernel also left in the OIT sums, measured
    // 30.03 / 0.149: see splat_resolve.comp).
    const Measured& oit = table["fur-bunny-close"]["oit"];
    const Measured& hybrid = table["fur-bunny-close"]["hybrid"];
    EXPECT_GT(hybrid.psnr, oit.psnr);
    EXPECT_LT(hybrid.flip, oit.flip);
    // The sorted method's claim: where opaque kernels overlap, compositing them in depth order
    // beats OIT's weighted average. It holds for PSNR on both fur scenes and for FLIP on the
    // close-up (32.06 dB / 0.110 against 29.83 / 0.119; fur-bunny 33.19 dB against 32.14), not
    // for FLIP on fur-bunny (0.077 against 0.066: EWA's brightening of sub-pixel strands, see
    // the table above and SortedBeatsOitWhereStrandsAreResolved).
    for (const char* scene : {"fur-bunny-close", "fur-bunny"})
        EXPECT_GT(table[scene]["sorted"].psnr, table[scene]["oit"].psnr) << scene;
    EXPECT_LT(table["fur-bunny-close"]["sorted"].flip, table["fur-bunny-close"]["oit"].flip);
    expectNoValidationErrors(ctx);
}

TEST(SplatRendererScenes, SortedBeatsOitWhereStrandsAreResolved) {
    // fur-bunny rendered at 256x256 without EWA and box-filtered to 128x128, against the same
    // reference: the strands cover a few pixels each, nothing is widened, and the sorted
    // composite beats OIT's on both metrics. Measured: sorted 38.59 dB / 0.0317 (mean linear
    // bias +0.0035 in red), oit 34.25 dB / 0.0502 (-0.0070).
    const noise::Image& reference = referenceImage("fur-bunny");
    const SceneSetup s = loadSetup("fur-bunny", 2 * kSceneSize);
    splat::Context ctx(validated());
    SplatRig renderer(ctx, s.mesh, s.kernel);
    const splat::Buffer impulses = upload(ctx, s.impulses);
    std::map<splat::Method, splat::ImageMetrics> metrics;
    for (splat::Method method : {splat::Method::Oit, splat::Method::Sorted}) {
        SplatSettings settings;
        settings.method = method;
        settings.ewa = false;
        const noise::Image big =
            renderer.render(s.scene.camera, s.scene.shading, s.scene.background, s.scene.baseColor,
                            impulses, std::uint32_t(s.impulses.size()), settings);
        noise::Image small(kSceneSize, kSceneSize);
        for (int y = 0; y < kSceneSize; ++y)
            for (int x = 0; x < kSceneSize; ++x)
                small.at(x, y) = 0.25f * (big.at(2 * x, 2 * y) + big.at(2 * x + 1, 2 * y) +
                                          big.at(2 * x, 2 * y + 1) + big.at(2 * x + 1, 2 * y + 1));
        metrics[method] = splat::compareImages(reference, small);
        std::printf("fur-bunny 2x, no EWA, %-6s PSNR %6.2f dB  FLIP %.4f\n",
                    splat::methodName(method), metrics[method].psnr, metrics[method].flip);
    }
    const splat::ImageMetrics& sorted = metrics[splat::Method::Sorted];
    const splat::ImageMetrics& oit = metrics[splat::Method::Oit];
    EXPECT_GT(sorted.psnr, oit.psnr + 3.0);
    EXPECT_LT(sorted.flip, 0.8 * oit.flip);
    expectNoValidationErrors(ctx);
}

// Clumps change only the impulses (their frames and bends), so a renderer that agrees with the
// reference on fur agrees as well on clumped fur (issue 44: within 1 dB): sorted against the
// reference on fur-bunny and fur-clumped-bunny, the same view, unlit, at the benches' 128x128.
// Measured (lavapipe, Mesa 22.3, 32 spp): 128x128 fur-bunny 38.65 dB, fur-clumped-bunny 38.00;
// at 96x96, where the gathered tips are under a pixel wide, 38.86 and 37.73 (1.13 apart: the
// coverage-keeping widening gains less where the tips of a clump overlap in one pixel).
TEST(SplatRendererScenes, SortedAgreesWithTheReferenceOnClumpedFurAsOnFur) {
    constexpr int kSize = 128, kSpp = 32;
    splat::Context ctx(validated());
    SplatSettings sorted;
    sorted.method = splat::Method::Sorted;
    std::map<std::string, double> psnr;
    for (const char* scene : {"fur-bunny", "fur-clumped-bunny"}) {
        const SceneSetup s = loadSetup(scene, kSize);
        const noise::Image& reference = test::referenceImage(scene, kSize, kSpp);
        const Measured m = measure(ctx, s, reference, sorted);
        psnr[scene] = m.psnr;
        std::printf("%-18s sorted against the reference (%dx%d, %d spp): PSNR %.2f dB, FLIP %.4f\n",
                    scene, kSize, kSize, kSpp, m.psnr, m.flip);
        if (std::getenv("SPOT_SPLAT_TEST_IMAGES"))
            writeImages(scene, "sorted-clumps", m, reference);
    }
    EXPECT_GE(psnr["fur-clumped-bunny"], psnr["fur-bunny"] - 1.0);
    EXPECT_GT(psnr["fur-bunny"], 37.5);
    expectNoValidationErrors(ctx);
}

TEST(SplatRendererScenes, HybridFindsTheSameClosestKernelEitherWay) {
    // docs/design.md section 4: the hybrid's closest kernel in the OIT pass (64-bit atomicMin) or in a
    // depth pass of its own: the same kernel per pixel, so the same image, bit for bit, on every
    // shipped scene (analytic and with kernel samples), every kernel drawn (the depth pass has no
    // compute path for small kernels; with it, the atomic image differs by float rounding:
    // SmallKernelsRenderAsTheRasterPathDoes). And not the OIT image: the closest kernel
    // changes the result, so the depth pass really found it.
    splat::Context ctx(validated());
    for (const char* name : {"fur-bunny", "fur-bunny-close", "fur-bunny-far", "grass-plane-grazing",
                             "lichen-torus", "ring-sphere"}) {
        const SceneSetup s = loadSetup(name, kSceneSize);
        SplatRig renderer(ctx, s.mesh, s.kernel);
        const splat::Buffer impulses = upload(ctx, s.impulses);
        for (int samples : {0, 16}) {
            noise::Image images[3];
            double splatMs[3] = {0.0, 0.0, 0.0};
            for (int i = 0; i < 3; ++i) {
                SplatSettings settings;
                settings.method = i == 2 ? splat::Method::Oit : splat::Method::Hybrid;
                settings.kernelSamples = samples;
                settings.closest = i == 1 ? splat::ClosestKernel::DepthPass : splat::ClosestKernel::Atomic;
                settings.smallPixels = 0; // the depth pass draws every kernel
                splat::FrameStats stats;
                images[i] = renderer.render(s.scene.camera, s.scene.shading, s.scene.background,
                                            s.scene.baseColor, impulses,
                                            std::uint32_t(s.impulses.size()), settings, &stats);
                for (const auto& [pass, ms] : stats.passMs)
                    if (pass == "splat")
                        splatMs[i] = ms;
            }
            std::printf("%-20s samples %2d: splat pass %.1f ms (atomicMin) vs %.1f ms (depth pass)\n",
                        name, samples, splatMs[0], splatMs[1]);
            EXPECT_EQ(std::memcmp(images[0].pixels.data(), images[1].pixels.data(),
                                  images[0].pixels.size() * sizeof(glm::vec3)),
                      0)
                << name << " samples " << samples;
            EXPECT_NE(std::memcmp(images[0].pixels.data(), images[2].pixels.data(),
                                  images[0].pixels.size() * sizeof(glm::vec3)),
                      0)
                << name << " samples " << samples;
        }
    }
    expectNoValidationErrors(ctx);
}

// ---- Determinism, degenerate input, refused settings ----------------------------------------

TEST(SplatRenderer, ImagesAreByteIdenticalAcrossRuns) {
    // lavapipe's rasterizer threads: pinned before any context exists in this test.
    ScopedLavapipeThreads lavapipe;
    lavapipe.set("2");
    const SceneSetup s = loadSetup("fur-bunny-close", 64);
    std::vector<noise::Image> images[2];
    for (int run = 0; run < 2; ++run) {
        splat::Context ctx(validated());
        SplatRig renderer(ctx, s.mesh, s.kernel);
        const splat::Buffer impulses = upload(ctx, s.impulses);
        for (const Configuration& c : configurations())
            for (int repeat = 0; repeat < 2; ++repeat)
                images[run].push_back(renderer.render(
                    s.scene.camera, s.scene.shading, s.scene.background, s.scene.baseColor,
                    impulses, std::uint32_t(s.impulses.size()), c.settings));
        expectNoValidationErrors(ctx);
    }
    ASSERT_EQ(images[0].size(), images[1].size());
    for (std::size_t i = 0; i < images[0].size(); ++i) {
        const noise::Image& first = images[0][i & ~std::size_t(1)];
        for (const noise::Image* other : {&images[0][i], &images[1][i]})
            EXPECT_EQ(std::memcmp(first.pixels.data(), other->pixels.data(),
                                  first.pixels.size() * sizeof(glm::vec3)),
                      0)
                << configurations()[i / 2].label;
    }
}

TEST(SplatRenderer, SortedIsByteIdenticalOnOneAndTwoThreads) {
    // lavapipe reads LP_NUM_THREADS when an instance creates its device: each Context below has
    // its own thread count. The sort has no atomics and blending follows primitive order, so the
    // image may not depend on it.
    ScopedLavapipeThreads lavapipe;
    const SceneSetup s = loadSetup("fur-bunny", 64);
    std::vector<noise::Image> images;
    for (const char* threads : {"1", "2", "1"}) {
        lavapipe.set(threads);
        splat::Context ctx(validated());
        SplatRig renderer(ctx, s.mesh, s.kernel);
        const splat::Buffer impulses = upload(ctx, s.impulses);
        SplatSettings settings;
        settings.method = splat::Method::Sorted;
        images.push_back(renderer.render(s.scene.camera, s.scene.shading, s.scene.background,
                                         s.scene.baseColor, impulses,
                                         std::uint32_t(s.impulses.size()), settings));
        expectNoValidationErrors(ctx);
    }
    for (std::size_t i = 1; i < images.size(); ++i)
        EXPECT_EQ(std::memcmp(images[0].pixels.data(), images[i].pixels.data(),
                              images[0].pixels.size() * sizeof(glm::vec3)),
                  0)
            << i;
}

// ---- The small kernels' compute path -----------------------------------------------------------

struct ImageDifference {
    double maxAbs = 0.0, meanAbs = 0.0;
    double changed = 0.0; ///< fraction of pixels with a channel off by more than 1e-3
};

ImageDifference difference(const noise::Image& a, const noise::Image& b) {
    ImageDifference d;
    EXPECT_EQ(a.pixels.size(), b.pixels.size());
    for (std::size_t i = 0; i < std::min(a.pixels.size(), b.pixels.size()); ++i) {
        const glm::vec3 e = glm::abs(a.pixels[i] - b.pixels[i]);
        const double m = std::max({e.x, e.y, e.z});
        d.maxAbs = std::max(d.maxAbs, m);
        d.meanAbs += (e.x + e.y + e.z) / 3.0;
        d.changed += m > 1e-3 ? 1.0 : 0.0;
    }
    d.meanAbs /= double(std::max<std::size_t>(a.pixels.size(), 1));
    d.changed /= double(std::max<std::size_t>(a.pixels.size(), 1));
    return d;
}

TEST(SplatRenderer, SmallKernelsRenderAsTheRasterPathDoes) {
    // The compute path takes a kernel whose quad's pixel box holds at most smallPixels centres,
    // and a thin one (kSplatThinHalfWidth) whose box holds at most kSplatMaxSmallPixels.
    // fur-bunny at 128x128 (threshold 16): the strands over 16 pixels are thin, so every kernel is
    // small; far away at 32x32, every kernel is small anyway; close up at 128x128, wider kernels
    // are drawn, so both paths run. Forcing every kernel through the raster path (smallPixels 0)
    // must give the same
    // image up to float rounding (the compute path evaluates the same code at the same pixel
    // centres; its OIT sums are fixed point, added in another order) and count the same
    // fragments (up to the pixel centres on a quad's very edge, where the two cover differently).
    enum class Paths { Compute, Both };
    struct Case {
        const char* scene;
        int size;
        int smallPixels;
        Paths paths;
    };
    for (const Case& k : {Case{"fur-bunny", 128, 16, Paths::Compute},
                          Case{"fur-bunny-far", 32, int(splat::gpu_splat::kSplatMaxSmallPixels),
                               Paths::Compute},
                          Case{"fur-bunny-close", 128, 16, Paths::Both}}) {
        const SceneSetup s = loadSetup(k.scene, k.size);
        splat::Context ctx(validated());
        SplatRig renderer(ctx, s.mesh, s.kernel);
        const splat::Buffer impulses = upload(ctx, s.impulses);
        const auto count = std::uint32_t(s.impulses.size());
        for (const Configuration& c : configurations()) {
            if (c.settings.method == splat::Method::Sorted)
                continue;
            SplatSettings both = c.settings;
            both.countFragments = true;
            both.smallPixels = k.smallPixels;
            SplatSettings raster = both;
            raster.smallPixels = 0;
            splat::FrameStats bothStats, rasterStats;
            const noise::Image a = renderer.render(s.scene.camera, s.scene.shading, s.scene.background,
                                                   s.scene.baseColor, impulses, count, both, &bothStats);
            const noise::Image b = renderer.render(s.scene.camera, s.scene.shading, s.scene.background,
                                                   s.scene.baseColor, impulses, count, raster,
                                                   &rasterStats);
            const std::string label = cat(k.scene, " ", c.label);
            const double small = extraCounter(bothStats, "kernels_small");
            EXPECT_EQ(extraCounter(rasterStats, "kernels_small"), 0.0) << label;
            EXPECT_GT(small, 0.0) << label;
            if (k.paths == Paths::Compute)
                EXPECT_EQ(small, double(bothStats.counters.kernelsDrawn)) << label;
            else
                EXPECT_LT(small, 0.9 * double(bothStats.counters.kernelsDrawn)) << label; // both paths
            // Kernels whose quad's box holds no pixel centre are culled by the split (the raster
            // path would draw them and shade nothing).
            EXPECT_LE(bothStats.counters.kernelsDrawn, rasterStats.counters.kernelsDrawn) << label;
            EXPECT_GT(rasterStats.counters.fragmentsShaded, 0u) << label;
            EXPECT_NEAR(double(bothStats.counters.fragmentsShaded),
                        double(rasterStats.counters.fragmentsShaded),
                        1e-3 * double(rasterStats.counters.fragmentsShaded) + 2.0)
                << label;
            EXPECT_NEAR(double(bothStats.counters.pixelsCovered),
                        double(rasterStats.counters.pixelsCovered),
                        1e-3 * double(rasterStats.counters.pixelsCovered) + 2.0)
                << label;
            const ImageDifference d = difference(a, b);
            std::printf("    %s: max %.2e mean %.2e changed %.4f\n", label.c_str(), d.maxAbs,
                        d.meanAbs, d.changed);
            if (c.settings.method == splat::Method::Instanced) {
                // All or nothing per pixel: a kernel at alpha 0.5 +- rounding may cover a pixel
                // on one path and not on the other.
                EXPECT_LE(d.changed, 0.001) << label;
                EXPECT_LT(d.meanAbs, 1e-5) << label;
            } else {
                // Measured: mean at most 1.6e-6; every pixel within 7.4e-4 but 6 of fur-bunny's
                // 16,384, within 1.9e-2 (3 within 8.2e-3 before the EWA widening kept coverage,
                // which reshapes every lobe). There a lobe's screen form is ill-conditioned, and
                // the fragment shader's (o' at the provoking vertex, w = o' x v per pixel) and the
                // compute path's (w and o'.v affine in the pixel) round apart; with the fragment
                // shader reading the affine form too, the two images agree to 2e-6 everywhere,
                // at 60% more splat time (docs/design.md, "Filtering").
                const bool illConditioned = std::string(k.scene) == "fur-bunny";
                EXPECT_LT(d.maxAbs, illConditioned ? 2.5e-2 : 2e-3) << label;
                EXPECT_LE(d.changed, 6.0 / (128.0 * 128.0)) << label; // pixels over 1e-3
                EXPECT_LT(d.meanAbs, 5e-6) << label;
            }
        }
        expectNoValidationErrors(ctx);
    }
}

TEST(SplatRenderer, LambertTermsFromTheVertexShaderMatchTheLoadedOnes) {
    // Lambert shading: a drawn kernel of up to kSplatMaxShadeVaryingLobes lobes gets each lobe's
    // gradient terms from the vertex shader (varyings), one with more lobes loads its world lobes
    // per fragment, and the compute path of small kernels loads them once per kernel. On lichen's
    // impulses at 48x48 (every kernel small), with lichen's 3 lobes and a 7-lobe variant, drawing
    // every kernel (smallPixels 0) must give the compute path's image up to float rounding.
    const SceneSetup s = loadSetup("lichen-torus", 48);
    ASSERT_EQ(s.scene.shading.mode, noise::Shading::Mode::Lambert);
    const noise::PresetDesc preset = noise::loadPreset(s.scene.preset);
    const noise::KernelDesc three = preset.kernel;
    noise::KernelDesc seven = three;
    for (int i = 0; seven.lobes.size() < 7; ++i) {
        noise::LobeDesc lobe = preset.kernel.lobes[std::size_t(i) % preset.kernel.lobes.size()];
        lobe.offset += glm::vec3(0.15f * float(i + 1), -0.1f * float(i), 0.02f * float(i));
        lobe.color = glm::vec3(0.3f + 0.1f * float(i), 0.5f, 0.7f - 0.1f * float(i));
        seven.lobes.push_back(lobe);
    }
    ASSERT_GT(seven.lobes.size(), std::size_t(splat::gpu_splat::kSplatMaxShadeVaryingLobes));
    ASSERT_LE(preset.kernel.lobes.size(), std::size_t(splat::gpu_splat::kSplatMaxShadeVaryingLobes));
    splat::Context ctx(validated());
    const splat::Buffer impulses = upload(ctx, s.impulses);
    const auto count = std::uint32_t(s.impulses.size());
    for (const noise::KernelDesc* desc : {&three, static_cast<const noise::KernelDesc*>(&seven)}) {
        SplatRig renderer(ctx, s.mesh, noise::buildKernel(*desc));
        for (splat::Method method : {splat::Method::Oit, splat::Method::Hybrid}) {
            SplatSettings drawn;
            drawn.method = method;
            drawn.smallPixels = 0;
            SplatSettings small = drawn;
            small.smallPixels = int(splat::gpu_splat::kSplatMaxSmallPixels);
            splat::FrameStats drawnStats, smallStats;
            const noise::Image a = renderer.render(s.scene.camera, s.scene.shading, s.scene.background,
                                                   s.scene.baseColor, impulses, count, drawn, &drawnStats);
            const noise::Image b = renderer.render(s.scene.camera, s.scene.shading, s.scene.background,
                                                   s.scene.baseColor, impulses, count, small, &smallStats);
            const std::string label = cat(desc->lobes.size(), " lobes ", splat::methodName(method));
            EXPECT_EQ(extraCounter(drawnStats, "kernels_small"), 0.0) << label;
            EXPECT_GT(extraCounter(smallStats, "kernels_small"),
                      0.9 * double(smallStats.counters.kernelsDrawn)) << label;
            const ImageDifference d = difference(a, b);
            std::printf("    %s: max %.2e mean %.2e changed %.4f\n", label.c_str(), d.maxAbs,
                        d.meanAbs, d.changed);
            // Measured: 2.07e-3 at most (the 7-lobe kernel's ill-conditioned screen forms, as
            // in SmallKernelsRenderAsTheRasterPathDoes), mean 2.2e-8.
            EXPECT_LT(d.maxAbs, 3e-3) << label;
            EXPECT_LT(d.meanAbs, 5e-6) << label;
        }
    }
    expectNoValidationErrors(ctx);
}

TEST(SplatRenderer, SmallKernelsFixedSumsFitOneBinding) {
    // oit and hybrid's fixed-point sums take 40 bytes a pixel, made with the targets; where they
    // would not fit one storage buffer binding the frame draws every kernel instead (instanced
    // has none: its compute path only takes atomicMin).
    splat::Context ctx(validated());
    const LobeCase c = isolatedLobe(3.0f);
    const noise::Mesh empty;
    const splat::SceneGpu scene(ctx, empty, c.kernel);
    splat::RenderSettings raster;
    raster.smallPixels = 0;
    const std::uint64_t range = ctx.properties().limits.maxStorageBufferRange;
    for (const splat::Method method :
         {splat::Method::Oit, splat::Method::Hybrid, splat::Method::Instanced}) {
        const auto r = splat::makeSplattingRenderer(scene, method);
        // 40 bytes a pixel and a uint per 8x8 tile.
        const std::uint64_t fixed = method == splat::Method::Instanced ? 0 : 64 * 64 * 40 + 64 * 4;
        EXPECT_EQ(r->frameBytes(64, 64, 0, {}) - r->frameBytes(64, 64, 0, raster), fixed);
        const int side = int(std::sqrt(double(range) / 40.0)) + 2; // just past the limit
        EXPECT_EQ(r->frameBytes(side, side, 0, {}), r->frameBytes(side, side, 0, raster));
    }
    expectNoValidationErrors(ctx);
}

TEST(SplatRenderer, SmallKernelsAreByteIdenticalOnOneAndTwoThreads) {
    // The compute path's invocations run in any order on lavapipe's threads; its OIT sums are
    // integers (associative) and its closest kernel an atomicMin of a total order, so the image
    // may not depend on the thread count nor the run. Every kernel small (the most atomics on
    // shared pixels), and the default split.
    ScopedLavapipeThreads lavapipe;
    const SceneSetup s = loadSetup("fur-bunny", 64);
    std::vector<std::vector<noise::Image>> images;
    for (const char* threads : {"1", "2", "1"}) {
        lavapipe.set(threads);
        splat::Context ctx(validated());
        SplatRig renderer(ctx, s.mesh, s.kernel);
        const splat::Buffer impulses = upload(ctx, s.impulses);
        images.emplace_back();
        for (const splat::Method method :
             {splat::Method::Oit, splat::Method::Hybrid, splat::Method::Instanced})
            for (const int small : {splat::RenderSettings{}.smallPixels,
                                    int(splat::gpu_splat::kSplatMaxSmallPixels)})
                for (int repeat = 0; repeat < 2; ++repeat) {
                    SplatSettings settings;
                    settings.method = method;
                    settings.smallPixels = small;
                    images.back().push_back(renderer.render(
                        s.scene.camera, s.scene.shading, s.scene.background, s.scene.baseColor,
                        impulses, std::uint32_t(s.impulses.size()), settings));
                }
        expectNoValidationErrors(ctx);
    }
    for (std::size_t run = 0; run < images.size(); ++run)
        for (std::size_t i = 0; i < images[run].size(); ++i) {
            const noise::Image& first = images[0][i & ~std::size_t(1)];
            EXPECT_EQ(std::memcmp(first.pixels.data(), images[run][i].pixels.data(),
                                  first.pixels.size() * sizeof(glm::vec3)),
                      0)
                << "run " << run << " image " << i;
        }
}

TEST(SplatRenderer, DegenerateLobesGiveFiniteImages) {
    noise::KernelDesc desc;
    noise::LobeDesc flat, needle, empty, normal;
    flat.sigma = glm::vec3(0.0f, 0.2f, 0.2f);     // zero sigma: floored to 1e-6 of the largest
    needle.sigma = glm::vec3(1e-4f, 1.0f, 1e-4f); // 1e4:1 anisotropy
    needle.rotationDeg = glm::vec3(30.0f, 10.0f, 70.0f);
    needle.extinction = 1e4f;
    empty.sigma = glm::vec3(0.3f);
    empty.extinction = 0.0f; // zero density
    normal.sigma = glm::vec3(0.1f, 0.2f, 0.3f);
    normal.offset = glm::vec3(0.1f, 0.0f, 0.2f);
    desc.lobes = {flat, needle, empty, normal};
    const noise::Kernel kernel = noise::buildKernel(desc);
    noise::KernelDesc zeroDesc;
    noise::LobeDesc zero;
    zero.sigma = glm::vec3(0.0f); // every sigma zero: an absolute floor
    zeroDesc.lobes = {zero};
    const noise::Kernel zeroKernel = noise::buildKernel(zeroDesc);

    std::vector<noise::Impulse> imps;
    for (int i = 0; i < 5; ++i)
        for (int j = 0; j < 5; ++j) {
            noise::Impulse imp =
                impulseAt(glm::vec3(0.3f * i - 0.6f, 0.3f * j - 0.6f, 0.1f * (i - j)));
            imp.bend = 0.3f * float(i);
            imp.scale = glm::vec3(0.5f + 0.1f * float(j));
            imps.push_back(imp);
        }
    imps[3].weight = 0.0f;           // zero weight
    imps[7].scale = glm::vec3(0.0f); // zero scale: infinite A
    imps[11].scale = glm::vec3(1e-20f);
    imps[12].position = glm::vec3(0.0f, 0.0f, 3.0f); // around the perspective eye
    imps[13].position = glm::vec3(0.0f, 0.0f, 9.0f); // behind the camera
    const noise::Mesh plane = noise::makePlane(2.0f, 4);

    splat::Context ctx(validated());
    const splat::Buffer impulses = upload(ctx, imps);
    for (const noise::Kernel* k : {&kernel, &zeroKernel}) {
        SplatRig renderer(ctx, plane, *k);
        for (auto projection : {noise::Projection::Perspective, noise::Projection::Orthographic}) {
            noise::Camera cam;
            cam.projection = projection;
            cam.eye = glm::dvec3(0.0, 0.0, 3.0);
            cam.up = glm::dvec3(0.0, 1.0, 0.0);
            cam.target = glm::dvec3(0.0, -0.5, 0.0);
            cam.width = cam.height = 40;
            for (auto mode : {noise::Shading::Mode::Unlit, noise::Shading::Mode::Lambert})
                for (splat::Method method : {splat::Method::Instanced, splat::Method::Oit,
                                             splat::Method::Hybrid, splat::Method::Sorted})
                    for (int samples : {0, 16})
                        for (bool ewa : {false, true}) {
                            noise::Shading shading;
                            shading.mode = mode;
                            SplatSettings s;
                            s.method = method;
                            s.kernelSamples = samples;
                            s.ewa = ewa;
                            const noise::Image image =
                                renderer.render(cam, shading, glm::vec3(0.1f), glm::vec3(0.4f),
                                                impulses, std::uint32_t(imps.size()), s);
                            int bad = 0;
                            for (const glm::vec3& p : image.pixels)
                                for (int c = 0; c < 3; ++c)
                                    if (!std::isfinite(p[c]) || p[c] < -1e-6f ||
                                        p[c] > 1.0f + 1e-5f) {
                                        ++bad;
                                        std::printf("bad %g at %d\n", p[c],
                                                    int(&p - image.pixels.data()));
                                    }
                            EXPECT_EQ(bad, 0)
                                << splat::methodName(method) << " samples " << samples << " ewa "
                                << ewa << " lit " << int(mode) << " ortho " << int(projection);
                        }
        }
    }
    expectNoValidationErrors(ctx);
}

TEST(SplatRenderer, RefusesWhatItCannotDo) {
    splat::ContextOptions options = validated();
    options.memoryBudget = 64ull << 20;
    splat::Context ctx(options);
    const LobeCase c = isolatedLobe(3.0f);
    const noise::Mesh empty;
    SplatRig renderer(ctx, empty, c.kernel);
    const splat::Buffer impulses = upload(ctx, c.impulses);
    noise::Camera cam = lobeCamera(noise::Projection::Perspective, 32);
    SplatSettings s;
    for (int samples : {-1, 2049}) {
        s.kernelSamples = samples;
        EXPECT_THROW(renderer.render(cam, noise::Shading{}, glm::vec3(0.0f), glm::vec3(0.0f),
                                     impulses, 1, s),
                     InputError)
            << samples;
    }
    s.kernelSamples = 2048; // the largest allowed
    EXPECT_NO_THROW(
        renderer.render(cam, noise::Shading{}, glm::vec3(0.0f), glm::vec3(0.0f), impulses, 1, s));
    s.kernelSamples = 0;
    for (int small : {-1, int(splat::gpu_splat::kSplatMaxSmallPixels) + 1}) {
        s.smallPixels = small;
        EXPECT_THROW(renderer.render(cam, noise::Shading{}, glm::vec3(0.0f), glm::vec3(0.0f),
                                     impulses, 1, s),
                     InputError)
            << small;
    }
    s.smallPixels = splat::RenderSettings{}.smallPixels;
    // More impulses than the buffer holds.
    EXPECT_THROW(
        renderer.render(cam, noise::Shading{}, glm::vec3(0.0f), glm::vec3(0.0f), impulses, 2, s),
        InputError);
    // A frame beyond the memory budget (2048^2 x 68 bytes = 272 MiB > 64 MiB).
    cam.width = cam.height = 2048;
    const std::uint64_t before = ctx.allocatedBytes();
    EXPECT_THROW(
        renderer.render(cam, noise::Shading{}, glm::vec3(0.0f), glm::vec3(0.0f), impulses, 1, s),
        InputError);
    EXPECT_EQ(ctx.allocatedBytes(), before); // nothing allocated by the refused frame
    cam.width = cam.height = 32;
    EXPECT_NO_THROW(
        renderer.render(cam, noise::Shading{}, glm::vec3(0.0f), glm::vec3(0.0f), impulses, 1, s));
    // A kernel of 9 lobes.
    noise::Kernel nine = c.kernel;
    nine.lobes.resize(9, nine.lobes[0]);
    EXPECT_THROW(splat::SceneGpu(ctx, empty, nine), InputError);
    expectNoValidationErrors(ctx);
}

} // namespace
