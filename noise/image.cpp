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

/// InputError unless the folder `file` goes in exists.
void requireFolder(const std::filesystem::path& file) {
    const std::filesystem::path dir = file.has_parent_path() ? file.parent_path() : ".";
    std::error_code ec;
    if (!std::filesystem::is_directory(dir, ec))
        throw InputError(cat(file.string(), ": folder ", dir.string(), " does not exist"));
}

/// Write `data` (of `type`, as `spec` describes) to a temporary file beside `file`, then rename
/// it: a reader (or a killed writer) never sees half a file.
void writeAtomic(const std::filesystem::path& file, const OIIO::ImageSpec& spec,
                 OIIO::TypeDesc type, const void* data) {
    const std::filesystem::path dir = file.has_parent_path() ? file.parent_path() : ".";
    std::random_device rd;
    const std::filesystem::path tmp =
        dir / cat(".", file.stem().string(), ".tmp", std::hex, rd(), file.extension().string());
    std::error_code ec;
    try {
        auto out = OIIO::ImageOutput::create(tmp.string());
        if (!out || !out->open(tmp.string(), spec) || !out->write_image(type, data) ||
            !out->close())
            throw InputError(cat(file.string(), ": cannot write image (",
                                 out ? out->geterror() : OIIO::geterror(), ")"));
        std::filesystem::rename(tmp, file, ec);
        if (ec)
            throw InputError(
                cat(file.string(), ": cannot rename temporary file (", ec.message(), ")"));
    } catch (...) {
        std::filesystem::remove(tmp, ec);
        throw;
    }
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
    requireFolder(file);

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
    if (!image.crop.empty()) {
        const PixelRect& c = image.crop;
        if (c.width() != image.width || c.height() != image.height || c.x0 < 0 || c.y0 < 0 ||
            c.x1 > image.fullWidth || c.y1 > image.fullHeight)
            throw std::logic_error(cat("writeImage: crop ", c.x0, ",", c.y0, ",", c.x1, ",", c.y1,
                                       " does not fit a ", image.width, "x", image.height,
                                       " tile of ", image.fullWidth, "x", image.fullHeight));
        spec.x = c.x0;
        spec.y = c.y0;
        spec.full_x = 0;
        spec.full_y = 0;
        spec.full_width = image.fullWidth;
        spec.full_height = image.fullHeight;
        spec.attribute("spotshell:crop", cat(c.x0, ",", c.y0, ",", c.x1, ",", c.y1));
        spec.attribute("spotshell:full_size", cat(image.fullWidth, "x", image.fullHeight));
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
    writeAtomic(file, spec, exr ? OIIO::TypeDesc::FLOAT : OIIO::TypeDesc::UINT8, data);
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
    const std::string crop = spec.get_string_attribute("spotshell:crop");
    if (!crop.empty()) {
        PixelRect& c = image.crop;
        const std::string full = spec.get_string_attribute("spotshell:full_size");
        if (std::sscanf(crop.c_str(), "%d,%d,%d,%d", &c.x0, &c.y0, &c.x1, &c.y1) != 4 ||
            std::sscanf(full.c_str(), "%dx%d", &image.fullWidth, &image.fullHeight) != 2 ||
            c.width() != spec.width || c.height() != spec.height || c.x0 < 0 || c.y0 < 0 ||
            c.x1 > image.fullWidth || c.y1 > image.fullHeight)
            throw InputError(cat(file.string(), ": spotshell:crop '", crop, "' of '", full,
                                 "' does not fit its ", spec.width, "x", spec.height, " pixels"));
    }
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

AssembledImage assembleTiles(const std::vector<std::filesystem::path>& tiles,
                             const std::filesystem::path& out) {
    if (tiles.empty())
        throw InputError("assemble: no tiles given");
    const std::string ext = lower(out.extension().string());
    requireFolder(out);
    StderrSilencer quiet;
    OIIO::ImageSpec first;
    PixelRect full;
    std::vector<std::uint8_t> pixels;
    std::vector<int> owner; // per pixel: 1 + the tile that wrote it (0: none yet)
    std::size_t pixelBytes = 0;
    for (std::size_t t = 0; t < tiles.size(); ++t) {
        const std::string name = tiles[t].string();
        if (lower(tiles[t].extension().string()) != ext)
            throw InputError(cat("assemble: ", name, " is not a ", ext, " file as ", out.string(),
                                 " is (tiles are joined as written, not converted)"));
        std::error_code ec;
        if (!std::filesystem::is_regular_file(tiles[t], ec))
            throw InputError(cat("assemble: ", name, ": no such file"));
        OIIO::ImageSpec config;
        config.attribute("oiio:UnassociatedAlpha", 1); // PNG's straight alpha as stored
        auto in = OIIO::ImageInput::open(name, &config);
        if (!in)
            throw InputError(
                cat("assemble: ", name, ": cannot read image (", OIIO::geterror(), ")"));
        const OIIO::ImageSpec& spec = in->spec();
        const std::string crop = spec.get_string_attribute("spotshell:crop");
        const std::string size = spec.get_string_attribute("spotshell:full_size");
        PixelRect c;
        int w = 0, h = 0;
        if (crop.empty() ||
            std::sscanf(crop.c_str(), "%d,%d,%d,%d", &c.x0, &c.y0, &c.x1, &c.y1) != 4 ||
            std::sscanf(size.c_str(), "%dx%d", &w, &h) != 2)
            throw InputError(
                cat("assemble: ", name,
                    " is not a tile (no spotshell:crop: render it with --tile or --crop)"));
        if (w < 1 || h < 1 || std::int64_t(w) * h > kMaxPixels || c.empty() || c.x0 < 0 ||
            c.y0 < 0 || c.x1 > w || c.y1 > h || c.width() != spec.width ||
            c.height() != spec.height || spec.depth != 1)
            throw InputError(cat("assemble: ", name, ": its crop ", crop, " of ", size,
                                 " does not fit its ", spec.width, "x", spec.height, " pixels"));
        if (t == 0) {
            first = spec;
            full = {0, 0, w, h};
            pixelBytes = spec.pixel_bytes(true);
            requireMemory(std::uint64_t(w) * std::uint64_t(h) * (pixelBytes + sizeof(int)),
                          cat("assembling a ", w, "x", h, " image"));
            pixels.assign(std::size_t(w) * std::size_t(h) * pixelBytes, 0);
            owner.assign(std::size_t(w) * std::size_t(h), 0);
        } else {
            const auto differs = [&](const char* what) {
                return InputError(cat("assemble: ", name, " and ", tiles[0].string(),
                                      " are tiles of different images (", what, ")"));
            };
            if (w != full.x1 || h != full.y1)
                throw differs(cat(size, " against ", full.x1, "x", full.y1).c_str());
            if (spec.nchannels != first.nchannels || spec.format != first.format ||
                spec.channelformats != first.channelformats)
                throw differs("channels");
            for (const char* key : {"spotshell:background", "spotshell:scene", "spotshell:method",
                                    "spotshell:time", "spotshell:seed"})
                if (spec.get_string_attribute(key) != first.get_string_attribute(key))
                    throw differs(key + 10);
        }
        std::vector<std::uint8_t> data(std::size_t(spec.width) * std::size_t(spec.height) *
                                       pixelBytes);
        if (!in->read_image(0, 0, 0, spec.nchannels, spec.format, data.data()))
            throw InputError(cat("assemble: ", name, ": corrupt image (", in->geterror(), ")"));
        for (int y = c.y0; y < c.y1; ++y) {
            for (int x = c.x0; x < c.x1; ++x) {
                int& o = owner[std::size_t(y) * std::size_t(w) + std::size_t(x)];
                if (o != 0)
                    throw InputError(cat("assemble: ", name, " and ",
                                         tiles[std::size_t(o - 1)].string(), " overlap (pixel ", x,
                                         ",", y, ")"));
                o = int(t + 1);
            }
            std::copy_n(data.data() + std::size_t(y - c.y0) * std::size_t(c.width()) * pixelBytes,
                        std::size_t(c.width()) * pixelBytes,
                        pixels.data() +
                            (std::size_t(y) * std::size_t(w) + std::size_t(c.x0)) * pixelBytes);
        }
    }
    for (std::size_t i = 0; i < owner.size(); ++i)
        if (owner[i] == 0)
            throw InputError(cat("assemble: no tile covers pixel ", i % std::size_t(full.x1), ",",
                                 i / std::size_t(full.x1), " of the ", full.x1, "x", full.y1,
                                 " image (a tile is missing)"));
    OIIO::ImageSpec spec = first;
    spec.x = spec.y = spec.full_x = spec.full_y = 0;
    spec.width = spec.full_width = full.x1;
    spec.height = spec.full_height = full.y1;
    spec.erase_attribute("spotshell:crop");
    spec.erase_attribute("spotshell:full_size");
    spec.erase_attribute("spotshell:tile");
    spec.attribute("spotshell:tiles", int(tiles.size()));
    if (spec.alpha_channel >= 0 && ext != ".exr")
        spec.attribute("oiio:UnassociatedAlpha", 1); // the straight values as read
    writeAtomic(out, spec, spec.format, pixels.data());
    return {full.x1, full.y1, tiles.size()};
}

} // namespace spot::noise
