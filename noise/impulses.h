/// @file impulses.h
/// @brief Impulses generated on the fly in surface cells (docs/design.md section 2; paper eq. 2, 3.1).
///
/// For a constant density the impulses are uniform per unit of surface area, whatever the mesh's
/// orientation against the grid and its triangle sizes: a cell's expected candidate count is
/// density_max x (surface area inside the cell) and candidates are placed uniformly on the cell's
/// exact surface pieces. Each candidate passes the density test xi < d(p). Every random number is
/// a counter-based hash of (cell, candidate index, seed) (spot_shared.h), so the same seed gives
/// the same impulses on any thread count and on the GPU.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

#include <glm/glm.hpp>

#include "cells.h"
#include "field.h"
#include "kernel.h"
#include "preset.h"
#include "shaders/spot_layout.hpp"

namespace spot::shared::f32 {
struct GeneratorArrays;
}

namespace spot::noise {

struct Mesh;

/// One impulse: where a kernel is placed and how. World units unless stated.
struct Impulse {
    glm::vec3 position{0.0f};  ///< kernel origin: surface point + height * normal
    glm::vec3 normal{0.0f};    ///< unit surface normal at the anchor
    glm::vec3 comb{0.0f};      ///< unit comb direction in the tangent plane (before tilt/spin)
    glm::mat3 frame{1.0f};     ///< kernel space -> world rotation (columns: x, y, z after tilt, spin)
    glm::vec3 scale{1.0f};     ///< world units per kernel unit, per kernel axis
    glm::vec3 color{1.0f};     ///< multiplies each lobe's colour, linear RGB
    float weight = 1.0f;       ///< |w|, multiplies each lobe's extinction
    float bend = 0.0f;         ///< curvature, radians per kernel unit
    float height = 0.0f;       ///< offset along the normal
    std::uint32_t triangle = 0;          ///< anchor triangle
    glm::vec2 barycentric{0.0f};         ///< anchor (b1, b2) in that triangle; b0 = 1 - b1 - b2
    glm::ivec3 cell{0};                  ///< generating cell
    /// Clumps (spot_clump.h): the strength the kernel was clumped with (0: not clumped) and
    /// the distance from its anchor to its clump's centre, world units (0 when not clumped).
    float clumpStrength = 0.0f;
    float clumpDistance = 0.0f;
};

struct GeneratorOptions {
    std::uint32_t seed = 0;
    /// Cell edge h in world units; 0 picks the smallest valid one (the kernel's world support
    /// radius). A smaller explicit value is refused: kernels would reach past the 3x3x3
    /// neighbourhood that the renderers search.
    float cellSize = 0.0f;
    CellLimits limits;
};

/// Fields of a preset bound to one mesh, indexed by slot (kFieldSlots; null: an unset comb).
using BoundFields = std::array<std::unique_ptr<Field>, kFieldSlotCount>;

/// The height of a kernel's tip, kernel units: the top of its highest lobe (offset z plus its
/// z sigma), at least 1e-3. The clumps move the tip towards the clump's axis (spot_clump.h).
float clumpTipHeight(const KernelDesc& kernel);

class ImpulseGenerator {
public:
    /// Binds the preset's fields to the mesh, builds the kernel, picks and checks the cell size,
    /// builds the surface cells. Throws InputError on anything the user must fix.
    ImpulseGenerator(const Mesh& mesh, const PresetDesc& preset, const GeneratorOptions& options);
    ~ImpulseGenerator();

    const SurfaceCells& cells() const { return m_cells; }
    const Kernel& kernel() const { return m_kernel; }
    const PresetDesc& preset() const { return m_preset; }
    float cellSize() const { return m_cells.cellSize; }
    /// The mesh the impulses are generated on (its rest pose, as loaded).
    const Mesh& mesh() const { return m_mesh; }
    /// Smallest valid cell size for this preset: the kernel's world support radius plus the
    /// largest height offset.
    float minimumCellSize() const { return m_minCellSize; }

    /// Append the impulses of cell `cellIndex` to `out`, in a fixed order.
    void generateCell(std::size_t cellIndex, std::vector<Impulse>& out) const;

    /// What the shared generator reads (shaders/spot_generate.h), for the GPU to upload: pieces
    /// with cumulative areas, the fields' data array and the parameters.
    const std::vector<gpu::SpotPiece>& sharedPieces() const { return m_sharedPieces; }
    const std::vector<float>& sharedFieldData() const { return m_fieldData; }
    const gpu::SpotGenParams& sharedParams() const { return m_params; }
    /// Live field edits (the editor). Slots are numbered as SPOT_FIELD_* (shaders/spot_layout.h).
    /// The description bound to `slot`; null for an unset comb (the surface tangent).
    const FieldDesc* fieldDesc(int slot) const;
    /// Bind `desc` to `slot` (its component count must be the slot's: 3 for comb, scale and
    /// colour, 1 otherwise) and rebuild the shared field data and parameters. Throws InputError,
    /// leaving the generator as it was, when the field cannot be bound or a scale field would
    /// need a larger cell size than the generator's. Cells (and so a GpuGenerator's candidate
    /// counts) do not change; a GpuGenerator of this generator needs refreshFields() after it.
    void setField(int slot, const FieldDesc& desc);
    /// Rebuild the shared field data after a bound painted grid changed in place (same checks
    /// as setField).
    void refreshFields();

    /// The editor's mask overlay (a view, not the document): masked impulses are tinted
    /// towards red by the mask's value. Rebuilds the shared parameters (a GpuGenerator of this
    /// generator needs refreshFields() after it).
    void setMaskOverlay(bool on);
    bool maskOverlay() const { return m_maskOverlay; }

    /// Impulses of the cells accepted by `keep` (all cells when empty), concatenated in cell
    /// order; parallel over cells, identical for any thread count. Checks the memory budget first.
    std::vector<Impulse> generate(const std::function<bool(const SurfaceCell&)>& keep = {}) const;

private:
    void buildSharedData();
    void buildFieldData();
    /// Smallest valid cell size with `scale` as the scale field.
    float minimumCellSizeFor(const Field& scale) const;
    shared::f32::GeneratorArrays arrays() const;

    const Mesh& m_mesh;
    PresetDesc m_preset;
    GeneratorOptions m_options;
    Kernel m_kernel;
    BoundFields m_fields;
    float m_minCellSize = 0.0f;
    SurfaceCells m_cells;
    std::vector<gpu::SpotPiece> m_sharedPieces;
    std::vector<float> m_fieldData;
    gpu::SpotGenParams m_params{};
    bool m_maskOverlay = false;
};

} // namespace spot::noise
