/// @file shell.h
/// @brief The shell the baked renderer will rasterize (docs/design.md section 5): the mesh
/// extruded along its vertex normals into one prism per triangle, each split into 3 tetrahedra.
///
/// Prism of triangle (a, b, c): the base vertices a, b, c on the mesh and the top vertices
/// a + thickness n_a, ... Each side quad (the prisms of the two triangles that share an edge
/// share it) is split along the diagonal that rises from the edge's lower vertex index: from the
/// base vertex of min(a, b) to the top vertex of max(a, b) (Leshonkov and Frolov 2021). Both
/// prisms decide from the indices alone, so they split their shared quad alike and the shell has
/// no cracks, with no pass over neighbours: each triangle's tetrahedra can be built on its own
/// (on the GPU, per frame, for an animated mesh).
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

namespace spot::noise {

struct Mesh;

/// One tetrahedron of the shell: indices into ShellMesh::positions, and its triangle.
struct ShellTetrahedron {
    std::array<std::uint32_t, 4> vertices{};
    std::uint32_t triangle = 0;
};

struct ShellMesh {
    /// The mesh's vertices (base, index i) then the extruded ones (top, index i + baseCount),
    /// world units.
    std::vector<glm::vec3> positions;
    std::uint32_t baseCount = 0;
    float thickness = 0.0f; ///< world units along the unit vertex normals
    /// Three per triangle, in triangle order, each positively oriented (the fourth vertex on the
    /// side of the first three's counter-clockwise normal) when the prism is not inverted.
    std::vector<ShellTetrahedron> tetrahedra;

    std::uint32_t top(std::uint32_t vertex) const { return vertex + baseCount; }
};

/// The tetrahedra of the prism of triangle `t` (vertex indices `tri`): with the corners sorted
/// by index, v0 < v1 < v2, (b0, b1, b2, t2), (b0, b1, t2, t1), (b0, t0, t1, t2), b for base and
/// t for top, so every side quad (vi, vj), i < j, is split along b_i - t_j.
std::array<ShellTetrahedron, 3> prismTetrahedra(glm::uvec3 tri, std::uint32_t t,
                                                std::uint32_t baseCount);

/// Per tetrahedron and face (face i is the one opposite vertex i), the tetrahedron across it, or
/// -1 on the shell's boundary. Faces match by their vertex-index triples (base vertex v or top
/// vertex v + baseCount): the rising-edge rule makes the two prisms of a shared edge split their
/// quad alike, so inside the shell every face is held by exactly two tetrahedra. Boundary: the
/// top (offset) surface, the base (the mesh), the side faces of open edges, and the faces of
/// non-manifold edges (held by more than two; none is paired). Topology only: a per-mesh
/// precomputation that an animated mesh keeps.
std::vector<std::array<std::int32_t, 4>> shellNeighbours(
    const std::vector<ShellTetrahedron>& tetrahedra);

/// The tetrahedra of the prisms of `triangles`, 3 per triangle in triangle order (as buildShell's,
/// without positions: vertex v's top vertex is v + baseCount).
std::vector<ShellTetrahedron> shellTetrahedra(const std::vector<glm::uvec3>& triangles,
                                              std::uint32_t baseCount);

/// Extrude `mesh` by `thickness` (world units, > 0 and finite; InputError otherwise) along its
/// vertex normals and split every prism. The prisms are built on the welded triangles
/// (Mesh::weldedTriangles): split copies of a vertex are one base and one top vertex.
ShellMesh buildShell(const Mesh& mesh, float thickness);

/// shellNeighbours as the baked renderer's walk reads them: per tetrahedron and face, the
/// neighbour across it times 4 plus that face's index as the neighbour numbers it (the face the
/// walk enters it through), or -1 on the shell's boundary.
std::vector<glm::ivec4> shellWalkNeighbours(const std::vector<ShellTetrahedron>& tetrahedra);

/// One tetrahedron of a walk: the ray's parameters where the walk enters and leaves it (tOut <
/// tIn where the walk runs backward through a folded, inverted tetrahedron: spotTetExit).
struct WalkSegment {
    std::uint32_t tet = 0;
    double tIn = 0.0, tOut = 0.0;
    std::uint32_t exitFace = 0; ///< the face it leaves through (opposite that corner)
};

/// The CPU twin of the baked renderer's walk through a shell's tetrahedra (baked_march.comp):
/// shaders/spot_tet_walk.h compiled for the CPU, the same source as the shaders, in float (the
/// GPU's precision) or double. Each tetrahedron's face planes come from the shared
/// spotTetFacePlane, as baked_shell.comp builds them every frame.
class ShellWalk {
public:
    enum class Precision { Float, Double };

    ShellWalk(const ShellMesh& shell, Precision precision);

    /// The part [tEnter, tExit] of the ray origin + t dir, t >= 0, inside tetrahedron `tet`
    /// alone, clipped by its 4 face planes: tEnter the last plane the ray enters, tExit the
    /// first it leaves (spotTetExit from inside). World units of t times |dir|. False when the
    /// ray misses it or the tetrahedron is flat; either orientation works.
    bool segment(std::uint32_t tet, glm::dvec3 origin, glm::dvec3 dir, double& tEnter,
                 double& tExit) const;

    /// The walk of the ray origin + t dir from tetrahedron `tet`, entered through `entryFace`
    /// (4: the ray starts inside it, at t = 0, as from the eye), across the faces it leaves
    /// through into the neighbours there, as baked_march.comp walks it: front to back, and back
    /// through the tetrahedra of a fold (spotTetExit). Ends at the shell's boundary, at t = tEnd
    /// (the mesh), at a flat tetrahedron, or after `maxTets`.
    std::vector<WalkSegment> walk(glm::dvec3 origin, glm::dvec3 dir, std::uint32_t tet,
                                  std::uint32_t entryFace, double tEnd,
                                  std::uint32_t maxTets) const;

    /// The lowest-index tetrahedron whose 4 face planes hold p (baked_shell.comp's eye test), or
    /// -1.
    std::int64_t containing(glm::dvec3 p) const;

    std::size_t tetrahedra() const { return m_neighbours.size(); }

private:
    Precision m_precision;
    std::vector<glm::vec4> m_planesF;  ///< 4 per tetrahedron (Precision::Float)
    std::vector<glm::dvec4> m_planesD; ///< 4 per tetrahedron (Precision::Double)
    std::vector<glm::ivec4> m_neighbours;
};

} // namespace spot::noise
