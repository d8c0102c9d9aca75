#version 450
// Compiles spot_light.h as GLSL and exercises every function in it, so a construct that is valid
// C++ but not GLSL fails the build. Each value is also checked against its closed form on the
// CPU (tests/shaders/light_test.cpp): `values` holds, per invocation's case, the numbers the test
// compares.
#extension GL_GOOGLE_include_directive : require
#include "spot_shared.h"
#include "spot_light.h"

layout(local_size_x = 1) in;

layout(std430, binding = 0) buffer Out { float values[]; };

void main() {
    vec3 t = normalize(vec3(1.0, 0.0, 0.0));
    vec3 l = normalize(vec3(1.0, 1.0, 0.0));
    vec3 v = normalize(vec3(0.0, 1.0, 1.0));
    vec3 c = vec3(0.5, 0.25, 0.125);
    vec3 primary = vec3(radians(-6.0), radians(8.0), 0.3);
    vec3 secondary = vec3(radians(9.0), radians(16.0), 0.5);
    vec3 s = spotLobeShade(kSpotShadeStrand, t, l, v, c, primary, secondary);
    vec3 f = spotLobeShade(kSpotShadeFlake, vec3(0.0, 0.0, -1.0), l, v, c, primary, secondary);
    vec3 n = spotLobeShade(kSpotShadeLambert, vec3(0.0, 1.0, 0.0), l, v, c, primary, secondary);
    vec3 axis = spotPlacedAxis(vec3(0.0, 0.0, 1.0), vec3(0.0, 0.0, 1.0), mat3(1.0), vec3(1.0), 0.5);
    vec3 normal = spotPlacedNormal(mat3(2.0), 2);
    vec3 sky = spotSkyDirection(0.5, 0.25);
    values[0] = s.x;
    values[1] = s.y;
    values[2] = f.x;
    values[3] = n.x;
    values[4] = axis.x;
    values[5] = normal.z;
    values[6] = sky.y + spotPointFalloff(4.0, 2.0) + spotLobeDiffuse(kSpotShadeFlake, t, l, v);
}
