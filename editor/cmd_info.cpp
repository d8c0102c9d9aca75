#include <cstdio>

#include "cli.h"
#include "commands.h"
#include "noise/animated_mesh.h"
#include "noise/bake.h"
#include "noise/error.h"
#include "noise/mesh.h"
#include "noise/splats_3dgs.h"

namespace spot::cmd {

int info(int argc, char** argv) {
    cli::Args args(
        "info",
        "Load and validate a mesh (OBJ or PLY, a glTF 2.0 clip or a numbered mesh cache) "
        "and print its counts and bounds (an animated one's at --time), read a bake "
        "(spotshell bake) and print its levels, or read a 3D Gaussian splatting PLY "
        "(spotshell export) and print its count, bounds and SH degree.",
        {{"mesh", "FILE",
          "mesh to inspect (.obj, .ply, .gltf, .glb, a cache walk.%04d.ply, or "
          "generated:NAME as scenes take)",
          false},
         {"clip", "NAME", "a glTF file's clip (default: its first)", false},
         {"fps", "N", "a mesh cache's frames per second (default 24)", false},
         {"time", "T", "an animated mesh's pose at T seconds (default: the rest pose)", false},
         {"bake", "FILE", "bake to inspect (.vdb written by spotshell bake)", false},
         {"splats", "FILE", "3DGS PLY to read back and check (spotshell export --format 3dgs)",
          false}},
        argc, argv);
    if (args.helpRequested()) {
        std::fputs(args.usage().c_str(), stdout);
        return 0;
    }
    if (int(args.has("mesh")) + int(args.has("bake")) + int(args.has("splats")) != 1)
        throw InputError(
            "spotshell info: give --mesh FILE, --bake FILE or --splats FILE (one of them)");
    if (args.has("splats")) {
        const noise::Splats3dgsFile file = noise::readSplats3dgs(args.str("splats"));
        std::printf("splats %s\n", args.str("splats").c_str());
        std::printf("  count      %zu\n", file.splats.size());
        std::printf("  bounds     [%g %g %g] .. [%g %g %g]\n", file.lo.x, file.lo.y, file.lo.z,
                    file.hi.x, file.hi.y, file.hi.z);
        std::printf("  sh degree  %d\n", file.shDegree);
        return 0;
    }
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
        std::printf("  shading    %s\n",
                    bake.hasShading() ? "tangent, normal (lit scenes render)"
                                      : "none (an older bake: unlit scenes only; bake it again)");
        std::printf("  distance   %llu voxels (level-0 voxels, capped at %g)\n",
                    static_cast<unsigned long long>(bake.distanceCount()),
                    double(noise::kBakeDistanceCap));
        return 0;
    }
    const noise::AnimatedMesh animated =
        noise::AnimatedMesh::load(args.str("mesh"), args.has("clip") ? args.str("clip") : "",
                                  args.number("fps", 24.0, 1e-3, 1e4));
    if (args.has("time") && !animated.animated())
        throw InputError(cat("spotshell info: ", args.str("mesh"), " does not move (--time)"));
    const noise::Mesh mesh =
        args.has("time") ? animated.pose(args.number("time", 0.0, -1e9, 1e9)) : animated.rest();
    const noise::Bounds b = mesh.bounds();
    std::printf("mesh %s\n", mesh.name.c_str());
    std::printf("  vertices   %zu\n", mesh.positions.size());
    std::printf("  triangles  %zu\n", mesh.triangles.size());
    std::printf("  dropped    %zu degenerate triangles\n", mesh.droppedTriangles);
    std::printf("  bounds     [%g %g %g] .. [%g %g %g]\n", b.lo.x, b.lo.y, b.lo.z, b.hi.x, b.hi.y,
                b.hi.z);
    std::printf("  area       %g\n", mesh.surfaceArea());
    std::printf("  uv         %s\n", mesh.hasUv() ? "yes" : "no");
    if (animated.animated() || !animated.clipNames().empty() || animated.jointCount() > 0) {
        std::string clips;
        for (const std::string& c : animated.clipNames())
            clips += (clips.empty() ? "" : ", ") + (c.empty() ? std::string("(unnamed)") : c);
        std::printf("  clips      %s\n", clips.empty() ? "none" : clips.c_str());
        std::printf("  clip       %s, %g s from %g s\n",
                    animated.clipName().empty() ? "(unnamed)" : animated.clipName().c_str(),
                    animated.duration(), animated.start());
        std::printf("  joints     %zu\n", animated.jointCount());
        std::printf("  morphs     %zu targets\n", animated.morphTargetCount());
    }
    if (animated.frameCount() > 0)
        std::printf("  frames     %zu (%g s)\n", animated.frameCount(), animated.duration());
    if (args.has("time"))
        std::printf("  pose       at %g s (bounds above)\n", args.number("time", 0.0, -1e9, 1e9));
    return 0;
}

} // namespace spot::cmd
