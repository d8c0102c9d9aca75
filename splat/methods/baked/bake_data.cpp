#include "bake_data.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <unordered_map>

#include <glm/gtc/packing.hpp>

#include "noise/bake.h"
#include "noise/error.h"
#include "splat/settings.h"

namespace spot::splat {

namespace {

using namespace gpu_baked;

struct LeafKey {
    glm::ivec3 leaf;
    bool operator==(const LeafKey& o) const { return leaf == o.leaf; }
};
struct LeafKeyHash {
    std::size_t operator()(const LeafKey& k) const {
        std::uint32_t h = std::uint32_t(k.leaf.x) * 73856093u ^
                          std::uint32_t(k.leaf.y) * 19349663u ^ std::uint32_t(k.leaf.z) * 83492791u;
        h ^= h >> 16u;
        h *= 0x7feb352du;
        return h ^ (h >> 15u);
    }
};

/// A section of leaves in first-seen order (the bake's tree order: deterministic).
struct Leaves {
    std::unordered_map<LeafKey, std::uint32_t, LeafKeyHash> index;
    std::vector<glm::ivec3> keys;
    std::uint32_t brick(glm::ivec3 leaf) {
        const auto [it, added] = index.try_emplace(LeafKey{leaf}, std::uint32_t(keys.size()));
        if (added)
            keys.push_back(leaf);
        return it->second;
    }
};

/// Level by level, the density leaves of `volume` (vec4(extinction x colour, extinction) per
/// voxel) packed with their aprons into `out` in units of the bake's largest value: one leaf
/// lookup a sample. `sections` receives each level's leaves in brick order.
void packDensity(const noise::BakedVolume& volume, BakeData& out,
                 std::vector<std::vector<glm::ivec3>>& sections) {
    const int levels = out.levels;
    std::vector<Leaves> leaves(static_cast<std::size_t>(levels));
    std::vector<std::vector<glm::vec4>> bricks(static_cast<std::size_t>(levels));
    std::vector<std::vector<glm::vec4>> shading(static_cast<std::size_t>(levels));
    out.shaded = volume.hasShading();
    for (int l = 0; l < levels; ++l) {
        volume.forEachActiveShaded(l, [&](glm::ivec3 ijk, float density, glm::vec3 color,
                                          glm::vec3 tangent, glm::vec3 normal) {
            const std::uint32_t b = leaves[std::size_t(l)].brick(ijk >> int(kBakedLeafBits));
            auto& data = bricks[std::size_t(l)];
            auto& axes = shading[std::size_t(l)];
            if (data.size() < std::size_t(b + 1) * kBakedLeafVoxels) {
                data.resize(std::size_t(b + 1) * kBakedLeafVoxels, glm::vec4(0.0f));
                if (out.shaded)
                    axes.resize(data.size(), glm::vec4(0.0f));
            }
            const glm::ivec3 o = ijk & 7;
            const std::size_t at =
                std::size_t(b) * kBakedLeafVoxels + std::size_t(o.x << 6 | o.y << 3 | o.z);
            data[at] = glm::vec4(density * color, density);
            if (out.shaded)
                axes[at] = glm::vec4(density * (tangent + normal), 0.0f);
        });
    }
    float largest = 0.0f;
    for (const auto& data : bricks)
        for (const glm::vec4& v : data)
            largest =
                std::max({largest, std::abs(v.r), std::abs(v.g), std::abs(v.b), std::abs(v.a)});
    out.unit = brickUnit(largest);
    out.packed.resize(static_cast<std::size_t>(levels));
    for (int l = 0; l < levels; ++l) {
        ApronBricks level =
            packApronBricks(leaves[std::size_t(l)].keys, bricks[std::size_t(l)], out.unit);
        out.brickCount += level.leaves.size();
        if (out.shaded) {
            // The same leaves in the same order: the same bricks, the same apron layout.
            ApronBricks axes =
                packApronBricks(leaves[std::size_t(l)].keys, shading[std::size_t(l)], out.unit);
            out.shadingPacked.push_back(std::move(axes.voxels));
        }
        sections[std::size_t(l)] = std::move(level.leaves);
        out.packed[std::size_t(l)] = std::move(level.voxels);
    }
}

/// The distance leaves: every leaf within 3 voxels of a non-empty level-0 voxel (nearer than the
/// cap), filled from the bake's distance grid; leaves that hold only the cap are left out (a
/// lookup that finds no leaf reads the cap). Returns their leaves in brick order.
std::vector<glm::ivec3> packDistances(const noise::BakedVolume& volume, BakeData& out) {
    const float cap = noise::kBakeDistanceCap;
    const int reach = int(cap) - 1;
    Leaves candidates;
    volume.forEachActive(0, [&](glm::ivec3 ijk, float, glm::vec3) {
        for (int c = 0; c < 8; ++c) {
            const glm::ivec3 d((c & 4) ? reach : -reach, (c & 2) ? reach : -reach,
                               (c & 1) ? reach : -reach);
            candidates.brick((ijk + d) >> int(kBakedLeafBits));
        }
    });
    Leaves distanceLeaves;
    std::vector<float> one(kBakedLeafVoxels);
    for (const glm::ivec3& leaf : candidates.keys) {
        bool any = false;
        for (std::uint32_t v = 0; v < kBakedLeafVoxels; ++v) {
            const glm::ivec3 ijk = leaf * 8 + glm::ivec3(int(v >> 6), int(v >> 3) & 7, int(v) & 7);
            one[v] = volume.distance(ijk);
            any = any || one[v] < cap;
        }
        if (!any)
            continue;
        distanceLeaves.brick(leaf);
        out.distances.insert(out.distances.end(), one.begin(), one.end());
    }
    out.distanceBricks = std::uint32_t(distanceLeaves.keys.size());
    return std::move(distanceLeaves.keys);
}

/// The leaf tables: per section (the levels, then the distance grid) the dense box of its
/// leaves, an int each (the brick, or empty).
void buildTables(const std::vector<std::vector<glm::ivec3>>& sections, BakeData& out) {
    const std::size_t levels = std::size_t(out.levels);
    std::vector<std::int32_t>& table = out.table;
    out.leafOrigin.assign(kBakedSections, glm::ivec4(0));
    out.leafDims.assign(kBakedSections, glm::ivec4(0));
    out.firstBrick.assign(levels + 1, 0);
    std::uint32_t base = 0;
    for (std::size_t s = 0; s < sections.size(); ++s) {
        const std::uint32_t id = s < levels ? std::uint32_t(s) : kBakedDistanceSection;
        const std::vector<glm::ivec3>& keys = sections[s];
        out.firstBrick[s] = s < levels ? base : 0;
        out.leafOrigin[id].w = std::int32_t(table.size());
        glm::i64vec3 d(0);
        if (!keys.empty()) {
            glm::ivec3 lo = keys[0], hi = keys[0];
            for (const glm::ivec3& k : keys) {
                lo = glm::min(lo, k);
                hi = glm::max(hi, k);
            }
            d = glm::i64vec3(hi) - glm::i64vec3(lo) + std::int64_t(1);
            const std::uint64_t entries = std::uint64_t(d.x * d.y * d.z);
            // No table outgrows one storage buffer (checked on upload): far less than this.
            if ((table.size() + entries) * sizeof(std::int32_t) > (std::uint64_t(1) << 32)) {
                out.tableEnd.push_back(table.size() + entries);
                out.sectionBox.push_back(d);
                return;
            }
            const std::size_t offset = table.size();
            table.resize(offset + entries, kBakedEmptySlot);
            for (std::uint32_t b = 0; b < keys.size(); ++b) {
                const glm::i64vec3 r = glm::i64vec3(keys[b]) - glm::i64vec3(lo);
                table[offset + std::size_t((r.z * d.y + r.y) * d.x + r.x)] =
                    std::int32_t(out.firstBrick[s] + b);
            }
            out.leafOrigin[id] = glm::ivec4(lo, std::int32_t(offset));
            out.leafDims[id] = glm::ivec4(glm::ivec3(d), 0);
        }
        out.tableEnd.push_back(table.size());
        out.sectionBox.push_back(d);
        if (s < levels)
            base += std::uint32_t(keys.size());
    }
    if (table.empty())
        table.push_back(kBakedEmptySlot);
}

} // namespace

std::vector<std::uint32_t> solidVoxels(const std::vector<glm::vec3>& positions,
                                       const std::vector<glm::uvec3>& triangles, glm::ivec3 lo,
                                       glm::ivec3 n, float size) {
    const std::size_t nx = std::size_t(std::max(n.x, 0)), ny = std::size_t(std::max(n.y, 0)),
                      nz = std::size_t(std::max(n.z, 0));
    // Per column (y, z) of voxel centres, the x where a triangle crosses it.
    std::vector<std::vector<double>> crossings(ny * nz);
    const double h = double(size);
    for (const glm::uvec3& t : triangles) {
        const glm::dvec3 a(positions[t.x]), b(positions[t.y]), c(positions[t.z]);
        const glm::dvec3 mn = glm::min(a, glm::min(b, c)), mx = glm::max(a, glm::max(b, c));
        const int y0 = std::max(0, int(std::ceil(mn.y / h - 0.5)) - lo.y);
        const int y1 = std::min(int(ny) - 1, int(std::floor(mx.y / h - 0.5)) - lo.y);
        const int z0 = std::max(0, int(std::ceil(mn.z / h - 0.5)) - lo.z);
        const int z1 = std::min(int(nz) - 1, int(std::floor(mx.z / h - 0.5)) - lo.z);
        // The triangle projected on yz: edge functions, and x from the barycentrics.
        const double area = (b.y - a.y) * (c.z - a.z) - (c.y - a.y) * (b.z - a.z);
        if (area == 0.0)
            continue;
        for (int z = z0; z <= z1; ++z)
            for (int y = y0; y <= y1; ++y) {
                const double py = (double(y + lo.y) + 0.5) * h, pz = (double(z + lo.z) + 0.5) * h;
                const double wa = ((b.y - py) * (c.z - pz) - (c.y - py) * (b.z - pz)) / area;
                const double wb = ((c.y - py) * (a.z - pz) - (a.y - py) * (c.z - pz)) / area;
                const double wc = 1.0 - wa - wb;
                if (wa < 0.0 || wb < 0.0 || wc < 0.0)
                    continue;
                crossings[std::size_t(z) * ny + std::size_t(y)].push_back(wa * a.x + wb * b.x +
                                                                          wc * c.x);
            }
    }
    std::vector<unsigned char> inside(nx * ny * nz, 0);
    for (std::size_t z = 0; z < nz; ++z)
        for (std::size_t y = 0; y < ny; ++y) {
            std::vector<double>& xs = crossings[z * ny + y];
            std::sort(xs.begin(), xs.end());
            std::size_t passed = 0; // crossings at or before the centre
            for (std::size_t x = 0; x < nx; ++x) {
                const double px = (double(int(x) + lo.x) + 0.5) * h;
                while (passed < xs.size() && xs[passed] <= px)
                    ++passed;
                inside[(z * ny + y) * nx + x] = (xs.size() - passed) % 2 == 1 ? 1 : 0;
            }
        }
    std::vector<std::uint32_t> bits((nx * ny * nz + 31) / 32 + 1, 0u);
    for (std::size_t bit = 0; bit < inside.size(); ++bit)
        if (inside[bit] != 0)
            bits[bit >> 5] |= 1u << (bit & 31);
    return bits;
}

float brickUnit(float largest) {
    if (!(largest > 0.0f) || !std::isfinite(largest))
        return 1.0f;
    return std::max(largest / 32768.0f, std::numeric_limits<float>::min());
}

ApronBricks packApronBricks(const std::vector<glm::ivec3>& leaves,
                            const std::vector<glm::vec4>& data, float unit) {
    Leaves stored;
    for (const glm::ivec3& key : leaves)
        stored.brick(key);
    const auto step = [](int n) { return glm::ivec3(n >> 2, (n >> 1) & 1, n & 1); };
    Leaves withApron;
    for (const glm::ivec3& key : leaves)
        for (int n = 0; n < 8; ++n)
            withApron.brick(key - step(n));
    ApronBricks out;
    out.voxels.resize(withApron.keys.size() * kBakedBrickVoxels);
    const int side = int(kBakedBrickSide);
    for (std::size_t b = 0; b < withApron.keys.size(); ++b) {
        // The leaf and its neighbours towards +x, +y, +z (index 4 x + 2 y + z), if stored.
        std::array<const glm::vec4*, 8> around{};
        for (int n = 0; n < 8; ++n) {
            const auto it = stored.index.find(LeafKey{withApron.keys[b] + step(n)});
            around[std::size_t(n)] = it == stored.index.end()
                                         ? nullptr
                                         : data.data() + std::size_t(it->second) * kBakedLeafVoxels;
        }
        for (int x = 0; x < side; ++x)
            for (int y = 0; y < side; ++y)
                for (int z = 0; z < side; ++z) {
                    const glm::vec4* leaf =
                        around[std::size_t((x >> 3) << 2 | (y >> 3) << 1 | (z >> 3))];
                    const glm::vec4 v =
                        leaf ? leaf[(x & 7) << 6 | (y & 7) << 3 | (z & 7)] / unit : glm::vec4(0.0f);
                    out.voxels[b * kBakedBrickVoxels + std::size_t((x * side + y) * side + z)] =
                        glm::uvec2(glm::packHalf2x16(glm::vec2(v.r, v.g)),
                                   glm::packHalf2x16(glm::vec2(v.b, v.a)));
                }
    }
    out.leaves = std::move(withApron.keys);
    return out;
}

std::shared_ptr<const BakeData> BakeData::load(const std::string& file) {
    const noise::BakedVolume volume = noise::readBakedGrids(file);
    auto out = std::make_shared<BakeData>();
    out->file = file;
    out->levels = volume.levels();
    out->voxelSize = volume.voxelSize(0);
    out->meshHash = volume.meshHash();
    // Each section's leaves in brick order: the levels' bricks, then the distance grid's.
    std::vector<std::vector<glm::ivec3>> sections(std::size_t(out->levels) + 1);
    packDensity(volume, *out, sections);
    sections.back() = packDistances(volume, *out);
    buildTables(sections, *out);
    return out;
}

namespace settings {

const Setting bake = [] {
    Setting s;
    s.name = "bake";
    s.type = SettingType::File;
    s.value = "FILE";
    s.help = "the bake to render (an OpenVDB file from spotshell bake), read once";
    s.getText = [](const RenderSettings& r) { return r.bake ? r.bake->file : std::string(); };
    s.setText = [](RenderSettings& r, const std::string& file) {
        r.bake = file.empty() ? nullptr : BakeData::load(file);
    };
    return s;
}();

} // namespace settings

} // namespace spot::splat
