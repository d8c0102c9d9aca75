#include "scene_job.h"

#include <chrono>
#include <cstdio>

#include "noise/camera.h"
#include "noise/error.h"

namespace spot::cli {

std::vector<OptionSpec> sceneOptions() {
    return {{"scene", "FILE", "scene JSON (presets/scenes/*.json)", true},
            {"mesh", "FILE", "override the scene's mesh (.obj/.ply or generated:NAME)", false},
            {"preset", "FILE", "override the scene's preset", false},
            {"size", "WxH", "override the image size, e.g. 640x480", false},
            {"seed", "N", "override the impulse seed", false}};
}

bool SceneJob::cellVisible(const noise::SurfaceCell& cell) const {
    const double h = generator->cellSize();
    return rays->boxMayBeVisible(glm::dvec3(cell.ijk) * h - h, glm::dvec3(cell.ijk + 1) * h + h);
}

namespace {

/// The part after the scene description is settled.
void finishJob(SceneJob& job, bool cpuImpulses) {
    job.rays = std::make_unique<noise::CameraRays>(job.scene.camera);
    job.mesh = noise::loadMeshOrGenerated(job.scene.mesh);
    job.preset = noise::loadPreset(job.scene.preset);
    noise::GeneratorOptions options;
    options.seed = job.scene.seed;
    const auto start = std::chrono::steady_clock::now();
    job.generator = std::make_unique<noise::ImpulseGenerator>(job.mesh, job.preset, options);
    for (const noise::SurfaceCell& cell : job.generator->cells().cells)
        job.visibleCells += job.cellVisible(cell);
    if (cpuImpulses)
        job.impulses = job.generator->generate(
            [&](const noise::SurfaceCell& cell) { return job.cellVisible(cell); });
    job.generateSeconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

} // namespace

SceneJob loadSceneJob(const std::filesystem::path& scene, int width, int height, bool cpuImpulses) {
    SceneJob job;
    job.scene = noise::loadScene(scene);
    if (width > 0 && height > 0) {
        job.scene.camera.width = width;
        job.scene.camera.height = height;
    }
    finishJob(job, cpuImpulses);
    return job;
}

SceneJob prepareScene(const Args& args, bool cpuImpulses) {
    SceneJob job;
    job.scene = noise::loadScene(args.str("scene"));
    if (args.has("mesh"))
        job.scene.mesh = args.str("mesh");
    if (args.has("preset"))
        job.scene.preset = args.str("preset");
    if (args.has("seed"))
        job.scene.seed = std::uint32_t(args.integer("seed", 0, 0, 0xffffffffll));
    if (args.has("size")) {
        const std::string size = args.str("size");
        int w = 0, h = 0;
        char x = 0, extra = 0;
        if (std::sscanf(size.c_str(), "%d%c%d%c", &w, &x, &h, &extra) != 3 || (x != 'x' && x != 'X') ||
            w < 1 || h < 1 || w > 16384 || h > 16384)
            throw InputError(cat("--size '", size, "' must be WxH with sides in [1, 16384]"));
        job.scene.camera.width = w;
        job.scene.camera.height = h;
    }
    finishJob(job, cpuImpulses);
    return job;
}

} // namespace spot::cli
