#include "edit_input.h"

// Only GLFW's constants (macros): this library does not link GLFW.
#include <GLFW/glfw3.h>

namespace spot::editor {

namespace {

using Type = InputAction::Type;

InputAction action(Type type, Drag drag) {
    InputAction a;
    a.type = type;
    a.drag = drag;
    return a;
}

InputAction mapButton(const InputEvent& e, const InputContext& c) {
    if (e.action == GLFW_RELEASE) {
        // Any release ends the drag; only the left button's ends a stroke.
        InputAction a = action(Type::None, Drag::None);
        if (c.drag == Drag::Brush && e.code == GLFW_MOUSE_BUTTON_LEFT) {
            a.type = Type::BrushRelease;
            a.x = e.x;
            a.y = e.y;
        }
        return a;
    }
    if (e.action != GLFW_PRESS || c.panelWantsMouse || c.drag != Drag::None)
        return action(Type::None, c.drag);
    const bool shift = e.mods & GLFW_MOD_SHIFT, alt = e.mods & GLFW_MOD_ALT;
    if (e.code == GLFW_MOUSE_BUTTON_MIDDLE || (e.code == GLFW_MOUSE_BUTTON_LEFT && alt))
        return action(Type::Navigate, shift ? Drag::Pan : Drag::Orbit);
    if (e.code == GLFW_MOUSE_BUTTON_RIGHT)
        return action(Type::Navigate, Drag::Light);
    if (e.code != GLFW_MOUSE_BUTTON_LEFT)
        return action(Type::None, c.drag);
    InputAction a = action(Type::BrushPress, Drag::Brush);
    a.x = e.x;
    a.y = e.y;
    // Shift or ctrl at the press inverts the stroke: density-add erases, length shrinks.
    a.invert = (e.mods & (GLFW_MOD_SHIFT | GLFW_MOD_CONTROL)) != 0;
    return a;
}

InputAction mapCursor(const InputEvent& e, const InputContext& c) {
    InputAction a = action(Type::None, c.drag);
    a.dx = e.x - c.lastX;
    a.dy = e.y - c.lastY;
    a.x = e.x;
    a.y = e.y;
    switch (c.drag) {
    case Drag::Orbit:
        a.type = Type::Orbit;
        break;
    case Drag::Pan:
        a.type = Type::Pan;
        break;
    case Drag::Brush:
        a.type = Type::BrushDrag;
        break;
    case Drag::Light:
        a.type = Type::TurnLight;
        break;
    case Drag::None:
        break;
    }
    return a;
}

InputAction mapKey(const InputEvent& e, const InputContext& c) {
    InputAction a = action(Type::None, c.drag);
    if ((e.action != GLFW_PRESS && e.action != GLFW_REPEAT) || c.panelWantsKeyboard ||
        c.drag == Drag::Brush) // no undo or brush change in the middle of a stroke
        return a;
    const bool shift = e.mods & GLFW_MOD_SHIFT, control = e.mods & GLFW_MOD_CONTROL;
    const int key = e.code;
    if (control) {
        if (key == GLFW_KEY_Z)
            a.type = shift ? Type::Redo : Type::Undo;
        else if (key == GLFW_KEY_Y)
            a.type = Type::Redo;
        return a;
    }
    if (key == GLFW_KEY_F || key == GLFW_KEY_HOME) {
        a.type = Type::FrameMesh;
    } else if (key == GLFW_KEY_LEFT_BRACKET || key == GLFW_KEY_RIGHT_BRACKET) {
        a.type = shift ? Type::BrushStrength : Type::BrushRadius;
        a.step = key == GLFW_KEY_RIGHT_BRACKET ? 1 : -1;
    } else if (key >= GLFW_KEY_1 && key <= GLFW_KEY_9) {
        a.type = Type::BrushKind;
        a.kind = key - GLFW_KEY_1;
    } else if (key == GLFW_KEY_0) {
        a.type = Type::BrushKind;
        a.kind = 9; // the mask brush: 0 follows 9 on the keyboard
    } else if (key == GLFW_KEY_M && e.action == GLFW_PRESS) {
        a.type = Type::MaskOverlay;
    } else if (key == GLFW_KEY_X) {
        a.type = Type::MirrorX;
    } else if (key == GLFW_KEY_F12 && e.action == GLFW_PRESS) {
        a.type = Type::Export;
    } else if (key == GLFW_KEY_N && e.action == GLFW_PRESS) {
        a.type = Type::TogglePanels;
    } else if (key == GLFW_KEY_SPACE && e.action == GLFW_PRESS) {
        a.type = Type::PlayPause;
    } else if (key == GLFW_KEY_LEFT || key == GLFW_KEY_RIGHT) {
        a.type = Type::StepFrame;
        a.step = key == GLFW_KEY_RIGHT ? 1 : -1;
    }
    return a;
}

} // namespace

InputAction mapInput(const InputEvent& event, const InputContext& context) {
    switch (event.kind) {
    case InputEvent::Kind::Button:
        return mapButton(event, context);
    case InputEvent::Kind::Cursor:
        return mapCursor(event, context);
    case InputEvent::Kind::Scroll: {
        if (context.panelWantsMouse)
            return action(Type::None, context.drag);
        InputAction a = action(Type::Dolly, context.drag);
        a.dy = event.y;
        return a;
    }
    case InputEvent::Kind::Key:
        return mapKey(event, context);
    }
    return action(Type::None, context.drag);
}

} // namespace spot::editor
