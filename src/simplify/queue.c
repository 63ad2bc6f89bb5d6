/*
 * queue.c - the exact greedy order (paper 4.2.3): the queue of edges by
 * priority, the collapse (4.2 step 4) and its log (5.1), and the
 * re-evaluation around each collapse.
 *
 *   fl_simp_run_queue     pops the best edge, evaluates it again, runs the
 *                         pop-time checks, collapses, re-evaluates the ring
 *   fl_simp_collapse      the collapse: faces, edges, face lists, flags,
 *                         quadrics, caches, grid, deviation lists, log
 *   reevaluate_ring       every edge at k or at a vertex of its ring,
 *                         evaluated on two threads (ring_eval and its
 *                         helper) and applied in list order
 *   fl_simp_evaluate_all  every edge not queued (the start of a phase and
 *                         the final retry), in chunks on the run's threads
 *   fl_simp_start_cap,    error_order's schedule: C1's cap and the stretch
 *   fl_simp_raise_cap     floor per phase, the next cap when a round is dry
 *
 * Invariants: the heap holds every eligible edge with its priority (with
 * FEMLOD_SIMPLIFY_BOUND, an upper bound marked E_STALE, settled before
 * any pop is compared); E_TOLFAIL on an edge means its last evaluation
 * failed C1 alone, which holds while i and j keep their positions; the
 * queue is updated in list order whatever thread evaluated an entry, so
 * the pops are those of one thread; the collapse keeps face lists in
 * order, feature degrees, valences and the face caches.
 */
#include "simp.h"

#include <stdatomic.h>
#include <stdlib.h>

/* {====== the exact queue's second thread (ring_eval)
 *
 * After each collapse the queue re-evaluates the ~33 edges at and around k
 * (reevaluate_ring), three quarters of its time. The evaluations are
 * independent, so a helper thread (pool.c) shares them: the main thread
 * publishes the list (its range in one atomic word, after the helper's
 * view W), each thread claims one entry at a time by compare-and-swap on
 * that word, the main thread from the front and the helper from the back,
 * and the main thread waits only for the entries the helper has claimed
 * (hdone), then applies the results in list order, as with one thread. A
 * helper that is slow to wake (it sleeps after a short spin) thus costs
 * nothing: the main thread evaluates the whole list (measured against a
 * fixed 40 / 60 split, which waited for the helper half the time:
 * docs/design.md "The exact queue's second thread"). The helper reads W
 * only under a claim, and a claim of the current word is a claim of the
 * current list (its range is all the word holds), so a stale helper can
 * neither read a half-written W nor take an entry of a finished list. It
 * lives only while the queue runs. */

#ifndef FEMLOD_SIMPLIFY_QUEUE_HELPER
#define FEMLOD_SIMPLIFY_QUEUE_HELPER 1 /* 0: the exact queue runs on one thread (experiments) */
#endif

typedef struct eval_helper {
    simp W; /* its view of the run, refreshed before each list */
    simp *S;
    fl_pool_helper *th;
    /* the list's unclaimed range [lo, hi) as lo << 32 | hi: the main
     * thread claims from lo up, the helper from hi down; hdone: items the
     * helper has finished, over the whole run; htaken: the main thread's
     * count of the items the helper has claimed */
    _Atomic uint64_t claim, hdone;
    uint64_t htaken;
} eval_helper;

/* The helper's share of the list: entries claimed from the back until
 * the two ends meet. */
#define CL_LO(w) ((size_t)((w) >> 32))
#define CL_HI(w) ((size_t)((w) & 0xffffffffu))
static void helper_share(void *arg) {
    eval_helper *h = arg;
    simp *S = h->S, *W = &h->W;
    for (;;) {
        uint64_t w = atomic_load_explicit(&h->claim, memory_order_acquire);
        if (CL_LO(w) >= CL_HI(w)) break;
        if (!atomic_compare_exchange_weak_explicit(&h->claim, &w, w - 1, memory_order_acq_rel, memory_order_acquire))
            continue;
        size_t x = CL_HI(w) - 1;
        S->rrho[x] = fl_simp_evaluate(W, &W->R, S->rlist[x]);
        S->rtol[x] = (uint8_t)W->R.tolfail;
        atomic_fetch_add_explicit(&h->hdone, 1, memory_order_release);
    }
}

/* Evaluates S->rlist[0, n) into S->rrho and S->rtol. */
static void ring_eval(simp *S, size_t n) {
    eval_helper *h = S->helper;
    if (!h || n < 2 || n >= 0xffffffffu) {
        for (size_t x = 0; x < n; x++) {
            S->rrho[x] = fl_simp_evaluate(S, &S->R, S->rlist[x]);
            S->rtol[x] = (uint8_t)S->R.tolfail;
        }
        return;
    }
    /* the last list is claimed whole and finished (hdone == htaken): the
     * helper reads W only under a claim */
    fl_simp_view(&h->W, S);
    atomic_store(&h->claim, (uint64_t)n);
    fl_pool_helper_post(h->th);
    size_t mine = 0;
    for (;;) {
        uint64_t w = atomic_load_explicit(&h->claim, memory_order_acquire);
        if (CL_LO(w) >= CL_HI(w)) break;
        if (!atomic_compare_exchange_weak_explicit(&h->claim, &w, w + ((uint64_t)1 << 32), memory_order_acq_rel,
                                                   memory_order_acquire))
            continue;
        size_t x = CL_LO(w);
        S->rrho[x] = fl_simp_evaluate(S, &S->R, S->rlist[x]);
        S->rtol[x] = (uint8_t)S->R.tolfail;
        mine++;
    }
    if (mine < n) {
        h->htaken += n - mine;
        int spins = 0;
        while (atomic_load_explicit(&h->hdone, memory_order_acquire) != h->htaken) fl_pool_backoff(&spins);
        if (h->W.oom) S->oom = 1;
    }
}

/* Starts the helper when the run has a second thread (none: ring_eval
 * evaluates alone; the results are the same). */
static void helper_start(simp *S) {
    S->helper = NULL;
    if (S->nthreads < 2 || !FEMLOD_SIMPLIFY_QUEUE_HELPER) return;
    eval_helper *h = calloc(1, sizeof *h);
    if (!h) return;
    h->S = S;
    atomic_init(&h->claim, 0);
    atomic_init(&h->hdone, 0);
    h->htaken = 0;
    h->th = fl_pool_helper_start(helper_share, h);
    if (!h->th) {
        free(h);
        return;
    }
    S->helper = h;
}

/* Stops the helper and adds its rejection counts to the run's. */
static void helper_stop(simp *S) {
    eval_helper *h = S->helper;
    if (!h) return;
    fl_pool_helper_stop(h->th);
    for (int r = 0; r < FEMLOD_REJECT_COUNT; r++) S->rejected[r] += h->W.rejected[r];
    fl_simp_free_scratch(&h->W);
    free(h);
    S->helper = NULL;
}

/* }====== */

/* {====== collapse (4.2 step 4) and the log (5.1) */

/* A vertex's local reference in the log's faces: 0 for i, 1 for j, else
 * 2 + its rank among the sorted vstars. */
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

/* The collapse's log entry (5.1): vstars (the ring's vertices by node id,
 * sorted), e_size, the removed and changed faces in local references. 0 on
 * ENOMEM. */
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

/* The edge on face f's side (u, v). */
static uint32_t side_edge(const simp *S, uint32_t f, uint32_t u, uint32_t v) {
    const uint32_t *t = S->face[f].v;
    for (int c = 0; c < 3; c++) {
        uint32_t x = t[c], y = t[(c + 1) % 3];
        if ((x == u && y == v) || (x == v && y == u)) return S->tedge[3 * (size_t)f + c];
    }
    return UINT32_MAX;
}

/* f out of v's face list. */
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

/* i's slot becomes k: j's faces and edges move to it, the faces on the
 * edge go, the face caches, grid, cones and deviation lists follow. */
int fl_simp_collapse(simp *S, ring *R, int c) {
    const double *pc = R->cand[c];
    double p[3] = {pc[0], pc[1], pc[2]};
    uint32_t i = R->i, j = R->j, e = R->e;
    int efeat = (S->edge[e].flag & E_FEATURE) != 0;
    if (S->log && !log_collapse(S, R, p)) return 0;

    /* out of the grid while the old positions hold */
    for (size_t s = 0; s < R->ns; s++) fl_simp_grid_remove_face(S, R->sface[s]);
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
        if (!fl_simp_compact_refs(S)) return 0;
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
        if (!fl_simp_build_grid(S, S->grid_h * 2.0)) return 0;
    }
    return 1;
}

/* }====== */

/* {====== (re-)evaluation */

/* In the pre-phase, a face below min_stretch. */
static int face_is_bad(const simp *S, uint32_t f) {
    const uint32_t *t = S->face[f].v;
    return tri_stretch(P(S, t[0]), P(S, t[1]), P(S, t[2]), NULL) < S->minst;
}

/* The edge's queue entry from a new evaluation (out of the queue when it
 * has no valid candidate or is not eligible). */
static void update_edge(simp *S, uint32_t ed, int eligible) {
    if (S->edge[ed].flag & E_DEAD) return;
    if (!eligible) {
        fl_heap_remove(&S->heap, ed);
        return;
    }
    double rho = fl_simp_evaluate(S, &S->R, ed);
    S->edge[ed].state = (uint8_t)((S->edge[ed].state & ~(E_TOLFAIL | E_STALE)) | (S->R.tolfail ? E_TOLFAIL : 0));
    if (rho >= 0.0) fl_heap_set(&S->heap, ed, rho);
    else fl_heap_remove(&S->heap, ed);
}

/* update_edge with an upper bound for the priority (phase 1, an edge away
 * from k): the same decisions on validity and E_TOLFAIL. */
static void bound_update(simp *S, uint32_t ed, uint32_t k) {
    double ub = fl_simp_bound_edge(S, &S->R, ed, k);
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
 * (method-notes: their collapses would create triangles containing k).
 * 0 on ENOMEM. */
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

/* }====== */

/* {====== evaluate_all on the run's threads */

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

/* evaluate_all's threads: one view of the run each, kept from call to
 * call (their scratch grows once) */
typedef struct eval_team {
    simp *S;
    simp *wk;
    int nw;
    size_t e0, e1; /* the chunk being evaluated */
} eval_team;

/* evaluate_all's sub-chunk k of 4,096 edges. An edge whose candidates
 * all fail C1 again (fl_simp_c1_holds) is counted as refused, not
 * evaluated (E_TOLFAIL: as the evaluation would leave it). */
static void eval_sub(void *arg, int worker, size_t k) {
    eval_team *X = arg;
    simp *S = X->S, *W = &X->wk[worker];
    size_t e0 = X->e0 + k * 4096, e1 = e0 + 4096 < X->e1 ? e0 + 4096 : X->e1;
    for (size_t ed = e0; ed < e1; ed++) {
        size_t x = ed - X->e0;
        S->rkind[x] = (uint8_t)eval_wanted(S, ed);
        if (!S->rkind[x]) continue;
        if (fl_simp_c1_holds(S, S->edge + ed)) {
            W->rejected[FEMLOD_REJECT_TOLERANCE]++;
            S->edge[ed].state |= E_TOLFAIL;
            S->rkind[x] = 0;
            continue;
        }
        S->rrho[x] = fl_simp_evaluate(W, &W->R, (uint32_t)ed);
        S->rtol[x] = (uint8_t)W->R.tolfail;
    }
}

/* Evaluates the edges [e0, e1) that evaluate_all wants into S->rkind,
 * S->rrho, S->rtol (index ed - e0) on the run's threads, and adds the
 * threads' rejection counts to the run's. 0 on ENOMEM. */
static int eval_range(simp *S, size_t e0, size_t e1) {
    size_t n = e1 - e0;
    if (!buf_reserve((void **)&S->rkind, &S->rkind_cap, n + 1, 1) ||
        !buf_reserve((void **)&S->rrho, &S->rrho_cap, n + 1, sizeof *S->rrho) ||
        !buf_reserve((void **)&S->rtol, &S->rtol_cap, n + 1, 1))
        return 0;
    if (!S->ectx) {
        eval_team *X = calloc(1, sizeof *X);
        if (!X) return 0;
        X->S = S;
        X->nw = S->nthreads < 1 ? 1 : (S->nthreads > 16 ? 16 : S->nthreads);
        X->wk = fl_calloc((size_t)X->nw, sizeof *X->wk);
        if (!X->wk) {
            free(X);
            return 0;
        }
        S->ectx = X;
    }
    eval_team *X = S->ectx;
    for (int t = 0; t < X->nw; t++) {
        fl_simp_view(&X->wk[t], S);
        memset(X->wk[t].rejected, 0, sizeof X->wk[t].rejected);
    }
    X->e0 = e0;
    X->e1 = e1;
    fl_pool_for(X->nw, (n + 4095) / 4096, eval_sub, X, STAT_WAIT(S));
    int ok = 1;
    for (int t = 0; t < X->nw; t++) {
        for (int r = 0; r < FEMLOD_REJECT_COUNT; r++) S->rejected[r] += X->wk[t].rejected[r];
        if (X->wk[t].oom) ok = 0;
    }
    return ok;
}

void fl_simp_free_eval(simp *S) {
    eval_team *X = S->ectx;
    if (!X) return;
    fl_simp_free_views(S, X->wk, X->nw);
    free(X);
    S->ectx = NULL;
}

/* Evaluates every live edge (phase 1 start and the final retry), or in the
 * pre-phase every edge of a triangle below min_stretch. Returns how many
 * entered the queue. Also polls the progress callback (with the fraction
 * done so far) every 65,536 edges: on a big mesh this pass takes seconds,
 * and a time cap or a user's cancel must reach it (the result does not
 * depend on the polls). */
size_t fl_simp_evaluate_all(simp *S, const femlod_simplify_options *o, double done) {
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

/* }====== */

/* {====== the error order's schedule (error_order; docs/design.md "An
 * order that knows the error")
 *
 * C1's limit starts at a cap far below the tolerance; the queue (and the
 * fast passes) take every valid collapse under it in the paper's shape
 * order, with a stretch floor FEMLOD_SIMPLIFY_CAP_STRETCH in place of
 * min_stretch; when a round of the queue finds none left, the cap rises by
 * FEMLOD_SIMPLIFY_CAP_RATE, and once it would reach the tolerance the
 * schedule ends: the tolerance and min_stretch, the paper's rules, from
 * there. Each cap is a plain C1 limit, so E_TOLFAIL's rule holds within a
 * round, and every edge is evaluated again when the cap rises. */

void fl_simp_start_cap(simp *S) {
    S->lim_on = S->tol_on;
    S->lim_tol = S->tol;
    S->lim_st2 = S->phase == 1 && S->st_on ? S->minst2 : -1.0;
    if (S->phase != 1 || !S->sched || (S->tol_on && S->cap0 >= S->tol)) return;
    S->lim_on = 1;
    S->lim_tol = S->cap0;
    if (S->st_on && FEMLOD_SIMPLIFY_CAP_STRETCH > S->minst)
        S->lim_st2 = FEMLOD_SIMPLIFY_CAP_STRETCH * FEMLOD_SIMPLIFY_CAP_STRETCH;
}

int fl_simp_raise_cap(simp *S) {
    if (S->phase != 1 || !S->sched || !S->lim_on || (S->tol_on && S->lim_tol >= S->tol)) return 0;
    double c = S->lim_tol * FEMLOD_SIMPLIFY_CAP_RATE;
    if ((S->tol_on && c >= S->tol) || (!S->tol_on && c > S->cap_end)) {
        /* the schedule's end: the paper's rules */
        S->lim_on = S->tol_on;
        S->lim_tol = S->tol;
        S->lim_st2 = S->st_on ? S->minst2 : -1.0;
        return 1;
    }
    S->lim_tol = c;
    return 1;
}

/* }====== */

/* {====== the queue */

/* The fraction of the collapses to do that are done, to the callback at
 * each further 1% (also the fast passes'). */
int fl_simp_progress(simp *S, const femlod_simplify_options *o, size_t live0, size_t *next) {
    if (!o->progress) return 0;
    if (S->collapses < *next) return 0;
    size_t goal = live0 > S->prog_target ? live0 - S->prog_target : 1;
    size_t done = live0 - S->live;
    *next = S->collapses + (goal / 100 > 0 ? goal / 100 : 1);
    double d = (double)done / (double)goal;
    return o->progress(o->progress_payload, d > 1.0 ? 1.0 : d);
}

/* One collapse after another, best first (4.2.3), until the target or an
 * empty queue. */
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
        double rho = fl_simp_evaluate(S, R, e);
        if (S->oom) return 0;
        if (rho < 0.0) continue;
        if (rho < fl_heap_top_key(&S->heap)) { /* stale key: back in line */
            fl_heap_set(&S->heap, e, rho);
            continue;
        }
        int lw = fl_simp_link_check(S, R);
        if (lw != NO_REASON) { /* back when its neighbourhood changes */
            S->rejected[lw]++;
            continue;
        }
        int chosen = -1;
        for (int c = 0; c < R->ncand && chosen < 0; c++) {
            if (!R->ok[c]) continue;
            int w = fl_simp_expensive_checks(S, R, c);
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
        if (!fl_simp_collapse(S, R, chosen)) return 0;
        if (!reevaluate_ring(S, k) || S->oom) return 0;
        if (fl_simp_progress(S, o, live0, next)) return 2;
    }
    return 1;
}

int fl_simp_run_queue(simp *S, const femlod_simplify_options *o, size_t live0, size_t *next) {
    helper_start(S);
    int r = run_queue_1(S, o, live0, next);
    helper_stop(S);
    return r;
}

/* }====== */
