#include "image_compare.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "noise/error.h"

namespace spot::splat {

namespace {

using noise::Image;

/// Display-referred values: clamp, sRGB encode.
std::vector<glm::dvec3> display(const Image& image) {
    std::vector<glm::dvec3> out(image.pixels.size());
    for (std::size_t i = 0; i < out.size(); ++i)
        for (int c = 0; c < 3; ++c)
            out[i][c] = noise::srgbEncode(image.pixels[i][c]);
    return out;
}

void requireSameSize(const Image& a, const Image& b) {
    if (a.width != b.width || a.height != b.height)
        throw InputError(cat("images differ in size: ", a.width, "x", a.height, " and ", b.width,
                             "x", b.height));
    if (a.width <= 0 || a.height <= 0)
        throw InputError("images are empty");
}

/// Index with mirrored edges (... 1 0 | 0 1 2 ... n-1 | n-1 n-2 ...), as scipy's 'symm'.
int mirror(int i, int n) {
    if (n == 1)
        return 0;
    while (i < 0 || i >= n) {
        if (i < 0)
            i = -i - 1;
        if (i >= n)
            i = 2 * n - i - 1;
    }
    return i;
}

int clampIndex(int i, int n) { return std::clamp(i, 0, n - 1); }

/// Separable or full 2D convolution of a single-channel image with a square kernel of radius r,
/// edges handled by `edge` (mirror or clamp).
std::vector<double> convolve(const std::vector<double>& img, int w, int h,
                             const std::vector<double>& kernel, int r, int (*edge)(int, int)) {
    std::vector<double> out(img.size(), 0.0);
    const int size = 2 * r + 1;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            double sum = 0.0;
            for (int j = -r; j <= r; ++j) {
                const int yy = edge(y + j, h);
                for (int i = -r; i <= r; ++i)
                    sum += kernel[std::size_t((j + r) * size + (i + r))] *
                           img[std::size_t(yy * w + edge(x + i, w))];
            }
            out[std::size_t(y * w + x)] = sum;
        }
    return out;
}

// ---- FLIP colour spaces (the constants of the FLIP reference code) ----------------------------

glm::dvec3 srgbToLinear(glm::dvec3 c) {
    for (int i = 0; i < 3; ++i)
        c[i] = c[i] > 0.04045 ? std::pow((c[i] + 0.055) / 1.055, 2.4) : c[i] / 12.92;
    return c;
}

glm::dvec3 linearToXyz(glm::dvec3 c) {
    return {(10135552.0 * c.r + 8788810.0 * c.g + 4435075.0 * c.b) / 24577794.0,
            (2613072.0 * c.r + 8788810.0 * c.g + 887015.0 * c.b) / 12288897.0,
            (1425312.0 * c.r + 8788810.0 * c.g + 70074185.0 * c.b) / 73733382.0};
}

glm::dvec3 xyzToLinear(glm::dvec3 c) {
    return {3.241003232976358 * c.x - 1.537398969488785 * c.y - 0.498615881996363 * c.z,
            -0.969224252202516 * c.x + 1.875929983695176 * c.y + 0.041554226340085 * c.z,
            0.055639419851975 * c.x - 0.204011206123910 * c.y + 1.057148977187533 * c.z};
}

const glm::dvec3& whitePoint() {
    static const glm::dvec3 white = linearToXyz(glm::dvec3(1.0));
    return white;
}

glm::dvec3 xyzToYcxcz(glm::dvec3 c) {
    c /= whitePoint();
    return {116.0 * c.y - 16.0, 500.0 * (c.x - c.y), 200.0 * (c.y - c.z)};
}

glm::dvec3 ycxczToXyz(glm::dvec3 c) {
    const double y = (c.x + 16.0) / 116.0;
    return glm::dvec3(y + c.y / 500.0, y, y - c.z / 200.0) * whitePoint();
}

glm::dvec3 xyzToLab(glm::dvec3 c) {
    c /= whitePoint();
    const double delta = 6.0 / 29.0, limit = 0.00885;
    for (int i = 0; i < 3; ++i)
        c[i] = c[i] > limit ? std::cbrt(c[i]) : c[i] / (3.0 * delta * delta) + 4.0 / 29.0;
    return {116.0 * c.y - 16.0, 500.0 * (c.x - c.y), 200.0 * (c.y - c.z)};
}

glm::dvec3 hunt(glm::dvec3 lab) { return {lab.x, 0.01 * lab.x * lab.y, 0.01 * lab.x * lab.z}; }

double hyab(glm::dvec3 a, glm::dvec3 b) {
    return std::abs(a.x - b.x) + std::hypot(a.y - b.y, a.z - b.z);
}

/// CSF-based spatial filter kernel of one opponent channel (0 achromatic, 1 red-green,
/// 2 blue-yellow), normalized to sum 1.
std::vector<double> spatialFilter(double ppd, int channel, int& radius) {
    static constexpr double a1[3] = {1.0, 1.0, 34.1}, b1[3] = {0.0047, 0.0053, 0.04};
    static constexpr double a2[3] = {0.0, 0.0, 13.5}, b2[3] = {1e-5, 1e-5, 0.025};
    const double maxScale = 0.04; // the largest b over all channels
    radius = int(std::ceil(3.0 * std::sqrt(maxScale / (2.0 * M_PI * M_PI)) * ppd));
    const int size = 2 * radius + 1;
    std::vector<double> k(std::size_t(size * size));
    double sum = 0.0;
    const double dx = 1.0 / ppd;
    for (int y = -radius; y <= radius; ++y)
        for (int x = -radius; x <= radius; ++x) {
            const double z = (x * dx) * (x * dx) + (y * dx) * (y * dx);
            const double g = a1[channel] * std::sqrt(M_PI / b1[channel]) *
                                 std::exp(-M_PI * M_PI * z / b1[channel]) +
                             a2[channel] * std::sqrt(M_PI / b2[channel]) *
                                 std::exp(-M_PI * M_PI * z / b2[channel]);
            k[std::size_t((y + radius) * size + (x + radius))] = g;
            sum += g;
        }
    for (double& v : k)
        v /= sum;
    return k;
}

/// Edge (first derivative) or point (second derivative) detector of FLIP's feature pipeline, in
/// x; positive weights sum to 1 and negative to -1.
std::vector<double> featureFilter(double ppd, bool edge, int& radius) {
    const double w = 0.082;
    const double sd = 0.5 * w * ppd;
    radius = int(std::ceil(3.0 * sd));
    const int size = 2 * radius + 1;
    std::vector<double> k(std::size_t(size * size));
    double pos = 0.0, neg = 0.0;
    for (int y = -radius; y <= radius; ++y)
        for (int x = -radius; x <= radius; ++x) {
            const double g = std::exp(-(x * x + y * y) / (2.0 * sd * sd));
            const double v = edge ? -x * g : (x * x / (sd * sd) - 1.0) * g;
            k[std::size_t((y + radius) * size + (x + radius))] = v;
            (v > 0 ? pos : neg) += v;
        }
    for (double& v : k)
        v = v > 0 ? v / pos : (v < 0 ? v / -neg : 0.0);
    return k;
}

std::vector<double> transposeKernel(const std::vector<double>& k, int r) {
    const int size = 2 * r + 1;
    std::vector<double> t(k.size());
    for (int y = 0; y < size; ++y)
        for (int x = 0; x < size; ++x)
            t[std::size_t(x * size + y)] = k[std::size_t(y * size + x)];
    return t;
}

} // namespace

double psnr(const Image& reference, const Image& test) {
    requireSameSize(reference, test);
    const auto a = display(reference), b = display(test);
    double sum = 0.0;
    for (std::size_t i = 0; i < a.size(); ++i) {
        const glm::dvec3 d = a[i] - b[i];
        sum += glm::dot(d, d);
    }
    const double mse = sum / (3.0 * double(a.size()));
    return mse > 0.0 ? 10.0 * std::log10(1.0 / mse) : std::numeric_limits<double>::infinity();
}

double ssim(const Image& reference, const Image& test) {
    requireSameSize(reference, test);
    const int w = reference.width, h = reference.height;
    const auto a = display(reference), b = display(test);
    std::vector<double> x(a.size()), y(a.size()), xx(a.size()), yy(a.size()), xy(a.size());
    for (std::size_t i = 0; i < a.size(); ++i) {
        x[i] = 0.2126 * a[i].r + 0.7152 * a[i].g + 0.0722 * a[i].b;
        y[i] = 0.2126 * b[i].r + 0.7152 * b[i].g + 0.0722 * b[i].b;
        xx[i] = x[i] * x[i];
        yy[i] = y[i] * y[i];
        xy[i] = x[i] * y[i];
    }
    const int r = 5;
    std::vector<double> k(121);
    double sum = 0.0;
    for (int j = -r; j <= r; ++j)
        for (int i = -r; i <= r; ++i)
            sum += k[std::size_t((j + r) * 11 + (i + r))] = std::exp(-(i * i + j * j) / (2.0 * 1.5 * 1.5));
    for (double& v : k)
        v /= sum;
    const auto mx = convolve(x, w, h, k, r, mirror), my = convolve(y, w, h, k, r, mirror);
    const auto sxx = convolve(xx, w, h, k, r, mirror), syy = convolve(yy, w, h, k, r, mirror);
    const auto sxy = convolve(xy, w, h, k, r, mirror);
    const double c1 = 0.01 * 0.01, c2 = 0.03 * 0.03;
    double total = 0.0;
    for (std::size_t i = 0; i < x.size(); ++i) {
        const double vx = sxx[i] - mx[i] * mx[i], vy = syy[i] - my[i] * my[i];
        const double cov = sxy[i] - mx[i] * my[i];
        total += ((2.0 * mx[i] * my[i] + c1) * (2.0 * cov + c2)) /
                 ((mx[i] * mx[i] + my[i] * my[i] + c1) * (vx + vy + c2));
    }
    return total / double(x.size());
}

double flip(const Image& reference, const Image& test, std::vector<float>* errorMap,
            double ppd) {
    requireSameSize(reference, test);
    if (!(ppd > 0.0) || !std::isfinite(ppd))
        throw InputError(cat("pixels per degree ", ppd, " must be positive"));
    const int w = reference.width, h = reference.height;
    const std::size_t n = reference.pixels.size();
    const double qc = 0.7, qf = 0.5, pc = 0.4, pt = 0.95;

    // Both images to YCxCz (linearized CIELAB), channel planes.
    auto toOpponent = [&](const Image& img, std::array<std::vector<double>, 3>& planes) {
        const auto srgb = display(img);
        for (auto& p : planes)
            p.resize(n);
        for (std::size_t i = 0; i < n; ++i) {
            const glm::dvec3 c = xyzToYcxcz(linearToXyz(srgbToLinear(srgb[i])));
            for (int ch = 0; ch < 3; ++ch)
                planes[std::size_t(ch)][i] = c[ch];
        }
    };
    std::array<std::vector<double>, 3> ref, tst;
    toOpponent(reference, ref);
    toOpponent(test, tst);

    // Colour pipeline: CSF filtering (edges replicated), back to linear RGB clamped to [0,1],
    // to CIELAB with the Hunt adjustment, HyAB distance.
    std::array<std::vector<double>, 3> fr, ft;
    for (int ch = 0; ch < 3; ++ch) {
        int r = 0;
        const auto k = spatialFilter(ppd, ch, r);
        fr[std::size_t(ch)] = convolve(ref[std::size_t(ch)], w, h, k, r, clampIndex);
        ft[std::size_t(ch)] = convolve(tst[std::size_t(ch)], w, h, k, r, clampIndex);
    }
    auto labAt = [](const std::array<std::vector<double>, 3>& p, std::size_t i) {
        glm::dvec3 lin = xyzToLinear(ycxczToXyz(glm::dvec3(p[0][i], p[1][i], p[2][i])));
        lin = glm::clamp(lin, glm::dvec3(0.0), glm::dvec3(1.0));
        return hunt(xyzToLab(linearToXyz(lin)));
    };
    const double cmax = std::pow(hyab(hunt(xyzToLab(linearToXyz(glm::dvec3(0, 1, 0)))),
                                      hunt(xyzToLab(linearToXyz(glm::dvec3(0, 0, 1))))),
                                 qc);
    const double pccmax = pc * cmax;

    // Feature pipeline on normalized achromatic channel (mirrored edges).
    std::vector<double> yr(n), yt(n);
    for (std::size_t i = 0; i < n; ++i) {
        yr[i] = (ref[0][i] + 16.0) / 116.0;
        yt[i] = (tst[0][i] + 16.0) / 116.0;
    }
    int re = 0, rp = 0;
    const auto edgeX = featureFilter(ppd, true, re), pointX = featureFilter(ppd, false, rp);
    const auto edgeY = transposeKernel(edgeX, re), pointY = transposeKernel(pointX, rp);
    const auto erx = convolve(yr, w, h, edgeX, re, mirror), ery = convolve(yr, w, h, edgeY, re, mirror);
    const auto etx = convolve(yt, w, h, edgeX, re, mirror), ety = convolve(yt, w, h, edgeY, re, mirror);
    const auto prx = convolve(yr, w, h, pointX, rp, mirror), pry = convolve(yr, w, h, pointY, rp, mirror);
    const auto ptx = convolve(yt, w, h, pointX, rp, mirror), pty = convolve(yt, w, h, pointY, rp, mirror);

    if (errorMap)
        errorMap->assign(n, 0.0f);
    double total = 0.0;
    for (std::size_t i = 0; i < n; ++i) {
        const double dE = std::pow(hyab(labAt(fr, i), labAt(ft, i)), qc);
        const double colour = dE < pccmax ? (pt / pccmax) * dE
                                          : pt + ((dE - pccmax) / (cmax - pccmax)) * (1.0 - pt);
        const double edge = std::abs(std::hypot(erx[i], ery[i]) - std::hypot(etx[i], ety[i]));
        const double point = std::abs(std::hypot(ptx[i], pty[i]) - std::hypot(prx[i], pry[i]));
        const double feature = std::pow(std::max(edge, point) / std::sqrt(2.0), qf);
        const double e = std::pow(colour, 1.0 - feature);
        total += e;
        if (errorMap)
            (*errorMap)[i] = float(e);
    }
    return total / double(n);
}

ImageMetrics compareImages(const Image& reference, const Image& test, std::vector<float>* flipMap,
                           double pixelsPerDegree) {
    requireSameSize(reference, test);
    ImageMetrics m;
    m.psnr = psnr(reference, test);
    m.ssim = ssim(reference, test);
    m.flip = flip(reference, test, flipMap, pixelsPerDegree);
    const auto a = display(reference), b = display(test);
    double sum = 0.0;
    for (std::size_t i = 0; i < a.size(); ++i)
        for (int c = 0; c < 3; ++c) {
            const double d = std::abs(a[i][c] - b[i][c]);
            sum += d;
            m.maxAbs = std::max(m.maxAbs, d);
        }
    m.meanAbs = sum / (3.0 * double(a.size()));
    double sumA = 0.0, sumB = 0.0, sumDisplay = 0.0;
    for (std::size_t i = 0; i < a.size(); ++i)
        for (int c = 0; c < 3; ++c) {
            sumA += reference.pixels[i][c];
            sumB += test.pixels[i][c];
            sumDisplay += b[i][c] - a[i][c];
        }
    const double n = 3.0 * double(a.size());
    m.meanDiffLinear = (sumB - sumA) / n;
    m.meanDiffDisplay = sumDisplay / n;
    m.bias = sumA > 0.0 ? sumB / sumA - 1.0 : 0.0;
    return m;
}

noise::Image heatMap(const std::vector<float>& errors, int width, int height) {
    // A few stops of matplotlib's magma (display values), interpolated.
    static const std::array<glm::vec3, 6> stops = {
        glm::vec3(0.001f, 0.000f, 0.014f), glm::vec3(0.232f, 0.059f, 0.437f),
        glm::vec3(0.550f, 0.161f, 0.506f), glm::vec3(0.868f, 0.288f, 0.409f),
        glm::vec3(0.994f, 0.624f, 0.427f), glm::vec3(0.987f, 0.991f, 0.750f)};
    noise::Image img(width, height);
    for (std::size_t i = 0; i < img.pixels.size() && i < errors.size(); ++i) {
        const float e = std::clamp(errors[i], 0.0f, 1.0f) * float(stops.size() - 1);
        const int lo = std::min(int(e), int(stops.size()) - 2);
        const glm::vec3 c = glm::mix(stops[std::size_t(lo)], stops[std::size_t(lo) + 1], e - float(lo));
        for (int ch = 0; ch < 3; ++ch)
            img.pixels[i][ch] = noise::srgbDecode(c[ch]);
    }
    return img;
}

} // namespace spot::splat
