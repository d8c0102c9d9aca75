/// @file render_options.h
/// @brief The methods' settings on the command line and in `--stats`, written from their
/// descriptors (splat/settings.h) and the registry (splat/method_vk.h): nothing here names a
/// setting or a method.
#pragma once

#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "cli.h"
#include "splat/method_vk.h"

namespace spot::cli {

/// An option for every setting some method takes (splat::allSettings()), its help saying which
/// methods take it, its default and its range.
std::vector<OptionSpec> renderOptions();

/// The settings `args` asks for (defaults where it says nothing); InputError for a bad value.
/// A file setting (the bake) is read here, once.
splat::RenderSettings renderSettings(const Args& args);

/// InputError, one line naming the methods that take it, for the first option of `args` that
/// sets what `method` does not take (it would silently do nothing). `context` starts the line
/// ("spotshell render").
void refuseSettingsNotTakenBy(const Args& args, const splat::MethodInfo& method,
                              const std::string& context);

/// The settings `method` takes, as JSON (for --stats and the bench): each under its key (the
/// option's name with '_'), as a bool, a number or a string.
nlohmann::json describe(const splat::MethodInfo& method, const splat::RenderSettings& settings);

} // namespace spot::cli
