/// @file edit_script.h
/// @brief The editor's scripts: one action per line, what a user's session does, replayed without
/// a window (`spotshell edit --script FILE`). Window coordinates are pixels from the top left.
///
///     camera eye X Y Z target X Y Z [fov DEG]
///     method NAME [key value ...]        # keys of `render`: steps, supersample, ewa, lod, ...;
///                                        # the settings not given stay as they were (the
///                                        # command line's: `method baked` keeps --bake)
///     brush KIND [radius PX] [strength S] [falloff smooth|linear|constant] [mirror x]
///                [color R G B] [raise] [backfaces] [target SLOT] [limit none|masked|unmasked]
///                # KIND: density-add, density-erase, comb, tilt, length, color, smooth, clump,
///                # clump-size, mask; target (smooth): density, comb, tilt, length, color,
///                # clump, clump-size or mask; raise (density-add): above the field's own
///                # density, towards 1; limit: paint only where the mask is set, or is not
///     mask overlay on|off                # tint the impulses by the mask (a view)
///     stroke X,Y X,Y ...                 # a drag through these window points (clipped to the
///                                        # window grown by the brush radius)
///     set fields.density.base.frequency 6   # a painted slot's field stays editable under it
///     undo | redo
///     lobe I offset X Y Z | rotation X Y Z | sigma X Y Z | extinction A | color R G B
///     lobe add I | lobe remove I
///     set KEY.PATH JSON                  # any preset key path
///     seed N                             # the impulse seed
///     wind on|off [amplitude DEG] [frequency HZ]   # animate the comb (Session::setWind)
///     frames N                           # render N frames, 1/30 s apart
///     time T                             # the time, seconds (an animated scene: its pose;
///                                        # clamped to the clip)
///     play N [loop on|off]               # N frames at the scene's fps, each rendered: the
///                                        # timeline's playback (it loops at the clip's end
///                                        # unless `loop off`, which stops there; without a
///                                        # clip the time runs on)
///     save FILE.json                     # the preset, with its .vdb grids beside it
///     screenshot FILE.png|FILE.exr
///
/// `#` starts a comment. The whole script is parsed first; a bad line throws InputError
/// "script FILE:LINE: message (the line: TEXT)" before anything runs or is written. An error
/// while the script runs names its line the same way.
#pragma once

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <glm/glm.hpp>
#include <nlohmann/json.hpp>

#include "edit_brush.h"
#include "splat/method_vk.h"

namespace spot::edit {

class Session;

struct ScriptAction {
    enum class Type {
        Camera,
        Method,
        Brush,
        Stroke,
        Undo,
        Redo,
        Lobe,
        Set,
        Seed,
        Wind,
        Light,
        Mask,
        Frames,
        Time,
        Play,
        Save,
        Screenshot
    };
    Type type = Type::Frames;
    int line = 0;
    std::string text; ///< the line, for the log

    glm::dvec3 eye{0.0}, target{0.0}; ///< Camera
    std::optional<double> fovDeg;     ///< Camera
    std::string name;               ///< Method: method; Lobe: property or add/remove; Set: key path
    /// Method: the settings the line gives (on the defaults), and which they are: only these
    /// change the session's settings.
    splat::RenderSettings settings;
    std::vector<const splat::Setting*> given;
    BrushSettings brush;            ///< Brush
    std::vector<glm::vec2> points;  ///< Stroke
    int index = 0;                  ///< Lobe
    nlohmann::json value;           ///< Lobe, Set
    int count = 0;                  ///< Frames, Play
    double seconds = 0.0;           ///< Time
    std::optional<bool> loop;       ///< Play: loop on or off (none: the session's)
    std::uint32_t seed = 0;         ///< Seed
    bool on = false;                ///< Wind, Light, Mask (the overlay)
    /// Light: the key light's azimuth, elevation (degrees), intensity and shadows, where given.
    std::optional<float> azimuthDeg, elevationDeg, intensity;
    std::optional<bool> shadows;
    float amplitudeDeg = 20.0f, frequencyHz = 0.5f; ///< Wind
    std::filesystem::path file;                     ///< Save, Screenshot
};

/// "script NAME:LINE: message (the line: TEXT)": an error caused by `action`'s line.
std::string scriptLineError(const std::string& name, const ScriptAction& action,
                            const std::string& message);
/// The settings a `method` action leaves on a session whose settings are `current`: the
/// current ones with those the line gives.
splat::RenderSettings methodSettings(const ScriptAction& action,
                                     const splat::RenderSettings& current);

/// Parse a script's text; `name` (the file) is used in messages. Throws InputError
/// "script NAME:LINE: message" for the first bad line.
std::vector<ScriptAction> parseScript(std::string_view text, const std::string& name);
/// Read (size-capped) and parse a script file.
std::vector<ScriptAction> loadScript(const std::filesystem::path& file);

/// What a run measured.
struct ScriptReport {
    int strokes = 0, frames = 0;         ///< frames: of `frames` and `play`
    double strokeMs = 0.0;               ///< summed dab + field refresh time of the strokes
    double paramMs = 0.0;                ///< summed rebuild time of set / lobe / undo / redo
    std::vector<double> strokeToFrameMs; ///< per stroke: last drag event to its frame's pixels
    std::vector<double> eventMs;    ///< per stroke: the last drag event's dabs and field refresh
    std::vector<double> frameMs;    ///< per stroke: the frame after it (host wall time)
    std::vector<double> generateMs; ///< per stroke: that frame's impulse regeneration (GPU)
    /// per `brush` line that armed or disarmed a slot (Session::armBrush): the arming, and the
    /// frame after it when it rebuilt the frame (else 0)
    std::vector<double> armMs, armFrameMs;
};

/// Run the actions on `session`, printing one line per action to `log` (null: silent; the
/// action's whole line, then what it did). Errors carry the line, as scriptLineError writes it.
ScriptReport runScript(Session& session, const std::vector<ScriptAction>& actions,
                       const std::string& name, std::FILE* log);
/// One action of a script (what runScript does per line), adding to `report`. The window
/// replays a script through this, one action between two frames (its strokes it replays as
/// pointer events instead, one per frame).
void runScriptAction(Session& session, const ScriptAction& action, const std::string& name,
                     std::FILE* log, ScriptReport& report);

} // namespace spot::edit
