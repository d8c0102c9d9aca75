// Lobe math: the analytic line integral against numerical quadrature, EWA widening conserving
// mass, and degenerate lobes staying finite.
#include <cmath>
#include <random>
#include <string>

#include <glm/gtc/matrix_transform.hpp>
#include <gtest/gtest.h>

#include "noise/impulses.h"
#include "noise/kernel.h"
#include "shaders/spot_shared.hpp"

namespace {

using namespace spot;
namespace f64 = spot::shared::f64;
namespace f32 = spot::shared::f32;

/// A random rotation, uniform enough for tests (random axis and angle).
glm::dmat3 randomRotation(std::mt19937& rng) {
    std::normal_distribution<double> g;
    glm::dvec3 axis(g(rng), g(rng), g(rng));
    axis = glm::normalize(axis);
    std::uniform_real_distribution<double> angle(0.0, 2.0 * M_PI);
    return glm::dmat3(glm::rotate(glm::dmat4(1.0), angle(rng), axis));
}

struct TestLobe {
    glm::dvec3 centre;
    glm::dmat3 toLobe; ///< A: world -> lobe
};

/// Random anisotropic lobe: sigmas log-uniform in [lo, hi], random rotation.
TestLobe randomLobe(std::mt19937& rng, double lo = 0.02, double hi = 2.0) {
    std::uniform_real_distribution<double> logSigma(std::log(lo), std::log(hi));
    std::uniform_real_distribution<double> pos(-1.0, 1.0);
    const glm::dvec3 sigma(std::exp(logSigma(rng)), std::exp(logSigma(rng)),
                           std::exp(logSigma(rng)));
    const glm::dmat3 r = randomRotation(rng);
    const glm::dmat3 invS(glm::dvec3(1.0 / sigma.x, 0, 0), glm::dvec3(0, 1.0 / sigma.y, 0),
                          glm::dvec3(0, 0, 1.0 / sigma.z));
    return {glm::dvec3(pos(rng), pos(rng), pos(rng)), invS * glm::transpose(r)};
}

/// Composite Gauss-Legendre (5 points per panel) of the truncated lobe density along the ray.
double quadrature(const TestLobe& lobe, glm::dvec3 o, glm::dvec3 d, double t0, double t1, double k,
                  int panels) {
    static const double x[5] = {-0.9061798459386640, -0.5384693101056831, 0.0,
                                0.5384693101056831, 0.9061798459386640};
    static const double w[5] = {0.2369268850561891, 0.4786286704993665, 0.5688888888888889,
                                0.4786286704993665, 0.2369268850561891};
    // Integrate only over the truncation chord, found independently by solving |u(t)| = k.
    const glm::dvec3 uo = lobe.toLobe * (o - lobe.centre), ud = lobe.toLobe * d;
    const double a = glm::dot(ud, ud), b = 2.0 * glm::dot(uo, ud), c = glm::dot(uo, uo) - k * k;
    const double disc = b * b - 4.0 * a * c;
    if (disc <= 0.0)
        return 0.0;
    const double lo = std::max(t0, (-b - std::sqrt(disc)) / (2.0 * a));
    const double hi = std::min(t1, (-b + std::sqrt(disc)) / (2.0 * a));
    if (hi <= lo)
        return 0.0;
    double sum = 0.0;
    const double step = (hi - lo) / panels;
    for (int p = 0; p < panels; ++p) {
        const double mid = lo + (p + 0.5) * step;
        for (int i = 0; i < 5; ++i) {
            const double t = mid + 0.5 * step * x[i];
            const glm::dvec3 u = lobe.toLobe * (o + t * d - lobe.centre);
            sum += w[i] * 0.5 * step * std::exp(-0.5 * glm::dot(u, u));
        }
    }
    return sum;
}

TEST(LobeMath, LineIntegralMatchesQuadratureForRandomLobesAndRays) {
    std::mt19937 rng(1234);
    std::uniform_real_distribution<double> unit(-1.0, 1.0);
    int checked = 0;
    for (int trial = 0; trial < 400; ++trial) {
        const TestLobe lobe = randomLobe(rng);
        // A ray through a point near the lobe (within ~1.5 sigma in lobe space), random direction,
        // non-unit length on purpose.
        const glm::dmat3 toWorld = glm::inverse(lobe.toLobe);
        const glm::dvec3 through =
            lobe.centre + toWorld * (1.5 * glm::dvec3(unit(rng), unit(rng), unit(rng)));
        const glm::dvec3 d =
            glm::normalize(glm::dvec3(unit(rng), unit(rng), unit(rng))) * (0.5 + 2.0 * (trial % 3));
        const glm::dvec3 o = through - 7.0 * d;
        const double k = (trial % 2 == 0) ? 3.0 : 50.0; // truncated, and effectively untruncated
        // Whole line, and a finite segment that cuts the lobe.
        for (int segment = 0; segment < 2; ++segment) {
            const double t0 = segment == 0 ? -1e6 : 6.7 + 0.1 * unit(rng);
            const double t1 = segment == 0 ? 1e6 : 7.2 + 0.1 * unit(rng);
            double tPeak = 0.0;
            const double analytic = f64::spotLobeDepth(lobe.toLobe * (o - lobe.centre),
                                                       lobe.toLobe * d, t0, t1, k, tPeak);
            const double numeric = quadrature(lobe, o, d, t0, t1, k, 4000);
            if (numeric < 1e-12)
                continue; // the ray missed the support: nothing to compare relatively
            EXPECT_NEAR(analytic / numeric, 1.0, 1e-5)
                << "trial " << trial << " segment " << segment << " analytic " << analytic
                << " numeric " << numeric;
            ++checked;
        }
    }
    EXPECT_GT(checked, 600);
}

TEST(LobeMath, WholeLineClosedFormMatchesDesignFormula) {
    // docs/design.md section 1: tau = a sqrt(2 pi) / |d'| exp(-1/2 (|o'|^2 - (o'.d')^2 / |d'|^2)).
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> unit(-1.0, 1.0);
    for (int i = 0; i < 100; ++i) {
        const glm::dvec3 o(unit(rng), unit(rng), unit(rng)), d(unit(rng), unit(rng), unit(rng));
        double tPeak = 0.0;
        const double tau = f64::spotLobeDepth(o, d, -1e9, 1e9, 1e3, tPeak);
        const double dd = glm::dot(d, d), od = glm::dot(o, d);
        const double expected =
            std::sqrt(2.0 * M_PI) / std::sqrt(dd) * std::exp(-0.5 * (glm::dot(o, o) - od * od / dd));
        EXPECT_NEAR(tau / expected, 1.0, 1e-12);
        EXPECT_NEAR(tPeak, -od / dd, 1e-12);
    }
}

/// Sum of optical depth over a fine grid of parallel rays along `dir`: the lobe's mass projected
/// on the image plane (per unit peak extinction).
double projectedMass(const TestLobe& lobe, glm::dvec3 dir, double amplitude, double halfWidth,
                     int n) {
    glm::dvec3 e1, e2;
    f64::spotOrthonormalBasis(dir, e1, e2);
    const double step = 2.0 * halfWidth / n;
    double sum = 0.0;
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
            const glm::dvec3 o = lobe.centre + (-halfWidth + (i + 0.5) * step) * e1 +
                                 (-halfWidth + (j + 0.5) * step) * e2 - 100.0 * dir;
            double tPeak = 0.0;
            sum += f64::spotLobeDepth(lobe.toLobe * (o - lobe.centre), lobe.toLobe * dir, -1e9,
                                      1e9, 60.0, tPeak);
        }
    return amplitude * sum * step * step;
}

TEST(LobeMath, EwaWideningConservesMass) {
    std::mt19937 rng(99);
    std::uniform_real_distribution<double> unit(-1.0, 1.0);
    for (int trial = 0; trial < 6; ++trial) {
        // Sigmas in [0.1, 1] so the image-plane grid below resolves every lobe.
        TestLobe lobe = randomLobe(rng, 0.1, 1.0);
        lobe.centre = glm::dvec3(0.0);
        const glm::dvec3 dir = glm::normalize(glm::dvec3(unit(rng), unit(rng), unit(rng)));
        const double s = 0.05 + 0.3 * trial;
        double amplitude = 0.0;
        const TestLobe widened{lobe.centre, f64::spotWidenLobe(lobe.toLobe, dir, s, amplitude)};
        // Closed form: mass = a (2 pi)^3/2 sqrt(det V) = a (2 pi)^3/2 / |det A|.
        const double mass = std::pow(2.0 * M_PI, 1.5) / std::abs(glm::determinant(lobe.toLobe));
        const double massWidened =
            amplitude * std::pow(2.0 * M_PI, 1.5) / std::abs(glm::determinant(widened.toLobe));
        EXPECT_NEAR(massWidened / mass, 1.0, 1e-10) << "trial " << trial;
        EXPECT_LT(amplitude, 1.0);
        // And numerically: the optical depth integrated over the image plane is unchanged.
        const double half = 7.0 * std::sqrt(1.0 + s * s);
        const double before = projectedMass(lobe, dir, 1.0, half, 700);
        const double after = projectedMass(widened, dir, amplitude, half, 700);
        EXPECT_NEAR(after / before, 1.0, 2e-4) << "trial " << trial << " s " << s;
        EXPECT_NEAR(before / mass, 1.0, 2e-3) << "trial " << trial;
    }
}

/// What a lobe covers of the image plane seen along `dir`: the integral of the opacity
/// 1 - exp(-tau) over a fine grid of parallel rays (tau the untruncated line integral times
/// `amplitude`), and the opacity footprint's covariance in the basis spotOrthonormalBasis(dir).
struct Footprint {
    double area = 0.0;
    glm::dmat2 covariance{0.0};
};
double largestEigenvalue(const glm::dmat2& m) {
    const double tr = m[0][0] + m[1][1], det = glm::determinant(m);
    return 0.5 * tr + std::sqrt(std::max(0.25 * tr * tr - det, 0.0));
}

Footprint opacityFootprint(const TestLobe& lobe, glm::dvec3 dir, double amplitude, double halfWidth,
                           int n) {
    glm::dvec3 e1, e2;
    f64::spotOrthonormalBasis(dir, e1, e2);
    const double step = 2.0 * halfWidth / n;
    double sum = 0.0;
    glm::dvec2 first(0.0);
    glm::dmat2 second(0.0);
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
            const glm::dvec2 q(-halfWidth + (i + 0.5) * step, -halfWidth + (j + 0.5) * step);
            const glm::dvec3 o = lobe.centre + q.x * e1 + q.y * e2 - 100.0 * dir;
            double tPeak = 0.0;
            const double alpha =
                -std::expm1(-amplitude * f64::spotLobeDepth(lobe.toLobe * (o - lobe.centre),
                                                            lobe.toLobe * dir, -1e9, 1e9, 60.0,
                                                            tPeak));
            sum += alpha;
            first += alpha * q;
            second += alpha * glm::outerProduct(q, q);
        }
    Footprint f;
    f.area = sum * step * step;
    const glm::dvec2 mean = first / sum;
    f.covariance = second / sum - glm::outerProduct(mean, mean);
    return f;
}

TEST(LobeMath, EinAndItsInverse) {
    // Ein(x) = integral_0^x (1 - e^-u) / u du, against composite Simpson with 20000 panels.
    for (double x : {1e-6, 1e-3, 0.1, 0.5, 0.999, 1.0, 1.001, 2.0, 5.0, 10.0, 30.0, 200.0}) {
        const int n = 20000;
        const auto f = [](double u) { return u > 0.0 ? -std::expm1(-u) / u : 1.0; };
        double sum = f(0.0) + f(x);
        for (int i = 1; i < n; ++i)
            sum += (i % 2 ? 4.0 : 2.0) * f(x * i / n);
        const double exact = sum * x / (3.0 * n);
        EXPECT_NEAR(f64::spotEin(x) / exact, 1.0, 3e-7) << x;
        EXPECT_NEAR(f32::spotEin(float(x)) / exact, 1.0, 2e-6) << x;
        // The inverse finds x again.
        EXPECT_NEAR(f64::spotEinInverse(f64::spotEin(x)) / x, 1.0, 1e-6) << x;
        EXPECT_NEAR(f32::spotEinInverse(f32::spotEin(float(x))) / x, 1.0, 2e-5) << x;
    }
    EXPECT_EQ(f64::spotEin(0.0), 0.0);
    EXPECT_EQ(f64::spotEinInverse(0.0), 0.0);
    // Monotone across the switch between the series and the asymptotic form.
    for (double x = 0.9; x < 1.1; x += 1e-3)
        EXPECT_LT(f64::spotEin(x), f64::spotEin(x + 1e-3)) << x;
}

TEST(LobeMath, CoverageWideningKeepsTheOpacityFootprint) {
    // The widening's CPU twin against a brute-force integral of the opacity 1 - e^-depth over the
    // image plane, before and after, for lobes from nearly transparent to opaque, long blades
    // tilted against the view included: the widened lobe covers the same area, and its opacity
    // footprint's covariance is the lobe's plus the pixel filter's s^2 on each axis (what the box
    // filter does to it). The mass-keeping widening covers more wherever the lobe is opaque (the
    // splatting's brightness this replaces); keeping the coverage with the shape merely widened
    // shortens opaque blades along their length.
    std::mt19937 rng(41);
    std::uniform_real_distribution<double> unit(-1.0, 1.0);
    std::uniform_real_distribution<double> logPeak(std::log(0.01), std::log(100.0));
    double worstMassKept = 0.0, worstShortened = 1.0;
    for (int trial = 0; trial < 12; ++trial) {
        TestLobe lobe = randomLobe(rng, 0.05, 1.0);
        lobe.centre = glm::dvec3(0.0);
        glm::dvec3 dir = glm::normalize(glm::dvec3(unit(rng), unit(rng), unit(rng)));
        if (trial % 3 == 0) { // a long thin blade, its long axis 70 degrees from the view
            const glm::dmat3 r = randomRotation(rng);
            lobe.toLobe = glm::dmat3(glm::dvec3(1.0 / 0.06, 0, 0), glm::dvec3(0, 1.0 / 0.01, 0),
                                     glm::dvec3(0, 0, 1.0)) *
                          glm::transpose(r);
            dir = glm::normalize(std::cos(1.2) * r[2] + std::sin(1.2) * r[0]);
        }
        const double s = 0.02 + 0.1 * trial;
        const double peak = trial == 0 ? 60.0 : std::exp(logPeak(rng));
        const double amplitude = peak * glm::length(lobe.toLobe * dir) / f64::kSqrtTwoPi;
        double widenedAmplitude = amplitude;
        const TestLobe widened{lobe.centre,
                               f64::spotWidenLobeCoverage(lobe.toLobe, dir, s, widenedAmplitude)};
        double massScale = 0.0;
        const TestLobe massWidened{lobe.centre, f64::spotWidenLobe(lobe.toLobe, dir, s, massScale)};
        const glm::dmat3 v = glm::inverse(glm::transpose(lobe.toLobe) * lobe.toLobe);
        const double half = 9.0 * std::sqrt(std::max({v[0][0], v[1][1], v[2][2]}) + s * s);
        const Footprint before = opacityFootprint(lobe, dir, amplitude, half, 900);
        const Footprint after = opacityFootprint(widened, dir, widenedAmplitude, half, 900);
        const std::string label = "trial " + std::to_string(trial) + " peak depth " +
                                  std::to_string(peak) + " s " + std::to_string(s);
        EXPECT_NEAR(after.area / before.area, 1.0, 3e-3) << label;
        const glm::dmat2 expected = before.covariance + glm::dmat2(s * s);
        const double scale = std::max(expected[0][0], expected[1][1]);
        for (int c = 0; c < 2; ++c)
            for (int r = 0; r < 2; ++r)
                EXPECT_NEAR(after.covariance[c][r], expected[c][r], 5e-3 * scale) << label;
        worstMassKept = std::max(
            worstMassKept,
            opacityFootprint(massWidened, dir, amplitude * massScale, half, 900).area / before.area);
        if (trial % 3 == 0) { // the shape merely widened, coverage kept: the blade's length
            double shapeOnly = amplitude;
            const TestLobe plain{lobe.centre, f64::spotWidenLobe(lobe.toLobe, dir, s, shapeOnly)};
            const double peakPlain = f64::spotEinInverse(
                massScale * glm::length(lobe.toLobe * dir) / glm::length(plain.toLobe * dir) *
                f64::spotEin(peak));
            const Footprint p = opacityFootprint(
                plain, dir, peakPlain * glm::length(plain.toLobe * dir) / f64::kSqrtTwoPi, half, 900);
            worstShortened =
                std::min(worstShortened, largestEigenvalue(p.covariance) / largestEigenvalue(expected));
        }
    }
    EXPECT_GT(worstMassKept, 1.2);   // what the mass-keeping widening adds, somewhere
    EXPECT_LT(worstShortened, 0.8);  // and how much shorter the shape-only widening leaves a blade
}

TEST(LobeMath, WideningAddsFootprintVariancePerpendicularToTheView) {
    // V' = V + s^2 (I - d d^T): the widened covariance (A'^T A')^-1 minus V is s^2 (I - d d^T).
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> unit(-1.0, 1.0);
    for (int trial = 0; trial < 50; ++trial) {
        const TestLobe lobe = randomLobe(rng);
        const glm::dvec3 dir = glm::normalize(glm::dvec3(unit(rng), unit(rng), unit(rng)));
        const double s = 0.01 + std::abs(unit(rng));
        double amplitude = 0.0;
        const glm::dmat3 a2 = f64::spotWidenLobe(lobe.toLobe, dir, s, amplitude);
        const glm::dmat3 v = glm::inverse(glm::transpose(lobe.toLobe) * lobe.toLobe);
        const glm::dmat3 v2 = glm::inverse(glm::transpose(a2) * a2);
        const glm::dmat3 expected = v + s * s * (glm::dmat3(1.0) - glm::outerProduct(dir, dir));
        for (int c = 0; c < 3; ++c)
            for (int r = 0; r < 3; ++r)
                EXPECT_NEAR(v2[c][r], expected[c][r], 1e-9 * (1.0 + std::abs(expected[c][r])));
    }
}

TEST(LobeMath, DegenerateLobesStayFinite) {
    noise::KernelDesc desc;
    desc.supportSigma = 3.0f;
    noise::LobeDesc zero; // a zero sigma
    zero.sigma = glm::vec3(0.0f, 1.0f, 1.0f);
    zero.rotationDeg = glm::vec3(10.0f, 20.0f, 30.0f);
    noise::LobeDesc flat; // 1e4:1 anisotropy
    flat.sigma = glm::vec3(1e-4f, 1.0f, 1.0f);
    flat.rotationDeg = glm::vec3(45.0f, 30.0f, 60.0f);
    noise::LobeDesc needle;
    needle.sigma = glm::vec3(1e-4f, 1e-4f, 1.0f);
    desc.lobes = {zero, flat, needle};
    const noise::Kernel kernel = noise::buildKernel(desc);

    noise::Impulse imp;
    imp.scale = glm::vec3(0.01f);
    imp.bend = 0.3f;
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> unit(-1.0, 1.0);
    int hits = 0;
    for (int l = 0; l < 3; ++l) {
        const noise::WorldLobe w = noise::placeLobe(kernel, l, imp);
        for (int i = 0; i < 2000; ++i) {
            const glm::dvec3 dir = glm::normalize(glm::dvec3(unit(rng), unit(rng), unit(rng)));
            const glm::dvec3 o = w.centre + 0.02 * glm::dvec3(unit(rng), unit(rng), unit(rng)) -
                                 dir * 0.1;
            for (double s : {0.0, 1e-6, 1e-3}) {
                double amp = 1.0;
                const glm::dmat3 a = s > 0.0 ? f64::spotWidenLobe(w.toLobe, dir, s, amp) : w.toLobe;
                double tPeak = 0.0;
                const double tau =
                    amp * f64::spotLobeDepth(a * (o - w.centre), a * dir, 0.0, 1.0, 3.0, tPeak);
                ASSERT_TRUE(std::isfinite(tau) && tau >= 0.0) << "lobe " << l << " s " << s;
                ASSERT_TRUE(std::isfinite(amp) && amp > 0.0 && amp <= 1.0);
                hits += tau > 0.0;
                // The GPU's float twin must stay finite too.
                float ampF = 1.0f;
                const glm::mat3 aF = s > 0.0 ? f32::spotWidenLobe(glm::mat3(w.toLobe),
                                                                  glm::vec3(dir), float(s), ampF)
                                             : glm::mat3(w.toLobe);
                float tPeakF = 0.0f;
                const float tauF = ampF * f32::spotLobeDepth(aF * glm::vec3(o - w.centre),
                                                             aF * glm::vec3(dir), 0.0f, 1.0f,
                                                             3.0f, tPeakF);
                ASSERT_TRUE(std::isfinite(tauF) && tauF >= 0.0f) << "lobe " << l << " s " << s;
            }
        }
    }
    EXPECT_GT(hits, 0);
}

TEST(LobeMath, FloatTwinAgreesWithDouble) {
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> unit(-1.0, 1.0);
    for (int i = 0; i < 1000; ++i) {
        const TestLobe lobe = randomLobe(rng);
        const glm::dvec3 o(unit(rng), unit(rng), unit(rng));
        const glm::dvec3 d = glm::normalize(glm::dvec3(unit(rng), unit(rng), unit(rng)));
        double tp = 0.0;
        float tpf = 0.0f;
        const glm::dvec3 uo = lobe.toLobe * (o - lobe.centre), ud = lobe.toLobe * d;
        const double t64 = f64::spotLobeDepth(uo, ud, -0.5, 0.7, 3.0, tp);
        const float t32 = f32::spotLobeDepth(glm::vec3(uo), glm::vec3(ud), -0.5f, 0.7f, 3.0f, tpf);
        EXPECT_NEAR(t32, t64, 1e-5 * (1.0 + t64)) << i;
    }
}

TEST(LobeMath, KernelSupportRadiusHoldsBentLobes) {
    noise::KernelDesc desc;
    noise::LobeDesc a;
    a.offset = glm::vec3(0.1f, 0.0f, 1.5f);
    a.sigma = glm::vec3(0.1f, 0.1f, 0.4f);
    desc.lobes = {a};
    const noise::Kernel kernel = noise::buildKernel(desc);
    const float radius = kernel.supportRadius();
    noise::Impulse imp;
    for (float bend : {0.0f, 0.5f, 2.0f, -3.0f}) {
        imp.bend = bend;
        const noise::WorldLobe w = noise::placeLobe(kernel, 0, imp);
        // Farthest point of the truncated ellipsoid from the origin <= radius.
        const glm::dmat3 toWorld = glm::inverse(w.toLobe);
        double farthest = 0.0;
        for (int i = 0; i < 2000; ++i) {
            const double th = M_PI * (i % 40) / 39.0, ph = 2.0 * M_PI * (i / 40) / 50.0;
            const glm::dvec3 u(std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph),
                               std::cos(th));
            farthest = std::max(farthest, glm::length(w.centre + toWorld * (3.0 * u)));
        }
        EXPECT_LE(farthest, radius * (1.0 + 1e-6)) << "bend " << bend;
    }
}

} // namespace
