/// @file error.h
/// @brief Error types shared by the whole project.
///
/// Two kinds of failure are distinguished because the command line maps them to different exit
/// codes: `InputError` means the user gave us something we cannot use (a malformed mesh, a preset
/// with an out-of-range value, a size that would not fit in memory) and exits with 2; anything
/// else is an internal failure and exits with 1. Messages carry their context (which file, which
/// key, which value) so `main` can print them as one line.
#pragma once

#include <sstream>
#include <stdexcept>
#include <string>

namespace spot {

/// Bad user input: malformed files, out-of-range parameters, requests that would not fit.
class InputError : public std::runtime_error {
public:
    explicit InputError(const std::string& what) : std::runtime_error(what) {}
};

/// Build a message from streamable parts: `cat("cell size ", h, " is too small")`.
template <typename... Args> std::string cat(const Args&... args) {
    std::ostringstream out;
    (out << ... << args);
    return out.str();
}

namespace detail {
[[noreturn]] void checkFailed(const char* expr, const char* file, int line, const std::string& lhs,
                              const std::string& rhs);
template <typename T> std::string show(const T& v) {
    std::ostringstream out;
    out << v;
    return out.str();
}
} // namespace detail

} // namespace spot

/// Invariant checks that print both operands on failure (internal errors, exit code 1).
#define SPOT_CHECK_OP(a, op, b)                                                                    \
    do {                                                                                           \
        const auto& spotCheckA_ = (a);                                                             \
        const auto& spotCheckB_ = (b);                                                             \
        if (!(spotCheckA_ op spotCheckB_))                                                         \
            ::spot::detail::checkFailed(#a " " #op " " #b, __FILE__, __LINE__,                     \
                                        ::spot::detail::show(spotCheckA_),                         \
                                        ::spot::detail::show(spotCheckB_));                        \
    } while (false)
#define SPOT_CHECK_EQ(a, b) SPOT_CHECK_OP(a, ==, b)
#define SPOT_CHECK_LE(a, b) SPOT_CHECK_OP(a, <=, b)
#define SPOT_CHECK_LT(a, b) SPOT_CHECK_OP(a, <, b)
#define SPOT_CHECK_NE(a, b) SPOT_CHECK_OP(a, !=, b)
#define SPOT_CHECK(cond)                                                                           \
    do {                                                                                           \
        if (!(cond))                                                                               \
            ::spot::detail::checkFailed(#cond, __FILE__, __LINE__, "false", "true");               \
    } while (false)
