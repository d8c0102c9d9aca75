#version 450
// The light-space structure, pass 5 (spot_shadow.h): per texel of every view, its layers'
// fixed-point increments summed front to back into the optical depth from the light to each
// layer's far boundary (float bits, in place), and where in each layer its own part lies (two
// unorm16, from its moments): what shadowTexelDepth interpolates.
#extension GL_GOOGLE_include_directive : require
#include "light_build.glsl"

layout(local_size_x = 64) in;

void main() {
    uint index = shadowIndex();
    uint views = push.n.z;
    uint start = 0u;
    for (uint v = 0u; v < views; ++v) {
        SpotShadowView view = lit.views[v];
        uint texels = view.offsets.w * view.offsets.w;
        if (index < start + texels) {
            uint layerCount = uint(view.axisW.w);
            uint base = view.offsets.x + (index - start) * layerCount * 3u;
            uint sum = 0u;
            for (uint k = 0u; k < layerCount; ++k) {
                uint w = base + 3u * k;
                uint tau = layers[w];
                sum += tau;
                // Where in the layer its optical depth lies: a uniform step over mean +- sqrt(3)
                // standard deviations (the moments' box), within the layer.
                float t = max(float(tau), 1.0);
                float mean = float(layers[w + 1u]) / t;
                float variance = max(float(layers[w + 2u]) / t - mean * mean, 0.0);
                float half_ = sqrt(3.0 * variance);
                vec2 box = clamp(vec2(mean - half_, mean + half_), vec2(0.0), vec2(1.0));
                layers[w] = floatBitsToUint(float(sum) * (1.0 / kShadowFixed));
                layers[w + 1u] = packUnorm2x16(box);
            }
            return;
        }
        start += texels;
    }
}
