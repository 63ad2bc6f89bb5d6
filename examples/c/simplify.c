/*
 * simplify.c - simplify a mesh to a target triangle count under the quality
 * thresholds, report what was reached and why, and write the result. Uses
 * only the public header (docs/api.md).
 *
 *   simplify MESH TARGET OUT
 *
 * TARGET is a triangle count; 0 simplifies as far as the thresholds allow.
 * Stopping short of the target is success: the program says why it stopped.
 * Every failure of the library prints femlod's one-line message and exits
 * with status 1; a usage error exits with status 2.
 */
#include <femlod.h>

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>

static void print_error(const femlod_error *err) {
    fprintf(stderr, "simplify: %s [%s]\n", err->message, femlod_status_name(err->status));
}

/* One row in the columns of the paper's Table 1. */
static void print_row(const char *name, const char *state, const femlod_quality *q) {
    printf("%s (%.4g x %.4g x %.4g) | %s | %zu | %.3f, %.3f | %.4g | %u\n", name,
           q->bbox_max[0] - q->bbox_min[0], q->bbox_max[1] - q->bbox_min[1],
           q->bbox_max[2] - q->bbox_min[2], state, q->triangles, q->stretch_avg, q->stretch_min,
           q->size_max, (unsigned)q->valence_max);
}

/* A resolved threshold: its value, or "off" (FEMLOD_SIMPLIFY_OFF). */
static void print_threshold(const char *name, double value) {
    if (value < 0.0)
        printf(" %s off", name);
    else
        printf(" %s %.6g", name, value);
}

int main(int argc, char **argv) {
    if (argc != 4) {
        fprintf(stderr, "usage: simplify MESH TARGET OUT\n");
        return 2; /* usage errors exit 2, as in the femlod program */
    }
    char *end;
    errno = 0;
    unsigned long long target = strtoull(argv[2], &end, 10);
    if (errno || end == argv[2] || *end || argv[2][0] == '-') {
        fprintf(stderr, "simplify: TARGET must be a triangle count, got '%s'\n", argv[2]);
        return 2;
    }

    int rc = EXIT_FAILURE;
    femlod_error err;
    femlod_mesh *mesh = NULL, *out = NULL;
    femlod_quality before, after;
    femlod_simplify_result res;
    femlod_hausdorff_result hd;
    /* Zero fields mean "the documented default"; set only what differs. */
    femlod_simplify_options opt = FEMLOD_SIMPLIFY_OPTIONS_INIT;
    opt.target = (size_t)target;
    opt.min_stretch = 0.2;

    if (femlod_mesh_read(&mesh, argv[1], NULL, &err) != FEMLOD_OK) goto error;
    if (femlod_mesh_quality(mesh, &before, &err) != FEMLOD_OK) goto error;

    if (femlod_simplify(&out, NULL, mesh, &opt, &res, &err) != FEMLOD_OK) goto error;
    if (femlod_mesh_quality(out, &after, &err) != FEMLOD_OK) goto error;
    /* NULL options: the default sample spacing (bounding-box diagonal / 500). */
    if (femlod_mesh_hausdorff(out, mesh, NULL, &hd, &err) != FEMLOD_OK) goto error;

    printf("model (H x W x D) | state | elements | stretch (avg, min) | size (max) | valence (max)\n");
    print_row(argv[1], "original", &before);
    print_row(argv[1], "simplified", &after);
    printf("stop: %s after %zu collapses (%zu in the pre-phase), %.3f s\n",
           femlod_stop_reason_name(res.stop_reason), res.collapses, res.prephase_collapses,
           res.seconds);
    printf("rejected:");
    for (int r = 0; r < FEMLOD_REJECT_COUNT; r++)
        printf("%s %s %zu", r ? "," : "", femlod_reject_name((femlod_reject)r), res.rejected[r]);
    printf("\nviolating input: %zu, dropped degenerate: %zu\n", res.violating_input,
           res.dropped_degenerate);
    printf("thresholds: target %zu", res.target);
    print_threshold("tolerance", res.tolerance);
    print_threshold("max_deviation", res.max_deviation);
    print_threshold("min_stretch", res.min_stretch);
    print_threshold("max_size", res.max_size);
    print_threshold("max_valence", res.max_valence);
    print_threshold("feature_angle", res.feature_angle);
    print_threshold("feature_weight", res.feature_weight);
    print_threshold("max_normal_change", res.max_normal_change);
    printf("\nhausdorff: %.6g (%.6g of the diagonal; forward %.6g, backward %.6g)\n", hd.distance,
           hd.relative, hd.forward, hd.backward);

    /* Written to a temporary file and renamed: a failure leaves argv[3] as it was. */
    if (femlod_mesh_write(out, argv[3], NULL, &err) != FEMLOD_OK) goto error;
    printf("wrote %s (%zu triangles, %zu vertices)\n", argv[3], res.triangles, res.vertices);
    rc = EXIT_SUCCESS;
    goto done;

error:
    print_error(&err);
done:
    femlod_mesh_free(out); /* _free(NULL) is a no-op */
    femlod_mesh_free(mesh);
    return rc;
}
