/*
 * vec3.h - the few 3-vector operations every geometry file needs (internal).
 * Plain double arithmetic in a fixed order: with -ffp-contract=off they give
 * the same bits in every build (docs/design.md, "Determinism").
 */
#ifndef FEMLOD_VEC3_H
#define FEMLOD_VEC3_H

static inline void sub3(double r[3], const double a[3], const double b[3]) {
    r[0] = a[0] - b[0];
    r[1] = a[1] - b[1];
    r[2] = a[2] - b[2];
}

static inline double dot3(const double a[3], const double b[3]) {
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

/* r may be a or b. */
static inline void cross3(double r[3], const double a[3], const double b[3]) {
    double x = a[1] * b[2] - a[2] * b[1];
    double y = a[2] * b[0] - a[0] * b[2];
    double z = a[0] * b[1] - a[1] * b[0];
    r[0] = x;
    r[1] = y;
    r[2] = z;
}

static inline double dist2(const double a[3], const double b[3]) {
    double d[3];
    sub3(d, a, b);
    return dot3(d, d);
}

#endif
