/// @file system.h
/// @brief Files and memory: capped reads, atomic writes, the memory budget.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <iosfwd>
#include <string>

namespace spot {

/// Read a whole file, refusing (InputError) one that is missing, unreadable or larger than
/// `maxBytes`, before allocating for it.
std::string readFileCapped(const std::filesystem::path& file, std::uint64_t maxBytes);

/// Write a file so that readers never see it half-written: `writer` fills a temporary file next
/// to `file`, which is renamed over `file` only if `writer` returns and the stream is good. On
/// any failure the temporary is removed and the old `file`, if any, is left as it was.
void writeFileAtomic(const std::filesystem::path& file,
                     const std::function<void(std::ostream&)>& writer);

/// Bytes this process may still allocate: MemAvailable from /proc/meminfo, lowered by
/// SPOT_MEMORY_LIMIT_MB when set (for tests and shared machines). lavapipe and the kernel's OOM
/// killer give no error when memory runs out, so large requests are checked against this first.
std::uint64_t memoryBudgetBytes();

/// Throw InputError("<what> needs N MiB but only M MiB are available ...") when `bytes` exceeds
/// the budget.
void requireMemory(std::uint64_t bytes, const std::string& what);

/// While alive, file descriptor 2 points to /dev/null. Some libraries (libpng under
/// OpenImageIO) print their own error lines to stderr before reporting the error to us; our
/// contract is one clear line per failure, which we print ourselves from the error we get back.
/// Not for use while other threads print to stderr.
class StderrSilencer {
public:
    StderrSilencer();
    ~StderrSilencer();
    StderrSilencer(const StderrSilencer&) = delete;
    StderrSilencer& operator=(const StderrSilencer&) = delete;

private:
    int m_saved = -1;
};

/// A message on one line: newlines and tabs become spaces, runs of spaces collapse.
std::string oneLine(const std::string& message);

} // namespace spot
