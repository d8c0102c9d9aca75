#include "deform_vk.h"

#include <algorithm>
#include <limits>

#include "deform_frames.comp.h"
#include "deform_move.comp.h"
#include "deform_normals.comp.h"
#include "deform_pose.comp.h"
#include "noise/error.h"
#include "shaders/spot_deform.hpp"

namespace spot::splat {

namespace {

using namespace passes;
using gpu::SpotDeformPush;
using namespace gpu; // the binding names

constexpr VkBufferUsageFlags kStorage = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT;
constexpr auto kHost = Buffer::Memory::HostVisible;

/// `items` into `buffer`, grown (with a quarter more room) when it holds too few.
template <typename T>
void put(Context& ctx, Buffer& buffer, const std::vector<T>& items, const char* what) {
    const VkDeviceSize need = std::max<VkDeviceSize>(items.size() * sizeof(T), 16);
    if (!buffer.handle() || buffer.size() < need) {
        buffer = Buffer();
        buffer = Buffer(ctx, need + need / 4, kStorage, kHost, what);
    }
    if (!items.empty())
        buffer.upload(items.data(), items.size() * sizeof(T));
}

void dispatch(VkCommandBuffer cmd, std::uint32_t n) {
    const std::uint32_t groups = (n + kDeformGroup - 1) / kDeformGroup;
    if (groups == 0)
        return;
    const std::uint32_t x = std::min<std::uint32_t>(groups, 65535);
    vkCmdDispatch(cmd, x, (groups + x - 1) / x, 1);
}

void bind(VkCommandBuffer cmd, const Pipeline& p, const SpotDeformPush& push) {
    vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, p.handle());
    vkCmdPushConstants(cmd, p.layout(), VK_SHADER_STAGE_COMPUTE_BIT, 0, sizeof(push), &push);
}

} // namespace

GpuDeformer::GpuDeformer(Context& ctx, const noise::AnimatedMesh& animation, MeshPass& mesh,
                         const noise::SurfaceCells& cells, const noise::Wind& wind)
    : m_ctx(ctx), m_animation(animation), m_mesh(mesh), m_cells(cells), m_wind(wind) {
    const noise::Mesh& rest = animation.rest();
    m_vertexCount = std::uint32_t(rest.positions.size());
    m_triangleCount = std::uint32_t(rest.triangles.size());
    // Each vertex's corners (offsets, then the lists of 3 t + k): the corners of every triangle
    // at its welded vertex, so that split copies of a vertex (uv and normal seams) get one
    // normal: the normals pass gathers over them.
    const std::vector<glm::uvec3> welded = rest.weldedTriangles();
    std::vector<std::uint32_t> valence(m_vertexCount, 0);
    for (const glm::uvec3& t : welded)
        for (int k = 0; k < 3; ++k)
            ++valence[t[k]];
    std::vector<std::uint32_t> first(m_vertexCount + 1, 0); // per welded vertex, into `corners`
    for (std::uint32_t v = 0; v < m_vertexCount; ++v)
        first[v + 1] = first[v] + valence[v];
    std::vector<std::uint32_t> corners(first[m_vertexCount]);
    {
        std::vector<std::uint32_t> fill(first.begin(), first.end() - 1);
        for (std::uint32_t t = 0; t < m_triangleCount; ++t)
            for (std::uint32_t k = 0; k < 3; ++k)
                corners[fill[welded[t][int(k)]]++] = 3 * t + k;
    }
    std::size_t entries = 0;
    for (std::uint32_t v = 0; v < m_vertexCount; ++v) {
        const std::uint32_t w = rest.welded(v);
        if (valence[w] > kDeformMaxValence)
            throw InputError(cat(rest.name, ": vertex ", v, " is shared by ", valence[w],
                                 " triangles, more than the ", kDeformMaxValence,
                                 " an animated mesh may have"));
        entries += valence[w];
    }
    if (entries > std::size_t(std::numeric_limits<std::uint32_t>::max()) - m_vertexCount - 1)
        throw InputError(cat(rest.name, ": its vertices' corners do not fit 32-bit offsets"));
    std::vector<std::uint32_t> adjacency(m_vertexCount + 1 + entries, 0);
    for (std::uint32_t v = 0; v < m_vertexCount; ++v) {
        const std::uint32_t w = rest.welded(v);
        adjacency[v + 1] = adjacency[v] + valence[w];
        std::copy(corners.begin() + first[w], corners.begin() + first[w + 1],
                  adjacency.begin() + m_vertexCount + 1 + adjacency[v]);
    }
    put(ctx, m_adjacency, adjacency, "deform adjacency");
    // Every triangle starts at rest (no rotation).
    std::vector<glm::vec4> rotations(3 * std::size_t(m_triangleCount));
    for (std::size_t t = 0; t < m_triangleCount; ++t) {
        rotations[3 * t] = glm::vec4(1, 0, 0, 0);
        rotations[3 * t + 1] = glm::vec4(0, 1, 0, 0);
        rotations[3 * t + 2] = glm::vec4(0, 0, 1, 0);
    }
    put(ctx, m_rotations, rotations, "deform rotations");
    mesh.keepRest();

    m_pose = makeComputePipeline(
        ctx, spirv(spv_deform_pose_comp),
        {storageBuffer(kDeformBindVertices), storageBuffer(kDeformBindPieces),
         storageBuffer(kDeformBindDeltas), storageBuffer(kDeformBindPalette),
         storageBuffer(kDeformBindWeights), storageBuffer(kDeformBindPosed)},
        sizeof(SpotDeformPush));
    m_normals = makeComputePipeline(ctx, spirv(spv_deform_normals_comp),
                                    {storageBuffer(kDeformBindPosed),
                                     storageBuffer(kDeformBindIndices),
                                     storageBuffer(kDeformBindAdjacency)},
                                    sizeof(SpotDeformPush));
    m_frames = makeComputePipeline(
        ctx, spirv(spv_deform_frames_comp),
        {storageBuffer(kDeformBindPosed), storageBuffer(kDeformBindRest),
         storageBuffer(kDeformBindIndices), storageBuffer(kDeformBindRotations)},
        sizeof(SpotDeformPush));
    m_move = makeComputePipeline(
        ctx, spirv(spv_deform_move_comp),
        {storageBuffer(kDeformBindPosed), storageBuffer(kDeformBindIndices),
         storageBuffer(kDeformBindRotations), storageBuffer(kDeformBindImpulses),
         storageBuffer(kDeformBindMoved), storageBuffer(kDeformBindCount)},
        sizeof(SpotDeformPush));
}

void GpuDeformer::prepare(double t) {
    m_time = m_animation.animated() ? m_animation.clampTime(t) : t;
    m_animation.poseInputs(m_time, m_inputs);
    if (m_inputs.vertices.size() != m_vertexCount)
        throw InputError(cat("deform: the pose has ", m_inputs.vertices.size(),
                             " vertices, the mesh ", m_vertexCount));
    if (m_uploadedGeometry != m_inputs.geometry) {
        put(m_ctx, m_vertices, m_inputs.vertices, "deform vertices");
        put(m_ctx, m_pieces, m_inputs.pieces, "deform pieces");
        put(m_ctx, m_deltas, m_inputs.deltas, "deform morph deltas");
        m_uploadedGeometry = m_inputs.geometry;
    }
    put(m_ctx, m_palette, m_inputs.palette, "deform palette");
    put(m_ctx, m_weights, m_inputs.weights, "deform morph weights");
    // The same pose on the host, for culling and the mesh's bounds.
    shared::f32::SharedPoser poser(m_inputs.arrays());
    m_posed.resize(m_vertexCount);
    glm::vec3 lo(std::numeric_limits<float>::max()), hi = -lo;
    for (std::uint32_t v = 0; v < m_vertexCount; ++v) {
        m_posed[v] = poser.spotPoseVertex(v);
        lo = glm::min(lo, m_posed[v]);
        hi = glm::max(hi, m_posed[v]);
    }
    m_mesh.setBounds(lo, hi);
    m_posedCellsValid = false;
}

const noise::SurfaceCells& GpuDeformer::posedCells() {
    if (m_posedCellsValid)
        return m_posedCells;
    const float h = m_cells.cellSize;
    const std::vector<glm::uvec3>& triangles = m_animation.rest().triangles;
    std::vector<glm::ivec3> found;
    for (const noise::SurfacePiece& p : m_cells.pieces) {
        const glm::uvec3 t = triangles[p.triangle];
        glm::vec3 lo(std::numeric_limits<float>::max()), hi = -lo;
        for (const glm::vec2& c : p.corner) {
            const glm::vec3 q =
                (1.0f - c.x - c.y) * m_posed[t.x] + c.x * m_posed[t.y] + c.y * m_posed[t.z];
            lo = glm::min(lo, q);
            hi = glm::max(hi, q);
        }
        const glm::ivec3 a(glm::floor(lo / h)), b(glm::floor(hi / h));
        if (glm::any(glm::greaterThan(b - a, glm::ivec3(64))))
            throw InputError(cat("deform: a posed surface piece spans more than 64 cells along an "
                                 "axis; the pose stretches the mesh too far"));
        for (int i = a.x; i <= b.x; ++i)
            for (int j = a.y; j <= b.y; ++j)
                for (int k = a.z; k <= b.z; ++k)
                    found.emplace_back(i, j, k);
    }
    const auto less = [](const glm::ivec3& x, const glm::ivec3& y) {
        return x.x != y.x ? x.x < y.x : x.y != y.y ? x.y < y.y : x.z < y.z;
    };
    std::sort(found.begin(), found.end(), less);
    found.erase(std::unique(found.begin(), found.end()), found.end());
    m_posedCells = noise::SurfaceCells{};
    m_posedCells.cellSize = h;
    m_posedCells.cells.resize(found.size());
    for (std::size_t i = 0; i < found.size(); ++i)
        m_posedCells.cells[i].ijk = found[i];
    m_posedCellsValid = true;
    return m_posedCells;
}

bool GpuDeformer::cellVisible(const noise::CameraRays& rays, const noise::SurfaceCells& cells,
                              const noise::SurfaceCell& cell) const {
    glm::vec3 lo, hi;
    noise::posedCellBounds(cells, cell, m_animation.rest().triangles, m_posed, lo, hi);
    const double h = cells.cellSize;
    return rays.boxMayBeVisible(glm::dvec3(lo) - h, glm::dvec3(hi) + h);
}

bool GpuDeformer::current(const ImpulseSet& rest) const {
    return m_last.valid && m_last.time == m_time && rest.version != 0 &&
           m_last.version == rest.version && m_last.impulses == rest.impulses &&
           rest.impulses && m_last.handle == rest.impulses->handle() &&
           m_last.capacity == rest.capacity;
}

void GpuDeformer::record(VkCommandBuffer cmd, PassTimer& timer, const ImpulseSet& rest) {
    if (current(rest)) {
        m_reserved = false;
        return;
    }
    SpotDeformPush push{};
    push.counts = glm::uvec4(m_vertexCount, m_triangleCount, rest.capacity, m_wind.on() ? 1u : 0u);
    push.wind = glm::vec4(m_wind.direction, m_wind.strength);
    push.gust = glm::vec4(m_wind.gustFrequency, m_wind.variation, float(m_time), m_cells.cellSize);
    const Buffer& posed = m_mesh.vertices();
    // Every earlier write (the host's uploads, the last frame's reads of the vertices) first.
    memoryBarrier(cmd, kAll | kHostStage, VK_ACCESS_2_MEMORY_WRITE_BIT | VK_ACCESS_2_MEMORY_READ_BIT,
                  kCompute, kStorageRW);
    bind(cmd, m_pose, push);
    Descriptors()
        .buffer(kDeformBindVertices, m_vertices)
        .buffer(kDeformBindPieces, m_pieces)
        .buffer(kDeformBindDeltas, m_deltas)
        .buffer(kDeformBindPalette, m_palette)
        .buffer(kDeformBindWeights, m_weights)
        .buffer(kDeformBindPosed, posed)
        .push(m_ctx, cmd, m_pose);
    dispatch(cmd, m_vertexCount);
    memoryBarrier(cmd, kCompute, kStorageRW, kCompute, kStorageRW);
    bind(cmd, m_normals, push);
    Descriptors()
        .buffer(kDeformBindPosed, posed)
        .buffer(kDeformBindIndices, m_mesh.indices())
        .buffer(kDeformBindAdjacency, m_adjacency)
        .push(m_ctx, cmd, m_normals);
    dispatch(cmd, m_vertexCount);
    memoryBarrier(cmd, kCompute, kStorageRW, kCompute, kStorageRW);
    bind(cmd, m_frames, push);
    Descriptors()
        .buffer(kDeformBindPosed, posed)
        .buffer(kDeformBindRest, m_mesh.restVertices())
        .buffer(kDeformBindIndices, m_mesh.indices())
        .buffer(kDeformBindRotations, m_rotations)
        .push(m_ctx, cmd, m_frames);
    dispatch(cmd, m_triangleCount);
    memoryBarrier(cmd, kCompute, kStorageRW, kCompute, kStorageRW);
    timer.mark(cmd, "deform");

    if (!m_reserved)
        reserve(rest);
    m_reserved = false;
    m_last = Moved{true, m_time, rest.version, rest.impulses,
                   rest.impulses ? rest.impulses->handle() : VK_NULL_HANDLE, rest.capacity};
    if (rest.capacity > 0) {
        bind(cmd, m_move, push);
        Descriptors()
            .buffer(kDeformBindPosed, posed)
            .buffer(kDeformBindIndices, m_mesh.indices())
            .buffer(kDeformBindRotations, m_rotations)
            .buffer(kDeformBindImpulses, *rest.impulses)
            .buffer(kDeformBindMoved, m_moved)
            .buffer(kDeformBindCount, *rest.count)
            .push(m_ctx, cmd, m_move);
        dispatch(cmd, rest.capacity);
    }
    // The posed mesh and the moved impulses for every later command, and the host.
    memoryBarrier(cmd, kCompute, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT, kAll | kHostStage,
                  VK_ACCESS_2_MEMORY_READ_BIT | VK_ACCESS_2_HOST_READ_BIT);
    timer.mark(cmd, "move");
}

ImpulseSet GpuDeformer::sortedByCell(std::uint32_t count) {
    SPOT_CHECK(count <= m_movedSet.capacity);
    const auto* moved = static_cast<const gpu::SpotImpulse*>(m_moved.mapped());
    std::vector<std::uint32_t> order(count);
    for (std::uint32_t i = 0; i < count; ++i)
        order[i] = i;
    const auto less = [&](std::uint32_t a, std::uint32_t b) {
        const glm::ivec4 x = moved[a].cell, y = moved[b].cell;
        return x.x != y.x ? x.x < y.x : x.y != y.y ? x.y < y.y : x.z < y.z;
    };
    std::stable_sort(order.begin(), order.end(), less);
    const std::uint64_t need = std::max<std::uint64_t>(m_movedSet.capacity, 1) * sizeof(gpu::SpotImpulse);
    if (!m_sorted.handle() || m_sorted.size() < need) {
        m_sorted = Buffer();
        m_sorted = Buffer(m_ctx, need + need / 4, kStorage, kHost, "moved impulses by cell");
    }
    auto* sorted = static_cast<gpu::SpotImpulse*>(m_sorted.mapped());
    for (std::uint32_t i = 0; i < count; ++i)
        sorted[i] = moved[order[i]];
    ImpulseSet set = m_movedSet;
    set.impulses = &m_sorted;
    set.cells = &posedCells();
    return set;
}

void GpuDeformer::reserve(const ImpulseSet& rest) {
    const std::uint64_t need = std::max<std::uint64_t>(rest.capacity, 1) * sizeof(gpu::SpotImpulse);
    if (!m_moved.handle() || m_moved.size() < need) {
        m_moved = Buffer();
        m_moved = Buffer(m_ctx, need + need / 4, kStorage, kHost, "moved impulses");
        m_last.valid = false; // a new buffer: nothing is moved into it yet
    }
    const bool keep = current(rest);
    const std::uint64_t version = m_movedSet.version;
    m_movedSet = rest;
    m_movedSet.impulses = &m_moved;
    // Versions of their own (the generator's count up from 0), kept while nothing moved.
    m_movedSet.version = keep ? version : (std::uint64_t(1) << 63) | ++m_version;
    m_reserved = true;
}

} // namespace spot::splat
