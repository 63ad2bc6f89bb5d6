#include "meshcheck.h"
#include "core.h"
#include "intersect.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

void (*meshcheck_on_pair)(const femlod_mesh *m, size_t f, size_t g, void *payload);
void *meshcheck_pair_payload;

size_t meshcheck_self_intersections(const femlod_mesh *m, double eps) {
    size_t nt = m->nt;
    if (nt < 2) return 0;
    double *box = malloc(6 * nt * sizeof *box), lo[3], hi[3], ext = 0;
    femlod_mesh_bbox(m, lo, hi);
    for (size_t f = 0; f < nt; f++) {
        double *b = box + 6 * f;
        for (int k = 0; k < 3; k++) {
            b[k] = INFINITY;
            b[3 + k] = -INFINITY;
        }
        for (int c = 0; c < 3; c++)
            for (int k = 0; k < 3; k++) {
                double x = m->pos[3 * (size_t)m->tri[3 * f + (size_t)c] + (size_t)k];
                b[k] = fmin(b[k], x);
                b[3 + k] = fmax(b[3 + k], x);
            }
        for (int k = 0; k < 3; k++) ext += b[3 + k] - b[k];
    }
    /* cells of about twice the mean box extent, at most ~4 cells per triangle */
    double h = fmax(2.0 * ext / (3.0 * (double)nt), 1e-300);
    int n[3];
    for (int k = 0; k < 3; k++) {
        double c = floor((hi[k] - lo[k]) / h) + 1;
        n[k] = c > 256 ? 256 : (int)c;
    }
    double inv[3];
    for (int k = 0; k < 3; k++) inv[k] = n[k] / fmax(hi[k] - lo[k], 1e-300);
    size_t ncell = (size_t)n[0] * (size_t)n[1] * (size_t)n[2];
    size_t *start = calloc(ncell + 1, sizeof *start);
    /* two passes: count the cells of every box, then fill */
    for (int pass = 0; pass < 2; pass++) {
        size_t *items = NULL, *fill = NULL;
        if (pass == 1) {
            for (size_t c = 0; c < ncell; c++) start[c + 1] += start[c];
            items = malloc((start[ncell] ? start[ncell] : 1) * sizeof *items);
            fill = calloc(ncell, sizeof *fill);
        }
        for (size_t f = 0; f < nt; f++) {
            int c0[3], c1[3];
            for (int k = 0; k < 3; k++) {
                c0[k] = (int)fmin(n[k] - 1, fmax(0, floor((box[6 * f + k] - lo[k]) * inv[k])));
                c1[k] = (int)fmin(n[k] - 1, fmax(0, floor((box[6 * f + 3 + k] - lo[k]) * inv[k])));
            }
            for (int z = c0[2]; z <= c1[2]; z++)
                for (int y = c0[1]; y <= c1[1]; y++)
                    for (int x = c0[0]; x <= c1[0]; x++) {
                        size_t c = ((size_t)z * (size_t)n[1] + (size_t)y) * (size_t)n[0] + (size_t)x;
                        if (pass == 0)
                            start[c + 1]++;
                        else
                            items[start[c] + fill[c]++] = f;
                    }
        }
        if (pass == 1) {
            free(fill);
            /* every pair sharing a cell, tested in the first cell both share */
            size_t hits = 0;
            for (size_t c = 0; c < ncell; c++)
                for (size_t a = start[c]; a < start[c + 1]; a++) {
                    size_t f = items[a];
                    for (size_t b = start[c]; b < start[c + 1]; b++) {
                        size_t g = items[b];
                        if (g <= f) continue;
                        const double *bf = box + 6 * f, *bg = box + 6 * g;
                        if (bg[0] > bf[3] || bg[1] > bf[4] || bg[2] > bf[5] || bg[3] < bf[0] ||
                            bg[4] < bf[1] || bg[5] < bf[2])
                            continue;
                        /* the first shared cell: the one holding the low corner of the
                         * boxes' intersection */
                        int first = 1;
                        for (int k = 0; k < 3 && first; k++) {
                            double l = fmax(bf[k], bg[k]);
                            int cl = (int)fmin(n[k] - 1, fmax(0, floor((l - lo[k]) * inv[k])));
                            int cc = (int)((k == 0 ? c % (size_t)n[0]
                                            : k == 1 ? (c / (size_t)n[0]) % (size_t)n[1]
                                                     : c / ((size_t)n[0] * (size_t)n[1])));
                            first = cl == cc;
                        }
                        if (!first) continue;
                        const double *P[3], *Q[3];
                        for (int k = 0; k < 3; k++) {
                            P[k] = m->pos + 3 * (size_t)m->tri[3 * f + (size_t)k];
                            Q[k] = m->pos + 3 * (size_t)m->tri[3 * g + (size_t)k];
                        }
                        int hit = fl_tri_tri_intersect(P, m->tri + 3 * f, Q, m->tri + 3 * g, eps);
                        hits += (size_t)hit;
                        if (hit && meshcheck_on_pair) meshcheck_on_pair(m, f, g, meshcheck_pair_payload);
                    }
                }
            free(items);
            free(start);
            free(box);
            return hits;
        }
    }
    return 0;
}

int meshcheck_same_for_threads(const femlod_mesh *m, const femlod_simplify_options *o) {
    int same = 1;
    for (int fast = 0; fast < 2; fast++) {
        femlod_mesh *a = NULL, *b = NULL;
        femlod_simplify_options q = *o;
        q.fast_above = fast ? 2.0 : FEMLOD_SIMPLIFY_OFF;
        q.threads = 1;
        int ok = femlod_simplify(&a, NULL, m, &q, NULL, NULL) == FEMLOD_OK;
        q.threads = 2;
        ok = ok && femlod_simplify(&b, NULL, m, &q, NULL, NULL) == FEMLOD_OK;
        if (!ok || a->nv != b->nv || a->nt != b->nt ||
            memcmp(femlod_mesh_positions(a), femlod_mesh_positions(b), 3 * sizeof(double) * a->nv) != 0 ||
            memcmp(femlod_mesh_triangles(a), femlod_mesh_triangles(b), 3 * sizeof(uint32_t) * a->nt) != 0)
            same = 0;
        femlod_mesh_free(a);
        femlod_mesh_free(b);
    }
    return same;
}

femlod_mesh *meshcheck_load(const char *dir, const char *name) {
    char path[1024];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    femlod_mesh *m = NULL;
    femlod_error err;
    if (femlod_mesh_read(&m, path, NULL, &err) != FEMLOD_OK) {
        fprintf(stderr, "cannot read %s: %s\n", path, err.message);
        return NULL;
    }
    return m;
}

/* {====== the same triangles up to vertex numbering */

typedef struct tri9 {
    double p[9];
} tri9;

static int cmp_pt(const double *a, const double *b) {
    for (int k = 0; k < 3; k++)
        if (a[k] != b[k]) return a[k] < b[k] ? -1 : 1;
    return 0;
}

static int cmp_tri9(const void *x, const void *y) {
    const tri9 *a = x, *b = y;
    for (int k = 0; k < 9; k++)
        if (a->p[k] != b->p[k]) return a->p[k] < b->p[k] ? -1 : 1;
    return 0;
}

/* Each triangle as its corner positions from the least corner on, sorted. */
static tri9 *canonical(const femlod_mesh *m, size_t *n) {
    size_t nt = femlod_mesh_triangle_count(m), k = 0;
    tri9 *t = malloc((nt ? nt : 1) * sizeof *t);
    if (!t) return NULL;
    const double *p = femlod_mesh_positions(m);
    const uint32_t *tr = femlod_mesh_triangles(m);
    for (size_t i = 0; i < nt; i++) {
        const uint32_t *v = tr + 3 * i;
        if (v[0] == v[1] || v[1] == v[2] || v[0] == v[2]) continue;
        int s = 0;
        for (int c = 1; c < 3; c++)
            if (cmp_pt(p + 3 * (size_t)v[c], p + 3 * (size_t)v[s]) < 0) s = c;
        for (int c = 0; c < 3; c++) memcpy(t[k].p + 3 * c, p + 3 * (size_t)v[(s + c) % 3], 3 * sizeof(double));
        k++;
    }
    qsort(t, k, sizeof *t, cmp_tri9);
    *n = k;
    return t;
}

int meshcheck_same_triangles(const femlod_mesh *a, const femlod_mesh *b) {
    size_t na = 0, nb = 0;
    tri9 *ta = canonical(a, &na), *tb = canonical(b, &nb);
    int same = ta && tb && na == nb && memcmp(ta, tb, na * sizeof *ta) == 0;
    free(ta);
    free(tb);
    return same;
}

/* }====== */
