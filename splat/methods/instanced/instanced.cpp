/// @file instanced.cpp
/// @brief `instanced`: the kernels drawn opaque where their alpha reaches 1/2, the nearest kept per
/// pixel (a 64-bit atomicMin). Its passes are the splatting passes (splat/passes/splatting_vk.h);
/// this is its registry entry and the settings it takes.
#include "splat/passes/splatting_vk.h"

namespace spot::splat {

MethodInfo instancedMethod() {
    namespace s = settings;
    return splattingMethod(
        Method::Instanced, "opaque kernels with the depth test (paper fig. 4 left)",
        {&s::kernelSamples, &s::ewa, &s::smallPixels, &s::lod, &s::countFragments});
}

} // namespace spot::splat
