#include "edit_present_vk.h"

#include <algorithm>
#include <stdexcept>
#include <utility>

#include <vulkan/vulkan.h>
// After vulkan.h: GLFW then declares glfwCreateWindowSurface and the presentation queries.
#include <GLFW/glfw3.h>
#include <imgui.h>
#include <imgui_impl_glfw.h>
#include <imgui_impl_vulkan.h>

#include "noise/error.h"

namespace spot::editor {

namespace {

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

/// The render pass ImGui draws in: over the blitted scene (loaded, not cleared), ending in the
/// layout the present wants.
splat::UniqueRenderPass makeOverlayPass(splat::Context& ctx, VkFormat format) {
    VkAttachmentDescription color{};
    color.format = format;
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
    VkRenderPass pass = VK_NULL_HANDLE;
    splat::vkCheck(vkCreateRenderPass(ctx.device(), &rpi, nullptr, &pass), "vkCreateRenderPass");
    return splat::UniqueRenderPass(ctx.device(), pass);
}

void checkImGuiVk(VkResult r) {
    if (r != VK_SUCCESS)
        splat::vkCheck(r, "a call of Dear ImGui's Vulkan backend");
}

/// The descriptor pool ImGui's Vulkan backend allocates its font texture's set from.
splat::UniqueDescriptorPool makeImGuiPool(splat::Context& ctx) {
    const VkDescriptorPoolSize size{VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, 16};
    VkDescriptorPoolCreateInfo pi{VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO};
    pi.flags = VK_DESCRIPTOR_POOL_CREATE_FREE_DESCRIPTOR_SET_BIT;
    pi.maxSets = 16;
    pi.poolSizeCount = 1;
    pi.pPoolSizes = &size;
    VkDescriptorPool pool = VK_NULL_HANDLE;
    splat::vkCheck(vkCreateDescriptorPool(ctx.device(), &pi, nullptr, &pool),
                   "vkCreateDescriptorPool");
    return splat::UniqueDescriptorPool(ctx.device(), pool);
}

} // namespace

splat::UniqueSurface makeSurface(splat::Context& ctx, GLFWwindow* window) {
    VkSurfaceKHR created = VK_NULL_HANDLE;
    splat::vkCheck(glfwCreateWindowSurface(ctx.instance(), window, nullptr, &created),
                   "glfwCreateWindowSurface");
    splat::UniqueSurface surface(ctx.instance(), created);
    VkBool32 supported = VK_FALSE;
    vkGetPhysicalDeviceSurfaceSupportKHR(ctx.physicalDevice(), ctx.queueFamily(), created,
                                         &supported);
    if (!supported)
        throw std::runtime_error(cat("Vulkan: queue family ", ctx.queueFamily(), " of ",
                                     ctx.deviceName(), " cannot present to the window"));
    return surface;
}

Swapchain::Swapchain(splat::Context& ctx, VkSurfaceKHR surface) : m_ctx(ctx), m_surface(surface) {
    format = chooseFormat(ctx.physicalDevice(), surface, srgb);
    renderPass = makeOverlayPass(ctx, format.format);
}

bool Swapchain::recreate(int fbWidth, int fbHeight) {
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
    framebuffers.clear();
    views.clear();
    createSwapchain(caps, e);
    std::uint32_t n = 0;
    vkGetSwapchainImagesKHR(m_ctx.device(), handle.get(), &n, nullptr);
    images.resize(n);
    vkGetSwapchainImagesKHR(m_ctx.device(), handle.get(), &n, images.data());
    for (VkImage image : images)
        addFramebuffer(image);
    // One "rendering done" semaphore per image: the present of an image waits on its own,
    // so a semaphore is only signalled again after its image came back from the presenter.
    while (renderDone.size() < images.size())
        renderDone.push_back(splat::makeSemaphore(m_ctx));
    return true;
}

/// The swapchain for extent `e`, replacing (and destroying) the one before.
void Swapchain::createSwapchain(const VkSurfaceCapabilitiesKHR& caps, VkExtent2D e) {
    std::uint32_t n = 0;
    vkGetPhysicalDeviceSurfacePresentModesKHR(m_ctx.physicalDevice(), m_surface, &n, nullptr);
    std::vector<VkPresentModeKHR> modes(n);
    vkGetPhysicalDeviceSurfacePresentModesKHR(m_ctx.physicalDevice(), m_surface, &n, modes.data());
    // MAILBOX never blocks on the display's refresh; FIFO is always there.
    presentMode = std::find(modes.begin(), modes.end(), VK_PRESENT_MODE_MAILBOX_KHR) != modes.end()
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
    sci.oldSwapchain = handle.get();
    VkSwapchainKHR created = VK_NULL_HANDLE;
    splat::vkCheck(vkCreateSwapchainKHR(m_ctx.device(), &sci, nullptr, &created),
                   "vkCreateSwapchainKHR");
    handle = splat::UniqueSwapchain(m_ctx.device(), created); // the old one destroyed
    extent = e;
}

/// A view of a swapchain image and the overlay pass's framebuffer on it.
void Swapchain::addFramebuffer(VkImage image) {
    VkImageViewCreateInfo vi{VK_STRUCTURE_TYPE_IMAGE_VIEW_CREATE_INFO};
    vi.image = image;
    vi.viewType = VK_IMAGE_VIEW_TYPE_2D;
    vi.format = format.format;
    vi.subresourceRange = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
    VkImageView view = VK_NULL_HANDLE;
    splat::vkCheck(vkCreateImageView(m_ctx.device(), &vi, nullptr, &view), "vkCreateImageView");
    views.emplace_back(m_ctx.device(), view);
    VkFramebufferCreateInfo fi{VK_STRUCTURE_TYPE_FRAMEBUFFER_CREATE_INFO};
    fi.renderPass = renderPass.get();
    fi.attachmentCount = 1;
    fi.pAttachments = &view;
    fi.width = extent.width;
    fi.height = extent.height;
    fi.layers = 1;
    VkFramebuffer fb = VK_NULL_HANDLE;
    splat::vkCheck(vkCreateFramebuffer(m_ctx.device(), &fi, nullptr, &fb), "vkCreateFramebuffer");
    framebuffers.emplace_back(m_ctx.device(), fb);
}

ImGuiContextScope::ImGuiContextScope(bool srgb) {
    IMGUI_CHECKVERSION();
    ImGui::CreateContext();
    ImGui::GetIO().IniFilename = nullptr; // no imgui.ini beside the user's files
    ImGui::StyleColorsDark();
    // The swapchain is sRGB: ImGui's colours are sRGB values, so decode them to linear or
    // the panels would come out washed out.
    if (srgb)
        for (ImVec4& c : ImGui::GetStyle().Colors)
            c = ImVec4(noise::srgbDecode(c.x), noise::srgbDecode(c.y), noise::srgbDecode(c.z), c.w);
}
ImGuiContextScope::~ImGuiContextScope() {
    ImGui::DestroyContext();
}

ImGuiGlfwBackend::ImGuiGlfwBackend(GLFWwindow* window) {
    ImGui_ImplGlfw_InitForVulkan(window, true);
}

ImGuiGlfwBackend::~ImGuiGlfwBackend() {
    ImGui_ImplGlfw_Shutdown();
}

ImGuiVulkanBackend::ImGuiVulkanBackend(splat::Context& ctx, VkDescriptorPool pool,
                                       const Swapchain& swapchain) {
    ImGui_ImplVulkan_InitInfo info{};
    info.Instance = ctx.instance();
    info.PhysicalDevice = ctx.physicalDevice();
    info.Device = ctx.device();
    info.QueueFamily = ctx.queueFamily();
    info.Queue = ctx.queue();
    info.DescriptorPool = pool;
    info.MinImageCount = swapchain.minImageCount;
    info.ImageCount = std::uint32_t(swapchain.images.size());
    info.MSAASamples = VK_SAMPLE_COUNT_1_BIT;
    info.CheckVkResultFn = checkImGuiVk;
    if (!ImGui_ImplVulkan_Init(&info, swapchain.renderPass.get()))
        throw std::runtime_error("Dear ImGui: the Vulkan backend did not initialize");
    try {
        ctx.submitAndWait([](VkCommandBuffer cmd) { ImGui_ImplVulkan_CreateFontsTexture(cmd); });
    } catch (...) {
        ImGui_ImplVulkan_Shutdown();
        throw;
    }
    ImGui_ImplVulkan_DestroyFontUploadObjects();
}
ImGuiVulkanBackend::~ImGuiVulkanBackend() {
    ImGui_ImplVulkan_Shutdown();
}

ImGuiLayer::ImGuiLayer(splat::Context& ctx, GLFWwindow* window, const Swapchain& swapchain)
    : m_ctx(ctx), m_context(swapchain.srgb), m_glfw(window), m_pool(makeImGuiPool(ctx)),
      m_vulkan(ctx, m_pool.get(), swapchain) {}

ImGuiLayer::~ImGuiLayer() {
    vkDeviceWaitIdle(m_ctx.device());
}

void WindowGrab::record(splat::Context& ctx, VkCommandBuffer cmd, VkImage image, VkExtent2D extent,
                        VkFormat imageFormat) {
    const VkDeviceSize bytes = VkDeviceSize(extent.width) * extent.height * 4;
    if (buffer.size() < bytes)
        buffer = splat::Buffer(ctx, bytes, VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                               splat::Buffer::Memory::HostVisible, "window screenshot");
    width = extent.width;
    height = extent.height;
    format = imageFormat;
    splat::transitionImage(cmd, image, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_PRESENT_SRC_KHR,
                           VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL,
                           VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT,
                           VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT, VK_PIPELINE_STAGE_2_COPY_BIT,
                           VK_ACCESS_2_TRANSFER_READ_BIT);
    VkBufferImageCopy region{};
    region.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
    region.imageExtent = {width, height, 1};
    vkCmdCopyImageToBuffer(cmd, image, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, buffer.handle(), 1,
                           &region);
    splat::transitionImage(cmd, image, VK_IMAGE_ASPECT_COLOR_BIT,
                           VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, VK_IMAGE_LAYOUT_PRESENT_SRC_KHR,
                           VK_PIPELINE_STAGE_2_COPY_BIT, VK_ACCESS_2_NONE,
                           VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, VK_ACCESS_2_NONE);
    splat::memoryBarrier(cmd, VK_PIPELINE_STAGE_2_COPY_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT,
                         VK_PIPELINE_STAGE_2_HOST_BIT, VK_ACCESS_2_HOST_READ_BIT);
}

noise::Image WindowGrab::read(bool srgb) const {
    noise::Image image(static_cast<int>(width), static_cast<int>(height));
    const auto* p = static_cast<const std::uint8_t*>(buffer.mapped());
    const bool bgr = format == VK_FORMAT_B8G8R8A8_SRGB || format == VK_FORMAT_B8G8R8A8_UNORM;
    for (std::size_t i = 0; i < image.pixels.size(); ++i) {
        glm::vec3 c(p[4 * i] / 255.0f, p[4 * i + 1] / 255.0f, p[4 * i + 2] / 255.0f);
        if (bgr)
            std::swap(c.x, c.z);
        image.pixels[i] =
            srgb ? glm::vec3(noise::srgbDecode(c.x), noise::srgbDecode(c.y), noise::srgbDecode(c.z))
                 : c;
    }
    return image;
}

bool present(splat::Context& ctx, Swapchain& swapchain, PresentSync& sync,
             const splat::Image& scene, VkExtent2D viewport, VkClearColorValue background,
             WindowGrab* grab, const splat::Image* inset, VkOffset2D insetAt) {
    std::uint32_t index = 0;
    const VkResult acquired =
        vkAcquireNextImageKHR(ctx.device(), swapchain.handle.get(), UINT64_MAX, sync.acquired.get(),
                              VK_NULL_HANDLE, &index);
    if (acquired == VK_ERROR_OUT_OF_DATE_KHR)
        return false;
    if (acquired != VK_SUBOPTIMAL_KHR)
        splat::vkCheck(acquired, "vkAcquireNextImageKHR");
    const VkCommandBuffer cmd = sync.cmd.begin();
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
    viewport.width = std::min(viewport.width, swapchain.extent.width);
    viewport.height = std::min(viewport.height, swapchain.extent.height);
    if (viewport.width < swapchain.extent.width || viewport.height < swapchain.extent.height) {
        // The panels' column (drawn without a background): its colour, then the blits over it.
        const VkImageSubresourceRange all{VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
        vkCmdClearColorImage(cmd, target, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, &background, 1,
                             &all);
        splat::memoryBarrier(cmd, VK_PIPELINE_STAGE_2_ALL_TRANSFER_BIT,
                             VK_ACCESS_2_TRANSFER_WRITE_BIT, VK_PIPELINE_STAGE_2_BLIT_BIT,
                             VK_ACCESS_2_TRANSFER_WRITE_BIT);
    }
    VkImageBlit blit{};
    blit.srcSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
    blit.srcOffsets[1] = {std::int32_t(scene.width()), std::int32_t(scene.height()), 1};
    blit.dstSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
    blit.dstOffsets[1] = {std::int32_t(viewport.width), std::int32_t(viewport.height), 1};
    const bool scaled = scene.width() != viewport.width || scene.height() != viewport.height;
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
        // The kernel preview in the column, at its own size.
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
    rp.renderPass = swapchain.renderPass.get();
    rp.framebuffer = swapchain.framebuffers[index].get();
    rp.renderArea.extent = swapchain.extent;
    vkCmdBeginRenderPass(cmd, &rp, VK_SUBPASS_CONTENTS_INLINE);
    ImGui_ImplVulkan_RenderDrawData(ImGui::GetDrawData(), cmd);
    vkCmdEndRenderPass(cmd);
    if (grab)
        grab->record(ctx, cmd, target, swapchain.extent, swapchain.format.format);
    sync.cmd.submit(sync.acquired.get(), VK_PIPELINE_STAGE_ALL_COMMANDS_BIT,
                    swapchain.renderDone[index].get());
    VkPresentInfoKHR pi{VK_STRUCTURE_TYPE_PRESENT_INFO_KHR};
    pi.waitSemaphoreCount = 1;
    pi.pWaitSemaphores = swapchain.renderDone[index].address();
    pi.swapchainCount = 1;
    pi.pSwapchains = swapchain.handle.address();
    pi.pImageIndices = &index;
    const VkResult presented = vkQueuePresentKHR(ctx.queue(), &pi);
    // One frame in flight: the next frame's renderer writes the image the blit reads.
    sync.cmd.wait();
    if (presented == VK_ERROR_OUT_OF_DATE_KHR || presented == VK_SUBOPTIMAL_KHR)
        return false;
    splat::vkCheck(presented, "vkQueuePresentKHR");
    return true;
}

void UploadedImage::upload(splat::Context& ctx, const noise::Image& pixels, const char* what) {
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

} // namespace spot::editor
