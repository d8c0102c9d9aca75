// The `spotshell` command as a user runs it: exit codes, one-line errors, byte-identical output on
// any thread count, the PLY's properties.
#include <array>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>
#include <sys/wait.h>
#include <unistd.h>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "cli_run.h"
#include "noise/image.h"
#include "splat/quality.h"

namespace {

using Result = spot::test::CliResult;

std::string tmp(const std::string& name) { return std::string(SPOT_TEST_TMP_DIR) + "/" + name; }

std::string slurp(const std::string& file) {
    std::ifstream in(file, std::ios::binary);
    std::ostringstream s;
    s << in.rdbuf();
    return s.str();
}

/// Validation on for every GPU method the command runs: any error fails the command (exit 1).
Result run(const std::string& args) { return spot::test::runSpotshell(args, "SPOT_VALIDATION=1"); }

void write(const std::string& file, const std::string& text) {
    std::ofstream(file, std::ios::binary) << text;
}

std::string preset(const std::string& name) {
    return std::string(SPOT_SOURCE_DIR) + "/presets/" + name + ".json";
}
std::string bunny() { return std::string(SPOT_SOURCE_DIR) + "/presets/meshes/bunny.ply"; }

/// Exit code 2 with exactly one line on stderr that says what is wrong.
void expectInputError(const std::string& args, const std::string& phrase) {
    const Result r = run(args);
    EXPECT_EQ(r.code, 2) << args << "\n" << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << args << "\n" << r.err;
    EXPECT_EQ(r.err.rfind("spotshell: error: ", 0), 0u) << r.err;
    EXPECT_NE(r.err.find(phrase), std::string::npos) << "expected '" << phrase << "' in: " << r.err;
}

TEST(Cli, HelpForEverySubcommand) {
    for (const char* cmd : {"--help", "impulses --help", "info --help", "bake --help"}) {
        const Result r = run(cmd);
        EXPECT_EQ(r.code, 0) << cmd;
        EXPECT_NE(r.out.find("usage: spotshell"), std::string::npos) << cmd;
    }
}

TEST(Cli, InfoPrintsCountsAndBounds) {
    const Result r = run("info --mesh " + bunny());
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_NE(r.out.find("vertices   1839"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("triangles"), std::string::npos);
    EXPECT_NE(r.out.find("bounds"), std::string::npos);
    EXPECT_NE(r.out.find("dropped"), std::string::npos);
}

TEST(Cli, BadInputGivesOneLineAndExitCode2) {
    expectInputError("frobnicate", "unknown command");
    expectInputError("impulses --preset " + preset("fur") + " --out " + tmp("x.ply"),
                     "--mesh FILE is required");
    expectInputError("impulses --mesh " + bunny() + " --preset " + preset("fur") + " --out " +
                         tmp("x.ply") + " --colour red",
                     "unknown option --colour");
    expectInputError("impulses --mesh " + bunny() + " --preset " + preset("fur") + " --out " +
                         tmp("x.ply") + " --seed banana",
                     "--seed expects an integer");
    expectInputError("impulses --mesh /nonexistent/mesh.ply --preset " + preset("fur") +
                         " --out " + tmp("x.ply"),
                     "mesh.ply");
    write(tmp("broken.ply"), "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n"
                             "property float y\nproperty float z\nelement face 1\n"
                             "property list uchar int vertex_indices\nend_header\n"
                             "0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n");
    expectInputError("info --mesh " + tmp("broken.ply"), "broken.ply");
    write(tmp("nan.obj"), "v 0 0 0\nv 1 nan 0\nv 0 1 0\nf 1 2 3\n");
    expectInputError("info --mesh " + tmp("nan.obj"), "nan.obj");
    write(tmp("bad.json"), "{\"version\": 1, \"kernel\": {\"lobes\": [] }}");
    expectInputError("impulses --mesh " + bunny() + " --preset " + tmp("bad.json") + " --out " +
                         tmp("x.ply"),
                     "bad.json");
    expectInputError("impulses --mesh " + bunny() + " --preset " + preset("fur") + " --out " +
                         tmp("x.ply") + " --cell-size 1e-6",
                     "cell size");
    expectInputError("impulses --mesh generated:cube --preset " + preset("fur") + " --out " +
                         tmp("x.ply"),
                     "unknown generated mesh");
    expectInputError("impulses --mesh " + bunny() + " --preset " + preset("fur") +
                         " --out /nonexistent/dir/x.ply",
                     "does not exist");
}

TEST(Cli, FailedRunLeavesNoPartialOutput) {
    const std::string out = tmp("kept.ply");
    write(out, "previous contents");
    const Result r = run("impulses --mesh " + bunny() + " --preset " + preset("fur") + " --out " +
                         out + " --cell-size 1e-6");
    EXPECT_EQ(r.code, 2);
    EXPECT_EQ(slurp(out), "previous contents");
}

TEST(Cli, ImpulsesPlyIsByteIdenticalOnOneAndTwoThreads) {
    for (const char* name : {"fur", "grass", "lichen", "ring", "uniform"}) {
        const std::string a = tmp(std::string(name) + "-t1.ply"), b = tmp(std::string(name) + "-t2.ply");
        const std::string common = "impulses --mesh " + bunny() + " --preset " + preset(name) +
                                   " --seed 7 --out ";
        const Result r1 = run(common + a + " --threads 1");
        const Result r2 = run(common + b + " --threads 2");
        ASSERT_EQ(r1.code, 0) << r1.err;
        ASSERT_EQ(r2.code, 0) << r2.err;
        EXPECT_NE(r1.out.find("impulses"), std::string::npos);
        EXPECT_NE(r1.out.find("wrote " + a), std::string::npos) << r1.out;
        const std::string da = slurp(a), db = slurp(b);
        EXPECT_GT(da.size(), 1000u) << name;
        EXPECT_TRUE(da == db) << name << ": PLY differs between 1 and 2 threads";
    }
}

TEST(Cli, ImpulsesPlyHasTheDocumentedProperties) {
    const std::string out = tmp("props.ply");
    const Result r = run("impulses --mesh generated:sphere --preset " + preset("uniform") +
                         " --out " + out);
    ASSERT_EQ(r.code, 0) << r.err;
    const std::string data = slurp(out);
    const std::string header = data.substr(0, data.find("end_header"));
    for (const char* p : {"x", "y", "z", "nx", "ny", "nz", "tx", "ty", "tz", "sx", "sy", "sz",
                          "red", "green", "blue"})
        EXPECT_NE(header.find(std::string("property float ") + p + "\n"), std::string::npos) << p;
    EXPECT_NE(header.find("property int face\n"), std::string::npos);
    // The vertex count in the header matches the data that follows.
    const auto at = header.find("element vertex ");
    ASSERT_NE(at, std::string::npos);
    const long count = std::stol(header.substr(at + 15));
    const std::size_t body = data.size() - (data.find("end_header\n") + 11);
    EXPECT_EQ(body, std::size_t(count) * (24 * 4 + 4));
    EXPECT_GT(count, 1000);
}

} // namespace

namespace {

TEST(Cli, RenderReferenceWritesImageMetadataAndStats) {
    const std::string scene = std::string(SPOT_SOURCE_DIR) + "/presets/scenes/ring-sphere.json";
    const std::string exr = tmp("ring.exr"), png = tmp("ring.png"), stats = tmp("ring.json");
    const Result r = run("render --scene " + scene + " --method reference --size 40x30 --spp 2 --out " +
                         exr + " --stats " + stats);
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_NE(r.out.find("wrote " + exr), std::string::npos) << r.out;
    const std::string data = slurp(exr);
    EXPECT_EQ(data.substr(0, 4), std::string("\x76\x2f\x31\x01", 4)); // OpenEXR magic
    EXPECT_NE(data.find("spotshell:method"), std::string::npos);
    EXPECT_NE(data.find("spotshell:spp"), std::string::npos);
    const std::string json = slurp(stats);
    for (const char* key : {"\"method\": \"reference\"", "\"width\": 40", "\"height\": 30", "\"spp\": 2",
                            "\"seconds\"", "\"kernels_generated\"", "\"memory_bytes\""})
        EXPECT_NE(json.find(key), std::string::npos) << key << " in " << json;
    const Result p = run("render --scene " + scene + " --method reference --size 40x30 --spp 1 --out " + png);
    ASSERT_EQ(p.code, 0) << p.err;
    EXPECT_EQ(slurp(png).substr(1, 3), "PNG");
}

TEST(Cli, RenderRejectsBadRequests) {
    const std::string scene = std::string(SPOT_SOURCE_DIR) + "/presets/scenes/ring-sphere.json";
    expectInputError("render --scene " + scene + " --method teleport --out " + tmp("x.png"), "unknown method");
    expectInputError("render --scene " + scene + " --method reference --size 40 --out " + tmp("x.png"), "--size");
    expectInputError("render --scene " + scene + " --method reference --out " + tmp("x.bmp"), "unknown image format");
    expectInputError("render --scene " + scene + " --method reference --spp 0 --out " + tmp("x.png"), "--spp");
    write(tmp("scene.json"), "{\"version\": 1, \"mesh\": \"generated:sphere\", \"preset\": \"x.json\", "
                             "\"camera\": {\"eye\": [0,0,1], \"target\": [0,0,1]}, "
                             "\"image\": {\"width\": 8, \"height\": 8}}");
    expectInputError("render --scene " + tmp("scene.json") + " --method reference --out " + tmp("x.png"),
                     "camera.eye and camera.target must be different");
    write(tmp("scene2.json"), "{\"version\": 1, \"mesh\": \"generated:sphere\", \"preset\": \"x.json\", "
                              "\"camera\": {\"eye\": [0,0,3], \"target\": [0,0,0]}, "
                              "\"image\": {\"width\": 100000, \"height\": 8}}");
    expectInputError("render --scene " + tmp("scene2.json") + " --method reference --out " + tmp("x.png"),
                     "image.width");
}

} // namespace

namespace {

TEST(Cli, RenderGpuMethodsWithValidation) {
    const std::string scene = std::string(SPOT_SOURCE_DIR) + "/presets/scenes/fur-bunny.json";
    for (const char* method : {"instanced", "oit", "hybrid"}) {
        const std::string out = tmp(std::string("gpu-") + method + ".png");
        const std::string stats = tmp(std::string("gpu-") + method + ".json");
        const Result r = run("render --scene " + scene + " --method " + method +
                             " --size 64x48 --out " + out + " --stats " + stats);
        ASSERT_EQ(r.code, 0) << method << ": " << r.err;
        EXPECT_NE(r.out.find("wrote " + out), std::string::npos) << r.out;
        const std::string json = slurp(stats);
        for (const char* key : {"\"gpu_ms\"", "\"kernels_generated\"", "\"kernels_drawn\"",
                                "\"gpu_memory_bytes\"", "\"validation_errors\": 0", "\"width\": 64"})
            EXPECT_NE(json.find(key), std::string::npos) << method << ": " << key << " in " << json;
    }
}

// fur-bunny is lit; --unlit renders it as the same scene with "shading": {"mode": "unlit"} and
// its lights and sky dropped does, bit for bit, and lit differs.
TEST(Cli, RenderUnlitDropsTheScenesLights) {
    const std::string dir = std::string(SPOT_SOURCE_DIR) + "/presets/scenes/";
    nlohmann::json j = nlohmann::json::parse(slurp(dir + "fur-bunny.json"));
    ASSERT_EQ(j["shading"]["mode"], "lit");
    j["shading"] = {{"mode", "unlit"}};
    j.erase("lights");
    j.erase("sky");
    for (const char* key : {"mesh", "preset"})
        j[key] = dir + j[key].get<std::string>();
    const std::string unlitScene = tmp("fur-bunny-unlit.json");
    std::ofstream(unlitScene) << j.dump(1);
    const std::string flag = tmp("unlit-flag.exr"), scene = tmp("unlit-scene.exr"),
                      lit = tmp("unlit-lit.exr");
    for (const auto& [args, out] : {std::pair{dir + "fur-bunny.json --unlit", flag},
                                    std::pair{unlitScene, scene},
                                    std::pair{dir + "fur-bunny.json", lit}}) {
        const Result r = run("render --scene " + args + " --method hybrid --size 48x40 --out " + out);
        ASSERT_EQ(r.code, 0) << r.err;
    }
    EXPECT_TRUE(spot::noise::readImage(flag).pixels == spot::noise::readImage(scene).pixels);
    EXPECT_FALSE(spot::noise::readImage(flag).pixels == spot::noise::readImage(lit).pixels);
}

TEST(Cli, RenderRepeatsWarmFramesAndReportsTheirTimes) {
    const std::string scene = std::string(SPOT_SOURCE_DIR) + "/presets/scenes/fur-bunny.json";
    const std::string out = tmp("gpu-repeat.png"), stats = tmp("gpu-repeat.json");
    const Result r = run("render --scene " + scene + " --method hybrid --size 64x48 --repeat 3 "
                         "--count-fragments --out " + out + " --stats " + stats);
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_NE(r.out.find("3 warm frames"), std::string::npos) << r.out;
    const nlohmann::json j = nlohmann::json::parse(slurp(stats));
    EXPECT_EQ(j["warm_frames"], 3);
    for (const char* series : {"frame_ms", "wall_ms"})
        for (const char* stat : {"median", "p90", "min"}) {
            ASSERT_TRUE(j[series].contains(stat)) << series << "." << stat;
            EXPECT_GT(double(j[series][stat]), 0.0) << series << "." << stat;
        }
    // The host waits for the GPU: a frame's wall time holds its GPU time.
    EXPECT_GE(double(j["wall_ms"]["min"]), 0.99 * double(j["frame_ms"]["min"]));
    EXPECT_GT(double(j["first_frame"]["gpu_ms"]), 0.0);
    EXPECT_GE(double(j["fragment_efficiency"]), 1.0);
    EXPECT_GT(j["pixels_covered"].get<std::uint64_t>(), 0u);
    expectInputError("render --scene " + scene + " --method oit --repeat -1 --out " + tmp("x.png"),
                     "--repeat");
}

TEST(Cli, RenderGpuRejectsBadSettings) {
    const std::string scene = std::string(SPOT_SOURCE_DIR) + "/presets/scenes/fur-bunny.json";
    expectInputError("render --scene " + scene + " --method oit --ewa maybe --out " + tmp("x.png"), "--ewa");
    expectInputError("render --scene " + scene + " --method oit --weight heavy --out " + tmp("x.png"), "--weight");
    expectInputError("render --scene " + scene + " --method oit --kernel-samples 100000 --out " + tmp("x.png"),
                     "--kernel-samples");
    expectInputError("render --scene " + scene + " --method hybrid --closest nearest --out " + tmp("x.png"),
                     "--closest");
    expectInputError("render --scene " + scene + " --method raymarch --supersample 9 --out " + tmp("x.png"),
                     "--supersample");
    expectInputError("render --scene " + scene + " --method raymarch --steps 5000 --out " + tmp("x.png"),
                     "--steps");
}

// A setting given to a method that does not take it would silently do nothing: it is refused
// (exit 2, one line naming the methods that take it), from the registry's settings.
TEST(Cli, RenderRefusesSettingsTheMethodDoesNotTake) {
    const std::string scene = std::string(SPOT_SOURCE_DIR) + "/presets/scenes/fur-bunny.json";
    const std::string render = "render --scene " + scene + " --size 16x12 --out " + tmp("x.png");
    expectInputError(render + " --method hybrid --supersample 2",
                     "--supersample is a setting of raymarch, not of hybrid");
    expectInputError(render + " --method hybrid --steps 64",
                     "--steps is a setting of raymarch, not of hybrid");
    expectInputError(render + " --method hybrid --peel-passes 2",
                     "--peel-passes is a setting of baked, not of hybrid");
    expectInputError(render + " --method instanced --closest depth-pass",
                     "--closest is a setting of hybrid, not of instanced");
    expectInputError(render + " --method reference --ewa off",
                     "--ewa is a setting of instanced, oit, hybrid, sorted, not of reference");
    expectInputError(render + " --method oit --spp 4", "--spp is a setting of reference, not of oit");
    expectInputError(render + " --method reference --repeat 2", "--repeat");
    EXPECT_FALSE(std::filesystem::exists(tmp("x.png")));
    // Every option's help names the methods that take it.
    const Result help = run("render --help");
    EXPECT_NE(help.out.find("raymarch: samples along each ray"), std::string::npos) << help.out;
}

TEST(Cli, RenderRaymarchSplitsAndSupersamples) {
    // 100 steps do not fit one dispatch on fur (the loop guard splits them); 2 x 2 rays per pixel.
    const std::string scene = std::string(SPOT_SOURCE_DIR) + "/presets/scenes/fur-bunny.json";
    const std::string out = tmp("gpu-raymarch.png"), stats = tmp("gpu-raymarch.json");
    const Result r = run("render --scene " + scene + " --method raymarch --steps 100 --supersample 2 "
                         "--size 48x36 --out " + out + " --stats " + stats);
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_NE(r.out.find("wrote " + out), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("2x2 rays per pixel"), std::string::npos) << r.out;
    const std::string json = slurp(stats);
    for (const char* key : {"\"steps\": 100", "\"supersample\": 2", "\"dispatches\"",
                            "\"steps_per_dispatch\"", "\"loop_bound\"", "\"validation_errors\": 0",
                            "\"width\": 48"})
        EXPECT_NE(json.find(key), std::string::npos) << key << " in " << json;
    EXPECT_EQ(json.find("\"dispatches\": 1,"), std::string::npos) << json;
}

} // namespace

// info takes the generated meshes scenes and `impulses` take (issue: it refused them).
TEST(Cli, InfoTakesGeneratedMeshes) {
    const Result r = run("info --mesh generated:torus");
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_NE(r.out.find("mesh torus"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("triangles"), std::string::npos) << r.out;
    expectInputError("info --mesh generated:teapot", "teapot");
}

// --quality picks the method and its settings from splat/quality.h's table; without --method,
// render uses the balanced choice; --quality with --method is refused; the setting options still
// apply on top of a quality's choice.
TEST(Cli, RenderQualityPicksTheTablesChoice) {
    const std::string scene = std::string(SPOT_SOURCE_DIR) + "/presets/scenes/fur-bunny.json";
    const auto renderStats = [&](const std::string& options, const std::string& name) {
        const std::string out = tmp("quality-" + name + ".png"),
                          stats = tmp("quality-" + name + ".json");
        const Result r = run("render --scene " + scene + " --size 40x30 " + options + " --out " +
                             out + " --stats " + stats);
        EXPECT_EQ(r.code, 0) << options << ": " << r.err;
        return r.code == 0 ? nlohmann::json::parse(slurp(stats)) : nlohmann::json();
    };
    const spot::splat::QualityChoice* balanced =
        spot::splat::findQuality(spot::splat::kDefaultQuality);
    ASSERT_NE(balanced, nullptr);
    const nlohmann::json byDefault = renderStats("", "default");
    EXPECT_EQ(byDefault.value("method", ""), balanced->method) << byDefault.dump();
    EXPECT_EQ(byDefault.value("quality", ""), "balanced") << byDefault.dump();
    // Each quality renders its choice (best with fewer steps: a setting option on top of the
    // choice; its other settings stay the table's).
    ASSERT_EQ(spot::splat::qualityChoices().size(), 3u);
    for (const spot::splat::QualityChoice& q : spot::splat::qualityChoices()) {
        if (q.name == balanced->name)
            continue; // the default's
        const std::string steps = q.method == "raymarch" ? " --steps 8" : "";
        const nlohmann::json j = renderStats("--quality " + q.name + steps, q.name);
        EXPECT_EQ(j.value("method", ""), q.method) << q.name;
        EXPECT_EQ(j.value("quality", ""), q.name) << q.name;
        if (q.method == "raymarch") {
            EXPECT_EQ(j.value("steps", 0), 8) << j.dump();
            EXPECT_EQ(j.value("supersample", 0), q.settings.supersample) << j.dump();
        }
    }
    // --quality with --method is refused; an unknown quality names the known ones; a setting
    // the chosen method does not take names the quality that chose it.
    expectInputError("render --scene " + scene + " --method oit --quality best --out " +
                         tmp("x.png"),
                     "give --quality or --method oit, not both");
    expectInputError("render --scene " + scene + " --quality great --out " + tmp("x.png"),
                     "unknown quality 'great' (fast, balanced or best)");
    expectInputError("render --scene " + scene + " --steps 16 --out " + tmp("x.png"),
                     "(--quality balanced picks " + balanced->method +
                         "): --steps is a setting of");
}

namespace {

std::string character() { return std::string(SPOT_SOURCE_DIR) + "/examples/character/"; }

/// A scene file in the tmp folder: `keys` (JSON members, with a trailing comma) then the rest.
std::string sceneFile(const std::string& name, const std::string& keys,
                      const std::string& mesh = bunny(), const std::string& presetFile = preset("fur")) {
    const std::string file = tmp(name + ".json");
    write(file, R"({"version": 1, "mesh": ")" + mesh + R"(", "preset": ")" + presetFile + R"(", )" +
                    keys +
                    R"( "camera": {"eye": [0, 0.5, 2], "target": [0, 0.4, 0]}, )"
                    R"("image": {"width": 16, "height": 16}})");
    return file;
}

} // namespace

// `info` on the character as its scene loads it: the weld's counts, its meshes, nodes, materials
// and parts (the stand left bald by the scene's "grow"), why triangles were dropped, and the
// clip's frames from Blender's frame 1.
TEST(Cli, InfoListsTheCharactersPartsWeldAndFrames) {
    const Result r = run("info --scene " + character() + "character-fur.json");
    ASSERT_EQ(r.code, 0) << r.err;
    for (const char* line :
         {"glTF       2.0", "vertices   302", "split copies merged at", "dropped    0 degenerate",
          "meshes     2: 0 'Stand', 1 'Body'", "nodes      6: 0 'Stand'", "materials  2",
          "0 'Wood': base colour 0.5 0.3 0.1 1, no texture",
          "1 'Fur': base colour 1 1 1 1, texture 'fur_colour' (embedded, image/png, TEXCOORD_0)",
          "mesh 0 'Stand' primitive 0, node 0 'Stand', material 0 'Wood': 12 triangles, no fur",
          "mesh 1 'Body' primitive 0, node 4 'Body', material 1 'Fur'", "grows fur",
          "clip       walk, 1 s from 0.0416667 s", "frames     1-25 at 24 fps"})
        EXPECT_NE(r.out.find(line), std::string::npos) << line << "\n" << r.out;
    const Result off = run("info --mesh " + character() + "character.glb --weld off");
    ASSERT_EQ(off.code, 0) << off.err;
    EXPECT_NE(off.out.find("welded     off"), std::string::npos) << off.out;
    // Past the clip, the pose is clamped and info says so.
    const Result late = run("info --mesh " + character() + "character.glb --time 5");
    ASSERT_EQ(late.code, 0) << late.err;
    EXPECT_NE(late.out.find("pose       at 5 s (frame 120), clamped to the clip's end at 1.04167 s"),
              std::string::npos)
        << late.out;
}

// The scene keys "weld" and "grow", and what the scene asks of a mesh that cannot give it.
TEST(Cli, SceneWeldAndGrowKeysAndTheirErrors) {
    const std::string glb = character() + "character.glb";
    expectInputError("info --scene " + sceneFile("weld-bad", R"("weld": "yes",)"),
                     "weld must be true, false or a tolerance");
    expectInputError("info --scene " + sceneFile("weld-big", R"("weld": 0.5,)"),
                     "weld = 0.5 is out of range");
    expectInputError("info --scene " + sceneFile("grow-obj", R"("grow": {"meshes": ["Body"]},)"),
                     "chooses glTF meshes and nodes; this mesh has none");
    expectInputError(
        "info --scene " + sceneFile("grow-typo", R"("grow": {"nodes": ["Bdy"]},)", glb),
        "grow.nodes names 'Bdy', which is none of its nodes");
    expectInputError(
        "info --scene " + sceneFile("grow-key", R"("grow": {"mesh": ["Body"]},)", glb),
        "unknown key \"grow.mesh\"");
    const Result off = run("info --scene " + sceneFile("weld-off", R"("weld": false,)", glb));
    ASSERT_EQ(off.code, 0) << off.err;
    EXPECT_NE(off.out.find("welded     off"), std::string::npos) << off.out;
}

// An animation block on a mesh that does not move: a clip or a rest frame is refused, a block
// nothing uses is a warning; a glTF 1.0 file names its version; a preset or mesh that does not
// resolve names the path tried; baked without --bake is refused before the device starts.
TEST(Cli, SilentOrUnclearInputsSayWhatIsWrong) {
    const std::string obj = tmp("static-square.obj");
    write(obj, "v -1 0 -1\nv 1 0 -1\nv 1 0 1\nv -1 0 1\nf 1 4 3 2\n");
    const std::string png = tmp("static.png");
    expectInputError("render --method reference --spp 1 --out " + png + " --scene " +
                         sceneFile("anim-clip", R"("animation": {"clip": "walk"},)", obj),
                     "animation.clip 'walk' names a clip, but mesh");
    expectInputError("render --method reference --spp 1 --out " + png + " --scene " +
                         sceneFile("anim-rest", R"("animation": {"rest_frame": 2},)", obj),
                     "animation.rest_frame is a mesh cache's");
    const Result warned = run("render --method reference --spp 1 --out " + png + " --scene " +
                              sceneFile("anim-time", R"("animation": {"time": 1.5},)", obj));
    EXPECT_EQ(warned.code, 0) << warned.err;
    EXPECT_NE(warned.err.find("warning: its \"animation\" block has no effect"), std::string::npos)
        << warned.err;
    const std::string old = tmp("old-version.gltf");
    write(old, R"({"asset": {"version": "1.0"}, "meshes": {}})");
    expectInputError("info --mesh " + old, "a glTF 1.0 file; spotshell reads glTF 2.0");
    const std::string lost = sceneFile("lost-preset", "", bunny(), "no-such/fur.json");
    const Result r = run("render --method reference --spp 1 --out " + png + " --scene " + lost);
    EXPECT_EQ(r.code, 2);
    EXPECT_NE(r.err.find("preset 'no-such/fur.json' (relative to the scene's folder) is not a "
                         "file: tried " + tmp("no-such/fur.json")),
              std::string::npos)
        << r.err;
    expectInputError("render --method reference --spp 1 --out " + png + " --scene " +
                         sceneFile("ok", "") + " --preset missing.json",
                     "preset 'missing.json' (relative to the current folder) is not a file");
    expectInputError("render --method baked --out " + png + " --scene " + sceneFile("ok", ""),
                     "--method baked needs --bake FILE.vdb");
}

// --stats of a --frames range lists every frame's own numbers (a CPU method too).
TEST(Cli, StatsOfAFramesRangeListEveryFrame) {
    const std::string scene = character() + "character-fur.json";
    for (const char* method : {"sorted", "reference --spp 1"}) {
        SCOPED_TRACE(method);
        const std::string stats = tmp("frames-stats.json");
        const Result r = run(std::string("render --method ") + method + " --scene " + scene +
                             " --unlit --size 24x24 --frames 1-3 --out " + tmp("fs.%04d.png") +
                             " --stats " + stats);
        ASSERT_EQ(r.code, 0) << r.err;
        const nlohmann::json j = nlohmann::json::parse(slurp(stats));
        ASSERT_TRUE(j.contains("frames")) << j.dump(2);
        ASSERT_EQ(j["frames"].size(), 3u);
        EXPECT_EQ(j["frame_count"], 3);
        for (int i = 0; i < 3; ++i) {
            const nlohmann::json& f = j["frames"][std::size_t(i)];
            EXPECT_EQ(f["frame"], i + 1);
            EXPECT_NEAR(double(f["time"]), (i + 1) / 24.0, 1e-12);
            EXPECT_EQ(f["file"], tmp("fs.000" + std::to_string(i + 1) + ".png"));
            EXPECT_FALSE(f.contains("first_frame"));
        }
        EXPECT_FALSE(j.contains("first_frame"));
        EXPECT_EQ(j["scene"], "character-fur");
    }
}
