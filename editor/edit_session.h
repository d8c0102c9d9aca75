/// @file edit_session.h
/// @brief The editor's document and its edits: a scene's mesh and camera, the preset (as JSON
/// and parsed), its painted grids, the impulse generator and the persistent GPU frame; strokes,
/// parameter edits, undo/redo, saving.
///
/// The window (or the script runner) drives it: pointer events become beginStroke / dragStroke /
/// endStroke in window pixels (top-left origin, noise/camera.h), panels call set() and the lobe
/// edits, and every frame calls render(). A stroke paints the slot's paint layer
/// (noise::PaintLayer), which lies over the slot's field (its base) and never replaces it: the
/// base's parameters stay editable (set "fields.density.base.frequency"). The dabs refresh the
/// generator's field data, so the next render() regenerates the impulses and shows them.
///
/// An animated scene (a glTF clip or a mesh cache, or the scene's wind; docs/design.md section 6)
/// has a time: the noise is generated on the mesh's rest pose, and every render() poses it at
/// time() on the GPU (splat::Frame::animate). A stroke paints at any time: the brush picks the
/// posed surface and writes the painted layers (which live in rest space, like everything that
/// defines the noise) at the rest-pose point of the same triangle and barycentrics, so the paint
/// stays on the skin.
///
/// Undo keeps at least kMinUndoSteps edits within a byte budget: a stroke stores per touched grid
/// a sparse delta (voxel, value and activity before and after), a parameter edit the JSON before
/// and after at its key path. Undo restores a bit-identical state (grids and preset).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "edit_brush.h"
#include "noise/animated_mesh.h"
#include "noise/bvh.h"
#include "noise/camera.h"
#include "noise/deform.h"
#include "noise/image.h"
#include "noise/impulses.h"
#include "noise/mesh.h"
#include "noise/painted.h"
#include "noise/preset.h"
#include "noise/scene.h"
#include "splat/context_vk.h"
#include "splat/frame_vk.h"
#include "splat/method_vk.h"

namespace spot::edit {

inline constexpr std::size_t kMinUndoSteps = 100;

struct SessionOptions {
    int width = 0, height = 0;    ///< window size in pixels; 0: the scene's image size
    std::filesystem::path preset; ///< override the scene's preset (empty: the scene's)
    float voxelScale = 0.25f;     ///< painted voxel size as a fraction of the cell size
    std::size_t undoSteps = 256;  ///< at most this many edits are kept (>= kMinUndoSteps)
    std::size_t undoBytes = std::size_t(256) << 20; ///< ... and at most this many bytes beyond
                                                    ///< the last kMinUndoSteps
    splat::ContextOptions context = splat::contextOptionsFromEnvironment();
    /// Arm the default brush's slot when the session starts (Session::armBrush).
    bool armBrush = true;
};

/// Where a window pixel's ray meets the mesh as shown (posed at the session's time when the
/// mesh is animated), and the same surface point at rest (where the painted layers are written).
struct Hit {
    glm::vec3 position{0.0f}; ///< world units, as shown
    glm::vec3 normal{0.0f};   ///< interpolated, unit, as shown
    double distance = 0.0;    ///< along the ray, world units
    std::uint32_t triangle = 0;
    glm::dvec3 barycentric{1.0, 0.0, 0.0}; ///< of `triangle` (the same at rest and posed)
    glm::vec3 restPosition{0.0f};          ///< the point at rest (equals position when static)
    glm::vec3 restNormal{0.0f};            ///< its normal at rest
};

/// The span the timeline scrubs over, seconds, and its frame rate.
struct Timeline {
    double start = 0.0, end = 0.0; ///< a clip's first and last key (see kNoClipSeconds)
    double fps = 24.0;             ///< the scene's animation.fps
    /// A mesh that does not move (a scene with wind only) has no clip: its timeline spans
    /// [0, this many seconds], or to the time when playback went past it.
    static constexpr double kNoClipSeconds = 10.0;
    /// The frame number of time t (t x fps, rounded).
    long frame(double t) const;
};

/// What an edit cost: milliseconds spent rebuilding, and what was rebuilt.
struct EditCost {
    double milliseconds = 0.0;
    bool generatorRebuilt = false; ///< a new ImpulseGenerator and Frame (kernel, distribution,...)
    bool fieldsRefreshed = false;  ///< only the fields' data re-flattened and re-uploaded
    std::size_t voxelsWritten = 0; ///< strokes
    std::size_t dabs = 0;          ///< strokes
    bool armed = false;            ///< a slot was armed (Session::armBrush)
};

class Session {
public:
    /// Loads the scene (mesh, preset, camera, look), builds the generator, the Vulkan context
    /// and the frame. Throws InputError for anything the files get wrong.
    Session(const std::filesystem::path& scene, const SessionOptions& options = {});
    ~Session();
    Session(const Session&) = delete;
    Session& operator=(const Session&) = delete;

    // --- view -------------------------------------------------------------------------------
    const noise::Camera& camera() const { return m_camera; }
    /// Keeps the window size unless `camera` carries another one (a resize).
    void setCamera(const noise::Camera& camera);
    /// `method` from the registry (splat::gpuMethods()); InputError otherwise.
    void setMethod(const std::string& method, const splat::RenderSettings& settings);
    const std::string& method() const { return m_method; }
    const splat::RenderSettings& settings() const { return m_settings; }
    /// One frame through splat::Frame::render; `out` receives the pixels when given.
    splat::FrameStats render(noise::Image* out = nullptr);
    /// Render and write the view (.png or .exr, noise::writeImage); the metadata names the
    /// method, the scene and, for an animated scene, the time (seconds) and the frame number.
    void exportImage(const std::filesystem::path& file);

    // --- picking and strokes ------------------------------------------------------------------
    /// The closest mesh hit of the ray through window pixel (x, y), top-left origin.
    std::optional<Hit> pick(glm::vec2 pixel) const;
    /// The brush. Changing its kind (or smooth target) through this reference does not arm its
    /// slot: call armBrush() after, or use setBrush / setBrushKind.
    BrushSettings& brush() { return m_brush; }
    const BrushSettings& brush() const { return m_brush; }
    /// Replace the brush, or only its kind, and arm its slot (armBrush).
    EditCost setBrush(const BrushSettings& brush);
    EditCost setBrushKind(BrushKind kind);
    /// Arm the slot the brush paints, so that its first stroke neither creates a layer nor
    /// compiles a pipeline: when the slot has no paint layer yet, create the empty layer the
    /// first stroke would create and compile the generation pipeline for the layered field
    /// (GpuGenerator::prepareFieldKind; a later rebuild, e.g. a parameter edit, drops it). The
    /// first stroke then binds the layer (ImpulseGenerator::setField: every impulse generated
    /// again, no new generator or frame); an empty layer gives its base bit for bit, so the
    /// impulses outside the stroke never move. Only the current brush's slot stays armed. Not an
    /// edit: the document, dirty() and the undo history are unchanged, and save() writes the
    /// slot's field as it was; undoing the first stroke arms the slot again when it is still the
    /// brush's. A change of the slot's field (set, undo) disarms it. Returns the cost (armed:
    /// false when the slot was painted or already armed).
    EditCost armBrush();
    /// The layer made for `slot` by arming, or null.
    const noise::PaintLayer* armedLayer(Slot slot) const { return m_armed[int(slot)].layer.get(); }
    /// What arming the default brush cost when the session started.
    const EditCost& startArmCost() const { return m_startArmCost; }
    /// Pointer pressed / moved / released. Dabs are spaced radius/4 pixels along the drag; each
    /// drag event's dabs are visible in the next render(). endStroke records the undo step.
    EditCost beginStroke(glm::vec2 pixel, bool invert = false);
    EditCost dragStroke(glm::vec2 pixel);
    EditCost endStroke();
    bool stroking() const { return m_stroke != nullptr; }
    /// One pointer event of the window (its left button): takes the event's view as the camera,
    /// then begins, continues or ends the stroke. `invert` (a modifier held at the press) inverts
    /// the brush for the whole stroke: density-add erases and density-erase adds, length
    /// shrinks, tilt lifts; comb, colour and smooth are unchanged.
    enum class PointerPhase { Press, Drag, Release };
    EditCost pointer(PointerPhase phase, glm::vec2 pixel, const noise::Camera& view,
                     bool invert = false);
    /// A whole stroke through `points` (the script's `stroke`).
    EditCost stroke(const std::vector<glm::vec2>& points);

    // --- parameters ---------------------------------------------------------------------------
    /// Set any preset key path ("distribution.density_max", "kernel.lobes.0.sigma") to a JSON
    /// value; checked by parsing the whole preset (InputError with the path, state unchanged).
    /// Rebuilds the generator and the frame.
    EditCost set(const std::string& keyPath, const nlohmann::json& value);
    /// Several key paths as one undo step (a panel's slider drag ends in one of these).
    EditCost set(const std::vector<std::pair<std::string, nlohmann::json>>& changes);
    /// The JSON at a key path (null when absent).
    nlohmann::json get(const std::string& keyPath) const;
    /// Lobe edits: `what` is offset, rotation_deg, sigma, extinction or color.
    EditCost setLobe(int lobe, const std::string& what, const nlohmann::json& value);
    /// Append a copy of lobe `copyOf` (at most noise::kMaxLobes), or remove one (at least 1).
    EditCost addLobe(int copyOf);
    EditCost removeLobe(int lobe);

    /// The impulse seed (the scene's, not the preset's): rebuilds the generator and the frame.
    /// Not an undo step; save writes the preset, which holds no seed.
    EditCost setSeed(std::uint32_t seed);
    std::uint32_t seed() const { return m_scene.seed; }

    // --- time (an animated scene) -------------------------------------------------------------
    /// Whether the scene moves: its mesh is a clip or a cache, or the scene has wind.
    bool animated() const { return m_frame && m_frame->animated(); }
    const noise::AnimatedMesh& animation() const { return m_animation; }
    Timeline timeline() const;
    /// Loop playback (advance): on by default.
    void setLoop(bool loop) { m_loop = loop; }
    bool loop() const { return m_loop; }
    /// Move the time by `seconds` (playback): past a clip's end it wraps to its start when
    /// looping, else it stops at the end (without a clip it runs on). Returns false when it
    /// stopped there.
    bool advance(double seconds);
    /// The frame number of the time (time() x fps, rounded).
    long frameNumber() const { return timeline().frame(m_time); }

    /// Wind: while on, render() bends the comb directions by a travelling wave, the comb
    /// offset by tan(amplitude) sin(2 pi (f t - x / wavelength)) along world +x (then projected
    /// on the tangent plane by the generator), on the voxels near the surface. Deterministic for
    /// a time `t` (seconds, setTime). Not part of the document: turning it off restores the
    /// document's comb; saving writes the document's comb.
    void setWind(bool on, float amplitudeDeg = 20.0f, float frequencyHz = 0.5f);
    bool wind() const { return m_windOn; }
    /// The mask overlay: while on, the impulses are drawn tinted towards red by the mask (the
    /// `mask` slot: its field and paint) at their anchors. A view, not an edit: the document,
    /// dirty() and the undo history are unchanged, and saving writes the impulses' own colours.
    void setMaskOverlay(bool on);
    bool maskOverlay() const { return m_maskOverlay; }
    /// Lighting as the frames show it (docs/design.md section 9): lit shows the scene's lights
    /// and sky, or, where the scene has none, a key light from the upper left with shadows and a
    /// pale sky; unlit shows the scene's colours as they are. Not an edit: the document is the
    /// preset, and the scene file keeps its shading. Throws InputError when the method cannot
    /// render lit scenes (MethodInfo::rendersLit; the frame is left unlit).
    void setLit(bool lit);
    bool lit() const { return m_scene.shading.mode == noise::Shading::Mode::Lit; }
    /// The key light (the first light; a lit session has one): its direction as azimuth about
    /// +y from +z and elevation above the horizon (degrees), its intensity and its shadows.
    void setKeyLight(float azimuthDeg, float elevationDeg, float intensity, bool shadows);
    /// Turn the key light by `dAzimuthDeg` about +y and `dElevationDeg` up (the elevation kept
    /// within [-89, 89]), its intensity and shadows as they are: the viewport's right drag. An
    /// unlit session turns lit first (setLit). Not an edit of the document.
    void turnKeyLight(float dAzimuthDeg, float dElevationDeg);
    struct KeyLight {
        float azimuthDeg = 0.0f, elevationDeg = 0.0f, intensity = 0.0f;
        bool shadows = false;
    };
    /// The key light now (zeros when the session has no light).
    KeyLight keyLight() const;
    /// The time, seconds: the pose of an animated mesh (clamped to its clip: a time outside it
    /// is stored clamped), the scene's wind's and the comb wind's. Not an edit.
    void setTime(double seconds);
    double time() const { return m_time; }

    // --- undo ---------------------------------------------------------------------------------
    bool canUndo() const { return !m_undo.empty(); }
    bool canRedo() const { return !m_redo.empty(); }
    /// Returns false when there was nothing to undo / redo.
    bool undo(EditCost* cost = nullptr);
    bool redo(EditCost* cost = nullptr);
    std::size_t undoSteps() const { return m_undo.size(); }
    std::size_t redoSteps() const { return m_redo.size(); }
    std::size_t undoBytes() const;

    // --- document -----------------------------------------------------------------------------
    /// The preset as JSON; a painted slot reads {"base": field, "paint": {"file", "grid"}}.
    const nlohmann::json& presetJson() const { return m_presetJson; }
    const noise::PresetDesc& preset() const { return m_preset; }
    const noise::SceneDesc& scene() const { return m_scene; }
    /// The mesh at rest (what the noise is generated on and painted in).
    const noise::Mesh& mesh() const { return m_mesh; }
    /// The mesh as shown at time(): posed on the CPU (the pose the brush picks) when it moves,
    /// else the rest.
    const noise::Mesh& shownMesh() const;
    const noise::ImpulseGenerator& generator() const { return *m_generator; }
    splat::Frame& frame() { return *m_frame; }
    splat::Context& context() { return *m_ctx; }
    /// The paint layer of `slot`, or null when the slot is not painted.
    const noise::PaintLayer* layer(Slot slot) const;
    /// Its value grid (the density's multiplier), or null.
    const noise::PaintedGrid* grid(Slot slot) const;
    /// Voxel size of grids created from now on, world units.
    float voxelSize() const;
    /// Unsaved changes since the load or the last save.
    bool dirty() const { return m_current != m_saved; }
    /// Write the preset to `file` and its paint layers (and the grids of painted base fields) to
    /// `file` with the extension .vdb (both atomically, the grids first). Loading `file` back
    /// gives the same impulses.
    void save(const std::filesystem::path& file);
    /// Paint layers plus the undo history, bytes.
    std::size_t memoryBytes() const;

private:
    struct JsonChange {
        nlohmann::json::json_pointer path;
        std::optional<nlohmann::json> before, after; ///< absent: the key does not exist
    };
    struct Edit {
        std::uint64_t id = 0;
        std::vector<JsonChange> json;
        std::vector<std::pair<Slot, GridDelta>> grids;
        /// Layers a stroke created (before: the slot's layer until then, usually null).
        std::vector<std::tuple<Slot, std::shared_ptr<noise::PaintLayer>,
                               std::shared_ptr<noise::PaintLayer>>>
            created;
        std::size_t bytes() const;
    };

    /// The layer a slot without paint was armed with (armBrush) and the slot's JSON when it was
    /// armed (a change of it disarms).
    struct Armed {
        std::shared_ptr<noise::PaintLayer> layer;
        nlohmann::json field;
    };

    void rebuild();
    /// m_preset from m_presetJson, with the paint layers attached.
    noise::PresetDesc parseDocument(const nlohmann::json& json) const;
    nlohmann::json slotJson(Slot slot) const;
    /// The empty layer a first stroke on `slot` starts from (see armBrush).
    std::shared_ptr<noise::PaintLayer> startLayer(Slot slot) const;
    /// The generator's kind of `slot`'s field with a layer (SpotField.kind.x, for the pipeline).
    std::int32_t layeredKind(Slot slot) const;
    /// The component count the slot's field has in the shared parameters once layered: its
    /// base's (constants, gradients and noise carry 3 whatever the slot's count), so that the
    /// pipeline armBrush prepares is the one the first stroke asks for.
    std::int32_t layeredComponents(Slot slot) const;
    /// After voxels of grids changed in place: the CPU generator re-flattens its fields, and
    /// the frame regenerates only the cells whose impulses read the voxels `changed` (world
    /// positions of voxels of size `voxelSize`), or every cell when `changed` is null.
    void refreshFields(const std::vector<glm::vec3>* changed = nullptr, float voxelSize = 0.0f);
    bool painted(Slot slot) const;
    noise::FieldDesc* slotDesc(Slot slot);
    /// `slot`'s JSON with a layer over its field.
    nlohmann::json layeredJson(Slot slot) const;
    /// Make `slot` painted for a stroke; true when that rebuilt the generator (not armed).
    bool ensurePainted(Slot slot, Edit& edit);
    void applyJson(const std::vector<JsonChange>& changes, bool after);
    void push(Edit edit);
    void dab(glm::vec2 pixel, glm::vec2 dragPixels);
    void refreshEvent();
    /// The brush as the current stroke applies it (m_strokeInvert).
    BrushSettings strokeBrush() const;
    void refreshDeltas(const Edit& edit);
    glm::vec3 screenToWorld(glm::vec2 dragPixels) const;
    /// The voxels of the current voxel size near the whole surface.
    const std::vector<SurfaceVoxel>& surfaceVoxels();
    /// `slot`'s current field (or the surface tangent for an unset comb) at the surface voxels.
    std::vector<glm::vec3> sampleSlot(Slot slot);
    void applyWind();
    /// The CPU pose at the session's time and its BVH, for picking (an animated mesh only;
    /// posed when the time changed since the last pick).
    void poseForPick() const;

    noise::SceneDesc m_scene;
    noise::Shading m_sceneShading; ///< the scene file's, what setLit(false) restores
    noise::AnimatedMesh m_animation; ///< the scene's mesh; the frame poses it (outlives m_frame)
    noise::Mesh m_mesh;              ///< its rest pose
    noise::Camera m_camera;
    std::filesystem::path m_presetFile;
    std::string m_vdbName; ///< file name the painted fields reference
    nlohmann::json m_presetJson;
    noise::PresetDesc m_preset;
    std::array<std::shared_ptr<noise::PaintLayer>, kSlotCount> m_layers;
    std::array<Armed, kSlotCount> m_armed;
    EditCost m_startArmCost;
    float m_voxelScale = 0.25f;

    std::unique_ptr<splat::Context> m_ctx;
    std::unique_ptr<noise::ImpulseGenerator> m_generator;
    std::unique_ptr<splat::Frame> m_frame;
    std::string m_method = "hybrid";
    splat::RenderSettings m_settings;

    noise::Bvh m_bvh;
    std::unique_ptr<SurfaceIndex> m_surface;
    BrushSettings m_brush;
    std::unique_ptr<Edit> m_stroke;
    glm::vec2 m_strokeLast{0.0f};
    float m_strokeCarry = 0.0f; ///< pixels travelled since the last dab
    std::size_t m_strokeDabs = 0, m_strokeVoxels = 0;
    bool m_strokeInvert = false;
    std::vector<glm::ivec3> m_eventVoxels; ///< written by the current pointer event's dabs
    std::unique_ptr<noise::Field> m_strokeBase; ///< the stroke's slot's field without its layer
    std::unique_ptr<noise::Field> m_strokeMask; ///< the mask a limited stroke reads (else null)
    bool m_maskOverlay = false;

    std::deque<Edit> m_undo;
    std::vector<Edit> m_redo;
    std::size_t m_undoSteps, m_undoBytes;
    std::uint64_t m_nextId = 1, m_current = 0, m_saved = 0;

    bool m_windOn = false;
    float m_windAmplitudeDeg = 20.0f, m_windFrequencyHz = 0.5f;
    double m_time = 0.0;
    bool m_loop = true;
    /// The pose the brush picks at (an animated mesh): the deformer and its BVH, at m_posedAt.
    mutable std::unique_ptr<noise::Deformer> m_deformer;
    mutable noise::Bvh m_posedBvh;
    mutable std::optional<double> m_posedAt;
    std::vector<SurfaceVoxel> m_surfaceVoxels; ///< cache of surfaceVoxels()
    float m_surfaceVoxelSize = 0.0f;           ///< ... for this voxel size
    std::vector<glm::vec3> m_windBase;         ///< the document's comb at the surface voxels
};

/// The process's peak resident memory, bytes (getrusage).
std::uint64_t peakResidentBytes();

/// "a.b.0.c" as a JSON pointer; InputError for an empty component.
nlohmann::json::json_pointer keyPathPointer(const std::string& keyPath);

} // namespace spot::edit
