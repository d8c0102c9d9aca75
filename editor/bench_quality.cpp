#include "bench_quality.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <utility>

#include "noise/error.h"
#include "render_options.h"
#include "splat/method_vk.h"

namespace spot::cmd {

namespace {

using nlohmann::json;

std::string fmt(const char* format, auto... args) {
    char buf[512];
    std::snprintf(buf, sizeof buf, format, args...);
    return buf;
}

/// A row with measurements (status ok or degraded).
bool measured(const json& r) {
    return (r.value("status", "") == "ok" || r.value("status", "") == "degraded") &&
           r.contains("psnr");
}

} // namespace

QualityVerdict qualityCheck(const json& rows, const std::vector<splat::QualityChoice>& table) {
    struct Point {
        std::string method, setting;
        json settings;
        double psnr = 0.0, logMs = 0.0;
        int scenes = 0;                      ///< measured on this many
        std::vector<std::string> unmeasured; ///< the scenes where its row failed
    };
    std::vector<std::string> scenes;
    std::map<std::pair<std::string, std::string>, Point> points;
    for (const json& r : rows) {
        if (std::string(r["scenario"]).rfind("scaling", 0) == 0)
            continue;
        if (std::find(scenes.begin(), scenes.end(), r["scene"]) == scenes.end())
            scenes.push_back(r["scene"]);
        const std::string method = r["method"];
        const splat::MethodInfo* info = splat::findMethod(method);
        if (!info || info->takes(splat::settings::bake))
            continue;
        Point& p = points[{method, r["setting"]}];
        p.method = method;
        p.setting = r["setting"];
        if (r.contains("settings"))
            p.settings = r["settings"];
        if (!measured(r) || !r.contains("wall_ms_median")) {
            p.unmeasured.push_back(r["scene"]);
            continue;
        }
        p.psnr += double(r["psnr"]);
        p.logMs += std::log(std::max(double(r["wall_ms_median"]), 1e-3));
        ++p.scenes;
    }
    std::vector<Point> all, failed;
    for (auto& entry : points) {
        Point& p = entry.second;
        if (!p.unmeasured.empty())
            failed.push_back(p);
        if (p.scenes != int(scenes.size()))
            continue; // not measured on every scene: no point of the front
        p.psnr /= p.scenes;
        p.logMs /= p.scenes;
        all.push_back(p);
    }
    const auto ms = [](const Point& p) { return std::exp(p.logMs); };
    const auto name = [](const Point& p) { return cat(p.method, " (", p.setting, ")"); };
    QualityVerdict v;
    v.doc = {{"scenes", scenes},
             {"psnr_noise_db", kQualityPsnrNoise},
             {"time_noise_factor", kQualityTimeNoise},
             {"choices", json::array()}};
    std::vector<const Point*> chosen;
    for (const splat::QualityChoice& q : table) {
        const json want = cli::describe(splat::gpuMethod(q.method), q.settings);
        const auto it = std::find_if(all.begin(), all.end(), [&](const Point& p) {
            return p.method == q.method && p.settings == want;
        });
        json entry = {{"quality", q.name}, {"method", q.method}, {"settings", want}};
        const auto broke = std::find_if(failed.begin(), failed.end(), [&](const Point& p) {
            return p.method == q.method && p.settings == want;
        });
        if (broke != failed.end()) {
            chosen.push_back(nullptr);
            entry["status"] = "failed";
            v.failures.push_back(cat("quality ", q.name, " picks ", name(*broke),
                                     ", whose row failed on ", broke->unmeasured.front(),
                                     " (see its reason in results.json)"));
            v.lines.push_back(v.failures.back());
            v.doc["choices"].push_back(entry);
            continue;
        }
        if (it == all.end()) {
            chosen.push_back(nullptr);
            entry["status"] = "not measured";
            v.lines.push_back(cat("quality ", q.name, " (", q.method,
                                  "): not measured on every "
                                  "scene of this run, not checked"));
            v.doc["choices"].push_back(entry);
            continue;
        }
        const Point& c = *it;
        chosen.push_back(&c);
        const Point* beaten = nullptr;
        // Beaten: a point as accurate (within the PSNR noise) and faster beyond the time noise.
        // One clearly more accurate at about the same time is not judged: which of two rows
        // within the time noise is faster changes from run to run.
        for (const Point& o : all) {
            if (&o == &c || o.psnr < c.psnr - kQualityPsnrNoise ||
                ms(o) * kQualityTimeNoise >= ms(c))
                continue;
            if (!beaten || ms(o) < ms(*beaten))
                beaten = &o;
        }
        entry.update({{"setting", c.setting},
                      {"psnr", c.psnr},
                      {"wall_ms", ms(c)},
                      {"status", beaten ? "off the front" : "on the front"}});
        std::string line =
            fmt("quality %s = %s: %.2f dB, %.2f ms (over %zu scenes): ", q.name.c_str(),
                name(c).c_str(), c.psnr, ms(c), scenes.size());
        if (beaten) {
            entry["beaten_by"] = {{"method", beaten->method},
                                  {"setting", beaten->setting},
                                  {"psnr", beaten->psnr},
                                  {"wall_ms", ms(*beaten)}};
            line += fmt("off the front: %s is %.2f dB in %.2f ms", name(*beaten).c_str(),
                        beaten->psnr, ms(*beaten));
            v.failures.push_back(cat("quality ", q.name, " no longer follows the measurements: ",
                                     name(*beaten), " beats ", name(c), " (",
                                     fmt("%.2f dB in %.2f ms against %.2f dB in %.2f ms",
                                         beaten->psnr, ms(*beaten), c.psnr, ms(c)),
                                     "); move the choice in splat/quality.h"));
        } else {
            line += "on the front";
        }
        v.lines.push_back(line);
        v.doc["choices"].push_back(entry);
    }
    // The order: each quality no slower and no more accurate than the next, within the noise.
    for (std::size_t i = 0; i + 1 < chosen.size(); ++i) {
        const Point *a = chosen[i], *b = chosen[i + 1];
        if (!a || !b)
            continue;
        if (ms(*a) > ms(*b) * kQualityTimeNoise || a->psnr > b->psnr + kQualityPsnrNoise)
            v.failures.push_back(
                cat("quality ", table[i].name, " and ", table[i + 1].name, " are out of order: ",
                    fmt("%.2f dB in %.2f ms against %.2f dB in %.2f ms", a->psnr, ms(*a), b->psnr,
                        ms(*b)),
                    " (the faster must be the less accurate); move the choice in splat/quality.h"));
    }
    v.doc["ok"] = v.failures.empty();
    v.doc["failures"] = v.failures;
    return v;
}

} // namespace spot::cmd
