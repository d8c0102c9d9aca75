/// @file quality.h
/// @brief The `--quality fast|balanced|best` table: which method and settings each quality
/// picks, read by `render`, `edit` and the bench. This file is the table's only copy.
///
/// The choices rest on the bench's measurements (docs/bench/: PSNR against the converged
/// reference and wall milliseconds per frame on lavapipe, the quick, full and realtime suites),
/// and the bench checks them on every run: over the scenes a run measured, each choice must lie
/// on (or within noise of) the Pareto front of mean PSNR against mean wall time of the rows the
/// run made, and the three must be ordered (fast no slower than balanced no slower than best,
/// and no more accurate either way, within noise). A run where the table no longer follows the
/// measurements fails with a line naming the choice and the row that beats it
/// (editor/cmd_bench.cpp, qualityCheck). When a method changes, rerun
/// `spotshell bench --suite quick` (and full, realtime) and move the choice along the front here.
///
/// What the numbers said when the table was set (lavapipe, 2 cores; PSNR in dB, wall ms):
/// - fast, `oit`: the cheapest splatter whose error stays near the others' (fur-bunny 128x128
///   32.1 dB; `instanced` costs as much at 640x480 and loses 5 to 15 dB).
/// - balanced, `sorted`: as accurate as `hybrid` or more on every fur scene (fur-dense-bunny
///   640x480: 33.0 dB against hybrid's 30.2 and oit's 27.7) and no slower at 640x480
///   (171 against 177 ms); at 128x128 it is the front's point past `hybrid`.
/// - best, `raymarch` with 64 steps and 2 x 2 rays a pixel: the most accurate GPU row on fur
///   (fur-bunny 128x128: 40 dB against sorted's 33), at 6 to 15 times sorted's time. It misses
///   paper-thin flakes and grazing blades (flakes-sphere 8 dB, grass-plane-grazing 26 dB against
///   sorted's 35 and 42): balanced is the choice there.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "splat/settings.h"

namespace spot::splat {

/// One quality's choice.
struct QualityChoice {
    std::string name;        ///< fast, balanced, best
    std::string method;      ///< a GPU method of the registry (method_vk.h)
    RenderSettings settings; ///< the method's settings (others at their defaults)
    std::string summary;     ///< one line for --help and README: the method and why
};

/// The table, fast first, best last.
inline const std::vector<QualityChoice>& qualityChoices() {
    static const std::vector<QualityChoice> table = [] {
        RenderSettings fast;     // oit: EWA, McGuire-Bavoil weights, analytic optical depths
        RenderSettings balanced; // sorted: EWA, analytic optical depths
        RenderSettings best;
        best.steps = 64;
        best.supersample = 2;
        return std::vector<QualityChoice>{
            {"fast", "oit", fast, "oit: the cheapest splatting at a usable error"},
            {"balanced", "sorted", balanced,
             "sorted: exact per-pixel order, as accurate as hybrid or more and no slower at "
             "640x480"},
            {"best", "raymarch", best,
             "raymarch, 64 steps, 2x2 rays a pixel: the most accurate on fur and volumes, "
             "several times slower; misses paper-thin flakes"}};
    }();
    return table;
}

/// The choice of `name`; nullptr when there is none.
inline const QualityChoice* findQuality(std::string_view name) {
    for (const QualityChoice& q : qualityChoices())
        if (q.name == name)
            return &q;
    return nullptr;
}

/// The default of `render` and `edit` when no method is given.
inline constexpr std::string_view kDefaultQuality = "balanced";

/// "fast, balanced or best".
inline std::string qualityNames() {
    std::string names;
    const auto& table = qualityChoices();
    for (std::size_t i = 0; i < table.size(); ++i)
        names += (i == 0 ? "" : i + 1 == table.size() ? " or " : ", ") + table[i].name;
    return names;
}

} // namespace spot::splat
