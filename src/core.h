/*
 * core.h - internal declarations shared by femlod's C files (never installed).
 *
 * Internal cross-file functions are named fl_<module>_<verb> and have hidden
 * visibility (FL_INTERNAL), like Lua's LUAI_FUNC.
 */
#ifndef FEMLOD_CORE_H
#define FEMLOD_CORE_H

#include "femlod.h"

#include <stdarg.h>
#include <stdio.h>

#if defined(__GNUC__)
#define FL_INTERNAL __attribute__((visibility("hidden")))
#define FL_PRINTF(f, a) __attribute__((format(printf, f, a)))
#else
#define FL_INTERNAL
#define FL_PRINTF(f, a)
#endif

/* The mesh object. Internal modules read and write the arrays directly;
 * nv and nt never exceed UINT32_MAX. */
struct femlod_mesh {
    double *pos;   /* 3*nv */
    uint32_t *tri; /* 3*nt */
    size_t nv, nt;
};

/* {====== errors (error.c) */

/* Fills err (when not NULL) and returns status. */
FL_INTERNAL femlod_status fl_error(femlod_error *err, femlod_status status, const char *fmt, ...)
    FL_PRINTF(3, 4);

/* }====== */

/* {====== progress (error.c): a femlod_progress_fn over `total` units of
 * work, called when at least 1% more is done (an integer compare per unit,
 * no division), so that the callback costs nothing per element. */

typedef struct fl_progress {
    femlod_progress_fn fn; /* NULL: never called */
    void *payload;
    size_t total, step, next;
    double last;           /* the last done reported: reports never go back */
} fl_progress;

FL_INTERNAL void fl_progress_init(fl_progress *p, femlod_progress_fn fn, void *payload,
                                  size_t total);
/* Calls the callback with done / total (clamped to [0, 1], never below the
 * last report); nonzero when it asked to stop. */
FL_INTERNAL int fl_progress_report(fl_progress *p, size_t done);
/* The cheap test to put in a loop: reports only when 1% more is done. */
static inline int fl_progress_at(fl_progress *p, size_t done) {
    return done >= p->next && fl_progress_report(p, done);
}
/* For a measure of its own: reports done (a fraction, clamped to [0, 1]) when
 * it is at least 1% above the last report; nonzero when asked to stop. */
FL_INTERNAL int fl_progress_fraction(fl_progress *p, double done);
/* The final report, done == 1; its return is ignored (the work is done). */
FL_INTERNAL void fl_progress_end(fl_progress *p);
/* The error of a cancel: FEMLOD_ECANCELLED, "WHAT: cancelled by the
 * progress callback". */
FL_INTERNAL femlod_status fl_progress_cancelled(femlod_error *err, const char *what);

/* }====== */

/* {====== allocation: checked sizes */

/* malloc(count * size) with overflow check; NULL on overflow or failure.
 * count == 0 returns a valid (1-byte) allocation so NULL always means failure. */
FL_INTERNAL void *fl_alloc(size_t count, size_t size);
FL_INTERNAL void *fl_calloc(size_t count, size_t size);
FL_INTERNAL void *fl_realloc(void *p, size_t count, size_t size);
/* Maps the whole pages of [p, p + bytes) now when bytes >= 1 MiB (Linux
 * MADV_POPULATE_WRITE; elsewhere nothing) and returns p (NULL stays NULL).
 * For large blocks that will be written whole, such as the simplifier's
 * arrays: a first-touch page fault costs 10-28 microseconds on the VMs
 * measured (error.c says more). */
FL_INTERNAL void *fl_populate(void *p, size_t bytes);

/* }====== */

/* {====== small sorts */

/* Sorts v[0..n) ascending: insertion sort for the short lists of a vertex
 * star, qsort above 24 entries (adjacency.c). */
FL_INTERNAL void fl_sort_u32(uint32_t *v, size_t n);

/* }====== */

/* {====== mesh internals (mesh.c) */

/* Allocates a mesh with uninitialised arrays of nv vertices and nt triangles;
 * NULL when counts exceed UINT32_MAX or memory is short. */
FL_INTERNAL femlod_mesh *fl_mesh_alloc(size_t nv, size_t nt);

/* Builds a mesh from a triangle soup of 3*nt corner positions, merging
 * positions that compare equal (-0.0 == 0.0; NaN must be rejected before).
 * Vertices are numbered in order of first appearance: deterministic. */
FL_INTERNAL femlod_status fl_mesh_from_soup(femlod_mesh **out, const double *corners, size_t nt,
                                            femlod_error *err);

/* Grows arrays for the readers: appends are amortised O(1). */
typedef struct fl_meshbuf {
    double *pos;
    uint32_t *tri;
    size_t nv, nt, cap_v, cap_t;
} fl_meshbuf;

FL_INTERNAL int fl_meshbuf_add_vertex(fl_meshbuf *b, double x, double y, double z); /* 0 on ENOMEM */
FL_INTERNAL int fl_meshbuf_add_triangle(fl_meshbuf *b, uint32_t a, uint32_t c, uint32_t d);
FL_INTERNAL int fl_meshbuf_reserve(fl_meshbuf *b, size_t nv, size_t nt);
/* Moves the arrays into a new mesh (b is emptied); NULL on ENOMEM. */
FL_INTERNAL femlod_mesh *fl_meshbuf_finish(fl_meshbuf *b);
FL_INTERNAL void fl_meshbuf_free(fl_meshbuf *b);

/* }====== */

/* {====== adjacency (adjacency.c) */

/* Edge and vertex adjacency of a triangle mesh, built in linear time.
 *
 * Edges are the distinct unordered vertex pairs {a, b}, a < b, that are
 * sides of triangles; a triangle with a repeated vertex contributes only its
 * proper sides. Edge e has edge_tri_count(e) = edge_start[e+1]-edge_start[e]
 * incident triangles, listed in edge_tris[] in increasing triangle order.
 * Vertex v's incident triangles are vert_tris[vert_start[v] ..
 * vert_start[v+1]) in increasing order (a triangle that repeats v is listed
 * once), and its neighbours through edges are vert_nbrs[nbr_start[v] ..
 * nbr_start[v+1]) in increasing order (valence = their count), with
 * vert_edges[] giving the edge index of each neighbour at the same place. */
typedef struct fl_adjacency {
    size_t nv, nt, ne;
    uint32_t *edge_v;      /* 2*ne: the two vertices, edge_v[2e] < edge_v[2e+1]; edges sorted by (a, b) */
    uint32_t *edge_start;  /* ne+1 */
    uint32_t *edge_tris;   /* edge_start[ne] */
    uint32_t *vert_start;  /* nv+1 */
    uint32_t *vert_tris;   /* vert_start[nv] */
    uint32_t *nbr_start;   /* nv+1 */
    uint32_t *vert_nbrs;   /* nbr_start[nv] == 2*ne */
    uint32_t *vert_edges;  /* nbr_start[nv] */
    uint32_t *tri_edges;   /* 3*nt: edge of side (c0,c1), (c1,c2), (c2,c0); UINT32_MAX for a degenerate side */
} fl_adjacency;

FL_INTERNAL femlod_status fl_adjacency_build(fl_adjacency *adj, const uint32_t *tri, size_t nt,
                                             size_t nv, femlod_error *err);
FL_INTERNAL void fl_adjacency_free(fl_adjacency *adj);
/* Each vertex's mean length of its incident edges (0 for an isolated
 * vertex), out[0..nv), equal bit for bit to the mean over a built
 * adjacency's vert_nbrs, without building it. */
FL_INTERNAL femlod_status fl_mean_edge_lengths(const double *pos, const uint32_t *tri, size_t nt,
                                               size_t nv, double *out, femlod_error *err);
/* Edge index of {a, b} or UINT32_MAX (binary search in a's neighbours). */
FL_INTERNAL uint32_t fl_adjacency_find_edge(const fl_adjacency *adj, uint32_t a, uint32_t b);
/* Topology facts from a built adjacency (fails only on ENOMEM). */
FL_INTERNAL femlod_status fl_adjacency_topology(const fl_adjacency *adj, const uint32_t *tri,
                                                femlod_topology *out, femlod_error *err);

/* }====== */

/* {====== quality (quality.c, hausdorff.c) */

/* The distinct edges {a, b}, a < b, of the triangles' proper sides, sorted by
 * (a, b), as 2*ne indices in *edges (caller frees). A lighter alternative to
 * fl_adjacency when only the edge list is wanted. Fails with FEMLOD_EINPUT on
 * an index >= nv, FEMLOD_ENOMEM on memory. */
FL_INTERNAL femlod_status fl_quality_edges(uint32_t **edges, size_t *ne, const uint32_t *tri,
                                           size_t nt, size_t nv, femlod_error *err);
/* Histogram bin of a stretch value: k such that k/10.0 <= stretch < (k+1)/10.0
 * (the edges being the doubles nearest k/10), the last bin closed; values
 * outside [0, 1] go to the end bins. */
FL_INTERNAL unsigned fl_quality_histogram_bin(double stretch);

/* }====== */

/* {====== curvature (curvature.c) */

/* Eigen-decomposition of the symmetric 3x3 m = (xx, xy, xz, yy, yz, zz) by
 * cyclic Jacobi rotations: value[k] with the unit eigenvector
 * vector[3k..3k+2], in no particular order; the vectors are orthonormal. */
FL_INTERNAL void fl_curvature_eigen3(const double m[6], double value[3], double vector[9]);

/* }====== */

/* {====== file helpers (fileio.c) */

/* Reads a whole file into memory (NUL-terminated; *size excludes the NUL). */
FL_INTERNAL femlod_status fl_file_read_all(const char *path, char **data, size_t *size,
                                           femlod_error *err);

/* Atomic output: a temporary file in the target's folder, renamed over the
 * target by fl_out_commit; fl_out_abort removes it. Write through fp. */
typedef struct fl_out {
    FILE *fp;
    char *tmp_path;
    const char *path; /* as the caller named it, for messages */
    char *target;     /* what is replaced: path, or the file a symbolic link at path points to */
} fl_out;

FL_INTERNAL femlod_status fl_out_open(fl_out *o, const char *path, femlod_error *err);
/* Flushes, checks every error, fsyncs, closes and renames; on failure removes
 * the temporary file. Always releases o. */
FL_INTERNAL femlod_status fl_out_commit(fl_out *o, femlod_error *err);
FL_INTERNAL void fl_out_abort(fl_out *o);

/* Locale-independent numbers. fl_strtod parses like strtod in the "C"
 * locale (decimal and exponent forms, inf/nan words accepted so the caller
 * can reject them with a clear message). fl_format_double writes the
 * shortest "%.Ng" form (N <= 17) that reads back to exactly x. */
FL_INTERNAL double fl_strtod(const char *s, char **end);
FL_INTERNAL int fl_format_double(char *buf, size_t size, double x);
/* fl_format_double within width characters: when the shortest exact form
 * is longer, the most significant digits that fit, in exponent form (so
 * the value is rounded: in 20 characters 15 digits, 14 with a minus sign,
 * one less with a three-digit exponent). For formats whose
 * readers limit a field's length (CalculiX: 20 characters). -1 when even
 * "1e+00" does not fit. */
FL_INTERNAL int fl_format_double_fit(char *buf, size_t size, double x, int width);

/* }====== */

/* {====== readers and writers (io_*.c); io.c dispatches to them, and the
 * helpers they share are in io_util.h. Each reader parses data[0..size)
 * (data[size] == '\0' is guaranteed) and names `name` in its messages. */

FL_INTERNAL femlod_status fl_read_obj(femlod_mesh **out, const char *data, size_t size,
                                      const char *name, femlod_error *err);
FL_INTERNAL femlod_status fl_read_stl(femlod_mesh **out, const char *data, size_t size,
                                      const char *name, femlod_format format, femlod_error *err);
FL_INTERNAL femlod_status fl_read_off(femlod_mesh **out, const char *data, size_t size,
                                      const char *name, femlod_error *err);
FL_INTERNAL femlod_status fl_read_ply(femlod_mesh **out, const char *data, size_t size,
                                      const char *name, femlod_error *err);

/* glTF (io_gltf_read.cpp, io_gltf_write.cpp: C++ behind a C face). file is
 * the path the data came from, whose folder may hold external buffers; NULL
 * when reading memory (external buffers are then an error). format is the
 * one asked for (FEMLOD_FORMAT_GLB or _GLTF): JSON or GLB is told by the
 * data. */
FL_INTERNAL femlod_status fl_read_gltf(femlod_mesh **out, const char *data, size_t size,
                                       const char *name, const char *file, femlod_format format,
                                       femlod_error *err);

FL_INTERNAL femlod_status fl_write_obj(const femlod_mesh *m, FILE *fp);
FL_INTERNAL femlod_status fl_write_stl(const femlod_mesh *m, FILE *fp, int binary);
FL_INTERNAL femlod_status fl_write_off(const femlod_mesh *m, FILE *fp);
FL_INTERNAL femlod_status fl_write_ply(const femlod_mesh *m, FILE *fp, int binary);
/* Unlike the writers above, fills err on every failure (names path), as a
 * glTF write can also fail on its options (EINPUT) or size (ELIMIT). */
FL_INTERNAL femlod_status fl_write_gltf(const femlod_mesh *m, FILE *fp, int binary,
                                        const femlod_write_options *options, const char *path,
                                        femlod_error *err);

/* The finite-element formats (io_msh.c, io_vtk.c, io_inp.c, io_medit.c).
 * The writers fill err on every failure and name path. */
FL_INTERNAL femlod_status fl_read_msh(femlod_mesh **out, const char *data, size_t size,
                                      const char *name, femlod_error *err);
FL_INTERNAL femlod_status fl_read_medit(femlod_mesh **out, const char *data, size_t size,
                                        const char *name, femlod_error *err);
FL_INTERNAL femlod_status fl_write_msh(const femlod_mesh *m, FILE *fp, int version,
                                       const char *path, femlod_error *err);
FL_INTERNAL femlod_status fl_write_vtk(const femlod_mesh *m, FILE *fp, const char *path,
                                       femlod_error *err);
FL_INTERNAL femlod_status fl_write_inp(const femlod_mesh *m, FILE *fp,
                                       const femlod_write_options *options, const char *path,
                                       femlod_error *err);
FL_INTERNAL femlod_status fl_write_medit(const femlod_mesh *m, FILE *fp, const char *path,
                                         femlod_error *err);

/* }====== */

#endif
