/// @file resources_vk.h
/// @brief The targets and buffers a method's passes declare, made by the frame when their extent
/// changes (nvpro-samples' onResize): per image size (the targets) or per impulse capacity (the
/// buffers sized per kernel).
///
/// A pass says what it needs: a name, how large it is for an extent, and the settings under which
/// it is needed. The set checks the memory budget for all of them at once (as if what it holds
/// were freed: a refused frame keeps the old ones), then frees and makes them. A pass binds only
/// what it declared: no stand-in for a resource another setting needs.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "splat/context_vk.h"
#include "splat/settings.h"

namespace spot::splat {

/// What resources are sized by: an image size (width x height), or a count (width; height 1).
struct Extent {
    std::uint64_t width = 0, height = 1;
    bool operator==(const Extent&) const = default;
};

class FrameResources {
public:
    /// Whether a resource is needed by a frame with these settings at this extent.
    using Wanted = std::function<bool(const RenderSettings&, Extent)>;
    /// Its bytes at an extent.
    using Bytes = std::function<std::uint64_t(Extent)>;

    /// `who` begins a refusal ("splat renderer").
    FrameResources(Context& ctx, std::string who) : m_ctx(&ctx), m_who(std::move(who)) {}
    FrameResources(const FrameResources&) = delete;
    FrameResources& operator=(const FrameResources&) = delete;

    /// An image of the extent's size (`image` outlives the set). Null `wanted`: always.
    void image(Image& image, std::string name, VkFormat format, VkImageUsageFlags usage,
               VkImageAspectFlags aspect, Wanted wanted = {});
    /// A buffer of `bytes(extent)` bytes (at least 1).
    void buffer(Buffer& buffer, std::string name, Bytes bytes, VkBufferUsageFlags usage,
                Buffer::Memory memory, Wanted wanted = {});
    /// Anything else that holds GPU memory (the radix sort's scratch): its bytes at an extent,
    /// how to make and free it, and what it holds now.
    void custom(std::string name, Bytes bytes, std::function<void(Extent)> make,
                std::function<void()> release, std::function<std::uint64_t()> held,
                Wanted wanted = {});

    /// Bytes of what a frame with `settings` at `extent` needs.
    std::uint64_t bytes(Extent extent, const RenderSettings& settings) const;
    /// Whether what was made last is what a frame with `settings` at `extent` needs.
    bool current(Extent extent, const RenderSettings& settings) const;
    /// Makes what a frame with `settings` at `extent` needs unless current(): true when it made
    /// them. `what` names the frame in a refusal ("a 640x480 frame needs"); InputError, keeping
    /// what it holds, when they would not fit the context's budget.
    bool ensure(Extent extent, const RenderSettings& settings, const std::string& what);
    /// The extent made last (0 wide before the first ensure).
    Extent extent() const { return m_extent; }
    /// Makes the next ensure() make everything again: what a resource's bytes depend on beyond
    /// the extent and the settings changed.
    void invalidate() { m_extent = Extent{0, 0}; }

private:
    struct Resource {
        std::string name;
        Bytes bytes;
        std::function<void(Extent)> make;
        std::function<void()> release;
        std::function<std::uint64_t()> held;
        Wanted wanted;
        bool made = false;
    };
    std::vector<bool> wantedSet(Extent extent, const RenderSettings& settings) const;

    Context* m_ctx;
    std::string m_who;
    std::vector<Resource> m_resources;
    Extent m_extent{0, 0};
};

/// Bytes per texel of the formats the renderers' targets use.
std::uint64_t texelBytes(VkFormat format);

} // namespace spot::splat
