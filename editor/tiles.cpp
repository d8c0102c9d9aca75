#include "tiles.h"

#include <cstdio>

#include "noise/error.h"

namespace spot::cli {

noise::PixelRect tileRect(long index, long count, int width, int height) {
    if (count < 1 || count > height)
        throw InputError(cat("--tile: ", count, " tiles of a ", width, "x", height,
                             " image (the tiles are bands of rows: 1 to ", height, ")"));
    if (index < 0 || index >= count)
        throw InputError(
            cat("--tile: tile ", index, " is outside 0-", count - 1, " (tiles count from 0)"));
    const auto row = [&](long i) { return int(i * long(height) / count); };
    return {0, row(index), width, row(index + 1)};
}

noise::PixelRect parseTile(const std::string& spec, int width, int height) {
    long index = 0, count = 0;
    char slash = 0, extra = 0;
    if (std::sscanf(spec.c_str(), "%ld%c%ld%c", &index, &slash, &count, &extra) != 3 ||
        slash != '/')
        throw InputError(cat("--tile '", spec, "' must be I/N: tile I (from 0) of N"));
    return tileRect(index, count, width, height);
}

noise::PixelRect parseCrop(const std::string& spec, int width, int height) {
    noise::PixelRect r;
    char extra = 0;
    if (std::sscanf(spec.c_str(), "%d,%d,%d,%d%c", &r.x0, &r.y0, &r.x1, &r.y1, &extra) != 4)
        throw InputError(
            cat("--crop '", spec, "' must be X0,Y0,X1,Y1 (pixels [X0, X1) x [Y0, Y1))"));
    if (r.x0 < 0 || r.y0 < 0 || r.x1 > width || r.y1 > height || r.empty())
        throw InputError(cat("--crop '", spec, "' is not a rectangle inside the ", width, "x",
                             height, " image (0 <= X0 < X1 <= ", width,
                             ", 0 <= Y0 < Y1 <= ", height, ")"));
    return r;
}

} // namespace spot::cli
