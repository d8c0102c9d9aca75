#include "noise/bake.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <mutex>
#include <system_error>

#include <unistd.h>

#include <openvdb/io/Archive.h>
#include <openvdb/io/File.h>
#include <openvdb/io/GridDescriptor.h>
#include <openvdb/openvdb.h>
#include <openvdb/tools/Morphology.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include "noise/cells.h"
#include "noise/error.h"
#include "noise/impulses.h"
#include "noise/kernel.h"
#include "noise/mesh.h"
#include "noise/system.h"
#include "shaders/spot_shared.hpp"

#ifndef SPOT_VERSION
#error "SPOT_VERSION (the project's version) must be defined by the build"
#endif

namespace spot::noise {

namespace sh = spot::shared::f64;

namespace {

using FloatGrid = openvdb::FloatGrid;
using Vec3Grid = openvdb::Vec3SGrid;

/// Bytes per non-empty voxel: level 0's density, colour, tangent and normal (40), the per-cell
/// list that carries it from a worker into the trees (52), the coarser levels (at most 40/7 more)
/// and slack for OpenVDB's partly filled leaves.
constexpr std::uint64_t kBytesPerVoxel = 104;
/// Bytes of a level-0 grid's voxel: density, colour, tangent and normal.
constexpr std::uint64_t kBytesPerGridVoxel = 40;
/// Bytes per voxel of the distance grid: its float and the bit masks of the dilation.
constexpr std::uint64_t kBytesPerDistanceVoxel = 6;

void initializeOpenVdb() {
    static std::once_flag once;
    std::call_once(once, [] { openvdb::initialize(); });
}

openvdb::Coord coord(glm::ivec3 v) {
    return openvdb::Coord(v.x, v.y, v.z);
}
glm::ivec3 ivec(const openvdb::Coord& c) {
    return glm::ivec3(c.x(), c.y(), c.z());
}

/// Level `level`'s voxel edge from level 0's: exact in double.
double levelVoxel(double voxel0, int level) {
    return std::ldexp(voxel0, level);
}

/// Index ijk at world (ijk + 1/2) x voxel: cell-centred voxels whose boxes nest across levels.
openvdb::math::Transform::Ptr bakeTransform(double voxel) {
    openvdb::math::Transform::Ptr xf = openvdb::math::Transform::createLinearTransform(voxel);
    xf->postTranslate(openvdb::Vec3d(0.5 * voxel));
    return xf;
}

std::string hex16(std::uint64_t v) {
    char buf[17];
    std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(v));
    return buf;
}

/// The first level-0 voxel index whose centre lies at or above the cell boundary `c h`: the same
/// expression on both sides of a boundary, so every voxel belongs to exactly one cell.
int boundaryVoxel(int c, double h, double voxel) {
    return int(std::ceil(double(c) * h / voxel - 0.5));
}

/// The surface cells and their 26 neighbours, sorted by (i, j, k).
std::vector<glm::ivec3> shellCells(const SurfaceCells& cells) {
    std::vector<glm::ivec3> shell;
    shell.reserve(cells.cells.size() * 27);
    for (const SurfaceCell& cell : cells.cells)
        for (int dz = -1; dz <= 1; ++dz)
            for (int dy = -1; dy <= 1; ++dy)
                for (int dx = -1; dx <= 1; ++dx)
                    shell.push_back(cell.ijk + glm::ivec3(dx, dy, dz));
    const auto less = [](glm::ivec3 a, glm::ivec3 b) {
        return a.x != b.x ? a.x < b.x : a.y != b.y ? a.y < b.y : a.z < b.z;
    };
    std::sort(shell.begin(), shell.end(), less);
    shell.erase(std::unique(shell.begin(), shell.end()), shell.end());
    return shell;
}

/// A lobe placed in the world, with its truncated support's box.
struct BakeLobe {
    glm::dvec3 centre;
    glm::dmat3 toLobe;
    double extinction;
    glm::dvec3 color;
    glm::dvec3 tangent; ///< a strand lobe's (placedShadingAxis), else 0
    glm::dvec3 normal;  ///< a flake lobe's, else 0
    glm::dvec3 lo, hi;
};

/// A non-empty level-0 voxel on its way from a worker to the trees.
struct BakedVoxel {
    glm::ivec3 ijk;
    float density;
    glm::vec3 color;
    glm::vec3 tangent, normal; ///< the shading grids' (bake.h)
};

template <typename GridT>
void tagGrid(GridT& grid, const std::string& name, int level, int levels, double voxel,
             std::uint64_t hash, const std::string& preset, const std::string& version) {
    grid.setName(name);
    grid.setTransform(bakeTransform(voxel));
    grid.insertMeta("spotshell_level", openvdb::Int32Metadata(level));
    grid.insertMeta("spotshell_levels", openvdb::Int32Metadata(levels));
    grid.insertMeta("spotshell_voxel_size", openvdb::DoubleMetadata(voxel));
    grid.insertMeta("spotshell_preset_hash", openvdb::StringMetadata(hex16(hash)));
    grid.insertMeta("spotshell_preset", openvdb::StringMetadata(preset));
    grid.insertMeta("spotshell_version", openvdb::StringMetadata(version));
}

/// The coarser level of (density, colour and the vector grids `fineVectors`, the shading
/// grids): the mean extinction of the 2x2x2 children (empty ones count 0) and their
/// extinction-weighted mean colour and vectors (a vector grid stores only non-zero ones).
/// Deterministic: coarse voxels are listed in tree order, each sums its children in a fixed
/// order.
void downsample(const FloatGrid& fineDensity, const Vec3Grid& fineColor,
                const std::vector<const Vec3Grid*>& fineVectors, FloatGrid& density,
                Vec3Grid& color, const std::vector<Vec3Grid*>& vectors) {
    openvdb::BoolTree parents(false);
    {
        openvdb::tree::ValueAccessor<openvdb::BoolTree> acc(parents);
        for (auto it = fineDensity.tree().cbeginValueOn(); it; ++it) {
            const openvdb::Coord c = it.getCoord();
            acc.setValueOn(openvdb::Coord(c.x() >> 1, c.y() >> 1, c.z() >> 1), true);
        }
    }
    std::vector<openvdb::Coord> coords;
    coords.reserve(std::size_t(parents.activeVoxelCount()));
    for (auto it = parents.cbeginValueOn(); it; ++it)
        coords.push_back(it.getCoord());
    const std::size_t nv = fineVectors.size();
    std::vector<float> sigma(coords.size());
    std::vector<openvdb::Vec3s> rgb(coords.size());
    std::vector<openvdb::Vec3s> vec(coords.size() * nv);
    tbb::parallel_for(
        tbb::blocked_range<std::size_t>(0, coords.size(), 4096),
        [&](const tbb::blocked_range<std::size_t>& range) {
            auto dAcc = fineDensity.getConstAccessor();
            auto cAcc = fineColor.getConstAccessor();
            std::vector<Vec3Grid::ConstAccessor> vAcc;
            for (const Vec3Grid* g : fineVectors)
                vAcc.push_back(g->getConstAccessor());
            std::vector<openvdb::Vec3d> weightedVectors(nv);
            for (std::size_t n = range.begin(); n != range.end(); ++n) {
                const openvdb::Coord base(coords[n].x() * 2, coords[n].y() * 2, coords[n].z() * 2);
                double sum = 0.0;
                openvdb::Vec3d weighted(0.0);
                std::fill(weightedVectors.begin(), weightedVectors.end(), openvdb::Vec3d(0.0));
                for (int dz = 0; dz < 2; ++dz)
                    for (int dy = 0; dy < 2; ++dy)
                        for (int dx = 0; dx < 2; ++dx) {
                            const openvdb::Coord c = base.offsetBy(dx, dy, dz);
                            if (!dAcc.isValueOn(c))
                                continue;
                            const double s = double(dAcc.getValue(c));
                            sum += s;
                            weighted += s * openvdb::Vec3d(cAcc.getValue(c));
                            for (std::size_t v = 0; v < nv; ++v)
                                weightedVectors[v] += s * openvdb::Vec3d(vAcc[v].getValue(c));
                        }
                sigma[n] = float(sum / 8.0);
                rgb[n] = sum > 0.0 ? openvdb::Vec3s(weighted / sum) : openvdb::Vec3s(0.0f);
                for (std::size_t v = 0; v < nv; ++v)
                    vec[n * nv + v] =
                        sum > 0.0 ? openvdb::Vec3s(weightedVectors[v] / sum) : openvdb::Vec3s(0.0f);
            }
        });
    auto dOut = density.getAccessor();
    auto cOut = color.getAccessor();
    std::vector<Vec3Grid::Accessor> vOut;
    for (Vec3Grid* g : vectors)
        vOut.push_back(g->getAccessor());
    for (std::size_t n = 0; n < coords.size(); ++n) {
        if (!(sigma[n] > 0.0f))
            continue;
        dOut.setValueOn(coords[n], sigma[n]);
        cOut.setValueOn(coords[n], rgb[n]);
        for (std::size_t v = 0; v < nv; ++v)
            if (vec[n * nv + v] != openvdb::Vec3s(0.0f))
                vOut[v].setValueOn(coords[n], vec[n * nv + v]);
    }
}

/// The capped Chebyshev distance (level-0 voxels) of every voxel within the cap of a non-empty
/// one: 0 on the non-empty voxels, k on the ring that the k-th 26-neighbour dilation adds.
FloatGrid::Ptr distanceGrid(const FloatGrid& density) {
    FloatGrid::Ptr dist = FloatGrid::create(kBakeDistanceCap);
    dist->tree().topologyUnion(density.tree());
    {
        // topologyUnion activates the voxels with the background's value; they are 0 away.
        auto acc = dist->getAccessor();
        for (auto it = density.tree().cbeginValueOn(); it; ++it)
            acc.setValueOn(it.getCoord(), 0.0f);
    }
    auto reached =
        std::make_unique<openvdb::BoolTree>(density.tree(), false, true, openvdb::TopologyCopy());
    auto acc = dist->getAccessor();
    for (int k = 1; k < int(kBakeDistanceCap); ++k) {
        auto grown = std::make_unique<openvdb::BoolTree>(*reached);
        openvdb::tools::dilateActiveValues(*grown, 1, openvdb::tools::NN_FACE_EDGE_VERTEX,
                                           openvdb::tools::IGNORE_TILES);
        openvdb::BoolTree ring(*grown);
        ring.topologyDifference(*reached);
        ring.voxelizeActiveTiles();
        for (auto it = ring.cbeginValueOn(); it; ++it)
            acc.setValueOn(it.getCoord(), float(k));
        reached = std::move(grown);
    }
    return dist;
}

void checkOptions(const BakeOptions& options) {
    if (!(std::isfinite(options.voxelSize) && options.voxelSize > 0.0f))
        throw InputError(cat("bake: voxel size ", options.voxelSize, " must be finite and > 0"));
    if (options.levels < 1 || options.levels > kMaxBakeLevels)
        throw InputError(
            cat("bake: ", options.levels, " levels is outside [1, ", kMaxBakeLevels, "]"));
}

} // namespace

std::uint64_t fnv1a64(std::string_view text, std::uint64_t hash) {
    std::uint64_t h = hash;
    for (const char c : text) {
        h ^= std::uint64_t(static_cast<unsigned char>(c));
        h *= 0x100000001b3ull;
    }
    return h;
}

namespace {
template <typename T> std::uint64_t hashBytes(const T* data, std::size_t count, std::uint64_t h) {
    return fnv1a64(std::string_view(reinterpret_cast<const char*>(data), count * sizeof(T)), h);
}
} // namespace

std::uint64_t meshHash(const Mesh& mesh) {
    static_assert(sizeof(glm::vec3) == 12 && sizeof(glm::uvec3) == 12);
    const std::uint64_t counts[2] = {mesh.positions.size(), mesh.triangles.size()};
    std::uint64_t h = hashBytes(counts, 2, kFnv1a64Basis);
    h = hashBytes(mesh.positions.data(), mesh.positions.size(), h);
    return hashBytes(mesh.triangles.data(), mesh.triangles.size(), h);
}

std::uint64_t shellHash(std::uint64_t meshHash, float cellSize) {
    return hashBytes(&cellSize, 1, meshHash);
}

std::string bakedDensityName(int level) {
    return level == 0 ? "density" : cat("density_lod", level);
}
std::string bakedColorName(int level) {
    return level == 0 ? "color" : cat("color_lod", level);
}
std::string bakedTangentName(int level) {
    return level == 0 ? "tangent" : cat("tangent_lod", level);
}
std::string bakedNormalName(int level) {
    return level == 0 ? "normal" : cat("normal_lod", level);
}

struct BakedVolume::Impl {
    double voxel0 = 1.0;
    std::vector<FloatGrid::Ptr> density;
    std::vector<Vec3Grid::Ptr> color;
    /// The shading grids per level (bake.h); empty in a bake written before them.
    std::vector<Vec3Grid::Ptr> tangent, normal;
    FloatGrid::Ptr distance;
    std::uint64_t presetHash = 0;
    std::string presetName;
    std::optional<std::uint64_t> meshHash;
    std::string version = SPOT_VERSION;

    int levels() const { return int(density.size()); }
    void checkLevel(int level) const {
        SPOT_CHECK_LE(0, level);
        SPOT_CHECK_LT(level, levels());
    }
};

BakedVolume::BakedVolume(std::unique_ptr<Impl> impl) : m_impl(std::move(impl)) {}
BakedVolume::BakedVolume(BakedVolume&&) noexcept = default;
BakedVolume& BakedVolume::operator=(BakedVolume&&) noexcept = default;
BakedVolume::~BakedVolume() = default;

int BakedVolume::levels() const {
    return m_impl->levels();
}
float BakedVolume::voxelSize(int level) const {
    return float(levelVoxel(m_impl->voxel0, level));
}
glm::dvec3 BakedVolume::voxelCentre(int level, glm::ivec3 ijk) const {
    return (glm::dvec3(ijk) + 0.5) * levelVoxel(m_impl->voxel0, level);
}
float BakedVolume::density(int level, glm::ivec3 ijk) const {
    m_impl->checkLevel(level);
    return m_impl->density[std::size_t(level)]->tree().getValue(coord(ijk));
}
glm::vec3 BakedVolume::color(int level, glm::ivec3 ijk) const {
    m_impl->checkLevel(level);
    const openvdb::Vec3s c = m_impl->color[std::size_t(level)]->tree().getValue(coord(ijk));
    return glm::vec3(c.x(), c.y(), c.z());
}
bool BakedVolume::hasShading() const {
    return !m_impl->tangent.empty();
}
glm::vec3 BakedVolume::tangent(int level, glm::ivec3 ijk) const {
    m_impl->checkLevel(level);
    if (!hasShading())
        return glm::vec3(0.0f);
    const openvdb::Vec3s v = m_impl->tangent[std::size_t(level)]->tree().getValue(coord(ijk));
    return glm::vec3(v.x(), v.y(), v.z());
}
glm::vec3 BakedVolume::normal(int level, glm::ivec3 ijk) const {
    m_impl->checkLevel(level);
    if (!hasShading())
        return glm::vec3(0.0f);
    const openvdb::Vec3s v = m_impl->normal[std::size_t(level)]->tree().getValue(coord(ijk));
    return glm::vec3(v.x(), v.y(), v.z());
}
float BakedVolume::distance(glm::ivec3 ijk) const {
    return m_impl->distance->tree().getValue(coord(ijk));
}
std::uint64_t BakedVolume::activeCount(int level) const {
    m_impl->checkLevel(level);
    return std::uint64_t(m_impl->density[std::size_t(level)]->activeVoxelCount());
}
std::uint64_t BakedVolume::distanceCount() const {
    return std::uint64_t(m_impl->distance->activeVoxelCount());
}
void BakedVolume::forEachActive(int level,
                                const std::function<void(glm::ivec3, float, glm::vec3)>& f) const {
    m_impl->checkLevel(level);
    const auto cAcc = m_impl->color[std::size_t(level)]->getConstAccessor();
    for (auto it = m_impl->density[std::size_t(level)]->tree().cbeginValueOn(); it; ++it) {
        const openvdb::Vec3s c = cAcc.getValue(it.getCoord());
        f(ivec(it.getCoord()), *it, glm::vec3(c.x(), c.y(), c.z()));
    }
}
void BakedVolume::forEachActiveShaded(
    int level,
    const std::function<void(glm::ivec3, float, glm::vec3, glm::vec3, glm::vec3)>& f) const {
    m_impl->checkLevel(level);
    const auto l = std::size_t(level);
    const auto cAcc = m_impl->color[l]->getConstAccessor();
    const Vec3Grid::Ptr none = Vec3Grid::create(openvdb::Vec3s(0.0f));
    const auto tAcc = (hasShading() ? m_impl->tangent[l] : none)->getConstAccessor();
    const auto nAcc = (hasShading() ? m_impl->normal[l] : none)->getConstAccessor();
    const auto v3 = [](const openvdb::Vec3s& v) { return glm::vec3(v.x(), v.y(), v.z()); };
    for (auto it = m_impl->density[l]->tree().cbeginValueOn(); it; ++it) {
        const openvdb::Coord c = it.getCoord();
        f(ivec(c), *it, v3(cAcc.getValue(c)), v3(tAcc.getValue(c)), v3(nAcc.getValue(c)));
    }
}
void BakedVolume::activeBounds(int level, glm::ivec3& lo, glm::ivec3& hi) const {
    m_impl->checkLevel(level);
    const openvdb::CoordBBox box =
        m_impl->density[std::size_t(level)]->evalActiveVoxelBoundingBox();
    lo = ivec(box.min());
    hi = ivec(box.max());
}
std::uint64_t BakedVolume::presetHash() const {
    return m_impl->presetHash;
}
const std::string& BakedVolume::presetName() const {
    return m_impl->presetName;
}
std::optional<std::uint64_t> BakedVolume::meshHash() const {
    return m_impl->meshHash;
}
const std::string& BakedVolume::version() const {
    return m_impl->version;
}
std::uint64_t BakedVolume::memoryBytes() const {
    std::uint64_t bytes = m_impl->distance ? m_impl->distance->memUsage() : 0;
    for (int l = 0; l < levels(); ++l)
        bytes +=
            m_impl->density[std::size_t(l)]->memUsage() + m_impl->color[std::size_t(l)]->memUsage();
    for (const auto* grids : {&m_impl->tangent, &m_impl->normal})
        for (const Vec3Grid::Ptr& g : *grids)
            bytes += g->memUsage();
    return bytes;
}

BakeEstimate estimateBake(const SurfaceCells& cells, const BakeOptions& options) {
    checkOptions(options);
    const double h = double(cells.cellSize), v = double(options.voxelSize);
    if (!(h > 0.0))
        throw InputError(cat("bake: cell size ", h, " must be > 0"));
    BakeEstimate e;
    if (cells.cells.empty())
        return e;
    glm::ivec3 lo(std::numeric_limits<int>::max()), hi(std::numeric_limits<int>::min());
    for (const SurfaceCell& cell : cells.cells) {
        lo = glm::min(lo, cell.ijk - 1);
        hi = glm::max(hi, cell.ijk + 1);
    }
    // OpenVDB coordinates are 32-bit: refuse a lattice that would not fit (a voxel size in the
    // wrong unit, usually) before counting anything.
    const double reach =
        std::max(std::abs(double(lo.x)),
                 std::max(std::abs(double(hi.x)) + 1,
                          std::max(std::max(std::abs(double(lo.y)), std::abs(double(hi.y)) + 1),
                                   std::max(std::abs(double(lo.z)), std::abs(double(hi.z)) + 1))));
    const glm::ivec3 span = hi - lo + 1;
    const double across = double(std::max(span.x, std::max(span.y, span.z))) * h;
    const double extent = across / v;
    if (!(extent <= kMaxBakeVoxelsPerAxis) || !(reach * h / v < double(1 << 30)))
        throw InputError(cat("bake: voxel size ", v, " is too small for a shell ", across,
                             " world units across (", extent, " voxels; at most ",
                             kMaxBakeVoxelsPerAxis, ")"));
    e.shellCells = shellCells(cells).size();
    const double perAxis = std::ceil(h / v) + 1.0;
    e.shellVoxels = std::uint64_t(double(e.shellCells) * perAxis * perAxis * perAxis);
    const std::uint64_t threads =
        std::uint64_t(std::max(1, tbb::this_task_arena::max_concurrency()));
    e.scratchBytes =
        threads * std::uint64_t(perAxis * perAxis * perAxis) * (sizeof(double) * 10 + 1);
    e.bytes = e.shellVoxels * kBytesPerVoxel + e.scratchBytes;
    return e;
}

namespace {

/// The impulses grouped by their generating cell, in their given order within a cell: impulse
/// order[n] is the n-th of the grouping, cell c's are n in [first[c], first[c + 1]).
struct CellImpulses {
    std::vector<std::uint32_t> first;
    std::vector<std::uint32_t> order;
};

CellImpulses groupByCell(const SurfaceCells& cells, const std::vector<Impulse>& impulses) {
    CellImpulses g;
    std::vector<std::uint32_t> cellOf(impulses.size());
    g.first.assign(cells.cells.size() + 1, 0);
    for (std::size_t i = 0; i < impulses.size(); ++i) {
        const std::int64_t c = cells.find(impulses[i].cell);
        if (c < 0)
            throw InputError(cat("bake: impulse ", i, "'s cell (", impulses[i].cell.x, ", ",
                                 impulses[i].cell.y, ", ", impulses[i].cell.z,
                                 ") is not a surface cell"));
        cellOf[i] = std::uint32_t(c);
        ++g.first[std::size_t(c) + 1];
    }
    for (std::size_t c = 0; c < cells.cells.size(); ++c)
        g.first[c + 1] += g.first[c];
    g.order.resize(impulses.size());
    std::vector<std::uint32_t> next(g.first.begin(), g.first.end() - 1);
    for (std::size_t i = 0; i < impulses.size(); ++i)
        g.order[next[cellOf[i]]++] = std::uint32_t(i);
    return g;
}

/// Every lobe placed once, as the reference places it (a lobe of zero extinction or a non-finite
/// box is skipped there too: here its extinction stays 0), lobe l of the n-th impulse of the
/// grouping at n x lobesPerKernel + l. `k`: the support (sigmas).
std::vector<BakeLobe> placeBakeLobes(const Kernel& kernel, const std::vector<Impulse>& impulses,
                                     const CellImpulses& groups, double k) {
    const std::size_t lobesPerKernel = kernel.lobes.size();
    std::vector<BakeLobe> lobes(impulses.size() * lobesPerKernel);
    tbb::parallel_for(std::size_t(0), impulses.size(), [&](std::size_t n) {
        const Impulse& imp = impulses[groups.order[n]];
        for (std::size_t l = 0; l < lobesPerKernel; ++l) {
            BakeLobe& out = lobes[n * lobesPerKernel + l];
            out.extinction = 0.0;
            if (!(imp.weight > 0.0f))
                continue;
            const WorldLobe w = placeLobe(kernel, int(l), imp);
            const glm::dmat3 toWorld = glm::inverse(w.toLobe);
            glm::dvec3 half;
            for (int a = 0; a < 3; ++a)
                half[a] = k * glm::length(glm::dvec3(toWorld[0][a], toWorld[1][a], toWorld[2][a]));
            if (!(w.extinction > 0.0) || !std::isfinite(half.x + half.y + half.z))
                continue;
            const glm::dvec3 axis = placedShadingAxis(kernel, int(l), imp, w);
            const bool strand = kernel.lobes[l].shading.model == LobeShading::Model::Strand;
            out = {w.centre,
                   w.toLobe,
                   w.extinction,
                   glm::dvec3(w.color),
                   strand ? axis : glm::dvec3(0.0),
                   strand ? glm::dvec3(0.0) : axis,
                   w.centre - half,
                   w.centre + half};
        }
    });
    return lobes;
}

/// An upper bound on the non-empty level-0 voxels from the lobes' boxes alone (voxel size v).
double lobeBoxVoxels(const std::vector<BakeLobe>& lobes, double v) {
    double boxVoxels = 0.0;
    for (const BakeLobe& lobe : lobes) {
        if (!(lobe.extinction > 0.0))
            continue;
        double n = 1.0;
        for (int a = 0; a < 3; ++a)
            n *= std::max(0.0,
                          std::floor(lobe.hi[a] / v - 0.5) - std::ceil(lobe.lo[a] / v - 0.5) + 1.0);
        boxVoxels += n;
    }
    return boxVoxels;
}

/// The shell cells' blocks of level-0 voxels and the lobes that reach them: each shell cell
/// evaluates the voxel centres inside it, summing the lobes of the kernels of its 27 neighbours.
class ShellVoxels {
public:
    ShellVoxels(const SurfaceCells& cells, const CellImpulses& groups,
                const std::vector<BakeLobe>& lobes, std::size_t lobesPerKernel, double v)
        : m_cells(cells), m_groups(groups), m_lobes(lobes), m_lobesPerKernel(lobesPerKernel),
          m_h(double(cells.cellSize)), m_v(v), m_shell(shellCells(cells)) {}

    std::size_t size() const { return m_shell.size(); }

    /// Shell cell `s`'s voxels: the index range [lo, end) per axis; returns their count.
    std::size_t block(std::size_t s, glm::ivec3& lo, glm::ivec3& end) const {
        for (int a = 0; a < 3; ++a) {
            lo[a] = boundaryVoxel(m_shell[s][a], m_h, m_v);
            end[a] = boundaryVoxel(m_shell[s][a] + 1, m_h, m_v);
        }
        const glm::ivec3 dims = glm::max(end - lo, glm::ivec3(0));
        return std::size_t(dims.x) * std::size_t(dims.y) * std::size_t(dims.z);
    }

    /// The voxels of shell cell `s` (block(s, lo, end)) each lobe of the kernels of its 27
    /// neighbours reaches, in a fixed order (neighbour, impulse, lobe, z, y, x): `visit(lobe,
    /// voxel offset in the cell's block, lobe-space point)` for every voxel centre inside the
    /// lobe's box.
    template <typename Visit>
    void forLobeVoxels(std::size_t s, glm::ivec3 lo, glm::ivec3 end, Visit&& visit) const {
        for (int dz = -1; dz <= 1; ++dz)
            for (int dy = -1; dy <= 1; ++dy)
                for (int dx = -1; dx <= 1; ++dx) {
                    const std::int64_t c = m_cells.find(m_shell[s] + glm::ivec3(dx, dy, dz));
                    if (c < 0)
                        continue;
                    for (std::uint32_t n = m_groups.first[std::size_t(c)];
                         n < m_groups.first[std::size_t(c) + 1]; ++n)
                        for (std::size_t l = 0; l < m_lobesPerKernel; ++l)
                            forVoxelsOf(m_lobes[n * m_lobesPerKernel + l], lo, end, visit);
                }
    }

private:
    /// The voxel centres of block [lo, end) inside `lobe`'s box, z, y, x order.
    template <typename Visit>
    void forVoxelsOf(const BakeLobe& lobe, glm::ivec3 lo, glm::ivec3 end, Visit& visit) const {
        if (!(lobe.extinction > 0.0))
            return;
        const glm::ivec3 dims = end - lo;
        glm::ivec3 a, b;
        bool empty = false;
        for (int ax = 0; ax < 3; ++ax) {
            a[ax] = std::max(lo[ax],
                             int(std::ceil(std::max(lobe.lo[ax] / m_v - 0.5, double(lo[ax] - 1)))));
            b[ax] = std::min(end[ax] - 1,
                             int(std::floor(std::min(lobe.hi[ax] / m_v - 0.5, double(end[ax])))));
            empty = empty || a[ax] > b[ax];
        }
        if (empty)
            return;
        for (int z = a.z; z <= b.z; ++z)
            for (int y = a.y; y <= b.y; ++y)
                for (int x = a.x; x <= b.x; ++x) {
                    const glm::dvec3 p = (glm::dvec3(x, y, z) + 0.5) * m_v;
                    const std::size_t at =
                        (std::size_t(z - lo.z) * std::size_t(dims.y) + std::size_t(y - lo.y)) *
                            std::size_t(dims.x) +
                        std::size_t(x - lo.x);
                    visit(lobe, at, lobe.toLobe * (p - lobe.centre));
                }
    }

    const SurfaceCells& m_cells;
    const CellImpulses& m_groups;
    const std::vector<BakeLobe>& m_lobes;
    std::size_t m_lobesPerKernel;
    double m_h, m_v;
    std::vector<glm::ivec3> m_shell;
};

/// Per shell cell, its non-empty voxels counted exactly (a pass without values: a voxel is
/// non-empty when some lobe's support, k sigmas, holds its centre). `tick` after each cell.
std::vector<std::uint64_t> countNonEmpty(const ShellVoxels& voxels, double k,
                                         const std::function<void()>& tick) {
    std::vector<std::uint64_t> nonEmpty(voxels.size(), 0);
    tbb::enumerable_thread_specific<std::vector<unsigned char>> marks;
    const double k2 = k * k;
    tbb::parallel_for(std::size_t(0), voxels.size(), [&](std::size_t s) {
        glm::ivec3 lo, end;
        const std::size_t count = voxels.block(s, lo, end);
        if (count > 0) {
            std::vector<unsigned char>& mark = marks.local();
            mark.assign(count, 0);
            voxels.forLobeVoxels(s, lo, end, [&](const BakeLobe&, std::size_t at, glm::dvec3 u) {
                mark[at] |= glm::dot(u, u) < k2 ? 1 : 0;
            });
            nonEmpty[s] = std::uint64_t(std::count(mark.begin(), mark.end(), 1));
        }
        tick();
    });
    return nonEmpty;
}

/// Level 0, per shell cell: its non-empty voxels (extinction and extinction-weighted colour)
/// in z, y, x order; `evaluated` receives each cell's voxels evaluated. `tick` after each cell.
std::vector<std::vector<BakedVoxel>> evaluateLevel0(const ShellVoxels& voxels, double k,
                                                    const std::vector<std::uint64_t>& nonEmpty,
                                                    std::vector<std::uint64_t>& evaluated,
                                                    const std::function<void()>& tick) {
    std::vector<std::vector<BakedVoxel>> perCell(voxels.size());
    evaluated.assign(voxels.size(), 0);
    struct Scratch {
        std::vector<double> sigma;
        std::vector<glm::dvec3> weighted, tangent, normal;
    };
    tbb::enumerable_thread_specific<Scratch> scratch;
    tbb::parallel_for(std::size_t(0), voxels.size(), [&](std::size_t s) {
        glm::ivec3 lo, end;
        const std::size_t count = voxels.block(s, lo, end);
        const glm::ivec3 dims = end - lo;
        if (count > 0) {
            Scratch& sc = scratch.local();
            sc.sigma.assign(count, 0.0);
            sc.weighted.assign(count, glm::dvec3(0.0));
            sc.tangent.assign(count, glm::dvec3(0.0));
            sc.normal.assign(count, glm::dvec3(0.0));
            voxels.forLobeVoxels(s, lo, end,
                                 [&](const BakeLobe& lobe, std::size_t at, glm::dvec3 u) {
                                     const double g = sh::spotLobeDensity(u, k);
                                     if (!(g > 0.0))
                                         return;
                                     const double sigma = lobe.extinction * g;
                                     sc.sigma[at] += sigma;
                                     sc.weighted[at] += sigma * lobe.color;
                                     sc.tangent[at] += sigma * lobe.tangent;
                                     sc.normal[at] += sigma * lobe.normal;
                                 });
            perCell[s].reserve(std::size_t(nonEmpty[s]));
            std::vector<BakedVoxel>& out = perCell[s];
            for (int z = 0; z < dims.z; ++z)
                for (int y = 0; y < dims.y; ++y)
                    for (int x = 0; x < dims.x; ++x) {
                        const std::size_t at =
                            (std::size_t(z) * std::size_t(dims.y) + std::size_t(y)) *
                                std::size_t(dims.x) +
                            std::size_t(x);
                        const float sigma = float(sc.sigma[at]);
                        if (!(sigma > 0.0f))
                            continue;
                        out.push_back({lo + glm::ivec3(x, y, z), sigma,
                                       glm::vec3(sc.weighted[at] / sc.sigma[at]),
                                       glm::vec3(sc.tangent[at] / sc.sigma[at]),
                                       glm::vec3(sc.normal[at] / sc.sigma[at])});
                    }
            evaluated[s] = count;
        }
        tick();
    });
    return perCell;
}

/// The bake's grids from level 0's voxels (consumed): the coarser levels by downsampling, the
/// distance grid, every grid named and tagged.
std::unique_ptr<BakedVolume::Impl> buildGrids(std::vector<std::vector<BakedVoxel>>& perCell,
                                              const BakeOptions& options) {
    auto impl = std::make_unique<BakedVolume::Impl>();
    const double v = double(options.voxelSize);
    impl->voxel0 = v;
    impl->presetHash = options.presetHash;
    impl->presetName = options.presetName;
    impl->meshHash = options.meshHash;
    FloatGrid::Ptr density0 = FloatGrid::create(0.0f);
    Vec3Grid::Ptr color0 = Vec3Grid::create(openvdb::Vec3s(0.0f));
    Vec3Grid::Ptr tangent0 = Vec3Grid::create(openvdb::Vec3s(0.0f));
    Vec3Grid::Ptr normal0 = Vec3Grid::create(openvdb::Vec3s(0.0f));
    {
        auto dAcc = density0->getAccessor();
        auto cAcc = color0->getAccessor();
        auto tAcc = tangent0->getAccessor();
        auto nAcc = normal0->getAccessor();
        for (std::vector<BakedVoxel>& list : perCell) {
            for (const BakedVoxel& b : list) {
                dAcc.setValueOn(coord(b.ijk), b.density);
                cAcc.setValueOn(coord(b.ijk), openvdb::Vec3s(b.color.x, b.color.y, b.color.z));
                if (b.tangent != glm::vec3(0.0f))
                    tAcc.setValueOn(coord(b.ijk),
                                    openvdb::Vec3s(b.tangent.x, b.tangent.y, b.tangent.z));
                if (b.normal != glm::vec3(0.0f))
                    nAcc.setValueOn(coord(b.ijk),
                                    openvdb::Vec3s(b.normal.x, b.normal.y, b.normal.z));
            }
            std::vector<BakedVoxel>().swap(list);
        }
    }
    impl->density.push_back(density0);
    impl->color.push_back(color0);
    impl->tangent.push_back(tangent0);
    impl->normal.push_back(normal0);
    for (int level = 1; level < options.levels; ++level) {
        FloatGrid::Ptr d = FloatGrid::create(0.0f);
        Vec3Grid::Ptr c = Vec3Grid::create(openvdb::Vec3s(0.0f));
        Vec3Grid::Ptr t = Vec3Grid::create(openvdb::Vec3s(0.0f));
        Vec3Grid::Ptr n = Vec3Grid::create(openvdb::Vec3s(0.0f));
        downsample(*impl->density.back(), *impl->color.back(),
                   {impl->tangent.back().get(), impl->normal.back().get()}, *d, *c,
                   {t.get(), n.get()});
        impl->density.push_back(d);
        impl->color.push_back(c);
        impl->tangent.push_back(t);
        impl->normal.push_back(n);
    }
    impl->distance = distanceGrid(*density0);

    const int levels = options.levels;
    for (int level = 0; level < levels; ++level) {
        const double vl = levelVoxel(v, level);
        tagGrid(*impl->density[std::size_t(level)], bakedDensityName(level), level, levels, vl,
                impl->presetHash, impl->presetName, impl->version);
        impl->density[std::size_t(level)]->setGridClass(openvdb::GRID_FOG_VOLUME);
        tagGrid(*impl->color[std::size_t(level)], bakedColorName(level), level, levels, vl,
                impl->presetHash, impl->presetName, impl->version);
        tagGrid(*impl->tangent[std::size_t(level)], bakedTangentName(level), level, levels, vl,
                impl->presetHash, impl->presetName, impl->version);
        tagGrid(*impl->normal[std::size_t(level)], bakedNormalName(level), level, levels, vl,
                impl->presetHash, impl->presetName, impl->version);
        impl->tangent[std::size_t(level)]->insertMeta(
            "spotshell_meaning",
            openvdb::StringMetadata("sum over strand lobes of extinction x unit tangent (world, "
                                    "root to tip) / the voxel's extinction"));
        impl->normal[std::size_t(level)]->insertMeta(
            "spotshell_meaning",
            openvdb::StringMetadata("sum over flake lobes of extinction x unit normal (world, "
                                    "the surface's side) / the voxel's extinction"));
    }
    tagGrid(*impl->distance, kBakedDistanceName, 0, levels, v, impl->presetHash, impl->presetName,
            impl->version);
    if (impl->meshHash) {
        const openvdb::StringMetadata hash(hex16(*impl->meshHash));
        for (int level = 0; level < levels; ++level) {
            impl->density[std::size_t(level)]->insertMeta("spotshell_mesh_hash", hash);
            impl->color[std::size_t(level)]->insertMeta("spotshell_mesh_hash", hash);
            impl->tangent[std::size_t(level)]->insertMeta("spotshell_mesh_hash", hash);
            impl->normal[std::size_t(level)]->insertMeta("spotshell_mesh_hash", hash);
        }
        impl->distance->insertMeta("spotshell_mesh_hash", hash);
    }
    impl->distance->insertMeta(
        "spotshell_distance_units",
        openvdb::StringMetadata(cat("Chebyshev (L-infinity) distance to the nearest non-empty "
                                    "level-0 voxel, in level-0 voxels, capped at ",
                                    kBakeDistanceCap)));
    return impl;
}

} // namespace

BakedVolume bakeImpulses(const SurfaceCells& cells, const Kernel& kernel,
                         const std::vector<Impulse>& impulses, const BakeOptions& options,
                         const std::function<void(long, long)>& progress, BakeStats* stats) {
    initializeOpenVdb();
    const auto start = std::chrono::steady_clock::now();
    BakeEstimate estimate = estimateBake(cells, options);
    const std::size_t lobesPerKernel = kernel.lobes.size();
    const std::uint64_t lobeBytes = std::uint64_t(impulses.size()) *
                                    (lobesPerKernel * sizeof(BakeLobe) + 2 * sizeof(std::uint32_t));
    requireMemory(lobeBytes + estimate.scratchBytes,
                  cat("a bake's ", impulses.size() * lobesPerKernel, " lobes"));

    const double h = double(cells.cellSize), v = double(options.voxelSize);
    const double k = double(kernel.supportSigma);
    const CellImpulses groups = groupByCell(cells, impulses);
    const std::vector<BakeLobe> lobes = placeBakeLobes(kernel, impulses, groups, k);
    const ShellVoxels voxels(cells, groups, lobes, lobesPerKernel, v);

    // Memory, in two steps, each before anything of that size is allocated. First the lobes'
    // boxes bound the non-empty voxels from above: refuse at once when even a level-0 grid of
    // that many voxels (fewer when the shell holds fewer) cannot fit.
    const double boundVoxels = std::min(double(estimate.shellVoxels), lobeBoxVoxels(lobes, v));
    requireMemory(std::uint64_t(boundVoxels * double(kBytesPerGridVoxel)),
                  cat("a bake of up to ", std::uint64_t(boundVoxels), " voxels (voxel size ",
                      options.voxelSize, ")"));
    // Then the non-empty voxels are counted exactly (a pass without values) and the whole bake
    // is bounded from that count: level 0 and its lists, the coarser levels, and the distance
    // grid (the voxels within the cap of a non-empty one, at most the shell cells' blocks grown
    // by the cap).
    std::atomic<long> cellsDone{0}; // progress: the count pass, then the values, per cell
    const auto tick = [&] {
        const long finished = ++cellsDone;
        if (progress)
            progress(finished, 2 * long(voxels.size()));
    };
    const std::vector<std::uint64_t> nonEmpty = countNonEmpty(voxels, k, tick);
    for (std::uint64_t n : nonEmpty)
        estimate.nonEmptyVoxels += n;
    const double grow = double(2 * (int(kBakeDistanceCap) - 1));
    const double perAxis = std::ceil(h / v) + 1.0 + grow;
    estimate.distanceVoxels = std::uint64_t(
        std::min(double(estimate.nonEmptyVoxels) * (grow + 1.0) * (grow + 1.0) * (grow + 1.0),
                 double(estimate.shellCells) * perAxis * perAxis * perAxis));
    estimate.bytes = estimate.nonEmptyVoxels * kBytesPerVoxel +
                     estimate.distanceVoxels * kBytesPerDistanceVoxel + estimate.scratchBytes +
                     lobeBytes;
    requireMemory(estimate.bytes, cat("a bake of ", estimate.nonEmptyVoxels, " voxels and up to ",
                                      estimate.distanceVoxels, " distance voxels (voxel size ",
                                      options.voxelSize, ", ", options.levels, " levels)"));

    std::vector<std::uint64_t> evaluated;
    std::vector<std::vector<BakedVoxel>> perCell =
        evaluateLevel0(voxels, k, nonEmpty, evaluated, tick);
    BakedVolume volume(buildGrids(perCell, options));
    if (stats) {
        stats->impulses = impulses.size();
        stats->lobes = std::size_t(std::count_if(
            lobes.begin(), lobes.end(), [](const BakeLobe& l) { return l.extinction > 0.0; }));
        stats->evaluatedVoxels = 0;
        for (std::uint64_t e : evaluated)
            stats->evaluatedVoxels += e;
        stats->activeVoxels.clear();
        for (int level = 0; level < options.levels; ++level)
            stats->activeVoxels.push_back(volume.activeCount(level));
        stats->distanceVoxels = volume.distanceCount();
        stats->estimate = estimate;
        stats->seconds =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    }
    return volume;
}

BakedVolume bakeNoise(const ImpulseGenerator& generator, const BakeOptions& options,
                      const std::function<void(long, long)>& progress, BakeStats* stats) {
    (void)estimateBake(generator.cells(), options);
    const auto start = std::chrono::steady_clock::now();
    const std::vector<Impulse> impulses = generator.generate();
    BakedVolume volume =
        bakeImpulses(generator.cells(), generator.kernel(), impulses, options, progress, stats);
    if (stats)
        stats->seconds =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return volume;
}

void writeBakedGrids(const std::filesystem::path& file, const BakedVolume& volume) {
    initializeOpenVdb();
    const BakedVolume::Impl& m = *volume.m_impl;
    openvdb::GridPtrVec grids;
    for (int level = 0; level < m.levels(); ++level) {
        grids.push_back(m.density[std::size_t(level)]);
        grids.push_back(m.color[std::size_t(level)]);
    }
    for (int level = 0; level < int(m.tangent.size()); ++level) {
        grids.push_back(m.tangent[std::size_t(level)]);
        grids.push_back(m.normal[std::size_t(level)]);
    }
    grids.push_back(m.distance);
    openvdb::MetaMap meta;
    meta.insertMeta("spotshell_levels", openvdb::Int32Metadata(m.levels()));
    meta.insertMeta("spotshell_voxel_size", openvdb::DoubleMetadata(m.voxel0));
    meta.insertMeta("spotshell_preset_hash", openvdb::StringMetadata(hex16(m.presetHash)));
    meta.insertMeta("spotshell_preset", openvdb::StringMetadata(m.presetName));
    meta.insertMeta("spotshell_version", openvdb::StringMetadata(m.version));
    if (m.meshHash)
        meta.insertMeta("spotshell_mesh_hash", openvdb::StringMetadata(hex16(*m.meshHash)));

    static std::atomic<unsigned> counter{0};
    const std::filesystem::path tmp = file.parent_path() / cat(".", file.filename().string(),
                                                               ".tmp-", ::getpid(), "-", counter++);
    std::error_code ec;
    try {
        openvdb::io::File f(tmp.string());
        f.write(grids, meta);
        f.close();
    } catch (const std::exception& e) {
        std::filesystem::remove(tmp, ec);
        throw InputError(cat(file.string(), ": cannot write the bake (", oneLine(e.what()), ")"));
    }
    std::filesystem::rename(tmp, file, ec);
    if (ec) {
        std::error_code ignored;
        std::filesystem::remove(tmp, ignored);
        throw InputError(cat(file.string(), ": cannot write the bake (", ec.message(), ")"));
    }
}

namespace {

/// Read grid `name` of the open file as a `GridT` at `level`, checking its type, transform and
/// values; errors name the file and the grid. `nonNegative`: a density grid, whose values are
/// extinctions (1 / world unit): a negative one would make the march's alpha 1 - exp(-sigma dt)
/// negative and add light, so the grid is refused (its background too).
template <typename GridT>
typename GridT::Ptr readBakedGrid(openvdb::io::File& in, const std::filesystem::path& file,
                                  const std::vector<std::string>& names, const std::string& name,
                                  double voxel, bool nonNegative = false) {
    const std::string where = cat(file.string(), ": grid \"", name, "\"");
    if (std::find(names.begin(), names.end(), name) == names.end()) {
        std::string list;
        for (const std::string& n : names)
            list += (list.empty() ? "\"" : ", \"") + n + "\"";
        throw InputError(cat(file.string(), ": not a complete bake: no grid \"", name,
                             "\" (it has: ", list, ")"));
    }
    const openvdb::GridBase::Ptr meta = in.readGridMetadata(name);
    if (meta->type() != GridT::gridType())
        throw InputError(
            cat(where, " is a ", meta->type(), ", a bake needs a ", GridT::gridType()));
    const openvdb::GridBase::Ptr base = in.readGrid(name);
    typename GridT::Ptr grid = openvdb::gridPtrCast<GridT>(base);
    if (!grid)
        throw InputError(cat(where, ": cannot read the grid"));
    const openvdb::math::Transform& xf = grid->transform();
    const auto near = [&](const openvdb::Vec3d& a, const openvdb::Vec3d& b) {
        return (a - b).length() <= 1e-6 * voxel;
    };
    if (!xf.isLinear() ||
        !near(xf.indexToWorld(openvdb::Vec3d(0.0)), openvdb::Vec3d(0.5 * voxel)) ||
        !near(xf.indexToWorld(openvdb::Vec3d(1, 0, 0)),
              openvdb::Vec3d(1.5 * voxel, 0.5 * voxel, 0.5 * voxel)) ||
        !near(xf.indexToWorld(openvdb::Vec3d(0, 1, 0)),
              openvdb::Vec3d(0.5 * voxel, 1.5 * voxel, 0.5 * voxel)) ||
        !near(xf.indexToWorld(openvdb::Vec3d(0, 0, 1)),
              openvdb::Vec3d(0.5 * voxel, 0.5 * voxel, 1.5 * voxel)))
        throw InputError(cat(where, ": the transform is not the bake's (voxel ", voxel,
                             ", centres at (ijk + 1/2) x voxel, no rotation)"));
    grid->tree().voxelizeActiveTiles();
    for (auto it = grid->tree().cbeginValueOn(); it; ++it) {
        const auto value = *it;
        if constexpr (std::is_same_v<GridT, Vec3Grid>) {
            if (!std::isfinite(value.x()) || !std::isfinite(value.y()) || !std::isfinite(value.z()))
                throw InputError(cat(where, ": the grid holds a NaN or infinite value"));
        } else {
            if (!std::isfinite(value))
                throw InputError(cat(where, ": the grid holds a NaN or infinite value"));
            if (nonNegative && value < 0.0f) {
                const openvdb::Coord c = it.getCoord();
                throw InputError(cat(where, ": negative density ", value, " at voxel (", c.x(),
                                     ", ", c.y(), ", ", c.z(), "); a density must be >= 0"));
            }
        }
    }
    if constexpr (!std::is_same_v<GridT, Vec3Grid>) {
        if (nonNegative && !(grid->background() >= 0.0f))
            throw InputError(cat(where, ": negative background density ", grid->background(),
                                 "; a density must be >= 0"));
    }
    return grid;
}

template <typename T>
T fileMeta(const openvdb::MetaMap& meta, const std::string& key,
           const std::filesystem::path& file) {
    const auto value = meta.getMetadata<openvdb::TypedMetadata<T>>(key);
    if (!value)
        throw InputError(cat(file.string(), ": not a spotshell bake (no ", key, " metadata)"));
    return value->value();
}

} // namespace

namespace {

/// The header and grid descriptors of a .vdb file, read as openvdb::io::File::open reads them
/// (the header through Archive's own reader, which is protected), without any grid's data.
class VdbDescriptors : public openvdb::io::Archive {
public:
    struct Range {
        std::string name;
        std::int64_t grid = 0, blocks = 0, end = 0;
    };
    std::vector<Range> read(std::istream& is) {
        readHeader(is);
        openvdb::io::setVersion(is, libraryVersion(), fileVersion());
        setDataCompression(is);
        openvdb::MetaMap meta;
        meta.readMeta(is);
        std::vector<Range> out;
        if (!inputHasGridOffsets() || !is)
            return out; // an old layout (grids read in sequence) or a cut header: File decides
        openvdb::Int32 count = 0;
        is.read(reinterpret_cast<char*>(&count), sizeof(count));
        for (openvdb::Int32 i = 0; is && i < count; ++i) {
            if (is.peek() == std::char_traits<char>::eof())
                break; // the file ends where this descriptor should start
            openvdb::io::GridDescriptor gd;
            gd.read(is);
            if (!is)
                break;
            out.push_back({gd.gridName(), gd.getGridPos(), gd.getBlockPos(), gd.getEndPos()});
            if (gd.getEndPos() < 0 || !is.seekg(gd.getEndPos(), std::ios_base::beg))
                break;
        }
        if (!is || std::int64_t(out.size()) != std::int64_t(count))
            out.push_back({cat("#", out.size() + 1), -1, -1, -1}); // its descriptor is cut off
        return out;
    }
};

} // namespace

void requireVdbGridsInFile(const std::filesystem::path& file) {
    initializeOpenVdb();
    std::error_code ec;
    const std::uintmax_t size = std::filesystem::file_size(file, ec);
    if (ec)
        throw InputError(cat(file.string(), ": cannot read (", ec.message(), ")"));
    std::ifstream is(file, std::ios_base::binary);
    if (!is)
        throw InputError(cat(file.string(), ": cannot open"));
    std::int64_t previous = 0;
    for (const VdbDescriptors::Range& r : VdbDescriptors().read(is)) {
        if (r.grid == -1)
            throw InputError(cat(file.string(),
                                 ": cannot read, truncated or corrupt: the file ends "
                                 "before the description of grid ",
                                 r.name, " (of ", size, " bytes)"));
        if (r.grid < previous || r.grid > r.blocks || r.blocks > r.end ||
            std::uintmax_t(r.end) > size)
            throw InputError(cat(file.string(), ": cannot read, truncated or corrupt: grid \"",
                                 r.name, "\" spans bytes ", r.grid, " to ", r.end, " of a file of ",
                                 size, " bytes"));
        previous = r.end;
    }
}

BakedVolume readBakedGrids(const std::filesystem::path& file) {
    initializeOpenVdb();
    std::error_code ec;
    if (!std::filesystem::is_regular_file(file, ec))
        throw InputError(cat(file.string(), ": no such bake file"));
    auto impl = std::make_unique<BakedVolume::Impl>();
    try {
        requireVdbGridsInFile(file);
        openvdb::io::File in(file.string());
        in.open(false); // everything read now: no memory map left on a file that may change
        std::vector<std::string> names;
        for (auto it = in.beginName(); it != in.endName(); ++it)
            names.push_back(*it);
        if (names.empty())
            throw InputError(cat(file.string(), ": cannot read (the file holds no grids: empty, "
                                                "truncated or not a .vdb file)"));
        const openvdb::MetaMap::Ptr meta = in.getMetadata();
        const int levels = fileMeta<openvdb::Int32>(*meta, "spotshell_levels", file);
        if (levels < 1 || levels > kMaxBakeLevels)
            throw InputError(
                cat(file.string(), ": ", levels, " levels is outside [1, ", kMaxBakeLevels, "]"));
        const double voxel = fileMeta<double>(*meta, "spotshell_voxel_size", file);
        if (!(std::isfinite(voxel) && voxel > 0.0 && voxel < 1e30))
            throw InputError(cat(file.string(), ": voxel size ", voxel, " is not finite and > 0"));
        const std::string hash = fileMeta<std::string>(*meta, "spotshell_preset_hash", file);
        impl->voxel0 = voxel;
        impl->presetHash = std::strtoull(hash.c_str(), nullptr, 16);
        impl->presetName = fileMeta<std::string>(*meta, "spotshell_preset", file);
        impl->version = fileMeta<std::string>(*meta, "spotshell_version", file);
        if (const auto mesh = meta->getMetadata<openvdb::StringMetadata>("spotshell_mesh_hash")) {
            char* end = nullptr;
            const std::string& text = mesh->value();
            const std::uint64_t value = std::strtoull(text.c_str(), &end, 16);
            if (text.size() != 16 || end != text.c_str() + text.size())
                throw InputError(
                    cat(file.string(), ": spotshell_mesh_hash '", text, "' is not 16 hex digits"));
            impl->meshHash = value;
        }
        // Refuse a file whose grids would not fit before reading their trees.
        std::uint64_t bytes = 0;
        for (const std::string& name : names)
            if (const auto count = in.readGridMetadata(name)->getMetadata<openvdb::Int64Metadata>(
                    "file_voxel_count"))
                bytes += std::uint64_t(std::max<openvdb::Int64>(count->value(), 0)) * 16;
        requireMemory(bytes, cat("reading the bake ", file.string()));
        for (int level = 0; level < levels; ++level) {
            const double vl = levelVoxel(voxel, level);
            impl->density.push_back(
                readBakedGrid<FloatGrid>(in, file, names, bakedDensityName(level), vl, true));
            impl->color.push_back(
                readBakedGrid<Vec3Grid>(in, file, names, bakedColorName(level), vl));
        }
        // The shading grids: all or none (a bake written before them has none).
        if (std::find(names.begin(), names.end(), bakedTangentName(0)) != names.end())
            for (int level = 0; level < levels; ++level) {
                const double vl = levelVoxel(voxel, level);
                impl->tangent.push_back(
                    readBakedGrid<Vec3Grid>(in, file, names, bakedTangentName(level), vl));
                impl->normal.push_back(
                    readBakedGrid<Vec3Grid>(in, file, names, bakedNormalName(level), vl));
            }
        impl->distance = readBakedGrid<FloatGrid>(in, file, names, kBakedDistanceName, voxel);
        in.close();
    } catch (const InputError&) {
        throw;
    } catch (const std::exception& e) {
        throw InputError(cat(file.string(), ": cannot read the bake, corrupt or truncated (",
                             oneLine(e.what()), ")"));
    }
    return BakedVolume(std::move(impl));
}

} // namespace spot::noise
