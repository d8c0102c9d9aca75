/// @file bake_data.h
/// @brief The bake `baked` renders, as a resource: read from its OpenVDB file (noise/bake.h) once
/// and packed on the host into what the march reads (baked_layout.glsl): the density bricks of
/// every mip level with their aprons, the distance grid's leaves and the dense leaf tables. A
/// BakedRenderer uploads a BakeData the first time it is handed one (RenderSettings::bake) and
/// keeps it while the same one is handed again: a frame reads no file.
///
/// No Vulkan here: the device's limits (storage-buffer range, memory budget) are checked when the
/// renderer uploads.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "shaders/spot_layout.hpp"

namespace spot::splat {

namespace gpu_baked {
using glm::ivec3;
using glm::ivec4;
using glm::min;
using glm::uvec2;
using glm::uvec3;
using glm::uvec4;
using glm::vec4;
using uint = std::uint32_t;
#define SPOT_CONST inline constexpr
#define SPOT_FN inline
#include "shaders/baked_layout.glsl"
#undef SPOT_CONST
#undef SPOT_FN
static_assert(sizeof(SpotBakedTet) == 176);
static_assert(sizeof(SpotBakedLight) == 32);
static_assert(sizeof(SpotBakedParams) == 432 + 5 * 16 + kBakedMaxLights * 32);
} // namespace gpu_baked

/// Loop iterations one march invocation may need by default (baked_march.comp).
inline constexpr std::uint32_t kBakedMarchLoopBudget = gpu_baked::kBakedLoopBudget;
/// Most peel passes accepted.
inline constexpr int kBakedMaxPeelPasses = 64;

/// One level's density bricks as the march reads them (baked_layout.glsl): a brick for every leaf
/// whose apron (the leaf and the first voxels of its +x, +y and +z neighbours, 9^3 voxels) holds
/// a stored voxel, that is every stored leaf and its -x, -y, -z neighbours, in the order first
/// met walking `leaves`; each voxel vec4(extinction x colour, extinction) / unit as two
/// packHalf2x16 words, 0 where no stored leaf holds it.
struct ApronBricks {
    std::vector<glm::ivec3> leaves; ///< brick b's leaf
    std::vector<glm::uvec2> voxels; ///< brick b's at [b x 729, +729), (x * 9 + y) * 9 + z
};
/// `leaves`: the level's stored leaves (distinct); `data`: 512 values per leaf, voxel xyz of
/// leaf i at i x 512 + (x << 6 | y << 3 | z); `unit`: what a stored 1 is (> 0).
ApronBricks packApronBricks(const std::vector<glm::ivec3>& leaves,
                            const std::vector<glm::vec4>& data, float unit);
/// The unit of a bake's bricks: its largest magnitude over 32,768 (the half floats' range, with
/// room to spare), never below the smallest normal float; 1 for an empty bake.
float brickUnit(float largest);

/// The lit march's solid (baked_layout.glsl, kBakedBindSolid): over the voxels [lo, lo + n) of
/// edge `size` (world units; voxel ijk's centre at (ijk + 1/2) size), a bit per voxel, bit
/// (z n.y + y) n.x + x of the words, set where the voxel's centre lies inside the mesh
/// (`positions`, `triangles`): an odd number of the triangles lies on the ray from the centre
/// towards +x. A mesh that is not closed gives what the crossings give.
std::vector<std::uint32_t> solidVoxels(const std::vector<glm::vec3>& positions,
                                       const std::vector<glm::uvec3>& triangles, glm::ivec3 lo,
                                       glm::ivec3 n, float size);

/// A bake packed for the march, read from one file.
class BakeData {
public:
    /// Reads and packs `file`; InputError, one line naming the file, for a missing or bad one.
    static std::shared_ptr<const BakeData> load(const std::string& file);

    std::string file;       ///< where it was read from
    int levels = 0;         ///< mip levels
    float voxelSize = 0.0f; ///< level 0's, world units
    float unit = 1.0f;      ///< what a stored 1 in the density bricks is (brickUnit)
    /// The shell hash the bake records (noise::shellHash); none in an older bake.
    std::optional<std::uint64_t> meshHash;
    /// Per level, its bricks (packApronBricks' voxels), in brick order; level l's are bricks
    /// [firstBrick[l], + packed[l].size() / kBakedBrickVoxels) of the whole.
    std::vector<std::vector<glm::uvec2>> packed;
    /// Whether the bake holds the shading grids (noise::BakedVolume::hasShading): lit scenes
    /// need them.
    bool shaded = false;
    /// Per level, the shading bricks, one per density brick in the same order and layout:
    /// vec4(extinction x (tangent + normal), 0) / unit per voxel (the shading grids of
    /// noise/bake.h; a kernel of one model has one of the two). Empty when not `shaded`.
    std::vector<std::vector<glm::uvec2>> shadingPacked;
    std::vector<std::uint32_t> firstBrick;
    std::uint64_t brickCount = 0; ///< over every level
    /// The distance grid's leaves (kBakedLeafVoxels floats each) and their count.
    std::vector<float> distances;
    std::uint32_t distanceBricks = 0;
    /// The leaf tables of every section (the levels, then the distance grid), one int per leaf of
    /// each section's box (the brick, or kBakedEmptySlot), and where each section's box is.
    std::vector<std::int32_t> table;
    std::vector<glm::ivec4> leafOrigin, leafDims; ///< per section id (kBakedSections)
    /// Per section in table order: the table's size after it, and its box in leaves (for the
    /// message when a table outgrows one storage buffer).
    std::vector<std::uint64_t> tableEnd;
    std::vector<glm::i64vec3> sectionBox;
};

} // namespace spot::splat
