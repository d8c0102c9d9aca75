#include "render_options.h"

#include "noise/error.h"

namespace spot::cli {

namespace {

using splat::Setting;
using splat::SettingType;

std::string rangeText(const Setting& s) {
    switch (s.type) {
    case SettingType::Integer:
    case SettingType::Number:
        return cat("; ", s.min, " to ", s.max);
    case SettingType::Choice: {
        std::string names;
        for (std::size_t i = 0; i < s.choices.size(); ++i)
            names += (i == 0 ? "" : i + 1 == s.choices.size() ? " or " : ", ") + s.choices[i];
        return "; " + names;
    }
    default:
        return "";
    }
}

} // namespace

std::vector<OptionSpec> renderOptions() {
    std::vector<OptionSpec> specs;
    for (const Setting* s : splat::allSettings()) {
        std::string help = splat::methodsTaking(*s) + ": " + s->help;
        if (s->type != SettingType::Flag && s->type != SettingType::File)
            help += " (default " + s->defaultValue() + rangeText(*s) + ")";
        specs.push_back({s->name, s->value, help, false});
    }
    return specs;
}

splat::RenderSettings renderSettings(const Args& args, splat::RenderSettings base) {
    splat::RenderSettings r = std::move(base);
    const std::vector<const Setting*> all = splat::allSettings();
    // Values first, files last: a bad value is named before a file is read.
    for (const bool files : {false, true})
        for (const Setting* s : all) {
            if ((s->type == SettingType::File) != files || !args.has(s->name))
                continue;
            switch (s->type) {
            case SettingType::Integer: // Args' messages: "spotshell render: --steps 5000 is ..."
                s->set(r, double(args.integer(s->name, 0, std::int64_t(s->min),
                                              std::int64_t(s->max))));
                break;
            case SettingType::Number:
                s->set(r, args.number(s->name, 0.0, s->min, s->max));
                break;
            case SettingType::Flag:
                s->set(r, 1.0);
                break;
            default:
                s->parse(r, args.str(s->name));
            }
        }
    return r;
}

OptionSpec qualityOption() {
    std::string help = "pick the method and its settings from the speed/accuracy front the bench "
                       "measured (splat/quality.h): ";
    for (const splat::QualityChoice& q : splat::qualityChoices())
        help += cat(q.name, " = ", q.summary, "; ");
    help +=
        cat("default ", splat::kDefaultQuality, " when --method is not given; not with --method");
    return {"quality", "NAME", help, false};
}

MethodChoice methodChoice(const Args& args, const std::string& context, bool gpuOnly) {
    if (args.has("method") && args.has("quality"))
        throw InputError(cat(context, ": --quality ", args.str("quality"),
                             " picks the method; give --quality or --method ", args.str("method"),
                             ", not both"));
    MethodChoice c;
    if (args.has("method")) {
        c.method = args.str("method");
        const splat::MethodInfo* info = splat::findMethod(c.method);
        if (!info || (gpuOnly && !info->gpu()))
            throw InputError(cat(context, ": unknown method '", c.method, "' (",
                                 gpuOnly ? splat::gpuMethodNames() : splat::methodNames(), ")"));
    } else {
        c.quality = args.str("quality", std::string(splat::kDefaultQuality));
        const splat::QualityChoice* q = splat::findQuality(c.quality);
        if (!q)
            throw InputError(
                cat(context, ": unknown quality '", c.quality, "' (", splat::qualityNames(), ")"));
        c.method = q->method;
        c.settings = q->settings;
    }
    return c;
}

void refuseSettingsNotTakenBy(const Args& args, const splat::MethodInfo& method,
                              const std::string& context) {
    for (const Setting* s : splat::allSettings())
        if (args.has(s->name) && !method.takes(*s))
            throw InputError(cat(context, ": --", s->name, " is a setting of ",
                                 splat::methodsTaking(*s), ", not of ", method.name));
}

nlohmann::json describe(const splat::MethodInfo& method, const splat::RenderSettings& settings) {
    nlohmann::json d = nlohmann::json::object();
    for (const Setting* s : method.settings) {
        switch (s->type) {
        case SettingType::Toggle:
        case SettingType::Flag:
            d[s->key()] = s->get(settings) != 0.0;
            break;
        case SettingType::Integer:
            d[s->key()] = std::int64_t(s->get(settings));
            break;
        case SettingType::Number:
            d[s->key()] = s->get(settings);
            break;
        case SettingType::Choice:
        case SettingType::File:
            d[s->key()] = s->text(settings);
            break;
        }
    }
    return d;
}

} // namespace spot::cli
