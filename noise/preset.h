/// @file preset.h
/// @brief Presets: a kernel, a distribution and the fields that drive them, as JSON.
///
/// The schema (every key, unit and range) is documented in presets/README.md. Parsing is strict:
/// unknown keys, wrong types, NaN/Inf and out-of-range values throw InputError naming the key
/// path and the file.
#pragma once

#include <cstdint>
#include <filesystem>
#include <iterator>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <glm/glm.hpp>

#include "field.h"

namespace spot::noise {

inline constexpr int kPresetVersion = 1;
inline constexpr int kMaxLobes = 8;

/// A longitudinal highlight of the strand model (shaders/spot_light.h): its peak's shift from
/// the mirror direction towards the tip (negative: towards the root), its width and its strength.
struct Highlight {
    float shiftDeg = 0.0f;  ///< degrees, [-90, 90]
    float widthDeg = 10.0f; ///< degrees, (0, 90]
    float strength = 0.0f;  ///< [0, 100]
};

/// How a lobe is shaded in a lit scene (scene shading.mode "lit"; other modes ignore it).
struct LobeShading {
    enum class Model { Lambert, Strand, Flake };
    /// Lambert: the normal from the extinction gradient. Strand: the lobe's longest axis is the
    /// tangent. Flake: its shortest axis is the normal, two-sided.
    Model model = Model::Lambert;
    /// Strand: white, shifted towards the root (Marschner's R).
    Highlight primary{-6.0f, 8.0f, 0.3f};
    /// Strand: tinted by the lobe's colour, shifted towards the tip (Marschner's TRT).
    Highlight secondary{9.0f, 16.0f, 0.5f};
};

/// One anisotropic Gaussian in kernel space (kernel units): g(p) = a exp(-1/2 |T^-1 p|^2) with
/// T = Translate(offset) * Rotate(rotationDeg, XYZ Euler) * Scale(sigma).
struct LobeDesc {
    glm::vec3 offset{0.0f};      ///< kernel units
    glm::vec3 rotationDeg{0.0f}; ///< degrees, applied as X, then Y, then Z (R = Rz Ry Rx)
    glm::vec3 sigma{1.0f};       ///< kernel units, >= 0 (0 is clamped to a tiny floor)
    float extinction = 1.0f;     ///< peak extinction a, 1/world unit, >= 0
    glm::vec3 color{1.0f};       ///< linear RGB in [0,1]
    LobeShading shading;
};

struct KernelDesc {
    std::vector<LobeDesc> lobes; ///< 1..kMaxLobes
    float supportSigma = 3.0f;   ///< truncation radius k in sigmas, [1, 6]
};

enum class DistributionType { Poisson, Jittered };

struct DistributionDesc {
    DistributionType type = DistributionType::Poisson;
    float densityMax = 100.0f; ///< impulses per square world unit where density is 1
    float jitter = 1.0f;       ///< Jittered: 0 = regular lattice .. 1 = fully jittered
    float heightOffset = 0.0f; ///< world units along the normal
    float heightJitter = 0.0f; ///< world units, uniform +- around heightOffset
};

/// Random variation per impulse, applied on top of the fields.
struct VariationDesc {
    float tiltDeg = 0.0f; ///< uniform +- degrees
    float spinDeg = 0.0f; ///< uniform +- degrees
    float bendDeg = 0.0f; ///< uniform +- degrees per kernel unit
    float scale = 0.0f;   ///< relative, uniform in [1 - v, 1 + v], same for all axes
    float color = 0.0f;   ///< relative brightness, uniform in [1 - v, 1 + v]
    float weight = 0.0f;  ///< relative, uniform in [1 - v, 1 + v]
    float clump = 0.0f;   ///< relative clump strength, uniform in [1 - v, 1 + v]
};

/// Clumps (presets/README.md "clump"; docs/design.md section 3, "Clumps"; shaders/spot_clump.h):
/// strands gather towards clump centres scattered on the surface. The strength is the `clump`
/// field, the relative size the `clump_size` field.
struct ClumpDesc {
    bool on = false;               ///< the preset clumps (a `clump` object or a `clump` field)
    float size = 0.1f;             ///< world units, (0, 1e3]: a clump's mean width (area size^2)
    float variation = 0.3f;        ///< [0, 1]: 0 clumps of even size, 1 very unequal ones
    float shape = 0.5f;            ///< [0, 1]: 0 a lean (linear in height), 1 a bend (quadratic)
    std::uint32_t seed = 0;        ///< the centres' seed (mixed with the scene's impulse seed)
    float secondarySize = 0.0f;    ///< world units, [0, size): smaller clumps inside; 0: none
    float secondaryStrength = 0.5f; ///< [0, 1]: their strength relative to the clump field
};

struct PresetDesc {
    int version = kPresetVersion;
    std::string name;
    KernelDesc kernel;
    DistributionDesc distribution;
    FieldDesc density;              ///< scalar probability in [0,1]; default constant 1
    std::optional<FieldDesc> comb;  ///< world direction (3); absent: the surface tangent (+u)
    FieldDesc tiltDeg;              ///< scalar degrees from the normal towards the comb
    FieldDesc spinDeg;              ///< scalar degrees about the tilted axis
    FieldDesc bendDeg;              ///< scalar degrees per kernel unit of height
    FieldDesc scale;                ///< 3 components, world units per kernel unit, > 0
    FieldDesc color;                ///< 3 components, multiplies each lobe's colour
    FieldDesc weight;               ///< scalar |w| multiplying extinction, >= 0
    FieldDesc clump;                ///< scalar clump strength in [0, 1]; default 0
    FieldDesc clumpSize;            ///< scalar relative clump size in [0.5, 2]; default 1
    FieldDesc mask;                 ///< scalar mask in [0, 1] (what masked slots are limited to)
    ClumpDesc clumpDesc;
    VariationDesc variation;
    std::filesystem::path baseDir;  ///< folder the preset came from (for relative image paths)
};

/// One field slot of a preset: the one table of the slots (name, components, index), read by the
/// parser, the generator, the editor and its panels.
struct FieldSlot {
    int index;        ///< the generator's slot: SPOT_FIELD_* (shaders/spot_layout.h)
    const char* key;  ///< the key under the preset's `fields`
    int components;   ///< 1 (scalar, in `.x`) or 3
    double lo, hi;    ///< the range of a value (lo excluded when loOpen)
    bool loOpen;
    float byDefault;  ///< the constant of an absent field (every component)
    bool optional;    ///< absent means no field (comb: the surface tangent), not the default
};

/// Indexed by FieldSlot::index; the order of `fields` in presets/README.md.
inline constexpr FieldSlot kFieldSlots[] = {
    {0, "density", 1, 0.0, 1.0, false, 1.0f, false},       // probability in [0, 1]
    {1, "comb", 3, -1e6, 1e6, false, 0.0f, true},          // world direction
    {2, "tilt_deg", 1, -360.0, 360.0, false, 0.0f, false}, // degrees
    {3, "spin_deg", 1, -360.0, 360.0, false, 0.0f, false}, // degrees
    {4, "bend_deg", 1, -3600.0, 3600.0, false, 0.0f, false}, // degrees per kernel unit
    {5, "scale", 3, 0.0, 1e3, true, 1.0f, false},          // world units per kernel unit
    {6, "color", 3, 0.0, 1.0, false, 1.0f, false},         // linear RGB
    {7, "weight", 1, 0.0, 1e3, false, 1.0f, false},        // multiplies extinction
    {8, "clump", 1, 0.0, 1.0, false, 0.0f, false},         // clump strength
    {9, "clump_size", 1, 0.5, 2.0, false, 1.0f, false},    // relative clump size
    {10, "mask", 1, 0.0, 1.0, false, 0.0f, false},         // the groom's mask
};
inline constexpr int kFieldSlotCount = int(std::size(kFieldSlots));

/// The slot of `key` under `fields`, or null.
const FieldSlot* findFieldSlot(std::string_view key);
/// The field of slot `index` (FieldSlot::index); null for an unset comb. Throws InputError for
/// an index out of range.
FieldDesc* presetField(PresetDesc& preset, int index);
const FieldDesc* presetField(const PresetDesc& preset, int index);

/// Whether a `clump` field asks for clumps: anything but the constant 0 (a painted layer, even
/// an empty one, counts: the editor's clump brush turns clumps on with its first stroke).
bool clumpFieldSet(const FieldDesc& clump);

/// Parse preset JSON from memory; `name` (the file) is used in messages.
PresetDesc parsePreset(std::string_view json, const std::string& name);
/// Read and parse a preset file (size-capped before reading).
PresetDesc loadPreset(const std::filesystem::path& file);

} // namespace spot::noise
