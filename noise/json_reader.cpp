#include "json_reader.h"

#include <cfloat>
#include <cmath>
#include <set>
#include <vector>

namespace spot::noise::json {

std::ostream& operator<<(std::ostream& out, const Interval& r) {
    return out << (r.loOpen ? "(" : "[") << r.lo << ", " << r.hi << (r.hiOpen ? ")" : "]");
}

std::string printable(std::string_view s, std::size_t maxShown) {
    std::string out;
    for (std::size_t i = 0; i < s.size() && i < maxShown; ++i) {
        const auto c = static_cast<unsigned char>(s[i]);
        if (c >= 0x20 && c < 0x7f && c != '"' && c != '\\') {
            out += static_cast<char>(c);
        } else {
            static const char* hex = "0123456789abcdef";
            out += "\\x";
            out += hex[c >> 4];
            out += hex[c & 15];
        }
    }
    if (s.size() > maxShown)
        out += "...";
    return out;
}

std::string join(const std::string& path, std::string_view key) {
    return path.empty() ? std::string(key) : cat(path, ".", key);
}

std::string index(const std::string& path, std::size_t i) { return cat(path, "[", i, "]"); }


void Reader::requireVersion(const Json& root, int expected) const {
    const Json& version = require(root, "", "version");
    if (!version.is_number_integer())
        fail(cat("version must be the integer ", expected, ", got ",
                 version.is_number() ? "a fractional number" : version.type_name()));
    if (version.is_number_unsigned() ? version.get<std::uint64_t>() != std::uint64_t(expected)
                                     : version.get<std::int64_t>() != expected)
        fail(cat("version = ", version.dump(), " is not supported (this build reads version ",
                 expected, ")"));
}

/// nlohmann keeps the last of duplicate keys silently; a preset with two "density" entries is a
/// mistake the user should hear about. The callback also bounds the nesting depth.
Json parse(std::string_view text, const std::string& name) {
    std::vector<std::set<std::string>> keysPerObject;
    const auto callback = [&](int depth, Json::parse_event_t event, Json& parsed) {
        switch (event) {
        case Json::parse_event_t::object_start:
        case Json::parse_event_t::array_start:
            if (depth >= kMaxJsonDepth)
                throw InputError(cat(name, ": JSON nested deeper than ", kMaxJsonDepth, " levels"));
            if (event == Json::parse_event_t::object_start)
                keysPerObject.emplace_back();
            break;
        case Json::parse_event_t::key:
            if (!keysPerObject.empty() &&
                !keysPerObject.back().insert(parsed.get<std::string>()).second)
                throw InputError(cat(name, ": duplicate key \"",
                                     printable(parsed.get_ref<const std::string&>()), "\""));
            break;
        case Json::parse_event_t::object_end:
            if (!keysPerObject.empty())
                keysPerObject.pop_back();
            break;
        default:
            break;
        }
        return true;
    };
    try {
        return Json::parse(text.begin(), text.end(), callback);
    } catch (const Json::parse_error& e) {
        // what() is "[json.exception.parse_error.101] parse error at line L, column C: <reason>"
        std::string detail = e.what();
        if (const auto pos = detail.find("] "); pos != std::string::npos)
            detail = detail.substr(pos + 2);
        constexpr std::string_view kAt = "parse error at ";
        std::string location;
        if (detail.rfind(kAt, 0) == 0) {
            if (const auto colon = detail.find(": "); colon != std::string::npos) {
                location = cat(" (", detail.substr(kAt.size(), colon - kAt.size()), ")");
                detail = detail.substr(colon + 2);
            }
        }
        throw InputError(cat(name, ": invalid JSON at byte ", e.byte, location, ": ",
                             printable(detail, kMaxDetailShown)));
    } catch (const Json::exception& e) {
        // Not a syntax error but still the document's fault, e.g. "number overflow parsing '1e999'".
        std::string detail = e.what();
        if (const auto pos = detail.find("] "); pos != std::string::npos)
            detail = detail.substr(pos + 2);
        throw InputError(cat(name, ": invalid JSON: ", printable(detail, kMaxDetailShown)));
    }
}

} // namespace spot::noise::json
