// Impulses that follow a moving mesh on the CPU (noise/deform.h, shaders/spot_deform.h): the
// triangle rotation, no swimming over a clip, the wind, collapsed triangles, the scene keys.
#include <cmath>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "gltf_clips.h"
#include "noise/animated_mesh.h"
#include "noise/deform.h"
#include "noise/error.h"
#include "noise/impulses.h"
#include "noise/preset.h"
#include "noise/scene.h"
#include "shaders/spot_deform.hpp"
#include "test_support.h"

namespace {

using namespace spot;
namespace sh = spot::shared::f32;

std::string tmp(const std::string& name) { return std::string(SPOT_TEST_TMP_DIR) + "/deform_" + name; }

float maxAbs(const glm::mat3& a, const glm::mat3& b) {
    float m = 0.0f;
    for (int c = 0; c < 3; ++c)
        for (int r = 0; r < 3; ++r)
            m = std::max(m, std::abs(a[c][r] - b[c][r]));
    return m;
}

noise::PresetDesc furPreset() {
    return noise::loadPreset(std::string(SPOT_SOURCE_DIR) + "/presets/fur.json");
}

} // namespace

TEST(TriangleRotation, IsTheRigidMotionsRotationWhicheverCornerComesFirst) {
    const glm::vec3 p[3] = {{0.1f, 0.2f, 0.3f}, {1.0f, 0.1f, 0.0f}, {0.2f, 0.9f, 0.4f}};
    const glm::mat3 turn = glm::mat3_cast(glm::angleAxis(1.1f, glm::normalize(glm::vec3(1, 2, 3))));
    const glm::vec3 shift(3.0f, -1.0f, 2.0f);
    glm::vec3 q[3];
    for (int i = 0; i < 3; ++i)
        q[i] = turn * p[i] + shift;
    for (int first = 0; first < 3; ++first) {
        glm::mat3 R(1.0f);
        const int a = first, b = (first + 1) % 3, c = (first + 2) % 3;
        ASSERT_TRUE(sh::spotTriangleRotation(p[a], p[b], p[c], q[a], q[b], q[c], R));
        EXPECT_LT(maxAbs(R, turn), 1e-5f) << "corner " << first;
    }
    // A shear and a stretch within the plane: still a rotation (orthonormal, det 1), the same
    // from every corner, and it carries the rest normal to the posed one.
    glm::vec3 s[3] = {{0, 0, 0}, {2.0f, 0.3f, 0}, {0.7f, 0.5f, 0}};
    glm::vec3 r[3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    glm::mat3 first(1.0f);
    ASSERT_TRUE(sh::spotTriangleRotation(r[0], r[1], r[2], s[0], s[1], s[2], first));
    EXPECT_LT(maxAbs(glm::transpose(first) * first, glm::mat3(1.0f)), 1e-5f);
    EXPECT_NEAR(glm::determinant(first), 1.0f, 1e-5f);
    for (int k = 1; k < 3; ++k) {
        glm::mat3 R(1.0f);
        ASSERT_TRUE(sh::spotTriangleRotation(r[k], r[(k + 1) % 3], r[(k + 2) % 3], s[k],
                                             s[(k + 1) % 3], s[(k + 2) % 3], R));
        EXPECT_LT(maxAbs(R, first), 1e-5f) << "corner " << k;
    }
    // Collapsed to a line: false, R untouched.
    glm::mat3 kept = turn;
    EXPECT_FALSE(sh::spotTriangleRotation(p[0], p[1], p[2], q[0], q[1], q[0] + 2.0f * (q[1] - q[0]),
                                          kept));
    EXPECT_EQ(maxAbs(kept, turn), 0.0f);
}

TEST(Deform, ImpulsesNeverSwimOverSixtyFrames) {
    const noise::AnimatedMesh clip = noise::AnimatedMesh::loadGltf(spot::test::bendClip(tmp("bend.glb")));
    const noise::ImpulseGenerator generator(clip.rest(), furPreset(), {});
    const std::vector<noise::Impulse> rest = generator.generate();
    ASSERT_GT(rest.size(), 1000u);
    noise::Deformer deformer(clip);
    double moved = 0.0;
    for (int f = 0; f < 60; ++f) {
        const double t = f / 59.0;
        deformer.pose(t);
        const noise::Mesh& posed = deformer.posed();
        const std::vector<noise::Impulse> now = deformer.move(rest, generator.cellSize());
        // The count and every anchor and random value, bit for bit (a fresh generation on the
        // rest gives the same impulses too: nothing depends on the pose).
        ASSERT_EQ(now.size(), rest.size());
        for (std::size_t i = 0; i < rest.size(); ++i) {
            const noise::Impulse& a = rest[i];
            const noise::Impulse& b = now[i];
            ASSERT_EQ(a.triangle, b.triangle);
            ASSERT_EQ(std::memcmp(&a.barycentric, &b.barycentric, sizeof(a.barycentric)), 0);
            ASSERT_EQ(std::memcmp(&a.scale, &b.scale, sizeof(a.scale)), 0);
            ASSERT_EQ(std::memcmp(&a.color, &b.color, sizeof(a.color)), 0);
            ASSERT_EQ(a.weight, b.weight);
            ASSERT_EQ(a.bend, b.bend);
            ASSERT_EQ(a.height, b.height);
            // The position: the posed triangle's point at the anchor plus the height along the
            // interpolated posed normal (computed here in double, independently).
            const glm::uvec3 tri = posed.triangles[a.triangle];
            const glm::dvec3 w(1.0 - a.barycentric.x - a.barycentric.y, a.barycentric.x,
                               a.barycentric.y);
            const glm::dvec3 point = w.x * glm::dvec3(posed.positions[tri.x]) +
                                     w.y * glm::dvec3(posed.positions[tri.y]) +
                                     w.z * glm::dvec3(posed.positions[tri.z]);
            const glm::dvec3 normal = glm::normalize(w.x * glm::dvec3(posed.normals[tri.x]) +
                                                     w.y * glm::dvec3(posed.normals[tri.y]) +
                                                     w.z * glm::dvec3(posed.normals[tri.z]));
            const glm::dvec3 want = point + double(a.height) * normal;
            ASSERT_LT(glm::length(glm::dvec3(b.position) - want), 1e-5 * std::max(1.0, glm::length(want)))
                << "impulse " << i << " at t " << t;
            // The frame stays a rotation of the rest's (the kernel's scale is unchanged).
            ASSERT_LT(maxAbs(glm::transpose(b.frame) * b.frame, glm::mat3(1.0f)), 1e-4f);
            moved = std::max(moved, double(glm::length(b.position - a.position)));
        }
    }
    EXPECT_GT(moved, 0.5) << "the bend moves the tube's tip by about its length";
    // At rest the impulses are where they were generated.
    deformer.pose(0.0);
    const std::vector<noise::Impulse> again = deformer.move(rest, generator.cellSize());
    for (std::size_t i = 0; i < rest.size(); i += 97)
        EXPECT_LT(glm::length(again[i].position - rest[i].position), 1e-5f);
}

// Clumped kernels on an animated surface keep their clumping: the deformer turns each kernel with
// its triangle (it never rebuilds the frame from the comb and tilt), so a kernel's lean towards
// its clump, seen from its surface normal, is the rest's at every pose.
TEST(Deform, ClumpedKernelsKeepTheirLeanWhenPosed) {
    const noise::AnimatedMesh clip = noise::AnimatedMesh::loadGltf(spot::test::bendClip(tmp("bend-clump.glb")));
    noise::PresetDesc preset =
        noise::loadPreset(std::string(SPOT_SOURCE_DIR) + "/presets/fur-clumped.json");
    const noise::ImpulseGenerator generator(clip.rest(), preset, {});
    const std::vector<noise::Impulse> rest = generator.generate();
    preset.clump = spot::test::constantField(glm::vec3(0.0f), 1);
    const std::vector<noise::Impulse> unclumped =
        noise::ImpulseGenerator(clip.rest(), preset, {}).generate();
    ASSERT_EQ(rest.size(), unclumped.size());
    ASSERT_GT(rest.size(), 1000u);
    noise::Deformer deformer(clip);
    for (const double t : {0.5, 1.0}) {
        deformer.pose(t);
        const std::vector<noise::Impulse> now = deformer.move(rest, generator.cellSize());
        const std::vector<noise::Impulse> plain = deformer.move(unclumped, generator.cellSize());
        double worst = 0.0, leaned = 0.0;
        for (std::size_t i = 0; i < rest.size(); ++i) {
            ASSERT_EQ(now[i].clumpStrength, rest[i].clumpStrength);
            ASSERT_EQ(now[i].clumpDistance, rest[i].clumpDistance);
            // The clumped axis in the frame of the unclumped one, at rest and posed: the same
            // rotation (the triangle's turns both).
            const glm::mat3 atRest = glm::transpose(unclumped[i].frame) * rest[i].frame;
            const glm::mat3 posed = glm::transpose(plain[i].frame) * now[i].frame;
            worst = std::max(worst, double(maxAbs(atRest, posed)));
            leaned = std::max(leaned, double(glm::length(atRest[2] - glm::vec3(0, 0, 1))));
        }
        EXPECT_LT(worst, 1e-4) << "t " << t;
        EXPECT_GT(leaned, 0.3) << "the clumps turn kernels";
    }
}

TEST(Deform, WindTurnsAboutTheRootDeterministicallyInTime) {
    const noise::AnimatedMesh still = noise::AnimatedMesh::load("generated:plane");
    const noise::ImpulseGenerator generator(still.rest(), furPreset(), {});
    const std::vector<noise::Impulse> rest = generator.generate();
    ASSERT_FALSE(rest.empty());
    noise::Deformer deformer(still);
    noise::Wind wind;
    wind.direction = glm::vec3(1, 0, 0);
    wind.strength = 0.5f;
    wind.gustFrequency = 1.0f;
    wind.variation = 0.5f;
    deformer.pose(0.3);
    const std::vector<noise::Impulse> a = deformer.move(rest, generator.cellSize(), wind);
    const std::vector<noise::Impulse> b = deformer.move(rest, generator.cellSize(), wind);
    deformer.pose(0.55);
    const std::vector<noise::Impulse> c = deformer.move(rest, generator.cellSize(), wind);
    const std::vector<noise::Impulse> calm = deformer.move(rest, generator.cellSize());
    double changed = 0.0, leanX = 0.0;
    for (std::size_t i = 0; i < rest.size(); ++i) {
        EXPECT_EQ(std::memcmp(&a[i].position, &b[i].position, sizeof(glm::vec3)), 0);
        // The root (the surface point) stays; the kernel keeps its distance from it.
        const glm::vec3 root = rest[i].position - rest[i].height * rest[i].normal;
        EXPECT_NEAR(glm::length(a[i].position - root), std::abs(rest[i].height), 1e-5f);
        EXPECT_LT(glm::length(calm[i].position - rest[i].position), 1e-5f);
        changed = std::max(changed, double(glm::length(c[i].frame[2] - a[i].frame[2])));
        leanX += a[i].frame[2].x;
    }
    EXPECT_GT(changed, 0.01) << "gusts move the kernels between t = 0.3 and 0.55";
    EXPECT_GT(leanX / double(rest.size()), 0.1) << "the kernels lean downwind (+x)";
}

TEST(Deform, ACollapsedTriangleKeepsItsLastFrameAndNoNaN) {
    const noise::AnimatedMesh squash = noise::AnimatedMesh::loadGltf(
        spot::test::squashClip(noise::loadMeshOrGenerated("generated:plane"), tmp("squash.glb")));
    const noise::ImpulseGenerator generator(squash.rest(), furPreset(), {});
    const std::vector<noise::Impulse> rest = generator.generate();
    noise::Deformer deformer(squash);
    deformer.pose(0.5);
    EXPECT_EQ(deformer.collapsed(), 0u);
    const std::vector<glm::mat3> half = deformer.rotations();
    deformer.pose(1.0);
    EXPECT_EQ(deformer.collapsed(), squash.rest().triangles.size());
    for (std::size_t t = 0; t < half.size(); ++t)
        ASSERT_EQ(maxAbs(half[t], deformer.rotations()[t]), 0.0f);
    for (const noise::Impulse& imp : deformer.move(rest, generator.cellSize())) {
        for (int k = 0; k < 3; ++k) {
            ASSERT_TRUE(std::isfinite(imp.position[k]));
            for (int c = 0; c < 3; ++c)
                ASSERT_TRUE(std::isfinite(imp.frame[c][k]));
        }
    }
}

TEST(Deform, SceneKeysAnimationAndWind) {
    const std::string base = R"({"version": 1, "mesh": "generated:plane", "preset": "p.json",
        "camera": {"eye": [0, 1, 3], "target": [0, 0, 0]}, "image": {"width": 8, "height": 8})";
    const noise::SceneDesc s = noise::parseScene(
        base + R"(, "animation": {"clip": "walk", "fps": 30, "frame": 15, "rest_frame": 2},
            "wind": {"direction": [0, 0, 2], "strength": 0.3, "gust_frequency": 2, "variation": 0.1}})",
        "s.json", ".");
    EXPECT_EQ(s.animation.clip, "walk");
    EXPECT_DOUBLE_EQ(s.animation.fps, 30.0);
    EXPECT_DOUBLE_EQ(s.animation.time, 0.5);
    EXPECT_EQ(s.animation.restFrame, 2);
    EXPECT_EQ(s.wind.direction, glm::vec3(0, 0, 1));
    EXPECT_FLOAT_EQ(s.wind.strength, 0.3f);
    EXPECT_FLOAT_EQ(s.wind.gustFrequency, 2.0f);
    EXPECT_FLOAT_EQ(s.wind.variation, 0.1f);
    for (const char* bad : {R"(, "animation": {"fps": 0}})", R"(, "animation": {"time": 1, "frame": 2}})",
                            R"(, "animation": {"speed": 2}})", R"(, "wind": {"direction": [0, 0, 0], "strength": 1}})",
                            R"(, "wind": {"direction": [1, 0, 0]}})", R"(, "wind": {"strength": 1, "variation": 2}})"}) {
        try {
            noise::parseScene(base + bad, "s.json", ".");
            ADD_FAILURE() << "accepted " << bad;
        } catch (const InputError& e) {
            EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos);
        }
    }
}

TEST(Deform, SceneCameraKeysAndTurntableMoveTheCamera) {
    const std::string base = R"({"version": 1, "mesh": "generated:plane", "preset": "p.json",
        "image": {"width": 8, "height": 8}, "camera": {"eye": [0, 0, 3], "target": [0, 0, 0])";
    const noise::SceneDesc keys = noise::parseScene(
        base + R"(, "keys": [{"time": 1, "eye": [0, 0, 3], "target": [0, 0, 0]},
                             {"time": 3, "eye": [0, 2, 5], "target": [1, 0, 0]}]}})",
        "s.json", ".");
    ASSERT_TRUE(keys.cameraMoves());
    EXPECT_EQ(noise::cameraAt(keys, keys.camera, 0.0).eye, glm::dvec3(0, 0, 3)); // before: the first
    EXPECT_EQ(noise::cameraAt(keys, keys.camera, 2.0).eye, glm::dvec3(0, 1, 4));
    EXPECT_EQ(noise::cameraAt(keys, keys.camera, 2.0).target, glm::dvec3(0.5, 0, 0));
    EXPECT_EQ(noise::cameraAt(keys, keys.camera, 9.0).eye, glm::dvec3(0, 2, 5)); // after: the last
    const noise::SceneDesc turn = noise::parseScene(base + R"(, "turntable_deg_per_s": 90}})", "s.json", ".");
    const glm::dvec3 quarter = noise::cameraAt(turn, turn.camera, 1.0).eye;
    EXPECT_NEAR(quarter.x, 3.0, 1e-12);
    EXPECT_NEAR(quarter.z, 0.0, 1e-12);
    EXPECT_EQ(noise::cameraAt(turn, turn.camera, 0.0).eye, glm::dvec3(0, 0, 3));
    const noise::SceneDesc still = noise::parseScene(base + "}}", "s.json", ".");
    EXPECT_FALSE(still.cameraMoves());
    for (const char* bad : {R"(, "keys": []}})",
                            R"(, "keys": [{"time": 1, "eye": [0, 0, 3], "target": [0, 0, 0]}, {"time": 1, "eye": [0, 0, 2], "target": [0, 0, 0]}]}})",
                            R"(, "keys": [{"time": 0, "eye": [0, 0, 0], "target": [0, 0, 0]}]}})",
                            R"(, "keys": [{"time": 0, "eye": [0, 3, 0], "target": [0, 0, 0]}]}})",
                            R"(, "turntable_deg_per_s": "fast"}})"}) {
        try {
            noise::parseScene(base + bad, "s.json", ".");
            ADD_FAILURE() << "accepted " << bad;
        } catch (const InputError& e) {
            EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos);
        }
    }
}
