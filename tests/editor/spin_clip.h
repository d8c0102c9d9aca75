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

#include "noise/gltf_clips.h" // tinygltf, built as the library is, and GltfBuilder

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
    noise::Mesh sphereMesh;
    for (std::size_t i = 0; i < positions.size(); i += 3)
        sphereMesh.positions.emplace_back(positions[i], positions[i + 1], positions[i + 2]);
    for (std::size_t i = 0; i < indices.size(); i += 3)
        sphereMesh.triangles.emplace_back(indices[i], indices[i + 1], indices[i + 2]);
    GltfBuilder b;
    tinygltf::Node node;
    node.name = "root";
    node.mesh = b.meshPrimitive(sphereMesh);
    b.model.meshes[0].name = "sphere";
    tinygltf::Accessor& bounds =
        b.model.accessors[std::size_t(b.model.meshes[0].primitives[0].attributes["POSITION"])];
    bounds.minValues = {-0.5, -0.5, -0.5};
    bounds.maxValues = {0.5, 0.5, 0.5};
    b.model.nodes.push_back(node);
    tinygltf::Scene scene;
    scene.nodes = {0};
    b.model.scenes.push_back(scene);
    b.model.defaultScene = 0;
    const glm::quat end = glm::angleAxis(float(M_PI / 2), glm::normalize(axis));
    tinygltf::Animation clip;
    clip.name = "spin";
    b.sampler(clip, {0.0f, 2.0f}, {0, 0, 0, 1, end.x, end.y, end.z, end.w}, TINYGLTF_TYPE_VEC4, 4,
              0, "rotation");
    b.sampler(clip, {0.0f, 2.0f}, {0, 0, 0, 1.5f, 0, 0}, TINYGLTF_TYPE_VEC3, 3, 0, "translation");
    b.model.animations.push_back(clip);
    const std::filesystem::path glb = dir / "spin.glb";
    tinygltf::TinyGLTF writer;
    if (!writer.WriteGltfSceneToFile(&b.model, glb.string(), false, true, false, true))
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
