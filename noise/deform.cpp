#include "deform.h"

#include <limits>

#include <tbb/parallel_for.h>

#include "shaders/spot_deform.hpp"

namespace spot::noise {

namespace sh = shared::f32;

void posedCellBounds(const SurfaceCells& cells, const SurfaceCell& cell,
                     const std::vector<glm::uvec3>& triangles, const std::vector<glm::vec3>& posed,
                     glm::vec3& lo, glm::vec3& hi) {
    lo = glm::vec3(std::numeric_limits<float>::max());
    hi = -lo;
    for (std::uint32_t i = cell.firstPiece; i < cell.firstPiece + cell.pieceCount; ++i) {
        const SurfacePiece& p = cells.pieces[i];
        const glm::uvec3 t = triangles[p.triangle];
        for (const glm::vec2& c : p.corner) {
            const glm::vec3 q =
                (1.0f - c.x - c.y) * posed[t.x] + c.x * posed[t.y] + c.y * posed[t.z];
            lo = glm::min(lo, q);
            hi = glm::max(hi, q);
        }
    }
}

Deformer::Deformer(const AnimatedMesh& mesh)
    : m_mesh(mesh), m_posed(mesh.rest()), m_rotations(mesh.rest().triangles.size(), glm::mat3(1.0f)) {}

void Deformer::pose(double t) {
    m_time = m_mesh.animated() ? m_mesh.clampTime(t) : t;
    m_posed = m_mesh.pose(m_time);
    const Mesh& rest = m_mesh.rest();
    std::size_t collapsed = 0;
    for (std::size_t i = 0; i < rest.triangles.size(); ++i) {
        const glm::uvec3 tri = rest.triangles[i];
        if (!sh::spotTriangleRotation(rest.positions[tri.x], rest.positions[tri.y],
                                      rest.positions[tri.z], m_posed.positions[tri.x],
                                      m_posed.positions[tri.y], m_posed.positions[tri.z],
                                      m_rotations[i]))
            ++collapsed;
    }
    m_collapsed = collapsed;
}

std::vector<Impulse> Deformer::move(const std::vector<Impulse>& rest, float cellSize,
                                    const Wind& wind) const {
    std::vector<Impulse> out(rest);
    const float t = float(m_time);
    tbb::parallel_for(std::size_t(0), out.size(), [&](std::size_t i) {
        Impulse& imp = out[i];
        const glm::uvec3 tri = m_posed.triangles[imp.triangle];
        const glm::mat3& R = m_rotations[imp.triangle];
        const glm::vec3 b(1.0f - imp.barycentric.x - imp.barycentric.y, imp.barycentric.x,
                          imp.barycentric.y);
        glm::vec3 root, position;
        sh::spotMoveAnchor(m_posed.positions[tri.x], m_posed.positions[tri.y],
                           m_posed.positions[tri.z], m_posed.normals[tri.x],
                           m_posed.normals[tri.y], m_posed.normals[tri.z], b, imp.height, R,
                           imp.normal, root, position);
        glm::mat3 turn = R;
        if (wind.on()) {
            const glm::mat3 W = sh::spotWindRotation(
                R * imp.normal, wind.direction, wind.strength, wind.gustFrequency, wind.variation,
                t, sh::spotAnchorKey(imp.triangle, imp.barycentric.x, imp.barycentric.y));
            position = root + W * (position - root);
            turn = W * R;
        }
        imp.position = position;
        imp.cell = glm::ivec3(glm::floor(root / cellSize));
        imp.normal = turn * imp.normal;
        imp.comb = turn * imp.comb;
        imp.frame = turn * imp.frame;
    });
    return out;
}

} // namespace spot::noise
