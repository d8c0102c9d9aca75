#include "splatting_vk.h"

#include <algorithm>
#include <array>
#include <cstring>

#include "noise/error.h"
#include "shaders/spot_shared.hpp"
#include "splat/layout.h"

#include "splat_compact.comp.h"
#include "splat_compact_small.comp.h"
#include "splat_quad.vert.h"

namespace spot::splat {

namespace {

using namespace gpu_splat;

constexpr VkImageUsageFlags kTargetUsage =
    VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_STORAGE_BIT;
constexpr VkBufferUsageFlags kStorage = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT;
constexpr Buffer::Memory kDevice = Buffer::Memory::DeviceLocal;
/// prepare.comp runs 64 impulses per workgroup and a dispatch has at most 65,535 workgroups.
constexpr std::uint32_t kMaxImpulses = 65535u * 64u;

static_assert(kDefaultSmallPixels == int(kSplatSmallPixels),
              "the default threshold is the shared header's");

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

std::unique_ptr<SplattingRenderer> makeSplattingRenderer(const SceneGpu& scene, Method method) {
    std::unique_ptr<Renderer> made = gpuMethod(methodName(method)).make(scene);
    auto* splatting = dynamic_cast<SplattingRenderer*>(made.get());
    SPOT_CHECK(splatting != nullptr);
    made.release();
    return std::unique_ptr<SplattingRenderer>(splatting);
}

SplattingRenderer::SplattingRenderer(const SceneGpu& scene, std::string name, bool smallPath)
    : m_scene(scene), m_ctx(scene.context()), m_name(std::move(name)),
      m_targets(scene.context(), "splat renderer"), m_kernels(scene.context(), "splat renderer"),
      m_smallPath(smallPath) {
    requireFormat(m_ctx, kColorFormat,
                  VK_FORMAT_FEATURE_COLOR_ATTACHMENT_BLEND_BIT | VK_FORMAT_FEATURE_STORAGE_IMAGE_BIT,
                  "blended, stored RGBA32F targets");
    requireFormat(m_ctx, kScalarFormat,
                  VK_FORMAT_FEATURE_COLOR_ATTACHMENT_BLEND_BIT | VK_FORMAT_FEATURE_STORAGE_IMAGE_BIT,
                  "blended, stored R32F targets");
    requireFormat(m_ctx, kDepthFormat, VK_FORMAT_FEATURE_DEPTH_STENCIL_ATTACHMENT_BIT, "depth");
    // The targets every splatting frame has.
    constexpr VkImageAspectFlags kColor = VK_IMAGE_ASPECT_COLOR_BIT;
    m_targets.image(m_base, "splat base colour", kColorFormat, kTargetUsage, kColor);
    m_targets.image(m_distance, "splat mesh distance", kScalarFormat, kTargetUsage, kColor);
    m_targets.image(m_depth, "splat depth", kDepthFormat,
                    VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT, VK_IMAGE_ASPECT_DEPTH_BIT);
    m_targets.image(m_result, "splat result", kColorFormat,
                    VK_IMAGE_USAGE_STORAGE_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT, kColor);
    // The buffers sized per kernel every splatting frame has.
    const std::uint64_t lobes = m_scene.lobeCount();
    const auto perKernel = [](std::uint64_t bytes) {
        return [bytes](Extent e) { return std::max<std::uint64_t>(e.width, 1) * bytes; };
    };
    // A lit frame's hold a second half: each lobe's colour change (spot_layout.h).
    m_kernels.buffer(
        m_worldLobes, "splat world lobes",
        [this, lobes](Extent e) {
            return std::max<std::uint64_t>(e.width, 1) * lobes * sizeof(gpu::SpotWorldLobe) *
                   (m_litLobes ? 2u : 1u);
        },
        kStorage, kDevice);
    m_kernels.buffer(m_screenLobes, "splat screen lobes", perKernel(lobes * sizeof(SpotScreenLobe)),
                     kStorage, kDevice);
    m_kernels.buffer(m_bounds, "splat kernel bounds", perKernel(sizeof(SpotKernelBound)), kStorage,
                     kDevice);
    m_kernels.buffer(m_visible, "splat kept kernels", perKernel(sizeof(std::uint32_t)), kStorage,
                     kDevice);
    m_kernels.buffer(
        m_clipList, "splat prepare's clipped kernels",
        [](Extent e) {
            return sizeof(SpotSplatList) +
                   std::max<std::uint64_t>(e.width, 1) * sizeof(std::uint32_t);
        },
        kStorage | VK_BUFFER_USAGE_INDIRECT_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT, kDevice);
    // The quads' indices (spot_splat.h, kSplatQuadIndices), the same every frame: written once.
    m_kernels.buffer(m_quadIndices, "splat quad indices",
                     perKernel(kSplatQuadIndices * sizeof(std::uint32_t)),
                     VK_BUFFER_USAGE_INDEX_BUFFER_BIT, Buffer::Memory::HostVisible);
    if (m_smallPath)
        m_kernels.buffer(m_small, "splat small kernels", perKernel(sizeof(std::uint32_t)), kStorage,
                         kDevice);
    m_draw = Buffer(m_ctx, kSplatDrawWords * sizeof(std::uint32_t),
                    kStorage | VK_BUFFER_USAGE_INDIRECT_BUFFER_BIT, Buffer::Memory::HostVisible,
                    "splat indirect draw and dispatch");
    std::memset(m_draw.mapped(), 0, m_draw.size()); // no kernel drawn before the first frame
    m_counters =
        Buffer(m_ctx, sizeof(SpotSplatCounters), kStorage | VK_BUFFER_USAGE_TRANSFER_DST_BIT,
               Buffer::Memory::HostVisible, "splat fragment counters");
}

void SplattingRenderer::declareClosest(Buffer& closest, Buffer& list,
                                       FrameResources::Wanted atomic) {
    constexpr VkBufferUsageFlags kCleared = kStorage | VK_BUFFER_USAGE_TRANSFER_DST_BIT;
    m_targets.buffer(
        closest, "splat closest kernels",
        [](Extent e) { return e.width * e.height * sizeof(std::uint64_t); }, kCleared, kDevice,
        std::move(atomic));
    m_targets.buffer(
        list, "splat resolve's listed pixels",
        [](Extent e) { return sizeof(SpotSplatList) + e.width * e.height * sizeof(std::uint32_t); },
        kCleared | VK_BUFFER_USAGE_INDIRECT_BUFFER_BIT, kDevice);
}

Specialization SplattingRenderer::specialization(const Spec& s) const {
    Specialization spec;
    spec.set(kSplatSpecLobes, m_scene.lobeCount())
        .set(kSplatSpecSamples, s.samples)
        .set(kSplatSpecLambert, s.lambert)
        .set(kSplatSpecOrthographic, s.orthographic)
        .set(kSplatSpecEwa, s.ewa)
        .set(kSplatSpecWeight, s.weight)
        .set(kSplatSpecCount, s.count)
        .set(kSplatSpecScreen, true)
        .set(kSplatSpecSmallPixels, s.smallPixels)
        .set(kSplatSpecLit, s.lit);
    const noise::Kernel& kernel = m_scene.kernel();
    for (std::uint32_t l = 0; l < kernel.lobes.size(); ++l)
        for (std::uint32_t c = 0; c < 3; ++c)
            spec.set(kSplatSpecLobeColor + 3 * l + c, kernel.lobes[l].color[c]);
    return spec;
}

GraphicsPipelineDesc SplattingRenderer::quadPipeline(const Spec& s) const {
    GraphicsPipelineDesc quads;
    quads.vertex = spirv(spv_splat_quad_vert);
    quads.bindings = {storageBuffer(kSplatBindBounds), storageBuffer(kSplatBindVisible),
                      storageBuffer(kSplatBindWorldLobes), storageBuffer(kSplatBindScreenLobes)};
    quads.pushBytes = sizeof(SpotSplatFrame);
    quads.topology = VK_PRIMITIVE_TOPOLOGY_TRIANGLE_LIST;
    quads.spec = specialization(s);
    return quads;
}

GraphicsPipelineDesc
SplattingRenderer::splatPipeline(const Spec& s, std::span<const std::uint32_t> fragment) const {
    GraphicsPipelineDesc splat = quadPipeline(s);
    splat.fragment = fragment;
    splat.bindings.insert(splat.bindings.end(),
                          {storageImage(kSplatBindMeshDistance),
                           storageBuffer(kSplatBindCounters)}); // counters: when counting
    splat.depthFormat = kDepthFormat;
    splat.depthTest = true;
    splat.depthWrite = false;
    splat.depthCompare = VK_COMPARE_OP_GREATER;
    return splat;
}

Pipeline SplattingRenderer::smallPipeline(const Spec& s, std::span<const std::uint32_t> module,
                                          const Bindings& extra) const {
    Bindings small = {storageBuffer(kSplatBindWorldLobes), storageBuffer(kSplatBindScreenLobes),
                      storageBuffer(kSplatBindBounds),     storageBuffer(kSplatBindSmall),
                      storageBuffer(kSplatBindDraw),       storageImage(kSplatBindMeshDistance),
                      storageBuffer(kSplatBindCounters)};
    small.insert(small.end(), extra.begin(), extra.end());
    return makeComputePipeline(m_ctx, module, small, sizeof(SpotSplatFrame), specialization(s));
}

Pipeline SplattingRenderer::resolvePipeline(const Spec& s, std::span<const std::uint32_t> module,
                                            Bindings bindings, bool listed) const {
    bindings.push_back(storageImage(kSplatBindResult));
    Specialization spec = specialization(s);
    spec.set(kSplatSpecResolveList, listed);
    return makeComputePipeline(m_ctx, module, bindings, sizeof(SpotSplatFrame), spec);
}

std::uint64_t SplattingRenderer::kernelBytes(std::uint32_t capacity) const {
    return m_kernels.bytes(Extent{capacity, 1}, m_frame.settings);
}

std::uint64_t SplattingRenderer::frameBytes(int width, int height, std::uint32_t capacity,
                                            const RenderSettings& settings) const {
    return m_targets.bytes(Extent{std::uint64_t(width), std::uint64_t(height)}, settings) +
           m_kernels.bytes(Extent{capacity, 1}, settings) + m_draw.size() + m_counters.size();
}

void SplattingRenderer::ensureKernels(std::uint32_t capacity) {
    if (capacity <= m_kernels.extent().width &&
        m_kernels.current(m_kernels.extent(), m_frame.settings))
        return;
    // Grow with a margin, so a capacity creeping up does not reallocate every frame.
    const std::uint32_t grown = std::max(
        capacity, std::uint32_t(std::min<std::uint64_t>(kMaxImpulses, capacity + capacity / 4)));
    if (!m_kernels.ensure(Extent{grown, 1}, m_frame.settings, cat(capacity, " kernels need")))
        return;
    constexpr std::array<std::uint32_t, kSplatQuadIndices> kQuad{0, 1, 2, 1, 3, 2};
    auto* index = static_cast<std::uint32_t*>(m_quadIndices.mapped());
    const std::uint64_t n = std::max<std::uint32_t>(grown, 1);
    for (std::uint64_t k = 0; k < n; ++k)
        for (std::uint32_t c = 0; c < kSplatQuadIndices; ++c)
            index[k * kSplatQuadIndices + c] = std::uint32_t(4 * k) + kQuad[c];
}

void SplattingRenderer::prepare(const View& view, const ImpulseSet& impulses,
                                const RenderSettings& settings) {
    static_cast<void>(noise::CameraRays(view.camera)); // validates the camera first (InputError)
    if (settings.kernelSamples < 0 || settings.kernelSamples > int(kSplatMaxKernelSamples))
        throw InputError(cat("splat renderer: kernel samples ", settings.kernelSamples,
                             " outside [0, ", kSplatMaxKernelSamples,
                             "] (0 = analytic; more would exceed lavapipe's loop budget)"));
    if (settings.smallPixels < 0 || settings.smallPixels > int(kSplatMaxSmallPixels))
        throw InputError(cat("splat renderer: small kernel pixels ", settings.smallPixels,
                             " outside [0, ", kSplatMaxSmallPixels, "]"));
    if (settings.roofline && !drawsRoofline())
        throw InputError(cat("splat renderer: the roofline is drawn by oit, not by ", m_name));
    impulses.require("splat renderer", kMaxImpulses, "prepare");
    const std::uint32_t width = std::uint32_t(view.camera.width);
    const std::uint32_t height = std::uint32_t(view.camera.height);
    if (m_targets.ensure(Extent{width, height}, settings,
                         cat("a ", width, "x", height, " frame needs")))
        targetsMade();
    Frame& f = m_frame;
    f.settings = settings;
    if (const bool lit = view.shading.mode == noise::Shading::Mode::Lit; lit != m_litLobes) {
        m_litLobes = lit; // the world lobes' size changes
        m_kernels.invalidate();
    }
    ensureKernels(impulses.capacity);

    f.view = view;
    f.impulses = impulses;
    f.width = width;
    f.height = height;
    Spec& s = f.spec;
    s = Spec{};
    s.samples = std::uint32_t(settings.kernelSamples);
    s.lambert = view.shading.mode == noise::Shading::Mode::Lambert;
    s.lit = view.shading.mode == noise::Shading::Mode::Lit;
    s.orthographic = view.camera.projection == noise::Projection::Orthographic;
    s.ewa = settings.ewa;
    s.smallPixels = smallPixels(settings, Extent{width, height});
    s.count = settings.countFragments && !settings.roofline;
    s.weight = settings.weight == OitWeight::McGuireBavoil ? shared::f32::kSpotWeightMcGuireBavoil
                                                           : shared::f32::kSpotWeightConstant;
    auto it = m_common.find(s);
    if (it == m_common.end()) {
        Common c;
        // World lobes are read by Lambert shading, by N samples and for their lit colours.
        const bool world = s.lambert || s.samples > 0 || s.lit;
        const std::uint32_t lobes = m_scene.lobeCount();
        c.prepare = makePreparePipeline(m_ctx, lobes, true, s.ewa, s.orthographic, world, false,
                                        s.lit);
        c.prepareClipped =
            makePreparePipeline(m_ctx, lobes, true, s.ewa, s.orthographic, world, true, s.lit);
        Bindings compact = {storageBuffer(kSplatBindBounds), storageBuffer(kSplatBindVisible),
                            storageBuffer(kSplatBindDraw), storageBuffer(kSplatBindCount)};
        if (m_smallPath)
            compact.push_back(storageBuffer(kSplatBindSmall));
        c.compact = makeComputePipeline(m_ctx,
                                        m_smallPath ? spirv(spv_splat_compact_small_comp)
                                                    : spirv(spv_splat_compact_comp),
                                        compact, sizeof(SpotSplatFrame), specialization(s));
        it = m_common.emplace(s, std::move(c)).first;
    }
    m_commonPipelines = &it->second;
    if (s.lit) {
        if (!m_light)
            m_light = std::make_unique<LightSpace>(m_scene);
        m_light->prepare(view.shading, impulses);
    }
    f.frame = makeSplatFrame(view.camera, view.shading, view.baseColor, impulses.capacity,
                             m_scene.lobeCount(), m_scene.support(),
                             std::uint32_t(settings.kernelSamples), 0);
    preparePasses();
}

void SplattingRenderer::recordPrepareAndCompact(VkCommandBuffer cmd, PassTimer& timer) {
    using namespace passes;
    const Frame& f = m_frame;
    const Common& p = *m_commonPipelines;
    const LightSpace* light = f.spec.lit ? m_light.get() : nullptr;
    if (light)
        m_light->record(cmd, timer);
    // Prepare: world and screen lobes and bounds, then the kept kernels in order and the draw.
    PrepareBuffers pb;
    pb.impulses = f.impulses.impulses;
    pb.count = f.impulses.count;
    pb.lobes = &m_scene.lobes();
    pb.worldLobes = &m_worldLobes;
    pb.screenLobes = &m_screenLobes;
    pb.bounds = &m_bounds;
    pb.clipList = &m_clipList;
    pb.clipped = &p.prepareClipped;
    pb.light = light;
    recordPrepare(m_ctx, cmd, p.prepare, f.frame, pb, f.impulses.capacity);
    memoryBarrier(cmd, kCompute, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT, kCompute, kStorageRead);
    vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, p.compact.handle());
    pushFrame(cmd, p.compact, f.frame);
    Descriptors compact;
    compact.buffer(kSplatBindBounds, m_bounds)
        .buffer(kSplatBindVisible, m_visible)
        .buffer(kSplatBindDraw, m_draw)
        .buffer(kSplatBindCount, *f.impulses.count);
    if (m_smallPath)
        compact.buffer(kSplatBindSmall, m_small);
    compact.push(m_ctx, cmd, p.compact);
    vkCmdDispatch(cmd, 1, 1, 1);
    if (f.settings.countFragments)
        vkCmdFillBuffer(cmd, m_counters.handle(), 0, VK_WHOLE_SIZE, 0u);
    recordClears(cmd);
    memoryBarrier(cmd, kCompute | VK_PIPELINE_STAGE_2_CLEAR_BIT,
                  VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT | VK_ACCESS_2_TRANSFER_WRITE_BIT,
                  VK_PIPELINE_STAGE_2_DRAW_INDIRECT_BIT | VK_PIPELINE_STAGE_2_VERTEX_SHADER_BIT |
                      kFragment | kCompute,
                  VK_ACCESS_2_INDIRECT_COMMAND_READ_BIT | kStorageRW);
}

void SplattingRenderer::recordMesh(VkCommandBuffer cmd) {
    using namespace passes;
    const Frame& f = m_frame;
    for (const Image* image : {&m_base, &m_distance})
        transitionImage(cmd, image->handle(), kColorAspect, VK_IMAGE_LAYOUT_UNDEFINED, kAttachment,
                        VK_PIPELINE_STAGE_2_NONE, 0, kColorOut, kColorRW);
    transitionImage(cmd, m_depth.handle(), VK_IMAGE_ASPECT_DEPTH_BIT, VK_IMAGE_LAYOUT_UNDEFINED,
                    VK_IMAGE_LAYOUT_DEPTH_ATTACHMENT_OPTIMAL, VK_PIPELINE_STAGE_2_NONE, 0, kTests,
                    kDepthRW);
    m_scene.meshPass().record(cmd, f.frame, m_base, m_distance, m_depth, f.view.background, {},
                              f.spec.lit ? m_light.get() : nullptr);
    transitionImage(cmd, m_distance.handle(), kColorAspect, kAttachment, kGeneral, kColorOut,
                    VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT, kFragment | kCompute, kStorageRead);
    // Base colour and depth stay attachments: the instanced and sorted passes draw over them.
    transitionImage(cmd, m_base.handle(), kColorAspect, kAttachment, kAttachment, kColorOut,
                    VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT, kColorOut, kColorRW);
    transitionImage(cmd, m_depth.handle(), VK_IMAGE_ASPECT_DEPTH_BIT,
                    VK_IMAGE_LAYOUT_DEPTH_ATTACHMENT_OPTIMAL,
                    VK_IMAGE_LAYOUT_DEPTH_ATTACHMENT_OPTIMAL, kTests,
                    VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT, kTests, kDepthRW);
}

void SplattingRenderer::pushQuadDescriptors(VkCommandBuffer cmd, const Pipeline& pipeline,
                                            Descriptors& extra) {
    extra.buffer(kSplatBindBounds, m_bounds)
        .buffer(kSplatBindVisible, m_visible)
        .buffer(kSplatBindWorldLobes, m_worldLobes)
        .buffer(kSplatBindScreenLobes, m_screenLobes)
        .push(m_ctx, cmd, pipeline);
}

Descriptors& SplattingRenderer::splatInputs(Descriptors& d) const {
    return d
        .image(kSplatBindMeshDistance, m_distance, passes::kGeneral,
               VK_DESCRIPTOR_TYPE_STORAGE_IMAGE)
        .buffer(kSplatBindCounters, m_counters);
}

void SplattingRenderer::drawQuads(VkCommandBuffer cmd) {
    // One quad per kept kernel: the compaction's indexed draw (spot_splat.h, kSplatQuadIndices).
    vkCmdBindIndexBuffer(cmd, m_quadIndices.handle(), 0, VK_INDEX_TYPE_UINT32);
    vkCmdDrawIndexedIndirect(cmd, m_draw.handle(), 0, 1, sizeof(VkDrawIndexedIndirectCommand));
}

void SplattingRenderer::recordSmall(VkCommandBuffer cmd, const Pipeline& pipeline,
                                    Descriptors& extra) {
    using namespace passes;
    // After the quads: both passes' atomics are order-independent, and the fixed-point sums are
    // the resolve's to add.
    memoryBarrier(cmd, kFragment, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT, kCompute, kStorageRW);
    vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, pipeline.handle());
    pushFrame(cmd, pipeline, m_frame.frame);
    extra.buffer(kSplatBindWorldLobes, m_worldLobes)
        .buffer(kSplatBindScreenLobes, m_screenLobes)
        .buffer(kSplatBindBounds, m_bounds)
        .buffer(kSplatBindSmall, m_small)
        .buffer(kSplatBindDraw, m_draw)
        .image(kSplatBindMeshDistance, m_distance, kGeneral, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE)
        .buffer(kSplatBindCounters, m_counters)
        .push(m_ctx, cmd, pipeline);
    vkCmdDispatchIndirect(cmd, m_draw.handle(), kSplatDrawDispatch * sizeof(std::uint32_t));
}

void SplattingRenderer::finishSplat(VkCommandBuffer cmd,
                                    std::initializer_list<const Image*> drawn) {
    using namespace passes;
    for (const Image* image : drawn)
        transitionImage(cmd, image->handle(), kColorAspect, kAttachment, kGeneral, kColorOut,
                        VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT, kCompute, kStorageRead);
    memoryBarrier(cmd, kFragment | kCompute, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT,
                  kCompute | kHostStage, kStorageRW | VK_ACCESS_2_HOST_READ_BIT);
}

void SplattingRenderer::recordResolve(VkCommandBuffer cmd, const Pipeline& resolve,
                                      Descriptors& bindings, const Pipeline* listed,
                                      const Buffer* list) {
    using namespace passes;
    const Frame& f = m_frame;
    if (listed)
        recordListReset(cmd, *list);
    transitionImage(cmd, m_result.handle(), kColorAspect, VK_IMAGE_LAYOUT_UNDEFINED, kGeneral,
                    VK_PIPELINE_STAGE_2_NONE, 0, kCompute, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT);
    vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, resolve.handle());
    pushFrame(cmd, resolve, f.frame);
    bindings.image(kSplatBindResult, m_result, kGeneral, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE);
    bindings.push(m_ctx, cmd, resolve);
    vkCmdDispatch(cmd, (f.width + kSplatResolveTile - 1) / kSplatResolveTile,
                  (f.height + kSplatResolveTile - 1) / kSplatResolveTile, 1);
    if (listed) {
        memoryBarrier(cmd, kCompute, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT,
                      kCompute | VK_PIPELINE_STAGE_2_DRAW_INDIRECT_BIT,
                      kStorageRW | VK_ACCESS_2_INDIRECT_COMMAND_READ_BIT);
        vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, listed->handle());
        pushFrame(cmd, *listed, f.frame);
        bindings.push(m_ctx, cmd, *listed);
        vkCmdDispatchIndirect(cmd, list->handle(), 0);
    }
    memoryBarrier(cmd, kCompute, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT,
                  kCompute | kTransfer | kHostStage,
                  kStorageRead | VK_ACCESS_2_TRANSFER_READ_BIT | VK_ACCESS_2_HOST_READ_BIT);
}

FrameCounters SplattingRenderer::counters() const {
    FrameCounters c;
    VkDrawIndexedIndirectCommand command;
    std::memcpy(&command, m_draw.mapped(), sizeof(command));
    std::uint32_t small = 0;
    std::memcpy(&small,
                static_cast<const char*>(m_draw.mapped()) + kSplatDrawSmallCount * sizeof(std::uint32_t),
                sizeof(small));
    c.kernelsDrawn = command.indexCount / kSplatQuadIndices + small;
    c.extra.emplace_back("kernels_small", double(small));
    if (m_frame.settings.countFragments && !m_frame.settings.roofline) {
        SpotSplatCounters counted;
        std::memcpy(&counted, m_counters.mapped(), sizeof(counted));
        c.fragmentsShaded = std::uint64_t(counted.fragments.x) | (std::uint64_t(counted.fragments.y) << 32);
        c.pixelsCovered = std::uint64_t(counted.fragments.z) | (std::uint64_t(counted.fragments.w) << 32);
    }
    return c;
}

MethodInfo splattingMethod(std::string name, std::string summary,
                           std::vector<const Setting*> settings) {
    MethodInfo m;
    m.name = std::move(name);
    m.summary = std::move(summary);
    m.settings = std::move(settings);
    m.rendersLit = true;
    return m;
}

} // namespace spot::splat
