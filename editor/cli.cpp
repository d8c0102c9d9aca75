#include "cli.h"

#include <charconv>
#include <cmath>
#include <sstream>

#include "noise/error.h"

namespace spot::cli {

Args::Args(const std::string& command, const std::string& summary, std::vector<OptionSpec> specs,
           int argc, char** argv)
    : m_command(command), m_summary(summary), m_specs(std::move(specs)) {
    for (int i = 0; i < argc; ++i) {
        std::string arg = argv[i];
        if (arg == "--help" || arg == "-h") {
            m_help = true;
            return;
        }
        if (arg.rfind("--", 0) != 0)
            throw InputError(cat("spotshell ", m_command, ": unexpected argument '", arg,
                                 "' (see spotshell ", m_command, " --help)"));
        std::string name = arg.substr(2);
        std::optional<std::string> value;
        if (const auto eq = name.find('='); eq != std::string::npos) {
            value = name.substr(eq + 1);
            name = name.substr(0, eq);
        }
        const OptionSpec& s = spec(name);
        if (s.value.empty()) {
            if (value)
                throw InputError(cat("spotshell ", m_command, ": --", name, " takes no value"));
            m_values[name] = "1";
            continue;
        }
        if (!value) {
            if (i + 1 >= argc)
                throw InputError(cat("spotshell ", m_command, ": --", name, " needs a value (",
                                     s.value, ")"));
            value = argv[++i];
        }
        m_values[name] = *value;
    }
    for (const OptionSpec& s : m_specs)
        if (s.required && !has(s.name))
            throw InputError(cat("spotshell ", m_command, ": --", s.name, " ", s.value,
                                 " is required (see spotshell ", m_command, " --help)"));
}

const OptionSpec& Args::spec(const std::string& name) const {
    for (const OptionSpec& s : m_specs)
        if (s.name == name)
            return s;
    throw InputError(cat("spotshell ", m_command, ": unknown option --", name, " (see spotshell ",
                         m_command, " --help)"));
}

std::string Args::usage() const {
    std::ostringstream out;
    out << "usage: spotshell " << m_command << " [options]\n" << m_summary << "\n\noptions:\n";
    for (const OptionSpec& s : m_specs) {
        std::string left = "  --" + s.name + (s.value.empty() ? "" : " " + s.value);
        out << left << std::string(left.size() < 28 ? 28 - left.size() : 1, ' ') << s.help
            << (s.required ? " (required)" : "") << "\n";
    }
    out << "  --help                    this text\n";
    return out.str();
}

std::string Args::str(const std::string& name) const {
    const auto it = m_values.find(name);
    if (it == m_values.end())
        throw InputError(cat("spotshell ", m_command, ": --", name, " is required"));
    return it->second;
}

std::string Args::str(const std::string& name, const std::string& fallback) const {
    const auto it = m_values.find(name);
    return it == m_values.end() ? fallback : it->second;
}

std::int64_t Args::integer(const std::string& name, std::int64_t fallback, std::int64_t lo,
                           std::int64_t hi) const {
    const auto it = m_values.find(name);
    if (it == m_values.end())
        return fallback;
    std::int64_t v = 0;
    const std::string& text = it->second;
    const auto [ptr, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
    if (ec != std::errc() || ptr != text.data() + text.size())
        throw InputError(cat("spotshell ", m_command, ": --", name, " expects an integer, got '",
                             text, "'"));
    if (v < lo || v > hi)
        throw InputError(cat("spotshell ", m_command, ": --", name, " ", v, " is outside [", lo,
                             ", ", hi, "]"));
    return v;
}

double Args::number(const std::string& name, double fallback, double lo, double hi) const {
    const auto it = m_values.find(name);
    if (it == m_values.end())
        return fallback;
    const std::string& text = it->second;
    char* end = nullptr;
    const double v = std::strtod(text.c_str(), &end);
    if (text.empty() || end != text.c_str() + text.size() || !std::isfinite(v))
        throw InputError(cat("spotshell ", m_command, ": --", name, " expects a finite number, got '",
                             text, "'"));
    if (v < lo || v > hi)
        throw InputError(cat("spotshell ", m_command, ": --", name, " ", v, " is outside [", lo,
                             ", ", hi, "]"));
    return v;
}

OptionSpec threadsOption() {
    return {"threads", "N", "worker threads (0 = all cores; results do not depend on it)", false};
}

} // namespace spot::cli
