/*
 * mesh_info.c - print a mesh's quality report and, on request, subdivide it
 * and write the result. Uses only the public header (docs/api.md).
 *
 *   mesh_info MESH                  the report of MESH
 *   mesh_info MESH LEVELS [OUT]     also 1-to-4 subdivide LEVELS times, print
 *                                   both Table 1 rows and write OUT
 *
 * MESH and OUT may be .obj, .stl, .off or .ply files. Every failure of the
 * library prints femlod's one-line message and exits with status 1; a usage
 * error exits with status 2.
 */
#include <femlod.h>

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>

/* femlod's message names the culprit (file and line, argument, option). */
static void print_error(const femlod_error *err) {
    fprintf(stderr, "mesh_info: %s [%s]\n", err->message, femlod_status_name(err->status));
}

/* The multi-line report, laid out as femlod.report.text prints it in Lua. */
static void print_report(const char *name, const femlod_quality *q) {
    const femlod_topology *t = &q->topology;
    printf("%s: %zu triangles, %zu vertices\n", name, q->triangles, q->vertices);
    printf("  stretch     avg %.6g  min %.6g  max %.6g\n", q->stretch_avg, q->stretch_min,
           q->stretch_max);
    printf("  size        avg %.6g  min %.6g  max %.6g (longest edge)\n", q->size_avg, q->size_min,
           q->size_max);
    printf("  valence     avg %.6g  max %u\n", q->valence_avg, (unsigned)q->valence_max);
    printf("  angles      min %.6g  max %.6g (degrees)\n", q->angle_min, q->angle_max);
    printf("  area        %.6g\n", q->area);
    printf("  bbox        (%.6g, %.6g, %.6g) - (%.6g, %.6g, %.6g)\n", q->bbox_min[0],
           q->bbox_min[1], q->bbox_min[2], q->bbox_max[0], q->bbox_max[1], q->bbox_max[2]);
    printf("  topology    %s, %s, %s; %zu component%s, %zu edges\n", t->closed ? "closed" : "open",
           t->manifold ? "manifold" : "non-manifold", t->oriented ? "oriented" : "not oriented",
           t->components, t->components == 1 ? "" : "s", t->edges);
    printf("  edges       %zu boundary, %zu non-manifold, %zu inconsistent\n", t->boundary_edges,
           t->nonmanifold_edges, t->inconsistent_edges);
    printf("  triangles   %zu degenerate, %zu duplicate\n", q->degenerate, q->duplicate);
    printf("  vertices    %zu non-manifold, %zu isolated\n", t->nonmanifold_vertices,
           t->isolated_vertices);
    printf("  stretch histogram:\n");
    for (int k = 0; k < FEMLOD_HISTOGRAM_BINS; k++) {
        double share = q->triangles ? 100.0 * (double)q->histogram[k] / (double)q->triangles : 0.0;
        printf("    [%.1f, %.1f%c %8zu %5.1f%%\n", k / 10.0, (k + 1) / 10.0,
               k == FEMLOD_HISTOGRAM_BINS - 1 ? ']' : ')', q->histogram[k], share);
    }
}

/* One row in the columns of the paper's Table 1. */
static void print_row(const char *name, const char *state, const femlod_quality *q) {
    printf("%s (%.4g x %.4g x %.4g) | %s | %zu | %.3f, %.3f | %.4g | %u\n", name,
           q->bbox_max[0] - q->bbox_min[0], q->bbox_max[1] - q->bbox_min[1],
           q->bbox_max[2] - q->bbox_min[2], state, q->triangles, q->stretch_avg, q->stretch_min,
           q->size_max, (unsigned)q->valence_max);
}

int main(int argc, char **argv) {
    if (argc < 2 || argc > 4) {
        fprintf(stderr, "usage: mesh_info MESH [LEVELS [OUT]]\n");
        return 2; /* usage errors exit 2, as in the femlod program */
    }
    unsigned levels = 0;
    if (argc >= 3) {
        char *end;
        errno = 0;
        unsigned long n = strtoul(argv[2], &end, 10);
        if (errno || end == argv[2] || *end || argv[2][0] == '-' || n > 16) {
            fprintf(stderr, "mesh_info: LEVELS must be an integer in 0..16, got '%s'\n", argv[2]);
            return 2;
        }
        levels = (unsigned)n;
    }

    int rc = EXIT_FAILURE;
    femlod_error err;
    femlod_mesh *mesh = NULL, *fine = NULL;
    femlod_quality q, qf;

    /* NULL options: the format comes from the file name's extension. */
    if (femlod_mesh_read(&mesh, argv[1], NULL, &err) != FEMLOD_OK) goto error;
    if (femlod_mesh_quality(mesh, &q, &err) != FEMLOD_OK) goto error;
    print_report(argv[1], &q);

    if (argc >= 3) {
        char state[32];
        if (femlod_mesh_subdivide(&fine, mesh, levels, &err) != FEMLOD_OK) goto error;
        if (femlod_mesh_quality(fine, &qf, &err) != FEMLOD_OK) goto error;
        snprintf(state, sizeof state, "subdivided %u", levels);
        printf("\nmodel (H x W x D) | state | elements | stretch (avg, min) | size (max) | valence (max)\n");
        print_row(argv[1], "original", &q);
        print_row(argv[1], state, &qf);
        if (argc == 4) {
            /* Written to a temporary file and renamed: a failure leaves argv[3] as it was. */
            if (femlod_mesh_write(fine, argv[3], NULL, &err) != FEMLOD_OK) goto error;
            printf("wrote %s (%zu triangles, %zu vertices)\n", argv[3],
                   femlod_mesh_triangle_count(fine), femlod_mesh_vertex_count(fine));
        }
    }
    rc = EXIT_SUCCESS;
    goto done;

error:
    print_error(&err);
done:
    femlod_mesh_free(fine); /* _free(NULL) is a no-op */
    femlod_mesh_free(mesh);
    return rc;
}
