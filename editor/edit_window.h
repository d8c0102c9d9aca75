/// @file edit_window.h
/// @brief The editor's window: a GLFW window with a Vulkan swapchain that shows and edits an
/// edit::Session live (the session's splat::Frame, the same renderers as `render`), with
/// Blender-like navigation (edit_view.h), painting on the left button, keys, and Dear ImGui
/// panels (render, brush, kernel, distribution, wind, file, stats; edit_panels.h). The session
/// is built on the window's context, so strokes, undo and panel edits show in the next frame.
///
/// An animated scene has a timeline at the top of the column (edit_panels.h's timelinePanel):
/// while it plays (space or its Play button) each frame advances the session's time by the
/// wall-clock time since the frame before, looping at the clip's end unless loop is off (then it
/// stops there); the slider scrubs, left and right step a frame. No idle refinement while it
/// plays. Painting works at any time (edit_session.h).
///
/// The window is the viewport (the scene, at the top left; the camera's aspect ratio is its) and
/// a column of panels along the right edge (edit_view.h's WindowLayout): no panel covers the
/// scene. A frame: splat::Frame::render() renders into the method's result image (RGBA32F,
/// linear) and waits; a second command buffer clears the swapchain image to the panels' colour,
/// blits the scene into the viewport (an sRGB format, so the blit encodes; scaled up when the
/// scene is rendered at a lower resolution while navigating) and the kernel preview into the
/// column, draws ImGui on top in a render pass, and is presented. One frame in flight: the editor
/// waits for the present's submit before the next frame (lavapipe runs both on the same CPU cores
/// anyway). While the camera moves or a stroke is in progress the scene renders at a lower
/// resolution; when idle the window refines: it averages sub-pixel-jittered `sorted` frames at full
/// resolution (read back, averaged on the host, uploaded to an image the blit shows).
///
/// The mouse and keys map to actions through edit_input.h (a tested pure function); the
/// swapchain, the ImGui layer and the present are in edit_present_vk.h.
#pragma once

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "cli.h"
#include "edit_quit.h"
#include "edit_script.h"
#include "noise/camera.h"
#include "splat/context_vk.h"
#include "splat/method_vk.h"

namespace spot::edit {
class Session;
}

namespace spot::editor {

struct EditWindowOptions {
    std::string title = "spotshell edit";
    /// Initial window size, screen pixels (the viewport is the part left of the panels' column).
    int width = 1280, height = 720;
    std::string method = "sorted"; ///< a name of splat::gpuMethods() (the command line sets it)
    splat::RenderSettings settings;
    /// Render this many frames (after the script, if any), then close (0: until the window is
    /// closed). Every one of these frames renders the scene (no redraw-on-demand), so they time
    /// the whole frame, unless the idle refinement runs (refineFrames > 0).
    int frames = 0;
    /// Write the scene as last shown here when the window closes (.png or .exr; the viewport
    /// only, at its full size whatever the render scale, without the panels; the refinement's
    /// average when it ran), atomically.
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
    /// The panels' column shown or not (none: shown in windows at least kColumnMinWindowWidth
    /// wide), and its sections unfolded at first (lower-case names; empty: Render, Brush, File).
    std::optional<bool> column;
    std::vector<std::string> openPanels;

    /// Idle refinement: after the interactive frame, while nothing changes, accumulate this
    /// many sub-pixel-jittered frames of the `sorted` method at full resolution into a running
    /// average (0: off). The Render panel changes it. With `frames`, the window closes once
    /// these steps are done too.
    int refineFrames = 16;
    /// Replay these script actions, one between two frames (strokes as pointer events, one per
    /// frame); `scriptName` names the file in messages, `log` gets one line per action.
    std::vector<edit::ScriptAction> script;
    std::string scriptName;
    std::FILE* log = nullptr;
};

/// Timings of the frames a window showed (milliseconds, medians over the warm frames: all but
/// the first of each method and size).
struct EditWindowReport {
    int frames = 0;               ///< frames presented
    int rendered = 0;             ///< of which the scene was rendered (not just the overlay)
    int warmFrames = 0;           ///< the frames the medians are over
    double frameMs = 0.0;         ///< wall time of a whole frame: events, render, overlay, present
    double renderMs = 0.0;        ///< splat::Frame::render() wall time
    double presentMs = 0.0;       ///< acquire, blit, ImGui, submit, present, wait
    double overlayMs = 0.0;       ///< building the ImGui panels on the host (included in frameMs)
    double refineMs = 0.0;        ///< one idle refinement step: render, read back, average, upload
    double refineAverageMs = 0.0; ///< ... of which the host average and the upload
    double previewMs = 0.0;       ///< the last kernel preview's render (0: not shown)
    int refined = 0;              ///< refinement steps done
    /// Brush events (pointer or replayed script) to the present of the frame that shows them.
    std::vector<double> strokeToFrameMs;
    double strokeFrameMs = 0.0; ///< median whole frame while a stroke is in progress
    int strokeFrames = 0;
    /// Moving and painting rendered at 1/lowScale of the window's size at the end (lowered
    /// from the Render panel's choice when those frames were slower than 10 fps).
    int lowScale = 2;
    int windowWidth = 0, windowHeight = 0;     ///< at the end
    int viewportWidth = 0, viewportHeight = 0; ///< the scene's part of it at the end
    int renderWidth = 0, renderHeight = 0;     ///< the last interactive render (not refinement)
    int previewX = -1, previewY = -1;     ///< where the kernel preview was last drawn (-1: never)
    bool validation = false;              ///< the validation layer was on (SPOT_VALIDATION=1)
    std::uint32_t validationWarnings = 0; ///< its warnings (errors throw)
};

/// Makes the window's session on a context with these options (the window's presentation
/// extensions and queue); called once the display is known to work.
using SessionFactory =
    std::function<std::unique_ptr<edit::Session>(const splat::ContextOptions& context)>;

/// Open the window on the session `makeSession` builds and run until it closes (or
/// options.frames ran out after the script). InputError (exit 2) without a display: DISPLAY
/// unset, or GLFW cannot open it. Throws when validation (SPOT_VALIDATION=1) reported errors.
EditWindowReport runEditWindow(const SessionFactory& makeSession, const EditWindowOptions& options);

/// The window's command-line options (besides the scene options and the render settings).
std::vector<cli::OptionSpec> editWindowOptions();
/// Options from the command line: --method, --frames, --screenshot, --window-screenshot,
/// --render-scale, --orbit, --resize, --cycle-methods, --refine, --panels, and the render
/// settings; `width` x `height` is the window's size (1280x720 or --size).
EditWindowOptions editWindowOptions(const cli::Args& args, int width, int height,
                                    const std::string& sceneName);

} // namespace spot::editor