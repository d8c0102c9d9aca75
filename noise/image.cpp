#include "image.h"

#include <algorithm>
#include <cmath>
#include <random>

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

    OIIO::ImageSpec spec(image.width, image.height, 3, exr ? OIIO::TypeDesc::FLOAT : OIIO::TypeDesc::UINT8);
    for (const auto& [key, value] : metadata)
        spec.attribute("spotshell:" + key, value);
    if (exr)
        spec.attribute("compression", "zip");
    else
        spec.attribute("oiio:ColorSpace", "sRGB");

    std::vector<float> linear;
    std::vector<unsigned char> bytes;
    const void* data = nullptr;
    if (exr) {
        linear.resize(image.pixels.size() * 3);
        for (std::size_t i = 0; i < image.pixels.size(); ++i)
            for (int c = 0; c < 3; ++c)
                linear[i * 3 + std::size_t(c)] = image.pixels[i][c];
        data = linear.data();
    } else {
        bytes.resize(image.pixels.size() * 3);
        for (std::size_t i = 0; i < image.pixels.size(); ++i)
            for (int c = 0; c < 3; ++c)
                bytes[i * 3 + std::size_t(c)] =
                    (unsigned char)std::lround(srgbEncode(image.pixels[i][c]) * 255.0f);
        data = bytes.data();
    }
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
    auto in = OIIO::ImageInput::open(file.string());
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
    for (std::size_t i = 0; i < image.pixels.size(); ++i) {
        glm::vec3 v;
        for (int c = 0; c < 3; ++c) {
            const float x = data[i * std::size_t(nc) + std::size_t(nc >= 3 ? c : 0)];
            if (!std::isfinite(x))
                throw InputError(cat(file.string(), ": pixel ", i % std::size_t(spec.width), ",",
                                     i / std::size_t(spec.width), " is not finite"));
            v[c] = isFloat ? x : srgbDecode(x);
        }
        image.pixels[i] = v;
    }
    return image;
}

} // namespace spot::noise
