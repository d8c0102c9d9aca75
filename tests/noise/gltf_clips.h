// glTF clips made in the tests (tinygltf): a mesh moved rigidly by its root node, and a tube
// bent by a two-joint skin. Each returns the file it wrote.
#pragma once

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

// The library is built without image support (noise/animated_mesh.cpp): the same switches.
#define TINYGLTF_NO_STB_IMAGE
#define TINYGLTF_NO_STB_IMAGE_WRITE
#define TINYGLTF_NO_EXTERNAL_IMAGE
#include <tiny_gltf.h>

#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

#include "noise/mesh.h"

namespace spot::test {

/// A glTF model's buffer and accessors.
struct GltfBuilder {
    tinygltf::Model model;
    GltfBuilder() {
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
    int meshPrimitive(const noise::Mesh& mesh) {
        std::vector<float> p, uv;
        for (const glm::vec3& x : mesh.positions)
            p.insert(p.end(), {x.x, x.y, x.z});
        std::vector<std::uint32_t> idx;
        for (const glm::uvec3& t : mesh.triangles)
            idx.insert(idx.end(), {t.x, t.y, t.z});
        tinygltf::Primitive prim;
        prim.mode = TINYGLTF_MODE_TRIANGLES;
        prim.attributes["POSITION"] = floats(p, TINYGLTF_TYPE_VEC3, 3);
        if (mesh.hasUv()) {
            for (const glm::vec2& t : mesh.uvs)
                uv.insert(uv.end(), {t.x, 1.0f - t.y});
            prim.attributes["TEXCOORD_0"] = floats(uv, TINYGLTF_TYPE_VEC2, 2);
        }
        prim.indices = add(idx.data(), idx.size() * 4, idx.size(), TINYGLTF_TYPE_SCALAR,
                           TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT);
        tinygltf::Mesh m;
        m.primitives.push_back(prim);
        model.meshes.push_back(m);
        return int(model.meshes.size()) - 1;
    }
    void sampler(tinygltf::Animation& clip, const std::vector<float>& times,
                 const std::vector<float>& values, int type, std::size_t per, int node,
                 const char* path) {
        tinygltf::AnimationSampler s;
        s.input = floats(times, TINYGLTF_TYPE_SCALAR, 1);
        s.output = floats(values, type, per);
        s.interpolation = "LINEAR";
        clip.samplers.push_back(s);
        tinygltf::AnimationChannel c;
        c.sampler = int(clip.samplers.size()) - 1;
        c.target_node = node;
        c.target_path = path;
        clip.channels.push_back(c);
    }
    std::string write(const std::string& file) {
        tinygltf::TinyGLTF writer;
        writer.WriteGltfSceneToFile(&model, file, false, true, false, true);
        return file;
    }
};

/// The root's rigid motion at t of rigidClip: a turn of 0.6 t radians about y, then a
/// translation along (0.3, 0.1, 0.1) t.
inline glm::mat4 rigidMotion(double t) {
    const glm::quat q = glm::angleAxis(float(0.6 * t), glm::vec3(0, 1, 0));
    glm::mat4 m = glm::mat4_cast(q);
    m[3] = glm::vec4(0.3f * float(t), 0.1f * float(t), 0.1f * float(t), 1.0f);
    return m;
}

/// `mesh` on a root node that rigidMotion moves over 2 s (keys every 0.25 s, LINEAR: the
/// rotation is slerped, exact between keys; the translation is linear in t).
inline std::string rigidClip(const noise::Mesh& mesh, const std::string& file) {
    GltfBuilder b;
    tinygltf::Node node;
    node.mesh = b.meshPrimitive(mesh);
    b.model.nodes = {node};
    tinygltf::Scene scene;
    scene.nodes = {0};
    b.model.scenes.push_back(scene);
    b.model.defaultScene = 0;
    tinygltf::Animation clip;
    clip.name = "rigid";
    std::vector<float> times, rotations, translations;
    for (int k = 0; k <= 8; ++k) {
        const double t = 0.25 * k;
        times.push_back(float(t));
        const glm::quat q = glm::angleAxis(float(0.6 * t), glm::vec3(0, 1, 0));
        rotations.insert(rotations.end(), {q.x, q.y, q.z, q.w});
        translations.insert(translations.end(),
                            {0.3f * float(t), 0.1f * float(t), 0.1f * float(t)});
    }
    b.sampler(clip, times, rotations, TINYGLTF_TYPE_VEC4, 4, 0, "rotation");
    b.sampler(clip, times, translations, TINYGLTF_TYPE_VEC3, 3, 0, "translation");
    b.model.animations.push_back(clip);
    return b.write(file);
}

/// A tube of radius 0.25 along x from 0 to 2 (rings every 0.05, 32 around, capped by fans),
/// skinned to two joints: the root at x = 0 and the second at x = 1, the weights blending
/// linearly over x in [0.8, 1.2]. Clip "bend": the second joint turns about z from 0 to `angle`
/// radians over 1 s.
inline std::string bendClip(const std::string& file, float angle = 1.0f) {
    GltfBuilder b;
    const int around = 32, rings = 41;
    std::vector<float> p, w;
    std::vector<std::uint8_t> j;
    std::vector<std::uint32_t> idx;
    const auto vertex = [&](glm::vec3 x) {
        p.insert(p.end(), {x.x, x.y, x.z});
        const float s = std::clamp((x.x - 0.8f) / 0.4f, 0.0f, 1.0f);
        j.insert(j.end(), {0, 1, 0, 0});
        w.insert(w.end(), {1.0f - s, s, 0.0f, 0.0f});
        return std::uint32_t(p.size() / 3 - 1);
    };
    for (int r = 0; r < rings; ++r)
        for (int a = 0; a < around; ++a) {
            const float phi = 2.0f * float(M_PI) * float(a) / float(around);
            vertex(glm::vec3(0.05f * float(r), 0.25f * std::cos(phi), 0.25f * std::sin(phi)));
        }
    for (int r = 0; r + 1 < rings; ++r)
        for (int a = 0; a < around; ++a) {
            const std::uint32_t v0 = std::uint32_t(r * around + a);
            const std::uint32_t v1 = std::uint32_t(r * around + (a + 1) % around);
            idx.insert(idx.end(), {v0, v1 + around, v1, v0, v0 + around, v1 + around});
        }
    const std::uint32_t c0 = vertex(glm::vec3(0.0f)), c1 = vertex(glm::vec3(2.0f, 0.0f, 0.0f));
    for (int a = 0; a < around; ++a) {
        const std::uint32_t v0 = std::uint32_t(a), v1 = std::uint32_t((a + 1) % around);
        idx.insert(idx.end(), {c0, v0, v1});
        const std::uint32_t e = std::uint32_t((rings - 1) * around);
        idx.insert(idx.end(), {c1, e + v1, e + v0});
    }
    tinygltf::Primitive prim;
    prim.mode = TINYGLTF_MODE_TRIANGLES;
    prim.attributes["POSITION"] = b.floats(p, TINYGLTF_TYPE_VEC3, 3);
    prim.attributes["JOINTS_0"] = b.add(j.data(), j.size(), j.size() / 4, TINYGLTF_TYPE_VEC4,
                                        TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE);
    prim.attributes["WEIGHTS_0"] = b.floats(w, TINYGLTF_TYPE_VEC4, 4);
    prim.indices = b.add(idx.data(), idx.size() * 4, idx.size(), TINYGLTF_TYPE_SCALAR,
                         TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT);
    tinygltf::Mesh mesh;
    mesh.primitives.push_back(prim);
    b.model.meshes.push_back(mesh);
    tinygltf::Node tube, root, second;
    tube.mesh = 0;
    tube.skin = 0;
    root.children = {2};
    second.translation = {1, 0, 0};
    b.model.nodes = {tube, root, second};
    const std::vector<float> inverseBind = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0,  0, 0, 1,
                                            1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, -1, 0, 0, 1};
    tinygltf::Skin skin;
    skin.joints = {1, 2};
    skin.inverseBindMatrices = b.floats(inverseBind, TINYGLTF_TYPE_MAT4, 16);
    b.model.skins.push_back(skin);
    tinygltf::Scene scene;
    scene.nodes = {0, 1};
    b.model.scenes.push_back(scene);
    b.model.defaultScene = 0;
    tinygltf::Animation clip;
    clip.name = "bend";
    const glm::quat q = glm::angleAxis(angle, glm::vec3(0, 0, 1));
    b.sampler(clip, {0.0f, 1.0f}, {0, 0, 0, 1, q.x, q.y, q.z, q.w}, TINYGLTF_TYPE_VEC4, 4, 2,
              "rotation");
    b.model.animations.push_back(clip);
    return b.write(file);
}

/// `mesh` with one morph target, a bump along y (0.3 (1 - r^2) over the unit disc about the
/// y axis), its weight animated from 0 to 1 over 1 s (LINEAR).
inline std::string morphClip(const noise::Mesh& mesh, const std::string& file) {
    GltfBuilder b;
    tinygltf::Node node;
    node.mesh = b.meshPrimitive(mesh);
    std::vector<float> bump;
    for (const glm::vec3& p : mesh.positions) {
        const float r2 = p.x * p.x + p.z * p.z;
        bump.insert(bump.end(), {0.0f, r2 < 1.0f ? 0.3f * (1.0f - r2) : 0.0f, 0.0f});
    }
    b.model.meshes[0].primitives[0].targets.push_back(
        {{"POSITION", b.floats(bump, TINYGLTF_TYPE_VEC3, 3)}});
    b.model.meshes[0].weights = {0.0};
    b.model.nodes = {node};
    tinygltf::Scene scene;
    scene.nodes = {0};
    b.model.scenes.push_back(scene);
    b.model.defaultScene = 0;
    tinygltf::Animation clip;
    clip.name = "bump";
    b.sampler(clip, {0.0f, 1.0f}, {0.0f, 1.0f}, TINYGLTF_TYPE_SCALAR, 1, 0, "weights");
    b.model.animations.push_back(clip);
    return b.write(file);
}

/// `mesh` on a node whose scale along z goes from 1 to 0 over 1 s: a plane in xz collapses onto
/// a line at t = 1.
inline std::string squashClip(const noise::Mesh& mesh, const std::string& file) {
    GltfBuilder b;
    tinygltf::Node node;
    node.mesh = b.meshPrimitive(mesh);
    b.model.nodes = {node};
    tinygltf::Scene scene;
    scene.nodes = {0};
    b.model.scenes.push_back(scene);
    b.model.defaultScene = 0;
    tinygltf::Animation clip;
    clip.name = "squash";
    b.sampler(clip, {0.0f, 0.5f, 1.0f}, {1, 1, 1, 1, 1, 0.5f, 1, 1, 0}, TINYGLTF_TYPE_VEC3, 3, 0,
              "scale");
    b.model.animations.push_back(clip);
    return b.write(file);
}

} // namespace spot::test
