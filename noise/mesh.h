/// @file mesh.h
/// @brief Triangle meshes: the validated in-memory form, loaders and generated shapes.
///
/// Every loader ends in `finalizeMesh`, so code past this header may assume: finite positions,
/// indices in range, no degenerate triangles (they are dropped and counted by reason), vertices
/// welded by position (`Mesh::weld`: split copies at one position share it exactly, with one
/// normal), unit per-vertex normals (angle-weighted over the welded vertex's triangles when the
/// file had none or its copies disagree), and, when the mesh has uv, per-vertex unit tangents
/// along +u orthogonal to the normal. Units are whatever the file uses ("world units").
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
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

/// How vertices are welded (docs/design.md section 1, "Welding"; scene key "weld").
struct WeldOptions {
    bool on = true;
    /// Vertices closer than this times the bounds' diagonal are at one position.
    double tolerance = 1e-5;
};

/// Whether vertices a and b (a < b), at one position, may also be welded for what moves them: a
/// glTF file's skins and morph targets, a mesh cache's frames. Empty: always.
using WeldCompatible = std::function<bool(std::uint32_t a, std::uint32_t b)>;

/// What welding found (for `spotshell info` and messages).
struct WeldReport {
    bool on = false;
    double tolerance = 0.0;   ///< world units
    std::size_t welded = 0;   ///< vertices after welding (distinct welded vertices)
    std::size_t shared = 0;   ///< positions held by more than one vertex (split vertices)
    /// Positions whose vertices were not all welded because WeldCompatible refused (their skins,
    /// morph targets or frames differ), and the first such pair.
    std::size_t refused = 0;
    std::uint32_t refusedA = 0, refusedB = 0;
};

/// A part of a mesh file: a glTF primitive (its mesh, the node that places it, its material),
/// for choosing what grows fur (scene key "grow") and for `spotshell info`.
struct MeshPart {
    std::string mesh, node; ///< names as the file gives them (may be empty)
    int meshIndex = -1, nodeIndex = -1, primitive = 0;
    int material = -1;  ///< into Mesh::materials, -1: none
    bool grows = true;  ///< false: drawn, but no fur (the scene's "grow" left it out)
    std::size_t triangles = 0; ///< kept (after dropping)
    std::map<std::string, std::size_t> dropped; ///< dropped triangles by reason
};

/// A glTF material's base colour (core glTF 2.0 `pbrMetallicRoughness`), for the `material`
/// field (noise/field.h). The texture is the encoded file (PNG or JPEG) as stored: bytes from
/// the .glb or a data uri, or a path to an external image.
struct MeshMaterial {
    std::string name;
    glm::vec4 baseColorFactor{1.0f}; ///< linear RGBA
    std::shared_ptr<const std::string> textureBytes; ///< embedded; null: none or external
    std::string textureMime;                          ///< image/png, image/jpeg (embedded)
    std::filesystem::path textureFile;                ///< external; empty: none or embedded
    std::string texture;                              ///< what the file calls it, for messages
    int texCoord = 0;                                 ///< TEXCOORD_n the texture reads
    bool repeat = true;                               ///< the sampler wraps (else clamps)
    bool hasTexture() const { return textureBytes != nullptr || !textureFile.empty(); }
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
    /// droppedTriangles by reason ("two corners on one vertex", "zero area", ...), for `info`.
    std::map<std::string, std::size_t> droppedWhy;
    std::string name;                 ///< file name or generator, for messages
    /// Per vertex, the vertex it is welded to: the lowest index at its position (itself when
    /// alone). Empty: not welded (every vertex its own). Welded vertices have equal positions and
    /// normals; uv, tangents and attributes stay per vertex (a uv seam keeps its two uvs).
    std::vector<std::uint32_t> weld;
    WeldReport weldReport;
    /// The file's parts (a glTF file's primitives; empty for OBJ, PLY and generated shapes) and
    /// per triangle its part (empty when `parts` is). Materials are a glTF file's.
    std::vector<MeshPart> parts;
    std::vector<std::uint32_t> trianglePart;
    std::vector<MeshMaterial> materials;

    bool hasUv() const { return !uvs.empty(); }
    std::uint32_t welded(std::uint32_t v) const { return weld.empty() ? v : weld[v]; }
    /// Whether triangle t grows fur (the cells hold only these; every triangle is drawn).
    bool grows(std::size_t t) const {
        return trianglePart.empty() || parts[trianglePart[t]].grows;
    }
    /// The triangles through `welded`: what the shell, the GPU's mesh and the posed normals use,
    /// so that neighbouring triangles share their edges' vertices across uv and normal seams.
    glm::uvec3 weldedTriangle(std::size_t t) const {
        const glm::uvec3 tri = triangles[t];
        return {welded(tri.x), welded(tri.y), welded(tri.z)};
    }
    std::vector<glm::uvec3> weldedTriangles() const;
    Bounds bounds() const;
    double surfaceArea() const;
};

/// A glTF mesh or node named in the scene's "grow" (presets/README.md): a name, with the
/// wildcards * and ? and [...] classes (fnmatch), or an index into the file's meshes or nodes.
struct PartPattern {
    std::string glob; ///< empty: by index
    long index = -1;
    std::string text() const { return glob.empty() ? std::to_string(index) : glob; }
};

/// Which of a glTF file's parts grow fur (scene key "grow"). A part is a primitive of a mesh,
/// placed by a node. With `meshes` or `nodes`, only the parts whose mesh matches `meshes`, or
/// whose node or one of its ancestors matches `nodes`, grow; without either, every part. Then
/// the parts matching `excludeMeshes` or `excludeNodes` (the node or an ancestor) are taken out.
/// Parts that do not grow are still drawn (the opaque base mesh), with no fur.
struct GrowSelection {
    std::vector<PartPattern> meshes, nodes, excludeMeshes, excludeNodes;
    bool chooses() const {
        return !meshes.empty() || !nodes.empty() || !excludeMeshes.empty() ||
               !excludeNodes.empty();
    }
};

/// What a scene asks of its mesh as it loads (scene keys "weld" and "grow").
struct MeshOptions {
    WeldOptions weld;
    GrowSelection grow;
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
Mesh loadMesh(const std::filesystem::path& file, const MeshLimits& limits = {},
              const WeldOptions& weld = {}, const WeldCompatible& compatible = {});

/// A mesh file, or a generated shape named `generated:sphere` (radius 1), `generated:torus`
/// (radii 1 and 0.35) or `generated:plane` (2 x 2 in xz): what scenes and the command line take.
Mesh loadMeshOrGenerated(const std::string& spec, const WeldOptions& weld = {});

/// Parse from memory; `name` is used in messages. These are what the fuzz targets drive.
Mesh parseObj(std::string_view text, const std::string& name, const MeshLimits& limits = {},
              const WeldOptions& weld = {}, const WeldCompatible& compatible = {});
Mesh parsePly(std::string_view bytes, const std::string& name, const MeshLimits& limits = {},
              const WeldOptions& weld = {}, const WeldCompatible& compatible = {});

/// Validate and complete a mesh built by hand or by a parser: checks finiteness and index range
/// (InputError), welds vertices by position (`weld`; `compatible` may refuse a pair), drops
/// degenerate triangles (counted in droppedTriangles and droppedWhy), computes normals
/// (angle-weighted over each welded vertex's triangles) where none were given or a welded
/// vertex's copies were given different ones (a hard edge), renormalizes given ones, computes
/// tangents when uvs are present (shared by welded copies whose own +u directions agree).
void finalizeMesh(Mesh& mesh, const WeldOptions& weld = {}, const WeldCompatible& compatible = {});

/// Whether finalizeMesh drops this triangle at these positions: two corners the same vertex, or
/// an area that is zero relative to its longest edge squared (a mesh cache's frames are compared
/// with it: a frame may collapse a triangle the first keeps).
bool degenerateTriangle(const std::vector<glm::vec3>& positions, const glm::uvec3& tri);

/// After the positions moved (a pose of an animated mesh): checks they are finite (InputError)
/// and recomputes the normals (angle-weighted, over the welded vertices) and tangents, keeping
/// every triangle and the weld.
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
