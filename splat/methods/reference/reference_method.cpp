/// @file reference_method.cpp
/// @brief `reference`, the converged CPU ground truth (noise/reference.h), registered like the
/// GPU methods: its settings are descriptors, and `render` and `bench` reach it through the
/// registry (method_vk.h) alone.
#include "noise/error.h"
#include "noise/reference.h"
#include "splat/method_vk.h"

namespace spot::splat {

namespace {

CpuFrame renderReference(const CpuScene& scene, const RenderSettings& s, const Progress& progress) {
    noise::ReferenceSettings settings;
    settings.spp = s.spp > 0 ? s.spp : scene.spp;
    settings.stepScale = s.stepScale;
    settings.seed = scene.seed;
    settings.window = s.window;
    const noise::ReferenceRenderer renderer(scene.mesh, scene.kernel, scene.impulses,
                                            scene.view.shading, scene.view.background,
                                            scene.view.baseColor);
    noise::ReferenceStats stats;
    CpuFrame r;
    r.image = renderer.render(scene.view.camera, settings, progress, &stats);
    r.kernels = scene.impulses.size();
    r.seconds = stats.seconds;
    r.stats = {{"spp", settings.spp},
               {"step_scale", settings.stepScale},
               {"kernels_generated", double(r.kernels)},
               {"kernels_drawn", double(r.kernels)},
               {"lobes", double(stats.lobes)},
               {"rays", double(stats.rays)},
               {"chords", double(stats.chords)},
               {"exact_chords", double(stats.exactChords)},
               {"quadrature_steps", double(stats.quadratureSteps)},
               {"memory_bytes", double(stats.memoryBytes)}};
    r.summary = cat(settings.spp, " spp, ", r.kernels, " kernels, ", stats.seconds, " s");
    return r;
}

} // namespace

MethodInfo referenceMethod() {
    MethodInfo m;
    m.rendersLit = true;
    m.name = "reference";
    m.summary = "converged CPU ground truth: every lobe integrated along each pixel's rays";
    m.settings = {&settings::spp, &settings::stepScale};
    m.renderCpu = renderReference;
    return m;
}

} // namespace spot::splat
