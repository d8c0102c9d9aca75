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
#include "noise/system.h"

// This file must not depend on OpenImageIO or field.cpp: the fuzz target compiles it with the mesh
// parsers only. Everything here is pure parsing and validation of data.

namespace spot::noise {

namespace {

using nlohmann::json;

/// Presets are a few kilobytes; the cap keeps a mistaken path (a mesh, a log) from being parsed.
constexpr std::uint64_t kMaxPresetBytes = 1u << 20;
/// nlohmann's parser is iterative, but nothing in the schema nests deeper than 6; a cap keeps a
/// hostile file from building a huge tree of empty arrays.
constexpr int kMaxJsonDepth = 32;
constexpr std::size_t kMaxStringLength = 4096;

/// Allowed interval of a number; open ends are written "(" or ")" in messages.
struct Interval {
    double lo;
    double hi;
    bool loOpen = false;
    bool hiOpen = false;

    bool contains(double v) const {
        return (loOpen ? v > lo : v >= lo) && (hiOpen ? v < hi : v <= hi);
    }
};

std::ostream& operator<<(std::ostream& out, const Interval& r) {
    return out << (r.loOpen ? "(" : "[") << r.lo << ", " << r.hi << (r.hiOpen ? ")" : "]");
}

// Ranges of the schema (presets/README.md documents each).
constexpr Interval kUnit{0.0, 1.0};
constexpr Interval kUnitOpenHi{0.0, 1.0, false, true};
constexpr Interval kKernelOffset{-1e3, 1e3};
constexpr Interval kRotationDeg{-360.0, 360.0};
constexpr Interval kSigma{0.0, 1e3};
constexpr Interval kExtinction{0.0, 1e6};
constexpr Interval kSupportSigma{1.0, 6.0};
constexpr Interval kDensityMax{0.0, 1e8, true, false};
constexpr Interval kHeightOffset{-1e3, 1e3};
constexpr Interval kHeightJitter{0.0, 1e3};
constexpr Interval kWorldPosition{-1e6, 1e6};
constexpr Interval kDirection{-1e6, 1e6};
constexpr Interval kAngleDeg{-360.0, 360.0};
constexpr Interval kBendDeg{-3600.0, 3600.0};
constexpr Interval kScale{0.0, 1e3, true, false};
constexpr Interval kWeight{0.0, 1e3};
constexpr Interval kFrequency{0.0, 1e6, true, false};
constexpr Interval kVariationAngle{0.0, 180.0};
constexpr Interval kVariationBend{0.0, 3600.0};
/// A gradient whose ends are closer than this has no usable direction in float.
constexpr float kMinGradientLength = 1e-6f;

/// Keys and strings from a hostile file end up in messages printed on one terminal line: keep
/// them printable and short.
constexpr std::size_t kMaxKeyShown = 64;
constexpr std::size_t kMaxDetailShown = 240;

std::string printable(std::string_view s, std::size_t maxShown = kMaxKeyShown) {
    std::string out;
    for (std::size_t i = 0; i < s.size() && i < maxShown; ++i) {
        const auto c = static_cast<unsigned char>(s[i]);
        if (c >= 0x20 && c < 0x7f && c != '"' && c != '\\') {
            out += static_cast<char>(c);
        } else {
            static const char* hex = "0123456789abcdef";
            out += "\\x";
            out += hex[c >> 4];
            out += hex[c & 15];
        }
    }
    if (s.size() > maxShown)
        out += "...";
    return out;
}

std::string join(const std::string& path, std::string_view key) {
    return path.empty() ? std::string(key) : cat(path, ".", key);
}

std::string index(const std::string& path, std::size_t i) {
    return cat(path, "[", i, "]");
}

/// Reads values out of the parsed document, each failure naming the file and the key path.
class Reader {
public:
    explicit Reader(const std::string& file) : m_file(file) {}

    [[noreturn]] void fail(const std::string& message) const {
        throw InputError(cat(m_file, ": ", message));
    }

    /// `obj` must be an object whose keys are all in `allowed`.
    void requireObject(const json& obj, const std::string& path,
                       std::initializer_list<std::string_view> allowed) const {
        if (!obj.is_object())
            fail(cat(path.empty() ? "the document" : path, " must be an object, got ",
                     obj.type_name()));
        for (const auto& item : obj.items()) {
            bool known = false;
            for (std::string_view a : allowed)
                known = known || item.key() == a;
            if (!known)
                fail(cat("unknown key \"", join(path, printable(item.key())), "\""));
        }
    }

    static const json* find(const json& obj, std::string_view key) {
        const auto it = obj.find(key);
        return it == obj.end() ? nullptr : &*it;
    }

    const json& require(const json& obj, const std::string& path, std::string_view key) const {
        const json* v = find(obj, key);
        if (!v)
            fail(cat("missing required key \"", join(path, key), "\""));
        return *v;
    }

    double number(const json& j, const std::string& path, const Interval& r) const {
        if (!j.is_number())
            fail(cat(path, " must be a number, got ", j.type_name()));
        const double v = j.get<double>();
        // JSON has no NaN literal, but 1e999 parses to infinity and 1e39 does not fit a float.
        if (!std::isfinite(v) || std::abs(v) > double(FLT_MAX))
            fail(cat(path, " = ", v, " is not a finite 32-bit float"));
        if (!r.contains(v))
            fail(cat(path, " = ", v, " is out of range ", r));
        return v;
    }

    float real(const json& j, const std::string& path, const Interval& r) const {
        return static_cast<float>(number(j, path, r));
    }

    std::int64_t integer(const json& j, const std::string& path, std::int64_t lo,
                         std::int64_t hi) const {
        if (!j.is_number_integer())
            fail(cat(path, " must be an integer, got ",
                     j.is_number() ? "a fractional number" : j.type_name()));
        if (j.is_number_unsigned()) {
            const auto u = j.get<std::uint64_t>();
            if (u > static_cast<std::uint64_t>(hi))
                fail(cat(path, " = ", u, " is out of range [", lo, ", ", hi, "]"));
            return static_cast<std::int64_t>(u);
        }
        const auto v = j.get<std::int64_t>();
        if (v < lo || v > hi)
            fail(cat(path, " = ", v, " is out of range [", lo, ", ", hi, "]"));
        return v;
    }

    const json& array(const json& j, const std::string& path, std::size_t size,
                      std::string_view what) const {
        if (!j.is_array())
            fail(cat(path, " must be an array of ", size, " ", what, ", got ", j.type_name()));
        if (j.size() != size)
            fail(cat(path, " must be an array of ", size, " ", what, ", got ", j.size(),
                     j.size() == 1 ? " element" : " elements"));
        return j;
    }

    glm::vec3 vec3(const json& j, const std::string& path, const Interval& r) const {
        array(j, path, 3, "numbers");
        return {real(j[0], index(path, 0), r), real(j[1], index(path, 1), r),
                real(j[2], index(path, 2), r)};
    }

    std::string string(const json& j, const std::string& path, bool allowEmpty) const {
        if (!j.is_string())
            fail(cat(path, " must be a string, got ", j.type_name()));
        const auto& s = j.get_ref<const std::string&>();
        if (!allowEmpty && s.empty())
            fail(cat(path, " must not be empty"));
        if (s.size() > kMaxStringLength)
            fail(cat(path, " is longer than ", kMaxStringLength, " characters"));
        return s;
    }

    /// A field value: a number (broadcast to 3 components for vec3 slots) or, for vec3 slots
    /// only, an array of 3. Unused components stay zero.
    glm::vec3 fieldValue(const json& j, const std::string& path, int components,
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
    void fieldRange(const json& j, const std::string& path, int components, const Interval& r,
                    FieldDesc& desc) const {
        array(j, path, 2, "values [lo, hi]");
        desc.lo = fieldValue(j[0], index(path, 0), components, r);
        desc.hi = fieldValue(j[1], index(path, 1), components, r);
    }

    FieldDesc field(const json& j, const std::string& path, int components,
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
            if (const json* f = find(j, "frequency"))
                desc.frequency = real(*f, join(path, "frequency"), kFrequency);
            if (const json* o = find(j, "octaves"))
                desc.octaves = static_cast<int>(integer(*o, join(path, "octaves"), 1, 8));
            if (const json* s = find(j, "seed"))
                desc.seed = static_cast<std::uint32_t>(
                    integer(*s, join(path, "seed"), 0, std::int64_t{UINT32_MAX}));
            fieldRange(require(j, path, "range"), join(path, "range"), components, r, desc);
        } else if (type == "vertex") {
            requireObject(j, path, {"type", "attribute"});
            desc.kind = FieldDesc::Kind::Vertex;
            const json& a = require(j, path, "attribute");
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
            requireObject(j, path, {"type", "file", "channel", "wrap", "range"});
            desc.kind = FieldDesc::Kind::Image;
            desc.file = string(require(j, path, "file"), join(path, "file"), false);
            if (const json* c = find(j, "channel"))
                desc.channel = static_cast<int>(integer(*c, join(path, "channel"), 0, 1023));
            if (const json* w = find(j, "wrap")) {
                const std::string wrap = string(*w, join(path, "wrap"), false);
                if (wrap != "repeat" && wrap != "clamp")
                    fail(cat(join(path, "wrap"), " = \"", printable(wrap),
                             "\" is not one of \"repeat\", \"clamp\""));
                desc.repeat = wrap == "repeat";
            }
            fieldRange(require(j, path, "range"), join(path, "range"), components, r, desc);
        } else {
            fail(cat(join(path, "type"), " = \"", printable(type),
                     "\" is not one of \"constant\", \"gradient\", \"noise\", \"vertex\", "
                     "\"image\""));
        }
        return desc;
    }

private:
    const std::string& m_file;
};

FieldDesc constantField(int components, float v) {
    FieldDesc d;
    d.kind = FieldDesc::Kind::Constant;
    d.components = components;
    d.value = components == 1 ? glm::vec3(v, 0.0f, 0.0f) : glm::vec3(v);
    return d;
}

LobeDesc parseLobe(const Reader& rd, const json& j, const std::string& path) {
    rd.requireObject(j, path, {"offset", "rotation_deg", "sigma", "extinction", "color"});
    LobeDesc lobe;
    if (const json* v = Reader::find(j, "offset"))
        lobe.offset = rd.vec3(*v, join(path, "offset"), kKernelOffset);
    if (const json* v = Reader::find(j, "rotation_deg"))
        lobe.rotationDeg = rd.vec3(*v, join(path, "rotation_deg"), kRotationDeg);
    if (const json* v = Reader::find(j, "sigma"))
        lobe.sigma = rd.vec3(*v, join(path, "sigma"), kSigma);
    if (const json* v = Reader::find(j, "extinction"))
        lobe.extinction = rd.real(*v, join(path, "extinction"), kExtinction);
    if (const json* v = Reader::find(j, "color"))
        lobe.color = rd.vec3(*v, join(path, "color"), kUnit);
    return lobe;
}

KernelDesc parseKernel(const Reader& rd, const json& j, const std::string& path) {
    rd.requireObject(j, path, {"support_sigma", "lobes"});
    KernelDesc kernel;
    if (const json* v = Reader::find(j, "support_sigma"))
        kernel.supportSigma = rd.real(*v, join(path, "support_sigma"), kSupportSigma);
    const std::string lobesPath = join(path, "lobes");
    const json& lobes = rd.require(j, path, "lobes");
    if (!lobes.is_array())
        rd.fail(cat(lobesPath, " must be an array of lobe objects, got ", lobes.type_name()));
    if (lobes.empty() || lobes.size() > static_cast<std::size_t>(kMaxLobes))
        rd.fail(cat(lobesPath, " has ", lobes.size(), " lobes; a kernel needs 1 to ", kMaxLobes));
    for (std::size_t i = 0; i < lobes.size(); ++i)
        kernel.lobes.push_back(parseLobe(rd, lobes[i], index(lobesPath, i)));
    return kernel;
}

DistributionDesc parseDistribution(const Reader& rd, const json& j, const std::string& path) {
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
    if (const json* v = Reader::find(j, "jitter"))
        d.jitter = rd.real(*v, join(path, "jitter"), kUnit);
    if (const json* v = Reader::find(j, "height_offset"))
        d.heightOffset = rd.real(*v, join(path, "height_offset"), kHeightOffset);
    if (const json* v = Reader::find(j, "height_jitter"))
        d.heightJitter = rd.real(*v, join(path, "height_jitter"), kHeightJitter);
    return d;
}

void parseFields(const Reader& rd, const json& j, const std::string& path, PresetDesc& p) {
    rd.requireObject(
        j, path,
        {"density", "comb", "tilt_deg", "spin_deg", "bend_deg", "scale", "color", "weight"});
    const auto slot = [&](std::string_view key, int components, const Interval& r, FieldDesc& out) {
        if (const json* v = Reader::find(j, key))
            out = rd.field(*v, join(path, key), components, r);
    };
    slot("density", 1, kUnit, p.density);
    if (Reader::find(j, "comb")) {
        FieldDesc comb;
        slot("comb", 3, kDirection, comb);
        p.comb = comb;
    }
    slot("tilt_deg", 1, kAngleDeg, p.tiltDeg);
    slot("spin_deg", 1, kAngleDeg, p.spinDeg);
    slot("bend_deg", 1, kBendDeg, p.bendDeg);
    slot("scale", 3, kScale, p.scale);
    slot("color", 3, kUnit, p.color);
    slot("weight", 1, kWeight, p.weight);
}

VariationDesc parseVariation(const Reader& rd, const json& j, const std::string& path) {
    rd.requireObject(j, path, {"tilt_deg", "spin_deg", "bend_deg", "scale", "color", "weight"});
    VariationDesc v;
    const auto read = [&](std::string_view key, const Interval& r, float& out) {
        if (const json* x = Reader::find(j, key))
            out = rd.real(*x, join(path, key), r);
    };
    read("tilt_deg", kVariationAngle, v.tiltDeg);
    read("spin_deg", kVariationAngle, v.spinDeg);
    read("bend_deg", kVariationBend, v.bendDeg);
    read("scale", kUnitOpenHi, v.scale);
    read("color", kUnitOpenHi, v.color);
    read("weight", kUnitOpenHi, v.weight);
    return v;
}

/// nlohmann keeps the last of duplicate keys silently; a preset with two "density" entries is a
/// mistake the user should hear about. The callback also bounds the nesting depth.
json parseJson(std::string_view text, const std::string& name) {
    std::vector<std::set<std::string>> keysPerObject;
    const auto callback = [&](int depth, json::parse_event_t event, json& parsed) {
        switch (event) {
        case json::parse_event_t::object_start:
        case json::parse_event_t::array_start:
            if (depth >= kMaxJsonDepth)
                throw InputError(cat(name, ": JSON nested deeper than ", kMaxJsonDepth, " levels"));
            if (event == json::parse_event_t::object_start)
                keysPerObject.emplace_back();
            break;
        case json::parse_event_t::key:
            if (!keysPerObject.empty() &&
                !keysPerObject.back().insert(parsed.get<std::string>()).second)
                throw InputError(cat(name, ": duplicate key \"",
                                     printable(parsed.get_ref<const std::string&>()), "\""));
            break;
        case json::parse_event_t::object_end:
            if (!keysPerObject.empty())
                keysPerObject.pop_back();
            break;
        default:
            break;
        }
        return true;
    };
    try {
        return json::parse(text.begin(), text.end(), callback);
    } catch (const json::parse_error& e) {
        // what() is "[json.exception.parse_error.101] parse error at line L, column C: <reason>"
        std::string detail = e.what();
        if (const auto pos = detail.find("] "); pos != std::string::npos)
            detail = detail.substr(pos + 2);
        constexpr std::string_view kAt = "parse error at ";
        std::string location;
        if (detail.rfind(kAt, 0) == 0) {
            if (const auto colon = detail.find(": "); colon != std::string::npos) {
                location = cat(" (", detail.substr(kAt.size(), colon - kAt.size()), ")");
                detail = detail.substr(colon + 2);
            }
        }
        throw InputError(cat(name, ": invalid JSON at byte ", e.byte, location, ": ",
                             printable(detail, kMaxDetailShown)));
    } catch (const json::exception& e) {
        // Not a syntax error but still the document's fault, e.g. "number overflow parsing
        // '1e999'".
        std::string detail = e.what();
        if (const auto pos = detail.find("] "); pos != std::string::npos)
            detail = detail.substr(pos + 2);
        throw InputError(cat(name, ": invalid JSON: ", printable(detail, kMaxDetailShown)));
    }
}

} // namespace

PresetDesc parsePreset(std::string_view text, const std::string& name) {
    if (text.size() > kMaxPresetBytes)
        throw InputError(cat(name, ": preset is ", text.size(), " bytes, more than the limit of ",
                             kMaxPresetBytes));
    const json root = parseJson(text, name);
    const Reader rd(name);
    rd.requireObject(
        root, "",
        {"version", "name", "description", "kernel", "distribution", "fields", "variation"});

    PresetDesc p;
    const json& version = rd.require(root, "", "version");
    if (!version.is_number_integer())
        rd.fail(cat("version must be the integer ", kPresetVersion, ", got ",
                    version.is_number() ? "a fractional number" : version.type_name()));
    if (version.is_number_unsigned() ? version.get<std::uint64_t>() != kPresetVersion
                                     : version.get<std::int64_t>() != kPresetVersion)
        rd.fail(cat("version = ", version.dump(), " is not supported (this build reads version ",
                    kPresetVersion, ")"));
    p.version = kPresetVersion;

    if (const json* n = Reader::find(root, "name"))
        p.name = rd.string(*n, "name", false);
    else
        p.name = std::filesystem::path(name).stem().string();
    if (const json* d = Reader::find(root, "description"))
        rd.string(*d, "description", true); // documentation for humans, checked but not kept

    p.kernel = parseKernel(rd, rd.require(root, "", "kernel"), "kernel");
    p.distribution = parseDistribution(rd, rd.require(root, "", "distribution"), "distribution");

    p.density = constantField(1, 1.0f);
    p.tiltDeg = constantField(1, 0.0f);
    p.spinDeg = constantField(1, 0.0f);
    p.bendDeg = constantField(1, 0.0f);
    p.scale = constantField(3, 1.0f);
    p.color = constantField(3, 1.0f);
    p.weight = constantField(1, 1.0f);
    if (const json* f = Reader::find(root, "fields"))
        parseFields(rd, *f, "fields", p);
    if (const json* v = Reader::find(root, "variation"))
        p.variation = parseVariation(rd, *v, "variation");
    return p;
}

PresetDesc loadPreset(const std::filesystem::path& file) {
    const std::string text = readFileCapped(file, kMaxPresetBytes);
    PresetDesc p = parsePreset(text, file.string());
    p.baseDir = file.parent_path();
    return p;
}

} // namespace spot::noise
