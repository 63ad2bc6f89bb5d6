/*
 * intersect.c - the geometric tests behind the simplifier's "no new triangle
 * intersects another triangle" rule (method-notes.md "Valid edges"; issue 3),
 * and the uniform grid that finds the triangles near a new one.
 *
 * Triangle-triangle: the interval method of Moller, "A fast triangle-triangle
 * intersection test" (JGT 1997), with the plane-side classification snapped
 * to zero within eps so that the nearly coplanar neighbours of a CAD face are
 * handled by an exact-in-the-plane 2D test (as Guigue and Devillers, "Fast
 * and robust triangle-triangle overlap test using orientation predicates",
 * JGT 2003, do for the coplanar case), and with the corners and edge the two
 * triangles share taken out of the question (as CGAL's
 * Polygon_mesh_processing::does_self_intersect does): neighbours in a mesh
 * always touch there, and only contact elsewhere is a self-intersection.
 * Two triangles with one common corner are tested edge against triangle
 * (each one's edge opposite that corner against the other), not through the
 * line of their planes, which nearly coplanar neighbours make ill-conditioned.
 *
 * Point-triangle distance: Ericson, "Real-Time Collision Detection", 5.1.5.
 */
#include "intersect.h"
#include "vec3.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>


static inline double mn(double a, double b) { return a < b ? a : b; }
static inline double mx(double a, double b) { return a > b ? a : b; }

/* {====== 2D tests in the plane of a triangle (coplanar case) */

typedef struct pt2 {
    double x, y;
} pt2;

static inline double orient2(pt2 a, pt2 b, pt2 c) {
    return (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
}

static inline int sgn(double v) { return (v > 0) - (v < 0); }

/* Closed segments (touching counts). */
static int seg_seg_2d(pt2 a, pt2 b, pt2 c, pt2 d) {
    int o1 = sgn(orient2(a, b, c)), o2 = sgn(orient2(a, b, d));
    int o3 = sgn(orient2(c, d, a)), o4 = sgn(orient2(c, d, b));
    if (o1 * o2 < 0 && o3 * o4 < 0) return 1;
    if (o1 == 0 && o2 == 0) { /* collinear: overlap of the projections */
        double ax = mn(a.x, b.x), bx = mx(a.x, b.x), cx = mn(c.x, d.x), dx = mx(c.x, d.x);
        double ay = mn(a.y, b.y), by = mx(a.y, b.y), cy = mn(c.y, d.y), dy = mx(c.y, d.y);
        return ax <= dx && cx <= bx && ay <= dy && cy <= by;
    }
    if (o1 == 0 && o3 * o4 <= 0) return 1;
    if (o2 == 0 && o3 * o4 <= 0) return 1;
    if (o3 == 0 && o1 * o2 <= 0) return 1;
    if (o4 == 0 && o1 * o2 <= 0) return 1;
    return 0;
}

/* p inside or on triangle t. */
static int pt_in_tri_2d(pt2 p, const pt2 t[3]) {
    double a = orient2(t[0], t[1], p), b = orient2(t[1], t[2], p), c = orient2(t[2], t[0], p);
    return (a >= 0 && b >= 0 && c >= 0) || (a <= 0 && b <= 0 && c <= 0);
}

static int seg_tri_2d(pt2 a, pt2 b, const pt2 t[3]) {
    if (pt_in_tri_2d(a, t) || pt_in_tri_2d(b, t)) return 1;
    for (int e = 0; e < 3; e++)
        if (seg_seg_2d(a, b, t[e], t[(e + 1) % 3])) return 1;
    return 0;
}

static int tri_tri_2d(const pt2 p[3], const pt2 q[3]) {
    for (int e = 0; e < 3; e++)
        for (int f = 0; f < 3; f++)
            if (seg_seg_2d(p[e], p[(e + 1) % 3], q[f], q[(f + 1) % 3])) return 1;
    return pt_in_tri_2d(p[0], q) || pt_in_tri_2d(q[0], p);
}

/* Drop coordinate axis. */
static inline pt2 proj1(const double *x, int axis) {
    int u = axis == 0 ? 1 : 0, v = axis == 2 ? 1 : 2;
    return (pt2){x[u], x[v]};
}

static void project(pt2 out[3], const double *const T[3], int axis) {
    for (int c = 0; c < 3; c++) out[c] = proj1(T[c], axis);
}

static int dominant_axis(const double n[3]) {
    double ax = fabs(n[0]), ay = fabs(n[1]), az = fabs(n[2]);
    return ax >= ay && ax >= az ? 0 : (ay >= az ? 1 : 2);
}

/* }====== */

/* Signed distances of Q's corners to the plane of P, snapped to 0 within eps;
 * corners shared with P (bit c of shared) lie on it by definition. Returns 1
 * when the other corners are all strictly on one side: then Q meets P's
 * plane at most in the shared corners. */
static int plane_side(const double *const P[3], const double n[3], double nlen, const double *const Q[3],
                      double d[3], double raw[3], double eps, unsigned shared) {
    int pos = 0, neg = 0;
    for (int c = 0; c < 3; c++) {
        if (shared >> c & 1) {
            d[c] = raw[c] = 0.0;
            continue;
        }
        double r[3];
        sub3(r, Q[c], P[0]);
        double v = dot3(r, n) / nlen;
        raw[c] = v;
        d[c] = fabs(v) <= eps ? 0.0 : v;
        pos += d[c] > 0;
        neg += d[c] < 0;
        if (d[c] == 0.0) pos = neg = 4; /* on the plane: no verdict */
    }
    return (pos > 0 && neg == 0 && pos < 4) || (neg > 0 && pos == 0 && neg < 4);
}

/* Interval of triangle T on the line direction D, from the points where T
 * meets the other plane (d: T's corners' snapped distances to it; raw: the
 * distances before snapping). An edge whose snapped end hides a real
 * crossing (the raw distances change sign) adds that crossing too: a
 * corner snapped onto the plane does not stand for its edges, which may
 * cross it elsewhere (docs/design.md "Where the invariant was weaker").
 * Points are only added, so the interval only widens. */
static void interval(const double *const T[3], const double d[3], const double raw[3], const double D[3],
                     double *lo, double *hi) {
    double a = __builtin_inf(), b = -__builtin_inf();
    for (int c = 0; c < 3; c++) {
        if (d[c] == 0.0) {
            double t = dot3(T[c], D);
            a = mn(a, t);
            b = mx(b, t);
        }
        int e = (c + 1) % 3;
        if ((d[c] > 0 && d[e] < 0) || (d[c] < 0 && d[e] > 0)) {
            double s = d[c] / (d[c] - d[e]), x[3];
            for (int k = 0; k < 3; k++) x[k] = T[c][k] + s * (T[e][k] - T[c][k]);
            double t = dot3(x, D);
            a = mn(a, t);
            b = mx(b, t);
        } else if ((d[c] == 0.0 || d[e] == 0.0) && ((raw[c] > 0 && raw[e] < 0) || (raw[c] < 0 && raw[e] > 0))) {
            double s = raw[c] / (raw[c] - raw[e]), x[3];
            for (int k = 0; k < 3; k++) x[k] = T[c][k] + s * (T[e][k] - T[c][k]);
            double t = dot3(x, D);
            a = mn(a, t);
            b = mx(b, t);
        }
    }
    *lo = a;
    *hi = b;
}

/* Segment (a, b) against triangle T, from a's and b's distances to T's
 * plane, snapped (da, db) and raw (ra, rb): an end snapped onto the plane
 * meets T when it lies in T, both ends snapped make a question in the
 * plane, and a change of sign of the raw distances puts a crossing point
 * in the plane, which must lie in T (checked even when an end was snapped:
 * a snapped end does not stand for the crossing). In T's plane the test
 * is 2D, on the axis plane that T projects onto best; closed, so touching
 * counts. */
static int seg_meets_tri(const double *a, const double *b, double da, double db, double ra, double rb,
                         const double *const T[3], int axis) {
    pt2 t2[3], a2 = proj1(a, axis), b2 = proj1(b, axis);
    project(t2, T, axis);
    if (da == 0.0 && db == 0.0) return seg_tri_2d(a2, b2, t2);
    if (da == 0.0 && pt_in_tri_2d(a2, t2)) return 1;
    if (db == 0.0 && pt_in_tri_2d(b2, t2)) return 1;
    if ((ra > 0 && rb < 0) || (ra < 0 && rb > 0)) {
        double s = ra / (ra - rb), x[3];
        for (int k = 0; k < 3; k++) x[k] = a[k] + s * (b[k] - a[k]);
        return pt_in_tri_2d(proj1(x, axis), t2);
    }
    return 0;
}

void fl_tri_plane_of(const double *const T[3], fl_tri_plane *pl) {
    double e1[3], e2[3];
    sub3(e1, T[1], T[0]);
    sub3(e2, T[2], T[0]);
    cross3(pl->n, e1, e2);
    pl->len = sqrt(dot3(pl->n, pl->n));
}

int fl_tri_tri_intersect(const double *const P[3], const uint32_t pid[3], const double *const Q[3],
                         const uint32_t qid[3], double eps) {
    fl_tri_plane pp;
    fl_tri_plane_of(P, &pp);
    return fl_tri_tri_intersect_p(P, pid, &pp, Q, qid, eps);
}

/* Q's plane is computed only when P's plane does not already separate the
 * two: most pairs the simplifier tests are neighbours lying on one side of
 * each other's plane. The answer is that of computing both first (a
 * degenerate Q gives 0 either way). */
int fl_tri_tri_intersect_p(const double *const P[3], const uint32_t pid[3], const fl_tri_plane *pp,
                           const double *const Q[3], const uint32_t qid[3], double eps) {
    int sp[3] = {-1, -1, -1}, shared = 0; /* sp[c]: Q's corner equal to P's corner c */
    for (int c = 0; c < 3; c++)
        for (int e = 0; e < 3; e++)
            if (pid[c] == qid[e]) {
                sp[c] = e;
                shared++;
            }
    if (shared >= 3) return 1;

    const double *np = pp->n;
    double lp = pp->len;
    if (!(lp > 0.0)) return 0; /* degenerate: the quality checks reject those */
    fl_tri_plane qp;

    if (shared == 2) {
        fl_tri_plane_of(Q, &qp);
        if (!(qp.len > 0.0)) return 0;
        /* Neighbours across an edge overlap only when folded flat onto each
         * other: the opposite corners on the same side of the edge and the
         * dihedral angle below about 0.6 degrees. */
        int cp = sp[0] < 0 ? 0 : (sp[1] < 0 ? 1 : 2), cq = 0;
        while (cq == sp[0] || cq == sp[1] || cq == sp[2]) cq++;
        int a = (cp + 1) % 3, b = (cp + 2) % 3;
        double u[3], x[3], y[3], cx[3], cy[3];
        sub3(u, P[b], P[a]);
        sub3(x, P[cp], P[a]);
        sub3(y, Q[cq], P[a]);
        cross3(cx, u, x);
        cross3(cy, u, y);
        double dxy = dot3(cx, cy);
        if (dxy <= 0) return 0;
        double c2 = dxy * dxy / (dot3(cx, cx) * dot3(cy, cy));
        return c2 > 0.99990;
    }

    unsigned pmask = 0, qmask = 0;
    for (int c = 0; c < 3; c++)
        if (sp[c] >= 0) {
            pmask |= 1u << c;
            qmask |= 1u << sp[c];
        }
    double dq[3], dp[3], rq[3], rp[3];
    if (plane_side(P, np, lp, Q, dq, rq, eps, qmask)) return 0;
    fl_tri_plane_of(Q, &qp);
    const double *nq = qp.n;
    double lq = qp.len;
    if (!(lq > 0.0)) return 0;
    if (plane_side(Q, nq, lq, P, dp, rp, eps, pmask)) return 0;

    if (dq[0] == 0.0 && dq[1] == 0.0 && dq[2] == 0.0) {
        /* coplanar within eps: decide in the plane */
        pt2 p2[3], q2[3];
        int axis = dominant_axis(np);
        project(p2, P, axis);
        project(q2, Q, axis);
        if (shared == 0) return tri_tri_2d(p2, q2);
        /* one shared corner v: apart when their angular sectors at v are
         * (the common case of neighbours in a flat region); else the
         * opposite edge of either meets the other */
        int cp = sp[0] >= 0 ? 0 : (sp[1] >= 0 ? 1 : 2), cq = sp[cp];
        {
            pt2 v = p2[cp], p1 = p2[(cp + 1) % 3], p2b = p2[(cp + 2) % 3];
            pt2 q1 = q2[(cq + 1) % 3], q2b = q2[(cq + 2) % 3];
            double sp1 = orient2(v, p1, p2b); /* sector of P: from p1 to p2b, this turn */
            if (sp1 < 0) {
                pt2 t = p1;
                p1 = p2b;
                p2b = t;
            }
            double sq = orient2(v, q1, q2b);
            if (sq < 0) {
                pt2 t = q1;
                q1 = q2b;
                q2b = t;
            }
            /* Each sector (< 180 degrees) lies left of the line of its first
             * ray and right of the line of its second; two such sectors meet
             * only at v exactly when the line of one of the four rays
             * separates them strictly. */
            if ((orient2(v, p1, q1) < 0 && orient2(v, p1, q2b) < 0) ||
                (orient2(v, p2b, q1) > 0 && orient2(v, p2b, q2b) > 0) ||
                (orient2(v, q1, p1) < 0 && orient2(v, q1, p2b) < 0) ||
                (orient2(v, q2b, p1) > 0 && orient2(v, q2b, p2b) > 0))
                return 0;
        }
        return seg_tri_2d(p2[(cp + 1) % 3], p2[(cp + 2) % 3], q2) ||
               seg_tri_2d(q2[(cq + 1) % 3], q2[(cq + 2) % 3], p2);
    }

    if (shared == 1) {
        /* Two triangles with one common corner v meet elsewhere exactly
         * when the edge of one opposite v meets the other: a common point
         * x != v makes the segment v-x common, and walking on from v along
         * it, the first triangle to end does so on its opposite edge,
         * inside the other. No line of the two planes is needed, which
         * for nearly coplanar faces is ill-conditioned: a corner within
         * eps of the other plane can lie far from that line
         * (docs/design.md "Intersection-free fronts"). */
        int cp = sp[0] >= 0 ? 0 : (sp[1] >= 0 ? 1 : 2), cq = sp[cp];
        int p1 = (cp + 1) % 3, p2 = (cp + 2) % 3, q1 = (cq + 1) % 3, q2 = (cq + 2) % 3;
        return seg_meets_tri(P[p1], P[p2], dp[p1], dp[p2], rp[p1], rp[p2], Q, dominant_axis(nq)) ||
               seg_meets_tri(Q[q1], Q[q2], dq[q1], dq[q2], rq[q1], rq[q2], P, dominant_axis(np));
    }

    /* Moller: both triangles meet the line L of the two planes in an
     * interval; they intersect when the intervals overlap. */
    double D[3];
    cross3(D, np, nq);
    double dl = sqrt(dot3(D, D));
    if (!(dl > 0.0)) return 0;
    for (int k = 0; k < 3; k++) D[k] /= dl;
    double a0, a1, b0, b1;
    interval(P, dp, rp, D, &a0, &a1);
    interval(Q, dq, rq, D, &b0, &b1);
    return mn(a1, b1) - mx(a0, b0) >= 0.0;
}

double fl_point_tri_dist2(const double p[3], const double a[3], const double b[3], const double c[3]) {
    double ab[3], ac[3], ap[3], q[3];
    sub3(ab, b, a);
    sub3(ac, c, a);
    sub3(ap, p, a);
    double d1 = dot3(ab, ap), d2 = dot3(ac, ap);
    if (d1 <= 0 && d2 <= 0) return dot3(ap, ap);
    double bp[3];
    sub3(bp, p, b);
    double d3 = dot3(ab, bp), d4 = dot3(ac, bp);
    if (d3 >= 0 && d4 <= d3) return dot3(bp, bp);
    double vc = d1 * d4 - d3 * d2;
    if (vc <= 0 && d1 >= 0 && d3 <= 0) {
        double v = d1 / (d1 - d3);
        for (int k = 0; k < 3; k++) q[k] = a[k] + v * ab[k] - p[k];
        return dot3(q, q);
    }
    double cp[3];
    sub3(cp, p, c);
    double d5 = dot3(ab, cp), d6 = dot3(ac, cp);
    if (d6 >= 0 && d5 <= d6) return dot3(cp, cp);
    double vb = d5 * d2 - d1 * d6;
    if (vb <= 0 && d2 >= 0 && d6 <= 0) {
        double w = d2 / (d2 - d6);
        for (int k = 0; k < 3; k++) q[k] = a[k] + w * ac[k] - p[k];
        return dot3(q, q);
    }
    double va = d3 * d6 - d5 * d4;
    if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
        double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        for (int k = 0; k < 3; k++) q[k] = b[k] + w * (c[k] - b[k]) - p[k];
        return dot3(q, q);
    }
    double den = 1.0 / (va + vb + vc);
    double v = vb * den, w = vc * den;
    for (int k = 0; k < 3; k++) q[k] = a[k] + ab[k] * v + ac[k] * w - p[k];
    return dot3(q, q);
}

/* {====== grid */

_Static_assert(sizeof(fl_grid_block) == 64, "a grid block is one cache line");

/* The block pool, aligned to cache lines (a block read is one line):
 * grown with realloc (which moves large pools by remapping, not copying,
 * and never holds two pools at once), then shifted when the alignment
 * offset changed. 0 on ENOMEM (the old pool is kept). */
static int blocks_resize(fl_grid *g, size_t n) {
    if (n == 0 || n > SIZE_MAX / sizeof(fl_grid_block) - 1) return 0;
    size_t old = g->blocks ? (size_t)((char *)g->blocks - (char *)g->blocks_mem) : 0;
    char *m = fl_realloc(g->blocks_mem, n + 1, sizeof(fl_grid_block));
    if (!m) return 0;
    size_t off = (size_t)(-(uintptr_t)m & 63u);
    if (g->blocks && off != old) memmove(m + off, m + old, g->nblocks * sizeof(fl_grid_block));
    g->blocks_mem = m;
    g->blocks = (fl_grid_block *)(void *)(m + off);
    return 1;
}

int fl_grid_init(fl_grid *g, const double lo[3], const double hi[3], double h, size_t max_cells) {
    memset(g, 0, sizeof *g);
    if (!(h > 0.0)) h = 1.0;
    if (max_cells < 1) max_cells = 1;
    for (;;) {
        size_t total = 1;
        for (int k = 0; k < 3; k++) {
            double ext = hi[k] - lo[k];
            double n = floor(ext / h) + 1.0;
            if (n > 1e6) n = 1e6;
            g->n[k] = (int)n;
            total *= (size_t)g->n[k];
        }
        if (total <= max_cells) break;
        h *= 1.25;
    }
    g->h = h;
    g->inv_h = 1.0 / h;
    for (int k = 0; k < 3; k++) g->origin[k] = lo[k];
    size_t cells = (size_t)g->n[0] * (size_t)g->n[1] * (size_t)g->n[2];
    g->cell = fl_populate(fl_alloc(cells, sizeof *g->cell), cells * sizeof *g->cell);
    g->capblocks = cells / 2 + 1024;
    g->free_block = UINT32_MAX;
    if (!g->cell || !blocks_resize(g, g->capblocks)) {
        fl_grid_free(g);
        return 0;
    }
    for (size_t c = 0; c < cells; c++) {
        g->cell[c].head = UINT32_MAX;
        g->cell[c].count = 0;
    }
    return 1;
}

void fl_grid_free(fl_grid *g) {
    free(g->cell);
    free(g->blocks_mem);
    memset(g, 0, sizeof *g);
}

void fl_grid_range(const fl_grid *g, const double lo[3], const double hi[3], int c0[3], int c1[3]) {
    for (int k = 0; k < 3; k++) {
        c0[k] = fl_grid_coord(g, lo[k], k);
        c1[k] = fl_grid_coord(g, hi[k], k);
    }
}

#define FL_GRID_MAP_AHEAD 16384 /* blocks: 1 MiB */

static uint32_t new_block(fl_grid *g) {
    if (g->free_block != UINT32_MAX) {
        uint32_t b = g->free_block;
        g->free_block = g->blocks[b].next;
        g->nfree--;
        return b;
    }
    if (g->fixed) return UINT32_MAX;
    if (g->nblocks == g->capblocks) {
        size_t cap = g->capblocks * 2;
        if (cap >= UINT32_MAX) return UINT32_MAX;
        if (!blocks_resize(g, cap)) return UINT32_MAX;
        g->capblocks = cap;
    }
    /* the pool's pages are mapped a mebibyte ahead of use (fl_populate:
     * its capacity is a guess, often well above what is used) */
    if (g->nblocks == g->mapped) {
        size_t n = FL_GRID_MAP_AHEAD;
        if (n > g->capblocks - g->nblocks) n = g->capblocks - g->nblocks;
        fl_populate(g->blocks + g->nblocks, n * sizeof(fl_grid_block));
        g->mapped = g->nblocks + n;
    }
    return (uint32_t)g->nblocks++;
}

int fl_grid_take(fl_grid *g, size_t n, uint32_t *head) {
    uint32_t h = *head;
    for (size_t k = 0; k < n; k++) {
        uint32_t b = new_block(g);
        if (b == UINT32_MAX) {
            *head = h;
            return 0;
        }
        g->blocks[b].next = h;
        h = b;
    }
    *head = h;
    return 1;
}

/* Adds item to cell (x, y, z) of a box whose first cell is c0. */
static int cell_insert(fl_grid *g, uint32_t item, int x, int y, int z, const int c0[3]) {
    size_t c = fl_grid_cell(g, x, y, z);
    uint32_t fill = g->cell[c].count % FL_GRID_BLOCK;
    if (fill == 0) { /* head full or absent */
        uint32_t b = new_block(g);
        if (b == UINT32_MAX) return 0;
        g->blocks[b].next = g->cell[c].head;
        g->cell[c].head = b;
    }
    fl_grid_block *B = g->blocks + g->cell[c].head;
    B->item[fill] = item;
    B->first[fill] = (uint8_t)((x == c0[0]) | ((y == c0[1]) << 1) | ((z == c0[2]) << 2));
    g->cell[c].count++;
    return 1;
}

/* Takes item out of cell (x, y, z): the head's last entry fills its place. */
static void cell_remove(fl_grid *g, uint32_t item, int x, int y, int z) {
    size_t c = fl_grid_cell(g, x, y, z);
    uint32_t n = g->cell[c].count;
    if (n == 0) return;
    uint32_t hb = g->cell[c].head, last = (n - 1) % FL_GRID_BLOCK;
    /* find the item: the head holds last+1 items, the rest full blocks */
    uint32_t b = hb, lim = last + 1;
    int found = 0;
    while (b != UINT32_MAX && !found) {
        for (uint32_t s = 0; s < lim; s++)
            if (g->blocks[b].item[s] == item) {
                g->blocks[b].item[s] = g->blocks[hb].item[last];
                g->blocks[b].first[s] = g->blocks[hb].first[last];
                found = 1;
                break;
            }
        b = g->blocks[b].next;
        lim = FL_GRID_BLOCK;
    }
    if (!found) return;
    g->cell[c].count = n - 1;
    if (last == 0) {
        g->cell[c].head = g->blocks[hb].next;
        g->blocks[hb].next = g->free_block;
        g->free_block = hb;
        g->nfree++;
    }
}

int fl_grid_insert(fl_grid *g, uint32_t item, const double lo[3], const double hi[3]) {
    int c0[3], c1[3];
    fl_grid_range(g, lo, hi, c0, c1);
    for (int z = c0[2]; z <= c1[2]; z++)
        for (int y = c0[1]; y <= c1[1]; y++)
            for (int x = c0[0]; x <= c1[0]; x++)
                if (!cell_insert(g, item, x, y, z, c0)) return 0;
    return 1;
}

void fl_grid_remove(fl_grid *g, uint32_t item, const double lo[3], const double hi[3]) {
    int c0[3], c1[3];
    fl_grid_range(g, lo, hi, c0, c1);
    for (int z = c0[2]; z <= c1[2]; z++)
        for (int y = c0[1]; y <= c1[1]; y++)
            for (int x = c0[0]; x <= c1[0]; x++) cell_remove(g, item, x, y, z);
}

static inline int in_range(int x, int y, int z, const int c0[3], const int c1[3]) {
    return x >= c0[0] && x <= c1[0] && y >= c0[1] && y <= c1[1] && z >= c0[2] && z <= c1[2];
}

/* When the first cell stays, the entries of the cells both boxes cover are
 * already right (their first-cell bits depend on the first cell only):
 * only the cells of one box alone change. */
int fl_grid_move(fl_grid *g, uint32_t item, const double olo[3], const double ohi[3], const double nlo[3],
                 const double nhi[3]) {
    int a0[3], a1[3], b0[3], b1[3];
    fl_grid_range(g, olo, ohi, a0, a1);
    fl_grid_range(g, nlo, nhi, b0, b1);
    if (a0[0] != b0[0] || a0[1] != b0[1] || a0[2] != b0[2]) {
        fl_grid_remove(g, item, olo, ohi);
        return fl_grid_insert(g, item, nlo, nhi);
    }
    if (a1[0] == b1[0] && a1[1] == b1[1] && a1[2] == b1[2]) return 1;
    for (int z = a0[2]; z <= a1[2]; z++)
        for (int y = a0[1]; y <= a1[1]; y++)
            for (int x = a0[0]; x <= a1[0]; x++)
                if (!in_range(x, y, z, b0, b1)) cell_remove(g, item, x, y, z);
    for (int z = b0[2]; z <= b1[2]; z++)
        for (int y = b0[1]; y <= b1[1]; y++)
            for (int x = b0[0]; x <= b1[0]; x++)
                if (!in_range(x, y, z, a0, a1) && !cell_insert(g, item, x, y, z, b0)) return 0;
    return 1;
}

/* }====== */
