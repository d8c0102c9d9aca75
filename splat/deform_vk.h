/// @file deform_vk.h
/// @brief An animated mesh's pose on the GPU, per frame (docs/design.md section 6): four compute
/// passes (shaders/spot_deform_layout.h) pose the vertices into the base mesh's vertex buffer,
/// recompute their normals, rebuild each triangle's rotation from rest, and carry the rest
/// impulses to the pose (then turn them by the wind). Every method then renders the moved
/// impulses over the posed mesh.
///
/// The host poses the vertices too, with the same formula (spot_pose.h) and inputs, for what it
/// decides before the frame: which cells the camera may see (their posed boxes), and the posed
/// mesh's bounds (MeshPass's back-face test).
#pragma once

#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "noise/animated_mesh.h"
#include "noise/cells.h"
#include "noise/deform.h"
#include "splat/context_vk.h"
#include "splat/method_vk.h"
#include "splat/pass_vk.h"

namespace spot::splat {

class GpuDeformer {
public:
    /// Uploads the topology (each vertex's triangles) and the rest pose; `animation` (whose rest
    /// is the mesh `mesh` holds) must outlive this object. InputError for a vertex shared by more
    /// than kDeformMaxValence triangles.
    GpuDeformer(Context& ctx, const noise::AnimatedMesh& animation, MeshPass& mesh,
                const noise::SurfaceCells& cells, const noise::Wind& wind);
    GpuDeformer(const GpuDeformer&) = delete;
    GpuDeformer& operator=(const GpuDeformer&) = delete;

    /// Host side of a frame at time t (clamped to the clip): the pose's inputs uploaded, the
    /// vertices posed on the host. No frame that reads this deformer may be in flight.
    void prepare(double t);
    double time() const { return m_time; }
    /// The posed positions on the host (prepare's).
    const std::vector<glm::vec3>& posedPositions() const { return m_posed; }
    /// Whether the camera may see `cell`'s kernels at this pose.
    bool cellVisible(const noise::CameraRays& rays, const noise::SurfaceCells& cells,
                     const noise::SurfaceCell& cell) const;

    /// Whether the last recorded passes already posed the mesh and moved `rest` at prepare()'s
    /// time: the same time and the same rest set (its version, buffer and capacity). A paused
    /// clip, a repeat or an orbit then skips the passes, and the moved set keeps its version, so
    /// what is built from it (the light space, the ray march's lists) is not built again.
    bool current(const ImpulseSet& rest) const;
    /// Host side of the moved set for `rest` (the generator's set of this frame): its buffer
    /// grown when needed, and a new version unless current(rest). record() does it when not done
    /// since the last.
    void reserve(const ImpulseSet& rest);
    /// The grid cells the posed surface passes through (each rest cell's pieces posed, and every
    /// cell their boxes touch: a superset of the moved impulses' root cells), for the ray
    /// march's shell. Made on first use after each prepare().
    const noise::SurfaceCells& posedCells();
    /// After the frame that moved them ran: the moved impulses reordered by their cells
    /// (contiguous per cell, cells in (i, j, k) order; the ray march's ranges need that order,
    /// which the pose breaks), in a buffer of their own, with posedCells() as their cells. Host
    /// work: a stable sort of the `count` impulses.
    ImpulseSet sortedByCell(std::uint32_t count);
    /// Record the four passes: the mesh posed, its normals, its triangles' rotations, and `rest`
    /// moved into moved() (marked on `timer` as "deform" and "move"). `rest` must be the set the
    /// generator holds at record time (its count is read on the GPU). Records nothing when
    /// current(rest): the mesh and the impulses are as they were left.
    void record(VkCommandBuffer cmd, PassTimer& timer, const ImpulseSet& rest);
    /// The moved impulses of the last reserve(): the rest set's count and capacity, a version of
    /// their own (a new one whenever the pose or the rest set changed).
    ImpulseSet moved() const { return m_movedSet; }

private:
    Context& m_ctx;
    const noise::AnimatedMesh& m_animation;
    MeshPass& m_mesh;
    const noise::SurfaceCells& m_cells;
    noise::Wind m_wind;
    noise::SurfaceCells m_posedCells;
    bool m_posedCellsValid = false;
    std::uint32_t m_vertexCount = 0, m_triangleCount = 0;
    noise::PoseInputs m_inputs;
    std::vector<glm::vec3> m_posed;
    double m_time = 0.0;
    std::uint64_t m_uploadedGeometry = ~std::uint64_t(0);
    Pipeline m_pose, m_normals, m_frames, m_move;
    Buffer m_vertices, m_pieces, m_deltas, m_palette, m_weights;
    Buffer m_adjacency, m_rotations, m_moved, m_sorted;
    ImpulseSet m_movedSet;
    std::uint64_t m_version = 0;
    bool m_reserved = false;
    /// What the last recorded passes posed and moved: the time and the rest set.
    struct Moved {
        bool valid = false;
        double time = 0.0;
        std::uint64_t version = 0;
        const Buffer* impulses = nullptr;
        VkBuffer handle = VK_NULL_HANDLE;
        std::uint32_t capacity = 0;
    } m_last;
};

} // namespace spot::splat
