/* shapes.h - generated meshes for unit tests (after PMP's algorithms/shapes.h). */
#ifndef FEMLOD_SHAPES_H
#define FEMLOD_SHAPES_H

#include "femlod.h"

/* Regular icosahedron on the unit sphere, subdivided `levels` times with the
 * new vertices pushed to the sphere: 20*4^levels triangles, closed, outward. */
femlod_mesh *shape_icosphere(unsigned levels);
/* Unit square [0,1]^2 at z = 0 split into n x n cells of two triangles, normals +z. */
femlod_mesh *shape_plane(unsigned n);
/* Open cylinder of radius 1, height h, with `around` x `up` quads, two triangles each. */
femlod_mesh *shape_cylinder(unsigned around, unsigned up, double h);
/* Regular tetrahedron, closed and outward. */
femlod_mesh *shape_tetrahedron(void);
/* Three triangles sharing edge (0,1): one non-manifold edge. */
femlod_mesh *shape_nonmanifold_fan(void);
/* Two triangles touching at one vertex (a bow tie): a non-manifold vertex. */
femlod_mesh *shape_bowtie(void);

/* 1 when a and b hold identical arrays (bit for bit); 0 when either is NULL. */
int shape_same_mesh(const femlod_mesh *a, const femlod_mesh *b);

#endif
