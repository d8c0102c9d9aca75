/// @file edit_brush.h
/// @brief The editor's brushes: what a dab of each kind does to the voxels of a painted grid
/// near the surface, and the sparse record of what it changed (the undo delta).
///
/// A brush paints a slot's paint layer (noise::PaintLayer), never the field under it: density
/// brushes its multiplier and raise, the others a weighted override ("over" compositing of the
/// brush's target with weight strength x falloff onto the layer's value and weight).
///
/// Units: the brush radius is in window pixels (converted to world units at the hit depth by the
/// session), a dab's centre and radius in world units, the tilt in degrees, the colour linear
/// RGB. A dab only touches voxels whose lattice point lies within one voxel diagonal of the
/// surface (the 8 voxels the trilinear lookup of any surface point reads: noise/painted.h) and
/// within the dab's radius less a voxel diagonal of its centre: every point whose lookup reads a
/// written voxel lies inside the dab's radius, so the field beyond it stays bit for bit.
#pragma once

#include <cstddef>
#include <cstdint>
#include <map>
#include <string>
#include <string_view>
#include <tuple>
#include <vector>

#include <glm/glm.hpp>

#include "noise/field.h"
#include "noise/mesh.h"
#include "noise/painted.h"
#include "noise/preset.h"

namespace spot::edit {

enum class BrushKind {
    DensityAdd,
    DensityErase,
    Comb,
    Tilt,
    Length,
    Color,
    Smooth,
    Clump,     ///< the clump strength towards 1 (negative strength: towards 0)
    ClumpSize, ///< the relative clump size x 1.25 per dab (negative strength: x 0.75)
    Mask,      ///< the mask towards 1 (negative strength: towards 0, unmasking)
};
inline constexpr int kBrushKindCount = 10;
enum class Falloff { Smooth, Linear, Constant };
/// Where a brush paints: everywhere, only where the mask is set (each voxel's weight times the
/// mask m there), or only where it is not (times 1 - m). A voxel where that factor is 0 is not
/// written, so nothing outside changes.
enum class MaskLimit { None, Masked, Unmasked };

/// The painted slots of a preset, in the order the preset's `fields` lists them.
enum class Slot { Density, Comb, Tilt, Scale, Color, Clump, ClumpSize, Mask };
inline constexpr int kSlotCount = 8;

/// The generator's field slot a painted slot is (SPOT_FIELD_*: an index into noise::kFieldSlots).
int slotField(Slot slot);
/// `density`, `comb`, `tilt_deg`, `scale`, `color`: the slot's key under the preset's `fields`
/// (also the grid's name in the .vdb file; noise::kFieldSlots).
const char* slotKey(Slot slot);
/// 1 or 3 (noise::kFieldSlots).
int slotComponents(Slot slot);

/// "density-add", ...; parse throws InputError listing the kinds.
const char* brushKindName(BrushKind kind);
BrushKind parseBrushKind(std::string_view name);
const char* falloffName(Falloff falloff);
Falloff parseFalloff(std::string_view name);
/// "none", "masked", "unmasked"; parse throws InputError listing them.
const char* maskLimitName(MaskLimit limit);
MaskLimit parseMaskLimit(std::string_view name);
/// The factor a dab's weight takes at a point where the mask reads `mask`.
float maskLimitFactor(MaskLimit limit, float mask);

struct BrushSettings {
    BrushKind kind = BrushKind::DensityAdd;
    float radiusPx = 30.0f; ///< window pixels
    /// [-1, 1]; negative inverts where it means something (length shrinks, tilt lifts towards 0).
    float strength = 1.0f;
    Falloff falloff = Falloff::Smooth;
    bool mirrorX = false;       ///< also paint the dab mirrored about x = 0 (mesh space)
    bool frontFacesOnly = true; ///< skip voxels whose surface faces away from the camera
    glm::vec3 color{1.0f};      ///< Color: linear RGB
    /// DensityAdd: also raise the density above the field under the layer, towards 1 (the
    /// layer's raise); otherwise adding only undoes erasing (the multiplier towards 1).
    bool raise = false;
    /// Smooth: the slot it averages (the other kinds imply theirs).
    Slot smoothTarget = Slot::Density;
    /// Where the brush paints (the mask brush itself ignores it).
    MaskLimit limit = MaskLimit::None;
};

/// The slot a brush paints.
Slot brushSlot(const BrushSettings& brush);

/// Weight of a dab at relative distance t = d / radius in [0, 1]: smooth 1 - (3t^2 - 2t^3),
/// linear 1 - t, constant 1; 0 beyond the radius.
float falloffWeight(Falloff falloff, float t);

/// One dab in world units.
struct Dab {
    glm::vec3 centre{0.0f};
    float radius = 0.0f;
    glm::vec3 eye{0.0f};       ///< camera position, for the front-face test
    glm::vec3 direction{0.0f}; ///< Comb: the drag direction in world units (any length)
};

/// A voxel near the surface: its index and the closest surface point (position, normal,
/// tangent, uv: what a field is evaluated at).
struct SurfaceVoxel {
    glm::ivec3 ijk{0};
    noise::SurfacePoint point;
    float distance = 0.0f; ///< lattice point to the surface, world units
};

/// The mesh's triangles as boxes, for the voxel queries.
class SurfaceIndex {
public:
    explicit SurfaceIndex(const noise::Mesh& mesh);
    /// Voxels of the lattice `voxelSize` within `radius` of `centre` and within one voxel
    /// diagonal of the surface, each with its closest surface point. Sorted by ijk
    /// (deterministic).
    std::vector<SurfaceVoxel> voxelsNear(glm::vec3 centre, float radius, float voxelSize) const;
    const noise::Mesh& mesh() const { return m_mesh; }

private:
    const noise::Mesh& m_mesh;
    std::vector<glm::vec3> m_lo, m_hi;
};

/// What a stroke changed in one layer: per voxel the state (value in xyz, weight in w) before its
/// first change and after its last one.
struct VoxelChange {
    glm::vec4 before{0.0f}, after{0.0f};
    bool activeBefore = false, activeAfter = false;
};
struct IjkLess {
    bool operator()(const glm::ivec3& a, const glm::ivec3& b) const {
        return std::tie(a.x, a.y, a.z) < std::tie(b.x, b.y, b.z);
    }
};
using GridDelta = std::map<glm::ivec3, VoxelChange, IjkLess>;

/// Bytes a delta holds (the undo budget counts these).
std::size_t deltaBytes(const GridDelta& delta);
/// Set every voxel of `delta` to its `after` (redo) or `before` (undo) state.
void applyDelta(noise::PaintLayer& layer, const GridDelta& delta, bool after);

/// Apply one dab of `brush` to `layer` (the brush's slot's), recording every change in `delta`
/// and, when given, appending the voxels written to `touched`. `base` is the field under the
/// layer (null: the surface tangent), which the length and clump-size brushes scale. `mask` is
/// the mask field (its base and paint) the brush's limit reads at each voxel's surface point
/// (null: no limit). Returns the number of voxels written.
std::size_t applyDab(const BrushSettings& brush, const Dab& dab, const SurfaceIndex& surface,
                     noise::PaintLayer& layer, const noise::Field* base, GridDelta& delta,
                     std::vector<glm::ivec3>* touched = nullptr,
                     const noise::Field* mask = nullptr);

} // namespace spot::edit
