/*
 * simplify_log.h - the collapse log's storage (internal; public accessors in
 * femlod.h, invariants in docs/simplify.md "Collapse log").
 */
#ifndef FEMLOD_SIMPLIFY_LOG_H
#define FEMLOD_SIMPLIFY_LOG_H

#include "core.h"

struct femlod_collapse_log {
    size_t nv_in;        /* input vertices: node ids 0..nv_in-1 */
    size_t n, cap;       /* collapses; collapse c made node nv_in + c */
    size_t prephase;     /* the first `prephase` collapses were the stretch pre-phase */
    size_t front;        /* the first `front` collapses made the output mesh (SIZE_MAX: all) */
    int binding;         /* femlod_reject that stopped the last collapses; FEMLOD_REJECT_COUNT: none */
    uint32_t *pair;      /* 2n */
    double *pos;         /* 3n */
    double *e_size;      /* n */
    uint32_t *vstar_start; /* n+1 */
    uint32_t *vstars;    /* vstar_start[n], increasing node id per collapse */
    size_t cap_vstars;
    uint32_t *face_start; /* n+1, in faces (3 refs each) */
    uint8_t *faces;      /* 3 * face_start[n] local refs */
    size_t cap_faces;
    uint32_t *out_nodes; /* node id of each output vertex */
    femlod_mesh *base;   /* the improved input the node ids 0..nv_in-1 are of; NULL: the input */
    size_t nv_out;
};

FL_INTERNAL femlod_collapse_log *fl_log_new(size_t nv_in, size_t expected);
/* Appends a collapse; 0 on ENOMEM. faces: nfaces triples of local refs. */
FL_INTERNAL int fl_log_add(femlod_collapse_log *log, uint32_t i, uint32_t j, const double pos[3],
                           double e_size, const uint32_t *vstars, size_t nvstars, const uint8_t *faces,
                           size_t nfaces);

/* Appends every collapse of src to dst, node ids >= from raised by shift
 * (a fast-pass worker's provisional ids, simplify/fast.c). 0 on ENOMEM. */
FL_INTERNAL int fl_log_merge(femlod_collapse_log *dst, const femlod_collapse_log *src, uint32_t from,
                             uint32_t shift);
/* Empties a log, keeping its memory. */
FL_INTERNAL void fl_log_clear(femlod_collapse_log *log);

#endif
