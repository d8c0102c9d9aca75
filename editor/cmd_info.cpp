#include <cstdio>

#include "cli.h"
#include "commands.h"
#include "noise/animated_mesh.h"
#include "noise/bake.h"
#include "noise/error.h"
#include "noise/mesh.h"
#include "noise/scene.h"
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
         {"scene", "FILE",
          "inspect a scene's mesh as the scene loads it (its weld, grow, clip and fps); --mesh "
          "overrides the mesh",
          false},
         {"weld", "on|off|TOL",
          "weld vertices by position (default on; TOL: a fraction of the mesh's size, default "
          "1e-5)",
          false},
         {"clip", "NAME", "a glTF file's clip (default: its first)", false},
         {"fps", "N", "frames per second: a cache's rate, --frame's numbering (default 24)", false},
         {"time", "T", "an animated mesh's pose at T seconds (default: the rest pose)", false},
         {"frame", "F", "an animated mesh's pose at frame F (F / fps seconds)", false},
         {"bake", "FILE", "bake to inspect (.vdb written by spotshell bake)", false},
         {"splats", "FILE", "3DGS PLY to read back and check (spotshell export --format 3dgs)",
          false}},
        argc, argv);
    if (args.helpRequested()) {
        std::fputs(args.usage().c_str(), stdout);
        return 0;
    }
    if (int(args.has("mesh") || args.has("scene")) + int(args.has("bake")) +
            int(args.has("splats")) !=
        1)
        throw InputError("spotshell info: give --mesh FILE, --bake FILE or --splats FILE (one "
                         "of them; --scene FILE gives its mesh)");
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
    // The scene's mesh and how it loads (its weld, its "grow", its clip and rate), or --mesh
    // with --clip and --fps; --mesh overrides the scene's mesh.
    noise::MeshOptions options;
    std::string meshSpec, clip = args.has("clip") ? args.str("clip") : "";
    double fps = args.number("fps", 24.0, 1e-3, 1e4);
    int restFrame = 0;
    if (args.has("scene")) {
        const noise::SceneDesc scene = noise::loadScene(args.str("scene"));
        options = scene.meshOptions;
        meshSpec = scene.mesh;
        if (!args.has("clip"))
            clip = scene.animation.clip;
        if (!args.has("fps"))
            fps = scene.animation.fps;
        restFrame = scene.animation.restFrame;
    }
    if (args.has("mesh"))
        meshSpec = args.str("mesh");
    if (args.has("weld")) {
        const std::string w = args.str("weld");
        if (w == "off") {
            options.weld.on = false;
        } else if (w == "on") {
            options.weld = noise::WeldOptions{};
        } else {
            options.weld.on = true;
            options.weld.tolerance = args.number("weld", 1e-5, 0.0, 0.01);
        }
    }
    const noise::AnimatedMesh animated =
        noise::AnimatedMesh::load(meshSpec, clip, fps, restFrame, options);
    const bool hasTime = args.has("time") || args.has("frame");
    if (args.has("time") && args.has("frame"))
        throw InputError("spotshell info: give --time or --frame, not both");
    if (hasTime && !animated.animated())
        throw InputError(cat("spotshell info: ", meshSpec, " does not move (",
                             args.has("time") ? "--time" : "--frame", ")"));
    const double requested = args.has("frame")
                                 ? double(args.integer("frame", 0, -1000000000, 1000000000)) / fps
                                 : args.number("time", 0.0, -1e9, 1e9);
    const noise::Mesh mesh = hasTime ? animated.pose(requested) : animated.rest();
    const noise::Mesh& rest = animated.rest();
    const noise::Bounds b = mesh.bounds();
    std::printf("mesh %s\n", mesh.name.c_str());
    if (!animated.gltfVersion().empty())
        std::printf("  glTF       %s\n", animated.gltfVersion().c_str());
    std::printf("  vertices   %zu\n", mesh.positions.size());
    const noise::WeldReport& weld = rest.weldReport;
    if (weld.on)
        std::printf("  welded     %zu vertices (%zu split copies merged at %zu shared positions; "
                    "tolerance %g)\n",
                    weld.welded, rest.positions.size() - weld.welded, weld.shared, weld.tolerance);
    else
        std::printf("  welded     off (split copies stay apart: the shell may crack along seams)\n");
    if (weld.refused > 0)
        std::printf("  not welded %zu positions whose copies move apart (skins, morph targets or "
                    "frames differ; first: vertices %u and %u)\n",
                    weld.refused, weld.refusedA, weld.refusedB);
    std::printf("  triangles  %zu\n", mesh.triangles.size());
    std::string why;
    for (const auto& [reason, count] : rest.droppedWhy)
        why += cat(why.empty() ? ": " : ", ", count, " ", reason);
    std::printf("  dropped    %zu degenerate triangles%s\n", mesh.droppedTriangles, why.c_str());
    std::printf("  bounds     [%g %g %g] .. [%g %g %g]\n", b.lo.x, b.lo.y, b.lo.z, b.hi.x, b.hi.y,
                b.hi.z);
    std::printf("  area       %g\n", mesh.surfaceArea());
    std::printf("  uv         %s\n", mesh.hasUv() ? "yes" : "no");
    if (!rest.parts.empty()) {
        const auto named = [](const std::string& n) {
            return n.empty() ? std::string("(unnamed)") : cat("'", n, "'");
        };
        std::string meshes, nodes;
        for (std::size_t i = 0; i < animated.meshNames().size(); ++i)
            meshes += cat(i ? ", " : "", i, " ", named(animated.meshNames()[i]));
        for (std::size_t i = 0; i < animated.nodeNames().size(); ++i)
            nodes += cat(i ? ", " : "", i, " ", named(animated.nodeNames()[i]));
        std::printf("  meshes     %zu: %s\n", animated.meshNames().size(), meshes.c_str());
        std::printf("  nodes      %zu: %s\n", animated.nodeNames().size(), nodes.c_str());
        std::printf("  materials  %zu\n", rest.materials.size());
        for (std::size_t i = 0; i < rest.materials.size(); ++i) {
            const noise::MeshMaterial& m = rest.materials[i];
            const glm::vec4 f = m.baseColorFactor;
            std::string texture = "no texture";
            if (m.hasTexture())
                texture = cat("texture ", named(m.texture), " (",
                              m.textureBytes ? cat("embedded, ", m.textureMime.empty()
                                                                     ? std::string("image")
                                                                     : m.textureMime)
                                             : cat("file ", m.textureFile.string()),
                              ", TEXCOORD_", m.texCoord, ")");
            std::printf("    %zu %s: base colour %g %g %g %g, %s\n", i, named(m.name).c_str(),
                        double(f.r), double(f.g), double(f.b), double(f.a), texture.c_str());
        }
        std::size_t growing = 0;
        for (const noise::MeshPart& p : rest.parts)
            growing += p.grows ? p.triangles : 0;
        std::printf("  parts      %zu (%zu of %zu triangles grow fur)\n", rest.parts.size(), growing,
                    rest.triangles.size());
        for (const noise::MeshPart& p : rest.parts) {
            std::string dropped;
            for (const auto& [reason, count] : p.dropped)
                dropped += cat(dropped.empty() ? "; dropped " : ", ", count, " ", reason);
            std::printf("    mesh %d %s primitive %d, node %d %s, material %s: %zu triangles, %s%s\n",
                        p.meshIndex, named(p.mesh).c_str(), p.primitive, p.nodeIndex,
                        named(p.node).c_str(),
                        p.material < 0 ? "none"
                                       : cat(p.material, " ",
                                             named(rest.materials[std::size_t(p.material)].name))
                                             .c_str(),
                        p.triangles, p.grows ? "grows fur" : "no fur (the scene's \"grow\")",
                        dropped.c_str());
        }
    }
    if (animated.animated() || !animated.clipNames().empty() || animated.jointCount() > 0) {
        std::string clips;
        for (const std::string& c : animated.clipNames())
            clips += (clips.empty() ? "" : ", ") + (c.empty() ? std::string("(unnamed)") : c);
        std::printf("  clips      %s\n", clips.empty() ? "none" : clips.c_str());
        std::printf("  clip       %s, %g s from %g s\n",
                    animated.clipName().empty() ? "(unnamed)" : animated.clipName().c_str(),
                    animated.duration(), animated.start());
        const noise::FrameRange range = noise::clipFrames(animated, fps);
        std::printf("  frames     %ld-%ld at %g fps (frame f at f / %g s)\n", range.first,
                    range.last, fps, fps);
        std::printf("  joints     %zu\n", animated.jointCount());
        std::printf("  morphs     %zu targets\n", animated.morphTargetCount());
    }
    if (animated.frameCount() > 0) {
        const noise::FrameRange range = noise::clipFrames(animated, fps);
        std::printf("  frames     %zu files, frames %ld-%ld at %g fps (%g s)\n",
                    animated.frameCount(), range.first, range.last, fps, animated.duration());
    }
    if (hasTime) {
        const double used = animated.clampTime(requested);
        if (used != requested)
            std::printf("  pose       at %g s (frame %g), clamped to the clip's %s at %g s "
                        "(bounds above)\n",
                        requested, requested * fps,
                        requested < used ? "start" : "end", used);
        else
            std::printf("  pose       at %g s (frame %g; bounds above)\n", requested,
                        requested * fps);
    }
    return 0;
}

} // namespace spot::cmd
