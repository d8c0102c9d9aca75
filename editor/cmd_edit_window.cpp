// `spotshell edit`: the editor's window on a scene (edit_window.h). The painting session's
// options and hooks join here as they arrive.
#include <cstdio>
#include <string>

#include "cli.h"
#include "commands.h"
#include "edit_window.h"
#include "noise/error.h"
#include "render_options.h"
#include "scene_job.h"

namespace spot::cmd {

int editWindow(int argc, char** argv) {
    std::vector<cli::OptionSpec> specs = cli::sceneOptions();
    for (const cli::OptionSpec& o : editor::editWindowOptions())
        specs.push_back(o);
    for (const cli::OptionSpec& o : cli::renderOptions())
        specs.push_back(o);
    cli::Args args("edit",
                   "Open the editor's window on a scene: the GPU methods live, with Blender-like "
                   "navigation (middle drag orbits, shift+middle pans, the wheel zooms, alt+left "
                   "orbits, F or Home frames the mesh). Needs a display (DISPLAY), or xvfb-run.",
                   specs, argc, argv);
    if (args.helpRequested()) {
        std::fputs(args.usage().c_str(), stdout);
        return 0;
    }
    cli::SceneJob job = cli::prepareScene(args, false);
    const editor::EditWindowOptions options = editor::editWindowOptions(args, job);
    const editor::EditWindowReport r = editor::runEditWindow(job, options);
    const std::string timing =
        r.warmFrames == 0
            ? std::string("no warm frames (each changed method or size)")
            : cat("warm frames: median ", r.frameMs, " ms (render ", r.renderMs,
                  " ms, present with ImGui ", r.presentMs, " ms, panels ", r.overlayMs, " ms)");
    std::printf("edit: %d frames (%d rendered) of %s; %s%s%s\n", r.frames, r.rendered,
                job.scene.name.c_str(), timing.c_str(),
                options.screenshot.empty() ? "" : "; wrote ", options.screenshot.string().c_str());
    if (r.validation)
        std::printf("edit: validation on: no errors, %u warnings\n", r.validationWarnings);
    return 0;
}

} // namespace spot::cmd
