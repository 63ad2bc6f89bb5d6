#include "shapes.h"
#include "core.h"

#include <assert.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

static femlod_mesh *make(const double *p, size_t nv, const uint32_t *t, size_t nt) {
    femlod_mesh *m = NULL;
    femlod_status s = femlod_mesh_create(&m, p, nv, t, nt, NULL);
    assert(s == FEMLOD_OK);
    (void)s;
    return m;
}

femlod_mesh *shape_icosphere(unsigned levels) {
    const double a = (1.0 + sqrt(5.0)) / 2.0;
    double p[12 * 3] = {-1, a, 0, 1, a, 0, -1, -a, 0, 1, -a, 0, 0, -1, a, 0, 1, a,
                        0, -1, -a, 0, 1, -a, a, 0, -1, a, 0, 1, -a, 0, -1, -a, 0, 1};
    static const uint32_t t[20 * 3] = {0, 11, 5, 0, 5, 1,  0, 1, 7,  0, 7,  10, 0, 10, 11,
                                       1, 5,  9, 5, 11, 4, 11, 10, 2, 10, 7, 6, 7, 1,  8,
                                       3, 9,  4, 3, 4,  2, 3, 2,  6, 3, 6,  8, 3, 8,  9,
                                       4, 9,  5, 2, 4,  11, 6, 2, 10, 8, 6, 7, 9, 8, 1};
    for (int i = 0; i < 12; i++) {
        double l = sqrt(p[3 * i] * p[3 * i] + p[3 * i + 1] * p[3 * i + 1] + p[3 * i + 2] * p[3 * i + 2]);
        for (int k = 0; k < 3; k++) p[3 * i + k] /= l;
    }
    femlod_mesh *m = make(p, 12, t, 20);
    if (levels == 0) return m;
    femlod_mesh *s = NULL;
    femlod_status st = femlod_mesh_subdivide(&s, m, levels, NULL);
    assert(st == FEMLOD_OK);
    (void)st;
    femlod_mesh_free(m);
    /* push to the sphere */
    double *q = s->pos; /* internal access: tests include core.h */
    for (size_t i = 0; i < femlod_mesh_vertex_count(s); i++) {
        double l = sqrt(q[3 * i] * q[3 * i] + q[3 * i + 1] * q[3 * i + 1] + q[3 * i + 2] * q[3 * i + 2]);
        for (int k = 0; k < 3; k++) q[3 * i + k] /= l;
    }
    return s;
}

femlod_mesh *shape_plane(unsigned n) {
    size_t nv = (size_t)(n + 1) * (n + 1), nt = (size_t)2 * n * n;
    double *p = malloc(nv * 3 * sizeof *p);
    uint32_t *t = malloc(nt * 3 * sizeof *t);
    assert(p && t);
    for (unsigned j = 0; j <= n; j++)
        for (unsigned i = 0; i <= n; i++) {
            size_t v = (size_t)j * (n + 1) + i;
            p[3 * v] = (double)i / n;
            p[3 * v + 1] = (double)j / n;
            p[3 * v + 2] = 0;
        }
    size_t k = 0;
    for (unsigned j = 0; j < n; j++)
        for (unsigned i = 0; i < n; i++) {
            uint32_t a = j * (n + 1) + i, b = a + 1, c = a + n + 1, d = c + 1;
            t[k++] = a; t[k++] = b; t[k++] = d;
            t[k++] = a; t[k++] = d; t[k++] = c;
        }
    femlod_mesh *m = make(p, nv, t, nt);
    free(p);
    free(t);
    return m;
}

femlod_mesh *shape_cylinder(unsigned around, unsigned up, double h) {
    size_t nv = (size_t)around * (up + 1), nt = (size_t)2 * around * up;
    double *p = malloc(nv * 3 * sizeof *p);
    uint32_t *t = malloc(nt * 3 * sizeof *t);
    assert(p && t);
    const double pi = 3.14159265358979323846;
    for (unsigned j = 0; j <= up; j++)
        for (unsigned i = 0; i < around; i++) {
            size_t v = (size_t)j * around + i;
            double phi = 2 * pi * i / around;
            p[3 * v] = cos(phi);
            p[3 * v + 1] = sin(phi);
            p[3 * v + 2] = h * j / up;
        }
    size_t k = 0;
    for (unsigned j = 0; j < up; j++)
        for (unsigned i = 0; i < around; i++) {
            uint32_t a = j * around + i, b = j * around + (i + 1) % around;
            uint32_t c = a + around, d = b + around;
            t[k++] = a; t[k++] = b; t[k++] = d;
            t[k++] = a; t[k++] = d; t[k++] = c;
        }
    femlod_mesh *m = make(p, nv, t, nt);
    free(p);
    free(t);
    return m;
}

femlod_mesh *shape_tetrahedron(void) {
    static const double p[] = {1, 1, 1, 1, -1, -1, -1, 1, -1, -1, -1, 1};
    static const uint32_t t[] = {0, 1, 2, 0, 3, 1, 0, 2, 3, 1, 3, 2};
    return make(p, 4, t, 4);
}

femlod_mesh *shape_nonmanifold_fan(void) {
    static const double p[] = {0, 0, 0, 1, 0, 0, 0.5, 1, 0, 0.5, -1, 0, 0.5, 0, 1};
    static const uint32_t t[] = {0, 1, 2, 1, 0, 3, 0, 1, 4};
    return make(p, 5, t, 3);
}

femlod_mesh *shape_bowtie(void) {
    static const double p[] = {0, 0, 0, 1, 0, 0, 1, 1, 0, -1, 0, 0, -1, -1, 0};
    static const uint32_t t[] = {0, 1, 2, 0, 3, 4};
    return make(p, 5, t, 2);
}

int shape_same_mesh(const femlod_mesh *a, const femlod_mesh *b) {
    if (!a || !b || a->nv != b->nv || a->nt != b->nt) return 0;
    return memcmp(a->pos, b->pos, a->nv * 3 * sizeof(double)) == 0 &&
           memcmp(a->tri, b->tri, a->nt * 3 * sizeof(uint32_t)) == 0;
}
