// Benchmarks of the noise model: surface cells and impulse generation for the shipped presets on
// the bunny at several cell sizes. Run: build/tests/spot_noise_bench
// (timings are ratios within one run; this machine is shared and noisy).
#include <benchmark/benchmark.h>

#include <chrono>

#include "noise/cells.h"
#include "noise/impulses.h"
#include "noise/mesh.h"
#include "noise/preset.h"
#include "splat/context_vk.h"
#include "splat/generate_vk.h"

namespace {

using namespace spot;

const noise::Mesh& bunny() {
    static const noise::Mesh mesh = noise::loadMesh(SPOT_SOURCE_DIR "/presets/meshes/bunny.ply");
    return mesh;
}

noise::PresetDesc preset(const char* name) {
    return noise::loadPreset(std::string(SPOT_SOURCE_DIR "/presets/") + name + ".json");
}

/// Cell size as a multiple (range(0) / 100) of the preset's minimum.
float cellSize(const noise::PresetDesc& p, benchmark::State& state) {
    noise::GeneratorOptions options;
    const float minimum = noise::ImpulseGenerator(bunny(), p, options).minimumCellSize();
    return minimum * float(state.range(0)) / 100.0f;
}

void BM_SurfaceCells(benchmark::State& state) {
    const noise::PresetDesc p = preset("fur");
    const float h = cellSize(p, state);
    std::size_t cells = 0;
    for (auto _ : state) {
        const noise::SurfaceCells c = noise::buildSurfaceCells(bunny(), h);
        cells = c.cells.size();
        benchmark::DoNotOptimize(c.cells.data());
    }
    state.counters["cells"] = double(cells);
    state.counters["h"] = h;
}
BENCHMARK(BM_SurfaceCells)->Arg(100)->Arg(200)->Arg(400)->Unit(benchmark::kMillisecond);

void BM_FurImpulses(benchmark::State& state) {
    const noise::PresetDesc p = preset("fur");
    noise::GeneratorOptions options;
    options.seed = 1;
    options.cellSize = cellSize(p, state);
    const noise::ImpulseGenerator generator(bunny(), p, options);
    std::size_t count = 0;
    for (auto _ : state) {
        const std::vector<noise::Impulse> impulses = generator.generate();
        count = impulses.size();
        benchmark::DoNotOptimize(impulses.data());
    }
    state.counters["impulses"] = double(count);
    state.counters["cells"] = double(generator.cells().cells.size());
    state.counters["impulses/s"] =
        benchmark::Counter(double(count) * double(state.iterations()), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_FurImpulses)->Arg(100)->Arg(200)->Arg(400)->Unit(benchmark::kMillisecond);

void BM_PresetImpulses(benchmark::State& state, const char* name) {
    const noise::PresetDesc p = preset(name);
    noise::GeneratorOptions options;
    const noise::ImpulseGenerator generator(bunny(), p, options);
    std::size_t count = 0;
    for (auto _ : state) {
        const std::vector<noise::Impulse> impulses = generator.generate();
        count = impulses.size();
        benchmark::DoNotOptimize(impulses.data());
    }
    state.counters["impulses/s"] =
        benchmark::Counter(double(count) * double(state.iterations()), benchmark::Counter::kIsRate);
}
BENCHMARK_CAPTURE(BM_PresetImpulses, fur, "fur")->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_PresetImpulses, fur_clumped, "fur-clumped")->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_PresetImpulses, grass, "grass")->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_PresetImpulses, grass_tufts, "grass-tufts")->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_PresetImpulses, lichen, "lichen")->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_PresetImpulses, ring, "ring")->Unit(benchmark::kMillisecond);

/// The GPU generator's passes on the whole bunny (their GPU time, GpuImpulses::milliseconds):
/// what a frame that regenerates its impulses pays; clumped against unclumped presets.
void BM_GpuGenerate(benchmark::State& state, const char* name) {
    static splat::Context ctx;
    const noise::PresetDesc p = preset(name);
    noise::GeneratorOptions options;
    options.seed = 1;
    const noise::ImpulseGenerator generator(bunny(), p, options);
    const auto start = std::chrono::steady_clock::now();
    splat::GpuGenerator gpu(ctx, bunny(), generator);
    (void)gpu.generate(); // compiles the pipeline
    // The first generation's wall time: the pipeline's creation (lavapipe compiles at first use).
    state.counters["first_ms"] =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    std::uint32_t count = 0;
    for (auto _ : state) {
        const splat::GpuImpulses g = gpu.generate();
        state.SetIterationTime(g.milliseconds * 1e-3);
        count = g.count;
    }
    state.counters["impulses"] = double(count);
}
BENCHMARK_CAPTURE(BM_GpuGenerate, fur, "fur")->UseManualTime()->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_GpuGenerate, fur_clumped, "fur-clumped")
    ->UseManualTime()
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_GpuGenerate, grass, "grass")->UseManualTime()->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_GpuGenerate, grass_tufts, "grass-tufts")
    ->UseManualTime()
    ->Unit(benchmark::kMillisecond);

} // namespace

BENCHMARK_MAIN();
