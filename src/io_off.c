/* io_off.c - Object File Format (Geomview's OFF, as CGAL and MeshLab write it).
 *
 * Header keyword [ST][C][N]OFF, then "nv nf ne" (on the keyword's line or
 * later), nv vertex records and nf face records "k i0 .. ik-1" with 0-based
 * indices. Values after x y z (normals, colours, texture coordinates) and
 * after a face's indices (its colour) are read as numbers and dropped; only
 * the rest of their own line counts as such, since COFF colours may have
 * three or four components. '#' starts a comment anywhere. */
#include "core.h"

#include <stdlib.h>
#include <string.h>

typedef struct off_reader {
    const char *p, *end, *start;
    const char *name;
    size_t line;
    femlod_error *err;
    int eof;
} off_reader;

static femlod_status fail(off_reader *r, femlod_status st, const char *fmt, ...) FL_PRINTF(3, 4);
static femlod_status fail(off_reader *r, femlod_status st, const char *fmt, ...) {
    char msg[FEMLOD_ERROR_MESSAGE_SIZE];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    return fl_error(r->err, st, "%s:%zu: %s", r->name, r->line, msg);
}

static int is_blank(char c) { return c == ' ' || c == '\t' || c == '\v' || c == '\f' || c == '\r'; }

static const char *scan_token(off_reader *r, const char *p, size_t *len) {
    const char *s = p;
    while (p < r->end && !is_blank(*p) && *p != '\n' && *p != '#') p++;
    *len = (size_t)(p - s);
    r->p = p;
    return s;
}

/* The next token on any line; NULL at the end of the data. */
static const char *token(off_reader *r, size_t *len) {
    const char *p = r->p, *end = r->end;
    for (;;) {
        while (p < end && is_blank(*p)) p++;
        if (p == end) break;
        if (*p == '\n') {
            r->line++;
            p++;
        } else if (*p == '#') {
            const char *nl = memchr(p, '\n', (size_t)(end - p));
            p = nl ? nl : end;
        } else {
            return scan_token(r, p, len);
        }
    }
    /* Name the file's last line, not the empty one after its final newline. */
    if (!r->eof && end > r->start && end[-1] == '\n') r->line--;
    r->eof = 1;
    r->p = end;
    return NULL;
}

/* The next token on the current line; NULL at its end (the newline stays). */
static const char *line_token(off_reader *r, size_t *len) {
    const char *p = r->p, *end = r->end;
    while (p < end && is_blank(*p)) p++;
    if (p < end && *p == '#') {
        const char *nl = memchr(p, '\n', (size_t)(end - p));
        p = nl ? nl : end;
    }
    r->p = p;
    if (p == end || *p == '\n') return NULL;
    return scan_token(r, p, len);
}

/* Unsigned decimal integer token; 0 when malformed; saturates past 2^40. */
static int parse_count(const char *s, size_t n, uint64_t *v) {
    if (n == 0) return 0;
    uint64_t x = 0;
    for (size_t i = 0; i < n; i++) {
        if (s[i] < '0' || s[i] > '9') return 0;
        if (x < (UINT64_C(1) << 40)) x = x * 10 + (uint64_t)(s[i] - '0');
    }
    *v = x;
    return 1;
}

static femlod_status read_count(off_reader *r, const char *what, uint64_t *v) {
    size_t n;
    const char *s = token(r, &n);
    char q[48];
    if (!s) return fail(r, FEMLOD_EPARSE, "expected the %s count, found the end of the file", what);
    if (!parse_count(s, n, v))
        return fail(r, FEMLOD_EPARSE, "bad %s count '%s'", what, fl_io_quote(q, sizeof q, s, n));
    return FEMLOD_OK;
}

/* Drops the numbers left on the current line (colours and the like). */
static femlod_status skip_extras(off_reader *r) {
    size_t n;
    const char *s;
    char q[48];
    while ((s = line_token(r, &n))) {
        char *e;
        fl_strtod(s, &e);
        if (e != s + n)
            return fail(r, FEMLOD_EPARSE, "bad number '%s'", fl_io_quote(q, sizeof q, s, n));
    }
    return FEMLOD_OK;
}

static femlod_status read_header(off_reader *r, uint64_t *nv, uint64_t *nf) {
    size_t n;
    char q[48];
    const char *s = token(r, &n);
    if (!s) return fl_error(r->err, FEMLOD_EPARSE, "%s: empty file", r->name);
    size_t i = 0;
    if (n - i >= 2 && s[i] == 'S' && s[i + 1] == 'T') i += 2;
    if (i < n && s[i] == 'C') i++;
    if (i < n && s[i] == 'N') i++;
    if (i < n && (s[i] == '4' || s[i] == 'n'))
        return fail(r, FEMLOD_EUNSUPPORTED, "'%s': only 3-dimensional OFF is supported",
                    fl_io_quote(q, sizeof q, s, n));
    if (n - i != 3 || memcmp(s + i, "OFF", 3) != 0)
        return fail(r, FEMLOD_EPARSE, "expected the 'OFF' header, found '%s'",
                    fl_io_quote(q, sizeof q, s, n));
    const char *t = line_token(r, &n);
    if (t) {
        if (n == 6 && memcmp(t, "BINARY", 6) == 0)
            return fail(r, FEMLOD_EUNSUPPORTED, "binary OFF is not supported");
        r->p = t; /* the counts share the header's line */
    }
    uint64_t ne;
    femlod_status st;
    if ((st = read_count(r, "vertex", nv)) != FEMLOD_OK) return st;
    if ((st = read_count(r, "face", nf)) != FEMLOD_OK) return st;
    if ((st = read_count(r, "edge", &ne)) != FEMLOD_OK) return st;
    if (*nv > UINT32_MAX || *nf > UINT32_MAX)
        return fail(r, FEMLOD_ELIMIT, "header declares %llu vertices and %llu faces (limit %u)",
                    (unsigned long long)*nv, (unsigned long long)*nf, (unsigned)UINT32_MAX);
    /* Bound memory by the data present, before reserving anything: a vertex
     * takes at least "0 0 0\n", a face at least "3 0 0 0\n". */
    uint64_t least = *nv * 6 + *nf * 8, left = (uint64_t)(r->end - r->p);
    if (least > left + 1)
        return fail(r, FEMLOD_EPARSE,
                    "header declares %llu vertices and %llu faces, but only %llu bytes follow",
                    (unsigned long long)*nv, (unsigned long long)*nf, (unsigned long long)left);
    return FEMLOD_OK;
}

static femlod_status parse(off_reader *r, fl_meshbuf *b) {
    uint64_t nv, nf;
    femlod_status st = read_header(r, &nv, &nf);
    if (st != FEMLOD_OK) return st;
    if (!fl_meshbuf_reserve(b, (size_t)nv, (size_t)nf))
        return fail(r, FEMLOD_ENOMEM, "out of memory for %llu vertices", (unsigned long long)nv);
    char why[128], q[48];
    size_t n;
    const char *s;
    for (uint64_t i = 0; i < nv; i++) {
        double c[3];
        for (int k = 0; k < 3; k++) {
            if (!(s = token(r, &n)))
                return fail(r, FEMLOD_EPARSE, "file ends after %llu of %llu vertices",
                            (unsigned long long)i, (unsigned long long)nv);
            if (!fl_io_coord(s, n, &c[k], why, sizeof why))
                return fail(r, FEMLOD_EPARSE, "%s", why);
        }
        if ((st = skip_extras(r)) != FEMLOD_OK) return st;
        if (!fl_meshbuf_add_vertex(b, c[0], c[1], c[2]))
            return fail(r, FEMLOD_ENOMEM, "out of memory");
    }
    for (uint64_t f = 0; f < nf; f++) {
        if (!(s = token(r, &n)))
            return fail(r, FEMLOD_EPARSE, "file ends after %llu of %llu faces",
                        (unsigned long long)f, (unsigned long long)nf);
        uint64_t k;
        if (!parse_count(s, n, &k))
            return fail(r, FEMLOD_EPARSE, "bad face vertex count '%s'",
                        fl_io_quote(q, sizeof q, s, n));
        if (k < 3)
            return fail(r, FEMLOD_EPARSE, "face has %llu vertices (at least 3 needed)",
                        (unsigned long long)k);
        uint32_t first = 0, prev = 0;
        for (uint64_t j = 0; j < k; j++) {
            if (!(s = token(r, &n)))
                return fail(r, FEMLOD_EPARSE, "file ends inside face %llu (%llu of %llu indices)",
                            (unsigned long long)f + 1, (unsigned long long)j,
                            (unsigned long long)k);
            uint64_t idx;
            if (!parse_count(s, n, &idx))
                return fail(r, FEMLOD_EPARSE, "bad face index '%s'",
                            fl_io_quote(q, sizeof q, s, n));
            if (idx >= nv)
                return fail(r, FEMLOD_EPARSE, "face index %s out of range (%llu vertices)",
                            fl_io_quote(q, sizeof q, s, n), (unsigned long long)nv);
            uint32_t v = (uint32_t)idx;
            if (j == 0) {
                first = v;
            } else if (j == 1) {
                prev = v;
            } else {
                if (b->nt >= UINT32_MAX)
                    return fail(r, FEMLOD_ELIMIT, "too many triangles (limit %u)",
                                (unsigned)UINT32_MAX);
                if (!fl_meshbuf_add_triangle(b, first, prev, v))
                    return fail(r, FEMLOD_ENOMEM, "out of memory");
                prev = v;
            }
        }
        if ((st = skip_extras(r)) != FEMLOD_OK) return st;
    }
    /* More data means the header's counts are wrong: say so rather than
     * silently drop part of the mesh. */
    if ((s = token(r, &n)))
        return fail(r, FEMLOD_EPARSE, "data after the last of %llu faces: '%s'",
                    (unsigned long long)nf, fl_io_quote(q, sizeof q, s, n));
    return FEMLOD_OK;
}

femlod_status fl_read_off(femlod_mesh **out, const char *data, size_t size, const char *name,
                          femlod_error *err) {
    if (size >= 3 && memcmp(data, "\xEF\xBB\xBF", 3) == 0) {
        data += 3;
        size -= 3;
    }
    off_reader r = {data, data + size, data, name, 1, err, 0};
    fl_meshbuf b;
    memset(&b, 0, sizeof b);
    femlod_status st = parse(&r, &b);
    if (st != FEMLOD_OK) {
        fl_meshbuf_free(&b);
        return st;
    }
    femlod_mesh *m = fl_meshbuf_finish(&b);
    if (!m) {
        fl_meshbuf_free(&b);
        return fl_error(err, FEMLOD_ENOMEM, "%s: out of memory", name);
    }
    *out = m;
    return FEMLOD_OK;
}

/* {====== writer */

static size_t format_xyz(char *buf, const double *p) {
    size_t n = 0;
    for (int k = 0; k < 3; k++) {
        if (k) buf[n++] = ' ';
        int w = fl_format_double(buf + n, 32, p[k]);
        n += w > 0 ? (size_t)w : 0;
    }
    buf[n] = '\0';
    return n;
}

femlod_status fl_write_off(const femlod_mesh *m, FILE *fp) {
    char line[128];
    /* No comment line: some OFF readers take none. */
    if (fprintf(fp, "OFF\n%zu %zu 0\n", m->nv, m->nt) < 0) return FEMLOD_EIO;
    for (size_t i = 0; i < m->nv; i++) {
        size_t n = format_xyz(line, m->pos + 3 * i);
        line[n++] = '\n';
        if (fwrite(line, 1, n, fp) != n) return FEMLOD_EIO;
    }
    for (size_t i = 0; i < m->nt; i++) {
        const uint32_t *t = m->tri + 3 * i;
        if (fprintf(fp, "3 %lu %lu %lu\n", (unsigned long)t[0], (unsigned long)t[1],
                    (unsigned long)t[2]) < 0)
            return FEMLOD_EIO;
    }
    return FEMLOD_OK;
}

/* }====== */
