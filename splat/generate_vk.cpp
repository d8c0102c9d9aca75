#include "generate_vk.h"

#include <cmath>
#include <cstring>
#include <vector>

#include "generate.comp.h"
#include "noise/error.h"
#include "noise/mesh.h"
#include "noise/shared_data.h"

namespace spot::splat {

namespace {

constexpr VkBufferUsageFlags kStorage = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT;

struct Push {
    std::uint32_t mode;
    std::uint32_t cellCount;
    std::uint32_t candidateCount;
};

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

/// Dispatch enough 64-wide groups for `n` invocations (2D when n is beyond one dimension).
void dispatch(VkCommandBuffer cmd, std::uint32_t n) {
    const std::uint32_t groups = (n + 63) / 64;
    const std::uint32_t x = std::min<std::uint32_t>(groups, 65535);
    const std::uint32_t y = (groups + x - 1) / x;
    vkCmdDispatch(cmd, x, y, 1);
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
    : m_ctx(ctx), m_generator(generator) {
    Bindings bindings; // TODO(binding names): the shader's bindings by position
    for (std::uint32_t i = 0; i < 12; ++i)
        bindings.push_back(storageBuffer(i));
    m_pipeline = makeComputePipeline(ctx, spv_generate_comp, bindings, sizeof(Push));
    m_params = upload(ctx, std::vector<gpu::SpotGenParams>{generator.sharedParams()}, "generator parameters");
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
}

bool GpuGenerator::prepare(const std::function<bool(const noise::SurfaceCell&)>& keep,
                           glm::vec4 lod) {
    std::vector<std::uint32_t> key;
    const auto& all = m_generator.cells().cells;
    for (std::uint32_t i = 0; i < all.size(); ++i)
        if (!keep || keep(all[i]))
            key.push_back(i);
    if (m_version > 0 && key == m_cellKey && lod == m_lod)
        return false;
    m_current = generate(keep, lod);
    m_cellKey = std::move(key);
    m_lod = lod;
    ++m_version;
    m_candidates = m_current.candidates;
    m_cellCount = m_current.cells;
    if (!m_count.handle())
        m_count = Buffer(m_ctx, 16, kStorage, Buffer::Memory::HostVisible, "impulse count");
    *static_cast<std::uint32_t*>(m_count.mapped()) = m_current.count;
    return true;
}

void GpuGenerator::record(VkCommandBuffer, PassTimer&) {}

ImpulseSet GpuGenerator::impulses() const {
    ImpulseSet s;
    s.impulses = &m_current.impulses;
    s.count = &m_count;
    s.capacity = m_current.count;
    s.version = m_version;
    s.cells = &m_generator.cells();
    return s;
}

std::uint32_t GpuGenerator::count() const { return m_current.count; }

GpuImpulses GpuGenerator::generate(const std::function<bool(const noise::SurfaceCell&)>& keep,
                                   glm::vec4 lod) {
    GpuImpulses result;
    static_cast<gpu::SpotGenParams*>(m_params.mapped())->lod = lod;
    std::vector<gpu::SpotCell> cells;
    for (const noise::SurfaceCell& c : m_generator.cells().cells)
        if (!keep || keep(c))
            cells.push_back(gpu::toGpu(c));
    result.cells = std::uint32_t(cells.size());
    result.impulses = Buffer(m_ctx, 16, kStorage, Buffer::Memory::HostVisible, "impulses");
    if (cells.empty())
        return result;
    Buffer cellBuffer = upload(m_ctx, cells, "visible cells");
    Buffer none(m_ctx, 16, kStorage, Buffer::Memory::HostVisible, "unused binding"); // a pass's unused bindings
    Timestamps time(m_ctx, 2);
    auto run = [&](std::uint32_t mode, std::uint32_t n, const Buffer& scratch, const Buffer& flags,
                   const Buffer& out) {
        m_ctx.submitAndWait([&](VkCommandBuffer cmd) {
            time.reset(cmd);
            vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, m_pipeline.handle());
            Descriptors()
                .buffer(0, m_params)
                .buffer(1, cellBuffer)
                .buffer(2, m_pieces)
                .buffer(3, m_triangles)
                .buffer(4, m_positions)
                .buffer(5, m_normals)
                .buffer(6, m_tangents)
                .buffer(7, m_uvs)
                .buffer(8, m_fieldData)
                .buffer(9, scratch)
                .buffer(10, flags)
                .buffer(11, out)
                .push(m_ctx, cmd, m_pipeline);
            const Push push{mode, result.cells, result.candidates};
            vkCmdPushConstants(cmd, m_pipeline.layout(), VK_SHADER_STAGE_COMPUTE_BIT, 0, sizeof(push), &push);
            time.write(cmd, 0, VK_PIPELINE_STAGE_2_TOP_OF_PIPE_BIT);
            dispatch(cmd, n);
            time.write(cmd, 1, VK_PIPELINE_STAGE_2_BOTTOM_OF_PIPE_BIT);
            memoryBarrier(cmd, VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, VK_ACCESS_2_SHADER_WRITE_BIT,
                          VK_PIPELINE_STAGE_2_HOST_BIT, VK_ACCESS_2_HOST_READ_BIT);
        });
        result.milliseconds += time.milliseconds()[1];
    };

    // 1. Candidates per cell, then their offsets (prefix sums here: a few thousand cells).
    run(0, result.cells, none, none, none);
    auto* gpuCells = static_cast<gpu::SpotCell*>(cellBuffer.mapped());
    std::uint64_t total = 0;
    for (std::uint32_t i = 0; i < result.cells; ++i) {
        gpuCells[i].info.z = std::uint32_t(total);
        total += gpuCells[i].info.w;
    }
    if (total > 0xffffffffull)
        throw InputError(cat(total, " impulse candidates are more than one GPU pass can index"));
    result.candidates = std::uint32_t(total);
    if (total == 0)
        return result;

    // 2. Every candidate decided; 3. accepted ones packed in (cell, candidate) order.
    Buffer scratch(m_ctx, total * sizeof(gpu::SpotImpulse), kStorage, Buffer::Memory::DeviceLocal,
                   "impulse candidates");
    Buffer flags(m_ctx, total * sizeof(std::uint32_t), kStorage, Buffer::Memory::HostVisible,
                 "candidate flags");
    run(1, result.candidates, scratch, flags, none);
    auto* flag = static_cast<std::uint32_t*>(flags.mapped());
    std::uint32_t accepted = 0;
    for (std::uint32_t i = 0; i < result.candidates; ++i)
        flag[i] = flag[i] ? ++accepted : 0u;
    result.count = accepted;
    result.impulses = Buffer(m_ctx, std::max<VkDeviceSize>(accepted, 1) * sizeof(gpu::SpotImpulse),
                             kStorage, Buffer::Memory::HostVisible, "impulses");
    if (accepted > 0)
        run(2, result.candidates, scratch, flags, result.impulses);
    return result;
}

} // namespace spot::splat
