#include "settings.h"

#include <charconv>
#include <cmath>
#include <cstdlib>

#include "noise/error.h"
#include "splat/layout.h"
#include "splat/methods/baked/bake_data.h"
#include "splat/methods/raymarch/raymarch_vk.h"

namespace spot::splat {

namespace {

Setting describe(std::string name, SettingType type, std::string value, std::string help,
                 double min = 0.0, double max = 0.0, double panelMax = 0.0) {
    Setting s;
    s.name = std::move(name);
    s.type = type;
    s.value = std::move(value);
    s.help = std::move(help);
    s.min = min;
    s.max = max;
    s.panelMax = panelMax;
    return s;
}

/// A setting stored in an int, bool or double member of RenderSettings.
template <typename T> Setting numeric(Setting s, T RenderSettings::*member) {
    s.get = [member](const RenderSettings& r) { return double(r.*member); };
    s.set = [member](RenderSettings& r, double v) {
        if constexpr (std::is_same_v<T, bool>)
            r.*member = v != 0.0;
        else
            r.*member = T(v);
    };
    return s;
}

/// A Choice stored in an enum member, `names` in the enum's order.
template <typename E>
Setting choice(Setting s, std::vector<std::string> names, E RenderSettings::*member) {
    s.choices = std::move(names);
    s.get = [member](const RenderSettings& r) { return double(int(r.*member)); };
    s.set = [member](RenderSettings& r, double v) { r.*member = E(int(v)); };
    return s;
}

std::string numberText(double v) {
    if (v == std::floor(v) && std::abs(v) < 1e15)
        return std::to_string(std::int64_t(v));
    return cat(v);
}

} // namespace

std::string Setting::key() const {
    std::string k = name;
    for (char& c : k)
        if (c == '-')
            c = '_';
    return k;
}

std::string Setting::text(const RenderSettings& s) const {
    switch (type) {
    case SettingType::Toggle:
    case SettingType::Flag:
        return get(s) != 0.0 ? "on" : "off";
    case SettingType::Choice:
        return choices.at(std::size_t(get(s)));
    case SettingType::File:
        return getText(s);
    case SettingType::Integer:
    case SettingType::Number:
        break;
    }
    return numberText(get(s));
}

std::string Setting::defaultValue() const {
    return defaultText.empty() ? text(RenderSettings{}) : defaultText;
}

void Setting::parse(RenderSettings& s, const std::string& value) const {
    switch (type) {
    case SettingType::Toggle:
    case SettingType::Flag:
        if (value != "on" && value != "off")
            throw InputError(cat("--", name, " must be on or off, not '", value, "'"));
        set(s, value == "on" ? 1.0 : 0.0);
        return;
    case SettingType::Choice:
        for (std::size_t i = 0; i < choices.size(); ++i)
            if (choices[i] == value) {
                set(s, double(i));
                return;
            }
        {
            std::string names;
            for (std::size_t i = 0; i < choices.size(); ++i)
                names += (i == 0 ? "" : i + 1 == choices.size() ? " or " : ", ") + choices[i];
            throw InputError(cat("--", name, " must be ", names, ", not '", value, "'"));
        }
    case SettingType::File:
        setText(s, value);
        return;
    case SettingType::Integer: {
        std::int64_t v = 0;
        const auto [ptr, ec] = std::from_chars(value.data(), value.data() + value.size(), v);
        if (ec != std::errc() || ptr != value.data() + value.size())
            throw InputError(cat("--", name, " expects an integer, got '", value, "'"));
        if (double(v) < min || double(v) > max)
            throw InputError(cat("--", name, " ", v, " is outside [", min, ", ", max, "]"));
        set(s, double(v));
        return;
    }
    case SettingType::Number: {
        char* end = nullptr;
        const double v = std::strtod(value.c_str(), &end);
        if (value.empty() || end != value.c_str() + value.size() || !std::isfinite(v))
            throw InputError(cat("--", name, " expects a finite number, got '", value, "'"));
        if (v < min || v > max)
            throw InputError(cat("--", name, " ", v, " is outside [", min, ", ", max, "]"));
        set(s, v);
        return;
    }
    }
}

namespace settings {

using T = SettingType;

const Setting kernelSamples =
    numeric(describe("kernel-samples", T::Integer, "N",
                     "march N samples per kernel (paper eq. 10); 0: the analytic integral", 0.0,
                     double(gpu_splat::kSplatMaxKernelSamples), 64.0),
            &RenderSettings::kernelSamples);
const Setting ewa =
    numeric(describe("ewa", T::Toggle, "on|off", "EWA filtering by the pixel footprint"),
            &RenderSettings::ewa);
const Setting weight = choice(describe("weight", T::Choice, "W", "the OIT weight"),
                              {"constant", "mcguire-bavoil"}, &RenderSettings::weight);
const Setting closest = choice(
    describe("closest", T::Choice, "HOW",
             "find each pixel's closest kernel with an atomicMin in the OIT pass (atomic) or in "
             "a depth pass of its own (depth-pass): the same kernel either way; the depth pass "
             "draws every kernel (no small-kernel compute path), so the images are identical "
             "with --small-pixels 0 and differ by the compute path's fixed-point rounding "
             "otherwise"),
    {"atomic", "depth-pass"}, &RenderSettings::closest);
const Setting smallPixels = numeric(
    describe("small-pixels", T::Integer, "N",
             cat("kernels whose quad covers at most N pixel centres are evaluated by a compute "
                 "pass instead of drawn, and so are thin ones (at most 3 pixels wide) covering "
                 "at most ",
                 gpu_splat::kSplatMaxSmallPixels, " (0: draw every kernel)"),
             0.0, double(gpu_splat::kSplatMaxSmallPixels)),
    &RenderSettings::smallPixels);
const Setting countFragments = numeric(
    describe("count-fragments", T::Flag, "",
             "count the fragments shaded and the pixels a kernel covers (alpha >= 1/255); slows "
             "the splat pass"),
    &RenderSettings::countFragments);
const Setting lod = numeric(describe("lod", T::Number, "PIXELS",
                                     "thin the kernels of cells smaller than PIXELS on screen, "
                                     "conserving mass (0: off)",
                                     0.0, 64.0, 16.0),
                            &RenderSettings::lodPixels);
const Setting steps = numeric(
    describe("steps", T::Integer, "N",
             "samples along each ray through the shell (split over dispatches so that no shader "
             "invocation loops too long)",
             1.0, double(kRaymarchMaxSteps), 256.0),
    &RenderSettings::steps);
const Setting supersample =
    numeric(describe("supersample", T::Integer, "N", "N x N rays per pixel, box-filtered", 1.0,
                     double(kRaymarchMaxSupersample), 4.0),
            &RenderSettings::supersample);
const Setting peelPasses =
    numeric(describe("peel-passes", T::Integer, "N", "depth-peeling layers of tetrahedra", 1.0,
                     double(kBakedMaxPeelPasses), 16.0),
            &RenderSettings::peelPasses);
const Setting allowMismatch = numeric(
    describe("allow-mismatch", T::Flag, "",
             "render a bake made for another mesh or cell size (its recorded mesh hash is not "
             "the scene's); the image is then meaningless"),
    &RenderSettings::allowMismatch);
const Setting spp = [] {
    Setting s = numeric(describe("spp", T::Integer, "N", "samples per pixel", 1.0, 65536.0),
                        &RenderSettings::spp);
    s.defaultText = "the scene's";
    return s;
}();
const Setting stepScale =
    numeric(describe("step-scale", T::Number, "X", "quadrature step multiplier", 1e-3, 1e3),
            &RenderSettings::stepScale);

} // namespace settings

} // namespace spot::splat
