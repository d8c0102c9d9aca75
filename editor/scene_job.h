/// @file scene_job.h
/// @brief What every rendering command starts from: a scene file with its command-line
/// overrides, the mesh and preset it names, and the impulses of the cells the camera can see.
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "cli.h"
#include "noise/impulses.h"
#include "noise/mesh.h"
#include "noise/preset.h"
#include "noise/scene.h"

namespace spot::cli {

/// The options shared by commands that take a scene (--scene, --mesh, --preset, --size, --seed).
std::vector<OptionSpec> sceneOptions();

struct SceneJob {
    noise::SceneDesc scene;
    noise::Mesh mesh;
    noise::PresetDesc preset;
    std::unique_ptr<noise::ImpulseGenerator> generator;
    std::vector<noise::Impulse> impulses; ///< of the visible cells only
    std::size_t visibleCells = 0;
    double generateSeconds = 0.0;
};

/// Load the scene, apply the overrides in `args`, load mesh and preset, generate the impulses of
/// the cells whose kernels may reach the view.
SceneJob prepareScene(const Args& args);

} // namespace spot::cli
