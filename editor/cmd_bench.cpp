// spotshell bench: every scene x method x setting against the converged reference: speed, error,
// temporal flicker, memory, and the charts that put speed against accuracy (docs/design.md section 7).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <sstream>

#include <nlohmann/json.hpp>

#include "bench_bake.h"
#include "bench_plot.h"
#include "bench_quality.h"
#include "cli.h"
#include "commands.h"
#include "noise/error.h"
#include "noise/image.h"
#include "noise/reference.h"
#include "noise/system.h"
#include "progress.h"
#include "render_options.h"
#include "scene_job.h"
#include "splat/context_vk.h"
#include "splat/frame_vk.h"
#include "splat/generate_vk.h"
#include "splat/image_compare.h"
#include "splat/methods/baked/baked_vk.h"
#include "splat/quality.h"

namespace spot::cmd {

namespace {

namespace fs = std::filesystem;
using nlohmann::json;

/// Bump when the reference renderer changes, so cached references are not reused.
constexpr int kReferenceVersion = 2; // 2: impulses generated in single precision
/// Verdicts (documented in the stability report): FLIP above this is "degraded"...
constexpr double kDegradedFlip = 0.15;
/// ... and so is flicker above the reference's own by more than this (mean display difference).
constexpr double kDegradedFlicker = 0.01;

struct Variant {
    std::string method;  ///< a GPU method of the registry (splat::gpuMethods())
    std::string setting; ///< human-readable settings, unique per method
    splat::RenderSettings settings;
    /// baked: the bake's level-0 voxels along the mesh's longest side and its levels (the bench
    /// bakes each scene's noise itself; settings.bake is set per scene).
    int bakeResolution = 0, bakeLevels = 0;
};

struct SceneEntry {
    std::string file;     ///< relative to presets/scenes
    std::string scenario; ///< the stability matrix's row
    int width = 0, height = 0; ///< image size; 0: the suite's
    /// Render the scene without its lights and sky (as `render --unlit`): the quick suite's
    /// claims are the paper's, about compositing emission and absorption.
    bool unlit = false;
};

struct Suite {
    std::string name;
    int width = 128, height = 128; ///< image size (a scene entry may have its own)
    int frames = 5;        ///< warm frames timed for the roofline (one more, the first, is not)
    int referenceSpp = 16;
    int orbitFrames = 8; ///< frames of the orbit: every row's error and flicker
    /// Every row's timed warm frames: the scene's camera, the image not read back (as `render
    /// --repeat` times them), at least timedFrames and on until they add up to timedMs of wall
    /// time (at most maxTimedFrames): a fast row's medians rest on many frames.
    int timedFrames = 5;
    double timedMs = 500.0;
    int maxTimedFrames = 200;
    double orbitDeg = 0.5; ///< camera step per orbit frame, degrees about the target's up axis
    std::vector<SceneEntry> scenes;
    std::vector<Variant> variants;
    bool scaling = false;
    /// Animated scenes (examples/animated, next to the source) and the clip frames benched in each
    /// (consecutive frames at the scene's fps from its time).
    std::vector<SceneEntry> animated;
    int clipFrames = 6;
};

splat::RenderSettings splatSettings(bool ewa, splat::OitWeight w, int samples, double lod = 0.0) {
    splat::RenderSettings s;
    s.ewa = ewa;
    s.weight = w;
    s.kernelSamples = samples;
    s.lodPixels = lod;
    return s;
}

enum class Variants { Quick, Full, Realtime };

std::string bakedSetting(int resolution, int levels, int peels) {
    return cat("res ", resolution, ", ", levels, levels == 1 ? " level, " : " levels, ", peels,
               peels == 1 ? " peel" : " peels");
}

std::vector<Variant> variants(Variants which) {
    const bool full = which == Variants::Full;
    using W = splat::OitWeight;
    std::vector<Variant> v = {
        {"instanced", "default", splatSettings(true, W::McGuireBavoil, 0)},
        {"oit", "ewa mb analytic", splatSettings(true, W::McGuireBavoil, 0)},
        {"oit", "ewa constant analytic", splatSettings(true, W::Constant, 0)},
        {"hybrid", "ewa mb analytic", splatSettings(true, W::McGuireBavoil, 0)},
        {"sorted", "ewa analytic", splatSettings(true, W::McGuireBavoil, 0)},
    };
    // The hybrid's closest kernel by a depth pass of its own instead of the atomicMin in the OIT
    // pass (docs/design.md: "measure both ways"): the same image, another cost.
    splat::RenderSettings depthPass = splatSettings(true, W::McGuireBavoil, 0);
    depthPass.closest = splat::ClosestKernel::DepthPass;
    v.push_back({"hybrid", "depth pass ewa mb analytic", depthPass});
    if (full) {
        v.push_back({"oit", "no-ewa mb analytic", splatSettings(false, W::McGuireBavoil, 0)});
        v.push_back({"oit", "ewa mb N16", splatSettings(true, W::McGuireBavoil, 16)});
        v.push_back({"sorted", "no-ewa analytic", splatSettings(false, W::McGuireBavoil, 0)});
        v.push_back({"hybrid", "ewa mb N16", splatSettings(true, W::McGuireBavoil, 16)});
        v.push_back({"hybrid", "lod 2px", splatSettings(true, W::McGuireBavoil, 0, 2.0)});
        v.push_back({"hybrid", "lod 4px", splatSettings(true, W::McGuireBavoil, 0, 4.0)});
    }
    // The ray-march baseline at rising step counts, with one ray per pixel and with 2 x 2 (the
    // pixel filter: one ray per pixel aliases sub-pixel strands, which flicker as the camera moves).
    const std::vector<std::pair<int, int>> marches =
        full                             ? std::vector<std::pair<int, int>>{{8, 1}, {16, 1}, {32, 1}, {64, 1}, {128, 1},
                                                                            {16, 2}, {32, 2}, {64, 2}}
        : which == Variants::Realtime ? std::vector<std::pair<int, int>>{{16, 1}, {32, 2}}
                                      : std::vector<std::pair<int, int>>{{16, 2}, {32, 2}, {64, 2}};
    for (const auto& [steps, n] : marches) {
        splat::RenderSettings s;
        s.steps = steps;
        s.supersample = n;
        v.push_back({"raymarch", n == 1 ? cat(steps, " steps") : cat(steps, " steps ", n, "x", n), s});
    }
    // The bake (baked) against its voxel size (resolution: level 0's voxels along the mesh's
    // longest side), its mip levels (1: level 0 only, so a far view samples voxels far below a
    // pixel) and its depth-peeling passes (a layer is a ray's whole passage through the shell,
    // so 1 misses only what lies behind a second entry, e.g. an ear behind the head). Quick: one
    // cheap row per scene, so CI covers the path. Full: resolution 128, 256, 512 with mips and
    // 128, 256 without, at the renderer's default 4 peels, and 1, 2 peels at 256 with mips, 1 peel
    // at 128 and 256 without. Realtime: with and without mips at 256, and 1 peel without.
    struct Baked {
        int resolution, levels, peels;
    };
    const std::vector<Baked> bakes =
        full ? std::vector<Baked>{{128, 1, 4}, {128, 4, 4}, {256, 1, 4}, {256, 4, 4},
                                  {512, 4, 4}, {256, 4, 1}, {256, 4, 2}, {128, 1, 1}, {256, 1, 1}}
        : which == Variants::Realtime ? std::vector<Baked>{{256, 1, 4}, {256, 4, 4}, {256, 1, 1}}
                                      : std::vector<Baked>{{128, 4, 4}};
    for (const Baked& b : bakes) {
        splat::RenderSettings s;
        s.peelPasses = b.peels;
        v.push_back({"baked", bakedSetting(b.resolution, b.levels, b.peels), s, b.resolution, b.levels});
    }
    return v;
}

/// The shipped scenes of the stability matrix, one scenario each.
std::vector<SceneEntry> matrixScenes() {
    return {{"fur-bunny.json", "whole object"},
            {"fur-bunny-far.json", "far view"},
            {"fur-bunny-close.json", "close-up"},
            {"grass-plane-grazing.json", "grazing angle"},
            {"lichen-torus.json", "semi-transparent overlap"},
            {"ring-sphere.json", "ring kernel"},
            {"bench/fur-dense-bunny.json", "high density"},
            {"bench/flakes-sphere.json", "1e4:1 anisotropy"},
            {"bench/grass-plane-top.json", "thin flat blades"}};
}

Suite makeSuite(const std::string& name) {
    Suite s;
    s.name = name;
    if (name == "quick") {
        // 128 px: below that the close-up's strands are sub-pixel and the methods' ranking is
        // decided by EWA rather than by compositing.
        s.frames = 5;
        s.referenceSpp = 16;
        s.scenes = {{"fur-bunny.json", "whole object", 0, 0, true},
                    {"fur-bunny-close.json", "close-up", 0, 0, true}};
        s.variants = variants(Variants::Quick);
        s.animated = {{SPOT_SOURCE_DIR "/examples/animated/tail-fur.json", "animated"}};
    } else if (name == "full") {
        s.frames = 7;
        s.referenceSpp = 64;
        s.scenes = matrixScenes();
        s.variants = variants(Variants::Full);
        s.scaling = true;
        s.animated = {{SPOT_SOURCE_DIR "/examples/animated/tail-fur.json", "animated"},
                      {SPOT_SOURCE_DIR "/examples/animated/tuft-grass.json", "animated, wind"}};
    } else if (name == "realtime") {
        // The interactive sizes: every scene at 640x480, and the real-time target, 50,000 fur
        // kernels at 1024x1024. References at 16 spp, a 5-frame orbit (references dominate the
        // run time at these sizes).
        s.width = 640;
        s.height = 480;
        s.frames = 5;
        s.referenceSpp = 16;
        s.orbitFrames = 5;
        s.scenes = matrixScenes();
        s.scenes.push_back({"bench/fur-bunny-50k.json", "real-time target", 1024, 1024});
        s.variants = variants(Variants::Realtime);
    } else {
        throw InputError(cat("spotshell bench: unknown suite '", name, "' (quick, full or realtime)"));
    }
    return s;
}

/// FNV-1a, 64 bits: the reference cache key.
std::uint64_t fnv(const std::string& text, std::uint64_t h = 1469598103934665603ull) {
    for (unsigned char c : text) {
        h ^= c;
        h *= 1099511628211ull;
    }
    return h;
}

std::string slurp(const fs::path& file) {
    if (file.string().rfind("generated:", 0) == 0)
        return file.string();
    return readFileCapped(file, 1ull << 30);
}

/// The camera of orbit frame k: the eye turned k steps about the target's up axis.
noise::Camera orbit(noise::Camera c, int k, double stepDeg) {
    const double a = k * stepDeg * M_PI / 180.0;
    const glm::dvec3 up = glm::normalize(c.up), d = c.eye - c.target;
    const glm::dvec3 along = up * glm::dot(up, d), across = d - along;
    c.eye = c.target + along + across * std::cos(a) + glm::cross(up, across) * std::sin(a);
    return c;
}

/// Mean absolute difference of consecutive frames (display values), averaged over the orbit.
double flicker(const std::vector<noise::Image>& frames) {
    double sum = 0.0;
    for (std::size_t k = 1; k < frames.size(); ++k)
        sum += splat::compareImages(frames[k - 1], frames[k]).meanAbs;
    return frames.size() > 1 ? sum / double(frames.size() - 1) : 0.0;
}

std::uint64_t hostResidentBytes() {
    std::ifstream status("/proc/self/status");
    std::string key;
    while (status >> key) {
        std::uint64_t kb = 0;
        if (key == "VmRSS:" && status >> kb)
            return kb * 1024;
        status.ignore(1 << 20, '\n');
    }
    return 0;
}

double percentile(std::vector<double> v, double p) {
    if (v.empty())
        return 0.0;
    std::sort(v.begin(), v.end());
    const double at = p * double(v.size() - 1);
    const std::size_t lo = std::size_t(std::floor(at)), hi = std::min(lo + 1, v.size() - 1);
    return v[lo] + (v[hi] - v[lo]) * (at - double(lo));
}

struct Bench {
    splat::Context ctx;
    fs::path out;
    fs::path scenesDir;
    Suite suite;
    json rows = json::array();

    /// The reference for one scene, camera and size, from the cache or rendered.
    noise::Image reference(const fs::path& sceneFile, cli::SceneJob& job, const noise::Camera& cam) {
        std::ostringstream key;
        key << kReferenceVersion << slurp(sceneFile) << slurp(job.scene.preset) << job.scene.mesh
            << cam.eye.x << cam.eye.y << cam.eye.z << cam.width << "x" << cam.height << " "
            << suite.referenceSpp << " shading " << int(job.scene.shading.mode);
        const fs::path cached = out / "cache" / cat(std::hex, fnv(key.str()), ".exr");
        if (fs::exists(cached))
            return noise::readImage(cached);
        if (job.impulses.empty())
            job.impulses = job.generator->generate();
        // The registry's `reference`, as `render --method reference` runs it.
        const splat::MethodInfo& method = splat::method("reference");
        splat::RenderSettings settings;
        settings.spp = suite.referenceSpp;
        const splat::CpuScene scene{
            job.mesh,       job.generator->kernel(),
            job.impulses,   {cam, job.scene.shading, job.scene.background, job.scene.baseColor},
            job.scene.seed, job.scene.referenceSpp};
        const noise::Image image = method.renderCpu(scene, settings, {}).image;
        noise::writeImage(cached, image, {{"method", "reference"}});
        return image;
    }

    struct Frame {
        noise::Image image;
        double gpuMs = 0.0, wallMs = 0.0;
        double splatMs = 0.0; ///< the splat pass alone (splatting methods)
        std::uint32_t generated = 0, drawn = 0;
        std::uint64_t fragments = 0, covered = 0; ///< counted frames (countFragments)
    };

    /// One frame of the scene's persistent frame (impulses regenerated only when the visible cells
    /// or the level of detail change, as in an interactive view).
    Frame render(cli::SceneJob& job, splat::Frame& frame, const noise::Camera& cam,
                 const Variant& v, bool image = true) {
        Frame f;
        const splat::View view{cam, job.scene.shading, job.scene.background, job.scene.baseColor};
        const splat::FrameStats stats = frame.render(v.method, view, v.settings, image ? &f.image : nullptr);
        f.gpuMs = stats.gpuMs;
        f.wallMs = stats.wallMs;
        f.drawn = stats.counters.kernelsDrawn;
        f.generated = stats.kernelsGenerated;
        f.fragments = stats.counters.fragmentsShaded;
        f.covered = stats.counters.pixelsCovered;
        for (const auto& [pass, ms] : stats.passMs)
            if (pass == "splat")
                f.splatMs = ms;
        return f;
    }

    /// The bakes of this run by cache key (bench_bake.h), and the refused ones with the reason.
    std::map<std::string, BenchBake> bakes{};
    std::map<std::string, std::string> refusedBakes{};

    /// The bake baked variant `v` renders on `job`'s scene, found in DIR/cache or made now; sets
    /// v.settings.bake (read once for the variant) and the row's bake columns. InputError when the
    /// bake is refused.
    void prepareBake(cli::SceneJob& job, const std::string& meshBytes, Variant& v, json& row) {
        BenchBakeInputs in;
        in.mesh = meshBytes;
        in.preset = slurp(job.scene.preset);
        in.seed = job.scene.seed;
        in.voxelSize = voxelSizeForResolution(job.mesh, v.bakeResolution);
        in.levels = v.bakeLevels;
        row.update({{"resolution", v.bakeResolution}, {"voxel_size", in.voxelSize},
                    {"levels", v.bakeLevels}, {"peel_passes", v.settings.peelPasses}});
        // What the renderer would refuse is refused before baking.
        splat::requireBakedView({job.scene.camera, job.scene.shading, job.scene.background,
                                 job.scene.baseColor});
        const std::string key = benchBakeKey(in);
        if (const auto r = refusedBakes.find(key); r != refusedBakes.end())
            throw InputError(r->second);
        auto it = bakes.find(key);
        if (it == bakes.end()) {
            try {
                it = bakes.emplace(key, benchBake(out / "cache", *job.generator, in, job.preset.name)).first;
            } catch (const InputError& e) {
                refusedBakes[key] = cat("bake refused: ", oneLine(e.what()));
                throw InputError(refusedBakes[key]);
            }
        }
        row.update({{"bake_seconds", it->second.seconds}, {"bake_bytes", it->second.bytes},
                    {"bake_cached", it->second.cached}});
        v.settings.bake = splat::BakeData::load(it->second.file.string());
    }

    json runVariant(const SceneEntry& entry, cli::SceneJob& job, splat::Frame& frame,
                    Variant v, const noise::Image& ref, double refFlicker,
                    double rooflineMs, const std::string& meshBytes) {
        json row = {{"scene", job.scene.name}, {"scenario", entry.scenario}, {"method", v.method},
                    {"setting", v.setting}, {"width", job.scene.camera.width},
                    {"rays_per_pixel", v.method == "raymarch" ? v.settings.supersample * v.settings.supersample : 0},
                    {"height", job.scene.camera.height},
                    {"shading", noise::Shading::modeName(job.scene.shading.mode)}};
        const splat::MethodInfo& method = splat::gpuMethod(v.method);
        const bool baked = method.takes(splat::settings::bake);
        try {
            if (baked)
                prepareBake(job, meshBytes, v, row);
            // The method's settings as its descriptors write them (what `render --stats` gives).
            row["settings"] = cli::describe(method, v.settings);
            ctx.resetPeak();
            // One cold frame, then the slow orbit (the view turns 0.5 degrees a frame, the work
            // stays the same): frame 0 is the scene's own camera and gives the error, and the
            // orbit gives the flicker. Then the timed warm frames (Suite::timedFrames).
            render(job, frame, job.scene.camera, v);
            std::vector<noise::Image> frames;
            std::vector<double> orbitGpu, orbitWall;
            Frame last;
            for (int k = 0; k < suite.orbitFrames; ++k) {
                Frame f = render(job, frame, orbit(job.scene.camera, k, suite.orbitDeg), v);
                frames.push_back(f.image);
                orbitGpu.push_back(f.gpuMs);
                orbitWall.push_back(f.wallMs);
                if (k == 0)
                    last = std::move(f);
            }
            // The orbit's frames are timed too: each has a new view (the visible cells picked
            // again, the impulses regenerated when they change) and reads its image back, as an
            // interactive window turning the camera does.
            row["orbit_ms_median"] = percentile(orbitGpu, 0.5);
            row["orbit_wall_ms_median"] = percentile(orbitWall, 0.5);
            std::vector<double> gpu, wall, splatPass;
            double timedWall = 0.0;
            while (int(gpu.size()) < suite.timedFrames ||
                   (timedWall < suite.timedMs && int(gpu.size()) < suite.maxTimedFrames)) {
                const Frame f = render(job, frame, job.scene.camera, v, false);
                gpu.push_back(f.gpuMs);
                wall.push_back(f.wallMs);
                splatPass.push_back(f.splatMs);
                timedWall += f.wallMs;
            }
            row["timed_frames"] = int(gpu.size());
            row["timed_wall_ms"] = timedWall;
            // The methods with a splat pass are those that count its fragments.
            if (method.takes(splat::settings::countFragments)) {
                // The splat pass against the rasterizer's own cost for the same primitives.
                const double splatMs = percentile(splatPass, 0.5);
                row["splat_ms_median"] = splatMs;
                row["roofline_splat_ms"] = rooflineMs;
                row["roofline_fraction"] = splatMs > 0.0 ? rooflineMs / splatMs : 0.0;
                // Fragment efficiency: fragments shaded against the pixels where a kernel's alpha
                // reaches 1/255, summed over kernels (one more frame, counted, not timed).
                Variant counted = v;
                counted.settings.countFragments = true;
                const Frame c = render(job, frame, job.scene.camera, counted, false);
                row["fragments_shaded"] = c.fragments;
                row["pixels_covered"] = c.covered;
                row["fragment_efficiency"] =
                    c.covered > 0 ? double(c.fragments) / double(c.covered) : 0.0;
            }
            const splat::ImageMetrics m = splat::compareImages(ref, last.image);
            const double flick = flicker(frames) - refFlicker;
            std::size_t nonFinite = 0;
            for (const glm::vec3& p : last.image.pixels)
                nonFinite += !std::isfinite(p.r + p.g + p.b);
            row.update({{"kernels_generated", last.generated},
                        {"kernels_drawn", last.drawn},
                        {"ms_median", percentile(gpu, 0.5)},
                        {"ms_p90", percentile(gpu, 0.9)},
                        {"wall_ms_median", percentile(wall, 0.5)},
                        {"psnr", std::isfinite(m.psnr) ? m.psnr : 99.0},
                        {"ssim", m.ssim},
                        {"flip", m.flip},
                        {"bias", m.bias},
                        {"mean_diff_display", m.meanDiffDisplay},
                        {"flicker", flick},
                        {"gpu_memory_bytes", ctx.peakAllocatedBytes()},
                        {"host_memory_bytes", hostResidentBytes()}});
            const splat::ValidationCounts val = ctx.validation();
            if (nonFinite > 0) {
                row["status"] = "failed";
                row["reason"] = cat(nonFinite, " non-finite pixels");
            } else if (val.errors > 0) {
                row["status"] = "failed";
                row["reason"] = cat(val.errors, " validation errors");
            } else if (m.flip > kDegradedFlip || flick > kDegradedFlicker) {
                row["status"] = "degraded";
                row["reason"] = m.flip > kDegradedFlip ? cat("FLIP ", m.flip, " > ", kDegradedFlip)
                                                        : cat("flicker +", flick, " > ", kDegradedFlicker);
            } else {
                row["status"] = "ok";
                row["reason"] = "";
            }
        } catch (const InputError& e) {
            // baked refuses what it cannot render (Lambert shading, bricks beyond the device's
            // buffers, a bake over the memory budget): a limit of the method, recorded as such.
            row["status"] = baked ? "refused" : "failed";
            row["reason"] = oneLine(e.what());
        } catch (const std::exception& e) {
            row["status"] = "failed";
            row["reason"] = oneLine(e.what());
        }
        return row;
    }

    void runScene(const SceneEntry& entry, cli::ProgressBar& bar, int& done, int total) {
        const fs::path file = scenesDir / entry.file;
        cli::SceneJob job = cli::loadSceneJob(file, entry.width > 0 ? entry.width : suite.width,
                                              entry.height > 0 ? entry.height : suite.height, false);
        if (entry.unlit)
            job.scene.shading = noise::Shading{};
        const noise::Image ref = reference(file, job, job.scene.camera);
        std::vector<noise::Image> refOrbit;
        refOrbit.reserve(std::size_t(suite.orbitFrames));
        for (int k = 0; k < suite.orbitFrames; ++k)
            refOrbit.push_back(reference(file, job, orbit(job.scene.camera, k, suite.orbitDeg)));
        const double refFlicker = flicker(refOrbit);
        splat::Frame frame(ctx, job.mesh, *job.generator);
        // The roofline: the same quads over the same pixels with trivial shaders (when a
        // splatting method is benched).
        Variant roofline{"oit", "roofline", splatSettings(true, splat::OitWeight::McGuireBavoil, 0)};
        roofline.settings.roofline = true;
        std::vector<double> rooflineMs;
        const bool splatting =
            std::any_of(suite.variants.begin(), suite.variants.end(), [](const Variant& v) {
                return splat::gpuMethod(v.method).takes(splat::settings::countFragments);
            });
        for (int f = 0; splatting && f <= suite.frames; ++f) {
            const Frame fr = render(job, frame, job.scene.camera, roofline, false);
            if (f > 0)
                rooflineMs.push_back(fr.splatMs);
        }
        const double rooflineMedian = percentile(rooflineMs, 0.5);
        // The mesh's bytes, for the bake cache's keys.
        std::string meshBytes;
        if (std::any_of(suite.variants.begin(), suite.variants.end(), [](const Variant& v) {
                return splat::gpuMethod(v.method).takes(splat::settings::bake);
            }))
            meshBytes = slurp(job.scene.mesh);
        for (const Variant& v : suite.variants) {
            json row = runVariant(entry, job, frame, v, ref, refFlicker, rooflineMedian, meshBytes);
            row["reference_flicker"] = refFlicker;
            rows.push_back(row);
            bar.update(++done, total);
        }
    }

    /// An animated scene (docs/design.md section 6) over suite.clipFrames consecutive frames of
    /// its clip, per GPU method (baked with one bake of the rest pose): the median frame
    /// of the persistent frame animated against the same frame static (the rest pose, nothing
    /// moving), the update passes' share (deform and move), the error against the reference at
    /// each frame, and the flicker over the clip against the reference's.
    void runAnimated(const SceneEntry& entry) {
        cli::SceneJob job = cli::loadSceneJob(entry.file, suite.width, suite.height, true);
        std::vector<double> times;
        for (int k = 0; k < suite.clipFrames; ++k)
            times.push_back(job.scene.animation.time + k / job.scene.animation.fps);
        std::vector<noise::Image> refs;
        const splat::MethodInfo& reference = splat::method("reference");
        splat::RenderSettings refSettings;
        refSettings.spp = suite.referenceSpp;
        const splat::View view{job.scene.camera, job.scene.shading, job.scene.background,
                               job.scene.baseColor};
        for (const double t : times) {
            job.poseAt(t);
            const splat::CpuScene scene{job.renderedMesh(), job.generator->kernel(), job.impulses,
                                        view, job.scene.seed, job.scene.referenceSpp};
            refs.push_back(reference.renderCpu(scene, refSettings, {}).image);
        }
        const double refFlicker = flicker(refs);
        // Each method once, with its first variant's settings (baked: its bake of the rest pose,
        // which serves every frame).
        std::vector<Variant> chosen;
        for (const Variant& v : suite.variants)
            if (std::none_of(chosen.begin(), chosen.end(),
                             [&](const Variant& c) { return c.method == v.method; }))
                chosen.push_back(v);
        const std::string meshBytes = slurp(job.scene.mesh);
        for (Variant v : chosen) {
            const std::string& method = v.method;
            json row = {{"scene", job.scene.name}, {"scenario", entry.scenario}, {"method", method},
                        {"setting", v.setting},
                        {"width", job.scene.camera.width}, {"height", job.scene.camera.height},
                        {"clip_frames", times.size()}, {"reference_flicker", refFlicker}};
            try {
                if (splat::gpuMethod(method).takes(splat::settings::bake))
                    prepareBake(job, meshBytes, v, row);
                const splat::RenderSettings& settings = v.settings;
                std::vector<double> shell; // baked: the shell rebuilt from the posed mesh
                int regenerated = 0;       // frames whose visible cells changed
                std::vector<double> still, animated, update, psnr;
                {
                    splat::Frame frame(ctx, job.mesh, *job.generator);
                    for (int k = 0; k <= suite.timedFrames; ++k) {
                        const splat::FrameStats s = frame.render(method, view, settings);
                        if (k > 0)
                            still.push_back(s.gpuMs);
                    }
                }
                splat::Frame frame(ctx, job.mesh, *job.generator);
                frame.animate(job.animation, job.scene.wind);
                std::vector<noise::Image> images;
                for (std::size_t k = 0; k < times.size(); ++k) {
                    frame.setTime(times[k]);
                    noise::Image image;
                    const splat::FrameStats s = frame.render(method, view, settings, &image);
                    double passes = 0.0;
                    double shellMs = 0.0;
                    for (const auto& [pass, ms] : s.passMs) {
                        if (pass == "deform" || pass == "move")
                            passes += ms;
                        if (pass == "shell")
                            shellMs += ms;
                    }
                    regenerated += s.regenerated;
                    if (k > 0) { // the first frame compiles and generates
                        animated.push_back(s.gpuMs);
                        update.push_back(passes);
                        shell.push_back(shellMs);
                    }
                    psnr.push_back(splat::psnr(refs[k], image));
                    images.push_back(std::move(image));
                }
                double meanPsnr = 0.0;
                for (const double p : psnr)
                    meanPsnr += p / double(psnr.size());
                row.update({{"static_ms", percentile(still, 0.5)},
                            {"animated_ms", percentile(animated, 0.5)},
                            {"update_ms", percentile(update, 0.5)},
                            {"animated_over_static",
                             percentile(animated, 0.5) / std::max(percentile(still, 0.5), 1e-9)},
                            {"psnr", meanPsnr},
                            {"flicker", flicker(images)},
                            {"status", "ok"}, {"reason", ""}});
                row["regenerated_frames"] = regenerated;
                if (!shell.empty() && percentile(shell, 0.5) > 0.0)
                    row["shell_ms"] = percentile(shell, 0.5);
            } catch (const std::exception& e) {
                row.update({{"status", "failed"}, {"reason", oneLine(e.what())}});
            }
            animatedRows.push_back(row);
        }
    }
    json animatedRows = json::array();

    /// Milliseconds and memory against visible kernels (the uniform preset on a sphere at rising
    /// density) and against resolution (fur-bunny).
    void runScaling(cli::ProgressBar& bar, int& done, int total) {
        const fs::path sphere = scenesDir / "ring-sphere.json";
        for (double density : {1e3, 4e3, 1.6e4, 6.4e4, 1.28e5}) {
            cli::SceneJob job = cli::loadSceneJob(sphere, 256, 256, false);
            job.preset = noise::loadPreset(scenesDir.parent_path() / "uniform.json");
            job.preset.distribution.densityMax = float(density);
            for (const char* method : {"oit", "hybrid"}) {
                json row = {{"scene", "uniform-sphere"}, {"scenario", "scaling-kernels"},
                            {"method", method}, {"setting", cat("density ", density)},
                            {"width", 256}, {"height", 256}};
                try {
                    noise::GeneratorOptions options;
                    options.seed = job.scene.seed;
                    job.generator = std::make_unique<noise::ImpulseGenerator>(job.mesh, job.preset, options);
                    splat::Frame frame(ctx, job.mesh, *job.generator);
                    const Variant v{method, "scaling", splatSettings(true, splat::OitWeight::McGuireBavoil, 0)};
                    ctx.resetPeak();
                    std::vector<double> gpu;
                    Frame f;
                    for (int k = 0; k <= 3; ++k) {
                        f = render(job, frame, job.scene.camera, v, false);
                        if (k > 0)
                            gpu.push_back(f.gpuMs);
                    }
                    row.update({{"kernels_generated", f.generated}, {"kernels_drawn", f.drawn},
                                {"ms_median", percentile(gpu, 0.5)}, {"ms_p90", percentile(gpu, 0.9)},
                                {"gpu_memory_bytes", ctx.peakAllocatedBytes()},
                                {"host_memory_bytes", hostResidentBytes()}, {"status", "ok"},
                                {"reason", ""}});
                } catch (const std::exception& e) {
                    row.update({{"status", "failed"}, {"reason", oneLine(e.what())}});
                }
                rows.push_back(row);
                bar.update(++done, total);
            }
        }
        for (int size : {64, 128, 256, 512}) {
            cli::SceneJob job = cli::loadSceneJob(scenesDir / "fur-bunny.json", size, size, false);
            splat::Frame frame(ctx, job.mesh, *job.generator);
            json row = {{"scene", "fur-bunny"}, {"scenario", "scaling-resolution"},
                        {"method", "hybrid"}, {"setting", cat(size, "x", size)},
                        {"width", size}, {"height", size}};
            ctx.resetPeak();
            std::vector<double> gpu;
            Frame f;
            const Variant v{"hybrid", "scaling", splatSettings(true, splat::OitWeight::McGuireBavoil, 0)};
            for (int k = 0; k <= 3; ++k) {
                f = render(job, frame, job.scene.camera, v, false);
                if (k > 0)
                    gpu.push_back(f.gpuMs);
            }
            row.update({{"kernels_generated", f.generated}, {"kernels_drawn", f.drawn},
                        {"ms_median", percentile(gpu, 0.5)}, {"ms_p90", percentile(gpu, 0.9)},
                        {"gpu_memory_bytes", ctx.peakAllocatedBytes()},
                        {"host_memory_bytes", hostResidentBytes()}, {"status", "ok"}, {"reason", ""}});
            rows.push_back(row);
            bar.update(++done, total);
        }
    }
};

/// The stability matrix's column of a row: the method, except that the ray-march without a pixel
/// filter and the bake without mips (level 0 only) are columns of their own.
std::string matrixColumn(const json& r) {
    const std::string method = r["method"];
    if (r.value("rays_per_pixel", 0) == 1)
        return method + " (1 ray/pixel)";
    if (method == "baked" && r.value("levels", 0) == 1)
        return method + " (no mips)";
    return method;
}

/// A row with measurements (status ok or degraded).
bool measured(const json& r) {
    return (r["status"] == "ok" || r["status"] == "degraded") && r.contains("flip");
}

std::string fmt(const char* format, auto... args) {
    char buf[512];
    std::snprintf(buf, sizeof buf, format, args...);
    return buf;
}

/// What the baked rows show, as sentences made from this run's numbers: in every far view, the
/// coarse mip levels against level 0 alone at the same voxel size and peel passes, and baked's
/// speed-up over hybrid's default setting with whether its FLIP is at most hybrid's.
std::vector<std::string> bakedFindings(const json& rows) {
    std::vector<std::string> out, scenes;
    for (const json& r : rows)
        if (r["scenario"] == "far view" && r["method"] == "baked" &&
            std::find(scenes.begin(), scenes.end(), r["scene"]) == scenes.end())
            scenes.push_back(r["scene"]);
    for (const std::string& scene : scenes) {
        std::vector<const json*> baked;
        const json* hybrid = nullptr;
        for (const json& r : rows) {
            if (r["scene"] != scene || r["scenario"] != "far view" || !measured(r))
                continue;
            if (r["method"] == "baked")
                baked.push_back(&r);
            else if (r["method"] == "hybrid" && r["setting"] == "ewa mb analytic")
                hybrid = &r;
        }
        if (baked.empty()) {
            out.push_back(cat("Far view (", scene, "): no baked row was measured."));
            continue;
        }
        // Mips: each setting with coarse levels against the same bake without them.
        for (const json* m : baked) {
            if (m->value("levels", 1) <= 1)
                continue;
            for (const json* z : baked) {
                if (z->value("levels", 1) != 1 || (*z)["resolution"] != (*m)["resolution"] ||
                    (*z)["peel_passes"] != (*m)["peel_passes"])
                    continue;
                const double fm = (*m)["flip"], fz = (*z)["flip"];
                out.push_back(fmt("Far view (%s), resolution %d, %d peel passes: with %d mip levels "
                                  "FLIP %.4f (PSNR %.2f dB), level 0 alone FLIP %.4f (PSNR %.2f dB): "
                                  "the coarse levels match the reference %s.",
                                  scene.c_str(), int((*m)["resolution"]), int((*m)["peel_passes"]),
                                  int((*m)["levels"]), fm, double((*m)["psnr"]), fz,
                                  double((*z)["psnr"]),
                                  fm <= fz ? "no worse than level 0 does"
                                           : fmt("worse than level 0 does (FLIP +%.4f)", fm - fz).c_str()));
            }
        }
        // Speed: baked's most accurate setting, and its fastest one at most as wrong as hybrid.
        if (!hybrid)
            continue;
        const double hMs = (*hybrid)["ms_median"], hFlip = (*hybrid)["flip"];
        const json* acc = *std::min_element(baked.begin(), baked.end(), [](const json* a, const json* b) {
            return double((*a)["flip"]) < double((*b)["flip"]);
        });
        const json* fast = nullptr;
        for (const json* r : baked)
            if (double((*r)["flip"]) <= hFlip && (!fast || double((*r)["ms_median"]) < double((*fast)["ms_median"])))
                fast = r;
        // GPU time and wall time both: lavapipe's timestamps miss work in frames that draw
        // nothing, as hybrid's far view (every kernel on the compute path) does (docs/design.md
        // section 8).
        const double hWall = hybrid->value("wall_ms_median", 0.0);
        auto against = [&](const char* what, const json& r) {
            const double ms = r["ms_median"], flip = r["flip"];
            const double wall = r.value("wall_ms_median", 0.0);
            return fmt("Far view (%s): baked's %s setting (%s) takes %.2f ms (wall %.2f ms) against "
                       "hybrid's (ewa mb analytic) %.2f ms (wall %.2f ms), a speed-up of %.2fx (wall "
                       "%.2fx); its FLIP %.4f is %s hybrid's %.4f.",
                       scene.c_str(), what, std::string(r["setting"]).c_str(), ms, wall, hMs, hWall,
                       ms > 0.0 ? hMs / ms : 0.0, wall > 0.0 ? hWall / wall : 0.0, flip,
                       flip <= hFlip ? "<=" : ">", hFlip);
        };
        out.push_back(against("most accurate", *acc));
        if (fast && fast != acc)
            out.push_back(against("fastest at most hybrid's FLIP", *fast));
        else if (!fast)
            out.push_back(cat("Far view (", scene, "): no baked setting reaches hybrid's FLIP."));
    }
    return out;
}

/// The stability matrix as markdown: scenario rows, method columns, error / flicker / verdict.
std::string stabilityMarkdown(const json& rows, const Suite& suite) {
    std::vector<std::string> methods;
    std::vector<std::pair<std::string, std::string>> scenarios; // scenario, scene
    std::map<std::pair<std::string, std::string>, json> best;  // (scenario, method) -> best row
    for (const json& r : rows) {
        const std::string scenario = r["scenario"];
        if (scenario.rfind("scaling", 0) == 0)
            continue;
        // The ray-march without a pixel filter is a column of its own: it fails where the
        // filtered one does not. So is the bake without mips: it aliases where they do not.
        const std::string method = matrixColumn(r);
        if (std::find(methods.begin(), methods.end(), method) == methods.end())
            methods.push_back(method);
        if (std::find_if(scenarios.begin(), scenarios.end(), [&](auto& s) { return s.first == scenario; }) ==
            scenarios.end())
            scenarios.emplace_back(scenario, r["scene"]);
        json& b = best[{scenario, method}];
        const auto unusable = [](const json& x) { return x["status"] == "failed" || x["status"] == "refused"; };
        const bool better = b.is_null() || (!unusable(r) && (unusable(b) || r.value("flip", 1.0) < b.value("flip", 1.0)));
        if (better)
            b = r;
    }
    std::ostringstream md;
    md << "# Stability matrix (suite " << suite.name << ", " << suite.width << "x" << suite.height
       << ")\n\nEach cell: the method's best setting on the scenario (least FLIP; named in "
          "italics): FLIP against the reference / "
          "temporal flicker above the reference's own (mean display difference between frames of "
          "a slow "
       << suite.orbitFrames << "-frame orbit) / verdict. Verdicts: **ok**; **degraded** when FLIP > "
       << kDegradedFlip << " or flicker > +" << kDegradedFlicker
       << "; **failed** with the reason (non-finite pixels, validation errors, refused); "
          "**refused** with the reason where baked declines what it cannot render (Lambert "
          "shading, a bake beyond the device's buffers or the memory budget). baked (no mips) is the bake "
          "with level 0 only, baked the bake with coarser levels.\n\n| "
          "scenario (scene) |";
    for (const std::string& m : methods)
        md << " " << m << " |";
    md << "\n| --- |";
    for (std::size_t i = 0; i < methods.size(); ++i)
        md << " --- |";
    md << "\n";
    for (const auto& [scenario, scene] : scenarios) {
        md << "| " << scenario << " (" << scene << ") |";
        for (const std::string& m : methods) {
            const json& r = best[{scenario, m}];
            if (r.is_null()) {
                md << " - |";
                continue;
            }
            if (r["status"] == "failed" || r["status"] == "refused") {
                md << " " << std::string(r["status"]) << ": " << std::string(r["reason"]) << " |";
                continue;
            }
            char cell[160];
            std::snprintf(cell, sizeof cell, " %.3f / %+.4f / %s _(%s)_ |", double(r["flip"]),
                          double(r["flicker"]), std::string(r["status"]).c_str(),
                          std::string(r["setting"]).c_str());
            md << cell;
        }
        md << "\n";
    }
    const std::vector<std::string> findings = bakedFindings(rows);
    if (!findings.empty()) {
        md << "\n## Baked in the far view\n\n";
        for (const std::string& f : findings)
            md << "- " << f << "\n";
    }
    return md.str();
}

/// The animated scenes' table (Bench::runAnimated).
std::string animatedMarkdown(const json& rows) {
    if (rows.empty())
        return "";
    std::ostringstream md;
    md << "\n# Animated scenes\n\nPer method over the clip's frames: the median frame (GPU ms) "
          "static and animated, the update passes (deform + move), the mean PSNR against the "
          "reference at each frame, and the flicker (mean absolute change between consecutive "
          "frames) against the reference's. baked renders every frame from one bake of the rest pose; "
          "its shell, rebuilt from the posed mesh each frame, is in brackets.\n\n"
          "| scene | method | static ms | animated ms | ratio | update ms | PSNR dB | flicker | "
          "reference flicker |\n|---|---|---|---|---|---|---|---|---|\n";
    for (const json& r : rows) {
        if (r.value("status", "") != "ok") {
            md << "| " << r.value("scene", "") << " | " << r.value("method", "") << " | "
               << r.value("reason", "") << " | | | | | | |\n";
            continue;
        }
        md << "| " << r.value("scene", "") << " | " << r.value("method", "") << " | "
           << fmt("%.1f", r.value("static_ms", 0.0)) << " | "
           << fmt("%.1f", r.value("animated_ms", 0.0)) << " | "
           << fmt("%.2f", r.value("animated_over_static", 0.0)) << " | "
           << fmt("%.2f", r.value("update_ms", 0.0))
           << (r.contains("shell_ms") ? fmt(" (shell %.2f)", r.value("shell_ms", 0.0)) : "")
           << " | " << fmt("%.2f", r.value("psnr", 0.0))
           << " | " << fmt("%.4f", r.value("flicker", 0.0)) << " | "
           << fmt("%.4f", r.value("reference_flicker", 0.0)) << " |\n";
    }
    return md.str();
}

void writeCsv(const fs::path& file, const json& rows) {
    const char* cols[] = {"scene", "scenario", "method", "setting", "width", "height",
                          "kernels_generated", "kernels_drawn", "ms_median", "ms_p90",
                          "splat_ms_median", "roofline_splat_ms", "roofline_fraction",
                          "fragments_shaded", "pixels_covered", "fragment_efficiency",
                          "wall_ms_median", "psnr", "ssim", "flip", "flicker", "reference_flicker",
                          "gpu_memory_bytes", "host_memory_bytes", "status", "reason",
                          // baked's (appended, so that the columns before keep their places)
                          "resolution", "voxel_size", "levels", "peel_passes", "bake_seconds",
                          "bake_bytes", "bake_cached",
                          // appended likewise
                          "timed_frames", "orbit_ms_median", "orbit_wall_ms_median",
                          // the mean brightness against the reference (compare's bias)
                          "bias", "mean_diff_display"};
    writeFileAtomic(file, [&](std::ostream& o) {
        for (std::size_t i = 0; i < std::size(cols); ++i)
            o << (i ? "," : "") << cols[i];
        o << "\n";
        for (const json& r : rows) {
            for (std::size_t i = 0; i < std::size(cols); ++i) {
                o << (i ? "," : "");
                if (!r.contains(cols[i]))
                    continue;
                const json& v = r[cols[i]];
                if (v.is_string()) {
                    std::string s = v;
                    std::replace(s.begin(), s.end(), '"', '\'');
                    o << '"' << s << '"';
                } else {
                    o << v.dump();
                }
            }
            o << "\n";
        }
    });
}

/// Keep the items whose name (by `name`) is in the comma-separated `list`; InputError naming the
/// suite's names for a name that matches none.
template <typename T, typename Name>
void restrict(std::vector<T>& items, const std::string& list, const char* option, const char* what,
              Name name) {
    std::vector<std::string> wanted;
    std::stringstream in(list);
    for (std::string w; std::getline(in, w, ',');)
        if (!w.empty())
            wanted.push_back(w);
    std::string known;
    for (const T& item : items)
        if (known.find(cat(" ", name(item), ",")) == std::string::npos)
            known += cat(" ", name(item), ",");
    for (const std::string& w : wanted)
        if (std::none_of(items.begin(), items.end(), [&](const T& i) { return name(i) == w; }))
            throw InputError(cat("spotshell bench: ", option, " ", w, ": no ", what,
                                 " of that name in the suite (", known.substr(1, known.size() - 2), ")"));
    if (wanted.empty())
        throw InputError(cat("spotshell bench: ", option, " names no ", what));
    std::erase_if(items, [&](const T& i) {
        return std::find(wanted.begin(), wanted.end(), name(i)) == wanted.end();
    });
}

} // namespace

int bench(int argc, char** argv) {
    cli::Args args("bench",
                   "Render every scene x method x setting, measure speed, error against the "
                   "reference, flicker and memory; write results.csv/json, pareto.png, "
                   "stability.md/png and scaling.png into DIR.",
                   {{"suite", "NAME", "quick (a few minutes), full (every scene at 128x128) or realtime (every "
                                      "scene at 640x480 and 50k fur kernels at 1024x1024); default quick", false},
                    {"out", "DIR", "output folder (created; references and bakes are cached in DIR/cache)", true},
                    {"scenes", "DIR", "scene folder (default: presets/scenes next to the source)", false},
                    {"only", "NAMES", "bench only these of the suite's scenes, comma-separated file "
                                      "names without .json (e.g. fur-bunny-far,fur-bunny-close); "
                                      "skips the scaling runs", false},
                    {"methods", "NAMES", "bench only these methods, comma-separated (e.g. "
                                         "hybrid,baked); skips the scaling runs", false},
                    cli::threadsOption()},
                   argc, argv);
    if (args.helpRequested()) {
        std::fputs(args.usage().c_str(), stdout);
        return 0;
    }
    Suite suite = makeSuite(args.str("suite", "quick"));
    if (args.has("only")) {
        // The names of animated scenes keep those; the others restrict the static ones.
        std::string staticNames;
        std::vector<SceneEntry> animated;
        std::stringstream list(args.str("only"));
        for (std::string name; std::getline(list, name, ',');) {
            const auto it = std::find_if(suite.animated.begin(), suite.animated.end(), [&](const SceneEntry& e) {
                return fs::path(e.file).stem().string() == name;
            });
            if (it != suite.animated.end())
                animated.push_back(*it);
            else
                staticNames += (staticNames.empty() ? "" : ",") + name;
        }
        suite.animated = animated;
        if (staticNames.empty())
            suite.scenes.clear();
        else
            restrict(suite.scenes, staticNames, "--only", "scene",
                     [](const SceneEntry& e) { return fs::path(e.file).stem().string(); });
        suite.scaling = false;
    }
    if (args.has("methods")) {
        restrict(suite.variants, args.str("methods"), "--methods", "method",
                 [](const Variant& v) { return v.method; });
        suite.scaling = false;
    }
    // Each quality's choice is a row of the run (the check below needs it): the suite's own when
    // it has the choice's method and settings, else one more row. Not when --methods chose.
    if (!args.has("methods"))
        for (const splat::QualityChoice& q : splat::qualityChoices()) {
            const splat::MethodInfo& m = splat::gpuMethod(q.method);
            const json want = cli::describe(m, q.settings);
            if (std::none_of(suite.variants.begin(), suite.variants.end(), [&](const Variant& v) {
                    return v.method == q.method && cli::describe(m, v.settings) == want;
                }))
                suite.variants.push_back({q.method, cat("quality ", q.name), q.settings});
        }
    Bench b{splat::Context(), fs::path(args.str("out")),
            fs::path(args.str("scenes", SPOT_SOURCE_DIR "/presets/scenes")), std::move(suite),
            json::array()};
    std::error_code ec;
    fs::create_directories(b.out / "cache", ec);
    if (ec)
        throw InputError(cat("spotshell bench: cannot create ", (b.out / "cache").string(), " (", ec.message(), ")"));
    if (!fs::is_directory(b.scenesDir))
        throw InputError(cat("spotshell bench: scene folder ", b.scenesDir.string(), " does not exist"));

    const int total = int(b.suite.scenes.size() * b.suite.variants.size()) + (b.suite.scaling ? 14 : 0);
    int done = 0;
    cli::ProgressBar bar("bench " + b.suite.name);
    for (const SceneEntry& entry : b.suite.scenes)
        b.runScene(entry, bar, done, total);
    if (b.suite.scaling)
        b.runScaling(bar, done, total);
    for (const SceneEntry& entry : b.suite.animated)
        b.runAnimated(entry);
    bar.finish();

    const QualityVerdict quality = qualityCheck(b.rows, splat::qualityChoices());
    const json doc = {{"suite", b.suite.name},
                      {"width", b.suite.width},
                      {"height", b.suite.height},
                      {"frames", b.suite.frames},
                      {"orbit_frames", b.suite.orbitFrames},
                      {"timed_frames", b.suite.timedFrames},
                      {"timed_ms", b.suite.timedMs},
                      {"max_timed_frames", b.suite.maxTimedFrames},
                      {"reference_spp", b.suite.referenceSpp},
                      {"device", b.ctx.deviceName()},
                      {"quality", quality.doc},
                      {"rows", b.rows},
                      {"animated", b.animatedRows}};
    writeFileAtomic(b.out / "results.json", [&](std::ostream& o) { o << doc.dump(2) << "\n"; });
    writeCsv(b.out / "results.csv", b.rows);
    std::string md = stabilityMarkdown(b.rows, b.suite);
    md += animatedMarkdown(b.animatedRows);
    writeFileAtomic(b.out / "stability.md", [&](std::ostream& o) { o << md; });
    drawBenchCharts(b.out);
    for (const std::string& f : bakedFindings(b.rows))
        std::printf("%s\n", f.c_str());
    std::printf("wrote %s/{results.csv,results.json,stability.md,stability.png,pareto.png%s} "
                "(%zu rows, suite %s)\n",
                b.out.string().c_str(), b.suite.scaling ? ",scaling.png" : "", b.rows.size(),
                b.suite.name.c_str());
    for (const std::string& line : quality.lines)
        std::printf("%s\n", line.c_str());
    // The quality table no longer following the measurements fails the run, after its outputs.
    for (const std::string& f : quality.failures)
        std::fprintf(stderr, "spotshell bench: %s\n", f.c_str());
    return quality.failures.empty() ? 0 : 1;
}

} // namespace spot::cmd
