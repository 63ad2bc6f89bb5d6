/*
 * simp.h - what the simplifier's files share (internal to src/simplify/):
 * the run's state (simp), an edge's gathered ring, the face and edge
 * records, the flags, the hot inline helpers, the cross-file functions
 * (fl_simp_*, fl_pool_*) and the stats build's counters.
 *
 * Files, each calling only those below it (docs/design.md "The simplifier's
 * files"):
 *
 *   simplify.c        driver: options, the phases, the output
 *   fast.c            the fast passes in priority bands, serial and parallel
 *   queue.c           the exact queue: collapse, re-evaluation, its helper thread
 *   candidate.c       an edge's evaluation: ring, candidates, C1-C4, priority, pop-time checks
 *   intersect_grid.c  the intersection test and the face grid it reads
 *   setup.c           the set-up of simp from the input mesh; per-thread views
 *   pool.c            every thread the simplifier starts
 *
 * Invariants every file keeps: results are bit for bit the same for every
 * thread count and build type (every choice that could depend on order is
 * made on indices; -ffp-contract=off); a vertex's face list is in
 * increasing face order at set-up and keeps its order after (the order of
 * sums); the face cache (normal, size, 1 / size) is a function of the
 * face's corners, refreshed whenever they move.
 */
#ifndef FEMLOD_SIMP_H
#define FEMLOD_SIMP_H

#include "../core.h"
#include "../heap.h"
#include "../intersect.h"
#include "../quadric.h"
#include "../simplify_log.h"
#include "../vec3.h"

#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>
#include <time.h>

#define PI 3.14159265358979323846

/* Tunables used by more than one file (each file's own are at its top),
 * fixed by the measurements in docs/simplify.md; -D overrides them for
 * experiments only. */
#ifndef FEMLOD_SIMPLIFY_BOUND
#define FEMLOD_SIMPLIFY_BOUND 0 /* 1: exact lazy re-evaluation with upper bounds (docs/simplify.md: fewer evaluations, more time) */
#endif
/* -DFEMLOD_SIMPLIFY_C1_SKIP=0: every edge evaluated at each round of
 * error_order's cap, none skipped by fl_simp_c1_holds; for
 * tests/c/scan_digest.c, which checks that both give byte-identical
 * results and counts (tests/CMakeLists.txt). */
#ifndef FEMLOD_SIMPLIFY_C1_SKIP
#define FEMLOD_SIMPLIFY_C1_SKIP 1
#endif
/* -DFEMLOD_SIMPLIFY_STATS=1: count the work (evaluations, checks, grid
 * visits) per run in simp.stats and print it to stderr; for measurements
 * only (docs/simplify.md). No global state: the counters live in the run. */
#ifndef FEMLOD_SIMPLIFY_STATS
#define FEMLOD_SIMPLIFY_STATS 0
#endif
/* error_order's schedule (docs/simplify.md "The error order"): the first
 * cap, times the mean input edge squared; the factor it rises by; the
 * least stretch of a new triangle while it runs */
#ifndef FEMLOD_SIMPLIFY_CAP0
#define FEMLOD_SIMPLIFY_CAP0 1e-6
#endif
#ifndef FEMLOD_SIMPLIFY_CAP_RATE
#define FEMLOD_SIMPLIFY_CAP_RATE 16.0
#endif
#ifndef FEMLOD_SIMPLIFY_CAP_STRETCH
#define FEMLOD_SIMPLIFY_CAP_STRETCH 0.4
#endif

static inline double now_seconds(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

#if FEMLOD_SIMPLIFY_STATS
#include <stdio.h>
#include <sys/resource.h> /* getrusage: the stats build's fault counts */
#define STAT(x) ((void)(S->stats.x++))
#define STAT_TIME(k, t0) ((void)(S->stats.t[k] += now_seconds() - (t0)))
#define STAT_TIME_ST(k, t0) ((void)(S->stats.tstage[k] += now_seconds() - (t0)))
/* where fl_pool_for adds the thread-seconds spent waiting for its last thread */
#define STAT_WAIT(S) (&(S)->stats.tstage[30])
/* the process's page faults so far (minor: first touches of fresh pages,
 * which cost 10-28 microseconds each on the VMs measured: error.c) */
static inline long minor_faults(void) {
    struct rusage u;
    getrusage(RUSAGE_SELF, &u);
    return u.ru_minflt;
}
#else
#define STAT_TIME(k, t0) ((void)0)
#define STAT_TIME_ST(k, t0) ((void)0)
#define STAT(x) ((void)0)
#define STAT_WAIT(S) ((double *)NULL)
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
    E_OPTC = 32,
    /* last evaluation (phase 1 of error_order): every candidate failed C1,
     * and the key is minus a lower bound of their least C1 error; holds
     * while i and j do (fl_simp_evaluate writes the key of a refused edge) */
    E_C1KEY = 64
};

#define NO_REASON (-1)
/* a fast-pass worker may not do this collapse in its slab: band_par's
 * sequential remainder will (never counted as a rejection) */
#define DEFER_REASON FEMLOD_REJECT_COUNT
#define MAX_VSTARS 253

/* An edge (i, j) gathered for evaluation (candidate.c), and what the last
 * evaluation found. */
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
    size_t dev_queries, dev_nodes, dev_tris;
    size_t deferred;
    size_t attempts, attempt_low, attempt_fresh;
    double t[6]; /* seconds: setup, pre-phase, first evaluation of the passes, passes, queue, output */
    size_t listed[4]; /* parallel passes: vertices listed in stage 0, 1, the remainder; sub-passes */
    /* and their seconds; [3]: in par_for; [4..9]: listing, bucketing, task
     * set-up, merge, grid rebuilds, compactions; [10 + t]: worker t's
     * seconds in tasks; [30]: thread-seconds spent waiting for the last
     * thread at the end of a fl_pool_for */
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
    double *devbox; /* deviation.c: per ring face the box of its new triangle */
    size_t devbox_cap;
    uint32_t dev_hint; /* deviation.c: the input tree's leaf to try first (speed only) */
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
    /* the error order (error_order: queue.c, docs/design.md "An order that
     * knows the error"): C1's limit in force, the tolerance or the
     * schedule's cap below it (lim_on 0: none); the first cap and the
     * largest (without a tolerance) */
    double lim_tol, cap0, cap_end;
    int lim_on, sched;
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
     * (NaN for degenerate) and 1 / its longest edge (for Sz_DIF): one 32-byte record,
     * so that the corners' read brings the rest (64-byte aligned) */
    face_rec *face;
    uint32_t *tedge;
    uint32_t *fin; /* input triangle index of each face slot */
    float *cone; /* axis xyz, half-angle (radians) */
    uint32_t *fmark; /* set-up only: the pinched-vertex flood (with vertex stamps) */
    uint8_t *fmade; /* 1: made by a collapse, not read from the input (plane_rule) */
    /* deviation (deviation.c): per face its first input sample, per sample
     * the next of its face's list (ids below nv: input vertices, the rest
     * spos's points); the input tree; the sample spacing */
    uint32_t *fpt;
    uint32_t *pnext;
    double *spos;
    size_t nsamp;
    struct dev_tree *dtree;
    double dev_h, dev_r2; /* spacing; the samples' limit, squared */

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
    scratch sc;  /* each thread's own (fl_simp_view keeps it) */
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
    struct u32vec *klist;
    /* the exact queue's ring re-evaluation on two threads (ring_eval): the
     * helper, and per listed edge what to do, its priority and C1 flag */
    struct eval_helper *helper;
    struct eval_team *ectx; /* evaluate_all's threads (eval_range) */
    uint32_t *rlist;
    uint8_t *rkind, *rtol;
    double *rrho;
    size_t rlist_cap, rkind_cap, rtol_cap, rrho_cap;
    femlod_collapse_log *log;
    size_t collapses, prephase;
    size_t rejected[FEMLOD_REJECT_COUNT];
    int binding;        /* the check that refused most in the finish's last round (simplify.c) */
    size_t prog_target; /* the count progress is measured towards: target, or the floor past it */
    int oom;
    int cancelled;  /* the progress callback asked to stop during evaluate_all */
#if FEMLOD_SIMPLIFY_STATS
    simp_stats stats;
#endif
} simp;

/* A sort key and its item: Morton order (setup.c), output order (simplify.c). */
typedef struct mkey {
    uint64_t key;
    uint32_t id;
} mkey;

/* What the set-up measures of the input, for the options' defaults. */
typedef struct simp_measure {
    double diag, mean_edge, size_max;
} simp_measure;

/* {====== hot helpers, inline in every file */

/* fmin/fmax are calls (NaN rules); no NaN reaches these */
static inline double mn(double a, double b) { return a < b ? a : b; }
static inline double mx(double a, double b) { return a > b ? a : b; }

static inline const double *P(const simp *S, uint32_t v) { return S->pos + 3 * (size_t)v; }

static inline int face_alive(const simp *S, uint32_t f) { return S->face[f].v[0] != UINT32_MAX; }

/* An edge, up to date but for its ends' neighbourhoods, whose last
 * evaluation found every candidate above C1's present limit (E_C1KEY): it
 * would again (docs/design.md "Cap rounds without the evaluations that
 * cannot change"). */
static inline int fl_simp_c1_holds(const simp *S, const edge_rec *E) {
    return FEMLOD_SIMPLIFY_C1_SKIP && (E->state & E_C1KEY) && S->lim_on && -(double)E->key > S->lim_tol;
}

/* Stretch (4.1 3), method-notes "Element measures") from the corners. */
static inline double tri_stretch(const double *a, const double *b, const double *c, double *size) {
    double la = sqrt(dist2(b, c)), lb = sqrt(dist2(a, c)), lc = sqrt(dist2(a, b));
    double L = mx(la, mx(lb, lc));
    if (size) *size = L;
    double s = 0.5 * (la + lb + lc);
    if (!(L > 0.0) || !(s > 0.0)) return 0.0;
    double r2 = (s - la) * (s - lb) * (s - lc) / s;
    if (!(r2 > 0.0)) return 0.0;
    return sqrt(12.0 * r2) / L;
}

static inline void face_bbox(const simp *S, uint32_t f, double lo[3], double hi[3]) {
    const uint32_t *t = S->face[f].v;
    const double *a = P(S, t[0]), *b = P(S, t[1]), *c = P(S, t[2]);
    for (int k = 0; k < 3; k++) {
        lo[k] = mn(a[k], mn(b[k], c[k]));
        hi[k] = mx(a[k], mx(b[k], c[k]));
    }
}

/* The face cache of f from its corners: unit normal, the inverse of the
 * longest edge (set-up, and each face a collapse moves); returns the
 * longest edge (a float: inv is 1 / that float). */
static inline float face_update_cache(simp *S, uint32_t f) {
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
    float size = (float)sqrt(L2);
    S->face[f].inv = 1.0 / (double)size;
    return size;
}

/* Grows *p to at least n elements of elem bytes (doubling); 0 on ENOMEM. */
static inline int buf_reserve(void **p, size_t *cap, size_t n, size_t elem) {
    if (n <= *cap) return 1;
    size_t c = *cap ? *cap : 64;
    while (c < n) c *= 2;
    void *q = fl_realloc(*p, c, elem);
    if (!q) return 0;
    *p = q;
    *cap = c;
    return 1;
}

/* A fresh mark value for vmark and emark (cleared when it wraps). */
static inline uint32_t next_stamp(simp *S) {
    if (++S->stamp == 0) { /* wrapped: clear */
        memset(S->vmark, 0, S->nv * sizeof *S->vmark);
        memset(S->emark, 0, S->ne * sizeof *S->emark);
        S->stamp = 1;
    }
    return S->stamp;
}

/* The slab (band_par) of a grid cell coordinate and of a point. */
static inline uint32_t slab_of_cell(const simp *S, int c) { return ((uint32_t)c + S->slab_shift) / S->slab_w; }
static inline uint32_t slab_of(const simp *S, const double *p) {
    return slab_of_cell(S, fl_grid_coord(&S->grid, p[S->slab_ax], S->slab_ax));
}

/* }====== */

/* {====== fast.c: the fast passes */

/* Phase 1 in priority bands until at most floor_live triangles are left
 * or no edge is valid. 0 on ENOMEM, 2 cancelled, 1 otherwise. */
FL_INTERNAL int fl_simp_band_run(simp *S, const femlod_simplify_options *o, size_t floor_live, size_t live0,
                                 size_t *next);

/* }====== */

/* {====== queue.c: the exact queue */

/* Pops edges until the target or an empty queue. 0 on ENOMEM, 2 when
 * cancelled, 1 otherwise. */
FL_INTERNAL int fl_simp_run_queue(simp *S, const femlod_simplify_options *o, size_t live0, size_t *next);
/* C1's limit and C2's for the phase S->phase: the tolerance and
 * min_stretch, or with error_order in phase 1 the schedule's first cap and
 * its stretch floor. */
FL_INTERNAL void fl_simp_start_cap(simp *S);
/* The schedule's next cap (the last: the tolerance, and min_stretch
 * again); 0 when the schedule is over or off. */
FL_INTERNAL int fl_simp_raise_cap(simp *S);
/* Queues every live edge not queued (in the pre-phase: those of a triangle
 * below min_stretch) that has a valid candidate; returns how many. */
FL_INTERNAL size_t fl_simp_evaluate_all(simp *S, const femlod_simplify_options *o, double done);
/* Frees evaluate_all's threads' views. */
FL_INTERNAL void fl_simp_free_eval(simp *S);
/* Collapses the gathered edge to candidate c (4.2 step 4), logs it (5.1).
 * 0 on ENOMEM. */
FL_INTERNAL int fl_simp_collapse(simp *S, ring *R, int c);
/* Calls the progress callback at each further 1% of the collapses to do;
 * nonzero when it asked to stop. */
FL_INTERNAL int fl_simp_progress(simp *S, const femlod_simplify_options *o, size_t live0, size_t *next);

/* }====== */

/* {====== candidate.c: an edge's evaluation and the pop-time checks */

/* The best priority of edge e (< 0: no valid candidate), its candidates
 * left in R, the best valid one first. */
FL_INTERNAL double fl_simp_evaluate(simp *S, ring *R, uint32_t e);
/* gather's first topology checks, apart (candidate.c) */
enum { FL_TOPO_NONMANIFOLD = 0, FL_TOPO_FEATURE = 1, FL_TOPO_BOUNDARY = 2 };
FL_INTERNAL int fl_simp_topology_kind(const simp *S, uint32_t e);
/* An upper bound of fl_simp_evaluate's priority for an edge away from the
 * last collapse's vertex k (the lazy queue, FEMLOD_SIMPLIFY_BOUND). */
FL_INTERNAL double fl_simp_bound_edge(simp *S, ring *R, uint32_t e, uint32_t k);
/* The link condition on the gathered ring: NO_REASON or the reason. */
FL_INTERNAL int fl_simp_link_check(simp *S, const ring *R);
/* Candidate c passes the checks too costly for every evaluation: normal
 * cones, deviation, intersection. NO_REASON, DEFER_REASON or the reason. */
FL_INTERNAL int fl_simp_expensive_checks(simp *S, ring *R, int c);

/* }====== */

/* {====== deviation.c: max_deviation's samples and input tree */

/* The input samples in the per-face lists and the input tree (after the
 * features: reads the faces, edges and positions of the set-up). */
FL_INTERNAL femlod_status fl_simp_setup_deviation(simp *S, double mean_edge, femlod_error *err);
FL_INTERNAL void fl_simp_free_deviation(simp *S);
/* The collapse of R to p keeps both invariants of docs/design.md "A
 * distance bound that holds"; *np gets the samples gathered (their new
 * faces in sc.pdst, for fl_simp_collapse). NO_REASON or the reason. */
FL_INTERNAL int fl_simp_deviation_check(simp *S, ring *R, const double p[3], size_t *np);

/* }====== */

/* {====== intersect_grid.c: the intersection test and its grid */

/* No new triangle of the collapse of R to p crosses the mesh. */
FL_INTERNAL int fl_simp_intersect_check(simp *S, ring *R, const double p[3]);
/* (Re)builds the grid of the live faces with cell edge h; 0 on ENOMEM. */
FL_INTERNAL int fl_simp_build_grid(simp *S, double h);
/* Takes face f out of the grid (its corners where they were inserted). */
FL_INTERNAL void fl_simp_grid_remove_face(simp *S, uint32_t f);

/* }====== */

/* {====== setup.c: the set-up and the per-thread views */

/* Vertices (Morton order), faces, face lists, face caches, edges; measures
 * the input into *m. */
FL_INTERNAL femlod_status fl_simp_setup_mesh(simp *S, const femlod_mesh *mesh, const femlod_simplify_options *o,
                                             size_t *dropped, simp_measure *m, femlod_error *err);
/* After the options are resolved: boundary and non-manifold vertices,
 * quadrics, features, fixed vertices and locks, cones, deviation lists,
 * the queue. */
FL_INTERNAL femlod_status fl_simp_setup_features(simp *S, const femlod_mesh *mesh, const femlod_simplify_options *o,
                                                 femlod_error *err);
/* Moves every live face list to the front of the arena, in place, and
 * resizes it to two thirds spare; 0 on ENOMEM. */
FL_INTERNAL int fl_simp_compact_refs(simp *S);
/* w becomes a view of the run with its own ring and scratch kept. */
FL_INTERNAL void fl_simp_view(simp *w, const simp *S);
/* Frees a view's (or the run's) ring and scratch. */
FL_INTERNAL void fl_simp_free_scratch(simp *S);
/* Frees n views of S (the stats build adds their counts to S's). */
FL_INTERNAL void fl_simp_free_views(simp *S, simp *W, int n);

/* }====== */

/* {====== pool.c: threads */

/* fn(ctx, worker, k) for every k < n, on up to nw threads (the caller is
 * worker 0); wait: when not NULL, gets the thread-seconds threads spent
 * waiting for the last one added. */
typedef void (*fl_pool_fn)(void *ctx, int worker, size_t k);
FL_INTERNAL void fl_pool_for(int nw, size_t n, fl_pool_fn fn, void *ctx, double *wait);
/* fn over [0, n) in fl_pool_parts(nth, n) contiguous parts, part t being
 * [fl_pool_part_lo(n, parts, t), fl_pool_part_lo(n, parts, t + 1)). */
typedef void (*fl_pool_range_fn)(void *ctx, size_t lo, size_t hi, int part);
FL_INTERNAL void fl_pool_ranges(int nth, size_t n, fl_pool_range_fn fn, void *ctx);
FL_INTERNAL int fl_pool_parts(int nth, size_t n);
FL_INTERNAL size_t fl_pool_part_lo(size_t n, int parts, int t);
/* A long-lived thread that runs job(arg) after each post (posts made while
 * it runs may be merged into one run). NULL when it cannot start. */
typedef struct fl_pool_helper fl_pool_helper;
FL_INTERNAL fl_pool_helper *fl_pool_helper_start(void (*job)(void *), void *arg);
FL_INTERNAL void fl_pool_helper_post(fl_pool_helper *h);
FL_INTERNAL void fl_pool_helper_stop(fl_pool_helper *h);
/* One step of a wait loop: a pause, and every 2,000 a yield of the core. */
FL_INTERNAL void fl_pool_backoff(int *spins);
/* The default thread count (options.threads 0): fl_pool_threads_for_load
 * of the online processors and the other runnable tasks at the start. */
FL_INTERNAL int fl_pool_default_threads(void);
/* The processors that `others` runnable tasks leave: np - floor(others),
 * at least 1 and at most min(np, 16) (docs/design.md "Threads on a shared
 * machine"). */
FL_INTERNAL int fl_pool_threads_for_load(long np, double others);

/* }====== */

#endif
