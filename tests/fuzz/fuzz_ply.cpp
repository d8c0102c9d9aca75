// libFuzzer target for the PLY loader (ascii and binary): any input must either parse or raise spot::InputError.
// Every other exception, crash, sanitizer report, hang or large allocation is a finding.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "noise/error.h"
#include "noise/mesh.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::string_view text(reinterpret_cast<const char*>(data), size);
    try {
        const spot::noise::Mesh mesh = spot::noise::parsePly(text, "fuzz.ply");
        (void)mesh.surfaceArea();
    } catch (const spot::InputError&) {
        // Refusing bad input with a message is the expected outcome.
    }
    return 0;
}
