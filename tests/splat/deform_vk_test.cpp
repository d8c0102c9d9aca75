// Animated surfaces on the GPU (splat/deform_vk.h) and through `spotshell render --time`: the
// deform passes move the impulses as the CPU does; a rigid clip gives the image of the static
// mesh seen from the camera moved back; every method at a bent frame matches the reference
// there as well as it does at rest.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "../noise/gltf_clips.h"
#include "cli_run.h"
#include "noise/animated_mesh.h"
#include "noise/deform.h"
#include "noise/image.h"
#include "noise/shared_data.h"
#include "splat/frame_vk.h"
#include "splat/image_compare.h"
#include "splat_test_support.h"

namespace {

using namespace spot;
using namespace spot::test;

std::string tmp(const std::string& name) { return std::string(SPOT_TEST_TMP_DIR) + "/deformvk_" + name; }

std::string vec(glm::dvec3 v) {
    return "[" + std::to_string(v.x) + ", " + std::to_string(v.y) + ", " + std::to_string(v.z) + "]";
}

/// A scene file for `mesh` with fur, seen from `eye` towards `target`.
std::string writeScene(const std::string& name, const std::string& mesh, glm::dvec3 eye,
                       glm::dvec3 target, glm::dvec3 up, int size, const std::string& extra = "") {
    const std::string file = tmp(name + ".json");
    std::ofstream(file) << R"({"version": 1, "name": ")" << name << R"(", "mesh": ")" << mesh
                        << R"(", "preset": ")" << SPOT_SOURCE_DIR << R"(/presets/fur.json", "seed": 3,
        "camera": {"eye": )" << vec(eye) << R"(, "target": )" << vec(target) << R"(, "up": )"
                        << vec(up) << R"(, "fov_deg": 40},
        "image": {"width": )" << size << R"(, "height": )" << size << R"(},
        "background": [0.03, 0.03, 0.04], "base_color": [0.2, 0.2, 0.22],
        "shading": {"mode": "unlit"}, "reference": {"spp": 16})"
                        << extra << "}";
    return file;
}

noise::Image render(const std::string& scene, const std::string& method, double time,
                    const std::string& name, const std::string& options = "") {
    const std::string out = tmp(name + ".exr");
    const CliResult r = runSpotshell("render --scene " + scene + " --method " + method +
                                     " --time " + std::to_string(time) + " --out " + out + " " +
                                     options);
    EXPECT_EQ(r.code, 0) << r.err;
    return noise::readImage(out);
}

/// The deform passes against noise::Deformer on `clip` at `times`: the posed vertices, the moved
/// impulses (positions, frames, root cells), the anchors and random values bit for bit.
void expectGpuMovesAsCpu(const noise::AnimatedMesh& clip, const std::vector<double>& times,
                         glm::dvec3 eye, glm::dvec3 target) {
    const noise::ImpulseGenerator generator(clip.rest(), noise::loadPreset(std::string(SPOT_SOURCE_DIR) + "/presets/fur.json"), {});
    const std::vector<noise::Impulse> rest = generator.generate(); // every cell
    noise::Camera camera;
    camera.eye = eye;
    camera.target = target;
    camera.fovYDeg = 60.0;
    camera.width = camera.height = 32; // sees the whole clip: every cell is generated
    const splat::View view{camera, {}, glm::vec3(0.0f), glm::vec3(0.5f)};
    splat::Context ctx(validated());
    splat::Frame frame(ctx, clip.rest(), generator);
    frame.animate(clip, noise::Wind{});
    noise::Deformer cpu(clip);
    for (const double t : times) {
        frame.setTime(t);
        frame.render("sorted", view, {});
        ASSERT_EQ(frame.generator().count(), rest.size()) << "t " << t;
        cpu.pose(t);
        const std::vector<noise::Impulse> want = cpu.move(rest, generator.cellSize());
        const auto* got = static_cast<const gpu::SpotImpulse*>(frame.deformer()->moved().impulses->mapped());
        std::size_t otherCell = 0;
        const auto* generated =
            static_cast<const gpu::SpotImpulse*>(frame.generator().impulses().impulses->mapped());
        for (std::size_t i = 0; i < want.size(); ++i) {
            const glm::vec3 p(got[i].position);
            for (int k = 0; k < 3; ++k)
                ASSERT_TRUE(std::isfinite(p[k]) && std::isfinite(got[i].frameZ[k])) << i;
            ASSERT_LT(glm::length(p - want[i].position), 1e-5f * std::max(1.0f, glm::length(p)))
                << "impulse " << i << " at t " << t;
            ASSERT_LT(glm::length(glm::vec3(got[i].frameZ) - want[i].frame[2]), 1e-4f) << i;
            ASSERT_LT(glm::length(glm::vec3(got[i].frameX) - want[i].frame[0]), 1e-4f) << i;
            // The root's cell: the same but where a rounding puts the root across a face.
            const glm::ivec3 cellOff = glm::abs(glm::ivec3(got[i].cell) - want[i].cell);
            ASSERT_LE(std::max(cellOff.x, std::max(cellOff.y, cellOff.z)), 1) << i;
            otherCell += cellOff != glm::ivec3(0);
            // The anchor and the random values, bit for bit those the GPU generated at rest:
            // scale, colour, triangle and b1; b2; the height, bend and weight.
            const gpu::SpotImpulse& atRest = generated[i];
            ASSERT_EQ(std::memcmp(&got[i].scale, &atRest.scale, 2 * sizeof(glm::vec4)), 0) << i;
            ASSERT_EQ(got[i].cell.w, atRest.cell.w) << i;
            ASSERT_EQ(std::memcmp(&got[i].comb.w, &atRest.comb.w, 4), 0) << i;
            ASSERT_EQ(std::memcmp(&got[i].normal.w, &atRest.normal.w, 4), 0) << i;
            ASSERT_EQ(std::memcmp(&got[i].position.w, &atRest.position.w, 4), 0) << i;
        }
        EXPECT_LE(otherCell, want.size() / 1000) << "t " << t;
        const auto* v = static_cast<const splat::gpu_splat::SpotMeshVertex*>(frame.scene().meshPass().vertices().mapped());
        for (std::size_t k = 0; k < cpu.posed().positions.size(); ++k) {
            ASSERT_LT(glm::length(glm::vec3(v[k].position) - cpu.posed().positions[k]), 1e-5f) << k;
            ASSERT_LT(glm::length(glm::vec3(v[k].normal) - cpu.posed().normals[k]), 1e-4f) << k;
        }
    }
    expectNoValidationErrors(ctx);
}

} // namespace

TEST(DeformGpu, MovesTheImpulsesAndPosesTheMeshAsTheCpuDoes) {
    // 60 frames over the bend: every one moves every impulse as the CPU does, with its anchor
    // and random values the rest's bit for bit (no swimming on the GPU either).
    SCOPED_TRACE("a skin");
    std::vector<double> times;
    for (int f = 0; f < 60; ++f)
        times.push_back(f / 59.0);
    expectGpuMovesAsCpu(noise::AnimatedMesh::loadGltf(bendClip(tmp("bend.glb"))), times,
                        {1.0, 0.5, 6.0}, {1.0, 0.5, 0.0});
}

TEST(DeformGpu, MovesTheImpulsesOfAMorphTargetAndACollapseAsTheCpuDoes) {
    const noise::Mesh plane = noise::loadMeshOrGenerated("generated:plane");
    {
        SCOPED_TRACE("a morph target");
        expectGpuMovesAsCpu(noise::AnimatedMesh::loadGltf(morphClip(plane, tmp("bump.glb"))),
                            {0.0, 0.5, 1.0}, {0.0, 4.0, 0.5}, {0.0, 0.0, 0.0});
    }
    {
        // At t = 1 every triangle is collapsed: they keep t = 0.5's rotations, and nothing is NaN.
        SCOPED_TRACE("a collapse");
        expectGpuMovesAsCpu(noise::AnimatedMesh::loadGltf(squashClip(plane, tmp("squash.glb"))),
                            {0.5, 1.0}, {0.0, 4.0, 0.5}, {0.0, 0.0, 0.0});
    }
}

TEST(DeformGpu, ARigidClipIsTheStaticMeshSeenFromTheCameraMovedBack) {
    const std::string glb = rigidClip(noise::loadMeshOrGenerated("generated:sphere"), tmp("rigid.glb"));
    const double t = 1.3;
    const glm::dvec3 eye(0.0, 0.8, 4.0), target(0.0, 0.0, 0.0), up(0.0, 1.0, 0.0);
    // The animated scene sees the sphere moved by M; the static one sees it at rest from M^-1.
    const glm::dmat4 inverse = glm::inverse(glm::dmat4(rigidMotion(t)));
    const glm::dvec3 movedTarget = glm::dvec3(rigidMotion(t) * glm::vec4(glm::vec3(target), 1.0f));
    const std::string animated = writeScene("rigid-animated", glb, eye + movedTarget, movedTarget, up, 96);
    const glm::dvec3 backEye = glm::dvec3(inverse * glm::dvec4(eye + movedTarget, 1.0));
    const glm::dvec3 backTarget = glm::dvec3(inverse * glm::dvec4(movedTarget, 1.0));
    const glm::dvec3 backUp = glm::dvec3(inverse * glm::dvec4(up, 0.0));
    const std::string still = writeScene("rigid-static", glb, backEye, backTarget, backUp, 96);
    const noise::Image refMoved = render(animated, "reference", t, "ref-moved");
    const noise::Image refStill = render(still, "reference", 0.0, "ref-still");
    const double refPsnr = splat::psnr(refStill, refMoved);
    EXPECT_GT(refPsnr, 40.0) << "the reference differs beyond its float noise";
    for (const char* method : {"instanced", "oit", "hybrid", "sorted", "raymarch"}) {
        const double moved = splat::psnr(refMoved, render(animated, method, t, std::string(method) + "-moved"));
        const double rest = splat::psnr(refStill, render(still, method, 0.0, std::string(method) + "-still"));
        EXPECT_GT(moved, rest - 0.5) << method << ": " << moved << " dB moved, " << rest << " dB at rest";
        std::printf("rigid %-9s %.2f dB at rest, %.2f dB moved (reference against itself %.1f dB)\n",
                    method, rest, moved, refPsnr);
    }
}

TEST(DeformGpu, EveryMethodAtABentFrameMatchesTheReferenceAsAtRest) {
    const std::string glb = bendClip(tmp("bent.glb"), 1.2f);
    const std::string scene = writeScene("bent", glb, {1.0, 0.9, 3.6}, {0.9, 0.45, 0.0}, {0, 1, 0}, 96);
    const CliResult bake = runSpotshell("bake --scene " + scene + " --resolution 320 --levels 2 --out " + tmp("bent.vdb"));
    ASSERT_EQ(bake.code, 0) << bake.err;
    const noise::Image refRest = render(scene, "reference", 0.0, "bent-ref0");
    const noise::Image refBent = render(scene, "reference", 1.0, "bent-ref1");
    EXPECT_LT(splat::psnr(refRest, refBent), 25.0) << "the bend changes the picture";
    const std::map<std::string, std::string> options = {{"baked", "--bake " + tmp("bent.vdb")}};
    for (const char* method : {"instanced", "oit", "hybrid", "sorted", "raymarch", "baked"}) {
        const std::string extra = options.count(method) ? options.at(method) : "";
        const double rest = splat::psnr(refRest, render(scene, method, 0.0, std::string(method) + "-bent0", extra));
        const double bent = splat::psnr(refBent, render(scene, method, 1.0, std::string(method) + "-bent1", extra));
        EXPECT_GT(bent, rest - 1.0) << method << ": " << bent << " dB bent, " << rest << " dB at rest";
        std::printf("bent  %-9s %.2f dB at rest, %.2f dB bent\n", method, rest, bent);
    }
}

TEST(DeformGpu, RenderFramesWritesEachFrameAndRefusesBadRanges) {
    const std::string scene = std::string(SPOT_SOURCE_DIR) + "/examples/animated/tail-fur.json";
    for (const char* f : {"shot.000.png", "shot.002.png", "shot.004.png", "shot.001.png"})
        std::remove(tmp(f).c_str());
    const CliResult r = runSpotshell("render --scene " + scene + " --size 48x48 --frames 0-4:2 --out " + tmp("shot.%03d.png"));
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_NE(r.out.find("wrote 3 frames"), std::string::npos) << r.out;
    EXPECT_FALSE(std::ifstream(tmp("shot.001.png")).good()) << "STEP 2 skips frame 1";
    std::map<std::string, std::string> meta0, meta4;
    const noise::Image f0 = noise::readImage(tmp("shot.000.png"), &meta0);
    const noise::Image f4 = noise::readImage(tmp("shot.004.png"), &meta4);
    EXPECT_EQ(meta0["time"], "0");
    EXPECT_EQ(std::stod(meta4["time"]), 4.0 / 24.0);
    EXPECT_LT(splat::psnr(f0, f4), 40.0) << "the tail moved between frames 0 and 4";
    // --resume: a frame removed and one cut short (as a killed copy would leave it, were the
    // writes not atomic) are rendered again, the complete one is skipped; the shot is the same.
    std::remove(tmp("shot.002.png").c_str());
    std::filesystem::resize_file(tmp("shot.004.png"), 100);
    const CliResult resumed = runSpotshell("render --scene " + scene + " --size 48x48 --frames 0-4:2 --resume --out " + tmp("shot.%03d.png"));
    ASSERT_EQ(resumed.code, 0) << resumed.err;
    EXPECT_NE(resumed.out.find("wrote 2 frames (1 already there)"), std::string::npos) << resumed.out;
    EXPECT_TRUE(std::isinf(splat::psnr(f4, noise::readImage(tmp("shot.004.png")))));
    const CliResult done = runSpotshell("render --scene " + scene + " --size 48x48 --frames 0-4:2 --resume --out " + tmp("shot.%03d.png"));
    ASSERT_EQ(done.code, 0) << done.err;
    EXPECT_NE(done.out.find("nothing rendered"), std::string::npos) << done.out;
    // The same frame alone (--time at 4 / 24 s) is the same image: the persistent frame carries
    // nothing from one frame to the next that changes it.
    const CliResult one = runSpotshell("render --scene " + scene + " --size 48x48 --time " +
                                       std::to_string(4.0 / 24.0) + " --out " + tmp("one.png"));
    ASSERT_EQ(one.code, 0) << one.err;
    EXPECT_GT(splat::psnr(f4, noise::readImage(tmp("one.png"))), 60.0);
    for (const std::string& bad : {std::string("--frames 0-2 --out ") + tmp("nopattern.png"),
                                   std::string("--frames 0-2 --time 1 --out ") + tmp("both.%d.png"),
                                   std::string("--frames 5-2 --out ") + tmp("back.%d.png"),
                                   std::string("--frames 0-2:0 --out ") + tmp("zero.%d.png"),
                                   std::string("--frames 0-2 --out ") + tmp("two.%d.%d.png")}) {
        const CliResult e = runSpotshell("render --scene " + scene + " --size 16x16 " + bad);
        EXPECT_EQ(e.code, 2) << bad << ": " << e.err;
        EXPECT_EQ(std::count(e.err.begin(), e.err.end(), '\n'), 1) << e.err;
    }
    for (const char* f : {"nopattern.png", "both.0.png", "back.5.png", "zero.0.png"})
        EXPECT_FALSE(std::ifstream(tmp(f)).good()) << f << " was written";
    // impulses --time: the moved impulses; a static mesh has no time.
    const CliResult moved = runSpotshell("impulses --mesh " + std::string(SPOT_SOURCE_DIR) +
                                         "/examples/animated/tail.glb --preset " + SPOT_SOURCE_DIR +
                                         "/presets/fur.json --time 0.5 --out " + tmp("tail.ply"));
    EXPECT_EQ(moved.code, 0) << moved.err;
    const CliResult still = runSpotshell("impulses --mesh generated:sphere --preset " +
                                         std::string(SPOT_SOURCE_DIR) + "/presets/fur.json --time 0.5 --out " + tmp("still.ply"));
    EXPECT_EQ(still.code, 2);
    EXPECT_NE(still.err.find("does not move"), std::string::npos) << still.err;
}

TEST(DeformGpu, AMeshCacheRendersItsInterpolatedFrame) {
    // Three frames of a sphere squashed along y and moved up: frame f is scaled by 1 - 0.2 f in y
    // and raised by 0.3 f; played at 2 fps, t = 0.75 is frame 1.5.
    const noise::Mesh sphere = noise::loadMeshOrGenerated("generated:sphere");
    for (int f = 0; f < 3; ++f) {
        noise::Mesh m = sphere;
        for (glm::vec3& p : m.positions)
            p = glm::vec3(p.x, p.y * (1.0f - 0.2f * float(f)) + 0.3f * float(f), p.z);
        m.normals.clear();
        noise::savePly(m, tmp("cache." + std::to_string(f) + ".ply"));
    }
    std::remove(tmp("cache.3.ply").c_str());
    const std::string scene = writeScene("cache", tmp("cache.%d.ply"), {0.0, 1.0, 4.5}, {0.0, 0.3, 0.0},
                                         {0, 1, 0}, 64, R"(, "animation": {"fps": 2})");
    const noise::Image ref = render(scene, "reference", 0.75, "cache-ref");
    const noise::Image refRest = render(scene, "reference", 0.0, "cache-ref0");
    EXPECT_LT(splat::psnr(ref, refRest), 25.0) << "frame 1.5 is not the rest";
    const double sorted = splat::psnr(ref, render(scene, "sorted", 0.75, "cache-sorted"));
    const double sortedRest = splat::psnr(refRest, render(scene, "sorted", 0.0, "cache-sorted0"));
    EXPECT_GT(sorted, sortedRest - 1.0) << sorted << " dB at frame 1.5, " << sortedRest << " at rest";
    // The scene's rest frame: the noise is generated on frame 2 instead, so frame 2 renders what
    // a static scene of frame 2's file renders.
    const std::string rest2 = writeScene("cache-rest2", tmp("cache.%d.ply"), {0.0, 1.0, 4.5}, {0.0, 0.3, 0.0},
                                         {0, 1, 0}, 64, R"(, "animation": {"fps": 2, "rest_frame": 2})");
    const noise::Image atTwo = render(rest2, "reference", 1.0, "cache-rest2");
    const std::string still = writeScene("cache-still2", tmp("cache.2.ply"), {0.0, 1.0, 4.5},
                                         {0.0, 0.3, 0.0}, {0, 1, 0}, 64);
    EXPECT_GT(splat::psnr(atTwo, render(still, "reference", 0.0, "cache-still2")), 60.0);
}

TEST(DeformGpu, ATurntableFrameIsTheStillSceneFromThatCamera) {
    // A pure function of the time: frame 12 of a turntable (30 degrees a second, 24 fps) is the
    // static scene seen from the camera turned by 15 degrees, byte for byte, on the GPU and in
    // the reference.
    const std::string turntable = writeScene("turntable", "generated:sphere", {0.0, 0.8, 3.2}, {0.0, 0.0, 0.0},
                                             {0, 1, 0}, 48, R"(, "animation": {"fps": 24})");
    {
        // The camera object with a turntable key: rewrite the file's camera.
        std::ifstream in(turntable);
        std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
        text.replace(text.find("\"fov_deg\": 40}"), 14, "\"fov_deg\": 40, \"turntable_deg_per_s\": 30}");
        std::ofstream(turntable) << text;
    }
    const double a = 15.0 * M_PI / 180.0;
    const glm::dvec3 eye(3.2 * std::sin(a), 0.8, 3.2 * std::cos(a));
    const std::string still = writeScene("turntable-still", "generated:sphere", eye, {0.0, 0.0, 0.0}, {0, 1, 0}, 48);
    for (const char* method : {"sorted", "reference"}) {
        const std::string out = tmp(std::string("tt-") + method + ".%02d.exr");
        const CliResult r = runSpotshell("render --scene " + turntable + " --method " + method +
                                         " --frames 0-12:12 --out " + out);
        ASSERT_EQ(r.code, 0) << r.err;
        const noise::Image frame12 = noise::readImage(tmp(std::string("tt-") + method + ".12.exr"));
        const noise::Image frame0 = noise::readImage(tmp(std::string("tt-") + method + ".00.exr"));
        const noise::Image want = render(still, method, 0.0, std::string("tt-still-") + method);
        EXPECT_GT(splat::psnr(want, frame12), 100.0) << method;
        EXPECT_LT(splat::psnr(frame0, frame12), 40.0) << method << ": the camera turned";
    }
}

namespace {

bool hasPass(const spot::splat::FrameStats& stats, const std::string& name) {
    for (const auto& [pass, ms] : stats.passMs)
        if (pass == name)
            return true;
    return false;
}

} // namespace

TEST(DeformGpu, AFrameAtTheSameTimeKeepsThePoseAndTheLightSpace) {
    // Issue 40, item 1: a paused clip, a repeat or an orbit at an unchanged time records no
    // deform or move pass and builds no light space; its image is the last frame's bit for bit,
    // and the impulses keep their version. A new time poses, moves and builds again.
    const noise::AnimatedMesh clip = noise::AnimatedMesh::loadGltf(bendClip(tmp("paused.glb")));
    const noise::ImpulseGenerator generator(
        clip.rest(), noise::loadPreset(std::string(SPOT_SOURCE_DIR) + "/presets/fur.json"), {});
    noise::Camera camera;
    camera.eye = {1.0, 0.5, 6.0};
    camera.target = {1.0, 0.5, 0.0};
    camera.fovYDeg = 40.0;
    camera.width = camera.height = 48;
    noise::Shading lit;
    lit.mode = noise::Shading::Mode::Lit;
    lit.lights.push_back(noise::Light{});
    lit.lights.back().direction = glm::normalize(glm::vec3(0.3f, 1.0f, 0.4f));
    lit.sky.intensity = 0.3f;
    ASSERT_TRUE(lit.castsShadows());
    splat::View view{camera, lit, glm::vec3(0.05f), glm::vec3(0.3f)};
    splat::Context ctx(validated());
    for (const char* method : {"sorted", "raymarch"}) {
        SCOPED_TRACE(method);
        splat::Frame frame(ctx, clip.rest(), generator);
        frame.animate(clip, noise::Wind{});
        frame.setTime(0.5);
        noise::Image first, again, orbit, moved;
        const splat::FrameStats a = frame.render(method, view, {}, &first);
        const std::uint64_t version = frame.deformer()->moved().version;
        EXPECT_TRUE(hasPass(a, "deform") && hasPass(a, "move") && hasPass(a, "light"));
        const splat::FrameStats b = frame.render(method, view, {}, &again);
        EXPECT_FALSE(hasPass(b, "deform") || hasPass(b, "move") || hasPass(b, "light"));
        EXPECT_EQ(frame.deformer()->moved().version, version);
        ASSERT_EQ(first.pixels.size(), again.pixels.size());
        EXPECT_EQ(std::memcmp(first.pixels.data(), again.pixels.data(),
                              first.pixels.size() * sizeof(glm::vec3)),
                  0);
        // An orbit: the camera moves, the pose and the light space stay.
        splat::View turned = view;
        turned.camera.eye = {2.5, 0.8, 5.5};
        const splat::FrameStats c = frame.render(method, turned, {}, &orbit);
        EXPECT_FALSE(hasPass(c, "deform") || hasPass(c, "move") || hasPass(c, "light"));
        EXPECT_NE(std::memcmp(first.pixels.data(), orbit.pixels.data(),
                              first.pixels.size() * sizeof(glm::vec3)),
                  0);
        // A new time: posed, moved and lit again, and a different picture.
        frame.setTime(0.9);
        const splat::FrameStats d = frame.render(method, view, {}, &moved);
        EXPECT_TRUE(hasPass(d, "deform") && hasPass(d, "move") && hasPass(d, "light"));
        EXPECT_NE(frame.deformer()->moved().version, version);
        EXPECT_NE(std::memcmp(first.pixels.data(), moved.pixels.data(),
                              first.pixels.size() * sizeof(glm::vec3)),
                  0);
        // Back at the first time: the first picture again, bit for bit (built again, not kept).
        frame.setTime(0.5);
        noise::Image back;
        frame.render(method, view, {}, &back);
        EXPECT_EQ(std::memcmp(first.pixels.data(), back.pixels.data(),
                              first.pixels.size() * sizeof(glm::vec3)),
                  0);
    }
    expectNoValidationErrors(ctx);
}
