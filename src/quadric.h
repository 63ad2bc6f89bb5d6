/*
 * quadric.h - small inline quadric algebra for the simplifier, no state.
 *
 * Implements the error measure of Garland and Heckbert, "Surface
 * simplification using quadric error metrics" (SIGGRAPH 1997), extended with
 * line quadrics on feature edges as in paper.md section 4.1 eqs. (1)-(4),
 * with the signs corrected by method-notes.md "Quadric error":
 *
 *     E(x) = x^T A x + 2 B x + C,  A symmetric 3x3, B a row 3-vector.
 *
 * Stored as 10 doubles: a00 a01 a02 a11 a12 a22 b0 b1 b2 c. Quadrics add.
 */
#ifndef FEMLOD_QUADRIC_H
#define FEMLOD_QUADRIC_H

#include <math.h>
#include <string.h>

typedef struct fl_quadric {
    double a00, a01, a02, a11, a12, a22;
    double b0, b1, b2;
    double c;
} fl_quadric;

static inline void fl_quadric_zero(fl_quadric *q) { memset(q, 0, sizeof *q); }

static inline void fl_quadric_add(fl_quadric *q, const fl_quadric *r) {
    q->a00 += r->a00; q->a01 += r->a01; q->a02 += r->a02;
    q->a11 += r->a11; q->a12 += r->a12; q->a22 += r->a22;
    q->b0 += r->b0; q->b1 += r->b1; q->b2 += r->b2;
    q->c += r->c;
}

static inline void fl_quadric_scale(fl_quadric *q, double s) {
    q->a00 *= s; q->a01 *= s; q->a02 *= s; q->a11 *= s; q->a12 *= s; q->a22 *= s;
    q->b0 *= s; q->b1 *= s; q->b2 *= s; q->c *= s;
}

/* Plane n.x = n.p with unit normal n, weight w (eq. 2-4, first terms):
 * A += w n n^T, B += -w (n.p) n^T, C += w (n.p)^2. */
static inline void fl_quadric_add_plane(fl_quadric *q, const double n[3], const double p[3], double w) {
    double d = n[0] * p[0] + n[1] * p[1] + n[2] * p[2];
    q->a00 += w * n[0] * n[0]; q->a01 += w * n[0] * n[1]; q->a02 += w * n[0] * n[2];
    q->a11 += w * n[1] * n[1]; q->a12 += w * n[1] * n[2]; q->a22 += w * n[2] * n[2];
    q->b0 -= w * d * n[0]; q->b1 -= w * d * n[1]; q->b2 -= w * d * n[2];
    q->c += w * d * d;
}

/* Line through p with unit direction u, weight w: squared distance
 * |x-p|^2 - (u.(x-p))^2 (method-notes.md, corrected eqs. 2-4, second terms):
 * A += w (I - u u^T), B += -w (p - (u.p) u)^T, C += w (p.p - (u.p)^2). */
static inline void fl_quadric_add_line(fl_quadric *q, const double u[3], const double p[3], double w) {
    double up = u[0] * p[0] + u[1] * p[1] + u[2] * p[2];
    double pp = p[0] * p[0] + p[1] * p[1] + p[2] * p[2];
    q->a00 += w * (1.0 - u[0] * u[0]); q->a01 -= w * u[0] * u[1]; q->a02 -= w * u[0] * u[2];
    q->a11 += w * (1.0 - u[1] * u[1]); q->a12 -= w * u[1] * u[2]; q->a22 += w * (1.0 - u[2] * u[2]);
    q->b0 -= w * (p[0] - up * u[0]); q->b1 -= w * (p[1] - up * u[1]); q->b2 -= w * (p[2] - up * u[2]);
    q->c += w * (pp - up * up);
}

/* E(x) for the sum of two quadrics, without forming the sum (eq. 1). */
static inline double fl_quadric_eval2(const fl_quadric *q, const fl_quadric *r, const double x[3]) {
    double a00 = q->a00 + r->a00, a01 = q->a01 + r->a01, a02 = q->a02 + r->a02;
    double a11 = q->a11 + r->a11, a12 = q->a12 + r->a12, a22 = q->a22 + r->a22;
    double ax0 = a00 * x[0] + a01 * x[1] + a02 * x[2];
    double ax1 = a01 * x[0] + a11 * x[1] + a12 * x[2];
    double ax2 = a02 * x[0] + a12 * x[1] + a22 * x[2];
    double e = x[0] * ax0 + x[1] * ax1 + x[2] * ax2;
    e += 2.0 * ((q->b0 + r->b0) * x[0] + (q->b1 + r->b1) * x[1] + (q->b2 + r->b2) * x[2]);
    e += q->c + r->c;
    /* Rounding can make a true zero slightly negative; errors are sums of squares. */
    return e > 0.0 ? e : 0.0;
}

/* Eigen-decomposition of a symmetric 3x3 matrix by cyclic Jacobi rotations:
 * m is destroyed; on return its diagonal holds the eigenvalues and the
 * columns of v the eigenvectors. Deterministic and robust for repeated
 * eigenvalues, which flat regions and straight features always have. */
static inline void fl_sym3_eigen(double m[3][3], double v[3][3]) {
    for (int r = 0; r < 3; r++)
        for (int c = 0; c < 3; c++) v[r][c] = r == c ? 1.0 : 0.0;
    for (int sweep = 0; sweep < 8; sweep++) {
        double off = fabs(m[0][1]) + fabs(m[0][2]) + fabs(m[1][2]);
        double diag = fabs(m[0][0]) + fabs(m[1][1]) + fabs(m[2][2]);
        if (off <= 1e-15 * diag || off == 0.0) break;
        for (int p = 0; p < 2; p++)
            for (int q = p + 1; q < 3; q++) {
                double apq = m[p][q];
                if (apq == 0.0) continue;
                double theta = (m[q][q] - m[p][p]) / (2.0 * apq);
                double t = (theta >= 0 ? 1.0 : -1.0) / (fabs(theta) + sqrt(theta * theta + 1.0));
                double c = 1.0 / sqrt(t * t + 1.0), s = t * c;
                for (int k = 0; k < 3; k++) { /* columns p, q */
                    double mkp = m[k][p], mkq = m[k][q];
                    m[k][p] = c * mkp - s * mkq;
                    m[k][q] = s * mkp + c * mkq;
                }
                for (int k = 0; k < 3; k++) { /* rows p, q */
                    double mpk = m[p][k], mqk = m[q][k];
                    m[p][k] = c * mpk - s * mqk;
                    m[q][k] = s * mpk + c * mqk;
                }
                for (int k = 0; k < 3; k++) {
                    double vkp = v[k][p], vkq = v[k][q];
                    v[k][p] = c * vkp - s * vkq;
                    v[k][q] = s * vkp + c * vkq;
                }
            }
    }
}

/* The robust optimum of q + r (paper 4.2.1, method-notes "Optimal position"):
 * minimises E(mid + x) over x in the span of the eigenvectors of A whose
 * eigenvalues exceed rel * (largest eigenvalue); the midpoint stands in for
 * the dropped (undetermined) directions, so on a flat region the optimum is
 * the midpoint moved onto the plane, never a point far along the plane.
 * Writes mid + x to out and returns the number of directions kept (0: the
 * optimum is the midpoint). */
static inline int fl_quadric_optimum2(const fl_quadric *q, const fl_quadric *r, const double mid[3],
                                      double rel, double out[3]) {
    double m[3][3], v[3][3];
    m[0][0] = q->a00 + r->a00; m[0][1] = m[1][0] = q->a01 + r->a01; m[0][2] = m[2][0] = q->a02 + r->a02;
    m[1][1] = q->a11 + r->a11; m[1][2] = m[2][1] = q->a12 + r->a12; m[2][2] = q->a22 + r->a22;
    /* gradient at the midpoint / 2: A mid + B^T */
    double g[3];
    for (int k = 0; k < 3; k++) g[k] = m[k][0] * mid[0] + m[k][1] * mid[1] + m[k][2] * mid[2];
    g[0] += q->b0 + r->b0; g[1] += q->b1 + r->b1; g[2] += q->b2 + r->b2;
    fl_sym3_eigen(m, v);
    double lmax = fmax(m[0][0], fmax(m[1][1], m[2][2]));
    out[0] = mid[0]; out[1] = mid[1]; out[2] = mid[2];
    if (!(lmax > 0.0)) return 0;
    int kept = 0;
    for (int e = 0; e < 3; e++) {
        double l = m[e][e];
        if (!(l > rel * lmax)) continue;
        double t = -(v[0][e] * g[0] + v[1][e] * g[1] + v[2][e] * g[2]) / l;
        out[0] += t * v[0][e]; out[1] += t * v[1][e]; out[2] += t * v[2][e];
        kept++;
    }
    return kept;
}

#endif
