/*
 * adjacency.c - edge and vertex adjacency of a triangle mesh, boundary and
 * non-manifold aware, built in time linear in the mesh size (counting sorts;
 * only each vertex's neighbour list is sorted, which is short).
 *
 * Nothing is rejected: boundary edges (one triangle), non-manifold edges
 * (three or more), pinched vertices, inconsistent orientation and triangles
 * with repeated vertices are all represented and counted, because the
 * quality report must describe any mesh a user loads.
 */
#include "core.h"

#include <assert.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

void fl_adjacency_free(fl_adjacency *adj) {
    if (!adj) return;
    free(adj->edge_v);
    free(adj->edge_start);
    free(adj->edge_tris);
    free(adj->vert_start);
    free(adj->vert_tris);
    free(adj->nbr_start);
    free(adj->vert_nbrs);
    free(adj->vert_edges);
    free(adj->tri_edges);
    memset(adj, 0, sizeof *adj);
}

static int cmp_u32(const void *a, const void *b) {
    uint32_t x = *(const uint32_t *)a, y = *(const uint32_t *)b;
    return (x > y) - (x < y);
}

void fl_sort_u32(uint32_t *v, size_t n) {
    if (n > 24) {
        qsort(v, n, sizeof *v, cmp_u32);
        return;
    }
    for (size_t i = 1; i < n; i++) {
        uint32_t x = v[i];
        size_t j = i;
        while (j > 0 && v[j - 1] > x) {
            v[j] = v[j - 1];
            j--;
        }
        v[j] = x;
    }
}

/* Position of x in the sorted v[0..n) or SIZE_MAX. */
static size_t find_sorted(const uint32_t *v, size_t n, uint32_t x) {
    size_t lo = 0, hi = n;
    while (lo < hi) {
        size_t mid = lo + (hi - lo) / 2;
        if (v[mid] < x)
            lo = mid + 1;
        else
            hi = mid;
    }
    return (lo < n && v[lo] == x) ? lo : SIZE_MAX;
}

uint32_t fl_adjacency_find_edge(const fl_adjacency *adj, uint32_t a, uint32_t b) {
    if (a >= adj->nv || b >= adj->nv || a == b) return UINT32_MAX;
    size_t s = adj->nbr_start[a], n = adj->nbr_start[a + 1] - s;
    size_t k = find_sorted(adj->vert_nbrs + s, n, b);
    return k == SIZE_MAX ? UINT32_MAX : adj->vert_edges[s + k];
}

femlod_status fl_adjacency_build(fl_adjacency *adj, const uint32_t *tri, size_t nt, size_t nv,
                                 femlod_error *err) {
    memset(adj, 0, sizeof *adj);
    if (nv > UINT32_MAX - 1 || nt > UINT32_MAX / 3)
        return fl_error(err, FEMLOD_EINPUT, "mesh too large for adjacency");
    adj->nv = nv;
    adj->nt = nt;
    uint32_t *mark = NULL, *cursor = NULL;
    adj->vert_start = fl_calloc(nv + 1, sizeof(uint32_t));
    adj->nbr_start = fl_calloc(nv + 1, sizeof(uint32_t));
    adj->tri_edges = fl_alloc(nt, 3 * sizeof(uint32_t));
    mark = fl_alloc(nv, sizeof *mark);
    cursor = fl_alloc(nv + 1, sizeof *cursor);
    if (!adj->vert_start || !adj->nbr_start || !adj->tri_edges || !mark || !cursor) goto nomem;

    /* Vertex -> triangles by counting sort; a triangle repeating v counts once. */
    for (size_t t = 0; t < nt; t++) {
        const uint32_t *c = tri + 3 * t;
        adj->vert_start[c[0] + 1]++;
        if (c[1] != c[0]) adj->vert_start[c[1] + 1]++;
        if (c[2] != c[0] && c[2] != c[1]) adj->vert_start[c[2] + 1]++;
    }
    for (size_t v = 0; v < nv; v++) adj->vert_start[v + 1] += adj->vert_start[v];
    adj->vert_tris = fl_alloc(adj->vert_start[nv], sizeof(uint32_t));
    if (!adj->vert_tris) goto nomem;
    memcpy(cursor, adj->vert_start, (nv + 1) * sizeof *cursor);
    for (size_t t = 0; t < nt; t++) {
        const uint32_t *c = tri + 3 * t;
        adj->vert_tris[cursor[c[0]]++] = (uint32_t)t;
        if (c[1] != c[0]) adj->vert_tris[cursor[c[1]]++] = (uint32_t)t;
        if (c[2] != c[0] && c[2] != c[1]) adj->vert_tris[cursor[c[2]]++] = (uint32_t)t;
    }

    /* Neighbours: each vertex's distinct neighbours through its triangles.
     * Every corner of a vertex's triangle is a neighbour through a side, so
     * the count is bounded by 2 * (number of incident triangles). */
    memset(mark, 0xFF, nv * sizeof *mark);
    size_t total = 0;
    for (size_t v = 0; v < nv; v++) {
        for (uint32_t k = adj->vert_start[v]; k < adj->vert_start[v + 1]; k++) {
            const uint32_t *c = tri + 3 * (size_t)adj->vert_tris[k];
            for (int i = 0; i < 3; i++)
                if (c[i] != v && mark[c[i]] != v) {
                    mark[c[i]] = (uint32_t)v;
                    total++;
                }
        }
        if (total > UINT32_MAX) goto nomem;
        adj->nbr_start[v + 1] = (uint32_t)total;
    }
    adj->vert_nbrs = fl_alloc(total, sizeof(uint32_t));
    adj->vert_edges = fl_alloc(total, sizeof(uint32_t));
    if (!adj->vert_nbrs || !adj->vert_edges) goto nomem;
    memset(mark, 0xFF, nv * sizeof *mark);
    for (size_t v = 0; v < nv; v++) {
        size_t n = adj->nbr_start[v];
        for (uint32_t k = adj->vert_start[v]; k < adj->vert_start[v + 1]; k++) {
            const uint32_t *c = tri + 3 * (size_t)adj->vert_tris[k];
            for (int i = 0; i < 3; i++)
                if (c[i] != v && mark[c[i]] != v) {
                    mark[c[i]] = (uint32_t)v;
                    adj->vert_nbrs[n++] = c[i];
                }
        }
        fl_sort_u32(adj->vert_nbrs + adj->nbr_start[v], n - adj->nbr_start[v]);
    }

    /* Edges {a, b}, a < b, numbered in (a, b) order. For b, the smaller
     * neighbours a come first in its sorted list and are met in increasing
     * a, so a cursor per vertex fills vert_edges on both ends. */
    adj->ne = total / 2;
    adj->edge_v = fl_alloc(adj->ne, 2 * sizeof(uint32_t));
    adj->edge_start = fl_calloc(adj->ne + 1, sizeof(uint32_t));
    if (!adj->edge_v || !adj->edge_start) goto nomem;
    memcpy(cursor, adj->nbr_start, (nv + 1) * sizeof *cursor);
    size_t e = 0;
    for (size_t a = 0; a < nv; a++) {
        for (uint32_t k = adj->nbr_start[a]; k < adj->nbr_start[a + 1]; k++) {
            uint32_t b = adj->vert_nbrs[k];
            if (b < a) continue; /* already numbered from b's side */
            adj->edge_v[2 * e] = (uint32_t)a;
            adj->edge_v[2 * e + 1] = b;
            adj->vert_edges[k] = (uint32_t)e;
            adj->vert_edges[cursor[b]++] = (uint32_t)e;
            e++;
        }
    }
    assert(e == adj->ne);

    /* Triangle sides -> edges, then edge -> triangles (each triangle once per
     * edge, in increasing triangle order). */
    for (size_t t = 0; t < nt; t++) {
        const uint32_t *c = tri + 3 * t;
        for (int i = 0; i < 3; i++) {
            uint32_t a = c[i], b = c[(i + 1) % 3];
            uint32_t id = a == b ? UINT32_MAX : fl_adjacency_find_edge(adj, a, b);
            adj->tri_edges[3 * t + (size_t)i] = id;
            if (id == UINT32_MAX) continue;
            int seen = 0;
            for (int j = 0; j < i; j++) seen |= adj->tri_edges[3 * t + (size_t)j] == id;
            if (!seen) adj->edge_start[id + 1]++;
        }
    }
    for (size_t k = 0; k < adj->ne; k++) adj->edge_start[k + 1] += adj->edge_start[k];
    adj->edge_tris = fl_alloc(adj->edge_start[adj->ne], sizeof(uint32_t));
    if (!adj->edge_tris) goto nomem;
    free(cursor);
    cursor = fl_alloc(adj->ne + 1, sizeof *cursor);
    if (!cursor) goto nomem;
    memcpy(cursor, adj->edge_start, (adj->ne + 1) * sizeof *cursor);
    for (size_t t = 0; t < nt; t++)
        for (int i = 0; i < 3; i++) {
            uint32_t id = adj->tri_edges[3 * t + (size_t)i];
            if (id == UINT32_MAX) continue;
            int seen = 0;
            for (int j = 0; j < i; j++) seen |= adj->tri_edges[3 * t + (size_t)j] == id;
            if (!seen) adj->edge_tris[cursor[id]++] = (uint32_t)t;
        }
    free(mark);
    free(cursor);
    return FEMLOD_OK;

nomem:
    free(mark);
    free(cursor);
    fl_adjacency_free(adj);
    return fl_error(err, FEMLOD_ENOMEM, "out of memory building adjacency of %zu triangles", nt);
}

/* The neighbours of fl_adjacency_build (each vertex's distinct corners of
 * its triangles, in increasing order) without the edges: only the vertex ->
 * triangles lists and one vertex's neighbours at a time, a sixth of the
 * adjacency's memory. The sums run in the same order, so the lengths are
 * bit for bit those computed over adj.vert_nbrs. */
femlod_status fl_mean_edge_lengths(const double *pos, const uint32_t *tri, size_t nt, size_t nv,
                                   double *out, femlod_error *err) {
    if (nv > UINT32_MAX - 2 || nt > UINT32_MAX / 3)
        return fl_error(err, FEMLOD_EINPUT, "mesh too large for adjacency");
    uint32_t *start = fl_calloc(nv + 2, sizeof *start), *vt = NULL, *mark = NULL, *nb = NULL;
    if (!start) goto nomem;
    /* counts at v + 2, so that filling at start[v + 1] leaves start[v + 1]
     * at the end of v's list */
    for (size_t t = 0; t < nt; t++) {
        const uint32_t *c = tri + 3 * t;
        start[c[0] + 2]++;
        if (c[1] != c[0]) start[c[1] + 2]++;
        if (c[2] != c[0] && c[2] != c[1]) start[c[2] + 2]++;
    }
    uint32_t most = 0;
    for (size_t v = 0; v < nv; v++) {
        if (start[v + 2] > most) most = start[v + 2];
        start[v + 2] += start[v + 1];
    }
    vt = fl_alloc(start[nv + 1] ? start[nv + 1] : 1, sizeof *vt);
    mark = fl_alloc(nv ? nv : 1, sizeof *mark);
    nb = fl_alloc(2 * (size_t)most + 1, sizeof *nb); /* a triangle adds at most two neighbours */
    if (!vt || !mark || !nb) goto nomem;
    for (size_t t = 0; t < nt; t++) {
        const uint32_t *c = tri + 3 * t;
        vt[start[c[0] + 1]++] = (uint32_t)t;
        if (c[1] != c[0]) vt[start[c[1] + 1]++] = (uint32_t)t;
        if (c[2] != c[0] && c[2] != c[1]) vt[start[c[2] + 1]++] = (uint32_t)t;
    }
    if (nv) memset(mark, 0xFF, nv * sizeof *mark);
    for (size_t v = 0; v < nv; v++) {
        size_t n = 0;
        for (uint32_t k = start[v]; k < start[v + 1]; k++) {
            const uint32_t *c = tri + 3 * (size_t)vt[k];
            for (int i = 0; i < 3; i++)
                if (c[i] != v && mark[c[i]] != v) {
                    mark[c[i]] = (uint32_t)v;
                    nb[n++] = c[i];
                }
        }
        fl_sort_u32(nb, n);
        double sum = 0.0;
        for (size_t k = 0; k < n; k++) {
            const double *a = pos + 3 * v, *b = pos + 3 * (size_t)nb[k];
            double d[3] = {a[0] - b[0], a[1] - b[1], a[2] - b[2]};
            sum += sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        }
        out[v] = n ? sum / (uint32_t)n : 0.0;
    }
    free(start);
    free(vt);
    free(mark);
    free(nb);
    return FEMLOD_OK;

nomem:
    free(start);
    free(vt);
    free(mark);
    free(nb);
    return fl_error(err, FEMLOD_ENOMEM, "out of memory measuring the edges of %zu triangles", nt);
}

/* Direction in which triangle t runs along edge {a, b}: +1 for a->b, -1 for
 * b->a, 0 when the triangle has no such side. */
static int side_direction(const uint32_t *c, uint32_t a, uint32_t b) {
    for (int i = 0; i < 3; i++) {
        uint32_t p = c[i], q = c[(i + 1) % 3];
        if (p == a && q == b) return 1;
        if (p == b && q == a) return -1;
    }
    return 0;
}

static uint32_t uf_find(uint32_t *parent, uint32_t x) {
    while (parent[x] != x) {
        parent[x] = parent[parent[x]];
        x = parent[x];
    }
    return x;
}

/* Joins the sets of x and y, keeping the smaller root so the result does not
 * depend on the order of calls; returns 1 when they were separate. */
static int uf_union(uint32_t *parent, uint32_t x, uint32_t y) {
    x = uf_find(parent, x);
    y = uf_find(parent, y);
    if (x == y) return 0;
    if (x < y)
        parent[y] = x;
    else
        parent[x] = y;
    return 1;
}

femlod_status fl_adjacency_topology(const fl_adjacency *adj, const uint32_t *tri,
                                    femlod_topology *result, femlod_error *err) {
    size_t nv = adj->nv, nt = adj->nt;
    unsigned char *vbad = fl_calloc(nv, 1);
    uint32_t *parent = fl_alloc(nt, sizeof *parent);
    if (!vbad || !parent) {
        free(vbad);
        free(parent);
        return fl_error(err, FEMLOD_ENOMEM, "out of memory in topology of %zu triangles", nt);
    }
    /* Filled locally: *result is written only on success. */
    femlod_topology top, *out = &top;
    memset(out, 0, sizeof *out);
    out->edges = adj->ne;
    for (size_t e = 0; e < adj->ne; e++) {
        uint32_t n = adj->edge_start[e + 1] - adj->edge_start[e];
        uint32_t a = adj->edge_v[2 * e], b = adj->edge_v[2 * e + 1];
        if (n == 1) out->boundary_edges++;
        if (n >= 3) {
            out->nonmanifold_edges++;
            vbad[a] = vbad[b] = 1;
        }
        if (n == 2) {
            const uint32_t *t0 = tri + 3 * (size_t)adj->edge_tris[adj->edge_start[e]];
            const uint32_t *t1 = tri + 3 * (size_t)adj->edge_tris[adj->edge_start[e] + 1];
            if (side_direction(t0, a, b) * side_direction(t1, a, b) > 0) out->inconsistent_edges++;
        }
    }
    {
        /* Fans around v: its triangles joined through its two-triangle edges.
         * parent[] is indexed by position in v's triangle list. */
        for (size_t v = 0; v < nv; v++) {
            uint32_t s = adj->vert_start[v], n = adj->vert_start[v + 1] - s;
            if (n == 0) {
                out->isolated_vertices++;
                continue;
            }
            if (vbad[v]) continue;
            for (uint32_t k = 0; k < n; k++) parent[k] = k;
            uint32_t fans = n;
            for (uint32_t k = adj->nbr_start[v]; k < adj->nbr_start[v + 1]; k++) {
                uint32_t e = adj->vert_edges[k];
                if (adj->edge_start[e + 1] - adj->edge_start[e] != 2) continue;
                size_t i = find_sorted(adj->vert_tris + s, n, adj->edge_tris[adj->edge_start[e]]);
                size_t j =
                    find_sorted(adj->vert_tris + s, n, adj->edge_tris[adj->edge_start[e] + 1]);
                if (i != SIZE_MAX && j != SIZE_MAX) fans -= (uint32_t)uf_union(parent, (uint32_t)i, (uint32_t)j);
            }
            if (fans > 1) vbad[v] = 1;
        }
        for (size_t v = 0; v < nv; v++) out->nonmanifold_vertices += vbad[v];

        /* Components: triangles joined through shared vertices. */
        for (size_t t = 0; t < nt; t++) parent[t] = (uint32_t)t;
        size_t comps = nt;
        for (size_t v = 0; v < nv; v++) {
            uint32_t s = adj->vert_start[v], n = adj->vert_start[v + 1] - s;
            for (uint32_t k = 1; k < n; k++)
                comps -= (size_t)uf_union(parent, adj->vert_tris[s], adj->vert_tris[s + k]);
        }
        out->components = comps;
    }
    free(vbad);
    free(parent);
    out->closed = adj->ne > 0 && out->boundary_edges == 0 && out->nonmanifold_edges == 0;
    out->manifold = out->nonmanifold_edges == 0 && out->nonmanifold_vertices == 0;
    out->oriented = out->inconsistent_edges == 0;
    *result = top;
    return FEMLOD_OK;
}

femlod_status femlod_mesh_topology(const femlod_mesh *mesh, femlod_topology *out,
                                   femlod_error *err) {
    assert(mesh && out);
    fl_adjacency adj;
    femlod_status s = fl_adjacency_build(&adj, mesh->tri, mesh->nt, mesh->nv, err);
    if (s != FEMLOD_OK) return s;
    s = fl_adjacency_topology(&adj, mesh->tri, out, err);
    fl_adjacency_free(&adj);
    return s;
}
