/// @file edit_panels.h
/// @brief The editor window's Dear ImGui panels on an edit::Session: Brush, Kernel (with a
/// schematic preview of the lobes), Distribution, Wind and File. Built every frame between
/// ImGui::NewFrame() and ImGui::Render(); the session's edits happen here, so the frame that
/// follows shows them.
///
/// A slider or drag is one undo step: the value is kept in the panel while the widget is held
/// and committed to the session when it is released (ImGui::IsItemDeactivatedAfterEdit), so a
/// drag rebuilds the generator once, not every frame.
#pragma once

#include <map>
#include <string>
#include <vector>

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
    bool kernelOpen = false; ///< the Kernel panel is unfolded (the window shows the preview)
};

/// Draw the panels; returns true when the session changed what it shows (render again).
/// Session errors (InputError: a value the preset refuses, a file that cannot be written) are
/// shown in the File panel, never thrown.
bool sessionPanels(edit::Session& session, SessionPanels& state);

/// Save to state.savePath; false (with the message set) when it failed.
bool saveSession(edit::Session& session, SessionPanels& state);

/// The Render panel's widgets for the settings `method` takes, from their descriptors
/// (splat/settings.h): a checkbox, a slider (to Setting::panelMax) or a combo each; a file
/// setting is shown, not edited. Returns whether a setting changed.
bool renderSettingsWidgets(const splat::MethodInfo& method, splat::RenderSettings& settings);

} // namespace spot::editor
