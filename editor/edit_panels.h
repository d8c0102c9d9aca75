/// @file edit_panels.h
/// @brief The editor window's Dear ImGui panels on an edit::Session: the timeline of an animated
/// scene, Brush, Kernel (with a rendered preview and a schematic of the lobes), Distribution, Wind
/// and File. Each is a
/// section (a collapsing header) of the panels' column at the right of the window (the window
/// adds Render and Stats; edit_view.h's WindowLayout places the column), so no panel covers the
/// scene. Built every frame between ImGui::NewFrame() and ImGui::Render(), inside the column's
/// ImGui window; the session's edits happen here, so the frame that follows shows them.
///
/// A slider or drag is one undo step: the value is kept in the panel while the widget is held
/// and committed to the session when it is released (ImGui::IsItemDeactivatedAfterEdit), so a
/// drag rebuilds the generator once, not every frame.
#pragma once

#include <map>
#include <string>
#include <vector>

#include <imgui.h>

namespace spot::edit {
class Session;
}
namespace spot::splat {
struct MethodInfo;
struct RenderSettings;
} // namespace spot::splat

namespace spot::editor {

/// What the panels keep between frames.
struct SessionPanels {
    /// Values of the widgets being dragged, by label (committed on release).
    std::map<std::string, std::vector<float>> held;
    std::string savePath;   ///< File: where Save writes the preset (.json, .vdb beside it)
    std::string exportPath; ///< File: where Export writes the view (.png or .exr)
    std::string message;    ///< the last error or file written, shown in the File panel
    bool messageIsError = false;
    float windAmplitudeDeg = 20.0f, windFrequencyHz = 0.5f;
    /// The timeline plays (the window advances the session's time by the wall-clock time
    /// between frames); its Play button and the space bar toggle it, a scrub pauses it.
    bool playing = false;
    /// The sections unfolded when the window opens (lower case: render, brush, kernel,
    /// distribution, clumps, wind, file, stats); the user folds and unfolds them after.
    std::vector<std::string> openAtStart = {"render", "brush", "file"};
    /// Where the Kernel section left room for the rendered kernel preview (screen pixels,
    /// kPreviewSize square), and whether all of it is on screen this frame (the section is
    /// unfolded and not scrolled away): the window then draws the preview there.
    ImVec2 previewAt{0.0f, 0.0f};
    bool previewShown = false;
    static constexpr int kPreviewSize = 160;
};

/// The names sessionPanels' sections and the window's (render, stats) answer to, in the column's
/// order.
const std::vector<std::string>& sectionNames();

/// A hint in the disabled colour, wrapped to the column.
void hint(const char* text);

/// Begin section `title` of the column (a collapsing header, unfolded at first when
/// state.openAtStart names it); true when it is unfolded (then draw its widgets).
bool beginSection(const char* title, const SessionPanels& state);

/// Draw the sections (Brush, Kernel, Distribution, Clumps, Wind, File); returns true when the
/// session changed what it shows (render again). Session errors (InputError: a value the preset
/// refuses, a file that cannot be written) are shown in the File panel, never thrown.
bool sessionPanels(edit::Session& session, SessionPanels& state);

/// The timeline of an animated scene (nothing for a static one), at the top of the column: Play /
/// Pause, loop, a slider that scrubs the time over the clip, the time and the frame number at
/// the scene's fps. Returns true when the time changed (render again).
bool timelinePanel(edit::Session& session, SessionPanels& state);

/// Save to state.savePath; false (with the message set) when it failed.
bool saveSession(edit::Session& session, SessionPanels& state);

/// The Render panel's widgets for the settings `method` takes, from their descriptors
/// (splat/settings.h): a checkbox, a slider (to Setting::panelMax) or a combo each; a file
/// setting is shown, not edited. Returns whether a setting changed.
bool renderSettingsWidgets(const splat::MethodInfo& method, splat::RenderSettings& settings);

} // namespace spot::editor
