/*
 * simplify.c - quality-controlled edge-collapse simplification: the entry
 * point femlod_simplify, its options and the order of its phases.
 *
 * Implements paper.md section 4 (Lee et al., "Mesh simplification and
 * adaptive LOD for finite element mesh generation") as corrected and settled
 * by method-notes.md; docs/simplify.md records the choices and the
 * measurements behind them, docs/algorithms.md maps each formula to its
 * function. The files of src/simplify/, top down (each calls only the ones
 * below it; simp.h says what they share):
 *
 *   simplify.c        options (resolve_options), phases (simplify_run),
 *                     output (make_output)
 *   fast.c            4.2.3 order above fast_above x target: passes in
 *                     priority bands (band_run), serial and parallel
 *   queue.c           4.2.3 greedy order: the queue (run_queue,
 *                     reevaluate_ring), 4.2 step 4 collapse, 5.1 log
 *   candidate.c       4.2.1 candidates, 4.2.2 validity (C1-C4, foldover,
 *                     link condition, cones, deviation), 4.2.3 priority
 *   intersect_grid.c  4.2.2 no crossing: the intersection test and its grid
 *   setup.c           4.1 (1)-(4) quadrics, features, connectivity
 *   pool.c            threads
 *
 * Phases (simplify_run): the stretch pre-phase (4.2.2: only edges of
 * triangles below min_stretch, collapses that raise the least stretch),
 * then optionally the fast passes, then the exact queue, with a final
 * retry of every edge when it runs dry.
 *
 * Invariants: the output depends only on the input and the options (not
 * on the thread count, pointer values or timing); it stops short with
 * FEMLOD_OK and says why; every failure frees what the run made.
 */
#include "simp.h"
#include "../improve.h"

#include <assert.h>
#if defined(__GLIBC__)
#include <malloc.h> /* malloc_trim: release_freed_memory */
#endif
#include <stdlib.h>
#include <unistd.h>

/* Tunables, fixed by the measurements in docs/simplify.md; -D overrides
 * them for experiments only. */
#ifndef FEMLOD_SIMPLIFY_DEFAULT_TOLERANCE
#define FEMLOD_SIMPLIFY_DEFAULT_TOLERANCE 4.0 /* times (mean input edge)^2 */
#endif
#ifndef FEMLOD_SIMPLIFY_DEFAULT_FAST
#define FEMLOD_SIMPLIFY_DEFAULT_FAST 3.0 /* fast_above's default factor */
#endif
#ifndef FEMLOD_SIMPLIFY_GRID_CELL
#define FEMLOD_SIMPLIFY_GRID_CELL 1.0 /* grid cell edge / mean edge length */
#endif

/* {====== options and set-up */

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
    if (o->threads < 0) return fl_error(err, FEMLOD_EINPUT, "simplify: threads %d is negative", o->threads);
    S->nthreads = o->threads;
    if (S->nthreads == 0) S->nthreads = fl_pool_default_threads(); /* pool.c: by the load */
    if (S->nthreads > 16) S->nthreads = 16;
    S->target = o->target;
    if (o->ratio > 0.0) S->target = (size_t)floor(o->ratio * (double)nt + 0.5);

    /* C1: the default is scale-aware: docs/simplify.md "Defaults" */
    S->tol_on = o->tolerance >= 0.0;
    S->tol = o->tolerance > 0.0 ? o->tolerance : FEMLOD_SIMPLIFY_DEFAULT_TOLERANCE * mean_edge * mean_edge;
    /* the error order's schedule (queue.c): the default; < 0 the paper's order */
    S->sched = o->error_order >= 0;
    /* fast_above 0: the default, fast passes at the default factor in the
     * error order and the exact order in the paper's (where the passes cost
     * more than 0.01 of average stretch: docs/simplify.md "Fast passes");
     * off (negative): the exact order throughout */
    if (o->fast_above >= 1.0)
        S->fast = o->fast_above;
    else
        S->fast = o->fast_above == 0.0 && S->sched ? FEMLOD_SIMPLIFY_DEFAULT_FAST : 0.0;
    S->cap0 = FEMLOD_SIMPLIFY_CAP0 * mean_edge * mean_edge;
    S->cap_end = 1e6 * diag * diag; /* without a tolerance: past any error a collapse can have */
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

static void release_freed_memory(size_t triangles);

/* The set-up in the order its parts need: the mesh measured, the options
 * resolved against it, then what depends on them, and the grid. */
static femlod_status setup(simp *S, const femlod_mesh *mesh, const femlod_simplify_options *o, size_t *dropped,
                           femlod_error *err) {
    simp_measure m;
    femlod_status st = fl_simp_setup_mesh(S, mesh, o, dropped, &m, err);
    if (st == FEMLOD_OK) st = resolve_options(S, o, mesh->nt, m.diag, m.mean_edge, m.size_max, err);
    if (st == FEMLOD_OK) st = fl_simp_setup_features(S, mesh, o, err);
    if (st == FEMLOD_OK && S->dev_on) st = fl_simp_setup_deviation(S, m.mean_edge, err);
    if (st == FEMLOD_OK &&
        !fl_simp_build_grid(S, m.mean_edge > 0.0 ? FEMLOD_SIMPLIFY_GRID_CELL * m.mean_edge : 1.0))
        st = fl_error(err, FEMLOD_ENOMEM, "simplify: out of memory");
    /* the set-up's temporaries (sort keys, edge sides, face maps) are
     * freed, but their pages inside the heap stay resident until trimmed */
    if (st == FEMLOD_OK) release_freed_memory(S->nt);
    return st;
}

/* Everything the run holds (what it never made is NULL). */
static void simp_free(simp *S) {
    fl_simp_free_eval(S);
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
    free(S->cone);
    free(S->fmark);
    free(S->fmade);
    free(S->fpt);
    free(S->pnext);
    fl_simp_free_deviation(S);
    free(S->ev);
    free(S->enf);
    free(S->edge);
    free(S->emark);
    free(S->ehint);
    free(S->eopt);
    fl_heap_free(&S->heap);
    fl_grid_free(&S->grid);
    fl_simp_free_scratch(S);
}

/* }====== */

/* {====== phases */

/* The phases: the stretch pre-phase (4.2.2), the fast passes (fast_above),
 * the exact queue with a final retry. 0 on ENOMEM, 2 cancelled, 1 otherwise;
 * *why says why it stopped. */
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
        fl_simp_start_cap(S); /* the tolerance; no C2: the pre-phase compares with the replaced faces */
        size_t queued = fl_simp_evaluate_all(S, o, 0.0);
        if (S->cancelled) {
            *why = FEMLOD_STOP_CANCELLED;
            return 2;
        }
        if (queued) {
            int r = fl_simp_run_queue(S, o, live0, &next);
            if (r != 1) {
                if (r == 2) *why = FEMLOD_STOP_CANCELLED;
                return r;
            }
        }
        while (fl_heap_size(&S->heap)) fl_heap_pop(&S->heap, NULL);
    }
    STAT_TIME(1, t1);
    S->phase = 1;
    fl_simp_start_cap(S); /* C1 and C2, or error_order's first cap and floor */
    if (S->fast > 0.0) {
        double fl = S->fast * (double)S->target;
        size_t floor_live = fl < (double)SIZE_MAX ? (size_t)fl : SIZE_MAX;
        if (S->live > floor_live) {
            int r = fl_simp_band_run(S, o, floor_live, live0, &next);
            if (r != 1) {
                if (r == 2) *why = FEMLOD_STOP_CANCELLED;
                return r;
            }
        }
    }
    *nextp = next;
    return finish(S, o, live0, nextp, why);
}

/* The exact order down to S->target: evaluate everything not queued, run
 * the queue, again until the target or until a round makes no collapse.
 * S->binding gets the check that refused most in that last round (when no
 * edge is valid). Returns as simplify_run. */
static int finish(simp *S, const femlod_simplify_options *o, size_t live0, size_t *nextp,
                  femlod_stop_reason *why) {
    size_t next = *nextp;
#if FEMLOD_SIMPLIFY_STATS
    double t4 = now_seconds();
#endif
    size_t last_retry = (size_t)-1;
    size_t before[FEMLOD_REJECT_COUNT] = {0};
    *why = FEMLOD_STOP_NO_VALID_EDGE;
    for (;;) {
        if (S->live <= S->target) break;
        /* evaluate everything not queued: at the start, and again when the
         * queue runs dry, for edges refused for reasons outside their ring
         * (an intersection with a triangle that has moved away since); a
         * round without a collapse ends the run, or with error_order raises
         * the schedule's cap (queue.c) */
        if (last_retry == S->collapses && !fl_simp_raise_cap(S)) break;
        last_retry = S->collapses;
        size_t goal = live0 > S->prog_target ? live0 - S->prog_target : 1;
        double done = (double)(live0 - S->live) / (double)goal;
#if FEMLOD_SIMPLIFY_STATS
        double tq0 = now_seconds();
#endif
        memcpy(before, S->rejected, sizeof before);
        size_t queued = fl_simp_evaluate_all(S, o, done > 1.0 ? 1.0 : done);
        if (S->cancelled) {
            *why = FEMLOD_STOP_CANCELLED;
            return 2;
        }
        /* nothing newly queued and nothing left in the queue: no valid
         * edge (past the target the queue still holds the edges that were
         * valid when the target was reached) */
        if (!queued && fl_heap_size(&S->heap) == 0) {
            if (!fl_simp_raise_cap(S)) break;
            last_retry = (size_t)-1; /* the schedule's next cap: evaluate again */
            continue;
        }
        if (S->oom) return 0;
#if FEMLOD_SIMPLIFY_STATS
        double tq1 = now_seconds();
        size_t c0 = S->collapses, e0 = S->stats.evals;
#endif
        int r = fl_simp_run_queue(S, o, live0, &next);
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
    /* the check that refused most in the last round */
    S->binding = FEMLOD_REJECT_COUNT;
    size_t most = 0;
    for (int k = 0; k < FEMLOD_REJECT_COUNT; k++)
        if (S->rejected[k] - before[k] > most) {
            most = S->rejected[k] - before[k];
            S->binding = k;
        }
    STAT_TIME(4, t4);
    return 1;
}

/* }====== */

/* {====== output */

static int cmp_mkey(const void *a, const void *b) {
    const mkey *x = a, *y = b;
    if (x->key != y->key) return x->key < y->key ? -1 : 1;
    return (x->id > y->id) - (x->id < y->id);
}

/* The surviving vertices and faces as a mesh (and the log's output node
 * ids): deterministic orders, independent of the slots. */
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

/* At a stop with no valid edge: one more evaluation of every live edge
 * (the heap is empty), its refusals by first failing check into rej, each
 * edge once; *taken gets the edges that pass that evaluation, which the
 * checks made when an edge is taken from the queue (intersection,
 * deviation) then refused; topo gets the edges refused by gather's first
 * topology checks, by kind. The run's own counts (S->rejected) are left as
 * they were, and the edges queued again are taken out. 0 on ENOMEM. */
static int stop_count(simp *S, const femlod_simplify_options *o, size_t rej[FEMLOD_REJECT_COUNT], size_t *taken,
                      size_t topo[3]) {
    size_t before[FEMLOD_REJECT_COUNT];
    memcpy(before, S->rejected, sizeof before);
    *taken = fl_simp_evaluate_all(S, o, 1.0);
    if (S->oom) return 0;
    for (int k = 0; k < FEMLOD_REJECT_COUNT; k++) rej[k] = S->rejected[k] - before[k];
    memcpy(S->rejected, before, sizeof before);
    for (size_t e = 0; e < S->ne; e++) {
        if (fl_heap_contains(&S->heap, (uint32_t)e)) fl_heap_remove(&S->heap, (uint32_t)e);
        if (S->edge[e].flag & E_DEAD) continue;
        int k = fl_simp_topology_kind(S, (uint32_t)e);
        if (k >= 0) topo[k]++;
    }
    return 1;
}

static femlod_status simplify_core(femlod_mesh **out, femlod_collapse_log **out_log, const femlod_mesh *mesh,
                                   const femlod_simplify_options *options, femlod_simplify_result *result,
                                   femlod_error *err) {
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
    int extend = S->log && o->hierarchy_floor > 0 && S->target > 0 && o->hierarchy_floor < S->target;
    size_t floor_live = extend ? o->hierarchy_floor : 0;
    S->prog_target = extend ? floor_live : S->target;
    femlod_stop_reason why = FEMLOD_STOP_NO_VALID_EDGE, hwhy;
    size_t live0 = 0, next = 0;
    int r = simplify_run(S, o, &why, &live0, &next);
    femlod_mesh *m = NULL;
    double t5 = now_seconds();
    (void)t5;
    size_t out_collapses = S->collapses, out_rejected[FEMLOD_REJECT_COUNT];
    memcpy(out_rejected, S->rejected, sizeof out_rejected);
    size_t stop_rejected[FEMLOD_REJECT_COUNT] = {0}, stop_topology[3] = {0}, stop_taken = 0;
    if (r == 1 && why == FEMLOD_STOP_NO_VALID_EDGE && result &&
        !stop_count(S, o, stop_rejected, &stop_taken, stop_topology))
        r = 0;
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
        memcpy(result->stop_rejected, stop_rejected, sizeof stop_rejected);
        memcpy(result->stop_topology, stop_topology, sizeof stop_topology);
        result->stop_taken = stop_taken;
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

/* {====== the improvement stage around the simplification */

/* 1 when the mesh breaks a threshold the stage raises: a triangle below
 * min_stretch or above a max_size given, a vertex above max_valence.
 * Triangles with a repeated corner do not count: both stages drop them. One
 * pass over the triangles and one over the vertices. */
static int breaks_threshold(const femlod_mesh *m, const femlod_simplify_options *o, femlod_status *st,
                            femlod_error *err) {
    double minst = o->min_stretch < 0.0 ? -1.0 : (o->min_stretch > 0.0 ? o->min_stretch : 0.2);
    double maxsz = o->max_size > 0.0 ? o->max_size : -1.0;
    for (size_t f = 0; f < m->nt; f++) {
        const uint32_t *t = m->tri + 3 * f;
        if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) continue;
        double sz;
        double s = tri_stretch(m->pos + 3 * (size_t)t[0], m->pos + 3 * (size_t)t[1], m->pos + 3 * (size_t)t[2], &sz);
        if ((minst > 0.0 && s < minst) || (maxsz > 0.0 && sz > maxsz)) return 1;
    }
    if (o->max_valence < 0) return 0;
    uint32_t maxval = o->max_valence > 0 ? (uint32_t)o->max_valence : 12;
    uint32_t *val = fl_alloc(m->nv ? m->nv : 1, sizeof *val);
    if (!val) {
        *st = fl_error(err, FEMLOD_ENOMEM, "simplify: out of memory");
        return 0;
    }
    *st = femlod_valence_array(val, m->nv, m->tri, m->nt, err);
    int bad = 0;
    for (size_t v = 0; *st == FEMLOD_OK && v < m->nv && !bad; v++) bad = val[v] > maxval;
    free(val);
    return bad;
}

/* The stage's options from the simplification's: the same thresholds,
 * features, normal change and locks. */
static femlod_improve_options improve_options(const femlod_simplify_options *o, int rounds) {
    femlod_improve_options io = FEMLOD_IMPROVE_OPTIONS_INIT;
    io.min_stretch = o->min_stretch;
    io.max_size = o->max_size > 0.0 ? o->max_size : 0.0;
    io.max_valence = o->max_valence;
    io.max_deviation = o->max_deviation > 0.0 ? o->max_deviation : 0.0;
    io.feature_angle = o->feature_angle;
    io.max_normal_change = o->max_normal_change;
    io.max_rounds = rounds;
    io.lock = o->lock;
    io.lock_count = o->lock_count;
    io.lock_fn = o->lock_fn;
    io.lock_payload = o->lock_payload;
    return io;
}

static int cmp_point(const void *a, const void *b) {
    const double *x = a, *y = b;
    for (int k = 0; k < 3; k++)
        if (x[k] != y[k]) return x[k] < y[k] ? -1 : 1;
    return 0;
}

typedef struct lock_points {
    double *p; /* sorted positions of the locked input vertices */
    size_t n;
    femlod_lock_fn fn; /* and the options' lock function (NULL: none) */
    void *payload;
} lock_points;

static int locked_at(void *payload, double x, double y, double z) {
    const lock_points *L = payload;
    if (L->fn && L->fn(L->payload, x, y, z)) return 1;
    double q[3] = {x, y, z};
    return L->n && bsearch(q, L->p, L->n, 3 * sizeof *L->p, cmp_point) != NULL;
}

/* The honest count (docs/design.md "What remains, and why"): the output's
 * elements that break a threshold, by reason, from femlod_improve_census
 * with the simplification's thresholds; locked input vertices are the
 * output's at their positions (they never move). Runs only when the output
 * breaks a threshold. */
static femlod_status census_into(femlod_simplify_result *r, const femlod_mesh *m, const femlod_mesh *input,
                                 const femlod_simplify_options *o, femlod_error *err) {
    memset(r->violating_by, 0, sizeof r->violating_by);
    memset(r->violating_valence_by, 0, sizeof r->violating_valence_by);
    r->violating_valence = 0;
    r->corner_angle_min = r->corner_angle_max = 0.0;
    femlod_status st = FEMLOD_OK;
    int bad = breaks_threshold(m, o, &st, err);
    if (st != FEMLOD_OK || !bad) return st;
    femlod_improve_options io = improve_options(o, 1);
    io.lock = NULL;
    io.lock_count = 0;
    io.progress = NULL;
    lock_points L = {NULL, 0, o->lock_fn, o->lock_payload};
    if (o->lock_count) {
        L.p = fl_alloc(3 * o->lock_count, sizeof *L.p);
        if (!L.p) return fl_error(err, FEMLOD_ENOMEM, "simplify: out of memory");
        for (size_t i = 0; i < o->lock_count; i++)
            if (o->lock[i] < input->nv) memcpy(L.p + 3 * L.n++, input->pos + 3 * (size_t)o->lock[i], 3 * sizeof *L.p);
        qsort(L.p, L.n, 3 * sizeof *L.p, cmp_point);
    }
    if (L.n || L.fn) {
        io.lock_fn = locked_at;
        io.lock_payload = &L;
    }
    femlod_improve_report rep;
    st = femlod_improve_census(m, &io, &rep, err);
    free(L.p);
    if (st != FEMLOD_OK) return st;
    r->violating_input = rep.violating;
    memcpy(r->violating_by, rep.violating_by, sizeof r->violating_by);
    r->violating_valence = rep.valence_out;
    memcpy(r->violating_valence_by, rep.valence_by, sizeof r->violating_valence_by);
    r->corner_angle_min = rep.corner_angle_min;
    r->corner_angle_max = rep.corner_angle_max;
    return FEMLOD_OK;
}

/* the polish's rounds: each ends when one changes nothing */
#define POLISH_ROUNDS 20
/* and its passes */
#define POLISH_PASSES 3

static size_t report_ops(const femlod_improve_report *r) {
    return r->flips + r->splits + r->collapses + r->relaxations;
}

/* Before: the stage on an input that breaks a threshold (the log's base,
 * locks carried over by the stage's vertex map). After, without a log and
 * without max_deviation: a polish of two rounds on the output (docs/design.md
 * "The improvement stage inside simplify" says why not with a log). */
femlod_status femlod_simplify(femlod_mesh **out, femlod_collapse_log **out_log, const femlod_mesh *mesh,
                              const femlod_simplify_options *options, femlod_simplify_result *result,
                              femlod_error *err) {
    assert(out && mesh); /* femlod.h: NULL handles are programming errors */
    double t0 = now_seconds();
    femlod_simplify_options defaults = FEMLOD_SIMPLIFY_OPTIONS_INIT;
    const femlod_simplify_options *o = options ? options : &defaults;
    femlod_status st = FEMLOD_OK;
    int run = !o->no_improve && !o->keep_boundary && breaks_threshold(mesh, o, &st, err);
    if (st != FEMLOD_OK) return st;
    int polish_on = !o->no_improve && !o->keep_boundary && !out_log && o->max_deviation <= 0.0 && !o->lock_count;
    if (!run && !polish_on) {
        st = simplify_core(out, out_log, mesh, options, result, err);
        if (st == FEMLOD_OK && result) st = census_into(result, *out, mesh, o, err);
        if (st != FEMLOD_OK && *out) {
            femlod_mesh_free(*out);
            *out = NULL;
            if (out_log) {
                femlod_collapse_log_free(*out_log);
                *out_log = NULL;
            }
        }
        return st;
    }
    femlod_mesh *better = NULL;
    femlod_improve_report rep;
    memset(&rep, 0, sizeof rep);
    femlod_simplify_options so = *o;
    uint32_t *lock = NULL;
    if (run) {
        for (size_t i = 0; i < o->lock_count; i++)
            if (o->lock[i] >= mesh->nv)
                return fl_error(err, FEMLOD_EINPUT, "simplify: lock index %u out of range (%zu vertices)",
                                (unsigned)o->lock[i], mesh->nv);
        uint32_t *vmap = fl_alloc(mesh->nv ? mesh->nv : 1, sizeof *vmap);
        if (!vmap) return fl_error(err, FEMLOD_ENOMEM, "simplify: out of memory");
        femlod_improve_options io = improve_options(o, 0);
        st = fl_improve_mapped(&better, mesh, &io, &rep, vmap, err);
        if (st == FEMLOD_OK && o->lock_count) {
            /* a locked vertex is fixed in the stage: it stays */
            lock = fl_alloc(o->lock_count, sizeof *lock);
            if (!lock) st = fl_error(err, FEMLOD_ENOMEM, "simplify: out of memory");
            for (size_t i = 0; lock && i < o->lock_count; i++) lock[i] = vmap[o->lock[i]];
            so.lock = lock;
        }
        free(vmap);
        if (st != FEMLOD_OK) {
            femlod_mesh_free(better);
            free(lock);
            return st;
        }
        /* the simplification never goes below min(min_stretch, the input's
         * least stretch), nor does the stage: it judges its loose run by
         * that rule and falls back to its strict one (docs/design.md "The
         * floor rule, compound changes and bands"; test_improve measures it) */
    }
    if (run) {
        /* a ratio stays the input's: the target is the count asked for */
        if (o->ratio > 0.0) {
            so.ratio = 0.0;
            so.target = (size_t)floor(o->ratio * (double)mesh->nt + 0.5);
            if (so.target == 0) so.target = 1;
        }
    }
    double t1 = now_seconds();
    femlod_mesh *m = NULL;
    st = simplify_core(&m, out_log, run ? better : mesh, &so, result, err);
    free(lock);
    if (st != FEMLOD_OK) {
        femlod_mesh_free(better);
        return st;
    }
    if (out_log && run) (*out_log)->base = better;
    else femlod_mesh_free(better);
    size_t polish = 0;
    double t2 = now_seconds();
    if (polish_on) {
        /* the polish: the output's own elements that break a threshold */
        int bad = breaks_threshold(m, o, &st, err);
        if (st != FEMLOD_OK) {
            femlod_mesh_free(m);
            return st;
        }
        /* passes of the strict stage, each on the last's output (its own
         * input surface, its features found again), while one changes
         * something and leaves an element breaking a threshold */
        for (int pass = 0; bad && pass < POLISH_PASSES; pass++) {
            femlod_improve_options io = improve_options(o, POLISH_ROUNDS);
            femlod_improve_report pr;
            femlod_mesh *p = NULL;
            st = fl_improve_strict(&p, m, &io, &pr, err);
            if (st != FEMLOD_OK) {
                femlod_mesh_free(m);
                return st;
            }
            /* every change of the strict stage keeps the floor rule: its
             * output's least stretch is at least min(min_stretch, m's), so
             * it is always kept (test_improve measures it) */
            femlod_mesh_free(m);
            m = p;
            polish += report_ops(&pr);
            bad = report_ops(&pr) > 0 && (pr.violating > 0 || pr.valence_out > 0);
        }
    }
    if (result) {
        result->improved = run;
        result->improve_operations = run ? report_ops(&rep) : 0;
        result->improve_triangles = run ? rep.triangles : 0;
        result->polish_operations = polish;
        result->improve_seconds = (t1 - t0) + (now_seconds() - t2);
        /* the output's elements that break a threshold, after the polish */
        size_t bad = 0;
        for (size_t f = 0; f < m->nt; f++) {
            const uint32_t *t = m->tri + 3 * f;
            double sz;
            double stv = tri_stretch(m->pos + 3 * (size_t)t[0], m->pos + 3 * (size_t)t[1], m->pos + 3 * (size_t)t[2], &sz);
            if ((result->min_stretch > 0.0 && stv < result->min_stretch) || (result->max_size > 0.0 && sz > result->max_size))
                bad++;
        }
        result->violating_input = bad;
        result->triangles = m->nt;
        result->vertices = m->nv;
        st = census_into(result, m, mesh, o, err);
        if (st != FEMLOD_OK) {
            femlod_mesh_free(m);
            if (out_log) {
                femlod_collapse_log_free(*out_log);
                *out_log = NULL;
            }
            return st;
        }
        result->seconds = now_seconds() - t0;
    }
    *out = m;
    return FEMLOD_OK;
}

/* }====== */
