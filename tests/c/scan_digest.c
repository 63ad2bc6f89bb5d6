/* scan_digest.c - digests of fast-pass simplifications, built three times:
 * against the library as it is; with every file of src/simplify/
 * compiled with FEMLOD_SIMPLIFY_MARKED_SCAN=1 (band_vertex, fast.c, then
 * finds a vertex's edges by the marked scan everywhere, not one side per
 * face at interior vertices of an oriented mesh); and with
 * FEMLOD_SIMPLIFY_C1_SKIP=0 (every edge evaluated at each raise of
 * error_order's cap in the passes). The tests scan_equivalence and
 * cap_round_equivalence (tests/scan_compare.cmake) run the library's build
 * against each other one and require identical lines: the one-side scan
 * must find the same edges, and the skipped evaluations must be those that
 * cannot change, so the passes make the same choices (docs/simplify.md
 * "Fast passes", docs/design.md "Cap rounds without the evaluations that
 * cannot change").
 *
 * Usage: scan_digest DATA-FOLDER. Each line: case, output triangles,
 * collapses, fast collapses, FNV-1a hashes of the output mesh and of the
 * collapse log, and the rejection counts. */
#include "digest.h"
#include "femlod.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static int lock_left(void *payload, double x, double y, double z) {
    (void)payload;
    (void)y;
    (void)z;
    return x < -0.2;
}

static int digest(const char *name, const femlod_mesh *m, const femlod_simplify_options *o) {
    femlod_mesh *out = NULL;
    femlod_collapse_log *log = NULL;
    femlod_simplify_result res;
    femlod_error err;
    if (femlod_simplify(&out, &log, m, o, &res, &err) != FEMLOD_OK) {
        fprintf(stderr, "%s: %s\n", name, err.message);
        return 1;
    }
    size_t nt = femlod_mesh_triangle_count(out);
    uint64_t hm = digest_mesh(out), hl = digest_log(log);
    printf("%s %zu %zu %zu %016llx %016llx", name, nt, res.collapses, res.fast_collapses,
           (unsigned long long)hm, (unsigned long long)hl);
    for (int k = 0; k < FEMLOD_REJECT_COUNT; k++) printf(" %zu", res.rejected[k]);
    printf("\n");
    femlod_mesh_free(out);
    femlod_collapse_log_free(log);
    /* a case where the passes did nothing would compare nothing */
    if (res.fast_collapses == 0) {
        fprintf(stderr, "%s: no collapse in fast passes\n", name);
        return 1;
    }
    return 0;
}

static femlod_mesh *load(const char *dir, const char *file) {
    char path[1024];
    snprintf(path, sizeof path, "%s/%s", dir, file);
    femlod_mesh *m = NULL;
    femlod_error err;
    if (femlod_mesh_read(&m, path, NULL, &err) != FEMLOD_OK) fprintf(stderr, "%s\n", err.message);
    return m;
}

/* The same surface with every triangle reversed: still consistently
 * oriented (inwards), so the one-side scan runs, on the other side of each
 * face. */
static femlod_mesh *inside_out(const femlod_mesh *m) {
    size_t nv = femlod_mesh_vertex_count(m), nt = femlod_mesh_triangle_count(m);
    uint32_t *t = malloc(3 * nt * sizeof *t);
    if (!t) return NULL;
    const uint32_t *s = femlod_mesh_triangles(m);
    for (size_t f = 0; f < nt; f++) {
        t[3 * f] = s[3 * f];
        t[3 * f + 1] = s[3 * f + 2];
        t[3 * f + 2] = s[3 * f + 1];
    }
    femlod_mesh *r = NULL;
    femlod_error err;
    if (femlod_mesh_create(&r, femlod_mesh_positions(m), nv, t, nt, &err) != FEMLOD_OK)
        fprintf(stderr, "%s\n", err.message);
    free(t);
    return r;
}

int main(int argc, char **argv) {
    if (argc != 2) {
        fprintf(stderr, "usage: scan_digest DATA-FOLDER\n");
        return 2;
    }
    int bad = 0;
    femlod_mesh *fan = load(argv[1], "fandisk.obj"), *cover = load(argv[1], "cover.obj");
    femlod_mesh *hole = load(argv[1], "sphereWithHole.stl");
    femlod_mesh *rev = fan ? inside_out(fan) : NULL;
    if (!fan || !cover || !hole || !rev) return 1;

    femlod_simplify_options o = FEMLOD_SIMPLIFY_OPTIONS_INIT;
    o.target = 1000;
    o.fast_above = 1.5;
    o.threads = 2;
    bad |= digest("fandisk-fast-1000", fan, &o);
    bad |= digest("fandisk-inside-out-fast-1000", rev, &o);
    o.max_deviation = 0.003;
    o.lock_fn = lock_left;
    o.threads = 3;
    bad |= digest("fandisk-fast-1000-deviation-locks", fan, &o);

    o = (femlod_simplify_options)FEMLOD_SIMPLIFY_OPTIONS_INIT;
    o.error_order = -1; /* the paper's order and thresholds */
    o.target = 12000;
    o.tolerance = 0.15;
    o.min_stretch = 0.2;
    o.max_size = 15.0;
    o.max_valence = 12;
    o.fast_above = 2.0;
    o.threads = 2;
    bad |= digest("cover-paper-fast-12000", cover, &o);

    /* a boundary: its vertices take the marked scan in both builds, the
     * interior ones do not (in the default order: no valid edge under the
     * schedule's first cap, so the passes must raise it before they start) */
    o = (femlod_simplify_options)FEMLOD_SIMPLIFY_OPTIONS_INIT;
    o.ratio = 0.2;
    o.fast_above = 2.0;
    o.threads = 2;
    bad |= digest("sphere-with-hole-fast-0.2", hole, &o);

    femlod_mesh_free(fan);
    femlod_mesh_free(rev);
    femlod_mesh_free(cover);
    femlod_mesh_free(hole);
    return bad;
}
