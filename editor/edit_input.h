/// @file edit_input.h
/// @brief What the editor window's mouse and keys do: a pure function from one GLFW event, its
/// modifiers and the window's input state (the drag in progress, the pointer, whether a panel
/// has the pointer or the keyboard) to one action on the view or the session. The window
/// applies the action (edit_window.cpp); the mapping is unit-tested without a window
/// (tests/editor/input_test.cpp).
///
/// Codes are GLFW's (GLFW_MOUSE_BUTTON_*, GLFW_KEY_*, GLFW_MOD_*, GLFW_PRESS / RELEASE /
/// REPEAT); positions are window pixels from the top left.
///
///     left drag            paint (shift or ctrl at the press: inverted, e.g. density-add erases)
///     middle drag          orbit (alt+left too); shift+middle pans
///     wheel                dolly
///     right drag           turn the key light: left-right its azimuth, up-down its elevation
///                          (an unlit session turns lit first)
///     ctrl+z, ctrl+shift+z, ctrl+y   undo, redo, redo
///     F or Home            frame the mesh
///     [ ]                  brush radius down / up; shift+[ ] strength down / up
///     1..9, 0              brush kind (density-add, density-erase, comb, tilt, length, colour,
///                          smooth, clump, clump-size, mask)
///     M                    show or hide the mask overlay
///     X                    mirror the brush about x = 0
///     F12                  export the view (the File panel's Export)
///     N                    show or hide the panels' column
///     space                play or pause the timeline (an animated scene)
///     left, right          the timeline one frame back / forward
#pragma once

namespace spot::editor {

/// The pointer drag in progress, from the press that began it to a release.
enum class Drag { None, Orbit, Pan, Brush, Light };

struct InputEvent {
    enum class Kind { Button, Cursor, Scroll, Key };
    Kind kind = Kind::Cursor;
    int code = 0;   ///< Button: GLFW_MOUSE_BUTTON_*; Key: GLFW_KEY_*
    int action = 0; ///< Button, Key: GLFW_PRESS, GLFW_RELEASE or GLFW_REPEAT
    int mods = 0;   ///< Button, Key: GLFW_MOD_* bits
    /// Button, Cursor: the pointer (for a button, where the pointer last was); Scroll: the
    /// wheel's offsets (y: steps, positive away from the user).
    double x = 0.0, y = 0.0;

    static InputEvent button(int button, int action, int mods, double x, double y) {
        return {Kind::Button, button, action, mods, x, y};
    }
    static InputEvent cursor(double x, double y) { return {Kind::Cursor, 0, 0, 0, x, y}; }
    static InputEvent scroll(double dx, double dy) { return {Kind::Scroll, 0, 0, 0, dx, dy}; }
    static InputEvent key(int key, int action, int mods) { return {Kind::Key, key, action, mods}; }
};

/// What the window knows when an event comes.
struct InputContext {
    Drag drag = Drag::None;
    double lastX = 0.0, lastY = 0.0; ///< the pointer at the event before (window pixels)
    bool panelWantsMouse = false;    ///< the pointer is over a panel (ImGui's WantCaptureMouse)
    bool panelWantsKeyboard = false; ///< a panel's text field has the keys (WantCaptureKeyboard)
};

struct InputAction {
    enum class Type {
        None,
        Navigate,     ///< a press that begins an orbit, a pan or a light drag (`drag` says which)
        Orbit,        ///< turn by (dx, dy) pixels of pointer motion
        TurnLight,    ///< turn the key light by (dx, dy) pixels of pointer motion
        Pan,          ///< move the view by (dx, dy) pixels
        Dolly,        ///< dy wheel steps towards the target
        BrushPress,   ///< begin a stroke at (x, y); `invert` for the whole stroke
        BrushDrag,    ///< continue the stroke to (x, y)
        BrushRelease, ///< end the stroke
        Undo,
        Redo,
        FrameMesh,     ///< frame the mesh's bounding sphere
        BrushRadius,   ///< scale the radius one step: `step` +1 up, -1 down
        BrushStrength, ///< change the strength one step: `step` +1 up, -1 down
        BrushKind,     ///< choose brush kind `kind` (edit::BrushKind's order)
        MirrorX,       ///< toggle the brush's mirror about x = 0
        Export,        ///< write the view as the File panel's Export does
        TogglePanels,  ///< show or hide the panels' column
        PlayPause,     ///< play or pause the timeline
        StepFrame,     ///< move the timeline by `step` frames (+1 forward, -1 back)
        MaskOverlay    ///< show or hide the mask overlay (Session::setMaskOverlay)
    };
    Type type = Type::None;
    Drag drag = Drag::None; ///< the drag after the event
    double dx = 0.0, dy = 0.0;
    double x = 0.0, y = 0.0;
    bool invert = false;
    int step = 0;
    int kind = 0;
};

/// The action `event` asks for, given `context`. A panel under the pointer takes presses and the
/// wheel, not releases (a drag that began over the scene ends wherever it is released); a panel
/// with a text field takes the keys. No undo or brush change in the middle of a stroke; other
/// ctrl+keys do nothing.
InputAction mapInput(const InputEvent& event, const InputContext& context);

} // namespace spot::editor
