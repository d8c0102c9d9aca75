/// @file json_reader.h
/// @brief Strict reading of JSON documents (presets, scenes): every failure is one InputError
/// naming the file and the key path, e.g. `fur.json: kernel.lobes[2].sigma[1] = -0.5 is out of
/// range [0, 1000]`. Unknown keys, duplicate keys, wrong types, NaN/Inf and values that do not fit
/// a float are all errors.
#pragma once

#include <cfloat>
#include <cmath>
#include <cstdint>
#include <initializer_list>
#include <ostream>
#include <string>
#include <string_view>
#include <vector>

#include <glm/glm.hpp>
#include <nlohmann/json.hpp>

#include "error.h"

namespace spot::noise::json {

using Json = nlohmann::json;

/// Keys and strings from a hostile file end up in messages printed on one terminal line: keep
/// them printable and short.
inline constexpr std::size_t kMaxKeyShown = 64;
inline constexpr std::size_t kMaxDetailShown = 240;
inline constexpr std::size_t kMaxStringLength = 4096;
/// Nothing in our schemas nests deeper than 6; a cap keeps a hostile file from building a huge
/// tree of empty arrays.
inline constexpr int kMaxJsonDepth = 32;

/// Allowed interval of a number; open ends are written "(" or ")" in messages.
struct Interval {
    double lo;
    double hi;
    bool loOpen = false;
    bool hiOpen = false;

    bool contains(double v) const {
        return (loOpen ? v > lo : v >= lo) && (hiOpen ? v < hi : v <= hi);
    }
};

std::ostream& operator<<(std::ostream& out, const Interval& r);

std::string printable(std::string_view s, std::size_t maxShown = kMaxKeyShown);
std::string join(const std::string& path, std::string_view key);
std::string index(const std::string& path, std::size_t i);

/// Parse text as JSON, refusing duplicate keys and deep nesting; syntax errors name the byte.
Json parse(std::string_view text, const std::string& name);

/// Reads values out of the parsed document, each failure naming the file and the key path.
class Reader {
public:
    explicit Reader(const std::string& file) : m_file(file) {}

    const std::string& file() const { return m_file; }

    [[noreturn]] void fail(const std::string& message) const {
        throw InputError(cat(m_file, ": ", message));
    }

    /// `obj` must be an object whose keys are all in `allowed`.
    void requireObject(const Json& obj, const std::string& path,
                       std::initializer_list<std::string_view> allowed) const {
        requireObject(obj, path, std::vector<std::string_view>(allowed));
    }
    void requireObject(const Json& obj, const std::string& path,
                       const std::vector<std::string_view>& allowed) const {
        if (!obj.is_object())
            fail(cat(path.empty() ? "the document" : path, " must be an object, got ",
                     obj.type_name()));
        for (const auto& item : obj.items()) {
            bool known = false;
            for (std::string_view a : allowed)
                known = known || item.key() == a;
            if (!known)
                fail(cat("unknown key \"", join(path, printable(item.key())), "\""));
        }
    }

    static const Json* find(const Json& obj, std::string_view key) {
        const auto it = obj.find(key);
        return it == obj.end() ? nullptr : &*it;
    }

    const Json& require(const Json& obj, const std::string& path, std::string_view key) const {
        const Json* v = find(obj, key);
        if (!v)
            fail(cat("missing required key \"", join(path, key), "\""));
        return *v;
    }

    double number(const Json& j, const std::string& path, const Interval& r) const {
        if (!j.is_number())
            fail(cat(path, " must be a number, got ", j.type_name()));
        const double v = j.get<double>();
        // JSON has no NaN literal, but 1e999 parses to infinity and 1e39 does not fit a float.
        if (!std::isfinite(v) || std::abs(v) > double(FLT_MAX))
            fail(cat(path, " = ", v, " is not a finite 32-bit float"));
        if (!r.contains(v))
            fail(cat(path, " = ", v, " is out of range ", r));
        return v;
    }

    float real(const Json& j, const std::string& path, const Interval& r) const {
        return static_cast<float>(number(j, path, r));
    }

    std::int64_t integer(const Json& j, const std::string& path, std::int64_t lo,
                         std::int64_t hi) const {
        if (!j.is_number_integer())
            fail(cat(path, " must be an integer, got ",
                     j.is_number() ? "a fractional number" : j.type_name()));
        if (j.is_number_unsigned()) {
            const auto u = j.get<std::uint64_t>();
            if (u > static_cast<std::uint64_t>(hi))
                fail(cat(path, " = ", u, " is out of range [", lo, ", ", hi, "]"));
            return static_cast<std::int64_t>(u);
        }
        const auto v = j.get<std::int64_t>();
        if (v < lo || v > hi)
            fail(cat(path, " = ", v, " is out of range [", lo, ", ", hi, "]"));
        return v;
    }

    const Json& array(const Json& j, const std::string& path, std::size_t size,
                      std::string_view what) const {
        if (!j.is_array())
            fail(cat(path, " must be an array of ", size, " ", what, ", got ", j.type_name()));
        if (j.size() != size)
            fail(cat(path, " must be an array of ", size, " ", what, ", got ", j.size(),
                     j.size() == 1 ? " element" : " elements"));
        return j;
    }

    glm::vec3 vec3(const Json& j, const std::string& path, const Interval& r) const {
        array(j, path, 3, "numbers");
        return {real(j[0], index(path, 0), r), real(j[1], index(path, 1), r),
                real(j[2], index(path, 2), r)};
    }

    std::string string(const Json& j, const std::string& path, bool allowEmpty) const {
        if (!j.is_string())
            fail(cat(path, " must be a string, got ", j.type_name()));
        const auto& s = j.get_ref<const std::string&>();
        if (!allowEmpty && s.empty())
            fail(cat(path, " must not be empty"));
        if (s.size() > kMaxStringLength)
            fail(cat(path, " is longer than ", kMaxStringLength, " characters"));
        return s;
    }

    /// The document's "version" key, which must equal `expected`.
    void requireVersion(const Json& root, int expected) const;

private:
    std::string m_file;
};

} // namespace spot::noise::json
