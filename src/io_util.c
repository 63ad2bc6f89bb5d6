/* io_util.c - owns what the format readers and writers share (io_util.h):
 * quoting and number checks for messages, the line-counting token reader,
 * "FILE:LINE:" and "FILE: byte N:" errors, fan triangulation, a reader's
 * hand-over of its arrays, boundary sides for the FE writers and the text
 * output of coordinates. Below the io_*.c files and io.c: it calls only the
 * core units under them (error.c, mesh.c, adjacency.c, fileio.c). */
#include "io_util.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* {====== tokens and numbers in messages */

const char *fl_io_quote(char *buf, size_t size, const char *s, size_t n) {
    enum { MAX = 40 };
    if (size == 0) return buf;
    size_t keep = n > MAX ? MAX : n;
    if (keep > size - 1) keep = size - 1;
    for (size_t i = 0; i < keep; i++) {
        unsigned char c = (unsigned char)s[i];
        buf[i] = (c >= 0x20 && c < 0x7F) ? (char)c : '?';
    }
    buf[keep] = '\0';
    if (keep < n && size > 4) {
        size_t at = keep > size - 4 ? size - 4 : keep;
        memcpy(buf + at, "...", 4);
    }
    return buf;
}

int fl_io_number(const char *s, size_t n, double *out, char *why, size_t why_size) {
    char q[48];
    char *end;
    double x = fl_strtod(s, &end);
    if (n == 0 || end != s + n) {
        snprintf(why, why_size, "bad number '%s'", fl_io_quote(q, sizeof q, s, n));
        return 0;
    }
    *out = x;
    return 1;
}

static int lower(int c) { return (c >= 'A' && c <= 'Z') ? c + ('a' - 'A') : c; }

int fl_io_coord(const char *s, size_t n, double *out, char *why, size_t why_size) {
    char q[48];
    double x;
    if (!fl_io_number(s, n, &x, why, why_size)) return 0;
    if (isnan(x) || (isinf(x) && lower((unsigned char)s[s[0] == '-' || s[0] == '+']) == 'i')) {
        snprintf(why, why_size, "coordinate '%s' is not finite", fl_io_quote(q, sizeof q, s, n));
        return 0;
    }
    if (isinf(x)) {
        snprintf(why, why_size, "coordinate '%s' is out of range", fl_io_quote(q, sizeof q, s, n));
        return 0;
    }
    *out = x;
    return 1;
}

int fl_io_uint(const char *s, size_t n, uint64_t cap, uint64_t *v) {
    if (n == 0) return 0;
    uint64_t x = 0;
    for (size_t i = 0; i < n; i++) {
        if (s[i] < '0' || s[i] > '9') return 0;
        if (x < cap) x = x * 10 + (uint64_t)(s[i] - '0');
    }
    *v = x;
    return 1;
}

/* }====== */

/* {====== errors */

femlod_status fl_io_vfail_line(femlod_error *err, femlod_status st, const char *name, size_t line,
                               const char *fmt, va_list ap) {
    char msg[FEMLOD_ERROR_MESSAGE_SIZE];
    vsnprintf(msg, sizeof msg, fmt, ap);
    return fl_error(err, st, "%s:%zu: %s", name, line, msg);
}

femlod_status fl_io_vfail_byte(femlod_error *err, const char *name, size_t byte, const char *fmt,
                               va_list ap) {
    char msg[FEMLOD_ERROR_MESSAGE_SIZE];
    vsnprintf(msg, sizeof msg, fmt, ap);
    return fl_error(err, FEMLOD_EPARSE, "%s: byte %zu: %s", name, byte, msg);
}

femlod_status fl_io_write_error(const char *path, femlod_error *err) {
    int e = errno;
    return fl_error(err, FEMLOD_EIO, "%s: cannot write: %s", path, strerror(e ? e : EIO));
}

/* }====== */

/* {====== the token reader */

void fl_text_init(fl_text *t, const char *data, size_t size, const char *name, char comment,
                  femlod_error *err) {
    if (size >= 3 && memcmp(data, "\xEF\xBB\xBF", 3) == 0) {
        data += 3;
        size -= 3;
    }
    t->p = t->start = data;
    t->end = data + size;
    t->name = name;
    t->line = 1;
    t->err = err;
    t->eof = 0;
    t->comment = comment;
}

static int text_space(char c) { return c == ' ' || (c >= '\t' && c <= '\r'); }

/* The token at p, which is neither space nor a comment; advances past it. */
static const char *text_token(fl_text *t, const char *p, size_t *len) {
    const char *s = p, *end = t->end;
    while (p < end && !text_space(*p) && !(t->comment && *p == t->comment)) p++;
    *len = (size_t)(p - s);
    t->p = p;
    return s;
}

const char *fl_text_next(fl_text *t, size_t *len) {
    const char *p = t->p, *end = t->end;
    for (;;) {
        while (p < end && text_space(*p) && *p != '\n') p++;
        if (p == end) break;
        if (*p == '\n') {
            t->line++;
            p++;
        } else if (t->comment && *p == t->comment) {
            const char *nl = memchr(p, '\n', (size_t)(end - p));
            p = nl ? nl : end;
        } else {
            return text_token(t, p, len);
        }
    }
    /* Name the file's last line, not the empty one after its final newline. */
    if (!t->eof && end > t->start && end[-1] == '\n') t->line--;
    t->eof = 1;
    t->p = end;
    return NULL;
}

const char *fl_text_line_next(fl_text *t, size_t *len) {
    const char *p = t->p, *end = t->end;
    while (p < end && text_space(*p) && *p != '\n') p++;
    if (p < end && t->comment && *p == t->comment) {
        const char *nl = memchr(p, '\n', (size_t)(end - p));
        p = nl ? nl : end;
    }
    t->p = p;
    if (p == end || *p == '\n') return NULL;
    return text_token(t, p, len);
}

femlod_status fl_text_fail(fl_text *t, femlod_status st, const char *fmt, ...) {
    va_list ap;
    va_start(ap, fmt);
    femlod_status s = fl_io_vfail_line(t->err, st, t->name, t->line, fmt, ap);
    va_end(ap);
    return s;
}

int fl_text_u64(const char *s, size_t n, uint64_t *v) {
    return fl_io_uint(s, n, UINT64_C(1) << 60, v);
}

int fl_text_is(const char *s, size_t n, const char *word) {
    size_t k = strlen(word);
    return n == k && memcmp(s, word, k) == 0;
}

/* }====== */

/* {====== building the mesh */

femlod_status fl_io_fan_add(fl_meshbuf *b, fl_io_fan *f, uint32_t v) {
    f->count++;
    if (f->count == 1) {
        f->first = v;
    } else if (f->count == 2) {
        f->prev = v;
    } else {
        if (b->nt >= UINT32_MAX) return FEMLOD_ELIMIT;
        if (!fl_meshbuf_add_triangle(b, f->first, f->prev, v)) return FEMLOD_ENOMEM;
        f->prev = v;
    }
    return FEMLOD_OK;
}

femlod_status fl_io_finish(fl_meshbuf *b, femlod_status st, femlod_mesh **out, const char *name,
                           femlod_error *err) {
    if (st == FEMLOD_OK) {
        femlod_mesh *m = fl_meshbuf_finish(b);
        if (!m)
            st = fl_error(err, FEMLOD_ENOMEM, "%s: out of memory", name);
        else
            *out = m;
    }
    fl_meshbuf_free(b);
    return st;
}

femlod_status fl_io_boundary_sides(const femlod_mesh *m, uint32_t **sides, size_t *count,
                                   femlod_error *err) {
    fl_adjacency adj;
    femlod_status st = fl_adjacency_build(&adj, m->tri, m->nt, m->nv, err);
    if (st != FEMLOD_OK) return st;
    size_t n = 0;
    for (size_t e = 0; e < adj.ne; e++) n += adj.edge_start[e + 1] - adj.edge_start[e] == 1;
    uint32_t *out = fl_alloc(2 * n, sizeof *out);
    if (!out) {
        fl_adjacency_free(&adj);
        return fl_error(err, FEMLOD_ENOMEM, "out of memory");
    }
    size_t k = 0;
    for (size_t t = 0; t < m->nt; t++)
        for (int c = 0; c < 3; c++) {
            uint32_t e = adj.tri_edges[3 * t + (size_t)c];
            if (e == UINT32_MAX || adj.edge_start[e + 1] - adj.edge_start[e] != 1) continue;
            out[2 * k] = m->tri[3 * t + (size_t)c];
            out[2 * k + 1] = m->tri[3 * t + (size_t)(c + 1) % 3];
            k++;
        }
    fl_adjacency_free(&adj);
    *sides = out;
    *count = k;
    return FEMLOD_OK;
}

/* }====== */

/* {====== text output */

/* x, y and z separated by sep (at most 16 bytes) into buf; the length in
 * *len. 0 when a number did not fit its 32 bytes (never for a double). */
static int format_xyz(char *buf, const double *p, const char *sep, size_t ls, size_t *len) {
    size_t n = 0;
    int ok = 1;
    for (int k = 0; k < 3; k++) {
        if (k) {
            memcpy(buf + n, sep, ls);
            n += ls;
        }
        int w = fl_format_double(buf + n, 32, p[k]);
        if (w < 0) ok = 0;
        n += w > 0 ? (size_t)w : 0;
    }
    *len = n;
    return ok;
}

size_t fl_io_format_xyz(char *buf, const double *p) {
    size_t n;
    format_xyz(buf, p, " ", 1, &n);
    buf[n] = '\0';
    return n;
}

int fl_io_put_xyz(FILE *fp, const double *p, const char *sep, const char *end) {
    char buf[160];
    size_t n, ls = strlen(sep), le = strlen(end);
    if (ls > 16 || le > 16 || !format_xyz(buf, p, sep, ls, &n)) return 0;
    memcpy(buf + n, end, le);
    n += le;
    return fwrite(buf, 1, n, fp) == n;
}

femlod_status fl_io_put_vertex_face_lines(const femlod_mesh *m, FILE *fp) {
    for (size_t i = 0; i < m->nv; i++)
        if (!fl_io_put_xyz(fp, m->pos + 3 * i, " ", "\n")) return FEMLOD_EIO;
    for (size_t i = 0; i < m->nt; i++) {
        const uint32_t *t = m->tri + 3 * i;
        if (fprintf(fp, "3 %lu %lu %lu\n", (unsigned long)t[0], (unsigned long)t[1],
                    (unsigned long)t[2]) < 0)
            return FEMLOD_EIO;
    }
    return FEMLOD_OK;
}

/* }====== */
