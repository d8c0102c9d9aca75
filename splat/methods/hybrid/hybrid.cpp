/// @file hybrid.cpp
/// @brief `hybrid`: oit, with each pixel's closest kernel composited over the blend. Its passes are
/// the splatting passes (splat/passes/splatting_vk.h); this is its registry entry and the settings
/// it takes.
#include "splat/passes/splatting_vk.h"

namespace spot::splat {

MethodInfo hybridMethod() {
    namespace s = settings;
    return splattingMethod(Method::Hybrid,
                           "oit plus the closest kernel composited over it (paper eq. 13)",
                           {&s::kernelSamples, &s::ewa, &s::weight, &s::closest, &s::smallPixels,
                            &s::lod, &s::countFragments});
}

} // namespace spot::splat
