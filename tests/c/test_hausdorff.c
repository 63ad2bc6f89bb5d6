/* test_hausdorff.c - the sampled two-sided Hausdorff distance: cases whose
 * distance is known exactly or bounded by geometry, a brute-force check of
 * the tree search, the sampling rule and cap, determinism and errors. */
#include "check.h"
#include "core.h"
#include "shapes.h"

#include <stdlib.h>

static femlod_mesh *mesh_of(const double *p, size_t nv, const uint32_t *t, size_t nt) {
    femlod_mesh *m = NULL;
    femlod_status s = femlod_mesh_create(&m, p, nv, t, nt, NULL);
    CHECK(s == FEMLOD_OK);
    return m;
}

/* A copy of m with every position mapped by x -> s * x + d. */
static femlod_mesh *moved(const femlod_mesh *m, double s, double dx, double dy, double dz) {
    size_t nv = femlod_mesh_vertex_count(m);
    double *p = malloc(3 * nv * sizeof *p);
    const double *q = femlod_mesh_positions(m);
    for (size_t v = 0; v < nv; v++) {
        p[3 * v] = s * q[3 * v] + dx;
        p[3 * v + 1] = s * q[3 * v + 1] + dy;
        p[3 * v + 2] = s * q[3 * v + 2] + dz;
    }
    femlod_mesh *r = mesh_of(p, nv, femlod_mesh_triangles(m), femlod_mesh_triangle_count(m));
    free(p);
    return r;
}

static femlod_hausdorff_result hausdorff(const femlod_mesh *a, const femlod_mesh *b, double spacing,
                                         size_t max_samples) {
    femlod_hausdorff_options o = FEMLOD_HAUSDORFF_OPTIONS_INIT;
    o.spacing = spacing;
    o.max_samples = max_samples;
    femlod_hausdorff_result r;
    memset(&r, 0, sizeof r);
    femlod_error err;
    memset(&err, 0, sizeof err);
    femlod_status s = femlod_mesh_hausdorff(a, b, &o, &r, &err);
    CHECK(s == FEMLOD_OK);
    if (s != FEMLOD_OK) fprintf(stderr, "  hausdorff: %s\n", err.message);
    return r;
}

static int same_result(const femlod_hausdorff_result *a, const femlod_hausdorff_result *b) {
    return a->distance == b->distance && a->relative == b->relative &&
           a->forward == b->forward && a->backward == b->backward &&
           a->mean_forward == b->mean_forward && a->diagonal == b->diagonal &&
           a->samples == b->samples;
}

static void test_self(void) {
    femlod_mesh *m = shape_icosphere(2);
    femlod_hausdorff_result r = hausdorff(m, m, 0, 0);
    CHECK(r.distance <= 1e-12);
    CHECK(r.forward <= 1e-12 && r.backward <= 1e-12 && r.mean_forward <= 1e-12);
    CHECK(r.samples > 2 * 162);
    double lo[3], hi[3];
    femlod_mesh_bbox(m, lo, hi);
    double dx = hi[0] - lo[0], dy = hi[1] - lo[1], dz = hi[2] - lo[2];
    CHECK_NEAR(r.diagonal, sqrt(dx * dx + dy * dy + dz * dz), 1e-15);
    /* A copy is another object with the same surface. */
    femlod_mesh *c = NULL;
    CHECK(femlod_mesh_copy(&c, m, NULL) == FEMLOD_OK);
    femlod_hausdorff_result rc = hausdorff(c, m, 0, 0);
    CHECK(same_result(&r, &rc));
    femlod_mesh_free(c);
    femlod_mesh_free(m);
}

static void test_translated_plane(void) {
    femlod_mesh *a = shape_plane(8);
    femlod_mesh *b = moved(a, 1.0, 0, 0, 0.1);
    femlod_hausdorff_result r = hausdorff(a, b, 0, 0);
    CHECK_NEAR(r.forward, 0.1, 1e-12);
    CHECK_NEAR(r.backward, 0.1, 1e-12);
    CHECK_NEAR(r.distance, 0.1, 1e-12);
    CHECK_NEAR(r.mean_forward, 0.1, 1e-12);
    CHECK_NEAR(r.diagonal, sqrt(2.0), 1e-15);
    CHECK_NEAR(r.relative, 0.1 / sqrt(2.0), 1e-12);
    /* Default spacing sqrt2/500: the unit square holds tens of thousands
     * of grid points per side. */
    CHECK(r.samples > 2 * 100000);
    femlod_mesh_free(b);

    /* Shifted sideways by half a cell within the plane: the surfaces
     * overlap except for two strips; the farthest points are the corners
     * left uncovered, at the shift distance. */
    b = moved(a, 1.0, 0.0625, 0, 0);
    r = hausdorff(a, b, 0, 0);
    CHECK_NEAR(r.forward, 0.0625, 1e-12);
    CHECK_NEAR(r.backward, 0.0625, 1e-12);
    CHECK(r.mean_forward > 0 && r.mean_forward < 0.0625 / 8);
    femlod_mesh_free(b);
    femlod_mesh_free(a);
}

/* A patch in the middle of a large plane: every patch point is on the
 * plane, the plane's far corner (1, 1) is sqrt(0.5) from the patch. */
static void test_asymmetric(void) {
    femlod_mesh *big = shape_plane(8);
    femlod_mesh *unit = shape_plane(4);
    femlod_mesh *patch = moved(unit, 0.25, 0.25, 0.25, 0);
    femlod_hausdorff_result r = hausdorff(patch, big, 0, 0);
    CHECK(r.forward <= 1e-12);
    CHECK(r.mean_forward <= 1e-12);
    CHECK_NEAR(r.backward, sqrt(0.5), 1e-12);
    CHECK_NEAR(r.distance, sqrt(0.5), 1e-12);
    CHECK_NEAR(r.relative, sqrt(0.5) / sqrt(2.0), 1e-12);
    /* The other way round the roles swap; the diagonal is now the patch's. */
    femlod_hausdorff_result s = hausdorff(big, patch, 0.01, 0);
    CHECK_NEAR(s.forward, sqrt(0.5), 1e-12);
    CHECK(s.backward <= 1e-12);
    CHECK_NEAR(s.diagonal, 0.25 * sqrt(2.0), 1e-15);
    CHECK(s.mean_forward > 0.1);
    femlod_mesh_free(patch);
    femlod_mesh_free(unit);
    femlod_mesh_free(big);
}

/* Icosphere level 3 against level 1: both inscribed in the unit sphere, the
 * coarse vertices among the fine ones. With h the smallest distance from
 * the origin to a coarse face plane, every point of either surface is
 * within 1 - h of the other along its ray from the origin. A fine vertex v
 * outside the coarse solid is at least max_f (n_f . v - h_f) from it. */
static void test_icospheres(void) {
    femlod_mesh *fine = shape_icosphere(3), *coarse = shape_icosphere(1);
    const double *p = femlod_mesh_positions(coarse), *q = femlod_mesh_positions(fine);
    const uint32_t *t = femlod_mesh_triangles(coarse);
    size_t nt = femlod_mesh_triangle_count(coarse), nv = femlod_mesh_vertex_count(fine);
    double *n = malloc(4 * nt * sizeof *n), hmin = 1.0;
    for (size_t f = 0; f < nt; f++) {
        const double *a = p + 3 * t[3 * f], *b = p + 3 * t[3 * f + 1], *c = p + 3 * t[3 * f + 2];
        double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
        double w[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
        double x[3] = {u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2],
                       u[0] * w[1] - u[1] * w[0]};
        double l = sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]);
        for (int k = 0; k < 3; k++) n[4 * f + k] = x[k] / l;
        n[4 * f + 3] = n[4 * f] * a[0] + n[4 * f + 1] * a[1] + n[4 * f + 2] * a[2];
        CHECK(n[4 * f + 3] > 0); /* outward */
        if (n[4 * f + 3] < hmin) hmin = n[4 * f + 3];
    }
    double lower = 0;
    for (size_t v = 0; v < nv; v++) {
        double best = -1;
        for (size_t f = 0; f < nt; f++) {
            double d = n[4 * f] * q[3 * v] + n[4 * f + 1] * q[3 * v + 1] +
                       n[4 * f + 2] * q[3 * v + 2] - n[4 * f + 3];
            if (d > best) best = d;
        }
        if (best > lower) lower = best;
    }
    free(n);
    double upper = 1.0 - hmin;
    CHECK(lower > 0.5 * upper); /* the bracket says something */
    femlod_hausdorff_result r = hausdorff(fine, coarse, 0, 0);
    fprintf(stderr, "  icosphere 3 vs 1: forward %.6g backward %.6g, bracket [%.6g, %.6g]\n",
            r.forward, r.backward, lower, upper);
    CHECK(r.forward >= lower - 1e-12);
    CHECK(r.forward <= upper + 1e-12);
    CHECK(r.backward > 0 && r.backward <= upper + 1e-12);
    CHECK(r.mean_forward > 0 && r.mean_forward < r.forward);
    femlod_mesh_free(fine);
    femlod_mesh_free(coarse);
}

/* {====== brute force */

static double bf_dot(const double *u, const double *v) {
    return u[0] * v[0] + u[1] * v[1] + u[2] * v[2];
}

static double bf_segment(const double *p, const double *a, const double *b) {
    double ab[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    double ap[3] = {p[0] - a[0], p[1] - a[1], p[2] - a[2]};
    double l = bf_dot(ab, ab), t = l > 0 ? bf_dot(ap, ab) / l : 0;
    t = t < 0 ? 0 : t > 1 ? 1 : t;
    double e[3] = {ap[0] - t * ab[0], ap[1] - t * ab[1], ap[2] - t * ab[2]};
    return sqrt(bf_dot(e, e));
}

/* A different route from the library's region tests: project on the plane
 * and solve for barycentric coordinates; outside (or flat), the nearest
 * side. */
static double bf_triangle(const double *p, const double *a, const double *b, const double *c) {
    double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    double v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    double w[3] = {p[0] - a[0], p[1] - a[1], p[2] - a[2]};
    double uu = bf_dot(u, u), uv = bf_dot(u, v), vv = bf_dot(v, v);
    double wu = bf_dot(w, u), wv = bf_dot(w, v);
    double det = uu * vv - uv * uv;
    if (det > 1e-12 * uu * vv) {
        double s = (wu * vv - wv * uv) / det, t = (wv * uu - wu * uv) / det;
        if (s >= 0 && t >= 0 && s + t <= 1) {
            double e[3] = {w[0] - s * u[0] - t * v[0], w[1] - s * u[1] - t * v[1],
                           w[2] - s * u[2] - t * v[2]};
            return sqrt(bf_dot(e, e));
        }
    }
    return fmin(bf_segment(p, a, b), fmin(bf_segment(p, b, c), bf_segment(p, c, a)));
}

static double bf_to_mesh(const double *p, const femlod_mesh *m) {
    const double *q = femlod_mesh_positions(m);
    const uint32_t *t = femlod_mesh_triangles(m);
    double best = INFINITY;
    for (size_t f = 0; f < femlod_mesh_triangle_count(m); f++)
        best = fmin(best,
                    bf_triangle(p, q + 3 * t[3 * f], q + 3 * t[3 * f + 1], q + 3 * t[3 * f + 2]));
    return best;
}

/* With an enormous spacing the samples are exactly the vertices and the
 * edge midpoints (a + b) / 2: the one-sided distance is their farthest. */
static double bf_one_side(const femlod_mesh *from, const femlod_mesh *to) {
    const double *q = femlod_mesh_positions(from);
    const uint32_t *t = femlod_mesh_triangles(from);
    double worst = 0;
    for (size_t f = 0; f < femlod_mesh_triangle_count(from); f++)
        for (int i = 0; i < 3; i++) {
            const double *a = q + 3 * t[3 * f + i], *b = q + 3 * t[3 * f + (i + 1) % 3];
            double mid[3] = {(a[0] + b[0]) / 2, (a[1] + b[1]) / 2, (a[2] + b[2]) / 2};
            worst = fmax(worst, fmax(bf_to_mesh(a, to), bf_to_mesh(mid, to)));
        }
    return worst;
}

static uint64_t rng_state = 99;
static double rnd(void) {
    rng_state = rng_state * 6364136223846793005ull + 1442695040888963407ull;
    return (double)(rng_state >> 11) / 9007199254740992.0;
}

/* A bumpy sphere against a rotated, shifted coarse one carrying degenerate
 * triangles (a segment, a point, a sliver): the tree search must find what
 * trying every triangle finds. */
static void test_brute_force(void) {
    femlod_mesh *s = shape_icosphere(2);
    size_t nv = femlod_mesh_vertex_count(s);
    double *p = malloc(3 * nv * sizeof *p);
    memcpy(p, femlod_mesh_positions(s), 3 * nv * sizeof *p);
    for (size_t v = 0; v < nv; v++) {
        double f = 1.0 + 0.2 * (rnd() - 0.5);
        for (int k = 0; k < 3; k++) p[3 * v + k] *= f;
    }
    femlod_mesh *a = mesh_of(p, nv, femlod_mesh_triangles(s), femlod_mesh_triangle_count(s));
    free(p);
    femlod_mesh_free(s);

    femlod_mesh *c = shape_icosphere(1);
    size_t cv = femlod_mesh_vertex_count(c), ct = femlod_mesh_triangle_count(c);
    double *cp = malloc((3 * cv + 9) * sizeof *cp);
    uint32_t *tp = malloc((3 * ct + 9) * sizeof *tp);
    const double ang = 0.3, co = cos(ang), si = sin(ang);
    const double *src = femlod_mesh_positions(c);
    for (size_t v = 0; v < cv; v++) {
        cp[3 * v] = co * src[3 * v] - si * src[3 * v + 1] + 0.05;
        cp[3 * v + 1] = si * src[3 * v] + co * src[3 * v + 1];
        cp[3 * v + 2] = src[3 * v + 2] * 1.1;
    }
    const double extra[9] = {1.5, 0, 0, 1.5, 0.5, 0, 1.5, 1e-13, 0.25};
    memcpy(cp + 3 * cv, extra, sizeof extra);
    memcpy(tp, femlod_mesh_triangles(c), 3 * ct * sizeof *tp);
    uint32_t e0 = (uint32_t)cv;
    const uint32_t more[9] = {e0, e0 + 1, e0, /* a segment */ e0 + 1, e0 + 1, e0 + 1, /* a point */
                              e0, e0 + 1, e0 + 2 /* a sliver */};
    memcpy(tp + 3 * ct, more, sizeof more);
    femlod_mesh *b = mesh_of(cp, cv + 3, tp, ct + 3);
    free(cp);
    free(tp);
    femlod_mesh_free(c);

    femlod_hausdorff_result r = hausdorff(a, b, 1e30, 0);
    double fwd = bf_one_side(a, b), bwd = bf_one_side(b, a);
    CHECK_NEAR(r.forward, fwd, 1e-12);
    CHECK_NEAR(r.backward, bwd, 1e-12);
    CHECK(r.forward > 0.05 && r.backward > 0.3); /* the detached triangles are far */
    /* Vertices plus one midpoint per distinct edge, on both sides. */
    CHECK(r.samples == (162 + 480) + (45 + 120 + 3));

    /* Swapping the meshes swaps the sides exactly when the spacing is fixed:
     * the backward pass, which may stop searches early, finds the same
     * maximum as the forward pass. */
    femlod_hausdorff_result r2 = hausdorff(b, a, 1e30, 0);
    CHECK(r2.forward == r.backward && r2.backward == r.forward);
    femlod_hausdorff_result g1 = hausdorff(a, b, 0.05, 0), g2 = hausdorff(b, a, 0.05, 0);
    CHECK(g1.forward == g2.backward && g1.backward == g2.forward);
    CHECK(g1.samples == g2.samples);
    CHECK(g1.forward >= r.forward && g1.backward >= r.backward); /* more samples, same ones kept */
    femlod_mesh_free(a);
    femlod_mesh_free(b);
}

/* }====== */

/* The sampling rule on the unit square of two triangles at spacing 1/4:
 * 4 vertices; the four unit sides get 3 points each (the midpoint among
 * them), the diagonal ceil(4 sqrt2) = 6 steps, 5 points; each triangle a
 * grid of 6 steps (its longest side is the diagonal), (6-1)(6-2)/2 = 10
 * interior points. 41 a side. */
static void test_sampling(void) {
    femlod_mesh *m = shape_plane(1);
    femlod_hausdorff_result r = hausdorff(m, m, 0.25, 0);
    CHECK(r.samples == 2 * 41);
    CHECK(r.distance <= 1e-12);
    femlod_mesh_free(m);

    /* The cap: plane(4) has 25 vertices and 56 edges, always sampled. */
    m = shape_plane(4);
    r = hausdorff(m, m, 0.002, 0);
    CHECK(r.samples > 2 * 250000); /* about 2 / (sqrt3 * 0.002^2) a side */
    r = hausdorff(m, m, 0.001, 2000);
    CHECK(r.samples <= 2 * 2000);
    CHECK(r.samples > 2 * 1000); /* the spacing grew about as far as needed, not further */
    r = hausdorff(m, m, 0.001, 50);
    CHECK(r.samples == 2 * (25 + 56));
    femlod_mesh_free(m);
}

static void test_determinism(void) {
    femlod_mesh *a = shape_icosphere(3), *b = shape_cylinder(24, 8, 2.0);
    femlod_hausdorff_result r1 = hausdorff(a, b, 0, 0), r2 = hausdorff(a, b, 0, 0);
    CHECK(same_result(&r1, &r2));
    CHECK(r1.forward > 0 && r1.backward > 0);
    /* The cylinder (radius 1, z in [0, 2]) reaches z = 2, the sphere z <= 1. */
    CHECK(r1.backward >= 1.0 - 1e-12);
    femlod_mesh_free(a);
    femlod_mesh_free(b);
}

static void test_errors(void) {
    femlod_mesh *m = shape_plane(2);
    femlod_mesh *empty = mesh_of(NULL, 0, NULL, 0);
    femlod_hausdorff_result r, before;
    memset(&r, 0x5A, sizeof r);
    before = r;
    femlod_error err;
    memset(&err, 0, sizeof err);
    CHECK(femlod_mesh_hausdorff(empty, m, NULL, &r, &err) == FEMLOD_EINPUT);
    CHECK_STR_HAS(err.message, "the mesh has no triangle");
    CHECK(femlod_mesh_hausdorff(m, empty, NULL, &r, &err) == FEMLOD_EINPUT);
    CHECK_STR_HAS(err.message, "the reference has no triangle");
    femlod_hausdorff_options o = FEMLOD_HAUSDORFF_OPTIONS_INIT;
    o.spacing = -1;
    CHECK(femlod_mesh_hausdorff(m, m, &o, &r, &err) == FEMLOD_EINPUT);
    CHECK_STR_HAS(err.message, "spacing must be a finite number >= 0 (got -1)");
    o.spacing = NAN;
    CHECK(femlod_mesh_hausdorff(m, m, &o, &r, NULL) == FEMLOD_EINPUT);
    o.spacing = INFINITY;
    CHECK(femlod_mesh_hausdorff(m, m, &o, &r, NULL) == FEMLOD_EINPUT);
    CHECK(memcmp(&r, &before, sizeof r) == 0); /* *out untouched on failure */
    CHECK(femlod_mesh_hausdorff(m, m, NULL, &r, NULL) == FEMLOD_OK);
    CHECK(r.distance <= 1e-12);

    /* A reference shrunk to one point: no diagonal, vertices only. */
    const double p[] = {0, 0, 0};
    const uint32_t t[] = {0, 0, 0};
    femlod_mesh *dot = mesh_of(p, 1, t, 1);
    r = hausdorff(m, dot, 0, 0);
    CHECK(r.diagonal == 0 && r.relative == 0);
    CHECK_NEAR(r.forward, sqrt(2.0), 1e-15);
    CHECK(r.backward == 0);
    femlod_mesh_free(dot);
    femlod_mesh_free(empty);
    femlod_mesh_free(m);
}

/* Real meshes: subdivision keeps the surface, so fandisk subdivided lies on
 * fandisk; the bunny against a copy is the speed case of docs/quality.md. */
static void test_shared(void) {
    const char *names[] = {"fandisk.obj", "bunny.obj"};
    for (int i = 0; i < 2; i++) {
        char path[1024];
        snprintf(path, sizeof path, "%s/%s", FEMLOD_SHARED_DATA, names[i]);
        femlod_mesh *m = NULL, *s = NULL;
        femlod_error err;
        memset(&err, 0, sizeof err);
        femlod_status st = femlod_mesh_read(&m, path, NULL, &err);
        CHECK(st == FEMLOD_OK);
        if (st != FEMLOD_OK) {
            fprintf(stderr, "  %s: %s\n", names[i], err.message);
            continue;
        }
        if (i == 0)
            CHECK(femlod_mesh_subdivide(&s, m, 1, NULL) == FEMLOD_OK);
        else
            CHECK(femlod_mesh_copy(&s, m, NULL) == FEMLOD_OK);
        femlod_hausdorff_result r = hausdorff(s, m, 0, 0);
        CHECK(r.relative <= 1e-12);
        CHECK(r.samples > femlod_mesh_vertex_count(m));
        femlod_mesh_free(s);
        femlod_mesh_free(m);
    }
}

/* The progress callback: about every 1% of the triangles of both sides,
 * ending at 1, the result the same as without; a cancel fails with
 * FEMLOD_ECANCELLED, stops calling and leaves *out as it was. */
static void test_progress(void) {
    femlod_mesh *a = shape_icosphere(5), *b = shape_icosphere(3);
    femlod_hausdorff_result want = hausdorff(a, b, 0, 0), got, kept;
    femlod_hausdorff_options o = FEMLOD_HAUSDORFF_OPTIONS_INIT;
    check_progress pr = CHECK_PROGRESS_INIT;
    o.progress = check_progress_fn;
    o.progress_payload = &pr;
    CHECK(femlod_mesh_hausdorff(a, b, &o, &got, NULL) == FEMLOD_OK);
    CHECK_PROGRESS_DONE(pr, 90);
    CHECK(same_result(&got, &want));
    check_progress stop = CHECK_PROGRESS_INIT;
    stop.stop_at = 50;
    o.progress_payload = &stop;
    memset(&kept, 0x5A, sizeof kept);
    got = kept;
    femlod_error err;
    CHECK(femlod_mesh_hausdorff(a, b, &o, &got, &err) == FEMLOD_ECANCELLED);
    CHECK(stop.calls == 50);
    CHECK(memcmp(&got, &kept, sizeof got) == 0);
    CHECK(strcmp(err.message, "hausdorff: cancelled by the progress callback") == 0);
    femlod_mesh_free(a);
    femlod_mesh_free(b);
}

int main(void) {
    test_progress();
    test_self();
    test_translated_plane();
    test_asymmetric();
    test_icospheres();
    test_brute_force();
    test_sampling();
    test_determinism();
    test_errors();
    test_shared();
    return check_report("hausdorff");
}
