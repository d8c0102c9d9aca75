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

/// The part [tEnter, tExit] of the ray origin + t dir, t >= 0, inside tetrahedron `tet` of
/// `shell`, clipped by its 4 face planes: per pixel, the tetrahedron's thickness along the view
/// ray that the renderer marches (Ritsche 2006). World units of t times |dir|. False when the ray
/// misses it or the tetrahedron is flat; either orientation works.
bool raySegmentInTetrahedron(const ShellMesh& shell, const ShellTetrahedron& tet, glm::dvec3 origin,
                             glm::dvec3 dir, double& tEnter, double& tExit);

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
/// vertex normals and split every prism.
ShellMesh buildShell(const Mesh& mesh, float thickness);

} // namespace spot::noise
