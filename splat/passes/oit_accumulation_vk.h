/// @file oit_accumulation_vk.h
/// @brief The weighted blended OIT accumulation that `oit` and `hybrid` splat into (McGuire and
/// Bavoil 2013; paper eq. 11-12): its two targets, the small kernels' fixed-point sums, and the
/// descriptors of the passes that read and write them.
///
/// The splat pass blends w x (premultiplied colour, alpha) additively into `accum` and the
/// optical depth into `opticalDepth` (splat_oit.frag). The small kernels' compute pass adds the
/// same terms in 64-bit fixed point (kSplatFixedChannels per pixel, integer atomics: the sum does
/// not depend on the order), and marks the kSplatResolveTile^2 tiles it wrote; the resolve adds
/// them to the targets' and clears what it read.
#pragma once

#include "splat/context_vk.h"
#include "splat/passes/resources_vk.h"

namespace spot::splat {

class OitAccumulation {
public:
    /// Declares its targets on `targets` (which outlives it): the two images always, the
    /// fixed-point sums and their tiles' flags where `fixed` says.
    OitAccumulation(FrameResources& targets, FrameResources::Wanted fixed);
    /// Whether a frame's fixed-point sums fit one storage buffer binding (128 MiB on lavapipe:
    /// 3.3 M pixels, about 1830^2); where they do not, every kernel is drawn.
    static bool fixedFits(const Context& ctx, Extent size);

    /// The targets were made anew: the sums are cleared by the next frame's clears.
    void targetsMade() { m_fixedCleared = false; }
    /// Clears before the splat pass: the sums once after they are made (then each resolve clears
    /// what it read), the tiles' flags every frame the compute path runs (`small`).
    void recordClears(VkCommandBuffer cmd, bool small);
    /// Begins the splat pass's rendering into the two targets, cleared, over the mesh's `depth`.
    void beginSplat(VkCommandBuffer cmd, std::uint32_t width, std::uint32_t height,
                    const Image& depth);

    /// What the small kernels' pass writes: the sums and the tiles' flags.
    static Bindings smallBindings();
    void smallDescriptors(Descriptors& d) const;
    /// What a resolve reads: the targets and, with `fixed`, the sums and flags.
    static Bindings resolveBindings(bool fixed);
    void resolveDescriptors(Descriptors& d, bool fixed) const;

    const Image& accum() const { return m_accum; }
    const Image& opticalDepth() const { return m_opticalDepth; }

private:
    Image m_accum, m_opticalDepth;
    Buffer m_fixed; ///< kSplatFixedChannels uint64 per pixel, zero between frames
    Buffer m_tiles; ///< a uint per kSplatResolveTile^2 tile, non-zero where the sums were written
    bool m_fixedCleared = false;
};

} // namespace spot::splat
