#include "context_vk.h"

#include <algorithm>
#include <bit>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <malloc.h>
#include <optional>
#include <stdexcept>
#include <string_view>

#include <vulkan/vk_enum_string_helper.h>

#include "noise/error.h"
#include "noise/system.h"

namespace spot::splat {

std::string vkFailure(VkResult result, const char* what, const char* file, int line) {
    // The folder and the name: the build's absolute (or ccache-relative) path says nothing more.
    const std::string_view path = file ? file : "?";
    const std::size_t name = path.rfind('/');
    const std::size_t folder = name == std::string_view::npos || name == 0
                                   ? std::string_view::npos
                                   : path.rfind('/', name - 1);
    const std::string_view shown =
        folder == std::string_view::npos ? path : path.substr(folder + 1);
    return cat("Vulkan: ", what, " failed: ", string_VkResult(result), " (", int(result), ") at ",
               shown, ":", line);
}

void vkCheck(VkResult result, const char* what, const char* file, int line) {
    if (result != VK_SUCCESS)
        throw std::runtime_error(vkFailure(result, what, file, line));
}

ContextOptions contextOptionsFromEnvironment() {
    ContextOptions o;
    const char* v = std::getenv("SPOT_VALIDATION");
    o.validation = v && std::strcmp(v, "1") == 0;
    if (const char* device = std::getenv("SPOT_DEVICE"))
        o.device = device;
    o.pipelineCache = defaultPipelineCacheFolder();
    return o;
}

struct Context::Messenger {
    mutable std::mutex mutex;
    ValidationCounts counts;
};

namespace {

/// lavapipe allocates each draw's vertex shader outputs on the host (about 6 MB for 14,000
/// instanced quads) and frees them after the draw; glibc then returns the pages to the kernel
/// (madvise DONTNEED on a thread arena's heap, or munmap above the mmap threshold), so the next
/// frame's vertex shader faults on every page afresh: 3-9 ms of a 128x128 frame
/// (docs/design.md section 8). Keep freed memory in the process instead: trim only above 256 MiB
/// of free heap top, and serve blocks up to 32 MiB (glibc's most) from the heap. Process-wide,
/// set once when a CPU device is chosen.
void keepFreedHostMemory() {
    static const bool done = [] {
        mallopt(M_TRIM_THRESHOLD, 256 << 20);
        mallopt(M_MMAP_THRESHOLD, 32 << 20);
        return true;
    }();
    (void)done;
}

VKAPI_ATTR VkBool32 VKAPI_CALL onMessage(VkDebugUtilsMessageSeverityFlagBitsEXT severity,
                                         VkDebugUtilsMessageTypeFlagsEXT,
                                         const VkDebugUtilsMessengerCallbackDataEXT* data,
                                         void* user) {
    auto* m = static_cast<Context::Messenger*>(user);
    const std::lock_guard<std::mutex> lock(m->mutex);
    if (severity & VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT) {
        if (m->counts.errors++ == 0)
            m->counts.firstError = data->pMessage ? data->pMessage : "(no message)";
        std::fprintf(stderr, "vulkan validation error: %s\n", data->pMessage ? data->pMessage : "");
    } else if (severity & VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT) {
        ++m->counts.warnings;
    }
    return VK_FALSE;
}

bool hasLayer(const char* name) {
    std::uint32_t n = 0;
    vkEnumerateInstanceLayerProperties(&n, nullptr);
    std::vector<VkLayerProperties> layers(n);
    vkEnumerateInstanceLayerProperties(&n, layers.data());
    return std::any_of(layers.begin(), layers.end(),
                       [&](const VkLayerProperties& l) { return std::strcmp(l.layerName, name) == 0; });
}

bool hasDeviceExtension(VkPhysicalDevice device, const char* name) {
    std::uint32_t n = 0;
    vkEnumerateDeviceExtensionProperties(device, nullptr, &n, nullptr);
    std::vector<VkExtensionProperties> extensions(n);
    vkEnumerateDeviceExtensionProperties(device, nullptr, &n, extensions.data());
    return std::any_of(extensions.begin(), extensions.end(), [&](const VkExtensionProperties& e) {
        return std::strcmp(e.extensionName, name) == 0;
    });
}

bool containsIgnoringCase(std::string_view text, std::string_view part) {
    // ASCII case folding: device names are ASCII.
    const auto lower = [](char c) { return c >= 'A' && c <= 'Z' ? char(c - 'A' + 'a') : c; };
    return std::search(text.begin(), text.end(), part.begin(), part.end(), [&](char a, char b) {
               return lower(a) == lower(b);
           }) != text.end();
}

/// Release a context's handles in reverse order of creation; null handles are skipped. The
/// destructor calls it, and so does a constructor that throws (the destructor then never runs).
void destroyHandles(VkInstance instance, VkDebugUtilsMessengerEXT messenger, VkDevice device,
                    VkCommandPool pool) {
    if (device) {
        vkDeviceWaitIdle(device);
        vkDestroyCommandPool(device, pool, nullptr);
        vkDestroyDevice(device, nullptr);
    }
    if (messenger) {
        auto destroy = reinterpret_cast<PFN_vkDestroyDebugUtilsMessengerEXT>(
            vkGetInstanceProcAddr(instance, "vkDestroyDebugUtilsMessengerEXT"));
        if (destroy)
            destroy(instance, messenger, nullptr);
    }
    if (instance)
        vkDestroyInstance(instance, nullptr);
}

constexpr const char* kValidationLayer = "VK_LAYER_KHRONOS_validation";

/// What the debug messenger reports (warnings and errors of every type) to onMessage.
VkDebugUtilsMessengerCreateInfoEXT messengerInfo(Context::Messenger* messages) {
    VkDebugUtilsMessengerCreateInfoEXT info{
        VK_STRUCTURE_TYPE_DEBUG_UTILS_MESSENGER_CREATE_INFO_EXT};
    info.messageSeverity = VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT |
                           VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT;
    info.messageType = VK_DEBUG_UTILS_MESSAGE_TYPE_GENERAL_BIT_EXT |
                       VK_DEBUG_UTILS_MESSAGE_TYPE_VALIDATION_BIT_EXT |
                       VK_DEBUG_UTILS_MESSAGE_TYPE_PERFORMANCE_BIT_EXT;
    info.pfnUserCallback = onMessage;
    info.pUserData = messages;
    return info;
}

/// A Vulkan 1.3 instance with the options' extensions, and with validation: the layer, the
/// debug-utils extension, and `messenger` chained to catch messages from the creation itself.
VkInstance createInstance(const ContextOptions& options,
                          const VkDebugUtilsMessengerCreateInfoEXT* messenger) {
    VkApplicationInfo app{VK_STRUCTURE_TYPE_APPLICATION_INFO};
    app.pApplicationName = "spotshell";
    app.apiVersion = VK_API_VERSION_1_3;
    std::vector<const char*> extensions;
    std::vector<const char*> layers;
    if (messenger) {
        extensions.push_back(VK_EXT_DEBUG_UTILS_EXTENSION_NAME);
        layers.push_back(kValidationLayer);
    }
    for (const std::string& e : options.instanceExtensions)
        extensions.push_back(e.c_str());
    VkInstanceCreateInfo ici{VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO};
    ici.pNext = messenger;
    ici.pApplicationInfo = &app;
    ici.enabledExtensionCount = std::uint32_t(extensions.size());
    ici.ppEnabledExtensionNames = extensions.data();
    ici.enabledLayerCount = std::uint32_t(layers.size());
    ici.ppEnabledLayerNames = layers.data();
    VkInstance instance = VK_NULL_HANDLE;
    const VkResult created = vkCreateInstance(&ici, nullptr, &instance);
    if (created != VK_SUCCESS)
        throw std::runtime_error(cat("Vulkan: no instance (", string_VkResult(created), " (",
                                     int(created), ")",
                                     created == VK_ERROR_EXTENSION_NOT_PRESENT
                                         ? "; an instance extension is missing"
                                         : "; is the Vulkan loader (libvulkan1) installed?",
                                     ")"));
    return instance;
}

/// The physical device and queue family a context runs on.
struct DeviceChoice {
    VkPhysicalDevice device = VK_NULL_HANDLE;
    std::uint32_t family = 0;
    VkPhysicalDeviceProperties properties{};
};

/// Why `d` cannot be used (empty: it can), given its properties.
std::string whyUnusable(VkPhysicalDevice d, const VkPhysicalDeviceProperties& p,
                        const ContextOptions& options) {
    if (!options.device.empty() && !containsIgnoringCase(p.deviceName, options.device))
        return cat("name does not contain '", options.device, "'");
    if (p.apiVersion < VK_API_VERSION_1_3)
        return "Vulkan < 1.3";
    if (options.swapchain && !hasDeviceExtension(d, VK_KHR_SWAPCHAIN_EXTENSION_NAME))
        return "no VK_KHR_swapchain";
    return {};
}

/// The first graphics+compute queue family of `d` with timestamps (and, when the options ask,
/// one that can present).
std::optional<std::uint32_t> usableFamily(VkInstance instance, VkPhysicalDevice d,
                                          const ContextOptions& options) {
    std::uint32_t families = 0;
    vkGetPhysicalDeviceQueueFamilyProperties(d, &families, nullptr);
    std::vector<VkQueueFamilyProperties> fam(families);
    vkGetPhysicalDeviceQueueFamilyProperties(d, &families, fam.data());
    for (std::uint32_t f = 0; f < families; ++f)
        if ((fam[f].queueFlags & VK_QUEUE_GRAPHICS_BIT) &&
            (fam[f].queueFlags & VK_QUEUE_COMPUTE_BIT) && fam[f].timestampValidBits > 0 &&
            (!options.canPresent || options.canPresent(instance, d, f)))
            return f;
    return std::nullopt;
}

/// A device with a graphics+compute queue, Vulkan 1.3, push descriptors, 64-bit buffer atomics;
/// a real GPU when there is one (the device tool's machines), else lavapipe. Throws naming the
/// devices rejected and why (an InputError when the user named a device: SPOT_DEVICE).
DeviceChoice chooseDevice(VkInstance instance, const ContextOptions& options) {
    std::uint32_t n = 0;
    vkEnumeratePhysicalDevices(instance, &n, nullptr);
    std::vector<VkPhysicalDevice> devices(n);
    vkEnumeratePhysicalDevices(instance, &n, devices.data());
    DeviceChoice chosen;
    std::string rejected;
    for (VkPhysicalDevice d : devices) {
        VkPhysicalDeviceProperties p;
        vkGetPhysicalDeviceProperties(d, &p);
        const std::string why = whyUnusable(d, p, options);
        if (!why.empty()) {
            rejected += cat(" ", p.deviceName, " (", why, ")");
            continue;
        }
        const std::optional<std::uint32_t> f = usableFamily(instance, d, options);
        if (f && (!chosen.device || p.deviceType == VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU))
            chosen = {d, *f, p};
    }
    if (chosen.device)
        return chosen;
    const std::string message = cat(
        "Vulkan: no usable device (need Vulkan 1.3 with a graphics and compute queue",
        options.canPresent ? " that can present to the window" : "",
        options.device.empty() ? ""
                               : cat(", a name containing '", options.device, "' (SPOT_DEVICE)"),
        "; install mesa-vulkan-drivers for lavapipe)",
        rejected.empty() ? "" : "; rejected:", rejected);
    // A device the user named and cannot have is bad input (exit code 2), not our failure.
    if (!options.device.empty())
        throw InputError(message);
    throw std::runtime_error(message);
}

/// The features every renderer needs (throws naming them when the device lacks one), and the
/// optional ones it has, to enable: filled into `want` (its pNext chain points into `chain`).
struct DeviceFeatures {
    VkPhysicalDeviceVulkan13Features want13{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_3_FEATURES};
    VkPhysicalDeviceVulkan12Features want12{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_2_FEATURES};
    VkPhysicalDeviceFeatures2 want{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2};

    DeviceFeatures(VkPhysicalDevice physical, const VkPhysicalDeviceProperties& properties) {
        VkPhysicalDeviceVulkan13Features f13{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_3_FEATURES};
        VkPhysicalDeviceVulkan12Features f12{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_2_FEATURES};
        VkPhysicalDeviceFeatures2 f2{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2};
        f12.pNext = &f13;
        f2.pNext = &f12;
        vkGetPhysicalDeviceFeatures2(physical, &f2);
        if (!f13.dynamicRendering || !f13.synchronization2 || !f13.maintenance4 ||
            !f12.shaderBufferInt64Atomics || !f2.features.shaderInt64 ||
            !f2.features.fragmentStoresAndAtomics)
            throw std::runtime_error(
                cat("Vulkan: device ", properties.deviceName,
                    " lacks dynamic rendering, synchronization2, maintenance4, "
                    "shaderInt64, 64-bit buffer atomics or fragment stores"));
        want13.dynamicRendering = VK_TRUE;
        want13.synchronization2 = VK_TRUE;
        // glslang targeting Vulkan 1.3 declares workgroup sizes with LocalSizeId, which needs this.
        want13.maintenance4 = f13.maintenance4;
        want12.shaderBufferInt64Atomics = VK_TRUE;
        want12.scalarBlockLayout = f12.scalarBlockLayout;
        want12.pNext = &want13;
        want.features.shaderInt64 = VK_TRUE;
        want.features.fragmentStoresAndAtomics = VK_TRUE;
        want.features.vertexPipelineStoresAndAtomics = f2.features.vertexPipelineStoresAndAtomics;
        want.features.geometryShader = f2.features.geometryShader;
        // No shader uses float64 (the impulse generator is single precision on both sides), so
        // shaderFloat64 is neither required nor enabled: a shader that declared it would fail
        // validation.
        want.pNext = &want12;
    }
    DeviceFeatures(const DeviceFeatures&) = delete; // the pNext chain points into this object
    DeviceFeatures& operator=(const DeviceFeatures&) = delete;
};

/// The logical device with one queue of the chosen family, push descriptors and (for the
/// editor's window) the swapchain extension.
VkDevice createDevice(const DeviceChoice& chosen, const ContextOptions& options) {
    const DeviceFeatures features(chosen.device, chosen.properties);
    const float priority = 1.0f;
    VkDeviceQueueCreateInfo qci{VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO};
    qci.queueFamilyIndex = chosen.family;
    qci.queueCount = 1;
    qci.pQueuePriorities = &priority;
    std::vector<const char*> deviceExtensions = {VK_KHR_PUSH_DESCRIPTOR_EXTENSION_NAME};
    if (options.swapchain)
        deviceExtensions.push_back(VK_KHR_SWAPCHAIN_EXTENSION_NAME);
    VkDeviceCreateInfo dci{VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO};
    dci.pNext = &features.want;
    dci.queueCreateInfoCount = 1;
    dci.pQueueCreateInfos = &qci;
    dci.enabledExtensionCount = std::uint32_t(deviceExtensions.size());
    dci.ppEnabledExtensionNames = deviceExtensions.data();
    VkDevice device = VK_NULL_HANDLE;
    vkCheck(vkCreateDevice(chosen.device, &dci, nullptr, &device), "vkCreateDevice");
    return device;
}

} // namespace

Context::Context(const ContextOptions& options) : m_messages(std::make_unique<Messenger>()) {
    // Every throw below the instance's creation must release what was made so far: the
    // destructor only runs for a fully constructed object.
    struct ReleaseOnThrow {
        Context& ctx;
        bool armed = true;
        ~ReleaseOnThrow() {
            if (armed)
                destroyHandles(ctx.m_instance, ctx.m_messenger, ctx.m_device, ctx.m_pool);
        }
    } releaseOnThrow{*this};
    m_validation = options.validation;
    if (m_validation && !hasLayer(kValidationLayer))
        throw std::runtime_error("Vulkan validation requested (SPOT_VALIDATION=1) but "
                                 "VK_LAYER_KHRONOS_validation is not installed "
                                 "(Debian package vulkan-validationlayers)");
    const auto start = std::chrono::steady_clock::now();
    const auto msSince = [](std::chrono::steady_clock::time_point t) {
        return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t)
            .count();
    };
    const VkDebugUtilsMessengerCreateInfoEXT messenger = messengerInfo(m_messages.get());
    m_instance = createInstance(options, m_validation ? &messenger : nullptr);
    if (m_validation) {
        auto create = reinterpret_cast<PFN_vkCreateDebugUtilsMessengerEXT>(
            vkGetInstanceProcAddr(m_instance, "vkCreateDebugUtilsMessengerEXT"));
        vkCheck(create ? create(m_instance, &messenger, nullptr, &m_messenger)
                       : VK_ERROR_EXTENSION_NOT_PRESENT,
                "vkCreateDebugUtilsMessengerEXT");
    }

    m_instanceMs = msSince(start);
    const auto deviceStart = std::chrono::steady_clock::now();
    const DeviceChoice chosen = chooseDevice(m_instance, options);
    m_physical = chosen.device;
    m_queueFamily = chosen.family;
    m_properties = chosen.properties;
    vkGetPhysicalDeviceMemoryProperties(m_physical, &m_memory);
    if (m_properties.deviceType == VK_PHYSICAL_DEVICE_TYPE_CPU)
        keepFreedHostMemory();

    m_device = createDevice(chosen, options);
    vkGetDeviceQueue(m_device, m_queueFamily, 0, &m_queue);
    pushDescriptorSet = reinterpret_cast<PFN_vkCmdPushDescriptorSetKHR>(
        vkGetDeviceProcAddr(m_device, "vkCmdPushDescriptorSetKHR"));
    if (!pushDescriptorSet)
        throw std::runtime_error("Vulkan: VK_KHR_push_descriptor is missing");

    VkCommandPoolCreateInfo pci{VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
    pci.flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT;
    pci.queueFamilyIndex = m_queueFamily;
    vkCheck(vkCreateCommandPool(m_device, &pci, nullptr, &m_pool), "vkCreateCommandPool");

    m_budget = options.memoryBudget ? options.memoryBudget : memoryBudgetBytes() / 10 * 8;
    // The pipeline cache and the threads that fill it. Nothing below throws: a cache that
    // cannot be read is a warning, and one that cannot be made is none.
    if (!options.pipelineCache.empty())
        m_pipelineCache = std::make_unique<PipelineCache>(
            m_device, m_properties, pipelineCacheFile(options.pipelineCache, m_properties));
    int threads = options.pipelineThreads;
    if (threads < 0) {
        const char* v = std::getenv("SPOT_PIPELINE_THREADS");
        threads = v && *v ? std::atoi(v) : int(std::thread::hardware_concurrency());
    }
    m_compiler = std::make_unique<PipelineCompiler>(unsigned(std::clamp(threads, 0, 8)));
    m_deviceMs = msSince(deviceStart);
    releaseOnThrow.armed = false;
}

Context::~Context() {
    m_compiler.reset(); // finishes what is queued
    if (m_pipelineCache) {
        m_pipelineCache->save();
        m_pipelineCache.reset();
    }
    destroyHandles(m_instance, m_messenger, m_device, m_pool);
}

PipelineStats Context::pipelineStats() const {
    const std::lock_guard<std::mutex> lock(m_pipelineMutex);
    return m_pipelineStats;
}

PipelineCacheInfo Context::pipelineCacheInfo() const {
    return m_pipelineCache ? m_pipelineCache->info() : PipelineCacheInfo{};
}

void Context::savePipelineCache() {
    if (m_pipelineCache)
        m_pipelineCache->save();
}

VkPipelineCache Context::pipelineCacheHandle() const {
    return m_pipelineCache ? m_pipelineCache->handle() : VK_NULL_HANDLE;
}

void Context::countCreated(std::uint64_t key, double ms, bool driverHit) {
    bool listed = false;
    if (m_pipelineCache) {
        listed = m_pipelineCache->listed(key);
        m_pipelineCache->record(key);
    }
    const std::lock_guard<std::mutex> lock(m_pipelineMutex);
    ++m_pipelineStats.created;
    m_pipelineStats.fromCache += listed;
    m_pipelineStats.driverCacheHits += driverHit;
    m_pipelineStats.createMs += ms;
}

void Context::countUsed(double waitMs) {
    const std::lock_guard<std::mutex> lock(m_pipelineMutex);
    ++m_pipelineStats.used;
    m_pipelineStats.waitMs += waitMs;
}

ValidationCounts Context::validation() const {
    const std::lock_guard<std::mutex> lock(m_messages->mutex);
    return m_messages->counts;
}

void Context::submitAndWait(const std::function<void(VkCommandBuffer)>& record) {
    VkCommandBufferAllocateInfo ai{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
    ai.commandPool = m_pool;
    ai.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
    ai.commandBufferCount = 1;
    VkCommandBuffer cmd = VK_NULL_HANDLE;
    vkCheck(vkAllocateCommandBuffers(m_device, &ai, &cmd), "vkAllocateCommandBuffers");
    VkFence fence = VK_NULL_HANDLE;
    try {
        VkCommandBufferBeginInfo bi{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
        bi.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
        vkCheck(vkBeginCommandBuffer(cmd, &bi), "vkBeginCommandBuffer");
        record(cmd);
        vkCheck(vkEndCommandBuffer(cmd), "vkEndCommandBuffer");
        VkFenceCreateInfo fci{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
        vkCheck(vkCreateFence(m_device, &fci, nullptr, &fence), "vkCreateFence");
        VkSubmitInfo si{VK_STRUCTURE_TYPE_SUBMIT_INFO};
        si.commandBufferCount = 1;
        si.pCommandBuffers = &cmd;
        vkCheck(vkQueueSubmit(m_queue, 1, &si, fence), "vkQueueSubmit");
        vkCheck(vkWaitForFences(m_device, 1, &fence, VK_TRUE, UINT64_MAX), "vkWaitForFences");
    } catch (...) {
        vkDeviceWaitIdle(m_device);
        if (fence)
            vkDestroyFence(m_device, fence, nullptr);
        vkFreeCommandBuffers(m_device, m_pool, 1, &cmd);
        throw;
    }
    vkDestroyFence(m_device, fence, nullptr);
    vkFreeCommandBuffers(m_device, m_pool, 1, &cmd);
}

CommandBuffer::CommandBuffer(Context& ctx) : m_ctx(ctx) {
    VkCommandBufferAllocateInfo ai{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
    ai.commandPool = ctx.commandPool();
    ai.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
    ai.commandBufferCount = 1;
    vkCheck(vkAllocateCommandBuffers(ctx.device(), &ai, &m_cmd), "vkAllocateCommandBuffers");
    VkFenceCreateInfo fci{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
    const VkResult r = vkCreateFence(ctx.device(), &fci, nullptr, &m_fence);
    if (r != VK_SUCCESS) {
        vkFreeCommandBuffers(ctx.device(), ctx.commandPool(), 1, &m_cmd);
        vkCheck(r, "vkCreateFence");
    }
}

CommandBuffer::~CommandBuffer() {
    vkQueueWaitIdle(m_ctx.queue()); // a submit whose wait threw may still run
    if (m_recording)
        vkEndCommandBuffer(m_cmd);
    vkDestroyFence(m_ctx.device(), m_fence, nullptr);
    vkFreeCommandBuffers(m_ctx.device(), m_ctx.commandPool(), 1, &m_cmd);
}

VkCommandBuffer CommandBuffer::begin() {
    if (m_recording) // an earlier frame threw while recording: start over
        vkEndCommandBuffer(m_cmd);
    vkCheck(vkResetCommandBuffer(m_cmd, 0), "vkResetCommandBuffer");
    VkCommandBufferBeginInfo bi{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
    bi.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
    vkCheck(vkBeginCommandBuffer(m_cmd, &bi), "vkBeginCommandBuffer");
    m_recording = true;
    return m_cmd;
}

void CommandBuffer::submitAndWait() {
    submit();
    wait();
}

void CommandBuffer::submit(VkSemaphore wait, VkPipelineStageFlags waitStage, VkSemaphore signal) {
    SPOT_CHECK(m_recording);
    m_recording = false;
    vkCheck(vkEndCommandBuffer(m_cmd), "vkEndCommandBuffer");
    vkCheck(vkResetFences(m_ctx.device(), 1, &m_fence), "vkResetFences");
    VkSubmitInfo si{VK_STRUCTURE_TYPE_SUBMIT_INFO};
    si.waitSemaphoreCount = wait ? 1 : 0;
    si.pWaitSemaphores = &wait;
    si.pWaitDstStageMask = &waitStage;
    si.commandBufferCount = 1;
    si.pCommandBuffers = &m_cmd;
    si.signalSemaphoreCount = signal ? 1 : 0;
    si.pSignalSemaphores = &signal;
    vkCheck(vkQueueSubmit(m_ctx.queue(), 1, &si, m_fence), "vkQueueSubmit");
}

void CommandBuffer::wait() {
    vkCheck(vkWaitForFences(m_ctx.device(), 1, &m_fence, VK_TRUE, UINT64_MAX), "vkWaitForFences");
}

UniqueSemaphore makeSemaphore(Context& ctx) {
    VkSemaphoreCreateInfo si{VK_STRUCTURE_TYPE_SEMAPHORE_CREATE_INFO};
    VkSemaphore s = VK_NULL_HANDLE;
    vkCheck(vkCreateSemaphore(ctx.device(), &si, nullptr, &s), "vkCreateSemaphore");
    return UniqueSemaphore(ctx.device(), s);
}

std::uint32_t Context::findMemoryType(std::uint32_t typeBits, VkMemoryPropertyFlags props) const {
    for (std::uint32_t i = 0; i < m_memory.memoryTypeCount; ++i)
        if ((typeBits & (1u << i)) && (m_memory.memoryTypes[i].propertyFlags & props) == props)
            return i;
    throw std::runtime_error(cat("Vulkan: no memory type with properties ", props));
}

void Context::reserveMemory(std::uint64_t bytes, const std::string& what) {
    const std::uint64_t now = m_allocated.fetch_add(bytes) + bytes;
    if (now > m_budget) {
        m_allocated.fetch_sub(bytes);
        throw InputError(cat(what, " needs ", bytes >> 20, " MiB of GPU memory; ",
                             (now - bytes) >> 20, " MiB are in use and the budget is ",
                             m_budget >> 20, " MiB; reduce the image size or the kernel count"));
    }
    std::uint64_t peak = m_peak.load();
    while (now > peak && !m_peak.compare_exchange_weak(peak, now)) {
    }
}

void Context::releaseMemory(std::uint64_t bytes) { m_allocated.fetch_sub(bytes); }

// ---- Buffer -----------------------------------------------------------------------------------

Buffer::Buffer(Context& ctx, VkDeviceSize size, VkBufferUsageFlags usage, Memory memory,
               const std::string& what)
    : m_ctx(&ctx), m_size(std::max<VkDeviceSize>(size, 16)) {
    const VkDeviceSize maxRange = ctx.properties().limits.maxStorageBufferRange;
    if ((usage & VK_BUFFER_USAGE_STORAGE_BUFFER_BIT) && m_size > maxRange)
        throw InputError(cat(what, " needs a storage buffer of ", m_size >> 20,
                             " MiB, more than this device's limit of ", maxRange >> 20, " MiB"));
    ctx.reserveMemory(m_size, what);
    m_reserved = m_size;
    try {
        VkBufferCreateInfo bci{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
        bci.size = m_size;
        bci.usage = usage;
        bci.sharingMode = VK_SHARING_MODE_EXCLUSIVE;
        vkCheck(vkCreateBuffer(ctx.device(), &bci, nullptr, &m_buffer), "vkCreateBuffer");
        VkMemoryRequirements req;
        vkGetBufferMemoryRequirements(ctx.device(), m_buffer, &req);
        const VkMemoryPropertyFlags props =
            memory == Memory::HostVisible
                ? VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT
                : VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT;
        VkMemoryAllocateInfo mai{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
        mai.allocationSize = req.size;
        mai.memoryTypeIndex = ctx.findMemoryType(req.memoryTypeBits, props);
        vkCheck(vkAllocateMemory(ctx.device(), &mai, nullptr, &m_memory), "vkAllocateMemory");
        vkCheck(vkBindBufferMemory(ctx.device(), m_buffer, m_memory, 0), "vkBindBufferMemory");
        if (memory == Memory::HostVisible)
            vkCheck(vkMapMemory(ctx.device(), m_memory, 0, VK_WHOLE_SIZE, 0, &m_mapped), "vkMapMemory");
    } catch (...) {
        destroy();
        throw;
    }
}

void Buffer::destroy() {
    if (!m_ctx)
        return;
    if (m_mapped)
        vkUnmapMemory(m_ctx->device(), m_memory);
    if (m_buffer)
        vkDestroyBuffer(m_ctx->device(), m_buffer, nullptr);
    if (m_memory)
        vkFreeMemory(m_ctx->device(), m_memory, nullptr);
    m_ctx->releaseMemory(m_reserved);
    m_ctx = nullptr;
    m_buffer = VK_NULL_HANDLE;
    m_memory = VK_NULL_HANDLE;
    m_mapped = nullptr;
    m_reserved = 0;
}

Buffer::~Buffer() { destroy(); }

Buffer::Buffer(Buffer&& o) noexcept { *this = std::move(o); }

Buffer& Buffer::operator=(Buffer&& o) noexcept {
    if (this != &o) {
        destroy();
        std::swap(m_ctx, o.m_ctx);
        std::swap(m_buffer, o.m_buffer);
        std::swap(m_memory, o.m_memory);
        std::swap(m_size, o.m_size);
        std::swap(m_reserved, o.m_reserved);
        std::swap(m_mapped, o.m_mapped);
    }
    return *this;
}

void Buffer::upload(const void* data, VkDeviceSize bytes, VkDeviceSize offset) {
    SPOT_CHECK(m_mapped != nullptr);
    SPOT_CHECK_LE(offset + bytes, m_size);
    std::memcpy(static_cast<char*>(m_mapped) + offset, data, std::size_t(bytes));
}

// ---- Image ------------------------------------------------------------------------------------

Image::Image(Context& ctx, std::uint32_t width, std::uint32_t height, VkFormat format,
             VkImageUsageFlags usage, VkImageAspectFlags aspect, const std::string& what)
    : m_ctx(&ctx), m_format(format), m_width(width), m_height(height) {
    const std::uint32_t maxSide = ctx.properties().limits.maxImageDimension2D;
    if (width == 0 || height == 0 || width > maxSide || height > maxSide)
        throw InputError(cat(what, ": image of ", width, "x", height, " is outside this device's [1, ",
                             maxSide, "] per side"));
    try {
        VkImageCreateInfo ici{VK_STRUCTURE_TYPE_IMAGE_CREATE_INFO};
        ici.imageType = VK_IMAGE_TYPE_2D;
        ici.format = format;
        ici.extent = {width, height, 1};
        ici.mipLevels = 1;
        ici.arrayLayers = 1;
        ici.samples = VK_SAMPLE_COUNT_1_BIT;
        ici.tiling = VK_IMAGE_TILING_OPTIMAL;
        ici.usage = usage;
        ici.initialLayout = VK_IMAGE_LAYOUT_UNDEFINED;
        vkCheck(vkCreateImage(ctx.device(), &ici, nullptr, &m_image), "vkCreateImage");
        VkMemoryRequirements req;
        vkGetImageMemoryRequirements(ctx.device(), m_image, &req);
        ctx.reserveMemory(req.size, what);
        m_reserved = req.size;
        VkMemoryAllocateInfo mai{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
        mai.allocationSize = req.size;
        mai.memoryTypeIndex = ctx.findMemoryType(req.memoryTypeBits, VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT);
        vkCheck(vkAllocateMemory(ctx.device(), &mai, nullptr, &m_memory), "vkAllocateMemory");
        vkCheck(vkBindImageMemory(ctx.device(), m_image, m_memory, 0), "vkBindImageMemory");
        VkImageViewCreateInfo vci{VK_STRUCTURE_TYPE_IMAGE_VIEW_CREATE_INFO};
        vci.image = m_image;
        vci.viewType = VK_IMAGE_VIEW_TYPE_2D;
        vci.format = format;
        vci.subresourceRange = {aspect, 0, 1, 0, 1};
        vkCheck(vkCreateImageView(ctx.device(), &vci, nullptr, &m_view), "vkCreateImageView");
    } catch (...) {
        destroy();
        throw;
    }
}

void Image::destroy() {
    if (!m_ctx)
        return;
    if (m_view)
        vkDestroyImageView(m_ctx->device(), m_view, nullptr);
    if (m_image)
        vkDestroyImage(m_ctx->device(), m_image, nullptr);
    if (m_memory)
        vkFreeMemory(m_ctx->device(), m_memory, nullptr);
    m_ctx->releaseMemory(m_reserved);
    m_ctx = nullptr;
    m_view = VK_NULL_HANDLE;
    m_image = VK_NULL_HANDLE;
    m_memory = VK_NULL_HANDLE;
    m_reserved = 0;
}

Image::~Image() { destroy(); }

Image::Image(Image&& o) noexcept { *this = std::move(o); }

Image& Image::operator=(Image&& o) noexcept {
    if (this != &o) {
        destroy();
        std::swap(m_ctx, o.m_ctx);
        std::swap(m_image, o.m_image);
        std::swap(m_view, o.m_view);
        std::swap(m_memory, o.m_memory);
        std::swap(m_format, o.m_format);
        std::swap(m_reserved, o.m_reserved);
        std::swap(m_width, o.m_width);
        std::swap(m_height, o.m_height);
    }
    return *this;
}

void transitionImage(VkCommandBuffer cmd, VkImage image, VkImageAspectFlags aspect,
                     VkImageLayout from, VkImageLayout to, VkPipelineStageFlags2 srcStage,
                     VkAccessFlags2 srcAccess, VkPipelineStageFlags2 dstStage,
                     VkAccessFlags2 dstAccess) {
    VkImageMemoryBarrier2 b{VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER_2};
    b.srcStageMask = srcStage;
    b.srcAccessMask = srcAccess;
    b.dstStageMask = dstStage;
    b.dstAccessMask = dstAccess;
    b.oldLayout = from;
    b.newLayout = to;
    b.srcQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
    b.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
    b.image = image;
    b.subresourceRange = {aspect, 0, 1, 0, 1};
    VkDependencyInfo dep{VK_STRUCTURE_TYPE_DEPENDENCY_INFO};
    dep.imageMemoryBarrierCount = 1;
    dep.pImageMemoryBarriers = &b;
    vkCmdPipelineBarrier2(cmd, &dep);
}

void memoryBarrier(VkCommandBuffer cmd, VkPipelineStageFlags2 srcStage, VkAccessFlags2 srcAccess,
                   VkPipelineStageFlags2 dstStage, VkAccessFlags2 dstAccess) {
    VkMemoryBarrier2 b{VK_STRUCTURE_TYPE_MEMORY_BARRIER_2};
    b.srcStageMask = srcStage;
    b.srcAccessMask = srcAccess;
    b.dstStageMask = dstStage;
    b.dstAccessMask = dstAccess;
    VkDependencyInfo dep{VK_STRUCTURE_TYPE_DEPENDENCY_INFO};
    dep.memoryBarrierCount = 1;
    dep.pMemoryBarriers = &b;
    vkCmdPipelineBarrier2(cmd, &dep);
}

// ---- Pipelines --------------------------------------------------------------------------------

Pipeline::~Pipeline() { destroy(); }

Pipeline::Pipeline(Pipeline&& o) noexcept { *this = std::move(o); }

Pipeline& Pipeline::operator=(Pipeline&& o) noexcept {
    if (this != &o) {
        destroy();
        std::swap(m_ctx, o.m_ctx);
        std::swap(m_job, o.m_job);
        std::swap(m_pipeline, o.m_pipeline);
        std::swap(m_layout, o.m_layout);
        std::swap(m_setLayout, o.m_setLayout);
        std::swap(m_bindPoint, o.m_bindPoint);
        std::swap(m_bindings, o.m_bindings);
    }
    return *this;
}

void Pipeline::finish() const {
    std::shared_ptr<PipelineJob> job = m_job;
    double waited = 0.0;
    m_pipeline = job->wait(&waited); // throws the creation's error (the job stays: it rethrows)
    m_job.reset();
    m_ctx->countUsed(waited);
}

void Pipeline::destroy() {
    if (!m_ctx)
        return;
    if (m_job) {
        // Made on another thread, perhaps still being made; never asked for.
        try {
            m_job->wait();
        } catch (...) {
        }
        m_pipeline = m_job->result();
        m_job.reset();
    }
    if (m_pipeline)
        vkDestroyPipeline(m_ctx->device(), m_pipeline, nullptr);
    if (m_layout)
        vkDestroyPipelineLayout(m_ctx->device(), m_layout, nullptr);
    if (m_setLayout)
        vkDestroyDescriptorSetLayout(m_ctx->device(), m_setLayout, nullptr);
    m_ctx = nullptr;
    m_pipeline = VK_NULL_HANDLE;
    m_layout = VK_NULL_HANDLE;
    m_setLayout = VK_NULL_HANDLE;
}

namespace {

VkShaderModule makeModule(Context& ctx, std::span<const std::uint32_t> spirv) {
    VkShaderModuleCreateInfo ci{VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO};
    ci.codeSize = spirv.size_bytes();
    ci.pCode = spirv.data();
    VkShaderModule m = VK_NULL_HANDLE;
    vkCheck(vkCreateShaderModule(ctx.device(), &ci, nullptr, &m), "vkCreateShaderModule");
    return m;
}

void makeLayout(Context& ctx, const Bindings& bindings, std::uint32_t pushBytes,
                VkShaderStageFlags stages, VkDescriptorSetLayout& setLayout, VkPipelineLayout& layout) {
    SPOT_CHECK_LE(pushBytes, 128u);
    std::vector<VkDescriptorSetLayoutBinding> b(bindings.size());
    for (std::size_t i = 0; i < bindings.size(); ++i) {
        for (std::size_t j = 0; j < i; ++j)
            SPOT_CHECK_NE(bindings[i].binding, bindings[j].binding);
        b[i] = {bindings[i].binding, bindings[i].type, 1, stages, nullptr};
    }
    VkDescriptorSetLayoutCreateInfo dci{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO};
    dci.flags = VK_DESCRIPTOR_SET_LAYOUT_CREATE_PUSH_DESCRIPTOR_BIT_KHR;
    dci.bindingCount = std::uint32_t(b.size());
    dci.pBindings = b.data();
    vkCheck(vkCreateDescriptorSetLayout(ctx.device(), &dci, nullptr, &setLayout),
            "vkCreateDescriptorSetLayout");
    VkPushConstantRange range{stages, 0, pushBytes};
    VkPipelineLayoutCreateInfo pci{VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO};
    pci.setLayoutCount = 1;
    pci.pSetLayouts = &setLayout;
    pci.pushConstantRangeCount = pushBytes ? 1 : 0;
    pci.pPushConstantRanges = &range;
    vkCheck(vkCreatePipelineLayout(ctx.device(), &pci, nullptr, &layout), "vkCreatePipelineLayout");
}

} // namespace

Specialization& Specialization::set(std::uint32_t id, std::uint32_t value) {
    for (const VkSpecializationMapEntry& e : m_entries)
        SPOT_CHECK_NE(e.constantID, id);
    m_entries.push_back({id, std::uint32_t(m_data.size() * sizeof(std::uint32_t)), sizeof(std::uint32_t)});
    m_data.push_back(value);
    return *this;
}

Specialization& Specialization::set(std::uint32_t id, std::int32_t value) {
    return set(id, std::bit_cast<std::uint32_t>(value));
}

Specialization& Specialization::set(std::uint32_t id, float value) {
    return set(id, std::bit_cast<std::uint32_t>(value));
}

Specialization& Specialization::set(std::uint32_t id, bool value) {
    return set(id, std::uint32_t(value ? 1 : 0));
}

VkSpecializationInfo Specialization::info() const {
    VkSpecializationInfo i{};
    i.mapEntryCount = std::uint32_t(m_entries.size());
    i.pMapEntries = m_entries.data();
    i.dataSize = m_data.size() * sizeof(std::uint32_t);
    i.pData = m_data.data();
    return i;
}

std::vector<std::uint32_t> declaredBindings(std::span<const std::uint32_t> spirv) {
    constexpr std::uint32_t kOpDecorate = 71, kDecorationBinding = 33;
    std::vector<std::uint32_t> out;
    for (std::size_t i = 5; i < spirv.size();) {
        const std::uint32_t words = spirv[i] >> 16, op = spirv[i] & 0xffffu;
        if (words == 0 || i + words > spirv.size())
            throw std::logic_error("declaredBindings: malformed SPIR-V");
        if (op == kOpDecorate && words >= 4 && spirv[i + 2] == kDecorationBinding)
            out.push_back(spirv[i + 3]);
        i += words;
    }
    std::sort(out.begin(), out.end());
    out.erase(std::unique(out.begin(), out.end()), out.end());
    return out;
}

namespace {

std::string bindingList(const std::vector<std::uint32_t>& bindings) {
    std::string out;
    for (const std::uint32_t b : bindings)
        out += (out.empty() ? "" : ", ") + std::to_string(b);
    return "{" + out + "}";
}

/// The layout's binding numbers, ascending, checked against those the modules declare.
std::vector<std::uint32_t>
checkedBindings(const Bindings& bindings,
                std::initializer_list<std::span<const std::uint32_t>> modules) {
    std::vector<std::uint32_t> layout, declared;
    for (const Binding& b : bindings)
        layout.push_back(b.binding);
    std::sort(layout.begin(), layout.end());
    for (const std::span<const std::uint32_t> m : modules)
        if (!m.empty())
            for (const std::uint32_t b : declaredBindings(m))
                declared.push_back(b);
    std::sort(declared.begin(), declared.end());
    declared.erase(std::unique(declared.begin(), declared.end()), declared.end());
    if (layout != declared)
        throw std::logic_error(cat("pipeline layout binds ", bindingList(layout),
                                   " but its shaders declare ", bindingList(declared)));
    return layout;
}

void hashSpecialization(PipelineKey& key, const Specialization& spec) {
    const VkSpecializationInfo info = spec.info();
    key.add(info.pMapEntries, info.mapEntryCount * sizeof(VkSpecializationMapEntry));
    key.add(info.pData, info.dataSize);
}

/// The driver's report of one pipeline's creation (core in Vulkan 1.3).
struct Feedback {
    VkPipelineCreationFeedback pipeline{};
    VkPipelineCreationFeedbackCreateInfo info{VK_STRUCTURE_TYPE_PIPELINE_CREATION_FEEDBACK_CREATE_INFO,
                                              nullptr, &pipeline, 0, nullptr};
    bool hit() const {
        return (pipeline.flags & VK_PIPELINE_CREATION_FEEDBACK_VALID_BIT) &&
               (pipeline.flags & VK_PIPELINE_CREATION_FEEDBACK_APPLICATION_PIPELINE_CACHE_HIT_BIT);
    }
};

double msSince(std::chrono::steady_clock::time_point start) {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
        .count();
}

} // namespace

Pipeline makeComputePipeline(Context& ctx, std::span<const std::uint32_t> spirv,
                             const Bindings& bindings, std::uint32_t pushBytes,
                             const Specialization& spec) {
    Pipeline p;
    p.m_ctx = &ctx;
    p.m_bindPoint = VK_PIPELINE_BIND_POINT_COMPUTE;
    p.m_bindings = checkedBindings(bindings, {spirv});
    makeLayout(ctx, bindings, pushBytes, VK_SHADER_STAGE_COMPUTE_BIT, p.m_setLayout, p.m_layout);
    PipelineKey key;
    key.value(std::uint32_t(1)).add(spirv);
    hashSpecialization(key, spec);
    for (const Binding& b : bindings)
        key.value(b.binding).value(b.type);
    key.value(pushBytes);
    VkShaderModule module = makeModule(ctx, spirv);
    const VkPipelineLayout layout = p.m_layout;
    // The creation runs on a pipeline thread: it owns copies of what it reads, and the module.
    p.m_job = ctx.pipelineCompiler().submit([&ctx, module, layout, spec, k = key.get()] {
        VkComputePipelineCreateInfo ci{VK_STRUCTURE_TYPE_COMPUTE_PIPELINE_CREATE_INFO};
        ci.flags =
            VK_PIPELINE_CREATE_DISPATCH_BASE_BIT; // a tile's passes: dispatchPixels (pass_vk.h)
        ci.stage = {VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO};
        ci.stage.stage = VK_SHADER_STAGE_COMPUTE_BIT;
        ci.stage.module = module;
        ci.stage.pName = "main";
        const VkSpecializationInfo specInfo = spec.info();
        ci.stage.pSpecializationInfo = spec.empty() ? nullptr : &specInfo;
        ci.layout = layout;
        Feedback feedback;
        ci.pNext = &feedback.info;
        const auto start = std::chrono::steady_clock::now();
        VkPipeline pipeline = VK_NULL_HANDLE;
        const VkResult r = vkCreateComputePipelines(ctx.device(), ctx.pipelineCacheHandle(), 1, &ci,
                                                    nullptr, &pipeline);
        vkDestroyShaderModule(ctx.device(), module, nullptr);
        vkCheck(r, "vkCreateComputePipelines");
        ctx.countCreated(k, msSince(start), feedback.hit());
        return pipeline;
    });
    return p;
}

Pipeline makeGraphicsPipeline(Context& ctx, const GraphicsPipelineDesc& desc) {
    Pipeline p;
    p.m_ctx = &ctx;
    p.m_bindPoint = VK_PIPELINE_BIND_POINT_GRAPHICS;
    const VkShaderStageFlags stages = VK_SHADER_STAGE_VERTEX_BIT | VK_SHADER_STAGE_FRAGMENT_BIT |
                                      (desc.geometry.empty() ? 0 : VK_SHADER_STAGE_GEOMETRY_BIT);
    p.m_bindings = checkedBindings(desc.bindings, {desc.vertex, desc.geometry, desc.fragment});
    makeLayout(ctx, desc.bindings, desc.pushBytes, stages, p.m_setLayout, p.m_layout);

    PipelineKey key;
    key.value(std::uint32_t(2)).add(desc.vertex).add(desc.geometry).add(desc.fragment);
    hashSpecialization(key, desc.spec);
    for (const Binding& b : desc.bindings)
        key.value(b.binding).value(b.type);
    key.value(desc.pushBytes)
        .add(desc.colorFormats.data(), desc.colorFormats.size() * sizeof(VkFormat));
    key.add(desc.blends.data(), desc.blends.size() * sizeof(VkPipelineColorBlendAttachmentState));
    key.value(desc.depthFormat).value(desc.depthTest).value(desc.depthWrite);
    key.value(desc.depthCompare).value(desc.topology).value(desc.cull);

    // The modules are made here; the creation runs on a pipeline thread with a copy of the
    // description (its code spans are not read there) and owns the modules.
    std::vector<std::pair<VkShaderModule, VkShaderStageFlagBits>> modules;
    const auto addStage = [&](std::span<const std::uint32_t> code, VkShaderStageFlagBits stage) {
        if (!code.empty())
            modules.emplace_back(makeModule(ctx, code), stage);
    };
    addStage(desc.vertex, VK_SHADER_STAGE_VERTEX_BIT);
    addStage(desc.geometry, VK_SHADER_STAGE_GEOMETRY_BIT);
    addStage(desc.fragment, VK_SHADER_STAGE_FRAGMENT_BIT);
    GraphicsPipelineDesc state = desc;
    state.vertex = state.geometry = state.fragment = {};
    const VkPipelineLayout layout = p.m_layout;
    p.m_job = ctx.pipelineCompiler().submit([&ctx, modules, layout, desc = std::move(state),
                                             k = key.get()] {
        std::vector<VkPipelineShaderStageCreateInfo> shaderStages;
        const VkSpecializationInfo specInfo = desc.spec.info();
        for (const auto& [module, stage] : modules) {
            VkPipelineShaderStageCreateInfo s{VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO};
            s.stage = stage;
            s.module = module;
            s.pName = "main";
            s.pSpecializationInfo = desc.spec.empty() ? nullptr : &specInfo;
            shaderStages.push_back(s);
        }

        VkPipelineVertexInputStateCreateInfo vertexInput{
            VK_STRUCTURE_TYPE_PIPELINE_VERTEX_INPUT_STATE_CREATE_INFO};
        VkPipelineInputAssemblyStateCreateInfo assembly{
            VK_STRUCTURE_TYPE_PIPELINE_INPUT_ASSEMBLY_STATE_CREATE_INFO};
        assembly.topology = desc.topology;
        VkPipelineViewportStateCreateInfo viewport{
            VK_STRUCTURE_TYPE_PIPELINE_VIEWPORT_STATE_CREATE_INFO};
        viewport.viewportCount = 1;
        viewport.scissorCount = 1;
        VkPipelineRasterizationStateCreateInfo raster{
            VK_STRUCTURE_TYPE_PIPELINE_RASTERIZATION_STATE_CREATE_INFO};
        raster.polygonMode = VK_POLYGON_MODE_FILL;
        raster.cullMode = desc.cull;
        raster.frontFace = VK_FRONT_FACE_COUNTER_CLOCKWISE;
        raster.lineWidth = 1.0f;
        VkPipelineMultisampleStateCreateInfo multisample{
            VK_STRUCTURE_TYPE_PIPELINE_MULTISAMPLE_STATE_CREATE_INFO};
        multisample.rasterizationSamples = VK_SAMPLE_COUNT_1_BIT;
        VkPipelineDepthStencilStateCreateInfo depth{
            VK_STRUCTURE_TYPE_PIPELINE_DEPTH_STENCIL_STATE_CREATE_INFO};
        depth.depthTestEnable = desc.depthTest;
        depth.depthWriteEnable = desc.depthWrite;
        depth.depthCompareOp = desc.depthCompare;
        VkPipelineColorBlendStateCreateInfo blend{
            VK_STRUCTURE_TYPE_PIPELINE_COLOR_BLEND_STATE_CREATE_INFO};
        SPOT_CHECK_EQ(desc.blends.size(), desc.colorFormats.size());
        blend.attachmentCount = std::uint32_t(desc.blends.size());
        blend.pAttachments = desc.blends.data();
        const VkDynamicState dynamicStates[] = {VK_DYNAMIC_STATE_VIEWPORT,
                                                VK_DYNAMIC_STATE_SCISSOR};
        VkPipelineDynamicStateCreateInfo dynamic{
            VK_STRUCTURE_TYPE_PIPELINE_DYNAMIC_STATE_CREATE_INFO};
        dynamic.dynamicStateCount = 2;
        dynamic.pDynamicStates = dynamicStates;
        VkPipelineRenderingCreateInfo rendering{VK_STRUCTURE_TYPE_PIPELINE_RENDERING_CREATE_INFO};
        rendering.colorAttachmentCount = std::uint32_t(desc.colorFormats.size());
        rendering.pColorAttachmentFormats = desc.colorFormats.data();
        rendering.depthAttachmentFormat = desc.depthFormat;

        VkGraphicsPipelineCreateInfo ci{VK_STRUCTURE_TYPE_GRAPHICS_PIPELINE_CREATE_INFO};
        ci.pNext = &rendering;
        ci.stageCount = std::uint32_t(shaderStages.size());
        ci.pStages = shaderStages.data();
        ci.pVertexInputState = &vertexInput;
        ci.pInputAssemblyState = &assembly;
        ci.pViewportState = &viewport;
        ci.pRasterizationState = &raster;
        ci.pMultisampleState = &multisample;
        ci.pDepthStencilState = &depth;
        ci.pColorBlendState = &blend;
        ci.pDynamicState = &dynamic;
        ci.layout = layout;
        Feedback feedback;
        rendering.pNext = &feedback.info;
        const auto start = std::chrono::steady_clock::now();
        VkPipeline pipeline = VK_NULL_HANDLE;
        const VkResult r = vkCreateGraphicsPipelines(ctx.device(), ctx.pipelineCacheHandle(), 1,
                                                     &ci, nullptr, &pipeline);
        for (const auto& m : modules)
            vkDestroyShaderModule(ctx.device(), m.first, nullptr);
        vkCheck(r, "vkCreateGraphicsPipelines");
        ctx.countCreated(k, msSince(start), feedback.hit());
        return pipeline;
    });
    return p;
}

// ---- Descriptors ------------------------------------------------------------------------------

Descriptors& Descriptors::buffer(std::uint32_t binding, const Buffer& b, VkDescriptorType type) {
    m_buffers.push_back(std::make_unique<VkDescriptorBufferInfo>(b.info()));
    VkWriteDescriptorSet w{VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET};
    w.dstBinding = binding;
    w.descriptorCount = 1;
    w.descriptorType = type;
    w.pBufferInfo = m_buffers.back().get();
    m_writes.push_back(w);
    return *this;
}

Descriptors& Descriptors::buffer(std::uint32_t binding, const Buffer& b, VkDeviceSize offset,
                                 VkDeviceSize range) {
    buffer(binding, b);
    m_buffers.back()->offset = offset;
    m_buffers.back()->range = range;
    return *this;
}

Descriptors& Descriptors::image(std::uint32_t binding, const Image& image, VkImageLayout layout,
                                VkDescriptorType type, VkSampler sampler) {
    m_images.push_back(std::make_unique<VkDescriptorImageInfo>(VkDescriptorImageInfo{sampler, image.view(), layout}));
    VkWriteDescriptorSet w{VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET};
    w.dstBinding = binding;
    w.descriptorCount = 1;
    w.descriptorType = type;
    w.pImageInfo = m_images.back().get();
    m_writes.push_back(w);
    return *this;
}

void Descriptors::push(Context& ctx, VkCommandBuffer cmd, const Pipeline& pipeline) {
    std::vector<std::uint32_t> written;
    written.reserve(m_writes.size());
    for (const VkWriteDescriptorSet& w : m_writes)
        written.push_back(w.dstBinding);
    std::sort(written.begin(), written.end());
    if (written != pipeline.bindings())
        throw std::logic_error(cat("descriptors write ", bindingList(written),
                                   " for a pipeline binding ", bindingList(pipeline.bindings())));
    ctx.pushDescriptorSet(cmd, pipeline.bindPoint(), pipeline.layout(), 0,
                          std::uint32_t(m_writes.size()), m_writes.data());
}

// ---- Timestamps -------------------------------------------------------------------------------

Timestamps::Timestamps(Context& ctx, std::uint32_t count) : m_ctx(ctx), m_count(count) {
    VkQueryPoolCreateInfo ci{VK_STRUCTURE_TYPE_QUERY_POOL_CREATE_INFO};
    ci.queryType = VK_QUERY_TYPE_TIMESTAMP;
    ci.queryCount = count;
    vkCheck(vkCreateQueryPool(ctx.device(), &ci, nullptr, &m_pool), "vkCreateQueryPool");
}

Timestamps::~Timestamps() { vkDestroyQueryPool(m_ctx.device(), m_pool, nullptr); }

void Timestamps::reset(VkCommandBuffer cmd) { vkCmdResetQueryPool(cmd, m_pool, 0, m_count); }

void Timestamps::write(VkCommandBuffer cmd, std::uint32_t slot, VkPipelineStageFlags2 stage) {
    vkCmdWriteTimestamp2(cmd, stage, m_pool, slot);
}

std::vector<double> Timestamps::milliseconds(std::uint32_t count) const {
    const std::uint32_t n = count == 0 ? m_count : std::min(count, m_count);
    std::vector<std::uint64_t> ticks(n);
    vkCheck(vkGetQueryPoolResults(m_ctx.device(), m_pool, 0, n, ticks.size() * 8, ticks.data(), 8,
                                  VK_QUERY_RESULT_64_BIT | VK_QUERY_RESULT_WAIT_BIT),
            "vkGetQueryPoolResults");
    std::vector<double> ms(n);
    const double period = m_ctx.properties().limits.timestampPeriod;
    for (std::uint32_t i = 0; i < n; ++i)
        ms[i] = double(ticks[i] - ticks[0]) * period * 1e-6;
    return ms;
}

} // namespace spot::splat
