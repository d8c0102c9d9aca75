/* spot_generate.h: impulse generation, one source for the CPU generator and the GPU compute pass.
 *
 * Included after spot_shared.h and spot_layout.h. The includer provides the data accessors:
 *   uvec3 spotMeshTriangle(uint t); rvec3 spotMeshPosition(uint v); rvec3 spotMeshNormal(uint v);
 *   rvec3 spotMeshTangent(uint v) (zero when the mesh has none); rvec2 spotMeshUv(uint v);
 *   SpotPiece spotCellPiece(uint i); real spotFieldData(uint i);
 *   vec4 spotParamDistribution(); vec4 spotParamVariation0(); vec4 spotParamVariation1();
 *   uvec4 spotParamFlags(); vec4 spotParamLod(); SpotField spotParamField(uint slot);
 *   ivec2 spotParamFieldKind(uint slot) (the slot's SpotField.kind.xy: kind, components);
 *   vec4 spotParamClump(); vec4 spotParamClump2(); uvec4 spotParamClumpFlags() (spot_clump.h).
 * In GLSL these read storage buffers, except what the pipeline is specialized for (the
 * distribution and flags, each field's kind: generate_candidates.comp), which are constants so
 * that only the paths a preset uses are compiled; in C++ this file is included inside a class
 * body (noise/generator_shared.h) whose members read the model's arrays.
 * Everything is single precision (`real` is float on both sides), so no GPU needs float64.
 *
 * Generation is split into candidates so that no GPU invocation loops long (lavapipe silently
 * stops a shader invocation after 65,535 loop iterations): spotCellCandidates(cell) gives a
 * cell's candidate count (a Poisson draw of density_max x area, or the jittered lattice sites to
 * examine), spotCandidate(cell, m, imp) decides candidate m. Impulses are the accepted candidates
 * in (cell, candidate) order, the same on both sides.
 */

/* Piece areas in SpotPiece.c2.z are cumulative within their cell (area up to and including the
 * piece), so a candidate finds its piece by binary search. */

/* Field kinds (SpotField.kind.x), the one numbering of both sides: noise/field.cpp builds fields
 * with these, spotFieldEval branches on them, splat/generate_vk.cpp specializes on them. */
SPOT_CONST int kFieldConstant = 0;
SPOT_CONST int kFieldGradient = 1;
SPOT_CONST int kFieldNoise = 2;
SPOT_CONST int kFieldVertex = 3;
SPOT_CONST int kFieldImage = 4;
SPOT_CONST int kFieldPainted = 5;
SPOT_CONST int kFieldTangent = 6; /* the surface tangent: the base of a painted, unset comb */

/* The surface at a point of a triangle (SpotSurface, spotSurfaceAt, spotUnit,
 * spotDefaultTangent): shared with the CPU's noise::surfacePoint. */
#include "spot_surface.h"

/* The linear map of the mapped field kinds, clamped to the interval its ends span. */
SPOT_FN rvec3 spotFieldMap(SpotField f, rvec3 t) {
    rvec3 lo = rvec3(f.lo);
    rvec3 hi = rvec3(f.hi);
    return clamp(lo * (rvec3(real(1.0)) - t) + hi * t, min(lo, hi), max(lo, hi));
}

SPOT_FN rvec3 spotKeepComponents(rvec3 v, int components) {
    return components == 1 ? rvec3(v.x, real(0.0), real(0.0)) : v;
}

SPOT_FN int spotWrapIndex(int i, int n, bool repeat) {
    return repeat ? ((i % n) + n) % n : clamp(i, 0, n - 1);
}

SPOT_FN real spotImageTexel(SpotField f, int x, int y, int c) {
    return spotFieldData(f.data.x + (uint(y) * f.data.y + uint(x)) * uint(f.kind.y) + uint(c));
}

/* ---- Painted sparse grid (kFieldPainted, noise/painted.h; docs/design.md section 3) ---------------- */
/* The grid flattened into the field data: each OpenVDB leaf (8^3 voxels) is a block of 512 x
 * components values (voxel n = (x & 7) << 6 | (y & 7) << 3 | (z & 7), components interleaved;
 * inactive voxels hold the background), found through an open-addressing hash table of the
 * leaves' coordinates (voxel index >> 3), linear probing. A table entry is 4 floats carrying
 * integer bits: the leaf's x, y, z and 1 + its block (0: empty). SpotField: data.x the table's
 * offset, data.y its size (a power of two), data.z the longest probe any stored leaf needs (the
 * lookup loop's bound, at most kPaintedMaxProbe), data.w the blocks' offset; from.w 1 / voxel
 * size; value the background; clampLo, clampHi the bounds of the values. */

SPOT_CONST uint kPaintedMaxProbe = 32u;
SPOT_CONST int kPaintedLeafVoxels = 512;

SPOT_FN uint spotPaintedHash(ivec3 leaf) {
    return spotHash(uint(leaf.x) * 73856093u ^ uint(leaf.y) * 19349663u ^ uint(leaf.z) * 83492791u);
}

/* The block of the leaf with coordinates `leaf`, or -1 when the grid has no such leaf. */
SPOT_FN int spotPaintedBlock(SpotField f, ivec3 leaf) {
    uint mask = f.data.y - 1u;
    uint home = spotPaintedHash(leaf) & mask;
    for (uint probe = 0u; probe < kPaintedMaxProbe && probe <= f.data.z; ++probe) {
        uint e = f.data.x + 4u * ((home + probe) & mask);
        int block = floatBitsToInt(spotFieldData(e + 3u)) - 1;
        if (block < 0)
            return -1;
        if (floatBitsToInt(spotFieldData(e)) == leaf.x && floatBitsToInt(spotFieldData(e + 1u)) == leaf.y &&
            floatBitsToInt(spotFieldData(e + 2u)) == leaf.z)
            return block;
    }
    return -1;
}

/* Voxel v's value in block `block` (-1: the leaf is not stored, the background). */
SPOT_FN rvec3 spotPaintedValue(SpotField f, int block, ivec3 v, int components) {
    rvec3 value = rvec3(f.value);
    if (block < 0)
        return value;
    uint n = uint(((v.x & 7) << 6) | ((v.y & 7) << 3) | (v.z & 7));
    uint at = f.data.w + (uint(block) * uint(kPaintedLeafVoxels) + n) * uint(components);
    for (int c = 0; c < components; ++c)
        value[c] = spotFieldData(at + uint(c));
    return value;
}

/* Corner i + d of a trilinear stencil: the first corner's block `block0` is reused when the
 * corner lies in the same leaf (7 stencils in 8 along each axis), else its leaf is looked up. */
SPOT_FN rvec3 spotPaintedCorner(SpotField f, ivec3 i, ivec3 d, int block0, int components) {
    ivec3 v = i + d;
    ivec3 leaf = ivec3(v.x >> 3, v.y >> 3, v.z >> 3);
    int block = leaf == ivec3(i.x >> 3, i.y >> 3, i.z >> 3) ? block0 : spotPaintedBlock(f, leaf);
    return spotPaintedValue(f, block, v, components);
}

/* Trilinear interpolation of the 8 voxels around world point p (index space = p / voxel size),
 * clamped to the bounds of the values (a convex combination leaves them only by rounding). */
SPOT_FN rvec3 spotPaintedSample(SpotField f, rvec3 p, int components) {
    /* Far outside any grid the index stays well inside int range (and reads the background). */
    rvec3 q = clamp(p * f.from.w, rvec3(real(-1e8)), rvec3(real(1e8)));
    rvec3 b = floor(q);
    rvec3 t = q - b;
    ivec3 i = ivec3(b);
    int block0 = spotPaintedBlock(f, ivec3(i.x >> 3, i.y >> 3, i.z >> 3));
    rvec3 c000 = spotPaintedValue(f, block0, i, components);
    rvec3 c100 = spotPaintedCorner(f, i, ivec3(1, 0, 0), block0, components);
    rvec3 c010 = spotPaintedCorner(f, i, ivec3(0, 1, 0), block0, components);
    rvec3 c110 = spotPaintedCorner(f, i, ivec3(1, 1, 0), block0, components);
    rvec3 c001 = spotPaintedCorner(f, i, ivec3(0, 0, 1), block0, components);
    rvec3 c101 = spotPaintedCorner(f, i, ivec3(1, 0, 1), block0, components);
    rvec3 c011 = spotPaintedCorner(f, i, ivec3(0, 1, 1), block0, components);
    rvec3 c111 = spotPaintedCorner(f, i, ivec3(1, 1, 1), block0, components);
    rvec3 c00 = c000 + (c100 - c000) * t.x;
    rvec3 c10 = c010 + (c110 - c010) * t.x;
    rvec3 c01 = c001 + (c101 - c001) * t.x;
    rvec3 c11 = c011 + (c111 - c011) * t.x;
    rvec3 c0 = c00 + (c10 - c00) * t.y;
    rvec3 c1 = c01 + (c11 - c01) * t.y;
    rvec3 v = c0 + (c1 - c0) * t.z;
    return spotKeepComponents(clamp(v, rvec3(f.clampLo), rvec3(f.clampHi)), components);
}

/* ---- Paint layers (noise/painted.h PaintLayer; presets/README.md "Painted layers") ---------- */
/* A field may carry a painted layer over its base: its kind is then the base kind plus
 * kFieldLayered (a weighted override: value v and weight w per voxel, out = b (1 - w) + v w) or
 * kFieldLayeredDensity (a multiplier m and a raise r per voxel, out = b m + (1 - b m) r). Both
 * give the base bit for bit where the layer reads its background (w = 0; m = 1, r = 0), so an
 * empty layer, and every point beyond a stroke's voxels, keeps the base's exact value. The
 * layer's two grids are painted grids (kFieldPainted) whose SpotFields are stored in the field
 * data, one after the other (36 floats each, the struct's bits), at the offset in the base
 * field's axis.w (bits). */
SPOT_CONST int kFieldKindMask = 15;
SPOT_CONST int kFieldLayered = 16;
SPOT_CONST int kFieldLayeredDensity = 32;
SPOT_CONST uint kFieldFloats = 36u;
/* A slot limited to the mask (the mask slot's value m at the point; presets/README.md "Masks")
 * carries one of these in its kind: its value v becomes e + (v - e) m (inside) or
 * e + (v - e) (1 - m) (outside), e its value outside (4 floats in the field data at the offset
 * in value.w, bits). Applied by spotSlotValue, not spotFieldEval: a field is the same field
 * wherever it is bound. */
SPOT_CONST int kFieldMaskedInside = 64;
SPOT_CONST int kFieldMaskedOutside = 128;
SPOT_CONST int kFieldLayerFlags = 48; /* kFieldLayered | kFieldLayeredDensity */

SPOT_FN ivec4 spotDataIvec4(uint at) {
    return ivec4(floatBitsToInt(spotFieldData(at)), floatBitsToInt(spotFieldData(at + 1u)),
                 floatBitsToInt(spotFieldData(at + 2u)), floatBitsToInt(spotFieldData(at + 3u)));
}

SPOT_FN vec4 spotDataVec4(uint at) {
    return vec4(spotFieldData(at), spotFieldData(at + 1u), spotFieldData(at + 2u), spotFieldData(at + 3u));
}

/* The SpotField stored at `at` in the field data (the members a painted grid uses). */
SPOT_FN SpotField spotStoredField(uint at) {
    SpotField f;
    f.kind = spotDataIvec4(at);
    f.value = spotDataVec4(at + 4u);
    f.lo = vec4(0.0);
    f.hi = vec4(0.0);
    f.from = spotDataVec4(at + 16u);
    f.axis = vec4(0.0);
    f.data = uvec4(spotDataIvec4(at + 24u));
    f.clampLo = spotDataVec4(at + 28u);
    f.clampHi = spotDataVec4(at + 32u);
    return f;
}

/* The layer of a field whose kind carries `flags` over the base value `base` at point p. The
 * layer's components are its value grid's (SpotField.kind.y): the base's may be 3 for a scalar
 * slot (a constant, gradient or noise base maps all three). */
SPOT_FN rvec3 spotFieldLayer(uint at, int flags, rvec3 base, rvec3 p) {
    SpotField valueGrid = spotStoredField(at);
    SpotField weightGrid = spotStoredField(at + kFieldFloats);
    int components = valueGrid.kind.y;
    rvec3 v = spotPaintedSample(valueGrid, p, components);
    real w = spotPaintedSample(weightGrid, p, 1).x;
    if ((flags & kFieldLayeredDensity) != 0) {
        real d = base.x * v.x;
        d = d + (real(1.0) - d) * w;
        return rvec3(d, real(0.0), real(0.0));
    }
    return spotKeepComponents(base * (real(1.0) - w) + v * w, components);
}

/* A field's base value (its kind without a layer) at a surface point (scalars in .x). */
SPOT_FN rvec3 spotFieldBase(SpotField f, int kind, int components, SpotSurface s) {
    if (kind == kFieldGradient) {
        rvec3 from = rvec3(f.from);
        real t = clamp(dot(s.position - from, rvec3(f.axis)), real(0.0), real(1.0));
        if (!(t == t))
            t = real(0.0);
        return spotKeepComponents(spotFieldMap(f, rvec3(t)), components);
    }
    if (kind == kFieldNoise) {
        real v = spotValueNoise(s.position * f.from.w, f.kind.z, uint(f.kind.w));
        return spotKeepComponents(spotFieldMap(f, rvec3(v)), components);
    }
    if (kind == kFieldVertex) {
        uvec3 t = spotMeshTriangle(s.triangle);
        rvec3 acc = rvec3(real(0.0));
        for (int c = 0; c < components; ++c) {
            uint column = c == 0 ? f.data.x : (c == 1 ? f.data.y : f.data.z);
            acc[c] = s.bary.x * spotFieldData(column + t.x) + s.bary.y * spotFieldData(column + t.y) +
                     s.bary.z * spotFieldData(column + t.z);
        }
        return spotKeepComponents(clamp(acc, rvec3(f.clampLo), rvec3(f.clampHi)), components);
    }
    if (kind == kFieldImage) {
        bool repeat = f.data.w != 0u;
        real u = s.uv.x == s.uv.x && abs(s.uv.x) < real(1e30) ? s.uv.x : real(0.0);
        real v = s.uv.y == s.uv.y && abs(s.uv.y) < real(1e30) ? s.uv.y : real(0.0);
        if (repeat) {
            u -= floor(u);
            v -= floor(v);
        } else {
            u = clamp(u, real(0.0), real(1.0));
            v = clamp(v, real(0.0), real(1.0));
        }
        int width = int(f.data.y);
        int height = int(f.data.z);
        real x = u * real(width) - real(0.5);
        real y = (real(1.0) - v) * real(height) - real(0.5);
        real xf = floor(x);
        real yf = floor(y);
        real fx = x - xf;
        real fy = y - yf;
        int xa = spotWrapIndex(int(xf), width, repeat);
        int xb = spotWrapIndex(int(xf) + 1, width, repeat);
        int ya = spotWrapIndex(int(yf), height, repeat);
        int yb = spotWrapIndex(int(yf) + 1, height, repeat);
        rvec3 t = rvec3(real(0.0));
        for (int c = 0; c < components; ++c) {
            real a = spotImageTexel(f, xa, ya, c);
            real b = spotImageTexel(f, xb, ya, c);
            real top = a + (b - a) * fx;
            real d = spotImageTexel(f, xa, yb, c);
            real e = spotImageTexel(f, xb, yb, c);
            real bottom = d + (e - d) * fx;
            t[c] = clamp(top + (bottom - top) * fy, f.clampLo[c], f.clampHi[c]);
        }
        return spotKeepComponents(spotFieldMap(f, t), components);
    }
    if (kind == kFieldPainted)
        return spotPaintedSample(f, s.position, components);
    if (kind == kFieldTangent)
        return s.tangent;
    return rvec3(f.value);
}

/* A field's value at a surface point (scalars in .x): its base, and its layer when it has one. */
SPOT_FN rvec3 spotFieldEval(uint slot, SpotSurface s) {
    SpotField f = spotParamField(slot);
    ivec2 kindComponents = spotParamFieldKind(slot);
    int flags = kindComponents.x & kFieldLayerFlags;
    rvec3 base = spotFieldBase(f, kindComponents.x & kFieldKindMask, kindComponents.y, s);
    if (flags == 0)
        return base;
    return spotFieldLayer(floatBitsToUint(f.axis.w), flags, base, s.position);
}

/* Clumps (spot_clump.h), the mask overlay: spotParamClumpFlags().y's bits. */
SPOT_CONST uint kClumpOn = 1u;
SPOT_CONST uint kClumpSecondary = 2u;
SPOT_CONST uint kClumpMaskOverlay = 4u;
/* The overlay's tint: the colour masked impulses are drawn towards, and how far. */
SPOT_CONST real kMaskOverlayAmount = real(0.8);

/* The groom's part of the generator (clumps, masks, the mask overlay) is compiled into the GPU
 * modules that need it only (SPOT_GEN_NO_GROOM defined before inclusion leaves it out: every
 * inlined field evaluation costs lavapipe's pipeline creation, used or not); C++ has it all. */
#ifndef SPOT_GEN_NO_GROOM

/* Whether an impulse reads the mask: a slot limited to it, or the overlay. */
SPOT_FN bool spotMaskRead() {
    if ((spotParamClumpFlags().y & kClumpMaskOverlay) != 0u)
        return true;
    for (uint slot = 0u; slot < uint(SPOT_FIELD_COUNT); ++slot)
        if ((spotParamFieldKind(slot).x & (kFieldMaskedInside | kFieldMaskedOutside)) != 0)
            return true;
    return false;
}

#include "spot_clump.h"

#endif /* SPOT_GEN_NO_GROOM */

/* A slot's value for an impulse: its field, limited to the mask (its value `mask` at the
 * impulse, evaluated once) when the slot says so. */
SPOT_FN rvec3 spotSlotValue(uint slot, SpotSurface s, real mask) {
    rvec3 v = spotFieldEval(slot, s);
#ifndef SPOT_GEN_NO_GROOM
    int kind = spotParamFieldKind(slot).x;
    if ((kind & (kFieldMaskedInside | kFieldMaskedOutside)) != 0) {
        real m = (kind & kFieldMaskedOutside) != 0 ? real(1.0) - mask : mask;
        rvec3 e = rvec3(spotDataVec4(floatBitsToUint(spotParamField(slot).value.w)));
        v = e + (v - e) * m;
    }
#endif
    return v;
}

SPOT_FN real spotSymmetric(uint key, uint counter) { return real(2.0) * spotRand(key, counter) - real(1.0); }

/* The candidate at barycentric `bary` of triangle `tri`: the density test, then the impulse. */
SPOT_FN bool spotFinishImpulse(ivec3 cell, uint key, uint tri, rvec3 bary, SPOT_OUT(SpotImpulse) imp) {
    SpotSurface sp = spotSurfaceAt(tri, bary);
    real mask = real(0.0);
#ifndef SPOT_GEN_NO_GROOM
    if (spotMaskRead())
        mask = spotFieldEval(uint(SPOT_FIELD_MASK), sp).x;
#endif
    real density = spotSlotValue(uint(SPOT_FIELD_DENSITY), sp, mask).x;
    if (!(spotRand(key, kRandDensity) < density))
        return false;
    rvec4 dist = rvec4(spotParamDistribution());
    rvec4 var0 = rvec4(spotParamVariation0());
    rvec4 var1 = rvec4(spotParamVariation1());
    uvec4 flags = spotParamFlags();
    real height = dist.z + dist.w * spotSymmetric(key, kRandHeight);
    rvec3 comb = flags.z != 0u ? spotSlotValue(uint(SPOT_FIELD_COMB), sp, mask) : sp.tangent;
    real tilt = radians(spotSlotValue(uint(SPOT_FIELD_TILT), sp, mask).x + var0.x * spotSymmetric(key, kRandTilt));
    real spin = radians(spotSlotValue(uint(SPOT_FIELD_SPIN), sp, mask).x + var0.y * spotSymmetric(key, kRandSpin));
    rmat3 frame = spotKernelFrame(sp.normal, comb, sp.tangent, tilt, spin);
    /* The comb as it lies in the tangent plane: the frame's x axis before tilt and spin. */
    rvec3 combPlane = normalize(frame[0] * cos(spin) - frame[1] * sin(spin));
    combPlane = normalize(combPlane * cos(tilt) + frame[2] * sin(tilt));
    real bend = radians(spotSlotValue(uint(SPOT_FIELD_BEND), sp, mask).x + var0.z * spotSymmetric(key, kRandBend));
    rvec3 scale = spotSlotValue(uint(SPOT_FIELD_SCALE), sp, mask) * (real(1.0) + var0.w * spotSymmetric(key, kRandScale));
    scale = max(scale, rvec3(real(1e-12)));
    rvec3 color = clamp(spotSlotValue(uint(SPOT_FIELD_COLOR), sp, mask) * (real(1.0) + var1.x * spotSymmetric(key, kRandColor)),
                        rvec3(real(0.0)), rvec3(real(1.0)));
    real weight = max(real(0.0), spotSlotValue(uint(SPOT_FIELD_WEIGHT), sp, mask).x *
                                     (real(1.0) + var1.y * spotSymmetric(key, kRandWeight)));
    /* Level of detail: thin the impulses of cells far below the LOD size on screen, conserving
     * their expected mass. */
    rvec4 lod = rvec4(spotParamLod());
    if (lod.w > real(0.0)) {
        real h = var1.z;
        rvec3 centre = (rvec3(cell) + rvec3(real(0.5))) * h;
        real size = h * lod.w / max(length(centre - rvec3(lod)), real(1e-6) * h);
        real keep = clamp(size * size, real(kMinLodKeep), real(1.0));
        if (keep < real(1.0)) {
            if (!(spotRand(key, kRandLod) < keep))
                return false;
            weight /= keep;
        }
    }
    /* Clumps: the kernel's tip moves towards its clump's axis, its root stays (spot_clump.h). */
    real clumpStrength = real(0.0);
    real clumpDistance = real(0.0);
#ifndef SPOT_GEN_NO_GROOM
    uvec4 clumpFlags = spotParamClumpFlags();
    if ((clumpFlags.y & kClumpOn) != 0u) {
        rvec4 clump = rvec4(spotParamClump());
        rvec4 clump2 = rvec4(spotParamClump2());
        real strength = spotSlotValue(uint(SPOT_FIELD_CLUMP), sp, mask).x *
                        (real(1.0) + clump2.z * spotSymmetric(key, kRandClump));
        strength = clamp(strength, real(0.0), real(1.0));
        /* Without strength the impulse is exactly the unclumped one (and costs no search). */
        if (strength > real(0.0)) {
            real size = spotSlotValue(uint(SPOT_FIELD_CLUMP_SIZE), sp, mask).x;
            SpotClump c1 = spotNearestClump(sp.position, sp.normal, clump.x, size, clump.y,
                                            clumpFlags.x);
            rvec3 move = rvec3(real(0.0));
            if (c1.found) {
                clumpStrength = strength;
                clumpDistance = c1.distance;
                move = strength * (c1.centre - sp.position);
            }
            if ((clumpFlags.y & kClumpSecondary) != 0u) {
                real strength2 = clamp(clump2.y * strength, real(0.0), real(1.0)) * (real(1.0) - strength);
                SpotClump c2 = spotNearestClump(sp.position, sp.normal, clump2.x, size, clump.y,
                                                spotHash(clumpFlags.x ^ kClumpSecondarySalt));
                if (c2.found)
                    move += strength2 * (c2.centre - sp.position);
            }
            if (dot(move, move) > real(0.0))
                spotClumpKernel(move, clump.z, clump.w, scale, frame, bend);
        }
    }
    if ((clumpFlags.y & kClumpMaskOverlay) != 0u)
        color = mix(color, rvec3(real(1.0), real(0.12), real(0.08)), kMaskOverlayAmount * mask);
#endif
    imp.position = rvec4(sp.position + height * sp.normal, weight);
    imp.normal = rvec4(sp.normal, bend);
    imp.comb = rvec4(combPlane, height);
    imp.frameX = rvec4(frame[0], real(1.0));
    imp.frameY = rvec4(frame[1], clumpStrength);
    imp.frameZ = rvec4(frame[2], clumpDistance);
    imp.scale = rvec4(scale, uintBitsToFloat(tri));
    imp.color = rvec4(color, bary.y);
    imp.cell = ivec4(cell, floatBitsToInt(float(bary.z)));
    return true;
}

#ifndef SPOT_GEN_NO_POISSON

/* ---- Poisson: count ~ Poisson(density_max x area), uniform on the cell's pieces --------------- */

SPOT_FN uint spotCellKeyOf(SpotCell cell) {
    return spotCellKey(cell.ijk.x, cell.ijk.y, cell.ijk.z, spotParamFlags().x);
}

SPOT_FN bool spotPoissonCandidate(SpotCell cell, uint m, SPOT_OUT(SpotImpulse) imp) {
    uint key = spotImpulseKey(spotCellKeyOf(cell), m);
    uint first = cell.info.x;
    uint count = uint(cell.ijk.w);
    real area = uintBitsToFloat(cell.info.y);
    real pick = spotRand(key, kRandPiece) * area;
    /* First piece whose cumulative area exceeds pick (binary search, at most 32 steps). */
    uint lo = 0u;
    uint hi = count - 1u;
    for (int step = 0; step < 32 && lo < hi; ++step) {
        uint mid = (lo + hi) / 2u;
        if (pick < spotCellPiece(first + mid).c2.z)
            hi = mid;
        else
            lo = mid + 1u;
    }
    SpotPiece piece = spotCellPiece(first + lo);
    rvec3 w = spotSampleTriangle(spotRand(key, kRandBary0), spotRand(key, kRandBary1));
    rvec2 b = w.x * rvec2(piece.c01.x, piece.c01.y) + w.y * rvec2(piece.c01.z, piece.c01.w) +
              w.z * rvec2(piece.c2.x, piece.c2.y);
    return spotFinishImpulse(ivec3(cell.ijk), key, floatBitsToUint(piece.c2.w),
                             rvec3(real(1.0) - b.x - b.y, b.x, b.y), imp);
}

#endif /* SPOT_GEN_NO_POISSON */

#ifndef SPOT_GEN_NO_JITTERED

/* ---- Jittered: a square lattice in each triangle's plane ------------------------------------- */
/* Spacing 1/sqrt(density_max), aligned with the surface tangent: site (a, b) of a triangle's plane
 * lies where the plane's lattice coordinates (dot(x, e1), dot(x, e2)) / spacing equal
 * (a + kLatticeOffsetA, b + kLatticeOffsetB), so coplanar triangles share one lattice. Each site
 * is jittered by up to +-jitter/2 spacing and belongs to the triangle and cell its jittered point
 * falls in; its random numbers come from (triangle, site, seed), so every cell that examines it
 * decides the same way. Irrational-looking offsets keep a regular lattice (jitter 0) off cell
 * faces and shared edges.
 * Single precision: lattice coordinates are taken relative to the triangle's first corner p0,
 * whose own coordinates are split once into an integer site k0 and a fraction f0, so every other
 * number stays small however far the mesh lies from the origin (sites are placed to the float
 * rounding of p0 and of their offset from it; coplanar triangles' lattices agree to the rounding
 * of their corners' coordinates). */

SPOT_CONST real kLatticeOffsetA = real(0.2360679774997897);
SPOT_CONST real kLatticeOffsetB = real(0.6180339887498949);

struct SpotLattice {
    rvec3 p0;     /* the triangle's first corner (world) */
    rvec3 v0;     /* p1 - p0 */
    rvec3 v1;     /* p2 - p0 */
    rvec3 e1;     /* unit lattice axes in the triangle's plane */
    rvec3 e2;
    ivec2 k0;     /* floor of p0's lattice coordinates */
    rvec2 f0;     /* p0's lattice coordinates minus k0, in [0, 1] */
    int a0;       /* first site examined, relative to k0 */
    int b0;
    uint rows;    /* sites along b */
    uint sites;   /* (a1 - a0 + 1) x rows */
};

SPOT_FN SpotLattice spotLatticeOf(uint first, uint last, uint tri, real spacing, real jitter) {
    uvec3 t = spotMeshTriangle(tri);
    SpotLattice l;
    l.p0 = spotMeshPosition(t.x);
    l.v0 = spotMeshPosition(t.y) - l.p0;
    l.v1 = spotMeshPosition(t.z) - l.p0;
    rvec3 n = spotUnit(cross(l.v0, l.v1));
    rvec3 e1 = spotMeshTangent(t.x) + spotMeshTangent(t.y) + spotMeshTangent(t.z);
    e1 -= n * dot(e1, n);
    e1 = dot(e1, e1) > real(1e-12) ? spotUnit(e1) : spotDefaultTangent(n);
    l.e1 = e1;
    l.e2 = cross(n, e1);
    rvec2 c0 = rvec2(dot(l.p0, l.e1), dot(l.p0, l.e2)) / spacing;
    rvec2 k = floor(c0);
    l.k0 = ivec2(k);
    l.f0 = c0 - k;
    /* The pieces' lattice coordinates relative to k0. */
    rvec2 lo = rvec2(real(1e30));
    rvec2 hi = rvec2(real(-1e30));
    for (uint p = first; p < last; ++p) {
        SpotPiece piece = spotCellPiece(p);
        for (int c = 0; c < 3; ++c) {
            rvec2 b = c == 0 ? rvec2(piece.c01.x, piece.c01.y)
                             : (c == 1 ? rvec2(piece.c01.z, piece.c01.w)
                                       : rvec2(piece.c2.x, piece.c2.y));
            rvec3 q = b.x * l.v0 + b.y * l.v1;
            rvec2 lc = rvec2(dot(q, l.e1), dot(q, l.e2)) / spacing + l.f0;
            lo = min(lo, lc);
            hi = max(hi, lc);
        }
    }
    l.a0 = int(ceil(lo.x - kLatticeOffsetA - real(0.5) * jitter));
    int a1 = int(floor(hi.x - kLatticeOffsetA + real(0.5) * jitter));
    l.b0 = int(ceil(lo.y - kLatticeOffsetB - real(0.5) * jitter));
    int b1 = int(floor(hi.y - kLatticeOffsetB + real(0.5) * jitter));
    l.rows = b1 >= l.b0 ? uint(b1 - l.b0 + 1) : 0u;
    l.sites = a1 >= l.a0 ? uint(a1 - l.a0 + 1) * l.rows : 0u;
    return l;
}

/* The end of the group of consecutive pieces (same triangle) starting at `first`. */
SPOT_FN uint spotGroupEnd(uint first, uint end) {
    uint tri = floatBitsToUint(spotCellPiece(first).c2.w);
    uint last = first + 1u;
    while (last < end && floatBitsToUint(spotCellPiece(last).c2.w) == tri)
        last += 1u;
    return last;
}

SPOT_FN uint spotJitteredCandidates(SpotCell cell) {
    real spacing = spotParamVariation1().w;
    real jitter = spotParamDistribution().y;
    uint end = cell.info.x + uint(cell.ijk.w);
    uint total = 0u;
    for (uint first = cell.info.x; first < end;) {
        uint last = spotGroupEnd(first, end);
        uint tri = floatBitsToUint(spotCellPiece(first).c2.w);
        total += spotLatticeOf(first, last, tri, spacing, jitter).sites;
        first = last;
    }
    return min(total, kMaxCandidatesPerCell);
}

/* Site m (in the group's candidate order) of lattice l, the group of triangle `tri` in `cell`: its
 * random key and the barycentric coordinates of the moved site; false when the moved site falls
 * outside the triangle or the cell. */
SPOT_FN bool spotLatticeSite(SpotLattice l, uint tri, uint m, ivec3 cell, SPOT_OUT(uint) key,
                             SPOT_OUT(rvec3) bary) {
    real spacing = spotParamVariation1().w;
    real jitter = spotParamDistribution().y;
    real h = spotParamVariation1().z;
    uint seedKey = spotHash(spotParamFlags().x ^ 0x3c6ef372u);
    int a = l.a0 + int(m / l.rows);
    int b = l.b0 + int(m % l.rows);
    key = spotHashCombine(spotHashCombine(spotHashCombine(seedKey, tri), uint(l.k0.x + a)),
                          uint(l.k0.y + b));
    /* The moved site's offset from p0, in lattice units. */
    real la = real(a) - l.f0.x + kLatticeOffsetA +
              jitter * (spotRand(key, kRandJitterU) - real(0.5));
    real lb = real(b) - l.f0.y + kLatticeOffsetB +
              jitter * (spotRand(key, kRandJitterV) - real(0.5));
    rvec3 v2 = spacing * (la * l.e1 + lb * l.e2);
    real d00 = dot(l.v0, l.v0);
    real d01 = dot(l.v0, l.v1);
    real d11 = dot(l.v1, l.v1);
    real d20 = dot(v2, l.v0);
    real d21 = dot(v2, l.v1);
    real denom = d00 * d11 - d01 * d01;
    real w1 = (d11 * d20 - d01 * d21) / denom;
    real w2 = (d00 * d21 - d01 * d20) / denom;
    real w0 = real(1.0) - w1 - w2;
    if (w0 < real(0.0) || w1 < real(0.0) || w2 < real(0.0))
        return false;
    if (ivec3(floor((l.p0 + v2) / h)) != cell)
        return false;
    bary = rvec3(w0, w1, w2);
    return true;
}

SPOT_FN bool spotJitteredCandidate(SpotCell cell, uint m, SPOT_OUT(SpotImpulse) imp) {
    real spacing = spotParamVariation1().w;
    real jitter = spotParamDistribution().y;
    uint end = cell.info.x + uint(cell.ijk.w);
    for (uint first = cell.info.x; first < end;) {
        uint last = spotGroupEnd(first, end);
        uint tri = floatBitsToUint(spotCellPiece(first).c2.w);
        SpotLattice l = spotLatticeOf(first, last, tri, spacing, jitter);
        if (m < l.sites) {
            uint key;
            rvec3 bary;
            if (!spotLatticeSite(l, tri, m, ivec3(cell.ijk), key, bary))
                return false;
            return spotFinishImpulse(ivec3(cell.ijk), key, tri, bary, imp);
        }
        m -= l.sites;
        first = last;
    }
    return false;
}

#endif /* SPOT_GEN_NO_JITTERED */

/* ---- Both distributions ---------------------------------------------------------------------- */
/* A GPU module carries one distribution (SPOT_GEN_NO_POISSON or SPOT_GEN_NO_JITTERED defined before
 * inclusion: lavapipe spends pipeline creation on every function of a module, even one a
 * specialization makes dead); C++ has both. */

SPOT_FN uint spotCellCandidates(SpotCell cell) {
#ifndef SPOT_GEN_NO_JITTERED
    if (spotParamFlags().y == 1u)
        return spotJitteredCandidates(cell);
#endif
#ifndef SPOT_GEN_NO_POISSON
    real lambda = spotParamDistribution().x * uintBitsToFloat(cell.info.y);
    return spotPoisson(lambda, spotCellKeyOf(cell));
#else
    return 0u;
#endif
}

SPOT_FN bool spotCandidate(SpotCell cell, uint m, SPOT_OUT(SpotImpulse) imp) {
#ifndef SPOT_GEN_NO_JITTERED
    if (spotParamFlags().y == 1u)
        return spotJitteredCandidate(cell, m, imp);
#endif
#ifndef SPOT_GEN_NO_POISSON
    return spotPoissonCandidate(cell, m, imp);
#else
    return false;
#endif
}
