#include "renderer_vk.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <span>
#include <stdexcept>

#include "noise/error.h"
#include "noise/mesh.h"
#include "splat/layout.h"
#include "splat/frame_vk.h"

#include "splat_closest.frag.h"
#include "splat_compact.comp.h"
#include "splat_instanced.frag.h"
#include "splat_oit.frag.h"
#include "splat_prepare.comp.h"
#include "splat_quad.vert.h"
#include "splat_resolve.comp.h"
#include "splat_sorted.frag.h"
#include "splat_roofline.frag.h"
#include "splat_sorted_keys.comp.h"

namespace spot::splat {


namespace {

constexpr VkImageUsageFlags kTargetUsage =
    VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_STORAGE_BIT;

using gpu_splat::SpotMeshVertex;
using gpu_splat::SpotSplatFrame;

/// Bytes per pixel of a frame: base colour, accumulation (RGBA32F), t, optical depth, depth
/// (32-bit), closest kernel (64-bit), result (RGBA32F).
constexpr std::uint64_t kBytesPerPixel = 16 + 16 + 4 + 4 + 4 + 8 + 16;
/// ... and with the hybrid's closest-kernel depth pass: its kernel index and depth (32-bit each).
constexpr std::uint64_t kClosestPassBytesPerPixel = 4 + 4;
constexpr VkFormat kKernelIndexFormat = VK_FORMAT_R32_UINT;
/// Timestamp slots: frame start, then the end of each pass. Every method writes every slot (the
/// sort's end right after the prepare's when there is no sort) and reports its own passes.
constexpr const char* kPassNames[] = {"prepare", "sort", "mesh", "splat", "resolve"};
constexpr std::uint32_t kSortPass = 1;
constexpr std::uint32_t kTimestampCount = 6;
/// prepare.comp runs 64 impulses per workgroup and a dispatch has at most 65,535 workgroups.
constexpr std::uint32_t kMaxImpulses = 65535u * 64u;

} // namespace

const char* methodName(Method method) {
    switch (method) {
    case Method::Instanced:
        return "instanced";
    case Method::Oit:
        return "oit";
    case Method::Hybrid:
        return "hybrid";
    case Method::Sorted:
        return "sorted";
    }
    return "?";
}

SplatRenderer::SplatRenderer(Context& ctx, const noise::Mesh& mesh, const noise::Kernel& kernel)
    : m_ctx(ctx), m_meshPass(ctx, mesh, "splat"), m_sort(ctx), m_timestamps(ctx, kTimestampCount) {
    m_lobes = uploadKernelLobes(ctx, kernel, "splat renderer");
    requireFormat(ctx, kColorFormat,
                  VK_FORMAT_FEATURE_COLOR_ATTACHMENT_BLEND_BIT |
                      VK_FORMAT_FEATURE_STORAGE_IMAGE_BIT,
                  "blended, stored RGBA32F targets");
    requireFormat(ctx, kScalarFormat,
                  VK_FORMAT_FEATURE_COLOR_ATTACHMENT_BLEND_BIT |
                      VK_FORMAT_FEATURE_STORAGE_IMAGE_BIT,
                  "blended, stored R32F targets");
    requireFormat(ctx, kDepthFormat, VK_FORMAT_FEATURE_DEPTH_STENCIL_ATTACHMENT_BIT, "depth");
    requireFormat(ctx, kKernelIndexFormat,
                  VK_FORMAT_FEATURE_COLOR_ATTACHMENT_BIT | VK_FORMAT_FEATURE_STORAGE_IMAGE_BIT,
                  "stored R32_UINT kernel index targets");
    m_lobeCount = std::uint32_t(kernel.lobes.size());
    m_support = kernel.supportSigma;

    const std::uint32_t push = sizeof(SpotSplatFrame);
    auto L = [](std::initializer_list<VkDescriptorType> types) {
        Bindings b;
        for (VkDescriptorType t : types)
            b.push_back({std::uint32_t(b.size()), t});
        return b;
    };
    constexpr VkDescriptorType kBuf = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
    constexpr VkDescriptorType kImg = VK_DESCRIPTOR_TYPE_STORAGE_IMAGE;
    m_prepare =
        makeComputePipeline(ctx, spirv(spv_splat_prepare_comp), L({kBuf, kBuf, kBuf, kBuf}), push);
    m_compact = makeComputePipeline(ctx, spirv(spv_splat_compact_comp), L({kBuf, kBuf, kBuf}), push);
    m_resolve = makeComputePipeline(ctx, spirv(spv_splat_resolve_comp),
                                    L({kImg, kImg, kImg, kImg, kBuf, kBuf, kBuf, kImg}), push);
    // Sort keys: 0 bounds, 1 kept kernels, 2 indirect draw, 3 world lobes, 4 keys.
    m_sortKeys = makeComputePipeline(ctx, spirv(spv_splat_sorted_keys_comp),
                                     L({kBuf, kBuf, kBuf, kBuf, kBuf}), push);

    // Splat pipelines: 0 bounds, 1 kept kernels, 2 world lobes, 3 mesh distance, 4 closest.
    GraphicsPipelineDesc quads;
    quads.vertex = spirv(spv_splat_quad_vert);
    quads.bindings = L({kBuf, kBuf, kBuf, kImg, kBuf});
    quads.pushBytes = push;
    quads.topology = VK_PRIMITIVE_TOPOLOGY_TRIANGLE_STRIP;

    GraphicsPipelineDesc instanced = quads;
    instanced.fragment = spirv(spv_splat_instanced_frag);
    instanced.colorFormats = {kColorFormat};
    instanced.blends = {opaqueBlend()};
    instanced.depthFormat = kDepthFormat;
    instanced.depthTest = true;
    instanced.depthWrite = true;
    instanced.depthCompare = VK_COMPARE_OP_GREATER;
    m_instanced = makeGraphicsPipeline(ctx, instanced);

    GraphicsPipelineDesc oit = quads;
    oit.fragment = spirv(spv_splat_oit_frag);
    oit.colorFormats = {kColorFormat, kScalarFormat};
    oit.blends = {additiveBlend(), additiveBlend()};
    m_oit = makeGraphicsPipeline(ctx, oit);

    GraphicsPipelineDesc sorted = quads;
    sorted.fragment = spirv(spv_splat_sorted_frag);
    sorted.bindings = L({kBuf, kBuf, kBuf, kImg});
    sorted.colorFormats = {kColorFormat};
    sorted.blends = {overBlend()};
    m_sorted = makeGraphicsPipeline(ctx, sorted);

    // The hybrid's closest kernel by a depth pass: nearest distance wins, the first on a tie.
    GraphicsPipelineDesc closest = quads;
    closest.fragment = spirv(spv_splat_closest_frag);
    closest.bindings = L({kBuf, kBuf, kBuf, kImg});
    closest.colorFormats = {kKernelIndexFormat};
    closest.blends = {opaqueBlend()};
    closest.depthFormat = kDepthFormat;
    closest.depthTest = true;
    closest.depthWrite = true;
    closest.depthCompare = VK_COMPARE_OP_LESS;
    m_closest = makeGraphicsPipeline(ctx, closest);

    GraphicsPipelineDesc roofline = oit;
    roofline.fragment = spirv(spv_splat_roofline_frag);
    m_roofline = makeGraphicsPipeline(ctx, roofline);
}

std::uint64_t SplatRenderer::frameBytes(int width, int height, std::uint32_t count,
                                        Method method, ClosestKernel closest) const {
    const std::uint64_t closestBytes =
        method == Method::Hybrid && closest == ClosestKernel::DepthPass
            ? std::uint64_t(width) * std::uint64_t(height) * kClosestPassBytesPerPixel
            : 8;
    const std::uint64_t sortBytes =
        method == Method::Sorted
            ? std::max<std::uint64_t>(std::uint64_t(count) * sizeof(std::uint32_t), 16) +
                  RadixSortScratch::bytes(count)
            : 0;
    return std::uint64_t(width) * std::uint64_t(height) * kBytesPerPixel +
           std::uint64_t(count) * (std::uint64_t(m_lobeCount) * sizeof(gpu::SpotWorldLobe) +
                                   sizeof(gpu::SpotKernelBound) + sizeof(std::uint32_t)) +
           16 + sortBytes + closestBytes;
}

noise::Image SplatRenderer::render(const noise::Camera& camera, const noise::Shading& shading,
                                   glm::vec3 background, glm::vec3 baseColor,
                                   const Buffer& impulses, std::uint32_t count,
                                   const SplatSettings& settings, FrameStats* stats) {
    static_cast<void>(noise::CameraRays(camera)); // validates the camera first (InputError)
    if (settings.kernelSamples < 0 ||
        settings.kernelSamples > int(gpu_splat::kSplatMaxKernelSamples))
        throw InputError(cat("splat renderer: kernel samples ", settings.kernelSamples,
                             " outside [0, ", gpu_splat::kSplatMaxKernelSamples,
                             "] (0 = analytic; more would exceed lavapipe's loop budget)"));
    if (count > kMaxImpulses)
        throw InputError(cat("splat renderer: ", count, " impulses, more than the ", kMaxImpulses,
                             " one frame can prepare"));
    if (std::uint64_t(count) * sizeof(gpu::SpotImpulse) > impulses.size() || !impulses.handle())
        throw InputError(cat("splat renderer: the impulse buffer holds ", impulses.size(),
                             " bytes, ", count, " impulses need ",
                             std::uint64_t(count) * sizeof(gpu::SpotImpulse)));
    const std::uint32_t width = std::uint32_t(camera.width), height = std::uint32_t(camera.height);
    const std::uint64_t need =
        frameBytes(camera.width, camera.height, count, settings.method, settings.closest);
    if (m_ctx.allocatedBytes() + need > m_ctx.memoryBudget())
        throw InputError(cat("splat renderer: a ", width, "x", height, " frame of ", count,
                             " kernels needs ", need >> 20, " MiB of GPU memory; ",
                             m_ctx.allocatedBytes() >> 20, " MiB are in use and the budget is ",
                             m_ctx.memoryBudget() >> 20,
                             " MiB; reduce the image size or the kernel count"));

    // The frame's constants (the camera basis exactly as noise::CameraRays builds it).
    std::uint32_t flags = 0;
    if (settings.ewa)
        flags |= gpu_splat::kSplatFlagEwa;
    if (settings.weight == OitWeight::McGuireBavoil)
        flags |= gpu_splat::kSplatFlagMcGuireBavoil;
    if (settings.method == Method::Hybrid)
        flags |= gpu_splat::kSplatFlagHybrid;
    if (settings.method == Method::Instanced)
        flags |= gpu_splat::kSplatFlagInstanced;
    const bool closestPass = settings.method == Method::Hybrid &&
                             settings.closest == ClosestKernel::DepthPass && !settings.roofline;
    if (closestPass)
        flags |= gpu_splat::kSplatFlagClosestPass;
    const SpotSplatFrame frame =
        makeSplatFrame(camera, shading, baseColor, count, m_lobeCount, m_support,
                       std::uint32_t(settings.kernelSamples), flags);

    // Per-frame resources (the budget was checked above; each allocation checks again).
    const std::uint64_t lobeCount = std::uint64_t(count) * m_lobeCount;
    Buffer worldLobes(m_ctx, lobeCount * sizeof(gpu::SpotWorldLobe),
                      VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, Buffer::Memory::DeviceLocal,
                      cat("splat world lobes (", count, " kernels)"));
    Buffer bounds(m_ctx, std::uint64_t(count) * sizeof(gpu::SpotKernelBound),
                  VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, Buffer::Memory::DeviceLocal,
                  "splat kernel bounds");
    Buffer kept(m_ctx, std::uint64_t(count) * sizeof(std::uint32_t),
                VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, Buffer::Memory::DeviceLocal,
                "splat kept kernels");
    Buffer draw(m_ctx, sizeof(VkDrawIndirectCommand),
                VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_INDIRECT_BUFFER_BIT,
                Buffer::Memory::HostVisible, "splat indirect draw");
    const std::uint64_t pixels = std::uint64_t(width) * height;
    Buffer closest(m_ctx, pixels * sizeof(std::uint64_t),
                   VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                   Buffer::Memory::DeviceLocal, "splat closest kernels");
    Buffer result(m_ctx, pixels * sizeof(glm::vec4), VK_BUFFER_USAGE_STORAGE_BUFFER_BIT,
                  Buffer::Memory::HostVisible, "splat result");
    Image base(m_ctx, width, height, kColorFormat, kTargetUsage, VK_IMAGE_ASPECT_COLOR_BIT,
               "splat base colour");
    Image distance(m_ctx, width, height, kScalarFormat, kTargetUsage, VK_IMAGE_ASPECT_COLOR_BIT,
                   "splat mesh distance");
    Image depth(m_ctx, width, height, kDepthFormat, VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT,
                VK_IMAGE_ASPECT_DEPTH_BIT, "splat depth");
    Image accum(m_ctx, width, height, kColorFormat, kTargetUsage, VK_IMAGE_ASPECT_COLOR_BIT,
                "splat OIT accumulation");
    Image opticalDepth(m_ctx, width, height, kScalarFormat, kTargetUsage, VK_IMAGE_ASPECT_COLOR_BIT,
                       "splat OIT optical depth");
    // The depth pass's kernel index and depth (1x1, never read, without the depth pass).
    const std::uint32_t closestWidth = closestPass ? width : 1;
    const std::uint32_t closestHeight = closestPass ? height : 1;
    Image closestKernel(m_ctx, closestWidth, closestHeight, kKernelIndexFormat, kTargetUsage,
                        VK_IMAGE_ASPECT_COLOR_BIT, "splat closest kernel index");
    Image closestDepth(m_ctx, closestWidth, closestHeight, kDepthFormat,
                       VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT, VK_IMAGE_ASPECT_DEPTH_BIT,
                       "splat closest kernel depth");
    // Sorted: the kept kernels' keys, sorted with the kept list itself as the values.
    const bool sorted = settings.method == Method::Sorted && !settings.roofline;
    Buffer sortKeys;
    RadixSortScratch sortScratch;
    if (sorted) {
        sortKeys = Buffer(m_ctx, std::uint64_t(count) * sizeof(std::uint32_t),
                          VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, Buffer::Memory::DeviceLocal,
                          "splat sort keys");
        sortScratch = RadixSortScratch(m_ctx, count);
    }
    // The resolve of `sorted` takes the base colour image as the result, as for `instanced`:
    // the kernels were blended onto it.
    SpotSplatFrame resolveFrame = frame;
    if (sorted)
        resolveFrame.counts.w |= gpu_splat::kSplatFlagInstanced;

    using namespace passes;

    const bool instanced = settings.method == Method::Instanced && !settings.roofline;
    m_ctx.submitAndWait([&](VkCommandBuffer cmd) {
        m_timestamps.reset(cmd);
        m_timestamps.write(cmd, 0, kAll);

        // 1. Prepare: world lobes and bounds, then the kept kernels in order and the draw.
        if (count > 0) {
            recordPrepare(m_ctx, cmd, m_prepare, frame, impulses, m_lobes, worldLobes, bounds, count);
            memoryBarrier(cmd, kCompute, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT, kCompute,
                          kStorageRead);
        }
        vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, m_compact.handle());
        pushFrame(cmd, m_compact, frame);
        Descriptors().buffer(0, bounds).buffer(1, kept).buffer(2, draw).push(m_ctx, cmd, m_compact);
        vkCmdDispatch(cmd, 1, 1, 1);
        vkCmdFillBuffer(cmd, closest.handle(), 0, VK_WHOLE_SIZE, 0xffffffffu); // "no kernel"
        memoryBarrier(cmd, kCompute | VK_PIPELINE_STAGE_2_CLEAR_BIT,
                      VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT | VK_ACCESS_2_TRANSFER_WRITE_BIT,
                      VK_PIPELINE_STAGE_2_DRAW_INDIRECT_BIT |
                          VK_PIPELINE_STAGE_2_VERTEX_SHADER_BIT | kFragment | kCompute,
                      VK_ACCESS_2_INDIRECT_COMMAND_READ_BIT | kStorageRW);
        m_timestamps.write(cmd, 1, kAll);

        // 1b. Sorted: the kept kernels back to front (the padding past the kept count last).
        if (sorted && count > 0) {
            vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, m_sortKeys.handle());
            pushFrame(cmd, m_sortKeys, frame);
            Descriptors()
                .buffer(0, bounds)
                .buffer(1, kept)
                .buffer(2, draw)
                .buffer(3, worldLobes)
                .buffer(4, sortKeys)
                .push(m_ctx, cmd, m_sortKeys);
            vkCmdDispatch(cmd, (count + 63) / 64, 1, 1);
            memoryBarrier(cmd, kCompute, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT, kCompute,
                          kStorageRW);
            m_sort.record(cmd, sortKeys, kept, count, sortScratch);
        }
        m_timestamps.write(cmd, 2, kAll);

        // 2. The base mesh.
        for (const Image* image : {&base, &distance, &accum, &opticalDepth})
            transitionImage(cmd, image->handle(), kColorAspect, VK_IMAGE_LAYOUT_UNDEFINED,
                            kAttachment, VK_PIPELINE_STAGE_2_NONE, 0, kColorOut, kColorRW);
        transitionImage(cmd, depth.handle(), VK_IMAGE_ASPECT_DEPTH_BIT, VK_IMAGE_LAYOUT_UNDEFINED,
                        VK_IMAGE_LAYOUT_DEPTH_ATTACHMENT_OPTIMAL, VK_PIPELINE_STAGE_2_NONE, 0,
                        kTests, kDepthRW);
        m_meshPass.record(cmd, frame, base, distance, depth, background);
        transitionImage(cmd, distance.handle(), kColorAspect, kAttachment, kGeneral, kColorOut,
                        VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT, kFragment | kCompute, kStorageRead);
        // Base colour and depth stay attachments: the instanced pass draws over them.
        transitionImage(cmd, base.handle(), kColorAspect, kAttachment, kAttachment, kColorOut,
                        VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT, kColorOut, kColorRW);
        transitionImage(cmd, depth.handle(), VK_IMAGE_ASPECT_DEPTH_BIT,
                        VK_IMAGE_LAYOUT_DEPTH_ATTACHMENT_OPTIMAL,
                        VK_IMAGE_LAYOUT_DEPTH_ATTACHMENT_OPTIMAL, kTests,
                        VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT, kTests, kDepthRW);
        m_timestamps.write(cmd, 3, kAll);

        // 3a. Hybrid with a depth pass: each pixel's closest kernel (index, depth test LESS).
        transitionImage(cmd, closestKernel.handle(), kColorAspect, VK_IMAGE_LAYOUT_UNDEFINED,
                        kAttachment, VK_PIPELINE_STAGE_2_NONE, 0, kColorOut, kColorRW);
        if (closestPass) {
            transitionImage(cmd, closestDepth.handle(), VK_IMAGE_ASPECT_DEPTH_BIT,
                            VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_DEPTH_ATTACHMENT_OPTIMAL,
                            VK_PIPELINE_STAGE_2_NONE, 0, kTests, kDepthRW);
            VkRenderingAttachmentInfo index = colorAttachment(closestKernel, VK_ATTACHMENT_LOAD_OP_CLEAR);
            index.clearValue.color.uint32[0] = 0xffffffffu; // no kernel
            VkRenderingAttachmentInfo nearest = depthAttachment(closestDepth, VK_ATTACHMENT_LOAD_OP_CLEAR);
            nearest.storeOp = VK_ATTACHMENT_STORE_OP_DONT_CARE;
            nearest.clearValue.depthStencil = {1.0f, 0};
            beginRendering(cmd, width, height, {index}, &nearest);
            vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, m_closest.handle());
            pushFrame(cmd, m_closest, frame);
            Descriptors()
                .buffer(0, bounds)
                .buffer(1, kept)
                .buffer(2, worldLobes)
                .image(3, distance, kGeneral, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE)
                .push(m_ctx, cmd, m_closest);
            vkCmdDrawIndirect(cmd, draw.handle(), 0, 1, sizeof(VkDrawIndirectCommand));
            vkCmdEndRendering(cmd);
        }
        transitionImage(cmd, closestKernel.handle(), kColorAspect, kAttachment, kGeneral, kColorOut,
                        VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT, kCompute, kStorageRead);

        // 3. The kernels: one quad each, drawn in impulse order (`sorted`: back to front).
        const Pipeline& splat = settings.roofline ? m_roofline
                                : instanced        ? m_instanced
                                : sorted           ? m_sorted
                                                   : m_oit;
        const VkRenderingAttachmentInfo depthInfo =
            depthAttachment(depth, VK_ATTACHMENT_LOAD_OP_LOAD);
        if (instanced)
            beginRendering(cmd, width, height, {colorAttachment(base, VK_ATTACHMENT_LOAD_OP_LOAD)},
                           &depthInfo);
        else if (sorted)
            beginRendering(cmd, width, height, {colorAttachment(base, VK_ATTACHMENT_LOAD_OP_LOAD)},
                           nullptr);
        else
            beginRendering(
                cmd, width, height,
                {colorAttachment(accum, VK_ATTACHMENT_LOAD_OP_CLEAR, glm::vec4(0.0f)),
                 colorAttachment(opticalDepth, VK_ATTACHMENT_LOAD_OP_CLEAR, glm::vec4(0.0f))},
                nullptr);
        vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, splat.handle());
        pushFrame(cmd, splat, frame);
        Descriptors quadDescriptors;
        quadDescriptors.buffer(0, bounds)
            .buffer(1, kept)
            .buffer(2, worldLobes)
            .image(3, distance, kGeneral, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE);
        if (!sorted)
            quadDescriptors.buffer(4, closest);
        quadDescriptors.push(m_ctx, cmd, splat);
        vkCmdDrawIndirect(cmd, draw.handle(), 0, 1, sizeof(VkDrawIndirectCommand));
        vkCmdEndRendering(cmd);
        for (const Image* image : {&base, &accum, &opticalDepth})
            transitionImage(cmd, image->handle(), kColorAspect, kAttachment, kGeneral, kColorOut,
                            VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT, kCompute, kStorageRead);
        memoryBarrier(cmd, kFragment, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT, kCompute, kStorageRead);
        m_timestamps.write(cmd, 4, kAll);

        // 4. Resolve into the readback buffer.
        vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, m_resolve.handle());
        pushFrame(cmd, m_resolve, resolveFrame);
        Descriptors()
            .image(0, base, kGeneral, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE)
            .image(1, accum, kGeneral, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE)
            .image(2, opticalDepth, kGeneral, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE)
            .image(3, distance, kGeneral, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE)
            .buffer(4, closest)
            .buffer(5, worldLobes)
            .buffer(6, result)
            .image(7, closestKernel, kGeneral, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE)
            .push(m_ctx, cmd, m_resolve);
        vkCmdDispatch(cmd, (width + 7) / 8, (height + 7) / 8, 1);
        memoryBarrier(cmd, kCompute, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT,
                      VK_PIPELINE_STAGE_2_HOST_BIT, VK_ACCESS_2_HOST_READ_BIT);
        m_timestamps.write(cmd, 5, kAll);
    });

    noise::Image image(camera.width, camera.height);
    const auto* rgba = static_cast<const glm::vec4*>(result.mapped());
    for (std::size_t i = 0; i < image.pixels.size(); ++i)
        image.pixels[i] = glm::vec3(rgba[i]);
    if (stats) {
        const std::vector<double> ms = m_timestamps.milliseconds();
        stats->passMs.clear();
        // Pass p runs from slot p to slot p + 1. Without a sort, its empty span counts towards the
        // prepare, so the passes always sum to the total.
        for (std::uint32_t p = 0; p + 1 < kTimestampCount; ++p) {
            if (p == kSortPass && !sorted)
                continue;
            const std::uint32_t end = p + 1 == kSortPass && !sorted ? p + 2 : p + 1;
            stats->passMs.emplace_back(kPassNames[p], ms[end] - ms[p]);
        }
        stats->totalMs = ms[kTimestampCount - 1];
        VkDrawIndirectCommand command;
        std::memcpy(&command, draw.mapped(), sizeof(command));
        stats->kernelsDrawn = command.instanceCount;
        stats->gpuMemoryBytes = m_ctx.peakAllocatedBytes();
    }
    return image;
}

} // namespace spot::splat
