/// @file cmd_assemble.cpp
/// @brief `spotshell assemble TILE... --out FILE`: the tiles of `render --tile` (or --crop) joined
/// into the whole image, each tile's stored pixels copied unconverted (noise::assembleTiles).
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "cli.h"
#include "commands.h"
#include "noise/error.h"
#include "noise/image.h"

namespace spot::cmd {

int assemble(int argc, char** argv) {
    // The tiles come first; the rest are options.
    std::vector<std::filesystem::path> tiles;
    int i = 0;
    for (; i < argc && argv[i][0] != '-'; ++i)
        tiles.emplace_back(argv[i]);
    cli::Args args("assemble",
                   "Join tiles into the whole image: spotshell assemble TILE... --out FILE.\n"
                   "The tiles are render --tile I/N (or --crop) outputs of one image, in any "
                   "order; each pixel is copied as stored, so the result is the whole render's "
                   "pixels byte for byte. Refuses missing, overlapping or mismatched tiles.",
                   {{"out", "FILE", "the whole image, in the tiles' format (.exr or .png)", true}},
                   argc - i, argv + i);
    if (args.helpRequested()) {
        std::fputs(args.usage().c_str(), stdout);
        return 0;
    }
    if (tiles.empty())
        throw InputError("spotshell assemble: give the tiles, then --out (see --help)");
    const std::string out = args.str("out");
    const noise::AssembledImage a = noise::assembleTiles(tiles, out);
    std::printf("wrote %s (%dx%d, from %zu tiles)\n", out.c_str(), a.width, a.height, a.tiles);
    return 0;
}

} // namespace spot::cmd
