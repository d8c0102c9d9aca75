#include "edit_brush.h"

#include <algorithm>
#include <cmath>
#include <iterator>

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
                               {BrushKind::Smooth, "smooth"},
                               {BrushKind::Clump, "clump"},
                               {BrushKind::ClumpSize, "clump-size"},
                               {BrushKind::Mask, "mask"}};
static_assert(std::size(kKinds) == kBrushKindCount);

/// "Over" compositing of target `t` with weight `a` onto the override (value v, weight w) of
/// `old`: the field b (1 - w) + v w becomes (that) (1 - a) + t a whatever the base b.
glm::vec4 over(glm::vec4 old, glm::vec3 t, float a) {
    const float w = old.w + a * (1.0f - old.w);
    if (!(w > 0.0f))
        return old;
    return glm::vec4((glm::vec3(old) * (old.w * (1.0f - a)) + t * a) / w, w);
}

/// The voxel's new layer state (value xyz, weight w) under one dab of weight a = |strength| x
/// falloff; the signed kinds take their direction from the strength's sign.
glm::vec4 paint(const BrushSettings& brush, const Dab& dab, const SurfaceVoxel& sv, glm::vec4 old,
                float falloff, const noise::PaintLayer& layer, const noise::Field* base) {
    const float s = brush.strength;
    const float a = std::clamp(std::abs(s) * falloff, 0.0f, 1.0f);
    switch (brush.kind) {
    case BrushKind::DensityAdd:
        // The multiplier back towards 1 (the field's own density); the raise only on request.
        return glm::vec4(old.x + (1.0f - old.x) * a, 0.0f, 0.0f,
                         brush.raise ? old.w + (1.0f - old.w) * a : old.w);
    case BrushKind::DensityErase:
        // m (1 - a): exactly 0 for a = 1, so no impulse passes the density test there.
        return glm::vec4(old.x * (1.0f - a), 0.0f, 0.0f, old.w * (1.0f - a));
    case BrushKind::Comb: {
        const glm::vec3 n = sv.point.normal;
        glm::vec3 d = dab.direction - n * glm::dot(dab.direction, n);
        if (glm::dot(d, d) < 1e-20f)
            return old;
        glm::vec4 v = over(old, glm::normalize(d), a);
        const glm::vec3 dir(v);
        if (glm::dot(dir, dir) > 1e-20f)
            v = glm::vec4(glm::normalize(dir), v.w);
        return v;
    }
    case BrushKind::Tilt:
        // Positive strength lays the strands down towards 90 degrees, negative lifts them (puff)
        // towards the normal.
        return over(old, glm::vec3(s >= 0.0f ? 90.0f : 0.0f, 0.0f, 0.0f), a);
    case BrushKind::Length: {
        // The field as it is here (base under the layer) 25% longer or shorter, by weight a: up
        // to +-25% per dab; the scale stays positive.
        const glm::vec3 b = base ? base->eval(sv.point) : sv.point.tangent;
        const glm::vec3 now = b * (1.0f - old.w) + glm::vec3(old) * old.w;
        glm::vec4 v = over(old, now * (s >= 0.0f ? 1.25f : 0.75f), a);
        return glm::vec4(glm::max(glm::vec3(v), glm::vec3(1e-6f)), v.w);
    }
    case BrushKind::Color:
        return over(old, brush.color, a);
    case BrushKind::Clump:
    case BrushKind::Mask:
        // Towards 1 (gather, mask) or, with a negative strength, towards 0.
        return over(old, glm::vec3(s >= 0.0f ? 1.0f : 0.0f, 0.0f, 0.0f), a);
    case BrushKind::ClumpSize: {
        // As the length brush: the relative size here 25% larger or smaller per dab, within
        // the clump_size slot's [0.5, 2].
        const float b = base ? base->eval(sv.point).x : 1.0f;
        const float now = b * (1.0f - old.w) + old.x * old.w;
        const glm::vec4 v = over(old, glm::vec3(now * (s >= 0.0f ? 1.25f : 0.75f), 0.0f, 0.0f), a);
        return glm::vec4(std::clamp(v.x, 0.5f, 2.0f), 0.0f, 0.0f, v.w);
    }
    case BrushKind::Smooth: {
        glm::vec4 sum(0.0f);
        constexpr glm::ivec3 kSteps[6] = {{1, 0, 0},  {-1, 0, 0}, {0, 1, 0},
                                          {0, -1, 0}, {0, 0, 1},  {0, 0, -1}};
        for (const glm::ivec3& o : kSteps)
            sum += layer.get(sv.ijk + o);
        return glm::mix(old, sum / 6.0f, a);
    }
    }
    return old;
}

} // namespace

int slotField(Slot slot) {
    constexpr int kFields[kSlotCount] = {SPOT_FIELD_DENSITY, SPOT_FIELD_COMB,       SPOT_FIELD_TILT,
                                         SPOT_FIELD_SCALE,   SPOT_FIELD_COLOR,      SPOT_FIELD_CLUMP,
                                         SPOT_FIELD_CLUMP_SIZE, SPOT_FIELD_MASK};
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
                         "' (density-add, density-erase, comb, tilt, length, color, smooth, "
                         "clump, clump-size, mask)"));
}

const char* maskLimitName(MaskLimit limit) {
    return limit == MaskLimit::None ? "none" : limit == MaskLimit::Masked ? "masked" : "unmasked";
}

MaskLimit parseMaskLimit(std::string_view name) {
    if (name == "none")
        return MaskLimit::None;
    if (name == "masked")
        return MaskLimit::Masked;
    if (name == "unmasked")
        return MaskLimit::Unmasked;
    throw InputError(cat("unknown mask limit '", name, "' (none, masked, unmasked)"));
}

float maskLimitFactor(MaskLimit limit, float mask) {
    const float m = std::clamp(mask, 0.0f, 1.0f);
    return limit == MaskLimit::Masked ? m : limit == MaskLimit::Unmasked ? 1.0f - m : 1.0f;
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
    case BrushKind::Clump:
        return Slot::Clump;
    case BrushKind::ClumpSize:
        return Slot::ClumpSize;
    case BrushKind::Mask:
        return Slot::Mask;
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

void applyDelta(noise::PaintLayer& grid, const GridDelta& delta, bool after) {
    for (const auto& [ijk, change] : delta) {
        const bool active = after ? change.activeAfter : change.activeBefore;
        if (active)
            grid.set(ijk, after ? change.after : change.before);
        else
            grid.clear(ijk);
    }
}

std::size_t applyDab(const BrushSettings& brush, const Dab& dab, const SurfaceIndex& surface,
                     noise::PaintLayer& layer, const noise::Field* base, GridDelta& delta,
                     std::vector<glm::ivec3>* touched, const noise::Field* mask) {
    const bool limited = mask && brush.limit != MaskLimit::None && brush.kind != BrushKind::Mask;
    // Written voxels stay a voxel diagonal inside the radius: the lookups that read them are
    // those of points inside it (the 8 voxels around a point lie within a diagonal of it).
    const float inner = dab.radius - layer.voxelSize() * std::sqrt(3.0f) * 1.001f;
    if (!(inner > 0.0f))
        return 0;
    const std::vector<SurfaceVoxel> voxels =
        surface.voxelsNear(dab.centre, inner, layer.voxelSize());
    const int components = layer.components();
    // Every new value is computed from the layer before this dab (smooth reads neighbours).
    std::vector<std::pair<glm::ivec3, glm::vec4>> writes;
    writes.reserve(voxels.size());
    for (const SurfaceVoxel& sv : voxels) {
        const glm::vec3 p = layer.value().voxelPosition(sv.ijk);
        if (brush.frontFacesOnly && glm::dot(sv.point.normal, dab.eye - p) <= 0.0f)
            continue;
        float f = falloffWeight(brush.falloff, glm::length(p - dab.centre) / inner);
        if (f <= 0.0f)
            continue;
        // Limited to the mask: a voxel the limit gives no weight is not written at all.
        if (limited && !((f *= maskLimitFactor(brush.limit, mask->eval(sv.point).x)) > 0.0f))
            continue;
        glm::vec4 v = paint(brush, dab, sv, layer.get(sv.ijk), f, layer, base);
        if (components == 1)
            v = glm::vec4(v.x, 0.0f, 0.0f, v.w);
        writes.emplace_back(sv.ijk, v);
    }
    for (const auto& [ijk, v] : writes) {
        auto [it, inserted] = delta.try_emplace(ijk);
        if (inserted) {
            it->second.before = layer.get(ijk);
            it->second.activeBefore = layer.active(ijk);
        }
        layer.set(ijk, v);
        it->second.after = layer.get(ijk);
        it->second.activeAfter = true;
        if (touched)
            touched->push_back(ijk);
    }
    return writes.size();
}

} // namespace spot::edit
