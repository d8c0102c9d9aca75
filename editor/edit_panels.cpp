#include "edit_panels.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstring>

#include <imgui.h>
#include <nlohmann/json.hpp>

#include "edit_session.h"
#include "noise/error.h"
#include "noise/image.h"
#include "splat/method_vk.h"

namespace spot::editor {

namespace {

/// A widget over `values` whose edits are held in the panel while it is active; returns true on
/// the frame it is released after an edit, with `values` then holding what to commit.
template <typename Widget>
bool heldEdit(SessionPanels& st, const std::string& label, std::vector<float>& values,
              Widget widget) {
    if (const auto it = st.held.find(label); it != st.held.end())
        values = it->second;
    widget(label.c_str(), values.data());
    const bool commit = ImGui::IsItemDeactivatedAfterEdit();
    if (ImGui::IsItemActive())
        st.held[label] = values;
    else
        st.held.erase(label);
    return commit;
}

std::vector<float> floats(const nlohmann::json& j, std::vector<float> fallback) {
    if (j.is_number())
        return {j.get<float>()};
    if (j.is_array() && j.size() == fallback.size())
        for (std::size_t i = 0; i < fallback.size(); ++i)
            fallback[i] = j[i].get<float>();
    return fallback;
}

nlohmann::json toJson(const std::vector<float>& v) {
    if (v.size() == 1)
        return double(v[0]);
    nlohmann::json a = nlohmann::json::array();
    for (float x : v)
        a.push_back(double(x));
    return a;
}

/// Run a session edit; an InputError goes to the File panel's message.
template <typename F> bool attempt(SessionPanels& st, F edit) {
    try {
        edit();
        return true;
    } catch (const InputError& e) {
        st.message = e.what();
        st.messageIsError = true;
        return false;
    }
}

/// Item widths leave this much of the column to the labels (pixels).
constexpr float kLabelWidth = -125.0f;

/// Choosing a kind or a smooth target arms its slot (Session::armBrush); returns true then (the
/// view is rendered again).
bool brushPanel(edit::Session& session, SessionPanels& st) {
    edit::BrushSettings& b = session.brush();
    bool armed = false;
    if (!beginSection("Brush", st))
        return false;
    ImGui::PushItemWidth(kLabelWidth);
    int kind = int(b.kind);
    if (ImGui::BeginCombo("kind", edit::brushKindName(b.kind))) {
        for (int k = 0; k < edit::kBrushKindCount; ++k)
            if (ImGui::Selectable(
                    cat((k + 1) % 10, "  ", edit::brushKindName(edit::BrushKind(k))).c_str(),
                    k == kind))
                armed |= attempt(st, [&] { session.setBrushKind(edit::BrushKind(k)); });
        ImGui::EndCombo();
    }
    ImGui::SliderFloat("radius px", &b.radiusPx, 2.0f, 200.0f, "%.0f");
    ImGui::SliderFloat("strength", &b.strength, -1.0f, 1.0f, "%.2f");
    int falloff = int(b.falloff);
    if (ImGui::Combo("falloff", &falloff, "smooth\0linear\0constant\0"))
        b.falloff = edit::Falloff(falloff);
    ImGui::Checkbox("front faces only", &b.frontFacesOnly);
    ImGui::Checkbox("X mirror", &b.mirrorX);
    ImGui::ColorEdit3("colour", &b.color.x, ImGuiColorEditFlags_Float);
    int target = int(b.smoothTarget);
    if (ImGui::Combo("smooth target", &target,
                     "density\0comb\0tilt\0length\0color\0clump\0clump size\0mask\0")) {
        b.smoothTarget = edit::Slot(target);
        armed |= attempt(st, [&] { session.armBrush(); });
    }
    int limit = int(b.limit);
    if (ImGui::Combo("limit", &limit, "everywhere\0only masked\0only unmasked\0"))
        b.limit = edit::MaskLimit(limit);
    bool overlay = session.maskOverlay();
    if (ImGui::Checkbox("show mask (M)", &overlay)) {
        session.setMaskOverlay(overlay);
        armed = true; // the view changes
    }
    ImGui::PopItemWidth();
    hint("paint: left drag (shift/ctrl: erase, shrink)\n1-9, 0 kind, [ ] radius,\n"
         "shift+[ ] strength, x mirror, m mask\nctrl+z undo, ctrl+shift+z / ctrl+y redo");
    return armed;
}

/// The lobes seen from the side (x right, the strand's z up): each an ellipse of 2 sigma around
/// its offset, in its colour (brightened to be seen). A schematic, not a render: rotations and
/// extinction are not drawn.
void kernelSchematic(const nlohmann::json& lobes) {
    const float side = std::min(180.0f, ImGui::GetContentRegionAvail().x);
    const ImVec2 size(side, side);
    const ImVec2 origin = ImGui::GetCursorScreenPos();
    ImDrawList* draw = ImGui::GetWindowDrawList();
    draw->AddRectFilled(origin, ImVec2(origin.x + size.x, origin.y + size.y),
                        IM_COL32(10, 10, 14, 255));
    float extent = 1e-3f;
    for (const nlohmann::json& lobe : lobes) {
        const auto o = floats(lobe.value("offset", nlohmann::json()), {0, 0, 0});
        const auto s = floats(lobe.value("sigma", nlohmann::json()), {1, 1, 1});
        extent = std::max({extent, std::abs(o[0]) + 2 * s[0], std::abs(o[2]) + 2 * s[2]});
    }
    const float scale = 0.45f * size.x / extent;
    const ImVec2 centre(origin.x + 0.5f * size.x, origin.y + 0.5f * size.y);
    draw->AddLine(ImVec2(origin.x, centre.y), ImVec2(origin.x + size.x, centre.y),
                  IM_COL32(60, 60, 70, 255));
    for (const nlohmann::json& lobe : lobes) {
        const auto o = floats(lobe.value("offset", nlohmann::json()), {0, 0, 0});
        const auto s = floats(lobe.value("sigma", nlohmann::json()), {1, 1, 1});
        const auto c = floats(lobe.value("color", nlohmann::json()), {1, 1, 1});
        const float peak = std::max({c[0], c[1], c[2], 1e-3f});
        ImVec2 points[32];
        for (int i = 0; i < 32; ++i) {
            const float a = 6.2831853f * float(i) / 32.0f;
            points[i] = ImVec2(centre.x + scale * (o[0] + 2 * s[0] * std::cos(a)),
                               centre.y - scale * (o[2] + 2 * s[2] * std::sin(a)));
        }
        const ImU32 colour =
            ImGui::ColorConvertFloat4ToU32(ImVec4(c[0] / peak, c[1] / peak, c[2] / peak, 0.55f));
        draw->AddConvexPolyFilled(points, 32, colour);
    }
    ImGui::Dummy(size);
}

bool kernelPanel(edit::Session& session, SessionPanels& st) {
    bool changed = false;
    st.previewShown = false;
    if (!beginSection("Kernel", st))
        return false;
    // Room for the rendered preview, which the window draws there when all of it is in view
    // (the column's section list scrolls).
    const float size = float(SessionPanels::kPreviewSize);
    st.previewAt = ImGui::GetCursorScreenPos();
    ImGui::Dummy(ImVec2(size, size));
    ImGui::GetWindowDrawList()->AddRect(
        ImVec2(st.previewAt.x - 1.0f, st.previewAt.y - 1.0f),
        ImVec2(st.previewAt.x + size + 1.0f, st.previewAt.y + size + 1.0f),
        IM_COL32(120, 120, 140, 255));
    const ImVec2 lo = ImGui::GetWindowPos(), extent = ImGui::GetWindowSize();
    st.previewShown = st.previewAt.y >= lo.y && st.previewAt.y + size <= lo.y + extent.y &&
                      st.previewAt.x + size <= lo.x + extent.x;
    hint("rendered: one kernel on a plane, from the side");
    const nlohmann::json lobes = session.get("kernel.lobes");
    kernelSchematic(lobes);
    hint("schematic: 2 sigma around each offset, from the side");
    const int count = int(lobes.size());
    ImGui::PushItemWidth(-100.0f);
    for (int i = 0; i < count; ++i) {
        const nlohmann::json& lobe = lobes[std::size_t(i)];
        ImGui::PushID(i);
        if (ImGui::TreeNodeEx(cat("lobe ", i).c_str(),
                              i == 0 ? ImGuiTreeNodeFlags_DefaultOpen : 0)) {
            struct Property {
                const char* key;
                std::vector<float> fallback;
                float speed, lo, hi;
            };
            const Property properties[] = {{"offset", {0, 0, 0}, 0.01f, -10.0f, 10.0f},
                                           {"rotation_deg", {0, 0, 0}, 0.5f, -360.0f, 360.0f},
                                           {"sigma", {0.1f, 0.1f, 0.1f}, 0.002f, 1e-3f, 10.0f},
                                           {"extinction", {100.0f}, 5.0f, 0.0f, 1e5f}};
            for (const Property& p : properties) {
                std::vector<float> v = floats(lobe.value(p.key, nlohmann::json()), p.fallback);
                const bool commit =
                    heldEdit(st, cat(p.key, "##", i), v, [&](const char* l, float* d) {
                        if (v.size() == 3)
                            ImGui::DragFloat3(l, d, p.speed, p.lo, p.hi, "%.3f");
                        else
                            ImGui::DragFloat(l, d, p.speed, p.lo, p.hi, "%.1f");
                    });
                if (commit)
                    changed |= attempt(st, [&] { session.setLobe(i, p.key, toJson(v)); });
            }
            std::vector<float> c = floats(lobe.value("color", nlohmann::json()), {1, 1, 1});
            if (heldEdit(st, cat("colour##", i), c, [&](const char* l, float* d) {
                    ImGui::ColorEdit3(l, d,
                                      ImGuiColorEditFlags_Float | ImGuiColorEditFlags_NoPicker);
                }))
                changed |= attempt(st, [&] { session.setLobe(i, "color", toJson(c)); });
            if (count < noise::kMaxLobes && ImGui::Button("duplicate"))
                changed |= attempt(st, [&] { session.addLobe(i); });
            if (count > 1) {
                ImGui::SameLine();
                if (ImGui::Button("remove"))
                    changed |= attempt(st, [&] { session.removeLobe(i); });
            }
            ImGui::TreePop();
        }
        ImGui::PopID();
        if (changed) // the lobes changed under the loop
            break;
    }
    ImGui::PopItemWidth();
    return changed;
}

/// The clumps' parameters (presets/README.md "clump"): size, variation, shape, seed and the
/// per-impulse strength variation; the strength and relative size are painted (the clump and
/// clump-size brushes). A preset without a `clump` object gets one at the first change.
bool clumpPanel(edit::Session& session, SessionPanels& st) {
    bool changed = false;
    if (!beginSection("Clumps", st))
        return false;
    ImGui::PushItemWidth(kLabelWidth);
    const nlohmann::json c = session.get("clump");
    const auto setKey = [&](const std::string& key, const nlohmann::json& value) {
        if (c.is_object())
            session.set("clump." + key, value);
        else
            session.set("clump", nlohmann::json{{key, value}});
    };
    struct Slider {
        const char* key;
        float fallback, lo, hi;
        const char* format;
    };
    const Slider sliders[] = {{"size", 0.1f, 0.005f, 0.5f, "%.3f"},
                              {"variation", 0.3f, 0.0f, 1.0f, "%.2f"},
                              {"shape", 0.5f, 0.0f, 1.0f, "%.2f"}};
    for (const Slider& sl : sliders) {
        const nlohmann::json now = c.is_object() ? c.value(sl.key, nlohmann::json()) : nlohmann::json();
        std::vector<float> v = {now.is_number() ? now.get<float>() : sl.fallback};
        if (heldEdit(st, cat("clump ", sl.key), v, [&](const char* l, float* x) {
                ImGui::SliderFloat(l, x, sl.lo, sl.hi, sl.format);
            }))
            changed |= attempt(st, [&] { setKey(sl.key, double(v[0])); });
    }
    const nlohmann::json strength = session.get("fields.clump");
    if (strength.is_number()) {
        std::vector<float> v = {strength.get<float>()};
        if (heldEdit(st, "clump strength", v, [&](const char* l, float* x) {
                ImGui::SliderFloat(l, x, 0.0f, 1.0f, "%.2f");
            }))
            changed |= attempt(st, [&] { session.set("fields.clump", double(v[0])); });
    }
    const nlohmann::json var = session.get("variation.clump");
    std::vector<float> v = {var.is_number() ? var.get<float>() : 0.0f};
    if (heldEdit(st, "strength variation", v, [&](const char* l, float* x) {
            ImGui::SliderFloat(l, x, 0.0f, 0.99f, "%.2f");
        }))
        changed |= attempt(st, [&] {
            if (session.get("variation").is_object())
                session.set("variation.clump", double(v[0]));
            else
                session.set("variation", nlohmann::json{{"clump", double(v[0])}});
        });
    ImGui::PopItemWidth();
    hint("paint the strength with the clump brush (8), the size with clump-size (9); a mask (0, "
         "M shows it) limits any brush");
    return changed;
}

bool distributionPanel(edit::Session& session, SessionPanels& st) {
    bool changed = false;
    if (!beginSection("Distribution", st))
        return false;
    ImGui::PushItemWidth(kLabelWidth);
    const nlohmann::json d = session.get("distribution");
    int type = d.value("type", std::string("poisson")) == "jittered" ? 1 : 0;
    if (ImGui::Combo("type", &type, "poisson\0jittered\0"))
        changed |= attempt(
            st, [&] { session.set("distribution.type", type == 1 ? "jittered" : "poisson"); });
    struct Slider {
        std::string key;
        float fallback, lo, hi;
        const char* format;
    };
    std::vector<Slider> sliders = {{"distribution.density_max", 1000.0f, 10.0f, 50000.0f, "%.0f"}};
    if (type == 1)
        sliders.push_back({"distribution.jitter", 1.0f, 0.0f, 1.0f, "%.2f"});
    for (const char* key : {"tilt_deg", "spin_deg", "bend_deg"})
        sliders.push_back({cat("variation.", key), 0.0f, 0.0f, 180.0f, "%.1f"});
    for (const char* key : {"scale", "color"})
        sliders.push_back({cat("variation.", key), 0.0f, 0.0f, 1.0f, "%.2f"});
    for (const Slider& s : sliders) {
        const nlohmann::json now = session.get(s.key);
        std::vector<float> v = {now.is_number() ? now.get<float>() : s.fallback};
        const std::string label = s.key.substr(s.key.find('.') + 1);
        if (heldEdit(st, label, v, [&](const char* l, float* x) {
                ImGui::SliderFloat(l, x, s.lo, s.hi, s.format);
            }))
            changed |= attempt(st, [&] { session.set(s.key, double(v[0])); });
    }
    int seed = int(session.seed());
    ImGui::InputInt("seed", &seed);
    if (ImGui::IsItemDeactivatedAfterEdit() && seed >= 0)
        changed |= attempt(st, [&] { session.setSeed(std::uint32_t(seed)); });
    ImGui::PopItemWidth();
    return changed;
}

bool windPanel(edit::Session& session, SessionPanels& st) {
    bool changed = false;
    if (!beginSection("Wind", st))
        return false;
    ImGui::PushItemWidth(kLabelWidth);
    bool on = session.wind();
    bool edited = ImGui::Checkbox("wind (animates)", &on);
    edited |= ImGui::SliderFloat("amplitude deg", &st.windAmplitudeDeg, 0.0f, 80.0f, "%.0f");
    edited |= ImGui::SliderFloat("frequency Hz", &st.windFrequencyHz, 0.05f, 4.0f, "%.2f");
    if (edited) {
        session.setWind(on, st.windAmplitudeDeg, st.windFrequencyHz);
        changed = true;
    }
    ImGui::Text("time %.2f s", session.time());
    ImGui::PopItemWidth();
    return changed;
}

bool lightPanel(edit::Session& session, SessionPanels& st) {
    if (!beginSection("Light", st))
        return false;
    ImGui::PushItemWidth(kLabelWidth);
    bool changed = false;
    bool lit = session.lit();
    if (ImGui::Checkbox("lit (key light, sky, shadows)", &lit))
        changed |= attempt(st, [&] { session.setLit(lit); });
    if (session.lit()) {
        edit::Session::KeyLight k = session.keyLight();
        bool edited = ImGui::SliderFloat("azimuth deg", &k.azimuthDeg, -180.0f, 180.0f, "%.0f");
        edited |= ImGui::SliderFloat("elevation deg", &k.elevationDeg, -10.0f, 90.0f, "%.0f");
        edited |= ImGui::SliderFloat("intensity", &k.intensity, 0.0f, 10.0f, "%.2f");
        edited |= ImGui::Checkbox("shadows", &k.shadows);
        if (edited)
            changed |= attempt(st, [&] {
                session.setKeyLight(k.azimuthDeg, k.elevationDeg, k.intensity, k.shadows);
            });
        hint("the key light: drag azimuth and elevation to move it; a lit frame costs several "
             "unlit ones on a CPU device");
    }
    ImGui::PopItemWidth();
    return changed;
}

bool filePanel(edit::Session& session, SessionPanels& st) {
    bool changed = false;
    if (!beginSection("File", st))
        return false;
    ImGui::Text("%s", session.dirty() ? "* unsaved changes" : "saved (no changes)");
    char save[512], image[512];
    std::snprintf(save, sizeof save, "%s", st.savePath.c_str());
    std::snprintf(image, sizeof image, "%s", st.exportPath.c_str());
    ImGui::PushItemWidth(-80.0f);
    if (ImGui::InputText("##save", save, sizeof save))
        st.savePath = save;
    ImGui::SameLine();
    if (ImGui::Button("Save as"))
        saveSession(session, st);
    if (ImGui::InputText("##export", image, sizeof image))
        st.exportPath = image;
    ImGui::PopItemWidth();
    ImGui::SameLine();
    if (ImGui::Button("Export"))
        attempt(st, [&] {
            session.exportImage(st.exportPath);
            st.message = "wrote " + st.exportPath;
            st.messageIsError = false;
        });
    ImGui::BeginDisabled(!session.canUndo());
    if (ImGui::Button(cat("Undo (", session.undoSteps(), ")").c_str()))
        changed |= session.undo();
    ImGui::EndDisabled();
    ImGui::SameLine();
    ImGui::BeginDisabled(!session.canRedo());
    if (ImGui::Button(cat("Redo (", session.redoSteps(), ")").c_str()))
        changed |= session.redo();
    ImGui::EndDisabled();
    if (!st.message.empty()) {
        // Wrapped: a message is often wider than the column.
        ImGui::PushStyleColor(ImGuiCol_Text, st.messageIsError ? ImVec4(1.0f, 0.3f, 0.2f, 1.0f)
                                                               : ImVec4(0.6f, 0.9f, 0.6f, 1.0f));
        ImGui::TextWrapped("%s", st.message.c_str());
        ImGui::PopStyleColor();
    }
    return changed;
}

} // namespace

const std::vector<std::string>& sectionNames() {
    static const std::vector<std::string> names = {"render", "brush", "kernel", "distribution",
                                                   "clumps", "wind",  "file",   "stats"};
    return names;
}

void hint(const char* text) {
    ImGui::PushStyleColor(ImGuiCol_Text, ImGui::GetStyle().Colors[ImGuiCol_TextDisabled]);
    ImGui::TextWrapped("%s", text);
    ImGui::PopStyleColor();
}

bool beginSection(const char* title, const SessionPanels& state) {
    std::string name = title;
    for (char& c : name)
        c = char(std::tolower(static_cast<unsigned char>(c)));
    const bool open = std::find(state.openAtStart.begin(), state.openAtStart.end(), name) !=
                      state.openAtStart.end();
    ImGui::SetNextItemOpen(open, ImGuiCond_Once);
    return ImGui::CollapsingHeader(title);
}

bool timelinePanel(edit::Session& session, SessionPanels& st) {
    if (!session.animated())
        return false;
    const edit::Timeline line = session.timeline();
    if (ImGui::Button(st.playing ? "Pause" : "Play", ImVec2(60.0f, 0.0f)))
        st.playing = !st.playing;
    if (ImGui::IsItemHovered())
        ImGui::SetTooltip("play or pause: space; step a frame: left / right");
    ImGui::SameLine();
    bool loop = session.loop();
    if (ImGui::Checkbox("loop", &loop))
        session.setLoop(loop);
    ImGui::SameLine();
    ImGui::Text("t %.3f s  frame %ld", session.time(), session.frameNumber());
    // The scrub: the whole column's width, the clip's first key to its last.
    float t = float(session.time());
    ImGui::SetNextItemWidth(-1.0f);
    const bool scrubbed = ImGui::SliderFloat("##time", &t, float(line.start), float(line.end),
                                             "%.3f s", ImGuiSliderFlags_AlwaysClamp);
    if (ImGui::IsItemActivated())
        st.playing = false;
    if (scrubbed)
        attempt(st, [&] { session.setTime(double(t)); });
    hint(cat("frames ", line.frame(line.start), " to ", line.frame(line.end), " at ", line.fps,
             " fps")
             .c_str());
    ImGui::Separator();
    return scrubbed;
}

bool saveSession(edit::Session& session, SessionPanels& st) {
    return attempt(st, [&] {
        session.save(st.savePath);
        st.message = "wrote " + st.savePath;
        st.messageIsError = false;
    });
}

bool sessionPanels(edit::Session& session, SessionPanels& state) {
    bool changed = brushPanel(session, state);
    changed |= kernelPanel(session, state);
    changed |= distributionPanel(session, state);
    changed |= clumpPanel(session, state);
    changed |= windPanel(session, state);
    changed |= lightPanel(session, state);
    changed |= filePanel(session, state);
    return changed;
}

bool renderSettingsWidgets(const splat::MethodInfo& method, splat::RenderSettings& settings) {
    using splat::SettingType;
    bool changed = false;
    for (const splat::Setting* s : method.settings) {
        const char* label = s->name.c_str();
        const double top = s->panelMax > 0.0 ? s->panelMax : s->max;
        switch (s->type) {
        case SettingType::Toggle:
        case SettingType::Flag: {
            bool on = s->get(settings) != 0.0;
            if (ImGui::Checkbox(label, &on)) {
                s->set(settings, on ? 1.0 : 0.0);
                changed = true;
            }
            break;
        }
        case SettingType::Integer: {
            int v = int(s->get(settings));
            if (ImGui::SliderInt(label, &v, int(s->min), int(top))) {
                s->set(settings, double(v));
                changed = true;
            }
            break;
        }
        case SettingType::Number: {
            float v = float(s->get(settings));
            if (ImGui::SliderFloat(label, &v, float(s->min), float(top), "%.1f")) {
                s->set(settings, double(v));
                changed = true;
            }
            break;
        }
        case SettingType::Choice: {
            int v = int(s->get(settings));
            std::string items;
            for (const std::string& c : s->choices)
                items += c + '\0';
            if (ImGui::Combo(label, &v, items.c_str())) {
                s->set(settings, double(v));
                changed = true;
            }
            break;
        }
        case SettingType::File:
            ImGui::Text("%s: %s", label, s->text(settings).c_str());
            break;
        }
        if (ImGui::IsItemHovered())
            ImGui::SetTooltip("%s", s->help.c_str());
    }
    return changed;
}

} // namespace spot::editor
