/*
 * hierarchy.h - the vertex hierarchy's storage, shared by hierarchy.c (the
 * operations) and hierarchy_io.c (the .flh file). Internal.
 */
#ifndef FEMLOD_HIERARCHY_H
#define FEMLOD_HIERARCHY_H

#include "core.h"

enum { ABOVE = 0, FRONT = 1, BELOW = 2 };

#define NONE UINT32_MAX

struct femlod_hierarchy {
    size_t nv;      /* leaves: input vertices */
    size_t nc;      /* collapses: internal nodes nv .. nv+nc-1 */
    size_t nn;      /* nodes */
    size_t nf_in;   /* input faces (degenerate input triangles excluded) */
    size_t nf;      /* every face that ever existed */
    double *pos;    /* 3*nn */
    double *e_size; /* nn */
    uint32_t *parent;      /* nn */
    uint32_t *child;       /* 2*nc */
    uint32_t *depth;       /* nn: ancestors above the node */
    uint32_t *vstar_start; /* nc+1 */
    uint32_t *vstars;
    uint32_t *dep_start;   /* nn+1: dependents, the reverse of vstars */
    uint32_t *deps;
    uint32_t *face_v;      /* 3*nf */
    uint32_t *removed_start; /* nc+1 */
    uint32_t *removed;       /* face ids removed by each collapse */
    uint32_t *created_start; /* nc+1: created faces of c are nf_in + created_start[c] .. */
    double *kappa;           /* nn or NULL: curvature (femlod_hierarchy_set_curvature) */
    int binding;             /* femlod_reject that stopped the coarsest collapses, or FEMLOD_REJECT_COUNT */
    int last_limit;          /* femlod_lod_limit of the last rescale */
    /* state */
    uint8_t *state;        /* nn */
    uint32_t *front;       /* front nodes, in no particular order */
    uint32_t *front_pos;   /* nn: index in front[] or NONE */
    size_t front_n;
    uint32_t *active;      /* active faces */
    uint32_t *active_pos;  /* nf */
    size_t active_n;
    /* scratch */
    uint32_t *stack;       /* nn */
    uint32_t *work;        /* worklist of refine/coarsen, nn + 2*nc */
    size_t work_n, work_cap;
    int collect;           /* push the children of every split / the parent of every collapse */
    uint32_t *stamp;       /* nn, for extraction: "seen in this epoch" */
    uint32_t *index;       /* nn, for extraction: vertex index of a used front node */
    uint32_t epoch;
};

/* Splits target (on the front, internal) after whatever depends on it, or
 * collapses target (above the front) after whatever it needs; they return
 * the number of primitive operations (docs/design.md). With h->collect set,
 * every split pushes its children and every collapse its parent on h->work. */
FL_INTERNAL size_t fl_hierarchy_force_split(femlod_hierarchy *h, uint32_t target);
FL_INTERNAL size_t fl_hierarchy_force_collapse(femlod_hierarchy *h, uint32_t target);
/* femlod_hierarchy_refine with a progress callback (options may be NULL):
 * done is the share of the starting front whose subtrees were walked; a
 * cancel fails with FEMLOD_ECANCELLED ("WHAT: cancelled by the progress
 * callback"), the front valid. */
FL_INTERNAL femlod_status fl_hierarchy_refine_progress(femlod_hierarchy *h, double size,
                                                       femlod_size_fn fn, void *payload,
                                                       const femlod_progress_options *options,
                                                       const char *what, size_t *ops,
                                                       femlod_error *err);

/* Sets the front to the given nodes (a cut, closed under vstars) and
 * rebuilds the active faces; FEMLOD_EPARSE with a message when the nodes do
 * not form a valid front (the state is then the simplification's result). */
FL_INTERNAL femlod_status fl_hierarchy_set_front(femlod_hierarchy *h, const uint32_t *nodes,
                                                 size_t count, femlod_error *err);

#endif
