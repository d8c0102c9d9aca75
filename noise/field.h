/// @file field.h
/// @brief Fields: the artist-controlled quantities (density, orientation, scale, colour, weight)
/// evaluated at points on the surface.
///
/// A field is described by data (`FieldDesc`, parsed from a preset, no I/O) and bound to a mesh
/// by `makeField`, which loads what it needs (an image) and checks what it refers to (a vertex
/// attribute). Kinds: constant, linear gradient, smooth value noise, vertex attribute, image map
/// through uv, and the editor's painted sparse grid (noise/painted.h), which reads
/// `SurfacePoint::position` (it needs no uv).
#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <glm/glm.hpp>

namespace spot::gpu {
struct SpotField;
}

namespace spot::noise {

struct Mesh;
class PaintedGrid;
class PaintLayer;

/// How a paint layer combines with the field under it (presets/README.md, "Paint layers").
enum class PaintMode {
    /// comb, tilt, scale, colour: per voxel a value v (the slot's components, background 0) and
    /// a weight w in [0, 1] (background 0); the field is b (1 - w) + v w over the base b.
    Override,
    /// The density: per voxel a multiplier m in [0, 1] (background 1) and a raise r in [0, 1]
    /// (background 0); the density is b m + (1 - b m) r. Erasing lowers m (and r), so it only
    /// removes impulses; adding raises m back towards 1 (up to the base's value) and, with the
    /// brush's raise option, r (up to 1).
    Density,
};

/// Where a field is evaluated: a point on the mesh surface, world units.
struct SurfacePoint {
    glm::vec3 position{0.0f};
    glm::vec3 normal{0.0f, 0.0f, 1.0f};  ///< unit, interpolated vertex normal
    glm::vec3 tangent{1.0f, 0.0f, 0.0f}; ///< unit, _|_ normal: +u direction, or a stable basis
    glm::vec2 uv{0.0f};                  ///< valid when the mesh has uv
    std::uint32_t triangle = 0;          ///< index into Mesh::triangles
    glm::vec3 barycentric{1.0f, 0.0f, 0.0f};
};

/// Parsed description of a field. Values are 1 or 3 components (`components`, fixed by the slot
/// the field fills: density is scalar, colour is RGB); scalars are stored in `.x`.
struct FieldDesc {
    /// Tangent: the surface tangent (+u), what an unset comb reads; only as the base of a comb
    /// whose preset has paint and no base.
    /// Material: a glTF material's base colour (its texture times its factor, or the factor
    /// alone) through the mesh's uv, as an image field (noise/mesh.h MeshMaterial).
    enum class Kind { Constant, Gradient, Noise, Vertex, Image, Painted, Tangent, Material };
    Kind kind = Kind::Constant;
    int components = 1;

    glm::vec3 value{0.0f}; ///< Constant

    /// Gradient: `lo` at `from`, `hi` at `to` (world units), linear along from->to, clamped.
    /// Noise and Image: the output maps [0,1] to [lo, hi].
    glm::vec3 lo{0.0f};
    glm::vec3 hi{1.0f};
    glm::vec3 from{0.0f};
    glm::vec3 to{0.0f, 1.0f, 0.0f};

    float frequency = 1.0f; ///< Noise: cells per world unit
    int octaves = 1;        ///< Noise: fractal octaves, each at double frequency, half amplitude
    std::uint32_t seed = 0; ///< Noise: its own seed, independent of the impulse seed

    std::vector<std::string> attributes; ///< Vertex: one attribute name per component

    std::string file;     ///< Image, Painted: path, relative paths resolved against the preset's folder
    int channel = 0;      ///< Image: first channel read
    bool repeat = true;   ///< Image: wrap mode for uv outside [0,1] (else clamp)
    /// Image: how texels are encoded; they are decoded to linear values when the image is
    /// loaded. Auto takes the file's own colour space (OpenImageIO's `oiio:ColorSpace`: sRGB,
    /// linear or a gamma), else sRGB for 8-bit images and linear for deeper ones. An alpha
    /// channel is never decoded.
    enum class ColorSpace { Auto, Srgb, Linear };
    ColorSpace colorSpace = ColorSpace::Auto;

    /// Material: the mesh's material by name, or by index (materialIndex >= 0); neither: the
    /// one material of the triangles that grow fur. `channel` picks red (0) to alpha (3).
    std::string material;
    int materialIndex = -1;

    std::string grid;     ///< Painted: the grid's name in the .vdb file
    /// Painted: when set, the grid in memory (the editor's live grid) instead of the file. The
    /// bound field shares it: after changing the grid, rebuild the shared form
    /// (ImpulseGenerator::refreshFields).
    std::shared_ptr<const PaintedGrid> painted;

    /// The paint layered over the field (the editor's strokes; presets/README.md "Paint
    /// layers"): its grids in `file` (resolved like an image), the value grid `grid` and the weight
    /// grid paintWeightGrid(grid); or, when `layer` is set, that layer in memory (the editor's
    /// live one, shared as `painted` is).
    struct Paint {
        std::string file;
        std::string grid;
        PaintMode mode = PaintMode::Override;
        std::shared_ptr<const PaintLayer> layer;
    };
    std::optional<Paint> paint;

    /// A slot limited to the mask (the preset's `fields.mask` slot, value m at the point;
    /// presets/README.md "Masks"): its value v becomes e + (v - e) m (Inside) or
    /// e + (v - e) (1 - m) (Outside), e = `maskElse` (the slot's components). The generator
    /// applies it (spot_generate.h spotSlotValue); a bound Field is the field alone.
    enum class MaskUse { None, Inside, Outside };
    MaskUse mask = MaskUse::None;
    glm::vec3 maskElse{0.0f};
};

/// Inclusive bounds of every value a field can return (componentwise).
struct FieldRange {
    glm::vec3 lo{0.0f};
    glm::vec3 hi{0.0f};
};

/// A field bound to a mesh. Its value is what the generator evaluates: `eval` runs the shared
/// header's spotFieldEval (shaders/spot_generate.h) on the field's shared form, the code that
/// renders, so CPU tests exercise it; the kinds differ only in how they build that form.
class Field {
public:
    Field() = default;
    Field(const Field&) = delete;
    Field& operator=(const Field&) = delete;
    virtual ~Field();
    /// Value at a surface point; scalars in `.x`, unused components zero. Builds the shared form
    /// on the first call, and again after a painted grid it reads changed (thread-safe).
    glm::vec3 eval(const SurfacePoint& p) const;
    /// Bounds of every value `eval` can return.
    virtual FieldRange range() const = 0;
    /// The field in the form the shared generator evaluates on the CPU and the GPU
    /// (shaders/spot_generate.h, spotFieldEval). Per-vertex columns, image texels and grids are
    /// appended to `data` and referenced by offset.
    virtual gpu::SpotField shared(std::vector<float>& data) const = 0;

protected:
    /// Changes when a painted grid the field reads changes (eval then builds its form again).
    virtual std::uint64_t version() const { return 0; }
    /// The mesh's triangles, for a field that reads per-vertex data (spotMeshTriangle).
    const glm::uvec3* m_triangles = nullptr;

private:
    struct Flat;
    mutable std::unique_ptr<Flat> m_flat;
};

/// Bind a description to a mesh. Throws InputError naming `context` (e.g. "preset fur.json,
/// fields.density") for a missing attribute, a mesh without uv under an image field, an
/// unreadable, corrupt or oversized image, or a painted grid that cannot be read
/// (readPaintedGrid) or has the wrong component count.
std::unique_ptr<Field> makeField(const FieldDesc& desc, const Mesh& mesh,
                                 const std::filesystem::path& baseDir, const std::string& context);

/// Smooth 3D value noise in [0,1] (quintic interpolation of hashed lattice values), fractal sum
/// normalized to [0,1]. Deterministic for a seed.
float valueNoise(glm::vec3 p, int octaves, std::uint32_t seed);

} // namespace spot::noise
