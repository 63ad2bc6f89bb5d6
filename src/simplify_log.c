/*
 * simplify_log.c - the collapse log: what every edge collapse of femlod_simplify
 * did, in the vertex numbering of a binary vertex hierarchy (paper section
 * 4.2 "storing the collapsed edge and neighbour information", 5.1 vstars and
 * e_size; Hoppe, "Progressive meshes", SIGGRAPH 1996, for the idea of
 * recording each collapse so that it can be undone as a vertex split).
 *
 * Stored as flat CSR arrays, about 100 bytes per collapse: the faces a
 * collapse removed are one byte per corner, indices into the collapse's
 * own (i, j, vstars) list rather than 32-bit node ids.
 */
#include "simplify_log.h"

#include <stdlib.h>
#include <string.h>

femlod_collapse_log *fl_log_new(size_t nv_in, size_t expected) {
    femlod_collapse_log *log = calloc(1, sizeof *log);
    if (!log) return NULL;
    log->nv_in = nv_in;
    log->front = SIZE_MAX;
    log->binding = FEMLOD_REJECT_COUNT;
    log->cap = expected < 16 ? 16 : expected;
    log->cap_vstars = log->cap * 8;
    log->cap_faces = log->cap * 10;
    log->pair = fl_alloc(2 * log->cap, sizeof *log->pair);
    log->pos = fl_alloc(3 * log->cap, sizeof *log->pos);
    log->e_size = fl_alloc(log->cap, sizeof *log->e_size);
    log->vstar_start = fl_alloc(log->cap + 1, sizeof *log->vstar_start);
    log->face_start = fl_alloc(log->cap + 1, sizeof *log->face_start);
    log->vstars = fl_alloc(log->cap_vstars, sizeof *log->vstars);
    log->faces = fl_alloc(3 * log->cap_faces, sizeof *log->faces);
    if (!log->pair || !log->pos || !log->e_size || !log->vstar_start || !log->face_start ||
        !log->vstars || !log->faces) {
        femlod_collapse_log_free(log);
        return NULL;
    }
    log->vstar_start[0] = 0;
    log->face_start[0] = 0;
    return log;
}

static int grow(void **p, size_t *cap, size_t need, size_t elem) {
    if (need <= *cap) return 1;
    size_t c = *cap * 2;
    if (c < need) c = need;
    void *q = fl_realloc(*p, c, elem);
    if (!q) return 0;
    *p = q;
    *cap = c;
    return 1;
}

/* Room for n more collapses in the per-collapse arrays (doubling). */
static int reserve_collapses(femlod_collapse_log *log, size_t n) {
    if (log->n + n <= log->cap) return 1;
    size_t c = log->cap * 2;
    if (c < log->n + n) c = log->n + n;
    uint32_t *pair = fl_realloc(log->pair, 2 * c, sizeof *pair);
    if (!pair) return 0;
    log->pair = pair;
    double *p = fl_realloc(log->pos, 3 * c, sizeof *p);
    if (!p) return 0;
    log->pos = p;
    double *es = fl_realloc(log->e_size, c, sizeof *es);
    if (!es) return 0;
    log->e_size = es;
    uint32_t *vs = fl_realloc(log->vstar_start, c + 1, sizeof *vs);
    if (!vs) return 0;
    log->vstar_start = vs;
    uint32_t *fs = fl_realloc(log->face_start, c + 1, sizeof *fs);
    if (!fs) return 0;
    log->face_start = fs;
    log->cap = c;
    return 1;
}

/* Room for n more collapses with nvstars vstars and nfaces faces in all;
 * 0 on ENOMEM or when the offsets would pass 32 bits. */
static int reserve(femlod_collapse_log *log, size_t n, size_t nvstars, size_t nfaces) {
    size_t v0 = log->vstar_start[log->n], f0 = log->face_start[log->n];
    if (v0 + nvstars > UINT32_MAX || f0 + nfaces > UINT32_MAX) return 0;
    if (!reserve_collapses(log, n)) return 0;
    void *vp = log->vstars, *fp = log->faces;
    size_t fcap3 = 3 * log->cap_faces;
    if (!grow(&vp, &log->cap_vstars, v0 + nvstars, sizeof *log->vstars)) return 0;
    log->vstars = vp;
    if (!grow(&fp, &fcap3, 3 * (f0 + nfaces), 1)) return 0;
    log->faces = fp;
    log->cap_faces = fcap3 / 3;
    return 1;
}

int fl_log_add(femlod_collapse_log *log, uint32_t i, uint32_t j, const double pos[3], double e_size,
               const uint32_t *vstars, size_t nvstars, const uint8_t *faces, size_t nfaces) {
    if (!reserve(log, 1, nvstars, nfaces)) return 0;
    size_t v0 = log->vstar_start[log->n], f0 = log->face_start[log->n];
    size_t c = log->n;
    log->pair[2 * c] = i;
    log->pair[2 * c + 1] = j;
    memcpy(log->pos + 3 * c, pos, 3 * sizeof *pos);
    log->e_size[c] = e_size;
    memcpy(log->vstars + v0, vstars, nvstars * sizeof *vstars);
    memcpy(log->faces + 3 * f0, faces, 3 * nfaces);
    log->vstar_start[c + 1] = (uint32_t)(v0 + nvstars);
    log->face_start[c + 1] = (uint32_t)(f0 + nfaces);
    log->n++;
    return 1;
}

/* The records of src appended in one piece: the same bytes as adding them
 * one by one with their node ids >= from raised by shift, without a call
 * and a capacity check per record (the fast passes merge a log per task). */
int fl_log_merge(femlod_collapse_log *dst, const femlod_collapse_log *src, uint32_t from, uint32_t shift) {
    size_t n = src->n, d = dst->n;
    if (n == 0) return 1;
    size_t nvs = src->vstar_start[n] - src->vstar_start[0], nf = src->face_start[n] - src->face_start[0];
    if (!reserve(dst, n, nvs, nf)) return 0;
    size_t v0 = dst->vstar_start[d], f0 = dst->face_start[d];
    for (size_t k = 0; k < 2 * n; k++) {
        uint32_t id = src->pair[k];
        dst->pair[2 * d + k] = id >= from ? id + shift : id;
    }
    memcpy(dst->pos + 3 * d, src->pos, 3 * n * sizeof *src->pos);
    memcpy(dst->e_size + d, src->e_size, n * sizeof *src->e_size);
    const uint32_t *sv = src->vstars + src->vstar_start[0];
    for (size_t k = 0; k < nvs; k++) {
        uint32_t id = sv[k];
        dst->vstars[v0 + k] = id >= from ? id + shift : id;
    }
    memcpy(dst->faces + 3 * f0, src->faces + 3 * (size_t)src->face_start[0], 3 * nf);
    for (size_t c = 1; c <= n; c++) {
        dst->vstar_start[d + c] = (uint32_t)(v0 + src->vstar_start[c] - src->vstar_start[0]);
        dst->face_start[d + c] = (uint32_t)(f0 + src->face_start[c] - src->face_start[0]);
    }
    dst->n = d + n;
    return 1;
}

void fl_log_clear(femlod_collapse_log *log) { log->n = 0; }

void femlod_collapse_log_free(femlod_collapse_log *log) {
    if (!log) return;
    free(log->pair);
    free(log->pos);
    free(log->e_size);
    free(log->vstar_start);
    free(log->vstars);
    free(log->face_start);
    free(log->faces);
    free(log->out_nodes);
    femlod_mesh_free(log->base);
    free(log);
}

size_t femlod_collapse_log_count(const femlod_collapse_log *log) { return log->n; }

size_t femlod_collapse_log_input_vertices(const femlod_collapse_log *log) { return log->nv_in; }

const femlod_mesh *femlod_collapse_log_base(const femlod_collapse_log *log) { return log->base; }

size_t femlod_collapse_log_prephase(const femlod_collapse_log *log) { return log->prephase; }
size_t femlod_collapse_log_front(const femlod_collapse_log *log) {
    return log->front < log->n ? log->front : log->n;
}

void femlod_collapse_log_get(const femlod_collapse_log *log, size_t c, femlod_collapse *out) {
    out->i = log->pair[2 * c];
    out->j = log->pair[2 * c + 1];
    out->k = (uint32_t)(log->nv_in + c);
    memcpy(out->position, log->pos + 3 * c, sizeof out->position);
    out->e_size = log->e_size[c];
    out->vstars = log->vstars + log->vstar_start[c];
    out->vstar_count = log->vstar_start[c + 1] - log->vstar_start[c];
    out->faces = log->faces + 3 * (size_t)log->face_start[c];
    out->face_count = log->face_start[c + 1] - log->face_start[c];
}

uint32_t femlod_collapse_node(const femlod_collapse *c, uint8_t ref) {
    if (ref == 0) return c->i;
    if (ref == 1) return c->j;
    return c->vstars[ref - 2];
}

const uint32_t *femlod_collapse_log_output_nodes(const femlod_collapse_log *log, size_t *count) {
    if (count) *count = log->nv_out;
    return log->out_nodes;
}

size_t femlod_collapse_log_bytes(const femlod_collapse_log *log) {
    return sizeof *log + log->n * (2 * sizeof(uint32_t) + 4 * sizeof(double) + 2 * sizeof(uint32_t)) +
           log->vstar_start[log->n] * sizeof(uint32_t) + 3 * (size_t)log->face_start[log->n] +
           log->nv_out * sizeof(uint32_t);
}
