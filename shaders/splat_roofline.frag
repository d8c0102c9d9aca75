#version 450
// The roofline of the splat pass (docs/design.md section 7): the same quads over the same pixels
// into the same blended targets as `oit`, with no work per fragment. What this pass costs is what
// lavapipe's rasterizer and blender cost by themselves; each splatting pass is reported as a
// multiple of it.
layout(location = 0) flat in uint vKernel;
layout(location = 0) out vec4 accum;
layout(location = 1) out float opticalDepth;

void main() {
    accum = vec4(1.0 / 4096.0);
    opticalDepth = 1.0 / 4096.0;
}
