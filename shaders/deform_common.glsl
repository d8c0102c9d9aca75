// The deform passes' common part (spot_deform_layout.h): push constants, the invocation's index
// over a 2D grid of workgroups (a dispatch holds at most 65,535 groups along x) and the posed
// mesh.
#include "spot_shared.h"
#include "spot_layout.h"
#include "spot_splat.h"
#include "spot_deform_layout.h"

layout(local_size_x = kDeformGroup) in;

layout(push_constant) uniform Push { SpotDeformPush push; };

uint deformInvocation() {
    return (gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x) * kDeformGroup +
           gl_LocalInvocationID.x;
}
