#include "scene_job.h"

#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstdio>
#include <utility>

#include "noise/camera.h"
#include "noise/error.h"

namespace spot::cli {

std::vector<OptionSpec> sceneOptions() {
    return {{"scene", "FILE", "scene JSON (presets/scenes/*.json)", true},
            {"mesh", "FILE",
             "override the scene's mesh (.obj/.ply, .gltf/.glb, a cache walk.%04d.ply, or "
             "generated:NAME)",
             false},
            {"preset", "FILE", "override the scene's preset", false},
            {"size", "WxH", "override the image size, e.g. 640x480", false},
            {"seed", "N", "override the impulse seed", false},
            {"unlit", "",
             "drop the scene's lights and sky: emission and absorption only (shading.mode "
             "\"unlit\")",
             false}};
}

bool SceneJob::cellVisible(const noise::SurfaceCell& cell) const {
    if (scene.shading.castsShadows())
        return true; // a cell out of view may shadow one in view
    const double h = generator->cellSize();
    if (deformer) {
        glm::vec3 lo, hi;
        noise::posedCellBounds(generator->cells(), cell, mesh.triangles,
                               deformer->posed().positions, lo, hi);
        return rays->boxMayBeVisible(glm::dvec3(lo) - h, glm::dvec3(hi) + h);
    }
    return rays->boxMayBeVisible(glm::dvec3(cell.ijk) * h - h, glm::dvec3(cell.ijk + 1) * h + h);
}

void SceneJob::poseAt(double t) {
    if (scene.cameraMoves()) {
        scene.camera = noise::cameraAt(scene, baseCamera, t);
        rays = std::make_unique<noise::CameraRays>(scene.camera);
    }
    if (!cpuImpulses || !moves())
        return;
    const auto start = std::chrono::steady_clock::now();
    if (deformer)
        deformer->pose(t);
    visibleCells = 0;
    for (const noise::SurfaceCell& cell : generator->cells().cells)
        visibleCells += cellVisible(cell);
    impulses = generator->generate([&](const noise::SurfaceCell& cell) { return cellVisible(cell); });
    if (deformer)
        impulses = deformer->move(impulses, generator->cellSize(), scene.wind);
    generateSeconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

SceneJob::SceneJob(noise::SceneDesc desc, bool withCpuImpulses)
    : scene(std::move(desc)), cpuImpulses(withCpuImpulses) {
    baseCamera = scene.camera;
    rays = std::make_unique<noise::CameraRays>(scene.camera);
    noise::requireSceneFiles(scene);
    animation = noise::AnimatedMesh::load(scene.mesh, scene.animation.clip, scene.animation.fps,
                                          scene.animation.restFrame, scene.meshOptions);
    if (const std::string warning = noise::checkAnimation(scene, animation); !warning.empty())
        std::fprintf(stderr, "%s\n", warning.c_str());
    if (animation.rest().weldReport.refused > 0) {
        const noise::WeldReport& w = animation.rest().weldReport;
        std::fprintf(stderr,
                     "%s: warning: %zu positions keep split vertices, whose skins, morph targets "
                     "or frames differ (first: vertices %u and %u); the shell may crack there\n",
                     scene.mesh.c_str(), w.refused, w.refusedA, w.refusedB);
    }
    mesh = animation.rest();
    preset = noise::loadPreset(scene.preset);
    noise::GeneratorOptions options;
    options.seed = scene.seed;
    const auto start = std::chrono::steady_clock::now();
    generator = std::make_unique<noise::ImpulseGenerator>(mesh, preset, options);
    if (animation.animated() || scene.wind.on())
        deformer = std::make_unique<noise::Deformer>(animation);
    if (moves()) {
        poseAt(scene.animation.time);
        if (cpuImpulses)
            return;
    }
    for (const noise::SurfaceCell& cell : generator->cells().cells)
        visibleCells += cellVisible(cell);
    if (cpuImpulses)
        impulses =
            generator->generate([&](const noise::SurfaceCell& cell) { return cellVisible(cell); });
    generateSeconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

std::vector<OptionSpec> timeOptions() {
    return {{"time", "T",
             "seconds into the mesh's clip (default: the scene's animation.time; clamped to the "
             "clip)",
             false},
            {"frames", "A-B[:STEP]",
             "render frames A to B (every STEP-th; frame f at f / animation.fps seconds) in one "
             "process, to --out's %d pattern; refused outside the mesh's clip (or the camera "
             "keys' span when they alone move), unlike --time, which is clamped",
             false},
            {"resume", "",
             "skip the frames whose output is already there and complete (outputs are written "
             "atomically: a killed run leaves none half-written)",
             false}};
}

namespace {

/// `pattern` with its one printf integer conversion (%d, %04d) replaced by `frame`.
std::string frameFile(const std::string& pattern, long frame) {
    const std::size_t p = pattern.find('%');
    std::size_t e = p + 1;
    while (e < pattern.size() && std::isdigit(static_cast<unsigned char>(pattern[e])))
        ++e;
    if (p == std::string::npos || e >= pattern.size() || pattern[e] != 'd' ||
        pattern.find('%', e) != std::string::npos || e - p > 4)
        throw InputError(cat("--out '", pattern,
                             "' must name the frames with one %d or %0Nd (shot.%04d.exr)"));
    const int width = e > p + 1 ? std::stoi(pattern.substr(p + 1, e - p - 1)) : 0;
    std::string number = std::to_string(std::labs(frame));
    if (int(number.size()) < width)
        number.insert(0, std::size_t(width) - number.size(), '0');
    return pattern.substr(0, p) + (frame < 0 ? "-" : "") + number + pattern.substr(e + 1);
}

} // namespace

std::optional<FrameSpan> frameSpan(const SceneJob& job) {
    const double fps = job.scene.animation.fps;
    const double eps = 1e-9;
    if (job.animation.animated()) {
        const std::string& clip = job.animation.clipName();
        const noise::FrameRange range = noise::clipFrames(job.animation, fps);
        return FrameSpan{range.first, range.last,
                         clip.empty() ? std::string("the mesh's clip")
                                      : cat("the clip '", clip, "'")};
    }
    const auto& keys = job.scene.cameraKeys;
    if (keys.size() < 2 || job.scene.wind.on() || job.scene.turntableDegPerSecond != 0.0 ||
        !(keys.back().time > keys.front().time))
        return std::nullopt;
    return FrameSpan{long(std::ceil(keys.front().time * fps - eps)),
                     long(std::floor(keys.back().time * fps + eps)), "the camera keys"};
}

Shot shotOf(const Args& args, const noise::AnimationDesc& animation, const std::string& out,
            const std::optional<FrameSpan>& span) {
    Shot shot;
    if (args.has("time") && args.has("frames"))
        throw InputError("give --time or --frames, not both");
    if (!args.has("frames")) {
        ShotFrame f;
        f.time = args.has("time") ? args.number("time", 0.0, -1e6, 1e6) : animation.time;
        f.frame = std::lround(f.time * animation.fps);
        f.file = out;
        shot.frames.push_back(f);
        return shot;
    }
    const std::string range = args.str("frames");
    long a = 0, b = 0, step = 1;
    char dash = 0, colon = 0, extra = 0;
    const int n = std::sscanf(range.c_str(), "%ld%c%ld%c%ld%c", &a, &dash, &b, &colon, &step, &extra);
    const bool ok = (n == 3 && dash == '-') || (n == 5 && dash == '-' && colon == ':');
    if (!ok || step < 1 || b < a)
        throw InputError(cat("--frames '", range, "' must be A-B or A-B:STEP with A <= B, STEP >= 1"));
    if (span && (a < span->first || b > span->last))
        throw InputError(cat("--frames '", range, "' reaches outside ", span->what, ": frames ",
                             span->first, "-", span->last, " at ", animation.fps, " fps"));
    if ((b - a) / step + 1 > 100000)
        throw InputError(cat("--frames '", range, "' is more than 100000 frames"));
    for (long f = a; f <= b; f += step)
        shot.frames.push_back({f, double(f) / animation.fps, frameFile(out, f)});
    return shot;
}

SceneJob loadSceneJob(const std::filesystem::path& scene, int width, int height, bool cpuImpulses) {
    noise::SceneDesc desc = noise::loadScene(scene);
    if (width > 0 && height > 0) {
        desc.camera.width = width;
        desc.camera.height = height;
    }
    return SceneJob(std::move(desc), cpuImpulses);
}

SceneJob prepareScene(const Args& args, bool cpuImpulses) {
    noise::SceneDesc desc = noise::loadScene(args.str("scene"));
    if (args.has("mesh")) {
        desc.mesh = args.str("mesh");
        desc.meshWritten = desc.mesh;
        desc.meshRelativeTo = "the current folder";
    }
    if (args.has("preset")) {
        desc.preset = args.str("preset");
        desc.presetWritten = args.str("preset");
        desc.presetRelativeTo = "the current folder";
    }
    if (args.has("seed"))
        desc.seed = std::uint32_t(args.integer("seed", 0, 0, 0xffffffffll));
    if (args.has("unlit"))
        desc.shading = noise::Shading{};
    if (args.has("size")) {
        const std::string size = args.str("size");
        int w = 0, h = 0;
        char x = 0, extra = 0;
        if (std::sscanf(size.c_str(), "%d%c%d%c", &w, &x, &h, &extra) != 3 ||
            (x != 'x' && x != 'X') || w < 1 || h < 1 || w > 16384 || h > 16384)
            throw InputError(cat("--size '", size, "' must be WxH with sides in [1, 16384]"));
        desc.camera.width = w;
        desc.camera.height = h;
    }
    return SceneJob(std::move(desc), cpuImpulses);
}

} // namespace spot::cli
