// The bakes of `spotshell bench` (bench_bake.h).
#include "bench_bake.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>

#include <glm/glm.hpp>
#include <nlohmann/json.hpp>

#include "noise/bake.h"
#include "noise/error.h"
#include "noise/impulses.h"
#include "noise/mesh.h"
#include "noise/system.h"

namespace spot::cmd {

namespace fs = std::filesystem;

std::string benchBakeKey(const BenchBakeInputs& in) {
    std::uint32_t voxelBits = 0;
    static_assert(sizeof voxelBits == sizeof in.voxelSize);
    std::memcpy(&voxelBits, &in.voxelSize, sizeof voxelBits);
    // Each field with its length, so no two different inputs make the same text.
    const std::string text = cat("bench-bake ", kBenchBakeVersion, " mesh ", in.mesh.size(), ":",
                                 in.mesh, " preset ", in.preset.size(), ":", in.preset, " seed ",
                                 in.seed, " voxel ", voxelBits, " levels ", in.levels);
    char hex[17];
    std::snprintf(hex, sizeof hex, "%016llx",
                  static_cast<unsigned long long>(noise::fnv1a64(text)));
    return hex;
}

double meshLongestSide(const noise::Mesh& mesh) {
    if (mesh.positions.empty())
        return 0.0;
    glm::vec3 lo(std::numeric_limits<float>::max()), hi(-std::numeric_limits<float>::max());
    for (const glm::vec3& p : mesh.positions) {
        lo = glm::min(lo, p);
        hi = glm::max(hi, p);
    }
    const glm::vec3 d = hi - lo;
    return double(std::max(d.x, std::max(d.y, d.z)));
}

float voxelSizeForResolution(const noise::Mesh& mesh, int resolution) {
    const float v = resolution > 0 ? float(meshLongestSide(mesh) / double(resolution)) : 0.0f;
    if (!(v > 0.0f) || !std::isfinite(v))
        throw InputError(cat("the mesh ", mesh.name, " has no extent to divide into ", resolution,
                             " voxels"));
    return v;
}

BenchBake benchBake(const fs::path& cacheDir, const noise::ImpulseGenerator& generator,
                    const BenchBakeInputs& inputs, const std::string& presetName) {
    const std::string key = benchBakeKey(inputs);
    BenchBake b;
    b.file = cacheDir / cat("bake-", key, ".vdb");
    const fs::path meta = cacheDir / cat("bake-", key, ".json");
    std::error_code ec;
    if (fs::exists(meta, ec) && fs::exists(b.file, ec)) {
        try {
            const nlohmann::json m = nlohmann::json::parse(readFileCapped(meta, 1 << 20));
            b.seconds = m.at("seconds").get<double>();
            b.bytes = fs::file_size(b.file);
            b.cached = true;
            return b;
        } catch (const std::exception&) {
            // An unreadable record: bake again and overwrite both.
        }
    }
    noise::BakeOptions options;
    options.voxelSize = inputs.voxelSize;
    options.levels = inputs.levels;
    options.presetName = presetName;
    options.presetHash = noise::fnv1a64(inputs.preset);
    options.meshHash = noise::shellHash(noise::meshHash(generator.mesh()), generator.cellSize());
    noise::BakeStats stats;
    const noise::BakedVolume volume = noise::bakeNoise(generator, options, {}, &stats);
    noise::writeBakedGrids(b.file, volume);
    b.seconds = stats.seconds;
    b.bytes = fs::file_size(b.file);
    const nlohmann::json m = {{"key", key},
                              {"seconds", stats.seconds},
                              {"voxel_size", inputs.voxelSize},
                              {"levels", inputs.levels},
                              {"seed", inputs.seed},
                              {"preset", presetName},
                              {"bytes", b.bytes}};
    writeFileAtomic(meta, [&](std::ostream& o) { o << m.dump(2) << "\n"; });
    return b;
}

} // namespace spot::cmd
