/// @file light_space_vk.h
/// @brief The light-space structure every lit GPU method shares (docs/design.md, "Lighting on the
/// GPU"; shaders/spot_shadow.h): one deep opacity map per light with shadows and per sky
/// direction, built each frame on the GPU from the frame's impulses and (posed) mesh, and the lit
/// frame's parameters. The prepare pass (splat_prepare_lit.comp) looks it up at each lobe's centre
/// to light the lobe; the mesh pass at each pixel of the base mesh for the lights
/// (splat_mesh_lit.frag) and at each vertex for the sky (splat_mesh_lit.vert).
///
/// Passes, all compute, one dispatch each over every view: place (the lobes in the world), tiles
/// (the work lists: each lobe's and triangle's tiles of texels per view; a lobe also lowers where
/// its tiles' layers start), mesh (each triangle's depth per texel) and deposit (each lobe's exact
/// optical depth per layer, with its moments, integer atomics), then prefix (the layers summed
/// front to back). Each view's extent comes from the host: the mesh's box as posed, grown by the
/// kernel's reach. The same impulses give the same structure, bit for bit, in any order.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "noise/reference.h"
#include "shaders/spot_shadow.hpp"
#include "splat/context_vk.h"
#include "splat/method_vk.h"

namespace spot::splat {

/// What the structure is made of: the texels per side of a light's view and of a sky
/// direction's, the layers per texel, and the sky's directions.
/// The defaults, measured on the lit fur-bunny (docs/design.md, "Lighting on the GPU"): at 256
/// texels the passes light its lobes within 0.028 of the exact lobe-averaged transmittance (mean;
/// 512 texels do no better); the sky at 3 directions against 6 loses about 2 dB on a sky-only
/// image and about 40% of the structure's cost.
struct LightSpaceSettings {
    std::uint32_t lightTexels = 256;
    std::uint32_t skyTexels = 48;
    std::uint32_t layers = 16;
    std::uint32_t skyDirections = 3;
};

/// While one is alive on this thread, a lit frame whose impulses changed (a stroke's frames in
/// the editor) keeps the light-space structure the last build made, as long as the lights, the
/// views and the mesh's extent are those it was built for: its shadows lag the paint, and the
/// first frame after the hold ends builds it again. Without one, a changed impulse set always
/// builds it.
class LightSpaceHold {
public:
    LightSpaceHold();
    ~LightSpaceHold();
    LightSpaceHold(const LightSpaceHold&) = delete;
    LightSpaceHold& operator=(const LightSpaceHold&) = delete;
    static bool active();

private:
    bool m_previous;
};

class LightSpace {
public:
    explicit LightSpace(const SceneGpu& scene);
    LightSpace(const LightSpace&) = delete;
    LightSpace& operator=(const LightSpace&) = delete;

    /// Host side of a lit frame: the views of `shading`'s lights (those with shadows) and sky,
    /// the parameters uploaded, the buffers (re)made for `impulses`' capacity. The layers are
    /// 8 h / layers thick (h: the impulses' cell size, the kernel's reach), so they span eight
    /// times the fur's depth from where it begins in a tile. No frame that reads this may be in flight.
    void prepare(const noise::Shading& shading, const ImpulseSet& impulses,
                 const LightSpaceSettings& settings = {});
    /// Record the passes (after the impulses and the posed mesh are written), marked "light" on
    /// `timer`. Ends with a barrier that makes the structure visible to compute and fragment
    /// shaders.
    void record(VkCommandBuffer cmd, PassTimer& timer);
    /// What a pass that looks the structure up declares (light_common.glsl), and its
    /// descriptors.
    static Bindings lookupBindings();
    Descriptors& bindLookup(Descriptors& d) const;
    /// After the frame completed: the work items it needed. More than it had room for leaves
    /// this frame's shadows incomplete (a warning says so) and grows the list for the next.
    std::uint64_t itemsNeeded();

private:
    const SceneGpu& m_scene;
    Context& m_ctx;
    std::uint32_t m_views = 0, m_texels = 0, m_capacity = 0, m_itemCapacity = 0,
                  m_meshItemCapacity = 0;
    ImpulseSet m_impulses;
    Pipeline m_place, m_tiles, m_tilesMesh, m_meshPass, m_deposit, m_prefix;
    Buffer m_paramsBuffer, m_extents, m_layers, m_first, m_placed, m_items, m_meshItems;
    bool m_warned = false;
    /// prepare()'s sources (the parameters, extents, buffers and impulse version), and those of
    /// the last build; m_current when they match.
    std::vector<std::byte> m_key, m_built;
    bool m_current = false;
};

} // namespace spot::splat
