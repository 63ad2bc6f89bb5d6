/* meshcheck.h - whole-mesh checks for tests: self-intersecting triangle
 * pairs (brute force over a uniform grid of triangle boxes; the pair test is
 * src/intersect.c's: shared corners and edges are not intersections), and
 * two meshes' triangles compared up to vertex numbering. */
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

/* Reads DIR/NAME; on failure prints the reader's message and returns NULL. */
femlod_mesh *meshcheck_load(const char *dir, const char *name);

#endif
