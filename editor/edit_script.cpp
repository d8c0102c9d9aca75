#include "edit_script.h"

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <sstream>

#include "cli.h"
#include "edit_session.h"
#include "noise/error.h"
#include "noise/system.h"
#include "render_options.h"

namespace spot::edit {

namespace {

using Clock = std::chrono::steady_clock;

double msSince(Clock::time_point start) {
    return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

/// The tokens of one line, with the failure message's prefix.
class Line {
public:
    Line(std::vector<std::string> tokens, std::string where, std::string text)
        : m_tokens(std::move(tokens)), m_where(std::move(where)), m_text(std::move(text)) {}

    [[noreturn]] void fail(const std::string& message) const {
        throw InputError(cat(m_where, ": ", message, " (the line: ", m_text, ")"));
    }
    bool done() const { return m_next >= m_tokens.size(); }
    const std::string& peek() const { return m_tokens[m_next]; }
    std::string word(const char* what) {
        if (done())
            fail(cat("missing ", what));
        return m_tokens[m_next++];
    }
    double number(const char* what, double lo, double hi) {
        const std::string t = word(what);
        char* end = nullptr;
        const double v = std::strtod(t.c_str(), &end);
        if (end != t.c_str() + t.size() || t.empty() || !std::isfinite(v))
            fail(cat(what, " '", t, "' is not a number"));
        if (v < lo || v > hi)
            fail(cat(what, " ", v, " is outside [", lo, ", ", hi, "]"));
        return v;
    }
    int integer(const char* what, int lo, int hi) {
        const std::string t = peekWord(what);
        const double v = number(what, lo, hi);
        if (v != std::floor(v))
            fail(cat(what, " '", t, "' is not an integer"));
        return int(v);
    }
    glm::dvec3 vec3(const char* what, double lo, double hi) {
        const double x = number(what, lo, hi), y = number(what, lo, hi), z = number(what, lo, hi);
        return {x, y, z};
    }
    std::string rest() {
        std::string s;
        while (!done())
            s += (s.empty() ? "" : " ") + m_tokens[m_next++];
        return s;
    }
    void end() const {
        if (!done())
            fail(cat("unexpected '", m_tokens[m_next], "'"));
    }

private:
    std::string peekWord(const char* what) const {
        if (done())
            fail(cat("missing ", what));
        return m_tokens[m_next];
    }
    std::vector<std::string> m_tokens;
    std::string m_where, m_text;
    std::size_t m_next = 0;
};

constexpr double kBig = 1e9;

/// `method NAME [KEY VALUE]...`: the settings from their descriptors (splat/settings.h), each
/// written as on the command line (flags as on|off), on the defaults, and which were given; a
/// setting the method does not take is refused, naming the methods that take it.
splat::RenderSettings parseMethodSettings(Line& line, const std::string& method,
                                          std::vector<const splat::Setting*>& givenSettings) {
    const splat::MethodInfo& info = splat::method(method);
    std::vector<std::pair<const splat::Setting*, std::string>> given;
    while (!line.done()) {
        const std::string key = line.word("setting");
        const std::string value = line.word(cat("value of ", key).c_str());
        const splat::Setting* setting = nullptr;
        for (const splat::Setting* s : splat::allSettings())
            if (s->name == key)
                setting = s;
        if (!setting)
            line.fail(cat("unknown setting '", key, "' of ", method));
        if (!info.takes(*setting))
            line.fail(
                cat(key, " is a setting of ", splat::methodsTaking(*setting), ", not of ", method));
        given.emplace_back(setting, value);
        givenSettings.push_back(setting);
    }
    splat::RenderSettings settings;
    try {
        // Values first, files last: a bad value is named before a file is read.
        for (const bool files : {false, true})
            for (const auto& [setting, value] : given)
                if ((setting->type == splat::SettingType::File) == files)
                    setting->parse(settings, value);
    } catch (const InputError& e) {
        line.fail(e.what());
    }
    return settings;
}

void parseBrush(Line& line, BrushSettings& b) {
    try {
        b.kind = parseBrushKind(line.word("brush kind"));
    } catch (const InputError& e) {
        line.fail(e.what());
    }
    while (!line.done()) {
        const std::string key = line.word("brush option");
        if (key == "radius") {
            b.radiusPx = float(line.number("radius", 0.5, 4096.0));
        } else if (key == "strength") {
            b.strength = float(line.number("strength", -1.0, 1.0));
        } else if (key == "falloff") {
            try {
                b.falloff = parseFalloff(line.word("falloff"));
            } catch (const InputError& e) {
                line.fail(e.what());
            }
        } else if (key == "raise") {
            b.raise = true;
        } else if (key == "mirror") {
            if (line.word("mirror axis") != "x")
                line.fail("only 'mirror x' is supported");
            b.mirrorX = true;
        } else if (key == "color") {
            b.color = glm::vec3(line.vec3("color", 0.0, 1.0));
        } else if (key == "backfaces") {
            b.frontFacesOnly = false;
        } else if (key == "target") {
            const std::string slot = line.word("target");
            if (slot == "density")
                b.smoothTarget = Slot::Density;
            else if (slot == "comb")
                b.smoothTarget = Slot::Comb;
            else if (slot == "tilt")
                b.smoothTarget = Slot::Tilt;
            else if (slot == "length")
                b.smoothTarget = Slot::Scale;
            else if (slot == "color")
                b.smoothTarget = Slot::Color;
            else if (slot == "clump")
                b.smoothTarget = Slot::Clump;
            else if (slot == "clump-size")
                b.smoothTarget = Slot::ClumpSize;
            else if (slot == "mask")
                b.smoothTarget = Slot::Mask;
            else
                line.fail(cat("target '", slot,
                              "' is not density, comb, tilt, length, color, clump, clump-size or "
                              "mask"));
        } else if (key == "limit") {
            try {
                b.limit = parseMaskLimit(line.word("limit"));
            } catch (const InputError& e) {
                line.fail(e.what());
            }
        } else {
            line.fail(cat("unknown brush option '", key,
                          "' (radius, strength, falloff, mirror, color, raise, backfaces, target, "
                          "limit)"));
        }
    }
}

void checkExtension(Line& line, const std::filesystem::path& file,
                    std::initializer_list<const char*> extensions) {
    std::string ext = file.extension().string();
    for (char& c : ext)
        c = char(std::tolower(static_cast<unsigned char>(c)));
    std::string list;
    for (const char* e : extensions) {
        if (ext == e)
            return;
        list += (list.empty() ? "" : ", ") + std::string(e);
    }
    line.fail(cat("'", file.string(), "' must end in ", list));
}

// One branch per verb, each a few lines (about 120 in all): the verbs read as one table.
ScriptAction parseLine(Line& line, const std::string& verb) {
    using T = ScriptAction::Type;
    ScriptAction a;
    if (verb == "camera") {
        a.type = T::Camera;
        if (line.word("'eye'") != "eye")
            line.fail("expected 'camera eye X Y Z target X Y Z [fov DEG]'");
        a.eye = line.vec3("eye", -kBig, kBig);
        if (line.word("'target'") != "target")
            line.fail("expected 'camera eye X Y Z target X Y Z [fov DEG]'");
        a.target = line.vec3("target", -kBig, kBig);
        if (!line.done()) {
            if (line.word("'fov'") != "fov")
                line.fail("expected 'fov DEG'");
            a.fovDeg = line.number("fov", 1.0, 179.0);
        }
        if (glm::length(a.eye - a.target) == 0.0)
            line.fail("eye and target coincide");
    } else if (verb == "method") {
        a.type = T::Method;
        a.name = line.word("method name");
        if (!splat::findGpuMethod(a.name))
            line.fail(cat("unknown method '", a.name, "' (", splat::gpuMethodNames(), ")"));
        a.settings = parseMethodSettings(line, a.name, a.given);
    } else if (verb == "brush") {
        a.type = T::Brush;
        parseBrush(line, a.brush);
    } else if (verb == "stroke") {
        a.type = T::Stroke;
        while (!line.done()) {
            const std::string p = line.word("point");
            float x = 0.0f, y = 0.0f;
            char extra = 0;
            if (std::sscanf(p.c_str(), "%f,%f%c", &x, &y, &extra) != 2 || !std::isfinite(x) ||
                !std::isfinite(y))
                line.fail(cat("point '", p, "' must be X,Y (window pixels)"));
            a.points.emplace_back(x, y);
        }
        if (a.points.empty())
            line.fail("a stroke needs at least one point X,Y");
    } else if (verb == "undo" || verb == "redo") {
        a.type = verb == "undo" ? T::Undo : T::Redo;
    } else if (verb == "lobe") {
        a.type = T::Lobe;
        const std::string first = line.word("lobe index, add or remove");
        if (first == "add" || first == "remove") {
            a.name = first;
            a.index = line.integer("lobe index", 0, noise::kMaxLobes - 1);
        } else {
            char* end = nullptr;
            const long i = std::strtol(first.c_str(), &end, 10);
            if (end != first.c_str() + first.size() || i < 0 || i >= noise::kMaxLobes)
                line.fail(cat("lobe index '", first, "' must be 0..", noise::kMaxLobes - 1));
            a.index = int(i);
            const std::string what = line.word("lobe property");
            if (what == "offset" || what == "sigma" || what == "color" || what == "rotation") {
                const glm::dvec3 v = what == "color"   ? line.vec3("color", 0.0, 1.0)
                                     : what == "sigma" ? line.vec3("sigma", 0.0, kBig)
                                                       : line.vec3(what.c_str(), -kBig, kBig);
                a.name = what == "rotation" ? "rotation_deg" : what;
                a.value = {v.x, v.y, v.z};
            } else if (what == "extinction") {
                a.name = what;
                a.value = line.number("extinction", 0.0, kBig);
            } else {
                line.fail(cat("lobe property '", what,
                              "' is not offset, rotation, sigma, extinction or color"));
            }
        }
    } else if (verb == "set") {
        a.type = T::Set;
        a.name = line.word("key path");
        try {
            (void)keyPathPointer(a.name);
        } catch (const InputError& e) {
            line.fail(e.what());
        }
        const std::string value = line.rest();
        if (value.empty())
            line.fail("missing value");
        try {
            a.value = nlohmann::json::parse(value);
        } catch (const nlohmann::json::exception&) {
            line.fail(cat("value '", value, "' is not JSON"));
        }
    } else if (verb == "seed") {
        a.type = T::Seed;
        a.seed = std::uint32_t(line.number("seed", 0.0, 4294967295.0));
    } else if (verb == "wind") {
        a.type = T::Wind;
        const std::string state = line.word("on or off");
        if (state != "on" && state != "off")
            line.fail(cat("wind '", state, "' must be on or off"));
        a.on = state == "on";
        while (!line.done()) {
            const std::string key = line.word("wind option");
            if (key == "amplitude")
                a.amplitudeDeg = float(line.number("amplitude", 0.0, 80.0));
            else if (key == "frequency")
                a.frequencyHz = float(line.number("frequency", 0.0, 100.0));
            else
                line.fail(cat("unknown wind option '", key, "' (amplitude, frequency)"));
        }
    } else if (verb == "light") {
        a.type = T::Light;
        const std::string state = line.word("on or off");
        if (state != "on" && state != "off")
            line.fail(cat("light '", state, "' must be on or off"));
        a.on = state == "on";
        while (!line.done()) {
            const std::string key = line.word("light option");
            if (key == "azimuth")
                a.azimuthDeg = float(line.number("azimuth", -360.0, 360.0));
            else if (key == "elevation")
                a.elevationDeg = float(line.number("elevation", -90.0, 90.0));
            else if (key == "intensity")
                a.intensity = float(line.number("intensity", 0.0, 10000.0));
            else if (key == "shadows") {
                const std::string s = line.word("on or off");
                if (s != "on" && s != "off")
                    line.fail(cat("shadows '", s, "' must be on or off"));
                a.shadows = s == "on";
            } else
                line.fail(cat("unknown light option '", key,
                              "' (azimuth, elevation, intensity, shadows)"));
        }
        if (!a.on && (a.azimuthDeg || a.elevationDeg || a.intensity || a.shadows))
            line.fail("'light off' takes no options");
    } else if (verb == "mask") {
        a.type = T::Mask;
        if (line.word("'overlay'") != "overlay")
            line.fail("expected 'mask overlay on|off'");
        const std::string state = line.word("on or off");
        if (state != "on" && state != "off")
            line.fail(cat("mask overlay '", state, "' must be on or off"));
        a.on = state == "on";
    } else if (verb == "frames") {
        a.type = T::Frames;
        a.count = line.integer("frame count", 1, 100000);
    } else if (verb == "time") {
        a.type = T::Time;
        a.seconds = line.number("time", -kBig, kBig);
    } else if (verb == "play") {
        a.type = T::Play;
        a.count = line.integer("frame count", 1, 100000);
        if (!line.done()) {
            if (line.word("'loop'") != "loop")
                line.fail("expected 'play N [loop on|off]'");
            const std::string state = line.word("on or off");
            if (state != "on" && state != "off")
                line.fail(cat("loop '", state, "' must be on or off"));
            a.loop = state == "on";
        }
    } else if (verb == "save") {
        a.type = T::Save;
        a.file = line.word("file");
        checkExtension(line, a.file, {".json"});
    } else if (verb == "screenshot") {
        a.type = T::Screenshot;
        a.file = line.word("file");
        checkExtension(line, a.file, {".png", ".exr"});
    } else {
        line.fail(
            cat("unknown action '", verb,
                "' (camera, method, brush, stroke, undo, redo, lobe, set, seed, wind, light, mask, "
                "frames, time, play, save, screenshot)"));
    }
    line.end();
    return a;
}

} // namespace

std::string scriptLineError(const std::string& name, const ScriptAction& action,
                            const std::string& message) {
    return cat("script ", name, ":", action.line, ": ", message, " (the line: ", action.text, ")");
}

splat::RenderSettings methodSettings(const ScriptAction& action,
                                     const splat::RenderSettings& current) {
    splat::RenderSettings s = current;
    for (const splat::Setting* setting : action.given) {
        if (setting->type == splat::SettingType::File) {
            // The resource the line read (the bake) is shared, not read again.
            if (setting == &splat::settings::bake)
                s.bake = action.settings.bake;
            else
                setting->setText(s, setting->getText(action.settings));
        } else {
            setting->set(s, setting->get(action.settings));
        }
    }
    return s;
}

std::vector<ScriptAction> parseScript(std::string_view text, const std::string& name) {
    std::vector<ScriptAction> actions;
    std::istringstream in{std::string(text)};
    std::string raw;
    int number = 0;
    while (std::getline(in, raw)) {
        ++number;
        std::string content = raw.substr(0, raw.find('#'));
        if (!content.empty() && content.back() == '\r')
            content.pop_back();
        std::istringstream words(content);
        std::vector<std::string> tokens;
        for (std::string w; words >> w;)
            tokens.push_back(w);
        if (tokens.empty())
            continue;
        const std::size_t first = content.find_first_not_of(" \t");
        const std::size_t last = content.find_last_not_of(" \t");
        const std::string text = content.substr(first, last - first + 1);
        Line line(tokens, cat("script ", name, ":", number), text);
        const std::string verb = line.word("action");
        ScriptAction a = parseLine(line, verb);
        a.line = number;
        a.text = text;
        actions.push_back(std::move(a));
    }
    return actions;
}

std::vector<ScriptAction> loadScript(const std::filesystem::path& file) {
    return parseScript(readFileCapped(file, 16ull << 20), file.string());
}

ScriptReport runScript(Session& session, const std::vector<ScriptAction>& actions,
                       const std::string& name, std::FILE* log) {
    ScriptReport report;
    for (const ScriptAction& a : actions)
        runScriptAction(session, a, name, log, report);
    return report;
}

// One branch per action type, each a few lines (about 120 in all), in the order of parseLine.
void runScriptAction(Session& session, const ScriptAction& a, const std::string& name,
                     std::FILE* log, ScriptReport& report) {
    using T = ScriptAction::Type;
    {
        const auto start = Clock::now();
        std::string note;
        try {
            switch (a.type) {
            case T::Camera: {
                noise::Camera c = session.camera();
                c.eye = a.eye;
                c.target = a.target;
                if (a.fovDeg)
                    c.fovYDeg = *a.fovDeg;
                session.setCamera(c);
                break;
            }
            case T::Method: {
                // One frame now, so that settings the method refuses (baked without a bake)
                // are blamed on this line, not on the next one that renders.
                session.setMethod(a.name, methodSettings(a, session.settings()));
                const double frameMs = session.render().wallMs;
                note = cat("a first frame in ", frameMs, " ms (checks the settings)");
                break;
            }
            case T::Brush: {
                // Arming a constant field's slot rebuilds the frame; the window's next frame
                // would absorb the rest (the renderer made again, every impulse generated), so
                // one frame here too: the script's first stroke then measures what the window's
                // does.
                const EditCost cost = session.setBrush(a.brush);
                if (!cost.armed && !cost.generatorRebuilt)
                    break;
                const double frameMs = cost.generatorRebuilt ? session.render().wallMs : 0.0;
                report.armMs.push_back(cost.milliseconds);
                report.armFrameMs.push_back(frameMs);
                note = cat(cost.armed ? cat("armed ", slotKey(brushSlot(a.brush)))
                                      : std::string("disarmed"),
                           " in ", cost.milliseconds, " ms",
                           cost.generatorRebuilt ? cat(", then a frame in ", frameMs, " ms") : "");
                break;
            }
            case T::Stroke: {
                // The last pointer event to the frame that shows it: the dabs of that event, the
                // fields' refresh, the regeneration and the render, pixels read back.
                EditCost cost = session.beginStroke(a.points.front());
                Clock::time_point lastEvent = start;
                double eventMs = cost.milliseconds;
                for (std::size_t i = 1; i < a.points.size(); ++i) {
                    lastEvent = Clock::now();
                    const EditCost c = session.dragStroke(a.points[i]);
                    cost.milliseconds += c.milliseconds;
                    eventMs = c.milliseconds;
                }
                const EditCost end = session.endStroke();
                noise::Image image;
                const splat::FrameStats frame = session.render(&image);
                const double toFrame = msSince(lastEvent);
                report.strokeToFrameMs.push_back(toFrame);
                report.eventMs.push_back(eventMs);
                report.frameMs.push_back(frame.wallMs);
                double generateMs = 0.0;
                for (const auto& [pass, ms] : frame.passMs)
                    generateMs += pass == "generate" ? ms : 0.0;
                report.generateMs.push_back(generateMs);
                report.strokeMs += cost.milliseconds;
                ++report.strokes;
                note = cat(end.dabs, " dabs, ", end.voxelsWritten, " voxels, ", cost.milliseconds,
                           " ms painting; frame ", frame.kernelsGenerated, " kernels, ", toFrame,
                           " ms event-to-frame (event ", eventMs, " ms, frame ", frame.wallMs,
                           " ms of which generate ", generateMs, " ms GPU)");
                break;
            }
            case T::Undo:
            case T::Redo: {
                EditCost cost;
                const bool done = a.type == T::Undo ? session.undo(&cost) : session.redo(&cost);
                report.paramMs += cost.milliseconds;
                note = done ? cat(cost.milliseconds, " ms") : "nothing to do";
                break;
            }
            case T::Lobe: {
                const EditCost cost = a.name == "add" ? session.addLobe(a.index)
                                      : a.name == "remove"
                                          ? session.removeLobe(a.index)
                                          : session.setLobe(a.index, a.name, a.value);
                report.paramMs += cost.milliseconds;
                note = cat("rebuilt in ", cost.milliseconds, " ms");
                break;
            }
            case T::Set: {
                const EditCost cost = session.set(a.name, a.value);
                report.paramMs += cost.milliseconds;
                note = cat("rebuilt in ", cost.milliseconds, " ms");
                break;
            }
            case T::Seed: {
                const EditCost cost = session.setSeed(a.seed);
                report.paramMs += cost.milliseconds;
                note = cat("rebuilt in ", cost.milliseconds, " ms");
                break;
            }
            case T::Wind:
                session.setWind(a.on, a.amplitudeDeg, a.frequencyHz);
                break;
            case T::Light: {
                session.setLit(a.on);
                if (a.on && (a.azimuthDeg || a.elevationDeg || a.intensity || a.shadows)) {
                    const Session::KeyLight k = session.keyLight();
                    session.setKeyLight(a.azimuthDeg.value_or(k.azimuthDeg),
                                        a.elevationDeg.value_or(k.elevationDeg),
                                        a.intensity.value_or(k.intensity),
                                        a.shadows.value_or(k.shadows));
                }
                break;
            }
            case T::Mask:
                session.setMaskOverlay(a.on);
                break;
            case T::Frames:
                for (int i = 0; i < a.count; ++i) {
                    session.setTime(session.time() + 1.0 / 30.0);
                    session.render();
                }
                report.frames += a.count;
                break;
            case T::Time:
                session.setTime(a.seconds);
                note = cat("t ", session.time(), " s, frame ", session.frameNumber());
                break;
            case T::Play: {
                if (a.loop)
                    session.setLoop(*a.loop);
                const double step = 1.0 / session.timeline().fps;
                for (int i = 0; i < a.count; ++i) {
                    session.advance(step);
                    session.render();
                }
                report.frames += a.count;
                note = cat(a.count, " frames to t ", session.time(), " s, frame ",
                           session.frameNumber());
                break;
            }
            case T::Save:
                session.save(a.file);
                note = cat("wrote ", a.file.string());
                break;
            case T::Screenshot:
                session.exportImage(a.file);
                note = cat("wrote ", a.file.string());
                break;
            }
        } catch (const InputError& e) {
            throw InputError(scriptLineError(name, a, e.what()));
        }
        // The whole line: a long one pushes the note to the right rather than being cut.
        if (log)
            std::fprintf(log, "%4d  %-40s %s%s%.1f ms\n", a.line, a.text.c_str(), note.c_str(),
                         note.empty() ? "" : "; ", msSince(start));
    }
}

} // namespace spot::edit
