/* test_error_order.c - the error order, femlod's default (error_order,
 * docs/design.md "An order that knows the error"), measured on its
 * outputs: at equal count on cover.obj its Hausdorff distance to the input
 * is far below the paper's order's and within twice OpenMesh+aspect's,
 * its stretch above OpenMesh+aspect's by 0.03; with
 * max_deviation the bound still holds; fandisk's sharp edges survive; the
 * runs repeat byte for byte for 1 and 2 threads, exact and fast. */
#include "check.h"
#include "core.h"
#include "intersect.h"
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

static double diagonal(const femlod_mesh *m) {
    double lo[3], hi[3];
    femlod_mesh_bbox(m, lo, hi);
    return sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) + (hi[2] - lo[2]) * (hi[2] - lo[2]));
}

/* One run: the output's Hausdorff distance to m, its stretch; NULL on failure. */
typedef struct outcome {
    femlod_mesh *out;
    femlod_simplify_result res;
    femlod_quality q;
    double hausdorff;
} outcome;

static int run(outcome *r, const femlod_mesh *m, const femlod_simplify_options *o, const char *label) {
    femlod_error err;
    r->out = NULL;
    CHECK(femlod_simplify(&r->out, NULL, m, o, &r->res, &err) == FEMLOD_OK);
    if (!r->out) return 0;
    femlod_hausdorff_result h;
    CHECK(femlod_mesh_quality(r->out, &r->q, NULL) == FEMLOD_OK);
    CHECK(femlod_mesh_hausdorff(r->out, m, NULL, &h, &err) == FEMLOD_OK);
    r->hausdorff = h.distance;
    printf("  %-34s %6zu triangles (%s): hausdorff %.4g, stretch avg %.3f min %.3f, size max %.3g, valence max %u\n",
           label, r->q.triangles, femlod_stop_reason_name(r->res.stop_reason), h.distance, r->q.stretch_avg,
           r->q.stretch_min, r->q.size_max, (unsigned)r->q.valence_max);
    return 1;
}

/* cover.obj at 12,000 and 6,000: the paper's order (error_order < 0), then
 * the default (the error order). Measured: Hausdorff 0.68 / 0.72 against
 * 0.0090 / 0.149, stretch avg 0.806 / 0.777 against 0.775 / 0.687.
 * The default must meet issue 37's bar against OpenMesh's Decimater with
 * ModQuadric, ModAspectRatio(5) and ModNormalFlipping at the same count:
 * Hausdorff at most twice its, average stretch at least its + 0.03, least
 * stretch at least 0.2. The test cannot run OpenMesh: its figures are
 * pinned as tests/bench/bench_peers measured them on cover.obj
 * (docs/simplify.md, the Peers table): 0.00866 / 0.737 at 12,000, 0.149 /
 * 0.615 at 6,000 (Hausdorff from femlod_mesh_hausdorff / stretch avg). */
static void test_cover(void) {
    femlod_mesh *m = load("cover.obj");
    if (!m) return;
    const size_t targets[2] = {12000, 6000};
    const double ratio[2] = {20.0, 2.0};           /* the default's distance at least this much smaller */
    const double peer_h[2] = {0.00866, 0.149};     /* OpenMesh+aspect's Hausdorff, bench_peers */
    const double peer_avg[2] = {0.737, 0.615};     /* its average stretch */
    for (int k = 0; k < 2; k++) {
        femlod_simplify_options o = FEMLOD_SIMPLIFY_OPTIONS_INIT;
        o.target = targets[k];
        o.error_order = -1;
        outcome plain, err;
        char label[64];
        snprintf(label, sizeof label, "cover %zu, paper's order", targets[k]);
        if (!run(&plain, m, &o, label)) continue;
        o.error_order = 0; /* the default */
        snprintf(label, sizeof label, "cover %zu, default (error order)", targets[k]);
        if (run(&err, m, &o, label)) {
            CHECK(err.res.stop_reason == FEMLOD_STOP_TARGET && err.q.triangles == targets[k]);
            CHECK(err.hausdorff * ratio[k] <= plain.hausdorff);
            CHECK(err.hausdorff <= 2.0 * peer_h[k]);
            CHECK(err.q.stretch_avg >= peer_avg[k] + 0.03);
            CHECK(err.q.stretch_min >= 0.2 && err.q.valence_max <= 12);
            CHECK(err.q.size_max <= err.res.max_size * (1 + 1e-12));
            femlod_mesh_free(err.out);
        }
        femlod_mesh_free(plain.out);
    }
    femlod_mesh_free(m);
}

/* max_deviation still bounds the distance under the error order. */
static void test_bound(void) {
    const char *names[2] = {"cover.obj", "fandisk.obj"};
    const size_t targets[2] = {12000, 2000};
    for (int k = 0; k < 2; k++) {
        femlod_mesh *m = load(names[k]);
        if (!m) continue;
        for (int fast = 0; fast < 2; fast++) {
            femlod_simplify_options o = FEMLOD_SIMPLIFY_OPTIONS_INIT;
            o.target = targets[k];
            o.error_order = 1;
            o.max_deviation = 1e-3 * diagonal(m);
            o.fast_above = fast ? 2.0 : FEMLOD_SIMPLIFY_OFF; /* off: the exact order */
            outcome r;
            char label[64];
            snprintf(label, sizeof label, "%s %s, d 1e-3 diag", names[k], fast ? "fast" : "exact");
            if (!run(&r, m, &o, label)) continue;
            CHECK(r.hausdorff <= 1.05 * o.max_deviation);
            CHECK(r.q.stretch_min >= 0.2);
            femlod_mesh_free(r.out);
        }
        femlod_mesh_free(m);
    }
}

/* The midpoints of the input's sharp edges (dihedral above 40 degrees). */
static size_t sharp_midpoints(const femlod_mesh *m, double **out) {
    fl_adjacency adj;
    *out = NULL;
    if (fl_adjacency_build(&adj, m->tri, m->nt, m->nv, NULL) != FEMLOD_OK) return 0;
    double *mid = malloc(3 * adj.ne * sizeof *mid);
    size_t n = 0;
    for (size_t e = 0; e < adj.ne && mid; e++) {
        if (adj.edge_start[e + 1] - adj.edge_start[e] != 2) continue;
        double nn[2][3];
        for (int s = 0; s < 2; s++) {
            const uint32_t *t = m->tri + 3 * (size_t)adj.edge_tris[adj.edge_start[e] + s];
            const double *a = m->pos + 3 * (size_t)t[0], *b = m->pos + 3 * (size_t)t[1], *c = m->pos + 3 * (size_t)t[2];
            double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
            nn[s][0] = u[1] * v[2] - u[2] * v[1];
            nn[s][1] = u[2] * v[0] - u[0] * v[2];
            nn[s][2] = u[0] * v[1] - u[1] * v[0];
            double l = sqrt(nn[s][0] * nn[s][0] + nn[s][1] * nn[s][1] + nn[s][2] * nn[s][2]);
            for (int k = 0; k < 3; k++) nn[s][k] /= l;
        }
        if (nn[0][0] * nn[1][0] + nn[0][1] * nn[1][1] + nn[0][2] * nn[1][2] > cos(40.0 * 3.14159265358979 / 180.0))
            continue;
        const double *a = m->pos + 3 * (size_t)adj.edge_v[2 * e], *b = m->pos + 3 * (size_t)adj.edge_v[2 * e + 1];
        for (int k = 0; k < 3; k++) mid[3 * n + k] = 0.5 * (a[k] + b[k]);
        n++;
    }
    fl_adjacency_free(&adj);
    *out = mid;
    return n;
}

/* fandisk to 2,000 under the error order: the sharp edges survive, as the
 * paper's order's test requires (tests/c/test_simplify.c test_fandisk). */
static void test_fandisk(void) {
    femlod_mesh *m = load("fandisk.obj");
    if (!m) return;
    double diag = diagonal(m);
    femlod_simplify_options o = FEMLOD_SIMPLIFY_OPTIONS_INIT;
    o.target = 2000;
    o.error_order = 1;
    outcome r;
    if (run(&r, m, &o, "fandisk 2000, error order")) {
        CHECK(r.res.stop_reason == FEMLOD_STOP_TARGET);
        double *mid;
        size_t n = sharp_midpoints(m, &mid), far = 0;
        double worst = 0;
        for (size_t q = 0; q < n; q++) {
            double best = 1e300;
            for (size_t f = 0; f < r.out->nt; f++) {
                const uint32_t *t = r.out->tri + 3 * f;
                double d2 = fl_point_tri_dist2(mid + 3 * q, r.out->pos + 3 * (size_t)t[0], r.out->pos + 3 * (size_t)t[1],
                                               r.out->pos + 3 * (size_t)t[2]);
                if (d2 < best) best = d2;
            }
            double d = sqrt(best);
            worst = fmax(worst, d);
            if (d > 1e-3 * diag) far++;
        }
        printf("  fandisk 2000, error order: %zu sharp-edge midpoints, farthest %.3g (%.2e diag), %zu beyond 1e-3 diag\n",
               n, worst, worst / diag, far);
        CHECK(n > 100);
        CHECK(worst <= 7.5e-3 * diag);
        CHECK(far * 20 <= n);
        free(mid);
        femlod_mesh_free(r.out);
    }
    femlod_mesh_free(m);
}

/* The same output for 1 and 2 threads, exact order and fast passes; the
 * default (0) is error_order = 1, and error_order = -1 (the paper's order)
 * another mesh. */
static void test_threads(void) {
    femlod_mesh *m = load("fandisk.obj");
    if (!m) return;
    femlod_simplify_options o = FEMLOD_SIMPLIFY_OPTIONS_INIT;
    o.target = 1500;
    o.error_order = 1;
    CHECK(meshcheck_same_for_threads(m, &o));
    for (int fast = 0; fast < 2; fast++) {
        femlod_mesh *a = NULL, *c = NULL, *d = NULL;
        o.fast_above = fast ? 2.0 : FEMLOD_SIMPLIFY_OFF; /* off: the exact order */
        o.error_order = 1;
        CHECK(femlod_simplify(&a, NULL, m, &o, NULL, NULL) == FEMLOD_OK);
        o.error_order = 0;
        CHECK(femlod_simplify(&c, NULL, m, &o, NULL, NULL) == FEMLOD_OK);
        CHECK(a && c && shape_same_mesh(a, c));
        o.error_order = -1;
        CHECK(femlod_simplify(&d, NULL, m, &o, NULL, NULL) == FEMLOD_OK);
        CHECK(a && d && !shape_same_mesh(a, d));
        femlod_mesh_free(a);
        femlod_mesh_free(c);
        femlod_mesh_free(d);
    }
    femlod_mesh_free(m);
}

int main(void) {
    test_cover();
    test_bound();
    test_fandisk();
    test_threads();
    return check_report("test_error_order");
}
