/*
 * repair.c - explicit, reported mesh repair (issue 8): weld, drop degenerate
 * and duplicate triangles, cut non-manifold edges and vertices, orient
 * consistently, drop unused vertices. Nothing here runs behind the user's
 * back: femlod_mesh_repair makes a new mesh and counts every change, so a
 * recipe or `femlod repair` can say what happened to the user's mesh.
 *
 * The steps run in this order, each on the result of the previous one:
 *   1. weld: vertices closer than the tolerance (0: equal positions) merge
 *      into the one that comes first in the file; a vertex joins a cluster
 *      only when it is within the tolerance of the cluster's first vertex,
 *      so a chain of close points does not collapse into one;
 *   2. degenerate triangles (a repeated vertex, or stretch < 1e-6 as the
 *      quality report counts them) are dropped;
 *   3. duplicates (the same three vertices, in either orientation) are
 *      dropped, the first one kept;
 *   4. non-manifold edges and vertices are cut: triangles are joined across
 *      their two-triangle edges only, each vertex keeps one fan of its
 *      triangles and gets a new copy (same position) for each other fan;
 *   5. orientation: each component is made consistent across its two-
 *      triangle edges (breadth first from its first triangle); a closed
 *      component then faces outwards (positive signed volume), an open one
 *      keeps the orientation that flips fewer triangles;
 *   6. unused vertices are dropped.
 * Every choice is by index order, so the result depends only on the input.
 */
#include "core.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* {====== weld */

typedef struct cell_item {
    uint64_t key;
    uint32_t v;
} cell_item;

static int cmp_cell(const void *a, const void *b) {
    const cell_item *x = (const cell_item *)a, *y = (const cell_item *)b;
    if (x->key != y->key) return x->key < y->key ? -1 : 1;
    return (x->v > y->v) - (x->v < y->v);
}

/* Cell coordinates are 21 bits each. */
static uint64_t cell_key(int64_t i, int64_t j, int64_t k) {
    return (uint64_t)i << 42 | (uint64_t)j << 21 | (uint64_t)k;
}

/* map[v]: the vertex v merges into (itself when it leads a cluster). */
static femlod_status weld(const femlod_mesh *m, double tol, uint32_t *map, size_t *merged,
                          femlod_error *err) {
    size_t nv = m->nv;
    *merged = 0;
    for (size_t v = 0; v < nv; v++) map[v] = (uint32_t)v;
    if (nv < 2) return FEMLOD_OK;
    double lo[3], hi[3];
    for (int k = 0; k < 3; k++) lo[k] = hi[k] = m->pos[k];
    for (size_t v = 0; v < nv; v++)
        for (int k = 0; k < 3; k++) {
            lo[k] = fmin(lo[k], m->pos[3 * v + (size_t)k]);
            hi[k] = fmax(hi[k], m->pos[3 * v + (size_t)k]);
        }
    /* cells of at least the tolerance, at most 2^20 to a side */
    double cell = tol;
    for (int k = 0; k < 3; k++) cell = fmax(cell, (hi[k] - lo[k]) / 1048576.0);
    if (!(cell > 0.0)) cell = 1.0; /* every vertex at one point */
    cell_item *items = fl_alloc(nv, sizeof *items);
    if (!items) return fl_error(err, FEMLOD_ENOMEM, "out of memory welding %zu vertices", nv);
    int64_t (*ijk)[3] = fl_alloc(nv, sizeof *ijk);
    if (!ijk) {
        free(items);
        return fl_error(err, FEMLOD_ENOMEM, "out of memory welding %zu vertices", nv);
    }
    for (size_t v = 0; v < nv; v++) {
        for (int k = 0; k < 3; k++) {
            double t = floor((m->pos[3 * v + (size_t)k] - lo[k]) / cell);
            ijk[v][k] = t < 0 ? 0 : t > 2097151.0 ? 2097151 : (int64_t)t;
        }
        items[v].key = cell_key(ijk[v][0], ijk[v][1], ijk[v][2]);
        items[v].v = (uint32_t)v;
    }
    qsort(items, nv, sizeof *items, cmp_cell);
    double tol2 = tol * tol;
    /* In index order, each vertex looks for a cluster leader (an earlier
     * vertex that leads itself) within tol in the 27 cells around it; the
     * smallest such leader wins. */
    for (size_t v = 0; v < nv; v++) {
        const double *p = m->pos + 3 * v;
        uint32_t best = (uint32_t)v;
        for (int64_t di = -1; di <= 1; di++)
            for (int64_t dj = -1; dj <= 1; dj++)
                for (int64_t dk = -1; dk <= 1; dk++) {
                    int64_t i = ijk[v][0] + di, j = ijk[v][1] + dj, k = ijk[v][2] + dk;
                    if (i < 0 || j < 0 || k < 0 || i > 2097151 || j > 2097151 || k > 2097151)
                        continue;
                    uint64_t key = cell_key(i, j, k);
                    size_t a = 0, b = nv; /* first item with this key */
                    while (a < b) {
                        size_t mid = a + (b - a) / 2;
                        if (items[mid].key < key) a = mid + 1; else b = mid;
                    }
                    for (; a < nv && items[a].key == key && items[a].v < best; a++) {
                        uint32_t w = items[a].v;
                        if (w >= v || map[w] != w) continue;
                        const double *q = m->pos + 3 * (size_t)w;
                        double d2 = (p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1]) +
                                    (p[2] - q[2]) * (p[2] - q[2]);
                        if (tol > 0.0 ? d2 <= tol2 : (p[0] == q[0] && p[1] == q[1] && p[2] == q[2]))
                            best = w;
                    }
                }
        if (best != v) {
            map[v] = best;
            (*merged)++;
        }
    }
    free(ijk);
    free(items);
    return FEMLOD_OK;
}

/* }====== */

/* {====== duplicates */

typedef struct tri_key {
    uint32_t s[3]; /* sorted corners */
    uint32_t t;
} tri_key;

static int cmp_tri_key(const void *a, const void *b) {
    const tri_key *x = (const tri_key *)a, *y = (const tri_key *)b;
    for (int k = 0; k < 3; k++)
        if (x->s[k] != y->s[k]) return x->s[k] < y->s[k] ? -1 : 1;
    return (x->t > y->t) - (x->t < y->t);
}

/* Marks keep[t] = 0 for every triangle whose vertex set an earlier one has. */
static int drop_duplicates(const uint32_t *tri, size_t nt, uint8_t *keep, size_t *dropped) {
    *dropped = 0;
    tri_key *k = fl_alloc(nt ? nt : 1, sizeof *k);
    if (!k) return 0;
    size_t n = 0;
    for (size_t t = 0; t < nt; t++) {
        if (!keep[t]) continue;
        uint32_t a = tri[3 * t], b = tri[3 * t + 1], c = tri[3 * t + 2], x;
        if (a > b) x = a, a = b, b = x;
        if (b > c) x = b, b = c, c = x;
        if (a > b) x = a, a = b, b = x;
        k[n].s[0] = a;
        k[n].s[1] = b;
        k[n].s[2] = c;
        k[n].t = (uint32_t)t;
        n++;
    }
    qsort(k, n, sizeof *k, cmp_tri_key);
    for (size_t i = 1; i < n; i++)
        if (memcmp(k[i].s, k[i - 1].s, sizeof k[i].s) == 0) {
            keep[k[i].t] = 0;
            (*dropped)++;
        }
    free(k);
    return 1;
}

/* }====== */

/* {====== non-manifold cut and orientation
 *
 * Both walk triangles across their two-triangle edges ("manifold edges"),
 * found from an fl_adjacency of the current triangles. */

/* The other triangle on side s of t when that side's edge has exactly two. */
static uint32_t across(const fl_adjacency *adj, size_t t, int s) {
    uint32_t e = adj->tri_edges[3 * t + (size_t)s];
    if (e == UINT32_MAX || adj->edge_start[e + 1] - adj->edge_start[e] != 2) return UINT32_MAX;
    uint32_t a = adj->edge_tris[adj->edge_start[e]], b = adj->edge_tris[adj->edge_start[e] + 1];
    return a == t ? b : a;
}

/* Cuts non-manifold vertices: for every vertex, its triangles are grouped
 * into fans joined across manifold edges at that vertex; the fan of its
 * first triangle keeps the vertex, every other fan gets a new copy. The
 * corners are rewritten in *tri; positions grow in *pos (3 per vertex). */
static femlod_status split_fans(uint32_t *tri, size_t nt, double **pos, size_t *nv,
                                size_t *added, femlod_error *err) {
    *added = 0;
    fl_adjacency adj;
    femlod_status st = fl_adjacency_build(&adj, tri, nt, *nv, err);
    if (st != FEMLOD_OK) return st;
    uint32_t *fan = fl_alloc(nt ? nt : 1, sizeof(uint32_t));   /* fan id of t at the current vertex */
    uint32_t *queue = fl_alloc(nt ? nt : 1, sizeof(uint32_t));
    uint32_t *newc = fl_alloc(nt ? 3 * nt : 1, sizeof(uint32_t)); /* corners after the cut */
    size_t cap = *nv;
    if (!fan || !queue || !newc) goto nomem;
    memcpy(newc, tri, 3 * nt * sizeof(uint32_t));
    for (size_t t = 0; t < nt; t++) fan[t] = UINT32_MAX;
    size_t nv0 = *nv;
    for (size_t v = 0; v < nv0; v++) {
        uint32_t b0 = adj.vert_start[v], b1 = adj.vert_start[v + 1];
        uint32_t fans = 0;
        for (uint32_t i = b0; i < b1; i++) {
            uint32_t t0 = adj.vert_tris[i];
            if (fan[t0] != UINT32_MAX) continue;
            /* a new fan: breadth first across manifold edges at v */
            size_t qh = 0, qt = 0;
            queue[qt++] = t0;
            fan[t0] = fans;
            while (qh < qt) {
                uint32_t t = queue[qh++];
                for (int s = 0; s < 3; s++) {
                    uint32_t a = tri[3 * (size_t)t + (size_t)s], b = tri[3 * (size_t)t + (size_t)((s + 1) % 3)];
                    if (a != v && b != v) continue;
                    uint32_t u = across(&adj, t, s);
                    if (u != UINT32_MAX && fan[u] == UINT32_MAX) {
                        fan[u] = fans;
                        queue[qt++] = u;
                    }
                }
            }
            if (fans > 0) {
                /* a copy of v for this fan */
                if (*nv >= UINT32_MAX) {
                    st = fl_error(err, FEMLOD_EINPUT, "too many vertices after cutting non-manifold vertices");
                    goto done;
                }
                if (*nv == cap) {
                    size_t ncap = cap < 16 ? 32 : cap + cap / 2;
                    double *np = fl_realloc(*pos, ncap, 3 * sizeof(double));
                    if (!np) goto nomem;
                    *pos = np;
                    cap = ncap;
                }
                uint32_t w = (uint32_t)(*nv)++;
                memcpy(*pos + 3 * (size_t)w, *pos + 3 * v, 3 * sizeof(double));
                for (size_t q = 0; q < qt; q++)
                    for (int c = 0; c < 3; c++)
                        if (tri[3 * (size_t)queue[q] + (size_t)c] == v) newc[3 * (size_t)queue[q] + (size_t)c] = w;
                (*added)++;
            }
            fans++;
        }
        for (uint32_t i = b0; i < b1; i++) fan[adj.vert_tris[i]] = UINT32_MAX;
    }
    memcpy(tri, newc, 3 * nt * sizeof(uint32_t));
    goto done;
nomem:
    st = fl_error(err, FEMLOD_ENOMEM, "out of memory cutting non-manifold vertices");
done:
    free(newc);
    free(queue);
    free(fan);
    fl_adjacency_free(&adj);
    return st;
}

/* Does t traverse the edge {a, b} as a -> b? */
static int goes(const uint32_t *c, uint32_t a, uint32_t b) {
    return (c[0] == a && c[1] == b) || (c[1] == a && c[2] == b) || (c[2] == a && c[0] == b);
}

static femlod_status orient(uint32_t *tri, size_t nt, const double *pos, size_t nv,
                            size_t *flipped, size_t *conflicts, femlod_error *err) {
    *flipped = *conflicts = 0;
    fl_adjacency adj;
    femlod_status st = fl_adjacency_build(&adj, tri, nt, nv, err);
    if (st != FEMLOD_OK) return st;
    uint8_t *flip = fl_calloc(nt ? nt : 1, 1), *seen = fl_calloc(nt ? nt : 1, 1);
    uint32_t *queue = fl_alloc(nt ? nt : 1, sizeof(uint32_t));
    if (!flip || !seen || !queue) {
        st = fl_error(err, FEMLOD_ENOMEM, "out of memory orienting %zu triangles", nt);
        goto done;
    }
    for (size_t t0 = 0; t0 < nt; t0++) {
        if (seen[t0]) continue;
        size_t qh = 0, qt = 0, nflip = 0;
        int closed = 1;
        queue[qt++] = (uint32_t)t0;
        seen[t0] = 1;
        while (qh < qt) {
            uint32_t t = queue[qh++];
            for (int s = 0; s < 3; s++) {
                uint32_t e = adj.tri_edges[3 * (size_t)t + (size_t)s];
                if (e == UINT32_MAX) continue;
                if (adj.edge_start[e + 1] - adj.edge_start[e] != 2) {
                    closed = 0;
                    continue;
                }
                uint32_t u = across(&adj, t, s);
                uint32_t a = tri[3 * (size_t)t + (size_t)s], b = tri[3 * (size_t)t + (size_t)((s + 1) % 3)];
                if (flip[t]) { uint32_t x = a; a = b; b = x; }
                /* as t (as oriented) goes a -> b, u must go b -> a */
                const uint32_t *cu = tri + 3 * (size_t)u;
                int u_same = goes(cu, a, b); /* u, unflipped, goes a -> b: it needs a flip */
                if (!seen[u]) {
                    seen[u] = 1;
                    flip[u] = (uint8_t)u_same;
                    nflip += (size_t)u_same;
                    queue[qt++] = u;
                } else if ((uint8_t)u_same != flip[u]) {
                    (*conflicts)++; /* counted from both sides */
                }
            }
        }
        /* the component is queue[0 .. qt) */
        int reverse;
        if (closed) {
            double vol = 0.0; /* six times the signed volume, as oriented now */
            for (size_t q = 0; q < qt; q++) {
                uint32_t t = queue[q];
                const double *A = pos + 3 * (size_t)tri[3 * (size_t)t];
                const double *B = pos + 3 * (size_t)tri[3 * (size_t)t + (flip[t] ? 2 : 1)];
                const double *C = pos + 3 * (size_t)tri[3 * (size_t)t + (flip[t] ? 1 : 2)];
                vol += A[0] * (B[1] * C[2] - B[2] * C[1]) - A[1] * (B[0] * C[2] - B[2] * C[0]) +
                       A[2] * (B[0] * C[1] - B[1] * C[0]);
            }
            reverse = vol < 0.0;
        } else {
            reverse = 2 * nflip > qt;
        }
        if (reverse)
            for (size_t q = 0; q < qt; q++) flip[queue[q]] ^= 1;
    }
    *conflicts /= 2;
    for (size_t t = 0; t < nt; t++)
        if (flip[t]) {
            uint32_t x = tri[3 * t + 1];
            tri[3 * t + 1] = tri[3 * t + 2];
            tri[3 * t + 2] = x;
            (*flipped)++;
        }
done:
    free(queue);
    free(seen);
    free(flip);
    fl_adjacency_free(&adj);
    return st;
}

/* }====== */

femlod_status femlod_mesh_repair(femlod_mesh **out, const femlod_mesh *mesh,
                                 const femlod_repair_options *options,
                                 femlod_repair_report *report, femlod_error *err) {
    femlod_repair_options o = FEMLOD_REPAIR_OPTIONS_INIT;
    if (options) o = *options;
    femlod_repair_report r;
    memset(&r, 0, sizeof r);
    if (isnan(o.weld) || isinf(o.weld))
        return fl_error(err, FEMLOD_EINPUT, "weld tolerance is %g (finite expected; < 0: off)",
                        o.weld);
    size_t nv = mesh->nv, nt = mesh->nt;
    r.vertices_in = nv;
    r.triangles_in = nt;
    uint32_t *map = fl_alloc(nv ? nv : 1, sizeof(uint32_t));
    uint32_t *tri = fl_alloc(nt ? 3 * nt : 1, sizeof(uint32_t));
    uint8_t *keep = fl_alloc(nt ? nt : 1, 1);
    double *pos = fl_alloc(nv ? nv : 1, 3 * sizeof(double));
    femlod_status st = FEMLOD_OK;
    if (!map || !tri || !keep || !pos) goto nomem;
    memcpy(pos, mesh->pos, 3 * nv * sizeof(double));
    /* 1. weld */
    if (o.weld >= 0.0) {
        st = weld(mesh, o.weld, map, &r.welded, err);
        if (st != FEMLOD_OK) goto done;
    } else {
        for (size_t v = 0; v < nv; v++) map[v] = (uint32_t)v;
    }
    for (size_t k = 0; k < 3 * nt; k++) tri[k] = map[mesh->tri[k]];
    /* 2. degenerate */
    for (size_t t = 0; t < nt; t++) {
        const uint32_t *c = tri + 3 * t;
        keep[t] = 1;
        if (!o.drop_degenerate) continue;
        if (c[0] == c[1] || c[1] == c[2] || c[2] == c[0] ||
            femlod_triangle_stretch(pos + 3 * (size_t)c[0], pos + 3 * (size_t)c[1],
                                    pos + 3 * (size_t)c[2]) < 1e-6) {
            keep[t] = 0;
            r.degenerate++;
        }
    }
    /* 3. duplicates */
    if (o.drop_duplicates && !drop_duplicates(tri, nt, keep, &r.duplicates)) goto nomem;
    size_t n = 0;
    for (size_t t = 0; t < nt; t++)
        if (keep[t]) {
            memmove(tri + 3 * n, tri + 3 * t, 3 * sizeof(uint32_t));
            n++;
        }
    nt = n;
    /* 4. non-manifold cut */
    if (o.split_nonmanifold) {
        st = split_fans(tri, nt, &pos, &nv, &r.split_vertices, err);
        if (st != FEMLOD_OK) goto done;
    }
    /* 5. orientation */
    if (o.orient) {
        st = orient(tri, nt, pos, nv, &r.flipped, &r.unorientable_edges, err);
        if (st != FEMLOD_OK) goto done;
    }
    /* 6. unused vertices (and the renumbering after welding) */
    {
        uint32_t *idx = fl_alloc(nv ? nv : 1, sizeof(uint32_t));
        if (!idx) goto nomem;
        /* idx: UINT32_MAX for a vertex no triangle uses, then the new index */
        for (size_t v = 0; v < nv; v++) idx[v] = UINT32_MAX;
        for (size_t k = 0; k < 3 * nt; k++) idx[tri[k]] = 0;
        size_t used = 0;
        for (size_t v = 0; v < nv; v++) {
            /* a vertex welded into another is gone either way (counted in welded) */
            int is_leader = v >= mesh->nv || map[v] == v;
            if (idx[v] != UINT32_MAX || (!o.drop_unused && is_leader)) {
                idx[v] = (uint32_t)used;
                memmove(pos + 3 * used, pos + 3 * v, 3 * sizeof(double));
                used++;
            } else if (is_leader) {
                r.unused++;
            }
        }
        for (size_t k = 0; k < 3 * nt; k++) tri[k] = idx[tri[k]];
        free(idx);
        nv = used;
    }
    {
        femlod_mesh *m = NULL;
        st = femlod_mesh_create(&m, pos, nv, tri, nt, err);
        if (st != FEMLOD_OK) goto done;
        r.vertices_out = nv;
        r.triangles_out = nt;
        /* what is left: edges a cut could not make manifold (a vertex whose
         * fans meet again elsewhere) */
        femlod_topology top;
        st = femlod_mesh_topology(m, &top, err);
        if (st != FEMLOD_OK) {
            femlod_mesh_free(m);
            goto done;
        }
        r.nonmanifold_edges_left = top.nonmanifold_edges;
        *out = m;
    }
    if (report) *report = r;
    goto done;
nomem:
    st = fl_error(err, FEMLOD_ENOMEM, "out of memory repairing a mesh of %zu triangles", nt);
done:
    free(pos);
    free(keep);
    free(tri);
    free(map);
    return st;
}
