#include "image.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <stdexcept>

#include <OpenImageIO/imageio.h>

#include "error.h"
#include "system.h"

namespace spot::noise {

namespace {

/// Images larger than this many pixels are refused before their pixels are read.
constexpr std::int64_t kMaxPixels = std::int64_t(1) << 28;

std::string lower(std::string s) {
    std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return char(std::tolower(c)); });
    return s;
}

} // namespace

float srgbEncode(float x) {
    x = std::clamp(x, 0.0f, 1.0f);
    return x <= 0.0031308f ? 12.92f * x : 1.055f * std::pow(x, 1.0f / 2.4f) - 0.055f;
}

float srgbDecode(float x) {
    return x <= 0.04045f ? x / 12.92f : std::pow((x + 0.055f) / 1.055f, 2.4f);
}

void writeImage(const std::filesystem::path& file, const Image& image,
                const std::map<std::string, std::string>& metadata) {
    const std::string ext = lower(file.extension().string());
    const bool exr = ext == ".exr";
    if (!exr && ext != ".png")
        throw InputError(cat(file.string(), ": unknown image format '", ext, "' (use .exr or .png)"));
    const std::filesystem::path dir = file.has_parent_path() ? file.parent_path() : ".";
    std::error_code ec;
    if (!std::filesystem::is_directory(dir, ec))
        throw InputError(cat(file.string(), ": folder ", dir.string(), " does not exist"));
    std::random_device rd;
    const std::filesystem::path tmp =
        dir / cat(".", file.stem().string(), ".tmp", std::hex, rd(), ext);

    const bool hasAlpha = !image.alpha.empty();
    if (hasAlpha && image.alpha.size() != image.pixels.size())
        throw std::logic_error("writeImage: alpha and pixels differ in size");
    const int nc = hasAlpha ? 4 : 3;
    OIIO::ImageSpec spec(image.width, image.height, nc,
                         exr ? OIIO::TypeDesc::FLOAT : OIIO::TypeDesc::UINT8);
    for (const auto& [key, value] : metadata)
        spec.attribute("spotshell:" + key, value);
    if (hasAlpha) {
        spec.alpha_channel = 3;
        const glm::vec3 b = image.background;
        spec.attribute("spotshell:background", cat(b.r, " ", b.g, " ", b.b));
        if (!exr) // straight, as PNG's convention is: OpenImageIO writes the values as given
            spec.attribute("oiio:UnassociatedAlpha", 1);
    }
    if (exr)
        spec.attribute("compression", "zip");
    else
        spec.attribute("oiio:ColorSpace", "sRGB");

    std::vector<float> linear;
    std::vector<unsigned char> bytes;
    const void* data = nullptr;
    if (exr)
        linear.resize(image.pixels.size() * std::size_t(nc));
    else
        bytes.resize(image.pixels.size() * std::size_t(nc));
    for (std::size_t i = 0; i < image.pixels.size(); ++i) {
        glm::vec3 v = image.pixels[i];
        const float a = hasAlpha ? std::clamp(image.alpha[i], 0.0f, 1.0f) : 1.0f;
        if (hasAlpha) {
            v -= (1.0f - a) * image.background; // premultiplied: the colour over nothing
            if (!exr)
                v = a > 0.0f ? v / a : glm::vec3(0.0f); // straight
        }
        for (int c = 0; c < nc; ++c) {
            const float x = c < 3 ? v[c] : a;
            if (exr)
                linear[i * std::size_t(nc) + std::size_t(c)] = x;
            else
                bytes[i * std::size_t(nc) + std::size_t(c)] =
                    (unsigned char)std::lround((c < 3 ? srgbEncode(x) : x) * 255.0f);
        }
    }
    if (exr)
        data = linear.data();
    else
        data = bytes.data();
    try {
        auto out = OIIO::ImageOutput::create(tmp.string());
        if (!out || !out->open(tmp.string(), spec) ||
            !out->write_image(exr ? OIIO::TypeDesc::FLOAT : OIIO::TypeDesc::UINT8, data) ||
            !out->close())
            throw InputError(cat(file.string(), ": cannot write image (",
                                 out ? out->geterror() : OIIO::geterror(), ")"));
        std::filesystem::rename(tmp, file, ec);
        if (ec)
            throw InputError(cat(file.string(), ": cannot rename temporary file (", ec.message(), ")"));
    } catch (...) {
        std::filesystem::remove(tmp, ec);
        throw;
    }
}

Image readImage(const std::filesystem::path& file, std::map<std::string, std::string>* metadata) {
    std::error_code ec;
    if (!std::filesystem::is_regular_file(file, ec))
        throw InputError(cat(file.string(), ": no such file"));
    StderrSilencer quiet; // libpng prints its own copy of errors we report ourselves
    OIIO::ImageSpec config;
    config.attribute("oiio:UnassociatedAlpha", 1); // PNG's straight alpha as stored
    auto in = OIIO::ImageInput::open(file.string(), &config);
    if (!in)
        throw InputError(cat(file.string(), ": cannot read image (", OIIO::geterror(), ")"));
    const OIIO::ImageSpec& spec = in->spec();
    if (spec.width <= 0 || spec.height <= 0 || spec.nchannels <= 0 || spec.depth != 1)
        throw InputError(cat(file.string(), ": unsupported image shape ", spec.width, "x",
                             spec.height, "x", spec.nchannels));
    if (std::int64_t(spec.width) * spec.height > kMaxPixels || spec.nchannels > 64)
        throw InputError(cat(file.string(), ": image of ", spec.width, "x", spec.height,
                             " pixels is larger than the limit"));
    const std::uint64_t bytes = std::uint64_t(spec.width) * std::uint64_t(spec.height) *
                                std::uint64_t(spec.nchannels) * 4u;
    requireMemory(bytes * 2, cat("reading ", file.string()));
    const bool isFloat = spec.format.basetype == OIIO::TypeDesc::FLOAT ||
                         spec.format.basetype == OIIO::TypeDesc::HALF ||
                         spec.format.basetype == OIIO::TypeDesc::DOUBLE;
    std::vector<float> data(std::size_t(spec.width) * std::size_t(spec.height) * std::size_t(spec.nchannels));
    if (!in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, data.data()))
        throw InputError(cat(file.string(), ": corrupt image (", in->geterror(), ")"));
    if (metadata)
        for (const OIIO::ParamValue& p : spec.extra_attribs) {
            const std::string name = p.name().string();
            if (name.rfind("spotshell:", 0) == 0)
                (*metadata)[name.substr(10)] = p.get_string();
        }
    Image image(spec.width, spec.height);
    const int nc = spec.nchannels;
    const int alphaChannel = spec.alpha_channel >= 0 && spec.alpha_channel < nc ? spec.alpha_channel
                             : nc == 4 || nc == 2                               ? nc - 1
                                                                                : -1;
    // Straight (integer formats, as read with oiio:UnassociatedAlpha) or premultiplied (float).
    const bool straight = !isFloat || spec.get_int_attribute("oiio:UnassociatedAlpha", 0) != 0;
    if (alphaChannel >= 0) {
        image.alpha.resize(image.pixels.size());
        const std::string b = spec.get_string_attribute("spotshell:background");
        if (!b.empty() && std::sscanf(b.c_str(), "%f %f %f", &image.background.r,
                                      &image.background.g, &image.background.b) != 3)
            throw InputError(
                cat(file.string(), ": spotshell:background '", b, "' is not 3 numbers"));
        if (!std::isfinite(image.background.r + image.background.g + image.background.b))
            throw InputError(cat(file.string(), ": spotshell:background is not finite"));
    }
    for (std::size_t i = 0; i < image.pixels.size(); ++i) {
        glm::vec3 v;
        for (int c = 0; c < 3; ++c) {
            const float x = data[i * std::size_t(nc) + std::size_t(nc >= 3 ? c : 0)];
            if (!std::isfinite(x))
                throw InputError(cat(file.string(), ": pixel ", i % std::size_t(spec.width), ",",
                                     i / std::size_t(spec.width), " is not finite"));
            v[c] = isFloat ? x : srgbDecode(x);
        }
        if (alphaChannel >= 0) {
            const float a = data[i * std::size_t(nc) + std::size_t(alphaChannel)];
            if (!std::isfinite(a))
                throw InputError(cat(file.string(), ": pixel ", i % std::size_t(spec.width), ",",
                                     i / std::size_t(spec.width), " has no finite alpha"));
            image.alpha[i] = std::clamp(a, 0.0f, 1.0f);
            if (straight)
                v *= image.alpha[i];
            v += (1.0f - image.alpha[i]) * image.background;
        }
        image.pixels[i] = v;
    }
    return image;
}

} // namespace spot::noise
