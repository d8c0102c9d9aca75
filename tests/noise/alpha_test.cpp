// Coverage alpha (noise/image.h): every method's image carries alpha = 1 - the transmittance
// through the detail and the mesh; EXR is premultiplied and PNG straight, so a render composited
// over a plate with oiiotool is the render over the plate's colour.
#include <algorithm>
#include <cmath>
#include <fstream>
#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "cli_run.h"
#include "noise/error.h"
#include "noise/image.h"

namespace {

using spot::cat;
using spot::noise::Image;

std::string tmp(const std::string& name) {
    return std::string(SPOT_TEST_TMP_DIR) + "/alpha_" + name;
}

spot::test::CliResult run(const std::string& args) {
    return spot::test::runSpotshell(args, "SPOT_VALIDATION=1 LP_NUM_THREADS=2");
}

/// fur-bunny with its background set to `background`, written beside the test's outputs.
std::string sceneWithBackground(const std::string& name, const glm::vec3& background) {
    const std::string source = std::string(SPOT_SOURCE_DIR) + "/presets/scenes/fur-bunny.json";
    nlohmann::json scene = nlohmann::json::parse(std::ifstream(source));
    scene["background"] = {background.r, background.g, background.b};
    // Paths in the scene are relative to its folder: keep them pointing at the shipped files.
    for (const char* key : {"mesh", "preset"})
        if (scene.contains(key) && scene[key].is_string() &&
            scene[key].get<std::string>().find(':') == std::string::npos)
            scene[key] =
                std::string(SPOT_SOURCE_DIR) + "/presets/scenes/" + scene[key].get<std::string>();
    const std::string file = tmp(name + ".json");
    std::ofstream(file) << scene.dump(2);
    return file;
}

float maxAbs(const Image& a, const Image& b) {
    float worst = 0.0f;
    for (std::size_t i = 0; i < a.pixels.size(); ++i)
        for (int c = 0; c < 3; ++c)
            worst = std::max(worst, std::abs(a.pixels[i][c] - b.pixels[i][c]));
    return worst;
}

} // namespace

TEST(Alpha, EveryMethodCompositesOverAPlateAsItRendersOverItsColour) {
    if (std::system("oiiotool --help > /dev/null 2>&1") != 0)
        FAIL() << "oiiotool is missing (scripts/install-deps.sh installs openimageio-tools)";
    const glm::vec3 plate(0.8f, 0.3f, 0.1f);
    const std::string own = sceneWithBackground("own", glm::vec3(0.02f, 0.02f, 0.03f));
    const std::string over = sceneWithBackground("plate", plate);
    const std::string bake = tmp("fur.vdb");
    const auto baked = run(cat("bake --scene ", own, " --resolution 64 --levels 2 --out ", bake));
    ASSERT_EQ(baked.code, 0) << baked.err;
    for (const std::string method :
         {"instanced", "oit", "hybrid", "sorted", "raymarch", "baked", "reference"}) {
        SCOPED_TRACE(method);
        const std::string extra = method == "reference" ? " --spp 2"
                                  : method == "baked"   ? " --bake " + bake
                                                        : "";
        const std::string a = tmp(method + ".exr"), p = tmp(method + "-plate.exr"),
                          png = tmp(method + ".png"), comp = tmp(method + "-comp.exr");
        for (const auto& [scene, out] :
             {std::pair{own, a}, std::pair{over, p}, std::pair{own, png}}) {
            const auto r = run(cat("render --scene ", scene, " --method ", method, extra,
                                   " --size 96x72 --out ", out));
            ASSERT_EQ(r.code, 0) << r.err;
        }
        const Image image = spot::noise::readImage(a);
        ASSERT_EQ(image.alpha.size(), image.pixels.size());
        // Coverage is 0 in the background, 1 on the mesh and in between at the fur's edge
        // (instanced: its kernels are opaque, so 0 or 1).
        const auto [lo, hi] = std::minmax_element(image.alpha.begin(), image.alpha.end());
        EXPECT_EQ(*lo, 0.0f);
        EXPECT_EQ(*hi, 1.0f);
        const auto partial = std::count_if(image.alpha.begin(), image.alpha.end(),
                                           [](float x) { return x > 0.0f && x < 1.0f; });
        if (method == "instanced")
            EXPECT_EQ(partial, 0);
        else
            EXPECT_GT(std::count_if(image.alpha.begin(), image.alpha.end(),
                                    [](float x) { return x > 0.05f && x < 0.95f; }),
                      20);
        // The render over its own background, composited over the plate by oiiotool (the plate
        // opaque), is the render over the plate's colour.
        const std::string cmd =
            cat("oiiotool ", a, " --pattern constant:color=", plate.r, ",", plate.g, ",", plate.b,
                ",1 96x72 4 --over -o ", comp, " > ", comp, ".log 2>&1");
        ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
        const Image composited = spot::noise::readImage(comp);
        const Image rendered = spot::noise::readImage(p);
        EXPECT_LT(maxAbs(composited, rendered), 2e-5f);
        EXPECT_GT(maxAbs(image, rendered), 0.1f); // the plate does show through
        // The PNG (straight alpha, 8 bits) reads back as the same image over its background,
        // its straight colour clamped to [0, 1] (the lit bunny's highlights go above 1).
        const Image straight = spot::noise::readImage(png);
        Image clamped = image;
        for (std::size_t i = 0; i < clamped.pixels.size(); ++i) {
            const float a = clamped.alpha[i];
            const glm::vec3 behind = (1.0f - a) * image.background;
            if (a > 0.0f)
                clamped.pixels[i] =
                    glm::clamp((image.pixels[i] - behind) / a, 0.0f, 1.0f) * a + behind;
        }
        ASSERT_EQ(straight.alpha.size(), image.alpha.size());
        float alphaWorst = 0.0f;
        for (std::size_t i = 0; i < image.alpha.size(); ++i)
            alphaWorst = std::max(alphaWorst, std::abs(straight.alpha[i] - image.alpha[i]));
        EXPECT_LE(alphaWorst, 0.5f / 255.0f + 1e-6f);
        EXPECT_LT(maxAbs(straight, clamped), 0.02f);
    }
}

TEST(Alpha, TheEditorsExportKeepsAlpha) {
    const std::string script = tmp("export.txt"), out = tmp("export.exr");
    std::ofstream(script) << "screenshot " << out << "\n";
    const auto r = run(cat("edit --scene ", std::string(SPOT_SOURCE_DIR),
                           "/presets/scenes/fur-bunny.json --size 96x72 --script ", script));
    ASSERT_EQ(r.code, 0) << r.err;
    const Image image = spot::noise::readImage(out);
    ASSERT_EQ(image.alpha.size(), image.pixels.size());
    EXPECT_EQ(*std::min_element(image.alpha.begin(), image.alpha.end()), 0.0f);
    EXPECT_EQ(*std::max_element(image.alpha.begin(), image.alpha.end()), 1.0f);
}
