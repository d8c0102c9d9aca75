/// @file cli.h
/// @brief A small, strict command-line parser shared by the subcommands.
///
/// Options are `--name value` or `--name=value`; flags are `--name`. Unknown options, missing
/// values and malformed numbers are InputErrors (exit code 2) naming the option.
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>


namespace spot::cli {

struct OptionSpec {
    std::string name;  ///< without the leading dashes
    std::string value; ///< placeholder shown in help ("FILE", "N"); empty for a flag
    std::string help;
    bool required = false;
};

class Args {
public:
    /// Parse argv (after the subcommand). Returns nullopt-like state via helpRequested() when
    /// --help was given; throws InputError on anything malformed.
    Args(const std::string& command, const std::string& summary, std::vector<OptionSpec> specs,
         int argc, char** argv);

    bool helpRequested() const { return m_help; }
    std::string usage() const;

    bool has(const std::string& name) const { return m_values.count(name) != 0; }
    std::string str(const std::string& name) const;
    std::string str(const std::string& name, const std::string& fallback) const;
    std::int64_t integer(const std::string& name, std::int64_t fallback, std::int64_t lo,
                         std::int64_t hi) const;
    double number(const std::string& name, double fallback, double lo, double hi) const;

private:
    const OptionSpec& spec(const std::string& name) const;

    std::string m_command;
    std::string m_summary;
    std::vector<OptionSpec> m_specs;
    std::map<std::string, std::string> m_values;
    bool m_help = false;
};

/// The `--threads N` option every subcommand accepts (0 = all cores).
OptionSpec threadsOption();

} // namespace spot::cli
