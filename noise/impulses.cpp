#include "impulses.h"

#include <algorithm>
#include <cmath>

#include <tbb/parallel_for.h>

#include "error.h"
#include "mesh.h"
#include "shaders/spot_shared.hpp"
#include "surface.h"
#include "system.h"

namespace spot::noise {

namespace sh = spot::shared::f32;

namespace {

/// Expected candidates of one cell above which we refuse: keeps every per-cell loop far below
/// lavapipe's 65,535-iteration limit (the GPU twin runs the same loops) and memory per cell small.
constexpr double kMaxExpectedPerCell = 8192.0;

/// Offset of the jittered lattice from the plane's origin, in lattice units: irrational-looking
/// fractions put lattice sites in general position, so a regular lattice (jitter 0) never lands
/// exactly on a cell face or on an edge shared by coplanar triangles (which would make the
/// ownership of a site depend on rounding).
constexpr double kLatticeOffsetA = 0.2360679774997897;
constexpr double kLatticeOffsetB = 0.6180339887498949;

float symmetric(std::uint32_t key, std::uint32_t counter) {
    return 2.0f * sh::spotRand(key, counter) - 1.0f;
}

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

    const FieldRange scaleRange = m_fields.scale->range();
    const float maxScale = std::max({scaleRange.hi.x, scaleRange.hi.y, scaleRange.hi.z}) *
                           (1.0f + preset.variation.scale);
    m_minCellSize = m_kernel.supportRadius() * maxScale +
                    std::abs(preset.distribution.heightOffset) + preset.distribution.heightJitter;
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
}

ImpulseGenerator::~ImpulseGenerator() = default;

double ImpulseGenerator::expectedCandidates() const {
    return m_preset.distribution.densityMax * m_cells.totalArea;
}

void ImpulseGenerator::finishImpulse(const SurfaceCell& cell, std::uint32_t key,
                                     std::uint32_t triangle, glm::dvec3 bary,
                                     std::vector<Impulse>& out) const {
    const SurfacePoint sp = surfacePoint(m_mesh, triangle, bary);
    const float density = m_fields.density->eval(sp).x;
    if (!(sh::spotRand(key, sh::kRandDensity) < density))
        return;
    const VariationDesc& var = m_preset.variation;
    const DistributionDesc& dist = m_preset.distribution;

    Impulse imp;
    imp.normal = sp.normal;
    imp.height = dist.heightOffset + dist.heightJitter * symmetric(key, sh::kRandHeight);
    imp.position = sp.position + imp.height * sp.normal;
    const glm::vec3 comb = m_fields.comb ? m_fields.comb->eval(sp) : sp.tangent;
    const float tilt = glm::radians(m_fields.tiltDeg->eval(sp).x +
                                    var.tiltDeg * symmetric(key, sh::kRandTilt));
    const float spin = glm::radians(m_fields.spinDeg->eval(sp).x +
                                    var.spinDeg * symmetric(key, sh::kRandSpin));
    imp.frame = sh::spotKernelFrame(sp.normal, comb, sp.tangent, tilt, spin);
    // The comb as it lies in the tangent plane: the frame's x axis before tilt and spin.
    imp.comb = glm::normalize(imp.frame[0] * std::cos(spin) - imp.frame[1] * std::sin(spin));
    imp.comb = glm::normalize(imp.comb * std::cos(tilt) + imp.frame[2] * std::sin(tilt));
    imp.bend = glm::radians(m_fields.bendDeg->eval(sp).x +
                            var.bendDeg * symmetric(key, sh::kRandBend));
    imp.scale = m_fields.scale->eval(sp) * (1.0f + var.scale * symmetric(key, sh::kRandScale));
    imp.scale = glm::max(imp.scale, glm::vec3(1e-12f));
    imp.color = glm::clamp(m_fields.color->eval(sp) *
                               (1.0f + var.color * symmetric(key, sh::kRandColor)),
                           glm::vec3(0.0f), glm::vec3(1.0f));
    imp.weight = std::max(0.0f, m_fields.weight->eval(sp).x *
                                    (1.0f + var.weight * symmetric(key, sh::kRandWeight)));
    imp.triangle = triangle;
    imp.barycentric = glm::vec2(float(bary.y), float(bary.z));
    imp.cell = cell.ijk;
    out.push_back(imp);
}

void ImpulseGenerator::generatePoisson(const SurfaceCell& cell, std::vector<Impulse>& out) const {
    const std::uint32_t cellKey =
        sh::spotCellKey(cell.ijk.x, cell.ijk.y, cell.ijk.z, m_options.seed);
    const float lambda = m_preset.distribution.densityMax * cell.area;
    const std::uint32_t count = sh::spotPoisson(lambda, cellKey);
    const SurfacePiece* pieces = m_cells.pieces.data() + cell.firstPiece;
    for (std::uint32_t m = 0; m < count; ++m) {
        const std::uint32_t key = sh::spotImpulseKey(cellKey, m);
        // Pick a piece with probability proportional to its area, then a uniform point in it.
        float pick = sh::spotRand(key, sh::kRandPiece) * cell.area;
        std::uint32_t p = 0;
        while (p + 1 < cell.pieceCount && pick >= pieces[p].area) {
            pick -= pieces[p].area;
            ++p;
        }
        const glm::vec3 w = sh::spotSampleTriangle(sh::spotRand(key, sh::kRandBary0),
                                                   sh::spotRand(key, sh::kRandBary1));
        const glm::vec2 b = w.x * pieces[p].corner[0] + w.y * pieces[p].corner[1] +
                            w.z * pieces[p].corner[2];
        finishImpulse(cell, key, pieces[p].triangle,
                      glm::dvec3(1.0 - double(b.x) - double(b.y), b.x, b.y), out);
    }
}

void ImpulseGenerator::generateJittered(const SurfaceCell& cell, std::vector<Impulse>& out) const {
    // A square lattice of spacing 1/sqrt(density_max) in each triangle's plane, anchored at the
    // plane's point nearest the world origin and aligned with the surface tangent, so coplanar
    // triangles share one lattice. Each site is jittered by up to +-jitter/2 spacing, belongs to
    // the triangle and the cell its jittered point falls in, and draws its random numbers from
    // (triangle, site, seed), so whichever cell looks at it decides the same way.
    const double spacing = 1.0 / std::sqrt(double(m_preset.distribution.densityMax));
    const double jitter = m_preset.distribution.jitter;
    const SurfacePiece* pieces = m_cells.pieces.data() + cell.firstPiece;
    const std::uint32_t seedKey = sh::spotHash(m_options.seed ^ 0x3c6ef372u);
    for (std::uint32_t first = 0; first < cell.pieceCount;) {
        const std::uint32_t t = pieces[first].triangle;
        std::uint32_t last = first;
        while (last < cell.pieceCount && pieces[last].triangle == t)
            ++last;
        const glm::uvec3 tri = m_mesh.triangles[t];
        const glm::dvec3 p0(m_mesh.positions[tri.x]), p1(m_mesh.positions[tri.y]),
            p2(m_mesh.positions[tri.z]);
        const glm::dvec3 n = glm::normalize(glm::cross(p1 - p0, p2 - p0));
        glm::dvec3 e1(0.0);
        if (!m_mesh.tangents.empty())
            e1 = glm::dvec3(m_mesh.tangents[tri.x] + m_mesh.tangents[tri.y] +
                            m_mesh.tangents[tri.z]);
        e1 -= n * glm::dot(e1, n);
        e1 = glm::dot(e1, e1) > 1e-12 ? glm::normalize(e1)
                                      : glm::dvec3(defaultTangent(glm::vec3(n)));
        const glm::dvec3 e2 = glm::cross(n, e1);
        const glm::dvec3 origin = n * glm::dot(n, p0);

        glm::dvec2 lo(std::numeric_limits<double>::infinity()), hi(-lo);
        for (std::uint32_t p = first; p < last; ++p)
            for (const glm::vec2& c : pieces[p].corner) {
                const glm::dvec3 q = (1.0 - double(c.x) - double(c.y)) * p0 + double(c.x) * p1 +
                                     double(c.y) * p2 - origin;
                const glm::dvec2 l(glm::dot(q, e1) / spacing, glm::dot(q, e2) / spacing);
                lo = glm::min(lo, l);
                hi = glm::max(hi, l);
            }
        const glm::dvec3 v0 = p1 - p0, v1 = p2 - p0;
        const double d00 = glm::dot(v0, v0), d01 = glm::dot(v0, v1), d11 = glm::dot(v1, v1);
        const double denom = d00 * d11 - d01 * d01;
        const std::uint32_t triKey = sh::spotHashCombine(seedKey, t);
        const long a0 = long(std::ceil(lo.x - kLatticeOffsetA - 0.5 * jitter));
        const long a1 = long(std::floor(hi.x - kLatticeOffsetA + 0.5 * jitter));
        const long b0 = long(std::ceil(lo.y - kLatticeOffsetB - 0.5 * jitter));
        const long b1 = long(std::floor(hi.y - kLatticeOffsetB + 0.5 * jitter));
        for (long a = a0; a <= a1; ++a) {
            for (long b = b0; b <= b1; ++b) {
                const std::uint32_t key =
                    sh::spotHashCombine(sh::spotHashCombine(triKey, std::uint32_t(a)),
                                        std::uint32_t(b));
                const double la = double(a) + kLatticeOffsetA +
                                  jitter * (double(sh::spotRand(key, sh::kRandJitterU)) - 0.5);
                const double lb = double(b) + kLatticeOffsetB +
                                  jitter * (double(sh::spotRand(key, sh::kRandJitterV)) - 0.5);
                const glm::dvec3 point = origin + spacing * (la * e1 + lb * e2);
                const glm::dvec3 v2 = point - p0;
                const double d20 = glm::dot(v2, v0), d21 = glm::dot(v2, v1);
                const double w1 = (d11 * d20 - d01 * d21) / denom;
                const double w2 = (d00 * d21 - d01 * d20) / denom;
                const double w0 = 1.0 - w1 - w2;
                if (w0 < 0.0 || w1 < 0.0 || w2 < 0.0)
                    continue;
                if (m_cells.cellOf(glm::vec3(point)) != cell.ijk)
                    continue;
                finishImpulse(cell, key, t, glm::dvec3(w0, w1, w2), out);
            }
        }
        first = last;
    }
}

void ImpulseGenerator::generateCell(std::size_t cellIndex, std::vector<Impulse>& out) const {
    const SurfaceCell& cell = m_cells.cells.at(cellIndex);
    if (m_preset.distribution.type == DistributionType::Jittered)
        generateJittered(cell, out);
    else
        generatePoisson(cell, out);
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
