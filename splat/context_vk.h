/// @file context_vk.h
/// @brief Vulkan plumbing: instance, device, queue, memory, buffers, images, pipelines,
/// timestamps. Headless by default; the editor's window asks for the presentation extensions
/// through ContextOptions and drives the same context.
///
/// Everything is RAII: handles are destroyed in reverse order of creation when their owner goes
/// away. Validation: when enabled, VK_LAYER_KHRONOS_validation is loaded and a debug messenger
/// counts errors and warnings; tests require zero errors. Memory: lavapipe never reports
/// VK_ERROR_OUT_OF_DEVICE_MEMORY (the process is killed instead), so every allocation is counted
/// against a budget and refused with an InputError before it is made.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include <vulkan/vulkan.h>

#include "splat/pipeline_cache_vk.h"

namespace spot::splat {

struct ContextOptions {
    /// Load the Khronos validation layer and count its messages. Default: on when the
    /// environment variable SPOT_VALIDATION is set to 1 (tests set it), off otherwise.
    bool validation = false;
    /// Device memory this context may allocate, bytes; 0 = 80% of spot::memoryBudgetBytes().
    std::uint64_t memoryBudget = 0;
    /// Use only a device whose name contains this, ignoring case (e.g. "llvmpipe" for lavapipe
    /// on a machine with a GPU); empty: any, a discrete GPU preferred. Default: SPOT_DEVICE.
    std::string device;
    /// Extra instance extensions (the editor: VK_KHR_surface and what GLFW needs for its window
    /// system); vkCreateInstance fails with VK_ERROR_EXTENSION_NOT_PRESENT when one is missing.
    std::vector<std::string> instanceExtensions;
    /// Enable VK_KHR_swapchain on the device (the editor's window); only devices that have it
    /// are chosen.
    bool swapchain = false;
    /// When set, only a queue family for which this returns true is chosen (the editor: whether
    /// the family can present to its window system). Called after the instance exists.
    std::function<bool(VkInstance, VkPhysicalDevice, std::uint32_t family)> canPresent;
    /// The folder of the pipeline cache file (pipeline_cache_vk.h: read at start, written when
    /// the context goes away); empty: no cache. Default: defaultPipelineCacheFolder()
    /// ($SPOT_PIPELINE_CACHE, else $XDG_CACHE_HOME/spotshell or ~/.cache/spotshell).
    std::string pipelineCache;
    /// Threads that make pipelines while the caller goes on; 0: each is made when asked for, on
    /// the caller's thread (serial). -1 (default): SPOT_PIPELINE_THREADS when set, else the
    /// hardware's threads (at most 8).
    int pipelineThreads = -1;
};

/// ContextOptions with `validation` taken from SPOT_VALIDATION, `device` from SPOT_DEVICE and
/// `pipelineCache` from defaultPipelineCacheFolder().
ContextOptions contextOptionsFromEnvironment();

struct ValidationCounts {
    std::uint32_t errors = 0;
    std::uint32_t warnings = 0;
    std::string firstError;
};

class Context {
public:
    explicit Context(const ContextOptions& options = contextOptionsFromEnvironment());
    ~Context();
    Context(const Context&) = delete;
    Context& operator=(const Context&) = delete;

    VkInstance instance() const { return m_instance; }
    VkPhysicalDevice physicalDevice() const { return m_physical; }
    VkDevice device() const { return m_device; }
    VkQueue queue() const { return m_queue; }
    std::uint32_t queueFamily() const { return m_queueFamily; }
    const VkPhysicalDeviceProperties& properties() const { return m_properties; }
    std::string deviceName() const { return m_properties.deviceName; }
    bool validationEnabled() const { return m_validation; }
    ValidationCounts validation() const;

    /// Record commands into a one-shot command buffer, submit, wait.
    void submitAndWait(const std::function<void(VkCommandBuffer)>& record);

    /// vkCmdPushDescriptorSetKHR (every pipeline here uses push descriptors).
    PFN_vkCmdPushDescriptorSetKHR pushDescriptorSet = nullptr;

    std::uint32_t findMemoryType(std::uint32_t typeBits, VkMemoryPropertyFlags properties) const;

    /// Memory accounting (bytes): reserve before allocating, release after freeing.
    void reserveMemory(std::uint64_t bytes, const std::string& what);
    void releaseMemory(std::uint64_t bytes);
    std::uint64_t allocatedBytes() const { return m_allocated.load(); }
    std::uint64_t peakAllocatedBytes() const { return m_peak.load(); }
    /// Start a new peak measurement from what is allocated now.
    void resetPeak() { m_peak.store(m_allocated.load()); }
    std::uint64_t memoryBudget() const { return m_budget; }
    VkCommandPool commandPool() const { return m_pool; }

    /// Start-up phases of the constructor, host milliseconds: the instance (with the loader and
    /// the driver's libraries), and the device (choosing it, creating it, the pipeline cache).
    double instanceMs() const { return m_instanceMs; }
    double deviceMs() const { return m_deviceMs; }
    /// Pipeline creation so far (pipeline_cache_vk.h).
    PipelineStats pipelineStats() const;
    /// The pipeline cache file as read at start (an empty path: no cache).
    PipelineCacheInfo pipelineCacheInfo() const;
    /// Write the pipeline cache file now if pipelines were made that it lacks (the destructor
    /// does too); never throws.
    void savePipelineCache();

    /// For the pipeline makers (makeComputePipeline, makeGraphicsPipeline): the driver's cache
    /// (may be null), the compiler, and the counters.
    VkPipelineCache pipelineCacheHandle() const;
    PipelineCompiler& pipelineCompiler() { return *m_compiler; }
    void countCreated(std::uint64_t key, double ms, bool driverHit);
    void countUsed(double waitMs);

    struct Messenger; ///< the debug messenger's state (defined in the .cpp)

private:
    bool m_validation = false;
    VkInstance m_instance = VK_NULL_HANDLE;
    VkDebugUtilsMessengerEXT m_messenger = VK_NULL_HANDLE;
    std::unique_ptr<Messenger> m_messages;
    VkPhysicalDevice m_physical = VK_NULL_HANDLE;
    VkPhysicalDeviceProperties m_properties{};
    VkPhysicalDeviceMemoryProperties m_memory{};
    VkDevice m_device = VK_NULL_HANDLE;
    VkQueue m_queue = VK_NULL_HANDLE;
    std::uint32_t m_queueFamily = 0;
    VkCommandPool m_pool = VK_NULL_HANDLE;
    std::uint64_t m_budget = 0;
    std::atomic<std::uint64_t> m_allocated{0};
    std::atomic<std::uint64_t> m_peak{0};
    double m_instanceMs = 0.0, m_deviceMs = 0.0;
    std::unique_ptr<PipelineCache> m_pipelineCache;
    std::unique_ptr<PipelineCompiler> m_compiler;
    mutable std::mutex m_pipelineMutex;
    PipelineStats m_pipelineStats;
};

/// An owned Vulkan handle whose parent (a device or an instance) destroys it with `Destroy`
/// (vkDestroySemaphore, vkDestroySwapchainKHR, ...) when the owner goes away or is assigned
/// another: the small objects the editor's window makes (semaphores, fences, render passes,
/// framebuffers, image views, the swapchain, the surface, a descriptor pool), so that a create
/// that throws part way releases what was made before it. Move-only.
template <typename Parent, typename T, void (*Destroy)(Parent, T, const VkAllocationCallbacks*)>
class UniqueHandle {
public:
    UniqueHandle() = default;
    /// Takes `handle` (made on `parent`); a null handle owns nothing.
    UniqueHandle(Parent parent, T handle) noexcept : m_parent(parent), m_handle(handle) {}
    ~UniqueHandle() { reset(); }
    UniqueHandle(UniqueHandle&& o) noexcept
        : m_parent(o.m_parent), m_handle(std::exchange(o.m_handle, T{})) {}
    UniqueHandle& operator=(UniqueHandle&& o) noexcept {
        if (this != &o) {
            reset();
            m_parent = o.m_parent;
            m_handle = std::exchange(o.m_handle, T{});
        }
        return *this;
    }
    UniqueHandle(const UniqueHandle&) = delete;
    UniqueHandle& operator=(const UniqueHandle&) = delete;

    T get() const { return m_handle; }
    /// For the create infos that take an array of handles (pWaitSemaphores, pSwapchains, ...).
    const T* address() const { return &m_handle; }
    explicit operator bool() const { return m_handle != T{}; }
    /// Destroy the handle now (nothing when null).
    void reset() noexcept {
        if (m_handle != T{})
            Destroy(m_parent, m_handle, nullptr);
        m_handle = T{};
    }

private:
    Parent m_parent{};
    T m_handle{};
};

using UniqueSemaphore = UniqueHandle<VkDevice, VkSemaphore, vkDestroySemaphore>;
using UniqueFence = UniqueHandle<VkDevice, VkFence, vkDestroyFence>;
using UniqueRenderPass = UniqueHandle<VkDevice, VkRenderPass, vkDestroyRenderPass>;
using UniqueFramebuffer = UniqueHandle<VkDevice, VkFramebuffer, vkDestroyFramebuffer>;
using UniqueImageView = UniqueHandle<VkDevice, VkImageView, vkDestroyImageView>;
using UniqueDescriptorPool = UniqueHandle<VkDevice, VkDescriptorPool, vkDestroyDescriptorPool>;
using UniqueSwapchain = UniqueHandle<VkDevice, VkSwapchainKHR, vkDestroySwapchainKHR>;
using UniqueSurface = UniqueHandle<VkInstance, VkSurfaceKHR, vkDestroySurfaceKHR>;

/// A binary semaphore of `ctx`'s device.
UniqueSemaphore makeSemaphore(Context& ctx);

/// A primary command buffer and its fence, allocated once and reused for every frame: begin()
/// resets and starts recording, submitAndWait() submits and blocks until the GPU is done. The
/// editor's present splits the two: submit() with its semaphores, then wait() after presenting.
class CommandBuffer {
public:
    explicit CommandBuffer(Context& ctx);
    ~CommandBuffer();
    CommandBuffer(const CommandBuffer&) = delete;
    CommandBuffer& operator=(const CommandBuffer&) = delete;

    VkCommandBuffer begin();
    void submitAndWait();
    /// End recording and submit, waiting on `wait` (at `waitStage`) and signalling `signal`
    /// (either null: none), without waiting for the GPU.
    void submit(VkSemaphore wait = VK_NULL_HANDLE,
                VkPipelineStageFlags waitStage = VK_PIPELINE_STAGE_ALL_COMMANDS_BIT,
                VkSemaphore signal = VK_NULL_HANDLE);
    /// Block until the last submit() finished.
    void wait();
    VkCommandBuffer handle() const { return m_cmd; }

private:
    Context& m_ctx;
    VkCommandBuffer m_cmd = VK_NULL_HANDLE;
    VkFence m_fence = VK_NULL_HANDLE;
    bool m_recording = false;
};

/// A buffer with its own memory. Host-visible buffers stay mapped (lavapipe's memory is host
/// memory either way; on a discrete GPU they are for uploads and readback).
class Buffer {
public:
    enum class Memory { HostVisible, DeviceLocal };
    Buffer() = default;
    Buffer(Context& ctx, VkDeviceSize size, VkBufferUsageFlags usage, Memory memory,
           const std::string& what);
    ~Buffer();
    Buffer(Buffer&& other) noexcept;
    Buffer& operator=(Buffer&& other) noexcept;

    VkBuffer handle() const { return m_buffer; }
    VkDeviceSize size() const { return m_size; }
    /// Device memory counted against the context's budget for this buffer.
    VkDeviceSize reservedBytes() const { return m_reserved; }
    void* mapped() const { return m_mapped; }
    /// Copy into a host-visible buffer at byte offset.
    void upload(const void* data, VkDeviceSize bytes, VkDeviceSize offset = 0);
    template <typename T> void upload(std::span<const T> items) {
        upload(items.data(), items.size_bytes());
    }
    VkDescriptorBufferInfo info() const { return {m_buffer, 0, VK_WHOLE_SIZE}; }

private:
    void destroy();
    Context* m_ctx = nullptr;
    VkBuffer m_buffer = VK_NULL_HANDLE;
    VkDeviceMemory m_memory = VK_NULL_HANDLE;
    VkDeviceSize m_size = 0;
    VkDeviceSize m_reserved = 0;
    void* m_mapped = nullptr;
};

/// A 2D image with one view.
class Image {
public:
    Image() = default;
    Image(Context& ctx, std::uint32_t width, std::uint32_t height, VkFormat format,
          VkImageUsageFlags usage, VkImageAspectFlags aspect, const std::string& what);
    ~Image();
    Image(Image&& other) noexcept;
    Image& operator=(Image&& other) noexcept;

    VkImage handle() const { return m_image; }
    VkImageView view() const { return m_view; }
    /// Device memory counted against the context's budget for this image.
    VkDeviceSize reservedBytes() const { return m_reserved; }
    VkFormat format() const { return m_format; }
    std::uint32_t width() const { return m_width; }
    std::uint32_t height() const { return m_height; }

private:
    void destroy();
    Context* m_ctx = nullptr;
    VkImage m_image = VK_NULL_HANDLE;
    VkImageView m_view = VK_NULL_HANDLE;
    VkDeviceMemory m_memory = VK_NULL_HANDLE;
    VkFormat m_format = VK_FORMAT_UNDEFINED;
    VkDeviceSize m_reserved = 0;
    std::uint32_t m_width = 0, m_height = 0;
};

/// One image layout transition (and memory dependency) with a full pipeline barrier between
/// the given stages.
void transitionImage(VkCommandBuffer cmd, VkImage image, VkImageAspectFlags aspect,
                     VkImageLayout from, VkImageLayout to, VkPipelineStageFlags2 srcStage,
                     VkAccessFlags2 srcAccess, VkPipelineStageFlags2 dstStage,
                     VkAccessFlags2 dstAccess);
/// A global memory barrier (buffers written by one pass, read by the next).
void memoryBarrier(VkCommandBuffer cmd, VkPipelineStageFlags2 srcStage, VkAccessFlags2 srcAccess,
                   VkPipelineStageFlags2 dstStage, VkAccessFlags2 dstAccess);

/// One descriptor of set 0: its binding number (a constant of the header shared with the shader,
/// so the number is written once) and its type. Visible to every stage of the pipeline.
struct Binding {
    std::uint32_t binding;
    VkDescriptorType type;
};
using Bindings = std::vector<Binding>;
inline Binding storageBuffer(std::uint32_t binding) {
    return {binding, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER};
}
inline Binding storageImage(std::uint32_t binding) {
    return {binding, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE};
}

/// Specialization constants (32-bit each) for every stage of a pipeline: shaders are compiled
/// for one setting instead of carrying every path (lavapipe compiles each shader at its first
/// use and pays for every branch any of its 8 lanes takes). Ids are constants of the shared
/// headers; an id a stage does not declare is ignored by that stage.
class Specialization {
public:
    Specialization& set(std::uint32_t id, std::uint32_t value);
    Specialization& set(std::uint32_t id, std::int32_t value);
    Specialization& set(std::uint32_t id, float value);
    Specialization& set(std::uint32_t id, bool value); ///< a GLSL bool constant (32-bit)
    bool empty() const { return m_entries.empty(); }
    /// Valid while this object lives and is not changed.
    VkSpecializationInfo info() const;

private:
    std::vector<VkSpecializationMapEntry> m_entries;
    std::vector<std::uint32_t> m_data;
};

/// The binding numbers (set 0) a SPIR-V module declares, ascending: every variable decorated
/// with a Binding, used or not.
std::vector<std::uint32_t> declaredBindings(std::span<const std::uint32_t> spirv);

/// A pipeline with its layout and its push-descriptor set layout (set 0).
///
/// The driver makes it on the context's pipeline threads (pipeline_cache_vk.h): the makers
/// return at once with the layout made, and handle() waits for the pipeline, or makes it on the
/// calling thread when no thread has started it. Make pipelines as soon as it is known that a
/// frame needs them, and ask for handle() only when recording them, so that they are made in
/// parallel with each other and with the caller's work; make none a frame does not use.
///
/// Its layout holds exactly the bindings its modules declare (checked when it is made), and a
/// push writes exactly those (checked at each push): no binding is filled with a stand-in for a
/// resource the pipeline does not read. A module that reads something a setting does not need is
/// compiled again without it (shaders/CMakeLists.txt, SPOT_SHADER_VARIANTS).
class Pipeline {
public:
    Pipeline() = default;
    ~Pipeline();
    Pipeline(Pipeline&& other) noexcept;
    Pipeline& operator=(Pipeline&& other) noexcept;

    /// The pipeline; waits until it is made (rethrowing a creation's error).
    VkPipeline handle() const {
        if (m_job)
            finish();
        return m_pipeline;
    }
    VkPipelineLayout layout() const { return m_layout; }
    VkPipelineBindPoint bindPoint() const { return m_bindPoint; }
    /// Its binding numbers, ascending.
    const std::vector<std::uint32_t>& bindings() const { return m_bindings; }

private:
    friend Pipeline makeComputePipeline(Context&, std::span<const std::uint32_t>, const Bindings&,
                                        std::uint32_t, const Specialization&);
    friend struct GraphicsPipelineDesc;
    friend Pipeline makeGraphicsPipeline(Context&, const struct GraphicsPipelineDesc&);
    void destroy();
    void finish() const;
    Context* m_ctx = nullptr;
    mutable std::shared_ptr<PipelineJob> m_job; ///< while being made
    mutable VkPipeline m_pipeline = VK_NULL_HANDLE;
    VkPipelineLayout m_layout = VK_NULL_HANDLE;
    VkDescriptorSetLayout m_setLayout = VK_NULL_HANDLE;
    VkPipelineBindPoint m_bindPoint = VK_PIPELINE_BIND_POINT_COMPUTE;
    std::vector<std::uint32_t> m_bindings;
};

/// Compute pipeline: one SPIR-V module (entry "main"), the given bindings, push constants of
/// `pushBytes` (<= 128), specialized by `spec`. Dispatches may have a base workgroup
/// (vkCmdDispatchBase: dispatchPixels in pass_vk.h).
Pipeline makeComputePipeline(Context& ctx, std::span<const std::uint32_t> spirv,
                             const Bindings& bindings, std::uint32_t pushBytes,
                             const Specialization& spec = {});

struct GraphicsPipelineDesc {
    std::span<const std::uint32_t> vertex, fragment, geometry; ///< geometry optional
    Bindings bindings;                                         ///< visible to all stages
    Specialization spec;                                       ///< for every stage
    std::uint32_t pushBytes = 0;
    std::vector<VkFormat> colorFormats;
    std::vector<VkPipelineColorBlendAttachmentState> blends;   ///< one per colour attachment
    VkFormat depthFormat = VK_FORMAT_UNDEFINED;
    bool depthTest = false;
    bool depthWrite = false;
    VkCompareOp depthCompare = VK_COMPARE_OP_LESS;
    VkPrimitiveTopology topology = VK_PRIMITIVE_TOPOLOGY_TRIANGLE_LIST;
    VkCullModeFlags cull = VK_CULL_MODE_NONE;
};

/// Graphics pipeline for dynamic rendering; vertices are pulled from storage buffers (no vertex
/// input state); viewport and scissor are dynamic.
Pipeline makeGraphicsPipeline(Context& ctx, const GraphicsPipelineDesc& desc);

/// Push-descriptor writes for set 0, built up then pushed with one call.
class Descriptors {
public:
    Descriptors& buffer(std::uint32_t binding, const Buffer& b,
                        VkDescriptorType type = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER);
    /// A storage buffer's `range` bytes from `offset` (a multiple of the device's
    /// minStorageBufferOffsetAlignment).
    Descriptors& buffer(std::uint32_t binding, const Buffer& b, VkDeviceSize offset,
                        VkDeviceSize range);
    Descriptors& image(std::uint32_t binding, const Image& image, VkImageLayout layout,
                       VkDescriptorType type, VkSampler sampler = VK_NULL_HANDLE);
    void push(Context& ctx, VkCommandBuffer cmd, const Pipeline& pipeline);

private:
    std::vector<VkWriteDescriptorSet> m_writes;
    std::vector<std::unique_ptr<VkDescriptorBufferInfo>> m_buffers;
    std::vector<std::unique_ptr<VkDescriptorImageInfo>> m_images;
};

/// GPU timestamps: `count` slots, written with write(), read after the submit finished.
class Timestamps {
public:
    Timestamps(Context& ctx, std::uint32_t count);
    ~Timestamps();
    /// One owner per query pool: a copy would destroy it twice.
    Timestamps(const Timestamps&) = delete;
    Timestamps& operator=(const Timestamps&) = delete;
    Timestamps(Timestamps&&) = delete;
    Timestamps& operator=(Timestamps&&) = delete;
    void reset(VkCommandBuffer cmd);
    void write(VkCommandBuffer cmd, std::uint32_t slot, VkPipelineStageFlags2 stage);
    /// Milliseconds of the first `count` slots (0: all) after slot 0; every one must have been
    /// written by a submitted command buffer.
    std::vector<double> milliseconds(std::uint32_t count = 0) const;

private:
    Context& m_ctx;
    VkQueryPool m_pool = VK_NULL_HANDLE;
    std::uint32_t m_count = 0;
};

/// The message for a failed Vulkan call: what failed, the result's name (string_VkResult) and
/// value, and the calling source line, e.g. "Vulkan: vkCreateFence failed:
/// VK_ERROR_OUT_OF_HOST_MEMORY (-1) at splat/context_vk.cpp:313". `file` is shortened to its
/// folder and name.
std::string vkFailure(VkResult result, const char* what, const char* file, int line);

/// Throw std::runtime_error(vkFailure(...)) unless `result` is VK_SUCCESS. The default
/// arguments capture the caller's file and line, so a call reads `vkCheck(vkCreateFence(...),
/// "vkCreateFence")`. (__builtin_FILE and __builtin_LINE: what std::source_location::current()
/// does, which clang 14 with libstdc++ 12 cannot compile.)
void vkCheck(VkResult result, const char* what, const char* file = __builtin_FILE(),
             int line = __builtin_LINE());

} // namespace spot::splat
