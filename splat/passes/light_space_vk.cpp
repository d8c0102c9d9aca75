#include "light_space_vk.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <iostream>
#include <limits>

#include "light_deposit.comp.h"
#include "light_mesh.comp.h"
#include "light_place.comp.h"
#include "light_prefix.comp.h"
#include "light_tiles.comp.h"
#include "light_tiles_mesh.comp.h"
#include "noise/error.h"
#include "noise/kernel.h"
#include "shaders/spot_layout.hpp"
#include "splat/pass_vk.h"

namespace spot::splat {

namespace {

using namespace gpu;

constexpr VkBufferUsageFlags kStorage = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT;
constexpr VkBufferUsageFlags kCleared = kStorage | VK_BUFFER_USAGE_TRANSFER_DST_BIT;
/// A dispatch has at most 65,535 workgroups along x; the passes index along x and y.
constexpr std::uint32_t kMaxGroupsX = 65535;
/// The item list's dispatch is one-dimensional: at most this many items.
constexpr std::uint64_t kMaxItems = std::uint64_t(kMaxGroupsX) * kShadowGroup;
/// The stages that look the structure up: the lit prepare (compute) and the lit mesh pass, its
/// sky per vertex and its lights per pixel.
constexpr VkPipelineStageFlags2 kLookups = passes::kCompute | passes::kFragment |
                                           VK_PIPELINE_STAGE_2_VERTEX_SHADER_BIT;

/// A unit basis (u, w) perpendicular to unit d.
void basis(glm::dvec3 d, glm::dvec3& u, glm::dvec3& w) {
    const glm::dvec3 a = std::abs(d.y) < 0.9 ? glm::dvec3(0, 1, 0) : glm::dvec3(1, 0, 0);
    u = glm::normalize(glm::cross(a, d));
    w = glm::cross(d, u);
}

SpotShadowView view(glm::dvec3 travel, std::uint32_t texels, std::uint32_t layers, float thickness) {
    glm::dvec3 u, w;
    basis(travel, u, w);
    SpotShadowView v{};
    v.axisU = glm::vec4(glm::vec3(u), float(texels));
    v.axisW = glm::vec4(glm::vec3(w), float(layers));
    v.axisD = glm::vec4(glm::vec3(travel), thickness);
    return v;
}

void dispatch(VkCommandBuffer cmd, std::uint64_t invocations) {
    const std::uint64_t groups = (invocations + kShadowGroup - 1) / kShadowGroup;
    if (groups == 0)
        return;
    const std::uint32_t x = std::uint32_t(std::min<std::uint64_t>(groups, kMaxGroupsX));
    vkCmdDispatch(cmd, x, std::uint32_t((groups + x - 1) / x), 1);
}

} // namespace

namespace {
thread_local bool t_hold = false;
} // namespace

LightSpaceHold::LightSpaceHold() : m_previous(t_hold) { t_hold = true; }
LightSpaceHold::~LightSpaceHold() { t_hold = m_previous; }
bool LightSpaceHold::active() { return t_hold; }

LightSpace::LightSpace(const SceneGpu& scene) : m_scene(scene), m_ctx(scene.context()) {
    Bindings common = lookupBindings();
    const auto with = [&](std::initializer_list<Binding> extra) {
        Bindings b = common;
        b.insert(b.end(), extra.begin(), extra.end());
        return b;
    };
    const std::uint32_t push = sizeof(SpotShadowPush);
    m_place = makeComputePipeline(
        m_ctx, spirv(spv_light_place_comp),
        with({storageBuffer(kShadowBindImpulses), storageBuffer(kShadowBindLobes),
              storageBuffer(kShadowBindCount), storageBuffer(kShadowBindPlaced)}),
        push);
    m_tiles = makeComputePipeline(m_ctx, spirv(spv_light_tiles_comp),
                                  with({storageBuffer(kShadowBindItems),
                                        storageBuffer(kShadowBindCount),
                                        storageBuffer(kShadowBindPlaced)}),
                                  push);
    m_tilesMesh = makeComputePipeline(m_ctx, spirv(spv_light_tiles_mesh_comp),
                                      with({storageBuffer(kShadowBindItems),
                                            storageBuffer(kShadowBindVertices),
                                            storageBuffer(kShadowBindIndices)}),
                                      push);
    m_meshPass = makeComputePipeline(
        m_ctx, spirv(spv_light_mesh_comp),
        with({storageBuffer(kShadowBindItems), storageBuffer(kShadowBindVertices),
              storageBuffer(kShadowBindIndices)}),
        push);
    m_deposit = makeComputePipeline(
        m_ctx, spirv(spv_light_deposit_comp),
        with({storageBuffer(kShadowBindItems), storageBuffer(kShadowBindPlaced)}), push);
    m_prefix = makeComputePipeline(m_ctx, spirv(spv_light_prefix_comp), common, push);
    // The parameters (each frame's), then the own-shadow table (the kernel's support's).
    const std::vector<float>& table = noise::ownShadowTable(m_scene.support());
    m_paramsBuffer = Buffer(m_ctx, sizeof(SpotLitParams) + sizeof(float) * table.size(), kStorage,
                            Buffer::Memory::HostVisible, "light space parameters");
    std::memcpy(static_cast<std::byte*>(m_paramsBuffer.mapped()) + sizeof(SpotLitParams),
                table.data(), sizeof(float) * table.size());
}

Bindings LightSpace::lookupBindings() {
    return {storageBuffer(kShadowBindParams), storageBuffer(kShadowBindExtents),
            storageBuffer(kShadowBindLayers), storageBuffer(kShadowBindFirst)};
}

Descriptors& LightSpace::bindLookup(Descriptors& d) const {
    return d.buffer(kShadowBindParams, m_paramsBuffer)
        .buffer(kShadowBindExtents, m_extents)
        .buffer(kShadowBindLayers, m_layers)
        .buffer(kShadowBindFirst, m_first);
}

void LightSpace::prepare(const noise::Shading& shading, const ImpulseSet& impulses,
                         const LightSpaceSettings& settings) {
    if (settings.layers < 1 || settings.layers > kShadowMaxLayers)
        throw InputError(cat("light space: ", settings.layers, " layers outside [1, ",
                             kShadowMaxLayers, "]"));
    const auto texelsOk = [](std::uint32_t r) { return r >= 4 && r <= 4096; };
    if (!texelsOk(settings.lightTexels) || !texelsOk(settings.skyTexels))
        throw InputError("light space: texels per side outside [4, 4096]");
    if (shading.lights.size() > 8)
        throw InputError(cat("light space: ", shading.lights.size(), " lights, at most 8"));
    itemsNeeded(); // the last frame's: grows the list when it had too little room
    const noise::Kernel& kernel = m_scene.kernel();
    const float h = impulses.cells && impulses.cells->cellSize > 0.0f
                        ? impulses.cells->cellSize
                        : kernel.supportRadius();
    const float thickness = 8.0f * h / float(settings.layers);

    SpotLitParams p{};
    std::uint32_t views = 0;
    const auto addView = [&](SpotShadowView v) {
        p.views[views] = v;
        return views++;
    };
    std::uint32_t lights = 0;
    for (const noise::Light& light : shading.lights) {
        SpotLitLight& l = p.lights[lights++];
        const bool point = light.type == noise::Light::Type::Point;
        l.where = glm::vec4(point ? light.position : light.direction, point ? 1.0f : 0.0f);
        l.radiance = glm::vec4(light.color * light.intensity, 0.0f);
        if (!light.shadows)
            continue;
        SpotShadowView v;
        if (point) {
            const noise::Bounds b = m_scene.meshBounds();
            glm::dvec3 axis = glm::dvec3(0.5f * (b.lo + b.hi)) - glm::dvec3(light.position);
            axis = glm::length(axis) > 0.0 ? glm::normalize(axis) : glm::dvec3(0, -1, 0);
            v = view(axis, settings.lightTexels, settings.layers, thickness);
            v.origin = glm::vec4(light.position, 1.0f);
        } else {
            v = view(-glm::dvec3(light.direction), settings.lightTexels, settings.layers,
                     thickness);
        }
        l.radiance.w = float(addView(v) + 1);
    }
    const std::uint32_t sky =
        shading.sky.intensity > 0.0f ? std::min(settings.skyDirections, kShadowMaxSky) : 0;
    for (std::uint32_t k = 0; k < sky; ++k) {
        // Uniform in solid angle over the upper hemisphere (a Fibonacci spiral): y uniform.
        const double y = (double(k) + 0.5) / double(sky);
        const double r = std::sqrt(std::max(0.0, 1.0 - y * y));
        const double phi = double(k) * 2.399963229728653;
        const glm::dvec3 w(r * std::cos(phi), y, r * std::sin(phi));
        p.skyDirs[k] = glm::vec4(glm::vec3(w), float(addView(view(-w, settings.skyTexels,
                                                                  settings.layers, thickness))));
    }
    p.sky = glm::vec4(shading.sky.color * shading.sky.intensity *
                          (sky > 0 ? 2.0f / float(sky) : 0.0f),
                      0.0f);
    p.counts = glm::uvec4(lights, sky, views, std::uint32_t(kernel.lobes.size()));
    for (std::size_t l = 0; l < kernel.lobes.size(); ++l) {
        const noise::LobeLitModel m = noise::lobeLitModel(kernel.lobes[l]);
        p.lobes[l].model = glm::uvec4(m.model, std::uint32_t(m.shortest), 0, 0);
        p.lobes[l].axis = glm::vec4(glm::vec3(m.tangent), 0.0f);
        p.lobes[l].primary = glm::vec4(glm::vec3(m.primary), 0.0f);
        p.lobes[l].secondary = glm::vec4(glm::vec3(m.secondary), 0.0f);
    }
    // Each view's words: its layers, its start map and its mesh map.
    std::uint64_t layerWords = 0, firstWords = 0, texels = 0;
    for (std::uint32_t v = 0; v < views; ++v) {
        const std::uint32_t r = std::uint32_t(p.views[v].axisU.w);
        const std::uint64_t tiles = (r + kShadowTile - 1) / kShadowTile;
        p.views[v].offsets = glm::uvec4(std::uint32_t(layerWords), std::uint32_t(firstWords),
                                        std::uint32_t(firstWords + tiles * tiles), r);
        layerWords += 3 * std::uint64_t(r) * r * settings.layers;
        firstWords += tiles * tiles + std::uint64_t(r) * r;
        texels += std::uint64_t(r) * r;
    }
    if (layerWords > 0xffffffffull || firstWords > 0xffffffffull)
        throw InputError("light space: the views' texels exceed 32-bit offsets");
    m_views = views;
    m_texels = std::uint32_t(texels);
    m_impulses = impulses;
    std::memcpy(m_paramsBuffer.mapped(), &p, sizeof(p));

    const auto grow = [&](Buffer& b, std::uint64_t bytes, VkBufferUsageFlags usage,
                          Buffer::Memory memory, const char* name) {
        bytes = std::max<std::uint64_t>(bytes, 16);
        if (!b.handle() || b.size() < bytes) {
            b = Buffer();
            b = Buffer(m_ctx, bytes, usage, memory, name);
        }
    };
    const auto device = Buffer::Memory::DeviceLocal;
    grow(m_extents, sizeof(SpotShadowExtent) * kShadowMaxViews, kStorage,
         Buffer::Memory::HostVisible, "light space extents");
    // Each view's extent: the mesh's box as posed grown by the kernel's reach h (every lobe's
    // support lies within h of its root on the surface; the wind turns it about the root).
    const noise::Bounds box = m_scene.meshPass().bounds();
    auto* extents = static_cast<SpotShadowExtent*>(m_extents.mapped());
    for (std::uint32_t v = 0; v < views; ++v) {
        const SpotShadowView& view = p.views[v];
        const glm::dvec3 u(view.axisU), w(view.axisW), d(view.axisD), o(view.origin);
        glm::dvec2 lo(std::numeric_limits<double>::max()), hi = -lo;
        bool perspective = view.origin.w > 0.5f, inFront = true;
        for (int c = 0; c < 8; ++c) {
            const glm::dvec3 corner((c & 1) ? box.hi.x + h : box.lo.x - h,
                                    (c & 2) ? box.hi.y + h : box.lo.y - h,
                                    (c & 4) ? box.hi.z + h : box.lo.z - h);
            glm::dvec2 xy(glm::dot(corner, u), glm::dot(corner, w));
            if (perspective) {
                const glm::dvec3 q = corner - o;
                const double z = glm::dot(q, d);
                inFront = inFront && z > 1e-3 * glm::length(q);
                xy = glm::dvec2(glm::dot(q, u), glm::dot(q, w)) / std::max(z, 1e-30);
            }
            lo = glm::min(lo, xy);
            hi = glm::max(hi, xy);
        }
        if (perspective && !inFront) { // the light lies in the box: a 90 degree frustum
            lo = glm::dvec2(-1.0);
            hi = glm::dvec2(1.0);
        }
        const auto bits = [](double x) {
            std::uint32_t b;
            const float f = float(x);
            std::memcpy(&b, &f, 4);
            return spotOrderedBits(b);
        };
        extents[v].lo = glm::uvec4(bits(lo.x), bits(lo.y), 0, 0);
        extents[v].hi = glm::uvec4(bits(hi.x), bits(hi.y), 0, 0);
    }
    grow(m_layers, 4 * layerWords, kCleared, device, "light space layers");
    grow(m_first, 4 * firstWords, kCleared, device, "light space start and mesh maps");
    const std::uint32_t lobes = std::uint32_t(kernel.lobes.size());
    m_capacity = impulses.capacity;
    grow(m_placed, std::uint64_t(std::max(m_capacity, 1u)) * lobes * sizeof(SpotWorldLobe), kStorage,
         device, "light space placed lobes");
    // Room for four tiles per lobe and triangle per view (a lobe thinner than a tile meets one
    // or two); itemsNeeded() grows it when a frame needed more.
    const auto room = [&](std::uint32_t& capacity, std::uint64_t sources, Buffer& list,
                          const char* name) {
        capacity = std::uint32_t(std::min<std::uint64_t>(
            std::max<std::uint64_t>(capacity, 4 * sources * views + 4096), kMaxItems));
        grow(list, sizeof(SpotShadowList) + 8 * std::uint64_t(capacity),
             kCleared | VK_BUFFER_USAGE_INDIRECT_BUFFER_BIT, Buffer::Memory::HostVisible, name);
    };
    room(m_itemCapacity, std::uint64_t(m_capacity) * lobes, m_items, "light space lobe items");
    room(m_meshItemCapacity, m_scene.meshPass().indexCount() / 3, m_meshItems,
         "light space triangle items");

    // What the structure is built from: the views and lights, the impulses (their version
    // changes with them and with the pose; 0 says unknown) and where it lives. The same as the
    // last build's: record() keeps it (the camera alone moved, or nothing did).
    // The structure's buffers first: with the parameters and extents, what a lookup reads.
    struct Sources {
        VkBuffer layers, first, impulses, count, placed, items, meshItems, vertices;
        std::uint64_t version;
        std::uint32_t capacity, itemCapacity, meshItemCapacity;
    } sources{};
    sources.impulses = impulses.impulses->handle();
    sources.count = impulses.count->handle();
    sources.layers = m_layers.handle();
    sources.first = m_first.handle();
    sources.placed = m_placed.handle();
    sources.items = m_items.handle();
    sources.meshItems = m_meshItems.handle();
    sources.vertices = m_scene.meshPass().vertices().handle();
    sources.version = impulses.version;
    sources.capacity = m_capacity;
    sources.itemCapacity = m_itemCapacity;
    sources.meshItemCapacity = m_meshItemCapacity;
    std::vector<std::byte> key(sizeof(p) + sizeof(SpotShadowExtent) * views + sizeof(sources));
    std::memcpy(key.data(), &p, sizeof(p));
    std::memcpy(key.data() + sizeof(p), extents, sizeof(SpotShadowExtent) * views);
    std::memcpy(key.data() + key.size() - sizeof(sources), &sources, sizeof(sources));
    const std::size_t lookupBytes = key.size() - sizeof(sources) + 2 * sizeof(VkBuffer);
    m_current = impulses.version != 0 && key == m_built;
    if (!m_current && LightSpaceHold::active() && m_built.size() == key.size() &&
        std::equal(key.begin(), key.begin() + std::ptrdiff_t(lookupBytes), m_built.begin()))
        m_current = true; // held: the last build stands for these impulses
    m_key = std::move(key);
}

void LightSpace::record(VkCommandBuffer cmd, PassTimer& timer) {
    using namespace passes;
    if (m_views == 0 || !m_impulses.impulses)
        return; // no shadows: nothing is looked up
    if (m_current) { // built from the same sources by an earlier frame: made visible again
        memoryBarrier(cmd, kAll, VK_ACCESS_2_MEMORY_WRITE_BIT, kLookups, kStorageRead);
        return;
    }
    m_built = m_key;
    memoryBarrier(cmd, kAll, VK_ACCESS_2_MEMORY_READ_BIT | VK_ACCESS_2_MEMORY_WRITE_BIT, kTransfer,
                  VK_ACCESS_2_TRANSFER_WRITE_BIT);
    vkCmdFillBuffer(cmd, m_layers.handle(), 0, VK_WHOLE_SIZE, 0u);
    vkCmdFillBuffer(cmd, m_first.handle(), 0, VK_WHOLE_SIZE, 0xffffffffu);
    const SpotShadowList empty{0u, 1u, 1u, 0u};
    vkCmdUpdateBuffer(cmd, m_items.handle(), 0, sizeof(empty), &empty);
    vkCmdUpdateBuffer(cmd, m_meshItems.handle(), 0, sizeof(empty), &empty);
    memoryBarrier(cmd, kTransfer, VK_ACCESS_2_TRANSFER_WRITE_BIT, kCompute, kStorageRW);

    const MeshPass& mesh = m_scene.meshPass();
    const std::uint32_t lobes = m_scene.lobeCount();
    const std::uint32_t triangles = mesh.indexCount() / 3;
    SpotShadowPush push{};
    push.n = glm::uvec4(0, lobes, m_views, m_itemCapacity);
    push.k = glm::vec4(m_scene.support(), 0.0f, 0.0f, 0.0f);
    const auto run = [&](const Pipeline& p, std::uint32_t n, std::uint32_t capacity,
                         Descriptors& d) {
        push.n.x = n;
        push.n.w = capacity;
        vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, p.handle());
        vkCmdPushConstants(cmd, p.layout(), VK_SHADER_STAGE_COMPUTE_BIT, 0, sizeof(push), &push);
        bindLookup(d).push(m_ctx, cmd, p);
        dispatch(cmd, n);
    };
    const auto between = [&] {
        memoryBarrier(cmd, kCompute, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT,
                      kCompute | VK_PIPELINE_STAGE_2_DRAW_INDIRECT_BIT,
                      kStorageRW | VK_ACCESS_2_INDIRECT_COMMAND_READ_BIT);
    };
    const auto indirect = [&](const Pipeline& p, const Buffer& list, std::uint32_t capacity,
                              Descriptors& d) {
        push.n.x = 0;
        push.n.w = capacity;
        vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, p.handle());
        vkCmdPushConstants(cmd, p.layout(), VK_SHADER_STAGE_COMPUTE_BIT, 0, sizeof(push), &push);
        bindLookup(d).push(m_ctx, cmd, p);
        vkCmdDispatchIndirect(cmd, list.handle(), 0);
    };
    // 1. Place the lobes (the views' extents come from the host, prepare()).
    {
        Descriptors d;
        d.buffer(kShadowBindImpulses, *m_impulses.impulses)
            .buffer(kShadowBindLobes, m_scene.lobes())
            .buffer(kShadowBindCount, *m_impulses.count)
            .buffer(kShadowBindPlaced, m_placed);
        run(m_place, m_capacity, 0, d);
    }
    between();
    timer.mark(cmd, "light place");
    // 2. The work items.
    {
        Descriptors d;
        d.buffer(kShadowBindItems, m_items)
            .buffer(kShadowBindCount, *m_impulses.count)
            .buffer(kShadowBindPlaced, m_placed);
        run(m_tiles, m_capacity * lobes, m_itemCapacity, d);
    }
    // The triangles' passes read their list and the posed mesh.
    const auto meshItems = [&](Descriptors& d) -> Descriptors& {
        return d.buffer(kShadowBindItems, m_meshItems)
            .buffer(kShadowBindVertices, mesh.vertices())
            .buffer(kShadowBindIndices, mesh.indices());
    };
    if (triangles > 0) {
        Descriptors d;
        run(m_tilesMesh, triangles, m_meshItemCapacity, meshItems(d));
    }
    between();
    timer.mark(cmd, "light tiles");
    // 3. The mesh's depth and the optical depth per layer: independent, so no barrier between
    // them, and one mark (a mark between them would split their time arbitrarily).
    if (triangles > 0) {
        Descriptors d;
        indirect(m_meshPass, m_meshItems, m_meshItemCapacity, meshItems(d));
    }
    {
        Descriptors d;
        d.buffer(kShadowBindItems, m_items).buffer(kShadowBindPlaced, m_placed);
        indirect(m_deposit, m_items, m_itemCapacity, d);
    }
    between();
    timer.mark(cmd, "light mesh and deposit");
    // 5. Summed front to back.
    {
        Descriptors d;
        run(m_prefix, m_texels, 0, d);
    }
    memoryBarrier(cmd, kCompute, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT, kLookups, kStorageRead);
    timer.mark(cmd, "light");
}

std::uint64_t LightSpace::itemsNeeded() {
    if (!m_items.handle() || m_views == 0)
        return 0;
    std::uint64_t total = 0;
    const auto check = [&](Buffer& items, std::uint32_t& capacity, const char* name) {
        const std::uint64_t need = static_cast<const SpotShadowList*>(items.mapped())->count;
        total += need;
        if (need <= capacity)
            return;
        if (!m_warned)
            std::cerr << "spotshell: warning: the light space needed " << need << " " << name
                      << ", more than the " << capacity
                      << " it had room for; this frame's shadows are incomplete (the next "
                         "frames have room)\n";
        m_warned = true;
        capacity = std::uint32_t(std::min<std::uint64_t>(need + need / 4, kMaxItems));
        items = Buffer();
        items = Buffer(m_ctx, sizeof(SpotShadowList) + 8 * std::uint64_t(capacity),
                       kCleared | VK_BUFFER_USAGE_INDIRECT_BUFFER_BIT, Buffer::Memory::HostVisible,
                       name);
    };
    check(m_items, m_itemCapacity, "lobe items");
    check(m_meshItems, m_meshItemCapacity, "triangle items");
    return total;
}

} // namespace spot::splat
