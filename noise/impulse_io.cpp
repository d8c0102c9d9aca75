#include "impulse_io.h"

#include <bit>
#include <cstring>
#include <ostream>

#include <glm/gtc/quaternion.hpp>

#include "system.h"

namespace spot::noise {

static_assert(std::endian::native == std::endian::little, "PLY writer assumes little-endian");

void writeImpulsesPly(const std::filesystem::path& file, const std::vector<Impulse>& impulses,
                      const std::vector<std::string>& comments) {
    writeFileAtomic(file, [&](std::ostream& out) {
        out << "ply\nformat binary_little_endian 1.0\n";
        for (const std::string& c : comments)
            out << "comment " << c << "\n";
        out << "element vertex " << impulses.size() << "\n";
        for (const char* name : {"x", "y", "z", "nx", "ny", "nz", "tx", "ty", "tz", "sx", "sy",
                                 "sz", "red", "green", "blue"})
            out << "property float " << name << "\n";
        out << "property int face\n";
        for (const char* name : {"u", "v", "weight", "height", "bend", "qw", "qx", "qy", "qz"})
            out << "property float " << name << "\n";
        out << "end_header\n";

        constexpr std::size_t kFloatsBefore = 15, kFloatsAfter = 9;
        constexpr std::size_t kRecord = (kFloatsBefore + kFloatsAfter) * 4 + 4;
        std::vector<char> buffer;
        buffer.reserve(kRecord * 4096);
        for (std::size_t i = 0; i < impulses.size(); ++i) {
            const Impulse& m = impulses[i];
            const glm::quat q = glm::normalize(glm::quat_cast(m.frame));
            const float before[kFloatsBefore] = {
                m.position.x, m.position.y, m.position.z, m.normal.x, m.normal.y,
                m.normal.z,   m.comb.x,     m.comb.y,     m.comb.z,   m.scale.x,
                m.scale.y,    m.scale.z,    m.color.r,    m.color.g,  m.color.b};
            const std::int32_t face = std::int32_t(m.triangle);
            const float after[kFloatsAfter] = {m.barycentric.x, m.barycentric.y, m.weight,
                                               m.height,        m.bend,          q.w,
                                               q.x,             q.y,             q.z};
            const std::size_t at = buffer.size();
            buffer.resize(at + kRecord);
            std::memcpy(buffer.data() + at, before, sizeof(before));
            std::memcpy(buffer.data() + at + sizeof(before), &face, 4);
            std::memcpy(buffer.data() + at + sizeof(before) + 4, after, sizeof(after));
            if (buffer.size() >= kRecord * 4096 || i + 1 == impulses.size()) {
                out.write(buffer.data(), std::streamsize(buffer.size()));
                buffer.clear();
            }
        }
    });
}

} // namespace spot::noise
