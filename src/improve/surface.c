/*
 * surface.c - the input surface of the improvement stage: its triangles in a
 * box grid, the nearest point to a point (relaxation and splits project back
 * onto it) and the test "within r" (the deviation bound).
 */
#include "impr.h"

#include <stdlib.h>
#include <string.h>

int fl_imsurf_init(im_surface *s, const femlod_mesh *m, double h) {
    memset(s, 0, sizeof *s);
    s->pos = m->pos;
    s->tri = m->tri;
    s->nt = m->nt;
    double lo[3], hi[3];
    femlod_mesh_bbox(m, lo, hi);
    s->diag = sqrt(dist2(lo, hi));
    size_t cells = 2 * m->nt + 64;
    if (cells > ((size_t)1 << 22)) cells = (size_t)1 << 22;
    if (!fl_imgrid_init(&s->grid, lo, hi, h, cells)) return 0;
    s->mark = fl_calloc(m->nt ? m->nt : 1, sizeof *s->mark);
    if (!s->mark) return 0;
    for (size_t f = 0; f < m->nt; f++) {
        const uint32_t *t = m->tri + 3 * f;
        double blo[3], bhi[3];
        im_box(m->pos + 3 * (size_t)t[0], m->pos + 3 * (size_t)t[1], m->pos + 3 * (size_t)t[2], blo, bhi);
        if (!fl_imgrid_insert(&s->grid, (uint32_t)f, blo, bhi)) return 0;
    }
    return 1;
}

void fl_imsurf_free(im_surface *s) {
    fl_imgrid_free(&s->grid);
    free(s->mark);
    memset(s, 0, sizeof *s);
}

static uint32_t surf_stamp(im_surface *s) {
    if (++s->stamp == 0) {
        memset(s->mark, 0, s->nt * sizeof *s->mark);
        s->stamp = 1;
    }
    return s->stamp;
}

typedef struct near_q {
    im_surface *s;
    const double *p;
    double best2, r2;
    uint32_t best;
    uint32_t stamp;
    int any; /* 1: stop at the first triangle within r */
} near_q;

static int visit(void *payload, uint32_t f) {
    near_q *q = payload;
    im_surface *s = q->s;
    if (s->mark[f] == q->stamp) return 0;
    s->mark[f] = q->stamp;
    const uint32_t *t = s->tri + 3 * (size_t)f;
    const double *a = s->pos + 3 * (size_t)t[0], *b = s->pos + 3 * (size_t)t[1], *c = s->pos + 3 * (size_t)t[2];
    /* box test first: most entries are far */
    for (int k = 0; k < 3; k++) {
        double lo = a[k] < b[k] ? a[k] : b[k], hi = a[k] > b[k] ? a[k] : b[k];
        lo = c[k] < lo ? c[k] : lo;
        hi = c[k] > hi ? c[k] : hi;
        double d = q->p[k] < lo ? lo - q->p[k] : (q->p[k] > hi ? q->p[k] - hi : 0.0);
        if (d * d > q->best2) return 0;
    }
    double d2 = fl_point_tri_dist2(q->p, a, b, c);
    if (d2 < q->best2 || (d2 == q->best2 && f < q->best)) {
        q->best2 = d2;
        q->best = f;
    }
    return q->any && d2 <= q->r2;
}

int fl_imsurf_within(im_surface *s, const double p[3], double r) {
    near_q q = {s, p, r * r * (1.0 + 1e-12), r * r, IM_DEAD, surf_stamp(s), 1};
    double lo[3], hi[3];
    for (int k = 0; k < 3; k++) {
        lo[k] = p[k] - r;
        hi[k] = p[k] + r;
    }
    return fl_imgrid_query(&s->grid, lo, hi, visit, &q) || q.best != IM_DEAD;
}

/* the nearest point of triangle (a, b, c) to p (Ericson 5.1.5) */
static void closest_on_tri(const double p[3], const double a[3], const double b[3], const double c[3],
                           double out[3]) {
    double ab[3], ac[3], ap[3], bp[3], cp[3];
    sub3(ab, b, a);
    sub3(ac, c, a);
    sub3(ap, p, a);
    double d1 = dot3(ab, ap), d2 = dot3(ac, ap);
    if (d1 <= 0 && d2 <= 0) {
        memcpy(out, a, 3 * sizeof *out);
        return;
    }
    sub3(bp, p, b);
    double d3 = dot3(ab, bp), d4 = dot3(ac, bp);
    if (d3 >= 0 && d4 <= d3) {
        memcpy(out, b, 3 * sizeof *out);
        return;
    }
    double vc = d1 * d4 - d3 * d2;
    if (vc <= 0 && d1 >= 0 && d3 <= 0) {
        double v = d1 / (d1 - d3);
        for (int k = 0; k < 3; k++) out[k] = a[k] + v * ab[k];
        return;
    }
    sub3(cp, p, c);
    double d5 = dot3(ab, cp), d6 = dot3(ac, cp);
    if (d6 >= 0 && d5 <= d6) {
        memcpy(out, c, 3 * sizeof *out);
        return;
    }
    double vb = d5 * d2 - d1 * d6;
    if (vb <= 0 && d2 >= 0 && d6 <= 0) {
        double w = d2 / (d2 - d6);
        for (int k = 0; k < 3; k++) out[k] = a[k] + w * ac[k];
        return;
    }
    double va = d3 * d6 - d5 * d4;
    if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
        double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        for (int k = 0; k < 3; k++) out[k] = b[k] + w * (c[k] - b[k]);
        return;
    }
    double den = 1.0 / (va + vb + vc);
    double v = vb * den, w = vc * den;
    for (int k = 0; k < 3; k++) out[k] = a[k] + ab[k] * v + ac[k] * w;
}

double fl_imsurf_nearest(im_surface *s, const double p[3], double r0, double q_out[3]) {
    double r = r0 > 0 ? r0 : 1e-6 * (s->diag > 0 ? s->diag : 1.0);
    for (;;) {
        near_q q = {s, p, r * r, r * r, IM_DEAD, surf_stamp(s), 0};
        double lo[3], hi[3];
        for (int k = 0; k < 3; k++) {
            lo[k] = p[k] - r;
            hi[k] = p[k] + r;
        }
        fl_imgrid_query(&s->grid, lo, hi, visit, &q);
        if (q.best != IM_DEAD) {
            const uint32_t *t = s->tri + 3 * (size_t)q.best;
            closest_on_tri(p, s->pos + 3 * (size_t)t[0], s->pos + 3 * (size_t)t[1], s->pos + 3 * (size_t)t[2],
                           q_out);
            return sqrt(q.best2);
        }
        if (r > 4.0 * s->diag + 1.0) {
            memcpy(q_out, p, 3 * sizeof *q_out);
            return INFINITY;
        }
        r *= 2.0;
    }
}
