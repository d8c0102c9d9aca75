/// @file layout.h
/// @brief The structs shared with GLSL and the model's conversions into them (noise/shared_data.h).
#pragma once

#include "noise/shared_data.h"
