#include "edit_brush.h"

#include <algorithm>
#include <cmath>

#include "noise/error.h"
#include "noise/surface.h"
#include "shaders/spot_layout.hpp"

namespace spot::edit {

namespace {

struct KindName {
    BrushKind kind;
    const char* name;
};
constexpr KindName kKinds[] = {{BrushKind::DensityAdd, "density-add"},
                               {BrushKind::DensityErase, "density-erase"},
                               {BrushKind::Comb, "comb"},
                               {BrushKind::Tilt, "tilt"},
                               {BrushKind::Length, "length"},
                               {BrushKind::Color, "color"},
                               {BrushKind::Smooth, "smooth"}};

/// The voxel's new value under one dab of weight w = strength x falloff (w in [0, 1] except for
/// the signed kinds, which take the sign from the strength).
glm::vec3 paint(const BrushSettings& brush, const Dab& dab, const SurfaceVoxel& sv, glm::vec3 v,
                float falloff, const noise::PaintedGrid& grid) {
    const float s = brush.strength;
    const float w = std::clamp(std::abs(s) * falloff, 0.0f, 1.0f);
    switch (brush.kind) {
    case BrushKind::DensityAdd:
        return glm::vec3(v.x + (1.0f - v.x) * w, 0.0f, 0.0f);
    case BrushKind::DensityErase:
        // v (1 - w): exactly 0 for w = 1, so no impulse passes the density test there.
        return glm::vec3(v.x * (1.0f - w), 0.0f, 0.0f);
    case BrushKind::Comb: {
        const glm::vec3 n = sv.point.normal;
        glm::vec3 d = dab.direction - n * glm::dot(dab.direction, n);
        if (glm::dot(d, d) < 1e-20f)
            return v;
        d = glm::normalize(d);
        const glm::vec3 mixed =
            glm::dot(v, v) > 1e-20f ? glm::normalize(v) * (1.0f - w) + d * w : d;
        return glm::dot(mixed, mixed) > 1e-20f ? glm::normalize(mixed) : d;
    }
    case BrushKind::Tilt: {
        // Positive strength lays the strands down towards 90 degrees, negative lifts them (puff)
        // towards the normal.
        const float target = s >= 0.0f ? 90.0f : 0.0f;
        return glm::vec3(v.x + (target - v.x) * w, 0.0f, 0.0f);
    }
    case BrushKind::Length: {
        // Up to +-25% per dab; the scale stays positive.
        const float factor = std::max(1.0f + 0.25f * s * falloff, 0.05f);
        return glm::max(v * factor, glm::vec3(1e-6f));
    }
    case BrushKind::Color:
        return glm::mix(v, brush.color, w);
    case BrushKind::Smooth: {
        glm::vec3 sum(0.0f);
        constexpr glm::ivec3 kSteps[6] = {{1, 0, 0},  {-1, 0, 0}, {0, 1, 0},
                                          {0, -1, 0}, {0, 0, 1},  {0, 0, -1}};
        for (const glm::ivec3& o : kSteps)
            sum += grid.get(sv.ijk + o);
        return glm::mix(v, sum / 6.0f, w);
    }
    }
    return v;
}

} // namespace

int slotField(Slot slot) {
    constexpr int kFields[kSlotCount] = {SPOT_FIELD_DENSITY, SPOT_FIELD_COMB, SPOT_FIELD_TILT,
                                         SPOT_FIELD_SCALE, SPOT_FIELD_COLOR};
    return kFields[int(slot)];
}

const char* slotKey(Slot slot) {
    return noise::kFieldSlots[slotField(slot)].key;
}

int slotComponents(Slot slot) {
    return noise::kFieldSlots[slotField(slot)].components;
}

const char* brushKindName(BrushKind kind) {
    for (const KindName& k : kKinds)
        if (k.kind == kind)
            return k.name;
    return "?";
}

BrushKind parseBrushKind(std::string_view name) {
    for (const KindName& k : kKinds)
        if (name == k.name)
            return k.kind;
    throw InputError(cat("unknown brush '", name,
                         "' (density-add, density-erase, comb, tilt, length, color, smooth)"));
}

const char* falloffName(Falloff falloff) {
    return falloff == Falloff::Smooth   ? "smooth"
           : falloff == Falloff::Linear ? "linear"
                                        : "constant";
}

Falloff parseFalloff(std::string_view name) {
    if (name == "smooth")
        return Falloff::Smooth;
    if (name == "linear")
        return Falloff::Linear;
    if (name == "constant")
        return Falloff::Constant;
    throw InputError(cat("unknown falloff '", name, "' (smooth, linear, constant)"));
}

Slot brushSlot(const BrushSettings& brush) {
    switch (brush.kind) {
    case BrushKind::DensityAdd:
    case BrushKind::DensityErase:
        return Slot::Density;
    case BrushKind::Comb:
        return Slot::Comb;
    case BrushKind::Tilt:
        return Slot::Tilt;
    case BrushKind::Length:
        return Slot::Scale;
    case BrushKind::Color:
        return Slot::Color;
    case BrushKind::Smooth:
        return brush.smoothTarget;
    }
    return Slot::Density;
}

float falloffWeight(Falloff falloff, float t) {
    if (!(t <= 1.0f))
        return 0.0f;
    t = std::max(t, 0.0f);
    switch (falloff) {
    case Falloff::Smooth:
        return 1.0f - t * t * (3.0f - 2.0f * t);
    case Falloff::Linear:
        return 1.0f - t;
    case Falloff::Constant:
        return 1.0f;
    }
    return 0.0f;
}

SurfaceIndex::SurfaceIndex(const noise::Mesh& mesh) : m_mesh(mesh) {
    m_lo.reserve(mesh.triangles.size());
    m_hi.reserve(mesh.triangles.size());
    for (const glm::uvec3& t : mesh.triangles) {
        const glm::vec3 a = mesh.positions[t.x], b = mesh.positions[t.y], c = mesh.positions[t.z];
        m_lo.push_back(glm::min(a, glm::min(b, c)));
        m_hi.push_back(glm::max(a, glm::max(b, c)));
    }
}

std::vector<SurfaceVoxel> SurfaceIndex::voxelsNear(glm::vec3 centre, float radius,
                                                   float voxelSize) const {
    // The 8 voxels around a surface point lie within one voxel diagonal of it.
    const float reach = voxelSize * std::sqrt(3.0f) * 1.0001f;
    const glm::vec3 lo = centre - glm::vec3(radius), hi = centre + glm::vec3(radius);
    std::map<glm::ivec3, SurfaceVoxel, IjkLess> best;
    for (std::size_t t = 0; t < m_lo.size(); ++t) {
        if (glm::any(glm::greaterThan(m_lo[t] - reach, hi)) ||
            glm::any(glm::lessThan(m_hi[t] + reach, lo)))
            continue;
        const glm::ivec3 v0(glm::ceil(glm::max(m_lo[t] - reach, lo) / voxelSize));
        const glm::ivec3 v1(glm::floor(glm::min(m_hi[t] + reach, hi) / voxelSize));
        const glm::uvec3 tri = m_mesh.triangles[t];
        const glm::dvec3 a = m_mesh.positions[tri.x], b = m_mesh.positions[tri.y],
                         c = m_mesh.positions[tri.z];
        for (int z = v0.z; z <= v1.z; ++z)
            for (int y = v0.y; y <= v1.y; ++y)
                for (int x = v0.x; x <= v1.x; ++x) {
                    const glm::ivec3 ijk(x, y, z);
                    const glm::vec3 p = glm::vec3(ijk) * voxelSize;
                    if (glm::length(p - centre) > radius)
                        continue;
                    const glm::dvec3 bary = noise::closestPointBarycentric(glm::dvec3(p), a, b, c);
                    const glm::dvec3 q = bary.x * a + bary.y * b + bary.z * c;
                    const float d = float(glm::length(glm::dvec3(p) - q));
                    if (d > reach)
                        continue;
                    auto it = best.find(ijk);
                    if (it != best.end() && it->second.distance <= d)
                        continue;
                    const noise::SurfacePoint sp =
                        noise::surfacePoint(m_mesh, std::uint32_t(t), bary);
                    best[ijk] = SurfaceVoxel{ijk, sp, d};
                }
    }
    std::vector<SurfaceVoxel> out;
    out.reserve(best.size());
    for (const auto& [ijk, sv] : best)
        out.push_back(sv);
    return out;
}

std::size_t deltaBytes(const GridDelta& delta) {
    // A std::map node: the value plus three pointers and a colour (rounded up).
    return delta.size() * (sizeof(glm::ivec3) + sizeof(VoxelChange) + 4 * sizeof(void*));
}

void applyDelta(noise::PaintedGrid& grid, const GridDelta& delta, bool after) {
    for (const auto& [ijk, change] : delta) {
        const bool active = after ? change.activeAfter : change.activeBefore;
        if (active)
            grid.set(ijk, after ? change.after : change.before);
        else
            grid.clear(ijk);
    }
}

std::size_t applyDab(const BrushSettings& brush, const Dab& dab, const SurfaceIndex& surface,
                     noise::PaintedGrid& grid, GridDelta& delta, std::vector<glm::ivec3>* touched) {
    if (!(dab.radius > 0.0f))
        return 0;
    const std::vector<SurfaceVoxel> voxels =
        surface.voxelsNear(dab.centre, dab.radius, grid.voxelSize());
    // Every new value is computed from the grid before this dab (smooth reads neighbours).
    std::vector<std::pair<glm::ivec3, glm::vec3>> writes;
    writes.reserve(voxels.size());
    for (const SurfaceVoxel& sv : voxels) {
        const glm::vec3 p = grid.voxelPosition(sv.ijk);
        if (brush.frontFacesOnly && glm::dot(sv.point.normal, dab.eye - p) <= 0.0f)
            continue;
        const float f = falloffWeight(brush.falloff, glm::length(p - dab.centre) / dab.radius);
        if (f <= 0.0f)
            continue;
        const glm::vec3 old = grid.get(sv.ijk);
        glm::vec3 v = paint(brush, dab, sv, old, f, grid);
        if (grid.components() == 1)
            v = glm::vec3(v.x, 0.0f, 0.0f);
        writes.emplace_back(sv.ijk, v);
    }
    for (const auto& [ijk, v] : writes) {
        auto [it, inserted] = delta.try_emplace(ijk);
        if (inserted) {
            it->second.before = grid.get(ijk);
            it->second.activeBefore = grid.active(ijk);
        }
        grid.set(ijk, v);
        it->second.after = grid.get(ijk);
        it->second.activeAfter = true;
        if (touched)
            touched->push_back(ijk);
    }
    return writes.size();
}

} // namespace spot::edit
