/* raymarch_shared.glsl: the ray march (paper eq. 7-9), one source for the GPU and its CPU twin.
 *
 * Compiles as GLSL 450 and as C++ (inside a class body in splat/raymarch_vk.cpp, in namespace
 * spot::shared::f32 with GLM, like spot_generate.h): keep to the common subset (no swizzles, no
 * references but SPOT_INOUT, float literals with an f suffix). Included after spot_shared.h and
 * raymarch_layout.glsl; the includer provides the data accessors
 *   SpotMarchParams marchParams(); ivec4 marchSlot(uint i);
 * and, unless RAYMARCH_LOOKUP_ONLY is defined,
 *   SpotMarchCell marchCell(uint record); SpotWorldLobe marchLobe(uint i);
 *   SpotMarchBox marchBox(uint impulse).
 *
 * Loop accounting. lavapipe stops an invocation after 65,535 loop iterations in total, counted
 * per SIMD vector of invocations: a loop runs while any lane of the vector is still in it, and
 * each pass through a loop's end (the last one, where every lane has left, included) costs one.
 * Every loop here adds 1 to `loops` on entry and 1 per iteration, so `loops` counts what one lane
 * would cost alone; the host's bound (RaymarchRenderer) multiplies the largest iteration count
 * any lane can reach in each loop, which bounds the vector's count too: each pass of an outer
 * loop runs an inner loop at most as often as its largest per-lane count allows. (Where lanes
 * skip different impulses by their boxes, the vector runs the lobe loop of every impulse some lane
 * enters, more than any one lane counts; the bound charges the lobe loop of every impulse, so it
 * holds all the same.)
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
 * around them; adjacent cells merge into one segment. Costs at most
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
    loops += 1u;
    for (uint n = 0u; n < p.counts.z; ++n) {
        loops += 1u;
        float tn = min(tNext.x, min(tNext.y, tNext.z));
        float tb = min(tn, t1);
        if (tb > tc) {
            int record = marchFind(c, loops);
            if (record >= 0 && marchCell(uint(record)).head.y > 0u) {
                if (s.count > 0u && s.seg[s.count - 1u].y >= tc) {
                    s.span += tb - s.seg[s.count - 1u].y; // adjacent: extend
                    s.seg[s.count - 1u].y = tb;
                } else if (s.count < kMarchMaxSegments) {
                    s.seg[s.count] = vec2(tc, tb);
                    s.count += 1u;
                    s.span += tb - tc;
                } else {
                    s.span += tb - s.seg[s.count - 1u].y; // full: the last one spans the gap
                    s.seg[s.count - 1u].y = tb;
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
    return s;
}

/* Paper eq. 7-9 along the ray o + t d (unit d) up to tEnd (the opaque mesh, or kMarchFar): N
 * samples evenly spaced over the ray's shell segments (midpoints of N equal steps of the segments
 * laid end to end); at each, the density (extinction) and extinction-weighted colour of every
 * lobe of the 27 neighbour cells' impulses (those whose box holds the sample: the others add
 * exactly zero), composited front to back with the 0-order attenuation
 * alpha = 1 - exp(-sigma dt). With Lambert shading the normal is the normalized negative gradient
 * of the summed density (the reference's).
 *
 * This call takes steps [first, end) of the N, continuing from `state` (radiance, transmittance:
 * (0, 0, 0, 1) before step 0) and returning the state after them, so a march can be split over
 * several invocations: the arithmetic, and so the result, is the same however it is split. Costs
 * at most marchShell's loops + 1 + (end - first) (1 + segments + longest probe + 2 + 1 +
 * neighbourhood impulses (lobes per impulse + 2)). */
SPOT_FN vec4 marchRay(vec3 o, vec3 d, float tEnd, uint first, uint end, vec4 state,
                      SPOT_INOUT(uint) loops) {
    SpotMarchParams p = marchParams();
    vec3 radiance = vec3(state.x, state.y, state.z);
    float transmittance = state.w;
    uint steps = p.counts.x;
    if (!(transmittance > kMarchOpaque) || first >= end || steps == 0u)
        return state;
    MarchSegments s = marchShell(o, d, tEnd, loops);
    if (s.count == 0u || !(s.span > 0.0f))
        return state;
    float dt = s.span / float(steps);
    float k = p.grid.z;
    uint lobes = p.counts.y;
    bool lit = (p.counts.w & kMarchFlagLambert) != 0u;
    uint seg = 0u;
    float segStart = 0.0f; // shell length before segment `seg`
    loops += 1u;
    for (uint j = first; j < min(end, steps) && transmittance > kMarchOpaque; ++j) {
        loops += 1u;
        float sj = (float(j) + 0.5f) * dt;
        loops += 1u;
        while (seg + 1u < s.count && sj >= segStart + (s.seg[seg].y - s.seg[seg].x)) {
            loops += 1u;
            segStart += s.seg[seg].y - s.seg[seg].x;
            seg += 1u;
        }
        float t = clamp(s.seg[seg].x + (sj - segStart), s.seg[seg].x, s.seg[seg].y);
        vec3 x = o + t * d;
        int record = marchFind(ivec3(floor(x * p.grid.y)), loops);
        if (record < 0)
            continue;
        SpotMarchCell cell = marchCell(uint(record));
        // The impulses of the neighbourhood in one flat loop (its cost is the impulse count,
        // whatever the ranges); ranges are never empty, so one advance reaches the next.
        uint total = cell.head.y;
        uint r = 0u;
        uint next = cell.range[0].x;
        uint left = cell.range[0].y;
        bool cull = (p.counts.w & kMarchFlagNoCulling) == 0u;
        float sigma = 0.0f;
        vec3 emitted = vec3(0.0f);
        vec3 gradient = vec3(0.0f); // of -density: points out of the strands
        loops += 1u;
        for (uint n = 0u; n < total; ++n) {
            loops += 1u;
            if (left == 0u) {
                r += 1u;
                uvec4 pair = cell.range[r >> 1u];
                bool odd = (r & 1u) != 0u;
                next = odd ? pair.z : pair.x;
                left = odd ? pair.w : pair.y;
            }
            uint impulse = next;
            next += 1u;
            left -= 1u;
            if (cull) {
                SpotMarchBox box = marchBox(impulse);
                if (x.x < box.lo.x || x.y < box.lo.y || x.z < box.lo.z || x.x > box.hi.x ||
                    x.y > box.hi.y || x.z > box.hi.z)
                    continue;
            }
            loops += 1u;
            for (uint l = 0u; l < lobes; ++l) {
                loops += 1u;
                SpotWorldLobe w = marchLobe(impulse * lobes + l);
                if (!(w.color.w > 0.0f))
                    continue;
                mat3 A = mat3(vec3(w.a0), vec3(w.a1), vec3(w.a2));
                vec3 u = A * (x - vec3(w.a0.w, w.a1.w, w.a2.w));
                float rho = w.color.w * spotLobeDensity(u, k);
                if (!(rho > 0.0f))
                    continue;
                sigma += rho;
                emitted += rho * vec3(w.color);
                if (lit)
                    gradient += rho * (transpose(A) * u);
            }
        }
        if (!(sigma > 0.0f && sigma < kMarchFar))
            continue;
        float alpha = spotOneMinusExp(sigma * dt);
        vec3 color = emitted / sigma;
        if (lit) {
            float len = length(gradient);
            vec3 normal = len > 0.0f && len < kMarchFar ? gradient / len : -d;
            color *= spotLambertFactor(normal, vec3(p.light), p.light.w);
        }
        radiance += transmittance * alpha * color;
        transmittance *= 1.0f - alpha;
    }
    return vec4(radiance, transmittance);
}

#endif
