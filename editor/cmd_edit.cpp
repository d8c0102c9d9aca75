// `spotshell edit`: the editor. One option set for both ways to run it: the window (GLFW,
// Vulkan, Dear ImGui; edit_window.h) on an edit::Session, or a script replayed on the session
// without a window (--script), or replayed in the window (--script with --window).
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>
#include <tbb/global_control.h>

#include "cli.h"
#include "commands.h"
#include "edit_script.h"
#include "edit_session.h"
#include "edit_window.h"
#include "noise/error.h"
#include "noise/scene.h"
#include "noise/system.h"
#include "render_options.h"

namespace spot::cmd {

namespace {

/// The window's size without --size.
constexpr int kWindowWidth = 1280, kWindowHeight = 720;

void writeReport(const std::string& file, const nlohmann::json& j) {
    writeFileAtomic(file, [&](std::ostream& o) { o << j.dump(2) << "\n"; });
}

std::vector<cli::OptionSpec> editOptions() {
    std::vector<cli::OptionSpec> specs = {
        {"scene", "FILE", "scene JSON to edit (presets/scenes/*.json)", true},
        {"preset", "FILE", "edit this preset instead of the scene's (e.g. one saved by the editor)",
         false},
        {"size", "WxH",
         "the window's size in pixels (default 1280x720; the scene is the part left of the "
         "panels' column); with --script and no window, the image's (default: the scene's image "
         "size)",
         false},
        {"voxel-scale", "X", "painted voxel size as a fraction of the cell size (default 0.25)",
         false},
        {"script", "FILE",
         "replay the actions of FILE (see editor/edit_script.h): without a window, or in it with "
         "--window",
         false},
        {"window", "", "with --script: replay it in the window, one action between two frames",
         false},
        {"report", "FILE", "write the script's (or the window's) timings and memory as JSON",
         false},
        cli::threadsOption()};
    for (const cli::OptionSpec& o : editor::editWindowOptions())
        specs.push_back(o);
    for (const cli::OptionSpec& o : cli::renderOptions())
        specs.push_back(o);
    return specs;
}

/// Whether the session runs in the window; the window's options without it are refused.
bool inWindow(const cli::Args& args) {
    const bool window = !args.has("script") || args.has("window");
    if (args.has("window") && !args.has("script"))
        throw InputError("--window replays a script: give --script FILE too");
    if (!window)
        for (const char* option : {"frames", "orbit", "resize", "cycle-methods",
                                   "window-screenshot", "render-scale", "refine", "panels"})
            if (args.has(option))
                throw InputError(cat("--", option,
                                     " needs the window: give --window too (a --script without "
                                     "it has no window)"));
    return window;
}

/// --size, --preset and --voxel-scale.
edit::SessionOptions sessionOptions(const cli::Args& args) {
    edit::SessionOptions options;
    if (args.has("size")) {
        const std::string size = args.str("size");
        char x = 0, extra = 0;
        if (std::sscanf(size.c_str(), "%d%c%d%c", &options.width, &x, &options.height, &extra) !=
                3 ||
            (x != 'x' && x != 'X') || options.width < 1 || options.height < 1 ||
            options.width > 16384 || options.height > 16384)
            throw InputError(cat("--size '", size, "' must be WxH with sides in [1, 16384]"));
    }
    if (args.has("preset"))
        options.preset = args.str("preset");
    options.voxelScale = float(args.number("voxel-scale", 0.25, 1e-3, 1.0));
    return options;
}

/// What `edit` was asked to do, checked before anything is loaded or written.
struct EditJob {
    edit::SessionOptions options;
    std::vector<edit::ScriptAction> actions;
    std::string scriptFile;
    std::optional<std::filesystem::path> screenshot;
    std::string method;
    splat::RenderSettings settings;
};

EditJob editJob(const cli::Args& args) {
    EditJob job;
    job.scriptFile = args.has("script") ? args.str("script") : std::string();
    if (!job.scriptFile.empty())
        job.actions = edit::loadScript(job.scriptFile);
    if (args.has("screenshot")) {
        job.screenshot = args.str("screenshot");
        const std::string ext = job.screenshot->extension().string();
        if (ext != ".png" && ext != ".exr")
            throw InputError(
                cat("--screenshot '", job.screenshot->string(), "' must end in .png or .exr"));
    }
    job.options = sessionOptions(args);
    const cli::MethodChoice choice = cli::methodChoice(args, "spotshell edit", true);
    job.method = choice.method;
    job.settings = cli::renderSettings(args, choice.settings);
    return job;
}

/// The window's timings, one line each.
void printWindowReport(const editor::EditWindowReport& r, const std::string& sceneName,
                       const std::filesystem::path& screenshot) {
    const std::string timing =
        r.warmFrames == 0
            ? std::string("no warm frames (each changed method or size)")
            : cat("warm frames: median ", r.frameMs, " ms (render ", r.renderMs,
                  " ms, present with ImGui ", r.presentMs, " ms, panels ", r.overlayMs, " ms)");
    std::printf("edit: %d frames (%d rendered) of %s; %s%s%s\n", r.frames, r.rendered,
                sceneName.c_str(), timing.c_str(), screenshot.empty() ? "" : "; wrote ",
                screenshot.string().c_str());
    std::printf("edit: a %dx%d window, the scene in a %dx%d viewport%s; the last frame rendered "
                "at %dx%d\n",
                r.windowWidth, r.windowHeight, r.viewportWidth, r.viewportHeight,
                r.viewportWidth < r.windowWidth ? " left of the panels" : " (the panels hidden)",
                r.renderWidth, r.renderHeight);
    if (!r.strokeToFrameMs.empty()) {
        std::vector<double> s = r.strokeToFrameMs;
        std::sort(s.begin(), s.end());
        std::printf("edit: stroke to frame: median %.1f ms, max %.1f ms over %zu events; "
                    "frames while painting: median %.1f ms (at 1/%d size)\n",
                    s[s.size() / 2], s.back(), s.size(), r.strokeFrameMs, r.lowScale);
    }
    if (r.refined > 0)
        std::printf("edit: idle refinement: %d steps, %.1f ms each (median; the average and "
                    "its upload %.1f ms)\n",
                    r.refined, r.refineMs, r.refineAverageMs);
    if (r.previewMs > 0.0)
        std::printf("edit: kernel preview: %.1f ms (the last render), drawn at (%d, %d)\n",
                    r.previewMs, r.previewX, r.previewY);
    if (r.validation)
        std::printf("edit: validation on: no errors, %u warnings\n", r.validationWarnings);
}

/// The session in the window (the script, if any, replayed there).
int editInWindow(const cli::Args& args, const EditJob& job) {
    const noise::SceneDesc desc = noise::loadScene(args.str("scene"));
    const int width = job.options.width > 0 ? job.options.width : kWindowWidth;
    const int height = job.options.height > 0 ? job.options.height : kWindowHeight;
    editor::EditWindowOptions window = editor::editWindowOptions(args, width, height, desc.name);
    window.script = job.actions;
    window.scriptName = job.scriptFile;
    window.log = stdout;
    const std::filesystem::path scene = args.str("scene");
    const editor::EditWindowReport r = editor::runEditWindow(
        [&](const splat::ContextOptions& context) {
            edit::SessionOptions o = job.options;
            o.context = context;
            auto session = std::make_unique<edit::Session>(scene, o);
            session->setMethod(job.method, job.settings);
            return session;
        },
        window);
    printWindowReport(r, desc.name, window.screenshot);
    if (args.has("report"))
        writeReport(args.str("report"), {{"frames", r.frames},
                                         {"rendered", r.rendered},
                                         {"frame_ms", r.frameMs},
                                         {"render_ms", r.renderMs},
                                         {"present_ms", r.presentMs},
                                         {"panels_ms", r.overlayMs},
                                         {"refined", r.refined},
                                         {"refine_ms", r.refineMs},
                                         {"refine_average_ms", r.refineAverageMs},
                                         {"stroke_to_frame_ms", r.strokeToFrameMs},
                                         {"stroke_frame_ms", r.strokeFrameMs},
                                         {"low_scale", r.lowScale},
                                         {"viewport", {r.viewportWidth, r.viewportHeight}},
                                         {"render_size", {r.renderWidth, r.renderHeight}}});
    return 0;
}

/// The script replayed on a session without a window.
int editHeadless(const cli::Args& args, const EditJob& job) {
    edit::Session session(args.str("scene"), job.options);
    session.setMethod(job.method, job.settings);
    const edit::ScriptReport report = edit::runScript(session, job.actions, job.scriptFile, stdout);
    if (job.screenshot)
        session.exportImage(*job.screenshot);
    if (args.has("report"))
        writeReport(args.str("report"),
                    {{"strokes", report.strokes},
                     {"frames", report.frames},
                     {"stroke_ms", report.strokeMs},
                     {"param_ms", report.paramMs},
                     {"stroke_to_frame_ms", report.strokeToFrameMs},
                     {"stroke_event_ms", report.eventMs},
                     {"stroke_frame_ms", report.frameMs},
                     {"stroke_generate_gpu_ms", report.generateMs},
                     {"start_arm_ms", session.startArmCost().milliseconds},
                     {"arm_ms", report.armMs},
                     {"arm_frame_ms", report.armFrameMs},
                     {"undo_steps", session.undoSteps()},
                     {"undo_bytes", session.undoBytes()},
                     {"session_bytes", session.memoryBytes()},
                     {"peak_rss_bytes", edit::peakResidentBytes()},
                     {"gpu_memory_bytes", session.context().peakAllocatedBytes()}});
    std::printf("edited %s: %d strokes, %d frames, %zu undo steps (%zu bytes)%s%s\n",
                session.scene().name.c_str(), report.strokes, report.frames, session.undoSteps(),
                session.undoBytes(), job.screenshot ? "; wrote " : "",
                job.screenshot ? job.screenshot->string().c_str() : "");
    return 0;
}

} // namespace

int edit(int argc, char** argv) {
    cli::Args args("edit",
                   "Paint density, comb, tilt, length and colour on the surface and edit the "
                   "kernel, in a window: the GPU methods live, with Blender-like navigation "
                   "(middle drag orbits, shift+middle pans, the wheel zooms, alt+left orbits, F "
                   "or Home frames the mesh), the left button paints, F12 exports the view; the "
                   "panels sit in a column right of the scene (N shows or hides it). Needs a "
                   "display (DISPLAY), or xvfb-run. --script replays a session without a window.",
                   editOptions(), argc, argv);
    if (args.helpRequested()) {
        std::fputs(args.usage().c_str(), stdout);
        return 0;
    }
    const auto threads = args.integer("threads", 0, 0, 1024);
    std::optional<tbb::global_control> threadLimit;
    if (threads > 0)
        threadLimit.emplace(tbb::global_control::max_allowed_parallelism, std::size_t(threads));
    const bool window = inWindow(args);
    // Everything is checked before anything is loaded or written.
    const EditJob job = editJob(args);
    return window ? editInWindow(args, job) : editHeadless(args, job);
}

} // namespace spot::cmd
