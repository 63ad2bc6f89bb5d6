/* io_medit.c - Medit (INRIA, P. J. Frey, "MEDIT: an interactive mesh
 * visualization software", RT-0253), ASCII, as TetGen (-p on a .mesh) and
 * MMG read it.
 *
 * Writing: MeshVersionFormatted 2 (double precision), Dimension 3,
 * Vertices with ref 0, Triangles (1-based) with ref 1, End.
 * Reading: keywords in any order, case-insensitive, '#' comments; Vertices
 * (x y z ref) and Triangles (i j k ref) are kept, refs dropped; the other
 * element sections (Edges, Tetrahedra, Corners, Normals...) are skipped by
 * their known record sizes; quadrilaterals are refused (they would leave
 * holes), as are 2-D files and unknown keywords. */
#include "io_util.h"

#include <stdlib.h>
#include <string.h>

/* {====== reader */

static int is_word(const char *s, size_t n, const char *word) {
    size_t k = strlen(word);
    if (n != k) return 0;
    for (size_t i = 0; i < n; i++) {
        char c = s[i], w = word[i];
        if (c >= 'A' && c <= 'Z') c = (char)(c + ('a' - 'A'));
        if (w >= 'A' && w <= 'Z') w = (char)(w + ('a' - 'A'));
        if (c != w) return 0;
    }
    return 1;
}

/* Sections skipped, with the numbers each record holds. */
static const struct {
    const char *word;
    unsigned values;
} skipped[] = {
    {"Edges", 3},         {"Tetrahedra", 5},        {"Hexahedra", 9},      {"Prisms", 7},
    {"Pyramids", 6},      {"Corners", 1},           {"Ridges", 1},         {"RequiredVertices", 1},
    {"RequiredEdges", 1}, {"RequiredTriangles", 1}, {"Normals", 3},        {"NormalAtVertices", 2},
    {"Tangents", 3},      {"TangentAtVertices", 2}, {"TangentAtEdges", 3}, {"Identifier", 0},
};

typedef struct medit_reader {
    fl_text t;
    fl_meshbuf b;
    int dimension, have_vertices;
} medit_reader;

static femlod_status count_of(medit_reader *r, const char *what, uint64_t *v, size_t least) {
    size_t n;
    char q[48];
    const char *s = fl_text_next(&r->t, &n);
    if (!s)
        return fl_text_fail(&r->t, FEMLOD_EPARSE, "file ends where the %s count was expected",
                            what);
    if (!fl_text_u64(s, n, v))
        return fl_text_fail(&r->t, FEMLOD_EPARSE, "bad %s count '%s'", what,
                            fl_io_quote(q, sizeof q, s, n));
    if (*v > UINT32_MAX)
        return fl_text_fail(&r->t, FEMLOD_ELIMIT, "%llu %s (limit %u)", (unsigned long long)*v,
                            what, (unsigned)UINT32_MAX);
    uint64_t left = (uint64_t)(r->t.end - r->t.p);
    if (*v * least > left + 1)
        return fl_text_fail(&r->t, FEMLOD_EPARSE, "%llu %s declared, but only %llu bytes follow",
                            (unsigned long long)*v, what, (unsigned long long)left);
    return FEMLOD_OK;
}

static femlod_status value(medit_reader *r, const char *what, uint64_t item, const char **s,
                           size_t *n) {
    if (!(*s = fl_text_next(&r->t, n)))
        return fl_text_fail(&r->t, FEMLOD_EPARSE, "file ends inside %s %llu", what,
                            (unsigned long long)item + 1);
    return FEMLOD_OK;
}

/* A ref or another integer whose value is not kept. */
static femlod_status integer(medit_reader *r, const char *what, uint64_t item) {
    const char *s;
    size_t n;
    char q[48];
    uint64_t v;
    femlod_status st = value(r, what, item, &s, &n);
    if (st != FEMLOD_OK) return st;
    if (n > 1 && s[0] == '-') s++, n--;
    if (!fl_text_u64(s, n, &v))
        return fl_text_fail(&r->t, FEMLOD_EPARSE, "bad integer '%s' in %s %llu",
                            fl_io_quote(q, sizeof q, s, n), what, (unsigned long long)item + 1);
    return FEMLOD_OK;
}

static femlod_status vertices(medit_reader *r) {
    uint64_t count;
    femlod_status st = count_of(r, "vertices", &count, 8);
    if (st != FEMLOD_OK) return st;
    if (r->have_vertices)
        return fl_text_fail(&r->t, FEMLOD_EUNSUPPORTED, "a second Vertices section");
    r->have_vertices = 1;
    if (!fl_meshbuf_reserve(&r->b, (size_t)count, 0))
        return fl_text_fail(&r->t, FEMLOD_ENOMEM, "out of memory for %llu vertices",
                            (unsigned long long)count);
    char why[128];
    for (uint64_t i = 0; i < count; i++) {
        double c[3];
        for (int k = 0; k < 3; k++) {
            const char *s;
            size_t n;
            if ((st = value(r, "vertex", i, &s, &n)) != FEMLOD_OK) return st;
            if (!fl_io_coord(s, n, &c[k], why, sizeof why))
                return fl_text_fail(&r->t, FEMLOD_EPARSE, "%s", why);
        }
        if ((st = integer(r, "vertex", i)) != FEMLOD_OK) return st;
        if (!fl_meshbuf_add_vertex(&r->b, c[0], c[1], c[2]))
            return fl_text_fail(&r->t, FEMLOD_ENOMEM, "out of memory");
    }
    return FEMLOD_OK;
}

static femlod_status triangles(medit_reader *r) {
    uint64_t count;
    femlod_status st = count_of(r, "triangles", &count, 8);
    if (st != FEMLOD_OK) return st;
    if (!r->have_vertices) return fl_text_fail(&r->t, FEMLOD_EPARSE, "Triangles before Vertices");
    if (!fl_meshbuf_reserve(&r->b, r->b.nv, r->b.nt + (size_t)count))
        return fl_text_fail(&r->t, FEMLOD_ENOMEM, "out of memory for %llu triangles",
                            (unsigned long long)count);
    char q[48];
    for (uint64_t i = 0; i < count; i++) {
        uint32_t v[3];
        for (int k = 0; k < 3; k++) {
            const char *s;
            size_t n;
            uint64_t idx;
            if ((st = value(r, "triangle", i, &s, &n)) != FEMLOD_OK) return st;
            if (!fl_text_u64(s, n, &idx))
                return fl_text_fail(&r->t, FEMLOD_EPARSE, "bad vertex index '%s'",
                                    fl_io_quote(q, sizeof q, s, n));
            if (idx == 0 || idx > r->b.nv)
                return fl_text_fail(&r->t, FEMLOD_EPARSE, "vertex index %llu out of range (1..%zu)",
                                    (unsigned long long)idx, r->b.nv);
            v[k] = (uint32_t)(idx - 1);
        }
        if ((st = integer(r, "triangle", i)) != FEMLOD_OK) return st;
        if (r->b.nt >= UINT32_MAX)
            return fl_text_fail(&r->t, FEMLOD_ELIMIT, "too many triangles (limit %u)",
                                (unsigned)UINT32_MAX);
        if (!fl_meshbuf_add_triangle(&r->b, v[0], v[1], v[2]))
            return fl_text_fail(&r->t, FEMLOD_ENOMEM, "out of memory");
    }
    return FEMLOD_OK;
}

static femlod_status parse(medit_reader *r) {
    size_t n;
    char q[48];
    const char *s = fl_text_next(&r->t, &n);
    if (!s) return fl_error(r->t.err, FEMLOD_EPARSE, "%s: empty file", r->t.name);
    if (!is_word(s, n, "MeshVersionFormatted"))
        return fl_text_fail(&r->t, FEMLOD_EPARSE, "expected 'MeshVersionFormatted', found '%s'",
                            fl_io_quote(q, sizeof q, s, n));
    uint64_t version;
    femlod_status st;
    if ((st = count_of(r, "version", &version, 0)) != FEMLOD_OK) return st;
    if (version < 1 || version > 2)
        return fl_text_fail(&r->t, FEMLOD_EUNSUPPORTED,
                            "MeshVersionFormatted %llu (1 and 2 are read)",
                            (unsigned long long)version);
    int ended = 0;
    while (!ended && (s = fl_text_next(&r->t, &n))) {
        if (is_word(s, n, "Dimension")) {
            uint64_t d;
            if ((st = count_of(r, "dimension", &d, 0)) != FEMLOD_OK) return st;
            if (d != 3)
                return fl_text_fail(&r->t, FEMLOD_EUNSUPPORTED, "Dimension %llu (only 3 is read)",
                                    (unsigned long long)d);
            r->dimension = 3;
            continue;
        }
        if (is_word(s, n, "End")) {
            ended = 1;
            break;
        }
        if (!r->dimension && !is_word(s, n, "Identifier"))
            return fl_text_fail(&r->t, FEMLOD_EPARSE, "'%s' before 'Dimension'",
                                fl_io_quote(q, sizeof q, s, n));
        if (is_word(s, n, "Vertices")) {
            st = vertices(r);
        } else if (is_word(s, n, "Triangles")) {
            st = triangles(r);
        } else if (is_word(s, n, "Quadrilaterals")) {
            return fl_text_fail(&r->t, FEMLOD_EUNSUPPORTED,
                                "Quadrilaterals are not supported: the surface must be triangles");
        } else {
            size_t k = 0, nk = sizeof skipped / sizeof skipped[0];
            while (k < nk && !is_word(s, n, skipped[k].word)) k++;
            if (k == nk)
                return fl_text_fail(&r->t, FEMLOD_EUNSUPPORTED, "unknown keyword '%s'",
                                    fl_io_quote(q, sizeof q, s, n));
            if (skipped[k].values == 0) { /* Identifier: a quoted string to the end of the line */
                const char *nl = memchr(r->t.p, '\n', (size_t)(r->t.end - r->t.p));
                r->t.p = nl ? nl : r->t.end;
                continue;
            }
            uint64_t count;
            if ((st = count_of(r, skipped[k].word, &count, 2 * skipped[k].values)) != FEMLOD_OK)
                return st;
            for (uint64_t i = 0; i < count * skipped[k].values; i++) {
                const char *v;
                size_t vn;
                char *e;
                if ((st = value(r, skipped[k].word, i / skipped[k].values, &v, &vn)) != FEMLOD_OK)
                    return st;
                fl_strtod(v, &e);
                if (e != v + vn)
                    return fl_text_fail(&r->t, FEMLOD_EPARSE, "bad number '%s'",
                                        fl_io_quote(q, sizeof q, v, vn));
            }
        }
        if (st != FEMLOD_OK) return st;
    }
    if (!ended) return fl_text_fail(&r->t, FEMLOD_EPARSE, "file ends without 'End'");
    if ((s = fl_text_next(&r->t, &n)))
        return fl_text_fail(&r->t, FEMLOD_EPARSE, "data after 'End': '%s'",
                            fl_io_quote(q, sizeof q, s, n));
    return FEMLOD_OK;
}

femlod_status fl_read_medit(femlod_mesh **out, const char *data, size_t size, const char *name,
                            femlod_error *err) {
    medit_reader r;
    memset(&r, 0, sizeof r);
    fl_text_init(&r.t, data, size, name, '#', err);
    return fl_io_finish(&r.b, parse(&r), out, name, err);
}

/* }====== */

/* {====== writer */

femlod_status fl_write_medit(const femlod_mesh *m, FILE *fp, const char *path, femlod_error *err) {
    int ok = fprintf(fp, "MeshVersionFormatted 2\nDimension 3\n") > 0;
    if (m->nv) ok &= fprintf(fp, "Vertices\n%zu\n", m->nv) > 0;
    for (size_t i = 0; i < m->nv && ok; i++) ok &= fl_io_put_xyz(fp, m->pos + 3 * i, " ", " 0\n");
    if (m->nt) ok &= fprintf(fp, "Triangles\n%zu\n", m->nt) > 0;
    for (size_t i = 0; i < m->nt && ok; i++) {
        const uint32_t *t = m->tri + 3 * i;
        ok &= fprintf(fp, "%lu %lu %lu 1\n", (unsigned long)t[0] + 1, (unsigned long)t[1] + 1,
                      (unsigned long)t[2] + 1) > 0;
    }
    ok &= fputs("End\n", fp) >= 0;
    return ok ? FEMLOD_OK : fl_io_write_error(path, err);
}

/* }====== */
