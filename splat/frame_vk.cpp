#include "frame_vk.h"

#include <atomic>

#include "noise/error.h"

namespace spot::splat {

void ResultReadback::record(Context& ctx, VkCommandBuffer cmd, const Image& result,
                            noise::PixelRect rect) {
    fullWidth = result.width();
    fullHeight = result.height();
    const noise::PixelRect all{0, 0, int(fullWidth), int(fullHeight)};
    window = rect.empty() ? all : rect;
    if (window.x0 < 0 || window.y0 < 0 || window.x1 > all.x1 || window.y1 > all.y1)
        throw InputError(cat("pixels ", window.x0, ",", window.y0, ",", window.x1, ",", window.y1,
                             " are outside the ", fullWidth, "x", fullHeight, " image"));
    width = std::uint32_t(window.width());
    height = std::uint32_t(window.height());
    const std::uint64_t bytes = std::uint64_t(width) * height * sizeof(glm::vec4);
    if (buffer.size() < bytes)
        buffer = Buffer(ctx, bytes, VK_BUFFER_USAGE_TRANSFER_DST_BIT, Buffer::Memory::HostVisible,
                        "frame readback");
    VkBufferImageCopy region{};
    region.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
    region.imageOffset = {window.x0, window.y0, 0};
    region.imageExtent = {width, height, 1};
    vkCmdCopyImageToBuffer(cmd, result.handle(), VK_IMAGE_LAYOUT_GENERAL, buffer.handle(), 1, &region);
    memoryBarrier(cmd, VK_PIPELINE_STAGE_2_ALL_TRANSFER_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT,
                  VK_PIPELINE_STAGE_2_HOST_BIT, VK_ACCESS_2_HOST_READ_BIT);
}

noise::Image ResultReadback::read(glm::vec3 background) const {
    noise::Image image(static_cast<int>(width), static_cast<int>(height));
    image.alpha.resize(image.pixels.size());
    image.background = background;
    if (width != fullWidth || height != fullHeight) {
        image.crop = window;
        image.fullWidth = int(fullWidth);
        image.fullHeight = int(fullHeight);
    }
    const auto* rgba = static_cast<const glm::vec4*>(buffer.mapped());
    for (std::size_t i = 0; i < image.pixels.size(); ++i) {
        image.pixels[i] = glm::vec3(rgba[i]);
        image.alpha[i] = rgba[i].a;
    }
    return image;
}

namespace {

void fillStats(FrameStats& stats, const PassTimer& timer, const Renderer& renderer, Context& ctx) {
    for (const auto& pass : timer.passMilliseconds())
        stats.passMs.push_back(pass);
    stats.gpuMs = timer.totalMilliseconds();
    stats.counters = renderer.counters();
    stats.gpuMemoryBytes = ctx.peakAllocatedBytes();
}

double since(std::chrono::steady_clock::time_point start) {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

} // namespace

Frame::Frame(Context& ctx, const noise::Mesh& mesh, const noise::ImpulseGenerator& generator)
    : m_ctx(ctx), m_cpuGenerator(generator), m_scene(ctx, mesh, generator.kernel()),
      m_generator(ctx, mesh, generator), m_timer(ctx), m_commands(ctx) {}

Frame::~Frame() = default;

Renderer& Frame::renderer(std::string_view method) {
    if (const auto it = m_renderers.find(method); it != m_renderers.end())
        return *it->second;
    const MethodInfo& info = gpuMethod(method);
    return *m_renderers.emplace(info.name, info.make(m_scene)).first->second;
}

void Frame::animate(const noise::AnimatedMesh& animation, const noise::Wind& wind) {
    if (animation.rest().positions.size() != m_cpuGenerator.mesh().positions.size() ||
        animation.rest().triangles != m_cpuGenerator.mesh().triangles)
        throw InputError("Frame::animate: the animation's rest is not the frame's mesh");
    m_deformer = std::make_unique<GpuDeformer>(m_ctx, animation, m_scene.posedMeshPass(),
                                               m_cpuGenerator.cells(), wind);
}

bool Frame::cellVisible(const noise::CameraRays& rays, const noise::SurfaceCell& cell) const {
    if (m_deformer)
        return m_deformer->cellVisible(rays, m_cpuGenerator.cells(), cell);
    const double h = m_cpuGenerator.cellSize();
    return rays.boxMayBeVisible(glm::dvec3(cell.ijk) * h - h, glm::dvec3(cell.ijk + 1) * h + h);
}

FrameStats Frame::render(std::string_view method, const View& view, const RenderSettings& settings,
                         noise::Image* image) {
    const auto start = std::chrono::steady_clock::now();
    Renderer& r = renderer(method);
    FrameStats stats;
    stats.method = std::string(method);
    const noise::CameraRays rays(view.camera); // validates the camera (InputError)
    if (m_deformer)
        m_deformer->prepare(m_time);
    // Lit with shadows, a cell out of view may shadow one in view: none is culled.
    const bool cullNone = view.shading.castsShadows();
    const bool regenerate = m_generator.prepare(
        [&](const noise::SurfaceCell& cell) {
            const bool visible = cullNone || cellVisible(rays, cell);
            stats.visibleCells += visible;
            return visible;
        },
        lodParameters(view.camera, settings.lodPixels));
    // What the frame records before the method: the generation when the cells changed, the
    // deform passes when the time or the rest impulses did (a paused clip, a repeat or an orbit
    // keeps the pose, the moved impulses and what is built from them).
    const auto recordImpulses = [&](VkCommandBuffer cmd, bool generate) {
        if (generate)
            m_generator.record(cmd, m_timer);
        if (m_deformer)
            m_deformer->record(cmd, m_timer, m_generator.impulses());
    };
    const bool pose = m_deformer && (regenerate || !m_deformer->current(m_generator.impulses()));
    bool impulsesInFrame = true;
    if (r.readsImpulsesInPrepare() && (regenerate || pose)) {
        // The renderer reads the new impulses on the host: make them in a submit of their own.
        VkCommandBuffer cmd = m_commands.begin();
        m_timer.begin(cmd);
        recordImpulses(cmd, regenerate);
        m_commands.submitAndWait();
        for (const auto& pass : m_timer.passMilliseconds())
            stats.passMs.push_back(pass);
        impulsesInFrame = false;
    }
    // The deform passes' set stands in for the generator's from the first record on (its
    // buffer is made there; the version changes whenever the pose or the rest set does).
    if (m_deformer && impulsesInFrame)
        m_deformer->reserve(m_generator.impulses());
    // A renderer that reads the impulses on the host (the ray march) takes them in cell order,
    // which the pose breaks: sorted again, with the posed cells as their shell.
    const ImpulseSet set =
        !m_deformer                    ? m_generator.impulses()
        : r.readsImpulsesInPrepare() ? m_deformer->sortedByCell(m_generator.count())
                                       : m_deformer->moved();
    r.prepare(view, set, settings);
    VkCommandBuffer cmd = m_commands.begin();
    m_timer.begin(cmd);
    if (impulsesInFrame)
        recordImpulses(cmd, regenerate);
    {
        const PixelScissor scissor(settings.window, std::uint32_t(view.camera.width),
                                   std::uint32_t(view.camera.height));
        r.record(cmd, m_timer);
    }
    if (image)
        m_readback.record(m_ctx, cmd, r.result(), settings.window);
    m_commands.submitAndWait();
    double earlierMs = 0.0; // the passes of a submit of their own
    for (const auto& pass : stats.passMs)
        earlierMs += pass.second;
    fillStats(stats, m_timer, r, m_ctx);
    stats.gpuMs += earlierMs;
    stats.regenerated = regenerate;
    stats.kernelsGenerated = m_generator.count();
    stats.candidates = m_generator.candidates();
    stats.cellsGenerated = m_generator.cells();
    if (image)
        *image = m_readback.read(view.background);
    stats.wallMs = since(start);
    return stats;
}

noise::Image renderImpulses(Context& ctx, Renderer& renderer, const View& view,
                            const Buffer& impulses, std::uint32_t count,
                            const RenderSettings& settings, FrameStats* stats,
                            const noise::SurfaceCells* cells) {
    static std::atomic<std::uint64_t> version{0};
    const auto start = std::chrono::steady_clock::now();
    Buffer countBuffer(ctx, 16, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, Buffer::Memory::HostVisible,
                       "impulse count");
    *static_cast<std::uint32_t*>(countBuffer.mapped()) = count;
    ImpulseSet set;
    set.impulses = &impulses;
    set.count = &countBuffer;
    set.capacity = count;
    set.version = ++version;
    set.cells = cells;
    renderer.prepare(view, set, settings);
    PassTimer timer(ctx);
    CommandBuffer commands(ctx);
    ResultReadback readback;
    VkCommandBuffer cmd = commands.begin();
    timer.begin(cmd);
    renderer.record(cmd, timer);
    readback.record(ctx, cmd, renderer.result());
    commands.submitAndWait();
    if (stats) {
        *stats = FrameStats{};
        fillStats(*stats, timer, renderer, ctx);
        stats->kernelsGenerated = count;
        stats->wallMs = since(start);
    }
    return readback.read(view.background);
}

} // namespace spot::splat
