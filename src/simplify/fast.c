/*
 * fast.c - the fast passes (fast_above; docs/simplify.md "Fast passes"):
 * above fast_above x target triangles, passes over the vertex slots in
 * priority bands replace the exact greedy order; every collapse still
 * goes through every check.
 *
 *   band_vertex        one visit: v's out-of-date edge keys evaluated, its
 *                      best edge collapsed when its key reaches the pass's
 *                      threshold
 *   band_par_pass      one pass on the run's threads: slabs of the grid's
 *                      longest axis as tasks, two stages of two colours,
 *                      then the deferred vertices one by one (docs/design.md
 *                      "Parallel fast passes")
 *   fl_simp_band_run   the first evaluation of every edge, then passes with
 *                      a threshold falling by FEMLOD_SIMPLIFY_BAND
 *
 * Invariants: the result depends on the slabs, never on the threads or
 * their timing: a worker collapses only inside its slab (par_star_readable,
 * par_ring_owned, par_candidate_ok, the intersection test's cell range) and
 * defers the rest; the tasks of a sub-pass share no data they write, and
 * par_merge folds them in slab order (node ids, logs, counts). Between
 * passes an edge's key is its last evaluated priority, E_STALE when an
 * endpoint has moved since; the passes leave no E_STALE behind.
 */
#include "simp.h"

#include <float.h>
#include <stdlib.h>

#ifndef FEMLOD_SIMPLIFY_BAND
#define FEMLOD_SIMPLIFY_BAND 0.9 /* each pass lowers the threshold by this factor */
#endif
#ifndef FEMLOD_SIMPLIFY_DEFER
/* A stale edge whose last key is below this times the pass's threshold is
 * not evaluated at a visit (0: every stale edge is). Measured on cover x4
 * (docs/simplify.md, the deferral): 11.1 -> 9.7 evaluations per collapse,
 * and the best minimum stretch of the factors tried (0.75-1.1) */
#define FEMLOD_SIMPLIFY_DEFER 0.85
#endif
/* -DFEMLOD_SIMPLIFY_MARKED_SCAN=1: band_vertex finds every vertex's edges
 * by the marked scan, as at boundary, non-manifold and unoriented vertices,
 * instead of one side per face; for tests/c/scan_digest.c, which checks
 * that the two scans give byte-identical results (tests/CMakeLists.txt). */
#ifndef FEMLOD_SIMPLIFY_MARKED_SCAN
#define FEMLOD_SIMPLIFY_MARKED_SCAN 0
#endif

typedef struct u32vec {
    uint32_t *v;
    size_t n, cap;
} u32vec;

static int u32vec_push(u32vec *a, uint32_t x) {
    if (a->n == a->cap && !buf_reserve((void **)&a->v, &a->cap, a->n + 1, sizeof *a->v)) return 0;
    a->v[a->n++] = x;
    return 1;
}

/* {====== one visit */

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
                rnow = fl_simp_evaluate(S, R, ed);
                if (S->oom) return -1;
                if (rnow >= 0.0) S->edge[ed].key = (float)rnow; /* refused: evaluate wrote the key */
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
        rho = fl_simp_evaluate(S, R, best);
    }
#if FEMLOD_SIMPLIFY_STATS
    if (rho < tau) S->stats.attempt_low++;
#endif
    if (S->oom) return -1;
    if (rho >= 0.0) S->edge[best].key = (float)rho;
    if (S->par && rho >= tau && !par_ring_owned(S, R)) return 2;
    int chosen = -1;
    if (rho >= tau && fl_simp_link_check(S, R) == NO_REASON) {
        for (int c = 0; c < R->ncand && chosen < 0; c++) {
            if (!R->ok[c] || R->rho[c] < tau) continue;
            if (S->par && !par_candidate_ok(S, R, R->cand[c])) return 2;
            int w = fl_simp_expensive_checks(S, R, c);
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
    if (!fl_simp_collapse(S, R, chosen)) return -1;
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

/* }====== */

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

typedef struct par_ctx {
    simp *S;
    simp *wk; /* per thread: its view of the run, with its own scratch */
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
} par_ctx;

static void par_free(par_ctx *X) {
    fl_simp_free_views(X->S, X->wk, X->nw);
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

/* The first evaluation of the passes, chunk k of the edges: every edge is
 * evaluated on its own (evaluate writes only the edge's record and cached
 * optimum). At a raise of error_order's cap, an edge whose candidates all
 * failed C1 below the new cap (fl_simp_c1_holds) is not evaluated: they
 * fail again, and the edge is counted as that evaluation would count it. */
static void par_eval_chunk(void *arg, int worker, size_t k) {
    par_ctx *X = arg;
    simp *S = X->S, *W = &X->wk[worker];
    size_t e0 = k * PAR_CHUNK, e1 = e0 + PAR_CHUNK < S->ne ? e0 + PAR_CHUNK : S->ne;
    for (size_t ed = e0; ed < e1 && !W->oom; ed++) {
        edge_rec *E = S->edge + ed;
        if (E->flag & E_DEAD) {
            E->key = -1.0f;
            continue;
        }
        if (!(E->state & E_STALE) && fl_simp_c1_holds(S, E)) {
            W->rejected[FEMLOD_REJECT_TOLERANCE]++;
            continue;
        }
        double rho = fl_simp_evaluate(W, &W->R, (uint32_t)ed);
        if (rho >= 0.0) E->key = (float)rho; /* refused: evaluate wrote the key */
    }
}

/* Every live edge evaluated (its key), in parallel chunks, each vertex's
 * best key and the best of all into *top; 0 on ENOMEM. At the start of
 * the passes, and again when error_order's cap rises. */
static int band_eval_all(simp *S, par_ctx *X, float *top) {
    for (size_t v = 0; v < S->nv; v++) S->vbest[v] = -1.0f;
    for (int t = 0; t < X->nw; t++) {
        fl_simp_view(&X->wk[t], S);
        memset(X->wk[t].rejected, 0, sizeof X->wk[t].rejected);
    }
    fl_pool_for(X->nw, (S->ne + PAR_CHUNK - 1) / PAR_CHUNK, par_eval_chunk, X, STAT_WAIT(S));
    for (int t = 0; t < X->nw; t++) {
        const simp *W = &X->wk[t];
        if (W->oom) return 0;
        for (int r = 0; r < FEMLOD_REJECT_COUNT; r++) S->rejected[r] += W->rejected[r];
    }
    *top = -1.0f;
    for (size_t ed = 0; ed < S->ne; ed++) {
        S->edge[ed].state &= (uint8_t)~E_STALE; /* every key is fresh */
        float key = S->edge[ed].key;
        uint32_t a = S->edge[ed].v[0], b = S->edge[ed].v[1];
        if (key > S->vbest[a]) S->vbest[a] = key;
        if (key > S->vbest[b]) S->vbest[b] = key;
        if (key > *top) *top = key;
    }
    return 1;
}

/* One task: slab t's vertices of the stage list, in order. */
static void par_run_task(void *arg, int worker, size_t k) {
    par_ctx *X = arg;
    simp *S = X->S, *W = &X->wk[worker];
#if FEMLOD_SIMPLIFY_STATS
    double tk0 = now_seconds();
#endif
    par_task *t = X->task + X->order[k];
    const uint32_t *list = X->list[0].v;
    fl_simp_view(W, S);
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
    S->stats.tstage[10 + worker] += now_seconds() - tk0;
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
        if (!fl_simp_compact_refs(S)) return (size_t)-1;
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
            fl_pool_for(X->nw, n, par_run_task, X, STAT_WAIT(S));
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
            if (fl_simp_progress(S, o, live0, next)) {
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
            if (fl_simp_progress(S, o, live0, next)) return (size_t)-2;
        }
    }
    STAT_TIME_ST(2, ts);
    /* the grid follows the mesh's coarsening between passes */
#if FEMLOD_SIMPLIFY_STATS
    double tg0 = now_seconds();
#endif
    if (S->live * 4 < S->grid_live && S->live > 64 && !fl_simp_build_grid(S, S->grid_h * 2.0)) return (size_t)-1;

    STAT_TIME_ST(8, tg0);
    return done;
}

/* }====== */

/* {====== the passes */

/* Phase 1 in passes until at most floor_live triangles are left or no edge
 * is valid: every edge is evaluated once; then passes over the slots (in
 * Morton order: each collapse works next to the previous one's memory)
 * collapse each vertex's best edge whose key reaches the pass's threshold,
 * which starts at FEMLOD_SIMPLIFY_BAND times the best key and drops
 * by that factor per pass. Returns 0 on ENOMEM, 2 cancelled, 1 otherwise. */
int fl_simp_band_run(simp *S, const femlod_simplify_options *o, size_t floor_live, size_t live0, size_t *next) {
    S->vlock = fl_populate(fl_calloc(S->nv, sizeof *S->vlock), S->nv * sizeof *S->vlock);
    S->vbest = fl_populate(fl_alloc(S->nv, sizeof *S->vbest), S->nv * sizeof *S->vbest);
    if (!S->vlock || !S->vbest) return 0;
    par_ctx X;
    memset(&X, 0, sizeof X);
    X.S = S;
    X.nw = S->nthreads < 1 ? 1 : (S->nthreads > 16 ? 16 : S->nthreads);
    X.wk = fl_calloc((size_t)X.nw, sizeof *X.wk);
    if (!X.wk) return 0;
    int ret = 0;
#if FEMLOD_SIMPLIFY_STATS
    double t2 = now_seconds();
#endif
    /* every edge evaluated once, in parallel chunks */
    if (o->progress && o->progress(o->progress_payload, 0.0)) {
        ret = 2;
        goto done;
    }
    float top = -1.0f;
    if (!band_eval_all(S, &X, &top)) goto done;
    /* no valid edge under error_order's first caps (a noisy input): raise
     * the cap here as the loop below does, or the passes would hand every
     * collapse to the exact queue */
    while (top < 0.0f && fl_simp_raise_cap(S))
        if (!band_eval_all(S, &X, &top)) goto done;
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
                        if (fl_simp_progress(S, o, live0, next)) {
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
        } else if (top < 0.0f && fl_simp_raise_cap(S)) {
            /* no valid edge under error_order's cap: the next cap, every
             * edge evaluated again, bands from its best key */
            if (!band_eval_all(S, &X, &top)) goto done;
            tau = (double)top * FEMLOD_SIMPLIFY_BAND;
        } else {
            tau = mn(tau * FEMLOD_SIMPLIFY_BAND, (double)top);
        }
    }
    STAT_TIME(3, t3);
    /* back to the queue's conventions */
    for (size_t ed = 0; ed < S->ne; ed++) /* an out-of-date E_C1KEY goes too */
        if (S->edge[ed].state & E_STALE) S->edge[ed].state &= (uint8_t)~(E_STALE | E_C1KEY);
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
