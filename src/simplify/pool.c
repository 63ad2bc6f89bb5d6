/*
 * pool.c - every thread the simplifier starts, behind a small API
 * (simp.h, "pool.c"):
 *
 *   fl_pool_for       n independent items on up to nw threads, the caller
 *                     among them; each thread takes the next item from one
 *                     shared counter until none is left (the fast passes'
 *                     tasks, the evaluation chunks).
 *   fl_pool_ranges    [0, n) cut into contiguous parts, each part one item
 *                     of fl_pool_for (the set-up's maps, face-list
 *                     compaction).
 *   fl_pool_default_threads  the default thread count: the processors the
 *                     other runnable tasks leave idle
 *   fl_pool_helper_*  one long-lived thread that runs a job after each post
 *                     (the exact queue's ring re-evaluation): it spins
 *                     briefly (not on a loaded machine), then sleeps until
 *                     the next post.
 *
 * Invariants: which thread runs an item never shows in a result (callers
 * give items disjoint writes and keep per-part results by part index, not
 * by thread); a thread that cannot start leaves its items to the others,
 * so every call completes, on the calling thread alone if need be. The
 * pool knows nothing of the simplifier's state.
 */
#include "simp.h"

#include <math.h>
#include <pthread.h>
#include <sched.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <unistd.h>

#define POOL_MAX 16 /* threads at most */

static inline void cpu_relax(void) {
#if defined(__x86_64__) || defined(__i386__)
    __builtin_ia32_pause();
#endif
}

void fl_pool_backoff(int *spins) {
    if (++*spins < 2000) {
        cpu_relax();
    } else {
        sched_yield();
        *spins = 0;
    }
}

/* {====== fork and join */

typedef struct pool_run {
    fl_pool_fn fn;
    void *ctx;
    size_t n;
    atomic_size_t next;
    int timed;              /* record when each thread ran out of items */
    double tend[POOL_MAX];
} pool_run;

typedef struct pool_thread {
    pool_run *run;
    int worker;
    pthread_t th;
} pool_thread;

static void pool_work(pool_run *r, int worker) {
    for (;;) {
        size_t k = atomic_fetch_add(&r->next, 1);
        if (k >= r->n) break;
        r->fn(r->ctx, worker, k);
    }
    if (r->timed) r->tend[worker] = now_seconds();
}

static void *pool_main(void *arg) {
    pool_thread *t = arg;
    pool_work(t->run, t->worker);
    return NULL;
}

void fl_pool_for(int nw, size_t n, fl_pool_fn fn, void *ctx, double *wait) {
    pool_run r;
    r.fn = fn;
    r.ctx = ctx;
    r.n = n;
    atomic_init(&r.next, 0);
    r.timed = wait != NULL;
    int nt = nw < 1 ? 1 : (nw > POOL_MAX ? POOL_MAX : nw);
    if ((size_t)nt > n) nt = n ? (int)n : 1;
    pool_thread th[POOL_MAX];
    int started[POOL_MAX] = {0};
    for (int t = 1; t < nt; t++) {
        th[t].run = &r;
        th[t].worker = t;
        started[t] = pthread_create(&th[t].th, NULL, pool_main, &th[t]) == 0;
    }
    pool_work(&r, 0);
    for (int t = 1; t < nt; t++)
        if (started[t]) pthread_join(th[t].th, NULL);
    if (wait) {
        double last = r.tend[0];
        for (int t = 1; t < nt; t++)
            if (started[t] && r.tend[t] > last) last = r.tend[t];
        *wait += last - r.tend[0];
        for (int t = 1; t < nt; t++)
            if (started[t]) *wait += last - r.tend[t];
    }
}

/* }====== */

/* {====== how many threads by default
 *
 * The parallel steps (set-up parts, evaluation chunks, the passes'
 * sub-passes) end when their last thread does, and the exact queue's
 * helper shares each collapse's evaluations: a thread that waits for a core
 * stalls every step. On this project's 2-core machines with another job
 * running, one thread was 1.3-1.9x faster than two (docs/performance.md
 * "Threads and the exact finish"), while on an idle machine two gain 7-16%.
 * So the default takes the processors that the other runnable tasks leave
 * idle, counted when the run starts: /proc/loadavg's count of runnable
 * tasks, this one excepted (the 1-minute load average would count the
 * run's own last seconds, and back-to-back runs of two threads push it to
 * 2 by themselves); without /proc, the 1-minute load average less one.
 * Only the time depends on it, never a result. */

int fl_pool_threads_for_load(long np, double others) {
    if (np < 1) np = 1;
    if (np > POOL_MAX) np = POOL_MAX;
    if (!(others >= 0.0)) others = 0.0; /* NaN too */
    double n = (double)np - floor(others);
    return n < 1.0 ? 1 : (int)n;
}

/* Runnable tasks other than the caller, from /proc/loadavg ("0.52 0.58
 * 0.59 3/467 12345": 3 runnable, the reader among them); -1 without it. */
static double others_runnable(void) {
    FILE *f = fopen("/proc/loadavg", "r");
    if (!f) return -1.0;
    double a, b, c;
    long run = 0, all = 0;
    int got = fscanf(f, "%lf %lf %lf %ld/%ld", &a, &b, &c, &run, &all);
    fclose(f);
    return got == 5 && run >= 1 ? (double)(run - 1) : -1.0;
}

int fl_pool_default_threads(void) {
    long np = sysconf(_SC_NPROCESSORS_ONLN);
    double others = others_runnable(), load;
    if (others < 0.0) others = getloadavg(&load, 1) == 1 ? load - 1.0 : 0.0;
    return fl_pool_threads_for_load(np, others);
}

/* }====== */

/* {====== contiguous parts */

/* The parts fl_pool_ranges cuts [0, n) into: part t is [n t / parts, n (t + 1) / parts). */
int fl_pool_parts(int nth, size_t n) {
    if (nth > POOL_MAX) nth = POOL_MAX;
    return nth < 2 || n < 32768 ? 1 : nth;
}

size_t fl_pool_part_lo(size_t n, int parts, int t) { return n * (size_t)t / (size_t)parts; }

typedef struct pool_ranges {
    fl_pool_range_fn fn;
    void *ctx;
    size_t n;
    int parts;
} pool_ranges;

static void range_item(void *arg, int worker, size_t k) {
    (void)worker;
    const pool_ranges *c = arg;
    int t = (int)k;
    c->fn(c->ctx, fl_pool_part_lo(c->n, c->parts, t), fl_pool_part_lo(c->n, c->parts, t + 1), t);
}

void fl_pool_ranges(int nth, size_t n, fl_pool_range_fn fn, void *ctx) {
    int parts = fl_pool_parts(nth, n);
    if (parts == 1) {
        fn(ctx, 0, n, 0);
        return;
    }
    pool_ranges c = {fn, ctx, n, parts};
    fl_pool_for(parts, (size_t)parts, range_item, &c, NULL);
}

/* }====== */

/* {====== the helper thread
 *
 * It waits for a post by spinning on a generation counter, then sleeps on a
 * condition variable, so that it never keeps a core from another process.
 * `sleeping` is set under mu before the last look at go, and a post signals
 * under mu when it sees it set (both sides sequentially consistent: one
 * sees the other), so no post is missed.
 *
 * How long it spins is set when it starts, from the machine's load: 4,000
 * pauses (about the rest of a collapse) while the 1-minute load average is
 * under twice the online cores, none above. A spin saves a wake-up per
 * collapse when a core is free (a spin of 100 pauses made cover 30%
 * slower), but on a machine with more runnable threads than cores it took a
 * third of the job's CPU and made the job slower (docs/performance.md
 * "Threads and the exact finish"). Only the timing depends on it, never a
 * result. -DFEMLOD_HELPER_SPIN=N fixes the spin at N pauses (experiments). */
#ifndef FEMLOD_HELPER_SPIN
#define FEMLOD_HELPER_SPIN -1 /* -1: from the load, as above */
#endif

static int helper_spin(void) {
    if (FEMLOD_HELPER_SPIN >= 0) return FEMLOD_HELPER_SPIN;
    double load;
    long cores = sysconf(_SC_NPROCESSORS_ONLN);
    if (cores < 1 || getloadavg(&load, 1) != 1) return 4000;
    return load >= 2.0 * (double)cores ? 0 : 4000;
}

struct fl_pool_helper {
    void (*job)(void *);
    void *arg;
    pthread_t th;
    atomic_uint go; /* posts so far: wakes a sleeping helper */
    atomic_int quit;
    atomic_int sleeping;
    pthread_mutex_t mu;
    pthread_cond_t cv;
    int spin; /* pauses before sleeping (helper_spin) */
};

static void *helper_main(void *arg) {
    fl_pool_helper *h = arg;
    unsigned seen = 0;
    for (;;) {
        unsigned g;
        int spins = 0;
        while ((g = atomic_load(&h->go)) == seen) {
            if (atomic_load(&h->quit)) return NULL;
            if (++spins < h->spin) {
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
        h->job(h->arg);
    }
}

fl_pool_helper *fl_pool_helper_start(void (*job)(void *), void *arg) {
    fl_pool_helper *h = calloc(1, sizeof *h);
    if (!h) return NULL;
    h->job = job;
    h->arg = arg;
    h->spin = helper_spin();
    atomic_init(&h->go, 0);
    atomic_init(&h->quit, 0);
    atomic_init(&h->sleeping, 0);
    if (pthread_mutex_init(&h->mu, NULL) != 0) {
        free(h);
        return NULL;
    }
    if (pthread_cond_init(&h->cv, NULL) != 0) {
        pthread_mutex_destroy(&h->mu);
        free(h);
        return NULL;
    }
    if (pthread_create(&h->th, NULL, helper_main, h) != 0) {
        pthread_cond_destroy(&h->cv);
        pthread_mutex_destroy(&h->mu);
        free(h);
        return NULL;
    }
    return h;
}

void fl_pool_helper_post(fl_pool_helper *h) {
    atomic_store(&h->go, atomic_load_explicit(&h->go, memory_order_relaxed) + 1);
    if (!atomic_load(&h->sleeping)) return;
    pthread_mutex_lock(&h->mu);
    pthread_cond_signal(&h->cv);
    pthread_mutex_unlock(&h->mu);
}

void fl_pool_helper_stop(fl_pool_helper *h) {
    if (!h) return;
    atomic_store(&h->quit, 1);
    pthread_mutex_lock(&h->mu);
    pthread_cond_signal(&h->cv);
    pthread_mutex_unlock(&h->mu);
    pthread_join(h->th, NULL);
    pthread_cond_destroy(&h->cv);
    pthread_mutex_destroy(&h->mu);
    free(h);
}

/* }====== */
