#include "resources_vk.h"

#include <algorithm>

#include "noise/error.h"

namespace spot::splat {

std::uint64_t texelBytes(VkFormat format) {
    switch (format) {
    case VK_FORMAT_R32G32B32A32_SFLOAT:
        return 16;
    case VK_FORMAT_R32_SFLOAT:
    case VK_FORMAT_R32_UINT:
    case VK_FORMAT_D32_SFLOAT:
        return 4;
    default:
        SPOT_CHECK(false && "a target format without its size here");
        return 0;
    }
}

void FrameResources::image(Image& image, std::string name, VkFormat format, VkImageUsageFlags usage,
                           VkImageAspectFlags aspect, Wanted wanted) {
    Context* ctx = m_ctx;
    const std::string label = name;
    custom(
        std::move(name), [format](Extent e) { return e.width * e.height * texelBytes(format); },
        [&image, ctx, format, usage, aspect, label](Extent e) {
            image = Image(*ctx, std::uint32_t(e.width), std::uint32_t(e.height), format, usage,
                          aspect, label);
        },
        [&image] { image = Image(); }, [&image] { return image.reservedBytes(); },
        std::move(wanted));
}

void FrameResources::buffer(Buffer& buffer, std::string name, Bytes bytes, VkBufferUsageFlags usage,
                            Buffer::Memory memory, Wanted wanted) {
    Context* ctx = m_ctx;
    const std::string label = name;
    Bytes size = [bytes](Extent e) { return std::max<std::uint64_t>(bytes(e), 1); };
    custom(
        std::move(name), size,
        [&buffer, ctx, size, usage, memory, label](Extent e) {
            buffer = Buffer(*ctx, size(e), usage, memory, label);
        },
        [&buffer] { buffer = Buffer(); }, [&buffer] { return buffer.reservedBytes(); },
        std::move(wanted));
}

void FrameResources::custom(std::string name, Bytes bytes, std::function<void(Extent)> make,
                            std::function<void()> release, std::function<std::uint64_t()> held,
                            Wanted wanted) {
    m_resources.push_back({std::move(name), std::move(bytes), std::move(make), std::move(release),
                           std::move(held), std::move(wanted)});
}

std::vector<bool> FrameResources::wantedSet(Extent extent, const RenderSettings& settings) const {
    std::vector<bool> out;
    out.reserve(m_resources.size());
    for (const Resource& r : m_resources)
        out.push_back(!r.wanted || r.wanted(settings, extent));
    return out;
}

std::uint64_t FrameResources::bytes(Extent extent, const RenderSettings& settings) const {
    const std::vector<bool> wanted = wantedSet(extent, settings);
    std::uint64_t total = 0;
    for (std::size_t i = 0; i < m_resources.size(); ++i)
        if (wanted[i])
            total += m_resources[i].bytes(extent);
    return total;
}

bool FrameResources::current(Extent extent, const RenderSettings& settings) const {
    if (!(extent == m_extent))
        return false;
    const std::vector<bool> wanted = wantedSet(extent, settings);
    for (std::size_t i = 0; i < m_resources.size(); ++i)
        if (wanted[i] != m_resources[i].made)
            return false;
    return true;
}

bool FrameResources::ensure(Extent extent, const RenderSettings& settings,
                            const std::string& what) {
    if (current(extent, settings))
        return false;
    const std::uint64_t need = bytes(extent, settings);
    std::uint64_t held = 0;
    for (const Resource& r : m_resources)
        held += r.held();
    const std::uint64_t inUse = m_ctx->allocatedBytes() - held;
    if (inUse + need > m_ctx->memoryBudget())
        throw InputError(cat(m_who, ": ", what, " ", need >> 20, " MiB of GPU memory; ",
                             inUse >> 20, " MiB are in use and the budget is ",
                             m_ctx->memoryBudget() >> 20,
                             " MiB; reduce the image size or the kernel count"));
    for (Resource& r : m_resources) {
        r.release();
        r.made = false;
    }
    m_extent = Extent{0, 0};
    const std::vector<bool> wanted = wantedSet(extent, settings);
    for (std::size_t i = 0; i < m_resources.size(); ++i)
        if (wanted[i]) {
            m_resources[i].make(extent);
            m_resources[i].made = true;
        }
    m_extent = extent;
    return true;
}

} // namespace spot::splat
