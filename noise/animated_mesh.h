/// @file animated_mesh.h
/// @brief Meshes that move (docs/design.md section 6): a glTF 2.0 clip or a numbered mesh cache,
/// posed on the CPU at any time. The first part of animated surfaces: what moves, and where every
/// vertex is at time t; the noise is still evaluated on the rest pose (`rest()`), which is what
/// every renderer draws today.
///
/// glTF 2.0 (`.gltf` or `.glb`, read with tinygltf): every triangle primitive of the scene's
/// meshes, merged into one mesh in node order; node hierarchies with TRS animation; skins with
/// JOINTS_0/WEIGHTS_0 and, where present, JOINTS_1/WEIGHTS_1 (linear blend skinning, the weights
/// normalised); morph targets (POSITION deltas, the mesh's weights or the clip's); samplers with
/// LINEAR (slerp for rotations), STEP and CUBICSPLINE interpolation. The rest pose is the bind
/// pose: skinned vertices as stored (every joint at its bind matrix), other meshes placed by
/// their nodes' static transforms, morph weights 0. Times outside a clip clamp to its ends.
///
/// A mesh cache: a printf pattern (`walk.%04d.ply`) over the consecutive frames its folder holds
/// (a gap is an error); every frame must have the first's vertex count and triangles (a frame
/// may collapse a triangle to zero area); the first is the rest pose unless the scene names
/// another frame, and the rest's triangles are the pose's. `pose(t)` interpolates linearly between
/// the frames around t x fps.
///
/// Every pose, on the CPU and on the GPU, is spot_pose.h's formula over PoseInputs: per vertex its
/// base, morph deltas and joints; per time the joint matrices (the palette) and morph weights.
///
/// A pose keeps the rest's topology (no triangle is dropped, even where a pose makes one
/// degenerate); its normals are recomputed (area-weighted) and its tangents carried from the rest.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

#include "noise/mesh.h"
#include "shaders/spot_deform.hpp"

namespace spot::noise {

/// What spot_pose.h reads to pose every vertex at one time: the pose pass's buffers
/// (splat/deform_vk.h), and the CPU's pose.
struct PoseInputs {
    /// The geometry: per vertex its base and joints, per piece its vertices and morph targets.
    std::vector<gpu::SpotDeformVertex> vertices;
    std::vector<gpu::SpotDeformPiece> pieces;
    std::vector<glm::vec4> deltas;
    /// Which geometry the three above hold (a cache's frame pair; 0 for a glTF file, whose
    /// geometry never changes); all ones: none yet.
    std::uint64_t geometry = ~std::uint64_t(0);
    /// The time's: the joint matrices (node world matrices, then each skin's joints times their
    /// inverse bind matrices) and every piece's morph weights.
    std::vector<glm::mat4> palette;
    std::vector<float> weights;

    /// The arrays spot_pose.h reads on the host (shaders/spot_deform.hpp's SharedPoser).
    shared::f32::PoseArrays arrays() const {
        shared::f32::PoseArrays a;
        a.vertices = vertices.data();
        a.pieces = pieces.data();
        a.deltas = deltas.data();
        a.weights = weights.data();
        a.palette = palette.data();
        return a;
    }
};

struct GltfReader;

class AnimatedMesh {
public:
    /// A glTF file's clip `clip` (by name; empty: the first clip, or none when the file has no
    /// animation). Point and line primitives are skipped, triangle strips and fans unrolled.
    /// InputError naming the file and the reason for anything malformed or not supported:
    /// buffers missing or short, an index (accessor, buffer view, joint, vertex) out of range,
    /// a negative joint weight or a skinned vertex whose weights sum to 0, a non-finite number,
    /// key times that go back, no triangles, sparse accessors, an unknown clip.
    /// `options`: the weld (split copies are welded only where their skins and morph targets
    /// agree: Mesh::weldReport counts the positions where they do not) and which parts grow fur.
    static AnimatedMesh loadGltf(const std::filesystem::path& file, const std::string& clip = "",
                                 const MeshLimits& limits = {}, const MeshOptions& options = {});
    /// A mesh cache: `pattern` with one printf integer conversion (`%d`, `%04d`) in its file
    /// name; the frames are the files it names from `first` (the lowest found when negative) to
    /// the highest, with no gap (InputError naming the missing file), played at `fps`;
    /// `restFrame` (an index into the frames found) is the rest pose.
    /// The rest frame is welded only where the copies stay together (within the tolerance) in
    /// every frame, and every frame's welded copies then take their kept vertex's position.
    static AnimatedMesh loadCache(const std::string& pattern, double fps, int first = -1,
                                  int restFrame = 0, const MeshLimits& limits = {},
                                  const WeldOptions& weld = {});
    /// A file by extension: .gltf/.glb as glTF; a name with a '%' as a cache (24 fps); anything
    /// else (a static OBJ/PLY or a generated shape) as a mesh that does not move. A selection of
    /// parts (`options.grow`) is refused for anything but a glTF file.
    static AnimatedMesh load(const std::string& spec, const std::string& clip = "",
                             double fps = 24.0, int restFrame = 0,
                             const MeshOptions& options = {});

    const Mesh& rest() const { return m_rest; }
    bool animated() const { return m_duration > 0.0; }
    /// Seconds from the clip's first key to its last (0: it does not move).
    double duration() const { return m_duration; }
    double start() const { return m_start; }
    const std::string& clipName() const { return m_clipName; }
    const std::vector<std::string>& clipNames() const { return m_clipNames; }
    /// A glTF file's meshes and nodes by name (index order), for `spotshell info`.
    const std::vector<std::string>& meshNames() const { return m_meshNames; }
    const std::vector<std::string>& nodeNames() const { return m_nodeNames; }
    /// The glTF file's version as its asset says ("2.0").
    const std::string& gltfVersion() const { return m_gltfVersion; }
    std::size_t jointCount() const { return m_jointCount; }
    std::size_t morphTargetCount() const { return m_morphTargets; }
    std::size_t frameCount() const { return m_frames.size(); } ///< a cache's frames
    /// The mesh at time t (seconds; clamped to the clip).
    Mesh pose(double t) const;
    /// Its positions only (what `pose` recomputes normals from).
    std::vector<glm::vec3> posePositions(double t) const;
    /// What spot_pose.h reads at time t (clamped to the clip): the palette and the weights, and
    /// the geometry too when `inputs` holds another (a cache's next frame pair, or none yet).
    void poseInputs(double t, PoseInputs& inputs) const { inputsAt(clampTime(t), false, inputs); }
    /// The same at rest (the bind pose).
    void restInputs(PoseInputs& inputs) const { inputsAt(0.0, true, inputs); }
    /// t clamped to the clip (a cache's frames: [0, duration]).
    double clampTime(double t) const;

    /// A glTF animation sampler's value at `t` (exposed for tests). `times` ascending; `values`
    /// holds `width` floats per key (3 times that for CUBICSPLINE: in-tangent, value, out-tangent);
    /// `rotation`: values are quaternions (x, y, z, w) interpolated by slerp and normalised.
    enum class Interpolation { Linear, Step, CubicSpline };
    static std::vector<float> sample(const std::vector<float>& times,
                                     const std::vector<float>& values, int width,
                                     Interpolation interpolation, bool rotation, double t);

    struct Node {
        int parent = -1;
        glm::vec3 translation{0.0f};
        glm::quat rotation{1.0f, 0.0f, 0.0f, 0.0f};
        glm::vec3 scale{1.0f};
        glm::mat4 matrix{1.0f}; ///< a node given by a matrix (then TRS are not animated)
        bool hasMatrix = false;
    };
    struct Channel {
        int node = -1;
        enum class Path { Translation, Rotation, Scale, Weights } path = Path::Translation;
        Interpolation interpolation = Interpolation::Linear;
        std::vector<float> times, values;
    };
    /// A primitive's vertices within the merged mesh and how they move.
    struct Piece {
        std::size_t first = 0, count = 0; ///< its vertices in the merged mesh
        int node = -1;                    ///< the node that instances its mesh
        int skin = -1;
        int mesh = -1;                               ///< its glTF mesh (the morph weights' owner)
        std::vector<glm::vec3> base;                 ///< positions as stored (mesh space)
        std::vector<std::vector<glm::vec3>> targets; ///< morph POSITION deltas, per target
        std::vector<glm::uvec4> joints[2];           ///< JOINTS_0/1 (skin joint indices)
        std::vector<glm::vec4> weights[2];           ///< WEIGHTS_0/1 (normalised together)
    };
    struct Skin {
        std::vector<int> joints;            ///< node per joint
        std::vector<glm::mat4> inverseBind; ///< per joint
    };

private:
    friend struct GltfReader; // builds a glTF file's pieces, skins and clip (animated_mesh.cpp)
    /// Node world matrices at time t (the clip's channels applied; t < start: the rest pose).
    std::vector<glm::mat4> worldMatrices(double t, bool rest) const;
    std::vector<float> morphWeights(int mesh, double t, bool rest) const;
    std::vector<glm::vec3> positionsAt(double t, bool rest) const;
    void inputsAt(double t, bool rest, PoseInputs& inputs) const;
    /// The glTF pieces' SpotDeformVertex/Piece/deltas (after loading).
    void buildPoseGeometry();

    Mesh m_rest;
    std::vector<std::string> m_meshNames, m_nodeNames;
    std::string m_gltfVersion;
    std::string m_clipName;
    std::vector<std::string> m_clipNames;
    double m_start = 0.0, m_duration = 0.0;
    std::size_t m_jointCount = 0, m_morphTargets = 0;
    // glTF
    std::vector<Node> m_nodes;
    std::vector<Channel> m_channels;
    std::vector<Piece> m_pieces;
    std::vector<Skin> m_skins;
    std::vector<std::vector<float>> m_meshWeights; ///< per glTF mesh: its default morph weights
    PoseInputs m_geometry;                         ///< a glTF file's (palette and weights empty)
    std::vector<std::uint32_t> m_skinPalette;      ///< per skin: its first palette entry
    std::vector<std::uint32_t> m_pieceWeights;     ///< per piece: its first morph weight
    std::uint32_t m_weightCount = 0;
    // a mesh cache
    std::vector<std::vector<glm::vec3>> m_frames;
    double m_fps = 24.0;
};

/// The frames an animated mesh's clip spans at `fps`, first to last inclusive. Frame f is at
/// f / fps seconds everywhere (render --frames, info, the editor's timeline, the farm), so a clip
/// from s to s + d seconds spans frames ceil(s fps) to floor((s + d) fps): Blender's frames 1 to
/// 383 for a clip it exported from frame 1 at 24 fps (from 1/24 s). A mesh cache's clip starts at
/// 0: its files are frames 0 to count - 1 at its own rate.
struct FrameRange {
    long first = 0, last = 0;
};
FrameRange clipFrames(const AnimatedMesh& mesh, double fps);

} // namespace spot::noise
