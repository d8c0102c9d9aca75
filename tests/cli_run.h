// Running the `spotshell` command from a test as a user would: its exit code, standard output and
// standard error. Shared by every test executable that drives the command line.
#pragma once

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <sys/wait.h>
#include <unistd.h>

namespace spot::test {

struct CliResult {
    int code = -1; ///< exit status; -1 when the command did not exit normally
    std::string out;
    std::string err;
};

/// Run `prefix spotshell args` through the shell (`prefix`: environment settings, xvfb-run).
/// Standard error goes to a file of its own per process and call (ctest runs tests in parallel
/// processes that share the tmp folder), read back into `err`.
inline CliResult runSpotshell(const std::string& args, const std::string& prefix = "") {
    static int calls = 0;
    const std::filesystem::path errFile =
        std::filesystem::path(SPOT_TEST_TMP_DIR) /
        ("stderr-" + std::to_string(::getpid()) + "-" + std::to_string(calls++) + ".txt");
    const std::string cmd =
        prefix + " " + std::string(SPOT_SPOTSHELL) + " " + args + " 2>'" + errFile.string() + "'";
    CliResult r;
    FILE* pipe = popen(cmd.c_str(), "r");
    if (!pipe)
        return r;
    std::array<char, 4096> buf{};
    while (std::fgets(buf.data(), int(buf.size()), pipe))
        r.out += buf.data();
    const int status = pclose(pipe);
    r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    std::ifstream in(errFile, std::ios::binary);
    r.err.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
    std::error_code ignored;
    std::filesystem::remove(errFile, ignored);
    return r;
}

} // namespace spot::test
