// Animated meshes (noise/animated_mesh.h): glTF 2.0 skins, morph targets, node animation and
// its three interpolations, posed on the CPU; mesh caches; bad files refused with one line.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <set>
#include <string>
#include <tuple>
#include <vector>

#include <gtest/gtest.h>
#include "gltf_clips.h" // tinygltf, built as the library is, and GltfBuilder

#include <glm/gtc/quaternion.hpp>

#include "cli_run.h"
#include "noise/animated_mesh.h"
#include "noise/error.h"
#include "noise/field.h"
#include "noise/image.h"
#include "noise/scene.h"

namespace {

using spot::noise::AnimatedMesh;

std::string tmp(const std::string& name) {
    return std::string(SPOT_TEST_TMP_DIR) + "/anim_" + name;
}

using Builder = spot::test::GltfBuilder;

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

namespace {

/// The float at element `i`, component `c` of a float accessor of `model` (to spoil a file).
float& floatAt(tinygltf::Model& model, int accessor, std::size_t i, int c = 0) {
    const tinygltf::Accessor& a = model.accessors[std::size_t(accessor)];
    const tinygltf::BufferView& view = model.bufferViews[std::size_t(a.bufferView)];
    const std::size_t stride = std::size_t(a.ByteStride(view));
    auto* p = model.buffers[std::size_t(view.buffer)].data.data() + view.byteOffset + a.byteOffset +
              i * stride + std::size_t(c) * 4;
    return *reinterpret_cast<float*>(p);
}

/// Writes `model` as a .glb and expects loadGltf to refuse it with one line that names the file
/// and holds `reason`.
void expectRefused(const tinygltf::Model& model, const std::string& name,
                   const std::string& reason) {
    tinygltf::TinyGLTF writer;
    const std::string file = tmp(name + ".glb");
    ASSERT_TRUE(writer.WriteGltfSceneToFile(&model, file, false, true, false, true)) << name;
    try {
        AnimatedMesh::loadGltf(file);
        ADD_FAILURE() << name << ": was loaded";
    } catch (const spot::InputError& e) {
        const std::string what = e.what();
        EXPECT_EQ(what.find('\n'), std::string::npos) << what;
        EXPECT_EQ(what.rfind(file, 0), 0u) << what;
        EXPECT_NE(what.find(reason), std::string::npos) << name << ": " << what;
    }
}

// makeClip's accessors, in the order it adds them.
constexpr int kStripPositions = 0, kStripJoints = 1, kStripWeights = 2, kStripIndices = 3,
              kInverseBind = 6, kTimes01 = 7, kRotationValues = 8;

} // namespace

TEST(AnimatedMesh, BadGltfBuffersAndIndicesAreRefused) {
    tinygltf::TinyGLTF writer;
    // A .gltf whose buffer file is missing, or shorter than it says.
    {
        tinygltf::Model model = makeClip();
        model.buffers[0].uri = "anim_external.bin";
        const std::string file = tmp("external.gltf");
        ASSERT_TRUE(writer.WriteGltfSceneToFile(&model, file, false, false, true, false));
        EXPECT_NO_THROW(AnimatedMesh::loadGltf(file));
        const std::string bin = tmp("external.bin");
        std::string bytes;
        {
            std::ifstream in(bin, std::ios::binary);
            bytes.assign(std::istreambuf_iterator<char>(in), {});
        }
        ASSERT_GT(bytes.size(), 100u);
        std::ofstream(bin, std::ios::binary | std::ios::trunc) << bytes.substr(0, 100);
        EXPECT_THROW(AnimatedMesh::loadGltf(file), spot::InputError);
        std::filesystem::remove(bin);
        EXPECT_THROW(AnimatedMesh::loadGltf(file), spot::InputError);
    }
    // A buffer view past its buffer.
    {
        tinygltf::Model model = makeClip();
        model.bufferViews[std::size_t(model.accessors[kStripPositions].bufferView)].byteLength +=
            model.buffers[0].data.size();
        expectRefused(model, "view_past_buffer", "reaches past buffer 0");
    }
    // An accessor past its buffer view, and past the buffer itself.
    {
        tinygltf::Model model = makeClip();
        model.accessors[kStripPositions].count = 7;
        expectRefused(model, "accessor_past_view", "reaches past buffer view");
        model.accessors[kStripPositions].count = 6;
        model.accessors[kStripPositions].byteOffset = model.buffers[0].data.size();
        expectRefused(model, "accessor_past_buffer", "reaches past buffer view");
    }
    // Accessor, buffer view, buffer and joint indices that do not exist.
    {
        tinygltf::Model model = makeClip();
        model.meshes[0].primitives[0].attributes["POSITION"] = 99;
        expectRefused(model, "no_accessor", "accessor 99 does not exist");
    }
    {
        tinygltf::Model model = makeClip();
        model.accessors[kStripWeights].bufferView = 99;
        expectRefused(model, "no_view", "buffer view 99 does not exist");
    }
    {
        tinygltf::Model model = makeClip();
        model.skins[0].inverseBindMatrices = 42;
        expectRefused(model, "no_ibm_accessor", "accessor 42 does not exist");
    }
    {
        tinygltf::Model model = makeClip();
        model.animations[0].samplers[0].output = 77;
        expectRefused(model, "no_key_accessor", "accessor 77 does not exist");
    }
    {
        tinygltf::Model model = makeClip();
        model.bufferViews[0].buffer = 3;
        expectRefused(model, "no_buffer", "buffer 3 does not exist");
    }
    {
        tinygltf::Model model = makeClip();
        const auto& a = model.accessors[kStripJoints];
        model.buffers[0].data[model.bufferViews[std::size_t(a.bufferView)].byteOffset + 9] = 7;
        expectRefused(model, "joint_out_of_range", "vertex 2 names joint 7 of a skin with 2");
    }
    {
        tinygltf::Model model = makeClip();
        model.skins[0].joints = {1, 9};
        expectRefused(model, "joint_node_out_of_range", "joint node 9 that does not exist");
    }
    // A triangle index past the primitive's vertices.
    {
        tinygltf::Model model = makeClip();
        const auto& a = model.accessors[kStripIndices];
        const std::uint16_t six = 6;
        std::memcpy(model.buffers[0].data.data() +
                        model.bufferViews[std::size_t(a.bufferView)].byteOffset + 2 * 4,
                    &six, 2);
        expectRefused(model, "index_out_of_range", "index 4 is 6, outside [0, 6)");
    }
}

TEST(AnimatedMesh, BadGltfWeightsKeysAndPrimitivesAreRefused) {
    // Weights: a negative one, or none for a vertex.
    {
        tinygltf::Model model = makeClip();
        floatAt(model, kStripWeights, 4, 1) = -0.5f;
        expectRefused(model, "negative_weight", "vertex 4 has a negative weight -0.5");
    }
    {
        tinygltf::Model model = makeClip();
        floatAt(model, kStripWeights, 3, 0) = 0.0f;
        expectRefused(model, "zero_weights", "vertex 3's joint weights sum to 0");
    }
    // NaN and infinity in key times, key values and inverse bind matrices; times going back.
    {
        tinygltf::Model model = makeClip();
        floatAt(model, kTimes01, 1) = std::nanf("");
        expectRefused(model, "nan_time", "non-finite");
    }
    {
        tinygltf::Model model = makeClip();
        floatAt(model, kTimes01, 1) = INFINITY;
        expectRefused(model, "inf_time", "non-finite");
    }
    {
        tinygltf::Model model = makeClip();
        floatAt(model, kRotationValues, 1, 2) = std::nanf("");
        expectRefused(model, "nan_value", "non-finite");
    }
    {
        tinygltf::Model model = makeClip();
        floatAt(model, kRotationValues, 0, 3) = -INFINITY;
        expectRefused(model, "inf_value", "non-finite");
    }
    {
        tinygltf::Model model = makeClip();
        floatAt(model, kInverseBind, 1, 12) = std::nanf("");
        expectRefused(model, "nan_inverse_bind", "inverse bind matrices: accessor 6 holds a non");
    }
    {
        tinygltf::Model model = makeClip();
        floatAt(model, kTimes01, 0) = 2.0f;
        expectRefused(model, "times_back", "its key times are not ascending");
    }
    // Only points and lines: nothing to grow on.
    {
        tinygltf::Model model = makeClip();
        model.meshes[0].primitives[0].mode = TINYGLTF_MODE_LINE;
        model.meshes[1].primitives[0].mode = TINYGLTF_MODE_POINTS;
        expectRefused(model, "lines_points", "only point or line primitives (2), no triangles");
    }
}

TEST(AnimatedMesh, GltfLinesAreSkippedStripsUnrolledAndWeightsNormalised) {
    tinygltf::TinyGLTF writer;
    // Lines beside triangles are skipped; the triangles load.
    {
        tinygltf::Model model = makeClip();
        model.meshes[1].primitives[0].mode = TINYGLTF_MODE_LINE_STRIP;
        const std::string file = tmp("with_lines.glb");
        ASSERT_TRUE(writer.WriteGltfSceneToFile(&model, file, false, true, false, true));
        const AnimatedMesh a = AnimatedMesh::loadGltf(file);
        EXPECT_EQ(a.rest().positions.size(), 6u);
        EXPECT_EQ(a.rest().triangles.size(), 4u);
    }
    // The flap as a strip of four vertices (two triangles) and as a fan: both unrolled, facing
    // +z as the list would.
    for (const int mode : {TINYGLTF_MODE_TRIANGLE_STRIP, TINYGLTF_MODE_TRIANGLE_FAN}) {
        Builder b;
        const std::vector<float> square = {0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0};
        tinygltf::Primitive prim;
        prim.mode = mode;
        prim.attributes["POSITION"] = b.floats(square, TINYGLTF_TYPE_VEC3, 3);
        const std::vector<std::uint16_t> indices = mode == TINYGLTF_MODE_TRIANGLE_STRIP
                                                       ? std::vector<std::uint16_t>{0, 1, 2, 3}
                                                       : std::vector<std::uint16_t>{0, 1, 3, 2};
        prim.indices = b.add(indices.data(), 8, 4, TINYGLTF_TYPE_SCALAR,
                             TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT);
        tinygltf::Mesh m;
        m.primitives.push_back(prim);
        b.model.meshes.push_back(m);
        tinygltf::Node node;
        node.mesh = 0;
        b.model.nodes.push_back(node);
        const std::string file = tmp("strip_" + std::to_string(mode) + ".glb");
        ASSERT_TRUE(writer.WriteGltfSceneToFile(&b.model, file, false, true, false, true));
        const AnimatedMesh a = AnimatedMesh::loadGltf(file);
        ASSERT_EQ(a.rest().triangles.size(), 2u) << mode;
        for (const glm::vec3& n : a.rest().normals)
            expectNear(n, glm::vec3(0, 0, 1), "a strip's or fan's normal");
        EXPECT_NEAR(a.rest().surfaceArea(), 1.0, 1e-6);
    }
    // Weights that do not sum to 1 are normalised: the blended vertex (1, 1) goes to (1, 1) on
    // the root and (0, 0) on the turned joint, so weights a (root) and b (joint) put it at
    // a / (a + b) x (1, 1); JOINTS_1/WEIGHTS_1 add to JOINTS_0/WEIGHTS_0's sum.
    struct Case {
        float root, joint, jointInSet1, expect;
    };
    for (const Case& c : {Case{0.2f, 0.2f, 0.0f, 0.5f}, Case{0.3f, 0.1f, 0.0f, 0.75f},
                          Case{3.0f, 0.0f, 3.0f, 0.5f}, Case{2.0f, 0.0f, 6.0f, 0.25f}}) {
        tinygltf::Model model = makeClip();
        floatAt(model, kStripWeights, 4, 0) = c.root;
        floatAt(model, kStripWeights, 4, 1) = c.joint;
        std::vector<std::uint8_t> joints1(24, 0);
        joints1[4 * 4] = 1;
        std::vector<float> weights1(24, 0.0f);
        weights1[4 * 4] = c.jointInSet1;
        auto& buffer = model.buffers[0].data;
        const auto append = [&](const void* data, std::size_t bytes, int type, int component) {
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
            a.count = 6;
            a.type = type;
            a.componentType = component;
            model.accessors.push_back(a);
            return int(model.accessors.size()) - 1;
        };
        if (c.jointInSet1 > 0.0f) {
            model.meshes[0].primitives[0].attributes["JOINTS_1"] = append(
                joints1.data(), 24, TINYGLTF_TYPE_VEC4, TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE);
            model.meshes[0].primitives[0].attributes["WEIGHTS_1"] =
                append(weights1.data(), 96, TINYGLTF_TYPE_VEC4, TINYGLTF_COMPONENT_TYPE_FLOAT);
        }
        const std::string file = tmp("unnormalised.glb");
        ASSERT_TRUE(writer.WriteGltfSceneToFile(&model, file, false, true, false, true));
        const AnimatedMesh a = AnimatedMesh::loadGltf(file);
        SCOPED_TRACE(testing::Message()
                     << "weights " << c.root << ", " << c.joint << ", " << c.jointInSet1);
        expectNear(a.rest().positions[4], glm::vec3(1, 1, 0), "rest");
        expectNear(a.posePositions(1.0)[4], glm::vec3(c.expect, c.expect, 0), "posed");
    }
}

TEST(AnimatedMesh, MeshCacheGapsAndPatternsThatMatchNothingAreRefused) {
    for (int f = 0; f < 10; ++f)
        std::remove(tmp("gap." + std::to_string(f) + ".obj").c_str());
    for (const int f : {1, 2, 4, 5})
        std::ofstream(tmp("gap." + std::to_string(f) + ".obj"))
            << "v 0 0 0\nv 1 0 0\nv 0 1 " << f << "\nf 1 2 3\n";
    try {
        AnimatedMesh::loadCache(tmp("gap.%d.obj"), 24.0);
        ADD_FAILURE() << "a cache with a gap was read";
    } catch (const spot::InputError& e) {
        EXPECT_NE(std::string(e.what()).find(tmp("gap.3.obj") + ": missing"), std::string::npos)
            << e.what();
    }
    // From frame 4 on, there is no gap.
    EXPECT_EQ(AnimatedMesh::loadCache(tmp("gap.%d.obj"), 24.0, 4).frameCount(), 2u);
    EXPECT_THROW(AnimatedMesh::loadCache(tmp("gap.%d.obj"), 24.0, 3), spot::InputError);
    EXPECT_THROW(AnimatedMesh::loadCache(tmp("nothing.%04d.obj"), 24.0), spot::InputError);
    EXPECT_THROW(AnimatedMesh::loadCache(tmp("gap.%s.obj"), 24.0), spot::InputError);
    EXPECT_THROW(AnimatedMesh::loadCache(tmp("gap.%d.%d.obj"), 24.0), spot::InputError);
    // %04d names its frames with four digits: gap.0001.obj is not frame 1 of gap.%d.obj.
    std::ofstream(tmp("pad.0001.obj")) << "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
    EXPECT_THROW(AnimatedMesh::loadCache(tmp("pad.%d.obj"), 24.0), spot::InputError);
    EXPECT_EQ(AnimatedMesh::loadCache(tmp("pad.%04d.obj"), 24.0).frameCount(), 1u);
}

TEST(AnimatedMesh, MeshCacheFrameMayCollapseATriangle) {
    // A quad whose corner 4 moves onto the line through corners 2 and 3 in frame 1 (its second
    // triangle has no area there: loading that frame alone drops it) and back in frame 2: the
    // same topology.
    for (int f = 0; f < 5; ++f)
        std::remove(tmp("pinch." + std::to_string(f) + ".obj").c_str());
    const char* corner4[] = {"1 1 0", "2 -1 0", "1 1 0"};
    for (int f = 0; f < 3; ++f)
        std::ofstream(tmp("pinch." + std::to_string(f) + ".obj"))
            << "v 0 0 0\nv 1 0 0\nv 0 1 0\nv " << corner4[f] << "\nf 1 2 3\nf 2 4 3\n";
    ASSERT_EQ(spot::noise::loadMesh(tmp("pinch.1.obj")).triangles.size(), 1u);
    const AnimatedMesh a = AnimatedMesh::loadCache(tmp("pinch.%d.obj"), 24.0);
    EXPECT_EQ(a.frameCount(), 3u);
    EXPECT_EQ(a.rest().triangles.size(), 2u);
    const spot::noise::Mesh pinched = a.pose(1.0 / 24.0); // never a NaN
    EXPECT_EQ(pinched.triangles.size(), 2u);
    for (const glm::vec3& n : pinched.normals)
        EXPECT_TRUE(std::isfinite(n.x) && std::isfinite(n.y) && std::isfinite(n.z));
    // A frame that changes a triangle is still refused.
    std::ofstream(tmp("pinch.3.obj")) << "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 3\nf 2 3 4\n";
    EXPECT_THROW(AnimatedMesh::loadCache(tmp("pinch.%d.obj"), 24.0), spot::InputError);
}

TEST(AnimatedMesh, InfoRefusesABadFileWithOneLine) {
    tinygltf::Model model = makeClip();
    floatAt(model, kStripWeights, 4, 1) = -0.5f;
    tinygltf::TinyGLTF writer;
    const std::string file = tmp("info_bad.glb");
    ASSERT_TRUE(writer.WriteGltfSceneToFile(&model, file, false, true, false, true));
    const auto r = spot::test::runSpotshell("info --mesh " + file);
    EXPECT_EQ(r.code, 2);
    EXPECT_TRUE(r.out.empty()) << r.out;
    ASSERT_FALSE(r.err.empty());
    EXPECT_EQ(r.err.find('\n'), r.err.size() - 1) << r.err; // one line
    EXPECT_NE(r.err.find("negative weight"), std::string::npos) << r.err;
}

namespace {

constexpr int kTubeRings = 9, kTubeSegments = 12; // rings at x = 0, 0.25, .., 2

/// A tube of radius `r` along +x from 0 to 2, skinned to two joints: the root at the origin and
/// its child at x = 1. Rings before x = 1 are on the root only, rings after it on the child only,
/// the ring at x = 1 half on each. Clip "bend": the child turns by `theta` about z from t = 0 to
/// t = 1 (LINEAR).
tinygltf::Model makeTube(float r, float theta) {
    Builder b;
    std::vector<float> positions, weights;
    std::vector<std::uint8_t> joints;
    for (int i = 0; i < kTubeRings; ++i) {
        const float x = 0.25f * float(i);
        for (int j = 0; j < kTubeSegments; ++j) {
            const float phi = 2.0f * float(M_PI) * float(j) / kTubeSegments;
            positions.insert(positions.end(), {x, r * std::cos(phi), r * std::sin(phi)});
            const float child = x < 1.0f ? 0.0f : x > 1.0f ? 1.0f : 0.5f;
            joints.insert(joints.end(), {0, 1, 0, 0});
            weights.insert(weights.end(), {1.0f - child, child, 0, 0});
        }
    }
    std::vector<std::uint16_t> indices;
    for (int i = 0; i + 1 < kTubeRings; ++i)
        for (int j = 0; j < kTubeSegments; ++j) {
            const auto at = [](int ring, int seg) {
                return std::uint16_t(ring * kTubeSegments + seg % kTubeSegments);
            };
            indices.insert(indices.end(), {at(i, j), at(i, j + 1), at(i + 1, j + 1), at(i, j),
                                           at(i + 1, j + 1), at(i + 1, j)});
        }
    tinygltf::Primitive prim;
    prim.mode = TINYGLTF_MODE_TRIANGLES;
    prim.attributes["POSITION"] = b.floats(positions, TINYGLTF_TYPE_VEC3, 3);
    prim.attributes["JOINTS_0"] = b.add(joints.data(), joints.size(), joints.size() / 4,
                                        TINYGLTF_TYPE_VEC4, TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE);
    prim.attributes["WEIGHTS_0"] = b.floats(weights, TINYGLTF_TYPE_VEC4, 4);
    prim.indices = b.add(indices.data(), indices.size() * 2, indices.size(), TINYGLTF_TYPE_SCALAR,
                         TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT);
    tinygltf::Mesh mesh;
    mesh.primitives.push_back(prim);
    b.model.meshes.push_back(mesh);
    tinygltf::Node tube, root, child;
    tube.mesh = 0;
    tube.skin = 0;
    root.children = {2};
    child.translation = {1, 0, 0};
    b.model.nodes = {tube, root, child};
    tinygltf::Skin skin;
    skin.joints = {1, 2};
    skin.inverseBindMatrices = b.floats({1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0,  0, 0, 1,
                                         1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, -1, 0, 0, 1},
                                        TINYGLTF_TYPE_MAT4, 16);
    b.model.skins.push_back(skin);
    tinygltf::Scene scene;
    scene.nodes = {0, 1};
    b.model.scenes.push_back(scene);
    b.model.defaultScene = 0;
    const glm::quat bent = glm::angleAxis(theta, glm::vec3(0, 0, 1));
    tinygltf::Animation clip;
    clip.name = "bend";
    tinygltf::AnimationSampler s;
    s.input = b.floats({0.0f, 1.0f}, TINYGLTF_TYPE_SCALAR, 1);
    s.output = b.floats({0, 0, 0, 1, bent.x, bent.y, bent.z, bent.w}, TINYGLTF_TYPE_VEC4, 4);
    s.interpolation = "LINEAR";
    clip.samplers.push_back(s);
    tinygltf::AnimationChannel c;
    c.sampler = 0;
    c.target_node = 2;
    c.target_path = "rotation";
    clip.channels.push_back(c);
    b.model.animations.push_back(clip);
    return b.model;
}

/// `p` turned by `angle` about the z axis through (1, 0, 0).
glm::vec3 turnAboutJoint(const glm::vec3& p, double angle) {
    const double c = std::cos(angle), s = std::sin(angle);
    const double x = p.x - 1.0, y = p.y;
    return glm::vec3(float(1.0 + c * x - s * y), float(s * x + c * y), p.z);
}

} // namespace

TEST(AnimatedMesh, TwoBoneTubeBendsAsTheClosedForm) {
    tinygltf::TinyGLTF writer;
    const float r = 0.2f;
    for (const double degrees : {30.0, 90.0, 150.0}) {
        const double theta = degrees * M_PI / 180.0;
        const tinygltf::Model model = makeTube(r, float(theta));
        const std::string file = tmp("tube.glb");
        ASSERT_TRUE(writer.WriteGltfSceneToFile(&model, file, false, true, false, true));
        const AnimatedMesh a = AnimatedMesh::loadGltf(file, "bend");
        ASSERT_EQ(a.rest().positions.size(), std::size_t(kTubeRings * kTubeSegments));
        EXPECT_EQ(a.jointCount(), 2u);
        // At t = 1 the full angle; at t = 0.5 half of it (slerp about one axis).
        for (const double t : {1.0, 0.5}) {
            const double angle = theta * t;
            const std::vector<glm::vec3> p = a.posePositions(t);
            int onRoot = 0, onChild = 0, blended = 0;
            for (std::size_t v = 0; v < p.size(); ++v) {
                SCOPED_TRACE(testing::Message()
                             << degrees << " degrees, t " << t << ", vertex " << v);
                const glm::vec3 rest = a.rest().positions[v];
                const glm::vec3 turned = turnAboutJoint(rest, angle);
                if (rest.x < 0.99f) {
                    expectNear(p[v], rest, "on the root: unmoved");
                    ++onRoot;
                } else if (rest.x > 1.01f) {
                    expectNear(p[v], turned, "on the child: turned about the joint");
                    // Still on a tube of radius r about the turned axis.
                    const glm::vec3 axis(std::cos(angle), std::sin(angle), 0.0);
                    const glm::vec3 d = p[v] - glm::vec3(1, 0, 0);
                    EXPECT_NEAR(glm::length(d - glm::dot(d, axis) * axis), r, 1e-5f);
                    ++onChild;
                } else {
                    expectNear(p[v], 0.5f * (rest + turned), "the ring at the joint: the mean");
                    ++blended;
                }
            }
            EXPECT_EQ(onRoot, 4 * kTubeSegments);
            EXPECT_EQ(onChild, 4 * kTubeSegments);
            EXPECT_EQ(blended, kTubeSegments);
        }
    }
}

TEST(AnimatedMesh, MorphTargetAtWeightWIsBasePlusWTimesDelta) {
    tinygltf::TinyGLTF writer;
    const std::vector<float> base = {0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0};
    const std::vector<float> d0 = {0, 0, 1, 0, 0, 0, 0.5f, 0, 0, 0, 0, -2};
    const std::vector<float> d1 = {0, 0.25f, 0, 0, 0, 0, 0, 0, 3, 1, 0, 0};
    const auto expected = [&](std::size_t v, double w0, double w1) {
        return glm::vec3(float(base[3 * v] + w0 * d0[3 * v] + w1 * d1[3 * v]),
                         float(base[3 * v + 1] + w0 * d0[3 * v + 1] + w1 * d1[3 * v + 1]),
                         float(base[3 * v + 2] + w0 * d0[3 * v + 2] + w1 * d1[3 * v + 2]));
    };
    const auto build = [&](const std::vector<double>& weights, bool animate) {
        Builder b;
        tinygltf::Primitive prim;
        prim.mode = TINYGLTF_MODE_TRIANGLES;
        prim.attributes["POSITION"] = b.floats(base, TINYGLTF_TYPE_VEC3, 3);
        const std::vector<std::uint16_t> indices = {0, 1, 3, 0, 3, 2};
        prim.indices = b.add(indices.data(), 12, 6, TINYGLTF_TYPE_SCALAR,
                             TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT);
        prim.targets.push_back({{"POSITION", b.floats(d0, TINYGLTF_TYPE_VEC3, 3)}});
        prim.targets.push_back({{"POSITION", b.floats(d1, TINYGLTF_TYPE_VEC3, 3)}});
        tinygltf::Mesh m;
        m.primitives.push_back(prim);
        m.weights = weights;
        b.model.meshes.push_back(m);
        tinygltf::Node node;
        node.mesh = 0;
        b.model.nodes.push_back(node);
        if (animate) { // weights (0, 1) at t = 0, (1, -0.5) at t = 2, (0.5, 0.5) at t = 3
            tinygltf::Animation clip;
            clip.name = "morph";
            tinygltf::AnimationSampler s;
            s.input = b.floats({0.0f, 2.0f, 3.0f}, TINYGLTF_TYPE_SCALAR, 1);
            s.output = b.floats({0, 1, 1, -0.5f, 0.5f, 0.5f}, TINYGLTF_TYPE_SCALAR, 1);
            s.interpolation = "LINEAR";
            clip.samplers.push_back(s);
            tinygltf::AnimationChannel c;
            c.sampler = 0;
            c.target_node = 0;
            c.target_path = "weights";
            clip.channels.push_back(c);
            b.model.animations.push_back(clip);
        }
        const std::string file = tmp("morph.glb");
        EXPECT_TRUE(writer.WriteGltfSceneToFile(&b.model, file, false, true, false, true));
        return AnimatedMesh::loadGltf(file);
    };
    // The mesh's own weights (no clip): the rest is the base, the pose base + w x delta.
    for (const double w : {0.0, 0.25, 0.5, 1.0, 1.75}) {
        const AnimatedMesh a = build({w, 0.5 * w}, false);
        EXPECT_EQ(a.morphTargetCount(), 2u);
        const std::vector<glm::vec3> p = a.posePositions(0.0);
        for (std::size_t v = 0; v < 4; ++v) {
            SCOPED_TRACE(testing::Message() << "w " << w << ", vertex " << v);
            expectNear(a.rest().positions[v], expected(v, 0, 0), "rest: the base");
            expectNear(p[v], expected(v, w, 0.5 * w), "the mesh's weights");
        }
    }
    // A weights channel, LINEAR between its keys.
    const AnimatedMesh a = build({}, true);
    EXPECT_DOUBLE_EQ(a.duration(), 3.0);
    struct Key {
        double t, w0, w1;
    };
    for (const Key& k : {Key{0.0, 0, 1}, Key{0.5, 0.25, 0.625}, Key{1.0, 0.5, 0.25},
                         Key{2.0, 1, -0.5}, Key{2.4, 0.8, -0.1}, Key{3.0, 0.5, 0.5}}) {
        const std::vector<glm::vec3> p = a.posePositions(k.t);
        for (std::size_t v = 0; v < 4; ++v) {
            SCOPED_TRACE(testing::Message() << "t " << k.t << ", vertex " << v);
            expectNear(p[v], expected(v, k.w0, k.w1), "the clip's weights");
        }
    }
}

TEST(AnimatedMesh, ClipInterpolationAtAndBetweenKeysThroughAFile) {
    // Five nodes each instancing one triangle (0, 0, 0), (1, 0, 0), (0, 1, 0) at the origin, each
    // moved by one sampler over keys at t = 0, 1 and 3 (unequal intervals):
    //   0 translation LINEAR, 1 translation STEP, 2 translation CUBICSPLINE, 3 rotation
    //   CUBICSPLINE, 4 rotation LINEAR (slerp, its second key the negated quaternion).
    Builder b;
    tinygltf::Primitive prim;
    prim.mode = TINYGLTF_MODE_TRIANGLES;
    prim.attributes["POSITION"] = b.floats({0, 0, 0, 1, 0, 0, 0, 1, 0}, TINYGLTF_TYPE_VEC3, 3);
    tinygltf::Mesh m;
    m.primitives.push_back(prim);
    b.model.meshes.push_back(m);
    tinygltf::Scene scene;
    for (int n = 0; n < 5; ++n) {
        tinygltf::Node node;
        node.mesh = 0;
        b.model.nodes.push_back(node);
        scene.nodes.push_back(n);
    }
    b.model.scenes.push_back(scene);
    b.model.defaultScene = 0;
    const std::vector<float> times = {0.0f, 1.0f, 3.0f};
    const int input = b.floats(times, TINYGLTF_TYPE_SCALAR, 1);
    tinygltf::Animation clip;
    clip.name = "keys";
    const auto channel = [&](int node, const char* path, const char* interpolation,
                             const std::vector<float>& values, int type, std::size_t per) {
        tinygltf::AnimationSampler s;
        s.input = input;
        s.output = b.floats(values, type, per);
        s.interpolation = interpolation;
        clip.samplers.push_back(s);
        tinygltf::AnimationChannel c;
        c.sampler = int(clip.samplers.size()) - 1;
        c.target_node = node;
        c.target_path = path;
        clip.channels.push_back(c);
    };
    const std::vector<glm::vec3> keys = {{0, 0, 0}, {2, 0, 0}, {2, 4, -1}};
    std::vector<float> flat;
    for (const glm::vec3& k : keys)
        flat.insert(flat.end(), {k.x, k.y, k.z});
    channel(0, "translation", "LINEAR", flat, TINYGLTF_TYPE_VEC3, 3);
    channel(1, "translation", "STEP", flat, TINYGLTF_TYPE_VEC3, 3);
    // CUBICSPLINE through a cubic f (per component) with its derivative as both tangents: Hermite
    // interpolation reproduces a cubic exactly, whatever the intervals.
    const auto f = [](double t) {
        return glm::dvec3(t * t * t - 2 * t * t + t, 0.5 * t * t - t, 3.0 - 0.25 * t * t * t);
    };
    const auto df = [](double t) {
        return glm::dvec3(3 * t * t - 4 * t + 1, t - 1.0, -0.75 * t * t);
    };
    std::vector<float> spline;
    for (const float t : times) {
        const glm::dvec3 v = f(t), d = df(t);
        spline.insert(spline.end(), {float(d.x), float(d.y), float(d.z), float(v.x), float(v.y),
                                     float(v.z), float(d.x), float(d.y), float(d.z)});
    }
    channel(2, "translation", "CUBICSPLINE", spline, TINYGLTF_TYPE_VEC3, 3);
    // A rotation spline: (0, 0, g(t), h(t)) with g cubic and h the quadratic through the keys'
    // sqrt(1 - g^2) (unit keys, as glTF asks); normalised between them, a turn by
    // 2 atan2(g, h) about z.
    const auto g = [](double t) { return 0.05 * t * t * t - 0.2 * t * t + 0.45 * t; };
    const auto dg = [](double t) { return 0.15 * t * t - 0.4 * t + 0.45; };
    const double h0 = 1.0, h1 = std::sqrt(1.0 - g(1) * g(1)), h3 = std::sqrt(1.0 - g(3) * g(3));
    const auto h = [&](double t) { // Lagrange through (0, h0), (1, h1), (3, h3)
        return h0 * (t - 1) * (t - 3) / 3.0 + h1 * t * (t - 3) / -2.0 + h3 * t * (t - 1) / 6.0;
    };
    const auto dh = [&](double t) {
        return h0 * (2 * t - 4) / 3.0 + h1 * (2 * t - 3) / -2.0 + h3 * (2 * t - 1) / 6.0;
    };
    std::vector<float> rotationSpline;
    for (const float t : times)
        rotationSpline.insert(rotationSpline.end(),
                              {0, 0, float(dg(t)), float(dh(t)), 0, 0, float(g(t)), float(h(t)), 0,
                               0, float(dg(t)), float(dh(t))});
    channel(3, "rotation", "CUBICSPLINE", rotationSpline, TINYGLTF_TYPE_VEC4, 4);
    // Slerp: identity, then 120 degrees about z stored negated (its dot with the first is
    // negative: the short way is 120 degrees, the long 240), then 120 + 60 degrees (stored as is).
    const glm::quat q1 = -glm::angleAxis(float(2 * M_PI / 3), glm::vec3(0, 0, 1));
    const glm::quat q2 = glm::angleAxis(float(M_PI), glm::vec3(0, 0, 1));
    channel(4, "rotation", "LINEAR", {0, 0, 0, 1, q1.x, q1.y, q1.z, q1.w, q2.x, q2.y, q2.z, q2.w},
            TINYGLTF_TYPE_VEC4, 4);
    b.model.animations.push_back(clip);
    tinygltf::TinyGLTF writer;
    const std::string file = tmp("keys.glb");
    ASSERT_TRUE(writer.WriteGltfSceneToFile(&b.model, file, false, true, false, true));
    const AnimatedMesh a = AnimatedMesh::loadGltf(file);
    ASSERT_EQ(a.rest().positions.size(), 15u);
    EXPECT_DOUBLE_EQ(a.duration(), 3.0);
    const auto linear = [&](double t) {
        if (t <= 1.0)
            return glm::mix(keys[0], keys[1], float(t));
        return glm::mix(keys[1], keys[2], float((t - 1.0) / 2.0));
    };
    const auto step = [&](double t) { return t < 1.0 ? keys[0] : t < 3.0 ? keys[1] : keys[2]; };
    // The slerp's angle: 120 degrees over [0, 1], then 60 more over [1, 3].
    const auto slerpAngle = [](double t) {
        return t <= 1.0 ? t * 2 * M_PI / 3 : 2 * M_PI / 3 + (t - 1.0) / 2.0 * M_PI / 3;
    };
    for (const double t : {0.0, 0.25, 0.5, 0.999, 1.0, 1.5, 2.0, 2.75, 3.0}) {
        SCOPED_TRACE(testing::Message() << "t " << t);
        const std::vector<glm::vec3> p = a.posePositions(t);
        expectNear(p[0], linear(t), "LINEAR translation");
        expectNear(p[3], step(t), "STEP translation");
        expectNear(p[6], glm::vec3(f(t)), "CUBICSPLINE translation");
        const double spun = 2.0 * std::atan2(g(t), h(t));
        expectNear(p[10], glm::vec3(float(std::cos(spun)), float(std::sin(spun)), 0),
                   "CUBICSPLINE rotation of (1, 0, 0)");
        const double turned = slerpAngle(t);
        expectNear(p[13], glm::vec3(float(std::cos(turned)), float(std::sin(turned)), 0),
                   "slerp of (1, 0, 0), the short way");
        expectNear(p[14], glm::vec3(float(-std::sin(turned)), float(std::cos(turned)), 0),
                   "slerp of (0, 1, 0), the short way");
    }
}

namespace {

std::string readBytes(const std::filesystem::path& file) {
    std::ifstream in(file, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
}

const std::filesystem::path kExamples =
    std::filesystem::path(SPOT_SOURCE_DIR) / "examples/animated";

} // namespace

TEST(AnimatedExamples, TheScriptWritesTheShippedFilesByteForByte) {
    const std::filesystem::path out = tmp("examples");
    std::filesystem::remove_all(out);
    const std::string cmd = "python3 '" + std::string(SPOT_SOURCE_DIR) +
                            "/scripts/make_animated_examples.py' '" + out.string() + "' >/dev/null";
    ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
    for (const char* name : {"tail.glb", "tuft.glb"}) {
        const std::string made = readBytes(out / name), shipped = readBytes(kExamples / name);
        ASSERT_FALSE(shipped.empty()) << name;
        EXPECT_LT(shipped.size(), 300u * 1024u) << name;
        EXPECT_TRUE(made == shipped) << name << ": the script's (" << made.size()
                                     << " bytes) differs from the shipped file (" << shipped.size()
                                     << " bytes); rerun scripts/make_animated_examples.py";
    }
}

TEST(AnimatedExamples, TheTailSwaysAndLoops) {
    const AnimatedMesh a = AnimatedMesh::loadGltf(kExamples / "tail.glb");
    EXPECT_EQ(a.clipName(), "sway");
    EXPECT_EQ(a.clipNames(), std::vector<std::string>{"sway"});
    EXPECT_EQ(a.jointCount(), 4u);
    EXPECT_EQ(a.morphTargetCount(), 0u);
    EXPECT_DOUBLE_EQ(a.start(), 0.0);
    EXPECT_NEAR(a.duration(), 2.0, 1e-6);
    EXPECT_EQ(a.rest().triangles.size(), 3008u);
    EXPECT_EQ(a.rest().droppedTriangles, 0u);
    EXPECT_TRUE(a.rest().hasUv());
    EXPECT_TRUE(spot::noise::closedOutward(a.rest()));
    const spot::noise::Bounds rest = a.rest().bounds();
    EXPECT_NEAR(rest.lo.y, 0.0f, 1e-6f);
    EXPECT_NEAR(rest.hi.y, 1.5f, 1e-6f);
    // It loops: the last frame is the first; half way, the tip has swung well off the axis.
    const std::vector<glm::vec3> first = a.posePositions(0.0), last = a.posePositions(2.0);
    for (std::size_t v = 0; v < first.size(); ++v)
        expectNear(last[v], first[v], "the clip's ends");
    float swing = 0.0f;
    for (int f = 0; f <= 48; ++f) {
        const spot::noise::Mesh posed = a.pose(f / 24.0);
        const spot::noise::Bounds b = posed.bounds();
        swing = std::max({swing, std::abs(b.lo.x), std::abs(b.hi.x)});
        EXPECT_GT(b.hi.y, 1.0f) << "frame " << f; // it sways, it does not fold
    }
    EXPECT_GT(swing, 0.4f);
}

TEST(AnimatedExamples, TheTuftBendsAndItsGroundStays) {
    const AnimatedMesh a = AnimatedMesh::loadGltf(kExamples / "tuft.glb");
    EXPECT_EQ(a.clipName(), "bend");
    EXPECT_EQ(a.jointCount(), 3u);
    EXPECT_NEAR(a.duration(), 2.0, 1e-6);
    EXPECT_EQ(a.rest().triangles.size(), 3200u);
    EXPECT_TRUE(a.rest().hasUv());
    const std::vector<glm::vec3>& rest = a.rest().positions;
    const std::vector<glm::vec3> gust = a.posePositions(1.0);
    float leanTop = 0.0f;
    for (std::size_t v = 0; v < rest.size(); ++v) {
        if (rest[v].y == 0.0f) // the ground does not move
            expectNear(gust[v], rest[v], "ground");
        if (rest[v].y > 0.445f)
            leanTop = gust[v].x - rest[v].x;
    }
    EXPECT_GT(leanTop, 0.05f) << "the top leans downwind (+x)";
}

TEST(AnimatedExamples, TheScenesLoadWithTheirClips) {
    for (const char* name : {"tail-fur.json", "tuft-grass.json"}) {
        SCOPED_TRACE(name);
        const spot::noise::SceneDesc s = spot::noise::loadScene(kExamples / name);
        const AnimatedMesh a = AnimatedMesh::load(s.mesh, s.animation.clip, s.animation.fps);
        EXPECT_TRUE(a.animated());
        EXPECT_EQ(a.clipName(), s.animation.clip);
        EXPECT_DOUBLE_EQ(s.animation.fps, 24.0);
        EXPECT_TRUE(std::filesystem::exists(s.preset)) << s.preset;
    }
}

// ---- A character as Blender exports it (examples/character/, scripts/make_character.py) -------

namespace {

const std::filesystem::path kCharacter =
    std::filesystem::path(SPOT_SOURCE_DIR) / "examples/character/character.glb";

} // namespace

// Flat shading and uv seams make Blender's exporter split vertices: welded, the body's 278 and
// the stand's 24 vertices are one per position, each copy of a position has one normal, and the
// skins of a position's copies agree (no position is left split).
TEST(Character, SplitVerticesAreWeldedAndTheirSkinsAgree) {
    const AnimatedMesh a = AnimatedMesh::loadGltf(kCharacter);
    const spot::noise::Mesh& m = a.rest();
    ASSERT_EQ(m.positions.size(), 302u);
    const spot::noise::WeldReport& w = m.weldReport;
    EXPECT_TRUE(w.on);
    EXPECT_EQ(w.refused, 0u);
    std::set<std::tuple<float, float, float>> distinct;
    for (const glm::vec3& p : m.positions)
        distinct.insert({p.x, p.y, p.z});
    EXPECT_EQ(w.welded, distinct.size());
    EXPECT_LT(w.welded, m.positions.size() - 60); // many copies
    for (std::uint32_t v = 0; v < m.positions.size(); ++v) {
        EXPECT_EQ(m.positions[v], m.positions[m.weld[v]]);
        EXPECT_EQ(m.normals[v], m.normals[m.weld[v]]);
    }
    // Off: every copy stays, the flat torso's corners keep their faces' normals apart.
    spot::noise::MeshOptions off;
    off.weld.on = false;
    const AnimatedMesh split = AnimatedMesh::loadGltf(kCharacter, "", {}, off);
    EXPECT_TRUE(split.rest().weld.empty());
    std::size_t apart = 0;
    for (std::uint32_t v = 0; v < m.positions.size(); ++v)
        apart += glm::length(split.rest().normals[v] - split.rest().normals[m.weld[v]]) > 0.1f;
    EXPECT_GT(apart, 50u);
}

// The welded copies pose alike at every time of the clip (their skins agree), and the posed
// normals are the welded ones.
TEST(Character, WeldedCopiesMoveTogether) {
    const AnimatedMesh a = AnimatedMesh::loadGltf(kCharacter);
    const spot::noise::Mesh& rest = a.rest();
    for (const double t : {0.0, 0.3, 0.5, 1.0}) {
        const spot::noise::Mesh posed = a.pose(t);
        for (std::uint32_t v = 0; v < rest.positions.size(); ++v) {
            EXPECT_LT(glm::length(posed.positions[v] - posed.positions[rest.weld[v]]), 1e-6f) << t;
            EXPECT_LT(glm::length(posed.normals[v] - posed.normals[rest.weld[v]]), 1e-6f) << t;
        }
    }
}

// Its meshes, nodes, materials and parts, the clip from Blender's frame 1, and "grow".
TEST(Character, PartsMaterialsAndTheClipsFrames) {
    const AnimatedMesh a = AnimatedMesh::loadGltf(kCharacter);
    const spot::noise::Mesh& m = a.rest();
    EXPECT_EQ(a.gltfVersion(), "2.0");
    EXPECT_EQ(a.meshNames(), (std::vector<std::string>{"Stand", "Body"}));
    ASSERT_EQ(m.parts.size(), 2u);
    EXPECT_EQ(m.parts[0].mesh, "Stand");
    EXPECT_EQ(m.parts[1].mesh, "Body");
    EXPECT_EQ(m.parts[0].triangles + m.parts[1].triangles, m.triangles.size());
    EXPECT_TRUE(m.parts[0].grows && m.parts[1].grows);
    ASSERT_EQ(m.materials.size(), 2u);
    EXPECT_EQ(m.materials[0].name, "Wood");
    EXPECT_FALSE(m.materials[0].hasTexture());
    EXPECT_NEAR(m.materials[0].baseColorFactor.r, 0.5f, 1e-6f);
    EXPECT_EQ(m.materials[1].name, "Fur");
    ASSERT_TRUE(m.materials[1].textureBytes);
    EXPECT_EQ(m.materials[1].textureMime, "image/png");
    EXPECT_EQ(m.parts[1].material, 1);
    // The stand has no uv: with every part growing, the mesh has none; with the body alone, it
    // has the body's.
    EXPECT_FALSE(m.hasUv());
    spot::noise::MeshOptions body;
    body.grow.meshes = {{"Bo*", -1}};
    const AnimatedMesh b = AnimatedMesh::loadGltf(kCharacter, "", {}, body);
    EXPECT_TRUE(b.rest().hasUv());
    EXPECT_FALSE(b.rest().parts[0].grows);
    EXPECT_TRUE(b.rest().parts[1].grows);
    for (std::size_t t = 0; t < b.rest().triangles.size(); ++t)
        EXPECT_EQ(b.rest().grows(t), b.rest().trianglePart[t] == 1u);
    // The same by node (the body is under the armature's node "rig"), by index, and excluded.
    for (const auto& grow : {spot::noise::GrowSelection{{}, {{"rig", -1}}, {}, {}},
                             spot::noise::GrowSelection{{{"", 1}}, {}, {}, {}},
                             spot::noise::GrowSelection{{}, {}, {{"Stand", -1}}, {}}}) {
        spot::noise::MeshOptions o;
        o.grow = grow;
        const AnimatedMesh c = AnimatedMesh::loadGltf(kCharacter, "", {}, o);
        EXPECT_FALSE(c.rest().parts[0].grows);
        EXPECT_TRUE(c.rest().parts[1].grows);
    }
    // A name that matches nothing, or a choice that leaves nothing, is one line naming them.
    spot::noise::MeshOptions typo;
    typo.grow.meshes = {{"Boddy", -1}};
    try {
        AnimatedMesh::loadGltf(kCharacter, "", {}, typo);
        ADD_FAILURE() << "a name that matches nothing was taken";
    } catch (const spot::InputError& e) {
        EXPECT_NE(std::string(e.what()).find("grow.meshes names 'Boddy', which is none of its "
                                             "meshes (0 'Stand', 1 'Body')"),
                  std::string::npos)
            << e.what();
    }
    spot::noise::MeshOptions none;
    none.grow.excludeNodes = {{"*", -1}};
    EXPECT_THROW(AnimatedMesh::loadGltf(kCharacter, "", {}, none), spot::InputError);
    // The clip: Blender's frames 1 to 25 at 24 fps, from 1/24 s.
    EXPECT_EQ(a.clipName(), "walk");
    EXPECT_NEAR(a.start(), 1.0 / 24.0, 1e-6);
    const spot::noise::FrameRange frames = spot::noise::clipFrames(a, 24.0);
    EXPECT_EQ(frames.first, 1);
    EXPECT_EQ(frames.last, 25);
}

// A material whose texture is a file beside the glTF (an external uri, %-escaped): its path is
// kept, and the material field reads it through the uv.
TEST(AnimatedMesh, AnExternalTextureIsReadBesideTheFile) {
    Builder b;
    spot::noise::Mesh tri;
    tri.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    tri.uvs = {{0, 0}, {1, 0}, {0, 1}};
    tri.triangles = {{0, 1, 2}};
    const int mesh = b.meshPrimitive(tri);
    b.model.meshes[std::size_t(mesh)].primitives[0].material = 0;
    tinygltf::Node node;
    node.mesh = mesh;
    b.model.nodes.push_back(node);
    tinygltf::Scene scene;
    scene.nodes = {0};
    b.model.scenes.push_back(scene);
    b.model.defaultScene = 0;
    tinygltf::Image image;
    image.uri = "anim%20tex.png";
    b.model.images.push_back(image);
    tinygltf::Texture texture;
    texture.source = 0;
    b.model.textures.push_back(texture);
    tinygltf::Material material;
    material.name = "Skin";
    material.pbrMetallicRoughness.baseColorTexture.index = 0;
    material.pbrMetallicRoughness.baseColorFactor = {0.5, 1.0, 1.0, 1.0};
    b.model.materials.push_back(material);
    spot::noise::Image red(2, 2, glm::vec3(1.0f, 0.0f, 0.0f));
    const std::filesystem::path dir(SPOT_TEST_TMP_DIR);
    spot::noise::writeImage(dir / "anim tex.png", red);
    const std::string file = b.write(tmp("external.glb"));
    const AnimatedMesh a = AnimatedMesh::loadGltf(file);
    ASSERT_EQ(a.rest().materials.size(), 1u);
    const spot::noise::MeshMaterial& m = a.rest().materials[0];
    EXPECT_EQ(m.textureFile, dir / "anim tex.png");
    EXPECT_FALSE(m.textureBytes);
    spot::noise::FieldDesc d;
    d.kind = spot::noise::FieldDesc::Kind::Material;
    d.components = 3;
    d.hi = glm::vec3(1.0f);
    const auto field = spot::noise::makeField(d, a.rest(), {}, "fields.color");
    spot::noise::SurfacePoint p;
    p.uv = {0.25f, 0.25f};
    EXPECT_EQ(field->eval(p), glm::vec3(0.5f, 0.0f, 0.0f));
}

// A glTF 1.0 file is refused with a message that names its version, not as a corrupt file.
TEST(AnimatedMesh, AGltfOneFileIsRefusedByItsVersion) {
    const std::string text = tmp("old.gltf");
    std::ofstream(text) << R"({"asset": {"version": "1.0"}, "meshes": {"m": {"primitives": []}},)"
                           R"( "scene": "s", "scenes": {"s": {"nodes": []}}})";
    const std::string binary = tmp("old.glb");
    {
        std::ofstream out(binary, std::ios::binary);
        const std::string json = R"({"asset":{"version":"1.0"}})";
        const std::uint32_t header[5] = {0x46546C67u, 1u, 20u + std::uint32_t(json.size()),
                                         std::uint32_t(json.size()), 0u};
        out.write(reinterpret_cast<const char*>(header), sizeof(header));
        out << json;
    }
    for (const std::string& file : {text, binary}) {
        try {
            AnimatedMesh::loadGltf(file);
            ADD_FAILURE() << file << " was loaded";
        } catch (const spot::InputError& e) {
            const std::string what = e.what();
            EXPECT_NE(what.find("a glTF 1.0 file; spotshell reads glTF 2.0"), std::string::npos)
                << what;
            EXPECT_EQ(what.find('\n'), std::string::npos) << what;
        }
    }
}

// A mesh cache whose split copies part in one frame: those stay apart (the rest's weld is
// checked against every frame), and every frame's welded copies take the kept vertex's place.
TEST(AnimatedMesh, MeshCacheWeldsOnlyCopiesThatStayTogether) {
    const auto frame = [&](int i, float apart) {
        std::ofstream(tmp(spot::cat("weld.", i, ".obj")))
            << "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 0 0\nv 1 1 0\nv 0 1 " << apart << "\n"
            << "f 1 2 3\nf 4 5 6\n";
    };
    frame(0, 0.0f);
    frame(1, 0.0f);
    frame(2, 0.5f); // vertex 6 leaves vertex 3
    const AnimatedMesh a = AnimatedMesh::loadCache(tmp("weld.%d.obj"), 24.0);
    const spot::noise::Mesh& m = a.rest();
    EXPECT_EQ(m.weld[3], 1u); // 4 and 2 stay together
    EXPECT_EQ(m.weld[5], 5u); // 6 parts from 3 in frame 2
    EXPECT_EQ(m.weldReport.refused, 1u);
}
