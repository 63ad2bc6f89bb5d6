/*
 * lod.c - adaptive LOD on the vertex hierarchy (paper section 5.3).
 *
 * Global LOD with density preservation (5.3.2, with method-notes.md's
 * rules): S_REF is fixed when the call starts (front nodes: their size;
 * nodes below the front: their front ancestor's; nodes above: the mean of
 * their children's, bottom-up), r = size / S_REF, and the count moves by
 * collapsing the pair whose parent has the smallest r or splitting the
 * front node with the largest r. A node's size is its order size, not the
 * paper's e_size (docs/design.md "Density in the simplification's order").
 *
 * Curvature LOD (5.3.1a): kappa on the leaves, the maximum of the children
 * on internal nodes (a collapse keeps the larger kappa), and a refine whose
 * size function maps a node's kappa to T_S.
 *
 * Region LOD (5.3.1b): a distance to the region on every node, the minimum
 * over its subtree (the nearest-child inheritance rule), and a refine to
 * size + (grading - 1) * distance.
 */
#include "heap.h"
#include "hierarchy.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* The order size of every node: 1 / sqrt(n), n the triangles of the
 * simplification's mesh right after the collapse that made the node (the
 * input's count for a leaf). It is the mean element size, up to the part's
 * area, of the plain simplification at the moment it made the node, so r
 * compares a region with the plain simplification's own fronts: a region
 * the tolerance kept fine is collapsed late by the simplification, and
 * its nodes count as coarse here however short their edges (the paper's
 * e_size counts them as fine, and the rescale merged them at the rate of
 * flat ones: docs/performance.md). Collapses on a boundary remove one
 * face, inside two; the count only falls, and never below 1. */
static double *order_sizes(const femlod_hierarchy *h) {
    double *s = fl_alloc(h->nn, sizeof(double));
    if (!s) return NULL;
    size_t n = h->nf_in;
    for (size_t x = 0; x < h->nv; x++) s[x] = 1.0 / sqrt(n > 0 ? (double)n : 1.0);
    for (size_t c = 0; c < h->nc; c++) {
        size_t removed = h->removed_start[c + 1] - h->removed_start[c];
        size_t created = h->created_start[c + 1] - h->created_start[c];
        n = n + created > removed ? n + created - removed : 1;
        s[h->nv + c] = 1.0 / sqrt((double)n);
    }
    return s;
}

/* r of every node for the current front. */
static double *density_ratios(const femlod_hierarchy *h) {
    double *sref = fl_alloc(h->nn, sizeof(double)), *size = order_sizes(h);
    if (!sref || !size) {
        free(sref);
        free(size);
        return NULL;
    }
    for (size_t x = 0; x < h->nn; x++)
        if (h->state[x] == FRONT) sref[x] = size[x];
    /* parents have larger ids than children: downwards for the nodes below
     * the front, upwards for the ones above it */
    for (size_t x = h->nn; x-- > 0;)
        if (h->state[x] == BELOW) sref[x] = sref[h->parent[x]];
    for (size_t x = h->nv; x < h->nn; x++)
        if (h->state[x] == ABOVE) {
            size_t c = x - h->nv;
            sref[x] = 0.5 * (sref[h->child[2 * c]] + sref[h->child[2 * c + 1]]);
        }
    for (size_t x = 0; x < h->nn; x++)
        sref[x] = sref[x] > 0 ? size[x] / sref[x] : 1.0; /* now r */
    free(size);
    return sref;
}

/* Tie-break order of the nodes, in [0, 1). Ties are the rule, not the
 * exception: every node of the starting front has r = 1, and a rescale by
 * 1.5 must split half of them. Node ids follow the collapse order, which
 * sweeps the part region by region, so taking ties by id would refine one
 * region before another. Instead the nodes are ordered by the bit-reversed
 * Morton code of their position (a van der Corput sequence over space):
 * every prefix of that order is spread evenly over the part, so whatever
 * fraction of the ties is taken, each region gets its share. Exact repeats
 * (same cell) fall back to a scramble of the id; results repeat exactly. */
static double *tie_order(const femlod_hierarchy *h) {
    double *u = fl_alloc(h->nn, sizeof(double)), lo[3], hi[3];
    if (!u) return NULL;
    for (int k = 0; k < 3; k++) lo[k] = hi[k] = h->nn ? h->pos[k] : 0.0;
    for (size_t x = 0; x < h->nn; x++)
        for (int k = 0; k < 3; k++) {
            lo[k] = fmin(lo[k], h->pos[3 * x + (size_t)k]);
            hi[k] = fmax(hi[k], h->pos[3 * x + (size_t)k]);
        }
    for (size_t x = 0; x < h->nn; x++) {
        uint32_t q[3], code = 0, rev = 0;
        for (int k = 0; k < 3; k++) {
            double t = hi[k] > lo[k] ? (h->pos[3 * x + (size_t)k] - lo[k]) / (hi[k] - lo[k]) : 0;
            q[k] = (uint32_t)fmin(1023.0, fmax(0.0, t * 1024.0));
        }
        for (int b = 0; b < 10; b++)
            for (int k = 0; k < 3; k++) code |= ((q[k] >> b) & 1u) << (3 * b + k);
        for (int b = 0; b < 30; b++) rev |= ((code >> b) & 1u) << (29 - b);
        uint32_t s = (uint32_t)x * 0x9E3779B1u;
        s ^= s >> 15;
        s *= 0x85EBCA77u;
        s ^= s >> 13;
        u[x] = ((double)rev + (double)s / 4294967296.0) / 1073741824.0;
    }
    return u;
}

/* Heap key: r, ties taken in tie order; the perturbation (below 1e-9
 * relative) does not reorder values that differ by more. */
static double key_of(double r, double u) { return r * (1.0 + 1e-9 * (1.0 - u)); }

/* A collapse whose vstars are all at or below the front needs no other
 * collapse first. */
static int free_collapse(const femlod_hierarchy *h, uint32_t k) {
    size_t c = k - h->nv;
    for (uint32_t v = h->vstar_start[c]; v < h->vstar_start[c + 1]; v++)
        if (h->state[h->vstars[v]] == ABOVE) return 0;
    return 1;
}

/* A split that no applied node depends on needs no other split first. */
static int free_split(const femlod_hierarchy *h, uint32_t x) {
    for (uint32_t d = h->dep_start[x]; d < h->dep_start[x + 1]; d++)
        if (h->state[h->deps[d]] != ABOVE) return 0;
    return 1;
}

/* Candidates of each direction. */
static int can_collapse(const femlod_hierarchy *h, uint32_t k) {
    if (k == NONE || h->state[k] != ABOVE) return 0;
    size_t c = k - h->nv;
    return h->state[h->child[2 * c]] == FRONT && h->state[h->child[2 * c + 1]] == FRONT;
}

static int can_split(const femlod_hierarchy *h, uint32_t x) {
    return x != NONE && x >= h->nv && h->state[x] == FRONT;
}

/* One direction of the rescale. Candidates come from the heap, best first;
 * one that needs other operations first waits until no free one is left, so
 * that a cascade of dependencies cannot carry the count far past the target
 * (it would change regions that the density order did not choose). */
static size_t run(femlod_hierarchy *h, fl_heap *heap, const double *r, const double *u,
                  uint32_t *waiting, size_t target, int down, fl_progress *prog,
                  int *cancelled, int *limit) {
    size_t done = 0, nwait = 0, n0 = h->active_n;
    int forced = 0;
    double sign = down ? -1.0 : 1.0; /* down: smallest r first */
    for (size_t p = 0; p < h->front_n; p++) {
        uint32_t x = down ? h->parent[h->front[p]] : h->front[p];
        if (down ? can_collapse(h, x) : can_split(h, x)) fl_heap_set(heap, x, sign * key_of(r[x], u[x]));
    }
    while (down ? h->active_n > target : h->active_n < target) {
        if (fl_heap_size(heap) == 0) {
            if (forced || nwait == 0) {
                /* nothing left in this direction: every root (down) or every
                 * leaf (up) on the front, or only operations that the
                 * dependencies made move past the target */
                int end = 1;
                for (size_t p = 0; p < h->front_n && end; p++) {
                    uint32_t x = h->front[p];
                    end = down ? h->parent[x] == NONE : x < h->nv;
                }
                *limit = end ? (down ? FEMLOD_LIMIT_COARSEST : FEMLOD_LIMIT_FINEST) : FEMLOD_LIMIT_DEPENDENCIES;
                break;
            }
            forced = 1; /* only dependent operations are left: allow them */
            for (size_t w = 0; w < nwait; w++) {
                uint32_t q = waiting[w];
                if (down ? can_collapse(h, q) : can_split(h, q))
                    fl_heap_set(heap, q, sign * key_of(r[q], u[q]));
            }
            nwait = 0;
            continue;
        }
        uint32_t x = fl_heap_pop(heap, NULL);
        if (!(down ? can_collapse(h, x) : can_split(h, x))) continue;
        if (!forced && !(down ? free_collapse(h, x) : free_split(h, x))) {
            waiting[nwait++] = x;
            continue;
        }
        done += down ? fl_hierarchy_force_collapse(h, x) : fl_hierarchy_force_split(h, x);
        /* collapses only lower the count, splits only raise it */
        if (fl_progress_at(prog, down ? n0 - h->active_n : h->active_n - n0)) {
            *cancelled = 1;
            h->work_n = 0;
            break;
        }
        /* new candidates: the parent of a collapse, the children of a split */
        while (h->work_n > 0) {
            uint32_t q = h->work[--h->work_n];
            if (down ? can_collapse(h, q) : can_split(h, q))
                fl_heap_set(heap, q, sign * key_of(r[q], u[q]));
        }
        /* the operation may have freed waiting ones */
        size_t keep = 0;
        for (size_t w = 0; w < nwait; w++) {
            uint32_t q = waiting[w];
            if (!(down ? can_collapse(h, q) : can_split(h, q))) continue;
            if (down ? free_collapse(h, q) : free_split(h, q))
                fl_heap_set(heap, q, sign * key_of(r[q], u[q]));
            else
                waiting[keep++] = q;
        }
        nwait = keep;
    }
    return done;
}

femlod_status femlod_hierarchy_rescale(femlod_hierarchy *h, size_t target,
                                       const femlod_progress_options *options, size_t *ops,
                                       femlod_error *err) {
    if (ops) *ops = 0;
    double *r = density_ratios(h), *u = tie_order(h);
    uint32_t *waiting = fl_alloc(h->nn, sizeof(uint32_t));
    fl_heap heap;
    int heap_ok = r && u && waiting && fl_heap_init(&heap, h->nn);
    if (!heap_ok) {
        free(r);
        free(u);
        free(waiting);
        return fl_error(err, FEMLOD_ENOMEM, "out of memory in rescale of %zu nodes", h->nn);
    }
    size_t done = 0;
    int cancelled = 0;
    fl_progress prog;
    fl_progress_init(&prog, options ? options->progress : NULL,
                     options ? options->progress_payload : NULL,
                     h->active_n > target ? h->active_n - target : target - h->active_n);
    h->collect = 1;
    h->work_n = 0;
    int limit = FEMLOD_LIMIT_NONE;
    if (h->active_n != target)
        done = run(h, &heap, r, u, waiting, target, h->active_n > target, &prog, &cancelled, &limit);
    h->last_limit = h->active_n == target ? FEMLOD_LIMIT_NONE : limit ? limit : FEMLOD_LIMIT_DEPENDENCIES;
    h->collect = 0;
    h->work_n = 0;
    fl_heap_free(&heap);
    free(waiting);
    free(u);
    free(r);
    if (ops) *ops = done;
    if (cancelled) return fl_progress_cancelled(err, "rescale");
    fl_progress_end(&prog);
    return FEMLOD_OK;
}

/* {====== Curvature LOD */

femlod_status femlod_hierarchy_set_curvature(femlod_hierarchy *h, const double *kappa,
                                             femlod_error *err) {
    if (!kappa) return fl_error(err, FEMLOD_EINPUT, "kappa is NULL");
    for (size_t x = 0; x < h->nv; x++)
        if (!(kappa[x] >= 0.0) || !isfinite(kappa[x]))
            return fl_error(err, FEMLOD_EINPUT,
                            "kappa of input vertex %zu is %g (finite and >= 0 expected)", x,
                            kappa[x]);
    if (!h->kappa) {
        h->kappa = fl_alloc(h->nn, sizeof(double));
        if (!h->kappa)
            return fl_error(err, FEMLOD_ENOMEM, "out of memory for the curvature of %zu nodes",
                            h->nn);
    }
    if (h->nv) memcpy(h->kappa, kappa, h->nv * sizeof(double));
    /* children have smaller ids than their parent: one pass upwards */
    for (size_t x = h->nv; x < h->nn; x++) {
        size_t c = x - h->nv;
        h->kappa[x] = fmax(h->kappa[h->child[2 * c]], h->kappa[h->child[2 * c + 1]]);
    }
    return FEMLOD_OK;
}

typedef struct kappa_size {
    const femlod_hierarchy *h;
    double fine, coarse, top; /* top: the percentile of the leaves' kappa */
    double mid;               /* log map: the median of the leaves' positive kappa */
    femlod_kappa_map_kind kind;
    femlod_kappa_map_fn map;
    void *payload;
} kappa_size;

static double kappa_threshold(void *payload, const femlod_node_info *node) {
    const kappa_size *ks = (const kappa_size *)payload;
    double k = ks->h->kappa[node->id];
    if (ks->map) return ks->map(ks->payload, k);
    if (!(k > 0.0)) return ks->coarse;
    if (k >= ks->top) return ks->fine;
    double t = k / ks->top;
    /* log: linear in log(1 + kappa / mid), so that the decades of
     * curvature below the top share the range of sizes instead of the
     * crease-dominated top taking it all */
    if (ks->kind == FEMLOD_KAPPA_LOG && ks->mid > 0.0)
        t = log1p(k / ks->mid) / log1p(ks->top / ks->mid);
    return ks->coarse + (ks->fine - ks->coarse) * t;
}

static int cmp_double(const void *a, const void *b) {
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

femlod_status femlod_hierarchy_refine_curvature(femlod_hierarchy *h,
                                                const femlod_curvature_lod_options *options,
                                                size_t *ops, femlod_error *err) {
    if (ops) *ops = 0;
    femlod_curvature_lod_options o = FEMLOD_CURVATURE_LOD_OPTIONS_INIT;
    if (options) o = *options;
    if (!h->kappa)
        return fl_error(err, FEMLOD_EINPUT, "no curvature: call femlod_hierarchy_set_curvature first");
    if (o.map != FEMLOD_KAPPA_LINEAR && o.map != FEMLOD_KAPPA_LOG)
        return fl_error(err, FEMLOD_EINPUT, "unknown kappa map %d", (int)o.map);
    kappa_size ks = {h, 0.0, 0.0, 0.0, 0.0, o.map, o.fn, o.payload};
    femlod_progress_options po = {o.progress, o.progress_payload};
    if (!o.fn) {
        double fine = o.fine, coarse = o.coarse, percentile = o.percentile;
        if (isnan(fine)) fine = 0.0;
        if (isnan(percentile)) percentile = 0.95;
        if (isnan(coarse)) {
            coarse = 0.0;
            for (size_t p = 0; p < h->front_n; p++) coarse = fmax(coarse, h->e_size[h->front[p]]);
        }
        if (!(fine >= 0.0) || !isfinite(fine))
            return fl_error(err, FEMLOD_EINPUT, "fine is %g (finite and >= 0 expected)", fine);
        if (!(coarse >= 0.0) || !isfinite(coarse))
            return fl_error(err, FEMLOD_EINPUT, "coarse is %g (finite and >= 0 expected)", coarse);
        if (!(percentile > 0.0 && percentile <= 1.0))
            return fl_error(err, FEMLOD_EINPUT, "percentile is %g (in (0, 1] expected)",
                            percentile);
        if (h->nv) {
            double *sorted = fl_alloc(h->nv, sizeof(double));
            if (!sorted)
                return fl_error(err, FEMLOD_ENOMEM, "out of memory for the kappa of %zu vertices",
                                h->nv);
            memcpy(sorted, h->kappa, h->nv * sizeof(double));
            qsort(sorted, h->nv, sizeof(double), cmp_double);
            /* nearest rank */
            size_t rank = (size_t)ceil(percentile * (double)h->nv);
            ks.top = sorted[rank > 0 ? rank - 1 : 0];
            size_t zero = 0;
            while (zero < h->nv && !(sorted[zero] > 0.0)) zero++;
            if (zero < h->nv) ks.mid = sorted[zero + (h->nv - zero - 1) / 2];
            free(sorted);
        }
        ks.fine = fine;
        ks.coarse = coarse;
    }
    return fl_hierarchy_refine_progress(h, 0.0, kappa_threshold, &ks, &po, "refine_curvature", ops,
                                        err);
}

femlod_status femlod_hierarchy_input_mesh(const femlod_hierarchy *h, femlod_mesh **out,
                                          femlod_error *err) {
    *out = NULL;
    return femlod_mesh_create(out, h->pos, h->nv, h->face_v, h->nf_in, err);
}

/* }====== */

/* {====== Region LOD (paper 5.3.1b)
 *
 * The region marks nodes: by position (sphere, box, a per-node mark) or by
 * input vertex (a per-vertex mark). d(x) is a node's distance to the region:
 * 0 for a marked node; a leaf's is the Euclidean distance to the sphere or
 * box, or for marks the shortest path along input edges to a marked vertex
 * (the surface, not the air: the far side of a thin wall is not "near");
 * an internal node's is the smaller of its own and its children's. The
 * threshold is T(x) = size + (grading - 1) d(x) (size inside, and no
 * threshold where grading is infinite).
 *
 * The minimum over the children is the paper's inheritance rule made exact
 * for regions: when a node whose subtree reaches the region splits, the
 * child that holds the marked leaf (the one nearest the marked position)
 * keeps the small threshold and the other gets the one of its own
 * distance, so refinement follows the region down the hierarchy instead of
 * spreading over everything its coarse ancestors covered.
 *
 * Grading: two front neighbours at distance L differ in d by at most L
 * (d is 1-Lipschitz along the surface), so their thresholds differ by at
 * most (grading - 1) L; where the front has been refined to its thresholds
 * (L <= T) their ratio is at most `grading`. */

static double dist_box(const double p[3], const double lo[3], const double hi[3]) {
    double s = 0.0;
    for (int k = 0; k < 3; k++) {
        double e = p[k] < lo[k] ? lo[k] - p[k] : p[k] > hi[k] ? p[k] - hi[k] : 0.0;
        s += e * e;
    }
    return sqrt(s);
}

static double dist_sphere(const double p[3], const double c[3], double r) {
    double s = 0.0;
    for (int k = 0; k < 3; k++) s += (p[k] - c[k]) * (p[k] - c[k]);
    double d = sqrt(s) - r;
    return d > 0.0 ? d : 0.0;
}

/* Shortest paths along the input edges from the leaves with d == 0 (the
 * others start at +inf); Dijkstra with the indexed heap (max-heap: keys
 * negated). Ties pop by index, so the result depends only on the mesh. */
static femlod_status leaf_paths(const femlod_hierarchy *h, double *d, femlod_error *err) {
    fl_adjacency adj;
    femlod_status st = fl_adjacency_build(&adj, h->face_v, h->nf_in, h->nv, err);
    if (st != FEMLOD_OK) return st;
    fl_heap heap;
    if (!fl_heap_init(&heap, h->nv)) {
        fl_adjacency_free(&adj);
        return fl_error(err, FEMLOD_ENOMEM, "out of memory for the distances of %zu vertices",
                        h->nv);
    }
    for (size_t v = 0; v < h->nv; v++)
        if (d[v] == 0.0) fl_heap_set(&heap, (uint32_t)v, -0.0);
    while (fl_heap_size(&heap) > 0) {
        double key;
        uint32_t v = fl_heap_pop(&heap, &key);
        double dv = -key;
        if (dv > d[v]) continue;
        const double *pv = h->pos + 3 * (size_t)v;
        for (uint32_t n = adj.nbr_start[v]; n < adj.nbr_start[v + 1]; n++) {
            uint32_t w = adj.vert_nbrs[n];
            const double *pw = h->pos + 3 * (size_t)w;
            double e = sqrt((pv[0] - pw[0]) * (pv[0] - pw[0]) + (pv[1] - pw[1]) * (pv[1] - pw[1]) +
                            (pv[2] - pw[2]) * (pv[2] - pw[2]));
            if (dv + e < d[w]) {
                d[w] = dv + e;
                fl_heap_set(&heap, w, -d[w]);
            }
        }
    }
    fl_heap_free(&heap);
    fl_adjacency_free(&adj);
    return FEMLOD_OK;
}

typedef struct region_size {
    const double *d;
    double size, slope; /* slope = grading - 1; INFINITY: none */
} region_size;

static double region_threshold(void *payload, const femlod_node_info *node) {
    const region_size *rs = (const region_size *)payload;
    double d = rs->d[node->id];
    if (d == 0.0) return rs->size;
    if (isinf(rs->slope) || isinf(d)) return INFINITY;
    return rs->size + rs->slope * d;
}

femlod_status femlod_hierarchy_region_distance(const femlod_hierarchy *h,
                                               const femlod_region *region, double *d,
                                               femlod_error *err) {
    if (!region) return fl_error(err, FEMLOD_EINPUT, "region is NULL");
    const femlod_region *r = region;
    switch (r->kind) {
    case FEMLOD_REGION_SPHERE:
        for (int k = 0; k < 3; k++)
            if (!isfinite(r->center[k]))
                return fl_error(err, FEMLOD_EINPUT, "sphere center[%d] is %g (finite expected)",
                                k, r->center[k]);
        if (!(r->radius >= 0.0) || !isfinite(r->radius))
            return fl_error(err, FEMLOD_EINPUT, "sphere radius is %g (finite and >= 0 expected)",
                            r->radius);
        for (size_t x = 0; x < h->nn; x++) d[x] = dist_sphere(h->pos + 3 * x, r->center, r->radius);
        break;
    case FEMLOD_REGION_BOX:
        for (int k = 0; k < 3; k++)
            if (!isfinite(r->min[k]) || !isfinite(r->max[k]) || r->min[k] > r->max[k])
                return fl_error(err, FEMLOD_EINPUT,
                                "box min[%d] = %g, max[%d] = %g (finite, min <= max expected)", k,
                                r->min[k], k, r->max[k]);
        for (size_t x = 0; x < h->nn; x++) d[x] = dist_box(h->pos + 3 * x, r->min, r->max);
        break;
    case FEMLOD_REGION_NODES:
    case FEMLOD_REGION_VERTICES: {
        if (!r->marks) return fl_error(err, FEMLOD_EINPUT, "region marks are NULL");
        size_t n = r->kind == FEMLOD_REGION_NODES ? h->nn : h->nv;
        for (size_t x = 0; x < h->nn; x++) d[x] = x < n && r->marks[x] ? 0.0 : INFINITY;
        femlod_status st = leaf_paths(h, d, err);
        if (st != FEMLOD_OK) return st;
        break;
    }
    default:
        return fl_error(err, FEMLOD_EINPUT, "unknown region kind %d", (int)r->kind);
    }
    /* children have smaller ids than their parent: one pass upwards */
    for (size_t x = h->nv; x < h->nn; x++) {
        size_t c = x - h->nv;
        d[x] = fmin(d[x], fmin(d[h->child[2 * c]], d[h->child[2 * c + 1]]));
    }
    return FEMLOD_OK;
}

femlod_status femlod_hierarchy_refine_region(femlod_hierarchy *h, const femlod_region *region,
                                             double size, double grading,
                                             const femlod_progress_options *options, size_t *ops,
                                             size_t *inside, femlod_error *err) {
    if (ops) *ops = 0;
    if (inside) *inside = 0;
    if (!(size >= 0.0) || !isfinite(size))
        return fl_error(err, FEMLOD_EINPUT, "size is %g (finite and >= 0 expected)", size);
    if (!(grading >= 1.0))
        return fl_error(err, FEMLOD_EINPUT, "grading is %g (>= 1 or infinite expected)", grading);
    double *d = fl_alloc(h->nn ? h->nn : 1, sizeof(double));
    if (!d)
        return fl_error(err, FEMLOD_ENOMEM, "out of memory for the distances of %zu nodes", h->nn);
    femlod_status st = femlod_hierarchy_region_distance(h, region, d, err);
    if (st == FEMLOD_OK && inside)
        for (size_t x = 0; x < h->nn; x++) *inside += d[x] == 0.0;
    if (st == FEMLOD_OK) {
        region_size rs = {d, size, grading - 1.0};
        st = fl_hierarchy_refine_progress(h, 0.0, region_threshold, &rs, options, "refine_region",
                                          ops, err);
    }
    free(d);
    return st;
}

/* }====== */

/* {====== what stopped the last rescale */

femlod_lod_limit femlod_hierarchy_last_limit(const femlod_hierarchy *h) {
    return (femlod_lod_limit)h->last_limit;
}

int femlod_hierarchy_coarsest_binding(const femlod_hierarchy *h) { return h->binding; }

const char *femlod_hierarchy_limit_reason(const femlod_hierarchy *h) {
    switch ((femlod_lod_limit)h->last_limit) {
    case FEMLOD_LIMIT_NONE: return "";
    case FEMLOD_LIMIT_COARSEST:
        return h->binding >= 0 && h->binding < FEMLOD_REJECT_COUNT
                   ? femlod_reject_name((femlod_reject)h->binding)
                   : "the hierarchy goes no coarser (hierarchy_floor)";
    case FEMLOD_LIMIT_FINEST: return "the input's count";
    case FEMLOD_LIMIT_DEPENDENCIES: return "dependencies";
    }
    return "";
}

/* }====== */
