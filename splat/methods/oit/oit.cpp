/// @file oit.cpp
/// @brief `oit`: weighted blended order-independent transparency (McGuire and Bavoil 2013; paper
/// eq. 10-12): every kernel blended into the OIT accumulation (passes/oit_accumulation_vk.h), the
/// small ones by the compute path in fixed point; the resolve composites the weighted mean colour
/// over the base by the revealage exp(-sum of optical depths). With RenderSettings::roofline the
/// same quads are drawn with trivial shaders (the bench's bound on the splat pass). Its registry
/// entry, its renderer and the settings it takes.
#include "splat/passes/oit_accumulation_vk.h"
#include "splat/passes/splatting_vk.h"

#include "shaders/spot_shared.hpp"

#include "splat_oit.frag.h"
#include "splat_resolve_oit.comp.h"
#include "splat_resolve_oit_fixed.comp.h"
#include "splat_roofline.frag.h"
#include "splat_small_oit.comp.h"

namespace spot::splat {

namespace {

using namespace gpu_splat;

class OitRenderer final : public SplattingRenderer {
public:
    explicit OitRenderer(const SceneGpu& scene)
        : SplattingRenderer(scene, "oit", true),
          m_oit(m_targets, [this](const RenderSettings& s, Extent size) {
              RenderSettings drawn = s; // the roofline's frames keep the sums
              drawn.roofline = false;
              return smallPixels(drawn, size) > 0;
          }) {}

    void record(VkCommandBuffer cmd, PassTimer& timer) override {
        recordPrepareAndCompact(cmd, timer);
        timer.mark(cmd, "prepare");
        recordMesh(cmd);
        timer.mark(cmd, "mesh");
        m_oit.beginSplat(cmd, m_frame.width, m_frame.height, m_depth);
        vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, m_pipelines->splat.handle());
        pushFrame(cmd, m_pipelines->splat, m_frame.frame);
        Descriptors splat; // the roofline's shaders read nothing but the quads
        pushQuadDescriptors(cmd, m_pipelines->splat,
                            m_frame.settings.roofline ? splat : splatInputs(splat));
        drawQuads(cmd);
        vkCmdEndRendering(cmd);
        if (m_frame.small()) {
            Descriptors small;
            m_oit.smallDescriptors(small);
            recordSmall(cmd, m_pipelines->small, small);
        }
        finishSplat(cmd, {&m_base, &m_oit.accum(), &m_oit.opticalDepth()});
        timer.mark(cmd, "splat");
        Descriptors resolve;
        resolve.image(kSplatBindBase, m_base, passes::kGeneral, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE);
        m_oit.resolveDescriptors(resolve, m_frame.small());
        recordResolve(cmd, m_pipelines->resolve, resolve);
        timer.mark(cmd, "resolve");
    }

private:
    struct Pipelines {
        Pipeline splat, small, resolve;
    };

    /// Not for the roofline (the raster cost of every quad), nor where the fixed-point sums would
    /// not fit one storage buffer binding.
    std::uint32_t smallPixels(const RenderSettings& settings, Extent size) const override {
        if (settings.roofline || !OitAccumulation::fixedFits(m_ctx, size))
            return 0;
        return std::uint32_t(std::max(settings.smallPixels, 0));
    }

    void targetsMade() override { m_oit.targetsMade(); }
    bool drawsRoofline() const override { return true; }
    void recordClears(VkCommandBuffer cmd) override { m_oit.recordClears(cmd, m_frame.small()); }

    void preparePasses() override {
        const Spec& s = m_frame.spec;
        const bool roofline = m_frame.settings.roofline;
        const auto key = std::make_pair(s, roofline);
        if (const auto it = m_cache.find(key); it != m_cache.end()) {
            m_pipelines = &it->second;
            return;
        }
        Pipelines p;
        GraphicsPipelineDesc splat =
            splatPipeline(s, roofline ? spirv(spv_splat_roofline_frag) : spirv(spv_splat_oit_frag));
        if (roofline)
            splat.bindings = quadPipeline(s).bindings;
        splat.colorFormats = {kColorFormat, kScalarFormat};
        splat.blends = {additiveBlend(), additiveBlend()};
        p.splat = makeGraphicsPipeline(m_ctx, splat);
        const bool small = s.smallPixels > 0;
        if (small)
            p.small =
                smallPipeline(s, spirv(spv_splat_small_oit_comp), OitAccumulation::smallBindings());
        Bindings resolve = OitAccumulation::resolveBindings(small);
        resolve.push_back(storageImage(kSplatBindBase));
        p.resolve = resolvePipeline(
            s, small ? spirv(spv_splat_resolve_oit_fixed_comp) : spirv(spv_splat_resolve_oit_comp),
            resolve, false);
        m_pipelines = &m_cache.emplace(key, std::move(p)).first->second;
    }

    OitAccumulation m_oit;
    std::map<std::pair<Spec, bool>, Pipelines> m_cache; ///< by (spec, roofline)
    const Pipelines* m_pipelines = nullptr;
};

} // namespace

MethodInfo oitMethod() {
    namespace s = settings;
    MethodInfo m = splattingMethod(
        "oit", "weighted blended OIT EWA splatting (paper eq. 10-12)",
        {&s::kernelSamples, &s::ewa, &s::weight, &s::smallPixels, &s::lod, &s::countFragments});
    m.make = [](const SceneGpu& scene) -> std::unique_ptr<Renderer> {
        return std::make_unique<OitRenderer>(scene);
    };
    return m;
}

} // namespace spot::splat
