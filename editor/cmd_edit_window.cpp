// `spotshell edit`: the editor's window on a scene (edit_window.h). The painting session's
// options and hooks join here as they arrive.
#include <cstdio>

#include "cli.h"
#include "commands.h"
#include "edit_window.h"
#include "render_options.h"
#include "scene_job.h"

namespace spot::cmd {

int edit(int argc, char** argv) {
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
    std::printf("edit: %d frames (%d rendered) of %s; warm frames: median %.2f ms (render %.2f ms, "
                "present with ImGui %.2f ms, panels %.2f ms)%s%s\n",
                r.frames, r.rendered, job.scene.name.c_str(), r.frameMs, r.renderMs, r.presentMs,
                r.overlayMs, options.screenshot.empty() ? "" : "; wrote ",
                options.screenshot.string().c_str());
    return 0;
}

} // namespace spot::cmd
