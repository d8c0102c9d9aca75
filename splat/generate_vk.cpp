#include "generate_vk.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "generate_jittered.comp.h"
#include "generate_jittered_groom.comp.h"
#include "generate_jittered_groom_partial.comp.h"
#include "generate_jittered_partial.comp.h"
#include "generate_poisson.comp.h"
#include "generate_poisson_groom.comp.h"
#include "generate_poisson_groom_partial.comp.h"
#include "generate_poisson_partial.comp.h"
#include "generate_scan.comp.h"
#include "generate_scatter.comp.h"
#include "noise/error.h"
#include "noise/mesh.h"
#include "noise/shared_data.h"
#include "splat/pass_vk.h"

namespace spot::splat {

namespace gpu_gen {
using glm::uvec4;
using glm::vec4;
using uint = std::uint32_t;
#define SPOT_CONST inline constexpr
#include "shaders/spot_generate_layout.h"
#undef SPOT_CONST
static_assert(sizeof(SpotGenPush) == 32, "push constants");
} // namespace gpu_gen

namespace {

using namespace gpu_gen;
using namespace passes;

constexpr VkBufferUsageFlags kStorage = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT;
constexpr std::uint32_t kUncounted = std::numeric_limits<std::uint32_t>::max();

template <typename T>
Buffer upload(Context& ctx, const std::vector<T>& items, const std::string& what) {
    Buffer b(ctx, std::max<VkDeviceSize>(items.size() * sizeof(T), 16), kStorage,
             Buffer::Memory::HostVisible, what);
    if (!items.empty())
        b.upload(items.data(), items.size() * sizeof(T));
    return b;
}

template <typename V> std::vector<float> flatten(const std::vector<V>& v, int n) {
    std::vector<float> out;
    out.reserve(v.size() * std::size_t(n));
    for (const V& x : v)
        for (int i = 0; i < n; ++i)
            out.push_back(x[i]);
    return out;
}

/// Make `buffer` hold at least `count` items of `itemBytes`: kept when it does, else replaced by
/// one with a quarter more room (within the device's storage-buffer limit) so that frames a
/// little larger than this one allocate nothing either.
void reserve(Context& ctx, Buffer& buffer, std::uint64_t count, std::uint64_t itemBytes,
             VkBufferUsageFlags usage, Buffer::Memory memory, const char* what) {
    const std::uint64_t need = std::max<std::uint64_t>(count * itemBytes, 16);
    if (buffer.handle() && buffer.size() >= need)
        return;
    const std::uint64_t limit = ctx.properties().limits.maxStorageBufferRange;
    const std::uint64_t roomy =
        std::max(need, std::min(need + need / 4, limit / itemBytes * itemBytes));
    buffer = Buffer(); // free the old one first: the two need not fit together
    buffer = Buffer(ctx, roomy, usage, memory, what);
}

/// Dispatch enough kGenGroup-wide groups for `n` invocations (2D when n is beyond one dimension).
void dispatch(VkCommandBuffer cmd, std::uint32_t n) {
    const std::uint32_t groups = (n + kGenGroup - 1) / kGenGroup;
    const std::uint32_t x = std::min<std::uint32_t>(groups, 65535);
    const std::uint32_t y = (groups + x - 1) / x;
    vkCmdDispatch(cmd, x, y, 1);
}

shared::f32::GeneratorArrays arraysOf(const noise::Mesh& mesh, const noise::ImpulseGenerator& g) {
    shared::f32::GeneratorArrays a;
    a.triangles = mesh.triangles.data();
    a.positions = mesh.positions.data();
    a.normals = mesh.normals.data();
    a.tangents = mesh.tangents.empty() ? nullptr : mesh.tangents.data();
    a.uvs = mesh.uvs.empty() ? nullptr : mesh.uvs.data();
    a.pieces = g.sharedPieces().data();
    a.fieldData = g.sharedFieldData().data();
    a.params = &g.sharedParams();
    return a;
}

void pushConstants(VkCommandBuffer cmd, const Pipeline& pipeline, const SpotGenPush& push) {
    vkCmdPushConstants(cmd, pipeline.layout(), VK_SHADER_STAGE_COMPUTE_BIT, 0, sizeof(push), &push);
}

} // namespace

glm::vec4 lodParameters(const noise::Camera& camera, double pixels) {
    if (!(pixels > 0.0) || camera.projection != noise::Projection::Perspective)
        return glm::vec4(0.0f);
    const double focalPixels = 0.5 * camera.height / std::tan(0.5 * camera.fovYDeg * M_PI / 180.0);
    return glm::vec4(glm::vec3(camera.eye), float(focalPixels / pixels));
}

GpuGenerator::GpuGenerator(Context& ctx, const noise::Mesh& mesh,
                           const noise::ImpulseGenerator& generator)
    : m_ctx(ctx), m_mesh(mesh), m_generator(generator), m_shared(arraysOf(mesh, generator)),
      m_jittered(generator.sharedParams().flags.y == 1u),
      m_cellCandidates(generator.cells().cells.size()) {
    m_scanPipeline = makeComputePipeline(
        ctx, spirv(spv_generate_scan_comp),
        {storageBuffer(kGenBindFlags), storageBuffer(kGenBindCount)}, sizeof(SpotGenPush));
    m_scatterPipeline =
        makeComputePipeline(ctx, spirv(spv_generate_scatter_comp),
                            {storageBuffer(kGenBindScratch), storageBuffer(kGenBindFlags),
                             storageBuffer(kGenBindImpulses)},
                            sizeof(SpotGenPush));
    m_params = upload(ctx, std::vector<gpu::SpotGenParams>{generator.sharedParams()},
                      "generator parameters");
    m_pieces = upload(ctx, generator.sharedPieces(), "surface pieces");
    std::vector<std::uint32_t> tris;
    tris.reserve(mesh.triangles.size() * 3);
    for (const glm::uvec3& t : mesh.triangles)
        tris.insert(tris.end(), {t.x, t.y, t.z});
    m_triangles = upload(ctx, tris, "mesh triangles");
    m_positions = upload(ctx, flatten(mesh.positions, 3), "mesh positions");
    m_normals = upload(ctx, flatten(mesh.normals, 3), "mesh normals");
    m_tangents = upload(ctx, flatten(mesh.tangents, 3), "mesh tangents");
    m_uvs = upload(ctx, flatten(mesh.uvs, 2), "mesh uvs");
    m_fieldData = upload(ctx, generator.sharedFieldData(), "field data");
    m_count = Buffer(ctx, 16, kStorage, Buffer::Memory::HostVisible, "impulse count");
    *static_cast<std::uint32_t*>(m_count.mapped()) = 0;
}

std::vector<std::int32_t> GpuGenerator::specializationKey() const {
    const gpu::SpotGenParams& params = m_generator.sharedParams();
    std::vector<std::int32_t> key = {std::int32_t(params.flags.z != 0u)};
    for (std::uint32_t slot = 0; slot < SPOT_FIELD_COUNT; ++slot)
        key.insert(key.end(), {params.fields[slot].kind.x, params.fields[slot].kind.y});
    key.push_back(std::int32_t(params.clumpFlags.y)); // clumps, secondary, the mask overlay
    return key;
}

void GpuGenerator::refreshFields() {
    const std::vector<float>& data = m_generator.sharedFieldData();
    reserve(m_ctx, m_fieldData, data.size(), sizeof(float), kStorage, Buffer::Memory::HostVisible,
            "field data");
    if (!data.empty())
        m_fieldData.upload(data.data(), data.size() * sizeof(float));
    const gpu::SpotGenParams& params = m_generator.sharedParams();
    m_params.upload(&params, sizeof(params));
    // The host twin reads the generator's arrays, which may have moved.
    m_shared = shared::f32::SharedGenerator(arraysOf(m_mesh, m_generator));
    if (m_candidatePipeline.handle() && specializationKey() != m_candidateKey) {
        m_candidatePipeline = Pipeline();
        m_partialPipeline = Pipeline();
    }
    m_valid = false;
    m_dirtyPending = false;
}

void GpuGenerator::refreshFields(const std::vector<std::uint32_t>& cells) {
    const bool valid = m_valid;
    refreshFields();
    if (!valid || m_candidateKey.empty())
        return; // nothing generated yet to keep: a full generation
    const std::size_t modelCells = m_generator.cells().cells.size();
    // Cells changed by an earlier refresh and not generated since stay dirty.
    for (const std::uint32_t c : cells) {
        if (c >= modelCells)
            throw InputError(cat("cell ", c, " is not a cell of the model (it has ", modelCells, ")"));
        m_dirty.push_back(c);
    }
    std::sort(m_dirty.begin(), m_dirty.end());
    m_dirty.erase(std::unique(m_dirty.begin(), m_dirty.end()), m_dirty.end());
    m_valid = true;
    m_dirtyPending = true;
}

void GpuGenerator::choosePartial() {
    const auto& all = m_generator.cells().cells;
    std::vector<gpu::SpotCell> cells;
    std::vector<std::uint32_t> offsets;
    std::uint32_t offset = 0, local = 0;
    auto dirty = m_dirty.begin();
    for (const std::uint32_t c : m_cellKey) {
        const std::uint32_t n = examined(cellCandidates(c));
        while (dirty != m_dirty.end() && *dirty < c)
            ++dirty;
        if (n > 0 && dirty != m_dirty.end() && *dirty == c) {
            gpu::SpotCell cell = gpu::toGpu(all[c]);
            cell.info.z = local;
            cell.info.w = n;
            cells.push_back(cell);
            offsets.push_back(offset);
            local += n;
        }
        offset += n;
    }
    SPOT_CHECK_EQ(offset, m_examined);
    reserve(m_ctx, m_dirtyCells, cells.size(), sizeof(gpu::SpotCell), kStorage,
            Buffer::Memory::HostVisible, "changed cells");
    reserve(m_ctx, m_dirtyOffsets, offsets.size(), sizeof(std::uint32_t), kStorage,
            Buffer::Memory::HostVisible, "changed cells' offsets");
    if (!cells.empty()) {
        m_dirtyCells.upload(cells.data(), cells.size() * sizeof(gpu::SpotCell));
        m_dirtyOffsets.upload(offsets.data(), offsets.size() * sizeof(std::uint32_t));
    }
    m_dirtyCellCount = std::uint32_t(cells.size());
    m_dirtyExamined = local;
    if (local > 0)
        partialPipeline();
    m_dirty.clear();
    m_dirtyPending = false;
    m_partial = true;
    ++m_version;
}

const Pipeline& GpuGenerator::candidatePipeline() {
    if (m_candidatePipeline.handle())
        return m_candidatePipeline;
    m_candidateKey = specializationKey();
    for (auto it = m_prepared.begin(); it != m_prepared.end(); ++it)
        if (it->key == m_candidateKey) {
            // Made on their thread (waits for it when it is not done yet).
            m_candidatePipeline = it->pipeline.get();
            m_partialPipeline = it->partial.get();
            m_prepared.erase(it);
            return m_candidatePipeline;
        }
    m_candidatePipeline = makeCandidatePipeline(m_candidateKey);
    return m_candidatePipeline;
}

const Pipeline& GpuGenerator::partialPipeline() {
    const Pipeline& full = candidatePipeline(); // the key is the full one's
    static_cast<void>(full);
    if (!m_partialPipeline.handle())
        m_partialPipeline = makeCandidatePipeline(m_candidateKey, true);
    return m_partialPipeline;
}

void GpuGenerator::prepareFieldKind(std::uint32_t slot, std::int32_t kind,
                                    std::int32_t components) {
    if (slot >= SPOT_FIELD_COUNT)
        throw InputError(cat("field slot ", slot, " does not exist (", SPOT_FIELD_COUNT, ")"));
    std::vector<std::int32_t> key = specializationKey();
    key[1 + 2 * slot] = kind;
    key[2 + 2 * slot] = components;
    if (slot == SPOT_FIELD_COMB)
        key[0] = 1; // a comb field is bound
    if (slot == SPOT_FIELD_CLUMP) { // a clump layer turns clumps on (noise::clumpFieldSet)
        const gpu::SpotGenParams& params = m_generator.sharedParams();
        key.back() |= std::int32_t(shared::f32::SharedGenerator::kClumpOn) |
                      (params.clump2.x > 0.0f
                           ? std::int32_t(shared::f32::SharedGenerator::kClumpSecondary)
                           : 0);
    }
    if (m_candidatePipeline.handle() && key == m_candidateKey)
        return;
    for (const Prepared& p : m_prepared)
        if (p.key == key)
            return;
    // The mesh's flags now (no field changes them); the compile reads nothing else that changes.
    const gpu::SpotGenParams& params = m_generator.sharedParams();
    const bool uv = (params.flags.w & 1u) != 0u, tangents = (params.flags.w & 2u) != 0u;
    constexpr std::size_t kKept = 4; // the editor's slots: a few kinds armed in turn
    if (m_prepared.size() >= kKept) {
        // Their threads must end before their pipelines are dropped.
        m_prepared.front().pipeline.wait();
        m_prepared.front().partial.wait();
        m_prepared.pop_front();
    }
    // The first stroke's pipeline and its partial twin (the strokes after it), each on a thread.
    m_prepared.push_back(
        {key,
         std::async(std::launch::async,
                    [this, key, uv, tangents] { return makeCandidatePipeline(key, false, uv, tangents); }),
         std::async(std::launch::async,
                    [this, key, uv, tangents] { return makeCandidatePipeline(key, true, uv, tangents); })});
}

Pipeline GpuGenerator::makeCandidatePipeline(const std::vector<std::int32_t>& key, bool partial) {
    const gpu::SpotGenParams& params = m_generator.sharedParams();
    return makeCandidatePipeline(key, partial, (params.flags.w & 1u) != 0u,
                                 (params.flags.w & 2u) != 0u);
}

Pipeline GpuGenerator::makeCandidatePipeline(const std::vector<std::int32_t>& key, bool partial,
                                             bool uv, bool tangents) {
    Specialization spec;
    spec.set(kGenSpecComb, key[0] != 0)
        .set(kGenSpecUv, uv) // the mesh's: no field changes them
        .set(kGenSpecTangents, tangents);
    for (std::uint32_t slot = 0; slot < SPOT_FIELD_COUNT; ++slot)
        spec.set(kGenSpecFieldKind + slot, key[1 + 2 * slot])
            .set(kGenSpecFieldComponents + slot, key[2 + 2 * slot]);
    spec.set(kGenSpecClump, std::uint32_t(key[1 + 2 * SPOT_FIELD_COUNT]));
    Bindings bindings = {storageBuffer(kGenBindParams),    storageBuffer(kGenBindCells),
                         storageBuffer(kGenBindPieces),    storageBuffer(kGenBindTriangles),
                         storageBuffer(kGenBindPositions), storageBuffer(kGenBindNormals),
                         storageBuffer(kGenBindTangents),  storageBuffer(kGenBindUvs),
                         storageBuffer(kGenBindFieldData), storageBuffer(kGenBindScratch),
                         storageBuffer(kGenBindFlags)};
    if (m_jittered)
        bindings.push_back(storageBuffer(kGenBindSites));
    if (partial)
        bindings.push_back(storageBuffer(kGenBindDirty));
    // A module per sampling and per full or partial generation, each declaring what it reads,
    // and with the groom's part (clumps, masks, the mask overlay) only where the preset uses it.
    bool groom = key[1 + 2 * SPOT_FIELD_COUNT] != 0;
    for (std::uint32_t slot = 0; slot < SPOT_FIELD_COUNT; ++slot)
        groom |= (key[1 + 2 * slot] & (shared::f32::SharedGenerator::kFieldMaskedInside |
                                       shared::f32::SharedGenerator::kFieldMaskedOutside)) != 0;
    const std::span<const std::uint32_t> module =
        groom ? (m_jittered ? (partial ? spirv(spv_generate_jittered_groom_partial_comp)
                                       : spirv(spv_generate_jittered_groom_comp))
                            : (partial ? spirv(spv_generate_poisson_groom_partial_comp)
                                       : spirv(spv_generate_poisson_groom_comp)))
              : (m_jittered ? (partial ? spirv(spv_generate_jittered_partial_comp)
                                       : spirv(spv_generate_jittered_comp))
                            : (partial ? spirv(spv_generate_poisson_partial_comp)
                                       : spirv(spv_generate_poisson_comp)));
    return makeComputePipeline(m_ctx, module, bindings, sizeof(SpotGenPush), spec);
}

const GpuGenerator::CellCandidates& GpuGenerator::cellCandidates(std::uint32_t cell) {
    CellCandidates& n = m_cellCandidates[cell];
    if (n.candidates == kUncounted) {
        const gpu::SpotCell c = gpu::toGpu(m_generator.cells().cells[cell]);
        if (m_jittered)
            m_shared.jitteredSitesInside(c, n.inside);
        n.candidates = m_shared.spotCellCandidates(c);
    }
    return n;
}

bool GpuGenerator::choose(const std::function<bool(const noise::SurfaceCell&)>& keep, glm::vec4 lod,
                          bool force) {
    const auto& all = m_generator.cells().cells;
    std::vector<std::uint32_t> key;
    key.reserve(m_cellKey.size());
    for (std::uint32_t i = 0; i < all.size(); ++i)
        if (!keep || keep(all[i]))
            key.push_back(i);
    if (!force && m_valid && key == m_cellKey && lod == m_lod) {
        if (!m_dirtyPending)
            return false;
        choosePartial();
        return true;
    }

    // Each cell's candidates, counted on the host with the shared code (as the CPU generator
    // does), those the GPU examines and their offsets.
    m_valid = false;
    m_partial = false;
    m_dirtyPending = false;
    m_dirty.clear();
    std::uint64_t total = 0, examinedTotal = 0;
    std::uint32_t withCandidates = 0;
    for (const std::uint32_t c : key) {
        const CellCandidates& n = cellCandidates(c);
        total += n.candidates;
        examinedTotal += examined(n);
        withCandidates += examined(n) > 0 ? 1u : 0u;
    }
    if (examinedTotal > kGenMaxCandidates)
        throw InputError(cat(examinedTotal, " impulse candidates in view, more than ",
                             kGenMaxCandidates, " (one generation); lower density_max"));
    const auto examinedCount = std::uint32_t(examinedTotal);
    reserve(m_ctx, m_cells, withCandidates, sizeof(gpu::SpotCell), kStorage,
            Buffer::Memory::HostVisible, "visible cells");
    if (m_jittered)
        reserve(m_ctx, m_sites, examinedCount, sizeof(std::uint32_t), kStorage,
                Buffer::Memory::HostVisible, "lattice sites");
    reserve(m_ctx, m_scratch, examinedCount, sizeof(gpu::SpotImpulse), kStorage,
            Buffer::Memory::DeviceLocal, "impulse candidates");
    reserve(m_ctx, m_flags, examinedCount, sizeof(std::uint32_t), kStorage,
            Buffer::Memory::DeviceLocal, "candidate flags");
    // Host-visible: a renderer may read the impulses on the host after their frame (and on
    // lavapipe all memory is host memory anyway); a transfer source for readback copies.
    reserve(m_ctx, m_impulses, examinedCount, sizeof(gpu::SpotImpulse),
            kStorage | VK_BUFFER_USAGE_TRANSFER_SRC_BIT, Buffer::Memory::HostVisible, "impulses");
    auto* cells = static_cast<gpu::SpotCell*>(m_cells.mapped());
    auto* sites = static_cast<std::uint32_t*>(m_sites.mapped());
    std::uint32_t offset = 0, uploaded = 0;
    for (const std::uint32_t c : key) {
        const CellCandidates& n = cellCandidates(c);
        if (examined(n) == 0)
            continue; // generates nothing: the GPU's cell search need not see it
        gpu::SpotCell cell = gpu::toGpu(all[c]);
        cell.info.z = offset;
        cell.info.w = examined(n);
        cells[uploaded++] = cell;
        if (m_jittered)
            std::copy(n.inside.begin(), n.inside.end(), sites + offset);
        offset += examined(n);
    }
    m_cellKey = std::move(key);
    m_lod = lod;
    m_candidates = std::uint32_t(total);
    m_examined = examinedCount;
    m_cellCount = std::uint32_t(m_cellKey.size());
    m_uploadedCells = uploaded;
    if (examinedCount > 0)
        candidatePipeline(); // made here, on the host, not while recording
    ++m_version;
    m_valid = true;
    return true;
}

bool GpuGenerator::prepare(const std::function<bool(const noise::SurfaceCell&)>& keep,
                           glm::vec4 lod) {
    return choose(keep, lod, false);
}

void GpuGenerator::record(VkCommandBuffer cmd, PassTimer& timer) {
    SPOT_CHECK(m_valid);
    const SpotGenPush push{glm::uvec4(m_uploadedCells, m_examined, 0u, 0u), m_lod};
    // A partial generation decides only the changed cells' candidates; the others' impulses and
    // flags (0, or their index: non-zero) stand in scratch and flags.
    const SpotGenPush candidatePush =
        m_partial ? SpotGenPush{glm::uvec4(m_dirtyCellCount, m_dirtyExamined, 1u, 0u), m_lod} : push;
    // 1. Every candidate decided.
    if (candidatePush.counts.y > 0) {
        const Pipeline& candidates = m_partial ? m_partialPipeline : m_candidatePipeline;
        vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, candidates.handle());
        Descriptors d;
        if (m_jittered)
            d.buffer(kGenBindSites, m_sites);
        if (m_partial)
            d.buffer(kGenBindDirty, m_dirtyOffsets);
        d.buffer(kGenBindParams, m_params)
            .buffer(kGenBindCells, m_partial ? m_dirtyCells : m_cells)
            .buffer(kGenBindPieces, m_pieces)
            .buffer(kGenBindTriangles, m_triangles)
            .buffer(kGenBindPositions, m_positions)
            .buffer(kGenBindNormals, m_normals)
            .buffer(kGenBindTangents, m_tangents)
            .buffer(kGenBindUvs, m_uvs)
            .buffer(kGenBindFieldData, m_fieldData)
            .buffer(kGenBindScratch, m_scratch)
            .buffer(kGenBindFlags, m_flags)
            .push(m_ctx, cmd, candidates);
        pushConstants(cmd, candidates, candidatePush);
        dispatch(cmd, candidatePush.counts.y);
        memoryBarrier(cmd, kCompute, kStorageRW, kCompute, kStorageRW);
    }
    // 2. The flags become output indices, and the count is written (0 without candidates).
    vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, m_scanPipeline.handle());
    Descriptors()
        .buffer(kGenBindFlags, m_flags)
        .buffer(kGenBindCount, m_count)
        .push(m_ctx, cmd, m_scanPipeline);
    pushConstants(cmd, m_scanPipeline, push);
    vkCmdDispatch(cmd, 1, 1, 1);
    // 3. Accepted impulses packed in (cell, candidate) order.
    if (m_examined > 0) {
        memoryBarrier(cmd, kCompute, kStorageRW, kCompute, kStorageRW);
        vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, m_scatterPipeline.handle());
        Descriptors()
            .buffer(kGenBindScratch, m_scratch)
            .buffer(kGenBindFlags, m_flags)
            .buffer(kGenBindImpulses, m_impulses)
            .push(m_ctx, cmd, m_scatterPipeline);
        pushConstants(cmd, m_scatterPipeline, push);
        dispatch(cmd, m_examined);
    }
    // The impulses and their count for every later command, and the count for the host.
    memoryBarrier(cmd, kCompute, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT, kAll | kHostStage,
                  VK_ACCESS_2_MEMORY_READ_BIT | VK_ACCESS_2_HOST_READ_BIT);
    timer.mark(cmd, "generate");
}

ImpulseSet GpuGenerator::impulses() const {
    ImpulseSet s;
    s.impulses = &m_impulses;
    s.count = &m_count;
    s.capacity = m_examined;
    s.version = m_version;
    s.cells = &m_generator.cells();
    return s;
}

std::uint32_t GpuGenerator::count() const {
    return *static_cast<const std::uint32_t*>(m_count.mapped());
}

GpuImpulses GpuGenerator::generate(const std::function<bool(const noise::SurfaceCell&)>& keep,
                                   glm::vec4 lod) {
    choose(keep, lod, true);
    PassTimer timer(m_ctx, 1);
    m_ctx.submitAndWait([&](VkCommandBuffer cmd) {
        timer.begin(cmd);
        record(cmd, timer);
    });
    GpuImpulses result;
    result.count = count();
    result.candidates = m_candidates;
    result.cells = m_cellCount;
    result.milliseconds = timer.totalMilliseconds();
    const VkDeviceSize bytes = VkDeviceSize(result.count) * sizeof(gpu::SpotImpulse);
    result.impulses = Buffer(m_ctx, bytes, kStorage, Buffer::Memory::HostVisible, "impulses");
    if (result.count > 0)
        result.impulses.upload(m_impulses.mapped(), bytes);
    return result;
}

} // namespace spot::splat
