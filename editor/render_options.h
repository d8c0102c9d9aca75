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
#include "splat/quality.h"

namespace spot::cli {

/// An option for every setting some method takes (splat::allSettings()), its help saying which
/// methods take it, its default and its range.
std::vector<OptionSpec> renderOptions();

/// The settings `args` asks for (`base`'s where it says nothing); InputError for a bad value.
/// A file setting (the bake) is read here, once.
splat::RenderSettings renderSettings(const Args& args, splat::RenderSettings base = {});

/// The `--quality NAME` option (splat/quality.h's table).
OptionSpec qualityOption();

/// A method and its settings, as `--method` or `--quality` chose them.
struct MethodChoice {
    std::string method;
    /// The quality's settings (the defaults with --method): the base that renderSettings(args,
    /// settings) lays the setting options on, once the caller has refused those the method does
    /// not take.
    splat::RenderSettings settings;
    std::string quality; ///< the quality that chose it; empty when --method did
};

/// `--method NAME`, else `--quality NAME`'s choice, else the default quality's (balanced). Both
/// options: InputError, one line starting with `context`; an unknown name: InputError naming the
/// known ones. With `gpuOnly`, a CPU method is refused.
MethodChoice methodChoice(const Args& args, const std::string& context, bool gpuOnly);

/// InputError, one line naming the methods that take it, for the first option of `args` that
/// sets what `method` does not take (it would silently do nothing). `context` starts the line
/// ("spotshell render").
void refuseSettingsNotTakenBy(const Args& args, const splat::MethodInfo& method,
                              const std::string& context);

/// The settings `method` takes, as JSON (for --stats and the bench): each under its key (the
/// option's name with '_'), as a bool, a number or a string.
nlohmann::json describe(const splat::MethodInfo& method, const splat::RenderSettings& settings);

} // namespace spot::cli
