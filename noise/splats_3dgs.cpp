#include "splats_3dgs.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstring>
#include <fstream>
#include <numeric>
#include <ostream>
#include <sstream>

#include <glm/gtc/quaternion.hpp>

#include "shaders/spot_shared.hpp"
#include "error.h"
#include "mesh.h"
#include "system.h"

namespace spot::noise {

static_assert(std::endian::native == std::endian::little, "3DGS PLY I/O assumes little-endian");

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kMinSigma = 1e-30;
constexpr double kMinOpacity = 1e-6;
/// The twin's near plane (world units from the eye's plane): splats nearer are culled, as
/// viewers cull at their near plane (the viewer test's three.js camera: 0.01).
constexpr double kNearPlane = 0.01;

/// The property names of an SH degree-0 file in order, without the f_rest_* block that would
/// follow f_dc_2.
constexpr std::array<const char*, 17> kHead = {
    "x",       "y",       "z",       "nx",      "ny",    "nz",    "f_dc_0", "f_dc_1", "f_dc_2",
    "opacity", "scale_0", "scale_1", "scale_2", "rot_0", "rot_1", "rot_2",  "rot_3"};
constexpr std::size_t kFloats = kHead.size();

/// Eigen-decomposition of a symmetric 3x3 matrix by cyclic Jacobi rotations: `values` ascending
/// is not promised; column i of `vectors` belongs to values[i]. Exact to double rounding for the
/// conditioning lobes have (sigma ratios up to 1e6, kSigmaFloorRelative).
void symmetricEigen(glm::dmat3 a, glm::dvec3& values, glm::dmat3& vectors) {
    vectors = glm::dmat3(1.0);
    for (int sweep = 0; sweep < 50; ++sweep) {
        const double off = a[1][0] * a[1][0] + a[2][0] * a[2][0] + a[2][1] * a[2][1];
        const double diag = a[0][0] * a[0][0] + a[1][1] * a[1][1] + a[2][2] * a[2][2];
        if (off <= 1e-32 * diag || off == 0.0)
            break;
        for (int p = 0; p < 2; ++p)
            for (int q = p + 1; q < 3; ++q) {
                const double apq = a[q][p];
                if (apq == 0.0)
                    continue;
                const double theta = (a[q][q] - a[p][p]) / (2.0 * apq);
                const double t = (theta >= 0.0 ? 1.0 : -1.0) /
                                 (std::abs(theta) + std::sqrt(theta * theta + 1.0));
                const double c = 1.0 / std::sqrt(t * t + 1.0), s = t * c;
                glm::dmat3 j(1.0); // a' = j^T a j
                j[p][p] = c;
                j[q][q] = c;
                j[q][p] = s;
                j[p][q] = -s;
                a = glm::transpose(j) * a * j;
                a[q][p] = a[p][q] = 0.0;
                vectors = vectors * j;
            }
    }
    values = glm::dvec3(a[0][0], a[1][1], a[2][2]);
}

/// Directions on the unit sphere (a Fibonacci lattice): the mean over directions of a lobe's
/// optical depth. 256 points average 1 / |A v| to better than 0.1 % at 100:1 anisotropy.
const std::vector<glm::dvec3>& sphereDirections() {
    static const std::vector<glm::dvec3> directions = [] {
        constexpr int kCount = 256;
        std::vector<glm::dvec3> d;
        const double golden = kPi * (3.0 - std::sqrt(5.0));
        for (int i = 0; i < kCount; ++i) {
            const double z = 1.0 - (2.0 * i + 1.0) / kCount;
            const double r = std::sqrt(1.0 - z * z);
            d.emplace_back(r * std::cos(golden * i), r * std::sin(golden * i), z);
        }
        return d;
    }();
    return directions;
}

Splat3dgs gaussianSplat(glm::dvec3 centre, glm::dvec3 variances, glm::dmat3 axes, double opacity,
                        glm::vec3 linearColor) {
    if (glm::determinant(axes) < 0.0)
        axes[2] = -axes[2];
    Splat3dgs s;
    s.position = glm::vec3(centre);
    for (int i = 0; i < 3; ++i) {
        s.logScale[i] =
            float(std::log(std::max(std::sqrt(std::max(variances[i], 0.0)), kMinSigma)));
        s.dc[i] = float((double(srgbEncode(linearColor[i])) - 0.5) / kShC0);
    }
    const glm::dquat q = glm::normalize(glm::quat_cast(axes));
    s.rotation = glm::vec4(float(q.w), float(q.x), float(q.y), float(q.z));
    const double o = std::clamp(opacity, kMinOpacity, 1.0 - kMinOpacity);
    s.opacityLogit = float(std::log(o / (1.0 - o)));
    return s;
}

glm::vec3 splatDisplayColor(const Splat3dgs& s) {
    return glm::max(glm::vec3(s.dc) * float(kShC0) + 0.5f, glm::vec3(0.0f));
}

} // namespace

Splat3dgs lobeSplat(const WorldLobe& lobe, const SplatOptions& options) {
    // Sigma = A^-1 A^-T; in its eigenframe |A v|^2 = sum u_i^2 / lambda_i, u = R^T v.
    const glm::dmat3 inverse = glm::inverse(lobe.toLobe);
    glm::dvec3 lambda;
    glm::dmat3 axes;
    symmetricEigen(inverse * glm::transpose(inverse), lambda, axes);
    lambda = glm::max(lambda, glm::dvec3(kMinSigma * kMinSigma));
    const auto inverseThickness = [&](glm::dvec3 u) { // 1 / |A v|
        return 1.0 / std::sqrt(u.x * u.x / lambda.x + u.y * u.y / lambda.y + u.z * u.z / lambda.z);
    };
    double thickness = 0.0;
    if (options.eye) {
        const glm::dvec3 v = lobe.centre - *options.eye;
        const double len = glm::length(v);
        thickness =
            inverseThickness(glm::transpose(axes) * (len > 0.0 ? v / len : glm::dvec3(0, 0, 1)));
    } else {
        for (const glm::dvec3& u : sphereDirections())
            thickness += inverseThickness(u);
        thickness /= double(sphereDirections().size());
    }
    const double tau = std::abs(lobe.extinction) * std::sqrt(2.0 * kPi) * thickness;
    const double opacity = -std::expm1(-tau);
    double widen = 1.0; // k^2
    if (options.mapping == SplatMapping::Coverage && opacity > 0.0)
        widen = std::max(1.0, shared::f64::spotEin(tau) / opacity);
    return gaussianSplat(lobe.centre, lambda * widen, axes, opacity, lobe.color);
}

std::vector<Splat3dgs> noiseSplats(const Kernel& kernel, const std::vector<Impulse>& impulses,
                                   const SplatOptions& options) {
    const std::size_t count = impulses.size() * kernel.lobes.size();
    if (count > kMaxSplats)
        throw InputError(cat(count, " splats (", impulses.size(), " kernels x ",
                             kernel.lobes.size(), " lobes) is more than the ", kMaxSplats,
                             " a 3DGS export may hold"));
    requireMemory(count * sizeof(Splat3dgs), cat("the export of ", count, " splats"));
    std::vector<Splat3dgs> splats(count);
    const std::size_t lobes = kernel.lobes.size();
    for (std::size_t i = 0; i < impulses.size(); ++i)
        for (std::size_t l = 0; l < lobes; ++l)
            splats[i * lobes + l] = lobeSplat(placeLobe(kernel, int(l), impulses[i]), options);
    return splats;
}

std::vector<Splat3dgs> meshSplats(const Mesh& mesh, glm::vec3 color, double spread) {
    std::vector<Splat3dgs> splats;
    splats.reserve(mesh.triangles.size());
    for (const glm::uvec3& t : mesh.triangles) {
        const glm::dvec3 v[3] = {glm::dvec3(mesh.positions[t.x]), glm::dvec3(mesh.positions[t.y]),
                                 glm::dvec3(mesh.positions[t.z])};
        const glm::dvec3 m = (v[0] + v[1] + v[2]) / 3.0;
        glm::dmat3 cov(0.0);
        for (const glm::dvec3& p : v)
            cov += glm::outerProduct(p - m, p - m) / 12.0;
        glm::dvec3 lambda;
        glm::dmat3 axes;
        symmetricEigen(cov, lambda, axes);
        // The smallest eigenvalue is the normal's (zero): a hundredth of the thinner side.
        int n = 0;
        for (int i = 1; i < 3; ++i)
            if (lambda[i] < lambda[n])
                n = i;
        double thinner = 1e300;
        for (int i = 0; i < 3; ++i)
            if (i != n)
                thinner = std::min(thinner, lambda[i]);
        lambda *= spread * spread;
        lambda[n] = thinner * spread * spread * 1e-4;
        splats.push_back(gaussianSplat(m, lambda, axes, 0.99, color));
    }
    return splats;
}

void writeSplats3dgs(const std::filesystem::path& file, const std::vector<Splat3dgs>& splats,
                     const std::vector<std::string>& comments) {
    if (splats.size() > kMaxSplats)
        throw InputError(cat(file.string(), ": ", splats.size(), " splats is more than the ",
                             kMaxSplats, " a 3DGS file may hold"));
    for (std::size_t i = 0; i < splats.size(); ++i) {
        const Splat3dgs& s = splats[i];
        const float* f[] = {&s.position.x, &s.dc.x, &s.opacityLogit, &s.logScale.x, &s.rotation.x};
        const int n[] = {3, 3, 1, 3, 4};
        for (int k = 0; k < 5; ++k)
            for (int j = 0; j < n[k]; ++j)
                if (!std::isfinite(f[k][j]))
                    throw InputError(cat(file.string(), ": splat ", i, " has a non-finite value"));
    }
    const std::uint64_t bytes = std::uint64_t(splats.size()) * kFloats * 4 + 4096;
    std::error_code ec;
    const std::filesystem::path dir =
        file.has_parent_path() ? file.parent_path() : std::filesystem::path(".");
    const std::filesystem::space_info space = std::filesystem::space(dir, ec);
    if (!ec && space.available < bytes)
        throw InputError(cat(file.string(), ": ", splats.size(), " splats need ", bytes >> 20,
                             " MiB but only ", space.available >> 20, " MiB are free there"));
    writeFileAtomic(file, [&](std::ostream& out) {
        out << "ply\nformat binary_little_endian 1.0\n";
        for (const std::string& c : comments)
            out << "comment " << oneLine(c) << "\n";
        out << "element vertex " << splats.size() << "\n";
        for (const char* name : kHead)
            out << "property float " << name << "\n";
        out << "end_header\n";
        std::vector<float> buffer;
        buffer.reserve(kFloats * 4096);
        for (std::size_t i = 0; i < splats.size(); ++i) {
            const Splat3dgs& s = splats[i];
            const float record[kFloats] = {
                s.position.x,  s.position.y, s.position.z, 0.0f,          0.0f,
                0.0f,          s.dc.x,       s.dc.y,       s.dc.z,        s.opacityLogit,
                s.logScale.x,  s.logScale.y, s.logScale.z, s.rotation[0], s.rotation[1],
                s.rotation[2], s.rotation[3]};
            buffer.insert(buffer.end(), record, record + kFloats);
            if (buffer.size() >= kFloats * 4096 || i + 1 == splats.size()) {
                out.write(reinterpret_cast<const char*>(buffer.data()),
                          std::streamsize(buffer.size() * sizeof(float)));
                buffer.clear();
            }
        }
    });
}

Splats3dgsFile readSplats3dgs(const std::filesystem::path& file) {
    const std::string name = file.string();
    std::ifstream in(file, std::ios::binary);
    if (!in)
        throw InputError(cat(name, ": cannot open"));
    const auto fail = [&](const std::string& why) -> InputError {
        return InputError(cat(name, ": not a 3DGS PLY: ", why));
    };
    std::string line;
    std::size_t headerBytes = 0;
    const auto next = [&]() {
        if (!std::getline(in, line))
            throw fail("the header ends early (no end_header)");
        headerBytes += line.size() + 1;
        if (headerBytes > 65536)
            throw fail("a header longer than 64 KiB");
        if (!line.empty() && line.back() == '\r')
            throw fail("the header has CR LF line ends");
    };
    next();
    if (line != "ply")
        throw fail("it does not start with 'ply'");
    next();
    while (line.rfind("comment", 0) == 0 || line.rfind("obj_info", 0) == 0)
        next();
    if (line != "format binary_little_endian 1.0")
        throw fail(cat("'", line, "' (only binary_little_endian 1.0 is read)"));
    next();
    while (line.rfind("comment", 0) == 0 || line.rfind("obj_info", 0) == 0)
        next();
    std::istringstream element(line);
    std::string word, kind;
    unsigned long long count = 0;
    if (!(element >> word >> kind >> count) || word != "element" || kind != "vertex")
        throw fail(cat("'", line, "' where 'element vertex N' should be first"));
    if (count > kMaxSplats)
        throw fail(cat(count, " splats is more than the ", kMaxSplats, " read"));
    std::vector<std::string> names;
    for (next(); line.rfind("property", 0) == 0; next()) {
        std::istringstream p(line);
        std::string property, type, prop;
        p >> property >> type >> prop;
        if (type != "float" && type != "float32")
            throw fail(cat("property '", prop, "' is ", type, ", not float"));
        names.push_back(prop);
    }
    if (line.rfind("element", 0) == 0)
        throw fail(cat("'", line, "': a 3DGS file holds only vertices"));
    if (line != "end_header")
        throw fail(cat("unexpected header line '", line, "'"));

    // The expected order: x y z [nx ny nz] f_dc_0..2 f_rest_0..(R-1) opacity scale_* rot_*.
    const bool normals = names.size() > 3 && names[3] == "nx";
    const std::size_t fixed = kFloats - (normals ? 0 : 3);
    const std::size_t rest = names.size() >= fixed ? names.size() - fixed : 1;
    Splats3dgsFile result;
    const std::size_t restBySh[] = {0, 9, 24, 45};
    const auto degree = std::find(std::begin(restBySh), std::end(restBySh), rest);
    if (degree == std::end(restBySh))
        throw fail(cat(names.size(),
                       " properties: not the 3DGS layout (x y z nx ny nz f_dc_0..2 "
                       "f_rest_* opacity scale_0..2 rot_0..3 with 0, 9, 24 or 45 f_rest_*)"));
    result.shDegree = int(degree - std::begin(restBySh));
    std::vector<std::string> expected;
    for (std::size_t i = 0; i < kFloats; ++i) {
        if (!normals && i >= 3 && i < 6)
            continue;
        expected.push_back(kHead[i]);
        if (std::string(kHead[i]) == "f_dc_2")
            for (std::size_t r = 0; r < rest; ++r)
                expected.push_back(cat("f_rest_", r));
    }
    for (std::size_t i = 0; i < expected.size(); ++i)
        if (names[i] != expected[i])
            throw fail(cat("property ", i, " is '", names[i], "' where the 3DGS layout has '",
                           expected[i], "'"));

    const std::size_t stride = names.size();
    const std::uint64_t bodyBytes = std::uint64_t(count) * stride * 4;
    const std::streampos bodyStart = in.tellg();
    in.seekg(0, std::ios::end);
    const std::uint64_t available = std::uint64_t(in.tellg() - bodyStart);
    if (available < bodyBytes)
        throw fail(cat("truncated: ", count, " splats need ", bodyBytes,
                       " bytes after the header, ", "the file has ", available));
    if (available > bodyBytes)
        throw fail(cat(available - bodyBytes, " bytes after the last splat"));
    in.seekg(bodyStart);
    requireMemory(count * sizeof(Splat3dgs), cat(name, "'s ", count, " splats"));
    result.splats.resize(count);
    const std::size_t base = normals ? 6 : 3, dcAt = base, opacityAt = base + 3 + rest;
    std::vector<float> chunk(stride * 4096);
    for (std::size_t first = 0; first < count; first += 4096) {
        const std::size_t n = std::min<std::size_t>(4096, count - first);
        in.read(reinterpret_cast<char*>(chunk.data()), std::streamsize(n * stride * 4));
        if (!in)
            throw fail("read failed");
        for (std::size_t k = 0; k < n; ++k) {
            const float* r = chunk.data() + k * stride;
            for (std::size_t j = 0; j < stride; ++j)
                if (!std::isfinite(r[j]))
                    throw fail(cat("splat ", first + k, "'s ", names[j], " is ", r[j]));
            Splat3dgs& s = result.splats[first + k];
            s.position = glm::vec3(r[0], r[1], r[2]);
            s.dc = glm::vec3(r[dcAt], r[dcAt + 1], r[dcAt + 2]);
            s.opacityLogit = r[opacityAt];
            s.logScale = glm::vec3(r[opacityAt + 1], r[opacityAt + 2], r[opacityAt + 3]);
            s.rotation =
                glm::vec4(r[opacityAt + 4], r[opacityAt + 5], r[opacityAt + 6], r[opacityAt + 7]);
        }
    }
    if (!result.splats.empty()) {
        result.lo = result.hi = result.splats[0].position;
        for (const Splat3dgs& s : result.splats) {
            result.lo = glm::min(result.lo, s.position);
            result.hi = glm::max(result.hi, s.position);
        }
    }
    return result;
}

std::string camerasJson(const Camera& camera, const std::string& imageName) {
    if (camera.projection != Projection::Perspective)
        throw InputError("cameras.json: 3DGS cameras are pinholes; the scene's camera is "
                         "orthographic");
    const CameraRays rays(camera);
    // Camera axes in the world (3DGS/COLMAP: x right, y down, z forward) as the columns.
    const glm::dvec3 axes[3] = {rays.right(), -rays.up(), rays.forward()};
    const double fy = camera.height / (2.0 * rays.halfHeight());
    const double fx = camera.width / (2.0 * rays.halfWidth());
    std::ostringstream out;
    out.precision(17);
    out << "[{\"id\": 0, \"img_name\": \"" << imageName << "\", \"width\": " << camera.width
        << ", \"height\": " << camera.height << ", \"position\": [" << camera.eye.x << ", "
        << camera.eye.y << ", " << camera.eye.z << "], \"rotation\": [";
    for (int row = 0; row < 3; ++row)
        out << (row ? ", " : "") << "[" << axes[0][row] << ", " << axes[1][row] << ", "
            << axes[2][row] << "]";
    out << "], \"fy\": " << fy << ", \"fx\": " << fx << "}]\n";
    return out.str();
}

Image renderSplats(const std::vector<Splat3dgs>& splats, const Camera& camera, glm::vec3 background,
                   bool antialiased) {
    const CameraRays rays(camera);
    const glm::dmat3 view = glm::transpose(glm::dmat3(rays.right(), rays.up(), rays.forward()));
    const bool ortho = camera.projection == Projection::Orthographic;
    const double fy = camera.height / (2.0 * rays.halfHeight());
    const double fx = camera.width / (2.0 * rays.halfWidth());
    struct Projected {
        double depth;
        glm::dvec2 mean;
        glm::dmat2 conic; ///< Sigma2D^-1
        glm::ivec2 lo, hi;
        float opacity;
        glm::vec3 color;
    };
    std::vector<Projected> projected;
    projected.reserve(splats.size());
    for (const Splat3dgs& s : splats) {
        const glm::dvec3 t = view * (glm::dvec3(s.position) - camera.eye);
        if (!ortho && t.z < kNearPlane)
            continue;
        const glm::dquat q =
            glm::normalize(glm::dquat(s.rotation[0], s.rotation[1], s.rotation[2], s.rotation[3]));
        const glm::dmat3 r = glm::mat3_cast(q);
        const glm::dvec3 scale = glm::exp(glm::dvec3(s.logScale));
        const glm::dmat3 m = view * r *
                             glm::dmat3(glm::dvec3(scale.x, 0, 0), glm::dvec3(0, scale.y, 0),
                                        glm::dvec3(0, 0, scale.z));
        // Image rows grow downwards: py = H/2 - fy Y / Z.
        glm::dmat3x2 j(0.0); // 2 rows, 3 columns
        if (ortho) {
            j[0][0] = fx;
            j[1][1] = -fy;
        } else {
            j[0][0] = fx / t.z;
            j[2][0] = -fx * t.x / (t.z * t.z);
            j[1][1] = -fy / t.z;
            j[2][1] = fy * t.y / (t.z * t.z);
        }
        const glm::dmat3x2 jm = j * m;
        glm::dmat2 cov = jm * glm::transpose(jm);
        const double detBefore = glm::determinant(cov);
        cov[0][0] += 0.3;
        cov[1][1] += 0.3;
        const double det = glm::determinant(cov);
        if (!(det > 0.0))
            continue;
        Projected p;
        p.depth = t.z;
        p.mean = ortho ? glm::dvec2(0.5 * camera.width + fx * t.x, 0.5 * camera.height - fy * t.y)
                       : glm::dvec2(0.5 * camera.width + fx * t.x / t.z,
                                    0.5 * camera.height - fy * t.y / t.z);
        p.conic = glm::inverse(cov);
        const double mid = 0.5 * (cov[0][0] + cov[1][1]);
        const double radius = 3.0 * std::sqrt(mid + std::sqrt(std::max(0.1, mid * mid - det)));
        // Clamped to the image before the conversion to int (a splat near the eye's plane
        // projects arbitrarily far).
        const glm::dvec2 size(camera.width, camera.height);
        if (!std::isfinite(radius) || !std::isfinite(p.mean.x) || !std::isfinite(p.mean.y))
            continue;
        p.lo = glm::ivec2(glm::clamp(glm::floor(p.mean - radius), glm::dvec2(0.0), size));
        p.hi = glm::ivec2(glm::clamp(glm::ceil(p.mean + radius), glm::dvec2(0.0), size));
        if (p.lo.x >= p.hi.x || p.lo.y >= p.hi.y)
            continue;
        p.opacity = 1.0f / (1.0f + std::exp(-s.opacityLogit));
        if (antialiased)
            p.opacity *= float(std::sqrt(std::max(0.0, detBefore / det)));
        p.color = splatDisplayColor(s);
        projected.push_back(p);
    }
    std::stable_sort(projected.begin(), projected.end(),
                     [](const Projected& a, const Projected& b) { return a.depth < b.depth; });
    const std::size_t pixels = std::size_t(camera.width) * std::size_t(camera.height);
    std::vector<float> transmittance(pixels, 1.0f);
    std::vector<glm::vec3> color(pixels, glm::vec3(0.0f));
    for (const Projected& p : projected)
        for (int y = p.lo.y; y < p.hi.y; ++y)
            for (int x = p.lo.x; x < p.hi.x; ++x) {
                const std::size_t i = std::size_t(y) * std::size_t(camera.width) + std::size_t(x);
                float& t = transmittance[i];
                if (t < 1e-4f)
                    continue;
                const glm::dvec2 d = glm::dvec2(x + 0.5, y + 0.5) - p.mean;
                const double power = -0.5 * glm::dot(d, p.conic * d);
                if (power > 0.0)
                    continue;
                const float alpha = std::min(0.99f, p.opacity * float(std::exp(power)));
                if (alpha < 1.0f / 255.0f)
                    continue;
                color[i] += t * alpha * p.color;
                t *= 1.0f - alpha;
            }
    Image image(camera.width, camera.height);
    const glm::vec3 bg(srgbEncode(background.r), srgbEncode(background.g),
                       srgbEncode(background.b));
    for (std::size_t i = 0; i < pixels; ++i) {
        const glm::vec3 c = glm::clamp(color[i] + transmittance[i] * bg, 0.0f, 1.0f);
        image.pixels[i] = glm::vec3(srgbDecode(c.r), srgbDecode(c.g), srgbDecode(c.b));
    }
    image.background = background;
    return image;
}

} // namespace spot::noise
