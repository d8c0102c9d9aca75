#include "edit_window.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <optional>
#include <stdexcept>
#include <utility>

#include <vulkan/vulkan.h>
// After vulkan.h: GLFW then declares glfwCreateWindowSurface and the presentation queries.
#include <GLFW/glfw3.h>
#include <imgui.h>
#include <imgui_impl_glfw.h>
#include <imgui_impl_vulkan.h>

#include "edit_panels.h"
#include "edit_script.h"
#include "edit_session.h"
#include "edit_view.h"
#include "noise/error.h"
#include "noise/image.h"
#include "noise/mesh.h"
#include "noise/shared_data.h"
#include "render_options.h"
#include "splat/context_vk.h"
#include "splat/frame_vk.h"
#include "splat/passes/splatting_vk.h"

namespace spot::editor {

namespace {

using Clock = std::chrono::steady_clock;

double msSince(Clock::time_point start) {
    return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

double median(std::vector<double> v) {
    if (v.empty())
        return 0.0;
    std::sort(v.begin(), v.end());
    const std::size_t n = v.size();
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// --- GLFW ----------------------------------------------------------------------------------

std::string g_glfwError; ///< the last message of GLFW's error callback

/// glfwInit() and glfwTerminate(), with a clear InputError when there is no display.
struct GlfwLibrary {
    GlfwLibrary() {
        const char* display = std::getenv("DISPLAY");
        if (!display || !*display)
            throw InputError("spotshell edit: no display (DISPLAY is not set); run it in a desktop "
                             "session, or headless under xvfb-run");
        glfwSetErrorCallback(
            [](int, const char* message) { g_glfwError = message ? message : ""; });
        if (!glfwInit())
            throw InputError(
                cat("spotshell edit: cannot open the display '", display, "': ", g_glfwError));
        if (!glfwVulkanSupported()) {
            glfwTerminate();
            throw std::runtime_error("GLFW: no Vulkan loader with window-system support");
        }
    }
    ~GlfwLibrary() { glfwTerminate(); }
    GlfwLibrary(const GlfwLibrary&) = delete;
    GlfwLibrary& operator=(const GlfwLibrary&) = delete;
};

struct GlfwWindow {
    GlfwWindow(int width, int height, const std::string& title) {
        glfwWindowHint(GLFW_CLIENT_API, GLFW_NO_API);
        handle = glfwCreateWindow(width, height, title.c_str(), nullptr, nullptr);
        if (!handle)
            throw std::runtime_error(
                cat("GLFW: cannot create a ", width, "x", height, " window: ", g_glfwError));
    }
    ~GlfwWindow() { glfwDestroyWindow(handle); }
    GlfwWindow(const GlfwWindow&) = delete;
    GlfwWindow& operator=(const GlfwWindow&) = delete;
    GLFWwindow* handle = nullptr;
};

splat::ContextOptions windowContextOptions() {
    splat::ContextOptions o = splat::contextOptionsFromEnvironment();
    std::uint32_t count = 0;
    const char** names = glfwGetRequiredInstanceExtensions(&count);
    if (!names)
        throw std::runtime_error(cat("GLFW: no Vulkan surface extensions: ", g_glfwError));
    for (std::uint32_t i = 0; i < count; ++i)
        o.instanceExtensions.emplace_back(names[i]);
    o.swapchain = true;
    o.canPresent = [](VkInstance instance, VkPhysicalDevice device, std::uint32_t family) {
        return glfwGetPhysicalDevicePresentationSupport(instance, device, family) == GLFW_TRUE;
    };
    return o;
}

// --- Vulkan presentation ------------------------------------------------------------------

struct Surface {
    Surface(splat::Context& ctx, GLFWwindow* window) : m_ctx(ctx) {
        splat::vkCheck(glfwCreateWindowSurface(ctx.instance(), window, nullptr, &handle),
                       "glfwCreateWindowSurface");
        VkBool32 supported = VK_FALSE;
        vkGetPhysicalDeviceSurfaceSupportKHR(ctx.physicalDevice(), ctx.queueFamily(), handle,
                                             &supported);
        if (!supported) {
            vkDestroySurfaceKHR(ctx.instance(), handle, nullptr);
            throw std::runtime_error(cat("Vulkan: queue family ", ctx.queueFamily(), " of ",
                                         ctx.deviceName(), " cannot present to the window"));
        }
    }
    ~Surface() { vkDestroySurfaceKHR(m_ctx.instance(), handle, nullptr); }
    Surface(const Surface&) = delete;
    Surface& operator=(const Surface&) = delete;
    splat::Context& m_ctx;
    VkSurfaceKHR handle = VK_NULL_HANDLE;
};

bool canBlitTo(VkPhysicalDevice device, VkFormat format) {
    VkFormatProperties p;
    vkGetPhysicalDeviceFormatProperties(device, format, &p);
    return (p.optimalTilingFeatures & VK_FORMAT_FEATURE_BLIT_DST_BIT) != 0;
}

/// An sRGB format the blit can write (it then encodes linear to sRGB), else the first format.
VkSurfaceFormatKHR chooseFormat(VkPhysicalDevice device, VkSurfaceKHR surface, bool& srgb) {
    std::uint32_t n = 0;
    vkGetPhysicalDeviceSurfaceFormatsKHR(device, surface, &n, nullptr);
    std::vector<VkSurfaceFormatKHR> formats(n);
    vkGetPhysicalDeviceSurfaceFormatsKHR(device, surface, &n, formats.data());
    if (formats.empty())
        throw std::runtime_error("Vulkan: the window surface has no formats");
    for (VkFormat wanted : {VK_FORMAT_B8G8R8A8_SRGB, VK_FORMAT_R8G8B8A8_SRGB})
        for (const VkSurfaceFormatKHR& f : formats)
            if (f.format == wanted && f.colorSpace == VK_COLOR_SPACE_SRGB_NONLINEAR_KHR &&
                canBlitTo(device, f.format)) {
                srgb = true;
                return f;
            }
    srgb = false;
    for (const VkSurfaceFormatKHR& f : formats)
        if (canBlitTo(device, f.format))
            return f;
    throw std::runtime_error("Vulkan: no window surface format can be a blit destination");
}

/// The swapchain with its images' views and the ImGui render pass's framebuffers, recreated
/// when the window's size changes.
class Swapchain {
public:
    Swapchain(splat::Context& ctx, VkSurfaceKHR surface) : m_ctx(ctx), m_surface(surface) {
        format = chooseFormat(ctx.physicalDevice(), surface, srgb);
        VkAttachmentDescription color{};
        color.format = format.format;
        color.samples = VK_SAMPLE_COUNT_1_BIT;
        color.loadOp = VK_ATTACHMENT_LOAD_OP_LOAD; // the blitted scene
        color.storeOp = VK_ATTACHMENT_STORE_OP_STORE;
        color.stencilLoadOp = VK_ATTACHMENT_LOAD_OP_DONT_CARE;
        color.stencilStoreOp = VK_ATTACHMENT_STORE_OP_DONT_CARE;
        color.initialLayout = VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL;
        color.finalLayout = VK_IMAGE_LAYOUT_PRESENT_SRC_KHR;
        VkAttachmentReference ref{0, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL};
        VkSubpassDescription subpass{};
        subpass.pipelineBindPoint = VK_PIPELINE_BIND_POINT_GRAPHICS;
        subpass.colorAttachmentCount = 1;
        subpass.pColorAttachments = &ref;
        // The blit's writes before ImGui's blending reads and writes.
        VkSubpassDependency dependency{};
        dependency.srcSubpass = VK_SUBPASS_EXTERNAL;
        dependency.dstSubpass = 0;
        dependency.srcStageMask = VK_PIPELINE_STAGE_TRANSFER_BIT;
        dependency.srcAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
        dependency.dstStageMask = VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT;
        dependency.dstAccessMask =
            VK_ACCESS_COLOR_ATTACHMENT_READ_BIT | VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT;
        VkRenderPassCreateInfo rpi{VK_STRUCTURE_TYPE_RENDER_PASS_CREATE_INFO};
        rpi.attachmentCount = 1;
        rpi.pAttachments = &color;
        rpi.subpassCount = 1;
        rpi.pSubpasses = &subpass;
        rpi.dependencyCount = 1;
        rpi.pDependencies = &dependency;
        splat::vkCheck(vkCreateRenderPass(ctx.device(), &rpi, nullptr, &renderPass),
                       "vkCreateRenderPass");
    }
    ~Swapchain() {
        destroyViews();
        for (VkSemaphore s : renderDone)
            vkDestroySemaphore(m_ctx.device(), s, nullptr);
        vkDestroySwapchainKHR(m_ctx.device(), handle, nullptr);
        vkDestroyRenderPass(m_ctx.device(), renderPass, nullptr);
    }
    Swapchain(const Swapchain&) = delete;
    Swapchain& operator=(const Swapchain&) = delete;

    /// (Re)create for the framebuffer size; false when the window is minimized (size 0).
    bool recreate(int fbWidth, int fbHeight) {
        VkSurfaceCapabilitiesKHR caps;
        splat::vkCheck(
            vkGetPhysicalDeviceSurfaceCapabilitiesKHR(m_ctx.physicalDevice(), m_surface, &caps),
            "vkGetPhysicalDeviceSurfaceCapabilitiesKHR");
        VkExtent2D e = caps.currentExtent;
        if (e.width == 0xffffffffu)
            e = {std::uint32_t(fbWidth), std::uint32_t(fbHeight)};
        e.width = std::clamp(e.width, caps.minImageExtent.width, caps.maxImageExtent.width);
        e.height = std::clamp(e.height, caps.minImageExtent.height, caps.maxImageExtent.height);
        if (e.width == 0 || e.height == 0 || fbWidth == 0 || fbHeight == 0)
            return false;
        vkDeviceWaitIdle(m_ctx.device());
        destroyViews();
        std::uint32_t n = 0;
        vkGetPhysicalDeviceSurfacePresentModesKHR(m_ctx.physicalDevice(), m_surface, &n, nullptr);
        std::vector<VkPresentModeKHR> modes(n);
        vkGetPhysicalDeviceSurfacePresentModesKHR(m_ctx.physicalDevice(), m_surface, &n,
                                                  modes.data());
        // MAILBOX never blocks on the display's refresh; FIFO is always there.
        presentMode =
            std::find(modes.begin(), modes.end(), VK_PRESENT_MODE_MAILBOX_KHR) != modes.end()
                ? VK_PRESENT_MODE_MAILBOX_KHR
                : VK_PRESENT_MODE_FIFO_KHR;
        minImageCount = std::max(2u, caps.minImageCount);
        if (caps.maxImageCount > 0)
            minImageCount = std::min(minImageCount, caps.maxImageCount);
        VkSwapchainCreateInfoKHR sci{VK_STRUCTURE_TYPE_SWAPCHAIN_CREATE_INFO_KHR};
        sci.surface = m_surface;
        sci.minImageCount = minImageCount;
        sci.imageFormat = format.format;
        sci.imageColorSpace = format.colorSpace;
        sci.imageExtent = e;
        sci.imageArrayLayers = 1;
        sci.imageUsage = VK_IMAGE_USAGE_TRANSFER_DST_BIT | VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT;
        // Read back for --window-screenshot where the surface allows it.
        readable = caps.supportedUsageFlags & VK_IMAGE_USAGE_TRANSFER_SRC_BIT;
        if (readable)
            sci.imageUsage |= VK_IMAGE_USAGE_TRANSFER_SRC_BIT;
        sci.imageSharingMode = VK_SHARING_MODE_EXCLUSIVE;
        sci.preTransform = caps.currentTransform;
        sci.compositeAlpha = VK_COMPOSITE_ALPHA_OPAQUE_BIT_KHR;
        sci.presentMode = presentMode;
        sci.clipped = VK_TRUE;
        sci.oldSwapchain = handle;
        VkSwapchainKHR created = VK_NULL_HANDLE;
        splat::vkCheck(vkCreateSwapchainKHR(m_ctx.device(), &sci, nullptr, &created),
                       "vkCreateSwapchainKHR");
        vkDestroySwapchainKHR(m_ctx.device(), handle, nullptr);
        handle = created;
        extent = e;
        vkGetSwapchainImagesKHR(m_ctx.device(), handle, &n, nullptr);
        images.resize(n);
        vkGetSwapchainImagesKHR(m_ctx.device(), handle, &n, images.data());
        for (VkImage image : images) {
            VkImageViewCreateInfo vi{VK_STRUCTURE_TYPE_IMAGE_VIEW_CREATE_INFO};
            vi.image = image;
            vi.viewType = VK_IMAGE_VIEW_TYPE_2D;
            vi.format = format.format;
            vi.subresourceRange = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
            VkImageView view = VK_NULL_HANDLE;
            splat::vkCheck(vkCreateImageView(m_ctx.device(), &vi, nullptr, &view),
                           "vkCreateImageView");
            views.push_back(view);
            VkFramebufferCreateInfo fi{VK_STRUCTURE_TYPE_FRAMEBUFFER_CREATE_INFO};
            fi.renderPass = renderPass;
            fi.attachmentCount = 1;
            fi.pAttachments = &view;
            fi.width = e.width;
            fi.height = e.height;
            fi.layers = 1;
            VkFramebuffer fb = VK_NULL_HANDLE;
            splat::vkCheck(vkCreateFramebuffer(m_ctx.device(), &fi, nullptr, &fb),
                           "vkCreateFramebuffer");
            framebuffers.push_back(fb);
        }
        // One "rendering done" semaphore per image: the present of an image waits on its own,
        // so a semaphore is only signalled again after its image came back from the presenter.
        while (renderDone.size() < images.size()) {
            VkSemaphoreCreateInfo si{VK_STRUCTURE_TYPE_SEMAPHORE_CREATE_INFO};
            VkSemaphore s = VK_NULL_HANDLE;
            splat::vkCheck(vkCreateSemaphore(m_ctx.device(), &si, nullptr, &s),
                           "vkCreateSemaphore");
            renderDone.push_back(s);
        }
        return true;
    }

    VkSwapchainKHR handle = VK_NULL_HANDLE;
    VkSurfaceFormatKHR format{};
    bool srgb = false;
    bool readable = false; ///< the images can be copied from (--window-screenshot)
    VkPresentModeKHR presentMode = VK_PRESENT_MODE_FIFO_KHR;
    std::uint32_t minImageCount = 2;
    VkExtent2D extent{0, 0};
    VkRenderPass renderPass = VK_NULL_HANDLE;
    std::vector<VkImage> images;
    std::vector<VkImageView> views;
    std::vector<VkFramebuffer> framebuffers;
    std::vector<VkSemaphore> renderDone;

private:
    void destroyViews() {
        for (VkFramebuffer fb : framebuffers)
            vkDestroyFramebuffer(m_ctx.device(), fb, nullptr);
        for (VkImageView v : views)
            vkDestroyImageView(m_ctx.device(), v, nullptr);
        framebuffers.clear();
        views.clear();
    }
    splat::Context& m_ctx;
    VkSurfaceKHR m_surface;
};

/// The present's command buffer, its fence and the acquire semaphore (one frame in flight).
struct PresentSync {
    explicit PresentSync(splat::Context& ctx) : m_ctx(ctx) {
        VkCommandBufferAllocateInfo ai{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
        ai.commandPool = ctx.commandPool();
        ai.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
        ai.commandBufferCount = 1;
        splat::vkCheck(vkAllocateCommandBuffers(ctx.device(), &ai, &cmd),
                       "vkAllocateCommandBuffers");
        VkFenceCreateInfo fci{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
        splat::vkCheck(vkCreateFence(ctx.device(), &fci, nullptr, &fence), "vkCreateFence");
        VkSemaphoreCreateInfo si{VK_STRUCTURE_TYPE_SEMAPHORE_CREATE_INFO};
        splat::vkCheck(vkCreateSemaphore(ctx.device(), &si, nullptr, &acquired),
                       "vkCreateSemaphore");
    }
    ~PresentSync() {
        vkDeviceWaitIdle(m_ctx.device());
        vkDestroySemaphore(m_ctx.device(), acquired, nullptr);
        vkDestroyFence(m_ctx.device(), fence, nullptr);
        vkFreeCommandBuffers(m_ctx.device(), m_ctx.commandPool(), 1, &cmd);
    }
    PresentSync(const PresentSync&) = delete;
    PresentSync& operator=(const PresentSync&) = delete;
    splat::Context& m_ctx;
    VkCommandBuffer cmd = VK_NULL_HANDLE;
    VkFence fence = VK_NULL_HANDLE;
    VkSemaphore acquired = VK_NULL_HANDLE;
};

// --- Dear ImGui ----------------------------------------------------------------------------

void checkImGuiVk(VkResult r) {
    if (r != VK_SUCCESS)
        throw std::runtime_error(cat("Vulkan (Dear ImGui backend): VkResult ", int(r)));
}

/// The ImGui context, its GLFW and Vulkan backends, their descriptor pool and font texture.
class ImGuiLayer {
public:
    ImGuiLayer(splat::Context& ctx, GLFWwindow* window, const Swapchain& swapchain) : m_ctx(ctx) {
        IMGUI_CHECKVERSION();
        ImGui::CreateContext();
        ImGui::GetIO().IniFilename = nullptr; // no imgui.ini beside the user's files
        ImGui::StyleColorsDark();
        // The swapchain is sRGB: ImGui's colours are sRGB values, so decode them to linear or
        // the panels would come out washed out.
        if (swapchain.srgb)
            for (ImVec4& c : ImGui::GetStyle().Colors)
                c = ImVec4(noise::srgbDecode(c.x), noise::srgbDecode(c.y), noise::srgbDecode(c.z),
                           c.w);
        // Chains to the callbacks the window installed before (navigation and the brush).
        ImGui_ImplGlfw_InitForVulkan(window, true);
        m_glfw = true;
        const VkDescriptorPoolSize size{VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, 16};
        VkDescriptorPoolCreateInfo pi{VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO};
        pi.flags = VK_DESCRIPTOR_POOL_CREATE_FREE_DESCRIPTOR_SET_BIT;
        pi.maxSets = 16;
        pi.poolSizeCount = 1;
        pi.pPoolSizes = &size;
        splat::vkCheck(vkCreateDescriptorPool(ctx.device(), &pi, nullptr, &m_pool),
                       "vkCreateDescriptorPool");
        ImGui_ImplVulkan_InitInfo info{};
        info.Instance = ctx.instance();
        info.PhysicalDevice = ctx.physicalDevice();
        info.Device = ctx.device();
        info.QueueFamily = ctx.queueFamily();
        info.Queue = ctx.queue();
        info.DescriptorPool = m_pool;
        info.MinImageCount = swapchain.minImageCount;
        info.ImageCount = std::uint32_t(swapchain.images.size());
        info.MSAASamples = VK_SAMPLE_COUNT_1_BIT;
        info.CheckVkResultFn = checkImGuiVk;
        if (!ImGui_ImplVulkan_Init(&info, swapchain.renderPass))
            throw std::runtime_error("Dear ImGui: the Vulkan backend did not initialize");
        m_vulkan = true;
        ctx.submitAndWait([](VkCommandBuffer cmd) { ImGui_ImplVulkan_CreateFontsTexture(cmd); });
        ImGui_ImplVulkan_DestroyFontUploadObjects();
    }
    ~ImGuiLayer() {
        vkDeviceWaitIdle(m_ctx.device());
        if (m_vulkan)
            ImGui_ImplVulkan_Shutdown();
        if (m_glfw)
            ImGui_ImplGlfw_Shutdown();
        ImGui::DestroyContext();
        vkDestroyDescriptorPool(m_ctx.device(), m_pool, nullptr);
    }
    ImGuiLayer(const ImGuiLayer&) = delete;
    ImGuiLayer& operator=(const ImGuiLayer&) = delete;

private:
    splat::Context& m_ctx;
    VkDescriptorPool m_pool = VK_NULL_HANDLE;
    bool m_glfw = false, m_vulkan = false;
};

// --- the window's state and input -----------------------------------------------------------

/// What the GLFW callbacks change (through the window's user pointer).
struct InputState {
    enum class Drag { None, Orbit, Pan, Brush };
    OrbitView* view = nullptr;
    edit::Session* session = nullptr;
    BoundingSphere sphere;
    Drag drag = Drag::None;
    double lastX = 0.0, lastY = 0.0;
    bool sceneDirty = true;       ///< render the scene again
    bool resized = true;          ///< recreate the swapchain
    bool closeRequested = false;  ///< the close button, with unsaved changes (the modal asks)
    Clock::time_point lastMotion; ///< of the camera (for the lower resolution while navigating)
    /// The first brush event not yet shown (stroke-to-frame is measured from it).
    std::optional<Clock::time_point> pendingBrush;
    std::string error; ///< a brush or key edit the session refused

    noise::Camera windowCamera(GLFWwindow* window) const {
        int w = 0, h = 0;
        glfwGetWindowSize(window, &w, &h);
        return view->camera(std::max(w, 1), std::max(h, 1));
    }
    void moved() {
        sceneDirty = true;
        lastMotion = Clock::now();
    }
    /// A brush event (window pixels): the session begins, continues or ends the stroke.
    void brush(edit::Session::PointerPhase phase, const noise::Camera& camera, double x, double y,
               bool invert) {
        // A release paints nothing: the frame after it is the full-resolution one.
        if (!pendingBrush && phase != edit::Session::PointerPhase::Release)
            pendingBrush = Clock::now();
        try {
            session->pointer(phase, glm::vec2(float(x), float(y)), camera, invert);
        } catch (const InputError& e) {
            error = e.what();
        }
        sceneDirty = true;
    }
};

InputState& state(GLFWwindow* window) {
    return *static_cast<InputState*>(glfwGetWindowUserPointer(window));
}

void onMouseButton(GLFWwindow* window, int button, int action, int mods) {
    InputState& s = state(window);
    glfwGetCursorPos(window, &s.lastX, &s.lastY);
    if (action == GLFW_RELEASE) {
        if (s.drag == InputState::Drag::Brush && button == GLFW_MOUSE_BUTTON_LEFT)
            s.brush(edit::Session::PointerPhase::Release, s.windowCamera(window), s.lastX, s.lastY,
                    false);
        s.drag = InputState::Drag::None;
        return;
    }
    if (action != GLFW_PRESS || ImGui::GetIO().WantCaptureMouse || s.drag != InputState::Drag::None)
        return;
    const bool shift = mods & GLFW_MOD_SHIFT, alt = mods & GLFW_MOD_ALT;
    if (button == GLFW_MOUSE_BUTTON_MIDDLE || (button == GLFW_MOUSE_BUTTON_LEFT && alt)) {
        s.drag = shift ? InputState::Drag::Pan : InputState::Drag::Orbit;
    } else if (button == GLFW_MOUSE_BUTTON_LEFT) {
        s.drag = InputState::Drag::Brush;
        // Shift or ctrl at the press inverts the stroke: density-add erases, length shrinks.
        s.brush(edit::Session::PointerPhase::Press, s.windowCamera(window), s.lastX, s.lastY,
                (mods & (GLFW_MOD_SHIFT | GLFW_MOD_CONTROL)) != 0);
    }
}

void onCursor(GLFWwindow* window, double x, double y) {
    InputState& s = state(window);
    const double dx = x - s.lastX, dy = y - s.lastY;
    s.lastX = x;
    s.lastY = y;
    int w = 0, h = 0;
    glfwGetWindowSize(window, &w, &h);
    switch (s.drag) {
    case InputState::Drag::Orbit:
        s.view->orbit(dx, dy, h);
        s.moved();
        break;
    case InputState::Drag::Pan:
        s.view->pan(dx, dy, h);
        s.moved();
        break;
    case InputState::Drag::Brush:
        s.brush(edit::Session::PointerPhase::Drag, s.windowCamera(window), x, y, false);
        break;
    case InputState::Drag::None:
        break;
    }
}

void onScroll(GLFWwindow* window, double, double dy) {
    if (ImGui::GetIO().WantCaptureMouse)
        return;
    InputState& s = state(window);
    s.view->dolly(dy);
    s.moved();
}

void frameMesh(GLFWwindow* window, InputState& s) {
    int w = 0, h = 0;
    glfwGetWindowSize(window, &w, &h);
    s.view->frame(s.sphere, h > 0 ? double(w) / double(h) : 1.0);
    s.moved();
}

void onKey(GLFWwindow* window, int key, int, int action, int mods) {
    if ((action != GLFW_PRESS && action != GLFW_REPEAT) || ImGui::GetIO().WantCaptureKeyboard)
        return;
    InputState& s = state(window);
    edit::Session& session = *s.session;
    edit::BrushSettings& brush = session.brush();
    const bool shift = mods & GLFW_MOD_SHIFT, control = mods & GLFW_MOD_CONTROL;
    if (s.drag == InputState::Drag::Brush) // no undo or brush change in the middle of a stroke
        return;
    try {
        if (control && key == GLFW_KEY_Z)
            s.sceneDirty |= shift ? session.redo() : session.undo();
        else if (control && key == GLFW_KEY_Y)
            s.sceneDirty |= session.redo();
        else if (control)
            return;
        else if (key == GLFW_KEY_F || key == GLFW_KEY_HOME)
            frameMesh(window, s);
        else if (key == GLFW_KEY_LEFT_BRACKET || key == GLFW_KEY_RIGHT_BRACKET) {
            const bool up = key == GLFW_KEY_RIGHT_BRACKET;
            if (shift)
                brush.strength = std::clamp(brush.strength + (up ? 0.05f : -0.05f), -1.0f, 1.0f);
            else
                brush.radiusPx =
                    std::clamp(brush.radiusPx * (up ? 1.15f : 1.0f / 1.15f), 2.0f, 400.0f);
        } else if (key >= GLFW_KEY_1 && key <= GLFW_KEY_7)
            s.sceneDirty |=
                session.setBrushKind(edit::BrushKind(key - GLFW_KEY_1)).generatorRebuilt;
        else if (key == GLFW_KEY_X)
            brush.mirrorX = !brush.mirrorX;
    } catch (const InputError& e) {
        s.error = e.what();
    }
}

void onClose(GLFWwindow* window) {
    InputState& s = state(window);
    const QuitStep step = quitStep(s.session->dirty(), true, QuitAnswer::None);
    if (!step.close) {
        glfwSetWindowShouldClose(window, GLFW_FALSE);
        s.closeRequested = step.ask;
    }
}

void onFramebufferSize(GLFWwindow* window, int, int) {
    state(window).resized = true;
    state(window).sceneDirty = true;
}

// --- panels -------------------------------------------------------------------------------

/// Render at 1/kScales[i] of the window's size (the blit scales up).
constexpr int kScales[] = {1, 2, 4};
/// Frames slower than this while moving or painting lower the resolution (10 fps).
constexpr double kInteractiveMs = 100.0;
constexpr const char* kScaleNames = "full resolution\0half resolution\0quarter resolution\0";

/// What the panels edit.
struct PanelState {
    int method = 0;
    splat::RenderSettings settings;
    bool continuous = false;
    int scale = 0;           ///< index into kScales: always
    int navigationScale = 1; ///< index into kScales: while the camera moves or a stroke paints
    int refineFrames = 16;   ///< idle refinement steps (0: off)
    std::string error;       ///< why the last render failed (shown until one succeeds)
};

std::string megabytes(std::uint64_t bytes) {
    char text[32];
    std::snprintf(text, sizeof text, "%.1f MiB", double(bytes) / (1024.0 * 1024.0));
    return text;
}

/// Returns whether a setting changed (the scene is then rendered again).
bool methodPanel(PanelState& p) {
    bool changed = false;
    const auto& methods = splat::gpuMethods();
    ImGui::SetNextWindowPos(ImVec2(8, 8), ImGuiCond_FirstUseEver);
    ImGui::SetNextWindowSize(ImVec2(300, 0), ImGuiCond_FirstUseEver);
    // A small window shows the scene first: the panel starts folded (below 700 pixels high, to
    // leave the left side to the Brush panel).
    ImGui::SetNextWindowCollapsed(ImGui::GetIO().DisplaySize.x < 640.0f ||
                                      ImGui::GetIO().DisplaySize.y < 700.0f,
                                  ImGuiCond_FirstUseEver);
    ImGui::Begin("Render");
    ImGui::PushItemWidth(150);
    if (ImGui::BeginCombo("method", methods[std::size_t(p.method)].name.c_str())) {
        for (int i = 0; i < int(methods.size()); ++i) {
            if (ImGui::Selectable(methods[std::size_t(i)].name.c_str(), i == p.method)) {
                changed |= i != p.method;
                p.method = i;
            }
            if (ImGui::IsItemHovered())
                ImGui::SetTooltip("%s", methods[std::size_t(i)].summary.c_str());
        }
        ImGui::EndCombo();
    }
    const splat::MethodInfo& m = methods[std::size_t(p.method)];
    splat::RenderSettings& s = p.settings;
    changed |= renderSettingsWidgets(m, s); // the settings `m` takes (edit_panels.h)
    ImGui::Separator();
    changed |= ImGui::Checkbox("render every frame", &p.continuous);
    changed |= ImGui::Combo("resolution", &p.scale, kScaleNames);
    ImGui::Combo("moving / painting", &p.navigationScale, kScaleNames);
    changed |= ImGui::SliderInt("refine when idle", &p.refineFrames, 0, 64);
    ImGui::TextDisabled("orbit: middle drag (alt+left)\npan: shift+middle\nzoom: wheel\n"
                        "frame the mesh: F or Home");
    if (!p.error.empty())
        ImGui::TextColored(ImVec4(1.0f, 0.3f, 0.2f, 1.0f), "%s", p.error.c_str());
    ImGui::PopItemWidth();
    ImGui::End();
    return changed;
}

void statsPanel(const splat::FrameStats& st, int renderW, int renderH, int windowW, int windowH,
                double frameMs, double presentMs, bool navigating, bool srgb,
                const std::string& refining) {
    const ImGuiIO& io = ImGui::GetIO();
    ImGui::SetNextWindowPos(ImVec2(io.DisplaySize.x - 8, io.DisplaySize.y - 8), ImGuiCond_Always,
                            ImVec2(1, 1));
    // The status line below says what matters; the details start folded in a small window.
    ImGui::SetNextWindowCollapsed(io.DisplaySize.x < 640.0f || io.DisplaySize.y < 700.0f,
                                  ImGuiCond_FirstUseEver);
    ImGui::SetNextWindowBgAlpha(0.6f);
    ImGui::Begin("Stats", nullptr,
                 ImGuiWindowFlags_AlwaysAutoResize | ImGuiWindowFlags_NoMove |
                     ImGuiWindowFlags_NoFocusOnAppearing | ImGuiWindowFlags_NoNav);
    if (renderW != windowW || renderH != windowH)
        ImGui::Text("%s  %dx%d scaled up%s", st.method.c_str(), renderW, renderH,
                    navigating ? " while moving or painting" : "");
    else
        ImGui::Text("%s  %dx%d", st.method.c_str(), renderW, renderH);
    for (const auto& [pass, ms] : st.passMs)
        ImGui::Text("  %-12s %8.2f ms GPU", pass.c_str(), ms);
    if (!refining.empty())
        ImGui::TextColored(ImVec4(0.5f, 0.8f, 1.0f, 1.0f), "%s", refining.c_str());
    ImGui::Text("total GPU      %8.2f ms", st.gpuMs);
    ImGui::Text("render wall    %8.2f ms", st.wallMs);
    ImGui::Text("present+ImGui  %8.2f ms", presentMs);
    ImGui::Text("frame          %8.2f ms (%.1f fps)", frameMs,
                frameMs > 0 ? 1000.0 / frameMs : 0.0);
    ImGui::Text("kernels %u generated%s, %u drawn", st.kernelsGenerated,
                st.regenerated ? " (new)" : "", st.counters.kernelsDrawn);
    ImGui::Text("cells %u of %u visible", st.cellsGenerated, st.visibleCells);
    ImGui::Text("GPU memory %s (peak)", megabytes(st.gpuMemoryBytes).c_str());
    if (!srgb)
        ImGui::TextColored(ImVec4(1, 0.5f, 0.2f, 1), "no sRGB swapchain: shown linear (dark)");
    ImGui::End();
}

/// One line at the bottom left, always shown: the method, the render size and whether it is
/// scaled up (moving or painting), the frame rate, the refinement's progress.
void statusLine(const splat::FrameStats& st, int renderW, int renderH, int windowW, int windowH,
                double frameMs, bool lowRes, const std::string& refining) {
    std::string text = cat(st.method, " ", renderW, "x", renderH);
    if (renderW != windowW || renderH != windowH)
        text += lowRes ? " scaled up while moving or painting" : " scaled up";
    char rate[48];
    std::snprintf(rate, sizeof rate, "  %.0f ms (%.1f fps)", frameMs,
                  frameMs > 0 ? 1000.0 / frameMs : 0.0);
    text += rate;
    if (!refining.empty())
        text += "  " + refining;
    ImDrawList* draw = ImGui::GetForegroundDrawList();
    const ImVec2 size = ImGui::CalcTextSize(text.c_str());
    const ImVec2 at(8.0f, ImGui::GetIO().DisplaySize.y - size.y - 8.0f);
    draw->AddRectFilled(ImVec2(at.x - 4, at.y - 2), ImVec2(at.x + size.x + 4, at.y + size.y + 2),
                        IM_COL32(0, 0, 0, 150));
    draw->AddText(at, IM_COL32(255, 255, 255, 255), text.c_str());
}

// --- the frame's presentation --------------------------------------------------------------

/// The presented image (scene and panels) copied back for --window-screenshot.
struct WindowGrab {
    splat::Buffer buffer;
    std::uint32_t width = 0, height = 0;
    VkFormat format = VK_FORMAT_UNDEFINED;

    void record(splat::Context& ctx, VkCommandBuffer cmd, VkImage image, VkExtent2D extent,
                VkFormat imageFormat) {
        const VkDeviceSize bytes = VkDeviceSize(extent.width) * extent.height * 4;
        if (buffer.size() < bytes)
            buffer = splat::Buffer(ctx, bytes, VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                                   splat::Buffer::Memory::HostVisible, "window screenshot");
        width = extent.width;
        height = extent.height;
        format = imageFormat;
        splat::transitionImage(
            cmd, image, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_PRESENT_SRC_KHR,
            VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT,
            VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT, VK_PIPELINE_STAGE_2_COPY_BIT,
            VK_ACCESS_2_TRANSFER_READ_BIT);
        VkBufferImageCopy region{};
        region.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
        region.imageExtent = {width, height, 1};
        vkCmdCopyImageToBuffer(cmd, image, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, buffer.handle(), 1,
                               &region);
        splat::transitionImage(
            cmd, image, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL,
            VK_IMAGE_LAYOUT_PRESENT_SRC_KHR, VK_PIPELINE_STAGE_2_COPY_BIT, VK_ACCESS_2_NONE,
            VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, VK_ACCESS_2_NONE);
        splat::memoryBarrier(cmd, VK_PIPELINE_STAGE_2_COPY_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT,
                             VK_PIPELINE_STAGE_2_HOST_BIT, VK_ACCESS_2_HOST_READ_BIT);
    }

    /// Linear RGB; the 8-bit values are sRGB-encoded when the swapchain is sRGB.
    noise::Image read(bool srgb) const {
        noise::Image image(static_cast<int>(width), static_cast<int>(height));
        const auto* p = static_cast<const std::uint8_t*>(buffer.mapped());
        const bool bgr = format == VK_FORMAT_B8G8R8A8_SRGB || format == VK_FORMAT_B8G8R8A8_UNORM;
        for (std::size_t i = 0; i < image.pixels.size(); ++i) {
            glm::vec3 c(p[4 * i] / 255.0f, p[4 * i + 1] / 255.0f, p[4 * i + 2] / 255.0f);
            if (bgr)
                std::swap(c.x, c.z);
            image.pixels[i] = srgb ? glm::vec3(noise::srgbDecode(c.x), noise::srgbDecode(c.y),
                                               noise::srgbDecode(c.z))
                                   : c;
        }
        return image;
    }
};

/// Blit the scene into the swapchain image, draw ImGui over it, present; with `grab`, also copy
/// the presented image back. Returns false when the swapchain is out of date (then recreated by
/// the caller).
bool present(splat::Context& ctx, Swapchain& swapchain, PresentSync& sync,
             const splat::Image& scene, WindowGrab* grab = nullptr,
             const splat::Image* inset = nullptr, VkOffset2D insetAt = {0, 0}) {
    std::uint32_t index = 0;
    const VkResult acquired = vkAcquireNextImageKHR(ctx.device(), swapchain.handle, UINT64_MAX,
                                                    sync.acquired, VK_NULL_HANDLE, &index);
    if (acquired == VK_ERROR_OUT_OF_DATE_KHR)
        return false;
    if (acquired != VK_SUBOPTIMAL_KHR)
        splat::vkCheck(acquired, "vkAcquireNextImageKHR");
    VkCommandBuffer cmd = sync.cmd;
    splat::vkCheck(vkResetCommandBuffer(cmd, 0), "vkResetCommandBuffer");
    VkCommandBufferBeginInfo bi{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
    bi.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
    splat::vkCheck(vkBeginCommandBuffer(cmd, &bi), "vkBeginCommandBuffer");
    const VkImage target = swapchain.images[index];
    // The renderer's last pass (a compute shader, in an earlier submit) wrote the scene; the
    // renderers keep it in the general layout, the blit reads it best as a transfer source.
    splat::transitionImage(cmd, scene.handle(), VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_GENERAL,
                           VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL,
                           VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, VK_ACCESS_2_MEMORY_WRITE_BIT,
                           VK_PIPELINE_STAGE_2_BLIT_BIT, VK_ACCESS_2_TRANSFER_READ_BIT);
    splat::transitionImage(cmd, target, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_UNDEFINED,
                           VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL,
                           VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, VK_ACCESS_2_NONE,
                           VK_PIPELINE_STAGE_2_BLIT_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT);
    VkImageBlit blit{};
    blit.srcSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
    blit.srcOffsets[1] = {std::int32_t(scene.width()), std::int32_t(scene.height()), 1};
    blit.dstSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
    blit.dstOffsets[1] = {std::int32_t(swapchain.extent.width),
                          std::int32_t(swapchain.extent.height), 1};
    const bool scaled =
        scene.width() != swapchain.extent.width || scene.height() != swapchain.extent.height;
    VkFormatProperties fp;
    vkGetPhysicalDeviceFormatProperties(ctx.physicalDevice(), scene.format(), &fp);
    const bool linear =
        scaled && (fp.optimalTilingFeatures & VK_FORMAT_FEATURE_SAMPLED_IMAGE_FILTER_LINEAR_BIT);
    vkCmdBlitImage(cmd, scene.handle(), VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, target,
                   VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, 1, &blit,
                   linear ? VK_FILTER_LINEAR : VK_FILTER_NEAREST);
    splat::transitionImage(cmd, scene.handle(), VK_IMAGE_ASPECT_COLOR_BIT,
                           VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, VK_IMAGE_LAYOUT_GENERAL,
                           VK_PIPELINE_STAGE_2_BLIT_BIT, VK_ACCESS_2_NONE,
                           VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT,
                           VK_ACCESS_2_MEMORY_READ_BIT | VK_ACCESS_2_MEMORY_WRITE_BIT);
    if (inset) {
        // The kernel preview over a corner of the scene, at its own size.
        splat::transitionImage(cmd, inset->handle(), VK_IMAGE_ASPECT_COLOR_BIT,
                               VK_IMAGE_LAYOUT_GENERAL, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL,
                               VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, VK_ACCESS_2_MEMORY_WRITE_BIT,
                               VK_PIPELINE_STAGE_2_BLIT_BIT, VK_ACCESS_2_TRANSFER_READ_BIT);
        splat::memoryBarrier(cmd, VK_PIPELINE_STAGE_2_BLIT_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT,
                             VK_PIPELINE_STAGE_2_BLIT_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT);
        VkImageBlit b{};
        b.srcSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
        b.srcOffsets[1] = {std::int32_t(inset->width()), std::int32_t(inset->height()), 1};
        b.dstSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
        b.dstOffsets[0] = {insetAt.x, insetAt.y, 0};
        b.dstOffsets[1] = {insetAt.x + std::int32_t(inset->width()),
                           insetAt.y + std::int32_t(inset->height()), 1};
        vkCmdBlitImage(cmd, inset->handle(), VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, target,
                       VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, 1, &b, VK_FILTER_NEAREST);
        splat::transitionImage(cmd, inset->handle(), VK_IMAGE_ASPECT_COLOR_BIT,
                               VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, VK_IMAGE_LAYOUT_GENERAL,
                               VK_PIPELINE_STAGE_2_BLIT_BIT, VK_ACCESS_2_NONE,
                               VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT,
                               VK_ACCESS_2_MEMORY_READ_BIT | VK_ACCESS_2_MEMORY_WRITE_BIT);
    }
    VkRenderPassBeginInfo rp{VK_STRUCTURE_TYPE_RENDER_PASS_BEGIN_INFO};
    rp.renderPass = swapchain.renderPass;
    rp.framebuffer = swapchain.framebuffers[index];
    rp.renderArea.extent = swapchain.extent;
    vkCmdBeginRenderPass(cmd, &rp, VK_SUBPASS_CONTENTS_INLINE);
    ImGui_ImplVulkan_RenderDrawData(ImGui::GetDrawData(), cmd);
    vkCmdEndRenderPass(cmd);
    if (grab)
        grab->record(ctx, cmd, target, swapchain.extent, swapchain.format.format);
    splat::vkCheck(vkEndCommandBuffer(cmd), "vkEndCommandBuffer");

    const VkPipelineStageFlags waitStage = VK_PIPELINE_STAGE_ALL_COMMANDS_BIT;
    VkSubmitInfo si{VK_STRUCTURE_TYPE_SUBMIT_INFO};
    si.waitSemaphoreCount = 1;
    si.pWaitSemaphores = &sync.acquired;
    si.pWaitDstStageMask = &waitStage;
    si.commandBufferCount = 1;
    si.pCommandBuffers = &cmd;
    si.signalSemaphoreCount = 1;
    si.pSignalSemaphores = &swapchain.renderDone[index];
    splat::vkCheck(vkResetFences(ctx.device(), 1, &sync.fence), "vkResetFences");
    splat::vkCheck(vkQueueSubmit(ctx.queue(), 1, &si, sync.fence), "vkQueueSubmit");
    VkPresentInfoKHR pi{VK_STRUCTURE_TYPE_PRESENT_INFO_KHR};
    pi.waitSemaphoreCount = 1;
    pi.pWaitSemaphores = &swapchain.renderDone[index];
    pi.swapchainCount = 1;
    pi.pSwapchains = &swapchain.handle;
    pi.pImageIndices = &index;
    const VkResult presented = vkQueuePresentKHR(ctx.queue(), &pi);
    // One frame in flight: the next frame's renderer writes the image the blit reads.
    splat::vkCheck(vkWaitForFences(ctx.device(), 1, &sync.fence, VK_TRUE, UINT64_MAX),
                   "vkWaitForFences");
    if (presented == VK_ERROR_OUT_OF_DATE_KHR || presented == VK_SUBOPTIMAL_KHR)
        return false;
    splat::vkCheck(presented, "vkQueuePresentKHR");
    return true;
}

/// A host image uploaded into an RGBA32F image in the general layout (as the renderers leave
/// their results), for present() to blit.
struct UploadedImage {
    splat::Image image;
    splat::Buffer staging;

    void upload(splat::Context& ctx, const noise::Image& pixels, const char* what) {
        const auto w = std::uint32_t(pixels.width), h = std::uint32_t(pixels.height);
        if (image.width() != w || image.height() != h)
            image = splat::Image(ctx, w, h, VK_FORMAT_R32G32B32A32_SFLOAT,
                                 VK_IMAGE_USAGE_TRANSFER_DST_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT |
                                     VK_IMAGE_USAGE_STORAGE_BIT,
                                 VK_IMAGE_ASPECT_COLOR_BIT, what);
        const VkDeviceSize bytes = VkDeviceSize(w) * h * 4 * sizeof(float);
        if (staging.size() < bytes)
            staging = splat::Buffer(ctx, bytes, VK_BUFFER_USAGE_TRANSFER_SRC_BIT,
                                    splat::Buffer::Memory::HostVisible, what);
        auto* p = static_cast<float*>(staging.mapped());
        for (const glm::vec3& c : pixels.pixels) {
            *p++ = c.x;
            *p++ = c.y;
            *p++ = c.z;
            *p++ = 1.0f;
        }
        ctx.submitAndWait([&](VkCommandBuffer cmd) {
            splat::transitionImage(cmd, image.handle(), VK_IMAGE_ASPECT_COLOR_BIT,
                                   VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL,
                                   VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, VK_ACCESS_2_NONE,
                                   VK_PIPELINE_STAGE_2_COPY_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT);
            VkBufferImageCopy region{};
            region.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
            region.imageExtent = {w, h, 1};
            vkCmdCopyBufferToImage(cmd, staging.handle(), image.handle(),
                                   VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, 1, &region);
            splat::transitionImage(cmd, image.handle(), VK_IMAGE_ASPECT_COLOR_BIT,
                                   VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, VK_IMAGE_LAYOUT_GENERAL,
                                   VK_PIPELINE_STAGE_2_COPY_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT,
                                   VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT,
                                   VK_ACCESS_2_MEMORY_READ_BIT | VK_ACCESS_2_MEMORY_WRITE_BIT);
        });
    }
};

/// The idle refinement: the running average of jittered full-resolution frames, on the host
/// and uploaded for the present to blit like a renderer's result.
struct Refinement {
    int count = 0; ///< frames averaged (0: not refining; the interactive frame is shown)
    std::vector<glm::vec3> sum;
    noise::Image average;
    UploadedImage uploaded;
    const splat::Image& image() const { return uploaded.image; }

    void add(splat::Context& ctx, const noise::Image& frame) {
        if (count == 0 || average.width != frame.width || average.height != frame.height) {
            count = 0;
            sum.assign(frame.pixels.size(), glm::vec3(0.0f));
            average = noise::Image(frame.width, frame.height);
        }
        ++count;
        const float inv = 1.0f / float(count);
        for (std::size_t i = 0; i < sum.size(); ++i) {
            sum[i] += frame.pixels[i];
            average.pixels[i] = sum[i] * inv;
        }
        uploaded.upload(ctx, average, "idle refinement");
    }
};

/// A live preview of one kernel: one impulse of the session's kernel standing on a plane, seen
/// from the side (orthographic), rendered by the `instanced` splatting renderer into a small
/// image whenever the kernel changes. Its own SceneGpu (the plane and the kernel's lobes), so
/// the session's frame and its targets are untouched. The impulse is scaled to fill the view
/// and its weight divided by the same factor, so its optical depth is the scene's at the
/// preset's constant scale.
class KernelPreview {
public:
    static constexpr int kSize = 160;

    /// Render again when the kernel's JSON changed; the image to show.
    const splat::Image& update(splat::Context& ctx, const edit::Session& session) {
        const nlohmann::json kernel = session.get("kernel");
        if (kernel == m_kernel && m_uploaded.image.handle() != VK_NULL_HANDLE)
            return m_uploaded.image;
        const auto start = Clock::now();
        m_kernel = kernel;
        const noise::Kernel& k = session.generator().kernel();
        m_renderer.reset();
        m_scene = std::make_unique<splat::SceneGpu>(ctx, m_plane, k);
        m_renderer = std::make_unique<splat::SplatRenderer>(*m_scene, splat::Method::Instanced);
        // The kernel's extent in kernel units (3 sigma around each lobe).
        float top = 1e-3f, side = 1e-3f;
        for (const noise::LobeDesc& l : session.preset().kernel.lobes) {
            top = std::max(top, l.offset.z + 3.0f * l.sigma.z);
            side = std::max({side, std::abs(l.offset.x) + 3.0f * l.sigma.x,
                             std::abs(l.offset.y) + 3.0f * l.sigma.y});
        }
        const float scale = 1.6f / std::max(top, 2.0f * side);
        const noise::FieldDesc& s = session.preset().scale;
        const float sceneScale =
            s.kind == noise::FieldDesc::Kind::Constant ? std::max(s.value.x, 1e-6f) : 0.02f;
        noise::Impulse impulse;
        impulse.normal = glm::vec3(0, 1, 0);
        impulse.comb = glm::vec3(1, 0, 0);
        // Kernel space x (comb), y (bitangent), z (normal) in world.
        impulse.frame = glm::mat3(glm::vec3(1, 0, 0), glm::vec3(0, 0, -1), glm::vec3(0, 1, 0));
        impulse.scale = glm::vec3(scale);
        impulse.weight = sceneScale / scale;
        const std::vector<gpu::SpotImpulse> g = gpu::toGpu(std::vector<noise::Impulse>{impulse});
        m_impulses =
            splat::Buffer(ctx, sizeof(gpu::SpotImpulse), VK_BUFFER_USAGE_STORAGE_BUFFER_BIT,
                          splat::Buffer::Memory::HostVisible, "kernel preview impulse");
        m_impulses.upload(std::span<const gpu::SpotImpulse>(g));
        noise::Camera camera;
        camera.projection = noise::Projection::Orthographic;
        camera.eye = glm::dvec3(0.0, 1.2, 5.0);
        camera.target = glm::dvec3(0.0, 0.85, 0.0);
        camera.orthoHeight = 2.0;
        camera.width = camera.height = kSize;
        const noise::SceneDesc& scene = session.scene();
        const noise::Image image = splat::renderImpulses(
            ctx, *m_renderer, splat::View{camera, scene.shading, scene.background, scene.baseColor},
            m_impulses, 1, splat::RenderSettings{});
        m_uploaded.upload(ctx, image, "kernel preview");
        lastMs = msSince(start);
        return m_uploaded.image;
    }
    double lastMs = 0.0; ///< the last render, milliseconds

private:
    noise::Mesh m_plane = noise::loadMeshOrGenerated("generated:plane");
    nlohmann::json m_kernel;
    std::unique_ptr<splat::SceneGpu> m_scene;
    std::unique_ptr<splat::SplatRenderer> m_renderer;
    splat::Buffer m_impulses;
    UploadedImage m_uploaded;
};

int methodIndex(const std::string& name) {
    const auto& methods = splat::gpuMethods();
    return int(&splat::gpuMethod(name) - methods.data());
}

/// The Save / Discard / Cancel modal, opened when the window was asked to close with unsaved
/// changes.
QuitAnswer quitModal(InputState& input, const SessionPanels& panels) {
    if (input.closeRequested) {
        ImGui::OpenPopup("Unsaved changes");
        input.closeRequested = false;
    }
    QuitAnswer answer = QuitAnswer::None;
    if (ImGui::BeginPopupModal("Unsaved changes", nullptr, ImGuiWindowFlags_AlwaysAutoResize)) {
        ImGui::Text("The preset has unsaved changes.\nSave them to %s first?",
                    panels.savePath.c_str());
        if (ImGui::Button("Save"))
            answer = QuitAnswer::Save;
        ImGui::SameLine();
        if (ImGui::Button("Discard"))
            answer = QuitAnswer::Discard;
        ImGui::SameLine();
        if (ImGui::Button("Cancel"))
            answer = QuitAnswer::Cancel;
        if (answer != QuitAnswer::None)
            ImGui::CloseCurrentPopup();
        ImGui::EndPopup();
    }
    return answer;
}

} // namespace

EditWindowReport runEditWindow(const SessionFactory& makeSession,
                               const EditWindowOptions& options) {
    const auto& methods = splat::gpuMethods();
    PanelState panel;
    panel.method = methodIndex(options.method);
    panel.settings = options.settings;
    panel.continuous = options.frames > 0;
    panel.refineFrames = options.refineFrames;
    panel.scale = int(std::find(std::begin(kScales), std::end(kScales), options.renderScale) -
                      std::begin(kScales));
    if (panel.scale == int(std::size(kScales)))
        throw InputError(cat("render scale ", options.renderScale, " must be 1, 2 or 4"));

    // Destroyed in reverse: ImGui, the swapchain, the surface, the session (its frame and
    // context), the window, GLFW. The display is checked before anything else is made.
    GlfwLibrary glfw;
    GlfwWindow window(options.width, options.height, options.title);
    const std::unique_ptr<edit::Session> owned = makeSession(windowContextOptions());
    edit::Session& session = *owned;
    splat::Context& ctx = session.context();
    Surface surface(ctx, window.handle);
    Swapchain swapchain(ctx, surface.handle);
    PresentSync sync(ctx);

    OrbitView view(session.camera());
    InputState input;
    input.view = &view;
    input.session = &session;
    input.sphere = boundingSphere(session.mesh());
    glfwSetWindowUserPointer(window.handle, &input);
    glfwSetMouseButtonCallback(window.handle, onMouseButton);
    glfwSetCursorPosCallback(window.handle, onCursor);
    glfwSetScrollCallback(window.handle, onScroll);
    glfwSetKeyCallback(window.handle, onKey);
    glfwSetFramebufferSizeCallback(window.handle, onFramebufferSize);
    glfwSetWindowCloseCallback(window.handle, onClose);

    int fbW = 0, fbH = 0;
    glfwGetFramebufferSize(window.handle, &fbW, &fbH);
    swapchain.recreate(fbW, fbH);
    input.resized = false;
    ImGuiLayer imgui(ctx, window.handle, swapchain);
    SessionPanels panels;
    panels.savePath = cat(session.scene().name, "-edited.json");
    panels.exportPath = cat(session.scene().name, "-view.png");

    splat::FrameStats stats;
    const splat::Image* scene = nullptr;
    int renderW = 0, renderH = 0;
    std::string renderedWith; ///< method and size of the last render (warm-frame bookkeeping)
    std::vector<double> frameMs, renderMs, presentMs, overlayMs, refineMs, refineAddMs,
        strokeFrameMs;
    EditWindowReport report;
    double lastFrameMs = 0.0, lastPresentMs = 0.0;
    std::optional<noise::Image> screenshot, windowImage;
    WindowGrab windowGrab;
    Refinement refine;
    KernelPreview preview;
    int movingScale = 0; ///< index into kScales: lowered when moving frames are too slow
    std::vector<double> recentLowMs; ///< the last moving or painting frames' times
    int slowWindows = 0;             ///< ... groups of five in a row with a slow median
    int navigationScaleChosen = panel.navigationScale;
    edit::ScriptReport scriptReport;
    std::size_t scriptNext = 0, strokePoint = 0; ///< the next action; a stroke's next point
    auto scriptDone = [&] { return scriptNext >= options.script.size(); };
    auto lastTick = Clock::now();
    bool quit = false;

    while (!glfwWindowShouldClose(window.handle) && !quit) {
        if (options.frames > 0 && report.frames >= options.frames && scriptDone())
            break;
        const auto frameStart = Clock::now();
        const bool busy = panel.continuous || input.drag != InputState::Drag::None ||
                          !scriptDone() || session.wind() ||
                          (panel.refineFrames > 0 && refine.count < panel.refineFrames);
        if (busy)
            glfwPollEvents();
        else
            glfwWaitEventsTimeout(0.25); // idle: redraw the overlay a few times a second
        glfwGetFramebufferSize(window.handle, &fbW, &fbH);
        if (fbW == 0 || fbH == 0) { // minimized
            glfwWaitEvents();
            continue;
        }
        if (input.resized) {
            if (!swapchain.recreate(fbW, fbH))
                continue;
            ImGui_ImplVulkan_SetMinImageCount(swapchain.minImageCount);
            input.resized = false;
        }
        const int fullW = int(swapchain.extent.width), fullH = int(swapchain.extent.height);
        if (options.cycleMethods) {
            int next = report.frames % int(methods.size());
            if (methods[std::size_t(next)].takes(splat::settings::bake) && !panel.settings.bake)
                next = 0; // `baked` needs a bake file (--bake)
            input.sceneDirty |= next != panel.method;
            panel.method = next;
        }
        if (options.orbitDegreesPerFrame != 0.0 && report.frames > 0) {
            view.orbit(options.orbitDegreesPerFrame, 0.0, 180.0); // 180 pixels: half a turn
            input.moved();
        }

        // The script: one action between two frames; a stroke one pointer event per frame.
        std::optional<glm::vec2> scriptPointer;
        if (!scriptDone()) {
            const edit::ScriptAction& a = options.script[scriptNext];
            if (a.type == edit::ScriptAction::Type::Stroke) {
                using Phase = edit::Session::PointerPhase;
                const std::size_t i = std::min(strokePoint, a.points.size() - 1);
                const Phase phase = strokePoint == 0                ? Phase::Press
                                    : strokePoint < a.points.size() ? Phase::Drag
                                                                    : Phase::Release;
                try {
                    if (!input.pendingBrush && phase != Phase::Release)
                        input.pendingBrush = Clock::now();
                    session.pointer(phase, a.points[i], input.windowCamera(window.handle));
                } catch (const InputError& e) {
                    throw InputError(
                        cat("script ", options.scriptName, ":", a.line, ": ", e.what()));
                }
                scriptPointer = a.points[i];
                input.sceneDirty = true;
                if (phase == Phase::Release) {
                    ++scriptReport.strokes;
                    ++scriptNext;
                    strokePoint = 0;
                    if (options.log)
                        std::fprintf(options.log, "%4d  %s\n", a.line, a.text.c_str());
                } else {
                    ++strokePoint;
                }
            } else {
                // The window's view, so that `screenshot` and `frames` show what it shows.
                session.setCamera(view.camera(fullW, fullH));
                edit::runScriptAction(session, a, options.scriptName, options.log, scriptReport);
                ++scriptNext;
                panel.method = methodIndex(session.method());
                panel.settings = session.settings();
                const noise::Camera now = session.camera(), shown = view.camera(fullW, fullH);
                if (now.eye != shown.eye || now.target != shown.target ||
                    now.fovYDeg != shown.fovYDeg)
                    view = OrbitView(now);
                input.sceneDirty = true;
            }
        }
        // Wind animates: the session's time advances (1/30 s a frame when scripted).
        const double tick = std::chrono::duration<double>(Clock::now() - lastTick).count();
        lastTick = Clock::now();
        if (session.wind() && scriptDone()) {
            session.setTime(session.time() + (options.frames > 0 ? 1.0 / 30.0 : tick));
            input.sceneDirty = true;
        }

        const bool stroking = input.drag == InputState::Drag::Brush || strokePoint > 0;
        const bool navigating =
            input.drag == InputState::Drag::Orbit || input.drag == InputState::Drag::Pan ||
            std::chrono::duration<double>(Clock::now() - input.lastMotion).count() < 0.3;
        const bool lowRes = navigating || stroking;
        const auto overlayStart = Clock::now();
        ImGui_ImplVulkan_NewFrame();
        ImGui_ImplGlfw_NewFrame();
        ImGui::NewFrame();
        const int methodShown = panel.method;
        input.sceneDirty |= methodPanel(panel);
        if (panel.navigationScale != navigationScaleChosen || panel.method != methodShown) {
            navigationScaleChosen = panel.navigationScale;
            movingScale = 0;
        }
        if (!input.error.empty()) {
            panels.message = input.error;
            panels.messageIsError = true;
            input.error.clear();
        }
        // The panels' Export renders the view as the window shows it.
        session.setMethod(methods[std::size_t(panel.method)].name, panel.settings);
        session.setCamera(view.camera(fullW, fullH));
        input.sceneDirty |= sessionPanels(session, panels);
        const QuitStep quitting = quitStep(session.dirty(), false, quitModal(input, panels));
        if (quitting.close && (!quitting.save || saveSession(session, panels)))
            quit = true;
        std::string refining;
        if (panel.refineFrames > 0 && refine.count > 0)
            refining =
                refine.count < panel.refineFrames
                    ? cat("refining ", refine.count, "/", panel.refineFrames, " (sorted, jittered)")
                    : cat("refined ", refine.count, "/", panel.refineFrames, " (sorted, jittered)");
        statsPanel(stats, renderW, renderH, fullW, fullH, lastFrameMs, lastPresentMs,
                   lowRes && std::max(panel.navigationScale, movingScale) > panel.scale,
                   swapchain.srgb, refining);
        statusLine(stats, renderW, renderH, fullW, fullH, lastFrameMs,
                   lowRes && std::max(panel.navigationScale, movingScale) > panel.scale, refining);
        // The brush under the pointer (or the script's pointer).
        const ImVec2 mouse = ImGui::GetIO().MousePos;
        const bool overScene = !ImGui::GetIO().WantCaptureMouse && ImGui::IsMousePosValid();
        if (scriptPointer || (overScene && input.drag != InputState::Drag::Orbit &&
                              input.drag != InputState::Drag::Pan)) {
            const ImVec2 at = scriptPointer ? ImVec2(scriptPointer->x, scriptPointer->y) : mouse;
            ImGui::GetForegroundDrawList()->AddCircle(at, session.brush().radiusPx,
                                                      IM_COL32(255, 255, 255, 200), 48, 1.5f);
        }
        if (panels.kernelOpen) { // a frame around the kernel preview
            const float x = float(fullW - 330 - 8 - KernelPreview::kSize);
            ImGui::GetForegroundDrawList()->AddRect(
                ImVec2(x - 1, 7), ImVec2(x + KernelPreview::kSize + 1, 9 + KernelPreview::kSize),
                IM_COL32(120, 120, 140, 255));
        }
        ImGui::Render();
        const double overlay = msSince(overlayStart);

        // Navigation or a stroke ended: back to the resolution chosen.
        if (!lowRes && scene && refine.count == 0 &&
            (renderW != std::max(1, fullW / kScales[panel.scale]) ||
             renderH != std::max(1, fullH / kScales[panel.scale])))
            input.sceneDirty = true;
        const bool change = input.sceneDirty || !scene;
        if (change)
            refine.count = 0;
        const bool last = options.frames > 0 && scriptDone() && report.frames + 1 >= options.frames;
        const bool refineNow = !change && !lowRes && panel.refineFrames > 0 &&
                               refine.count < panel.refineFrames && !session.wind();
        const std::string& method = methods[std::size_t(panel.method)].name;
        bool warm = true, rendered = false;
        const splat::Image* shown = refine.count > 0 ? &refine.image() : scene;
        if (refineNow) {
            // One more jittered frame of the most accurate method into the running average.
            const auto refineStart = Clock::now();
            // Without EWA: the average of the jittered point-sampled frames is the box-filtered
            // image; EWA's widened kernels would blur it twice.
            splat::RenderSettings refineSettings = panel.settings;
            refineSettings.ewa = false;
            session.setMethod("sorted", refineSettings);
            const glm::dvec2 jitter = haltonJitter(refine.count);
            session.setCamera(jitteredCamera(view.camera(fullW, fullH), jitter.x, jitter.y));
            noise::Image image;
            stats = session.render(&image);
            const auto addStart = Clock::now();
            refine.add(ctx, image);
            refineAddMs.push_back(msSince(addStart));
            refineMs.push_back(msSince(refineStart));
            ++report.refined;
            renderW = fullW;
            renderH = fullH;
            shown = &refine.image();
            warm = false;
            renderedWith = "refine";
        } else if (change || (panel.continuous && refine.count == 0)) {
            const int scale =
                kScales[lowRes ? std::max({panel.scale, panel.navigationScale, movingScale})
                               : panel.scale];
            renderW = std::max(1, fullW / scale);
            renderH = std::max(1, fullH / scale);
            noise::Image image;
            const bool capture = last && !options.screenshot.empty();
            const auto renderStart = Clock::now();
            try {
                session.setMethod(method, panel.settings);
                session.setCamera(view.camera(renderW, renderH));
                stats = session.render(capture ? &image : nullptr);
                panel.error.clear();
            } catch (const InputError& e) {
                // Interactively, a setting the method refuses (or a frame beyond the memory
                // budget) is shown in the panel; scripted, it fails. The session may have
                // rebuilt its frame: the last image is gone.
                if (!scene || options.frames > 0)
                    throw;
                panel.error = e.what();
                input.sceneDirty = false;
                scene = nullptr;
                ImGui::EndFrame();
                continue;
            }
            const double renderWall = msSince(renderStart);
            if (capture)
                screenshot = std::move(image);
            scene = &session.frame().renderer(method).result();
            shown = scene;
            input.sceneDirty = false;
            rendered = true;
            ++report.rendered;
            // Warm: the same method at the same size as the last render (the first frame after
            // a change creates targets and compiles pipelines).
            const std::string key = cat(method, " ", renderW, "x", renderH);
            warm = key == renderedWith;
            renderedWith = key;
            if (warm)
                renderMs.push_back(renderWall);
        }
        if (last && !options.screenshot.empty() && refine.count > 0)
            screenshot = refine.average;
        const auto presentStart = Clock::now();
        const bool grab = last && !options.windowScreenshot.empty();
        if (grab && !swapchain.readable)
            throw std::runtime_error("--window-screenshot: the window's images cannot be read back "
                                     "on this surface");
        // The kernel preview while the Kernel panel is open (rendered again when the kernel
        // changed), left of the panel's place at the top right.
        const splat::Image* inset = nullptr;
        const int insetX = fullW - 330 - 8 - KernelPreview::kSize;
        if (panels.kernelOpen && insetX >= 8 && fullH >= KernelPreview::kSize + 16) {
            try {
                inset = &preview.update(ctx, session);
            } catch (const InputError& e) {
                panels.message = e.what();
                panels.messageIsError = true;
            }
        }
        if (!present(ctx, swapchain, sync, *shown, grab ? &windowGrab : nullptr, inset,
                     VkOffset2D{insetX, 8}))
            input.resized = true;
        if (grab)
            windowImage = windowGrab.read(swapchain.srgb);
        lastPresentMs = msSince(presentStart);
        lastFrameMs = msSince(frameStart);
        if (rendered && input.pendingBrush) {
            report.strokeToFrameMs.push_back(msSince(*input.pendingBrush));
            input.pendingBrush.reset();
        }
        if (rendered && stroking && warm)
            strokeFrameMs.push_back(lastFrameMs);
        // Moving or painting below 10 frames a second (the median of five such frames, twice
        // in a row: not the rebuild after a parameter edit): a lower resolution for the rest of the
        // session (a quarter at most); the Render panel's choice resets it.
        if (rendered && lowRes && warm) {
            recentLowMs.push_back(lastFrameMs);
            if (recentLowMs.size() == 5) {
                slowWindows = median(recentLowMs) > kInteractiveMs ? slowWindows + 1 : 0;
                if (slowWindows == 2 && movingScale < int(std::size(kScales)) - 1) {
                    movingScale = std::max(movingScale, panel.navigationScale) + 1;
                    slowWindows = 0;
                }
                recentLowMs.clear();
            }
        }
        if (warm && report.frames > 0) {
            presentMs.push_back(lastPresentMs);
            frameMs.push_back(lastFrameMs);
            overlayMs.push_back(overlay);
        }
        ++report.frames;
        if (report.frames == 1 && options.resizeWidth > 0 && options.resizeHeight > 0)
            glfwSetWindowSize(window.handle, options.resizeWidth, options.resizeHeight);
    }
    vkDeviceWaitIdle(ctx.device());

    if (!options.screenshot.empty()) {
        if (!screenshot) { // closed by the user: the view as it was last shown
            session.setMethod(methods[std::size_t(panel.method)].name, panel.settings);
            session.setCamera(
                view.camera(int(swapchain.extent.width), int(swapchain.extent.height)));
            noise::Image image;
            session.render(&image);
            screenshot = std::move(image);
        }
        noise::writeImage(options.screenshot, *screenshot,
                          {{"method", refine.count > 0 ? std::string("sorted (refined)")
                                                       : methods[std::size_t(panel.method)].name},
                           {"scene", session.scene().name}});
    }
    if (windowImage)
        noise::writeImage(options.windowScreenshot, *windowImage,
                          {{"scene", session.scene().name}});
    const splat::ValidationCounts v = ctx.validation();
    if (v.errors > 0)
        throw std::runtime_error(cat(v.errors, " Vulkan validation errors, first: ", v.firstError));
    report.validation = ctx.validationEnabled();
    report.validationWarnings = v.warnings;
    report.warmFrames = int(frameMs.size());
    report.frameMs = median(frameMs);
    report.renderMs = median(renderMs);
    report.presentMs = median(presentMs);
    report.overlayMs = median(overlayMs);
    report.refineMs = median(refineMs);
    report.refineAverageMs = median(refineAddMs);
    report.previewMs = preview.lastMs;
    report.strokeFrameMs = median(strokeFrameMs);
    report.strokeFrames = int(strokeFrameMs.size());
    report.lowScale = kScales[std::max(panel.navigationScale, movingScale)];
    return report;
}

std::vector<cli::OptionSpec> editWindowOptions() {
    return {
        {"method", "NAME",
         "the method shown first: " + splat::gpuMethodNames() + " (default instanced)", false},
        {"frames", "N", "render N frames, then close (default: until the window is closed)", false},
        {"screenshot", "FILE",
         "write the last rendered scene (without the panels) as .png or .exr when the window "
         "closes (without a window: the view after the script)",
         false},
        {"window-screenshot", "FILE",
         "with --frames: write the last frame as the window "
         "showed it, panels included",
         false},
        {"render-scale", "N",
         "render at 1/N of the window's size, scaled up: 1 (default), 2 "
         "or 4",
         false},
        {"orbit", "DEG",
         "scripted navigation: orbit by DEG degrees per frame from the second "
         "frame on (times a moving camera)",
         false},
        {"resize", "WxH", "after the first frame, resize the window (scripted checks)", false},
        {"cycle-methods", "",
         "frame i shows method i of the registry, in turn (scripted "
         "checks)",
         false},
        {"refine", "N",
         "when idle, average N jittered full-resolution frames of `sorted` (default 16; 0 "
         "with --frames unless given)",
         false}};
}

EditWindowOptions editWindowOptions(const cli::Args& args, int width, int height,
                                    const std::string& sceneName) {
    EditWindowOptions o;
    o.title = cat("spotshell edit - ", sceneName);
    o.width = width;
    o.height = height;
    o.method = args.str("method", "instanced");
    splat::gpuMethod(o.method); // InputError naming the methods
    o.settings = cli::renderSettings(args);
    o.frames = int(args.integer("frames", 0, 0, 1000000));
    // Scripted runs time and compare the interactive frames: no refinement unless asked for.
    o.refineFrames = int(args.integer("refine", o.frames > 0 ? 0 : 16, 0, 1024));
    if (args.has("screenshot"))
        o.screenshot = args.str("screenshot");
    if (args.has("resize")) {
        const std::string size = args.str("resize");
        char x = 0, extra = 0;
        if (std::sscanf(size.c_str(), "%d%c%d%c", &o.resizeWidth, &x, &o.resizeHeight, &extra) !=
                3 ||
            (x != 'x' && x != 'X') || o.resizeWidth < 1 || o.resizeHeight < 1 ||
            o.resizeWidth > 16384 || o.resizeHeight > 16384)
            throw InputError(cat("--resize '", size, "' must be WxH with sides in [1, 16384]"));
    }
    o.cycleMethods = args.has("cycle-methods");
    o.orbitDegreesPerFrame = args.number("orbit", 0.0, -180.0, 180.0);
    o.renderScale = int(args.integer("render-scale", 1, 1, 4));
    if (o.renderScale == 3)
        throw InputError("--render-scale must be 1, 2 or 4, not 3");
    if (args.has("window-screenshot")) {
        if (o.frames == 0)
            throw InputError("--window-screenshot needs --frames");
        o.windowScreenshot = args.str("window-screenshot");
    }
    return o;
}

} // namespace spot::editor
