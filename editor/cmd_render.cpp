#include <cstdio>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

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
#include "splat/context_vk.h"
#include "splat/generate_vk.h"
#include "splat/raymarch_vk.h"
#include "splat/renderer_vk.h"

namespace spot::cmd {

namespace {

struct Rendered {
    noise::Image image;
    nlohmann::json stats;
    std::size_t kernels = 0;
    double seconds = 0.0;
    std::string summary; ///< for the closing line
};

Rendered renderReference(const cli::Args& args, cli::SceneJob& job) {
    noise::ReferenceSettings settings;
    settings.spp = int(args.integer("spp", job.scene.referenceSpp, 1, 65536));
    settings.stepScale = args.number("step-scale", 1.0, 1e-3, 1e3);
    settings.seed = job.scene.seed;
    const noise::ReferenceRenderer renderer(job.mesh, job.generator->kernel(), job.impulses,
                                            job.scene.shading, job.scene.background,
                                            job.scene.baseColor);
    noise::ReferenceStats stats;
    cli::ProgressBar bar("reference");
    Rendered r;
    r.image = renderer.render(job.scene.camera, settings,
                              [&](int done, int total) { bar.update(done, total); }, &stats);
    bar.finish();
    r.kernels = job.impulses.size();
    r.seconds = stats.seconds;
    r.stats = {{"spp", settings.spp},
               {"step_scale", settings.stepScale},
               {"kernels_generated", r.kernels},
               {"kernels_drawn", r.kernels},
               {"lobes", stats.lobes},
               {"rays", stats.rays},
               {"chords", stats.chords},
               {"exact_chords", stats.exactChords},
               {"quadrature_steps", stats.quadratureSteps},
               {"memory_bytes", stats.memoryBytes}};
    r.summary = cat(settings.spp, " spp, ", r.kernels, " kernels, ", stats.seconds, " s");
    return r;
}

/// What both GPU paths report: the image, device, kernel counts, GPU time per pass (generation
/// first) and in all, memory, validation errors (any fails the run), plus the method's own
/// `settings`. The summary line ends with the time and the device.
Rendered gpuRendered(splat::Context& ctx, noise::Image image, const splat::GpuImpulses& impulses,
                     std::uint32_t drawn, const std::vector<std::pair<std::string, double>>& passMs,
                     double frameMs, const nlohmann::json& settings) {
    const splat::ValidationCounts v = ctx.validation();
    if (v.errors > 0)
        throw std::runtime_error(cat(v.errors, " Vulkan validation errors, first: ", v.firstError));
    nlohmann::json passes = nlohmann::json::object();
    passes["generate"] = impulses.milliseconds;
    for (const auto& [name, ms] : passMs)
        passes[name] = ms;
    const double totalMs = impulses.milliseconds + frameMs;
    Rendered r;
    r.image = std::move(image);
    r.kernels = impulses.count;
    r.seconds = totalMs * 1e-3;
    r.stats = settings;
    r.stats.update({{"device", ctx.deviceName()},
                    {"kernels_generated", impulses.count},
                    {"kernel_candidates", impulses.candidates},
                    {"kernels_drawn", drawn},
                    {"gpu_ms", passes},
                    {"gpu_total_ms", totalMs},
                    {"gpu_memory_bytes", ctx.peakAllocatedBytes()},
                    {"validation_errors", v.errors}});
    r.summary = cat(totalMs, " ms GPU on ", ctx.deviceName());
    return r;
}

Rendered renderGpu(const cli::Args& args, cli::SceneJob& job, splat::Method method) {
    splat::SplatSettings settings;
    settings.method = method;
    settings.kernelSamples = int(args.integer("kernel-samples", 0, 0, 2048));
    const std::string ewa = args.str("ewa", "on");
    if (ewa != "on" && ewa != "off")
        throw InputError(cat("spotshell render: --ewa must be on or off, not '", ewa, "'"));
    settings.ewa = ewa == "on";
    const std::string weight = args.str("weight", "mcguire-bavoil");
    if (weight == "constant")
        settings.weight = splat::OitWeight::Constant;
    else if (weight == "mcguire-bavoil")
        settings.weight = splat::OitWeight::McGuireBavoil;
    else
        throw InputError(cat("spotshell render: --weight must be constant or mcguire-bavoil, not '",
                             weight, "'"));
    const std::string closest = args.str("closest", "atomic");
    if (closest == "atomic")
        settings.closest = splat::ClosestKernel::Atomic;
    else if (closest == "depth-pass")
        settings.closest = splat::ClosestKernel::DepthPass;
    else
        throw InputError(cat("spotshell render: --closest must be atomic or depth-pass, not '",
                             closest, "'"));

    splat::Context ctx;
    splat::GpuGenerator generator(ctx, job.mesh, *job.generator);
    const double lod = args.number("lod", 0.0, 0.0, 64.0);
    const splat::GpuImpulses impulses =
        generator.generate([&](const noise::SurfaceCell& cell) { return job.cellVisible(cell); },
                           splat::lodParameters(job.scene.camera, lod));
    splat::SplatRenderer renderer(ctx, job.mesh, job.generator->kernel());
    splat::FrameStats frame;
    noise::Image image = renderer.render(job.scene.camera, job.scene.shading, job.scene.background,
                                         job.scene.baseColor, impulses.impulses, impulses.count,
                                         settings, &frame);
    Rendered r = gpuRendered(ctx, std::move(image), impulses, frame.kernelsDrawn, frame.passMs,
                             frame.totalMs,
                             {{"ewa", settings.ewa},
                              {"kernel_samples", settings.kernelSamples},
                              {"weight", weight},
                              {"closest", closest},
                              {"lod_pixels", lod}});
    r.summary = cat(impulses.count, " kernels, ", frame.kernelsDrawn, " drawn, ", r.summary);
    return r;
}

Rendered renderRaymarch(const cli::Args& args, cli::SceneJob& job) {
    splat::RaymarchSettings settings;
    settings.steps = int(args.integer("steps", 32, 1, splat::kRaymarchMaxSteps));
    settings.supersample = int(args.integer("supersample", 1, 1, splat::kRaymarchMaxSupersample));
    splat::Context ctx;
    splat::GpuGenerator generator(ctx, job.mesh, *job.generator);
    const splat::GpuImpulses impulses =
        generator.generate([&](const noise::SurfaceCell& cell) { return job.cellVisible(cell); });
    splat::RaymarchRenderer renderer(ctx, job.mesh, job.generator->kernel());
    splat::RaymarchStats stats;
    noise::Image image = renderer.render(job.scene.camera, job.scene.shading, job.scene.background,
                                         job.scene.baseColor, job.generator->cells(),
                                         impulses.impulses, impulses.count, settings, &stats);
    Rendered r = gpuRendered(ctx, std::move(image), impulses, impulses.count, stats.passMs,
                             stats.totalMs,
                             {{"steps", settings.steps},
                              {"supersample", settings.supersample},
                              {"loop_bound", stats.loopBound},
                              {"max_loop_iterations", stats.maxLoopIterations},
                              {"steps_per_dispatch", stats.stepsPerDispatch},
                              {"dispatches", stats.dispatches},
                              {"shell_cells", stats.shellCells}});
    r.summary = cat(impulses.count, " kernels, ", settings.steps, " steps in ", stats.dispatches,
                    stats.dispatches == 1 ? " dispatch, " : " dispatches, ", settings.supersample,
                    "x", settings.supersample, " rays per pixel, ", r.summary);
    return r;
}

} // namespace

int render(int argc, char** argv) {
    std::vector<cli::OptionSpec> specs = cli::sceneOptions();
    specs.insert(specs.end(),
                 {{"method", "NAME", "reference (converged CPU ground truth), instanced, oit, hybrid, sorted or raymarch", true},
                  {"spp", "N", "reference: samples per pixel (default: the scene's)", false},
                  {"step-scale", "X", "reference: quadrature step multiplier (default 1)", false},
                  {"kernel-samples", "N", "oit/hybrid: march N samples per kernel (paper eq. 10) "
                                          "instead of the analytic integral (default 0)", false},
                  {"ewa", "on|off", "GPU methods: EWA filtering by the pixel footprint (default on)", false},
                  {"weight", "W", "oit/hybrid: constant or mcguire-bavoil (default)", false},
                  {"closest", "HOW", "hybrid: find each pixel's closest kernel with an atomicMin in "
                                     "the OIT pass (atomic, default) or in a depth pass of its own "
                                     "(depth-pass); the same image either way", false},
                  {"steps", "N", "raymarch: samples along each ray through the shell (default 32, "
                                 "at most 4096; split over dispatches so that no shader "
                                 "invocation loops too long)", false},
                  {"supersample", "N", "raymarch: N x N rays per pixel, box-filtered (default 1, "
                                       "at most 8)", false},
                  {"lod", "PIXELS", "GPU methods: thin the kernels of cells smaller than PIXELS on "
                                    "screen, conserving mass (default 0: off)", false},
                  {"out", "FILE", "output image: .exr (linear float) or .png (sRGB 8-bit)", true},
                  {"stats", "FILE", "also write timings and counts as JSON", false},
                  cli::threadsOption()});
    cli::Args args("render", "Render a scene with one of the methods. GPU methods run on Vulkan "
                             "(lavapipe without a GPU); SPOT_VALIDATION=1 turns validation on.",
                   specs, argc, argv);
    if (args.helpRequested()) {
        std::fputs(args.usage().c_str(), stdout);
        return 0;
    }
    const std::string method = args.str("method");
    std::optional<splat::Method> gpuMethod;
    if (method == "instanced")
        gpuMethod = splat::Method::Instanced;
    else if (method == "oit")
        gpuMethod = splat::Method::Oit;
    else if (method == "hybrid")
        gpuMethod = splat::Method::Hybrid;
    else if (method == "sorted")
        gpuMethod = splat::Method::Sorted;
    else if (method != "reference" && method != "raymarch")
        throw InputError(cat("spotshell render: unknown method '", method,
                             "' (reference, instanced, oit, hybrid, sorted, raymarch)"));
    const auto threads = args.integer("threads", 0, 0, 1024);
    std::optional<tbb::global_control> threadLimit;
    if (threads > 0)
        threadLimit.emplace(tbb::global_control::max_allowed_parallelism, std::size_t(threads));

    const bool reference = method == "reference";
    cli::SceneJob job = cli::prepareScene(args, reference);
    const std::string out = args.str("out");
    Rendered r = gpuMethod   ? renderGpu(args, job, *gpuMethod)
                 : reference ? renderReference(args, job)
                             : renderRaymarch(args, job);

    std::map<std::string, std::string> metadata = {{"method", method},
                                                   {"scene", job.scene.name},
                                                   {"seconds", cat(r.seconds)},
                                                   {"kernels", std::to_string(r.kernels)},
                                                   {"seed", std::to_string(job.scene.seed)},
                                                   {"stats", r.stats.dump()}};
    if (r.stats.contains("spp"))
        metadata["spp"] = r.stats["spp"].dump();
    noise::writeImage(out, r.image, metadata);
    if (args.has("stats")) {
        nlohmann::json j = r.stats;
        j["method"] = method;
        j["scene"] = job.scene.name;
        j["width"] = r.image.width;
        j["height"] = r.image.height;
        j["seed"] = job.scene.seed;
        j["seconds"] = r.seconds;
        j["generate_seconds"] = job.generateSeconds;
        j["cells"] = job.generator->cells().cells.size();
        j["visible_cells"] = job.visibleCells;
        writeFileAtomic(args.str("stats"), [&](std::ostream& o) { o << j.dump(2) << "\n"; });
    }
    std::printf("wrote %s (%s, %dx%d, %s)\n", out.c_str(), method.c_str(), r.image.width,
                r.image.height, r.summary.c_str());
    return 0;
}

} // namespace spot::cmd
