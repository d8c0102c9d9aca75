#include <cmath>
#include <cstdio>

#include <nlohmann/json.hpp>

#include "cli.h"
#include "commands.h"
#include "noise/error.h"
#include "noise/image.h"
#include "splat/image_compare.h"

namespace spot::cmd {

int compare(int argc, char** argv) {
    // Positional A and B come first; the rest are options.
    std::vector<std::string> files;
    int i = 0;
    for (; i < argc && argv[i][0] != '-'; ++i)
        files.emplace_back(argv[i]);
    cli::Args args("compare",
                   "Compare image B against reference A: spotshell compare A B [options].\n"
                   "PSNR, SSIM (luma, 11x11 Gaussian window) and FLIP (LDR) on display values; the signed\n"
                   "mean difference (linear and display) and the relative bias of the mean.",
                   {{"diff", "FILE", "write the per-pixel FLIP error as a heat map (.png/.exr)", false},
                    {"json", "", "print the metrics as JSON", false},
                    {"ppd", "N", "FLIP observer's pixels per degree (default 67)", false}},
                   argc - i, argv + i);
    if (args.helpRequested()) {
        std::fputs(args.usage().c_str(), stdout);
        return 0;
    }
    if (files.size() != 2)
        throw InputError("spotshell compare: needs two images, A (reference) and B (see --help)");
    const noise::Image a = noise::readImage(files[0]);
    const noise::Image b = noise::readImage(files[1]);
    if (a.width != b.width || a.height != b.height)
        throw InputError(cat("spotshell compare: ", files[0], " is ", a.width, "x", a.height, " but ",
                             files[1], " is ", b.width, "x", b.height));
    std::vector<float> flipMap;
    const splat::ImageMetrics m = splat::compareImages(
        a, b, &flipMap, args.number("ppd", splat::kDefaultPixelsPerDegree, 1.0, 1000.0));
    if (args.has("diff"))
        noise::writeImage(args.str("diff"), splat::heatMap(flipMap, a.width, a.height),
                          {{"metric", "flip"}});
    if (args.has("json")) {
        nlohmann::json j = {{"ssim", m.ssim},
                            {"flip", m.flip},
                            {"mean_abs", m.meanAbs},
                            {"max_abs", m.maxAbs},
                            {"mean_diff", m.meanDiffLinear},
                            {"mean_diff_display", m.meanDiffDisplay},
                            {"bias", m.bias},
                            {"width", a.width},
                            {"height", a.height}};
        // JSON has no infinity: identical images report psnr null and identical true.
        j["psnr"] = std::isfinite(m.psnr) ? nlohmann::json(m.psnr) : nlohmann::json(nullptr);
        j["identical"] = !std::isfinite(m.psnr);
        std::printf("%s\n", j.dump(2).c_str());
    } else {
        std::printf("psnr %.4f dB\nssim %.6f\nflip %.6f\nmean_abs %.6f\nmax_abs %.6f\n"
                    "mean_diff %+.6f (linear)\nmean_diff_display %+.6f\nbias %+.2f%% (mean, linear)\n",
                    m.psnr, m.ssim, m.flip, m.meanAbs, m.maxAbs, m.meanDiffLinear,
                    m.meanDiffDisplay, 100.0 * m.bias);
    }
    if (args.has("diff") && !args.has("json")) // --json output stays pure JSON
        std::printf("wrote %s\n", args.str("diff").c_str());
    return 0;
}

} // namespace spot::cmd
