#include "scene.h"

#include <algorithm>
#include <cmath>

#include "json_reader.h"
#include "system.h"

namespace spot::noise {

namespace {

constexpr std::uint64_t kMaxSceneBytes = 1u << 20;
constexpr json::Interval kCoordinate{-1e6, 1e6};
constexpr json::Interval kColor{0.0, 1e3};
constexpr json::Interval kUnit{0.0, 1.0};
/// A light's or the sky's intensity (it multiplies the colour).
constexpr json::Interval kIntensity{0.0, 1e6};
constexpr json::Interval kFov{0.0, 179.0, true, true};
constexpr json::Interval kOrthoHeight{0.0, 1e6, true, false};
/// Images larger than this per side are refused: a typo (256000) should not allocate gigabytes.
constexpr std::int64_t kMaxImageSide = 16384;

Camera parseCamera(const json::Reader& rd, const json::Json& j) {
    rd.requireObject(j, "camera", {"projection", "eye", "target", "up", "fov_deg", "ortho_height",
                                   "keys", "turntable_deg_per_s"});
    Camera c;
    if (const json::Json* p = json::Reader::find(j, "projection")) {
        const std::string mode = rd.string(*p, "camera.projection", false);
        if (mode == "perspective")
            c.projection = Projection::Perspective;
        else if (mode == "orthographic")
            c.projection = Projection::Orthographic;
        else
            rd.fail(cat("camera.projection = \"", json::printable(mode),
                        "\" is not one of \"perspective\", \"orthographic\""));
    }
    c.eye = glm::dvec3(rd.vec3(rd.require(j, "camera", "eye"), "camera.eye", kCoordinate));
    c.target = glm::dvec3(rd.vec3(rd.require(j, "camera", "target"), "camera.target", kCoordinate));
    if (const json::Json* u = json::Reader::find(j, "up"))
        c.up = glm::dvec3(rd.vec3(*u, "camera.up", kCoordinate));
    if (const json::Json* f = json::Reader::find(j, "fov_deg"))
        c.fovYDeg = rd.number(*f, "camera.fov_deg", kFov);
    if (const json::Json* h = json::Reader::find(j, "ortho_height"))
        c.orthoHeight = rd.number(*h, "camera.ortho_height", kOrthoHeight);
    if (!(glm::length(c.target - c.eye) > 1e-9))
        rd.fail("camera.eye and camera.target must be different points");
    if (!(glm::length(glm::cross(glm::normalize(c.target - c.eye), c.up)) > 1e-6))
        rd.fail("camera.up must not be parallel to the view direction (or zero)");
    return c;
}

Shading parseShading(const json::Reader& rd, const json::Json& j) {
    rd.requireObject(j, "shading", {"mode", "light_dir", "ambient"});
    Shading s;
    const std::string mode = rd.string(rd.require(j, "shading", "mode"), "shading.mode", false);
    bool known = false;
    for (const Shading::Mode m :
         {Shading::Mode::Unlit, Shading::Mode::Lambert, Shading::Mode::Lit})
        if (mode == Shading::modeName(m)) {
            s.mode = m;
            known = true;
        }
    if (!known)
        rd.fail(cat("shading.mode = \"", json::printable(mode),
                    "\" is not one of \"unlit\", \"lambert\", \"lit\""));
    if (s.mode == Shading::Mode::Lit)
        for (const char* key : {"light_dir", "ambient"})
            if (json::Reader::find(j, key))
                rd.fail(
                    cat("shading.", key, " is lambert's; \"lit\" takes \"lights\" and \"sky\""));
    if (const json::Json* l = json::Reader::find(j, "light_dir")) {
        const glm::vec3 d = rd.vec3(*l, "shading.light_dir", kCoordinate);
        if (!(glm::length(d) > 1e-6f))
            rd.fail("shading.light_dir must not be zero");
        s.lightDir = glm::normalize(d);
    }
    if (const json::Json* a = json::Reader::find(j, "ambient"))
        s.ambient = rd.real(*a, "shading.ambient", kUnit);
    return s;
}

std::vector<CameraKey> parseCameraKeys(const json::Reader& rd, const json::Json& j,
                                       const Camera& camera) {
    if (!j.is_array() || j.empty() || j.size() > 100000)
        rd.fail("camera.keys must be an array of 1 to 100000 keys");
    std::vector<CameraKey> keys;
    for (std::size_t i = 0; i < j.size(); ++i) {
        const std::string path = cat("camera.keys[", i, "]");
        rd.requireObject(j[i], path, {"time", "eye", "target"});
        CameraKey k;
        k.time = rd.number(rd.require(j[i], path, "time"), path + ".time", json::Interval{-1e6, 1e6});
        k.eye = glm::dvec3(rd.vec3(rd.require(j[i], path, "eye"), path + ".eye", kCoordinate));
        k.target = glm::dvec3(rd.vec3(rd.require(j[i], path, "target"), path + ".target", kCoordinate));
        if (!keys.empty() && !(k.time > keys.back().time))
            rd.fail(cat(path, ".time must be after the key before it"));
        if (!(glm::length(k.target - k.eye) > 1e-9))
            rd.fail(cat(path, ": eye and target must be different points"));
        if (!(glm::length(glm::cross(glm::normalize(k.target - k.eye), camera.up)) > 1e-6))
            rd.fail(cat(path, ": camera.up must not be parallel to the view direction"));
        keys.push_back(k);
    }
    return keys;
}

bool parseBool(const json::Reader& rd, const json::Json& j, const std::string& path) {
    if (!j.is_boolean())
        rd.fail(cat(path, " must be true or false, got ", j.type_name()));
    return j.get<bool>();
}

Light parseLight(const json::Reader& rd, const json::Json& j, const std::string& path) {
    rd.requireObject(j, path, {"type", "direction", "position", "color", "intensity", "shadows"});
    Light light;
    const std::string type = rd.string(rd.require(j, path, "type"), path + ".type", false);
    if (type == "directional")
        light.type = Light::Type::Directional;
    else if (type == "point")
        light.type = Light::Type::Point;
    else
        rd.fail(cat(path, ".type = \"", json::printable(type),
                    "\" is not one of \"directional\", \"point\""));
    const bool directional = light.type == Light::Type::Directional;
    const char* wrong = directional ? "position" : "direction";
    if (json::Reader::find(j, wrong))
        rd.fail(cat(path, ".", wrong, " does not apply to a ", type, " light"));
    if (directional) {
        const glm::vec3 d =
            rd.vec3(rd.require(j, path, "direction"), path + ".direction", kCoordinate);
        if (!(glm::length(d) > 1e-6f))
            rd.fail(cat(path, ".direction must not be zero"));
        light.direction = glm::normalize(d);
    } else {
        light.position = rd.vec3(rd.require(j, path, "position"), path + ".position", kCoordinate);
    }
    if (const json::Json* c = json::Reader::find(j, "color"))
        light.color = rd.vec3(*c, path + ".color", kColor);
    if (const json::Json* i = json::Reader::find(j, "intensity"))
        light.intensity = rd.real(*i, path + ".intensity", kIntensity);
    if (const json::Json* sh = json::Reader::find(j, "shadows"))
        light.shadows = parseBool(rd, *sh, path + ".shadows");
    return light;
}

std::vector<Light> parseLights(const json::Reader& rd, const json::Json& j) {
    if (!j.is_array())
        rd.fail(cat("lights must be an array of lights, got ", j.type_name()));
    if (j.size() > std::size_t(kMaxLights))
        rd.fail(cat("lights has ", j.size(), " lights, more than the limit of ", kMaxLights));
    std::vector<Light> lights;
    for (std::size_t i = 0; i < j.size(); ++i)
        lights.push_back(parseLight(rd, j[i], json::index("lights", i)));
    return lights;
}

Sky parseSky(const json::Reader& rd, const json::Json& j) {
    rd.requireObject(j, "sky", {"color", "intensity"});
    Sky sky;
    if (const json::Json* c = json::Reader::find(j, "color"))
        sky.color = rd.vec3(*c, "sky.color", kColor);
    sky.intensity = rd.real(rd.require(j, "sky", "intensity"), "sky.intensity", kIntensity);
    return sky;
}

AnimationDesc parseAnimation(const json::Reader& rd, const json::Json& j) {
    rd.requireObject(j, "animation", {"clip", "fps", "time", "frame", "rest_frame"});
    AnimationDesc a;
    a.given = true;
    if (const json::Json* c = json::Reader::find(j, "clip"))
        a.clip = rd.string(*c, "animation.clip", false);
    if (const json::Json* f = json::Reader::find(j, "fps"))
        a.fps = rd.number(*f, "animation.fps", json::Interval{0.0, 1000.0, true, false});
    const json::Json* time = json::Reader::find(j, "time");
    const json::Json* frame = json::Reader::find(j, "frame");
    if (time && frame)
        rd.fail("animation: give \"time\" (seconds) or \"frame\", not both");
    if (time)
        a.time = rd.number(*time, "animation.time", json::Interval{-1e6, 1e6});
    if (frame)
        a.time = rd.number(*frame, "animation.frame", json::Interval{-1e9, 1e9}) / a.fps;
    if (const json::Json* r = json::Reader::find(j, "rest_frame")) {
        a.restFrame = int(rd.integer(*r, "animation.rest_frame", 0, 100000));
        a.restFrameGiven = true;
    }
    return a;
}

Wind parseWind(const json::Reader& rd, const json::Json& j) {
    rd.requireObject(j, "wind", {"direction", "strength", "gust_frequency", "variation"});
    Wind w;
    if (const json::Json* d = json::Reader::find(j, "direction")) {
        const glm::vec3 v = rd.vec3(*d, "wind.direction", kCoordinate);
        if (!(glm::length(v) > 1e-6f))
            rd.fail("wind.direction must not be zero");
        w.direction = glm::normalize(v);
    }
    w.strength = rd.real(rd.require(j, "wind", "strength"), "wind.strength",
                         json::Interval{-3.14159, 3.14159});
    if (const json::Json* f = json::Reader::find(j, "gust_frequency"))
        w.gustFrequency = rd.real(*f, "wind.gust_frequency", json::Interval{0.0, 100.0});
    if (const json::Json* v = json::Reader::find(j, "variation"))
        w.variation = rd.real(*v, "wind.variation", kUnit);
    return w;
}

/// "weld": true (the default tolerance), false, or a tolerance relative to the mesh's size.
WeldOptions parseWeld(const json::Reader& rd, const json::Json& j) {
    WeldOptions w;
    if (j.is_boolean()) {
        w.on = j.get<bool>();
        return w;
    }
    if (!j.is_number())
        rd.fail(cat("weld must be true, false or a tolerance (a fraction of the mesh's size, "
                    "such as 1e-5), got ", j.type_name()));
    w.tolerance = rd.number(j, "weld", json::Interval{0.0, 0.01});
    return w;
}

/// "grow": {"meshes": [...], "nodes": [...], "exclude_meshes": [...], "exclude_nodes": [...]},
/// each entry a name (with * ? [..] wildcards) or an index.
GrowSelection parseGrow(const json::Reader& rd, const json::Json& j) {
    rd.requireObject(j, "grow", {"meshes", "nodes", "exclude_meshes", "exclude_nodes"});
    GrowSelection g;
    const auto list = [&](const char* key, std::vector<PartPattern>& out) {
        const json::Json* l = json::Reader::find(j, key);
        if (!l)
            return;
        const std::string path = cat("grow.", key);
        if (!l->is_array() || l->empty() || l->size() > 10000)
            rd.fail(cat(path, " must be an array of 1 to 10000 names or indices"));
        for (std::size_t i = 0; i < l->size(); ++i) {
            const json::Json& e = (*l)[i];
            PartPattern p;
            if (e.is_string())
                p.glob = rd.string(e, json::index(path, i), false);
            else if (e.is_number_integer())
                p.index = long(rd.integer(e, json::index(path, i), 0, 1000000000));
            else
                rd.fail(cat(json::index(path, i), " must be a name or an index, got ",
                            e.type_name()));
            out.push_back(p);
        }
    };
    list("meshes", g.meshes);
    list("nodes", g.nodes);
    list("exclude_meshes", g.excludeMeshes);
    list("exclude_nodes", g.excludeNodes);
    return g;
}

} // namespace

SceneDesc parseScene(std::string_view text, const std::string& name,
                     const std::filesystem::path& baseDir) {
    if (text.size() > kMaxSceneBytes)
        throw InputError(cat(name, ": scene is ", text.size(), " bytes, more than the limit of ",
                             kMaxSceneBytes));
    const json::Json root = json::parse(text, name);
    const json::Reader rd(name);
    rd.requireObject(root, "",
                     {"version", "name", "description", "mesh", "preset", "seed", "camera", "image",
                      "background", "base_color", "shading", "reference", "animation", "wind",
                      "lights", "sky", "weld", "grow"});
    rd.requireVersion(root, kSceneVersion);
    SceneDesc s;
    if (const json::Json* n = json::Reader::find(root, "name"))
        s.name = rd.string(*n, "name", false);
    else
        s.name = std::filesystem::path(name).stem().string();
    if (const json::Json* d = json::Reader::find(root, "description"))
        rd.string(*d, "description", true);
    const std::string mesh = rd.string(rd.require(root, "", "mesh"), "mesh", false);
    s.file = name;
    s.mesh = mesh.rfind("generated:", 0) == 0 ? mesh : (baseDir / mesh).string();
    s.meshWritten = mesh;
    s.presetWritten = rd.string(rd.require(root, "", "preset"), "preset", false);
    s.preset = baseDir / s.presetWritten;
    if (const json::Json* seed = json::Reader::find(root, "seed"))
        s.seed = std::uint32_t(rd.integer(*seed, "seed", 0, 0xffffffffll));
    const json::Json& camera = rd.require(root, "", "camera");
    s.camera = parseCamera(rd, camera);
    if (const json::Json* k = json::Reader::find(camera, "keys"))
        s.cameraKeys = parseCameraKeys(rd, *k, s.camera);
    if (const json::Json* t = json::Reader::find(camera, "turntable_deg_per_s"))
        s.turntableDegPerSecond = rd.number(*t, "camera.turntable_deg_per_s", json::Interval{-1e4, 1e4});
    const json::Json& image = rd.require(root, "", "image");
    rd.requireObject(image, "image", {"width", "height"});
    s.camera.width = int(rd.integer(rd.require(image, "image", "width"), "image.width", 1, kMaxImageSide));
    s.camera.height = int(rd.integer(rd.require(image, "image", "height"), "image.height", 1, kMaxImageSide));
    if (const json::Json* b = json::Reader::find(root, "background"))
        s.background = rd.vec3(*b, "background", kColor);
    if (const json::Json* b = json::Reader::find(root, "base_color"))
        s.baseColor = rd.vec3(*b, "base_color", kColor);
    if (const json::Json* sh = json::Reader::find(root, "shading"))
        s.shading = parseShading(rd, *sh);
    if (const json::Json* l = json::Reader::find(root, "lights"))
        s.shading.lights = parseLights(rd, *l);
    if (const json::Json* sky = json::Reader::find(root, "sky"))
        s.shading.sky = parseSky(rd, *sky);
    if (s.shading.mode == Shading::Mode::Lit && s.shading.lights.empty() &&
        !(s.shading.sky.intensity > 0.0f))
        rd.fail(
            "shading.mode \"lit\" needs a light (\"lights\") or a sky (\"sky\") with an intensity");
    if (const json::Json* r = json::Reader::find(root, "reference")) {
        rd.requireObject(*r, "reference", {"spp"});
        if (const json::Json* spp = json::Reader::find(*r, "spp"))
            s.referenceSpp = int(rd.integer(*spp, "reference.spp", 1, 65536));
    }
    if (const json::Json* a = json::Reader::find(root, "animation"))
        s.animation = parseAnimation(rd, *a);
    if (const json::Json* w = json::Reader::find(root, "wind"))
        s.wind = parseWind(rd, *w);
    if (const json::Json* w = json::Reader::find(root, "weld"))
        s.meshOptions.weld = parseWeld(rd, *w);
    if (const json::Json* g = json::Reader::find(root, "grow"))
        s.meshOptions.grow = parseGrow(rd, *g);
    return s;
}

Camera cameraAt(const SceneDesc& scene, const Camera& base, double t) {
    Camera c = base;
    const std::vector<CameraKey>& keys = scene.cameraKeys;
    if (!keys.empty()) {
        std::size_t i = 0;
        while (i + 1 < keys.size() && keys[i + 1].time <= t)
            ++i;
        const CameraKey& a = keys[i];
        const CameraKey& b = keys[std::min(i + 1, keys.size() - 1)];
        const double u = b.time > a.time ? std::clamp((t - a.time) / (b.time - a.time), 0.0, 1.0) : 0.0;
        c.eye = a.eye + (b.eye - a.eye) * u;
        c.target = a.target + (b.target - a.target) * u;
    }
    if (scene.turntableDegPerSecond != 0.0) {
        const double angle = scene.turntableDegPerSecond * t * M_PI / 180.0;
        const glm::dvec3 up = glm::normalize(c.up), d = c.eye - c.target;
        const glm::dvec3 along = up * glm::dot(up, d), across = d - along;
        c.eye = c.target + along + across * std::cos(angle) + glm::cross(up, across) * std::sin(angle);
    }
    return c;
}

void requireSceneFiles(const SceneDesc& scene) {
    const auto check = [&](const char* key, const std::filesystem::path& path,
                           const std::string& written, const std::string& relativeTo) {
        std::error_code ec;
        if (std::filesystem::is_regular_file(path, ec))
            return;
        const std::filesystem::path tried = std::filesystem::absolute(path, ec).lexically_normal();
        const bool relative = !written.empty() && std::filesystem::path(written).is_relative();
        throw InputError(cat(scene.file.empty() ? std::string("scene") : scene.file, ": ", key,
                             " '", written.empty() ? path.string() : written, "' ",
                             relative ? cat("(relative to ", relativeTo, ") ") : std::string(),
                             "is not a file: tried ", tried.string()));
    };
    const bool generated = scene.mesh.rfind("generated:", 0) == 0;
    if (!generated && scene.mesh.find('%') == std::string::npos)
        check("mesh", scene.mesh, scene.meshWritten, scene.meshRelativeTo);
    check("preset", scene.preset, scene.presetWritten, scene.presetRelativeTo);
}

std::string checkAnimation(const SceneDesc& scene, const AnimatedMesh& mesh) {
    const AnimationDesc& a = scene.animation;
    if (!a.given)
        return {};
    const std::string where = scene.file.empty() ? std::string("scene") : scene.file;
    const bool hasClip = mesh.animated() || !mesh.clipNames().empty() || mesh.frameCount() > 0;
    if (!hasClip && !a.clip.empty())
        throw InputError(cat(where, ": animation.clip '", a.clip, "' names a clip, but mesh ",
                             scene.mesh, " has none (it does not move; a glTF file or a mesh "
                             "cache walk.%04d.ply brings one)"));
    if (!hasClip && a.restFrameGiven)
        throw InputError(cat(where, ": animation.rest_frame is a mesh cache's, and mesh ",
                             scene.mesh, " is not one"));
    if (!hasClip && !scene.wind.on() && !scene.cameraMoves())
        return cat(where, ": warning: its \"animation\" block has no effect: mesh ", scene.mesh,
                   " does not move, and neither wind nor camera keys nor a turntable do");
    return {};
}

SceneDesc loadScene(const std::filesystem::path& file) {
    const std::string text = readFileCapped(file, kMaxSceneBytes);
    return parseScene(text, file.string(), file.parent_path());
}

} // namespace spot::noise
