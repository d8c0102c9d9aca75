/// @file bake.h
/// @brief The bake: the noise's extinction and colour evaluated into sparse voxel mip levels in
/// the mesh's rest pose, and their OpenVDB files (docs/design.md section 5).
///
/// Voxels are cell-centred boxes: voxel ijk of level l spans [ijk, ijk + 1) x voxelSize(l) in
/// world units and holds the noise at its centre (ijk + 1/2) x voxelSize(l); voxelSize(l) =
/// voxelSize(0) x 2^l, so the 2x2x2 voxels 2 ijk + {0, 1}^3 of level l make voxel ijk of level
/// l + 1. Level 0 is evaluated exactly as the reference renderer integrates the noise
/// (noise/reference.h): extinction sum_i sigma_i(x) over every lobe, colour the
/// extinction-weighted mean sum_i sigma_i(x) c_i / sum_i sigma_i(x). Only voxels whose centre
/// lies in the shell (the surface cells and their 26 neighbours: every place a kernel reaches)
/// are evaluated, and only those with non-zero extinction are stored. A coarser level holds the
/// mean extinction of its 8 children (empty ones count 0), so the optical depth through it along
/// an axis is the mean of the finer optical depths over its cross-section, and the
/// extinction-weighted mean of their colours; alpha is never averaged.
///
/// The distance grid (level 0's voxels) holds, per voxel, the Chebyshev (L-infinity) distance in
/// level-0 voxels to the nearest non-empty voxel, capped at kBakeDistanceCap (its background): a
/// ray from anywhere in a voxel of distance d may advance (d - 1) voxel widths without entering a
/// non-empty voxel's box.
///
/// The shading grids (lit scenes, docs/design.md "Lighting"), per level: `tangent`, the strand
/// lobes' tangents (placedShadingAxis: unit, world space, root to tip) summed weighted by their
/// extinction over the voxel's whole extinction, sum_strand sigma_i t_i / sum_all sigma_i, and
/// `normal`, the same over the flake lobes' normals (turned to their surface's side). A voxel
/// of one strand holds its unit tangent; strands that cross, or lobes of other models, shorten
/// it. Coarser levels take their children's extinction-weighted mean, as the colour does. Only
/// non-zero vectors are stored (a bake of strands has an empty `normal` grid).
///
/// OpenVDB's headers stay inside bake.cpp.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <glm/glm.hpp>

namespace spot::noise {

struct Impulse;
struct Kernel;
struct Mesh;
struct SurfaceCells;
class ImpulseGenerator;

/// Levels a bake may hold (level 0 and up to 7 coarser ones).
inline constexpr int kMaxBakeLevels = 8;
/// The distance grid's cap and background, in level-0 voxels.
inline constexpr float kBakeDistanceCap = 4.0f;
/// A bake's voxel lattice may span at most this many voxels per axis (OpenVDB coordinates are
/// 32-bit; far beyond any practical bake).
inline constexpr double kMaxBakeVoxelsPerAxis = double(1 << 24);

/// FNV-1a's 64-bit offset basis: the hash of nothing.
inline constexpr std::uint64_t kFnv1a64Basis = 0xcbf29ce484222325ull;
/// FNV-1a, 64 bits, of `text` continued from `hash` (the hash of what came before): the preset
/// hash a bake records (of the preset file's JSON text).
std::uint64_t fnv1a64(std::string_view text, std::uint64_t hash = kFnv1a64Basis);

/// The hash of `mesh` as loaded (its rest pose): FNV-1a over the position and triangle counts
/// (64 bits each), the positions (3 floats each) and the triangles (3 uint32 each), as stored in
/// memory (little-endian). Normals, uvs and attributes do not enter: the shell does not read them.
std::uint64_t meshHash(const Mesh& mesh);
/// The shell hash a bake records and `baked` checks (spotshell_mesh_hash): `meshHash` continued
/// with the cell size's 4 bytes. The bake's voxels are the noise in the rest pose of this mesh's
/// shell, whose thickness is the cell size (the surface cells and their neighbours); a bake
/// rendered on another mesh (or cell size) maps its voxels onto the wrong places.
std::uint64_t shellHash(std::uint64_t meshHash, float cellSize);

struct BakeOptions {
    float voxelSize = 0.0f;       ///< level 0's voxel edge, world units, > 0
    int levels = 1;               ///< [1, kMaxBakeLevels]
    std::uint64_t presetHash = 0; ///< recorded in the file (fnv1a64 of the preset's JSON text)
    std::string presetName;       ///< recorded in the file
    /// Recorded in the file when set (shellHash of the rest mesh and the cell size).
    std::optional<std::uint64_t> meshHash;
};

/// What a bake will need, known before anything large is allocated.
struct BakeEstimate {
    std::size_t shellCells = 0;     ///< surface cells and their neighbours
    std::uint64_t shellVoxels = 0;  ///< level-0 voxels evaluated (an upper bound)
    std::uint64_t scratchBytes = 0; ///< the workers' per-cell buffers
    /// Peak memory the bake may use (an upper bound). From estimateBake: the worst case, every
    /// shell voxel non-empty. After bakeImpulses: from the counted non-empty voxels.
    std::uint64_t bytes = 0;
    std::uint64_t nonEmptyVoxels = 0; ///< counted by bakeImpulses before the values
    std::uint64_t distanceVoxels = 0; ///< bakeImpulses' upper bound of the distance grid
};

struct BakeStats {
    double seconds = 0.0;
    std::size_t impulses = 0;
    std::size_t lobes = 0;
    std::uint64_t evaluatedVoxels = 0;       ///< level-0 voxel centres evaluated
    std::vector<std::uint64_t> activeVoxels; ///< non-empty voxels per level
    std::uint64_t distanceVoxels = 0;        ///< voxels stored in the distance grid
    BakeEstimate estimate;
};

/// A bake in memory: per level a density (extinction, 1/world unit) grid and a colour (linear
/// RGB) grid, and the distance grid. Voxels outside the stored ones read 0 density, black and
/// kBakeDistanceCap.
class BakedVolume {
public:
    BakedVolume(BakedVolume&&) noexcept;
    BakedVolume& operator=(BakedVolume&&) noexcept;
    BakedVolume(const BakedVolume&) = delete;
    BakedVolume& operator=(const BakedVolume&) = delete;
    ~BakedVolume();

    int levels() const;
    /// World units; voxelSize(0) x 2^level.
    float voxelSize(int level) const;
    /// World position of the centre of voxel `ijk` of `level`: (ijk + 1/2) x voxelSize(level).
    glm::dvec3 voxelCentre(int level, glm::ivec3 ijk) const;
    /// Extinction of voxel `ijk` of `level`, 1/world unit (0 when empty).
    float density(int level, glm::ivec3 ijk) const;
    /// Colour of voxel `ijk` of `level`, linear RGB (black when empty).
    glm::vec3 color(int level, glm::ivec3 ijk) const;
    /// Whether the bake holds the shading grids (tangent, normal); a bake written before them
    /// does not, and renders unlit scenes only.
    bool hasShading() const;
    /// The shading grids' vectors at voxel `ijk` of `level` (zero when not stored, or without
    /// shading grids): the strand tangent and the flake normal, weighted as the file comment says.
    glm::vec3 tangent(int level, glm::ivec3 ijk) const;
    glm::vec3 normal(int level, glm::ivec3 ijk) const;
    /// Distance of level-0 voxel `ijk` to the nearest non-empty one, level-0 voxels, capped.
    float distance(glm::ivec3 ijk) const;
    /// Non-empty voxels of `level`.
    std::uint64_t activeCount(int level) const;
    std::uint64_t distanceCount() const;
    /// Calls `f` on every non-empty voxel of `level` in OpenVDB's tree order (deterministic for
    /// the grids' content).
    void forEachActive(int level, const std::function<void(glm::ivec3, float, glm::vec3)>& f) const;
    /// forEachActive with the shading grids' vectors at each voxel (tangent, then normal; zero
    /// without shading grids).
    void forEachActiveShaded(
        int level,
        const std::function<void(glm::ivec3, float, glm::vec3, glm::vec3, glm::vec3)>& f) const;
    /// The bounds, in voxels of `level`, of its non-empty voxels (lo > hi when there are none).
    void activeBounds(int level, glm::ivec3& lo, glm::ivec3& hi) const;
    std::uint64_t presetHash() const;
    const std::string& presetName() const;
    /// The shell hash recorded (shellHash); none in a bake written before it was recorded.
    std::optional<std::uint64_t> meshHash() const;
    /// The spotshell version that wrote the bake.
    const std::string& version() const;
    /// Memory held by the OpenVDB trees.
    std::uint64_t memoryBytes() const;

    struct Impl;

private:
    explicit BakedVolume(std::unique_ptr<Impl> impl);
    friend BakedVolume bakeImpulses(const SurfaceCells&, const Kernel&, const std::vector<Impulse>&,
                                    const BakeOptions&, const std::function<void(long, long)>&,
                                    BakeStats*);
    friend BakedVolume readBakedGrids(const std::filesystem::path&);
    friend void writeBakedGrids(const std::filesystem::path&, const BakedVolume&);

    std::unique_ptr<Impl> m_impl;
};

/// What baking `cells` at `options` needs. Throws InputError for a voxel size that is not finite
/// and positive, a level count outside [1, kMaxBakeLevels], or a lattice of more than
/// kMaxBakeVoxelsPerAxis voxels along an axis.
BakeEstimate estimateBake(const SurfaceCells& cells, const BakeOptions& options);

/// Bake `impulses` (each in its generating cell `Impulse::cell`, one of `cells`; the kernel
/// reaching at most the 3x3x3 cells around it) into `options.levels` levels. Memory is checked
/// against the budget (requireMemory) before each large allocation, so an oversized request is
/// refused (InputError) before it allocates: at once when a level-0 grid of the voxels in the
/// lobes' boxes cannot fit, otherwise after counting the non-empty voxels (a pass over the
/// lobes without values), from that count. Parallel over cells with oneTBB;
/// the result is identical for any thread count. `progress(done, total)` (may be empty) is
/// called from worker threads as cells finish, each cell twice (counted, then evaluated).
BakedVolume bakeImpulses(const SurfaceCells& cells, const Kernel& kernel,
                         const std::vector<Impulse>& impulses, const BakeOptions& options,
                         const std::function<void(long, long)>& progress = {},
                         BakeStats* stats = nullptr);

/// Bake every impulse `generator` makes (all cells): the options are checked first, then the
/// impulses are generated and baked.
BakedVolume bakeNoise(const ImpulseGenerator& generator, const BakeOptions& options,
                      const std::function<void(long, long)>& progress = {},
                      BakeStats* stats = nullptr);

/// Grid names in a bake file: "density", "color", "tangent", "normal" for level 0,
/// "density_lod1", "color_lod1", "tangent_lod1", "normal_lod1", ... for the coarser ones, and
/// "distance".
std::string bakedDensityName(int level);
std::string bakedColorName(int level);
std::string bakedTangentName(int level);
std::string bakedNormalName(int level);
inline constexpr const char* kBakedDistanceName = "distance";

/// Write `volume` to `file` (one OpenVDB file) atomically: a temporary file in the same folder,
/// then a rename. Density grids are fog volumes (openvdb::GRID_FOG_VOLUME). Every grid and the
/// file carry the metadata spotshell_level (grids), spotshell_levels, spotshell_voxel_size
/// (of level 0 for the file, of the grid's level for a grid), spotshell_preset_hash (16 hex
/// digits), spotshell_preset, spotshell_version; the distance grid also spotshell_distance_units.
/// On failure InputError names the file and the old file is left as it was.
void writeBakedGrids(const std::filesystem::path& file, const BakedVolume& volume);

/// Read a bake file. Throws InputError with one line naming the file (and the grid) for: a
/// missing, unreadable, corrupt or truncated file; a missing grid (the names present are
/// listed); a grid of the wrong value type; a level count outside [1, kMaxBakeLevels]; a
/// transform or voxel size that does not match the level; NaN or infinite values. Each grid's
/// byte range (its descriptor's offsets) is checked against the file's size before OpenVDB
/// reads it (requireVdbGridsInFile). A file without spotshell_mesh_hash (older) reads without
/// one (meshHash() empty); a file without a "tangent" grid (older) reads without shading grids
/// (hasShading() false); one with it must hold every level's tangent and normal grids.
BakedVolume readBakedGrids(const std::filesystem::path& file);

/// Reads the grid descriptors of the .vdb `file` (as openvdb::io::File::open does) and throws
/// InputError, one line naming the file and the grid, when a grid's byte range (start, data
/// blocks, end) is out of order or reaches past the end of the file: OpenVDB itself would read
/// sizes from past the end of a truncated file (a compressed size of terabytes) and allocate
/// them. Errors of OpenVDB's own (a bad header) propagate as its exceptions.
void requireVdbGridsInFile(const std::filesystem::path& file);

} // namespace spot::noise
