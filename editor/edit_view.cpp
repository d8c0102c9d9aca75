#include "edit_view.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include <glm/gtc/matrix_transform.hpp>

#include "noise/mesh.h"

namespace spot::editor {

namespace {

constexpr double kMinDistance = 1e-4;
/// Keeps the view direction this far (radians) from the up vector: the camera's basis is
/// undefined when they are parallel.
constexpr double kPoleMargin = 1e-3;

glm::dvec3 rotate(glm::dvec3 v, glm::dvec3 axis, double angle) {
    return glm::dvec3(glm::rotate(glm::dmat4(1.0), angle, glm::normalize(axis)) *
                      glm::dvec4(v, 0.0));
}

} // namespace

WindowLayout windowLayout(int width, int height, bool column) {
    WindowLayout l;
    l.width = std::max(width, 0);
    l.height = std::max(height, 0);
    if (column) {
        const int wanted = std::clamp(int(std::lround(0.3 * l.width)), 300, 400);
        const int fits = std::min(wanted, l.width - 160);
        l.columnWidth = fits >= 200 ? fits : 0;
    }
    l.viewportWidth = l.width - l.columnWidth;
    return l;
}

BoundingSphere boundingSphere(const noise::Mesh& mesh) {
    BoundingSphere s;
    if (mesh.positions.empty())
        return s;
    const noise::Bounds b = mesh.bounds();
    s.center = (glm::dvec3(b.lo) + glm::dvec3(b.hi)) * 0.5;
    double r2 = 0.0;
    for (const glm::vec3& p : mesh.positions) {
        const glm::dvec3 d = glm::dvec3(p) - s.center;
        r2 = std::max(r2, glm::dot(d, d));
    }
    s.radius = std::max(std::sqrt(r2), kMinDistance);
    return s;
}

OrbitView::OrbitView(const noise::Camera& camera)
    : m_base(camera), m_eye(camera.eye), m_target(camera.target), m_up(glm::normalize(camera.up)) {}

noise::Camera OrbitView::camera(int width, int height) const {
    noise::Camera c = m_base;
    c.eye = m_eye;
    c.target = m_target;
    c.up = m_up;
    c.width = width;
    c.height = height;
    return c;
}

double OrbitView::distance() const {
    return glm::length(m_eye - m_target);
}

void OrbitView::orbit(double dx, double dy, double viewHeight) {
    const double perPixel = std::numbers::pi / std::max(viewHeight, 1.0);
    glm::dvec3 offset = m_eye - m_target;
    offset = rotate(offset, m_up, -dx * perPixel);
    // Elevation: the angle between the offset and up, kept away from both poles.
    const double r = glm::length(offset);
    const double polar = std::acos(std::clamp(glm::dot(offset / r, m_up), -1.0, 1.0));
    const double wanted =
        std::clamp(polar - dy * perPixel, kPoleMargin, std::numbers::pi - kPoleMargin);
    const glm::dvec3 right = glm::cross(m_up, offset);
    if (glm::length(right) > 0.0)
        offset = rotate(offset, right, wanted - polar); // a positive turn moves away from up
    m_eye = m_target + offset;
}

void OrbitView::pan(double dx, double dy, double viewHeight) {
    const double height = m_base.projection == noise::Projection::Orthographic
                              ? m_base.orthoHeight
                              : 2.0 * distance() * std::tan(glm::radians(m_base.fovYDeg) * 0.5);
    const double perPixel = height / std::max(viewHeight, 1.0);
    const glm::dvec3 forward = glm::normalize(m_target - m_eye);
    const glm::dvec3 right = glm::normalize(glm::cross(forward, m_up));
    const glm::dvec3 up = glm::cross(right, forward);
    // The scene follows the pointer: the camera moves the other way.
    const glm::dvec3 move = (-dx * right + dy * up) * perPixel;
    m_eye += move;
    m_target += move;
}

void OrbitView::dolly(double steps) {
    const double scale = std::pow(0.85, steps);
    if (m_base.projection == noise::Projection::Orthographic) {
        m_base.orthoHeight = std::max(m_base.orthoHeight * scale, kMinDistance);
        return;
    }
    const glm::dvec3 offset = m_eye - m_target;
    const double d = std::max(glm::length(offset) * scale, kMinDistance);
    m_eye = m_target + glm::normalize(offset) * d;
}

void OrbitView::frame(const BoundingSphere& sphere, double aspect) {
    constexpr double kMargin = 1.05;
    const glm::dvec3 direction = glm::normalize(m_eye - m_target);
    m_target = sphere.center;
    if (m_base.projection == noise::Projection::Orthographic) {
        m_base.orthoHeight = 2.0 * sphere.radius * kMargin / std::min(1.0, aspect);
        m_eye = m_target + direction * (sphere.radius * 3.0);
        return;
    }
    const double halfY = glm::radians(m_base.fovYDeg) * 0.5;
    const double halfX = std::atan(std::tan(halfY) * aspect);
    const double half = std::min(halfX, halfY);
    m_eye = m_target + direction * (sphere.radius * kMargin / std::sin(half));
}

noise::Camera jitteredCamera(const noise::Camera& camera, double dx, double dy) {
    noise::Camera c = camera;
    const glm::dvec3 forward = glm::normalize(camera.target - camera.eye);
    const glm::dvec3 right = glm::normalize(glm::cross(forward, camera.up));
    const glm::dvec3 up = glm::cross(right, forward);
    const double distance = glm::length(camera.target - camera.eye);
    const double height = camera.projection == noise::Projection::Perspective
                              ? 2.0 * distance * std::tan(glm::radians(camera.fovYDeg) * 0.5)
                              : camera.orthoHeight;
    const double pixel = height / double(std::max(camera.height, 1));
    // The view moves by -(dx, dy) so that the image moves by +(dx, dy); window y grows down.
    const glm::dvec3 shift = -right * (dx * pixel) + up * (dy * pixel);
    c.target += shift;
    if (camera.projection != noise::Projection::Perspective)
        c.eye += shift;
    return c;
}

glm::dvec2 haltonJitter(int index) {
    auto radical = [](int i, int base) {
        double f = 1.0, r = 0.0;
        for (; i > 0; i /= base) {
            f /= base;
            r += f * (i % base);
        }
        return r;
    };
    return {radical(index + 1, 2) - 0.5, radical(index + 1, 3) - 0.5};
}

} // namespace spot::editor
