#include "edit_session.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <optional>
#include <utility>

#include <sys/resource.h>

#include "noise/error.h"
#include "noise/field.h"
#include "noise/generator_shared.h"
#include "noise/surface.h"
#include "noise/system.h"
#include "splat/passes/light_space_vk.h"

namespace spot::edit {

namespace {

using Clock = std::chrono::steady_clock;

double msSince(Clock::time_point start) {
    return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

bool paintedIn(const nlohmann::json& preset, Slot slot) {
    const auto ptr = keyPathPointer(std::string("fields.") + slotKey(slot));
    if (!preset.contains(ptr))
        return false;
    const nlohmann::json& j = preset.at(ptr);
    return j.is_object() && j.contains("paint");
}

using Generator = shared::f32::SharedGenerator;

/// The value grid's name of `slot`'s layer in the .vdb file (its weight grid adds ".weight"):
/// distinct from the names of painted base fields (the slot's key).
std::string layerGrid(Slot slot) {
    return cat(slotKey(slot), ".paint");
}

noise::PaintMode paintMode(Slot slot) {
    return slot == Slot::Density ? noise::PaintMode::Density : noise::PaintMode::Override;
}

/// The part of the segment from -> to inside the window grown by `margin` pixels.
struct ClippedSegment {
    bool inside = false;
    glm::vec2 from{0.0f}, to{0.0f};
    bool startClipped = false, endClipped = false;
};

ClippedSegment clipSegment(glm::vec2 from, glm::vec2 to, glm::dvec2 lo, glm::dvec2 hi) {
    // Liang-Barsky in double: the parameters where the segment enters and leaves the box.
    const glm::dvec2 a(from), d = glm::dvec2(to) - a;
    double t0 = 0.0, t1 = 1.0;
    for (int axis = 0; axis < 2; ++axis) {
        const double p[2] = {-d[axis], d[axis]};
        const double q[2] = {a[axis] - lo[axis], hi[axis] - a[axis]};
        for (int k = 0; k < 2; ++k) {
            if (p[k] == 0.0) {
                if (q[k] < 0.0)
                    return {};
                continue;
            }
            const double t = q[k] / p[k];
            if (p[k] < 0.0)
                t0 = std::max(t0, t);
            else
                t1 = std::min(t1, t);
        }
    }
    if (t0 > t1)
        return {};
    ClippedSegment c;
    c.inside = true;
    c.startClipped = t0 > 0.0;
    c.endClipped = t1 < 1.0;
    c.from = c.startClipped ? glm::vec2(a + d * t0) : from;
    c.to = c.endClipped ? glm::vec2(a + d * t1) : to;
    return c;
}

glm::vec3 mirrorX(glm::vec3 v) {
    return glm::vec3(-v.x, v.y, v.z);
}

} // namespace

std::uint64_t peakResidentBytes() {
    rusage usage{};
    getrusage(RUSAGE_SELF, &usage);
    return std::uint64_t(usage.ru_maxrss) * 1024; // kilobytes on Linux
}

nlohmann::json::json_pointer keyPathPointer(const std::string& keyPath) {
    std::string pointer;
    std::size_t start = 0;
    while (true) {
        const std::size_t dot = keyPath.find('.', start);
        const std::string part =
            keyPath.substr(start, dot == std::string::npos ? dot : dot - start);
        if (part.empty() || part.find_first_of("/~") != std::string::npos)
            throw InputError(cat("key path '", keyPath, "' must be names separated by dots"));
        pointer += "/" + part;
        if (dot == std::string::npos)
            break;
        start = dot + 1;
    }
    return nlohmann::json::json_pointer(pointer);
}

std::size_t Session::Edit::bytes() const {
    std::size_t n = sizeof(Edit);
    for (const JsonChange& c : json)
        n += sizeof(JsonChange) + c.path.to_string().size() +
             (c.before ? c.before->dump().size() : 0) + (c.after ? c.after->dump().size() : 0);
    for (const auto& [slot, delta] : grids)
        n += deltaBytes(delta);
    for (const auto& [slot, before, after] : created)
        n += before ? std::size_t(before->memoryBytes()) : 0;
    return n;
}

Session::Session(const std::filesystem::path& scene, const SessionOptions& options)
    : m_scene(noise::loadScene(scene)), m_voxelScale(options.voxelScale),
      m_undoSteps(std::max(options.undoSteps, kMinUndoSteps)), m_undoBytes(options.undoBytes) {
    if (!(options.voxelScale > 0.0f && options.voxelScale <= 1.0f))
        throw InputError(cat("voxel scale ", options.voxelScale, " must be in (0, 1]"));
    if (options.width > 0 && options.height > 0) {
        m_scene.camera.width = options.width;
        m_scene.camera.height = options.height;
    }
    m_camera = m_scene.camera;
    m_sceneShading = m_scene.shading;
    (void)noise::CameraRays(m_camera); // checks the camera
    // A static OBJ/PLY or generated mesh loads as before (AnimatedMesh::load: a mesh that does
    // not move); the noise is generated on the rest pose of one that does.
    if (options.preset.empty())
        noise::requireSceneFiles(m_scene);
    m_animation = noise::AnimatedMesh::load(m_scene.mesh, m_scene.animation.clip,
                                            m_scene.animation.fps, m_scene.animation.restFrame,
                                            m_scene.meshOptions);
    if (const std::string warning = noise::checkAnimation(m_scene, m_animation); !warning.empty())
        std::fprintf(stderr, "%s\n", warning.c_str());
    m_mesh = m_animation.rest();
    if (m_animation.animated() || m_scene.wind.on())
        setTime(m_scene.animation.time);
    m_presetFile = options.preset.empty() ? m_scene.preset : options.preset;
    const std::string text = readFileCapped(m_presetFile, 64ull << 20);
    try {
        m_presetJson = nlohmann::json::parse(text);
    } catch (const nlohmann::json::exception& e) {
        throw InputError(cat("preset ", m_presetFile.string(), ": ", e.what()));
    }
    m_vdbName = m_presetFile.stem().string() + ".vdb";
    // The paint layers of a saved preset are read once and then edited in memory (painted base
    // fields are read by the generator, like images).
    const noise::PresetDesc loaded = noise::loadPreset(m_presetFile);
    for (int s = 0; s < kSlotCount; ++s) {
        const Slot slot = Slot(s);
        const noise::FieldDesc* d = noise::presetField(loaded, slotField(slot));
        if (d && d->paint) {
            const std::filesystem::path file = loaded.baseDir / d->paint->file;
            m_layers[s] = std::make_shared<noise::PaintLayer>(noise::readPaintLayer(
                file, d->paint->grid, slotComponents(slot), paintMode(slot)));
            m_vdbName = d->paint->file;
        }
    }
    m_ctx = std::make_unique<splat::Context>(options.context);
    rebuild();
    m_surface = std::make_unique<SurfaceIndex>(m_mesh);
    m_bvh = noise::triangleBvh(m_mesh);
    if (options.armBrush)
        m_startArmCost = armBrush();
}

Session::~Session() {
    // The frame refers to the generator, the generator to the mesh.
    m_frame.reset();
    m_generator.reset();
}

void Session::setCamera(const noise::Camera& camera) {
    (void)noise::CameraRays(camera);
    m_camera = camera;
}

void Session::setMethod(const std::string& method, const splat::RenderSettings& settings) {
    m_method = splat::gpuMethod(method).name;
    m_settings = settings;
}

splat::FrameStats Session::render(noise::Image* out) {
    if (m_windOn)
        applyWind();
    if (m_frame->animated())
        m_frame->setTime(m_time);
    const splat::View view{m_camera, m_scene.shading, m_scene.background, m_scene.baseColor};
    // Lit, a stroke's frames keep the light-space structure of the frame before it: its
    // shadows lag the paint until the stroke ends, and painting is not slowed by building it.
    std::optional<splat::LightSpaceHold> hold;
    if (m_stroke)
        hold.emplace();
    return m_frame->render(m_method, view, m_settings, out);
}

void Session::exportImage(const std::filesystem::path& file) {
    noise::Image image;
    const splat::FrameStats stats = render(&image);
    std::map<std::string, std::string> metadata = {
        {"method", m_method},
        {"scene", m_scene.name},
        {"kernels", std::to_string(stats.kernelsGenerated)},
        {"preset", m_presetJson.dump()}};
    if (animated()) {
        // Which frame of the clip this is.
        char time[32];
        std::snprintf(time, sizeof time, "%.9g", m_time);
        metadata["time"] = time;
        metadata["frame"] = std::to_string(frameNumber());
    }
    noise::writeImage(file, image, metadata);
}

void Session::poseForPick() const {
    if (!m_deformer)
        m_deformer = std::make_unique<noise::Deformer>(m_animation);
    if (m_posedAt == m_time)
        return;
    m_deformer->pose(m_time);
    m_posedBvh = noise::triangleBvh(m_deformer->posed());
    m_posedAt = m_time;
}

const noise::Mesh& Session::shownMesh() const {
    if (!m_animation.animated())
        return m_mesh;
    poseForPick();
    return m_deformer->posed();
}

std::optional<Hit> Session::pick(glm::vec2 pixel) const {
    const noise::Ray ray = noise::CameraRays(m_camera).ray(pixel.x, pixel.y);
    // A moving mesh is picked as shown, posed at the time on the CPU (the same pose formula as
    // the GPU's): the pose keeps the rest's topology, so the hit's triangle and barycentrics
    // name the same skin point at rest.
    const bool posed = m_animation.animated();
    if (posed)
        poseForPick();
    const noise::Mesh& shown = posed ? m_deformer->posed() : m_mesh;
    const std::optional<noise::MeshHit> hit =
        noise::closestHit(posed ? m_posedBvh : m_bvh, shown, ray);
    if (!hit)
        return std::nullopt;
    const noise::SurfacePoint sp = noise::surfacePoint(shown, hit->triangle, hit->barycentric);
    Hit h{sp.position, sp.normal, hit->t, hit->triangle, hit->barycentric, sp.position, sp.normal};
    if (posed) {
        const noise::SurfacePoint rest =
            noise::surfacePoint(m_mesh, hit->triangle, hit->barycentric);
        h.restPosition = rest.position;
        h.restNormal = rest.normal;
    }
    return h;
}

glm::vec3 Session::screenToWorld(glm::vec2 drag) const {
    const glm::dvec3 forward = glm::normalize(m_camera.target - m_camera.eye);
    const glm::dvec3 right = glm::normalize(glm::cross(forward, m_camera.up));
    const glm::dvec3 up = glm::cross(right, forward);
    // Window y grows downwards.
    return glm::vec3(right * double(drag.x) - up * double(drag.y));
}

bool Session::painted(Slot slot) const {
    return paintedIn(m_presetJson, slot);
}

nlohmann::json Session::slotJson(Slot slot) const {
    const auto ptr = keyPathPointer(std::string("fields.") + slotKey(slot));
    return m_presetJson.contains(ptr) ? m_presetJson.at(ptr) : nlohmann::json();
}

const noise::PaintLayer* Session::layer(Slot slot) const {
    return painted(slot) ? m_layers[int(slot)].get() : nullptr;
}

const noise::PaintedGrid* Session::grid(Slot slot) const {
    const noise::PaintLayer* l = layer(slot);
    return l ? &l->value() : nullptr;
}

noise::FieldDesc* Session::slotDesc(Slot slot) {
    return noise::presetField(m_preset, slotField(slot));
}

nlohmann::json Session::layeredJson(Slot slot) const {
    const nlohmann::json paint = {{"file", m_vdbName}, {"grid", layerGrid(slot)}};
    nlohmann::json base = slotJson(slot);
    // A slot limited to the mask is already in the object form: the layer joins its base.
    if (base.is_object() && (base.contains("mask") || base.contains("else"))) {
        base["paint"] = paint;
        return base;
    }
    nlohmann::json j = {{"paint", paint}};
    if (!base.is_null())
        j["base"] = base; // absent: the slot's default (the comb's: the surface tangent)
    return j;
}

float Session::voxelSize() const {
    return m_generator->cellSize() * m_voxelScale;
}

noise::PresetDesc Session::parseDocument(const nlohmann::json& json) const {
    noise::PresetDesc preset = noise::parsePreset(json.dump(), m_presetFile.string());
    preset.baseDir = m_presetFile.parent_path();
    for (int s = 0; s < kSlotCount; ++s) {
        const Slot slot = Slot(s);
        if (!paintedIn(json, slot))
            continue;
        const std::shared_ptr<noise::PaintLayer>& layer = m_layers[s];
        if (!layer)
            throw InputError(cat("preset ", m_presetFile.string(), ": fields.", slotKey(slot),
                                 " is painted but its layer is not loaded"));
        noise::FieldDesc* d = noise::presetField(preset, slotField(slot));
        SPOT_CHECK(d != nullptr && d->paint);
        d->paint->layer = layer;
    }
    return preset;
}

void Session::rebuild() {
    // An armed layer stands for the slot's field as it was armed: a changed or painted field
    // disarms it.
    for (int s = 0; s < kSlotCount; ++s)
        if (m_armed[s].layer && (painted(Slot(s)) || slotJson(Slot(s)) != m_armed[s].field))
            m_armed[s] = {};
    m_preset = parseDocument(m_presetJson);
    noise::GeneratorOptions options;
    options.seed = m_scene.seed;
    auto generator = std::make_unique<noise::ImpulseGenerator>(m_mesh, m_preset, options);
    generator->setMaskOverlay(m_maskOverlay);
    m_frame.reset();
    m_generator = std::move(generator);
    m_frame = std::make_unique<splat::Frame>(*m_ctx, m_mesh, *m_generator);
    if (m_animation.animated() || m_scene.wind.on()) {
        m_frame->animate(m_animation, m_scene.wind);
        m_frame->setTime(m_time);
    }
    m_windBase.clear();
}

void Session::refreshFields(const std::vector<glm::vec3>* changed, float voxelSize) {
    // A length stroke may change the smallest valid cell size; the generator then starts over
    // with the cell size a fresh load of the preset picks, so the impulses match the saved file
    // and undo stays exact.
    bool cellsChanged = false;
    try {
        m_generator->refreshFields();
        cellsChanged = m_generator->minimumCellSize() != m_generator->cellSize();
    } catch (const InputError&) {
        cellsChanged = true;
    }
    if (cellsChanged) {
        rebuild();
        return;
    }
    m_windBase.clear(); // the comb may have changed
    if (!changed || m_windOn) {
        m_frame->fieldsChanged();
        return;
    }
    // An impulse reads the 8 voxels around its anchor (trilinear), so a voxel's change reaches
    // the anchors within one voxel of it along each axis, in the cells that box overlaps.
    const noise::SurfaceCells& cells = m_generator->cells();
    const float h = cells.cellSize;
    std::vector<std::uint32_t> touched;
    for (const glm::vec3& p : *changed) {
        const glm::ivec3 lo(glm::floor((p - voxelSize) / h)), hi(glm::floor((p + voxelSize) / h));
        for (int z = lo.z; z <= hi.z; ++z)
            for (int y = lo.y; y <= hi.y; ++y)
                for (int x = lo.x; x <= hi.x; ++x) {
                    const std::int64_t c = cells.find(glm::ivec3(x, y, z));
                    if (c >= 0)
                        touched.push_back(std::uint32_t(c));
                }
    }
    std::sort(touched.begin(), touched.end());
    touched.erase(std::unique(touched.begin(), touched.end()), touched.end());
    m_frame->fieldsChanged(touched);
}

std::shared_ptr<noise::PaintLayer> Session::startLayer(Slot slot) const {
    return std::make_shared<noise::PaintLayer>(layerGrid(slot), slotComponents(slot), voxelSize(),
                                               paintMode(slot));
}

std::int32_t Session::layeredKind(Slot slot) const {
    const gpu::SpotField& f = m_generator->sharedParams().fields[slotField(slot)];
    // An unset comb (no field: the surface tangent) is layered over the tangent field.
    const std::int32_t base = slot == Slot::Comb && m_generator->sharedParams().flags.z == 0u
                                  ? Generator::kFieldTangent
                                  : (f.kind.x & Generator::kFieldKindMask);
    // A slot limited to the mask keeps its flag (spot_generate.h spotSlotValue).
    const std::int32_t masked =
        f.kind.x & (Generator::kFieldMaskedInside | Generator::kFieldMaskedOutside);
    return base | masked |
           (slot == Slot::Density ? Generator::kFieldLayeredDensity : Generator::kFieldLayered);
}

std::int32_t Session::layeredComponents(Slot slot) const {
    const gpu::SpotGenParams& params = m_generator->sharedParams();
    if (slot == Slot::Comb && params.flags.z == 0u)
        return 3; // layered over the tangent field
    return params.fields[slotField(slot)].kind.y;
}

EditCost Session::setBrush(const BrushSettings& brush) {
    m_brush = brush;
    return armBrush();
}

EditCost Session::setBrushKind(BrushKind kind) {
    m_brush.kind = kind;
    return armBrush();
}

EditCost Session::armBrush() {
    EditCost cost;
    const Slot slot = brushSlot(m_brush);
    const int s = int(slot);
    const Armed& a = m_armed[s];
    const bool arm = !painted(slot) && !(a.layer && a.layer->voxelSize() == voxelSize() &&
                                         a.field == slotJson(slot));
    bool others = false;
    for (int t = 0; t < kSlotCount; ++t)
        others |= t != s && m_armed[t].layer != nullptr;
    if (!arm && !others)
        return cost;
    if (m_stroke)
        endStroke();
    const auto start = Clock::now();
    // Only the current brush's slot stays armed.
    for (int t = 0; t < kSlotCount; ++t)
        if (t != s)
            m_armed[t] = {};
    if (arm) {
        m_armed[s] = Armed{startLayer(slot), slotJson(slot)};
        m_frame->generator().prepareFieldKind(std::uint32_t(slotField(slot)), layeredKind(slot),
                                              layeredComponents(slot));
    }
    cost.armed = arm;
    cost.milliseconds = msSince(start);
    return cost;
}

bool Session::ensurePainted(Slot slot, Edit& edit) {
    if (painted(slot))
        return false;
    const int s = int(slot);
    const Armed& a = m_armed[s];
    const bool armed =
        a.layer && a.layer->voxelSize() == voxelSize() && a.field == slotJson(slot);
    const std::shared_ptr<noise::PaintLayer> layer = armed ? a.layer : startLayer(slot);
    m_armed[s] = {};
    const auto ptr = keyPathPointer(std::string("fields.") + slotKey(slot));
    JsonChange change{ptr, std::nullopt, layeredJson(slot)};
    if (m_presetJson.contains(ptr))
        change.before = m_presetJson.at(ptr);
    edit.created.emplace_back(slot, m_layers[s], layer);
    edit.json.push_back(change);
    m_layers[s] = layer;
    m_presetJson[ptr] = *change.after;
    // The empty layer gives its base bit for bit: bound without a new generator or frame.
    m_preset = parseDocument(m_presetJson);
    noise::FieldDesc* d = slotDesc(slot);
    SPOT_CHECK(d != nullptr);
    try {
        m_generator->setField(slotField(slot), *d);
    } catch (const InputError&) {
        rebuild();
        return true;
    }
    m_frame->fieldsChanged();
    return false;
}

const std::vector<SurfaceVoxel>& Session::surfaceVoxels() {
    if (m_surfaceVoxelSize != voxelSize()) {
        const noise::Bounds b = m_mesh.bounds();
        const glm::vec3 centre = 0.5f * (b.lo + b.hi);
        const float radius = 0.5f * glm::length(b.size()) + 2.0f * voxelSize();
        m_surfaceVoxels = m_surface->voxelsNear(centre, radius, voxelSize());
        m_surfaceVoxelSize = voxelSize();
    }
    return m_surfaceVoxels;
}

std::vector<glm::vec3> Session::sampleSlot(Slot slot) {
    const noise::FieldDesc* desc = slotDesc(slot);
    std::unique_ptr<noise::Field> field;
    if (desc)
        field = noise::makeField(*desc, m_mesh, m_preset.baseDir,
                                 cat("preset ", m_presetFile.string(), ", fields.", slotKey(slot)));
    std::vector<glm::vec3> values;
    values.reserve(surfaceVoxels().size());
    for (const SurfaceVoxel& v : surfaceVoxels())
        values.push_back(field ? field->eval(v.point) : v.point.tangent);
    return values;
}

void Session::applyWind() {
    const std::vector<SurfaceVoxel>& voxels = surfaceVoxels();
    if (m_windBase.size() != voxels.size())
        m_windBase = sampleSlot(Slot::Comb);
    const noise::Bounds b = m_mesh.bounds();
    const float wavelength = std::max(glm::length(b.size()), 1e-6f);
    const float gain = std::tan(glm::radians(std::clamp(m_windAmplitudeDeg, 0.0f, 80.0f)));
    const float twoPi = 6.28318530718f;
    auto wind =
        std::make_shared<noise::PaintedGrid>(slotKey(Slot::Comb), 3, voxelSize(), glm::vec3(0.0f));
    for (std::size_t i = 0; i < voxels.size(); ++i) {
        const glm::vec3 p = glm::vec3(voxels[i].ijk) * voxelSize();
        const glm::vec3 base = m_windBase[i];
        const float phase = twoPi * (m_windFrequencyHz * float(m_time) - p.x / wavelength);
        wind->set(voxels[i].ijk,
                  base + gain * glm::length(base) * std::sin(phase) * glm::vec3(1.0f, 0.0f, 0.0f));
    }
    noise::FieldDesc desc;
    desc.kind = noise::FieldDesc::Kind::Painted;
    desc.components = 3;
    desc.file = m_vdbName;
    desc.grid = slotKey(Slot::Comb);
    desc.painted = wind;
    m_generator->setField(SPOT_FIELD_COMB, desc);
    m_frame->fieldsChanged();
}

void Session::applyJson(const std::vector<JsonChange>& changes, bool after) {
    auto apply = [&](const JsonChange& c) {
        const std::optional<nlohmann::json>& v = after ? c.after : c.before;
        if (v) {
            m_presetJson[c.path] = *v;
        } else if (m_presetJson.contains(c.path)) {
            nlohmann::json& parent = m_presetJson.at(c.path.parent_pointer());
            if (parent.is_object())
                parent.erase(c.path.back());
            else
                parent.erase(std::size_t(std::stoul(c.path.back())));
        }
    };
    if (after)
        for (const JsonChange& c : changes)
            apply(c);
    else
        for (auto it = changes.rbegin(); it != changes.rend(); ++it)
            apply(*it);
}

void Session::push(Edit edit) {
    m_redo.clear();
    m_current = edit.id;
    m_undo.push_back(std::move(edit));
    while (m_undo.size() > m_undoSteps)
        m_undo.pop_front();
    while (m_undo.size() > kMinUndoSteps && undoBytes() > m_undoBytes)
        m_undo.pop_front();
}

std::size_t Session::undoBytes() const {
    std::size_t n = 0;
    for (const Edit& e : m_undo)
        n += e.bytes();
    for (const Edit& e : m_redo)
        n += e.bytes();
    return n;
}

std::size_t Session::memoryBytes() const {
    std::size_t n = undoBytes();
    for (const auto& l : m_layers)
        n += l ? std::size_t(l->memoryBytes()) : 0;
    return n;
}

// --- strokes ------------------------------------------------------------------------------------

EditCost Session::beginStroke(glm::vec2 pixel, bool invert) {
    if (!std::isfinite(pixel.x) || !std::isfinite(pixel.y))
        throw InputError(cat("stroke point (", pixel.x, ", ", pixel.y, ") is not finite"));
    if (m_stroke)
        endStroke();
    m_strokeInvert = invert;
    const auto start = Clock::now();
    m_stroke = std::make_unique<Edit>();
    m_stroke->id = m_nextId++;
    EditCost cost;
    const Slot slot = brushSlot(m_brush);
    if (!painted(slot))
        cost.generatorRebuilt = ensurePainted(slot, *m_stroke);
    // The field under the layer, which the length brush scales (null: the surface tangent).
    m_strokeBase.reset();
    if (const noise::FieldDesc* d = slotDesc(slot); d && d->kind != noise::FieldDesc::Kind::Tangent) {
        noise::FieldDesc base = *d;
        base.paint.reset();
        m_strokeBase = noise::makeField(base, m_mesh, m_preset.baseDir,
                                        cat("preset ", m_presetFile.string(), ", fields.",
                                            slotKey(slot), ".base"));
    }
    // The mask as it is now (its base and paint), which a limited brush reads.
    m_strokeMask.reset();
    if (m_brush.limit != MaskLimit::None && slot != Slot::Mask)
        m_strokeMask = noise::makeField(m_preset.mask, m_mesh, m_preset.baseDir,
                                        cat("preset ", m_presetFile.string(), ", fields.mask"));
    m_strokeLast = pixel;
    m_strokeCarry = 0.0f;
    m_strokeDabs = m_strokeVoxels = 0;
    // The first dab has no drag direction yet: comb waits for the pointer to move.
    if (m_brush.kind != BrushKind::Comb) {
        dab(pixel, glm::vec2(0.0f));
        refreshEvent();
        cost.fieldsRefreshed = true;
    }
    cost.dabs = m_strokeDabs;
    cost.voxelsWritten = m_strokeVoxels;
    cost.milliseconds = msSince(start);
    return cost;
}

EditCost Session::dragStroke(glm::vec2 pixel) {
    if (!std::isfinite(pixel.x) || !std::isfinite(pixel.y))
        throw InputError(cat("stroke point (", pixel.x, ", ", pixel.y, ") is not finite"));
    if (!m_stroke)
        return beginStroke(pixel);
    const auto start = Clock::now();
    const std::size_t dabs = m_strokeDabs, voxels = m_strokeVoxels;
    const float spacing = std::max(m_brush.radiusPx * 0.25f, 1.0f);
    // Only the part of the drag within a brush radius of the window can reach what the window
    // shows: clipping to it bounds the dabs (and keeps `at` below where adding the spacing in
    // float stops advancing it: a point 1e9 pixels away).
    glm::vec2 from = m_strokeLast, to = pixel;
    const double margin = std::max(double(m_brush.radiusPx), 0.0);
    const ClippedSegment clipped =
        clipSegment(from, to, glm::dvec2(-margin),
                    glm::dvec2(m_camera.width + margin, m_camera.height + margin));
    m_strokeLast = pixel;
    EditCost cost;
    if (!clipped.inside) {
        m_strokeCarry = 0.0f;
    } else {
        from = clipped.from;
        to = clipped.to;
        if (clipped.startClipped)
            m_strokeCarry = spacing; // the first dab where the drag enters
        const float length = glm::length(to - from);
        if (length > 0.0f) {
            const glm::vec2 dir = (to - from) / length;
            float at = spacing - m_strokeCarry;
            for (; at <= length; at += spacing)
                dab(from + dir * at, dir);
            m_strokeCarry = clipped.endClipped ? 0.0f : length - (at - spacing);
            if (m_strokeDabs > dabs) {
                refreshEvent();
                cost.fieldsRefreshed = true;
            }
        }
    }
    cost.dabs = m_strokeDabs - dabs;
    cost.voxelsWritten = m_strokeVoxels - voxels;
    cost.milliseconds = msSince(start);
    return cost;
}

EditCost Session::endStroke() {
    EditCost cost;
    if (!m_stroke)
        return cost;
    cost.dabs = m_strokeDabs;
    cost.voxelsWritten = m_strokeVoxels;
    Edit edit = std::move(*m_stroke);
    m_stroke.reset();
    if (edit.grids.empty() && edit.created.empty())
        return cost;
    push(std::move(edit));
    return cost;
}

EditCost Session::pointer(PointerPhase phase, glm::vec2 pixel, const noise::Camera& view,
                          bool invert) {
    if (phase != PointerPhase::Release)
        setCamera(view);
    switch (phase) {
    case PointerPhase::Press: {
        EditCost cost = beginStroke(pixel, invert);
        return cost;
    }
    case PointerPhase::Drag:
        return dragStroke(pixel);
    case PointerPhase::Release:
        return endStroke();
    }
    return {};
}

BrushSettings Session::strokeBrush() const {
    BrushSettings b = m_brush;
    if (!m_strokeInvert)
        return b;
    if (b.kind == BrushKind::DensityAdd)
        b.kind = BrushKind::DensityErase;
    else if (b.kind == BrushKind::DensityErase)
        b.kind = BrushKind::DensityAdd;
    else if (b.kind == BrushKind::Length || b.kind == BrushKind::Tilt ||
             b.kind == BrushKind::Clump || b.kind == BrushKind::ClumpSize ||
             b.kind == BrushKind::Mask)
        b.strength = -b.strength;
    return b;
}

EditCost Session::stroke(const std::vector<glm::vec2>& points) {
    EditCost total;
    auto add = [&](const EditCost& c) {
        total.milliseconds += c.milliseconds;
        total.generatorRebuilt |= c.generatorRebuilt;
        total.fieldsRefreshed |= c.fieldsRefreshed;
    };
    if (points.empty())
        return total;
    add(beginStroke(points.front()));
    for (std::size_t i = 1; i < points.size(); ++i)
        add(dragStroke(points[i]));
    const EditCost end = endStroke();
    total.dabs = end.dabs;
    total.voxelsWritten = end.voxelsWritten;
    return total;
}

void Session::refreshEvent() {
    const float size = m_layers[int(brushSlot(m_brush))]->voxelSize();
    std::vector<glm::vec3> changed;
    changed.reserve(m_eventVoxels.size());
    for (const glm::ivec3& v : m_eventVoxels)
        changed.push_back(glm::vec3(v) * size);
    m_eventVoxels.clear();
    refreshFields(&changed, size);
}

void Session::dab(glm::vec2 pixel, glm::vec2 drag) {
    const std::optional<Hit> hit = pick(pixel);
    if (!hit)
        return;
    const Slot slot = brushSlot(m_brush);
    noise::PaintLayer& layer = *m_layers[int(slot)];
    auto it = std::find_if(m_stroke->grids.begin(), m_stroke->grids.end(),
                           [&](const auto& g) { return g.first == slot; });
    if (it == m_stroke->grids.end()) {
        m_stroke->grids.emplace_back(slot, GridDelta{});
        it = std::prev(m_stroke->grids.end());
    }
    Dab d;
    d.radius = float(m_brush.radiusPx * noise::CameraRays(m_camera).pixelFootprint(hit->distance));
    if (m_animation.animated()) {
        // The layers live at rest: the dab at the hit's rest point, and the eye and the drag
        // carried back from the pose by the hit triangle's rotation (pick posed it), so the
        // front-face test and the comb see at rest what the user sees at the pose.
        const glm::mat3 back = glm::transpose(m_deformer->rotations()[hit->triangle]);
        d.centre = hit->restPosition;
        d.eye = hit->restPosition + back * (glm::vec3(m_camera.eye) - hit->position);
        d.direction = back * screenToWorld(drag);
    } else {
        d.centre = hit->position;
        d.eye = glm::vec3(m_camera.eye);
        d.direction = screenToWorld(drag);
    }
    const BrushSettings brush = strokeBrush();
    m_strokeVoxels += applyDab(brush, d, *m_surface, layer, m_strokeBase.get(), it->second,
                               &m_eventVoxels, m_strokeMask.get());
    if (brush.mirrorX) {
        // The mirrored dab sees the mirrored camera, so front faces stay front faces.
        Dab m = d;
        m.centre = mirrorX(d.centre);
        m.eye = mirrorX(d.eye);
        m.direction = mirrorX(d.direction);
        m_strokeVoxels += applyDab(brush, m, *m_surface, layer, m_strokeBase.get(), it->second,
                                   &m_eventVoxels, m_strokeMask.get());
    }
    ++m_strokeDabs;
}

// --- parameters ---------------------------------------------------------------------------------

nlohmann::json Session::get(const std::string& keyPath) const {
    const auto ptr = keyPathPointer(keyPath);
    return m_presetJson.contains(ptr) ? m_presetJson.at(ptr) : nlohmann::json();
}

EditCost Session::set(const std::string& keyPath, const nlohmann::json& value) {
    return set(std::vector<std::pair<std::string, nlohmann::json>>{{keyPath, value}});
}

EditCost Session::set(const std::vector<std::pair<std::string, nlohmann::json>>& changes) {
    if (m_stroke)
        endStroke();
    const auto start = Clock::now();
    Edit edit;
    edit.id = m_nextId++;
    for (const auto& [path, value] : changes) {
        JsonChange c{keyPathPointer(path), std::nullopt, value};
        if (m_presetJson.contains(c.path))
            c.before = m_presetJson.at(c.path);
        edit.json.push_back(std::move(c));
    }
    const nlohmann::json saved = m_presetJson;
    try {
        for (const JsonChange& c : edit.json) {
            // Only an existing array element or a key of an existing object may be set.
            const nlohmann::json& parent = m_presetJson.contains(c.path.parent_pointer())
                                               ? m_presetJson.at(c.path.parent_pointer())
                                               : nlohmann::json();
            if (!parent.is_object() && !(parent.is_array() && c.before))
                throw InputError(cat("'", c.path.to_string(), "' is not a key of the preset"));
            m_presetJson[c.path] = *c.after;
        }
        rebuild();
    } catch (const std::exception& e) {
        m_presetJson = saved;
        rebuild();
        // The preset's reader names its file; the value refused is the edit's, not the file's.
        std::string message = e.what();
        const std::string file = m_presetFile.string() + ": ";
        if (message.rfind(file, 0) == 0)
            message.erase(0, file.size());
        throw InputError(cat("set ", changes.front().first, ": ", message));
    }
    push(std::move(edit));
    EditCost cost;
    cost.generatorRebuilt = true;
    cost.milliseconds = msSince(start);
    return cost;
}

EditCost Session::setLobe(int lobe, const std::string& what, const nlohmann::json& value) {
    const int count = int(m_presetJson["kernel"]["lobes"].size());
    if (lobe < 0 || lobe >= count)
        throw InputError(cat("lobe ", lobe, " does not exist (the kernel has ", count, ")"));
    if (what != "offset" && what != "rotation_deg" && what != "sigma" && what != "extinction" &&
        what != "color")
        throw InputError(cat("lobe property '", what,
                             "' is not one of offset, rotation_deg, sigma, extinction, color"));
    return set(cat("kernel.lobes.", lobe, ".", what), value);
}

EditCost Session::addLobe(int copyOf) {
    nlohmann::json lobes = m_presetJson["kernel"]["lobes"];
    if (int(lobes.size()) >= noise::kMaxLobes)
        throw InputError(cat("a kernel has at most ", noise::kMaxLobes, " lobes"));
    if (copyOf < 0 || copyOf >= int(lobes.size()))
        throw InputError(cat("lobe ", copyOf, " does not exist"));
    lobes.push_back(lobes[std::size_t(copyOf)]);
    return set("kernel.lobes", lobes);
}

EditCost Session::removeLobe(int lobe) {
    nlohmann::json lobes = m_presetJson["kernel"]["lobes"];
    if (lobes.size() <= 1)
        throw InputError("a kernel needs at least one lobe");
    if (lobe < 0 || lobe >= int(lobes.size()))
        throw InputError(cat("lobe ", lobe, " does not exist"));
    lobes.erase(std::size_t(lobe));
    return set("kernel.lobes", lobes);
}

EditCost Session::setSeed(std::uint32_t seed) {
    if (m_stroke)
        endStroke();
    const auto start = Clock::now();
    m_scene.seed = seed;
    rebuild();
    EditCost cost;
    cost.generatorRebuilt = true;
    cost.milliseconds = msSince(start);
    return cost;
}

// --- undo ---------------------------------------------------------------------------------------

void Session::refreshDeltas(const Edit& edit) {
    std::vector<glm::vec3> changed;
    float size = 0.0f;
    for (const auto& [slot, delta] : edit.grids) {
        const float s = m_layers[int(slot)]->voxelSize();
        size = std::max(size, s);
        for (const auto& [ijk, change] : delta)
            changed.push_back(glm::vec3(ijk) * s);
    }
    refreshFields(&changed, size);
}

bool Session::undo(EditCost* cost) {
    if (m_stroke)
        endStroke();
    if (m_undo.empty())
        return false;
    const auto start = Clock::now();
    Edit e = std::move(m_undo.back());
    m_undo.pop_back();
    for (auto it = e.grids.rbegin(); it != e.grids.rend(); ++it)
        applyDelta(*m_layers[int(it->first)], it->second, false);
    for (auto it = e.created.rbegin(); it != e.created.rend(); ++it)
        m_layers[int(std::get<0>(*it))] = std::get<1>(*it);
    applyJson(e.json, false);
    // Undoing the first stroke on the brush's slot returns to the armed state: the layer it
    // created, empty again.
    for (const auto& [slot, before, after] : e.created)
        if (after && !painted(slot) && slot == brushSlot(m_brush))
            m_armed[int(slot)] = Armed{after, slotJson(slot)};
    const bool full = !e.json.empty();
    if (full)
        rebuild();
    else
        refreshDeltas(e);
    for (int t = 0; t < kSlotCount; ++t)
        if (full && m_armed[t].layer)
            m_frame->generator().prepareFieldKind(std::uint32_t(slotField(Slot(t))),
                                                  layeredKind(Slot(t)),
                                                  layeredComponents(Slot(t)));
    m_current = m_undo.empty() ? 0 : m_undo.back().id;
    m_redo.push_back(std::move(e));
    if (cost) {
        cost->generatorRebuilt = full;
        cost->fieldsRefreshed = !full;
        cost->milliseconds = msSince(start);
    }
    return true;
}

bool Session::redo(EditCost* cost) {
    if (m_stroke)
        endStroke();
    if (m_redo.empty())
        return false;
    const auto start = Clock::now();
    Edit e = std::move(m_redo.back());
    m_redo.pop_back();
    for (const auto& [slot, before, after] : e.created)
        m_layers[int(slot)] = after;
    applyJson(e.json, true);
    for (const auto& [slot, delta] : e.grids)
        applyDelta(*m_layers[int(slot)], delta, true);
    const bool full = !e.json.empty();
    if (full)
        rebuild();
    else
        refreshDeltas(e);
    m_current = e.id;
    m_undo.push_back(std::move(e));
    if (cost) {
        cost->generatorRebuilt = full;
        cost->fieldsRefreshed = !full;
        cost->milliseconds = msSince(start);
    }
    return true;
}

// --- files --------------------------------------------------------------------------------------

void Session::save(const std::filesystem::path& file) {
    if (m_stroke)
        endStroke();
    std::filesystem::path vdb = file;
    vdb.replace_extension(".vdb");
    const std::string vdbName = vdb.filename().string();
    nlohmann::json out = m_presetJson;
    std::vector<const noise::PaintedGrid*> grids;
    std::vector<std::unique_ptr<noise::PaintedGrid>> bases; // painted base fields, read back
    const std::filesystem::path from = std::filesystem::absolute(m_presetFile).parent_path();
    const std::filesystem::path to = std::filesystem::absolute(file).parent_path();
    // A field's files, kept reachable: an image from the new folder, a painted grid copied into
    // the new .vdb (which replaces the file it may have come from).
    const auto keepFiles = [&](nlohmann::json& field, const noise::FieldSlot& slot) {
        if (!field.is_object())
            return;
        const std::string type = field.value("type", std::string());
        const std::filesystem::path path(field.value("file", std::string()));
        if (type == "painted") {
            bases.push_back(std::make_unique<noise::PaintedGrid>(noise::readPaintedGrid(
                path.is_absolute() ? path : from / path, field.value("grid", std::string()),
                slot.components)));
            grids.push_back(bases.back().get());
            field["file"] = vdbName;
        } else if (type == "image" && from != to && path.is_relative()) {
            field["file"] = std::filesystem::relative(from / path, to).generic_string();
        }
    };
    if (out.contains("fields"))
        for (auto& [key, field] : out["fields"].items()) {
            const noise::FieldSlot* slot = noise::findFieldSlot(key);
            if (!slot || !field.is_object())
                continue;
            if (!field.contains("paint")) {
                // A field, or the object form of a slot limited to the mask.
                keepFiles(field.contains("base") ? field["base"] : field, *slot);
                continue;
            }
            if (field.contains("base"))
                keepFiles(field["base"], *slot);
            field["paint"]["file"] = vdbName;
            for (int s = 0; s < kSlotCount; ++s)
                if (slotField(Slot(s)) == slot->index) {
                    grids.push_back(&m_layers[s]->value());
                    grids.push_back(&m_layers[s]->weight());
                }
        }
    // The grids first: a preset on disk never names a .vdb that is not there yet.
    if (!grids.empty())
        noise::writePaintedGrids(vdb, grids);
    writeFileAtomic(file, [&](std::ostream& o) { o << out.dump(2) << "\n"; });
    m_presetJson = out;
    m_presetFile = file;
    m_vdbName = vdbName;
    m_preset.baseDir = file.parent_path();
    m_saved = m_current;
}

void Session::setMaskOverlay(bool on) {
    if (on == m_maskOverlay)
        return;
    m_maskOverlay = on;
    m_generator->setMaskOverlay(on);
    m_frame->fieldsChanged();
}

void Session::setWind(bool on, float amplitudeDeg, float frequencyHz) {
    const bool wasOn = m_windOn;
    m_windOn = on;
    m_windAmplitudeDeg = amplitudeDeg;
    m_windFrequencyHz = frequencyHz;
    m_windBase.clear();
    if (wasOn && !on)
        rebuild(); // the document's comb again
}

void Session::setLit(bool lit) {
    if (lit == this->lit())
        return; // a lit session keeps its lights as set
    if (!lit) {
        if (m_sceneShading.mode == noise::Shading::Mode::Lit) {
            m_sceneShading = m_scene.shading; // keeps the lights as set here
            m_scene.shading.mode = noise::Shading::Mode::Unlit;
        } else {
            m_scene.shading = m_sceneShading;
        }
        return;
    }
    noise::Shading asked;
    asked.mode = noise::Shading::Mode::Lit;
    splat::requireLitSupport(splat::method(m_method), asked);
    noise::Shading shading = m_sceneShading;
    if (shading.mode != noise::Shading::Mode::Lit || shading.lights.empty()) {
        if (shading.lights.empty()) {
            noise::Light key;
            key.direction = glm::normalize(glm::vec3(-0.6f, 0.8f, 0.45f));
            key.color = glm::vec3(1.0f, 0.95f, 0.88f);
            key.intensity = 3.0f;
            key.shadows = true;
            shading.lights = {key};
        }
        if (!(shading.sky.intensity > 0.0f)) {
            shading.sky.color = glm::vec3(0.55f, 0.65f, 0.85f);
            shading.sky.intensity = 0.5f;
        }
    }
    shading.mode = noise::Shading::Mode::Lit;
    m_scene.shading = shading;
}

void Session::setKeyLight(float azimuthDeg, float elevationDeg, float intensity, bool shadows) {
    if (!std::isfinite(azimuthDeg) || !(elevationDeg >= -90.0f && elevationDeg <= 90.0f) ||
        !(intensity >= 0.0f && intensity <= 1e4f))
        throw InputError(cat("key light: azimuth ", azimuthDeg, ", elevation ", elevationDeg,
                             " (in [-90, 90]), intensity ", intensity, " (in [0, 10000])"));
    if (!lit())
        setLit(true);
    noise::Light& key = m_scene.shading.lights.front();
    const float a = glm::radians(azimuthDeg), e = glm::radians(elevationDeg);
    key.type = noise::Light::Type::Directional;
    key.direction = glm::vec3(std::cos(e) * std::sin(a), std::sin(e), std::cos(e) * std::cos(a));
    key.intensity = intensity;
    key.shadows = shadows;
}

void Session::turnKeyLight(float dAzimuthDeg, float dElevationDeg) {
    if (!std::isfinite(dAzimuthDeg) || !std::isfinite(dElevationDeg))
        throw InputError(cat("key light: turn by ", dAzimuthDeg, ", ", dElevationDeg, " degrees"));
    if (!lit())
        setLit(true);
    const KeyLight k = keyLight();
    const float azimuth = std::remainder(k.azimuthDeg + dAzimuthDeg, 360.0f);
    setKeyLight(azimuth, std::clamp(k.elevationDeg + dElevationDeg, -89.0f, 89.0f), k.intensity,
                k.shadows);
}

Session::KeyLight Session::keyLight() const {
    KeyLight k;
    if (m_scene.shading.lights.empty())
        return k;
    const noise::Light& key = m_scene.shading.lights.front();
    const glm::vec3 d = key.type == noise::Light::Type::Directional
                            ? glm::normalize(key.direction)
                            : glm::vec3(0.0f, 1.0f, 0.0f);
    k.azimuthDeg = glm::degrees(std::atan2(d.x, d.z));
    k.elevationDeg = glm::degrees(std::asin(std::clamp(d.y, -1.0f, 1.0f)));
    k.intensity = key.intensity;
    k.shadows = key.shadows;
    return k;
}

void Session::setTime(double seconds) {
    if (!std::isfinite(seconds))
        throw InputError(cat("time ", seconds, " is not finite"));
    m_time = m_animation.animated() ? m_animation.clampTime(seconds) : seconds;
}

long Timeline::frame(double t) const {
    return std::lround(t * fps);
}

Timeline Session::timeline() const {
    Timeline t;
    t.fps = m_scene.animation.fps;
    if (m_animation.animated()) {
        t.start = m_animation.clampTime(std::numeric_limits<double>::lowest());
        t.end = m_animation.clampTime(std::numeric_limits<double>::max());
    } else {
        t.end = std::max(Timeline::kNoClipSeconds, m_time);
    }
    return t;
}

bool Session::advance(double seconds) {
    if (!m_animation.animated()) {
        setTime(m_time + seconds); // no clip: the time runs on (the wind's gusts never jump)
        return true;
    }
    const Timeline t = timeline();
    double next = m_time + seconds;
    bool running = true;
    // A hair past the end (a sum of frame steps) is the end.
    if (next > t.end + 1e-9 * std::max(1.0, std::abs(t.end))) {
        if (m_loop && t.end > t.start) {
            next = t.start + std::fmod(next - t.start, t.end - t.start);
        } else {
            next = t.end;
            running = false;
        }
    }
    setTime(next);
    return running;
}

} // namespace spot::edit
