/* io_msh.c - Gmsh MSH, versions 4.1 and 2.2 (gmsh.info/doc/texinfo, "MSH file
 * format"), ASCII and binary.
 *
 * Reading: $MeshFormat first, then sections in any order with $Nodes before
 * $Elements; other sections ($PhysicalNames, $Entities, $NodeData,
 * $Comments...) are skipped to their $End marker. Every node becomes a
 * vertex, in file order; node tags may be sparse and in any order. 3-node
 * triangles (type 2) make the surface; elements of dimension 0, 1 and 3
 * (points, lines, tetrahedra...) are skipped; other 2-D elements
 * (quadrangles, 6-node triangles) are errors, as dropping them would leave
 * holes. Binary files (either byte order) are read too; their errors name
 * a byte offset ("FILE: byte N: ...") instead of a line.
 *
 * Writing: 4.1 (or 2.2) ASCII with node tags 1..nv, element tags 1..nt, one
 * surface entity (tag 1) in the physical group 1 "surface", so what gmsh
 * reads back is what femlod wrote. */
#include "io_util.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* {====== element types (gmsh's numbering) */

typedef struct msh_type {
    unsigned char dim, nodes;
    const char *name;
} msh_type;

static const msh_type msh_types[] = {
    {0, 0, NULL},
    {1, 2, "2-node line"},
    {2, 3, "3-node triangle"},
    {2, 4, "4-node quadrangle"},
    {3, 4, "4-node tetrahedron"},
    {3, 8, "8-node hexahedron"},
    {3, 6, "6-node prism"},
    {3, 5, "5-node pyramid"},
    {1, 3, "3-node line"},
    {2, 6, "6-node triangle"},
    {2, 9, "9-node quadrangle"},
    {3, 10, "10-node tetrahedron"},
    {3, 27, "27-node hexahedron"},
    {3, 18, "18-node prism"},
    {3, 14, "14-node pyramid"},
    {0, 1, "1-node point"},
    {2, 8, "8-node quadrangle"},
    {3, 20, "20-node hexahedron"},
    {3, 15, "15-node prism"},
    {3, 13, "13-node pyramid"},
    {2, 9, "9-node triangle"},
    {2, 10, "10-node triangle"},
    {2, 12, "12-node triangle"},
    {2, 15, "15-node triangle"},
    {2, 15, "15-node triangle (incomplete)"},
    {2, 21, "21-node triangle"},
    {1, 4, "4-node line"},
    {1, 5, "5-node line"},
    {1, 6, "6-node line"},
    {3, 20, "20-node tetrahedron"},
    {3, 35, "35-node tetrahedron"},
    {3, 56, "56-node tetrahedron"},
};

#define MSH_TRIANGLE 2

static const msh_type *type_of(uint64_t t) {
    if (t == 0 || t >= sizeof msh_types / sizeof msh_types[0]) return NULL;
    return &msh_types[t];
}

/* }====== */

/* {====== reader */

typedef struct node_key {
    uint64_t tag;
    uint32_t index;
} node_key;

typedef struct msh_reader {
    fl_text t;
    int version;      /* 2 or 4 */
    int binary, swap; /* binary data; little-endian */
    fl_meshbuf b;
    uint64_t *tags; /* tags[i]: node tag of vertex i */
    size_t *tag_line;
    size_t cap_tags;
    /* The lookup from tag to vertex: a direct table when the tags are dense,
     * else the sorted keys. */
    uint32_t *direct;
    uint64_t direct_min;
    size_t direct_n;
    node_key *keys;
    uint64_t min_tag, max_tag;
    int have_nodes, have_elements;
    size_t skipped;     /* elements of other dimensions */
    uint64_t skip_type; /* the first one's type */
} msh_reader;

static void reader_free(msh_reader *r) {
    fl_meshbuf_free(&r->b);
    free(r->tags);
    free(r->tag_line);
    free(r->direct);
    free(r->keys);
}

static const char *quote(char *q, size_t size, const char *s, size_t n) {
    return fl_io_quote(q, size, s, n);
}

/* The next token, which must exist: what names the thing expected. */
static femlod_status need(msh_reader *r, const char **s, size_t *n, const char *what) {
    *s = fl_text_next(&r->t, n);
    if (!*s) return fl_text_fail(&r->t, FEMLOD_EPARSE, "file ends where %s was expected", what);
    return FEMLOD_OK;
}

static femlod_status need_u64(msh_reader *r, uint64_t *v, const char *what) {
    const char *s;
    size_t n;
    char q[48];
    femlod_status st = need(r, &s, &n, what);
    if (st != FEMLOD_OK) return st;
    if (n > 1 && s[0] == '$')
        return fl_text_fail(&r->t, FEMLOD_EPARSE,
                            "'%s' where the %s was expected (a count "
                            "promises more data)",
                            quote(q, sizeof q, s, n), what);
    if (!fl_text_u64(s, n, v))
        return fl_text_fail(&r->t, FEMLOD_EPARSE, "bad %s '%s'", what, quote(q, sizeof q, s, n));
    return FEMLOD_OK;
}

/* A signed integer whose value does not matter (physical and partition tags). */
static femlod_status need_int(msh_reader *r, const char *what) {
    const char *s;
    size_t n;
    char q[48];
    uint64_t v;
    femlod_status st = need(r, &s, &n, what);
    if (st != FEMLOD_OK) return st;
    if (n > 1 && s[0] == '-') s++, n--;
    if (!fl_text_u64(s, n, &v))
        return fl_text_fail(&r->t, FEMLOD_EPARSE, "bad %s '%s'", what, quote(q, sizeof q, s, n));
    return FEMLOD_OK;
}

static femlod_status need_coord(msh_reader *r, double *x, uint64_t node) {
    const char *s;
    size_t n;
    char why[128];
    if (!(s = fl_text_next(&r->t, &n)))
        return fl_text_fail(&r->t, FEMLOD_EPARSE, "file ends inside the coordinates of node %llu",
                            (unsigned long long)node);
    if (!fl_io_coord(s, n, x, why, sizeof why))
        return fl_text_fail(&r->t, FEMLOD_EPARSE, "%s", why);
    return FEMLOD_OK;
}

/* The section must end here with $End<name>. */
static femlod_status need_end(msh_reader *r, const char *end, const char *after) {
    const char *s;
    size_t n;
    char q[48];
    if (!(s = fl_text_next(&r->t, &n)))
        return fl_text_fail(&r->t, FEMLOD_EPARSE, "file ends before '%s' (after %s)", end, after);
    if (!fl_text_is(s, n, end))
        return fl_text_fail(&r->t, FEMLOD_EPARSE, "expected '%s' after %s, found '%s'", end, after,
                            quote(q, sizeof q, s, n));
    return FEMLOD_OK;
}

/* need_end after "N WHAT" (e.g. "12 nodes"). */
static femlod_status need_end_after(msh_reader *r, const char *end, uint64_t n, const char *what) {
    char after[64];
    snprintf(after, sizeof after, "%llu %s", (unsigned long long)n, what);
    return need_end(r, end, after);
}

/* The line that opens a 4.1 $Nodes or $Elements section: the block count,
 * the item count and the smallest and largest tag; item is "node" or
 * "element", for the messages. */
static femlod_status need_v4_counts(msh_reader *r, const char *item, uint64_t *blocks,
                                    uint64_t *count, uint64_t *lo, uint64_t *hi) {
    char what[4][48];
    snprintf(what[0], sizeof what[0], "%s block count", item);
    snprintf(what[1], sizeof what[1], "%s count", item);
    snprintf(what[2], sizeof what[2], "smallest %s tag", item);
    snprintf(what[3], sizeof what[3], "largest %s tag", item);
    uint64_t *v[4] = {blocks, count, lo, hi};
    for (int k = 0; k < 4; k++) {
        femlod_status st = need_u64(r, v[k], what[k]);
        if (st != FEMLOD_OK) return st;
    }
    return FEMLOD_OK;
}

/* A count of things that take at least `least` bytes each: bounded by the
 * bytes left, so a lying header cannot make us reserve memory. */
static size_t plausible(const msh_reader *r, uint64_t count, size_t least) {
    uint64_t left = (uint64_t)(r->t.end - r->t.p) / least + 1;
    return (size_t)(count < left ? count : left);
}

/* Appends a tag for the vertex about to be added (or, in 4.1 blocks, the
 * count-th one from now). */
static femlod_status push_tag(msh_reader *r, size_t at, uint64_t tag) {
    if (tag == 0)
        return fl_text_fail(&r->t, FEMLOD_EPARSE, "node tag 0 is invalid (tags start at 1)");
    if (at >= r->cap_tags) {
        size_t cap = r->cap_tags ? 2 * r->cap_tags : 1024;
        if (cap <= at) cap = at + 1;
        uint64_t *t = fl_realloc(r->tags, cap, sizeof *t);
        if (!t) return fl_text_fail(&r->t, FEMLOD_ENOMEM, "out of memory for node tags");
        r->tags = t;
        size_t *l = fl_realloc(r->tag_line, cap, sizeof *l);
        if (!l) return fl_text_fail(&r->t, FEMLOD_ENOMEM, "out of memory for node tags");
        r->tag_line = l;
        r->cap_tags = cap;
    }
    r->tags[at] = tag;
    r->tag_line[at] = r->t.line;
    return FEMLOD_OK;
}

static femlod_status add_vertex(msh_reader *r, const double c[3]) {
    if (r->b.nv >= UINT32_MAX)
        return fl_text_fail(&r->t, FEMLOD_ELIMIT, "too many nodes (limit %u)",
                            (unsigned)UINT32_MAX);
    if (!fl_meshbuf_add_vertex(&r->b, c[0], c[1], c[2]))
        return fl_text_fail(&r->t, FEMLOD_ENOMEM, "out of memory for nodes");
    return FEMLOD_OK;
}

static int cmp_key(const void *a, const void *b) {
    const node_key *x = a, *y = b;
    if (x->tag != y->tag) return x->tag < y->tag ? -1 : 1;
    return x->index < y->index ? -1 : x->index > y->index;
}

static femlod_status duplicate(msh_reader *r, uint32_t first, uint32_t second) {
    return fl_error(r->t.err, FEMLOD_EPARSE,
                    "%s:%zu: node tag %llu is defined twice (first on line %zu)", r->t.name,
                    r->tag_line[second], (unsigned long long)r->tags[second], r->tag_line[first]);
}

/* Builds the tag lookup once all nodes are read; finds duplicate tags. */
static femlod_status build_lookup(msh_reader *r) {
    size_t nv = r->b.nv;
    if (nv == 0) return FEMLOD_OK;
    uint64_t lo = r->tags[0], hi = r->tags[0];
    for (size_t i = 1; i < nv; i++) {
        if (r->tags[i] < lo) lo = r->tags[i];
        if (r->tags[i] > hi) hi = r->tags[i];
    }
    r->min_tag = lo;
    r->max_tag = hi;
    if (hi - lo < (uint64_t)nv * 2 + 1024) {
        size_t n = (size_t)(hi - lo) + 1;
        r->direct = fl_alloc(n, sizeof *r->direct);
        if (!r->direct) return fl_text_fail(&r->t, FEMLOD_ENOMEM, "out of memory for node tags");
        memset(r->direct, 0xFF, n * sizeof *r->direct);
        r->direct_min = lo;
        r->direct_n = n;
        for (size_t i = 0; i < nv; i++) {
            uint32_t *slot = &r->direct[r->tags[i] - lo];
            if (*slot != UINT32_MAX) return duplicate(r, *slot, (uint32_t)i);
            *slot = (uint32_t)i;
        }
        return FEMLOD_OK;
    }
    r->keys = fl_alloc(nv, sizeof *r->keys);
    if (!r->keys) return fl_text_fail(&r->t, FEMLOD_ENOMEM, "out of memory for node tags");
    for (size_t i = 0; i < nv; i++) r->keys[i] = (node_key){r->tags[i], (uint32_t)i};
    qsort(r->keys, nv, sizeof *r->keys, cmp_key);
    /* The duplicate reported is the later one in the file, against the
     * earliest: the sort keeps equal tags in index order. */
    uint32_t worst = UINT32_MAX, first = 0;
    for (size_t i = 1; i < nv; i++)
        if (r->keys[i].tag == r->keys[i - 1].tag) {
            size_t j = i - 1;
            while (j > 0 && r->keys[j - 1].tag == r->keys[i].tag) j--;
            if (r->keys[i].index < worst) {
                worst = r->keys[i].index;
                first = r->keys[j].index;
            }
        }
    if (worst != UINT32_MAX) return duplicate(r, first, worst);
    return FEMLOD_OK;
}

static uint32_t lookup(const msh_reader *r, uint64_t tag) {
    if (r->direct) {
        if (tag < r->direct_min || tag - r->direct_min >= r->direct_n) return UINT32_MAX;
        return r->direct[tag - r->direct_min];
    }
    size_t lo = 0, hi = r->b.nv;
    while (lo < hi) {
        size_t mid = lo + (hi - lo) / 2;
        if (r->keys[mid].tag < tag)
            lo = mid + 1;
        else
            hi = mid;
    }
    return lo < r->b.nv && r->keys[lo].tag == tag ? r->keys[lo].index : UINT32_MAX;
}

/* A node tag of an element: the vertex index, or an error. */
static femlod_status element_node(msh_reader *r, int resolve, uint32_t *v) {
    const char *s;
    size_t n;
    char q[48];
    uint64_t tag;
    femlod_status st = need(r, &s, &n, "an element's node tag");
    if (st != FEMLOD_OK) return st;
    if (n > 1 && s[0] == '$')
        return fl_text_fail(&r->t, FEMLOD_EPARSE, "'%s' inside an element (too few node tags)",
                            quote(q, sizeof q, s, n));
    if (!fl_text_u64(s, n, &tag) || tag == 0)
        return fl_text_fail(&r->t, FEMLOD_EPARSE, "bad node tag '%s'", quote(q, sizeof q, s, n));
    if (!resolve) return FEMLOD_OK;
    *v = lookup(r, tag);
    if (*v != UINT32_MAX) return FEMLOD_OK;
    if (r->b.nv == 0)
        return fl_text_fail(&r->t, FEMLOD_EPARSE, "node tag %llu out of range (no nodes)",
                            (unsigned long long)tag);
    if (tag < r->min_tag || tag > r->max_tag)
        return fl_text_fail(&r->t, FEMLOD_EPARSE, "node tag %llu out of range (nodes %llu..%llu)",
                            (unsigned long long)tag, (unsigned long long)r->min_tag,
                            (unsigned long long)r->max_tag);
    return fl_text_fail(&r->t, FEMLOD_EPARSE,
                        "node tag %llu is not defined (%zu nodes with tags %llu..%llu)",
                        (unsigned long long)tag, r->b.nv, (unsigned long long)r->min_tag,
                        (unsigned long long)r->max_tag);
}

/* Reads one element of a known type: its node tags, adding a triangle. */
static femlod_status element_nodes(msh_reader *r, uint64_t type, const msh_type *mt) {
    int tri = type == MSH_TRIANGLE;
    uint32_t v[3] = {0, 0, 0};
    for (unsigned k = 0; k < mt->nodes; k++) {
        femlod_status st = element_node(r, tri, tri ? &v[k] : NULL);
        if (st != FEMLOD_OK) return st;
    }
    if (!tri) {
        if (r->skipped++ == 0) r->skip_type = type;
        return FEMLOD_OK;
    }
    if (r->b.nt >= UINT32_MAX)
        return fl_text_fail(&r->t, FEMLOD_ELIMIT, "too many triangles (limit %u)",
                            (unsigned)UINT32_MAX);
    if (!fl_meshbuf_add_triangle(&r->b, v[0], v[1], v[2]))
        return fl_text_fail(&r->t, FEMLOD_ENOMEM, "out of memory for triangles");
    return FEMLOD_OK;
}

/* The element type's entry, or a status with the reason in why. */
static femlod_status type_problem(uint64_t type, const msh_type **mt, char *why, size_t size) {
    *mt = type_of(type);
    if (!*mt) {
        snprintf(why, size, "unknown element type %llu", (unsigned long long)type);
        return FEMLOD_EUNSUPPORTED;
    }
    if ((*mt)->dim == 2 && type != MSH_TRIANGLE) {
        snprintf(why, size,
                 "element type %llu (%s) is not supported: the surface must be 3-node triangles "
                 "(type 2)",
                 (unsigned long long)type, (*mt)->name);
        return FEMLOD_EUNSUPPORTED;
    }
    return FEMLOD_OK;
}

static femlod_status check_type(msh_reader *r, uint64_t type, const msh_type **mt) {
    char why[160];
    femlod_status st = type_problem(type, mt, why, sizeof why);
    return st == FEMLOD_OK ? st : fl_text_fail(&r->t, st, "%s", why);
}

static femlod_status nodes_v2(msh_reader *r) {
    uint64_t count;
    femlod_status st = need_u64(r, &count, "node count");
    if (st != FEMLOD_OK) return st;
    if (count > UINT32_MAX)
        return fl_text_fail(&r->t, FEMLOD_ELIMIT, "%llu nodes declared (limit %u)",
                            (unsigned long long)count, (unsigned)UINT32_MAX);
    if (!fl_meshbuf_reserve(&r->b, plausible(r, count, 8), 0))
        return fl_text_fail(&r->t, FEMLOD_ENOMEM, "out of memory for nodes");
    for (uint64_t i = 0; i < count; i++) {
        const char *s;
        size_t n;
        char q[48];
        uint64_t tag;
        if (!(s = fl_text_next(&r->t, &n)))
            return fl_text_fail(&r->t, FEMLOD_EPARSE, "file ends after %llu of %llu nodes",
                                (unsigned long long)i, (unsigned long long)count);
        if (fl_text_is(s, n, "$EndNodes"))
            return fl_text_fail(&r->t, FEMLOD_EPARSE, "'$EndNodes' after %llu of %llu nodes",
                                (unsigned long long)i, (unsigned long long)count);
        if (!fl_text_u64(s, n, &tag))
            return fl_text_fail(&r->t, FEMLOD_EPARSE, "bad node tag '%s'",
                                quote(q, sizeof q, s, n));
        if ((st = push_tag(r, r->b.nv, tag)) != FEMLOD_OK) return st;
        double c[3];
        for (int k = 0; k < 3; k++)
            if ((st = need_coord(r, &c[k], tag)) != FEMLOD_OK) return st;
        if ((st = add_vertex(r, c)) != FEMLOD_OK) return st;
    }
    return need_end_after(r, "$EndNodes", count, "nodes");
}

static femlod_status nodes_v4(msh_reader *r) {
    uint64_t blocks, count, lo, hi;
    femlod_status st = need_v4_counts(r, "node", &blocks, &count, &lo, &hi);
    if (st != FEMLOD_OK) return st;
    if (count > UINT32_MAX)
        return fl_text_fail(&r->t, FEMLOD_ELIMIT, "%llu nodes declared (limit %u)",
                            (unsigned long long)count, (unsigned)UINT32_MAX);
    if (count && lo > hi)
        return fl_text_fail(&r->t, FEMLOD_EPARSE, "smallest node tag %llu exceeds the largest %llu",
                            (unsigned long long)lo, (unsigned long long)hi);
    if (!fl_meshbuf_reserve(&r->b, plausible(r, count, 8), 0))
        return fl_text_fail(&r->t, FEMLOD_ENOMEM, "out of memory for nodes");
    uint64_t total = 0;
    for (uint64_t blk = 0; blk < blocks; blk++) {
        uint64_t dim, param, n;
        if ((st = need_u64(r, &dim, "node block's entity dimension")) != FEMLOD_OK) return st;
        if (dim > 3)
            return fl_text_fail(&r->t, FEMLOD_EPARSE, "node block %llu: entity dimension %llu",
                                (unsigned long long)blk + 1, (unsigned long long)dim);
        if ((st = need_int(r, "node block's entity tag")) != FEMLOD_OK) return st;
        if ((st = need_u64(r, &param, "node block's parametric flag")) != FEMLOD_OK) return st;
        if (param > 1)
            return fl_text_fail(&r->t, FEMLOD_EPARSE, "node block %llu: parametric flag %llu",
                                (unsigned long long)blk + 1, (unsigned long long)param);
        if ((st = need_u64(r, &n, "node block's node count")) != FEMLOD_OK) return st;
        if (n > count - total)
            return fl_text_fail(&r->t, FEMLOD_EPARSE,
                                "node block %llu holds %llu nodes, more than the %llu left of "
                                "the header's %llu",
                                (unsigned long long)blk + 1, (unsigned long long)n,
                                (unsigned long long)(count - total), (unsigned long long)count);
        size_t base = r->b.nv;
        for (uint64_t j = 0; j < n; j++) {
            uint64_t tag;
            if ((st = need_u64(r, &tag, "node tag")) != FEMLOD_OK) return st;
            if (tag < lo || tag > hi)
                return fl_text_fail(
                    &r->t, FEMLOD_EPARSE, "node tag %llu outside the header's range %llu..%llu",
                    (unsigned long long)tag, (unsigned long long)lo, (unsigned long long)hi);
            if ((st = push_tag(r, base + (size_t)j, tag)) != FEMLOD_OK) return st;
        }
        for (uint64_t j = 0; j < n; j++) {
            double c[3], u;
            uint64_t tag = r->tags[base + (size_t)j];
            for (int k = 0; k < 3; k++)
                if ((st = need_coord(r, &c[k], tag)) != FEMLOD_OK) return st;
            for (uint64_t k = 0; param && k < dim; k++)
                if ((st = need_coord(r, &u, tag)) != FEMLOD_OK) return st;
            if ((st = add_vertex(r, c)) != FEMLOD_OK) return st;
        }
        total += n;
    }
    if (total != count)
        return fl_text_fail(
            &r->t, FEMLOD_EPARSE, "header declares %llu nodes, its %llu blocks hold %llu",
            (unsigned long long)count, (unsigned long long)blocks, (unsigned long long)total);
    return need_end_after(r, "$EndNodes", blocks, "node blocks");
}

static femlod_status elements_v2(msh_reader *r) {
    uint64_t count;
    femlod_status st = need_u64(r, &count, "element count");
    if (st != FEMLOD_OK) return st;
    if (!fl_meshbuf_reserve(&r->b, r->b.nv, plausible(r, count, 12)))
        return fl_text_fail(&r->t, FEMLOD_ENOMEM, "out of memory for elements");
    for (uint64_t i = 0; i < count; i++) {
        const char *s;
        size_t n;
        char q[48];
        uint64_t tag, type, ntags;
        if (!(s = fl_text_next(&r->t, &n)))
            return fl_text_fail(&r->t, FEMLOD_EPARSE, "file ends after %llu of %llu elements",
                                (unsigned long long)i, (unsigned long long)count);
        if (fl_text_is(s, n, "$EndElements"))
            return fl_text_fail(&r->t, FEMLOD_EPARSE, "'$EndElements' after %llu of %llu elements",
                                (unsigned long long)i, (unsigned long long)count);
        if (!fl_text_u64(s, n, &tag))
            return fl_text_fail(&r->t, FEMLOD_EPARSE, "bad element tag '%s'",
                                quote(q, sizeof q, s, n));
        if ((st = need_u64(r, &type, "element type")) != FEMLOD_OK) return st;
        const msh_type *mt;
        if ((st = check_type(r, type, &mt)) != FEMLOD_OK) return st;
        if ((st = need_u64(r, &ntags, "element tag count")) != FEMLOD_OK) return st;
        if (ntags > 64)
            return fl_text_fail(&r->t, FEMLOD_EPARSE, "element %llu has %llu tags (at most 64)",
                                (unsigned long long)tag, (unsigned long long)ntags);
        for (uint64_t k = 0; k < ntags; k++)
            if ((st = need_int(r, "element tag")) != FEMLOD_OK) return st;
        if ((st = element_nodes(r, type, mt)) != FEMLOD_OK) return st;
    }
    return need_end_after(r, "$EndElements", count, "elements");
}

static femlod_status elements_v4(msh_reader *r) {
    uint64_t blocks, count, lo, hi;
    femlod_status st = need_v4_counts(r, "element", &blocks, &count, &lo, &hi);
    if (st != FEMLOD_OK) return st;
    if (!fl_meshbuf_reserve(&r->b, r->b.nv, plausible(r, count, 8)))
        return fl_text_fail(&r->t, FEMLOD_ENOMEM, "out of memory for elements");
    uint64_t total = 0;
    for (uint64_t blk = 0; blk < blocks; blk++) {
        uint64_t dim, type, n;
        if ((st = need_u64(r, &dim, "element block's entity dimension")) != FEMLOD_OK) return st;
        if ((st = need_int(r, "element block's entity tag")) != FEMLOD_OK) return st;
        if ((st = need_u64(r, &type, "element type")) != FEMLOD_OK) return st;
        const msh_type *mt;
        if ((st = check_type(r, type, &mt)) != FEMLOD_OK) return st;
        if (dim != mt->dim)
            return fl_text_fail(&r->t, FEMLOD_EPARSE,
                                "element block %llu: type %llu (%s) in an entity of dimension %llu",
                                (unsigned long long)blk + 1, (unsigned long long)type, mt->name,
                                (unsigned long long)dim);
        if ((st = need_u64(r, &n, "element block's element count")) != FEMLOD_OK) return st;
        if (n > count - total)
            return fl_text_fail(&r->t, FEMLOD_EPARSE,
                                "element block %llu holds %llu elements, more than the %llu left "
                                "of the header's %llu",
                                (unsigned long long)blk + 1, (unsigned long long)n,
                                (unsigned long long)(count - total), (unsigned long long)count);
        for (uint64_t j = 0; j < n; j++) {
            uint64_t tag;
            if ((st = need_u64(r, &tag, "element tag")) != FEMLOD_OK) return st;
            if ((st = element_nodes(r, type, mt)) != FEMLOD_OK) return st;
        }
        total += n;
    }
    if (total != count)
        return fl_text_fail(
            &r->t, FEMLOD_EPARSE, "header declares %llu elements, its %llu blocks hold %llu",
            (unsigned long long)count, (unsigned long long)blocks, (unsigned long long)total);
    return need_end_after(r, "$EndElements", blocks, "element blocks");
}

/* {====== binary data: "FILE: byte N: message" */

static femlod_status bin_fail(msh_reader *r, const char *at, const char *fmt, ...) FL_PRINTF(3, 4);
static femlod_status bin_fail(msh_reader *r, const char *at, const char *fmt, ...) {
    char msg[FEMLOD_ERROR_MESSAGE_SIZE];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    return fl_error(r->t.err, FEMLOD_EPARSE, "%s: byte %zu: %s", r->t.name,
                    (size_t)(at - r->t.start), msg);
}

static size_t bin_left(const msh_reader *r) { return (size_t)(r->t.end - r->t.p); }

/* The binary data of a section starts after the end of its header line. */
static femlod_status bin_begin(msh_reader *r, const char *section) {
    const char *nl = memchr(r->t.p, '\n', bin_left(r));
    if (!nl) return fl_text_fail(&r->t, FEMLOD_EPARSE, "file ends after '%s'", section);
    r->t.p = nl + 1;
    r->t.line++;
    return FEMLOD_OK;
}

/* Moves the reader over n bytes of binary data, counting their newlines so
 * that later line numbers stay right. */
static void bin_skip(msh_reader *r, size_t n) {
    const char *p = r->t.p, *e = p + n;
    while ((p = memchr(p, '\n', (size_t)(e - p)))) {
        r->t.line++;
        p++;
    }
    r->t.p = e;
}

static uint64_t bin_u(msh_reader *r, size_t size) {
    const unsigned char *p = (const unsigned char *)r->t.p;
    uint64_t v = 0;
    for (size_t i = 0; i < size; i++) {
        unsigned b = p[r->swap ? size - 1 - i : i];
        v = v << 8 | b;
    }
    bin_skip(r, size);
    return v;
}

static int32_t bin_i32(msh_reader *r) {
    uint32_t u = (uint32_t)bin_u(r, 4);
    int32_t v;
    memcpy(&v, &u, sizeof v);
    return v;
}

static double bin_f64(msh_reader *r) {
    uint64_t u = bin_u(r, 8);
    double v;
    memcpy(&v, &u, sizeof v);
    return v;
}

static femlod_status bin_need(msh_reader *r, uint64_t count, uint64_t size, const char *what) {
    uint64_t total;
    if (__builtin_mul_overflow(count, size, &total) || total > bin_left(r))
        return bin_fail(r, r->t.p, "%s: %llu records of %llu bytes, only %zu bytes are left", what,
                        (unsigned long long)count, (unsigned long long)size, bin_left(r));
    return FEMLOD_OK;
}

static femlod_status bin_coords(msh_reader *r, size_t values) {
    double c[3];
    const char *at = r->t.p;
    for (size_t k = 0; k < values; k++) {
        double x = bin_f64(r);
        if (k < 3) c[k] = x;
        if (k < 3 && !isfinite(x))
            return bin_fail(r, at + 8 * k, "node %zu: coordinate is not finite (%s)", r->b.nv + 1,
                            isnan(x) ? "nan" : "inf");
    }
    return add_vertex(r, c);
}

static femlod_status bin_nodes_v2(msh_reader *r, uint64_t count) {
    femlod_status st = bin_need(r, count, 28, "nodes");
    if (st != FEMLOD_OK) return st;
    if (!fl_meshbuf_reserve(&r->b, (size_t)count, 0))
        return fl_text_fail(&r->t, FEMLOD_ENOMEM, "out of memory for nodes");
    for (uint64_t i = 0; i < count; i++) {
        const char *at = r->t.p;
        int32_t tag = bin_i32(r);
        if (tag <= 0)
            return bin_fail(r, at, "node tag %ld is invalid (tags start at 1)", (long)tag);
        if ((st = push_tag(r, r->b.nv, (uint64_t)tag)) != FEMLOD_OK) return st;
        if ((st = bin_coords(r, 3)) != FEMLOD_OK) return st;
    }
    return FEMLOD_OK;
}

static femlod_status bin_nodes_v4(msh_reader *r) {
    femlod_status st = bin_need(r, 4, 8, "node section header");
    if (st != FEMLOD_OK) return st;
    uint64_t blocks = bin_u(r, 8), count = bin_u(r, 8), lo = bin_u(r, 8), hi = bin_u(r, 8);
    if (count > UINT32_MAX)
        return bin_fail(r, r->t.p - 24, "%llu nodes declared (limit %u)", (unsigned long long)count,
                        (unsigned)UINT32_MAX);
    if ((st = bin_need(r, count, 32, "nodes")) != FEMLOD_OK) return st;
    if (!fl_meshbuf_reserve(&r->b, (size_t)count, 0))
        return fl_text_fail(&r->t, FEMLOD_ENOMEM, "out of memory for nodes");
    uint64_t total = 0;
    for (uint64_t blk = 0; blk < blocks; blk++) {
        if ((st = bin_need(r, 1, 20, "node block header")) != FEMLOD_OK) return st;
        const char *at = r->t.p;
        int32_t dim = bin_i32(r);
        (void)bin_i32(r);
        int32_t param = bin_i32(r);
        uint64_t n = bin_u(r, 8);
        if (dim < 0 || dim > 3 || param < 0 || param > 1)
            return bin_fail(r, at, "node block %llu: entity dimension %ld, parametric flag %ld",
                            (unsigned long long)blk + 1, (long)dim, (long)param);
        if (n > count - total)
            return bin_fail(r, at + 12,
                            "node block %llu holds %llu nodes, more than the %llu left "
                            "of the header's %llu",
                            (unsigned long long)blk + 1, (unsigned long long)n,
                            (unsigned long long)(count - total), (unsigned long long)count);
        size_t values = 3 + (size_t)(param ? dim : 0);
        if ((st = bin_need(r, n, 8 + 8 * values, "node block")) != FEMLOD_OK) return st;
        size_t base = r->b.nv;
        for (uint64_t j = 0; j < n; j++) {
            const char *tat = r->t.p;
            uint64_t tag = bin_u(r, 8);
            if (tag < lo || tag > hi || tag == 0)
                return bin_fail(r, tat, "node tag %llu outside the header's range %llu..%llu",
                                (unsigned long long)tag, (unsigned long long)lo,
                                (unsigned long long)hi);
            if ((st = push_tag(r, base + (size_t)j, tag)) != FEMLOD_OK) return st;
        }
        for (uint64_t j = 0; j < n; j++)
            if ((st = bin_coords(r, values)) != FEMLOD_OK) return st;
        total += n;
    }
    if (total != count)
        return bin_fail(r, r->t.p, "header declares %llu nodes, its %llu blocks hold %llu",
                        (unsigned long long)count, (unsigned long long)blocks,
                        (unsigned long long)total);
    return FEMLOD_OK;
}

/* One element's node tags (size bytes each) at the reader. */
static femlod_status bin_element(msh_reader *r, uint64_t type, const msh_type *mt, size_t size) {
    uint32_t v[3] = {0, 0, 0};
    int tri = type == MSH_TRIANGLE;
    for (unsigned k = 0; k < mt->nodes; k++) {
        const char *at = r->t.p;
        uint64_t tag = bin_u(r, size);
        if (!tri) continue;
        v[k] = lookup(r, tag);
        if (v[k] == UINT32_MAX)
            return bin_fail(r, at, "node tag %llu is not defined (%zu nodes with tags %llu..%llu)",
                            (unsigned long long)tag, r->b.nv, (unsigned long long)r->min_tag,
                            (unsigned long long)r->max_tag);
    }
    if (!tri) {
        if (r->skipped++ == 0) r->skip_type = type;
        return FEMLOD_OK;
    }
    if (r->b.nt >= UINT32_MAX)
        return bin_fail(r, r->t.p, "too many triangles (limit %u)", (unsigned)UINT32_MAX);
    if (!fl_meshbuf_add_triangle(&r->b, v[0], v[1], v[2]))
        return fl_text_fail(&r->t, FEMLOD_ENOMEM, "out of memory for triangles");
    return FEMLOD_OK;
}

static femlod_status bin_type(msh_reader *r, const char *at, uint64_t type, const msh_type **mt) {
    char why[160];
    femlod_status st = type_problem(type, mt, why, sizeof why);
    if (st != FEMLOD_OK)
        fl_error(r->t.err, st, "%s: byte %zu: %s", r->t.name, (size_t)(at - r->t.start), why);
    return st;
}

static femlod_status bin_elements_v2(msh_reader *r, uint64_t count) {
    uint64_t done = 0;
    femlod_status st;
    while (done < count) {
        if ((st = bin_need(r, 3, 4, "element header")) != FEMLOD_OK) return st;
        const char *at = r->t.p;
        int32_t type = bin_i32(r), n = bin_i32(r), ntags = bin_i32(r);
        const msh_type *mt;
        if ((st = bin_type(r, at, (uint64_t)(type < 0 ? 0 : type), &mt)) != FEMLOD_OK) return st;
        if (n <= 0 || (uint64_t)n > count - done || ntags < 0 || ntags > 64)
            return bin_fail(r, at + 4,
                            "element header: %ld elements with %ld tags (%llu of %llu "
                            "elements left)",
                            (long)n, (long)ntags, (unsigned long long)(count - done),
                            (unsigned long long)count);
        if ((st = bin_need(r, (uint64_t)n, 4 * (1 + (uint64_t)ntags + mt->nodes), "elements")) !=
            FEMLOD_OK)
            return st;
        for (int32_t i = 0; i < n; i++) {
            bin_skip(r, 4 * (1 + (size_t)ntags));
            if ((st = bin_element(r, (uint64_t)type, mt, 4)) != FEMLOD_OK) return st;
        }
        done += (uint64_t)n;
    }
    return FEMLOD_OK;
}

static femlod_status bin_elements_v4(msh_reader *r) {
    femlod_status st = bin_need(r, 4, 8, "element section header");
    if (st != FEMLOD_OK) return st;
    uint64_t blocks = bin_u(r, 8), count = bin_u(r, 8);
    bin_skip(r, 16);
    uint64_t total = 0;
    for (uint64_t blk = 0; blk < blocks; blk++) {
        if ((st = bin_need(r, 1, 20, "element block header")) != FEMLOD_OK) return st;
        const char *at = r->t.p;
        int32_t dim = bin_i32(r);
        (void)bin_i32(r);
        int32_t type = bin_i32(r);
        uint64_t n = bin_u(r, 8);
        const msh_type *mt;
        if ((st = bin_type(r, at + 8, (uint64_t)(type < 0 ? 0 : type), &mt)) != FEMLOD_OK)
            return st;
        if (dim != mt->dim)
            return bin_fail(r, at,
                            "element block %llu: type %ld (%s) in an entity of dimension %ld",
                            (unsigned long long)blk + 1, (long)type, mt->name, (long)dim);
        if (n > count - total)
            return bin_fail(r, at + 12,
                            "element block %llu holds %llu elements, more than the %llu "
                            "left of the header's %llu",
                            (unsigned long long)blk + 1, (unsigned long long)n,
                            (unsigned long long)(count - total), (unsigned long long)count);
        if ((st = bin_need(r, n, 8 * (1 + (uint64_t)mt->nodes), "element block")) != FEMLOD_OK)
            return st;
        for (uint64_t j = 0; j < n; j++) {
            bin_skip(r, 8);
            if ((st = bin_element(r, (uint64_t)type, mt, 8)) != FEMLOD_OK) return st;
        }
        total += n;
    }
    if (total != count)
        return bin_fail(r, r->t.p, "header declares %llu elements, its %llu blocks hold %llu",
                        (unsigned long long)count, (unsigned long long)blocks,
                        (unsigned long long)total);
    return FEMLOD_OK;
}

/* $Entities in a binary 4.1 file: read through to find its end. */
static femlod_status bin_entities(msh_reader *r) {
    femlod_status st = bin_need(r, 4, 8, "entity counts");
    if (st != FEMLOD_OK) return st;
    uint64_t n[4];
    for (int d = 0; d < 4; d++) n[d] = bin_u(r, 8);
    for (int d = 0; d < 4; d++)
        for (uint64_t i = 0; i < n[d]; i++) {
            size_t fixed = d == 0 ? 4 + 24 : 4 + 48;
            if ((st = bin_need(r, 1, fixed + 8, "entity")) != FEMLOD_OK) return st;
            bin_skip(r, fixed);
            uint64_t k = bin_u(r, 8);
            if ((st = bin_need(r, k, 4, "entity's physical tags")) != FEMLOD_OK) return st;
            bin_skip(r, 4 * (size_t)k);
            if (d == 0) continue;
            if ((st = bin_need(r, 1, 8, "entity")) != FEMLOD_OK) return st;
            k = bin_u(r, 8);
            if ((st = bin_need(r, k, 4, "entity's bounding entities")) != FEMLOD_OK) return st;
            bin_skip(r, 4 * (size_t)k);
        }
    return FEMLOD_OK;
}

/* }====== */

/* Skips a section to its $End marker. */
static femlod_status skip_section(msh_reader *r, const char *s, size_t n) {
    char end[80], q[48];
    if (n + 4 > sizeof end)
        return fl_text_fail(&r->t, FEMLOD_EPARSE, "section name '%s' too long",
                            quote(q, sizeof q, s, n));
    memcpy(end, "$End", 4);
    memcpy(end + 4, s + 1, n - 1);
    end[n + 3] = '\0';
    size_t line = r->t.line;
    size_t len;
    const char *t;
    while ((t = fl_text_next(&r->t, &len)))
        if (fl_text_is(t, len, end)) return FEMLOD_OK;
    return fl_text_fail(&r->t, FEMLOD_EPARSE, "section '%s' (line %zu) has no '%s'",
                        quote(q, sizeof q, s, n), line, end);
}

static femlod_status bin_nodes(msh_reader *r) {
    uint64_t count = 0;
    femlod_status st;
    if (r->version == 2 && (st = need_u64(r, &count, "node count")) != FEMLOD_OK) return st;
    if ((st = bin_begin(r, "$Nodes")) != FEMLOD_OK) return st;
    st = r->version == 4 ? bin_nodes_v4(r) : bin_nodes_v2(r, count);
    if (st != FEMLOD_OK) return st;
    return need_end(r, "$EndNodes", "the binary nodes");
}

static femlod_status bin_elements(msh_reader *r) {
    uint64_t count = 0;
    femlod_status st;
    if (r->version == 2 && (st = need_u64(r, &count, "element count")) != FEMLOD_OK) return st;
    if ((st = bin_begin(r, "$Elements")) != FEMLOD_OK) return st;
    st = r->version == 4 ? bin_elements_v4(r) : bin_elements_v2(r, count);
    if (st != FEMLOD_OK) return st;
    return need_end(r, "$EndElements", "the binary elements");
}

static femlod_status read_format(msh_reader *r) {
    const char *s;
    size_t n;
    char q[48];
    s = fl_text_next(&r->t, &n);
    if (!s) return fl_error(r->t.err, FEMLOD_EPARSE, "%s: empty file", r->t.name);
    if (fl_text_is(s, n, "$NOD") || fl_text_is(s, n, "$NOE"))
        return fl_text_fail(&r->t, FEMLOD_EUNSUPPORTED,
                            "MSH version 1 is not supported (2.2 and 4.1 are)");
    if (!fl_text_is(s, n, "$MeshFormat"))
        return fl_text_fail(&r->t, FEMLOD_EPARSE, "expected '$MeshFormat', found '%s'",
                            quote(q, sizeof q, s, n));
    femlod_status st = need(r, &s, &n, "the MSH version");
    if (st != FEMLOD_OK) return st;
    if (fl_text_is(s, n, "4.1"))
        r->version = 4;
    else if (fl_text_is(s, n, "2.2") || fl_text_is(s, n, "2.1") || fl_text_is(s, n, "2.0") ||
             fl_text_is(s, n, "2"))
        r->version = 2;
    else
        return fl_text_fail(&r->t, FEMLOD_EUNSUPPORTED,
                            "MSH version '%s' is not supported (2.2 and 4.1 are; "
                            "'gmsh -0 IN -format msh41 -o OUT' converts)",
                            quote(q, sizeof q, s, n));
    uint64_t type, size;
    if ((st = need_u64(r, &type, "file type")) != FEMLOD_OK) return st;
    if (type > 1)
        return fl_text_fail(&r->t, FEMLOD_EPARSE, "file type %llu (0 is ASCII, 1 binary)",
                            (unsigned long long)type);
    if ((st = need_u64(r, &size, "data size")) != FEMLOD_OK) return st;
    if (type == 1) {
        if (size != 8)
            return fl_text_fail(&r->t, FEMLOD_EUNSUPPORTED, "binary data size %llu (8 is read)",
                                (unsigned long long)size);
        r->binary = 1;
        if ((st = bin_begin(r, "$MeshFormat")) != FEMLOD_OK) return st;
        if (bin_left(r) < 4) return bin_fail(r, r->t.p, "file ends inside the byte-order integer");
        const unsigned char *p = (const unsigned char *)r->t.p;
        if (p[0] == 1 && !p[1] && !p[2] && !p[3])
            r->swap = 1; /* little-endian */
        else if (!p[0] && !p[1] && !p[2] && p[3] == 1)
            r->swap = 0;
        else
            return bin_fail(r, r->t.p, "the byte-order integer is not 1");
        bin_skip(r, 4);
    }
    return need_end(r, "$EndMeshFormat", "the format line");
}

static femlod_status parse(msh_reader *r) {
    femlod_status st = read_format(r);
    if (st != FEMLOD_OK) return st;
    const char *s;
    size_t n;
    char q[48];
    while ((s = fl_text_next(&r->t, &n))) {
        if (fl_text_is(s, n, "$Nodes")) {
            if (r->have_nodes)
                return fl_text_fail(&r->t, FEMLOD_EUNSUPPORTED, "a second '$Nodes' section");
            r->have_nodes = 1;
            st = r->binary ? bin_nodes(r) : r->version == 4 ? nodes_v4(r) : nodes_v2(r);
            if (st == FEMLOD_OK) st = build_lookup(r);
        } else if (fl_text_is(s, n, "$Elements")) {
            if (!r->have_nodes)
                return fl_text_fail(&r->t, FEMLOD_EPARSE, "'$Elements' before '$Nodes'");
            if (r->have_elements)
                return fl_text_fail(&r->t, FEMLOD_EUNSUPPORTED, "a second '$Elements' section");
            r->have_elements = 1;
            st = r->binary ? bin_elements(r) : r->version == 4 ? elements_v4(r) : elements_v2(r);
        } else if (r->binary && fl_text_is(s, n, "$Entities")) {
            if ((st = bin_begin(r, "$Entities")) == FEMLOD_OK &&
                (st = bin_entities(r)) == FEMLOD_OK)
                st = need_end(r, "$EndEntities", "the entities");
        } else if (fl_text_is(s, n, "$MeshFormat")) {
            return fl_text_fail(&r->t, FEMLOD_EPARSE, "a second '$MeshFormat' section");
        } else if (n > 4 && memcmp(s, "$End", 4) == 0) {
            return fl_text_fail(&r->t, FEMLOD_EPARSE, "'%s' without its section",
                                quote(q, sizeof q, s, n));
        } else if (n > 1 && s[0] == '$') {
            st = skip_section(r, s, n);
        } else {
            return fl_text_fail(&r->t, FEMLOD_EPARSE, "expected a section ('$Name'), found '%s'",
                                quote(q, sizeof q, s, n));
        }
        if (st != FEMLOD_OK) return st;
    }
    if (!r->have_nodes) return fl_text_fail(&r->t, FEMLOD_EPARSE, "no '$Nodes' section");
    if (!r->have_elements) return fl_text_fail(&r->t, FEMLOD_EPARSE, "no '$Elements' section");
    if (r->b.nt == 0 && r->skipped)
        return fl_text_fail(&r->t, FEMLOD_EUNSUPPORTED,
                            "no triangles: all %zu elements are of other dimensions (the first "
                            "is type %llu, %s)",
                            r->skipped, (unsigned long long)r->skip_type,
                            type_of(r->skip_type)->name);
    return FEMLOD_OK;
}

femlod_status fl_read_msh(femlod_mesh **out, const char *data, size_t size, const char *name,
                          femlod_error *err) {
    msh_reader r;
    memset(&r, 0, sizeof r);
    fl_text_init(&r.t, data, size, name, 0, err);
    femlod_status st = fl_io_finish(&r.b, parse(&r), out, name, err);
    reader_free(&r);
    return st;
}

/* }====== */

/* {====== writer */

/* Bounding box of the boundary sides' nodes. */
static void sides_bbox(const femlod_mesh *m, const uint32_t *sides, size_t ns, double lo[3],
                       double hi[3]) {
    for (size_t i = 0; i < 2 * ns; i++)
        for (int k = 0; k < 3; k++) {
            double x = m->pos[3 * (size_t)sides[i] + k];
            if (i == 0 || x < lo[k]) lo[k] = x;
            if (i == 0 || x > hi[k]) hi[k] = x;
        }
}

femlod_status fl_write_msh(const femlod_mesh *m, FILE *fp, int version, const char *path,
                           femlod_error *err) {
    size_t nv = m->nv, nt = m->nt, nb = 0;
    uint32_t *sides = NULL;
    femlod_status st = fl_io_boundary_sides(m, &sides, &nb, err);
    if (st != FEMLOD_OK) {
        if (err) {
            char msg[FEMLOD_ERROR_MESSAGE_SIZE];
            snprintf(msg, sizeof msg, "%s", err->message);
            fl_error(err, st, "%s: %s", path, msg);
        }
        return st;
    }
    int ok = 1;
    ok &= fprintf(fp, "$MeshFormat\n%s 0 8\n$EndMeshFormat\n", version == 4 ? "4.1" : "2.2") > 0;
    /* Every triangle is in the physical surface 1, so gmsh (which saves only
     * physical elements once groups exist) keeps them all; boundary edges,
     * when there are any, are 2-node lines in the physical curve 2. */
    if (nt) {
        ok &= fprintf(fp, "$PhysicalNames\n%d\n", nb ? 2 : 1) > 0;
        if (nb) ok &= fputs("1 2 \"boundary\"\n", fp) >= 0;
        ok &= fputs("2 1 \"surface\"\n$EndPhysicalNames\n", fp) >= 0;
    }
    if (version == 4) {
        if (nv) {
            double lo[3], hi[3];
            ok &= fprintf(fp, "$Entities\n0 %d 1 0\n", nb ? 1 : 0) > 0;
            if (nb) {
                sides_bbox(m, sides, nb, lo, hi);
                ok &= fputs("1 ", fp) >= 0;
                ok &= fl_io_put_xyz(fp, lo, " ", " ");
                ok &= fl_io_put_xyz(fp, hi, " ", " 1 2 0\n");
            }
            femlod_mesh_bbox(m, lo, hi);
            ok &= fputs("1 ", fp) >= 0;
            ok &= fl_io_put_xyz(fp, lo, " ", " ");
            ok &= fl_io_put_xyz(fp, hi, " ", nt ? (nb ? " 1 1 1 1\n" : " 1 1 0\n") : " 0 0\n");
            ok &= fputs("$EndEntities\n", fp) >= 0;
            ok &= fprintf(fp, "$Nodes\n1 %zu 1 %zu\n2 1 0 %zu\n", nv, nv, nv) > 0;
            for (size_t i = 0; i < nv && ok; i++) ok &= fprintf(fp, "%zu\n", i + 1) > 0;
            for (size_t i = 0; i < nv && ok; i++)
                ok &= fl_io_put_xyz(fp, m->pos + 3 * i, " ", "\n");
        } else {
            ok &= fputs("$Nodes\n0 0 0 0\n", fp) >= 0;
        }
        ok &= fputs("$EndNodes\n$Elements\n", fp) >= 0;
        if (nt)
            ok &= fprintf(fp, "%d %zu 1 %zu\n2 1 2 %zu\n", nb ? 2 : 1, nt + nb, nt + nb, nt) > 0;
        else
            ok &= fputs("0 0 0 0\n", fp) >= 0;
        for (size_t i = 0; i < nt && ok; i++) {
            const uint32_t *t = m->tri + 3 * i;
            ok &= fprintf(fp, "%zu %lu %lu %lu\n", i + 1, (unsigned long)t[0] + 1,
                          (unsigned long)t[1] + 1, (unsigned long)t[2] + 1) > 0;
        }
        if (nb) ok &= fprintf(fp, "1 1 1 %zu\n", nb) > 0;
        for (size_t i = 0; i < nb && ok; i++)
            ok &= fprintf(fp, "%zu %lu %lu\n", nt + i + 1, (unsigned long)sides[2 * i] + 1,
                          (unsigned long)sides[2 * i + 1] + 1) > 0;
    } else {
        ok &= fprintf(fp, "$Nodes\n%zu\n", nv) > 0;
        for (size_t i = 0; i < nv && ok; i++) {
            ok &= fprintf(fp, "%zu ", i + 1) > 0;
            ok &= fl_io_put_xyz(fp, m->pos + 3 * i, " ", "\n");
        }
        ok &= fprintf(fp, "$EndNodes\n$Elements\n%zu\n", nt + nb) > 0;
        /* number, type 2, two tags (physical 1, elementary 1), nodes */
        for (size_t i = 0; i < nt && ok; i++) {
            const uint32_t *t = m->tri + 3 * i;
            ok &= fprintf(fp, "%zu 2 2 1 1 %lu %lu %lu\n", i + 1, (unsigned long)t[0] + 1,
                          (unsigned long)t[1] + 1, (unsigned long)t[2] + 1) > 0;
        }
        /* lines: type 1, physical 2, elementary 1 */
        for (size_t i = 0; i < nb && ok; i++)
            ok &= fprintf(fp, "%zu 1 2 2 1 %lu %lu\n", nt + i + 1, (unsigned long)sides[2 * i] + 1,
                          (unsigned long)sides[2 * i + 1] + 1) > 0;
    }
    ok &= fputs("$EndElements\n", fp) >= 0;
    free(sides);
    return ok ? FEMLOD_OK : fl_io_write_error(path, err);
}

/* }====== */
