// The quick benchmark suite, run as a user runs it, and the paper's claims asserted on its
// results (hybrid error <= oit error on the close-up; every method's status is ok on
// fur-bunny; the speed-up over the ray-march at matched error is reported, not asserted), and its
// baked rows (the bench bakes each scene itself, into DIR/cache), and the --quality table
// checked against the run.
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <sys/wait.h>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

namespace {

using nlohmann::json;
namespace fs = std::filesystem;

const json& row(const json& rows, const std::string& scene, const std::string& method,
                const std::string& setting) {
    for (const json& r : rows)
        if (r["scene"] == scene && r["method"] == method && r["setting"] == setting)
            return r;
    static const json none;
    ADD_FAILURE() << "no row " << scene << " " << method << " " << setting;
    return none;
}

TEST(BenchQuick, RunsAndHoldsThePapersClaims) {
    const fs::path out = fs::path(SPOT_TEST_TMP_DIR) / "bench-quick";
    for (const char* f : {"results.json", "results.csv", "stability.md", "stability.png", "pareto.png"})
        fs::remove(out / f);
    const std::string cmd = "SPOT_VALIDATION=1 " + std::string(SPOT_SPOTSHELL) +
                            " bench --suite quick --out " + out.string() + " > " +
                            (out.parent_path() / "bench-quick.log").string() + " 2>&1";
    const int status = std::system(cmd.c_str());
    std::ifstream logIn(out.parent_path() / "bench-quick.log");
    const std::string log((std::istreambuf_iterator<char>(logIn)),
                          std::istreambuf_iterator<char>());
    ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << cmd << "\n" << log;
    for (const char* f : {"results.json", "results.csv", "stability.md", "stability.png", "pareto.png"})
        EXPECT_GT(fs::file_size(out / f), 100u) << f;

    std::ifstream in(out / "results.json");
    const json doc = json::parse(in);
    const json& rows = doc["rows"];
    ASSERT_GE(rows.size(), 8u);
    // The animated scene: every splatting method and the ray march over the clip, the update
    // passes timed, an error and a flicker per method beside the reference's flicker.
    const json& animated = doc["animated"];
    ASSERT_GE(animated.size(), 5u);
    for (const json& r : animated) {
        ASSERT_EQ(r.value("status", ""), "ok") << r.dump();
        EXPECT_GT(double(r["update_ms"]), 0.0) << r.dump();
        EXPECT_GT(double(r["animated_ms"]), double(r["update_ms"])) << r.dump();
        EXPECT_GT(double(r["psnr"]), 20.0) << r.dump();
        EXPECT_GT(double(r["reference_flicker"]), 0.0) << "the clip moves";
        // No method flickers far beyond the reference's own change between frames.
        EXPECT_LT(double(r["flicker"]), 3.0 * double(r["reference_flicker"])) << r.dump();
    }
    // One CSV line per row, plus the header.
    std::ifstream csv(out / "results.csv");
    std::size_t lines = 0;
    for (std::string line; std::getline(csv, line);)
        ++lines;
    EXPECT_EQ(lines, rows.size() + 1);

    for (const json& r : rows) {
        for (const char* key : {"kernels_generated", "kernels_drawn", "ms_median", "ms_p90",
                                "wall_ms_median", "psnr", "ssim", "flip", "flicker",
                                "gpu_memory_bytes", "host_memory_bytes"})
            EXPECT_TRUE(r.contains(key)) << key << " in " << r.dump();
        // Timings are positive and finite, and each frame's GPU time lies within the host's wall
        // time for the same frame (so do their medians): a wrong timestamp period or a timestamp
        // from another frame would break it. 1% for two clocks on a real GPU.
        const double ms = r["ms_median"], p90 = r["ms_p90"], wallMs = r["wall_ms_median"];
        EXPECT_TRUE(std::isfinite(ms) && ms > 0.0) << r.dump();
        EXPECT_TRUE(std::isfinite(p90) && p90 > 0.0) << r.dump();
        EXPECT_LE(ms, wallMs * 1.01) << r.dump();
        // The timed warm frames: at least the suite's few, then on until half a second of wall
        // time or the cap.
        const int timed = r["timed_frames"];
        EXPECT_GE(timed, int(doc["timed_frames"])) << r.dump();
        EXPECT_LE(timed, int(doc["max_timed_frames"])) << r.dump();
        EXPECT_TRUE(double(r["timed_wall_ms"]) >= double(doc["timed_ms"]) ||
                    timed == int(doc["max_timed_frames"]))
            << r.dump();
        // The orbit's frames, timed apart (a new view each, the image read back).
        const double orbitMs = r["orbit_ms_median"], orbitWall = r["orbit_wall_ms_median"];
        EXPECT_TRUE(std::isfinite(orbitMs) && orbitMs > 0.0) << r.dump();
        EXPECT_LE(orbitMs, orbitWall * 1.01) << r.dump();
        EXPECT_LE(std::uint64_t(r["kernels_drawn"]), std::uint64_t(r["kernels_generated"]))
            << r.dump();
        // Splatting rows carry their splat pass, a part of the frame, and the roofline of the same
        // primitives.
        if (r["method"] != "raymarch" && r["method"] != "baked") {
            EXPECT_GT(double(r["splat_ms_median"]), 0.0) << r.dump();
            EXPECT_LE(double(r["splat_ms_median"]), ms) << r.dump();
            EXPECT_GT(double(r["roofline_splat_ms"]), 0.0) << r.dump();
            EXPECT_GT(double(r["roofline_fraction"]), 0.0) << r.dump();
            // Fragment efficiency, counted: every covered pixel was shaded, and on the whole
            // furry bunny the splat pass shades at most twice the covered pixels.
            const double fragments = r["fragments_shaded"], covered = r["pixels_covered"];
            EXPECT_GT(covered, 0.0) << r.dump();
            EXPECT_GE(fragments, covered) << r.dump();
            EXPECT_NEAR(double(r["fragment_efficiency"]), fragments / covered, 1e-9) << r.dump();
            if (r["scene"] == "fur-bunny")
                EXPECT_LE(fragments, 2.0 * covered) << r.dump();
        }
        // Every method is ok on the whole furry bunny, at every quick setting (the ray-march's
        // with 2 x 2 rays per pixel: with one ray per pixel it aliases sub-pixel strands and its
        // flicker fails, which the full suite's stability matrix shows).
        if (r["scene"] == "fur-bunny")
            EXPECT_EQ(r["status"], "ok") << r.dump();
        EXPECT_NE(r["status"], "failed") << r.dump(); // every quick setting runs
    }
    // Mean bias (compare's signed relative mean difference against the reference), per method
    // and scene: measured (fur-bunny, close-up) instanced +1.7, +3.3%; oit -5.7, -3.5%; oit
    // constant -5.1, -3.5%; hybrid -2.7, +1.3%; sorted +2.5, +2.1%; the 64-step march -0.7,
    // -1.4%; baked +6.4, +7.7%. Each bound is that plus 1.5 points: a widening that conserved
    // optical depth again (sorted +9.3% on fur-bunny, docs/bench/measurements.md) fails it.
    const struct {
        const char* scene;
        const char* method;
        const char* setting;
        double bound;
    } biases[] = {
        {"fur-bunny", "instanced", "default", 0.032},
        {"fur-bunny", "oit", "ewa mb analytic", 0.072},
        {"fur-bunny", "oit", "ewa constant analytic", 0.066},
        {"fur-bunny", "hybrid", "ewa mb analytic", 0.042},
        {"fur-bunny", "sorted", "ewa analytic", 0.040},
        {"fur-bunny", "raymarch", "64 steps 2x2", 0.022},
        {"fur-bunny", "baked", "res 128, 4 levels, 4 peels", 0.079},
        {"fur-bunny-close", "instanced", "default", 0.048},
        {"fur-bunny-close", "oit", "ewa mb analytic", 0.050},
        {"fur-bunny-close", "hybrid", "ewa mb analytic", 0.028},
        {"fur-bunny-close", "sorted", "ewa analytic", 0.036},
        {"fur-bunny-close", "raymarch", "64 steps 2x2", 0.029},
        {"fur-bunny-close", "baked", "res 128, 4 levels, 4 peels", 0.092},
    };
    for (const auto& b : biases) {
        const json& r = row(rows, b.scene, b.method, b.setting);
        ASSERT_TRUE(r.contains("bias")) << r.dump();
        EXPECT_LE(std::abs(double(r["bias"])), b.bound) << r.dump();
    }
    // The paper's fig. 4: compositing the closest kernel over OIT helps the close-up.
    const json& oit = row(rows, "fur-bunny-close", "oit", "ewa mb analytic");
    const json& hybrid = row(rows, "fur-bunny-close", "hybrid", "ewa mb analytic");
    EXPECT_GE(double(hybrid["psnr"]), double(oit["psnr"]));
    EXPECT_LE(double(hybrid["flip"]), double(oit["flip"]));
    // The hybrid's closest kernel found by a depth pass of its own: the same closest kernel as
    // by the atomicMin, so the same error up to rounding (its cost is what the row measures).
    // The atomic variant evaluates small kernels in a compute pass whose OIT sums are fixed
    // point, the depth pass draws every kernel (renderer_test holds the two bit-identical with
    // every kernel drawn); measured apart by 1e-4 dB and 1e-6 FLIP.
    for (const char* scene : {"fur-bunny", "fur-bunny-close"}) {
        const json& atomic = row(rows, scene, "hybrid", "ewa mb analytic");
        const json& depthPass = row(rows, scene, "hybrid", "depth pass ewa mb analytic");
        EXPECT_NEAR(double(atomic["psnr"]), double(depthPass["psnr"]), 0.01) << scene;
        EXPECT_NEAR(double(atomic["flip"]), double(depthPass["flip"]), 1e-5) << scene;
    }
    // At matched error, splatting against the ray-march: the suite holds raymarch settings at
    // least as accurate as oit/hybrid (the quick suite's longest march is more accurate than
    // both on fur-bunny), so the speed-up at matched error can be read from its rows. Timing is
    // measured and reported here, never asserted (a shared machine's load decides it): the
    // ratio is printed, and must be a measured, finite one.
    int compared = 0;
    for (const json& r : rows) {
        if (r["method"] != "raymarch" || r["status"] == "failed")
            continue;
        for (const char* method : {"oit", "hybrid"}) {
            const json& s = row(rows, r["scene"], method, "ewa mb analytic");
            if (double(r["flip"]) <= double(s["flip"])) {
                ++compared;
                const double ratio = double(r["ms_median"]) / double(s["ms_median"]);
                EXPECT_TRUE(std::isfinite(ratio) && ratio > 0.0) << r.dump() << s.dump();
                std::printf("matched error on %s: raymarch %s takes %.2fx %s's frame\n",
                            std::string(r["scene"]).c_str(), std::string(r["setting"]).c_str(),
                            ratio, method);
            }
        }
    }
    EXPECT_GE(compared, 2);

    // baked: a row per quick scene, rendered (not refused), its error numbers finite, its bake
    // made by the bench and cached, the bake columns appended to the CSV after the old ones.
    int baked = 0;
    for (const json& r : rows) {
        if (r["method"] != "baked")
            continue;
        ++baked;
        EXPECT_TRUE(r["status"] == "ok" || r["status"] == "degraded") << r.dump();
        bool complete = true;
        for (const char* key : {"psnr", "ssim", "flip", "flicker", "ms_median", "voxel_size",
                                "bake_seconds", "bake_bytes", "resolution", "levels", "peel_passes"}) {
            complete &= r.contains(key) && r[key].is_number();
            EXPECT_TRUE(r.contains(key) && r[key].is_number() && std::isfinite(double(r[key])))
                << key << " in " << r.dump();
        }
        if (!complete)
            continue;
        EXPECT_GT(double(r["voxel_size"]), 0.0) << r.dump();
        EXPECT_GT(int(r["resolution"]), 0) << r.dump();
        EXPECT_GE(int(r["levels"]), 1) << r.dump();
        EXPECT_GE(int(r["peel_passes"]), 1) << r.dump();
        EXPECT_GT(double(r["bake_seconds"]), 0.0) << r.dump();
        EXPECT_GT(std::uint64_t(r["bake_bytes"]), 0u) << r.dump();
        bool found = false; // the bake file, in the cache, of the recorded size
        for (const fs::directory_entry& e : fs::directory_iterator(out / "cache"))
            found |= e.path().extension() == ".vdb" && e.file_size() == std::uint64_t(r["bake_bytes"]);
        EXPECT_TRUE(found) << r.dump();
        // On the whole bunny the bake is good enough to be ok.
        if (r["scene"] == "fur-bunny")
            EXPECT_EQ(r["status"], "ok") << r.dump();
    }
    EXPECT_GE(baked, 1);
    std::ifstream header(out / "results.csv");
    std::string first;
    std::getline(header, first);
    EXPECT_EQ(first.rfind("scene,scenario,method,setting,width,height,kernels_generated,", 0), 0u) << first;
    EXPECT_NE(first.find(",status,reason,resolution,voxel_size,levels,peel_passes,bake_seconds,"
                         "bake_bytes,bake_cached"),
              std::string::npos)
        << first;
    // The --quality table (splat/quality.h) follows this run's measurements: each choice on the
    // front of mean PSNR against wall time over the two scenes, within noise, and the three in
    // order (the bench exits 1 otherwise, above, with a line naming the row that beats a choice;
    // editor/bench_quality.h).
    const json& quality = doc["quality"];
    ASSERT_TRUE(quality.is_object()) << doc.dump().substr(0, 400);
    EXPECT_TRUE(quality["ok"].get<bool>()) << quality.dump(2);
    ASSERT_EQ(quality["choices"].size(), 3u) << quality.dump(2);
    for (const json& c : quality["choices"])
        EXPECT_EQ(c["status"], "on the front") << c.dump() << "\n" << quality.dump(2);
    EXPECT_NE(log.find("quality balanced = "), std::string::npos) << log;
    // The stability matrix has baked's column.
    std::ifstream mdIn(out / "stability.md");
    const std::string md((std::istreambuf_iterator<char>(mdIn)), std::istreambuf_iterator<char>());
    EXPECT_NE(md.find("| baked |"), std::string::npos) << md;
}

} // namespace
