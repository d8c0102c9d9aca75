#include <cstdio>

#include "cli.h"
#include "commands.h"
#include "noise/mesh.h"

namespace spot::cmd {

int info(int argc, char** argv) {
    cli::Args args("info", "Load and validate a mesh (OBJ or PLY); print its counts and bounds.",
                   {{"mesh", "FILE", "mesh to inspect (.obj or .ply)", true}}, argc, argv);
    if (args.helpRequested()) {
        std::fputs(args.usage().c_str(), stdout);
        return 0;
    }
    const noise::Mesh mesh = noise::loadMesh(args.str("mesh"));
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
