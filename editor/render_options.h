/// @file render_options.h
/// @brief The command-line options of the GPU methods (render, and whatever else drives a
/// splat::Frame), parsed into splat::RenderSettings.
#pragma once

#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "cli.h"
#include "splat/method_vk.h"

namespace spot::cli {

/// --kernel-samples, --ewa, --weight, --closest, --lod, --steps, --supersample, --bake,
/// --peel-passes,
/// --count-fragments.
std::vector<OptionSpec> renderOptions();

/// The settings `args` asks for (defaults where it says nothing); InputError for a bad value.
splat::RenderSettings renderSettings(const Args& args);

/// The settings `method` reads, as JSON (for --stats and the bench).
nlohmann::json describe(const splat::MethodInfo& method, const splat::RenderSettings& settings);

} // namespace spot::cli
