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

/* femlod_improve without splits: every change it makes raises the least
 * stretch of the faces it touches, so the mesh's least stretch never falls
 * (the polish's fallback, docs/design.md "What remains, and why"). */
FL_INTERNAL femlod_status fl_improve_no_split(femlod_mesh **out, const femlod_mesh *mesh,
                                              const femlod_improve_options *options, femlod_improve_report *report,
                                              femlod_error *err);

#endif
