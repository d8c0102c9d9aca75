// Impulses generated on the GPU equal the CPU's: same count, same order, positions within 1e-5 h;
// the persistent generation (prepared on the host, recorded into a caller's command buffer)
// equals the one-shot one and allocates nothing for a frame like the last.
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include <unistd.h>

#include <gtest/gtest.h>

#include "noise/camera.h"
#include "noise/image.h"
#include "noise/impulses.h"
#include "noise/mesh.h"
#include "noise/preset.h"
#include "noise/shared_data.h"
#include "splat/generate_vk.h"
#include "splat_test_support.h"

namespace {

using namespace spot;

splat::ContextOptions validated() {
    splat::ContextOptions o;
    o.validation = true;
    return o;
}

noise::Mesh meshFor(const std::string& name) {
    if (name == "sphere")
        return noise::makeSphere(1.0f, 48, 96);
    if (name == "torus")
        return noise::makeTorus(1.0f, 0.35f, 96, 32);
    if (name == "plane")
        return noise::makePlane(2.0f, 16);
    return noise::loadMesh(std::string(SPOT_SOURCE_DIR) + "/presets/meshes/" + name + ".ply");
}

noise::PresetDesc shippedPreset(const std::string& name) {
    return noise::loadPreset(std::string(SPOT_SOURCE_DIR) + "/presets/" + name + ".json");
}

void expectSameImpulses(const noise::PresetDesc& preset, const noise::Mesh& mesh,
                        const std::string& meshName, std::uint32_t seed = 17) {
    const std::string& presetName = preset.name;
    noise::GeneratorOptions options;
    options.seed = seed;
    const noise::ImpulseGenerator generator(mesh, preset, options);
    const std::vector<noise::Impulse> cpu = generator.generate();

    splat::Context ctx(validated());
    splat::GpuGenerator gpuGenerator(ctx, mesh, generator);
    const splat::GpuImpulses gpu = gpuGenerator.generate();
    ASSERT_EQ(gpu.count, cpu.size()) << presetName << " on " << meshName;
    const auto* g = static_cast<const gpu::SpotImpulse*>(gpu.impulses.mapped());
    const double tolerance = 1e-5 * generator.cellSize();
    double worst = 0.0;
    for (std::size_t i = 0; i < cpu.size(); ++i) {
        const noise::Impulse m = gpu::fromGpu(g[i]);
        ASSERT_EQ(m.cell, cpu[i].cell) << i;
        ASSERT_EQ(m.triangle, cpu[i].triangle) << i;
        worst = std::max(worst, double(glm::length(m.position - cpu[i].position)));
        EXPECT_NEAR(glm::length(m.scale - cpu[i].scale), 0.0f, 1e-4f * glm::length(cpu[i].scale));
        EXPECT_NEAR(glm::length(m.color - cpu[i].color), 0.0f, 1e-4f);
        EXPECT_GT(glm::dot(m.frame[2], cpu[i].frame[2]), 0.9999f);
        EXPECT_GT(glm::dot(m.frame[0], cpu[i].frame[0]), 0.9999f);
        EXPECT_NEAR(m.bend, cpu[i].bend, 1e-4f * (1.0f + std::abs(cpu[i].bend)));
        EXPECT_NEAR(m.clumpStrength, cpu[i].clumpStrength, 1e-6f);
        EXPECT_NEAR(m.clumpDistance, cpu[i].clumpDistance, 1e-5f * generator.cellSize());
    }
    EXPECT_LE(worst, tolerance) << presetName << " on " << meshName;
    // The host's bound of the count sizes the impulse buffer: between the two.
    const std::uint32_t capacity = gpuGenerator.impulses().capacity;
    EXPECT_GE(capacity, gpu.count);
    EXPECT_LE(capacity, gpu.candidates);
    EXPECT_EQ(ctx.validation().errors, 0u) << ctx.validation().firstError;
    std::printf("%s on %s: %zu impulses of %u candidates (bound %u), worst position difference "
                "%.3g h\n",
                presetName.c_str(), meshName.c_str(), cpu.size(), gpu.candidates, capacity,
                worst / generator.cellSize());
}

void expectSameImpulses(const std::string& presetName, const std::string& meshName,
                        std::uint32_t seed = 17) {
    expectSameImpulses(shippedPreset(presetName), meshFor(meshName), meshName, seed);
}

// Every shipped preset (each compiles its own specialization of the candidate pass).
TEST(GpuGenerate, FurOnTheBunny) {
    expectSameImpulses("fur", "bunny");
} // poisson, noise density
TEST(GpuGenerate, DenseFurOnTheBunny) {
    expectSameImpulses("fur-dense", "bunny");
}
// Clumps: the same clumped kernels on both sides (frames within the comparison's tolerance).
TEST(GpuGenerate, ClumpedFurOnTheBunny) {
    expectSameImpulses("fur-clumped", "bunny");
}
TEST(GpuGenerate, TuftedGrassOnAPlane) {
    expectSameImpulses("grass-tufts", "plane");
}
TEST(GpuGenerate, GrassOnAPlane) {
    expectSameImpulses("grass", "plane");
} // jittered
TEST(GpuGenerate, LichenOnATorus) {
    expectSameImpulses("lichen", "torus");
} // jittered, patchy
TEST(GpuGenerate, RingOnASphere) {
    expectSameImpulses("ring", "sphere");
} // jittered, gradient
TEST(GpuGenerate, UniformOnTheBunny) {
    expectSameImpulses("uniform", "bunny");
}
TEST(GpuGenerate, FlakesOnASphere) {
    expectSameImpulses("flakes", "sphere");
}

// The jittered lattice on a curved mesh without uvs or tangents, off the grid's axes: which
// triangle and cell a site falls in is decided from float lattice axes, identical on both sides.
TEST(GpuGenerate, JitteredOnTheBunny) {
    expectSameImpulses("grass", "bunny", 3);
    expectSameImpulses("lichen", "bunny", 5);
}

// Every field kind (constant, gradient, noise, vertex, image; scalar and RGB), a comb field,
// uvs and tangents: what the specialization constants select.
TEST(GpuGenerate, EveryFieldKindOnAPlane) {
    noise::Mesh mesh = noise::makePlane(2.0f, 16);
    mesh.attributes["heat"].resize(mesh.positions.size());
    for (std::size_t i = 0; i < mesh.positions.size(); ++i)
        mesh.attributes["heat"][i] = 0.2f + 0.6f * float(i % 7) / 6.0f;
    noise::PresetDesc preset = test::uniformPreset(3000.0f, 0.02f);
    preset.name = "every-field-kind";
    const std::string spots = std::string(SPOT_SOURCE_DIR) + "/presets/textures/density_spots.png";
    const std::string rgb =
        std::string(SPOT_TEST_TMP_DIR) + "/generate-rgb-" + std::to_string(::getpid()) + ".exr";
    {
        noise::Image img(7, 5);
        for (int y = 0; y < 5; ++y)
            for (int x = 0; x < 7; ++x)
                img.at(x, y) = glm::vec3(0.1f * float(x), 0.2f * float(y), 0.05f * float(x + y));
        noise::writeImage(rgb, img);
    }
    preset.density.kind = noise::FieldDesc::Kind::Image;
    preset.density.file = spots;
    preset.density.lo = glm::vec3(0.2f);
    noise::FieldDesc comb;
    comb.kind = noise::FieldDesc::Kind::Gradient;
    comb.components = 3;
    comb.from = glm::vec3(-1.0f, 0.0f, -1.0f);
    comb.to = glm::vec3(1.0f, 0.0f, 1.0f);
    comb.lo = glm::vec3(1.0f, 0.0f, 0.0f);
    comb.hi = glm::vec3(0.0f, 0.0f, 1.0f);
    preset.comb = comb;
    preset.tiltDeg.kind = noise::FieldDesc::Kind::Noise;
    preset.tiltDeg.frequency = 3.0f;
    preset.tiltDeg.octaves = 2;
    preset.tiltDeg.lo = glm::vec3(10.0f);
    preset.tiltDeg.hi = glm::vec3(60.0f);
    preset.spinDeg.kind = noise::FieldDesc::Kind::Gradient;
    preset.spinDeg.from = glm::vec3(0.0f, 0.0f, -1.0f);
    preset.spinDeg.to = glm::vec3(0.0f, 0.0f, 1.0f);
    preset.spinDeg.hi = glm::vec3(90.0f);
    preset.bendDeg.kind = noise::FieldDesc::Kind::Vertex;
    preset.bendDeg.attributes = {"heat"};
    preset.color.kind = noise::FieldDesc::Kind::Image;
    preset.color.components = 3;
    preset.color.file = rgb;
    preset.color.repeat = false;
    preset.weight.kind = noise::FieldDesc::Kind::Vertex;
    preset.weight.attributes = {"heat"};
    preset.scale.kind = noise::FieldDesc::Kind::Vertex;
    preset.scale.attributes = {"heat", "heat", "heat"};
    expectSameImpulses(preset, mesh, "plane");
    std::remove(rgb.c_str());
}

TEST(GpuGenerate, CellsOutsideTheViewGenerateNothing) {
    const noise::Mesh mesh = meshFor("bunny");
    const noise::PresetDesc preset =
        noise::loadPreset(std::string(SPOT_SOURCE_DIR) + "/presets/fur.json");
    const noise::ImpulseGenerator generator(mesh, preset, noise::GeneratorOptions{});
    splat::Context ctx(validated());
    splat::GpuGenerator gpuGenerator(ctx, mesh, generator);
    // A camera looking at the bunny's left half only (x < 0).
    noise::Camera cam;
    cam.eye = glm::dvec3(-0.6, 0.5, 2.0);
    cam.target = glm::dvec3(-0.6, 0.5, 0.0);
    cam.fovYDeg = 12.0;
    const noise::CameraRays rays(cam);
    const double h = generator.cellSize();
    const auto visible = [&](const noise::SurfaceCell& c) {
        return rays.boxMayBeVisible(glm::dvec3(c.ijk) * h - h, glm::dvec3(c.ijk + 1) * h + h);
    };
    const splat::GpuImpulses all = gpuGenerator.generate();
    const splat::GpuImpulses culled = gpuGenerator.generate(visible);
    EXPECT_LT(culled.cells, all.cells / 2);
    EXPECT_LT(culled.count, all.count / 2);
    EXPECT_GT(culled.count, 0u);
    const auto* g = static_cast<const gpu::SpotImpulse*>(culled.impulses.mapped());
    for (std::uint32_t i = 0; i < culled.count; ++i)
        EXPECT_LT(g[i].position.x, 0.1f); // nothing from the right half
    const splat::GpuImpulses none =
        gpuGenerator.generate([](const noise::SurfaceCell&) { return false; });
    EXPECT_EQ(none.count, 0u);
    EXPECT_EQ(none.candidates, 0u);
    EXPECT_EQ(ctx.validation().errors, 0u) << ctx.validation().firstError;
}

} // namespace

namespace {

TEST(GpuGenerate, LevelOfDetailThinsFarCellsAndConservesMass) {
    const noise::Mesh mesh = meshFor("bunny");
    const noise::PresetDesc preset =
        noise::loadPreset(std::string(SPOT_SOURCE_DIR) + "/presets/fur.json");
    const noise::ImpulseGenerator generator(mesh, preset, noise::GeneratorOptions{});
    splat::Context ctx(validated());
    splat::GpuGenerator gpuGenerator(ctx, mesh, generator);
    noise::Camera far;
    far.eye = glm::dvec3(5.2, 3.4, 10.4); // the bunny about 40 pixels tall
    far.target = glm::dvec3(0.0, 0.45, 0.0);
    far.fovYDeg = 30.0;
    far.width = far.height = 256;
    auto mass = [](const splat::GpuImpulses& g) {
        const auto* p = static_cast<const gpu::SpotImpulse*>(g.impulses.mapped());
        double sum = 0.0;
        for (std::uint32_t i = 0; i < g.count; ++i)
            sum += double(p[i].position.w); // weight
        return sum;
    };
    const splat::GpuImpulses full = gpuGenerator.generate({}, splat::lodParameters(far, 0.0));
    const splat::GpuImpulses thin = gpuGenerator.generate({}, splat::lodParameters(far, 6.0));
    EXPECT_LT(thin.count, full.count / 2);
    // Expected mass is conserved: the kept impulses carry the weight of the dropped ones.
    const double sigma = std::sqrt(double(full.count)) * 4.0; // weights up to ~4 after thinning
    EXPECT_NEAR(mass(thin), mass(full), 4.0 * sigma);
    // Close up, nothing is thinned.
    noise::Camera close = far;
    close.eye = glm::dvec3(0.8, 0.6, 1.6);
    EXPECT_EQ(gpuGenerator.generate({}, splat::lodParameters(close, 1.0)).count, full.count);
    // Off for an orthographic camera.
    noise::Camera ortho = far;
    ortho.projection = noise::Projection::Orthographic;
    EXPECT_EQ(splat::lodParameters(ortho, 6.0).w, 0.0f);
    EXPECT_EQ(ctx.validation().errors, 0u) << ctx.validation().firstError;
}

} // namespace

namespace {

// --- The persistent generation ---------------------------------------------------------------

/// A shipped preset on a mesh, its GPU generator and a validated context (shared set-up).
struct GeneratorSetup {
    GeneratorSetup(const std::string& preset, const std::string& meshName)
        : mesh(meshFor(meshName)),
          generator(mesh, shippedPreset(preset), noise::GeneratorOptions{}) {}
    noise::Mesh mesh;
    noise::ImpulseGenerator generator;
    splat::Context ctx{validated()};
    splat::GpuGenerator gpu{ctx, mesh, generator};

    /// Cells left of x (world units); all cells for a large x.
    std::function<bool(const noise::SurfaceCell&)> leftOf(double x) const {
        const double h = generator.cellSize();
        return [x, h](const noise::SurfaceCell& c) { return (c.ijk.x + 0.5) * h < x; };
    }
};

/// The impulses of the last generation read back after `record` (into a caller's command buffer,
/// followed by the caller's own copy of the impulses, in one submit).
std::vector<gpu::SpotImpulse> generateInFrame(splat::Context& ctx, splat::GpuGenerator& gpu) {
    const splat::ImpulseSet set = gpu.impulses();
    const VkDeviceSize bytes =
        std::max<VkDeviceSize>(VkDeviceSize(set.capacity) * sizeof(gpu::SpotImpulse), 16);
    splat::Buffer readback(ctx, bytes, VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                           splat::Buffer::Memory::HostVisible, "test readback");
    splat::CommandBuffer commands(ctx);
    splat::PassTimer timer(ctx);
    VkCommandBuffer cmd = commands.begin();
    timer.begin(cmd);
    gpu.record(cmd, timer);
    if (set.capacity > 0) {
        const VkBufferCopy region{0, 0, VkDeviceSize(set.capacity) * sizeof(gpu::SpotImpulse)};
        vkCmdCopyBuffer(cmd, set.impulses->handle(), readback.handle(), 1, &region);
        splat::memoryBarrier(cmd, VK_PIPELINE_STAGE_2_ALL_TRANSFER_BIT,
                             VK_ACCESS_2_TRANSFER_WRITE_BIT, VK_PIPELINE_STAGE_2_HOST_BIT,
                             VK_ACCESS_2_HOST_READ_BIT);
    }
    commands.submitAndWait();
    EXPECT_EQ(timer.passMilliseconds().size(), 1u);
    EXPECT_EQ(timer.passMilliseconds().front().first, "generate");
    const std::uint32_t count = gpu.count();
    EXPECT_EQ(*static_cast<const std::uint32_t*>(set.count->mapped()), count);
    EXPECT_LE(count, set.capacity);
    const auto* p = static_cast<const gpu::SpotImpulse*>(readback.mapped());
    return std::vector<gpu::SpotImpulse>(p, p + count);
}

/// Byte-identical impulses (the generation is deterministic).
void expectIdentical(const std::vector<gpu::SpotImpulse>& a, const splat::GpuImpulses& b) {
    ASSERT_EQ(a.size(), b.count);
    EXPECT_EQ(std::memcmp(a.data(), b.impulses.mapped(), a.size() * sizeof(gpu::SpotImpulse)), 0);
}

void expectPersistentEqualsOneShot(const std::string& preset, const std::string& meshName) {
    SCOPED_TRACE(preset + " on " + meshName);
    GeneratorSetup s(preset, meshName);
    const glm::vec4 lod(0.3f, 2.0f, 3.0f, 40.0f); // thins some cells: the LOD variant too
    const splat::GpuImpulses oneShot = s.gpu.generate(s.leftOf(0.0), lod);
    ASSERT_GT(oneShot.count, 1000u);

    splat::GpuGenerator fresh(s.ctx, s.mesh, s.generator);
    ASSERT_TRUE(fresh.prepare(s.leftOf(0.0), lod));
    EXPECT_EQ(fresh.candidates(), oneShot.candidates);
    EXPECT_EQ(fresh.cells(), oneShot.cells);
    expectIdentical(generateInFrame(s.ctx, fresh), oneShot);
    EXPECT_EQ(fresh.count(), oneShot.count);
    test::expectNoValidationErrors(s.ctx);
}

TEST(GpuGenerate, PersistentGenerationInACallersFrameEqualsTheOneShot) {
    expectPersistentEqualsOneShot("fur", "bunny");    // Poisson
    expectPersistentEqualsOneShot("lichen", "torus"); // jittered: the host lists the sites
}

TEST(GpuGenerate, PrepareRegeneratesOnlyWhenTheCellsOrTheLevelOfDetailChange) {
    GeneratorSetup s("fur", "bunny");
    const glm::vec4 lodOff(0.0f);
    const glm::vec4 lodOn(0.3f, 2.0f, 3.0f, 40.0f);
    ASSERT_TRUE(s.gpu.prepare(s.leftOf(0.0), lodOff));
    const std::uint64_t first = s.gpu.impulses().version;
    generateInFrame(s.ctx, s.gpu);
    EXPECT_FALSE(s.gpu.prepare(s.leftOf(0.0), lodOff)); // same cells, same lod: impulses stand
    EXPECT_EQ(s.gpu.impulses().version, first);
    EXPECT_TRUE(s.gpu.prepare(s.leftOf(0.05), lodOff)); // more cells
    EXPECT_GT(s.gpu.impulses().version, first);
    generateInFrame(s.ctx, s.gpu);
    EXPECT_TRUE(s.gpu.prepare(s.leftOf(0.05), lodOn)); // same cells, another lod
    generateInFrame(s.ctx, s.gpu);
    EXPECT_FALSE(s.gpu.prepare(s.leftOf(0.05), lodOn));
    EXPECT_TRUE(s.gpu.prepare({}, lodOn));             // all cells
    EXPECT_FALSE(s.gpu.prepare(s.leftOf(1e9), lodOn)); // ... the same cells, chosen otherwise
    test::expectNoValidationErrors(s.ctx);
}

void expectRegrowthKeepsResults(const std::string& preset, const std::string& meshName) {
    SCOPED_TRACE(preset + " on " + meshName);
    GeneratorSetup s(preset, meshName);
    // Small, then everything (the buffers grow), then small again: the same impulses.
    ASSERT_TRUE(s.gpu.prepare(s.leftOf(-0.4), glm::vec4(0.0f)));
    const std::vector<gpu::SpotImpulse> small = generateInFrame(s.ctx, s.gpu);
    ASSERT_GT(small.size(), 100u);
    const std::uint64_t allocatedSmall = s.ctx.allocatedBytes();
    ASSERT_TRUE(s.gpu.prepare({}, glm::vec4(0.0f)));
    const std::vector<gpu::SpotImpulse> all = generateInFrame(s.ctx, s.gpu);
    ASSERT_GT(all.size(), 2 * small.size());
    // Now large enough: frames that need no more room allocate nothing, regenerating or not.
    const std::uint64_t allocated = s.ctx.allocatedBytes();
    EXPECT_GT(allocated, allocatedSmall); // the buffers did grow
    ASSERT_TRUE(s.gpu.prepare(s.leftOf(-0.4), glm::vec4(0.0f)));
    const std::vector<gpu::SpotImpulse> smallAgain = generateInFrame(s.ctx, s.gpu);
    ASSERT_EQ(smallAgain.size(), small.size());
    EXPECT_EQ(std::memcmp(smallAgain.data(), small.data(), small.size() * sizeof(gpu::SpotImpulse)),
              0);
    EXPECT_FALSE(s.gpu.prepare(s.leftOf(-0.4), glm::vec4(0.0f)));
    EXPECT_TRUE(s.gpu.prepare(s.leftOf(0.0), glm::vec4(0.0f)));
    generateInFrame(s.ctx, s.gpu);
    EXPECT_TRUE(s.gpu.prepare({}, glm::vec4(0.0f)));
    const std::vector<gpu::SpotImpulse> allAgain = generateInFrame(s.ctx, s.gpu);
    EXPECT_EQ(s.ctx.allocatedBytes(), allocated);
    ASSERT_EQ(allAgain.size(), all.size());
    EXPECT_EQ(std::memcmp(allAgain.data(), all.data(), all.size() * sizeof(gpu::SpotImpulse)), 0);
    // ... and equal what a generator that never grew makes.
    splat::GpuGenerator fresh(s.ctx, s.mesh, s.generator);
    expectIdentical(all, fresh.generate());
    test::expectNoValidationErrors(s.ctx);
}

TEST(GpuGenerate, RegrowthKeepsResultsAndAFrameLikeTheLastAllocatesNothing) {
    expectRegrowthKeepsResults("fur", "bunny");
    expectRegrowthKeepsResults("lichen", "torus");
}

} // namespace
