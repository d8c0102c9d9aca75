#include "kernel.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <mutex>

#include <glm/gtc/matrix_transform.hpp>
#include <tbb/parallel_for.h>

#include "error.h"
#include "impulses.h"
#include "shaders/spot_light.hpp"
#include "shaders/spot_shadow.hpp"
#include "shaders/spot_shared.hpp"

namespace spot::noise {

namespace {

/// R = Rz * Ry * Rx from XYZ Euler angles in degrees (x applied first).
glm::mat3 eulerXyz(glm::vec3 degrees) {
    const glm::vec3 r = glm::radians(degrees);
    const glm::mat4 m = glm::rotate(glm::mat4(1.0f), r.z, glm::vec3(0, 0, 1)) *
                        glm::rotate(glm::mat4(1.0f), r.y, glm::vec3(0, 1, 0)) *
                        glm::rotate(glm::mat4(1.0f), r.x, glm::vec3(1, 0, 0));
    return glm::mat3(m);
}

} // namespace

float Kernel::supportRadius() const {
    float radius = 0.0f;
    for (const Lobe& lobe : lobes) {
        const float sideways = std::hypot(lobe.centre.x, lobe.centre.y);
        const float maxSigma = std::max({lobe.sigma.x, lobe.sigma.y, lobe.sigma.z});
        radius = std::max(radius, std::abs(lobe.centre.z) + sideways + supportSigma * maxSigma);
    }
    return radius;
}

Kernel buildKernel(const KernelDesc& desc) {
    SPOT_CHECK(!desc.lobes.empty());
    SPOT_CHECK_LE(desc.lobes.size(), static_cast<std::size_t>(kMaxLobes));
    float largest = 0.0f;
    for (const LobeDesc& l : desc.lobes)
        largest = std::max({largest, l.sigma.x, l.sigma.y, l.sigma.z});
    // All-zero sigmas make an invisible kernel; keep it finite with an absolute floor.
    const float floor = largest > 0.0f ? largest * kSigmaFloorRelative : 1e-9f;

    Kernel kernel;
    kernel.supportSigma = desc.supportSigma;
    for (const LobeDesc& l : desc.lobes) {
        Lobe lobe;
        lobe.sigma = glm::max(l.sigma, glm::vec3(floor));
        lobe.centre = l.offset;
        const glm::mat3 rotation = eulerXyz(l.rotationDeg);
        const glm::mat3 linear = rotation * glm::mat3(glm::vec3(lobe.sigma.x, 0, 0),
                                                      glm::vec3(0, lobe.sigma.y, 0),
                                                      glm::vec3(0, 0, lobe.sigma.z));
        lobe.transform = glm::mat4(linear);
        lobe.transform[3] = glm::vec4(l.offset, 1.0f);
        // (R S)^-1 = S^-1 R^T, exact for a rotation.
        lobe.inverseLinear = glm::mat3(glm::vec3(1.0f / lobe.sigma.x, 0, 0),
                                       glm::vec3(0, 1.0f / lobe.sigma.y, 0),
                                       glm::vec3(0, 0, 1.0f / lobe.sigma.z)) *
                             glm::transpose(rotation);
        lobe.extinction = l.extinction;
        lobe.color = l.color;
        lobe.shading = l.shading;
        kernel.lobes.push_back(lobe);
    }
    return kernel;
}

WorldLobe placeLobe(const Kernel& kernel, int lobeIndex, const Impulse& impulse) {
    const Lobe& lobe = kernel.lobes.at(static_cast<std::size_t>(lobeIndex));
    WorldLobe out;
    out.toLobe = shared::f64::spotPlaceLobe(
        glm::dmat3(lobe.inverseLinear), glm::dvec3(lobe.centre), glm::dmat3(impulse.frame),
        glm::dvec3(impulse.scale), double(impulse.bend), glm::dvec3(impulse.position), out.centre);
    out.extinction = double(lobe.extinction) * double(impulse.weight);
    out.color = lobe.color * impulse.color;
    return out;
}

LobeLitModel lobeLitModel(const Lobe& lobe) {
    namespace sh = shared::f64;
    LobeLitModel m;
    switch (lobe.shading.model) {
    case LobeShading::Model::Strand:
        m.model = sh::kSpotShadeStrand;
        break;
    case LobeShading::Model::Flake:
        m.model = sh::kSpotShadeFlake;
        break;
    case LobeShading::Model::Lambert:
        m.model = sh::kSpotShadeLambert;
        break;
    }
    int k = 0;
    for (int i = 1; i < 3; ++i)
        if (lobe.sigma[i] > lobe.sigma[k])
            k = i;
    glm::dvec3 a = glm::normalize(glm::dvec3(glm::mat3(lobe.transform)[k]));
    const double lead = a.z != 0.0 ? a.z : a.x != 0.0 ? a.x : a.y;
    m.tangent = lead < 0.0 ? -a : a;
    m.shortest = int(std::min_element(&lobe.sigma[0], &lobe.sigma[0] + 3) - &lobe.sigma[0]);
    const auto radians = [](const Highlight& h) {
        return glm::dvec3(glm::radians(double(h.shiftDeg)), glm::radians(double(h.widthDeg)),
                          double(h.strength));
    };
    m.primary = radians(lobe.shading.primary);
    m.secondary = radians(lobe.shading.secondary);
    return m;
}

glm::dvec3 placedShadingAxis(const Kernel& kernel, int lobeIndex, const Impulse& impulse,
                             const WorldLobe& placed) {
    namespace sh = shared::f64;
    const Lobe& lobe = kernel.lobes.at(static_cast<std::size_t>(lobeIndex));
    const LobeLitModel m = lobeLitModel(lobe);
    if (m.model == sh::kSpotShadeStrand)
        return sh::spotPlacedAxis(m.tangent, glm::dvec3(lobe.centre), glm::dmat3(impulse.frame),
                                  glm::dvec3(impulse.scale), double(impulse.bend));
    if (m.model == sh::kSpotShadeFlake) {
        const glm::dvec3 n = sh::spotPlacedNormal(placed.toLobe, m.shortest);
        return glm::dot(n, glm::dvec3(impulse.normal)) < 0.0 ? -n : n;
    }
    return glm::dvec3(0.0);
}

const std::vector<float>& ownShadowTable(float support) {
    static std::mutex mutex;
    static std::map<float, std::vector<float>> tables;
    const std::lock_guard<std::mutex> lock(mutex);
    std::vector<float>& table = tables[support];
    if (!table.empty())
        return table;
    using namespace gpu;
    table.resize(std::size_t(kOwnShadowA) * kOwnShadowB * kOwnShadowC);
    // Float, as the shaders evaluate it; one slice of c per task.
    tbb::parallel_for(std::uint32_t(0), kOwnShadowC, [&](std::uint32_t ic) {
        const float c = -1.0f + 2.0f * float(ic) / float(kOwnShadowC - 1);
        for (std::uint32_t ib = 0; ib < kOwnShadowB; ++ib)
            for (std::uint32_t ia = 0; ia < kOwnShadowA; ++ia)
                table[(std::size_t(ic) * kOwnShadowB + ib) * kOwnShadowA + ia] =
                    shared::f32::spotOwnShadow(spotOwnShadowNode(ia, kOwnShadowA),
                                               spotOwnShadowNode(ib, kOwnShadowB), c, support, 3u);
    });
    return table;
}

float ownShadowLookup(const std::vector<float>& table, float a, float b, float c) {
    using namespace gpu;
    glm::vec3 w;
    const std::uint32_t base = spotOwnShadowCell(a, b, c, w);
    float sum = 0.0f;
    for (std::uint32_t z = 0; z < 2; ++z)
        for (std::uint32_t y = 0; y < 2; ++y)
            for (std::uint32_t x = 0; x < 2; ++x)
                sum += (x ? w.x : 1.0f - w.x) * (y ? w.y : 1.0f - w.y) * (z ? w.z : 1.0f - w.z) *
                       table.at(base + (z * kOwnShadowB + y) * kOwnShadowA + x);
    return sum;
}

} // namespace spot::noise
