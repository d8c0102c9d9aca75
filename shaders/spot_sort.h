/* spot_sort.h: the GPU radix sort's push constants and constants, shared by C++ and GLSL
 * (splat/passes/radix_sort_vk.cpp and the sort_*.comp shaders).
 *
 * Same rules as spot_layout.h: 16-byte members only, so the push-constant layout equals the C++
 * layout; sort_vk.cpp includes this file inside a namespace with glm types and static_asserts
 * the size.
 *
 * The sort (least significant digit first, 4 passes of 8 bits) over n (key, value) pairs:
 *   histogram  one invocation per chunk of `chunk` consecutive pairs counts its digits (in a
 *              private array) and writes them to its own column of hist[digit * chunks + chunk];
 *   reduce     one invocation per block of kSortScanBlock histogram entries sums its block;
 *   scan       one workgroup scans the block sums (exclusive), each thread a contiguous run;
 *   apply      one invocation per block turns its entries into exclusive prefix sums: in
 *              digit-major order, entry (d, c) becomes the output position of chunk c's first
 *              pair with digit d;
 *   scatter    one invocation per chunk walks its pairs in order, writing each to its digit's
 *              position and advancing it: a stable scatter, with no atomics at all.
 * The result is the unique stable order, whatever the chunking or the thread count.
 *
 * Loop iterations per invocation (lavapipe stops a shader silently after 65,535 in all):
 *   histogram  2 x kSortRadix + chunk <= 512 + 2,048 = 2,560
 *   reduce     kSortScanBlock = 1,024
 *   scan       2 x ceil(blocks / kSortScanThreads) + log2(kSortScanThreads)
 *              <= 2 x 8 + 8 = 24 (blocks <= 2,048 at kSortMaxCount)
 *   apply      kSortScanBlock = 1,024
 *   scatter    chunk <= 2,048
 */
#ifndef SPOT_CONST
#define SPOT_CONST const
#endif

/* Push constants of every sort pipeline (32 bytes). */
struct SpotSortPush {
    uvec4 counts; /* x: pairs n; y: pairs per chunk; z: chunks; w: digit shift (0, 8, 16, 24) */
    uvec4 scan;   /* x: histogram entries (kSortRadix x chunks); y: blocks of kSortScanBlock
                     entries; z, w: unused */
};

/* Descriptor bindings of the sort passes (C++ and GLSL use these names, never numbers). */
SPOT_CONST uint kSortBindKeys = 0u;      /* histogram: keys; scatter: keys in */
SPOT_CONST uint kSortBindValues = 1u;    /* scatter: values in */
SPOT_CONST uint kSortBindKeysOut = 2u;   /* scatter */
SPOT_CONST uint kSortBindValuesOut = 3u; /* scatter */
SPOT_CONST uint kSortBindHistogram = 4u; /* histogram, reduce, apply, scatter */
SPOT_CONST uint kSortBindBlockSums = 5u; /* reduce, scan, apply */

SPOT_CONST uint kSortRadix = 256u;       /* 8-bit digits */
SPOT_CONST uint kSortPasses = 4u;        /* 32-bit keys */
SPOT_CONST uint kSortMinChunk = 256u;    /* pairs per chunk, at least ... */
SPOT_CONST uint kSortMaxChunk = 2048u;   /* ... and at most (the loop budget above) */
SPOT_CONST uint kSortTargetChunks = 512u; /* chunks aimed at, for parallelism (sort_vk.cpp) */
SPOT_CONST uint kSortScanBlock = 1024u;  /* histogram entries per reduce / apply invocation */
SPOT_CONST uint kSortScanThreads = 256u; /* the scan's one workgroup */
SPOT_CONST uint kSortGroup = 16u;        /* workgroup size of the per-chunk and per-block passes */
/* Chosen by measurement on lavapipe (2 threads): 8, 16 or 64 invocations per workgroup time
 * alike; aiming at 128 or 2,048 chunks, or letting chunks grow to 8,192 pairs, was 1.5-2x slower
 * at 1M-4M pairs; counting in the histogram buffer itself instead of a private array, 2-3x
 * slower (a column's counters lie `chunks` entries apart). */
/* Pairs at most: 2^24 (64 MiB of keys, 64 of values: one storage binding holds 128 MiB). Then
 * chunks <= 8,192, histogram entries <= 2^21, blocks <= 2,048 = 8 per scan thread. */
SPOT_CONST uint kSortMaxCount = 16777216u;
SPOT_CONST uint kSortMaxBlocksPerThread = 8u;
