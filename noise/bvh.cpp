#include "bvh.h"

#include "error.h"
#include "mesh.h"

namespace spot::noise {

void Bvh::build(const std::vector<Aabb>& boxes) {
    m_nodes.clear();
    m_order.resize(boxes.size());
    for (std::uint32_t i = 0; i < boxes.size(); ++i)
        m_order[i] = i;
    if (boxes.empty())
        return;
    m_nodes.reserve(2 * boxes.size());
    m_nodes.emplace_back();
    struct Task {
        std::uint32_t node, begin, end;
    };
    std::vector<Task> tasks{{0, 0, std::uint32_t(boxes.size())}};
    // Depth stays below ~2 log2(n) + a few with median splits: far below the traversal stack.
    while (!tasks.empty()) {
        const Task t = tasks.back();
        tasks.pop_back();
        Aabb box, centres;
        for (std::uint32_t i = t.begin; i < t.end; ++i) {
            box.grow(boxes[m_order[i]]);
            centres.grow(boxes[m_order[i]].centre());
        }
        m_nodes[t.node].box = box;
        const std::uint32_t n = t.end - t.begin;
        const glm::dvec3 extent = centres.hi - centres.lo;
        if (n <= 4 || !(glm::max(extent.x, glm::max(extent.y, extent.z)) > 0.0)) {
            m_nodes[t.node].first = t.begin;
            m_nodes[t.node].count = n;
            continue;
        }
        const int axis = extent.x >= extent.y && extent.x >= extent.z ? 0 : extent.y >= extent.z ? 1 : 2;
        const std::uint32_t mid = t.begin + n / 2;
        std::nth_element(m_order.begin() + t.begin, m_order.begin() + mid, m_order.begin() + t.end,
                         [&](std::uint32_t a, std::uint32_t b) {
                             return boxes[a].centre()[axis] < boxes[b].centre()[axis];
                         });
        const std::uint32_t left = std::uint32_t(m_nodes.size());
        m_nodes.emplace_back();
        m_nodes.emplace_back();
        m_nodes[t.node].first = left;
        m_nodes[t.node].count = 0;
        tasks.push_back({left, t.begin, mid});
        tasks.push_back({left + 1, mid, t.end});
    }
}

double intersectTriangle(const Ray& ray, glm::dvec3 a, glm::dvec3 b, glm::dvec3 c,
                         glm::dvec3& barycentric) {
    constexpr double kMiss = std::numeric_limits<double>::infinity();
    const glm::dvec3 e1 = b - a, e2 = c - a;
    const glm::dvec3 p = glm::cross(ray.dir, e2);
    const double det = glm::dot(e1, p);
    if (std::abs(det) < 1e-300)
        return kMiss;
    const double inv = 1.0 / det;
    const glm::dvec3 s = ray.origin - a;
    const double u = glm::dot(s, p) * inv;
    if (u < 0.0 || u > 1.0)
        return kMiss;
    const glm::dvec3 q = glm::cross(s, e1);
    const double v = glm::dot(ray.dir, q) * inv;
    if (v < 0.0 || u + v > 1.0)
        return kMiss;
    const double t = glm::dot(e2, q) * inv;
    if (!(t > 0.0))
        return kMiss;
    barycentric = glm::dvec3(1.0 - u - v, u, v);
    return t;
}

Bvh triangleBvh(const Mesh& mesh) {
    std::vector<Aabb> boxes(mesh.triangles.size());
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t)
        for (int v = 0; v < 3; ++v)
            boxes[t].grow(glm::dvec3(mesh.positions[mesh.triangles[t][v]]));
    Bvh bvh;
    bvh.build(boxes);
    return bvh;
}

std::optional<MeshHit> closestHit(const Bvh& bvh, const Mesh& mesh, const Ray& ray) {
    double tMax = std::numeric_limits<double>::infinity();
    std::optional<MeshHit> best;
    bvh.traverse(ray, 0.0, tMax, [&](std::uint32_t t, double& limit) {
        const glm::uvec3 tri = mesh.triangles[t];
        glm::dvec3 bary;
        const double d = intersectTriangle(ray, glm::dvec3(mesh.positions[tri.x]),
                                           glm::dvec3(mesh.positions[tri.y]),
                                           glm::dvec3(mesh.positions[tri.z]), bary);
        if (!(d < limit))
            return;
        limit = d;
        best = MeshHit{d, t, bary};
    });
    return best;
}

} // namespace spot::noise
