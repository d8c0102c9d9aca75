/// @file camera.h
/// @brief Pinhole or orthographic camera and image-plane sampling.
///
/// Pixel coordinates are continuous: (0, 0) is the top-left corner of the top-left pixel,
/// (width, height) the bottom-right corner; pixel (x, y) covers [x, x+1) x [y, y+1).
#pragma once

#include <glm/glm.hpp>

namespace spot::noise {

enum class Projection { Perspective, Orthographic };

struct Camera {
    glm::dvec3 eye{0.0, 0.0, 3.0};
    glm::dvec3 target{0.0};
    glm::dvec3 up{0.0, 1.0, 0.0};
    Projection projection = Projection::Perspective;
    double fovYDeg = 40.0;      ///< perspective: vertical field of view, degrees
    double orthoHeight = 2.0;   ///< orthographic: world units covered vertically
    int width = 256;
    int height = 256;
};

/// A ray o + t d; d is unit length, so t is world distance.
struct Ray {
    glm::dvec3 origin{0.0};
    glm::dvec3 dir{0.0, 0.0, -1.0};
};

/// Precomputed camera basis. Throws InputError for a degenerate camera (eye == target, up
/// parallel to the view, non-positive fov or size).
class CameraRays {
public:
    explicit CameraRays(const Camera& camera);
    /// Ray through continuous pixel position (px, py).
    Ray ray(double px, double py) const;
    /// World-space size of one pixel at distance t along a central ray (the footprint used by
    /// EWA filtering and level of detail).
    double pixelFootprint(double t) const;
    /// False only when the box lies entirely outside the view frustum (conservative: a box
    /// near a corner may be reported visible). Cells failing it generate nothing.
    bool boxMayBeVisible(glm::dvec3 lo, glm::dvec3 hi) const;
    const Camera& camera() const { return m_camera; }
    /// The unit camera axes (world): view direction, right, and up (image rows grow downwards).
    glm::dvec3 forward() const { return m_forward; }
    glm::dvec3 right() const { return m_right; }
    glm::dvec3 up() const { return m_up; }
    /// Half the view's height and width at unit distance (perspective: tan(fov / 2)) or in world
    /// units (orthographic): the lengths of spotPixelRay's `up` and `right` (spot_shared.h).
    double halfHeight() const { return m_halfHeight; }
    double halfWidth() const {
        return m_halfHeight * double(m_camera.width) / double(m_camera.height);
    }

private:
    Camera m_camera;
    glm::dvec3 m_forward, m_right, m_up;
    double m_halfHeight; ///< tan(fov/2) (perspective) or orthoHeight/2 (orthographic)
    /// Frustum side planes (and the near plane for perspective): dot(n, p) + d >= 0 inside.
    glm::dvec4 m_planes[5];
    int m_planeCount = 0;
};

} // namespace spot::noise
