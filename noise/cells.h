/// @file cells.h
/// @brief Surface cells: the sparse cells of a regular grid that the surface passes through
/// (docs/design.md section 2; paper section 3.1).
///
/// Cell (i, j, k) spans [i h, (i+1) h) x [j h, (j+1) h) x [k h, (k+1) h) in world units. Each
/// cell holds the exact parts of the triangles inside it ("pieces", so impulses can be placed
/// uniformly per unit of area and exactly on the surface) and a summary (area, the surface point
/// closest to the cell centre with its normal, tangent and uv) for per-cell work. The cell set is
/// found with OpenVDB's meshToVolume (unsigned distance narrow band with its closest-polygon
/// index grid); memory grows with the surface area, never with the bounding volume.
#pragma once

#include <cstddef>
#include <cstdint>
#include <unordered_map>
#include <vector>

#include <glm/glm.hpp>

namespace spot::noise {

struct Mesh;

/// Part of one mesh triangle inside one cell: a triangle of the fan of the clipped polygon, in
/// the parent triangle's barycentric coordinates (b1, b2; b0 = 1 - b1 - b2).
struct SurfacePiece {
    std::uint32_t triangle = 0;
    glm::vec2 corner[3]{};
    float area = 0.0f; ///< world units^2
};

struct SurfaceCell {
    glm::ivec3 ijk{0};
    std::uint32_t firstPiece = 0;
    std::uint32_t pieceCount = 0;
    float area = 0.0f;               ///< surface area inside the cell, world units^2
    glm::vec3 closestPoint{0.0f};    ///< surface point closest to the cell centre
    glm::vec3 normal{0.0f, 0.0f, 1.0f};
    glm::vec3 tangent{1.0f, 0.0f, 0.0f};
    glm::vec2 uv{0.0f};
    std::uint32_t closestTriangle = 0;
};

/// Caps checked before OpenVDB allocates anything.
struct CellLimits {
    std::size_t maxCells = 20'000'000;
    /// Largest bounding-box extent in cells along one axis (OpenVDB coordinates are 32-bit, and a
    /// tiny h against a large mesh is almost always a unit mistake).
    double maxCellsPerAxis = 1 << 20;
};

struct SurfaceCells {
    float cellSize = 0.0f;               ///< h, world units
    std::vector<SurfaceCell> cells;      ///< sorted by (i, j, k)
    std::vector<SurfacePiece> pieces;    ///< grouped by cell, by triangle within a cell
    double totalArea = 0.0;

    /// Index of cell ijk, or -1 if the surface does not pass through it.
    std::int64_t find(glm::ivec3 ijk) const;
    /// Cell containing world point p.
    glm::ivec3 cellOf(glm::vec3 p) const;
    std::size_t memoryBytes() const;

    std::unordered_map<std::uint64_t, std::uint32_t> index; ///< packed ijk -> cell
};

/// Estimate of the cells for a mesh and h (for budgeting before building).
double estimateCellCount(const Mesh& mesh, float cellSize);

/// Build the surface cells of `mesh` with edge `cellSize`. Throws InputError for a non-positive
/// or non-finite h, for an h absurdly small against the mesh's bounds, or for a cell count or
/// memory need beyond the limits, before any large allocation.
SurfaceCells buildSurfaceCells(const Mesh& mesh, float cellSize, const CellLimits& limits = {});

} // namespace spot::noise
