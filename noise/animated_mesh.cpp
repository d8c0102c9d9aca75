#include "animated_mesh.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fnmatch.h>
#include <fstream>
#include <functional>
#include <limits>
#include <map>

#define TINYGLTF_IMPLEMENTATION
#define TINYGLTF_NO_STB_IMAGE
#define TINYGLTF_NO_STB_IMAGE_WRITE
#define TINYGLTF_NO_EXTERNAL_IMAGE
#include <tiny_gltf.h>

#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/type_ptr.hpp>
#include <nlohmann/json.hpp>

#include "noise/error.h"

namespace spot::noise {

namespace {

using Interpolation = AnimatedMesh::Interpolation;

/// An accessor's elements as floats, `components` each (integer components converted as glTF
/// says: normalized ones to [0, 1] or [-1, 1], others as their value). InputError for anything
/// out of the buffers, sparse, or of another shape.
std::vector<float> readAccessor(const tinygltf::Model& model, int index, int components,
                                const std::string& what) {
    if (index < 0 || index >= int(model.accessors.size()))
        throw InputError(cat(what, ": accessor ", index, " does not exist"));
    const tinygltf::Accessor& a = model.accessors[std::size_t(index)];
    if (a.sparse.isSparse)
        throw InputError(cat(what, ": sparse accessors are not supported (export without them)"));
    const int n = tinygltf::GetNumComponentsInType(std::uint32_t(a.type));
    if (n != components)
        throw InputError(
            cat(what, ": accessor ", index, " has ", n, " components, ", components, " expected"));
    std::vector<float> out(a.count * std::size_t(components), 0.0f);
    if (a.bufferView < 0)
        return out; // all zeros, as glTF says
    if (a.bufferView >= int(model.bufferViews.size()))
        throw InputError(cat(what, ": buffer view ", a.bufferView, " does not exist"));
    const tinygltf::BufferView& view = model.bufferViews[std::size_t(a.bufferView)];
    if (view.buffer < 0 || view.buffer >= int(model.buffers.size()))
        throw InputError(cat(what, ": buffer ", view.buffer, " does not exist"));
    const std::vector<unsigned char>& data = model.buffers[std::size_t(view.buffer)].data;
    if (view.byteOffset + view.byteLength > data.size())
        throw InputError(cat(what, ": buffer view ", a.bufferView, " (bytes ", view.byteOffset,
                             " to ", view.byteOffset + view.byteLength, ") reaches past buffer ",
                             view.buffer, " (", data.size(), " bytes: missing or short)"));
    const int size = tinygltf::GetComponentSizeInBytes(std::uint32_t(a.componentType));
    const int stride = a.ByteStride(view);
    if (size <= 0 || stride <= 0)
        throw InputError(cat(what, ": accessor ", index, " has an unknown component type"));
    const std::uint64_t begin = std::uint64_t(view.byteOffset) + a.byteOffset;
    const std::uint64_t end = a.count == 0 ? begin
                                           : begin + std::uint64_t(stride) * (a.count - 1) +
                                                 std::uint64_t(size) * components;
    if (end > view.byteOffset + view.byteLength)
        throw InputError(cat(what, ": accessor ", index, " (", a.count, " elements) reaches past ",
                             "buffer view ", a.bufferView));
    for (std::size_t i = 0; i < a.count; ++i)
        for (int c = 0; c < components; ++c) {
            const unsigned char* p =
                data.data() + begin + i * std::size_t(stride) + std::size_t(c * size);
            float v = 0.0f;
            switch (a.componentType) {
            case TINYGLTF_COMPONENT_TYPE_FLOAT:
                std::memcpy(&v, p, 4);
                break;
            case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
                v = a.normalized ? float(*p) / 255.0f : float(*p);
                break;
            case TINYGLTF_COMPONENT_TYPE_BYTE:
                v = a.normalized ? std::max(float(std::int8_t(*p)) / 127.0f, -1.0f)
                                 : float(std::int8_t(*p));
                break;
            case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
                std::uint16_t u;
                std::memcpy(&u, p, 2);
                v = a.normalized ? float(u) / 65535.0f : float(u);
                break;
            }
            case TINYGLTF_COMPONENT_TYPE_SHORT: {
                std::int16_t s;
                std::memcpy(&s, p, 2);
                v = a.normalized ? std::max(float(s) / 32767.0f, -1.0f) : float(s);
                break;
            }
            case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: {
                std::uint32_t u;
                std::memcpy(&u, p, 4);
                v = float(u);
                break;
            }
            default:
                throw InputError(
                    cat(what, ": accessor ", index, " has component type ", a.componentType));
            }
            if (!std::isfinite(v))
                throw InputError(cat(what, ": accessor ", index, " holds a non-finite value"));
            out[i * std::size_t(components) + std::size_t(c)] = v;
        }
    return out;
}

/// Indices are read exactly (floats hold integers up to 2^24 exactly; larger are refused).
std::vector<std::uint32_t> readIndices(const tinygltf::Model& model, int index,
                                       std::size_t vertices, const std::string& what) {
    const std::vector<float> f = readAccessor(model, index, 1, what);
    std::vector<std::uint32_t> out(f.size());
    for (std::size_t i = 0; i < f.size(); ++i) {
        if (!(f[i] >= 0.0f) || f[i] >= float(vertices) || f[i] > 16777216.0f)
            throw InputError(
                cat(what, ": index ", i, " is ", f[i], ", outside [0, ", vertices, ")"));
        out[i] = std::uint32_t(f[i]);
    }
    return out;
}

template <int N> std::vector<glm::vec<N, float>> asVectors(const std::vector<float>& f) {
    std::vector<glm::vec<N, float>> out(f.size() / N);
    for (std::size_t i = 0; i < out.size(); ++i)
        for (int c = 0; c < N; ++c)
            out[i][c] = f[i * N + std::size_t(c)];
    return out;
}

glm::mat4 localMatrix(const AnimatedMesh::Node& n) {
    if (n.hasMatrix)
        return n.matrix;
    return glm::translate(glm::mat4(1.0f), n.translation) * glm::mat4_cast(n.rotation) *
           glm::scale(glm::mat4(1.0f), n.scale);
}

} // namespace

std::vector<float> AnimatedMesh::sample(const std::vector<float>& times,
                                        const std::vector<float>& values, int width,
                                        Interpolation interpolation, bool rotation, double t) {
    const std::size_t keys = times.size();
    const std::size_t stride =
        std::size_t(width) * (interpolation == Interpolation::CubicSpline ? 3 : 1);
    std::vector<float> out(std::size_t(width), 0.0f);
    if (keys == 0)
        return out;
    const std::size_t valueAt =
        interpolation == Interpolation::CubicSpline ? std::size_t(width) : 0;
    const auto value = [&](std::size_t k) { return values.data() + k * stride + valueAt; };
    std::size_t k = 0;
    if (t <= times.front() || keys == 1) {
        std::copy(value(0), value(0) + width, out.begin());
        return out;
    }
    if (t >= times.back()) {
        std::copy(value(keys - 1), value(keys - 1) + width, out.begin());
        return out;
    }
    k = std::size_t(std::upper_bound(times.begin(), times.end(), float(t)) - times.begin()) - 1;
    const double t0 = times[k], t1 = times[k + 1], dt = t1 - t0;
    const double u = dt > 0.0 ? (t - t0) / dt : 0.0;
    const float* a = value(k);
    const float* b = value(k + 1);
    if (interpolation == Interpolation::Step) {
        std::copy(a, a + width, out.begin());
    } else if (interpolation == Interpolation::Linear && rotation) {
        const glm::quat qa(a[3], a[0], a[1], a[2]), qb(b[3], b[0], b[1], b[2]);
        const glm::quat q = glm::normalize(glm::slerp(qa, qb, float(u))); // the short way round
        out = {q.x, q.y, q.z, q.w};
    } else if (interpolation == Interpolation::Linear) {
        for (int c = 0; c < width; ++c)
            out[std::size_t(c)] = float(a[c] + (b[c] - a[c]) * u);
    } else { // Hermite with the tangents scaled by the interval
        const float* outTangent = values.data() + k * stride + 2 * std::size_t(width);
        const float* inTangent = values.data() + (k + 1) * stride;
        const double u2 = u * u, u3 = u2 * u;
        for (int c = 0; c < width; ++c)
            out[std::size_t(c)] =
                float((2 * u3 - 3 * u2 + 1) * a[c] + (u3 - 2 * u2 + u) * dt * outTangent[c] +
                      (-2 * u3 + 3 * u2) * b[c] + (u3 - u2) * dt * inTangent[c]);
        if (rotation) {
            const glm::quat q = glm::normalize(glm::quat(out[3], out[0], out[1], out[2]));
            out = {q.x, q.y, q.z, q.w};
        }
    }
    return out;
}

namespace {

/// The glTF version a file says it is ("1.0", "2.0"), or empty when it says none readable: a
/// binary's header version, or a text file's asset.version.
std::string gltfVersionOf(const std::filesystem::path& file, std::uint64_t bytes) {
    std::ifstream in(file, std::ios::binary);
    char head[12] = {};
    if (!in.read(head, sizeof(head)))
        return {};
    if (std::memcmp(head, "glTF", 4) == 0) {
        std::uint32_t version = 0;
        std::memcpy(&version, head + 4, 4);
        return version == 1 ? "1.0" : version == 2 ? "2.0" : std::to_string(version);
    }
    if (bytes > (64u << 20))
        return {}; // a text file this large is not read twice for its version
    in.seekg(0);
    try {
        const nlohmann::json j = nlohmann::json::parse(in);
        const auto asset = j.find("asset");
        if (asset != j.end() && asset->is_object()) {
            const auto v = asset->find("version");
            if (v != asset->end() && v->is_string())
                return v->get<std::string>();
        }
        // glTF 1.0 files often carry no asset at all; their meshes are an object, not an array.
        const auto meshes = j.find("meshes");
        if (meshes != j.end() && meshes->is_object())
            return "1.0";
    } catch (const std::exception&) {
    }
    return {};
}

/// The file read by tinygltf, after the size check. Images are kept as their encoded bytes (the
/// `material` field decodes a base-colour texture with OpenImageIO when a preset asks for one);
/// external images are left as their uri.
tinygltf::Model readModel(const std::filesystem::path& file, const MeshLimits& limits) {
    const std::string name = file.string();
    std::error_code ec;
    const std::uintmax_t bytes = std::filesystem::file_size(file, ec);
    if (ec)
        throw InputError(cat(name, ": cannot read (", ec.message(), ")"));
    if (bytes > limits.maxFileBytes)
        throw InputError(
            cat(name, ": ", bytes, " bytes, more than the ", limits.maxFileBytes, " accepted"));
    const auto notVersion2 = [&](const std::string& version) {
        return cat(name, ": a glTF ", version,
                   " file; spotshell reads glTF 2.0 (export it again as glTF 2.0, as Blender 2.80 "
                   "and later do)");
    };
    tinygltf::TinyGLTF loader;
    loader.SetImageLoader(
        [](tinygltf::Image* image, const int, std::string*, std::string*, int, int,
           const unsigned char* data, int size, void*) {
            if (data && size > 0)
                image->image.assign(data, data + size); // encoded: decoded when a field reads it
            return true;
        },
        nullptr);
    tinygltf::Model model;
    std::string err, warn;
    const bool binary = file.extension() == ".glb" || file.extension() == ".GLB";
    const bool ok = binary ? loader.LoadBinaryFromFile(&model, &err, &warn, name)
                           : loader.LoadASCIIFromFile(&model, &err, &warn, name);
    if (!ok) {
        const std::string version = gltfVersionOf(file, bytes);
        if (!version.empty() && version.rfind("2.", 0) != 0)
            throw InputError(notVersion2(version));
        std::string first = err.substr(0, err.find('\n'));
        throw InputError(cat(name, ": not a glTF 2.0 file tinygltf reads (",
                             first.empty() ? "no reason given" : first, ")"));
    }
    if (!model.asset.version.empty() && model.asset.version.rfind("2.", 0) != 0)
        throw InputError(notVersion2(model.asset.version));
    return model;
}

/// Whether `name` (or index `index`) matches a "grow" pattern.
bool matches(const PartPattern& p, const std::string& name, int index) {
    if (p.glob.empty())
        return p.index == index;
    return fnmatch(p.glob.c_str(), name.c_str(), 0) == 0;
}

} // namespace

/// Builds an AnimatedMesh from a glTF model, part by part (friend of AnimatedMesh).
struct GltfReader {
    const tinygltf::Model& model;
    const std::string& name;
    const MeshLimits& limits;
    AnimatedMesh& out;
    std::vector<glm::vec2> uvs; ///< every primitive's, (0, 0) where one has none
    bool anyUv = false, allUv = true;
    std::vector<bool> partUv; ///< per part: it has TEXCOORD_0
    std::size_t skipped = 0; ///< point and line primitives

    /// Nodes with their parents (no cycles).
    void nodes() {
        out.m_nodes.resize(model.nodes.size());
        for (std::size_t i = 0; i < model.nodes.size(); ++i) {
            const tinygltf::Node& n = model.nodes[i];
            AnimatedMesh::Node& node = out.m_nodes[i];
            if (n.matrix.size() == 16) {
                node.hasMatrix = true;
                for (int c = 0; c < 16; ++c)
                    glm::value_ptr(node.matrix)[c] = float(n.matrix[std::size_t(c)]);
            }
            if (n.translation.size() == 3)
                node.translation = glm::vec3(n.translation[0], n.translation[1], n.translation[2]);
            if (n.rotation.size() == 4)
                node.rotation = glm::quat(float(n.rotation[3]), float(n.rotation[0]),
                                          float(n.rotation[1]), float(n.rotation[2]));
            if (n.scale.size() == 3)
                node.scale = glm::vec3(n.scale[0], n.scale[1], n.scale[2]);
            for (const int c : n.children) {
                if (c < 0 || c >= int(model.nodes.size()) ||
                    out.m_nodes[std::size_t(c)].parent >= 0 || c == int(i))
                    throw InputError(cat(name, ": node ", i, " has a bad child ", c));
                out.m_nodes[std::size_t(c)].parent = int(i);
            }
        }
        for (std::size_t i = 0; i < out.m_nodes.size(); ++i) { // no cycles
            std::size_t steps = 0;
            for (int p = out.m_nodes[i].parent; p >= 0; p = out.m_nodes[std::size_t(p)].parent)
                if (++steps > out.m_nodes.size())
                    throw InputError(cat(name, ": its node hierarchy has a cycle"));
        }
    }

    /// Skins and each mesh's default morph weights.
    void skins() {
        for (const tinygltf::Skin& s : model.skins) {
            AnimatedMesh::Skin skin;
            for (const int j : s.joints) {
                if (j < 0 || j >= int(model.nodes.size()))
                    throw InputError(
                        cat(name, ": a skin names joint node ", j, " that does not exist"));
                skin.joints.push_back(j);
            }
            skin.inverseBind.assign(skin.joints.size(), glm::mat4(1.0f));
            if (s.inverseBindMatrices >= 0) {
                const auto m =
                    readAccessor(model, s.inverseBindMatrices, 16, name + " inverse bind matrices");
                if (m.size() != skin.joints.size() * 16)
                    throw InputError(cat(name, ": a skin has ", m.size() / 16,
                                         " inverse bind matrices for ", skin.joints.size(),
                                         " joints"));
                for (std::size_t j = 0; j < skin.joints.size(); ++j)
                    std::copy(m.begin() + std::ptrdiff_t(16 * j),
                              m.begin() + std::ptrdiff_t(16 * j + 16),
                              glm::value_ptr(skin.inverseBind[j]));
            }
            out.m_jointCount += skin.joints.size();
            out.m_skins.push_back(std::move(skin));
        }
        for (const tinygltf::Mesh& m : model.meshes) {
            std::vector<float> w(m.weights.begin(), m.weights.end());
            out.m_meshWeights.push_back(std::move(w));
        }
    }

    /// The scene's nodes in depth-first order.
    std::vector<int> sceneOrder() const {
        std::vector<int> order;
        const int sceneIndex = model.defaultScene >= 0 ? model.defaultScene : 0;
        std::function<void(int)> visit = [&](int n) {
            order.push_back(n);
            for (const int c : model.nodes[std::size_t(n)].children)
                visit(c);
        };
        if (sceneIndex < int(model.scenes.size())) {
            for (const int n : model.scenes[std::size_t(sceneIndex)].nodes) {
                if (n < 0 || n >= int(model.nodes.size()) ||
                    out.m_nodes[std::size_t(n)].parent >= 0)
                    throw InputError(cat(name, ": its scene names node ", n, ", not a root node"));
                visit(n);
            }
        } else {
            for (std::size_t n = 0; n < model.nodes.size(); ++n)
                if (out.m_nodes[n].parent < 0)
                    visit(int(n));
        }
        return order;
    }

    /// Primitive p of node n's mesh, appended to the rest mesh as a piece.
    void primitive(int n, std::size_t p) {
        const tinygltf::Node& node = model.nodes[std::size_t(n)];
        const tinygltf::Mesh& m = model.meshes[std::size_t(node.mesh)];
        const tinygltf::Primitive& prim = m.primitives[p];
        const std::string what = cat(name, " mesh '", m.name, "' primitive ", p);
        // Points and lines carry no surface: skipped (a file of nothing else is refused
        // below). Strips and fans are triangles, unrolled as glTF says.
        const int mode = prim.mode == -1 ? TINYGLTF_MODE_TRIANGLES : prim.mode;
        if (mode == TINYGLTF_MODE_POINTS || mode == TINYGLTF_MODE_LINE ||
            mode == TINYGLTF_MODE_LINE_LOOP || mode == TINYGLTF_MODE_LINE_STRIP) {
            ++skipped;
            return;
        }
        if (mode != TINYGLTF_MODE_TRIANGLES && mode != TINYGLTF_MODE_TRIANGLE_STRIP &&
            mode != TINYGLTF_MODE_TRIANGLE_FAN)
            throw InputError(cat(what, ": mode ", prim.mode, " is not a glTF primitive mode"));
        const auto attr = [&](const char* key) {
            const auto it = prim.attributes.find(key);
            return it == prim.attributes.end() ? -1 : it->second;
        };
        if (attr("POSITION") < 0)
            throw InputError(cat(what, ": has no POSITION"));
        Mesh& mesh = out.m_rest;
        MeshPart part;
        part.mesh = m.name;
        part.meshIndex = node.mesh;
        part.node = node.name;
        part.nodeIndex = n;
        part.primitive = int(p);
        part.material = prim.material >= 0 && prim.material < int(model.materials.size())
                            ? prim.material
                            : -1;
        AnimatedMesh::Piece piece;
        piece.node = n;
        piece.skin = node.skin;
        piece.mesh = node.mesh;
        piece.first = mesh.positions.size();
        piece.base = asVectors<3>(readAccessor(model, attr("POSITION"), 3, what + " POSITION"));
        piece.count = piece.base.size();
        if (mesh.positions.size() + piece.count > limits.maxVertices)
            throw InputError(cat(name, ": more than ", limits.maxVertices, " vertices"));
        uv(attr("TEXCOORD_0"), piece.count, what);
        partUv.push_back(attr("TEXCOORD_0") >= 0);
        joints(prim, node.skin, piece, what);
        targets(prim, piece, what);
        const std::size_t before = mesh.triangles.size();
        triangles(prim, mode, piece, what);
        mesh.trianglePart.resize(mesh.triangles.size(), std::uint32_t(mesh.parts.size()));
        part.triangles = mesh.triangles.size() - before;
        mesh.parts.push_back(std::move(part));
        mesh.positions.resize(mesh.positions.size() + piece.count);
        out.m_pieces.push_back(std::move(piece));
    }

    /// The materials' base colours (factor and texture), as the `material` field reads them.
    void materials() {
        const std::filesystem::path dir = std::filesystem::path(name).parent_path();
        for (std::size_t i = 0; i < model.materials.size(); ++i) {
            const tinygltf::Material& m = model.materials[i];
            MeshMaterial mat;
            mat.name = m.name;
            const std::vector<double>& f = m.pbrMetallicRoughness.baseColorFactor;
            if (f.size() == 4)
                mat.baseColorFactor = glm::vec4(float(f[0]), float(f[1]), float(f[2]), float(f[3]));
            for (int c = 0; c < 4; ++c)
                if (!std::isfinite(mat.baseColorFactor[c]) || mat.baseColorFactor[c] < 0.0f)
                    throw InputError(cat(name, ": material ", i, " '", m.name,
                                         "' has a negative or non-finite base colour factor"));
            const tinygltf::TextureInfo& info = m.pbrMetallicRoughness.baseColorTexture;
            if (info.index >= 0) {
                if (info.index >= int(model.textures.size()))
                    throw InputError(cat(name, ": material ", i, " '", m.name, "' names texture ",
                                         info.index, " that does not exist"));
                const tinygltf::Texture& tex = model.textures[std::size_t(info.index)];
                if (tex.source < 0 || tex.source >= int(model.images.size()))
                    throw InputError(cat(name, ": texture ", info.index, " names image ",
                                         tex.source, " that does not exist"));
                const tinygltf::Image& image = model.images[std::size_t(tex.source)];
                mat.texture = image.name.empty() ? (image.uri.empty() || image.uri.rfind("data:", 0) == 0
                                                        ? cat("image ", tex.source)
                                                        : image.uri)
                                                 : image.name;
                mat.texCoord = info.texCoord;
                if (!image.image.empty()) {
                    mat.textureBytes = std::make_shared<const std::string>(image.image.begin(),
                                                                           image.image.end());
                    mat.textureMime = image.mimeType;
                } else if (!image.uri.empty()) {
                    mat.textureFile = dir / uriDecode(image.uri);
                } else {
                    throw InputError(cat(name, ": image ", tex.source, " has no data"));
                }
                if (tex.sampler >= 0 && tex.sampler < int(model.samplers.size()))
                    mat.repeat = model.samplers[std::size_t(tex.sampler)].wrapS !=
                                 TINYGLTF_TEXTURE_WRAP_CLAMP_TO_EDGE;
            }
            out.m_rest.materials.push_back(std::move(mat));
        }
    }

    /// %XX escapes of a uri decoded (glTF's external image uris).
    static std::string uriDecode(const std::string& uri) {
        std::string out;
        for (std::size_t i = 0; i < uri.size(); ++i) {
            if (uri[i] == '%' && i + 2 < uri.size() && std::isxdigit((unsigned char)uri[i + 1]) &&
                std::isxdigit((unsigned char)uri[i + 2])) {
                out.push_back(char(std::stoi(uri.substr(i + 1, 2), nullptr, 16)));
                i += 2;
            } else {
                out.push_back(uri[i]);
            }
        }
        return out;
    }

    /// Which parts grow fur (the scene's "grow"): every pattern must match a mesh or node of the
    /// file, and some triangle must remain.
    void select(const GrowSelection& grow) {
        if (!grow.chooses())
            return;
        const auto list = [](const auto& names) {
            std::string s;
            for (std::size_t i = 0; i < names.size(); ++i)
                s += cat(i ? ", " : "", i, " '", names[i].name, "'");
            return s.empty() ? std::string("none") : s;
        };
        const auto check = [&](const std::vector<PartPattern>& patterns, const auto& things,
                               const char* key, const char* kind) {
            for (const PartPattern& p : patterns) {
                bool any = false;
                for (std::size_t i = 0; i < things.size(); ++i)
                    any = any || matches(p, things[i].name, int(i));
                if (!any)
                    throw InputError(cat(name, ": grow.", key, " names '", p.text(),
                                         "', which is none of its ", kind, " (", list(things),
                                         ")"));
            }
        };
        check(grow.meshes, model.meshes, "meshes", "meshes");
        check(grow.excludeMeshes, model.meshes, "exclude_meshes", "meshes");
        check(grow.nodes, model.nodes, "nodes", "nodes");
        check(grow.excludeNodes, model.nodes, "exclude_nodes", "nodes");
        // The node or an ancestor matches one of `patterns`.
        const auto underNode = [&](int node, const std::vector<PartPattern>& patterns) {
            for (int n = node; n >= 0; n = out.m_nodes[std::size_t(n)].parent)
                for (const PartPattern& p : patterns)
                    if (matches(p, model.nodes[std::size_t(n)].name, n))
                        return true;
            return false;
        };
        const auto meshIs = [&](int mesh, const std::vector<PartPattern>& patterns) {
            for (const PartPattern& p : patterns)
                if (matches(p, model.meshes[std::size_t(mesh)].name, mesh))
                    return true;
            return false;
        };
        const bool include = !grow.meshes.empty() || !grow.nodes.empty();
        std::size_t growing = 0;
        for (MeshPart& part : out.m_rest.parts) {
            part.grows = !include || meshIs(part.meshIndex, grow.meshes) ||
                         underNode(part.nodeIndex, grow.nodes);
            if (meshIs(part.meshIndex, grow.excludeMeshes) ||
                underNode(part.nodeIndex, grow.excludeNodes))
                part.grows = false;
            growing += part.grows ? part.triangles : 0;
        }
        if (growing == 0)
            throw InputError(cat(name, ": the scene's \"grow\" leaves no triangle to grow fur on"));
    }

    /// Whether split copies a and b (at one position) move together: the same node and skin,
    /// the same joints with the same weights (within 1e-3), and the same morph deltas (within
    /// `eps`, world units).
    bool moveTogether(std::uint32_t a, std::uint32_t b, double eps) const {
        const auto pieceOf = [&](std::uint32_t v) -> const AnimatedMesh::Piece& {
            std::size_t lo = 0, hi = out.m_pieces.size();
            while (hi - lo > 1) {
                const std::size_t mid = (lo + hi) / 2;
                (out.m_pieces[mid].first <= v ? lo : hi) = mid;
            }
            return out.m_pieces[lo];
        };
        const AnimatedMesh::Piece& pa = pieceOf(a);
        const AnimatedMesh::Piece& pb = pieceOf(b);
        const std::size_t ia = a - pa.first, ib = b - pb.first;
        if (pa.skin != pb.skin || (pa.skin < 0 && pa.node != pb.node))
            return false;
        if (pa.skin >= 0) {
            std::map<std::uint32_t, double> wa, wb;
            for (int set = 0; set < 2; ++set)
                for (int c = 0; c < 4; ++c) {
                    if (!pa.joints[set].empty() && pa.weights[set][ia][c] > 0.0f)
                        wa[pa.joints[set][ia][c]] += pa.weights[set][ia][c];
                    if (!pb.joints[set].empty() && pb.weights[set][ib][c] > 0.0f)
                        wb[pb.joints[set][ib][c]] += pb.weights[set][ib][c];
                }
            for (const auto& [j, w] : wa)
                if (std::abs(w - (wb.count(j) ? wb[j] : 0.0)) > 1e-3)
                    return false;
            for (const auto& [j, w] : wb)
                if (std::abs(w - (wa.count(j) ? wa[j] : 0.0)) > 1e-3)
                    return false;
        }
        const std::size_t targets = std::max(pa.targets.size(), pb.targets.size());
        for (std::size_t t = 0; t < targets; ++t) {
            const glm::vec3 da = t < pa.targets.size() ? pa.targets[t][ia] : glm::vec3(0.0f);
            const glm::vec3 db = t < pb.targets.size() ? pb.targets[t][ib] : glm::vec3(0.0f);
            if (glm::length(glm::dvec3(da) - glm::dvec3(db)) > eps)
                return false;
        }
        // Morph weights belong to the mesh: different meshes' targets play apart.
        if (targets > 0 && pa.mesh != pb.mesh)
            return false;
        return true;
    }

    /// TEXCOORD_0 (accessor `index`, -1: none) of a primitive of `count` vertices.
    void uv(int index, std::size_t count, const std::string& what) {
        if (index >= 0) {
            auto uv = asVectors<2>(readAccessor(model, index, 2, what + " TEXCOORD_0"));
            if (uv.size() != count)
                throw InputError(
                    cat(what, ": TEXCOORD_0 has ", uv.size(), " values for ", count, " vertices"));
            for (glm::vec2& t : uv)
                t.y =
                    1.0f - t.y; // glTF's uv (0, 0) is the image's top-left; spotshell's bottom-left
            uvs.insert(uvs.end(), uv.begin(), uv.end());
            anyUv = true;
        } else {
            allUv = false;
            uvs.resize(uvs.size() + count, glm::vec2(0.0f));
        }
    }

    /// JOINTS_0/1 and WEIGHTS_0/1, checked, the weights normalised together.
    void joints(const tinygltf::Primitive& prim, int skin, AnimatedMesh::Piece& piece,
                const std::string& what) {
        const auto attr = [&](const char* key) {
            const auto it = prim.attributes.find(key);
            return it == prim.attributes.end() ? -1 : it->second;
        };
        for (int set = 0; set < 2; ++set) {
            const int j = attr(set == 0 ? "JOINTS_0" : "JOINTS_1");
            const int w = attr(set == 0 ? "WEIGHTS_0" : "WEIGHTS_1");
            if ((j < 0) != (w < 0))
                throw InputError(
                    cat(what, ": JOINTS_", set, " and WEIGHTS_", set, " come in pairs"));
            if (j < 0)
                continue;
            if (skin < 0)
                throw InputError(cat(what, ": has joints but its node has no skin"));
            const auto joints = asVectors<4>(readAccessor(model, j, 4, what + " JOINTS"));
            const auto weights = asVectors<4>(readAccessor(model, w, 4, what + " WEIGHTS"));
            if (joints.size() != piece.count || weights.size() != piece.count)
                throw InputError(cat(what, ": JOINTS/WEIGHTS do not have one value per vertex"));
            const std::size_t jointCount = out.m_skins[std::size_t(skin)].joints.size();
            piece.joints[set].resize(piece.count);
            for (std::size_t v = 0; v < piece.count; ++v)
                for (int c = 0; c < 4; ++c) {
                    if (!(joints[v][c] >= 0.0f) || joints[v][c] >= float(jointCount) ||
                        joints[v][c] != std::floor(joints[v][c]))
                        throw InputError(cat(what, ": vertex ", v, " names joint ", joints[v][c],
                                             " of a skin with ", jointCount));
                    if (weights[v][c] < 0.0f)
                        throw InputError(cat(what, ": vertex ", v, " has a negative weight ",
                                             weights[v][c], " (WEIGHTS_", set, ")"));
                    piece.joints[set][v][c] = std::uint32_t(joints[v][c]);
                }
            piece.weights[set] = weights;
        }
        if (skin >= 0 && piece.joints[0].empty())
            throw InputError(cat(what, ": its node has a skin but it has no JOINTS_0/WEIGHTS_0"));
        // The weights of both sets normalised together, as glTF asks (exporters round them);
        // a skinned vertex that no joint moves is an error, not a vertex left behind.
        if (skin >= 0)
            for (std::size_t v = 0; v < piece.count; ++v) {
                double sum = 0.0;
                for (int set = 0; set < 2; ++set)
                    if (!piece.weights[set].empty())
                        for (int c = 0; c < 4; ++c)
                            sum += double(piece.weights[set][v][c]);
                if (!(sum > 0.0))
                    throw InputError(
                        cat(what, ": vertex ", v, "'s joint weights sum to 0 (no joint moves it)"));
                for (int set = 0; set < 2; ++set)
                    if (!piece.weights[set].empty())
                        piece.weights[set][v] = glm::vec4(glm::dvec4(piece.weights[set][v]) / sum);
            }
    }

    /// The morph targets' POSITION deltas.
    void targets(const tinygltf::Primitive& prim, AnimatedMesh::Piece& piece,
                 const std::string& what) {
        for (std::size_t t = 0; t < prim.targets.size(); ++t) {
            const auto it = prim.targets[t].find("POSITION");
            std::vector<glm::vec3> delta(piece.count, glm::vec3(0.0f));
            if (it != prim.targets[t].end()) {
                delta = asVectors<3>(readAccessor(model, it->second, 3, cat(what, " target ", t)));
                if (delta.size() != piece.count)
                    throw InputError(cat(what, ": morph target ", t, " has ", delta.size(),
                                         " positions for ", piece.count, " vertices"));
            }
            piece.targets.push_back(std::move(delta));
        }
        out.m_morphTargets = std::max(out.m_morphTargets, piece.targets.size());
    }

    /// The triangles (strips and fans unrolled), offset to the piece's first vertex.
    void triangles(const tinygltf::Primitive& prim, int mode, const AnimatedMesh::Piece& piece,
                   const std::string& what) {
        Mesh& mesh = out.m_rest;
        std::vector<std::uint32_t> indices;
        if (prim.indices >= 0) {
            indices = readIndices(model, prim.indices, piece.count, what + " indices");
        } else {
            indices.resize(piece.count);
            for (std::size_t i = 0; i < piece.count; ++i)
                indices[i] = std::uint32_t(i);
        }
        if (mode == TINYGLTF_MODE_TRIANGLE_STRIP || mode == TINYGLTF_MODE_TRIANGLE_FAN) {
            std::vector<std::uint32_t> list;
            for (std::size_t i = 0; i + 2 < indices.size(); ++i) {
                if (mode == TINYGLTF_MODE_TRIANGLE_STRIP)
                    list.insert(list.end(),
                                {indices[i], indices[i + 1 + i % 2], indices[i + 2 - i % 2]});
                else
                    list.insert(list.end(), {indices[i + 1], indices[i + 2], indices[0]});
            }
            indices = std::move(list);
        }
        if (indices.size() % 3 != 0)
            throw InputError(cat(what, ": ", indices.size(), " indices, not a multiple of 3"));
        if (mesh.triangles.size() + indices.size() / 3 > limits.maxTriangles)
            throw InputError(cat(name, ": more than ", limits.maxTriangles, " triangles"));
        for (std::size_t i = 0; i < indices.size(); i += 3)
            mesh.triangles.emplace_back(std::uint32_t(piece.first) + indices[i],
                                        std::uint32_t(piece.first) + indices[i + 1],
                                        std::uint32_t(piece.first) + indices[i + 2]);
    }

    /// The clip named `clip` (empty: the first, or none).
    void clip(const std::string& clip) {
        for (const tinygltf::Animation& a : model.animations)
            out.m_clipNames.push_back(a.name);
        int chosen = -1;
        if (!clip.empty()) {
            for (std::size_t i = 0; i < model.animations.size(); ++i)
                if (model.animations[i].name == clip)
                    chosen = int(i);
            if (chosen < 0) {
                std::string names;
                for (const std::string& c : out.m_clipNames)
                    names +=
                        (names.empty() ? "" : ", ") + (c.empty() ? std::string("(unnamed)") : c);
                throw InputError(
                    cat(name, ": has no clip '", clip, "' (", names.empty() ? "none" : names, ")"));
            }
        } else if (!model.animations.empty()) {
            chosen = 0;
        }
        if (chosen < 0)
            return;
        const tinygltf::Animation& a = model.animations[std::size_t(chosen)];
        out.m_clipName = a.name;
        double lo = std::numeric_limits<double>::infinity(), hi = -lo;
        for (const tinygltf::AnimationChannel& c : a.channels) {
            AnimatedMesh::Channel ch;
            if (!channel(a, c, ch))
                continue;
            if (!ch.times.empty()) {
                lo = std::min(lo, double(ch.times.front()));
                hi = std::max(hi, double(ch.times.back()));
            }
            out.m_channels.push_back(std::move(ch));
        }
        if (hi >= lo) {
            out.m_start = lo;
            out.m_duration = hi - lo;
        }
    }

    /// Channel `c` of clip `a`, checked; false for one that moves nothing of the mesh.
    bool channel(const tinygltf::Animation& a, const tinygltf::AnimationChannel& c,
                 AnimatedMesh::Channel& ch) const {
        using Interpolation = AnimatedMesh::Interpolation;
        using Channel = AnimatedMesh::Channel;
        const std::string what = cat(name, " clip '", a.name, "'");
        if (c.sampler < 0 || c.sampler >= int(a.samplers.size()))
            throw InputError(cat(what, ": a channel names sampler ", c.sampler));
        if (c.target_node < 0 || c.target_node >= int(model.nodes.size()))
            return false; // a channel without a node (an extension's) moves nothing here
        const tinygltf::AnimationSampler& s = a.samplers[std::size_t(c.sampler)];
        ch.node = c.target_node;
        int width = 0;
        if (c.target_path == "translation") {
            ch.path = Channel::Path::Translation;
            width = 3;
        } else if (c.target_path == "rotation") {
            ch.path = Channel::Path::Rotation;
            width = 4;
        } else if (c.target_path == "scale") {
            ch.path = Channel::Path::Scale;
            width = 3;
        } else if (c.target_path == "weights") {
            ch.path = Channel::Path::Weights;
            const int m = model.nodes[std::size_t(c.target_node)].mesh;
            if (m < 0 || m >= int(model.meshes.size()) ||
                model.meshes[std::size_t(m)].primitives.empty())
                return false; // weights of a node without a mesh move nothing
            width = int(std::max<std::size_t>(
                1, model.meshes[std::size_t(m)].primitives.front().targets.size()));
        } else {
            return false; // "pointer" and others: nothing of the mesh
        }
        ch.interpolation = s.interpolation == "STEP"          ? Interpolation::Step
                           : s.interpolation == "CUBICSPLINE" ? Interpolation::CubicSpline
                                                              : Interpolation::Linear;
        ch.times = readAccessor(model, s.input, 1, what + " times");
        for (std::size_t k = 1; k < ch.times.size(); ++k)
            if (!(ch.times[k] >= ch.times[k - 1]))
                throw InputError(cat(what, ": its key times are not ascending"));
        const int outWidth = ch.path == Channel::Path::Weights ? 1 : width;
        ch.values = readAccessor(model, s.output, outWidth, what + " values");
        const std::size_t per =
            std::size_t(width) * (ch.interpolation == Interpolation::CubicSpline ? 3 : 1);
        if (ch.values.size() != ch.times.size() * per)
            throw InputError(cat(what, ": ", ch.values.size(), " values for ", ch.times.size(),
                                 " keys of ", per));
        // Rotation keys are unit quaternions (glTF asks it): one that is not is normalised
        // here, so a key's value (and the clip's ends) are rotations too (one within float
        // rounding of unit is kept as stored). A spline's tangents are left as they are.
        if (ch.path == Channel::Path::Rotation)
            for (std::size_t k = 0; k < ch.times.size(); ++k) {
                float* q = ch.values.data() + k * per +
                           (ch.interpolation == Interpolation::CubicSpline ? 4 : 0);
                const float length =
                    std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
                if (!(length > 1e-6f))
                    throw InputError(cat(what, ": rotation key ", k, " is not a rotation (", q[0],
                                         ", ", q[1], ", ", q[2], ", ", q[3], ")"));
                if (std::abs(length - 1.0f) > 1e-6f)
                    for (int c = 0; c < 4; ++c)
                        q[c] /= length;
            }
        return true;
    }
};

AnimatedMesh AnimatedMesh::loadGltf(const std::filesystem::path& file, const std::string& clip,
                                    const MeshLimits& limits, const MeshOptions& options) {
    const std::string name = file.string();
    const tinygltf::Model model = readModel(file, limits);
    AnimatedMesh out;
    out.m_rest.name = name;
    out.m_gltfVersion = model.asset.version;
    for (const tinygltf::Mesh& m : model.meshes)
        out.m_meshNames.push_back(m.name);
    for (const tinygltf::Node& n : model.nodes)
        out.m_nodeNames.push_back(n.name);
    GltfReader r{model, name, limits, out, {}};
    r.nodes();
    r.skins();
    r.materials();
    // The scene's nodes in depth-first order, their primitives merged.
    for (const int n : r.sceneOrder()) {
        const tinygltf::Node& node = model.nodes[std::size_t(n)];
        if (node.mesh < 0)
            continue;
        if (node.mesh >= int(model.meshes.size()))
            throw InputError(
                cat(name, ": node ", n, " names mesh ", node.mesh, " that does not exist"));
        if (node.skin >= int(out.m_skins.size()))
            throw InputError(
                cat(name, ": node ", n, " names skin ", node.skin, " that does not exist"));
        for (std::size_t p = 0; p < model.meshes[std::size_t(node.mesh)].primitives.size(); ++p)
            r.primitive(n, p);
    }
    if (out.m_pieces.empty() && r.skipped > 0)
        throw InputError(cat(name, ": its scene holds only point or line primitives (", r.skipped,
                             "), no triangles"));
    if (out.m_pieces.empty())
        throw InputError(cat(name, ": its scene holds no triangle mesh"));
    r.select(options.grow);
    // uv when every part that grows fur has it (a stand without uv left bald does not take the
    // character's uv away); a part without it reads (0, 0).
    bool growingUv = true;
    for (std::size_t i = 0; i < out.m_rest.parts.size(); ++i)
        growingUv = growingUv && (r.partUv[i] || !out.m_rest.parts[i].grows);
    if (r.anyUv && growingUv)
        out.m_rest.uvs = std::move(r.uvs);
    r.clip(clip);
    // The rest pose.
    out.buildPoseGeometry();
    out.m_rest.positions = out.positionsAt(0.0, true);
    const Bounds b = out.m_rest.bounds();
    const double eps = options.weld.tolerance * glm::length(glm::dvec3(b.hi) - glm::dvec3(b.lo));
    finalizeMesh(out.m_rest, options.weld,
                 [&](std::uint32_t a, std::uint32_t c) { return r.moveTogether(a, c, eps); });
    return out;
}

std::vector<glm::mat4> AnimatedMesh::worldMatrices(double t, bool rest) const {
    std::vector<Node> nodes = m_nodes;
    if (!rest)
        for (const Channel& c : m_channels) {
            Node& n = nodes[std::size_t(c.node)];
            switch (c.path) {
            case Channel::Path::Translation: {
                const auto v = sample(c.times, c.values, 3, c.interpolation, false, t);
                n.translation = glm::vec3(v[0], v[1], v[2]);
                break;
            }
            case Channel::Path::Rotation: {
                const auto v = sample(c.times, c.values, 4, c.interpolation, true, t);
                n.rotation = glm::quat(v[3], v[0], v[1], v[2]);
                break;
            }
            case Channel::Path::Scale: {
                const auto v = sample(c.times, c.values, 3, c.interpolation, false, t);
                n.scale = glm::vec3(v[0], v[1], v[2]);
                break;
            }
            case Channel::Path::Weights:
                break;
            }
        }
    std::vector<glm::mat4> world(nodes.size(), glm::mat4(1.0f));
    std::vector<bool> done(nodes.size(), false);
    std::function<const glm::mat4&(std::size_t)> get = [&](std::size_t i) -> const glm::mat4& {
        if (!done[i]) {
            const int p = nodes[i].parent;
            world[i] = (p >= 0 ? get(std::size_t(p)) : glm::mat4(1.0f)) * localMatrix(nodes[i]);
            done[i] = true;
        }
        return world[i];
    };
    for (std::size_t i = 0; i < nodes.size(); ++i)
        get(i);
    return world;
}

std::vector<float> AnimatedMesh::morphWeights(int mesh, double t, bool rest) const {
    std::vector<float> w(m_morphTargets, 0.0f);
    if (rest)
        return w; // the bind pose: the base geometry
    const std::vector<float>& d = m_meshWeights[std::size_t(mesh)];
    std::copy(d.begin(), d.begin() + std::ptrdiff_t(std::min(d.size(), w.size())), w.begin());
    for (const Channel& c : m_channels) {
        if (c.path != Channel::Path::Weights)
            continue;
        bool ours = false;
        for (const Piece& p : m_pieces)
            ours = ours || (p.node == c.node && p.mesh == mesh);
        if (!ours)
            continue;
        const int width = int(c.values.size() / std::max<std::size_t>(c.times.size(), 1) /
                              (c.interpolation == Interpolation::CubicSpline ? 3 : 1));
        const auto v = sample(c.times, c.values, width, c.interpolation, false, t);
        std::copy(v.begin(), v.begin() + std::ptrdiff_t(std::min(v.size(), w.size())), w.begin());
    }
    return w;
}

void AnimatedMesh::buildPoseGeometry() {
    PoseInputs& g = m_geometry;
    g = PoseInputs{};
    g.geometry = 0;
    m_skinPalette.clear();
    std::uint32_t palette = std::uint32_t(m_nodes.size()); // node matrices first
    for (const Skin& s : m_skins) {
        m_skinPalette.push_back(palette);
        palette += std::uint32_t(s.joints.size());
    }
    m_pieceWeights.clear();
    m_weightCount = 0;
    std::size_t total = 0;
    for (const Piece& p : m_pieces)
        total = std::max(total, p.first + p.count);
    g.vertices.resize(total);
    for (std::size_t i = 0; i < m_pieces.size(); ++i) {
        const Piece& p = m_pieces[i];
        gpu::SpotDeformPiece piece{};
        piece.info = glm::uvec4(p.first, p.count, p.targets.size(), g.deltas.size());
        piece.morph.x = m_weightCount;
        m_pieceWeights.push_back(m_weightCount);
        m_weightCount += std::uint32_t(p.targets.size());
        g.pieces.push_back(piece);
        for (const std::vector<glm::vec3>& target : p.targets)
            for (const glm::vec3& d : target)
                g.deltas.emplace_back(d, 0.0f);
        for (std::size_t v = 0; v < p.count; ++v) {
            gpu::SpotDeformVertex& d = g.vertices[p.first + v];
            d.base = glm::vec4(p.base[v], glm::uintBitsToFloat(std::uint32_t(i)));
            if (p.skin < 0) { // the node's matrix alone
                d.joints0 = glm::uvec4(std::uint32_t(p.node), 0, 0, 0);
                d.weights0 = glm::vec4(1.0f, 0.0f, 0.0f, 0.0f);
                continue;
            }
            const std::uint32_t first = m_skinPalette[std::size_t(p.skin)];
            if (!p.joints[0].empty()) {
                d.joints0 = p.joints[0][v] + first;
                d.weights0 = p.weights[0][v];
            }
            if (!p.joints[1].empty()) {
                d.joints1 = p.joints[1][v] + first;
                d.weights1 = p.weights[1][v];
            }
        }
    }
}

double AnimatedMesh::clampTime(double t) const {
    return m_frames.empty() ? std::clamp(t, m_start, m_start + m_duration)
                            : std::clamp(t, 0.0, m_duration);
}

void AnimatedMesh::inputsAt(double t, bool rest, PoseInputs& in) const {
    if (!m_frames.empty()) {
        // A cache: frame i's positions as the base, frame j - frame i as one morph target.
        std::size_t i = 0, j = 0;
        float u = 0.0f;
        if (!rest) {
            const double f = std::clamp(t * m_fps, 0.0, double(m_frames.size() - 1));
            i = std::min(std::size_t(f), m_frames.size() - 1);
            j = std::min(i + 1, m_frames.size() - 1);
            u = float(f - double(i));
        }
        const std::uint64_t key = rest ? ~std::uint64_t(0) - 1 : i;
        if (in.geometry != key) {
            const std::vector<glm::vec3>& a = rest ? m_rest.positions : m_frames[i];
            const std::vector<glm::vec3>& b = rest ? m_rest.positions : m_frames[j];
            in.vertices.assign(a.size(), gpu::SpotDeformVertex{});
            in.deltas.resize(a.size());
            for (std::size_t v = 0; v < a.size(); ++v) {
                in.vertices[v].base = glm::vec4(a[v], glm::uintBitsToFloat(0u));
                in.vertices[v].weights0 = glm::vec4(1.0f, 0.0f, 0.0f, 0.0f);
                in.deltas[v] = glm::vec4(b[v] - a[v], 0.0f);
            }
            in.pieces = {gpu::SpotDeformPiece{glm::uvec4(0, a.size(), 1, 0), glm::uvec4(0)}};
            in.geometry = key;
        }
        in.palette.assign(1, glm::mat4(1.0f));
        in.weights.assign(1, u);
        return;
    }
    if (m_pieces.empty()) { // a mesh that does not move
        if (in.geometry != 0) {
            in.vertices.assign(m_rest.positions.size(), gpu::SpotDeformVertex{});
            for (std::size_t v = 0; v < m_rest.positions.size(); ++v) {
                in.vertices[v].base = glm::vec4(m_rest.positions[v], glm::uintBitsToFloat(0u));
                in.vertices[v].weights0 = glm::vec4(1.0f, 0.0f, 0.0f, 0.0f);
            }
            in.pieces = {
                gpu::SpotDeformPiece{glm::uvec4(0, m_rest.positions.size(), 0, 0), glm::uvec4(0)}};
            in.deltas.clear();
            in.geometry = 0;
        }
        in.palette.assign(1, glm::mat4(1.0f));
        in.weights.clear();
        return;
    }
    if (in.geometry != 0) {
        in.vertices = m_geometry.vertices;
        in.pieces = m_geometry.pieces;
        in.deltas = m_geometry.deltas;
        in.geometry = 0;
    }
    const std::vector<glm::mat4> world = worldMatrices(t, rest);
    in.palette = world;
    for (std::size_t s = 0; s < m_skins.size(); ++s)
        for (std::size_t j = 0; j < m_skins[s].joints.size(); ++j)
            in.palette.push_back(rest ? glm::mat4(1.0f)
                                      : world[std::size_t(m_skins[s].joints[j])] *
                                            m_skins[s].inverseBind[j]);
    in.weights.assign(m_weightCount, 0.0f);
    for (std::size_t i = 0; i < m_pieces.size(); ++i) {
        const Piece& p = m_pieces[i];
        if (p.targets.empty())
            continue;
        const std::vector<float> w = morphWeights(p.mesh, t, rest);
        for (std::size_t k = 0; k < p.targets.size() && k < w.size(); ++k)
            in.weights[m_pieceWeights[i] + k] = w[k];
    }
}

std::vector<glm::vec3> AnimatedMesh::positionsAt(double t, bool rest) const {
    if (rest && !m_frames.empty())
        return m_rest.positions;
    PoseInputs in;
    inputsAt(t, rest, in);
    shared::f32::SharedPoser poser(in.arrays());
    std::vector<glm::vec3> out(in.vertices.size());
    for (std::size_t v = 0; v < out.size(); ++v)
        out[v] = poser.spotPoseVertex(std::uint32_t(v));
    return out;
}

std::vector<glm::vec3> AnimatedMesh::posePositions(double t) const {
    return positionsAt(clampTime(t), false);
}

Mesh AnimatedMesh::pose(double t) const {
    Mesh out = m_rest;
    out.positions = posePositions(t);
    recomputeFrames(out);
    return out;
}

AnimatedMesh AnimatedMesh::loadCache(const std::string& pattern, double fps, int first,
                                     int restFrame, const MeshLimits& limits,
                                     const WeldOptions& weld) {
    if (!(fps > 0.0) || !std::isfinite(fps))
        throw InputError(cat(pattern, ": fps ", fps, " is not positive"));
    // One integer conversion (%d, %04d, %4d, %i) in the file name, nothing else for printf.
    const std::filesystem::path patternPath(pattern);
    const std::string filePattern = patternPath.filename().string();
    const std::size_t percent = filePattern.find('%');
    std::size_t conversion = percent == std::string::npos ? percent : percent + 1;
    while (conversion < filePattern.size() &&
           (std::isdigit(filePattern[conversion]) != 0 || filePattern[conversion] == ' '))
        ++conversion;
    if (percent == std::string::npos || conversion >= filePattern.size() ||
        (filePattern[conversion] != 'd' && filePattern[conversion] != 'i') ||
        filePattern.find('%', percent + 1) != std::string::npos ||
        patternPath.parent_path().string().find('%') != std::string::npos)
        throw InputError(cat(pattern,
                             ": a mesh cache names its frames with one %d in the file name "
                             "(walk.%04d.ply)"));
    const auto frameName = [&](int i) {
        char buf[4096];
        const int n = std::snprintf(buf, sizeof(buf), pattern.c_str(), i);
        if (n <= 0 || n >= int(sizeof(buf)))
            throw InputError(cat(pattern, ": not a frame pattern"));
        return std::string(buf);
    };
    // The frames: the files of the pattern's folder that it formats exactly, consecutive from the
    // first (or from `first`); a gap is an error (a cache that silently stopped at a missing frame
    // would play a shorter clip).
    const std::filesystem::path dir =
        patternPath.parent_path().empty() ? std::filesystem::path(".") : patternPath.parent_path();
    const std::string prefix = filePattern.substr(0, percent);
    const std::string suffix = filePattern.substr(conversion + 1);
    std::vector<int> found;
    std::error_code ec;
    for (std::filesystem::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
        const std::string file = it->path().filename().string();
        if (file.size() <= prefix.size() + suffix.size() || file.rfind(prefix, 0) != 0 ||
            file.compare(file.size() - suffix.size(), suffix.size(), suffix) != 0)
            continue;
        const std::string digits =
            file.substr(prefix.size(), file.size() - prefix.size() - suffix.size());
        if (digits.size() > 9 || digits.find_first_not_of(" 0123456789") != std::string::npos ||
            digits.find_first_of("0123456789") == std::string::npos)
            continue;
        const int number = std::stoi(digits);
        if (std::filesystem::path(frameName(number)).filename().string() == file &&
            (first < 0 || number >= first))
            found.push_back(number);
    }
    if (ec)
        throw InputError(cat(pattern, ": cannot list ", dir.string(), " (", ec.message(), ")"));
    std::sort(found.begin(), found.end());
    if (found.empty())
        throw InputError(first < 0 ? cat(pattern, ": no file matches the pattern")
                                   : cat(frameName(first), ": no such file"));
    const int start = first < 0 ? found.front() : first;
    if (found.front() != start)
        throw InputError(cat(frameName(start), ": no such file"));
    constexpr int kMaxFrames = 100000;
    if (found.back() - start >= kMaxFrames)
        throw InputError(cat(pattern, ": more than ", kMaxFrames, " frames"));
    for (std::size_t i = 1; i < found.size(); ++i)
        if (found[i] != found[i - 1] + 1)
            throw InputError(cat(frameName(found[i - 1] + 1), ": missing (the cache has frames ",
                                 start, " to ", found.back(), "; a cache has no gaps)"));
    if (restFrame < 0 || restFrame >= int(found.size()))
        throw InputError(cat(pattern, ": rest frame ", restFrame, " is not one of the ",
                             found.size(), " frames"));
    // Two frames have the same topology when their vertex counts are equal and their triangle
    // lists (in file order, each less the triangles it collapses to zero area, which loading
    // drops) differ only by triangles that the frame lacking them collapses.
    const auto sameTopology = [](const Mesh& a, const Mesh& b) {
        if (a.positions.size() != b.positions.size())
            return false;
        std::size_t i = 0, j = 0;
        while (i < a.triangles.size() || j < b.triangles.size()) {
            if (i < a.triangles.size() && j < b.triangles.size() &&
                a.triangles[i] == b.triangles[j]) {
                ++i;
                ++j;
            } else if (i < a.triangles.size() && degenerateTriangle(b.positions, a.triangles[i])) {
                ++i;
            } else if (j < b.triangles.size() && degenerateTriangle(a.positions, b.triangles[j])) {
                ++j;
            } else {
                return false;
            }
        }
        return true;
    };
    AnimatedMesh out;
    out.m_fps = fps;
    Mesh firstMesh;
    WeldOptions unwelded = weld;
    unwelded.on = false; // each frame as stored; the rest is welded below, against every frame
    for (const int number : found) {
        Mesh m = loadMesh(frameName(number), limits, unwelded);
        if (!out.m_frames.empty() && !sameTopology(firstMesh, m))
            throw InputError(cat(m.name, ": its topology differs from ", firstMesh.name, "'s (",
                                 m.positions.size(), " vertices, ", m.triangles.size(),
                                 " triangles against ", firstMesh.positions.size(), " and ",
                                 firstMesh.triangles.size(), ")"));
        out.m_frames.push_back(m.positions);
        if (number - start == restFrame)
            out.m_rest = m;
        if (number == start)
            firstMesh = std::move(m);
    }
    out.m_duration = double(out.m_frames.size() - 1) / fps;
    if (weld.on) {
        // The rest frame welded where the copies stay within the tolerance in every frame; then
        // every frame's welded copies take their kept vertex's position, as the rest's do.
        const std::string restFile = out.m_rest.name;
        double eps = 0.0;
        for (const std::vector<glm::vec3>& f : out.m_frames) {
            glm::dvec3 lo(f.front()), hi(f.front());
            for (const glm::vec3& p : f) {
                lo = glm::min(lo, glm::dvec3(p));
                hi = glm::max(hi, glm::dvec3(p));
            }
            eps = std::max(eps, weld.tolerance * glm::length(hi - lo));
        }
        out.m_rest = loadMesh(restFile, limits, weld, [&](std::uint32_t a, std::uint32_t b) {
            for (const std::vector<glm::vec3>& f : out.m_frames)
                if (glm::length(glm::dvec3(f[a]) - glm::dvec3(f[b])) > eps)
                    return false;
            return true;
        });
        for (std::vector<glm::vec3>& f : out.m_frames)
            for (std::size_t v = 0; v < f.size(); ++v)
                f[v] = f[out.m_rest.welded(std::uint32_t(v))];
    }
    return out;
}

AnimatedMesh AnimatedMesh::load(const std::string& spec, const std::string& clip, double fps,
                                int restFrame, const MeshOptions& options) {
    const std::filesystem::path p(spec);
    std::string ext = p.extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(),
                   [](unsigned char c) { return char(std::tolower(c)); });
    if (ext == ".gltf" || ext == ".glb")
        return loadGltf(p, clip, {}, options);
    if (options.grow.chooses())
        throw InputError(cat(spec, ": the scene's \"grow\" chooses glTF meshes and nodes; this "
                                   "mesh has none (a glTF file, .gltf or .glb, has)"));
    if (spec.find('%') != std::string::npos)
        return loadCache(spec, fps, -1, restFrame, {}, options.weld);
    AnimatedMesh out;
    out.m_rest = loadMeshOrGenerated(spec, options.weld);
    return out;
}

FrameRange clipFrames(const AnimatedMesh& mesh, double fps) {
    // A frame within 1e-6 of a frame's time is that frame (key times are floats: 1/24 s is
    // 0.0416666679).
    constexpr double eps = 1e-6;
    const double start = mesh.start(), end = mesh.start() + mesh.duration();
    FrameRange r;
    r.first = long(std::ceil(start * fps - eps));
    r.last = std::max(r.first, long(std::floor(end * fps + eps)));
    return r;
}

} // namespace spot::noise
