// spotshell: procedural volumetric surface detail (spot noise shells).
// Only this file catches: every failure ends as one line on stderr and an exit code
// (2 for bad input, 1 for an internal failure).
#include <cstdio>
#include <cstring>
#include <exception>
#include <iostream>
#include <string>

#include "commands.h"
#include "noise/error.h"
#include "noise/system.h"

namespace {

struct Command {
    const char* name;
    int (*run)(int, char**);
    const char* summary;
};

const Command kCommands[] = {
    {"impulses", spot::cmd::impulses, "generate the impulses of a preset on a mesh, write a PLY"},
    {"render", spot::cmd::render, "render a scene (reference: the converged CPU ground truth)"},
    {"bake", spot::cmd::bake, "evaluate a scene's noise into OpenVDB voxel mip levels (.vdb)"},
    {"assemble", spot::cmd::assemble, "join the tiles of render --tile into the whole image"},
    {"compare", spot::cmd::compare, "PSNR, SSIM and FLIP of an image against a reference"},
    {"edit", spot::cmd::edit, "paint and edit a preset on a scene: a window, or --script without one"},
    {"bench", spot::cmd::bench, "speed against accuracy of every method, with charts"},
    {"export", spot::cmd::exportScene, "write a scene's noise as 3D Gaussian splats (3DGS PLY)"},
    {"info", spot::cmd::info, "print a mesh's counts, bounds and dropped triangles"},
};

void printUsage(std::FILE* out) {
    std::fprintf(out, "usage: spotshell COMMAND [options]   (spotshell COMMAND --help for more)\n\n"
                      "commands:\n");
    for (const Command& c : kCommands)
        std::fprintf(out, "  %-10s %s\n", c.name, c.summary);
}

} // namespace

int main(int argc, char** argv) {
    if (argc < 2) {
        printUsage(stderr);
        return 2;
    }
    const std::string name = argv[1];
    if (name == "--help" || name == "-h" || name == "help") {
        printUsage(stdout);
        return 0;
    }
    for (const Command& c : kCommands) {
        if (name != c.name)
            continue;
        try {
            return c.run(argc - 2, argv + 2);
        } catch (const spot::InputError& e) {
            std::fprintf(stderr, "spotshell: error: %s\n", spot::oneLine(e.what()).c_str());
            return 2;
        } catch (const std::bad_alloc&) {
            std::fprintf(stderr, "spotshell: internal error: out of memory\n");
            return 1;
        } catch (const std::exception& e) {
            std::fprintf(stderr, "spotshell: internal error: %s\n", spot::oneLine(e.what()).c_str());
            return 1;
        }
    }
    std::fprintf(stderr, "spotshell: error: unknown command '%s' (see spotshell --help)\n",
                 name.c_str());
    return 2;
}
