/// @file sorted.cpp
/// @brief `sorted`: the kept kernels radix-sorted back to front and blended "over": the accuracy
/// ceiling of splatting. Its passes are the splatting passes (splat/passes/splatting_vk.h); this is
/// its registry entry and the settings it takes.
#include "splat/passes/splatting_vk.h"

namespace spot::splat {

MethodInfo sortedMethod() {
    namespace s = settings;
    return splattingMethod(Method::Sorted, "kernels sorted by depth, composited back to front",
                           {&s::kernelSamples, &s::ewa, &s::lod, &s::countFragments});
}

} // namespace spot::splat
