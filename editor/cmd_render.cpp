#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
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
#include "noise/system.h"
#include "progress.h"
#include "render_options.h"
#include "scene_job.h"
#include "splat/context_vk.h"
#include "splat/frame_vk.h"
#include "splat/generate_vk.h"
#include "splat/pass_vk.h"
#include "tiles.h"

namespace spot::cmd {

namespace {

struct Rendered {
    noise::Image image;
    nlohmann::json stats;
    std::size_t kernels = 0;
    double seconds = 0.0;
    std::string summary; ///< for the closing line
    nlohmann::json firstPipelines; ///< a GPU method's pipeline counters after its first frame
};

/// A number for --stats: an integer when it is one.
nlohmann::json statValue(double v) {
    if (v == std::floor(v) && std::abs(v) < 9007199254740992.0)
        return std::int64_t(v);
    return v;
}

/// A CPU method (the reference) on the scene's impulses, with a progress bar.
Rendered renderCpu(cli::SceneJob& job, const splat::MethodInfo& method,
                   const splat::RenderSettings& settings, bool quiet) {
    const splat::CpuScene scene{
        job.renderedMesh(),
        job.generator->kernel(),
        job.impulses,
        {job.scene.camera, job.scene.shading, job.scene.background, job.scene.baseColor},
        job.scene.seed,
        job.scene.referenceSpp};
    cli::ProgressBar bar(quiet ? std::string() : method.name);
    splat::CpuFrame f =
        method.renderCpu(scene, settings, [&](int done, int total) {
            if (!quiet)
                bar.update(done, total);
        });
    bar.finish();
    Rendered r;
    r.image = std::move(f.image);
    r.kernels = f.kernels;
    r.seconds = f.seconds;
    r.stats = cli::describe(method, settings);
    for (const auto& [name, value] : f.stats)
        r.stats[name] = statValue(value);
    r.summary = f.summary;
    return r;
}

/// Whether `file` is a complete image (--resume): there, and read without error.
bool complete(const std::string& file) {
    std::error_code ec;
    if (!std::filesystem::is_regular_file(file, ec))
        return false;
    try {
        noise::readImage(file);
        return true;
    } catch (const std::exception&) {
        return false;
    }
}

/// Median, 90th percentile and minimum of `values` (empty: zeros), as JSON.
nlohmann::json summary(std::vector<double> values) {
    nlohmann::json j = {{"median", 0.0}, {"p90", 0.0}, {"min", 0.0}};
    if (values.empty())
        return j;
    std::sort(values.begin(), values.end());
    auto at = [&](double p) {
        const double x = p * double(values.size() - 1);
        const std::size_t lo = std::size_t(x), hi = std::min(lo + 1, values.size() - 1);
        return values[lo] + (values[hi] - values[lo]) * (x - double(lo));
    };
    j["median"] = at(0.5);
    j["p90"] = at(0.9);
    j["min"] = values.front();
    return j;
}

/// A GPU method through the persistent frame: one frame (read back), then `--repeat N` warm
/// frames (not read back), timed.
Rendered renderGpu(const cli::Args& args, cli::SceneJob& job, splat::Context& ctx,
                   splat::Frame& frame, const splat::MethodInfo& method,
                   const splat::RenderSettings& settings) {
    const int repeat = int(args.integer("repeat", 0, 0, 100000));
    const splat::View view{job.scene.camera, job.scene.shading, job.scene.background,
                           job.scene.baseColor};
    Rendered r;
    const splat::FrameStats first = frame.render(method.name, view, settings, &r.image);
    {
        const splat::PipelineStats p = ctx.pipelineStats();
        const splat::PipelineCacheInfo c = ctx.pipelineCacheInfo();
        r.firstPipelines = {{"created", p.created},
                            {"used", p.used},
                            {"from_cache", p.fromCache},
                            {"driver_cache_hits", p.driverCacheHits},
                            {"create_ms", p.createMs},
                            {"wait_ms", p.waitMs},
                            {"cache_file", c.path},
                            {"cache_loaded", c.loaded},
                            {"cache_bytes", c.bytes}};
    }
    splat::FrameStats last = first;
    std::vector<double> gpu, wall;
    // Each pass's milliseconds per frame (a name marked more than once in a frame, such as a
    // layer's pass, summed), for their medians over the warm frames.
    std::map<std::string, std::vector<double>> perPass;
    const auto addPasses = [&](const splat::FrameStats& s) {
        std::map<std::string, double> sums;
        for (const auto& [name, ms] : s.passMs)
            sums[name] += ms;
        for (const auto& [name, ms] : sums)
            perPass[name].push_back(ms);
    };
    for (int i = 0; i < repeat; ++i) {
        last = frame.render(method.name, view, settings);
        gpu.push_back(last.gpuMs);
        wall.push_back(last.wallMs);
        addPasses(last);
    }
    if (repeat == 0) {
        gpu.push_back(first.gpuMs);
        wall.push_back(first.wallMs);
        addPasses(first);
    }
    const splat::ValidationCounts v = ctx.validation();
    if (v.errors > 0)
        throw std::runtime_error(cat(v.errors, " Vulkan validation errors, first: ", v.firstError));
    nlohmann::json passes = nlohmann::json::object();
    for (const auto& [name, ms] : perPass)
        passes[name] = summary(ms)["median"];
    // The first frame's passes: the only one that generates the impulses ("generate").
    nlohmann::json firstPasses = nlohmann::json::object();
    for (const auto& [name, ms] : first.passMs)
        firstPasses[name] = firstPasses.value(name, 0.0) + ms;
    r.kernels = first.kernelsGenerated;
    r.seconds = first.gpuMs * 1e-3;
    r.stats = cli::describe(method, settings);
    r.stats.update({{"device", ctx.deviceName()},
                    {"kernels_generated", first.kernelsGenerated},
                    {"kernel_candidates", first.candidates},
                    {"visible_cells", first.visibleCells},
                    {"kernels_drawn", last.counters.kernelsDrawn},
                    {"gpu_ms", passes},
                    {"gpu_total_ms", last.gpuMs},
                    {"warm_frames", repeat},
                    {"frame_ms", summary(gpu)},
                    {"wall_ms", summary(wall)},
                    {"first_frame", {{"gpu_ms", first.gpuMs}, {"wall_ms", first.wallMs},
                                     {"passes", firstPasses}}},
                    {"gpu_memory_bytes", ctx.peakAllocatedBytes()},
                    {"validation_errors", v.errors}});
    for (const auto& [name, value] : last.counters.extra)
        r.stats[name] = value;
    if (settings.countFragments && method.takes(splat::settings::countFragments)) {
        const auto& c = last.counters;
        r.stats["fragments_shaded"] = c.fragmentsShaded;
        r.stats["pixels_covered"] = c.pixelsCovered;
        r.stats["fragment_efficiency"] =
            c.pixelsCovered > 0 ? double(c.fragmentsShaded) / double(c.pixelsCovered) : 0.0;
    }
    r.summary = cat(first.kernelsGenerated, " kernels, ");
    if (method.drawsKernels)
        r.summary += cat(last.counters.kernelsDrawn, " drawn, ");
    if (method.summarize)
        r.summary += method.summarize(settings);
    r.summary += cat(first.gpuMs, " ms GPU");
    if (repeat > 0)
        r.summary += cat(" (", repeat, " warm frames: median ", double(summary(gpu)["median"]),
                         " ms GPU, ", double(summary(wall)["median"]), " ms wall)");
    r.summary += cat(" on ", ctx.deviceName());
    return r;
}

} // namespace

int render(int argc, char** argv) {
    std::vector<cli::OptionSpec> specs = cli::sceneOptions();
    specs.push_back({"method", "NAME",
                     splat::methodNames() + " (default: --quality " +
                         std::string(splat::kDefaultQuality) + "'s method)",
                     false});
    specs.push_back(cli::qualityOption());
    for (const cli::OptionSpec& o : cli::renderOptions())
        specs.push_back(o);
    specs.insert(specs.end(),
                 {{"repeat", "N",
                   "GPU methods: render N warm frames after the first and report "
                   "their times (frame_ms, wall_ms in --stats, and gpu_ms: each "
                   "pass's median; default 0)",
                   false},
                  {"out", "FILE",
                   "output image: .exr (linear float) or .png (sRGB 8-bit); with --frames, a "
                   "pattern with one %d (shot.%04d.exr) numbered by frame",
                   true},
                  {"tile", "I/N",
                   "render tile I (from 0) of N: band I of N full-width bands of rows (rows "
                   "floor(I H / N) to floor((I + 1) H / N)); each pixel as in the whole image, "
                   "written with its place in it (spotshell assemble joins the tiles)",
                   false},
                  {"crop", "X0,Y0,X1,Y1",
                   "render only pixels [X0, X1) x [Y0, Y1) of the image, as --tile does", false},
                  {"stats", "FILE", "also write timings and counts as JSON", false},
                  cli::threadsOption()});
    for (const cli::OptionSpec& o : cli::timeOptions())
        specs.push_back(o);
    cli::Args args("render", "Render a scene with one of the methods. GPU methods run on Vulkan "
                             "(lavapipe without a GPU); SPOT_VALIDATION=1 turns validation on.",
                   specs, argc, argv);
    if (args.helpRequested()) {
        std::fputs(args.usage().c_str(), stdout);
        return 0;
    }
    const cli::MethodChoice choice = cli::methodChoice(args, "spotshell render", false);
    const std::string& method = choice.method;
    const splat::MethodInfo* info = splat::findMethod(method);
    cli::refuseSettingsNotTakenBy(
        args, *info,
        choice.quality.empty()
            ? std::string("spotshell render")
            : cat("spotshell render (--quality ", choice.quality, " picks ", method, ")"));
    if (!info->gpu() && args.has("repeat"))
        throw InputError(cat("spotshell render: --repeat times the warm frames of a GPU method (",
                             splat::gpuMethodNames(), "), not of ", method));
    const auto commandStart = std::chrono::steady_clock::now();
    const auto msSince = [](std::chrono::steady_clock::time_point t) {
        return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t)
            .count();
    };
    const auto threads = args.integer("threads", 0, 0, 1024);
    std::optional<tbb::global_control> threadLimit;
    if (threads > 0)
        threadLimit.emplace(tbb::global_control::max_allowed_parallelism, std::size_t(threads));

    // A CPU method renders the impulses generated on the host.
    cli::SceneJob job = cli::prepareScene(args, !info->gpu());
    const double sceneMs = msSince(commandStart);
    splat::requireLitSupport(*info, job.scene.shading); // before the device starts, not after

    const std::string out = args.str("out");
    splat::RenderSettings settings = cli::renderSettings(args, choice.settings);
    const cli::Shot shot = cli::shotOf(args, job.scene.animation, out, cli::frameSpan(job));
    if (args.has("tile") && args.has("crop"))
        throw InputError("spotshell render: give --tile or --crop, not both");
    const int width = job.scene.camera.width, height = job.scene.camera.height;
    noise::PixelRect window;
    if (args.has("tile"))
        window = cli::parseTile(args.str("tile"), width, height);
    else if (args.has("crop"))
        window = cli::parseCrop(args.str("crop"), width, height);
    if (window == noise::PixelRect{0, 0, width, height})
        window = {}; // the whole image: written as one
    settings.window = window;

    // What the method needs from the command line, checked before the device starts (seconds
    // on lavapipe), not after.
    if (info->takes(splat::settings::bake) && !settings.bake)
        throw InputError(cat("spotshell render: --method ", method, " needs --bake FILE.vdb "
                             "(spotshell bake makes one)"));
    std::optional<splat::Context> ctx;
    std::optional<splat::Frame> frame;
    // --stats: where a GPU method's start-up went (docs/design.md, "Start-up"), host ms.
    nlohmann::json startup;
    if (info->gpu()) {
        ctx.emplace();
        const auto uploadStart = std::chrono::steady_clock::now();
        frame.emplace(*ctx, job.mesh, *job.generator);
        if (job.animated())
            frame->animate(job.animation, job.scene.wind);
        startup = {{"scene_ms", sceneMs},
                   {"instance_ms", ctx->instanceMs()},
                   {"device_ms", ctx->deviceMs()},
                   {"upload_ms", msSince(uploadStart)}};
    }
    cli::ProgressBar bar(shot.frames.size() > 1 ? "frames" : "");
    Rendered r;
    std::string written;
    std::size_t skipped = 0, rendered = 0;
    nlohmann::json perFrame = nlohmann::json::array(); // --stats of a --frames range: each frame
    for (std::size_t i = 0; i < shot.frames.size(); ++i) {
        const double t = shot.frames[i].time;
        if (args.has("resume") && complete(shot.frames[i].file)) {
            ++skipped;
            bar.update(long(i + 1), long(shot.frames.size()));
            continue;
        }
        ++rendered;
        if (job.moves() && (i > 0 || t != job.scene.animation.time))
            job.poseAt(t); // the camera; a CPU method's posed impulses
        if (info->gpu()) {
            frame->setTime(t);
            r = renderGpu(args, job, *ctx, *frame, *info, settings);
            if (!startup.contains("first_frame_ms")) {
                startup["first_frame_ms"] = double(r.stats["first_frame"]["wall_ms"]);
                startup["to_first_frame_ms"] = msSince(commandStart);
                startup["pipelines"] = r.firstPipelines;
            }
        } else {
            r = renderCpu(job, *info, settings, shot.frames.size() > 1);
        }
        std::map<std::string, std::string> metadata = {{"method", method},
                                                       {"scene", job.scene.name},
                                                       {"seconds", cat(r.seconds)},
                                                       {"kernels", std::to_string(r.kernels)},
                                                       {"seed", std::to_string(job.scene.seed)},
                                                       {"stats", r.stats.dump()}};
        if (job.moves()) {
            char time[32];
            std::snprintf(time, sizeof(time), "%.17g", t); // round-trips
            metadata["time"] = time;
        }
        if (r.stats.contains("spp"))
            metadata["spp"] = r.stats["spp"].dump();
        if (args.has("tile"))
            metadata["tile"] = args.str("tile");
        written = shot.frames[i].file;
        noise::writeImage(written, r.image, metadata);
        if (args.has("stats") && args.has("frames")) {
            nlohmann::json f = r.stats;
            f["frame"] = shot.frames[i].frame;
            f["time"] = t;
            f["file"] = written;
            f["seconds"] = r.seconds;
            if (f.contains("first_frame"))
                f.erase("first_frame"); // each frame here is its own first: gpu_total_ms, wall_ms
            perFrame.push_back(std::move(f));
        }
        bar.update(long(i + 1), long(shot.frames.size()));
    }
    bar.finish();
    if (rendered == 0) {
        std::printf("all %zu frames are there (--resume): nothing rendered\n", shot.frames.size());
        return 0;
    }
    if (args.has("stats")) {
        nlohmann::json j = r.stats;
        j["method"] = method;
        if (!choice.quality.empty())
            j["quality"] = choice.quality;
        j["scene"] = job.scene.name;
        j["width"] = r.image.width;
        j["height"] = r.image.height;
        j["seed"] = job.scene.seed;
        j["seconds"] = r.seconds;
        j["generate_seconds"] = job.generateSeconds;
        j["cells"] = job.generator->cells().cells.size();
        j["visible_cells"] = r.stats.contains("visible_cells") ? std::size_t(r.stats["visible_cells"])
                                                               : job.visibleCells;
        if (job.moves())
            j["time"] = shot.frames.back().time;
        if (args.has("frames")) {
            // A range: what every frame shares at the top, each frame's own numbers in "frames"
            // (in order; frames skipped by --resume are not there).
            for (const char* key : {"time", "seconds", "first_frame", "frame_ms", "wall_ms",
                                    "gpu_ms", "gpu_total_ms", "kernels_generated",
                                    "kernel_candidates", "visible_cells", "kernels_drawn"})
                j.erase(key);
            for (auto it = j.begin(); it != j.end();) {
                bool perFrameKey = false;
                for (const nlohmann::json& f : perFrame)
                    perFrameKey = perFrameKey || (f.contains(it.key()) && f[it.key()] != it.value());
                it = perFrameKey ? j.erase(it) : std::next(it);
            }
            j["frames"] = perFrame;
            j["frame_count"] = perFrame.size();
        }
        if (!startup.empty())
            j["startup"] = startup;
        writeFileAtomic(args.str("stats"), [&](std::ostream& o) { o << j.dump(2) << "\n"; });
    }
    const std::string chosen =
        choice.quality.empty() ? method : cat(method, ", quality ", choice.quality);
    const std::string size = window.empty()
                                 ? cat(r.image.width, "x", r.image.height)
                                 : cat("pixels ", window.x0, ",", window.y0, "-", window.x1, ",",
                                       window.y1, " of ", width, "x", height);
    if (shot.frames.size() > 1)
        std::printf("wrote %zu frames%s, %s to %s (%s, %s, last: %s)\n", rendered,
                    skipped > 0 ? cat(" (", skipped, " already there)").c_str() : "",
                    shot.frames.front().file.c_str(), written.c_str(), chosen.c_str(), size.c_str(),
                    r.summary.c_str());
    else
        std::printf("wrote %s (%s, %s, %s)\n", written.c_str(), chosen.c_str(), size.c_str(),
                    r.summary.c_str());
    return 0;
}

} // namespace spot::cmd
