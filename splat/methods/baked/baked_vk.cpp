#include "baked_vk.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <optional>
#include <span>
#include <system_error>
#include <unordered_map>
#include <vector>

#include <glm/gtc/packing.hpp>

#include "noise/bake.h"
#include "noise/error.h"
#include "noise/kernel.h"
#include "noise/preset.h"
#include "noise/reference.h"
#include "noise/shell.h"
#include "shaders/spot_light.hpp"

#include "baked_march.comp.h"
#include "baked_march_2.comp.h"
#include "baked_march_3.comp.h"
#include "baked_march_4.comp.h"
#include "baked_march_lit.comp.h"
#include "baked_march_lit_2.comp.h"
#include "baked_march_lit_3.comp.h"
#include "baked_march_lit_4.comp.h"
#include "baked_peel.frag.h"
#include "baked_shell.comp.h"
#include "baked_tet.vert.h"

namespace spot::splat {

namespace {

using namespace gpu_baked;

constexpr VkBufferUsageFlags kStorage = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT;
constexpr Buffer::Memory kHost = Buffer::Memory::HostVisible;
constexpr Buffer::Memory kDevice = Buffer::Memory::DeviceLocal;
/// Layers whose peel and march passes are timed apart (2 marks each, within PassTimer's 32).
constexpr std::uint32_t kBakedMarkedLayers = 12;

/// Every memory barrier the passes need: each pass reads what the previous ones wrote (images,
/// buffers, attachments); lavapipe runs them in order anyway, the barrier keeps it valid Vulkan.
void fullBarrier(VkCommandBuffer cmd) {
    memoryBarrier(cmd, passes::kAll, VK_ACCESS_2_MEMORY_READ_BIT | VK_ACCESS_2_MEMORY_WRITE_BIT,
                  passes::kAll, VK_ACCESS_2_MEMORY_READ_BIT | VK_ACCESS_2_MEMORY_WRITE_BIT);
}

} // namespace

BakedRenderer::BakedRenderer(const SceneGpu& scene) : m_scene(scene), m_ctx(scene.context()) {
    requireFormat(m_ctx, kColorFormat,
                  VK_FORMAT_FEATURE_COLOR_ATTACHMENT_BIT | VK_FORMAT_FEATURE_STORAGE_IMAGE_BIT,
                  "stored RGBA32F targets");
    requireFormat(m_ctx, kScalarFormat,
                  VK_FORMAT_FEATURE_COLOR_ATTACHMENT_BIT | VK_FORMAT_FEATURE_STORAGE_IMAGE_BIT,
                  "stored R32F targets");
    requireFormat(m_ctx, kDepthFormat, VK_FORMAT_FEATURE_DEPTH_STENCIL_ATTACHMENT_BIT, "depth");
    const std::uint32_t push = sizeof(gpu_splat::SpotSplatFrame);
    m_shell =
        makeComputePipeline(m_ctx, spirv(spv_baked_shell_comp),
                            {storageBuffer(kBakedBindParams), storageBuffer(kBakedBindVertices),
                             storageBuffer(kBakedBindRest), storageBuffer(kBakedBindIndices),
                             storageBuffer(kBakedBindTets), storageBuffer(kBakedBindEyeTet),
                             storageBuffer(kBakedBindEntryMasks), storageBuffer(kBakedBindPeelDraw),
                             storageBuffer(kBakedBindList)},
                            push);
    for (const bool first : {false, true}) {
        GraphicsPipelineDesc desc;
        desc.vertex = spirv(spv_baked_tet_vert);
        desc.fragment = spirv(spv_baked_peel_frag);
        desc.bindings = {storageBuffer(kBakedBindTets),     storageBuffer(kBakedBindPeelDraw),
                         storageImage(kBakedBindPrevDepth), storageBuffer(kBakedBindLayerEntry),
                         storageBuffer(kBakedBindList),     storageBuffer(kBakedBindListPixels)};
        desc.pushBytes = push;
        // No colour target: the nearest entry is an atomicMax per pixel (baked_peel.frag). The
        // depth attachment is the mesh's, tested (nearer than the mesh) and never written.
        desc.depthFormat = kDepthFormat;
        desc.depthTest = true;
        desc.depthWrite = false;
        desc.depthCompare = VK_COMPARE_OP_GREATER;
        desc.spec.set(kBakedSpecFirstLayer, first);
        if (first) {
            // Drawn in the mesh's own rendering, after the mesh (MeshPass::record): its colour
            // targets, left unwritten.
            VkPipelineColorBlendAttachmentState none{};
            desc.colorFormats = {kColorFormat, kScalarFormat};
            desc.blends = {none, none};
        }
        m_peel[first] = makeGraphicsPipeline(m_ctx, desc);
    }
    m_params = Buffer(m_ctx, sizeof(SpotBakedParams), kStorage, kHost, "baked parameters");
    m_loops =
        Buffer(m_ctx, 16, kStorage | VK_BUFFER_USAGE_TRANSFER_DST_BIT, kHost, "baked loop counter");
    m_eyeTet = Buffer(m_ctx, 16, kStorage | VK_BUFFER_USAGE_TRANSFER_DST_BIT, kHost,
                      "baked eye tetrahedron");
    const VkDeviceSize align =
        std::max<VkDeviceSize>(m_ctx.properties().limits.minStorageBufferOffsetAlignment, 1);
    m_listStride = (sizeof(SpotBakedList) + align - 1) / align * align;
    m_lists =
        Buffer(m_ctx, m_listStride * kBakedMaxPeelPasses,
               kStorage | VK_BUFFER_USAGE_INDIRECT_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT,
               kDevice, "baked list headers");
    m_emptyLists.assign(m_listStride * kBakedMaxPeelPasses, std::byte{0});
    const SpotBakedList emptyList{glm::uvec3(0u, 1u, 1u), 0u};
    for (std::uint32_t k = 0; k < kBakedMaxPeelPasses; ++k)
        std::memcpy(m_emptyLists.data() + k * m_listStride, &emptyList, sizeof(emptyList));
}

BakedRenderer::~BakedRenderer() = default;

const Pipeline& BakedRenderer::marchPipeline(bool count, bool first, bool lit,
                                             std::uint32_t buffers) {
    SPOT_CHECK(buffers >= 1 && buffers <= kBakedBrickBuffers);
    if (const auto it = m_march.find({count, first, lit, buffers}); it != m_march.end())
        return it->second;
    Specialization spec;
    spec.set(kBakedSpecCount, count);
    spec.set(kBakedSpecFirstLayer, first);
    // One module per count of brick buffers, each declaring those it reads, and its lit variant
    // (BAKED_LIT), which also declares the mesh's and the solid's bindings.
    const std::span<const std::uint32_t> modules[] = {
        spirv(spv_baked_march_comp), spirv(spv_baked_march_2_comp), spirv(spv_baked_march_3_comp),
        spirv(spv_baked_march_4_comp)};
    const std::span<const std::uint32_t> litModules[] = {
        spirv(spv_baked_march_lit_comp), spirv(spv_baked_march_lit_2_comp),
        spirv(spv_baked_march_lit_3_comp), spirv(spv_baked_march_lit_4_comp)};
    static_assert(std::size(modules) == kBakedBrickBuffers);
    static_assert(std::size(litModules) == kBakedBrickBuffers);
    Bindings bindings = {storageBuffer(kBakedBindParams),      storageBuffer(kBakedBindTets),
                         storageBuffer(kBakedBindNeighbours),  storageBuffer(kBakedBindEyeTet),
                         storageBuffer(kBakedBindTable),       storageBuffer(kBakedBindLayerEntry),
                         storageImage(kBakedBindMeshDistance), storageImage(kBakedBindAccum),
                         storageImage(kBakedBindBase),         storageImage(kBakedBindBaseKept),
                         storageImage(kBakedBindExitDepth),    storageBuffer(kBakedBindLoops),
                         storageBuffer(kBakedBindList),        storageBuffer(kBakedBindListPixels)};
    if (lit)
        for (const std::uint32_t b : {kBakedBindVertices, kBakedBindIndices, kBakedBindSolid})
            bindings.push_back(storageBuffer(b));
    const std::uint32_t shadingBindings[] = {kBakedBindShading, kBakedBindShading1,
                                             kBakedBindShading2, kBakedBindShading3};
    for (std::uint32_t i = 0; lit && i < buffers; ++i)
        bindings.push_back(storageBuffer(shadingBindings[i]));
    const std::uint32_t brickBindings[] = {kBakedBindBricks, kBakedBindBricks1, kBakedBindBricks2,
                                           kBakedBindBricks3};
    for (std::uint32_t i = 0; i < buffers; ++i)
        bindings.push_back(storageBuffer(brickBindings[i]));
    Pipeline p = makeComputePipeline(m_ctx, (lit ? litModules : modules)[buffers - 1], bindings,
                                     sizeof(gpu_splat::SpotSplatFrame), spec);
    return m_march.emplace(std::tuple{count, first, lit, buffers}, std::move(p)).first->second;
}

void BakedRenderer::checkBakeFits(const BakeData& bake, bool lit, std::uint64_t perBuffer) const {
    const std::uint64_t range = m_ctx.properties().limits.maxStorageBufferRange;
    for (std::size_t s = 0; s < bake.tableEnd.size(); ++s)
        if (bake.tableEnd[s] * sizeof(std::int32_t) > range) {
            const glm::i64vec3 d = bake.sectionBox[s];
            throw InputError(cat("baked: ", bake.file, "'s leaves span a box of ", d.x, "x", d.y,
                                 "x", d.z, " leaves (level ", s,
                                 "), more than one storage "
                                 "buffer of this device takes as a leaf table (",
                                 range >> 20, " MiB)"));
        }
    const std::uint64_t brickBytesEach = std::uint64_t(kBakedBrickVoxels) * sizeof(glm::uvec2);
    // Lit: as many bytes again of shading bricks, in buffers of their own split alike.
    const std::uint64_t brickBytes =
        (lit ? 2 : 1) * std::max<std::uint64_t>(bake.brickCount, 1) * brickBytesEach;
    const std::uint64_t tableBytes = bake.table.size() * sizeof(std::int32_t);
    const std::uint64_t bufferCount =
        std::max<std::uint64_t>((bake.brickCount + perBuffer - 1) / perBuffer, 1);
    if (bufferCount > kBakedBrickBuffers || tableBytes > range)
        throw InputError(cat("baked: ", bake.file, " holds ", bake.brickCount, " leaves (",
                             brickBytes >> 20, " MiB of bricks), more than ", kBakedBrickBuffers,
                             " storage buffers of this device take (", range >> 20,
                             " MiB each); bake it at a larger voxel size"));
    std::uint64_t held = m_table.reservedBytes() + m_solid.reservedBytes();
    for (const Buffer& b : m_bricks)
        held += b.reservedBytes();
    for (const Buffer& b : m_shadingBricks)
        held += b.reservedBytes();
    if (m_ctx.allocatedBytes() - held + brickBytes + tableBytes > m_ctx.memoryBudget())
        throw InputError(cat("baked: ", bake.file, " needs ", (brickBytes + tableBytes) >> 20,
                             " MiB of GPU memory; ", (m_ctx.allocatedBytes() - held) >> 20,
                             " MiB are in use and the budget is ", m_ctx.memoryBudget() >> 20,
                             " MiB; bake it at a larger voxel size"));
}

void BakedRenderer::uploadBake(const BakeData& bake, bool lit) {
    const std::uint64_t range = m_ctx.properties().limits.maxStorageBufferRange;
    const std::uint64_t brickBytesEach = std::uint64_t(kBakedBrickVoxels) * sizeof(glm::uvec2);
    // The density bricks over up to kBakedBrickBuffers buffers of one storage buffer's range.
    const std::uint64_t fits = range / brickBytesEach;
    const std::uint64_t perBuffer =
        m_brickSplit > 0 ? std::min<std::uint64_t>(m_brickSplit, fits) : fits;
    checkBakeFits(bake, lit, perBuffer);
    const std::uint64_t brickCount = bake.brickCount;
    const std::uint64_t bufferCount =
        std::max<std::uint64_t>((brickCount + perBuffer - 1) / perBuffer, 1);
    const std::uint64_t brickBytes =
        (lit ? 2 : 1) * std::max<std::uint64_t>(brickCount, 1) * brickBytesEach;
    const std::uint64_t tableBytes = bake.table.size() * sizeof(std::int32_t);
    m_table = Buffer();
    m_solid = Buffer();
    for (Buffer& b : m_bricks)
        b = Buffer();
    for (Buffer& b : m_shadingBricks)
        b = Buffer();
    m_table = Buffer(m_ctx, tableBytes, kStorage, kHost, "baked leaf tables");
    m_table.upload(std::span<const std::int32_t>(bake.table));
    for (std::uint64_t i = 0; i < bufferCount; ++i) {
        const std::uint64_t n = std::min<std::uint64_t>(
            perBuffer, std::max<std::uint64_t>(brickCount, 1) - i * perBuffer);
        m_bricks[i] = Buffer(m_ctx, n * brickBytesEach, kStorage, kHost,
                             cat("baked bricks (", n, ", buffer ", i, ")"));
        // Lit: density brick b's shading brick at the same place in the shading buffers.
        if (lit)
            m_shadingBricks[i] = Buffer(m_ctx, n * brickBytesEach, kStorage, kHost,
                                        cat("baked shading bricks (", n, ", buffer ", i, ")"));
    }
    // Level l's bricks are [firstBrick[l], + its leaves), uploaded in pieces at buffer bounds.
    for (const bool shading : {false, true}) {
        if (shading && !lit)
            break;
        auto& buffers = shading ? m_shadingBricks : m_bricks;
        for (std::size_t level = 0; level < std::size_t(bake.levels); ++level) {
            const auto& data = shading ? bake.shadingPacked[level] : bake.packed[level];
            const std::uint64_t count = data.size() / kBakedBrickVoxels;
            for (std::uint64_t done = 0; done < count;) {
                const std::uint64_t b = bake.firstBrick[level] + done;
                const std::uint64_t buffer = b / perBuffer, local = b % perBuffer;
                const std::uint64_t n = std::min(count - done, perBuffer - local);
                buffers[buffer].upload(data.data() + done * kBakedBrickVoxels, n * brickBytesEach,
                                       local * brickBytesEach);
                done += n;
            }
        }
    }
    if (lit) {
        // The mesh's inside at level 1 (level 0 in a bake of one level), over the box of its
        // leaves: the shadow marches stop there (the bake holds only the fur).
        const int level = std::min(1, bake.levels - 1);
        m_solidLevel = std::uint32_t(level);
        const glm::ivec3 lo = glm::ivec3(bake.leafOrigin[std::size_t(level)]) * 8;
        const glm::ivec3 n = glm::ivec3(bake.leafDims[std::size_t(level)]) * 8;
        const MeshPass& mesh = m_scene.meshPass();
        const auto* vertices =
            static_cast<const gpu_splat::SpotMeshVertex*>(mesh.restVertices().mapped());
        const auto* indices = static_cast<const std::uint32_t*>(mesh.indices().mapped());
        std::vector<glm::vec3> positions(mesh.restVertices().size() /
                                         sizeof(gpu_splat::SpotMeshVertex));
        for (std::size_t i = 0; i < positions.size(); ++i)
            positions[i] = glm::vec3(vertices[i].position);
        std::vector<glm::uvec3> triangles(mesh.indexCount() / 3);
        for (std::size_t t = 0; t < triangles.size(); ++t)
            triangles[t] = glm::uvec3(indices[3 * t], indices[3 * t + 1], indices[3 * t + 2]);
        const std::vector<std::uint32_t> bits =
            solidVoxels(positions, triangles, lo, n, bake.voxelSize * float(1 << level));
        m_solid = Buffer(m_ctx, bits.size() * sizeof(std::uint32_t), kStorage, kHost,
                         "baked solid (the mesh's inside)");
        m_solid.upload(std::span<const std::uint32_t>(bits));
    }
    m_bricksPerBuffer = std::uint32_t(perBuffer);
    m_leafOrigin = bake.leafOrigin;
    m_leafDims = bake.leafDims;
    m_bakeStats = BakedStats{};
    m_brickUnit = bake.unit;
    m_bakeStats.voxelSize = bake.voxelSize;
    m_bakeStats.levels = std::uint32_t(bake.levels);
    m_bakeStats.bricks = std::uint32_t(bake.brickCount);
    m_bakeStats.brickBuffers = std::uint32_t(bufferCount);
    m_bakeStats.distanceBricks = bake.distanceBricks;
    m_bakeStats.tableEntries = std::uint32_t(bake.table.size());
    m_bakeStats.gpuBytes = brickBytes + tableBytes + (lit ? m_solid.size() : 0);
}

void BakedRenderer::ensureTargets(std::uint32_t width, std::uint32_t height) {
    if (m_width == width && m_height == height && m_baseKept.handle())
        return;
    // The march's indirect dispatch covers every pixel when the eye is inside the shell, in rows
    // of workgroups (SpotBakedList); a device takes at least 65,535 in each dimension.
    // The shaders count pixels in 32 bits, so the product is checked before it is formed.
    const VkPhysicalDeviceLimits& limits = m_ctx.properties().limits;
    const bool fits = std::uint64_t(width) * height <= std::numeric_limits<std::uint32_t>::max();
    const glm::uvec2 groups =
        fits ? gpu_baked::spotBakedMarchGroups(width * height) : glm::uvec2(0);
    if (!fits || groups.x > limits.maxComputeWorkGroupCount[0] ||
        groups.y > limits.maxComputeWorkGroupCount[1])
        throw InputError(cat("baked: a ", width, "x", height,
                             " frame needs more workgroups in one ",
                             "dispatch than the device takes; reduce the image size"));
    // Per pixel: base 16, distance 4, depth 4, exit depth 4, layer entry 8, accum 16, the kept
    // base 16, the march's list 4.
    const std::uint64_t need = std::uint64_t(width) * height * 72;
    std::uint64_t held = 0;
    for (const Image* i : {&m_base, &m_distance, &m_meshDepth, &m_exitDepth, &m_accum, &m_baseKept})
        held += i->reservedBytes();
    held += m_listPixels.reservedBytes() + m_layerEntry.reservedBytes();
    if (m_ctx.allocatedBytes() - held + need > m_ctx.memoryBudget())
        throw InputError(cat("baked: a ", width, "x", height, " frame needs ", need >> 20,
                             " MiB of GPU memory for its targets; ",
                             (m_ctx.allocatedBytes() - held) >> 20,
                             " MiB are in use and the budget is ", m_ctx.memoryBudget() >> 20,
                             " MiB; reduce the image size"));
    for (Image* i : {&m_base, &m_distance, &m_meshDepth, &m_exitDepth, &m_accum, &m_baseKept})
        *i = Image();
    m_listPixels = Buffer();
    m_layerEntry = Buffer();
    m_width = m_height = 0;
    constexpr VkImageUsageFlags kAttach = VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT;
    constexpr VkImageUsageFlags kStore = VK_IMAGE_USAGE_STORAGE_BIT;
    constexpr VkImageUsageFlags kSrc = VK_IMAGE_USAGE_TRANSFER_SRC_BIT;
    constexpr VkImageUsageFlags kDepthUse = VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT;
    constexpr VkImageAspectFlags kColor = VK_IMAGE_ASPECT_COLOR_BIT;
    constexpr VkImageAspectFlags kDepth = VK_IMAGE_ASPECT_DEPTH_BIT;
    m_base = Image(m_ctx, width, height, kColorFormat, kAttach | kStore | kSrc, kColor,
                   "baked base colour and result");
    m_distance =
        Image(m_ctx, width, height, kScalarFormat, kAttach | kStore, kColor, "baked mesh distance");
    m_meshDepth = Image(m_ctx, width, height, kDepthFormat, kDepthUse, kDepth, "baked mesh depth");
    // x: the depth the next peel's entries lie behind, y: the ray parameter sampled to.
    m_exitDepth =
        Image(m_ctx, width, height, kColorFormat, kStore, kColor, "baked peel depth and coverage");
    m_layerEntry =
        Buffer(m_ctx, std::uint64_t(width) * height * 8,
               kStorage | VK_BUFFER_USAGE_TRANSFER_DST_BIT, kDevice, "baked layer entries");
    m_accum = Image(m_ctx, width, height, kColorFormat, kStore, kColor, "baked accumulation");
    m_baseKept =
        Image(m_ctx, width, height, kColorFormat, kStore, kColor, "baked kept base colour");
    m_listPixels =
        Buffer(m_ctx, std::uint64_t(width) * height * 4, kStorage, kDevice, "baked pixel list");
    m_width = width;
    m_height = height;
}

void requireBakedView(const View& view) {
    if (view.camera.projection == noise::Projection::Orthographic)
        throw InputError("baked: orthographic cameras are not supported yet");
    if (view.shading.mode == noise::Shading::Mode::Lambert)
        throw InputError("baked: Lambert shading needs normals the bake does not store; use "
                         "unlit shading");
}

void BakedRenderer::useBake(const RenderSettings& settings, float cellSize, bool lit) {
    // The bake's voxels are the noise in the rest pose of the shell it was baked on (the mesh and
    // the cell size, the shell's thickness): on another shell they land in the wrong places.
    const std::uint64_t shell = noise::shellHash(m_scene.meshHash(), cellSize);
    const std::optional<std::uint64_t> recorded = settings.bake->meshHash;
    const auto hex = [](std::uint64_t v) {
        char text[17];
        std::snprintf(text, sizeof text, "%016llx", static_cast<unsigned long long>(v));
        return std::string(text);
    };
    if (recorded && *recorded != shell && !settings.allowMismatch)
        throw InputError(cat("baked: ", settings.bake->file, " was baked for mesh hash ",
                             hex(*recorded), ", this scene's is ", hex(shell),
                             " (another mesh or cell size): bake this scene, or pass "
                             "--allow-mismatch to render it anyway"));
    if (lit && !settings.bake->shaded)
        throw InputError(cat("baked: ", settings.bake->file,
                             " has no shading grids (tangent, normal: a bake written before them);"
                             " bake it again to render lit scenes"));
    if (settings.bake != m_bake ||
        (lit && !m_bakeLit)) { // a new bake: uploaded once, kept while it is handed again
        if (!recorded)
            std::fprintf(stderr,
                         "warning: %s records no mesh hash (an older bake): not checked "
                         "against the scene\n",
                         settings.bake->file.c_str());
        m_bake.reset();
        uploadBake(*settings.bake, lit);
        m_bake = settings.bake;
        m_bakeLit = lit;
    }
}

void BakedRenderer::ensureShell(std::uint32_t triangles) {
    // The tetrahedra (rebuilt per frame on the GPU), and per mesh their neighbours and the
    // boundary faces a ray can enter through (topology only, from the triangles).
    const std::uint64_t tetBytes = std::max<std::uint64_t>(triangles, 1) * 3 * sizeof(SpotBakedTet);
    if (m_tets.size() < tetBytes) {
        const std::uint64_t range = m_ctx.properties().limits.maxStorageBufferRange;
        if (tetBytes > range)
            throw InputError(cat("baked: the shell of ", triangles, " triangles needs ",
                                 tetBytes >> 20, " MiB in one storage buffer, more than ",
                                 range >> 20, " MiB"));
        m_tets = Buffer();
        m_tets = Buffer(m_ctx, tetBytes, kStorage, kDevice, "baked tetrahedra");
    }
    if (m_bakeStats.tetrahedra != 3 * triangles || !m_neighbours.handle()) {
        const auto* indices =
            static_cast<const std::uint32_t*>(m_scene.meshPass().indices().mapped());
        const std::uint32_t vertexCount =
            std::uint32_t(m_scene.meshPass().vertices().size() / sizeof(gpu_splat::SpotMeshVertex));
        std::vector<glm::uvec3> tris(triangles);
        for (std::uint32_t t = 0; t < triangles; ++t)
            tris[t] = glm::uvec3(indices[3 * t], indices[3 * t + 1], indices[3 * t + 2]);
        const std::vector<noise::ShellTetrahedron> tets = noise::shellTetrahedra(tris, vertexCount);
        // The neighbours as the walk reads them (the one packing, noise::shellWalkNeighbours).
        std::vector<glm::ivec4> packed = noise::shellWalkNeighbours(tets);
        std::vector<std::uint32_t> entries;
        for (std::size_t t = 0; t < tets.size(); ++t)
            for (std::uint32_t f = 0; f < 4; ++f) {
                // Boundary faces but the base (all three corners on the mesh): the top surface
                // and the sides of open edges.
                bool base = true;
                for (std::uint32_t i = 1; i < 4; ++i)
                    base = base && tets[t].vertices[(f + i) % 4] < vertexCount;
                if (packed[t][int(f)] < 0 && !base)
                    entries.push_back(std::uint32_t(t) * 4 + f);
            }
        if (packed.empty())
            packed.assign(1, glm::ivec4(-1)); // a buffer is never empty
        m_entryFaceCount = std::uint32_t(entries.size());
        std::vector<std::uint32_t> masks(std::max<std::size_t>(triangles, 1), 0u);
        for (const std::uint32_t e : entries)
            masks[(e >> 2) / 3] |= 1u << ((e >> 2) % 3 * 4 + (e & 3));
        m_neighbours = Buffer();
        m_entryMasks = Buffer();
        m_peelDraw = Buffer();
        m_neighbours = Buffer(m_ctx, packed.size() * sizeof(glm::ivec4), kStorage, kHost,
                              "baked tetrahedron neighbours");
        m_neighbours.upload(std::span<const glm::ivec4>(packed));
        m_entryMasks = Buffer(m_ctx, masks.size() * sizeof(std::uint32_t), kStorage, kHost,
                              "baked entry face masks");
        m_entryMasks.upload(std::span<const std::uint32_t>(masks));
        // Room for every face but the base: the shell pass lists the faces of folded
        // tetrahedra too, which the geometry decides frame by frame.
        m_peelDraw = Buffer(m_ctx, 16 + (11 * std::size_t(triangles) + 1) * sizeof(std::uint32_t),
                            kStorage | VK_BUFFER_USAGE_INDIRECT_BUFFER_BIT |
                                VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                            kDevice, "baked peel draw");
    }
}

void BakedRenderer::prepare(const View& view, const ImpulseSet& impulses,
                            const RenderSettings& settings) {
    if (!settings.bake)
        throw InputError("baked: no bake file (render --bake FILE.vdb; spotshell bake makes one)");
    requireBakedView(view);
    if (settings.peelPasses < 1 || settings.peelPasses > kBakedMaxPeelPasses)
        throw InputError(cat("baked: ", settings.peelPasses, " peel passes; 1 to ",
                             kBakedMaxPeelPasses, " are accepted"));
    if (!impulses.cells)
        throw InputError("baked: the shell's thickness needs the impulses' cells");
    const bool lit = view.shading.mode == noise::Shading::Mode::Lit;
    useBake(settings, impulses.cells->cellSize, lit);
    const float thickness = impulses.cells->cellSize;
    const std::uint32_t triangles = m_scene.meshPass().indexCount() / 3;
    ensureShell(triangles);
    m_bakeStats.thickness = thickness;
    m_bakeStats.tetrahedra = 3 * triangles;
    m_bakeStats.entryFaces = m_entryFaceCount;
    m_bakeStats.maxLayerTets = kBakedMaxLayerTets;
    m_bakeStats.maxLayerSamples = kBakedMaxLayerSamples;
    const std::uint32_t budget =
        settings.loopBudget > 0 ? settings.loopBudget : kBakedMarchLoopBudget;
    // baked_march.comp: M (1 + 4) + S (the trilinear sample is unrolled, no loop).
    const std::uint64_t bound =
        std::uint64_t(kBakedMaxLayerTets) * 5 + std::uint64_t(kBakedMaxLayerSamples);
    if (bound > budget)
        throw InputError(cat("baked: a layer may walk ", kBakedMaxLayerTets,
                             " tetrahedra and take ", kBakedMaxLayerSamples,
                             " samples, so one march invocation may loop ", bound,
                             " times, more than the budget of ", budget,
                             " (lavapipe stops an invocation at 65,535)"));
    m_bakeStats.loopBound = std::uint32_t(bound);
    m_bakeStats.peelPasses = std::uint32_t(settings.peelPasses);

    SpotBakedParams params{};
    params.grid = glm::vec4(m_bakeStats.voxelSize, 1.0f / m_bakeStats.voxelSize,
                            noise::kBakeDistanceCap, thickness);
    params.counts = glm::uvec4(triangles, m_bakeStats.levels, 3 * triangles, m_bricksPerBuffer);
    params.unit = glm::vec4(m_brickUnit, 0.0f, 0.0f, 0.0f);
    for (std::uint32_t s = 0; s < kBakedSections; ++s) {
        params.leafOrigin[s] = m_leafOrigin[s];
        params.leafDims[s] = m_leafDims[s];
    }
    if (lit)
        litParams(view.shading, params);
    m_params.upload(&params, sizeof(params));

    ensureTargets(std::uint32_t(view.camera.width), std::uint32_t(view.camera.height));
    // Lit: the mesh pass draws the mesh's colour unlit; the march lights it where a walk reaches
    // it (baked_march.comp).
    noise::Shading frameShading = view.shading;
    if (lit)
        frameShading = noise::Shading{};
    m_frame.frame = makeSplatFrame(view.camera, frameShading, view.baseColor, 0, 1, 1.0f, 0, 0);
    m_frame.background = view.background;
    m_frame.peelPasses = std::uint32_t(settings.peelPasses);
    m_frame.count = m_countLoops;
    m_frame.brickBuffers = m_bakeStats.brickBuffers;
    m_frame.lit = lit;
    marchPipeline(m_frame.count, false, lit, m_frame.brickBuffers);
    marchPipeline(m_frame.count, true, lit, m_frame.brickBuffers);
}

void BakedRenderer::litParams(const noise::Shading& shading, SpotBakedParams& params) const {
    if (shading.lights.size() > kBakedMaxLights)
        throw InputError(cat("baked: ", shading.lights.size(), " lights; at most ", kBakedMaxLights,
                             " are rendered"));
    static_assert(kBakedMaxLights == std::uint32_t(noise::kMaxLights));
    // The axis model: strand where the kernel has strand lobes, else flake where it has flakes,
    // else lambert (the gradient normal alone); its highlights the mean of its lobes'.
    const noise::Kernel& kernel = m_scene.kernel();
    using Model = noise::LobeShading::Model;
    const auto count = [&](Model m) {
        return std::count_if(kernel.lobes.begin(), kernel.lobes.end(),
                             [&](const noise::Lobe& l) { return l.shading.model == m; });
    };
    const Model model = count(Model::Strand) > 0  ? Model::Strand
                        : count(Model::Flake) > 0 ? Model::Flake
                                                  : Model::Lambert;
    const std::uint32_t code = model == Model::Strand  ? shared::f32::kSpotShadeStrand
                               : model == Model::Flake ? shared::f32::kSpotShadeFlake
                                                       : shared::f32::kSpotShadeLambert;
    glm::vec3 primary(0.0f), secondary(0.0f);
    for (const noise::Lobe& l : kernel.lobes)
        if (l.shading.model == model) {
            const noise::LobeLitModel m = noise::lobeLitModel(l);
            primary += glm::vec3(m.primary) / float(count(model));
            secondary += glm::vec3(m.secondary) / float(count(model));
        }
    params.lit = glm::uvec4(std::uint32_t(shading.lights.size()), code,
                            std::uint32_t(count(model)) == kernel.lobes.size() ? 1u : 0u, 0u);
    params.shadow = glm::uvec4(m_solidLevel, 0u, 0u, 0u);
    params.sky = glm::vec4(shading.sky.color * shading.sky.intensity, 0.0f);
    params.primary = glm::vec4(primary, 0.0f);
    params.secondary = glm::vec4(secondary, 0.0f);
    for (std::size_t i = 0; i < shading.lights.size(); ++i) {
        const noise::Light& light = shading.lights[i];
        const bool point = light.type == noise::Light::Type::Point;
        params.lights[i].position =
            glm::vec4(point ? light.position : light.direction, point ? 1.0f : 0.0f);
        params.lights[i].radiance =
            glm::vec4(light.color * light.intensity, light.shadows ? 1.0f : 0.0f);
    }
}

void BakedRenderer::record(VkCommandBuffer cmd, PassTimer& timer) {
    recordShell(cmd);
    timer.mark(cmd, "shell");
    recordMeshAndFirstPeel(cmd);
    timer.mark(cmd, "mesh+peel");
    // Per layer: the peel (the nearest entry face behind the previous layer's exit, before the
    // mesh: the mesh's depth tested and not written; the entry an atomicMax per pixel, the
    // pixels listed as they get one), then the march over the list, from the entry (or, in the
    // first layer, from the eye), composited under the earlier layers and over the mesh.
    // Per-layer marks while the timer has room for them (PassTimer takes 32), else one.
    const bool markLayers = m_frame.peelPasses <= kBakedMarkedLayers;
    for (std::uint32_t k = 0; k < m_frame.peelPasses; ++k) {
        if (k > 0) {
            VkRenderingAttachmentInfo depthInfo =
                depthAttachment(m_meshDepth, VK_ATTACHMENT_LOAD_OP_LOAD);
            depthInfo.imageLayout = passes::kGeneral;
            beginRendering(cmd, m_width, m_height, {}, &depthInfo);
            recordPeel(cmd, k);
            vkCmdEndRendering(cmd);
            fullBarrier(cmd);
            if (markLayers)
                timer.mark(cmd, "peel");
        }
        recordMarch(cmd, k);
        if (markLayers)
            timer.mark(cmd, "march");
    }
    if (!markLayers)
        timer.mark(cmd, "peel+march");
    using namespace passes;
    memoryBarrier(cmd, kAll, VK_ACCESS_2_MEMORY_WRITE_BIT, kCompute | kTransfer | kHostStage,
                  kStorageRead | VK_ACCESS_2_TRANSFER_READ_BIT | VK_ACCESS_2_HOST_READ_BIT);
}

Descriptors& BakedRenderer::bindList(Descriptors& d, std::uint32_t layer) const {
    return d.buffer(kBakedBindList, m_lists, layer * m_listStride, sizeof(SpotBakedList));
}

void BakedRenderer::recordShell(VkCommandBuffer cmd) {
    const Prepared& f = m_frame;
    const std::uint32_t triangles = m_bakeStats.tetrahedra / 3;
    const MeshPass& mesh = m_scene.meshPass();
    // The frame starts with no tetrahedron holding the eye, no face to peel, every layer's list
    // empty and no pixel with an entry (each march clears the entries it takes).
    vkCmdFillBuffer(cmd, m_eyeTet.handle(), 0, VK_WHOLE_SIZE, kBakedNoTet);
    const VkDrawIndirectCommand noFaces{0, 1, 0, 0};
    vkCmdUpdateBuffer(cmd, m_peelDraw.handle(), 0, sizeof(noFaces), &noFaces);
    vkCmdUpdateBuffer(cmd, m_lists.handle(), 0, f.peelPasses * m_listStride, m_emptyLists.data());
    vkCmdFillBuffer(cmd, m_layerEntry.handle(), 0, VK_WHOLE_SIZE, 0u);
    if (f.count)
        vkCmdFillBuffer(cmd, m_loops.handle(), 0, VK_WHOLE_SIZE, 0u);
    fullBarrier(cmd);

    // The shell from the mesh's vertices as posed (an animated mesh's deform passes wrote them
    // this frame) mapped back to the rest (the bake's coordinates), and the tetrahedron holding
    // the eye, if any (the lowest index).
    if (triangles > 0) {
        vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, m_shell.handle());
        pushFrame(cmd, m_shell, f.frame);
        Descriptors d;
        d.buffer(kBakedBindParams, m_params)
            .buffer(kBakedBindVertices, mesh.vertices())
            .buffer(kBakedBindRest, mesh.restVertices())
            .buffer(kBakedBindIndices, mesh.indices())
            .buffer(kBakedBindTets, m_tets)
            .buffer(kBakedBindEyeTet, m_eyeTet)
            .buffer(kBakedBindEntryMasks, m_entryMasks)
            .buffer(kBakedBindPeelDraw, m_peelDraw);
        bindList(d, 0).push(m_ctx, cmd, m_shell);
        vkCmdDispatch(cmd, (triangles + 63) / 64, 1, 1);
    }
    fullBarrier(cmd);
}

void BakedRenderer::recordMeshAndFirstPeel(VkCommandBuffer cmd) {
    using namespace passes;
    const Prepared& f = m_frame;
    const MeshPass& mesh = m_scene.meshPass();
    // The base mesh: its colour is the frame's result where no layer walks.
    for (const Image* image : {&m_base, &m_distance})
        transitionImage(cmd, image->handle(), kColorAspect, VK_IMAGE_LAYOUT_UNDEFINED, kAttachment,
                        VK_PIPELINE_STAGE_2_NONE, 0, kColorOut, kColorRW);
    transitionImage(cmd, m_meshDepth.handle(), VK_IMAGE_ASPECT_DEPTH_BIT, VK_IMAGE_LAYOUT_UNDEFINED,
                    VK_IMAGE_LAYOUT_DEPTH_ATTACHMENT_OPTIMAL, VK_PIPELINE_STAGE_2_NONE, 0, kTests,
                    kDepthRW);
    // The peel depth and coverage: written by a layer's march at every pixel the next peel tests
    // (a pixel without an entry in the first layer has none in any), so never cleared.
    transitionImage(cmd, m_exitDepth.handle(), kColorAspect, VK_IMAGE_LAYOUT_UNDEFINED, kGeneral,
                    VK_PIPELINE_STAGE_2_NONE, 0, kAll,
                    VK_ACCESS_2_MEMORY_READ_BIT | VK_ACCESS_2_MEMORY_WRITE_BIT);
    // The first layer's peel is drawn in the mesh's rendering, against the depth the mesh has
    // just written (a rendering and a barrier fewer).
    mesh.record(cmd, f.frame, m_base, m_distance, m_meshDepth, f.background,
                [&](VkCommandBuffer c) { recordPeel(c, 0); });
    for (const Image* image : {&m_base, &m_distance})
        transitionImage(cmd, image->handle(), kColorAspect, kAttachment, kGeneral, kColorOut,
                        VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT, kAll,
                        VK_ACCESS_2_MEMORY_READ_BIT | VK_ACCESS_2_MEMORY_WRITE_BIT);
    transitionImage(cmd, m_meshDepth.handle(), VK_IMAGE_ASPECT_DEPTH_BIT,
                    VK_IMAGE_LAYOUT_DEPTH_ATTACHMENT_OPTIMAL, kGeneral, kTests, kDepthRW, kAll,
                    VK_ACCESS_2_MEMORY_READ_BIT);
    // Written before they are read: by the first layer's march at every pixel a later one walks.
    for (const Image* image : {&m_accum, &m_baseKept})
        transitionImage(cmd, image->handle(), kColorAspect, VK_IMAGE_LAYOUT_UNDEFINED, kGeneral,
                        VK_PIPELINE_STAGE_2_NONE, 0, kAll,
                        VK_ACCESS_2_MEMORY_READ_BIT | VK_ACCESS_2_MEMORY_WRITE_BIT);
    fullBarrier(cmd);
}

void BakedRenderer::recordPeel(VkCommandBuffer cmd, std::uint32_t k) {
    using namespace passes;
    const Prepared& f = m_frame;
    if (m_entryFaceCount == 0)
        return;
    const Pipeline& peel = m_peel[k == 0];
    vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, peel.handle());
    pushFrame(cmd, peel, f.frame);
    Descriptors d;
    d.buffer(kBakedBindTets, m_tets)
        .buffer(kBakedBindPeelDraw, m_peelDraw)
        .image(kBakedBindPrevDepth, m_exitDepth, kGeneral, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE)
        .buffer(kBakedBindLayerEntry, m_layerEntry)
        .buffer(kBakedBindListPixels, m_listPixels);
    bindList(d, k).push(m_ctx, cmd, peel);
    vkCmdDrawIndirect(cmd, m_peelDraw.handle(), 0, 1, sizeof(VkDrawIndirectCommand));
}

void BakedRenderer::recordMarch(VkCommandBuffer cmd, std::uint32_t k) {
    using namespace passes;
    const Prepared& f = m_frame;
    const bool first = k == 0;
    const Pipeline& march = m_march.at({f.count, first, f.lit, f.brickBuffers});
    vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, march.handle());
    pushFrame(cmd, march, f.frame);
    Descriptors d;
    d.buffer(kBakedBindParams, m_params)
        .buffer(kBakedBindTets, m_tets)
        .buffer(kBakedBindNeighbours, m_neighbours)
        .buffer(kBakedBindEyeTet, m_eyeTet)
        .buffer(kBakedBindTable, m_table)
        .buffer(kBakedBindLayerEntry, m_layerEntry)
        .image(kBakedBindMeshDistance, m_distance, kGeneral, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE)
        .image(kBakedBindAccum, m_accum, kGeneral, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE)
        .image(kBakedBindBase, m_base, kGeneral, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE)
        .image(kBakedBindBaseKept, m_baseKept, kGeneral, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE)
        .image(kBakedBindExitDepth, m_exitDepth, kGeneral, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE)
        .buffer(kBakedBindLoops, m_loops)
        .buffer(kBakedBindListPixels, m_listPixels);
    if (f.lit)
        d.buffer(kBakedBindVertices, m_scene.meshPass().vertices())
            .buffer(kBakedBindIndices, m_scene.meshPass().indices())
            .buffer(kBakedBindSolid, m_solid);
    const std::uint32_t brickBindings[] = {kBakedBindBricks, kBakedBindBricks1, kBakedBindBricks2,
                                           kBakedBindBricks3};
    const std::uint32_t shadingBindings[] = {kBakedBindShading, kBakedBindShading1,
                                             kBakedBindShading2, kBakedBindShading3};
    for (std::uint32_t i = 0; i < f.brickBuffers; ++i) { // the march module reads these alone
        d.buffer(brickBindings[i], m_bricks[i]);
        if (f.lit)
            d.buffer(shadingBindings[i], m_shadingBricks[i]);
    }
    bindList(d, k).push(m_ctx, cmd, march);
    vkCmdDispatchIndirect(cmd, m_lists.handle(), k * m_listStride);
    fullBarrier(cmd);
}

BakedStats BakedRenderer::stats() const {
    BakedStats s = m_bakeStats;
    if (m_frame.count)
        std::memcpy(&s.maxLoopIterations, m_loops.mapped(), sizeof(std::uint32_t));
    std::uint32_t eye = kBakedNoTet;
    std::memcpy(&eye, m_eyeTet.mapped(), sizeof(eye));
    s.eyeTetrahedron = eye == kBakedNoTet ? -1 : std::int64_t(eye);
    return s;
}

FrameCounters BakedRenderer::counters() const {
    const BakedStats s = stats();
    FrameCounters c;
    c.extra = {{"voxel_size", double(s.voxelSize)},
               {"levels", double(s.levels)},
               {"thickness", double(s.thickness)},
               {"tetrahedra", double(s.tetrahedra)},
               {"bricks", double(s.bricks)},
               {"brick_buffers", double(s.brickBuffers)},
               {"distance_bricks", double(s.distanceBricks)},
               {"entry_faces", double(s.entryFaces)},
               {"max_layer_tets", double(s.maxLayerTets)},
               {"max_layer_samples", double(s.maxLayerSamples)},
               {"table_entries", double(s.tableEntries)},
               {"loop_bound", double(s.loopBound)},
               {"peel_passes", double(s.peelPasses)},
               {"eye_tetrahedron", double(s.eyeTetrahedron)},
               {"bake_mib", double(s.gpuBytes) / double(1 << 20)}};
    if (m_frame.count)
        c.extra.emplace_back("max_loop_iterations", double(s.maxLoopIterations));
    return c;
}

MethodInfo bakedMethod() {
    MethodInfo m;
    m.name = "baked";
    m.summary = "a bake (render --bake FILE.vdb) marched through the shell's tetrahedra, "
                "composited by depth peeling";
    m.settings = {&settings::bake, &settings::peelPasses, &settings::allowMismatch};
    m.make = [](const SceneGpu& scene) -> std::unique_ptr<Renderer> {
        return std::make_unique<BakedRenderer>(scene);
    };
    m.summarize = [](const RenderSettings& s) {
        return cat(s.peelPasses, s.peelPasses == 1 ? " peel pass, " : " peel passes, ");
    };
    m.drawsKernels = false;
    m.rendersLit = true;
    return m;
}

} // namespace spot::splat
