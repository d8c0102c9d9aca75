#include <cstdio>
#include <filesystem>
#include <fstream>

#include "cli.h"
#include "commands.h"
#include "noise/error.h"
#include "noise/image.h"
#include "noise/splats_3dgs.h"
#include "noise/system.h"
#include "scene_job.h"

namespace spot::cmd {

int exportScene(int argc, char** argv) {
    std::vector<cli::OptionSpec> specs = cli::sceneOptions();
    specs.insert(
        specs.end(),
        {{"format", "NAME", "3dgs: a 3D Gaussian splatting PLY and its cameras.json", true},
         {"out", "FILE", "output .ply (cameras.json is written beside it)", true},
         {"time", "T",
          "the pose at T seconds, as the renderers see it (default: the scene's "
          "animation.time)",
          false},
         {"mapping", "NAME",
          "lobe -> splat: coverage (default: the opacity of the lobe's mean optical "
          "depth, widened to its coverage), peak (not widened), or view (coverage, "
          "with the depth along the scene camera's rays)",
          false},
         {"base-mesh", "on|off",
          "also write the opaque base mesh as flat splats, one per triangle (default on)", false},
         {"preview", "FILE",
          "also render the splats as a 3DGS viewer does (a CPU twin) at the scene "
          "camera, to an image",
          false},
         {"preview-mode", "NAME",
          "the preview's rasteriser: antialiased (default: opacity scaled to keep the mass "
          "the 0.3 px^2 widening adds, as Mip-Splatting and viewers' antialiased modes) "
          "or classic (the reference 3DGS rasteriser)",
          false}});
    cli::Args args("export",
                   "Write a scene's noise in another tool's format: one 3D Gaussian splat per "
                   "lobe (3DGS PLY, SH degree 0) at the pose of --time, every cell's kernels.",
                   specs, argc, argv);
    if (args.helpRequested()) {
        std::fputs(args.usage().c_str(), stdout);
        return 0;
    }
    if (args.str("format") != "3dgs")
        throw InputError(
            cat("spotshell export: --format '", args.str("format"), "' is not known (3dgs)"));
    const std::string mappingName = args.str("mapping", "coverage");
    noise::SplatOptions options;
    if (mappingName == "peak")
        options.mapping = noise::SplatMapping::Peak;
    else if (mappingName != "coverage" && mappingName != "view")
        throw InputError(cat("spotshell export: --mapping '", mappingName,
                             "' is not known (coverage, peak, view)"));
    const std::string baseMesh = args.str("base-mesh", "on");
    if (baseMesh != "on" && baseMesh != "off")
        throw InputError(cat("spotshell export: --base-mesh '", baseMesh, "' must be on or off"));
    const std::string previewMode = args.str("preview-mode", "antialiased");
    if (previewMode != "antialiased" && previewMode != "classic")
        throw InputError(cat("spotshell export: --preview-mode '", previewMode,
                             "' must be antialiased or classic"));
    const std::filesystem::path out = args.str("out");
    if (out.extension() != ".ply")
        throw InputError(cat("spotshell export: --out '", out.string(), "' must end in .ply"));

    // Every cell's impulses, not only the visible ones: a splat file is looked at from anywhere.
    cli::SceneJob job = cli::prepareScene(args, false);
    const double time =
        args.has("time") ? args.number("time", 0.0, -1e6, 1e6) : job.scene.animation.time;
    job.poseAt(time);
    if (job.deformer)
        job.deformer->pose(time);
    std::vector<noise::Impulse> impulses = job.generator->generate();
    if (job.deformer)
        impulses = job.deformer->move(impulses, job.generator->cellSize(), job.scene.wind);
    if (mappingName == "view")
        options.eye = job.scene.camera.eye;
    std::vector<noise::Splat3dgs> splats =
        noise::noiseSplats(job.generator->kernel(), impulses, options);
    const std::size_t lobes = splats.size();
    if (baseMesh == "on") {
        const std::vector<noise::Splat3dgs> mesh =
            noise::meshSplats(job.renderedMesh(), job.scene.baseColor);
        splats.insert(splats.end(), mesh.begin(), mesh.end());
    }
    const bool shaded = job.scene.shading.mode != noise::Shading::Mode::Unlit;
    noise::writeSplats3dgs(
        out, splats,
        {cat("spotshell export scene=", job.scene.name, " preset=", job.preset.name,
             " seed=", job.scene.seed, " time=", time, " mapping=", mappingName),
         cat(lobes, " lobe splats of ", impulses.size(), " kernels, then ", splats.size() - lobes,
             " base mesh splats"),
         "colours: the lobes' unlit colours, sRGB-encoded"});
    std::string cameraNote;
    if (job.scene.camera.projection == noise::Projection::Perspective) {
        const std::filesystem::path cameras = out.parent_path() / "cameras.json";
        const std::string json = noise::camerasJson(job.scene.camera, out.stem().string());
        writeFileAtomic(cameras, [&](std::ostream& o) { o << json; });
        cameraNote = cat(", ", cameras.string());
    } else {
        cameraNote = " (no cameras.json: 3DGS cameras are pinholes, the scene's is orthographic)";
    }
    std::printf("%zu kernels x %zu lobes -> %zu splats, %zu base mesh splats%s\n", impulses.size(),
                job.generator->kernel().lobes.size(), lobes, splats.size() - lobes,
                shaded ? " (the scene's shading is not baked: unlit colours)" : "");
    if (args.has("preview")) {
        const noise::Image image = noise::renderSplats(
            splats, job.scene.camera, job.scene.background, previewMode == "antialiased");
        noise::writeImage(args.str("preview"), image,
                          {{"method", "3dgs-cpu-twin"}, {"scene", job.scene.name}});
        std::printf("wrote %s\n", args.str("preview").c_str());
    }
    std::printf("wrote %s (%llu bytes)%s\n", out.string().c_str(),
                static_cast<unsigned long long>(std::filesystem::file_size(out)),
                cameraNote.c_str());
    return 0;
}

} // namespace spot::cmd
