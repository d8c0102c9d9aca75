/// @file bench_bake.h
/// @brief The bakes `spotshell bench` renders with the `baked` method: made by the bench itself
/// (noise/bake.h), cached in DIR/cache under a key of everything that determines them.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>

namespace spot::noise {
struct Mesh;
class ImpulseGenerator;
} // namespace spot::noise

namespace spot::cmd {

/// Bump when the bake's content changes (noise/bake.cpp's evaluation or file layout), so that
/// cached bakes are not reused.
inline constexpr int kBenchBakeVersion = 1;

/// Everything that determines a bake: the impulses (mesh, preset, seed: what the scene's
/// ImpulseGenerator is made from) and the lattice. The scene's camera, image size and shading do
/// not enter: scenes that differ only in those share their bakes.
struct BenchBakeInputs {
    std::string mesh;   ///< the mesh file's bytes (or the `generated:NAME` spec)
    std::string preset; ///< the preset file's JSON text
    std::uint32_t seed = 0;
    float voxelSize = 0.0f; ///< level 0's
    int levels = 1;
};

/// The cache key: 16 hex digits of a hash of kBenchBakeVersion and every input (the voxel size
/// by its bits).
std::string benchBakeKey(const BenchBakeInputs& inputs);

/// The longest side of the mesh's bounding box, world units (0 for an empty mesh).
double meshLongestSide(const noise::Mesh& mesh);

/// Level 0's voxel size for `resolution` voxels along the mesh's longest side; InputError for a
/// mesh without extent.
float voxelSizeForResolution(const noise::Mesh& mesh, int resolution);

struct BenchBake {
    std::filesystem::path file; ///< the OpenVDB file
    double seconds = 0.0;       ///< the bake's (noise::BakeStats::seconds), also when cached
    std::uint64_t bytes = 0;    ///< the file's size
    bool cached = false;        ///< found in the cache, not baked by this call
};

/// The bake of `inputs` from `cacheDir` (bake-KEY.vdb with bake-KEY.json beside it, recording
/// the bake's seconds), or baked from `generator` (made from the same mesh, preset and seed) and
/// written there atomically: the .vdb first, then the .json, so a bake counts as cached only
/// once both are complete. InputError when the bake is refused (the memory budget, the
/// lattice's size).
BenchBake benchBake(const std::filesystem::path& cacheDir, const noise::ImpulseGenerator& generator,
                    const BenchBakeInputs& inputs, const std::string& presetName);

} // namespace spot::cmd
