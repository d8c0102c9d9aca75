/// @file edit_view.h
/// @brief The editor window's layout and navigation. The layout: the viewport (the scene) at the
/// top left and the panels in a column along the right edge, never over the scene. The
/// navigation, Blender-like: orbit around a target (turntable about the scene's up vector), pan
/// in the view plane, dolly towards the target, and framing a bounding sphere. Pure math, no
/// window system: the window feeds it its size and pointer motion in window pixels and reads the
/// viewport and the camera back.
#pragma once

#include <glm/glm.hpp>

#include "noise/camera.h"

namespace spot::noise {
struct Mesh;
}

namespace spot::editor {

/// Where the scene and the panels go in a window (pixels from the top left): the viewport at
/// (0, 0), viewportWidth x height; the panels' column right of it, columnWidth x height (0:
/// hidden). Together they fill the window and never overlap.
struct WindowLayout {
    int width = 0, height = 0; ///< the window's framebuffer
    int viewportWidth = 0;     ///< the scene's width (its height is the window's)
    int columnWidth = 0;       ///< the panels' column, at x = viewportWidth (0: hidden)

    int viewportHeight() const { return height; }
    bool columnShown() const { return columnWidth > 0; }
    /// The point (window pixels) is over the scene, not the column or outside the window.
    bool inViewport(double x, double y) const {
        return x >= 0.0 && y >= 0.0 && x < viewportWidth && y < height;
    }
};

/// Windows narrower than this start with the column hidden (the scene alone; N shows it).
constexpr int kColumnMinWindowWidth = 560;

/// The layout of a width x height window with the column shown or not: 30% of the width, between
/// 300 and 400 pixels, and always leaving the scene at least 160 pixels (hidden when it would be
/// narrower than 200).
WindowLayout windowLayout(int width, int height, bool column);

/// A sphere around every vertex of a mesh (world units): the centre of the bounding box and the
/// largest distance from it.
struct BoundingSphere {
    glm::dvec3 center{0.0};
    double radius = 1.0;
};
BoundingSphere boundingSphere(const noise::Mesh& mesh);

class OrbitView {
public:
    /// Starts at `camera` (its eye, target, up, projection and field of view).
    explicit OrbitView(const noise::Camera& camera);

    /// The camera now, with the given image size in pixels (the aspect ratio follows it).
    noise::Camera camera(int width, int height) const;

    /// Turntable orbit by a pointer motion in window pixels: dragging right turns the scene to
    /// the right (the eye goes left around the target), dragging down shows it from higher up.
    /// `viewHeight` (pixels) sets the rate: a drag over the whole height turns by pi.
    void orbit(double dx, double dy, double viewHeight);
    /// Move eye and target in the view plane so that the point under the pointer follows it
    /// (exactly at the target's depth). `viewHeight` in pixels.
    void pan(double dx, double dy, double viewHeight);
    /// Dolly towards the target by wheel steps (positive: closer); each step scales the
    /// distance (or the orthographic height) by 0.85. Never closer than 1e-4 world units.
    void dolly(double steps);
    /// Look at the sphere's centre from the current direction, from the distance at which the
    /// sphere fits the narrower of the two fields of view with 5% margin.
    void frame(const BoundingSphere& sphere, double aspect);

    glm::dvec3 eye() const { return m_eye; }
    glm::dvec3 target() const { return m_target; }
    double distance() const;

private:
    noise::Camera m_base; ///< projection and field of view
    glm::dvec3 m_eye, m_target, m_up;
};

/// `camera` with its image shifted by (dx, dy) pixels (x right, y down; sub-pixel jitter for
/// the idle refinement). Perspective: the view turns about the eye (the target moves in the
/// view plane), which shifts the centre of the image by exactly (dx, dy) pixels and the corners
/// by at most (1 + tan^2(fov / 2)) times that; orthographic: eye and target move together.
noise::Camera jitteredCamera(const noise::Camera& camera, double dx, double dy);

/// Point `index` of the Halton (2, 3) sequence minus 0.5: a jitter in [-0.5, 0.5)^2 pixels.
glm::dvec2 haltonJitter(int index);

} // namespace spot::editor
