#include "noise/mesh.h"

#include <algorithm>
#include <array>
#include <bit>
#include <functional>
#include <cmath>
#include <cstring>
#include <limits>
#include <numbers>
#include <ostream>

#include "noise/error.h"
#include "noise/system.h"

namespace spot::noise {

namespace {

/// A triangle is degenerate when |e1 x e2| <= kDegenerateRelArea * (longest edge)^2: zero area
/// relative to its size, so the threshold does not depend on the mesh's units.
constexpr double kDegenerateRelArea = 1e-12;

/// A vertex normal or tangent whose accumulated sum is this small relative to the largest
/// contribution cancelled out (opposite faces sharing a vertex); its direction is noise.
constexpr double kCancelledRel = 1e-6; // shaders/spot_deform_layout.h kDeformCancelled

bool isFinite(const glm::vec3& v) {
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

bool isFinite(const glm::dvec3& v) {
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

/// Any unit vector orthogonal to the unit vector `n`, continuous except at n.z = -0 (Duff et al.
/// 2017, "Building an Orthonormal Basis, Revisited").
glm::dvec3 orthogonalUnit(const glm::dvec3& n) {
    const double sign = std::copysign(1.0, n.z);
    const double a = -1.0 / (sign + n.z);
    const double b = n.x * n.y * a;
    return glm::normalize(glm::dvec3(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x));
}

std::string meshName(const Mesh& mesh) {
    return mesh.name.empty() ? std::string("mesh") : mesh.name;
}

void checkSizes(const Mesh& mesh, const std::string& name) {
    const std::size_t n = mesh.positions.size();
    if (n > std::numeric_limits<std::uint32_t>::max())
        throw InputError(cat(name, ": ", n, " vertices do not fit 32-bit indices"));
    if (!mesh.normals.empty() && mesh.normals.size() != n)
        throw InputError(cat(name, ": ", mesh.normals.size(), " normals for ", n, " vertices"));
    if (!mesh.uvs.empty() && mesh.uvs.size() != n)
        throw InputError(cat(name, ": ", mesh.uvs.size(), " uvs for ", n, " vertices"));
    for (const auto& [key, values] : mesh.attributes) {
        if (values.size() != n)
            throw InputError(cat(name, ": attribute '", key, "' has ", values.size(),
                                 " values for ", n, " vertices"));
    }
}

void checkParts(const Mesh& mesh, const std::string& name) {
    if (mesh.trianglePart.empty())
        return;
    if (mesh.trianglePart.size() != mesh.triangles.size())
        throw InputError(cat(name, ": ", mesh.trianglePart.size(), " triangle parts for ",
                             mesh.triangles.size(), " triangles"));
    for (const std::uint32_t p : mesh.trianglePart)
        if (p >= mesh.parts.size())
            throw InputError(cat(name, ": a triangle names part ", p, " of ", mesh.parts.size()));
}

void checkValues(const Mesh& mesh, const std::string& name) {
    for (std::size_t i = 0; i < mesh.positions.size(); ++i) {
        if (!isFinite(mesh.positions[i]))
            throw InputError(cat(name, ": vertex ", i, " has a non-finite coordinate (",
                                 mesh.positions[i].x, " ", mesh.positions[i].y, " ",
                                 mesh.positions[i].z, ")"));
    }
    for (std::size_t i = 0; i < mesh.uvs.size(); ++i) {
        if (!std::isfinite(mesh.uvs[i].x) || !std::isfinite(mesh.uvs[i].y))
            throw InputError(cat(name, ": vertex ", i, " has a non-finite uv (", mesh.uvs[i].x, " ",
                                 mesh.uvs[i].y, ")"));
    }
    for (const auto& [key, values] : mesh.attributes) {
        for (std::size_t i = 0; i < values.size(); ++i) {
            if (!std::isfinite(values[i]))
                throw InputError(cat(name, ": vertex ", i, " has a non-finite value ", values[i],
                                     " for attribute '", key, "'"));
        }
    }
    const std::size_t n = mesh.positions.size();
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
        for (int k = 0; k < 3; ++k) {
            if (mesh.triangles[t][k] >= n)
                throw InputError(cat(name, ": triangle ", t, " refers to vertex ",
                                     mesh.triangles[t][k], " but there are ", n, " vertices"));
        }
    }
}

void dropDegenerate(Mesh& mesh) {
    const bool parted = !mesh.trianglePart.empty();
    std::size_t kept = 0;
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
        const glm::uvec3 tri = mesh.triangles[t];
        const glm::uvec3 w(mesh.welded(tri.x), mesh.welded(tri.y), mesh.welded(tri.z));
        const char* why = nullptr;
        if (tri.x == tri.y || tri.y == tri.z || tri.z == tri.x)
            why = "two corners on one vertex";
        else if (w.x == w.y || w.y == w.z || w.z == w.x)
            why = "two corners at one position (welded)";
        else if (degenerateTriangle(mesh.positions, tri))
            why = "zero area (corners on a line)";
        if (why) {
            ++mesh.droppedTriangles;
            ++mesh.droppedWhy[why];
            if (parted)
                ++mesh.parts[mesh.trianglePart[t]].dropped[why];
            continue;
        }
        if (parted)
            mesh.trianglePart[kept] = mesh.trianglePart[t];
        mesh.triangles[kept++] = tri;
    }
    mesh.triangles.resize(kept);
    mesh.triangles.shrink_to_fit();
    if (parted) {
        mesh.trianglePart.resize(kept);
        for (MeshPart& p : mesh.parts)
            p.triangles = 0;
        for (const std::uint32_t p : mesh.trianglePart)
            ++mesh.parts[p].triangles;
    }
}

/// Union-find over vertex indices; the root of a set is its lowest index.
struct LowestRootSets {
    std::vector<std::uint32_t> parent;
    explicit LowestRootSets(std::size_t n) : parent(n) {
        for (std::size_t i = 0; i < n; ++i)
            parent[i] = std::uint32_t(i);
    }
    std::uint32_t root(std::uint32_t i) {
        while (parent[i] != i)
            i = parent[i] = parent[parent[i]];
        return i;
    }
    void join(std::uint32_t a, std::uint32_t b) {
        a = root(a);
        b = root(b);
        if (a < b)
            parent[b] = a;
        else if (b < a)
            parent[a] = b;
    }
};

/// Weld the mesh's vertices by position (docs/design.md section 1, "Welding"): vertices within
/// `options.tolerance` x the bounds' diagonal of each other (chains included) are one position;
/// within a position, each vertex joins the lowest-index vertex already kept there that
/// `compatible` accepts, or is kept itself. Welded vertices take their kept vertex's position
/// exactly. Deterministic (no hashing: a sort of grid keys).
void weldVertices(Mesh& mesh, const WeldOptions& options, const WeldCompatible& compatible) {
    const std::size_t n = mesh.positions.size();
    mesh.weld.clear();
    mesh.weldReport = WeldReport{};
    mesh.weldReport.on = options.on;
    mesh.weldReport.welded = n;
    if (!options.on || n == 0)
        return;
    const Bounds b = mesh.bounds();
    const double diagonal = glm::length(glm::dvec3(b.hi) - glm::dvec3(b.lo));
    const double eps = options.tolerance * diagonal;
    mesh.weldReport.tolerance = eps;
    // Grid cells of edge eps (exact positions only when eps is 0); vertices closer than eps lie
    // in the same or neighbouring cells.
    struct Key {
        std::int64_t x, y, z;
        std::uint32_t v;
        bool operator<(const Key& o) const {
            return x != o.x ? x < o.x : y != o.y ? y < o.y : z != o.z ? z < o.z : v < o.v;
        }
    };
    std::vector<Key> sorted(n);
    for (std::uint32_t v = 0; v < n; ++v) {
        const glm::dvec3 p(mesh.positions[v]);
        if (eps > 0.0) {
            const glm::dvec3 q = (p - glm::dvec3(b.lo)) / eps;
            sorted[v] = {std::int64_t(std::floor(q.x)), std::int64_t(std::floor(q.y)),
                         std::int64_t(std::floor(q.z)), v};
        } else { // the float's bits (-0 read as +0) as the key: equal positions only
            const glm::vec3 f = mesh.positions[v] + glm::vec3(0.0f);
            sorted[v] = {std::int64_t(std::bit_cast<std::int32_t>(f.x)),
                         std::int64_t(std::bit_cast<std::int32_t>(f.y)),
                         std::int64_t(std::bit_cast<std::int32_t>(f.z)), v};
        }
    }
    std::sort(sorted.begin(), sorted.end());
    LowestRootSets sets(n);
    const double eps2 = eps * eps;
    const int reach = eps > 0.0 ? 1 : 0;
    for (const Key& k : sorted) {
        const glm::dvec3 p(mesh.positions[k.v]);
        // This cell and the 13 neighbours after it in key order: each pair of cells once.
        for (int dx = 0; dx <= reach; ++dx)
            for (int dy = dx == 0 ? 0 : -reach; dy <= reach; ++dy)
                for (int dz = (dx == 0 && dy == 0) ? 0 : -reach; dz <= reach; ++dz) {
                    const bool same = dx == 0 && dy == 0 && dz == 0;
                    const Key lo{k.x + dx, k.y + dy, k.z + dz, same ? k.v + 1 : 0};
                    for (auto it = std::lower_bound(sorted.begin(), sorted.end(), lo);
                         it != sorted.end() && it->x == lo.x && it->y == lo.y && it->z == lo.z;
                         ++it) {
                        const glm::dvec3 d = glm::dvec3(mesh.positions[it->v]) - p;
                        if (glm::dot(d, d) <= eps2)
                            sets.join(k.v, it->v);
                    }
                }
    }
    // Within each position, in index order: join the first kept vertex that accepts, or keep.
    // The kept vertices of a position are a list through `next`, from `head` to `tail`.
    constexpr std::uint32_t kNone = ~std::uint32_t(0);
    std::vector<std::uint32_t> head(n, kNone), tail(n, kNone), next(n, kNone), weld(n);
    std::vector<std::uint8_t> refused(n, 0), shared(n, 0);
    std::size_t welded = 0;
    for (std::uint32_t v = 0; v < n; ++v) {
        const std::uint32_t r = sets.root(v);
        std::uint32_t to = kNone;
        for (std::uint32_t k = head[r]; k != kNone && to == kNone; k = next[k])
            if (!compatible || compatible(k, v))
                to = k;
        if (to == kNone) {
            if (head[r] != kNone && !refused[r]) {
                refused[r] = 1;
                if (mesh.weldReport.refused++ == 0) {
                    mesh.weldReport.refusedA = head[r];
                    mesh.weldReport.refusedB = v;
                }
            }
            (head[r] == kNone ? head[r] : next[tail[r]]) = v;
            tail[r] = v;
            to = v;
            ++welded;
        }
        if (v != r && !shared[r]) {
            shared[r] = 1;
            ++mesh.weldReport.shared;
        }
        weld[v] = to;
    }
    for (std::uint32_t v = 0; v < n; ++v)
        mesh.positions[v] = mesh.positions[weld[v]];
    mesh.weld = std::move(weld);
    mesh.weldReport.welded = welded;
}

/// The angle of the triangle (p0, p1, p2) at p0, in [0, pi] (atan2 of |a x b| and a . b: exact
/// near 0 and pi, where acos is not).
double cornerAngle(const glm::dvec3& p0, const glm::dvec3& p1, const glm::dvec3& p2) {
    const glm::dvec3 a = p1 - p0, b = p2 - p0;
    return std::atan2(glm::length(glm::cross(a, b)), glm::dot(a, b));
}

/// Given normals of welded copies agree when their directions are within about 1.1 degrees; a
/// welded vertex whose copies were given other directions (a hard edge, flat shading) takes the
/// computed normal instead.
constexpr double kGivenNormalsAgree = 0.9998;

void computeNormals(Mesh& mesh) {
    const std::size_t n = mesh.positions.size();
    // Angle-weighted (Thuermer and Wuethrich 1998): each triangle adds its unit normal times its
    // angle at the corner to the corner's welded vertex, so the normal depends neither on how
    // the faces around it are cut into triangles nor on their sizes.
    std::vector<glm::dvec3> sum(n, glm::dvec3(0.0));
    // The incident face of the largest angle, used where the weighted sum cancels out.
    std::vector<glm::dvec3> largest(n, glm::dvec3(0.0));
    std::vector<double> largestWeight(n, 0.0);
    for (const glm::uvec3& tri : mesh.triangles) {
        const glm::dvec3 p[3] = {glm::dvec3(mesh.positions[tri.x]),
                                 glm::dvec3(mesh.positions[tri.y]),
                                 glm::dvec3(mesh.positions[tri.z])};
        const glm::dvec3 c = glm::cross(p[1] - p[0], p[2] - p[0]);
        const double length = glm::length(c);
        if (!(length > 0.0))
            continue;
        const glm::dvec3 unit = c / length;
        for (int k = 0; k < 3; ++k) {
            const double angle = cornerAngle(p[k], p[(k + 1) % 3], p[(k + 2) % 3]);
            const std::uint32_t w = mesh.welded(tri[k]);
            sum[w] += angle * unit;
            if (angle > largestWeight[w]) {
                largestWeight[w] = angle;
                largest[w] = unit;
            }
        }
    }
    const bool given = !mesh.normals.empty();
    // Per welded vertex: whether its copies' given normals agree (a hard edge's do not).
    std::vector<std::uint8_t> agree(given ? n : 0, 1);
    if (given && !mesh.weld.empty()) {
        std::vector<glm::dvec3> first(n, glm::dvec3(0.0));
        for (std::size_t i = 0; i < n; ++i) {
            const std::uint32_t w = mesh.weld[i];
            const glm::dvec3 g(mesh.normals[i]);
            const double length = glm::length(g);
            if (!(isFinite(g) && std::isfinite(length) && length > 0.0)) {
                agree[w] = 0; // one copy has none: all take the computed one
                continue;
            }
            if (first[w] == glm::dvec3(0.0))
                first[w] = g / length;
            else if (glm::dot(first[w], g / length) < kGivenNormalsAgree)
                agree[w] = 0;
        }
    }
    mesh.normals.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
        const std::uint32_t w = mesh.welded(std::uint32_t(i));
        if (given && agree[w]) {
            const glm::dvec3 g(mesh.normals[i]);
            const double length = glm::length(g);
            if (isFinite(g) && std::isfinite(length) && length > 0.0) {
                mesh.normals[i] = glm::vec3(g / length);
                continue;
            }
        }
        const double length = glm::length(sum[w]);
        if (length > kCancelledRel * largestWeight[w] && length > 0.0)
            mesh.normals[i] = glm::vec3(sum[w] / length);
        else if (largestWeight[w] > 0.0)
            mesh.normals[i] = glm::vec3(largest[w]);
        else
            mesh.normals[i] = glm::vec3(0.0f, 1.0f, 0.0f); // used by no triangle: any unit vector
    }
}

void computeTangents(Mesh& mesh) {
    mesh.tangents.clear();
    if (mesh.uvs.empty())
        return;
    const std::size_t n = mesh.positions.size();
    std::vector<glm::dvec3> sum(n, glm::dvec3(0.0));
    std::vector<double> weight(n, 0.0);
    for (const glm::uvec3& tri : mesh.triangles) {
        const glm::dvec3 p0(mesh.positions[tri.x]);
        const glm::dvec3 e1 = glm::dvec3(mesh.positions[tri.y]) - p0;
        const glm::dvec3 e2 = glm::dvec3(mesh.positions[tri.z]) - p0;
        const glm::dvec2 t0(mesh.uvs[tri.x]);
        const glm::dvec2 d1 = glm::dvec2(mesh.uvs[tri.y]) - t0;
        const glm::dvec2 d2 = glm::dvec2(mesh.uvs[tri.z]) - t0;
        const double det = d1.x * d2.y - d2.x * d1.y;
        if (det == 0.0)
            continue; // uv collapsed to a line: no gradient
        // Solve e1 = d1.x dP/du + d1.y dP/dv, e2 = d2.x dP/du + d2.y dP/dv for dP/du.
        const glm::dvec3 dPdu = (e1 * d2.y - e2 * d1.y) / det;
        const double length = glm::length(dPdu);
        if (!std::isfinite(length) || length == 0.0)
            continue;
        // Direction weighted by area, like the normals, so a tiny triangle with a stretched uv
        // map does not dominate its neighbours.
        const double area = 0.5 * glm::length(glm::cross(e1, e2));
        for (int k = 0; k < 3; ++k) {
            sum[tri[k]] += dPdu * (area / length);
            weight[tri[k]] += area;
        }
    }
    // Welded copies share their +u direction where theirs agree (within 60 degrees of the
    // welded vertex's sum: a uv seam cut through one parametrization), and keep their own where
    // it does not (a mirrored or turned uv island meets them there).
    std::vector<glm::dvec3> groupSum;
    std::vector<double> groupWeight;
    if (!mesh.weld.empty()) {
        groupSum.assign(n, glm::dvec3(0.0));
        groupWeight.assign(n, 0.0);
        for (std::size_t i = 0; i < n; ++i) {
            groupSum[mesh.weld[i]] += sum[i];
            groupWeight[mesh.weld[i]] += weight[i];
        }
    }
    mesh.tangents.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
        glm::dvec3 s = sum[i];
        double w = weight[i];
        if (!groupSum.empty()) {
            const glm::dvec3& g = groupSum[mesh.weld[i]];
            if (glm::dot(s, g) > 0.5 * glm::length(s) * glm::length(g)) {
                s = g;
                w = groupWeight[mesh.weld[i]];
            }
        }
        const glm::dvec3 normal(mesh.normals[i]);
        const glm::dvec3 t = s - normal * glm::dot(normal, s); // Gram-Schmidt
        const double length = glm::length(t);
        const glm::dvec3 unit = (length > kCancelledRel * w && length > 0.0)
                                    ? t / length
                                    : orthogonalUnit(normal);
        mesh.tangents[i] = glm::vec3(unit);
    }
}

/// Little-endian bytes of a 4-byte value, independent of the host's byte order.
void appendLe32(std::string& out, std::uint32_t bits) {
    for (int k = 0; k < 4; ++k)
        out.push_back(static_cast<char>((bits >> (8 * k)) & 0xffu));
}

void appendFloat(std::string& out, float value) {
    appendLe32(out, std::bit_cast<std::uint32_t>(value));
}

void checkGeneratorSize(const char* what, long long vertices) {
    const MeshLimits limits;
    if (vertices > static_cast<long long>(limits.maxVertices))
        throw InputError(
            cat(what, ": ", vertices, " vertices, more than the limit ", limits.maxVertices));
}

} // namespace

Bounds Mesh::bounds() const {
    if (positions.empty())
        return {};
    Bounds b{positions.front(), positions.front()};
    for (const glm::vec3& p : positions) {
        b.lo = glm::min(b.lo, p);
        b.hi = glm::max(b.hi, p);
    }
    return b;
}

double Mesh::surfaceArea() const {
    double area = 0.0;
    for (const glm::uvec3& tri : triangles) {
        const glm::dvec3 p0(positions[tri.x]);
        area += 0.5 * glm::length(glm::cross(glm::dvec3(positions[tri.y]) - p0,
                                             glm::dvec3(positions[tri.z]) - p0));
    }
    return area;
}

bool closedOutward(const Mesh& mesh) {
    if (mesh.triangles.empty())
        return false;
    // Welded ids: vertices sorted by position (-0 read as +0), equal positions one id.
    const auto key = [&](std::uint32_t v) {
        const glm::vec3 p = mesh.positions[v] + glm::vec3(0.0f);
        return std::array<float, 3>{p.x, p.y, p.z};
    };
    std::vector<std::uint32_t> order(mesh.positions.size());
    for (std::uint32_t v = 0; v < order.size(); ++v)
        order[v] = v;
    std::sort(order.begin(), order.end(),
              [&](std::uint32_t a, std::uint32_t b) { return key(a) < key(b); });
    std::vector<std::uint32_t> weld(mesh.positions.size());
    std::uint32_t ids = 0;
    for (std::size_t i = 0; i < order.size(); ++i) {
        if (i > 0 && key(order[i]) != key(order[i - 1]))
            ++ids;
        weld[order[i]] = ids;
    }
    ++ids;
    // Directed edges: each once, each with its reverse.
    std::vector<std::uint64_t> edges;
    edges.reserve(3 * mesh.triangles.size());
    for (const glm::uvec3& t : mesh.triangles) {
        const std::uint32_t c[3] = {weld[t.x], weld[t.y], weld[t.z]};
        if (c[0] == c[1] || c[1] == c[2] || c[2] == c[0])
            return false;
        for (int i = 0; i < 3; ++i)
            edges.push_back(std::uint64_t(c[i]) << 32 | c[(i + 1) % 3]);
    }
    std::sort(edges.begin(), edges.end());
    if (std::adjacent_find(edges.begin(), edges.end()) != edges.end())
        return false;
    std::vector<std::uint32_t> parent(ids);
    for (std::uint32_t i = 0; i < ids; ++i)
        parent[i] = i;
    const auto root = [&](std::uint32_t i) {
        while (parent[i] != i)
            i = parent[i] = parent[parent[i]];
        return i;
    };
    for (const std::uint64_t e : edges) {
        const std::uint32_t a = std::uint32_t(e >> 32), b = std::uint32_t(e);
        if (!std::binary_search(edges.begin(), edges.end(), std::uint64_t(b) << 32 | a))
            return false;
        parent[root(a)] = root(b);
    }
    // Each piece's signed volume (divergence theorem: the sum of p0 . (p1 x p2) / 6, about the
    // bounds' centre for precision). Vertices no triangle uses belong to no piece.
    const Bounds b = mesh.bounds();
    const glm::dvec3 centre = 0.5 * (glm::dvec3(b.lo) + glm::dvec3(b.hi));
    std::vector<double> volume(ids, 0.0);
    std::vector<bool> used(ids, false);
    for (const glm::uvec3& t : mesh.triangles) {
        const std::uint32_t piece = root(weld[t.x]);
        used[piece] = true;
        volume[piece] += glm::dot(glm::dvec3(mesh.positions[t.x]) - centre,
                                  glm::cross(glm::dvec3(mesh.positions[t.y]) - centre,
                                             glm::dvec3(mesh.positions[t.z]) - centre));
    }
    for (std::uint32_t i = 0; i < ids; ++i)
        if (used[i] && !(volume[i] > 0.0))
            return false;
    return true;
}

bool degenerateTriangle(const std::vector<glm::vec3>& positions, const glm::uvec3& tri) {
    if (tri.x == tri.y || tri.y == tri.z || tri.z == tri.x)
        return true;
    const glm::dvec3 p0(positions[tri.x]);
    const glm::dvec3 e1 = glm::dvec3(positions[tri.y]) - p0;
    const glm::dvec3 e2 = glm::dvec3(positions[tri.z]) - p0;
    const glm::dvec3 e3 = e2 - e1;
    const double longest2 = std::max({glm::dot(e1, e1), glm::dot(e2, e2), glm::dot(e3, e3)});
    return glm::length(glm::cross(e1, e2)) <= kDegenerateRelArea * longest2;
}

std::vector<glm::uvec3> Mesh::weldedTriangles() const {
    if (weld.empty())
        return triangles;
    std::vector<glm::uvec3> out(triangles.size());
    for (std::size_t t = 0; t < triangles.size(); ++t)
        out[t] = weldedTriangle(t);
    return out;
}

void finalizeMesh(Mesh& mesh, const WeldOptions& weld, const WeldCompatible& compatible) {
    const std::string name = meshName(mesh);
    checkSizes(mesh, name);
    checkValues(mesh, name);
    checkParts(mesh, name);
    if (!(weld.tolerance >= 0.0 && weld.tolerance <= 0.01))
        throw InputError(cat(name, ": weld tolerance ", weld.tolerance,
                             " is not in [0, 0.01] (a fraction of the mesh's size)"));
    weldVertices(mesh, weld, compatible);
    const std::size_t before = mesh.triangles.size();
    const std::size_t droppedBefore = mesh.droppedTriangles;
    dropDegenerate(mesh);
    if (mesh.triangles.empty()) {
        if (mesh.droppedTriangles > droppedBefore)
            throw InputError(
                cat(name, ": has no usable triangles (all ", before, " are degenerate)"));
        throw InputError(cat(name, ": has no usable triangles"));
    }
    computeNormals(mesh);
    computeTangents(mesh);
}

void recomputeFrames(Mesh& mesh) {
    checkValues(mesh, meshName(mesh));
    mesh.normals.clear();
    computeNormals(mesh);
    computeTangents(mesh);
}

void savePly(const Mesh& mesh, const std::filesystem::path& file) {
    const std::string name = file.string();
    checkSizes(mesh, name);
    const std::size_t n = mesh.positions.size();
    const bool hasNormals = mesh.normals.size() == n;
    for (const auto& [key, values] : mesh.attributes) {
        const bool reserved = key == "x" || key == "y" || key == "z" ||
                              (hasNormals && (key == "nx" || key == "ny" || key == "nz")) ||
                              (mesh.hasUv() && (key == "u" || key == "v"));
        const bool token = !key.empty() && std::none_of(key.begin(), key.end(), [](char c) {
            return static_cast<unsigned char>(c) <= ' ' || static_cast<unsigned char>(c) > '~';
        });
        if (reserved || !token)
            throw InputError(
                cat(name, ": attribute '", key, "' cannot be written as a PLY property"));
    }

    std::string header = "ply\nformat binary_little_endian 1.0\ncomment written by spotshell\n";
    header += cat("element vertex ", n, "\n");
    header += "property float x\nproperty float y\nproperty float z\n";
    if (hasNormals)
        header += "property float nx\nproperty float ny\nproperty float nz\n";
    if (mesh.hasUv())
        header += "property float u\nproperty float v\n";
    for (const auto& [key, values] : mesh.attributes)
        header += cat("property float ", key, "\n");
    header += cat("element face ", mesh.triangles.size(), "\n");
    header += "property list uchar int vertex_indices\nend_header\n";

    std::string body;
    const std::size_t floatsPerVertex =
        3 + (hasNormals ? 3 : 0) + (mesh.hasUv() ? 2 : 0) + mesh.attributes.size();
    body.reserve(n * floatsPerVertex * 4 + mesh.triangles.size() * 13);
    for (std::size_t i = 0; i < n; ++i) {
        for (int k = 0; k < 3; ++k)
            appendFloat(body, mesh.positions[i][k]);
        if (hasNormals) {
            for (int k = 0; k < 3; ++k)
                appendFloat(body, mesh.normals[i][k]);
        }
        if (mesh.hasUv()) {
            appendFloat(body, mesh.uvs[i].x);
            appendFloat(body, mesh.uvs[i].y);
        }
        for (const auto& [key, values] : mesh.attributes)
            appendFloat(body, values[i]);
    }
    for (const glm::uvec3& tri : mesh.triangles) {
        body.push_back(3);
        for (int k = 0; k < 3; ++k) {
            if (tri[k] >= n)
                throw InputError(cat(name, ": triangle refers to vertex ", tri[k],
                                     " but there are ", n, " vertices"));
            appendLe32(body, tri[k]);
        }
    }
    writeFileAtomic(file, [&](std::ostream& out) {
        out.write(header.data(), static_cast<std::streamsize>(header.size()));
        out.write(body.data(), static_cast<std::streamsize>(body.size()));
    });
}

Mesh makeSphere(float radius, int rings, int segments) {
    if (!(radius > 0.0f) || !std::isfinite(radius))
        throw InputError(cat("sphere: radius must be positive and finite, got ", radius));
    if (rings < 2 || segments < 3)
        throw InputError(
            cat("sphere: needs at least 2 rings and 3 segments, got ", rings, " and ", segments));
    checkGeneratorSize("sphere", (static_cast<long long>(rings) + 1) *
                                     (static_cast<long long>(segments) + 1));

    // Rows from the north pole (v = 1) to the south pole (v = 0). Each pole is one vertex per
    // segment, at the middle of that segment's u range, so the pole triangles have a proper uv
    // gradient; the quads touching a pole collapse to one triangle, so none is degenerate.
    Mesh mesh;
    mesh.name = "sphere";
    const double pi = std::numbers::pi;
    // The seam (u = 1) takes u = 0's angle and the poles lie exactly on the axis, so that the
    // repeated vertices there have equal positions (the surface is closed: noise::closedOutward).
    auto addVertex = [&](double u, double v) {
        const double theta = pi * (1.0 - v);               // from +y
        const double phi = 2.0 * pi * (u < 1.0 ? u : 0.0); // from +z towards +x
        const bool pole = v == 0.0 || v == 1.0;
        const double sinTheta = pole ? 0.0 : std::sin(theta);
        const double cosTheta = pole ? (v > 0.0 ? 1.0 : -1.0) : std::cos(theta);
        const glm::dvec3 n(sinTheta * std::sin(phi), cosTheta, sinTheta * std::cos(phi));
        mesh.positions.push_back(glm::vec3(n * static_cast<double>(radius)));
        mesh.normals.push_back(glm::vec3(n));
        mesh.uvs.push_back(glm::vec2(static_cast<float>(u), static_cast<float>(v)));
    };
    const auto north = static_cast<std::uint32_t>(mesh.positions.size());
    for (int j = 0; j < segments; ++j)
        addVertex((j + 0.5) / segments, 1.0);
    const auto firstRow = static_cast<std::uint32_t>(mesh.positions.size());
    for (int i = 1; i < rings; ++i) {
        for (int j = 0; j <= segments; ++j)
            addVertex(static_cast<double>(j) / segments, 1.0 - static_cast<double>(i) / rings);
    }
    const auto south = static_cast<std::uint32_t>(mesh.positions.size());
    for (int j = 0; j < segments; ++j)
        addVertex((j + 0.5) / segments, 0.0);

    const auto row = [&](int i, int j) { // ring i in 1..rings-1
        return firstRow + static_cast<std::uint32_t>((i - 1) * (segments + 1) + j);
    };
    for (int j = 0; j < segments; ++j) {
        // Counter-clockwise in uv (u right, v up) is counter-clockwise seen from outside.
        const auto uj = static_cast<std::uint32_t>(j);
        mesh.triangles.push_back({row(1, j), row(1, j + 1), north + uj});
        for (int i = 1; i + 1 < rings; ++i) {
            const std::uint32_t upperLeft = row(i, j), upperRight = row(i, j + 1);
            const std::uint32_t lowerLeft = row(i + 1, j), lowerRight = row(i + 1, j + 1);
            mesh.triangles.push_back({lowerLeft, lowerRight, upperRight});
            mesh.triangles.push_back({lowerLeft, upperRight, upperLeft});
        }
        mesh.triangles.push_back({south + uj, row(rings - 1, j + 1), row(rings - 1, j)});
    }
    finalizeMesh(mesh);
    return mesh;
}

Mesh makeTorus(float majorRadius, float minorRadius, int majorSegments, int minorSegments) {
    if (!std::isfinite(majorRadius) || !std::isfinite(minorRadius) || !(minorRadius > 0.0f) ||
        !(majorRadius > minorRadius))
        throw InputError(cat("torus: radii must be finite with 0 < minor < major, got major ",
                             majorRadius, " and minor ", minorRadius));
    if (majorSegments < 3 || minorSegments < 3)
        throw InputError(cat("torus: needs at least 3 segments each way, got ", majorSegments,
                             " and ", minorSegments));
    checkGeneratorSize("torus", (static_cast<long long>(majorSegments) + 1) *
                                    (static_cast<long long>(minorSegments) + 1));

    // u goes around the y axis, v around the tube; the seams are duplicated so uv stays in [0,1],
    // each copy at its first vertex's angle, so that they have equal positions (the surface is
    // closed: noise::closedOutward).
    Mesh mesh;
    mesh.name = "torus";
    const double pi = std::numbers::pi;
    for (int i = 0; i <= majorSegments; ++i) {
        const double u = static_cast<double>(i) / majorSegments;
        const double phi = 2.0 * pi * static_cast<double>(i % majorSegments) / majorSegments;
        for (int j = 0; j <= minorSegments; ++j) {
            const double v = static_cast<double>(j) / minorSegments;
            const double theta = 2.0 * pi * static_cast<double>(j % minorSegments) / minorSegments;
            const glm::dvec3 n(std::cos(theta) * std::sin(phi), std::sin(theta),
                               std::cos(theta) * std::cos(phi));
            const glm::dvec3 centre(majorRadius * std::sin(phi), 0.0, majorRadius * std::cos(phi));
            mesh.positions.push_back(glm::vec3(centre + n * static_cast<double>(minorRadius)));
            mesh.normals.push_back(glm::vec3(n));
            mesh.uvs.push_back(glm::vec2(static_cast<float>(u), static_cast<float>(v)));
        }
    }
    const auto at = [&](int i, int j) {
        return static_cast<std::uint32_t>(i * (minorSegments + 1) + j);
    };
    for (int i = 0; i < majorSegments; ++i) {
        for (int j = 0; j < minorSegments; ++j) {
            mesh.triangles.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
            mesh.triangles.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
        }
    }
    finalizeMesh(mesh);
    return mesh;
}

Mesh makePlane(float size, int cells) {
    if (!(size > 0.0f) || !std::isfinite(size))
        throw InputError(cat("plane: size must be positive and finite, got ", size));
    if (cells < 1)
        throw InputError(cat("plane: needs at least 1 cell per side, got ", cells));
    checkGeneratorSize("plane",
                       (static_cast<long long>(cells) + 1) * (static_cast<long long>(cells) + 1));

    // u along +x, v along -z: counter-clockwise in uv is then counter-clockwise seen from +y.
    Mesh mesh;
    mesh.name = "plane";
    for (int i = 0; i <= cells; ++i) {
        const double u = static_cast<double>(i) / cells;
        for (int j = 0; j <= cells; ++j) {
            const double v = static_cast<double>(j) / cells;
            mesh.positions.push_back(glm::vec3(static_cast<float>((u - 0.5) * size), 0.0f,
                                               static_cast<float>((0.5 - v) * size)));
            mesh.normals.push_back(glm::vec3(0.0f, 1.0f, 0.0f));
            mesh.uvs.push_back(glm::vec2(static_cast<float>(u), static_cast<float>(v)));
        }
    }
    const auto at = [&](int i, int j) { return static_cast<std::uint32_t>(i * (cells + 1) + j); };
    for (int i = 0; i < cells; ++i) {
        for (int j = 0; j < cells; ++j) {
            mesh.triangles.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
            mesh.triangles.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
        }
    }
    finalizeMesh(mesh);
    return mesh;
}

} // namespace spot::noise
