/// @file commands.h
/// @brief The subcommands of `spotshell`. Each takes the arguments after its name, returns the
/// exit code, and throws InputError (exit 2) or anything else (exit 1) on failure.
#pragma once

namespace spot::cmd {

int info(int argc, char** argv);
int impulses(int argc, char** argv);
int render(int argc, char** argv);
int bake(int argc, char** argv); ///< the noise into OpenVDB voxel mip levels (cmd_bake.cpp)
int compare(int argc, char** argv);
/// render --tile's tiles into the whole image (cmd_assemble.cpp)
int assemble(int argc, char** argv);
int bench(int argc, char** argv);
int edit(int argc, char** argv); ///< the editor: its window, or a script headless (cmd_edit.cpp)
int exportScene(int argc, char** argv); ///< the noise as 3D Gaussian splats (cmd_export.cpp)

} // namespace spot::cmd
