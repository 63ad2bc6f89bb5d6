/*
 * improve.c - femlod_improve: the stage that raises every element to the
 * thresholds with local operators (docs/design.md "Improving a mesh in
 * place"): the options, the rounds over what breaks a threshold, the census
 * of what remains and why, the output.
 */
#include "impr.h"
#include "../improve.h"

#include <stdlib.h>
#include <string.h>
#include <time.h>

#define DEFAULT_MIN_STRETCH 0.2
#define DEFAULT_MAX_VALENCE 12
#define DEFAULT_DEVIATION 0.001 /* x the bounding-box diagonal */
#define DEFAULT_FEATURE_ANGLE 40.0
#define DEFAULT_NORMAL_CHANGE 60.0
#define DEFAULT_ROUNDS 20

static const char *const reason_names[FEMLOD_IMPROVE_REASON_COUNT] = {
    "corner", "fixed",   "deviation", "stretch",  "valence",  "foldover",
    "topology", "intersection", "untried", "depth", "boundary", "fixable"};

const char *femlod_improve_reason_name(femlod_improve_reason reason) {
    if ((int)reason < 0 || reason >= FEMLOD_IMPROVE_REASON_COUNT) return "unknown";
    return reason_names[reason];
}

int femlod_improve_reason_forced(femlod_improve_reason reason) {
    return reason == FEMLOD_IMPROVE_CORNER || reason == FEMLOD_IMPROVE_BOUNDARY;
}

#define PI 3.14159265358979323846

/* Every triangle with an angle a at a vertex is similar to one with legs 1
 * and t in (0, 1] there (docs/design.md "What remains, and why"); the
 * stretch is smooth in t, so a grid of 1,000 steps is within 1e-5 of the
 * largest. */
double femlod_stretch_bound(double angle_degrees) {
    if (!(angle_degrees > 0.0) || !(angle_degrees < 180.0)) return 0.0;
    double a = angle_degrees * PI / 180.0, best = 0.0;
    const double o[3] = {0, 0, 0}, x[3] = {1, 0, 0};
    for (int i = 1; i <= 1000; i++) {
        double t = i / 1000.0, w[3] = {t * cos(a), t * sin(a), 0.0};
        best = fmax(best, im_stretch(o, x, w));
    }
    return best;
}

/* The angle at corner p between q and r, degrees. */
static double angle_at(const double *p, const double *q, const double *r) {
    double u[3], w[3];
    sub3(u, q, p);
    sub3(w, r, p);
    double lu = sqrt(dot3(u, u)), lw = sqrt(dot3(w, w));
    if (!(lu > 0) || !(lw > 0)) return 0.0;
    return acos(fmax(-1.0, fmin(1.0, dot3(u, w) / (lu * lw)))) * 180.0 / PI;
}

/* A triangle below min_stretch that the geometry forces: its two edges at a
 * vertex are feature edges meeting at an angle a < 60 degrees whose bound
 * femlod_stretch_bound(a) is below min_stretch. Every triangle between those
 * lines at that vertex has an angle at most a there, and the bound rises on
 * (0, 60], so none can reach min_stretch. FEMLOD_IMPROVE_BOUNDARY when both
 * edges are boundary edges, FEMLOD_IMPROVE_CORNER otherwise, -1 when not
 * forced; *angle gets the sharpest such angle. */
static int forced_face(const imesh *M, const uint32_t t[3], double minst, double *angle) {
    int r = -1;
    for (int k = 0; k < 3; k++) {
        uint32_t v = t[k], u = t[(k + 1) % 3], w = t[(k + 2) % 3];
        if (!fl_imesh_is_feature(M, v, u) || !fl_imesh_is_feature(M, v, w)) continue;
        double a = angle_at(im_P(M, v), im_P(M, u), im_P(M, w));
        if (!(a < 60.0) || !(femlod_stretch_bound(a) < minst)) continue;
        if (r >= 0 && a >= *angle) continue;
        *angle = a;
        r = fl_imesh_edge_faces(M, v, u, NULL, 0) == 1 && fl_imesh_edge_faces(M, v, w, NULL, 0) == 1
                ? FEMLOD_IMPROVE_BOUNDARY
                : FEMLOD_IMPROVE_CORNER;
    }
    return r;
}

/* A vertex above max_valence that the geometry forces: more feature edges
 * meet there than max_valence (no flip removes a feature edge, no collapse
 * takes a corner). FEMLOD_IMPROVE_CORNER or -1. */
static int forced_vertex(imesh *M, uint32_t v, int maxval) {
    return fl_imesh_feature_valence(M, v) > (uint32_t)maxval ? FEMLOD_IMPROVE_CORNER : -1;
}

static double wall(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static double resolve(double v, double def) { return v == 0.0 ? def : (v < 0.0 ? FEMLOD_SIMPLIFY_OFF : v); }

/* the input's counts of elements breaking a threshold */
typedef struct census {
    size_t st, sz, val;
    double stmin;
    uint32_t valmax;
} census;

static femlod_status measure_input(const femlod_mesh *m, const im_params *p, census *c, femlod_error *err) {
    memset(c, 0, sizeof *c);
    c->stmin = m->nt ? 1.0 : 0.0;
    for (size_t f = 0; f < m->nt; f++) {
        const uint32_t *t = m->tri + 3 * f;
        if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) { /* stretch 0; dropped from the output */
            c->stmin = 0.0;
            if (p->st_on) c->st++;
            continue;
        }
        const double *a = m->pos + 3 * (size_t)t[0], *b = m->pos + 3 * (size_t)t[1], *d = m->pos + 3 * (size_t)t[2];
        double s = im_stretch(a, b, d);
        c->stmin = fmin(c->stmin, s);
        if (p->st_on && s < p->minst) c->st++;
        if (p->sz_on) {
            double L2 = fmax(dist2(a, b), fmax(dist2(b, d), dist2(a, d)));
            if (L2 > p->maxsz * p->maxsz) c->sz++;
        }
    }
    uint32_t *val = fl_alloc(m->nv ? m->nv : 1, sizeof *val);
    if (!val) return fl_error(err, FEMLOD_ENOMEM, "improve: out of memory");
    femlod_status st = femlod_valence_array(val, m->nv, m->tri, m->nt, err);
    if (st != FEMLOD_OK) {
        free(val);
        return st;
    }
    for (size_t v = 0; v < m->nv; v++) {
        c->valmax = val[v] > c->valmax ? val[v] : c->valmax;
        if (p->val_on && val[v] > (uint32_t)p->maxval) c->val++;
    }
    free(val);
    return FEMLOD_OK;
}

typedef struct run {
    im_ctx C;
    uint8_t *vreason; /* per vertex: last refusal of a valence fix, +1 */
    size_t capvr;
    size_t budget;    /* splits left (bounds the growth: 4 per input triangle) */
} run;

static int vreason_set(run *R, uint32_t v, int why) {
    if (v >= R->capvr) {
        size_t c = R->capvr ? R->capvr : 64;
        while (c <= v) c *= 2;
        uint8_t *p = fl_realloc(R->vreason, c, 1);
        if (!p) return 0;
        memset(p + R->capvr, 0, c - R->capvr);
        R->vreason = p;
        R->capvr = c;
    }
    R->vreason[v] = (uint8_t)(why + 1);
    return 1;
}

static int face_live(const imesh *M, uint32_t f) { return M->tri[3 * (size_t)f] != IM_DEAD; }

/* the corner opposite the longest edge (k: the edge is t[k+1], t[k+2]) and
 * the shortest edge's first corner */
static void face_edges(const imesh *M, uint32_t f, int *longest, int *shortest) {
    const uint32_t *t = M->tri + 3 * (size_t)f;
    double l[3];
    for (int k = 0; k < 3; k++) l[k] = dist2(im_P(M, t[(k + 1) % 3]), im_P(M, t[(k + 2) % 3]));
    int lo = 0, hi = 0;
    for (int k = 1; k < 3; k++) {
        if (l[k] > l[hi]) hi = k;
        if (l[k] < l[lo]) lo = k;
    }
    *longest = hi;
    *shortest = lo;
}

/* The flips that raise the smaller stretch of their two faces, over the
 * faces made since slot nt0, until a pass makes none (at most 8). */
static void flip_sweep(run *R, size_t nt0) {
    im_ctx *C = &R->C;
    imesh *M = C->M;
    int w;
    for (int pass = 0; pass < 8 && !C->oom; pass++) {
        int any = 0;
        for (size_t f = nt0, end = M->nt; f < end && !C->oom; f++)
            for (int k = 0; k < 3 && face_live(M, (uint32_t)f); k++) {
                const uint32_t *t = M->tri + 3 * f;
                if (fl_imop_flip(C, t[k], t[(k + 1) % 3], 0, &w)) any = 1;
            }
        if (!any) break;
    }
}

#define REFINE_MAX 64 /* splits of a band refinement */

/* Inside a transaction: while a face it made is below min_stretch, the
 * worst (the lowest slot among equals) has an edge halved: its longest
 * feature edge when that is longer than k times the face's height (a band's
 * line, in pieces short enough), else its longest edge; then the flips and
 * the relaxation of the free vertices made. The longest-edge bisection with
 * flips that carries a band's refinement along both lines and across them to
 * the faces beyond, until none is below, every bad face's split is refused or
 * REFINE_MAX are made. */
static void refine_bad(run *R, size_t nt0, size_t nv0) {
    im_ctx *C = &R->C;
    imesh *M = C->M;
    double k = sqrt(3.0) / C->p->minst;
    uint32_t skip[REFINE_MAX];
    int nskip = 0, w;
    for (int made = 0; made < REFINE_MAX && R->budget > 0 && !C->oom;) {
        flip_sweep(R, nt0);
        for (size_t v = nv0; v < M->nv && !C->oom; v++)
            if (M->vf[v].n && M->vclass[v] == IM_FREE) fl_imop_relax(C, (uint32_t)v, &w);
        uint32_t g = IM_DEAD;
        double worst = C->p->minst;
        for (size_t f = nt0; f < M->nt; f++) {
            if (!face_live(M, (uint32_t)f)) continue;
            double st = im_face_stretch(M, (uint32_t)f);
            if (!(st < worst)) continue;
            int skipped = 0;
            for (int i = 0; i < nskip; i++) skipped |= skip[i] == (uint32_t)f;
            if (skipped) continue;
            worst = st;
            g = (uint32_t)f;
        }
        if (g == IM_DEAD) return;
        const uint32_t *t = M->tri + 3 * (size_t)g;
        double l2[3], lmax = 0.0;
        for (int e = 0; e < 3; e++) {
            l2[e] = dist2(im_P(M, t[(e + 1) % 3]), im_P(M, t[(e + 2) % 3]));
            lmax = fmax(lmax, l2[e]);
        }
        double n[3];
        im_normal(n, im_P(M, t[0]), im_P(M, t[1]), im_P(M, t[2]));
        double hg = sqrt(dot3(n, n) / fmax(lmax, 1e-300)); /* twice the area over the longest edge */
        int pick = -1, feat = -1;
        for (int e = 0; e < 3; e++) {
            if (pick < 0 || l2[e] > l2[pick]) pick = e;
            if (fl_imesh_is_feature(M, t[(e + 1) % 3], t[(e + 2) % 3]) && l2[e] > k * k * hg * hg &&
                (feat < 0 || l2[e] > l2[feat]))
                feat = e;
        }
        if (feat >= 0) pick = feat;
        /* its shortest edge collapsed when that raises the least stretch
         * there (a needle); else the split, at the apex's foot when inside
         * the edge (a cap: right triangles), else at the midpoint */
        int sh = 0;
        for (int e = 1; e < 3; e++)
            if (l2[e] < l2[sh]) sh = e;
        if (fl_imop_collapse(C, t[(sh + 1) % 3], t[(sh + 2) % 3], &w)) {
            made++;
            continue;
        }
        t = M->tri + 3 * (size_t)g;
        const double *pu = im_P(M, t[(pick + 1) % 3]), *pv = im_P(M, t[(pick + 2) % 3]), *pw = im_P(M, t[pick]);
        double uv[3], uw[3], at[3];
        sub3(uv, pv, pu);
        sub3(uw, pw, pu);
        double sf = dot3(uv, uw) / fmax(dot3(uv, uv), 1e-300);
        for (int q = 0; q < 3; q++) at[q] = pu[q] + (sf > 0.1 && sf < 0.9 ? sf : 0.5) * uv[q];
        if (!fl_imop_split(C, t[(pick + 1) % 3], t[(pick + 2) % 3], at, &w)) {
            if (nskip == REFINE_MAX) return;
            skip[nskip++] = g;
            continue;
        }
        R->budget--;
        made++;
    }
    flip_sweep(R, nt0);
}

/* The same without transactions or the floor rule (the stage's first try,
 * "The floor rule, compound changes and bands"): a cap split at the apex's
 * foot and the apex taken there, or, for a band within half the depth bound,
 * the split alone; a needle's two long edges halved. */
static int fix_loose(run *R, const uint32_t t[3], uint32_t a, uint32_t b, uint32_t c, uint32_t x, uint32_t y, int sk,
                     int *why) {
    im_ctx *C = &R->C;
    imesh *M = C->M;
    int w;
    /* a cap (the apex's foot inside ab): split there, take the apex onto it */
    const double *pa = im_P(M, a), *pb = im_P(M, b), *pc = im_P(M, c);
    double ab[3], ac[3];
    sub3(ab, pb, pa);
    sub3(ac, pc, pa);
    double s = dot3(ab, ac) / dot3(ab, ab);
    int reach = 1;
    if (s > 0.1 && s < 0.9 && M->vclass[c] != IM_FREE) {
        /* an apex that cannot move (a band between feature lines): only
         * halvings along ab make the band's triangles round, about
         * log2(|ab| / height) of them; past the depth bound they would
         * only make more needles */
        double h2 = 0.0;
        for (int k = 0; k < 3; k++) h2 += (pc[k] - pa[k] - s * ab[k]) * (pc[k] - pa[k] - s * ab[k]);
        unsigned d = M->vdepth[a] > M->vdepth[b] ? M->vdepth[a] : M->vdepth[b];
        double need = 0.5 * log2(dot3(ab, ab) / fmax(h2, 1e-300));
        if (!((double)d + need <= (double)IM_MAX_DEPTH / 2)) {
            reach = 0;
            *why = FEMLOD_IMPROVE_DEPTH;
        }
    }
    if (s > 0.1 && s < 0.9 && reach) {
        double foot[3];
        for (int k = 0; k < 3; k++) foot[k] = pa[k] + s * ab[k];
        if (fl_imop_split(C, a, b, foot, &w)) {
            R->budget--;
            uint32_t m = (uint32_t)M->nv - 1;
            /* the apex onto the foot; without it (an apex on a feature line
             * or fixed: a band between two lines), the halves are left to
             * the next operators, which halve them along the lines */
            if (M->vclass[c] == IM_FREE) fl_imop_collapse(C, c, m, &w);
            return 1;
        }
        *why = w;
    } else if (s <= 0.1 || s >= 0.9) {
        /* a needle: halve its longest edge; the halves are needles of half
         * the aspect, which the next tries halve again or collapse */
        int done = 0;
        if (fl_imop_split(C, a, b, NULL, &w)) {
            R->budget--;
            done = 1;
        } else
            *why = w;
        /* and the other long edge (c, z): a strip's needle has its long
         * side and its diagonal nearly alike, and only halving both makes
         * the halves rounder */
        uint32_t z = t[sk];
        double ls = dist2(im_P(M, x), im_P(M, y));
        if (done && R->budget > 0 && z != c && fl_imesh_has_edge(M, c, z) &&
            dist2(im_P(M, c), im_P(M, z)) > 4.0 * ls && fl_imop_split(C, c, z, NULL, &w))
            R->budget--;
        if (done) return 1;
    }
    return 0;
}

/* One try at a triangle below min_stretch: flip its longest edge, collapse
 * its shortest, or, as one transaction, split a cap's longest edge at the
 * apex's foot and take the apex there, halve a needle, or refine a band.
 * 1 when something changed. */
static int fix_face(run *R, uint32_t f) {
    im_ctx *C = &R->C;
    imesh *M = C->M;
    const im_params *p = C->p;
    int lk, sk, why = FEMLOD_IMPROVE_UNTRIED, w;
    face_edges(M, f, &lk, &sk);
    /* a copy: a split may move the face array */
    uint32_t t[3];
    memcpy(t, M->tri + 3 * (size_t)f, sizeof t);
    uint32_t c = t[lk], a = t[(lk + 1) % 3], b = t[(lk + 2) % 3];
    uint32_t x = t[(sk + 1) % 3], y = t[(sk + 2) % 3];
    if (fl_imop_flip(C, a, b, 0, &w)) return 1;
    why = w;
    if (fl_imop_collapse(C, x, y, &w)) return 1;
    if (why == FEMLOD_IMPROVE_TOPOLOGY || why == FEMLOD_IMPROVE_STRETCH) why = w;
    if (R->budget == 0 || C->oom) goto refused;
    if (!p->strict) {
        if (fix_loose(R, t, a, b, c, x, y, sk, &why)) return 1;
        goto refused;
    }
    const double *pa = im_P(M, a), *pb = im_P(M, b), *pc = im_P(M, c);
    double ab[3], ac[3];
    sub3(ab, pb, pa);
    sub3(ac, pc, pa);
    double L2 = dot3(ab, ab);
    double s = dot3(ab, ac) / L2, h2 = 0.0;
    for (int k = 0; k < 3; k++) h2 += (ac[k] - s * ab[k]) * (ac[k] - s * ab[k]);
    int cap = s > 0.1 && s < 0.9;
    double foot[3];
    for (int k = 0; k < 3; k++) foot[k] = pa[k] + s * ab[k];
    size_t b0 = R->budget;
    if (M->vclass[c] == IM_FREE) {
        /* a cap: split at the apex's foot, the apex onto it; a needle: halve
         * its longest edge and its other long edge (c, z), when more than
         * twice the short one (a strip's needle has its long side and its
         * diagonal nearly alike, and only halving both makes the halves
         * rounder); then the flips around; judged as one */
        fl_imtx_begin(C);
        int split = fl_imop_split(C, a, b, cap ? foot : NULL, &w);
        if (split) {
            R->budget--;
            uint32_t m = (uint32_t)M->nv - 1, z = t[sk];
            if (cap) fl_imop_collapse(C, c, m, &w);
            else if (R->budget > 0 && z != c && fl_imesh_has_edge(M, c, z) &&
                     dist2(im_P(M, c), im_P(M, z)) > 4.0 * dist2(im_P(M, x), im_P(M, y)) &&
                     fl_imop_split(C, c, z, NULL, &w))
                R->budget--;
            flip_sweep(R, C->tx.nt0);
        }
        if (fl_imtx_end(C)) return 1;
        R->budget = b0;
        why = split ? C->tx.why : w;
        if (!split || R->budget == 0) goto refused;
    }
    /* a band (an apex that cannot move, on a feature line), or what the
     * above left: split ab at the apex's foot (a needle's at its midpoint),
     * then the bisections and flips of refine_bad; the halvings a band
     * needs, log2(|ab| / (k h)) with k = sqrt(3) / min_stretch, within the
     * depth left */
    unsigned d = M->vdepth[a] > M->vdepth[b] ? M->vdepth[a] : M->vdepth[b];
    double need = log2(sqrt(L2) / fmax(sqrt(3.0) / p->minst * sqrt(h2), 1e-300));
    if (!((double)d + ceil(fmax(need, 1.0)) <= (double)IM_MAX_DEPTH)) {
        why = FEMLOD_IMPROVE_DEPTH;
        goto refused;
    }
    /* at the foot, then (a cap) at the midpoint: the faces across ab
     * split there may take the refinement elsewhere */
    for (int at_mid = !cap; at_mid < 2; at_mid++) {
        fl_imtx_begin(C);
        int split = fl_imop_split(C, a, b, at_mid ? NULL : foot, &w);
        if (split) {
            R->budget--;
            refine_bad(R, C->tx.nt0, C->tx.nv0);
        }
        if (fl_imtx_end(C)) return 1;
        R->budget = b0;
        why = split ? C->tx.why : w;
    }
refused:
    if (face_live(M, f)) M->freason[f] = (uint8_t)(why + 1);
    return 0;
}

/* A vertex above max_valence: flips of its edges that lower it, then
 * splits of its longest spokes (later collapses join the new ring). */
static int fix_valence(run *R, uint32_t v) {
    im_ctx *C = &R->C;
    imesh *M = C->M;
    const im_params *p = C->p;
    int changed = 0, why = FEMLOD_IMPROVE_UNTRIED, w;
    if (M->vclass[v] == IM_FIXED) why = FEMLOD_IMPROVE_FIXED;
    for (int pass = 0; pass < 2; pass++) {
        if (fl_imesh_valence(M, v) <= (uint32_t)p->maxval) return changed;
        /* the neighbours now, in face-list order */
        size_t nn = 0;
        const im_list *l = M->vf + v;
        uint32_t s = fl_imesh_next_stamp(M);
        if (!buf_grow(&C->buf, &C->bufcap, 3 * (size_t)l->n)) {
            C->oom = 1;
            return changed;
        }
        for (uint32_t i = 0; i < l->n; i++) {
            const uint32_t *t = M->tri + 3 * (size_t)l->f[i];
            for (int k = 0; k < 3; k++)
                if (t[k] != v && M->vmark[t[k]] != s) {
                    M->vmark[t[k]] = s;
                    C->buf[nn++] = t[k];
                }
        }
        uint32_t *nb = malloc((nn ? nn : 1) * sizeof *nb);
        if (!nb) {
            C->oom = 1;
            return changed;
        }
        memcpy(nb, C->buf, nn * sizeof *nb);
        for (size_t i = 0; i < nn; i++) {
            if (fl_imesh_valence(M, v) <= (uint32_t)p->maxval) break;
            if (pass == 0) {
                if (fl_imop_flip(C, v, nb[i], 1, &w)) changed = 1;
                else if (why != FEMLOD_IMPROVE_FIXED) why = w;
            } else if (R->budget > 0 && fl_imesh_has_edge(M, v, nb[i])) {
                /* spokes longer than the shortest: split in the middle */
                double lmin = INFINITY;
                for (size_t j = 0; j < nn; j++)
                    if (fl_imesh_has_edge(M, v, nb[j])) lmin = fmin(lmin, dist2(im_P(M, v), im_P(M, nb[j])));
                if (dist2(im_P(M, v), im_P(M, nb[i])) > 1.0 * lmin) {
                    if (fl_imop_split(C, v, nb[i], NULL, &w)) {
                        changed = 1;
                        R->budget--;
                    } else if (why != FEMLOD_IMPROVE_FIXED)
                        why = w;
                }
            }
        }
        free(nb);
    }
    if (!vreason_set(R, v, why)) C->oom = 1;
    return changed;
}

static femlod_status make_output(femlod_mesh **out, imesh *M, uint32_t *vmap, femlod_error *err) {
    uint32_t *map = fl_alloc(M->nv ? M->nv : 1, sizeof *map);
    if (!map) return fl_error(err, FEMLOD_ENOMEM, "improve: out of memory");
    size_t nv = 0;
    for (size_t v = 0; v < M->nv; v++) map[v] = M->vf[v].n ? (uint32_t)nv++ : IM_DEAD;
    if (vmap) memcpy(vmap, map, M->nv0 * sizeof *vmap);
    femlod_mesh *m = fl_mesh_alloc(nv, M->live);
    if (!m) {
        free(map);
        return fl_error(err, FEMLOD_ENOMEM, "improve: out of memory");
    }
    for (size_t v = 0; v < M->nv; v++)
        if (map[v] != IM_DEAD) memcpy(m->pos + 3 * (size_t)map[v], M->pos + 3 * v, 3 * sizeof *m->pos);
    size_t k = 0;
    for (size_t f = 0; f < M->nt; f++) {
        const uint32_t *t = M->tri + 3 * f;
        if (t[0] == IM_DEAD) continue;
        for (int c = 0; c < 3; c++) m->tri[3 * k + (size_t)c] = map[t[c]];
        k++;
    }
    free(map);
    *out = m;
    return FEMLOD_OK;
}

static void note_angle(femlod_improve_report *rep, double a) {
    if (rep->corner_angle_max == 0.0 || a > rep->corner_angle_max) rep->corner_angle_max = a;
    if (rep->corner_angle_min == 0.0 || a < rep->corner_angle_min) rep->corner_angle_min = a;
}

/* what breaks a threshold in face f: bit 1 stretch, bit 2 size */
static int face_breaks(const imesh *M, const im_params *p, uint32_t f) {
    const uint32_t *t = M->tri + 3 * (size_t)f;
    int b = 0;
    if (p->st_on && im_face_stretch(M, f) < p->minst) b |= 1;
    if (p->sz_on) {
        const double *a = im_P(M, t[0]), *c = im_P(M, t[1]), *d = im_P(M, t[2]);
        double L2 = fmax(dist2(a, c), fmax(dist2(c, d), dist2(a, d)));
        if (L2 > p->maxsz * p->maxsz) b |= 2;
    }
    return b;
}

/* the reason of a face the operators left: its last refusal; untried
 * faces of fixed vertices only are fixed */
static int left_reason(const imesh *M, uint32_t f) {
    const uint32_t *t = M->tri + 3 * (size_t)f;
    int r = M->freason[f] ? M->freason[f] - 1 : FEMLOD_IMPROVE_UNTRIED;
    if (r == FEMLOD_IMPROVE_UNTRIED && M->vclass[t[0]] == IM_FIXED && M->vclass[t[1]] == IM_FIXED &&
        M->vclass[t[2]] == IM_FIXED)
        r = FEMLOD_IMPROVE_FIXED;
    return r;
}

static void count_face(femlod_improve_report *rep, int breaks, int r) {
    if (breaks & 1) {
        rep->stretch_out++;
        rep->stretch_by[r]++;
    }
    if (breaks & 2) {
        rep->size_out++;
        rep->size_by[r]++;
    }
    rep->violating++;
    rep->violating_by[r]++;
}

static void count_vertex(femlod_improve_report *rep, int r) {
    rep->valence_out++;
    rep->valence_by[r]++;
}

/* What still breaks a threshold, by reason: forced first, else the last
 * refusal. */
static void final_census(run *R, femlod_improve_report *rep) {
    imesh *M = R->C.M;
    const im_params *p = R->C.p;
    rep->stretch_min = M->live ? 1.0 : 0.0;
    for (size_t f = 0; f < M->nt; f++) {
        if (!face_live(M, (uint32_t)f)) continue;
        rep->stretch_min = fmin(rep->stretch_min, im_face_stretch(M, (uint32_t)f));
        int b = face_breaks(M, p, (uint32_t)f);
        if (!b) continue;
        double a = 0.0;
        int r = (b & 1) ? forced_face(M, M->tri + 3 * f, p->minst, &a) : -1;
        if (r >= 0) note_angle(rep, a);
        else r = left_reason(M, (uint32_t)f);
        count_face(rep, b, r);
    }
    rep->valence_max = 0;
    for (uint32_t v = 0; v < M->nv; v++) {
        if (!M->vf[v].n) continue;
        uint32_t val = fl_imesh_valence(M, v);
        if (val > rep->valence_max) rep->valence_max = val;
        if (p->val_on && val > (uint32_t)p->maxval) {
            int r = forced_vertex(M, v, p->maxval);
            if (r < 0) r = v < R->capvr && R->vreason[v] ? R->vreason[v] - 1 : FEMLOD_IMPROVE_UNTRIED;
            if (r == FEMLOD_IMPROVE_UNTRIED && M->vclass[v] == IM_FIXED) r = FEMLOD_IMPROVE_FIXED;
            count_vertex(rep, r);
        }
    }
}

/* The census's elements: what breaks a threshold in the mesh as given, with
 * the forced class (-1: none) taken before any operator runs. */
typedef struct census_item {
    uint32_t id;
    int breaks, forced;
    double angle;
} census_item;

typedef struct census_list {
    census_item *face, *vert;
    size_t nf, nv;
} census_list;

static int census_take(run *R, census_list *L) {
    imesh *M = R->C.M;
    const im_params *p = R->C.p;
    size_t nf = 0, nv = 0;
    for (uint32_t f = 0; f < M->nt; f++)
        if (face_live(M, f) && face_breaks(M, p, f)) nf++;
    for (uint32_t v = 0; v < M->nv; v++)
        if (p->val_on && M->vf[v].n && fl_imesh_valence(M, v) > (uint32_t)p->maxval) nv++;
    L->face = fl_alloc(nf ? nf : 1, sizeof *L->face);
    L->vert = fl_alloc(nv ? nv : 1, sizeof *L->vert);
    if (!L->face || !L->vert) return 0;
    L->nf = L->nv = 0;
    for (uint32_t f = 0; f < M->nt; f++) {
        int b = face_live(M, f) ? face_breaks(M, p, f) : 0;
        if (!b) continue;
        census_item *c = L->face + L->nf++;
        c->id = f;
        c->breaks = b;
        c->angle = 0.0;
        c->forced = (b & 1) ? forced_face(M, M->tri + 3 * (size_t)f, p->minst, &c->angle) : -1;
    }
    for (uint32_t v = 0; v < M->nv; v++) {
        if (!p->val_on || !M->vf[v].n || fl_imesh_valence(M, v) <= (uint32_t)p->maxval) continue;
        census_item *c = L->vert + L->nv++;
        c->id = v;
        c->breaks = 0;
        c->angle = 0.0;
        c->forced = forced_vertex(M, v, p->maxval);
    }
    return 1;
}

/* After one round of the operators: each element taken is forced, or
 * fixable (gone, or no longer breaking its threshold), or its refusal. */
static void census_count(run *R, const census_list *L, femlod_improve_report *rep) {
    imesh *M = R->C.M;
    const im_params *p = R->C.p;
    for (size_t i = 0; i < L->nf; i++) {
        const census_item *c = L->face + i;
        int r = c->forced;
        if (r >= 0) note_angle(rep, c->angle);
        else if (!face_live(M, c->id) || !(face_breaks(M, p, c->id) & c->breaks)) r = FEMLOD_IMPROVE_FIXABLE;
        else r = left_reason(M, c->id);
        count_face(rep, c->breaks, r);
    }
    for (size_t i = 0; i < L->nv; i++) {
        const census_item *c = L->vert + i;
        int r = c->forced;
        if (r < 0 && fl_imesh_valence(M, c->id) <= (uint32_t)p->maxval) r = FEMLOD_IMPROVE_FIXABLE;
        if (r < 0) r = c->id < R->capvr && R->vreason[c->id] ? R->vreason[c->id] - 1 : FEMLOD_IMPROVE_UNTRIED;
        if (r == FEMLOD_IMPROVE_UNTRIED && M->vclass[c->id] == IM_FIXED) r = FEMLOD_IMPROVE_FIXED;
        count_vertex(rep, r);
    }
}

static femlod_status improve_run(femlod_mesh **out, const femlod_mesh *mesh, const femlod_improve_options *options,
                                 femlod_improve_report *report, uint32_t *vmap, int census_only, int strict,
                                 femlod_error *err);

/* The stage's least stretch below both min_stretch and its input's: the
 * loose run went below the floor on its way and did not come back. */
static int lowers_floor(const femlod_improve_report *r) {
    return r->stretch_min < r->stretch_min_in && r->stretch_min < r->min_stretch;
}

/* The loose run first (its multi-round fixes of fans and caps pass through
 * worse triangles); judged as one change by the floor rule, and when it
 * fails, the strict run, whose every change keeps the rule (docs/design.md
 * "The floor rule, compound changes and bands"). */
static femlod_status improve_judged(femlod_mesh **out, const femlod_mesh *mesh, const femlod_improve_options *options,
                                    femlod_improve_report *report, uint32_t *vmap, femlod_error *err) {
    femlod_improve_report r;
    femlod_status st = improve_run(out, mesh, options, &r, vmap, 0, 0, err);
    if (st != FEMLOD_OK || !lowers_floor(&r)) {
        if (st == FEMLOD_OK && report) *report = r;
        return st;
    }
    femlod_mesh_free(*out);
    *out = NULL;
    double t = r.seconds;
    st = improve_run(out, mesh, options, &r, vmap, 0, 1, err);
    r.seconds += t;
    if (st == FEMLOD_OK && report) *report = r;
    return st;
}

femlod_status femlod_improve(femlod_mesh **out, const femlod_mesh *mesh, const femlod_improve_options *options,
                             femlod_improve_report *report, femlod_error *err) {
    return improve_judged(out, mesh, options, report, NULL, err);
}

femlod_status fl_improve_mapped(femlod_mesh **out, const femlod_mesh *mesh, const femlod_improve_options *options,
                                femlod_improve_report *report, uint32_t *vmap, femlod_error *err) {
    return improve_judged(out, mesh, options, report, vmap, err);
}

femlod_status fl_improve_strict(femlod_mesh **out, const femlod_mesh *mesh, const femlod_improve_options *options,
                                femlod_improve_report *report, femlod_error *err) {
    return improve_run(out, mesh, options, report, NULL, 0, 1, err);
}

femlod_status femlod_improve_census(const femlod_mesh *mesh, const femlod_improve_options *options,
                                    femlod_improve_report *report, femlod_error *err) {
    return improve_run(NULL, mesh, options, report, NULL, 1, 1, err);
}

/* census_only: one round on a working copy, no output (femlod_improve_census);
 * strict: every change keeps the floor rule */
static femlod_status improve_run(femlod_mesh **out, const femlod_mesh *mesh, const femlod_improve_options *options,
                                 femlod_improve_report *report, uint32_t *vmap, int census_only, int strict,
                                 femlod_error *err) {
    double t0 = wall();
    femlod_improve_options o = FEMLOD_IMPROVE_OPTIONS_INIT;
    if (options) o = *options;
    femlod_improve_report rep;
    memset(&rep, 0, sizeof rep);
    double lo[3], hi[3];
    femlod_mesh_bbox(mesh, lo, hi);
    double diag = sqrt(dist2(lo, hi));
    if (!isfinite(o.min_stretch) || o.min_stretch > 1.0)
        return fl_error(err, FEMLOD_EINPUT, "improve: min_stretch %g is not in (0, 1]", o.min_stretch);
    if (!isfinite(o.max_size) || !isfinite(o.max_deviation) || !isfinite(o.feature_angle) ||
        !isfinite(o.max_normal_change))
        return fl_error(err, FEMLOD_EINPUT, "improve: an option is not finite");
    if (o.max_rounds < 0) return fl_error(err, FEMLOD_EINPUT, "improve: max_rounds %d is negative", o.max_rounds);
    if (o.lock_count && !o.lock) return fl_error(err, FEMLOD_EINPUT, "improve: lock_count without lock");
    for (size_t i = 0; i < o.lock_count; i++)
        if (o.lock[i] >= mesh->nv)
            return fl_error(err, FEMLOD_EINPUT, "improve: lock index %u out of range (%zu vertices)",
                            (unsigned)o.lock[i], mesh->nv);
    im_params p;
    p.minst = resolve(o.min_stretch, DEFAULT_MIN_STRETCH);
    p.maxsz = o.max_size > 0 ? o.max_size : FEMLOD_SIMPLIFY_OFF;
    p.maxval = o.max_valence == 0 ? DEFAULT_MAX_VALENCE : (o.max_valence < 0 ? -1 : o.max_valence);
    p.maxdev = resolve(o.max_deviation, DEFAULT_DEVIATION * diag);
    double fa = resolve(o.feature_angle, DEFAULT_FEATURE_ANGLE);
    double nc = resolve(o.max_normal_change, DEFAULT_NORMAL_CHANGE);
    p.cos_nc = nc < 0 ? 0.0 : cos(fmin(nc, 179.0) * 3.14159265358979323846 / 180.0);
    p.st_on = p.minst > 0;
    p.sz_on = p.maxsz > 0;
    p.val_on = p.maxval > 0;
    p.strict = strict;
    int rounds = census_only ? 1 : o.max_rounds ? o.max_rounds : DEFAULT_ROUNDS;
    rep.min_stretch = p.minst;
    rep.max_size = p.maxsz;
    rep.max_valence = p.val_on ? p.maxval : -1;
    rep.max_deviation = p.maxdev;
    rep.feature_angle = fa;
    rep.max_normal_change = nc;
    rep.triangles_in = mesh->nt;
    rep.vertices_in = mesh->nv;
    census c;
    femlod_status st = measure_input(mesh, &p, &c, err);
    if (st != FEMLOD_OK) return st;
    rep.stretch_in = c.st;
    rep.size_in = c.sz;
    rep.valence_in = c.val;
    rep.stretch_min_in = c.stmin;
    rep.valence_max_in = c.valmax;

    uint8_t *locked = fl_calloc(mesh->nv ? mesh->nv : 1, 1);
    if (!locked) return fl_error(err, FEMLOD_ENOMEM, "improve: out of memory");
    for (size_t i = 0; i < o.lock_count; i++) locked[o.lock[i]] = 1;
    if (o.lock_fn)
        for (size_t v = 0; v < mesh->nv; v++)
            if (o.lock_fn(o.lock_payload, mesh->pos[3 * v], mesh->pos[3 * v + 1], mesh->pos[3 * v + 2]))
                locked[v] = 1;
    /* grid cells of about twice the geometric mean of the edges: a CAD
     * export's few long edges would make cells of the arithmetic mean hold
     * thousands of its many small triangles */
    double lsum = 0;
    size_t ln = 0;
    for (size_t f = 0; f < mesh->nt; f++) {
        const uint32_t *t = mesh->tri + 3 * f;
        for (int k = 0; k < 3; k++) {
            double l = dist2(mesh->pos + 3 * (size_t)t[k], mesh->pos + 3 * (size_t)t[(k + 1) % 3]);
            if (l > 0) {
                lsum += 0.5 * log(l);
                ln++;
            }
        }
    }
    double h = ln ? 2.0 * exp(lsum / (double)ln) : 1.0;
    if (!(h > 0)) h = diag > 0 ? diag : 1.0;

    imesh M;
    im_surface S;
    run R;
    memset(&R, 0, sizeof R);
    int ok = fl_imesh_init(&M, mesh, fa, locked, h) && fl_imsurf_init(&S, mesh, h);
    free(locked);
    R.C.M = &M;
    R.C.S = &S;
    R.C.p = &p;
    R.budget = 4 * mesh->nt + 1024;
    fl_progress prog;
    fl_progress_init(&prog, o.progress, o.progress_payload, (size_t)rounds);
    int nothing = c.st == 0 && c.sz == 0 && c.val == 0;
    /* the backward bound's samples, at the grid's step (docs/design.md "The
     * two-sided bound of the stage") */
    im_samples samp;
    memset(&samp, 0, sizeof samp);
    if (ok && !nothing && p.maxdev > 0) {
        ok = fl_imsamp_init(&samp, &M, h);
        R.C.samp = &samp;
    }
    census_list CL = {NULL, NULL, 0, 0};
    if (ok && census_only && !nothing && !census_take(&R, &CL)) ok = 0;
    for (int round = 0; ok && !nothing && round < rounds; round++) {
        size_t ops0 = R.C.flips + R.C.splits + R.C.collapses + R.C.relaxations;
        /* long edges */
        if (p.sz_on)
            for (uint32_t f = 0; f < M.nt && !R.C.oom; f++) {
                if (!face_live(&M, f)) continue;
                int lk, sk, w;
                face_edges(&M, f, &lk, &sk);
                const uint32_t *t = M.tri + 3 * (size_t)f;
                uint32_t a = t[(lk + 1) % 3], b = t[(lk + 2) % 3];
                if (dist2(im_P(&M, a), im_P(&M, b)) > p.maxsz * p.maxsz && R.budget > 0) {
                    if (fl_imop_split(&R.C, a, b, NULL, &w)) R.budget--;
                    else M.freason[f] = (uint8_t)(w + 1);
                }
            }
        /* triangles below min_stretch, those of the round's start: what a
         * fix makes waits for the next round, so a fix that another undoes
         * (a cap's split and collapse, then a flip back) costs one try per
         * round, not an endless chain within one (measured on the engine,
         * docs/design.md) */
        if (p.st_on)
            for (uint32_t f = 0, end = (uint32_t)M.nt; f < end && !R.C.oom; f++)
                if (face_live(&M, f) && im_face_stretch(&M, f) < p.minst) fix_face(&R, f);
        /* vertices above max_valence */
        if (p.val_on)
            for (uint32_t v = 0; v < M.nv && !R.C.oom; v++)
                if (M.vf[v].n && fl_imesh_valence(&M, v) > (uint32_t)p.maxval) fix_valence(&R, v);
        /* relaxation around what is still below min_stretch */
        if (p.st_on) {
            uint32_t end = (uint32_t)M.nt;
            for (uint32_t f = 0; f < end && !R.C.oom; f++) {
                if (!face_live(&M, f) || !(im_face_stretch(&M, f) < p.minst)) continue;
                for (int k = 0; k < 3 && face_live(&M, f); k++) {
                    int w;
                    fl_imop_relax(&R.C, M.tri[3 * (size_t)f + (size_t)k], &w);
                }
            }
        }
        rep.rounds++;
        if (R.C.oom) break;
        if (fl_progress_report(&prog, (size_t)round + 1)) {
            rep.cancelled = 1;
            break;
        }
        if (R.C.flips + R.C.splits + R.C.collapses + R.C.relaxations == ops0) break;
    }
    if (ok && R.C.oom) ok = 0;
    if (ok && census_only) {
        fl_progress_end(&prog);
        rep.stretch_min = c.stmin;
        rep.valence_max = c.valmax;
        census_count(&R, &CL, &rep);
        st = FEMLOD_OK;
    } else if (ok) {
        fl_progress_end(&prog);
        final_census(&R, &rep);
        st = make_output(out, &M, vmap, err);
    } else
        st = fl_error(err, FEMLOD_ENOMEM, "improve: out of memory");
    rep.flips = R.C.flips;
    rep.splits = R.C.splits;
    rep.collapses = R.C.collapses;
    rep.relaxations = R.C.relaxations;
    for (int k = 0; k < FEMLOD_IMPROVE_REASON_COUNT; k++) rep.refused[k] = R.C.refused[k];
    if (st == FEMLOD_OK && !census_only) {
        rep.triangles = (*out)->nt;
        rep.vertices = (*out)->nv;
    } else if (st == FEMLOD_OK) {
        rep.triangles = mesh->nt;
        rep.vertices = mesh->nv;
        /* no change is made: the operators' counts are the try's */
    }
    free(CL.face);
    free(CL.vert);
    free(R.C.buf);
    fl_imtx_free(&R.C);
    free(R.vreason);
    fl_imesh_free(&M);
    fl_imsurf_free(&S);
    fl_imsamp_free(&samp);
    rep.seconds = wall() - t0;
    if (report && st == FEMLOD_OK) *report = rep;
    return st;
}
