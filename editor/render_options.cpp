#include "render_options.h"

#include "noise/error.h"
#include "splat/baked_vk.h"
#include "splat/raymarch_vk.h"

namespace spot::cli {

std::vector<OptionSpec> renderOptions() {
    return {{"kernel-samples", "N", "splatting: march N samples per kernel (paper eq. 10) instead "
                                    "of the analytic integral (default 0)", false},
            {"ewa", "on|off", "splatting: EWA filtering by the pixel footprint (default on)", false},
            {"weight", "W", "oit/hybrid: constant or mcguire-bavoil (default)", false},
            {"closest", "HOW", "hybrid: find each pixel's closest kernel with an atomicMin in the "
                               "OIT pass (atomic, default) or in a depth pass of its own "
                               "(depth-pass); the same image either way", false},
            {"small-pixels", "N", "oit/hybrid/instanced: kernels whose quad covers at most N pixel "
                                  "centres are evaluated by a compute pass instead of drawn, and "
                                  "so are thin ones (at most 3 pixels wide) covering at most 256 "
                                  "(default 36, at most 256; 0: draw every kernel)", false},
            {"steps", "N", "raymarch: samples along each ray through the shell (default 32, at "
                           "most 4096; split over dispatches so that no shader invocation loops "
                           "too long)", false},
            {"supersample", "N", "raymarch: N x N rays per pixel, box-filtered (default 1, at "
                                 "most 8)", false},
            {"bake", "FILE", "baked: the bake to render (an OpenVDB file from spotshell bake)",
             false},
            {"peel-passes", "N", "baked: depth-peeling layers of tetrahedra (default 4, at most "
                                 "64)", false},
            {"lod", "PIXELS", "GPU methods: thin the kernels of cells smaller than PIXELS on "
                              "screen, conserving mass (default 0: off)", false},
            {"count-fragments", "", "splatting: count the fragments shaded and the pixels a "
                                    "kernel covers (alpha >= 1/255); slows the splat pass", false}};
}

splat::RenderSettings renderSettings(const Args& args) {
    splat::RenderSettings s;
    s.kernelSamples = int(args.integer("kernel-samples", 0, 0, 2048));
    const std::string ewa = args.str("ewa", "on");
    if (ewa != "on" && ewa != "off")
        throw InputError(cat("--ewa must be on or off, not '", ewa, "'"));
    s.ewa = ewa == "on";
    const std::string weight = args.str("weight", "mcguire-bavoil");
    if (weight == "constant")
        s.weight = splat::OitWeight::Constant;
    else if (weight == "mcguire-bavoil")
        s.weight = splat::OitWeight::McGuireBavoil;
    else
        throw InputError(cat("--weight must be constant or mcguire-bavoil, not '", weight, "'"));
    const std::string closest = args.str("closest", "atomic");
    if (closest == "atomic")
        s.closest = splat::ClosestKernel::Atomic;
    else if (closest == "depth-pass")
        s.closest = splat::ClosestKernel::DepthPass;
    else
        throw InputError(cat("--closest must be atomic or depth-pass, not '", closest, "'"));
    s.smallPixels = int(args.integer("small-pixels", s.smallPixels, 0, splat::gpu_splat::kSplatMaxSmallPixels));
    s.steps = int(args.integer("steps", 32, 1, splat::kRaymarchMaxSteps));
    s.supersample = int(args.integer("supersample", 1, 1, splat::kRaymarchMaxSupersample));
    s.bakeFile = args.str("bake", "");
    s.peelPasses = int(args.integer("peel-passes", 4, 1, splat::kBakedMaxPeelPasses));
    s.lodPixels = args.number("lod", 0.0, 0.0, 64.0);
    s.countFragments = args.has("count-fragments");
    return s;
}

nlohmann::json describe(const splat::MethodInfo& method, const splat::RenderSettings& s) {
    nlohmann::json d = nlohmann::json::object();
    if (method.splatting) {
        d["ewa"] = s.ewa;
        d["kernel_samples"] = s.kernelSamples;
        d["weight"] = s.weight == splat::OitWeight::Constant ? "constant" : "mcguire-bavoil";
        d["closest"] = s.closest == splat::ClosestKernel::Atomic ? "atomic" : "depth-pass";
        d["small_pixels"] = s.smallPixels;
    }
    if (method.marching) {
        d["steps"] = s.steps;
        d["supersample"] = s.supersample;
    }
    if (method.baked) {
        d["bake"] = s.bakeFile;
        d["peel_passes"] = s.peelPasses;
    }
    d["lod_pixels"] = s.lodPixels;
    return d;
}

} // namespace spot::cli
