#include "system.h"

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <random>
#include <sstream>
#include <system_error>

#include "error.h"

#include <fcntl.h>
#include <unistd.h>

namespace spot {

std::string readFileCapped(const std::filesystem::path& file, std::uint64_t maxBytes) {
    std::error_code ec;
    if (!std::filesystem::is_regular_file(file, ec))
        throw InputError(cat(file.string(), ": no such file"));
    const std::uint64_t size = std::filesystem::file_size(file, ec);
    if (ec)
        throw InputError(cat(file.string(), ": cannot read size (", ec.message(), ")"));
    if (size > maxBytes)
        throw InputError(cat(file.string(), ": file is ", size, " bytes, more than the limit of ",
                             maxBytes));
    std::ifstream in(file, std::ios::binary);
    if (!in)
        throw InputError(cat(file.string(), ": cannot open for reading"));
    std::string data(static_cast<std::size_t>(size), '\0');
    in.read(data.data(), static_cast<std::streamsize>(size));
    if (static_cast<std::uint64_t>(in.gcount()) != size)
        throw InputError(cat(file.string(), ": short read"));
    return data;
}

void writeFileAtomic(const std::filesystem::path& file,
                     const std::function<void(std::ostream&)>& writer) {
    const std::filesystem::path dir =
        file.has_parent_path() ? file.parent_path() : std::filesystem::path(".");
    std::error_code ec;
    if (!std::filesystem::is_directory(dir, ec))
        throw InputError(cat(file.string(), ": folder ", dir.string(), " does not exist"));
    std::random_device rd;
    const std::filesystem::path tmp =
        dir / cat(".", file.filename().string(), ".tmp", std::hex, rd());
    try {
        {
            std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
            if (!out)
                throw InputError(cat(file.string(), ": cannot open ", tmp.string(), " for writing"));
            writer(out);
            out.flush();
            if (!out)
                throw InputError(cat(file.string(), ": write failed (disk full?)"));
        }
        std::filesystem::rename(tmp, file, ec);
        if (ec)
            throw InputError(cat(file.string(), ": cannot rename temporary file (", ec.message(),
                                 ")"));
    } catch (...) {
        std::filesystem::remove(tmp, ec);
        throw;
    }
}

std::uint64_t memoryBudgetBytes() {
    std::uint64_t available = 0;
    std::ifstream meminfo("/proc/meminfo");
    std::string key;
    std::uint64_t valueKb = 0;
    std::string unit;
    while (meminfo >> key >> valueKb >> unit) {
        if (key == "MemAvailable:") {
            available = valueKb * 1024;
            break;
        }
    }
    if (available == 0)
        available = 4ull << 30; // no /proc: assume a small machine rather than an unlimited one
    if (const char* limit = std::getenv("SPOT_MEMORY_LIMIT_MB")) {
        char* end = nullptr;
        const unsigned long long mb = std::strtoull(limit, &end, 10);
        if (end != limit && *end == '\0')
            available = std::min<std::uint64_t>(available, mb << 20);
    }
    return available;
}

void requireMemory(std::uint64_t bytes, const std::string& what) {
    const std::uint64_t budget = memoryBudgetBytes();
    if (bytes > budget)
        throw InputError(cat(what, " needs ", (bytes >> 20), " MiB but only ", (budget >> 20),
                             " MiB are available; reduce the request"));
}

StderrSilencer::StderrSilencer() {
    std::fflush(stderr);
    m_saved = dup(2);
    const int null = open("/dev/null", O_WRONLY);
    if (null >= 0) {
        dup2(null, 2);
        close(null);
    }
}

StderrSilencer::~StderrSilencer() {
    std::fflush(stderr);
    if (m_saved >= 0) {
        dup2(m_saved, 2);
        close(m_saved);
    }
}

std::string oneLine(const std::string& message) {
    std::string out;
    out.reserve(message.size());
    for (char c : message) {
        const char d = (c == '\n' || c == '\r' || c == '\t') ? ' ' : c;
        if (d == ' ' && (out.empty() || out.back() == ' '))
            continue;
        out += d;
    }
    while (!out.empty() && out.back() == ' ')
        out.pop_back();
    return out;
}

} // namespace spot
