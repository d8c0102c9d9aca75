#include "pipeline_cache_vk.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <ostream>
#include <stdexcept>

#include "noise/error.h"
#include "noise/system.h"
#include "splat/context_vk.h"

namespace spot::splat {

namespace {

constexpr char kMagic[8] = {'S', 'P', 'O', 'T', 'P', 'I', 'P', 'E'};
/// A cache file larger than this is not read (a driver's data for spotshell's few dozen
/// pipelines is well under it).
constexpr std::uint64_t kMaxFileBytes = 512ull << 20;

/// The file's header; the keys (uint64 each) and then the driver's data follow.
struct FileHeader {
    char magic[8];
    std::uint32_t format;
    std::uint32_t vendorId;
    std::uint32_t deviceId;
    std::uint32_t driverVersion;
    std::uint8_t uuid[VK_UUID_SIZE];
    std::uint32_t keyCount;
    std::uint32_t reserved;
    std::uint64_t dataBytes;
    std::uint64_t hash; ///< PipelineKey over the keys and the data
};
static_assert(sizeof(FileHeader) == 64);

FileHeader headerFor(const VkPhysicalDeviceProperties& p) {
    FileHeader h{};
    std::memcpy(h.magic, kMagic, sizeof(kMagic));
    h.format = kPipelineCacheFormat;
    h.vendorId = p.vendorID;
    h.deviceId = p.deviceID;
    h.driverVersion = p.driverVersion;
    std::memcpy(h.uuid, p.pipelineCacheUUID, VK_UUID_SIZE);
    return h;
}

/// Why the file's bytes cannot be used for this device (empty: they can); fills `keys` and
/// `data` when they can.
std::string parse(const std::string& bytes, const VkPhysicalDeviceProperties& p,
                  std::vector<std::uint64_t>& keys, std::span<const char>& data) {
    FileHeader h;
    if (bytes.size() < sizeof(h))
        return cat("shorter than its header (", bytes.size(), " bytes)");
    std::memcpy(&h, bytes.data(), sizeof(h));
    if (std::memcmp(h.magic, kMagic, sizeof(kMagic)) != 0)
        return "not a spotshell pipeline cache";
    if (h.format != kPipelineCacheFormat)
        return cat("format ", h.format, ", this spotshell writes ", kPipelineCacheFormat);
    const FileHeader mine = headerFor(p);
    if (h.vendorId != mine.vendorId || h.deviceId != mine.deviceId ||
        h.driverVersion != mine.driverVersion || std::memcmp(h.uuid, mine.uuid, VK_UUID_SIZE) != 0)
        return cat("made by another driver or device (vendor 0x", std::hex, h.vendorId,
                   ", device 0x", h.deviceId, ", driver 0x", h.driverVersion, ")");
    const std::uint64_t expected = sizeof(h) + std::uint64_t(h.keyCount) * 8 + h.dataBytes;
    if (h.dataBytes > kMaxFileBytes || expected != bytes.size())
        return cat("truncated or padded (", bytes.size(), " bytes, its header says ", expected,
                   ")");
    const std::span<const char> body(bytes.data() + sizeof(h), bytes.size() - sizeof(h));
    if (PipelineKey().add(body.data(), body.size()).get() != h.hash)
        return "corrupt (its checksum does not match)";
    keys.resize(h.keyCount);
    std::memcpy(keys.data(), body.data(), keys.size() * 8);
    data = body.subspan(keys.size() * 8);
    return {};
}

void warn(const std::string& path, const std::string& why) {
    std::fprintf(stderr, "spotshell: warning: pipeline cache %s ignored: %s\n", path.c_str(),
                 why.c_str());
}

} // namespace

std::string defaultPipelineCacheFolder() {
    if (const char* v = std::getenv("SPOT_PIPELINE_CACHE"))
        return std::strcmp(v, "off") == 0 ? std::string() : std::string(v);
    if (const char* xdg = std::getenv("XDG_CACHE_HOME"); xdg && *xdg)
        return (std::filesystem::path(xdg) / "spotshell").string();
    if (const char* home = std::getenv("HOME"); home && *home)
        return (std::filesystem::path(home) / ".cache" / "spotshell").string();
    return {};
}

std::string pipelineCacheFile(const std::string& folder, const VkPhysicalDeviceProperties& p) {
    // The driver's cache UUID in the name too: nodes of one shot with different driver builds
    // keep a file each rather than overwrite one another's.
    char name[96];
    std::snprintf(name, sizeof(name), "pipelines-%04x-%04x-%02x%02x%02x%02x.bin", p.vendorID,
                  p.deviceID, p.pipelineCacheUUID[0], p.pipelineCacheUUID[1],
                  p.pipelineCacheUUID[2], p.pipelineCacheUUID[3]);
    return (std::filesystem::path(folder) / name).string();
}

// ---- PipelineCache ----------------------------------------------------------------------------

PipelineCache::PipelineCache(VkDevice device, const VkPhysicalDeviceProperties& properties,
                             std::string path)
    : m_device(device), m_properties(properties) {
    m_info.path = std::move(path);
    std::string bytes;
    std::span<const char> data;
    std::error_code ec;
    if (std::filesystem::exists(m_info.path, ec)) {
        std::vector<std::uint64_t> keys;
        try {
            bytes = readFileCapped(m_info.path, kMaxFileBytes);
            m_info.ignored = parse(bytes, properties, keys, data);
        } catch (const std::exception& e) {
            m_info.ignored = e.what();
        }
        if (m_info.ignored.empty()) {
            m_loadedKeys.insert(keys.begin(), keys.end());
            m_info.loaded = true;
            m_info.bytes = data.size();
            m_info.keys = std::uint32_t(m_loadedKeys.size());
        } else {
            warn(m_info.path, m_info.ignored);
            data = {};
        }
    }
    VkPipelineCacheCreateInfo ci{VK_STRUCTURE_TYPE_PIPELINE_CACHE_CREATE_INFO};
    ci.initialDataSize = data.size();
    ci.pInitialData = data.empty() ? nullptr : data.data();
    if (vkCreatePipelineCache(device, &ci, nullptr, &m_cache) != VK_SUCCESS && !data.empty()) {
        // The driver refused its own data: start empty.
        m_info.ignored = "the driver refused its data";
        warn(m_info.path, m_info.ignored);
        m_info.loaded = false;
        m_loadedKeys.clear();
        ci.initialDataSize = 0;
        ci.pInitialData = nullptr;
        m_cache = VK_NULL_HANDLE;
        if (vkCreatePipelineCache(device, &ci, nullptr, &m_cache) != VK_SUCCESS)
            m_cache = VK_NULL_HANDLE; // no cache: pipelines are made without one
    }
    m_keys = m_loadedKeys;
    // A file that was there but could not be used is rewritten at the end.
    m_dirty = !m_info.ignored.empty();
}

PipelineCache::~PipelineCache() {
    if (m_cache)
        vkDestroyPipelineCache(m_device, m_cache, nullptr);
}

bool PipelineCache::listed(std::uint64_t key) const {
    return m_loadedKeys.count(key) > 0;
}

void PipelineCache::record(std::uint64_t key) {
    const std::lock_guard<std::mutex> lock(m_mutex);
    m_dirty = m_keys.insert(key).second || m_dirty;
}

void PipelineCache::save() {
    std::vector<std::uint64_t> keys;
    {
        const std::lock_guard<std::mutex> lock(m_mutex);
        if (!m_dirty || !m_cache)
            return;
        keys.assign(m_keys.begin(), m_keys.end());
        m_dirty = false;
    }
    try {
        std::size_t size = 0;
        vkCheck(vkGetPipelineCacheData(m_device, m_cache, &size, nullptr),
                "vkGetPipelineCacheData");
        std::string body(keys.size() * 8 + size, '\0');
        std::memcpy(body.data(), keys.data(), keys.size() * 8);
        vkCheck(vkGetPipelineCacheData(m_device, m_cache, &size, body.data() + keys.size() * 8),
                "vkGetPipelineCacheData");
        body.resize(keys.size() * 8 + size);
        FileHeader h = headerFor(m_properties);
        h.keyCount = std::uint32_t(keys.size());
        h.dataBytes = size;
        h.hash = PipelineKey().add(body.data(), body.size()).get();
        const std::filesystem::path file(m_info.path);
        if (file.has_parent_path())
            std::filesystem::create_directories(file.parent_path());
        writeFileAtomic(file, [&](std::ostream& out) {
            out.write(reinterpret_cast<const char*>(&h), sizeof(h));
            out.write(body.data(), std::streamsize(body.size()));
        });
    } catch (const std::exception& e) {
        std::fprintf(stderr, "spotshell: warning: pipeline cache %s not written: %s\n",
                     m_info.path.c_str(), e.what());
    }
}

// ---- PipelineJob, PipelineCompiler ------------------------------------------------------------

void PipelineJob::run() {
    {
        const std::lock_guard<std::mutex> lock(m_mutex);
        if (m_state != State::Queued)
            return;
        m_state = State::Running;
    }
    VkPipeline made = VK_NULL_HANDLE;
    std::exception_ptr error;
    try {
        made = m_work();
    } catch (...) {
        error = std::current_exception();
    }
    {
        const std::lock_guard<std::mutex> lock(m_mutex);
        m_pipeline = made;
        m_error = error;
        m_state = State::Done;
        m_work = nullptr; // what it captured (shader modules are destroyed by the work itself)
    }
    m_done.notify_all();
}

VkPipeline PipelineJob::wait(double* waitedMs) {
    const auto start = std::chrono::steady_clock::now();
    bool runHere = false;
    {
        const std::lock_guard<std::mutex> lock(m_mutex);
        runHere = m_state == State::Queued;
    }
    if (runHere)
        run(); // no worker took it yet: make it here rather than wait in line
    std::unique_lock<std::mutex> lock(m_mutex);
    m_done.wait(lock, [&] { return m_state == State::Done; });
    if (waitedMs)
        *waitedMs =
            std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
                .count();
    if (m_error)
        std::rethrow_exception(m_error);
    return m_pipeline;
}

VkPipeline PipelineJob::result() const {
    const std::lock_guard<std::mutex> lock(m_mutex);
    return m_state == State::Done ? m_pipeline : VK_NULL_HANDLE;
}

PipelineCompiler::PipelineCompiler(unsigned threads) {
    for (unsigned i = 0; i < threads; ++i)
        m_threads.emplace_back([this] { loop(); });
}

PipelineCompiler::~PipelineCompiler() {
    {
        const std::lock_guard<std::mutex> lock(m_mutex);
        m_stop = true;
    }
    m_wake.notify_all();
    for (std::thread& t : m_threads)
        t.join();
}

std::shared_ptr<PipelineJob> PipelineCompiler::submit(std::function<VkPipeline()> work) {
    auto job = std::make_shared<PipelineJob>(std::move(work));
    if (m_threads.empty()) {
        job->run();
        return job;
    }
    {
        const std::lock_guard<std::mutex> lock(m_mutex);
        m_queue.push_back(job);
    }
    m_wake.notify_one();
    return job;
}

void PipelineCompiler::loop() {
    for (;;) {
        std::shared_ptr<PipelineJob> job;
        {
            std::unique_lock<std::mutex> lock(m_mutex);
            m_wake.wait(lock, [&] { return m_stop || !m_queue.empty(); });
            if (m_queue.empty())
                return; // stopping, and every queued job taken
            job = std::move(m_queue.front());
            m_queue.pop_front();
        }
        job->run();
    }
}

// ---- PipelineKey ------------------------------------------------------------------------------

PipelineKey& PipelineKey::add(std::span<const std::uint32_t> words) {
    const std::uint64_t n = words.size();
    value(n);
    return add(words.data(), words.size_bytes());
}

PipelineKey& PipelineKey::add(const void* data, std::size_t bytes) {
    const auto* p = static_cast<const unsigned char*>(data);
    for (std::size_t i = 0; i < bytes; ++i) {
        m_hash ^= p[i];
        m_hash *= 0x100000001b3ull;
    }
    return *this;
}

} // namespace spot::splat
