#include "impulses.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <iterator>

#include <tbb/parallel_for.h>

#include "error.h"
#include "mesh.h"
#include "shaders/spot_shared.hpp"
#include "surface.h"
#include "system.h"
#include "generator_shared.h"
#include "shared_data.h"

namespace spot::noise {

using Generator = shared::f32::SharedGenerator;

namespace {

/// Expected candidates of one cell above which we refuse: keeps every per-cell loop far below
/// lavapipe's 65,535-iteration limit (the GPU twin runs the same loops) and memory per cell small.
constexpr double kMaxExpectedPerCell = 4096.0;

std::unique_ptr<Field> bind(const FieldDesc& desc, const Mesh& mesh, const PresetDesc& preset,
                            int slot) {
    return makeField(desc, mesh, preset.baseDir,
                     cat("preset ", preset.name, ", fields.", kFieldSlots[slot].key));
}

} // namespace

float clumpTipHeight(const KernelDesc& kernel) {
    float tip = 0.0f;
    for (const LobeDesc& lobe : kernel.lobes)
        tip = std::max(tip, lobe.offset.z + lobe.sigma.z);
    return std::max(tip, 1e-3f);
}

ImpulseGenerator::ImpulseGenerator(const Mesh& mesh, const PresetDesc& preset,
                                   const GeneratorOptions& options)
    : m_mesh(mesh), m_preset(preset), m_options(options) {
    for (const FieldSlot& slot : kFieldSlots)
        if (const FieldDesc* desc = presetField(preset, slot.index))
            m_fields[slot.index] = bind(*desc, mesh, preset, slot.index);
    m_kernel = buildKernel(preset.kernel);

    m_minCellSize = minimumCellSizeFor(*m_fields[SPOT_FIELD_SCALE]);
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
                            std::clamp(double(m_fields[SPOT_FIELD_DENSITY]->range().hi.x), 0.0, 1.0);
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

const FieldDesc* ImpulseGenerator::fieldDesc(int slot) const {
    return presetField(m_preset, slot);
}

void ImpulseGenerator::setField(int slot, const FieldDesc& desc) {
    if (slot < 0 || slot >= kFieldSlotCount)
        throw InputError(cat("field slot ", slot, " is not one of 0..", kFieldSlotCount - 1));
    const FieldSlot& info = kFieldSlots[slot];
    if (desc.components != info.components)
        throw InputError(cat("fields.", info.key, " has ", info.components,
                             info.components == 1 ? " component" : " components", ", not ",
                             desc.components));
    std::unique_ptr<Field>& bound = m_fields[slot];
    std::unique_ptr<Field> field = bind(desc, m_mesh, m_preset, slot);
    if (slot == SPOT_FIELD_SCALE) {
        const float need = minimumCellSizeFor(*field);
        if (!(need <= m_cells.cellSize * (1.0f + 1e-6f)))
            throw InputError(cat("preset ", m_preset.name, ", fields.scale: the scale needs cells of ",
                                 need, " world units, larger than the generator's ",
                                 m_cells.cellSize));
    }
    // The description first: the shared form reads its mask (buildFieldData).
    const PresetDesc before = m_preset;
    if (info.optional)
        m_preset.comb = desc;
    else
        *presetField(m_preset, slot) = desc;
    if (slot == SPOT_FIELD_CLUMP)
        m_preset.clumpDesc.on = m_preset.clumpDesc.on || clumpFieldSet(desc);
    std::swap(bound, field);
    try {
        buildFieldData();
    } catch (...) {
        std::swap(bound, field); // the previous fields flatten as before
        m_preset = before;
        buildFieldData();
        throw;
    }
    if (slot == SPOT_FIELD_SCALE)
        m_minCellSize = minimumCellSizeFor(*bound);
}

void ImpulseGenerator::refreshFields() {
    const float need = minimumCellSizeFor(*m_fields[SPOT_FIELD_SCALE]);
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
                                m_fields[SPOT_FIELD_COMB] ? 1u : 0u,
                                (m_mesh.hasUv() ? 1u : 0u) | (m_mesh.tangents.empty() ? 0u : 2u));
    const ClumpDesc& c = m_preset.clumpDesc;
    m_params.clump = glm::vec4(c.size, c.variation, c.shape, clumpTipHeight(m_preset.kernel));
    m_params.clump2 = glm::vec4(c.secondarySize, c.secondaryStrength, v.clump, 0.0f);
    const std::uint32_t clumpBits =
        (c.on ? Generator::kClumpOn : 0u) |
        (c.on && c.secondarySize > 0.0f ? Generator::kClumpSecondary : 0u) |
        (m_maskOverlay ? Generator::kClumpMaskOverlay : 0u);
    m_params.clumpFlags =
        glm::uvec4(shared::f32::spotHashCombine(shared::f32::spotHash(m_options.seed ^ 0x85ebca6bu),
                                                c.seed),
                   clumpBits, 0u, 0u);
    gpu::SpotField fields[SPOT_FIELD_COUNT];
    for (int i = 0; i < SPOT_FIELD_COUNT; ++i) {
        fields[i] = m_fields[i] ? m_fields[i]->shared(data) : gpu::SpotField{};
        const FieldDesc* desc = presetField(m_preset, i);
        if (!desc || desc->mask == FieldDesc::MaskUse::None || !m_fields[i])
            continue;
        // Limited to the mask (spot_generate.h spotSlotValue): the value outside it, and a flag.
        const float e[4] = {desc->maskElse.x, desc->maskElse.y, desc->maskElse.z, 0.0f};
        SPOT_CHECK_LE(data.size() + 4, std::size_t(UINT32_MAX));
        const auto at = static_cast<std::uint32_t>(data.size());
        data.insert(data.end(), std::begin(e), std::end(e));
        fields[i].value.w = std::bit_cast<float>(at);
        fields[i].kind.x |= desc->mask == FieldDesc::MaskUse::Inside ? Generator::kFieldMaskedInside
                                                                     : Generator::kFieldMaskedOutside;
    }
    // Nothing changes until every field is flattened (a painted grid may refuse).
    m_fieldData = std::move(data);
    std::copy(std::begin(fields), std::end(fields), std::begin(m_params.fields));
}

void ImpulseGenerator::setMaskOverlay(bool on) {
    if (on == m_maskOverlay)
        return;
    m_maskOverlay = on;
    buildFieldData();
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
