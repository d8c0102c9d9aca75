// `spotshell bake`: the noise of a scene's preset on its mesh, in the rest pose, evaluated into
// sparse voxel mip levels and written as one OpenVDB file (docs/design.md section 5).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <optional>

#include <tbb/global_control.h>

#include "bench_bake.h"
#include "cli.h"
#include "commands.h"
#include "noise/bake.h"
#include "noise/error.h"
#include "noise/mesh.h"
#include "noise/system.h"
#include "progress.h"
#include "scene_job.h"

namespace spot::cmd {

namespace {

/// Presets are small JSON files; the cap only guards against a wrong path.
constexpr std::uint64_t kMaxPresetBytes = 64ull << 20;

} // namespace

int bake(int argc, char** argv) {
    std::vector<cli::OptionSpec> specs;
    for (const cli::OptionSpec& o : cli::sceneOptions())
        if (o.name != "size")
            specs.push_back(o);
    specs.insert(specs.end(), {{"voxel-size", "V",
                                "level 0's voxel edge in world units (default: the cell "
                                "size / 32)",
                                false},
                               {"resolution", "N",
                                "level 0's voxels along the mesh's longest side (instead "
                                "of --voxel-size)",
                                false},
                               {"levels", "L",
                                "mip levels: level 0 and L-1 coarser ones, each of twice the "
                                "voxel size (default 1, at most 8)",
                                false},
                               {"out", "FILE", "output OpenVDB file (.vdb)", true},
                               cli::threadsOption()});
    cli::Args args("bake",
                   "Evaluate a scene's noise (the reference's extinction and colour, the mesh's "
                   "rest pose) into sparse voxel mip levels and write one OpenVDB file: density "
                   "and color (level 0), density_lodN and color_lodN, distance.",
                   specs, argc, argv);
    if (args.helpRequested()) {
        std::fputs(args.usage().c_str(), stdout);
        return 0;
    }
    if (args.has("voxel-size") && args.has("resolution"))
        throw InputError("spotshell bake: give --voxel-size or --resolution, not both");
    const auto threads = args.integer("threads", 0, 0, 1024);
    std::optional<tbb::global_control> threadLimit;
    if (threads > 0)
        threadLimit.emplace(tbb::global_control::max_allowed_parallelism, std::size_t(threads));
    const std::filesystem::path out = args.str("out");

    const cli::SceneJob job = cli::prepareScene(args, false);
    noise::BakeOptions options;
    options.levels = int(args.integer("levels", 1, 1, noise::kMaxBakeLevels));
    options.presetName = job.preset.name;
    options.presetHash = noise::fnv1a64(readFileCapped(job.scene.preset, kMaxPresetBytes));
    options.meshHash = noise::shellHash(noise::meshHash(job.mesh), job.generator->cellSize());
    if (args.has("resolution")) {
        const auto n = args.integer("resolution", 0, 1, 1 << 24);
        try {
            options.voxelSize = voxelSizeForResolution(job.mesh, int(n));
        } catch (const InputError& e) {
            throw InputError(cat("spotshell bake: ", e.what()));
        }
    } else {
        // 32 voxels per cell edge: on fur-bunny 0.0019, about 1.7 sigmas of the thinnest lobe
        // (docs/bench/measurements.md has the measured costs).
        options.voxelSize =
            float(args.number("voxel-size", double(job.generator->cellSize()) / 32.0, 1e-30, 1e30));
    }

    // The bake checks its memory against the budget before each large allocation.
    noise::BakeStats stats;
    cli::ProgressBar bar("bake");
    const noise::BakedVolume volume = noise::bakeNoise(
        *job.generator, options, [&](long done, long total) { bar.update(done, total); }, &stats);
    bar.finish();
    noise::writeBakedGrids(out, volume);

    std::error_code ec;
    const auto bytes = std::filesystem::file_size(out, ec);
    std::string levels;
    for (int l = 0; l < volume.levels(); ++l)
        levels += cat(l == 0 ? "" : ", ", stats.activeVoxels[std::size_t(l)]);
    std::printf("wrote %s (%d level%s, voxel %g, voxels per level %s, %llu distance voxels, "
                "%zu impulses, %llu shell voxels evaluated, %.2f MiB, %.2f s; estimated peak "
                "%.0f MiB)\n",
                out.string().c_str(), volume.levels(), volume.levels() == 1 ? "" : "s",
                double(options.voxelSize), levels.c_str(),
                static_cast<unsigned long long>(stats.distanceVoxels), stats.impulses,
                static_cast<unsigned long long>(stats.evaluatedVoxels),
                ec ? 0.0 : double(bytes) / double(1 << 20), stats.seconds,
                double(stats.estimate.bytes) / double(1 << 20));
    return 0;
}

} // namespace spot::cmd
