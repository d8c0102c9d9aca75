#include "reference.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <optional>

#include <tbb/parallel_for.h>

#include "error.h"
#include "mesh.h"
#include "shaders/spot_light.hpp"
#include "shaders/spot_shared.hpp"
#include "surface.h"
#include "system.h"

namespace spot::noise {

namespace sh = spot::shared::f64;

namespace {

/// Transmittance below which the rest of a ray cannot change a pixel visibly (1e-6 of white).
constexpr double kOpaque = 1e-6;
/// Quadrature steps per cluster at most: a bound on the work of one ray, far above what a
/// converged step needs for the shipped presets (see the convergence tests).
constexpr int kMaxStepsPerCluster = 1 << 16;

/// Kensler's permutation of [0, l) with pattern p (hash with cycle walking).
std::uint32_t permute(std::uint32_t i, std::uint32_t l, std::uint32_t p) {
    std::uint32_t w = l - 1;
    w |= w >> 1;
    w |= w >> 2;
    w |= w >> 4;
    w |= w >> 8;
    w |= w >> 16;
    do {
        i ^= p;
        i *= 0xe170893du;
        i ^= p >> 16;
        i ^= (i & w) >> 4;
        i ^= p >> 8;
        i *= 0x0929eb3fu;
        i ^= p >> 23;
        i ^= (i & w) >> 1;
        i *= 1 | p >> 27;
        i *= 0x6935fa69u;
        i ^= (i & w) >> 11;
        i *= 0x74dcb303u;
        i ^= (i & w) >> 2;
        i *= 0x9e501cc3u;
        i ^= (i & w) >> 2;
        i *= 0xc860a3dfu;
        i &= w;
        i ^= i >> 5;
    } while (i >= l);
    return (i + p) % l;
}

/// Optical depth beyond which a shadow ray stops: e^-30 is far below any visible light.
constexpr double kShadowOpaqueDepth = 30.0;

double randUnit(std::uint32_t i, std::uint32_t p) {
    return double(sh::spotHash(sh::spotHashCombine(p, i)) >> 8) * (1.0 / 16777216.0);
}

} // namespace

glm::dvec2 cmjSample(std::uint32_t s, std::uint32_t n, std::uint32_t p) {
    const std::uint32_t m = std::max(1u, std::uint32_t(std::sqrt(double(n))));
    const std::uint32_t rows = (n + m - 1) / m;
    s = permute(s, n, p * 0x51633e2du);
    const std::uint32_t sx = permute(s % m, m, p * 0x68bc21ebu);
    const std::uint32_t sy = permute(s / m, rows, p * 0x02e5be93u);
    const double jx = randUnit(s, p * 0x967a889bu);
    const double jy = randUnit(s, p * 0x368cc8b7u);
    return {(double(sx) + (double(sy) + jx) / double(rows)) / double(m), (double(s) + jy) / double(n)};
}

/// One lobe's chord along the current ray: the part of the ray inside its truncated support.
struct ReferenceRenderer::Chord {
    double ta, tb;        ///< chord, clipped to [0, end of ray]
    double tStar, len;    ///< peak parameter, |A d|
    double scale;         ///< a sqrt(2 pi) / |A d| exp(-perp^2 / 2): optical depth of the whole line
    std::uint32_t lobe;
    /// Optical depth from ta to t.
    double depthTo(double t) const {
        const double x0 = (ta - tStar) * len * 0.70710678118654752;
        const double x1 = (std::min(t, tb) - tStar) * len * 0.70710678118654752;
        return x1 > x0 ? scale * sh::spotErfDifferenceHalf(x0, x1) : 0.0;
    }
};

ReferenceRenderer::ReferenceRenderer(const Mesh& mesh, const Kernel& kernel,
                                     const std::vector<Impulse>& impulses, const Shading& shading,
                                     glm::vec3 background, glm::vec3 baseColor)
    : m_mesh(mesh), m_support(kernel.supportSigma), m_shading(shading), m_background(background),
      m_baseColor(baseColor), m_impulseCount(impulses.size()) {
    const std::size_t lobeCount = impulses.size() * kernel.lobes.size();
    requireMemory(std::uint64_t(lobeCount) * (sizeof(Lobe) + sizeof(Aabb) + 2 * 64 + 8) +
                      std::uint64_t(mesh.triangles.size()) * (sizeof(Aabb) + 2 * 64 + 8),
                  cat("the reference's ", lobeCount, " lobes"));
    m_lobes.reserve(lobeCount);
    const bool lit = shading.mode == Shading::Mode::Lit;
    std::vector<glm::dvec3> axes; // per kernel lobe: a strand's tangent in kernel space
    std::vector<int> shortest;    // per kernel lobe: its shortest axis (a flake's normal)
    for (const noise::Lobe& l : kernel.lobes) {
        const LobeLitModel lm = lobeLitModel(l);
        LobeModel m;
        m.model = lm.model;
        m.primary = lm.primary;
        m.secondary = lm.secondary;
        m_models.push_back(m);
        axes.push_back(lm.tangent);
        shortest.push_back(lm.shortest);
    }
    if (lit) {
        Aabb bounds;
        for (const glm::vec3& p : mesh.positions)
            bounds.grow(glm::dvec3(p));
        m_epsilon =
            mesh.positions.empty() ? 1e-9 : 1e-6 * (1.0 + glm::length(bounds.hi - bounds.lo));
    }
    std::vector<Aabb> boxes;
    boxes.reserve(lobeCount);
    for (const Impulse& imp : impulses) {
        if (!(imp.weight > 0.0f))
            continue;
        for (std::size_t l = 0; l < kernel.lobes.size(); ++l) {
            const WorldLobe w = placeLobe(kernel, int(l), imp);
            if (!(w.extinction > 0.0))
                continue;
            const glm::dmat3 toWorld = glm::inverse(w.toLobe);
            glm::dvec3 half;
            for (int i = 0; i < 3; ++i)
                half[i] = m_support * glm::length(glm::dvec3(toWorld[0][i], toWorld[1][i], toWorld[2][i]));
            if (!std::isfinite(half.x + half.y + half.z))
                continue;
            glm::vec3 axis(0.0f);
            if (lit && m_models[l].model == sh::kSpotShadeStrand)
                axis = glm::vec3(sh::spotPlacedAxis(axes[l], glm::dvec3(kernel.lobes[l].centre),
                                                    glm::dmat3(imp.frame), glm::dvec3(imp.scale),
                                                    double(imp.bend)));
            else if (lit && m_models[l].model == sh::kSpotShadeFlake)
                axis = glm::vec3(sh::spotPlacedNormal(w.toLobe, shortest[l]));
            m_lobes.push_back({w.centre, w.toLobe, w.extinction, w.color, axis, std::uint32_t(l)});
            boxes.push_back({w.centre - half, w.centre + half});
        }
    }
    m_lobeBvh.build(boxes);
    m_meshBvh = triangleBvh(mesh);
}

double ReferenceRenderer::hitMesh(const Ray& ray, glm::vec3& normal) const {
    const std::optional<MeshHit> hit = closestHit(m_meshBvh, m_mesh, ray);
    if (!hit)
        return std::numeric_limits<double>::infinity();
    normal = surfacePoint(m_mesh, hit->triangle, hit->barycentric).normal;
    return hit->t;
}

glm::vec3 ReferenceRenderer::shade(glm::vec3 color, glm::dvec3 normal) const {
    if (m_shading.mode == Shading::Mode::Unlit)
        return color;
    return color * float(sh::spotLambertFactor(normal, glm::dvec3(m_shading.lightDir),
                                               double(m_shading.ambient)));
}

ReferenceRenderer::Arrival ReferenceRenderer::arrive(const Light& light, glm::dvec3 p) const {
    const glm::dvec3 power = glm::dvec3(light.color) * double(light.intensity);
    if (light.type == Light::Type::Directional)
        return {glm::dvec3(light.direction), std::numeric_limits<double>::infinity(), power};
    const glm::dvec3 to = glm::dvec3(light.position) - p;
    const double d = glm::length(to);
    if (!(d > 0.0))
        return {glm::dvec3(0.0, 1.0, 0.0), 0.0, glm::dvec3(0.0)};
    return {to / d, d, power * sh::spotPointFalloff(1.0, d)};
}

double ReferenceRenderer::transmittance(glm::dvec3 p, glm::dvec3 dir, double distance,
                                        ReferenceStats* stats) const {
    if (stats)
        stats->shadowRays += 1;
    const Ray ray{p, dir};
    if (const std::optional<MeshHit> hit = closestHit(m_meshBvh, m_mesh, ray);
        hit && hit->t < distance)
        return 0.0;
    double tau = 0.0;
    double tMax = distance;
    m_lobeBvh.traverse(ray, 0.0, tMax, [&](std::uint32_t l, double& stop) {
        const Lobe& lobe = m_lobes[l];
        const glm::dvec3 o = lobe.toLobe * (p - lobe.centre);
        const glm::dvec3 d = lobe.toLobe * dir;
        double tStar = 0.0, perp2 = 0.0, half = 0.0;
        if (!sh::spotLobeLine(o, d, m_support, tStar, perp2, half))
            return;
        const double ta = std::max(0.0, tStar - half), tb = std::min(distance, tStar + half);
        if (!(tb > ta))
            return;
        const double len = std::sqrt(glm::dot(d, d));
        const double scale = lobe.extinction * sh::kSqrtTwoPi / len * std::exp(-0.5 * perp2);
        tau += scale * sh::spotErfDifferenceHalf((ta - tStar) * len * sh::kInvSqrtTwo,
                                                 (tb - tStar) * len * sh::kInvSqrtTwo);
        if (tau > kShadowOpaqueDepth)
            stop = -1.0; // no box is crossed any more: the light is gone
    });
    return std::exp(-tau);
}

glm::dvec3 ReferenceRenderer::shadeMeshLit(glm::dvec3 p, glm::dvec3 n, glm::dvec3 v, glm::dvec3 sky,
                                           ReferenceStats* stats) const {
    n = sh::spotTwoSided(n, v);
    const glm::dvec3 origin = p + m_epsilon * n;
    glm::dvec3 sum(0.0);
    for (const Light& light : m_shading.lights) {
        const Arrival a = arrive(light, p);
        const double cosine = std::max(0.0, glm::dot(n, a.dir));
        if (!(cosine > 0.0))
            continue;
        const double t = light.shadows ? transmittance(origin, a.dir, a.distance, stats) : 1.0;
        sum += a.radiance * (cosine * t);
    }
    if (m_shading.sky.intensity > 0.0f) {
        const double cosine = std::max(0.0, glm::dot(n, sky));
        if (cosine > 0.0)
            sum += 2.0 * glm::dvec3(m_shading.sky.color) * double(m_shading.sky.intensity) *
                   cosine *
                   transmittance(origin, sky, std::numeric_limits<double>::infinity(), stats);
    }
    return sum * glm::dvec3(m_baseColor);
}

glm::vec3 ReferenceRenderer::radiance(const Ray& ray, double stepScale, ReferenceStats* stats,
                                      double* coverage, glm::dvec2 skySample) const {
    glm::vec3 meshNormal(0.0f);
    const double tEnd = hitMesh(ray, meshNormal);

    // 1. Chords of every lobe the ray crosses before the mesh.
    // Per-thread scratch: no allocation per ray once warm.
    thread_local std::vector<Chord> chords;
    thread_local std::vector<double> done; // optical depth of each cluster lobe so far
    thread_local std::vector<double> stepDepth; // lit: each cluster lobe's optical depth in a step
    chords.clear();
    double tMax = tEnd;
    m_lobeBvh.traverse(ray, 0.0, tMax, [&](std::uint32_t l, double&) {
        const Lobe& lobe = m_lobes[l];
        const glm::dvec3 o = lobe.toLobe * (ray.origin - lobe.centre);
        const glm::dvec3 d = lobe.toLobe * ray.dir;
        double tStar = 0.0, perp2 = 0.0, half = 0.0;
        if (!sh::spotLobeLine(o, d, m_support, tStar, perp2, half))
            return;
        const double ta = std::max(0.0, tStar - half), tb = std::min(tEnd, tStar + half);
        if (!(tb > ta))
            return;
        const double len = std::sqrt(glm::dot(d, d));
        chords.push_back({ta, tb, tStar, len,
                          lobe.extinction * sh::kSqrtTwoPi / len * std::exp(-0.5 * perp2), l});
    });
    std::sort(chords.begin(), chords.end(), [](const Chord& a, const Chord& b) {
        return a.ta < b.ta || (a.ta == b.ta && a.lobe < b.lobe);
    });

    // Lambert and Lit shade per step (the normal or the light varies inside a lobe).
    const bool lit = m_shading.mode != Shading::Mode::Unlit;
    const bool lights = m_shading.mode == Shading::Mode::Lit;
    const glm::dvec3 skyDir = sh::spotSkyDirection(skySample.x, skySample.y);
    const glm::dvec3 skyRadiance =
        glm::dvec3(m_shading.sky.color) * double(m_shading.sky.intensity);
    const glm::dvec3 view = -ray.dir;

    // Lit: the light one quadrature step of cluster [i, j) at `mid` sends to the eye per unit of
    // optical depth: each light through each lobe's model (shaders/spot_light.h), weighted by
    // the lobe's share of the step's depth `tau`, attenuated by a shadow ray; the sky likewise
    // from its one direction. `n` is the gradient normal (the lambert model's).
    const auto lightStep = [&](std::size_t first, std::size_t last, glm::dvec3 mid, glm::dvec3 n,
                               double tau) {
        glm::dvec3 sum(0.0);
        const auto each = [&](const auto& add) {
            for (std::size_t c = first; c < last; ++c) {
                const double depth = stepDepth[c - first];
                if (!(depth > 0.0))
                    continue;
                const Lobe& lobe = m_lobes[chords[c].lobe];
                const LobeModel& m = m_models[lobe.kernelLobe];
                add(depth, lobe, m, m.model == sh::kSpotShadeLambert ? n : glm::dvec3(lobe.axis));
            }
        };
        for (const Light& light : m_shading.lights) {
            const Arrival a = arrive(light, mid);
            const double t = light.shadows ? transmittance(mid, a.dir, a.distance, stats) : 1.0;
            if (!(t > 0.0))
                continue;
            each([&](double depth, const Lobe& lobe, const LobeModel& m, glm::dvec3 axis) {
                sum += (depth * t) * a.radiance *
                       sh::spotLobeShade(m.model, axis, a.dir, view, glm::dvec3(lobe.color),
                                         m.primary, m.secondary);
            });
        }
        if (m_shading.sky.intensity > 0.0f) {
            const double t =
                transmittance(mid, skyDir, std::numeric_limits<double>::infinity(), stats);
            if (t > 0.0)
                each([&](double depth, const Lobe& lobe, const LobeModel& m, glm::dvec3 axis) {
                    sum += (2.0 * depth * t * sh::spotLobeDiffuse(m.model, axis, skyDir, view)) *
                           skyRadiance * glm::dvec3(lobe.color);
                });
        }
        return sum / tau;
    };

    // 2. Front to back over clusters of overlapping chords.
    glm::dvec3 radiance(0.0);
    double transmittance = 1.0;
    std::size_t i = 0;
    while (i < chords.size() && transmittance > kOpaque) {
        std::size_t j = i + 1;
        double clusterEnd = chords[i].tb;
        while (j < chords.size() && chords[j].ta < clusterEnd) {
            clusterEnd = std::max(clusterEnd, chords[j].tb);
            ++j;
        }
        if (stats)
            stats->chords += j - i;
        if (j == i + 1 && !lit) {
            const Chord& c = chords[i];
            const double tau = c.depthTo(c.tb);
            radiance += transmittance * -std::expm1(-tau) * glm::dvec3(m_lobes[c.lobe].color);
            transmittance *= std::exp(-tau);
            if (stats)
                stats->exactChords += 1;
            i = j;
            continue;
        }
        // Quadrature over the cluster.
        const double clusterStart = chords[i].ta;
        double thinnest = std::numeric_limits<double>::infinity();
        for (std::size_t c = i; c < j; ++c)
            thinnest = std::min(thinnest, 1.0 / chords[c].len);
        const double step = std::max(stepScale * 0.25 * thinnest, 1e-300);
        const int steps = int(std::clamp(std::ceil((clusterEnd - clusterStart) / step), 1.0,
                                         double(kMaxStepsPerCluster)));
        done.assign(j - i, 0.0);
        stepDepth.assign(j - i, 0.0);
        double t0 = clusterStart;
        for (int s = 1; s <= steps && transmittance > kOpaque; ++s) {
            const double t1 = s == steps ? clusterEnd : clusterStart + (clusterEnd - clusterStart) * s / steps;
            double tau = 0.0;
            glm::dvec3 emitted(0.0), gradient(0.0);
            const glm::dvec3 mid = ray.origin + 0.5 * (t0 + t1) * ray.dir;
            for (std::size_t c = i; c < j; ++c) {
                const Chord& ch = chords[c];
                if (ch.ta >= t1 || ch.tb <= t0) {
                    stepDepth[c - i] = 0.0;
                    continue;
                }
                const double upTo = ch.depthTo(t1);
                const double dTau = upTo - done[c - i];
                done[c - i] = upTo;
                stepDepth[c - i] = dTau;
                tau += dTau;
                emitted += dTau * glm::dvec3(m_lobes[ch.lobe].color);
                if (lit) {
                    const Lobe& lobe = m_lobes[ch.lobe];
                    const glm::dvec3 u = lobe.toLobe * (mid - lobe.centre);
                    gradient += sh::spotLobeGradient(
                        lobe.toLobe, u, lobe.extinction * sh::spotLobeDensity(u, m_support));
                }
            }
            if (tau > 0.0) {
                glm::dvec3 color = emitted / tau;
                const glm::dvec3 n =
                    lit ? sh::spotGradientNormal(gradient, view,
                                                 std::numeric_limits<double>::infinity())
                        : glm::dvec3(0.0);
                if (lights)
                    color = lightStep(i, j, mid, n, tau);
                else if (lit)
                    color = glm::dvec3(shade(glm::vec3(color), n));
                radiance += transmittance * -std::expm1(-tau) * color;
                transmittance *= std::exp(-tau);
            }
            t0 = t1;
        }
        if (stats)
            stats->quadratureSteps += std::uint64_t(steps);
        i = j;
    }
    glm::dvec3 behind(m_background);
    if (std::isfinite(tEnd) && lights)
        behind = transmittance > kOpaque ? shadeMeshLit(ray.origin + tEnd * ray.dir,
                                                        glm::dvec3(meshNormal), view, skyDir, stats)
                                         : glm::dvec3(0.0);
    else if (std::isfinite(tEnd))
        behind = glm::dvec3(shade(m_baseColor, glm::dvec3(meshNormal)));
    radiance += transmittance * behind;
    if (coverage)
        *coverage = std::isfinite(tEnd) ? 1.0 : 1.0 - transmittance;
    if (stats)
        stats->rays += 1;
    return glm::vec3(radiance);
}

Image ReferenceRenderer::render(const Camera& camera, const ReferenceSettings& settings,
                                const std::function<void(int, int)>& progress,
                                ReferenceStats* stats) const {
    if (settings.spp < 1 || settings.spp > 65536)
        throw InputError(cat("spp ", settings.spp, " is outside [1, 65536]"));
    if (!(settings.stepScale > 0.0) || !std::isfinite(settings.stepScale))
        throw InputError(cat("step scale ", settings.stepScale, " must be positive"));
    requireMemory(std::uint64_t(camera.width) * std::uint64_t(camera.height) * 64u,
                  cat("a ", camera.width, "x", camera.height, " image"));
    const CameraRays rays(camera);
    const auto start = std::chrono::steady_clock::now();
    const PixelRect full{0, 0, camera.width, camera.height};
    const PixelRect w = settings.window.empty() ? full : settings.window;
    if (w.x0 < 0 || w.y0 < 0 || w.x1 > camera.width || w.y1 > camera.height)
        throw InputError(cat("pixels ", w.x0, ",", w.y0, ",", w.x1, ",", w.y1, " are outside the ",
                             camera.width, "x", camera.height, " image"));
    Image image(w.width(), w.height());
    if (w != full) {
        image.crop = w;
        image.fullWidth = camera.width;
        image.fullHeight = camera.height;
    }
    image.alpha.resize(image.pixels.size());
    image.background = m_background;
    std::atomic<int> rowsDone{0};
    const bool lit = m_shading.mode == Shading::Mode::Lit;
    std::vector<ReferenceStats> rowStats(std::size_t(w.height()));
    tbb::parallel_for(w.y0, w.y1, [&](int y) {
        ReferenceStats& rs = rowStats[std::size_t(y - w.y0)];
        for (int x = w.x0; x < w.x1; ++x) {
            const std::uint32_t pattern =
                sh::spotHashCombine(sh::spotHashCombine(settings.seed ^ 0x2545f491u, std::uint32_t(x)),
                                    std::uint32_t(y));
            // Lit: the sky's directions, stratified over the pixel's samples like its positions.
            const std::uint32_t skyPattern = sh::spotHashCombine(pattern, 0x5bd1e995u);
            glm::dvec3 sum(0.0);
            double covered = 0.0;
            for (int s = 0; s < settings.spp; ++s) {
                const glm::dvec2 u = cmjSample(std::uint32_t(s), std::uint32_t(settings.spp), pattern);
                const glm::dvec2 sky =
                    lit ? cmjSample(std::uint32_t(s), std::uint32_t(settings.spp), skyPattern)
                        : glm::dvec2(0.5);
                double c = 0.0;
                sum += glm::dvec3(
                    radiance(rays.ray(x + u.x, y + u.y), settings.stepScale, &rs, &c, sky));
                covered += c;
            }
            image.at(x - w.x0, y - w.y0) = glm::vec3(sum / double(settings.spp));
            image.alpha[std::size_t(y - w.y0) * std::size_t(w.width()) + std::size_t(x - w.x0)] =
                float(covered / double(settings.spp));
        }
        const int finished = ++rowsDone;
        if (progress)
            progress(finished, w.height());
    });
    if (stats) {
        for (const ReferenceStats& rs : rowStats) {
            stats->rays += rs.rays;
            stats->chords += rs.chords;
            stats->exactChords += rs.exactChords;
            stats->quadratureSteps += rs.quadratureSteps;
            stats->shadowRays += rs.shadowRays;
        }
        stats->seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        stats->impulses = m_impulseCount;
        stats->lobes = m_lobes.size();
        stats->memoryBytes = m_lobes.capacity() * sizeof(Lobe) + m_lobeBvh.memoryBytes() +
                             m_meshBvh.memoryBytes();
    }
    return image;
}

} // namespace spot::noise
