/// @file shared_data.h
/// @brief The model in the layout shared with GLSL (shaders/spot_layout.h): impulses, kernel
/// lobes, cells and pieces, fields and generation parameters. The CPU generator and the GPU read
/// exactly these bytes.
#pragma once

#include <vector>

#include "shaders/spot_layout.hpp"

#include "cells.h"
#include "impulses.h"
#include "kernel.h"

namespace spot::gpu {

/// An impulse in the shared layout and back (floats copied bit for bit).
SpotImpulse toGpu(const noise::Impulse& impulse);
noise::Impulse fromGpu(const SpotImpulse& impulse);
std::vector<SpotImpulse> toGpu(const std::vector<noise::Impulse>& impulses);
/// Kernel lobes (at most 8).
std::vector<SpotLobe> toGpu(const noise::Kernel& kernel);
/// A cell (its output offset left 0).
SpotCell toGpu(const noise::SurfaceCell& cell);
/// All pieces, with areas made cumulative within each cell (what the generator's binary search
/// expects).
std::vector<SpotPiece> piecesToGpu(const noise::SurfaceCells& cells);

} // namespace spot::gpu
