/* check.h - the smallest test harness that tells where and why.
 * CHECK(expr) and CHECK_NEAR(a, b, tol) count failures and go on; a test
 * program returns check_report() from main, which prints the closing line
 * "N passed, N failed" that CI reads. */
#ifndef FEMLOD_CHECK_H
#define FEMLOD_CHECK_H

#include <math.h>
#include <stdio.h>
#include <string.h>

static int check_passed, check_failed;

#define CHECK(expr)                                                                        \
    do {                                                                                   \
        if (expr) {                                                                        \
            check_passed++;                                                                \
        } else {                                                                           \
            check_failed++;                                                                \
            fprintf(stderr, "%s:%d: check failed: %s\n", __FILE__, __LINE__, #expr);      \
        }                                                                                  \
    } while (0)

#define CHECK_NEAR(a, b, tol)                                                              \
    do {                                                                                   \
        double check_a_ = (double)(a), check_b_ = (double)(b);                             \
        if (fabs(check_a_ - check_b_) <= (double)(tol)) {                                  \
            check_passed++;                                                                \
        } else {                                                                           \
            check_failed++;                                                                \
            fprintf(stderr, "%s:%d: check failed: %s = %.17g, expected %s = %.17g (tol %g)\n", \
                    __FILE__, __LINE__, #a, check_a_, #b, check_b_, (double)(tol));        \
        }                                                                                  \
    } while (0)

/* Relative tolerance: |a - b| <= tol * max(|b|, tiny). */
#define CHECK_REL(a, b, tol) CHECK_NEAR(a, b, (tol) * fmax(fabs((double)(b)), 1e-300))

/* The error message contains the substring. */
#define CHECK_STR_HAS(msg, sub)                                                            \
    do {                                                                                   \
        const char *check_m_ = (msg), *check_s_ = (sub);                                   \
        if (check_m_ && strstr(check_m_, check_s_)) {                                      \
            check_passed++;                                                                \
        } else {                                                                           \
            check_failed++;                                                                \
            fprintf(stderr, "%s:%d: message \"%s\" lacks \"%s\"\n", __FILE__, __LINE__,    \
                    check_m_ ? check_m_ : "(null)", check_s_);                             \
        }                                                                                  \
    } while (0)

/* A femlod_progress_fn that records what it is given: the calls, whether
 * done never went back and stayed in [0, 1], the last value; it asks to
 * stop at call stop_at (0: never). */
typedef struct check_progress {
    size_t calls, stop_at;
    double last;
    int ordered, in_range;
} check_progress;
#define CHECK_PROGRESS_INIT {0, 0, -1.0, 1, 1}

static inline int check_progress_fn(void *payload, double done) {
    check_progress *p = (check_progress *)payload;
    p->calls++;
    if (!(done >= p->last)) p->ordered = 0;
    if (!(done >= 0.0 && done <= 1.0)) p->in_range = 0;
    p->last = done;
    return p->stop_at && p->calls == p->stop_at;
}

/* A run that finished: called often enough, in order, in range, ending at 1. */
#define CHECK_PROGRESS_DONE(p, min_calls)                                                  \
    do {                                                                                   \
        CHECK((p).calls >= (min_calls));                                                   \
        CHECK((p).calls <= 102); /* about every 1%, not per element */                     \
        CHECK((p).ordered);                                                                \
        CHECK((p).in_range);                                                               \
        CHECK((p).last == 1.0);                                                            \
    } while (0)

static inline int check_report(const char *name) {
    printf("%s: %d passed, %d failed\n", name, check_passed, check_failed);
    return check_failed ? 1 : 0;
}

#endif
