#include "method_vk.h"

#include <algorithm>

#include "noise/error.h"
#include "noise/mesh.h"
#include "splat/baked_vk.h"
#include "splat/raymarch_vk.h"
#include "splat/renderer_vk.h"

namespace spot::splat {

PassTimer::PassTimer(Context& ctx, std::uint32_t maxPasses)
    : m_timestamps(ctx, maxPasses + 1), m_maxPasses(maxPasses) {}

void PassTimer::begin(VkCommandBuffer cmd) {
    m_names.clear();
    m_timestamps.reset(cmd);
    m_timestamps.write(cmd, 0, VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT);
}

void PassTimer::mark(VkCommandBuffer cmd, const char* pass) {
    SPOT_CHECK_LT(m_names.size(), std::size_t(m_maxPasses));
    m_names.emplace_back(pass);
    m_timestamps.write(cmd, std::uint32_t(m_names.size()), VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT);
}

std::vector<std::pair<std::string, double>> PassTimer::passMilliseconds() const {
    std::vector<std::pair<std::string, double>> out;
    if (m_names.empty())
        return out;
    const std::vector<double> ms = m_timestamps.milliseconds(std::uint32_t(m_names.size()) + 1);
    for (std::size_t i = 0; i < m_names.size(); ++i) {
        const double span = ms[i + 1] - ms[i];
        auto it = std::find_if(out.begin(), out.end(), [&](const auto& p) { return p.first == m_names[i]; });
        if (it == out.end())
            out.emplace_back(m_names[i], span);
        else
            it->second += span;
    }
    return out;
}

double PassTimer::totalMilliseconds() const {
    if (m_names.empty())
        return 0.0;
    return m_timestamps.milliseconds(std::uint32_t(m_names.size()) + 1).back();
}

SceneGpu::SceneGpu(Context& ctx, const noise::Mesh& mesh, const noise::Kernel& kernel)
    : m_ctx(&ctx), m_kernel(kernel), m_meshPass(ctx, mesh, "scene"),
      m_lobes(uploadKernelLobes(ctx, kernel, "scene")) {}

const std::vector<MethodInfo>& gpuMethods() {
    static const std::vector<MethodInfo> methods = [] {
        std::vector<MethodInfo> m;
        auto splat = [&](Method method, const char* summary) {
            m.push_back({methodName(method), summary, true, false,
                         [method](const SceneGpu& scene) -> std::unique_ptr<Renderer> {
                             return std::make_unique<SplatRenderer>(scene, method);
                         }});
        };
        splat(Method::Instanced, "opaque kernels with the depth test (paper fig. 4 left)");
        splat(Method::Oit, "weighted blended OIT EWA splatting (paper eq. 10-12)");
        splat(Method::Hybrid, "oit plus the closest kernel composited over it (paper eq. 13)");
        splat(Method::Sorted, "kernels sorted by depth, composited back to front");
        m.push_back({"raymarch",
                     "the baseline: each pixel's ray marched through the shell, the neighbouring "
                     "kernels summed at every step (paper eq. 7-9)",
                     false, true, [](const SceneGpu& scene) -> std::unique_ptr<Renderer> {
                         return std::make_unique<RaymarchRenderer>(scene);
                     }});
        m.push_back({"baked",
                     "a bake (render --bake FILE.vdb) marched through the shell's tetrahedra, "
                     "composited by depth peeling",
                     false, false,
                     [](const SceneGpu& scene) -> std::unique_ptr<Renderer> {
                         return std::make_unique<BakedRenderer>(scene);
                     },
                     true});
        return m;
    }();
    return methods;
}

std::string gpuMethodNames() {
    std::string names;
    for (const MethodInfo& m : gpuMethods())
        names += (names.empty() ? "" : ", ") + m.name;
    return names;
}

const MethodInfo* findGpuMethod(std::string_view name) {
    for (const MethodInfo& m : gpuMethods())
        if (m.name == name)
            return &m;
    return nullptr;
}

const MethodInfo& gpuMethod(std::string_view name) {
    if (const MethodInfo* m = findGpuMethod(name))
        return *m;
    throw InputError(cat("unknown GPU method '", name, "' (", gpuMethodNames(), ")"));
}

} // namespace spot::splat
