// Helpers shared by the noise tests: presets built in code, meshes built by hand, statistics.
#pragma once

#include <cmath>
#include <string>
#include <vector>

#include <boost/math/special_functions/gamma.hpp>
#include <glm/gtc/matrix_transform.hpp>

#include "noise/impulses.h"
#include "noise/kernel.h"
#include "noise/mesh.h"
#include "noise/preset.h"
#include "noise/scene.h"

namespace spot::test {

/// The shipped scene presets/scenes/NAME.json. The fur-bunny scenes are lit; a test that gates a
/// method's unlit accuracy on one drops its lights and sky, as `render --unlit` does. A NAME
/// ending in "+lit" keeps them ("fur-bunny+lit").
inline noise::SceneDesc loadShippedScene(std::string name) {
    const std::string suffix = "+lit";
    const bool lit = name.size() > suffix.size() &&
                     name.compare(name.size() - suffix.size(), suffix.size(), suffix) == 0;
    if (lit)
        name.resize(name.size() - suffix.size());
    noise::SceneDesc scene =
        noise::loadScene(std::string(SPOT_SOURCE_DIR) + "/presets/scenes/" + name + ".json");
    if (!lit && scene.shading.mode == noise::Shading::Mode::Lit)
        scene.shading = noise::Shading{};
    return scene;
}

inline noise::FieldDesc constantField(glm::vec3 value, int components) {
    noise::FieldDesc f;
    f.kind = noise::FieldDesc::Kind::Constant;
    f.components = components;
    f.value = value;
    return f;
}

/// One isotropic lobe of sigma 1 kernel unit, scale `scale`, constant density 1: the support
/// radius (and so the default cell size) is 3 * scale.
inline noise::PresetDesc uniformPreset(float densityMax, float scale = 0.01f,
                                       noise::DistributionType type = noise::DistributionType::Poisson) {
    noise::PresetDesc p;
    p.name = "test-uniform";
    noise::LobeDesc lobe;
    lobe.sigma = glm::vec3(1.0f);
    lobe.extinction = 50.0f;
    p.kernel.lobes = {lobe};
    p.kernel.supportSigma = 3.0f;
    p.distribution.type = type;
    p.distribution.densityMax = densityMax;
    p.density = constantField(glm::vec3(1.0f), 1);
    p.tiltDeg = constantField(glm::vec3(0.0f), 1);
    p.spinDeg = constantField(glm::vec3(0.0f), 1);
    p.bendDeg = constantField(glm::vec3(0.0f), 1);
    p.scale = constantField(glm::vec3(scale), 3);
    p.color = constantField(glm::vec3(1.0f), 3);
    p.weight = constantField(glm::vec3(1.0f), 1);
    return p;
}

/// Rigidly move a mesh (positions and normals, tangents) by rotation `r` then translation `t`.
inline void transformMesh(noise::Mesh& mesh, const glm::mat3& r, glm::vec3 t) {
    for (glm::vec3& p : mesh.positions)
        p = r * p + t;
    for (glm::vec3& n : mesh.normals)
        n = r * n;
    for (glm::vec3& v : mesh.tangents)
        v = r * v;
}

inline glm::mat3 rotation(float angle, glm::vec3 axis) {
    return glm::mat3(glm::rotate(glm::mat4(1.0f), angle, glm::normalize(axis)));
}

/// A flat 2 x 1 rectangle in the xz plane (y = 0, normal +y): the left unit square cut into
/// 20 x 20 quads, the right one into 2 x 2, so triangle areas differ by 100x.
inline noise::Mesh mixedPlane() {
    noise::Mesh m;
    m.name = "mixed-plane";
    auto grid = [&](float x0, int n) {
        const std::uint32_t base = std::uint32_t(m.positions.size());
        for (int j = 0; j <= n; ++j)
            for (int i = 0; i <= n; ++i)
                m.positions.emplace_back(x0 + float(i) / n, 0.0f, float(j) / n);
        for (int j = 0; j < n; ++j)
            for (int i = 0; i < n; ++i) {
                const std::uint32_t a = base + std::uint32_t(j * (n + 1) + i);
                const std::uint32_t b = a + 1, c = a + std::uint32_t(n + 1), d = c + 1;
                // counter-clockwise seen from +y
                m.triangles.emplace_back(a, c, b);
                m.triangles.emplace_back(b, c, d);
            }
    };
    grid(0.0f, 20);
    grid(1.0f, 2);
    noise::finalizeMesh(m);
    return m;
}

/// A kernel of one lobe (kernel units; extinction 1 / world unit).
inline noise::Kernel oneLobeKernel(glm::vec3 sigma, glm::vec3 rotationDeg, float extinction,
                                   glm::vec3 color, float support) {
    noise::KernelDesc desc;
    noise::LobeDesc lobe;
    lobe.sigma = sigma;
    lobe.rotationDeg = rotationDeg;
    lobe.extinction = extinction;
    lobe.color = color;
    desc.lobes = {lobe};
    desc.supportSigma = support;
    return noise::buildKernel(desc);
}

/// An impulse at `position` with the identity frame and unit scale.
inline noise::Impulse impulseAt(glm::vec3 position) {
    noise::Impulse imp;
    imp.position = position;
    imp.frame = glm::mat3(1.0f);
    imp.scale = glm::vec3(1.0f);
    return imp;
}

/// Optical depth of a world lobe along a whole line: docs/design.md section 1's closed form, written
/// independently of the shared header's.
inline double closedFormDepth(const noise::WorldLobe& lobe, glm::dvec3 o, glm::dvec3 d) {
    const glm::dvec3 op = lobe.toLobe * (o - lobe.centre), dp = lobe.toLobe * d;
    const double dd = glm::dot(dp, dp), od = glm::dot(op, dp);
    return lobe.extinction * std::sqrt(2.0 * M_PI) / std::sqrt(dd) *
           std::exp(-0.5 * (glm::dot(op, op) - od * od / dd));
}

/// Upper-tail p-value of a chi-square statistic with `dof` degrees of freedom.
inline double chiSquareP(double statistic, double dof) {
    return boost::math::gamma_q(dof / 2.0, statistic / 2.0);
}

/// Pearson's chi-square of observed counts against expected fractions (summing to 1).
inline double chiSquare(const std::vector<double>& observed, const std::vector<double>& fraction) {
    double n = 0.0;
    for (double o : observed)
        n += o;
    double chi2 = 0.0;
    for (std::size_t i = 0; i < observed.size(); ++i) {
        const double e = n * fraction[i];
        chi2 += (observed[i] - e) * (observed[i] - e) / e;
    }
    return chi2;
}

} // namespace spot::test
