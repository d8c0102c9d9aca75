/// @file scene_job.h
/// @brief What every rendering command starts from: a scene file with its command-line
/// overrides, the mesh and preset it names, and the impulses of the cells the camera can see.
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "cli.h"
#include "noise/animated_mesh.h"
#include "noise/camera.h"
#include "noise/deform.h"
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

    /// Cells whose kernels may reach the view (a cell's kernels reach at most h beyond it; at a
    /// pose, from the cell's posed box); every cell when kernels cast shadows
    /// (Shading::castsShadows): one out of view may shadow one in view.
    bool cellVisible(const noise::SurfaceCell& cell) const;

    /// Whether the scene's surface moves: an animated mesh, or wind (docs/design.md section 6).
    bool animated() const { return deformer != nullptr; }
    /// Whether anything moves over time: the surface, or the camera (keys, a turntable).
    bool moves() const { return animated() || scene.cameraMoves(); }
    /// The scene at time t (seconds): its camera (scene.camera, from the keys and the turntable);
    /// with `cpuImpulses`, the posed mesh (clamped to the clip) and the impulses of the cells
    /// visible at that pose and camera, carried to it (the GPU poses on its own: splat::Frame).
    void poseAt(double t);
    /// The mesh as rendered: posed (poseAt's), or the mesh as loaded.
    const noise::Mesh& renderedMesh() const { return deformer ? deformer->posed() : mesh; }

    noise::SceneDesc scene;
    std::unique_ptr<noise::CameraRays> rays; ///< the scene's camera, after the overrides
    noise::Camera baseCamera;                ///< scene.camera as loaded (poseAt moves scene.camera)
    noise::AnimatedMesh animation; ///< the scene's mesh as loaded, at rest and at any time
    noise::Mesh mesh;              ///< its rest pose: what the noise is generated on
    noise::PresetDesc preset;
    std::unique_ptr<noise::ImpulseGenerator> generator;
    std::unique_ptr<noise::Deformer> deformer; ///< a scene that moves
    bool cpuImpulses = false;
    std::vector<noise::Impulse> impulses; ///< of the visible cells only (at poseAt's pose)
    std::size_t visibleCells = 0;
    double generateSeconds = 0.0;
};

/// --time T and --frames A-B[:STEP] (docs/design.md section 6).
std::vector<OptionSpec> timeOptions();

/// One frame of a shot: its number, its time (seconds) and its output file.
struct ShotFrame {
    long frame = 0;
    double time = 0.0;
    std::string file;
};
struct Shot {
    std::vector<ShotFrame> frames; ///< in order; one without --frames
};
/// The frames a scene's animation spans, first to last inclusive, at its fps.
struct FrameSpan {
    long first = 0, last = 0;
    std::string what; ///< what bounds it, for messages ("the clip 'sway'")
};
/// A scene's frame span: a mesh clip's frames (noise::clipFrames: from the clip's start, frame f
/// at f / fps); without a clip, the camera keys'
/// times when they are all that moves (at least two keys apart in time); otherwise none (the wind
/// and a turntable go on forever).
std::optional<FrameSpan> frameSpan(const SceneJob& job);
/// The frames `args` asks for: --frames A-B[:STEP] (frame f at f / fps, `out` a pattern with one
/// printf integer conversion), --time T, or the scene's time (`out` as given). InputError for a
/// malformed range (reversed, a step of 0), frames outside `span` when given (--time is clamped
/// instead, never refused), both options, a pattern without (or with more than) one conversion,
/// or more than 100,000 frames.
Shot shotOf(const Args& args, const noise::AnimationDesc& animation, const std::string& out,
            const std::optional<FrameSpan>& span = std::nullopt);

/// Load a scene file with an optional image size override; mesh, preset and surface cells, and
/// with `cpuImpulses` the impulses of the visible cells generated on the CPU.
SceneJob loadSceneJob(const std::filesystem::path& scene, int width, int height, bool cpuImpulses);

/// Load the scene, apply the overrides in `args`, load mesh and preset, build the surface cells;
/// with `cpuImpulses`, also generate the impulses of the visible cells on the CPU.
SceneJob prepareScene(const Args& args, bool cpuImpulses);

} // namespace spot::cli
