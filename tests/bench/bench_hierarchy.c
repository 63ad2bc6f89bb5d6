/* bench_hierarchy.c - vertex hierarchy throughput on cover.obj subdivided
 * twice (1,245,984 triangles) simplified to 12,000: build time, split and
 * collapse operations per second (refine(0) / coarsen(inf)), extraction
 * time, and a local change of about 10% of the front against the
 * simplification's time. Medians of several runs; no assertion on time.
 * Usage: bench_hierarchy [DATA_DIR] */
#include "bench_util.h"
#include "femlod.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <sys/resource.h>
#include <time.h>


static void die(const femlod_error *err) {
    fprintf(stderr, "bench_hierarchy: %s\n", err->message);
    exit(1);
}

/* Threshold: fine (0) inside a ball around the part's centre, coarse
 * (infinite) elsewhere. */
typedef struct ball {
    double c[3], r;
} ball;

static double ball_size(void *payload, const femlod_node_info *n) {
    const ball *b = payload;
    double d2 = 0;
    for (int k = 0; k < 3; k++) d2 += (n->position[k] - b->c[k]) * (n->position[k] - b->c[k]);
    return d2 <= b->r * b->r ? 0.0 : INFINITY;
}

int main(int argc, char **argv) {
    const char *data = argc > 1 ? argv[1] : "examples/data";
    char path[4096];
    snprintf(path, sizeof path, "%s/cover.obj", data);
    femlod_error err;
    femlod_mesh *cover = NULL, *dense = NULL, *out = NULL;
    if (femlod_mesh_read(&cover, path, NULL, &err) != FEMLOD_OK) die(&err);
    if (femlod_mesh_subdivide(&dense, cover, 2, &err) != FEMLOD_OK) die(&err);
    femlod_mesh_free(cover);
    size_t nt = femlod_mesh_triangle_count(dense);

    femlod_collapse_log *log = NULL;
    femlod_simplify_options o = FEMLOD_SIMPLIFY_OPTIONS_INIT;
    o.target = 12000;
    double t0 = bench_now();
    if (femlod_simplify(&out, &log, dense, &o, NULL, &err) != FEMLOD_OK) die(&err);
    double t_simplify = bench_now() - t0;
    printf("input %zu triangles; simplify to %zu: %.2f s\n", nt, femlod_mesh_triangle_count(out),
           t_simplify);

    enum { RUNS = 5 };
    double t_build[RUNS], t_split[RUNS], t_coll[RUNS], t_ext[RUNS], t_local[RUNS], t_back[RUNS];
    size_t n_split = 0, n_coll = 0, n_local = 0, front_coarse = 0, front_local = 0, bytes = 0;
    double lo[3], hi[3];
    femlod_mesh_bbox(dense, lo, hi);
    ball b = {{0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1]), 0.5 * (lo[2] + hi[2])}, 0};
    /* a ball holding about a tenth of the part's area: radius from the
     * in-plane extent (the cover is a plate) */
    b.r = sqrt(0.1 * (hi[0] - lo[0]) * (hi[1] - lo[1]) / 3.14159265358979);
    for (int r = 0; r < RUNS; r++) {
        femlod_hierarchy *h = NULL;
        femlod_mesh *m = NULL;
        t0 = bench_now();
        if (femlod_hierarchy_create(&h, dense, log, NULL, &err) != FEMLOD_OK) die(&err);
        t_build[r] = bench_now() - t0;
        bytes = femlod_hierarchy_bytes(h);
        front_coarse = femlod_hierarchy_front_triangles(h);
        t0 = bench_now();
        if (femlod_hierarchy_refine(h, 0.0, NULL, NULL, &n_split, &err) != FEMLOD_OK) die(&err);
        t_split[r] = bench_now() - t0;
        t0 = bench_now();
        if (femlod_hierarchy_coarsen(h, INFINITY, NULL, NULL, &n_coll, &err) != FEMLOD_OK) die(&err);
        t_coll[r] = bench_now() - t0;
        t0 = bench_now();
        if (femlod_hierarchy_refine(h, 0.0, ball_size, &b, &n_local, &err) != FEMLOD_OK) die(&err);
        t_local[r] = bench_now() - t0;
        front_local = femlod_hierarchy_front_triangles(h);
        t0 = bench_now();
        if (femlod_hierarchy_extract(h, &m, NULL, &err) != FEMLOD_OK) die(&err);
        t_ext[r] = bench_now() - t0;
        femlod_mesh_free(m);
        t0 = bench_now();
        size_t back = 0;
        if (femlod_hierarchy_coarsen(h, INFINITY, NULL, NULL, &back, &err) != FEMLOD_OK) die(&err);
        t_back[r] = bench_now() - t0;
        femlod_hierarchy_free(h);
    }
    double ts = bench_median(t_split, RUNS), tc = bench_median(t_coll, RUNS), tl = bench_median(t_local, RUNS);
    printf("hierarchy: %zu bytes (%.0f per input vertex), build %.3f s\n", bytes,
           (double)bytes / (double)femlod_mesh_vertex_count(dense), bench_median(t_build, RUNS));
    printf("split everything:    %zu splits in %.3f s = %.2f M splits/s\n", n_split, ts,
           (double)n_split / ts * 1e-6);
    printf("collapse everything: %zu collapses in %.3f s = %.2f M collapses/s\n", n_coll, tc,
           (double)n_coll / tc * 1e-6);
    printf("local refine (ball, %zu -> %zu triangles, %zu splits): %.4f s = %.2f%% of simplify\n",
           front_coarse, front_local, n_local, tl, 100.0 * tl / t_simplify);
    printf("extract the front (%zu triangles): %.4f s; coarsen back: %.4f s\n", front_local,
           bench_median(t_ext, RUNS), bench_median(t_back, RUNS));
    struct rusage ru;
    getrusage(RUSAGE_SELF, &ru);
    printf("peak resident memory: %.1f MiB\n", (double)ru.ru_maxrss / 1024.0);
    femlod_collapse_log_free(log);
    femlod_mesh_free(out);
    femlod_mesh_free(dense);
    return 0;
}
