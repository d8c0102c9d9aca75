#include "shared_data.h"

#include <bit>

namespace spot::gpu {

SpotImpulse toGpu(const noise::Impulse& m) {
    SpotImpulse g;
    g.position = vec4(m.position, m.weight);
    g.normal = vec4(m.normal, m.bend);
    g.comb = vec4(m.comb, m.height);
    g.frameX = vec4(m.frame[0], 1.0f);
    g.frameY = vec4(m.frame[1], m.clumpStrength);
    g.frameZ = vec4(m.frame[2], m.clumpDistance);
    g.scale = vec4(m.scale, std::bit_cast<float>(m.triangle));
    g.color = vec4(m.color, m.barycentric.x);
    g.cell = ivec4(m.cell, std::bit_cast<std::int32_t>(m.barycentric.y));
    return g;
}

noise::Impulse fromGpu(const SpotImpulse& g) {
    noise::Impulse m;
    m.position = glm::vec3(g.position);
    m.weight = g.position.w;
    m.normal = glm::vec3(g.normal);
    m.bend = g.normal.w;
    m.comb = glm::vec3(g.comb);
    m.height = g.comb.w;
    m.frame = glm::mat3(glm::vec3(g.frameX), glm::vec3(g.frameY), glm::vec3(g.frameZ));
    m.clumpStrength = g.frameY.w;
    m.clumpDistance = g.frameZ.w;
    m.scale = glm::vec3(g.scale);
    m.triangle = std::bit_cast<std::uint32_t>(g.scale.w);
    m.color = glm::vec3(g.color);
    m.barycentric = glm::vec2(g.color.w, std::bit_cast<float>(g.cell.w));
    m.cell = glm::ivec3(g.cell);
    return m;
}

std::vector<SpotImpulse> toGpu(const std::vector<noise::Impulse>& impulses) {
    std::vector<SpotImpulse> out;
    out.reserve(impulses.size());
    for (const noise::Impulse& m : impulses)
        out.push_back(toGpu(m));
    return out;
}

std::vector<SpotLobe> toGpu(const noise::Kernel& kernel) {
    std::vector<SpotLobe> out;
    for (const noise::Lobe& l : kernel.lobes) {
        SpotLobe g;
        g.inv0 = vec4(l.inverseLinear[0], l.centre.x);
        g.inv1 = vec4(l.inverseLinear[1], l.centre.y);
        g.inv2 = vec4(l.inverseLinear[2], l.centre.z);
        g.color = vec4(l.color, l.extinction);
        out.push_back(g);
    }
    return out;
}

SpotCell toGpu(const noise::SurfaceCell& c) {
    SpotCell g;
    g.ijk = ivec4(c.ijk, std::int32_t(c.pieceCount));
    g.info = uvec4(c.firstPiece, std::bit_cast<std::uint32_t>(c.area), 0u, 0u);
    return g;
}

std::vector<SpotPiece> piecesToGpu(const noise::SurfaceCells& cells) {
    std::vector<SpotPiece> out(cells.pieces.size());
    for (const noise::SurfaceCell& c : cells.cells) {
        float cumulative = 0.0f;
        for (std::uint32_t i = 0; i < c.pieceCount; ++i) {
            const noise::SurfacePiece& p = cells.pieces[c.firstPiece + i];
            cumulative += p.area;
            SpotPiece& g = out[c.firstPiece + i];
            g.c01 = vec4(p.corner[0], p.corner[1]);
            g.c2 = vec4(p.corner[2], cumulative, std::bit_cast<float>(p.triangle));
        }
    }
    return out;
}

} // namespace spot::gpu
