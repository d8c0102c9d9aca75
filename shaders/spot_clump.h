/* spot_clump.h: clumps, decided per impulse when it is generated (docs/design.md section 3,
 * "Clumps"; presets/README.md "clump"). One source for the CPU generator and the GPU's candidate
 * pass: included by spot_generate.h after the fields, with the same accessors.
 *
 * Clump centres are a point process on the surface found on the fly, like impulses: a grid of
 * cells of edge G = clump.size (world units) holds per cell up to kClumpMaxSeeds seeds, each a
 * pure function of (cell ijk, clump seed, its index). Seen from a surface point p with normal n,
 * the seeds that count are those of the slab |(x - p).n| < G / 2 around the tangent plane, each
 * projected on that plane: mu seeds per cell times the slab's thickness G gives mu / G^2 centres
 * per unit of surface area, uniform on any locally flat surface whatever its orientation against
 * the grid. A point belongs to the centre nearest to it in the tangent plane, each distance
 * divided by its seed's weight w in [1 - a, 1 + a] (a multiplicatively weighted Voronoi
 * partition: a = variation / 2 makes clumps of unequal size); mu = 1 / m^2 for the relative size
 * m of the clump_size field at p, seed k of a cell existing when its rank is below mu - k, so the
 * seeds thin out one by one as m grows (clumps merge) and come back as it shrinks. Nothing is
 * stored: memory stays proportional to the surface, and every renderer sees the same kernels.
 *
 * The clumped kernel: its tip (the top of its highest lobe, on the bent axis) moves by
 * D = s1 (c1 - p) + s2 (1 - s1) (c2 - p) (c1 the clump's centre, c2 the secondary clump's, s1
 * the clump strength, s2 the secondary's): the strand's tip goes towards its clump's axis (the
 * line through the centre along the strand's own direction) in proportion to the strength, and
 * its root stays. A fraction `shape` of the move is a bend (the kernel turned about its axis so
 * that its bend plane faces the clump, the curvatures added as vectors: the tip moves as the
 * square of the height, the root stays put), the rest a lean (the whole kernel turned about its
 * root: the move grows linearly with height). The lean keeps the kernel rigid, so its length is
 * kept and the support radius (the cell size) does not change.
 */

SPOT_CONST uint kRandClump = 14u;     /* impulse key: the clump strength's variation */
SPOT_CONST uint kClumpMaxSeeds = 4u;  /* seeds per clump cell: 1 / 0.5^2 at the smallest size */
SPOT_CONST uint kClumpSeedSalt = 0x2545f491u;
SPOT_CONST uint kClumpSecondarySalt = 0x9e3779b1u;
SPOT_CONST real kClumpMinRelativeSize = real(0.5);
SPOT_CONST real kClumpMaxRelativeSize = real(2.0);
SPOT_CONST real kClumpMaxVariation = real(1.0);

/* A clump cell's key: one hash of its ijk and the clumps' seed (the search hashes a few dozen
 * cells per impulse, so each costs one hash, not spotCellKey's four). */
SPOT_FN uint spotClumpCellKey(ivec3 q, uint seed) {
    return spotHash((uint(q.x) * 73856093u) ^ (uint(q.y) * 19349663u) ^ (uint(q.z) * 83492791u) ^ seed);
}

/* The clump a surface point belongs to. */
struct SpotClump {
    rvec3 centre;  /* the seed projected on the point's tangent plane (world) */
    real distance; /* from the point to the centre, world units */
    uint id;       /* the seed's key (cell key and index): the same for every point of the clump */
    bool found;    /* false only when no seed lies within the search radius (never in practice) */
};

/* Seed s of clump cell q (key spotClumpCellKey(q, seed)) at mu seeds per cell: false when it
 * does not exist (its rank is not below mu - s), else its position x (world) and its weight w in
 * [1 - a, 1 + a]. Two hashes: the rank (16 bits) and the weight (16 bits) from one, the position
 * in the cell from the other (10 bits per axis, at the centres of a 1024^3 lattice: clump
 * centres need no finer placing). */
SPOT_FN bool spotClumpSeed(ivec3 q, uint key, uint s, real grid, real mu, real a, SPOT_OUT(rvec3) x,
                           SPOT_OUT(real) w) {
    uint h = spotHash(key + s * 0x9e3779b9u);
    x = rvec3(real(0.0));
    w = real(1.0);
    if (!(real(h >> 16u) * real(1.0 / 65536.0) < mu - real(s)))
        return false;
    uint hx = spotHash(h ^ 0x85ebca6bu);
    rvec3 f = (rvec3(real(hx & 1023u), real((hx >> 10u) & 1023u), real((hx >> 20u) & 1023u)) +
               rvec3(real(0.5))) * real(1.0 / 1024.0);
    x = (rvec3(q) + f) * grid;
    w = real(1.0) + a * (real(2.0) * (real(h & 65535u) * real(1.0 / 65536.0)) - real(1.0));
    return true;
}

/* Offset t of the centred search order 0, -1, 1, -2, 2, ...: the nearest cells first, so the
 * bound below skips the far ones early. */
SPOT_FN int spotCentredOffset(int t) {
    return (t & 1) != 0 ? -((t + 1) / 2) : t / 2;
}

/* The clump of surface point p (unit normal n): clump cells of edge `grid` (world units), the
 * relative size m in [0.5, 2] at p, size variation `variation` in [0, 1], the clumps' `seed`. */
SPOT_FN SpotClump spotNearestClump(rvec3 p, rvec3 n, real grid, real relativeSize, real variation,
                                   uint seed) {
    SpotClump best;
    best.centre = p;
    best.distance = real(0.0);
    best.id = 0u;
    best.found = false;
    real m = clamp(relativeSize, kClumpMinRelativeSize, kClumpMaxRelativeSize);
    real mu = real(1.0) / (m * m);
    real a = real(0.5) * clamp(variation, real(0.0), kClumpMaxVariation);
    real wMax = real(1.0) + a;
    /* The centre nearest in weighted distance lies within twice the mean spacing m G times the
     * weights' spread, but for a vanishing fraction of points (docs/design.md section 3). */
    real reach = m * grid * (real(2.0) + real(2.0) * a);
    int r = int(ceil(reach / grid));
    real halfSlab = real(0.5) * grid;
    /* Columns of cells along the normal's dominant axis k; the slab crosses a few of each. The
     * axes are permuted once (i, j, k): no vector is indexed by a variable in the loops. */
    rvec3 an = abs(n);
    int k = an.x >= an.y ? (an.x >= an.z ? 0 : 2) : (an.y >= an.z ? 1 : 2);
    ivec3 ei = k == 0 ? ivec3(0, 1, 0) : ivec3(1, 0, 0);
    ivec3 ej = k == 2 ? ivec3(0, 1, 0) : ivec3(0, 0, 1);
    ivec3 ek = ivec3(1, 1, 1) - ei - ej;
    rvec3 pp = rvec3(dot(p, rvec3(ei)), dot(p, rvec3(ej)), dot(p, rvec3(ek)));
    rvec3 np = rvec3(dot(n, rvec3(ei)), dot(n, rvec3(ej)), dot(n, rvec3(ek)));
    ivec3 c = ivec3(floor(pp / grid));
    real pn = dot(p, n);
    real wMax2 = wMax * wMax;
    real slab2 = halfSlab * halfSlab;
    real bestScore = real(1e30);
    for (int ti = 0; ti <= 2 * r; ++ti) {
        int qi = c.x + spotCentredOffset(ti);
        real xi0 = real(qi) * grid;
        real xi1 = xi0 + grid;
        real gi = max(max(xi0 - pp.x, pp.x - xi1), real(0.0));
        if ((gi * gi - slab2) / wMax2 >= bestScore)
            continue; /* the whole row is farther than the best so far (the bound below) */
        real ti0 = min(np.x * xi0, np.x * xi1);
        real ti1 = max(np.x * xi0, np.x * xi1);
        for (int tj = 0; tj <= 2 * r; ++tj) {
            int qj = c.y + spotCentredOffset(tj);
            real xj0 = real(qj) * grid;
            real xj1 = xj0 + grid;
            real gj = max(max(xj0 - pp.y, pp.y - xj1), real(0.0));
            /* Every seed of the column is at least this far from p in the tangent plane
             * (squared, weighted): its distance across the column less the slab's half. */
            if ((gi * gi + gj * gj - slab2) / wMax2 >= bestScore)
                continue;
            /* The cells of the column the slab |x.n - p.n| < G / 2 crosses. */
            real tj0 = min(np.y * xj0, np.y * xj1);
            real tj1 = max(np.y * xj0, np.y * xj1);
            real lo = (pn - halfSlab - ti1 - tj1) / np.z;
            real hi = (pn + halfSlab - ti0 - tj0) / np.z;
            int qk0 = int(floor(min(lo, hi) / grid));
            int qk1 = int(floor(max(lo, hi) / grid));
            real gij = gi * gi + gj * gj - slab2;
            for (int qk = qk0; qk <= qk1; ++qk) {
                /* The same bound with the cell's distance along k too. */
                real xk0 = real(qk) * grid;
                real gk = max(max(xk0 - pp.z, pp.z - xk0 - grid), real(0.0));
                if ((gij + gk * gk) / wMax2 >= bestScore)
                    continue;
                ivec3 q = qi * ei + qj * ej + qk * ek;
                uint key = spotClumpCellKey(q, seed);
                for (uint s = 0u; s < kClumpMaxSeeds; ++s) {
                    if (!(real(s) < mu))
                        break;
                    rvec3 x;
                    real w;
                    if (!spotClumpSeed(q, key, s, grid, mu, a, x, w))
                        continue;
                    rvec3 d = x - p;
                    real dn = dot(d, n);
                    if (!(abs(dn) < halfSlab))
                        continue;
                    rvec3 t = d - n * dn;
                    real score = dot(t, t) / (w * w);
                    if (score < bestScore) {
                        bestScore = score;
                        best.centre = p + t;
                        best.id = spotHashCombine(key, s);
                        best.found = true;
                    }
                }
            }
        }
    }
    if (best.found)
        best.distance = length(best.centre - p);
    return best;
}

/* The rotation taking unit vector a to unit vector b (about a x b; columns). */
SPOT_FN rmat3 spotRotationBetween(rvec3 a, rvec3 b) {
    rvec3 v = cross(a, b);
    real c = dot(a, b);
    real k = real(1.0) / max(real(1.0) + c, real(1e-6));
    return rmat3(rvec3(c + v.x * v.x * k, v.z + v.x * v.y * k, -v.y + v.x * v.z * k),
                 rvec3(-v.z + v.y * v.x * k, c + v.y * v.y * k, v.x + v.y * v.z * k),
                 rvec3(v.y + v.z * v.x * k, -v.x + v.z * v.y * k, c + v.z * v.z * k));
}

/* The tip of a kernel placed by frame F, scale s and bend kappa, relative to its root (world):
 * the point at height `tip` (kernel units) on the bent axis. */
SPOT_FN rvec3 spotKernelTip(rmat3 frame, rvec3 scale, real kappa, real tip) {
    rmat3 rot;
    rvec3 k = spotBendLobe(rvec3(real(0.0), real(0.0), tip), kappa, rot);
    return frame * (scale * k);
}

/* Move the tip of the kernel (frame, scale, kappa; tip height `tip` in kernel units) by `move`
 * (world units), its root staying: a fraction `shape` as a bend, the rest as a lean (above). */
SPOT_FN void spotClumpKernel(rvec3 move, real shape, real tip, rvec3 scale, SPOT_INOUT(rmat3) frame,
                             SPOT_INOUT(real) kappa) {
    rvec3 tip0 = spotKernelTip(frame, scale, kappa, tip);
    if (shape > real(0.0)) {
        /* The bend's share of the move across the kernel's axis, in kernel units. */
        rvec3 b = shape * move;
        rvec2 across = rvec2(dot(b, frame[0]) / scale.x, dot(b, frame[1]) / scale.y);
        real len = length(across);
        if (len > real(1e-12)) {
            /* Curvature moving the tip `len` across at arc length `tip` (at most a radian). */
            real kc = min(real(2.0) * len / (tip * tip), real(1.0) / tip);
            rvec2 total = rvec2(kappa, real(0.0)) + (kc / len) * across;
            real k2 = length(total);
            if (k2 > real(1e-12)) {
                rvec2 cs = total / k2;
                rvec3 x = cs.x * frame[0] + cs.y * frame[1];
                rvec3 y = cs.x * frame[1] - cs.y * frame[0];
                frame = rmat3(x, y, frame[2]);
                kappa = k2;
            }
        }
    }
    rvec3 now = spotKernelTip(frame, scale, kappa, tip);
    rvec3 target = tip0 + move;
    real nowLength = length(now);
    real targetLength = length(target);
    if (!(nowLength > real(0.0)) || !(targetLength > real(0.0)))
        return;
    frame = spotRotationBetween(now / nowLength, target / targetLength) * frame;
}
