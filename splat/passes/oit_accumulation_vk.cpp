#include "oit_accumulation_vk.h"

#include "shaders/spot_shared.hpp"
#include "splat/pass_vk.h"

namespace spot::splat {

namespace {

using namespace gpu_splat;

constexpr std::uint64_t kFixedBytesPerPixel = kSplatFixedChannels * sizeof(std::uint64_t);

} // namespace

OitAccumulation::OitAccumulation(FrameResources& targets, FrameResources::Wanted fixed) {
    constexpr VkImageUsageFlags kUsage =
        VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_STORAGE_BIT;
    constexpr VkBufferUsageFlags kCleared =
        VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT;
    targets.image(m_accum, "splat OIT accumulation", kColorFormat, kUsage,
                  VK_IMAGE_ASPECT_COLOR_BIT);
    targets.image(m_opticalDepth, "splat OIT optical depth", kScalarFormat, kUsage,
                  VK_IMAGE_ASPECT_COLOR_BIT);
    targets.buffer(
        m_fixed, "splat small kernels' fixed-point OIT sums",
        [](Extent e) { return e.width * e.height * kFixedBytesPerPixel; }, kCleared,
        Buffer::Memory::DeviceLocal, fixed);
    targets.buffer(
        m_tiles, "splat small kernels' tiles with sums",
        [](Extent e) {
            return (e.width + kSplatResolveTile - 1) / kSplatResolveTile *
                   ((e.height + kSplatResolveTile - 1) / kSplatResolveTile) * sizeof(std::uint32_t);
        },
        kCleared, Buffer::Memory::DeviceLocal, fixed);
}

bool OitAccumulation::fixedFits(const Context& ctx, Extent size) {
    return size.width * size.height * kFixedBytesPerPixel <=
           ctx.properties().limits.maxStorageBufferRange;
}

void OitAccumulation::recordClears(VkCommandBuffer cmd, bool small) {
    if (m_fixed.handle() && !m_fixedCleared) { // once: then each resolve clears its sums
        vkCmdFillBuffer(cmd, m_fixed.handle(), 0, VK_WHOLE_SIZE, 0u);
        m_fixedCleared = true;
    }
    if (small) // a uint per 8x8 tile: cheap to clear every frame
        vkCmdFillBuffer(cmd, m_tiles.handle(), 0, VK_WHOLE_SIZE, 0u);
}

void OitAccumulation::beginSplat(VkCommandBuffer cmd, std::uint32_t width, std::uint32_t height,
                                 const Image& depth) {
    using namespace passes;
    for (const Image* image : {&m_accum, &m_opticalDepth})
        transitionImage(cmd, image->handle(), kColorAspect, VK_IMAGE_LAYOUT_UNDEFINED, kAttachment,
                        VK_PIPELINE_STAGE_2_NONE, 0, kColorOut, kColorRW);
    const VkRenderingAttachmentInfo tested = depthAttachment(depth, VK_ATTACHMENT_LOAD_OP_LOAD);
    beginRendering(cmd, width, height,
                   {colorAttachment(m_accum, VK_ATTACHMENT_LOAD_OP_CLEAR, glm::vec4(0.0f)),
                    colorAttachment(m_opticalDepth, VK_ATTACHMENT_LOAD_OP_CLEAR, glm::vec4(0.0f))},
                   &tested);
}

Bindings OitAccumulation::smallBindings() {
    return {storageBuffer(kSplatBindOitFixed), storageBuffer(kSplatBindOitTiles)};
}

void OitAccumulation::smallDescriptors(Descriptors& d) const {
    d.buffer(kSplatBindOitFixed, m_fixed).buffer(kSplatBindOitTiles, m_tiles);
}

Bindings OitAccumulation::resolveBindings(bool fixed) {
    Bindings b = {storageImage(kSplatBindAccum), storageImage(kSplatBindOpticalDepth)};
    if (fixed)
        b.insert(b.end(), {storageBuffer(kSplatBindOitFixed), storageBuffer(kSplatBindOitTiles)});
    return b;
}

void OitAccumulation::resolveDescriptors(Descriptors& d, bool fixed) const {
    using passes::kGeneral;
    d.image(kSplatBindAccum, m_accum, kGeneral, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE)
        .image(kSplatBindOpticalDepth, m_opticalDepth, kGeneral, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE);
    if (fixed)
        smallDescriptors(d);
}

} // namespace spot::splat
