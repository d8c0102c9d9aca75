// Fields: exact values of each kind on hand-made meshes, the noise's statistics and smoothness,
// image lookups (texel centres, bilinear, wrap modes, v flip), and refusal of bad images.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include <OpenImageIO/imageio.h>

#include "noise/error.h"
#include "noise/field.h"
#include "noise/mesh.h"

namespace spot::noise {
namespace {

const std::filesystem::path kTmp = std::filesystem::path(SPOT_TEST_TMP_DIR) / "field_test";

/// One triangle in the z = 0 plane with uv and a few vertex attributes; filled by hand so these
/// tests do not depend on the mesh loaders.
Mesh triangleMesh(bool withUv = true) {
    Mesh m;
    m.name = "tri";
    m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    m.normals = {{0, 0, 1}, {0, 0, 1}, {0, 0, 1}};
    if (withUv) {
        m.uvs = {{0, 0}, {1, 0}, {0, 1}};
        m.tangents = {{1, 0, 0}, {1, 0, 0}, {1, 0, 0}};
    }
    m.triangles = {{0, 1, 2}};
    m.attributes["a"] = {1.0f, 2.0f, 4.0f};
    m.attributes["red"] = {0.0f, 0.5f, 1.0f};
    m.attributes["green"] = {0.25f, 0.25f, 0.25f};
    m.attributes["blue"] = {1.0f, 0.0f, 0.5f};
    return m;
}

SurfacePoint at(glm::vec3 position) {
    SurfacePoint p;
    p.position = position;
    return p;
}

SurfacePoint atUv(float u, float v) {
    SurfacePoint p;
    p.uv = {u, v};
    return p;
}

FieldDesc constant(glm::vec3 v, int components) {
    FieldDesc d;
    d.kind = FieldDesc::Kind::Constant;
    d.components = components;
    d.value = v;
    return d;
}

FieldDesc gradient(glm::vec3 from, glm::vec3 to, glm::vec3 lo, glm::vec3 hi, int components) {
    FieldDesc d;
    d.kind = FieldDesc::Kind::Gradient;
    d.components = components;
    d.from = from;
    d.to = to;
    d.lo = lo;
    d.hi = hi;
    return d;
}

FieldDesc noise(float frequency, int octaves, std::uint32_t seed, float lo, float hi) {
    FieldDesc d;
    d.kind = FieldDesc::Kind::Noise;
    d.components = 1;
    d.frequency = frequency;
    d.octaves = octaves;
    d.seed = seed;
    d.lo = {lo, 0, 0};
    d.hi = {hi, 0, 0};
    return d;
}

FieldDesc image(const std::filesystem::path& file, int components, int channel, bool repeat,
                glm::vec3 lo = glm::vec3(0.0f), glm::vec3 hi = glm::vec3(1.0f)) {
    FieldDesc d;
    d.kind = FieldDesc::Kind::Image;
    d.components = components;
    d.file = file.string();
    d.channel = channel;
    d.repeat = repeat;
    d.lo = lo;
    d.hi = hi;
    return d;
}

void expectInRange(const Field& f, glm::vec3 v) {
    const FieldRange r = f.range();
    for (int c = 0; c < 3; ++c) {
        EXPECT_GE(v[c], r.lo[c]) << "component " << c;
        EXPECT_LE(v[c], r.hi[c]) << "component " << c;
    }
}

/// The InputError message that binding `desc` throws (and a test failure if it does not).
std::string bindError(const FieldDesc& desc, const Mesh& mesh, const std::string& context = "ctx") {
    try {
        makeField(desc, mesh, {}, context);
    } catch (const InputError& e) {
        return e.what();
    }
    ADD_FAILURE() << "no InputError";
    return {};
}

// --- constant, gradient ---------------------------------------------------------------------

TEST(FieldConstant, ExactAndScalarsKeepOnlyX) {
    const Mesh mesh = triangleMesh();
    const auto scalar = makeField(constant({0.3f, 7.0f, 9.0f}, 1), mesh, {}, "c");
    EXPECT_EQ(scalar->eval(at({5, 5, 5})), glm::vec3(0.3f, 0.0f, 0.0f));
    EXPECT_EQ(scalar->range().lo, glm::vec3(0.3f, 0.0f, 0.0f));
    EXPECT_EQ(scalar->range().hi, glm::vec3(0.3f, 0.0f, 0.0f));
    const auto rgb = makeField(constant({0.1f, 0.2f, 0.3f}, 3), mesh, {}, "c");
    EXPECT_EQ(rgb->eval(at({-1, 2, 0})), glm::vec3(0.1f, 0.2f, 0.3f));
}

TEST(FieldGradient, LinearAlongTheAxisAndClampedBeyond) {
    const Mesh mesh = triangleMesh();
    const auto f =
        makeField(gradient({0, 0, 0}, {2, 0, 0}, {1, 0, 0}, {3, 0, 0}, 1), mesh, {}, "g");
    EXPECT_EQ(f->eval(at({0, 0, 0})).x, 1.0f);
    EXPECT_NEAR(f->eval(at({2, 0, 0})).x, 3.0f, 1e-6);
    EXPECT_NEAR(f->eval(at({1, 0, 0})).x, 2.0f, 1e-6);
    EXPECT_NEAR(f->eval(at({0.5f, 0, 0})).x, 1.5f, 1e-6);
    // Only the projection on from->to matters.
    EXPECT_NEAR(f->eval(at({1, 7, -3})).x, 2.0f, 1e-6);
    EXPECT_EQ(f->eval(at({5, 0, 0})).x, 3.0f);
    EXPECT_EQ(f->eval(at({-4, 0, 0})).x, 1.0f);
    EXPECT_EQ(f->eval(at({1, 0, 0})).y, 0.0f);
    EXPECT_EQ(f->range().lo.x, 1.0f);
    EXPECT_EQ(f->range().hi.x, 3.0f);

    // vec3, decreasing in one component, along a diagonal.
    const auto g =
        makeField(gradient({1, 1, 1}, {1, 2, 2}, {0, 1, 0.5f}, {1, 0, 0.5f}, 3), mesh, {}, "g");
    const glm::vec3 mid = g->eval(at({1, 1.5f, 1.5f}));
    EXPECT_NEAR(mid.x, 0.5f, 1e-6);
    EXPECT_NEAR(mid.y, 0.5f, 1e-6);
    EXPECT_NEAR(mid.z, 0.5f, 1e-6);
    EXPECT_EQ(g->range().lo, glm::vec3(0.0f, 0.0f, 0.5f));
    EXPECT_EQ(g->range().hi, glm::vec3(1.0f, 1.0f, 0.5f));
    std::mt19937 rng(1);
    std::uniform_real_distribution<float> u(-3.0f, 3.0f);
    for (int i = 0; i < 1000; ++i)
        expectInRange(*g, g->eval(at({u(rng), u(rng), u(rng)})));
}

TEST(FieldGradient, CoincidentEndsAreRefused) {
    const std::string message =
        bindError(gradient({1, 1, 1}, {1, 1, 1}, {0, 0, 0}, {1, 0, 0}, 1), triangleMesh(), "ctx");
    EXPECT_NE(message.find("ctx"), std::string::npos) << message;
}

// --- noise ----------------------------------------------------------------------------------

TEST(FieldNoise, ValueNoiseStaysInUnitIntervalWithMeanNearHalf) {
    std::mt19937 rng(2);
    std::uniform_real_distribution<float> u(-50.0f, 50.0f);
    for (int octaves : {1, 4, 8}) {
        SCOPED_TRACE(octaves);
        double sum = 0.0;
        double sumSq = 0.0;
        const int n = 20000;
        for (int i = 0; i < n; ++i) {
            const float v = valueNoise({u(rng), u(rng), u(rng)}, octaves, 5);
            ASSERT_GE(v, 0.0f);
            ASSERT_LE(v, 1.0f);
            sum += v;
            sumSq += double(v) * v;
        }
        const double mean = sum / n;
        const double stddev = std::sqrt(sumSq / n - mean * mean);
        EXPECT_NEAR(mean, 0.5, 0.03);
        EXPECT_GT(stddev, 0.05); // not a constant
    }
}

TEST(FieldNoise, DeterministicAndSeedsDiffer) {
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> u(-10.0f, 10.0f);
    int differ = 0;
    const int n = 2000;
    for (int i = 0; i < n; ++i) {
        const glm::vec3 p(u(rng), u(rng), u(rng));
        EXPECT_EQ(valueNoise(p, 3, 42), valueNoise(p, 3, 42));
        differ += std::abs(valueNoise(p, 3, 42) - valueNoise(p, 3, 43)) > 1e-3f;
    }
    EXPECT_GT(differ, n * 9 / 10);
}

TEST(FieldNoise, SmallStepsGiveSmallChanges) {
    // Per octave the slope is at most 1.875 (the quintic's) per axis; octave o runs at 2^o times
    // the frequency with 2^-o of the weight, so a step h along a unit direction changes the
    // normalized sum by at most 1.875 * sqrt(3) * octaves * h / (sum of weights) < 0.01 here.
    std::mt19937 rng(4);
    std::uniform_real_distribution<float> u(-20.0f, 20.0f);
    std::normal_distribution<float> g(0.0f, 1.0f);
    const float h = 1e-3f;
    for (int i = 0; i < 5000; ++i) {
        const glm::vec3 p(u(rng), u(rng), u(rng));
        const glm::vec3 dir = glm::normalize(glm::vec3(g(rng), g(rng), g(rng)) + 1e-6f);
        EXPECT_LT(std::abs(valueNoise(p + h * dir, 4, 9) - valueNoise(p, 4, 9)), 0.01f);
    }
    // Across lattice planes too: no jump at integer coordinates.
    for (int k = -5; k <= 5; ++k) {
        const float x = static_cast<float>(k);
        EXPECT_LT(std::abs(valueNoise({x - 1e-4f, 0.3f, 0.7f}, 1, 1) -
                           valueNoise({x + 1e-4f, 0.3f, 0.7f}, 1, 1)),
                  1e-3f);
    }
}

TEST(FieldNoise, FieldMapsIntoItsRange) {
    const Mesh mesh = triangleMesh();
    const auto f = makeField(noise(3.0f, 3, 17, 0.2f, 0.7f), mesh, {}, "n");
    EXPECT_EQ(f->range().lo.x, 0.2f);
    EXPECT_EQ(f->range().hi.x, 0.7f);
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> u(-5.0f, 5.0f);
    float lo = 1.0f;
    float hi = 0.0f;
    for (int i = 0; i < 5000; ++i) {
        const glm::vec3 p(u(rng), u(rng), u(rng));
        const glm::vec3 v = f->eval(at(p));
        expectInRange(*f, v);
        EXPECT_EQ(v.y, 0.0f);
        // The field is the noise at frequency x position, mapped linearly.
        EXPECT_NEAR(v.x, 0.2f + 0.5f * valueNoise(p * 3.0f, 3, 17), 1e-5);
        lo = std::min(lo, v.x);
        hi = std::max(hi, v.x);
    }
    EXPECT_LT(lo, 0.35f); // the range is actually used, not squeezed to the middle
    EXPECT_GT(hi, 0.55f);

    // An inverted range still reports ordered bounds.
    const auto inv = makeField(noise(1.0f, 1, 0, 0.9f, 0.1f), mesh, {}, "n");
    EXPECT_EQ(inv->range().lo.x, 0.1f);
    EXPECT_EQ(inv->range().hi.x, 0.9f);
}

TEST(FieldNoise, BadParametersAreRefused) {
    const Mesh mesh = triangleMesh();
    bindError(noise(0.0f, 1, 0, 0, 1), mesh);
    bindError(noise(1.0f, 0, 0, 0, 1), mesh);
    bindError(noise(1.0f, 9, 0, 0, 1), mesh);
}

// --- vertex attributes ----------------------------------------------------------------------

TEST(FieldVertex, BarycentricInterpolationIsExact) {
    const Mesh mesh = triangleMesh();
    FieldDesc d;
    d.kind = FieldDesc::Kind::Vertex;
    d.components = 1;
    d.attributes = {"a"};
    const auto f = makeField(d, mesh, {}, "v");
    SurfacePoint p;
    p.triangle = 0;
    p.barycentric = {0.2f, 0.3f, 0.5f};
    EXPECT_NEAR(f->eval(p).x, 0.2f * 1 + 0.3f * 2 + 0.5f * 4, 1e-6);
    EXPECT_EQ(f->eval(p).y, 0.0f);
    p.barycentric = {0, 1, 0};
    EXPECT_EQ(f->eval(p).x, 2.0f);
    EXPECT_EQ(f->range().lo.x, 1.0f);
    EXPECT_EQ(f->range().hi.x, 4.0f);

    d.components = 3;
    d.attributes = {"red", "green", "blue"};
    const auto rgb = makeField(d, mesh, {}, "v");
    p.barycentric = {0.5f, 0.25f, 0.25f};
    const glm::vec3 v = rgb->eval(p);
    EXPECT_NEAR(v.x, 0.125f + 0.25f, 1e-6);
    EXPECT_NEAR(v.y, 0.25f, 1e-6);
    EXPECT_NEAR(v.z, 0.5f + 0.125f, 1e-6);
    EXPECT_EQ(rgb->range().lo, glm::vec3(0.0f, 0.25f, 0.0f));
    EXPECT_EQ(rgb->range().hi, glm::vec3(1.0f, 0.25f, 1.0f));
    std::mt19937 rng(6);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    for (int i = 0; i < 1000; ++i) {
        const float a = u(rng);
        const float b = u(rng) * (1.0f - a);
        p.barycentric = {a, b, 1.0f - a - b};
        expectInRange(*rgb, rgb->eval(p));
    }
}

TEST(FieldVertex, MissingOrMalformedAttributeIsAnInputError) {
    Mesh mesh = triangleMesh();
    FieldDesc d;
    d.kind = FieldDesc::Kind::Vertex;
    d.components = 1;
    d.attributes = {"moss"};
    const std::string message = bindError(d, mesh, "preset p.json, fields.density");
    EXPECT_NE(message.find("preset p.json, fields.density"), std::string::npos) << message;
    EXPECT_NE(message.find("\"moss\""), std::string::npos) << message;
    EXPECT_NE(message.find("tri"), std::string::npos) << message;

    mesh.attributes["short"] = {1.0f, 2.0f};
    d.attributes = {"short"};
    EXPECT_NE(bindError(d, mesh).find("2 values for 3 vertices"), std::string::npos);

    mesh.attributes["nan"] = {1.0f, NAN, 2.0f};
    d.attributes = {"nan"};
    EXPECT_NE(bindError(d, mesh).find("non-finite"), std::string::npos);
}

// --- images ---------------------------------------------------------------------------------

constexpr int kW = 4;
constexpr int kH = 3;
constexpr int kC = 3;

/// Texel (col, row) of the test image, row 0 at the top; distinct values in [0, 1].
float texelValue(int col, int row, int channel) {
    return static_cast<float>(col + kW * row) / 16.0f + 0.01f * static_cast<float>(channel);
}

void writeImage(const std::filesystem::path& file, int w, int h, int channels,
                const std::vector<float>& pixels, OIIO::TypeDesc format) {
    std::unique_ptr<OIIO::ImageOutput> out = OIIO::ImageOutput::create(file.string());
    ASSERT_TRUE(out) << OIIO::geterror();
    const OIIO::ImageSpec spec(w, h, channels, format);
    ASSERT_TRUE(out->open(file.string(), spec)) << out->geterror();
    ASSERT_TRUE(out->write_image(OIIO::TypeDesc::FLOAT, pixels.data())) << out->geterror();
    ASSERT_TRUE(out->close());
}

class FieldImage : public ::testing::Test {
protected:
    static void SetUpTestSuite() {
        std::filesystem::create_directories(kTmp);
        std::vector<float> pixels;
        for (int row = 0; row < kH; ++row)
            for (int col = 0; col < kW; ++col)
                for (int c = 0; c < kC; ++c)
                    pixels.push_back(texelValue(col, row, c));
        writeImage(file(), kW, kH, kC, pixels, OIIO::TypeDesc::FLOAT);
    }
    /// One file per test process: ctest runs the cases of this suite in parallel processes.
    static std::filesystem::path file() {
        return kTmp / ("grid-" + std::to_string(::getpid()) + ".tif");
    }

    /// uv at the centre of texel (col, row): v is flipped, row 0 is the top of the image.
    static glm::vec2 centre(int col, int row) {
        return {(static_cast<float>(col) + 0.5f) / kW,
                1.0f - (static_cast<float>(row) + 0.5f) / kH};
    }

    Mesh m_mesh = triangleMesh();
};

TEST_F(FieldImage, TexelCentresAreExact) {
    const auto f = makeField(image(file(), 3, 0, true), m_mesh, {}, "img");
    for (int row = 0; row < kH; ++row) {
        for (int col = 0; col < kW; ++col) {
            const glm::vec2 uv = centre(col, row);
            const glm::vec3 v = f->eval(atUv(uv.x, uv.y));
            for (int c = 0; c < 3; ++c)
                EXPECT_NEAR(v[c], texelValue(col, row, c), 1e-6) << col << "," << row << "," << c;
        }
    }
}

TEST_F(FieldImage, BilinearBetweenCentres) {
    const auto f = makeField(image(file(), 3, 0, true), m_mesh, {}, "img");
    // Halfway between (1,1) and (2,1), then a quarter of the way down towards row 2.
    const glm::vec2 a = centre(1, 1);
    const glm::vec2 b = centre(2, 1);
    EXPECT_NEAR(f->eval(atUv(0.5f * (a.x + b.x), a.y)).x,
                0.5f * (texelValue(1, 1, 0) + texelValue(2, 1, 0)), 1e-6);
    const float v = a.y - 0.25f / kH;
    const float top = 0.5f * (texelValue(1, 1, 1) + texelValue(2, 1, 1));
    const float bottom = 0.5f * (texelValue(1, 2, 1) + texelValue(2, 2, 1));
    EXPECT_NEAR(f->eval(atUv(0.5f * (a.x + b.x), v)).y, 0.75f * top + 0.25f * bottom, 1e-6);
}

TEST_F(FieldImage, VIsFlippedSoUvOriginIsBottomLeft) {
    const auto f = makeField(image(file(), 1, 0, false), m_mesh, {}, "img");
    // Clamp mode: the corner uv (0,0) is exactly the bottom-left texel, (0,1) the top-left.
    EXPECT_NEAR(f->eval(atUv(0.0f, 0.0f)).x, texelValue(0, kH - 1, 0), 1e-6);
    EXPECT_NEAR(f->eval(atUv(0.0f, 1.0f)).x, texelValue(0, 0, 0), 1e-6);
    EXPECT_NEAR(f->eval(atUv(1.0f, 1.0f)).x, texelValue(kW - 1, 0, 0), 1e-6);
}

TEST_F(FieldImage, RepeatAndClampDifferAtEdges) {
    const auto rep = makeField(image(file(), 1, 0, true), m_mesh, {}, "img");
    const auto clamp = makeField(image(file(), 1, 0, false), m_mesh, {}, "img");
    const float v = centre(0, 1).y;
    // At u = 0 repeat blends the first and last columns; clamp returns the first.
    EXPECT_NEAR(rep->eval(atUv(0.0f, v)).x, 0.5f * (texelValue(0, 1, 0) + texelValue(kW - 1, 1, 0)),
                1e-6);
    EXPECT_NEAR(clamp->eval(atUv(0.0f, v)).x, texelValue(0, 1, 0), 1e-6);
    // Outside [0,1]: repeat is periodic, clamp holds the border.
    const glm::vec2 c = centre(1, 2);
    EXPECT_NEAR(rep->eval(atUv(c.x + 3.0f, c.y - 2.0f)).x, texelValue(1, 2, 0), 1e-5);
    EXPECT_NEAR(clamp->eval(atUv(c.x + 3.0f, c.y)).x, texelValue(kW - 1, 2, 0), 1e-6);
    EXPECT_NEAR(clamp->eval(atUv(-7.0f, -7.0f)).x, texelValue(0, kH - 1, 0), 1e-6);
}

TEST_F(FieldImage, ChannelSelectionAndRangeMapping) {
    const auto f =
        makeField(image(file(), 1, 2, true, {0.2f, 0, 0}, {0.6f, 0, 0}), m_mesh, {}, "img");
    const glm::vec2 uv = centre(3, 0);
    const glm::vec3 v = f->eval(atUv(uv.x, uv.y));
    EXPECT_NEAR(v.x, 0.2f + 0.4f * texelValue(3, 0, 2), 1e-6);
    EXPECT_EQ(v.y, 0.0f);
    EXPECT_EQ(v.z, 0.0f);
    // Exact bounds: the smallest and largest texel of channel 2, mapped.
    EXPECT_NEAR(f->range().lo.x, 0.2f + 0.4f * texelValue(0, 0, 2), 1e-6);
    EXPECT_NEAR(f->range().hi.x, 0.2f + 0.4f * texelValue(kW - 1, kH - 1, 2), 1e-6);

    // Channels 1..3 of a 3-channel image do not exist.
    const std::string message = bindError(image(file(), 3, 1, true), m_mesh, "ctx");
    EXPECT_NE(message.find(file().filename().string()), std::string::npos) << message;
    EXPECT_NE(message.find("channels"), std::string::npos) << message;
}

TEST_F(FieldImage, RangeContainsEverySample) {
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> u(-2.0f, 3.0f);
    for (bool repeat : {true, false}) {
        const auto f = makeField(
            image(file(), 3, 0, repeat, {0.9f, 0.0f, 0.5f}, {0.1f, 1.0f, 0.5f}), m_mesh, {}, "img");
        for (int i = 0; i < 5000; ++i)
            expectInRange(*f, f->eval(atUv(u(rng), u(rng))));
    }
}

TEST_F(FieldImage, RelativePathsResolveAgainstBaseDir) {
    const auto f = makeField(image(file().filename().string(), 1, 0, true), m_mesh, kTmp, "img");
    const glm::vec2 uv = centre(2, 2);
    EXPECT_NEAR(f->eval(atUv(uv.x, uv.y)).x, texelValue(2, 2, 0), 1e-6);
}

TEST_F(FieldImage, MeshWithoutUvIsAnInputError) {
    const std::string message = bindError(image(file(), 1, 0, true), triangleMesh(false), "ctx");
    EXPECT_NE(message.find("uv"), std::string::npos) << message;
    EXPECT_NE(message.find(file().filename().string()), std::string::npos) << message;
}

void expectImageRefused(const std::filesystem::path& file, const std::string& alsoExpected = "") {
    const std::string message = bindError(image(file, 1, 0, true), triangleMesh(), "ctx");
    EXPECT_NE(message.find(file.filename().string()), std::string::npos) << message;
    EXPECT_NE(message.find("ctx"), std::string::npos) << message;
    if (!alsoExpected.empty())
        EXPECT_NE(message.find(alsoExpected), std::string::npos) << message;
}

TEST_F(FieldImage, MissingFileIsAnInputError) {
    expectImageRefused(kTmp / "absent.png", "no such file");
}

TEST_F(FieldImage, CorruptImageIsAnInputError) {
    const std::filesystem::path corrupt = kTmp / "corrupt.png";
    std::mt19937 rng(8);
    std::string bytes(2000, '\0');
    for (char& b : bytes)
        b = static_cast<char>(rng() & 0xff);
    std::ofstream(corrupt, std::ios::binary) << bytes;
    expectImageRefused(corrupt);
}

TEST_F(FieldImage, TruncatedPngIsAnInputError) {
    const std::filesystem::path whole = kTmp / "whole.png";
    std::vector<float> pixels(64 * 64 * 3);
    std::mt19937 rng(9);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    for (float& p : pixels)
        p = u(rng); // noise does not compress, so the pixel data dominates the file
    writeImage(whole, 64, 64, 3, pixels, OIIO::TypeDesc::UINT8);
    std::ifstream in(whole, std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    ASSERT_GT(bytes.size(), 4000u);
    const std::filesystem::path truncated = kTmp / "truncated.png";
    std::ofstream(truncated, std::ios::binary) << bytes.substr(0, bytes.size() / 2);
    expectImageRefused(truncated);
}

std::uint32_t crc32(const std::string& data) {
    std::uint32_t crc = 0xffffffffu;
    for (unsigned char byte : data) {
        crc ^= byte;
        for (int k = 0; k < 8; ++k)
            crc = (crc >> 1) ^ (0xedb88320u & (0u - (crc & 1u)));
    }
    return ~crc;
}

std::string pngChunk(const std::string& type, const std::string& data) {
    const auto be32 = [](std::uint32_t v) {
        return std::string{static_cast<char>(v >> 24), static_cast<char>(v >> 16),
                           static_cast<char>(v >> 8), static_cast<char>(v)};
    };
    return be32(static_cast<std::uint32_t>(data.size())) + type + data + be32(crc32(type + data));
}

TEST_F(FieldImage, OversizedImageIsRefusedFromItsHeader) {
    // A valid PNG header announcing 30000 x 30000 RGBA (14 GB as float) and almost no data: the
    // field must refuse it from the header alone, without trying to decode or allocate.
    const std::string ihdr{0, 0, 0x75, 0x30, 0, 0, 0x75, 0x30, 8, 6, 0, 0, 0};
    const std::string png = std::string("\x89PNG\r\n\x1a\n", 8) + pngChunk("IHDR", ihdr) +
                            pngChunk("IDAT", std::string(16, '\0')) + pngChunk("IEND", "");
    const std::filesystem::path file = kTmp / "huge.png";
    std::ofstream(file, std::ios::binary) << png;
    expectImageRefused(file, "too large");
}

FieldDesc imageIn(const std::filesystem::path& file, int components, FieldDesc::ColorSpace space) {
    FieldDesc d = image(file, components, 0, true);
    d.colorSpace = space;
    return d;
}

/// A 2x2 image of one value in every channel, written in `format` with `colorSpace` (when set).
std::filesystem::path flatImage(const std::string& name, int channels, float value,
                                OIIO::TypeDesc format, const std::string& colorSpace = "") {
    const std::filesystem::path file = kTmp / (std::to_string(::getpid()) + "-" + name);
    std::unique_ptr<OIIO::ImageOutput> out = OIIO::ImageOutput::create(file.string());
    EXPECT_TRUE(out) << OIIO::geterror();
    OIIO::ImageSpec spec(2, 2, channels, format);
    if (channels == 4) {
        spec.alpha_channel = 3;
        spec.attribute("oiio:UnassociatedAlpha", 1); // write the values as given
    }
    if (!colorSpace.empty())
        spec.attribute("oiio:ColorSpace", colorSpace);
    const std::vector<float> pixels(static_cast<std::size_t>(4 * channels), value);
    EXPECT_TRUE(out->open(file.string(), spec)) << out->geterror();
    EXPECT_TRUE(out->write_image(OIIO::TypeDesc::FLOAT, pixels.data())) << out->geterror();
    EXPECT_TRUE(out->close());
    return file;
}

// 8-bit textures are painted in sRGB: mid-grey 128 is 0.2158 linear (IEC 61966-2-1), read as
// such by default and with "srgb", and as 128/255 only when the preset says "linear".
TEST_F(FieldImage, EightBitPngIsDecodedFromSrgbUnlessTheKeySaysLinear) {
    using Space = FieldDesc::ColorSpace;
    const std::filesystem::path png =
        flatImage("grey.png", 3, 128.0f / 255.0f, OIIO::TypeDesc::UINT8);
    const SurfacePoint p = atUv(0.5f, 0.5f);
    const float srgb128 = std::pow((128.0f / 255.0f + 0.055f) / 1.055f, 2.4f);
    EXPECT_NEAR(srgb128, 0.2158f, 1e-4);
    for (Space space : {Space::Auto, Space::Srgb}) {
        const glm::vec3 v = makeField(imageIn(png, 3, space), m_mesh, {}, "img")->eval(p);
        for (int c = 0; c < 3; ++c)
            EXPECT_NEAR(v[c], srgb128, 1e-5) << "space " << int(space) << ", component " << c;
    }
    const glm::vec3 raw = makeField(imageIn(png, 3, Space::Linear), m_mesh, {}, "img")->eval(p);
    EXPECT_NEAR(raw.x, 128.0f / 255.0f, 1e-6);
    EXPECT_NEAR(raw.x, 0.502f, 1e-3);
    // The range the generator bounds densities with is the decoded one.
    const auto f = makeField(imageIn(png, 1, Space::Auto), m_mesh, {}, "img");
    EXPECT_NEAR(f->range().hi.x, srgb128, 1e-5);
}

// Float images hold linear values: an EXR is read unchanged by default (its header says
// "Linear"); "srgb" on it is the user's explicit choice and decodes.
TEST_F(FieldImage, FloatExrIsUnchanged) {
    using Space = FieldDesc::ColorSpace;
    const std::filesystem::path exr = flatImage("grey.exr", 3, 0.5f, OIIO::TypeDesc::FLOAT);
    const SurfacePoint p = atUv(0.5f, 0.5f);
    for (Space space : {Space::Auto, Space::Linear})
        EXPECT_EQ(makeField(imageIn(exr, 1, space), m_mesh, {}, "img")->eval(p).x, 0.5f);
    EXPECT_NEAR(makeField(imageIn(exr, 1, Space::Srgb), m_mesh, {}, "img")->eval(p).x,
                std::pow((0.5f + 0.055f) / 1.055f, 2.4f), 1e-6);
}

// Auto follows the file's own colour space: a PNG that declares gamma 2.2, an 8-bit TIFF that
// declares nothing (sRGB, as 8-bit images are painted), a float TIFF that declares nothing
// (linear), an 8-bit PNG that declares gamma 1 (OIIO reads it as "Linear": used as stored).
TEST_F(FieldImage, AutoFollowsTheFilesColourSpace) {
    using Space = FieldDesc::ColorSpace;
    const float e = 128.0f / 255.0f;
    const SurfacePoint p = atUv(0.5f, 0.5f);
    const auto read = [&](const std::filesystem::path& file) {
        return makeField(imageIn(file, 1, Space::Auto), m_mesh, {}, "img")->eval(p).x;
    };
    EXPECT_NEAR(read(flatImage("g22.png", 1, e, OIIO::TypeDesc::UINT8, "Gamma2.2")),
                std::pow(e, 2.2f), 1e-5);
    EXPECT_NEAR(read(flatImage("plain.tif", 1, e, OIIO::TypeDesc::UINT8)),
                std::pow((e + 0.055f) / 1.055f, 2.4f), 1e-5);
    EXPECT_EQ(read(flatImage("float.tif", 1, 0.5f, OIIO::TypeDesc::FLOAT)), 0.5f);
    EXPECT_NEAR(read(flatImage("linear.png", 1, e, OIIO::TypeDesc::UINT8, "Linear")), e, 1e-6);
}

// Alpha is coverage, not colour: a density read from an RGBA PNG's alpha is never decoded, its
// colour channels are.
TEST_F(FieldImage, AlphaChannelIsNeverDecoded) {
    const float e = 128.0f / 255.0f;
    const std::filesystem::path png = flatImage("rgba.png", 4, e, OIIO::TypeDesc::UINT8);
    const SurfacePoint p = atUv(0.5f, 0.5f);
    for (FieldDesc::ColorSpace space : {FieldDesc::ColorSpace::Auto, FieldDesc::ColorSpace::Srgb}) {
        FieldDesc alpha = imageIn(png, 1, space);
        alpha.channel = 3;
        EXPECT_NEAR(makeField(alpha, m_mesh, {}, "img")->eval(p).x, e, 1e-6);
        FieldDesc blue = imageIn(png, 1, space);
        blue.channel = 2;
        EXPECT_NEAR(makeField(blue, m_mesh, {}, "img")->eval(p).x,
                    std::pow((e + 0.055f) / 1.055f, 2.4f), 1e-5);
    }
}

TEST_F(FieldImage, MemoryBudgetIsCheckedBeforeReading) {
    // 1024 x 1024 x 3 float = 12 MiB, over a 4 MiB budget.
    const std::filesystem::path file = kTmp / "budget.png";
    writeImage(file, 1024, 1024, 3, std::vector<float>(1024 * 1024 * 3, 0.5f),
               OIIO::TypeDesc::UINT8);
    ASSERT_EQ(setenv("SPOT_MEMORY_LIMIT_MB", "4", 1), 0);
    const std::string message = bindError(image(file, 1, 0, true), m_mesh, "ctx");
    unsetenv("SPOT_MEMORY_LIMIT_MB");
    EXPECT_NE(message.find("budget.png"), std::string::npos) << message;
    EXPECT_NE(message.find("MiB"), std::string::npos) << message;
}

// --- glTF materials (the "material" field) --------------------------------------------------

FieldDesc material(int components = 3, int channel = 0) {
    FieldDesc d;
    d.kind = FieldDesc::Kind::Material;
    d.components = components;
    d.channel = channel;
    d.lo = glm::vec3(0.0f);
    d.hi = components == 1 ? glm::vec3(1.0f, 0.0f, 0.0f) : glm::vec3(1.0f);
    return d;
}

/// A 2 x 2 sRGB PNG, top row red (128 in 8 bits) and green, bottom row blue and white; alpha
/// 1, 0.5, 1, 0 (uv (0, 0) is the image's bottom-left: blue).
std::filesystem::path writeQuadrants(const std::string& name) {
    std::filesystem::create_directories(kTmp);
    const std::filesystem::path file = kTmp / (name + "-" + std::to_string(::getpid()) + ".png");
    const std::vector<float> pixels = {128.0f / 255.0f, 0, 0, 1, 0, 1, 0, 0.5f,
                                       0, 0, 1, 1, 1, 1, 1, 0};
    std::unique_ptr<OIIO::ImageOutput> out = OIIO::ImageOutput::create(file.string());
    EXPECT_TRUE(out) << OIIO::geterror();
    OIIO::ImageSpec spec(2, 2, 4, OIIO::TypeDesc::UINT8);
    spec.attribute("oiio:UnassociatedAlpha", 1); // the colours as given, not divided by alpha
    EXPECT_TRUE(out->open(file.string(), spec)) << out->geterror();
    EXPECT_TRUE(out->write_image(OIIO::TypeDesc::FLOAT, pixels.data())) << out->geterror();
    EXPECT_TRUE(out->close());
    return file;
}

Mesh materialMesh() {
    Mesh m = triangleMesh();
    MeshPart part;
    part.material = 0;
    part.triangles = 1;
    m.parts = {part};
    m.trianglePart = {0};
    m.materials.resize(1);
    m.materials[0].name = "Fur";
    return m;
}

TEST(FieldMaterial, TextureTimesFactorThroughUvDecodedFromSrgb) {
    Mesh mesh = materialMesh();
    const std::filesystem::path png = writeQuadrants("material");
    mesh.materials[0].textureFile = png;
    mesh.materials[0].texture = "quadrants";
    mesh.materials[0].baseColorFactor = glm::vec4(0.5f, 1.0f, 1.0f, 1.0f);
    mesh.materials[0].repeat = false;
    const auto colour = makeField(material(), mesh, {}, "fields.color");
    // Texel centres: sRGB 128 is 0.2158 linear, times the factor's 0.5.
    EXPECT_NEAR(colour->eval(atUv(0.25f, 0.75f)).r, 0.5f * std::pow((128.0f / 255.0f + 0.055f) / 1.055f, 2.4f), 1e-5f);
    EXPECT_EQ(colour->eval(atUv(0.75f, 0.75f)), glm::vec3(0.0f, 1.0f, 0.0f));
    EXPECT_EQ(colour->eval(atUv(0.25f, 0.25f)), glm::vec3(0.0f, 0.0f, 1.0f));
    EXPECT_EQ(colour->eval(atUv(0.75f, 0.25f)), glm::vec3(0.5f, 1.0f, 1.0f));
    // The alpha channel as a scalar (a density mask), never decoded.
    const auto alpha = makeField(material(1, 3), mesh, {}, "fields.density");
    EXPECT_NEAR(alpha->eval(atUv(0.75f, 0.75f)).x, 0.5f, 1e-2f);
    EXPECT_EQ(alpha->eval(atUv(0.75f, 0.25f)).x, 0.0f);
    // Embedded bytes read the same.
    std::ifstream in(png, std::ios::binary);
    Mesh embedded = mesh;
    embedded.materials[0].textureFile.clear();
    embedded.materials[0].textureBytes = std::make_shared<const std::string>(
        std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
    embedded.materials[0].textureMime = "image/png";
    const auto same = makeField(material(), embedded, {}, "fields.color");
    for (const glm::vec2 uv : {glm::vec2(0.1f, 0.2f), glm::vec2(0.6f, 0.9f), glm::vec2(0.5f)})
        EXPECT_EQ(same->eval(atUv(uv.x, uv.y)), colour->eval(atUv(uv.x, uv.y)));
}

TEST(FieldMaterial, AFactorAloneIsAConstantAndNeedsNoUv) {
    Mesh mesh = materialMesh();
    mesh.uvs.clear();
    mesh.tangents.clear();
    mesh.materials[0].baseColorFactor = glm::vec4(0.5f, 0.3f, 0.1f, 1.0f);
    const auto f = makeField(material(), mesh, {}, "fields.color");
    EXPECT_EQ(f->eval(atUv(0.3f, 0.9f)), glm::vec3(0.5f, 0.3f, 0.1f));
    EXPECT_EQ(f->range().lo, glm::vec3(0.5f, 0.3f, 0.1f));
}

TEST(FieldMaterial, WhichMaterialAndBadTexturesAreOneLine) {
    Mesh mesh = materialMesh();
    mesh.materials.push_back(mesh.materials[0]);
    mesh.materials[1].name = "Wood";
    mesh.parts.push_back(mesh.parts[0]);
    mesh.parts[1].material = 1;
    // Both parts grow: which material is ambiguous.
    EXPECT_NE(bindError(material(), mesh).find("use 2 materials (0 'Fur', 1 'Wood'); name one"),
              std::string::npos);
    FieldDesc byName = material();
    byName.material = "Wood";
    EXPECT_NO_THROW(makeField(byName, mesh, {}, "ctx"));
    byName.material = "Stone";
    EXPECT_NE(bindError(byName, mesh).find("material 'Stone' is not one of tri's (0 'Fur', 1 "
                                           "'Wood')"),
              std::string::npos);
    FieldDesc byIndex = material();
    byIndex.materialIndex = 1;
    EXPECT_NO_THROW(makeField(byIndex, mesh, {}, "ctx"));
    byIndex.materialIndex = 2;
    EXPECT_NE(bindError(byIndex, mesh).find("material 2 is not one of"), std::string::npos);
    mesh.parts[1].grows = false; // the one that grows decides
    EXPECT_NO_THROW(makeField(material(), mesh, {}, "ctx"));
    // Corrupt or missing textures, a mesh without materials.
    Mesh bad = materialMesh();
    bad.materials[0].textureBytes = std::make_shared<const std::string>("not an image");
    bad.materials[0].texture = "skin";
    const std::string corrupt = bindError(material(), bad);
    EXPECT_NE(corrupt.find("texture 'skin': not a PNG or JPEG image"), std::string::npos) << corrupt;
    bad.materials[0].textureBytes =
        std::make_shared<const std::string>(std::string("\x89PNG\r\n\x1a\n", 8) + "truncated");
    const std::string truncated = bindError(material(), bad);
    EXPECT_NE(truncated.find("cannot read"), std::string::npos) << truncated;
    EXPECT_EQ(truncated.find('\n'), std::string::npos) << truncated;
    bad.materials[0].textureBytes.reset();
    bad.materials[0].textureFile = kTmp / "missing-texture.png";
    EXPECT_NE(bindError(material(), bad).find("no such file"), std::string::npos);
    Mesh plain = triangleMesh();
    EXPECT_NE(bindError(material(), plain).find("has none"), std::string::npos);
}

} // namespace
} // namespace spot::noise

// ---- The shared evaluation (CPU generator and GPU) equals Field::eval ------------------------

#include "noise/generator_shared.h"
#include "noise/image.h"
#include "noise/surface.h"

namespace {

TEST(FieldShared, SharedEvaluationEqualsFieldEvalForEveryKind) {
    using namespace spot;
    noise::Mesh mesh = noise::makePlane(2.0f, 4);
    mesh.attributes["heat"].resize(mesh.positions.size());
    for (std::size_t i = 0; i < mesh.positions.size(); ++i)
        mesh.attributes["heat"][i] = 0.1f + 0.8f * float(i % 7) / 6.0f;
    const std::string texture = std::string(SPOT_TEST_TMP_DIR) + "/shared_eval.exr";
    {
        spot::noise::Image img(5, 3);
        for (int y = 0; y < 3; ++y)
            for (int x = 0; x < 5; ++x)
                img.at(x, y) = glm::vec3(0.1f * float(x), 0.3f * float(y), 0.05f * float(x + y));
        spot::noise::writeImage(texture, img);
    }
    std::vector<noise::FieldDesc> descs(5);
    descs[0].kind = noise::FieldDesc::Kind::Constant;
    descs[0].value = glm::vec3(0.25f, 0.5f, 0.75f);
    descs[1].kind = noise::FieldDesc::Kind::Gradient;
    descs[1].from = glm::vec3(-1.0f, 0.0f, 0.3f);
    descs[1].to = glm::vec3(0.7f, 0.2f, -0.4f);
    descs[1].lo = glm::vec3(0.9f, 0.1f, 0.2f);
    descs[1].hi = glm::vec3(0.0f, 0.8f, 0.6f);
    descs[2].kind = noise::FieldDesc::Kind::Noise;
    descs[2].frequency = 3.7f;
    descs[2].octaves = 4;
    descs[2].seed = 99;
    descs[2].lo = glm::vec3(0.2f);
    descs[2].hi = glm::vec3(0.9f);
    descs[3].kind = noise::FieldDesc::Kind::Vertex;
    descs[3].attributes = {"heat", "heat", "heat"};
    descs[4].kind = noise::FieldDesc::Kind::Image;
    descs[4].file = texture;
    descs[4].lo = glm::vec3(0.0f);
    descs[4].hi = glm::vec3(2.0f);
    for (int components : {1, 3}) {
        for (std::size_t k = 0; k < descs.size(); ++k) {
            noise::FieldDesc d = descs[k];
            d.components = components;
            if (components == 1 && d.kind == noise::FieldDesc::Kind::Vertex)
                d.attributes = {"heat"};
            const auto field = noise::makeField(d, mesh, "", "test");
            std::vector<float> data;
            gpu::SpotGenParams params{};
            params.fields[0] = field->shared(data);
            shared::f32::GeneratorArrays arrays;
            arrays.triangles = mesh.triangles.data();
            arrays.positions = mesh.positions.data();
            arrays.normals = mesh.normals.data();
            arrays.tangents = mesh.tangents.data();
            arrays.uvs = mesh.uvs.data();
            arrays.fieldData = data.data();
            arrays.params = &params;
            shared::f32::SharedGenerator generator(arrays);
            for (std::uint32_t i = 0; i < 300; ++i) {
                const std::uint32_t tri = i % std::uint32_t(mesh.triangles.size());
                const glm::vec3 w = shared::f32::spotSampleTriangle(shared::f32::spotRand(i, 0u),
                                                                     shared::f32::spotRand(i, 1u));
                const auto s = generator.spotSurfaceAt(tri, w);
                noise::SurfacePoint p;
                p.position = s.position;
                p.normal = s.normal;
                p.tangent = s.tangent;
                p.uv = s.uv;
                p.triangle = tri;
                p.barycentric = w;
                const glm::vec3 expected = field->eval(p);
                const glm::vec3 got = generator.spotFieldEval(0u, s);
                for (int c = 0; c < 3; ++c)
                    ASSERT_EQ(got[c], expected[c]) << "kind " << k << " components " << components
                                                   << " point " << i << " component " << c;
            }
        }
    }
}

} // namespace
