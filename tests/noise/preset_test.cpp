// Preset parsing: the shipped presets load and round-trip, and every kind of malformed input is
// refused with one InputError naming the file and the key path.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <string>
#include <vector>

#include "noise/error.h"
#include "noise/field.h"
#include "noise/mesh.h"
#include "noise/preset.h"

namespace spot::noise {
namespace {

const std::filesystem::path kPresetDir = std::filesystem::path(SPOT_SOURCE_DIR) / "presets";
const std::vector<std::string> kShipped = {"fur",  "grass",       "lichen",     "ring",
                                           "uniform", "fur-clumped", "grass-tufts"};

/// A valid preset with the given pieces; `rest` is appended inside the top-level object.
std::string
makePreset(const std::string& kernel = R"({"lobes": [{}]})",
           const std::string& distribution = R"({"type": "poisson", "density_max": 100})",
           const std::string& rest = "") {
    return R"({"version": 1, "kernel": )" + kernel + R"(, "distribution": )" + distribution + rest +
           "}";
}

std::string withFields(const std::string& fields) {
    return makePreset(R"({"lobes": [{}]})", R"({"type": "poisson", "density_max": 100})",
                      R"(, "fields": )" + fields);
}

/// The message of the InputError that parsing `json` throws, or a failure if it does not throw.
std::string parseError(const std::string& json, const std::string& name = "t.json") {
    try {
        parsePreset(json, name);
    } catch (const InputError& e) {
        return e.what();
    }
    ADD_FAILURE() << "no InputError for: " << json;
    return {};
}

/// A one-triangle mesh with uv, enough to bind every non-image field of a preset.
Mesh smallMesh() {
    Mesh m;
    m.name = "tri";
    m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    m.normals = {{0, 0, 1}, {0, 0, 1}, {0, 0, 1}};
    m.uvs = {{0, 0}, {1, 0}, {0, 1}};
    m.tangents = {{1, 0, 0}, {1, 0, 0}, {1, 0, 0}};
    m.triangles = {{0, 1, 2}};
    return m;
}

TEST(Preset, ShippedPresetsLoad) {
    for (const std::string& name : kShipped) {
        SCOPED_TRACE(name);
        const std::filesystem::path file = kPresetDir / (name + ".json");
        PresetDesc p;
        ASSERT_NO_THROW(p = loadPreset(file));
        EXPECT_EQ(p.version, 1);
        EXPECT_EQ(p.name, name);
        EXPECT_EQ(p.baseDir, kPresetDir);
        EXPECT_GE(p.kernel.lobes.size(), 1u);
        EXPECT_LE(p.kernel.lobes.size(), static_cast<std::size_t>(kMaxLobes));
        EXPECT_EQ(p.density.components, 1);
        EXPECT_EQ(p.tiltDeg.components, 1);
        EXPECT_EQ(p.spinDeg.components, 1);
        EXPECT_EQ(p.bendDeg.components, 1);
        EXPECT_EQ(p.scale.components, 3);
        EXPECT_EQ(p.color.components, 3);
        EXPECT_EQ(p.weight.components, 1);
    }
}

TEST(Preset, ShippedPresetsBindAndStayInRange) {
    const Mesh mesh = smallMesh();
    for (const std::string& name : kShipped) {
        SCOPED_TRACE(name);
        const PresetDesc p = loadPreset(kPresetDir / (name + ".json"));
        const auto bind = [&](const FieldDesc& d) { return makeField(d, mesh, p.baseDir, name); };
        const FieldRange density = bind(p.density)->range();
        EXPECT_GE(density.lo.x, 0.0f);
        EXPECT_LE(density.hi.x, 1.0f);
        EXPECT_GT(density.hi.x, 0.0f);
        const FieldRange scale = bind(p.scale)->range();
        for (int c = 0; c < 3; ++c)
            EXPECT_GT(scale.lo[c], 0.0f);
        // Shipped presets are made for meshes about 1 world unit in size: a kernel a few percent.
        EXPECT_LE(scale.hi.x, 0.1f);
        const FieldRange color = bind(p.color)->range();
        for (int c = 0; c < 3; ++c) {
            EXPECT_GE(color.lo[c], 0.0f);
            EXPECT_LE(color.hi[c], 1.0f);
        }
        EXPECT_GE(bind(p.weight)->range().lo.x, 0.0f);
        bind(p.tiltDeg);
        bind(p.spinDeg);
        bind(p.bendDeg);
        if (p.comb)
            bind(*p.comb);
    }
}

TEST(Preset, FurValuesRoundTrip) {
    const PresetDesc p = loadPreset(kPresetDir / "fur.json");
    ASSERT_EQ(p.kernel.lobes.size(), 3u);
    EXPECT_EQ(p.kernel.supportSigma, 3.0f);
    EXPECT_EQ(p.kernel.lobes[1].offset, glm::vec3(0.0f, 0.0f, 0.9f));
    EXPECT_EQ(p.kernel.lobes[0].sigma, glm::vec3(0.08f, 0.08f, 0.35f));
    EXPECT_EQ(p.kernel.lobes[0].extinction, 600.0f);
    EXPECT_EQ(p.kernel.lobes[0].rotationDeg, glm::vec3(0.0f));
    EXPECT_EQ(p.kernel.lobes[2].color, glm::vec3(0.52f, 0.35f, 0.20f));
    EXPECT_EQ(p.distribution.type, DistributionType::Poisson);
    EXPECT_EQ(p.distribution.densityMax, 8000.0f);
    EXPECT_EQ(p.density.kind, FieldDesc::Kind::Noise);
    EXPECT_EQ(p.density.lo.x, 0.6f);
    EXPECT_EQ(p.density.hi.x, 1.0f);
    EXPECT_EQ(p.density.frequency, 4.0f);
    EXPECT_EQ(p.density.octaves, 3);
    EXPECT_EQ(p.density.seed, 7u);
    EXPECT_EQ(p.tiltDeg.kind, FieldDesc::Kind::Constant);
    EXPECT_EQ(p.tiltDeg.value, glm::vec3(35.0f, 0.0f, 0.0f));
    EXPECT_EQ(p.scale.value, glm::vec3(0.02f));
    EXPECT_FALSE(p.comb.has_value());
    EXPECT_EQ(p.variation.spinDeg, 180.0f);
    EXPECT_EQ(p.variation.tiltDeg, 10.0f);
    EXPECT_EQ(p.variation.scale, 0.2f);
    EXPECT_EQ(p.variation.color, 0.15f);
    EXPECT_EQ(p.variation.weight, 0.0f);
}

TEST(Preset, OtherShippedValuesRoundTrip) {
    const PresetDesc grass = loadPreset(kPresetDir / "grass.json");
    EXPECT_EQ(grass.distribution.type, DistributionType::Jittered);
    EXPECT_EQ(grass.distribution.jitter, 0.8f);
    EXPECT_EQ(grass.kernel.lobes.at(0).sigma, glm::vec3(0.12f, 0.01f, 0.6f));
    EXPECT_EQ(grass.color.kind, FieldDesc::Kind::Noise);
    EXPECT_EQ(grass.color.lo, glm::vec3(0.8f, 0.85f, 0.55f));
    EXPECT_EQ(grass.color.hi, glm::vec3(1.0f));

    const PresetDesc ring = loadPreset(kPresetDir / "ring.json");
    ASSERT_EQ(ring.kernel.lobes.size(), 2u);
    EXPECT_EQ(ring.color.kind, FieldDesc::Kind::Gradient);
    EXPECT_EQ(ring.color.from, glm::vec3(-1.0f, 0.0f, 0.0f));
    EXPECT_EQ(ring.color.to, glm::vec3(1.0f, 0.0f, 0.0f));
    EXPECT_EQ(ring.distribution.densityMax, 600.0f);

    const PresetDesc uniform = loadPreset(kPresetDir / "uniform.json");
    EXPECT_EQ(uniform.density.kind, FieldDesc::Kind::Constant);
    EXPECT_EQ(uniform.density.value.x, 1.0f);
    EXPECT_EQ(uniform.scale.value, glm::vec3(0.01f));
    EXPECT_EQ(uniform.kernel.lobes.at(0).sigma, glm::vec3(1.0f));
    EXPECT_EQ(uniform.variation.spinDeg, 0.0f);
}

TEST(Preset, DefaultsOfAMinimalPreset) {
    const PresetDesc p = parsePreset(makePreset(), "dir/t.json");
    EXPECT_EQ(p.name, "t");
    EXPECT_TRUE(p.baseDir.empty());
    ASSERT_EQ(p.kernel.lobes.size(), 1u);
    EXPECT_EQ(p.kernel.lobes[0].sigma, glm::vec3(1.0f));
    EXPECT_EQ(p.kernel.lobes[0].offset, glm::vec3(0.0f));
    EXPECT_EQ(p.kernel.lobes[0].extinction, 1.0f);
    EXPECT_EQ(p.kernel.lobes[0].color, glm::vec3(1.0f));
    EXPECT_EQ(p.kernel.supportSigma, 3.0f);
    EXPECT_EQ(p.distribution.jitter, 1.0f);
    EXPECT_EQ(p.distribution.heightOffset, 0.0f);
    EXPECT_EQ(p.distribution.heightJitter, 0.0f);
    const auto expectConstant = [](const FieldDesc& d, int components, glm::vec3 value) {
        EXPECT_EQ(d.kind, FieldDesc::Kind::Constant);
        EXPECT_EQ(d.components, components);
        EXPECT_EQ(d.value, value);
    };
    expectConstant(p.density, 1, {1, 0, 0});
    expectConstant(p.tiltDeg, 1, {0, 0, 0});
    expectConstant(p.spinDeg, 1, {0, 0, 0});
    expectConstant(p.bendDeg, 1, {0, 0, 0});
    expectConstant(p.scale, 3, {1, 1, 1});
    expectConstant(p.color, 3, {1, 1, 1});
    expectConstant(p.weight, 1, {1, 0, 0});
    EXPECT_FALSE(p.comb.has_value());
    EXPECT_EQ(p.variation.tiltDeg, 0.0f);
    EXPECT_EQ(p.variation.scale, 0.0f);
}

TEST(Preset, FieldForms) {
    const PresetDesc p = parsePreset(withFields(R"({
            "comb": [1, 0, 0],
            "scale": 0.5,
            "tilt_deg": {"type": "constant", "value": 12},
            "spin_deg": {"type": "gradient", "from": [0, 0, 0], "to": [0, 1, 0], "values": [-30, 30]},
            "color": {"type": "vertex", "attribute": ["red", "green", "blue"]},
            "weight": {"type": "vertex", "attribute": "w"},
            "bend_deg": {"type": "noise", "range": [1, 2]},
            "density": {"type": "image", "file": "textures/d.png", "channel": 3, "wrap": "clamp",
                        "range": [0.25, 0.75]}
        })"),
                                     "t.json");
    ASSERT_TRUE(p.comb.has_value());
    EXPECT_EQ(p.comb->components, 3);
    EXPECT_EQ(p.comb->value, glm::vec3(1, 0, 0));
    EXPECT_EQ(p.scale.value, glm::vec3(0.5f)); // a number fills all three components
    EXPECT_EQ(p.tiltDeg.value, glm::vec3(12, 0, 0));
    EXPECT_EQ(p.spinDeg.kind, FieldDesc::Kind::Gradient);
    EXPECT_EQ(p.spinDeg.lo, glm::vec3(-30, 0, 0));
    EXPECT_EQ(p.spinDeg.hi, glm::vec3(30, 0, 0));
    EXPECT_EQ(p.color.kind, FieldDesc::Kind::Vertex);
    EXPECT_EQ(p.color.attributes, (std::vector<std::string>{"red", "green", "blue"}));
    EXPECT_EQ(p.weight.attributes, std::vector<std::string>{"w"});
    EXPECT_EQ(p.bendDeg.kind, FieldDesc::Kind::Noise);
    EXPECT_EQ(p.bendDeg.frequency, 1.0f);
    EXPECT_EQ(p.bendDeg.octaves, 1);
    EXPECT_EQ(p.bendDeg.seed, 0u);
    EXPECT_EQ(p.density.kind, FieldDesc::Kind::Image);
    EXPECT_EQ(p.density.file, "textures/d.png");
    EXPECT_EQ(p.density.channel, 3);
    EXPECT_FALSE(p.density.repeat);
    EXPECT_EQ(p.density.colorSpace, FieldDesc::ColorSpace::Auto);
    EXPECT_EQ(p.density.lo.x, 0.25f);
    EXPECT_EQ(p.density.hi.x, 0.75f);

    // One attribute name in a vec3 slot fills all three components.
    const PresetDesc q =
        parsePreset(withFields(R"({"scale": {"type": "vertex", "attribute": "s"}})"), "t.json");
    EXPECT_EQ(q.scale.attributes, (std::vector<std::string>{"s", "s", "s"}));
}

struct BadCase {
    const char* label;
    std::string json;
    std::vector<std::string> expected; ///< substrings of the message (file name is checked too)
};

TEST(Preset, MalformedInputsNameFileAndKey) {
    const std::string lobes9 = R"({"lobes": [{},{},{},{},{},{},{},{},{}]})";
    const std::vector<BadCase> cases = {
        {"unknown field key", withFields(R"({"denisty": 1})"), {"unknown key \"fields.denisty\""}},
        {"unknown lobe key",
         makePreset(R"({"lobes": [{"sigmaa": [1, 1, 1]}]})"),
         {"unknown key \"kernel.lobes[0].sigmaa\""}},
        {"wrong type",
         makePreset(R"({"support_sigma": "3", "lobes": [{}]})"),
         {"kernel.support_sigma must be a number, got string"}},
        {"out of range",
         makePreset(R"({"lobes": [{}, {}, {"sigma": [1, -0.5, 1]}]})"),
         {"t.json: kernel.lobes[2].sigma[1] = -0.5 is out of range [0, 1000]"}},
        {"support sigma out of range",
         makePreset(R"({"support_sigma": 7, "lobes": [{}]})"),
         {"kernel.support_sigma = 7 is out of range [1, 6]"}},
        {"missing version",
         R"({"kernel": {"lobes": [{}]}, "distribution": {"type": "poisson", "density_max": 1}})",
         {"missing required key \"version\""}},
        {"wrong version",
         R"({"version": 2, "kernel": {"lobes": [{}]}, "distribution": {"type": "poisson", "density_max": 1}})",
         {"version = 2"}},
        {"fractional version",
         R"({"version": 1.0, "kernel": {"lobes": [{}]}, "distribution": {"type": "poisson", "density_max": 1}})",
         {"version must be the integer 1"}},
        {"nine lobes", makePreset(lobes9), {"kernel.lobes has 9 lobes"}},
        {"empty lobes", makePreset(R"({"lobes": []})"), {"kernel.lobes has 0 lobes"}},
        {"missing lobes",
         makePreset(R"({"support_sigma": 3})"),
         {"missing required key \"kernel.lobes\""}},
        {"sigma of length 2",
         makePreset(R"({"lobes": [{"sigma": [1, 1]}]})"),
         {"kernel.lobes[0].sigma must be an array of 3 numbers, got 2 elements"}},
        {"bad JSON syntax",
         R"({"version": 1,, "kernel": {}})",
         {"invalid JSON at byte 15 (line 1, column 15): syntax error"}},
        {"truncated JSON", R"({"version": 1, "kernel": {"lobes": [)", {"invalid JSON at byte"}},
        {"empty document", "", {"invalid JSON at byte 1"}},
        {"document not an object", "[1, 2]", {"the document must be an object, got array"}},
        {"huge number",
         makePreset(R"({"lobes": [{}]})", R"({"type": "poisson", "density_max": 1e39})"),
         {"distribution.density_max = 1e+39 is not a finite 32-bit float"}},
        {"infinite number",
         makePreset(R"({"lobes": [{}]})", R"({"type": "poisson", "density_max": 1e999})"),
         {"invalid JSON: number overflow parsing '1e999'"}},
        {"huge integer",
         makePreset(R"({"lobes": [{"extinction": 1000000000000000000000000000000000000000000}]})"),
         {"kernel.lobes[0].extinction", "is not a finite 32-bit float"}},
        {"integer out of range",
         makePreset(R"({"lobes": [{"extinction": 18446744073709551615}]})"),
         {"kernel.lobes[0].extinction = 1.84467e+19 is out of range [0, 1e+06]"}},
        {"density_max zero",
         makePreset(R"({"lobes": [{}]})", R"({"type": "poisson", "density_max": 0})"),
         {"distribution.density_max = 0 is out of range (0, 1e+08]"}},
        {"missing density_max",
         makePreset(R"({"lobes": [{}]})", R"({"type": "poisson"})"),
         {"missing required key \"distribution.density_max\""}},
        {"missing distribution type",
         makePreset(R"({"lobes": [{}]})", R"({"density_max": 5})"),
         {"missing required key \"distribution.type\""}},
        {"unknown distribution type",
         makePreset(R"({"lobes": [{}]})", R"({"type": "blue", "density_max": 5})"),
         {"distribution.type = \"blue\" is not one of"}},
        {"jitter out of range",
         makePreset(R"({"lobes": [{}]})",
                    R"({"type": "jittered", "density_max": 5, "jitter": 1.5})"),
         {"distribution.jitter = 1.5 is out of range [0, 1]"}},
        {"gradient from == to",
         withFields(
             R"({"density": {"type": "gradient", "from": [1, 2, 3], "to": [1, 2, 3], "values": [0, 1]}})"),
         {"fields.density: gradient \"from\" and \"to\" must be different points"}},
        {"density constant above 1",
         withFields(R"({"density": 2})"),
         {"fields.density = 2 is out of range [0, 1]"}},
        {"density noise range above 1",
         withFields(R"({"density": {"type": "noise", "range": [0, 1.5]}})"),
         {"fields.density.range[1] = 1.5 is out of range [0, 1]"}},
        {"density gradient below 0",
         withFields(
             R"({"density": {"type": "gradient", "from": [0, 0, 0], "to": [1, 0, 0], "values": [-0.1, 1]}})"),
         {"fields.density.values[0] = -0.1 is out of range [0, 1]"}},
        {"density image range above 1",
         withFields(R"({"density": {"type": "image", "file": "x.png", "range": [0, 3]}})"),
         {"fields.density.range[1] = 3 is out of range [0, 1]"}},
        {"scale zero",
         withFields(R"({"scale": [1, 0, 1]})"),
         {"fields.scale[1] = 0 is out of range (0, 1000]"}},
        {"negative weight",
         withFields(R"({"weight": {"type": "constant", "value": -1}})"),
         {"fields.weight.value = -1 is out of range [0, 1000]"}},
        {"colour above 1",
         withFields(R"({"color": [0.5, 1.2, 0.5]})"),
         {"fields.color[1] = 1.2 is out of range [0, 1]"}},
        {"array in a scalar slot",
         withFields(R"({"tilt_deg": [1, 2, 3]})"),
         {"fields.tilt_deg must be a number (this field is a scalar), got array"}},
        {"vec3 of length 2",
         withFields(R"({"color": [1, 1]})"),
         {"fields.color must be an array of 3 numbers, got 2 elements"}},
        {"unknown field type",
         withFields(R"({"density": {"type": "perlin"}})"),
         {"fields.density.type = \"perlin\" is not one of"}},
        {"field without type",
         withFields(R"({"density": {"value": 1}})"),
         {"missing required key \"fields.density.type\""}},
        {"unknown key in a field",
         withFields(R"({"density": {"type": "constant", "value": 1, "seed": 2}})"),
         {"unknown key \"fields.density.seed\""}},
        {"noise octaves",
         withFields(R"({"density": {"type": "noise", "octaves": 9, "range": [0, 1]}})"),
         {"fields.density.octaves = 9 is out of range [1, 8]"}},
        {"fractional octaves",
         withFields(R"({"density": {"type": "noise", "octaves": 2.5, "range": [0, 1]}})"),
         {"fields.density.octaves must be an integer"}},
        {"negative seed",
         withFields(R"({"density": {"type": "noise", "seed": -1, "range": [0, 1]}})"),
         {"fields.density.seed = -1 is out of range [0, 4294967295]"}},
        {"noise without range",
         withFields(R"({"density": {"type": "noise"}})"),
         {"missing required key \"fields.density.range\""}},
        {"vertex list in a scalar slot",
         withFields(R"({"weight": {"type": "vertex", "attribute": ["a", "b", "c"]}})"),
         {"fields.weight.attribute must be a string"}},
        {"image wrap",
         withFields(
             R"({"density": {"type": "image", "file": "x.png", "wrap": "mirror", "range": [0, 1]}})"),
         {"fields.density.wrap = \"mirror\" is not one of"}},
        {"image colour space",
         withFields(
             R"({"density": {"type": "image", "file": "x.png", "colorspace": "rec709", "range": [0, 1]}})"),
         {"fields.density.colorspace = \"rec709\" is not one of \"auto\", \"srgb\", \"linear\""}},
        {"image colour space not a string",
         withFields(
             R"({"density": {"type": "image", "file": "x.png", "colorspace": 1, "range": [0, 1]}})"),
         {"fields.density.colorspace must be a string, got number"}},
        {"image without file",
         withFields(R"({"density": {"type": "image", "range": [0, 1]}})"),
         {"missing required key \"fields.density.file\""}},
        {"variation at 1",
         makePreset(R"({"lobes": [{}]})", R"({"type": "poisson", "density_max": 5})",
                    R"(, "variation": {"scale": 1})"),
         {"variation.scale = 1 is out of range [0, 1)"}},
        {"negative variation",
         makePreset(R"({"lobes": [{}]})", R"({"type": "poisson", "density_max": 5})",
                    R"(, "variation": {"spin_deg": -5})"),
         {"variation.spin_deg = -5 is out of range [0, 180]"}},
        {"duplicate key",
         withFields(R"({"density": 1, "density": 0.5})"),
         {"duplicate key \"density\""}},
        {"deep nesting",
         withFields(std::string(40, '[') + std::string(40, ']')),
         {"nested deeper than"}},
        {"name not a string",
         makePreset(R"({"lobes": [{}]})", R"({"type": "poisson", "density_max": 5})",
                    R"(, "name": 3)"),
         {"name must be a string, got number"}},
    };
    for (const BadCase& c : cases) {
        SCOPED_TRACE(c.label);
        const std::string message = parseError(c.json);
        EXPECT_NE(message.find("t.json: "), std::string::npos) << message;
        for (const std::string& s : c.expected)
            EXPECT_NE(message.find(s), std::string::npos)
                << "expected \"" << s << "\" in: " << message;
        // One clear line: no newlines, no raw control characters from the input.
        EXPECT_EQ(message.find('\n'), std::string::npos) << message;
    }
}

TEST(Preset, UnknownTopLevelKey) {
    const std::string message = parseError(makePreset(
        R"({"lobes": [{}]})", R"({"type": "poisson", "density_max": 5})", R"(, "densty": 1)"));
    EXPECT_NE(message.find("t.json: unknown key \"densty\""), std::string::npos) << message;
}

TEST(Preset, ControlCharactersInKeysAreEscaped) {
    const std::string message = parseError(withFields("{\"a\\u0001b\": 1}"));
    EXPECT_NE(message.find("unknown key \"fields.a\\x01b\""), std::string::npos) << message;
}

TEST(Preset, LoadPresetRefusesMissingAndOversizedFiles) {
    const std::filesystem::path missing = std::filesystem::path(SPOT_TEST_TMP_DIR) / "nope.json";
    try {
        loadPreset(missing);
        FAIL() << "no InputError";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("nope.json"), std::string::npos) << e.what();
    }

    const std::filesystem::path big = std::filesystem::path(SPOT_TEST_TMP_DIR) / "big.json";
    {
        std::ofstream out(big, std::ios::binary);
        out << makePreset();
        out << std::string((1u << 20) + 1, ' ');
    }
    try {
        loadPreset(big);
        FAIL() << "no InputError";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("big.json"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("limit"), std::string::npos) << e.what();
    }
    std::filesystem::remove(big);
}

TEST(Preset, LoadPresetErrorsNameThePath) {
    const std::filesystem::path file = std::filesystem::path(SPOT_TEST_TMP_DIR) / "broken.json";
    {
        std::ofstream out(file, std::ios::binary);
        out << withFields(R"({"density": 1.5})");
    }
    try {
        loadPreset(file);
        FAIL() << "no InputError";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("broken.json: fields.density = 1.5"),
                  std::string::npos)
            << e.what();
    }
    std::filesystem::remove(file);
}

// The complete example in presets/README.md must stay a valid preset.
TEST(Preset, ReadmeExampleParses) {
    std::ifstream in(kPresetDir / "README.md");
    const std::string readme((std::istreambuf_iterator<char>(in)),
                             std::istreambuf_iterator<char>());
    const std::size_t begin = readme.find("```json\n");
    ASSERT_NE(begin, std::string::npos);
    const std::size_t end = readme.find("```", begin + 8);
    ASSERT_NE(end, std::string::npos);
    const PresetDesc p = parsePreset(readme.substr(begin + 8, end - begin - 8), "README.md");
    EXPECT_EQ(p.name, "moss");
    EXPECT_EQ(p.density.kind, FieldDesc::Kind::Image);
    EXPECT_EQ(p.density.file, "textures/density_spots.png");
}

// The committed 64x64 density map (scripts/make_density_texture.py) read through an image field
// declared in a preset: every texel centre returns the scripted value, decoded as the key says
// (an 8-bit PNG is sRGB unless "colorspace" says otherwise), mapped into the range.
TEST(Preset, ImageFieldReadsTheShippedTexture) {
    const auto srgbToLinear = [](double e) {
        return e <= 0.04045 ? e / 12.92 : std::pow((e + 0.055) / 1.055, 2.4);
    };
    for (const char* space : {"", "auto", "srgb", "linear"}) {
        SCOPED_TRACE(space);
        const std::string key =
            *space ? std::string(R"("colorspace": ")") + space + "\", " : std::string();
        PresetDesc p = parsePreset(
            withFields(R"({"density": {"type": "image", "file": "textures/density_spots.png", )" +
                       key + R"("wrap": "repeat", "range": [0.2, 1.0]}})"),
            "image.json");
        p.baseDir = kPresetDir;
        const bool linear = std::string(space) == "linear";
        const Mesh mesh = smallMesh();
        const std::unique_ptr<Field> f =
            makeField(p.density, mesh, p.baseDir, "image.json, fields.density");
        const auto expected = [&](int col, int row) {
            const double v = std::nearbyint(255.0 * (0.5 + 0.5 * std::sin(2.0 * M_PI * col / 32.0) *
                                                               std::cos(2.0 * M_PI * row / 16.0)));
            return 0.2 + 0.8 * (linear ? v / 255.0 : srgbToLinear(v / 255.0));
        };
        for (int row = 0; row < 64; row += 7) {
            for (int col = 0; col < 64; col += 5) {
                SurfacePoint sp;
                sp.uv = {(col + 0.5f) / 64.0f, 1.0f - (row + 0.5f) / 64.0f};
                EXPECT_NEAR(f->eval(sp).x, expected(col, row), 1e-5) << col << "," << row;
            }
        }
        EXPECT_NEAR(f->range().lo.x, 0.2, 1e-6);
        EXPECT_NEAR(f->range().hi.x, 1.0, 1e-6);
    }
}

// Paint layers: {"base": FIELD, "paint": {"file", "grid"}}; an absent base is the slot's default
// (the comb's: the surface tangent); the density's layer multiplies, the others override; a
// plain painted field (presets written before layers) is still a field of its own.
TEST(Preset, PaintLayerForms) {
    const PresetDesc p = parsePreset(withFields(R"({
            "density": {"base": {"type": "noise", "range": [0.5, 1]},
                        "paint": {"file": "p.vdb", "grid": "density.paint"}},
            "comb": {"paint": {"file": "p.vdb", "grid": "comb.paint"}},
            "scale": {"paint": {"file": "p.vdb", "grid": "scale.paint"}},
            "color": {"type": "painted", "file": "old.vdb", "grid": "color"}
        })"),
                                     "t.json");
    EXPECT_EQ(p.density.kind, FieldDesc::Kind::Noise);
    ASSERT_TRUE(p.density.paint);
    EXPECT_EQ(p.density.paint->file, "p.vdb");
    EXPECT_EQ(p.density.paint->grid, "density.paint");
    EXPECT_EQ(p.density.paint->mode, PaintMode::Density);
    ASSERT_TRUE(p.comb.has_value());
    EXPECT_EQ(p.comb->kind, FieldDesc::Kind::Tangent);
    ASSERT_TRUE(p.comb->paint);
    EXPECT_EQ(p.comb->paint->mode, PaintMode::Override);
    EXPECT_EQ(p.scale.kind, FieldDesc::Kind::Constant);
    EXPECT_EQ(p.scale.value, glm::vec3(1.0f));
    ASSERT_TRUE(p.scale.paint);
    EXPECT_EQ(p.color.kind, FieldDesc::Kind::Painted);
    EXPECT_FALSE(p.color.paint);

    EXPECT_NE(parseError(withFields(R"({"density": {"paint": {"file": "p.vdb"}}})"))
                  .find("fields.density.paint.grid"),
              std::string::npos);
    EXPECT_NE(parseError(withFields(R"({"density": {"base": 0.5, "paint": {"file": "p.vdb",
               "grid": "g"}, "more": 1}})"))
                  .find("fields.density.more"),
              std::string::npos);
    EXPECT_NE(parseError(withFields(R"({"density": {"base": 2, "paint": {"file": "p.vdb",
               "grid": "g"}}})"))
                  .find("fields.density.base"),
              std::string::npos);
}

} // namespace
} // namespace spot::noise

namespace spot::noise {
namespace {

TEST(Preset, ClumpKeysAndRanges) {
    const PresetDesc fur = loadPreset(kPresetDir / "fur.json");
    EXPECT_FALSE(fur.clumpDesc.on); // no clump object, no clump field: off
    EXPECT_EQ(fur.clump.value.x, 0.0f);
    EXPECT_EQ(fur.clumpSize.value.x, 1.0f);
    EXPECT_EQ(fur.mask.value.x, 0.0f);

    const PresetDesc c = loadPreset(kPresetDir / "fur-clumped.json");
    EXPECT_TRUE(c.clumpDesc.on);
    EXPECT_EQ(c.clumpDesc.size, 0.05f);
    EXPECT_EQ(c.clumpDesc.variation, 0.4f);
    EXPECT_EQ(c.clumpDesc.shape, 0.5f);
    EXPECT_EQ(c.clumpDesc.seed, 3u);
    EXPECT_EQ(c.clumpDesc.secondarySize, 0.0f);
    EXPECT_EQ(c.clump.value.x, 0.85f);
    EXPECT_EQ(c.variation.clump, 0.15f);
    const PresetDesc g = loadPreset(kPresetDir / "grass-tufts.json");
    EXPECT_EQ(g.clumpDesc.secondarySize, 0.05f);
    EXPECT_EQ(g.clumpDesc.secondaryStrength, 0.6f);

    // A clump field alone turns clumps on with the defaults; a clump object alone too.
    const PresetDesc fieldOnly = parsePreset(withFields(R"({"clump": 0.5})"), "t.json");
    EXPECT_TRUE(fieldOnly.clumpDesc.on);
    EXPECT_EQ(fieldOnly.clumpDesc.size, 0.1f);
    const PresetDesc objectOnly = parsePreset(
        makePreset(R"({"lobes": [{}]})", R"({"type": "poisson", "density_max": 100})",
                   R"(, "clump": {"size": 0.2})"),
        "t.json");
    EXPECT_TRUE(objectOnly.clumpDesc.on);
    EXPECT_EQ(objectOnly.clumpDesc.size, 0.2f);

    const auto clump = [](const std::string& body) {
        return makePreset(R"({"lobes": [{}]})", R"({"type": "poisson", "density_max": 100})",
                          R"(, "clump": )" + body);
    };
    EXPECT_EQ(parseError(clump(R"({"size": 0})")), "t.json: clump.size = 0 is out of range (0, 1000]");
    EXPECT_NE(parseError(clump(R"({"variation": 1.5})")).find("clump.variation"), std::string::npos);
    EXPECT_NE(parseError(clump(R"({"shape": -0.1})")).find("clump.shape"), std::string::npos);
    EXPECT_NE(parseError(clump(R"({"sise": 0.1})")).find("unknown key \"clump.sise\""),
              std::string::npos);
    EXPECT_NE(parseError(clump(R"({"size": 0.1, "secondary": {"size": 0.1}})"))
                  .find("clump.secondary.size = 0.1 must be smaller than clump.size"),
              std::string::npos);
    EXPECT_NE(parseError(clump(R"({"secondary": {"strength": 0.5}})")).find("clump.secondary"),
              std::string::npos); // its size is required
    EXPECT_NE(parseError(withFields(R"({"clump": 1.5})")).find("fields.clump = 1.5 is out of range"),
              std::string::npos);
    EXPECT_NE(parseError(withFields(R"({"clump_size": 4})")).find("fields.clump_size = 4"),
              std::string::npos);
    EXPECT_NE(parseError(withFields(R"({"mask": -1})")).find("fields.mask"), std::string::npos);
    EXPECT_NE(parseError(makePreset(R"({"lobes": [{}]})",
                                    R"({"type": "poisson", "density_max": 100})",
                                    R"(, "variation": {"clump": 1})"))
                  .find("variation.clump"),
              std::string::npos);
}

TEST(Preset, MaskedSlotForms) {
    const PresetDesc p = parsePreset(
        withFields(R"({"mask": {"type": "gradient", "from": [0, 0, 0], "to": [1, 0, 0],
                                "values": [0, 1]},
                       "clump": {"base": 0.8, "mask": "inside"},
                       "density": {"base": {"type": "noise", "frequency": 2, "range": [0.5, 1]},
                                   "mask": "outside", "else": 0},
                       "color": {"mask": "inside", "else": [1, 0, 0]}})"),
        "t.json");
    EXPECT_EQ(p.mask.kind, FieldDesc::Kind::Gradient);
    EXPECT_EQ(p.clump.mask, FieldDesc::MaskUse::Inside);
    EXPECT_EQ(p.clump.value.x, 0.8f);
    EXPECT_EQ(p.clump.maskElse.x, 0.0f); // the slot's default
    EXPECT_EQ(p.density.mask, FieldDesc::MaskUse::Outside);
    EXPECT_EQ(p.density.kind, FieldDesc::Kind::Noise);
    EXPECT_EQ(p.density.maskElse.x, 0.0f);
    EXPECT_EQ(p.color.mask, FieldDesc::MaskUse::Inside);
    EXPECT_EQ(p.color.value, glm::vec3(1.0f)); // no base: the slot's default
    EXPECT_EQ(p.color.maskElse, glm::vec3(1.0f, 0.0f, 0.0f));
    EXPECT_EQ(p.tiltDeg.mask, FieldDesc::MaskUse::None);

    EXPECT_NE(parseError(withFields(R"({"clump": {"base": 0.5, "mask": "within"}})"))
                  .find("fields.clump.mask = \"within\" is not one of \"inside\", \"outside\""),
              std::string::npos);
    EXPECT_NE(parseError(withFields(R"({"mask": {"base": 0.5, "mask": "inside"}})"))
                  .find("the mask cannot be limited to itself"),
              std::string::npos);
    EXPECT_NE(parseError(withFields(R"({"clump": {"base": 0.5, "else": 0}})"))
                  .find("needs \"mask\""),
              std::string::npos);
    EXPECT_NE(parseError(withFields(R"({"clump": {"mask": "inside", "else": 2}})"))
                  .find("fields.clump.else = 2 is out of range"),
              std::string::npos);
    EXPECT_NE(parseError(withFields(R"({"comb": {"base": [1, 0, 0], "mask": "inside"}})"))
                  .find("the comb cannot be masked"),
              std::string::npos);
    EXPECT_NE(parseError(withFields(R"({"clump": {"base": 0.5, "mask": "inside", "x": 1}})"))
                  .find("unknown key \"fields.clump.x\""),
              std::string::npos);
}

} // namespace
} // namespace spot::noise
