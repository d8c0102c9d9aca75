// Surface cells: exact pieces, the summary, memory growing with area, refusal of absurd sizes.
#include <chrono>
#include <cmath>
#include <set>
#include <tuple>

#include <gtest/gtest.h>

#include "noise/cells.h"
#include "noise/error.h"
#include "noise/mesh.h"
#include "noise/surface.h"
#include "test_support.h"

namespace {

using namespace spot;

glm::dvec3 piecePoint(const noise::Mesh& mesh, const noise::SurfacePiece& piece, int corner) {
    const glm::uvec3 t = mesh.triangles[piece.triangle];
    const glm::dvec2 b(piece.corner[corner]);
    return (1.0 - b.x - b.y) * glm::dvec3(mesh.positions[t.x]) +
           b.x * glm::dvec3(mesh.positions[t.y]) + b.y * glm::dvec3(mesh.positions[t.z]);
}

void checkCells(const noise::Mesh& mesh, float h) {
    const noise::SurfaceCells cells = noise::buildSurfaceCells(mesh, h);
    ASSERT_FALSE(cells.cells.empty());
    // The pieces partition the surface: their areas add up to the mesh's.
    EXPECT_NEAR(cells.totalArea / mesh.surfaceArea(), 1.0, 1e-5);
    std::set<std::tuple<int, int, int>> seen;
    glm::ivec3 previous(std::numeric_limits<int>::min());
    double pieceSum = 0.0;
    for (std::size_t c = 0; c < cells.cells.size(); ++c) {
        const noise::SurfaceCell& cell = cells.cells[c];
        EXPECT_TRUE(seen.emplace(cell.ijk.x, cell.ijk.y, cell.ijk.z).second) << "duplicate cell";
        EXPECT_TRUE(std::tie(previous.x, previous.y, previous.z) <
                    std::tie(cell.ijk.x, cell.ijk.y, cell.ijk.z));
        previous = cell.ijk;
        EXPECT_EQ(cells.find(cell.ijk), std::int64_t(c));
        ASSERT_GT(cell.pieceCount, 0u);
        double area = 0.0;
        const glm::dvec3 lo = glm::dvec3(cell.ijk) * double(h), hi = lo + double(h);
        const double slack = 1e-5 * h;
        for (std::uint32_t p = 0; p < cell.pieceCount; ++p) {
            const noise::SurfacePiece& piece = cells.pieces[cell.firstPiece + p];
            area += piece.area;
            for (int k = 0; k < 3; ++k) {
                const glm::dvec3 q = piecePoint(mesh, piece, k);
                for (int a = 0; a < 3; ++a) {
                    ASSERT_GE(q[a], lo[a] - slack) << "piece corner outside its cell";
                    ASSERT_LE(q[a], hi[a] + slack) << "piece corner outside its cell";
                }
            }
        }
        EXPECT_NEAR(area, cell.area, 1e-5 * area + 1e-12);
        pieceSum += area;
        // The summary: a surface point within half a diagonal of the cell centre, unit normal.
        const glm::dvec3 centre = (lo + hi) * 0.5;
        EXPECT_LE(glm::length(glm::dvec3(cell.closestPoint) - centre), 0.8661 * h * (1 + 1e-4));
        EXPECT_NEAR(glm::length(cell.normal), 1.0f, 1e-5f);
        EXPECT_NEAR(glm::length(cell.tangent), 1.0f, 1e-5f);
        EXPECT_NEAR(glm::dot(cell.normal, cell.tangent), 0.0f, 1e-4f);
    }
    EXPECT_NEAR(pieceSum, cells.totalArea, 1e-6 * pieceSum);
}

TEST(Cells, SpherePiecesPartitionTheSurface) {
    checkCells(noise::makeSphere(1.0f, 48, 96), 0.07f);
}

TEST(Cells, RotatedTorusPiecesPartitionTheSurface) {
    noise::Mesh torus = noise::makeTorus(1.0f, 0.35f, 64, 24);
    test::transformMesh(torus, test::rotation(0.83f, {0.3f, 0.5f, 0.8f}), {0.123f, -0.4f, 0.07f});
    checkCells(torus, 0.05f);
}

TEST(Cells, PlaneOnACellFaceAndMixedTriangleSizes) {
    // y = 0 lies exactly on cell faces; triangle areas differ by 100x.
    checkCells(test::mixedPlane(), 0.03f);
}

TEST(Cells, ClosestPointIsTheNearestSurfacePoint) {
    noise::Mesh torus = noise::makeTorus(1.0f, 0.35f, 48, 16);
    test::transformMesh(torus, test::rotation(0.5f, {1.0f, 0.2f, 0.1f}), glm::vec3(0.03f));
    const float h = 0.1f;
    const noise::SurfaceCells cells = noise::buildSurfaceCells(torus, h);
    for (std::size_t c = 0; c < cells.cells.size(); c += 5) {
        const noise::SurfaceCell& cell = cells.cells[c];
        const glm::dvec3 centre = (glm::dvec3(cell.ijk) + 0.5) * double(h);
        // Brute force over every triangle.
        double best = 1e30;
        for (const glm::uvec3& t : torus.triangles) {
            const glm::dvec3 a(torus.positions[t.x]), b(torus.positions[t.y]),
                cc(torus.positions[t.z]);
            const glm::dvec3 w = noise::closestPointBarycentric(centre, a, b, cc);
            best = std::min(best, glm::length(centre - (w.x * a + w.y * b + w.z * cc)));
        }
        EXPECT_NEAR(glm::length(glm::dvec3(cell.closestPoint) - centre), best, 1e-5) << c;
    }
}

TEST(Cells, MemoryGrowsWithAreaNotVolume) {
    const noise::Mesh sphere = noise::makeSphere(1.0f, 64, 128);
    const noise::SurfaceCells coarse = noise::buildSurfaceCells(sphere, 0.08f);
    const noise::SurfaceCells fine = noise::buildSurfaceCells(sphere, 0.04f);
    const double cellRatio = double(fine.cells.size()) / double(coarse.cells.size());
    // Halving h multiplies surface cells by ~4 (area / h^2); a volume would give 8.
    EXPECT_GT(cellRatio, 3.3);
    EXPECT_LT(cellRatio, 4.7);
    const double memoryRatio = double(fine.memoryBytes()) / double(coarse.memoryBytes());
    EXPECT_LT(memoryRatio, 5.5);
    // And the count is near area / h^2 times the mean of |nx| + |ny| + |nz| over a sphere (1.5).
    const double expected = 1.5 * sphere.surfaceArea() / (0.04 * 0.04);
    EXPECT_NEAR(double(fine.cells.size()) / expected, 1.0, 0.15);
}

TEST(Cells, AbsurdCellSizesAreRefusedQuickly) {
    const noise::Mesh sphere = noise::makeSphere(1.0f, 16, 32);
    for (float h : {0.0f, -1.0f, std::nanf(""), std::numeric_limits<float>::infinity()})
        EXPECT_THROW(noise::buildSurfaceCells(sphere, h), InputError) << h;
    const auto start = std::chrono::steady_clock::now();
    try {
        noise::buildSurfaceCells(sphere, 1e-7f);
        FAIL() << "a 1e-7 cell size on a unit sphere must be refused";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("cell size"), std::string::npos) << e.what();
    }
    // 2e-4: below the per-axis cap but ~4e8 cells: refused by the cell-count limit.
    EXPECT_THROW(noise::buildSurfaceCells(sphere, 2e-4f), InputError);
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    EXPECT_LT(seconds, 2.0) << "refusal must come before any large allocation";

    // A mesh far from the origin with a small h: coordinates beyond the grid's range.
    noise::Mesh far = noise::makeSphere(1.0f, 8, 16);
    test::transformMesh(far, glm::mat3(1.0f), glm::vec3(1e6f, 0.0f, 0.0f));
    EXPECT_THROW(noise::buildSurfaceCells(far, 0.5f), InputError);
}

TEST(Cells, MemoryBudgetIsEnforced) {
    const noise::Mesh sphere = noise::makeSphere(1.0f, 16, 32);
    setenv("SPOT_MEMORY_LIMIT_MB", "1", 1);
    EXPECT_THROW(noise::buildSurfaceCells(sphere, 0.005f), InputError);
    unsetenv("SPOT_MEMORY_LIMIT_MB");
    EXPECT_NO_THROW(noise::buildSurfaceCells(sphere, 0.2f));
}

} // namespace
