/*
 * simplify.c - quality-controlled edge-collapse simplification.
 *
 * Implements paper.md section 4 (Lee et al., "Mesh simplification and
 * adaptive LOD for finite element mesh generation") as corrected and settled
 * by method-notes.md; docs/simplify.md maps each step to the functions here
 * and records the choices and the measurements behind them.
 *
 *   4.1 (1)-(4) quadrics        setup (planes, optionally area-weighted; line
 *                               quadrics on feature edges weighted by
 *                               sharpness) and quadric.h (Garland and
 *                               Heckbert, SIGGRAPH 1997, plus line terms)
 *   4.1 2)-3) size, stretch     tri_eval (squared forms: no sqrt to
 *                               compare), tri_stretch
 *   4.2.1 candidates            make_candidates (midpoint and the robust
 *                               optimum, fl_quadric_optimum2, cached per
 *                               edge; the fixed endpoint for corners, locks
 *                               and feature lines; endpoints and midpoint
 *                               along a feature line), evaluate
 *   4.2.2 validity              gather (C4 valence, features, locks),
 *                               eval_candidate and tri_eval (C1 tolerance,
 *                               C2 stretch, C3 size, turn against the
 *                               current mesh), at pop time link_check and
 *                               expensive_checks:
 *                               cone_check (turn against the input surface,
 *                               PMP's normal cones), deviation_check
 *                               (max_deviation, PMP's Hausdorff tracking),
 *                               intersect_check (intersect.c)
 *   4.2.2 pre-phase             simplify_run, phase 0
 *   4.2.3 priority              rho = Sz_DIF * St_MIN * St_AVE, eval_candidate;
 *                               the queue: run_queue, reevaluate_ring, heap.c
 *                               (optionally exact lazy: bound_edge, settle)
 *   4.2 step 4, 5.1 log         collapse, log_collapse, simplify_log.c
 *
 * Topology (link condition, Dey et al., "Topology preserving edge
 * contraction", 1999; the tetrahedron and handle cases as in OpenMesh's
 * is_collapse_ok) is checked in gather and link_check.
 *
 * Structure: vertices keep their incident faces in one growing reference
 * array (a new vertex's list is appended; the merged vertex takes the slot
 * of i); faces keep their corners and the edges of their sides; edges are
 * numbered once at setup (collapses only remove and merge edges) and are the
 * items of an indexed max-heap. Every choice that could depend on order is
 * made on indices, so results repeat bit for bit.
 */
#include "core.h"
#include "heap.h"
#include "intersect.h"
#include "quadric.h"
#include "simplify_log.h"
#include "vec3.h"

#include <assert.h>
#include <math.h>
#include <float.h>
#include <pthread.h>
#if defined(__GLIBC__)
#include <malloc.h> /* malloc_trim: release_freed_memory */
#endif
#include <sched.h>
#include <stdatomic.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h> /* getrusage: the stats build's fault counts */
#include <time.h>
#include <unistd.h>

#define PI 3.14159265358979323846

/* Tunables, fixed by the measurements in docs/simplify.md; -D overrides
 * them for experiments only. */
#ifndef FEMLOD_SIMPLIFY_DEFAULT_TOLERANCE
#define FEMLOD_SIMPLIFY_DEFAULT_TOLERANCE 4.0 /* times (mean input edge)^2 */
#endif
#ifndef FEMLOD_SIMPLIFY_GRID_CELL
#define FEMLOD_SIMPLIFY_GRID_CELL 1.0 /* grid cell edge / mean edge length */
#endif
#ifndef FEMLOD_SIMPLIFY_SZDIF_RING
#define FEMLOD_SIMPLIFY_SZDIF_RING 1 /* Sz_DIF over every triangle at i or j */
#endif
#ifndef FEMLOD_SIMPLIFY_EIGEN_REL
#define FEMLOD_SIMPLIFY_EIGEN_REL 1e-3 /* eigen directions kept in the optimum */
#endif
#ifndef FEMLOD_SIMPLIFY_LINE_TURN
#define FEMLOD_SIMPLIFY_LINE_TURN 20.0 /* degrees: a feature line this straight takes midpoints */
#endif
#ifndef FEMLOD_SIMPLIFY_CERTIFY
#define FEMLOD_SIMPLIFY_CERTIFY 1 /* star certificates in the intersection test */
#endif
#ifndef FEMLOD_SIMPLIFY_PLANE_RULE
#define FEMLOD_SIMPLIFY_PLANE_RULE 1 /* intersection test: the plane rule (docs/design.md) */
#endif
#ifndef FEMLOD_SIMPLIFY_PLANE_VERIFY
#define FEMLOD_SIMPLIFY_PLANE_VERIFY 0 /* 1: run the full test too and report disagreements */
#endif
#ifndef FEMLOD_SIMPLIFY_BOUND
#define FEMLOD_SIMPLIFY_BOUND 0 /* 1: exact lazy re-evaluation with upper bounds (docs/simplify.md: fewer evaluations, more time) */
#endif
#ifndef FEMLOD_SIMPLIFY_USE_OPTIMUM
#define FEMLOD_SIMPLIFY_USE_OPTIMUM 1
#endif
/* -DFEMLOD_SIMPLIFY_STATS=1: count the work (evaluations, checks, grid
 * visits) per run in simp.stats and print it to stderr; for measurements
 * only (docs/simplify.md). No global state: the counters live in the run. */
#ifndef FEMLOD_SIMPLIFY_STATS
#define FEMLOD_SIMPLIFY_STATS 0
#endif
/* -DFEMLOD_SIMPLIFY_MARKED_SCAN=1: band_vertex finds every vertex's edges
 * by the marked scan, as at boundary, non-manifold and unoriented vertices,
 * instead of one side per face; for tests/c/scan_digest.c, which checks
 * that the two scans give byte-identical results (tests/CMakeLists.txt). */
#ifndef FEMLOD_SIMPLIFY_MARKED_SCAN
#define FEMLOD_SIMPLIFY_MARKED_SCAN 0
#endif
#if FEMLOD_SIMPLIFY_STATS
#include <stdio.h>
#define STAT(x) ((void)(S->stats.x++))
static double now_seconds(void);
#define STAT_TIME(k, t0) ((void)(S->stats.t[k] += now_seconds() - (t0)))
#define STAT_TIME_ST(k, t0) ((void)(S->stats.tstage[k] += now_seconds() - (t0)))
#else
#define STAT_TIME(k, t0) ((void)0)
#define STAT_TIME_ST(k, t0) ((void)0)
#define STAT(x) ((void)0)
#endif

/* vertex flags */
enum {
    V_DEAD = 1,
    V_FIXED = 2,      /* corner, locked, non-manifold or kept boundary: never moves */
    V_BOUNDARY = 4,
    V_NONMANIFOLD = 8
};
/* edge flags: eflag holds E_FEATURE and E_DEAD (the mesh), estate the
 * rest (what the last evaluation left): a fast-pass worker writes the state
 * of an edge while another may read its flags (docs/design.md) */
enum {
    E_FEATURE = 1,
    E_DEAD = 2,
    E_TOLFAIL = 4, /* last evaluation: every candidate failed C1 only; stays so while i and j do */
    E_STALE = 8,   /* queued with an upper bound of its priority (bound_edge), not the priority */
    E_OPT = 16,    /* eopt holds the edge's optimum candidate, or E_OPTC is clear: none (make_candidates) */
    E_OPTC = 32
};

/* candidate modes */
enum {
    M_FREE,   /* midpoint and optimum */
    M_KEEP_I, /* k = p_i (i fixed, or on a feature line that j is not on) */
    M_KEEP_J,
    M_LINE    /* i and j on one feature line: the endpoints, and the midpoint where the line is straight */
};

#define NO_REASON (-1)
/* a fast-pass worker may not do this collapse in its slab: band_par's
 * sequential remainder will (never counted as a rejection) */
#define DEFER_REASON FEMLOD_REJECT_COUNT
#define MAX_VSTARS 253

typedef struct u32vec {
    uint32_t *v;
    size_t n, cap;
} u32vec;

typedef struct ring {
    uint32_t e, i, j;
    size_t n, cap;   /* surviving faces of i and j: the new triangles (k, a, b) */
    uint32_t *face;
    uint32_t *a, *b;
    uint8_t *from_j;
    double *lab;     /* |a - b| */
    double *lab2;
    size_t ns;       /* faces with both i and j (removed) */
    uint32_t sface[2], sopp[2];
    int mode;
    int newval;
    double szdif;
    double st_removed; /* pre-phase: least stretch of the faces a collapse removes or changes */
    /* candidates */
    int ncand;
    double cand[3][3];
    double rho[3];
    int ok[3];
    int reason;      /* first failing check of the last candidate */
    int tolfail;     /* every candidate failed C1 and nothing else before it */
} ring;

typedef struct simp_stats {
    size_t evals, settles, bounds, rings, cands, cand_ok, solves, pops, links, expensive, cells, items, tritri, skipped;
    size_t planar;
    size_t deferred;
    size_t attempts, attempt_low, attempt_fresh;
    double t[6]; /* seconds: setup, pre-phase, first evaluation of the passes, passes, queue, output */
    size_t listed[4]; /* parallel passes: vertices listed in stage 0, 1, the remainder; sub-passes */
    /* and their seconds; [3]: in par_for; [4..9]: listing, bucketing, task
     * set-up, merge, grid rebuilds, compactions; [10 + t]: worker t's
     * seconds in tasks; [30]: thread-seconds spent waiting for the last
     * thread at the end of a par_for */
    double tstage[32];
    double tpass; /* when the last pass (or the first evaluation) ended */
} simp_stats;

/* Per-thread buffers of the checks, grown on demand. */
typedef struct scratch {
    uint32_t *ebuf;
    size_t ebuf_cap;
    uint32_t *pbuf; /* deviation points */
    uint32_t *pdst; /* their new face (ring index) */
    size_t pbuf_cap, pdst_cap;
    double *tbox; /* per ring face: box of the new triangle */
    size_t tbox_cap;
    double *obox; /* per ring face: its box before the collapse (collapse) */
    size_t obox_cap;
    fl_tri_plane *tplane; /* per ring face: plane of the new triangle */
    size_t tplane_cap;
    uint8_t *cert; /* per ring face: star certificates of a and b (intersect_check) */
    size_t cert_cap;
    float *newcone; /* per ring face */
    size_t newcone_cap;
} scratch;

typedef struct edge_rec {
    uint32_t v[2]; /* endpoints, v[0] < v[1] at first */
    float key;
    uint16_t nf;
    uint8_t flag, state;
} edge_rec;

typedef struct face_rec {
    uint32_t v[3];
    float n[3];
    double inv;
} face_rec;

typedef struct simp {
    /* resolved thresholds */
    size_t target;
    double tol, maxdev, minst, maxsz, feat_angle, feat_w, max_nc;
    int maxval, keep_boundary, area_w;
    int tol_on, dev_on, st_on, sz_on, val_on, cone_on;
    /* every interior edge's two faces run opposite ways (set-up); collapses
     * keep it. Then each edge at an interior manifold vertex v runs from v
     * in exactly one of v's faces (band_vertex). */
    int oriented;
    double minst2, maxsz2, cos_nc, cos_nc2, maxdev2, eps;
    /* tri_eval's limits with "off" folded in (a limit nothing crosses), so
     * its tests need no flags: size^2, turn cos^2, stretch^2 (phase 1 only) */
    double lim_sz2, lim_turn2, lim_st2;

    /* vertices: slot s holds input vertex node[s] at first (Morton order) */
    size_t nv;
    uint32_t *slot_of; /* during setup: input index -> slot */
    const double *pos0; /* the input positions */
    double *pos;
    fl_quadric *q;
    uint32_t *node;
    uint32_t *fstart, *fcount;
    uint32_t *val;
    uint8_t *vflag;
    uint8_t *fdeg;
    uint32_t *vmark;
    uint32_t *refs;
    size_t nrefs, caprefs;

    /* faces */
    size_t nt, live, nt_in;
    /* per face slot its corners (v[0] = UINT32_MAX: dead), unit normal
     * (NaN for degenerate) and 1 / fsz (for Sz_DIF): one 32-byte record,
     * so that the corners' read brings the rest (64-byte aligned) */
    face_rec *face;
    uint32_t *tedge;
    uint32_t *fin; /* input triangle index of each face slot */
    float *fsz;  /* longest edge */
    float *cone; /* axis xyz, half-angle (radians) */
    uint32_t *fmark; /* set-up only: the pinched-vertex flood (with vertex stamps) */
    uint8_t *fmade; /* 1: made by a collapse, not read from the input (plane_rule) */
    uint32_t *fpt; /* deviation: first removed input vertex assigned to the face */
    uint32_t *pnext;

    /* edges */
    size_t ne;
    uint32_t *ev;
    uint16_t *enf;
    /* per edge: its endpoints, key in the fast passes, face count, flags
     * (E_FEATURE, E_DEAD) and state (the rest): one 16-byte record, read
     * together (ev and enf only during the set-up) */
    edge_rec *edge;
    uint32_t *emark;
    double *eopt;    /* per edge: the optimum candidate (E_OPT) */
    uint32_t *ehint; /* per edge and candidate (make_candidates order, first two): see eval_candidate */

    fl_heap heap;
    fl_grid grid;
    size_t grid_live; /* live faces when the grid was built */
    uint32_t grid_gen; /* grids built so far (band_par's block pools belong to one) */
    double grid_h;
    uint32_t stamp;

    ring R;
    ring R2; /* band_vertex: the best edge's evaluation while others are evaluated */
    scratch sc;  /* each thread's own (simp_view keeps it) */
    size_t npts; /* points gathered by the last deviation check */
    uint32_t vstars[MAX_VSTARS + 2];
    uint8_t lfaces[3 * 1024];

    int phase;
    /* fast passes (band_run): the factor (0: off), per slot the pass that
     * locked it and the best key of its edges, per edge its last key */
    double fast;
    uint32_t *vlock;
    float *vbest;
    uint32_t pass;
    size_t swept;
    /* parallel fast passes (band_par): the thread count; in a worker's view
     * (par = 1) the slab it owns, the live triangles at the start of its
     * task and how many it may remove, and its new vertices' slots */
    int nthreads;
    int par;
    int slab_ax;
    uint32_t slab, slab_w, slab_shift;
    size_t live_start, live_budget;
    u32vec *klist;
    /* the exact queue's ring re-evaluation on two threads (ring_eval): the
     * helper, and per listed edge what to do, its priority and C1 flag */
    struct eval_helper *helper;
    struct par_ctx *ectx; /* evaluate_all's threads (eval_range) */
    size_t er0;           /* the first edge of eval_range's chunk */
    uint32_t *rlist;
    uint8_t *rkind, *rtol;
    double *rrho;
    size_t rlist_cap, rkind_cap, rtol_cap, rrho_cap;
    femlod_collapse_log *log;
    size_t collapses, prephase;
    size_t rejected[FEMLOD_REJECT_COUNT];
    int binding; /* the check that refused most edges in the last full evaluation (finish) */
    size_t prog_target; /* the count progress is measured towards: target, or the floor past it */
    int oom;
    int cancelled;  /* the progress callback asked to stop during evaluate_all */
#if FEMLOD_SIMPLIFY_STATS
    simp_stats stats;
#endif
} simp;

/* {====== small vector helpers */

/* fmin/fmax are calls (NaN rules); no NaN reaches these */
static inline double mn(double a, double b) { return a < b ? a : b; }
static inline double mx(double a, double b) { return a > b ? a : b; }
static inline uint32_t min3u(const uint32_t t[3]) {
    uint32_t m = t[0] < t[1] ? t[0] : t[1];
    return m < t[2] ? m : t[2];
}


/* Stretch (4.1 3), method-notes "Element measures") from the corners. */
static double tri_stretch(const double *a, const double *b, const double *c, double *size) {
    double la = sqrt(dist2(b, c)), lb = sqrt(dist2(a, c)), lc = sqrt(dist2(a, b));
    double L = mx(la, mx(lb, lc));
    if (size) *size = L;
    double s = 0.5 * (la + lb + lc);
    if (!(L > 0.0) || !(s > 0.0)) return 0.0;
    double r2 = (s - la) * (s - lb) * (s - lc) / s;
    if (!(r2 > 0.0)) return 0.0;
    return sqrt(12.0 * r2) / L;
}

/* }====== */

/* {====== faces */

static inline const double *P(const simp *S, uint32_t v) { return S->pos + 3 * (size_t)v; }

static void face_bbox(const simp *S, uint32_t f, double lo[3], double hi[3]) {
    const uint32_t *t = S->face[f].v;
    const double *a = P(S, t[0]), *b = P(S, t[1]), *c = P(S, t[2]);
    for (int k = 0; k < 3; k++) {
        lo[k] = mn(a[k], mn(b[k], c[k]));
        hi[k] = mx(a[k], mx(b[k], c[k]));
    }
}

static void face_update_cache(simp *S, uint32_t f) {
    const uint32_t *t = S->face[f].v;
    const double *a = P(S, t[0]), *b = P(S, t[1]), *c = P(S, t[2]);
    double e1[3], e2[3], n[3];
    sub3(e1, b, a);
    sub3(e2, c, a);
    cross3(n, e1, e2);
    double l = sqrt(dot3(n, n));
    /* a degenerate face gets a NaN normal: every comparison with it is
     * false, so tri_eval skips the turn test without a branch of its own */
    for (int k = 0; k < 3; k++) S->face[f].n[k] = l > 0 ? (float)(n[k] / l) : __builtin_nanf("");
    double L2 = mx(dot3(e1, e1), mx(dot3(e2, e2), dist2(b, c)));
    S->fsz[f] = (float)sqrt(L2);
    S->face[f].inv = 1.0 / (double)S->fsz[f];
}

static inline int face_alive(const simp *S, uint32_t f) { return S->face[f].v[0] != UINT32_MAX; }

/* }====== */

/* {====== normal cones (PMP's NormalCone, pmp/algorithms/normal_cone.h) */

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

/* }====== */

/* {====== growing scratch */

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

static int buf_reserve(void **p, size_t *cap, size_t n, size_t elem) {
    if (n <= *cap) return 1;
    size_t c = *cap ? *cap : 64;
    while (c < n) c *= 2;
    void *q = fl_realloc(*p, c, elem);
    if (!q) return 0;
    *p = q;
    *cap = c;
    return 1;
}

/* n elements of size bytes, 64-byte aligned (cache lines); NULL on
 * ENOMEM or overflow. Freed with free. */
static void *alloc_lines(size_t n, size_t size) {
    if (size && n > SIZE_MAX / size) return NULL;
    void *p = NULL;
    size_t bytes = n * size;
    return posix_memalign(&p, 64, bytes ? bytes : 64) == 0 ? fl_populate(p, bytes) : NULL;
}

static uint32_t next_stamp(simp *S) {
    if (++S->stamp == 0) { /* wrapped: clear */
        memset(S->vmark, 0, S->nv * sizeof *S->vmark);
        memset(S->emark, 0, S->ne * sizeof *S->emark);
        S->stamp = 1;
    }
    return S->stamp;
}


/* }====== */

/* {====== gather: the position-independent part of an edge's evaluation */

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
    int feature = (S->edge[e].flag & E_FEATURE) != 0;

    /* Which positions may k take (method-notes "Optimal position"): fixed
     * vertices stay, a vertex on one feature line only slides along it,
     * two features never merge across a non-feature edge. */
    if (nf == 0 || nf > 2 || ((fi | fj) & V_NONMANIFOLD)) return FEMLOD_REJECT_TOPOLOGY;
    int fixi = (fi & V_FIXED) != 0, fixj = (fj & V_FIXED) != 0;
    int feati = S->fdeg[i] > 0, featj = S->fdeg[j] > 0;
    if (fixi && fixj) return FEMLOD_REJECT_TOPOLOGY;
    if (fixi) {
        if (featj && !feature) return FEMLOD_REJECT_TOPOLOGY;
        R->mode = M_KEEP_I;
    } else if (fixj) {
        if (feati && !feature) return FEMLOD_REJECT_TOPOLOGY;
        R->mode = M_KEEP_J;
    } else if (feati && featj) {
        if (!feature) return FEMLOD_REJECT_TOPOLOGY;
        R->mode = M_LINE; /* both on the line: slide along it */
    } else if (feati) {
        R->mode = M_KEEP_I;
    } else if (featj) {
        R->mode = M_KEEP_J;
    } else {
        R->mode = M_FREE;
    }

    /* C4 (method-notes "Valid edges"): val(i) + val(j) - 4 interior, - 3 boundary. */
    int boundary_edge = nf == 1;
    if (!boundary_edge && (fi & V_BOUNDARY) && (fj & V_BOUNDARY))
        return FEMLOD_REJECT_TOPOLOGY; /* would pinch the surface at k */
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
static int link_check(simp *S, const ring *R) {
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
    if (S->tol_on && fl_quadric_eval2(qi, qj, p) > S->tol) return FEMLOD_REJECT_TOLERANCE;
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
static double evaluate(simp *S, ring *R, uint32_t e) {
    STAT(evals);
    R->ncand = 0;
    R->tolfail = 0;
    int why = gather(S, R, e);
    if (why != NO_REASON) {
        S->rejected[why]++;
        R->reason = why;
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
static double bound_edge(simp *S, ring *R, uint32_t e, uint32_t k) {
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
        if (S->tol_on && fl_quadric_eval2(qi, qj, p) > S->tol) {
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

static int deviation_check(simp *S, ring *R, const double p[3], size_t *np) {
    size_t n = 0;
    /* the removed input vertices held by the changed faces, and i, j
     * themselves when they are input vertices */
    for (int side = 0; side < 2; side++) {
        uint32_t v = side ? R->j : R->i;
        const uint32_t *fl = S->refs + S->fstart[v];
        for (uint32_t m = 0; m < S->fcount[v]; m++) {
            uint32_t f = fl[m];
            if (side == 1) { /* shared faces were listed from i */
                const uint32_t *t = S->face[f].v;
                if (t[0] == R->i || t[1] == R->i || t[2] == R->i) continue;
            }
            for (uint32_t x = S->fpt[f]; x != UINT32_MAX; x = S->pnext[x]) {
                if (!buf_reserve((void **)&S->sc.pbuf, &S->sc.pbuf_cap, n + 1, sizeof *S->sc.pbuf)) {
                    S->oom = 1;
                    return FEMLOD_REJECT_DEVIATION;
                }
                S->sc.pbuf[n++] = x;
            }
        }
    }
    for (int side = 0; side < 2; side++) {
        uint32_t v = side ? R->j : R->i;
        if (S->node[v] < S->nv) {
            if (!buf_reserve((void **)&S->sc.pbuf, &S->sc.pbuf_cap, n + 1, sizeof *S->sc.pbuf)) {
                S->oom = 1;
                return FEMLOD_REJECT_DEVIATION;
            }
            S->sc.pbuf[n++] = S->node[v];
        }
    }
    if (!buf_reserve((void **)&S->sc.pdst, &S->sc.pdst_cap, n, sizeof *S->sc.pdst)) {
        S->oom = 1;
        return FEMLOD_REJECT_DEVIATION;
    }
    *np = n;
    if (R->n == 0) return n ? FEMLOD_REJECT_DEVIATION : NO_REASON;
    for (size_t m = 0; m < n; m++) {
        const double *x = S->pos0 + 3 * (size_t)S->sc.pbuf[m];
        double best = __builtin_inf();
        uint32_t bi = 0;
        for (size_t r = 0; r < R->n; r++) {
            double d = fl_point_tri_dist2(x, p, P(S, R->a[r]), P(S, R->b[r]));
            if (d < best) {
                best = d;
                bi = (uint32_t)r;
            }
        }
        if (best > S->maxdev2) return FEMLOD_REJECT_DEVIATION;
        S->sc.pdst[m] = bi;
    }
    return NO_REASON;
}

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

/* The slab (band_par) of a grid cell coordinate and of a point. */
static inline uint32_t slab_of_cell(const simp *S, int c) { return ((uint32_t)c + S->slab_shift) / S->slab_w; }
static inline uint32_t slab_of(const simp *S, const double *p) {
    return slab_of_cell(S, fl_grid_coord(&S->grid, p[S->slab_ax], S->slab_ax));
}

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
static int intersect_check(simp *S, ring *R, const double p[3]) {
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

/* Candidate c passes the checks that are too costly for every evaluation. */
static int expensive_checks(simp *S, ring *R, int c) {
    STAT(expensive);
    const double *p = R->cand[c];
    int w;
    if (S->cone_on && (w = cone_check(S, R, p)) != NO_REASON) return w;
    if (S->dev_on && (w = deviation_check(S, R, p, &S->npts)) != NO_REASON) return w;
    return intersect_check(S, R, p);
}

/* }====== */

/* {====== collapse (4.2 step 4) and the log (5.1) */


static uint8_t local_ref(const simp *S, const ring *R, size_t nvs, uint32_t v) {
    if (v == R->i) return 0;
    if (v == R->j) return 1;
    uint32_t id = S->node[v];
    size_t lo = 0, hi = nvs;
    while (lo < hi) {
        size_t mid = (lo + hi) / 2;
        if (S->vstars[mid] < id) lo = mid + 1;
        else hi = mid;
    }
    return (uint8_t)(2 + lo);
}

static int log_collapse(simp *S, ring *R, const double p[3]) {
    uint32_t mk = next_stamp(S);
    size_t nvs = 0;
    for (size_t r = 0; r < R->n; r++) {
        uint32_t ab[2] = {R->a[r], R->b[r]};
        for (int q = 0; q < 2; q++)
            if (S->vmark[ab[q]] != mk) {
                S->vmark[ab[q]] = mk;
                S->vstars[nvs++] = S->node[ab[q]];
            }
    }
    for (size_t s = 0; s < R->ns; s++)
        if (S->vmark[R->sopp[s]] != mk) {
            S->vmark[R->sopp[s]] = mk;
            S->vstars[nvs++] = S->node[R->sopp[s]];
        }
    /* at most a few dozen distinct ids: insertion sort beats qsort's calls */
    for (size_t x = 1; x < nvs; x++) {
        uint32_t v = S->vstars[x];
        size_t y = x;
        for (; y > 0 && S->vstars[y - 1] > v; y--) S->vstars[y] = S->vstars[y - 1];
        S->vstars[y] = v;
    }
    double es = 0.0;
    /* e_size: mean distance from k to its vstars (paper 5.1) */
    mk = next_stamp(S);
    size_t cnt = 0;
    for (size_t r = 0; r < R->n; r++) {
        uint32_t ab[2] = {R->a[r], R->b[r]};
        for (int q = 0; q < 2; q++)
            if (S->vmark[ab[q]] != mk) {
                S->vmark[ab[q]] = mk;
                es += sqrt(dist2(p, P(S, ab[q])));
                cnt++;
            }
    }
    for (size_t s = 0; s < R->ns; s++)
        if (S->vmark[R->sopp[s]] != mk) {
            S->vmark[R->sopp[s]] = mk;
            es += sqrt(dist2(p, P(S, R->sopp[s])));
            cnt++;
        }
    es = cnt ? es / (double)cnt : 0.0;
    size_t nf = R->ns + R->n;
    if (nf > sizeof S->lfaces / 3) return 0;
    size_t w = 0;
    for (size_t s = 0; s < R->ns; s++) {
        const uint32_t *t = S->face[R->sface[s]].v;
        for (int c = 0; c < 3; c++) S->lfaces[w++] = local_ref(S, R, nvs, t[c]);
    }
    for (size_t r = 0; r < R->n; r++) {
        const uint32_t *t = S->face[R->face[r]].v;
        for (int c = 0; c < 3; c++) S->lfaces[w++] = local_ref(S, R, nvs, t[c]);
    }
    return fl_log_add(S->log, S->node[R->i], S->node[R->j], p, es, S->vstars, nvs, S->lfaces, nf);
}

static int grid_add_face(simp *S, uint32_t f) {
    double lo[3], hi[3];
    face_bbox(S, f, lo, hi);
    return fl_grid_insert(&S->grid, f, lo, hi);
}

static void grid_remove_face(simp *S, uint32_t f) {
    double lo[3], hi[3];
    face_bbox(S, f, lo, hi);
    fl_grid_remove(&S->grid, f, lo, hi);
}

static uint32_t side_edge(const simp *S, uint32_t f, uint32_t u, uint32_t v) {
    const uint32_t *t = S->face[f].v;
    for (int c = 0; c < 3; c++) {
        uint32_t x = t[c], y = t[(c + 1) % 3];
        if ((x == u && y == v) || (x == v && y == u)) return S->tedge[3 * (size_t)f + c];
    }
    return UINT32_MAX;
}

static void list_remove(simp *S, uint32_t v, uint32_t f) {
    uint32_t *fl = S->refs + S->fstart[v];
    uint32_t n = S->fcount[v];
    for (uint32_t m = 0; m < n; m++)
        if (fl[m] == f) {
            /* keep the order: it decides the order of sums, and results must
             * not depend on which face went first */
            memmove(fl + m, fl + m + 1, (n - m - 1) * sizeof *fl);
            S->fcount[v] = n - 1;
            return;
        }
}

typedef void (*range_fn)(void *ctx, size_t lo, size_t hi, int part);
static void par_ranges(int nth, size_t n, range_fn fn, void *ctx);
static int par_parts(int nth, size_t n);

/* compact_refs in vertex parts: each part's lists, at its offset */
typedef struct compact_ctx {
    simp *S;
    uint32_t *nr;
    size_t at[16];
} compact_ctx;

static void compact_count(void *arg, size_t v0, size_t v1, int part) {
    compact_ctx *C = arg;
    size_t n = 0;
    for (size_t v = v0; v < v1; v++) n += C->S->fcount[v];
    C->at[part] = n;
}

static void compact_copy(void *arg, size_t v0, size_t v1, int part) {
    compact_ctx *C = arg;
    simp *S = C->S;
    size_t w = C->at[part], w0 = w;
    for (size_t v = v0; v < v1; v++) w += S->fcount[v];
    fl_populate(C->nr + w0, (w - w0) * sizeof *C->nr); /* the part copied now */
    w = w0;
    for (size_t v = v0; v < v1; v++) {
        memcpy(C->nr + w, S->refs + S->fstart[v], S->fcount[v] * sizeof *C->nr);
        S->fstart[v] = (uint32_t)w;
        w += S->fcount[v];
    }
}

static int compact_refs(simp *S) {
    compact_ctx C;
    C.S = S;
    par_ranges(S->nthreads, S->nv, compact_count, &C);
    size_t total = 0;
    for (int t = 0; t < par_parts(S->nthreads, S->nv); t++) {
        size_t n = C.at[t];
        C.at[t] = total;
        total += n;
    }
    /* room for as many appended lists again: compaction stays amortised O(1) */
    size_t cap = 2 * total + 1024;
    C.nr = fl_alloc(cap, sizeof *C.nr);
    if (!C.nr) return 0;
    par_ranges(S->nthreads, S->nv, compact_copy, &C);
    free(S->refs);
    S->refs = C.nr;
    S->nrefs = total;
    S->caprefs = cap;
    return 1;
}

static int build_grid(simp *S, double h) {
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

static int collapse(simp *S, ring *R, int c) {
    const double *pc = R->cand[c];
    double p[3] = {pc[0], pc[1], pc[2]};
    uint32_t i = R->i, j = R->j, e = R->e;
    int efeat = (S->edge[e].flag & E_FEATURE) != 0;
    if (S->log && !log_collapse(S, R, p)) return 0;

    /* out of the grid while the old positions hold */
    for (size_t s = 0; s < R->ns; s++) grid_remove_face(S, R->sface[s]);
    /* the ring faces stay in the grid: moved to their new boxes below */
    if (!buf_reserve((void **)&S->sc.obox, &S->sc.obox_cap, 6 * R->n + 6, sizeof *S->sc.obox)) return 0;
    for (size_t r = 0; r < R->n; r++) face_bbox(S, R->face[r], S->sc.obox + 6 * r, S->sc.obox + 6 * r + 3);

    if (S->dev_on) {
        for (size_t s = 0; s < R->ns; s++) S->fpt[R->sface[s]] = UINT32_MAX;
        for (size_t r = 0; r < R->n; r++) S->fpt[R->face[r]] = UINT32_MAX;
        for (size_t m = 0; m < S->npts; m++) {
            uint32_t x = S->sc.pbuf[m], f = R->face[S->sc.pdst[m]];
            S->pnext[x] = S->fpt[f];
            S->fpt[f] = x;
        }
    }

    /* edges: (i,j) goes; (j,x) merges into (i,x) at each removed face */
    fl_heap_remove(&S->heap, e);
    S->edge[e].flag = E_DEAD;
    for (size_t s = 0; s < R->ns; s++) {
        uint32_t F = R->sface[s], x = R->sopp[s];
        uint32_t eix = side_edge(S, F, i, x), ejx = side_edge(S, F, j, x);
        for (size_t r = 0; r < R->n; r++) {
            if (!R->from_j[r]) continue;
            uint32_t *te = S->tedge + 3 * (size_t)R->face[r];
            for (int k = 0; k < 3; k++)
                if (te[k] == ejx) te[k] = eix;
        }
        S->edge[eix].nf = (uint16_t)(S->edge[eix].nf + S->edge[ejx].nf - 2);
        S->edge[eix].flag |= S->edge[ejx].flag & E_FEATURE;
        S->edge[ejx].flag = E_DEAD;
        fl_heap_remove(&S->heap, ejx);
        list_remove(S, x, F);
        S->val[x]--;
        uint32_t *t = S->face[F].v;
        t[0] = t[1] = t[2] = UINT32_MAX;
        S->live--;
    }
    /* j's faces and edges now belong to i's slot */
    for (size_t r = 0; r < R->n; r++) {
        if (!R->from_j[r]) continue;
        uint32_t f = R->face[r];
        uint32_t *t = S->face[f].v;
        for (int k = 0; k < 3; k++) {
            if (t[k] == j) t[k] = i;
            uint32_t ed = S->tedge[3 * (size_t)f + k];
            if (S->edge[ed].v[0] == j) S->edge[ed].v[0] = i;
            if (S->edge[ed].v[1] == j) S->edge[ed].v[1] = i;
        }
    }
    /* the new vertex's face list, appended */
    if (S->nrefs + R->n > S->caprefs) {
        if (!compact_refs(S)) return 0;
        if (S->nrefs + R->n > S->caprefs) {
            size_t cap = S->caprefs * 2 + R->n;
            uint32_t *nr = fl_realloc(S->refs, cap, sizeof *nr);
            if (!nr) return 0;
            S->refs = nr;
            S->caprefs = cap;
        }
    }
    memcpy(S->refs + S->nrefs, R->face, R->n * sizeof *R->face);
    S->fstart[i] = (uint32_t)S->nrefs;
    S->fcount[i] = (uint32_t)R->n;
    S->nrefs += R->n;
    S->fcount[j] = 0;

    uint8_t fi = S->vflag[i], fj = S->vflag[j];
    S->vflag[i] = (uint8_t)((fi | fj) & (V_FIXED | V_BOUNDARY));
    S->vflag[j] = V_DEAD;
    /* k keeps the feature edges of both, the collapsed one excepted */
    S->fdeg[i] = (uint8_t)(S->fdeg[i] + S->fdeg[j] - (efeat ? 2 : 0));
    fl_quadric_add(S->q + i, S->q + j);
    memcpy(S->pos + 3 * (size_t)i, p, sizeof p);
    S->val[i] = (uint32_t)R->newval;
    S->node[i] = (uint32_t)(S->nv + S->collapses);

    for (size_t r = 0; r < R->n; r++) {
        uint32_t f = R->face[r];
        face_update_cache(S, f);
        S->fmade[f] = 1;
        if (S->cone_on) memcpy(S->cone + 4 * (size_t)f, S->sc.newcone + 4 * r, 4 * sizeof(float));
        double lo[3], hi[3];
        face_bbox(S, f, lo, hi);
        if (!fl_grid_move(&S->grid, f, S->sc.obox + 6 * r, S->sc.obox + 6 * r + 3, lo, hi)) return 0;
    }
    S->collapses++;
    if (S->phase == 0) S->prephase++;
    if (S->live * 4 < S->grid_live && S->live > 64) {
        if (!build_grid(S, S->grid_h * 2.0)) return 0;
    }
    return 1;
}

/* }====== */

/* {====== (re-)evaluation */

static int face_is_bad(const simp *S, uint32_t f) {
    const uint32_t *t = S->face[f].v;
    return tri_stretch(P(S, t[0]), P(S, t[1]), P(S, t[2]), NULL) < S->minst;
}

static void update_edge(simp *S, uint32_t ed, int eligible) {
    if (S->edge[ed].flag & E_DEAD) return;
    if (!eligible) {
        fl_heap_remove(&S->heap, ed);
        return;
    }
    double rho = evaluate(S, &S->R, ed);
    S->edge[ed].state = (uint8_t)((S->edge[ed].state & ~(E_TOLFAIL | E_STALE)) | (S->R.tolfail ? E_TOLFAIL : 0));
    if (rho >= 0.0) fl_heap_set(&S->heap, ed, rho);
    else fl_heap_remove(&S->heap, ed);
}

/* update_edge with an upper bound for the priority (phase 1, an edge away
 * from k): the same decisions on validity and E_TOLFAIL. */
static void bound_update(simp *S, uint32_t ed, uint32_t k) {
    double ub = bound_edge(S, &S->R, ed, k);
    S->edge[ed].state = (uint8_t)((S->edge[ed].state & ~(E_TOLFAIL | E_STALE)) | (S->R.tolfail ? E_TOLFAIL : 0));
    if (ub >= 0.0) {
        fl_heap_set(&S->heap, ed, ub);
        S->edge[ed].state |= E_STALE;
    } else {
        fl_heap_remove(&S->heap, ed);
    }
}

/* Evaluates queued upper bounds until the first of the queue is a priority:
 * then it is the largest priority of all (each bound is at least its
 * edge's priority), and the pops follow the same order as if every edge
 * had been evaluated at once. */
static void settle(simp *S) {
    while (fl_heap_size(&S->heap) && !S->oom) {
        uint32_t t = fl_heap_top(&S->heap);
        if (!(S->edge[t].state & E_STALE)) return;
        STAT(settles);
        update_edge(S, t, 1);
    }
}

/* After a collapse into slot k, every edge at k or at a vertex of its ring
 * (method-notes: their collapses would create triangles containing k). */
static void ring_eval(simp *S, size_t n);

static int reevaluate_ring(simp *S, uint32_t k) {
    uint32_t vm = next_stamp(S);
    size_t ne = 0;
    const uint32_t *fk = S->refs + S->fstart[k];
    uint32_t nk = S->fcount[k];
    /* ring vertices first listed, k itself included */
    S->vmark[k] = vm;
    for (uint32_t m = 0; m <= nk; m++) {
        /* m == nk: k itself; else the corners of k's faces */
        uint32_t verts[3];
        int nvv;
        if (m == nk) {
            verts[0] = k;
            nvv = 1;
        } else {
            const uint32_t *t = S->face[fk[m]].v;
            nvv = 0;
            for (int c = 0; c < 3; c++)
                if (t[c] != k && S->vmark[t[c]] != vm) {
                    S->vmark[t[c]] = vm;
                    verts[nvv++] = t[c];
                }
        }
        for (int q = 0; q < nvv; q++) {
            uint32_t v = verts[q];
            const uint32_t *fl = S->refs + S->fstart[v];
            for (uint32_t a = 0; a < S->fcount[v]; a++) {
                uint32_t f = fl[a];
                const uint32_t *t = S->face[f].v;
                int bad = S->phase == 0 && face_is_bad(S, f);
                for (int c = 0; c < 3; c++) {
                    if (t[c] != v && t[(c + 1) % 3] != v) continue;
                    uint32_t ed = S->tedge[3 * (size_t)f + c];
                    if (S->emark[ed] != vm) {
                        S->emark[ed] = vm;
                        if (!buf_reserve((void **)&S->sc.ebuf, &S->sc.ebuf_cap, 2 * (ne + 1), sizeof *S->sc.ebuf))
                            return 0;
                        S->sc.ebuf[2 * ne] = ed;
                        S->sc.ebuf[2 * ne + 1] = (uint32_t)bad;
                        ne++;
                    } else if (bad) {
                        for (size_t x = ne; x-- > 0;)
                            if (S->sc.ebuf[2 * x] == ed) {
                                S->sc.ebuf[2 * x + 1] = 1;
                                break;
                            }
                    }
                }
            }
        }
    }
    /* what each listed edge needs; the evaluations (independent of one
     * another: each writes only its own edge's cache) may run on two
     * threads (ring_eval), the queue is then updated in list order as one
     * thread would */
    enum { RK_SKIP, RK_BOUND, RK_REMOVE, RK_EVAL };
    if (!buf_reserve((void **)&S->rkind, &S->rkind_cap, ne + 1, 1) ||
        !buf_reserve((void **)&S->rlist, &S->rlist_cap, ne + 1, sizeof *S->rlist) ||
        !buf_reserve((void **)&S->rrho, &S->rrho_cap, ne + 1, sizeof *S->rrho) ||
        !buf_reserve((void **)&S->rtol, &S->rtol_cap, ne + 1, 1))
        return 0;
    size_t nev = 0;
    for (size_t x = 0; x < ne; x++) {
        uint32_t ed = S->sc.ebuf[2 * x];
        uint8_t kind = S->phase == 1 || S->sc.ebuf[2 * x + 1] ? RK_EVAL : RK_REMOVE;
        if (S->edge[ed].v[0] == k || S->edge[ed].v[1] == k) S->edge[ed].state &= (uint8_t)~E_OPT;
        else if (S->phase == 1) {
            /* An edge away from k keeps its endpoints, hence its candidates
             * and their quadric errors: one that failed C1 alone still does. */
            if (S->edge[ed].state & E_TOLFAIL) {
                STAT(skipped);
                kind = RK_SKIP;
            } else if (FEMLOD_SIMPLIFY_BOUND) {
                /* Exact lazy: an upper bound now, the priority when the
                 * bound reaches the top of the queue (settle). */
                kind = RK_BOUND;
            }
        }
        if (kind == RK_EVAL && (S->edge[ed].flag & E_DEAD)) kind = RK_SKIP; /* as update_edge */
        S->rkind[x] = kind;
        if (kind == RK_EVAL) S->rlist[nev++] = ed;
    }
    ring_eval(S, nev);
    if (S->oom) return 0;
    nev = 0;
    for (size_t x = 0; x < ne; x++) {
        uint32_t ed = S->sc.ebuf[2 * x];
        switch (S->rkind[x]) {
        case RK_BOUND:
            bound_update(S, ed, k);
            break;
        case RK_REMOVE:
            update_edge(S, ed, 0);
            break;
        case RK_EVAL: {
            double rho = S->rrho[nev];
            S->edge[ed].state = (uint8_t)((S->edge[ed].state & ~(E_TOLFAIL | E_STALE)) | (S->rtol[nev] ? E_TOLFAIL : 0));
            if (rho >= 0.0) fl_heap_set(&S->heap, ed, rho);
            else fl_heap_remove(&S->heap, ed);
            nev++;
            break;
        }
        default:
            break;
        }
    }
    return 1;
}

/* Evaluates every live edge (phase 1 start and the final retry), or in the
 * pre-phase every edge of a triangle below min_stretch. Returns how many
 * entered the queue. */
/* Also polls the progress callback (with the fraction done so far) every
 * 65,536 edges: on a big mesh this pass takes seconds, and a time cap or a
 * user's cancel must reach it (the result does not depend on the polls). */
static int eval_range(simp *S, size_t e0, size_t e1);

static size_t evaluate_all(simp *S, const femlod_simplify_options *o, double done) {
    size_t n = 0;
    /* in chunks of 65,536 edges: evaluated on the run's threads into
     * S->rrho / S->rtol (rkind: 1 when the edge is to be evaluated), then
     * queued in edge order, as one thread would */
    for (size_t e0 = 0; e0 < S->ne; e0 += 0x10000u) {
        size_t e1 = e0 + 0x10000u < S->ne ? e0 + 0x10000u : S->ne;
        if (e0 && o->progress && o->progress(o->progress_payload, done)) {
            S->cancelled = 1;
            return n;
        }
        if (!eval_range(S, e0, e1)) {
            S->oom = 1;
            return n;
        }
        for (size_t ed = e0; ed < e1; ed++) {
            size_t x = ed - e0;
            if (!S->rkind[x]) continue;
            double rho = S->rrho[x];
            S->edge[ed].state = (uint8_t)((S->edge[ed].state & ~(E_TOLFAIL | E_STALE)) | (S->rtol[x] ? E_TOLFAIL : 0));
            if (rho >= 0.0) {
                fl_heap_set(&S->heap, (uint32_t)ed, rho);
                n++;
            } else {
                fl_heap_remove(&S->heap, (uint32_t)ed);
            }
        }
    }
    return n;
}

/* Whether evaluate_all evaluates edge ed: live, not queued, and in the
 * pre-phase on a triangle below min_stretch. */
static int eval_wanted(const simp *S, size_t ed) {
    if (S->edge[ed].flag & E_DEAD) return 0;
    if (fl_heap_contains(&S->heap, (uint32_t)ed)) return 0;
    if (S->phase != 0) return 1;
    uint32_t v = S->edge[ed].v[0];
    const uint32_t *fl = S->refs + S->fstart[v];
    for (uint32_t a = 0; a < S->fcount[v]; a++) {
        const uint32_t *te = S->tedge + 3 * (size_t)fl[a];
        if ((te[0] == ed || te[1] == ed || te[2] == ed) && face_is_bad(S, fl[a])) return 1;
    }
    return 0;
}

/* }====== */

/* {====== setup: defaults, connectivity, features, quadrics */

typedef struct erec {
    uint32_t other, face, side;
} erec;

static int erec_less(const erec *x, const erec *y) {
    if (x->other != y->other) return x->other < y->other;
    if (x->face != y->face) return x->face < y->face;
    return x->side < y->side;
}

/* The per-thread part: the ring and the check buffers. */
static void ring_free(ring *R) {
    free(R->face);
    free(R->a);
    free(R->b);
    free(R->from_j);
    free(R->lab);
    free(R->lab2);
}

static void simp_free_scratch(simp *S) {
    ring_free(&S->R);
    ring_free(&S->R2);
    free(S->sc.ebuf);
    free(S->sc.pbuf);
    free(S->sc.pdst);
    free(S->sc.newcone);
    free(S->sc.tbox);
    free(S->sc.obox);
    free(S->sc.tplane);
    free(S->sc.cert);
}

/* A worker's view of the run (band_par): the run's state with w's own
 * scratch kept. */
static void simp_view(simp *w, const simp *S) {
    ring R = w->R, R2 = w->R2;
    scratch sc = w->sc;
    memcpy(w, S, offsetof(simp, vstars));
    w->phase = S->phase;
    w->fast = S->fast;
    w->vlock = S->vlock;
    w->vbest = S->vbest;
    w->pass = S->pass;
    w->nthreads = 1;
    w->par = 0;
    w->slab_ax = S->slab_ax;
    w->slab = S->slab;
    w->slab_w = S->slab_w;
    w->slab_shift = S->slab_shift;
    w->log = S->log;
    w->collapses = S->collapses;
    w->prephase = S->prephase;
    w->swept = 0;
    w->oom = 0; /* rejected: w's own count goes on */
    w->cancelled = 0;
    w->R = R;
    w->R2 = R2;
    w->sc = sc;
}

static void par_ctx_free(struct par_ctx *X);

static void simp_free(simp *S) {
    par_ctx_free(S->ectx);
    free(S->rlist);
    free(S->rkind);
    free(S->rtol);
    free(S->rrho);
    free(S->slot_of);
    free(S->pos);
    free(S->q);
    free(S->node);
    free(S->fstart);
    free(S->fcount);
    free(S->val);
    free(S->vflag);
    free(S->fdeg);
    free(S->vmark);
    free(S->vlock);
    free(S->vbest);
    free(S->refs);
    free(S->face);
    free(S->fin);
    free(S->tedge);
    free(S->fsz);
    free(S->cone);
    free(S->fmark);
    free(S->fmade);
    free(S->fpt);
    free(S->pnext);
    free(S->ev);
    free(S->enf);
    free(S->edge);
    free(S->emark);
    free(S->ehint);
    free(S->eopt);
    fl_heap_free(&S->heap);
    fl_grid_free(&S->grid);
    simp_free_scratch(S);
}

static int bad_number(double x) { return isnan(x) || isinf(x); }

/* Resolves the options (zero: default, negative: off). */
static femlod_status resolve_options(simp *S, const femlod_simplify_options *o, size_t nt, double diag,
                                     double mean_edge, double size_max, femlod_error *err) {
    if (bad_number(o->ratio) || bad_number(o->tolerance) || bad_number(o->max_deviation) ||
        bad_number(o->min_stretch) || bad_number(o->max_size) || bad_number(o->feature_angle) ||
        bad_number(o->feature_weight) || bad_number(o->max_normal_change))
        return fl_error(err, FEMLOD_EINPUT, "simplify: options must be finite numbers");
    if (o->target && o->ratio != 0.0)
        return fl_error(err, FEMLOD_EINPUT, "simplify: give target or ratio, not both");
    if (o->ratio < 0.0 || o->ratio > 1.0)
        return fl_error(err, FEMLOD_EINPUT, "simplify: ratio %g is outside (0, 1]", o->ratio);
    if (o->min_stretch > 1.0)
        return fl_error(err, FEMLOD_EINPUT, "simplify: min_stretch %g is above 1", o->min_stretch);
    if (o->max_valence > 0 && o->max_valence < 3)
        return fl_error(err, FEMLOD_EINPUT, "simplify: max_valence %d is below 3", o->max_valence);
    if (o->feature_angle > 180.0 || o->max_normal_change > 180.0)
        return fl_error(err, FEMLOD_EINPUT, "simplify: angles are degrees in [0, 180]");
    if (bad_number(o->fast_above) || (o->fast_above > 0.0 && o->fast_above < 1.0))
        return fl_error(err, FEMLOD_EINPUT, "simplify: fast_above %g is not a factor >= 1", o->fast_above);
    S->fast = o->fast_above >= 1.0 ? o->fast_above : 0.0;
    if (o->threads < 0) return fl_error(err, FEMLOD_EINPUT, "simplify: threads %d is negative", o->threads);
    S->nthreads = o->threads;
    if (S->nthreads == 0) {
        long np = sysconf(_SC_NPROCESSORS_ONLN);
        S->nthreads = np < 1 ? 1 : (np > 16 ? 16 : (int)np);
    }
    if (S->nthreads > 16) S->nthreads = 16;
    S->target = o->target;
    if (o->ratio > 0.0) S->target = (size_t)floor(o->ratio * (double)nt + 0.5);

    /* C1: the default is scale-aware: docs/simplify.md "Defaults" */
    S->tol_on = o->tolerance >= 0.0;
    S->tol = o->tolerance > 0.0 ? o->tolerance : FEMLOD_SIMPLIFY_DEFAULT_TOLERANCE * mean_edge * mean_edge;
    S->dev_on = o->max_deviation > 0.0;
    S->maxdev = o->max_deviation;
    S->maxdev2 = S->maxdev * S->maxdev;
    S->st_on = o->min_stretch >= 0.0;
    S->minst = o->min_stretch > 0.0 ? o->min_stretch : 0.2;
    if (!S->st_on) S->minst = 0.0;
    S->minst2 = S->minst * S->minst;
    S->sz_on = o->max_size >= 0.0;
    S->maxsz = o->max_size > 0.0 ? o->max_size : mx(0.1 * diag, 2.0 * size_max);
    S->maxsz2 = S->maxsz * S->maxsz;
    S->val_on = o->max_valence >= 0;
    S->maxval = o->max_valence > 0 ? o->max_valence : 12;
    S->feat_angle = o->feature_angle > 0.0 ? o->feature_angle : (o->feature_angle < 0.0 ? -1.0 : 40.0);
    S->feat_w = o->feature_weight > 0.0 ? o->feature_weight : (o->feature_weight < 0.0 ? 0.0 : 2.0);
    S->cone_on = o->max_normal_change >= 0.0;
    S->max_nc = o->max_normal_change > 0.0 ? o->max_normal_change : 60.0;
    if (S->cone_on) {
        S->cos_nc = cos(S->max_nc * PI / 180.0);
        S->cos_nc2 = S->cos_nc * S->cos_nc;
    } else {
        S->cos_nc = 0.0; /* flips only */
        S->cos_nc2 = 0.0;
    }
    S->lim_sz2 = S->sz_on ? S->maxsz2 : __builtin_inf();
    S->lim_turn2 = S->cos_nc > 0.0 ? S->cos_nc2 : 0.0; /* d^2 < 0 never holds */
    S->lim_st2 = -1.0;                                 /* set per phase */
    S->keep_boundary = o->keep_boundary != 0;
    S->area_w = o->area_weighted != 0;
    (void)mean_edge;
    return FEMLOD_OK;
}

/* {====== set-up in parallel: maps over index ranges
 *
 * The set-up's per-face and per-vertex loops (face caches, quadrics,
 * Morton keys) write only what their index owns, reading what no part
 * writes; cut into contiguous ranges, one per thread, they give the same
 * bytes for any thread count. */


typedef struct range_job {
    void *ctx;
    range_fn fn;
    size_t lo, hi;
    int part;
    pthread_t th;
} range_job;

static void *range_main(void *arg) {
    range_job *j = arg;
    j->fn(j->ctx, j->lo, j->hi, j->part);
    return NULL;
}

/* The parts par_ranges cuts [0, n) into: part t is [n t / parts, n (t + 1) / parts). */
static int par_parts(int nth, size_t n) {
    if (nth > 16) nth = 16;
    return nth < 2 || n < 32768 ? 1 : nth;
}

static size_t par_part_lo(size_t n, int parts, int t) { return n * (size_t)t / (size_t)parts; }

/* fn over [0, n) in par_parts(nth, n) parts, one per thread (this one
 * included); a thread that cannot start has its part done here. */
static void par_ranges(int nth, size_t n, range_fn fn, void *ctx) {
    range_job job[16];
    int started[16] = {0};
    int parts = par_parts(nth, n);
    for (int t = 0; t < parts; t++) {
        job[t].ctx = ctx;
        job[t].fn = fn;
        job[t].lo = par_part_lo(n, parts, t);
        job[t].hi = par_part_lo(n, parts, t + 1);
        job[t].part = t;
    }
    for (int t = 1; t < parts; t++) started[t] = pthread_create(&job[t].th, NULL, range_main, &job[t]) == 0;
    fn(ctx, job[0].lo, job[0].hi, 0);
    for (int t = 1; t < parts; t++) {
        if (started[t]) pthread_join(job[t].th, NULL);
        else fn(ctx, job[t].lo, job[t].hi, t);
    }
}

/* }====== */

static uint64_t spread21(uint32_t x) {
    uint64_t v = x & 0x1fffff;
    v = (v | v << 32) & 0x1f00000000ffffull;
    v = (v | v << 16) & 0x1f0000ff0000ffull;
    v = (v | v << 8) & 0x100f00f00f00f00full;
    v = (v | v << 4) & 0x10c30c30c30c30c3ull;
    v = (v | v << 2) & 0x1249249249249249ull;
    return v;
}

typedef struct mkey {
    uint64_t key;
    uint32_t id;
} mkey;

static int cmp_mkey(const void *a, const void *b) {
    const mkey *x = a, *y = b;
    if (x->key != y->key) return x->key < y->key ? -1 : 1;
    return (x->id > y->id) - (x->id < y->id);
}

typedef struct morton_ctx {
    const double *pos;
    mkey *k;
    double lo[3], sc;
} morton_ctx;

static void morton_keys(void *arg, size_t v0, size_t v1, int part) {
    (void)part;
    const morton_ctx *m = arg;
    for (size_t v = v0; v < v1; v++) {
        uint64_t code = 0;
        for (int c = 0; c < 3; c++) code |= spread21((uint32_t)((m->pos[3 * v + c] - m->lo[c]) * m->sc)) << c;
        m->k[v].key = code;
        m->k[v].id = (uint32_t)v;
    }
}

/* perm[s] = the input vertex of slot s, sorted by (Morton code, index):
 * a stable radix sort of the codes, 11 bits a pass (a pass whose digit is
 * the same everywhere is skipped), from index order. Returns the inverse
 * (input -> slot), NULL on ENOMEM. */
static uint32_t *morton_slots(const double *pos, size_t nv, uint32_t *perm, int nth) {
    /* all written whole: mapped at once (fl_populate) */
    mkey *k = fl_populate(fl_alloc(nv, sizeof *k), nv * sizeof *k);
    mkey *k2 = fl_populate(fl_alloc(nv, sizeof *k2), nv * sizeof *k2);
    uint32_t *inv = fl_populate(fl_alloc(nv, sizeof *inv), nv * sizeof *inv);
    if (!k || !k2 || !inv) {
        free(k);
        free(k2);
        free(inv);
        return NULL;
    }
    morton_ctx m = {pos, k, {__builtin_inf(), __builtin_inf(), __builtin_inf()}, 0.0};
    double hi[3];
    for (int c = 0; c < 3; c++) hi[c] = -m.lo[c];
    for (size_t v = 0; v < nv; v++)
        for (int c = 0; c < 3; c++) {
            m.lo[c] = mn(m.lo[c], pos[3 * v + c]);
            hi[c] = mx(hi[c], pos[3 * v + c]);
        }
    double ext = mx(hi[0] - m.lo[0], mx(hi[1] - m.lo[1], hi[2] - m.lo[2]));
    m.sc = ext > 0.0 ? 2097151.0 / ext : 0.0;
    par_ranges(nth, nv, morton_keys, &m);
    enum { RB = 11 }; /* digit bits: 6 passes cover the 63-bit codes */
    for (int shift = 0; shift < 64; shift += RB) {
        size_t cnt[(1 << RB) + 1] = {0};
        const uint64_t dm = (1u << RB) - 1;
        for (size_t v = 0; v < nv; v++) cnt[((k[v].key >> shift) & dm) + 1]++;
        int one = 0;
        for (int d = 1; d <= 1 << RB; d++) one |= cnt[d] == nv;
        if (one) continue;
        for (int d = 0; d < 1 << RB; d++) cnt[d + 1] += cnt[d];
        for (size_t v = 0; v < nv; v++) k2[cnt[(k[v].key >> shift) & dm]++] = k[v];
        mkey *x = k;
        k = k2;
        k2 = x;
    }
    for (size_t s = 0; s < nv; s++) {
        perm[s] = k[s].id;
        inv[k[s].id] = (uint32_t)s;
    }
    free(k);
    free(k2);
    return inv;
}

static void face_cache_range(void *arg, size_t f0, size_t f1, int part) {
    (void)part;
    simp *S = arg;
    for (size_t f = f0; f < f1; f++) face_update_cache(S, (uint32_t)f);
}

/* Whether the faces around v form one fan (flooded from the first face
 * through edges at v); mark: cnt bytes of scratch, or NULL for the shared
 * face marks (stamps). */
#ifndef FEMLOD_SIMPLIFY_PINCH_LOCAL
#define FEMLOD_SIMPLIFY_PINCH_LOCAL 256 /* tests/CMakeLists.txt sets 2: nearly every vertex takes the shared marks */
#endif
#define PINCH_LOCAL FEMLOD_SIMPLIFY_PINCH_LOCAL
static int fan_is_one(simp *S, uint32_t v, uint8_t *mark) {
    uint32_t cnt = S->fcount[v];
    const uint32_t *fl = S->refs + S->fstart[v];
    uint32_t mk = mark ? 1u : next_stamp(S);
#define FAN_MARKED(m) (mark ? mark[m] != 0 : S->fmark[fl[m]] == mk)
#define FAN_MARK(m) (mark ? (void)(mark[m] = 1) : (void)(S->fmark[fl[m]] = mk))
    if (mark) memset(mark, 0, cnt);
    uint32_t reached = 1, changed = 1;
    FAN_MARK(0);
    while (changed) {
        changed = 0;
        for (uint32_t m = 0; m < cnt; m++) {
            if (FAN_MARKED(m)) continue;
            const uint32_t *te = S->tedge + 3 * (size_t)fl[m];
            for (uint32_t w = 0; w < cnt && !FAN_MARKED(m); w++) {
                if (!FAN_MARKED(w)) continue;
                const uint32_t *tw = S->tedge + 3 * (size_t)fl[w];
                for (int x = 0; x < 3; x++)
                    for (int y = 0; y < 3; y++)
                        if (te[x] == tw[y] && (S->edge[te[x]].v[0] == v || S->edge[te[x]].v[1] == v)) {
                            FAN_MARK(m);
                            x = y = 3;
                        }
            }
            if (FAN_MARKED(m)) {
                reached++;
                changed = 1;
            }
        }
    }
#undef FAN_MARKED
#undef FAN_MARK
    return reached == cnt;
}

static void pinched_range(void *arg, size_t v0, size_t v1, int part) {
    (void)part;
    simp *S = arg;
    uint8_t mark[PINCH_LOCAL];
    for (size_t v = v0; v < v1; v++) {
        uint32_t cnt = S->fcount[v];
        if (cnt == 0 || cnt > PINCH_LOCAL || (S->vflag[v] & V_NONMANIFOLD)) continue;
        if (!fan_is_one(S, (uint32_t)v, mark)) S->vflag[v] |= V_NONMANIFOLD;
    }
}

/* An edge's sharpness: 1 at a boundary or non-manifold edge, (1 - cos)/2
 * where its two faces' normals part by more than the feature angle, else
 * 0 (not a feature). */
static double edge_sharpness(const simp *S, uint32_t e, double cos_feat) {
    if (S->edge[e].nf != 2) return 1.0;
    if (!(S->feat_angle > 0.0)) return 0.0;
    uint32_t a = S->edge[e].v[0];
    /* the two faces: scan a's list */
    const uint32_t *fl = S->refs + S->fstart[a];
    uint32_t f2[2], n2 = 0;
    for (uint32_t m = 0; m < S->fcount[a] && n2 < 2; m++) {
        const uint32_t *te = S->tedge + 3 * (size_t)fl[m];
        if (te[0] == e || te[1] == e || te[2] == e) f2[n2++] = fl[m];
    }
    if (n2 != 2) return 0.0;
    const float *x = S->face[f2[0]].n, *y = S->face[f2[1]].n;
    /* a degenerate face (NaN normal) counts as normal 0: c = 0 */
    double c = isnan(x[0]) || isnan(y[0]) ? 0.0 : (double)x[0] * y[0] + (double)x[1] * y[1] + (double)x[2] * y[2];
    return c < cos_feat ? 0.5 * (1.0 - c) : 0.0;
}

typedef struct feat_ctx {
    simp *S;
    double cos_feat;
} feat_ctx;

static void feature_range(void *arg, size_t e0, size_t e1, int part) {
    (void)part;
    feat_ctx *C = arg;
    for (size_t e = e0; e < e1; e++)
        if (edge_sharpness(C->S, (uint32_t)e, C->cos_feat) > 0.0) C->S->edge[e].flag |= E_FEATURE;
}

/* The face-plane quadrics (4.1 (2)-(4)), gathered per vertex over its
 * faces in increasing face order: the sums of a face-order scatter, in
 * the same order, so the same bits. With area weights, renormalised per
 * vertex (method-notes) so that tolerance keeps its units. */
static void plane_quadrics(void *arg, size_t v0, size_t v1, int part) {
    (void)part;
    simp *S = arg;
    for (size_t v = v0; v < v1; v++) {
        const uint32_t *fl = S->refs + S->fstart[v];
        double area = 0.0;
        for (uint32_t m = 0; m < S->fcount[v]; m++) {
            const uint32_t *t = S->face[fl[m]].v;
            /* the float cache is for checks; the quadric gets the exact normal */
            double e1[3], e2[3], nn[3], n[3];
            sub3(e1, P(S, t[1]), P(S, t[0]));
            sub3(e2, P(S, t[2]), P(S, t[0]));
            cross3(nn, e1, e2);
            double l = sqrt(dot3(nn, nn));
            if (!(l > 0.0)) continue;
            for (int k = 0; k < 3; k++) n[k] = nn[k] / l;
            double w = S->area_w ? 0.5 * l : 1.0;
            fl_quadric_add_plane(S->q + v, n, P(S, t[0]), w);
            area += w;
        }
        if (S->area_w && area > 0.0) fl_quadric_scale(S->q + v, (double)S->fcount[v] / area);
    }
}

/* The edge table in parts: part t numbers the edges of its vertices from
 * 0 (a's sides towards larger neighbours b, in increasing (a, b) order;
 * tedge gets these local ids) into its own region of S->ev and S->enf,
 * which starts at at[t] (at most 2 edges per face at a vertex: the
 * regions cannot overlap), and counts valences; then the regions are
 * moved down end to end (off[t]) and edge_renumber adds each side's part
 * offset: the numbering of one sequential pass over the vertices, in the
 * memory of one table (the unused tail is given back). */
typedef struct edge_ctx {
    simp *S;
    int parts;
    size_t at[16], cap[16], n[16], off[16];
    size_t misoriented[16]; /* interior edges whose two faces run the same way */
} edge_ctx;

static void edge_part(void *arg, size_t a0, size_t a1, int part) {
    edge_ctx *E = arg;
    simp *S = E->S;
    uint32_t *ev = S->ev + 2 * E->at[part];
    uint16_t *enf = S->enf + E->at[part];
    size_t ne = 0;
    /* a closed manifold part writes a quarter of its room (1.5 edges per
     * face, 6 sides per face reserved): that much is mapped at once, the
     * rest (other meshes) faults as it is written */
    size_t likely = E->cap[part] / 4 + E->cap[part] / 32;
    fl_populate(ev, likely * 2 * sizeof *ev);
    fl_populate(enf, likely * sizeof *enf);
    for (size_t a = a0; a < a1; a++) {
        size_t nrec = 0, nnb = 0;
        const uint32_t *fl = S->refs + S->fstart[a];
        uint32_t cnt = S->fcount[a];
        /* a few dozen sides at most in a mesh; a star of more than 256
         * faces takes the heap */
        erec rec_s[512], *rec = rec_s;
        uint32_t nb_s[512], *nb = nb_s;
        if (cnt > 256) {
            rec = fl_alloc(2 * (size_t)cnt, sizeof *rec);
            nb = fl_alloc(2 * (size_t)cnt, sizeof *nb);
            if (!rec || !nb) {
                free(rec);
                free(nb);
                E->n[part] = SIZE_MAX;
                return;
            }
        }
        for (uint32_t m = 0; m < cnt; m++) {
            uint32_t f = fl[m];
            const uint32_t *t = S->face[f].v;
            int c = t[0] == a ? 0 : (t[1] == a ? 1 : 2);
            int sides[2] = {c, (c + 2) % 3};
            uint32_t others[2] = {t[(c + 1) % 3], t[(c + 2) % 3]};
            for (int q = 0; q < 2; q++) {
                nb[nnb++] = others[q];
                if (others[q] > a) {
                    erec r = {others[q], f, (uint32_t)sides[q]};
                    size_t x = nrec++;
                    while (x > 0 && erec_less(&r, &rec[x - 1])) {
                        rec[x] = rec[x - 1];
                        x--;
                    }
                    rec[x] = r;
                }
            }
        }
        /* valence: distinct neighbours */
        fl_sort_u32(nb, nnb);
        uint32_t val = 0;
        for (size_t x = 0; x < nnb; x++)
            if (x == 0 || nb[x] != nb[x - 1]) val++;
        S->val[a] = val;
        for (size_t x = 0; x < nrec;) {
            size_t y = x;
            while (y < nrec && rec[y].other == rec[x].other) y++;
            ev[2 * ne] = (uint32_t)a;
            ev[2 * ne + 1] = rec[x].other;
            enf[ne] = (uint16_t)(y - x > 65535 ? 65535 : y - x);
            /* the side runs a -> other when a is its first corner */
            if (y - x == 2 && (S->face[rec[x].face].v[rec[x].side] == a) ==
                                  (S->face[rec[x + 1].face].v[rec[x + 1].side] == a))
                E->misoriented[part]++;
            for (size_t z = x; z < y; z++) S->tedge[3 * (size_t)rec[z].face + rec[z].side] = (uint32_t)ne;
            ne++;
            x = y;
        }
        if (rec != rec_s) {
            free(rec);
            free(nb);
        }
    }
    E->n[part] = ne;
}

static void edge_renumber(void *arg, size_t f0, size_t f1, int part) {
    edge_ctx *E = arg;
    simp *S = E->S;
    size_t nv = S->nv;
    (void)part;
    for (size_t f = f0; f < f1; f++) {
        const uint32_t *t = S->face[f].v;
        for (int c = 0; c < 3; c++) {
            uint32_t a = t[c] < t[(c + 1) % 3] ? t[c] : t[(c + 1) % 3];
            int p = 0;
            while (p + 1 < E->parts && a >= par_part_lo(nv, E->parts, p + 1)) p++;
            S->tedge[3 * f + c] += (uint32_t)E->off[p];
        }
    }
}

/* The set-up's face maps (docs/design.md "The set-up in parallel parts").
 * Those that write per vertex (counts, the sort's scatter, the face
 * lists) run in vertex parts, each part scanning every face in order and
 * taking the corners in its own range: its writes are those of one
 * sequential pass, in the same order, and the scans stream. */
typedef struct fmap_ctx {
    simp *S;
    const femlod_mesh *mesh;
    const uint32_t *slot_of;
    uint32_t *fin0, *tmp, *cnt;
    size_t nf[16]; /* faces kept per part of the input faces, then their offsets */
} fmap_ctx;

static inline int tri_degenerate(const uint32_t *t) { return t[0] == t[1] || t[1] == t[2] || t[0] == t[2]; }

static void pos_gather(void *arg, size_t s0, size_t s1, int part) {
    (void)part;
    fmap_ctx *C = arg;
    simp *S = C->S;
    for (size_t s = s0; s < s1; s++) memcpy(S->pos + 3 * s, C->mesh->pos + 3 * (size_t)S->node[s], 3 * sizeof(double));
}

static void faces_kept(void *arg, size_t f0, size_t f1, int part) {
    fmap_ctx *C = arg;
    size_t n = 0;
    for (size_t f = f0; f < f1; f++) n += !tri_degenerate(C->mesh->tri + 3 * f);
    C->nf[part] = n;
}

/* the kept input faces in slots, and their input indices (fin0) */
static void faces_copy(void *arg, size_t f0, size_t f1, int part) {
    fmap_ctx *C = arg;
    simp *S = C->S;
    size_t w = C->nf[part];
    for (size_t f = f0; f < f1; f++) {
        const uint32_t *t = C->mesh->tri + 3 * f;
        if (tri_degenerate(t)) continue;
        for (int c = 0; c < 3; c++) S->face[w].v[c] = C->slot_of[t[c]];
        C->fin0[w++] = (uint32_t)f;
    }
}

/* fcount, and cnt[v + 1]: the faces whose least corner is v */
static void faces_count(void *arg, size_t v0, size_t v1, int part) {
    (void)part;
    fmap_ctx *C = arg;
    simp *S = C->S;
    for (size_t f = 0; f < S->nt; f++) {
        const uint32_t *t = S->face[f].v;
        for (int c = 0; c < 3; c++)
            if (t[c] >= v0 && t[c] < v1) S->fcount[t[c]]++;
        uint32_t m = min3u(t);
        if (m >= v0 && m < v1) C->cnt[m + 1]++;
    }
}

/* the stable counting sort's scatter into tmp and fin */
static void faces_scatter(void *arg, size_t v0, size_t v1, int part) {
    (void)part;
    fmap_ctx *C = arg;
    simp *S = C->S;
    for (size_t f = 0; f < S->nt; f++) {
        const uint32_t *t = S->face[f].v;
        uint32_t m = min3u(t);
        if (m < v0 || m >= v1) continue;
        uint32_t d = C->cnt[m]++;
        memcpy(C->tmp + 3 * (size_t)d, t, 3 * sizeof *t);
        S->fin[d] = C->fin0[f];
    }
}

static void faces_back(void *arg, size_t f0, size_t f1, int part) {
    (void)part;
    fmap_ctx *C = arg;
    for (size_t f = f0; f < f1; f++) memcpy(C->S->face[f].v, C->tmp + 3 * f, 3 * sizeof *C->tmp);
}

/* vertex -> faces, in increasing face order */
static void faces_refs(void *arg, size_t v0, size_t v1, int part) {
    (void)part;
    fmap_ctx *C = arg;
    simp *S = C->S;
    for (size_t f = 0; f < S->nt; f++)
        for (int c = 0; c < 3; c++) {
            uint32_t v = S->face[f].v[c];
            if (v >= v0 && v < v1) S->refs[S->fstart[v] + S->fcount[v]++] = (uint32_t)f;
        }
}

static void edge_records(void *arg, size_t e0, size_t e1, int part) {
    (void)part;
    simp *S = arg;
    size_t ne = S->ne;
    for (size_t e = e0; e < e1; e++) {
        S->edge[e].key = -1.0f;
        S->edge[e].nf = e < ne ? S->enf[e] : 0;
        S->edge[e].flag = S->edge[e].state = 0;
        S->edge[e].v[0] = e < ne ? S->ev[2 * e] : 0;
        S->edge[e].v[1] = e < ne ? S->ev[2 * e + 1] : 0;
    }
}

static void cone_init(void *arg, size_t f0, size_t f1, int part) {
    (void)part;
    simp *S = arg;
    for (size_t f = f0; f < f1; f++) {
        memcpy(S->cone + 4 * f, S->face[f].n, 3 * sizeof(float));
        if (isnan(S->cone[4 * f])) S->cone[4 * f] = S->cone[4 * f + 1] = S->cone[4 * f + 2] = 0.0f;
        S->cone[4 * f + 3] = 0.0f;
    }
}

#if FEMLOD_SIMPLIFY_STATS
static double setup_t0;
/* the process's page faults so far (minor: first touches of fresh pages,
 * which cost 10-28 microseconds each on the VMs measured: error.c) */
static long minor_faults(void) {
    struct rusage u;
    getrusage(RUSAGE_SELF, &u);
    return u.ru_minflt;
}
#define SETUP_T(k) \
    (fprintf(stderr, "setup %d %.3f faults %ld\n", (k), now_seconds() - setup_t0, minor_faults()), (void)0)
#else
#define SETUP_T(k) ((void)0)
#endif
static femlod_status setup(simp *S, const femlod_mesh *mesh, const femlod_simplify_options *o,
                           size_t *dropped, femlod_error *err) {
#if FEMLOD_SIMPLIFY_STATS
    setup_t0 = now_seconds();
#endif
    size_t nv = mesh->nv, nt_in = mesh->nt;
    const uint32_t *tin = mesh->tri;
    S->nv = nv;
    S->pos0 = mesh->pos;
    size_t nt = 0;
    for (size_t f = 0; f < nt_in; f++) {
        const uint32_t *t = tin + 3 * f;
        if (t[0] != t[1] && t[1] != t[2] && t[0] != t[2]) nt++;
    }
    *dropped = nt_in - nt;
    S->nt = nt;
    S->nt_in = nt_in;
    S->live = nt;
    /* every array mapped at once (fl_populate: on the VMs measured, 90,000
     * first-touch faults took 0.9-1.3 s of this set-up on cover x4) */
#define ALLOC(p, n) (((p) = fl_populate(fl_alloc((n), sizeof *(p)), (n) * sizeof *(p))) != NULL)
#define CALLOC(p, n) (((p) = fl_populate(fl_calloc((n), sizeof *(p)), (n) * sizeof *(p))) != NULL)
    if (!ALLOC(S->pos, 3 * nv) || !CALLOC(S->q, nv) || !ALLOC(S->node, nv) || !ALLOC(S->fstart, nv + 1) ||
        !CALLOC(S->fcount, nv) || !CALLOC(S->val, nv) || !CALLOC(S->vflag, nv) || !CALLOC(S->fdeg, nv) ||
        !CALLOC(S->vmark, nv) || !(S->face = alloc_lines(nt, sizeof *S->face)) || !ALLOC(S->tedge, 3 * nt) ||
        !ALLOC(S->fsz, nt) || !CALLOC(S->fmark, nt) || !CALLOC(S->fmade, nt))
        return fl_error(err, FEMLOD_ENOMEM, "simplify: out of memory (%zu triangles)", nt_in);
    /* Vertex slots in Morton order of position: the neighbours of a vertex
     * then sit near it in memory, which halves the time on large meshes
     * (docs/simplify.md). Node ids stay the input indices. */
    SETUP_T(0);
    /* threads for the set-up's maps (resolve_options checks the option) */
    int nth = o->threads > 0 ? o->threads : 1;
    if (o->threads == 0) {
        long np = sysconf(_SC_NPROCESSORS_ONLN);
        nth = np < 1 ? 1 : (np > 16 ? 16 : (int)np);
    }
    uint32_t *slot_of = morton_slots(mesh->pos, nv, S->node, nth);
    S->slot_of = slot_of;
    if (!slot_of) return fl_error(err, FEMLOD_ENOMEM, "simplify: out of memory");
    /* Faces in the order of their least vertex slot (a stable counting
     * sort): the faces around a vertex then share cache lines too. fin
     * remembers each face's input index for the output order. */
    fmap_ctx C;
    memset(&C, 0, sizeof C);
    C.S = S;
    C.mesh = mesh;
    C.slot_of = slot_of;
    C.fin0 = fl_populate(fl_alloc(nt, sizeof *C.fin0), nt * sizeof *C.fin0);
    C.cnt = fl_populate(fl_calloc(nv + 1, sizeof *C.cnt), (nv + 1) * sizeof *C.cnt);
    C.tmp = fl_populate(fl_alloc(3 * nt, sizeof *C.tmp), 3 * nt * sizeof *C.tmp);
    if (!C.fin0 || !C.cnt || !C.tmp || !ALLOC(S->fin, nt)) {
        free(C.fin0);
        free(C.cnt);
        free(C.tmp);
        return fl_error(err, FEMLOD_ENOMEM, "simplify: out of memory");
    }
    par_ranges(nth, nv, pos_gather, &C);
    par_ranges(nth, nt_in, faces_kept, &C);
    size_t run = 0;
    for (int t = 0; t < par_parts(nth, nt_in); t++) {
        size_t n = C.nf[t];
        C.nf[t] = run;
        run += n;
    }
    par_ranges(nth, nt_in, faces_copy, &C);
    par_ranges(nth, nv, faces_count, &C);
    SETUP_T(1);
    for (size_t v = 0; v < nv; v++) C.cnt[v + 1] += C.cnt[v];
    par_ranges(nth, nv, faces_scatter, &C);
    par_ranges(nth, nt, faces_back, &C);
    free(C.cnt);
    free(C.tmp);
    free(C.fin0);
    size_t acc = 0;
    for (size_t v = 0; v < nv; v++) {
        S->fstart[v] = (uint32_t)acc;
        acc += S->fcount[v];
    }
    S->fstart[nv] = (uint32_t)acc;
    S->caprefs = acc + acc / 2 + 1024;
    /* the lists are mapped, their spare room faults when used */
    if (!(S->refs = fl_populate(fl_alloc(S->caprefs, sizeof *S->refs), acc * sizeof *S->refs)))
        return fl_error(err, FEMLOD_ENOMEM, "simplify: out of memory");
    S->nrefs = acc;
    memset(S->fcount, 0, nv * sizeof *S->fcount);
    par_ranges(nth, nv, faces_refs, &C);
    SETUP_T(2);
    par_ranges(nth, nt, face_cache_range, S);

    SETUP_T(3);
    /* edges, numbered in increasing (a, b) order: each vertex a lists its
     * sides towards larger neighbours b (edge_part, in parallel parts) */
    edge_ctx E;
    memset(&E, 0, sizeof E);
    E.S = S;
    E.parts = par_parts(nth, nv);
    size_t cap_e = 0;
    for (int t = 0; t < E.parts; t++) {
        E.at[t] = cap_e;
        size_t hi = par_part_lo(nv, E.parts, t + 1);
        for (size_t a = par_part_lo(nv, E.parts, t); a < hi; a++) cap_e += 2 * (size_t)S->fcount[a];
        E.cap[t] = cap_e - E.at[t];
    }
    /* sized for the worst case (two sides per face corner: four times the
     * edges of a closed mesh) and written in part: not mapped */
    if (!(S->ev = fl_alloc(2 * cap_e + 2, sizeof *S->ev)) || !(S->enf = fl_alloc(cap_e + 1, sizeof *S->enf)))
        return fl_error(err, FEMLOD_ENOMEM, "simplify: out of memory");
    par_ranges(nth, nv, edge_part, &E);
    size_t ne = 0;
    for (int t = 0; t < E.parts; t++) {
        if (E.n[t] == SIZE_MAX) return fl_error(err, FEMLOD_ENOMEM, "simplify: out of memory");
        E.off[t] = ne;
        if (t > 0 && E.n[t]) {
            memmove(S->ev + 2 * ne, S->ev + 2 * E.at[t], 2 * E.n[t] * sizeof *S->ev);
            memmove(S->enf + ne, S->enf + E.at[t], E.n[t] * sizeof *S->enf);
        }
        ne += E.n[t];
    }
    uint32_t *ev2 = fl_realloc(S->ev, 2 * ne + 2, sizeof *ev2);
    if (ev2) S->ev = ev2;
    uint16_t *enf2 = fl_realloc(S->enf, ne + 1, sizeof *enf2);
    if (enf2) S->enf = enf2;
    if (E.parts > 1) par_ranges(nth, nt, edge_renumber, &E);
    S->oriented = 1;
    for (int t = 0; t < E.parts; t++)
        if (E.misoriented[t]) S->oriented = 0;
    double elen = 0.0;
    for (size_t e = 0; e < ne; e++) elen += sqrt(dist2(P(S, S->ev[2 * e]), P(S, S->ev[2 * e + 1])));
    S->ne = ne;
    /* the edge marks are written by the exact queue's ring listing and the
     * marked scans only, after fast passes on a small part of the edges:
     * not mapped */
    if (!(S->edge = alloc_lines(ne + 1, sizeof *S->edge)) || !(S->emark = fl_calloc(ne + 1, sizeof *S->emark)) ||
        !ALLOC(S->eopt, 3 * ne + 3) ||
        (FEMLOD_SIMPLIFY_BOUND && !ALLOC(S->ehint, 2 * ne + 2)))
        return fl_error(err, FEMLOD_ENOMEM, "simplify: out of memory");
    if (FEMLOD_SIMPLIFY_BOUND) memset(S->ehint, 0xff, (2 * ne + 2) * sizeof *S->ehint);
    par_ranges(nth, ne + 1, edge_records, S);
    free(S->enf);
    S->enf = NULL;
    free(S->ev);
    S->ev = NULL;

    SETUP_T(4);
    double lo[3], hi[3];
    femlod_mesh_bbox(mesh, lo, hi);
    double diag = sqrt(dist2(lo, hi));
    double mean_edge = ne ? elen / (double)ne : 0.0;
    double size_max = 0.0;
    for (size_t f = 0; f < nt; f++) size_max = mx(size_max, (double)S->fsz[f]);
    femlod_status st = resolve_options(S, o, nt_in, diag, mean_edge, size_max, err);
    if (st != FEMLOD_OK) return st;
    S->eps = 1e-10 * (diag > 0 ? diag : 1.0);

    SETUP_T(5);
    /* boundary and non-manifold edges */
    for (size_t e = 0; e < ne; e++) {
        uint32_t a = S->edge[e].v[0], b = S->edge[e].v[1];
        if (S->edge[e].nf == 1) {
            S->vflag[a] |= V_BOUNDARY;
            S->vflag[b] |= V_BOUNDARY;
        } else if (S->edge[e].nf > 2) {
            S->vflag[a] |= V_NONMANIFOLD;
            S->vflag[b] |= V_NONMANIFOLD;
        }
    }
    /* pinched vertices: more than one fan of faces around them (in
     * parallel, each vertex's flood in its own marks; the rare vertex of
     * more than PINCH_LOCAL faces afterwards, with the shared ones) */
    par_ranges(nth, nv, pinched_range, S);
    for (size_t v = 0; v < nv; v++)
        if (S->fcount[v] > PINCH_LOCAL && !(S->vflag[v] & V_NONMANIFOLD) && !fan_is_one(S, (uint32_t)v, NULL))
            S->vflag[v] |= V_NONMANIFOLD;
    memset(S->fmark, 0, nt * sizeof *S->fmark);
    S->stamp = 0;
    memset(S->vmark, 0, nv * sizeof *S->vmark);

    SETUP_T(6);
    par_ranges(nth, nv, plane_quadrics, S);
    SETUP_T(7);
    /* features (in parallel, per edge) and line quadrics, weighted by
     * sharpness (in edge order: the same sums as one pass; the sharpness of
     * the few feature edges is computed again here rather than kept in a
     * per-edge array for all of them) */
    feat_ctx FC = {S, S->feat_angle > 0.0 ? cos(S->feat_angle * PI / 180.0) : -2.0};
    par_ranges(nth, ne, feature_range, &FC);
    for (size_t e = 0; e < ne; e++) {
        if (!(S->edge[e].flag & E_FEATURE)) continue;
        uint32_t a = S->edge[e].v[0], b = S->edge[e].v[1];
        double sharp = edge_sharpness(S, (uint32_t)e, FC.cos_feat);
        if (S->fdeg[a] < 255) S->fdeg[a]++;
        if (S->fdeg[b] < 255) S->fdeg[b]++;
        if (S->feat_w > 0.0) {
            double u[3];
            sub3(u, P(S, b), P(S, a));
            double l = sqrt(dot3(u, u));
            if (l > 0.0) {
                for (int k = 0; k < 3; k++) u[k] /= l;
                fl_quadric_add_line(S->q + a, u, P(S, a), S->feat_w * sharp);
                fl_quadric_add_line(S->q + b, u, P(S, a), S->feat_w * sharp);
            }
        }
    }
    SETUP_T(8);
    /* vertices that never move */
    for (size_t v = 0; v < nv; v++) {
        if (S->fdeg[v] == 1 || S->fdeg[v] >= 3) S->vflag[v] |= V_FIXED;
        if (S->keep_boundary && (S->vflag[v] & V_BOUNDARY)) S->vflag[v] |= V_FIXED;
        if (S->vflag[v] & V_NONMANIFOLD) S->vflag[v] |= V_FIXED;
    }
    for (size_t m = 0; m < o->lock_count; m++) {
        if (o->lock[m] >= nv) {
            return fl_error(err, FEMLOD_EINPUT, "simplify: lock[%zu] = %u is out of range (%zu vertices)", m,
                            (unsigned)o->lock[m], nv);
        }
        S->vflag[slot_of[o->lock[m]]] |= V_FIXED;
    }
    if (o->lock_fn)
        for (size_t v = 0; v < nv; v++) {
            const double *p = mesh->pos + 3 * v;
            if (o->lock_fn(o->lock_payload, p[0], p[1], p[2])) S->vflag[slot_of[v]] |= V_FIXED;
        }
    free(S->slot_of);
    S->slot_of = NULL;

    if (S->cone_on) {
        if (!ALLOC(S->cone, 4 * nt)) return fl_error(err, FEMLOD_ENOMEM, "simplify: out of memory");
        par_ranges(nth, nt, cone_init, S);
    }
    if (S->dev_on) {
        if (!ALLOC(S->fpt, nt) || !ALLOC(S->pnext, nv))
            return fl_error(err, FEMLOD_ENOMEM, "simplify: out of memory");
        memset(S->fpt, 0xff, nt * sizeof *S->fpt);
        memset(S->pnext, 0xff, nv * sizeof *S->pnext);
    }
    SETUP_T(9);
    if (!fl_heap_init(&S->heap, ne + 1)) return fl_error(err, FEMLOD_ENOMEM, "simplify: out of memory");
    if (!build_grid(S, mean_edge > 0.0 ? FEMLOD_SIMPLIFY_GRID_CELL * mean_edge : 1.0))
        return fl_error(err, FEMLOD_ENOMEM, "simplify: out of memory");
    SETUP_T(10);
#undef ALLOC
#undef CALLOC
    return FEMLOD_OK;
}

/* }====== */

/* {====== driver */

static int progress(simp *S, const femlod_simplify_options *o, size_t live0, size_t *next) {
    if (!o->progress) return 0;
    if (S->collapses < *next) return 0;
    size_t goal = live0 > S->prog_target ? live0 - S->prog_target : 1;
    size_t done = live0 - S->live;
    *next = S->collapses + (goal / 100 > 0 ? goal / 100 : 1);
    double d = (double)done / (double)goal;
    return o->progress(o->progress_payload, d > 1.0 ? 1.0 : d);
}

/* Pops edges until the target or an empty queue. Returns 0 on ENOMEM, 2
 * when cancelled, 1 otherwise. */
/* {====== the exact queue's second thread (ring_eval)
 *
 * After each collapse the queue re-evaluates the ~33 edges at and around k
 * (reevaluate_ring), three quarters of its time. The evaluations are
 * independent, so a helper thread shares them: the main thread publishes
 * the list (its range in one atomic word, after the helper's view W),
 * each thread claims one entry at a time by compare-and-swap on that word,
 * the main thread from the front and the helper from the back, and the
 * main thread waits only for the entries the helper has claimed (hdone),
 * then applies the results in list order, as with one thread. A helper
 * that is slow to wake (it sleeps after a short spin) thus costs nothing:
 * the main thread evaluates the whole list (docs/simplify.md "Session 16":
 * the fixed 40 / 60 split it replaces waited for the helper half the
 * time). The helper reads W only under a claim, and a claim of the
 * current word is a claim of the current list (its range is all the word
 * holds), so a stale helper can neither read a half-written W nor take an
 * entry of a finished list. It lives only while the queue runs. */

typedef struct eval_helper {
    simp W; /* its view of the run, refreshed before each list */
    simp *S;
    pthread_t th;
    atomic_uint go; /* the lists published: wakes a sleeping helper */
    /* the list's unclaimed range [lo, hi) as lo << 32 | hi: the main
     * thread claims from lo up, the helper from hi down; hdone: items the
     * helper has finished, over the whole run; htaken: the main thread's
     * count of the items the helper has claimed */
    _Atomic uint64_t claim, hdone;
    uint64_t htaken;
    atomic_int quit;
    /* after a short spin the helper sleeps (so that it never holds a core
     * another process could use): sleeping is set under mu before the
     * last look at go, and the main thread signals under mu when it sees
     * it set (both sides sequentially consistent: one sees the other) */
    atomic_int sleeping;
    pthread_mutex_t mu;
    pthread_cond_t cv;
} eval_helper;

static inline void cpu_relax(void) {
#if defined(__x86_64__) || defined(__i386__)
    __builtin_ia32_pause();
#endif
}

/* The helper's share of the list: entries claimed from the back until
 * the two ends meet. */
#define CL_LO(w) ((size_t)((w) >> 32))
#define CL_HI(w) ((size_t)((w) & 0xffffffffu))
static void helper_share(eval_helper *h) {
    simp *S = h->S, *W = &h->W;
    for (;;) {
        uint64_t w = atomic_load_explicit(&h->claim, memory_order_acquire);
        if (CL_LO(w) >= CL_HI(w)) break;
        if (!atomic_compare_exchange_weak_explicit(&h->claim, &w, w - 1, memory_order_acq_rel, memory_order_acquire))
            continue;
        size_t x = CL_HI(w) - 1;
        S->rrho[x] = evaluate(W, &W->R, S->rlist[x]);
        S->rtol[x] = (uint8_t)W->R.tolfail;
        atomic_fetch_add_explicit(&h->hdone, 1, memory_order_release);
    }
}

static void *helper_main(void *arg) {
    eval_helper *h = arg;
    unsigned seen = 0;
    for (;;) {
        unsigned g;
        int spins = 0;
        while ((g = atomic_load(&h->go)) == seen) {
            if (atomic_load(&h->quit)) return NULL;
            if (++spins < 4000) {
                cpu_relax();
                continue;
            }
            pthread_mutex_lock(&h->mu);
            atomic_store(&h->sleeping, 1);
            while (atomic_load(&h->go) == seen && !atomic_load(&h->quit)) pthread_cond_wait(&h->cv, &h->mu);
            atomic_store(&h->sleeping, 0);
            pthread_mutex_unlock(&h->mu);
            spins = 0;
        }
        seen = g;
        helper_share(h);
    }
}

static void helper_wake(eval_helper *h) {
    if (!atomic_load(&h->sleeping)) return;
    pthread_mutex_lock(&h->mu);
    pthread_cond_signal(&h->cv);
    pthread_mutex_unlock(&h->mu);
}

/* Evaluates S->rlist[0, n) into S->rrho and S->rtol. */
static void ring_eval(simp *S, size_t n) {
    eval_helper *h = S->helper;
    if (!h || n < 2 || n >= 0xffffffffu) {
        for (size_t x = 0; x < n; x++) {
            S->rrho[x] = evaluate(S, &S->R, S->rlist[x]);
            S->rtol[x] = (uint8_t)S->R.tolfail;
        }
        return;
    }
    /* the last list is claimed whole and finished (hdone == htaken): the
     * helper reads W only under a claim */
    simp_view(&h->W, S);
    atomic_store(&h->claim, (uint64_t)n);
    atomic_store(&h->go, atomic_load_explicit(&h->go, memory_order_relaxed) + 1);
    helper_wake(h);
    size_t mine = 0;
    for (;;) {
        uint64_t w = atomic_load_explicit(&h->claim, memory_order_acquire);
        if (CL_LO(w) >= CL_HI(w)) break;
        if (!atomic_compare_exchange_weak_explicit(&h->claim, &w, w + ((uint64_t)1 << 32), memory_order_acq_rel,
                                                   memory_order_acquire))
            continue;
        size_t x = CL_LO(w);
        S->rrho[x] = evaluate(S, &S->R, S->rlist[x]);
        S->rtol[x] = (uint8_t)S->R.tolfail;
        mine++;
    }
    if (mine < n) {
        h->htaken += n - mine;
        int spins = 0;
        while (atomic_load_explicit(&h->hdone, memory_order_acquire) != h->htaken) {
            if (++spins < 2000) {
                cpu_relax();
            } else {
                sched_yield();
                spins = 0;
            }
        }
        if (h->W.oom) S->oom = 1;
    }
}
/* Starts the helper when the run has a second thread (none: ring_eval
 * evaluates alone; the results are the same). */
static void helper_start(simp *S) {
    S->helper = NULL;
    if (S->nthreads < 2) return;
    eval_helper *h = calloc(1, sizeof *h);
    if (!h) return;
    h->S = S;
    atomic_init(&h->go, 0);
    atomic_init(&h->claim, 0);
    atomic_init(&h->hdone, 0);
    h->htaken = 0;
    atomic_init(&h->quit, 0);
    atomic_init(&h->sleeping, 0);
    if (pthread_mutex_init(&h->mu, NULL) != 0) {
        free(h);
        return;
    }
    if (pthread_cond_init(&h->cv, NULL) != 0) {
        pthread_mutex_destroy(&h->mu);
        free(h);
        return;
    }
    if (pthread_create(&h->th, NULL, helper_main, h) != 0) {
        pthread_cond_destroy(&h->cv);
        pthread_mutex_destroy(&h->mu);
        free(h);
        return;
    }
    S->helper = h;
}

/* Stops the helper and adds its rejection counts to the run's. */
static void helper_stop(simp *S) {
    eval_helper *h = S->helper;
    if (!h) return;
    atomic_store(&h->quit, 1);
    pthread_mutex_lock(&h->mu);
    pthread_cond_signal(&h->cv);
    pthread_mutex_unlock(&h->mu);
    pthread_join(h->th, NULL);
    pthread_cond_destroy(&h->cv);
    pthread_mutex_destroy(&h->mu);
    for (int r = 0; r < FEMLOD_REJECT_COUNT; r++) S->rejected[r] += h->W.rejected[r];
    simp_free_scratch(&h->W);
    free(h);
    S->helper = NULL;
}

/* }====== */

static int run_queue_1(simp *S, const femlod_simplify_options *o, size_t live0, size_t *next);

static int run_queue(simp *S, const femlod_simplify_options *o, size_t live0, size_t *next) {
    helper_start(S);
    int r = run_queue_1(S, o, live0, next);
    helper_stop(S);
    return r;
}

static int run_queue_1(simp *S, const femlod_simplify_options *o, size_t live0, size_t *next) {
    ring *R = &S->R;
    while (S->live > S->target) {
        double key;
        settle(S);
        uint32_t e = fl_heap_pop(&S->heap, &key);
        if (e == UINT32_MAX) break;
        STAT(pops);
        settle(S); /* the keys compared below are priorities */
        if (S->oom) return 0;
        double rho = evaluate(S, R, e);
        if (S->oom) return 0;
        if (rho < 0.0) continue;
        if (rho < fl_heap_top_key(&S->heap)) { /* stale key: back in line */
            fl_heap_set(&S->heap, e, rho);
            continue;
        }
        int lw = link_check(S, R);
        if (lw != NO_REASON) { /* back when its neighbourhood changes */
            S->rejected[lw]++;
            continue;
        }
        int chosen = -1;
        for (int c = 0; c < R->ncand && chosen < 0; c++) {
            if (!R->ok[c]) continue;
            int w = expensive_checks(S, R, c);
            if (S->oom) return 0;
            if (w == NO_REASON) chosen = c;
            else S->rejected[w]++;
        }
        if (chosen < 0) continue; /* back when its neighbourhood changes */
        if (R->rho[chosen] < fl_heap_top_key(&S->heap)) {
            fl_heap_set(&S->heap, e, R->rho[chosen]);
            continue;
        }
        uint32_t k = R->i;
        if (!collapse(S, R, chosen)) return 0;
        if (!reevaluate_ring(S, k) || S->oom) return 0;
        if (progress(S, o, live0, next)) return 2;
    }
    return 1;
}

/* {====== fast passes (docs/simplify.md "Fast passes") */

#ifndef FEMLOD_SIMPLIFY_BAND
#define FEMLOD_SIMPLIFY_BAND 0.9 /* each pass lowers the threshold by this factor */
#endif
#ifndef FEMLOD_SIMPLIFY_DEFER
/* A stale edge whose last key is below this times the pass's threshold is
 * not evaluated at a visit (0: every stale edge is; docs/simplify.md
 * "Session 12") */
#define FEMLOD_SIMPLIFY_DEFER 0.85
#endif

static int u32vec_push(u32vec *a, uint32_t x) {
    if (a->n == a->cap && !buf_reserve((void **)&a->v, &a->cap, a->n + 1, sizeof *a->v)) return 0;
    a->v[a->n++] = x;
    return 1;
}

/* The worker's rules (docs/design.md "Parallel fast passes"). To visit v,
 * every neighbour must be in the worker's slab or in a slab of the other
 * colour (idle in this sub-pass): their data then changes only by this
 * worker or not at all. */
static int par_star_readable(const simp *S, uint32_t v) {
    const uint32_t *fl = S->refs + S->fstart[v];
    for (uint32_t m = 0; m < S->fcount[v]; m++) {
        const uint32_t *t = S->face[fl[m]].v;
        for (int c = 0; c < 3; c++) {
            if (t[c] == v) continue;
            uint32_t sl = slab_of(S, P(S, t[c]));
            if (sl != S->slab && ((sl ^ S->slab) & 1u) == 0) return 0;
        }
    }
    return 1;
}

/* To collapse the gathered edge: i, j and every neighbour of theirs in the
 * slab (so every face and edge it writes has all its corners there), room
 * in the worker's face-list slice and triangle budget. */
static int par_ring_owned(const simp *S, const ring *R) {
    if (slab_of(S, P(S, R->i)) != S->slab || slab_of(S, P(S, R->j)) != S->slab) return 0;
    for (size_t r = 0; r < R->n; r++)
        if (slab_of(S, P(S, R->a[r])) != S->slab || slab_of(S, P(S, R->b[r])) != S->slab) return 0;
    for (size_t x = 0; x < R->ns; x++)
        if (slab_of(S, P(S, R->sopp[x])) != S->slab) return 0;
    if (S->nrefs + R->n > S->caprefs) return 0;
    return S->live_start - S->live + R->ns <= S->live_budget;
}

/* To move k to p: p in the slab (a vertex never leaves its slab) and
 * enough blocks in the worker's pool for the new faces' grid cells. */
static int par_candidate_ok(const simp *S, const ring *R, const double p[3]) {
    if (slab_of(S, p) != S->slab) return 0;
    size_t need = 0;
    for (size_t r = 0; r < R->n; r++) {
        const double *a = P(S, R->a[r]), *b = P(S, R->b[r]);
        double lo[3], hi[3];
        int c0[3], c1[3];
        for (int k = 0; k < 3; k++) {
            lo[k] = mn(p[k], mn(a[k], b[k]));
            hi[k] = mx(p[k], mx(a[k], b[k]));
        }
        fl_grid_range(&S->grid, lo, hi, c0, c1);
        need += (size_t)(c1[0] - c0[0] + 1) * (size_t)(c1[1] - c0[1] + 1) * (size_t)(c1[2] - c0[2] + 1);
    }
    return need <= S->grid.nfree;
}

/* One visit of slot v in a pass with threshold tau: evaluates v's edges
 * whose key is out of date, then tries v's best edge if it reaches tau and
 * its other end is not locked in this pass. Returns 1 collapsed, 0 not, -1
 * on ENOMEM, 2 deferred (a worker, S->par: the collapse would leave its
 * slab). */
static int band_vertex(simp *S, uint32_t v, double tau) {
    ring *R = &S->R;
    if (S->par && !par_star_readable(S, v)) return 2;
    uint32_t em = next_stamp(S);
    uint32_t best = UINT32_MAX;
    float bkey = -1.0f, vb = -1.0f;
    /* fresh: best was evaluated in this visit, its evaluation kept in S->R2
     * (nothing it reads changes during the visit: evaluating it again
     * would give the same) */
    int fresh = 0;
    double frho = -1.0;
    const uint32_t *fl = S->refs + S->fstart[v];
    uint32_t cnt = S->fcount[v];
    /* v's edges, each once: at an interior manifold vertex of an oriented
     * mesh, the side leaving v in each face (no marks: they were a fifth
     * of the scan's time); elsewhere both sides at v, told apart by marks */
    int once = !FEMLOD_SIMPLIFY_MARKED_SCAN && S->oriented && !(S->vflag[v] & (V_BOUNDARY | V_NONMANIFOLD));
    for (uint32_t a = 0; a < cnt; a++) {
        uint32_t f = fl[a];
        const uint32_t *t = S->face[f].v;
        for (int c = 0; c < 3; c++) {
            uint32_t ed;
            if (once) {
                if (t[c] != v) continue;
                ed = S->tedge[3 * (size_t)f + c];
            } else {
                if (t[c] != v && t[(c + 1) % 3] != v) continue;
                ed = S->tedge[3 * (size_t)f + c];
                if (S->emark[ed] == em) continue;
                S->emark[ed] = em;
            }
            if (S->edge[ed].flag & E_DEAD) continue;
            int now = 0;
            double rnow = -1.0;
            if ((S->edge[ed].state & E_STALE) && FEMLOD_SIMPLIFY_DEFER > 0.0 && S->edge[ed].key >= 0.0f &&
                S->edge[ed].key < (float)(FEMLOD_SIMPLIFY_DEFER * tau)) {
                /* it waits, its last key standing in for its priority:
                 * that keeps v listed until the threshold comes down to
                 * about that key, and an edge that reached it a pass ago
                 * seldom jumps above the band (the stale edges evaluated
                 * at visits that collapse nothing were more than half of
                 * all evaluations); an invalid last key (< 0) says
                 * nothing, so that edge is evaluated */
                STAT(deferred);
            } else if (S->edge[ed].state & E_STALE) {
                rnow = evaluate(S, R, ed);
                if (S->oom) return -1;
                S->edge[ed].key = rnow < 0.0 ? -1.0f : (float)rnow;
                S->edge[ed].state &= (uint8_t)~E_STALE;
                now = 1;
            }
            float key = S->edge[ed].key;
            if (key > vb) vb = key;
            uint32_t u = S->edge[ed].v[0] == v ? S->edge[ed].v[1] : S->edge[ed].v[0];
            if (S->vlock[u] == S->pass || !(key >= (float)tau)) continue;
            if (key > bkey || (key == bkey && ed < best)) {
                bkey = key;
                best = ed;
                fresh = now;
                if (now) {
                    ring x = S->R;
                    S->R = S->R2;
                    S->R2 = x;
                    frho = rnow;
                }
            }
        }
    }
    S->vbest[v] = vb;
    if (best == UINT32_MAX) return 0;
    /* its key may predate changes around its far end: evaluate again
     * (unless it was evaluated in this visit) */
    STAT(attempts);
    double rho;
    if (fresh) {
        ring x = S->R;
        S->R = S->R2;
        S->R2 = x;
        rho = frho;
    } else {
        rho = evaluate(S, R, best);
    }
#if FEMLOD_SIMPLIFY_STATS
    if (rho < tau) S->stats.attempt_low++;
#endif
    if (S->oom) return -1;
    S->edge[best].key = rho < 0.0 ? -1.0f : (float)rho;
    if (S->par && rho >= tau && !par_ring_owned(S, R)) return 2;
    int chosen = -1;
    if (rho >= tau && link_check(S, R) == NO_REASON) {
        for (int c = 0; c < R->ncand && chosen < 0; c++) {
            if (!R->ok[c] || R->rho[c] < tau) continue;
            if (S->par && !par_candidate_ok(S, R, R->cand[c])) return 2;
            int w = expensive_checks(S, R, c);
            if (S->oom) return -1;
            if (w == DEFER_REASON) return 2;
            if (w == NO_REASON) chosen = c;
            else S->rejected[w]++;
        }
    } else if (rho >= tau) {
        S->rejected[FEMLOD_REJECT_TOPOLOGY]++;
    }
    if (chosen < 0) {
        /* refused for reasons outside its key (topology, the costly
         * checks): out of the passes until one of its ends moves (the
         * exact queue evaluates it again); v's best key without it */
        if (rho >= tau) S->edge[best].key = -1.0f;
        float rest = -1.0f;
        for (uint32_t a = 0; a < cnt; a++) {
            const uint32_t *t = S->face[fl[a]].v;
            for (int c = 0; c < 3; c++) {
                if (t[c] != v && t[(c + 1) % 3] != v) continue;
                uint32_t ed = S->tedge[3 * (size_t)fl[a] + c];
                if (!(S->edge[ed].flag & E_DEAD) && S->edge[ed].key > rest) rest = S->edge[ed].key;
            }
        }
        S->vbest[v] = rest;
        return 0;
    }
    uint32_t k = R->i;
    if (!collapse(S, R, chosen)) return -1;
    if (S->par && !u32vec_push(S->klist, k)) return -1;
    S->swept++;
    /* k's edges have a new endpoint: out of date; the edges around keep
     * their keys (docs/simplify.md says what that costs); k and its ring
     * wait for the next pass */
    S->vlock[k] = S->pass;
    S->vbest[k] = FLT_MAX;
    const uint32_t *fk = S->refs + S->fstart[k];
    for (uint32_t m = 0; m < S->fcount[k]; m++) {
        uint32_t f = fk[m];
        const uint32_t *t = S->face[f].v;
        for (int c = 0; c < 3; c++) {
            S->vlock[t[c]] = S->pass;
            S->vbest[t[c]] = FLT_MAX;
            if (t[c] == k || t[(c + 1) % 3] == k) {
                /* E_STALE marks the key out of date (free in the passes:
                 * the lazy queue, FEMLOD_SIMPLIFY_BOUND, is not used there);
                 * the cached optimum is gone with the endpoint */
                uint32_t ed = S->tedge[3 * (size_t)f + c];
                S->edge[ed].state = (uint8_t)((S->edge[ed].state | E_STALE) & ~E_OPT);
            }
        }
    }
    return 1;
}

/* {====== parallel fast passes (docs/design.md "Parallel fast passes")
 *
 * A pass runs in two stages of sub-passes, then a sequential remainder.
 * The grid's longest axis is cut into slabs of slab_w cells; in a sub-pass
 * the slabs of one colour (parity) are tasks, done in any order by any
 * thread, each visiting its vertices in slot order under the worker's rules
 * (par_star_readable, par_ring_owned, par_candidate_ok and the cell range
 * of intersect_check); a visit they forbid is deferred. Stage 1 visits
 * stage 0's deferred vertices in slabs shifted by half a slab, where most
 * lie far from a border; what it defers is visited sequentially. Each
 * task's collapses get provisional node ids and a log of their own; both
 * are merged in slab order. So the result depends on the slabs, never on
 * the threads. */

#define PAR_SLAB_CELLS 16   /* least slab width, in grid cells */
#define PAR_MAX_SLABS 64    /* slabs along the axis at most (wider slabs beyond) */
#define PAR_MIN_LEFT 4096   /* triangles above the floor below which a pass runs sequentially */
#define PAR_CHUNK 16384     /* edges per task of the first evaluation */
/* Face-list arena slice per listed vertex of a task: a visit appends a
 * list only when it collapses (k's faces, about 6), and about one visit in
 * eight does (cover x4), so 3 is about four times the mean need; a task
 * whose slice runs out defers its visit (par_ring_owned), which the
 * deferral rules make thread-independent. The whole slice is consumed until the next
 * compaction, so a smaller slice means fewer compactions: 8 gave the same
 * output on the 21 digest cases and cover x4, with compactions taking 0.28
 * instead of 0.13 s of one thread at 50,000. */
#ifndef PAR_REFS_PER_VISIT
#define PAR_REFS_PER_VISIT 3
#endif

typedef struct par_task {
    uint32_t slab;
    size_t lo, hi;           /* its vertices: the stage list [lo, hi) */
    size_t refs_lo, refs_hi; /* its slice of the face-list arena */
    uint32_t blocks;         /* its pool of grid blocks (kept from sub-pass to sub-pass) */
    size_t nblocks;
    uint32_t gen;            /* the grid the pool's blocks belong to */
    size_t budget;           /* triangles it may remove */
    femlod_collapse_log *log;
    u32vec klist, deferred;
    /* what it did */
    size_t collapses, removed, swept, done, refs_end;
    size_t rejected[FEMLOD_REJECT_COUNT];
    uint32_t stamp;
    int oom;
} par_task;

typedef struct par_worker {
    simp W; /* its view of the run, with its own scratch */
    struct par_ctx *X;
    pthread_t th;
    double tend; /* stats build: when it ran out of tasks */
} par_worker;

typedef struct par_ctx {
    simp *S;
    par_worker *wk;
    int nw;
    par_task *task;
    size_t ntask, captask;
    uint32_t *order; /* the tasks of a sub-pass, largest first (par_order) */
    size_t caporder;
    u32vec list[2];  /* the stage's vertices, bucketed by slab */
    u32vec tmp;
    uint32_t *count; /* per slab */
    size_t capcount;
    double tau;
    /* the running sub-pass */
    void (*fn)(struct par_ctx *, par_worker *, size_t);
    size_t nrun, nrun_end;
    atomic_size_t next;
} par_ctx;

static void *par_thread(void *arg) {
    par_worker *w = arg;
    par_ctx *X = w->X;
    for (;;) {
        size_t k = atomic_fetch_add(&X->next, 1);
        if (k >= X->nrun) break;
        X->fn(X, w, k);
    }
#if FEMLOD_SIMPLIFY_STATS
    w->tend = now_seconds();
#endif
    return NULL;
}

/* Runs fn(X, worker, k) for k < n on up to nw threads (this one included).
 * A thread that cannot start leaves its share to the others. */
static void par_for(par_ctx *X, size_t n, void (*fn)(par_ctx *, par_worker *, size_t)) {
    X->fn = fn;
    X->nrun = n;
    atomic_store(&X->next, 0);
    int nt = X->nw;
    if ((size_t)nt > n) nt = n ? (int)n : 1;
    int started[16] = {0};
    for (int t = 1; t < nt; t++) started[t] = pthread_create(&X->wk[t].th, NULL, par_thread, &X->wk[t]) == 0;
    par_thread(&X->wk[0]);
    for (int t = 1; t < nt; t++)
        if (started[t]) pthread_join(X->wk[t].th, NULL);
#if FEMLOD_SIMPLIFY_STATS
    /* how long threads waited for the last one (tstage[30]) */
    double last = 0.0;
    for (int t = 0; t < nt; t++) last = X->wk[t].tend > last ? X->wk[t].tend : last;
    for (int t = 0; t < nt; t++) X->S->stats.tstage[30] += last - X->wk[t].tend;
#endif
}

static void par_free(par_ctx *X) {
#if FEMLOD_SIMPLIFY_STATS
    /* the workers' counts (the fields before t, all size_t) */
    for (int t = 0; t < X->nw; t++) {
        size_t *a = (size_t *)&X->S->stats, *w = (size_t *)&X->wk[t].W.stats;
        for (size_t k = 0; k < offsetof(simp_stats, t) / sizeof(size_t); k++) a[k] += w[k];
    }
#endif
    for (int t = 0; t < X->nw; t++) simp_free_scratch(&X->wk[t].W);
    free(X->wk);
    for (size_t k = 0; k < X->captask; k++) {
        femlod_collapse_log_free(X->task[k].log);
        free(X->task[k].klist.v);
        free(X->task[k].deferred.v);
    }
    free(X->task);
    free(X->order);
    free(X->list[0].v);
    free(X->list[1].v);
    free(X->tmp.v);
    free(X->count);
}

static void par_ctx_free(par_ctx *X) {
    if (!X) return;
    par_free(X);
    free(X);
}

/* evaluate_all's sub-chunk k of 4,096 edges. */
static void par_eval_sub(par_ctx *X, par_worker *w, size_t k) {
    simp *S = X->S, *W = &w->W;
    size_t e0 = S->er0 + k * 4096, e1 = e0 + 4096 < X->nrun_end ? e0 + 4096 : X->nrun_end;
    for (size_t ed = e0; ed < e1; ed++) {
        size_t x = ed - S->er0;
        S->rkind[x] = (uint8_t)eval_wanted(S, ed);
        if (!S->rkind[x]) continue;
        S->rrho[x] = evaluate(W, &W->R, (uint32_t)ed);
        S->rtol[x] = (uint8_t)W->R.tolfail;
    }
}

/* Evaluates the edges [e0, e1) that evaluate_all wants into S->rkind,
 * S->rrho, S->rtol (index ed - e0) on the run's threads. 0 on ENOMEM. */
static int eval_range(simp *S, size_t e0, size_t e1) {
    size_t n = e1 - e0;
    if (!buf_reserve((void **)&S->rkind, &S->rkind_cap, n + 1, 1) ||
        !buf_reserve((void **)&S->rrho, &S->rrho_cap, n + 1, sizeof *S->rrho) ||
        !buf_reserve((void **)&S->rtol, &S->rtol_cap, n + 1, 1))
        return 0;
    if (!S->ectx) {
        par_ctx *X = calloc(1, sizeof *X);
        if (!X) return 0;
        X->S = S;
        X->nw = S->nthreads < 1 ? 1 : (S->nthreads > 16 ? 16 : S->nthreads);
        X->wk = fl_calloc((size_t)X->nw, sizeof *X->wk);
        if (!X->wk) {
            free(X);
            return 0;
        }
        for (int t = 0; t < X->nw; t++) X->wk[t].X = X;
        S->ectx = X;
    }
    par_ctx *X = S->ectx;
    for (int t = 0; t < X->nw; t++) simp_view(&X->wk[t].W, S); /* rejected: summed into the run's at the end */
    S->er0 = e0;
    X->nrun_end = e1;
    par_for(X, (n + 4095) / 4096, par_eval_sub);
    for (int t = 0; t < X->nw; t++)
        if (X->wk[t].W.oom) return 0;
    return 1;
}

/* The first evaluation of the passes, chunk k of the edges: every edge is
 * evaluated on its own (evaluate writes only the edge's cached optimum). */
static void par_eval_chunk(par_ctx *X, par_worker *w, size_t k) {
    simp *S = X->S, *W = &w->W;
    size_t e0 = k * PAR_CHUNK, e1 = e0 + PAR_CHUNK < S->ne ? e0 + PAR_CHUNK : S->ne;
    for (size_t ed = e0; ed < e1 && !W->oom; ed++) {
        float key = -1.0f;
        if (!(S->edge[ed].flag & E_DEAD)) {
            double rho = evaluate(W, &W->R, (uint32_t)ed);
            if (rho >= 0.0) key = (float)rho;
        }
        S->edge[ed].key = key;
    }
}

/* One task: slab t's vertices of the stage list, in order. */
static void par_run_task(par_ctx *X, par_worker *w, size_t k) {
    simp *S = X->S, *W = &w->W;
#if FEMLOD_SIMPLIFY_STATS
    double tk0 = now_seconds();
#endif
    par_task *t = X->task + X->order[k];
    const uint32_t *list = X->list[0].v;
    simp_view(W, S);
    memset(W->rejected, 0, sizeof W->rejected); /* the task's own count */
    W->par = 1;
    W->slab = t->slab;
    W->nrefs = t->refs_lo;
    W->caprefs = t->refs_hi;
    W->grid.free_block = t->blocks;
    W->grid.nfree = t->nblocks;
    W->grid.fixed = 1;
    W->grid_live = 0; /* no grid rebuild in a worker */
    W->log = t->log;
    W->live_start = S->live;
    W->live_budget = t->budget;
    W->klist = &t->klist;
    t->klist.n = 0;
    t->deferred.n = 0;
    size_t done = 0;
    float ftau = (float)X->tau;
    for (size_t x = t->lo; x < t->hi && !W->oom; x++) {
        uint32_t v = list[x];
        if ((W->vflag[v] & V_DEAD) || !W->fcount[v]) continue;
        if (W->vlock[v] == W->pass || !(W->vbest[v] >= ftau)) continue;
        int c = band_vertex(W, v, X->tau);
        if (c < 0) W->oom = 1;
        else if (c == 1) done++;
        else if (c == 2 && !u32vec_push(&t->deferred, v)) W->oom = 1;
    }
#if FEMLOD_SIMPLIFY_STATS
    S->stats.tstage[10 + (w - X->wk)] += now_seconds() - tk0;
#endif
    t->collapses = W->collapses - S->collapses;
    t->removed = S->live - W->live;
    t->swept = W->swept;
    t->done = done;
    t->refs_end = W->nrefs;
    t->blocks = W->grid.free_block;
    t->nblocks = W->grid.nfree;
    memcpy(t->rejected, W->rejected, sizeof t->rejected);
    t->stamp = W->stamp;
    t->oom = W->oom;
}

/* Buckets the vertices of `in` by slab (stable: slot order within a slab)
 * into X->list[0] and makes one task per non-empty slab of colour `col`
 * later; returns the slab count, 0 on ENOMEM. */
static size_t par_bucket(par_ctx *X, const u32vec *in) {
    simp *S = X->S;
    size_t ncell = (size_t)S->grid.n[S->slab_ax];
    size_t nslab = (ncell + S->slab_shift) / S->slab_w + 1;
    if (!buf_reserve((void **)&X->count, &X->capcount, nslab + 1, sizeof *X->count) ||
        !buf_reserve((void **)&X->list[0].v, &X->list[0].cap, in->n + 1, sizeof *X->list[0].v) ||
        !buf_reserve((void **)&X->list[1].v, &X->list[1].cap, in->n + 1, sizeof *X->list[1].v))
        return 0;
    memset(X->count, 0, (nslab + 1) * sizeof *X->count);
    for (size_t x = 0; x < in->n; x++) {
        uint32_t v = in->v[x];
        uint32_t sl = slab_of(S, P(S, v));
        X->list[1].v[x] = sl;
        X->count[sl + 1]++;
    }
    for (size_t sl = 0; sl < nslab; sl++) X->count[sl + 1] += X->count[sl];
    /* count[sl] = start of slab sl; scatter */
    for (size_t x = 0; x < in->n; x++) X->list[0].v[X->count[X->list[1].v[x]]++] = in->v[x];
    /* count[sl] = end of slab sl now */
    X->list[0].n = in->n;
    return nslab;
}

/* Prepares the tasks of the slabs of colour col (stage list in X->list[0],
 * slab ends in X->count): face-list slices, block pools, triangle budgets,
 * logs. Returns the task count, (size_t)-1 on ENOMEM. */
static size_t par_tasks(par_ctx *X, size_t nslab, unsigned col, size_t floor_live) {
    simp *S = X->S;
    size_t n = 0, total = 0;
    for (size_t sl = col; sl < nslab; sl += 2) {
        size_t lo = sl ? X->count[sl - 1] : 0, hi = X->count[sl];
        if (hi == lo) continue;
        if (n == X->captask) {
            size_t cap = X->captask ? 2 * X->captask : 32;
            par_task *nt = fl_realloc(X->task, cap, sizeof *nt);
            if (!nt) return (size_t)-1;
            memset(nt + X->captask, 0, (cap - X->captask) * sizeof *nt);
            X->task = nt;
            X->captask = cap;
        }
        par_task *t = X->task + n++;
        t->slab = (uint32_t)sl;
        t->lo = lo;
        t->hi = hi;
        total += hi - lo;
    }
    if (!n) return 0;
    /* stamps: room for every task's values without a wrap-around clear */
    if (S->stamp > 0x7FFFFFFFu) {
        memset(S->vmark, 0, S->nv * sizeof *S->vmark);
        memset(S->emark, 0, S->ne * sizeof *S->emark);
        S->stamp = 0;
    }
    /* face lists: a slice per task (PAR_REFS_PER_VISIT) */
    size_t need = 0;
    for (size_t k = 0; k < n; k++) need += PAR_REFS_PER_VISIT * (X->task[k].hi - X->task[k].lo) + 256;
    if (S->nrefs + need > S->caprefs) {
#if FEMLOD_SIMPLIFY_STATS
        double tc0 = now_seconds();
#endif
        if (!compact_refs(S)) return (size_t)-1;
        STAT_TIME_ST(9, tc0);
        if (S->nrefs + need > S->caprefs) {
            size_t cap = S->nrefs + 2 * need;
            uint32_t *nr = fl_realloc(S->refs, cap, sizeof *nr);
            if (!nr) return (size_t)-1;
            S->refs = nr;
            S->caprefs = cap;
        }
    }
    size_t at = S->nrefs, left = S->live > floor_live ? S->live - floor_live : 0;
    for (size_t k = 0; k < n; k++) {
        par_task *t = X->task + k;
        size_t len = t->hi - t->lo;
        t->refs_lo = at;
        at += PAR_REFS_PER_VISIT * len + 256;
        t->refs_hi = at;
        t->budget = (size_t)((double)left * (double)len / (double)total);
        /* grid blocks: the pool the task slot kept, topped up */
        if (t->gen != S->grid_gen) {
            t->gen = S->grid_gen;
            t->blocks = UINT32_MAX;
            t->nblocks = 0;
        }
        size_t want = 128 + len / 8;
        if (t->nblocks < want) {
            if (!fl_grid_take(&S->grid, want - t->nblocks, &t->blocks)) return (size_t)-1;
            t->nblocks = want;
        }
        if (S->log && !t->log && !(t->log = fl_log_new(S->nv, 64))) return (size_t)-1;
    }
    return n;
}

/* The order in which the threads take the n tasks of a sub-pass: the
 * largest (most listed vertices) first, ties in slab order. Slabs differ
 * in size by the part's shape, and a large slab taken last kept one thread
 * busy while the other waited: at 50,000 (cover x4, two threads) the
 * threads waited 0.38-0.40 thread-seconds per run at the ends of the
 * parallel steps in slab order, 0.21-0.33 largest first (stats build).
 * The order of work never changes a
 * result: the tasks of a sub-pass share no data they write, and par_merge
 * folds them in slab order. 0 on ENOMEM. */
static int par_order(par_ctx *X, size_t n) {
    if (!buf_reserve((void **)&X->order, &X->caporder, n + 1, sizeof *X->order)) return 0;
    for (size_t k = 0; k < n; k++) {
        /* insertion sort: a few dozen tasks */
        size_t len = X->task[k].hi - X->task[k].lo, m = k;
        for (; m > 0; m--) {
            const par_task *o = X->task + X->order[m - 1];
            if (o->hi - o->lo >= len) break;
            X->order[m] = X->order[m - 1];
        }
        X->order[m] = (uint32_t)k;
    }
    return 1;
}

/* Folds the tasks' work into the run, in slab order: node ids and logs
 * renumbered, counters summed, pools and slices given back, deferred
 * vertices appended to out. Returns the collapses, (size_t)-1 on ENOMEM. */
static size_t par_merge(par_ctx *X, size_t n, u32vec *out) {
    simp *S = X->S;
    uint32_t base = (uint32_t)(S->nv + S->collapses);
    size_t offset = 0, done = 0;
    int oom = 0;
    for (size_t k = 0; k < n; k++) {
        par_task *t = X->task + k;
        oom |= t->oom;
        for (size_t m = 0; m < t->klist.n; m++) S->node[t->klist.v[m]] += (uint32_t)offset;
        if (S->log && !oom) {
            if (!fl_log_merge(S->log, t->log, base, (uint32_t)offset)) oom = 1;
            fl_log_clear(t->log);
        }
        for (int r = 0; r < FEMLOD_REJECT_COUNT; r++) S->rejected[r] += t->rejected[r];
        S->swept += t->swept;
        S->live -= t->removed;
        offset += t->collapses;
        done += t->done;
        if (t->stamp > S->stamp) S->stamp = t->stamp;
        for (size_t m = 0; m < t->deferred.n && !oom; m++)
            if (!u32vec_push(out, t->deferred.v[m])) oom = 1;
    }
    S->collapses += offset;
    if (n) S->nrefs = X->task[n - 1].refs_hi;
    if (oom) {
        S->oom = 1;
        return (size_t)-1;
    }
    return done;
}

/* One pass at threshold tau in parallel; returns the collapses, (size_t)-1
 * on ENOMEM, (size_t)-2 when cancelled. */
static size_t band_par_pass(simp *S, par_ctx *X, double tau, size_t floor_live, const femlod_simplify_options *o,
                            size_t live0, size_t *next) {
    X->tau = tau;
    float ftau = (float)tau;
    /* slabs along the longest axis of the grid */
    int ax = 0;
    for (int k = 1; k < 3; k++)
        if (S->grid.n[k] > S->grid.n[ax]) ax = k;
    uint32_t w = (uint32_t)((S->grid.n[ax] + PAR_MAX_SLABS - 1) / PAR_MAX_SLABS);
    if (w < PAR_SLAB_CELLS) w = PAR_SLAB_CELLS;
    S->slab_ax = ax;
    S->slab_w = w;
    /* stage 0's vertices: those a visit could collapse */
    u32vec *in = &X->tmp;
    in->n = 0;
#if FEMLOD_SIMPLIFY_STATS
    double tl0 = now_seconds();
#endif
    for (uint32_t v = 0; v < S->nv; v++) {
        if ((S->vflag[v] & V_DEAD) || !S->fcount[v]) continue;
        if (S->vlock[v] != S->pass && S->vbest[v] >= ftau && !u32vec_push(in, v)) return (size_t)-1;
    }
    STAT_TIME_ST(4, tl0);
    size_t done = 0;
    u32vec deferred = {NULL, 0, 0};
    for (int stage = 0; stage < 2; stage++) {
#if FEMLOD_SIMPLIFY_STATS
        S->stats.listed[stage] += in->n;
        double ts = now_seconds();
#endif
        S->slab_shift = stage ? w / 2 : 0;
#if FEMLOD_SIMPLIFY_STATS
        double tb0 = now_seconds();
#endif
        size_t nslab = par_bucket(X, in);
        STAT_TIME_ST(5, tb0);
        if (!nslab) {
            free(deferred.v);
            return (size_t)-1;
        }
        deferred.n = 0;
        for (unsigned col = 0; col < 2; col++) {
            if (S->live <= floor_live) break;
#if FEMLOD_SIMPLIFY_STATS
            double tt0 = now_seconds();
#endif
            size_t n = par_tasks(X, nslab, col, floor_live);
            STAT_TIME_ST(6, tt0);
            if (n == (size_t)-1) {
                free(deferred.v);
                return (size_t)-1;
            }
            if (!n) continue;
            if (!par_order(X, n)) {
                free(deferred.v);
                return (size_t)-1;
            }
#if FEMLOD_SIMPLIFY_STATS
            double tf = now_seconds();
#endif
            par_for(X, n, par_run_task);
            STAT_TIME_ST(3, tf);
#if FEMLOD_SIMPLIFY_STATS
            S->stats.listed[3]++;
#endif
#if FEMLOD_SIMPLIFY_STATS
            double tm0 = now_seconds();
#endif
            size_t c = par_merge(X, n, &deferred);
            STAT_TIME_ST(7, tm0);
            if (c == (size_t)-1) {
                free(deferred.v);
                return (size_t)-1;
            }
            done += c;
            if (progress(S, o, live0, next)) {
                free(deferred.v);
                return (size_t)-2;
            }
        }
        STAT_TIME_ST(stage, ts);
        /* the deferred are the next stage's vertices */
        u32vec t = *in;
        *in = deferred;
        deferred = t;
    }
    free(deferred.v);
#if FEMLOD_SIMPLIFY_STATS
    S->stats.listed[2] += in->n;
    double ts = now_seconds();
#endif
    /* the remainder, one by one as the sequential passes do */
    for (size_t x = 0; x < in->n && S->live > floor_live; x++) {
        uint32_t v = in->v[x];
        if ((S->vflag[v] & V_DEAD) || !S->fcount[v]) continue;
        if (S->vlock[v] == S->pass || !(S->vbest[v] >= ftau)) continue;
        int c = band_vertex(S, v, tau);
        if (c < 0) return (size_t)-1;
        if (c > 0) {
            done++;
            if (progress(S, o, live0, next)) return (size_t)-2;
        }
    }
    STAT_TIME_ST(2, ts);
    /* the grid follows the mesh's coarsening between passes */
#if FEMLOD_SIMPLIFY_STATS
    double tg0 = now_seconds();
#endif
    if (S->live * 4 < S->grid_live && S->live > 64 && !build_grid(S, S->grid_h * 2.0)) return (size_t)-1;
    STAT_TIME_ST(8, tg0);
    return done;
}

/* }====== */

/* Phase 1 in passes until at most floor_live triangles are left or no edge
 * is valid: every edge is evaluated once; then passes over the slots (in
 * Morton order: each collapse works next to the previous one's memory)
 * collapse each vertex's best edge whose key reaches the pass's threshold,
 * which starts at FEMLOD_SIMPLIFY_BAND times the best key and drops
 * by that factor per pass. Returns 0 on ENOMEM, 2 cancelled, 1 otherwise. */
static int band_run(simp *S, const femlod_simplify_options *o, size_t floor_live, size_t live0, size_t *next) {
    S->vlock = fl_populate(fl_calloc(S->nv, sizeof *S->vlock), S->nv * sizeof *S->vlock);
    S->vbest = fl_populate(fl_alloc(S->nv, sizeof *S->vbest), S->nv * sizeof *S->vbest);
    if (!S->vlock || !S->vbest) return 0;
    par_ctx X;
    memset(&X, 0, sizeof X);
    X.S = S;
    X.nw = S->nthreads < 1 ? 1 : (S->nthreads > 16 ? 16 : S->nthreads);
    X.wk = fl_calloc((size_t)X.nw, sizeof *X.wk);
    if (!X.wk) return 0;
    for (int t = 0; t < X.nw; t++) X.wk[t].X = &X;
    int ret = 0;
    for (size_t v = 0; v < S->nv; v++) S->vbest[v] = -1.0f;
#if FEMLOD_SIMPLIFY_STATS
    double t2 = now_seconds();
#endif
    /* every edge evaluated once, in parallel chunks */
    if (o->progress && o->progress(o->progress_payload, 0.0)) {
        ret = 2;
        goto done;
    }
    for (int t = 0; t < X.nw; t++) simp_view(&X.wk[t].W, S);
    par_for(&X, (S->ne + PAR_CHUNK - 1) / PAR_CHUNK, par_eval_chunk);
    for (int t = 0; t < X.nw; t++) {
        const simp *W = &X.wk[t].W;
        if (W->oom) goto done;
        for (int r = 0; r < FEMLOD_REJECT_COUNT; r++) S->rejected[r] += W->rejected[r];
    }
    float top = -1.0f;
    for (size_t ed = 0; ed < S->ne; ed++) {
        float key = S->edge[ed].key;
        uint32_t a = S->edge[ed].v[0], b = S->edge[ed].v[1];
        if (key > S->vbest[a]) S->vbest[a] = key;
        if (key > S->vbest[b]) S->vbest[b] = key;
        if (key > top) top = key;
    }
    double tau = (double)top * FEMLOD_SIMPLIFY_BAND;
    STAT_TIME(2, t2);
#if FEMLOD_SIMPLIFY_STATS
    S->stats.tpass = now_seconds();
#endif
#if FEMLOD_SIMPLIFY_STATS
    double t3 = now_seconds();
#endif
    while (top >= 0.0f && S->live > floor_live) {
        if (++S->pass == 0) { /* wrapped: unlock all */
            memset(S->vlock, 0, S->nv * sizeof *S->vlock);
            S->pass = 1;
        }
        size_t done = 0;
        top = -1.0f; /* the best key left below tau */
        if (S->live - floor_live >= PAR_MIN_LEFT) {
            size_t c = band_par_pass(S, &X, tau, floor_live, o, live0, next);
            if (c == (size_t)-1) goto done;
            if (c == (size_t)-2) {
                ret = 2;
                goto done;
            }
            done = c;
            for (uint32_t v = 0; v < S->nv && !done; v++)
                if (!(S->vflag[v] & V_DEAD) && S->fcount[v] && S->vbest[v] > top && S->vbest[v] < FLT_MAX)
                    top = S->vbest[v];
        } else {
            for (uint32_t v = 0; v < S->nv && S->live > floor_live; v++) {
                if ((S->vflag[v] & V_DEAD) || !S->fcount[v]) continue;
                if (S->vlock[v] != S->pass && S->vbest[v] >= (float)tau) {
                    int c = band_vertex(S, v, tau);
                    if (c < 0) goto done;
                    if (c > 0) {
                        done++;
                        if (progress(S, o, live0, next)) {
                            ret = 2;
                            goto done;
                        }
                        continue;
                    }
                }
                if (S->vbest[v] > top && S->vbest[v] < FLT_MAX) top = S->vbest[v];
            }
        }
#if FEMLOD_SIMPLIFY_STATS
        {
            double tn = now_seconds();
            fprintf(stderr, "pass %u tau %.4f live %zu collapses %zu seconds %.3f faults %ld\n", S->pass, tau, S->live,
                    done, tn - S->stats.tpass, minor_faults());
            S->stats.tpass = tn;
        }
#endif
        if (S->oom) goto done;
        /* next band; a pass without a collapse jumps to the best key left
         * (none left: done) */
        if (done) {
            tau *= FEMLOD_SIMPLIFY_BAND;
            top = 0.0f; /* keys changed: go on */
        } else {
            tau = mn(tau * FEMLOD_SIMPLIFY_BAND, (double)top);
        }
    }
    STAT_TIME(3, t3);
    /* back to the queue's conventions */
    for (size_t ed = 0; ed < S->ne; ed++) S->edge[ed].state &= (uint8_t)~E_STALE;
    free(S->vlock);
    free(S->vbest);
    S->vlock = NULL;
    S->vbest = NULL;
    ret = 1;
done:
    par_free(&X);
    return ret;
}

/* }====== */

static int finish(simp *S, const femlod_simplify_options *o, size_t live0, size_t *nextp,
                  femlod_stop_reason *why);

static int simplify_run(simp *S, const femlod_simplify_options *o, femlod_stop_reason *why, size_t *live0p,
                        size_t *nextp) {
    size_t live0 = S->live, next = 0;
    *live0p = live0;
    *why = FEMLOD_STOP_NO_VALID_EDGE;
    /* pre-phase (4.2.2): only edges of triangles below min_stretch */
#if FEMLOD_SIMPLIFY_STATS
    double t1 = now_seconds();
#endif
    if (S->st_on) {
        S->phase = 0;
        S->lim_st2 = -1.0; /* the pre-phase compares with the replaced faces instead */
        size_t queued = evaluate_all(S, o, 0.0);
        if (S->cancelled) {
            *why = FEMLOD_STOP_CANCELLED;
            return 2;
        }
        if (queued) {
            int r = run_queue(S, o, live0, &next);
            if (r != 1) {
                if (r == 2) *why = FEMLOD_STOP_CANCELLED;
                return r;
            }
        }
        while (fl_heap_size(&S->heap)) fl_heap_pop(&S->heap, NULL);
    }
    STAT_TIME(1, t1);
    S->phase = 1;
    S->lim_st2 = S->st_on ? S->minst2 : -1.0;
    if (S->fast > 0.0) {
        double fl = S->fast * (double)S->target;
        size_t floor_live = fl < (double)SIZE_MAX ? (size_t)fl : SIZE_MAX;
        if (S->live > floor_live) {
            int r = band_run(S, o, floor_live, live0, &next);
            if (r != 1) {
                if (r == 2) *why = FEMLOD_STOP_CANCELLED;
                return r;
            }
        }
    }
    *nextp = next;
    return finish(S, o, live0, nextp, why);
}

/* Every edge's refusals so far: the main thread's and evaluate_all's
 * workers' counts. */
static void rejected_total(const simp *S, size_t out[FEMLOD_REJECT_COUNT]) {
    memcpy(out, S->rejected, FEMLOD_REJECT_COUNT * sizeof *out);
    if (S->ectx)
        for (int t = 0; t < S->ectx->nw; t++)
            for (int k = 0; k < FEMLOD_REJECT_COUNT; k++) out[k] += S->ectx->wk[t].W.rejected[k];
}

/* The exact order down to S->target: evaluate everything not queued, run
 * the queue, again until the target or until a full evaluation queues
 * nothing. S->binding gets the check that refused most edges in that last
 * evaluation. Returns as simplify_run. */
static int finish(simp *S, const femlod_simplify_options *o, size_t live0, size_t *nextp,
                  femlod_stop_reason *why) {
    size_t next = *nextp;
#if FEMLOD_SIMPLIFY_STATS
    double t4 = now_seconds();
#endif
    size_t last_retry = (size_t)-1;
    size_t before[FEMLOD_REJECT_COUNT] = {0}, after[FEMLOD_REJECT_COUNT];
    *why = FEMLOD_STOP_NO_VALID_EDGE;
    for (;;) {
        if (S->live <= S->target) break;
        /* evaluate everything not queued: at the start, and again when the
         * queue runs dry, for edges refused for reasons outside their ring
         * (an intersection with a triangle that has moved away since) */
        if (last_retry == S->collapses) break;
        last_retry = S->collapses;
        size_t goal = live0 > S->prog_target ? live0 - S->prog_target : 1;
        double done = (double)(live0 - S->live) / (double)goal;
#if FEMLOD_SIMPLIFY_STATS
        double tq0 = now_seconds();
#endif
        rejected_total(S, before);
        size_t queued = evaluate_all(S, o, done > 1.0 ? 1.0 : done);
        if (S->cancelled) {
            *why = FEMLOD_STOP_CANCELLED;
            return 2;
        }
        if (!queued) break;
        if (S->oom) return 0;
#if FEMLOD_SIMPLIFY_STATS
        double tq1 = now_seconds();
        size_t c0 = S->collapses, e0 = S->stats.evals;
#endif
        int r = run_queue(S, o, live0, &next);
        *nextp = next;
#if FEMLOD_SIMPLIFY_STATS
        fprintf(stderr, "finish: evaluate_all %.3f s (%zu queued), queue %.3f s, %zu collapses, %.1f evals each (main thread)\n",
                tq1 - tq0, queued, now_seconds() - tq1, S->collapses - c0,
                (double)(S->stats.evals - e0) / (double)(S->collapses - c0 ? S->collapses - c0 : 1));
#endif
        if (r != 1) {
            if (r == 2) *why = FEMLOD_STOP_CANCELLED;
            return r;
        }
    }
    if (S->live <= S->target) *why = FEMLOD_STOP_TARGET;
    /* the check that refused most in the last round (no valid edge) */
    S->binding = FEMLOD_REJECT_COUNT;
    rejected_total(S, after);
    size_t most = 0;
    for (int k = 0; k < FEMLOD_REJECT_COUNT; k++)
        if (after[k] - before[k] > most) {
            most = after[k] - before[k];
            S->binding = k;
        }
    STAT_TIME(4, t4);
    return 1;
}

static femlod_status make_output(simp *S, femlod_mesh **out, femlod_collapse_log *log) {
    uint32_t *map = fl_populate(fl_alloc(S->nv, sizeof *map), S->nv * sizeof *map);
    if (!map) return FEMLOD_ENOMEM;
    /* output vertices in increasing node id: surviving input vertices in
     * input order, then the new ones in collapse order */
    mkey *order = fl_alloc(S->nv, sizeof *order);
    if (!order) {
        free(map);
        return FEMLOD_ENOMEM;
    }
    size_t nv = 0;
    for (size_t v = 0; v < S->nv; v++) {
        map[v] = UINT32_MAX;
        if (!(S->vflag[v] & V_DEAD) && S->fcount[v] > 0) {
            order[nv].key = S->node[v];
            order[nv].id = (uint32_t)v;
            nv++;
        }
    }
    qsort(order, nv, sizeof *order, cmp_mkey);
    for (size_t x = 0; x < nv; x++) map[order[x].id] = (uint32_t)x;
    free(order);
    femlod_mesh *m = fl_mesh_alloc(nv, S->live);
    if (!m) {
        free(map);
        return FEMLOD_ENOMEM;
    }
    for (size_t v = 0; v < S->nv; v++)
        if (map[v] != UINT32_MAX) memcpy(m->pos + 3 * (size_t)map[v], S->pos + 3 * v, 3 * sizeof(double));
    /* triangles in the order of the input triangles they descend from */
    uint32_t *byin = fl_populate(fl_alloc(S->nt_in, sizeof *byin), S->nt_in * sizeof *byin);
    if (!byin) {
        free(map);
        femlod_mesh_free(m);
        return FEMLOD_ENOMEM;
    }
    memset(byin, 0xff, S->nt_in * sizeof *byin);
    for (size_t f = 0; f < S->nt; f++)
        if (face_alive(S, (uint32_t)f)) byin[S->fin[f]] = (uint32_t)f;
    size_t w = 0;
    for (size_t x = 0; x < S->nt_in; x++) {
        uint32_t f = byin[x];
        if (f == UINT32_MAX) continue;
        for (int c = 0; c < 3; c++) m->tri[3 * w + c] = map[S->face[f].v[c]];
        w++;
    }
    free(byin);
    if (log) {
        log->out_nodes = fl_alloc(nv, sizeof *log->out_nodes);
        if (!log->out_nodes) {
            free(map);
            femlod_mesh_free(m);
            return FEMLOD_ENOMEM;
        }
        for (size_t v = 0; v < S->nv; v++)
            if (map[v] != UINT32_MAX) log->out_nodes[map[v]] = S->node[v];
        log->nv_out = nv;
    }
    free(map);
    *out = m;
    return FEMLOD_OK;
}

const char *femlod_stop_reason_name(femlod_stop_reason reason) {
    switch (reason) {
    case FEMLOD_STOP_TARGET: return "target";
    case FEMLOD_STOP_NO_VALID_EDGE: return "no_valid_edge";
    case FEMLOD_STOP_CANCELLED: return "cancelled";
    }
    return "unknown";
}

const char *femlod_reject_name(femlod_reject reason) {
    static const char *const names[FEMLOD_REJECT_COUNT] = {
        "tolerance", "deviation", "stretch", "size", "valence", "foldover", "topology", "intersection"};
    return (unsigned)reason < FEMLOD_REJECT_COUNT ? names[reason] : "unknown";
}

static double now_seconds(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* After a large run, gives the freed working memory back to the system.
 * glibc raises its mmap threshold as large blocks are freed (up to 32 MB),
 * so the next run's arrays come from the heap, around blocks still in use,
 * and what a run frees stays resident: measured on cover.obj subdivided once
 * (311k triangles) to 12,000, nine runs in one process, peak resident 101 ->
 * 131 MB and 30 -> 112 MB still resident after a run; with this call the
 * peak stays at 101-104 MB and 13-14 MB after each run (docs/simplify.md,
 * "Memory across runs"). Runs below 65,536 triangles skip it (a sweep of
 * small runs should not pay for a heap walk each time). */
static void release_freed_memory(size_t triangles) {
#if defined(__GLIBC__)
    if (triangles >= 65536) (void)malloc_trim(0);
#else
    (void)triangles;
#endif
}

femlod_status femlod_simplify(femlod_mesh **out, femlod_collapse_log **out_log, const femlod_mesh *mesh,
                              const femlod_simplify_options *options, femlod_simplify_result *result,
                              femlod_error *err) {
    assert(out && mesh); /* femlod.h: NULL handles are programming errors */
    double t0 = now_seconds();
    femlod_simplify_options defaults = FEMLOD_SIMPLIFY_OPTIONS_INIT;
    const femlod_simplify_options *o = options ? options : &defaults;
    simp *S = calloc(1, sizeof *S);
    if (!S) return fl_error(err, FEMLOD_ENOMEM, "simplify: out of memory");
    size_t dropped = 0;
    femlod_status st = setup(S, mesh, o, &dropped, err);
    STAT_TIME(0, t0);
    if (st != FEMLOD_OK) {
        simp_free(S);
        free(S);
        return st;
    }
    if (out_log) {
        S->log = fl_log_new(mesh->nv, S->nt / 2 + 16);
        if (!S->log) {
            simp_free(S);
            free(S);
            return fl_error(err, FEMLOD_ENOMEM, "simplify: out of memory");
        }
    }
    /* Past the target (docs/design.md "The hierarchy below the target"):
     * the output is taken at the target, then the exact order goes on down
     * to the floor, extending only the log. */
    size_t floor_live = 0;
    int extend = S->log && o->hierarchy_floor > 0 && S->target > 0 && o->hierarchy_floor < S->target;
    if (extend) floor_live = o->hierarchy_floor;
    S->prog_target = extend ? floor_live : S->target;
    femlod_stop_reason why = FEMLOD_STOP_NO_VALID_EDGE, hwhy;
    size_t live0 = 0, next = 0;
    int r = simplify_run(S, o, &why, &live0, &next);
    femlod_mesh *m = NULL;
    double t5 = now_seconds();
    (void)t5;
    size_t out_collapses = S->collapses, out_rejected[FEMLOD_REJECT_COUNT];
    rejected_total(S, out_rejected);
    if (r == 0 || make_output(S, &m, S->log) != FEMLOD_OK) {
        femlod_collapse_log_free(S->log);
        simp_free(S);
        free(S);
        return fl_error(err, FEMLOD_ENOMEM, "simplify: out of memory");
    }
    hwhy = why;
    if (S->log) {
        S->log->prephase = S->prephase;
        S->log->front = S->collapses;
        S->log->binding = why == FEMLOD_STOP_NO_VALID_EDGE ? S->binding : FEMLOD_REJECT_COUNT;
    }
    if (extend && r == 1 && why == FEMLOD_STOP_TARGET) {
        size_t target0 = S->target;
        S->target = floor_live;
        r = finish(S, o, live0, &next, &hwhy);
        if (r == 0) {
            femlod_mesh_free(m);
            femlod_collapse_log_free(S->log);
            simp_free(S);
            free(S);
            return fl_error(err, FEMLOD_ENOMEM, "simplify: out of memory");
        }
        /* a cancel here keeps the result at the target: the log is as far
         * as it got, every state of it valid */
        S->log->binding = hwhy == FEMLOD_STOP_NO_VALID_EDGE ? S->binding : FEMLOD_REJECT_COUNT;
        S->target = target0;
    }
#if FEMLOD_SIMPLIFY_STATS
    STAT_TIME(5, t5);
    fprintf(stderr, "simplify seconds: setup %.3f pre-phase %.3f first evaluation %.3f passes %.3f queue %.3f output %.3f\n",
            S->stats.t[0], S->stats.t[1], S->stats.t[2], S->stats.t[3], S->stats.t[4], S->stats.t[5]);
    fprintf(stderr, "busy in tasks per worker: %.3f %.3f %.3f %.3f; waiting for the last thread at the end of parallel steps: %.3f thread-seconds\n", S->stats.tstage[10], S->stats.tstage[11], S->stats.tstage[12], S->stats.tstage[13], S->stats.tstage[30]);
    fprintf(stderr, "band attempts %zu, below tau on re-evaluation %zu\n", S->stats.attempts, S->stats.attempt_low);
    fprintf(stderr, "parallel passes: listed %zu / %zu / %zu, seconds %.3f / %.3f / %.3f; %zu sub-passes, %.3f s in tasks\n", S->stats.listed[0],
            S->stats.listed[1], S->stats.listed[2], S->stats.tstage[0], S->stats.tstage[1], S->stats.tstage[2], S->stats.listed[3], S->stats.tstage[3]);
    fprintf(stderr, "outside tasks: listing %.3f bucket %.3f tasks %.3f (compaction %.3f) merge %.3f grid %.3f\n", S->stats.tstage[4], S->stats.tstage[5], S->stats.tstage[6], S->stats.tstage[9], S->stats.tstage[7], S->stats.tstage[8]);
    {
        const simp_stats *c = &S->stats;
        double n = S->collapses ? (double)S->collapses : 1.0;
        fprintf(stderr,
                "simplify stats per collapse (%zu): bounds %.2f evals %.2f (settle %.2f, prefix fail %.2f) cands %.2f (ok %.2f) "
                "solves %.2f pops %.2f links %.2f expensive %.2f cells %.1f items %.1f tritri %.1f skipped %.2f deferred %.2f planar %.2f\n",
                S->collapses, (double)c->bounds / n, (double)c->evals / n, (double)c->settles / n, (double)(c->evals + c->bounds - c->rings) / n,
                (double)c->cands / n, (double)c->cand_ok / n, (double)c->solves / n, (double)c->pops / n,
                (double)c->links / n, (double)c->expensive / n, (double)c->cells / n, (double)c->items / n,
                (double)c->tritri / n, (double)c->skipped / n, (double)c->deferred / n, (double)c->planar / n);
    }
#endif
    if (result) {
        memset(result, 0, sizeof *result);
        result->triangles = m->nt;
        result->vertices = m->nv;
        result->stop_reason = why;
        result->collapses = out_collapses;
        result->prephase_collapses = S->prephase;
        result->fast_collapses = S->swept;
        memcpy(result->rejected, out_rejected, sizeof result->rejected);
        result->hierarchy_triangles = S->live;
        result->hierarchy_stop = hwhy;
        result->hierarchy_binding = S->log ? S->log->binding : FEMLOD_REJECT_COUNT;
        size_t bad = 0;
        for (size_t f = 0; f < m->nt; f++) {
            const uint32_t *t = m->tri + 3 * f;
            double sz;
            double stv = tri_stretch(m->pos + 3 * (size_t)t[0], m->pos + 3 * (size_t)t[1], m->pos + 3 * (size_t)t[2], &sz);
            if ((S->st_on && stv < S->minst) || (S->sz_on && sz > S->maxsz)) bad++;
        }
        result->violating_input = bad;
        result->dropped_degenerate = dropped;
        result->target = S->target;
        result->tolerance = S->tol_on ? S->tol : FEMLOD_SIMPLIFY_OFF;
        result->max_deviation = S->dev_on ? S->maxdev : FEMLOD_SIMPLIFY_OFF;
        result->min_stretch = S->st_on ? S->minst : FEMLOD_SIMPLIFY_OFF;
        result->max_size = S->sz_on ? S->maxsz : FEMLOD_SIMPLIFY_OFF;
        result->feature_angle = S->feat_angle > 0.0 ? S->feat_angle : FEMLOD_SIMPLIFY_OFF;
        result->feature_weight = S->feat_w > 0.0 ? S->feat_w : FEMLOD_SIMPLIFY_OFF;
        result->max_normal_change = S->cone_on ? S->max_nc : FEMLOD_SIMPLIFY_OFF;
        result->max_valence = S->val_on ? S->maxval : -1;
        result->fast_above = S->fast > 0.0 ? S->fast : FEMLOD_SIMPLIFY_OFF;
        result->threads = S->nthreads;
        result->seconds = now_seconds() - t0;
    }
    *out = m;
    if (out_log) *out_log = S->log;
    size_t big = S->nt;
    simp_free(S);
    free(S);
    release_freed_memory(big);
    return FEMLOD_OK;
}

/* }====== */
