/// @file painted.h
/// @brief The painted field: values the editor paints on the surface, stored in a sparse
/// OpenVDB grid over world space (no uv needed), and its `.vdb` files.
///
/// A grid holds 1 component (openvdb::FloatGrid, scalars in `.x`) or 3 (openvdb::Vec3SGrid) per
/// voxel, with a uniform linear transform: the value of index ijk sits at world ijk x voxelSize
/// (OpenVDB's convention: voxel centres on the lattice, no offset). Inactive voxels read the
/// background. Between voxels the field is the trilinear interpolation of the 8 surrounding
/// voxels; `sample` is exactly what the generator evaluates on the CPU and the GPU (the flattened
/// form of docs/design.md section 3, shaders/spot_generate.h spotFieldEval kind 5).
///
/// OpenVDB's headers stay inside painted.cpp.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include <glm/glm.hpp>

namespace spot::gpu {
struct SpotField;
}

namespace spot::noise {

/// What a painted grid may hold once flattened for the generator: leaves x 512 voxels x
/// components floats. Reading refuses files above it (checked on the active voxel count before
/// anything is flattened).
inline constexpr std::uint64_t kMaxPaintedBytes = 1ull << 30;

class PaintedGrid {
public:
    /// An empty grid (every voxel reads `background`). `components` is 1 or 3; `voxelSize` in
    /// world units, > 0 and finite. Throws InputError otherwise (naming the grid).
    PaintedGrid(std::string name, int components, float voxelSize, glm::vec3 background);
    PaintedGrid(PaintedGrid&&) noexcept;
    PaintedGrid& operator=(PaintedGrid&&) noexcept;
    PaintedGrid(const PaintedGrid&) = delete;
    PaintedGrid& operator=(const PaintedGrid&) = delete;
    ~PaintedGrid();

    const std::string& name() const;
    int components() const;
    float voxelSize() const;
    /// The value of every inactive voxel (scalars in `.x`, other components zero).
    glm::vec3 background() const;

    /// The voxel whose lattice point is nearest to `world`: round(world / voxelSize).
    glm::ivec3 nearestVoxel(glm::vec3 world) const;
    /// World position of voxel `v`'s value: v x voxelSize.
    glm::vec3 voxelPosition(glm::ivec3 v) const;

    /// The value of voxel `v`; the background when it is inactive.
    glm::vec3 get(glm::ivec3 v) const;
    bool active(glm::ivec3 v) const;
    /// Activates `v` with `value` (a scalar grid keeps `.x`).
    void set(glm::ivec3 v, glm::vec3 value);
    /// Deactivates `v`: it reads the background again.
    void clear(glm::ivec3 v);

    /// The trilinear interpolation of the 8 voxels around `world` (each the background when
    /// inactive): bit for bit what the generator's field evaluates. Flattens the grid on the
    /// first call after a change (thread-safe).
    glm::vec3 sample(glm::vec3 world) const;

    /// Counts the changes (set, clear): a field reading the grid rebuilds its form when it moved.
    std::uint64_t version() const;

    std::size_t activeCount() const;
    /// Calls `f` on every active voxel, in OpenVDB's tree order (deterministic for a grid's
    /// content).
    void forEachActive(const std::function<void(glm::ivec3, glm::vec3)>& f) const;
    /// Memory held by the OpenVDB tree.
    std::uint64_t memoryBytes() const;
    /// A deep copy (same name, values, activity).
    std::shared_ptr<PaintedGrid> clone() const;

    /// The flattened form the generator reads (docs/design.md section 3): the leaves' blocks of
    /// values and the hash table of their origins appended to `data`, described by the returned
    /// SpotField (kind 5). Throws InputError when the flattened grid would exceed
    /// kMaxPaintedBytes or 32-bit offsets.
    gpu::SpotField flatten(std::vector<float>& data) const;
    /// Componentwise bounds of every value `sample` can return (the active values and the
    /// background).
    void valueRange(glm::vec3& lo, glm::vec3& hi) const;

    struct Impl;

private:
    explicit PaintedGrid(std::unique_ptr<Impl> impl);
    friend PaintedGrid readPaintedGrid(const std::filesystem::path&, const std::string&, int);
    friend void writePaintedGrids(const std::filesystem::path&,
                                  const std::vector<const PaintedGrid*>&);
    void changed();

    std::unique_ptr<Impl> m_impl;
};

/// Read grid `grid` of `file` as a painted grid of `components` components. Throws InputError
/// with one line naming the file and the grid for: a missing, unreadable, corrupt or truncated
/// file; no grid of that name (the names present are listed); the wrong value type (FloatGrid
/// for 1 component, Vec3SGrid for 3); a transform that is not a uniform scale (rotated,
/// stretched, translated, or not linear); NaN or infinite values; more active voxels than
/// kMaxPaintedBytes allows.
PaintedGrid readPaintedGrid(const std::filesystem::path& file, const std::string& grid,
                            int components);

/// Write `grids` (distinct, non-empty names) to `file` atomically: a temporary file in the same
/// folder, then a rename over `file`. On failure the temporary file is removed, `file` is left as
/// it was, and InputError names the file.
void writePaintedGrids(const std::filesystem::path& file,
                       const std::vector<const PaintedGrid*>& grids);

} // namespace spot::noise
