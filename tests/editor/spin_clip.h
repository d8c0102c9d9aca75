// A rigid glTF clip for the editor's tests, written by the test itself (tinygltf): a uv sphere of
// radius 0.5 at the origin that, from t = 0 to 2 s, turns 90 degrees about an axis (+y unless
// given) and moves 1.5 along +x (LINEAR), so that at t = 2 every point is far (more than a
// diameter) from where it rests; and a scene that sees both places, with the fur preset.
#pragma once

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

// The library is built without image support (noise/animated_mesh.cpp): the same switches.
#define TINYGLTF_NO_STB_IMAGE
#define TINYGLTF_NO_STB_IMAGE_WRITE
#define TINYGLTF_NO_EXTERNAL_IMAGE
#include <tiny_gltf.h>

#include <glm/glm.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>

namespace spot::test {

/// The clip's motion at time t in [0, 2]: the sphere's rigid transform, world from rest.
inline glm::mat4 spinTransform(double t, glm::vec3 axis = {0, 1, 0}) {
    const float u = float(std::clamp(t, 0.0, 2.0) / 2.0);
    const glm::quat turn = glm::angleAxis(u * float(M_PI / 2), glm::normalize(axis));
    return glm::translate(glm::mat4(1.0f), glm::vec3(1.5f * u, 0, 0)) * glm::mat4_cast(turn);
}

/// Write `dir`/spin.glb and `dir`/spin.json (the scene: 256x256, fps 24) and return the scene.
inline std::filesystem::path writeSpinClip(const std::filesystem::path& dir,
                                           glm::vec3 axis = {0, 1, 0}) {
    std::filesystem::create_directories(dir);
    std::vector<float> positions;
    std::vector<std::uint32_t> indices;
    const int rings = 24, segments = 48;
    for (int i = 0; i <= rings; ++i)
        for (int j = 0; j <= segments; ++j) {
            const double th = M_PI * i / rings, ph = 2.0 * M_PI * j / segments;
            positions.push_back(float(0.5 * std::sin(th) * std::cos(ph)));
            positions.push_back(float(0.5 * std::cos(th)));
            positions.push_back(float(0.5 * std::sin(th) * std::sin(ph)));
        }
    for (int i = 0; i < rings; ++i)
        for (int j = 0; j < segments; ++j) {
            const std::uint32_t a = std::uint32_t(i * (segments + 1) + j), b = a + segments + 1;
            indices.insert(indices.end(), {a, a + 1, b, a + 1, b + 1, b});
        }
    tinygltf::Model model;
    model.asset.version = "2.0";
    model.buffers.emplace_back();
    const auto add = [&](const void* data, std::size_t bytes, std::size_t count, int type,
                         int component, std::vector<double> lo = {}, std::vector<double> hi = {}) {
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
        a.minValues = std::move(lo);
        a.maxValues = std::move(hi);
        model.accessors.push_back(a);
        return int(model.accessors.size()) - 1;
    };
    tinygltf::Primitive sphere;
    sphere.mode = TINYGLTF_MODE_TRIANGLES;
    sphere.attributes["POSITION"] =
        add(positions.data(), positions.size() * 4, positions.size() / 3, TINYGLTF_TYPE_VEC3,
            TINYGLTF_COMPONENT_TYPE_FLOAT, {-0.5, -0.5, -0.5}, {0.5, 0.5, 0.5});
    sphere.indices = add(indices.data(), indices.size() * 4, indices.size(), TINYGLTF_TYPE_SCALAR,
                         TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT);
    tinygltf::Mesh mesh;
    mesh.name = "sphere";
    mesh.primitives.push_back(sphere);
    model.meshes.push_back(mesh);
    tinygltf::Node node;
    node.name = "root";
    node.mesh = 0;
    model.nodes.push_back(node);
    tinygltf::Scene scene;
    scene.nodes = {0};
    model.scenes.push_back(scene);
    model.defaultScene = 0;

    const std::vector<float> times = {0.0f, 2.0f};
    const glm::quat end = glm::angleAxis(float(M_PI / 2), glm::normalize(axis));
    const std::vector<float> rotations = {0, 0, 0, 1, end.x, end.y, end.z, end.w};
    const std::vector<float> translations = {0, 0, 0, 1.5f, 0, 0};
    const int input = add(times.data(), times.size() * 4, times.size(), TINYGLTF_TYPE_SCALAR,
                          TINYGLTF_COMPONENT_TYPE_FLOAT, {0.0}, {2.0});
    tinygltf::Animation clip;
    clip.name = "spin";
    const auto channel = [&](const std::vector<float>& values, int type, int width,
                             const char* path) {
        tinygltf::AnimationSampler s;
        s.input = input;
        s.output = add(values.data(), values.size() * 4, values.size() / std::size_t(width), type,
                       TINYGLTF_COMPONENT_TYPE_FLOAT);
        s.interpolation = "LINEAR";
        clip.samplers.push_back(s);
        tinygltf::AnimationChannel c;
        c.sampler = int(clip.samplers.size()) - 1;
        c.target_node = 0;
        c.target_path = path;
        clip.channels.push_back(c);
    };
    channel(rotations, TINYGLTF_TYPE_VEC4, 4, "rotation");
    channel(translations, TINYGLTF_TYPE_VEC3, 3, "translation");
    model.animations.push_back(clip);

    const std::filesystem::path glb = dir / "spin.glb";
    tinygltf::TinyGLTF writer;
    if (!writer.WriteGltfSceneToFile(&model, glb.string(), false, true, false, true))
        return {};
    const std::filesystem::path sceneFile = dir / "spin.json";
    std::ofstream(sceneFile)
        << R"({"version": 1, "name": "spin", "mesh": "spin.glb", "preset": ")"
        << (std::filesystem::path(SPOT_SOURCE_DIR) / "presets/fur.json").string()
        << R"(", "seed": 1,
  "camera": {"eye": [0.75, 0.4, 4.2], "target": [0.75, 0.0, 0.0], "up": [0, 1, 0], "fov_deg": 40},
  "image": {"width": 256, "height": 256},
  "background": [0.03, 0.03, 0.04], "base_color": [0.2, 0.2, 0.22],
  "shading": {"mode": "unlit"},
  "animation": {"clip": "spin", "fps": 24}}
)";
    return sceneFile;
}

} // namespace spot::test
