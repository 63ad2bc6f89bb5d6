/* digest.h - 64-bit FNV-1a digests of a simplification's output mesh and
 * collapse log, for checks that results stay byte-identical
 * (tests/bench/simplify_digest.c, tests/c/scan_digest.c). */
#ifndef FEMLOD_TEST_DIGEST_H
#define FEMLOD_TEST_DIGEST_H

#include "femlod.h"

#include <stddef.h>
#include <stdint.h>

static inline uint64_t digest_fnv(uint64_t h, const void *p, size_t n) {
    const unsigned char *c = p;
    for (size_t i = 0; i < n; i++) {
        h ^= c[i];
        h *= 1099511628211ull;
    }
    return h;
}

/* Positions, then triangles. */
static inline uint64_t digest_mesh(const femlod_mesh *m) {
    uint64_t h = 1469598103934665603ull;
    h = digest_fnv(h, femlod_mesh_positions(m), 3 * femlod_mesh_vertex_count(m) * sizeof(double));
    return digest_fnv(h, femlod_mesh_triangles(m), 3 * femlod_mesh_triangle_count(m) * sizeof(uint32_t));
}

/* Every field of every collapse, then the output nodes. */
static inline uint64_t digest_log(const femlod_collapse_log *log) {
    uint64_t h = 1469598103934665603ull;
    size_t nc = femlod_collapse_log_count(log);
    for (size_t x = 0; x < nc; x++) {
        femlod_collapse cl;
        femlod_collapse_log_get(log, x, &cl);
        h = digest_fnv(h, &cl.i, sizeof cl.i);
        h = digest_fnv(h, &cl.j, sizeof cl.j);
        h = digest_fnv(h, &cl.k, sizeof cl.k);
        h = digest_fnv(h, cl.position, sizeof cl.position);
        h = digest_fnv(h, &cl.e_size, sizeof cl.e_size);
        h = digest_fnv(h, cl.vstars, cl.vstar_count * sizeof *cl.vstars);
        h = digest_fnv(h, cl.faces, 3 * cl.face_count);
    }
    size_t nout = 0;
    const uint32_t *on = femlod_collapse_log_output_nodes(log, &nout);
    return digest_fnv(h, on, nout * sizeof *on);
}

#endif
