/*
 * quality.c - the element measures of paper section 4.1 (stretch, size,
 * valence; exact definitions in reference/method-notes.md, "Element
 * measures") as pure array functions, and the mesh quality report built on
 * them: Table 1's columns plus angles, defects, histogram and topology.
 */
#include "core.h"
#include "vec3.h"

#include <assert.h>
#include <inttypes.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* {====== one triangle */

/* What every per-triangle measure needs, computed once. */
typedef struct tri_shape {
    double len[3];  /* side opposite corner i */
    double cross;   /* |(q - p) x (r - p)| = twice the area */
    double longest; /* max of len */
} tri_shape;



static void shape_of(tri_shape *s, const double *p0, const double *p1, const double *p2) {
    const double *p[3] = {p0, p1, p2};
    int top = 0;
    for (int i = 0; i < 3; i++) {
        double d[3];
        sub3(d, p[(i + 1) % 3], p[(i + 2) % 3]);
        s->len[i] = sqrt(dot3(d, d));
        if (s->len[i] > s->len[top]) top = i;
    }
    s->longest = s->len[top];
    /* The cross product is taken at the corner facing the longest side, whose
     * two sides are the shortest: for a sliver this keeps the cancellation
     * that Heron's formula suffers far away. */
    double u[3], v[3];
    sub3(u, p[(top + 1) % 3], p[top]);
    sub3(v, p[(top + 2) % 3], p[top]);
    double n[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
    s->cross = sqrt(dot3(n, n));
}

/* sqrt(12) * r / L with r = Area / s = cross / perimeter. */
static double shape_stretch(const tri_shape *s) {
    double perimeter = s->len[0] + s->len[1] + s->len[2];
    if (!(s->longest > 0.0) || !(perimeter > 0.0)) return 0.0;
    double st = sqrt(12.0) * s->cross / (perimeter * s->longest);
    /* Rounding can push an equilateral triangle a few ulps past 1; an
     * overflowing coordinate range gives NaN. Neither is a shape. */
    if (!(st > 0.0)) return 0.0;
    return st > 1.0 ? 1.0 : st;
}

/* Smallest and largest interior angle in degrees. atan2(|cross|, dot) stays
 * accurate near 0 and 180 degrees where acos of a cosine does not. A
 * triangle with a zero-length side has no defined angles at its collapsed
 * corner; it is reported as flat (0 and 180), which is what it is. */
static void shape_angles(const tri_shape *s, const double *p0, const double *p1, const double *p2,
                         double *amin, double *amax) {
    if (!(s->len[0] > 0.0 && s->len[1] > 0.0 && s->len[2] > 0.0)) {
        *amin = 0.0;
        *amax = 180.0;
        return;
    }
    const double *p[3] = {p0, p1, p2};
    const double deg = 180.0 / 3.14159265358979323846;
    double lo = 180.0, hi = 0.0;
    for (int i = 0; i < 3; i++) {
        double u[3], v[3];
        sub3(u, p[(i + 1) % 3], p[i]);
        sub3(v, p[(i + 2) % 3], p[i]);
        double a = atan2(s->cross, dot3(u, v)) * deg;
        if (a > 180.0) a = 180.0; /* pi * (180 / pi) may round up */
        if (a < lo) lo = a;
        if (a > hi) hi = a;
    }
    *amin = lo;
    *amax = hi;
}

double femlod_triangle_stretch(const double a[3], const double b[3], const double c[3]) {
    tri_shape s;
    shape_of(&s, a, b, c);
    return shape_stretch(&s);
}

double femlod_triangle_size(const double a[3], const double b[3], const double c[3]) {
    tri_shape s;
    shape_of(&s, a, b, c);
    return s.longest;
}

unsigned fl_quality_histogram_bin(double stretch) {
    if (!(stretch > 0.0)) return 0;
    if (stretch >= 1.0) return FEMLOD_HISTOGRAM_BINS - 1;
    /* 10 * s rounds, so its floor can be one bin off next to an edge (the
     * double just below 0.9, times 10, is 9.0): settle against the edges as
     * the doubles k / 10.0, so that a stretch that prints as 0.3 is in bin 3
     * and anything below it in bin 2. */
    int k = (int)(stretch * FEMLOD_HISTOGRAM_BINS);
    if (k > FEMLOD_HISTOGRAM_BINS - 1) k = FEMLOD_HISTOGRAM_BINS - 1;
    while (k > 0 && stretch < (double)k / FEMLOD_HISTOGRAM_BINS) k--;
    while (k < FEMLOD_HISTOGRAM_BINS - 1 && stretch >= (double)(k + 1) / FEMLOD_HISTOGRAM_BINS) k++;
    return (unsigned)k;
}

/* }====== */

/* {====== arrays */

void femlod_stretch_array(double *out, const double *positions, const uint32_t *triangles,
                          size_t triangle_count) {
    for (size_t t = 0; t < triangle_count; t++) {
        const uint32_t *c = triangles + 3 * t;
        out[t] = femlod_triangle_stretch(positions + 3 * (size_t)c[0], positions + 3 * (size_t)c[1],
                                         positions + 3 * (size_t)c[2]);
    }
}

void femlod_size_array(double *out, const double *positions, const uint32_t *triangles,
                       size_t triangle_count) {
    for (size_t t = 0; t < triangle_count; t++) {
        const uint32_t *c = triangles + 3 * t;
        out[t] = femlod_triangle_size(positions + 3 * (size_t)c[0], positions + 3 * (size_t)c[1],
                                      positions + 3 * (size_t)c[2]);
    }
}

static int cmp_u64(const void *a, const void *b) {
    uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return (x > y) - (x < y);
}

/* Sorts n (bucket, key) pairs by bucket then key: a counting sort on the
 * bucket, then each bucket's keys sorted on their own. Buckets are vertices,
 * which hold a valence's worth of keys, so this is linear in practice, and
 * equal keys are equal values: the result does not depend on any order.
 * start has nb+1 zeroed entries and ends as the bucket offsets into sorted. */
static void sort_pairs(uint64_t *sorted, size_t *start, size_t nb, const uint32_t *bucket,
                       const uint64_t *key, size_t n) {
    for (size_t i = 0; i < n; i++) start[bucket[i] + 1]++;
    for (size_t b = 0; b < nb; b++) start[b + 1] += start[b];
    for (size_t i = 0; i < n; i++) sorted[start[bucket[i]]++] = key[i];
    /* start[b] now ends bucket b: shift back to beginnings. */
    for (size_t b = nb; b > 0; b--) start[b] = start[b - 1];
    start[0] = 0;
    for (size_t b = 0; b < nb; b++) {
        uint64_t *v = sorted + start[b];
        size_t m = start[b + 1] - start[b];
        if (m > 16) {
            qsort(v, m, sizeof *v, cmp_u64);
            continue;
        }
        for (size_t i = 1; i < m; i++) {
            uint64_t x = v[i];
            size_t j = i;
            for (; j > 0 && v[j - 1] > x; j--) v[j] = v[j - 1];
            v[j] = x;
        }
    }
}

static femlod_status check_indices(const uint32_t *tri, size_t nt, size_t nv, femlod_error *err) {
    for (size_t i = 0; i < 3 * nt; i++)
        if (tri[i] >= nv)
            return fl_error(err, FEMLOD_EINPUT,
                            "triangle %zu: vertex index %" PRIu32 " out of range (%zu vertices)",
                            i / 3, tri[i], nv);
    return FEMLOD_OK;
}

femlod_status fl_quality_edges(uint32_t **edges, size_t *ne, const uint32_t *tri, size_t nt,
                               size_t nv, femlod_error *err) {
    femlod_status st = check_indices(tri, nt, nv, err);
    if (st != FEMLOD_OK) return st;
    size_t n = 0;
    for (size_t t = 0; t < nt; t++)
        for (int i = 0; i < 3; i++) n += tri[3 * t + (size_t)i] != tri[3 * t + (size_t)(i + 1) % 3];
    uint32_t *bucket = fl_alloc(n, sizeof *bucket);
    uint64_t *key = fl_alloc(n, sizeof *key);
    uint64_t *sorted = fl_alloc(n, sizeof *sorted);
    size_t *start = fl_calloc(nv + 1, sizeof *start);
    uint32_t *out = NULL;
    if (!bucket || !key || !sorted || !start) goto nomem;
    n = 0;
    for (size_t t = 0; t < nt; t++)
        for (int i = 0; i < 3; i++) {
            uint32_t a = tri[3 * t + (size_t)i], b = tri[3 * t + (size_t)(i + 1) % 3];
            if (a == b) continue;
            bucket[n] = a < b ? a : b;
            key[n++] = a < b ? b : a;
        }
    sort_pairs(sorted, start, nv, bucket, key, n);
    size_t count = 0;
    for (size_t v = 0; v < nv; v++)
        for (size_t k = start[v]; k < start[v + 1]; k++)
            count += k == start[v] || sorted[k] != sorted[k - 1];
    out = fl_alloc(count, 2 * sizeof *out);
    if (!out) goto nomem;
    count = 0;
    for (size_t v = 0; v < nv; v++)
        for (size_t k = start[v]; k < start[v + 1]; k++)
            if (k == start[v] || sorted[k] != sorted[k - 1]) {
                out[2 * count] = (uint32_t)v;
                out[2 * count + 1] = (uint32_t)sorted[k];
                count++;
            }
    free(bucket);
    free(key);
    free(sorted);
    free(start);
    *edges = out;
    *ne = count;
    return FEMLOD_OK;
nomem:
    free(bucket);
    free(key);
    free(sorted);
    free(start);
    return fl_error(err, FEMLOD_ENOMEM, "out of memory listing the edges of %zu triangles", nt);
}

femlod_status femlod_valence_array(uint32_t *out, size_t vertex_count, const uint32_t *triangles,
                                   size_t triangle_count, femlod_error *err) {
    uint32_t *edges = NULL;
    size_t ne = 0;
    femlod_status st = fl_quality_edges(&edges, &ne, triangles, triangle_count, vertex_count, err);
    if (st != FEMLOD_OK) return st;
    if (vertex_count) memset(out, 0, vertex_count * sizeof *out);
    for (size_t e = 0; e < ne; e++) {
        out[edges[2 * e]]++;
        out[edges[2 * e + 1]]++;
    }
    free(edges);
    return FEMLOD_OK;
}

/* Triangles whose sorted index triple equals an earlier one's. The count is
 * the number of triples minus the number of distinct ones, so it needs no
 * notion of which copy came first. */
static femlod_status count_duplicates(size_t *out, const uint32_t *tri, size_t nt, size_t nv,
                                      femlod_error *err) {
    uint32_t *bucket = fl_alloc(nt, sizeof *bucket);
    uint64_t *key = fl_alloc(nt, sizeof *key);
    uint64_t *sorted = fl_alloc(nt, sizeof *sorted);
    size_t *start = fl_calloc(nv + 1, sizeof *start);
    if (!bucket || !key || !sorted || !start) {
        free(bucket);
        free(key);
        free(sorted);
        free(start);
        return fl_error(err, FEMLOD_ENOMEM, "out of memory looking for duplicates in %zu triangles",
                        nt);
    }
    for (size_t t = 0; t < nt; t++) {
        uint32_t a = tri[3 * t], b = tri[3 * t + 1], c = tri[3 * t + 2];
        uint32_t lo = a < b ? a : b, hi = a < b ? b : a;
        uint32_t first = c < lo ? c : lo, last = c > hi ? c : hi;
        uint32_t middle = c < lo ? lo : c > hi ? hi : c;
        bucket[t] = first;
        key[t] = (uint64_t)middle << 32 | last;
    }
    sort_pairs(sorted, start, nv, bucket, key, nt);
    size_t dup = 0;
    for (size_t v = 0; v < nv; v++)
        for (size_t k = start[v] + 1; k < start[v + 1]; k++) dup += sorted[k] == sorted[k - 1];
    free(bucket);
    free(key);
    free(sorted);
    free(start);
    *out = dup;
    return FEMLOD_OK;
}

/* }====== */

/* {====== the report */

femlod_status femlod_mesh_quality(const femlod_mesh *mesh, femlod_quality *out, femlod_error *err) {
    assert(mesh && out);
    femlod_quality q;
    memset(&q, 0, sizeof q);
    q.triangles = mesh->nt;
    q.vertices = mesh->nv;

    fl_adjacency adj;
    femlod_status st = fl_adjacency_build(&adj, mesh->tri, mesh->nt, mesh->nv, err);
    if (st != FEMLOD_OK) return st;
    st = fl_adjacency_topology(&adj, mesh->tri, &q.topology, err);
    if (st == FEMLOD_OK) st = count_duplicates(&q.duplicate, mesh->tri, mesh->nt, mesh->nv, err);
    if (st != FEMLOD_OK) {
        fl_adjacency_free(&adj);
        return st;
    }

    size_t used = 0;
    double valence_sum = 0.0;
    for (size_t v = 0; v < mesh->nv; v++) {
        if (adj.vert_start[v + 1] == adj.vert_start[v]) continue;
        uint32_t val = adj.nbr_start[v + 1] - adj.nbr_start[v];
        if (val > q.valence_max) q.valence_max = val;
        valence_sum += val;
        used++;
    }
    q.valence_avg = used ? valence_sum / (double)used : 0.0;
    fl_adjacency_free(&adj);

    double stretch_sum = 0.0, size_sum = 0.0;
    q.stretch_min = q.size_min = q.angle_min = INFINITY;
    for (size_t t = 0; t < mesh->nt; t++) {
        const uint32_t *c = mesh->tri + 3 * t;
        const double *a = mesh->pos + 3 * (size_t)c[0], *b = mesh->pos + 3 * (size_t)c[1],
                     *d = mesh->pos + 3 * (size_t)c[2];
        tri_shape s;
        shape_of(&s, a, b, d);
        double stretch = shape_stretch(&s), amin, amax;
        shape_angles(&s, a, b, d, &amin, &amax);
        stretch_sum += stretch;
        size_sum += s.longest;
        if (stretch < q.stretch_min) q.stretch_min = stretch;
        if (stretch > q.stretch_max) q.stretch_max = stretch;
        if (s.longest < q.size_min) q.size_min = s.longest;
        if (s.longest > q.size_max) q.size_max = s.longest;
        if (amin < q.angle_min) q.angle_min = amin;
        if (amax > q.angle_max) q.angle_max = amax;
        if (c[0] == c[1] || c[1] == c[2] || c[2] == c[0] || stretch < 1e-6) q.degenerate++;
        q.histogram[fl_quality_histogram_bin(stretch)]++;
    }
    if (mesh->nt) {
        q.stretch_avg = stretch_sum / (double)mesh->nt;
        q.size_avg = size_sum / (double)mesh->nt;
    } else {
        q.stretch_min = q.size_min = q.angle_min = 0.0;
    }
    q.area = femlod_mesh_area(mesh);
    femlod_mesh_bbox(mesh, q.bbox_min, q.bbox_max);
    *out = q;
    return FEMLOD_OK;
}

/* }====== */
