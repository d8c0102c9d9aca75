#version 450
// Compiles spot_shared.h as GLSL and exercises every function in it, so a construct that is
// valid C++ but not GLSL fails the build. The CPU twin of each call is tested in
// tests/shaders/shared_header_test.cpp.
#extension GL_GOOGLE_include_directive : require
#include "spot_shared.h"

layout(local_size_x = 64) in;

layout(std430, binding = 0) buffer Out { float values[]; };

void main() {
    uint i = gl_GlobalInvocationID.x;
    uint key = spotImpulseKey(spotCellKey(int(i), -int(i), 7, 42u), i);
    float u = spotRand(key, kRandPiece);
    uint n = spotPoisson(u * 40.0, key);
    vec3 bary = spotSampleTriangle(u, spotRand(key, kRandBary0));
    vec3 t;
    vec3 b;
    spotOrthonormalBasis(normalize(bary + vec3(0.1)), t, b);
    mat3 frame = spotKernelFrame(vec3(0.0, 0.0, 1.0), t, b, u, float(n));
    mat3 bend;
    vec3 c = spotBendLobe(bary, u, bend);
    float amp;
    mat3 widened = spotWidenLobe(frame * bend, normalize(c + vec3(1.0)), u, amp);
    float tPeak;
    float tau = spotLobeDepth(widened * c, widened * vec3(0.0, 0.0, 1.0), -1.0, 1.0, 3.0, tPeak);
    values[i] = tau * amp + spotLobeDensity(c, 3.0) + tPeak;
}
