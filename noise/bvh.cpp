#include "bvh.h"

#include "error.h"

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

} // namespace spot::noise
