/// @file hybrid.cpp
/// @brief `hybrid` (paper eq. 13): oit, with each pixel's closest kernel composited over the blend
/// of the others. The closest kernel is found in the OIT pass by a 64-bit atomicMin of
/// (depth bits << 32 | kernel index) (ClosestKernel::Atomic; splat_oit_closest.frag, and the
/// compute path's), or in a pass of its own over the same quads with a depth test before the OIT
/// pass (ClosestKernel::DepthPass; splat_closest.frag, no compute path). The resolve lists the
/// pixels with a closest kernel; a second dispatch evaluates it there and takes its own terms out
/// of the accumulation before compositing. Its registry entry, its renderer and the settings it
/// takes.
#include "splat/passes/oit_accumulation_vk.h"
#include "splat/passes/splatting_vk.h"

#include "shaders/spot_shared.hpp"

#include "splat_closest.frag.h"
#include "splat_oit.frag.h"
#include "splat_oit_closest.frag.h"
#include "splat_resolve_hybrid.comp.h"
#include "splat_resolve_hybrid_fixed.comp.h"
#include "splat_resolve_hybrid_pass.comp.h"
#include "splat_small_hybrid.comp.h"

namespace spot::splat {

namespace {

using namespace gpu_splat;

constexpr VkFormat kKernelIndexFormat = VK_FORMAT_R32_UINT;

bool atomic(const RenderSettings& s) {
    return s.closest == ClosestKernel::Atomic;
}

class HybridRenderer final : public SplattingRenderer {
public:
    explicit HybridRenderer(const SceneGpu& scene)
        : SplattingRenderer(scene, "hybrid", true),
          m_oit(m_targets,
                [this](const RenderSettings& s, Extent size) { return smallPixels(s, size) > 0; }) {
        requireFormat(m_ctx, kKernelIndexFormat,
                      VK_FORMAT_FEATURE_COLOR_ATTACHMENT_BIT | VK_FORMAT_FEATURE_STORAGE_IMAGE_BIT,
                      "stored R32_UINT kernel index targets");
        const auto byAtomic = [](const RenderSettings& s, Extent) { return atomic(s); };
        const auto byPass = [](const RenderSettings& s, Extent) { return !atomic(s); };
        declareClosest(m_closest, m_closestList, byAtomic);
        m_targets.image(m_closestKernel, "splat closest kernel index", kKernelIndexFormat,
                        VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_STORAGE_BIT,
                        VK_IMAGE_ASPECT_COLOR_BIT, byPass);
        m_targets.image(m_closestDepth, "splat closest kernel depth", kDepthFormat,
                        VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT, VK_IMAGE_ASPECT_DEPTH_BIT,
                        byPass);
    }

    void record(VkCommandBuffer cmd, PassTimer& timer) override {
        const bool atomics = atomic(m_frame.settings);
        recordPrepareAndCompact(cmd, timer);
        timer.mark(cmd, "prepare");
        recordMesh(cmd);
        timer.mark(cmd, "mesh");
        if (!atomics)
            recordClosestPass(cmd);
        m_oit.beginSplat(cmd, m_frame.width, m_frame.height, m_depth);
        vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, m_pipelines->splat.handle());
        pushFrame(cmd, m_pipelines->splat, m_frame.frame);
        Descriptors splat;
        splatInputs(splat);
        if (atomics)
            splat.buffer(kSplatBindClosest, m_closest);
        pushQuadDescriptors(cmd, m_pipelines->splat, splat);
        drawQuads(cmd);
        vkCmdEndRendering(cmd);
        if (m_frame.small()) {
            Descriptors small;
            m_oit.smallDescriptors(small);
            small.buffer(kSplatBindClosest, m_closest);
            recordSmall(cmd, m_pipelines->small, small);
        }
        finishSplat(cmd, {&m_base, &m_oit.accum(), &m_oit.opticalDepth()});
        timer.mark(cmd, "splat");
        using passes::kGeneral;
        Descriptors resolve;
        resolve.buffer(kSplatBindWorldLobes, m_worldLobes)
            .buffer(kSplatBindScreenLobes, m_screenLobes)
            .buffer(kSplatBindBounds, m_bounds)
            .image(kSplatBindBase, m_base, kGeneral, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE)
            .image(kSplatBindMeshDistance, m_distance, kGeneral, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE)
            .buffer(kSplatBindClosestList, m_closestList);
        if (atomics)
            resolve.buffer(kSplatBindClosest, m_closest);
        else
            resolve.image(kSplatBindClosestKernel, m_closestKernel, kGeneral,
                          VK_DESCRIPTOR_TYPE_STORAGE_IMAGE);
        m_oit.resolveDescriptors(resolve, m_frame.small());
        recordResolve(cmd, m_pipelines->resolve, resolve, &m_pipelines->resolveList,
                      &m_closestList);
        timer.mark(cmd, "resolve");
    }

private:
    struct Pipelines {
        Pipeline closest, splat, small, resolve, resolveList;
    };

    /// Not with the depth pass (it draws the same quads), nor where the fixed-point sums would
    /// not fit one storage buffer binding.
    std::uint32_t smallPixels(const RenderSettings& settings, Extent size) const override {
        if (!atomic(settings) || !OitAccumulation::fixedFits(m_ctx, size))
            return 0;
        return std::uint32_t(std::max(settings.smallPixels, 0));
    }

    void targetsMade() override { m_oit.targetsMade(); }

    void recordClears(VkCommandBuffer cmd) override {
        if (atomic(m_frame.settings))
            vkCmdFillBuffer(cmd, m_closest.handle(), 0, VK_WHOLE_SIZE, 0xffffffffu); // "no kernel"
        m_oit.recordClears(cmd, m_frame.small());
    }

    void preparePasses() override {
        const Spec& s = m_frame.spec;
        const bool atomics = atomic(m_frame.settings);
        const auto key = std::make_pair(s, atomics);
        if (const auto it = m_cache.find(key); it != m_cache.end()) {
            m_pipelines = &it->second;
            return;
        }
        Pipelines p;
        if (!atomics) {
            // The closest kernel by a depth pass: nearest wins, the first on a tie.
            GraphicsPipelineDesc closest = quadPipeline(s);
            closest.fragment = spirv(spv_splat_closest_frag);
            closest.bindings.push_back(storageImage(kSplatBindMeshDistance));
            closest.colorFormats = {kKernelIndexFormat};
            closest.blends = {opaqueBlend()};
            closest.depthFormat = kDepthFormat;
            closest.depthTest = true;
            closest.depthWrite = true;
            closest.depthCompare = VK_COMPARE_OP_LESS;
            p.closest = makeGraphicsPipeline(m_ctx, closest);
        }
        GraphicsPipelineDesc splat = splatPipeline(s, atomics ? spirv(spv_splat_oit_closest_frag)
                                                              : spirv(spv_splat_oit_frag));
        if (atomics)
            splat.bindings.push_back(storageBuffer(kSplatBindClosest));
        splat.colorFormats = {kColorFormat, kScalarFormat};
        splat.blends = {additiveBlend(), additiveBlend()};
        p.splat = makeGraphicsPipeline(m_ctx, splat);
        const bool small = s.smallPixels > 0;
        if (small) {
            Bindings extra = OitAccumulation::smallBindings();
            extra.push_back(storageBuffer(kSplatBindClosest));
            p.small = smallPipeline(s, spirv(spv_splat_small_hybrid_comp), extra);
        }
        Bindings resolve = OitAccumulation::resolveBindings(small);
        resolve.insert(
            resolve.end(),
            {storageBuffer(kSplatBindWorldLobes), storageBuffer(kSplatBindScreenLobes),
             storageBuffer(kSplatBindBounds), storageImage(kSplatBindBase),
             storageImage(kSplatBindMeshDistance), storageBuffer(kSplatBindClosestList),
             atomics ? storageBuffer(kSplatBindClosest) : storageImage(kSplatBindClosestKernel)});
        const std::span<const std::uint32_t> module =
            !atomics ? spirv(spv_splat_resolve_hybrid_pass_comp)
            : small  ? spirv(spv_splat_resolve_hybrid_fixed_comp)
                     : spirv(spv_splat_resolve_hybrid_comp);
        p.resolve = resolvePipeline(s, module, resolve, false);
        p.resolveList = resolvePipeline(s, module, resolve, true);
        m_pipelines = &m_cache.emplace(key, std::move(p)).first->second;
    }

    /// Each pixel's closest kernel (index, depth test LESS) before the OIT pass.
    void recordClosestPass(VkCommandBuffer cmd) {
        using namespace passes;
        transitionImage(cmd, m_closestKernel.handle(), kColorAspect, VK_IMAGE_LAYOUT_UNDEFINED,
                        kAttachment, VK_PIPELINE_STAGE_2_NONE, 0, kColorOut, kColorRW);
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
        beginRendering(cmd, m_frame.width, m_frame.height, {index}, &nearest);
        vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, m_pipelines->closest.handle());
        pushFrame(cmd, m_pipelines->closest, m_frame.frame);
        Descriptors distance;
        distance.image(kSplatBindMeshDistance, m_distance, kGeneral,
                       VK_DESCRIPTOR_TYPE_STORAGE_IMAGE);
        pushQuadDescriptors(cmd, m_pipelines->closest, distance);
        drawQuads(cmd);
        vkCmdEndRendering(cmd);
        transitionImage(cmd, m_closestKernel.handle(), kColorAspect, kAttachment, kGeneral,
                        kColorOut, VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT, kCompute, kStorageRead);
    }

    OitAccumulation m_oit;
    Buffer m_closest;      ///< atomic: uint64 per pixel, the closest kernel's key
    Image m_closestKernel; ///< depth pass: the closest kernel's index per pixel
    Image m_closestDepth;  ///< depth pass: its depth test
    Buffer m_closestList;  ///< SpotSplatList and a uint per pixel: the listed pixels
    std::map<std::pair<Spec, bool>, Pipelines> m_cache; ///< by (spec, atomic)
    const Pipelines* m_pipelines = nullptr;
};

} // namespace

MethodInfo hybridMethod() {
    namespace s = settings;
    MethodInfo m =
        splattingMethod("hybrid", "oit plus the closest kernel composited over it (paper eq. 13)",
                        {&s::kernelSamples, &s::ewa, &s::weight, &s::closest, &s::smallPixels,
                         &s::lod, &s::countFragments});
    m.make = [](const SceneGpu& scene) -> std::unique_ptr<Renderer> {
        return std::make_unique<HybridRenderer>(scene);
    };
    return m;
}

} // namespace spot::splat
