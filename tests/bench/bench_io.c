/* bench_io.c - reading speed: a ~1.25M-triangle binary STL (cover.obj
 * subdivided twice, written by femlod) and the OBJ meshes of examples/data.
 * Prints the median of several runs; never asserts a time (see docs/testing.md).
 * Usage: bench_io [DATA_DIR] [TMP_DIR]
 *        bench_io --files FILE...   (medians of 3 warm loads each, in MB/s) */
#include "bench_util.h"
#include "femlod.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <time.h>


/* Median seconds of `runs` loads of path; prints the counts once. */
static double time_load(const char *path, int runs) {
    static const char *last;
    double t[15];
    if (runs > 15) runs = 15;
    for (int r = 0; r < runs; r++) {
        femlod_mesh *m = NULL;
        femlod_error err;
        double t0 = bench_now();
        if (femlod_mesh_read(&m, path, NULL, &err) != FEMLOD_OK) {
            fprintf(stderr, "bench_io: %s\n", err.message);
            exit(1);
        }
        t[r] = bench_now() - t0;
        if (r == 0 && path != last)
            printf("  %s: %zu triangles, %zu vertices\n", path, femlod_mesh_triangle_count(m),
                   femlod_mesh_vertex_count(m));
        femlod_mesh_free(m);
        last = path;
    }
    return bench_median(t, runs);
}

static double cpu_seconds(void) {
    struct rusage ru;
    getrusage(RUSAGE_SELF, &ru);
    return (double)ru.ru_utime.tv_sec + 1e-6 * (double)ru.ru_utime.tv_usec +
           (double)ru.ru_stime.tv_sec + 1e-6 * (double)ru.ru_stime.tv_usec;
}

/* Each file: one warm-up load, then 3 loads; the medians of their wall and
 * CPU (user + system) times, and the rates. On a shared machine the CPU
 * time is the steadier figure: the wall time also counts the waits for a
 * processor. */
static int time_files(int n, char **paths) {
    for (int i = 0; i < n; i++) {
        struct stat st;
        if (stat(paths[i], &st) != 0) {
            fprintf(stderr, "bench_io: cannot stat %s\n", paths[i]);
            return 1;
        }
        time_load(paths[i], 1);
        double wall[3], cpu[3];
        for (int r = 0; r < 3; r++) {
            double c0 = cpu_seconds();
            wall[r] = time_load(paths[i], 1);
            cpu[r] = cpu_seconds() - c0;
        }
        double w = bench_median(wall, 3), c = bench_median(cpu, 3), mb = (double)st.st_size / 1e6;
        printf("  %.1f MB: wall %.3f s (%.0f MB/s), CPU %.3f s (%.0f MB/s)\n", mb, w, mb / w, c,
               mb / c);
    }
    return 0;
}

int main(int argc, char **argv) {
    if (argc > 1 && strcmp(argv[1], "--files") == 0) return time_files(argc - 2, argv + 2);
    const char *data = argc > 1 ? argv[1] : "examples/data";
    const char *tmp = argc > 2 ? argv[2] : "/tmp";
    char path[4096], stl[4096];
    snprintf(path, sizeof path, "%s/cover.obj", data);
    snprintf(stl, sizeof stl, "%s/femlod-bench-cover4.stl", tmp);

    femlod_mesh *cover = NULL, *dense = NULL;
    femlod_error err;
    if (femlod_mesh_read(&cover, path, NULL, &err) != FEMLOD_OK ||
        femlod_mesh_subdivide(&dense, cover, 2, &err) != FEMLOD_OK ||
        femlod_mesh_write(dense, stl, NULL, &err) != FEMLOD_OK) {
        fprintf(stderr, "bench_io: %s\n", err.message);
        return 1;
    }
    femlod_mesh_free(cover);
    femlod_mesh_free(dense);

    printf("reading (median of 7 runs)\n");
    double t_stl = time_load(stl, 7);
    printf("  binary STL: %.3f s (%.0f ns per triangle)\n", t_stl, t_stl * 1e9 / (77874.0 * 16));
    const char *objs[] = {"cover.obj", "bunny.obj", "fandisk.obj"};
    for (int i = 0; i < 3; i++) {
        snprintf(path, sizeof path, "%s/%s", data, objs[i]);
        printf("  OBJ %s: %.3f s\n", objs[i], time_load(path, 7));
    }
    struct rusage ru;
    getrusage(RUSAGE_SELF, &ru);
    printf("peak resident memory: %.1f MiB\n", (double)ru.ru_maxrss / 1024.0);
    remove(stl);
    return 0;
}
