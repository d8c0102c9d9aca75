/// @file pass_vk.h
/// @brief What the splat renderer and the ray-march share: the frame constants (the camera
/// basis exactly as noise::CameraRays builds it, so every method's rays are the reference's),
/// the base mesh and kernel lobes on the GPU, and the small Vulkan helpers of their passes.
#pragma once

#include <cstdint>
#include <functional>
#include <span>
#include <vector>

#include <glm/glm.hpp>

#include "context_vk.h"
#include "noise/camera.h"
#include "noise/kernel.h"
#include "noise/mesh.h"
#include "noise/reference.h"

namespace spot::noise {
struct Mesh;
}

namespace spot::splat {

class LightSpace;

namespace gpu_splat {
using glm::uvec4;
using glm::vec4;
#define SPOT_CONST inline constexpr
#include "shaders/spot_splat.h"
#undef SPOT_CONST
static_assert(sizeof(SpotSplatFrame) == 128, "push constants: 128 bytes at most on lavapipe");
static_assert(sizeof(SpotMeshVertex) == 32);
static_assert(sizeof(SpotScreenLobe) == 64);
static_assert(sizeof(SpotKernelBound) == 48);
static_assert(sizeof(SpotSplatCounters) == 16);
} // namespace gpu_splat

inline constexpr VkFormat kColorFormat = VK_FORMAT_R32G32B32A32_SFLOAT;
inline constexpr VkFormat kScalarFormat = VK_FORMAT_R32_SFLOAT;
inline constexpr VkFormat kDepthFormat = VK_FORMAT_D32_SFLOAT;
/// Near plane of the reversed depth mapping (world units): float depth near / z keeps its
/// relative precision at every distance, so the near plane can sit this close to the eye.
inline constexpr float kNearPlane = 1e-4f;

/// Short names for the stages, accesses and layouts the splat and march passes synchronize.
namespace passes {
inline constexpr VkPipelineStageFlags2 kAll = VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT;
inline constexpr VkPipelineStageFlags2 kCompute = VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT;
inline constexpr VkPipelineStageFlags2 kColorOut = VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT;
inline constexpr VkPipelineStageFlags2 kTests =
    VK_PIPELINE_STAGE_2_EARLY_FRAGMENT_TESTS_BIT | VK_PIPELINE_STAGE_2_LATE_FRAGMENT_TESTS_BIT;
inline constexpr VkPipelineStageFlags2 kFragment = VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT;
inline constexpr VkPipelineStageFlags2 kTransfer = VK_PIPELINE_STAGE_2_ALL_TRANSFER_BIT;
inline constexpr VkPipelineStageFlags2 kHostStage = VK_PIPELINE_STAGE_2_HOST_BIT;
inline constexpr VkAccessFlags2 kColorRW =
    VK_ACCESS_2_COLOR_ATTACHMENT_READ_BIT | VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT;
inline constexpr VkAccessFlags2 kDepthRW =
    VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_READ_BIT | VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT;
inline constexpr VkAccessFlags2 kStorageRead = VK_ACCESS_2_SHADER_STORAGE_READ_BIT;
inline constexpr VkAccessFlags2 kStorageRW =
    VK_ACCESS_2_SHADER_STORAGE_READ_BIT | VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT;
inline constexpr VkImageAspectFlags kColorAspect = VK_IMAGE_ASPECT_COLOR_BIT;
inline constexpr VkImageLayout kAttachment = VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL;
inline constexpr VkImageLayout kGeneral = VK_IMAGE_LAYOUT_GENERAL;
} // namespace passes

template <std::size_t N> std::span<const std::uint32_t> spirv(const std::uint32_t (&code)[N]) {
    return {code, N};
}

/// The frame constants for a camera (units: world; image size in pixels). `flags` are the
/// method's kSplatFlag* bits (Lambert is added from `shading`; a lit frame's lights are the
/// light-space structure's, splat/passes/light_space_vk.h).
gpu_splat::SpotSplatFrame makeSplatFrame(const noise::Camera& camera, const noise::Shading& shading,
                                         glm::vec3 baseColor, std::uint32_t count,
                                         std::uint32_t lobes, float support,
                                         std::uint32_t kernelSamples, std::uint32_t flags);

/// The opaque base mesh on the GPU (vertex pulling) and the pass that draws it first in every
/// method: its colour (lit as the frame says) over the background, the ray distance t to it
/// (kSplatNoMesh where none) and a reversed float depth.
class MeshPass {
public:
    /// Uploads the mesh (may be empty) and builds the pipeline; `who` names the buffers.
    MeshPass(Context& ctx, const noise::Mesh& mesh, const char* who);
    /// Records the pass into `base` (kColorFormat), `distance` (kScalarFormat) and `depth`
    /// (kDepthFormat), all in attachment layouts, cleared first. Nothing else changes layout.
    /// `after`, if given, records more draws into the same rendering after the mesh's (their
    /// pipelines made for those three formats; the mesh's depth is written by then).
    /// With `light` (a lit frame), the mesh is shaded by its lights and sky, shadowed
    /// (splat_mesh_lit.frag).
    void record(VkCommandBuffer cmd, const gpu_splat::SpotSplatFrame& frame, const Image& base,
                const Image& distance, const Image& depth, glm::vec3 background,
                const std::function<void(VkCommandBuffer)>& after = {},
                const LightSpace* light = nullptr) const;
    /// Whether `record` culls back faces for this frame: when the mesh bounds solids facing out
    /// (noise::closedOutward) and its bounds lie wholly beyond the near plane (so every ray starts
    /// outside them, and meets a front face first). Half the triangles are then dropped at setup,
    /// which is most of the pass on lavapipe (ring-sphere's 36,864 triangles at 128x128: 6.2 to
    /// 3.1 ms); the colour, distance and depth written are the same. The closedness and bounds
    /// are the constructor's mesh's (a pose keeps the topology), the bounds the pose's (setBounds).
    bool cullsBackFaces(const gpu_splat::SpotSplatFrame& frame) const;
    /// gpu_splat::SpotMeshVertex[] (world units, unit normals or zero): the mesh as drawn, which
    /// an animated mesh's deform passes write every frame (splat/deform_vk.h).
    const Buffer& vertices() const { return m_vertices; }
    /// The mesh at rest: vertices() until keepRest(), then a copy of the rest that no pass
    /// writes (what the baked method's shell maps back to, and the deform passes rotate from).
    const Buffer& restVertices() const { return m_rest.handle() ? m_rest : m_vertices; }
    /// Keep a copy of the rest vertices before the deform passes overwrite vertices().
    void keepRest();
    /// The posed mesh's bounds (cullsBackFaces' test), set by the host each frame it poses.
    void setBounds(glm::vec3 lo, glm::vec3 hi) {
        m_lo = lo;
        m_hi = hi;
    }
    /// The mesh's bounds as drawn: at rest, or the pose's (setBounds).
    noise::Bounds bounds() const { return {m_lo, m_hi}; }
    /// uint32[3 x triangles], usable as a storage buffer too.
    const Buffer& indices() const { return m_indices; }
    std::uint32_t indexCount() const { return m_indexCount; }

private:
    Context* m_ctx;
    Buffer m_vertices, m_indices, m_rest;
    std::uint32_t m_indexCount = 0;
    bool m_closed = false;
    glm::vec3 m_lo{0.0f}, m_hi{0.0f};
    GraphicsPipelineDesc m_desc; ///< the unlit pipeline's, for the others
    /// The pipeline for unlit or lit frames, drawing both faces or culling back faces, made at
    /// the first frame that draws with it.
    const Pipeline& pipeline(bool lit, bool culled) const;
    /// Unlit, unlit culled, lit, lit culled: each made by pipeline() when first drawn.
    mutable Pipeline m_pipelines[4];
};
/// The kernel's lobes (gpu::SpotLobe[]); InputError for 0 or more than 8 lobes or a bad support.
Buffer uploadKernelLobes(Context& ctx, const noise::Kernel& kernel, const char* who);

void requireFormat(Context& ctx, VkFormat format, VkFormatFeatureFlags features, const char* what);
VkPipelineColorBlendAttachmentState opaqueBlend();
/// dst = src + dst.
VkPipelineColorBlendAttachmentState additiveBlend();
/// Premultiplied "over": dst = src + (1 - src.a) dst.
VkPipelineColorBlendAttachmentState overBlend();
VkRenderingAttachmentInfo colorAttachment(const Image& image, VkAttachmentLoadOp load,
                                          glm::vec4 clear = glm::vec4(0.0f));
/// Reversed depth: cleared to 0, infinitely far.
VkRenderingAttachmentInfo depthAttachment(const Image& image, VkAttachmentLoadOp load);
/// vkCmdBeginRendering over the whole image, with viewport and scissor set (the scissor to the
/// window of a live PixelScissor when the image has its full size).
void beginRendering(VkCommandBuffer cmd, std::uint32_t width, std::uint32_t height,
                    const std::vector<VkRenderingAttachmentInfo>& colors,
                    const VkRenderingAttachmentInfo* depth);
void pushFrame(VkCommandBuffer cmd, const Pipeline& pipeline, const gpu_splat::SpotSplatFrame& frame);

/// While alive (on this thread), every beginRendering into a target of `fullWidth` x `fullHeight`
/// sets its scissor to `window`, and dispatchPixels over that image dispatches only the
/// workgroups that cover it: a tile's frame (RenderSettings::window) computes only the tile's
/// pixels, each exactly as in the whole image (the viewport and the invocation ids, and so every
/// fragment's and invocation's values, stay the whole image's). An empty window restricts
/// nothing.
/// A compute pass with one invocation per element of a `width` x `height` grid (`scale` x
/// `scale` elements a pixel: a pass over rays), in `group` x `group` workgroups: vkCmdDispatch,
/// or under a live PixelScissor for the grid's image, the workgroups that cover the window
/// alone (vkCmdDispatchBase). The shader must index by gl_GlobalInvocationID (or the workgroup
/// id) only, never by gl_NumWorkGroups, and bound-check the grid itself.
void dispatchPixels(VkCommandBuffer cmd, std::uint32_t width, std::uint32_t height,
                    std::uint32_t group, std::uint32_t scale = 1);

class PixelScissor {
public:
    PixelScissor(noise::PixelRect window, std::uint32_t fullWidth, std::uint32_t fullHeight);
    ~PixelScissor();
    PixelScissor(const PixelScissor&) = delete;
    PixelScissor& operator=(const PixelScissor&) = delete;

private:
    noise::PixelRect m_previous;
    std::uint32_t m_previousWidth, m_previousHeight;
};

/// The prepare pass (splat_prepare.comp) specialized for a kernel of `lobes` lobes: `screen` for
/// the splatting methods (screen lobes and kernel bounds too), `ewa` widening, the projection,
/// `worldLobes` whether the world lobes are stored (always without `screen`), and `clipped` for
/// its second dispatch (the kernels the first listed, with a lobe that projects to no ellipse).
/// `lit`: the variant that lights each world lobe (splat_prepare_lit.comp; it also reads the
/// light-space structure, PrepareBuffers::light).
Pipeline makePreparePipeline(Context& ctx, std::uint32_t lobes, bool screen, bool ewa,
                             bool orthographic, bool worldLobes = true, bool clipped = false,
                             bool lit = false);

/// What the prepare pass reads and writes. Without `screen`, screenLobes and bounds may be any
/// storage buffer: nothing is written there.
struct PrepareBuffers {
    const Buffer* impulses = nullptr;    ///< gpu::SpotImpulse[capacity]
    const Buffer* count = nullptr;       ///< uint32: the impulse count
    const Buffer* lobes = nullptr;       ///< gpu::SpotLobe[lobes]: the kernel
    const Buffer* worldLobes = nullptr;  ///< gpu::SpotWorldLobe[capacity * lobes]
    const Buffer* screenLobes = nullptr; ///< gpu_splat::SpotScreenLobe[capacity * lobes]
    const Buffer* bounds = nullptr;      ///< gpu_splat::SpotKernelBound[capacity]
    /// With `screen`: SpotSplatList then uint[capacity], the kernels the second dispatch bounds.
    const Buffer* clipList = nullptr;
    /// With `screen`: the second dispatch's pipeline (makePreparePipeline with `clipped`).
    const Pipeline* clipped = nullptr;
    /// A lit pipeline's light-space structure.
    const LightSpace* light = nullptr;
};

/// Reset a SpotSplatList (count 0, no groups) for a first dispatch to append to and a second,
/// indirect one to run over: after the previous frame's dispatches read it, before this frame's
/// compute shaders use it.
void recordListReset(VkCommandBuffer cmd, const Buffer& list);

/// Record the prepare pass over `capacity` impulses (those past the count return at once), and,
/// with a clip list, its second dispatch over the kernels the first listed (the list is reset
/// first; barriers between). Records nothing for no capacity.
void recordPrepare(Context& ctx, VkCommandBuffer cmd, const Pipeline& prepare,
                   const gpu_splat::SpotSplatFrame& frame, const PrepareBuffers& buffers,
                   std::uint32_t capacity);

} // namespace spot::splat
