/// @file edit_window.h
/// @brief The editor's window: a GLFW window with a Vulkan swapchain on splat::Context that shows
/// the scene live through the persistent splat::Frame (the same renderers as `render`), with
/// Blender-like navigation (edit_view.h), Dear ImGui panels (method, settings, stats) and hooks
/// for the painting session: brush pointer events on the left button and extra panels.
///
/// A frame: splat::Frame::render() renders into the method's result image (RGBA32F, linear) and
/// waits; a second command buffer blits it into the swapchain image (an sRGB format, so the blit
/// encodes; scaled up when the scene is rendered at a lower resolution while navigating), draws
/// ImGui on top in a render pass, and is presented. One frame in flight: the editor waits for the
/// present's submit before the next frame (lavapipe runs both on the same CPU cores anyway).
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "cli.h"
#include "noise/camera.h"
#include "splat/method_vk.h"

namespace spot::cli {
struct SceneJob;
}

namespace spot::editor {

/// A left-button event (the brush's): press, drag (pointer moved with the button held), release.
struct PointerEvent {
    enum class Phase { Press, Drag, Release };
    Phase phase = Phase::Press;
    /// Window pixels (screen coordinates), from the top-left corner of the window.
    double x = 0.0, y = 0.0;
    /// The view at the event with width and height set to the window's size in the same pixels,
    /// so noise::CameraRays(camera).ray(x, y) is the ray under the pointer.
    noise::Camera camera;
    bool shift = false, control = false, alt = false;
};

struct EditWindowOptions {
    std::string title = "spotshell edit";
    /// Initial window size, screen pixels (the scene's image size by default).
    int width = 1280, height = 720;
    std::string method = "instanced"; ///< a name of splat::gpuMethods()
    splat::RenderSettings settings;
    /// Render this many frames, then close (0: until the window is closed). Every one of these
    /// frames renders the scene (no redraw-on-demand), so they time the whole frame.
    int frames = 0;
    /// Write the last rendered scene image here when the window closes (.png or .exr; the scene
    /// only, without the ImGui overlay), atomically.
    std::filesystem::path screenshot;
    /// With `frames`: write the last frame as presented (scene and panels), read back from the
    /// swapchain image.
    std::filesystem::path windowScreenshot;
    /// Render the scene at 1/renderScale of the window's size (1, 2 or 4) and let the blit scale
    /// it up; the Render panel changes it.
    int renderScale = 1;
    /// Scripted checks: after the first frame, resize the window to this size (0: no resize).
    int resizeWidth = 0, resizeHeight = 0;
    /// Scripted navigation: from the second frame on, orbit by this many degrees per frame (as a
    /// middle drag to the right would), so the frames time a moving camera.
    double orbitDegreesPerFrame = 0.0;
    /// Scripted checks: frame i uses method i modulo the registry's count.
    bool cycleMethods = false;

    /// Left-button presses, drags and releases outside the ImGui panels (and without alt, which
    /// orbits). The scene is re-rendered after each event.
    std::function<void(const PointerEvent&)> onBrush;
    /// Called every frame between ImGui::NewFrame() and ImGui::Render(): the session's panels.
    std::function<void()> extraPanels;
    /// Polled once per frame, after the panels: true renders the scene again (the session
    /// changed what it shows, e.g. from a panel or a script).
    std::function<bool()> needsRedraw;
};

/// Timings of the frames a window showed (milliseconds, medians over the warm frames: all but
/// the first of each method and size).
struct EditWindowReport {
    int frames = 0;          ///< frames presented
    int rendered = 0;        ///< of which the scene was rendered (not just the overlay)
    int warmFrames = 0;      ///< the frames the medians are over
    double frameMs = 0.0;    ///< wall time of a whole frame: events, render, overlay, present
    double renderMs = 0.0;   ///< splat::Frame::render() wall time
    double presentMs = 0.0;  ///< acquire, blit, ImGui, submit, present, wait
    double overlayMs = 0.0;  ///< building the ImGui panels on the host (included in frameMs)
    bool validation = false; ///< the validation layer was on (SPOT_VALIDATION=1)
    std::uint32_t validationWarnings = 0; ///< its warnings (errors throw)
};

/// Open the window on `job`'s scene and run until it closes (or options.frames ran out).
/// InputError (exit 2) without a display: DISPLAY unset, or GLFW cannot open it. Throws when
/// validation (SPOT_VALIDATION=1) reported errors.
EditWindowReport runEditWindow(cli::SceneJob& job, const EditWindowOptions& options);

/// The window's command-line options (besides the scene options and the render settings).
std::vector<cli::OptionSpec> editWindowOptions();
/// Options from the command line: --method, --frames, --screenshot, --window-screenshot,
/// --render-scale, --orbit, --resize, --cycle-methods,
/// and the render settings; window size from the scene's image size (--size).
EditWindowOptions editWindowOptions(const cli::Args& args, const cli::SceneJob& job);

} // namespace spot::editor
