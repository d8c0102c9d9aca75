#include "edit_window.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <utility>

#include <vulkan/vulkan.h>
// After vulkan.h: GLFW then declares glfwCreateWindowSurface and the presentation queries.
#include <GLFW/glfw3.h>
#include <imgui.h>
#include <imgui_impl_glfw.h>
#include <imgui_impl_vulkan.h>

#include "edit_input.h"
#include "edit_panels.h"
#include "edit_present_vk.h"
#include "edit_script.h"
#include "edit_session.h"
#include "edit_view.h"
#include "noise/error.h"
#include "noise/image.h"
#include "noise/mesh.h"
#include "noise/shared_data.h"
#include "render_options.h"
#include "splat/context_vk.h"
#include "splat/frame_vk.h"
#include "splat/passes/splatting_vk.h"

namespace spot::editor {

namespace {

using Clock = std::chrono::steady_clock;

double msSince(Clock::time_point start) {
    return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

double median(std::vector<double> v) {
    if (v.empty())
        return 0.0;
    std::sort(v.begin(), v.end());
    const std::size_t n = v.size();
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// --- GLFW ----------------------------------------------------------------------------------

std::string g_glfwError; ///< the last message of GLFW's error callback

/// glfwInit() and glfwTerminate(), with a clear InputError when there is no display.
struct GlfwLibrary {
    GlfwLibrary() {
        const char* display = std::getenv("DISPLAY");
        if (!display || !*display)
            throw InputError("spotshell edit: no display (DISPLAY is not set); run it in a desktop "
                             "session, or headless under xvfb-run");
        glfwSetErrorCallback(
            [](int, const char* message) { g_glfwError = message ? message : ""; });
        if (!glfwInit())
            throw InputError(
                cat("spotshell edit: cannot open the display '", display, "': ", g_glfwError));
        if (!glfwVulkanSupported()) {
            glfwTerminate();
            throw std::runtime_error("GLFW: no Vulkan loader with window-system support");
        }
    }
    ~GlfwLibrary() { glfwTerminate(); }
    GlfwLibrary(const GlfwLibrary&) = delete;
    GlfwLibrary& operator=(const GlfwLibrary&) = delete;
};

struct GlfwWindow {
    GlfwWindow(int width, int height, const std::string& title) {
        glfwWindowHint(GLFW_CLIENT_API, GLFW_NO_API);
        handle = glfwCreateWindow(width, height, title.c_str(), nullptr, nullptr);
        if (!handle)
            throw std::runtime_error(
                cat("GLFW: cannot create a ", width, "x", height, " window: ", g_glfwError));
    }
    ~GlfwWindow() { glfwDestroyWindow(handle); }
    GlfwWindow(const GlfwWindow&) = delete;
    GlfwWindow& operator=(const GlfwWindow&) = delete;
    GLFWwindow* handle = nullptr;
};

splat::ContextOptions windowContextOptions() {
    splat::ContextOptions o = splat::contextOptionsFromEnvironment();
    std::uint32_t count = 0;
    const char** names = glfwGetRequiredInstanceExtensions(&count);
    if (!names)
        throw std::runtime_error(cat("GLFW: no Vulkan surface extensions: ", g_glfwError));
    for (std::uint32_t i = 0; i < count; ++i)
        o.instanceExtensions.emplace_back(names[i]);
    o.swapchain = true;
    o.canPresent = [](VkInstance instance, VkPhysicalDevice device, std::uint32_t family) {
        return glfwGetPhysicalDevicePresentationSupport(instance, device, family) == GLFW_TRUE;
    };
    return o;
}

// --- the window's state and input -----------------------------------------------------------

/// What the GLFW callbacks change (through the window's user pointer).
struct InputState {
    OrbitView* view = nullptr;
    edit::Session* session = nullptr;
    BoundingSphere sphere;
    Drag drag = Drag::None;
    double lastX = 0.0, lastY = 0.0; ///< the pointer at the last cursor event
    bool pointerKnown = false;       ///< a cursor event came (else lastX, lastY are queried)
    bool exportRequested = false;    ///< F12: export the view when the panels are built
    bool sceneDirty = true;       ///< render the scene again
    bool resized = true;          ///< recreate the swapchain
    bool closeRequested = false;  ///< the close button, with unsaved changes (the modal asks)
    bool togglePanels = false;    ///< N: show or hide the panels' column
    bool playPause = false;       ///< space: play or pause the timeline
    int stepFrames = 0;           ///< left / right: frames to step the timeline
    /// Where the scene is in the window (the viewport) and where the panels' column is.
    WindowLayout layout;
    Clock::time_point lastMotion; ///< of the camera (for the lower resolution while navigating)
    /// The first brush event not yet shown (stroke-to-frame is measured from it).
    std::optional<Clock::time_point> pendingBrush;
    std::string error; ///< a brush or key edit the session refused

    /// The camera of the viewport (its aspect ratio; pointer positions are window pixels, the
    /// viewport's origin is the window's).
    noise::Camera viewCamera() const {
        return view->camera(std::max(layout.viewportWidth, 1),
                            std::max(layout.viewportHeight(), 1));
    }
    void moved() {
        sceneDirty = true;
        lastMotion = Clock::now();
    }
    /// A brush event (window pixels): the session begins, continues or ends the stroke.
    void brush(edit::Session::PointerPhase phase, const noise::Camera& camera, double x, double y,
               bool invert) {
        // A release paints nothing: the frame after it is the full-resolution one.
        if (!pendingBrush && phase != edit::Session::PointerPhase::Release)
            pendingBrush = Clock::now();
        try {
            session->pointer(phase, glm::vec2(float(x), float(y)), camera, invert);
        } catch (const InputError& e) {
            error = e.what();
        }
        sceneDirty = true;
    }
};

InputState& state(GLFWwindow* window) {
    return *static_cast<InputState*>(glfwGetWindowUserPointer(window));
}

void frameMesh(InputState& s) {
    const int w = s.layout.viewportWidth, h = s.layout.viewportHeight();
    // The mesh where it is shown (an animated one moves away from its rest pose).
    if (s.session->animation().animated())
        s.sphere = boundingSphere(s.session->shownMesh());
    s.view->frame(s.sphere, h > 0 && w > 0 ? double(w) / double(h) : 1.0);
    s.moved();
}

/// A brush key's action on the session's brush (radius, strength, kind, mirror).
void applyBrushKey(InputState& s, const InputAction& a) {
    edit::BrushSettings& brush = s.session->brush();
    switch (a.type) {
    case InputAction::Type::BrushRadius:
        brush.radiusPx =
            std::clamp(brush.radiusPx * (a.step > 0 ? 1.15f : 1.0f / 1.15f), 2.0f, 400.0f);
        break;
    case InputAction::Type::BrushStrength:
        brush.strength = std::clamp(brush.strength + (a.step > 0 ? 0.05f : -0.05f), -1.0f, 1.0f);
        break;
    case InputAction::Type::BrushKind:
        s.sceneDirty |= s.session->setBrushKind(edit::BrushKind(a.kind)).generatorRebuilt;
        break;
    case InputAction::Type::MirrorX:
        brush.mirrorX = !brush.mirrorX;
        break;
    default:
        break;
    }
}

/// Carry out what mapInput() made of an event: the view moves, the session paints or undoes.
void applyInput(InputState& s, const InputAction& a) {
    using T = InputAction::Type;
    using Phase = edit::Session::PointerPhase;
    s.drag = a.drag;
    const int h = s.layout.viewportHeight();
    try {
        switch (a.type) {
        case T::None:
        case T::Navigate:
            break;
        case T::Orbit:
            s.view->orbit(a.dx, a.dy, h);
            s.moved();
            break;
        case T::Pan:
            s.view->pan(a.dx, a.dy, h);
            s.moved();
            break;
        case T::Dolly:
            s.view->dolly(a.dy);
            s.moved();
            break;
        case T::TurnLight: {
            // A quarter degree a pixel: across an 800-pixel viewport, 200 degrees of azimuth.
            s.session->turnKeyLight(0.25f * float(a.dx), -0.25f * float(a.dy));
            s.moved();
            break;
        }
        case T::BrushPress:
        case T::BrushDrag:
        case T::BrushRelease:
            s.brush(a.type == T::BrushPress  ? Phase::Press
                    : a.type == T::BrushDrag ? Phase::Drag
                                             : Phase::Release,
                    s.viewCamera(), a.x, a.y, a.invert);
            break;
        case T::Undo:
            s.sceneDirty |= s.session->undo();
            break;
        case T::Redo:
            s.sceneDirty |= s.session->redo();
            break;
        case T::FrameMesh:
            frameMesh(s);
            break;
        case T::BrushRadius:
        case T::BrushStrength:
        case T::BrushKind:
        case T::MirrorX:
            applyBrushKey(s, a);
            break;
        case T::Export:
            s.exportRequested = true;
            break;
        case T::TogglePanels:
            s.togglePanels = true;
            break;
        case T::PlayPause:
            s.playPause = !s.playPause;
            break;
        case T::StepFrame:
            s.stepFrames += a.step;
            break;
        case T::MaskOverlay:
            s.session->setMaskOverlay(!s.session->maskOverlay());
            s.sceneDirty = true;
            break;
        }
    } catch (const InputError& e) {
        s.error = e.what();
    }
}

InputContext inputContext(const InputState& s, bool panelWantsMouse, bool panelWantsKeyboard) {
    return {s.drag, s.lastX, s.lastY, panelWantsMouse, panelWantsKeyboard};
}

void onMouseButton(GLFWwindow* window, int button, int action, int mods) {
    InputState& s = state(window);
    // The pointer as the last cursor event left it (queued events replay in order, however
    // late they are read); asked of the display only before the first one.
    if (!s.pointerKnown)
        glfwGetCursorPos(window, &s.lastX, &s.lastY);
    const InputEvent e = InputEvent::button(button, action, mods, s.lastX, s.lastY);
    // Outside the viewport (over the column) a press is the panels', even before ImGui has seen
    // the pointer there (a click without a motion first).
    const bool panel = ImGui::GetIO().WantCaptureMouse || !s.layout.inViewport(s.lastX, s.lastY);
    applyInput(s, mapInput(e, inputContext(s, panel, false)));
}

void onCursor(GLFWwindow* window, double x, double y) {
    InputState& s = state(window);
    const InputAction a = mapInput(InputEvent::cursor(x, y), inputContext(s, false, false));
    s.lastX = x;
    s.lastY = y;
    s.pointerKnown = true;
    applyInput(s, a);
}

void onScroll(GLFWwindow* window, double dx, double dy) {
    InputState& s = state(window);
    if (!s.pointerKnown)
        glfwGetCursorPos(window, &s.lastX, &s.lastY);
    const bool panel = ImGui::GetIO().WantCaptureMouse || !s.layout.inViewport(s.lastX, s.lastY);
    applyInput(s, mapInput(InputEvent::scroll(dx, dy), inputContext(s, panel, false)));
}

void onKey(GLFWwindow* window, int key, int, int action, int mods) {
    InputState& s = state(window);
    applyInput(s, mapInput(InputEvent::key(key, action, mods),
                           inputContext(s, false, ImGui::GetIO().WantCaptureKeyboard)));
}

void onClose(GLFWwindow* window) {
    InputState& s = state(window);
    const QuitStep step = quitStep(s.session->dirty(), true, QuitAnswer::None);
    if (!step.close) {
        glfwSetWindowShouldClose(window, GLFW_FALSE);
        s.closeRequested = step.ask;
    }
}

void onFramebufferSize(GLFWwindow* window, int, int) {
    state(window).resized = true;
    state(window).sceneDirty = true;
}

// --- panels -------------------------------------------------------------------------------

/// Render at 1/kScales[i] of the window's size (the blit scales up).
constexpr int kScales[] = {1, 2, 4};
/// Frames slower than this while moving or painting lower the resolution (10 fps).
constexpr double kInteractiveMs = 100.0;
constexpr const char* kScaleNames = "full resolution\0half resolution\0quarter resolution\0";

/// What the panels edit.
struct PanelState {
    int method = 0;
    splat::RenderSettings settings;
    bool continuous = false;
    int scale = 0;           ///< index into kScales: always
    int navigationScale = 1; ///< index into kScales: while the camera moves or a stroke paints
    int refineFrames = 16;   ///< idle refinement steps (0: off)
    std::string error;       ///< why the last render failed (shown until one succeeds)
};

std::string megabytes(std::uint64_t bytes) {
    char text[32];
    std::snprintf(text, sizeof text, "%.1f MiB", double(bytes) / (1024.0 * 1024.0));
    return text;
}

/// The Render section; returns whether a setting changed (the scene is then rendered again).
bool methodPanel(PanelState& p, const SessionPanels& sections) {
    if (!beginSection("Render", sections))
        return false;
    bool changed = false;
    const auto& methods = splat::gpuMethods();
    ImGui::PushItemWidth(-125.0f);
    if (ImGui::BeginCombo("method", methods[std::size_t(p.method)].name.c_str())) {
        for (int i = 0; i < int(methods.size()); ++i) {
            if (ImGui::Selectable(methods[std::size_t(i)].name.c_str(), i == p.method)) {
                changed |= i != p.method;
                p.method = i;
            }
            if (ImGui::IsItemHovered())
                ImGui::SetTooltip("%s", methods[std::size_t(i)].summary.c_str());
        }
        ImGui::EndCombo();
    }
    const splat::MethodInfo& m = methods[std::size_t(p.method)];
    splat::RenderSettings& s = p.settings;
    changed |= renderSettingsWidgets(m, s); // the settings `m` takes (edit_panels.h)
    ImGui::Separator();
    changed |= ImGui::Checkbox("render every frame", &p.continuous);
    changed |= ImGui::Combo("resolution", &p.scale, kScaleNames);
    ImGui::Combo("moving / painting", &p.navigationScale, kScaleNames);
    changed |= ImGui::SliderInt("refine when idle", &p.refineFrames, 0, 64);
    hint("orbit: middle drag (alt+left)\npan: shift+middle\nzoom: wheel\n"
         "frame the mesh: F or Home\nshow or hide this column: N");
    if (!p.error.empty())
        ImGui::TextColored(ImVec4(1.0f, 0.3f, 0.2f, 1.0f), "%s", p.error.c_str());
    ImGui::PopItemWidth();
    return changed;
}

/// What the Stats section and the status show of the frame.
struct FrameReport {
    const splat::FrameStats* stats = nullptr; ///< the last render (a refinement step's too)
    std::string method;                       ///< the method chosen (the Render section's)
    int renderW = 0, renderH = 0;             ///< the last interactive render's size
    int viewportW = 0, viewportH = 0;
    double frameMs = 0.0, presentMs = 0.0;
    bool scaledUp = false;             ///< rendered smaller while moving or painting
    int refined = 0, refineTarget = 0; ///< refinement steps shown (0: the method's frame)
    bool srgb = true;
    std::string time; ///< an animated scene's time and frame (empty: static)
};

/// The Stats section: the last render's passes, timings and counts.
void statsPanel(const FrameReport& r, const SessionPanels& sections) {
    if (!beginSection("Stats", sections))
        return;
    const splat::FrameStats& st = *r.stats;
    ImGui::Text("last render: %s %s", st.method.c_str(),
                r.refined > 0 ? "(a refinement step)" : "");
    for (const auto& [pass, ms] : st.passMs)
        ImGui::Text("  %-12s %8.2f ms GPU", pass.c_str(), ms);
    ImGui::Text("total GPU      %8.2f ms", st.gpuMs);
    ImGui::Text("render wall    %8.2f ms", st.wallMs);
    ImGui::Text("present+ImGui  %8.2f ms", r.presentMs);
    ImGui::Text("frame          %8.2f ms (%.1f fps)", r.frameMs,
                r.frameMs > 0 ? 1000.0 / r.frameMs : 0.0);
    ImGui::Text("kernels %u generated%s, %u drawn", st.kernelsGenerated,
                st.regenerated ? " (new)" : "", st.counters.kernelsDrawn);
    ImGui::Text("cells %u of %u visible", st.cellsGenerated, st.visibleCells);
    ImGui::Text("GPU memory %s (peak)", megabytes(st.gpuMemoryBytes).c_str());
    if (!r.srgb)
        ImGui::TextColored(ImVec4(1, 0.5f, 0.2f, 1), "no sRGB swapchain: shown linear (dark)");
}

/// The status at the foot of the column, always shown: the method chosen and the last frame's
/// time (a refinement step's, when that was the last), then what the viewport shows: that method's
/// frame (its size, scaled up or not) or the idle refinement's average of jittered `sorted` frames,
/// with its progress.
std::string statusText(const FrameReport& r) {
    char rate[48];
    std::snprintf(rate, sizeof rate, "%.0f ms (%.1f fps)", r.frameMs,
                  r.frameMs > 0 ? 1000.0 / r.frameMs : 0.0);
    std::string text = cat("method ", r.method, "  last frame ", rate, "\n");
    if (!r.time.empty())
        text += r.time + "\n";
    text += "shown: ";
    if (r.refined > 0)
        text += cat(r.refined < r.refineTarget ? "refining " : "refined ", r.refined, "/",
                    r.refineTarget, ", an average of jittered sorted frames");
    else
        text += cat(r.method, " ", r.renderW, "x", r.renderH,
                    r.renderW == r.viewportW && r.renderH == r.viewportH ? ""
                    : r.scaledUp ? " scaled up while moving or painting"
                                 : " scaled up");
    return text;
}

/// The idle refinement: the running average of jittered full-resolution frames, on the host
/// and uploaded for the present to blit like a renderer's result.
struct Refinement {
    int count = 0; ///< frames averaged (0: not refining; the interactive frame is shown)
    std::vector<glm::vec3> sum;
    std::vector<float> alphaSum; ///< the coverage's, averaged alike (the export keeps alpha)
    noise::Image average;
    UploadedImage uploaded;
    const splat::Image& image() const { return uploaded.image; }

    void add(splat::Context& ctx, const noise::Image& frame) {
        if (count == 0 || average.width != frame.width || average.height != frame.height) {
            count = 0;
            sum.assign(frame.pixels.size(), glm::vec3(0.0f));
            alphaSum.assign(frame.alpha.size(), 0.0f);
            average = noise::Image(frame.width, frame.height);
            average.alpha.assign(frame.alpha.size(), 0.0f);
            average.background = frame.background;
        }
        ++count;
        const float inv = 1.0f / float(count);
        for (std::size_t i = 0; i < sum.size(); ++i) {
            sum[i] += frame.pixels[i];
            average.pixels[i] = sum[i] * inv;
        }
        for (std::size_t i = 0; i < alphaSum.size() && i < frame.alpha.size(); ++i) {
            alphaSum[i] += frame.alpha[i];
            average.alpha[i] = alphaSum[i] * inv;
        }
        uploaded.upload(ctx, average, "idle refinement");
    }
};

/// A live preview of one kernel: one impulse of the session's kernel standing on a plane, seen
/// from the side (orthographic), rendered by the `instanced` splatting renderer into a small
/// image whenever the kernel changes. Its own SceneGpu (the plane and the kernel's lobes), so
/// the session's frame and its targets are untouched. The impulse is scaled to fill the view
/// and its weight divided by the same factor, so its optical depth is the scene's at the
/// preset's constant scale.
class KernelPreview {
public:
    static constexpr int kSize = SessionPanels::kPreviewSize;

    /// Render again when the kernel's JSON changed; the image to show.
    const splat::Image& update(splat::Context& ctx, const edit::Session& session) {
        const nlohmann::json kernel = session.get("kernel");
        if (kernel == m_kernel && m_uploaded.image.handle() != VK_NULL_HANDLE)
            return m_uploaded.image;
        const auto start = Clock::now();
        m_kernel = kernel;
        const noise::Kernel& k = session.generator().kernel();
        m_renderer.reset();
        m_scene = std::make_unique<splat::SceneGpu>(ctx, m_plane, k);
        m_renderer = splat::makeSplattingRenderer(*m_scene, splat::Method::Instanced);
        // The kernel's extent in kernel units (3 sigma around each lobe).
        float top = 1e-3f, side = 1e-3f;
        for (const noise::LobeDesc& l : session.preset().kernel.lobes) {
            top = std::max(top, l.offset.z + 3.0f * l.sigma.z);
            side = std::max({side, std::abs(l.offset.x) + 3.0f * l.sigma.x,
                             std::abs(l.offset.y) + 3.0f * l.sigma.y});
        }
        const float scale = 1.6f / std::max(top, 2.0f * side);
        const noise::FieldDesc& s = session.preset().scale;
        const float sceneScale =
            s.kind == noise::FieldDesc::Kind::Constant ? std::max(s.value.x, 1e-6f) : 0.02f;
        noise::Impulse impulse;
        impulse.normal = glm::vec3(0, 1, 0);
        impulse.comb = glm::vec3(1, 0, 0);
        // Kernel space x (comb), y (bitangent), z (normal) in world.
        impulse.frame = glm::mat3(glm::vec3(1, 0, 0), glm::vec3(0, 0, -1), glm::vec3(0, 1, 0));
        impulse.scale = glm::vec3(scale);
        impulse.weight = sceneScale / scale;
        const std::vector<gpu::SpotImpulse> g = gpu::toGpu(std::vector<noise::Impulse>{impulse});
        m_impulses =
            splat::Buffer(ctx, sizeof(gpu::SpotImpulse), VK_BUFFER_USAGE_STORAGE_BUFFER_BIT,
                          splat::Buffer::Memory::HostVisible, "kernel preview impulse");
        m_impulses.upload(std::span<const gpu::SpotImpulse>(g));
        noise::Camera camera;
        camera.projection = noise::Projection::Orthographic;
        camera.eye = glm::dvec3(0.0, 1.2, 5.0);
        camera.target = glm::dvec3(0.0, 0.85, 0.0);
        camera.orthoHeight = 2.0;
        camera.width = camera.height = kSize;
        const noise::SceneDesc& scene = session.scene();
        const noise::Image image = splat::renderImpulses(
            ctx, *m_renderer, splat::View{camera, scene.shading, scene.background, scene.baseColor},
            m_impulses, 1, splat::RenderSettings{});
        m_uploaded.upload(ctx, image, "kernel preview");
        lastMs = msSince(start);
        return m_uploaded.image;
    }
    double lastMs = 0.0; ///< the last render, milliseconds

private:
    noise::Mesh m_plane = noise::loadMeshOrGenerated("generated:plane");
    nlohmann::json m_kernel;
    std::unique_ptr<splat::SceneGpu> m_scene;
    std::unique_ptr<splat::SplattingRenderer> m_renderer;
    splat::Buffer m_impulses;
    UploadedImage m_uploaded;
};

int methodIndex(const std::string& name) {
    const auto& methods = splat::gpuMethods();
    return int(&splat::gpuMethod(name) - methods.data());
}

/// The Save / Discard / Cancel modal, opened when the window was asked to close with unsaved
/// changes.
QuitAnswer quitModal(InputState& input, const SessionPanels& panels) {
    if (input.closeRequested) {
        ImGui::OpenPopup("Unsaved changes");
        input.closeRequested = false;
    }
    QuitAnswer answer = QuitAnswer::None;
    if (ImGui::BeginPopupModal("Unsaved changes", nullptr, ImGuiWindowFlags_AlwaysAutoResize)) {
        ImGui::Text("The preset has unsaved changes.\nSave them to %s first?",
                    panels.savePath.c_str());
        if (ImGui::Button("Save"))
            answer = QuitAnswer::Save;
        ImGui::SameLine();
        if (ImGui::Button("Discard"))
            answer = QuitAnswer::Discard;
        ImGui::SameLine();
        if (ImGui::Button("Cancel"))
            answer = QuitAnswer::Cancel;
        if (answer != QuitAnswer::None)
            ImGui::CloseCurrentPopup();
        ImGui::EndPopup();
    }
    return answer;
}

/// The Render panel's state from the command line's options.
PanelState initialPanel(const EditWindowOptions& options) {
    PanelState panel;
    panel.method = methodIndex(options.method);
    panel.settings = options.settings;
    panel.continuous = options.frames > 0;
    panel.refineFrames = options.refineFrames;
    panel.scale = int(std::find(std::begin(kScales), std::end(kScales), options.renderScale) -
                      std::begin(kScales));
    if (panel.scale == int(std::size(kScales)))
        throw InputError(cat("render scale ", options.renderScale, " must be 1, 2 or 4"));
    return panel;
}

/// What one pass of the window's loop decided, shared by its steps.
struct FrameState {
    Clock::time_point start;
    WindowLayout layout;                    ///< the viewport and the column in the swapchain
    int fullW = 0, fullH = 0;               ///< the viewport's size (full resolution)
    std::optional<glm::vec2> scriptPointer; ///< the script's stroke point this frame
    bool stroking = false, lowRes = false;
    double overlayMs = 0.0;
    bool last = false;     ///< the last of options.frames
    bool warm = true;      ///< the same method and size as the frame before
    bool rendered = false; ///< the scene was rendered (not the overlay alone)
    const splat::Image* shown = nullptr;
};

/// The window, its session and everything the loop keeps between frames. Members are destroyed
/// in reverse: the kernel preview and the refinement's images, ImGui, the present's
/// synchronization, the swapchain, the surface, the session (its frame and context), the
/// window, GLFW. The display is checked before anything else is made.
class EditWindow {
public:
    EditWindow(const SessionFactory& makeSession, const EditWindowOptions& options)
        : m_options(options), m_panel(initialPanel(options)),
          m_window(options.width, options.height, options.title),
          m_owned(makeSession(windowContextOptions())), m_session(*m_owned),
          m_ctx(m_session.context()), m_surface(makeSurface(m_ctx, m_window.handle)),
          m_swapchain(m_ctx, m_surface.get()), m_sync(m_ctx), m_view(m_session.camera()) {
        installCallbacks();
        int fbW = 0, fbH = 0;
        glfwGetFramebufferSize(m_window.handle, &fbW, &fbH);
        m_swapchain.recreate(fbW, fbH);
        m_input.resized = false;
        m_imgui.emplace(m_ctx, m_window.handle, m_swapchain);
        m_panels.savePath = cat(m_session.scene().name, "-edited.json");
        m_panels.exportPath = cat(m_session.scene().name, "-view.png");
        if (!options.openPanels.empty())
            m_panels.openAtStart = options.openPanels;
        m_columnWanted = options.column;
        m_navigationScaleChosen = m_panel.navigationScale;
        // The clear colour of the column (under its panels, which are drawn without a
        // background so that the kernel preview blitted into it shows): the panels' own
        // background, already linear for an sRGB swapchain.
        const ImVec4 bg = ImGui::GetStyle().Colors[ImGuiCol_WindowBg];
        m_columnColor = {{bg.x, bg.y, bg.z, 1.0f}};
    }

    EditWindowReport run() {
        m_lastTick = Clock::now();
        while (!glfwWindowShouldClose(m_window.handle) && !m_quit) {
            if (m_options.frames > 0 && m_report.frames >= m_options.frames && scriptDone() &&
                refinementDone(m_refine.count))
                break;
            FrameState f;
            f.start = Clock::now();
            if (!pollEvents(f))
                continue;
            scriptedNavigation();
            f.scriptPointer = scriptStep(f);
            advanceTime();
            f.stroking = m_input.drag == Drag::Brush || m_strokePoint > 0;
            const bool navigating =
                m_input.drag == Drag::Orbit || m_input.drag == Drag::Pan ||
                m_input.drag == Drag::Light ||
                std::chrono::duration<double>(Clock::now() - m_input.lastMotion).count() < 0.3;
            f.lowRes = navigating || f.stroking;
            buildOverlay(f);
            if (!renderScene(f))
                continue;
            presentFrame(f);
            countFrame(f);
        }
        vkDeviceWaitIdle(m_ctx.device());
        writeScreenshots();
        return finalReport();
    }

private:
    bool scriptDone() const { return m_scriptNext >= m_options.script.size(); }
    /// With --frames, the run waits for the idle refinement's steps too (none while the wind
    /// animates: it never rests).
    bool refinementDone(int steps) const {
        return m_panel.refineFrames == 0 || steps >= m_panel.refineFrames || m_session.wind() ||
               m_panels.playing;
    }
    const std::string& methodName() const {
        return splat::gpuMethods()[std::size_t(m_panel.method)].name;
    }

    void installCallbacks() {
        m_input.view = &m_view;
        m_input.session = &m_session;
        m_input.sphere = boundingSphere(m_session.mesh());
        glfwSetWindowUserPointer(m_window.handle, &m_input);
        glfwSetMouseButtonCallback(m_window.handle, onMouseButton);
        glfwSetCursorPosCallback(m_window.handle, onCursor);
        glfwSetScrollCallback(m_window.handle, onScroll);
        glfwSetKeyCallback(m_window.handle, onKey);
        glfwSetFramebufferSizeCallback(m_window.handle, onFramebufferSize);
        glfwSetWindowCloseCallback(m_window.handle, onClose);
    }

    /// Events (waiting a little when idle), then the swapchain for the window's size; false
    /// when there is nothing to draw into (minimized, or the swapchain not recreated).
    bool pollEvents(FrameState& f) {
        const bool busy = m_panel.continuous || m_input.drag != Drag::None || !scriptDone() ||
                          m_session.wind() || m_panels.playing ||
                          (m_panel.refineFrames > 0 && m_refine.count < m_panel.refineFrames);
        if (busy)
            glfwPollEvents();
        else
            glfwWaitEventsTimeout(0.25); // idle: redraw the overlay a few times a second
        int fbW = 0, fbH = 0;
        glfwGetFramebufferSize(m_window.handle, &fbW, &fbH);
        if (fbW == 0 || fbH == 0) { // minimized
            glfwWaitEvents();
            return false;
        }
        if (m_input.resized) {
            if (!m_swapchain.recreate(fbW, fbH))
                return false;
            ImGui_ImplVulkan_SetMinImageCount(m_swapchain.minImageCount);
            m_input.resized = false;
        }
        const int width = int(m_swapchain.extent.width), height = int(m_swapchain.extent.height);
        if (m_input.togglePanels) {
            m_columnWanted = !m_input.layout.columnShown();
            m_input.togglePanels = false;
        }
        f.layout =
            windowLayout(width, height, m_columnWanted.value_or(width >= kColumnMinWindowWidth));
        if (f.layout.viewportWidth != m_input.layout.viewportWidth ||
            f.layout.height != m_input.layout.height)
            m_input.sceneDirty = true; // the viewport changed size
        m_input.layout = f.layout;
        f.fullW = f.layout.viewportWidth;
        f.fullH = f.layout.viewportHeight();
        return true;
    }

    /// --cycle-methods and --orbit.
    void scriptedNavigation() {
        const auto& methods = splat::gpuMethods();
        if (m_options.cycleMethods) {
            int next = m_report.frames % int(methods.size());
            if (methods[std::size_t(next)].takes(splat::settings::bake) && !m_panel.settings.bake)
                next = 0; // `baked` needs a bake file (--bake)
            m_input.sceneDirty |= next != m_panel.method;
            m_panel.method = next;
        }
        // From the second frame to the last of --frames (the refinement it waits for then rests).
        if (m_options.orbitDegreesPerFrame != 0.0 && m_report.frames > 0 &&
            m_report.frames < m_options.frames) {
            m_view.orbit(m_options.orbitDegreesPerFrame, 0.0, 180.0); // 180 pixels: half a turn
            m_input.moved();
        }
    }

    /// The script: one action between two frames; a stroke one pointer event per frame. Returns
    /// the stroke's pointer this frame (for the brush's circle).
    std::optional<glm::vec2> scriptStep(const FrameState& f) {
        if (scriptDone())
            return std::nullopt;
        const edit::ScriptAction& a = m_options.script[m_scriptNext];
        if (a.type == edit::ScriptAction::Type::Stroke)
            return scriptStrokeStep(a);
        // The window's view, so that `screenshot` and `frames` show what it shows.
        m_session.setCamera(m_view.camera(f.fullW, f.fullH));
        edit::runScriptAction(m_session, a, m_options.scriptName, m_options.log, m_scriptReport);
        ++m_scriptNext;
        m_lastScriptAction = &a; // a render that fails next names this line
        m_panel.method = methodIndex(m_session.method());
        m_panel.settings = m_session.settings();
        const noise::Camera now = m_session.camera(), shown = m_view.camera(f.fullW, f.fullH);
        if (now.eye != shown.eye || now.target != shown.target || now.fovYDeg != shown.fovYDeg)
            m_view = OrbitView(now);
        m_input.sceneDirty = true;
        return std::nullopt;
    }

    /// One pointer event of the script's stroke `a`: the press, a drag, or the release.
    glm::vec2 scriptStrokeStep(const edit::ScriptAction& a) {
        using Phase = edit::Session::PointerPhase;
        const std::size_t i = std::min(m_strokePoint, a.points.size() - 1);
        const Phase phase = m_strokePoint == 0                ? Phase::Press
                            : m_strokePoint < a.points.size() ? Phase::Drag
                                                              : Phase::Release;
        try {
            if (!m_input.pendingBrush && phase != Phase::Release)
                m_input.pendingBrush = Clock::now();
            m_session.pointer(phase, a.points[i], m_input.viewCamera());
        } catch (const InputError& e) {
            throw InputError(edit::scriptLineError(m_options.scriptName, a, e.what()));
        }
        m_lastScriptAction = &a;
        m_input.sceneDirty = true;
        if (phase == Phase::Release) {
            ++m_scriptReport.strokes;
            ++m_scriptNext;
            m_strokePoint = 0;
            if (m_options.log)
                std::fprintf(m_options.log, "%4d  %s\n", a.line, a.text.c_str());
        } else {
            ++m_strokePoint;
        }
        return a.points[i];
    }

    /// The time: the timeline plays by the wall-clock time since the last frame (space and the
    /// Play button toggle it, left and right step a frame); else the comb's wind animates it
    /// (1/30 s a frame when scripted).
    void advanceTime() {
        const Clock::time_point now = Clock::now();
        const double tick = std::chrono::duration<double>(now - m_lastTick).count();
        m_lastTick = now;
        const bool animated = m_session.animated();
        if (m_input.playPause && animated)
            m_panels.playing = !m_panels.playing;
        m_input.playPause = false;
        if (m_input.stepFrames != 0 && animated) {
            const edit::Timeline line = m_session.timeline();
            m_session.setTime(
                std::clamp(double(m_session.frameNumber() + m_input.stepFrames) / line.fps,
                           line.start, line.end));
            m_input.sceneDirty = true;
        }
        m_input.stepFrames = 0;
        if (m_panels.playing && !animated)
            m_panels.playing = false;
        if (m_panels.playing && !m_wasPlaying) {
            // Play from where the time is (from the start when it stopped at the end).
            const edit::Timeline line = m_session.timeline();
            if (m_session.animation().animated() && !m_session.loop() &&
                m_session.time() >= line.end)
                m_session.setTime(line.start);
            m_input.sceneDirty = true;
        } else if (m_panels.playing) {
            m_panels.playing = m_session.advance(tick);
            m_input.sceneDirty = true;
        } else if (m_session.wind() && scriptDone()) {
            m_session.setTime(m_session.time() + (m_options.frames > 0 ? 1.0 / 30.0 : tick));
            m_input.sceneDirty = true;
        }
        m_wasPlaying = m_panels.playing;
    }

    /// The ImGui frame: the column (the Render section, the session's sections, Stats, and the
    /// status at its foot; edits reach the session), F12's export, the quit modal and the brush
    /// circle.
    void buildOverlay(FrameState& f) {
        const auto overlayStart = Clock::now();
        ImGui_ImplVulkan_NewFrame();
        ImGui_ImplGlfw_NewFrame();
        ImGui::NewFrame();
        if (!m_input.error.empty()) {
            m_panels.message = m_input.error;
            m_panels.messageIsError = true;
            m_input.error.clear();
        }
        m_panels.previewShown = false;
        if (f.layout.columnShown())
            drawColumn(f);
        if (m_input.exportRequested)
            exportView();
        const QuitStep quitting = quitStep(m_session.dirty(), false, quitModal(m_input, m_panels));
        if (quitting.close && (!quitting.save || saveSession(m_session, m_panels)))
            m_quit = true;
        drawBrush(f);
        ImGui::Render();
        f.overlayMs = msSince(overlayStart);
    }

    /// The panels' column right of the viewport: one ImGui window without a background (the
    /// present clears the column to the panels' colour, and the kernel preview is blitted into
    /// it), its sections in a scrolling child, the status at its foot.
    void drawColumn(const FrameState& f) {
        const WindowLayout& l = f.layout;
        ImGui::SetNextWindowPos(ImVec2(float(l.viewportWidth), 0.0f));
        ImGui::SetNextWindowSize(ImVec2(float(l.columnWidth), float(l.height)));
        ImGui::SetNextWindowBgAlpha(0.0f);
        ImGui::Begin("##column", nullptr,
                     ImGuiWindowFlags_NoTitleBar | ImGuiWindowFlags_NoResize |
                         ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoCollapse |
                         ImGuiWindowFlags_NoSavedSettings | ImGuiWindowFlags_NoBringToFrontOnFocus);
        const FrameReport report = frameReport(f);
        const std::string status = statusText(report);
        // The status's lines, wrapped to the column, and a separator above them.
        const float statusHeight =
            ImGui::CalcTextSize(status.c_str(), nullptr, false, ImGui::GetContentRegionAvail().x)
                .y +
            2.0f * ImGui::GetStyle().ItemSpacing.y + 4.0f;
        ImGui::BeginChild("##sections", ImVec2(0.0f, -statusHeight));
        m_input.sceneDirty |= timelinePanel(m_session, m_panels);
        const int methodShown = m_panel.method;
        m_input.sceneDirty |= methodPanel(m_panel, m_panels);
        if (m_panel.navigationScale != m_navigationScaleChosen || m_panel.method != methodShown) {
            m_navigationScaleChosen = m_panel.navigationScale;
            m_movingScale = 0;
        }
        // The panels' Export renders the view as the window shows it.
        m_session.setMethod(methodName(), m_panel.settings);
        m_session.setCamera(m_view.camera(f.fullW, f.fullH));
        m_input.sceneDirty |= sessionPanels(m_session, m_panels);
        statsPanel(report, m_panels);
        ImGui::EndChild();
        ImGui::Separator();
        ImGui::TextWrapped("%s", status.c_str());
        ImGui::End();
    }

    FrameReport frameReport(const FrameState& f) const {
        FrameReport r;
        r.stats = &m_stats;
        r.method = methodName();
        r.renderW = m_renderW;
        r.renderH = m_renderH;
        r.viewportW = f.fullW;
        r.viewportH = f.fullH;
        r.frameMs = m_lastFrameMs;
        r.presentMs = m_lastPresentMs;
        r.scaledUp = f.lowRes && std::max(m_panel.navigationScale, m_movingScale) > m_panel.scale;
        // The panels are built before the frame renders: what this frame will show (one more
        // refinement step, unless a change since resets it; the status is then current).
        const bool change = sceneChanges(f);
        r.refined = m_panel.refineFrames == 0 || change ? 0
                    : refinesNext(f, change)            ? m_refine.count + 1
                                                        : m_refine.count;
        r.refineTarget = m_panel.refineFrames;
        r.srgb = m_swapchain.srgb;
        if (m_session.animated()) {
            char time[96];
            std::snprintf(time, sizeof time, "time %.3f s  frame %ld%s", m_session.time(),
                          m_session.frameNumber(), m_panels.playing ? "  playing" : "");
            r.time = time;
        }
        return r;
    }

    /// F12: what the File panel's Export does.
    void exportView() {
        m_input.exportRequested = false;
        try {
            m_session.setMethod(methodName(), m_panel.settings);
            m_session.setCamera(
                m_view.camera(m_input.layout.viewportWidth, m_input.layout.viewportHeight()));
            m_session.exportImage(m_panels.exportPath);
            m_panels.message = "wrote " + m_panels.exportPath;
            m_panels.messageIsError = false;
        } catch (const InputError& e) {
            m_panels.message = e.what();
            m_panels.messageIsError = true;
        }
    }

    /// The brush under the pointer (or the script's pointer) when it is over the viewport.
    void drawBrush(const FrameState& f) {
        const ImVec2 mouse = ImGui::GetIO().MousePos;
        const bool overScene = !ImGui::GetIO().WantCaptureMouse && ImGui::IsMousePosValid() &&
                               f.layout.inViewport(mouse.x, mouse.y);
        if (f.scriptPointer ||
            (overScene && m_input.drag != Drag::Orbit && m_input.drag != Drag::Pan &&
             m_input.drag != Drag::Light)) {
            const ImVec2 at =
                f.scriptPointer ? ImVec2(f.scriptPointer->x, f.scriptPointer->y) : mouse;
            // Clipped to the viewport: the circle never reaches into the column.
            ImDrawList* draw = ImGui::GetBackgroundDrawList();
            draw->PushClipRect(ImVec2(0.0f, 0.0f),
                               ImVec2(float(f.layout.viewportWidth), float(f.layout.height)));
            draw->AddCircle(at, m_session.brush().radiusPx, IM_COL32(255, 255, 255, 200), 48, 1.5f);
            draw->PopClipRect();
        }
    }

    /// Whether this frame renders the scene anew: something changed, or navigation or a stroke
    /// ended (back to the resolution chosen).
    bool sceneChanges(const FrameState& f) const {
        const bool resolution = !f.lowRes && m_scene && m_refine.count == 0 &&
                                (m_renderW != std::max(1, f.fullW / kScales[m_panel.scale]) ||
                                 m_renderH != std::max(1, f.fullH / kScales[m_panel.scale]));
        return m_input.sceneDirty || !m_scene || resolution;
    }

    /// Whether this frame is one more refinement step: nothing changed, not moving or painting,
    /// steps left, the wind off.
    bool refinesNext(const FrameState& f, bool change) const {
        return !change && !f.lowRes && m_panel.refineFrames > 0 &&
               m_refine.count < m_panel.refineFrames && !m_session.wind() && !m_panels.playing;
    }

    /// The scene for this frame: one more refinement step when idle, a render when something
    /// changed (or every frame when asked), else the last image. False when the method refused
    /// the settings interactively (the frame is dropped; the panel shows why).
    bool renderScene(FrameState& f) {
        const bool change = sceneChanges(f);
        if (change)
            m_refine.count = 0;
        const bool refineNow = refinesNext(f, change);
        f.last = m_options.frames > 0 && scriptDone() && m_report.frames + 1 >= m_options.frames &&
                 refinementDone(m_refine.count + (refineNow ? 1 : 0));
        f.shown = m_refine.count > 0 ? &m_refine.image() : m_scene;
        if (refineNow)
            refineStep(f);
        else if (change || (m_panel.continuous && m_refine.count == 0))
            return renderInteractive(f);
        return true;
    }

    /// One more jittered frame of the most accurate method into the running average.
    void refineStep(FrameState& f) {
        const auto refineStart = Clock::now();
        // Without EWA: the average of the jittered point-sampled frames is the box-filtered
        // image; EWA's widened kernels would blur it twice.
        splat::RenderSettings refineSettings = m_panel.settings;
        refineSettings.ewa = false;
        m_session.setMethod("sorted", refineSettings);
        const glm::dvec2 jitter = haltonJitter(m_refine.count);
        m_session.setCamera(jitteredCamera(m_view.camera(f.fullW, f.fullH), jitter.x, jitter.y));
        noise::Image image;
        m_stats = m_session.render(&image);
        const auto addStart = Clock::now();
        m_refine.add(m_ctx, image);
        m_refineAddMs.push_back(msSince(addStart));
        m_refineMs.push_back(msSince(refineStart));
        ++m_report.refined;
        m_renderW = f.fullW;
        m_renderH = f.fullH;
        f.shown = &m_refine.image();
        f.warm = false;
        m_renderedWith = "refine";
    }

    /// The chosen method at the interactive resolution (lower while moving or painting).
    bool renderInteractive(FrameState& f) {
        const int scale =
            kScales[f.lowRes ? std::max({m_panel.scale, m_panel.navigationScale, m_movingScale})
                             : m_panel.scale];
        m_renderW = std::max(1, f.fullW / scale);
        m_renderH = std::max(1, f.fullH / scale);
        noise::Image image;
        // --screenshot is the viewport at full resolution: the frame itself when it is that.
        const bool capture =
            f.last && !m_options.screenshot.empty() && m_renderW == f.fullW && m_renderH == f.fullH;
        const std::string& method = methodName();
        const auto renderStart = Clock::now();
        try {
            m_session.setMethod(method, m_panel.settings);
            m_session.setCamera(m_view.camera(m_renderW, m_renderH));
            m_stats = m_session.render(capture ? &image : nullptr);
            m_panel.error.clear();
        } catch (const InputError& e) {
            // Interactively, a setting the method refuses (or a frame beyond the memory
            // budget) is shown in the panel; scripted, it fails. The session may have
            // rebuilt its frame: the last image is gone.
            if (!m_scene || m_options.frames > 0) {
                // The script line that asked for it (a method or setting the frame refuses).
                if (m_lastScriptAction)
                    throw InputError(
                        edit::scriptLineError(m_options.scriptName, *m_lastScriptAction, e.what()));
                throw;
            }
            m_panel.error = e.what();
            m_input.sceneDirty = false;
            m_scene = nullptr;
            ImGui::EndFrame();
            return false;
        }
        const double renderWall = msSince(renderStart);
        m_lastScriptAction = nullptr;
        m_report.renderWidth = m_renderW;
        m_report.renderHeight = m_renderH;
        if (capture)
            m_screenshot = std::move(image);
        m_scene = &m_session.frame().renderer(method).result();
        f.shown = m_scene;
        m_input.sceneDirty = false;
        f.rendered = true;
        ++m_report.rendered;
        // Warm: the same method at the same size as the last render (the first frame after
        // a change creates targets and compiles pipelines).
        const std::string key = cat(method, " ", m_renderW, "x", m_renderH);
        f.warm = key == m_renderedWith;
        m_renderedWith = key;
        if (f.warm)
            m_renderMs.push_back(renderWall);
        return true;
    }

    /// Blit the scene (and the kernel preview), draw the panels, present; read the window back
    /// for --window-screenshot on the last frame.
    void presentFrame(FrameState& f) {
        if (f.last && !m_options.screenshot.empty() && m_refine.count > 0)
            m_screenshot = m_refine.average;
        const auto presentStart = Clock::now();
        const bool grab = f.last && !m_options.windowScreenshot.empty();
        if (grab && !m_swapchain.readable)
            throw std::runtime_error("--window-screenshot: the window's images cannot be read back "
                                     "on this surface");
        // The kernel preview where the Kernel section left room for it, when all of it is in
        // view (rendered again when the kernel changed).
        const splat::Image* inset = nullptr;
        const VkOffset2D insetAt{int(std::lround(m_panels.previewAt.x)),
                                 int(std::lround(m_panels.previewAt.y))};
        if (m_panels.previewShown && insetAt.x >= f.layout.viewportWidth &&
            insetAt.x + KernelPreview::kSize <= f.layout.width && insetAt.y >= 0 &&
            insetAt.y + KernelPreview::kSize <= f.layout.height) {
            try {
                inset = &m_preview.update(m_ctx, m_session);
                m_report.previewX = insetAt.x;
                m_report.previewY = insetAt.y;
            } catch (const InputError& e) {
                m_panels.message = e.what();
                m_panels.messageIsError = true;
            }
        }
        const VkExtent2D viewport{std::uint32_t(f.layout.viewportWidth),
                                  std::uint32_t(f.layout.height)};
        if (!present(m_ctx, m_swapchain, m_sync, *f.shown, viewport, m_columnColor,
                     grab ? &m_windowGrab : nullptr, inset, insetAt))
            m_input.resized = true;
        if (grab)
            m_windowImage = m_windowGrab.read(m_swapchain.srgb);
        m_lastPresentMs = msSince(presentStart);
        m_lastFrameMs = msSince(f.start);
    }

    /// The frame's timings, and the resolution while moving lowered when those frames are slow.
    void countFrame(const FrameState& f) {
        if (f.rendered && m_input.pendingBrush) {
            m_report.strokeToFrameMs.push_back(msSince(*m_input.pendingBrush));
            m_input.pendingBrush.reset();
        }
        if (f.rendered && f.stroking && f.warm)
            m_strokeFrameMs.push_back(m_lastFrameMs);
        if (f.rendered && f.lowRes && f.warm)
            adaptMovingScale();
        if (f.warm && m_report.frames > 0) {
            m_presentMs.push_back(m_lastPresentMs);
            m_frameMs.push_back(m_lastFrameMs);
            m_overlayMs.push_back(f.overlayMs);
        }
        ++m_report.frames;
        if (m_report.frames == 1 && m_options.resizeWidth > 0 && m_options.resizeHeight > 0)
            glfwSetWindowSize(m_window.handle, m_options.resizeWidth, m_options.resizeHeight);
    }

    /// Moving or painting below 10 frames a second (the median of five such frames, twice in a
    /// row: not the rebuild after a parameter edit): a lower resolution for the rest of the
    /// session (a quarter at most); the Render panel's choice resets it.
    void adaptMovingScale() {
        m_recentLowMs.push_back(m_lastFrameMs);
        if (m_recentLowMs.size() < 5)
            return;
        m_slowWindows = median(m_recentLowMs) > kInteractiveMs ? m_slowWindows + 1 : 0;
        if (m_slowWindows == 2 && m_movingScale < int(std::size(kScales)) - 1) {
            m_movingScale = std::max(m_movingScale, m_panel.navigationScale) + 1;
            m_slowWindows = 0;
        }
        m_recentLowMs.clear();
    }

    /// --screenshot (the scene; rendered now when the user closed the window) and
    /// --window-screenshot.
    void writeScreenshots() {
        if (!m_options.screenshot.empty()) {
            // The viewport at full resolution, whatever the render scale: when the last frame
            // was rendered smaller (the render scale, moving or painting) or the user closed
            // the window, the view as it was last shown, rendered again at that size.
            const int w = m_input.layout.viewportWidth, h = m_input.layout.viewportHeight();
            if (!m_screenshot || m_screenshot->width != w || m_screenshot->height != h) {
                m_session.setMethod(methodName(), m_panel.settings);
                m_session.setCamera(m_view.camera(w, h));
                noise::Image image;
                m_session.render(&image);
                m_screenshot = std::move(image);
            }
            noise::writeImage(
                m_options.screenshot, *m_screenshot,
                {{"method", m_refine.count > 0 ? std::string("sorted (refined)") : methodName()},
                 {"scene", m_session.scene().name}});
        }
        if (m_windowImage)
            noise::writeImage(m_options.windowScreenshot, *m_windowImage,
                              {{"scene", m_session.scene().name}});
    }

    /// The medians, and validation's verdict (errors throw).
    EditWindowReport finalReport() {
        const splat::ValidationCounts v = m_ctx.validation();
        if (v.errors > 0)
            throw std::runtime_error(
                cat(v.errors, " Vulkan validation errors, first: ", v.firstError));
        EditWindowReport report = m_report;
        report.validation = m_ctx.validationEnabled();
        report.validationWarnings = v.warnings;
        report.warmFrames = int(m_frameMs.size());
        report.frameMs = median(m_frameMs);
        report.renderMs = median(m_renderMs);
        report.presentMs = median(m_presentMs);
        report.overlayMs = median(m_overlayMs);
        report.refineMs = median(m_refineMs);
        report.refineAverageMs = median(m_refineAddMs);
        report.previewMs = m_preview.lastMs;
        report.strokeFrameMs = median(m_strokeFrameMs);
        report.strokeFrames = int(m_strokeFrameMs.size());
        report.lowScale = kScales[std::max(m_panel.navigationScale, m_movingScale)];
        report.windowWidth = m_input.layout.width;
        report.windowHeight = m_input.layout.height;
        report.viewportWidth = m_input.layout.viewportWidth;
        report.viewportHeight = m_input.layout.viewportHeight();
        return report;
    }

    const EditWindowOptions& m_options;
    PanelState m_panel;
    GlfwLibrary m_glfw;
    GlfwWindow m_window;
    const std::unique_ptr<edit::Session> m_owned;
    edit::Session& m_session;
    splat::Context& m_ctx;
    const splat::UniqueSurface m_surface;
    Swapchain m_swapchain;
    PresentSync m_sync;
    VkClearColorValue m_columnColor{};  ///< under the panels' column
    std::optional<bool> m_columnWanted; ///< N or --panels (none: by the window's width)
    const edit::ScriptAction* m_lastScriptAction = nullptr; ///< ran since the last render
    OrbitView m_view;
    InputState m_input;
    std::optional<ImGuiLayer> m_imgui;
    SessionPanels m_panels;

    splat::FrameStats m_stats;
    const splat::Image* m_scene = nullptr; ///< the last interactive render (null: none)
    int m_renderW = 0, m_renderH = 0;
    std::string m_renderedWith; ///< method and size of the last render (warm-frame bookkeeping)
    std::vector<double> m_frameMs, m_renderMs, m_presentMs, m_overlayMs, m_refineMs, m_refineAddMs,
        m_strokeFrameMs;
    EditWindowReport m_report;
    double m_lastFrameMs = 0.0, m_lastPresentMs = 0.0;
    std::optional<noise::Image> m_screenshot, m_windowImage;
    WindowGrab m_windowGrab;
    Refinement m_refine;
    KernelPreview m_preview;
    int m_movingScale = 0; ///< index into kScales: lowered when moving frames are too slow
    std::vector<double> m_recentLowMs; ///< the last moving or painting frames' times
    int m_slowWindows = 0;             ///< ... groups of five in a row with a slow median
    int m_navigationScaleChosen = 0;
    edit::ScriptReport m_scriptReport;
    std::size_t m_scriptNext = 0, m_strokePoint = 0; ///< the next action; a stroke's next point
    Clock::time_point m_lastTick;                    ///< the time's last step
    bool m_wasPlaying = false;                       ///< the timeline played last frame
    bool m_quit = false;
};

} // namespace

EditWindowReport runEditWindow(const SessionFactory& makeSession,
                               const EditWindowOptions& options) {
    EditWindow window(makeSession, options);
    return window.run();
}

std::vector<cli::OptionSpec> editWindowOptions() {
    return {
        {"method", "NAME",
         "the method shown first: " + splat::gpuMethodNames() + " (default: --quality " +
             std::string(splat::kDefaultQuality) + "'s method)",
         false},
        cli::qualityOption(),
        {"frames", "N",
         "render N frames (and then the --refine steps), then close (default: until the window "
         "is closed)",
         false},
        {"screenshot", "FILE",
         "write the scene as last shown (without the panels) as .png or .exr when the window "
         "closes, at the viewport's full size whatever the render scale (without a window: the "
         "view after the script, at --size)",
         false},
        {"panels", "LIST",
         "the panels' column: the sections to unfold at first, separated by commas (render, "
         "brush, kernel, distribution, wind, file, stats; or all; default render,brush,file), "
         "or off to hide the column (N shows or hides it; it starts hidden in windows narrower "
         "than 560 pixels unless this is given)",
         false},
        {"window-screenshot", "FILE",
         "with --frames: write the last frame as the window "
         "showed it, panels included",
         false},
        {"render-scale", "N",
         "render at 1/N of the window's size, scaled up: 1 (default), 2 "
         "or 4",
         false},
        {"orbit", "DEG",
         "scripted navigation: orbit by DEG degrees per frame from the second "
         "frame on (times a moving camera)",
         false},
        {"resize", "WxH", "after the first frame, resize the window (scripted checks)", false},
        {"cycle-methods", "",
         "frame i shows method i of the registry, in turn (scripted "
         "checks)",
         false},
        {"refine", "N",
         "when idle, average N jittered full-resolution frames of `sorted` (default 16; 0 "
         "with --frames unless given; with --frames the window waits for them before it closes)",
         false}};
}

EditWindowOptions editWindowOptions(const cli::Args& args, int width, int height,
                                    const std::string& sceneName) {
    EditWindowOptions o;
    o.title = cat("spotshell edit - ", sceneName);
    o.width = width;
    o.height = height;
    const cli::MethodChoice choice = cli::methodChoice(args, "spotshell edit", true);
    o.method = choice.method;
    o.settings = cli::renderSettings(args, choice.settings);
    o.frames = int(args.integer("frames", 0, 0, 1000000));
    // Scripted runs time and compare the interactive frames: no refinement unless asked for.
    o.refineFrames = int(args.integer("refine", o.frames > 0 ? 0 : 16, 0, 1024));
    if (args.has("screenshot"))
        o.screenshot = args.str("screenshot");
    if (args.has("resize")) {
        const std::string size = args.str("resize");
        char x = 0, extra = 0;
        if (std::sscanf(size.c_str(), "%d%c%d%c", &o.resizeWidth, &x, &o.resizeHeight, &extra) !=
                3 ||
            (x != 'x' && x != 'X') || o.resizeWidth < 1 || o.resizeHeight < 1 ||
            o.resizeWidth > 16384 || o.resizeHeight > 16384)
            throw InputError(cat("--resize '", size, "' must be WxH with sides in [1, 16384]"));
    }
    o.cycleMethods = args.has("cycle-methods");
    if (args.has("panels")) {
        const std::string list = args.str("panels");
        const std::vector<std::string>& names = sectionNames();
        if (list == "off") {
            o.column = false;
        } else {
            o.column = true;
            o.openPanels.clear();
            std::stringstream in(list);
            for (std::string name; std::getline(in, name, ',');) {
                if (name == "all")
                    o.openPanels.insert(o.openPanels.end(), names.begin(), names.end());
                else if (std::find(names.begin(), names.end(), name) != names.end())
                    o.openPanels.push_back(name);
                else
                    throw InputError(cat("--panels: '", name,
                                         "' is not a section (render, brush, kernel, "
                                         "distribution, wind, file, stats, all) or off"));
            }
            if (o.openPanels.empty())
                throw InputError("--panels needs a section name, all or off");
        }
    }
    o.orbitDegreesPerFrame = args.number("orbit", 0.0, -180.0, 180.0);
    o.renderScale = int(args.integer("render-scale", 1, 1, 4));
    if (o.renderScale == 3)
        throw InputError("--render-scale must be 1, 2 or 4, not 3");
    if (args.has("window-screenshot")) {
        if (o.frames == 0)
            throw InputError("--window-screenshot needs --frames");
        o.windowScreenshot = args.str("window-screenshot");
    }
    return o;
}

} // namespace spot::editor
