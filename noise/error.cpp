#include "error.h"

namespace spot::detail {

void checkFailed(const char* expr, const char* file, int line, const std::string& lhs,
                 const std::string& rhs) {
    throw std::logic_error(cat("internal check failed: ", expr, " (", lhs, " vs ", rhs, ") at ",
                               file, ":", line));
}

} // namespace spot::detail
