// Helpers shared by the GPU renderer tests: validated contexts, uploads, scenes and their
// references (rendered once per test process).
#pragma once

#include <cstdlib>
#include <map>
#include <optional>
#include <memory>
#include <span>
#include <string>
#include <tuple>
#include <vector>

#include <gtest/gtest.h>

#include "../noise/test_support.h"
#include "noise/camera.h"
#include "noise/impulses.h"
#include "noise/reference.h"
#include "noise/scene.h"
#include "splat/context_vk.h"
#include "splat/frame_vk.h"
#include "splat/layout.h"
#include "splat/passes/splatting_vk.h"

namespace spot::test {

inline splat::ContextOptions validated() {
    splat::ContextOptions o;
    o.validation = true;
    return o;
}

inline void expectNoValidationErrors(const splat::Context& ctx) {
    EXPECT_EQ(ctx.validation().errors, 0u) << ctx.validation().firstError;
}

/// lavapipe's thread count (LP_NUM_THREADS, read when a Context creates its device) for this
/// object's life: set() before each Context; the value found at construction comes back at
/// destruction (or the variable is unset again).
class ScopedLavapipeThreads {
public:
    ScopedLavapipeThreads() {
        if (const char* previous = std::getenv("LP_NUM_THREADS"))
            m_saved = previous;
    }
    ~ScopedLavapipeThreads() {
        if (m_saved)
            setenv("LP_NUM_THREADS", m_saved->c_str(), 1);
        else
            unsetenv("LP_NUM_THREADS");
    }
    ScopedLavapipeThreads(const ScopedLavapipeThreads&) = delete;
    ScopedLavapipeThreads& operator=(const ScopedLavapipeThreads&) = delete;
    void set(const char* threads) { setenv("LP_NUM_THREADS", threads, 1); }

private:
    std::optional<std::string> m_saved;
};

/// CPU impulses in a host-visible storage buffer, in the GPU layout.
inline splat::Buffer upload(splat::Context& ctx, const std::vector<noise::Impulse>& impulses) {
    const std::vector<gpu::SpotImpulse> g = gpu::toGpu(impulses);
    splat::Buffer b(ctx, g.size() * sizeof(gpu::SpotImpulse), VK_BUFFER_USAGE_STORAGE_BUFFER_BIT,
                    splat::Buffer::Memory::HostVisible, "test impulses");
    if (!g.empty())
        b.upload(std::span<const gpu::SpotImpulse>(g));
    return b;
}

/// 32x32 orthographic camera looking straight down (-y) at the origin over 4 world units: the
/// occlusion tests' view of a lobe centred on the plane y = 0.
inline noise::Camera topDownCamera() {
    noise::Camera cam;
    cam.projection = noise::Projection::Orthographic;
    cam.eye = glm::dvec3(0.0, 3.0, 0.0);
    cam.target = glm::dvec3(0.0);
    cam.up = glm::dvec3(0.0, 0.0, -1.0);
    cam.orthoHeight = 4.0;
    cam.width = cam.height = 32;
    return cam;
}

/// A camera looking at the origin from +z (slightly off axis), for single-lobe tests.
inline noise::Camera lobeCamera(noise::Projection projection, int size) {
    noise::Camera cam;
    cam.projection = projection;
    cam.eye = glm::dvec3(0.3, 0.4, 5.0);
    cam.target = glm::dvec3(0.0);
    cam.orthoHeight = 2.0;
    cam.fovYDeg = 22.0;
    cam.width = cam.height = size;
    return cam;
}

/// A shipped scene at a square size, with its impulses generated on the CPU.
struct SceneSetup {
    noise::SceneDesc scene;
    noise::Mesh mesh;
    noise::Kernel kernel;
    noise::SurfaceCells cells;
    std::vector<noise::Impulse> impulses;
};

inline SceneSetup loadSetup(const std::string& name, int size) {
    SceneSetup s;
    s.scene = loadShippedScene(name);
    s.scene.camera.width = s.scene.camera.height = size;
    s.mesh = noise::loadMeshOrGenerated(s.scene.mesh);
    noise::GeneratorOptions options;
    options.seed = s.scene.seed;
    const noise::ImpulseGenerator generator(s.mesh, noise::loadPreset(s.scene.preset), options);
    s.kernel = generator.kernel();
    s.cells = generator.cells();
    s.impulses = generator.generate();
    return s;
}

/// A shipped scene at a square size with its generator (not its impulses), for a splat::Frame.
struct FrameSetup {
    noise::SceneDesc scene;
    noise::Mesh mesh;
    std::unique_ptr<noise::ImpulseGenerator> generator;
    splat::View view() const {
        return {scene.camera, scene.shading, scene.background, scene.baseColor};
    }
};

inline FrameSetup loadFrameSetup(const std::string& name, int size) {
    FrameSetup s;
    s.scene = loadShippedScene(name);
    s.scene.camera.width = s.scene.camera.height = size;
    s.mesh = noise::loadMeshOrGenerated(s.scene.mesh);
    noise::GeneratorOptions options;
    options.seed = s.scene.seed;
    s.generator = std::make_unique<noise::ImpulseGenerator>(s.mesh, noise::loadPreset(s.scene.preset),
                                                            options);
    return s;
}

/// The reference of a shipped scene (sample pattern seed 3), rendered once per test process.
inline const noise::Image& referenceImage(const std::string& name, int size, int spp) {
    static std::map<std::tuple<std::string, int, int>, noise::Image> cache;
    const auto key = std::make_tuple(name, size, spp);
    auto it = cache.find(key);
    if (it == cache.end()) {
        const SceneSetup s = loadSetup(name, size);
        const noise::ReferenceRenderer reference(s.mesh, s.kernel, s.impulses, s.scene.shading,
                                                 s.scene.background, s.scene.baseColor);
        noise::ReferenceSettings settings;
        settings.spp = spp;
        settings.seed = 3;
        it = cache.emplace(key, reference.render(s.scene.camera, settings)).first;
    }
    return it->second;
}

/// A splatting method and its settings, as the tests choose them.
struct SplatSettings : splat::RenderSettings {
    splat::Method method = splat::Method::Hybrid;
};

/// The splatting renderers over one mesh and kernel, rendering impulses the test holds: one frame
/// per call through splat::renderImpulses (prepare, record, submit, wait, read back).
class SplatRig {
public:
    SplatRig(splat::Context& ctx, const noise::Mesh& mesh, const noise::Kernel& kernel)
        : m_ctx(ctx), m_scene(ctx, mesh, kernel) {}
    noise::Image render(const noise::Camera& camera, const noise::Shading& shading,
                        glm::vec3 background, glm::vec3 baseColor, const splat::Buffer& impulses,
                        std::uint32_t count, const SplatSettings& settings,
                        splat::FrameStats* stats = nullptr) {
        auto& r = m_renderers[int(settings.method)];
        if (!r)
            r = splat::makeSplattingRenderer(m_scene, settings.method);
        return splat::renderImpulses(m_ctx, *r, splat::View{camera, shading, background, baseColor},
                                     impulses, count, settings, stats);
    }
    const splat::SceneGpu& scene() const { return m_scene; }

private:
    splat::Context& m_ctx;
    splat::SceneGpu m_scene;
    std::map<int, std::unique_ptr<splat::SplattingRenderer>> m_renderers;
};

} // namespace spot::test
