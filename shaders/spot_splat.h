/* spot_splat.h: the splatting renderer's structs and constants, shared by C++ and GLSL
 * (splat/renderer_vk.cpp and the splat_*.glsl / *.vert / *.frag / *.comp shaders it runs).
 *
 * Same rules as spot_layout.h: 16-byte members only, so std430 (and push-constant) layout equals
 * the C++ layout; renderer_vk.cpp includes this file inside a namespace with glm types and
 * static_asserts the sizes. Units: world units; pixels with (0, 0) the top-left corner of the
 * top-left pixel (noise/camera.h); colours linear RGB.
 */
#ifndef SPOT_CONST
#define SPOT_CONST const
#endif

/* Everything a pass needs to know about the frame: the push constants of every splat pipeline
 * (128 bytes, the limit lavapipe guarantees). */
struct SpotSplatFrame {
    vec4 eye;      /* xyz: camera position; w: 1 orthographic, 0 perspective */
    vec4 forward;  /* xyz: unit view direction; w: near plane (view depth) of the depth mapping */
    vec4 right;    /* xyz: unit right axis; w: half width of the view at unit depth (perspective) or
                      in world units (orthographic) */
    vec4 up;       /* xyz: unit up axis (image rows grow downwards); w: half height, likewise */
    vec4 size;     /* x, y: image width, height (pixels); z: pixel footprint per unit view depth
                      (perspective) or in world units (orthographic); w: lobe support k (sigmas) */
    uvec4 counts;  /* x: impulse count; y: lobes per kernel; z: kernel samples N (0 = analytic);
                      w: kSplatFlag* bits */
    vec4 light;    /* xyz: unit direction towards the light (world); w: ambient in [0, 1] */
    vec4 base;     /* rgb: base mesh colour; w: unused */
};

/* One base-mesh vertex for vertex pulling (32 bytes). */
struct SpotMeshVertex {
    vec4 position; /* xyz: world; w unused */
    vec4 normal;   /* xyz: unit normal; w unused */
};

/* SpotSplatFrame.counts.w bits. */
SPOT_CONST uint kSplatFlagEwa = 1u;         /* widen lobes by the pixel footprint (EWA) */
SPOT_CONST uint kSplatFlagLambert = 2u;     /* Lambert + ambient shading, else unlit */
SPOT_CONST uint kSplatFlagMcGuireBavoil = 4u; /* OIT weight: MB13 eq. 7, else constant */
SPOT_CONST uint kSplatFlagHybrid = 8u;      /* hybrid: find and composite the closest kernel */
SPOT_CONST uint kSplatFlagInstanced = 16u;  /* instanced: the base colour image is the result */
SPOT_CONST uint kSplatFlagClosestPass = 32u; /* hybrid: the closest kernel comes from a separate
                                                depth pass (splat_closest.frag), not atomicMin */

/* Kernel samples (paper eq. 10's N_s) at most. Every shader invocation stays far below lavapipe's
 * 65,535 loop iterations: a march costs N x (lobes + 1) <= 2048 x 9 = 18,432 iterations, the
 * analytic path at most about 300. */
SPOT_CONST uint kSplatMaxKernelSamples = 2048u;

/* Analytic path with Lambert shading: normals per lobe and pixel (splatLobeShading). Loop budget
 * of the analytic path: 8 lobes x 4 points x 8 lobes of gradient = 256 iterations. */
SPOT_CONST uint kSplatShadingSamples = 4u;

/* Hybrid: a kernel competes for "closest" at a pixel only where its alpha exceeds this (one 8-bit
 * step): fainter kernels would claim the front while hiding nothing. */
SPOT_CONST float kSplatHybridMinAlpha = 1.0 / 255.0;

/* Hybrid with a closest-kernel depth pass: the depth written is the kernel's ray distance times
 * this power of two, so it orders exactly as the distances do (the atomicMin key's order) for
 * every distance up to 2^20 world units (farther ones all tie at 1, then the first kernel wins,
 * as atomicMin's kernel index does on equal distances). */
SPOT_CONST float kSplatClosestDepthScale = 1.0 / 1048576.0;

/* Instanced: a kernel covers a pixel (opaque proxy) where its alpha reaches this. */
SPOT_CONST float kSplatInstancedMinAlpha = 0.5;

/* Ray distance stored where no mesh is hit. */
SPOT_CONST float kSplatNoMesh = 3.0e38;

/* Workgroup size of the deterministic stream compaction (one workgroup). */
SPOT_CONST uint kSplatCompactThreads = 256u;
