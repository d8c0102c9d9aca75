#include "pass_vk.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "noise/error.h"
#include "noise/mesh.h"
#include "splat/layout.h"

#include "splat/passes/light_space_vk.h"
#include "splat_mesh.frag.h"
#include "splat_mesh.vert.h"
#include "splat_mesh_lit.frag.h"
#include "splat_mesh_lit.vert.h"
#include "splat_prepare.comp.h"
#include "splat_prepare_lit.comp.h"

namespace spot::splat {

gpu_splat::SpotSplatFrame makeSplatFrame(const noise::Camera& camera, const noise::Shading& shading,
                                         glm::vec3 baseColor, std::uint32_t count,
                                         std::uint32_t lobes, float support,
                                         std::uint32_t kernelSamples, std::uint32_t flags) {
    const noise::CameraRays rays(camera); // validates the camera; the one camera basis
    const glm::dvec3 forward = rays.forward(), right = rays.right(), up = rays.up();
    const bool ortho = camera.projection == noise::Projection::Orthographic;
    const double halfHeight = rays.halfHeight(), halfWidth = rays.halfWidth();
    if (shading.mode == noise::Shading::Mode::Lambert)
        flags |= gpu_splat::kSplatFlagLambert;
    gpu_splat::SpotSplatFrame frame{};
    frame.eye = glm::vec4(glm::vec3(camera.eye), ortho ? 1.0f : 0.0f);
    frame.forward = glm::vec4(glm::vec3(forward), kNearPlane);
    frame.right = glm::vec4(glm::vec3(right), float(halfWidth));
    frame.up = glm::vec4(glm::vec3(up), float(halfHeight));
    frame.size = glm::vec4(float(camera.width), float(camera.height),
                           float(rays.pixelFootprint(1.0)), support);
    frame.counts = glm::uvec4(count, lobes, kernelSamples, flags);
    frame.light = glm::vec4(shading.lightDir, shading.ambient);
    frame.base = glm::vec4(baseColor, 0.0f);
    return frame;
}

void MeshPass::keepRest() {
    if (m_rest.handle() || m_vertices.size() == 0)
        return;
    m_rest = Buffer(*m_ctx, m_vertices.size(), VK_BUFFER_USAGE_STORAGE_BUFFER_BIT,
                    Buffer::Memory::HostVisible, "mesh vertices at rest");
    m_rest.upload(m_vertices.mapped(), m_vertices.size());
}

MeshPass::MeshPass(Context& ctx, const noise::Mesh& mesh, const char* who) : m_ctx(&ctx) {
    std::vector<gpu_splat::SpotMeshVertex> vertices(mesh.positions.size());
    for (std::size_t i = 0; i < vertices.size(); ++i) {
        vertices[i].position = glm::vec4(mesh.positions[i], 1.0f);
        vertices[i].normal =
            glm::vec4(i < mesh.normals.size() ? mesh.normals[i] : glm::vec3(0.0f), 0.0f);
    }
    m_vertices = Buffer(ctx, vertices.size() * sizeof(gpu_splat::SpotMeshVertex),
                        VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, Buffer::Memory::HostVisible,
                        cat(who, " mesh vertices (", mesh.name, ")"));
    if (!vertices.empty())
        m_vertices.upload(std::span<const gpu_splat::SpotMeshVertex>(vertices));
    // The welded triangles (noise::Mesh::weld): the shell, the posed normals and the shadow
    // rays read these indices, so that triangles meet at one vertex across uv and normal seams.
    // Welded copies have equal positions and normals, so the mesh draws the same.
    const std::vector<glm::uvec3> triangles = mesh.weldedTriangles();
    m_indexCount = std::uint32_t(triangles.size() * 3);
    m_indices = Buffer(ctx, triangles.size() * sizeof(glm::uvec3),
                       VK_BUFFER_USAGE_INDEX_BUFFER_BIT | VK_BUFFER_USAGE_STORAGE_BUFFER_BIT,
                       Buffer::Memory::HostVisible, cat(who, " mesh indices (", mesh.name, ")"));
    if (!triangles.empty())
        m_indices.upload(std::span<const glm::uvec3>(triangles));

    GraphicsPipelineDesc desc;
    desc.vertex = spirv(spv_splat_mesh_vert);
    desc.fragment = spirv(spv_splat_mesh_frag);
    desc.bindings = {storageBuffer(gpu_splat::kSplatBindVertices)};
    desc.pushBytes = sizeof(gpu_splat::SpotSplatFrame);
    desc.colorFormats = {kColorFormat, kScalarFormat};
    desc.blends = {opaqueBlend(), opaqueBlend()};
    desc.depthFormat = kDepthFormat;
    desc.depthTest = true;
    desc.depthWrite = true;
    desc.depthCompare = VK_COMPARE_OP_GREATER;
    m_desc = desc; // its pipelines are made at the first frame that draws them (pipeline())
    // The test sorts 3 edges of 8 bytes per triangle: above 2 million triangles (48 MB, about
    // half a second) the pass draws both faces rather than spend that at every start.
    constexpr std::size_t kMaxTestedTriangles = 2'000'000;
    m_closed = mesh.triangles.size() <= kMaxTestedTriangles && noise::closedOutward(mesh);
    {
        const noise::Bounds b = mesh.bounds();
        m_lo = b.lo;
        m_hi = b.hi;
    }
}

const Pipeline& MeshPass::pipeline(bool lit, bool culled) const {
    Pipeline& p = m_pipelines[(lit ? 2 : 0) + (culled ? 1 : 0)];
    if (p.layout())
        return p;
    GraphicsPipelineDesc desc = m_desc;
    if (lit) {
        desc.vertex = spirv(spv_splat_mesh_lit_vert);
        desc.fragment = spirv(spv_splat_mesh_lit_frag);
        const Bindings lookup = LightSpace::lookupBindings();
        desc.bindings.insert(desc.bindings.end(), lookup.begin(), lookup.end());
    }
    // Counter-clockwise seen from outside stays so in the framebuffer: the vertex shader flips
    // y, so that NDC y points down, as framebuffer rows do.
    if (culled)
        desc.cull = VK_CULL_MODE_BACK_BIT;
    p = makeGraphicsPipeline(*m_ctx, desc);
    return p;
}

bool MeshPass::cullsBackFaces(const gpu_splat::SpotSplatFrame& frame) const {
    if (!m_closed)
        return false;
    const glm::vec3 eye(frame.eye), forward(frame.forward);
    for (int c = 0; c < 8; ++c) {
        const glm::vec3 corner((c & 1) ? m_hi.x : m_lo.x, (c & 2) ? m_hi.y : m_lo.y,
                               (c & 4) ? m_hi.z : m_lo.z);
        // The near plane for both projections (orthographic rays start at view depth 0).
        if (!(glm::dot(corner - eye, forward) > frame.forward.w))
            return false;
    }
    return true;
}

void MeshPass::record(VkCommandBuffer cmd, const gpu_splat::SpotSplatFrame& frame,
                      const Image& base, const Image& distance, const Image& depth,
                      glm::vec3 background,
                      const std::function<void(VkCommandBuffer)>& after,
                      const LightSpace* light) const {
    const VkRenderingAttachmentInfo depthInfo = depthAttachment(depth, VK_ATTACHMENT_LOAD_OP_CLEAR);
    beginRendering(cmd, base.width(), base.height(),
                   {colorAttachment(base, VK_ATTACHMENT_LOAD_OP_CLEAR, glm::vec4(background, 0.0f)),
                    colorAttachment(distance, VK_ATTACHMENT_LOAD_OP_CLEAR,
                                    glm::vec4(gpu_splat::kSplatNoMesh))},
                   &depthInfo);
    if (m_indexCount > 0) {
        const Pipeline& pipeline = this->pipeline(light != nullptr, cullsBackFaces(frame));
        vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, pipeline.handle());
        pushFrame(cmd, pipeline, frame);
        Descriptors d;
        d.buffer(gpu_splat::kSplatBindVertices, m_vertices);
        if (light)
            light->bindLookup(d);
        d.push(*m_ctx, cmd, pipeline);
        vkCmdBindIndexBuffer(cmd, m_indices.handle(), 0, VK_INDEX_TYPE_UINT32);
        vkCmdDrawIndexed(cmd, m_indexCount, 1, 0, 0, 0);
    }
    if (after)
        after(cmd);
    vkCmdEndRendering(cmd);
}

Buffer uploadKernelLobes(Context& ctx, const noise::Kernel& kernel, const char* who) {
    if (kernel.lobes.empty() || kernel.lobes.size() > 8)
        throw InputError(cat(who, ": a kernel needs 1 to 8 lobes, this one has ", kernel.lobes.size()));
    if (!(kernel.supportSigma > 0.0f) || !std::isfinite(kernel.supportSigma))
        throw InputError(cat(who, ": support ", kernel.supportSigma, " sigmas must be positive"));
    const std::vector<gpu::SpotLobe> lobes = gpu::toGpu(kernel);
    Buffer b(ctx, lobes.size() * sizeof(gpu::SpotLobe), VK_BUFFER_USAGE_STORAGE_BUFFER_BIT,
             Buffer::Memory::HostVisible, cat(who, " kernel lobes"));
    b.upload(std::span<const gpu::SpotLobe>(lobes));
    return b;
}

void requireFormat(Context& ctx, VkFormat format, VkFormatFeatureFlags features, const char* what) {
    VkFormatProperties props;
    vkGetPhysicalDeviceFormatProperties(ctx.physicalDevice(), format, &props);
    if ((props.optimalTilingFeatures & features) != features)
        throw std::runtime_error(cat("Vulkan: device ", ctx.deviceName(), " cannot use format ",
                                     int(format), " for ", what));
}

VkPipelineColorBlendAttachmentState opaqueBlend() {
    VkPipelineColorBlendAttachmentState b{};
    b.colorWriteMask = VK_COLOR_COMPONENT_R_BIT | VK_COLOR_COMPONENT_G_BIT |
                       VK_COLOR_COMPONENT_B_BIT | VK_COLOR_COMPONENT_A_BIT;
    return b;
}

/// dst = src + dst: MB13's weighted sums, and the optical-depth sum that stands for its revealage
/// (exp(-sum tau) = prod (1 - alpha); see splat_oit.frag). One blend state for both targets:
/// the context does not enable independentBlend.
VkPipelineColorBlendAttachmentState additiveBlend() {
    VkPipelineColorBlendAttachmentState b = opaqueBlend();
    b.blendEnable = VK_TRUE;
    b.srcColorBlendFactor = VK_BLEND_FACTOR_ONE;
    b.dstColorBlendFactor = VK_BLEND_FACTOR_ONE;
    b.colorBlendOp = VK_BLEND_OP_ADD;
    b.srcAlphaBlendFactor = VK_BLEND_FACTOR_ONE;
    b.dstAlphaBlendFactor = VK_BLEND_FACTOR_ONE;
    b.alphaBlendOp = VK_BLEND_OP_ADD;
    return b;
}

/// Premultiplied "over": dst = src + (1 - src.a) dst (the sorted method, back to front).
VkPipelineColorBlendAttachmentState overBlend() {
    VkPipelineColorBlendAttachmentState b = opaqueBlend();
    b.blendEnable = VK_TRUE;
    b.srcColorBlendFactor = VK_BLEND_FACTOR_ONE;
    b.dstColorBlendFactor = VK_BLEND_FACTOR_ONE_MINUS_SRC_ALPHA;
    b.colorBlendOp = VK_BLEND_OP_ADD;
    b.srcAlphaBlendFactor = VK_BLEND_FACTOR_ONE;
    b.dstAlphaBlendFactor = VK_BLEND_FACTOR_ONE_MINUS_SRC_ALPHA;
    b.alphaBlendOp = VK_BLEND_OP_ADD;
    return b;
}

VkRenderingAttachmentInfo colorAttachment(const Image& image, VkAttachmentLoadOp load,
                                          glm::vec4 clear) {
    VkRenderingAttachmentInfo a{VK_STRUCTURE_TYPE_RENDERING_ATTACHMENT_INFO};
    a.imageView = image.view();
    a.imageLayout = VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL;
    a.loadOp = load;
    a.storeOp = VK_ATTACHMENT_STORE_OP_STORE;
    a.clearValue.color = {{clear.r, clear.g, clear.b, clear.a}};
    return a;
}

VkRenderingAttachmentInfo depthAttachment(const Image& image, VkAttachmentLoadOp load) {
    VkRenderingAttachmentInfo a{VK_STRUCTURE_TYPE_RENDERING_ATTACHMENT_INFO};
    a.imageView = image.view();
    a.imageLayout = VK_IMAGE_LAYOUT_DEPTH_ATTACHMENT_OPTIMAL;
    a.loadOp = load;
    a.storeOp = VK_ATTACHMENT_STORE_OP_STORE;
    a.clearValue.depthStencil = {0.0f, 0}; // reversed depth: 0 is infinitely far
    return a;
}

namespace {
/// PixelScissor's window and the size it applies to (empty: none).
thread_local noise::PixelRect t_scissor;
thread_local std::uint32_t t_scissorWidth = 0, t_scissorHeight = 0;
} // namespace

PixelScissor::PixelScissor(noise::PixelRect window, std::uint32_t fullWidth,
                           std::uint32_t fullHeight)
    : m_previous(t_scissor), m_previousWidth(t_scissorWidth), m_previousHeight(t_scissorHeight) {
    t_scissor = window;
    t_scissorWidth = fullWidth;
    t_scissorHeight = fullHeight;
}

PixelScissor::~PixelScissor() {
    t_scissor = m_previous;
    t_scissorWidth = m_previousWidth;
    t_scissorHeight = m_previousHeight;
}

void dispatchPixels(VkCommandBuffer cmd, std::uint32_t width, std::uint32_t height,
                    std::uint32_t group, std::uint32_t scale) {
    std::uint32_t x0 = 0, y0 = 0, x1 = (width + group - 1) / group,
                  y1 = (height + group - 1) / group;
    if (!t_scissor.empty() && width == t_scissorWidth * scale &&
        height == t_scissorHeight * scale) {
        x0 = std::uint32_t(t_scissor.x0) * scale / group;
        y0 = std::uint32_t(t_scissor.y0) * scale / group;
        x1 = (std::uint32_t(t_scissor.x1) * scale + group - 1) / group;
        y1 = (std::uint32_t(t_scissor.y1) * scale + group - 1) / group;
    }
    if (x0 == 0 && y0 == 0)
        vkCmdDispatch(cmd, x1, y1, 1);
    else
        vkCmdDispatchBase(cmd, x0, y0, 0, x1 - x0, y1 - y0, 1);
}

void beginRendering(VkCommandBuffer cmd, std::uint32_t width, std::uint32_t height,
                    const std::vector<VkRenderingAttachmentInfo>& colors,
                    const VkRenderingAttachmentInfo* depth) {
    VkRenderingInfo info{VK_STRUCTURE_TYPE_RENDERING_INFO};
    info.renderArea = {{0, 0}, {width, height}};
    info.layerCount = 1;
    info.colorAttachmentCount = std::uint32_t(colors.size());
    info.pColorAttachments = colors.data();
    info.pDepthAttachment = depth;
    vkCmdBeginRendering(cmd, &info);
    const VkViewport viewport{0.0f, 0.0f, float(width), float(height), 0.0f, 1.0f};
    VkRect2D scissor{{0, 0}, {width, height}};
    if (!t_scissor.empty() && width == t_scissorWidth && height == t_scissorHeight)
        scissor = {{t_scissor.x0, t_scissor.y0},
                   {std::uint32_t(t_scissor.width()), std::uint32_t(t_scissor.height())}};
    vkCmdSetViewport(cmd, 0, 1, &viewport);
    vkCmdSetScissor(cmd, 0, 1, &scissor);
}

void pushFrame(VkCommandBuffer cmd, const Pipeline& pipeline, const gpu_splat::SpotSplatFrame& frame) {
    const VkShaderStageFlags stages =
        pipeline.bindPoint() == VK_PIPELINE_BIND_POINT_COMPUTE
            ? VK_SHADER_STAGE_COMPUTE_BIT
            : VK_SHADER_STAGE_VERTEX_BIT | VK_SHADER_STAGE_FRAGMENT_BIT;
    vkCmdPushConstants(cmd, pipeline.layout(), stages, 0, sizeof(frame), &frame);
}

void recordListReset(VkCommandBuffer cmd, const Buffer& list) {
    using namespace passes;
    memoryBarrier(cmd, kCompute | VK_PIPELINE_STAGE_2_DRAW_INDIRECT_BIT,
                  kStorageRW | VK_ACCESS_2_INDIRECT_COMMAND_READ_BIT, kTransfer,
                  VK_ACCESS_2_TRANSFER_WRITE_BIT);
    const gpu_splat::SpotSplatList empty{0u, 1u, 1u, 0u};
    vkCmdUpdateBuffer(cmd, list.handle(), 0, sizeof(empty), &empty);
    memoryBarrier(cmd, kTransfer, VK_ACCESS_2_TRANSFER_WRITE_BIT, kCompute, kStorageRW);
}

Pipeline makePreparePipeline(Context& ctx, std::uint32_t lobes, bool screen, bool ewa,
                             bool orthographic, bool worldLobes, bool clipped, bool lit) {
    using namespace gpu_splat;
    Specialization spec;
    spec.set(kSplatSpecLobes, lobes)
        .set(kSplatSpecScreen, screen)
        .set(kSplatSpecEwa, ewa)
        .set(kSplatSpecOrthographic, orthographic)
        .set(kSplatSpecWorldLobes, worldLobes || !screen)
        .set(kSplatSpecClipped, clipped && screen);
    Bindings bindings = {storageBuffer(kSplatBindImpulses),    storageBuffer(kSplatBindLobes),
                         storageBuffer(kSplatBindWorldLobes),  storageBuffer(kSplatBindScreenLobes),
                         storageBuffer(kSplatBindBounds),      storageBuffer(kSplatBindCount),
                         storageBuffer(kSplatBindClipList)};
    if (lit) {
        const Bindings lookup = LightSpace::lookupBindings();
        bindings.insert(bindings.end(), lookup.begin(), lookup.end());
    }
    return makeComputePipeline(
        ctx, lit ? spirv(spv_splat_prepare_lit_comp) : spirv(spv_splat_prepare_comp), bindings,
        sizeof(SpotSplatFrame), spec);
}

void recordPrepare(Context& ctx, VkCommandBuffer cmd, const Pipeline& prepare,
                   const gpu_splat::SpotSplatFrame& frame, const PrepareBuffers& b,
                   std::uint32_t capacity) {
    if (capacity == 0)
        return;
    using namespace gpu_splat;
    using namespace passes;
    const bool clip = b.clipList && b.clipped;
    if (clip)
        recordListReset(cmd, *b.clipList);
    Descriptors descriptors;
    descriptors.buffer(kSplatBindImpulses, *b.impulses)
        .buffer(kSplatBindCount, *b.count)
        .buffer(kSplatBindLobes, *b.lobes)
        .buffer(kSplatBindWorldLobes, *b.worldLobes)
        .buffer(kSplatBindScreenLobes, *b.screenLobes)
        .buffer(kSplatBindBounds, *b.bounds)
        .buffer(kSplatBindClipList, clip ? *b.clipList : *b.bounds); // unread without `screen`
    if (b.light)
        b.light->bindLookup(descriptors);
    vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, prepare.handle());
    pushFrame(cmd, prepare, frame);
    descriptors.push(ctx, cmd, prepare);
    vkCmdDispatch(cmd, (capacity + 63) / 64, 1, 1);
    if (!clip)
        return;
    memoryBarrier(cmd, kCompute, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT,
                  kCompute | VK_PIPELINE_STAGE_2_DRAW_INDIRECT_BIT,
                  kStorageRW | VK_ACCESS_2_INDIRECT_COMMAND_READ_BIT);
    vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, b.clipped->handle());
    pushFrame(cmd, *b.clipped, frame);
    descriptors.push(ctx, cmd, *b.clipped);
    vkCmdDispatchIndirect(cmd, b.clipList->handle(), 0);
}

} // namespace spot::splat
