/* raymarch_shared.glsl: the ray march (paper eq. 7-9), one source for the GPU and its CPU twin.
 *
 * Compiles as GLSL 450 and as C++ (inside a class body in splat/methods/raymarch/raymarch_vk.cpp, in namespace
 * spot::shared::f32 with GLM, like spot_generate.h): keep to the common subset (no swizzles, no
 * references but SPOT_INOUT, float literals with an f suffix). Included after spot_shared.h and
 * raymarch_layout.glsl; the includer provides the data accessors
 *   SpotMarchParams marchParams(); ivec4 marchSlot(uint i);
 * and, unless RAYMARCH_LOOKUP_ONLY is defined,
 *   SpotMarchCell marchCell(uint record); uint marchStart(uint slot); uint marchEntry(uint i);
 *   uvec2 marchWalkBrick(ivec3 brick) (kMarchBindWalkBits); mat3 marchLobeMatrix(uint i); vec3 marchLobeCentre(uint i); vec4 marchLobeColor(uint i)
 *   (world lobe i's A, centre and colour with its amplitude, SpotWorldLobe);
 *   vec4 marchLobeSlope(uint i) and vec4 marchLobeAxis(uint i) (record i's a0 and a1: in a lit
 *   frame, a lobe's colour change along its shading axis, at SpotMarchParams counts.x + the
 *   lobe, spot_layout.h);
 *   SpotMarchBox marchBox(uint impulse); vec4 marchLight() (SpotMarchPush::light),
 * and the specialization constants kMarchLobes (uint), kMarchLambert, kMarchCull and
 * kMarchWalkBits (bool).
 *
 * Loop accounting. lavapipe stops an invocation after 65,535 loop iterations in total, counted
 * per SIMD vector of invocations: a loop runs while any lane of the vector is still in it, and
 * each pass through a loop's end (the last one, where every lane has left, included) costs one.
 * Every loop here adds 1 to `loops` on entry and 1 per iteration, so `loops` counts what one lane
 * would cost alone; the host's bound (RaymarchRenderer) multiplies the largest iteration count
 * any lane can reach in each loop, which bounds the vector's count too: each pass of an outer
 * loop runs an inner loop at most as often as its largest per-lane count allows. (Where lanes
 * skip different impulses by their boxes, the vector runs the lobe loop of every impulse some lane
 * enters, more than any one lane counts; the bound charges the lobe loop of every listed impulse,
 * so it holds all the same.)
 */

/* Home slot of cell q in the hash table (before the mask). */
SPOT_FN uint marchHash(ivec3 q) {
    return spotHashCombine(spotHashCombine(spotHash(uint(q.x) + 0x2f6b1e3du), uint(q.y)), uint(q.z));
}

/* The record of shell cell q, or -1 if q is not in the shell. Linear probing; a key present in the
 * table lies at most marchParams().hi.w slots past its home slot (the host measured it while
 * inserting), so no lookup examines more than hi.w + 1 slots. Costs at most hi.w + 2 loops. */
SPOT_FN int marchFind(ivec3 q, SPOT_INOUT(uint) loops) {
    SpotMarchParams p = marchParams();
    if (q.x < p.lo.x || q.y < p.lo.y || q.z < p.lo.z || q.x > p.hi.x || q.y > p.hi.y || q.z > p.hi.z)
        return -1;
    uint mask = uint(p.lo.w);
    uint home = marchHash(q);
    int found = -1;
    loops += 1u;
    for (int probe = 0; probe <= p.hi.w; ++probe) {
        loops += 1u;
        ivec4 slot = marchSlot((home + uint(probe)) & mask);
        if (slot.w < 0)
            break;
        if (slot.x == q.x && slot.y == q.y && slot.z == q.z) {
            found = slot.w;
            break;
        }
    }
    return found;
}

#ifndef RAYMARCH_LOOKUP_ONLY

/* The ray through continuous pixel position (px, py) of the march image (pixels, (0, 0)
 * top-left), as noise::CameraRays and splatPixelRay build it: world origin and unit direction. */
SPOT_FN void marchPixelRay(SpotMarchPush f, float px, float py, SPOT_OUT(vec3) o, SPOT_OUT(vec3) d) {
    spotPixelRay(vec3(f.eye), vec3(f.forward), vec3(f.right) * f.right.w, vec3(f.up) * f.up.w,
                 f.eye.w > 0.5f, vec2(f.size), vec2(px, py), o, d);
}

/* The parts of a ray inside the shell, front to back. */
struct MarchSegments {
    vec2 seg[kMarchMaxSegments]; /* [t0, t1], world distance along the ray */
    uint count;
    float span; /* sum of t1 - t0 over the segments */
};

/* Clip [t0, t1] to the slab lo <= o + t d <= hi along one axis. */
SPOT_FN void marchSlab(float o, float d, float lo, float hi, SPOT_INOUT(float) t0, SPOT_INOUT(float) t1) {
    if (d == 0.0f) {
        if (o < lo || o > hi)
            t1 = -1.0f;
        return;
    }
    float a = (lo - o) / d;
    float b = (hi - o) / d;
    t0 = max(t0, min(a, b));
    t1 = min(t1, max(a, b));
}

/* Walk set-up along one axis (Amanatides and Woo 1987): the ray parameter of the first cell
 * boundary after cell c, and the parameter step between boundaries. */
SPOT_FN vec2 marchAxis(float o, float d, int c, float h) {
    if (d > 0.0f)
        return vec2((float(c + 1) * h - o) / d, h / d);
    if (d < 0.0f)
        return vec2((float(c) * h - o) / d, -h / d);
    return vec2(kMarchFar, kMarchFar);
}

SPOT_FN int marchStep(float d) { return d > 0.0f ? 1 : (d < 0.0f ? -1 : 0); }

/* The shell segments of the ray o + t d (unit d), t in [0, tEnd]: a cell-by-cell walk (3D DDA)
 * through the shell's bounding box, keeping the cells that are in the shell and have impulses
 * around them (their bits with kMarchWalkBits, else the hash table and the cell's record);
 * adjacent cells merge into one segment. Costs at most
 * 1 + walkCap (1 + longest probe + 2) loops. */
SPOT_FN MarchSegments marchShell(vec3 o, vec3 d, float tEnd, SPOT_INOUT(uint) loops) {
    SpotMarchParams p = marchParams();
    MarchSegments s;
    s.count = 0u;
    s.span = 0.0f;
    float h = p.grid.x;
    ivec3 lo = ivec3(p.lo);
    ivec3 hi = ivec3(p.hi);
    vec3 boxLo = vec3(lo) * h;
    vec3 boxHi = vec3(hi + ivec3(1)) * h;
    float t0 = 0.0f;
    float t1 = min(tEnd, kMarchFar);
    marchSlab(o.x, d.x, boxLo.x, boxHi.x, t0, t1);
    marchSlab(o.y, d.y, boxLo.y, boxHi.y, t0, t1);
    marchSlab(o.z, d.z, boxLo.z, boxHi.z, t0, t1);
    if (!(t1 > t0))
        return s;
    // The entry cell; rounding may put the entry point a hair outside the box.
    ivec3 c = clamp(ivec3(floor((o + t0 * d) * p.grid.y)), lo, hi);
    ivec3 stp = ivec3(marchStep(d.x), marchStep(d.y), marchStep(d.z));
    vec2 ax = marchAxis(o.x, d.x, c.x, h);
    vec2 ay = marchAxis(o.y, d.y, c.y, h);
    vec2 az = marchAxis(o.z, d.z, c.z, h);
    vec3 tNext = vec3(ax.x, ay.x, az.x);
    vec3 tDelta = vec3(ax.y, ay.y, az.y);
    float tc = t0;
    // The last segment (index s.count - 1) stays in `last` until the walk ends: the array is
    // written once per segment, not indexed at every cell (a per-lane index into a local array
    // costs much more than a register on lavapipe).
    vec2 last = vec2(0.0f);
    // With kMarchWalkBits, the bits of the brick the cell lies in, read again only when the walk
    // enters another brick (a load per cell costs more than the rest of the step on lavapipe).
    ivec3 brick = ivec3(-1);
    uvec2 brickBits = uvec2(0u);
    loops += 1u;
    for (uint n = 0u; n < p.counts.z; ++n) {
        loops += 1u;
        float tn = min(tNext.x, min(tNext.y, tNext.z));
        float tb = min(tn, t1);
        if (tb > tc) {
            bool kept;
            if (kMarchWalkBits) {
                ivec3 q = c - lo; // inside the box: the walk leaves when c does
                ivec3 b = q / kMarchWalkBrick;
                if (b.x != brick.x || b.y != brick.y || b.z != brick.z) {
                    brick = b;
                    brickBits = marchWalkBrick(b);
                }
                ivec3 l = q - b * kMarchWalkBrick;
                uint bit = uint((l.x * kMarchWalkBrick + l.y) * kMarchWalkBrick + l.z);
                kept = ((bit < 32u ? brickBits.x >> bit : brickBits.y >> (bit - 32u)) & 1u) != 0u;
            } else {
                int record = marchFind(c, loops);
                kept = record >= 0 && marchCell(uint(record)).head.x > 0u;
            }
            if (kept) {
                if (s.count > 0u && last.y >= tc) {
                    s.span += tb - last.y; // adjacent: extend
                    last.y = tb;
                } else if (s.count < kMarchMaxSegments) {
                    if (s.count > 0u)
                        s.seg[s.count - 1u] = last;
                    last = vec2(tc, tb);
                    s.count += 1u;
                    s.span += tb - tc;
                } else {
                    s.span += tb - last.y; // full: the last one spans the gap
                    last.y = tb;
                }
            }
        }
        if (!(tn < t1))
            break;
        if (tNext.x <= tNext.y && tNext.x <= tNext.z) {
            c.x += stp.x;
            tNext.x += tDelta.x;
        } else if (tNext.y <= tNext.z) {
            c.y += stp.y;
            tNext.y += tDelta.y;
        } else {
            c.z += stp.z;
            tNext.z += tDelta.z;
        }
        tc = max(tc, tn);
        if (c.x < lo.x || c.y < lo.y || c.z < lo.z || c.x > hi.x || c.y > hi.y || c.z > hi.z)
            break;
    }
    if (s.count > 0u)
        s.seg[s.count - 1u] = last;
    return s;
}

/* Paper eq. 7-9 along the ray o + t d (unit d) up to tEnd (the opaque mesh, or kMarchFar): N
 * samples evenly spaced over the ray's shell segments (midpoints of N equal steps of the segments
 * laid end to end); at each, the density (extinction) and extinction-weighted colour of every
 * lobe of the 27 neighbour cells' impulses, composited front to back with the 0-order
 * attenuation alpha = 1 - exp(-sigma dt). Only the lobes the sample's sub-cell lists are
 * visited (with kMarchCull, also only those of impulses whose box holds the sample): every other
 * one adds exactly zero, and the sums run in impulse and lobe order either way. With Lambert shading the normal is
 * the normalized negative gradient of the summed density (the reference's).
 *
 * This call takes steps [first, end) of the N, continuing from `state` (radiance, transmittance:
 * (0, 0, 0, 1) before step 0) and returning the state after them, so a march can be split over
 * several invocations: the arithmetic, and so the result, is the same however it is split. Costs
 * at most marchShell's loops + 1 + (end - first) (1 + segments + longest probe + 2 + 1 +
 * listed impulses (lobes per impulse + 2)). */
SPOT_FN vec4 marchRay(vec3 o, vec3 d, float tEnd, uint first, uint end, uint steps, vec4 state,
                      SPOT_INOUT(uint) loops) {
    SpotMarchParams p = marchParams();
    vec3 radiance = vec3(state.x, state.y, state.z);
    float transmittance = state.w;
    if (!(transmittance > kMarchOpaque) || first >= end || steps == 0u)
        return state;
    MarchSegments s = marchShell(o, d, tEnd, loops);
    if (s.count == 0u || !(s.span > 0.0f))
        return state;
    float dt = s.span / float(steps);
    float k = p.grid.z;
    uint changes = p.counts.x; // a lit frame's colour changes (0: none)
    float subScale = p.grid.y * float(kMarchSub);
    uint seg = 0u;
    vec2 cur = s.seg[0]; // segment `seg`, in registers
    float segStart = 0.0f; // shell length before segment `seg`
    // The last cell looked up (consecutive samples often share one): its index and record.
    ivec3 lastCell = ivec3(p.hi) + ivec3(1);
    int record = -1;
    loops += 1u;
    for (uint j = first; j < min(end, steps) && transmittance > kMarchOpaque; ++j) {
        loops += 1u;
        float sj = (float(j) + 0.5f) * dt;
        // The structure below keeps the work in `if` blocks rather than behind `continue`: lavapipe
        // runs 8 lanes in lockstep and skips a block only when no lane enters it.
        loops += 1u;
        if (seg + 1u < s.count && sj >= segStart + (cur.y - cur.x)) {
            while (seg + 1u < s.count && sj >= segStart + (cur.y - cur.x)) {
                loops += 1u;
                segStart += cur.y - cur.x;
                seg += 1u;
                cur = s.seg[seg];
            }
        }
        float t = clamp(cur.x + (sj - segStart), cur.x, cur.y);
        vec3 x = o + t * d;
        ivec3 cell = ivec3(floor(x * p.grid.y));
        if (cell.x != lastCell.x || cell.y != lastCell.y || cell.z != lastCell.z) {
            lastCell = cell;
            record = marchFind(cell, loops);
        }
        if (record >= 0) {
            // With culling, the list of the sample's sub-cell (rounding may put it a hair past the
            // cell: the lists were built with a margin, so the nearest sub-cell of the cell lists
            // every lobe that counts); without, the cell's list of all its neighbours' impulses.
            uint slot = uint(record);
            if (kMarchCull) {
                ivec3 sub = clamp(ivec3(floor(x * subScale)) - cell * int(kMarchSub), ivec3(0),
                                  ivec3(int(kMarchSub) - 1));
                slot = slot * kMarchSubCells +
                       uint((sub.x * int(kMarchSub) + sub.y) * int(kMarchSub) + sub.z);
            }
            uint listStart = marchStart(slot);
            uint listEnd = marchStart(slot + 1u);
            float sigma = 0.0f;
            vec3 emitted = vec3(0.0f);
            vec3 gradient = vec3(0.0f); // of -density: points out of the strands
            loops += 1u;
            if (listStart < listEnd) {
                for (uint e = listStart; e < listEnd; ++e) {
                    loops += 1u;
                    uint entry = marchEntry(e);
                    uint impulse = entry & kMarchEntryImpulse;
                    uint lobeMask = entry >> kMarchEntryLobeShift;
                    bool inside = true;
                    if (kMarchCull) {
                        SpotMarchBox box = marchBox(impulse);
                        inside = !(x.x < box.lo.x || x.y < box.lo.y || x.z < box.lo.z ||
                                   x.x > box.hi.x || x.y > box.hi.y || x.z > box.hi.z);
                    }
                    loops += 1u;
                    if (inside) {
                        for (uint l = 0u; l < kMarchLobes; ++l) {
                            loops += 1u;
                            // A lobe whose box misses the sub-cell has no density here.
                            if ((lobeMask & (1u << l)) != 0u) {
                                uint i = impulse * kMarchLobes + l;
                                mat3 A = marchLobeMatrix(i);
                                vec3 u = A * (x - marchLobeCentre(i));
                                // Outside its support the lobe adds exactly zero: its colour
                                // and the exponential are read only inside.
                                if (dot(u, u) < k * k) {
                                    vec4 c = marchLobeColor(i);
                                    float rho = c.w * spotLobeDensity(u, k);
                                    if (c.w > 0.0f && rho > 0.0f) {
                                        vec3 color = vec3(c);
                                        if (changes > 0u) { // lit: along the shading axis
                                            vec3 along = vec3(marchLobeAxis(changes + i));
                                            color = color + vec3(marchLobeSlope(changes + i)) *
                                                                clamp(dot(along, u), -1.0f, 1.0f);
                                        }
                                        sigma += rho;
                                        emitted += rho * color;
                                        if (kMarchLambert)
                                            gradient += spotLobeGradient(A, u, rho);
                                    }
                                }
                            }
                        }
                    }
                }
            }
            if (sigma > 0.0f && sigma < kMarchFar) {
                float alpha = spotOneMinusExp(sigma * dt);
                vec3 color = emitted / sigma;
                if (kMarchLambert) {
                    vec3 normal = spotGradientNormal(gradient, -d, kMarchFar);
                    color *= spotLambertFactor(normal, vec3(marchLight()), marchLight().w);
                }
                radiance += transmittance * alpha * color;
                transmittance *= 1.0f - alpha;
            }
        }
    }
    return vec4(radiance, transmittance);
}

#endif
