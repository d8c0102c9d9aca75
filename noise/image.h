/// @file image.h
/// @brief Linear RGB float images and their files.
///
/// EXR holds linear float RGB; PNG (and other 8-bit formats) hold sRGB-encoded 8-bit values.
/// Metadata (method, spp, seconds, kernel counts) travels as string attributes.
///
/// A rendered image carries its coverage: alpha = 1 - the transmittance through the detail and
/// the mesh, so that it composites over a plate. In memory the colour stays the image as rendered
/// over the scene's background (every comparison and metric reads that), with the background
/// beside it; a file holds the convention of its format: EXR premultiplied (colour over nothing:
/// colour - (1 - alpha) background), PNG straight (that divided by alpha, sRGB-encoded; alpha
/// linear). The background travels as the `spotshell:background` attribute, so reading the file
/// back gives the image over its background again.
#pragma once

#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include <glm/glm.hpp>

namespace spot::noise {

/// A rectangle of pixels, [x0, x1) x [y0, y1), in an image's pixel grid (top-left origin).
struct PixelRect {
    int x0 = 0, y0 = 0, x1 = 0, y1 = 0;
    int width() const { return x1 - x0; }
    int height() const { return y1 - y0; }
    bool empty() const { return x1 <= x0 || y1 <= y0; }
    bool operator==(const PixelRect&) const = default;
};

struct Image {
    int width = 0;
    int height = 0;
    std::vector<glm::vec3> pixels; ///< linear RGB, row-major, top row first
    /// Coverage per pixel, in [0, 1] (empty: opaque, no alpha channel). `pixels` are composited
    /// over `background` where it is below 1.
    std::vector<float> alpha;
    glm::vec3 background{0.0f};
    /// A tile of a larger image (render --tile, --crop): where this image's pixels sit in it, and
    /// its size. Empty `crop` (the default): the image is whole. writeImage records both (an
    /// EXR's data and display windows; the spotshell:crop and spotshell:full_size attributes in
    /// every format), readImage reads them back.
    PixelRect crop;
    int fullWidth = 0, fullHeight = 0;

    Image() = default;
    Image(int w, int h, glm::vec3 fill = glm::vec3(0.0f))
        : width(w), height(h), pixels(std::size_t(w) * std::size_t(h), fill) {}
    glm::vec3& at(int x, int y) { return pixels[std::size_t(y) * std::size_t(width) + std::size_t(x)]; }
    const glm::vec3& at(int x, int y) const {
        return pixels[std::size_t(y) * std::size_t(width) + std::size_t(x)];
    }
};

float srgbEncode(float linear);
float srgbDecode(float encoded);

/// Write by extension: .exr (linear float RGB, premultiplied alpha) or .png (sRGB 8-bit, straight
/// alpha); RGBA where the image has alpha. Atomic: written to a temporary file in the same
/// folder, then renamed. Throws InputError for an unknown extension
/// or a folder that does not exist.
void writeImage(const std::filesystem::path& file, const Image& image,
                const std::map<std::string, std::string>& metadata = {});

/// Read any image OpenImageIO reads into linear RGB (8-bit and other integer formats are taken as
/// sRGB-encoded; float formats as linear). Grey images are expanded. An alpha channel is kept
/// as `alpha`, and the colour is composited over the file's `spotshell:background` (black for
/// files spotshell did not write). Throws
/// InputError naming the file when it is missing, corrupt or absurdly large.
Image readImage(const std::filesystem::path& file, std::map<std::string, std::string>* metadata = nullptr);

/// What assembleTiles joined.
struct AssembledImage {
    int width = 0, height = 0;
    std::size_t tiles = 0;
};
/// Join tiles that writeImage wrote with a crop (render --tile, --crop) into the whole image at
/// `out`, written atomically in the tiles' own format: every pixel's stored bytes are the tile's,
/// unconverted, so the result is the whole image's pixels byte for byte. The metadata is the
/// first tile's (less the crop). InputError naming the file for a tile that is not one, a format
/// other than `out`'s, tiles of different images (size, channels, scene, method, time, seed,
/// background), tiles that overlap, or pixels no tile covers.
AssembledImage assembleTiles(const std::vector<std::filesystem::path>& tiles,
                             const std::filesystem::path& out);

} // namespace spot::noise
