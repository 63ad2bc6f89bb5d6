/* test_hierarchy.c - the vertex hierarchy: split everything gives the input,
 * collapse everything gives the simplification output, and thousands of
 * random operations keep the invariant of docs/design.md at every step. */
#include "core.h"
#include "check.h"
#include "shapes.h"

#include <stdlib.h>

static femlod_mesh *load(const char *name) {
    char path[1024];
    snprintf(path, sizeof path, "%s/%s", FEMLOD_SHARED_DATA, name);
    femlod_mesh *m = NULL;
    femlod_error err;
    if (femlod_mesh_read(&m, path, NULL, &err) != FEMLOD_OK) {
        fprintf(stderr, "%s\n", err.message);
        exit(1);
    }
    return m;
}

/* Canonical form of a mesh for comparison up to vertex renumbering: each
 * triangle as its three corner positions, rotated to start at the smallest
 * corner (orientation kept), triangles sorted. */
typedef struct { double p[9]; } tri9;

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

static tri9 *canonical(const femlod_mesh *m, size_t *n) {
    size_t nt = femlod_mesh_triangle_count(m), k = 0;
    tri9 *t = malloc((nt ? nt : 1) * sizeof *t);
    const double *p = femlod_mesh_positions(m);
    const uint32_t *tr = femlod_mesh_triangles(m);
    for (size_t i = 0; i < nt; i++) {
        const uint32_t *v = tr + 3 * i;
        if (v[0] == v[1] || v[1] == v[2] || v[0] == v[2]) continue; /* as the hierarchy drops them */
        int s = 0;
        for (int c = 1; c < 3; c++)
            if (cmp_pt(p + 3 * v[c], p + 3 * v[s]) < 0) s = c;
        for (int c = 0; c < 3; c++) memcpy(t[k].p + 3 * c, p + 3 * v[(s + c) % 3], 3 * sizeof(double));
        k++;
    }
    qsort(t, k, sizeof *t, cmp_tri9);
    *n = k;
    return t;
}

static int same_mesh(const femlod_mesh *a, const femlod_mesh *b) {
    size_t na, nb;
    tri9 *ta = canonical(a, &na), *tb = canonical(b, &nb);
    int same = na == nb && memcmp(ta, tb, na * sizeof *ta) == 0;
    free(ta);
    free(tb);
    return same;
}

static femlod_mesh *front_mesh(femlod_hierarchy *h) {
    femlod_mesh *m = NULL;
    femlod_status s = femlod_hierarchy_extract(h, &m, NULL, NULL);
    CHECK(s == FEMLOD_OK);
    return m;
}

/* Every front triangle that is not an input triangle was created by a
 * collapse, so it meets the thresholds; the front stays manifold, oriented. */
static void check_front(femlod_hierarchy *h, const femlod_topology *in_top, double min_stretch,
                        double max_size, const femlod_mesh *input) {
    femlod_error err;
    femlod_status s = femlod_hierarchy_validate(h, &err);
    CHECK(s == FEMLOD_OK);
    if (s != FEMLOD_OK) fprintf(stderr, "validate: %s\n", err.message);
    femlod_mesh *m = front_mesh(h);
    femlod_topology top;
    CHECK(femlod_mesh_topology(m, &top, NULL) == FEMLOD_OK);
    CHECK(top.manifold == in_top->manifold && top.oriented == in_top->oriented);
    CHECK(top.closed == in_top->closed);
    femlod_quality q, qi;
    CHECK(femlod_mesh_quality(m, &q, NULL) == FEMLOD_OK);
    CHECK(femlod_mesh_quality(input, &qi, NULL) == FEMLOD_OK);
    CHECK(q.stretch_min >= fmin(min_stretch, qi.stretch_min) - 1e-12);
    CHECK(q.size_max <= fmax(max_size, qi.size_max) + 1e-12);
    femlod_mesh_free(m);
}

static void run(const char *name, size_t target, size_t random_ops, unsigned seed) {
    femlod_mesh *in = load(name), *out = NULL;
    femlod_collapse_log *log = NULL;
    femlod_simplify_options o = FEMLOD_SIMPLIFY_OPTIONS_INIT;
    o.target = target;
    femlod_simplify_result r;
    femlod_error err;
    CHECK(femlod_simplify(&out, &log, in, &o, &r, &err) == FEMLOD_OK);
    femlod_hierarchy *h = NULL;
    femlod_status s = femlod_hierarchy_create(&h, in, log, &err);
    CHECK(s == FEMLOD_OK);
    if (s != FEMLOD_OK) {
        fprintf(stderr, "%s: %s\n", name, err.message);
        return;
    }
    femlod_topology in_top;
    CHECK(femlod_mesh_topology(in, &in_top, NULL) == FEMLOD_OK);
    printf("%s: %zu -> %zu triangles, %zu nodes, %.1f bytes per input vertex\n", name,
           femlod_mesh_triangle_count(in), r.triangles, femlod_hierarchy_node_count(h),
           (double)femlod_hierarchy_bytes(h) / (double)femlod_mesh_vertex_count(in));

    /* the first front is the simplification output */
    femlod_mesh *m = front_mesh(h);
    CHECK(same_mesh(m, out));
    femlod_mesh_free(m);
    CHECK(femlod_hierarchy_validate(h, &err) == FEMLOD_OK);

    /* split everything: the input */
    size_t ops = 0;
    CHECK(femlod_hierarchy_refine(h, 0.0, NULL, NULL, &ops, &err) == FEMLOD_OK);
    CHECK(ops == femlod_collapse_log_count(log));
    m = front_mesh(h);
    CHECK(same_mesh(m, in));
    femlod_mesh_free(m);
    CHECK(femlod_hierarchy_validate(h, &err) == FEMLOD_OK);

    /* collapse everything: the output again */
    CHECK(femlod_hierarchy_coarsen(h, INFINITY, NULL, NULL, &ops, &err) == FEMLOD_OK);
    CHECK(ops == femlod_collapse_log_count(log));
    m = front_mesh(h);
    CHECK(same_mesh(m, out));
    femlod_mesh_free(m);

    /* random mixed operations, the invariant after every batch */
    printf("%s: %zu random operations, seed %u\n", name, random_ops, seed);
    size_t nn = femlod_hierarchy_node_count(h), nv = femlod_hierarchy_input_vertices(h);
    size_t done = 0, batches = 0;
    for (size_t step = 0; step < random_ops; step++) {
        seed = seed * 1103515245u + 12345u;
        uint32_t x = (uint32_t)(nv + (seed >> 8) % (nn - nv));
        femlod_node_info info;
        femlod_hierarchy_node(h, x, &info);
        size_t n = 0;
        if (step % 500 == 250) {
            double t = 0.002 * (double)((seed >> 4) % 50);
            CHECK(femlod_hierarchy_refine(h, t, NULL, NULL, &n, NULL) == FEMLOD_OK);
        } else if (step % 500 == 499) {
            double t = 0.002 * (double)((seed >> 4) % 50);
            CHECK(femlod_hierarchy_coarsen(h, t, NULL, NULL, &n, NULL) == FEMLOD_OK);
        } else if (info.state == FEMLOD_NODE_FRONT) {
            CHECK(femlod_hierarchy_split(h, x, &n, NULL) == FEMLOD_OK);
        } else if (info.state == FEMLOD_NODE_ABOVE) {
            CHECK(femlod_hierarchy_collapse(h, x, &n, NULL) == FEMLOD_OK);
        } else {
            CHECK(femlod_hierarchy_split(h, x, &n, &err) == FEMLOD_EINPUT);
        }
        done += n;
        if (step % 1000 == 999) {
            check_front(h, &in_top, r.min_stretch, r.max_size, in);
            batches++;
        }
    }
    printf("%s: %zu primitive operations in %zu checked batches\n", name, done, batches);
    check_front(h, &in_top, r.min_stretch, r.max_size, in);

    femlod_hierarchy_free(h);
    femlod_collapse_log_free(log);
    femlod_mesh_free(out);
    femlod_mesh_free(in);
}

static void test_errors(void) {
    femlod_mesh *a = shape_icosphere(2), *b = shape_icosphere(1), *out = NULL;
    femlod_collapse_log *log = NULL;
    femlod_simplify_options o = FEMLOD_SIMPLIFY_OPTIONS_INIT;
    o.target = 100;
    CHECK(femlod_simplify(&out, &log, a, &o, NULL, NULL) == FEMLOD_OK);
    femlod_hierarchy *h = NULL;
    femlod_error err;
    CHECK(femlod_hierarchy_create(&h, b, log, &err) == FEMLOD_EINPUT);
    CHECK(h == NULL);
    CHECK_STR_HAS(err.message, "collapse log is for 162 input vertices, the mesh has 42");
    CHECK(femlod_hierarchy_create(&h, a, log, &err) == FEMLOD_OK);
    CHECK(femlod_hierarchy_split(h, 0, NULL, &err) == FEMLOD_EINPUT);
    CHECK_STR_HAS(err.message, "node 0 is an input vertex");
    CHECK(femlod_hierarchy_split(h, 1u << 30, NULL, &err) == FEMLOD_EINPUT);
    CHECK_STR_HAS(err.message, "does not exist");
    femlod_hierarchy_free(h);
    femlod_hierarchy_free(NULL);
    femlod_collapse_log_free(log);
    femlod_mesh_free(out);
    femlod_mesh_free(a);
    femlod_mesh_free(b);
}

int main(void) {
    const char *heavy = getenv("FEMLOD_TEST_HEAVY");
    int is_heavy = !(heavy && heavy[0] == '0');
    test_errors();
    run("fandisk.obj", 1500, 10000, 20261122u);
    if (is_heavy) {
        run("cover.obj", 6000, 10000, 7u);
        run("bunny.obj", 3000, 2000, 11u);
    }
    return check_report("hierarchy");
}
