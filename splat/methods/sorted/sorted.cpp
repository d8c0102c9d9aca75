/// @file sorted.cpp
/// @brief `sorted`: the kept kernels radix-sorted back to front by the view depth of their centre
/// of mass (splat_sorted_keys.comp, then passes/radix_sort_vk.h) and blended over the base colour
/// with premultiplied "over" (C = C_k + (1 - alpha_k) C): exact compositing wherever kernels do
/// not interpenetrate along a ray, the accuracy ceiling of splatting. No compute path (ordered
/// blending). Its registry entry, its renderer and the settings it takes.
#include "splat/passes/radix_sort_vk.h"
#include "splat/passes/splatting_vk.h"

#include "shaders/spot_shared.hpp"

#include "splat_resolve_copy.comp.h"
#include "splat_sorted.frag.h"
#include "splat_sorted_keys.comp.h"

namespace spot::splat {

namespace {

using namespace gpu_splat;

class SortedRenderer final : public SplattingRenderer {
public:
    explicit SortedRenderer(const SceneGpu& scene) : SplattingRenderer(scene, "sorted", false) {
        m_kernels.buffer(
            m_keys, "splat sort keys",
            [](Extent e) { return std::max<std::uint64_t>(e.width, 1) * sizeof(std::uint32_t); },
            VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, Buffer::Memory::DeviceLocal);
        m_kernels.custom(
            "splat sort scratch",
            [](Extent e) { return RadixSortScratch::bytes(std::uint32_t(e.width)); },
            [this](Extent e) { m_scratch = RadixSortScratch(m_ctx, std::uint32_t(e.width)); },
            [this] { m_scratch = RadixSortScratch(); },
            [this] { return m_scratch.reservedBytes(); });
    }

    void record(VkCommandBuffer cmd, PassTimer& timer) override {
        recordPrepareAndCompact(cmd, timer);
        timer.mark(cmd, "prepare");
        recordSort(cmd);
        timer.mark(cmd, "sort");
        recordMesh(cmd);
        timer.mark(cmd, "mesh");
        // The kernels' quads, back to front, blended over the base colour.
        const VkRenderingAttachmentInfo tested =
            depthAttachment(m_depth, VK_ATTACHMENT_LOAD_OP_LOAD);
        beginRendering(cmd, m_frame.width, m_frame.height,
                       {colorAttachment(m_base, VK_ATTACHMENT_LOAD_OP_LOAD)}, &tested);
        vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, m_pipelines->splat.handle());
        pushFrame(cmd, m_pipelines->splat, m_frame.frame);
        Descriptors splat;
        pushQuadDescriptors(cmd, m_pipelines->splat, splatInputs(splat));
        drawQuads(cmd);
        vkCmdEndRendering(cmd);
        finishSplat(cmd, {&m_base});
        timer.mark(cmd, "splat");
        // The base colour, kernels drawn onto it, is the image.
        recordResolve(cmd, m_pipelines->resolve,
                      Descriptors().image(kSplatBindBase, m_base, passes::kGeneral,
                                          VK_DESCRIPTOR_TYPE_STORAGE_IMAGE));
        timer.mark(cmd, "resolve");
    }

private:
    struct Pipelines {
        Pipeline sortKeys, splat, resolve;
    };

    std::uint32_t smallPixels(const RenderSettings&, Extent) const override { return 0; }

    void preparePasses() override {
        if (!m_sort)
            m_sort = std::make_unique<RadixSort>(m_ctx);
        const Spec& s = m_frame.spec;
        if (const auto it = m_cache.find(s); it != m_cache.end()) {
            m_pipelines = &it->second;
            return;
        }
        Pipelines p;
        p.sortKeys =
            makeComputePipeline(m_ctx, spirv(spv_splat_sorted_keys_comp),
                                {storageBuffer(kSplatBindBounds), storageBuffer(kSplatBindVisible),
                                 storageBuffer(kSplatBindDraw), storageBuffer(kSplatBindKeys)},
                                sizeof(SpotSplatFrame), specialization(s));
        GraphicsPipelineDesc splat = splatPipeline(s, spirv(spv_splat_sorted_frag));
        splat.colorFormats = {kColorFormat};
        splat.blends = {overBlend()};
        p.splat = makeGraphicsPipeline(m_ctx, splat);
        p.resolve = resolvePipeline(s, spirv(spv_splat_resolve_copy_comp),
                                    {storageImage(kSplatBindBase)}, false);
        m_pipelines = &m_cache.emplace(s, std::move(p)).first->second;
    }

    /// The kept kernels back to front (the padding past the kept count last).
    void recordSort(VkCommandBuffer cmd) {
        using namespace passes;
        const std::uint32_t capacity = m_frame.impulses.capacity;
        const Pipeline& keys = m_pipelines->sortKeys;
        vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, keys.handle());
        pushFrame(cmd, keys, m_frame.frame);
        Descriptors()
            .buffer(kSplatBindBounds, m_bounds)
            .buffer(kSplatBindVisible, m_visible)
            .buffer(kSplatBindDraw, m_draw)
            .buffer(kSplatBindKeys, m_keys)
            .push(m_ctx, cmd, keys);
        if (capacity > 0)
            vkCmdDispatch(cmd, (capacity + 63) / 64, 1, 1);
        memoryBarrier(cmd, kCompute, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT, kCompute, kStorageRW);
        m_sort->record(cmd, m_keys, m_visible, capacity, m_scratch);
    }

    std::unique_ptr<RadixSort> m_sort; ///< made at the first frame
    Buffer m_keys;
    RadixSortScratch m_scratch;
    std::map<Spec, Pipelines> m_cache;
    const Pipelines* m_pipelines = nullptr;
};

} // namespace

MethodInfo sortedMethod() {
    namespace s = settings;
    MethodInfo m = splattingMethod("sorted", "kernels sorted by depth, composited back to front",
                                   {&s::kernelSamples, &s::ewa, &s::lod, &s::countFragments});
    m.make = [](const SceneGpu& scene) -> std::unique_ptr<Renderer> {
        return std::make_unique<SortedRenderer>(scene);
    };
    return m;
}

} // namespace spot::splat
