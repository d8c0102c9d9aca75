#include "noise/field.h"

#include <algorithm>
#include <bit>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <iterator>
#include <limits>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>

#include "noise/error.h"
#include "noise/generator_shared.h"
#include "noise/image.h"
#include "noise/mesh.h"
#include "noise/painted.h"
#include "noise/system.h"
#include "shaders/spot_layout.hpp"
#include "shaders/spot_shared.hpp"

namespace spot::noise {

using Generator = shared::f32::SharedGenerator;

/// The field's own shared form, for eval: the parameters (the field in slot 0) and its data.
struct Field::Flat {
    std::mutex mutex;
    bool valid = false;
    std::uint64_t version = 0;
    gpu::SpotGenParams params{};
    std::vector<float> data;
};

Field::~Field() = default;

glm::vec3 Field::eval(const SurfacePoint& p) const {
    // m_flat is made by the first call; concurrent first calls are not supported (a field is
    // evaluated first by the thread that bound it: the generator, the editor).
    if (!m_flat)
        m_flat = std::make_unique<Flat>();
    Flat& f = *m_flat;
    {
        std::lock_guard lock(f.mutex);
        const std::uint64_t v = version();
        if (!f.valid || f.version != v) {
            f.data.clear();
            f.params = gpu::SpotGenParams{};
            f.params.fields[0] = shared(f.data);
            f.version = v;
            f.valid = true;
        }
    }
    shared::f32::GeneratorArrays arrays;
    arrays.triangles = m_triangles;
    arrays.fieldData = f.data.data();
    arrays.params = &f.params;
    Generator generator(arrays);
    Generator::SpotSurface s{};
    s.position = p.position;
    s.normal = p.normal;
    s.tangent = p.tangent;
    s.uv = p.uv;
    s.triangle = p.triangle;
    s.bary = p.barycentric;
    return generator.spotFieldEval(0u, s);
}

namespace {

/// Images are decoded to float in memory; this caps what one field may hold (all channels of the
/// file count, since the decoder may allocate them even when only some are kept).
constexpr std::uint64_t kMaxImageBytes = 1ull << 30;
constexpr float kMinGradientLength = 1e-6f;

gpu::SpotField sharedField(int kind, int components) {
    gpu::SpotField f{};
    f.kind = glm::ivec4(kind, components, 1, 0);
    return f;
}

/// The offset of `values` once appended to the shared data array (checked to fit 32 bits).
std::uint32_t appendData(std::vector<float>& data, const float* values, std::size_t count) {
    SPOT_CHECK_LE(data.size() + count, std::size_t(UINT32_MAX));
    const auto offset = static_cast<std::uint32_t>(data.size());
    data.insert(data.end(), values, values + count);
    return offset;
}

glm::vec3 keepComponents(glm::vec3 v, int components) {
    return components == 1 ? glm::vec3(v.x, 0.0f, 0.0f) : v;
}

/// The map of the mapped kinds (gradient, noise, image): spotFieldMap clamps their outputs to the
/// interval lo and hi span (`mix` in float can land one ulp outside it; range() promises exact
/// bounds).
struct LinearMap {
    glm::vec3 lo;
    glm::vec3 hi;
    glm::vec3 min;
    glm::vec3 max;

    LinearMap(glm::vec3 l, glm::vec3 h) : lo(l), hi(h), min(glm::min(l, h)), max(glm::max(l, h)) {}
};

class ConstantField final : public Field {
public:
    explicit ConstantField(glm::vec3 value) : m_value(value) {}
    FieldRange range() const override { return {m_value, m_value}; }
    gpu::SpotField shared(std::vector<float>&) const override {
        gpu::SpotField f = sharedField(Generator::kFieldConstant, 3);
        f.value = glm::vec4(m_value, 0.0f);
        return f;
    }

private:
    glm::vec3 m_value;
};

/// lo at `from`, hi at `to`, linear in the projection of the point on the from->to line.
class GradientField final : public Field {
public:
    GradientField(glm::vec3 from, glm::vec3 to, LinearMap map)
        : m_from(from), m_axis((to - from) / glm::dot(to - from, to - from)), m_map(map) {}
    FieldRange range() const override { return {m_map.min, m_map.max}; }
    gpu::SpotField shared(std::vector<float>&) const override {
        // Unused components have lo = hi = 0, so all three map to the same values as eval.
        gpu::SpotField f = sharedField(Generator::kFieldGradient, 3);
        f.from = glm::vec4(m_from, 0.0f);
        f.axis = glm::vec4(m_axis, 0.0f);
        f.lo = glm::vec4(m_map.lo, 0.0f);
        f.hi = glm::vec4(m_map.hi, 0.0f);
        return f;
    }

private:
    glm::vec3 m_from;
    glm::vec3 m_axis; ///< (to - from) / |to - from|^2, so the dot product is 0 at from, 1 at to
    LinearMap m_map;
};

class NoiseField final : public Field {
public:
    NoiseField(float frequency, int octaves, std::uint32_t seed, LinearMap map)
        : m_frequency(frequency), m_octaves(octaves), m_seed(seed), m_map(map) {}
    FieldRange range() const override { return {m_map.min, m_map.max}; }
    gpu::SpotField shared(std::vector<float>&) const override {
        gpu::SpotField f = sharedField(Generator::kFieldNoise, 3);
        f.kind.z = m_octaves;
        f.kind.w = static_cast<std::int32_t>(m_seed);
        f.from = glm::vec4(0.0f, 0.0f, 0.0f, m_frequency);
        f.lo = glm::vec4(m_map.lo, 0.0f);
        f.hi = glm::vec4(m_map.hi, 0.0f);
        return f;
    }

private:
    float m_frequency;
    int m_octaves;
    std::uint32_t m_seed;
    LinearMap m_map;
};

/// Barycentric interpolation of per-vertex attributes. Holds pointers into the mesh, which must
/// outlive the field (fields are bound to one mesh for one render or bake).
class VertexField final : public Field {
public:
    VertexField(const Mesh& mesh, std::vector<const std::vector<float>*> attributes)
        : m_attributes(std::move(attributes)) {
        m_triangles = mesh.triangles.data();
        m_range.lo = glm::vec3(0.0f);
        m_range.hi = glm::vec3(0.0f);
        for (std::size_t c = 0; c < m_attributes.size(); ++c) {
            const auto [lo, hi] =
                std::minmax_element(m_attributes[c]->begin(), m_attributes[c]->end());
            m_range.lo[static_cast<int>(c)] = lo == m_attributes[c]->end() ? 0.0f : *lo;
            m_range.hi[static_cast<int>(c)] = hi == m_attributes[c]->end() ? 0.0f : *hi;
        }
    }
    FieldRange range() const override { return m_range; }
    gpu::SpotField shared(std::vector<float>& data) const override {
        gpu::SpotField f = sharedField(Generator::kFieldVertex, static_cast<int>(m_attributes.size()));
        std::uint32_t offsets[3] = {0, 0, 0};
        for (std::size_t c = 0; c < m_attributes.size() && c < 3; ++c)
            offsets[c] = appendData(data, m_attributes[c]->data(), m_attributes[c]->size());
        f.data = glm::uvec4(offsets[0], offsets[1], offsets[2], 0u);
        f.clampLo = glm::vec4(m_range.lo, 0.0f);
        f.clampHi = glm::vec4(m_range.hi, 0.0f);
        return f;
    }

private:
    std::vector<const std::vector<float>*> m_attributes; ///< one per component
    FieldRange m_range;
};

/// Bilinear lookup of a float image through uv. Texels are stored top row first (as images are),
/// so v is flipped: uv (0,0) is the bottom-left corner of the image and texel centres lie at
/// ((i + 0.5) / width, 1 - (j + 0.5) / height).
class ImageField final : public Field {
public:
    ImageField(int width, int height, int components, std::vector<float> texels, bool repeat,
               LinearMap map)
        : m_width(width), m_height(height), m_components(components), m_texels(std::move(texels)),
          m_repeat(repeat), m_map(map) {
        // Bounds of the stored texels; bilinear weights are convex, so no lookup leaves them.
        m_tMin = glm::vec3(1.0f);
        m_tMax = glm::vec3(0.0f);
        for (std::size_t i = 0; i < m_texels.size(); ++i) {
            const int c = static_cast<int>(i % static_cast<std::size_t>(m_components));
            m_tMin[c] = std::min(m_tMin[c], m_texels[i]);
            m_tMax[c] = std::max(m_tMax[c], m_texels[i]);
        }
        m_tMin = keepComponents(m_tMin, m_components);
        m_tMax = keepComponents(m_tMax, m_components);
        const glm::vec3 a = mapEach(m_tMin);
        const glm::vec3 b = mapEach(m_tMax);
        m_range = {keepComponents(glm::min(a, b), m_components),
                   keepComponents(glm::max(a, b), m_components)};
    }

    FieldRange range() const override { return m_range; }
    gpu::SpotField shared(std::vector<float>& data) const override {
        gpu::SpotField f = sharedField(Generator::kFieldImage, m_components);
        f.data = glm::uvec4(appendData(data, m_texels.data(), m_texels.size()),
                            static_cast<std::uint32_t>(m_width), static_cast<std::uint32_t>(m_height),
                            m_repeat ? 1u : 0u);
        f.clampLo = glm::vec4(m_tMin, 0.0f);
        f.clampHi = glm::vec4(m_tMax, 0.0f);
        f.lo = glm::vec4(m_map.lo, 0.0f);
        f.hi = glm::vec4(m_map.hi, 0.0f);
        return f;
    }

private:
    /// Each component maps through its own lo/hi (a texel value t per component).
    glm::vec3 mapEach(glm::vec3 t) const {
        glm::vec3 out;
        for (int c = 0; c < 3; ++c)
            out[c] = std::clamp(m_map.lo[c] * (1.0f - t[c]) + m_map.hi[c] * t[c], m_map.min[c],
                                m_map.max[c]);
        return out;
    }

    int m_width;
    int m_height;
    int m_components;
    std::vector<float> m_texels; ///< row-major, top row first, m_components floats per texel
    bool m_repeat;
    LinearMap m_map;
    glm::vec3 m_tMin{0.0f};
    glm::vec3 m_tMax{0.0f};
    FieldRange m_range;
};

/// The trilinear interpolation of a painted sparse grid at the surface point's position. Shares
/// the grid (the editor's live one, or one read from a file).
class PaintedField final : public Field {
public:
    explicit PaintedField(std::shared_ptr<const PaintedGrid> grid) : m_grid(std::move(grid)) {}
    FieldRange range() const override {
        FieldRange r;
        m_grid->valueRange(r.lo, r.hi);
        return r;
    }
    gpu::SpotField shared(std::vector<float>& data) const override { return m_grid->flatten(data); }

protected:
    std::uint64_t version() const override { return m_grid->version(); }

private:
    std::shared_ptr<const PaintedGrid> m_grid;
};

/// The surface tangent (an unset comb), as the base of a painted comb.
class TangentField final : public Field {
public:
    FieldRange range() const override { return {glm::vec3(-1.0f), glm::vec3(1.0f)}; }
    gpu::SpotField shared(std::vector<float>&) const override {
        return sharedField(Generator::kFieldTangent, 3);
    }
};

/// A paint layer over a base field (PaintMode): spotFieldLayer over the base's value.
class LayeredField final : public Field {
public:
    LayeredField(std::unique_ptr<Field> base, std::shared_ptr<const PaintLayer> layer,
                 const Mesh& mesh)
        : m_base(std::move(base)), m_layer(std::move(layer)) {
        m_triangles = mesh.triangles.data();
    }
    FieldRange range() const override {
        const FieldRange b = m_base->range();
        glm::vec3 vLo, vHi, wLo, wHi;
        m_layer->value().valueRange(vLo, vHi);
        m_layer->weight().valueRange(wLo, wHi);
        if (m_layer->mode() == PaintMode::Density) {
            // b m + (1 - b m) r grows with b m and with r (all in [0, 1]).
            const auto f = [](float bm, float r) { return bm + (1.0f - bm) * r; };
            return {glm::vec3(f(b.lo.x * vLo.x, wLo.x), 0.0f, 0.0f),
                    glm::vec3(f(b.hi.x * vHi.x, wHi.x), 0.0f, 0.0f)};
        }
        // A convex combination of the base and the values (w in [0, 1]).
        const int n = m_layer->components();
        return {keepComponents(glm::min(b.lo, vLo), n), keepComponents(glm::max(b.hi, vHi), n)};
    }
    gpu::SpotField shared(std::vector<float>& data) const override {
        gpu::SpotField f = m_base->shared(data);
        const gpu::SpotField grids[2] = {m_layer->value().flatten(data),
                                         m_layer->weight().flatten(data)};
        static_assert(sizeof(gpu::SpotField) == Generator::kFieldFloats * sizeof(float));
        float stored[2 * Generator::kFieldFloats];
        std::memcpy(stored, grids, sizeof(grids));
        const std::uint32_t at = appendData(data, stored, std::size(stored));
        f.axis.w = std::bit_cast<float>(at);
        f.kind.x |= m_layer->mode() == PaintMode::Density ? Generator::kFieldLayeredDensity
                                                          : Generator::kFieldLayered;
        return f;
    }

protected:
    std::uint64_t version() const override { return m_layer->version(); }

private:
    std::unique_ptr<Field> m_base;
    std::shared_ptr<const PaintLayer> m_layer;
};

std::unique_ptr<Field> makePaintedField(const FieldDesc& desc, const std::filesystem::path& baseDir,
                                        const std::string& context) {
    std::shared_ptr<const PaintedGrid> grid = desc.painted;
    if (!grid) {
        if (desc.file.empty())
            throw InputError(cat(context, ": painted field has no file"));
        const std::filesystem::path file = std::filesystem::path(desc.file).is_absolute()
                                               ? std::filesystem::path(desc.file)
                                               : baseDir / desc.file;
        try {
            grid = std::make_shared<const PaintedGrid>(
                readPaintedGrid(file, desc.grid, desc.components));
        } catch (const InputError& e) {
            throw InputError(cat(context, ": ", e.what()));
        }
    }
    if (grid->components() != desc.components)
        throw InputError(cat(context, ": painted grid \"", grid->name(), "\" has ",
                             grid->components(), " components, the slot needs ", desc.components));
    return std::make_unique<PaintedField>(std::move(grid));
}

/// How an image's texels are encoded, decided from the preset's key and the file's header.
struct TexelEncoding {
    enum class Kind { Linear, Srgb, Gamma } kind = Kind::Linear;
    float gamma = 1.0f; ///< Gamma: linear = stored ^ gamma
};

/// The encoding OpenImageIO's `oiio:ColorSpace` names (OIIO 2.4 says "sRGB", "Linear",
/// "GammaX.Y"; OIIO 2.5+ adds the colour-interop names "srgb_rec709_scene",
/// "lin_rec709_scene", "g22_rec709_scene"), or nothing for a name it does not say.
std::optional<TexelEncoding> encodingNamed(std::string name, float gammaAttribute) {
    std::transform(name.begin(), name.end(), name.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    if (name.empty())
        return std::nullopt;
    if (name == "srgb" || name.starts_with("srgb_"))
        return TexelEncoding{TexelEncoding::Kind::Srgb, 1.0f};
    if (name == "linear" || name.starts_with("lin_") || name == "scene_linear" || name == "raw" ||
        name == "acescg" || name == "aces2065-1")
        return TexelEncoding{TexelEncoding::Kind::Linear, 1.0f};
    float gamma = 0.0f;
    if (name.starts_with("gamma"))
        gamma = std::strtof(name.c_str() + 5, nullptr);
    else if (name.size() > 4 && name[0] == 'g' && name[3] == '_' &&
             std::isdigit(static_cast<unsigned char>(name[1])) &&
             std::isdigit(static_cast<unsigned char>(name[2])))
        gamma = static_cast<float>(name[1] - '0') + 0.1f * static_cast<float>(name[2] - '0');
    if (!(gamma > 0.0f) && gammaAttribute > 0.0f && name == "gammacorrected")
        gamma = gammaAttribute;
    if (gamma > 0.0f && gamma < 10.0f)
        return TexelEncoding{TexelEncoding::Kind::Gamma, gamma};
    return std::nullopt;
}

TexelEncoding texelEncoding(FieldDesc::ColorSpace space, const OIIO::ImageSpec& spec) {
    switch (space) {
    case FieldDesc::ColorSpace::Srgb:
        return {TexelEncoding::Kind::Srgb, 1.0f};
    case FieldDesc::ColorSpace::Linear:
        return {TexelEncoding::Kind::Linear, 1.0f};
    case FieldDesc::ColorSpace::Auto:
        break;
    }
    if (const std::optional<TexelEncoding> named =
            encodingNamed(spec.get_string_attribute("oiio:ColorSpace"),
                          spec.get_float_attribute("oiio:Gamma", 0.0f)))
        return *named;
    // No colour space, or one we cannot name: 8-bit images are painted and photographed in
    // sRGB, deeper and float ones hold linear data.
    if (spec.format.size() == 1 && !spec.format.is_floating_point())
        return {TexelEncoding::Kind::Srgb, 1.0f};
    return {TexelEncoding::Kind::Linear, 1.0f};
}

/// An image's texels as floats, decoded to linear.
struct DecodedImage {
    int width = 0, height = 0, channels = 0;
    int alphaChannel = -1; ///< among the channels read (-1: none)
    std::vector<float> texels;
};

/// Channels [first, first + count) of an opened image (count 0: all of them), clamped to [0, 1]
/// (NaN read as 0) and decoded to linear by `space` and the file's header; an alpha channel is
/// never decoded. `where` names the image in messages.
DecodedImage decodeImage(OIIO::ImageInput& in, int first, int count, FieldDesc::ColorSpace space,
                         const std::string& where) {
    // Everything below is decided from the header, before any pixel is decoded.
    const OIIO::ImageSpec& spec = in.spec();
    if (spec.width <= 0 || spec.height <= 0 || spec.nchannels <= 0)
        throw InputError(cat(where, ": image has no pixels (", spec.width, "x", spec.height, ", ",
                             spec.nchannels, " channels)"));
    if (spec.depth > 1)
        throw InputError(cat(where, ": volume images are not supported"));
    if (count == 0)
        count = spec.nchannels - first;
    if (first < 0 || count <= 0 || first + count > spec.nchannels)
        throw InputError(cat(where, ": needs channels ", first, "..", first + count - 1,
                             " but the image has ", spec.nchannels,
                             spec.nchannels == 1 ? " channel" : " channels"));
    const std::uint64_t pixels =
        static_cast<std::uint64_t>(spec.width) * static_cast<std::uint64_t>(spec.height);
    const std::uint64_t perPixel = static_cast<std::uint64_t>(spec.nchannels) * sizeof(float);
    if (pixels > kMaxImageBytes / perPixel)
        throw InputError(cat(where, ": image is too large (", spec.width, "x", spec.height, " x ",
                             spec.nchannels, " channels as float exceeds ", kMaxImageBytes >> 20,
                             " MiB)"));
    requireMemory(pixels * perPixel, where);

    DecodedImage out;
    out.width = spec.width;
    out.height = spec.height;
    out.channels = count;
    out.alphaChannel = spec.alpha_channel >= first && spec.alpha_channel < first + count
                           ? spec.alpha_channel - first
                           : -1;
    out.texels.resize(pixels * static_cast<std::uint64_t>(count));
    bool ok = false;
    StderrSilencer quiet; // libpng prints its own copy of errors we report ourselves
    try {
        ok = in.read_image(0, 0, first, first + count, OIIO::TypeDesc::FLOAT, out.texels.data());
    } catch (const std::exception& e) {
        throw InputError(cat(where, ": cannot decode (", oneLine(e.what()), ")"));
    }
    if (!ok)
        throw InputError(cat(where, ": cannot decode (", oneLine(in.geterror()), ")"));
    in.close();

    // The field maps [0,1] to [lo, hi]; float images may hold anything, NaN included. Texels
    // are decoded to linear here, once, so the CPU and the GPU read the same values.
    const TexelEncoding encoding = texelEncoding(space, spec);
    const std::size_t n = static_cast<std::size_t>(count);
    for (std::size_t i = 0; i < out.texels.size(); ++i) {
        float& t = out.texels[i];
        t = std::isnan(t) ? 0.0f : std::clamp(t, 0.0f, 1.0f);
        if (static_cast<int>(i % n) == out.alphaChannel)
            continue; // coverage, never colour-encoded
        if (encoding.kind == TexelEncoding::Kind::Srgb)
            t = srgbDecode(t);
        else if (encoding.kind == TexelEncoding::Kind::Gamma)
            t = std::pow(t, encoding.gamma);
    }
    return out;
}

/// An image file opened for reading (its alpha as stored), or InputError naming `where`.
/// `proxy`: read from memory instead, `file` then only names the format (its extension).
std::unique_ptr<OIIO::ImageInput> openImage(const std::filesystem::path& file,
                                            const std::string& where,
                                            OIIO::Filesystem::IOProxy* proxy = nullptr) {
    // Alpha as stored: a density or weight map in the alpha channel must not be premultiplied.
    OIIO::ImageSpec config;
    config.attribute("oiio:UnassociatedAlpha", 1);
    std::unique_ptr<OIIO::ImageInput> in;
    StderrSilencer quiet; // libpng prints its own copy of errors we report ourselves
    try {
        if (!proxy) {
            in = OIIO::ImageInput::open(file.string(), &config);
        } else {
            // From memory: the reader for the format the name says, given the bytes (OIIO 2.4
            // takes the proxy as the configuration's "oiio:ioproxy" pointer).
            config.attribute("oiio:ioproxy", OIIO::TypeDesc::PTR, &proxy);
            in = OIIO::ImageInput::open(file.string(), &config, proxy);
        }
    } catch (const InputError&) {
        throw;
    } catch (const std::exception& e) {
        throw InputError(cat(where, ": cannot read (", oneLine(e.what()), ")"));
    }
    if (!in)
        throw InputError(cat(where, ": cannot read (", oneLine(OIIO::geterror()), ")"));
    return in;
}

std::unique_ptr<Field> makeImageField(const FieldDesc& desc, const Mesh& mesh,
                                      const std::filesystem::path& baseDir,
                                      const std::string& context) {
    if (desc.file.empty())
        throw InputError(cat(context, ": image field has no file"));
    const std::filesystem::path file = std::filesystem::path(desc.file).is_absolute()
                                           ? std::filesystem::path(desc.file)
                                           : baseDir / desc.file;
    const std::string where = cat(context, ": image ", file.string());
    if (!mesh.hasUv())
        throw InputError(
            cat(where, ": mesh ", mesh.name, " has no uv coordinates, which an image field needs"));
    std::error_code ec;
    if (!std::filesystem::is_regular_file(file, ec))
        throw InputError(cat(where, ": no such file"));
    std::unique_ptr<OIIO::ImageInput> in = openImage(file, where);
    DecodedImage image =
        decodeImage(*in, desc.channel, desc.components, desc.colorSpace, where);
    return std::make_unique<ImageField>(image.width, image.height, desc.components,
                                        std::move(image.texels), desc.repeat,
                                        LinearMap(keepComponents(desc.lo, desc.components),
                                                  keepComponents(desc.hi, desc.components)));
}

/// The material a material field names (by name, by index, or the one the growing triangles
/// use), or InputError listing the mesh's materials.
const MeshMaterial& chooseMaterial(const FieldDesc& desc, const Mesh& mesh,
                                   const std::string& context) {
    std::string names;
    for (std::size_t i = 0; i < mesh.materials.size(); ++i)
        names += cat(i ? ", " : "", i, " '", mesh.materials[i].name, "'");
    if (mesh.materials.empty())
        throw InputError(cat(context, ": a material field reads a glTF material, and mesh ",
                             mesh.name, " has none"));
    if (desc.materialIndex >= 0) {
        if (std::size_t(desc.materialIndex) >= mesh.materials.size())
            throw InputError(cat(context, ": material ", desc.materialIndex, " is not one of ",
                                 mesh.name, "'s (", names, ")"));
        return mesh.materials[std::size_t(desc.materialIndex)];
    }
    if (!desc.material.empty()) {
        for (const MeshMaterial& m : mesh.materials)
            if (m.name == desc.material)
                return m;
        throw InputError(cat(context, ": material '", desc.material, "' is not one of ", mesh.name,
                             "'s (", names, ")"));
    }
    // The materials of the parts that grow fur.
    std::vector<int> used;
    for (const MeshPart& p : mesh.parts)
        if (p.grows && p.triangles > 0 && p.material >= 0 &&
            std::find(used.begin(), used.end(), p.material) == used.end())
            used.push_back(p.material);
    if (used.size() == 1)
        return mesh.materials[std::size_t(used.front())];
    std::string usedNames;
    for (std::size_t i = 0; i < used.size(); ++i)
        usedNames += cat(i ? ", " : "", used[i], " '", mesh.materials[std::size_t(used[i])].name, "'");
    throw InputError(cat(context, ": the triangles that grow fur use ",
                         used.empty() ? std::string("no material")
                                      : cat(used.size(), " materials (", usedNames, ")"),
                         "; name one with \"material\""));
}

/// A glTF material's base colour as an image field: its texture (sRGB, as glTF says) times its
/// factor, or the factor alone (a 1 x 1 image), channels `desc.channel`.. of RGBA.
std::unique_ptr<Field> makeMaterialField(const FieldDesc& desc, const Mesh& mesh,
                                         const std::string& context) {
    const MeshMaterial& m = chooseMaterial(desc, mesh, context);
    const std::string where = cat(context, ": material '", m.name, "' of ", mesh.name);
    DecodedImage image;
    if (!m.hasTexture()) {
        image.width = image.height = 1;
        image.channels = 4;
        image.alphaChannel = 3;
        image.texels = {1.0f, 1.0f, 1.0f, 1.0f};
    } else {
        if (!mesh.hasUv())
            throw InputError(cat(where, ": its texture needs uv, and the mesh has none (some "
                                        "primitive has no TEXCOORD_0)"));
        if (m.texCoord != 0)
            throw InputError(cat(where, ": its base colour texture reads TEXCOORD_", m.texCoord,
                                 "; spotshell reads TEXCOORD_0"));
        const std::string texture = cat(where, ", texture '", m.texture, "'");
        std::unique_ptr<OIIO::ImageInput> in;
        std::optional<OIIO::Filesystem::IOMemReader> memory;
        if (m.textureBytes) {
            // The format from the bytes: PNG's and JPEG's signatures.
            const std::string& b = *m.textureBytes;
            const char* ext = b.size() >= 8 && b.compare(0, 8, "\x89PNG\r\n\x1a\n") == 0 ? "png"
                              : b.size() >= 3 && static_cast<unsigned char>(b[0]) == 0xff &&
                                      static_cast<unsigned char>(b[1]) == 0xd8
                                  ? "jpg"
                                  : nullptr;
            if (!ext)
                throw InputError(cat(texture, ": not a PNG or JPEG image (",
                                     m.textureMime.empty() ? std::string("no type given")
                                                           : m.textureMime,
                                     ")"));
            memory.emplace(b.data(), b.size());
            in = openImage(cat("embedded.", ext), texture, &*memory);
        } else {
            std::error_code ec;
            if (!std::filesystem::is_regular_file(m.textureFile, ec))
                throw InputError(cat(texture, ": ", m.textureFile.string(), ": no such file"));
            in = openImage(m.textureFile, cat(texture, " (", m.textureFile.string(), ")"));
        }
        // glTF's base colour textures are sRGB (alpha linear), whatever the file says.
        image = decodeImage(*in, 0, 0, FieldDesc::ColorSpace::Srgb, texture);
    }
    // RGBA times the factor: a grey image fills red, green and blue; no alpha reads 1.
    const std::size_t pixels = std::size_t(image.width) * std::size_t(image.height);
    const std::size_t n = std::size_t(desc.components);
    std::vector<float> texels(pixels * n);
    const int colour = image.alphaChannel >= 0 ? image.channels - 1 : image.channels;
    for (std::size_t i = 0; i < pixels; ++i) {
        const float* t = image.texels.data() + i * std::size_t(image.channels);
        glm::vec4 rgba(1.0f);
        for (int c = 0; c < 3; ++c)
            rgba[c] = colour <= 0 ? 1.0f : t[std::min(c, colour - 1)];
        if (image.alphaChannel >= 0)
            rgba.a = t[image.alphaChannel];
        rgba *= m.baseColorFactor;
        for (std::size_t c = 0; c < n; ++c)
            texels[i * n + c] = std::clamp(rgba[int(std::size_t(desc.channel) + c)], 0.0f, 1.0f);
    }
    return std::make_unique<ImageField>(image.width, image.height, desc.components,
                                        std::move(texels), m.repeat,
                                        LinearMap(keepComponents(desc.lo, desc.components),
                                                  keepComponents(desc.hi, desc.components)));
}

std::unique_ptr<Field> makeVertexField(const FieldDesc& desc, const Mesh& mesh,
                                       const std::string& context) {
    if (desc.attributes.size() != static_cast<std::size_t>(desc.components) &&
        desc.attributes.size() != 1)
        throw InputError(cat(context, ": vertex field names ", desc.attributes.size(),
                             " attributes for ", desc.components, " components"));
    std::vector<const std::vector<float>*> columns;
    for (int c = 0; c < desc.components; ++c) {
        const std::string& name = desc.attributes[desc.attributes.size() == 1 ? 0 : c];
        const auto it = mesh.attributes.find(name);
        if (it == mesh.attributes.end()) {
            std::string available;
            for (const auto& [key, values] : mesh.attributes)
                available += (available.empty() ? "" : ", ") + key;
            throw InputError(
                cat(context, ": vertex attribute \"", name, "\" is not on mesh ", mesh.name,
                    " (it has: ", available.empty() ? std::string("none") : available, ")"));
        }
        if (it->second.size() != mesh.positions.size())
            throw InputError(cat(context, ": vertex attribute \"", name, "\" of mesh ", mesh.name,
                                 " has ", it->second.size(), " values for ", mesh.positions.size(),
                                 " vertices"));
        for (float v : it->second)
            if (!std::isfinite(v))
                throw InputError(cat(context, ": vertex attribute \"", name, "\" of mesh ",
                                     mesh.name, " holds a non-finite value"));
        columns.push_back(&it->second);
    }
    // Loaders guarantee this (finalizeMesh); a mesh built by hand may not, and eval indexes with
    // it.
    for (const glm::uvec3& t : mesh.triangles)
        if (t.x >= mesh.positions.size() || t.y >= mesh.positions.size() ||
            t.z >= mesh.positions.size())
            throw InputError(
                cat(context, ": mesh ", mesh.name, " has a vertex index out of range"));
    return std::make_unique<VertexField>(mesh, std::move(columns));
}

bool finite(glm::vec3 v) {
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

} // namespace

float valueNoise(glm::vec3 p, int octaves, std::uint32_t seed) {
    // The shared header's noise, so CPU and GPU fields agree bit for bit.
    return spot::shared::f32::spotValueNoise(p, octaves, seed);
}

namespace {
std::unique_ptr<Field> makeBaseField(const FieldDesc& desc, const Mesh& mesh,
                                     const std::filesystem::path& baseDir,
                                     const std::string& context);
} // namespace

std::unique_ptr<Field> makeField(const FieldDesc& desc, const Mesh& mesh,
                                 const std::filesystem::path& baseDir, const std::string& context) {
    std::unique_ptr<Field> base = makeBaseField(desc, mesh, baseDir, context);
    if (!desc.paint)
        return base;
    std::shared_ptr<const PaintLayer> layer = desc.paint->layer;
    if (!layer) {
        if (desc.paint->file.empty())
            throw InputError(cat(context, ": paint has no file"));
        const std::filesystem::path file = std::filesystem::path(desc.paint->file).is_absolute()
                                               ? std::filesystem::path(desc.paint->file)
                                               : baseDir / desc.paint->file;
        try {
            layer = std::make_shared<const PaintLayer>(
                readPaintLayer(file, desc.paint->grid, desc.components, desc.paint->mode));
        } catch (const InputError& e) {
            throw InputError(cat(context, ".paint: ", e.what()));
        }
    }
    if (layer->components() != desc.components)
        throw InputError(cat(context, ".paint: grid \"", layer->value().name(), "\" has ",
                             layer->components(), " components, the slot needs ", desc.components));
    if (layer->mode() != desc.paint->mode)
        throw InputError(cat(context, ".paint: the layer's mode is not the slot's"));
    return std::make_unique<LayeredField>(std::move(base), std::move(layer), mesh);
}

namespace {

std::unique_ptr<Field> makeBaseField(const FieldDesc& desc, const Mesh& mesh,
                                     const std::filesystem::path& baseDir,
                                     const std::string& context) {
    if (desc.components != 1 && desc.components != 3)
        throw InputError(cat(context, ": a field has 1 or 3 components, not ", desc.components));
    const int n = desc.components;
    switch (desc.kind) {
    case FieldDesc::Kind::Constant:
        if (!finite(desc.value))
            throw InputError(cat(context, ": constant value is not finite"));
        return std::make_unique<ConstantField>(keepComponents(desc.value, n));
    case FieldDesc::Kind::Gradient:
        if (!finite(desc.from) || !finite(desc.to) || !finite(desc.lo) || !finite(desc.hi))
            throw InputError(cat(context, ": gradient has a non-finite parameter"));
        if (!(glm::length(desc.to - desc.from) >= kMinGradientLength))
            throw InputError(cat(context, ": gradient \"from\" and \"to\" are the same point"));
        return std::make_unique<GradientField>(
            desc.from, desc.to, LinearMap(keepComponents(desc.lo, n), keepComponents(desc.hi, n)));
    case FieldDesc::Kind::Noise:
        if (!(std::isfinite(desc.frequency) && desc.frequency > 0.0f) || !finite(desc.lo) ||
            !finite(desc.hi))
            throw InputError(
                cat(context, ": noise needs a finite frequency > 0 and a finite range"));
        if (desc.octaves < 1 || desc.octaves > 8)
            throw InputError(
                cat(context, ": noise octaves = ", desc.octaves, " is out of range [1, 8]"));
        return std::make_unique<NoiseField>(
            desc.frequency, desc.octaves, desc.seed,
            LinearMap(keepComponents(desc.lo, n), keepComponents(desc.hi, n)));
    case FieldDesc::Kind::Vertex:
        return makeVertexField(desc, mesh, context);
    case FieldDesc::Kind::Image:
        if (!finite(desc.lo) || !finite(desc.hi))
            throw InputError(cat(context, ": image range is not finite"));
        return makeImageField(desc, mesh, baseDir, context);
    case FieldDesc::Kind::Material:
        if (!finite(desc.lo) || !finite(desc.hi))
            throw InputError(cat(context, ": material range is not finite"));
        if (desc.channel < 0 || desc.channel + desc.components > 4)
            throw InputError(cat(context, ": material channels ", desc.channel, "..",
                                 desc.channel + desc.components - 1, " are not within RGBA"));
        return makeMaterialField(desc, mesh, context);
    case FieldDesc::Kind::Painted:
        return makePaintedField(desc, baseDir, context);
    case FieldDesc::Kind::Tangent:
        if (desc.components != 3)
            throw InputError(cat(context, ": the surface tangent has 3 components"));
        return std::make_unique<TangentField>();
    }
    throw InputError(cat(context, ": unknown field kind ", static_cast<int>(desc.kind)));
}

} // namespace

} // namespace spot::noise
