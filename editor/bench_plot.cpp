#include "bench_plot.h"

#include <cstdio>
#include <stdexcept>
#include <string>
#include <sys/wait.h>

#include "bench_plot_script.h"
#include "noise/error.h"

namespace spot::cmd {

void drawBenchCharts(const std::filesystem::path& dir) {
    // The folder goes to python as an argument, quoted for the shell.
    std::string quoted = "'";
    for (char c : dir.string())
        quoted += c == '\'' ? std::string("'\\''") : std::string(1, c);
    quoted += "'";
    // Debian's python3-matplotlib belongs to the system interpreter; prefer it over another
    // python3 earlier on PATH (pyenv, a virtual environment) that may lack matplotlib.
    std::error_code ec;
    const std::string python = std::filesystem::exists("/usr/bin/python3", ec) ? "/usr/bin/python3" : "python3";
    FILE* pipe = popen((python + " - " + quoted).c_str(), "w");
    if (!pipe)
        throw std::runtime_error("cannot start python3 to draw the benchmark's charts");
    const std::size_t length = std::char_traits<char>::length(kPlotBenchScript);
    const bool written = std::fwrite(kPlotBenchScript, 1, length, pipe) == length;
    const int status = pclose(pipe);
    if (!written || !WIFEXITED(status) || WEXITSTATUS(status) != 0)
        throw std::runtime_error(cat("drawing the benchmark's charts failed (python3 with matplotlib, "
                                     "Debian package python3-matplotlib, is needed); the results "
                                     "are in ", dir.string(), "/results.json"));
}

} // namespace spot::cmd
