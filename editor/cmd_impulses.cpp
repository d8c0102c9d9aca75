#include <chrono>
#include <cstdio>
#include <optional>

#include <tbb/global_control.h>

#include "cli.h"
#include "commands.h"
#include "noise/error.h"
#include "noise/impulse_io.h"
#include "noise/impulses.h"
#include "noise/mesh.h"
#include "noise/preset.h"

namespace spot::cmd {

int impulses(int argc, char** argv) {
    cli::Args args("impulses",
                   "Generate the impulses of a preset on a mesh and write them as PLY points.",
                   {{"mesh", "FILE", "mesh (.obj/.ply) or generated:sphere|torus|plane", true},
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
    const noise::Mesh mesh = noise::loadMeshOrGenerated(args.str("mesh"));
    const noise::PresetDesc preset = noise::loadPreset(args.str("preset"));
    noise::GeneratorOptions options;
    options.seed = std::uint32_t(args.integer("seed", 0, 0, 0xffffffffll));
    options.cellSize = float(args.number("cell-size", 0.0, 0.0, 1e30));
    if (args.has("cell-size") && !(options.cellSize > 0.0f))
        throw InputError("spotshell impulses: --cell-size must be positive");

    const noise::ImpulseGenerator generator(mesh, preset, options);
    const std::vector<noise::Impulse> impulses = generator.generate();
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

    const std::string out = args.str("out");
    noise::writeImpulsesPly(out, impulses,
                            {cat("spotshell impulses preset=", preset.name, " seed=", options.seed,
                                 " cell_size=", generator.cellSize()),
                             cat("mesh ", mesh.name)});
    std::printf("%zu cells (h = %g), %zu impulses of %s on %s, %.3f s (%.0f impulses/s)\n",
                generator.cells().cells.size(), double(generator.cellSize()), impulses.size(),
                preset.name.c_str(), mesh.name.c_str(), seconds,
                seconds > 0.0 ? double(impulses.size()) / seconds : 0.0);
    std::printf("wrote %s\n", out.c_str());
    return 0;
}

} // namespace spot::cmd
