#include "raymarch_vk.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <memory>
#include <span>
#include <thread>

#include "noise/error.h"
#include "noise/mesh.h"
#include "noise/system.h"
#include "shaders/spot_shared.hpp"
#include "splat/layout.h"
#include "splat/pass_vk.h"

#include "raymarch_bin.comp.h"
#include "raymarch_march.comp.h"
#include "raymarch_resolve.comp.h"
#include "splat_prepare.comp.h"

namespace spot::splat {


} // namespace spot::splat

namespace spot::shared::f32 {

using gpu::SpotWorldLobe;
using splat::gpu_march::kMarchFar;
using splat::gpu_march::kMarchFlagLambert;
using splat::gpu_march::kMarchFlagNoCulling;
using splat::gpu_march::SpotMarchBox;
using splat::gpu_march::kMarchMaxSegments;
using splat::gpu_march::kMarchOpaque;
using splat::gpu_march::SpotMarchCell;
using splat::gpu_march::SpotMarchParams;

/// shaders/raymarch_shared.glsl compiled for the CPU: the march the GPU runs, as member functions
/// reading host arrays (the pattern of noise/generator_shared.h).
class MarchTwin {
public:
    struct Arrays {
        const SpotMarchParams* params = nullptr;
        const glm::ivec4* table = nullptr;
        const SpotMarchCell* cells = nullptr;
        const SpotWorldLobe* lobes = nullptr;
        const SpotMarchBox* boxes = nullptr;
    };
    explicit MarchTwin(const Arrays& arrays) : m_a(arrays) {}

private:
    Arrays m_a;
    const SpotMarchParams& marchParams() const { return *m_a.params; }
    glm::ivec4 marchSlot(uint i) const { return m_a.table[i]; }
    const SpotMarchCell& marchCell(uint record) const { return m_a.cells[record]; }
    const SpotWorldLobe& marchLobe(uint i) const { return m_a.lobes[i]; }
    const SpotMarchBox& marchBox(uint impulse) const { return m_a.boxes[impulse]; }

public:
#define SPOT_FN
#define SPOT_CONST static constexpr
#define SPOT_OUT(T) T&
#define SPOT_INOUT(T) T&
#include "shaders/raymarch_shared.glsl"
#undef SPOT_FN
#undef SPOT_CONST
#undef SPOT_OUT
#undef SPOT_INOUT
};

} // namespace spot::shared::f32

namespace spot::splat {

namespace {

using gpu_march::SpotMarchBox;
using gpu_march::SpotMarchCell;
using gpu_march::SpotMarchParams;
using gpu_splat::SpotMeshVertex;
using gpu_splat::SpotSplatFrame;
using shared::f32::MarchTwin;

/// prepare.comp and raymarch_bin.comp run 64 impulses per workgroup; a dispatch has at most
/// 65,535 workgroups.
constexpr std::uint32_t kMaxImpulses = 65535u * 64u;
/// Hash table: at most half full; a longer probe than this doubles the table (the bound pays P
/// per lookup, so a short probe matters more than memory).
constexpr std::int32_t kWantedProbe = 8;
constexpr int kTableGrowths = 4;

/// 91234 -> "91,234".
std::string withCommas(std::uint64_t n) {
    std::string digits = std::to_string(n), out;
    for (std::size_t i = 0; i < digits.size(); ++i) {
        if (i > 0 && (digits.size() - i) % 3 == 0)
            out += ',';
        out += digits[i];
    }
    return out;
}

bool lexLess(const glm::ivec3& a, const glm::ivec3& b) {
    return a.x != b.x ? a.x < b.x : a.y != b.y ? a.y < b.y : a.z < b.z;
}

std::uint64_t fingerprint(const noise::SurfaceCells& cells) {
    std::uint64_t h = 0xcbf29ce484222325ull; // FNV-1a over the cell size and every ijk
    const auto mix = [&h](std::uint32_t v) {
        for (int b = 0; b < 4; ++b) {
            h ^= (v >> (8 * b)) & 0xffu;
            h *= 0x100000001b3ull;
        }
    };
    std::uint32_t bits;
    std::memcpy(&bits, &cells.cellSize, 4);
    mix(bits);
    mix(std::uint32_t(cells.cells.size()));
    for (const noise::SurfaceCell& c : cells.cells) {
        mix(std::uint32_t(c.ijk.x));
        mix(std::uint32_t(c.ijk.y));
        mix(std::uint32_t(c.ijk.z));
    }
    return h;
}

} // namespace

std::uint64_t raymarchLoopBound(std::uint64_t steps, std::uint64_t walkCells,
                                std::uint64_t longestProbe, std::uint64_t neighbourhoodImpulses,
                                std::uint64_t lobesPerImpulse) {
    // raymarch_shared.glsl: marchShell costs 1 + W (1 + marchFind), marchFind at most P + 2;
    // marchRay adds 1 + N (1 + (1 + S - 1) + marchFind + 1 + T (1 + 1 + L)).
    const std::uint64_t find = longestProbe + 2;
    const std::uint64_t walk = 1 + walkCells * (1 + find);
    const std::uint64_t perStep = 1 + gpu_march::kMarchMaxSegments + find + 1 +
                                  neighbourhoodImpulses * (2 + lobesPerImpulse);
    return walk + 1 + steps * perStep;
}

/// The shell: surface cells dilated by one cell, sorted by (i, j, k) like the surface cells, and
/// the hash table that finds them. Depends only on the cells, so it is kept while they stay the
/// same (checked by a fingerprint of every ijk).
struct RaymarchRenderer::Shell {
    std::uint64_t fingerprint = 0;
    float cellSize = 0.0f;
    std::vector<glm::ivec3> cells;
    std::vector<std::uint8_t> surface; ///< per shell cell: 1 for a surface cell
    std::vector<glm::ivec4> table;
    glm::ivec3 lo{0}, hi{-1};
    std::uint32_t mask = 0;
    std::int32_t longestProbe = 0;
    Buffer tableBuffer;

    std::uint32_t walkCells() const {
        return cells.empty()
                   ? 0u
                   : std::uint32_t((hi.x - lo.x + 1) + (hi.y - lo.y + 1) + (hi.z - lo.z + 1));
    }
    /// Params with the shell's part filled in.
    SpotMarchParams params() const {
        SpotMarchParams p{};
        p.grid = glm::vec4(cellSize, 1.0f / cellSize, 0.0f, 0.0f);
        p.lo = glm::ivec4(lo, std::int32_t(mask));
        p.hi = glm::ivec4(hi, longestProbe);
        p.counts = glm::uvec4(0u, 0u, walkCells(), 0u);
        return p;
    }
};

const RaymarchRenderer::Shell& RaymarchRenderer::shellFor(const noise::SurfaceCells& cells) {
    const std::uint64_t print = fingerprint(cells);
    if (m_shell && m_shell->fingerprint == print && m_shell->cellSize == cells.cellSize)
        return *m_shell;
    auto shell = std::make_shared<Shell>();
    shell->fingerprint = print;
    shell->cellSize = cells.cellSize;
    // Dilate: 27 neighbours of every surface cell (|ijk| < 2^20 + 1, no overflow).
    requireMemory(std::uint64_t(cells.cells.size()) * 27 * sizeof(glm::ivec3),
                  cat("the ray march's shell of ", cells.cells.size(), " cells"));
    shell->cells.reserve(cells.cells.size() * 27);
    for (const noise::SurfaceCell& c : cells.cells)
        for (int i = -1; i <= 1; ++i)
            for (int j = -1; j <= 1; ++j)
                for (int k = -1; k <= 1; ++k)
                    shell->cells.push_back(c.ijk + glm::ivec3(i, j, k));
    std::sort(shell->cells.begin(), shell->cells.end(), lexLess);
    shell->cells.erase(std::unique(shell->cells.begin(), shell->cells.end()), shell->cells.end());
    shell->cells.shrink_to_fit();
    shell->surface.assign(shell->cells.size(), 0);
    for (const noise::SurfaceCell& c : cells.cells)
        shell->surface[std::size_t(
            std::lower_bound(shell->cells.begin(), shell->cells.end(), c.ijk, lexLess) -
            shell->cells.begin())] = 1;
    if (!shell->cells.empty()) {
        shell->lo = shell->cells.front();
        shell->hi = shell->cells.front();
        for (const glm::ivec3& c : shell->cells) {
            shell->lo = glm::min(shell->lo, c);
            shell->hi = glm::max(shell->hi, c);
        }
    }

    // Open addressing with linear probing, at most half full; grown until no key lies more than
    // kWantedProbe slots past its home (or kTableGrowths doublings: the bound pays for the rest).
    std::uint64_t capacity = 16;
    while (capacity < 2 * std::uint64_t(shell->cells.size()))
        capacity *= 2;
    const SpotMarchParams none{};
    MarchTwin hasher(MarchTwin::Arrays{&none, nullptr, nullptr, nullptr});
    for (int growth = 0;; ++growth, capacity *= 2) {
        shell->table.assign(capacity, glm::ivec4(0, 0, 0, gpu_march::kMarchEmptySlot));
        shell->mask = std::uint32_t(capacity - 1);
        shell->longestProbe = 0;
        for (std::size_t r = 0; r < shell->cells.size(); ++r) {
            const glm::ivec3 c = shell->cells[r];
            std::uint32_t slot = hasher.marchHash(c) & shell->mask;
            std::int32_t probe = 0;
            while (shell->table[slot].w != gpu_march::kMarchEmptySlot) {
                slot = (slot + 1) & shell->mask;
                ++probe;
            }
            shell->table[slot] = glm::ivec4(c, std::int32_t(r));
            shell->longestProbe = std::max(shell->longestProbe, probe);
        }
        if (shell->longestProbe <= kWantedProbe || growth == kTableGrowths)
            break;
    }
    shell->tableBuffer =
        Buffer(m_ctx, shell->table.size() * sizeof(glm::ivec4), VK_BUFFER_USAGE_STORAGE_BUFFER_BIT,
               Buffer::Memory::HostVisible,
               cat("ray march cell table (", shell->cells.size(), " shell cells)"));
    shell->tableBuffer.upload(std::span<const glm::ivec4>(shell->table));
    m_shell = std::move(shell);
    return *m_shell;
}

RaymarchRenderer::RaymarchRenderer(Context& ctx, const noise::Mesh& mesh,
                                   const noise::Kernel& kernel)
    : m_ctx(ctx), m_meshPass(ctx, mesh, "raymarch"), m_binTimes(ctx, 4), m_marchTimes(ctx, 3) {
    m_lobes = uploadKernelLobes(ctx, kernel, "raymarch renderer");
    m_lobeCount = std::uint32_t(kernel.lobes.size());
    m_support = kernel.supportSigma;

    const std::uint32_t push = sizeof(SpotSplatFrame);
    // TODO(binding names): these numbers are the shaders' bindings by position.
    auto buffers = [](std::uint32_t n) {
        Bindings b;
        for (std::uint32_t i = 0; i < n; ++i)
            b.push_back(storageBuffer(i));
        return b;
    };
    m_bin = makeComputePipeline(ctx, spirv(spv_raymarch_bin_comp), buffers(6), 2 * sizeof(std::uint32_t));
    // One layout for the march and its resolve (each pushes the bindings it reads): 0 params,
    // 1 hash table, 2 neighbourhoods, 3 world lobes, 4 base colour, 5 mesh distance, 6 march
    // state, 7 loop counts, 8 result, 9 impulse boxes.
    Bindings marchBindings = buffers(10);
    marchBindings[4] = storageImage(4);
    marchBindings[5] = storageImage(5);
    m_march = makeComputePipeline(ctx, spirv(spv_raymarch_march_comp), marchBindings, push);
    m_resolve = makeComputePipeline(ctx, spirv(spv_raymarch_resolve_comp), marchBindings, push);
}

noise::Image RaymarchRenderer::render(const noise::Camera& camera, const noise::Shading& shading,
                                      glm::vec3 background, glm::vec3 baseColor,
                                      const noise::SurfaceCells& cells, const Buffer& impulses,
                                      std::uint32_t count, const RaymarchSettings& settings,
                                      RaymarchStats* stats, RaymarchCapture* capture) {
    if (settings.steps < 1 || settings.steps > kRaymarchMaxSteps)
        throw InputError(cat("raymarch: --steps ", settings.steps, " is outside [1, ",
                             kRaymarchMaxSteps, "]"));
    if (settings.supersample < 1 || settings.supersample > kRaymarchMaxSupersample)
        throw InputError(cat("raymarch: --supersample ", settings.supersample, " is outside [1, ",
                             kRaymarchMaxSupersample, "]"));
    const std::uint32_t n = std::uint32_t(settings.supersample);
    // The march renders the n x n supersampled image: the same view, n times the pixels a side.
    noise::Camera marchCamera = camera;
    marchCamera.width = int(std::min<std::int64_t>(std::int64_t(camera.width) * n, 1 << 30));
    marchCamera.height = int(std::min<std::int64_t>(std::int64_t(camera.height) * n, 1 << 30));
    const SpotSplatFrame frame =
        // No EWA flag: the march samples the density itself, and lobes widened by the pixel
        // footprint could reach past the 27 cells it searches. (Also validates the camera.)
        makeSplatFrame(marchCamera, shading, baseColor, count, m_lobeCount, m_support, 0, 0);
    if (count > kMaxImpulses)
        throw InputError(cat("raymarch: ", count, " impulses, more than the ", kMaxImpulses,
                             " one frame can place"));
    if (std::uint64_t(count) * sizeof(gpu::SpotImpulse) > impulses.size() || !impulses.handle())
        throw InputError(cat("raymarch: the impulse buffer holds ", impulses.size(), " bytes, ",
                             count, " impulses need ",
                             std::uint64_t(count) * sizeof(gpu::SpotImpulse)));
    if (!(cells.cellSize > 0.0f) || !std::isfinite(cells.cellSize))
        throw InputError(cat("raymarch: cell size ", cells.cellSize, " must be positive"));
    const Shell& shell = shellFor(cells);
    const std::uint32_t records = std::uint32_t(shell.cells.size());
    const std::uint32_t outWidth = std::uint32_t(camera.width);
    const std::uint32_t outHeight = std::uint32_t(camera.height);
    const std::uint32_t width = std::uint32_t(marchCamera.width);
    const std::uint32_t height = std::uint32_t(marchCamera.height);
    const std::uint64_t pixels = std::uint64_t(width) * height; // march pixels
    const std::uint64_t outPixels = std::uint64_t(outWidth) * outHeight;

    // Memory: world lobes and kernel bounds (prepare), bins, records; per march pixel the base
    // colour, mesh distance, depth, state and loop count; per output pixel the result.
    const std::uint64_t need =
        std::uint64_t(count) *
            (m_lobeCount * sizeof(gpu::SpotWorldLobe) +
             sizeof(SpotMarchBox)) +
        std::uint64_t(records) * (3 * 4 + sizeof(SpotMarchCell)) + 4 + sizeof(SpotMarchParams) +
        pixels * (16 + 4 + 4 + 16 + 4) + outPixels * 16 + 4 + (capture ? pixels * 20 : 0);
    if (m_ctx.allocatedBytes() + need > m_ctx.memoryBudget())
        throw InputError(cat("raymarch: a ", outWidth, "x", outHeight, " frame (", n, "x", n,
                             " rays per pixel) of ", count,
                             " kernels over ", records, " shell cells needs ", need >> 20,
                             " MiB of GPU memory; ", m_ctx.allocatedBytes() >> 20,
                             " MiB are in use and the budget is ", m_ctx.memoryBudget() >> 20,
                             " MiB; reduce the image size or the kernel count"));
    const std::uint64_t allocatedBefore = m_ctx.allocatedBytes();

    SpotMarchParams params = shell.params();
    params.grid.z = m_support;
    params.counts.x = std::uint32_t(settings.steps);
    params.counts.y = m_lobeCount;
    params.counts.w =
        (shading.mode == noise::Shading::Mode::Lambert ? gpu_march::kMarchFlagLambert : 0u) |
        (settings.cullImpulses ? 0u : gpu_march::kMarchFlagNoCulling);
    params.light = glm::vec4(shading.lightDir, shading.ambient);
    params.range = glm::uvec4(0u, 0u, n, 0u);

    constexpr VkBufferUsageFlags kStorage = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT;
    constexpr VkBufferUsageFlags kFilled = kStorage | VK_BUFFER_USAGE_TRANSFER_DST_BIT;
    constexpr Buffer::Memory kHost = Buffer::Memory::HostVisible;
    constexpr Buffer::Memory kDevice = Buffer::Memory::DeviceLocal;
    // Each dispatch of the march rewrites params.range (vkCmdUpdateBuffer).
    Buffer paramBuffer(m_ctx, sizeof(SpotMarchParams), kFilled, kHost, "ray march parameters");
    paramBuffer.upload(&params, sizeof(params));
    Buffer worldLobes(m_ctx, std::uint64_t(count) * m_lobeCount * sizeof(gpu::SpotWorldLobe),
                      kStorage, capture ? kHost : kDevice,
                      cat("ray march world lobes (", count, " kernels)"));
    Buffer boxes(m_ctx, std::uint64_t(count) * sizeof(SpotMarchBox), kStorage,
                 capture ? kHost : kDevice, cat("ray march impulse boxes (", count, " kernels)"));
    // The prepare pass writes world lobes only here; its screen outputs are not written.
    Buffer unused(m_ctx, 16, kStorage, kDevice, "ray march prepare: unused screen outputs");
    Buffer countBuffer(m_ctx, 16, kStorage, kHost, "ray march impulse count");
    *static_cast<std::uint32_t*>(countBuffer.mapped()) = count;
    if (!m_prepare.handle() || m_prepareOrthographic != (camera.projection == noise::Projection::Orthographic)) {
        m_prepareOrthographic = camera.projection == noise::Projection::Orthographic;
        m_prepare = makePreparePipeline(m_ctx, m_lobeCount, false, false, m_prepareOrthographic);
    }
    Buffer bins(m_ctx, (3 * std::uint64_t(records) + 1) * sizeof(std::uint32_t), kFilled, kHost,
                "ray march cell bins");
    Buffer recordBuffer(m_ctx, std::uint64_t(records) * sizeof(SpotMarchCell), kStorage, kHost,
                        cat("ray march neighbourhoods (", records, " shell cells)"));
    Buffer state(m_ctx, pixels * sizeof(glm::vec4), kStorage, kDevice,
                 "ray march state (radiance, transmittance)");
    Buffer result(m_ctx, outPixels * sizeof(glm::vec4), kStorage, kHost, "ray march result");
    Buffer loopCounts(m_ctx, (pixels + 1) * sizeof(std::uint32_t), kFilled, kHost,
                      "ray march loop counts");
    constexpr VkImageUsageFlags kTarget = VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT |
                                          VK_IMAGE_USAGE_STORAGE_BIT |
                                          VK_IMAGE_USAGE_TRANSFER_SRC_BIT;
    Image base(m_ctx, width, height, kColorFormat, kTarget, VK_IMAGE_ASPECT_COLOR_BIT,
               "ray march base colour");
    Image distance(m_ctx, width, height, kScalarFormat, kTarget, VK_IMAGE_ASPECT_COLOR_BIT,
                   "ray march mesh distance");
    Image depth(m_ctx, width, height, kDepthFormat, VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT,
                VK_IMAGE_ASPECT_DEPTH_BIT, "ray march depth");
    Buffer baseCopy, distanceCopy;
    if (capture) {
        baseCopy = Buffer(m_ctx, pixels * sizeof(glm::vec4), VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                          kHost, "ray march capture: base colour");
        distanceCopy = Buffer(m_ctx, pixels * sizeof(float), VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                              kHost, "ray march capture: mesh distance");
    }

    using namespace passes;

    // Submit 1: world lobes, bins, the mesh (what the march needs besides the neighbourhoods).
    m_ctx.submitAndWait([&](VkCommandBuffer cmd) {
        m_binTimes.reset(cmd);
        m_binTimes.write(cmd, 0, kAll);
        if (count > 0) {
            PrepareBuffers pb;
            pb.impulses = &impulses;
            pb.count = &countBuffer;
            pb.lobes = &m_lobes;
            pb.worldLobes = &worldLobes;
            pb.screenLobes = &unused;
            pb.bounds = &unused;
            recordPrepare(m_ctx, cmd, m_prepare, frame, pb, count);
        }
        m_binTimes.write(cmd, 1, kAll);
        const std::uint64_t firstBytes = std::uint64_t(records) * sizeof(std::uint32_t);
        if (records > 0)
            vkCmdFillBuffer(cmd, bins.handle(), 0, firstBytes, 0xffffffffu);
        vkCmdFillBuffer(cmd, bins.handle(), firstBytes, VK_WHOLE_SIZE, 0u);
        vkCmdFillBuffer(cmd, loopCounts.handle(), 0, VK_WHOLE_SIZE, 0u);
        // The bins are cleared and the world lobes (prepare) written before the bin pass.
        memoryBarrier(cmd, VK_PIPELINE_STAGE_2_CLEAR_BIT | kCompute,
                      VK_ACCESS_2_TRANSFER_WRITE_BIT | VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT,
                      kCompute, kStorageRW);
        if (count > 0) {
            vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, m_bin.handle());
            const std::uint32_t push[2] = {count, records};
            vkCmdPushConstants(cmd, m_bin.layout(), VK_SHADER_STAGE_COMPUTE_BIT, 0, sizeof(push),
                               push);
            Descriptors()
                .buffer(0, paramBuffer)
                .buffer(1, shell.tableBuffer)
                .buffer(2, impulses)
                .buffer(3, bins)
                .buffer(4, worldLobes)
                .buffer(5, boxes)
                .push(m_ctx, cmd, m_bin);
            vkCmdDispatch(cmd, (count + 63) / 64, 1, 1);
        }
        m_binTimes.write(cmd, 2, kAll);

        for (const Image* image : {&base, &distance})
            transitionImage(cmd, image->handle(), VK_IMAGE_ASPECT_COLOR_BIT,
                            VK_IMAGE_LAYOUT_UNDEFINED, kAttachment, VK_PIPELINE_STAGE_2_NONE, 0,
                            kColorOut, kColorRW);
        transitionImage(cmd, depth.handle(), VK_IMAGE_ASPECT_DEPTH_BIT, VK_IMAGE_LAYOUT_UNDEFINED,
                        VK_IMAGE_LAYOUT_DEPTH_ATTACHMENT_OPTIMAL, VK_PIPELINE_STAGE_2_NONE, 0,
                        kTests, kDepthRW);
        m_meshPass.record(cmd, frame, base, distance, depth, background);
        for (const Image* image : {&base, &distance})
            transitionImage(cmd, image->handle(), VK_IMAGE_ASPECT_COLOR_BIT, kAttachment, kGeneral,
                            kColorOut, VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT, kCompute | kTransfer,
                            kStorageRead | VK_ACCESS_2_TRANSFER_READ_BIT);
        if (capture) {
            VkBufferImageCopy region{};
            region.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
            region.imageExtent = {width, height, 1};
            vkCmdCopyImageToBuffer(cmd, base.handle(), kGeneral, baseCopy.handle(), 1, &region);
            vkCmdCopyImageToBuffer(cmd, distance.handle(), kGeneral, distanceCopy.handle(), 1,
                                   &region);
        }
        m_binTimes.write(cmd, 3, kAll);
        memoryBarrier(cmd, kCompute | kTransfer,
                      VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT | VK_ACCESS_2_TRANSFER_WRITE_BIT,
                      kHostStage, VK_ACCESS_2_HOST_READ_BIT);
    });

    // On the host: check the impulse order, build each shell cell's neighbourhood ranges, bound
    // the march's loops.
    const auto hostStart = std::chrono::steady_clock::now();
    const auto* bin = static_cast<const std::uint32_t*>(bins.mapped());
    const std::uint32_t* binFirst = bin;
    const std::uint32_t* binEnd = bin + records;
    const std::uint32_t* binCount = bin + 2 * std::uint64_t(records);
    if (const std::uint32_t outside = bin[3 * std::uint64_t(records)]; outside > 0)
        throw InputError(cat("raymarch: ", outside, " of ", count,
                             " impulses lie outside the given surface cells (cell size ",
                             cells.cellSize,
                             "); render impulses with the cells that generated them"));
    std::uint32_t expected = 0;
    for (std::uint32_t r = 0; r < records; ++r) {
        if (binCount[r] == 0)
            continue;
        if (!shell.surface[r])
            throw InputError(cat("raymarch: ", binCount[r], " impulses lie in cell ",
                                 shell.cells[r].x, " ", shell.cells[r].y, " ", shell.cells[r].z,
                                 ", which is not one of the given surface cells (cell size ",
                                 cells.cellSize,
                                 "); render impulses with the cells that "
                                 "generated them"));
        if (binFirst[r] != expected || binEnd[r] - binFirst[r] != binCount[r])
            throw InputError(cat("raymarch: the impulses are not in cell order (cell ",
                                 shell.cells[r].x, " ", shell.cells[r].y, " ", shell.cells[r].z,
                                 " holds ", binCount[r], " impulses spread over [", binFirst[r],
                                 ", ", binEnd[r], "), expected from ", expected,
                                 "); the generators give them in cell order"));
        expected = binEnd[r];
    }
    SPOT_CHECK_EQ(expected, count);
    std::vector<SpotMarchCell> neighbourhoods(records);
    std::uint32_t mostImpulses = 0;
    {
        MarchTwin find(MarchTwin::Arrays{&params, shell.table.data(), nullptr, nullptr, nullptr});
        for (std::uint32_t r = 0; r < records; ++r) {
            SpotMarchCell& cell = neighbourhoods[r];
            cell = SpotMarchCell{};
            std::uint32_t ranges = 0, total = 0;
            for (int di = -1; di <= 1; ++di)
                for (int dj = -1; dj <= 1; ++dj) {
                    // The column's (up to three) cells are consecutive records, so their
                    // impulses are one range.
                    std::uint32_t first = ~0u, end = 0;
                    for (int dk = -1; dk <= 1; ++dk) {
                        std::uint32_t loops = 0;
                        const int n =
                            find.marchFind(shell.cells[r] + glm::ivec3(di, dj, dk), loops);
                        if (n >= 0 && binCount[n] > 0) {
                            first = std::min(first, binFirst[n]);
                            end = std::max(end, binEnd[n]);
                        }
                    }
                    if (end == 0)
                        continue;
                    cell.range[ranges / 2][2 * (ranges % 2)] = first;
                    cell.range[ranges / 2][2 * (ranges % 2) + 1] = end - first;
                    ++ranges;
                    total += end - first;
                }
            cell.head = glm::uvec4(ranges, total, 0u, 0u);
            mostImpulses = std::max(mostImpulses, total);
        }
    }
    // The guard: split the march over dispatches of at most `perDispatch` steps, each within the
    // loop budget; refuse a frame where not even one step fits.
    const std::uint32_t walk = shell.walkCells();
    const std::uint64_t lobesPerStep = std::uint64_t(mostImpulses) * m_lobeCount;
    const auto loopBound = [&](std::uint64_t n) {
        return raymarchLoopBound(n, walk, std::uint64_t(shell.longestProbe), mostImpulses,
                                 m_lobeCount);
    };
    const std::uint64_t fixed = loopBound(0);
    const std::uint64_t perStep = loopBound(1) - fixed;
    const std::uint64_t fits =
        settings.loopBudget > fixed ? (settings.loopBudget - fixed) / perStep : 0;
    if (fits == 0)
        throw InputError(cat(
            "raymarch: even one step would need up to ", withCommas(fixed + perStep),
            " loop iterations in one shader invocation (", withCommas(lobesPerStep),
            " lobes summed at each step in the densest neighbourhood, ", withCommas(fixed),
            " to walk the shell's ", shell.hi.x - shell.lo.x + 1, "x", shell.hi.y - shell.lo.y + 1,
            "x", shell.hi.z - shell.lo.z + 1, " cells) and the budget is ",
            withCommas(settings.loopBudget), " (lavapipe stops at ",
            withCommas(gpu_march::kMarchLavapipeLoopLimit),
            " without an error); lower the kernel density or the cell count"));
    // As few dispatches as fit, with the steps spread evenly over them.
    const std::uint32_t steps = std::uint32_t(settings.steps);
    const std::uint32_t dispatches = std::uint32_t((steps + fits - 1) / fits);
    const std::uint32_t perDispatch = (steps + dispatches - 1) / dispatches;
    const std::uint64_t bound = loopBound(perDispatch);
    if (records > 0)
        recordBuffer.upload(std::span<const SpotMarchCell>(neighbourhoods));
    const double hostMs =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - hostStart)
            .count();

    // Submit 2: the march, in `dispatches` dispatches of at most `perDispatch` steps each (params
    // .range names them), then the resolve: each output pixel the mean of its n x n rays.
    m_ctx.submitAndWait([&](VkCommandBuffer cmd) {
        m_marchTimes.reset(cmd);
        m_marchTimes.write(cmd, 0, kAll);
        vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, m_march.handle());
        pushFrame(cmd, m_march, frame);
        Descriptors()
            .buffer(0, paramBuffer)
            .buffer(1, shell.tableBuffer)
            .buffer(2, recordBuffer)
            .buffer(3, worldLobes)
            .image(5, distance, kGeneral, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE)
            .buffer(6, state)
            .buffer(7, loopCounts)
            .buffer(9, boxes)
            .push(m_ctx, cmd, m_march);
        for (std::uint32_t k = 0; k < dispatches; ++k) {
            const glm::uvec4 range(k * perDispatch, std::min(steps, (k + 1) * perDispatch), n, 0u);
            if (k > 0) // the previous dispatch read the params and wrote the state
                memoryBarrier(cmd, kCompute, kStorageRW, kTransfer | kCompute,
                              VK_ACCESS_2_TRANSFER_WRITE_BIT | kStorageRW);
            vkCmdUpdateBuffer(cmd, paramBuffer.handle(), offsetof(SpotMarchParams, range),
                              sizeof(range), &range);
            memoryBarrier(cmd, kTransfer, VK_ACCESS_2_TRANSFER_WRITE_BIT, kCompute, kStorageRead);
            vkCmdDispatch(cmd, (width + 7) / 8, (height + 7) / 8, 1);
        }
        memoryBarrier(cmd, kCompute, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT, kCompute, kStorageRead);
        m_marchTimes.write(cmd, 1, kAll);
        vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, m_resolve.handle());
        pushFrame(cmd, m_resolve, frame);
        Descriptors()
            .buffer(0, paramBuffer)
            .image(4, base, kGeneral, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE)
            .buffer(6, state)
            .buffer(8, result)
            .push(m_ctx, cmd, m_resolve);
        vkCmdDispatch(cmd, (outWidth + 7) / 8, (outHeight + 7) / 8, 1);
        memoryBarrier(cmd, kCompute, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT, kHostStage,
                      VK_ACCESS_2_HOST_READ_BIT);
        m_marchTimes.write(cmd, 2, kAll);
    });

    noise::Image image(camera.width, camera.height);
    const auto* rgba = static_cast<const glm::vec4*>(result.mapped());
    for (std::size_t i = 0; i < image.pixels.size(); ++i)
        image.pixels[i] = glm::vec3(rgba[i]);
    const auto* counted = static_cast<const std::uint32_t*>(loopCounts.mapped());
    if (stats) {
        const std::vector<double> first = m_binTimes.milliseconds();
        const std::vector<double> second = m_marchTimes.milliseconds();
        stats->passMs = {{"prepare", first[1] - first[0]},
                         {"bin", first[2] - first[1]},
                         {"mesh", first[3] - first[2]},
                         {"march", second[1] - second[0]},
                         {"resolve", second[2] - second[1]}};
        stats->totalMs = first[3] + second[2];
        stats->hostMs = hostMs;
        stats->loopBound = std::uint32_t(bound);
        stats->maxLoopIterations = counted[0];
        stats->stepsPerDispatch = perDispatch;
        stats->maxStepsPerDispatch = std::uint32_t(std::min<std::uint64_t>(fits, 0xffffffffu));
        stats->dispatches = dispatches;
        stats->supersample = n;
        stats->shellCells = records;
        stats->maxNeighbourhoodLobes = std::uint32_t(lobesPerStep);
        stats->maxNeighbourhoodImpulses = mostImpulses;
        stats->lobesPerImpulse = m_lobeCount;
        stats->longestProbe = std::uint32_t(shell.longestProbe);
        stats->walkCells = walk;
        stats->frameBytes = m_ctx.allocatedBytes() - allocatedBefore;
        stats->gpuMemoryBytes = m_ctx.peakAllocatedBytes();
    }
    if (capture) {
        capture->camera = camera;
        capture->params = params;
        capture->stepsPerDispatch = perDispatch;
        capture->table = shell.table;
        capture->cells = std::move(neighbourhoods);
        const auto* lobes = static_cast<const gpu::SpotWorldLobe*>(worldLobes.mapped());
        capture->lobes.assign(lobes, lobes + std::uint64_t(count) * m_lobeCount);
        const auto* box = static_cast<const SpotMarchBox*>(boxes.mapped());
        capture->boxes.assign(box, box + count);
        const auto* b = static_cast<const glm::vec4*>(baseCopy.mapped());
        capture->base.assign(b, b + pixels);
        const auto* dist = static_cast<const float*>(distanceCopy.mapped());
        capture->meshDistance.assign(dist, dist + pixels);
        capture->gpuLoops.assign(counted + 1, counted + 1 + pixels);
    }
    return image;
}

noise::Image raymarchOnCpu(const RaymarchCapture& capture, std::vector<std::uint32_t>* loops) {
    const std::uint32_t n = capture.params.range.z;
    const std::uint32_t steps = capture.params.counts.x;
    const std::uint32_t perDispatch = capture.stepsPerDispatch;
    SPOT_CHECK(n >= 1 && perDispatch >= 1);
    noise::Camera marchCamera = capture.camera;
    marchCamera.width *= int(n);
    marchCamera.height *= int(n);
    const SpotSplatFrame frame =
        makeSplatFrame(marchCamera, noise::Shading{}, glm::vec3(0.0f), 0, 0, 0.0f, 0, 0);
    const std::size_t width = std::size_t(marchCamera.width);
    const std::uint64_t pixels = std::uint64_t(width) * std::uint64_t(marchCamera.height);
    SPOT_CHECK_EQ(capture.base.size(), pixels);
    SPOT_CHECK_EQ(capture.meshDistance.size(), pixels);
    std::vector<glm::vec4> state(pixels);
    if (loops)
        loops->assign(pixels, 0u);
    const MarchTwin::Arrays arrays{&capture.params, capture.table.data(), capture.cells.data(),
                                   capture.lobes.data(), capture.boxes.data()};
    // raymarch_march.comp, every dispatch of it, one row band per thread.
    const auto rows = [&](int y0, int y1) {
        MarchTwin twin(arrays);
        for (int y = y0; y < y1; ++y)
            for (int x = 0; x < marchCamera.width; ++x) {
                // splatPixelRay's arithmetic, in float.
                const float px = float(x) + 0.5f, py = float(y) + 0.5f;
                const float sx = 2.0f * px / frame.size.x - 1.0f;
                const float sy = 1.0f - 2.0f * py / frame.size.y;
                glm::vec3 o, d;
                shared::f32::spotCameraRay(glm::vec3(frame.eye), glm::vec3(frame.forward),
                                           glm::vec3(frame.right) * frame.right.w,
                                           glm::vec3(frame.up) * frame.up.w, frame.eye.w > 0.5f, sx,
                                           sy, o, d);
                const std::size_t i = std::size_t(y) * width + std::size_t(x);
                glm::vec4 s(0.0f, 0.0f, 0.0f, 1.0f);
                std::uint32_t most = 0;
                for (std::uint32_t first = 0; first < steps; first += perDispatch) {
                    std::uint32_t count = 0;
                    s = twin.marchRay(o, d, capture.meshDistance[i], first,
                                      std::min(steps, first + perDispatch), s, count);
                    most = std::max(most, count);
                }
                state[i] = s;
                if (loops)
                    (*loops)[i] = most;
            }
    };
    const int threads = int(std::clamp(std::thread::hardware_concurrency(), 1u, 16u));
    std::vector<std::thread> workers;
    for (int t = 0; t < threads; ++t)
        workers.emplace_back(rows, marchCamera.height * t / threads,
                             marchCamera.height * (t + 1) / threads);
    for (std::thread& w : workers)
        w.join();
    // raymarch_resolve.comp.
    noise::Image image(capture.camera.width, capture.camera.height);
    for (int y = 0; y < image.height; ++y)
        for (int x = 0; x < image.width; ++x) {
            glm::vec3 sum(0.0f);
            for (std::uint32_t sy = 0; sy < n; ++sy)
                for (std::uint32_t sx = 0; sx < n; ++sx) {
                    const std::size_t i =
                        (std::size_t(y) * n + sy) * width + std::size_t(x) * n + sx;
                    sum += glm::vec3(state[i]) + state[i].w * glm::vec3(capture.base[i]);
                }
            image.pixels[std::size_t(y) * std::size_t(image.width) + std::size_t(x)] =
                sum / float(n * n);
        }
    return image;
}

} // namespace spot::splat
