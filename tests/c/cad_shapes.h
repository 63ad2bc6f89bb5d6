/* cad_shapes.h - CAD-style tessellations for the improvement stage's tests:
 * fans from a rim to a centre, long strips along fillets, needles from
 * T-joins, a thin plate, a plate with many holes. */
#ifndef FEMLOD_CAD_SHAPES_H
#define FEMLOD_CAD_SHAPES_H

#include "femlod.h"

/* Closed cylinder of radius 1 and height h: one strip of 2 n triangles round
 * the side, each cap a fan of n triangles from its centre. */
femlod_mesh *cad_cylinder_fans(unsigned n, double h);
/* Closed cone of radius 1 and height h: n triangles from the apex to the
 * rim, the base a fan of n from its centre. */
femlod_mesh *cad_cone_fans(unsigned n, double h);
/* Closed L-shaped bracket of width w with a filleted bend: a profile of two
 * legs and a quarter-circle fillet of `arc` segments, extruded with one
 * strip of two triangles per profile segment; the ends fanned. */
femlod_mesh *cad_bracket(unsigned arc, double w);
/* Open unit square: n x 1 quads along the bottom half, the top half two
 * fans from its top corners down to the n + 1 points of the join. */
femlod_mesh *cad_tjoin(unsigned n);
/* Closed box side x side x thick: top and bottom n x n grids, each side a
 * strip of 2 n triangles. */
femlod_mesh *cad_thin_plate(unsigned n, double side, double thick);
/* Open unit square plate of n x n cells with every other cell (both
 * indices odd) a square hole; the cells between holes as long strips. */
femlod_mesh *cad_holes(unsigned n);

#endif
