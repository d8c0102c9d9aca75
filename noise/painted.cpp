#include "noise/painted.h"

#include <algorithm>
#include <atomic>
#include <bit>
#include <cmath>
#include <mutex>
#include <string>
#include <system_error>
#include <vector>

#include <unistd.h>

#include <openvdb/io/File.h>
#include <openvdb/openvdb.h>

#include "noise/bake.h"
#include "noise/error.h"
#include "noise/generator_shared.h"
#include "noise/system.h"

namespace spot::noise {

namespace {

using FloatGrid = openvdb::FloatGrid;
using Vec3Grid = openvdb::Vec3SGrid;

void initializeOpenVdb() {
    static std::once_flag once;
    std::call_once(once, [] { openvdb::initialize(); });
}

bool finite(glm::vec3 v) {
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

glm::vec3 toGlm(float v) {
    return glm::vec3(v, 0.0f, 0.0f);
}
glm::vec3 toGlm(const openvdb::Vec3s& v) {
    return glm::vec3(v.x(), v.y(), v.z());
}
void fromGlm(glm::vec3 v, float& out) {
    out = v.x;
}
void fromGlm(glm::vec3 v, openvdb::Vec3s& out) {
    out = openvdb::Vec3s(v.x, v.y, v.z);
}

openvdb::Coord coord(glm::ivec3 v) {
    return openvdb::Coord(v.x, v.y, v.z);
}
glm::ivec3 ivec(const openvdb::Coord& c) {
    return glm::ivec3(c.x(), c.y(), c.z());
}

float asFloat(std::int32_t i) {
    return std::bit_cast<float>(i);
}

/// A uniform scale with no rotation or translation: index ijk at world ijk x voxelSize.
openvdb::math::Transform::Ptr uniformTransform(float voxelSize) {
    return openvdb::math::Transform::createLinearTransform(double(voxelSize));
}

} // namespace

struct PaintedGrid::Impl {
    std::string name;
    int components = 1;
    float voxelSize = 1.0f;
    glm::vec3 background{0.0f};
    FloatGrid::Ptr scalar; ///< when components == 1
    Vec3Grid::Ptr vector;  ///< when components == 3

    /// The flattened form, rebuilt by sample() after a change.
    mutable std::mutex flatMutex;
    mutable bool flatValid = false;
    std::atomic<std::uint64_t> version{0};
    mutable std::vector<float> flatData;
    mutable gpu::SpotGenParams flatParams{};

    template <typename F> decltype(auto) visit(F&& f) const {
        return components == 1 ? f(*scalar) : f(*vector);
    }
    openvdb::GridBase& grid() const {
        return components == 1 ? static_cast<openvdb::GridBase&>(*scalar)
                               : static_cast<openvdb::GridBase&>(*vector);
    }
};

PaintedGrid::PaintedGrid(std::unique_ptr<Impl> impl) : m_impl(std::move(impl)) {}

PaintedGrid::PaintedGrid(std::string name, int components, float voxelSize, glm::vec3 background)
    : m_impl(std::make_unique<Impl>()) {
    initializeOpenVdb();
    if (components != 1 && components != 3)
        throw InputError(
            cat("painted grid \"", name, "\": a grid has 1 or 3 components, not ", components));
    if (!(std::isfinite(voxelSize) && voxelSize > 0.0f))
        throw InputError(
            cat("painted grid \"", name, "\": voxel size ", voxelSize, " is not finite and > 0"));
    if (!finite(background))
        throw InputError(cat("painted grid \"", name, "\": background is not finite"));
    Impl& m = *m_impl;
    m.name = std::move(name);
    m.components = components;
    m.voxelSize = voxelSize;
    m.background = components == 1 ? glm::vec3(background.x, 0.0f, 0.0f) : background;
    if (components == 1) {
        m.scalar = FloatGrid::create(m.background.x);
        m.scalar->setTransform(uniformTransform(voxelSize));
        m.scalar->setName(m.name);
    } else {
        m.vector = Vec3Grid::create(openvdb::Vec3s(background.x, background.y, background.z));
        m.vector->setTransform(uniformTransform(voxelSize));
        m.vector->setName(m.name);
    }
}

PaintedGrid::PaintedGrid(PaintedGrid&&) noexcept = default;
PaintedGrid& PaintedGrid::operator=(PaintedGrid&&) noexcept = default;
PaintedGrid::~PaintedGrid() = default;

const std::string& PaintedGrid::name() const {
    return m_impl->name;
}
int PaintedGrid::components() const {
    return m_impl->components;
}
float PaintedGrid::voxelSize() const {
    return m_impl->voxelSize;
}
glm::vec3 PaintedGrid::background() const {
    return m_impl->background;
}

glm::ivec3 PaintedGrid::nearestVoxel(glm::vec3 world) const {
    return glm::ivec3(glm::round(world / m_impl->voxelSize));
}

glm::vec3 PaintedGrid::voxelPosition(glm::ivec3 v) const {
    return glm::vec3(v) * m_impl->voxelSize;
}

glm::vec3 PaintedGrid::get(glm::ivec3 v) const {
    return m_impl->visit([&](const auto& grid) {
        const auto acc = grid.getConstAccessor();
        const openvdb::Coord c = coord(v);
        return acc.isValueOn(c) ? toGlm(acc.getValue(c)) : m_impl->background;
    });
}

bool PaintedGrid::active(glm::ivec3 v) const {
    return m_impl->visit([&](const auto& grid) { return grid.tree().isValueOn(coord(v)); });
}

void PaintedGrid::set(glm::ivec3 v, glm::vec3 value) {
    if (!finite(value))
        throw InputError(cat("painted grid \"", m_impl->name, "\": value at voxel (", v.x, ", ",
                             v.y, ", ", v.z, ") is not finite"));
    m_impl->visit([&](auto& grid) {
        typename std::remove_cvref_t<decltype(grid)>::ValueType stored;
        fromGlm(value, stored);
        const_cast<std::remove_cvref_t<decltype(grid)>&>(grid).tree().setValueOn(coord(v), stored);
    });
    changed();
}

void PaintedGrid::clear(glm::ivec3 v) {
    m_impl->visit([&](auto& grid) {
        // The stored value becomes the background too, so an inactive voxel holds nothing stale.
        auto& tree = const_cast<std::remove_cvref_t<decltype(grid)>&>(grid).tree();
        tree.setValueOff(coord(v), tree.background());
    });
    changed();
}

void PaintedGrid::changed() {
    std::lock_guard lock(m_impl->flatMutex);
    m_impl->flatValid = false;
    ++m_impl->version;
}

std::uint64_t PaintedGrid::version() const {
    return m_impl->version;
}

std::size_t PaintedGrid::activeCount() const {
    return std::size_t(m_impl->grid().activeVoxelCount());
}

void PaintedGrid::forEachActive(const std::function<void(glm::ivec3, glm::vec3)>& f) const {
    m_impl->visit([&](const auto& grid) {
        for (auto it = grid.cbeginValueOn(); it; ++it) {
            const glm::vec3 value = toGlm(*it);
            if (it.isVoxelValue()) {
                f(ivec(it.getCoord()), value);
                continue;
            }
            // An active tile (a grid read from a file keeps none: they are voxelized) stands for
            // every voxel of its box.
            openvdb::CoordBBox box;
            it.getBoundingBox(box);
            for (auto c = box.begin(); c; ++c)
                f(ivec(*c), value);
        }
    });
}

std::uint64_t PaintedGrid::memoryBytes() const {
    return m_impl->grid().memUsage();
}

std::shared_ptr<PaintedGrid> PaintedGrid::clone() const {
    auto impl = std::make_unique<Impl>();
    impl->name = m_impl->name;
    impl->components = m_impl->components;
    impl->voxelSize = m_impl->voxelSize;
    impl->background = m_impl->background;
    if (m_impl->components == 1)
        impl->scalar = m_impl->scalar->deepCopy();
    else
        impl->vector = m_impl->vector->deepCopy();
    return std::shared_ptr<PaintedGrid>(new PaintedGrid(std::move(impl)));
}

void PaintedGrid::valueRange(glm::vec3& lo, glm::vec3& hi) const {
    lo = hi = m_impl->background;
    forEachActive([&](glm::ivec3, glm::vec3 v) {
        lo = glm::min(lo, v);
        hi = glm::max(hi, v);
    });
    if (m_impl->components == 1) {
        lo = glm::vec3(lo.x, 0.0f, 0.0f);
        hi = glm::vec3(hi.x, 0.0f, 0.0f);
    }
}

gpu::SpotField PaintedGrid::flatten(std::vector<float>& data) const {
    const Impl& m = *m_impl;
    const int n = m.components;
    const std::uint32_t perBlock =
        std::uint32_t(shared::f32::SharedGenerator::kPaintedLeafVoxels) * std::uint32_t(n);

    // The leaves holding an active voxel, in tree order, and their blocks of values.
    std::vector<glm::ivec3> leaves;
    std::vector<float> blocks;
    const auto budget = [&](std::uint64_t leafCount, std::uint64_t tableSize) {
        const std::uint64_t bytes =
            (leafCount * perBlock + 4 * tableSize) * sizeof(float) + data.size() * sizeof(float);
        if (bytes > kMaxPaintedBytes || bytes / sizeof(float) > UINT32_MAX)
            throw InputError(cat("painted grid \"", m.name, "\": ", leafCount,
                                 " leaves of 8^3 voxels flatten to ", bytes >> 20,
                                 " MiB of field data, more than the limit of ",
                                 kMaxPaintedBytes >> 20, " MiB"));
    };
    m.visit([&](const auto& grid) {
        std::uint64_t count = 0;
        for (auto leaf = grid.tree().cbeginLeaf(); leaf; ++leaf)
            count += leaf->isEmpty() ? 0 : 1;
        budget(count, 2 * count);
        requireMemory(count * perBlock * sizeof(float), cat("painted grid \"", m.name, "\""));
        leaves.reserve(count);
        blocks.reserve(count * perBlock);
        for (auto leaf = grid.tree().cbeginLeaf(); leaf; ++leaf) {
            if (leaf->isEmpty())
                continue;
            leaves.push_back(ivec(leaf->origin()) >> 3);
            for (openvdb::Index i = 0; i < 512; ++i) {
                const glm::vec3 v = leaf->isValueOn(i) ? toGlm(leaf->getValue(i)) : m.background;
                for (int c = 0; c < n; ++c)
                    blocks.push_back(v[c]);
            }
        }
    });

    // The hash table: the smallest power of two >= 2 x leaves whose longest probe is short.
    std::uint32_t size = 2;
    while (size < 2 * leaves.size())
        size *= 2;
    std::vector<std::int32_t> table;
    std::uint32_t longest = 0;
    for (;;) {
        budget(leaves.size(), size);
        table.assign(std::size_t(size) * 4, 0);
        longest = 0;
        const std::uint32_t mask = size - 1;
        shared::f32::SharedGenerator hasher{shared::f32::GeneratorArrays{}};
        bool fits = true;
        for (std::size_t b = 0; b < leaves.size() && fits; ++b) {
            const std::uint32_t home = hasher.spotPaintedHash(leaves[b]) & mask;
            std::uint32_t probe = 0;
            while (table[4 * ((home + probe) & mask) + 3] != 0)
                ++probe;
            if (probe >= shared::f32::SharedGenerator::kPaintedMaxProbe) {
                fits = false;
                break;
            }
            const std::size_t e = 4 * ((home + probe) & mask);
            table[e] = leaves[b].x;
            table[e + 1] = leaves[b].y;
            table[e + 2] = leaves[b].z;
            table[e + 3] = std::int32_t(b) + 1;
            longest = std::max(longest, probe);
        }
        if (fits)
            break;
        size *= 2;
    }

    gpu::SpotField f{};
    f.kind = glm::ivec4(shared::f32::SharedGenerator::kFieldPainted, n, 0, 0);
    f.value = glm::vec4(m.background, 0.0f);
    f.from = glm::vec4(0.0f, 0.0f, 0.0f, 1.0f / m.voxelSize);
    const auto tableOffset = std::uint32_t(data.size());
    for (const std::int32_t i : table)
        data.push_back(asFloat(i));
    const auto blocksOffset = std::uint32_t(data.size());
    data.insert(data.end(), blocks.begin(), blocks.end());
    f.data = glm::uvec4(tableOffset, size, longest, blocksOffset);
    glm::vec3 lo, hi;
    valueRange(lo, hi);
    f.clampLo = glm::vec4(lo, 0.0f);
    f.clampHi = glm::vec4(hi, 0.0f);
    return f;
}

glm::vec3 PaintedGrid::sample(glm::vec3 world) const {
    Impl& m = *m_impl;
    {
        std::lock_guard lock(m.flatMutex);
        if (!m.flatValid) {
            m.flatData.clear();
            m.flatParams = gpu::SpotGenParams{};
            m.flatParams.fields[0] = flatten(m.flatData);
            m.flatValid = true;
        }
    }
    shared::f32::GeneratorArrays arrays;
    arrays.fieldData = m.flatData.data();
    arrays.params = &m.flatParams;
    shared::f32::SharedGenerator generator(arrays);
    shared::f32::SharedGenerator::SpotSurface s{};
    s.position = world;
    return generator.spotFieldEval(0u, s);
}

std::string paintWeightGrid(const std::string& grid) {
    return grid + ".weight";
}

PaintLayer::PaintLayer(const std::string& name, int components, float voxelSize, PaintMode mode)
    : m_value(name, components, voxelSize,
              glm::vec3(mode == PaintMode::Density ? 1.0f : 0.0f, 0.0f, 0.0f)),
      m_weight(paintWeightGrid(name), 1, voxelSize, glm::vec3(0.0f)), m_mode(mode) {}

PaintLayer::PaintLayer(PaintedGrid value, PaintedGrid weight, PaintMode mode)
    : m_value(std::move(value)), m_weight(std::move(weight)), m_mode(mode) {
    if (m_weight.components() != 1 || m_weight.voxelSize() != m_value.voxelSize())
        throw InputError(cat("paint layer \"", m_value.name(), "\": its weight grid \"",
                             m_weight.name(), "\" needs 1 component and the same voxel size"));
}

glm::vec4 PaintLayer::get(glm::ivec3 v) const {
    return glm::vec4(m_value.get(v), m_weight.get(v).x);
}

bool PaintLayer::active(glm::ivec3 v) const {
    return m_value.active(v);
}

void PaintLayer::set(glm::ivec3 v, glm::vec4 value) {
    m_value.set(v, glm::vec3(value));
    m_weight.set(v, glm::vec3(value.w, 0.0f, 0.0f));
}

void PaintLayer::clear(glm::ivec3 v) {
    m_value.clear(v);
    m_weight.clear(v);
}

std::shared_ptr<PaintLayer> PaintLayer::clone() const {
    return std::make_shared<PaintLayer>(std::move(*m_value.clone()), std::move(*m_weight.clone()),
                                        m_mode);
}

PaintLayer readPaintLayer(const std::filesystem::path& file, const std::string& grid,
                          int components, PaintMode mode) {
    PaintedGrid value = readPaintedGrid(file, grid, components);
    PaintedGrid weight = readPaintedGrid(file, paintWeightGrid(grid), 1);
    const auto inUnit = [](const PaintedGrid& g) {
        glm::vec3 lo, hi;
        g.valueRange(lo, hi);
        return lo.x >= 0.0f && hi.x <= 1.0f;
    };
    const std::string where = cat("paint layer \"", grid, "\" of ", file.string());
    if (!inUnit(weight))
        throw InputError(cat(where, ": its weight grid holds values outside [0, 1]"));
    if (mode == PaintMode::Density && !inUnit(value))
        throw InputError(cat(where, ": a density multiplier outside [0, 1]"));
    if (weight.voxelSize() != value.voxelSize())
        throw InputError(cat(where, ": its two grids have different voxel sizes"));
    return PaintLayer(std::move(value), std::move(weight), mode);
}

PaintedGrid readPaintedGrid(const std::filesystem::path& file, const std::string& grid,
                            int components) {
    initializeOpenVdb();
    const std::string where = cat("painted grid \"", grid, "\" of ", file.string());
    if (components != 1 && components != 3)
        throw InputError(cat(where, ": a grid has 1 or 3 components, not ", components));
    std::error_code ec;
    if (!std::filesystem::is_regular_file(file, ec))
        throw InputError(cat(where, ": no such file"));
    const openvdb::Name wanted = components == 1 ? FloatGrid::gridType() : Vec3Grid::gridType();

    openvdb::GridBase::Ptr base;
    try {
        requireVdbGridsInFile(file); // a truncated file stops here, not in OpenVDB's reader
        openvdb::io::File in(file.string());
        in.open(false); // read everything now: no memory map left on a file that may change
        std::vector<std::string> names;
        for (auto it = in.beginName(); it != in.endName(); ++it)
            names.push_back(*it);
        if (names.empty())
            throw InputError(cat(where, ": cannot read (the file holds no grids: empty, "
                                        "truncated or not a .vdb file)"));
        if (std::find(names.begin(), names.end(), grid) == names.end()) {
            std::string list;
            for (const std::string& name : names)
                list += (list.empty() ? "\"" : ", \"") + name + "\"";
            throw InputError(cat(where, ": the file has no grid of that name (it has: ",
                                 list.empty() ? std::string("none") : list, ")"));
        }
        const openvdb::GridBase::Ptr meta = in.readGridMetadata(grid);
        if (meta->type() != wanted)
            throw InputError(cat(where, ": grid is a ", meta->type(), ", a ", components,
                                 "-component field needs a ", wanted));
        // The writer records the voxel count: refuse an absurd grid before reading its tree.
        if (const auto count = meta->getMetadata<openvdb::Int64Metadata>("file_voxel_count"))
            if (std::uint64_t(std::max<openvdb::Int64>(count->value(), 0)) >
                kMaxPaintedBytes / (sizeof(float) * std::uint64_t(components)))
                throw InputError(cat(where, ": ", count->value(),
                                     " active voxels are more than a painted field may hold (",
                                     kMaxPaintedBytes >> 20, " MiB)"));
        base = in.readGrid(grid);
        in.close();
    } catch (const InputError&) {
        throw;
    } catch (const std::exception& e) {
        throw InputError(cat(where, ": cannot read (", oneLine(e.what()), ")"));
    }
    if (!base || base->type() != wanted)
        throw InputError(cat(where, ": cannot read the grid"));

    const openvdb::math::Transform& xform = base->transform();
    const double voxel = xform.voxelSize()[0];
    const auto near = [&](const openvdb::Vec3d& a, const openvdb::Vec3d& b) {
        return (a - b).length() <= 1e-6 * std::max(voxel, 1e-30);
    };
    if (!xform.isLinear() || !(voxel > 0.0) || !std::isfinite(voxel) || voxel > 1e30 ||
        !near(xform.indexToWorld(openvdb::Vec3d(0.0)), openvdb::Vec3d(0.0)) ||
        !near(xform.indexToWorld(openvdb::Vec3d(1, 0, 0)), openvdb::Vec3d(voxel, 0, 0)) ||
        !near(xform.indexToWorld(openvdb::Vec3d(0, 1, 0)), openvdb::Vec3d(0, voxel, 0)) ||
        !near(xform.indexToWorld(openvdb::Vec3d(0, 0, 1)), openvdb::Vec3d(0, 0, voxel)))
        throw InputError(cat(where, ": the transform is not a uniform scale about the origin "
                                    "(a painted grid may not be rotated, stretched or moved)"));
    if (std::uint64_t(base->activeVoxelCount()) >
        kMaxPaintedBytes / (sizeof(float) * std::uint64_t(components)))
        throw InputError(cat(where, ": ", base->activeVoxelCount(),
                             " active voxels are more than a painted field may hold (",
                             kMaxPaintedBytes >> 20, " MiB)"));

    auto impl = std::make_unique<PaintedGrid::Impl>();
    impl->name = grid;
    impl->components = components;
    impl->voxelSize = float(voxel);
    if (components == 1) {
        impl->scalar = openvdb::gridPtrCast<FloatGrid>(base);
        impl->scalar->tree().voxelizeActiveTiles();
        impl->background = toGlm(impl->scalar->background());
        impl->scalar->setTransform(uniformTransform(impl->voxelSize));
    } else {
        impl->vector = openvdb::gridPtrCast<Vec3Grid>(base);
        impl->vector->tree().voxelizeActiveTiles();
        impl->background = toGlm(impl->vector->background());
        impl->vector->setTransform(uniformTransform(impl->voxelSize));
    }
    PaintedGrid result(std::move(impl));
    if (!finite(result.background()))
        throw InputError(cat(where, ": the background is not finite"));
    bool allFinite = true;
    result.forEachActive([&](glm::ivec3, glm::vec3 v) { allFinite = allFinite && finite(v); });
    if (!allFinite)
        throw InputError(cat(where, ": the grid holds a NaN or infinite value"));
    return result;
}

void writePaintedGrids(const std::filesystem::path& file,
                       const std::vector<const PaintedGrid*>& grids) {
    initializeOpenVdb();
    openvdb::GridPtrVec out;
    std::vector<std::string> names;
    for (const PaintedGrid* g : grids) {
        SPOT_CHECK(g != nullptr);
        if (g->name().empty() || std::find(names.begin(), names.end(), g->name()) != names.end())
            throw InputError(cat(file.string(),
                                 ": painted grids need distinct, non-empty names "
                                 "(\"",
                                 g->name(), "\")"));
        names.push_back(g->name());
        openvdb::GridBase::Ptr copy = g->m_impl->grid().copyGrid(); // shares the tree
        copy->setName(g->name());
        out.push_back(copy);
    }
    static std::atomic<unsigned> counter{0};
    const std::filesystem::path tmp = file.parent_path() / cat(".", file.filename().string(),
                                                               ".tmp-", ::getpid(), "-", counter++);
    std::error_code ec;
    try {
        openvdb::io::File f(tmp.string());
        f.write(out);
        f.close();
    } catch (const std::exception& e) {
        std::filesystem::remove(tmp, ec);
        throw InputError(
            cat(file.string(), ": cannot write painted grids (", oneLine(e.what()), ")"));
    }
    std::filesystem::rename(tmp, file, ec);
    if (ec) {
        std::error_code ignored;
        std::filesystem::remove(tmp, ignored);
        throw InputError(cat(file.string(), ": cannot write painted grids (", ec.message(), ")"));
    }
}

} // namespace spot::noise
