/// @file scene.h
/// @brief Scenes as data (presets/scenes/*.json): a mesh, a preset, a camera, an image size,
/// colours and shading. The schema is documented in presets/README.md ("Scenes").
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>

#include <glm/glm.hpp>

#include "camera.h"
#include "reference.h"

namespace spot::noise {

inline constexpr int kSceneVersion = 1;

struct SceneDesc {
    std::string name;
    std::string mesh;                ///< path (resolved against the scene's folder) or generated:NAME
    std::filesystem::path preset;    ///< resolved against the scene's folder
    std::uint32_t seed = 0;
    Camera camera;                   ///< includes the image size
    glm::vec3 background{0.0f};      ///< linear RGB
    glm::vec3 baseColor{0.5f};       ///< linear RGB of the opaque base mesh
    Shading shading;
    int referenceSpp = 16;
};

/// Parse a scene; `name` is the file (for messages), `baseDir` resolves relative paths.
SceneDesc parseScene(std::string_view json, const std::string& name,
                     const std::filesystem::path& baseDir);
SceneDesc loadScene(const std::filesystem::path& file);

} // namespace spot::noise
