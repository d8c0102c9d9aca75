/// @file bvh.h
/// @brief A bounding volume hierarchy over axis-aligned boxes, for the CPU reference: the base
/// mesh's triangles (closest hit) and the lobes' truncated ellipsoids (all hits along a ray).
/// The closest hit on the mesh (Moller-Trumbore under the BVH) is written once here, for the
/// reference's base mesh and the editor's picking.
#pragma once

#include <algorithm>
#include <cstdint>
#include <limits>
#include <optional>
#include <vector>

#include <glm/glm.hpp>

#include "camera.h"

namespace spot::noise {

struct Aabb {
    glm::dvec3 lo{std::numeric_limits<double>::infinity()};
    glm::dvec3 hi{-std::numeric_limits<double>::infinity()};
    void grow(const Aabb& b) {
        lo = glm::min(lo, b.lo);
        hi = glm::max(hi, b.hi);
    }
    void grow(glm::dvec3 p) {
        lo = glm::min(lo, p);
        hi = glm::max(hi, p);
    }
    glm::dvec3 centre() const { return 0.5 * (lo + hi); }
};

class Bvh {
public:
    /// Build over `boxes` (median split on the longest centroid axis, leaves of <= 4).
    void build(const std::vector<Aabb>& boxes);
    bool empty() const { return m_nodes.empty(); }
    std::size_t memoryBytes() const {
        return m_nodes.capacity() * sizeof(Node) + m_order.capacity() * sizeof(std::uint32_t);
    }

    /// Visit every primitive whose box the ray segment [tMin, tMax] crosses, near boxes first.
    /// `visit(primitive, tMax)` may lower tMax (closest-hit queries prune with it).
    template <typename Visit> void traverse(const Ray& ray, double tMin, double& tMax, Visit&& visit) const {
        if (m_nodes.empty())
            return;
        const glm::dvec3 inv(1.0 / ray.dir.x, 1.0 / ray.dir.y, 1.0 / ray.dir.z);
        std::uint32_t stack[64];
        int top = 0;
        stack[top++] = 0;
        while (top > 0) {
            const Node& node = m_nodes[stack[--top]];
            double entry = 0.0;
            if (!hit(node.box, ray.origin, inv, tMin, tMax, entry))
                continue;
            if (node.count > 0) {
                for (std::uint32_t i = 0; i < node.count; ++i)
                    visit(m_order[node.first + i], tMax);
                continue;
            }
            // Push the far child first so the near one is visited first.
            const std::uint32_t a = node.first, b = node.first + 1;
            double ea = 0.0, eb = 0.0;
            const bool ha = hit(m_nodes[a].box, ray.origin, inv, tMin, tMax, ea);
            const bool hb = hit(m_nodes[b].box, ray.origin, inv, tMin, tMax, eb);
            if (ha && hb) {
                stack[top++] = ea <= eb ? b : a;
                stack[top++] = ea <= eb ? a : b;
            } else if (ha) {
                stack[top++] = a;
            } else if (hb) {
                stack[top++] = b;
            }
        }
    }

private:
    struct Node {
        Aabb box;
        std::uint32_t first = 0; ///< leaf: first index into m_order; inner: left child (right = +1)
        std::uint32_t count = 0; ///< leaf: primitive count; inner: 0
    };

    static bool hit(const Aabb& b, glm::dvec3 o, glm::dvec3 inv, double tMin, double tMax,
                    double& entry) {
        double t0 = tMin, t1 = tMax;
        for (int a = 0; a < 3; ++a) {
            double n = (b.lo[a] - o[a]) * inv[a];
            double f = (b.hi[a] - o[a]) * inv[a];
            if (n > f)
                std::swap(n, f);
            // NaN (0 * inf on a slab boundary) leaves the interval unchanged.
            t0 = n > t0 ? n : t0;
            t1 = f < t1 ? f : t1;
            if (t0 > t1)
                return false;
        }
        entry = t0;
        return true;
    }

    std::vector<Node> m_nodes;
    std::vector<std::uint32_t> m_order;
};

struct Mesh;

/// Moller-Trumbore ("Fast, Minimum Storage Ray/Triangle Intersection", 1997) in double: the ray
/// parameter t > 0 of the ray's hit with triangle (a, b, c) (world distance: Ray::dir is unit),
/// or +inf when it misses, the triangle is edge-on, or the hit lies at or behind the origin.
/// On a hit `barycentric` receives the hit's weights of a, b and c.
double intersectTriangle(const Ray& ray, glm::dvec3 a, glm::dvec3 b, glm::dvec3 c,
                         glm::dvec3& barycentric);

/// A BVH over `mesh`'s triangles, one box per triangle in triangle order (for closestHit).
Bvh triangleBvh(const Mesh& mesh);

struct MeshHit {
    double t = 0.0;             ///< ray parameter (world distance), > 0
    std::uint32_t triangle = 0; ///< index into Mesh::triangles
    glm::dvec3 barycentric{1.0, 0.0, 0.0};
};

/// The nearest hit of `ray` (t in (0, inf)) with the triangles of `mesh`, `bvh` built by
/// triangleBvh(mesh); of hits at the same t, the first the traversal meets. None on a miss.
std::optional<MeshHit> closestHit(const Bvh& bvh, const Mesh& mesh, const Ray& ray);

} // namespace spot::noise
