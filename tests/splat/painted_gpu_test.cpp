// The painted field on the GPU (shaders/spot_generate.h kind 5): the impulses of a preset with
// painted density, comb and colour equal the CPU generator's, before and after the grids are
// painted in place and the fields refreshed; a frame shows the change on its next render.
#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "../noise/test_support.h"
#include "noise/impulses.h"
#include "noise/mesh.h"
#include "noise/painted.h"
#include "noise/shared_data.h"
#include "splat/frame_vk.h"
#include "splat/generate_vk.h"
#include "splat_test_support.h"

namespace {

using namespace spot;
using namespace spot::noise;

struct Rng {
    std::uint32_t h = 12345;
    float operator()() {
        h = h * 1664525u + 1013904223u;
        return float(h >> 8) / float(1u << 24);
    }
};

FieldDesc paintedDesc(std::shared_ptr<PaintedGrid> grid) {
    FieldDesc d;
    d.kind = FieldDesc::Kind::Painted;
    d.components = grid->components();
    d.painted = std::move(grid);
    return d;
}

/// Grids over the unit sphere (voxel 0.08): density in [0, 1], comb directions, colours, each
/// with random voxels painted near the surface.
struct Grids {
    std::shared_ptr<PaintedGrid> density =
        std::make_shared<PaintedGrid>("density", 1, 0.08f, glm::vec3(0.7f));
    std::shared_ptr<PaintedGrid> comb =
        std::make_shared<PaintedGrid>("comb", 3, 0.08f, glm::vec3(0.0f, 1.0f, 0.0f));
    std::shared_ptr<PaintedGrid> color =
        std::make_shared<PaintedGrid>("color", 3, 0.08f, glm::vec3(0.6f, 0.4f, 0.2f));

    void paint(Rng& rnd, int voxels) {
        for (int i = 0; i < voxels; ++i) {
            const glm::vec3 dir =
                glm::normalize(glm::vec3(rnd() - 0.5f, rnd() - 0.5f, rnd() - 0.5f) + 1e-3f);
            const glm::ivec3 v = density->nearestVoxel(dir * (0.9f + 0.2f * rnd()));
            density->set(v, glm::vec3(rnd()));
            comb->set(v, glm::vec3(rnd() - 0.5f, rnd() - 0.5f, rnd() - 0.5f));
            color->set(v, glm::vec3(rnd(), rnd(), rnd()));
        }
    }
};

struct Comparison {
    std::size_t count = 0;
    float worstColor = 0.0f, worstPosition = 0.0f;
    std::size_t colorDiffer = 0;
};

/// CPU and GPU impulses of `generator`: the same count, cells and triangles. Poisson (`exact`):
/// the same anchors, and colours, scales and weights (which the painted fields decide with no
/// trigonometry) bit for bit. Jittered: the lattice sites' barycentric coordinates may differ in
/// their last bits between the two sides (as they do with constant fields: generate_test.cpp), so
/// the painted values read there agree to a tolerance.
Comparison compare(const ImpulseGenerator& generator, splat::GpuGenerator& gpuGenerator,
                   bool exact) {
    const std::vector<Impulse> cpu = generator.generate();
    const splat::GpuImpulses gpu = gpuGenerator.generate();
    Comparison c;
    c.count = cpu.size();
    EXPECT_EQ(gpu.count, cpu.size());
    if (gpu.count != cpu.size())
        return c;
    const auto* g = static_cast<const gpu::SpotImpulse*>(gpu.impulses.mapped());
    for (std::size_t i = 0; i < cpu.size(); ++i) {
        const Impulse m = gpu::fromGpu(g[i]);
        EXPECT_EQ(m.cell, cpu[i].cell) << i;
        EXPECT_EQ(m.triangle, cpu[i].triangle) << i;
        if (exact) {
            EXPECT_EQ(m.barycentric, cpu[i].barycentric) << i;
            EXPECT_EQ(m.scale, cpu[i].scale) << i;
            EXPECT_EQ(m.weight, cpu[i].weight) << i;
        } else {
            EXPECT_LE(glm::length(m.barycentric - cpu[i].barycentric), 1e-4f) << i;
            EXPECT_LE(glm::length(m.position - cpu[i].position), 1e-5f) << i;
            EXPECT_NEAR(m.weight, cpu[i].weight, 1e-4f) << i;
        }
        EXPECT_GT(glm::dot(m.frame[0], cpu[i].frame[0]), 0.9999f) << i;
        EXPECT_GT(glm::dot(m.frame[2], cpu[i].frame[2]), 0.9999f) << i;
        c.colorDiffer += m.color != cpu[i].color;
        const glm::vec3 d = glm::abs(m.color - cpu[i].color);
        c.worstColor = std::max({c.worstColor, d.x, d.y, d.z});
        c.worstPosition = std::max(c.worstPosition, glm::length(m.position - cpu[i].position));
    }
    if (exact)
        EXPECT_EQ(c.colorDiffer, 0u) << "worst colour difference " << c.worstColor;
    else
        EXPECT_LE(c.worstColor, 1e-4f);
    return c;
}

class PaintedGpu : public ::testing::TestWithParam<DistributionType> {};

TEST_P(PaintedGpu, DensityCombAndColourGiveTheCpuImpulses) {
    const Mesh mesh = makeSphere(1.0f, 32, 64);
    Grids grids;
    Rng rnd;
    grids.paint(rnd, 3000);
    PresetDesc preset = test::uniformPreset(4000.0f, 0.01f, GetParam());
    preset.density = paintedDesc(grids.density);
    preset.comb = paintedDesc(grids.comb);
    preset.color = paintedDesc(grids.color);
    GeneratorOptions options;
    options.seed = 11;
    ImpulseGenerator generator(mesh, preset, options);

    splat::Context ctx(test::validated());
    splat::GpuGenerator gpuGenerator(ctx, mesh, generator);
    const bool exact = GetParam() == DistributionType::Poisson;
    const Comparison before = compare(generator, gpuGenerator, exact);
    EXPECT_GT(before.count, 5000u);

    // Paint more in place, refresh both sides: they still agree, on the new grids.
    grids.paint(rnd, 6000);
    generator.refreshFields();
    gpuGenerator.refreshFields();
    const Comparison after = compare(generator, gpuGenerator, exact);
    EXPECT_NE(after.count, before.count);

    // A slot changing kind (constant -> painted weight) re-specializes the pipeline.
    auto weight = std::make_shared<PaintedGrid>("weight", 1, 0.08f, glm::vec3(0.5f));
    weight->set(glm::ivec3(0, 12, 0), glm::vec3(2.0f));
    generator.setField(SPOT_FIELD_WEIGHT, paintedDesc(weight));
    gpuGenerator.refreshFields();
    compare(generator, gpuGenerator, exact);
    test::expectNoValidationErrors(ctx);
    std::printf("%zu then %zu impulses; worst position difference %.3g, worst colour difference "
                "%.3g\n",
                before.count, after.count,
                double(std::max(before.worstPosition, after.worstPosition)),
                double(std::max(before.worstColor, after.worstColor)));
}

// Paint layers over procedural fields on the GPU (spotFieldLayer): a noise density under a
// multiplier and raise layer, the surface tangent (an unset comb) and a gradient colour under
// override layers. The impulses equal the CPU generator's, before and after the layers are painted
// in place; an empty layer gives the base's impulses bit for bit.
TEST(PaintedGpuLayers, LayersOverProceduralFieldsGiveTheCpuImpulses) {
    const Mesh mesh = makeSphere(1.0f, 32, 64);
    PresetDesc preset = test::uniformPreset(4000.0f, 0.01f, DistributionType::Poisson);
    preset.density.kind = FieldDesc::Kind::Noise;
    preset.density.frequency = 3.0f;
    preset.density.octaves = 2;
    preset.density.seed = 5;
    preset.density.lo = glm::vec3(0.3f, 0.0f, 0.0f);
    preset.density.hi = glm::vec3(0.9f, 0.0f, 0.0f);
    preset.color.kind = FieldDesc::Kind::Gradient;
    preset.color.from = glm::vec3(0.0f, -1.0f, 0.0f);
    preset.color.to = glm::vec3(0.0f, 1.0f, 0.0f);
    preset.color.lo = glm::vec3(0.2f, 0.3f, 0.4f);
    preset.color.hi = glm::vec3(0.9f, 0.6f, 0.1f);
    GeneratorOptions options;
    options.seed = 11;
    const std::vector<Impulse> unlayered = ImpulseGenerator(mesh, preset, options).generate();

    auto density = std::make_shared<PaintLayer>("density.paint", 1, 0.08f, PaintMode::Density);
    auto comb = std::make_shared<PaintLayer>("comb.paint", 3, 0.08f, PaintMode::Override);
    auto color = std::make_shared<PaintLayer>("color.paint", 3, 0.08f, PaintMode::Override);
    const auto layered = [](FieldDesc d, std::shared_ptr<PaintLayer> layer) {
        d.paint = FieldDesc::Paint{"", "", layer->mode(), std::move(layer)};
        return d;
    };
    preset.density = layered(preset.density, density);
    FieldDesc tangent;
    tangent.kind = FieldDesc::Kind::Tangent;
    tangent.components = 3;
    preset.comb = layered(tangent, comb);
    preset.color = layered(preset.color, color);
    ImpulseGenerator generator(mesh, preset, options);
    const std::vector<Impulse> empty = generator.generate();
    ASSERT_EQ(empty.size(), unlayered.size()) << "empty layers";
    for (std::size_t i = 0; i < empty.size(); ++i) {
        EXPECT_EQ(empty[i].position, unlayered[i].position) << i;
        EXPECT_EQ(empty[i].comb, unlayered[i].comb) << i;
        EXPECT_EQ(empty[i].color, unlayered[i].color) << i;
        EXPECT_EQ(empty[i].frame, unlayered[i].frame) << i;
    }

    splat::Context ctx(test::validated());
    splat::GpuGenerator gpuGenerator(ctx, mesh, generator);
    compare(generator, gpuGenerator, true);

    Rng rnd;
    for (int i = 0; i < 6000; ++i) {
        const glm::vec3 dir =
            glm::normalize(glm::vec3(rnd() - 0.5f, rnd() - 0.5f, rnd() - 0.5f) + 1e-3f);
        const glm::ivec3 v = density->value().nearestVoxel(dir * (0.9f + 0.2f * rnd()));
        density->set(v, glm::vec4(rnd(), 0.0f, 0.0f, rnd() < 0.5f ? 0.0f : rnd()));
        comb->set(v, glm::vec4(rnd() - 0.5f, rnd() - 0.5f, rnd() - 0.5f, rnd()));
        color->set(v, glm::vec4(rnd(), rnd(), rnd(), rnd()));
    }
    generator.refreshFields();
    gpuGenerator.refreshFields();
    const Comparison painted = compare(generator, gpuGenerator, true);
    EXPECT_GT(painted.count, 2000u);
    EXPECT_NE(painted.count, unlayered.size());
    test::expectNoValidationErrors(ctx);
    std::printf("layers: %zu impulses unlayered, %zu painted\n", unlayered.size(), painted.count);
}

INSTANTIATE_TEST_SUITE_P(Distributions, PaintedGpu,
                         ::testing::Values(DistributionType::Poisson, DistributionType::Jittered),
                         [](const auto& info) {
                             return info.param == DistributionType::Poisson ? "Poisson"
                                                                            : "Jittered";
                         });

TEST(PaintedGpuFrame, ShowsThePaintAfterFieldsChanged) {
    const Mesh mesh = makeSphere(1.0f, 32, 64);
    auto density = std::make_shared<PaintedGrid>("density", 1, 0.1f, glm::vec3(1.0f));
    PresetDesc preset = test::uniformPreset(3000.0f, 0.01f);
    preset.density = paintedDesc(density);
    ImpulseGenerator generator(mesh, preset, GeneratorOptions{});
    splat::Context ctx(test::validated());
    splat::Frame frame(ctx, mesh, generator);
    splat::View view;
    view.camera.eye = glm::dvec3(0.0, 0.0, 4.0);
    view.camera.target = glm::dvec3(0.0);
    view.camera.width = view.camera.height = 32;
    splat::RenderSettings settings;
    const splat::FrameStats first = frame.render("oit", view, settings);
    EXPECT_TRUE(first.regenerated);
    EXPECT_FALSE(frame.render("oit", view, settings).regenerated);
    // Paint the front half (z > 0) out.
    for (int x = -12; x <= 12; ++x)
        for (int y = -12; y <= 12; ++y)
            for (int z = 0; z <= 12; ++z)
                density->set(glm::ivec3(x, y, z), glm::vec3(0.0f));
    generator.refreshFields();
    frame.fieldsChanged();
    const splat::FrameStats second = frame.render("oit", view, settings);
    EXPECT_TRUE(second.regenerated);
    EXPECT_LT(second.kernelsGenerated, first.kernelsGenerated * 6 / 10);
    EXPECT_EQ(second.kernelsGenerated, generator.generate().size());
    test::expectNoValidationErrors(ctx);
}

/// The frame's last impulses, as the GPU wrote them.
std::vector<gpu::SpotImpulse> frameImpulses(splat::Frame& frame) {
    const splat::ImpulseSet set = frame.generator().impulses();
    const auto* g = static_cast<const gpu::SpotImpulse*>(set.impulses->mapped());
    return std::vector<gpu::SpotImpulse>(g, g + frame.generator().count());
}

bool sameBits(const std::vector<gpu::SpotImpulse>& a, const std::vector<gpu::SpotImpulse>& b) {
    return a.size() == b.size() &&
           std::memcmp(a.data(), b.data(), a.size() * sizeof(gpu::SpotImpulse)) == 0;
}

/// Paints the voxels within `radius` of `centre` with `value`; returns the model cells whose
/// candidates can read one of them (the cell's box grown by a voxel holds it).
std::vector<std::uint32_t> paintPatch(PaintedGrid& grid, const SurfaceCells& cells,
                                      glm::vec3 centre, float radius, float value) {
    const float v = grid.voxelSize();
    const glm::ivec3 lo = grid.nearestVoxel(centre - radius),
                     hi = grid.nearestVoxel(centre + radius);
    std::vector<glm::vec3> changed;
    for (int x = lo.x; x <= hi.x; ++x)
        for (int y = lo.y; y <= hi.y; ++y)
            for (int z = lo.z; z <= hi.z; ++z)
                if (glm::length(grid.voxelPosition({x, y, z}) - centre) <= radius) {
                    grid.set({x, y, z}, glm::vec3(value));
                    changed.push_back(grid.voxelPosition({x, y, z}));
                }
    std::vector<std::uint32_t> dirty;
    const float h = cells.cellSize;
    for (std::uint32_t i = 0; i < cells.cells.size(); ++i) {
        const glm::vec3 boxLo = glm::vec3(cells.cells[i].ijk) * h - v;
        const glm::vec3 boxHi = glm::vec3(cells.cells[i].ijk + 1) * h + v;
        for (const glm::vec3& p : changed)
            if (glm::all(glm::greaterThanEqual(p, boxLo)) &&
                glm::all(glm::lessThanEqual(p, boxHi))) {
                dirty.push_back(i);
                break;
            }
    }
    return dirty;
}

void regeneratesOnlyTheChangedCells(DistributionType type) {
    const Mesh mesh = makeSphere(1.0f, 32, 64);
    auto density = std::make_shared<PaintedGrid>("density", 1, 0.05f, glm::vec3(1.0f));
    PresetDesc preset = test::uniformPreset(3000.0f, 0.01f, type);
    preset.density = paintedDesc(density);
    ImpulseGenerator generator(mesh, preset, GeneratorOptions{});
    splat::Context ctx(test::validated());
    splat::Frame frame(ctx, mesh, generator);
    splat::View view;
    view.camera.eye = glm::dvec3(0.0, 0.0, 4.0);
    view.camera.target = glm::dvec3(0.0);
    view.camera.width = view.camera.height = 32;
    const splat::RenderSettings settings;
    frame.render("oit", view, settings);
    const std::vector<gpu::SpotImpulse> first = frameImpulses(frame);
    const noise::CameraRays rays(view.camera);
    const auto visible = [&](const SurfaceCell& c) { return frame.cellVisible(rays, c); };
    EXPECT_EQ(first.size(), generator.generate(visible).size());

    // A patch painted out, its cells listed: only they are generated again, and the result is
    // the full generation's, bit for bit.
    const std::vector<std::uint32_t> dirty =
        paintPatch(*density, generator.cells(), glm::vec3(0.0f, 0.0f, 1.0f), 0.3f, 0.0f);
    ASSERT_FALSE(dirty.empty());
    EXPECT_LT(dirty.size(), generator.cells().cells.size() / 4);
    generator.refreshFields();
    frame.fieldsChanged(dirty);
    const splat::FrameStats partial = frame.render("oit", view, settings);
    EXPECT_TRUE(partial.regenerated);
    const std::vector<gpu::SpotImpulse> afterPartial = frameImpulses(frame);
    EXPECT_LT(afterPartial.size(), first.size());
    EXPECT_EQ(afterPartial.size(), generator.generate(visible).size());
    frame.fieldsChanged();
    EXPECT_TRUE(frame.render("oit", view, settings).regenerated);
    EXPECT_TRUE(sameBits(afterPartial, frameImpulses(frame)));

    // Painting elsewhere without listing its cells changes nothing: the other cells are not
    // decided again.
    paintPatch(*density, generator.cells(), glm::vec3(1.0f, 0.0f, 0.0f), 0.3f, 0.0f);
    generator.refreshFields();
    frame.fieldsChanged(std::vector<std::uint32_t>{dirty.front()});
    EXPECT_TRUE(frame.render("oit", view, settings).regenerated);
    EXPECT_TRUE(sameBits(afterPartial, frameImpulses(frame)));
    // A full refresh sees it.
    frame.fieldsChanged();
    frame.render("oit", view, settings);
    EXPECT_LT(frame.generator().count(), afterPartial.size());
    EXPECT_EQ(frame.generator().count(), generator.generate(visible).size());
    test::expectNoValidationErrors(ctx);
    std::printf("%zu cells of %zu regenerated; %zu then %zu impulses\n", dirty.size(),
                generator.cells().cells.size(), first.size(), afterPartial.size());
}

TEST(PaintedGpuFrame, RegeneratesOnlyTheChangedCellsPoisson) {
    regeneratesOnlyTheChangedCells(DistributionType::Poisson);
}

TEST(PaintedGpuFrame, RegeneratesOnlyTheChangedCellsJittered) {
    regeneratesOnlyTheChangedCells(DistributionType::Jittered);
}

} // namespace
