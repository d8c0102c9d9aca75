#include <cstdio>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>
#include <tbb/global_control.h>

#include "cli.h"
#include "commands.h"
#include "edit_script.h"
#include "edit_session.h"
#include "noise/error.h"
#include "noise/system.h"
#include "scene_job.h"

namespace spot::cmd {

int edit(int argc, char** argv) {
    // Without --script the window opens (cmd_edit_window.cpp).
    bool script = false;
    for (int i = 1; i < argc; ++i)
        script |= std::string(argv[i]) == "--script" || std::string(argv[i]).rfind("--script=", 0) == 0;
    if (!script)
        return editWindow(argc, argv);
    std::vector<cli::OptionSpec> specs = {
        {"scene", "FILE", "scene JSON to edit (presets/scenes/*.json)", true},
        {"preset", "FILE", "edit this preset instead of the scene's (e.g. one saved by the editor)",
         false},
        {"size", "WxH", "window size in pixels (default: the scene's image size)", false},
        {"script", "FILE", "run the actions of FILE without a window (see editor/edit_script.h)",
         false},
        {"screenshot", "FILE", "after the script, write the view (.png or .exr)", false},
        {"voxel-scale", "X", "painted voxel size as a fraction of the cell size (default 0.25)",
         false},
        {"report", "FILE", "write the script's timings and memory as JSON", false},
        cli::threadsOption()};
    cli::Args args("edit",
                   "Paint density, comb, tilt, length and colour on the surface and edit "
                   "the kernel. Without a window yet: --script replays a session.",
                   specs, argc, argv);
    if (args.helpRequested()) {
        std::fputs(args.usage().c_str(), stdout);
        return 0;
    }
    if (!args.has("script"))
        throw InputError("spotshell edit: the editor window is not built yet; give --script FILE");
    const auto threads = args.integer("threads", 0, 0, 1024);
    std::optional<tbb::global_control> threadLimit;
    if (threads > 0)
        threadLimit.emplace(tbb::global_control::max_allowed_parallelism, std::size_t(threads));

    // Everything is checked before anything is loaded or written.
    const std::string scriptFile = args.str("script");
    const std::vector<edit::ScriptAction> actions = edit::loadScript(scriptFile);
    std::optional<std::filesystem::path> screenshot;
    if (args.has("screenshot")) {
        screenshot = args.str("screenshot");
        const std::string ext = screenshot->extension().string();
        if (ext != ".png" && ext != ".exr")
            throw InputError(
                cat("--screenshot '", screenshot->string(), "' must end in .png or .exr"));
    }
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

    edit::Session session(args.str("scene"), options);
    const edit::ScriptReport report = edit::runScript(session, actions, scriptFile, stdout);
    if (screenshot)
        session.exportImage(*screenshot);
    if (args.has("report")) {
        nlohmann::json j = {{"strokes", report.strokes},
                            {"frames", report.frames},
                            {"stroke_ms", report.strokeMs},
                            {"param_ms", report.paramMs},
                            {"stroke_to_frame_ms", report.strokeToFrameMs},
                            {"stroke_event_ms", report.eventMs},
                            {"stroke_frame_ms", report.frameMs},
                            {"stroke_generate_gpu_ms", report.generateMs},
                            {"undo_steps", session.undoSteps()},
                            {"undo_bytes", session.undoBytes()},
                            {"session_bytes", session.memoryBytes()},
                            {"peak_rss_bytes", edit::peakResidentBytes()},
                            {"gpu_memory_bytes", session.context().peakAllocatedBytes()}};
        writeFileAtomic(args.str("report"), [&](std::ostream& o) { o << j.dump(2) << "\n"; });
    }
    std::printf("edited %s: %d strokes, %d frames, %zu undo steps (%zu bytes)%s%s\n",
                session.scene().name.c_str(), report.strokes, report.frames, session.undoSteps(),
                session.undoBytes(), screenshot ? "; wrote " : "",
                screenshot ? screenshot->string().c_str() : "");
    return 0;
}

} // namespace spot::cmd
