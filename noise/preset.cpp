#include "noise/preset.h"

#include <cctype>
#include <cfloat>
#include <cmath>
#include <cstdint>
#include <initializer_list>
#include <set>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "noise/error.h"
#include "noise/json_reader.h"
#include "noise/system.h"
#include "shaders/spot_layout.hpp"

// This file must not depend on OpenImageIO or field.cpp: the fuzz target compiles it with the mesh
// parsers only. Everything here is pure parsing and validation of data.

namespace spot::noise {

namespace {

using Json = nlohmann::json;
using json::Interval;
using json::index;
using json::join;
using json::printable;

/// Presets are a few kilobytes; the cap keeps a mistaken path (a mesh, a log) from being parsed.
constexpr std::uint64_t kMaxPresetBytes = 1u << 20;

// Ranges of the schema (presets/README.md documents each).
constexpr Interval kUnit{0.0, 1.0};
constexpr Interval kUnitOpenHi{0.0, 1.0, false, true};
constexpr Interval kKernelOffset{-1e3, 1e3};
constexpr Interval kRotationDeg{-360.0, 360.0};
constexpr Interval kSigma{0.0, 1e3};
constexpr Interval kExtinction{0.0, 1e6};
constexpr Interval kSupportSigma{1.0, 6.0};
constexpr Interval kHighlightShift{-90.0, 90.0};
constexpr Interval kHighlightWidth{0.0, 90.0, true, false};
constexpr Interval kHighlightStrength{0.0, 100.0};
constexpr Interval kDensityMax{0.0, 1e8, true, false};
constexpr Interval kHeightOffset{-1e3, 1e3};
constexpr Interval kHeightJitter{0.0, 1e3};
constexpr Interval kWorldPosition{-1e6, 1e6};
constexpr Interval kFrequency{0.0, 1e6, true, false};
constexpr Interval kVariationAngle{0.0, 180.0};
constexpr Interval kVariationBend{0.0, 3600.0};
constexpr Interval kClumpSize{0.0, 1e3, true, false};
/// A gradient whose ends are closer than this has no usable direction in float.
constexpr float kMinGradientLength = 1e-6f;

/// Reads preset values; adds the field forms to the generic strict reader.
class Reader : public json::Reader {
public:
    using json::Reader::Reader;

    /// A field value: a number (broadcast to 3 components for vec3 slots) or, for vec3 slots
    /// only, an array of 3. Unused components stay zero.
    glm::vec3 fieldValue(const Json& j, const std::string& path, int components,
                         const Interval& r) const {
        if (j.is_number()) {
            const float v = real(j, path, r);
            return components == 1 ? glm::vec3(v, 0.0f, 0.0f) : glm::vec3(v);
        }
        if (components == 1)
            fail(cat(path, " must be a number (this field is a scalar), got ", j.type_name()));
        if (!j.is_array())
            fail(cat(path, " must be a number or an array of 3 numbers, got ", j.type_name()));
        return vec3(j, path, r);
    }

    /// "range"/"values": [lo, hi], each a field value. lo > hi is allowed (it inverts the map).
    void fieldRange(const Json& j, const std::string& path, int components, const Interval& r,
                    FieldDesc& desc) const {
        array(j, path, 2, "values [lo, hi]");
        desc.lo = fieldValue(j[0], index(path, 0), components, r);
        desc.hi = fieldValue(j[1], index(path, 1), components, r);
    }

    FieldDesc field(const Json& j, const std::string& path, int components,
                    const Interval& r) const {
        FieldDesc desc;
        desc.components = components;
        if (!j.is_object()) {
            desc.kind = FieldDesc::Kind::Constant;
            if (!j.is_number() && !j.is_array())
                fail(cat(path,
                         components == 1 ? " must be a number or a field object, got "
                                         : " must be a number, an array of 3 numbers or a field "
                                           "object, got ",
                         j.type_name()));
            desc.value = fieldValue(j, path, components, r);
            return desc;
        }
        const std::string type = string(require(j, path, "type"), join(path, "type"), false);
        if (type == "constant") {
            requireObject(j, path, {"type", "value"});
            desc.kind = FieldDesc::Kind::Constant;
            desc.value = fieldValue(require(j, path, "value"), join(path, "value"), components, r);
        } else if (type == "gradient") {
            requireObject(j, path, {"type", "from", "to", "values"});
            desc.kind = FieldDesc::Kind::Gradient;
            desc.from = vec3(require(j, path, "from"), join(path, "from"), kWorldPosition);
            desc.to = vec3(require(j, path, "to"), join(path, "to"), kWorldPosition);
            if (!(glm::length(desc.to - desc.from) >= kMinGradientLength))
                fail(cat(path, ": gradient \"from\" and \"to\" must be different points (at least ",
                         kMinGradientLength, " world units apart)"));
            fieldRange(require(j, path, "values"), join(path, "values"), components, r, desc);
        } else if (type == "noise") {
            requireObject(j, path, {"type", "frequency", "octaves", "seed", "range"});
            desc.kind = FieldDesc::Kind::Noise;
            if (const Json* f = find(j, "frequency"))
                desc.frequency = real(*f, join(path, "frequency"), kFrequency);
            if (const Json* o = find(j, "octaves"))
                desc.octaves = static_cast<int>(integer(*o, join(path, "octaves"), 1, 8));
            if (const Json* s = find(j, "seed"))
                desc.seed = static_cast<std::uint32_t>(
                    integer(*s, join(path, "seed"), 0, std::int64_t{UINT32_MAX}));
            fieldRange(require(j, path, "range"), join(path, "range"), components, r, desc);
        } else if (type == "vertex") {
            requireObject(j, path, {"type", "attribute"});
            desc.kind = FieldDesc::Kind::Vertex;
            const Json& a = require(j, path, "attribute");
            const std::string aPath = join(path, "attribute");
            if (a.is_string()) {
                // One attribute in a vec3 slot fills all three components, like a number does.
                desc.attributes.assign(static_cast<std::size_t>(components),
                                       string(a, aPath, false));
            } else if (components == 1) {
                fail(cat(aPath, " must be a string (this field is a scalar), got ", a.type_name()));
            } else {
                array(a, aPath, 3, "attribute names");
                for (std::size_t i = 0; i < 3; ++i)
                    desc.attributes.push_back(string(a[i], index(aPath, i), false));
            }
        } else if (type == "image") {
            requireObject(j, path, {"type", "file", "channel", "wrap", "colorspace", "range"});
            desc.kind = FieldDesc::Kind::Image;
            desc.file = string(require(j, path, "file"), join(path, "file"), false);
            if (const Json* c = find(j, "channel"))
                desc.channel = static_cast<int>(integer(*c, join(path, "channel"), 0, 1023));
            if (const Json* w = find(j, "wrap")) {
                const std::string wrap = string(*w, join(path, "wrap"), false);
                if (wrap != "repeat" && wrap != "clamp")
                    fail(cat(join(path, "wrap"), " = \"", printable(wrap),
                             "\" is not one of \"repeat\", \"clamp\""));
                desc.repeat = wrap == "repeat";
            }
            if (const Json* c = find(j, "colorspace")) {
                const std::string space = string(*c, join(path, "colorspace"), false);
                if (space == "auto")
                    desc.colorSpace = FieldDesc::ColorSpace::Auto;
                else if (space == "srgb")
                    desc.colorSpace = FieldDesc::ColorSpace::Srgb;
                else if (space == "linear")
                    desc.colorSpace = FieldDesc::ColorSpace::Linear;
                else
                    fail(cat(join(path, "colorspace"), " = \"", printable(space),
                             "\" is not one of \"auto\", \"srgb\", \"linear\""));
            }
            fieldRange(require(j, path, "range"), join(path, "range"), components, r, desc);
        } else if (type == "material") {
            // A glTF material's base colour (texture times factor) through the mesh's uv:
            // checked against the mesh when the field is bound (makeField).
            requireObject(j, path, {"type", "material", "channel", "range"});
            desc.kind = FieldDesc::Kind::Material;
            if (const Json* m = find(j, "material")) {
                if (m->is_number_integer())
                    desc.materialIndex =
                        static_cast<int>(integer(*m, join(path, "material"), 0, 1000000));
                else
                    desc.material = string(*m, join(path, "material"), false);
            }
            if (const Json* c = find(j, "channel"))
                desc.channel = static_cast<int>(integer(*c, join(path, "channel"), 0, 3));
            if (desc.channel + components > 4)
                fail(cat(join(path, "channel"), " = ", desc.channel, ": a material's colour has 4 "
                         "channels (red, green, blue, alpha), and this slot reads ", components));
            if (const Json* rg = find(j, "range")) {
                fieldRange(*rg, join(path, "range"), components, r, desc);
            } else {
                if (!r.contains(0.0) || !r.contains(1.0))
                    fail(cat(path, ": a material's colour is in [0, 1], outside this slot's range ",
                             r, "; give \"range\""));
                desc.lo = components == 1 ? glm::vec3(0.0f) : glm::vec3(0.0f);
                desc.hi = components == 1 ? glm::vec3(1.0f, 0.0f, 0.0f) : glm::vec3(1.0f);
            }
        } else if (type == "painted") {
            // The values are read with the grid (makeField), so they are not checked here.
            requireObject(j, path, {"type", "file", "grid"});
            desc.kind = FieldDesc::Kind::Painted;
            desc.file = string(require(j, path, "file"), join(path, "file"), false);
            desc.grid = string(require(j, path, "grid"), join(path, "grid"), false);
        } else {
            fail(cat(join(path, "type"), " = \"", printable(type),
                     "\" is not one of \"constant\", \"gradient\", \"noise\", \"vertex\", "
                     "\"image\", \"material\", \"painted\""));
        }
        return desc;
    }

    /// A slot's field: a field, or {"base": field, "paint": {"file", "grid"}, "mask": "inside"
    /// or "outside", "else": value} (a paint layer over the base, the slot limited to the mask;
    /// `paint` or `mask` makes the form; an absent base is the slot's default, the surface
    /// tangent for the comb).
    FieldDesc slotField(const Json& j, const std::string& path, const FieldSlot& slot,
                        const Interval& r) const {
        if (!j.is_object() || (!find(j, "paint") && !find(j, "mask") && !find(j, "else")))
            return field(j, path, slot.components, r);
        requireObject(j, path, {"base", "paint", "mask", "else"});
        FieldDesc desc = slotBase(j, path, slot, r);
        if (const Json* mask = find(j, "mask")) {
            if (slot.index == SPOT_FIELD_MASK)
                fail(cat(join(path, "mask"), ": the mask cannot be limited to itself"));
            const std::string where = string(*mask, join(path, "mask"), false);
            if (where == "inside")
                desc.mask = FieldDesc::MaskUse::Inside;
            else if (where == "outside")
                desc.mask = FieldDesc::MaskUse::Outside;
            else
                fail(cat(join(path, "mask"), " = \"", printable(where),
                         "\" is not one of \"inside\", \"outside\""));
            desc.maskElse = slot.components == 1 ? glm::vec3(slot.byDefault, 0.0f, 0.0f)
                                                 : glm::vec3(slot.byDefault);
            if (slot.optional) // an unset comb: the tangent is not a value
                fail(cat(join(path, "mask"), ": the comb cannot be masked"));
            if (const Json* e = find(j, "else"))
                desc.maskElse = fieldValue(*e, join(path, "else"), slot.components, r);
        } else if (find(j, "else")) {
            fail(cat(join(path, "else"), ": \"else\" is the value outside the mask; it needs "
                                        "\"mask\""));
        }
        return desc;
    }

    /// The base and the paint layer of a slot's object form.
    FieldDesc slotBase(const Json& j, const std::string& path, const FieldSlot& slot,
                       const Interval& r) const {
        FieldDesc desc;
        if (const Json* base = find(j, "base")) {
            desc = field(*base, join(path, "base"), slot.components, r);
        } else if (slot.optional) {
            desc.kind = FieldDesc::Kind::Tangent;
            desc.components = slot.components;
        } else {
            desc.kind = FieldDesc::Kind::Constant;
            desc.components = slot.components;
            desc.value = slot.components == 1 ? glm::vec3(slot.byDefault, 0.0f, 0.0f)
                                              : glm::vec3(slot.byDefault);
        }
        const Json* paintJson = find(j, "paint");
        if (!paintJson)
            return desc;
        const std::string paintPath = join(path, "paint");
        const Json& paint = *paintJson;
        requireObject(paint, paintPath, {"file", "grid"});
        FieldDesc::Paint layer;
        layer.file = string(require(paint, paintPath, "file"), join(paintPath, "file"), false);
        layer.grid = string(require(paint, paintPath, "grid"), join(paintPath, "grid"), false);
        layer.mode = slot.index == SPOT_FIELD_DENSITY ? PaintMode::Density : PaintMode::Override;
        desc.paint = std::move(layer);
        return desc;
    }
};

FieldDesc constantField(int components, float v) {
    FieldDesc d;
    d.kind = FieldDesc::Kind::Constant;
    d.components = components;
    d.value = components == 1 ? glm::vec3(v, 0.0f, 0.0f) : glm::vec3(v);
    return d;
}

Highlight parseHighlight(const Reader& rd, const Json& j, const std::string& path, Highlight h) {
    rd.requireObject(j, path, {"shift_deg", "width_deg", "strength"});
    if (const Json* v = Reader::find(j, "shift_deg"))
        h.shiftDeg = rd.real(*v, join(path, "shift_deg"), kHighlightShift);
    if (const Json* v = Reader::find(j, "width_deg"))
        h.widthDeg = rd.real(*v, join(path, "width_deg"), kHighlightWidth);
    if (const Json* v = Reader::find(j, "strength"))
        h.strength = rd.real(*v, join(path, "strength"), kHighlightStrength);
    return h;
}

/// A lobe's `shading`: a model's name, or an object {"model", "primary", "secondary"}.
LobeShading parseLobeShading(const Reader& rd, const Json& j, const std::string& path) {
    LobeShading s;
    const Json* model = &j;
    if (j.is_object()) {
        rd.requireObject(j, path, {"model", "primary", "secondary"});
        model = &rd.require(j, path, "model");
    }
    if (!j.is_object() && !j.is_string())
        rd.fail(cat(path, " must be a model's name or an object, got ", j.type_name()));
    const std::string modelPath = j.is_object() ? join(path, "model") : path;
    const std::string name = rd.string(*model, modelPath, false);
    if (name == "lambert")
        s.model = LobeShading::Model::Lambert;
    else if (name == "strand")
        s.model = LobeShading::Model::Strand;
    else if (name == "flake")
        s.model = LobeShading::Model::Flake;
    else
        rd.fail(cat(modelPath, " = \"", printable(name),
                    "\" is not one of \"lambert\", \"strand\", \"flake\""));
    for (const char* key : {"primary", "secondary"}) {
        const Json* h = j.is_object() ? Reader::find(j, key) : nullptr;
        if (!h)
            continue;
        if (s.model != LobeShading::Model::Strand)
            rd.fail(cat(join(path, key), ": highlights belong to the \"strand\" model"));
        Highlight& target = std::string_view(key) == "primary" ? s.primary : s.secondary;
        target = parseHighlight(rd, *h, join(path, key), target);
    }
    return s;
}

LobeDesc parseLobe(const Reader& rd, const Json& j, const std::string& path) {
    rd.requireObject(j, path,
                     {"offset", "rotation_deg", "sigma", "extinction", "color", "shading"});
    LobeDesc lobe;
    if (const Json* v = Reader::find(j, "offset"))
        lobe.offset = rd.vec3(*v, join(path, "offset"), kKernelOffset);
    if (const Json* v = Reader::find(j, "rotation_deg"))
        lobe.rotationDeg = rd.vec3(*v, join(path, "rotation_deg"), kRotationDeg);
    if (const Json* v = Reader::find(j, "sigma"))
        lobe.sigma = rd.vec3(*v, join(path, "sigma"), kSigma);
    if (const Json* v = Reader::find(j, "extinction"))
        lobe.extinction = rd.real(*v, join(path, "extinction"), kExtinction);
    if (const Json* v = Reader::find(j, "color"))
        lobe.color = rd.vec3(*v, join(path, "color"), kUnit);
    if (const Json* v = Reader::find(j, "shading"))
        lobe.shading = parseLobeShading(rd, *v, join(path, "shading"));
    return lobe;
}

KernelDesc parseKernel(const Reader& rd, const Json& j, const std::string& path) {
    rd.requireObject(j, path, {"support_sigma", "lobes"});
    KernelDesc kernel;
    if (const Json* v = Reader::find(j, "support_sigma"))
        kernel.supportSigma = rd.real(*v, join(path, "support_sigma"), kSupportSigma);
    const std::string lobesPath = join(path, "lobes");
    const Json& lobes = rd.require(j, path, "lobes");
    if (!lobes.is_array())
        rd.fail(cat(lobesPath, " must be an array of lobe objects, got ", lobes.type_name()));
    if (lobes.empty() || lobes.size() > static_cast<std::size_t>(kMaxLobes))
        rd.fail(cat(lobesPath, " has ", lobes.size(), " lobes; a kernel needs 1 to ", kMaxLobes));
    for (std::size_t i = 0; i < lobes.size(); ++i)
        kernel.lobes.push_back(parseLobe(rd, lobes[i], index(lobesPath, i)));
    return kernel;
}

DistributionDesc parseDistribution(const Reader& rd, const Json& j, const std::string& path) {
    rd.requireObject(j, path, {"type", "density_max", "jitter", "height_offset", "height_jitter"});
    DistributionDesc d;
    const std::string typePath = join(path, "type");
    const std::string type = rd.string(rd.require(j, path, "type"), typePath, false);
    if (type == "poisson")
        d.type = DistributionType::Poisson;
    else if (type == "jittered")
        d.type = DistributionType::Jittered;
    else
        rd.fail(
            cat(typePath, " = \"", printable(type), "\" is not one of \"poisson\", \"jittered\""));
    d.densityMax =
        rd.real(rd.require(j, path, "density_max"), join(path, "density_max"), kDensityMax);
    if (const Json* v = Reader::find(j, "jitter"))
        d.jitter = rd.real(*v, join(path, "jitter"), kUnit);
    if (const Json* v = Reader::find(j, "height_offset"))
        d.heightOffset = rd.real(*v, join(path, "height_offset"), kHeightOffset);
    if (const Json* v = Reader::find(j, "height_jitter"))
        d.heightJitter = rd.real(*v, join(path, "height_jitter"), kHeightJitter);
    return d;
}

void parseFields(const Reader& rd, const Json& j, const std::string& path, PresetDesc& p) {
    std::vector<std::string_view> keys;
    for (const FieldSlot& slot : kFieldSlots)
        keys.push_back(slot.key);
    rd.requireObject(j, path, keys);
    for (const FieldSlot& slot : kFieldSlots) {
        const Json* v = Reader::find(j, slot.key);
        if (!v)
            continue;
        const Interval range{slot.lo, slot.hi, slot.loOpen, false};
        FieldDesc desc = rd.slotField(*v, join(path, slot.key), slot, range);
        if (slot.optional)
            p.comb = std::move(desc);
        else
            *presetField(p, slot.index) = std::move(desc);
    }
}

ClumpDesc parseClump(const Reader& rd, const Json& j, const std::string& path) {
    rd.requireObject(j, path, {"size", "variation", "shape", "seed", "secondary"});
    ClumpDesc c;
    c.on = true;
    if (const Json* v = Reader::find(j, "size"))
        c.size = rd.real(*v, join(path, "size"), kClumpSize);
    if (const Json* v = Reader::find(j, "variation"))
        c.variation = rd.real(*v, join(path, "variation"), kUnit);
    if (const Json* v = Reader::find(j, "shape"))
        c.shape = rd.real(*v, join(path, "shape"), kUnit);
    if (const Json* v = Reader::find(j, "seed"))
        c.seed = static_cast<std::uint32_t>(
            rd.integer(*v, join(path, "seed"), 0, std::int64_t{UINT32_MAX}));
    if (const Json* s = Reader::find(j, "secondary")) {
        const std::string sPath = join(path, "secondary");
        rd.requireObject(*s, sPath, {"size", "strength"});
        c.secondarySize = rd.real(rd.require(*s, sPath, "size"), join(sPath, "size"), kClumpSize);
        if (!(c.secondarySize < c.size))
            rd.fail(cat(join(sPath, "size"), " = ", c.secondarySize,
                        " must be smaller than clump.size = ", c.size,
                        " (secondary clumps lie inside the clumps)"));
        if (const Json* v = Reader::find(*s, "strength"))
            c.secondaryStrength = rd.real(*v, join(sPath, "strength"), kUnit);
    }
    return c;
}

VariationDesc parseVariation(const Reader& rd, const Json& j, const std::string& path) {
    rd.requireObject(j, path,
                     {"tilt_deg", "spin_deg", "bend_deg", "scale", "color", "weight", "clump"});
    VariationDesc v;
    const auto read = [&](std::string_view key, const Interval& r, float& out) {
        if (const Json* x = Reader::find(j, key))
            out = rd.real(*x, join(path, key), r);
    };
    read("tilt_deg", kVariationAngle, v.tiltDeg);
    read("spin_deg", kVariationAngle, v.spinDeg);
    read("bend_deg", kVariationBend, v.bendDeg);
    read("scale", kUnitOpenHi, v.scale);
    read("color", kUnitOpenHi, v.color);
    read("weight", kUnitOpenHi, v.weight);
    read("clump", kUnitOpenHi, v.clump);
    return v;
}

} // namespace

bool clumpFieldSet(const FieldDesc& clump) {
    return !(clump.kind == FieldDesc::Kind::Constant && clump.value.x == 0.0f && !clump.paint &&
             clump.mask == FieldDesc::MaskUse::None);
}

const FieldSlot* findFieldSlot(std::string_view key) {
    for (const FieldSlot& slot : kFieldSlots)
        if (key == slot.key)
            return &slot;
    return nullptr;
}

const FieldDesc* presetField(const PresetDesc& p, int index) {
    return presetField(const_cast<PresetDesc&>(p), index);
}

FieldDesc* presetField(PresetDesc& p, int index) {
    static_assert(kFieldSlotCount == SPOT_FIELD_COUNT);
    static_assert(kFieldSlots[SPOT_FIELD_DENSITY].index == SPOT_FIELD_DENSITY &&
                  kFieldSlots[SPOT_FIELD_COMB].index == SPOT_FIELD_COMB &&
                  kFieldSlots[SPOT_FIELD_TILT].index == SPOT_FIELD_TILT &&
                  kFieldSlots[SPOT_FIELD_SPIN].index == SPOT_FIELD_SPIN &&
                  kFieldSlots[SPOT_FIELD_BEND].index == SPOT_FIELD_BEND &&
                  kFieldSlots[SPOT_FIELD_SCALE].index == SPOT_FIELD_SCALE &&
                  kFieldSlots[SPOT_FIELD_COLOR].index == SPOT_FIELD_COLOR &&
                  kFieldSlots[SPOT_FIELD_WEIGHT].index == SPOT_FIELD_WEIGHT &&
                  kFieldSlots[SPOT_FIELD_CLUMP].index == SPOT_FIELD_CLUMP &&
                  kFieldSlots[SPOT_FIELD_CLUMP_SIZE].index == SPOT_FIELD_CLUMP_SIZE &&
                  kFieldSlots[SPOT_FIELD_MASK].index == SPOT_FIELD_MASK);
    // The PresetDesc members, in the table's order.
    FieldDesc* const members[] = {&p.density, p.comb ? &*p.comb : nullptr, &p.tiltDeg, &p.spinDeg,
                                  &p.bendDeg, &p.scale, &p.color, &p.weight,
                                  &p.clump, &p.clumpSize, &p.mask};
    static_assert(std::size(members) == std::size(kFieldSlots));
    if (index < 0 || index >= kFieldSlotCount)
        throw InputError(cat("field slot ", index, " is not one of 0..", kFieldSlotCount - 1));
    return members[index];
}

PresetDesc parsePreset(std::string_view text, const std::string& name) {
    if (text.size() > kMaxPresetBytes)
        throw InputError(cat(name, ": preset is ", text.size(), " bytes, more than the limit of ",
                             kMaxPresetBytes));
    const Json root = json::parse(text, name);
    const Reader rd(name);
    rd.requireObject(
        root, "",
        {"version", "name", "description", "kernel", "distribution", "fields", "variation",
         "clump"});

    PresetDesc p;
    const Json& version = rd.require(root, "", "version");
    if (!version.is_number_integer())
        rd.fail(cat("version must be the integer ", kPresetVersion, ", got ",
                    version.is_number() ? "a fractional number" : version.type_name()));
    if (version.is_number_unsigned() ? version.get<std::uint64_t>() != kPresetVersion
                                     : version.get<std::int64_t>() != kPresetVersion)
        rd.fail(cat("version = ", version.dump(), " is not supported (this build reads version ",
                    kPresetVersion, ")"));
    p.version = kPresetVersion;

    if (const Json* n = Reader::find(root, "name"))
        p.name = rd.string(*n, "name", false);
    else
        p.name = std::filesystem::path(name).stem().string();
    if (const Json* d = Reader::find(root, "description"))
        rd.string(*d, "description", true); // documentation for humans, checked but not kept

    p.kernel = parseKernel(rd, rd.require(root, "", "kernel"), "kernel");
    p.distribution = parseDistribution(rd, rd.require(root, "", "distribution"), "distribution");

    for (const FieldSlot& slot : kFieldSlots)
        if (!slot.optional)
            *presetField(p, slot.index) = constantField(slot.components, slot.byDefault);
    if (const Json* f = Reader::find(root, "fields"))
        parseFields(rd, *f, "fields", p);
    if (const Json* v = Reader::find(root, "variation"))
        p.variation = parseVariation(rd, *v, "variation");
    if (const Json* c = Reader::find(root, "clump"))
        p.clumpDesc = parseClump(rd, *c, "clump");
    p.clumpDesc.on = p.clumpDesc.on || clumpFieldSet(p.clump);
    return p;
}

PresetDesc loadPreset(const std::filesystem::path& file) {
    const std::string text = readFileCapped(file, kMaxPresetBytes);
    PresetDesc p = parsePreset(text, file.string());
    p.baseDir = file.parent_path();
    return p;
}

} // namespace spot::noise
