/// @file radix_sort_vk.h
/// @brief A GPU radix sort of (uint32 key, uint32 value) pairs: ascending keys, stable,
/// deterministic (the same bytes whatever lavapipe's thread count: no atomics at all).
///
/// Least significant digit first, 4 passes of 8-bit digits, each pass 5 compute dispatches over
/// consecutive chunks of 256 to 2,048 pairs (histogram per chunk, a scan of the digit-major
/// histogram split into blocks of 1,024 entries, a stable scatter per chunk). Every invocation
/// loops at most 2,560 times, far below lavapipe's silent 65,535; shaders/spot_sort.h has the
/// algorithm and the bounds. Keys and values live in separate buffers (structure of arrays), so
/// the sorted values are directly a list of indices (the sorted renderer draws from it).
#pragma once

#include <cstdint>
#include <vector>

#include "splat/context_vk.h"

namespace spot::splat {

/// Buffers one sort of up to `capacity` pairs works in: the other half of the key/value
/// ping-pong, the digit histogram and its block sums.
class RadixSortScratch {
public:
    RadixSortScratch() = default;
    RadixSortScratch(Context& ctx, std::uint32_t capacity);

    std::uint32_t capacity() const { return m_capacity; }
    /// Device memory its buffers hold against the context's budget.
    std::uint64_t reservedBytes() const {
        return m_keys.reservedBytes() + m_values.reservedBytes() + m_histogram.reservedBytes() +
               m_blockSums.reservedBytes();
    }
    /// Device memory a scratch for `capacity` pairs allocates (bytes).
    static std::uint64_t bytes(std::uint32_t capacity);

private:
    friend class RadixSort;
    std::uint32_t m_capacity = 0;
    Buffer m_keys, m_values, m_histogram, m_blockSums;
};

class RadixSort {
public:
    /// Pairs one sort takes at most (2^24: keys and values each fill half a storage binding).
    static constexpr std::uint32_t kMaxCount = 16777216u;

    /// Builds the five pipelines.
    explicit RadixSort(Context& ctx);

    /// Record the sort of keys[0, n) with values[0, n) in place. Throws InputError when n exceeds
    /// kMaxCount, the scratch's capacity, or the buffers. n = 0 records nothing. The caller makes
    /// earlier writes to keys and values visible to compute-shader reads; the sort ends with a
    /// barrier that makes its results visible to every later command.
    void record(VkCommandBuffer cmd, const Buffer& keys, const Buffer& values, std::uint32_t n,
                const RadixSortScratch& scratch);

    /// Upload, sort, read back: a convenience for tests and tools. `milliseconds`, when given,
    /// receives the sort's GPU time (without the transfers).
    void sort(std::vector<std::uint32_t>& keys, std::vector<std::uint32_t>& values,
              double* milliseconds = nullptr);

    /// Pairs per chunk the sort uses for n pairs (the chunking changes the speed, never the
    /// result).
    static std::uint32_t chunkSize(std::uint32_t n);

private:
    Context& m_ctx;
    Pipeline m_histogram, m_reduce, m_scan, m_apply, m_scatter;
    Timestamps m_timestamps;
};

} // namespace spot::splat
