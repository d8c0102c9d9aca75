#include "edit_window.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <optional>
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
    Clock::time_point lastMotion; ///< of the camera (for the lower resolution while navigating)
    /// The first brush event not yet shown (stroke-to-frame is measured from it).
    std::optional<Clock::time_point> pendingBrush;
    std::string error; ///< a brush or key edit the session refused

    noise::Camera windowCamera(GLFWwindow* window) const {
        int w = 0, h = 0;
        glfwGetWindowSize(window, &w, &h);
        return view->camera(std::max(w, 1), std::max(h, 1));
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

void frameMesh(GLFWwindow* window, InputState& s) {
    int w = 0, h = 0;
    glfwGetWindowSize(window, &w, &h);
    s.view->frame(s.sphere, h > 0 ? double(w) / double(h) : 1.0);
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
void applyInput(GLFWwindow* window, InputState& s, const InputAction& a) {
    using T = InputAction::Type;
    using Phase = edit::Session::PointerPhase;
    s.drag = a.drag;
    int w = 0, h = 0;
    glfwGetWindowSize(window, &w, &h);
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
        case T::BrushPress:
        case T::BrushDrag:
        case T::BrushRelease:
            s.brush(a.type == T::BrushPress  ? Phase::Press
                    : a.type == T::BrushDrag ? Phase::Drag
                                             : Phase::Release,
                    s.windowCamera(window), a.x, a.y, a.invert);
            break;
        case T::Undo:
            s.sceneDirty |= s.session->undo();
            break;
        case T::Redo:
            s.sceneDirty |= s.session->redo();
            break;
        case T::FrameMesh:
            frameMesh(window, s);
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
    applyInput(window, s, mapInput(e, inputContext(s, ImGui::GetIO().WantCaptureMouse, false)));
}

void onCursor(GLFWwindow* window, double x, double y) {
    InputState& s = state(window);
    const InputAction a = mapInput(InputEvent::cursor(x, y), inputContext(s, false, false));
    s.lastX = x;
    s.lastY = y;
    s.pointerKnown = true;
    applyInput(window, s, a);
}

void onScroll(GLFWwindow* window, double dx, double dy) {
    InputState& s = state(window);
    applyInput(window, s,
               mapInput(InputEvent::scroll(dx, dy),
                        inputContext(s, ImGui::GetIO().WantCaptureMouse, false)));
}

void onKey(GLFWwindow* window, int key, int, int action, int mods) {
    InputState& s = state(window);
    applyInput(window, s,
               mapInput(InputEvent::key(key, action, mods),
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

/// Returns whether a setting changed (the scene is then rendered again).
bool methodPanel(PanelState& p) {
    bool changed = false;
    const auto& methods = splat::gpuMethods();
    ImGui::SetNextWindowPos(ImVec2(8, 8), ImGuiCond_FirstUseEver);
    ImGui::SetNextWindowSize(ImVec2(300, 0), ImGuiCond_FirstUseEver);
    // A small window shows the scene first: the panel starts folded (below 700 pixels high, to
    // leave the left side to the Brush panel).
    ImGui::SetNextWindowCollapsed(ImGui::GetIO().DisplaySize.x < 640.0f ||
                                      ImGui::GetIO().DisplaySize.y < 700.0f,
                                  ImGuiCond_FirstUseEver);
    ImGui::Begin("Render");
    ImGui::PushItemWidth(150);
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
    ImGui::TextDisabled("orbit: middle drag (alt+left)\npan: shift+middle\nzoom: wheel\n"
                        "frame the mesh: F or Home");
    if (!p.error.empty())
        ImGui::TextColored(ImVec4(1.0f, 0.3f, 0.2f, 1.0f), "%s", p.error.c_str());
    ImGui::PopItemWidth();
    ImGui::End();
    return changed;
}

void statsPanel(const splat::FrameStats& st, int renderW, int renderH, int windowW, int windowH,
                double frameMs, double presentMs, bool navigating, bool srgb,
                const std::string& refining) {
    const ImGuiIO& io = ImGui::GetIO();
    ImGui::SetNextWindowPos(ImVec2(io.DisplaySize.x - 8, io.DisplaySize.y - 8), ImGuiCond_Always,
                            ImVec2(1, 1));
    // The status line below says what matters; the details start folded in a small window.
    ImGui::SetNextWindowCollapsed(io.DisplaySize.x < 640.0f || io.DisplaySize.y < 700.0f,
                                  ImGuiCond_FirstUseEver);
    ImGui::SetNextWindowBgAlpha(0.6f);
    ImGui::Begin("Stats", nullptr,
                 ImGuiWindowFlags_AlwaysAutoResize | ImGuiWindowFlags_NoMove |
                     ImGuiWindowFlags_NoFocusOnAppearing | ImGuiWindowFlags_NoNav);
    if (renderW != windowW || renderH != windowH)
        ImGui::Text("%s  %dx%d scaled up%s", st.method.c_str(), renderW, renderH,
                    navigating ? " while moving or painting" : "");
    else
        ImGui::Text("%s  %dx%d", st.method.c_str(), renderW, renderH);
    for (const auto& [pass, ms] : st.passMs)
        ImGui::Text("  %-12s %8.2f ms GPU", pass.c_str(), ms);
    if (!refining.empty())
        ImGui::TextColored(ImVec4(0.5f, 0.8f, 1.0f, 1.0f), "%s", refining.c_str());
    ImGui::Text("total GPU      %8.2f ms", st.gpuMs);
    ImGui::Text("render wall    %8.2f ms", st.wallMs);
    ImGui::Text("present+ImGui  %8.2f ms", presentMs);
    ImGui::Text("frame          %8.2f ms (%.1f fps)", frameMs,
                frameMs > 0 ? 1000.0 / frameMs : 0.0);
    ImGui::Text("kernels %u generated%s, %u drawn", st.kernelsGenerated,
                st.regenerated ? " (new)" : "", st.counters.kernelsDrawn);
    ImGui::Text("cells %u of %u visible", st.cellsGenerated, st.visibleCells);
    ImGui::Text("GPU memory %s (peak)", megabytes(st.gpuMemoryBytes).c_str());
    if (!srgb)
        ImGui::TextColored(ImVec4(1, 0.5f, 0.2f, 1), "no sRGB swapchain: shown linear (dark)");
    ImGui::End();
}

/// One line at the bottom left, always shown: the method, the render size and whether it is
/// scaled up (moving or painting), the frame rate, the refinement's progress.
void statusLine(const splat::FrameStats& st, int renderW, int renderH, int windowW, int windowH,
                double frameMs, bool lowRes, const std::string& refining) {
    std::string text = cat(st.method, " ", renderW, "x", renderH);
    if (renderW != windowW || renderH != windowH)
        text += lowRes ? " scaled up while moving or painting" : " scaled up";
    char rate[48];
    std::snprintf(rate, sizeof rate, "  %.0f ms (%.1f fps)", frameMs,
                  frameMs > 0 ? 1000.0 / frameMs : 0.0);
    text += rate;
    if (!refining.empty())
        text += "  " + refining;
    ImDrawList* draw = ImGui::GetForegroundDrawList();
    const ImVec2 size = ImGui::CalcTextSize(text.c_str());
    const ImVec2 at(8.0f, ImGui::GetIO().DisplaySize.y - size.y - 8.0f);
    draw->AddRectFilled(ImVec2(at.x - 4, at.y - 2), ImVec2(at.x + size.x + 4, at.y + size.y + 2),
                        IM_COL32(0, 0, 0, 150));
    draw->AddText(at, IM_COL32(255, 255, 255, 255), text.c_str());
}

/// The idle refinement: the running average of jittered full-resolution frames, on the host
/// and uploaded for the present to blit like a renderer's result.
struct Refinement {
    int count = 0; ///< frames averaged (0: not refining; the interactive frame is shown)
    std::vector<glm::vec3> sum;
    noise::Image average;
    UploadedImage uploaded;
    const splat::Image& image() const { return uploaded.image; }

    void add(splat::Context& ctx, const noise::Image& frame) {
        if (count == 0 || average.width != frame.width || average.height != frame.height) {
            count = 0;
            sum.assign(frame.pixels.size(), glm::vec3(0.0f));
            average = noise::Image(frame.width, frame.height);
        }
        ++count;
        const float inv = 1.0f / float(count);
        for (std::size_t i = 0; i < sum.size(); ++i) {
            sum[i] += frame.pixels[i];
            average.pixels[i] = sum[i] * inv;
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
    static constexpr int kSize = 160;

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
    int fullW = 0, fullH = 0;               ///< the swapchain's size
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
        m_navigationScaleChosen = m_panel.navigationScale;
    }

    EditWindowReport run() {
        m_lastTick = Clock::now();
        while (!glfwWindowShouldClose(m_window.handle) && !m_quit) {
            if (m_options.frames > 0 && m_report.frames >= m_options.frames && scriptDone())
                break;
            FrameState f;
            f.start = Clock::now();
            if (!pollEvents(f))
                continue;
            scriptedNavigation();
            f.scriptPointer = scriptStep(f);
            advanceWind();
            f.stroking = m_input.drag == Drag::Brush || m_strokePoint > 0;
            const bool navigating =
                m_input.drag == Drag::Orbit || m_input.drag == Drag::Pan ||
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
                          m_session.wind() ||
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
        f.fullW = int(m_swapchain.extent.width);
        f.fullH = int(m_swapchain.extent.height);
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
        if (m_options.orbitDegreesPerFrame != 0.0 && m_report.frames > 0) {
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
            m_session.pointer(phase, a.points[i], m_input.windowCamera(m_window.handle));
        } catch (const InputError& e) {
            throw InputError(cat("script ", m_options.scriptName, ":", a.line, ": ", e.what()));
        }
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

    /// Wind animates: the session's time advances (1/30 s a frame when scripted).
    void advanceWind() {
        const double tick = std::chrono::duration<double>(Clock::now() - m_lastTick).count();
        m_lastTick = Clock::now();
        if (m_session.wind() && scriptDone()) {
            m_session.setTime(m_session.time() + (m_options.frames > 0 ? 1.0 / 30.0 : tick));
            m_input.sceneDirty = true;
        }
    }

    /// The ImGui frame: the panels (whose edits reach the session), F12's export, the quit
    /// modal, the stats, the status line, the brush circle and the kernel preview's frame.
    void buildOverlay(FrameState& f) {
        const auto overlayStart = Clock::now();
        ImGui_ImplVulkan_NewFrame();
        ImGui_ImplGlfw_NewFrame();
        ImGui::NewFrame();
        const int methodShown = m_panel.method;
        m_input.sceneDirty |= methodPanel(m_panel);
        if (m_panel.navigationScale != m_navigationScaleChosen || m_panel.method != methodShown) {
            m_navigationScaleChosen = m_panel.navigationScale;
            m_movingScale = 0;
        }
        if (!m_input.error.empty()) {
            m_panels.message = m_input.error;
            m_panels.messageIsError = true;
            m_input.error.clear();
        }
        // The panels' Export renders the view as the window shows it.
        m_session.setMethod(methodName(), m_panel.settings);
        m_session.setCamera(m_view.camera(f.fullW, f.fullH));
        m_input.sceneDirty |= sessionPanels(m_session, m_panels);
        if (m_input.exportRequested)
            exportView();
        const QuitStep quitting = quitStep(m_session.dirty(), false, quitModal(m_input, m_panels));
        if (quitting.close && (!quitting.save || saveSession(m_session, m_panels)))
            m_quit = true;
        drawStatus(f);
        drawBrushAndPreviewFrame(f);
        ImGui::Render();
        f.overlayMs = msSince(overlayStart);
    }

    /// F12: what the File panel's Export does.
    void exportView() {
        m_input.exportRequested = false;
        try {
            m_session.exportImage(m_panels.exportPath);
            m_panels.message = "wrote " + m_panels.exportPath;
            m_panels.messageIsError = false;
        } catch (const InputError& e) {
            m_panels.message = e.what();
            m_panels.messageIsError = true;
        }
    }

    /// The Stats panel and the status line.
    void drawStatus(const FrameState& f) {
        std::string refining;
        if (m_panel.refineFrames > 0 && m_refine.count > 0)
            refining = m_refine.count < m_panel.refineFrames
                           ? cat("refining ", m_refine.count, "/", m_panel.refineFrames,
                                 " (sorted, jittered)")
                           : cat("refined ", m_refine.count, "/", m_panel.refineFrames,
                                 " (sorted, jittered)");
        const bool scaledUp =
            f.lowRes && std::max(m_panel.navigationScale, m_movingScale) > m_panel.scale;
        statsPanel(m_stats, m_renderW, m_renderH, f.fullW, f.fullH, m_lastFrameMs, m_lastPresentMs,
                   scaledUp, m_swapchain.srgb, refining);
        statusLine(m_stats, m_renderW, m_renderH, f.fullW, f.fullH, m_lastFrameMs, scaledUp,
                   refining);
    }

    /// The brush under the pointer (or the script's pointer), and a frame around the kernel
    /// preview.
    void drawBrushAndPreviewFrame(const FrameState& f) {
        const ImVec2 mouse = ImGui::GetIO().MousePos;
        const bool overScene = !ImGui::GetIO().WantCaptureMouse && ImGui::IsMousePosValid();
        if (f.scriptPointer ||
            (overScene && m_input.drag != Drag::Orbit && m_input.drag != Drag::Pan)) {
            const ImVec2 at =
                f.scriptPointer ? ImVec2(f.scriptPointer->x, f.scriptPointer->y) : mouse;
            ImGui::GetForegroundDrawList()->AddCircle(at, m_session.brush().radiusPx,
                                                      IM_COL32(255, 255, 255, 200), 48, 1.5f);
        }
        if (m_panels.kernelOpen) {
            const float x = float(f.fullW - 330 - 8 - KernelPreview::kSize);
            ImGui::GetForegroundDrawList()->AddRect(
                ImVec2(x - 1, 7), ImVec2(x + KernelPreview::kSize + 1, 9 + KernelPreview::kSize),
                IM_COL32(120, 120, 140, 255));
        }
    }

    /// The scene for this frame: one more refinement step when idle, a render when something
    /// changed (or every frame when asked), else the last image. False when the method refused
    /// the settings interactively (the frame is dropped; the panel shows why).
    bool renderScene(FrameState& f) {
        // Navigation or a stroke ended: back to the resolution chosen.
        if (!f.lowRes && m_scene && m_refine.count == 0 &&
            (m_renderW != std::max(1, f.fullW / kScales[m_panel.scale]) ||
             m_renderH != std::max(1, f.fullH / kScales[m_panel.scale])))
            m_input.sceneDirty = true;
        const bool change = m_input.sceneDirty || !m_scene;
        if (change)
            m_refine.count = 0;
        f.last = m_options.frames > 0 && scriptDone() && m_report.frames + 1 >= m_options.frames;
        const bool refineNow = !change && !f.lowRes && m_panel.refineFrames > 0 &&
                               m_refine.count < m_panel.refineFrames && !m_session.wind();
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
        const bool capture = f.last && !m_options.screenshot.empty();
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
            if (!m_scene || m_options.frames > 0)
                throw;
            m_panel.error = e.what();
            m_input.sceneDirty = false;
            m_scene = nullptr;
            ImGui::EndFrame();
            return false;
        }
        const double renderWall = msSince(renderStart);
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
        // The kernel preview while the Kernel panel is open (rendered again when the kernel
        // changed), left of the panel's place at the top right.
        const splat::Image* inset = nullptr;
        const int insetX = f.fullW - 330 - 8 - KernelPreview::kSize;
        if (m_panels.kernelOpen && insetX >= 8 && f.fullH >= KernelPreview::kSize + 16) {
            try {
                inset = &m_preview.update(m_ctx, m_session);
            } catch (const InputError& e) {
                m_panels.message = e.what();
                m_panels.messageIsError = true;
            }
        }
        if (!present(m_ctx, m_swapchain, m_sync, *f.shown, grab ? &m_windowGrab : nullptr, inset,
                     VkOffset2D{insetX, 8}))
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
            if (!m_screenshot) { // closed by the user: the view as it was last shown
                m_session.setMethod(methodName(), m_panel.settings);
                m_session.setCamera(
                    m_view.camera(int(m_swapchain.extent.width), int(m_swapchain.extent.height)));
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
    Clock::time_point m_lastTick;                    ///< the wind's last time step
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
         "the method shown first: " + splat::gpuMethodNames() + " (default instanced)", false},
        {"frames", "N", "render N frames, then close (default: until the window is closed)", false},
        {"screenshot", "FILE",
         "write the last rendered scene (without the panels) as .png or .exr when the window "
         "closes (without a window: the view after the script)",
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
         "with --frames unless given)",
         false}};
}

EditWindowOptions editWindowOptions(const cli::Args& args, int width, int height,
                                    const std::string& sceneName) {
    EditWindowOptions o;
    o.title = cat("spotshell edit - ", sceneName);
    o.width = width;
    o.height = height;
    o.method = args.str("method", "instanced");
    splat::gpuMethod(o.method); // InputError naming the methods
    o.settings = cli::renderSettings(args);
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
