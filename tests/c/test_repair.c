/* test_repair.c - femlod_mesh_repair: each step on a mesh made to need it,
 * counted exactly; the defective shared meshes come out manifold and
 * oriented; a second repair changes nothing; bad options are refused. */
#include "check.h"
#include "core.h"
#include "shapes.h"

#include <stdlib.h>

static femlod_mesh *make(const double *p, size_t nv, const uint32_t *t, size_t nt) {
    femlod_mesh *m = NULL;
    CHECK(femlod_mesh_create(&m, p, nv, t, nt, NULL) == FEMLOD_OK);
    return m;
}

static femlod_topology topology(const femlod_mesh *m) {
    femlod_topology t;
    memset(&t, 0, sizeof t);
    CHECK(femlod_mesh_topology(m, &t, NULL) == FEMLOD_OK);
    return t;
}

static double volume6(const femlod_mesh *m) {
    double v = 0;
    const double *p = femlod_mesh_positions(m);
    const uint32_t *t = femlod_mesh_triangles(m);
    for (size_t f = 0; f < femlod_mesh_triangle_count(m); f++) {
        const double *A = p + 3 * t[3 * f], *B = p + 3 * t[3 * f + 1], *C = p + 3 * t[3 * f + 2];
        v += A[0] * (B[1] * C[2] - B[2] * C[1]) - A[1] * (B[0] * C[2] - B[2] * C[0]) +
             A[2] * (B[0] * C[1] - B[1] * C[0]);
    }
    return v;
}

static femlod_mesh *repair(const femlod_mesh *m, const femlod_repair_options *o,
                           femlod_repair_report *r) {
    femlod_mesh *out = NULL;
    femlod_error err;
    femlod_status st = femlod_mesh_repair(&out, m, o, r, &err);
    CHECK(st == FEMLOD_OK);
    if (st != FEMLOD_OK) fprintf(stderr, "repair: %s\n", err.message);
    return out;
}

/* A repaired mesh repaired again: the same mesh, nothing done, except that
 * the copies a non-manifold cut made (coincident by construction) are
 * welded and cut again, one for one. */
static void check_idempotent(const femlod_mesh *m, const femlod_repair_options *o) {
    femlod_repair_report r;
    femlod_mesh *again = repair(m, o, &r);
    CHECK(r.degenerate + r.duplicates + r.flipped + r.unused == 0);
    CHECK(r.welded == r.split_vertices);
    CHECK(shape_same_mesh(again, m));
    femlod_mesh_free(again);
}

/* An icosphere as a triangle soup: every corner its own vertex. */
static femlod_mesh *soup(const femlod_mesh *m) {
    size_t nt = femlod_mesh_triangle_count(m);
    double *p = malloc(9 * nt * sizeof(double));
    uint32_t *t = malloc(3 * nt * sizeof(uint32_t));
    for (size_t k = 0; k < 3 * nt; k++) {
        memcpy(p + 3 * k, femlod_mesh_positions(m) + 3 * femlod_mesh_triangles(m)[k], 3 * sizeof(double));
        t[k] = (uint32_t)k;
    }
    femlod_mesh *s = make(p, 3 * nt, t, nt);
    free(p);
    free(t);
    return s;
}

static void test_weld(void) {
    femlod_mesh *ico = shape_icosphere(2), *s = soup(ico);
    femlod_repair_report r;
    femlod_mesh *w = repair(s, NULL, &r);
    CHECK(r.welded == 3 * femlod_mesh_triangle_count(ico) - femlod_mesh_vertex_count(ico));
    CHECK(r.vertices_out == femlod_mesh_vertex_count(ico));
    femlod_topology t = topology(w);
    CHECK(t.closed && t.manifold && t.oriented);
    CHECK(r.flipped == 0 && volume6(w) > 0);
    check_idempotent(w, NULL);
    femlod_mesh_free(w);
    /* off: nothing merges, so every triangle is its own component */
    femlod_repair_options o = FEMLOD_REPAIR_OPTIONS_INIT;
    o.weld = -1;
    w = repair(s, &o, &r);
    CHECK(r.welded == 0 && r.vertices_out == femlod_mesh_vertex_count(s));
    femlod_mesh_free(w);
    femlod_mesh_free(s);
    femlod_mesh_free(ico);

    /* tolerance, and no chaining: 0, 0.6, 1.2 on a line with tolerance 1
     * gives clusters {0, 0.6} and {1.2}; 1e-7 apart merges only with a
     * tolerance, not with 0 */
    static const double p[] = {0, 0, 0, 0.6, 0, 0, 1.2, 0, 0, 0, 5, 0, 1e-7, 5, 0, 0, 0, 5};
    static const uint32_t t3[] = {0, 3, 5, 1, 4, 5, 2, 3, 5};
    femlod_mesh *m = make(p, 6, t3, 3);
    o = (femlod_repair_options)FEMLOD_REPAIR_OPTIONS_INIT;
    o.drop_degenerate = 0;
    o.split_nonmanifold = 0; /* vertex 5 joins two fans */
    o.weld = 1.0;
    w = repair(m, &o, &r);
    CHECK(r.welded == 2); /* 0.6 -> 0 and (1e-7, 5) -> (0, 5) */
    CHECK(r.vertices_out == 4);
    CHECK(femlod_mesh_positions(w)[3] == 1.2); /* the second kept vertex is 1.2, not merged */
    femlod_mesh_free(w);
    o.weld = 0.0;
    w = repair(m, &o, &r);
    CHECK(r.welded == 0 && r.vertices_out == 6);

    femlod_mesh_free(w);
    femlod_mesh_free(m);
}

static void test_degenerate_duplicates_unused(void) {
    /* 0 1 2 good; 0 1 1 repeated; 0 1 3 collinear (3 on the line 0-1);
     * 2 1 0 the first reversed (duplicate), 0 1 2 again (duplicate);
     * vertex 4 in no triangle */
    static const double p[] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 2, 0, 0, 7, 7, 7};
    static const uint32_t t[] = {0, 1, 2, 0, 1, 1, 0, 1, 3, 2, 1, 0, 0, 1, 2};
    femlod_mesh *m = make(p, 5, t, 5);
    femlod_repair_report r;
    femlod_mesh *w = repair(m, NULL, &r);
    CHECK(r.degenerate == 2);
    CHECK(r.duplicates == 2);
    CHECK(r.unused == 2); /* 4, and 3 once its collinear triangle is gone */
    CHECK(r.triangles_out == 1 && r.vertices_out == 3);
    CHECK(femlod_mesh_triangles(w)[0] == 0 && femlod_mesh_triangles(w)[1] == 1 &&
          femlod_mesh_triangles(w)[2] == 2);
    femlod_mesh_free(w);
    /* each step off on its own */
    femlod_repair_options o = FEMLOD_REPAIR_OPTIONS_INIT;
    o.drop_degenerate = 0;
    w = repair(m, &o, &r);
    CHECK(r.degenerate == 0 && r.duplicates == 2 && r.triangles_out == 3);
    femlod_mesh_free(w);
    o = (femlod_repair_options)FEMLOD_REPAIR_OPTIONS_INIT;
    o.drop_duplicates = 0;
    o.orient = 0;
    w = repair(m, &o, &r);
    CHECK(r.duplicates == 0 && r.triangles_out == 3);
    femlod_mesh_free(w);
    o = (femlod_repair_options)FEMLOD_REPAIR_OPTIONS_INIT;
    o.drop_unused = 0;
    w = repair(m, &o, &r);
    CHECK(r.unused == 0 && r.vertices_out == 5);
    femlod_mesh_free(w);
    femlod_mesh_free(m);
}

/* Flips every triangle for which pick(t) is true. */
static femlod_mesh *flipped(const femlod_mesh *m, size_t every, size_t *count) {
    size_t nt = femlod_mesh_triangle_count(m);
    uint32_t *t = malloc(3 * nt * sizeof(uint32_t));
    memcpy(t, femlod_mesh_triangles(m), 3 * nt * sizeof(uint32_t));
    *count = 0;
    for (size_t f = 0; f < nt; f++)
        if (f % every == 0) {
            uint32_t x = t[3 * f + 1];
            t[3 * f + 1] = t[3 * f + 2];
            t[3 * f + 2] = x;
            (*count)++;
        }
    femlod_mesh *out = make(femlod_mesh_positions(m), femlod_mesh_vertex_count(m), t, nt);
    free(t);
    return out;
}

static void test_orient(void) {
    femlod_mesh *ico = shape_icosphere(2);
    size_t n = 0, nt = femlod_mesh_triangle_count(ico);
    femlod_repair_report r;
    /* a third flipped: flipped back, outwards */
    femlod_mesh *m = flipped(ico, 3, &n), *w = repair(m, NULL, &r);
    CHECK(!topology(m).oriented);
    CHECK(r.flipped == n);
    CHECK(shape_same_mesh(w, ico));
    femlod_mesh_free(w);
    femlod_mesh_free(m);
    /* all flipped (inside out, consistent): turned outwards */
    m = flipped(ico, 1, &n);
    w = repair(m, NULL, &r);
    CHECK(r.flipped == nt && volume6(w) > 0);
    CHECK(shape_same_mesh(w, ico));
    femlod_mesh_free(w);
    femlod_mesh_free(m);
    femlod_mesh_free(ico);
    /* open: the fewer flips */
    femlod_mesh *plane = shape_plane(6);
    m = flipped(plane, 4, &n);
    w = repair(m, NULL, &r);
    CHECK(r.flipped == n && topology(w).oriented);
    CHECK(shape_same_mesh(w, plane));
    femlod_mesh_free(w);
    femlod_mesh_free(m);
    femlod_mesh_free(plane);
    /* a Moebius strip cannot be oriented: one edge is left inconsistent */
    enum { N = 12 };
    double p[2 * N * 3];
    uint32_t t[2 * N * 3];
    for (int i = 0; i < N; i++) {
        double a = 2 * M_PI * i / N, h = 0.3;
        double c = cos(a / 2) * h;
        p[6 * i + 0] = cos(a) * (1 + c);
        p[6 * i + 1] = sin(a) * (1 + c);
        p[6 * i + 2] = sin(a / 2) * h;
        p[6 * i + 3] = cos(a) * (1 - c);
        p[6 * i + 4] = sin(a) * (1 - c);
        p[6 * i + 5] = -sin(a / 2) * h;
    }
    for (int i = 0; i < N; i++) {
        uint32_t a0 = (uint32_t)(2 * i), a1 = a0 + 1, b0, b1;
        if (i + 1 < N) b0 = a0 + 2, b1 = a0 + 3;
        else b0 = 1, b1 = 0; /* the half twist */
        uint32_t q[6] = {a0, b0, a1, a1, b0, b1};
        memcpy(t + 6 * i, q, sizeof q);
    }
    m = make(p, 2 * N, t, 2 * N);
    w = repair(m, NULL, &r);
    CHECK(r.unorientable_edges == 1);
    CHECK(topology(w).inconsistent_edges == 1);
    femlod_mesh_free(w);
    femlod_mesh_free(m);
}

static void test_nonmanifold(void) {
    femlod_repair_report r;
    /* three triangles on one edge: both ends cut twice, three loose triangles */
    femlod_mesh *fan = shape_nonmanifold_fan(), *w = repair(fan, NULL, &r);
    CHECK(topology(fan).nonmanifold_edges == 1);
    CHECK(r.split_vertices == 4);
    CHECK(r.nonmanifold_edges_left == 0);
    femlod_topology t = topology(w);
    CHECK(t.manifold && t.components == 3);
    check_idempotent(w, NULL);
    femlod_mesh_free(w);
    femlod_mesh_free(fan);
    /* a bow-tie: the shared vertex cut once */
    femlod_mesh *bow = shape_bowtie();
    w = repair(bow, NULL, &r);
    CHECK(r.split_vertices == 1 && r.vertices_out == 6);
    CHECK(topology(w).manifold);
    femlod_mesh_free(w);
    femlod_repair_options o = FEMLOD_REPAIR_OPTIONS_INIT;
    o.split_nonmanifold = 0;
    w = repair(bow, &o, &r);
    CHECK(r.split_vertices == 0 && !topology(w).manifold);
    femlod_mesh_free(w);
    femlod_mesh_free(bow);
}

static void test_edge_cases(void) {
    femlod_repair_report r;
    femlod_error err;
    femlod_mesh *empty = make(NULL, 0, NULL, 0), *w = repair(empty, NULL, &r);
    CHECK(r.triangles_out == 0 && r.vertices_out == 0);
    femlod_mesh_free(w);
    femlod_mesh_free(empty);
    static const double p[] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    static const uint32_t t[] = {0, 1, 2};
    femlod_mesh *one = make(p, 3, t, 1);
    w = repair(one, NULL, &r);
    CHECK(shape_same_mesh(w, one));
    femlod_mesh_free(w);
    femlod_repair_options o = FEMLOD_REPAIR_OPTIONS_INIT;
    o.weld = NAN;
    femlod_mesh *out = (femlod_mesh *)&o; /* must stay untouched */
    CHECK(femlod_mesh_repair(&out, one, &o, &r, &err) == FEMLOD_EINPUT);
    CHECK(out == (femlod_mesh *)&o);
    CHECK_STR_HAS(err.message, "weld tolerance is nan");
    o.weld = INFINITY;
    CHECK(femlod_mesh_repair(&out, one, &o, &r, &err) == FEMLOD_EINPUT);
    femlod_mesh_free(one);
}

/* The defective meshes of the shared data: repaired, they are manifold and
 * oriented with no degenerate or duplicate triangle left. */
static void test_shared(const char *name) {
    char path[1024];
    snprintf(path, sizeof path, "%s/%s", FEMLOD_SHARED_DATA, name);
    femlod_mesh *m = NULL;
    femlod_error err;
    CHECK(femlod_mesh_read(&m, path, NULL, &err) == FEMLOD_OK);
    if (!m) return;
    femlod_repair_report r;
    femlod_mesh *w = repair(m, NULL, &r);
    femlod_topology before = topology(m), after = topology(w);
    femlod_quality q;
    CHECK(femlod_mesh_quality(w, &q, NULL) == FEMLOD_OK);
    printf("repair %s: %zu -> %zu triangles, %zu -> %zu vertices: welded %zu, degenerate %zu, "
           "duplicates %zu, split %zu, flipped %zu, unorientable %zu, unused %zu; non-manifold "
           "edges %zu -> %zu, vertices %zu -> %zu, inconsistent edges %zu -> %zu\n",
           name, r.triangles_in, r.triangles_out, r.vertices_in, r.vertices_out, r.welded,
           r.degenerate, r.duplicates, r.split_vertices, r.flipped, r.unorientable_edges,
           r.unused, before.nonmanifold_edges, after.nonmanifold_edges,
           before.nonmanifold_vertices, after.nonmanifold_vertices, before.inconsistent_edges,
           after.inconsistent_edges);
    CHECK(q.degenerate == 0 && q.duplicate == 0);
    CHECK(after.nonmanifold_edges == r.nonmanifold_edges_left);
    if (r.nonmanifold_edges_left == 0) CHECK(after.manifold);
    CHECK(after.inconsistent_edges == r.unorientable_edges);
    CHECK(after.isolated_vertices == 0);
    check_idempotent(w, NULL);
    femlod_mesh_free(w);
    femlod_mesh_free(m);
}

int main(void) {
    test_weld();
    test_degenerate_duplicates_unused();
    test_orient();
    test_nonmanifold();
    test_edge_cases();
    test_shared("sphereWithHole.stl");
    test_shared("spider_binary.stl");
    test_shared("2CylinderEngine.glb");
    test_shared("bunny.obj");
    return check_report("repair");
}
