/// @file edit_quit.h
/// @brief What closing the editor's window does: unsaved changes are never lost silently. The
/// window's close button asks (a Save / Discard / Cancel modal) when the session is dirty.
#pragma once

namespace spot::editor {

/// The modal's button pressed this frame (None when none was).
enum class QuitAnswer { None, Save, Discard, Cancel };

struct QuitStep {
    bool close = false; ///< close the window now
    bool save = false;  ///< save first (close only when saving succeeded)
    bool ask = false;   ///< keep the window open and show the Save / Discard / Cancel modal
};

/// `closeRequested`: the user asked to close the window this frame (the close button).
inline QuitStep quitStep(bool dirty, bool closeRequested, QuitAnswer answer) {
    switch (answer) {
    case QuitAnswer::Save:
        return {true, true, false};
    case QuitAnswer::Discard:
        return {true, false, false};
    case QuitAnswer::Cancel:
        return {};
    case QuitAnswer::None:
        break;
    }
    if (!closeRequested)
        return {};
    return dirty ? QuitStep{false, false, true} : QuitStep{true, false, false};
}

} // namespace spot::editor
