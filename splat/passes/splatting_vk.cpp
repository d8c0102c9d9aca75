#include "splatting_vk.h"

#include <algorithm>
#include <array>
#include <cstring>

#include "noise/error.h"
#include "shaders/spot_shared.hpp"
#include "splat/layout.h"

#include "splat_closest.frag.h"
#include "splat_compact.comp.h"
#include "splat_instanced.frag.h"
#include "splat_oit.frag.h"
#include "splat_quad.vert.h"
#include "splat_resolve.comp.h"
#include "splat_roofline.frag.h"
#include "splat_small.comp.h"
#include "splat_sorted.frag.h"
#include "splat_sorted_keys.comp.h"

namespace spot::splat {

namespace {

using namespace gpu_splat;

constexpr VkImageUsageFlags kTargetUsage =
    VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_STORAGE_BIT;
constexpr VkFormat kKernelIndexFormat = VK_FORMAT_R32_UINT;
constexpr VkBufferUsageFlags kStorage = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT;
/// prepare.comp runs 64 impulses per workgroup and a dispatch has at most 65,535 workgroups.
constexpr std::uint32_t kMaxImpulses = 65535u * 64u;

/// Bytes per pixel of the targets every method has: base colour, mesh distance, depth, result;
/// those of the OIT accumulation (oit, hybrid); the hybrid's closest kernel (atomic: 64-bit;
/// depth pass: index and depth).
constexpr std::uint64_t kCommonBytesPerPixel = 16 + 4 + 4 + 16;
constexpr std::uint64_t kOitBytesPerPixel = 16 + 4;
constexpr std::uint64_t kAtomicBytesPerPixel = 8;
constexpr std::uint64_t kClosestPassBytesPerPixel = 4 + 4;
/// With either, the resolve's list of the pixels with a closest kernel (and its header).
constexpr std::uint64_t kListBytesPerPixel = 4;

/// Whether the method resolves a closest kernel per pixel (the resolve's list).
bool usesClosest(Method m) { return m == Method::Hybrid || m == Method::Instanced; }
/// The compute path's fixed-point OIT sums (oit, hybrid).
constexpr std::uint64_t kFixedBytesPerPixel = kSplatFixedChannels * sizeof(std::uint64_t);
/// Their tiles' flags: one uint per resolve workgroup.
std::uint64_t fixedTileBytes(std::uint64_t width, std::uint64_t height) {
    return (width + kSplatResolveTile - 1) / kSplatResolveTile *
           ((height + kSplatResolveTile - 1) / kSplatResolveTile) * sizeof(std::uint32_t);
}

bool usesOit(Method m) { return m == Method::Oit || m == Method::Hybrid; }

static_assert(kDefaultSmallPixels == int(kSplatSmallPixels),
              "the default threshold is the shared header's");

/// The compute path's threshold for a frame (0: every kernel drawn): not for `sorted` (ordered
/// blending), nor the hybrid's depth pass (it draws the same quads), nor the roofline (the raster
/// cost of every quad), nor `oit` and `hybrid` where the fixed-point sums would not fit one
/// storage buffer binding (`fixedFits`: 128 MiB on lavapipe, 3.3 M pixels, about 1830^2).
std::uint32_t smallPixels(Method m, const RenderSettings& s, bool fixedFits) {
    if (m == Method::Sorted || s.roofline ||
        (m == Method::Hybrid && s.closest == ClosestKernel::DepthPass) || (usesOit(m) && !fixedFits))
        return 0;
    return std::uint32_t(std::max(s.smallPixels, 0));
}

/// Whether a frame with `s` needs the fixed-point sums (made with the targets; the roofline's
/// frames keep them).
bool usesFixed(Method m, const RenderSettings& s, bool fixedFits) {
    RenderSettings drawn = s;
    drawn.roofline = false;
    return usesOit(m) && smallPixels(m, drawn, fixedFits) > 0;
}

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

SplatRenderer::SplatRenderer(const SceneGpu& scene, Method method)
    : m_scene(scene), m_ctx(scene.context()), m_method(method) {
    requireFormat(m_ctx, kColorFormat,
                  VK_FORMAT_FEATURE_COLOR_ATTACHMENT_BLEND_BIT | VK_FORMAT_FEATURE_STORAGE_IMAGE_BIT,
                  "blended, stored RGBA32F targets");
    requireFormat(m_ctx, kScalarFormat,
                  VK_FORMAT_FEATURE_COLOR_ATTACHMENT_BLEND_BIT | VK_FORMAT_FEATURE_STORAGE_IMAGE_BIT,
                  "blended, stored R32F targets");
    requireFormat(m_ctx, kDepthFormat, VK_FORMAT_FEATURE_DEPTH_STENCIL_ATTACHMENT_BIT, "depth");
    requireFormat(m_ctx, kKernelIndexFormat,
                  VK_FORMAT_FEATURE_COLOR_ATTACHMENT_BIT | VK_FORMAT_FEATURE_STORAGE_IMAGE_BIT,
                  "stored R32_UINT kernel index targets");
}

const SplatRenderer::Pipelines& SplatRenderer::pipelines(const Spec& s, bool roofline) {
    const auto key = std::make_pair(s, roofline);
    if (const auto it = m_pipelines.find(key); it != m_pipelines.end())
        return it->second;
    const std::uint32_t push = sizeof(SpotSplatFrame);
    Specialization spec;
    spec.set(kSplatSpecLobes, m_scene.lobeCount())
        .set(kSplatSpecSamples, s.samples)
        .set(kSplatSpecLambert, s.lambert)
        .set(kSplatSpecOrthographic, s.orthographic)
        .set(kSplatSpecEwa, s.ewa)
        .set(kSplatSpecWeight, s.weight)
        .set(kSplatSpecHybridAtomic, s.hybridAtomic)
        .set(kSplatSpecCount, s.count)
        .set(kSplatSpecResolve, s.resolve)
        .set(kSplatSpecScreen, true)
        .set(kSplatSpecSmallPixels, s.smallPixels);
    const noise::Kernel& kernel = m_scene.kernel();
    for (std::uint32_t l = 0; l < kernel.lobes.size(); ++l)
        for (std::uint32_t c = 0; c < 3; ++c)
            spec.set(kSplatSpecLobeColor + 3 * l + c, kernel.lobes[l].color[c]);
    Pipelines p;
    // World lobes are read by Lambert shading and by N samples only.
    const bool world = s.lambert || s.samples > 0;
    p.prepare = makePreparePipeline(m_ctx, m_scene.lobeCount(), true, s.ewa, s.orthographic, world);
    p.prepareClipped =
        makePreparePipeline(m_ctx, m_scene.lobeCount(), true, s.ewa, s.orthographic, world, true);
    p.compact = makeComputePipeline(m_ctx, spirv(spv_splat_compact_comp),
                                    {storageBuffer(kSplatBindBounds), storageBuffer(kSplatBindVisible),
                                     storageBuffer(kSplatBindDraw), storageBuffer(kSplatBindCount),
                                     storageBuffer(kSplatBindSmall)},
                                    push, spec);
    const Bindings lobes = {storageBuffer(kSplatBindWorldLobes), storageBuffer(kSplatBindScreenLobes)};
    Bindings resolve = lobes;
    resolve.insert(resolve.end(),
                   {storageImage(kSplatBindBase), storageImage(kSplatBindAccum),
                    storageImage(kSplatBindOpticalDepth), storageImage(kSplatBindMeshDistance),
                    storageBuffer(kSplatBindClosest), storageImage(kSplatBindClosestKernel),
                    storageImage(kSplatBindResult), storageBuffer(kSplatBindOitFixed),
                    storageBuffer(kSplatBindOitTiles), storageBuffer(kSplatBindClosestList),
                    storageBuffer(kSplatBindBounds)});
    p.resolve = makeComputePipeline(m_ctx, spirv(spv_splat_resolve_comp), resolve, push, spec);
    if (!roofline && (s.resolve == kSplatResolveHybrid || s.resolve == kSplatResolveHybridPass ||
                      s.resolve == kSplatResolveInstanced)) {
        Specialization listed = spec;
        listed.set(kSplatSpecResolveList, true);
        p.resolveList = makeComputePipeline(m_ctx, spirv(spv_splat_resolve_comp), resolve, push, listed);
    }
    if (s.smallPixels > 0 && !roofline) {
        Bindings small = lobes;
        small.insert(small.end(),
                     {storageBuffer(kSplatBindBounds), storageBuffer(kSplatBindSmall),
                      storageBuffer(kSplatBindDraw), storageImage(kSplatBindMeshDistance),
                      storageBuffer(kSplatBindClosest), storageBuffer(kSplatBindOitFixed),
                      storageBuffer(kSplatBindOitTiles), storageBuffer(kSplatBindCounters)});
        p.small = makeComputePipeline(m_ctx, spirv(spv_splat_small_comp), small, push, spec);
    }
    if (m_method == Method::Sorted)
        p.sortKeys = makeComputePipeline(
            m_ctx, spirv(spv_splat_sorted_keys_comp),
            {storageBuffer(kSplatBindBounds), storageBuffer(kSplatBindVisible),
             storageBuffer(kSplatBindDraw), storageBuffer(kSplatBindKeys)},
            push, spec);

    // Splat pipelines: the quads, the kernel's lobes, the mesh distance (and what each writes).
    GraphicsPipelineDesc quads;
    quads.vertex = spirv(spv_splat_quad_vert);
    quads.bindings = {storageBuffer(kSplatBindBounds), storageBuffer(kSplatBindVisible),
                      storageImage(kSplatBindMeshDistance)};
    quads.bindings.insert(quads.bindings.end(), lobes.begin(), lobes.end());
    quads.pushBytes = push;
    quads.topology = VK_PRIMITIVE_TOPOLOGY_TRIANGLE_LIST;
    quads.spec = spec;
    GraphicsPipelineDesc splat = quads;
    splat.bindings.push_back(storageBuffer(kSplatBindCounters)); // read only when counting
    // Quads at their kernel's nearest depth, tested against the mesh's depth (not written):
    // pixels where the mesh hides the whole kernel are never shaded.
    splat.depthFormat = kDepthFormat;
    splat.depthTest = true;
    splat.depthWrite = false;
    splat.depthCompare = VK_COMPARE_OP_GREATER;
    if (roofline) {
        splat.fragment = spirv(spv_splat_roofline_frag);
        splat.colorFormats = {kColorFormat, kScalarFormat};
        splat.blends = {additiveBlend(), additiveBlend()};
    } else if (m_method == Method::Instanced) {
        splat.fragment = spirv(spv_splat_instanced_frag);
        splat.bindings.push_back(storageBuffer(kSplatBindClosest));
    } else if (m_method == Method::Sorted) {
        splat.fragment = spirv(spv_splat_sorted_frag);
        splat.colorFormats = {kColorFormat};
        splat.blends = {overBlend()};
    } else {
        splat.fragment = spirv(spv_splat_oit_frag);
        splat.bindings.push_back(storageBuffer(kSplatBindClosest));
        splat.colorFormats = {kColorFormat, kScalarFormat};
        splat.blends = {additiveBlend(), additiveBlend()};
    }
    p.splat = makeGraphicsPipeline(m_ctx, splat);
    if (s.closestPass && !roofline) {
        // The closest kernel by a depth pass: nearest wins, the first on a tie.
        GraphicsPipelineDesc closest = quads;
        closest.fragment = spirv(spv_splat_closest_frag);
        closest.colorFormats = {kKernelIndexFormat};
        closest.blends = {opaqueBlend()};
        closest.depthFormat = kDepthFormat;
        closest.depthTest = true;
        closest.depthWrite = true;
        closest.depthCompare = VK_COMPARE_OP_LESS;
        p.closest = makeGraphicsPipeline(m_ctx, closest);
    }
    return m_pipelines.emplace(key, std::move(p)).first->second;
}

bool SplatRenderer::fixedFits(std::uint64_t width, std::uint64_t height) const {
    return width * height * kFixedBytesPerPixel <= m_ctx.properties().limits.maxStorageBufferRange;
}

SplatRenderer::Targets SplatRenderer::targets(std::uint64_t width, std::uint64_t height,
                                              const RenderSettings& settings) const {
    Targets t;
    t.oit = usesOit(m_method);
    t.atomic = m_method == Method::Instanced ||
               (m_method == Method::Hybrid && settings.closest == ClosestKernel::Atomic);
    t.pass = m_method == Method::Hybrid && settings.closest == ClosestKernel::DepthPass;
    t.fixed = usesFixed(m_method, settings, fixedFits(width, height));
    t.list = usesClosest(m_method);
    return t;
}

std::uint64_t SplatRenderer::targetBytes(std::uint64_t width, std::uint64_t height,
                                         const RenderSettings& settings) const {
    const Targets t = targets(width, height, settings);
    return width * height *
               (kCommonBytesPerPixel + (t.oit ? kOitBytesPerPixel : 0) +
                (t.atomic ? kAtomicBytesPerPixel : 0) + (t.pass ? kClosestPassBytesPerPixel : 0) +
                (t.list ? kListBytesPerPixel : 0) + (t.fixed ? kFixedBytesPerPixel : 0)) +
           (t.fixed ? fixedTileBytes(width, height) : 0) + (t.list ? sizeof(SpotSplatList) : 0);
}

std::uint64_t SplatRenderer::kernelBytes() const {
    return std::uint64_t(m_scene.lobeCount()) * (sizeof(gpu::SpotWorldLobe) + sizeof(SpotScreenLobe)) +
           sizeof(SpotKernelBound) +
           sizeof(std::uint32_t) + // the kept list
           sizeof(std::uint32_t) + // sorted: the keys; else the small kernels' list
           sizeof(std::uint32_t) + // prepare's clip list
           kSplatQuadIndices * sizeof(std::uint32_t); // the quads' indices
}

std::uint64_t SplatRenderer::frameBytes(int width, int height, std::uint32_t capacity,
                                        const RenderSettings& settings) const {
    return targetBytes(std::uint64_t(width), std::uint64_t(height), settings) +
           std::uint64_t(capacity) * kernelBytes() +
           (m_method == Method::Sorted ? RadixSortScratch::bytes(capacity) : 0) +
           kSplatDrawWords * sizeof(std::uint32_t) + sizeof(SpotSplatCounters) + sizeof(SpotSplatList);
}

void SplatRenderer::ensureTargets(std::uint32_t width, std::uint32_t height,
                                  const RenderSettings& settings) {
    const auto [oit, atomic, pass, fixed, list] = targets(width, height, settings);
    const bool have = m_width == width && m_height == height && m_base.handle() &&
                      (!oit || m_accum.handle()) && (!atomic || m_closest.handle()) &&
                      (!list || m_closestList.handle()) &&
                      (!fixed || m_oitFixed.handle()) &&
                      (m_closestKernel.width() == (pass ? width : 1));
    if (have)
        return;
    // Check the budget for the new size as if the old one were freed (a refused frame keeps the
    // old targets), then free, then allocate.
    const std::uint64_t pixels = std::uint64_t(width) * height;
    const std::uint64_t need = targetBytes(width, height, settings);
    std::uint64_t held = m_closest.reservedBytes() + m_closestList.reservedBytes() +
                         m_oitFixed.reservedBytes() + m_oitTiles.reservedBytes();
    for (const Image* i : {&m_base, &m_distance, &m_depth, &m_accum, &m_opticalDepth,
                           &m_closestKernel, &m_closestDepth, &m_result})
        held += i->reservedBytes();
    if (m_ctx.allocatedBytes() - held + need > m_ctx.memoryBudget())
        throw InputError(cat("splat renderer: a ", width, "x", height, " frame needs ", need >> 20,
                             " MiB of GPU memory for its targets; ",
                             (m_ctx.allocatedBytes() - held) >> 20,
                             " MiB are in use and the budget is ", m_ctx.memoryBudget() >> 20,
                             " MiB; reduce the image size or the kernel count"));
    m_base = Image();
    m_distance = Image();
    m_depth = Image();
    m_accum = Image();
    m_opticalDepth = Image();
    m_closestKernel = Image();
    m_closestDepth = Image();
    m_result = Image();
    m_closest = Buffer();
    m_closestList = Buffer();
    m_oitFixed = Buffer();
    m_oitTiles = Buffer();
    m_width = m_height = 0;
    constexpr VkImageAspectFlags kColor = VK_IMAGE_ASPECT_COLOR_BIT;
    m_base = Image(m_ctx, width, height, kColorFormat, kTargetUsage, kColor, "splat base colour");
    m_distance = Image(m_ctx, width, height, kScalarFormat, kTargetUsage, kColor, "splat mesh distance");
    m_depth = Image(m_ctx, width, height, kDepthFormat, VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT,
                    VK_IMAGE_ASPECT_DEPTH_BIT, "splat depth");
    m_result = Image(m_ctx, width, height, kColorFormat,
                     VK_IMAGE_USAGE_STORAGE_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT, kColor,
                     "splat result");
    if (oit) {
        m_accum = Image(m_ctx, width, height, kColorFormat, kTargetUsage, kColor, "splat OIT accumulation");
        m_opticalDepth = Image(m_ctx, width, height, kScalarFormat, kTargetUsage, kColor,
                               "splat OIT optical depth");
    }
    if (atomic)
        m_closest = Buffer(m_ctx, pixels * sizeof(std::uint64_t),
                           kStorage | VK_BUFFER_USAGE_TRANSFER_DST_BIT, Buffer::Memory::DeviceLocal,
                           "splat closest kernels");
    if (list)
        m_closestList = Buffer(m_ctx, sizeof(SpotSplatList) + pixels * kListBytesPerPixel,
                               kStorage | VK_BUFFER_USAGE_INDIRECT_BUFFER_BIT |
                                   VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                               Buffer::Memory::DeviceLocal, "splat resolve's listed pixels");
    if (fixed) {
        m_oitFixed = Buffer(m_ctx, pixels * kFixedBytesPerPixel,
                            kStorage | VK_BUFFER_USAGE_TRANSFER_DST_BIT, Buffer::Memory::DeviceLocal,
                            "splat small kernels' fixed-point OIT sums");
        m_oitTiles = Buffer(m_ctx, fixedTileBytes(width, height),
                            kStorage | VK_BUFFER_USAGE_TRANSFER_DST_BIT, Buffer::Memory::DeviceLocal,
                            "splat small kernels' tiles with sums");
        m_oitFixedCleared = false;
    }
    // The depth pass's kernel index (1x1, never read, without the depth pass: the resolve's
    // binding needs an image of its format).
    m_closestKernel = Image(m_ctx, pass ? width : 1, pass ? height : 1, kKernelIndexFormat,
                            kTargetUsage, kColor, "splat closest kernel index");
    if (pass) {
        m_closestDepth = Image(m_ctx, width, height, kDepthFormat,
                               VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT, VK_IMAGE_ASPECT_DEPTH_BIT,
                               "splat closest kernel depth");
    }
    m_width = width;
    m_height = height;
}

void SplatRenderer::ensureBuffers(std::uint32_t capacity, const RenderSettings& settings) {
    const bool sorted = m_method == Method::Sorted;
    if (capacity <= m_capacity && m_draw.handle() && (!sorted || m_sortKeys.handle()) &&
        (sorted || m_small.handle()))
        return;
    static_cast<void>(settings);
    // Grow with a margin, so a capacity creeping up does not reallocate every frame.
    const std::uint32_t grown =
        std::max(capacity, std::uint32_t(std::min<std::uint64_t>(kMaxImpulses, capacity + capacity / 4)));
    const std::uint32_t lobes = m_scene.lobeCount();
    const std::uint64_t need = std::uint64_t(grown) * kernelBytes() +
                               (sorted ? RadixSortScratch::bytes(grown) : 0);
    std::uint64_t held = m_sortScratch.reservedBytes();
    for (const Buffer* b :
         {&m_worldLobes, &m_screenLobes, &m_bounds, &m_visible, &m_small, &m_sortKeys, &m_clipList,
          &m_quadIndices})
        held += b->reservedBytes();
    if (m_ctx.allocatedBytes() - held + need > m_ctx.memoryBudget())
        throw InputError(cat("splat renderer: ", capacity, " kernels need ", need >> 20,
                             " MiB of GPU memory; ", (m_ctx.allocatedBytes() - held) >> 20,
                             " MiB are in use and the budget is ", m_ctx.memoryBudget() >> 20,
                             " MiB; reduce the image size or the kernel count"));
    m_worldLobes = Buffer();
    m_screenLobes = Buffer();
    m_bounds = Buffer();
    m_visible = Buffer();
    m_small = Buffer();
    m_sortKeys = Buffer();
    m_clipList = Buffer();
    m_quadIndices = Buffer();
    m_sortScratch = RadixSortScratch();
    m_capacity = 0;
    const std::uint64_t n = std::max<std::uint32_t>(grown, 1);
    constexpr Buffer::Memory kDevice = Buffer::Memory::DeviceLocal;
    m_worldLobes = Buffer(m_ctx, n * lobes * sizeof(gpu::SpotWorldLobe), kStorage, kDevice,
                          cat("splat world lobes (", grown, " kernels)"));
    m_screenLobes = Buffer(m_ctx, n * lobes * sizeof(SpotScreenLobe), kStorage, kDevice,
                           cat("splat screen lobes (", grown, " kernels)"));
    m_bounds = Buffer(m_ctx, n * sizeof(SpotKernelBound), kStorage, kDevice, "splat kernel bounds");
    m_visible = Buffer(m_ctx, n * sizeof(std::uint32_t), kStorage, kDevice, "splat kept kernels");
    m_clipList = Buffer(m_ctx, sizeof(SpotSplatList) + n * sizeof(std::uint32_t),
                        kStorage | VK_BUFFER_USAGE_INDIRECT_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                        kDevice, "splat prepare's clipped kernels");
    if (!sorted)
        m_small = Buffer(m_ctx, n * sizeof(std::uint32_t), kStorage, kDevice, "splat small kernels");
    // The quads' indices (spot_splat.h, kSplatQuadIndices), the same every frame: written once.
    m_quadIndices = Buffer(m_ctx, std::uint64_t(n) * kSplatQuadIndices * sizeof(std::uint32_t),
                           VK_BUFFER_USAGE_INDEX_BUFFER_BIT, Buffer::Memory::HostVisible,
                           "splat quad indices");
    {
        constexpr std::array<std::uint32_t, kSplatQuadIndices> kQuad{0, 1, 2, 1, 3, 2};
        auto* index = static_cast<std::uint32_t*>(m_quadIndices.mapped());
        for (std::uint64_t k = 0; k < n; ++k)
            for (std::uint32_t c = 0; c < kSplatQuadIndices; ++c)
                index[k * kSplatQuadIndices + c] = std::uint32_t(4 * k) + kQuad[c];
    }
    if (!m_draw.handle()) {
        // The quads' indirect draw, the small kernels' indirect dispatch and their count.
        m_draw = Buffer(m_ctx, kSplatDrawWords * sizeof(std::uint32_t),
                        kStorage | VK_BUFFER_USAGE_INDIRECT_BUFFER_BIT, Buffer::Memory::HostVisible,
                        "splat indirect draw and dispatch");
        m_counters = Buffer(m_ctx, sizeof(SpotSplatCounters),
                            kStorage | VK_BUFFER_USAGE_TRANSFER_DST_BIT, Buffer::Memory::HostVisible,
                            "splat fragment counters");
    }
    if (sorted) {
        m_sortKeys = Buffer(m_ctx, n * sizeof(std::uint32_t), kStorage, kDevice, "splat sort keys");
        m_sortScratch = RadixSortScratch(m_ctx, grown);
    }
    m_capacity = grown;
}

void SplatRenderer::prepare(const View& view, const ImpulseSet& impulses,
                            const RenderSettings& settings) {
    static_cast<void>(noise::CameraRays(view.camera)); // validates the camera first (InputError)
    if (settings.kernelSamples < 0 || settings.kernelSamples > int(kSplatMaxKernelSamples))
        throw InputError(cat("splat renderer: kernel samples ", settings.kernelSamples,
                             " outside [0, ", kSplatMaxKernelSamples,
                             "] (0 = analytic; more would exceed lavapipe's loop budget)"));
    if (settings.smallPixels < 0 || settings.smallPixels > int(kSplatMaxSmallPixels))
        throw InputError(cat("splat renderer: small kernel pixels ", settings.smallPixels,
                             " outside [0, ", kSplatMaxSmallPixels, "]"));
    if (impulses.capacity > kMaxImpulses)
        throw InputError(cat("splat renderer: ", impulses.capacity, " impulses, more than the ",
                             kMaxImpulses, " one frame can prepare"));
    if (!impulses.impulses || !impulses.count || !impulses.impulses->handle() ||
        std::uint64_t(impulses.capacity) * sizeof(gpu::SpotImpulse) > impulses.impulses->size())
        throw InputError(cat("splat renderer: the impulse buffer holds ",
                             impulses.impulses ? impulses.impulses->size() : 0, " bytes, ",
                             impulses.capacity, " impulses need ",
                             std::uint64_t(impulses.capacity) * sizeof(gpu::SpotImpulse)));
    ensureTargets(std::uint32_t(view.camera.width), std::uint32_t(view.camera.height), settings);
    ensureBuffers(impulses.capacity, settings);

    Prepared& f = m_frame;
    f.view = view;
    f.impulses = impulses;
    f.settings = settings;
    f.sorted = m_method == Method::Sorted && !settings.roofline;
    f.instanced = m_method == Method::Instanced && !settings.roofline;
    f.closestPass = m_method == Method::Hybrid && settings.closest == ClosestKernel::DepthPass &&
                    !settings.roofline;
    f.hybridAtomic = m_method == Method::Hybrid && settings.closest == ClosestKernel::Atomic &&
                     !settings.roofline;
    Spec s;
    s.samples = std::uint32_t(settings.kernelSamples);
    s.lambert = view.shading.mode == noise::Shading::Mode::Lambert;
    s.orthographic = view.camera.projection == noise::Projection::Orthographic;
    s.ewa = settings.ewa;
    s.hybridAtomic = f.hybridAtomic;
    s.closestPass = f.closestPass;
    s.smallPixels = smallPixels(m_method, settings,
                                fixedFits(std::uint64_t(view.camera.width), std::uint64_t(view.camera.height)));
    f.small = s.smallPixels > 0;
    s.count = settings.countFragments && !settings.roofline;
    s.weight = settings.weight == OitWeight::McGuireBavoil ? shared::f32::kSpotWeightMcGuireBavoil
                                                           : shared::f32::kSpotWeightConstant;
    s.resolve = f.sorted              ? kSplatResolveCopy
                : f.instanced           ? kSplatResolveInstanced
                : f.hybridAtomic        ? kSplatResolveHybrid
                : f.closestPass         ? kSplatResolveHybridPass
                                        : kSplatResolveOit;
    if (settings.roofline) // the roofline's image is meaningless; resolve it as plain OIT
        s.resolve = kSplatResolveOit;
    f.pipelines = &pipelines(s, settings.roofline);
    if (f.sorted && !m_sort)
        m_sort = std::make_unique<RadixSort>(m_ctx);
    f.frame = makeSplatFrame(view.camera, view.shading, view.baseColor, impulses.capacity,
                             m_scene.lobeCount(), m_scene.support(),
                             std::uint32_t(settings.kernelSamples), 0);
}

void SplatRenderer::record(VkCommandBuffer cmd, PassTimer& timer) {
    recordPrepareAndCompact(cmd);
    timer.mark(cmd, "prepare");
    if (m_frame.sorted) {
        recordSort(cmd);
        timer.mark(cmd, "sort");
    }
    recordMesh(cmd);
    timer.mark(cmd, "mesh");
    recordClosestPass(cmd);
    recordSplat(cmd);
    timer.mark(cmd, "splat");
    recordResolve(cmd);
    timer.mark(cmd, "resolve");
}

std::vector<const Image*> SplatRenderer::attachments() const {
    std::vector<const Image*> targets = {&m_base, &m_distance};
    if (usesOit(m_method) || m_frame.settings.roofline)
        targets.insert(targets.end(), {&m_accum, &m_opticalDepth});
    return targets;
}

void SplatRenderer::recordPrepareAndCompact(VkCommandBuffer cmd) {
    using namespace passes;
    const Prepared& f = m_frame;
    const Pipelines& p = *f.pipelines;
    const std::uint32_t capacity = f.impulses.capacity;
    // 1. Prepare: world and screen lobes and bounds, then the kept kernels in order and the draw.
    PrepareBuffers pb;
    pb.impulses = f.impulses.impulses;
    pb.count = f.impulses.count;
    pb.lobes = &m_scene.lobes();
    pb.worldLobes = &m_worldLobes;
    pb.screenLobes = &m_screenLobes;
    pb.bounds = &m_bounds;
    pb.clipList = &m_clipList;
    pb.clipped = &p.prepareClipped;
    recordPrepare(m_ctx, cmd, p.prepare, f.frame, pb, capacity);
    memoryBarrier(cmd, kCompute, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT, kCompute, kStorageRead);
    vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, p.compact.handle());
    pushFrame(cmd, p.compact, f.frame);
    Descriptors()
        .buffer(kSplatBindBounds, m_bounds)
        .buffer(kSplatBindVisible, m_visible)
        .buffer(kSplatBindDraw, m_draw)
        .buffer(kSplatBindCount, *f.impulses.count)
        .buffer(kSplatBindSmall, m_small.handle() ? m_small : m_visible) // sorted: never written
        .push(m_ctx, cmd, p.compact);
    vkCmdDispatch(cmd, 1, 1, 1);
    if (f.hybridAtomic || f.instanced)
        vkCmdFillBuffer(cmd, m_closest.handle(), 0, VK_WHOLE_SIZE, 0xffffffffu); // "no kernel"
    if (f.settings.countFragments)
        vkCmdFillBuffer(cmd, m_counters.handle(), 0, VK_WHOLE_SIZE, 0u);
    if (m_oitFixed.handle() && !m_oitFixedCleared) { // once: then each resolve clears its sums
        vkCmdFillBuffer(cmd, m_oitFixed.handle(), 0, VK_WHOLE_SIZE, 0u);
        m_oitFixedCleared = true;
    }
    if (f.small && m_oitTiles.handle()) // a uint per 8x8 tile: cheap to clear every frame
        vkCmdFillBuffer(cmd, m_oitTiles.handle(), 0, VK_WHOLE_SIZE, 0u);
    memoryBarrier(cmd, kCompute | VK_PIPELINE_STAGE_2_CLEAR_BIT,
                  VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT | VK_ACCESS_2_TRANSFER_WRITE_BIT,
                  VK_PIPELINE_STAGE_2_DRAW_INDIRECT_BIT | VK_PIPELINE_STAGE_2_VERTEX_SHADER_BIT |
                      kFragment | kCompute,
                  VK_ACCESS_2_INDIRECT_COMMAND_READ_BIT | kStorageRW);
}

void SplatRenderer::recordSort(VkCommandBuffer cmd) {
    // The kept kernels back to front (the padding past the kept count last).
    using namespace passes;
    const Prepared& f = m_frame;
    const Pipelines& p = *f.pipelines;
    const std::uint32_t capacity = f.impulses.capacity;
    vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, p.sortKeys.handle());
    pushFrame(cmd, p.sortKeys, f.frame);
    Descriptors()
        .buffer(kSplatBindBounds, m_bounds)
        .buffer(kSplatBindVisible, m_visible)
        .buffer(kSplatBindDraw, m_draw)
        .buffer(kSplatBindKeys, m_sortKeys)
        .push(m_ctx, cmd, p.sortKeys);
    if (capacity > 0)
        vkCmdDispatch(cmd, (capacity + 63) / 64, 1, 1);
    memoryBarrier(cmd, kCompute, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT, kCompute, kStorageRW);
    m_sort->record(cmd, m_sortKeys, m_visible, capacity, m_sortScratch);
}

void SplatRenderer::recordMesh(VkCommandBuffer cmd) {
    using namespace passes;
    const Prepared& f = m_frame;
    const std::vector<const Image*> targets = attachments();
    for (const Image* image : targets)
        transitionImage(cmd, image->handle(), kColorAspect, VK_IMAGE_LAYOUT_UNDEFINED, kAttachment,
                        VK_PIPELINE_STAGE_2_NONE, 0, kColorOut, kColorRW);
    transitionImage(cmd, m_depth.handle(), VK_IMAGE_ASPECT_DEPTH_BIT, VK_IMAGE_LAYOUT_UNDEFINED,
                    VK_IMAGE_LAYOUT_DEPTH_ATTACHMENT_OPTIMAL, VK_PIPELINE_STAGE_2_NONE, 0, kTests,
                    kDepthRW);
    m_scene.meshPass().record(cmd, f.frame, m_base, m_distance, m_depth, f.view.background);
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

void SplatRenderer::pushQuadDescriptors(VkCommandBuffer cmd, const Pipeline& pipeline, bool closest,
                                        bool counters) {
    Descriptors d;
    d.buffer(kSplatBindBounds, m_bounds)
        .buffer(kSplatBindVisible, m_visible)
        .buffer(kSplatBindWorldLobes, m_worldLobes)
        .buffer(kSplatBindScreenLobes, m_screenLobes)
        .image(kSplatBindMeshDistance, m_distance, passes::kGeneral,
               VK_DESCRIPTOR_TYPE_STORAGE_IMAGE);
    if (closest)
        d.buffer(kSplatBindClosest, m_closest.handle() ? m_closest : m_counters);
    if (counters)
        d.buffer(kSplatBindCounters, m_counters);
    d.push(m_ctx, cmd, pipeline);
}

void SplatRenderer::drawQuads(VkCommandBuffer cmd) {
    // One quad per kept kernel: the compaction's indexed draw (spot_splat.h, kSplatQuadIndices).
    vkCmdBindIndexBuffer(cmd, m_quadIndices.handle(), 0, VK_INDEX_TYPE_UINT32);
    vkCmdDrawIndexedIndirect(cmd, m_draw.handle(), 0, 1, sizeof(VkDrawIndexedIndirectCommand));
}

void SplatRenderer::recordClosestPass(VkCommandBuffer cmd) {
    using namespace passes;
    const Prepared& f = m_frame;
    const Pipelines& p = *f.pipelines;
    const std::uint32_t width = m_width, height = m_height;
    // 3a. Hybrid with a depth pass: each pixel's closest kernel (index, depth test LESS).
    transitionImage(cmd, m_closestKernel.handle(), kColorAspect, VK_IMAGE_LAYOUT_UNDEFINED,
                    kAttachment, VK_PIPELINE_STAGE_2_NONE, 0, kColorOut, kColorRW);
    if (f.closestPass) {
        transitionImage(cmd, m_closestDepth.handle(), VK_IMAGE_ASPECT_DEPTH_BIT,
                        VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_DEPTH_ATTACHMENT_OPTIMAL,
                        VK_PIPELINE_STAGE_2_NONE, 0, kTests, kDepthRW);
        VkRenderingAttachmentInfo index =
            colorAttachment(m_closestKernel, VK_ATTACHMENT_LOAD_OP_CLEAR);
        index.clearValue.color.uint32[0] = 0xffffffffu; // no kernel
        VkRenderingAttachmentInfo nearest =
            depthAttachment(m_closestDepth, VK_ATTACHMENT_LOAD_OP_CLEAR);
        nearest.storeOp = VK_ATTACHMENT_STORE_OP_DONT_CARE;
        nearest.clearValue.depthStencil = {1.0f, 0};
        beginRendering(cmd, width, height, {index}, &nearest);
        vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, p.closest.handle());
        pushFrame(cmd, p.closest, f.frame);
        pushQuadDescriptors(cmd, p.closest, false, false);
        drawQuads(cmd);
        vkCmdEndRendering(cmd);
    }
    transitionImage(cmd, m_closestKernel.handle(), kColorAspect, kAttachment, kGeneral, kColorOut,
                    VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT, kCompute, kStorageRead);
}

void SplatRenderer::recordSplat(VkCommandBuffer cmd) {
    using namespace passes;
    const Prepared& f = m_frame;
    const Pipelines& p = *f.pipelines;
    const std::uint32_t width = m_width, height = m_height;
    // 3. The kernels: one quad each, drawn in impulse order (`sorted`: back to front).
    const VkRenderingAttachmentInfo depthInfo =
        depthAttachment(m_depth, VK_ATTACHMENT_LOAD_OP_LOAD);
    if (f.instanced) // nothing but the atomics, behind the mesh test
        beginRendering(cmd, width, height, {}, &depthInfo);
    else if (f.sorted)
        beginRendering(cmd, width, height, {colorAttachment(m_base, VK_ATTACHMENT_LOAD_OP_LOAD)},
                       &depthInfo);
    else
        beginRendering(
            cmd, width, height,
            {colorAttachment(m_accum, VK_ATTACHMENT_LOAD_OP_CLEAR, glm::vec4(0.0f)),
             colorAttachment(m_opticalDepth, VK_ATTACHMENT_LOAD_OP_CLEAR, glm::vec4(0.0f))},
            &depthInfo);
    vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, p.splat.handle());
    pushFrame(cmd, p.splat, f.frame);
    const bool atomics = (usesOit(m_method) || f.instanced) && !f.settings.roofline;
    pushQuadDescriptors(cmd, p.splat, atomics, true);
    drawQuads(cmd);
    vkCmdEndRendering(cmd);
    // 3b. The small kernels: one invocation each (after the quads: both pass's atomics are
    // order-independent, and the fixed-point sums are the resolve's to add).
    if (f.small) {
        memoryBarrier(cmd, kFragment, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT, kCompute, kStorageRW);
        vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, p.small.handle());
        pushFrame(cmd, p.small, f.frame);
        Descriptors()
            .buffer(kSplatBindWorldLobes, m_worldLobes)
            .buffer(kSplatBindScreenLobes, m_screenLobes)
            .buffer(kSplatBindBounds, m_bounds)
            .buffer(kSplatBindSmall, m_small)
            .buffer(kSplatBindDraw, m_draw)
            .image(kSplatBindMeshDistance, m_distance, kGeneral, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE)
            .buffer(kSplatBindClosest, m_closest.handle() ? m_closest : m_counters)
            .buffer(kSplatBindOitFixed, m_oitFixed.handle() ? m_oitFixed : m_counters)
            .buffer(kSplatBindOitTiles, m_oitTiles.handle() ? m_oitTiles : m_counters)
            .buffer(kSplatBindCounters, m_counters)
            .push(m_ctx, cmd, p.small);
        vkCmdDispatchIndirect(cmd, m_draw.handle(), kSplatDrawDispatch * sizeof(std::uint32_t));
    }
    for (const Image* image : attachments())
        if (image != &m_distance)
            transitionImage(cmd, image->handle(), kColorAspect, kAttachment, kGeneral, kColorOut,
                            VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT, kCompute, kStorageRead);
    memoryBarrier(cmd, kFragment | kCompute, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT,
                  kCompute | kHostStage, kStorageRW | VK_ACCESS_2_HOST_READ_BIT);
}

void SplatRenderer::recordResolve(VkCommandBuffer cmd) {
    using namespace passes;
    const Prepared& f = m_frame;
    const Pipelines& p = *f.pipelines;
    const std::uint32_t width = m_width, height = m_height;
    const bool oitTargets = usesOit(m_method) || f.settings.roofline;
    // 4. Resolve into the result image (hybrid, instanced: in two dispatches, SpotSplatList).
    const bool listed = p.resolveList.handle() != VK_NULL_HANDLE;
    if (listed)
        recordListReset(cmd, m_closestList);
    transitionImage(cmd, m_result.handle(), kColorAspect, VK_IMAGE_LAYOUT_UNDEFINED, kGeneral,
                    VK_PIPELINE_STAGE_2_NONE, 0, kCompute, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT);
    vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, p.resolve.handle());
    pushFrame(cmd, p.resolve, f.frame);
    // Bindings a setting does not read are given a target of the right kind that exists.
    const Image& accum = oitTargets ? m_accum : m_base;
    const Image& opticalDepth = oitTargets ? m_opticalDepth : m_distance;
    Descriptors resolve;
    resolve.buffer(kSplatBindWorldLobes, m_worldLobes)
        .buffer(kSplatBindScreenLobes, m_screenLobes)
        .image(kSplatBindBase, m_base, kGeneral, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE)
        .image(kSplatBindAccum, accum, kGeneral, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE)
        .image(kSplatBindOpticalDepth, opticalDepth, kGeneral, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE)
        .image(kSplatBindMeshDistance, m_distance, kGeneral, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE)
        .buffer(kSplatBindClosest, m_closest.handle() ? m_closest : m_counters)
        .image(kSplatBindClosestKernel, m_closestKernel, kGeneral, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE)
        .image(kSplatBindResult, m_result, kGeneral, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE)
        .buffer(kSplatBindOitFixed, m_oitFixed.handle() ? m_oitFixed : m_counters)
        .buffer(kSplatBindOitTiles, m_oitTiles.handle() ? m_oitTiles : m_counters)
        .buffer(kSplatBindClosestList, listed ? m_closestList : m_counters)
        .buffer(kSplatBindBounds, m_bounds);
    resolve.push(m_ctx, cmd, p.resolve);
    vkCmdDispatch(cmd, (width + kSplatResolveTile - 1) / kSplatResolveTile,
                  (height + kSplatResolveTile - 1) / kSplatResolveTile, 1);
    if (listed) {
        memoryBarrier(cmd, kCompute, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT,
                      kCompute | VK_PIPELINE_STAGE_2_DRAW_INDIRECT_BIT,
                      kStorageRW | VK_ACCESS_2_INDIRECT_COMMAND_READ_BIT);
        vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, p.resolveList.handle());
        pushFrame(cmd, p.resolveList, f.frame);
        resolve.push(m_ctx, cmd, p.resolveList);
        vkCmdDispatchIndirect(cmd, m_closestList.handle(), 0);
    }
    memoryBarrier(cmd, kCompute, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT,
                  kCompute | kTransfer | kHostStage,
                  kStorageRead | VK_ACCESS_2_TRANSFER_READ_BIT | VK_ACCESS_2_HOST_READ_BIT);
}

FrameCounters SplatRenderer::counters() const {
    FrameCounters c;
    if (!m_draw.handle())
        return c;
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

MethodInfo splattingMethod(Method method, std::string summary,
                           std::vector<const Setting*> settings) {
    MethodInfo m;
    m.name = methodName(method);
    m.summary = std::move(summary);
    m.settings = std::move(settings);
    m.make = [method](const SceneGpu& scene) -> std::unique_ptr<Renderer> {
        return std::make_unique<SplatRenderer>(scene, method);
    };
    return m;
}

} // namespace spot::splat
