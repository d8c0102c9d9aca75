// libFuzzer target for the preset JSON parser: any byte string must either parse or throw
// spot::InputError; anything else (a crash, a sanitizer report, another exception) is a bug.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "noise/error.h"
#include "noise/preset.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::string_view text(reinterpret_cast<const char*>(data), size);
    try {
        spot::noise::parsePreset(text, "fuzz.json");
    } catch (const spot::InputError&) {
        // Rejected input is the expected outcome for most mutations.
    }
    return 0;
}
