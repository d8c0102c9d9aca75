// The structs shared by the host and the shaders (shaders/spot_layout.h, spot_splat.h,
// spot_sort.h, spot_generate_layout.h, raymarch_layout.glsl, baked_layout.glsl): every one's size
// and every field's offset asserted at compile time on the C++ side (each header included the
// way its host code includes it: in a namespace with GLM's types), and the same offsets read
// back from the SPIR-V the build compiled, so a layout the GLSL compiler decides differently
// (std430 rounding a vec3, an array's stride) fails here rather than as a garbled image.
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <map>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "shaders/spot_layout.hpp"

namespace layout_splat {
using glm::uvec4;
using glm::vec4;
using uint = std::uint32_t;
#include "shaders/spot_splat.h"
} // namespace layout_splat

namespace layout_sort {
using glm::uvec4;
using uint = std::uint32_t;
#include "shaders/spot_sort.h"
} // namespace layout_sort

namespace layout_gen {
using glm::uvec4;
using glm::vec4;
using uint = std::uint32_t;
#include "shaders/spot_generate_layout.h"
} // namespace layout_gen

namespace layout_march {
using glm::ivec4;
using glm::uvec4;
using glm::vec4;
using uint = std::uint32_t;
#include "shaders/raymarch_layout.glsl"
} // namespace layout_march

namespace layout_baked {
using glm::ivec3;
using glm::ivec4;
using glm::min;
using glm::uvec2;
using glm::uvec3;
using glm::uvec4;
using glm::vec4;
using uint = std::uint32_t;
#undef SPOT_CONST
#define SPOT_CONST inline constexpr
#define SPOT_FN inline
#include "shaders/baked_layout.glsl"
#undef SPOT_FN
} // namespace layout_baked

#include "baked_march.comp.h"
#include "baked_march_2.comp.h"
#include "baked_march_3.comp.h"
#include "baked_march_4.comp.h"
#include "baked_march_lit.comp.h"
#include "baked_peel.frag.h"
#include "baked_shell.comp.h"
#include "baked_tet.vert.h"
#include "generate_jittered.comp.h"
#include "generate_jittered_partial.comp.h"
#include "generate_poisson.comp.h"
#include "generate_poisson_groom.comp.h"
#include "generate_poisson_groom_partial.comp.h"
#include "generate_jittered_groom.comp.h"
#include "generate_jittered_groom_partial.comp.h"
#include "generate_poisson_partial.comp.h"
#include "generate_scan.comp.h"
#include "generate_scatter.comp.h"
#include "raymarch_bin.comp.h"
#include "raymarch_march.comp.h"
#include "raymarch_resolve.comp.h"
#include "sort_apply.comp.h"
#include "sort_histogram.comp.h"
#include "sort_reduce.comp.h"
#include "sort_scan.comp.h"
#include "sort_scatter.comp.h"
#include "splat_closest.frag.h"
#include "splat_compact.comp.h"
#include "splat_compact_small.comp.h"
#include "splat_instanced.frag.h"
#include "splat_mesh.frag.h"
#include "splat_mesh.vert.h"
#include "splat_oit.frag.h"
#include "splat_oit_closest.frag.h"
#include "splat_prepare.comp.h"
#include "splat_quad.vert.h"
#include "splat_resolve_copy.comp.h"
#include "splat_resolve_hybrid.comp.h"
#include "splat_resolve_hybrid_fixed.comp.h"
#include "splat_resolve_hybrid_pass.comp.h"
#include "splat_resolve_instanced.comp.h"
#include "splat_resolve_oit.comp.h"
#include "splat_resolve_oit_fixed.comp.h"
#include "splat_roofline.frag.h"
#include "splat_small_hybrid.comp.h"
#include "splat_small_instanced.comp.h"
#include "splat_small_oit.comp.h"
#include "splat_sorted.frag.h"
#include "splat_sorted_keys.comp.h"

namespace {

// One table drives both checks: the compile-time asserts below and the SPIR-V comparison.
// SPOT_LAYOUT(X) lists (struct, namespace, field) for every field of every shared struct;
// SPOT_SIZES(X) each struct's size.
#define SPOT_LAYOUT(X)                                                                             \
    X(spot::gpu, SpotCell, ijk, 0)                                                                 \
    X(spot::gpu, SpotCell, info, 16)                                                               \
    X(spot::gpu, SpotPiece, c01, 0)                                                                \
    X(spot::gpu, SpotPiece, c2, 16)                                                                \
    X(spot::gpu, SpotImpulse, position, 0)                                                         \
    X(spot::gpu, SpotImpulse, normal, 16)                                                          \
    X(spot::gpu, SpotImpulse, comb, 32)                                                            \
    X(spot::gpu, SpotImpulse, frameX, 48)                                                          \
    X(spot::gpu, SpotImpulse, frameY, 64)                                                          \
    X(spot::gpu, SpotImpulse, frameZ, 80)                                                          \
    X(spot::gpu, SpotImpulse, scale, 96)                                                           \
    X(spot::gpu, SpotImpulse, color, 112)                                                          \
    X(spot::gpu, SpotImpulse, cell, 128)                                                           \
    X(spot::gpu, SpotLobe, inv0, 0)                                                                \
    X(spot::gpu, SpotLobe, inv1, 16)                                                               \
    X(spot::gpu, SpotLobe, inv2, 32)                                                               \
    X(spot::gpu, SpotLobe, color, 48)                                                              \
    X(spot::gpu, SpotWorldLobe, a0, 0)                                                             \
    X(spot::gpu, SpotWorldLobe, a1, 16)                                                            \
    X(spot::gpu, SpotWorldLobe, a2, 32)                                                            \
    X(spot::gpu, SpotWorldLobe, color, 48)                                                         \
    X(spot::gpu, SpotField, kind, 0)                                                               \
    X(spot::gpu, SpotField, value, 16)                                                             \
    X(spot::gpu, SpotField, lo, 32)                                                                \
    X(spot::gpu, SpotField, hi, 48)                                                                \
    X(spot::gpu, SpotField, from, 64)                                                              \
    X(spot::gpu, SpotField, axis, 80)                                                              \
    X(spot::gpu, SpotField, data, 96)                                                              \
    X(spot::gpu, SpotField, clampLo, 112)                                                          \
    X(spot::gpu, SpotField, clampHi, 128)                                                          \
    X(spot::gpu, SpotGenParams, distribution, 0)                                                   \
    X(spot::gpu, SpotGenParams, variation0, 16)                                                    \
    X(spot::gpu, SpotGenParams, variation1, 32)                                                    \
    X(spot::gpu, SpotGenParams, flags, 48)                                                         \
    X(spot::gpu, SpotGenParams, lod, 64)                                                           \
    X(spot::gpu, SpotGenParams, clump, 80)                                                         \
    X(spot::gpu, SpotGenParams, clump2, 96)                                                        \
    X(spot::gpu, SpotGenParams, clumpFlags, 112)                                                   \
    X(spot::gpu, SpotGenParams, fields, 128)                                                       \
    X(layout_splat, SpotSplatFrame, eye, 0)                                                        \
    X(layout_splat, SpotSplatFrame, forward, 16)                                                   \
    X(layout_splat, SpotSplatFrame, right, 32)                                                     \
    X(layout_splat, SpotSplatFrame, up, 48)                                                        \
    X(layout_splat, SpotSplatFrame, size, 64)                                                      \
    X(layout_splat, SpotSplatFrame, counts, 80)                                                    \
    X(layout_splat, SpotSplatFrame, light, 96)                                                     \
    X(layout_splat, SpotSplatFrame, base, 112)                                                     \
    X(layout_splat, SpotMeshVertex, position, 0)                                                   \
    X(layout_splat, SpotMeshVertex, normal, 16)                                                    \
    X(layout_splat, SpotScreenLobe, a0, 0)                                                         \
    X(layout_splat, SpotScreenLobe, ax, 16)                                                        \
    X(layout_splat, SpotScreenLobe, ay, 32)                                                        \
    X(layout_splat, SpotScreenLobe, b, 48)                                                         \
    X(layout_splat, SpotKernelBound, quad, 0)                                                      \
    X(layout_splat, SpotKernelBound, axis, 16)                                                     \
    X(layout_splat, SpotKernelBound, color, 32)                                                    \
    X(layout_splat, SpotSplatList, groupsX, 0)                                                     \
    X(layout_splat, SpotSplatList, groupsY, 4)                                                     \
    X(layout_splat, SpotSplatList, groupsZ, 8)                                                     \
    X(layout_splat, SpotSplatList, count, 12)                                                      \
    X(layout_splat, SpotSplatCounters, fragments, 0)                                               \
    X(layout_sort, SpotSortPush, counts, 0)                                                        \
    X(layout_sort, SpotSortPush, scan, 16)                                                         \
    X(layout_gen, SpotGenPush, counts, 0)                                                          \
    X(layout_gen, SpotGenPush, lod, 16)                                                            \
    X(layout_march, SpotMarchParams, grid, 0)                                                      \
    X(layout_march, SpotMarchParams, lo, 16)                                                       \
    X(layout_march, SpotMarchParams, hi, 32)                                                       \
    X(layout_march, SpotMarchParams, counts, 48)                                                   \
    X(layout_march, SpotMarchPush, eye, 0)                                                         \
    X(layout_march, SpotMarchPush, forward, 16)                                                    \
    X(layout_march, SpotMarchPush, right, 32)                                                      \
    X(layout_march, SpotMarchPush, up, 48)                                                         \
    X(layout_march, SpotMarchPush, size, 64)                                                       \
    X(layout_march, SpotMarchPush, light, 80)                                                      \
    X(layout_march, SpotMarchPush, range, 96)                                                      \
    X(layout_march, SpotMarchCell, head, 0)                                                        \
    X(layout_march, SpotMarchBox, lo, 0)                                                           \
    X(layout_march, SpotMarchBox, hi, 16)                                                          \
    X(layout_baked, SpotBakedTet, world, 0)                                                        \
    X(layout_baked, SpotBakedTet, plane, 64)                                                       \
    X(layout_baked, SpotBakedTet, toRest, 128)                                                     \
    X(layout_baked, SpotBakedParams, grid, 0)                                                      \
    X(layout_baked, SpotBakedParams, counts, 16)                                                   \
    X(layout_baked, SpotBakedParams, unit, 32)                                                     \
    X(layout_baked, SpotBakedParams, leafOrigin, 48)                                               \
    X(layout_baked, SpotBakedParams, leafDims, 48 + 16 * 12)                                       \
    X(layout_baked, SpotBakedParams, lit, 48 + 2 * 16 * 12)                                        \
    X(layout_baked, SpotBakedParams, shadow, 48 + 2 * 16 * 12 + 16)                                \
    X(layout_baked, SpotBakedParams, sky, 48 + 2 * 16 * 12 + 32)                                   \
    X(layout_baked, SpotBakedParams, primary, 48 + 2 * 16 * 12 + 48)                               \
    X(layout_baked, SpotBakedParams, secondary, 48 + 2 * 16 * 12 + 64)                             \
    X(layout_baked, SpotBakedParams, lights, 48 + 2 * 16 * 12 + 80)                                \
    X(layout_baked, SpotBakedLight, position, 0)                                                   \
    X(layout_baked, SpotBakedLight, radiance, 16)                                                  \
    X(layout_baked, SpotBakedList, groups, 0)                                                      \
    X(layout_baked, SpotBakedList, count, 12)

#define SPOT_SIZES(X)                                                                              \
    X(spot::gpu, SpotCell, 32)                                                                     \
    X(spot::gpu, SpotPiece, 32)                                                                    \
    X(spot::gpu, SpotImpulse, 144)                                                                 \
    X(spot::gpu, SpotLobe, 64)                                                                     \
    X(spot::gpu, SpotWorldLobe, 64)                                                                \
    X(spot::gpu, SpotField, 144)                                                                   \
    X(spot::gpu, SpotGenParams, 128 + 11 * 144)                                                    \
    X(layout_splat, SpotSplatFrame, 128)                                                           \
    X(layout_splat, SpotMeshVertex, 32)                                                            \
    X(layout_splat, SpotScreenLobe, 64)                                                            \
    X(layout_splat, SpotKernelBound, 48)                                                           \
    X(layout_splat, SpotSplatList, 16)                                                             \
    X(layout_splat, SpotSplatCounters, 16)                                                         \
    X(layout_sort, SpotSortPush, 32)                                                               \
    X(layout_gen, SpotGenPush, 32)                                                                 \
    X(layout_march, SpotMarchParams, 64)                                                           \
    X(layout_march, SpotMarchPush, 112)                                                            \
    X(layout_march, SpotMarchCell, 16)                                                             \
    X(layout_march, SpotMarchBox, 32)                                                              \
    X(layout_baked, SpotBakedTet, 176)                                                             \
    X(layout_baked, SpotBakedParams, 48 + 2 * 16 * 12 + 5 * 16 + 8 * 32)                           \
    X(layout_baked, SpotBakedLight, 32)                                                            \
    X(layout_baked, SpotBakedList, 16)

#define SPOT_ASSERT_OFFSET(ns, type, field, offset)                                                \
    static_assert(offsetof(ns::type, field) == (offset), #type "." #field);
#define SPOT_ASSERT_SIZE(ns, type, size) static_assert(sizeof(ns::type) == (size), #type);
SPOT_LAYOUT(SPOT_ASSERT_OFFSET)
SPOT_SIZES(SPOT_ASSERT_SIZE)

/// (struct, field) -> the C++ offset.
std::map<std::pair<std::string, std::string>, std::uint32_t> hostOffsets() {
    std::map<std::pair<std::string, std::string>, std::uint32_t> out;
#define SPOT_RECORD_OFFSET(ns, type, field, offset)                                                \
    out[{#type, #field}] = std::uint32_t(offsetof(ns::type, field));
    SPOT_LAYOUT(SPOT_RECORD_OFFSET)
#undef SPOT_RECORD_OFFSET
    return out;
}

struct Module {
    const char* name;
    const std::uint32_t* words;
    std::size_t count;
};
#define SPOT_MODULE(var)                                                                           \
    Module {                                                                                       \
#var, var, sizeof(var) / sizeof(var[0])                                                    \
    }

/// Every (struct, field, offset) the module decorates with an explicit offset, for its structs
/// named Spot*: OpName (5) names the struct type, OpMemberName (6) its fields, OpMemberDecorate
/// (72) with decoration Offset (35) their offsets.
struct SpirvField {
    std::string type, field;
    std::uint32_t offset;
};
std::vector<SpirvField> spirvOffsets(const Module& m) {
    std::map<std::uint32_t, std::string> typeNames;
    std::map<std::pair<std::uint32_t, std::uint32_t>, std::string> memberNames;
    std::vector<std::tuple<std::uint32_t, std::uint32_t, std::uint32_t>> offsets;
    const auto text = [](const std::uint32_t* w, std::size_t n) {
        return std::string(reinterpret_cast<const char*>(w),
                           strnlen(reinterpret_cast<const char*>(w), 4 * n));
    };
    for (std::size_t i = 5; i < m.count;) {
        const std::uint32_t op = m.words[i] & 0xffffu, length = m.words[i] >> 16;
        if (length == 0 || i + length > m.count)
            break;
        const std::uint32_t* w = m.words + i;
        if (op == 5 && length >= 3)
            typeNames[w[1]] = text(w + 2, length - 2);
        else if (op == 6 && length >= 4)
            memberNames[{w[1], w[2]}] = text(w + 3, length - 3);
        else if (op == 72 && length >= 5 && w[3] == 35)
            offsets.emplace_back(w[1], w[2], w[4]);
        i += length;
    }
    std::vector<SpirvField> out;
    for (const auto& [type, member, offset] : offsets) {
        const auto t = typeNames.find(type);
        const auto f = memberNames.find({type, member});
        if (t == typeNames.end() || f == memberNames.end() || t->second.rfind("Spot", 0) != 0)
            continue;
        out.push_back({t->second, f->second, offset});
    }
    return out;
}

} // namespace

TEST(SharedLayout, EveryFieldOffsetTheShadersUseIsTheHosts) {
    const Module modules[] = {SPOT_MODULE(spv_baked_march_comp),
                              SPOT_MODULE(spv_baked_peel_frag),
                              SPOT_MODULE(spv_baked_shell_comp),
                              SPOT_MODULE(spv_baked_tet_vert),
                              SPOT_MODULE(spv_generate_jittered_comp),
                              SPOT_MODULE(spv_generate_poisson_comp),
                              SPOT_MODULE(spv_generate_scan_comp),
                              SPOT_MODULE(spv_generate_scatter_comp),
                              SPOT_MODULE(spv_raymarch_bin_comp),
                              SPOT_MODULE(spv_raymarch_march_comp),
                              SPOT_MODULE(spv_raymarch_resolve_comp),
                              SPOT_MODULE(spv_sort_apply_comp),
                              SPOT_MODULE(spv_sort_histogram_comp),
                              SPOT_MODULE(spv_sort_reduce_comp),
                              SPOT_MODULE(spv_sort_scan_comp),
                              SPOT_MODULE(spv_sort_scatter_comp),
                              SPOT_MODULE(spv_splat_closest_frag),
                              SPOT_MODULE(spv_splat_compact_comp),
                              SPOT_MODULE(spv_splat_instanced_frag),
                              SPOT_MODULE(spv_splat_mesh_frag),
                              SPOT_MODULE(spv_splat_mesh_vert),
                              SPOT_MODULE(spv_splat_oit_frag),
                              SPOT_MODULE(spv_splat_prepare_comp),
                              SPOT_MODULE(spv_splat_quad_vert),
                              SPOT_MODULE(spv_splat_resolve_hybrid_fixed_comp),
                              SPOT_MODULE(spv_splat_resolve_hybrid_pass_comp),
                              SPOT_MODULE(spv_splat_resolve_instanced_comp),
                              SPOT_MODULE(spv_splat_roofline_frag),
                              SPOT_MODULE(spv_splat_small_hybrid_comp),
                              SPOT_MODULE(spv_splat_small_instanced_comp),
                              SPOT_MODULE(spv_splat_sorted_frag),
                              SPOT_MODULE(spv_splat_sorted_keys_comp),
                              SPOT_MODULE(spv_splat_compact_small_comp),
                              SPOT_MODULE(spv_splat_oit_closest_frag),
                              SPOT_MODULE(spv_splat_small_oit_comp),
                              SPOT_MODULE(spv_splat_resolve_copy_comp),
                              SPOT_MODULE(spv_splat_resolve_oit_comp),
                              SPOT_MODULE(spv_splat_resolve_oit_fixed_comp),
                              SPOT_MODULE(spv_splat_resolve_hybrid_comp),
                              SPOT_MODULE(spv_generate_poisson_partial_comp),
                              SPOT_MODULE(spv_generate_jittered_partial_comp),
                              SPOT_MODULE(spv_generate_poisson_groom_comp),
                              SPOT_MODULE(spv_generate_jittered_groom_comp),
                              SPOT_MODULE(spv_generate_poisson_groom_partial_comp),
                              SPOT_MODULE(spv_generate_jittered_groom_partial_comp),
                              SPOT_MODULE(spv_baked_march_2_comp),
                              SPOT_MODULE(spv_baked_march_3_comp),
                              SPOT_MODULE(spv_baked_march_4_comp),
                              SPOT_MODULE(spv_baked_march_lit_comp)};
    const auto host = hostOffsets();
    std::map<std::string, int> checked; // fields compared, per struct
    for (const Module& m : modules) {
        ASSERT_GT(m.count, 5u) << m.name;
        ASSERT_EQ(m.words[0], 0x07230203u) << m.name << ": not SPIR-V";
        for (const SpirvField& f : spirvOffsets(m)) {
            const auto it = host.find({f.type, f.field});
            ASSERT_NE(it, host.end()) << m.name << ": " << f.type << "." << f.field
                                      << " is not in this test's table (add it, and assert it)";
            EXPECT_EQ(f.offset, it->second) << m.name << ": " << f.type << "." << f.field;
            ++checked[f.type];
        }
    }
    // The shaders the build compiled use (nearly) every shared struct in a buffer or a push
    // constant block; these must have been compared at least once.
    for (const char* type :
         {"SpotCell", "SpotPiece", "SpotImpulse", "SpotLobe", "SpotWorldLobe", "SpotField",
          "SpotGenParams", "SpotSplatFrame", "SpotMeshVertex", "SpotScreenLobe", "SpotKernelBound",
          "SpotSortPush", "SpotGenPush", "SpotMarchParams", "SpotMarchPush", "SpotBakedTet",
          "SpotBakedParams", "SpotBakedList"})
        EXPECT_GT(checked[type], 0) << type << ": no shader decorated its offsets";
}
