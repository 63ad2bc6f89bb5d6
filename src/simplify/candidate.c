/*
 * candidate.c - an edge's evaluation (paper 4.2.1-4.2.3): its ring, its
 * candidate positions, the validity checks and the priority; and the
 * checks run only when an edge is popped.
 *
 *   gather                  the position-independent part: which positions
 *                           k may take, C4 valence, the faces of i and j,
 *                           Sz_DIF (4.2.3)
 *   fl_simp_link_check      the link condition (Dey et al. 1999; the
 *                           tetrahedron and handle cases as in OpenMesh's
 *                           is_collapse_ok), at pop time
 *   make_candidates         midpoint and the robust optimum
 *                           (fl_quadric_optimum2, cached per edge); the
 *                           fixed endpoint; endpoints and midpoint along a
 *                           feature line (4.2.1)
 *   eval_candidate,         C1 tolerance (or error_order's cap), C3 size, degeneracy, turn against
 *   tri_eval                the current mesh, C2 stretch (4.2.2), and
 *                           rho = Sz_DIF * St_MIN * St_AVE (4.2.3)
 *   fl_simp_evaluate        all of it for one edge
 *   fl_simp_bound_edge      an upper bound of the priority (the exact lazy
 *                           queue, FEMLOD_SIMPLIFY_BOUND)
 *   fl_simp_expensive_checks  at pop time: normal cones (cone_check, PMP's
 *                           NormalCone), deviation (deviation.c),
 *                           intersections
 *                           (intersect_grid.c)
 *
 * Invariants: an evaluation writes only its ring, its thread's scratch,
 * its own edge's cached optimum (eopt, E_OPT) and hint, and the rejection
 * counts of its view, so evaluations of different edges may run on
 * different threads; tri_eval is the one place a new triangle's measures
 * are computed, so the priority and its bound agree bit for bit; ties
 * between candidates keep the earlier.
 */
#include "simp.h"

#include <float.h>

#include <stdlib.h>

#ifndef FEMLOD_SIMPLIFY_SZDIF_RING
#define FEMLOD_SIMPLIFY_SZDIF_RING 1 /* Sz_DIF over every triangle at i or j */
#endif
#ifndef FEMLOD_SIMPLIFY_EIGEN_REL
#define FEMLOD_SIMPLIFY_EIGEN_REL 1e-3 /* eigen directions kept in the optimum */
#endif
#ifndef FEMLOD_SIMPLIFY_LINE_TURN
#define FEMLOD_SIMPLIFY_LINE_TURN 20.0 /* degrees: a feature line this straight takes midpoints */
#endif
#ifndef FEMLOD_SIMPLIFY_USE_OPTIMUM
#define FEMLOD_SIMPLIFY_USE_OPTIMUM 1
#endif

/* candidate modes */
enum {
    M_FREE,   /* midpoint and optimum */
    M_KEEP_I, /* k = p_i (i fixed, or on a feature line that j is not on) */
    M_KEEP_J,
    M_LINE    /* i and j on one feature line: the endpoints, and the midpoint where the line is straight */
};

/* R's arrays for n ring faces; 0 on ENOMEM (what grew is kept). */
static int ring_reserve(ring *R, size_t n) {
    if (n <= R->cap) return 1;
    size_t c = R->cap ? R->cap : 32;
    while (c < n) c *= 2;
    uint32_t *f = fl_realloc(R->face, c, sizeof *f);
    if (f) R->face = f;
    uint32_t *a = fl_realloc(R->a, c, sizeof *a);
    if (a) R->a = a;
    uint32_t *b = fl_realloc(R->b, c, sizeof *b);
    if (b) R->b = b;
    uint8_t *fj = fl_realloc(R->from_j, c, sizeof *fj);
    if (fj) R->from_j = fj;
    double *l = fl_realloc(R->lab, c, sizeof *l);
    if (l) R->lab = l;
    double *l2 = fl_realloc(R->lab2, c, sizeof *l2);
    if (l2) R->lab2 = l2;
    if (!f || !a || !b || !fj || !l || !l2) return 0;
    R->cap = c;
    return 1;
}

/* {====== gather: the position-independent part of an edge's evaluation */

/* Which of gather's first topology checks refuses edge e (they come first
 * in every evaluation, in this order): FL_TOPO_NONMANIFOLD (a non-manifold
 * edge or end), FL_TOPO_FEATURE (two fixed ends, or a feature vertex that
 * would leave its line or merge with another line across a non-feature
 * edge), FL_TOPO_BOUNDARY (an interior edge between two boundary vertices:
 * it would pinch the surface), or -1 (none: a later check decides). */
int fl_simp_topology_kind(const simp *S, uint32_t e) {
    uint32_t i = S->edge[e].v[0], j = S->edge[e].v[1];
    uint8_t fi = S->vflag[i], fj = S->vflag[j];
    unsigned nf = S->edge[e].nf;
    int feature = (S->edge[e].flag & E_FEATURE) != 0;
    if (nf == 0 || nf > 2 || ((fi | fj) & V_NONMANIFOLD)) return FL_TOPO_NONMANIFOLD;
    int fixi = (fi & V_FIXED) != 0, fixj = (fj & V_FIXED) != 0;
    int feati = S->fdeg[i] > 0, featj = S->fdeg[j] > 0;
    if (fixi && fixj) return FL_TOPO_FEATURE;
    if ((fixi && featj && !feature) || (fixj && feati && !feature) || (!fixi && !fixj && feati && featj && !feature))
        return FL_TOPO_FEATURE;
    if (nf != 1 && (fi & V_BOUNDARY) && (fj & V_BOUNDARY)) return FL_TOPO_BOUNDARY;
    return -1;
}

/* Returns NO_REASON when the edge may be collapsed (position aside) and
 * fills R; otherwise the reason. */
static int gather(simp *S, ring *R, uint32_t e) {
    uint32_t i = S->edge[e].v[0], j = S->edge[e].v[1];
    R->e = e;
    R->i = i;
    R->j = j;
    R->n = 0;
    R->ns = 0;
    uint8_t fi = S->vflag[i], fj = S->vflag[j];
    unsigned nf = S->edge[e].nf;

    /* Which positions may k take (method-notes "Optimal position"): fixed
     * vertices stay, a vertex on one feature line only slides along it,
     * two features never merge across a non-feature edge; an interior edge
     * between two boundary vertices would pinch the surface at k. The
     * refusals are fl_simp_topology_kind's, which the stop's count uses too. */
    if (fl_simp_topology_kind(S, e) >= 0) return FEMLOD_REJECT_TOPOLOGY;
    int fixi = (fi & V_FIXED) != 0, fixj = (fj & V_FIXED) != 0;
    int feati = S->fdeg[i] > 0, featj = S->fdeg[j] > 0;
    if (fixi) R->mode = M_KEEP_I;
    else if (fixj) R->mode = M_KEEP_J;
    else if (feati && featj) R->mode = M_LINE; /* both on the line: slide along it */
    else if (feati) R->mode = M_KEEP_I;
    else if (featj) R->mode = M_KEEP_J;
    else R->mode = M_FREE;

    /* C4 (method-notes "Valid edges"): val(i) + val(j) - 4 interior, - 3 boundary. */
    int boundary_edge = nf == 1;
    int newval = (int)S->val[i] + (int)S->val[j] - (boundary_edge ? 3 : 4);
    R->newval = newval;
    if (S->val_on && newval > S->maxval) return FEMLOD_REJECT_VALENCE;
    if (newval < (boundary_edge ? 2 : 3) || newval > MAX_VSTARS - 2) return FEMLOD_REJECT_TOPOLOGY;

    STAT(rings);
    size_t need = (size_t)S->fcount[i] + S->fcount[j];
    if (!ring_reserve(R, need)) {
        S->oom = 1;
        return FEMLOD_REJECT_TOPOLOGY;
    }
    /* Sz_DIF (4.2.3) over every face at i or j (FEMLOD_SIMPLIFY_SZDIF_RING)
     * or the edge's own, summed in list order */
    double szsum = 0.0;
    size_t szn = 0;
    size_t n = 0, ns = 0;
    /* locals: the stores into R below could otherwise alias them */
    const face_rec *const face = S->face;
    uint32_t *const rface = R->face, *const ra = R->a, *const rb = R->b;
    uint8_t *const rfrom = R->from_j;
    for (int side = 0; side < 2; side++) {
        uint32_t v = side ? j : i, o = side ? i : j;
        const uint32_t *fl = S->refs + S->fstart[v];
        uint32_t cnt = S->fcount[v];
        if (FEMLOD_SIMPLIFY_SZDIF_RING) szn += cnt;
        for (uint32_t m = 0; m < cnt; m++) {
            uint32_t f = fl[m];
            const face_rec *F = face + f;
            uint32_t t0 = F->v[0], t1 = F->v[1], t2 = F->v[2], a, b;
            if (t0 == v) {
                a = t1;
                b = t2;
            } else if (t1 == v) {
                a = t2;
                b = t0;
            } else {
                a = t0;
                b = t1;
            }
            if (FEMLOD_SIMPLIFY_SZDIF_RING) szsum += F->inv;
            if (a == o || b == o) {
                if (side == 0) {
                    if (ns == 2) return FEMLOD_REJECT_TOPOLOGY;
                    R->sface[ns] = f;
                    R->sopp[ns] = a == o ? b : a;
                    ns++;
                    if (!FEMLOD_SIMPLIFY_SZDIF_RING) {
                        szsum += F->inv;
                        szn++;
                    }
                }
                continue;
            }
            rface[n] = f;
            ra[n] = a;
            rb[n] = b;
            rfrom[n] = (uint8_t)side;
            n++;
        }
    }
    R->n = n;
    R->ns = ns;
    if (R->ns != nf) return FEMLOD_REJECT_TOPOLOGY;
    if (R->ns == 2 && R->sopp[0] == R->sopp[1]) return FEMLOD_REJECT_TOPOLOGY;
    R->szdif = szn ? szsum / (double)szn : 1.0;
    if (S->phase == 0) {
        /* pre-phase: the least stretch among the faces the collapse removes
         * or changes */
        double stmin = 2.0;
        for (int side = 0; side < 2; side++) {
            uint32_t v = side ? j : i, o = side ? i : j;
            const uint32_t *fl = S->refs + S->fstart[v];
            for (uint32_t m = 0; m < S->fcount[v]; m++) {
                const uint32_t *t = S->face[fl[m]].v;
                if (side == 1 && (t[0] == o || t[1] == o || t[2] == o)) continue;
                double st = tri_stretch(P(S, t[0]), P(S, t[1]), P(S, t[2]), NULL);
                if (st < stmin) stmin = st;
            }
        }
        R->st_removed = stmin;
    }

    /* the opposite vertices lose a neighbour: keep them at least triangular */
    for (size_t s = 0; s < R->ns; s++) {
        uint32_t x = R->sopp[s];
        unsigned minval = (S->vflag[x] & V_BOUNDARY) ? 2 : 3;
        if (S->val[x] - 1 < minval) return FEMLOD_REJECT_TOPOLOGY;
        if (S->vflag[x] & V_NONMANIFOLD) return FEMLOD_REJECT_TOPOLOGY;
    }
    /* two feature edges of one removed face would merge into one (only
     * possible when i or j is on a feature: fdeg counts feature edges,
     * collapse keeps the count; fixed vertices, corners among them, are
     * checked whatever their count) */
    int any_feature = feati || featj || fixi || fixj;
    for (size_t s = 0; s < R->ns && any_feature; s++) {
        const uint32_t *te = S->tedge + 3 * (size_t)R->sface[s];
        int nfeat = 0;
        for (int c = 0; c < 3; c++)
            if (te[c] != e && (S->edge[te[c]].flag & E_FEATURE)) nfeat++;
        if (nfeat == 2) return FEMLOD_REJECT_TOPOLOGY;
    }

    return NO_REASON;
}

/* Link condition (Dey et al. 1999): the common neighbours of i and j are
 * exactly the opposite vertices of the faces on the edge: no handle pinched,
 * no duplicate face, no tetrahedron closed. It depends on the ring only, not
 * on the position, and fails rarely: it is checked when an edge is popped,
 * not at every evaluation (measured: a fifth of the evaluation time). */
int fl_simp_link_check(simp *S, const ring *R) {
    STAT(links);
    uint32_t mi = next_stamp(S);
    uint32_t mj = next_stamp(S);
    for (size_t r = 0; r < R->n; r++)
        if (!R->from_j[r]) S->vmark[R->a[r]] = S->vmark[R->b[r]] = mi;
    for (size_t s = 0; s < R->ns; s++) S->vmark[R->sopp[s]] = mi;
    unsigned common = 0;
    for (size_t r = 0; r < R->n; r++) {
        if (!R->from_j[r]) continue;
        uint32_t ab[2] = {R->a[r], R->b[r]};
        for (int q = 0; q < 2; q++) {
            uint32_t x = ab[q];
            if (S->vmark[x] == mi) {
                S->vmark[x] = mj;
                common++;
            }
        }
    }
    /* the opposite vertices are neighbours of j through the shared faces only
     * when j has no other face at them; count them once */
    for (size_t s = 0; s < R->ns; s++) {
        uint32_t x = R->sopp[s];
        if (S->vmark[x] == mi) {
            S->vmark[x] = mj;
            common++;
        }
    }
    if (common != R->ns) return FEMLOD_REJECT_TOPOLOGY;
    return NO_REASON;
}

/* }====== */

/* {====== candidates: C1-C3, foldover against the current mesh, priority */

/* The new triangle (p, a_r, b_r) of ring face r: C3 size, degeneracy,
 * turn against the face it replaces, C2 stretch (phase 1). On success *st
 * is its stretch, clamped to 1. The one place these are computed: the
 * priority and its upper bound (bound_edge) must agree bit for bit. */
static inline int tri_eval(const simp *S, const ring *R, size_t r, const double p[3], double *st_out) {
    const double *a = P(S, R->a[r]), *b = P(S, R->b[r]);
    double ea[3], eb[3], n[3];
    sub3(ea, a, p);
    sub3(eb, b, p);
    double la2 = dot3(ea, ea), lb2 = dot3(eb, eb), lab2 = R->lab2[r];
    double L2 = mx(la2, mx(lb2, lab2));
    if (L2 > S->lim_sz2) return FEMLOD_REJECT_SIZE;
    cross3(n, ea, eb);
    double n2 = dot3(n, n);
    if (!(n2 > 0.0)) return FEMLOD_REJECT_STRETCH;
    /* foldover: the normal may not flip nor turn past max_normal_change */
    const float *fo = S->face[R->face[r]].n;
    double d = n[0] * fo[0] + n[1] * fo[1] + n[2] * fo[2]; /* NaN: the old face was degenerate, no test */
    if (d <= 0.0) return FEMLOD_REJECT_FOLDOVER;
    if (d * d < S->lim_turn2 * n2) return FEMLOD_REJECT_FOLDOVER;
    /* C2: St = sqrt(3) |n| / (s L), compared squared */
    double s = 0.5 * (sqrt(la2) + sqrt(lb2) + R->lab[r]);
    double den = s * s * L2;
    double st2 = 3.0 * n2 / den;
    if (st2 < S->lim_st2) return FEMLOD_REJECT_STRETCH;
    double st = sqrt(st2);
    if (st > 1.0) st = 1.0;
    *st_out = st;
    return NO_REASON;
}

/* |a - b| of ring face r (squared and not). */
static inline void ring_length(const simp *S, ring *R, size_t r) {
    R->lab2[r] = dist2(P(S, R->a[r]), P(S, R->b[r]));
    R->lab[r] = sqrt(R->lab2[r]);
}

/* C1, then every new triangle; *hint gets the face of the failing or the
 * least-stretch triangle (for bound_edge), UINT32_MAX when none. */
static int eval_candidate(simp *S, ring *R, const double p[3], double *rho, uint32_t *hint) {
    STAT(cands);
    *hint = UINT32_MAX;
    const fl_quadric *qi = S->q + R->i, *qj = S->q + R->j;
    if (S->lim_on && fl_quadric_eval2(qi, qj, p) > S->lim_tol) return FEMLOD_REJECT_TOLERANCE;
    double stsum = 0.0, stmin = 2.0;
    size_t rmin = 0;
    for (size_t r = 0; r < R->n; r++) {
        double st = 0.0;
        int w = tri_eval(S, R, r, p, &st);
        if (w != NO_REASON) {
            *hint = R->face[r];
            return w;
        }
        stsum += st;
        if (st < stmin) {
            stmin = st;
            rmin = r;
        }
    }
    if (R->n) *hint = R->face[rmin];
    if (S->phase == 0 && !(stmin > R->st_removed)) return FEMLOD_REJECT_STRETCH;
    STAT(cand_ok);
    double stavg = R->n ? stsum / (double)R->n : 1.0;
    if (!R->n) stmin = 1.0;
    /* 4.2.3: rho = Sz_DIF * St_MIN * St_AVE (tau_SZ is a common factor) */
    *rho = R->szdif * stmin * stavg;
    return NO_REASON;
}

/* The other feature edge at v (v on one line), as its far vertex. */
static uint32_t line_neighbour(const simp *S, uint32_t v, uint32_t e) {
    const uint32_t *fl = S->refs + S->fstart[v];
    for (uint32_t m = 0; m < S->fcount[v]; m++) {
        const uint32_t *te = S->tedge + 3 * (size_t)fl[m];
        for (int c = 0; c < 3; c++) {
            uint32_t ed = te[c];
            if (ed == e || !(S->edge[ed].flag & E_FEATURE)) continue;
            uint32_t a = S->edge[ed].v[0], b = S->edge[ed].v[1];
            if (a == v) return b;
            if (b == v) return a;
        }
    }
    return UINT32_MAX;
}

/* The candidate positions of the gathered edge (method-notes "Optimal
 * position"), into R->cand, the preferred first (ties keep the earlier):
 *   M_KEEP_*: the fixed endpoint;
 *   M_LINE: a collapse along a feature line (a vertex on one feature line
 *     may only move along it): the endpoints lie on the line exactly; the
 *     midpoint comes first, but only where the line is straight (the
 *     neighbouring feature edges continue the edge within
 *     FEMLOD_SIMPLIFY_LINE_TURN degrees): elsewhere it would cut the corner
 *     of a curved line, and repeated collapses would shrink it;
 *   M_FREE: the midpoint and the robust optimum. */
static void make_candidates(simp *S, ring *R) {
    const double *pi = P(S, R->i), *pj = P(S, R->j);
    if (R->mode == M_KEEP_I || R->mode == M_KEEP_J) {
        memcpy(R->cand[0], R->mode == M_KEEP_I ? pi : pj, sizeof R->cand[0]);
        R->ncand = 1;
        return;
    }
    if (R->mode == M_LINE) {
        uint32_t oi = line_neighbour(S, R->i, R->e), oj = line_neighbour(S, R->j, R->e);
        int straight = 0;
        if (oi != UINT32_MAX && oj != UINT32_MAX) {
            double u[3], a[3], b[3];
            sub3(u, pj, pi);
            sub3(a, pi, P(S, oi));
            sub3(b, P(S, oj), pj);
            double uu = dot3(u, u), ua = dot3(u, a), ub = dot3(u, b);
            const double cl = cos(FEMLOD_SIMPLIFY_LINE_TURN * PI / 180.0), c2 = cl * cl;
            straight = ua > 0 && ub > 0 && ua * ua >= c2 * uu * dot3(a, a) && ub * ub >= c2 * uu * dot3(b, b);
        }
        int n = 0;
        if (straight) {
            for (int k = 0; k < 3; k++) R->cand[n][k] = 0.5 * (pi[k] + pj[k]);
            n++;
        }
        memcpy(R->cand[n++], pi, 3 * sizeof *pi);
        memcpy(R->cand[n++], pj, 3 * sizeof *pj);
        R->ncand = n;
        return;
    }
    double *mid = R->cand[0];
    for (int k = 0; k < 3; k++) mid[k] = 0.5 * (pi[k] + pj[k]);
    R->ncand = 1;
    if (FEMLOD_SIMPLIFY_USE_OPTIMUM) {
        /* cached while i and j keep their positions and quadrics (cleared
         * for the edges at k after each collapse, reevaluate_ring) */
        uint8_t *fl = &S->edge[R->e].state;
        double *opt = S->eopt + 3 * (size_t)R->e;
        if (!(*fl & E_OPT)) {
            STAT(solves);
            int kept = fl_quadric_optimum2(S->q + R->i, S->q + R->j, mid, FEMLOD_SIMPLIFY_EIGEN_REL, opt);
            /* an optimum farther than the edge length from the midpoint is
             * the sign of a near-singular system, not a better position */
            int use = kept > 0 && dist2(opt, mid) <= dist2(pi, pj) && dist2(opt, mid) > 0.0;
            *fl = (uint8_t)((*fl & ~E_OPTC) | E_OPT | (use ? E_OPTC : 0));
        }
        if (*fl & E_OPTC) {
            memcpy(R->cand[1], opt, 3 * sizeof *opt);
            R->ncand = 2;
        }
    }
}

/* Full cheap evaluation: returns the best priority (< 0 when no candidate is
 * valid) and leaves the candidates in R, the best valid one first. */
double fl_simp_evaluate(simp *S, ring *R, uint32_t e) {
    STAT(evals);
    R->ncand = 0;
    R->tolfail = 0;
    edge_rec *E = S->edge + e;
    E->state &= (uint8_t)~E_C1KEY;
    int why = gather(S, R, e);
    if (why != NO_REASON) {
        S->rejected[why]++;
        R->reason = why;
        E->key = -1.0f;
        return -1.0;
    }
    make_candidates(S, R);
    for (size_t r = 0; r < R->n; r++) ring_length(S, R, r);
    double best = -1.0;
    int bi = -1, w = NO_REASON, alltol = 1;
    for (int c = 0; c < R->ncand; c++) {
        uint32_t h;
        w = eval_candidate(S, R, R->cand[c], &R->rho[c], &h);
        if (FEMLOD_SIMPLIFY_BOUND && c < 2) S->ehint[2 * (size_t)e + c] = h;
        R->ok[c] = w == NO_REASON;
        alltol &= w == FEMLOD_REJECT_TOLERANCE;
        if (R->ok[c] && R->rho[c] > best) { /* ties keep the earlier */
            best = R->rho[c];
            bi = c;
        }
    }
    if (bi > 0) { /* best first */
        double t[3], tr = R->rho[0];
        int to = R->ok[0];
        memcpy(t, R->cand[0], sizeof t);
        memcpy(R->cand[0], R->cand[bi], sizeof t);
        memcpy(R->cand[bi], t, sizeof t);
        R->rho[0] = R->rho[bi];
        R->rho[bi] = tr;
        R->ok[0] = R->ok[bi];
        R->ok[bi] = to;
    }
    if (best < 0.0) {
        S->rejected[w]++;
        R->reason = w;
        R->tolfail = alltol; /* every candidate failed C1, which depends on i and j only */
        E->key = -1.0f;
        if (alltol && R->mode != M_LINE && S->sched && S->phase == 1) {
            /* error_order's rounds: minus a lower bound of the least C1
             * error as the key (E_C1KEY): no cap below it lets a candidate
             * pass while i and j keep their positions (M_LINE's midpoint
             * depends on the feature edges around them too); docs/design.md
             * "Cap rounds without the evaluations that cannot change" */
            double m = HUGE_VAL;
            for (int c = 0; c < R->ncand; c++) m = mn(m, fl_quadric_eval2(S->q + R->i, S->q + R->j, R->cand[c]));
            float f = (float)m; /* rounded down below */
            if ((double)f > m) f = nextafterf(f, 0.0f);
            if (f > 0.0f && f < FLT_MAX) {
                E->key = -f;
                E->state |= E_C1KEY;
            }
        }
    }
    return best;
}

/* An upper bound of the priority evaluate would give an edge away from the
 * last collapse's vertex k, for the lazy queue (docs/simplify.md "Exact lazy
 * re-evaluation"): the edge's endpoints, hence its candidates and their
 * quadric errors, are unchanged; of its new triangles only those with
 * corner k changed. Exact in what it decides: returns < 0, with R->tolfail
 * set as evaluate would set it, when evaluate would find no valid
 * candidate by the checks it runs (topology and valence, C1, and the
 * per-triangle checks of the triangles at k); otherwise a value >= the
 * priority evaluate would return: rho = Sz_DIF * St_MIN * St_AVE with the
 * stretch of every triangle not at k replaced by 1, its upper limit (the
 * products, sum and quotient are monotone under rounding, so the bound
 * holds in floating point too). */
double fl_simp_bound_edge(simp *S, ring *R, uint32_t e, uint32_t k) {
    STAT(bounds);
    R->ncand = 0;
    R->tolfail = 0;
    int why = gather(S, R, e);
    if (why != NO_REASON) {
        S->rejected[why]++;
        return -1.0;
    }
    make_candidates(S, R);
    const fl_quadric *qi = S->q + R->i, *qj = S->q + R->j;
    /* the triangles the bound evaluates: at k, or the last evaluation's
     * least-stretch or failing one (ehint) */
    uint32_t h0 = S->ehint[2 * (size_t)e], h1 = R->ncand > 1 ? S->ehint[2 * (size_t)e + 1] : UINT32_MAX;
    for (size_t r = 0; r < R->n; r++)
        if (R->a[r] == k || R->b[r] == k || R->face[r] == h0 || R->face[r] == h1) ring_length(S, R, r);
    double ub = -1.0;
    int alltol = 1, w = NO_REASON;
    for (int c = 0; c < R->ncand; c++) {
        const double *p = R->cand[c];
        if (S->lim_on && fl_quadric_eval2(qi, qj, p) > S->lim_tol) {
            w = FEMLOD_REJECT_TOLERANCE;
            continue;
        }
        alltol = 0;
        double stmin = 1.0, stsum = 0.0;
        int bad = 0;
        uint32_t h = c < 2 ? S->ehint[2 * (size_t)e + c] : UINT32_MAX;
        for (size_t r = 0; r < R->n && !bad; r++) {
            if (R->a[r] != k && R->b[r] != k && R->face[r] != h) {
                stsum += 1.0;
                continue;
            }
            double st = 0.0;
            w = tri_eval(S, R, r, p, &st);
            if (w != NO_REASON) bad = 1;
            stsum += st;
            if (st < stmin) stmin = st;
        }
        if (bad) continue;
        double b = R->n ? R->szdif * stmin * (stsum / (double)R->n) : R->szdif;
        if (b > ub) ub = b;
    }
    if (ub < 0.0) {
        S->rejected[w]++;
        R->tolfail = alltol;
    }
    return ub;
}

/* }====== */

/* {====== expensive checks, run when an edge is popped */

/* Normal cones (PMP's NormalCone, pmp/algorithms/normal_cone.h): c grows to
 * hold the cone of axis n2 and half-angle a2 too. */
static void cone_merge(float c[4], const double n2[3], double a2) {
    double n1[3] = {c[0], c[1], c[2]}, a1 = c[3];
    double dp = dot3(n1, n2);
    if (dp > 0.99999) {
        c[3] = (float)mx(a1, a2);
        return;
    }
    if (dp < -0.99999) {
        c[3] = (float)PI;
        return;
    }
    double ca = acos(dp);
    double amin = mn(-a1, ca - a2), amax = mx(a1, ca + a2);
    double ang = 0.5 * (amax - amin), axis = 0.5 * (amin + amax);
    double s = sin(ca), w1 = sin(ca - axis) / s, w2 = sin(axis) / s;
    double m[3];
    for (int k = 0; k < 3; k++) m[k] = w1 * n1[k] + w2 * n2[k];
    double l = sqrt(dot3(m, m));
    if (l > 0)
        for (int k = 0; k < 3; k++) c[k] = (float)(m[k] / l);
    c[3] = (float)ang;
}

static int cone_check(simp *S, ring *R, const double p[3]) {
    if (!buf_reserve((void **)&S->sc.newcone, &S->sc.newcone_cap, 4 * R->n, sizeof(float))) {
        S->oom = 1;
        return FEMLOD_REJECT_FOLDOVER;
    }
    /* twice the per-collapse limit: the drift bound (docs/simplify.md) */
    double lim = mn(2.0 * S->max_nc, 180.0) * PI / 180.0;
    for (size_t r = 0; r < R->n; r++) {
        const double *a = P(S, R->a[r]), *b = P(S, R->b[r]);
        double ea[3], eb[3], n[3];
        sub3(ea, a, p);
        sub3(eb, b, p);
        cross3(n, ea, eb);
        double l = sqrt(dot3(n, n));
        for (int k = 0; k < 3; k++) n[k] /= l;
        /* the cone holds the input normals the face stands for; the new
         * normal must stay within max_normal_change of all of them */
        float *c = S->sc.newcone + 4 * r;
        memcpy(c, S->cone + 4 * (size_t)R->face[r], 4 * sizeof(float));
        /* a removed face's area goes to the new faces at its opposite
         * vertex (merging it into every new face, as PMP does, would mix
         * the two sides of every feature line collapsed along) */
        for (size_t s = 0; s < R->ns; s++) {
            if (R->a[r] != R->sopp[s] && R->b[r] != R->sopp[s]) continue;
            const float *o = S->cone + 4 * (size_t)R->sface[s];
            double on[3] = {o[0], o[1], o[2]};
            cone_merge(c, on, o[3]);
        }
        double ca = n[0] * c[0] + n[1] * c[1] + n[2] * c[2];
        ca = ca > 1.0 ? 1.0 : (ca < -1.0 ? -1.0 : ca);
        if (acos(ca) + c[3] > lim) return FEMLOD_REJECT_FOLDOVER;
    }
    return NO_REASON;
}

/* Candidate c passes the checks that are too costly for every evaluation. */
int fl_simp_expensive_checks(simp *S, ring *R, int c) {
    STAT(expensive);
    const double *p = R->cand[c];
    int w;
    if (S->cone_on && (w = cone_check(S, R, p)) != NO_REASON) return w;
    if (S->dev_on && (w = fl_simp_deviation_check(S, R, p, &S->npts)) != NO_REASON) return w;
    return fl_simp_intersect_check(S, R, p);
}

/* }====== */
