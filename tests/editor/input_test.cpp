// The editor window's mouse and keys (edit_input.h): each event, with its modifiers and the
// window's state, maps to the action the window carries out. No window: the same function the
// GLFW callbacks call.
#include <gtest/gtest.h>

#include <GLFW/glfw3.h>

#include "edit_input.h"

namespace {

using spot::editor::Drag;
using spot::editor::InputAction;
using spot::editor::InputContext;
using spot::editor::InputEvent;
using spot::editor::mapInput;
using Type = InputAction::Type;

InputContext idle() {
    return {};
}

InputContext dragging(Drag drag, double x = 0.0, double y = 0.0) {
    InputContext c;
    c.drag = drag;
    c.lastX = x;
    c.lastY = y;
    return c;
}

InputAction press(int button, int mods, const InputContext& c = idle(), double x = 10.0,
                  double y = 20.0) {
    return mapInput(InputEvent::button(button, GLFW_PRESS, mods, x, y), c);
}

InputAction key(int k, int mods = 0, const InputContext& c = idle(), int action = GLFW_PRESS) {
    return mapInput(InputEvent::key(k, action, mods), c);
}

TEST(EditInput, LeftDragPaintsAndShiftOrCtrlInvertsTheStroke) {
    const InputAction plain = press(GLFW_MOUSE_BUTTON_LEFT, 0, idle(), 12.0, 34.0);
    EXPECT_EQ(plain.type, Type::BrushPress);
    EXPECT_EQ(plain.drag, Drag::Brush);
    EXPECT_FALSE(plain.invert);
    EXPECT_EQ(plain.x, 12.0);
    EXPECT_EQ(plain.y, 34.0);
    EXPECT_TRUE(press(GLFW_MOUSE_BUTTON_LEFT, GLFW_MOD_SHIFT).invert);
    EXPECT_TRUE(press(GLFW_MOUSE_BUTTON_LEFT, GLFW_MOD_CONTROL).invert);

    // The drag continues the stroke at the pointer; the left release ends it.
    const InputAction drag =
        mapInput(InputEvent::cursor(40.0, 50.0), dragging(Drag::Brush, 12, 34));
    EXPECT_EQ(drag.type, Type::BrushDrag);
    EXPECT_EQ(drag.x, 40.0);
    EXPECT_EQ(drag.y, 50.0);
    EXPECT_EQ(drag.drag, Drag::Brush);
    const InputAction release =
        mapInput(InputEvent::button(GLFW_MOUSE_BUTTON_LEFT, GLFW_RELEASE, 0, 40.0, 50.0),
                 dragging(Drag::Brush));
    EXPECT_EQ(release.type, Type::BrushRelease);
    EXPECT_EQ(release.drag, Drag::None);
    // Another button's release ends the drag but not as a stroke's end.
    const InputAction other = mapInput(
        InputEvent::button(GLFW_MOUSE_BUTTON_RIGHT, GLFW_RELEASE, 0, 0, 0), dragging(Drag::Brush));
    EXPECT_EQ(other.type, Type::None);
    EXPECT_EQ(other.drag, Drag::None);
}

TEST(EditInput, MiddleDragOrbitsShiftMiddlePansAltLeftOrbitsRightTurnsTheLight) {
    const InputAction orbit = press(GLFW_MOUSE_BUTTON_MIDDLE, 0);
    EXPECT_EQ(orbit.type, Type::Navigate);
    EXPECT_EQ(orbit.drag, Drag::Orbit);
    EXPECT_EQ(press(GLFW_MOUSE_BUTTON_MIDDLE, GLFW_MOD_SHIFT).drag, Drag::Pan);
    EXPECT_EQ(press(GLFW_MOUSE_BUTTON_LEFT, GLFW_MOD_ALT).drag, Drag::Orbit);
    EXPECT_EQ(press(GLFW_MOUSE_BUTTON_LEFT, GLFW_MOD_ALT | GLFW_MOD_SHIFT).drag, Drag::Pan);
    // The motion since the last cursor event, in pixels.
    const InputAction turn =
        mapInput(InputEvent::cursor(130.0, 95.0), dragging(Drag::Orbit, 100, 100));
    EXPECT_EQ(turn.type, Type::Orbit);
    EXPECT_EQ(turn.dx, 30.0);
    EXPECT_EQ(turn.dy, -5.0);
    const InputAction pan =
        mapInput(InputEvent::cursor(90.0, 110.0), dragging(Drag::Pan, 100, 100));
    EXPECT_EQ(pan.type, Type::Pan);
    EXPECT_EQ(pan.dx, -10.0);
    EXPECT_EQ(pan.dy, 10.0);
    // Motion without a drag does nothing.
    EXPECT_EQ(mapInput(InputEvent::cursor(5, 5), idle()).type, Type::None);
    // The right button turns the key light by the motion; its release ends the drag.
    const InputAction light = press(GLFW_MOUSE_BUTTON_RIGHT, 0);
    EXPECT_EQ(light.type, Type::Navigate);
    EXPECT_EQ(light.drag, Drag::Light);
    const InputAction turnLight =
        mapInput(InputEvent::cursor(80.0, 120.0), dragging(Drag::Light, 100, 100));
    EXPECT_EQ(turnLight.type, Type::TurnLight);
    EXPECT_EQ(turnLight.dx, -20.0);
    EXPECT_EQ(turnLight.dy, 20.0);
    EXPECT_EQ(mapInput(InputEvent::button(GLFW_MOUSE_BUTTON_RIGHT, GLFW_RELEASE, 0, 80, 120),
                       dragging(Drag::Light))
                  .drag,
              Drag::None);
    InputContext overPanel;
    overPanel.panelWantsMouse = true;
    EXPECT_EQ(press(GLFW_MOUSE_BUTTON_RIGHT, 0, overPanel).type, Type::None);
    // The wheel dollies.
    const InputAction wheel = mapInput(InputEvent::scroll(0.0, -2.0), idle());
    EXPECT_EQ(wheel.type, Type::Dolly);
    EXPECT_EQ(wheel.dy, -2.0);
}

TEST(EditInput, PanelsTakeWhatIsOverThem) {
    InputContext overPanel;
    overPanel.panelWantsMouse = true;
    EXPECT_EQ(press(GLFW_MOUSE_BUTTON_LEFT, 0, overPanel).type, Type::None);
    EXPECT_EQ(press(GLFW_MOUSE_BUTTON_MIDDLE, 0, overPanel).drag, Drag::None);
    EXPECT_EQ(mapInput(InputEvent::scroll(0, 1), overPanel).type, Type::None);
    // A stroke begun over the scene ends over a panel.
    InputContext strokeOverPanel = dragging(Drag::Brush);
    strokeOverPanel.panelWantsMouse = true;
    EXPECT_EQ(
        mapInput(InputEvent::button(GLFW_MOUSE_BUTTON_LEFT, GLFW_RELEASE, 0, 0, 0), strokeOverPanel)
            .type,
        Type::BrushRelease);
    // A text field has the keys.
    InputContext typing;
    typing.panelWantsKeyboard = true;
    EXPECT_EQ(key(GLFW_KEY_Z, GLFW_MOD_CONTROL, typing).type, Type::None);
    EXPECT_EQ(key(GLFW_KEY_F, 0, typing).type, Type::None);
    // A second press during a drag does not start another.
    const InputAction second = press(GLFW_MOUSE_BUTTON_LEFT, 0, dragging(Drag::Orbit));
    EXPECT_EQ(second.type, Type::None);
    EXPECT_EQ(second.drag, Drag::Orbit);
}

TEST(EditInput, KeysUndoRedoFrameAndTheBrush) {
    EXPECT_EQ(key(GLFW_KEY_Z, GLFW_MOD_CONTROL).type, Type::Undo);
    EXPECT_EQ(key(GLFW_KEY_Z, GLFW_MOD_CONTROL | GLFW_MOD_SHIFT).type, Type::Redo);
    EXPECT_EQ(key(GLFW_KEY_Y, GLFW_MOD_CONTROL).type, Type::Redo);
    EXPECT_EQ(key(GLFW_KEY_Z, GLFW_MOD_CONTROL, idle(), GLFW_REPEAT).type, Type::Undo);
    EXPECT_EQ(key(GLFW_KEY_Z, GLFW_MOD_CONTROL, idle(), GLFW_RELEASE).type, Type::None);
    EXPECT_EQ(key(GLFW_KEY_Z).type, Type::None);
    EXPECT_EQ(key(GLFW_KEY_F, GLFW_MOD_CONTROL).type, Type::None); // other ctrl keys: nothing
    EXPECT_EQ(key(GLFW_KEY_F).type, Type::FrameMesh);
    EXPECT_EQ(key(GLFW_KEY_HOME).type, Type::FrameMesh);
    const InputAction bigger = key(GLFW_KEY_RIGHT_BRACKET);
    EXPECT_EQ(bigger.type, Type::BrushRadius);
    EXPECT_EQ(bigger.step, 1);
    const InputAction weaker = key(GLFW_KEY_LEFT_BRACKET, GLFW_MOD_SHIFT);
    EXPECT_EQ(weaker.type, Type::BrushStrength);
    EXPECT_EQ(weaker.step, -1);
    for (int k = 0; k < 9; ++k) { // 1..9: density-add .. clump-size
        const InputAction kind = key(GLFW_KEY_1 + k);
        EXPECT_EQ(kind.type, Type::BrushKind);
        EXPECT_EQ(kind.kind, k);
    }
    const InputAction mask = key(GLFW_KEY_0); // the tenth: the mask brush
    EXPECT_EQ(mask.type, Type::BrushKind);
    EXPECT_EQ(mask.kind, 9);
    EXPECT_EQ(key(GLFW_KEY_M).type, Type::MaskOverlay);
    EXPECT_EQ(key(GLFW_KEY_M, 0, idle(), GLFW_REPEAT).type, Type::None); // one toggle a press
    EXPECT_EQ(key(GLFW_KEY_X).type, Type::MirrorX);
    EXPECT_EQ(key(GLFW_KEY_F12).type, Type::Export);
    EXPECT_EQ(key(GLFW_KEY_F12, 0, idle(), GLFW_REPEAT).type, Type::None); // one file a press
    EXPECT_EQ(key(GLFW_KEY_N).type, Type::TogglePanels);
    EXPECT_EQ(key(GLFW_KEY_N, 0, idle(), GLFW_REPEAT).type, Type::None); // one toggle a press
    // No undo or brush change in the middle of a stroke; navigation drags allow them.
    EXPECT_EQ(key(GLFW_KEY_Z, GLFW_MOD_CONTROL, dragging(Drag::Brush)).type, Type::None);
    EXPECT_EQ(key(GLFW_KEY_2, 0, dragging(Drag::Brush)).type, Type::None);
    EXPECT_EQ(key(GLFW_KEY_Z, GLFW_MOD_CONTROL, dragging(Drag::Orbit)).type, Type::Undo);
    EXPECT_EQ(key(GLFW_KEY_Z, GLFW_MOD_CONTROL, dragging(Drag::Orbit)).drag, Drag::Orbit);
}

// The timeline's keys: space plays or pauses (once a press), left and right step a frame (held,
// they repeat); none in the middle of a stroke (the surface would move under the brush) or while
// a panel's text field has the keys.
TEST(EditInput, SpacePlaysAndArrowsStepTheTimeline) {
    EXPECT_EQ(key(GLFW_KEY_SPACE).type, Type::PlayPause);
    EXPECT_EQ(key(GLFW_KEY_SPACE, 0, idle(), GLFW_REPEAT).type, Type::None);
    EXPECT_EQ(key(GLFW_KEY_SPACE, GLFW_MOD_CONTROL).type, Type::None);
    const InputAction forward = key(GLFW_KEY_RIGHT), back = key(GLFW_KEY_LEFT);
    EXPECT_EQ(forward.type, Type::StepFrame);
    EXPECT_EQ(forward.step, 1);
    EXPECT_EQ(back.type, Type::StepFrame);
    EXPECT_EQ(back.step, -1);
    EXPECT_EQ(key(GLFW_KEY_RIGHT, 0, idle(), GLFW_REPEAT).type, Type::StepFrame);
    EXPECT_EQ(key(GLFW_KEY_SPACE, 0, dragging(Drag::Brush)).type, Type::None);
    EXPECT_EQ(key(GLFW_KEY_RIGHT, 0, dragging(Drag::Brush)).type, Type::None);
    InputContext typing;
    typing.panelWantsKeyboard = true;
    EXPECT_EQ(key(GLFW_KEY_SPACE, 0, typing).type, Type::None);
    EXPECT_EQ(key(GLFW_KEY_SPACE, 0, dragging(Drag::Orbit)).type, Type::PlayPause);
}

} // namespace
