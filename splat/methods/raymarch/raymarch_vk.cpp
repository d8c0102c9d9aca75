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
#include "noise/system.h"
#include "shaders/spot_shared.hpp"
#include "splat/layout.h"
#include "splat/pass_vk.h"

#include "raymarch_bin.comp.h"
#include "raymarch_march.comp.h"
#include "raymarch_resolve.comp.h"

namespace spot::shared::f32 {

using gpu::SpotWorldLobe;
using splat::gpu_march::kMarchEntryImpulse;
using splat::gpu_march::kMarchEntryLobeShift;
using splat::gpu_march::kMarchFar;
using splat::gpu_march::kMarchMaxSegments;
using splat::gpu_march::kMarchOpaque;
using splat::gpu_march::kMarchSub;
using splat::gpu_march::kMarchSubCells;
using splat::gpu_march::kMarchWalkBrick;
using splat::gpu_march::SpotMarchBox;
using splat::gpu_march::SpotMarchCell;
using splat::gpu_march::SpotMarchParams;
using splat::gpu_march::SpotMarchPush;

/// shaders/raymarch_shared.glsl compiled for the CPU: the march the GPU runs, as member functions
/// reading host arrays (the pattern of noise/generator_shared.h), with the pipeline's
/// specialization constants as members.
class MarchTwin {
public:
    struct Arrays {
        const SpotMarchParams* params = nullptr;
        const glm::ivec4* table = nullptr;
        const SpotMarchCell* cells = nullptr;
        const std::uint32_t* starts = nullptr;
        const std::uint32_t* list = nullptr;
        const SpotWorldLobe* lobes = nullptr;
        const SpotMarchBox* boxes = nullptr;
        const glm::uvec2* walkBits = nullptr; ///< null: the walk uses the hash table
        glm::vec4 light{0.0f};
        std::uint32_t lobeCount = 1;
        bool lambert = false, cull = true;
    };
    explicit MarchTwin(const Arrays& arrays)
        : m_a(arrays), kMarchLobes(arrays.lobeCount), kMarchLambert(arrays.lambert),
          kMarchCull(arrays.cull), kMarchWalkBits(arrays.walkBits != nullptr) {}

private:
    Arrays m_a;
    uint kMarchLobes;
    bool kMarchLambert;
    bool kMarchCull;
    bool kMarchWalkBits;
    const SpotMarchParams& marchParams() const { return *m_a.params; }
    glm::ivec4 marchSlot(uint i) const { return m_a.table[i]; }
    const SpotMarchCell& marchCell(uint record) const { return m_a.cells[record]; }
    uint marchStart(uint slot) const { return m_a.starts[slot]; }
    uint marchEntry(uint i) const { return m_a.list[i]; }
    glm::mat3 marchLobeMatrix(uint i) const {
        const SpotWorldLobe& w = m_a.lobes[i];
        return glm::mat3(glm::vec3(w.a0), glm::vec3(w.a1), glm::vec3(w.a2));
    }
    glm::vec3 marchLobeCentre(uint i) const {
        const SpotWorldLobe& w = m_a.lobes[i];
        return glm::vec3(w.a0.w, w.a1.w, w.a2.w);
    }
    glm::vec4 marchLobeColor(uint i) const { return m_a.lobes[i].color; }
    glm::vec4 marchLobeSlope(uint i) const { return m_a.lobes[i].a0; }
    glm::vec4 marchLobeAxis(uint i) const { return m_a.lobes[i].a1; }
    const SpotMarchBox& marchBox(uint impulse) const { return m_a.boxes[impulse]; }
    glm::vec4 marchLight() const { return m_a.light; }
    glm::uvec2 marchWalkBrick(glm::ivec3 b) const {
        const glm::ivec3 n =
            (glm::ivec3(m_a.params->hi) - glm::ivec3(m_a.params->lo) + kMarchWalkBrick) /
            kMarchWalkBrick;
        return m_a.walkBits[(b.x * n.y + b.y) * n.z + b.z];
    }

public:
#include "shaders/spot_member_begin.h"
#include "shaders/raymarch_shared.glsl"
#include "shaders/spot_member_end.h"
};

} // namespace spot::shared::f32

namespace spot::splat {

namespace {

using namespace gpu_march;
using gpu_splat::SpotSplatFrame;
using shared::f32::MarchTwin;

/// prepare.comp and raymarch_bin.comp run 64 impulses per workgroup; a dispatch has at most
/// 65,535 workgroups.
constexpr std::uint32_t kMaxImpulses = 65535u * 64u;
/// Hash table: at most half full; a longer probe than this doubles the table (the bound pays P
/// per lookup, so a short probe matters more than memory).
constexpr std::int32_t kWantedProbe = 8;
constexpr int kTableGrowths = 4;
constexpr VkBufferUsageFlags kStorage = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT;
constexpr Buffer::Memory kHost = Buffer::Memory::HostVisible;
constexpr Buffer::Memory kDevice = Buffer::Memory::DeviceLocal;
/// Bytes per march pixel: base colour, mesh distance, depth, state, loop count; per output pixel:
/// the result.
constexpr std::uint64_t kBytesPerMarchPixel = 16 + 4 + 4 + 16 + 4;
constexpr std::uint64_t kBytesPerPixel = 16;

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

double since(std::chrono::steady_clock::time_point start) {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
        .count();
}

/// The three slabs |a_i . (x - c)| < k that hold a lobe's support |A (x - c)| < k (a_i: row i of
/// A), as a conservative test of whether the support may reach a box: a flat or thin lobe tilted
/// across the axes reaches far fewer sub-cells than its axis-aligned box. The margin covers the
/// float arithmetic of the march's u = A (x - c) (about 1e-7 relative) many times over; a lobe
/// with a non-finite or zero matrix is never excluded.
struct Slabs {
    glm::dvec3 row[3];
    double centre[3]; ///< a_i . c
    double limit[3];  ///< k, plus the margin
    Slabs(const gpu::SpotWorldLobe& w, double k) {
        const glm::dvec3 c(w.a0.w, w.a1.w, w.a2.w);
        const double far = std::max({std::abs(c.x), std::abs(c.y), std::abs(c.z), 1.0});
        for (int i = 0; i < 3; ++i) {
            row[i] = glm::dvec3(w.a0[i], w.a1[i], w.a2[i]);
            centre[i] = glm::dot(row[i], c);
            const double norm = std::abs(row[i].x) + std::abs(row[i].y) + std::abs(row[i].z);
            limit[i] = 1.01 * k + 1e-4 * norm * far;
        }
    }
    /// Whether the support may reach the box of centre `b` and half sides `half` (world).
    bool mayReach(const glm::dvec3& b, const glm::dvec3& half) const {
        for (int i = 0; i < 3; ++i) {
            const double reach = limit[i] + std::abs(row[i].x) * half.x +
                                 std::abs(row[i].y) * half.y + std::abs(row[i].z) * half.z;
            if (std::abs(glm::dot(row[i], b) - centre[i]) > reach) // false for NaN: kept
                return false;
        }
        return true;
    }
};

/// floor(a / b) for b > 0.
int floorDiv(int a, int b) {
    return a >= 0 ? a / b : -((-a + b - 1) / b);
}

/// The walk reads bits per brick of the shell's bounding box up to this many bricks (16 MiB),
/// else the hash table.
constexpr std::uint64_t kMaxWalkBricks = std::uint64_t(1) << 21;

/// Grow-only with a margin, so a size creeping up does not reallocate every frame.
std::uint64_t grownSize(std::uint64_t need) {
    return std::max<std::uint64_t>(need + need / 4, 16);
}

} // namespace

std::uint64_t raymarchLoopBound(std::uint64_t steps, std::uint64_t walkCells,
                                std::uint64_t longestProbe, std::uint64_t listedImpulses,
                                std::uint64_t lobesPerImpulse) {
    // raymarch_shared.glsl: marchShell costs 1 + W (1 + marchFind), marchFind at most P + 2;
    // marchRay adds 1 + N (1 + (1 + S - 1) + marchFind + 1 + T (1 + 1 + L)).
    const std::uint64_t find = longestProbe + 2;
    const std::uint64_t walk = 1 + walkCells * (1 + find);
    const std::uint64_t perStep =
        1 + gpu_march::kMarchMaxSegments + find + 1 + listedImpulses * (2 + lobesPerImpulse);
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
    MarchTwin hasher(MarchTwin::Arrays{&none});
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
    // The old shell's table is freed only once the new one fits (a refused frame keeps it).
    const std::uint64_t tableBytes = shell->table.size() * sizeof(glm::ivec4);
    const std::uint64_t held = m_shell ? m_shell->tableBuffer.reservedBytes() : 0;
    if (m_ctx.allocatedBytes() - held + tableBytes > m_ctx.memoryBudget())
        throw InputError(cat("raymarch: the hash table of ", shell->cells.size(),
                             " shell cells needs ", tableBytes >> 20, " MiB of GPU memory; ",
                             (m_ctx.allocatedBytes() - held) >> 20,
                             " MiB are in use and the budget is ", m_ctx.memoryBudget() >> 20,
                             " MiB; reduce the cell count"));
    m_shell.reset();
    shell->tableBuffer =
        Buffer(m_ctx, tableBytes, kStorage, kHost,
               cat("ray march cell table (", shell->cells.size(), " shell cells)"));
    shell->tableBuffer.upload(std::span<const glm::ivec4>(shell->table));
    m_shell = std::move(shell);
    return *m_shell;
}

RaymarchRenderer::RaymarchRenderer(const SceneGpu& scene) : m_scene(scene), m_ctx(scene.context()) {
    requireFormat(m_ctx, kColorFormat,
                  VK_FORMAT_FEATURE_COLOR_ATTACHMENT_BIT | VK_FORMAT_FEATURE_STORAGE_IMAGE_BIT,
                  "stored RGBA32F targets");
    requireFormat(m_ctx, kScalarFormat,
                  VK_FORMAT_FEATURE_COLOR_ATTACHMENT_BIT | VK_FORMAT_FEATURE_STORAGE_IMAGE_BIT,
                  "stored R32F targets");
    requireFormat(m_ctx, kDepthFormat, VK_FORMAT_FEATURE_DEPTH_STENCIL_ATTACHMENT_BIT, "depth");
    // World lobes only (no screen outputs, no EWA: they depend on the impulses alone).
    m_prepare = makePreparePipeline(m_ctx, m_scene.lobeCount(), false, false, false);
    m_bin =
        makeComputePipeline(m_ctx, spirv(spv_raymarch_bin_comp),
                            {storageBuffer(kMarchBindParams), storageBuffer(kMarchBindTable),
                             storageBuffer(kMarchBindImpulses), storageBuffer(kMarchBindCount),
                             storageBuffer(kMarchBindBins), storageBuffer(kMarchBindWorldLobes),
                             storageBuffer(kMarchBindBoxes), storageBuffer(kMarchBindLobeBoxes)},
                            sizeof(std::uint32_t));
    m_params = Buffer(m_ctx, sizeof(SpotMarchParams), kStorage, kHost, "ray march parameters");
    m_prepareUnused =
        Buffer(m_ctx, 16, kStorage, kDevice, "ray march prepare: unused screen outputs");
}

RaymarchRenderer::~RaymarchRenderer() = default;

const RaymarchRenderer::Pipelines& RaymarchRenderer::pipelines(bool lambert, bool cull, bool count,
                                                               bool walkBits) {
    const auto key = std::make_tuple(lambert, cull, count, walkBits);
    if (const auto it = m_pipelines.find(key); it != m_pipelines.end())
        return it->second;
    Specialization spec;
    spec.set(kMarchSpecLobes, m_scene.lobeCount())
        .set(kMarchSpecLambert, lambert)
        .set(kMarchSpecCull, cull)
        .set(kMarchSpecCount, count)
        .set(kMarchSpecWalkBits, walkBits);
    const std::uint32_t push = sizeof(SpotMarchPush);
    Pipelines p;
    p.march =
        makeComputePipeline(m_ctx, spirv(spv_raymarch_march_comp),
                            {storageBuffer(kMarchBindParams), storageBuffer(kMarchBindTable),
                             storageBuffer(kMarchBindCells), storageBuffer(kMarchBindStarts),
                             storageBuffer(kMarchBindList), storageBuffer(kMarchBindWorldLobes),
                             storageBuffer(kMarchBindBoxes), storageImage(kMarchBindMeshDistance),
                             storageBuffer(kMarchBindState), storageBuffer(kMarchBindLoops),
                             storageBuffer(kMarchBindWalkBits)},
                            push, spec);
    p.resolve = makeComputePipeline(m_ctx, spirv(spv_raymarch_resolve_comp),
                                    {storageImage(kMarchBindBase), storageBuffer(kMarchBindState),
                                     storageImage(kMarchBindResult)},
                                    push, spec);
    return m_pipelines.emplace(key, std::move(p)).first->second;
}

void RaymarchRenderer::ensureImpulseBuffers(std::uint32_t capacity) {
    if (capacity <= m_capacity && m_worldLobes.handle())
        return;
    const std::uint32_t grown = std::max(
        capacity, std::uint32_t(std::min<std::uint64_t>(kMaxImpulses, capacity + capacity / 4)));
    const std::uint64_t n = std::max<std::uint32_t>(grown, 1);
    // Twice: a lit frame's colour changes follow the world lobes (spot_layout.h).
    const std::uint64_t lobeBytes = 2 * n * m_scene.lobeCount() * sizeof(gpu::SpotWorldLobe);
    const std::uint64_t need = lobeBytes + n * (1 + m_scene.lobeCount()) * sizeof(SpotMarchBox);
    const std::uint64_t held =
        m_worldLobes.reservedBytes() + m_boxes.reservedBytes() + m_lobeBoxes.reservedBytes();
    if (m_ctx.allocatedBytes() - held + need > m_ctx.memoryBudget())
        throw InputError(cat("raymarch: ", capacity, " kernels need ", need >> 20,
                             " MiB of GPU memory; ", (m_ctx.allocatedBytes() - held) >> 20,
                             " MiB are in use and the budget is ", m_ctx.memoryBudget() >> 20,
                             " MiB; reduce the kernel count"));
    m_worldLobes = Buffer();
    m_boxes = Buffer();
    m_lobeBoxes = Buffer();
    m_capacity = 0;
    // Host-visible: the host reads the world lobes and boxes for the lists.
    m_worldLobes = Buffer(m_ctx, lobeBytes, kStorage, kHost,
                          cat("ray march world lobes (", grown, " kernels)"));
    m_boxes = Buffer(m_ctx, n * sizeof(SpotMarchBox), kStorage, kHost,
                     cat("ray march impulse boxes (", grown, " kernels)"));
    m_lobeBoxes = Buffer(m_ctx, n * m_scene.lobeCount() * sizeof(SpotMarchBox), kStorage, kHost,
                         cat("ray march lobe boxes (", grown, " kernels)"));
    m_capacity = grown;
}

void RaymarchRenderer::ensureTargets(std::uint32_t outWidth, std::uint32_t outHeight,
                                     std::uint32_t n) {
    if (m_width == outWidth && m_height == outHeight && m_n == n && m_result.handle())
        return;
    const std::uint64_t width = std::uint64_t(outWidth) * n, height = std::uint64_t(outHeight) * n;
    const std::uint64_t need = width * height * kBytesPerMarchPixel + 4 +
                               std::uint64_t(outWidth) * outHeight * kBytesPerPixel;
    // What the device cannot hold is refused before the old targets are freed, like the budget.
    const VkPhysicalDeviceLimits& limits = m_ctx.properties().limits;
    if (width > limits.maxImageDimension2D || height > limits.maxImageDimension2D)
        throw InputError(cat("raymarch: a ", outWidth, "x", outHeight, " frame with ", n, "x", n,
                             " rays per pixel marches ", width, "x", height,
                             " rays, more than this device's ", limits.maxImageDimension2D,
                             " per side; reduce the image size or the supersampling"));
    if (width * height * sizeof(glm::vec4) > limits.maxStorageBufferRange)
        throw InputError(cat("raymarch: the march state of ", width, "x", height, " rays needs ",
                             (width * height * sizeof(glm::vec4)) >> 20,
                             " MiB in one storage buffer, more than this device's limit of ",
                             limits.maxStorageBufferRange >> 20,
                             " MiB; reduce the image size or the supersampling"));
    std::uint64_t held = m_state.reservedBytes() + m_loops.reservedBytes();
    for (const Image* i : {&m_base, &m_distance, &m_depth, &m_result})
        held += i->reservedBytes();
    // Checked as if the old targets were freed; a refused frame keeps them.
    if (m_ctx.allocatedBytes() - held + need > m_ctx.memoryBudget())
        throw InputError(
            cat("raymarch: a ", outWidth, "x", outHeight, " frame (", n, "x", n,
                " rays per pixel) needs ", need >> 20, " MiB of GPU memory for its targets; ",
                (m_ctx.allocatedBytes() - held) >> 20, " MiB are in use and the budget is ",
                m_ctx.memoryBudget() >> 20, " MiB; reduce the image size or the supersampling"));
    m_base = Image();
    m_distance = Image();
    m_depth = Image();
    m_result = Image();
    m_state = Buffer();
    m_loops = Buffer();
    m_width = m_height = m_n = 0;
    const std::uint32_t w = std::uint32_t(width), h = std::uint32_t(height);
    // The capture copies the base colour and mesh distance out.
    constexpr VkImageUsageFlags kTarget = VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT |
                                          VK_IMAGE_USAGE_STORAGE_BIT |
                                          VK_IMAGE_USAGE_TRANSFER_SRC_BIT;
    constexpr VkImageAspectFlags kColor = VK_IMAGE_ASPECT_COLOR_BIT;
    m_base = Image(m_ctx, w, h, kColorFormat, kTarget, kColor, "ray march base colour");
    m_distance = Image(m_ctx, w, h, kScalarFormat, kTarget, kColor, "ray march mesh distance");
    m_depth = Image(m_ctx, w, h, kDepthFormat, VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT,
                    VK_IMAGE_ASPECT_DEPTH_BIT, "ray march depth");
    m_result = Image(m_ctx, outWidth, outHeight, kColorFormat,
                     VK_IMAGE_USAGE_STORAGE_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT, kColor,
                     "ray march result");
    m_state = Buffer(m_ctx, width * height * sizeof(glm::vec4), kStorage, kDevice,
                     "ray march state (radiance, transmittance)");
    m_loops = Buffer(m_ctx, (width * height + 1) * sizeof(std::uint32_t),
                     kStorage | VK_BUFFER_USAGE_TRANSFER_DST_BIT, kHost, "ray march loop counts");
    m_width = outWidth;
    m_height = outHeight;
    m_n = n;
}

/// What bin() builds on the host for the march (raymarch_vk.h's file comment), and the bins it
/// builds it from.
struct RaymarchRenderer::Lists {
    // The bin pass's output, read back: per shell cell its impulses [first, end) and their count.
    const std::uint32_t* binFirst = nullptr;
    const std::uint32_t* binEnd = nullptr;
    const std::uint32_t* binCount = nullptr;
    std::uint32_t count = 0; ///< impulses binned
    /// Each record's 27 neighbours (-1 outside the shell), in (di, dj, dk) order.
    std::vector<std::int32_t> neighbours;
    std::vector<SpotMarchCell> cells; ///< head.x: impulses around; head.y: listed
    std::uint32_t mostAround = 0;
    /// The lists: slot q's entries are list[starts[q], starts[q + 1]) (a slot per sub-cell with
    /// culling, per cell without).
    std::vector<std::uint32_t> starts, list;
};

void RaymarchRenderer::bin(const ImpulseSet& impulses, const noise::Camera& marchCamera,
                           bool cull) {
    m_version = 0; // until the lists are done
    const auto hostStart = std::chrono::steady_clock::now();
    const Shell& shell = shellFor(*impulses.cells);
    const std::uint32_t records = std::uint32_t(shell.cells.size());
    const std::uint32_t lobes = m_scene.lobeCount();
    ensureImpulseBuffers(impulses.capacity);
    SpotMarchParams params = shell.params();
    params.grid.z = m_scene.support();
    params.counts.y = lobes;
    const double binMs = binOnGpu(impulses, shell, marchCamera, params);
    Lists lists = checkBins(impulses, shell);
    findNeighbours(shell, params, lists);
    if (cull)
        listCulled(shell, params, lists);
    else
        listEveryImpulse(shell, lists);
    std::uint32_t longest = 0;
    for (std::size_t q = 0; q + 1 < lists.starts.size(); ++q)
        longest = std::max(longest, lists.starts[q + 1] - lists.starts[q]);
    uploadLists(shell, lists);

    RaymarchStats& s = m_binStats;
    s = RaymarchStats{};
    s.shellCells = records;
    s.maxNeighbourhoodImpulses = lists.mostAround;
    s.maxListedImpulses = longest;
    s.lobesPerImpulse = lobes;
    s.longestProbe = std::uint32_t(shell.longestProbe);
    s.walkCells = shell.walkCells();
    s.listEntries = lists.list.size();
    s.impulses = lists.count;
    s.binMs = binMs;
    s.binHostMs = since(hostStart);
    m_version = impulses.version;
    m_listsCulled = cull;
    m_listedCells = impulses.cells;
}

double RaymarchRenderer::binOnGpu(const ImpulseSet& impulses, const Shell& shell,
                                  const noise::Camera& marchCamera, const SpotMarchParams& params) {
    const std::uint32_t records = std::uint32_t(shell.cells.size());
    const std::uint32_t capacity = impulses.capacity;
    const std::uint32_t lobes = m_scene.lobeCount();
    const std::uint64_t binBytes = (3 * std::uint64_t(records) + 2) * sizeof(std::uint32_t);
    if (m_bins.size() < binBytes) {
        const std::uint64_t held = m_bins.reservedBytes();
        if (m_ctx.allocatedBytes() - held + grownSize(binBytes) > m_ctx.memoryBudget())
            throw InputError(cat("raymarch: the bins of ", records, " shell cells need ",
                                 binBytes >> 20, " MiB of GPU memory; the budget is ",
                                 m_ctx.memoryBudget() >> 20, " MiB"));
        m_bins = Buffer();
        m_bins = Buffer(m_ctx, grownSize(binBytes), kStorage | VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                        kHost, cat("ray march cell bins (", records, " shell cells)"));
    }
    m_params.upload(&params, sizeof(params));

    // World lobes, boxes and bins on the GPU, waited for.
    const SpotSplatFrame frame = makeSplatFrame(marchCamera, noise::Shading{}, glm::vec3(0.0f),
                                                capacity, lobes, m_scene.support(), 0, 0);
    Timestamps times(m_ctx, 2);
    m_ctx.submitAndWait([&](VkCommandBuffer cmd) {
        using namespace passes;
        times.reset(cmd);
        times.write(cmd, 0, kAll);
        PrepareBuffers pb;
        pb.impulses = impulses.impulses;
        pb.count = impulses.count;
        pb.lobes = &m_scene.lobes();
        pb.worldLobes = &m_worldLobes;
        pb.screenLobes = &m_prepareUnused;
        pb.bounds = &m_prepareUnused;
        recordPrepare(m_ctx, cmd, m_prepare, frame, pb, capacity);
        const std::uint64_t firstBytes = std::uint64_t(records) * sizeof(std::uint32_t);
        if (records > 0)
            vkCmdFillBuffer(cmd, m_bins.handle(), 0, firstBytes, 0xffffffffu);
        vkCmdFillBuffer(cmd, m_bins.handle(), firstBytes, binBytes - firstBytes, 0u);
        // The bins are cleared and the world lobes (prepare) written before the bin pass.
        memoryBarrier(cmd, VK_PIPELINE_STAGE_2_CLEAR_BIT | kCompute,
                      VK_ACCESS_2_TRANSFER_WRITE_BIT | VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT,
                      kCompute, kStorageRW);
        if (capacity > 0) {
            vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, m_bin.handle());
            vkCmdPushConstants(cmd, m_bin.layout(), VK_SHADER_STAGE_COMPUTE_BIT, 0, sizeof(records),
                               &records);
            Descriptors()
                .buffer(kMarchBindParams, m_params)
                .buffer(kMarchBindTable, shell.tableBuffer)
                .buffer(kMarchBindImpulses, *impulses.impulses)
                .buffer(kMarchBindCount, *impulses.count)
                .buffer(kMarchBindBins, m_bins)
                .buffer(kMarchBindWorldLobes, m_worldLobes)
                .buffer(kMarchBindBoxes, m_boxes)
                .buffer(kMarchBindLobeBoxes, m_lobeBoxes)
                .push(m_ctx, cmd, m_bin);
            vkCmdDispatch(cmd, (capacity + 63) / 64, 1, 1);
        }
        memoryBarrier(cmd, kCompute | VK_PIPELINE_STAGE_2_CLEAR_BIT,
                      VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT | VK_ACCESS_2_TRANSFER_WRITE_BIT,
                      kHostStage, VK_ACCESS_2_HOST_READ_BIT);
        times.write(cmd, 1, kAll);
    });
    return times.milliseconds()[1];
}

RaymarchRenderer::Lists RaymarchRenderer::checkBins(const ImpulseSet& impulses,
                                                    const Shell& shell) const {
    // On the host: check the impulse order (each cell's impulses contiguous, in cell order).
    const noise::SurfaceCells& surface = *impulses.cells;
    const std::uint32_t records = std::uint32_t(shell.cells.size());
    const std::uint32_t capacity = impulses.capacity;
    const auto* bin = static_cast<const std::uint32_t*>(m_bins.mapped());
    Lists lists;
    lists.binFirst = bin;
    lists.binEnd = bin + records;
    lists.binCount = bin + 2 * std::uint64_t(records);
    const std::uint32_t* binFirst = lists.binFirst;
    const std::uint32_t* binEnd = lists.binEnd;
    const std::uint32_t* binCount = lists.binCount;
    const std::uint32_t count = bin[3 * std::uint64_t(records) + 1];
    if (count > capacity)
        throw InputError(cat("raymarch: the impulse count ", count, " exceeds the capacity ",
                             capacity, " the impulses came with"));
    if (const std::uint32_t outside = bin[3 * std::uint64_t(records)]; outside > 0)
        throw InputError(cat("raymarch: ", outside, " of ", count,
                             " impulses lie outside the given surface cells (cell size ",
                             surface.cellSize,
                             "); render impulses with the cells that generated them"));
    std::uint32_t expected = 0;
    for (std::uint32_t r = 0; r < records; ++r) {
        if (binCount[r] == 0)
            continue;
        if (!shell.surface[r])
            throw InputError(cat("raymarch: ", binCount[r], " impulses lie in cell ",
                                 shell.cells[r].x, " ", shell.cells[r].y, " ", shell.cells[r].z,
                                 ", which is not one of the given surface cells (cell size ",
                                 surface.cellSize,
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
    lists.count = count;
    return lists;
}

void RaymarchRenderer::findNeighbours(const Shell& shell, const SpotMarchParams& params,
                                      Lists& lists) const {
    // Each record's 27 neighbours (-1 outside the shell), in (di, dj, dk) order: cell order, so
    // their impulses come in impulse order.
    const std::uint32_t records = std::uint32_t(shell.cells.size());
    requireMemory(std::uint64_t(records) * (27 * 4 + 16 + kMarchSubCells * 8),
                  cat("the ray march's lists of ", records, " shell cells"));
    lists.neighbours.assign(std::size_t(records) * 27, 0);
    lists.cells.assign(records, SpotMarchCell{});
    MarchTwin find(MarchTwin::Arrays{&params, shell.table.data()});
    for (std::uint32_t r = 0; r < records; ++r) {
        std::uint32_t around = 0;
        for (int n = 0; n < 27; ++n) {
            std::uint32_t loops = 0;
            const int found = find.marchFind(
                shell.cells[r] + glm::ivec3(n / 9 - 1, n / 3 % 3 - 1, n % 3 - 1), loops);
            lists.neighbours[std::size_t(r) * 27 + std::size_t(n)] = found;
            if (found >= 0)
                around += lists.binCount[found];
        }
        lists.cells[r].head = glm::uvec4(around, 0u, 0u, 0u);
        lists.mostAround = std::max(lists.mostAround, around);
    }
}

void RaymarchRenderer::listEveryImpulse(const Shell& shell, Lists& lists) const {
    // The paper's baseline: every sub-cell of a cell lists all its 27 neighbours' impulses, with
    // all their lobes; a list per cell.
    const std::uint32_t records = std::uint32_t(shell.cells.size());
    const std::uint32_t allLobes = (1u << m_scene.lobeCount()) - 1u;
    std::vector<std::uint32_t>& starts = lists.starts;
    std::vector<std::uint32_t>& list = lists.list;
    starts.assign(std::size_t(records) + 1, 0u);
    std::uint64_t total = 0;
    for (std::uint32_t r = 0; r < records; ++r)
        total += lists.cells[r].head.x;
    requireMemory(total * 4, cat("the ray march's lists (", total, " entries)"));
    list.reserve(total);
    for (std::uint32_t r = 0; r < records; ++r) {
        const std::uint32_t first = std::uint32_t(list.size());
        starts[r] = first;
        for (int n = 0; n < 27; ++n)
            if (const int nb = lists.neighbours[std::size_t(r) * 27 + std::size_t(n)];
                nb >= 0 && lists.binCount[nb] > 0)
                for (std::uint32_t i = lists.binFirst[nb]; i < lists.binEnd[nb]; ++i)
                    list.push_back(i | allLobes << kMarchEntryLobeShift);
        lists.cells[r].head.y = std::uint32_t(list.size()) - first;
    }
    starts[records] = std::uint32_t(list.size());
}

void RaymarchRenderer::listCulled(const Shell& shell, const SpotMarchParams& params,
                                  Lists& lists) const {
    // Each impulse goes to the sub-cells its box reaches within its cell's 27 neighbours, with a
    // margin of 1/1000 of a sub-cell (and the float rounding of large coordinates) for the
    // shader's floor(x / (h / kMarchSub)), so a sample a hair past a sub-cell's side still finds
    // every impulse whose box holds it.
    const std::uint32_t records = std::uint32_t(shell.cells.size());
    const std::uint32_t lobes = m_scene.lobeCount();
    const std::size_t slots = std::size_t(records) * kMarchSubCells;
    const auto* boxes = static_cast<const SpotMarchBox*>(m_boxes.mapped());
    const auto* lobeBoxes = static_cast<const SpotMarchBox*>(m_lobeBoxes.mapped());
    const auto* worldLobes = static_cast<const gpu::SpotWorldLobe*>(m_worldLobes.mapped());
    const double scale = double(params.grid.y * float(kMarchSub));
    const double k = double(m_scene.support());
    // A sub-cell as the slab test sees it: its centre and half side, grown by the margin of
    // `reach` (1/1000 of a sub-cell, and the rounding of large coordinates below).
    const double subSize = 1.0 / scale;
    const glm::dvec3 subHalf(0.5 * subSize);
    const glm::dvec3 subReach(0.5 * subSize * 1.002);
    const int sub = int(kMarchSub);
    // The sub-cells a box reaches, clamped to [first, last] per axis (hi < lo: none).
    const auto reach = [&](const SpotMarchBox& box, glm::ivec3 first, glm::ivec3 last,
                           glm::ivec3& lo, glm::ivec3& hi) {
        for (int a = 0; a < 3; ++a) {
            const double l = double(box.lo[a]) * scale;
            const double h = double(box.hi[a]) * scale;
            lo[a] = int(std::clamp(std::floor(l - 1e-3 - 1e-6 * std::abs(l)), double(first[a]),
                                   double(last[a])));
            hi[a] = int(std::clamp(std::floor(h + 1e-3 + 1e-6 * std::abs(h)), double(first[a]),
                                   double(last[a])));
            if (!(l <= h)) // empty (no lobe with density) or not a number
                hi[a] = lo[a] - 1;
        }
    };
    std::vector<std::pair<std::uint32_t, std::uint32_t>> pairs; // (slot, entry)
    std::vector<std::uint32_t> masks; // per sub-cell of one impulse's box: its lobes there
    for (std::uint32_t r = 0; r < records; ++r) {
        if (lists.binCount[r] == 0)
            continue;
        const glm::ivec3 c = shell.cells[r];
        const glm::ivec3 first = (c - 1) * sub, last = (c + 2) * sub - 1;
        for (std::uint32_t i = lists.binFirst[r]; i < lists.binEnd[r]; ++i) {
            glm::ivec3 lo, hi;
            reach(boxes[i], first, last, lo, hi);
            if (hi.x < lo.x || hi.y < lo.y || hi.z < lo.z)
                continue;
            const glm::ivec3 size = hi - lo + 1;
            masks.assign(std::size_t(size.x) * size.y * size.z, 0u);
            for (std::uint32_t l = 0; l < lobes; ++l) {
                glm::ivec3 a, b;
                reach(lobeBoxes[std::size_t(i) * lobes + l], lo, hi, a, b);
                const Slabs slabs(worldLobes[std::size_t(i) * lobes + l], k);
                for (int x = a.x; x <= b.x; ++x)
                    for (int y = a.y; y <= b.y; ++y)
                        for (int z = a.z; z <= b.z; ++z)
                            if (slabs.mayReach(glm::dvec3(x, y, z) * subSize + subHalf, subReach))
                                masks[(std::size_t(x - lo.x) * size.y + std::size_t(y - lo.y)) *
                                          size.z +
                                      std::size_t(z - lo.z)] |= 1u << l;
            }
            std::size_t m = 0;
            for (int x = lo.x; x <= hi.x; ++x)
                for (int y = lo.y; y <= hi.y; ++y)
                    for (int z = lo.z; z <= hi.z; ++z, ++m) {
                        if (masks[m] == 0)
                            continue;
                        const glm::ivec3 q(floorDiv(x, sub), floorDiv(y, sub), floorDiv(z, sub));
                        const glm::ivec3 d = q - c + 1;
                        const int nb = lists.neighbours[std::size_t(r) * 27 +
                                                        std::size_t(d.x * 9 + d.y * 3 + d.z)];
                        SPOT_CHECK_LE(0, nb);
                        const glm::ivec3 local = glm::ivec3(x, y, z) - q * sub;
                        pairs.emplace_back(
                            std::uint32_t(nb) * kMarchSubCells +
                                std::uint32_t((local.x * sub + local.y) * sub + local.z),
                            i | masks[m] << kMarchEntryLobeShift);
                    }
        }
    }
    // Counting sort by slot, stable: each list in impulse order.
    std::vector<std::uint32_t>& starts = lists.starts;
    std::vector<std::uint32_t>& list = lists.list;
    starts.assign(slots + 1, 0u);
    for (const auto& pair : pairs)
        ++starts[pair.first + 1];
    for (std::size_t q = 0; q < slots; ++q)
        starts[q + 1] += starts[q];
    list.resize(pairs.size());
    std::vector<std::uint32_t> fill(starts.begin(), starts.end() - 1);
    for (const auto& [slot, entry] : pairs)
        list[fill[slot]++] = entry;
    for (std::uint32_t r = 0; r < records; ++r)
        lists.cells[r].head.y =
            starts[std::size_t(r + 1) * kMarchSubCells] - starts[std::size_t(r) * kMarchSubCells];
}

std::vector<glm::uvec2> RaymarchRenderer::walkBits(const Shell& shell, const Lists& lists) const {
    // The walk's bits: per brick of the shell's bounding box, the cells a segment may pass (shell
    // cells with impulses around them), when the box is small enough (else the walk looks cells
    // up in the hash table: memory never grows without bound with the volume).
    const std::uint32_t records = std::uint32_t(shell.cells.size());
    std::vector<glm::uvec2> bits;
    const glm::ivec3 extent = glm::max(shell.hi - shell.lo + 1, glm::ivec3(0));
    const glm::u64vec3 bricks = glm::u64vec3((extent + kMarchWalkBrick - 1) / kMarchWalkBrick);
    if (records > 0 && bricks.x * bricks.y * bricks.z <= kMaxWalkBricks) {
        bits.assign(std::size_t(bricks.x * bricks.y * bricks.z), glm::uvec2(0u));
        for (std::uint32_t r = 0; r < records; ++r)
            if (lists.cells[r].head.x > 0) {
                const glm::ivec3 q = shell.cells[r] - shell.lo;
                const glm::u64vec3 b = glm::u64vec3(q / kMarchWalkBrick);
                const glm::ivec3 l = q - glm::ivec3(b) * kMarchWalkBrick;
                const int bit = (l.x * kMarchWalkBrick + l.y) * kMarchWalkBrick + l.z;
                bits[std::size_t((b.x * bricks.y + b.y) * bricks.z + b.z)][bit / 32] |=
                    1u << (bit % 32);
            }
    }
    return bits;
}

void RaymarchRenderer::uploadLists(const Shell& shell, const Lists& lists) {
    // Upload into the grow-only buffers (each checked against the budget before anything is
    // freed, so a refused frame leaves the old ones).
    const std::uint32_t records = std::uint32_t(shell.cells.size());
    std::vector<glm::uvec2> bits = walkBits(shell, lists);
    const std::uint64_t cellBytes = std::uint64_t(records) * sizeof(SpotMarchCell);
    const std::uint64_t startBytes = lists.starts.size() * sizeof(std::uint32_t);
    const std::uint64_t listBytes = lists.list.size() * sizeof(std::uint32_t);
    const std::uint64_t bitBytes = bits.size() * sizeof(glm::uvec2);
    std::uint64_t held = 0, need = 0;
    for (const auto& [buffer, bytes] : {std::pair<Buffer*, std::uint64_t>{&m_cells, cellBytes},
                                        {&m_starts, startBytes},
                                        {&m_list, listBytes},
                                        {&m_walkBits, bitBytes}})
        if (buffer->size() < bytes || !buffer->handle()) {
            held += buffer->reservedBytes();
            need += grownSize(bytes);
            if (grownSize(bytes) > m_ctx.properties().limits.maxStorageBufferRange)
                throw InputError(cat("raymarch: the impulse lists of ", records, " shell cells (",
                                     lists.list.size(), " entries) need ", grownSize(bytes) >> 20,
                                     " MiB in one storage buffer, more than this device's limit "
                                     "of ",
                                     m_ctx.properties().limits.maxStorageBufferRange >> 20,
                                     " MiB; reduce the kernel density or the cell count"));
        }
    if (need > 0 && m_ctx.allocatedBytes() - held + need > m_ctx.memoryBudget())
        throw InputError(cat("raymarch: the impulse lists of ", records, " shell cells (",
                             lists.list.size(), " entries) need ", need >> 20,
                             " MiB of GPU memory; ", (m_ctx.allocatedBytes() - held) >> 20,
                             " MiB are in use and the budget is ", m_ctx.memoryBudget() >> 20,
                             " MiB; reduce the kernel density or the cell count"));
    const auto put = [&](Buffer& buffer, const void* data, std::uint64_t bytes, const char* what) {
        if (buffer.size() < bytes || !buffer.handle()) {
            buffer = Buffer();
            buffer = Buffer(m_ctx, grownSize(bytes), kStorage, kHost, what);
        }
        if (bytes > 0)
            buffer.upload(data, bytes);
    };
    put(m_cells, lists.cells.data(), cellBytes, "ray march shell cells");
    put(m_starts, lists.starts.data(), startBytes, "ray march list starts");
    put(m_list, lists.list.data(), listBytes, "ray march impulse lists");
    put(m_walkBits, bits.data(), bitBytes, "ray march walk bits");
    m_walkBitData = std::move(bits);
}

void RaymarchRenderer::prepare(const View& view, const ImpulseSet& impulses,
                               const RenderSettings& settings) {
    if (settings.steps < 1 || settings.steps > kRaymarchMaxSteps)
        throw InputError(
            cat("raymarch: --steps ", settings.steps, " is outside [1, ", kRaymarchMaxSteps, "]"));
    if (settings.supersample < 1 || settings.supersample > kRaymarchMaxSupersample)
        throw InputError(cat("raymarch: --supersample ", settings.supersample, " is outside [1, ",
                             kRaymarchMaxSupersample, "]"));
    const std::uint32_t n = std::uint32_t(settings.supersample);
    static_cast<void>(noise::CameraRays(view.camera)); // validates the camera first (InputError)
    // The march renders the n x n supersampled image: the same view, n times the pixels a side.
    noise::Camera marchCamera = view.camera;
    marchCamera.width = int(std::min<std::int64_t>(std::int64_t(view.camera.width) * n, 1 << 30));
    marchCamera.height = int(std::min<std::int64_t>(std::int64_t(view.camera.height) * n, 1 << 30));
    impulses.require("raymarch", kMaxImpulses, "place");
    if (!impulses.cells)
        throw InputError("raymarch: the impulses came without their surface cells (the shell)");
    if (!(impulses.cells->cellSize > 0.0f) || !std::isfinite(impulses.cells->cellSize))
        throw InputError(
            cat("raymarch: cell size ", impulses.cells->cellSize, " must be positive"));

    Prepared& f = m_frame;
    f.binned = false;
    const bool cull = settings.cullImpulses;
    if (impulses.version == 0 || impulses.version != m_version || cull != m_listsCulled ||
        impulses.cells != m_listedCells) {
        bin(impulses, marchCamera, cull);
        f.binned = true;
    }

    // The guard: split the march over dispatches of at most `perDispatch` steps, each within the
    // loop budget; refuse a frame where not even one step fits.
    const RaymarchStats& b = m_binStats;
    const std::uint32_t budget =
        settings.loopBudget > 0 ? settings.loopBudget : kRaymarchLoopBudget;
    const auto loopBound = [&](std::uint64_t steps) {
        return raymarchLoopBound(steps, b.walkCells, b.longestProbe, b.maxListedImpulses,
                                 b.lobesPerImpulse);
    };
    const std::uint64_t fixed = loopBound(0);
    const std::uint64_t perStep = loopBound(1) - fixed;
    const std::uint64_t fits = budget > fixed ? (budget - fixed) / perStep : 0;
    if (fits == 0) {
        const Shell& shell = *m_shell;
        throw InputError(cat(
            "raymarch: even one step would need up to ", withCommas(fixed + perStep),
            " loop iterations in one shader invocation (",
            withCommas(std::uint64_t(b.maxListedImpulses) * b.lobesPerImpulse),
            " lobes summed at each step in the longest list, ", withCommas(fixed),
            " to walk the shell's ", shell.hi.x - shell.lo.x + 1, "x", shell.hi.y - shell.lo.y + 1,
            "x", shell.hi.z - shell.lo.z + 1, " cells) and the budget is ", withCommas(budget),
            " (lavapipe stops at ", withCommas(kMarchLavapipeLoopLimit),
            " without an error); lower the kernel density or the cell count"));
    }
    // As few dispatches as fit, with the steps spread evenly over them.
    const std::uint32_t steps = std::uint32_t(settings.steps);
    f.dispatches = std::uint32_t((steps + fits - 1) / fits);
    f.stepsPerDispatch = (steps + f.dispatches - 1) / f.dispatches;
    f.maxStepsPerDispatch = std::uint32_t(std::min<std::uint64_t>(fits, 0xffffffffu));
    f.loopBound = loopBound(f.stepsPerDispatch);

    ensureTargets(std::uint32_t(view.camera.width), std::uint32_t(view.camera.height), n);

    f.lambert = view.shading.mode == noise::Shading::Mode::Lambert;
    f.cull = cull;
    f.count = m_countLoops;
    f.walkBits = !m_walkBitData.empty() && !m_walkByHash;
    f.pipelines = &pipelines(f.lambert, f.cull, f.count, f.walkBits);
    f.camera = view.camera;
    f.background = view.background;
    f.meshFrame = makeSplatFrame(marchCamera, view.shading, view.baseColor, 0, m_scene.lobeCount(),
                                 m_scene.support(), 0, 0);
    SpotMarchPush& p = f.push;
    p.eye = f.meshFrame.eye;
    p.forward = f.meshFrame.forward;
    p.right = f.meshFrame.right;
    p.up = f.meshFrame.up;
    p.size = glm::vec4(glm::vec2(f.meshFrame.size), 0.0f, 0.0f);
    p.light = glm::vec4(view.shading.lightDir, view.shading.ambient);
    p.range = glm::uvec4(0u, 0u, steps, n);
    f.lit = view.shading.mode == noise::Shading::Mode::Lit;
    f.impulses = impulses;
    if (f.lit) {
        if (!m_light)
            m_light = std::make_unique<LightSpace>(m_scene);
        m_light->prepare(view.shading, impulses);
        if (!m_prepareLit.handle())
            m_prepareLit = makePreparePipeline(m_ctx, m_scene.lobeCount(), false, false, false,
                                               true, false, true);
        f.prepareFrame = makeSplatFrame(marchCamera, view.shading, view.baseColor,
                                        impulses.capacity, m_scene.lobeCount(), m_scene.support(),
                                        0, 0);
    }
    // Where the lit prepare writes the colour changes, for the march (0: unlit, none).
    static_cast<SpotMarchParams*>(m_params.mapped())->counts.x =
        f.lit ? impulses.capacity * m_scene.lobeCount() : 0u;
}

void RaymarchRenderer::record(VkCommandBuffer cmd, PassTimer& timer) {
    using namespace passes;
    const Prepared& f = m_frame;
    const std::uint32_t width = m_width * m_n, height = m_height * m_n;

    // A lit frame: the light-space structure, then every world lobe's lit colour (its geometry
    // is the bins' own, unchanged).
    if (f.lit && f.impulses.capacity > 0) {
        m_light->record(cmd, timer);
        memoryBarrier(cmd, kCompute, kStorageRead, kCompute, kStorageRW);
        PrepareBuffers pb;
        pb.impulses = f.impulses.impulses;
        pb.count = f.impulses.count;
        pb.lobes = &m_scene.lobes();
        pb.worldLobes = &m_worldLobes;
        pb.screenLobes = &m_prepareUnused;
        pb.bounds = &m_prepareUnused;
        pb.light = m_light.get();
        recordPrepare(m_ctx, cmd, m_prepareLit, f.prepareFrame, pb, f.impulses.capacity);
        memoryBarrier(cmd, kCompute, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT, kCompute, kStorageRead);
        timer.mark(cmd, "prepare");
    }

    // The base mesh at the march's resolution.
    for (const Image* image : {&m_base, &m_distance})
        transitionImage(cmd, image->handle(), kColorAspect, VK_IMAGE_LAYOUT_UNDEFINED, kAttachment,
                        VK_PIPELINE_STAGE_2_NONE, 0, kColorOut, kColorRW);
    transitionImage(cmd, m_depth.handle(), VK_IMAGE_ASPECT_DEPTH_BIT, VK_IMAGE_LAYOUT_UNDEFINED,
                    VK_IMAGE_LAYOUT_DEPTH_ATTACHMENT_OPTIMAL, VK_PIPELINE_STAGE_2_NONE, 0, kTests,
                    kDepthRW);
    m_scene.meshPass().record(cmd, f.meshFrame, m_base, m_distance, m_depth, f.background, {},
                              f.lit ? m_light.get() : nullptr);
    for (const Image* image : {&m_base, &m_distance})
        transitionImage(cmd, image->handle(), kColorAspect, kAttachment, kGeneral, kColorOut,
                        VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT, kCompute | kTransfer,
                        kStorageRead | VK_ACCESS_2_TRANSFER_READ_BIT);
    if (f.count) {
        vkCmdFillBuffer(cmd, m_loops.handle(), 0, VK_WHOLE_SIZE, 0u);
        memoryBarrier(cmd, VK_PIPELINE_STAGE_2_CLEAR_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT, kCompute,
                      kStorageRW);
    }
    timer.mark(cmd, "mesh");

    // The march, in `dispatches` dispatches of at most `stepsPerDispatch` steps each.
    const Pipelines& p = *f.pipelines;
    vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, p.march.handle());
    Descriptors()
        .buffer(kMarchBindParams, m_params)
        .buffer(kMarchBindTable, m_shell->tableBuffer)
        .buffer(kMarchBindCells, m_cells)
        .buffer(kMarchBindStarts, m_starts)
        .buffer(kMarchBindList, m_list)
        .buffer(kMarchBindWorldLobes, m_worldLobes)
        .buffer(kMarchBindBoxes, m_boxes)
        .image(kMarchBindMeshDistance, m_distance, kGeneral, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE)
        .buffer(kMarchBindState, m_state)
        .buffer(kMarchBindLoops, m_loops)
        .buffer(kMarchBindWalkBits, m_walkBits)
        .push(m_ctx, cmd, p.march);
    const std::uint32_t steps = f.push.range.z;
    for (std::uint32_t k = 0; k < f.dispatches; ++k) {
        SpotMarchPush push = f.push;
        push.range.x = k * f.stepsPerDispatch;
        push.range.y = std::min(steps, (k + 1) * f.stepsPerDispatch);
        if (k > 0) // the previous dispatch wrote the state this one continues
            memoryBarrier(cmd, kCompute, kStorageRW, kCompute, kStorageRW);
        vkCmdPushConstants(cmd, p.march.layout(), VK_SHADER_STAGE_COMPUTE_BIT, 0, sizeof(push),
                           &push);
        dispatchPixels(cmd, width, height, 8, m_n);
    }
    memoryBarrier(cmd, kCompute, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT, kCompute | kHostStage,
                  kStorageRead | VK_ACCESS_2_HOST_READ_BIT);
    timer.mark(cmd, "march");

    // The resolve: each output pixel the mean of its n x n rays.
    transitionImage(cmd, m_result.handle(), kColorAspect, VK_IMAGE_LAYOUT_UNDEFINED, kGeneral,
                    VK_PIPELINE_STAGE_2_NONE, 0, kCompute, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT);
    vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, p.resolve.handle());
    vkCmdPushConstants(cmd, p.resolve.layout(), VK_SHADER_STAGE_COMPUTE_BIT, 0, sizeof(f.push),
                       &f.push);
    Descriptors()
        .image(kMarchBindBase, m_base, kGeneral, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE)
        .buffer(kMarchBindState, m_state)
        .image(kMarchBindResult, m_result, kGeneral, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE)
        .push(m_ctx, cmd, p.resolve);
    dispatchPixels(cmd, m_width, m_height, 8);
    memoryBarrier(cmd, kCompute, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT,
                  kCompute | kTransfer | kHostStage,
                  kStorageRead | VK_ACCESS_2_TRANSFER_READ_BIT | VK_ACCESS_2_HOST_READ_BIT);
    timer.mark(cmd, "resolve");
}

RaymarchStats RaymarchRenderer::stats() const {
    RaymarchStats s = m_binStats;
    const Prepared& f = m_frame;
    s.loopBound = std::uint32_t(std::min<std::uint64_t>(f.loopBound, 0xffffffffu));
    s.maxLoopIterations =
        m_loops.handle() && f.count ? *static_cast<const std::uint32_t*>(m_loops.mapped()) : 0;
    s.stepsPerDispatch = f.stepsPerDispatch;
    s.maxStepsPerDispatch = f.maxStepsPerDispatch;
    s.dispatches = f.dispatches;
    s.supersample = m_n;
    s.binned = f.binned;
    if (!f.binned)
        s.binMs = s.binHostMs = 0.0;
    return s;
}

FrameCounters RaymarchRenderer::counters() const {
    const RaymarchStats s = stats();
    FrameCounters c;
    c.kernelsDrawn = s.impulses;
    c.extra = {{"loop_bound", double(s.loopBound)},
               {"dispatches", double(s.dispatches)},
               {"steps_per_dispatch", double(s.stepsPerDispatch)},
               {"listed_impulses", double(s.maxListedImpulses)},
               {"neighbourhood_impulses", double(s.maxNeighbourhoodImpulses)},
               {"shell_cells", double(s.shellCells)},
               {"walk_cells", double(s.walkCells)},
               {"longest_probe", double(s.longestProbe)},
               {"binned", s.binned ? 1.0 : 0.0}};
    if (m_frame.count)
        c.extra.emplace_back("max_loop_iterations", double(s.maxLoopIterations));
    if (s.binned)
        c.extra.insert(c.extra.end(), {{"bin_ms", s.binMs}, {"bin_host_ms", s.binHostMs}});
    return c;
}

RaymarchCapture RaymarchRenderer::capture() {
    SPOT_CHECK(m_result.handle() && m_shell && m_frame.pipelines);
    const std::uint32_t width = m_width * m_n, height = m_height * m_n;
    const std::uint64_t pixels = std::uint64_t(width) * height;
    Buffer base(m_ctx, pixels * sizeof(glm::vec4), VK_BUFFER_USAGE_TRANSFER_DST_BIT, kHost,
                "ray march capture: base colour");
    Buffer distance(m_ctx, pixels * sizeof(float), VK_BUFFER_USAGE_TRANSFER_DST_BIT, kHost,
                    "ray march capture: mesh distance");
    m_ctx.submitAndWait([&](VkCommandBuffer cmd) {
        VkBufferImageCopy region{};
        region.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
        region.imageExtent = {width, height, 1};
        vkCmdCopyImageToBuffer(cmd, m_base.handle(), passes::kGeneral, base.handle(), 1, &region);
        vkCmdCopyImageToBuffer(cmd, m_distance.handle(), passes::kGeneral, distance.handle(), 1,
                               &region);
        memoryBarrier(cmd, passes::kTransfer, VK_ACCESS_2_TRANSFER_WRITE_BIT, passes::kHostStage,
                      VK_ACCESS_2_HOST_READ_BIT);
    });
    const Prepared& f = m_frame;
    RaymarchCapture c;
    c.camera = f.camera;
    c.params = *static_cast<const SpotMarchParams*>(m_params.mapped());
    c.push = f.push;
    c.stepsPerDispatch = f.stepsPerDispatch;
    c.lobes = m_scene.lobeCount();
    c.lambert = f.lambert;
    c.cull = f.cull;
    if (f.walkBits)
        c.walkBits = m_walkBitData;
    c.table = m_shell->table;
    const std::uint32_t records = m_binStats.shellCells;
    const auto* cells = static_cast<const SpotMarchCell*>(m_cells.mapped());
    c.cells.assign(cells, cells + records);
    const auto* starts = static_cast<const std::uint32_t*>(m_starts.mapped());
    c.starts.assign(starts, starts + std::uint64_t(records) * (f.cull ? kMarchSubCells : 1u) + 1);
    const auto* list = static_cast<const std::uint32_t*>(m_list.mapped());
    c.list.assign(list, list + m_binStats.listEntries);
    const auto* w = static_cast<const gpu::SpotWorldLobe*>(m_worldLobes.mapped());
    const std::uint64_t lobes = std::uint64_t(m_binStats.impulses) * m_scene.lobeCount();
    c.lobeData.assign(w, w + lobes);
    if (c.params.counts.x > 0) { // a lit frame's colour changes, right after the captured lobes
        c.lobeData.insert(c.lobeData.end(), w + c.params.counts.x, w + c.params.counts.x + lobes);
        c.params.counts.x = std::uint32_t(lobes);
    }
    const auto* box = static_cast<const SpotMarchBox*>(m_boxes.mapped());
    c.boxes.assign(box, box + m_binStats.impulses);
    const auto* b = static_cast<const glm::vec4*>(base.mapped());
    c.base.assign(b, b + pixels);
    const auto* dist = static_cast<const float*>(distance.mapped());
    c.meshDistance.assign(dist, dist + pixels);
    const auto* counted = static_cast<const std::uint32_t*>(m_loops.mapped());
    if (f.count)
        c.gpuLoops.assign(counted + 1, counted + 1 + pixels);
    return c;
}

noise::Image raymarchOnCpu(const RaymarchCapture& capture, std::vector<std::uint32_t>* loops) {
    const std::uint32_t n = capture.push.range.w;
    const std::uint32_t steps = capture.push.range.z;
    const std::uint32_t perDispatch = capture.stepsPerDispatch;
    SPOT_CHECK(n >= 1 && perDispatch >= 1);
    const int width = int(capture.push.size.x), height = int(capture.push.size.y);
    SPOT_CHECK_EQ(width, capture.camera.width * int(n));
    SPOT_CHECK_EQ(height, capture.camera.height * int(n));
    const std::uint64_t pixels = std::uint64_t(width) * std::uint64_t(height);
    SPOT_CHECK_EQ(capture.base.size(), pixels);
    SPOT_CHECK_EQ(capture.meshDistance.size(), pixels);
    std::vector<glm::vec4> state(pixels);
    if (loops)
        loops->assign(pixels, 0u);
    MarchTwin::Arrays arrays;
    arrays.params = &capture.params;
    arrays.table = capture.table.data();
    arrays.cells = capture.cells.data();
    arrays.starts = capture.starts.data();
    arrays.list = capture.list.data();
    arrays.lobes = capture.lobeData.data();
    arrays.boxes = capture.boxes.data();
    arrays.light = capture.push.light;
    arrays.lobeCount = capture.lobes;
    arrays.lambert = capture.lambert;
    arrays.cull = capture.cull;
    arrays.walkBits = capture.walkBits.empty() ? nullptr : capture.walkBits.data();
    // raymarch_march.comp, every dispatch of it, one row band per thread.
    const auto rows = [&](int y0, int y1) {
        MarchTwin twin(arrays);
        for (int y = y0; y < y1; ++y)
            for (int x = 0; x < width; ++x) {
                glm::vec3 o, d;
                twin.marchPixelRay(capture.push, float(x) + 0.5f, float(y) + 0.5f, o, d);
                const std::size_t i = std::size_t(y) * std::size_t(width) + std::size_t(x);
                glm::vec4 s(0.0f, 0.0f, 0.0f, 1.0f);
                std::uint32_t most = 0;
                for (std::uint32_t first = 0; first < steps; first += perDispatch) {
                    std::uint32_t count = 0;
                    s = twin.marchRay(o, d, capture.meshDistance[i], first,
                                      std::min(steps, first + perDispatch), steps, s, count);
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
        workers.emplace_back(rows, height * t / threads, height * (t + 1) / threads);
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
                        (std::size_t(y) * n + sy) * std::size_t(width) + std::size_t(x) * n + sx;
                    sum += glm::vec3(state[i]) + state[i].w * glm::vec3(capture.base[i]);
                }
            image.pixels[std::size_t(y) * std::size_t(image.width) + std::size_t(x)] =
                sum / float(n * n);
        }
    return image;
}

MethodInfo raymarchMethod() {
    MethodInfo m;
    m.name = "raymarch";
    m.summary = "the baseline: each pixel's ray marched through the shell, the neighbouring "
                "kernels summed at every step (paper eq. 7-9)";
    m.settings = {&settings::steps, &settings::supersample, &settings::lod};
    m.rendersLit = true;
    m.make = [](const SceneGpu& scene) -> std::unique_ptr<Renderer> {
        return std::make_unique<RaymarchRenderer>(scene);
    };
    m.summarize = [](const RenderSettings& s) {
        return cat(s.steps, " steps, ", s.supersample, "x", s.supersample, " rays per pixel, ");
    };
    return m;
}

} // namespace spot::splat
