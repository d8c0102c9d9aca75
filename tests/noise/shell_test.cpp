// The shell's prisms and tetrahedra (noise/shell.h, docs/design.md section 5): the split of
// each prism by the vertex-index rule, and no cracks between adjacent prisms on the bunny.
#include <algorithm>
#include <array>
#include <cstdio>
#include <limits>
#include <map>
#include <set>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "noise/error.h"
#include "noise/mesh.h"
#include "noise/shell.h"

using namespace spot;
using namespace spot::noise;

namespace {

double signedVolume(const ShellMesh& shell, const ShellTetrahedron& tet) {
    const glm::dvec3 a(shell.positions[tet.vertices[0]]), b(shell.positions[tet.vertices[1]]),
        c(shell.positions[tet.vertices[2]]), d(shell.positions[tet.vertices[3]]);
    return glm::dot(glm::cross(b - a, c - a), d - a) / 6.0;
}

using Face = std::array<std::uint32_t, 3>;
Face face(std::uint32_t a, std::uint32_t b, std::uint32_t c) {
    Face f = {a, b, c};
    std::sort(f.begin(), f.end());
    return f;
}

/// The 4 faces of a tetrahedron, each with its vertex indices sorted.
std::array<Face, 4> faces(const ShellTetrahedron& tet) {
    const auto& v = tet.vertices;
    return {face(v[0], v[1], v[2]), face(v[0], v[1], v[3]), face(v[0], v[2], v[3]),
            face(v[1], v[2], v[3])};
}

} // namespace

TEST(Shell, EachPrismSplitsAlongTheDiagonalsRisingFromTheLowerIndex) {
    // A flat triangle with equal normals: a right prism, whose volume is area x thickness, for
    // every order of the same three indices (both windings).
    Mesh m;
    m.name = "one-triangle";
    m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 0}, {0, 0, 0}};
    m.normals = std::vector<glm::vec3>(5, glm::vec3(0, 0, 1));
    // Indices 4, 0, 2 name positions 4 -> (1,0,0) after the swap below, so corners keep their
    // places while their indices' order changes.
    m.positions[4] = m.positions[1];
    const std::vector<glm::uvec3> orders = {{0, 4, 2}, {4, 2, 0}, {2, 0, 4}};
    for (const glm::uvec3 tri : orders) {
        m.triangles = {tri};
        const ShellMesh shell = buildShell(m, 0.25f);
        ASSERT_EQ(shell.tetrahedra.size(), 3u);
        double volume = 0.0;
        for (const ShellTetrahedron& tet : shell.tetrahedra) {
            const double v = signedVolume(shell, tet);
            EXPECT_GT(v, 0.0) << tet.vertices[0] << " " << tet.vertices[1] << " " << tet.vertices[2]
                              << " " << tet.vertices[3];
            volume += v;
        }
        EXPECT_NEAR(volume, 0.5 * 0.25, 1e-7);
        // Side quad (i, j), i < j: its two triangles both hold the diagonal b_i - t_j, and no
        // face holds the other one.
        std::set<std::pair<std::uint32_t, std::uint32_t>> edges;
        for (const ShellTetrahedron& tet : shell.tetrahedra)
            for (int a = 0; a < 4; ++a)
                for (int b = a + 1; b < 4; ++b)
                    edges.insert({std::min(tet.vertices[a], tet.vertices[b]),
                                  std::max(tet.vertices[a], tet.vertices[b])});
        const std::array<std::uint32_t, 3> v = {0, 2, 4};
        for (int i = 0; i < 3; ++i)
            for (int j = i + 1; j < 3; ++j) {
                EXPECT_TRUE(edges.count({v[i], shell.top(v[j])})) << v[i] << "-" << v[j];
                EXPECT_FALSE(edges.count({v[j], shell.top(v[i])})) << v[j] << "-" << v[i];
            }
    }
    m.triangles = {orders[0]};
    EXPECT_THROW(buildShell(m, 0.0f), InputError);
}

TEST(Shell, AdjacentPrismsSplitTheirSharedQuadAlikeOnTheBunny) {
    const Mesh mesh = loadMesh(std::string(SPOT_SOURCE_DIR) + "/presets/meshes/bunny.ply");
    const ShellMesh shell = buildShell(mesh, 0.06f); // about fur.json's cell size
    ASSERT_EQ(shell.tetrahedra.size(), 3 * mesh.triangles.size());
    // Every face of every tetrahedron, counted: a face shared by two tetrahedra (inside a prism,
    // or a side quad's half shared by the two prisms of an edge) appears twice. A crack, two
    // prisms splitting their quad along different diagonals, leaves four side faces that appear
    // once on an edge that two triangles share.
    std::map<Face, int> count;
    for (const ShellTetrahedron& tet : shell.tetrahedra)
        for (const Face& f : faces(tet))
            ++count[f];
    std::map<std::pair<std::uint32_t, std::uint32_t>, int> edgeUse;
    for (const glm::uvec3& t : mesh.triangles)
        for (int e = 0; e < 3; ++e) {
            const std::uint32_t a = t[e], b = t[(e + 1) % 3];
            ++edgeUse[{std::min(a, b), std::max(a, b)}];
        }
    const std::uint32_t n = shell.baseCount;
    std::size_t sharedSideFaces = 0, cracks = 0, overused = 0;
    for (const auto& [f, c] : count) {
        overused += c > 2;
        // A side face has base and top vertices, of exactly two mesh vertices.
        std::set<std::uint32_t> corners;
        int tops = 0;
        for (const std::uint32_t v : f) {
            corners.insert(v % n);
            tops += v >= n;
        }
        if (tops == 0 || tops == 3 || corners.size() != 2)
            continue;
        const std::pair<std::uint32_t, std::uint32_t> edge = {*corners.begin(), *corners.rbegin()};
        const auto it = edgeUse.find(edge);
        ASSERT_NE(it, edgeUse.end());
        if (it->second == 2) {
            sharedSideFaces += c == 2;
            cracks += c != 2;
        }
    }
    EXPECT_EQ(overused, 0u);
    EXPECT_EQ(cracks, 0u) << "side faces on shared edges used by one prism only";
    std::size_t interiorEdges = 0;
    for (const auto& [edge, uses] : edgeUse)
        interiorEdges += uses == 2;
    EXPECT_EQ(sharedSideFaces, 2 * interiorEdges);
    EXPECT_GT(interiorEdges, 5000u);
    std::size_t inverted = 0;
    for (const ShellTetrahedron& tet : shell.tetrahedra)
        inverted += !(signedVolume(shell, tet) > 0.0);
    // Where the vertex normals diverge over a small triangle the extruded prism folds; few do at
    // fur's thickness (131 of 11,022 when measured).
    EXPECT_LT(inverted, shell.tetrahedra.size() / 50);
    std::printf("bunny shell: %zu prisms, %zu tetrahedra, %zu interior edges, %zu tetrahedra "
                "not positively oriented at thickness 0.06\n",
                mesh.triangles.size(), shell.tetrahedra.size(), interiorEdges, inverted);
}

TEST(Shell, RaySegmentsOfAPrismsTetrahedraTileItsChord) {
    // A right prism (flat triangle, equal normals) and random rays: the lengths of the ray's
    // segments in the 3 tetrahedra add up to its chord through the prism, clipped independently
    // by the prism's 5 planes (the slab 0 <= z <= thickness and the triangle's 3 sides). The
    // segments come from the walk's shared source (shaders/spot_tet_walk.h) in double, and in
    // float (the GPU's precision) to float's tolerance.
    Mesh m;
    m.name = "one-triangle";
    m.positions = {{0.0f, 0.0f, 0.0f}, {1.0f, 0.1f, 0.0f}, {0.2f, 0.9f, 0.0f}};
    m.normals = std::vector<glm::vec3>(3, glm::vec3(0, 0, 1));
    m.triangles = {{2, 0, 1}};
    const float thickness = 0.3f;
    const ShellMesh shell = buildShell(m, thickness);
    const ShellWalk walk(shell, ShellWalk::Precision::Double);
    const ShellWalk walkFloat(shell, ShellWalk::Precision::Float);
    std::uint32_t state = 12345u;
    const auto rand01 = [&] {
        state = state * 1664525u + 1013904223u;
        return double(state >> 8) / double(1u << 24);
    };
    int hits = 0;
    for (int r = 0; r < 2000; ++r) {
        const glm::dvec3 o(rand01() * 1.6 - 0.3, rand01() * 1.6 - 0.3, rand01() * 1.2 - 0.45);
        const glm::dvec3 d = glm::normalize(
            glm::dvec3(rand01() - 0.5, rand01() - 0.5, rand01() - 0.5) + glm::dvec3(0, 0, 1e-3));
        double sum = 0.0, sumFloat = 0.0;
        for (std::uint32_t tet = 0; tet < shell.tetrahedra.size(); ++tet) {
            double t0 = 0.0, t1 = 0.0;
            if (walk.segment(tet, o, d, t0, t1))
                sum += t1 - t0;
            if (walkFloat.segment(tet, o, d, t0, t1))
                sumFloat += t1 - t0;
        }
        // The prism's chord.
        double enter = 0.0, exit = std::numeric_limits<double>::infinity();
        const auto clip = [&](glm::dvec3 n, double offset) { // inside: n.x >= offset
            const double num = glm::dot(n, o) - offset, den = glm::dot(n, d);
            if (den == 0.0) {
                if (num < 0.0)
                    exit = -1.0;
                return;
            }
            const double t = -num / den;
            if (den > 0.0)
                enter = std::max(enter, t);
            else
                exit = std::min(exit, t);
        };
        clip({0, 0, 1}, 0.0);
        clip({0, 0, -1}, -double(thickness));
        const glm::dvec3 c[3] = {glm::dvec3(m.positions[2]), glm::dvec3(m.positions[0]),
                                 glm::dvec3(m.positions[1])};
        for (int e = 0; e < 3; ++e) {
            const glm::dvec3 edge = c[(e + 1) % 3] - c[e];
            const glm::dvec3 n = glm::cross(glm::dvec3(0, 0, 1), edge); // inwards for CCW
            clip(n, glm::dot(n, c[e]));
        }
        const double chord = std::max(0.0, exit - enter);
        hits += chord > 0.0;
        EXPECT_NEAR(sum, chord, 1e-9) << "ray " << r;
        // Float: each plane's crossing to a few ulps of the coordinates (about 1), the chord
        // up to 3 segments and 2 rounded ends.
        EXPECT_NEAR(sumFloat, chord, 2e-5) << "ray " << r;
    }
    EXPECT_GT(hits, 200);
}

TEST(Shell, WalkFromInsideCrossesTheSquaresPrismsToTheShellsBoundary) {
    // A flat unit square (2 triangles, normals +z) extruded by 0.3: the shell is the box
    // [0, 1]^2 x [0, 0.3]. A walk as baked_march.comp takes it, from the tetrahedron holding the
    // ray's origin (the eye test) across the faces it leaves into their neighbours: its segments
    // follow each other without a gap, each inside its tetrahedron, and end where the ray leaves
    // the box, whatever prisms and tetrahedra it crosses. In double and in float.
    Mesh m;
    m.name = "square";
    m.positions = {{0.0f, 0.0f, 0.0f}, {1.0f, 0.0f, 0.0f}, {0.0f, 1.0f, 0.0f}, {1.0f, 1.0f, 0.0f}};
    m.normals = std::vector<glm::vec3>(4, glm::vec3(0, 0, 1));
    m.triangles = {{0, 1, 2}, {1, 3, 2}};
    const float thickness32 = 0.3f;
    const double thickness = double(thickness32); // the shell's top, exactly
    const ShellMesh shell = buildShell(m, thickness32);
    std::uint32_t state = 777u;
    const auto rand01 = [&] {
        state = state * 1664525u + 1013904223u;
        return double(state >> 8) / double(1u << 24);
    };
    for (const auto precision : {ShellWalk::Precision::Double, ShellWalk::Precision::Float}) {
        const bool isFloat = precision == ShellWalk::Precision::Float;
        const double tolerance = isFloat ? 2e-5 : 1e-9;
        const ShellWalk walk(shell, precision);
        int crossed = 0; // walks that cross more than one prism
        for (int r = 0; r < 500; ++r) {
            const glm::dvec3 o(0.05 + 0.9 * rand01(), 0.05 + 0.9 * rand01(),
                               thickness * (0.05 + 0.9 * rand01()));
            const glm::dvec3 d =
                glm::normalize(glm::dvec3(rand01() - 0.5, rand01() - 0.5, 0.3 * (rand01() - 0.5)));
            const std::int64_t start = walk.containing(o);
            ASSERT_GE(start, 0) << "ray " << r;
            const std::vector<WalkSegment> segments =
                walk.walk(o, d, std::uint32_t(start), 4u, 1e30, 64);
            ASSERT_FALSE(segments.empty()) << "ray " << r;
            // Where the ray leaves the box.
            double exit = std::numeric_limits<double>::infinity();
            const glm::dvec3 lo(0.0), hi(1.0, 1.0, thickness);
            for (int a = 0; a < 3; ++a) {
                if (d[a] > 0.0)
                    exit = std::min(exit, (hi[a] - o[a]) / d[a]);
                else if (d[a] < 0.0)
                    exit = std::min(exit, (lo[a] - o[a]) / d[a]);
            }
            EXPECT_EQ(segments.front().tIn, 0.0) << "ray " << r;
            std::set<std::uint32_t> prisms;
            for (std::size_t i = 0; i < segments.size(); ++i) {
                const WalkSegment& s = segments[i];
                prisms.insert(shell.tetrahedra[s.tet].triangle);
                EXPECT_LE(s.tIn, s.tOut) << "ray " << r << " segment " << i;
                if (i > 0)
                    EXPECT_EQ(s.tIn, segments[i - 1].tOut) << "ray " << r << " segment " << i;
                double t0 = 0.0, t1 = 0.0;
                if (s.tOut > s.tIn + tolerance && walk.segment(s.tet, o, d, t0, t1)) {
                    EXPECT_NEAR(s.tIn, std::max(t0, s.tIn), tolerance) << "ray " << r;
                    EXPECT_NEAR(s.tOut, t1, tolerance) << "ray " << r << " segment " << i;
                }
            }
            EXPECT_NEAR(segments.back().tOut, exit, tolerance) << "ray " << r;
            crossed += prisms.size() > 1;
        }
        EXPECT_GT(crossed, 50) << (isFloat ? "float" : "double");
        // The mesh ends the walk: a walk cut at t = 0.1 ends there.
        const glm::dvec3 o(0.5, 0.4, 0.15), d(1.0, 0.0, 0.0);
        const std::vector<WalkSegment> cut =
            walk.walk(o, d, std::uint32_t(walk.containing(o)), 4u, 0.1, 64);
        ASSERT_FALSE(cut.empty());
        EXPECT_EQ(cut.back().tOut, isFloat ? double(float(0.1)) : 0.1);
    }
}

TEST(Shell, NeighboursAreSymmetricAndPairEveryInteriorFaceOnTheBunny) {
    const Mesh mesh = loadMesh(std::string(SPOT_SOURCE_DIR) + "/presets/meshes/bunny.ply");
    const ShellMesh shell = buildShell(mesh, 0.06f);
    const auto neighbours = shellNeighbours(shell.tetrahedra);
    ASSERT_EQ(neighbours.size(), shell.tetrahedra.size());
    // Face f of a tetrahedron: the one opposite its vertex f.
    const auto faceOf = [&](std::size_t t, int f) {
        const auto& v = shell.tetrahedra[t].vertices;
        return face(v[std::size_t(f + 1) % 4], v[std::size_t(f + 2) % 4], v[std::size_t(f + 3) % 4]);
    };
    std::map<Face, int> holders;
    for (std::size_t t = 0; t < shell.tetrahedra.size(); ++t)
        for (int f = 0; f < 4; ++f)
            ++holders[faceOf(t, f)];
    const std::uint32_t n = shell.baseCount;
    std::size_t interior = 0, top = 0, base = 0, other = 0;
    for (std::size_t t = 0; t < shell.tetrahedra.size(); ++t)
        for (int f = 0; f < 4; ++f) {
            const Face key = faceOf(t, f);
            const std::int32_t b = neighbours[t][std::size_t(f)];
            int tops = 0;
            for (const std::uint32_t v : key)
                tops += v >= n;
            if (b < 0) {
                // Only the top and base surfaces are boundary on the closed bunny.
                EXPECT_EQ(holders[key], 1) << t << " " << f;
                top += tops == 3;
                base += tops == 0;
                other += tops == 1 || tops == 2;
                continue;
            }
            ++interior;
            EXPECT_EQ(holders[key], 2) << t << " " << f;
            ASSERT_NE(std::size_t(b), t);
            // B holds the same face, and its neighbour across it is A, exactly once.
            int back = 0;
            for (int g = 0; g < 4; ++g)
                if (neighbours[std::size_t(b)][std::size_t(g)] == std::int32_t(t)) {
                    ++back;
                    EXPECT_EQ(faceOf(std::size_t(b), g), key) << t << " " << f;
                }
            EXPECT_EQ(back, 1) << t << " " << f;
        }
    // Every face held twice is paired (interior), every face held once is not.
    std::size_t twice = 0;
    for (const auto& [key, c] : holders)
        twice += c == 2;
    EXPECT_EQ(interior, 2 * twice);
    EXPECT_EQ(top, mesh.triangles.size());
    EXPECT_EQ(base, mesh.triangles.size());
    EXPECT_EQ(other, 0u);
    std::printf("bunny shell: %zu paired faces, %zu top and %zu base boundary faces\n", interior,
                top, base);
}

TEST(Shell, NeighboursOfAnOpenSquareLeaveItsRimOpen) {
    // Two triangles sharing one edge: the side faces on the 4 open edges (2 each) are boundary,
    // the 2 on the shared edge are paired, and each prism pairs its 3 tetrahedra with 2 faces.
    const std::vector<glm::uvec3> triangles = {{0, 2, 1}, {1, 2, 3}};
    const auto tets = shellTetrahedra(triangles, 4);
    const auto neighbours = shellNeighbours(tets);
    int paired = 0, open = 0;
    for (std::size_t t = 0; t < tets.size(); ++t)
        for (int f = 0; f < 4; ++f) {
            int tops = 0;
            for (int i = 1; i < 4; ++i)
                tops += tets[t].vertices[std::size_t(f + i) % 4] >= 4;
            if (neighbours[t][std::size_t(f)] >= 0)
                ++paired;
            else
                open += tops == 1 || tops == 2;
        }
    EXPECT_EQ(paired, 2 * (2 * 2 + 2)); // 2 inner faces per prism, 2 faces on the shared quad
    EXPECT_EQ(open, 4 * 2);
}

namespace {

/// Where the ray o + t d crosses triangle (a, b, c), or -1 (Moller-Trumbore).
double crossTriangle(glm::dvec3 o, glm::dvec3 d, glm::dvec3 a, glm::dvec3 b, glm::dvec3 c) {
    const glm::dvec3 e1 = b - a, e2 = c - a, p = glm::cross(d, e2);
    const double det = glm::dot(e1, p);
    if (det == 0.0)
        return -1.0;
    const glm::dvec3 s = o - a, q = glm::cross(s, e1);
    const double u = glm::dot(s, p) / det, v = glm::dot(d, q) / det;
    return u < 0.0 || v < 0.0 || u + v > 1.0 ? -1.0 : glm::dot(e2, q) / det;
}

} // namespace

// Where vertex normals diverge over a crease, a prism folds: some tetrahedra turn inside out and
// overlap their neighbours (on the bunny at the fur's thickness, 0.0612: over a hundred, at the
// chest, the paws and the base of the ears). A walk that only ever went forward, out through
// the nearest plane it leaves, stepped into a folded tetrahedron the ray does not run through
// and circled among the fold's tetrahedra, without advancing, to the walk's limit (2,048; the
// march's loop guard), which drew bald streaks there. Following the ray's preimage, backward
// through folded tetrahedra (spotTetExit), no walk visits a tetrahedron twice. Rays through
// every folded tetrahedron's centroid, in 6 directions each, walked in float (the GPU's
// precision) from the first entry face (a top face the ray enters) before it.
TEST(Shell, WalksThroughTheBunnysFoldsNeverCircle) {
    const Mesh mesh = loadMesh(std::string(SPOT_SOURCE_DIR) + "/presets/meshes/bunny.ply");
    const ShellMesh shell = buildShell(mesh, 0.0612f);
    const auto neighbours = shellNeighbours(shell.tetrahedra);
    const ShellWalk walk(shell, ShellWalk::Precision::Float);
    const auto corner = [&](std::size_t t, std::size_t i) {
        return glm::dvec3(shell.positions[shell.tetrahedra[t].vertices[i]]);
    };
    const glm::dvec3 directions[] = {{1, 0, 0},  {-1, 0, 0}, {0, 1, 0},
                                     {0, -1, 0}, {0, 0, 1},  {0, 0, -1}};
    std::size_t folded = 0, walks = 0, longest = 0;
    for (std::size_t t = 0; t < shell.tetrahedra.size(); ++t) {
        if (signedVolume(shell, shell.tetrahedra[t]) >= 0.0)
            continue;
        ++folded;
        const glm::dvec3 centroid =
            0.25 * (corner(t, 0) + corner(t, 1) + corner(t, 2) + corner(t, 3));
        for (const glm::dvec3& d : directions) {
            const glm::dvec3 o = centroid - 0.2 * d;
            // The first top face the ray enters, before the centroid.
            double first = 0.2;
            std::uint32_t tet = 0, entry = 4;
            for (std::size_t u = 0; u < shell.tetrahedra.size(); ++u)
                for (std::uint32_t f = 0; f < 4; ++f) {
                    const auto& v = shell.tetrahedra[u].vertices;
                    const std::uint32_t a = v[(f + 1) % 4], b = v[(f + 2) % 4], c = v[(f + 3) % 4];
                    if (neighbours[u][f] >= 0 || std::max({a, b, c}) < shell.baseCount)
                        continue; // inside, or the base
                    const glm::dvec3 pa(shell.positions[a]), pb(shell.positions[b]),
                        pc(shell.positions[c]);
                    glm::dvec3 n = glm::cross(pb - pa, pc - pa);
                    if (glm::dot(n, corner(u, f) - pa) > 0.0)
                        n = -n; // outwards
                    const double hit = crossTriangle(o, d, pa, pb, pc);
                    if (glm::dot(n, d) < 0.0 && hit >= 0.0 && hit < first) {
                        first = hit;
                        tet = std::uint32_t(u);
                        entry = f;
                    }
                }
            if (entry == 4)
                continue; // the centroid is not behind a top face along d
            ++walks;
            const std::vector<WalkSegment> segments = walk.walk(o, d, tet, entry, 1e30, 2048);
            longest = std::max(longest, segments.size());
            std::set<std::uint32_t> seen;
            for (const WalkSegment& s : segments)
                EXPECT_TRUE(seen.insert(s.tet).second)
                    << "the walk through folded tetrahedron " << t << " visits " << s.tet
                    << " twice (" << segments.size() << " tetrahedra walked)";
        }
    }
    std::printf("bunny at 0.0612: %zu folded tetrahedra, %zu walks through them, the longest %zu "
                "tetrahedra\n",
                folded, walks, longest);
    EXPECT_GT(folded, 100u);
    EXPECT_GT(walks, 300u);
    EXPECT_LT(longest, 200u);
}

// A flat-shaded box as exporters write it (each corner split into 3 vertices, one per face, with
// the face's normal): welded, its prisms extrude along one angle-weighted normal per corner and
// pair every side face, so only the top and base surfaces are boundary (no crack along any edge,
// where the walk would stop and the baked renderer draw a black line). Unwelded, each face's
// prisms stand alone: every side face along the 12 edges is boundary, and the tops of two faces
// meeting at an edge part (their top vertices are apart).
TEST(Shell, SplitVerticesOfAFlatBoxWeldIntoOneCracklessShell) {
    std::string obj;
    for (int i = 0; i < 8; ++i)
        obj += cat("v ", (i & 1) ? 1 : -1, " ", (i & 2) ? 0.5 : -0.5, " ", (i & 4) ? 0.25 : -0.25,
                   "\n");
    obj += "vn -1 0 0\nvn 1 0 0\nvn 0 -1 0\nvn 0 1 0\nvn 0 0 -1\nvn 0 0 1\n";
    obj += "f 1//1 5//1 7//1 3//1\nf 2//2 4//2 8//2 6//2\nf 1//3 2//3 6//3 5//3\n"
           "f 3//4 7//4 8//4 4//4\nf 1//5 3//5 4//5 2//5\nf 5//6 6//6 8//6 7//6\n";
    const auto boundary = [](const Mesh& m) {
        const ShellMesh shell = buildShell(m, 0.1f);
        std::size_t open = 0;
        for (const auto& n : shellNeighbours(shell.tetrahedra))
            for (const std::int32_t f : n)
                open += f < 0;
        // The widest gap between the top vertices of one welded position.
        float gap = 0.0f;
        for (std::uint32_t a = 0; a < m.positions.size(); ++a)
            for (std::uint32_t b = 0; b < m.positions.size(); ++b)
                if (m.positions[a] == m.positions[b])
                    gap = std::max(gap, glm::length(shell.positions[shell.top(a)] -
                                                    shell.positions[shell.top(b)]));
        return std::pair<std::size_t, float>(open, gap);
    };
    const Mesh welded = parseObj(obj, "flat-box.obj");
    ASSERT_EQ(welded.positions.size(), 24u);
    const auto [open, gap] = boundary(welded);
    EXPECT_EQ(open, 2 * welded.triangles.size()); // the top and base faces only
    EXPECT_EQ(gap, 0.0f);
    WeldOptions off;
    off.on = false;
    const Mesh split = parseObj(obj, "flat-box.obj", {}, off);
    const auto [splitOpen, splitGap] = boundary(split);
    EXPECT_EQ(splitOpen, 2 * split.triangles.size() + 2 * 12 * 2); // + both sides of 12 edges
    EXPECT_GT(splitGap, 0.1f);
}
