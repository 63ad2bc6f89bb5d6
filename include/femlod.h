/*
 * femlod.h - the one public C header of femlod.
 *
 * femlod turns dense triangle meshes into finite-element surface meshes of
 * chosen size and quality (Lee et al., "Mesh simplification and adaptive LOD
 * for finite element mesh generation"; see docs/algorithms.md).
 *
 * Conventions (docs/design.md has the reasons):
 *   - Objects with state are opaque handles (femlod_mesh); options and results
 *     are plain structs that are valid when zero-initialised, with an _INIT
 *     macro giving the documented defaults.
 *   - Every function that can fail returns a femlod_status (FEMLOD_OK == 0,
 *     negative on failure) and fills the optional caller-owned femlod_error
 *     with a one-line message naming the culprit, e.g.
 *     "part.obj:14: face index 9 out of range (8 vertices)".
 *   - *out is written only on success; a failed call frees what it made;
 *     every _free(NULL) is a no-op.
 *   - Views returned by getters stay valid until the object is changed or freed.
 *   - Programming errors (NULL handles) are asserts; bad data never is.
 *   - Results never depend on pointer values, hash order or timing.
 *
 * Units: lengths are in the mesh's own units; angles in degrees.
 */
#ifndef FEMLOD_H
#define FEMLOD_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define FEMLOD_VERSION_MAJOR 0
#define FEMLOD_VERSION_MINOR 1
#define FEMLOD_VERSION_PATCH 0
#define FEMLOD_VERSION_STRING "0.1.0"

/* {====================================================================
 * Status and errors
 * ===================================================================== */

typedef enum femlod_status {
    FEMLOD_OK = 0,
    FEMLOD_ENOMEM = -1,     /* an allocation failed */
    FEMLOD_EIO = -2,        /* a file could not be opened, read or written */
    FEMLOD_EPARSE = -3,     /* a file is malformed */
    FEMLOD_EINPUT = -4,     /* an argument or option is out of range */
    FEMLOD_ETOPOLOGY = -5,  /* the mesh's connectivity does not allow the operation */
    FEMLOD_ECANCELLED = -6, /* a progress callback asked to stop */
    FEMLOD_EUNSUPPORTED = -7, /* a valid file uses a feature femlod does not read */
    FEMLOD_ELIMIT = -8      /* a resource limit (memory, time) was exceeded */
} femlod_status;

#define FEMLOD_ERROR_MESSAGE_SIZE 256

/* Caller-owned error record; pass NULL where the details are not wanted. */
typedef struct femlod_error {
    femlod_status status;
    char message[FEMLOD_ERROR_MESSAGE_SIZE];
} femlod_error;

/* A short stable name for a status: "ok", "nomem", "io", "parse", "input",
 * "topology", "cancelled", "unsupported", "limit" ("unknown" otherwise). */
const char *femlod_status_name(femlod_status status);

/* Progress callback: done is in [0, 1]; a nonzero return cancels the
 * operation, which then fails with FEMLOD_ECANCELLED. */
typedef int (*femlod_progress_fn)(void *payload, double done);

/* The progress callback of an operation that takes no other options
 * (femlod_hierarchy_create, femlod_hierarchy_rescale,
 * femlod_hierarchy_refine_region); NULL options or a NULL progress: none.
 * Operations with their own options struct carry the same two fields
 * there. Every such operation calls progress with done non-decreasing,
 * about every 1% of its work and once with done == 1 when it finishes; a
 * nonzero return makes it fail with FEMLOD_ECANCELLED ("cancelled by the
 * progress callback"), leaving its objects as its declaration says.
 * The callback never changes a result. */
typedef struct femlod_progress_options {
    femlod_progress_fn progress;
    void *progress_payload;
} femlod_progress_options;
#define FEMLOD_PROGRESS_OPTIONS_INIT {NULL, NULL}

/* }==================================================================== */

/* {====================================================================
 * Mesh
 * ===================================================================== */

/* An indexed triangle mesh: double-precision positions and 32-bit vertex
 * indices, three per triangle. Triangles may be degenerate, duplicated or
 * non-manifold: a mesh holds what its file held, and the quality report
 * counts the defects. */
typedef struct femlod_mesh femlod_mesh;

/* Makes a mesh from arrays (copied). positions holds 3*vertex_count
 * coordinates, triangles 3*triangle_count indices. Fails with FEMLOD_EINPUT
 * on an index >= vertex_count, a non-finite coordinate or a count above
 * UINT32_MAX, and with FEMLOD_ENOMEM when memory is short. */
femlod_status femlod_mesh_create(femlod_mesh **out, const double *positions, size_t vertex_count,
                                 const uint32_t *triangles, size_t triangle_count,
                                 femlod_error *err);

/* Deep copy. */
femlod_status femlod_mesh_copy(femlod_mesh **out, const femlod_mesh *mesh, femlod_error *err);

void femlod_mesh_free(femlod_mesh *mesh);

size_t femlod_mesh_vertex_count(const femlod_mesh *mesh);
size_t femlod_mesh_triangle_count(const femlod_mesh *mesh);
/* Views: 3*vertex_count doubles and 3*triangle_count indices. */
const double *femlod_mesh_positions(const femlod_mesh *mesh);
const uint32_t *femlod_mesh_triangles(const femlod_mesh *mesh);

/* Axis-aligned bounding box of the vertices; all zero for an empty mesh. */
void femlod_mesh_bbox(const femlod_mesh *mesh, double min[3], double max[3]);

/* Total area of the triangles. */
double femlod_mesh_area(const femlod_mesh *mesh);

/* 1-to-4 subdivision, repeated levels times (paper section 3): each triangle
 * is split at its edge midpoints; a midpoint is shared by every triangle on
 * its edge (also on non-manifold edges). The triangle count grows by 4^levels:
 * fails with FEMLOD_EINPUT when that would pass UINT32_MAX. levels == 0
 * copies. Orientation and triangle order are kept (child k of triangle t is
 * triangle 4t+k, the corner children first, the middle one last). */
femlod_status femlod_mesh_subdivide(femlod_mesh **out, const femlod_mesh *mesh, unsigned levels,
                                    femlod_error *err);

/* Explicit repair, every change counted (docs/api.md, src/repair.c). The
 * steps run in this order: weld vertices closer than `weld` (a length; 0:
 * equal positions only; < 0: off) into the first of them in file order;
 * drop degenerate triangles (a repeated vertex or stretch < 1e-6); drop
 * duplicate triangles (same vertex set, either orientation; the first is
 * kept); cut non-manifold edges and vertices (each vertex keeps one fan of
 * triangles joined across two-triangle edges and gets a copy for every other
 * fan); orient each component consistently (closed ones outwards, open ones
 * flipping the fewer triangles); drop unused vertices. */
typedef struct femlod_repair_options {
    double weld;
    int drop_degenerate, drop_duplicates, split_nonmanifold, orient, drop_unused;
} femlod_repair_options;
#define FEMLOD_REPAIR_OPTIONS_INIT {0.0, 1, 1, 1, 1, 1}

typedef struct femlod_repair_report {
    size_t vertices_in, triangles_in, vertices_out, triangles_out;
    size_t welded;          /* vertices merged into an earlier one */
    size_t degenerate;      /* triangles dropped */
    size_t duplicates;      /* triangles dropped */
    size_t split_vertices;  /* vertex copies made to cut non-manifold vertices */
    size_t flipped;         /* triangles turned over */
    size_t unorientable_edges; /* edges left inconsistent (a Moebius-like component) */
    size_t unused;          /* vertices dropped for being in no triangle */
    size_t nonmanifold_edges_left; /* edges the cut could not make manifold */
} femlod_repair_report;

/* Makes the repaired mesh in *out (the input is not changed); report (may
 * be NULL) gets the counts. FEMLOD_EINPUT on a non-finite weld tolerance. */
femlod_status femlod_mesh_repair(femlod_mesh **out, const femlod_mesh *mesh,
                                 const femlod_repair_options *options,
                                 femlod_repair_report *report, femlod_error *err);

/* Connectivity facts, computed in time linear in the mesh size. */
typedef struct femlod_topology {
    size_t edges;                 /* distinct undirected edges (degenerate triangles' a-a "edges" excluded) */
    size_t boundary_edges;        /* edges with one triangle */
    size_t nonmanifold_edges;     /* edges with three or more triangles */
    size_t nonmanifold_vertices;  /* vertices whose triangles form more than one fan, or on a non-manifold edge */
    size_t inconsistent_edges;    /* two-triangle edges traversed twice in the same direction */
    size_t isolated_vertices;     /* vertices used by no triangle */
    size_t components;            /* connected components of triangles (through shared vertices) */
    int closed;                   /* every edge has exactly two triangles (and there is one) */
    int manifold;                 /* no non-manifold edge or vertex */
    int oriented;                 /* no inconsistent edge */
} femlod_topology;

femlod_status femlod_mesh_topology(const femlod_mesh *mesh, femlod_topology *out,
                                   femlod_error *err);

/* }==================================================================== */

/* {====================================================================
 * Quality (paper section 4.1, method-notes.md "Element measures")
 * ===================================================================== */

/* Stretch of triangle (a, b, c): sqrt(12) * inradius / longest edge; 1 for an
 * equilateral triangle, 0 for a degenerate one. */
double femlod_triangle_stretch(const double a[3], const double b[3], const double c[3]);

/* Size of a triangle: its longest edge. */
double femlod_triangle_size(const double a[3], const double b[3], const double c[3]);

/* Per-triangle stretch and size, and per-vertex valence (distinct neighbours
 * through edges), as pure array functions. out has triangle_count
 * (vertex_count) entries. Indices must be < vertex_count. */
void femlod_stretch_array(double *out, const double *positions, const uint32_t *triangles,
                          size_t triangle_count);
void femlod_size_array(double *out, const double *positions, const uint32_t *triangles,
                       size_t triangle_count);
femlod_status femlod_valence_array(uint32_t *out, size_t vertex_count, const uint32_t *triangles,
                                   size_t triangle_count, femlod_error *err);

#define FEMLOD_HISTOGRAM_BINS 10

/* The quality report: the paper's Table 1 columns and the defects a FE user
 * needs to know of. Stretch and angle statistics are over all triangles
 * (degenerate ones included, with stretch 0; a triangle with a zero-length
 * side counts as angles 0 and 180). Duplicates compare sorted index triples.
 * A mesh without triangles gives zeros in every statistic, minima included.
 * docs/quality.md has the formulas. */
typedef struct femlod_quality {
    size_t triangles;
    size_t vertices;
    double stretch_avg, stretch_min, stretch_max;
    double size_max, size_min, size_avg; /* longest edge per triangle */
    uint32_t valence_max;
    double valence_avg;          /* over vertices used by at least one triangle */
    double angle_min, angle_max; /* smallest and largest interior angle, degrees */
    size_t degenerate;           /* repeated vertex index or stretch < 1e-6 */
    size_t duplicate;            /* triangles with the same vertex set as an earlier one */
    size_t histogram[FEMLOD_HISTOGRAM_BINS]; /* bin k: stretch in [k/10, (k+1)/10), last bin closed */
    double area;
    double bbox_min[3], bbox_max[3];
    femlod_topology topology;
} femlod_quality;

femlod_status femlod_mesh_quality(const femlod_mesh *mesh, femlod_quality *out, femlod_error *err);

/* Two-sided Hausdorff distance, sampled: every vertex, every edge midpoint
 * and a regular barycentric grid on each triangle with spacing about
 * `spacing` (0: the reference's bounding-box diagonal / 500) of both meshes
 * is projected on the other mesh through an AABB tree. Deterministic.
 * Vertices used by no triangle are not samples; docs/quality.md has the
 * exact sampling rule. */
typedef struct femlod_hausdorff_options {
    double spacing;      /* sample spacing in mesh units; 0 for the default */
    size_t max_samples;  /* cap per mesh side (0: 4 000 000); spacing grows to respect it,
                            but vertices and edge midpoints are always taken */
    /* Called about every 1% of the triangles walked (both sides); a nonzero
     * return fails with FEMLOD_ECANCELLED, *out not written. */
    femlod_progress_fn progress;
    void *progress_payload;
} femlod_hausdorff_options;
#define FEMLOD_HAUSDORFF_OPTIONS_INIT {0.0, 0, NULL, NULL}

typedef struct femlod_hausdorff_result {
    double distance;      /* max of both one-sided distances */
    double relative;      /* distance / reference bounding-box diagonal (0 when that is 0) */
    double forward;       /* max over mesh samples of the distance to the reference */
    double backward;      /* max over reference samples of the distance to the mesh */
    double mean_forward;  /* mean over mesh samples */
    double diagonal;      /* the reference's bounding-box diagonal */
    size_t samples;       /* samples taken on both sides */
} femlod_hausdorff_result;

/* Fails with FEMLOD_EINPUT when either mesh has no triangle or the spacing
 * is negative or not finite. */
femlod_status femlod_mesh_hausdorff(const femlod_mesh *mesh, const femlod_mesh *reference,
                                    const femlod_hausdorff_options *options,
                                    femlod_hausdorff_result *out, femlod_error *err);

/* }==================================================================== */

/* {====================================================================
 * Reading and writing
 * ===================================================================== */

typedef enum femlod_format {
    FEMLOD_FORMAT_AUTO = 0,   /* from the file name's extension (reading STL: ASCII/binary by size) */
    FEMLOD_FORMAT_OBJ,
    FEMLOD_FORMAT_STL,        /* reading: detect; writing: binary */
    FEMLOD_FORMAT_STL_ASCII,
    FEMLOD_FORMAT_STL_BINARY,
    FEMLOD_FORMAT_OFF,
    FEMLOD_FORMAT_PLY,        /* reading: any supported encoding; writing: binary little-endian */
    FEMLOD_FORMAT_PLY_ASCII,
    FEMLOD_FORMAT_PLY_BINARY,
    FEMLOD_FORMAT_GLTF,       /* glTF 2.0, extension .gltf. Reading: JSON or GLB (told by the
                                 'glTF' magic); writing: GLB when the path ends in .glb, else
                                 JSON with the buffer embedded as a base64 data: URI */
    FEMLOD_FORMAT_GLB,        /* glTF 2.0 binary, extension .glb; writing: always GLB */
    FEMLOD_FORMAT_MSH,        /* Gmsh MSH, extension .msh. Reading: 4.1 or 2.2, ASCII or binary
                                 (told by the data); writing: 4.1 ASCII */
    FEMLOD_FORMAT_MSH2,       /* Gmsh MSH 2.2 ASCII (writing; reading as FEMLOD_FORMAT_MSH) */
    FEMLOD_FORMAT_VTK,        /* VTK legacy 4.2 ASCII UNSTRUCTURED_GRID, extension .vtk (writing
                                 only) with per-triangle stretch and size, per-vertex valence */
    FEMLOD_FORMAT_INP,        /* Abaqus/CalculiX input, extension .inp (writing only): *NODE,
                                 *ELEMENT TYPE=S3, node and element sets */
    FEMLOD_FORMAT_MEDIT       /* Medit (INRIA) ASCII, extension .mesh, as TetGen and MMG read it */
} femlod_format;

/* Format names as the Lua `format` option spells them: "obj", "stl",
 * "stl_ascii", "stl_binary", "off", "ply", "ply_ascii", "ply_binary",
 * "gltf", "glb", "msh", "msh2", "vtk", "inp", "medit". */
const char *femlod_format_name(femlod_format format);
/* The names above, in that order, ending with NULL (for option lists). */
const char *const *femlod_format_names(void);
/* Returns FEMLOD_FORMAT_AUTO when the name is unknown. */
femlod_format femlod_format_from_name(const char *name);
/* From a path's extension (case-insensitive); FEMLOD_FORMAT_AUTO when unknown. */
femlod_format femlod_format_from_path(const char *path);

typedef struct femlod_read_options {
    femlod_format format; /* FEMLOD_FORMAT_AUTO: from the extension */
} femlod_read_options;
#define FEMLOD_READ_OPTIONS_INIT {FEMLOD_FORMAT_AUTO}

/* Reads a mesh. OBJ, OFF and PLY keep the file's vertices and indices;
 * STL (which has no shared vertices) is welded: positions that compare equal
 * (-0.0 == 0.0) become one vertex, numbered in order of first appearance.
 * glTF is welded the same way, after node transforms: every triangle
 * primitive of the default scene, in world space (docs/formats.md).
 * Degenerate and duplicate triangles are kept. Errors name the place:
 * "FILE:LINE: message" for text, "FILE: byte N: message" for binary data,
 * "FILE: /accessors/3: message" (a JSON pointer) for glTF. */
femlod_status femlod_mesh_read(femlod_mesh **out, const char *path,
                               const femlod_read_options *options, femlod_error *err);

/* The same from memory; name is used in messages only. format must not be
 * FEMLOD_FORMAT_AUTO unless name has a known extension. glTF from memory has
 * no folder: a buffer in an external file is an error (data: URIs and GLB's
 * own binary chunk are read). */
femlod_status femlod_mesh_read_memory(femlod_mesh **out, const void *data, size_t size,
                                      const char *name, const femlod_read_options *options,
                                      femlod_error *err);

/* What glTF output colours its vertices by (femlod_write_options.color_by).
 * The colour is COLOR_0 (linear float RGB, the viridis map), the raw value a
 * float attribute _STRETCH, _SIZE or _VALENCE; docs/formats.md has the scales. */
typedef enum femlod_color_by {
    FEMLOD_COLOR_NONE = 0,  /* no colours */
    FEMLOD_COLOR_STRETCH,   /* per triangle (flat): stretch on [0, 1] */
    FEMLOD_COLOR_SIZE,      /* per triangle (flat): longest edge, on [min, max] of the mesh */
    FEMLOD_COLOR_VALENCE    /* per vertex: valence, on [3, 12] (clamped) */
} femlod_color_by;

/* A named list of indices (femlod_write_options.node_sets, element_sets).
 * The name: a letter, then letters, digits or '_', at most 80 bytes
 * (Abaqus's rule); names are compared ignoring case. Repeated indices are
 * written once, in increasing order. */
typedef struct femlod_index_set {
    const char *name;
    const uint32_t *indices;
    size_t count;
} femlod_index_set;

typedef struct femlod_write_options {
    femlod_format format; /* FEMLOD_FORMAT_AUTO: from the extension */
    /* The fields below apply to glTF output only; set for another format,
     * they make the write fail with FEMLOD_EINPUT. */
    femlod_color_by color_by; /* FEMLOD_COLOR_NONE: no COLOR_0, no material */
    int normals;              /* nonzero: write NORMAL, area-weighted vertex normals */
    /* NULL, or a JSON object (UTF-8 text), e.g. the recipe's parameters,
     * stored as asset.extras.params; not JSON or not an object fails with
     * FEMLOD_EINPUT. Borrowed for the call. */
    const char *extras;
    /* Named sets for the finite-element formats: .inp writes each as an
     * *NSET or *ELSET; set for another format, they make the write fail with
     * FEMLOD_EINPUT. Borrowed for the call; docs/formats.md has the rules. */
    const femlod_index_set *node_sets;    /* 0-based vertex indices */
    size_t node_set_count;
    const femlod_index_set *element_sets; /* 0-based triangle indices */
    size_t element_set_count;
} femlod_write_options;
#define FEMLOD_WRITE_OPTIONS_INIT {FEMLOD_FORMAT_AUTO, FEMLOD_COLOR_NONE, 0, NULL, NULL, 0, NULL, 0}

/* Writes a mesh. Output goes to a temporary file beside path that is renamed
 * over path only once complete, so a failed write leaves path as it was.
 * Text formats print each coordinate with the fewest digits that read back
 * to the same double (locale-independent); binary STL stores float32, binary
 * PLY stores float64, so PLY and text formats round-trip exactly. glTF
 * stores float32 positions (a coordinate beyond the float range fails with
 * FEMLOD_EINPUT) and the quality figures in asset.extras.quality. */
femlod_status femlod_mesh_write(const femlod_mesh *mesh, const char *path,
                                const femlod_write_options *options, femlod_error *err);
/* The same into memory: *data (malloc'd, free with free()) gets *size bytes
 * of the file femlod_mesh_write would write to a file called name (the
 * format from options or name's extension, as there). */
femlod_status femlod_mesh_write_memory(const femlod_mesh *mesh, const char *name,
                                       const femlod_write_options *options, char **data,
                                       size_t *size, femlod_error *err);

/* }==================================================================== */

/* {=== Simplification (paper section 4) */

/*
 * Quality-controlled edge collapse (paper 4.2 with method-notes.md's
 * corrections; docs/simplify.md maps every step to the code). Every
 * triangle a collapse creates meets the thresholds below, so the output
 * meets them wherever the input did; the input's own violations are
 * counted in femlod_simplify_result.violating_input.
 *
 * Thresholds, one convention for every numeric option (Lua: nil, false,
 * number):
 *   0 (zero-initialised, or nil in Lua)  the documented default;
 *   < 0 (FEMLOD_SIMPLIFY_OFF, or false)  switched off;
 *   > 0                                  the value itself.
 * A value of exactly zero cannot be asked for: use a tiny positive number
 * (e.g. tolerance = 1e-300 collapses only where the error is zero).
 * ===================================================================== */

#define FEMLOD_SIMPLIFY_OFF (-1.0)

/* Lock callback: called once per input vertex, in index order, with its
 * position; nonzero locks the vertex (it keeps its exact position). */
typedef int (*femlod_lock_fn)(void *payload, double x, double y, double z);

typedef struct femlod_simplify_options {
    /* Stop when the mesh has at most this many triangles; 0: no target
     * (simplify until no valid edge is left). */
    size_t target;
    /* Output triangles / input triangles in (0, 1], instead of target;
     * 0: none. Setting both target and ratio fails with FEMLOD_EINPUT. */
    double ratio;
    /* tau_TL (C1): the largest quadric error d_ij(k) of a collapse, in the
     * paper's units: a sum of squared distances to face planes and
     * (weighted) feature lines, length^2. Default: 4 * (mean input edge
     * length)^2 (docs/simplify.md says why). */
    double tolerance;
    /* Length: the two-sided distance bound between the output and the
     * input surface, held at samples of both (every input vertex, edge and
     * face sample within it of the output; every output vertex, edge and
     * face sample within it of the input; docs/simplify.md). Default:
     * off. */
    double max_deviation;
    /* tau_ST (C2): least stretch (sqrt(12) * inradius / longest edge, in
     * [0, 1]) of every created triangle. Default 0.2. */
    double min_stretch;
    /* tau_SZ (C3): longest edge of every created triangle, length.
     * Default: max(0.1 * bounding-box diagonal, 2 * the longest edge of any
     * input triangle). */
    double max_size;
    /* tau_VL (C4): most neighbours of every created vertex. Default 12;
     * < 0: off (vertices with more than 251 neighbours are never created:
     * the collapse log holds at most 253 neighbours per collapse). */
    int max_valence;
    /* Degrees: an edge whose two triangles' normals differ by more than this
     * is a sharp feature edge. Boundary and non-manifold edges always are.
     * Default 40; off: no sharp edges. */
    double feature_angle;
    /* Weight of the line quadric of a feature edge, relative to one face
     * plane, scaled by sharpness (1 - cos dihedral) / 2, and full weight for
     * boundary and non-manifold edges. Default 2; off: no line quadrics
     * (features still never merge or leave their line). */
    double feature_weight;
    /* Degrees: no collapse may turn a triangle's normal by more than this,
     * and no output triangle's normal may differ by more than this from the
     * normals of the input triangles it replaces (normal cones). Default 60;
     * off: only flipped triangles (turned past 90 degrees) are refused and
     * no normal cones are kept. */
    double max_normal_change;
    /* Nonzero: boundary vertices never move and boundary edges never
     * collapse. */
    int keep_boundary;
    /* Nonzero: face planes are weighted by area, normalised per vertex so
     * that tolerance keeps its units (method-notes.md). Default 0 (the
     * paper's uniform weights). */
    int area_weighted;
    /* Fast passes (docs/simplify.md "Fast passes"): a factor F >= 1 makes
     * every collapse above F * target triangles come from passes over the
     * mesh in bands of decreasing priority instead of the exact greedy order
     * (every collapse still meets every threshold; about 2x faster on a
     * 1.25M-triangle input, average stretch about 0.01-0.02 lower); below
     * F * target the exact order finishes. Without a target, the passes run
     * until no valid edge is left and the exact queue then finishes. 0 (the
     * default): 3 with error_order (average stretch within 0.01 of the
     * exact order's: docs/simplify.md "Fast passes"), the exact order
     * without it; FEMLOD_SIMPLIFY_OFF: the exact order throughout; a value
     * in (0, 1) fails with FEMLOD_EINPUT. */
    double fast_above;
    /* Threads (docs/design.md "The set-up in parallel parts", "Parallel
     * fast passes", "The exact queue's second thread" and "Threads on a
     * shared machine"): 0 (the default) as many as the processors that the
     * other runnable tasks leave idle when the run starts (/proc/loadavg),
     * at least 1, at most 16; the set-up's
     * maps, the fast passes and the full evaluations use them all, the
     * exact queue two. The result does not depend on it:
     * every value gives byte-identical output, log and counts. Negative
     * fails with FEMLOD_EINPUT. */
    int threads;
    /* Input vertex indices that must keep their exact position (loads,
     * boundary conditions); out-of-range indices fail with FEMLOD_EINPUT.
     * Collapses may merge a neighbour into a locked vertex, never move it. */
    const uint32_t *lock;
    size_t lock_count;
    femlod_lock_fn lock_fn; /* NULL: none */
    void *lock_payload;
    /* Called about every 1% of the work with done in [0, 1]; a nonzero
     * return stops the simplification, which then succeeds with the mesh as
     * it stands and stop_reason FEMLOD_STOP_CANCELLED (stopping short is
     * success: every intermediate mesh is valid). */
    femlod_progress_fn progress;
    void *progress_payload;
    /* With a collapse log (log not NULL): 0 (the default) stops at the
     * target; N >= 1 goes on past the target, down to N triangles or as far
     * as the thresholds allow (1: the coarsest mesh they allow), so that the
     * hierarchy built from the log reaches coarser fronts than the target.
     * The returned mesh, and the hierarchy's first front, are the state at
     * the target either way: the collapses up to it are the same as without
     * a floor (docs/design.md "The hierarchy below the target"). Ignored
     * without a log or a target. */
    size_t hierarchy_floor;
    /* 0 (the default) or > 0: the error order (docs/simplify.md "The
     * error order"): the collapses are taken in the paper's shape order
     * under a cap on the quadric error that starts far below the tolerance
     * and rises only when no valid collapse is left under it, with a least
     * stretch of 0.4 (or min_stretch, if higher) while the cap is below the
     * tolerance. At equal count the distance to the input is far smaller
     * than the paper's order's (cover.obj to 12,000: 0.0090 against 0.68),
     * the stretch somewhat lower. < 0: the paper's order, under the
     * tolerance alone (its Table 1). */
    int error_order;
    /* 0 (the default): when the input breaks min_stretch, max_valence or a
     * max_size given, the improvement stage (femlod_improve, with these
     * thresholds, feature angle, normal change, locks and max_deviation or
     * its own default) runs first and the simplification starts from its
     * mesh; the collapse log's node ids 0..V-1 are then that mesh's
     * vertices (femlod_collapse_log_base), and without a log a short polish
     * (two rounds of the stage, with its default deviation bound, skipped
     * when max_deviation is given; without splits when its splits would
     * take the least stretch below both min_stretch and the output's own)
     * runs on the output. Skipped with
     * keep_boundary. Nonzero: neither runs. An input that breaks no
     * threshold gives the same output either way. */
    int no_improve;
} femlod_simplify_options;

#define FEMLOD_SIMPLIFY_OPTIONS_INIT {0, 0.0, 0.0, 0.0, 0.0, 0.0, 0, 0.0, 0.0, 0.0, 0, 0, 0.0, 0, NULL, 0, NULL, NULL, NULL, NULL, 0, 0, 0}

typedef enum femlod_stop_reason {
    FEMLOD_STOP_TARGET = 0,        /* the target count was reached */
    FEMLOD_STOP_NO_VALID_EDGE = 1, /* every remaining collapse would break a threshold */
    FEMLOD_STOP_CANCELLED = 2      /* the progress callback asked to stop */
} femlod_stop_reason;

/* "target", "no_valid_edge", "cancelled". */
const char *femlod_stop_reason_name(femlod_stop_reason reason);

/* Why a candidate collapse was refused (the first failing check). */
typedef enum femlod_reject {
    FEMLOD_REJECT_TOLERANCE = 0,  /* C1 quadric error */
    FEMLOD_REJECT_DEVIATION,      /* max_deviation */
    FEMLOD_REJECT_STRETCH,        /* C2 (pre-phase: no improvement) */
    FEMLOD_REJECT_SIZE,           /* C3 */
    FEMLOD_REJECT_VALENCE,        /* C4 */
    FEMLOD_REJECT_FOLDOVER,       /* normal flip or turn, current mesh or normal cone */
    FEMLOD_REJECT_TOPOLOGY,       /* link condition, non-manifold, features, locks */
    FEMLOD_REJECT_INTERSECTION,   /* a new triangle would cross another */
    FEMLOD_REJECT_COUNT
} femlod_reject;

/* "tolerance", "deviation", "stretch", "size", "valence", "foldover",
 * "topology", "intersection". */
const char *femlod_reject_name(femlod_reject reason);

/* Why an element still breaks a threshold: what the geometry forces
 * (corner, boundary), or else the first failing check of the last change
 * that would have removed it (docs/design.md "What remains, and why").
 * Forced means no local operator can remove it without breaking a feature,
 * boundary or corner: a triangle whose two edges at a vertex are both
 * feature (boundary) edges meeting at an angle a where no triangle with an
 * angle a reaches min_stretch (a <= 7.0 degrees at min_stretch 0.2); a
 * vertex where more feature edges meet than max_valence. */
typedef enum femlod_improve_reason {
    FEMLOD_IMPROVE_CORNER = 0,    /* forced: at a corner of feature lines too sharp for min_stretch, or
                                     a vertex with more feature edges than max_valence */
    FEMLOD_IMPROVE_FIXED,         /* the operators it needs move a corner or locked vertex */
    FEMLOD_IMPROVE_DEVIATION,     /* every fix leaves max_deviation */
    FEMLOD_IMPROVE_STRETCH,       /* no operator raises the least stretch around it */
    FEMLOD_IMPROVE_VALENCE,       /* every fix raises a valence past max_valence */
    FEMLOD_IMPROVE_FOLDOVER,      /* every fix turns a face past max_normal_change */
    FEMLOD_IMPROVE_TOPOLOGY,      /* every fix breaks the link condition, a feature or a boundary */
    FEMLOD_IMPROVE_INTERSECTION,  /* every fix makes a new self-intersection */
    FEMLOD_IMPROVE_UNTRIED,       /* the rounds ran out before any operator was tried */
    FEMLOD_IMPROVE_DEPTH,         /* every fix splits an edge cut from an input edge too often */
    FEMLOD_IMPROVE_BOUNDARY,      /* forced: as corner, the two edges being boundary edges */
    FEMLOD_IMPROVE_FIXABLE,       /* census only: an operator changes it; no stage ran on this mesh */
    FEMLOD_IMPROVE_REASON_COUNT
} femlod_improve_reason;

typedef struct femlod_simplify_result {
    size_t triangles;              /* in the output */
    size_t vertices;               /* in the output */
    femlod_stop_reason stop_reason;
    size_t collapses;              /* all, pre-phase included */
    size_t prephase_collapses;     /* of which removed input triangles below min_stretch */
    size_t fast_collapses;         /* of which came from fast passes (options.fast_above) */
    /* Refused edge evaluations by first failing check. An edge is evaluated
     * each time its neighbourhood changes, so these count evaluations, not
     * edges: they tell which threshold binds. */
    size_t rejected[FEMLOD_REJECT_COUNT];
    /* Output triangles that break min_stretch or max_size (after the
     * improvement stage and polish: what they left), and by reason
     * (femlod_improve_census on the output; sums to violating_input); the
     * output's vertices above max_valence, by reason; the forced corners'
     * angles, degrees (0: none). */
    size_t violating_input;
    size_t violating_by[FEMLOD_IMPROVE_REASON_COUNT];
    size_t violating_valence;
    size_t violating_valence_by[FEMLOD_IMPROVE_REASON_COUNT];
    double corner_angle_min, corner_angle_max;
    /* With stop_reason no_valid_edge: one more evaluation of every edge
     * left, after the stop, by first failing check (each edge once): which
     * threshold binds at the stop; stop_taken: the edges that pass it, which
     * the checks made when an edge is taken from the queue (intersection,
     * deviation) refuse. Zero otherwise. */
    size_t stop_rejected[FEMLOD_REJECT_COUNT];
    size_t stop_taken;
    /* Of stop_rejected's topology: the edges refused as non-manifold [0],
     * for the features (two fixed ends, or a feature vertex that would leave
     * its line or merge lines) [1], and as interior edges between two
     * boundary vertices [2]; the rest failed the link condition or the
     * ring's checks. */
    size_t stop_topology[3];
    size_t dropped_degenerate;     /* input triangles with a repeated vertex index, not kept */
    double seconds;                /* wall time (never influences the result) */
    /* The thresholds in force, defaults resolved; FEMLOD_SIMPLIFY_OFF when off. */
    size_t target;
    double tolerance, max_deviation, min_stretch, max_size, feature_angle, feature_weight,
        max_normal_change;
    int max_valence;
    double fast_above; /* the fast_above factor, FEMLOD_SIMPLIFY_OFF when off */
    int threads;       /* threads the run had (options.threads resolved; the exact queue uses two at most) */
    /* The log's extent past the target (options.hierarchy_floor): the
     * triangles of its coarsest state and why it stopped there (equal to
     * triangles and stop_reason without a floor), and the check that refused
     * most edges in its last full evaluation (FEMLOD_REJECT_COUNT when it
     * stopped at the floor, or none was refused). */
    size_t hierarchy_triangles;
    femlod_stop_reason hierarchy_stop;
    int hierarchy_binding; /* a femlod_reject */
    /* The improvement stage (options.no_improve): 1 when it ran on the
     * input; its operations (flips + splits + collapses + relaxations) and
     * the triangles it handed to the simplification; the polish's
     * operations on the output; their wall time (within seconds). */
    int improved;
    size_t improve_operations, improve_triangles, polish_operations;
    double improve_seconds;
} femlod_simplify_result;

/* The collapse log: every collapse in order, in a vertex numbering made for
 * a binary vertex hierarchy (paper 5.1): input vertices are nodes
 * 0..V-1 (V = femlod_collapse_log_input_vertices), collapse c merges nodes i
 * and j into the new node V + c. Owned by the caller; immutable. */
typedef struct femlod_collapse_log femlod_collapse_log;

typedef struct femlod_collapse {
    uint32_t i, j;        /* the merged nodes, i < j not implied */
    uint32_t k;           /* the new node: V + c */
    double position[3];   /* of k */
    double e_size;        /* mean distance from k to its vstars (paper 5.1), length */
    /* vstars: the neighbours of i or j at collapse time other than i and j,
     * increasing node ids; view into the log. */
    const uint32_t *vstars;
    size_t vstar_count;   /* at most 253 */
    /* The triangles the collapse removed: every triangle that had i or j as
     * a corner, each as 3 local refs in the mesh's orientation, the ones
     * with both i and j first; ref 0 is i, 1 is j, r >= 2 is vstars[r-2]
     * (femlod_collapse_node). The created triangles are the others with i
     * and j replaced by k; a vertex split restores the removed ones. */
    const uint8_t *faces;
    size_t face_count;
} femlod_collapse;

size_t femlod_collapse_log_count(const femlod_collapse_log *log);
size_t femlod_collapse_log_input_vertices(const femlod_collapse_log *log);
/* The mesh whose vertices are nodes 0..V-1 when the simplification ran the
 * improvement stage on its input first (options.no_improve), owned by the
 * log; NULL when they are the input's. femlod_hierarchy_create builds on
 * it. */
const femlod_mesh *femlod_collapse_log_base(const femlod_collapse_log *log);
/* Collapses 0..n-1 were the stretch pre-phase. */
size_t femlod_collapse_log_prephase(const femlod_collapse_log *log);
/* Collapses 0..n-1 made the simplification's output mesh; the ones after
 * them went on past the target (options.hierarchy_floor). Equal to the
 * count without a floor. */
size_t femlod_collapse_log_front(const femlod_collapse_log *log);
/* Collapse c < count; the views stay valid until the log is freed. */
void femlod_collapse_log_get(const femlod_collapse_log *log, size_t c, femlod_collapse *out);
/* Node id of a local ref of c->faces. */
uint32_t femlod_collapse_node(const femlod_collapse *c, uint8_t ref);
/* Node id of each vertex of the output mesh (count = its vertex count). */
const uint32_t *femlod_collapse_log_output_nodes(const femlod_collapse_log *log, size_t *count);
/* Bytes held. */
size_t femlod_collapse_log_bytes(const femlod_collapse_log *log);
void femlod_collapse_log_free(femlod_collapse_log *log);

/* Simplifies mesh into *out (a new mesh; mesh is not changed) and, when
 * log is not NULL, records every collapse into *log. options NULL: all
 * defaults. result (may be NULL) is filled on success. Output vertices
 * come in increasing node id (see the collapse log: surviving input
 * vertices in input order, then new vertices in collapse order); output
 * triangles in the order of the input triangles they descend from. Unused
 * input vertices and triangles with a repeated index are not carried over
 * (result->dropped_degenerate counts the latter).
 * out and mesh must not be NULL (asserted). Fails with FEMLOD_EINPUT for
 * inconsistent options, FEMLOD_ENOMEM.
 * Deterministic: the same input and options give identical arrays.
 * After a run on 65,536 triangles or more it gives the memory it freed
 * back to the system (malloc_trim where the C library is glibc), so that
 * repeated runs in one process do not grow (docs/simplify.md). */
femlod_status femlod_simplify(femlod_mesh **out, femlod_collapse_log **log, const femlod_mesh *mesh,
                              const femlod_simplify_options *options, femlod_simplify_result *result,
                              femlod_error *err);

/* }==================================================================== */

/* {=== Vertex hierarchy and local LOD (paper sections 5.1, 5.2) */

/*
 * The binary vertex hierarchy of a simplification: leaves are the input
 * vertices (node ids 0..V-1), collapse c made node V+c from its two
 * children. The *front* is the set of nodes that form the current mesh; it
 * starts at the simplification's result (the mesh at its target, also when
 * the log goes on past it: femlod_collapse_log_front). Splits and collapses resolve their
 * dependencies themselves, and every front is a valid mesh: every triangle
 * of it appeared during the simplification (docs/design.md gives the rule
 * and its proof). Lua numbers nodes from 1 (id + 1).
 */
typedef struct femlod_hierarchy femlod_hierarchy;

/* Builds the hierarchy of a simplification from its input mesh and collapse
 * log (femlod_simplify). Fails with FEMLOD_EINPUT when the log does not
 * belong to the mesh. The front starts at the simplification's output.
 * options (may be NULL): progress over the collapses replayed; a cancel
 * fails with FEMLOD_ECANCELLED and makes nothing (*out not written). */
femlod_status femlod_hierarchy_create(femlod_hierarchy **out, const femlod_mesh *input,
                                      const femlod_collapse_log *log,
                                      const femlod_progress_options *options, femlod_error *err);
/* femlod_hierarchy_create that takes the log and frees it (*log set to NULL,
 * on failure too) as soon as it has been replayed, before the front's arrays
 * are made: the build then never holds the log and the whole hierarchy at
 * once (on 1.25M triangles a peak 70 MB lower). */
femlod_status femlod_hierarchy_create_from_log(femlod_hierarchy **out, const femlod_mesh *input,
                                               femlod_collapse_log **log,
                                               const femlod_progress_options *options,
                                               femlod_error *err);
void femlod_hierarchy_free(femlod_hierarchy *h);

typedef enum femlod_node_state {
    FEMLOD_NODE_ABOVE = 0, /* not yet formed: its descendants are on the front */
    FEMLOD_NODE_FRONT = 1, /* a vertex of the current mesh */
    FEMLOD_NODE_BELOW = 2  /* merged into a front node above it */
} femlod_node_state;

typedef struct femlod_node_info {
    uint32_t id;
    uint32_t parent;      /* UINT32_MAX for a root */
    uint32_t child[2];    /* UINT32_MAX for a leaf */
    double position[3];
    double e_size;        /* length: mean distance to the vstars (leaf: mean incident input edge) */
    uint32_t depth;       /* number of ancestors */
    femlod_node_state state;
} femlod_node_info;

size_t femlod_hierarchy_node_count(const femlod_hierarchy *h);
size_t femlod_hierarchy_input_vertices(const femlod_hierarchy *h);
/* Nodes on the front (unused input vertices included) and triangles of the front mesh. */
size_t femlod_hierarchy_front_nodes(const femlod_hierarchy *h);
size_t femlod_hierarchy_front_triangles(const femlod_hierarchy *h);
/* Returns 0 when id does not exist. */
int femlod_hierarchy_node(const femlod_hierarchy *h, uint32_t id, femlod_node_info *out);
/* View of the front nodes, valid until the next operation. */
const uint32_t *femlod_hierarchy_front(const femlod_hierarchy *h, size_t *count);
size_t femlod_hierarchy_bytes(const femlod_hierarchy *h);

/* Splits front node `node` (an internal node), splitting first whatever
 * depends on it; *ops (may be NULL) gets the number of splits done.
 * FEMLOD_EINPUT when node is a leaf or not on the front. */
femlod_status femlod_hierarchy_split(femlod_hierarchy *h, uint32_t node, size_t *ops,
                                     femlod_error *err);
/* Collapses the children of `node` (above the front) into it, collapsing
 * first whatever it needs. FEMLOD_EINPUT when node is a leaf or already
 * on or below the front. */
femlod_status femlod_hierarchy_collapse(femlod_hierarchy *h, uint32_t node, size_t *ops,
                                        femlod_error *err);

/* Size threshold T_S of a node (length); a NaN return stops the operation
 * with FEMLOD_ECANCELLED, leaving a valid front. */
typedef double (*femlod_size_fn)(void *payload, const femlod_node_info *node);

/* Local LOD (5.2): splits every front node whose e_size exceeds its
 * threshold (fn(node), or `size` when fn is NULL), then its children, and
 * so on; refine(0) gives back the input mesh (the improve stage's mesh when
 * the simplification ran it first: femlod_collapse_log_base). */
femlod_status femlod_hierarchy_refine(femlod_hierarchy *h, double size, femlod_size_fn fn,
                                      void *payload, size_t *ops, femlod_error *err);
/* The inverse: collapses a pair whose two children are on the front while
 * the parent's e_size is at most its threshold (fn(parent) or `size`);
 * coarsen(INFINITY) gives the coarsest front the hierarchy has: the
 * simplification's result, or, when it went on past its target
 * (options.hierarchy_floor), the mesh it reached there. */
femlod_status femlod_hierarchy_coarsen(femlod_hierarchy *h, double size, femlod_size_fn fn,
                                       void *payload, size_t *ops, femlod_error *err);

/* The front as a mesh, in time linear in the front. The order is canonical:
 * vertices are the front nodes used by a triangle in increasing node id,
 * triangles in the order they first appeared during simplification (input
 * triangles first), so a front gives the same mesh however it was reached.
 * When nodes is not NULL, *nodes gets a malloc'd array (free with free()) of
 * each vertex's node id. */
femlod_status femlod_hierarchy_extract(femlod_hierarchy *h, femlod_mesh **out, uint32_t **nodes,
                                       femlod_error *err);

/* Global LOD with density preservation (paper 5.3.2): collapses the pair
 * whose parent has the smallest r = s / S_REF, or splits the front node
 * with the largest r, until the front has `target` triangles (or the
 * nearest count the hierarchy allows: dependencies can move it by a few).
 * s is a node's order size, 1 / sqrt(n) with n the triangles of the
 * simplification's mesh right after it made the node (the input's count
 * for a leaf), in place of the paper's e_size (docs/design.md "Density in
 * the simplification's order"). S_REF is fixed from the front when the call
 * starts, so the density distribution of that front is kept; from the
 * input's front, a rescale to a count the simplification passed through
 * gives its mesh at that count. *ops gets the operations done.
 * options (may be NULL): progress as the triangle count moves towards the
 * target; a cancel fails with FEMLOD_ECANCELLED, leaving the valid front
 * reached so far (*ops counts its operations: rescale again to go on). */
femlod_status femlod_hierarchy_rescale(femlod_hierarchy *h, size_t target,
                                       const femlod_progress_options *options, size_t *ops,
                                       femlod_error *err);

/* Why the last rescale stopped away from its target (it stops at the
 * nearest front the hierarchy has, and succeeds). */
typedef enum femlod_lod_limit {
    FEMLOD_LIMIT_NONE = 0,     /* the target was reached (or no rescale yet) */
    FEMLOD_LIMIT_COARSEST = 1, /* every root is on the front: the thresholds allow no coarser mesh */
    FEMLOD_LIMIT_FINEST = 2,   /* every leaf is on the front: the input's count */
    FEMLOD_LIMIT_DEPENDENCIES = 3 /* every operation left moves the count past the target */
} femlod_lod_limit;
femlod_lod_limit femlod_hierarchy_last_limit(const femlod_hierarchy *h);
/* A short reason, for messages: "tolerance" (the check that refused most
 * edges when the simplification could go no further, when known), "the
 * hierarchy goes no coarser (hierarchy_floor)" (stopped at a floor, or a
 * file that does not say), "the input's count", "dependencies"; "" for
 * FEMLOD_LIMIT_NONE. */
const char *femlod_hierarchy_limit_reason(const femlod_hierarchy *h);
/* The check (a femlod_reject) that refused most edges when the
 * simplification stopped going coarser; FEMLOD_REJECT_COUNT when unknown
 * or when it stopped at a floor. Set by femlod_hierarchy_create from the
 * log, and by femlod_hierarchy_load from the file's result block. */
int femlod_hierarchy_coarsest_binding(const femlod_hierarchy *h);

/* Curvature LOD (paper 5.3.1a). set_curvature stores kappa (one value per
 * input vertex, finite and >= 0, e.g. femlod_mesh_curvature's kappa of
 * femlod_hierarchy_input_mesh) on the leaves and gives every internal node
 * the maximum of its children's. FEMLOD_EINPUT on a bad value. */
femlod_status femlod_hierarchy_set_curvature(femlod_hierarchy *h,
                                             const double *kappa_per_input_vertex,
                                             femlod_error *err);

/* Maps a node's kappa to its size threshold T_S (length); a NaN return
 * stops the operation with FEMLOD_ECANCELLED, leaving a valid front. */
typedef double (*femlod_kappa_map_fn)(void *payload, double kappa);

/* How refine_curvature maps kappa to T_S. With K the `percentile` of the
 * leaves' kappa: kappa >= K gives `fine`, kappa = 0 gives `coarse`, and in
 * between T_S = coarse + (fine - coarse) t with
 *   LINEAR: t = kappa / K;
 *   LOG:    t = log(1 + kappa / M) / log(1 + K / M), M the median of the
 *           leaves' positive kappa (linear when there is none), which
 *           refines moderately curved regions (fillets, holes) more than
 *           LINEAR when creases put K far above the typical curvature. */
typedef enum femlod_kappa_map_kind {
    FEMLOD_KAPPA_LINEAR = 0,
    FEMLOD_KAPPA_LOG = 1
} femlod_kappa_map_kind;

typedef struct femlod_curvature_lod_options {
    double fine;       /* length; NaN: 0 (input elements where kappa >= K) */
    double coarse;     /* length; NaN: the largest e_size of the current front (flat regions stay) */
    double percentile; /* in (0, 1]; NaN: 0.95 */
    femlod_kappa_map_kind map;
    femlod_kappa_map_fn fn; /* when not NULL: T_S = fn(payload, kappa), the four above unused */
    void *payload;
    /* Called about every 1% of the front walked (femlod_progress_options);
     * a cancel fails with FEMLOD_ECANCELLED, the front valid and refined
     * part way (*ops counts the splits done: refine again to go on). */
    femlod_progress_fn progress;
    void *progress_payload;
} femlod_curvature_lod_options;
#define FEMLOD_CURVATURE_LOD_OPTIONS_INIT \
    {__builtin_nan(""), __builtin_nan(""), __builtin_nan(""), FEMLOD_KAPPA_LINEAR, NULL, NULL, \
     NULL, NULL}

/* Refines (femlod_hierarchy_refine) with T_S from each node's kappa, as the
 * options say (NULL: the defaults). FEMLOD_EINPUT "no curvature: call
 * femlod_hierarchy_set_curvature first" when no curvature was set, or on a
 * negative or non-finite fine or coarse, or a percentile outside (0, 1].
 * A NaN from fn stops with FEMLOD_ECANCELLED, the front still valid. *ops
 * gets the splits done. */
femlod_status femlod_hierarchy_refine_curvature(femlod_hierarchy *h,
                                                const femlod_curvature_lod_options *options,
                                                size_t *ops, femlod_error *err);

/* Region LOD (paper 5.3.1b). A region is a sphere or a box (tested on node
 * positions), or marks: one byte per node (FEMLOD_REGION_NODES, node_count
 * bytes) or per input vertex (FEMLOD_REGION_VERTICES, input_vertices
 * bytes), nonzero inside. Zero-initialise and set what the kind uses. */
typedef enum femlod_region_kind {
    FEMLOD_REGION_SPHERE = 0, /* center, radius (lengths) */
    FEMLOD_REGION_BOX = 1,    /* min, max corners */
    FEMLOD_REGION_NODES = 2,  /* marks per node */
    FEMLOD_REGION_VERTICES = 3 /* marks per input vertex */
} femlod_region_kind;

typedef struct femlod_region {
    femlod_region_kind kind;
    double center[3], radius;
    double min[3], max[3];
    const unsigned char *marks;
} femlod_region;

/* Every node's distance to the region (length), into d (node_count
 * doubles): 0 for a node inside (by position, or marked, or with a marked
 * node below it); otherwise, for a sphere or box, the Euclidean distance of
 * the nearest of the node and its descendants, and for marks the shortest
 * path along the input mesh's edges from the nearest marked input vertex
 * below or at the node (INFINITY when no marked vertex is connected to it).
 * FEMLOD_EINPUT on a non-finite or inverted shape or NULL marks. */
femlod_status femlod_hierarchy_region_distance(const femlod_hierarchy *h,
                                               const femlod_region *region, double *d,
                                               femlod_error *err);

/* Refines (femlod_hierarchy_refine) so that the front inside the region
 * reaches element size `size` (length, 0: the input's elements): T_S(x) =
 * size + (grading - 1) d(x) with d the region distance above, so sizes grow
 * by at most the factor `grading` (>= 1) from one element to the next away
 * from the region; grading INFINITY refines the inside only. Only the child
 * that holds the region keeps the small threshold on a split (the paper's
 * rule that the child nearest the marked position inherits T_S). Only
 * refines: nodes farther than (e_size - size) / (grading - 1) from the
 * region are not split, except where a split inside needs them (the
 * hierarchy's dependencies). *ops gets the splits done, *inside (may be
 * NULL) the number of nodes at distance 0. FEMLOD_EINPUT on a negative or
 * non-finite size, grading < 1 or NaN, or a bad region. options (may be
 * NULL): progress over the front walked; a cancel fails with
 * FEMLOD_ECANCELLED, the front valid and refined part way (*ops and *inside
 * as far as they got: refine again to go on). */
femlod_status femlod_hierarchy_refine_region(femlod_hierarchy *h, const femlod_region *region,
                                             double size, double grading,
                                             const femlod_progress_options *options, size_t *ops,
                                             size_t *inside, femlod_error *err);

/* The hierarchy's input mesh (input vertices, input triangles without the
 * degenerate ones the hierarchy dropped), newly allocated. */
femlod_status femlod_hierarchy_input_mesh(const femlod_hierarchy *h, femlod_mesh **out,
                                          femlod_error *err);

/* Saves the hierarchy and its current front to a versioned binary file
 * (".flh", docs/formats.md) with a CRC-32 checksum, written atomically;
 * result (may be NULL) is the simplification's result, stored with it. */
femlod_status femlod_hierarchy_save(const femlod_hierarchy *h, const char *path,
                                    const femlod_simplify_result *result, femlod_error *err);
/* Loads a saved hierarchy with its front. A damaged, truncated or foreign
 * file fails with FEMLOD_EPARSE and a message naming the byte offset or the
 * inconsistency, a file of another format version with FEMLOD_EUNSUPPORTED;
 * result (may be NULL) gets the stored simplification result (zeroed when
 * the file has none). */
femlod_status femlod_hierarchy_load(femlod_hierarchy **out, const char *path,
                                    femlod_simplify_result *result, femlod_error *err);
/* The same from size bytes in memory; name (may be NULL: "<memory>") stands
 * for the path in messages. The bytes are not kept. */
femlod_status femlod_hierarchy_load_memory(femlod_hierarchy **out, const void *data, size_t size,
                                           const char *name, femlod_simplify_result *result,
                                           femlod_error *err);

/* Checks the invariant from scratch, in time linear in the hierarchy: the
 * front is a cut, the applied collapses are closed under vstars, and the
 * front's triangles are exactly the faces whose corners are all on it. */
femlod_status femlod_hierarchy_validate(const femlod_hierarchy *h, femlod_error *err);

/* }==================================================================== */

/* {=== Improvement: local operators that raise quality (docs/design.md
 * "Improving a mesh in place") */

/*
 * Flips, splits, collapses of short edges and tangential relaxation with
 * projection back onto the input surface, on the elements that break a
 * threshold, until every element meets them or no operator may change what
 * remains. Every change keeps the features (no flip across a feature edge or
 * boundary; corners and locked vertices stay; feature vertices are created
 * and moved only on their line), the fidelity bound, the topology (closed
 * stays closed, manifold stays manifold, same genus) and makes no new
 * self-intersection. Options follow femlod_simplify_options' convention:
 * 0 the default, < 0 (FEMLOD_SIMPLIFY_OFF) off, > 0 the value.
 */
typedef struct femlod_improve_options {
    double min_stretch;   /* least stretch of every triangle; default 0.2 */
    /* longest edge of every triangle (longer edges are split), length;
     * default off */
    double max_size;
    int max_valence;      /* most neighbours of every vertex; default 12 */
    /* length: the distance from every changed face's samples to the input
     * surface and from every removed point to the changed faces; default
     * 0.001 x the input's bounding-box diagonal */
    double max_deviation;
    double feature_angle;     /* degrees, as femlod_simplify_options; default 40 */
    double max_normal_change; /* degrees: no face turns more in one change; default 60 */
    int max_rounds;           /* rounds of the operators; default 20 */
    /* locked input vertices, as femlod_simplify_options */
    const uint32_t *lock;
    size_t lock_count;
    femlod_lock_fn lock_fn;
    void *lock_payload;
    /* about every round; a nonzero return stops with the mesh reached
     * (success, report.cancelled set) */
    femlod_progress_fn progress;
    void *progress_payload;
} femlod_improve_options;
#define FEMLOD_IMPROVE_OPTIONS_INIT {0.0, 0.0, 0, 0.0, 0.0, 0.0, 0, NULL, 0, NULL, NULL, NULL, NULL}


/* "corner", "fixed", "deviation", "stretch", "valence", "foldover",
 * "topology", "intersection", "untried", "depth", "boundary", "fixable". */
const char *femlod_improve_reason_name(femlod_improve_reason reason);
/* 1 for the reasons the geometry forces (corner, boundary). */
int femlod_improve_reason_forced(femlod_improve_reason reason);
/* The largest stretch of any triangle with an angle of the given degrees
 * (in (0, 180)): a corner of feature lines meeting at it forces a triangle
 * below min_stretch when this is below min_stretch. */
double femlod_stretch_bound(double angle_degrees);

typedef struct femlod_improve_report {
    size_t triangles_in, vertices_in, triangles, vertices;
    size_t flips, splits, collapses, relaxations;
    size_t rounds;
    int cancelled;
    /* elements breaking a threshold in the input and in the output:
     * triangles below min_stretch, triangles above max_size, vertices above
     * max_valence */
    size_t stretch_in, size_in, valence_in;
    size_t stretch_out, size_out, valence_out;
    /* the output's, by reason: each element counted once */
    size_t stretch_by[FEMLOD_IMPROVE_REASON_COUNT];
    size_t size_by[FEMLOD_IMPROVE_REASON_COUNT];
    size_t valence_by[FEMLOD_IMPROVE_REASON_COUNT];
    /* the output's triangles breaking min_stretch or max_size, each once,
     * by reason (sums to violating); the forced ones' corner angles,
     * degrees (0 when none) */
    size_t violating;
    size_t violating_by[FEMLOD_IMPROVE_REASON_COUNT];
    double corner_angle_min, corner_angle_max;
    /* refused changes by first failing check */
    size_t refused[FEMLOD_IMPROVE_REASON_COUNT];
    double stretch_min_in, stretch_min; /* least stretch, input and output */
    uint32_t valence_max_in, valence_max;
    /* the thresholds in force, defaults resolved (FEMLOD_SIMPLIFY_OFF: off) */
    double min_stretch, max_size, max_deviation, feature_angle, max_normal_change;
    int max_valence;
    double seconds; /* wall time (never influences the result) */
} femlod_improve_report;

/* The improved mesh in *out (the input is not changed); report may be NULL.
 * Vertices: the input's that remain, in input order, then the new ones;
 * degenerate triangles with a repeated index are dropped. Deterministic.
 * FEMLOD_EINPUT on an option out of range or a lock index out of range. */
femlod_status femlod_improve(femlod_mesh **out, const femlod_mesh *mesh,
                             const femlod_improve_options *options,
                             femlod_improve_report *report, femlod_error *err);
/* What in mesh breaks a threshold, and why, without changing it: the
 * report's *_out, *_by, violating and corner angles for mesh itself (the
 * other counts as for a stage that made no change). The forced classes come
 * from its geometry; each other element gets the refusal of one try of the
 * operators on a working copy (options.max_rounds is ignored), or fixable
 * when the try changed it. */
femlod_status femlod_improve_census(const femlod_mesh *mesh, const femlod_improve_options *options,
                                    femlod_improve_report *report, femlod_error *err);

/* }==================================================================== */

/* {=== Curvature (paper 5.3.1, normal cycle) */

/*
 * Per-vertex principal curvatures and directions of the input mesh, from
 * the normal-cycle curvature tensor of Cohen-Steiner and Morvan as Alliez
 * et al. use it (docs/curvature.md): for vertex v, the tensor
 *     T = sum_e beta(e) W(e) ebar ebar^T / sum_e A(e) W(e) / |e|
 * over the edges e of the surface within distance `radius` of v that is
 * connected to v (a walk over triangles from v's own), with beta(e) the
 * signed dihedral angle of e, ebar its unit direction, A(e) a third of the
 * area of its triangles and W(e) the length of e inside the ball weighted
 * by 1 - (distance to v / radius)^2: the papers' beta(e) |e cap B| over the
 * area of B, with a weight that falls to 0 at the ball's surface (it
 * makes the worst vertex of a fine sphere 1% off instead of 5%).
 *
 * Units: curvatures are 1/length (1/R on a sphere of radius R). Sign: with
 * respect to the triangles' orientation, positive where the surface bends
 * away from the side its normals face (a sphere with outward normals has
 * k1 = k2 = +1/R; the inside of a hole is negative).
 *
 * Boundary edges (one triangle) and non-manifold edges (three or more)
 * contribute no bending, but their share of area counts: within `radius`
 * of a boundary, curvature across the boundary line is underestimated
 * (by up to 40% on the cut of a sphere; a cylinder's rims, which bend
 * along themselves, lose nothing). Degenerate triangles (repeated corner or
 * stretch < 1e-6) count for nothing, but the walk passes through them. An
 * edge whose two triangles disagree on orientation is measured against the
 * first (lower-index) triangle's.
 */
typedef struct femlod_curvature_options {
    /* Radius of the neighbourhood ball, length; 0: 2 x the mean length of
     * the mesh's distinct edges. The work per vertex grows as
     * (radius / edge length)^2. */
    double radius;
    /* Called about every 1% of the vertices; a nonzero return fails with
     * FEMLOD_ECANCELLED, the output arrays then partly written (their
     * contents unspecified). */
    femlod_progress_fn progress;
    void *progress_payload;
} femlod_curvature_options;
#define FEMLOD_CURVATURE_OPTIONS_INIT {0.0, NULL, NULL}

/* Fills per-vertex arrays, caller-allocated, any of them NULL when not
 * wanted: k1, k2 and kappa have vertex_count entries, dir1 and dir2
 * 3*vertex_count. k1 >= k2 by value (k1 is the algebraically larger
 * principal curvature, not the larger in magnitude); kappa = max(|k1|, |k2|).
 * dir1 is the unit direction of k1 and dir2 that of k2, tangent to the
 * surface and perpendicular; a direction is a line, its sign fixed by
 * convention (dir1's largest component is positive; dir1, dir2 and the
 * surface normal are right-handed). Where k1 == k2 the directions are any
 * orthonormal tangent pair. A vertex used by no triangle, or whose
 * neighbourhood holds only degenerate ones, gets zeros everywhere,
 * directions included.
 * options NULL: the defaults. Time: linear in the mesh size times the
 * triangles within radius of a vertex. Deterministic. Fails with
 * FEMLOD_EINPUT when radius is negative or not finite (nothing written) and
 * with FEMLOD_ENOMEM. */
femlod_status femlod_mesh_curvature(const femlod_mesh *mesh,
                                    const femlod_curvature_options *options, double *k1,
                                    double *k2, double *kappa, double *dir1, double *dir2,
                                    femlod_error *err);

/* }==================================================================== */

#ifdef __cplusplus
}
#endif

#endif /* FEMLOD_H */
