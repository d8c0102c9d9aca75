/// @file oit.cpp
/// @brief `oit`: weighted blended order-independent transparency (McGuire and Bavoil 2013). Its
/// passes are the splatting passes (splat/passes/splatting_vk.h); this is its registry entry and
/// the settings it takes.
#include "splat/passes/splatting_vk.h"

namespace spot::splat {

MethodInfo oitMethod() {
    namespace s = settings;
    return splattingMethod(
        Method::Oit, "weighted blended OIT EWA splatting (paper eq. 10-12)",
        {&s::kernelSamples, &s::ewa, &s::weight, &s::smallPixels, &s::lod, &s::countFragments});
}

} // namespace spot::splat
