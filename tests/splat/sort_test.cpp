// The GPU radix sort against std::stable_sort: random keys over the whole 32-bit range, many
// duplicates (stability), counts that are multiples of nothing, 0 and 1 pair, a large count (all
// chunks at the longest loop), byte-identical output with lavapipe on 1 and 2 threads, refused
// requests.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <numeric>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "noise/error.h"
#include "splat/passes/radix_sort_vk.h"
#include "splat_test_support.h"

namespace {

using namespace spot;
using spot::test::validated;

struct Pairs {
    std::vector<std::uint32_t> keys, values;
};

/// n pairs, values = input position (so stability is visible), keys drawn by `key`.
template <typename KeyFn> Pairs makePairs(std::size_t n, KeyFn key) {
    Pairs p;
    p.keys.resize(n);
    p.values.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
        p.keys[i] = key(i);
        p.values[i] = std::uint32_t(i);
    }
    return p;
}

Pairs randomPairs(std::size_t n, std::uint32_t seed, std::uint32_t keyMask = 0xffffffffu) {
    std::mt19937 rng(seed);
    return makePairs(n, [&](std::size_t) { return std::uint32_t(rng()) & keyMask; });
}

/// What the GPU must return: the pairs in std::stable_sort's order of keys.
Pairs expected(const Pairs& in) {
    std::vector<std::uint32_t> order(in.keys.size());
    std::iota(order.begin(), order.end(), 0u);
    std::stable_sort(order.begin(), order.end(),
                     [&](std::uint32_t a, std::uint32_t b) { return in.keys[a] < in.keys[b]; });
    Pairs out;
    for (std::uint32_t i : order) {
        out.keys.push_back(in.keys[i]);
        out.values.push_back(in.values[i]);
    }
    return out;
}

/// Sorts a copy on the GPU and compares it with std::stable_sort; reports the first mismatch.
void expectSorted(splat::RadixSort& sort, const Pairs& in, const std::string& what,
                  double* milliseconds = nullptr) {
    Pairs gpu = in;
    sort.sort(gpu.keys, gpu.values, milliseconds);
    const Pairs want = expected(in);
    ASSERT_EQ(gpu.keys.size(), want.keys.size()) << what;
    std::size_t wrong = 0, first = 0;
    for (std::size_t i = 0; i < want.keys.size(); ++i)
        if (gpu.keys[i] != want.keys[i] || gpu.values[i] != want.values[i])
            first = wrong++ == 0 ? i : first;
    EXPECT_EQ(wrong, 0u) << what << ": first difference at " << first << " of " << in.keys.size()
                         << ": (" << (wrong ? gpu.keys[first] : 0) << ", "
                         << (wrong ? gpu.values[first] : 0) << ") instead of ("
                         << (wrong ? want.keys[first] : 0) << ", "
                         << (wrong ? want.values[first] : 0) << ")";
}

TEST(RadixSort, EmptyAndSinglePair) {
    splat::Context ctx(validated());
    splat::RadixSort sort(ctx);
    Pairs none;
    sort.sort(none.keys, none.values);
    EXPECT_TRUE(none.keys.empty());
    Pairs one = makePairs(1, [](std::size_t) { return 0xdeadbeefu; });
    one.values[0] = 42;
    sort.sort(one.keys, one.values);
    EXPECT_EQ(one.keys[0], 0xdeadbeefu);
    EXPECT_EQ(one.values[0], 42u);
    EXPECT_EQ(ctx.validation().errors, 0u) << ctx.validation().firstError;
}

TEST(RadixSort, RandomKeysMatchStableSort) {
    splat::Context ctx(validated());
    splat::RadixSort sort(ctx);
    // Around every chunking boundary (256-pair chunks up to 131,072 pairs, then 512 chunks
    // growing to 2,048 pairs, then more chunks) and the scan's 1,024-entry blocks.
    for (std::size_t n : {2u, 3u, 17u, 255u, 256u, 257u, 1000u, 1023u, 4097u, 65'537u, 131'071u,
                          131'072u, 131'073u, 300'007u, 1'048'577u})
        expectSorted(sort, randomPairs(n, std::uint32_t(n)), "n = " + std::to_string(n));
    // Already sorted, reversed, and all keys equal.
    expectSorted(sort, makePairs(5000, [](std::size_t i) { return std::uint32_t(i * 977); }),
                 "ascending");
    expectSorted(sort,
                 makePairs(5000, [](std::size_t i) { return 0xffffffffu - std::uint32_t(i); }),
                 "descending");
    expectSorted(sort, makePairs(70'001, [](std::size_t) { return 7u; }), "one key");
    EXPECT_EQ(ctx.validation().errors, 0u) << ctx.validation().firstError;
}

TEST(RadixSort, DuplicatesKeepTheirOrder) {
    splat::Context ctx(validated());
    splat::RadixSort sort(ctx);
    // Few distinct keys, differing in each byte in turn, and the extremes.
    const std::uint32_t distinct[] = {0u,          1u,          0x100u,      0x10000u,   0x1000000u,
                                      0x80000000u, 0x7f800000u, 0xffffffffu, 0x01010101u};
    std::mt19937 rng(5);
    const Pairs in = makePairs(200'003, [&](std::size_t) { return distinct[rng() % 9]; });
    expectSorted(sort, in, "nine keys");
    // Positive float depths as keys (the sorted renderer's): the float order.
    std::uniform_real_distribution<float> depth(0.0f, 30.0f);
    std::vector<float> depths;
    const Pairs floats = makePairs(50'000, [&](std::size_t) {
        float d = depth(rng);
        d = rng() % 4 == 0 ? std::floor(d) : d; // plenty of equal depths
        depths.push_back(d);
        std::uint32_t bits;
        std::memcpy(&bits, &d, 4);
        return bits;
    });
    Pairs gpu = floats;
    sort.sort(gpu.keys, gpu.values);
    for (std::size_t i = 1; i < gpu.values.size(); ++i) {
        const float a = depths[gpu.values[i - 1]], b = depths[gpu.values[i]];
        ASSERT_TRUE(a < b || (a == b && gpu.values[i - 1] < gpu.values[i])) << i;
    }
    EXPECT_EQ(ctx.validation().errors, 0u) << ctx.validation().firstError;
}

TEST(RadixSort, LargeCount) {
    // 2^22 + 1 pairs: 2,049 chunks, all but the last of 2,048 pairs (the longest loops the sort
    // runs), 513 scan blocks (runs of 3 per scan thread, uneven).
    splat::Context ctx(validated());
    splat::RadixSort sort(ctx);
    const Pairs in = randomPairs(4'194'305, 11);
    double ms = 0.0;
    expectSorted(sort, in, "2^22 + 1 pairs", &ms);
    std::printf("radix sort: %zu pairs in %.1f ms (%.1f M pairs/s)\n", in.keys.size(), ms,
                double(in.keys.size()) / ms * 1e-3);
    EXPECT_EQ(ctx.validation().errors, 0u) << ctx.validation().firstError;
}

TEST(RadixSort, Throughput) {
    // Keys per second on warm buffers (timings are reported, never asserted): the best and the
    // median of 7 sorts recorded on the same buffers (the best is what the sort costs when no
    // other process shares the CPU).
    splat::Context ctx(validated());
    splat::RadixSort sort(ctx);
    splat::Timestamps timestamps(ctx, 2);
    for (std::uint32_t n : {10'000u, 100'000u, 1'000'000u, 4'000'000u}) {
        const Pairs in = randomPairs(n, n);
        splat::Buffer keys(ctx, std::uint64_t(n) * 4, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT,
                           splat::Buffer::Memory::HostVisible, "test keys");
        splat::Buffer values(ctx, std::uint64_t(n) * 4, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT,
                             splat::Buffer::Memory::HostVisible, "test values");
        const splat::RadixSortScratch scratch(ctx, n);
        std::vector<double> ms;
        for (int run = 0; run < 7; ++run) {
            keys.upload(in.keys.data(), std::uint64_t(n) * 4);
            values.upload(in.values.data(), std::uint64_t(n) * 4);
            ctx.submitAndWait([&](VkCommandBuffer cmd) {
                timestamps.reset(cmd);
                timestamps.write(cmd, 0, VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT);
                sort.record(cmd, keys, values, n, scratch);
                timestamps.write(cmd, 1, VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT);
            });
            ms.push_back(timestamps.milliseconds()[1]);
        }
        std::sort(ms.begin(), ms.end());
        std::printf("radix sort of %u pairs: best %.2f ms (%.1f M pairs/s), median %.2f ms (chunk "
                    "%u)\n",
                    n, ms[0], n / ms[0] * 1e-3, ms[3], splat::RadixSort::chunkSize(n));
        const auto* k = static_cast<const std::uint32_t*>(keys.mapped());
        EXPECT_TRUE(std::is_sorted(k, k + n)) << n;
    }
    EXPECT_EQ(ctx.validation().errors, 0u) << ctx.validation().firstError;
}

TEST(RadixSort, ByteIdenticalOnOneAndTwoThreads) {
    // lavapipe reads LP_NUM_THREADS when an instance creates its device: each Context is a new
    // instance, so each run below has its own thread count.
    spot::test::ScopedLavapipeThreads lavapipe;
    const Pairs in = randomPairs(777'777, 3, 0x00ff0fffu); // many duplicates
    Pairs runs[3];
    const char* threads[3] = {"1", "2", "2"};
    for (int r = 0; r < 3; ++r) {
        lavapipe.set(threads[r]);
        splat::Context ctx(validated());
        splat::RadixSort sort(ctx);
        runs[r] = in;
        double ms = 0.0;
        sort.sort(runs[r].keys, runs[r].values, &ms);
        std::printf("LP_NUM_THREADS=%s: %.1f ms\n", threads[r], ms);
        EXPECT_EQ(ctx.validation().errors, 0u) << ctx.validation().firstError;
    }
    for (int r = 1; r < 3; ++r) {
        EXPECT_EQ(runs[r].keys, runs[0].keys) << r;
        EXPECT_EQ(runs[r].values, runs[0].values) << r;
    }
    EXPECT_EQ(runs[0].values, expected(in).values);
}

TEST(RadixSort, RefusesWhatItCannotDo) {
    splat::Context ctx(validated());
    splat::RadixSort sort(ctx);
    std::vector<std::uint32_t> keys(10), values(9);
    EXPECT_THROW(sort.sort(keys, values), InputError);
    EXPECT_THROW(splat::RadixSortScratch(ctx, splat::RadixSort::kMaxCount + 1), InputError);
    // More pairs than the scratch or the buffers hold.
    const splat::RadixSortScratch scratch(ctx, 100);
    const splat::Buffer small(ctx, 400, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT,
                              splat::Buffer::Memory::DeviceLocal, "test keys");
    const splat::Buffer big(ctx, 800, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT,
                            splat::Buffer::Memory::DeviceLocal, "test values");
    EXPECT_THROW(
        ctx.submitAndWait([&](VkCommandBuffer cmd) { sort.record(cmd, big, big, 101, scratch); }),
        InputError);
    const splat::RadixSortScratch large(ctx, 200);
    EXPECT_THROW(
        ctx.submitAndWait([&](VkCommandBuffer cmd) { sort.record(cmd, small, big, 200, large); }),
        InputError);
    EXPECT_EQ(ctx.validation().errors, 0u) << ctx.validation().firstError;
}

} // namespace
