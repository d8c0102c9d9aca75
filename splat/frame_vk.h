/// @file frame_vk.h
/// @brief The persistent frame: what `render`, `bench` and the editor drive. It owns the scene's
/// GPU data, the impulse generator, one renderer per method (made on first use, from the
/// registry of method_vk.h), one command buffer and its fence, and the readback buffer.
///
/// One frame: the cells the camera may see are chosen on the host (frustum culling), the
/// generator regenerates the impulses only when those cells or the level of detail changed
/// (otherwise the last frame's impulses are drawn again), the renderer prepares, and everything
/// is recorded into one command buffer: generation, the method's passes and, when the pixels are
/// wanted, the copy into the readback buffer. One submit, one wait.
#pragma once

#include <chrono>
#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "noise/camera.h"
#include "noise/image.h"
#include "noise/impulses.h"
#include "splat/context_vk.h"
#include "splat/deform_vk.h"
#include "splat/generate_vk.h"
#include "splat/method_vk.h"

namespace spot::splat {

struct FrameStats {
    std::string method;
    /// GPU milliseconds per pass, in recording order ("generate" first when it ran).
    std::vector<std::pair<std::string, double>> passMs;
    double gpuMs = 0.0;  ///< GPU time of the frame, first pass to last
    double wallMs = 0.0; ///< host time of render(): preparing, recording, submit, wait, readback
    bool regenerated = false;            ///< the impulses were generated in this frame
    std::uint32_t kernelsGenerated = 0;  ///< impulses drawn from (this frame's or the last)
    std::uint32_t candidates = 0;        ///< examined before the density test
    std::uint32_t cellsGenerated = 0;    ///< cells the impulses came from (after culling)
    /// Cells the camera may see; every cell when kernels cast shadows (Shading::castsShadows)
    std::uint32_t visibleCells = 0;
    FrameCounters counters;
    std::uint64_t gpuMemoryBytes = 0; ///< the context's peak allocation so far
};

/// Copy `renderer`'s result into `readback` (grown to fit) and read it back after the submit:
/// record() before the submit, read() after.
struct ResultReadback {
    /// `window`: those pixels alone (empty: all); read() then gives an image of the window's
    /// size with its crop set.
    void record(Context& ctx, VkCommandBuffer cmd, const Image& result,
                noise::PixelRect window = {});
    /// The result's colour and coverage alpha; `background`: what the colour is composited over
    /// where the coverage is below 1 (the frame's View::background).
    noise::Image read(glm::vec3 background) const;
    Buffer buffer;
    std::uint32_t width = 0, height = 0;
    noise::PixelRect window;
    std::uint32_t fullWidth = 0, fullHeight = 0;
};

class Frame {
public:
    /// Uploads the mesh and the generator's data; `generator` (and the mesh it was made for) must
    /// outlive the frame.
    Frame(Context& ctx, const noise::Mesh& mesh, const noise::ImpulseGenerator& generator);
    Frame(const Frame&) = delete;
    Frame& operator=(const Frame&) = delete;
    ~Frame();

    /// Render one frame with the registry's method `method` and wait for it. `image`, when given,
    /// receives the pixels (linear RGB, top-left origin): settings.window's alone when it is set
    /// (InputError when it is outside the image). Throws InputError for an unknown
    /// method, a bad setting, or a frame beyond the memory budget.
    FrameStats render(std::string_view method, const View& view, const RenderSettings& settings,
                      noise::Image* image = nullptr);

    /// The renderer of `method`, made on first use.
    Renderer& renderer(std::string_view method);
    const SceneGpu& scene() const { return m_scene; }
    GpuGenerator& generator() { return m_generator; }
    /// The generator's fields changed (noise::ImpulseGenerator::setField or refreshFields after
    /// painting): the next render() uploads nothing stale and regenerates the impulses.
    void fieldsChanged() { m_generator.refreshFields(); }
    /// fieldsChanged() when only the model cells `cells` (indices into the generator's cells)
    /// read what changed: if the next render() sees the cells of the last one at the same level
    /// of detail, only those cells' impulses are generated again, every other cell's impulses
    /// stay bit for bit (GpuGenerator::refreshFields(cells)).
    void fieldsChanged(const std::vector<std::uint32_t>& cells) { m_generator.refreshFields(cells); }
    /// Whether a cell may be seen by the camera (its box grown by one cell: kernels reach the
    /// neighbouring cells; an animated mesh's cell, its posed box).
    bool cellVisible(const noise::CameraRays& rays, const noise::SurfaceCell& cell) const;

    /// Make every later render() pose `animation` (whose rest() must be the frame's mesh, and
    /// which must outlive the frame) at the time setTime() gives, and turn the impulses by
    /// `wind` (docs/design.md section 6). A static mesh with wind animates too. InputError for a
    /// mesh the deform passes cannot take.
    void animate(const noise::AnimatedMesh& animation, const noise::Wind& wind);
    bool animated() const { return m_deformer != nullptr; }
    /// The time (seconds) of the next render()s' pose; clamped to the clip.
    void setTime(double t) { m_time = t; }
    double time() const { return m_time; }
    GpuDeformer* deformer() { return m_deformer.get(); }

private:
    Context& m_ctx;
    const noise::ImpulseGenerator& m_cpuGenerator;
    SceneGpu m_scene;
    GpuGenerator m_generator;
    std::unique_ptr<GpuDeformer> m_deformer;
    double m_time = 0.0;
    std::map<std::string, std::unique_ptr<Renderer>, std::less<>> m_renderers;
    PassTimer m_timer;
    CommandBuffer m_commands;
    ResultReadback m_readback;
};

/// One frame of `renderer` from impulses the caller holds (tests and tools): the count uploaded,
/// the frame recorded, submitted, waited for and read back. Each call counts as a new impulse
/// set (ImpulseSet::version). `stats`, when given, receives the pass times and counters.
noise::Image renderImpulses(Context& ctx, Renderer& renderer, const View& view,
                            const Buffer& impulses, std::uint32_t count,
                            const RenderSettings& settings, FrameStats* stats = nullptr,
                            const noise::SurfaceCells* cells = nullptr);

} // namespace spot::splat
