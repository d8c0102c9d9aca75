#include <cstdio>
#include <optional>

#include <nlohmann/json.hpp>
#include <tbb/global_control.h>

#include "cli.h"
#include "commands.h"
#include "noise/error.h"
#include "noise/image.h"
#include "noise/reference.h"
#include "noise/system.h"
#include "progress.h"
#include "scene_job.h"

namespace spot::cmd {

int render(int argc, char** argv) {
    std::vector<cli::OptionSpec> specs = cli::sceneOptions();
    specs.insert(specs.end(),
                 {{"method", "NAME", "renderer: reference (the converged CPU ground truth)", true},
                  {"spp", "N", "samples per pixel (default: the scene's)", false},
                  {"step-scale", "X", "reference quadrature step multiplier (default 1)", false},
                  {"out", "FILE", "output image: .exr (linear float) or .png (sRGB 8-bit)", true},
                  {"stats", "FILE", "also write timings and counts as JSON", false},
                  cli::threadsOption()});
    cli::Args args("render", "Render a scene with one of the methods.", specs, argc, argv);
    if (args.helpRequested()) {
        std::fputs(args.usage().c_str(), stdout);
        return 0;
    }
    const std::string method = args.str("method");
    if (method != "reference")
        throw InputError(cat("spotshell render: unknown method '", method, "' (available: reference)"));
    const auto threads = args.integer("threads", 0, 0, 1024);
    std::optional<tbb::global_control> threadLimit;
    if (threads > 0)
        threadLimit.emplace(tbb::global_control::max_allowed_parallelism, std::size_t(threads));

    cli::SceneJob job = cli::prepareScene(args);
    noise::ReferenceSettings settings;
    settings.spp = int(args.integer("spp", job.scene.referenceSpp, 1, 65536));
    settings.stepScale = args.number("step-scale", 1.0, 1e-3, 1e3);
    settings.seed = job.scene.seed;
    const std::string out = args.str("out");

    const noise::ReferenceRenderer renderer(job.mesh, job.generator->kernel(), job.impulses,
                                            job.scene.shading, job.scene.background,
                                            job.scene.baseColor);
    noise::ReferenceStats stats;
    cli::ProgressBar bar("reference");
    const noise::Image image = renderer.render(
        job.scene.camera, settings, [&](int done, int total) { bar.update(done, total); }, &stats);
    bar.finish();

    const std::size_t kernels = job.impulses.size();
    noise::writeImage(out, image,
                      {{"method", method},
                       {"scene", job.scene.name},
                       {"spp", std::to_string(settings.spp)},
                       {"step_scale", cat(settings.stepScale)},
                       {"seconds", cat(stats.seconds)},
                       {"kernels", std::to_string(kernels)},
                       {"lobes", std::to_string(stats.lobes)},
                       {"seed", std::to_string(job.scene.seed)}});
    if (args.has("stats")) {
        const nlohmann::json j = {{"method", method},
                                  {"scene", job.scene.name},
                                  {"width", image.width},
                                  {"height", image.height},
                                  {"spp", settings.spp},
                                  {"step_scale", settings.stepScale},
                                  {"seed", job.scene.seed},
                                  {"seconds", stats.seconds},
                                  {"generate_seconds", job.generateSeconds},
                                  {"cells", job.generator->cells().cells.size()},
                                  {"visible_cells", job.visibleCells},
                                  {"kernels_generated", kernels},
                                  {"kernels_drawn", kernels},
                                  {"lobes", stats.lobes},
                                  {"rays", stats.rays},
                                  {"chords", stats.chords},
                                  {"exact_chords", stats.exactChords},
                                  {"quadrature_steps", stats.quadratureSteps},
                                  {"memory_bytes", stats.memoryBytes}};
        writeFileAtomic(args.str("stats"), [&](std::ostream& o) { o << j.dump(2) << "\n"; });
    }
    std::printf("wrote %s (%s, %dx%d, %d spp, %zu kernels, %.2f s)\n", out.c_str(), method.c_str(),
                image.width, image.height, settings.spp, kernels, stats.seconds);
    return 0;
}

} // namespace spot::cmd
