/// @file impulse_io.h
/// @brief Writing impulses as a PLY point cloud (one vertex per impulse) for inspection and for
/// other tools (Blender and Houdini import PLY points with their attributes).
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "impulses.h"

namespace spot::noise {

/// Binary little-endian PLY, one vertex per impulse with float properties
/// x y z (position), nx ny nz (normal), tx ty tz (comb direction), sx sy sz (scale),
/// red green blue (colour in [0,1]), int face (anchor triangle), float u v (anchor barycentric
/// b1 b2), weight, height, bend (rad per kernel unit), qw qx qy qz (kernel frame as a unit
/// quaternion, kernel -> world). `comments` become header comments. Written atomically.
void writeImpulsesPly(const std::filesystem::path& file, const std::vector<Impulse>& impulses,
                      const std::vector<std::string>& comments);

} // namespace spot::noise
