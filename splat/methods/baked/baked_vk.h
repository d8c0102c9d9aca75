/// @file baked_vk.h
/// @brief The `baked` method of docs/design.md section 5: the bake (noise/bake.h) rendered
/// through the mesh's shell of tetrahedra with depth-peeling order-independent transparency.
/// A Renderer of the registry (method_vk.h).
///
/// Per frame, recorded into the caller's command buffer with no host wait:
///  1. shell (compute, baked_shell.comp): per triangle its prism (the mesh extruded along its
///     vertex normals by the shell thickness) split into 3 tetrahedra with noise/shell.h's rule,
///     each with its corners now, its 4 inward face planes and its affine map from world now to
///     rest (the texture coordinate into the bake); and the lowest tetrahedron holding the eye,
///     if any; and the list of the shell's entry faces that face the eye, with the peel's
///     indirect draw. Rebuilt from the mesh's vertices every frame, so an animated mesh's shell
///     follows it. Per mesh, on the host (topology only): each tetrahedron's neighbour across each
///     face (noise::shellNeighbours) and the shell's entry faces, the boundary faces a ray can
///     enter through (the top surface and the sides of open edges; not the base, the mesh), as a
///     mask per triangle.
///  2. mesh (raster): the opaque base mesh's colour, ray distance and depth (MeshPass).
///  3. per layer k = 1..N (RenderSettings::peelPasses): peel (raster, baked_tet.vert and
///     baked_peel.frag): the entry faces that face the eye (one triangle per mesh triangle on a
///     closed mesh), tested against the mesh's depth (z-buffer culling behind the mesh, no
///     depth written) and, after the first, against where layer k-1's walk left the shell, keep
///     per pixel the nearest entry by a 64-bit atomicMax (the same entry in any drawing order),
///     and list each pixel as it gets its first entry (the layer's list, its own header); march
///     (compute, baked_march.comp, dispatched indirectly over the list): from the entry, a walk
///     through the tetrahedra across their shared faces until the ray leaves the shell, reaches
///     the mesh or is opaque, sampling the bake at one spacing for the whole layer (the mip level
///     of the pixel's footprint at the entry) through each tetrahedron's affine map, composited
///     under the earlier layers (front to back) and over the mesh colour into result() (the mesh's
///     colour image: the result as it stands where no layer walks); it writes the walk's exit
///     depth, where the next peel starts (0 once opaque), and clears the pixel's entry for the
///     next peel. So one layer is the ray's whole contiguous passage through the shell, and later
///     layers are re-entries (ears, silhouettes). The first layer starts every pixel at the eye,
///     t = 0, when the eye is inside the shell (the shell pass raises its dispatch to every pixel).
///     A pixel with no entry face before the mesh has none in any layer, so nothing per pixel is
///     cleared but the entries: what a layer reads, an earlier layer's march wrote.
///
/// The bake on the GPU stays sparse: its OpenVDB leaves (8^3 voxels) as bricks in up to 4 storage
/// buffers of one binding's range each (each leaf with a voxel of apron towards +x, +y, +z, 9^3
/// voxels of 8 bytes: half floats), the distance grid's leaves in another (4 bytes a voxel),
/// found through dense leaf tables (one int per leaf of each level's box of leaves, and of the
/// distance grid's: one read, no probing). The march no longer reads the distance grid (its
/// skip, capped at 4 voxels, cost more than it saved; docs/design.md 5); it is still uploaded.
///
/// The loop guard: lavapipe stops an invocation after 65,535 loop iterations, so a layer walks at
/// most kBakedMaxLayerTets tetrahedra and takes at most kBakedMaxLayerSamples samples, prepare()
/// computes the bound one march invocation can run (baked_march.comp's formula) and refuses a
/// frame above the budget (kBakedLoopBudget by default).
///
/// Lit scenes (docs/design.md section 5): the bake's shading grids (noise/bake.h) as shading
/// bricks in buffers of their own (density brick b's at the same place), each sample shaded by
/// spot_light.h's models for every light and the sky, with shadow marches through the bake (a
/// light's at the samples' level, the sky's at the coarsest) stopped by the mesh's solid (its
/// inside voxelized on the host), and the mesh shaded diffuse where a walk reaches it
/// (baked_march.comp's BAKED_LIT modules).
///
/// Limits: perspective cameras, unlit and lit shading (not Lambert: no normals); a passage
/// longer than the per-layer caps, or a walk stopped by a degenerate tetrahedron, leaves the
/// rest of that passage out (the next layer starts at the next entry face behind it); faces of
/// non-manifold edges are boundary (the walk stops there). More layers never make the image
/// worse. Results are deterministic: no float atomics, every pixel independent.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <tuple>
#include <vector>

#include <glm/glm.hpp>

#include "shaders/spot_layout.hpp"
#include "splat/context_vk.h"
#include "splat/method_vk.h"
#include "splat/methods/baked/bake_data.h"
#include "splat/pass_vk.h"

namespace spot::splat {

/// What the last frame used (the stats' FrameCounters::extra gives them to `render --stats`).
struct BakedStats {
    float voxelSize = 0.0f;   ///< level 0's, world units
    std::uint32_t levels = 0; ///< mip levels in the bake
    float thickness = 0.0f;   ///< the shell's, world units
    std::uint32_t tetrahedra = 0;
    std::uint32_t bricks = 0;         ///< density leaves of every level
    std::uint32_t brickBuffers = 0;   ///< storage buffers they are split over
    std::uint32_t distanceBricks = 0; ///< distance leaves
    std::uint32_t entryFaces = 0;     ///< enterable boundary faces (the peel draws eye-facing ones)
    std::uint32_t maxLayerTets = 0;   ///< most tetrahedra one layer walks
    std::uint32_t maxLayerSamples = 0;   ///< most samples one layer takes (skipped ones included)
    std::uint32_t tableEntries = 0;      ///< of the leaf tables (one int per leaf of each box)
    std::uint32_t loopBound = 0;         ///< what one march invocation may run
    std::uint32_t maxLoopIterations = 0; ///< counted (countLoops) in the last frame
    std::uint32_t peelPasses = 0;
    std::int64_t eyeTetrahedron = -1; ///< the one holding the eye in the last frame, -1: none
    std::uint64_t gpuBytes =
        0; ///< the bake's bricks and tables (lit: its shading bricks, the solid)
};

/// Throws InputError, with the reason, when `baked` cannot render `view` (an orthographic camera;
/// Lambert shading, which needs normals the bake does not store). Lit scenes it renders (a bake
/// without shading grids is refused by prepare()).
void requireBakedView(const View& view);

class BakedRenderer final : public Renderer {
public:
    /// `scene` must outlive the renderer.
    explicit BakedRenderer(const SceneGpu& scene);
    ~BakedRenderer() override;

    /// Uploads settings.bake when it is not the one uploaded last (InputError, one line naming
    /// the file, for a bake beyond the storage-buffer or memory limits); reads no file. The shell's
    /// thickness is the impulses' cell size (ImpulseSet::cells; the kernels reach at most one
    /// cell from the surface). InputError for an orthographic camera, Lambert shading, a peel
    /// count outside [1, kBakedMaxPeelPasses] or a loop bound beyond the budget.
    void prepare(const View& view, const ImpulseSet& impulses,
                 const RenderSettings& settings) override;
    void record(VkCommandBuffer cmd, PassTimer& timer) override;
    const Image& result() const override { return m_base; }
    /// extra: voxel_size, levels, thickness, tetrahedra, bricks, brick_buffers, distance_bricks,
    /// entry_faces, max_layer_tets, max_layer_samples, table_entries, loop_bound, peel_passes,
    /// eye_tetrahedron, bake_mib (and max_loop_iterations when counting).
    FrameCounters counters() const override;

    /// Count every march invocation's loop iterations from the next frame on (for tests).
    void countLoops(bool on) { m_countLoops = on; }
    /// Split the density bricks over buffers of at most this many bricks (0: as many as one
    /// storage buffer takes) from the next bake loaded on (for tests: the split of a small bake).
    void splitBricks(std::uint32_t bricksPerBuffer) {
        m_brickSplit = bricksPerBuffer;
        m_bake.reset();
    }
    /// After the frame completed.
    BakedStats stats() const;

private:
    struct Bake;
    /// InputError when `bake` does not fit the device (a leaf table or the bricks beyond its
    /// storage buffers, or the memory budget) split `perBuffer` bricks a buffer.
    /// `lit`: its shading bricks too (as many bytes again).
    void checkBakeFits(const BakeData& bake, bool lit, std::uint64_t perBuffer) const;
    /// Replace the bake on the GPU by `bake`; `lit`: its shading bricks too, in buffers of their
    /// own split as the density bricks are, and the mesh's solid.
    void uploadBake(const BakeData& bake, bool lit);
    /// Checks the bake handed in `settings` against the scene's shell (the mesh's hash with
    /// `cellSize`, its thickness) and uploads it when it is not the one uploaded last (or was
    /// uploaded without the shading bricks a lit frame needs). InputError for a lit frame of a
    /// bake without shading grids.
    void useBake(const RenderSettings& settings, float cellSize, bool lit);
    /// Lit: the lights, the sky and the kernel's models into `params`.
    void litParams(const noise::Shading& shading, gpu_baked::SpotBakedParams& params) const;
    /// The tetrahedra's buffer for `triangles` prisms, and per mesh their neighbours, entry
    /// faces and the peel's indirect draw.
    void ensureShell(std::uint32_t triangles);
    void ensureTargets(std::uint32_t width, std::uint32_t height);
    // The passes record() records, in order (the file comment's steps).
    /// 1. The frame's clears, then the shell's tetrahedra and the eye's.
    void recordShell(VkCommandBuffer cmd);
    /// 2. The base mesh, with the first layer's peel drawn in its rendering.
    void recordMeshAndFirstPeel(VkCommandBuffer cmd);
    /// 3. Layer k's peel (in a rendering the caller begins) and its march.
    void recordPeel(VkCommandBuffer cmd, std::uint32_t k);
    void recordMarch(VkCommandBuffer cmd, std::uint32_t k);
    /// Layer `layer`'s list header, bound at its offset.
    Descriptors& bindList(Descriptors& d, std::uint32_t layer) const;
    const Pipeline& marchPipeline(bool count, bool first, bool lit, std::uint32_t brickBuffers);

    const SceneGpu& m_scene;
    Context& m_ctx;
    Pipeline m_shell;
    std::array<Pipeline, 2> m_peel; ///< later layers, the first
    std::map<std::tuple<bool, bool, bool, std::uint32_t>, Pipeline>
        m_march; ///< by (count loops, first layer, lit, brick buffers)
    bool m_countLoops = false;

    // Per bake (RenderSettings::bake): the one on the GPU.
    std::shared_ptr<const BakeData> m_bake;
    bool m_bakeLit = false; ///< its shading bricks are uploaded too
    BakedStats m_bakeStats;
    Buffer m_table;
    std::array<Buffer, gpu_baked::kBakedBrickBuffers> m_bricks; ///< the density bricks' buffers
    /// Lit: the shading bricks' buffers (density brick b's at the same place) and the mesh's
    /// inside at level m_solidLevel (solidVoxels; kBakedBindSolid).
    std::array<Buffer, gpu_baked::kBakedBrickBuffers> m_shadingBricks;
    Buffer m_solid;
    std::uint32_t m_solidLevel = 0;
    std::uint32_t m_bricksPerBuffer = 0, m_brickSplit = 0;
    float m_brickUnit = 1.0f; ///< what a stored 1 in the density bricks is (SpotBakedParams::unit)
    std::vector<glm::ivec4> m_leafOrigin, m_leafDims;
    // Per mesh: the tetrahedra (3 per triangle), their neighbours, the entry faces (a mask per
    // triangle) and the peel's draw of those that face the eye (baked_shell.comp).
    Buffer m_tets, m_params, m_neighbours, m_entryMasks, m_peelDraw, m_eyeTet;
    std::uint32_t m_entryFaceCount = 0;
    // Per image size.
    std::uint32_t m_width = 0, m_height = 0;
    Image m_base, m_distance, m_meshDepth, m_exitDepth, m_accum, m_baseKept;
    Buffer m_loops, m_listPixels, m_layerEntry;
    /// The layers' list headers (SpotBakedList), one per layer at m_listStride bytes (the
    /// device's storage-buffer offset alignment), each bound at its own offset; the march's
    /// indirect dispatch.
    Buffer m_lists;
    VkDeviceSize m_listStride = 0;
    std::vector<std::byte> m_emptyLists; ///< every layer's header empty, at m_listStride (host)

    struct Prepared {
        gpu_splat::SpotSplatFrame frame{};
        glm::vec3 background{0.0f};
        std::uint32_t peelPasses = 1;
        bool count = false;
        std::uint32_t brickBuffers = 1; ///< the storage buffers the bricks span
        bool lit = false;               ///< a lit scene: the lit march
    } m_frame;
};

} // namespace spot::splat
