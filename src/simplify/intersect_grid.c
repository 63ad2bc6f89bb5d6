/*
 * intersect_grid.c - the intersection test at pop time (issue 3: no new
 * triangle may cross the mesh) and the uniform grid of the live faces it
 * reads.
 *
 *   fl_simp_intersect_check   each new triangle against the faces whose
 *                             grid cells its box meets and against the
 *                             other new triangles (the pair test is
 *                             intersect.c's); skipped pairs: star
 *                             certificates (star_embedded), the plane rule
 *                             (plane_rule)
 *   fl_simp_build_grid        the grid of the live faces (set-up, and
 *                             again with cells twice as large when the
 *                             mesh has shrunk to a quarter)
 *   fl_simp_grid_remove_face  a removed face out of the grid (collapse
 *                             moves the others with fl_grid_move)
 *
 * Invariants: every live face is in the grid under the box of its current
 * corners; the faces a collapse replaces are never tested against its new
 * triangles; a certificate or the plane rule only ever skips a pair that
 * cannot cross, decided with margins far above rounding; a fast-pass
 * worker reads only the cells of its slab and the two next to it, else
 * the test returns DEFER_REASON.
 */
#include "simp.h"

#include <stdio.h>

#ifndef FEMLOD_SIMPLIFY_CERTIFY
#define FEMLOD_SIMPLIFY_CERTIFY 1 /* star certificates in the intersection test */
#endif
#ifndef FEMLOD_SIMPLIFY_PLANE_RULE
#define FEMLOD_SIMPLIFY_PLANE_RULE 1 /* intersection test: the plane rule (docs/design.md) */
#endif
#ifndef FEMLOD_SIMPLIFY_PLANE_VERIFY
#define FEMLOD_SIMPLIFY_PLANE_VERIFY 0 /* 1: run the full test too and report disagreements */
#endif

/* {====== star certificates */

/* Star certificate (docs/simplify.md "Intersection test: invariants"): the
 * closed star of a vertex at c, faces (c, u[f], w[f]) in mesh orientation,
 * projects one to one onto the plane through c across the sum of its face
 * normals: every face turns positively about that normal and the faces'
 * angular sectors wind once around c. Then two of its faces meet only at c
 * or along their common edge, and their pair test can be skipped. Decided
 * with margins: anything near a sector's border or near edge-on is "no
 * certificate" (the full tests run). */
static int star_embedded(const double c[3], const double *const *u, const double *const *w, size_t nf) {
    if (nf < 3 || nf > 64) return 0;
    /* each face's turn a x b, kept for the second loop; the margins are
     * compared squared (no square roots: the decisions differ from the
     * unsquared ones only within rounding of the margins, which are far
     * above rounding, so both are certificates) */
    double x[64][3], ea[64][3], eb[64][3];
    double n[3] = {0, 0, 0};
    for (size_t f = 0; f < nf; f++) {
        sub3(ea[f], u[f], c);
        sub3(eb[f], w[f], c);
        cross3(x[f], ea[f], eb[f]);
        n[0] += x[f][0];
        n[1] += x[f][1];
        n[2] += x[f][2];
    }
    double nn2 = dot3(n, n);
    /* squares of squares: keep clear of overflow and underflow */
    if (!(nn2 > 1e-120 && nn2 < 1e120)) return 0;
    const double *d = ea[0]; /* reference direction: the first face's first edge */
    double dl2 = dot3(d, d);
    const double rel2 = 1e-18, turn2 = 1e-12;
    int wind = 1; /* face 0's sector starts on d */
    for (size_t f = 0; f < nf; f++) {
        const double *a = ea[f], *b = eb[f];
        double al2 = dot3(a, a), bl2 = dot3(b, b);
        /* turns positively, clearly (not edge-on, not degenerate):
         * x.n > 1e-6 |a| |b| |n| */
        double xn = dot3(x[f], n);
        if (!(xn > 0.0 && xn * xn > turn2 * al2 * bl2 * nn2)) return 0;
        if (f == 0) continue;
        /* the face before face 0 ends on d itself: outside (sectors are
         * half-open, [u, w)) */
        if (w[f] == u[0]) continue;
        double ad[3], db[3];
        cross3(ad, a, d);
        cross3(db, d, b);
        double t1 = dot3(ad, n), t2 = dot3(db, n);
        /* d near a border: |t1| < 1e-9 |a| |d| |n| or the same for t2 */
        if (t1 * t1 < rel2 * al2 * dl2 * nn2 || t2 * t2 < rel2 * dl2 * bl2 * nn2) return 0;
        if (t1 > 0.0 && t2 > 0.0) wind++;
    }
    return wind == 1;
}

/* f is one of R's ring or shared faces. */
static inline int ring_has_face(const ring *R, uint32_t f) {
    for (size_t r = 0; r < R->n; r++)
        if (R->face[r] == f) return 1;
    return R->ns > 0 && (R->sface[0] == f || (R->ns > 1 && R->sface[1] == f));
}

#define K_ID (UINT32_MAX - 1) /* the id of the new vertex in intersection tests */

#define CERT_UNKNOWN 2 /* sc.cert: not computed yet (0: no certificate, 1: certified) */

/* The star certificate of ring vertex x (x = 2r: a_r, 2r + 1: b_r) after
 * the collapse to p: its faces with i or j moved to p, the removed faces
 * left out. Computed on first use and stored for every entry of the same
 * vertex (a function of the vertex alone). */
static int link_cert_compute(simp *S, const ring *R, const double p[3], size_t x) {
    uint8_t *cert = S->sc.cert;
    uint32_t v = x & 1 ? R->b[x >> 1] : R->a[x >> 1];
    uint8_t ok = 0;
    const uint32_t *fl = S->refs + S->fstart[v];
    uint32_t cnt = S->fcount[v];
    if (!(S->vflag[v] & (V_BOUNDARY | V_NONMANIFOLD)) && cnt <= 64) {
        const double *U[64], *W[64];
        size_t nf = 0;
        for (uint32_t m = 0; m < cnt; m++) {
            uint32_t f = fl[m];
            if ((R->ns > 0 && f == R->sface[0]) || (R->ns > 1 && f == R->sface[1])) continue;
            const uint32_t *t = S->face[f].v;
            int c = t[0] == v ? 0 : (t[1] == v ? 1 : 2);
            uint32_t y = t[(c + 1) % 3], z = t[(c + 2) % 3];
            U[nf] = y == R->i || y == R->j ? p : P(S, y);
            W[nf] = z == R->i || z == R->j ? p : P(S, z);
            nf++;
        }
        ok = (uint8_t)star_embedded(P(S, v), U, W, nf);
    }
    for (size_t r = 0; r < R->n; r++) {
        if (R->a[r] == v) cert[2 * r] = ok;
        if (R->b[r] == v) cert[2 * r + 1] = ok;
    }
    return ok;
}

static inline int link_cert(simp *S, const ring *R, const double p[3], size_t x) {
    uint8_t c = S->sc.cert[x];
    return c != CERT_UNKNOWN ? c : link_cert_compute(S, R, p, x);
}

/* }====== */

/* {====== the plane rule and the test */

/* n x m along axis ax (the ax component of the cross product) is clearly
 * nonzero: its sine above 1e-6 in magnitude. Returns its sign, 0 if not. */
static inline int plane_turn(const double *a, const double *b, const double *c, int ax) {
    int u = (ax + 1) % 3, w = (ax + 2) % 3;
    double n0 = b[u] - a[u], n1 = b[w] - a[w], m0 = c[u] - a[u], m1 = c[w] - a[w];
    double o = n0 * m1 - n1 * m0;
    if (!(o * o > 1e-12 * (n0 * n0 + n1 * n1) * (m0 * m0 + m1 * m1))) return 0;
    return o > 0.0 ? 1 : -1;
}

/* The plane rule (docs/design.md "The intersection test's plane rule"):
 * with k's new star certified (the caller), a collapse whose star and p lie
 * in one axis plane exactly, whose replaced faces were all made by
 * collapses and turn the same way as the new triangles, creates no
 * intersection: the new triangles cover the same region as the old. */
static int plane_rule(const simp *S, const ring *R, const double p[3]) {
    const double *pi = P(S, R->i), *pj = P(S, R->j);
    int ax = -1;
    for (int k = 0; k < 3 && ax < 0; k++) {
        if (pi[k] != p[k] || pj[k] != p[k]) continue;
        int same = 1;
        for (size_t r = 0; r < R->n && same; r++) same = P(S, R->a[r])[k] == p[k] && P(S, R->b[r])[k] == p[k];
        if (same) ax = k;
    }
    if (ax < 0) return 0;
    for (size_t r = 0; r < R->n; r++)
        if (!S->fmade[R->face[r]]) return 0;
    for (size_t s = 0; s < R->ns; s++)
        if (!S->fmade[R->sface[s]]) return 0;
    int sg = 0;
    for (size_t r = 0; r < R->n; r++) {
        const double *a = P(S, R->a[r]), *b = P(S, R->b[r]);
        int tn = plane_turn(p, a, b, ax), to = plane_turn(R->from_j[r] ? pj : pi, a, b, ax);
        if (r == 0) sg = tn;
        if (tn == 0 || tn != sg || to != sg) return 0;
    }
    for (size_t s = 0; s < R->ns; s++) {
        const uint32_t *t = S->face[R->sface[s]].v;
        if (plane_turn(P(S, t[0]), P(S, t[1]), P(S, t[2]), ax) != sg) return 0;
    }
    return sg != 0;
}

/* The full test found a crossing. A build with FEMLOD_SIMPLIFY_PLANE_VERIFY=1
 * runs it after the plane rule accepted too, and prints any disagreement to
 * stderr (a diagnostic, not a test: the full test's conservative refusals
 * are disagreements too, docs/design.md); the rule's answer stands. */
static int plane_disagrees(const ring *R, const double p[3], int planar, uint32_t f, const double *const T[3],
                           const double *const Q[3], const uint32_t *qid) {
    if (!planar) return FEMLOD_REJECT_INTERSECTION;
    fprintf(stderr, "plane rule: edge %u (%u, %u) to (%.17g, %.17g, %.17g) accepted, full test: face %u\n", R->e, R->i,
            R->j, p[0], p[1], p[2], f);
    for (int c = 0; c < 3; c++) fprintf(stderr, "  T %.17g %.17g %.17g\n", T[c][0], T[c][1], T[c][2]);
    for (int c = 0; c < 3; c++) fprintf(stderr, "  Q %u %.17g %.17g %.17g\n", qid[c], Q[c][0], Q[c][1], Q[c][2]);
    return NO_REASON;
}

/* No new triangle may cross another triangle of the mesh (issue 3): each new
 * triangle is tested against the triangles whose grid cells its box
 * overlaps, the triangles being replaced excepted, and against the other new
 * triangles. Shared corners and edges are told to the test by vertex id. */
int fl_simp_intersect_check(simp *S, ring *R, const double p[3]) {
    if (!buf_reserve((void **)&S->sc.tbox, &S->sc.tbox_cap, 6 * R->n + 6, sizeof *S->sc.tbox) ||
        !buf_reserve((void **)&S->sc.tplane, &S->sc.tplane_cap, R->n + 1, sizeof *S->sc.tplane)) {
        S->oom = 1;
        return FEMLOD_REJECT_INTERSECTION;
    }
    /* boxes and planes of the new triangles (once, not per pair) and the
     * box of the whole new fan */
    double lo[3], hi[3];
    for (int k = 0; k < 3; k++) lo[k] = hi[k] = p[k];
    for (size_t r = 0; r < R->n; r++) {
        const double *a = P(S, R->a[r]), *b = P(S, R->b[r]);
        const double *T[3] = {p, a, b};
        fl_tri_plane_of(T, S->sc.tplane + r);
        double *bx = S->sc.tbox + 6 * r;
        for (int k = 0; k < 3; k++) {
            bx[k] = mn(p[k], mn(a[k], b[k])) - S->eps;
            bx[3 + k] = mx(p[k], mx(a[k], b[k])) + S->eps;
            lo[k] = mn(lo[k], bx[k]);
            hi[k] = mx(hi[k], bx[3 + k]);
        }
    }
    /* the faces being replaced (those at i or j: R's ring and shared
     * faces), told by their id range, then by a scan of the ring (no
     * per-face mark: its reads would miss the cache at every item) */
    uint32_t fmin = UINT32_MAX, fmax = 0;
    uint64_t fbits = 0; /* bit f % 64 of every such face: most others skip the scan */
    for (size_t r = 0; r < R->n; r++) {
        fmin = R->face[r] < fmin ? R->face[r] : fmin;
        fmax = R->face[r] > fmax ? R->face[r] : fmax;
        fbits |= (uint64_t)1 << (R->face[r] & 63u);
    }
    for (size_t s = 0; s < R->ns; s++) {
        fmin = R->sface[s] < fmin ? R->sface[s] : fmin;
        fmax = R->sface[s] > fmax ? R->sface[s] : fmax;
        fbits |= (uint64_t)1 << (R->sface[s] & 63u);
    }
    /* star certificates: k's now; a ring vertex's (interior, manifold)
     * only when a triangle at it meets a new triangle's box (link_cert):
     * on cover x4, 7.2 of the about 10 ring vertices per check */
    int kcert = 0, planar = 0;
    (void)planar;
    if (!buf_reserve((void **)&S->sc.cert, &S->sc.cert_cap, 2 * R->n + 2, 1)) {
        S->oom = 1;
        return FEMLOD_REJECT_INTERSECTION;
    }
    int certify = FEMLOD_SIMPLIFY_CERTIFY && !((S->vflag[R->i] | S->vflag[R->j]) & (V_BOUNDARY | V_NONMANIFOLD)) &&
                  R->n <= 64;
    memset(S->sc.cert, certify ? CERT_UNKNOWN : 0, 2 * R->n);
    if (certify) {
        const double *U[64] = {NULL}, *W[64] = {NULL};
        for (size_t r = 0; r < R->n; r++) {
            U[r] = P(S, R->a[r]);
            W[r] = P(S, R->b[r]);
        }
        kcert = star_embedded(p, U, W, R->n);
        if (kcert && FEMLOD_SIMPLIFY_PLANE_RULE && S->oriented && plane_rule(S, R, p)) {
            STAT(planar);
            if (!FEMLOD_SIMPLIFY_PLANE_VERIFY) return NO_REASON;
            planar = 1;
        }
    }
    /* one pass over the cells under the fan; each triangle met once */
    int c0[3], c1[3];
    fl_grid_range(&S->grid, lo, hi, c0, c1);
    /* a fast-pass worker reads cells of its slab and the two next to it
     * only: no other worker writes those (band_par) */
    if (S->par && !planar && (slab_of_cell(S, c0[S->slab_ax]) + 1 < S->slab || slab_of_cell(S, c1[S->slab_ax]) > S->slab + 1))
        return DEFER_REASON;
    for (int z = c0[2]; z <= c1[2]; z++)
        for (int y = c0[1]; y <= c1[1]; y++)
            for (int x = c0[0]; x <= c1[0]; x++) {
                size_t cell = fl_grid_cell(&S->grid, x, y, z);
                STAT(cells);
                uint32_t cnt = S->grid.cell[cell].count;
                uint32_t blk = S->grid.cell[cell].head;
                uint32_t lim = cnt ? (cnt - 1) % FL_GRID_BLOCK + 1 : 0;
                /* each triangle met once, in the first walked cell of its
                 * box (the box it was inserted with: its corners have not
                 * moved since), told by the block's first-cell bits without
                 * reading the triangle; not by a mark, which would be a
                 * write to a face a fast-pass worker does not own */
                uint8_t need = FL_GRID_NEED(x, y, z, c0);
                while (blk != UINT32_MAX) {
                    const fl_grid_block *B = S->grid.blocks + blk;
                    for (uint32_t s = 0; s < lim; s++) {
                        STAT(items);
                        if ((B->first[s] & need) != need) continue; /* met in an earlier cell */
                        uint32_t f = B->item[s];
                        if (f >= fmin && f <= fmax && (fbits >> (f & 63u) & 1u) && ring_has_face(R, f))
                            continue; /* being replaced */
                        const uint32_t *t = S->face[f].v;
                        const double *Q[3] = {P(S, t[0]), P(S, t[1]), P(S, t[2])};
                        double qb[6];
                        for (int k = 0; k < 3; k++) {
                            qb[k] = mn(Q[0][k], mn(Q[1][k], Q[2][k]));
                            qb[3 + k] = mx(Q[0][k], mx(Q[1][k], Q[2][k]));
                        }
                        if (qb[0] > hi[0] || qb[1] > hi[1] || qb[2] > hi[2] || qb[3] < lo[0] ||
                            qb[4] < lo[1] || qb[5] < lo[2])
                            continue;
                        /* the new triangles whose box meets it, as a
                         * mask per 64 of them, computed without branches
                         * (the boxes of one fan are too alike for the
                         * branch predictor); then those in ascending order */
                        for (size_t r0 = 0; r0 < R->n; r0 += 64) {
                            size_t r1 = R->n - r0 < 64 ? R->n : r0 + 64;
                            uint64_t hit = 0;
                            for (size_t r = r0; r < r1; r++) {
                                const double *bx = S->sc.tbox + 6 * r;
                                unsigned miss = (unsigned)(qb[0] > bx[3]) | (unsigned)(qb[1] > bx[4]) |
                                                (unsigned)(qb[2] > bx[5]) | (unsigned)(qb[3] < bx[0]) |
                                                (unsigned)(qb[4] < bx[1]) | (unsigned)(qb[5] < bx[2]);
                                hit |= (uint64_t)(miss ^ 1u) << (r - r0);
                            }
                            for (; hit; hit &= hit - 1) {
                                size_t r = r0 + (size_t)__builtin_ctzll(hit);
                                /* both in the certified star of a shared corner */
                                uint32_t ar = R->a[r], br = R->b[r];
                                if (((t[0] == ar || t[1] == ar || t[2] == ar) && link_cert(S, R, p, 2 * r)) ||
                                    ((t[0] == br || t[1] == br || t[2] == br) && link_cert(S, R, p, 2 * r + 1)))
                                    continue;
                                const double *T[3] = {p, P(S, R->a[r]), P(S, R->b[r])};
                                uint32_t tid[3] = {K_ID, R->a[r], R->b[r]};
                                STAT(tritri);
                                if (fl_tri_tri_intersect_p(T, tid, S->sc.tplane + r, Q, t, S->eps))
                                    return plane_disagrees(R, p, planar, f, T, Q, t);
                            }
                        }
                    }
                    blk = B->next;
                    lim = FL_GRID_BLOCK;
                }
            }
    /* the new triangles among themselves: they all share k */
    for (size_t r = 0; r < R->n && !kcert; r++) {
        const double *T[3] = {p, P(S, R->a[r]), P(S, R->b[r])};
        uint32_t tid[3] = {K_ID, R->a[r], R->b[r]};
        const double *br = S->sc.tbox + 6 * r;
        for (size_t s2 = r + 1; s2 < R->n; s2++) {
            const double *bs = S->sc.tbox + 6 * s2;
            if (br[0] > bs[3] || br[1] > bs[4] || br[2] > bs[5] || br[3] < bs[0] || br[4] < bs[1] ||
                br[5] < bs[2])
                continue;
            const double *Q[3] = {p, P(S, R->a[s2]), P(S, R->b[s2])};
            uint32_t qid[3] = {K_ID, R->a[s2], R->b[s2]};
            if (fl_tri_tri_intersect_p(T, tid, S->sc.tplane + r, Q, qid, S->eps))
                return plane_disagrees(R, p, planar, UINT32_MAX, T, Q, qid);
        }
    }
    return NO_REASON;
}

/* }====== */

/* {====== the grid of the live faces */

static int grid_add_face(simp *S, uint32_t f) {
    double lo[3], hi[3];
    face_bbox(S, f, lo, hi);
    return fl_grid_insert(&S->grid, f, lo, hi);
}

void fl_simp_grid_remove_face(simp *S, uint32_t f) {
    double lo[3], hi[3];
    face_bbox(S, f, lo, hi);
    fl_grid_remove(&S->grid, f, lo, hi);
}

int fl_simp_build_grid(simp *S, double h) {
    double lo[3] = {__builtin_inf(), __builtin_inf(), __builtin_inf()};
    double hi[3] = {-__builtin_inf(), -__builtin_inf(), -__builtin_inf()};
    for (size_t v = 0; v < S->nv; v++) {
        if (S->vflag[v] & V_DEAD || S->fcount[v] == 0) continue;
        for (int k = 0; k < 3; k++) {
            lo[k] = mn(lo[k], S->pos[3 * v + k]);
            hi[k] = mx(hi[k], S->pos[3 * v + k]);
        }
    }
    if (!(lo[0] <= hi[0])) {
        for (int k = 0; k < 3; k++) lo[k] = hi[k] = 0.0;
    }
    fl_grid_free(&S->grid);
    S->grid_gen++;
    if (!fl_grid_init(&S->grid, lo, hi, h, 2 * S->live + 4096)) return 0;
    S->grid_h = S->grid.h;
    S->grid_live = S->live;
    for (size_t f = 0; f < S->nt; f++)
        if (face_alive(S, (uint32_t)f) && !grid_add_face(S, (uint32_t)f)) return 0;
    return 1;
}

/* }====== */
