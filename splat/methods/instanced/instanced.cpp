/// @file instanced.cpp
/// @brief `instanced` (paper fig. 4 left): each kernel drawn opaque where its alpha reaches 1/2,
/// the nearest kept per pixel by a 64-bit atomicMin of (depth bits << 32 | kernel index), behind
/// the mesh's depth test; the resolve evaluates that kernel again and paints its mean colour
/// (premul / alpha) over the base. Small kernels take the compute path (splat_small.comp).
/// Its registry entry, its renderer and the settings it takes.
#include "splat/passes/splatting_vk.h"

#include "shaders/spot_shared.hpp"

#include "splat_instanced.frag.h"
#include "splat_resolve_instanced.comp.h"
#include "splat_small_instanced.comp.h"

namespace spot::splat {

namespace {

using namespace gpu_splat;

class InstancedRenderer final : public SplattingRenderer {
public:
    explicit InstancedRenderer(const SceneGpu& scene)
        : SplattingRenderer(scene, "instanced", true) {
        declareClosest(m_closest, m_closestList);
    }

    void record(VkCommandBuffer cmd, PassTimer& timer) override {
        recordPrepareAndCompact(cmd, timer);
        timer.mark(cmd, "prepare");
        recordMesh(cmd);
        timer.mark(cmd, "mesh");
        // Nothing but the atomics, behind the mesh's depth test.
        const VkRenderingAttachmentInfo tested =
            depthAttachment(m_depth, VK_ATTACHMENT_LOAD_OP_LOAD);
        beginRendering(cmd, m_frame.width, m_frame.height, {}, &tested);
        vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, m_pipelines->splat.handle());
        pushFrame(cmd, m_pipelines->splat, m_frame.frame);
        Descriptors splat;
        pushQuadDescriptors(cmd, m_pipelines->splat,
                            splatInputs(splat).buffer(kSplatBindClosest, m_closest));
        drawQuads(cmd);
        vkCmdEndRendering(cmd);
        if (m_frame.small())
            recordSmall(cmd, m_pipelines->small,
                        Descriptors().buffer(kSplatBindClosest, m_closest));
        finishSplat(cmd, {&m_base});
        timer.mark(cmd, "splat");
        // The pixels with a kernel are listed by the first dispatch and painted by the second.
        using passes::kGeneral;
        Descriptors resolve;
        resolve.buffer(kSplatBindWorldLobes, m_worldLobes)
            .buffer(kSplatBindScreenLobes, m_screenLobes)
            .buffer(kSplatBindBounds, m_bounds)
            .image(kSplatBindBase, m_base, kGeneral, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE)
            .image(kSplatBindMeshDistance, m_distance, kGeneral, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE)
            .buffer(kSplatBindClosest, m_closest)
            .buffer(kSplatBindClosestList, m_closestList);
        recordResolve(cmd, m_pipelines->resolve, resolve, &m_pipelines->resolveList,
                      &m_closestList);
        timer.mark(cmd, "resolve");
    }

private:
    struct Pipelines {
        Pipeline splat, small, resolve, resolveList;
    };

    std::uint32_t smallPixels(const RenderSettings& settings, Extent) const override {
        return std::uint32_t(std::max(settings.smallPixels, 0));
    }

    void recordClears(VkCommandBuffer cmd) override {
        vkCmdFillBuffer(cmd, m_closest.handle(), 0, VK_WHOLE_SIZE, 0xffffffffu); // "no kernel"
    }

    void preparePasses() override {
        const Spec& s = m_frame.spec;
        if (const auto it = m_cache.find(s); it != m_cache.end()) {
            m_pipelines = &it->second;
            return;
        }
        Pipelines p;
        GraphicsPipelineDesc splat = splatPipeline(s, spirv(spv_splat_instanced_frag));
        splat.bindings.push_back(storageBuffer(kSplatBindClosest));
        p.splat = makeGraphicsPipeline(m_ctx, splat);
        if (s.smallPixels > 0)
            p.small = smallPipeline(s, spirv(spv_splat_small_instanced_comp),
                                    {storageBuffer(kSplatBindClosest)});
        const Bindings resolve = {
            storageBuffer(kSplatBindWorldLobes),  storageBuffer(kSplatBindScreenLobes),
            storageBuffer(kSplatBindBounds),      storageImage(kSplatBindBase),
            storageImage(kSplatBindMeshDistance), storageBuffer(kSplatBindClosest),
            storageBuffer(kSplatBindClosestList)};
        p.resolve = resolvePipeline(s, spirv(spv_splat_resolve_instanced_comp), resolve, false);
        p.resolveList = resolvePipeline(s, spirv(spv_splat_resolve_instanced_comp), resolve, true);
        m_pipelines = &m_cache.emplace(s, std::move(p)).first->second;
    }

    Buffer m_closest;     ///< uint64 per pixel: the nearest covering kernel's key
    Buffer m_closestList; ///< SpotSplatList and a uint per pixel: the resolve's listed pixels
    std::map<Spec, Pipelines> m_cache;
    const Pipelines* m_pipelines = nullptr;
};

} // namespace

MethodInfo instancedMethod() {
    namespace s = settings;
    MethodInfo m =
        splattingMethod("instanced", "opaque kernels with the depth test (paper fig. 4 left)",
                        {&s::kernelSamples, &s::ewa, &s::smallPixels, &s::lod, &s::countFragments});
    m.make = [](const SceneGpu& scene) -> std::unique_ptr<Renderer> {
        return std::make_unique<InstancedRenderer>(scene);
    };
    return m;
}

} // namespace spot::splat
