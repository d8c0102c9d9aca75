/// @file scene_job.h
/// @brief What every rendering command starts from: a scene file with its command-line
/// overrides, the mesh and preset it names, and the impulses of the cells the camera can see.
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "cli.h"
#include "noise/camera.h"
#include "noise/impulses.h"
#include "noise/mesh.h"
#include "noise/preset.h"
#include "noise/scene.h"

namespace spot::cli {

/// The options shared by commands that take a scene (--scene, --mesh, --preset, --size, --seed).
std::vector<OptionSpec> sceneOptions();

/// Neither copyable nor movable: `generator` keeps a reference to the sibling `mesh`, so the job
/// must stay where it was built. The loaders return it as a prvalue (guaranteed copy elision), so
/// `SceneJob job = loadSceneJob(...);` still works.
struct SceneJob {
    /// Sets the camera, loads mesh and preset, builds the surface cells; with `cpuImpulses`, also
    /// generates the impulses of the visible cells on the CPU.
    SceneJob(noise::SceneDesc desc, bool cpuImpulses);
    SceneJob(const SceneJob&) = delete;
    SceneJob& operator=(const SceneJob&) = delete;
    SceneJob(SceneJob&&) = delete;
    SceneJob& operator=(SceneJob&&) = delete;

    /// Cells whose kernels may reach the view (a cell's kernels reach at most h beyond it).
    bool cellVisible(const noise::SurfaceCell& cell) const;

    noise::SceneDesc scene;
    std::unique_ptr<noise::CameraRays> rays; ///< the scene's camera, after the overrides
    noise::Mesh mesh;
    noise::PresetDesc preset;
    std::unique_ptr<noise::ImpulseGenerator> generator;
    std::vector<noise::Impulse> impulses; ///< of the visible cells only
    std::size_t visibleCells = 0;
    double generateSeconds = 0.0;
};

/// Load a scene file with an optional image size override; mesh, preset and surface cells, and
/// with `cpuImpulses` the impulses of the visible cells generated on the CPU.
SceneJob loadSceneJob(const std::filesystem::path& scene, int width, int height, bool cpuImpulses);

/// Load the scene, apply the overrides in `args`, load mesh and preset, build the surface cells;
/// with `cpuImpulses`, also generate the impulses of the visible cells on the CPU.
SceneJob prepareScene(const Args& args, bool cpuImpulses);

} // namespace spot::cli
