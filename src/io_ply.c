/* io_ply.c - PLY (Greg Turk's Polygon File Format), ascii, binary_little_endian
 * and binary_big_endian.
 *
 * Any element order and any property types: element "vertex" supplies x, y, z
 * (any numeric type; other properties skipped), element "face" the list
 * property "vertex_indices" (or "vertex_index", as some scanners write it),
 * fan-triangulated; other properties and elements are skipped. Header
 * errors are "FILE:LINE:", binary data errors "FILE: byte N:". Declared
 * counts are compared with the bytes present before anything is reserved. */
#include "io_util.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

typedef enum ply_type { T_NONE, T_I8, T_U8, T_I16, T_U16, T_I32, T_U32, T_F32, T_F64 } ply_type;

static const struct {
    const char *name;
    ply_type type;
} type_names[] = {
    {"char", T_I8},   {"int8", T_I8},     {"uchar", T_U8},   {"uint8", T_U8},
    {"short", T_I16}, {"int16", T_I16},   {"ushort", T_U16}, {"uint16", T_U16},
    {"int", T_I32},   {"int32", T_I32},   {"uint", T_U32},   {"uint32", T_U32},
    {"float", T_F32}, {"float32", T_F32}, {"double", T_F64}, {"float64", T_F64},
};

static size_t type_size(ply_type t) {
    static const size_t size[] = {0, 1, 1, 2, 2, 4, 4, 4, 8};
    return size[t];
}

static int type_is_int(ply_type t) { return t != T_F32 && t != T_F64 && t != T_NONE; }

typedef enum ply_role { R_SKIP, R_X, R_Y, R_Z, R_INDICES } ply_role;

typedef struct ply_prop {
    ply_type type;       /* of the value, or of a list's entries */
    ply_type count_type; /* T_NONE for a scalar */
    ply_role role;
    const char *name;
    size_t name_len;
} ply_prop;

typedef struct ply_elem {
    const char *name;
    size_t name_len;
    uint64_t count;
    size_t line; /* of its "element" header line */
    size_t first_prop, nprops;
} ply_elem;

enum { ENC_ASCII, ENC_LE, ENC_BE };

typedef struct ply_reader {
    const char *data, *p, *end;
    const char *name;
    size_t line;
    femlod_error *err;
    int encoding;
    ply_elem *elems;
    size_t nelems, cap_elems;
    ply_prop *props;
    size_t nprops, cap_props;
    uint64_t nv; /* the vertex element's count: the range of face indices */
    fl_meshbuf b;
} ply_reader;

static femlod_status fail_line(ply_reader *r, size_t line, femlod_status st, const char *fmt, ...)
    FL_PRINTF(4, 5);
static femlod_status fail_line(ply_reader *r, size_t line, femlod_status st, const char *fmt, ...) {
    va_list ap;
    va_start(ap, fmt);
    st = fl_io_vfail_line(r->err, st, r->name, line, fmt, ap);
    va_end(ap);
    return st;
}

static femlod_status fail_byte(ply_reader *r, const char *at, const char *fmt, ...) FL_PRINTF(3, 4);
static femlod_status fail_byte(ply_reader *r, const char *at, const char *fmt, ...) {
    va_list ap;
    va_start(ap, fmt);
    femlod_status st = fl_io_vfail_byte(r->err, r->name, (size_t)(at - r->data), fmt, ap);
    va_end(ap);
    return st;
}

static int is_blank(char c) { return c == ' ' || c == '\t' || c == '\v' || c == '\f' || c == '\r'; }

static int word_is(const char *s, size_t n, const char *w) {
    return strlen(w) == n && memcmp(s, w, n) == 0;
}

/* {====== header */

/* Splits the header line [p, e) into at most max tokens; returns the count. */
static size_t split(const char *p, const char *e, const char **tok, size_t *len, size_t max) {
    size_t n = 0;
    for (;;) {
        while (p < e && is_blank(*p)) p++;
        if (p == e) return n;
        const char *s = p;
        while (p < e && !is_blank(*p)) p++;
        if (n < max) {
            tok[n] = s;
            len[n] = (size_t)(p - s);
        }
        n++;
    }
}

static ply_type parse_type(const char *s, size_t n) {
    for (size_t i = 0; i < sizeof type_names / sizeof type_names[0]; i++)
        if (word_is(s, n, type_names[i].name)) return type_names[i].type;
    return T_NONE;
}

static int grow(void **p, size_t *cap, size_t n, size_t elem) {
    if (n < *cap) return 1;
    size_t c = *cap ? 2 * *cap : 8;
    void *q = fl_realloc(*p, c, elem);
    if (!q) return 0;
    *p = q;
    *cap = c;
    return 1;
}

static femlod_status add_property(ply_reader *r, const char **tok, const size_t *len, size_t n) {
    char q[48];
    if (r->nelems == 0) return fail_line(r, r->line, FEMLOD_EPARSE, "property before any element");
    ply_prop prop = {T_NONE, T_NONE, R_SKIP, NULL, 0};
    size_t name_tok;
    if (n >= 2 && word_is(tok[1], len[1], "list")) {
        if (n != 5)
            return fail_line(r, r->line, FEMLOD_EPARSE,
                             "expected 'property list COUNT_TYPE TYPE NAME'");
        prop.count_type = parse_type(tok[2], len[2]);
        prop.type = parse_type(tok[3], len[3]);
        if (prop.count_type == T_NONE)
            return fail_line(r, r->line, FEMLOD_EPARSE, "unknown type '%s'",
                             fl_io_quote(q, sizeof q, tok[2], len[2]));
        if (prop.type == T_NONE)
            return fail_line(r, r->line, FEMLOD_EPARSE, "unknown type '%s'",
                             fl_io_quote(q, sizeof q, tok[3], len[3]));
        if (!type_is_int(prop.count_type))
            return fail_line(r, r->line, FEMLOD_EUNSUPPORTED,
                             "list count type '%s' is not an integer type",
                             fl_io_quote(q, sizeof q, tok[2], len[2]));
        name_tok = 4;
    } else {
        if (n != 3) return fail_line(r, r->line, FEMLOD_EPARSE, "expected 'property TYPE NAME'");
        prop.type = parse_type(tok[1], len[1]);
        if (prop.type == T_NONE)
            return fail_line(r, r->line, FEMLOD_EPARSE, "unknown type '%s'",
                             fl_io_quote(q, sizeof q, tok[1], len[1]));
        name_tok = 2;
    }
    prop.name = tok[name_tok];
    prop.name_len = len[name_tok];
    ply_elem *e = &r->elems[r->nelems - 1];
    for (size_t i = e->first_prop; i < r->nprops; i++)
        if (r->props[i].name_len == prop.name_len &&
            memcmp(r->props[i].name, prop.name, prop.name_len) == 0)
            return fail_line(r, r->line, FEMLOD_EPARSE, "duplicate property '%s'",
                             fl_io_quote(q, sizeof q, prop.name, prop.name_len));
    if (!grow((void **)&r->props, &r->cap_props, r->nprops, sizeof *r->props))
        return fail_line(r, r->line, FEMLOD_ENOMEM, "out of memory");
    r->props[r->nprops++] = prop;
    e->nprops++;
    return FEMLOD_OK;
}

static femlod_status read_header(ply_reader *r) {
    const char *tok[6];
    size_t len[6];
    char q[48];
    int have_format = 0;
    const char *p = r->p;
    if (p == r->end) return fl_error(r->err, FEMLOD_EPARSE, "%s: empty file", r->name);
    for (;; r->line++) {
        if (p == r->end)
            return fail_line(r, r->line - 1, FEMLOD_EPARSE,
                             "file ends inside the header (no 'end_header')");
        const char *nl = memchr(p, '\n', (size_t)(r->end - p));
        const char *e = nl ? nl : r->end;
        const char *next = nl ? nl + 1 : r->end;
        size_t n = split(p, e, tok, len, 6);
        r->p = next;
        p = next;
        if (r->line == 1) {
            if (n != 1 || !word_is(tok[0], len[0], "ply"))
                return fail_line(r, 1, FEMLOD_EPARSE,
                                 "not a PLY file (the first line must be 'ply')");
            continue;
        }
        if (n == 0) continue;
        if (word_is(tok[0], len[0], "comment") || word_is(tok[0], len[0], "obj_info")) continue;
        if (word_is(tok[0], len[0], "end_header")) {
            if (!have_format)
                return fail_line(r, r->line, FEMLOD_EPARSE, "no 'format' line before 'end_header'");
            r->line++;
            return FEMLOD_OK;
        }
        if (word_is(tok[0], len[0], "format")) {
            if (n != 3) return fail_line(r, r->line, FEMLOD_EPARSE, "expected 'format NAME 1.0'");
            if (have_format) return fail_line(r, r->line, FEMLOD_EPARSE, "second 'format' line");
            if (word_is(tok[1], len[1], "ascii")) {
                r->encoding = ENC_ASCII;
            } else if (word_is(tok[1], len[1], "binary_little_endian")) {
                r->encoding = ENC_LE;
            } else if (word_is(tok[1], len[1], "binary_big_endian")) {
                r->encoding = ENC_BE;
            } else {
                return fail_line(r, r->line, FEMLOD_EPARSE,
                                 "unknown format '%s' (ascii, binary_little_endian or "
                                 "binary_big_endian expected)",
                                 fl_io_quote(q, sizeof q, tok[1], len[1]));
            }
            if (!word_is(tok[2], len[2], "1.0"))
                return fail_line(r, r->line, FEMLOD_EUNSUPPORTED, "unsupported PLY version '%s'",
                                 fl_io_quote(q, sizeof q, tok[2], len[2]));
            have_format = 1;
        } else if (word_is(tok[0], len[0], "element")) {
            uint64_t count;
            if (n != 3)
                return fail_line(r, r->line, FEMLOD_EPARSE, "expected 'element NAME COUNT'");
            if (!fl_io_uint(tok[2], len[2], UINT64_C(1) << 40, &count))
                return fail_line(r, r->line, FEMLOD_EPARSE, "bad element count '%s'",
                                 fl_io_quote(q, sizeof q, tok[2], len[2]));
            if (!grow((void **)&r->elems, &r->cap_elems, r->nelems, sizeof *r->elems))
                return fail_line(r, r->line, FEMLOD_ENOMEM, "out of memory");
            r->elems[r->nelems++] = (ply_elem){tok[1], len[1], count, r->line, r->nprops, 0};
        } else if (word_is(tok[0], len[0], "property")) {
            femlod_status st = add_property(r, tok, len, n);
            if (st != FEMLOD_OK) return st;
        } else {
            return fail_line(r, r->line, FEMLOD_EPARSE, "unknown header line '%s'",
                             fl_io_quote(q, sizeof q, tok[0], len[0]));
        }
    }
}

static ply_prop *find_prop(ply_reader *r, const ply_elem *e, const char *name) {
    for (size_t i = 0; i < e->nprops; i++) {
        ply_prop *pr = &r->props[e->first_prop + i];
        if (word_is(pr->name, pr->name_len, name)) return pr;
    }
    return NULL;
}

/* Finds the vertex and face elements and marks the properties femlod reads. */
static femlod_status assign_roles(ply_reader *r) {
    const ply_elem *vert = NULL, *face = NULL;
    char q[48];
    for (size_t i = 0; i < r->nelems; i++) {
        const ply_elem *e = &r->elems[i];
        const ply_elem **slot = word_is(e->name, e->name_len, "vertex") ? &vert
                                : word_is(e->name, e->name_len, "face") ? &face
                                                                        : NULL;
        if (slot) {
            if (*slot)
                return fail_line(r, e->line, FEMLOD_EPARSE, "second element '%s'",
                                 fl_io_quote(q, sizeof q, e->name, e->name_len));
            *slot = e;
        } else if (word_is(e->name, e->name_len, "tristrips") && e->count > 0) {
            return fail_line(r, e->line, FEMLOD_EUNSUPPORTED, "triangle strips are not supported");
        }
    }
    if (!vert) return fail_line(r, r->line - 1, FEMLOD_EPARSE, "no element 'vertex' in the header");
    if (vert->count > UINT32_MAX)
        return fail_line(r, vert->line, FEMLOD_ELIMIT, "too many vertices: %llu (limit %u)",
                         (unsigned long long)vert->count, (unsigned)UINT32_MAX);
    r->nv = vert->count;
    static const char *const axes[] = {"x", "y", "z"};
    for (int k = 0; k < 3; k++) {
        ply_prop *pr = find_prop(r, vert, axes[k]);
        if (!pr)
            return fail_line(r, vert->line, FEMLOD_EPARSE, "element 'vertex' has no property '%s'",
                             axes[k]);
        if (pr->count_type != T_NONE)
            return fail_line(r, vert->line, FEMLOD_EPARSE, "vertex property '%s' is a list",
                             axes[k]);
        pr->role = (ply_role)(R_X + k);
    }
    if (face) {
        if (face->count > UINT32_MAX)
            return fail_line(r, face->line, FEMLOD_ELIMIT, "too many faces: %llu (limit %u)",
                             (unsigned long long)face->count, (unsigned)UINT32_MAX);
        ply_prop *pr = find_prop(r, face, "vertex_indices");
        if (!pr) pr = find_prop(r, face, "vertex_index");
        if (!pr)
            return fail_line(r, face->line, FEMLOD_EPARSE,
                             "element 'face' has no property 'vertex_indices'");
        if (pr->count_type == T_NONE)
            return fail_line(r, face->line, FEMLOD_EPARSE, "face property '%s' is not a list",
                             fl_io_quote(q, sizeof q, pr->name, pr->name_len));
        if (!type_is_int(pr->type))
            return fail_line(r, face->line, FEMLOD_EUNSUPPORTED,
                             "face indices of a floating-point type");
        pr->role = R_INDICES;
    }
    return FEMLOD_OK;
}

/* }====== */

/* {====== data, shared */

static femlod_status add_vertex(ply_reader *r, const double c[3]) {
    if (!fl_meshbuf_add_vertex(&r->b, c[0], c[1], c[2]))
        return fl_error(r->err, FEMLOD_ENOMEM, "%s: out of memory", r->name);
    return FEMLOD_OK;
}

/* }====== */

/* {====== ascii data */

/* An integer of type t (range checked); 0 on a malformed or out-of-range token. */
static int ascii_int(const char *s, size_t n, ply_type t, long long *v) {
    static const long long lo[] = {0, -128, 0, -32768, 0, -2147483648LL, 0};
    static const long long hi[] = {0, 127, 255, 32767, 65535, 2147483647LL, 4294967295LL};
    size_t i = 0;
    int neg = 0;
    if (i < n && (s[i] == '-' || s[i] == '+')) neg = s[i++] == '-';
    if (i == n) return 0;
    long long x = 0;
    for (; i < n; i++) {
        if (s[i] < '0' || s[i] > '9') return 0;
        if (x < (1LL << 40)) x = x * 10 + (s[i] - '0');
    }
    if (neg) x = -x;
    if (x < lo[t] || x > hi[t]) return 0;
    *v = x;
    return 1;
}

static femlod_status ascii_end(ply_reader *r, size_t line, const ply_elem *e, uint64_t item) {
    char q[48];
    return fail_line(r, line, FEMLOD_EPARSE, "file ends inside element '%s' (item %llu of %llu)",
                     fl_io_quote(q, sizeof q, e->name, e->name_len), (unsigned long long)item + 1,
                     (unsigned long long)e->count);
}

static femlod_status read_ascii(ply_reader *r) {
    /* Tokens on any line, no comments; the last line is counted from the
     * file's start, so an empty data section names the end_header line. */
    fl_text t = {.p = r->p, .end = r->end, .start = r->data, .name = r->name, .line = r->line,
                 .err = r->err};
    char q[48], why[128];
    size_t n;
    const char *s;
    for (size_t ei = 0; ei < r->nelems; ei++) {
        const ply_elem *e = &r->elems[ei];
        const ply_prop *props = r->props + e->first_prop;
        if (e->nprops == 0) continue; /* items without data: nothing to read */
        /* Every value takes at least a digit and a separator. */
        uint64_t left = (uint64_t)(t.end - t.p);
        if (e->nprops && e->count > (left + 1) / (2 * (uint64_t)e->nprops))
            return fail_line(r, e->line, FEMLOD_EPARSE,
                             "element '%s' declares %llu items, but only %llu bytes of data follow",
                             fl_io_quote(q, sizeof q, e->name, e->name_len),
                             (unsigned long long)e->count, (unsigned long long)left);
        for (uint64_t it = 0; it < e->count; it++) {
            double c[3] = {0, 0, 0}, x;
            int is_vertex = 0;
            for (size_t pi = 0; pi < e->nprops; pi++) {
                const ply_prop *pr = &props[pi];
                if (!(s = fl_text_next(&t, &n))) return ascii_end(r, t.line, e, it);
                if (pr->count_type == T_NONE) {
                    if (pr->role >= R_X && pr->role <= R_Z) {
                        if (!fl_io_coord(s, n, &c[pr->role - R_X], why, sizeof why))
                            return fail_line(r, t.line, FEMLOD_EPARSE, "%s", why);
                        is_vertex = 1;
                    } else if (!fl_io_number(s, n, &x, why, sizeof why)) {
                        return fail_line(r, t.line, FEMLOD_EPARSE, "%s", why);
                    }
                    continue;
                }
                long long count;
                if (!ascii_int(s, n, pr->count_type, &count) || count < 0)
                    return fail_line(r, t.line, FEMLOD_EPARSE, "bad list count '%s'",
                                     fl_io_quote(q, sizeof q, s, n));
                if (pr->role == R_INDICES && count < 3)
                    return fail_line(r, t.line, FEMLOD_EPARSE,
                                     "face has %lld vertices (at least 3 needed)", count);
                fl_io_fan f = {0, 0, 0};
                for (long long j = 0; j < count; j++) {
                    if (!(s = fl_text_next(&t, &n))) return ascii_end(r, t.line, e, it);
                    if (pr->role != R_INDICES) {
                        if (!fl_io_number(s, n, &x, why, sizeof why))
                            return fail_line(r, t.line, FEMLOD_EPARSE, "%s", why);
                        continue;
                    }
                    long long v;
                    if (!ascii_int(s, n, pr->type, &v))
                        return fail_line(r, t.line, FEMLOD_EPARSE, "bad face index '%s'",
                                         fl_io_quote(q, sizeof q, s, n));
                    if (v < 0 || (uint64_t)v >= r->nv)
                        return fail_line(r, t.line, FEMLOD_EPARSE,
                                         "face index %lld out of range (%llu vertices)", v,
                                         (unsigned long long)r->nv);
                    if (fl_io_fan_add(&r->b, &f, (uint32_t)v) != FEMLOD_OK)
                        return fail_line(r, t.line, FEMLOD_ENOMEM, "out of memory");
                }
            }
            if (is_vertex) {
                femlod_status st = add_vertex(r, c);
                if (st != FEMLOD_OK) return st;
            }
        }
    }
    if ((s = fl_text_next(&t, &n)))
        return fail_line(r, t.line, FEMLOD_EPARSE, "data after the last element: '%s'",
                         fl_io_quote(q, sizeof q, s, n));
    return FEMLOD_OK;
}

/* }====== */

/* {====== binary data */

static uint64_t load_bits(const unsigned char *p, size_t n, int big) {
    uint64_t v = 0;
    for (size_t i = 0; i < n; i++) v |= (uint64_t)p[big ? n - 1 - i : i] << (8 * i);
    return v;
}

/* Integer value of an integer-typed field. */
static long long load_int(const unsigned char *p, ply_type t, int big) {
    uint64_t u = load_bits(p, type_size(t), big);
    switch (t) {
    case T_I8: return (int8_t)(uint8_t)u;
    case T_I16: return (int16_t)(uint16_t)u;
    case T_I32: return (int32_t)(uint32_t)u;
    default: return (long long)u;
    }
}

static double load_double(const unsigned char *p, ply_type t, int big) {
    if (t == T_F32) {
        uint32_t u = (uint32_t)load_bits(p, 4, big);
        float f;
        memcpy(&f, &u, sizeof f);
        return f;
    }
    if (t == T_F64) {
        uint64_t u = load_bits(p, 8, big);
        double d;
        memcpy(&d, &u, sizeof d);
        return d;
    }
    return (double)load_int(p, t, big);
}

static femlod_status read_binary(ply_reader *r) {
    const int big = r->encoding == ENC_BE;
    const unsigned char *base = (const unsigned char *)r->data;
    size_t pos = (size_t)(r->p - r->data), size = (size_t)(r->end - r->data);
    char q[48];
    for (size_t ei = 0; ei < r->nelems; ei++) {
        const ply_elem *e = &r->elems[ei];
        const ply_prop *props = r->props + e->first_prop;
        if (e->nprops == 0) continue; /* items without data: nothing to read */
        size_t least = 0;             /* bytes of one item: exact without lists */
        int has_list = 0;
        for (size_t pi = 0; pi < e->nprops; pi++) {
            has_list |= props[pi].count_type != T_NONE;
            least +=
                type_size(props[pi].count_type != T_NONE ? props[pi].count_type : props[pi].type);
        }
        uint64_t need;
        if (__builtin_mul_overflow(e->count, (uint64_t)least, &need) || need > size - pos)
            return fail_byte(r, r->data + pos,
                             "element '%s' declares %llu items of %s%zu bytes, but only %zu "
                             "bytes are left",
                             fl_io_quote(q, sizeof q, e->name, e->name_len),
                             (unsigned long long)e->count, has_list ? "at least " : "", least,
                             size - pos);
        for (uint64_t it = 0; it < e->count; it++) {
            double c[3] = {0, 0, 0};
            int is_vertex = 0;
            for (size_t pi = 0; pi < e->nprops; pi++) {
                const ply_prop *pr = &props[pi];
                if (pr->count_type == T_NONE) {
                    size_t ts = type_size(pr->type);
                    if (ts > size - pos)
                        return fail_byte(r, r->data + pos,
                                         "file ends inside element '%s' (item %llu of %llu)",
                                         fl_io_quote(q, sizeof q, e->name, e->name_len),
                                         (unsigned long long)it + 1, (unsigned long long)e->count);
                    if (pr->role >= R_X && pr->role <= R_Z) {
                        double x = load_double(base + pos, pr->type, big);
                        if (!isfinite(x))
                            return fail_byte(r, r->data + pos,
                                             "vertex %llu: coordinate is not finite (%s)",
                                             (unsigned long long)it + 1, isnan(x) ? "nan" : "inf");
                        c[pr->role - R_X] = x;
                        is_vertex = 1;
                    }
                    pos += ts;
                    continue;
                }
                size_t cs = type_size(pr->count_type), ts = type_size(pr->type);
                if (cs > size - pos)
                    return fail_byte(r, r->data + pos,
                                     "file ends inside element '%s' (item %llu of %llu)",
                                     fl_io_quote(q, sizeof q, e->name, e->name_len),
                                     (unsigned long long)it + 1, (unsigned long long)e->count);
                long long count = load_int(base + pos, pr->count_type, big);
                if (count < 0)
                    return fail_byte(r, r->data + pos, "negative list count %lld", count);
                if (pr->role == R_INDICES && count < 3)
                    return fail_byte(r, r->data + pos, "face has %lld vertices (at least 3 needed)",
                                     count);
                uint64_t bytes;
                if (__builtin_mul_overflow((uint64_t)count, (uint64_t)ts, &bytes) ||
                    bytes > size - pos - cs)
                    return fail_byte(r, r->data + pos,
                                     "list of %lld entries runs past the end of the file "
                                     "(%zu bytes left)",
                                     count, size - pos - cs);
                pos += cs;
                if (pr->role != R_INDICES) {
                    pos += (size_t)bytes;
                    continue;
                }
                fl_io_fan f = {0, 0, 0};
                for (long long j = 0; j < count; j++, pos += ts) {
                    long long v = load_int(base + pos, pr->type, big);
                    if (v < 0 || (uint64_t)v >= r->nv)
                        return fail_byte(r, r->data + pos,
                                         "face index %lld out of range (%llu vertices)", v,
                                         (unsigned long long)r->nv);
                    if (fl_io_fan_add(&r->b, &f, (uint32_t)v) != FEMLOD_OK)
                        return fl_error(r->err, FEMLOD_ENOMEM, "%s: out of memory", r->name);
                }
            }
            if (is_vertex) {
                femlod_status st = add_vertex(r, c);
                if (st != FEMLOD_OK) return st;
            }
        }
    }
    if (pos != size)
        return fail_byte(r, r->data + pos, "%zu bytes after the last element", size - pos);
    return FEMLOD_OK;
}

/* }====== */

static femlod_status parse(ply_reader *r) {
    femlod_status st = read_header(r);
    if (st == FEMLOD_OK) st = assign_roles(r);
    if (st != FEMLOD_OK) return st;
    /* Reserve no more than the data can hold: the checks above bound the
     * vertex count by the bytes for binary files, and the ascii reader
     * rechecks per element; growth takes care of the rest. */
    size_t left = (size_t)(r->end - r->p);
    size_t nv = (size_t)r->nv < left / 2 ? (size_t)r->nv : left / 2;
    if (!fl_meshbuf_reserve(&r->b, nv, 0))
        return fl_error(r->err, FEMLOD_ENOMEM, "%s: out of memory", r->name);
    return r->encoding == ENC_ASCII ? read_ascii(r) : read_binary(r);
}

femlod_status fl_read_ply(femlod_mesh **out, const char *data, size_t size, const char *name,
                          femlod_error *err) {
    ply_reader r;
    memset(&r, 0, sizeof r);
    r.data = r.p = data;
    r.end = data + size;
    r.name = name;
    r.line = 1;
    r.err = err;
    femlod_status st = parse(&r);
    free(r.elems);
    free(r.props);
    if (st == FEMLOD_OK && r.b.nv != r.nv)
        st = fl_error(err, FEMLOD_EPARSE, "%s: read %zu of %llu vertices", name, r.b.nv,
                      (unsigned long long)r.nv);
    return fl_io_finish(&r.b, st, out, name, err);
}

/* {====== writers */

static void put_le(unsigned char *p, uint64_t v, size_t n) {
    for (size_t i = 0; i < n; i++) p[i] = (unsigned char)(v >> (8 * i));
}

femlod_status fl_write_ply(const femlod_mesh *m, FILE *fp, int binary) {
    if (fprintf(fp,
                "ply\nformat %s 1.0\ncomment femlod %s\nelement vertex %zu\n"
                "property double x\nproperty double y\nproperty double z\n"
                "element face %zu\nproperty list uchar uint vertex_indices\nend_header\n",
                binary ? "binary_little_endian" : "ascii", FEMLOD_VERSION_STRING, m->nv, m->nt) < 0)
        return FEMLOD_EIO;
    if (binary) {
        unsigned char rec[24];
        for (size_t i = 0; i < m->nv; i++) {
            for (int k = 0; k < 3; k++) {
                uint64_t u;
                memcpy(&u, &m->pos[3 * i + (size_t)k], sizeof u);
                put_le(rec + 8 * k, u, 8);
            }
            if (fwrite(rec, 1, 24, fp) != 24) return FEMLOD_EIO;
        }
        for (size_t i = 0; i < m->nt; i++) {
            rec[0] = 3;
            for (int k = 0; k < 3; k++) put_le(rec + 1 + 4 * k, m->tri[3 * i + (size_t)k], 4);
            if (fwrite(rec, 1, 13, fp) != 13) return FEMLOD_EIO;
        }
        return FEMLOD_OK;
    }
    return fl_io_put_vertex_face_lines(m, fp);
}

/* }====== */
