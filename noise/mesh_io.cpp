// Mesh loaders: OBJ through tinyobjloader behind a strict pre-scan, PLY by hand.
//
// Both treat their input as hostile: every count read from the file is checked against
// MeshLimits and against what the remaining bytes can hold before anything is sized from it, and
// every loop is bounded by the input's length. The first problem found becomes one InputError that
// names the file, the place and the value.
#include "noise/mesh.h"

#include <algorithm>
#include <functional>
#include <array>
#include <bit>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <sstream>
#include <unordered_map>
#include <unordered_set>
#include <utility>

#include <tiny_obj_loader.h>

#include "noise/error.h"
#include "noise/system.h"

namespace spot::noise {

namespace {

/// Loads estimated below this skip the memory-budget check, which reads /proc.
constexpr std::uint64_t kMemoryCheckThreshold = 64ull << 20;

// ------------------------------------------------------------------------------------------------
// Shared helpers

bool isBlank(char c) {
    return c == ' ' || c == '\t';
}

/// Numbers must be whole tokens: "1.5x" or "0x10" are errors, not 1.5 or 0. A leading '+' is
/// accepted (some writers emit it; std::from_chars does not).
bool stripPlus(std::string_view& token) {
    if (!token.empty() && token.front() == '+') {
        token.remove_prefix(1);
        if (token.empty() || token.front() == '-' || token.front() == '+')
            return false;
    }
    return !token.empty();
}

bool parseDouble(std::string_view token, double& out) {
    if (!stripPlus(token))
        return false;
    const char* end = token.data() + token.size();
    const auto [ptr, ec] = std::from_chars(token.data(), end, out);
    if (ptr != end)
        return false;
    if (ec == std::errc::result_out_of_range) {
        // Syntactically fine but over- or underflowing: strtod gives +-inf or (sub)normal zero.
        const std::string copy(token);
        out = std::strtod(copy.c_str(), nullptr);
        return true;
    }
    return ec == std::errc();
}

bool parseInt(std::string_view token, std::int64_t& out) {
    if (!stripPlus(token))
        return false;
    const char* end = token.data() + token.size();
    const auto [ptr, ec] = std::from_chars(token.data(), end, out);
    return ptr == end && ec == std::errc();
}

/// A token or header line quoted in a message: cut short, non-printable bytes shown as '?', so
/// the message stays one readable line whatever the file holds.
std::string quote(std::string_view text) {
    constexpr std::size_t kMaxShown = 40;
    std::string out = "'";
    for (std::size_t i = 0; i < text.size() && i < kMaxShown; ++i) {
        const auto c = static_cast<unsigned char>(text[i]);
        out.push_back(c >= 0x20 && c < 0x7f ? static_cast<char>(c) : '?');
    }
    if (text.size() > kMaxShown)
        out += "...";
    out += "'";
    return out;
}

std::string lowerExtension(const std::filesystem::path& file) {
    std::string ext = file.extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](char c) {
        return (c >= 'A' && c <= 'Z') ? static_cast<char>(c - 'A' + 'a') : c;
    });
    return ext;
}

void checkInputSize(std::string_view bytes, const std::string& name, const MeshLimits& limits) {
    if (bytes.size() > limits.maxFileBytes)
        throw InputError(cat(name, ": file is ", bytes.size(), " bytes, more than the limit of ",
                             limits.maxFileBytes));
    if (bytes.empty())
        throw InputError(cat(name, ": file is empty"));
}

void checkMemory(std::uint64_t bytes, const std::string& name) {
    if (bytes >= kMemoryCheckThreshold)
        requireMemory(bytes, cat("loading ", name));
}

// ------------------------------------------------------------------------------------------------
// OBJ
//
// tinyobjloader is lenient where we must be strict: it reads an unparsable number as 0, an index
// through atoi (overflow wraps), keeps at most 255 corners per face when not triangulating, and
// some statements ('t' tags) allocate from counts in the text. So every line is checked here
// first, and tinyobjloader is handed a canonical copy holding only the statements we use
// (v, vt, vn, f) with numbers re-printed and indices made absolute. Its own triangulation is not
// used: polygons are fan-triangulated below, the documented behaviour.

constexpr std::size_t kObjMaxCornersPerFace = 255; // tinyobj stores corner counts as uchar

struct ObjCounts {
    std::size_t positions = 0;
    std::size_t texcoords = 0;
    std::size_t normals = 0;
    std::size_t faces = 0; // after splitting faces with more than kObjMaxCornersPerFace corners
    std::size_t corners = 0;
    std::size_t triangles = 0;
};

class ObjScanner {
public:
    ObjScanner(std::string_view text, const std::string& name, const MeshLimits& limits)
        : m_text(text), m_name(name), m_limits(limits) {}

    /// Validate every line; return the canonical text for tinyobjloader.
    std::string run() {
        if (m_text.find('\0') != std::string_view::npos)
            throw InputError(cat(m_name, ": contains a NUL byte; not a text OBJ file"));
        m_out.reserve(m_text.size());
        std::size_t pos = 0;
        while (pos < m_text.size()) {
            // Line ends as tinyobjloader sees them: "\n", "\r\n" or a lone "\r".
            std::size_t end = m_text.find_first_of("\r\n", pos);
            if (end == std::string_view::npos)
                end = m_text.size();
            ++m_line;
            scanLine(m_text.substr(pos, end - pos));
            pos = end;
            if (pos < m_text.size())
                pos += (m_text[pos] == '\r' && pos + 1 < m_text.size() && m_text[pos + 1] == '\n')
                           ? 2
                           : 1;
        }
        return std::move(m_out);
    }

    const ObjCounts& counts() const { return m_counts; }

private:
    [[noreturn]] void fail(const std::string& what) const {
        throw InputError(cat(m_name, ": line ", m_line, ": ", what));
    }

    static std::string_view nextToken(std::string_view line, std::size_t& i) {
        while (i < line.size() && isBlank(line[i]))
            ++i;
        const std::size_t start = i;
        while (i < line.size() && !isBlank(line[i]))
            ++i;
        return line.substr(start, i - start);
    }

    void scanLine(std::string_view line) {
        std::size_t i = 0;
        const std::string_view keyword = nextToken(line, i);
        // Everything else (comments, groups, objects, materials, smoothing, lines, points, tags,
        // free-form curves) does not change the triangle mesh and is left out unread.
        std::size_t maxTokens = 0; // keyword included; bounds the token list of a hostile line
        if (keyword == "v" || keyword == "vt" || keyword == "vn") {
            maxTokens = 8;
        } else if (keyword == "f") {
            const std::size_t budget =
                m_limits.maxTriangles - std::min(m_limits.maxTriangles, m_counts.triangles);
            maxTokens = budget > std::numeric_limits<std::size_t>::max() - 3
                            ? std::numeric_limits<std::size_t>::max()
                            : budget + 3;
        } else {
            return;
        }
        m_tokens.clear();
        m_tokens.push_back(keyword);
        for (std::string_view token = nextToken(line, i); !token.empty();
             token = nextToken(line, i)) {
            if (m_tokens.size() == maxTokens) {
                if (keyword == "f")
                    fail(cat("more than the limit of ", m_limits.maxTriangles, " triangles"));
                fail(cat("too many values for '", keyword, "'"));
            }
            m_tokens.push_back(token);
        }
        if (keyword == "v")
            scanPosition();
        else if (keyword == "vt")
            scanTexcoord();
        else if (keyword == "vn")
            scanNormal();
        else if (keyword == "f")
            scanFace();
    }

    double number(std::size_t k, const char* what) {
        double value = 0.0;
        if (!parseDouble(m_tokens[k], value))
            fail(cat(what, " ", quote(m_tokens[k]), " is not a number"));
        return value;
    }

    static bool fitsFloat(double value) {
        return std::isfinite(value) && std::fabs(value) <= std::numeric_limits<float>::max();
    }

    void appendNumber(double value) {
        std::array<char, 64> buffer{};
        const auto [ptr, ec] =
            std::to_chars(buffer.data(), buffer.data() + buffer.size(), static_cast<float>(value));
        SPOT_CHECK(ec == std::errc());
        m_out.push_back(' ');
        m_out.append(buffer.data(), ptr);
    }

    void scanPosition() {
        // x y z, optionally w or r g b (ignored but checked to be numbers).
        if (m_tokens.size() < 4 || m_tokens.size() > 8)
            fail(cat("vertex ", m_counts.positions + 1, " needs 3 coordinates, got ",
                     m_tokens.size() - 1));
        if (++m_counts.positions > m_limits.maxVertices)
            fail(cat("more than the limit of ", m_limits.maxVertices, " vertices"));
        m_out += "v";
        for (std::size_t k = 1; k < m_tokens.size(); ++k) {
            const double value = number(k, "coordinate");
            if (k <= 3 && !fitsFloat(value))
                fail(cat("vertex ", m_counts.positions, " has a non-finite coordinate ",
                         quote(m_tokens[k])));
            if (!std::isfinite(value))
                fail(cat("vertex ", m_counts.positions, " has a non-finite value ",
                         quote(m_tokens[k])));
            if (k <= 3)
                appendNumber(value);
        }
        m_out += "\n";
    }

    void scanTexcoord() {
        if (m_tokens.size() < 2 || m_tokens.size() > 4)
            fail(cat("texture coordinate ", m_counts.texcoords + 1, " needs 1 to 3 values, got ",
                     m_tokens.size() - 1));
        if (++m_counts.texcoords > m_limits.maxVertices)
            fail(cat("more than the limit of ", m_limits.maxVertices, " texture coordinates"));
        m_out += "vt";
        for (std::size_t k = 1; k < m_tokens.size(); ++k) {
            const double value = number(k, "texture coordinate");
            if (!fitsFloat(value))
                fail(cat("texture coordinate ", m_counts.texcoords,
                         " is not finite: ", quote(m_tokens[k])));
            if (k <= 2)
                appendNumber(value);
        }
        if (m_tokens.size() == 2)
            m_out += " 0";
        m_out += "\n";
    }

    void scanNormal() {
        if (m_tokens.size() != 4)
            fail(
                cat("normal ", m_counts.normals + 1, " needs 3 values, got ", m_tokens.size() - 1));
        if (++m_counts.normals > m_limits.maxVertices)
            fail(cat("more than the limit of ", m_limits.maxVertices, " normals"));
        m_out += "vn";
        for (std::size_t k = 1; k < 4; ++k) {
            // A non-finite normal is written as 0: finalizeMesh replaces zero normals by computed
            // ones, which is what a NaN normal in the file should get too.
            const double value = number(k, "normal component");
            appendNumber(fitsFloat(value) ? value : 0.0);
        }
        m_out += "\n";
    }

    /// Resolve a 1-based or negative (relative) OBJ index against the count so far; 0 when absent.
    std::int64_t resolve(std::string_view text, std::size_t count, const char* what,
                         const char* whatPlural, std::string_view corner) const {
        std::int64_t index = 0;
        if (!parseInt(text, index))
            fail(cat("bad face corner ", quote(corner), ": ", quote(text), " is not an index"));
        const auto n = static_cast<std::int64_t>(count);
        if (index == 0)
            fail(cat("face refers to ", what, " 0; OBJ indices start at 1"));
        if (index > n || index < -n)
            fail(cat("face refers to ", what, " ", index, " but there are ", n, " ",
                     n == 1 ? what : whatPlural, " so far"));
        return index > 0 ? index : n + index + 1;
    }

    struct Corner {
        std::int64_t v = 0, vt = 0, vn = 0; // 1-based, 0 = absent
    };

    Corner parseCorner(std::string_view corner) const {
        // v, v/vt, v//vn or v/vt/vn
        std::array<std::string_view, 3> parts{};
        std::size_t count = 0;
        std::size_t start = 0;
        while (true) {
            const std::size_t slash = corner.find('/', start);
            if (count == 3)
                fail(cat("bad face corner ", quote(corner), ": too many '/'"));
            parts[count++] = corner.substr(
                start, slash == std::string_view::npos ? std::string_view::npos : slash - start);
            if (slash == std::string_view::npos)
                break;
            start = slash + 1;
        }
        Corner c;
        c.v = resolve(parts[0], m_counts.positions, "vertex", "vertices", corner);
        if (count >= 2 && !(count == 3 && parts[1].empty()))
            c.vt = resolve(parts[1], m_counts.texcoords, "texture coordinate",
                           "texture coordinates", corner);
        if (count == 3)
            c.vn = resolve(parts[2], m_counts.normals, "normal", "normals", corner);
        return c;
    }

    void appendIndex(std::int64_t index) {
        std::array<char, 24> buffer{};
        const auto [ptr, ec] = std::to_chars(buffer.data(), buffer.data() + buffer.size(), index);
        SPOT_CHECK(ec == std::errc());
        m_out.append(buffer.data(), ptr);
    }

    void writeCorner(const Corner& c) {
        m_out.push_back(' ');
        appendIndex(c.v);
        if (c.vt != 0 || c.vn != 0)
            m_out.push_back('/');
        if (c.vt != 0)
            appendIndex(c.vt);
        if (c.vn != 0) {
            m_out.push_back('/');
            appendIndex(c.vn);
        }
    }

    void writeFace(const std::vector<Corner>& corners, std::size_t first, std::size_t last) {
        m_out += "f";
        writeCorner(corners[0]);
        for (std::size_t k = first; k <= last; ++k)
            writeCorner(corners[k]);
        m_out += "\n";
        ++m_counts.faces;
    }

    void scanFace() {
        const std::size_t n = m_tokens.size() - 1;
        if (n < 3)
            fail(cat("face has ", n, " corner", n == 1 ? "" : "s", "; a face needs at least 3"));
        m_counts.triangles += n - 2;
        m_counts.corners += n;
        if (m_counts.triangles > m_limits.maxTriangles)
            fail(cat("more than the limit of ", m_limits.maxTriangles, " triangles"));
        m_corners.clear();
        for (std::size_t k = 1; k <= n; ++k)
            m_corners.push_back(parseCorner(m_tokens[k]));
        // Split a long polygon into fans sharing corner 0: the triangles are the same as one fan
        // over the whole polygon, and each piece fits tinyobjloader's 255-corner faces.
        for (std::size_t first = 1; first + 1 < n;) {
            const std::size_t last = std::min(first + kObjMaxCornersPerFace - 2, n - 1);
            writeFace(m_corners, first, last);
            first = last;
        }
    }

    std::string_view m_text;
    const std::string& m_name;
    const MeshLimits& m_limits;
    std::size_t m_line = 0;
    std::vector<std::string_view> m_tokens;
    std::vector<Corner> m_corners;
    ObjCounts m_counts;
    std::string m_out;
};

struct ObjCornerKey {
    int v, vt, vn;
    bool operator==(const ObjCornerKey&) const = default;
};

struct ObjCornerHash {
    std::size_t operator()(const ObjCornerKey& k) const {
        std::uint64_t h = static_cast<std::uint32_t>(k.v);
        h = h * 0x9E3779B97F4A7C15ull ^ static_cast<std::uint32_t>(k.vt);
        h = h * 0x9E3779B97F4A7C15ull ^ static_cast<std::uint32_t>(k.vn);
        return static_cast<std::size_t>(h ^ (h >> 29));
    }
};

Mesh buildObjMesh(const tinyobj::attrib_t& attrib, const std::vector<tinyobj::shape_t>& shapes,
                  const std::string& name, const MeshLimits& limits, const ObjCounts& counts) {
    SPOT_CHECK_EQ(attrib.vertices.size(), 3 * counts.positions);
    SPOT_CHECK_EQ(attrib.texcoords.size(), 2 * counts.texcoords);
    SPOT_CHECK_EQ(attrib.normals.size(), 3 * counts.normals);
    const auto nv = static_cast<int>(counts.positions);
    const auto nvt = static_cast<int>(counts.texcoords);
    const auto nvn = static_cast<int>(counts.normals);

    // uv only if every corner has one: a partly textured mesh has no consistent parameterization.
    bool allUv = true;
    bool anyNormal = false;
    std::size_t faces = 0;
    for (const tinyobj::shape_t& shape : shapes) {
        faces += shape.mesh.num_face_vertices.size();
        for (const tinyobj::index_t& idx : shape.mesh.indices) {
            if (idx.vertex_index < 0 || idx.vertex_index >= nv || idx.texcoord_index < -1 ||
                idx.texcoord_index >= nvt || idx.normal_index < -1 || idx.normal_index >= nvn)
                throw InputError(cat(name, ": face index out of range after parsing (vertex ",
                                     idx.vertex_index, ")"));
            allUv = allUv && idx.texcoord_index >= 0;
            anyNormal = anyNormal || idx.normal_index >= 0;
        }
    }
    SPOT_CHECK_EQ(faces, counts.faces);

    Mesh mesh;
    mesh.name = name;
    mesh.triangles.reserve(counts.triangles);
    std::unordered_map<ObjCornerKey, std::uint32_t, ObjCornerHash> unique;
    unique.reserve(std::min(counts.corners, counts.positions * 2 + 16));
    auto vertexFor = [&](const tinyobj::index_t& idx) {
        const ObjCornerKey key{idx.vertex_index, allUv ? idx.texcoord_index : -1,
                               anyNormal ? idx.normal_index : -1};
        const auto [it, inserted] =
            unique.try_emplace(key, static_cast<std::uint32_t>(mesh.positions.size()));
        if (inserted) {
            if (mesh.positions.size() >= limits.maxVertices)
                throw InputError(cat(name,
                                     ": splitting vertices at uv and normal seams gives more ",
                                     "than the limit of ", limits.maxVertices, " vertices"));
            const auto v = static_cast<std::size_t>(key.v);
            mesh.positions.emplace_back(attrib.vertices[3 * v], attrib.vertices[3 * v + 1],
                                        attrib.vertices[3 * v + 2]);
            if (allUv) {
                const auto t = static_cast<std::size_t>(key.vt);
                mesh.uvs.emplace_back(attrib.texcoords[2 * t], attrib.texcoords[2 * t + 1]);
            }
            if (anyNormal) {
                // A corner without a normal gets a zero one, which finalizeMesh replaces by the
                // computed normal.
                glm::vec3 normal(0.0f);
                if (key.vn >= 0) {
                    const auto n = static_cast<std::size_t>(key.vn);
                    normal = {attrib.normals[3 * n], attrib.normals[3 * n + 1],
                              attrib.normals[3 * n + 2]};
                }
                mesh.normals.push_back(normal);
            }
        }
        return it->second;
    };

    for (const tinyobj::shape_t& shape : shapes) {
        std::size_t offset = 0;
        for (const unsigned char cornerCount : shape.mesh.num_face_vertices) {
            SPOT_CHECK_LE(offset + cornerCount, shape.mesh.indices.size());
            SPOT_CHECK_LE(3u, static_cast<unsigned>(cornerCount));
            const std::uint32_t first = vertexFor(shape.mesh.indices[offset]);
            std::uint32_t previous = vertexFor(shape.mesh.indices[offset + 1]);
            for (std::size_t k = 2; k < cornerCount; ++k) {
                const std::uint32_t current = vertexFor(shape.mesh.indices[offset + k]);
                mesh.triangles.emplace_back(first, previous, current);
                previous = current;
            }
            offset += cornerCount;
        }
        SPOT_CHECK_EQ(offset, shape.mesh.indices.size());
    }
    return mesh;
}

// ------------------------------------------------------------------------------------------------
// PLY

/// A header this long is not a mesh header; refusing it bounds the work before end_header.
constexpr std::size_t kPlyMaxHeaderBytes = 1 << 20;

enum class PlyType { Int8, UInt8, Int16, UInt16, Int32, UInt32, Float32, Float64 };

struct PlyTypeInfo {
    std::string_view name;
    PlyType type;
};

constexpr std::array<PlyTypeInfo, 16> kPlyTypeNames{{
    {"char", PlyType::Int8},
    {"int8", PlyType::Int8},
    {"uchar", PlyType::UInt8},
    {"uint8", PlyType::UInt8},
    {"short", PlyType::Int16},
    {"int16", PlyType::Int16},
    {"ushort", PlyType::UInt16},
    {"uint16", PlyType::UInt16},
    {"int", PlyType::Int32},
    {"int32", PlyType::Int32},
    {"uint", PlyType::UInt32},
    {"uint32", PlyType::UInt32},
    {"float", PlyType::Float32},
    {"float32", PlyType::Float32},
    {"double", PlyType::Float64},
    {"float64", PlyType::Float64},
}};

std::size_t typeSize(PlyType t) {
    switch (t) {
    case PlyType::Int8:
    case PlyType::UInt8:
        return 1;
    case PlyType::Int16:
    case PlyType::UInt16:
        return 2;
    case PlyType::Int32:
    case PlyType::UInt32:
    case PlyType::Float32:
        return 4;
    case PlyType::Float64:
        return 8;
    }
    return 1;
}

bool isIntegral(PlyType t) {
    return t != PlyType::Float32 && t != PlyType::Float64;
}

std::string_view typeName(PlyType t) {
    for (const PlyTypeInfo& info : kPlyTypeNames) {
        if (info.type == t)
            return info.name;
    }
    return "?";
}

/// Largest value of an integer type, used to scale integer colours to [0,1].
double typeMax(PlyType t) {
    switch (t) {
    case PlyType::Int8:
        return 127.0;
    case PlyType::UInt8:
        return 255.0;
    case PlyType::Int16:
        return 32767.0;
    case PlyType::UInt16:
        return 65535.0;
    case PlyType::Int32:
        return 2147483647.0;
    case PlyType::UInt32:
        return 4294967295.0;
    default:
        return 1.0;
    }
}

std::pair<double, double> typeRange(PlyType t) {
    switch (t) {
    case PlyType::Int8:
        return {-128.0, 127.0};
    case PlyType::UInt8:
        return {0.0, 255.0};
    case PlyType::Int16:
        return {-32768.0, 32767.0};
    case PlyType::UInt16:
        return {0.0, 65535.0};
    case PlyType::Int32:
        return {-2147483648.0, 2147483647.0};
    case PlyType::UInt32:
        return {0.0, 4294967295.0};
    default:
        return {-std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity()};
    }
}

struct PlyProperty {
    std::string name;
    PlyType type = PlyType::Float32; ///< scalar type, or the list's item type
    bool isList = false;
    PlyType countType = PlyType::UInt8;
};

struct PlyElement {
    std::string name;
    std::uint64_t count = 0;
    std::vector<PlyProperty> properties;

    /// Bytes (binary) or tokens (ascii) a record needs at least: every scalar, every list count.
    std::uint64_t minBinaryBytes() const {
        std::uint64_t bytes = 0;
        for (const PlyProperty& p : properties)
            bytes += typeSize(p.isList ? p.countType : p.type);
        return bytes;
    }
    std::uint64_t minTokens() const { return properties.size(); }
    bool hasLists() const {
        return std::any_of(properties.begin(), properties.end(),
                           [](const PlyProperty& p) { return p.isList; });
    }
    const PlyProperty* find(std::string_view key) const {
        for (const PlyProperty& p : properties) {
            if (p.name == key)
                return &p;
        }
        return nullptr;
    }
};

std::string plural(const PlyElement& e) {
    if (e.name == "vertex")
        return "vertices";
    if (e.name == "face")
        return "faces";
    return cat(quote(e.name), " elements");
}

std::string singular(const PlyElement& e) {
    if (e.name == "vertex" || e.name == "face")
        return e.name;
    return cat(quote(e.name), " element");
}

enum class PlyFormat { Ascii, BinaryLittleEndian };

struct PlyHeader {
    PlyFormat format = PlyFormat::Ascii;
    std::vector<PlyElement> elements;
    std::size_t dataOffset = 0;
};

/// `line` split at blanks into `tokens` (cleared first).
void splitPlyTokens(std::string_view line, std::vector<std::string_view>& tokens) {
    tokens.clear();
    for (std::size_t i = 0; i < line.size();) {
        while (i < line.size() && isBlank(line[i]))
            ++i;
        const std::size_t start = i;
        while (i < line.size() && !isBlank(line[i]))
            ++i;
        if (i > start)
            tokens.push_back(line.substr(start, i - start));
    }
}

/// A header's failure on its current line: throws InputError naming the line (never returns).
using PlyHeaderFail = std::function<void(const std::string&)>;

/// An `element NAME COUNT` line; its name must be new (`elementNames`) and its count within
/// `limits` for the vertex and face elements.
PlyElement parsePlyElement(const std::vector<std::string_view>& tokens, const std::string& name,
                           const MeshLimits& limits, std::unordered_set<std::string>& elementNames,
                           const PlyHeaderFail& fail) {
    if (tokens.size() != 3)
        fail("expected 'element NAME COUNT'");
    const std::string_view countText = tokens[2];
    std::int64_t count = 0;
    std::uint64_t ucount = 0;
    if (parseInt(countText, count)) {
        if (count < 0)
            fail(cat("negative element count ", count));
        ucount = static_cast<std::uint64_t>(count);
    } else if (std::all_of(countText.begin(), countText.end(),
                           [](char c) { return c >= '0' && c <= '9'; })) {
        // Too large for 64 bits: still a count, refused below with the other huge ones.
        ucount = std::numeric_limits<std::uint64_t>::max();
    } else {
        fail(cat("element count ", quote(countText), " is not a number"));
    }
    PlyElement element;
    element.name = std::string(tokens[1]);
    element.count = ucount;
    if (!elementNames.insert(element.name).second)
        fail(cat("element ", quote(element.name), " is declared twice"));
    if (element.name == "vertex" && ucount > limits.maxVertices)
        throw InputError(cat(name, ": header declares ", countText,
                             " vertices, more than the limit ", limits.maxVertices));
    if (element.name == "face" && ucount > limits.maxTriangles)
        throw InputError(cat(name, ": header declares ", countText,
                             " faces, more than the limit ", limits.maxTriangles));
    return element;
}

/// A `property TYPE NAME` or `property list COUNT_TYPE ITEM_TYPE NAME` line.
PlyProperty parsePlyProperty(const std::vector<std::string_view>& tokens,
                             const PlyHeaderFail& fail) {
    PlyProperty property;
    auto lookup = [&](std::string_view typeToken) {
        for (const PlyTypeInfo& info : kPlyTypeNames) {
            if (info.name == typeToken)
                return info.type;
        }
        fail(cat("unknown property type ", quote(typeToken)));
        return PlyType::UInt8; // not reached
    };
    if (tokens.size() >= 2 && tokens[1] == "list") {
        if (tokens.size() != 5)
            fail("expected 'property list COUNT_TYPE ITEM_TYPE NAME'");
        property.isList = true;
        property.countType = lookup(tokens[2]);
        property.type = lookup(tokens[3]);
        property.name = std::string(tokens[4]);
        if (!isIntegral(property.countType))
            fail("a list's count type must be an integer type");
    } else {
        if (tokens.size() != 3)
            fail("expected 'property TYPE NAME'");
        property.type = lookup(tokens[1]);
        property.name = std::string(tokens[2]);
    }
    return property;
}

PlyHeader parsePlyHeader(std::string_view bytes, const std::string& name,
                         const MeshLimits& limits) {
    if (bytes.substr(0, 3) != "ply" || bytes.size() < 4 ||
        !(bytes[3] == '\n' || (bytes[3] == '\r' && bytes.size() > 4 && bytes[4] == '\n')))
        throw InputError(cat(name, ": not a PLY file (it does not start with the line 'ply')"));

    PlyHeader header;
    bool haveFormat = false;
    bool done = false;
    std::size_t pos = bytes[3] == '\n' ? 4 : 5;
    std::size_t lineNo = 1;
    std::vector<std::string_view> tokens;
    // Sets, not scans of the lists: a 1 MiB header can declare tens of thousands of names.
    std::unordered_set<std::string> elementNames;
    std::unordered_set<std::string> propertyNames;
    while (!done) {
        if (pos >= bytes.size())
            throw InputError(cat(name, ": header has no end_header line"));
        if (pos > kPlyMaxHeaderBytes)
            throw InputError(cat(name, ": header is longer than ", kPlyMaxHeaderBytes,
                                 " bytes (is end_header missing?)"));
        // Search only the allowed window, so a header without newlines costs no more than that.
        std::size_t end = bytes.substr(0, kPlyMaxHeaderBytes + 1).find('\n', pos);
        if (end == std::string_view::npos) {
            if (bytes.size() > kPlyMaxHeaderBytes)
                throw InputError(cat(name, ": header is longer than ", kPlyMaxHeaderBytes,
                                     " bytes (is end_header missing?)"));
            end = bytes.size();
        }
        std::string_view line = bytes.substr(pos, end - pos);
        pos = std::min(end + 1, bytes.size());
        ++lineNo;
        if (!line.empty() && line.back() == '\r')
            line.remove_suffix(1);
        const auto fail = [&](const std::string& what) {
            throw InputError(cat(name, ": header line ", lineNo, " ", quote(line), ": ", what));
        };

        splitPlyTokens(line, tokens);
        if (tokens.empty())
            continue;
        const std::string_view keyword = tokens[0];
        if (keyword == "comment" || keyword == "obj_info")
            continue;
        if (keyword == "end_header") {
            done = true;
        } else if (keyword == "format") {
            if (haveFormat)
                fail("a second format line");
            if (tokens.size() != 3)
                fail("expected 'format ascii|binary_little_endian 1.0'");
            if (tokens[1] == "ascii")
                header.format = PlyFormat::Ascii;
            else if (tokens[1] == "binary_little_endian")
                header.format = PlyFormat::BinaryLittleEndian;
            else if (tokens[1] == "binary_big_endian")
                throw InputError(cat(name, ": binary_big_endian PLY is not supported; convert it ",
                                     "to binary_little_endian or ascii"));
            else
                fail(cat("unknown format ", quote(tokens[1])));
            haveFormat = true;
        } else if (keyword == "element") {
            if (!haveFormat)
                fail("element before the format line");
            header.elements.push_back(
                parsePlyElement(tokens, name, limits, elementNames, fail));
            propertyNames.clear();
        } else if (keyword == "property") {
            if (header.elements.empty())
                fail("property before any element");
            PlyElement& element = header.elements.back();
            PlyProperty property = parsePlyProperty(tokens, fail);
            if (!propertyNames.insert(property.name).second)
                fail(cat("property ", quote(property.name), " is declared twice in element ",
                         quote(element.name)));
            element.properties.push_back(std::move(property));
        } else {
            fail(cat("unknown header keyword ", quote(keyword)));
        }
    }
    if (!haveFormat)
        throw InputError(cat(name, ": header has no format line"));
    header.dataOffset = pos;
    return header;
}

/// Reads scalars from the data after the header, in either encoding. Methods return false when
/// the data ends; a token that is not a valid number of its type throws through `fail`.
class PlyReader {
public:
    PlyReader(std::string_view data, PlyFormat format)
        : m_data(data), m_binary(format != PlyFormat::Ascii) {}

    bool binary() const { return m_binary; }
    std::uint64_t remaining() const { return m_data.size() - m_pos; }

    /// Largest number of further items of type `t` the data could still hold.
    std::uint64_t capacity(PlyType t) const {
        return m_binary ? remaining() / typeSize(t) : (remaining() + 1) / 2;
    }

    /// One scalar as a double (exact for every PLY integer type). `bad` receives the offending
    /// token for an ascii value that does not parse or does not fit its type.
    bool read(PlyType t, double& value, std::string_view& bad) {
        if (m_binary)
            return readBinary(t, value);
        const std::string_view token = nextToken();
        if (token.empty())
            return false;
        if (isIntegral(t)) {
            std::int64_t i = 0;
            const auto [lo, hi] = typeRange(t);
            if (!parseInt(token, i) || static_cast<double>(i) < lo || static_cast<double>(i) > hi) {
                bad = token;
                value = 0.0;
                return true;
            }
            value = static_cast<double>(i);
            return true;
        }
        if (!parseDouble(token, value)) {
            bad = token;
            value = 0.0;
        }
        return true;
    }

    /// Skip `n` items of type `t` (a list's items or a scalar-only record run), n <= capacity(t).
    bool skip(PlyType t, std::uint64_t n) {
        if (m_binary) {
            if (n > remaining() / typeSize(t))
                return false;
            m_pos += static_cast<std::size_t>(n * typeSize(t));
            return true;
        }
        for (std::uint64_t i = 0; i < n; ++i) {
            if (nextToken().empty())
                return false;
        }
        return true;
    }

private:
    bool readBinary(PlyType t, double& value) {
        const std::size_t size = typeSize(t);
        if (remaining() < size)
            return false;
        std::uint64_t bits = 0;
        for (std::size_t k = 0; k < size; ++k)
            bits |= static_cast<std::uint64_t>(static_cast<unsigned char>(m_data[m_pos + k]))
                    << (8 * k);
        m_pos += size;
        switch (t) {
        case PlyType::Int8:
            value = static_cast<std::int8_t>(bits);
            break;
        case PlyType::UInt8:
            value = static_cast<std::uint8_t>(bits);
            break;
        case PlyType::Int16:
            value = static_cast<std::int16_t>(bits);
            break;
        case PlyType::UInt16:
            value = static_cast<std::uint16_t>(bits);
            break;
        case PlyType::Int32:
            value = static_cast<std::int32_t>(bits);
            break;
        case PlyType::UInt32:
            value = static_cast<std::uint32_t>(bits);
            break;
        case PlyType::Float32:
            value = std::bit_cast<float>(static_cast<std::uint32_t>(bits));
            break;
        case PlyType::Float64:
            value = std::bit_cast<double>(bits);
            break;
        }
        return true;
    }

    std::string_view nextToken() {
        auto space = [](char c) {
            return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\v' || c == '\f';
        };
        while (m_pos < m_data.size() && space(m_data[m_pos]))
            ++m_pos;
        const std::size_t start = m_pos;
        while (m_pos < m_data.size() && !space(m_data[m_pos]))
            ++m_pos;
        return m_data.substr(start, m_pos - start);
    }

    std::string_view m_data;
    std::size_t m_pos = 0;
    bool m_binary;
};

/// Where a vertex property's value goes.
struct VertexSlot {
    enum Kind { Skip, Position, Normal, Uv, Colour, Attribute } kind = Skip;
    int component = 0;
    float* attribute = nullptr; ///< Colour and Attribute: the first value of the column
    double scale = 1.0;         ///< Colour: 1 / largest value of an integer type
};

class PlyParser {
public:
    PlyParser(std::string_view bytes, const std::string& name, const MeshLimits& limits)
        : m_name(name), m_limits(limits), m_header(parsePlyHeader(bytes, name, limits)),
          m_reader(bytes.substr(m_header.dataOffset), m_header.format) {}

    Mesh run() {
        const PlyElement* vertex = findElement("vertex");
        const PlyElement* face = findElement("face");
        if (vertex == nullptr)
            throw InputError(cat(m_name, ": header has no vertex element"));
        if (face == nullptr)
            throw InputError(cat(m_name, ": header has no face element"));
        // Indices are checked against the vertex count as they are read, so it must be known.
        if (face < vertex)
            throw InputError(cat(m_name, ": the face element comes before the vertex element; ",
                                 "faces must follow the vertices they use"));
        for (const char* axis : {"x", "y", "z"}) {
            const PlyProperty* p = vertex->find(axis);
            if (p == nullptr || p->isList)
                throw InputError(
                    cat(m_name, ": vertex element has no scalar '", axis, "' property"));
        }
        m_indexList = face->find("vertex_indices");
        if (m_indexList == nullptr)
            m_indexList = face->find("vertex_index");
        if (m_indexList == nullptr || !m_indexList->isList)
            throw InputError(cat(m_name, ": face element has no vertex_indices list"));
        if (!isIntegral(m_indexList->type))
            throw InputError(cat(m_name, ": face vertex_indices are ", typeName(m_indexList->type),
                                 "; they must be an integer type"));
        checkCapacity();
        checkMemory(estimateBytes(*vertex, *face), m_name);

        m_mesh.name = m_name;
        for (const PlyElement& element : m_header.elements) {
            if (&element == vertex)
                readVertices(element);
            else if (&element == face)
                readFaces(element);
            else
                skipElement(element);
        }
        return std::move(m_mesh);
    }

private:
    const PlyElement* findElement(std::string_view key) const {
        for (const PlyElement& e : m_header.elements) {
            if (e.name == key)
                return &e;
        }
        return nullptr;
    }

    /// Before anything is sized from a count: can the data after the header hold that many
    /// records, each at its smallest (empty lists)?
    void checkCapacity() const {
        const bool binary = m_reader.binary();
        std::uint64_t left = binary ? m_reader.remaining() : (m_reader.remaining() + 1) / 2;
        for (const PlyElement& e : m_header.elements) {
            const std::uint64_t per = binary ? e.minBinaryBytes() : e.minTokens();
            if (per == 0)
                continue; // no properties: no data, whatever the count
            const std::uint64_t fits = left / per;
            if (e.count > fits)
                throw InputError(cat(m_name, ": truncated: header declares ", e.count, " ",
                                     plural(e), " but the data can hold at most ", fits));
            left -= e.count * per;
        }
    }

    std::uint64_t estimateBytes(const PlyElement& vertex, const PlyElement& face) const {
        // Vertex arrays, attribute columns and finalizeMesh's double-precision scratch; a face is
        // at least one triangle.
        const std::uint64_t perVertex = 12 * 4 + 4 * vertex.properties.size() + 3 * 24 + 16;
        return vertex.count * perVertex + face.count * 12;
    }

    [[noreturn]] void truncated(const PlyElement& e, std::uint64_t complete) const {
        throw InputError(cat(m_name, ": truncated: header declares ", e.count, " ", plural(e),
                             " but the data ends after ", complete));
    }

    double readValue(const PlyElement& e, std::uint64_t record, const PlyProperty& p,
                     PlyType type) {
        double value = 0.0;
        std::string_view bad;
        if (!m_reader.read(type, value, bad))
            truncated(e, record);
        if (!bad.empty())
            throw InputError(cat(m_name, ": ", singular(e), " ", record, " property ",
                                 quote(p.name), ": ", quote(bad), " is not a valid ",
                                 typeName(type)));
        return value;
    }

    /// A list's length, checked against what the remaining data can hold before it is used.
    std::uint64_t readListCount(const PlyElement& e, std::uint64_t record, const PlyProperty& p) {
        const double count = readValue(e, record, p, p.countType);
        if (count < 0.0)
            throw InputError(cat(m_name, ": ", singular(e), " ", record, " has a negative list ",
                                 "count ", count, " for ", quote(p.name)));
        const auto n = static_cast<std::uint64_t>(count);
        if (n > m_reader.capacity(p.type))
            throw InputError(cat(m_name, ": truncated or corrupt: ", singular(e), " ", record,
                                 " has a list of ", n, " ", quote(p.name),
                                 " items, more than the remaining data can hold"));
        return n;
    }

    void skipList(const PlyElement& e, std::uint64_t record, const PlyProperty& p) {
        const std::uint64_t n = readListCount(e, record, p);
        if (!m_reader.skip(p.type, n))
            truncated(e, record);
    }

    std::vector<VertexSlot> vertexSlots(const PlyElement& e) {
        const std::size_t n = static_cast<std::size_t>(e.count);
        std::vector<VertexSlot> slots(e.properties.size());
        auto assign = [&](std::string_view key, VertexSlot::Kind kind, int component) {
            for (std::size_t k = 0; k < e.properties.size(); ++k) {
                if (e.properties[k].name == key && !e.properties[k].isList) {
                    slots[k].kind = kind;
                    slots[k].component = component;
                }
            }
        };
        auto hasScalar = [&](std::string_view key) {
            const PlyProperty* p = e.find(key);
            return p != nullptr && !p->isList;
        };
        assign("x", VertexSlot::Position, 0);
        assign("y", VertexSlot::Position, 1);
        assign("z", VertexSlot::Position, 2);
        m_mesh.positions.resize(n);
        if (hasScalar("nx") && hasScalar("ny") && hasScalar("nz")) {
            assign("nx", VertexSlot::Normal, 0);
            assign("ny", VertexSlot::Normal, 1);
            assign("nz", VertexSlot::Normal, 2);
            m_mesh.normals.resize(n);
        }
        constexpr std::array<std::pair<std::string_view, std::string_view>, 4> kUvNames{
            {{"u", "v"}, {"s", "t"}, {"texture_u", "texture_v"}, {"texture_s", "texture_t"}}};
        for (const auto& [uName, vName] : kUvNames) {
            if (hasScalar(uName) && hasScalar(vName)) {
                assign(uName, VertexSlot::Uv, 0);
                assign(vName, VertexSlot::Uv, 1);
                m_mesh.uvs.resize(n);
                break;
            }
        }
        // Every other scalar keeps its name; colours are also scaled to [0,1].
        for (std::size_t k = 0; k < e.properties.size(); ++k) {
            const PlyProperty& p = e.properties[k];
            if (p.isList || slots[k].kind != VertexSlot::Skip)
                continue;
            const bool colour =
                p.name == "red" || p.name == "green" || p.name == "blue" || p.name == "alpha";
            std::vector<float>& column = m_mesh.attributes[p.name];
            column.resize(n);
            slots[k].kind = colour ? VertexSlot::Colour : VertexSlot::Attribute;
            slots[k].attribute = column.data();
            slots[k].scale = colour && isIntegral(p.type) ? 1.0 / typeMax(p.type) : 1.0;
        }
        return slots;
    }

    void readVertices(const PlyElement& e) {
        const std::vector<VertexSlot> slots = vertexSlots(e);
        const std::size_t n = static_cast<std::size_t>(e.count);
        for (std::size_t i = 0; i < n; ++i) {
            for (std::size_t k = 0; k < e.properties.size(); ++k) {
                const PlyProperty& p = e.properties[k];
                if (p.isList) {
                    skipList(e, i, p);
                    continue;
                }
                const double value = readValue(e, i, p, p.type);
                const VertexSlot& slot = slots[k];
                switch (slot.kind) {
                case VertexSlot::Skip:
                    break;
                case VertexSlot::Position:
                    m_mesh.positions[i][slot.component] = static_cast<float>(value);
                    break;
                case VertexSlot::Normal:
                    m_mesh.normals[i][slot.component] = static_cast<float>(value);
                    break;
                case VertexSlot::Uv:
                    m_mesh.uvs[i][slot.component] = static_cast<float>(value);
                    break;
                case VertexSlot::Colour:
                    // NaN passes the clamp and is refused by finalizeMesh with the vertex number.
                    slot.attribute[i] =
                        static_cast<float>(std::clamp(value * slot.scale, 0.0, 1.0));
                    break;
                case VertexSlot::Attribute:
                    slot.attribute[i] = static_cast<float>(value);
                    break;
                }
            }
            // Checked here, not only in finalizeMesh, so the message names the file's vertex.
            const glm::vec3& p = m_mesh.positions[i];
            if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
                throw InputError(cat(m_name, ": vertex ", i, " has a non-finite coordinate (", p.x,
                                     " ", p.y, " ", p.z, ")"));
        }
        m_vertexCount = n;
        m_verticesRead = true;
    }

    void readFaces(const PlyElement& e) {
        SPOT_CHECK(m_verticesRead);
        m_mesh.triangles.reserve(static_cast<std::size_t>(e.count));
        std::vector<std::uint32_t> polygon;
        for (std::uint64_t f = 0; f < e.count; ++f) {
            for (const PlyProperty& p : e.properties) {
                if (&p != m_indexList) {
                    if (p.isList)
                        skipList(e, f, p);
                    else
                        readValue(e, f, p, p.type);
                    continue;
                }
                const std::uint64_t n = readListCount(e, f, p);
                polygon.clear();
                for (std::uint64_t k = 0; k < n; ++k) {
                    const double index = readValue(e, f, p, p.type);
                    if (index < 0.0 || index >= static_cast<double>(m_vertexCount))
                        throw InputError(cat(m_name, ": face ", f, " refers to vertex ",
                                             static_cast<std::int64_t>(index), " but there are ",
                                             m_vertexCount, " vertices"));
                    polygon.push_back(static_cast<std::uint32_t>(index));
                }
                if (n < 3) {
                    ++m_mesh.droppedTriangles; // a face with fewer than 3 corners has no area
                    ++m_mesh.droppedWhy["a face of fewer than 3 corners"];
                    continue;
                }
                if (m_mesh.triangles.size() + (n - 2) > m_limits.maxTriangles)
                    throw InputError(cat(m_name, ": faces make more than the limit of ",
                                         m_limits.maxTriangles, " triangles"));
                for (std::size_t k = 2; k < n; ++k)
                    m_mesh.triangles.emplace_back(polygon[0], polygon[k - 1], polygon[k]);
            }
        }
    }

    void skipElement(const PlyElement& e) {
        if (e.properties.empty())
            return;
        if (m_reader.binary() && !e.hasLists()) {
            // Fixed-size records: one jump (the count was checked against the data already).
            if (!m_reader.skip(PlyType::UInt8, e.count * e.minBinaryBytes()))
                truncated(e, 0);
            return;
        }
        for (std::uint64_t r = 0; r < e.count; ++r) {
            for (const PlyProperty& p : e.properties) {
                if (p.isList)
                    skipList(e, r, p);
                else
                    readValue(e, r, p, p.type);
            }
        }
    }

    const std::string& m_name;
    const MeshLimits& m_limits;
    PlyHeader m_header;
    PlyReader m_reader;
    const PlyProperty* m_indexList = nullptr;
    std::size_t m_vertexCount = 0;
    bool m_verticesRead = false;
    Mesh m_mesh;
};

} // namespace

Mesh parseObj(std::string_view text, const std::string& name, const MeshLimits& limits,
              const WeldOptions& weld, const WeldCompatible& compatible) {
    checkInputSize(text, name, limits);
    ObjScanner scanner(text, name, limits);
    std::string canonical = scanner.run();
    const ObjCounts& counts = scanner.counts();
    if (counts.faces == 0)
        throw InputError(cat(name, ": has no usable triangles (no faces)"));
    // tinyobjloader's arrays and face records, our vertex map and finalizeMesh's scratch.
    checkMemory(canonical.size() * 2 + counts.positions * 48 + counts.faces * 160 +
                    counts.corners * 100,
                name);

    tinyobj::attrib_t attrib;
    std::vector<tinyobj::shape_t> shapes;
    std::vector<tinyobj::material_t> materials;
    std::string warnings;
    std::string errors;
    std::istringstream stream(std::move(canonical));
    if (!tinyobj::LoadObj(&attrib, &shapes, &materials, &warnings, &errors, &stream, nullptr,
                          /*triangulate=*/false, /*default_vcols_fallback=*/false)) {
        const std::string first = errors.substr(0, errors.find('\n'));
        throw InputError(cat(name, ": ", first.empty() ? std::string("cannot parse") : first));
    }
    Mesh mesh = buildObjMesh(attrib, shapes, name, limits, counts);
    finalizeMesh(mesh, weld, compatible);
    return mesh;
}

Mesh parsePly(std::string_view bytes, const std::string& name, const MeshLimits& limits,
              const WeldOptions& weld, const WeldCompatible& compatible) {
    checkInputSize(bytes, name, limits);
    Mesh mesh = PlyParser(bytes, name, limits).run();
    finalizeMesh(mesh, weld, compatible);
    return mesh;
}

Mesh loadMesh(const std::filesystem::path& file, const MeshLimits& limits, const WeldOptions& weld,
              const WeldCompatible& compatible) {
    const std::string name = file.string();
    const std::string ext = lowerExtension(file);
    if (ext != ".obj" && ext != ".ply")
        throw InputError(cat(name, ": unknown mesh format ",
                             ext.empty() ? std::string("(no extension)") : quote(ext),
                             "; expected .obj or .ply"));
    const std::string bytes = readFileCapped(file, limits.maxFileBytes);
    return ext == ".obj" ? parseObj(bytes, name, limits, weld, compatible)
                         : parsePly(bytes, name, limits, weld, compatible);
}

Mesh loadMeshOrGenerated(const std::string& spec, const WeldOptions& weld) {
    const std::string prefix = "generated:";
    if (spec.rfind(prefix, 0) != 0)
        return loadMesh(spec, {}, weld);
    const std::string shape = spec.substr(prefix.size());
    // The shapes are made welded by default; another weld is done again over them (their normals
    // are given, and kept).
    const auto welded = [&](Mesh m) {
        if (!weld.on || weld.tolerance != WeldOptions{}.tolerance)
            finalizeMesh(m, weld);
        return m;
    };
    if (shape == "sphere")
        return welded(makeSphere(1.0f, 96, 192));
    if (shape == "torus")
        return welded(makeTorus(1.0f, 0.35f, 192, 64));
    if (shape == "plane")
        return welded(makePlane(2.0f, 32));
    throw InputError(cat("unknown generated mesh '", shape, "' (sphere, torus or plane)"));
}

} // namespace spot::noise
