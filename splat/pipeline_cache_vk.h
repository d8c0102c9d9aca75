/// @file pipeline_cache_vk.h
/// @brief Start-up: pipelines compiled on worker threads while the caller goes on, and a
/// VkPipelineCache kept on disk between runs (docs/design.md, "Start-up").
///
/// A Context owns one PipelineCompiler and, when ContextOptions::pipelineCache names a folder,
/// one PipelineCache. makeComputePipeline and makeGraphicsPipeline (context_vk.h) hand the
/// driver's compilation to the compiler and return at once; Pipeline::handle() waits for it (or
/// compiles it on the calling thread when no worker has started it yet). The pipeline made is
/// the same object whichever thread makes it, so images do not depend on the threads.
#pragma once

#include <condition_variable>
#include <cstdint>
#include <deque>
#include <exception>
#include <functional>
#include <memory>
#include <mutex>
#include <set>
#include <span>
#include <string>
#include <thread>
#include <vector>

#include <vulkan/vulkan.h>

namespace spot::splat {

/// A context's pipeline creation so far (Context::pipelineStats()).
struct PipelineStats {
    std::uint32_t created = 0;   ///< pipelines the driver created (vkCreate*Pipelines calls)
    std::uint32_t used = 0;      ///< of those, pipelines whose handle() was asked for
    /// Created with a key (pipelineKey) that the cache file loaded at start listed: made from the
    /// cache's data as far as the driver uses it.
    std::uint32_t fromCache = 0;
    /// Creations the driver itself reported as served by the pipeline cache
    /// (VkPipelineCreationFeedback: VK_PIPELINE_CREATION_FEEDBACK_APPLICATION_PIPELINE_CACHE_HIT_BIT).
    std::uint32_t driverCacheHits = 0;
    double createMs = 0.0; ///< the driver's creation time, summed over threads (milliseconds)
    double waitMs = 0.0;   ///< time callers of Pipeline::handle() blocked on a pipeline being made
};

/// What the context's cache file held when it started (Context::pipelineCacheInfo()).
struct PipelineCacheInfo {
    std::string path;           ///< the file; empty: no cache (ContextOptions::pipelineCache)
    bool loaded = false;        ///< a valid file for this device was read
    std::uint64_t bytes = 0;    ///< the driver's cache data read from it
    std::uint32_t keys = 0;     ///< pipelines it listed
    std::string ignored;        ///< why a file that was there was not used (the warning)
};

/// Version of spotshell's cache file layout; a file of another version is ignored.
inline constexpr std::uint32_t kPipelineCacheFormat = 1;

/// The default cache folder: $SPOT_PIPELINE_CACHE when set ("off" or empty: none), else
/// $XDG_CACHE_HOME/spotshell, else $HOME/.cache/spotshell, else none (empty).
std::string defaultPipelineCacheFolder();

/// The cache file for a device inside `folder`: pipelines-<vendor>-<device>-<uuid>.bin
/// (hexadecimal ids and the first 4 bytes of pipelineCacheUUID), so that machines with different
/// GPUs or driver builds may share one folder.
std::string pipelineCacheFile(const std::string& folder, const VkPhysicalDeviceProperties& p);

/// A VkPipelineCache read from and written to one file. The file begins with a header that keys
/// it to the driver (pipelineCacheUUID, vendor and device ids, driver version) and to
/// kPipelineCacheFormat, lists the pipelines it was filled with (their pipelineKey) and checks
/// the driver's data with a hash: a file that is short, corrupt or for another driver or format
/// is ignored with one warning line on stderr, never an error. save() writes a temporary file
/// and renames it over the file (noise/system.h: writeFileAtomic), so that concurrent runs (a
/// farm's tasks sharing a shot's folder) each leave a whole file.
class PipelineCache {
public:
    /// Reads `path` if it is there (a missing file is silent: the first run).
    PipelineCache(VkDevice device, const VkPhysicalDeviceProperties& properties, std::string path);
    ~PipelineCache();
    PipelineCache(const PipelineCache&) = delete;
    PipelineCache& operator=(const PipelineCache&) = delete;

    VkPipelineCache handle() const { return m_cache; }
    const PipelineCacheInfo& info() const { return m_info; }
    /// Whether the loaded file listed `key`; record() it as made either way.
    bool listed(std::uint64_t key) const;
    void record(std::uint64_t key);
    /// Write the file when pipelines were made that it did not list; a failure is one warning
    /// line, not an error (the cache only saves time).
    void save();

private:
    VkDevice m_device;
    VkPhysicalDeviceProperties m_properties;
    VkPipelineCache m_cache = VK_NULL_HANDLE;
    PipelineCacheInfo m_info;
    std::set<std::uint64_t> m_loadedKeys;
    mutable std::mutex m_mutex;
    std::set<std::uint64_t> m_keys;
    bool m_dirty = false;
};

/// One pipeline being made: queued, running or done. The worker that takes it, or the first
/// caller of wait() when none has yet, runs `work`.
class PipelineJob {
public:
    explicit PipelineJob(std::function<VkPipeline()> work) : m_work(std::move(work)) {}
    /// Run the work here unless another thread has started it (workers call this).
    void run();
    /// The pipeline, made on this thread when no one has started it; rethrows the creation's
    /// error. `waitedMs` receives the time spent here.
    VkPipeline wait(double* waitedMs = nullptr);
    /// The pipeline when made (null otherwise), without waiting; for destroying after wait().
    VkPipeline result() const;

private:
    enum class State { Queued, Running, Done };
    std::function<VkPipeline()> m_work;
    mutable std::mutex m_mutex;
    std::condition_variable m_done;
    State m_state = State::Queued;
    VkPipeline m_pipeline = VK_NULL_HANDLE;
    std::exception_ptr m_error;
};

/// Worker threads that make queued pipelines in the order they were asked for. With no
/// threads, submit() makes the pipeline at once on the caller's thread (the serial start-up).
class PipelineCompiler {
public:
    explicit PipelineCompiler(unsigned threads);
    /// Finishes the queued jobs, then joins.
    ~PipelineCompiler();
    PipelineCompiler(const PipelineCompiler&) = delete;
    PipelineCompiler& operator=(const PipelineCompiler&) = delete;

    std::shared_ptr<PipelineJob> submit(std::function<VkPipeline()> work);
    unsigned threads() const { return unsigned(m_threads.size()); }

private:
    void loop();
    std::mutex m_mutex;
    std::condition_variable m_wake;
    std::deque<std::shared_ptr<PipelineJob>> m_queue;
    bool m_stop = false;
    std::vector<std::thread> m_threads;
};

/// FNV-1a over what makes a pipeline: the stages' SPIR-V, the specialization, the bindings and
/// the fixed state, fed in by the pipeline makers. Equal keys: the driver makes the same pipeline.
class PipelineKey {
public:
    PipelineKey& add(std::span<const std::uint32_t> words);
    PipelineKey& add(const void* data, std::size_t bytes);
    template <typename T> PipelineKey& value(const T& v) { return add(&v, sizeof(T)); }
    std::uint64_t get() const { return m_hash; }

private:
    std::uint64_t m_hash = 0xcbf29ce484222325ull;
};

} // namespace spot::splat
