/* meshcheck.h - whole-mesh checks for tests: self-intersecting triangle
 * pairs (brute force over a uniform grid of triangle boxes; the pair test is
 * src/intersect.c's: shared corners and edges are not intersections), and
 * two meshes' triangles compared up to vertex numbering, and a
 * simplification's independence of its thread count. */
#ifndef FEMLOD_MESHCHECK_H
#define FEMLOD_MESHCHECK_H

#include "femlod.h"

/* Pairs of triangles that meet other than in shared corners or a shared
 * edge; eps is the plane tolerance of fl_tri_tri_intersect. */
size_t meshcheck_self_intersections(const femlod_mesh *m, double eps);

/* When set, called with every intersecting pair (triangle indices f < g). */
extern void (*meshcheck_on_pair)(const femlod_mesh *m, size_t f, size_t g, void *payload);
extern void *meshcheck_pair_payload;

/* 1 when a and b have the same triangles by corner positions, in any order
 * and rotation (orientation kept); triangles with a repeated corner are left
 * out, as the hierarchy drops them. */
int meshcheck_same_triangles(const femlod_mesh *a, const femlod_mesh *b);

/* Simplifies m with o on 1 and on 2 threads, in the exact order (fast_above
 * off) and with fast passes (fast_above 2): 1 when both thread counts give
 * identical arrays in both, 0 when they differ or a run fails. */
int meshcheck_same_for_threads(const femlod_mesh *m, const femlod_simplify_options *o);

/* Reads DIR/NAME; on failure prints the reader's message and returns NULL. */
femlod_mesh *meshcheck_load(const char *dir, const char *name);

#endif
