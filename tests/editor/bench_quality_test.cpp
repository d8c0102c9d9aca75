// The bench's check of the --quality table (editor/bench_quality.h) on rows made up here: a
// choice on the front passes, one beaten beyond the noise fails with a line naming the row that
// beats it, a beating within the noise does not count, qualities out of order fail, a choice's
// failed row fails, and a choice the run left out is reported, not failed.
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "bench_quality.h"
#include "render_options.h"

namespace {

using nlohmann::json;
using namespace spot;

/// A table of three: oit, sorted, raymarch 64 steps 2x2 (as splat/quality.h's was when written;
/// the test's own, so that moving the real table does not change what is tested here).
std::vector<splat::QualityChoice> table() {
    splat::RenderSettings march;
    march.steps = 64;
    march.supersample = 2;
    return {
        {"fast", "oit", {}, ""}, {"balanced", "sorted", {}, ""}, {"best", "raymarch", march, ""}};
}

/// A measured row as the bench writes it (the settings as cli::describe() writes them).
json row(const std::string& scene, const std::string& method, const std::string& setting,
         const splat::RenderSettings& settings, double psnr, double wallMs) {
    return {{"scene", scene},
            {"scenario", "s"},
            {"method", method},
            {"setting", setting},
            {"settings", cli::describe(splat::gpuMethod(method), settings)},
            {"psnr", psnr},
            {"wall_ms_median", wallMs},
            {"status", "ok"}};
}

/// Two scenes; per scene: oit 30 dB in 10 ms, sorted 33 dB in 20 ms, raymarch 64x2x2 38 dB in
/// 200 ms, hybrid `hybridDb` in `hybridMs`.
json rows(double hybridDb, double hybridMs) {
    splat::RenderSettings march = table()[2].settings, hybrid;
    json r = json::array();
    for (const char* scene : {"a", "b"}) {
        r.push_back(row(scene, "oit", "ewa mb analytic", {}, 30.0, 10.0));
        r.push_back(row(scene, "sorted", "ewa analytic", {}, 33.0, 20.0));
        r.push_back(row(scene, "raymarch", "64 steps 2x2", march, 38.0, 200.0));
        r.push_back(row(scene, "hybrid", "ewa mb analytic", hybrid, hybridDb, hybridMs));
    }
    return r;
}

TEST(BenchQuality, ChoicesOnTheFrontPass) {
    const cmd::QualityVerdict v = cmd::qualityCheck(rows(32.0, 15.0), table());
    EXPECT_TRUE(v.failures.empty()) << v.doc.dump(2);
    EXPECT_TRUE(v.doc["ok"].get<bool>());
    ASSERT_EQ(v.doc["choices"].size(), 3u);
    for (const json& c : v.doc["choices"])
        EXPECT_EQ(c["status"], "on the front") << c.dump();
    EXPECT_NEAR(double(v.doc["choices"][1]["psnr"]), 33.0, 1e-9);
    EXPECT_NEAR(double(v.doc["choices"][1]["wall_ms"]), 20.0, 1e-9);
    ASSERT_EQ(v.lines.size(), 3u);
    EXPECT_NE(v.lines[1].find("quality balanced = sorted (ewa analytic): 33.00 dB"),
              std::string::npos)
        << v.lines[1];
}

TEST(BenchQuality, ABeatenChoiceFailsNamingTheRowThatBeatsIt) {
    // hybrid: as accurate as sorted and 1.67x faster.
    const cmd::QualityVerdict v = cmd::qualityCheck(rows(33.0, 12.0), table());
    ASSERT_EQ(v.failures.size(), 1u) << v.doc.dump(2);
    EXPECT_NE(v.failures[0].find("quality balanced no longer follows the measurements: hybrid "
                                 "(ewa mb analytic) beats sorted (ewa analytic)"),
              std::string::npos)
        << v.failures[0];
    EXPECT_NE(v.failures[0].find("splat/quality.h"), std::string::npos) << v.failures[0];
    EXPECT_FALSE(v.doc["ok"].get<bool>());
    EXPECT_EQ(v.doc["choices"][1]["status"], "off the front");
    EXPECT_EQ(v.doc["choices"][1]["beaten_by"]["method"], "hybrid");
    // More accurate and twice as fast; 0.05 dB less accurate (a tie) and twice as fast: beaten.
    EXPECT_EQ(cmd::qualityCheck(rows(34.0, 10.0), table()).failures.size(), 1u);
    EXPECT_EQ(cmd::qualityCheck(rows(32.95, 10.0), table()).failures.size(), 1u);
    // Not beaten: 0.2 dB less accurate and twice as fast; as accurate and 1.4x faster; 1 dB more
    // accurate at the same time (the time noise decides which is faster).
    EXPECT_TRUE(cmd::qualityCheck(rows(32.8, 10.0), table()).failures.empty());
    EXPECT_TRUE(cmd::qualityCheck(rows(33.0, 14.3), table()).failures.empty());
    EXPECT_TRUE(cmd::qualityCheck(rows(34.0, 19.0), table()).failures.empty());
}

TEST(BenchQuality, QualitiesOutOfOrderFail) {
    // best picks oit and fast picks raymarch: fast is slower and more accurate than balanced.
    std::vector<splat::QualityChoice> swapped = table();
    std::swap(swapped[0].method, swapped[2].method);
    std::swap(swapped[0].settings, swapped[2].settings);
    const cmd::QualityVerdict v = cmd::qualityCheck(rows(32.0, 15.0), swapped);
    ASSERT_EQ(v.failures.size(), 2u) << v.doc.dump(2);
    EXPECT_NE(v.failures[0].find("quality fast and balanced are out of order"), std::string::npos)
        << v.failures[0];
}

TEST(BenchQuality, AFailedChoiceFailsAndALeftOutOneIsNotChecked) {
    json r = rows(32.0, 15.0);
    for (json& x : r)
        if (x["method"] == "sorted" && x["scene"] == "b")
            x["status"] = "failed";
    const cmd::QualityVerdict v = cmd::qualityCheck(r, table());
    ASSERT_EQ(v.failures.size(), 1u) << v.doc.dump(2);
    EXPECT_NE(v.failures[0].find("whose row failed on b"), std::string::npos) << v.failures[0];
    // A run without the ray-march (bench --methods): best is not measured, not failed.
    json noMarch = json::array();
    for (const json& x : rows(32.0, 15.0))
        if (x["method"] != "raymarch")
            noMarch.push_back(x);
    const cmd::QualityVerdict w = cmd::qualityCheck(noMarch, table());
    EXPECT_TRUE(w.failures.empty()) << w.doc.dump(2);
    EXPECT_EQ(w.doc["choices"][2]["status"], "not measured");
}

} // namespace
