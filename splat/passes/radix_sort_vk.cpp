#include "radix_sort_vk.h"

#include <algorithm>
#include <span>

#include <glm/glm.hpp>

#include "noise/error.h"

#include "sort_apply.comp.h"
#include "sort_histogram.comp.h"
#include "sort_reduce.comp.h"
#include "sort_scan.comp.h"
#include "sort_scatter.comp.h"

namespace spot::splat {

namespace gpu_sort {
using glm::uvec4;
#define SPOT_CONST inline constexpr
#include "shaders/spot_sort.h"
#undef SPOT_CONST
static_assert(sizeof(SpotSortPush) == 32);
static_assert(kSortMaxCount == RadixSort::kMaxCount);
static_assert(kSortRadix == 256u && kSortPasses * 8u == 32u, "4 passes of 8-bit digits");
// The scan's one workgroup takes every block at the largest count (spot_sort.h's loop bounds).
static_assert((kSortMaxCount / kSortMaxChunk) * kSortRadix / kSortScanBlock <=
              kSortScanThreads * kSortMaxBlocksPerThread);
} // namespace gpu_sort

namespace {

using gpu_sort::SpotSortPush;

template <std::size_t N> std::span<const std::uint32_t> spirv(const std::uint32_t (&code)[N]) {
    return {code, N};
}

std::uint32_t divUp(std::uint64_t a, std::uint64_t b) {
    return std::uint32_t((a + b - 1) / b);
}

/// Chunks of a sort of n pairs.
std::uint32_t chunkCount(std::uint32_t n) {
    return divUp(n, RadixSort::chunkSize(n));
}

/// Chunks of any sort of at most `capacity` pairs: chunkCount is not monotonic in n (the chunk
/// grows with n between the two clamps), so this bounds each regime of chunkSize.
std::uint32_t maxChunkCount(std::uint32_t capacity) {
    return std::max(
        divUp(capacity, gpu_sort::kSortMaxChunk),
        std::min(divUp(capacity, gpu_sort::kSortMinChunk), gpu_sort::kSortTargetChunks));
}

constexpr VkPipelineStageFlags2 kCompute = VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT;
constexpr VkAccessFlags2 kStorageRW =
    VK_ACCESS_2_SHADER_STORAGE_READ_BIT | VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT;

void computeToCompute(VkCommandBuffer cmd) {
    memoryBarrier(cmd, kCompute, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT, kCompute, kStorageRW);
}

} // namespace

std::uint32_t RadixSort::chunkSize(std::uint32_t n) {
    return std::clamp(divUp(n, gpu_sort::kSortTargetChunks), gpu_sort::kSortMinChunk,
                      gpu_sort::kSortMaxChunk);
}

std::uint64_t RadixSortScratch::bytes(std::uint32_t capacity) {
    const std::uint64_t entries = std::uint64_t(maxChunkCount(capacity)) * gpu_sort::kSortRadix;
    // Buffer allocates 16 bytes at least.
    return 2 * std::max<std::uint64_t>(std::uint64_t(capacity) * 4, 16) +
           std::max<std::uint64_t>(entries * 4, 16) +
           std::max<std::uint64_t>(std::uint64_t(divUp(entries, gpu_sort::kSortScanBlock)) * 4, 16);
}

RadixSortScratch::RadixSortScratch(Context& ctx, std::uint32_t capacity) : m_capacity(capacity) {
    if (capacity > RadixSort::kMaxCount)
        throw InputError(cat("radix sort: ", capacity, " pairs, more than the ",
                             RadixSort::kMaxCount, " one sort takes"));
    const std::uint64_t entries = std::uint64_t(maxChunkCount(capacity)) * gpu_sort::kSortRadix;
    constexpr VkBufferUsageFlags kStorage = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT;
    m_keys = Buffer(ctx, std::uint64_t(capacity) * 4, kStorage, Buffer::Memory::DeviceLocal,
                    cat("radix sort scratch keys (", capacity, ")"));
    m_values = Buffer(ctx, std::uint64_t(capacity) * 4, kStorage, Buffer::Memory::DeviceLocal,
                      cat("radix sort scratch values (", capacity, ")"));
    m_histogram =
        Buffer(ctx, entries * 4, kStorage, Buffer::Memory::DeviceLocal, "radix sort histogram");
    m_blockSums = Buffer(ctx, std::uint64_t(divUp(entries, gpu_sort::kSortScanBlock)) * 4, kStorage,
                         Buffer::Memory::DeviceLocal, "radix sort block sums");
}

RadixSort::RadixSort(Context& ctx) : m_ctx(ctx), m_timestamps(ctx, 2) {
    using namespace gpu_sort;
    const std::uint32_t push = sizeof(SpotSortPush);
    const Binding keys = storageBuffer(kSortBindKeys), hist = storageBuffer(kSortBindHistogram),
                  sums = storageBuffer(kSortBindBlockSums);
    m_histogram = makeComputePipeline(ctx, spirv(spv_sort_histogram_comp), {keys, hist}, push);
    m_reduce = makeComputePipeline(ctx, spirv(spv_sort_reduce_comp), {hist, sums}, push);
    m_scan = makeComputePipeline(ctx, spirv(spv_sort_scan_comp), {sums}, push);
    m_apply = makeComputePipeline(ctx, spirv(spv_sort_apply_comp), {hist, sums}, push);
    m_scatter = makeComputePipeline(ctx, spirv(spv_sort_scatter_comp),
                                    {keys, storageBuffer(kSortBindValues),
                                     storageBuffer(kSortBindKeysOut),
                                     storageBuffer(kSortBindValuesOut), hist},
                                    push);
}

void RadixSort::record(VkCommandBuffer cmd, const Buffer& keys, const Buffer& values,
                       std::uint32_t n, const RadixSortScratch& scratch) {
    if (n > kMaxCount)
        throw InputError(
            cat("radix sort: ", n, " pairs, more than the ", kMaxCount, " one sort takes"));
    if (n > scratch.capacity())
        throw InputError(cat("radix sort: ", n, " pairs, the scratch holds ", scratch.capacity()));
    if (std::uint64_t(n) * 4 > keys.size() || std::uint64_t(n) * 4 > values.size())
        throw InputError(cat("radix sort: ", n, " pairs need ", std::uint64_t(n) * 4,
                             " bytes of keys and of values; the buffers hold ", keys.size(),
                             " and ", values.size()));
    if (n == 0)
        return;
    const std::uint32_t chunk = chunkSize(n), chunks = chunkCount(n);
    const std::uint32_t entries = chunks * gpu_sort::kSortRadix;
    const std::uint32_t blocks = divUp(entries, gpu_sort::kSortScanBlock);
    SPOT_CHECK_LE(chunks, maxChunkCount(scratch.capacity()));
    SPOT_CHECK_LE(blocks, gpu_sort::kSortScanThreads * gpu_sort::kSortMaxBlocksPerThread);

    auto bind = [&](const Pipeline& p, const SpotSortPush& push) {
        vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, p.handle());
        vkCmdPushConstants(cmd, p.layout(), VK_SHADER_STAGE_COMPUTE_BIT, 0, sizeof(push), &push);
    };
    const Buffer* from[2] = {&keys, &values};
    const Buffer* to[2] = {&scratch.m_keys, &scratch.m_values};
    for (std::uint32_t pass = 0; pass < gpu_sort::kSortPasses; ++pass) {
        SpotSortPush push{};
        push.counts = glm::uvec4(n, chunk, chunks, 8u * pass);
        push.scan = glm::uvec4(entries, blocks, 0u, 0u);

        bind(m_histogram, push);
        Descriptors()
            .buffer(gpu_sort::kSortBindKeys, *from[0])
            .buffer(gpu_sort::kSortBindHistogram, scratch.m_histogram)
            .push(m_ctx, cmd, m_histogram);
        vkCmdDispatch(cmd, divUp(chunks, gpu_sort::kSortGroup), 1, 1);
        computeToCompute(cmd);

        bind(m_reduce, push);
        Descriptors()
            .buffer(gpu_sort::kSortBindHistogram, scratch.m_histogram)
            .buffer(gpu_sort::kSortBindBlockSums, scratch.m_blockSums)
            .push(m_ctx, cmd, m_reduce);
        vkCmdDispatch(cmd, divUp(blocks, gpu_sort::kSortGroup), 1, 1);
        computeToCompute(cmd);

        bind(m_scan, push);
        Descriptors().buffer(gpu_sort::kSortBindBlockSums, scratch.m_blockSums).push(m_ctx, cmd, m_scan);
        vkCmdDispatch(cmd, 1, 1, 1);
        computeToCompute(cmd);

        bind(m_apply, push);
        Descriptors()
            .buffer(gpu_sort::kSortBindHistogram, scratch.m_histogram)
            .buffer(gpu_sort::kSortBindBlockSums, scratch.m_blockSums)
            .push(m_ctx, cmd, m_apply);
        vkCmdDispatch(cmd, divUp(blocks, gpu_sort::kSortGroup), 1, 1);
        computeToCompute(cmd);

        bind(m_scatter, push);
        Descriptors()
            .buffer(gpu_sort::kSortBindKeys, *from[0])
            .buffer(gpu_sort::kSortBindValues, *from[1])
            .buffer(gpu_sort::kSortBindKeysOut, *to[0])
            .buffer(gpu_sort::kSortBindValuesOut, *to[1])
            .buffer(gpu_sort::kSortBindHistogram, scratch.m_histogram)
            .push(m_ctx, cmd, m_scatter);
        vkCmdDispatch(cmd, divUp(chunks, gpu_sort::kSortGroup), 1, 1);
        // An even number of passes: the result ends in the caller's buffers.
        std::swap(from[0], to[0]);
        std::swap(from[1], to[1]);
        if (pass + 1 < gpu_sort::kSortPasses)
            computeToCompute(cmd);
    }
    memoryBarrier(cmd, kCompute, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT,
                  VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT,
                  VK_ACCESS_2_MEMORY_READ_BIT | VK_ACCESS_2_MEMORY_WRITE_BIT);
}

void RadixSort::sort(std::vector<std::uint32_t>& keys, std::vector<std::uint32_t>& values,
                     double* milliseconds) {
    if (keys.size() != values.size())
        throw InputError(cat("radix sort: ", keys.size(), " keys but ", values.size(), " values"));
    if (keys.size() > kMaxCount)
        throw InputError(cat("radix sort: ", keys.size(), " pairs, more than the ", kMaxCount,
                             " one sort takes"));
    const std::uint32_t n = std::uint32_t(keys.size());
    constexpr VkBufferUsageFlags kStorage = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT;
    Buffer keyBuffer(m_ctx, std::uint64_t(n) * 4, kStorage, Buffer::Memory::HostVisible,
                     "radix sort keys");
    Buffer valueBuffer(m_ctx, std::uint64_t(n) * 4, kStorage, Buffer::Memory::HostVisible,
                       "radix sort values");
    if (n > 0) {
        keyBuffer.upload(keys.data(), std::uint64_t(n) * 4);
        valueBuffer.upload(values.data(), std::uint64_t(n) * 4);
    }
    const RadixSortScratch scratch(m_ctx, n);
    m_ctx.submitAndWait([&](VkCommandBuffer cmd) {
        m_timestamps.reset(cmd);
        m_timestamps.write(cmd, 0, VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT);
        memoryBarrier(cmd, VK_PIPELINE_STAGE_2_HOST_BIT, VK_ACCESS_2_HOST_WRITE_BIT, kCompute,
                      VK_ACCESS_2_SHADER_STORAGE_READ_BIT);
        record(cmd, keyBuffer, valueBuffer, n, scratch);
        m_timestamps.write(cmd, 1, VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT);
        memoryBarrier(cmd, kCompute, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT,
                      VK_PIPELINE_STAGE_2_HOST_BIT, VK_ACCESS_2_HOST_READ_BIT);
    });
    if (milliseconds)
        *milliseconds = m_timestamps.milliseconds()[1];
    if (n > 0) {
        const auto* k = static_cast<const std::uint32_t*>(keyBuffer.mapped());
        const auto* v = static_cast<const std::uint32_t*>(valueBuffer.mapped());
        std::copy(k, k + n, keys.begin());
        std::copy(v, v + n, values.begin());
    }
}

} // namespace spot::splat
