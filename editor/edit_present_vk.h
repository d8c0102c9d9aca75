/// @file edit_present_vk.h
/// @brief The editor window's Vulkan presentation: the window's surface, the swapchain with the
/// render pass Dear ImGui draws in, the present's command buffer and semaphores, ImGui's context
/// and backends, and present() (blit the scene into the swapchain image, draw the panels over
/// it, present). Every object is owned by an RAII type (splat::UniqueHandle,
/// splat::CommandBuffer, or the small owners here), so a create that throws releases what was
/// made before it and nothing leaks at exit.
#pragma once

#include <cstdint>
#include <vector>

#include <vulkan/vulkan.h>

#include "noise/image.h"
#include "splat/context_vk.h"

struct GLFWwindow;

namespace spot::editor {

/// The window's surface, refused when the context's queue cannot present to it.
splat::UniqueSurface makeSurface(splat::Context& ctx, GLFWwindow* window);

/// The swapchain with its images' views and the ImGui render pass's framebuffers, recreated
/// when the window's size changes. Members are destroyed in reverse: framebuffers, views,
/// semaphores, the swapchain, the render pass.
class Swapchain {
public:
    /// The format (sRGB when the blit can write one) and the render pass; no images until
    /// recreate().
    Swapchain(splat::Context& ctx, VkSurfaceKHR surface);

    /// (Re)create for the framebuffer size; false when the window is minimized (size 0).
    bool recreate(int fbWidth, int fbHeight);

    VkSurfaceFormatKHR format{};
    bool srgb = false;
    bool readable = false; ///< the images can be copied from (--window-screenshot)
    VkPresentModeKHR presentMode = VK_PRESENT_MODE_FIFO_KHR;
    std::uint32_t minImageCount = 2;
    VkExtent2D extent{0, 0};
    splat::UniqueRenderPass renderPass;
    splat::UniqueSwapchain handle;
    std::vector<VkImage> images;
    std::vector<splat::UniqueSemaphore> renderDone;
    std::vector<splat::UniqueImageView> views;
    std::vector<splat::UniqueFramebuffer> framebuffers;

private:
    void createSwapchain(const VkSurfaceCapabilitiesKHR& caps, VkExtent2D e);
    void addFramebuffer(VkImage image);

    splat::Context& m_ctx;
    VkSurfaceKHR m_surface;
};

/// The present's command buffer (with its fence) and the acquire semaphore: one frame in
/// flight. The command buffer is destroyed first; it waits for the queue to be idle.
struct PresentSync {
    explicit PresentSync(splat::Context& ctx) : acquired(splat::makeSemaphore(ctx)), cmd(ctx) {}
    splat::UniqueSemaphore acquired;
    splat::CommandBuffer cmd;
};

/// ImGui's context (no imgui.ini; the dark style, decoded to linear for an sRGB swapchain).
struct ImGuiContextScope {
    explicit ImGuiContextScope(bool srgb);
    ~ImGuiContextScope();
    ImGuiContextScope(const ImGuiContextScope&) = delete;
    ImGuiContextScope& operator=(const ImGuiContextScope&) = delete;
};

/// ImGui's GLFW backend; it chains to the callbacks the window installed before (navigation
/// and the brush).
struct ImGuiGlfwBackend {
    explicit ImGuiGlfwBackend(GLFWwindow* window);
    ~ImGuiGlfwBackend();
    ImGuiGlfwBackend(const ImGuiGlfwBackend&) = delete;
    ImGuiGlfwBackend& operator=(const ImGuiGlfwBackend&) = delete;
};

/// ImGui's Vulkan backend on the overlay render pass, with its font texture uploaded.
struct ImGuiVulkanBackend {
    ImGuiVulkanBackend(splat::Context& ctx, VkDescriptorPool pool, const Swapchain& swapchain);
    ~ImGuiVulkanBackend();
    ImGuiVulkanBackend(const ImGuiVulkanBackend&) = delete;
    ImGuiVulkanBackend& operator=(const ImGuiVulkanBackend&) = delete;
};

/// The ImGui context, its GLFW and Vulkan backends, their descriptor pool and font texture:
/// each part owns itself, so a part that throws releases those made before it.
class ImGuiLayer {
public:
    ImGuiLayer(splat::Context& ctx, GLFWwindow* window, const Swapchain& swapchain);
    /// The GPU may still draw the last frame's panels.
    ~ImGuiLayer();
    ImGuiLayer(const ImGuiLayer&) = delete;
    ImGuiLayer& operator=(const ImGuiLayer&) = delete;

private:
    splat::Context& m_ctx;
    ImGuiContextScope m_context;
    ImGuiGlfwBackend m_glfw;
    splat::UniqueDescriptorPool m_pool;
    ImGuiVulkanBackend m_vulkan;
};

/// The presented image (scene and panels) copied back for --window-screenshot.
struct WindowGrab {
    splat::Buffer buffer;
    std::uint32_t width = 0, height = 0;
    VkFormat format = VK_FORMAT_UNDEFINED;

    /// Copy the presentable `image` into `buffer` (its layout back to PRESENT_SRC after).
    void record(splat::Context& ctx, VkCommandBuffer cmd, VkImage image, VkExtent2D extent,
                VkFormat imageFormat);
    /// Linear RGB; the 8-bit values are sRGB-encoded when the swapchain is sRGB.
    noise::Image read(bool srgb) const;
};

/// Clear the swapchain image to `background` where the viewport does not cover it, blit the
/// scene into the viewport (the image's top-left `viewport`, scaled when their sizes differ) and
/// `inset` at `insetAt` (at its own size), draw ImGui's draw data over it, present; with `grab`,
/// also copy the presented image back. Returns false when the swapchain is out of date (then
/// recreated by the caller).
bool present(splat::Context& ctx, Swapchain& swapchain, PresentSync& sync,
             const splat::Image& scene, VkExtent2D viewport, VkClearColorValue background,
             WindowGrab* grab = nullptr, const splat::Image* inset = nullptr,
             VkOffset2D insetAt = {0, 0});

/// A host image uploaded into an RGBA32F image in the general layout (as the renderers leave
/// their results), for present() to blit.
struct UploadedImage {
    splat::Image image;
    splat::Buffer staging;

    void upload(splat::Context& ctx, const noise::Image& pixels, const char* what);
};

} // namespace spot::editor
