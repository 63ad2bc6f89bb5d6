/* error.c - status names, error records and checked allocation. */
#include "core.h"

#include <stdlib.h>
#include <string.h>
#include <stdint.h>
#if defined(__linux__)
#include <sys/mman.h>
#endif

const char *femlod_status_name(femlod_status status) {
    switch (status) {
    case FEMLOD_OK: return "ok";
    case FEMLOD_ENOMEM: return "nomem";
    case FEMLOD_EIO: return "io";
    case FEMLOD_EPARSE: return "parse";
    case FEMLOD_EINPUT: return "input";
    case FEMLOD_ETOPOLOGY: return "topology";
    case FEMLOD_ECANCELLED: return "cancelled";
    case FEMLOD_EUNSUPPORTED: return "unsupported";
    case FEMLOD_ELIMIT: return "limit";
    }
    return "unknown";
}

femlod_status fl_error(femlod_error *err, femlod_status status, const char *fmt, ...) {
    if (err) {
        va_list ap;
        err->status = status;
        va_start(ap, fmt);
        vsnprintf(err->message, sizeof err->message, fmt, ap);
        va_end(ap);
    }
    return status;
}

/* fl_populate: one madvise(MADV_POPULATE_WRITE) maps all the pages of a
 * block at once instead of one page fault per 4 KiB page on first touch.
 * On the virtual machines femlod is measured on, a first-touch fault costs
 * 10-28 microseconds (more when two threads fault at once), so the 90,000
 * faults of the simplifier's set-up on the 1.25M-triangle benchmark took
 * 0.9-1.3 s; populated, the set-up takes 0.75 s instead of 1.6 s on two
 * threads (docs/design.md "Memory: populated blocks"). Pages already mapped
 * cost nothing (4 ms per 400 MB), so a grown block may be populated whole.
 * Only blocks that will be written whole are populated (the simplifier's
 * arrays, sized from a valid mesh), never one sized from a file's header
 * before the file is checked: that would commit memory a malformed file
 * only claims. A kernel without the call (before Linux 5.14), or another
 * system, keeps the faults; a failure is ignored (the pages then fault on
 * first touch as before). */
#define FL_POPULATE_MIN ((size_t)1 << 20)

void *fl_populate(void *p, size_t bytes) {
#if defined(__linux__) && defined(MADV_POPULATE_WRITE)
    if (p && bytes >= FL_POPULATE_MIN) {
        uintptr_t a = ((uintptr_t)p + 4095u) & ~(uintptr_t)4095u;
        uintptr_t b = ((uintptr_t)p + bytes) & ~(uintptr_t)4095u;
        if (b > a) (void)madvise((void *)a, b - a, MADV_POPULATE_WRITE);
    }
#else
    (void)bytes;
#endif
    return p;
}

void *fl_alloc(size_t count, size_t size) {
    size_t bytes;
    if (__builtin_mul_overflow(count, size, &bytes)) return NULL;
    return malloc(bytes ? bytes : 1);
}

void *fl_calloc(size_t count, size_t size) {
    if (count == 0 || size == 0) return calloc(1, 1);
    return calloc(count, size);
}

void *fl_realloc(void *p, size_t count, size_t size) {
    size_t bytes;
    if (__builtin_mul_overflow(count, size, &bytes)) return NULL;
    return realloc(p, bytes ? bytes : 1);
}

void fl_progress_init(fl_progress *p, femlod_progress_fn fn, void *payload, size_t total) {
    p->fn = fn;
    p->payload = payload;
    p->total = total;
    p->step = total / 100 + (total % 100 != 0); /* at most 100 reports before the end */
    if (p->step == 0) p->step = 1;
    p->next = fn ? 0 : SIZE_MAX;
    p->last = 0.0;
}

int fl_progress_report(fl_progress *p, size_t done) {
    if (!p->fn) return 0;
    p->next = done + p->step > done ? done + p->step : SIZE_MAX;
    double d = p->total ? (double)(done < p->total ? done : p->total) / (double)p->total : 1.0;
    if (d < p->last) d = p->last;
    p->last = d;
    return p->fn(p->payload, d) != 0;
}

int fl_progress_fraction(fl_progress *p, double done) {
    if (!p->fn) return 0;
    if (!(done >= 0.0)) done = 0.0;
    if (done > 1.0) done = 1.0;
    if (p->next == 0) { /* the first report, at the start */
        p->next = 1;
    } else if (done < p->last + 0.01) {
        return 0;
    }
    p->last = done;
    return p->fn(p->payload, done) != 0;
}

void fl_progress_end(fl_progress *p) {
    if (!p->fn) return;
    p->last = 1.0;
    (void)p->fn(p->payload, 1.0);
}

femlod_status fl_progress_cancelled(femlod_error *err, const char *what) {
    return fl_error(err, FEMLOD_ECANCELLED, "%s: cancelled by the progress callback", what);
}
