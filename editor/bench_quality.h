/// @file bench_quality.h
/// @brief The bench's check of the `--quality` table (splat/quality.h) against a run's rows:
/// does each quality's choice still lie on the measured front of speed against accuracy?
#pragma once

#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "splat/quality.h"

namespace spot::cmd {

/// A row beats a quality's choice when it is as accurate, within this many dB of mean PSNR (the
/// images are deterministic: PSNR moves by 0.01 dB between the hybrid's two ways to the same
/// image)...
inline constexpr double kQualityPsnrNoise = 0.1;
/// ... and faster by more than this factor (the geometric mean of the scenes' wall
/// milliseconds). On a shared machine the splatters' costs at 128x128 tie within noise: in four
/// quick runs here instanced took 0.69 to 1.04 times oit's time, oit 0.95 to 1.06 times hybrid's.
/// A row clearly more accurate at about the same time is therefore not judged.
inline constexpr double kQualityTimeNoise = 1.5;

/// What a run's rows say of a quality table.
struct QualityVerdict {
    nlohmann::json doc = nlohmann::json::object(); ///< results.json's "quality"
    std::vector<std::string> lines;                ///< one per quality, for the bench's output
    std::vector<std::string> failures; ///< one line each; empty when the table follows the rows
};

/// Checks `table` against the bench's `rows` (results.json's). Over the scenes the run measured,
/// each (method, setting) measured on every scene is a point: its mean PSNR and the geometric
/// mean of its wall milliseconds (every scene counts alike, whatever its cost). A quality's
/// choice is the point of its method whose settings (the row's "settings", as
/// cli::describe() writes them) are the choice's. It fails when another point is as accurate and
/// faster beyond the noise (kQualityPsnrNoise, kQualityTimeNoise), and when consecutive
/// qualities are out of order (the earlier slower, or more accurate, than the next beyond the
/// noise). Rows of methods that need a file (baked's bake) are not points: a
/// quality cannot pick them. A choice without a point (a run restricted by --methods or --only
/// to leave it out) is reported as not measured, not failed.
QualityVerdict qualityCheck(const nlohmann::json& rows,
                            const std::vector<splat::QualityChoice>& table);

} // namespace spot::cmd
