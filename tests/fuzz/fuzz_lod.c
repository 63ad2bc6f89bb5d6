/* fuzz_lod.c - libFuzzer target for simplification and level of detail:
 * the input bytes choose a small generated mesh (closed, open, non-manifold
 * or degenerate), perturb its vertices, choose the thresholds and the
 * order (exact or fast passes), simplify, build the vertex hierarchy and
 * run a sequence of LOD operations (refine,
 * coarsen, split, collapse, rescale, region and curvature refinement).
 * Besides crashes, sanitizer reports, leaks and hangs, a finding is a
 * broken promise: after every operation the hierarchy must validate, and
 * the front mesh must keep the simplification's stretch and size bounds
 * (or the input's, where an input triangle was already worse). */
#include "femlod.h"
#include "shapes.h"

#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

typedef struct bytes {
    const uint8_t *p;
    size_t n, at;
} bytes;

static unsigned next(bytes *b) { return b->at < b->n ? b->p[b->at++] : 0u; }

static femlod_mesh *shape(unsigned kind, unsigned a, unsigned c) {
    switch (kind % 6) {
    /* small: a fuzzing build runs unoptimised and instrumented, and every
     * input should take milliseconds */
    case 0: return shape_icosphere(1 + a % 2);
    case 1: return shape_cylinder(6 + a % 11, 2 + c % 5, 0.5 + (double)(c % 7));
    case 2: return shape_plane(3 + a % 7);
    case 3: return shape_tetrahedron();
    case 4: return shape_nonmanifold_fan();
    default: return shape_bowtie();
    }
}

static void check(femlod_hierarchy *h, const femlod_quality *qin, double min_stretch,
                  double max_size) {
    femlod_error err;
    if (femlod_hierarchy_validate(h, &err) != FEMLOD_OK) abort();
    femlod_mesh *m = NULL;
    if (femlod_hierarchy_extract(h, &m, NULL, &err) != FEMLOD_OK) abort();
    femlod_quality q;
    if (femlod_mesh_quality(m, &q, &err) == FEMLOD_OK && q.triangles > 0) {
        if (min_stretch > 0 && q.stretch_min < fmin(min_stretch, qin->stretch_min) - 1e-9) abort();
        if (max_size > 0 && q.size_max > fmax(max_size, qin->size_max) * (1 + 1e-9)) abort();
    }
    femlod_mesh_free(m);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    bytes b = {data, size, 0};
    femlod_mesh *in0 = shape(next(&b), next(&b), next(&b));
    size_t nv = femlod_mesh_vertex_count(in0), nt = femlod_mesh_triangle_count(in0);
    double *pos = malloc(3 * nv * sizeof(double));
    uint32_t *tri = malloc(3 * nt * sizeof(uint32_t));
    memcpy(pos, femlod_mesh_positions(in0), 3 * nv * sizeof(double));
    memcpy(tri, femlod_mesh_triangles(in0), 3 * nt * sizeof(uint32_t));
    femlod_mesh_free(in0);
    /* perturbations: (vertex, axis, amount) triples; a zero amount snaps
     * the coordinate to 0, which makes duplicates and degenerate triangles */
    unsigned np = next(&b) % 32;
    for (unsigned k = 0; k < np; k++) {
        size_t v = next(&b) % nv;
        unsigned axis = next(&b) % 3, amount = next(&b);
        if (amount == 0)
            pos[3 * v + axis] = 0.0;
        else
            pos[3 * v + axis] += ((double)amount - 128.0) / 512.0;
    }
    femlod_mesh *in = NULL;
    femlod_error err;
    femlod_status st = femlod_mesh_create(&in, pos, nv, tri, nt, &err);
    free(pos);
    free(tri);
    if (st != FEMLOD_OK) return 0;
    femlod_simplify_options o = FEMLOD_SIMPLIFY_OPTIONS_INIT;
    unsigned t = next(&b);
    o.target = t % 2 ? (size_t)(t / 2) : 0; /* 0: until no valid edge */
    unsigned s = next(&b);
    o.min_stretch = s % 4 == 0 ? FEMLOD_SIMPLIFY_OFF : (double)(s % 100) / 200.0;
    unsigned z = next(&b);
    o.max_size = z % 4 == 0 ? FEMLOD_SIMPLIFY_OFF : 0.2 + (double)z / 64.0;
    unsigned va = next(&b);
    o.max_valence = va % 4 == 0 ? -1 : (int)(4 + va % 12);
    unsigned kb = next(&b);
    o.keep_boundary = (int)(kb & 1u);
    o.fast_above = kb & 2u ? 1.0 + (double)((kb >> 2) % 4) : FEMLOD_SIMPLIFY_OFF; /* fast passes or the exact order (docs/simplify.md) */
    femlod_mesh *out = NULL;
    femlod_collapse_log *log = NULL;
    femlod_simplify_result res;
    femlod_hierarchy *h = NULL;
    if (femlod_simplify(&out, &log, in, &o, &res, &err) != FEMLOD_OK) goto done;
    if (femlod_hierarchy_create(&h, in, log, NULL, &err) != FEMLOD_OK) abort(); /* its own log */
    femlod_quality qin;
    if (femlod_mesh_quality(in, &qin, &err) != FEMLOD_OK) goto done;
    double diag = sqrt(pow(qin.bbox_max[0] - qin.bbox_min[0], 2) +
                       pow(qin.bbox_max[1] - qin.bbox_min[1], 2) +
                       pow(qin.bbox_max[2] - qin.bbox_min[2], 2));
    int has_kappa = 0;
    check(h, &qin, res.min_stretch, res.max_size);
    for (int op = 0; op < 24 && b.at < b.n; op++) {
        unsigned code = next(&b), arg = next(&b);
        size_t ops = 0, count = 0, inside = 0;
        const uint32_t *front = femlod_hierarchy_front(h, &count);
        femlod_node_info n;
        switch (code % 8) {
        case 0: (void)femlod_hierarchy_refine(h, diag * arg / 1024.0, NULL, NULL, &ops, &err); break;
        case 1: (void)femlod_hierarchy_coarsen(h, diag * arg / 256.0, NULL, NULL, &ops, &err); break;
        case 2:
            if (count && femlod_hierarchy_node(h, front[arg % count], &n) && n.child[0] != UINT32_MAX)
                (void)femlod_hierarchy_split(h, n.id, &ops, &err);
            break;
        case 3:
            if (count && femlod_hierarchy_node(h, front[arg % count], &n) && n.parent != UINT32_MAX)
                (void)femlod_hierarchy_collapse(h, n.parent, &ops, &err);
            break;
        case 4:
            (void)femlod_hierarchy_rescale(h, 1 + (size_t)arg * 2, NULL, &ops, &err);
            break;
        case 5: {
            femlod_region r;
            memset(&r, 0, sizeof r);
            r.kind = arg % 2 ? FEMLOD_REGION_SPHERE : FEMLOD_REGION_BOX;
            const double *p = femlod_mesh_positions(in) + 3 * (arg % nv);
            for (int k = 0; k < 3; k++) {
                r.center[k] = p[k];
                r.min[k] = p[k] - diag / 8;
                r.max[k] = p[k] + diag / 8;
            }
            r.radius = diag * (double)(arg % 16) / 32.0;
            (void)femlod_hierarchy_refine_region(h, &r, diag * (double)(arg / 16) / 64.0,
                                                 arg % 3 ? 1.0 + (double)(arg % 5) / 2.0 : INFINITY,
                                                 NULL, &ops, &inside, &err);
            break;
        }
        case 6: {
            femlod_region r;
            memset(&r, 0, sizeof r);
            /* one mark per vertex of the hierarchy's input: the improve
             * stage's mesh when it ran, so not nv */
            size_t hv = femlod_hierarchy_input_vertices(h);
            unsigned char *marks = calloc(hv ? hv : 1, 1);
            for (size_t v = arg % 7; v < hv; v += 7 + arg % 11) marks[v] = 1;
            r.kind = FEMLOD_REGION_VERTICES;
            r.marks = marks;
            (void)femlod_hierarchy_refine_region(h, &r, 0.0, 1.5, NULL, &ops, &inside, &err);
            free(marks);
            break;
        }
        default:
            if (!has_kappa) {
                size_t hv = femlod_hierarchy_input_vertices(h);
                double *kappa = calloc(hv ? hv : 1, sizeof(double));
                femlod_mesh *im = NULL;
                if (femlod_hierarchy_input_mesh(h, &im, &err) == FEMLOD_OK &&
                    femlod_mesh_curvature(im, NULL, NULL, NULL, kappa, NULL, NULL, &err) == FEMLOD_OK &&
                    femlod_hierarchy_set_curvature(h, kappa, &err) == FEMLOD_OK)
                    has_kappa = 1;
                femlod_mesh_free(im);
                free(kappa);
            }
            if (has_kappa) {
                femlod_curvature_lod_options co = FEMLOD_CURVATURE_LOD_OPTIONS_INIT;
                co.map = arg % 2 ? FEMLOD_KAPPA_LOG : FEMLOD_KAPPA_LINEAR;
                co.percentile = 0.5 + (double)(arg % 100) / 200.0;
                (void)femlod_hierarchy_refine_curvature(h, &co, &ops, &err);
            }
            break;
        }
        check(h, &qin, res.min_stretch, res.max_size);
    }
done:
    femlod_hierarchy_free(h);
    femlod_collapse_log_free(log);
    femlod_mesh_free(out);
    femlod_mesh_free(in);
    return 0;
}
