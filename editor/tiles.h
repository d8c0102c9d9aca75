/// @file tiles.h
/// @brief The tiles of a large still (render --tile I/N, --crop X0,Y0,X1,Y1): which pixels of the
/// camera's image a task renders. A tile is a pure function of (scene, time, tile): its pixels
/// are the whole image's (splat::View::window), and `spotshell assemble` joins the tiles back.
#pragma once

#include <string>

#include "noise/image.h"

namespace spot::cli {

/// Tile `index` (0-based) of `count` of a `width` x `height` image: full-width bands of rows,
/// band i covering rows [floor(i H / N), floor((i + 1) H / N)), so the bands tile the image
/// exactly, in order, and differ in height by at most one row. Bands keep each tile's rows whole
/// (one contiguous block of the file) and every tile's cost alike for a subject centred in frame.
/// InputError for a count outside [1, height] or an index outside [0, count).
noise::PixelRect tileRect(long index, long count, int width, int height);
/// --tile I/N (tileRect's); InputError for anything else, naming the option.
noise::PixelRect parseTile(const std::string& spec, int width, int height);
/// --crop X0,Y0,X1,Y1: pixels [X0, X1) x [Y0, Y1); InputError unless 0 <= X0 < X1 <= width and
/// 0 <= Y0 < Y1 <= height.
noise::PixelRect parseCrop(const std::string& spec, int width, int height);

} // namespace spot::cli
