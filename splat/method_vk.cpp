#include "method_vk.h"

#include <algorithm>

#include "noise/bake.h"
#include "noise/error.h"
#include "noise/mesh.h"

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

void ImpulseSet::require(const char* who, std::uint32_t most, const char* verb) const {
    if (capacity > most)
        throw InputError(
            cat(who, ": ", capacity, " impulses, more than the ", most, " one frame can ", verb));
    const std::uint64_t need = std::uint64_t(capacity) * sizeof(gpu::SpotImpulse);
    if (!impulses || !count || !impulses->handle() || need > impulses->size())
        throw InputError(cat(who, ": the impulse buffer holds ", impulses ? impulses->size() : 0,
                             " bytes, ", capacity, " impulses need ", need));
}

SceneGpu::SceneGpu(Context& ctx, const noise::Mesh& mesh, const noise::Kernel& kernel)
    : m_ctx(&ctx), m_meshHash(noise::meshHash(mesh)), m_meshBounds(mesh.bounds()), m_kernel(kernel),
      m_meshPass(ctx, mesh, "scene"), m_lobes(uploadKernelLobes(ctx, kernel, "scene")) {}

// The registry: each method's module makes its entry (splat/methods/registry.h lists them).
#define SPOT_METHOD(name) MethodInfo name##Method();
#include "splat/methods/registry.h"
#undef SPOT_METHOD

const std::vector<MethodInfo>& methods() {
    static const std::vector<MethodInfo> all = {
#define SPOT_METHOD(name) name##Method(),
#include "splat/methods/registry.h"
#undef SPOT_METHOD
    };
    return all;
}

bool MethodInfo::takes(const Setting& setting) const {
    return std::find(settings.begin(), settings.end(), &setting) != settings.end();
}

bool MethodInfo::takes(std::string_view setting) const {
    return std::any_of(settings.begin(), settings.end(),
                       [&](const Setting* s) { return s->name == setting; });
}

namespace {

std::string names(const std::vector<MethodInfo>& list) {
    std::string out;
    for (const MethodInfo& m : list)
        out += (out.empty() ? "" : ", ") + m.name;
    return out;
}

const MethodInfo* find(const std::vector<MethodInfo>& list, std::string_view name) {
    for (const MethodInfo& m : list)
        if (m.name == name)
            return &m;
    return nullptr;
}

} // namespace

const MethodInfo* findMethod(std::string_view name) {
    return find(methods(), name);
}

const MethodInfo& method(std::string_view name) {
    if (const MethodInfo* m = findMethod(name))
        return *m;
    throw InputError(cat("unknown method '", name, "' (", methodNames(), ")"));
}

void requireLitSupport(const MethodInfo& method, const noise::Shading& shading) {
    if (shading.mode != noise::Shading::Mode::Lit || method.rendersLit)
        return;
    std::string lit;
    for (const MethodInfo& m : methods())
        if (m.rendersLit)
            lit += (lit.empty() ? "" : ", ") + m.name;
    throw InputError(cat(method.name, " does not render lit scenes (shading.mode \"lit\") yet; use --method ",
                         lit));
}

std::string methodNames() {
    return names(methods());
}

std::vector<const Setting*> allSettings() {
    std::vector<const Setting*> out;
    for (const MethodInfo& m : methods())
        for (const Setting* s : m.settings)
            if (std::find(out.begin(), out.end(), s) == out.end())
                out.push_back(s);
    return out;
}

std::string methodsTaking(const Setting& setting) {
    std::string out;
    for (const MethodInfo& m : methods())
        if (m.takes(setting))
            out += (out.empty() ? "" : ", ") + m.name;
    return out;
}

const std::vector<MethodInfo>& gpuMethods() {
    static const std::vector<MethodInfo> gpu = [] {
        std::vector<MethodInfo> out;
        for (const MethodInfo& m : methods())
            if (m.gpu())
                out.push_back(m);
        return out;
    }();
    return gpu;
}

std::string gpuMethodNames() {
    return names(gpuMethods());
}

const MethodInfo* findGpuMethod(std::string_view name) {
    return find(gpuMethods(), name);
}

const MethodInfo& gpuMethod(std::string_view name) {
    if (const MethodInfo* m = findGpuMethod(name))
        return *m;
    throw InputError(cat("unknown GPU method '", name, "' (", gpuMethodNames(), ")"));
}

} // namespace spot::splat
