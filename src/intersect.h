/*
 * intersect.h - triangle-triangle intersection with shared corners, point to
 * triangle distance, and the uniform grid the simplifier keeps its triangles
 * in (internal; see intersect.c and docs/simplify.md "Intersection test").
 */
#ifndef FEMLOD_INTERSECT_H
#define FEMLOD_INTERSECT_H

#include "core.h"

/* 1 when triangles P and Q (corner positions P[c], Q[c] and vertex ids
 * pid[c], qid[c]) meet anywhere other than in the corners and the edge they
 * share (by id). Points closer than eps to a plane count as on it, and
 * touching counts as meeting, so the answer errs towards "intersects".
 * Triangles sharing all three ids are reported as intersecting. */
FL_INTERNAL int fl_tri_tri_intersect(const double *const P[3], const uint32_t pid[3],
                                     const double *const Q[3], const uint32_t qid[3], double eps);

/* The unnormalised normal (T1 - T0) x (T2 - T0) and its length. */
typedef struct fl_tri_plane {
    double n[3], len;
} fl_tri_plane;
FL_INTERNAL void fl_tri_plane_of(const double *const T[3], fl_tri_plane *pl);
/* fl_tri_tri_intersect with P's plane given (fl_tri_plane_of(P)): the same
 * answer, for testing one triangle against many. */
FL_INTERNAL int fl_tri_tri_intersect_p(const double *const P[3], const uint32_t pid[3],
                                       const fl_tri_plane *pp, const double *const Q[3],
                                       const uint32_t qid[3], double eps);

/* Squared distance from p to triangle (a, b, c) (Ericson, Real-Time
 * Collision Detection, 5.1.5). */
FL_INTERNAL double fl_point_tri_dist2(const double p[3], const double a[3], const double b[3],
                                      const double c[3]);

/* {====== uniform grid of items (triangle slots) by bounding box.
 * An item is listed in every cell its box overlaps; cells outside the grid's
 * box clamp to the border cells, identically for insert, remove and query,
 * so a point that leaves the original box stays findable. Cell lists are
 * chains of fixed blocks from one pool: no allocation per cell. */

#define FL_GRID_BLOCK 12

/* One cache line (the pool is 64-byte aligned). first[s] tells, by bits
 * 1, 2, 4 for x, y, z, whether this cell is the first cell of item[s]'s box
 * along that axis: a query over cells [c0, c1] meets an item once, in the
 * cell where every axis has its bit set or is the query's first
 * coordinate, without reading the item's box (FL_GRID_NEED). */
typedef struct fl_grid_block {
    uint32_t item[FL_GRID_BLOCK];
    uint8_t first[FL_GRID_BLOCK];
    uint32_t next;
} fl_grid_block;

/* The bits an item's first[] must hold to be met in cell (x, y, z) of a
 * query starting at c0: an item is met there when (first & need) == need. */
#define FL_GRID_NEED(x, y, z, c0) \
    ((uint8_t)(((x) != (c0)[0]) | (((y) != (c0)[1]) << 1) | (((z) != (c0)[2]) << 2)))

typedef struct fl_grid_cell_info {
    uint32_t head;  /* first block (the partly filled one), UINT32_MAX if none */
    uint32_t count; /* items */
} fl_grid_cell_info;

typedef struct fl_grid {
    double origin[3], inv_h, h;
    int n[3];
    fl_grid_cell_info *cell; /* per cell; head and count together: one cache line per cell visited */
    fl_grid_block *blocks; /* in blocks_mem, aligned to 64 bytes */
    void *blocks_mem;
    size_t nblocks, capblocks;
    size_t mapped; /* blocks below this index are mapped (new_block) */
    uint32_t free_block;
    size_t nfree;  /* blocks on the free list */
    int fixed;     /* 1: the free list only, never a new block (a worker's view, simplify/fast.c) */
} fl_grid;

/* Grid over [lo, hi] with cells of about edge h, enlarged so that there are
 * at most max_cells cells. 0 on ENOMEM. */
FL_INTERNAL int fl_grid_init(fl_grid *g, const double lo[3], const double hi[3], double h,
                             size_t max_cells);
FL_INTERNAL void fl_grid_free(fl_grid *g);
/* 0 on ENOMEM. */
FL_INTERNAL int fl_grid_insert(fl_grid *g, uint32_t item, const double lo[3], const double hi[3]);
/* The box must be the one the item was inserted with. */
FL_INTERNAL void fl_grid_remove(fl_grid *g, uint32_t item, const double lo[3], const double hi[3]);
/* The item's box changes from the old (the one it was inserted with) to
 * the new: the same entries as removing and inserting it (in another order
 * within a cell), touching only the cells that change when its first cell
 * stays. 0 on ENOMEM (the item may then be missing from cells of the new
 * box). */
FL_INTERNAL int fl_grid_move(fl_grid *g, uint32_t item, const double olo[3], const double ohi[3],
                             const double nlo[3], const double nhi[3]);
/* Puts n free blocks, from the free list, then new ones, at the head of
 * the chain *head (linked by next, UINT32_MAX-terminated): a fast-pass
 * worker's own pool (simplify/fast.c). 0 on ENOMEM (the chain then holds what
 * could be taken). */
FL_INTERNAL int fl_grid_take(fl_grid *g, size_t n, uint32_t *head);
/* Cell index range [c0, c1] (inclusive) covering a box. */
FL_INTERNAL void fl_grid_range(const fl_grid *g, const double lo[3], const double hi[3], int c0[3],
                               int c1[3]);

/* The cell coordinate of x along axis k, clamped to the grid (NaN: 0). */
static inline int fl_grid_coord(const fl_grid *g, double x, int k) {
    double c = (x - g->origin[k]) * g->inv_h;
    if (!(c > 0.0)) return 0; /* also NaN */
    if (c >= (double)(g->n[k] - 1)) return g->n[k] - 1;
    return (int)c;
}

static inline size_t fl_grid_cell(const fl_grid *g, int x, int y, int z) {
    return ((size_t)z * (size_t)g->n[1] + (size_t)y) * (size_t)g->n[0] + (size_t)x;
}

/* }====== */

#endif
