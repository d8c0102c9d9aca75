/// @file preset.h
/// @brief Presets: a kernel, a distribution and the fields that drive them, as JSON.
///
/// The schema (every key, unit and range) is documented in presets/README.md. Parsing is strict:
/// unknown keys, wrong types, NaN/Inf and out-of-range values throw InputError naming the key
/// path and the file.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <glm/glm.hpp>

#include "field.h"

namespace spot::noise {

inline constexpr int kPresetVersion = 1;
inline constexpr int kMaxLobes = 8;

/// One anisotropic Gaussian in kernel space (kernel units): g(p) = a exp(-1/2 |T^-1 p|^2) with
/// T = Translate(offset) * Rotate(rotationDeg, XYZ Euler) * Scale(sigma).
struct LobeDesc {
    glm::vec3 offset{0.0f};      ///< kernel units
    glm::vec3 rotationDeg{0.0f}; ///< degrees, applied as X, then Y, then Z (R = Rz Ry Rx)
    glm::vec3 sigma{1.0f};       ///< kernel units, >= 0 (0 is clamped to a tiny floor)
    float extinction = 1.0f;     ///< peak extinction a, 1/world unit, >= 0
    glm::vec3 color{1.0f};       ///< linear RGB in [0,1]
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
    VariationDesc variation;
    std::filesystem::path baseDir;  ///< folder the preset came from (for relative image paths)
};

/// Parse preset JSON from memory; `name` (the file) is used in messages.
PresetDesc parsePreset(std::string_view json, const std::string& name);
/// Read and parse a preset file (size-capped before reading).
PresetDesc loadPreset(const std::filesystem::path& file);

} // namespace spot::noise
