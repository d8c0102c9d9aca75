/// @file settings.h
/// @brief Every method's settings (RenderSettings) and their descriptors: each setting described
/// once (name, type, range, default, help) for the command line (editor/render_options.h), the
/// script's `method` verb, the editor's Render panel and the bench. Which methods take a setting
/// is the registry's to say (method_vk.h, MethodInfo::settings).
///
/// No Vulkan here: the descriptors only read and write RenderSettings.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "noise/image.h"

namespace spot::splat {

class BakeData;

/// How `hybrid` finds each pixel's closest kernel (docs/design.md section 4: "measure both
/// ways"). Both find the same kernel, so the images are identical; only the cost differs.
enum class ClosestKernel {
    Atomic,   ///< in the OIT pass itself: a 64-bit atomicMin of (distance bits, kernel index)
    DepthPass ///< a separate pass over the same quads with a depth test (splat_closest.frag)
};
enum class OitWeight {
    Constant,     ///< w = 1: a plain unordered blend ("no OIT", paper fig. 3.3)
    McGuireBavoil ///< MB13 eq. 7 with z = view depth in world units (see spotOitWeight)
};

/// RenderSettings::smallPixels's default: kSplatSmallPixels (shaders/spot_splat.h; the splatting
/// methods hold them equal).
inline constexpr int kDefaultSmallPixels = 36;

/// Every method's settings, flat: a method reads the ones it takes (MethodInfo::settings) and
/// ignores the others. Defaults here are the only ones: the descriptors read them.
struct RenderSettings {
    // Splatting (instanced, oit, hybrid, sorted).
    bool ewa = true;       ///< widen lobes by the pixel footprint (anti-aliasing)
    int kernelSamples = 0; ///< 0: analytic optical depths; N in [1, 2048]: paper eq. 10's N_s
    OitWeight weight = OitWeight::McGuireBavoil;   ///< oit, hybrid
    ClosestKernel closest = ClosestKernel::Atomic; ///< hybrid
    /// oit, hybrid (atomic), instanced: a kernel whose quad's pixel box holds at most this many
    /// pixel centres is evaluated by a compute pass instead of drawn (lavapipe's cost per
    /// primitive dwarfs the few fragments of such a quad), and so is a thin quad (at most 3
    /// pixels wide) whose box holds at most kSplatMaxSmallPixels (lavapipe shades a quad in 4x4
    /// blocks, few of whose lanes a thin one fills: docs/design.md section 4); 0: every kernel is
    /// drawn. In [0, kSplatMaxSmallPixels]; the default is kSplatSmallPixels
    /// (shaders/spot_splat.h). oit and hybrid draw every kernel in frames over about 1830^2 pixels
    /// (their fixed-point sums, 40 bytes a pixel, would not fit one 128 MiB storage buffer
    /// binding).
    int smallPixels = kDefaultSmallPixels;
    /// The roofline instead of the method's splat pass: the same quads over the same pixels into
    /// the `oit` targets with a fragment shader that does nothing (the image is meaningless; the
    /// splat pass time is what lavapipe's rasterizer itself costs for this frame).
    bool roofline = false;
    /// Count the fragments each splat pass shades and the pixels where a kernel's alpha reaches
    /// 1/255 (FrameCounters); costs atomics in the fragment shader, so off unless measuring.
    bool countFragments = false;

    // Impulse generation (every GPU method).
    double lodPixels = 0.0; ///< thin the kernels of cells smaller than this on screen (0: off)

    // Ray-march.
    int steps = 32;      ///< samples along each ray through the shell, [1, 4096]
    int supersample = 1; ///< n x n rays per pixel, box-filtered, [1, 8]
    /// Largest loop bound one march dispatch may reach (methods/raymarch/raymarch_vk.h); tests raise it past
    /// lavapipe's 65,535 to show what the guard prevents. 0: the default budget.
    std::uint32_t loopBudget = 0;
    bool cullImpulses = true; ///< skip impulses whose box misses the sample (exact)

    // Baked (methods/baked/).
    /// The bake the method renders: read once from its file (loadBake), shared by every frame
    /// and renderer that is handed it; a frame reads no file.
    std::shared_ptr<const BakeData> bake;
    int peelPasses = 4; ///< depth-peeling layers of tetrahedra, [1, kBakedMaxPeelPasses]
    /// Render a bake whose recorded mesh hash is not the scene's (else InputError).
    bool allowMismatch = false;

    // Every method (not a descriptor: render's --tile and --crop set it).
    /// A tile: only these pixels of the camera's image are wanted, each the same as in the whole
    /// image; empty: the whole image. The GPU methods render the whole view with the raster
    /// passes scissored to it (PixelScissor) and read back the window alone (Frame::render).
    noise::PixelRect window;

    // The CPU reference (noise/reference.h).
    int spp = 0;            ///< samples per pixel; 0: the scene's (SceneDesc::referenceSpp)
    double stepScale = 1.0; ///< quadrature step multiplier
};

/// What kind of value a setting holds, and so how it is written on the command line and shown.
enum class SettingType {
    Toggle,  ///< on | off
    Flag,    ///< present or not (command line: `--name`; script: `name on|off`)
    Integer, ///< in [min, max]
    Number,  ///< in [min, max]
    Choice,  ///< one of `choices`, stored as its index
    File     ///< a path, read into a resource when parsed (the bake)
};

/// One setting, described once. Its name is the command-line option (`--name`), the script's
/// key and, with '-' as '_', the key in `--stats` and the bench's rows.
struct Setting {
    std::string name;
    SettingType type = SettingType::Integer;
    std::string value; ///< the value's placeholder in --help ("N", "on|off", "FILE")
    std::string help;  ///< what it does; the methods that take it and the default are added
    double min = 0.0, max = 0.0;      ///< Integer, Number
    std::vector<std::string> choices; ///< Choice: the names, in the stored index's order
    double panelMax =
        0.0; ///< the editor's slider ends here (0: at max; the command line takes max)
    /// Shown as the default instead of the value of RenderSettings{} (a default that is not a
    /// value: "the scene's").
    std::string defaultText;
    /// The value as a number (Toggle and Flag: 0 or 1; Choice: the index). Not for File.
    std::function<double(const RenderSettings&)> get;
    std::function<void(RenderSettings&, double)> set;
    /// File: the path it was read from ("" when none), and reading the file into `settings`.
    std::function<std::string(const RenderSettings&)> getText;
    std::function<void(RenderSettings&, const std::string&)> setText;

    /// The JSON key: the name with '-' as '_'.
    std::string key() const;
    /// The value in `s` as the command line writes it ("on", "32", "mcguire-bavoil", a path).
    std::string text(const RenderSettings& s) const;
    /// The default as the command line writes it.
    std::string defaultValue() const;
    /// Parse `text` (as the command line writes it) into `s`; InputError naming `--name` and the
    /// range for a bad value.
    void parse(RenderSettings& s, const std::string& text) const;
};

/// The settings, one each; the registry's methods point at these.
namespace settings {
extern const Setting kernelSamples, ewa, weight, closest, smallPixels, countFragments, lod, steps,
    supersample, bake, peelPasses, allowMismatch, spp, stepScale;
}

} // namespace spot::splat
