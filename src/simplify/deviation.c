/*
 * deviation.c - max_deviation: the two-sided distance bound between the
 * output and the input surface, held at samples (docs/design.md "A distance
 * bound that holds").
 *
 *   the input tree            an AABB tree over the input triangles in slot
 *                             order (leaves of DEV_LEAF faces, a complete
 *                             binary tree above them): "is some input
 *                             triangle within d of x?"
 *   fl_simp_setup_deviation   the input samples (vertices, edge points,
 *                             face grids) in the per-face lists, the tree
 *   fl_simp_deviation_check   at pop time: every sample held by a changed
 *                             face re-assigned within d of a new triangle
 *                             (backward), every new output sample within d
 *                             of the input (forward)
 *
 * Invariants: every input sample is held by one live face within d of it
 * (or is an input vertex still at its place in the mesh); every output
 * vertex, edge sample and face sample is within d of the input. The check's
 * answer depends only on distances compared with d^2, never on the search
 * order or the per-thread hint, so results are the same for every thread
 * count.
 */
#include "simp.h"

#include <stdlib.h>

#ifndef FEMLOD_SIMPLIFY_DEV_SPACING
#define FEMLOD_SIMPLIFY_DEV_SPACING 0.5 /* sample spacing h / mean input edge (docs/simplify.md) */
#endif
#ifndef FEMLOD_SIMPLIFY_DEV_MARGIN
#define FEMLOD_SIMPLIFY_DEV_MARGIN 0.9 /* samples are held to this fraction of max_deviation */
#endif
#ifndef FEMLOD_SIMPLIFY_DEV_MAXDIV
#define FEMLOD_SIMPLIFY_DEV_MAXDIV 64.0 /* divisions of one edge or triangle at most */
#endif
#define DEV_LEAF 4
#ifndef FEMLOD_SIMPLIFY_DEV_HINTS
#define FEMLOD_SIMPLIFY_DEV_HINTS 2 /* leaves tried on each side of the last answer */
#endif

/* {====== the input tree */

struct dev_tree {
    size_t nt;           /* faces (slots at set-up) */
    double *corner;      /* 9 coordinates per face: a leaf's faces are adjacent in memory */
    float *box;          /* 6 per node (lo, hi), level by level from the leaves */
    size_t off[64];      /* first node of each level */
    size_t count[64];    /* nodes of each level */
    int levels;
};

static float float_down(double x) {
    float f = (float)x;
    return (double)f > x ? nextafterf(f, -__builtin_inff()) : f;
}

static float float_up(double x) {
    float f = (float)x;
    return (double)f < x ? nextafterf(f, __builtin_inff()) : f;
}

static double box_dist2(const float *b, const double x[3]) {
    double d = 0.0;
    for (int k = 0; k < 3; k++) {
        double e = 0.0;
        if (x[k] < b[k])
            e = b[k] - x[k];
        else if (x[k] > b[3 + k])
            e = x[k] - b[3 + k];
        d += e * e;
    }
    return d;
}

static int leaf_near(simp *S, const struct dev_tree *t, size_t leaf, const double x[3], double r2) {
    (void)S; /* only the stats build counts */
    size_t lo = leaf * DEV_LEAF, hi = lo + DEV_LEAF < t->nt ? lo + DEV_LEAF : t->nt;
    for (size_t f = lo; f < hi; f++) {
        const double *c = t->corner + 9 * f;
        STAT(dev_tris);
        if (fl_point_tri_dist2(x, c, c + 3, c + 6) <= r2) return 1;
    }
    return 0;
}

/* 1 when some input triangle lies within sqrt(r2) of x. *hint: a leaf to
 * try first, the leaf that answered on return (speed only). */
static int tree_near(simp *S, const double x[3], double r2, uint32_t *hint) {
    const struct dev_tree *t = S->dtree;
    STAT(dev_queries);
    size_t nleaf = t->count[0];
    /* the last answer and the leaves beside it (faces in slot order: near
     * in space) settle most queries of a new triangle's samples */
    if (*hint < nleaf) {
        if (leaf_near(S, t, *hint, x, r2)) return 1;
        for (uint32_t s = 1; s <= FEMLOD_SIMPLIFY_DEV_HINTS; s++) {
            if (*hint + s < nleaf && leaf_near(S, t, *hint + s, x, r2)) {
                *hint += s;
                return 1;
            }
            if (*hint >= s && leaf_near(S, t, *hint - s, x, r2)) {
                *hint -= s;
                return 1;
            }
        }
    }
    struct {
        int l;
        size_t k;
    } st[2 * 64 + 2];
    int top = 0;
    st[top].l = t->levels - 1;
    st[top++].k = 0;
    while (top > 0) {
        top--;
        int l = st[top].l;
        size_t k = st[top].k;
        STAT(dev_nodes);
        if (box_dist2(t->box + 6 * (t->off[l] + k), x) > r2) continue;
        if (l == 0) {
            if (k != *hint && leaf_near(S, t, k, x, r2)) {
                *hint = (uint32_t)k;
                return 1;
            }
            continue;
        }
        for (size_t c = 2 * k + 1; c + 1 > 2 * k; c--) /* the second child first: the first pops first */
            if (c < t->count[l - 1]) {
                st[top].l = l - 1;
                st[top++].k = c;
            }
    }
    return 0;
}

static void tree_free(struct dev_tree *t) {
    if (!t) return;
    free(t->corner);
    free(t->box);
    free(t);
}

static struct dev_tree *tree_build(const simp *S) {
    struct dev_tree *t = calloc(1, sizeof *t);
    if (!t) return NULL;
    size_t nt = S->nt;
    t->nt = nt;
    size_t n = nt ? (nt + DEV_LEAF - 1) / DEV_LEAF : 1, total = 0;
    int l = 0;
    for (;;) {
        t->off[l] = total;
        t->count[l] = n;
        total += n;
        l++;
        if (n == 1) break;
        n = (n + 1) / 2;
    }
    t->levels = l;
    t->corner = fl_alloc(9 * nt + 9, sizeof *t->corner);
    t->box = fl_alloc(6 * total, sizeof *t->box);
    if (!t->corner || !t->box) {
        tree_free(t);
        return NULL;
    }
    for (size_t f = 0; f < nt; f++)
        for (int c = 0; c < 3; c++) memcpy(t->corner + 9 * f + 3 * c, P(S, S->face[f].v[c]), 3 * sizeof(double));
    for (size_t k = 0; k < t->count[0]; k++) {
        double lo[3] = {__builtin_inf(), __builtin_inf(), __builtin_inf()}, hi[3] = {-lo[0], -lo[0], -lo[0]};
        for (size_t f = k * DEV_LEAF; f < nt && f < (k + 1) * DEV_LEAF; f++)
            for (int c = 0; c < 3; c++) {
                const double *p = t->corner + 9 * f + 3 * c;
                for (int a = 0; a < 3; a++) {
                    lo[a] = mn(lo[a], p[a]);
                    hi[a] = mx(hi[a], p[a]);
                }
            }
        float *b = t->box + 6 * k;
        for (int a = 0; a < 3; a++) {
            b[a] = float_down(lo[a]);
            b[3 + a] = float_up(hi[a]);
        }
    }
    for (int v = 1; v < t->levels; v++)
        for (size_t k = 0; k < t->count[v]; k++) {
            float *b = t->box + 6 * (t->off[v] + k);
            const float *c0 = t->box + 6 * (t->off[v - 1] + 2 * k);
            memcpy(b, c0, 6 * sizeof *b);
            if (2 * k + 1 < t->count[v - 1]) {
                const float *c1 = c0 + 6;
                for (int a = 0; a < 3; a++) {
                    b[a] = c1[a] < b[a] ? c1[a] : b[a];
                    b[3 + a] = c1[3 + a] > b[3 + a] ? c1[3 + a] : b[3 + a];
                }
            }
        }
    return t;
}

void fl_simp_free_deviation(simp *S) {
    tree_free(S->dtree);
    S->dtree = NULL;
    free(S->spos);
    S->spos = NULL;
}

/* }====== */

/* {====== the input samples */

/* Steps across a length at spacing h: at least lo, at most the cap. */
static double steps(double len, double h, double lo) {
    double n = ceil(len / h);
    if (!(n >= lo)) n = lo;
    return n > FEMLOD_SIMPLIFY_DEV_MAXDIV ? FEMLOD_SIMPLIFY_DEV_MAXDIV : n;
}

static double longest(const double *a, const double *b, const double *c) {
    return sqrt(mx(dist2(a, b), mx(dist2(b, c), dist2(c, a))));
}

/* Adds sample x to face f's list. */
static inline void hold(simp *S, uint32_t f, uint32_t x) {
    S->pnext[x] = S->fpt[f];
    S->fpt[f] = x;
}

femlod_status fl_simp_setup_deviation(simp *S, double mean_edge, femlod_error *err) {
    size_t nt = S->nt, nv = S->nv;
    double h = FEMLOD_SIMPLIFY_DEV_SPACING * mean_edge;
    if (!(h > 0.0)) h = __builtin_inf();
    S->dev_h = h;
    /* the samples are held to a fraction of d, so that the surface between
     * them stays within d (docs/design.md "What sampling leaves") */
    S->dev_r2 = FEMLOD_SIMPLIFY_DEV_MARGIN * FEMLOD_SIMPLIFY_DEV_MARGIN * S->maxdev2;
    /* count: per edge its inner points, per face its inner grid */
    size_t ns = 0;
    for (size_t e = 0; e < S->ne; e++) {
        if (S->edge[e].flag & E_DEAD) continue;
        ns += (size_t)steps(sqrt(dist2(P(S, S->edge[e].v[0]), P(S, S->edge[e].v[1]))), h, 2.0) - 1;
    }
    for (size_t f = 0; f < nt; f++) {
        const uint32_t *t = S->face[f].v;
        size_t n = (size_t)steps(longest(P(S, t[0]), P(S, t[1]), P(S, t[2])), h, 3.0);
        ns += (n - 1) * (n - 2) / 2;
    }
    if (nv + ns > UINT32_MAX - 1)
        return fl_error(err, FEMLOD_EINPUT, "simplify: too many deviation samples (%zu)", nv + ns);
    S->nsamp = ns;
    S->fpt = fl_alloc(nt, sizeof *S->fpt);
    S->pnext = fl_alloc(nv + ns, sizeof *S->pnext);
    S->spos = fl_alloc(3 * ns + 3, sizeof *S->spos);
    uint8_t *done = fl_calloc(S->ne + 1, 1);
    S->dtree = tree_build(S);
    if (!S->fpt || !S->pnext || !S->spos || !done || !S->dtree) {
        free(done);
        return fl_error(err, FEMLOD_ENOMEM, "simplify: out of memory (deviation samples)");
    }
    memset(S->fpt, 0xff, nt * sizeof *S->fpt);
    memset(S->pnext, 0xff, (nv + ns) * sizeof *S->pnext);
    /* in face order: the face's edges not sampled yet, then its grid; each
     * sample is held by the face it lies on */
    size_t w = 0;
    for (size_t f = 0; f < nt; f++) {
        for (int c = 0; c < 3; c++) {
            uint32_t e = S->tedge[3 * f + (size_t)c];
            if (done[e]) continue;
            done[e] = 1;
            const double *a = P(S, S->edge[e].v[0]), *b = P(S, S->edge[e].v[1]);
            double n = steps(sqrt(dist2(a, b)), h, 2.0);
            for (double i = 1.0; i < n; i += 1.0) {
                double *x = S->spos + 3 * w;
                for (int k = 0; k < 3; k++) x[k] = (a[k] * (n - i) + b[k] * i) / n;
                hold(S, (uint32_t)f, (uint32_t)(nv + w));
                w++;
            }
        }
        const uint32_t *t = S->face[f].v;
        const double *a = P(S, t[0]), *b = P(S, t[1]), *d = P(S, t[2]);
        double n = steps(longest(a, b, d), h, 3.0);
        for (double i = 1.0; i + 2.0 <= n; i += 1.0)
            for (double j = 1.0; i + j + 1.0 <= n; j += 1.0) {
                double *x = S->spos + 3 * w, g = n - i - j;
                for (int k = 0; k < 3; k++) x[k] = (a[k] * g + b[k] * i + d[k] * j) / n;
                hold(S, (uint32_t)f, (uint32_t)(nv + w));
                w++;
            }
    }
    free(done);
    return FEMLOD_OK;
}

/* }====== */

/* {====== the check */

static inline const double *sample_pos(const simp *S, uint32_t x) {
    return x < S->nv ? S->pos0 + 3 * (size_t)x : S->spos + 3 * (size_t)(x - S->nv);
}

/* Sample x, and the ring index of the new triangle to try first. */
static int push_point(simp *S, size_t *n, uint32_t x, uint32_t start) {
    if (!buf_reserve((void **)&S->sc.pbuf, &S->sc.pbuf_cap, *n + 1, sizeof *S->sc.pbuf) ||
        !buf_reserve((void **)&S->sc.pdst, &S->sc.pdst_cap, *n + 1, sizeof *S->sc.pdst)) {
        S->oom = 1;
        return 0;
    }
    S->sc.pdst[*n] = start;
    S->sc.pbuf[(*n)++] = x;
    return 1;
}

/* The output samples of edge (p, a) strictly between its ends. */
static int edge_near(simp *S, const double p[3], const double *a) {
    double n = steps(sqrt(dist2(p, a)), S->dev_h, 2.0);
    n += fmod(n, 2.0); /* even: the midpoint is a sample */
    for (double i = 1.0; i < n; i += 1.0) {
        double x[3];
        for (int k = 0; k < 3; k++) x[k] = 2.0 * i == n ? 0.5 * (p[k] + a[k]) : (p[k] * (n - i) + a[k] * i) / n;
        if (!tree_near(S, x, S->dev_r2, &S->sc.dev_hint)) return 0;
    }
    return 1;
}

int fl_simp_deviation_check(simp *S, ring *R, const double p[3], size_t *np) {
    *np = 0;
    /* forward: the new vertex first (one query, refuses most) */
    if (!tree_near(S, p, S->dev_r2, &S->sc.dev_hint)) return FEMLOD_REJECT_DEVIATION;
    /* backward: the samples held by the faces that change or go, and i, j
     * themselves when they are input vertices */
    size_t n = 0, rr = 0;
    for (int side = 0; side < 2; side++) {
        uint32_t v = side ? R->j : R->i;
        const uint32_t *fl = S->refs + S->fstart[v];
        for (uint32_t m = 0; m < S->fcount[v]; m++) {
            uint32_t f = fl[m];
            /* the ring lists the faces of i, then of j, without the shared
             * ones (gather): so is r counted */
            const uint32_t *t = S->face[f].v;
            int shared = t[0] == R->i + R->j - v || t[1] == R->i + R->j - v || t[2] == R->i + R->j - v;
            if (side == 1 && shared) continue; /* listed from i */
            uint32_t start = shared || rr >= R->n ? 0 : (uint32_t)rr;
            for (uint32_t x = S->fpt[f]; x != UINT32_MAX; x = S->pnext[x])
                if (!push_point(S, &n, x, start)) return FEMLOD_REJECT_DEVIATION;
            if (!shared) rr++;
        }
    }
    for (int side = 0; side < 2; side++) {
        uint32_t v = side ? R->j : R->i;
        if (S->node[v] < S->nv && !push_point(S, &n, S->node[v], 0)) return FEMLOD_REJECT_DEVIATION;
    }
    if (R->n == 0) return n ? FEMLOD_REJECT_DEVIATION : NO_REASON;
    /* each sample to its nearest new triangle (the lowest ring index on
     * ties), starting from the one that replaces its old face: the boxes of
     * the others then rule most of them out */
    if (!buf_reserve((void **)&S->sc.devbox, &S->sc.devbox_cap, 6 * R->n, sizeof *S->sc.devbox)) {
        S->oom = 1;
        return FEMLOD_REJECT_DEVIATION;
    }
    double *box = S->sc.devbox;
    for (size_t r = 0; r < R->n; r++) {
        const double *a = P(S, R->a[r]), *b = P(S, R->b[r]);
        for (int k = 0; k < 3; k++) {
            box[6 * r + k] = mn(p[k], mn(a[k], b[k]));
            box[6 * r + 3 + k] = mx(p[k], mx(a[k], b[k]));
        }
    }
    for (size_t m = 0; m < n; m++) {
        const double *x = sample_pos(S, S->sc.pbuf[m]);
        uint32_t bi = S->sc.pdst[m];
        double best = fl_point_tri_dist2(x, p, P(S, R->a[bi]), P(S, R->b[bi]));
        for (size_t r = 0; r < R->n; r++) {
            if (r == bi) continue;
            double e = 0.0;
            for (int k = 0; k < 3; k++) {
                double lo = box[6 * r + k], hi = box[6 * r + 3 + k];
                double t = x[k] < lo ? lo - x[k] : (x[k] > hi ? x[k] - hi : 0.0);
                e += t * t;
            }
            if (e > best) continue;
            double d = fl_point_tri_dist2(x, p, P(S, R->a[r]), P(S, R->b[r]));
            if (d < best || (d == best && r < bi)) {
                best = d;
                bi = (uint32_t)r;
            }
        }
        if (!(best <= S->dev_r2)) return FEMLOD_REJECT_DEVIATION;
        S->sc.pdst[m] = bi;
    }
    /* forward: the new edges (p, x), each once (an x that is some a_r; the
     * b_r that is none: the ends of an open fan), then the new faces' grids */
    for (size_t r = 0; r < R->n; r++) {
        if (!edge_near(S, p, P(S, R->a[r]))) return FEMLOD_REJECT_DEVIATION;
        int open = 1;
        for (size_t q = 0; q < R->n && open; q++) open = R->a[q] != R->b[r];
        if (open && !edge_near(S, p, P(S, R->b[r]))) return FEMLOD_REJECT_DEVIATION;
    }
    for (size_t r = 0; r < R->n; r++) {
        const double *a = P(S, R->a[r]), *b = P(S, R->b[r]);
        double g = steps(longest(p, a, b), S->dev_h, 3.0);
        for (double i = 1.0; i + 2.0 <= g; i += 1.0)
            for (double j = 1.0; i + j + 1.0 <= g; j += 1.0) {
                double x[3], c = g - i - j;
                for (int k = 0; k < 3; k++) x[k] = (p[k] * c + a[k] * i + b[k] * j) / g;
                if (!tree_near(S, x, S->dev_r2, &S->sc.dev_hint)) return FEMLOD_REJECT_DEVIATION;
            }
    }
    *np = n;
    return NO_REASON;
}

/* }====== */
