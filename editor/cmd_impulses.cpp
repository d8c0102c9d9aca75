#include <chrono>
#include <cstdio>
#include <optional>

#include <tbb/global_control.h>

#include "cli.h"
#include "commands.h"
#include "noise/animated_mesh.h"
#include "noise/deform.h"
#include "noise/error.h"
#include "noise/impulse_io.h"
#include "noise/impulses.h"
#include "noise/mesh.h"
#include "noise/preset.h"

namespace spot::cmd {

int impulses(int argc, char** argv) {
    cli::Args args("impulses",
                   "Generate the impulses of a preset on a mesh and write them as PLY points.",
                   {{"mesh", "FILE",
                     "mesh (.obj/.ply), an animated mesh (.gltf/.glb, a cache walk.%04d.ply) or "
                     "generated:sphere|torus|plane",
                     true},
                    {"time", "T",
                     "an animated mesh: the impulses generated at rest, carried to the pose at T "
                     "seconds (default: at rest)",
                     false},
                    {"clip", "NAME", "a glTF file's clip (default: its first)", false},
                    {"fps", "F", "a mesh cache's frames per second (default 24)", false},
                    {"preset", "FILE", "preset JSON (see presets/README.md)", true},
                    {"seed", "N", "global random seed (default 0)", false},
                    {"cell-size", "H", "cell edge in world units (default: the kernel's support "
                                       "radius, the smallest valid)", false},
                    {"out", "FILE", "output PLY", true},
                    cli::threadsOption()},
                   argc, argv);
    if (args.helpRequested()) {
        std::fputs(args.usage().c_str(), stdout);
        return 0;
    }
    const auto threads = args.integer("threads", 0, 0, 1024);
    std::optional<tbb::global_control> threadLimit;
    if (threads > 0)
        threadLimit.emplace(tbb::global_control::max_allowed_parallelism, std::size_t(threads));

    const auto start = std::chrono::steady_clock::now();
    const noise::AnimatedMesh animation = noise::AnimatedMesh::load(
        args.str("mesh"), args.has("clip") ? args.str("clip") : "", args.number("fps", 24.0, 1e-3, 1e3));
    const noise::Mesh& mesh = animation.rest();
    const noise::PresetDesc preset = noise::loadPreset(args.str("preset"));
    noise::GeneratorOptions options;
    options.seed = std::uint32_t(args.integer("seed", 0, 0, 0xffffffffll));
    options.cellSize = float(args.number("cell-size", 0.0, 0.0, 1e30));
    if (args.has("cell-size") && !(options.cellSize > 0.0f))
        throw InputError("spotshell impulses: --cell-size must be positive");

    const noise::ImpulseGenerator generator(mesh, preset, options);
    std::vector<noise::Impulse> impulses = generator.generate();
    std::string pose = "at rest";
    if (args.has("time")) {
        if (!animation.animated())
            throw InputError(cat("spotshell impulses: --time needs an animated mesh; ", mesh.name,
                                 " does not move"));
        noise::Deformer deformer(animation);
        deformer.pose(args.number("time", 0.0, -1e6, 1e6));
        impulses = deformer.move(impulses, generator.cellSize());
        pose = cat("at ", deformer.time(), " s");
    }
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

    const std::string out = args.str("out");
    noise::writeImpulsesPly(out, impulses,
                            {cat("spotshell impulses preset=", preset.name, " seed=", options.seed,
                                 " cell_size=", generator.cellSize()),
                             cat("mesh ", mesh.name, " ", pose)});
    std::printf("%zu cells (h = %g), %zu impulses of %s on %s, %.3f s (%.0f impulses/s)\n",
                generator.cells().cells.size(), double(generator.cellSize()), impulses.size(),
                preset.name.c_str(), mesh.name.c_str(), seconds,
                seconds > 0.0 ? double(impulses.size()) / seconds : 0.0);
    std::printf("wrote %s\n", out.c_str());
    return 0;
}

} // namespace spot::cmd
