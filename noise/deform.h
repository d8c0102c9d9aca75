/// @file deform.h
/// @brief Impulses that follow a moving mesh, on the CPU (docs/design.md section 6): the mesh
/// posed, each triangle's rotation from rest, the impulses carried from their rest anchors, and
/// the wind. The GPU's deform passes (splat/deform_vk.h) run the same formulas
/// (shaders/spot_deform.h); the reference renders what this makes.
///
/// Everything that defines the noise is decided on the rest pose: the generator runs on
/// AnimatedMesh::rest(), and an impulse is its anchor (triangle, barycentrics, height, and its
/// kernel frame at rest). At time t its root is the posed surface point at its barycentrics, its
/// position the root plus its height along the posed normal there, and its frame, normal and comb
/// are turned by its triangle's rotation from rest to the pose (the rotation part of the
/// triangle's own deformation; the kernel's scale is unchanged). No impulse appears, vanishes or
/// slides as the mesh moves. The wind then turns each one about its root.
#pragma once

#include <vector>

#include <glm/glm.hpp>

#include "noise/animated_mesh.h"
#include "noise/cells.h"
#include "noise/impulses.h"
#include "noise/mesh.h"

namespace spot::noise {

/// The scene's wind (presets/README.md, scene key "wind"): a time-varying turn of every impulse
/// about its root, leaning it downwind (shaders/spot_deform.h, spotWindRotation).
struct Wind {
    glm::vec3 direction{1.0f, 0.0f, 0.0f}; ///< unit, world
    float strength = 0.0f;                 ///< radians of lean at the gusts' peak; 0: no wind
    float gustFrequency = 0.5f;            ///< gusts per second
    float variation = 0.5f;                ///< [0, 1]: how much each impulse's lean differs
    bool on() const { return strength != 0.0f; }
};

/// The box of a rest cell's surface at a pose: its pieces' corners carried to the posed triangles
/// (`posed`: the posed positions, `triangles` the mesh's). The surface inside the cell is posed
/// exactly inside it (a pose is linear over each triangle); the cell's kernels reach at most one
/// cell edge beyond, as at rest.
void posedCellBounds(const SurfaceCells& cells, const SurfaceCell& cell,
                     const std::vector<glm::uvec3>& triangles, const std::vector<glm::vec3>& posed,
                     glm::vec3& lo, glm::vec3& hi);

/// An animated mesh's pose on the CPU, kept from one pose to the next: a triangle the pose
/// collapses keeps the rotation of the last pose where it had one (the rest's at first).
class Deformer {
public:
    /// `mesh` must outlive the deformer.
    explicit Deformer(const AnimatedMesh& mesh);

    /// Pose the mesh at time t (seconds; clamped to the clip): positions, normals and each
    /// triangle's rotation from rest.
    void pose(double t);
    double time() const { return m_time; }
    /// The mesh at the last pose (the rest's topology, uv and tangents carried).
    const Mesh& posed() const { return m_posed; }
    /// Each triangle's rotation from rest to the last pose.
    const std::vector<glm::mat3>& rotations() const { return m_rotations; }
    /// Triangles that the last pose collapsed (they kept an earlier rotation).
    std::size_t collapsed() const { return m_collapsed; }

    /// Impulses generated on the rest pose, carried to the last pose, then turned by `wind` at
    /// its time. Each one's cell becomes its root's at the pose (floor(root / cellSize)), the
    /// cells the ray march bins by. Everything but the position, the normal, the comb, the frame
    /// and the cell is kept: the anchor and every random value are the rest's, bit for bit.
    std::vector<Impulse> move(const std::vector<Impulse>& rest, float cellSize,
                              const Wind& wind = {}) const;

private:
    const AnimatedMesh& m_mesh;
    Mesh m_posed;
    std::vector<glm::mat3> m_rotations;
    std::size_t m_collapsed = 0;
    double m_time = 0.0;
};

} // namespace spot::noise
