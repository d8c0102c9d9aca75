// Surface cells. This is the only translation unit that includes OpenVDB's MeshToVolume.h (it
// takes ~30 s to compile), so nothing else pays for it.
#include "cells.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include <openvdb/openvdb.h>
#include <openvdb/tools/MeshToVolume.h>
#include <tbb/parallel_for.h>

#include "error.h"
#include "mesh.h"
#include "surface.h"
#include "system.h"

namespace spot::noise {

namespace {

std::uint64_t packCell(glm::ivec3 c) {
    // 21 bits per axis, offset to unsigned; buildSurfaceCells keeps |i| < 2^20.
    const auto u = [](int v) { return std::uint64_t(std::uint32_t(v + (1 << 20)) & 0x1fffffu); };
    return u(c.x) << 42 | u(c.y) << 21 | u(c.z);
}

/// A polygon vertex during clipping: world position and parent-triangle barycentrics (b1, b2).
struct ClipVertex {
    glm::dvec3 p;
    glm::dvec2 b;
};

/// A triangle clipped by 6 planes has at most 9 vertices.
struct Polygon {
    std::array<ClipVertex, 12> v;
    int n = 0;
};

/// Keep the part of `in` where sign * (p[axis] - value) >= 0 (Sutherland-Hodgman, one plane).
Polygon clip(const Polygon& in, int axis, double value, double sign) {
    Polygon out;
    for (int i = 0; i < in.n; ++i) {
        const ClipVertex& a = in.v[i];
        const ClipVertex& b = in.v[(i + 1) % in.n];
        const double da = sign * (a.p[axis] - value);
        const double db = sign * (b.p[axis] - value);
        if (da >= 0.0)
            out.v[out.n++] = a;
        if ((da >= 0.0) != (db >= 0.0)) {
            const double t = da / (da - db);
            ClipVertex c{a.p + t * (b.p - a.p), a.b + t * (b.b - a.b)};
            c.p[axis] = value; // exactly on the plane, so neighbouring cells share the edge
            out.v[out.n++] = c;
        }
    }
    return out;
}

void bounds(const Polygon& poly, int axis, double& lo, double& hi) {
    lo = std::numeric_limits<double>::infinity();
    hi = -lo;
    for (int i = 0; i < poly.n; ++i) {
        lo = std::min(lo, poly.v[i].p[axis]);
        hi = std::max(hi, poly.v[i].p[axis]);
    }
}

struct PieceEntry {
    std::uint64_t cell;
    glm::ivec3 ijk;
    SurfacePiece piece;
};

/// Clip triangle `t` into the grid, slab by slab along x, then y, then z, so the work is
/// proportional to the cells the triangle really crosses (not to its bounding box).
void clipTriangle(const Mesh& mesh, std::uint32_t t, double h, std::vector<PieceEntry>& out) {
    const glm::uvec3 tri = mesh.triangles[t];
    Polygon poly;
    poly.n = 3;
    poly.v[0] = {glm::dvec3(mesh.positions[tri.x]), {0.0, 0.0}};
    poly.v[1] = {glm::dvec3(mesh.positions[tri.y]), {1.0, 0.0}};
    poly.v[2] = {glm::dvec3(mesh.positions[tri.z]), {0.0, 1.0}};
    const double triArea = 0.5 * glm::length(glm::cross(poly.v[1].p - poly.v[0].p,
                                                        poly.v[2].p - poly.v[0].p));
    // Slivers below this are rounding noise from the clipping, not surface.
    const double minArea = triArea * 1e-12;

    // Each level keeps its own range: the loop bounds must not change while iterating.
    double xLo = 0.0, xHi = 0.0;
    bounds(poly, 0, xLo, xHi);
    const int i0 = int(std::floor(xLo / h)), i1 = int(std::floor(xHi / h));
    for (int i = i0; i <= i1; ++i) {
        const Polygon px = clip(clip(poly, 0, i * h, 1.0), 0, (i + 1) * h, -1.0);
        if (px.n < 3)
            continue;
        double yLo = 0.0, yHi = 0.0;
        bounds(px, 1, yLo, yHi);
        const int j0 = int(std::floor(yLo / h)), j1 = int(std::floor(yHi / h));
        for (int j = j0; j <= j1; ++j) {
            const Polygon py = clip(clip(px, 1, j * h, 1.0), 1, (j + 1) * h, -1.0);
            if (py.n < 3)
                continue;
            double zLo = 0.0, zHi = 0.0;
            bounds(py, 2, zLo, zHi);
            const int k0 = int(std::floor(zLo / h)), k1 = int(std::floor(zHi / h));
            for (int k = k0; k <= k1; ++k) {
                const Polygon pz = clip(clip(py, 2, k * h, 1.0), 2, (k + 1) * h, -1.0);
                // Fan-triangulate the convex clipped polygon.
                for (int f = 1; f + 1 < pz.n; ++f) {
                    const ClipVertex &a = pz.v[0], &b = pz.v[f], &c = pz.v[f + 1];
                    const double area = 0.5 * glm::length(glm::cross(b.p - a.p, c.p - a.p));
                    if (!(area > minArea))
                        continue;
                    PieceEntry e;
                    e.ijk = glm::ivec3(i, j, k);
                    e.cell = packCell(e.ijk);
                    e.piece.triangle = t;
                    e.piece.corner[0] = glm::vec2(a.b);
                    e.piece.corner[1] = glm::vec2(b.b);
                    e.piece.corner[2] = glm::vec2(c.b);
                    e.piece.area = float(area);
                    out.push_back(e);
                }
            }
        }
    }
}

/// Adapter feeding our triangles (those that grow fur: `triangles`) to meshToVolume in index
/// space.
struct MeshAdapter {
    const Mesh* mesh;
    const std::vector<std::uint32_t>* triangles;
    const openvdb::math::Transform* transform;
    std::size_t polygonCount() const { return triangles->size(); }
    std::size_t pointCount() const { return mesh->positions.size(); }
    std::size_t vertexCount(std::size_t) const { return 3; }
    void getIndexSpacePoint(std::size_t n, std::size_t v, openvdb::Vec3d& pos) const {
        const glm::vec3 p = mesh->positions[mesh->triangles[(*triangles)[n]][int(v)]];
        pos = transform->worldToIndex(openvdb::Vec3d(p.x, p.y, p.z));
    }
};

} // namespace

std::int64_t SurfaceCells::find(glm::ivec3 ijk) const {
    const auto it = index.find(packCell(ijk));
    return it == index.end() ? -1 : std::int64_t(it->second);
}

glm::ivec3 SurfaceCells::cellOf(glm::vec3 p) const {
    const double h = cellSize;
    return glm::ivec3(int(std::floor(double(p.x) / h)), int(std::floor(double(p.y) / h)),
                      int(std::floor(double(p.z) / h)));
}

std::size_t SurfaceCells::memoryBytes() const {
    return cells.capacity() * sizeof(SurfaceCell) + pieces.capacity() * sizeof(SurfacePiece) +
           index.size() * (sizeof(std::uint64_t) + sizeof(std::uint32_t) + 2 * sizeof(void*)) +
           index.bucket_count() * sizeof(void*);
}

double estimateCellCount(const Mesh& mesh, float cellSize) {
    // A plane of area A crosses about A (|nx| + |ny| + |nz|) / h^2 <= sqrt(3) A / h^2 cells, plus
    // the cells along its border; each triangle adds at least one cell of its own at worst.
    const double h = cellSize;
    return 1.8 * mesh.surfaceArea() / (h * h) + double(mesh.triangles.size()) + 8.0;
}

namespace {

/// Refuses a cell size the mesh cannot be cut into within `limits` and the memory budget.
void checkCellBudget(const Mesh& mesh, float cellSize, const CellLimits& limits) {
    if (!std::isfinite(cellSize) || !(cellSize > 0.0f))
        throw InputError(cat("cell size ", cellSize, " must be a positive finite number"));
    const Bounds box = mesh.bounds();
    const glm::vec3 extent = box.size();
    const double largest = std::max({extent.x, extent.y, extent.z});
    const double perAxis = largest / cellSize;
    const double farthest = std::max({std::abs(box.lo.x), std::abs(box.lo.y), std::abs(box.lo.z),
                                      std::abs(box.hi.x), std::abs(box.hi.y), std::abs(box.hi.z)});
    if (perAxis > limits.maxCellsPerAxis || farthest / cellSize > double(1 << 20) - 2.0)
        throw InputError(cat("cell size ", cellSize, " is absurdly small for a mesh spanning ",
                             largest, " world units (", perAxis, " cells along one axis, limit ",
                             limits.maxCellsPerAxis, ")"));
    const double estimated = estimateCellCount(mesh, cellSize);
    if (estimated > double(limits.maxCells))
        throw InputError(cat("cell size ", cellSize, " would create about ", std::llround(estimated),
                             " surface cells, more than the limit of ", limits.maxCells,
                             "; use a larger cell size"));
    // OpenVDB's narrow band: leaves of 8^3 voxels, two grids (distance, polygon index), ~3 voxels
    // thick; pieces and the index on our side.
    const double leaves = 3.0 * mesh.surfaceArea() / (64.0 * cellSize * cellSize) +
                          double(mesh.triangles.size()) + 64.0;
    const double vdbBytes = leaves * 512.0 * 8.0 * 2.0;
    const double ourBytes = estimated * (sizeof(SurfaceCell) + 4 * sizeof(SurfacePiece) + 64.0);
    requireMemory(std::uint64_t(vdbBytes + ourBytes), cat("surface cells of size ", cellSize));
}

/// 1. Exact pieces: every triangle clipped into the cells of edge `h` it crosses, in parallel
///    over fixed blocks so the order (and hence the impulses) never depends on the thread count;
///    sorted by cell, then triangle.
std::vector<PieceEntry> clipIntoCells(const Mesh& mesh, double h) {
    constexpr std::size_t kBlock = 256;
    const std::size_t triangleCount = mesh.triangles.size();
    const std::size_t blockCount = (triangleCount + kBlock - 1) / kBlock;
    std::vector<std::vector<PieceEntry>> blocks(blockCount);
    tbb::parallel_for(std::size_t(0), blockCount, [&](std::size_t b) {
        const std::size_t end = std::min(triangleCount, (b + 1) * kBlock);
        for (std::size_t t = b * kBlock; t < end; ++t)
            if (mesh.grows(t)) // a part the scene's "grow" left out is drawn, but has no cells
                clipTriangle(mesh, std::uint32_t(t), h, blocks[b]);
    });
    std::vector<PieceEntry> entries;
    std::size_t total = 0;
    for (const auto& b : blocks)
        total += b.size();
    entries.reserve(total);
    for (auto& b : blocks) {
        entries.insert(entries.end(), b.begin(), b.end());
        std::vector<PieceEntry>().swap(b);
    }
    std::stable_sort(entries.begin(), entries.end(), [](const PieceEntry& a, const PieceEntry& b) {
        if (a.ijk.x != b.ijk.x)
            return a.ijk.x < b.ijk.x;
        if (a.ijk.y != b.ijk.y)
            return a.ijk.y < b.ijk.y;
        if (a.ijk.z != b.ijk.z)
            return a.ijk.z < b.ijk.z;
        return a.piece.triangle < b.piece.triangle;
    });
    return entries;
}

/// The sorted pieces grouped into cells (each cell's pieces contiguous, its area their sum).
void groupIntoCells(const std::vector<PieceEntry>& entries, SurfaceCells& result) {
    result.pieces.reserve(entries.size());
    for (std::size_t i = 0; i < entries.size();) {
        SurfaceCell cell;
        cell.ijk = entries[i].ijk;
        cell.firstPiece = std::uint32_t(result.pieces.size());
        double area = 0.0;
        std::size_t j = i;
        for (; j < entries.size() && entries[j].cell == entries[i].cell; ++j) {
            result.pieces.push_back(entries[j].piece);
            area += entries[j].piece.area;
        }
        cell.pieceCount = std::uint32_t(j - i);
        cell.area = float(area);
        result.totalArea += area;
        result.index.emplace(entries[i].cell, std::uint32_t(result.cells.size()));
        result.cells.push_back(cell);
        i = j;
    }
}

/// 2. Each cell's summary (closest point, normal, tangent, uv) from the polygon OpenVDB finds
///    closest to its centre.
void summarizeCells(const Mesh& mesh, double h, SurfaceCells& result) {
    std::vector<std::uint32_t> growing;
    growing.reserve(mesh.triangles.size());
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t)
        if (mesh.grows(t))
            growing.push_back(std::uint32_t(t));
    const std::size_t triangleCount = growing.size();
    // OpenVDB's unsigned distance band over the same grid (voxel ijk centred at
    //    (ijk + 1/2) h) with its closest-polygon index: the per-cell summary comes from the
    //    polygon closest to each cell centre, and every cell the pieces found must lie in the band
    //    (a cell the surface crosses has its centre within sqrt(3)/2 h of the surface).
    openvdb::initialize();
    openvdb::math::Transform::Ptr transform = openvdb::math::Transform::createLinearTransform(h);
    transform->postTranslate(openvdb::Vec3d(0.5 * h));
    openvdb::Int32Grid polygonIndex;
    MeshAdapter adapter{&mesh, &growing, transform.get()};
    const float bandVoxels = 1.0f; // >= sqrt(3)/2: holds every crossed cell's centre
    openvdb::FloatGrid::Ptr distance = openvdb::tools::meshToVolume<openvdb::FloatGrid>(
        adapter, *transform, bandVoxels, bandVoxels, openvdb::tools::UNSIGNED_DISTANCE_FIELD,
        &polygonIndex);
    tbb::parallel_for(std::size_t(0), result.cells.size(), [&](std::size_t c) {
        SurfaceCell& cell = result.cells[c];
        const openvdb::Coord coord(cell.ijk.x, cell.ijk.y, cell.ijk.z);
        auto da = distance->getConstAccessor();
        auto ia = polygonIndex.getConstAccessor();
        float dist = 0.0f;
        const bool inBand = da.probeValue(coord, dist);
        SPOT_CHECK(inBand);
        SPOT_CHECK_LE(double(dist), 0.8661 * h + 1e-6 * h);
        std::int32_t tri = -1;
        if (!ia.probeValue(coord, tri) || tri < 0 || std::size_t(tri) >= triangleCount) {
            // No index here (cannot happen for a band voxel): use the cell's largest piece.
            const SurfacePiece* best = &result.pieces[cell.firstPiece];
            for (std::uint32_t p = 1; p < cell.pieceCount; ++p)
                if (result.pieces[cell.firstPiece + p].area > best->area)
                    best = &result.pieces[cell.firstPiece + p];
            tri = std::int32_t(best->triangle);
        } else {
            tri = std::int32_t(growing[std::size_t(tri)]);
        }
        const glm::uvec3 t = mesh.triangles[std::size_t(tri)];
        const glm::dvec3 centre = (glm::dvec3(cell.ijk) + 0.5) * h;
        const glm::dvec3 bary =
            closestPointBarycentric(centre, glm::dvec3(mesh.positions[t.x]),
                                    glm::dvec3(mesh.positions[t.y]), glm::dvec3(mesh.positions[t.z]));
        const SurfacePoint sp = surfacePoint(mesh, std::uint32_t(tri), bary);
        cell.closestTriangle = std::uint32_t(tri);
        cell.closestPoint = sp.position;
        cell.normal = sp.normal;
        cell.tangent = sp.tangent;
        cell.uv = sp.uv;
    });
}

} // namespace

SurfaceCells buildSurfaceCells(const Mesh& mesh, float cellSize, const CellLimits& limits) {
    checkCellBudget(mesh, cellSize, limits);
    SurfaceCells result;
    result.cellSize = cellSize;
    const double h = cellSize;
    groupIntoCells(clipIntoCells(mesh, h), result);
    summarizeCells(mesh, h, result);
    return result;
}
} // namespace spot::noise
