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

static inline int check_report(const char *name) {
    printf("%s: %d passed, %d failed\n", name, check_passed, check_failed);
    return check_failed ? 1 : 0;
}

#endif
