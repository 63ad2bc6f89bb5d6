/*
 * mesh.c - the femlod_mesh object: arrays, create/copy/free, exact welding
 * of triangle soups (STL), growable buffers for the readers, and 1-to-4
 * subdivision (paper section 3: a coarse good mesh made dense keeps its
 * triangle shapes).
 */
#include "core.h"

#include <assert.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

femlod_mesh *fl_mesh_alloc(size_t nv, size_t nt) {
    if (nv > UINT32_MAX || nt > UINT32_MAX) return NULL;
    femlod_mesh *m = calloc(1, sizeof *m);
    if (!m) return NULL;
    m->pos = fl_alloc(nv, 3 * sizeof(double));
    m->tri = fl_alloc(nt, 3 * sizeof(uint32_t));
    if (!m->pos || !m->tri) {
        femlod_mesh_free(m);
        return NULL;
    }
    m->nv = nv;
    m->nt = nt;
    return m;
}

void femlod_mesh_free(femlod_mesh *mesh) {
    if (!mesh) return;
    free(mesh->pos);
    free(mesh->tri);
    free(mesh);
}

femlod_status femlod_mesh_create(femlod_mesh **out, const double *positions, size_t vertex_count,
                                 const uint32_t *triangles, size_t triangle_count,
                                 femlod_error *err) {
    assert(out);
    assert(positions || vertex_count == 0);
    assert(triangles || triangle_count == 0);
    if (vertex_count > UINT32_MAX || triangle_count > UINT32_MAX)
        return fl_error(err, FEMLOD_EINPUT, "mesh too large: %zu vertices, %zu triangles (limit %u)",
                        vertex_count, triangle_count, (unsigned)UINT32_MAX);
    for (size_t i = 0; i < 3 * vertex_count; i++)
        if (!isfinite(positions[i]))
            return fl_error(err, FEMLOD_EINPUT, "vertex %zu: coordinate %zu is not finite", i / 3,
                            i % 3);
    for (size_t i = 0; i < 3 * triangle_count; i++)
        if (triangles[i] >= vertex_count)
            return fl_error(err, FEMLOD_EINPUT,
                            "triangle %zu: vertex index %u out of range (%zu vertices)", i / 3,
                            triangles[i], vertex_count);
    femlod_mesh *m = fl_mesh_alloc(vertex_count, triangle_count);
    if (!m) return fl_error(err, FEMLOD_ENOMEM, "out of memory");
    if (vertex_count) memcpy(m->pos, positions, vertex_count * 3 * sizeof(double));
    if (triangle_count) memcpy(m->tri, triangles, triangle_count * 3 * sizeof(uint32_t));
    *out = m;
    return FEMLOD_OK;
}

femlod_status femlod_mesh_copy(femlod_mesh **out, const femlod_mesh *mesh, femlod_error *err) {
    assert(out && mesh);
    femlod_mesh *m = fl_mesh_alloc(mesh->nv, mesh->nt);
    if (!m) return fl_error(err, FEMLOD_ENOMEM, "out of memory");
    if (mesh->nv) memcpy(m->pos, mesh->pos, mesh->nv * 3 * sizeof(double));
    if (mesh->nt) memcpy(m->tri, mesh->tri, mesh->nt * 3 * sizeof(uint32_t));
    *out = m;
    return FEMLOD_OK;
}

size_t femlod_mesh_vertex_count(const femlod_mesh *mesh) {
    assert(mesh);
    return mesh->nv;
}

size_t femlod_mesh_triangle_count(const femlod_mesh *mesh) {
    assert(mesh);
    return mesh->nt;
}

const double *femlod_mesh_positions(const femlod_mesh *mesh) {
    assert(mesh);
    return mesh->pos;
}

const uint32_t *femlod_mesh_triangles(const femlod_mesh *mesh) {
    assert(mesh);
    return mesh->tri;
}

void femlod_mesh_bbox(const femlod_mesh *mesh, double min[3], double max[3]) {
    assert(mesh);
    for (int k = 0; k < 3; k++) min[k] = max[k] = 0.0;
    if (mesh->nv == 0) return;
    for (int k = 0; k < 3; k++) min[k] = max[k] = mesh->pos[k];
    for (size_t i = 1; i < mesh->nv; i++)
        for (int k = 0; k < 3; k++) {
            double x = mesh->pos[3 * i + (size_t)k];
            if (x < min[k]) min[k] = x;
            if (x > max[k]) max[k] = x;
        }
}

double femlod_mesh_area(const femlod_mesh *mesh) {
    assert(mesh);
    double sum = 0.0;
    for (size_t t = 0; t < mesh->nt; t++) {
        const double *a = mesh->pos + 3 * (size_t)mesh->tri[3 * t];
        const double *b = mesh->pos + 3 * (size_t)mesh->tri[3 * t + 1];
        const double *c = mesh->pos + 3 * (size_t)mesh->tri[3 * t + 2];
        double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
        double v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
        double n[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2],
                       u[0] * v[1] - u[1] * v[0]};
        sum += 0.5 * sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    }
    return sum;
}

/* {====== exact welding of a triangle soup */

/* Hash of a position's bits; -0.0 was turned into 0.0 by the caller so that
 * the two compare equal and hash equal. */
static uint64_t hash_position(const double p[3]) {
    uint64_t h = 0x9E3779B97F4A7C15ull;
    for (int k = 0; k < 3; k++) {
        uint64_t bits;
        memcpy(&bits, &p[k], sizeof bits);
        h ^= bits + 0x9E3779B97F4A7C15ull + (h << 6) + (h >> 2);
        h *= 0xFF51AFD7ED558CCDull;
        h ^= h >> 33;
    }
    return h;
}

femlod_status fl_mesh_from_soup(femlod_mesh **out, const double *corners, size_t nt,
                                femlod_error *err) {
    assert(out);
    size_t nc;
    if (nt > UINT32_MAX || __builtin_mul_overflow(nt, (size_t)3, &nc))
        return fl_error(err, FEMLOD_EINPUT, "too many triangles: %zu", nt);
    /* Open addressing with a power-of-two table at least twice the corner
     * count: the number of distinct positions is at most nc. */
    size_t cap = 16;
    while (cap < 2 * nc) cap *= 2;
    uint32_t *table = fl_alloc(cap, sizeof *table);
    double *pos = fl_alloc(nc, 3 * sizeof(double));
    femlod_mesh *m = fl_mesh_alloc(0, nt);
    if (!table || !pos || !m) {
        free(table);
        free(pos);
        femlod_mesh_free(m);
        return fl_error(err, FEMLOD_ENOMEM, "out of memory welding %zu triangles", nt);
    }
    memset(table, 0xFF, cap * sizeof *table);
    size_t nv = 0;
    for (size_t c = 0; c < nc; c++) {
        double p[3];
        for (int k = 0; k < 3; k++) {
            double x = corners[3 * c + (size_t)k];
            p[k] = x == 0.0 ? 0.0 : x; /* -0.0 == 0.0 */
        }
        size_t slot = (size_t)hash_position(p) & (cap - 1);
        uint32_t id;
        for (;;) {
            id = table[slot];
            if (id == UINT32_MAX) {
                id = (uint32_t)nv;
                table[slot] = id;
                memcpy(pos + 3 * nv, p, sizeof p);
                nv++;
                break;
            }
            const double *q = pos + 3 * (size_t)id;
            if (q[0] == p[0] && q[1] == p[1] && q[2] == p[2]) break;
            slot = (slot + 1) & (cap - 1);
        }
        m->tri[c] = id;
    }
    free(table);
    double *shrunk = realloc(pos, (nv ? nv : 1) * 3 * sizeof(double));
    free(m->pos);
    m->pos = shrunk ? shrunk : pos;
    m->nv = nv;
    *out = m;
    return FEMLOD_OK;
}

/* }====== */

/* {====== growable buffers for the readers */

static int grow(void **p, size_t *cap, size_t need, size_t elem) {
    if (need <= *cap) return 1;
    size_t n = *cap ? *cap : 64;
    while (n < need) {
        if (n > SIZE_MAX / 2) return 0;
        n *= 2;
    }
    void *q = fl_realloc(*p, n, elem);
    if (!q) return 0;
    *p = q;
    *cap = n;
    return 1;
}

int fl_meshbuf_reserve(fl_meshbuf *b, size_t nv, size_t nt) {
    void *p = b->pos, *t = b->tri;
    int ok = grow(&p, &b->cap_v, nv, 3 * sizeof(double));
    b->pos = p;
    ok = ok && grow(&t, &b->cap_t, nt, 3 * sizeof(uint32_t));
    b->tri = t;
    return ok;
}

int fl_meshbuf_add_vertex(fl_meshbuf *b, double x, double y, double z) {
    if (b->nv >= UINT32_MAX) return 0;
    if (b->nv == b->cap_v) {
        void *p = b->pos;
        if (!grow(&p, &b->cap_v, b->nv + 1, 3 * sizeof(double))) return 0;
        b->pos = p;
    }
    double *q = b->pos + 3 * b->nv++;
    q[0] = x;
    q[1] = y;
    q[2] = z;
    return 1;
}

int fl_meshbuf_add_triangle(fl_meshbuf *b, uint32_t a, uint32_t c, uint32_t d) {
    if (b->nt >= UINT32_MAX) return 0;
    if (b->nt == b->cap_t) {
        void *p = b->tri;
        if (!grow(&p, &b->cap_t, b->nt + 1, 3 * sizeof(uint32_t))) return 0;
        b->tri = p;
    }
    uint32_t *q = b->tri + 3 * b->nt++;
    q[0] = a;
    q[1] = c;
    q[2] = d;
    return 1;
}

/* Shrinks an array to n elements of size elem, keeping it when realloc fails
 * (the data stay valid); an empty array becomes a 1-byte block so that a
 * mesh's arrays are never NULL. */
static void *shrink(void *p, size_t n, size_t elem) {
    void *q = realloc(p, n ? n * elem : 1);
    return q ? q : p;
}

femlod_mesh *fl_meshbuf_finish(fl_meshbuf *b) {
    femlod_mesh *m = calloc(1, sizeof *m);
    if (!m) return NULL;
    /* Give back the slack of the doubling growth. */
    m->pos = shrink(b->pos, b->nv, 3 * sizeof(double));
    m->tri = shrink(b->tri, b->nt, 3 * sizeof(uint32_t));
    m->nv = b->nv;
    m->nt = b->nt;
    memset(b, 0, sizeof *b);
    if (!m->pos || !m->tri) {
        femlod_mesh_free(m);
        return NULL;
    }
    return m;
}

void fl_meshbuf_free(fl_meshbuf *b) {
    free(b->pos);
    free(b->tri);
    memset(b, 0, sizeof *b);
}

/* }====== */

/* {====== 1-to-4 subdivision (paper section 3) */

static femlod_status subdivide_once(femlod_mesh **out, const femlod_mesh *in, femlod_error *err) {
    fl_adjacency adj;
    femlod_status s = fl_adjacency_build(&adj, in->tri, in->nt, in->nv, err);
    if (s != FEMLOD_OK) return s;
    size_t nv = in->nv + adj.ne, nt = 4 * in->nt;
    femlod_mesh *m = (nv > UINT32_MAX || nt > UINT32_MAX) ? NULL : fl_mesh_alloc(nv, nt);
    if (!m) {
        fl_adjacency_free(&adj);
        if (nv > UINT32_MAX || nt > UINT32_MAX)
            return fl_error(err, FEMLOD_EINPUT, "subdivision would exceed %u vertices or triangles",
                            (unsigned)UINT32_MAX);
        return fl_error(err, FEMLOD_ENOMEM, "out of memory subdividing %zu triangles", in->nt);
    }
    if (in->nv) memcpy(m->pos, in->pos, in->nv * 3 * sizeof(double));
    for (size_t e = 0; e < adj.ne; e++) {
        const double *a = in->pos + 3 * (size_t)adj.edge_v[2 * e];
        const double *b = in->pos + 3 * (size_t)adj.edge_v[2 * e + 1];
        double *p = m->pos + 3 * (in->nv + e);
        /* halves first: no overflow near DBL_MAX, and the same value otherwise */
        for (int k = 0; k < 3; k++) p[k] = 0.5 * a[k] + 0.5 * b[k];
    }
    for (size_t t = 0; t < in->nt; t++) {
        const uint32_t *c = in->tri + 3 * t;
        uint32_t mid[3]; /* on sides (c0,c1), (c1,c2), (c2,c0) */
        for (int k = 0; k < 3; k++) {
            uint32_t e = adj.tri_edges[3 * t + (size_t)k];
            /* A degenerate side (a repeated vertex) has its vertex as midpoint. */
            mid[k] = e == UINT32_MAX ? c[k] : (uint32_t)(in->nv + e);
        }
        uint32_t *o = m->tri + 12 * t;
        const uint32_t kids[12] = {c[0],   mid[0], mid[2], mid[0], c[1],   mid[1],
                                   mid[2], mid[1], c[2],   mid[0], mid[1], mid[2]};
        memcpy(o, kids, sizeof kids);
    }
    fl_adjacency_free(&adj);
    *out = m;
    return FEMLOD_OK;
}

femlod_status femlod_mesh_subdivide(femlod_mesh **out, const femlod_mesh *mesh, unsigned levels,
                                    femlod_error *err) {
    assert(out && mesh);
    /* Refuse before allocating anything when the count cannot fit. */
    size_t nt = mesh->nt;
    for (unsigned l = 0; l < levels; l++) {
        if (nt > UINT32_MAX / 4)
            return fl_error(err, FEMLOD_EINPUT,
                            "subdividing %zu triangles %u times exceeds %u triangles", mesh->nt,
                            levels, (unsigned)UINT32_MAX);
        nt *= 4;
    }
    femlod_mesh *cur = NULL;
    femlod_status s = femlod_mesh_copy(&cur, mesh, err);
    for (unsigned l = 0; s == FEMLOD_OK && l < levels; l++) {
        femlod_mesh *next = NULL;
        s = subdivide_once(&next, cur, err);
        femlod_mesh_free(cur);
        cur = next;
    }
    if (s != FEMLOD_OK) return s;
    *out = cur;
    return FEMLOD_OK;
}

/* }====== */
