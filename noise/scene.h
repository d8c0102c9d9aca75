/// @file scene.h
/// @brief Scenes as data (presets/scenes/*.json): a mesh, a preset, a camera, an image size,
/// colours and shading. The schema is documented in presets/README.md ("Scenes").
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include <glm/glm.hpp>

#include "camera.h"
#include "deform.h"
#include "reference.h"

namespace spot::noise {

inline constexpr int kSceneVersion = 1;

/// How an animated mesh plays (scene key "animation"; docs/design.md section 6).
struct AnimationDesc {
    bool given = false;         ///< the scene has an "animation" block
    bool restFrameGiven = false; ///< it names "rest_frame"
    std::string clip;  ///< a glTF file's clip by name; empty: its first
    double fps = 24.0; ///< frames per second: --frames' numbering, a mesh cache's rate
    double time = 0.0; ///< the time rendered when the command line names none (seconds)
    int restFrame = 0; ///< a mesh cache's rest pose: an index into its frames
};

/// A camera key (scene key "camera.keys"): where the camera is at `time`.
struct CameraKey {
    double time = 0.0;
    glm::dvec3 eye{0.0}, target{0.0};
};

struct SceneDesc {
    std::string name;
    std::string file;                ///< the scene file, for messages (empty: parsed from text)
    std::string mesh;                ///< path (resolved against the scene's folder) or generated:NAME
    std::filesystem::path preset;    ///< resolved against the scene's folder
    /// The mesh and preset as written, and what a relative one was resolved against ("the
    /// scene's folder", or "the current folder" for a command-line override): for messages.
    std::string meshWritten, presetWritten;
    std::string meshRelativeTo = "the scene's folder", presetRelativeTo = "the scene's folder";
    std::uint32_t seed = 0;
    Camera camera;                   ///< includes the image size
    glm::vec3 background{0.0f};      ///< linear RGB
    glm::vec3 baseColor{0.5f};       ///< linear RGB of the opaque base mesh
    Shading shading;
    int referenceSpp = 16;
    AnimationDesc animation;
    /// How the mesh loads: its weld (scene key "weld") and the glTF parts that grow fur ("grow").
    MeshOptions meshOptions;
    Wind wind;
    /// The camera over time: keys (ascending times; eye and target interpolated linearly,
    /// clamped at the ends), then a turntable turning the eye about the target's up axis by
    /// turntableDegPerSecond x t. Neither: the camera stands.
    std::vector<CameraKey> cameraKeys;
    double turntableDegPerSecond = 0.0;
    bool cameraMoves() const { return !cameraKeys.empty() || turntableDegPerSecond != 0.0; }
};

/// The camera at time t (seconds): `base` (the scene's camera as parsed, with the command
/// line's size) moved by the scene's keys and turntable.
Camera cameraAt(const SceneDesc& scene, const Camera& base, double t);

/// The scene's mesh file (not a generated shape or a cache pattern) and preset exist, or
/// InputError naming the scene, the path as written, what it was resolved against and the path
/// tried.
void requireSceneFiles(const SceneDesc& scene);

/// The scene's "animation" block against the mesh it loaded: InputError for a "clip" or
/// "rest_frame" on a mesh that has no clip (a static OBJ, PLY or generated shape); a warning
/// (returned, one line; empty: none) for a block that nothing in the scene uses (nothing moves).
std::string checkAnimation(const SceneDesc& scene, const AnimatedMesh& mesh);

/// Parse a scene; `name` is the file (for messages), `baseDir` resolves relative paths.
SceneDesc parseScene(std::string_view json, const std::string& name,
                     const std::filesystem::path& baseDir);
SceneDesc loadScene(const std::filesystem::path& file);

} // namespace spot::noise
