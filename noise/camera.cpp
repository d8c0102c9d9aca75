#include "camera.h"

#include <cmath>

#include "error.h"
#include "shaders/spot_shared.hpp"

namespace spot::noise {

CameraRays::CameraRays(const Camera& camera) : m_camera(camera) {
    if (camera.width <= 0 || camera.height <= 0)
        throw InputError(cat("camera: image size ", camera.width, "x", camera.height,
                             " must be positive"));
    const glm::dvec3 view = camera.target - camera.eye;
    if (!(glm::length(view) > 0.0) || !std::isfinite(glm::length(view)))
        throw InputError("camera: eye and target must differ and be finite");
    m_forward = glm::normalize(view);
    const glm::dvec3 side = glm::cross(m_forward, camera.up);
    if (!(glm::length(side) > 1e-9))
        throw InputError("camera: up is parallel to the view direction");
    m_right = glm::normalize(side);
    m_up = glm::cross(m_right, m_forward);
    if (camera.projection == Projection::Perspective) {
        if (!(camera.fovYDeg > 0.0 && camera.fovYDeg < 179.0))
            throw InputError(cat("camera: fov_deg ", camera.fovYDeg, " must be in (0, 179)"));
        m_halfHeight = std::tan(0.5 * camera.fovYDeg * M_PI / 180.0);
    } else {
        if (!(camera.orthoHeight > 0.0) || !std::isfinite(camera.orthoHeight))
            throw InputError(cat("camera: ortho_height ", camera.orthoHeight, " must be positive"));
        m_halfHeight = 0.5 * camera.orthoHeight;
    }
    const Ray corners[4] = {ray(0, 0), ray(camera.width, 0), ray(camera.width, camera.height),
                            ray(0, camera.height)};
    const glm::dvec3 inside = ray(0.5 * camera.width, 0.5 * camera.height).origin +
                              ray(0.5 * camera.width, 0.5 * camera.height).dir;
    for (int i = 0; i < 4; ++i) {
        const Ray& a = corners[i];
        const Ray& b = corners[(i + 1) % 4];
        glm::dvec3 n = camera.projection == Projection::Perspective
                           ? glm::cross(a.dir, b.dir)
                           : glm::cross(m_forward, b.origin - a.origin);
        n = glm::normalize(n);
        double d = -glm::dot(n, a.origin);
        if (glm::dot(n, inside) + d < 0.0) {
            n = -n;
            d = -d;
        }
        m_planes[m_planeCount++] = glm::dvec4(n, d);
    }
    if (camera.projection == Projection::Perspective)
        m_planes[m_planeCount++] = glm::dvec4(m_forward, -glm::dot(m_forward, camera.eye));
}

bool CameraRays::boxMayBeVisible(glm::dvec3 lo, glm::dvec3 hi) const {
    for (int p = 0; p < m_planeCount; ++p) {
        const glm::dvec3 n(m_planes[p]);
        // The box corner farthest along n: if even it is outside, the whole box is.
        const glm::dvec3 far(n.x >= 0 ? hi.x : lo.x, n.y >= 0 ? hi.y : lo.y, n.z >= 0 ? hi.z : lo.z);
        if (glm::dot(n, far) + m_planes[p].w < 0.0)
            return false;
    }
    return true;
}

Ray CameraRays::ray(double px, double py) const {
    // The shaders' mapping (spot_shared.h), in double; the GPU gets the same axes and half
    // extents (splat::makeSplatFrame reads them from here).
    Ray r;
    shared::f64::spotPixelRay(m_camera.eye, m_forward, m_right * halfWidth(), m_up * m_halfHeight,
                              m_camera.projection == Projection::Orthographic,
                              glm::dvec2(m_camera.width, m_camera.height), glm::dvec2(px, py),
                              r.origin, r.dir);
    return r;
}

double CameraRays::pixelFootprint(double t) const {
    const double perPixel = 2.0 * m_halfHeight / m_camera.height;
    return m_camera.projection == Projection::Perspective ? perPixel * t : perPixel;
}

} // namespace spot::noise
