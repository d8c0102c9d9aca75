/// @file quality.h
/// @brief The `--quality fast|balanced|best` table: which method and settings each quality
/// picks, read by `render`, `edit` and the bench. This file is the table's only copy.
///
/// The choices rest on the bench's measurements (docs/bench/: PSNR against the converged
/// reference and wall milliseconds per frame on lavapipe, the quick, full and realtime suites),
/// and the bench checks them on every run: over the scenes a run measured, each choice must lie
/// on (or within noise of) the Pareto front of mean PSNR against the geometric mean of wall time
/// of the rows the run made, and the three must be ordered (fast no slower than balanced no slower
/// than best, and no more accurate either way, within noise). A run where the table no longer
/// follows the measurements fails with a line naming the choice and the row that beats it
/// (editor/bench_quality.h). When a method changes, rerun
/// `spotshell bench --suite quick` (and full, realtime) and move the choice along the front here.
///
/// What the numbers said when the table was set: mean PSNR over the suite's scenes and the
/// geometric mean of wall milliseconds per frame, lavapipe on 2 cores (README, "Which method to
/// use when", has the table):
/// - quick (2 scenes, 128x128): oit 30.96 dB 18.7 ms, hybrid 32.21 dB 19.4 ms, sorted 32.59 dB
///   25.0 ms, raymarch 64 steps 2x2 35.92 dB 258 ms; instanced 25.71 dB 15.2 ms. Rerun after the
///   EWA widening kept each lobe's coverage: oit 31.56, hybrid 33.57, sorted 35.66, raymarch
///   35.92, instanced 26.05 dB (times on a loaded machine, in the same order as before: instanced
///   106, hybrid 130, oit 139, sorted 176, raymarch 2024 ms); the choices stay on the front.
/// - full (9 scenes, 128x128): oit 32.18 dB 21.9 ms, hybrid 32.61 dB 24.9 ms, sorted 33.52 dB
///   30.1 ms, raymarch 64 steps 2x2 34.93 dB 178 ms.
/// - realtime (10 scenes, 640x480): oit 34.25 dB 97.0 ms, sorted 36.67 dB 98.3 ms, hybrid
///   35.61 dB 120 ms (sorted beats it), instanced 27.71 dB 76.7 ms.
/// So: fast is `instanced`, the cheapest row in every suite (its error the largest: 5 to 9 dB
/// below the others; previews and navigation). `oit` is not on the quick suite's front: `hybrid`
/// costs the same there at 128x128 (30.3 against 32.0 ms in one run, 19.4 against 18.7 in
/// another) and is 1.2 dB more accurate, while at 640x480 `sorted` beats `hybrid`; only
/// `instanced` stays ahead on time everywhere. Balanced is `sorted`; best is the ray-march at 64
/// steps and 2 x 2 rays, the most accurate GPU row on fur and volumes, which misses paper-thin
/// flakes (flakes-sphere 8 dB against sorted's 36): balanced is the choice there.
/// The table is measured unlit. On the lit fur-bunny (docs/bench-lit) best is off the front:
/// the ray-march lights each lobe from two points on its axis, as the splatting does, and sorted
/// beats it (24.1 dB in 43 ms against 23.0 dB in 202 ms); README says to use balanced, or baked,
/// for lit fur.
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
        RenderSettings fast;     // instanced: EWA, analytic optical depths
        RenderSettings balanced; // sorted: EWA, analytic optical depths
        RenderSettings best;
        best.steps = 64;
        best.supersample = 2;
        return std::vector<QualityChoice>{
            {"fast", "instanced", fast,
             "instanced: one blend of unsorted quads, the cheapest; previews and navigation"},
            {"balanced", "sorted", balanced,
             "sorted: every kernel composited in order, more accurate than hybrid and no "
             "slower over the bench's scenes at 640x480"},
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
