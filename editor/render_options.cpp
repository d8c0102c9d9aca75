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

splat::RenderSettings renderSettings(const Args& args) {
    splat::RenderSettings r;
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
