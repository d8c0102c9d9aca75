#include <cstdio>

#include "cli.h"
#include "commands.h"
#include "noise/bake.h"
#include "noise/error.h"
#include "noise/mesh.h"

namespace spot::cmd {

int info(int argc, char** argv) {
    cli::Args args("info",
                   "Load and validate a mesh (OBJ or PLY) and print its counts and bounds, or read "
                   "a bake (spotshell bake) and print its levels.",
                   {{"mesh", "FILE",
                     "mesh to inspect (.obj or .ply, or generated:NAME as scenes take)", false},
                    {"bake", "FILE", "bake to inspect (.vdb written by spotshell bake)", false}},
                   argc, argv);
    if (args.helpRequested()) {
        std::fputs(args.usage().c_str(), stdout);
        return 0;
    }
    if (args.has("mesh") == args.has("bake"))
        throw InputError("spotshell info: give --mesh FILE or --bake FILE (one of them)");
    if (args.has("bake")) {
        const noise::BakedVolume bake = noise::readBakedGrids(args.str("bake"));
        std::printf("bake %s\n", args.str("bake").c_str());
        std::printf("  preset     %s (hash %016llx)\n", bake.presetName().c_str(),
                    static_cast<unsigned long long>(bake.presetHash()));
        if (bake.meshHash())
            std::printf("  mesh hash  %016llx (the rest mesh and the cell size)\n",
                        static_cast<unsigned long long>(*bake.meshHash()));
        else
            std::printf("  mesh hash  none recorded (an older bake: not checked against "
                        "the scene)\n");
        std::printf("  version    %s\n", bake.version().c_str());
        for (int l = 0; l < bake.levels(); ++l)
            std::printf("  level %d    voxel %g, %llu voxels\n", l, double(bake.voxelSize(l)),
                        static_cast<unsigned long long>(bake.activeCount(l)));
        std::printf("  distance   %llu voxels (level-0 voxels, capped at %g)\n",
                    static_cast<unsigned long long>(bake.distanceCount()),
                    double(noise::kBakeDistanceCap));
        return 0;
    }
    const noise::Mesh mesh = noise::loadMeshOrGenerated(args.str("mesh"));
    const noise::Bounds b = mesh.bounds();
    std::printf("mesh %s\n", mesh.name.c_str());
    std::printf("  vertices   %zu\n", mesh.positions.size());
    std::printf("  triangles  %zu\n", mesh.triangles.size());
    std::printf("  dropped    %zu degenerate triangles\n", mesh.droppedTriangles);
    std::printf("  bounds     [%g %g %g] .. [%g %g %g]\n", b.lo.x, b.lo.y, b.lo.z, b.hi.x, b.hi.y,
                b.hi.z);
    std::printf("  area       %g\n", mesh.surfaceArea());
    std::printf("  uv         %s\n", mesh.hasUv() ? "yes" : "no");
    return 0;
}

} // namespace spot::cmd
