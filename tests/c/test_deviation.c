/* test_deviation.c - max_deviation bounds the two-sided Hausdorff distance
 * (docs/design.md "A distance bound that holds"): femlod's own sampled
 * Hausdorff distance of every output to its input is at most 1.05 d, for
 * several d on cover, fandisk, bunny and a generated part; and the bound's
 * runs repeat byte for byte for 1 and 2 threads, exact and fast. */
#include "check.h"
#include "meshcheck.h"
#include "shapes.h"

#include "femlod.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

static femlod_mesh *load(const char *name) {
    femlod_mesh *m = meshcheck_load(FEMLOD_SHARED_DATA, name);
    CHECK(m != NULL);
    return m;
}

/* A part with sharp edges, corners and curved faces: the box [0,4]x[0,2]x[0,1]
 * made of grids of cell 1/N, welded, then bent (z scaled by 1 + 0.15
 * sin(pi x / 2), so the top is a wave and the sides are ruled). */
static femlod_mesh *generated_part(void) {
    enum { N = 12, X = 4 * N, Y = 2 * N, Z = N };
    /* each face: a grid over two axes at a fixed third coordinate */
    const int dims[3] = {X, Y, Z};
    size_t nv = 0, nt = 0;
    for (int ax = 0; ax < 3; ax++) {
        int u = (ax + 1) % 3, v = (ax + 2) % 3;
        nv += 2 * (size_t)(dims[u] + 1) * (size_t)(dims[v] + 1);
        nt += 4 * (size_t)dims[u] * (size_t)dims[v];
    }
    double *pos = malloc(3 * nv * sizeof *pos);
    uint32_t *tri = malloc(3 * nt * sizeof *tri);
    size_t w = 0, t = 0;
    for (int ax = 0; ax < 3; ax++)
        for (int side = 0; side < 2; side++) {
            int u = (ax + 1) % 3, v = (ax + 2) % 3;
            size_t base = w;
            for (int j = 0; j <= dims[v]; j++)
                for (int i = 0; i <= dims[u]; i++) {
                    double *p = pos + 3 * w++;
                    p[ax] = side ? (double)dims[ax] / N : 0.0;
                    p[u] = (double)i / N;
                    p[v] = (double)j / N;
                }
            for (int j = 0; j < dims[v]; j++)
                for (int i = 0; i < dims[u]; i++) {
                    uint32_t a = (uint32_t)(base + (size_t)j * (size_t)(dims[u] + 1) + (size_t)i);
                    uint32_t b = a + 1, c = a + (uint32_t)(dims[u] + 1), d = c + 1;
                    uint32_t q[6] = {a, b, d, a, d, c};
                    if (!side) q[1] = d, q[2] = b, q[4] = c, q[5] = d;
                    for (int k = 0; k < 6; k++) tri[3 * t + (size_t)k] = q[k];
                    t += 2;
                }
        }
    /* bent before welding: equal positions stay equal */
    for (size_t k = 0; k < nv; k++) pos[3 * k + 2] *= 1.0 + 0.15 * sin(3.14159265358979323846 * pos[3 * k] / 2.0);
    femlod_mesh *raw = NULL, *m = NULL;
    CHECK(femlod_mesh_create(&raw, pos, nv, tri, nt, NULL) == FEMLOD_OK);
    femlod_repair_options ro = FEMLOD_REPAIR_OPTIONS_INIT;
    CHECK(femlod_mesh_repair(&m, raw, &ro, NULL, NULL) == FEMLOD_OK);
    femlod_mesh_free(raw);
    free(pos);
    free(tri);
    return m;
}

/* Simplifies m to target with bound d (exact order, or fast passes) and
 * checks femlod_mesh_hausdorff <= 1.05 d. */
static void bound_holds(const char *name, const femlod_mesh *m, size_t target, double d, int fast) {
    femlod_simplify_options o = FEMLOD_SIMPLIFY_OPTIONS_INIT;
    o.target = target;
    o.max_deviation = d;
    o.fast_above = fast ? 2.0 : FEMLOD_SIMPLIFY_OFF; /* off: the exact order */
    femlod_mesh *out = NULL;
    femlod_simplify_result r;
    femlod_error err;
    CHECK(femlod_simplify(&out, NULL, m, &o, &r, &err) == FEMLOD_OK);
    if (!out) return;
    femlod_hausdorff_result h;
    CHECK(femlod_mesh_hausdorff(out, m, NULL, &h, &err) == FEMLOD_OK);
    printf("  %-8s d %-7g %s %6zu triangles (%s): hausdorff %.4g = %.3f d (forward %.4g, backward %.4g)\n", name, d,
           fast ? "fast " : "exact", r.triangles, femlod_stop_reason_name(r.stop_reason), h.distance,
           h.distance / d, h.forward, h.backward);
    CHECK(h.distance <= 1.05 * d);
    CHECK(r.max_deviation == d);
    femlod_mesh_free(out);
}

static void test_bound(void) {
    femlod_mesh *cover = load("cover.obj"), *fandisk = load("fandisk.obj"), *bunny = load("bunny.obj");
    femlod_mesh *part = generated_part();
    if (cover) {
        bound_holds("cover", cover, 12000, 0.03, 0);
        bound_holds("cover", cover, 12000, 0.1, 0);
        bound_holds("cover", cover, 6000, 0.3, 0);
        bound_holds("cover", cover, 12000, 0.1, 1);
    }
    if (fandisk) {
        bound_holds("fandisk", fandisk, 2000, 0.001, 0);
        bound_holds("fandisk", fandisk, 2000, 0.003, 0);
        bound_holds("fandisk", fandisk, 1000, 0.01, 1);
    }
    if (bunny) {
        bound_holds("bunny", bunny, 5000, 0.001, 0);
        bound_holds("bunny", bunny, 5000, 0.003, 0);
    }
    if (part) {
        bound_holds("part", part, 1500, 0.003, 0);
        bound_holds("part", part, 1500, 0.01, 0);
        bound_holds("part", part, 1000, 0.03, 1);
    }
    femlod_mesh_free(cover);
    femlod_mesh_free(fandisk);
    femlod_mesh_free(bunny);
    femlod_mesh_free(part);
}

/* The same output for 1 and 2 threads, exact order and fast passes. */
static void test_threads(void) {
    femlod_mesh *m = load("fandisk.obj");
    if (!m) return;
    femlod_simplify_options o = FEMLOD_SIMPLIFY_OPTIONS_INIT;
    o.target = 1500;
    o.max_deviation = 0.002;
    CHECK(meshcheck_same_for_threads(m, &o));
    femlod_mesh_free(m);
}

int main(void) {
    test_bound();
    test_threads();
    return check_report("test_deviation");
}
