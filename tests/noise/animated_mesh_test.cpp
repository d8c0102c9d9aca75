// Animated meshes (noise/animated_mesh.h): glTF 2.0 skins, morph targets, node animation and
// its three interpolations, posed on the CPU; mesh caches; bad files refused with one line.
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
// The library is built without image support (noise/animated_mesh.cpp): the same switches.
#define TINYGLTF_NO_STB_IMAGE
#define TINYGLTF_NO_STB_IMAGE_WRITE
#define TINYGLTF_NO_EXTERNAL_IMAGE
#include <tiny_gltf.h>

#include <glm/gtc/quaternion.hpp>

#include "cli_run.h"
#include "noise/animated_mesh.h"
#include "noise/error.h"

namespace {

using spot::noise::AnimatedMesh;

std::string tmp(const std::string& name) {
    return std::string(SPOT_TEST_TMP_DIR) + "/anim_" + name;
}

/// Builds a glTF model's buffer and accessors.
struct Builder {
    tinygltf::Model model;
    Builder() {
        model.buffers.emplace_back();
        model.asset.version = "2.0";
    }
    int add(const void* data, std::size_t bytes, std::size_t count, int type, int component,
            bool normalized = false) {
        auto& buffer = model.buffers[0].data;
        while (buffer.size() % 4 != 0)
            buffer.push_back(0);
        tinygltf::BufferView view;
        view.buffer = 0;
        view.byteOffset = buffer.size();
        view.byteLength = bytes;
        const auto* p = static_cast<const unsigned char*>(data);
        buffer.insert(buffer.end(), p, p + bytes);
        model.bufferViews.push_back(view);
        tinygltf::Accessor a;
        a.bufferView = int(model.bufferViews.size()) - 1;
        a.count = count;
        a.type = type;
        a.componentType = component;
        a.normalized = normalized;
        if (type == TINYGLTF_TYPE_SCALAR && component == TINYGLTF_COMPONENT_TYPE_FLOAT) {
            const float* f = static_cast<const float*>(data);
            a.minValues = {*std::min_element(f, f + count)};
            a.maxValues = {*std::max_element(f, f + count)};
        }
        model.accessors.push_back(a);
        return int(model.accessors.size()) - 1;
    }
    int floats(const std::vector<float>& v, int type, std::size_t per) {
        return add(v.data(), v.size() * 4, v.size() / per, type, TINYGLTF_COMPONENT_TYPE_FLOAT);
    }
};

/// A strip of two quads along x (x = 0, 1, 2; y = 0, 1) skinned to two joints (the second at
/// x = 1, a child of the first), its second joint turned 90 degrees about z from t = 0 to 1
/// (LINEAR); and a triangle on a node of its own, translated to x = 2 by a CUBICSPLINE with zero
/// tangents from t = 0 to 1 and its morph target (vertex 0 up by z = 1) switched on at t = 0.5
/// (STEP).
tinygltf::Model makeClip() {
    Builder b;
    const std::vector<float> positions = {0, 0, 0, 1, 0, 0, 2, 0, 0, 0, 1, 0, 1, 1, 0, 2, 1, 0};
    const std::vector<std::uint16_t> indices = {0, 1, 4, 0, 4, 3, 1, 2, 5, 1, 5, 4};
    const std::vector<std::uint8_t> joints = {0, 0, 0, 0, 0, 1, 0, 0, 1, 0, 0, 0,
                                              0, 0, 0, 0, 0, 1, 0, 0, 1, 0, 0, 0};
    const std::vector<float> weights = {1, 0, 0, 0, 0.5f, 0.5f, 0, 0, 1, 0, 0, 0,
                                        1, 0, 0, 0, 0.5f, 0.5f, 0, 0, 1, 0, 0, 0};
    tinygltf::Primitive strip;
    strip.mode = TINYGLTF_MODE_TRIANGLES;
    strip.attributes["POSITION"] = b.floats(positions, TINYGLTF_TYPE_VEC3, 3);
    strip.attributes["JOINTS_0"] = b.add(joints.data(), joints.size(), 6, TINYGLTF_TYPE_VEC4,
                                         TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE);
    strip.attributes["WEIGHTS_0"] = b.floats(weights, TINYGLTF_TYPE_VEC4, 4);
    strip.indices = b.add(indices.data(), indices.size() * 2, indices.size(), TINYGLTF_TYPE_SCALAR,
                          TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT);
    tinygltf::Mesh stripMesh;
    stripMesh.name = "strip";
    stripMesh.primitives.push_back(strip);
    b.model.meshes.push_back(stripMesh);

    const std::vector<float> tri = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    const std::vector<float> up = {0, 0, 1, 0, 0, 0, 0, 0, 0};
    tinygltf::Primitive triangle;
    triangle.mode = TINYGLTF_MODE_TRIANGLES;
    triangle.attributes["POSITION"] = b.floats(tri, TINYGLTF_TYPE_VEC3, 3);
    triangle.targets.push_back({{"POSITION", b.floats(up, TINYGLTF_TYPE_VEC3, 3)}});
    tinygltf::Mesh triangleMesh;
    triangleMesh.name = "flap";
    triangleMesh.primitives.push_back(triangle);
    b.model.meshes.push_back(triangleMesh);

    // Nodes: 0 the strip (skinned), 1 the root joint, 2 the second joint (x = 1), 3 the flap.
    tinygltf::Node stripNode, root, second, flap;
    stripNode.mesh = 0;
    stripNode.skin = 0;
    root.children = {2};
    second.translation = {1, 0, 0};
    flap.mesh = 1;
    flap.translation = {0, 0, 5};
    b.model.nodes = {stripNode, root, second, flap};
    const std::vector<float> inverseBind = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0,  0, 0, 1,
                                            1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, -1, 0, 0, 1};
    tinygltf::Skin skin;
    skin.joints = {1, 2};
    skin.inverseBindMatrices = b.floats(inverseBind, TINYGLTF_TYPE_MAT4, 16);
    b.model.skins.push_back(skin);
    tinygltf::Scene scene;
    scene.nodes = {0, 1, 3};
    b.model.scenes.push_back(scene);
    b.model.defaultScene = 0;

    tinygltf::Animation clip;
    clip.name = "wave";
    const glm::quat turned = glm::angleAxis(float(M_PI / 2), glm::vec3(0, 0, 1));
    const int times01 = b.floats({0.0f, 1.0f}, TINYGLTF_TYPE_SCALAR, 1);
    const auto sampler = [&](int input, int output, const char* interpolation) {
        tinygltf::AnimationSampler s;
        s.input = input;
        s.output = output;
        s.interpolation = interpolation;
        clip.samplers.push_back(s);
        return int(clip.samplers.size()) - 1;
    };
    const auto channel = [&](int s, int node, const char* path) {
        tinygltf::AnimationChannel c;
        c.sampler = s;
        c.target_node = node;
        c.target_path = path;
        clip.channels.push_back(c);
    };
    channel(sampler(times01,
                    b.floats({0, 0, 0, 1, turned.x, turned.y, turned.z, turned.w},
                             TINYGLTF_TYPE_VEC4, 4),
                    "LINEAR"),
            2, "rotation");
    channel(sampler(times01,
                    b.floats({0, 0, 0, 0, 0, 5, 0, 0, 0, 0, 0, 0, 2, 0, 5, 0, 0, 0},
                             TINYGLTF_TYPE_VEC3, 3),
                    "CUBICSPLINE"),
            3, "translation");
    channel(sampler(b.floats({0.0f, 0.5f}, TINYGLTF_TYPE_SCALAR, 1),
                    b.floats({0.0f, 1.0f}, TINYGLTF_TYPE_SCALAR, 1), "STEP"),
            3, "weights");
    b.model.animations.push_back(clip);
    return b.model;
}

void expectNear(const glm::vec3& got, const glm::vec3& want, const char* what) {
    EXPECT_NEAR(got.x, want.x, 1e-5f) << what;
    EXPECT_NEAR(got.y, want.y, 1e-5f) << what;
    EXPECT_NEAR(got.z, want.z, 1e-5f) << what;
}

} // namespace

TEST(AnimatedMesh, SamplersInterpolateAsGltfSays) {
    using I = AnimatedMesh::Interpolation;
    // LINEAR on a vec1, STEP holds the earlier key, times clamp at the ends.
    EXPECT_FLOAT_EQ(AnimatedMesh::sample({0, 2}, {1, 3}, 1, I::Linear, false, 0.5)[0], 1.5f);
    EXPECT_FLOAT_EQ(AnimatedMesh::sample({0, 2}, {1, 3}, 1, I::Step, false, 1.99)[0], 1.0f);
    EXPECT_FLOAT_EQ(AnimatedMesh::sample({0, 2}, {1, 3}, 1, I::Linear, false, -4)[0], 1.0f);
    EXPECT_FLOAT_EQ(AnimatedMesh::sample({0, 2}, {1, 3}, 1, I::Linear, false, 9)[0], 3.0f);
    // Rotations by slerp: half way from identity to 180 degrees about z is 90 degrees.
    const glm::quat half = glm::angleAxis(float(M_PI), glm::vec3(0, 0, 1));
    const auto q = AnimatedMesh::sample({0, 1}, {0, 0, 0, 1, half.x, half.y, half.z, half.w}, 4,
                                        I::Linear, true, 0.5);
    const glm::quat want = glm::angleAxis(float(M_PI / 2), glm::vec3(0, 0, 1));
    EXPECT_NEAR(std::abs(q[2]), want.z, 1e-6f);
    EXPECT_NEAR(std::abs(q[3]), want.w, 1e-6f);
    // CUBICSPLINE: the Hermite curve, tangents scaled by the interval (here 2 s): from 0 with
    // slope 1 to 2 with slope 1 is the line p = t, so t = 0.5 gives 0.5 (a linear key blend
    // would too; a slope of 0 at both ends gives the smoothstep 2 x 0.15625 = 0.3125 at 0.5).
    EXPECT_NEAR(AnimatedMesh::sample({0, 2}, {1, 0, 1, 1, 2, 1}, 1, I::CubicSpline, false, 0.5)[0],
                0.5f, 1e-6f);
    EXPECT_NEAR(AnimatedMesh::sample({0, 2}, {0, 0, 0, 0, 2, 0}, 1, I::CubicSpline, false, 0.5)[0],
                0.3125f, 1e-6f);
}

TEST(AnimatedMesh, GltfSkinMorphAndNodeAnimationPoseAsComputedByHand) {
    const tinygltf::Model model = makeClip();
    tinygltf::TinyGLTF writer;
    for (const bool binary : {false, true}) {
        const std::string file = tmp(binary ? "clip.glb" : "clip.gltf");
        ASSERT_TRUE(writer.WriteGltfSceneToFile(&model, file, false, true, true, binary));
        const AnimatedMesh a = AnimatedMesh::loadGltf(file);
        SCOPED_TRACE(file);
        ASSERT_EQ(a.rest().positions.size(), 9u);
        ASSERT_EQ(a.rest().triangles.size(), 5u);
        EXPECT_EQ(a.clipName(), "wave");
        EXPECT_EQ(a.jointCount(), 2u);
        EXPECT_EQ(a.morphTargetCount(), 1u);
        EXPECT_DOUBLE_EQ(a.duration(), 1.0);
        // The rest pose is the bind pose: the strip as stored, the flap at its node's place.
        expectNear(a.rest().positions[5], glm::vec3(2, 1, 0), "rest strip");
        expectNear(a.rest().positions[6], glm::vec3(0, 0, 5), "rest flap");
        const std::vector<glm::vec3> p = a.posePositions(1.0);
        // The second joint turned 90 degrees about z at x = 1: (2, 0) goes to (1, 1), (2, 1) to
        // (0, 1); the middle column, half on each joint, to the mean of both places.
        expectNear(p[0], glm::vec3(0, 0, 0), "root-only vertex");
        expectNear(p[2], glm::vec3(1, 1, 0), "second-joint vertex");
        expectNear(p[5], glm::vec3(0, 1, 0), "second-joint vertex");
        expectNear(p[4], glm::vec3(0.5f, 0.5f, 0), "blended vertex (1, 1): (1, 1) and (0, 0)");
        // The flap: translated along x by the spline (2 at t = 1), its morph on since t = 0.5.
        expectNear(p[6], glm::vec3(2, 0, 6), "flap vertex 0, morphed");
        expectNear(p[7], glm::vec3(3, 0, 5), "flap vertex 1");
        const std::vector<glm::vec3> mid = a.posePositions(0.25);
        expectNear(mid[6], glm::vec3(2 * 0.15625f, 0, 5), "spline at a quarter, morph still off");
        // A pose keeps the rest's topology, with unit normals.
        const spot::noise::Mesh posed = a.pose(0.75);
        EXPECT_EQ(posed.triangles, a.rest().triangles);
        for (const glm::vec3& n : posed.normals)
            EXPECT_NEAR(glm::length(n), 1.0f, 1e-5f);
    }
}

TEST(AnimatedMesh, BadFilesAreRefusedWithOneLine) {
    const tinygltf::Model model = makeClip();
    tinygltf::TinyGLTF writer;
    const std::string file = tmp("bad.glb");
    ASSERT_TRUE(writer.WriteGltfSceneToFile(&model, file, false, true, false, true));
    std::string bytes;
    {
        std::ifstream in(file, std::ios::binary);
        bytes.assign(std::istreambuf_iterator<char>(in), {});
    }
    EXPECT_THROW(AnimatedMesh::loadGltf(file, "no such clip"), spot::InputError);
    for (const std::size_t cut :
         {std::size_t(0), std::size_t(12), bytes.size() / 2, bytes.size() - 9}) {
        const std::string cutFile = tmp("cut.glb");
        std::ofstream(cutFile, std::ios::binary) << bytes.substr(0, cut);
        try {
            AnimatedMesh::loadGltf(cutFile);
            ADD_FAILURE() << "a file cut at " << cut << " bytes was read";
        } catch (const spot::InputError& e) {
            EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos) << e.what();
        }
    }
    // A joint index past the skin's joints.
    tinygltf::Model bad = makeClip();
    bad.skins[0].joints = {1};
    bad.skins[0].inverseBindMatrices = -1;
    const std::string badFile = tmp("badjoint.gltf");
    ASSERT_TRUE(writer.WriteGltfSceneToFile(&bad, badFile, false, true, true, false));
    EXPECT_THROW(AnimatedMesh::loadGltf(badFile), spot::InputError);
}

TEST(AnimatedMesh, MeshCacheInterpolatesItsFramesAndChecksTheirTopology) {
    // A run leaves the frames behind; the cache is whatever consecutive files exist.
    for (int f = 0; f < 20; ++f)
        std::remove(tmp("cache." + std::to_string(f) + ".obj").c_str());
    for (int f = 0; f < 3; ++f) {
        std::ofstream obj(tmp("cache." + std::to_string(10 + f) + ".obj"));
        obj << "v 0 0 0\nv 1 0 0\nv 0 1 " << f << "\nf 1 2 3\n";
    }
    const AnimatedMesh a = AnimatedMesh::loadCache(tmp("cache.%d.obj"), 2.0);
    EXPECT_EQ(a.frameCount(), 3u);
    EXPECT_DOUBLE_EQ(a.duration(), 1.0);
    EXPECT_NEAR(a.posePositions(0.75)[2].z, 1.5f, 1e-6f); // frame 1.5
    EXPECT_NEAR(a.posePositions(9.0)[2].z, 2.0f, 1e-6f);  // clamped to the last
    EXPECT_NEAR(a.rest().positions[2].z, 0.0f, 1e-6f);
    std::ofstream(tmp("cache.13.obj")) << "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 3\nf 2 4 3\n";
    EXPECT_THROW(AnimatedMesh::loadCache(tmp("cache.%d.obj"), 2.0), spot::InputError);
}

TEST(AnimatedMesh, InfoPrintsAClipAndItsPose) {
    const tinygltf::Model model = makeClip();
    tinygltf::TinyGLTF writer;
    const std::string file = tmp("info.glb");
    ASSERT_TRUE(writer.WriteGltfSceneToFile(&model, file, false, true, false, true));
    const auto r = spot::test::runSpotshell("info --mesh " + file + " --time 1");
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_NE(r.out.find("clip       wave, 1 s"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("joints     2"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("[0 0 0] .. [3 1 6]"), std::string::npos) << r.out; // the pose at 1 s
    const auto bad = spot::test::runSpotshell("info --mesh " + file + " --clip run");
    EXPECT_EQ(bad.code, 2);
    EXPECT_NE(bad.err.find("has no clip 'run' (wave)"), std::string::npos) << bad.err;
}
