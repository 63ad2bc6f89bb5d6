/*
 * hausdorff.c - the sampled two-sided Hausdorff distance between two
 * triangle meshes: the deviation every later step reports against its input
 * (issue 2, paper section 4.1's quality report; docs/quality.md).
 *
 * Samples of one mesh (its vertices, edge points with every midpoint, and a
 * regular barycentric grid inside each triangle) are projected on the other
 * through an AABB tree over its triangles. The exact point-triangle distance
 * is Ericson's region method ("Real-Time Collision Detection", 2005,
 * section 5.1.5), made safe for degenerate triangles.
 */
#include "core.h"
#include "vec3.h"

#include <assert.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#define DEFAULT_MAX_SAMPLES 4000000u
#define DEFAULT_DIVISOR 500.0
#define LEAF_SIZE 4
/* Grid subdivisions of one triangle or edge are capped so that counts and
 * loops stay in range whatever the spacing; the max_samples loop then grows
 * the spacing until the total fits. */
#define MAX_DIVISIONS 1048576.0

/* {====== vector helpers */



/* |p - (o + t d)|^2 */
static double dist2_along(const double p[3], const double o[3], const double d[3], double t) {
    double e[3] = {p[0] - (o[0] + t * d[0]), p[1] - (o[1] + t * d[1]), p[2] - (o[2] + t * d[2])};
    return dot3(e, e);
}

static double length3(const double *a, const double *b) {
    double d[3];
    sub3(d, a, b);
    return sqrt(dot3(d, d));
}

/* }====== */

/* {====== point-triangle distance */

static double segment_dist2(const double p[3], const double a[3], const double b[3]) {
    double ab[3], ap[3];
    sub3(ab, b, a);
    sub3(ap, p, a);
    double t = dot3(ap, ab), l = dot3(ab, ab);
    if (t <= 0.0 || !(l > 0.0)) return dot3(ap, ap);
    if (t >= l) {
        double bp[3];
        sub3(bp, p, b);
        return dot3(bp, bp);
    }
    return dist2_along(p, a, ab, t / l);
}

/* Squared distance from p to triangle t (9 coordinates). Ericson's tests
 * classify p by the Voronoi region of the triangle's features. A zero-length
 * edge would divide 0 by 0 in an edge region, and a (nearly) flat triangle
 * has no trustworthy face region: there the sides, whose union is the
 * triangle's boundary and all of a flat triangle, give the answer. */
static double triangle_dist2(const double *t, const double p[3]) {
    const double *a = t, *b = t + 3, *c = t + 6;
    double ab[3], ac[3], ap[3], bp[3], cp[3];
    sub3(ab, b, a);
    sub3(ac, c, a);
    sub3(ap, p, a);
    double d1 = dot3(ab, ap), d2 = dot3(ac, ap);
    if (d1 <= 0.0 && d2 <= 0.0) return dot3(ap, ap);

    sub3(bp, p, b);
    double d3 = dot3(ab, bp), d4 = dot3(ac, bp);
    if (d3 >= 0.0 && d4 <= d3) return dot3(bp, bp);

    double vc = d1 * d4 - d3 * d2;
    if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) {
        double den = d1 - d3;
        return dist2_along(p, a, ab, den > 0.0 ? d1 / den : 0.0);
    }

    sub3(cp, p, c);
    double d5 = dot3(ab, cp), d6 = dot3(ac, cp);
    if (d6 >= 0.0 && d5 <= d6) return dot3(cp, cp);

    double vb = d5 * d2 - d1 * d6;
    if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) {
        double den = d2 - d6;
        return dist2_along(p, a, ac, den > 0.0 ? d2 / den : 0.0);
    }

    double va = d3 * d6 - d5 * d4;
    if (va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0) {
        double den = (d4 - d3) + (d5 - d6), bc[3];
        sub3(bc, c, b);
        return dist2_along(p, b, bc, den > 0.0 ? (d4 - d3) / den : 0.0);
    }

    /* va + vb + vc = |ab x ac|^2 = |ab|^2 |ac|^2 sin^2(A) in exact arithmetic;
     * its rounding error is relative to |ab|^2 |ac|^2. */
    double den = va + vb + vc, scale = dot3(ab, ab) * dot3(ac, ac), face = INFINITY;
    if (den > 0.0) {
        double v = vb / den, w = vc / den;
        double e[3] = {p[0] - (a[0] + ab[0] * v + ac[0] * w),
                       p[1] - (a[1] + ab[1] * v + ac[1] * w),
                       p[2] - (a[2] + ab[2] * v + ac[2] * w)};
        face = dot3(e, e);
        if (den > 1e-6 * scale) return face;
    }
    /* A sliver: the face point may carry the error of a small denominator,
     * the sides cannot. Both are points of the triangle, so the nearer one
     * is the better answer. */
    double sides = segment_dist2(p, a, b), s2 = segment_dist2(p, b, c), s3 = segment_dist2(p, c, a);
    if (s2 < sides) sides = s2;
    if (s3 < sides) sides = s3;
    return face < sides ? face : sides;
}

/* }====== */

/* {====== AABB tree over triangles */

/* A node holds the boxes of its two children, so one cache line (64 bytes)
 * decides which of them to visit. A child is an inner node (count 0, index
 * child) or a leaf of count triangles from slot child of the corner array.
 * Boxes are floats rounded outward: still bounds, at half the memory. */
typedef struct bvh_node {
    float lo[2][3], hi[2][3];
    uint32_t child[2];
    uint32_t count[2];
} bvh_node;

/* Links up the tree, so that a search can start at the hint's leaf:
 * (node << 1 | k) names child k of a node. */
typedef struct bvh {
    bvh_node *nodes;
    double *corners;  /* 9 coordinates per triangle, in leaf order */
    uint64_t *up;     /* per node but the root: where it hangs */
    uint64_t *leaf;   /* per slot: the leaf holding it */
    size_t nt;
} bvh;

/* Centroids compare by (coordinate, triangle index): a strict total order, so
 * the median split is one definite set whatever the selection does. */
static int cen_less(const double *cen, int axis, uint32_t x, uint32_t y) {
    double a = cen[3 * (size_t)x + (size_t)axis], b = cen[3 * (size_t)y + (size_t)axis];
    return a < b || (a == b && x < y);
}

static void swap_u32(uint32_t *v, size_t i, size_t j) {
    uint32_t x = v[i];
    v[i] = v[j];
    v[j] = x;
}

static void sift_down(const double *cen, int axis, uint32_t *v, size_t root, size_t n) {
    for (;;) {
        size_t child = 2 * root + 1;
        if (child >= n) return;
        if (child + 1 < n && cen_less(cen, axis, v[child], v[child + 1])) child++;
        if (!cen_less(cen, axis, v[root], v[child])) return;
        swap_u32(v, root, child);
        root = child;
    }
}

/* The fallback that bounds quickselect's worst case. */
static void heap_sort(const double *cen, int axis, uint32_t *v, size_t n) {
    for (size_t i = n / 2; i > 0; i--) sift_down(cen, axis, v, i - 1, n);
    for (size_t end = n; end > 1; end--) {
        swap_u32(v, 0, end - 1);
        sift_down(cen, axis, v, 0, end - 1);
    }
}

/* Puts the k-th smallest of v[0..n) at k, smaller ones before it. Median of
 * three keeps sorted input (meshes often come sorted along an axis) linear;
 * a budget of partitions switches to heap sort on inputs that defeat it. */
static void select_nth(const double *cen, int axis, uint32_t *v, size_t n, size_t k) {
    size_t lo = 0, hi = n;
    unsigned budget = 64;
    while (hi - lo > 8) {
        if (budget-- == 0) {
            heap_sort(cen, axis, v + lo, hi - lo);
            return;
        }
        size_t mid = lo + (hi - lo) / 2, last = hi - 1;
        if (cen_less(cen, axis, v[mid], v[lo])) swap_u32(v, mid, lo);
        if (cen_less(cen, axis, v[last], v[lo])) swap_u32(v, last, lo);
        if (cen_less(cen, axis, v[last], v[mid])) swap_u32(v, last, mid);
        swap_u32(v, mid, last); /* the median of three becomes the pivot, at the end */
        uint32_t pivot = v[last];
        size_t store = lo;
        for (size_t i = lo; i < last; i++)
            if (cen_less(cen, axis, v[i], pivot)) swap_u32(v, i, store++);
        swap_u32(v, store, last);
        if (k == store) return;
        if (k < store)
            hi = store;
        else
            lo = store + 1;
    }
    for (size_t i = lo + 1; i < hi; i++)
        for (size_t j = i; j > lo && cen_less(cen, axis, v[j], v[j - 1]); j--)
            swap_u32(v, j, j - 1);
}

/* The tree's shape depends only on the count (leaves of at most LEAF_SIZE,
 * halves at the middle slot), so ordering the slots and making the nodes
 * are separate passes over the same recursion. */
static void order_slots(uint32_t *perm, const double *cen, size_t lo, size_t hi) {
    if (hi - lo <= LEAF_SIZE) return;
    double clo[3] = {INFINITY, INFINITY, INFINITY}, chi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (size_t s = lo; s < hi; s++)
        for (int k = 0; k < 3; k++) {
            double x = cen[3 * (size_t)perm[s] + (size_t)k];
            if (x < clo[k]) clo[k] = x;
            if (x > chi[k]) chi[k] = x;
        }
    int axis = 0;
    for (int k = 1; k < 3; k++)
        if (chi[k] - clo[k] > chi[axis] - clo[axis]) axis = k;
    size_t mid = lo + (hi - lo) / 2;
    select_nth(cen, axis, perm + lo, hi - lo, mid - lo);
    order_slots(perm, cen, lo, mid);
    order_slots(perm, cen, mid, hi);
}

static float float_down(double x) {
    float f = (float)x;
    return (double)f > x ? nextafterf(f, -INFINITY) : f;
}

static float float_up(double x) {
    float f = (float)x;
    return (double)f < x ? nextafterf(f, INFINITY) : f;
}

/* Makes child k of node `node` for slots [lo, hi) and returns its box. */
static void make_child(bvh *t, size_t node, int k, size_t lo, size_t hi, size_t *next,
                       double box[6]) {
    bvh_node *nd = &t->nodes[node];
    if (hi - lo <= LEAF_SIZE) {
        nd->child[k] = (uint32_t)lo;
        nd->count[k] = (uint32_t)(hi - lo);
        for (size_t s = lo; s < hi; s++) t->leaf[s] = (uint64_t)node << 1 | (uint64_t)k;
        for (int j = 0; j < 3; j++) {
            box[j] = INFINITY;
            box[3 + j] = -INFINITY;
        }
        for (size_t s = lo; s < hi; s++)
            for (int j = 0; j < 9; j++) {
                double x = t->corners[9 * s + (size_t)j];
                if (x < box[j % 3]) box[j % 3] = x;
                if (x > box[3 + j % 3]) box[3 + j % 3] = x;
            }
    } else {
        size_t c = (*next)++, mid = lo + (hi - lo) / 2;
        double b0[6], b1[6];
        nd->child[k] = (uint32_t)c;
        nd->count[k] = 0;
        t->up[c] = (uint64_t)node << 1 | (uint64_t)k;
        make_child(t, c, 0, lo, mid, next, b0);
        make_child(t, c, 1, mid, hi, next, b1);
        for (int j = 0; j < 3; j++) {
            box[j] = b0[j] < b1[j] ? b0[j] : b1[j];
            box[3 + j] = b0[3 + j] > b1[3 + j] ? b0[3 + j] : b1[3 + j];
        }
        nd = &t->nodes[node];
    }
    for (int j = 0; j < 3; j++) {
        nd->lo[k][j] = float_down(box[j]);
        nd->hi[k][j] = float_up(box[3 + j]);
    }
}

static void bvh_free(bvh *t) {
    free(t->nodes);
    free(t->corners);
    free(t->up);
    free(t->leaf);
    memset(t, 0, sizeof *t);
}

/* Triangles in spatial order (the tree's leaf order), in *perm (caller
 * frees). The samplers walk the same order, so one mesh's order serves as
 * its tree in one direction and its sample order in the other. */
static femlod_status mesh_order(uint32_t **perm, const femlod_mesh *m, femlod_error *err) {
    uint32_t *o = fl_alloc(m->nt, sizeof *o);
    double *cen = fl_alloc(m->nt, 3 * sizeof *cen);
    if (!o || !cen) {
        free(o);
        free(cen);
        return fl_error(err, FEMLOD_ENOMEM, "hausdorff: out of memory ordering %zu triangles",
                        m->nt);
    }
    for (size_t i = 0; i < m->nt; i++) {
        o[i] = (uint32_t)i;
        const uint32_t *c = m->tri + 3 * i;
        for (int k = 0; k < 3; k++)
            cen[3 * i + (size_t)k] = (m->pos[3 * (size_t)c[0] + (size_t)k] +
                                      m->pos[3 * (size_t)c[1] + (size_t)k] +
                                      m->pos[3 * (size_t)c[2] + (size_t)k]) / 3.0;
    }
    order_slots(o, cen, 0, m->nt);
    free(cen);
    *perm = o;
    return FEMLOD_OK;
}

static femlod_status bvh_build(bvh *t, const femlod_mesh *m, const uint32_t *perm,
                               femlod_error *err) {
    memset(t, 0, sizeof *t);
    size_t nt = m->nt;
    /* Halving a range of more than LEAF_SIZE slots leaves at least 2 in
     * each half, so beyond 4 triangles every leaf holds 2 or more: at most
     * nt / 2 leaves, one inner node fewer. */
    size_t nn = nt / 2 + 1;
    t->nodes = fl_alloc(nn, sizeof *t->nodes);
    t->corners = fl_alloc(nt, 9 * sizeof *t->corners);
    t->up = fl_alloc(nn, sizeof *t->up);
    t->leaf = fl_alloc(nt, sizeof *t->leaf);
    if (!t->nodes || !t->corners || !t->up || !t->leaf) {
        bvh_free(t);
        return fl_error(err, FEMLOD_ENOMEM, "hausdorff: out of memory for a tree of %zu triangles",
                        nt);
    }
    t->nt = nt;
    /* Copies of the corners in leaf order: a leaf's triangles are then
     * adjacent in memory, which the queries feel more than the 72 bytes a
     * triangle cost. */
    for (size_t s = 0; s < nt; s++) {
        const uint32_t *c = m->tri + 3 * (size_t)perm[s];
        for (int i = 0; i < 3; i++)
            memcpy(t->corners + 9 * s + 3 * (size_t)i, m->pos + 3 * (size_t)c[i],
                   3 * sizeof(double));
    }
    /* The root is always a node: with one triangle both its children are
     * that triangle's leaf. */
    size_t next = 1, mid = nt > 1 ? nt / 2 : 0;
    double box[6];
    make_child(t, 0, 0, 0, nt > 1 ? mid : 1, &next, box);
    make_child(t, 0, 1, mid, nt, &next, box);
    assert(next <= nn);
    t->up[0] = UINT64_MAX;
    return FEMLOD_OK;
}

static double box_dist2(const bvh_node *n, int k, const double p[3]) {
    double d = 0.0;
    for (int j = 0; j < 3; j++) {
        double lo = n->lo[k][j], hi = n->hi[k][j], e = 0.0;
        if (p[j] < lo)
            e = lo - p[j];
        else if (p[j] > hi)
            e = p[j] - hi;
        d += e * e;
    }
    return d;
}

typedef struct nearest {
    double best;
    size_t slot;
} nearest;

static void search_leaf(const bvh *t, size_t first, size_t count, const double p[3],
                        nearest *r) {
    for (size_t s = first; s < first + count; s++) {
        double e = triangle_dist2(t->corners + 9 * s, p);
        if (e < r->best) {
            r->best = e;
            r->slot = s;
        }
    }
}

/* Top-down search below child k of a node, whose box distance d is known. */
static void search_down(const bvh *t, uint32_t node, int k, double d, const double p[3],
                        double enough, nearest *r) {
    const bvh_node *nd = &t->nodes[node];
    if (nd->count[k]) {
        search_leaf(t, nd->child[k], nd->count[k], p, r);
        return;
    }
    /* Median splits keep the tree balanced: its depth is below 33 for 2^32
     * triangles, and the stack holds at most one pending child per level. */
    struct {
        uint32_t node;
        double d;
    } stack[80];
    size_t top = 0;
    stack[top].node = nd->child[k];
    stack[top++].d = d;
    while (top > 0) {
        top--;
        if (stack[top].d >= r->best) continue;
        nd = &t->nodes[stack[top].node];
        double dk[2] = {box_dist2(nd, 0, p), box_dist2(nd, 1, p)};
        int near = dk[1] < dk[0];
        /* Pushed far first so that the near child is searched first. */
        for (int i = 0; i < 2; i++) {
            int c = i == 0 ? !near : near;
            if (dk[c] >= r->best) continue;
            if (nd->count[c]) {
                search_leaf(t, nd->child[c], nd->count[c], p, r);
                if (r->best <= enough) return;
            } else {
                assert(top < sizeof stack / sizeof stack[0]);
                stack[top].node = nd->child[c];
                stack[top++].d = dk[c];
            }
        }
    }
}

/* Squared distance from p to the nearest triangle. The search starts at
 * the leaf of slot *hint, the previous sample's answer (samples come in
 * spatial order, so it is close and its distance prunes most of the tree),
 * and climbs: at each ancestor only the sibling's box needs a look, and the
 * whole tree is covered once the root is passed. It may stop once the
 * distance is <= enough: the caller then only needs to know it is not
 * larger. */
static double bvh_nearest(const bvh *t, const double p[3], size_t *hint, double enough) {
    nearest r = {triangle_dist2(t->corners + 9 * *hint, p), *hint};
    if (r.best <= enough) return r.best;
    uint64_t at = t->leaf[*hint];
    const bvh_node *nd = &t->nodes[at >> 1];
    int k = (int)(at & 1);
    search_leaf(t, nd->child[k], nd->count[k], p, &r);
    while (r.best > enough) {
        uint32_t node = (uint32_t)(at >> 1);
        int sib = 1 - (int)(at & 1);
        double d = box_dist2(&t->nodes[node], sib, p);
        if (d < r.best) search_down(t, node, sib, d, p, enough, &r);
        at = t->up[node];
        if (at == UINT64_MAX) break;
    }
    *hint = r.slot;
    return r.best;
}

/* }====== */

/* {====== sampling one side */

/* The samples of one mesh: what the grid needs, computed once. */
typedef struct side_mesh {
    const femlod_mesh *m;
    uint32_t *edges;   /* 2*ne, sorted by (a, b) */
    size_t ne;
    size_t *estart;    /* nv+1: vertex a's edges {a, b > a} are estart[a] .. estart[a+1]-1 */
    const uint32_t *order; /* nt: triangles in spatial order (borrowed) */
    unsigned char *vdone, *edone; /* sampled already */
    size_t used;       /* vertices used by a triangle */
} side_mesh;

static void side_free(side_mesh *s) {
    free(s->edges);
    free(s->estart);
    free(s->vdone);
    free(s->edone);
    memset(s, 0, sizeof *s);
}

static femlod_status side_init(side_mesh *s, const femlod_mesh *m, const uint32_t *order,
                               femlod_error *err) {
    memset(s, 0, sizeof *s);
    s->m = m;
    s->order = order;
    femlod_status st = fl_quality_edges(&s->edges, &s->ne, m->tri, m->nt, m->nv, err);
    if (st != FEMLOD_OK) return st;
    s->estart = fl_calloc(m->nv + 1, sizeof *s->estart);
    s->vdone = fl_calloc(m->nv, 1);
    s->edone = fl_calloc(s->ne, 1);
    if (!s->estart || !s->vdone || !s->edone) {
        side_free(s);
        return fl_error(err, FEMLOD_ENOMEM, "hausdorff: out of memory for %zu samples' bookkeeping",
                        m->nv + s->ne);
    }
    for (size_t e = 0; e < s->ne; e++) s->estart[s->edges[2 * e] + 1]++;
    for (size_t v = 0; v < m->nv; v++) s->estart[v + 1] += s->estart[v];
    for (size_t i = 0; i < 3 * m->nt; i++) s->vdone[m->tri[i]] = 1;
    for (size_t v = 0; v < m->nv; v++) s->used += s->vdone[v];
    memset(s->vdone, 0, m->nv);
    return FEMLOD_OK;
}

/* Index of edge {a, b}, which exists: a binary search among a's edges. */
static size_t edge_index(const side_mesh *s, uint32_t a, uint32_t b) {
    if (a > b) {
        uint32_t x = a;
        a = b;
        b = x;
    }
    size_t lo = s->estart[a], hi = s->estart[a + 1];
    while (hi - lo > 1) {
        size_t mid = lo + (hi - lo) / 2;
        if (s->edges[2 * mid + 1] <= b)
            lo = mid;
        else
            hi = mid;
    }
    assert(s->edges[2 * lo + 1] == b);
    return lo;
}

/* Grid steps across a length: at least 1, so a spacing larger than the mesh
 * (or infinite) leaves the vertices and midpoints alone. */
static double divisions(double length, double spacing) {
    double n = ceil(length / spacing);
    if (!(n >= 1.0)) return 1.0;
    return n > MAX_DIVISIONS ? MAX_DIVISIONS : n;
}

/* Edge steps: even, so that the midpoint is one of the points. */
static double edge_divisions(double length, double spacing) {
    double n = divisions(length, spacing);
    return n < 2.0 ? 2.0 : n + fmod(n, 2.0);
}

static double tri_longest(const femlod_mesh *m, size_t t) {
    const uint32_t *c = m->tri + 3 * t;
    const double *a = m->pos + 3 * (size_t)c[0], *b = m->pos + 3 * (size_t)c[1],
                 *d = m->pos + 3 * (size_t)c[2];
    double l = length3(a, b), l2 = length3(b, d), l3 = length3(d, a);
    if (l2 > l) l = l2;
    return l3 > l ? l3 : l;
}

/* Samples at a spacing, in double: exact below 2^53 and never wraps. */
static double side_count(const side_mesh *s, double spacing) {
    const femlod_mesh *m = s->m;
    double n = (double)s->used;
    for (size_t e = 0; e < s->ne; e++) {
        const double *a = m->pos + 3 * (size_t)s->edges[2 * e];
        const double *b = m->pos + 3 * (size_t)s->edges[2 * e + 1];
        n += edge_divisions(length3(a, b), spacing) - 1.0;
    }
    for (size_t t = 0; t < m->nt; t++) {
        double k = divisions(tri_longest(m, t), spacing);
        n += (k - 1.0) * (k - 2.0) / 2.0;
    }
    return n;
}

/* The spacing actually used on one side: the asked one, grown until the
 * side has at most cap samples. Vertices and edge midpoints are always
 * taken, so a mesh with more of those than cap gets only them. */
static double side_spacing(const side_mesh *s, double spacing, double cap) {
    double base = (double)s->used + (double)s->ne;
    if (base >= cap) return INFINITY;
    for (int iter = 0; iter < 200; iter++) {
        double n = side_count(s, spacing);
        if (n <= cap) return spacing;
        /* Grid points go with 1/spacing^2: aim straight at the cap, but
         * always move so that the loop ends. */
        double grow = sqrt((n - base) / (cap - base));
        spacing *= grow > 1.01 ? grow : 1.01;
    }
    return INFINITY;
}

typedef struct side_result {
    double max2;  /* largest squared distance */
    double sum;   /* of distances, when means are wanted */
    size_t count;
} side_result;

typedef struct sampler {
    fl_progress *prog; /* counts triangles over both sides */
    size_t walked;     /* triangles of the earlier side */
    int cancelled;
    const bvh *target;
    size_t hint;
    int exact; /* every distance exact (for the mean), or only the maximum */
    side_result r;
} sampler;

static void sample(sampler *q, const double p[3]) {
    double d2 = bvh_nearest(q->target, p, &q->hint, q->exact ? 0.0 : q->r.max2);
    if (d2 > q->r.max2) q->r.max2 = d2;
    if (q->exact) q->r.sum += sqrt(d2);
    q->r.count++;
}

/* Triangle by triangle in spatial order: the corners and sides not
 * sampled yet, then the strictly interior grid points. Edge points run
 * from the smaller vertex index, so they do not depend on which triangle
 * comes first. */
static void side_run(sampler *q, side_mesh *s, double spacing) {
    const femlod_mesh *m = s->m;
    for (size_t o = 0; o < m->nt; o++) {
        if (fl_progress_at(q->prog, q->walked + o)) {
            q->cancelled = 1;
            return;
        }
        size_t t = s->order[o];
        const uint32_t *c = m->tri + 3 * t;
        for (int k = 0; k < 3; k++)
            if (!s->vdone[c[k]]) {
                s->vdone[c[k]] = 1;
                sample(q, m->pos + 3 * (size_t)c[k]);
            }
        for (int k = 0; k < 3; k++) {
            if (c[k] == c[(k + 1) % 3]) continue;
            size_t e = edge_index(s, c[k], c[(k + 1) % 3]);
            if (s->edone[e]) continue;
            s->edone[e] = 1;
            const double *a = m->pos + 3 * (size_t)s->edges[2 * e];
            const double *b = m->pos + 3 * (size_t)s->edges[2 * e + 1];
            double n = edge_divisions(length3(a, b), spacing);
            for (double i = 1.0; i < n; i += 1.0) {
                double p[3];
                /* The midpoint exactly, whatever n: it is the one edge point
                 * a caller can name. */
                for (int j = 0; j < 3; j++)
                    p[j] = 2.0 * i == n ? (a[j] + b[j]) / 2.0 : (a[j] * (n - i) + b[j] * i) / n;
                sample(q, p);
            }
        }
        double n = divisions(tri_longest(m, t), spacing);
        if (n < 3.0) continue;
        const double *a = m->pos + 3 * (size_t)c[0], *b = m->pos + 3 * (size_t)c[1],
                     *d = m->pos + 3 * (size_t)c[2];
        for (double i = 1.0; i + 2.0 <= n; i += 1.0)
            for (double j = 1.0; i + j + 1.0 <= n; j += 1.0) {
                double h = n - i - j, p[3];
                for (int k = 0; k < 3; k++) p[k] = (a[k] * h + b[k] * i + d[k] * j) / n;
                sample(q, p);
            }
    }
}

/* One direction: samples of `from` (walked in from_order) against the tree
 * of `to` (built on to_order). */
static femlod_status one_side(side_result *out, const femlod_mesh *from, const uint32_t *from_order,
                              const femlod_mesh *to, const uint32_t *to_order, double spacing,
                              double cap, int exact, fl_progress *prog, size_t walked,
                              femlod_error *err) {
    side_mesh s;
    bvh tree;
    femlod_status st = side_init(&s, from, from_order, err);
    if (st != FEMLOD_OK) return st;
    st = bvh_build(&tree, to, to_order, err);
    if (st != FEMLOD_OK) {
        side_free(&s);
        return st;
    }
    sampler q;
    memset(&q, 0, sizeof q);
    q.target = &tree;
    q.exact = exact;
    q.prog = prog;
    q.walked = walked;
    side_run(&q, &s, side_spacing(&s, spacing, cap));
    *out = q.r;
    bvh_free(&tree);
    side_free(&s);
    return q.cancelled ? fl_progress_cancelled(err, "hausdorff") : FEMLOD_OK;
}

/* }====== */

femlod_status femlod_mesh_hausdorff(const femlod_mesh *mesh, const femlod_mesh *reference,
                                    const femlod_hausdorff_options *options,
                                    femlod_hausdorff_result *out, femlod_error *err) {
    assert(mesh && reference && out);
    femlod_hausdorff_options opt = FEMLOD_HAUSDORFF_OPTIONS_INIT;
    if (options) opt = *options;
    if (!(opt.spacing >= 0.0) || !isfinite(opt.spacing))
        return fl_error(err, FEMLOD_EINPUT,
                        "hausdorff: spacing must be a finite number >= 0 (got %g)", opt.spacing);
    if (mesh->nt == 0) return fl_error(err, FEMLOD_EINPUT, "hausdorff: the mesh has no triangle");
    if (reference->nt == 0)
        return fl_error(err, FEMLOD_EINPUT, "hausdorff: the reference has no triangle");

    double lo[3], hi[3], d[3];
    femlod_mesh_bbox(reference, lo, hi);
    sub3(d, hi, lo);
    double diagonal = sqrt(dot3(d, d));
    double spacing = opt.spacing > 0.0 ? opt.spacing : diagonal / DEFAULT_DIVISOR;
    if (!(spacing > 0.0)) spacing = INFINITY; /* a reference shrunk to a point */
    double cap = (double)(opt.max_samples ? opt.max_samples : DEFAULT_MAX_SAMPLES);

    /* The mean is reported forward only, so the backward pass may stop each
     * search as soon as it cannot raise the maximum. */
    side_result fwd, bwd;
    uint32_t *morder = NULL, *ref_order = NULL;
    fl_progress prog;
    fl_progress_init(&prog, opt.progress, opt.progress_payload, mesh->nt + reference->nt);
    femlod_status st = mesh_order(&morder, mesh, err);
    if (st == FEMLOD_OK) st = mesh_order(&ref_order, reference, err);
    if (st == FEMLOD_OK)
        st = one_side(&fwd, mesh, morder, reference, ref_order, spacing, cap, 1, &prog, 0, err);
    if (st == FEMLOD_OK)
        st = one_side(&bwd, reference, ref_order, mesh, morder, spacing, cap, 0, &prog, mesh->nt,
                      err);
    free(morder);
    free(ref_order);
    if (st != FEMLOD_OK) return st;
    fl_progress_end(&prog);

    femlod_hausdorff_result r;
    memset(&r, 0, sizeof r);
    r.forward = sqrt(fwd.max2);
    r.backward = sqrt(bwd.max2);
    r.distance = r.forward > r.backward ? r.forward : r.backward;
    r.mean_forward = fwd.count ? fwd.sum / (double)fwd.count : 0.0;
    r.diagonal = diagonal;
    r.relative = diagonal > 0.0 ? r.distance / diagonal : 0.0;
    r.samples = fwd.count + bwd.count;
    *out = r;
    return FEMLOD_OK;
}
