// Helpers shared by the editor tests: a session on the furry bunny with validation on, impulse
// comparisons, the spotshell process.
#pragma once

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <unistd.h>

#include <gtest/gtest.h>

#include "cli_run.h"
#include "editor/edit_session.h"
#include "noise/camera.h"
#include "noise/impulses.h"
#include "splat/context_vk.h"

namespace spot::test {

inline std::filesystem::path bunnyScene() {
    return std::filesystem::path(SPOT_SOURCE_DIR) / "presets/scenes/fur-bunny.json";
}

inline std::filesystem::path tmpPath(const std::string& name) {
    return std::filesystem::path(SPOT_TEST_TMP_DIR) / name;
}

/// The bunny at `size` x `size` with Vulkan validation on.
inline edit::SessionOptions editOptions(int size = 256) {
    edit::SessionOptions o;
    o.width = o.height = size;
    o.context.validation = true;
    return o;
}

inline void expectNoValidationErrors(const splat::Context& ctx) {
    EXPECT_EQ(ctx.validation().errors, 0u) << ctx.validation().firstError;
}

/// Bitwise equality of everything an impulse carries.
inline bool sameImpulse(const noise::Impulse& a, const noise::Impulse& b) {
    return a.position == b.position && a.normal == b.normal && a.comb == b.comb &&
           a.frame == b.frame && a.scale == b.scale && a.color == b.color && a.weight == b.weight &&
           a.bend == b.bend && a.height == b.height && a.triangle == b.triangle &&
           a.barycentric == b.barycentric && a.cell == b.cell &&
           a.clumpStrength == b.clumpStrength && a.clumpDistance == b.clumpDistance;
}

inline void expectSameImpulses(const std::vector<noise::Impulse>& a,
                               const std::vector<noise::Impulse>& b, const char* what) {
    ASSERT_EQ(a.size(), b.size()) << what;
    std::size_t differ = 0;
    for (std::size_t i = 0; i < a.size(); ++i)
        differ += !sameImpulse(a[i], b[i]);
    EXPECT_EQ(differ, 0u) << what << ": impulses that differ of " << a.size();
}

/// Every active voxel of a grid, in tree order.
inline std::vector<std::pair<glm::ivec3, glm::vec3>> voxels(const noise::PaintedGrid* grid) {
    std::vector<std::pair<glm::ivec3, glm::vec3>> out;
    if (grid)
        grid->forEachActive([&](glm::ivec3 ijk, glm::vec3 v) { out.emplace_back(ijk, v); });
    return out;
}

/// World radius of a brush of `radiusPx` pixels at a hit, as the session converts it.
inline float worldRadius(const edit::Session& s, const edit::Hit& hit, float radiusPx) {
    return float(radiusPx * noise::CameraRays(s.camera()).pixelFootprint(hit.distance));
}

/// Run spotshell with `args`; the exit code, stderr in `err`.
inline int spotshell(const std::string& args, std::string* err = nullptr) {
    const CliResult r = runSpotshell(args + " >/dev/null");
    if (err)
        *err = r.err;
    return r.code;
}

inline void writeText(const std::filesystem::path& file, const std::string& text) {
    std::ofstream out(file, std::ios::binary);
    out << text;
}

} // namespace spot::test
