/*
 * improve.h - what the simplifier calls of the improvement stage
 * (src/improve/, docs/design.md "Improving a mesh in place"): femlod_improve
 * with the map of the input's vertices to the output's.
 */
#ifndef FEMLOD_IMPROVE_H
#define FEMLOD_IMPROVE_H

#include "core.h"

/* femlod_improve; vmap (NULL: none), input vertex count entries, gets each
 * input vertex's index in *out, UINT32_MAX for those the stage removed. */
FL_INTERNAL femlod_status fl_improve_mapped(femlod_mesh **out, const femlod_mesh *mesh,
                                            const femlod_improve_options *options,
                                            femlod_improve_report *report, uint32_t *vmap, femlod_error *err);

/* femlod_improve with every change under the floor rule: no face it makes
 * has a stretch below min(min_stretch, the least of the faces the change
 * removes), so the mesh's least stretch never falls below min(min_stretch,
 * its input's) (the polish, docs/design.md "The floor rule, compound changes
 * and bands"). */
FL_INTERNAL femlod_status fl_improve_strict(femlod_mesh **out, const femlod_mesh *mesh,
                                            const femlod_improve_options *options, femlod_improve_report *report,
                                            femlod_error *err);

#endif
