// Mesh loading, validation and generation: geometric properties with explicit tolerances, exact
// round trips through OBJ and PLY, and one InputError naming the file and the problem for every
// kind of malformed input.
#include <gtest/gtest.h>

#include <bit>
#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <numbers>
#include <set>
#include <string>

#include "noise/error.h"
#include "noise/mesh.h"

namespace spot::noise {
namespace {

static_assert(std::endian::native == std::endian::little, "the binary PLY fixtures are built LE");

const std::filesystem::path kTmp = SPOT_TEST_TMP_DIR;
const std::filesystem::path kSource = SPOT_SOURCE_DIR;
constexpr double kPi = std::numbers::pi;

// ---- helpers -----------------------------------------------------------------------------------

double signedVolume(const Mesh& m) {
    double v = 0.0;
    for (const glm::uvec3& t : m.triangles) {
        const glm::dvec3 a(m.positions[t.x]), b(m.positions[t.y]), c(m.positions[t.z]);
        v += glm::dot(a, glm::cross(b, c)) / 6.0;
    }
    return v;
}

void expectUnitNormals(const Mesh& m, double tol = 1e-5) {
    ASSERT_EQ(m.normals.size(), m.positions.size());
    for (std::size_t i = 0; i < m.normals.size(); ++i)
        ASSERT_NEAR(glm::length(m.normals[i]), 1.0, tol) << "vertex " << i;
}

void expectTangentFrames(const Mesh& m) {
    ASSERT_EQ(m.tangents.size(), m.positions.size());
    for (std::size_t i = 0; i < m.tangents.size(); ++i) {
        ASSERT_NEAR(glm::length(m.tangents[i]), 1.0, 1e-5) << "vertex " << i;
        ASSERT_NEAR(glm::dot(m.tangents[i], m.normals[i]), 0.0, 1e-5) << "vertex " << i;
    }
}

void expectUvInUnitSquare(const Mesh& m) {
    ASSERT_EQ(m.uvs.size(), m.positions.size());
    for (const glm::vec2& uv : m.uvs) {
        ASSERT_GE(uv.x, 0.0f);
        ASSERT_LE(uv.x, 1.0f);
        ASSERT_GE(uv.y, 0.0f);
        ASSERT_LE(uv.y, 1.0f);
    }
}

/// Same triangles in the same order with the same corner positions (and uvs when both have
/// them), whatever the vertex numbering: loaders may split or reorder vertices.
void expectSameGeometry(const Mesh& a, const Mesh& b, float tol = 1e-6f) {
    ASSERT_EQ(a.triangles.size(), b.triangles.size());
    ASSERT_EQ(a.hasUv(), b.hasUv());
    for (std::size_t t = 0; t < a.triangles.size(); ++t) {
        for (int k = 0; k < 3; ++k) {
            const glm::vec3 pa = a.positions[a.triangles[t][k]];
            const glm::vec3 pb = b.positions[b.triangles[t][k]];
            ASSERT_NEAR(glm::length(pa - pb), 0.0f, tol) << "triangle " << t << " corner " << k;
            if (a.hasUv()) {
                const glm::vec2 ua = a.uvs[a.triangles[t][k]];
                const glm::vec2 ub = b.uvs[b.triangles[t][k]];
                ASSERT_NEAR(glm::length(ua - ub), 0.0f, tol) << "triangle " << t;
            }
        }
    }
}

template <typename F> std::string inputErrorOf(F&& f) {
    try {
        f();
    } catch (const InputError& e) {
        return e.what();
    }
    ADD_FAILURE() << "expected an InputError";
    return {};
}

/// The message must name the file and say what is wrong.
template <typename F>
void expectInputError(F&& f, const std::string& file, const std::string& phrase) {
    const std::string message = inputErrorOf(f);
    EXPECT_NE(message.find(file), std::string::npos) << "message: " << message;
    EXPECT_NE(message.find(phrase), std::string::npos)
        << "message: " << message << "\nexpected phrase: " << phrase;
}

template <typename T> void put(std::string& out, T value) {
    char bytes[sizeof(T)];
    std::memcpy(bytes, &value, sizeof(T));
    out.append(bytes, sizeof(T));
}

std::filesystem::path writeTmp(const std::string& fileName, const std::string& bytes) {
    const std::filesystem::path path = kTmp / fileName;
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    return path;
}

/// A square pyramid (5 vertices, 4 sides and a quad base), outward, with uv and two attributes.
Mesh pyramid() {
    Mesh m;
    m.name = "pyramid";
    m.positions = {{-1, 0, -1}, {1, 0, -1}, {1, 0, 1}, {-1, 0, 1}, {0, 1.5f, 0}};
    m.uvs = {{0, 0}, {1, 0}, {1, 1}, {0, 1}, {0.5f, 0.5f}};
    m.triangles = {{0, 1, 2}, {0, 2, 3}, {0, 4, 1}, {1, 4, 2}, {2, 4, 3}, {3, 4, 0}};
    m.attributes["quality"] = {0.5f, 1.5f, -2.0f, 4.0f, 8.25f};
    m.attributes["red"] = {0.0f, 1.0f, 0.2f, 0.4f, 0.6f};
    finalizeMesh(m);
    return m;
}

std::string pyramidAsciiPly() {
    // Base as one quad (fan-triangulated on load), other elements interleaved to be skipped.
    return "ply\n"
           "format ascii 1.0\n"
           "comment pyramid with uv, a float attribute and uchar colour\n"
           "element vertex 5\n"
           "property float x\nproperty float y\nproperty float z\n"
           "property float s\nproperty float t\n"
           "property float quality\n"
           "property uchar red\n"
           "property list uchar int ignored_list\n"
           "element material 2\n"
           "property list uchar float params\n"
           "property int id\n"
           "element face 5\n"
           "property uchar flags\n"
           "property list uchar int vertex_indices\n"
           "element edge 1\n"
           "property int vertex1\nproperty int vertex2\n"
           "end_header\n"
           "-1 0 -1 0 0 0.5 0 0\n"
           "1 0 -1 1 0 1.5 255 2 7 8\n"
           "1 0 1 1 1 -2 51 0\n"
           "-1 0 1 0 1 4 102 1 3\n"
           "0 1.5 0 0.5 0.5 8.25 153 0\n"
           "3 0.5 0.25 1 7\n"
           "0 -1\n"
           "0 4 0 1 2 3\n"
           "1 3 0 4 1\n"
           "0 3 1 4 2\n"
           "0 3 2 4 3\n"
           "0 3 3 4 0\n"
           "0 4\n";
}

// ---- the shipped bunny -------------------------------------------------------------------------

TEST(MeshBunny, LoadsWithExpectedCountsOrientationAndSize) {
    const Mesh m = loadMesh(kSource / "presets/meshes/bunny.ply");
    EXPECT_EQ(m.positions.size(), 1839u);
    // The decimated Stanford bunny has no degenerate triangles by our test.
    EXPECT_EQ(m.droppedTriangles, 0u);
    EXPECT_EQ(m.triangles.size() + m.droppedTriangles, 3674u);
    EXPECT_GT(signedVolume(m), 0.0);
    expectUnitNormals(m);
    EXPECT_FALSE(m.hasUv());
    EXPECT_TRUE(m.tangents.empty());
    const Bounds b = m.bounds();
    EXPECT_NEAR(b.size().y, 0.966, 0.005);
    EXPECT_NEAR(b.lo.y, 0.0, 0.005);
    EXPECT_GT(m.surfaceArea(), 0.0);
}

// ---- generated shapes --------------------------------------------------------------------------

TEST(MeshGenerate, SphereAreaNormalsUvTangents) {
    const float r = 2.0f;
    const Mesh m = makeSphere(r, 64, 128);
    EXPECT_EQ(m.droppedTriangles, 0u);
    EXPECT_NEAR(m.surfaceArea() / (4.0 * kPi * r * r), 1.0, 0.01);
    EXPECT_NEAR(signedVolume(m) / (4.0 / 3.0 * kPi * r * r * r), 1.0, 0.01);
    expectUnitNormals(m);
    expectUvInUnitSquare(m);
    expectTangentFrames(m);
    for (std::size_t i = 0; i < m.positions.size(); ++i) {
        // Outward: the normal is the radial direction; the tangent follows +u around +y.
        EXPECT_GT(glm::dot(m.normals[i], glm::normalize(m.positions[i])), 0.999f);
        if (std::abs(m.normals[i].y) < 0.9f) {
            const float phi = 2.0f * static_cast<float>(kPi) * m.uvs[i].x;
            const glm::vec3 alongU(std::cos(phi), 0.0f, -std::sin(phi));
            EXPECT_GT(glm::dot(m.tangents[i], alongU), 0.99f) << "vertex " << i;
        }
    }
}

TEST(MeshGenerate, TorusAreaVolumeAndFrames) {
    const float major = 1.0f, minor = 0.25f;
    const Mesh m = makeTorus(major, minor, 96, 48);
    EXPECT_EQ(m.droppedTriangles, 0u);
    EXPECT_NEAR(m.surfaceArea() / (4.0 * kPi * kPi * major * minor), 1.0, 0.01);
    EXPECT_NEAR(signedVolume(m) / (2.0 * kPi * kPi * major * minor * minor), 1.0, 0.01);
    expectUnitNormals(m);
    expectUvInUnitSquare(m);
    expectTangentFrames(m);
    const Bounds b = m.bounds();
    EXPECT_NEAR(b.size().y, 2.0f * minor, 1e-4);
    EXPECT_NEAR(b.size().x, 2.0f * (major + minor), 1e-4);
    for (std::size_t i = 0; i < m.positions.size(); ++i) {
        // Outward from the tube's centre circle.
        const glm::vec3 p = m.positions[i];
        const glm::vec3 centre = major * glm::normalize(glm::vec3(p.x, 0.0f, p.z));
        EXPECT_GT(glm::dot(m.normals[i], glm::normalize(p - centre)), 0.999f);
    }
}

TEST(MeshGenerate, PlaneIsExactAndFacesUp) {
    const Mesh m = makePlane(3.0f, 10);
    EXPECT_EQ(m.positions.size(), 121u);
    EXPECT_EQ(m.triangles.size(), 200u);
    EXPECT_NEAR(m.surfaceArea(), 9.0, 1e-9);
    expectUvInUnitSquare(m);
    expectTangentFrames(m);
    for (std::size_t i = 0; i < m.positions.size(); ++i) {
        EXPECT_EQ(m.normals[i], glm::vec3(0, 1, 0));
        EXPECT_NEAR(glm::length(m.tangents[i] - glm::vec3(1, 0, 0)), 0.0f, 1e-6f);
    }
    for (const glm::uvec3& t : m.triangles) {
        // Counter-clockwise seen from +y.
        const glm::vec3 c =
            glm::cross(m.positions[t.y] - m.positions[t.x], m.positions[t.z] - m.positions[t.x]);
        EXPECT_GT(c.y, 0.0f);
    }
    const Bounds b = m.bounds();
    EXPECT_EQ(b.lo, glm::vec3(-1.5f, 0.0f, -1.5f));
    EXPECT_EQ(b.hi, glm::vec3(1.5f, 0.0f, 1.5f));
}

TEST(MeshClosed, GeneratedSolidsAreClosedAndOutward) {
    // The sphere repeats positions at its uv seam and poles, the torus at both seams: welded,
    // every edge pairs up.
    EXPECT_TRUE(closedOutward(makeSphere(1.0f, 12, 24)));
    EXPECT_TRUE(closedOutward(makeTorus(1.0f, 0.35f, 24, 12)));
    // Far from the origin too (the volume is taken about the bounds' centre).
    Mesh moved = makeSphere(0.01f, 8, 16);
    for (glm::vec3& p : moved.positions)
        p += glm::vec3(1.0e4f, -2.0e4f, 3.0e4f);
    EXPECT_TRUE(closedOutward(moved));
    // The shipped bunny is closed; a plane has a boundary.
    EXPECT_TRUE(closedOutward(loadMesh(kSource / "presets/meshes/bunny.ply")));
    EXPECT_FALSE(closedOutward(makePlane(2.0f, 4)));
    EXPECT_FALSE(closedOutward(Mesh{}));
}

TEST(MeshClosed, HolesInsideOutAndNonManifoldEdgesAreNot) {
    const Mesh sphere = makeSphere(1.0f, 12, 24);
    Mesh holed = sphere;
    holed.triangles.erase(holed.triangles.begin() + 40);
    EXPECT_FALSE(closedOutward(holed));
    Mesh flipped = sphere;
    for (glm::uvec3& t : flipped.triangles)
        std::swap(t.y, t.z);
    EXPECT_FALSE(closedOutward(flipped)); // closed, facing in
    Mesh oneFlipped = sphere;
    std::swap(oneFlipped.triangles[7].y, oneFlipped.triangles[7].z);
    EXPECT_FALSE(closedOutward(oneFlipped)); // its edges run the same way as the neighbours'
    // Two pieces: an outward sphere and, apart from it, an inward one.
    Mesh pair = sphere;
    const auto base = std::uint32_t(pair.positions.size());
    for (const glm::vec3& p : flipped.positions)
        pair.positions.push_back(p + glm::vec3(5.0f, 0.0f, 0.0f));
    for (const glm::uvec3& t : flipped.triangles)
        pair.triangles.push_back(t + base);
    EXPECT_FALSE(closedOutward(pair));
    for (std::size_t i = sphere.triangles.size(); i < pair.triangles.size(); ++i)
        std::swap(pair.triangles[i].y, pair.triangles[i].z);
    EXPECT_TRUE(closedOutward(pair)); // both outward
    // A triangle repeated: its edges are shared by three triangles.
    Mesh doubled = sphere;
    doubled.triangles.push_back(doubled.triangles.front());
    EXPECT_FALSE(closedOutward(doubled));
    // A vertex no triangle uses changes nothing.
    Mesh extra = sphere;
    extra.positions.push_back(glm::vec3(9.0f));
    EXPECT_TRUE(closedOutward(extra));
}

TEST(MeshGenerate, BadParametersAreInputErrors) {
    expectInputError([] { makeSphere(1.0f, 1, 8); }, "sphere", "at least 2 rings");
    expectInputError([] { makeSphere(-1.0f, 8, 8); }, "sphere", "radius");
    expectInputError([] { makeTorus(0.5f, 1.0f, 8, 8); }, "torus", "minor < major");
    expectInputError([] { makePlane(1.0f, 0); }, "plane", "at least 1 cell");
    expectInputError([] { makePlane(1.0f, 100000); }, "plane", "more than the limit");
}

// ---- finalizeMesh ------------------------------------------------------------------------------

TEST(MeshFinalize, CubeNormalsPointOutwardAndAreaWeighted) {
    // 8 shared corners, 6 quads: each corner normal is the area-weighted sum of its 3 faces'
    // (two triangles each, of which a corner touches one or two), which points outward.
    const std::string obj = "v -1 -1 -1\nv 1 -1 -1\nv 1 1 -1\nv -1 1 -1\n"
                            "v -1 -1 1\nv 1 -1 1\nv 1 1 1\nv -1 1 1\n"
                            "f 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 3 4 8 7\nf 2 3 7 6\nf 1 5 8 4\n";
    const Mesh m = parseObj(obj, "cube.obj");
    EXPECT_EQ(m.positions.size(), 8u);
    EXPECT_EQ(m.triangles.size(), 12u);
    EXPECT_NEAR(m.surfaceArea(), 24.0, 1e-9);
    EXPECT_NEAR(signedVolume(m), 8.0, 1e-9);
    expectUnitNormals(m);
    for (std::size_t i = 0; i < m.positions.size(); ++i)
        EXPECT_GT(glm::dot(m.normals[i], glm::normalize(m.positions[i])), 0.5f) << i;
}

TEST(MeshFinalize, DropsAndCountsDegenerateTriangles) {
    Mesh m;
    m.name = "degenerate";
    m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {2, 0, 0}, {0, 0, 0}};
    m.triangles = {{0, 1, 2}, {0, 0, 1}, {0, 1, 3}, {0, 4, 2}, {1, 2, 1}};
    finalizeMesh(m);
    EXPECT_EQ(m.droppedTriangles, 4u); // repeated index, collinear, coincident corners, repeated
    ASSERT_EQ(m.triangles.size(), 1u);
    EXPECT_EQ(m.triangles[0], glm::uvec3(0, 1, 2));
    expectUnitNormals(m); // unused vertices get a unit normal too
    EXPECT_NEAR(glm::length(m.normals[0] - glm::vec3(0, 0, 1)), 0.0f, 1e-6f);
}

TEST(MeshFinalize, RenormalizesGivenNormalsAndReplacesBadOnes) {
    Mesh m;
    m.name = "normals";
    m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    m.normals = {{0, 0, 2}, {0, 0, 0}, {NAN, 0, 0}};
    m.triangles = {{0, 1, 2}};
    finalizeMesh(m);
    for (const glm::vec3& n : m.normals)
        EXPECT_NEAR(glm::length(n - glm::vec3(0, 0, 1)), 0.0f, 1e-6f);
}

TEST(MeshFinalize, CollapsedUvStillGivesUnitOrthogonalTangents) {
    // All corners share one uv: no gradient, so any unit vector orthogonal to the normal will do;
    // both signs of n.z go through different branches of the orthonormal-basis construction.
    for (const float z : {1.0f, -1.0f}) {
        Mesh m;
        m.name = "flat_uv";
        m.positions = {{0, 0, 0}, {1, 0, 0}, {0, z, 0}};
        m.uvs = {{0.5f, 0.5f}, {0.5f, 0.5f}, {0.5f, 0.5f}};
        m.triangles = {{0, 1, 2}};
        finalizeMesh(m);
        EXPECT_NEAR(m.normals[0].z, z, 1e-6f);
        expectTangentFrames(m);
    }
}

TEST(MeshFinalize, RejectsBadHandBuiltMeshes) {
    Mesh nan;
    nan.name = "hand.mesh";
    nan.positions = {{0, 0, 0}, {1, NAN, 0}, {0, 1, 0}};
    nan.triangles = {{0, 1, 2}};
    expectInputError([&] { finalizeMesh(nan); }, "hand.mesh", "vertex 1 has a non-finite");
    Mesh range;
    range.name = "hand.mesh";
    range.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    range.triangles = {{0, 1, 3}};
    expectInputError([&] { finalizeMesh(range); }, "hand.mesh",
                     "refers to vertex 3 but there are 3 vertices");
}

// ---- round trips -------------------------------------------------------------------------------

TEST(MeshRoundTrip, ObjKeepsPositionsTrianglesAndUv) {
    const Mesh ref = pyramid();
    std::string obj = "# pyramid\no pyramid\ng sides\nusemtl none\nmtllib none.mtl\ns 1\n";
    for (const glm::vec3& p : ref.positions)
        obj += cat("v ", p.x, " ", p.y, " ", p.z, "\n");
    for (const glm::vec2& uv : ref.uvs)
        obj += cat("vt ", uv.x, " ", uv.y, "\n");
    for (const glm::uvec3& t : ref.triangles)
        obj += cat("f ", t.x + 1, "/", t.x + 1, " ", t.y + 1, "/", t.y + 1, " ", t.z + 1, "/",
                   t.z + 1, "\n");
    obj += "l 1 2\np 3\n";
    const Mesh m = parseObj(obj, "pyramid.obj");
    EXPECT_EQ(m.positions.size(), 5u);
    EXPECT_EQ(m.droppedTriangles, 0u);
    expectSameGeometry(ref, m);
    expectTangentFrames(m);
    EXPECT_NEAR(signedVolume(m), signedVolume(ref), 1e-9);
}

TEST(MeshRoundTrip, ObjSplitsSeamsAndHandlesRelativeIndicesAndCrlf) {
    // A unit square of two triangles with per-face normals given at two corners only, relative
    // indices, CRLF endings and a second uv for the shared corner 1: that corner splits.
    const std::string obj = "v 0 0 0\r\nv 1 0 0\r\nv 1 1 0\r\nv 0 1 0\r\n"
                            "vt 0 0\r\nvt 1 0\r\nvt 1 1\r\nvt 0 1\r\nvt 0.5 0.5\r\n"
                            "vn 0 0 3\r\n"
                            "f -4/1/1 -3/2/1 -2/3\r\n"
                            "f 1/5 3/3 4/4\r\n";
    const Mesh m = parseObj(obj, "seam.obj");
    ASSERT_EQ(m.triangles.size(), 2u);
    EXPECT_EQ(m.positions.size(), 5u); // vertex 1 with uv 1 and with uv 5
    ASSERT_TRUE(m.hasUv());
    EXPECT_EQ(m.uvs[m.triangles[1].x], glm::vec2(0.5f, 0.5f));
    expectUnitNormals(m);
    for (const glm::vec3& n : m.normals)
        EXPECT_NEAR(glm::length(n - glm::vec3(0, 0, 1)), 0.0f, 1e-6f);
}

TEST(MeshRoundTrip, ObjPartialUvMeansNoUv) {
    const std::string obj = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\n"
                            "f 1/1 2/2 3/3\nf 1 3 4\n";
    const Mesh m = parseObj(obj, "partial.obj");
    EXPECT_FALSE(m.hasUv());
    EXPECT_TRUE(m.tangents.empty());
    EXPECT_EQ(m.positions.size(), 4u);
    EXPECT_EQ(m.triangles.size(), 2u);
}

TEST(MeshRoundTrip, ObjLongPolygonIsOneFan) {
    // 300 corners: more than tinyobjloader's 255 per face; must still be one fan of 298.
    const int n = 300;
    std::string obj;
    for (int k = 0; k < n; ++k) {
        const double a = 2.0 * kPi * k / n;
        obj += cat("v ", std::cos(a), " 0 ", -std::sin(a), "\n");
    }
    obj += "f";
    for (int k = 1; k <= n; ++k)
        obj += cat(" ", k);
    obj += "\n";
    const Mesh m = parseObj(obj, "disc.obj");
    ASSERT_EQ(m.triangles.size(), 298u);
    for (std::size_t t = 0; t < m.triangles.size(); ++t)
        EXPECT_EQ(m.positions[m.triangles[t].x], m.positions[m.triangles[0].x]);
    EXPECT_NEAR(m.surfaceArea(), 0.5 * n * std::sin(2.0 * kPi / n), 1e-4);
    EXPECT_GT(m.normals[0].y, 0.999f);
}

TEST(MeshRoundTrip, AsciiPlyKeepsUvAttributesColoursAndSkipsOtherElements) {
    const Mesh ref = pyramid();
    const Mesh m = parsePly(pyramidAsciiPly(), "pyramid.ply");
    EXPECT_EQ(m.positions.size(), 5u);
    expectSameGeometry(ref, m);
    ASSERT_EQ(m.attributes.count("quality"), 1u);
    ASSERT_EQ(m.attributes.count("red"), 1u);
    EXPECT_EQ(m.attributes.size(), 2u); // lists and uv names are not attributes
    for (std::size_t i = 0; i < 5; ++i) {
        EXPECT_EQ(m.attributes.at("quality")[i], ref.attributes.at("quality")[i]);
        EXPECT_NEAR(m.attributes.at("red")[i], ref.attributes.at("red")[i], 1e-6f);
    }
    expectTangentFrames(m);
}

std::string pyramidBinaryPly(bool polygonBase) {
    // Unusual but valid types: double positions, ushort colour, int8 attribute, a list with
    // ushort count and uint indices, an element with a list between vertices and faces.
    const Mesh ref = pyramid();
    std::string ply = "ply\r\nformat binary_little_endian 1.0\r\n"
                      "element vertex 5\r\n"
                      "property float64 x\r\nproperty double y\r\nproperty float64 z\r\n"
                      "property float32 texture_u\r\nproperty float texture_v\r\n"
                      "property ushort green\r\nproperty int8 level\r\n"
                      "element junk 2\r\nproperty list uchar int16 stuff\r\nproperty uint8 k\r\n"
                      "element face " +
                      std::to_string(polygonBase ? 5 : 6) +
                      "\r\n"
                      "property list ushort uint vertex_index\r\n"
                      "end_header\r\n";
    for (std::size_t i = 0; i < 5; ++i) {
        for (int k = 0; k < 3; ++k)
            put<double>(ply, ref.positions[i][k]);
        put<float>(ply, ref.uvs[i].x);
        put<float>(ply, ref.uvs[i].y);
        put<std::uint16_t>(ply, static_cast<std::uint16_t>(i * 10000));
        put<std::int8_t>(ply, static_cast<std::int8_t>(-static_cast<int>(i)));
    }
    put<std::uint8_t>(ply, 2);
    put<std::int16_t>(ply, 1);
    put<std::int16_t>(ply, 2);
    put<std::uint8_t>(ply, 9);
    put<std::uint8_t>(ply, 0);
    put<std::uint8_t>(ply, 9);
    std::size_t first = 0;
    if (polygonBase) {
        put<std::uint16_t>(ply, 4);
        for (std::uint32_t v : {0u, 1u, 2u, 3u})
            put<std::uint32_t>(ply, v);
        first = 2;
    }
    for (std::size_t t = first; t < ref.triangles.size(); ++t) {
        put<std::uint16_t>(ply, 3);
        for (int k = 0; k < 3; ++k)
            put<std::uint32_t>(ply, ref.triangles[t][k]);
    }
    return ply;
}

TEST(MeshRoundTrip, BinaryPlyWithUnusualTypes) {
    const Mesh ref = pyramid();
    for (const bool polygonBase : {false, true}) {
        const Mesh m = parsePly(pyramidBinaryPly(polygonBase), "pyramid_bin.ply");
        expectSameGeometry(ref, m);
        EXPECT_NEAR(m.attributes.at("green")[3], 30000.0f / 65535.0f, 1e-6f);
        EXPECT_EQ(m.attributes.at("level")[4], -4.0f);
        EXPECT_EQ(m.attributes.count("stuff"), 0u);
    }
}

TEST(MeshRoundTrip, SavePlyThenLoadReproducesTheMesh) {
    const Mesh ref = pyramid();
    const std::filesystem::path file = kTmp / "saved_pyramid.ply";
    savePly(ref, file);
    const Mesh m = loadMesh(file);
    ASSERT_EQ(m.positions.size(), ref.positions.size());
    ASSERT_EQ(m.triangles, ref.triangles);
    EXPECT_EQ(m.positions, ref.positions);
    EXPECT_EQ(m.uvs, ref.uvs);
    EXPECT_EQ(m.attributes, ref.attributes);
    for (std::size_t i = 0; i < m.normals.size(); ++i) {
        EXPECT_NEAR(glm::length(m.normals[i] - ref.normals[i]), 0.0f, 1e-6f);
        EXPECT_NEAR(glm::length(m.tangents[i] - ref.tangents[i]), 0.0f, 1e-5f);
    }
    // A generated mesh survives too, and loadMesh matches the extension case-insensitively.
    const Mesh torus = makeTorus(1.0f, 0.3f, 12, 8);
    const std::filesystem::path upper = kTmp / "TORUS.PLY";
    savePly(torus, upper);
    const Mesh back = loadMesh(upper);
    EXPECT_EQ(back.positions, torus.positions);
    EXPECT_EQ(back.triangles, torus.triangles);
    EXPECT_EQ(back.uvs, torus.uvs);
}

TEST(MeshRoundTrip, ObjFromFile) {
    const std::filesystem::path file =
        writeTmp("quad.OBJ", "v 0 0 0\nv 2 0 0\nv 2 0 -2\nv 0 0 -2\nf 1 2 3 4\n");
    const Mesh m = loadMesh(file);
    EXPECT_EQ(m.triangles.size(), 2u);
    EXPECT_NEAR(m.surfaceArea(), 4.0, 1e-9);
    EXPECT_EQ(m.name, file.string());
}

// ---- malformed input ---------------------------------------------------------------------------

std::string plyHeader(const std::string& format, const std::string& elements) {
    return "ply\nformat " + format + " 1.0\n" + elements + "end_header\n";
}

const std::string kTriangleElements = "element vertex 3\nproperty float x\nproperty float y\n"
                                      "property float z\nelement face 1\n"
                                      "property list uchar int vertex_indices\n";

std::string binaryTriangle(float x0, int index2) {
    std::string ply = plyHeader("binary_little_endian", kTriangleElements);
    for (float v : {x0, 0.0f, 0.0f, 1.0f, 0.0f, 0.0f, 0.0f, 1.0f, 0.0f})
        put<float>(ply, v);
    put<std::uint8_t>(ply, 3);
    for (int i : {0, 1, index2})
        put<std::int32_t>(ply, i);
    return ply;
}

TEST(MeshBadInput, ValidBaselinesParse) {
    EXPECT_EQ(parsePly(binaryTriangle(0.0f, 2), "x.ply").triangles.size(), 1u);
    EXPECT_EQ(parseObj("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "x.obj").triangles.size(), 1u);
}

TEST(MeshBadInput, NonFiniteCoordinates) {
    expectInputError([] { parsePly(binaryTriangle(NAN, 2), "nan.ply"); }, "nan.ply",
                     "vertex 0 has a non-finite coordinate");
    expectInputError([] { parsePly(binaryTriangle(INFINITY, 2), "inf.ply"); }, "inf.ply",
                     "non-finite coordinate");
    expectInputError(
        [] {
            parsePly(plyHeader("ascii", kTriangleElements) + "0 0 0\n1 nan 0\n0 1 0\n3 0 1 2\n",
                     "nan_ascii.ply");
        },
        "nan_ascii.ply", "vertex 1 has a non-finite coordinate");
    expectInputError([] { parseObj("v 0 0 0\nv 1 nan 0\nv 0 1 0\nf 1 2 3\n", "nan.obj"); },
                     "nan.obj", "vertex 2 has a non-finite coordinate");
    expectInputError([] { parseObj("v 0 0 1e999\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "big.obj"); },
                     "big.obj", "non-finite coordinate");
    expectInputError([] { parseObj("v 0 0 1e39\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "big.obj"); },
                     "big.obj", "non-finite coordinate"); // beyond float
    expectInputError([] { parseObj("v 0 0 0\nvt inf 0\nf 1/1 1/1 1/1\n", "uv.obj"); }, "uv.obj",
                     "not finite");
}

TEST(MeshBadInput, IndexOutOfRange) {
    expectInputError([] { parsePly(binaryTriangle(0.0f, 9001), "range.ply"); }, "range.ply",
                     "face 0 refers to vertex 9001 but there are 3 vertices");
    expectInputError([] { parsePly(binaryTriangle(0.0f, -1), "neg.ply"); }, "neg.ply",
                     "refers to vertex -1");
    const std::string v = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
    expectInputError([&] { parseObj(v + "f 1 2 4\n", "pos.obj"); }, "pos.obj",
                     "line 4: face refers to vertex 4 but there are 3 vertices");
    expectInputError([&] { parseObj(v + "f -1 -2 -4\n", "neg.obj"); }, "neg.obj",
                     "face refers to vertex -4 but there are 3 vertices");
    expectInputError([&] { parseObj(v + "f 0 1 2\n", "zero.obj"); }, "zero.obj",
                     "indices start at 1");
    expectInputError([&] { parseObj(v + "f 1/1 2/1 3/1\n", "vt.obj"); }, "vt.obj",
                     "refers to texture coordinate 1 but there are 0");
    expectInputError([&] { parseObj(v + "f 1//2 2//2 3//2\n", "vn.obj"); }, "vn.obj",
                     "refers to normal 2");
    expectInputError([&] { parseObj(v + "f 1 2 99999999999999999999\n", "huge.obj"); }, "huge.obj",
                     "is not an index");
    expectInputError([&] { parseObj(v + "f 1 2 4294967297\n", "wrap.obj"); }, "wrap.obj",
                     "refers to vertex 4294967297");
    expectInputError([&] { parseObj("f 1 2 3\nv 0 0 0\nv 1 0 0\nv 0 1 0\n", "early.obj"); },
                     "early.obj", "but there are 0 vertices");
}

/// Runs `f` expecting an InputError, and checks it came back quickly (no allocation or loop
/// sized from the bogus count).
template <typename F>
void expectFastInputError(F&& f, const std::string& file, const std::string& phrase) {
    const auto start = std::chrono::steady_clock::now();
    expectInputError(f, file, phrase);
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    EXPECT_LT(seconds, 0.5);
}

TEST(MeshBadInput, HugeDeclaredCountsFailFast) {
    const std::string rest = "property float x\nproperty float y\nproperty float z\n"
                             "element face 1\nproperty list uchar int vertex_indices\n";
    expectFastInputError(
        [&] {
            parsePly(plyHeader("binary_little_endian", "element vertex 4000000000\n" + rest),
                     "huge.ply");
        },
        "huge.ply", "header declares 4000000000 vertices, more than the limit 20000000");
    expectFastInputError(
        [&] {
            parsePly(plyHeader("ascii", "element vertex 99999999999999999999999\n" + rest),
                     "huger.ply");
        },
        "huger.ply", "more than the limit");
    // Within the limit, but the data cannot hold it.
    expectFastInputError(
        [&] {
            parsePly(plyHeader("binary_little_endian", "element vertex 19000000\n" + rest) +
                         std::string(1200, '\0'),
                     "short.ply");
        },
        "short.ply", "truncated: header declares 19000000 vertices but the data can hold at most");
    expectFastInputError(
        [&] {
            parsePly(plyHeader("binary_little_endian",
                               "element vertex 3\nproperty float x\nproperty float y\n"
                               "property float z\nelement face 39000000\n"
                               "property list uchar int vertex_indices\n") +
                         std::string(100, '\0'),
                     "faces.ply");
        },
        "faces.ply", "truncated: header declares 39000000 faces");
    // An ignored element with a huge count and a property costs as much data as it claims.
    expectFastInputError(
        [&] {
            parsePly(plyHeader("binary_little_endian",
                               "element junk 18446744073709551615\nproperty uchar a\n" +
                                   kTriangleElements),
                     "junk.ply");
        },
        "junk.ply", "truncated");
    MeshLimits small;
    small.maxTriangles = 2;
    expectFastInputError(
        [&] { parseObj("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 3 4 1 2\n", "t.obj", small); },
        "t.obj", "limit of 2 triangles");
    small.maxVertices = 2;
    expectFastInputError([&] { parseObj("v 0 0 0\nv 1 0 0\nv 0 1 0\n", "v.obj", small); }, "v.obj",
                         "limit of 2 vertices");
    small.maxFileBytes = 10;
    expectFastInputError([&] { parseObj("v 0 0 0\nv 1 0 0\n", "b.obj", small); }, "b.obj",
                         "more than the limit of 10");
}

TEST(MeshBadInput, TruncatedData) {
    // Binary: the bunny cut in the middle of its faces, and in the middle of its vertices.
    const std::filesystem::path bunny = kSource / "presets/meshes/bunny.ply";
    std::ifstream in(bunny, std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    ASSERT_GT(bytes.size(), 60000u);
    const std::filesystem::path cut = writeTmp("cut_bunny.ply", bytes.substr(0, bytes.size() - 7));
    expectInputError([&] { loadMesh(cut); }, "cut_bunny.ply", "truncated");
    const std::filesystem::path cutVertices = writeTmp("cut_vertices.ply", bytes.substr(0, 1000));
    expectInputError([&] { loadMesh(cutVertices); }, "cut_vertices.ply",
                     "truncated: header declares 1839 vertices");
    // A binary face list cut after its count.
    std::string ply = binaryTriangle(0.0f, 2);
    expectInputError([&] { parsePly(ply.substr(0, ply.size() - 6), "cutlist.ply"); }, "cutlist.ply",
                     "truncated");
    // Ascii: one vertex line missing, and the last face cut short.
    expectInputError(
        [] {
            parsePly(plyHeader("ascii", kTriangleElements) + "0 0 0\n1 0 0\n3 0 1 2\n",
                     "short_ascii.ply");
        },
        "short_ascii.ply", "truncated");
    expectInputError(
        [] {
            parsePly(plyHeader("ascii", kTriangleElements) + "0 0 0\n1 0 0\n0 1 0\n3 0 1\n",
                     "short_face.ply");
        },
        "short_face.ply", "truncated");
}

TEST(MeshBadInput, HeaderProblems) {
    expectInputError([] { parsePly(plyHeader("binary_big_endian", kTriangleElements), "be.ply"); },
                     "be.ply", "binary_big_endian PLY is not supported");
    expectInputError(
        [] { parsePly(plyHeader("binary_middle_endian", kTriangleElements), "fmt.ply"); },
        "fmt.ply", "unknown format 'binary_middle_endian'");
    expectInputError([] { parsePly("ply\nelement vertex 1\nend_header\n", "nofmt.ply"); },
                     "nofmt.ply", "element before the format line");
    expectInputError(
        [] {
            parsePly(plyHeader("ascii", "element point 1\nproperty float x\n") + "1\n",
                     "novertex.ply");
        },
        "novertex.ply", "has no vertex element");
    expectInputError(
        [] {
            parsePly(plyHeader("ascii", "element vertex 3\nproperty float x\nproperty float y\n"
                                        "property float z\n") +
                         "0 0 0\n1 0 0\n0 1 0\n",
                     "noface.ply");
        },
        "noface.ply", "has no face element");
    expectInputError(
        [] {
            parsePly(plyHeader("ascii", "element face 1\nproperty list uchar int vertex_indices\n"
                                        "element vertex 3\nproperty float x\nproperty float y\n"
                                        "property float z\n") +
                         "3 0 1 2\n0 0 0\n1 0 0\n0 1 0\n",
                     "order.ply");
        },
        "order.ply", "face element comes before the vertex element");
    expectInputError(
        [] {
            parsePly(plyHeader("ascii", "element vertex 1\nproperty float x\nproperty float y\n"
                                        "element face 0\nproperty list uchar int vertex_indices\n"),
                     "noz.ply");
        },
        "noz.ply", "no scalar 'z' property");
    expectInputError([] { parsePly("solid cube\nendsolid\n", "stl.ply"); }, "stl.ply",
                     "not a PLY file");
    expectInputError([] { parsePly("ply\nformat ascii 1.0\nelement vertex 3\n", "open.ply"); },
                     "open.ply", "no end_header");
    expectInputError(
        [] { parsePly(plyHeader("ascii", "element vertex 3\nproperty quad x\n"), "type.ply"); },
        "type.ply", "unknown property type 'quad'");
    expectInputError(
        [] { parsePly(plyHeader("ascii", "element vertex -3\nproperty float x\n"), "neg.ply"); },
        "neg.ply", "negative element count");
    expectInputError(
        [] {
            parsePly(plyHeader("ascii", "element vertex 3\nproperty float x\nproperty float x\n"),
                     "dup.ply");
        },
        "dup.ply", "declared twice");
    expectInputError([] { parsePly(plyHeader("ascii", "bogus line\n"), "kw.ply"); }, "kw.ply",
                     "unknown header keyword 'bogus'");
    expectInputError(
        [] {
            parsePly(plyHeader("ascii", "element vertex 3\nproperty float x\nproperty float y\n"
                                        "property float z\nelement face 1\n"
                                        "property list float int vertex_indices\n"),
                     "lf.ply");
        },
        "lf.ply", "count type must be an integer type");
}

TEST(MeshBadInput, AbsurdListCountsAndBadValues) {
    std::string ply =
        plyHeader("binary_little_endian", "element vertex 3\nproperty float x\nproperty float y\n"
                                          "property float z\nelement face 1\n"
                                          "property list uint int vertex_indices\n");
    for (float v : {0.0f, 0.0f, 0.0f, 1.0f, 0.0f, 0.0f, 0.0f, 1.0f, 0.0f})
        put<float>(ply, v);
    put<std::uint32_t>(ply, 4000000000u);
    put<std::int32_t>(ply, 0);
    expectFastInputError([&] { parsePly(ply, "list.ply"); }, "list.ply",
                         "face 0 has a list of 4000000000 'vertex_indices' items, more than the "
                         "remaining data can hold");
    const std::string header = "element vertex 3\nproperty float x\nproperty float y\n"
                               "property float z\nelement face 1\n"
                               "property list int int vertex_indices\n";
    expectInputError(
        [&] { parsePly(plyHeader("ascii", header) + "0 0 0 1 0 0 0 1 0 -3 0 1 2\n", "n.ply"); },
        "n.ply", "negative list count");
    expectInputError(
        [&] { parsePly(plyHeader("ascii", header) + "0 0 0 1 0 zero 0 1 0 3 0 1 2\n", "w.ply"); },
        "w.ply", "vertex 1 property 'z': 'zero' is not a valid float");
    expectInputError(
        [] {
            parsePly(plyHeader("ascii", "element vertex 3\nproperty float x\nproperty float y\n"
                                        "property float z\nelement face 1\n"
                                        "property list uchar int vertex_indices\n") +
                         "0 0 0 1 0 0 0 1 0 300 0 1 2\n",
                     "u.ply");
        },
        "u.ply", "'300' is not a valid uchar");
    expectInputError([] { parseObj("v 1 2 three\n", "word.obj"); }, "word.obj",
                     "line 1: coordinate 'three' is not a number");
    expectInputError([] { parseObj("v 1 2\n", "two.obj"); }, "two.obj", "needs 3 coordinates");
    expectInputError([] { parseObj("v 0 0 0\nv 1 0 0\nf 1 2\n", "line.obj"); }, "line.obj",
                     "a face needs at least 3");
    expectInputError([] { parseObj("v 0 0 0\nf 1/2/3/4 1 1\n", "slash.obj"); }, "slash.obj",
                     "too many '/'");
    expectInputError([] { parseObj(std::string("v 0 0 0\0\n", 9), "nul.obj"); }, "nul.obj",
                     "NUL byte");
}

TEST(MeshBadInput, FilesAndEmptyInput) {
    expectInputError([] { loadMesh(kTmp / "does_not_exist.ply"); }, "does_not_exist.ply",
                     "no such file");
    const std::filesystem::path empty = writeTmp("empty.ply", "");
    expectInputError([&] { loadMesh(empty); }, "empty.ply", "file is empty");
    const std::filesystem::path emptyObj = writeTmp("empty.obj", "");
    expectInputError([&] { loadMesh(emptyObj); }, "empty.obj", "file is empty");
    const std::filesystem::path comments = writeTmp("comments.obj", "# nothing\n\n");
    expectInputError([&] { loadMesh(comments); }, "comments.obj", "has no usable triangles");
    const std::filesystem::path stl = writeTmp("model.stl", "solid x\n");
    expectInputError([&] { loadMesh(stl); }, "model.stl", "unknown mesh format '.stl'");
}

TEST(MeshBadInput, OnlyDegenerateTriangles) {
    expectInputError([] { parseObj("v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\nf 1 1 2\n", "flat.obj"); },
                     "flat.obj", "has no usable triangles (all 2 are degenerate)");
    expectInputError(
        [] {
            parsePly(plyHeader("ascii", kTriangleElements) + "0 0 0\n0 0 0\n0 0 0\n3 0 1 2\n",
                     "point.ply");
        },
        "point.ply", "has no usable triangles");
}

// ---- welding (docs/design.md section 1, "Welding") ---------------------------------------------

/// A flat-shaded box of half sizes (a, b, c) as an exporter writes it: every face with its own
/// normal ("vn" per face), so each corner is split into 3 vertices; with `uv`, each face also has
/// its own uv square (a seam along every edge).
std::string flatBoxObj(float a, float b, float c, bool uv) {
    std::string obj;
    for (int i = 0; i < 8; ++i)
        obj += cat("v ", (i & 1) ? a : -a, " ", (i & 2) ? b : -b, " ", (i & 4) ? c : -c, "\n");
    obj += "vn -1 0 0\nvn 1 0 0\nvn 0 -1 0\nvn 0 1 0\nvn 0 0 -1\nvn 0 0 1\n";
    if (uv)
        obj += "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n";
    // Faces counter-clockwise from outside: (corners, normal).
    const int faces[6][5] = {{1, 5, 7, 3, 1}, {2, 4, 8, 6, 2}, {1, 2, 6, 5, 3},
                             {3, 7, 8, 4, 4}, {1, 3, 4, 2, 5}, {5, 6, 8, 7, 6}};
    for (const auto& f : faces) {
        obj += "f";
        for (int k = 0; k < 4; ++k)
            obj += uv ? cat(" ", f[k], "/", k + 1, "/", f[4]) : cat(" ", f[k], "//", f[4]);
        obj += "\n";
    }
    return obj;
}

TEST(MeshWeld, SplitCornersOfAFlatBoxAreWeldedWithOneAngleWeightedNormal) {
    // A box 4 x 2 x 1: each corner's three faces meet at right angles, so the angle-weighted
    // normal is the diagonal (1, 1, 1)/sqrt 3 whatever the faces' sizes (area weighting would
    // lean towards the largest face).
    const Mesh m = parseObj(flatBoxObj(2.0f, 1.0f, 0.5f, false), "box.obj");
    ASSERT_EQ(m.positions.size(), 24u); // 8 corners x 3 faces
    ASSERT_EQ(m.weld.size(), 24u);
    EXPECT_TRUE(m.weldReport.on);
    EXPECT_EQ(m.weldReport.welded, 8u);
    EXPECT_EQ(m.weldReport.shared, 8u);
    EXPECT_EQ(m.weldReport.refused, 0u);
    EXPECT_GT(m.weldReport.tolerance, 0.0);
    std::set<std::uint32_t> kept;
    for (std::uint32_t v = 0; v < 24; ++v) {
        const std::uint32_t w = m.weld[v];
        kept.insert(w);
        EXPECT_LE(w, v);
        EXPECT_EQ(m.weld[w], w);
        EXPECT_EQ(m.positions[v], m.positions[w]);
        EXPECT_EQ(m.normals[v], m.normals[w]) << v;
        const glm::vec3 diagonal = glm::sign(m.positions[v]) / std::sqrt(3.0f);
        EXPECT_NEAR(glm::length(m.normals[v] - diagonal), 0.0f, 1e-6f) << v;
    }
    EXPECT_EQ(kept.size(), 8u);
    // The welded triangles use the 8 kept vertices only, each triangle's three distinct.
    for (std::size_t t = 0; t < m.triangles.size(); ++t) {
        const glm::uvec3 w = m.weldedTriangle(t);
        EXPECT_TRUE(kept.count(w.x) && kept.count(w.y) && kept.count(w.z));
        EXPECT_TRUE(w.x != w.y && w.y != w.z && w.x != w.z);
    }
    EXPECT_TRUE(closedOutward(m));
}

TEST(MeshWeld, OffKeepsEveryCopyAndItsOwnNormal) {
    WeldOptions off;
    off.on = false;
    const Mesh m = parseObj(flatBoxObj(2.0f, 1.0f, 0.5f, false), "box.obj", {}, off);
    EXPECT_TRUE(m.weld.empty());
    EXPECT_FALSE(m.weldReport.on);
    EXPECT_EQ(m.weldReport.welded, 24u);
    // Each copy keeps its face's normal (the file's), an axis.
    for (const glm::vec3& n : m.normals)
        EXPECT_NEAR(std::abs(n.x) + std::abs(n.y) + std::abs(n.z), 1.0f, 1e-6f);
    for (std::size_t t = 0; t < m.triangles.size(); ++t)
        EXPECT_EQ(m.weldedTriangle(t), m.triangles[t]);
}

TEST(MeshWeld, ToleranceIsRelativeToTheMeshSize) {
    // Two triangles meeting along an edge whose copies are 1e-7 of the size apart (welded), and
    // the same at 1e-3 (apart: a gap, not a seam); at 1000x the scale, the same.
    for (const float scale : {1.0f, 1000.0f}) {
        for (const float gap : {1e-7f, 1e-3f}) {
            Mesh m;
            m.name = "two";
            m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1 + gap, 0, 0}, {gap, 1, 0},
                           {1, 1, 0}};
            for (glm::vec3& p : m.positions)
                p *= scale;
            m.triangles = {{0, 1, 2}, {3, 5, 4}};
            finalizeMesh(m);
            const bool welded = gap < 1e-5f;
            EXPECT_EQ(m.weldReport.welded, welded ? 4u : 6u) << scale << " " << gap;
            EXPECT_EQ(m.weld[3], welded ? 1u : 3u);
            EXPECT_EQ(m.weld[4], welded ? 2u : 4u);
            if (welded)
                EXPECT_EQ(m.positions[3], m.positions[1]); // the copy takes the kept position
        }
    }
    WeldOptions coarse;
    coarse.tolerance = 1e-2;
    Mesh m;
    m.name = "two";
    m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1.001f, 0, 0}, {0.001f, 1, 0}, {1, 1, 0}};
    m.triangles = {{0, 1, 2}, {3, 5, 4}};
    finalizeMesh(m, coarse);
    EXPECT_EQ(m.weldReport.welded, 4u);
    WeldOptions absurd;
    absurd.tolerance = 0.5;
    expectInputError([&] { finalizeMesh(m, absurd); }, "two", "weld tolerance 0.5");
}

TEST(MeshWeld, CompatibleRefusesPairsAndTheReportSaysWhich) {
    Mesh m;
    m.name = "skins";
    m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
    m.triangles = {{0, 1, 2}, {3, 4, 5}};
    // Vertices 1 and 3 are one position but "move apart"; 2 and 5 may weld.
    finalizeMesh(m, {}, [](std::uint32_t a, std::uint32_t b) { return !(a == 1 && b == 3); });
    EXPECT_EQ(m.weld[3], 3u);
    EXPECT_EQ(m.weld[5], 2u);
    EXPECT_EQ(m.weldReport.welded, 5u);
    EXPECT_EQ(m.weldReport.shared, 2u);
    EXPECT_EQ(m.weldReport.refused, 1u);
    EXPECT_EQ(m.weldReport.refusedA, 1u);
    EXPECT_EQ(m.weldReport.refusedB, 3u);
}

TEST(MeshWeld, SeamCopiesShareTheirTangentUnlessTheirUvTurns) {
    // A plane of two quads along x, its uv cut at x = 1: the right quad's uv continues +u along
    // +x (its copies share the +u direction), then the same with the right quad's uv mirrored
    // (+u along -x: each copy keeps its own).
    for (const bool mirrored : {false, true}) {
        Mesh m;
        m.name = "seam";
        m.positions = {{0, 0, 0}, {1, 0, 0}, {1, 0, -1}, {0, 0, -1},
                       {1, 0, 0}, {2, 0, 0}, {2, 0, -1}, {1, 0, -1}};
        const float a = mirrored ? 1.0f : 0.0f, b = mirrored ? 0.0f : 1.0f;
        m.uvs = {{0, 0}, {1, 0}, {1, 1}, {0, 1}, {a, 0}, {b, 0}, {b, 1}, {a, 1}};
        m.triangles = {{0, 1, 2}, {0, 2, 3}, {4, 5, 6}, {4, 6, 7}};
        finalizeMesh(m);
        EXPECT_EQ(m.weldReport.welded, 6u);
        EXPECT_EQ(m.normals[1], m.normals[4]);
        const float along = glm::dot(m.tangents[1], m.tangents[4]);
        if (mirrored)
            EXPECT_NEAR(along, -1.0f, 1e-6f);
        else
            EXPECT_EQ(m.tangents[1], m.tangents[4]);
        EXPECT_NEAR(m.tangents[4].x, mirrored ? -1.0f : 1.0f, 1e-6f);
    }
}

TEST(MeshWeld, GivenNormalsThatAgreeAreKeptAndHardEdgesAreComputed) {
    // A smooth-shaded box whose corners were given one normal per position (an exporter's uv
    // seam split): kept as given. The flat box's face normals disagree: computed instead.
    std::string obj = flatBoxObj(1.0f, 1.0f, 1.0f, true);
    const Mesh flat = parseObj(obj, "flat.obj");
    for (std::size_t v = 0; v < flat.positions.size(); ++v)
        EXPECT_NEAR(glm::length(flat.normals[v] - glm::sign(flat.positions[v]) / std::sqrt(3.0f)),
                    0.0f, 1e-6f);
    Mesh smooth;
    smooth.name = "smooth";
    smooth.positions = flat.positions;
    smooth.uvs = flat.uvs;
    smooth.triangles = flat.triangles;
    for (const glm::vec3& p : smooth.positions)
        smooth.normals.push_back(glm::normalize(p * glm::vec3(1.0f, 2.0f, 3.0f))); // not diagonal
    finalizeMesh(smooth);
    for (std::size_t v = 0; v < smooth.positions.size(); ++v)
        EXPECT_NEAR(glm::length(smooth.normals[v] -
                                glm::normalize(smooth.positions[v] * glm::vec3(1.0f, 2.0f, 3.0f))),
                    0.0f, 1e-6f);
}

TEST(MeshWeld, DroppedTrianglesAreCountedByReason) {
    Mesh m;
    m.name = "dropped";
    m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {2, 0, 0}, {0, 0, 0}};
    m.triangles = {{0, 1, 2}, {0, 0, 1}, {0, 1, 3}, {4, 0, 2}};
    finalizeMesh(m);
    EXPECT_EQ(m.droppedTriangles, 3u);
    EXPECT_EQ(m.droppedWhy.at("two corners on one vertex"), 1u);
    EXPECT_EQ(m.droppedWhy.at("zero area (corners on a line)"), 1u);
    EXPECT_EQ(m.droppedWhy.at("two corners at one position (welded)"), 1u);
}

TEST(MeshWeld, PlyCopiesAreWeldedToo) {
    // Two triangles of a square, each with its own copies of the diagonal's corners (and its own
    // uv): 6 vertices at 4 positions.
    const std::string ply = "ply\nformat ascii 1.0\nelement vertex 6\nproperty float x\n"
                            "property float y\nproperty float z\nproperty float u\n"
                            "property float v\nelement face 2\n"
                            "property list uchar int vertex_indices\nend_header\n"
                            "0 0 0 0 0\n1 0 0 1 0\n1 1 0 1 1\n0 0 0 0.5 0\n1 1 0 0.5 1\n"
                            "0 1 0 0 1\n3 0 1 2\n3 3 4 5\n";
    const Mesh m = parsePly(ply, "copies.ply");
    EXPECT_EQ(m.weldReport.welded, 4u);
    EXPECT_EQ(m.weldReport.shared, 2u);
    EXPECT_EQ(m.weld[3], 0u);
    EXPECT_EQ(m.weld[4], 2u);
    EXPECT_EQ(m.uvs[3], glm::vec2(0.5f, 0.0f)); // the copies keep their own uv
}

TEST(MeshWeld, GeneratedShapesAreWeldedAtTheirSeamsAndPoles) {
    const Mesh sphere = makeSphere(1.0f, 8, 16);
    // Poles: one vertex per segment each (16 -> 1); the seam: 7 rings of 17 -> 16.
    EXPECT_EQ(sphere.weldReport.welded, 2u + 7u * 16u);
    EXPECT_EQ(sphere.weldReport.shared, 2u + 7u);
    const Mesh unwelded = loadMeshOrGenerated("generated:torus", WeldOptions{false, 1e-5});
    EXPECT_TRUE(unwelded.weld.empty());
}

} // namespace
} // namespace spot::noise
