/* simplify_digest.c - a digest of femlod_simplify's outputs (mesh and
 * collapse log) over a fixed set of inputs and options, for checking that a
 * speed change leaves every result byte-identical: run it before and after
 * and compare the lines (docs/simplify.md "Benchmark").
 *
 * Usage: simplify_digest [data-folder [case-substring [threads]]]  ("" for
 * every case; threads: options.threads, which must not change a digest)
 * Each line: case name, output triangles, collapses, a 64-bit FNV-1a hash of
 * the output positions and triangles, one of the collapse log, and the
 * seconds (the only field that may differ between two runs). */
#include "digest.h"
#include "bench_util.h"
#include "femlod.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#ifndef FEMLOD_SHARED_DATA
#define FEMLOD_SHARED_DATA "../shared/data"
#endif

typedef struct scase {
    const char *name, *file;
    unsigned levels;
    size_t target;
    double tol, st, sz, dev, nc;
    int val, keep_boundary, area, lock;
    double fangle, fweight;
    double fast; /* fast_above; 0: the exact order (fast_above off) */
} scase;

static int lock_half(void *payload, double x, double y, double z) {
    (void)payload;
    (void)y;
    (void)z;
    return x > 40.0 && x < 45.0;
}

int main(int argc, char **argv) {
    const char *dir = argc > 1 ? argv[1] : FEMLOD_SHARED_DATA;
    const char *only = argc > 2 && argv[2][0] ? argv[2] : NULL;
    int threads = argc > 3 ? atoi(argv[3]) : 0; /* options.threads: the digests must not change with it */
    static const scase cases[] = {
        {"cover-paper-12k", "cover.obj", 0, 12000, 0.15, 0.2, 15, 0, 0, 12, 0, 0, 0, 0, 0, 0},
        {"cover-paper-6k", "cover.obj", 0, 6000, 0.15, 0.2, 15, 0, 0, 12, 0, 0, 0, 0, 0, 0},
        {"cover-default-all", "cover.obj", 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0},
        {"cover-dev-lock", "cover.obj", 0, 3000, 0, 0.3, 0, 0.05, 0, 10, 0, 0, 1, 0, 0, 0},
        {"cover-nocone-area", "cover.obj", 0, 5000, 0, 0, 0, 0, -1, -1, 0, 1, 0, 0, 0, 0},
        {"cover-notol", "cover.obj", 0, 2000, -1, -1, -1, 0, 30, 0, 0, 0, 0, 0, 0, 0},
        {"fandisk-2k", "fandisk.obj", 0, 2000, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0},
        {"fandisk-strict", "fandisk.obj", 0, 1000, 0, 0.4, 0, 0.01, 20, 8, 0, 0, 0, 0, 0, 0},
        {"fandisk-paper", "fandisk.obj", 0, 3000, 0.15, 0.2, 15, 0, 0, 12, 0, 0, 0, 0, 0, 0},
        {"bunny-3k", "bunny.obj", 0, 3000, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0},
        {"sphere-hole", "sphereWithHole.stl", 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0},
        {"sphere-hole-keep", "sphereWithHole.stl", 0, 0, 0, 0, 0, 0, 0, 0, 1, 0, 0, 0, 0, 0},
        {"spider", "spider_binary.stl", 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0},
        {"cover-nofeat", "cover.obj", 0, 4000, 0, 0, 0, 0, 0, 0, 0, 0, 0, -1, -1, 0},
        {"fandisk-dev-nocone", "fandisk.obj", 0, 1500, 0, 0, 0, 0.02, -1, 0, 0, 0, 0, 60, 5, 0},
        {"engine", "2CylinderEngine.glb", 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0},
        {"cover1-paper-12k", "cover.obj", 1, 12000, 0.15, 0.2, 15, 0, 0, 12, 0, 0, 0, 0, 0, 0},
        /* fast passes */
        {"cover-fast-12k", "cover.obj", 0, 12000, 0.15, 0.2, 15, 0, 0, 12, 0, 0, 0, 0, 0, 2},
        {"cover-fast-dev-lock", "cover.obj", 0, 3000, 0, 0.3, 0, 0.05, 0, 10, 0, 0, 1, 0, 0, 1.5},
        {"bunny-fast-3k", "bunny.obj", 0, 3000, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 2},
        {"cover1-fast-12k", "cover.obj", 1, 12000, 0.15, 0.2, 15, 0, 0, 12, 0, 0, 0, 0, 0, 2},
        /* the benchmark's input and options (bench_simplify's fast mode) */
        {"cover2-fast-50k", "cover.obj", 2, 50000, 0.15, 0.2, 15, 0, 0, 12, 0, 0, 0, 0, 0, 2},
        {"cover2-fast-12k", "cover.obj", 2, 12000, 0.15, 0.2, 15, 0, 0, 12, 0, 0, 0, 0, 0, 2},
    };
    /* Runs past the target (hierarchy_floor): the mesh must be the base
     * case's, the log longer (docs/design.md "The hierarchy below the
     * target"). */
    static const struct {
        const char *name, *base;
        size_t floor;
    } floors[] = {
        {"cover-paper-12k-floor", "cover-paper-12k", 1},
        {"fandisk-paper-floor", "fandisk-paper", 1},
        {"cover-fast-12k-floor", "cover-fast-12k", 6000},
    };
    size_t ncases = sizeof cases / sizeof cases[0], nfloors = sizeof floors / sizeof floors[0];
    for (size_t c = 0; c < ncases + nfloors; c++) {
        const scase *k = cases + c;
        const char *name = c < ncases ? cases[c].name : floors[c - ncases].name;
        size_t floor = 0;
        if (c >= ncases) {
            floor = floors[c - ncases].floor;
            for (k = cases; strcmp(k->name, floors[c - ncases].base) != 0; k++) {}
        }
        if (only && !strstr(name, only)) continue;
        char path[1024];
        snprintf(path, sizeof path, "%s/%s", dir, k->file);
        femlod_error err;
        femlod_mesh *m0 = NULL, *m = NULL;
        if (femlod_mesh_read(&m0, path, NULL, &err) != FEMLOD_OK) {
            printf("%-20s cannot read: %s\n", name, err.message);
            continue;
        }
        if (k->levels) {
            if (femlod_mesh_subdivide(&m, m0, k->levels, &err) != FEMLOD_OK) return 1;
            femlod_mesh_free(m0);
        } else {
            m = m0;
        }
        femlod_simplify_options o = FEMLOD_SIMPLIFY_OPTIONS_INIT;
        o.target = k->target;
        o.tolerance = k->tol;
        o.min_stretch = k->st;
        o.max_size = k->sz;
        o.max_deviation = k->dev;
        o.max_normal_change = k->nc;
        o.max_valence = k->val;
        o.keep_boundary = k->keep_boundary;
        o.area_weighted = k->area;
        if (k->lock) o.lock_fn = lock_half;
        o.feature_angle = k->fangle;
        o.feature_weight = k->fweight;
        o.fast_above = k->fast > 0.0 ? k->fast : FEMLOD_SIMPLIFY_OFF; /* 0: the exact order */
        o.threads = threads;
        o.hierarchy_floor = floor;
        /* the "paper" cases pin the paper's order (its Table 1); the rest
         * run femlod's default order, the error order */
        if (strstr(k->name, "paper")) o.error_order = -1;
        femlod_mesh *out = NULL;
        femlod_collapse_log *log = NULL;
        femlod_simplify_result res;
        double t0 = bench_now();
        if (femlod_simplify(&out, &log, m, &o, &res, &err) != FEMLOD_OK) {
            printf("%-20s error: %s\n", name, err.message);
            femlod_mesh_free(m);
            continue;
        }
        double t = bench_now() - t0;
        size_t nt = femlod_mesh_triangle_count(out);
        uint64_t hm = digest_mesh(out), hl = digest_log(log);
        printf("%-20s %7zu tris %7zu collapses (pre %zu) %s  mesh %016llx  log %016llx  %7.3f s\n", name, nt,
               res.collapses, res.prephase_collapses, femlod_stop_reason_name(res.stop_reason),
               (unsigned long long)hm, (unsigned long long)hl, t);
        if (floor)
            printf("%-20s %7zu tris in the log's coarsest state (%s), %zu collapses in all\n", "", res.hierarchy_triangles,
                   femlod_stop_reason_name(res.hierarchy_stop), femlod_collapse_log_count(log));
        fflush(stdout);
        femlod_collapse_log_free(log);
        femlod_mesh_free(out);
        femlod_mesh_free(m);
    }
    return 0;
}
