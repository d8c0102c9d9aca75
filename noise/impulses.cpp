#include "impulses.h"

#include <algorithm>
#include <cmath>

#include <tbb/parallel_for.h>

#include "error.h"
#include "mesh.h"
#include "shaders/spot_shared.hpp"
#include "surface.h"
#include "system.h"
#include "generator_shared.h"
#include "shared_data.h"

namespace spot::noise {


namespace {

/// Expected candidates of one cell above which we refuse: keeps every per-cell loop far below
/// lavapipe's 65,535-iteration limit (the GPU twin runs the same loops) and memory per cell small.
constexpr double kMaxExpectedPerCell = 4096.0;

std::unique_ptr<Field> bind(const FieldDesc& desc, const Mesh& mesh, const PresetDesc& preset,
                            const char* slot) {
    return makeField(desc, mesh, preset.baseDir, cat("preset ", preset.name, ", fields.", slot));
}

} // namespace

ImpulseGenerator::ImpulseGenerator(const Mesh& mesh, const PresetDesc& preset,
                                   const GeneratorOptions& options)
    : m_mesh(mesh), m_preset(preset), m_options(options) {
    m_fields.density = bind(preset.density, mesh, preset, "density");
    if (preset.comb)
        m_fields.comb = bind(*preset.comb, mesh, preset, "comb");
    m_fields.tiltDeg = bind(preset.tiltDeg, mesh, preset, "tilt_deg");
    m_fields.spinDeg = bind(preset.spinDeg, mesh, preset, "spin_deg");
    m_fields.bendDeg = bind(preset.bendDeg, mesh, preset, "bend_deg");
    m_fields.scale = bind(preset.scale, mesh, preset, "scale");
    m_fields.color = bind(preset.color, mesh, preset, "color");
    m_fields.weight = bind(preset.weight, mesh, preset, "weight");
    m_kernel = buildKernel(preset.kernel);

    m_minCellSize = minimumCellSizeFor(*m_fields.scale);
    if (!(m_minCellSize > 0.0f) || !std::isfinite(m_minCellSize))
        throw InputError(cat("preset ", preset.name, ": kernel support radius ", m_minCellSize,
                             " world units is not a usable cell size"));
    float h = options.cellSize;
    if (h == 0.0f) {
        h = m_minCellSize;
    } else if (!(h >= m_minCellSize * (1.0f - 1e-6f)) || !std::isfinite(h)) {
        throw InputError(cat("cell size ", h, " is smaller than the kernel's support radius ",
                             m_minCellSize, " (preset ", preset.name,
                             "): kernels would reach beyond the neighbouring cells"));
    }

    // Budget the impulses before building anything large.
    const double expected = preset.distribution.densityMax * mesh.surfaceArea() *
                            std::clamp(double(m_fields.density->range().hi.x), 0.0, 1.0);
    requireMemory(std::uint64_t((expected * 1.1 + 1024.0) * sizeof(Impulse)),
                  cat(std::llround(expected), " impulses of preset ", preset.name));

    m_cells = buildSurfaceCells(mesh, h, options.limits);

    float maxArea = 0.0f;
    for (const SurfaceCell& c : m_cells.cells)
        maxArea = std::max(maxArea, c.area);
    const double perCell = double(maxArea) * preset.distribution.densityMax;
    if (perCell > kMaxExpectedPerCell)
        throw InputError(cat("preset ", preset.name, ": density_max ",
                             preset.distribution.densityMax, " puts up to ", std::llround(perCell),
                             " impulses in one cell of size ", h, " (limit ", kMaxExpectedPerCell,
                             "); lower density_max or the cell size"));
    buildSharedData();
    if (preset.distribution.type == DistributionType::Jittered) {
        // Lattice sites examined per cell: capped by the shared generator, so refuse when a cell
        // would reach the cap (it would drop sites).
        shared::f32::SharedGenerator generator(arrays());
        for (const SurfaceCell& c : m_cells.cells)
            if (generator.spotCellCandidates(gpu::toGpu(c)) >= shared::f32::kMaxCandidatesPerCell)
                throw InputError(cat("preset ", preset.name, ": density_max ",
                                     preset.distribution.densityMax,
                                     " puts too many lattice sites in one cell of size ", h,
                                     "; lower density_max"));
    }
}

ImpulseGenerator::~ImpulseGenerator() = default;

float ImpulseGenerator::minimumCellSizeFor(const Field& scale) const {
    const FieldRange scaleRange = scale.range();
    const float maxScale = std::max({scaleRange.hi.x, scaleRange.hi.y, scaleRange.hi.z}) *
                           (1.0f + m_preset.variation.scale);
    return m_kernel.supportRadius() * maxScale + std::abs(m_preset.distribution.heightOffset) +
           m_preset.distribution.heightJitter;
}

std::unique_ptr<Field>& ImpulseGenerator::boundField(int slot) {
    switch (slot) {
    case SPOT_FIELD_DENSITY: return m_fields.density;
    case SPOT_FIELD_COMB: return m_fields.comb;
    case SPOT_FIELD_TILT: return m_fields.tiltDeg;
    case SPOT_FIELD_SPIN: return m_fields.spinDeg;
    case SPOT_FIELD_BEND: return m_fields.bendDeg;
    case SPOT_FIELD_SCALE: return m_fields.scale;
    case SPOT_FIELD_COLOR: return m_fields.color;
    case SPOT_FIELD_WEIGHT: return m_fields.weight;
    }
    throw InputError(cat("field slot ", slot, " is not one of 0..", SPOT_FIELD_COUNT - 1));
}

const FieldDesc* ImpulseGenerator::fieldDesc(int slot) const {
    switch (slot) {
    case SPOT_FIELD_DENSITY: return &m_preset.density;
    case SPOT_FIELD_COMB: return m_preset.comb ? &*m_preset.comb : nullptr;
    case SPOT_FIELD_TILT: return &m_preset.tiltDeg;
    case SPOT_FIELD_SPIN: return &m_preset.spinDeg;
    case SPOT_FIELD_BEND: return &m_preset.bendDeg;
    case SPOT_FIELD_SCALE: return &m_preset.scale;
    case SPOT_FIELD_COLOR: return &m_preset.color;
    case SPOT_FIELD_WEIGHT: return &m_preset.weight;
    }
    throw InputError(cat("field slot ", slot, " is not one of 0..", SPOT_FIELD_COUNT - 1));
}

void ImpulseGenerator::setField(int slot, const FieldDesc& desc) {
    static const char* const kNames[SPOT_FIELD_COUNT] = {
        "density", "comb", "tilt_deg", "spin_deg", "bend_deg", "scale", "color", "weight"};
    std::unique_ptr<Field>& bound = boundField(slot);
    const int components =
        slot == SPOT_FIELD_COMB || slot == SPOT_FIELD_SCALE || slot == SPOT_FIELD_COLOR ? 3 : 1;
    if (desc.components != components)
        throw InputError(cat("fields.", kNames[slot], " has ", components,
                             components == 1 ? " component" : " components", ", not ",
                             desc.components));
    std::unique_ptr<Field> field = bind(desc, m_mesh, m_preset, kNames[slot]);
    if (slot == SPOT_FIELD_SCALE) {
        const float need = minimumCellSizeFor(*field);
        if (!(need <= m_cells.cellSize * (1.0f + 1e-6f)))
            throw InputError(cat("preset ", m_preset.name, ", fields.scale: the scale needs cells of ",
                                 need, " world units, larger than the generator's ",
                                 m_cells.cellSize));
    }
    std::swap(bound, field);
    try {
        buildFieldData();
    } catch (...) {
        std::swap(bound, field); // the previous fields flatten as before
        buildFieldData();
        throw;
    }
    switch (slot) {
    case SPOT_FIELD_DENSITY: m_preset.density = desc; break;
    case SPOT_FIELD_COMB: m_preset.comb = desc; break;
    case SPOT_FIELD_TILT: m_preset.tiltDeg = desc; break;
    case SPOT_FIELD_SPIN: m_preset.spinDeg = desc; break;
    case SPOT_FIELD_BEND: m_preset.bendDeg = desc; break;
    case SPOT_FIELD_SCALE: m_preset.scale = desc; m_minCellSize = minimumCellSizeFor(*bound); break;
    case SPOT_FIELD_COLOR: m_preset.color = desc; break;
    case SPOT_FIELD_WEIGHT: m_preset.weight = desc; break;
    }
}

void ImpulseGenerator::refreshFields() {
    const float need = minimumCellSizeFor(*m_fields.scale);
    if (!(need <= m_cells.cellSize * (1.0f + 1e-6f)))
        throw InputError(cat("preset ", m_preset.name, ", fields.scale: the scale needs cells of ",
                             need, " world units, larger than the generator's ",
                             m_cells.cellSize));
    buildFieldData();
    m_minCellSize = need;
}

void ImpulseGenerator::buildSharedData() {
    m_sharedPieces = gpu::piecesToGpu(m_cells);
    buildFieldData();
}

void ImpulseGenerator::buildFieldData() {
    std::vector<float> data;
    const DistributionDesc& d = m_preset.distribution;
    const VariationDesc& v = m_preset.variation;
    m_params.distribution = glm::vec4(d.densityMax, d.jitter, d.heightOffset, d.heightJitter);
    m_params.variation0 = glm::vec4(v.tiltDeg, v.spinDeg, v.bendDeg, v.scale);
    m_params.variation1 = glm::vec4(v.color, v.weight, m_cells.cellSize,
                                    1.0f / std::sqrt(d.densityMax));
    m_params.flags = glm::uvec4(m_options.seed, d.type == DistributionType::Jittered ? 1u : 0u,
                                m_fields.comb ? 1u : 0u,
                                (m_mesh.hasUv() ? 1u : 0u) | (m_mesh.tangents.empty() ? 0u : 2u));
    const Field* slots[SPOT_FIELD_COUNT] = {m_fields.density.get(), m_fields.comb.get(),
                                            m_fields.tiltDeg.get(), m_fields.spinDeg.get(),
                                            m_fields.bendDeg.get(), m_fields.scale.get(),
                                            m_fields.color.get(),   m_fields.weight.get()};
    gpu::SpotField fields[SPOT_FIELD_COUNT];
    for (int i = 0; i < SPOT_FIELD_COUNT; ++i)
        fields[i] = slots[i] ? slots[i]->shared(data) : gpu::SpotField{};
    // Nothing changes until every field is flattened (a painted grid may refuse).
    m_fieldData = std::move(data);
    std::copy(std::begin(fields), std::end(fields), std::begin(m_params.fields));
}

shared::f32::GeneratorArrays ImpulseGenerator::arrays() const {
    shared::f32::GeneratorArrays a;
    a.triangles = m_mesh.triangles.data();
    a.positions = m_mesh.positions.data();
    a.normals = m_mesh.normals.data();
    a.tangents = m_mesh.tangents.empty() ? nullptr : m_mesh.tangents.data();
    a.uvs = m_mesh.uvs.empty() ? nullptr : m_mesh.uvs.data();
    a.pieces = m_sharedPieces.data();
    a.fieldData = m_fieldData.data();
    a.params = &m_params;
    return a;
}

void ImpulseGenerator::generateCell(std::size_t cellIndex, std::vector<Impulse>& out) const {
    shared::f32::SharedGenerator generator(arrays());
    const gpu::SpotCell cell = gpu::toGpu(m_cells.cells.at(cellIndex));
    const std::uint32_t candidates = generator.spotCellCandidates(cell);
    gpu::SpotImpulse impulse;
    for (std::uint32_t m = 0; m < candidates; ++m)
        if (generator.spotCandidate(cell, m, impulse))
            out.push_back(gpu::fromGpu(impulse));
}

std::vector<Impulse> ImpulseGenerator::generate(
    const std::function<bool(const SurfaceCell&)>& keep) const {
    std::vector<std::uint32_t> selected;
    double area = 0.0;
    for (std::size_t c = 0; c < m_cells.cells.size(); ++c)
        if (!keep || keep(m_cells.cells[c])) {
            selected.push_back(std::uint32_t(c));
            area += m_cells.cells[c].area;
        }
    const double expected = m_preset.distribution.densityMax * area;
    requireMemory(std::uint64_t((2.0 * expected + 6.0 * std::sqrt(expected) + 1024.0) *
                                sizeof(Impulse)),
                  cat(std::llround(expected), " impulses"));

    std::vector<std::vector<Impulse>> perCell(selected.size());
    tbb::parallel_for(std::size_t(0), selected.size(),
                      [&](std::size_t i) { generateCell(selected[i], perCell[i]); });
    std::size_t total = 0;
    for (const auto& v : perCell)
        total += v.size();
    std::vector<Impulse> all;
    all.reserve(total);
    for (auto& v : perCell) {
        all.insert(all.end(), v.begin(), v.end());
        std::vector<Impulse>().swap(v);
    }
    return all;
}

} // namespace spot::noise
