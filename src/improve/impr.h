/*
 * impr.h - what the files of the improvement stage share (internal to
 * src/improve/; docs/design.md "Improving a mesh in place"):
 *
 *   improve.c   femlod_improve: options, rounds, census, output
 *   ops.c       flip, split, collapse, relaxation: a change built aside,
 *               checked, then written; transactions (judge, undo)
 *   samples.c   the input samples of the backward bound, held by faces
 *   imesh.c     the working mesh: faces, vertex face lists, feature edges,
 *               vertex classes, the face grid
 *   surface.c   the input surface: nearest point and distance
 *
 * Each file calls only those below it in this list. Every loop runs in index
 * order, so the result depends on the input and options only.
 */
#ifndef FEMLOD_IMPR_H
#define FEMLOD_IMPR_H

#include "../core.h"
#include "../intersect.h"
#include "../vec3.h"

#include <math.h>
#include <stddef.h>
#include <stdint.h>

#define IM_DEAD UINT32_MAX

/* The longest chain of splits: a split's vertex has depth 1 + the larger
 * depth of the edge's ends (the input's have 0), and no split makes a
 * vertex deeper than this. Halving the pieces of a piece stops after this
 * many cuts (a needle halved this often keeps 1/4096 of its aspect), so a
 * region the operators cannot settle (a fix and its undoing, round after
 * round) grows by a bounded amount, not without end. */
#define IM_MAX_DEPTH 12

/* vertex classes */
enum { IM_FREE = 0, IM_LINE = 1, IM_FIXED = 2 };

/* A grid of items by bounding box, entries only appended: a query meets
 * every item whose box was inserted into an overlapping cell, including
 * stale entries, which the caller filters by the item's current box. A box
 * goes to the finest of the grid's levels where it covers few cells; one
 * too big for them all goes to a list that every query meets. */
#define IM_LEVELS 4
typedef struct im_level {
    double inv_h;
    int n[3];
    uint32_t *head; /* per cell: first entry, IM_DEAD if none */
} im_level;
typedef struct im_grid {
    double origin[3];
    im_level lv[IM_LEVELS]; /* cells 8 times wider at each level: a box goes to the first
                               where it covers few cells */
    uint32_t *item, *next;
    uint32_t *cell; /* per entry: its level (top 2 bits) and cell, for a rollback */
    size_t ne, cape;
    uint32_t *big;
    size_t nbig, capbig;
    unsigned gen; /* rebuilds so far: a rollback's mark holds within one */
} im_grid;

FL_INTERNAL int fl_imgrid_init(im_grid *g, const double lo[3], const double hi[3], double h,
                               size_t max_cells);
FL_INTERNAL void fl_imgrid_free(im_grid *g);
FL_INTERNAL int fl_imgrid_insert(im_grid *g, uint32_t item, const double lo[3], const double hi[3]);
/* Calls fn(payload, item) for each entry overlapping the box (an item may
 * come more than once); stops early when fn returns nonzero, returning it. */
/* Removes every entry appended since the grid held ne entries and nbig big
 * ones (each list is last in, first out), in the same generation. */
FL_INTERNAL void fl_imgrid_rollback(im_grid *g, size_t ne, size_t nbig);
FL_INTERNAL int fl_imgrid_query(const im_grid *g, const double lo[3], const double hi[3],
                                int (*fn)(void *payload, uint32_t item), void *payload);

/* The input surface (surface.c). */
typedef struct im_surface {
    const double *pos;
    const uint32_t *tri;
    size_t nt;
    im_grid grid;
    uint32_t *mark;
    uint32_t stamp;
    double diag;
} im_surface;

FL_INTERNAL int fl_imsurf_init(im_surface *s, const femlod_mesh *m, double h);
FL_INTERNAL void fl_imsurf_free(im_surface *s);
/* 1 when some input triangle lies within r of p. */
FL_INTERNAL int fl_imsurf_within(im_surface *s, const double p[3], double r);
/* The nearest point of the input surface to p into q; its distance. */
FL_INTERNAL double fl_imsurf_nearest(im_surface *s, const double p[3], double r0, double q[3]);

/* A vertex's face list. */
typedef struct im_list {
    uint32_t *f;
    uint32_t n, cap;
} im_list;

/* The working mesh (imesh.c). */
typedef struct imesh {
    size_t nv, capv, nv0; /* nv0: the input's vertices */
    double *pos;
    uint32_t *vorig; /* per vertex from nv0 on: the ends of the edge its split cut */
    uint8_t *vdepth; /* per vertex: 0 for the input's, 1 + the larger of the split edge's ends' */
    uint8_t *vclass;
    im_list *vf;
    uint32_t *vmark;
    size_t nt, capt, live;
    uint32_t *tri;    /* 3 per face; tri[3f] == IM_DEAD: removed */
    uint8_t *freason; /* per face: the last refusal of a change that would remove it (+1; 0: none) */
    uint32_t *fmark;
    uint32_t stamp;
    /* feature edges: open addressing on (min << 32 | max); 0 empty, 1 removed */
    uint64_t *fe;
    size_t fecap, fecount, feused;
    im_grid grid; /* faces by box */
    size_t grid_ne0; /* its entries when last built from the live faces */
    double eps;
} imesh;

FL_INTERNAL int fl_imesh_init(imesh *M, const femlod_mesh *m, double feature_angle,
                              const uint8_t *locked, double h);
FL_INTERNAL void fl_imesh_free(imesh *M);
FL_INTERNAL uint32_t fl_imesh_next_stamp(imesh *M);
FL_INTERNAL int fl_imesh_is_feature(const imesh *M, uint32_t a, uint32_t b);
FL_INTERNAL int fl_imesh_set_feature(imesh *M, uint32_t a, uint32_t b, int on);
/* Faces with both a and b into out (at most max); the count (may exceed max). */
FL_INTERNAL size_t fl_imesh_edge_faces(const imesh *M, uint32_t a, uint32_t b, uint32_t *out, size_t max);
FL_INTERNAL int fl_imesh_has_edge(const imesh *M, uint32_t a, uint32_t b);
FL_INTERNAL uint32_t fl_imesh_valence(imesh *M, uint32_t v);
/* the neighbours of v across a feature edge */
FL_INTERNAL uint32_t fl_imesh_feature_valence(imesh *M, uint32_t v);
/* Appends a face (lists, grid); its slot, or IM_DEAD on ENOMEM. */
FL_INTERNAL uint32_t fl_imesh_add_face(imesh *M, uint32_t a, uint32_t b, uint32_t c);
FL_INTERNAL void fl_imesh_remove_face(imesh *M, uint32_t f);
/* Puts a removed face back in its slot f (lists in slot order; the grid
 * when into_grid, else its old entries must still be there); 0 on ENOMEM. */
FL_INTERNAL int fl_imesh_restore_face(imesh *M, uint32_t f, const uint32_t t[3], int into_grid);
/* A new vertex; its index, or IM_DEAD on ENOMEM. */
FL_INTERNAL uint32_t fl_imesh_add_vertex(imesh *M, const double p[3], uint8_t cls);

static inline const double *im_P(const imesh *M, uint32_t v) { return M->pos + 3 * (size_t)v; }

static inline double im_stretch(const double *a, const double *b, const double *c) {
    double la = sqrt(dist2(b, c)), lb = sqrt(dist2(a, c)), lc = sqrt(dist2(a, b));
    double L = fmax(la, fmax(lb, lc));
    double s = 0.5 * (la + lb + lc);
    if (!(L > 0.0) || !(s > 0.0)) return 0.0;
    double r2 = (s - la) * (s - lb) * (s - lc) / s;
    if (!(r2 > 0.0)) return 0.0;
    return sqrt(12.0 * r2) / L;
}

static inline double im_face_stretch(const imesh *M, uint32_t f) {
    const uint32_t *t = M->tri + 3 * (size_t)f;
    return im_stretch(im_P(M, t[0]), im_P(M, t[1]), im_P(M, t[2]));
}

static inline void im_normal(double n[3], const double *a, const double *b, const double *c) {
    double e1[3], e2[3];
    sub3(e1, b, a);
    sub3(e2, c, a);
    cross3(n, e1, e2);
}

static inline void im_box(const double *a, const double *b, const double *c, double lo[3], double hi[3]) {
    for (int k = 0; k < 3; k++) {
        lo[k] = fmin(a[k], fmin(b[k], c[k]));
        hi[k] = fmax(a[k], fmax(b[k], c[k]));
    }
}

/* {====== ops.c */

/* The input samples of the backward bound (samples.c): each held by one
 * live face, within the bound of it. */
typedef struct im_samples {
    double *pt;      /* 3 per sample */
    uint32_t *next;  /* per sample: the next one of its face's list, IM_DEAD: none */
    size_t n, cap;
    uint32_t *head;  /* per face slot: its first sample, IM_DEAD: none */
    size_t caph;
    /* the change checked last: the samples it moves, the face each is held
     * by, and to which added face (index in the change) it goes */
    uint32_t *pend, *pend_from, *pend_to;
    size_t npend, cappend;
    /* in a transaction: the samples moved off the faces that existed when
     * it began, and those faces (an undo puts them back) */
    int tx_on;
    size_t tx_nt0;
    uint32_t *txs, *txf;
    size_t ntx, captx;
    int oom;
} im_samples;

/* Samples of M's faces as given (the input): its vertices, points along its
 * edges and inside its faces at most spacing apart (at most 8 steps). */
FL_INTERNAL int fl_imsamp_init(im_samples *S, const imesh *M, double spacing);
FL_INTERNAL void fl_imsamp_free(im_samples *S);
/* 1 when every sample of the faces rm lies within r of one of the nadd
 * triangles T (corner pointers); each one's nearest is kept for commit. */
FL_INTERNAL int fl_imsamp_place(im_samples *S, const uint32_t *rm, size_t nrm, const double *const (*T)[3],
                                size_t nadd, double r);
/* After the change is written: the samples placed last move to the added
 * faces' slots; 0 on ENOMEM. */
FL_INTERNAL int fl_imsamp_commit(im_samples *S, const uint32_t *rm, size_t nrm, const uint32_t *slots, size_t nadd);
/* A transaction over the faces from slot nt0 on; its end keeps the moves,
 * or (keep 0, after the faces were put back) returns every sample moved
 * since the begin to the face that held it then. */
FL_INTERNAL void fl_imsamp_tx_begin(im_samples *S, size_t nt0);
FL_INTERNAL void fl_imsamp_tx_end(im_samples *S, int keep, size_t nt);

typedef struct im_params {
    double minst, maxsz, maxdev, cos_nc;
    int maxval;
    int st_on, sz_on, val_on;
    int strict; /* every change keeps the floor rule (docs/design.md) */
} im_params;

/* A transaction: what the changes since fl_imtx_begin did, to judge their
 * net effect and undo them (docs/design.md "The floor rule, compound
 * changes and bands"). */
typedef struct im_rmface {
    uint32_t f, t[3];
    double st; /* its stretch when removed */
} im_rmface;
typedef struct im_moved {
    uint32_t v;
    double p[3];
} im_moved;
typedef struct im_fechange {
    uint32_t a, b;
    uint8_t was;
} im_fechange;
typedef struct im_vcchange {
    uint32_t v;
    uint8_t was;
} im_vcchange;
typedef struct im_tx {
    int active;
    size_t nt0, nv0;                 /* the faces and vertices when it began */
    size_t ops0[4], refused0[16];    /* the counters then */
    im_rmface *rm;                   /* removed faces that existed when it began */
    size_t nrm, caprm;
    im_moved *mv;
    size_t nmv, capmv;
    im_fechange *fe;
    size_t nfe, capfe;
    im_vcchange *vc;
    size_t nvc, capvc;
    struct {
        uint32_t v, was;
    } *vl;                           /* vertices splits took past max_valence, their valence before */
    size_t nvl, capvl;
    int why;                         /* the last refused transaction's reason */
    size_t gne0, gnbig0;             /* the face grid's entries when it began */
    unsigned ggen0;                  /* and its generation */
} im_tx;

/* The refusals (femlod_improve_reason values, +1 in freason). */
typedef struct im_ctx {
    imesh *M;
    im_surface *S;
    im_samples *samp; /* the backward bound's samples; NULL when max_deviation is off */
    const im_params *p;
    size_t flips, splits, collapses, relaxations;
    size_t refused[16];
    int oom;
    im_tx tx;
    /* scratch */
    uint32_t *buf;
    size_t bufcap;
} im_ctx;

/* Each returns 1 when the change was made, 0 when refused (the reason in
 * *why, a femlod_improve_reason) or on ENOMEM (C->oom set). */
FL_INTERNAL int fl_imop_flip(im_ctx *C, uint32_t a, uint32_t b, int for_valence, int *why);
FL_INTERNAL int fl_imop_split(im_ctx *C, uint32_t a, uint32_t b, const double *at, int *why);
FL_INTERNAL int fl_imop_collapse(im_ctx *C, uint32_t a, uint32_t b, int *why);
FL_INTERNAL int fl_imop_relax(im_ctx *C, uint32_t v, int *why);

/* Transactions: the changes between begin and end are judged as one. end
 * keeps them when no face they left has a stretch below min(min_stretch,
 * the least stretch of the faces they removed) and the count of faces below
 * min_stretch fell (or, equal, their least stretch rose); otherwise it undoes
 * them all. 1 when kept. A split outside a transaction obeys the first rule
 * alone. */
FL_INTERNAL void fl_imtx_begin(im_ctx *C);
FL_INTERNAL int fl_imtx_end(im_ctx *C);
FL_INTERNAL void fl_imtx_free(im_ctx *C);

/* }====== */

/* Grows *p to at least n entries (doubling); 0 on ENOMEM. */
static inline int buf_grow(uint32_t **p, size_t *cap, size_t n) {
    if (n <= *cap) return 1;
    size_t c = *cap ? *cap : 64;
    while (c < n) c *= 2;
    uint32_t *q = fl_realloc(*p, c, sizeof *q);
    if (!q) return 0;
    *p = q;
    *cap = c;
    return 1;
}

#endif
