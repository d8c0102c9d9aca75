// Image metrics on pairs with known answers, and the `compare` command's behaviour.
#include <cmath>
#include <cstdio>
#include <fstream>
#include <random>
#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "noise/error.h"
#include "noise/image.h"
#include "splat/image_compare.h"
#include "cli_run.h"

namespace {

using namespace spot;
using noise::Image;

/// An image whose display (sRGB-encoded) value is `v` everywhere.
Image uniformDisplay(int w, int h, glm::vec3 v) {
    return Image(w, h, glm::vec3(noise::srgbDecode(v.r), noise::srgbDecode(v.g), noise::srgbDecode(v.b)));
}

TEST(Compare, IdenticalImages) {
    Image a(40, 30);
    std::mt19937 rng(1);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    for (glm::vec3& p : a.pixels)
        p = glm::vec3(u(rng), u(rng), u(rng));
    const splat::ImageMetrics m = splat::compareImages(a, a);
    EXPECT_TRUE(std::isinf(m.psnr) && m.psnr > 0);
    EXPECT_DOUBLE_EQ(m.ssim, 1.0);
    EXPECT_DOUBLE_EQ(m.flip, 0.0);
    EXPECT_DOUBLE_EQ(m.meanAbs, 0.0);
}

TEST(Compare, PsnrOfAConstantOffsetIs20dB) {
    // Display values differ by exactly 0.1 in every channel: MSE 0.01, PSNR 20 dB.
    const Image a = uniformDisplay(16, 16, glm::vec3(0.3f, 0.5f, 0.2f));
    const Image b = uniformDisplay(16, 16, glm::vec3(0.4f, 0.6f, 0.3f));
    EXPECT_NEAR(splat::psnr(a, b), 20.0, 1e-4);
    const splat::ImageMetrics m = splat::compareImages(a, b);
    EXPECT_NEAR(m.meanAbs, 0.1, 1e-5);
    EXPECT_NEAR(m.maxAbs, 0.1, 1e-5);
}

TEST(Compare, BiasIsTheSignedRelativeMeanDifference) {
    // b is a scaled by 1.1 in linear values: 10% too bright; the signed differences follow, and
    // swapping the images gives the opposite sign.
    Image a(20, 10), b(20, 10);
    std::mt19937 rng(4);
    std::uniform_real_distribution<float> u(0.05f, 0.8f);
    double sumA = 0.0, sumDisplay = 0.0;
    for (std::size_t i = 0; i < a.pixels.size(); ++i) {
        a.pixels[i] = glm::vec3(u(rng), u(rng), u(rng));
        b.pixels[i] = 1.1f * a.pixels[i];
        for (int c = 0; c < 3; ++c) {
            sumA += a.pixels[i][c];
            sumDisplay += noise::srgbEncode(b.pixels[i][c]) - noise::srgbEncode(a.pixels[i][c]);
        }
    }
    const double n = 3.0 * double(a.pixels.size());
    const splat::ImageMetrics m = splat::compareImages(a, b);
    EXPECT_NEAR(m.bias, 0.1, 1e-6);
    EXPECT_NEAR(m.meanDiffLinear, 0.1 * sumA / n, 1e-7);
    EXPECT_NEAR(m.meanDiffDisplay, sumDisplay / n, 1e-7);
    EXPECT_GT(m.meanDiffDisplay, 0.0);
    const splat::ImageMetrics back = splat::compareImages(b, a);
    EXPECT_NEAR(back.bias, 1.0 / 1.1 - 1.0, 1e-6);
    EXPECT_NEAR(back.meanDiffLinear, -m.meanDiffLinear, 1e-9);
    EXPECT_DOUBLE_EQ(splat::compareImages(a, a).bias, 0.0);
}

TEST(Compare, SsimOfUniformImagesHasItsClosedForm) {
    // Uniform images: variances and covariance vanish, SSIM = (2ab + C1) / (a^2 + b^2 + C1).
    const double a = 0.2, b = 0.6, c1 = 1e-4;
    const Image x = uniformDisplay(20, 20, glm::vec3(float(a)));
    const Image y = uniformDisplay(20, 20, glm::vec3(float(b)));
    EXPECT_NEAR(splat::ssim(x, y), (2 * a * b + c1) / (a * a + b * b + c1), 1e-5);
}

TEST(Compare, SsimPenalizesStructureNotJustMean) {
    // Same mean, different structure: a checkerboard against flat grey scores far below 1,
    // while a slightly brighter checkerboard scores close to 1.
    Image checker(32, 32), flat = uniformDisplay(32, 32, glm::vec3(0.5f)), brighter(32, 32);
    for (int y = 0; y < 32; ++y)
        for (int x = 0; x < 32; ++x) {
            const float v = ((x / 2 + y / 2) % 2) ? 0.8f : 0.2f;
            checker.at(x, y) = glm::vec3(noise::srgbDecode(v));
            brighter.at(x, y) = glm::vec3(noise::srgbDecode(v + 0.02f));
        }
    EXPECT_LT(splat::ssim(checker, flat), 0.1);
    EXPECT_GT(splat::ssim(checker, brighter), 0.99);
}

TEST(Compare, FlipOfUniformPairsMatchesTheHandComputedValue) {
    // Uniform images have no features and are unchanged by the CSF filters, so FLIP reduces to
    // the redistributed HyAB distance of their Hunt-adjusted CIELAB colours. The expected values
    // were computed by hand from the paper's formulas (cmax = 41.2761 from pure green and blue).
    struct Pair {
        glm::vec3 a, b;
        double flip;
    };
    const Pair pairs[] = {{glm::vec3(0.0f), glm::vec3(1.0f), 0.9673797614921327},
                          {glm::vec3(1, 0, 0), glm::vec3(0, 1, 0), 0.9866622751952875},
                          {glm::vec3(0.5f), glm::vec3(0.6f), 0.28501300251170403}};
    for (const Pair& p : pairs) {
        const Image a = uniformDisplay(24, 24, p.a), b = uniformDisplay(24, 24, p.b);
        EXPECT_NEAR(splat::flip(a, b, nullptr), p.flip, 2e-6);
        EXPECT_NEAR(splat::flip(b, a, nullptr), p.flip, 2e-6); // symmetric
    }
}

TEST(Compare, FlipSeesEdgesAndGrowsWithTheError) {
    // A sharp vertical edge against a blurred one: the feature pipeline must report more error
    // near the edge than far from it, and more blur must mean more error.
    auto edge = [](int blur) {
        Image img(64, 16);
        for (int y = 0; y < 16; ++y)
            for (int x = 0; x < 64; ++x) {
                const float t = blur == 0 ? (x >= 32 ? 1.0f : 0.0f)
                                          : std::clamp((x - 32 + blur) / (2.0f * blur), 0.0f, 1.0f);
                img.at(x, y) = glm::vec3(noise::srgbDecode(0.2f + 0.6f * t));
            }
        return img;
    };
    const Image sharp = edge(0);
    std::vector<float> map;
    const double small = splat::flip(sharp, edge(2), &map);
    const double large = splat::flip(sharp, edge(8), nullptr);
    EXPECT_GT(small, 0.0);
    EXPECT_GT(large, small);
    EXPECT_GT(map[8 * 64 + 32], 10.0f * map[8 * 64 + 2]);
    // Error maps are in [0,1].
    for (float e : map)
        ASSERT_TRUE(e >= 0.0f && e <= 1.0f);
}

TEST(Compare, DifferentSizesAreAnInputError) {
    EXPECT_THROW(splat::compareImages(Image(4, 4), Image(4, 5)), InputError);
}

// ---- the command ---------------------------------------------------------------------------

std::string tmp(const std::string& name) { return std::string(SPOT_TEST_TMP_DIR) + "/" + name; }

using Result = spot::test::CliResult;
Result run(const std::string& args) { return spot::test::runSpotshell(args); }

TEST(CompareCommand, MetricsAsJsonAndTheDiffImage) {
    const Image a = uniformDisplay(32, 32, glm::vec3(0.3f, 0.5f, 0.2f));
    const Image b = uniformDisplay(32, 32, glm::vec3(0.4f, 0.6f, 0.3f));
    noise::writeImage(tmp("a.exr"), a);
    noise::writeImage(tmp("b.png"), b);
    const Result r = run("compare " + tmp("a.exr") + " " + tmp("b.png") + " --json --diff " + tmp("diff.png"));
    ASSERT_EQ(r.code, 0) << r.err;
    const nlohmann::json j = nlohmann::json::parse(r.out);
    EXPECT_NEAR(j["psnr"].get<double>(), 20.0, 0.2) << r.out; // the PNG rounds to 8 bits
    EXPECT_GT(j["flip"].get<double>(), 0.0);
    EXPECT_LT(j["ssim"].get<double>(), 1.0);
    const Image diff = noise::readImage(tmp("diff.png"));
    EXPECT_EQ(diff.width, 32);
    const Result same = run("compare " + tmp("a.exr") + " " + tmp("a.exr") + " --json");
    ASSERT_EQ(same.code, 0);
    EXPECT_TRUE(nlohmann::json::parse(same.out)["identical"].get<bool>()) << same.out;
}

TEST(CompareCommand, BadInputsExitWith2) {
    noise::writeImage(tmp("small.png"), Image(8, 8));
    noise::writeImage(tmp("other.png"), Image(8, 9));
    std::ofstream(tmp("corrupt.png"), std::ios::binary) << "\x89PNG\r\n\x1a\nnot really a png";
    for (const std::string& args :
         {"compare " + tmp("small.png") + " " + tmp("other.png"),
          "compare " + tmp("small.png") + " " + tmp("missing.png"),
          "compare " + tmp("corrupt.png") + " " + tmp("small.png"), "compare " + tmp("small.png")}) {
        const Result r = run(args);
        EXPECT_EQ(r.code, 2) << args;
        EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
        EXPECT_EQ(r.err.rfind("spotshell: error: ", 0), 0u) << r.err;
    }
}

} // namespace
