/* io_off.c - Object File Format (Geomview's OFF, as CGAL and MeshLab write it).
 *
 * Header keyword [ST][C][N]OFF, then "nv nf ne" (on the keyword's line or
 * later), nv vertex records and nf face records "k i0 .. ik-1" with 0-based
 * indices. Values after x y z (normals, colours, texture coordinates) and
 * after a face's indices (its colour) are read as numbers and dropped; only
 * the rest of their own line counts as such, since COFF colours may have
 * three or four components. '#' starts a comment anywhere. */
#include "io_util.h"

#include <stdlib.h>
#include <string.h>

/* Counts saturate here: far past any count that fits, and the messages
 * print the saturated value. */
#define COUNT_CAP (UINT64_C(1) << 40)

static femlod_status read_count(fl_text *r, const char *what, uint64_t *v) {
    size_t n;
    const char *s = fl_text_next(r, &n);
    char q[48];
    if (!s)
        return fl_text_fail(r, FEMLOD_EPARSE, "expected the %s count, found the end of the file",
                            what);
    if (!fl_io_uint(s, n, COUNT_CAP, v))
        return fl_text_fail(r, FEMLOD_EPARSE, "bad %s count '%s'", what,
                            fl_io_quote(q, sizeof q, s, n));
    return FEMLOD_OK;
}

/* Drops the numbers left on the current line (colours and the like). */
static femlod_status skip_extras(fl_text *r) {
    size_t n;
    const char *s;
    char why[128];
    while ((s = fl_text_line_next(r, &n))) {
        double x;
        if (!fl_io_number(s, n, &x, why, sizeof why))
            return fl_text_fail(r, FEMLOD_EPARSE, "%s", why);
    }
    return FEMLOD_OK;
}

static femlod_status read_header(fl_text *r, uint64_t *nv, uint64_t *nf) {
    size_t n;
    char q[48];
    const char *s = fl_text_next(r, &n);
    if (!s) return fl_error(r->err, FEMLOD_EPARSE, "%s: empty file", r->name);
    size_t i = 0;
    if (n - i >= 2 && s[i] == 'S' && s[i + 1] == 'T') i += 2;
    if (i < n && s[i] == 'C') i++;
    if (i < n && s[i] == 'N') i++;
    if (i < n && (s[i] == '4' || s[i] == 'n'))
        return fl_text_fail(r, FEMLOD_EUNSUPPORTED, "'%s': only 3-dimensional OFF is supported",
                            fl_io_quote(q, sizeof q, s, n));
    if (n - i != 3 || memcmp(s + i, "OFF", 3) != 0)
        return fl_text_fail(r, FEMLOD_EPARSE, "expected the 'OFF' header, found '%s'",
                            fl_io_quote(q, sizeof q, s, n));
    const char *t = fl_text_line_next(r, &n);
    if (t) {
        if (n == 6 && memcmp(t, "BINARY", 6) == 0)
            return fl_text_fail(r, FEMLOD_EUNSUPPORTED, "binary OFF is not supported");
        r->p = t; /* the counts share the header's line */
    }
    uint64_t ne;
    femlod_status st;
    if ((st = read_count(r, "vertex", nv)) != FEMLOD_OK) return st;
    if ((st = read_count(r, "face", nf)) != FEMLOD_OK) return st;
    if ((st = read_count(r, "edge", &ne)) != FEMLOD_OK) return st;
    if (*nv > UINT32_MAX || *nf > UINT32_MAX)
        return fl_text_fail(r, FEMLOD_ELIMIT,
                            "header declares %llu vertices and %llu faces (limit %u)",
                            (unsigned long long)*nv, (unsigned long long)*nf, (unsigned)UINT32_MAX);
    /* Bound memory by the data present, before reserving anything: a vertex
     * takes at least "0 0 0\n", a face at least "3 0 0 0\n". */
    uint64_t least = *nv * 6 + *nf * 8, left = (uint64_t)(r->end - r->p);
    if (least > left + 1)
        return fl_text_fail(
            r, FEMLOD_EPARSE,
            "header declares %llu vertices and %llu faces, but only %llu bytes follow",
            (unsigned long long)*nv, (unsigned long long)*nf, (unsigned long long)left);
    return FEMLOD_OK;
}

static femlod_status parse(fl_text *r, fl_meshbuf *b) {
    uint64_t nv, nf;
    femlod_status st = read_header(r, &nv, &nf);
    if (st != FEMLOD_OK) return st;
    if (!fl_meshbuf_reserve(b, (size_t)nv, (size_t)nf))
        return fl_text_fail(r, FEMLOD_ENOMEM, "out of memory for %llu vertices",
                            (unsigned long long)nv);
    char why[128], q[48];
    size_t n;
    const char *s;
    for (uint64_t i = 0; i < nv; i++) {
        double c[3];
        for (int k = 0; k < 3; k++) {
            if (!(s = fl_text_next(r, &n)))
                return fl_text_fail(r, FEMLOD_EPARSE, "file ends after %llu of %llu vertices",
                                    (unsigned long long)i, (unsigned long long)nv);
            if (!fl_io_coord(s, n, &c[k], why, sizeof why))
                return fl_text_fail(r, FEMLOD_EPARSE, "%s", why);
        }
        if ((st = skip_extras(r)) != FEMLOD_OK) return st;
        if (!fl_meshbuf_add_vertex(b, c[0], c[1], c[2]))
            return fl_text_fail(r, FEMLOD_ENOMEM, "out of memory");
    }
    for (uint64_t f = 0; f < nf; f++) {
        if (!(s = fl_text_next(r, &n)))
            return fl_text_fail(r, FEMLOD_EPARSE, "file ends after %llu of %llu faces",
                                (unsigned long long)f, (unsigned long long)nf);
        uint64_t k;
        if (!fl_io_uint(s, n, COUNT_CAP, &k))
            return fl_text_fail(r, FEMLOD_EPARSE, "bad face vertex count '%s'",
                                fl_io_quote(q, sizeof q, s, n));
        if (k < 3)
            return fl_text_fail(r, FEMLOD_EPARSE, "face has %llu vertices (at least 3 needed)",
                                (unsigned long long)k);
        fl_io_fan fan = {0, 0, 0};
        for (uint64_t j = 0; j < k; j++) {
            if (!(s = fl_text_next(r, &n)))
                return fl_text_fail(
                    r, FEMLOD_EPARSE, "file ends inside face %llu (%llu of %llu indices)",
                    (unsigned long long)f + 1, (unsigned long long)j, (unsigned long long)k);
            uint64_t idx;
            if (!fl_io_uint(s, n, COUNT_CAP, &idx))
                return fl_text_fail(r, FEMLOD_EPARSE, "bad face index '%s'",
                                    fl_io_quote(q, sizeof q, s, n));
            if (idx >= nv)
                return fl_text_fail(r, FEMLOD_EPARSE, "face index %s out of range (%llu vertices)",
                                    fl_io_quote(q, sizeof q, s, n), (unsigned long long)nv);
            st = fl_io_fan_add(b, &fan, (uint32_t)idx);
            if (st == FEMLOD_ELIMIT)
                return fl_text_fail(r, st, "too many triangles (limit %u)", (unsigned)UINT32_MAX);
            if (st != FEMLOD_OK) return fl_text_fail(r, st, "out of memory");
        }
        if ((st = skip_extras(r)) != FEMLOD_OK) return st;
    }
    /* More data means the header's counts are wrong: say so rather than
     * silently drop part of the mesh. */
    if ((s = fl_text_next(r, &n)))
        return fl_text_fail(r, FEMLOD_EPARSE, "data after the last of %llu faces: '%s'",
                            (unsigned long long)nf, fl_io_quote(q, sizeof q, s, n));
    return FEMLOD_OK;
}

femlod_status fl_read_off(femlod_mesh **out, const char *data, size_t size, const char *name,
                          femlod_error *err) {
    fl_text r;
    fl_text_init(&r, data, size, name, '#', err);
    fl_meshbuf b;
    memset(&b, 0, sizeof b);
    return fl_io_finish(&b, parse(&r, &b), out, name, err);
}

/* {====== writer */

femlod_status fl_write_off(const femlod_mesh *m, FILE *fp) {
    /* No comment line: some OFF readers take none. */
    if (fprintf(fp, "OFF\n%zu %zu 0\n", m->nv, m->nt) < 0) return FEMLOD_EIO;
    return fl_io_put_vertex_face_lines(m, fp);
}

/* }====== */
