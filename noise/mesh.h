/// @file mesh.h
/// @brief Triangle meshes: the validated in-memory form, loaders and generated shapes.
///
/// Every loader ends in `finalizeMesh`, so code past this header may assume: finite positions,
/// indices in range, no degenerate triangles (they are dropped and counted), unit per-vertex
/// normals (area-weighted when the file had none), and, when the mesh has uv, per-vertex unit
/// tangents along +u orthogonal to the normal. Units are whatever the file uses ("world units").
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <map>
#include <string>
#include <string_view>
#include <vector>

#include <glm/glm.hpp>

namespace spot::noise {

/// Axis-aligned box in world units.
struct Bounds {
    glm::vec3 lo{0.0f};
    glm::vec3 hi{0.0f};
    glm::vec3 size() const { return hi - lo; }
};

struct Mesh {
    std::vector<glm::vec3> positions;  ///< world units
    std::vector<glm::vec3> normals;    ///< unit, one per position
    std::vector<glm::vec2> uvs;        ///< empty, or one per position
    std::vector<glm::vec3> tangents;   ///< empty, or one per position (unit, along +u, _|_ normal)
    std::vector<glm::uvec3> triangles; ///< counter-clockwise seen from outside
    /// Extra per-vertex scalar attributes by name (PLY properties, `red`/`green`/`blue` in [0,1]),
    /// each one value per position. Read by vertex-attribute fields.
    std::map<std::string, std::vector<float>> attributes;
    std::size_t droppedTriangles = 0; ///< degenerate or repeated-index triangles removed on load
    std::string name;                 ///< file name or generator, for messages

    bool hasUv() const { return !uvs.empty(); }
    Bounds bounds() const;
    double surfaceArea() const;
};

/// Whether the mesh's triangles bound solids and face out of them: with vertices welded where
/// their positions are equal (uv seams and poles repeat positions), every edge is shared by
/// exactly two triangles that run it in opposite directions, no triangle has two welded corners,
/// and each connected piece encloses a positive volume (counter-clockwise seen from outside).
/// Then a ray from a point outside every piece meets a triangle's front before any back, so the
/// back faces can be culled without changing what the ray sees first. O(n log n).
bool closedOutward(const Mesh& mesh);

/// Caps checked before anything is allocated from a count read in a file.
struct MeshLimits {
    std::size_t maxVertices = 20'000'000;
    std::size_t maxTriangles = 40'000'000;
    std::uint64_t maxFileBytes = 2ull << 30;
};

/// Load an OBJ or PLY (ascii or binary little-endian) by extension. Throws InputError with the
/// file name and the reason on anything malformed.
Mesh loadMesh(const std::filesystem::path& file, const MeshLimits& limits = {});

/// A mesh file, or a generated shape named `generated:sphere` (radius 1), `generated:torus`
/// (radii 1 and 0.35) or `generated:plane` (2 x 2 in xz): what scenes and the command line take.
Mesh loadMeshOrGenerated(const std::string& spec);

/// Parse from memory; `name` is used in messages. These are what the fuzz targets drive.
Mesh parseObj(std::string_view text, const std::string& name, const MeshLimits& limits = {});
Mesh parsePly(std::string_view bytes, const std::string& name, const MeshLimits& limits = {});

/// Validate and complete a mesh built by hand or by a parser: checks finiteness and index range
/// (InputError), drops degenerate triangles (counted in droppedTriangles), computes missing normals
/// (area-weighted), renormalizes given ones, computes tangents when uvs are present.
void finalizeMesh(Mesh& mesh);

/// Whether finalizeMesh drops this triangle at these positions: two corners the same vertex, or
/// an area that is zero relative to its longest edge squared (a mesh cache's frames are compared
/// with it: a frame may collapse a triangle the first keeps).
bool degenerateTriangle(const std::vector<glm::vec3>& positions, const glm::uvec3& tri);

/// After the positions moved (a pose of an animated mesh): checks they are finite (InputError)
/// and recomputes the normals (area-weighted) and tangents, keeping every triangle.
void recomputeFrames(Mesh& mesh);
/// Write a mesh as binary little-endian PLY (positions, normals, uvs if present, faces), via a
/// temporary file renamed into place.
void savePly(const Mesh& mesh, const std::filesystem::path& file);

/// Generated shapes, already finalized. All have uv.
Mesh makeSphere(float radius, int rings, int segments);
Mesh makeTorus(float majorRadius, float minorRadius, int majorSegments, int minorSegments);
/// A square in the xz plane centred at the origin, normal +y, `cells` quads per side.
Mesh makePlane(float size, int cells);

} // namespace spot::noise
