/// @file image.h
/// @brief Linear RGB float images and their files.
///
/// EXR holds linear float RGB; PNG (and other 8-bit formats) hold sRGB-encoded 8-bit values.
/// Metadata (method, spp, seconds, kernel counts) travels as string attributes.
#pragma once

#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include <glm/glm.hpp>

namespace spot::noise {

struct Image {
    int width = 0;
    int height = 0;
    std::vector<glm::vec3> pixels; ///< linear RGB, row-major, top row first

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

/// Write by extension: .exr (linear float RGB) or .png (sRGB 8-bit). Atomic: written to a
/// temporary file in the same folder, then renamed. Throws InputError for an unknown extension
/// or a folder that does not exist.
void writeImage(const std::filesystem::path& file, const Image& image,
                const std::map<std::string, std::string>& metadata = {});

/// Read any image OpenImageIO reads into linear RGB (8-bit and other integer formats are taken as
/// sRGB-encoded; float formats as linear). Grey images are expanded, alpha is dropped. Throws
/// InputError naming the file when it is missing, corrupt or absurdly large.
Image readImage(const std::filesystem::path& file, std::map<std::string, std::string>* metadata = nullptr);

} // namespace spot::noise
