#include "scene_job.h"

#include <chrono>
#include <cstdio>
#include <utility>

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

SceneJob::SceneJob(noise::SceneDesc desc, bool cpuImpulses) : scene(std::move(desc)) {
    rays = std::make_unique<noise::CameraRays>(scene.camera);
    mesh = noise::loadMeshOrGenerated(scene.mesh);
    preset = noise::loadPreset(scene.preset);
    noise::GeneratorOptions options;
    options.seed = scene.seed;
    const auto start = std::chrono::steady_clock::now();
    generator = std::make_unique<noise::ImpulseGenerator>(mesh, preset, options);
    for (const noise::SurfaceCell& cell : generator->cells().cells)
        visibleCells += cellVisible(cell);
    if (cpuImpulses)
        impulses =
            generator->generate([&](const noise::SurfaceCell& cell) { return cellVisible(cell); });
    generateSeconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

SceneJob loadSceneJob(const std::filesystem::path& scene, int width, int height, bool cpuImpulses) {
    noise::SceneDesc desc = noise::loadScene(scene);
    if (width > 0 && height > 0) {
        desc.camera.width = width;
        desc.camera.height = height;
    }
    return SceneJob(std::move(desc), cpuImpulses);
}

SceneJob prepareScene(const Args& args, bool cpuImpulses) {
    noise::SceneDesc desc = noise::loadScene(args.str("scene"));
    if (args.has("mesh"))
        desc.mesh = args.str("mesh");
    if (args.has("preset"))
        desc.preset = args.str("preset");
    if (args.has("seed"))
        desc.seed = std::uint32_t(args.integer("seed", 0, 0, 0xffffffffll));
    if (args.has("size")) {
        const std::string size = args.str("size");
        int w = 0, h = 0;
        char x = 0, extra = 0;
        if (std::sscanf(size.c_str(), "%d%c%d%c", &w, &x, &h, &extra) != 3 ||
            (x != 'x' && x != 'X') || w < 1 || h < 1 || w > 16384 || h > 16384)
            throw InputError(cat("--size '", size, "' must be WxH with sides in [1, 16384]"));
        desc.camera.width = w;
        desc.camera.height = h;
    }
    return SceneJob(std::move(desc), cpuImpulses);
}

} // namespace spot::cli
