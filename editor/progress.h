/// @file progress.h
/// @brief A progress bar on the terminal (stderr), thread-safe, silent when stderr is not a TTY
/// (CI logs get the closing line only).
#pragma once

#include <chrono>
#include <mutex>
#include <string>

namespace spot::cli {

class ProgressBar {
public:
    explicit ProgressBar(std::string label);
    ~ProgressBar();
    /// Report `done` of `total`; redraws at most ~10 times a second.
    void update(long done, long total);
    /// Clear the bar's line.
    void finish();

private:
    std::string m_label;
    bool m_enabled;
    bool m_drawn = false;
    std::mutex m_mutex;
    std::chrono::steady_clock::time_point m_start, m_last;
};

} // namespace spot::cli
