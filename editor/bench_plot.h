/// @file bench_plot.h
/// @brief The benchmark's charts, drawn by matplotlib (scripts/plot_bench.py, embedded in the
/// binary at build time, so the command needs no files beside it).
#pragma once

#include <filesystem>

namespace spot::cmd {

/// Draw DIR/pareto.png, DIR/stability.png (and DIR/scaling.png when measured) from
/// DIR/results.json. Throws if python3 or matplotlib is missing or the script fails.
void drawBenchCharts(const std::filesystem::path& dir);

} // namespace spot::cmd
