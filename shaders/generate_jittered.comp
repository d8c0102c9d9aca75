#version 450
// Impulse generation, pass 1 of 3, for the jittered distribution: generate_candidates.glsl.
#extension GL_GOOGLE_include_directive : require
#define SPOT_GEN_JITTERED 1
#include "generate_candidates.glsl"
