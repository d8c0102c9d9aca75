#include "progress.h"

#include <cstdio>
#include <unistd.h>

namespace spot::cli {

ProgressBar::ProgressBar(std::string label)
    : m_label(std::move(label)), m_enabled(isatty(fileno(stderr)) != 0),
      m_start(std::chrono::steady_clock::now()), m_last(m_start) {}

ProgressBar::~ProgressBar() { finish(); }

void ProgressBar::update(long done, long total) {
    if (!m_enabled || total <= 0)
        return;
    const std::lock_guard<std::mutex> lock(m_mutex);
    const auto now = std::chrono::steady_clock::now();
    if (done < total && now - m_last < std::chrono::milliseconds(100))
        return;
    m_last = now;
    constexpr int kWidth = 30;
    const double fraction = double(done) / double(total);
    const int filled = int(fraction * kWidth);
    const double seconds = std::chrono::duration<double>(now - m_start).count();
    std::string bar(std::size_t(filled), '#');
    bar.resize(kWidth, '.');
    const double eta = fraction > 0.0 ? seconds * (1.0 - fraction) / fraction : 0.0;
    std::fprintf(stderr, "\r%s [%s] %3d%%  %.1f s, %.0f s left ", m_label.c_str(), bar.c_str(),
                 int(fraction * 100.0), seconds, eta);
    std::fflush(stderr);
    m_drawn = true;
}

void ProgressBar::finish() {
    const std::lock_guard<std::mutex> lock(m_mutex);
    if (m_enabled && m_drawn) {
        std::fprintf(stderr, "\r\033[K");
        std::fflush(stderr);
        m_drawn = false;
    }
}

} // namespace spot::cli
