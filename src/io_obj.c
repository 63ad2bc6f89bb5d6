/* io_obj.c - Wavefront OBJ: v and f statements of the OBJ spec (Wavefront
 * "Advanced Visualizer" appendix B1).
 *
 * Single pass over the buffer, no allocation per line. What is accepted and
 * rejected is listed in docs/formats.md; the robustness rules come from
 * ecosystem-notes.md 5.2 (relative indices resolve against the vertices read
 * so far, trimesh#2556 and TALOS-2020-1212; `\v` is whitespace, assimp
 * PR#6540; never read past the buffer, assimp #4234/#4770). */
#include "io_util.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* A face line that used an index beyond the vertices read so far: legal
 * when the vertex comes later in the file, checked once all are read. */
typedef struct forward_ref {
    size_t line, first_tri, ntri;
} forward_ref;

typedef struct obj_reader {
    const char *p, *end;
    const char *name;
    size_t line;
    femlod_error *err;
    fl_meshbuf b;
    forward_ref *fwd;
    size_t nfwd, cap_fwd;
} obj_reader;

static femlod_status fail(obj_reader *r, femlod_status st, const char *fmt, ...) FL_PRINTF(3, 4);
static femlod_status fail(obj_reader *r, femlod_status st, const char *fmt, ...) {
    va_list ap;
    va_start(ap, fmt);
    st = fl_io_vfail_line(r->err, st, r->name, r->line, fmt, ap);
    va_end(ap);
    return st;
}

static int is_blank(char c) { return c == ' ' || c == '\t' || c == '\v' || c == '\f' || c == '\r'; }

/* The bytes that end a token, or may (a backslash starting a continuation):
 * blanks, the newline and '\\'; one table look-up a byte in next_token. */
static const unsigned char token_stop[256] = {
    ['\t'] = 1, ['\n'] = 1, ['\v'] = 1, ['\f'] = 1, ['\r'] = 1, [' '] = 1, ['\\'] = 1,
};

/* A backslash followed by blanks and a newline (or the end) joins lines;
 * returns the position after the newline, or NULL when p is no such thing. */
static const char *continuation(const char *p, const char *end) {
    if (p >= end || *p != '\\') return NULL;
    const char *q = p + 1;
    while (q < end && is_blank(*q)) q++;
    if (q == end) return q;
    return *q == '\n' ? q + 1 : NULL;
}

/* Skips blanks and line continuations, counting the joined lines. */
static void skip_blank(obj_reader *r) {
    const char *p = r->p, *end = r->end;
    for (;;) {
        while (p < end && is_blank(*p)) p++;
        const char *q = continuation(p, end);
        if (!q) break;
        if (q > p && q[-1] == '\n') r->line++;
        p = q;
    }
    r->p = p;
}

/* End of statement: end of data, newline or a comment. Call after skip_blank. */
static int at_eos(const obj_reader *r) { return r->p == r->end || *r->p == '\n' || *r->p == '#'; }

/* Consumes the rest of a statement known to be at_eos. */
static void end_statement(obj_reader *r) {
    if (r->p < r->end && *r->p == '#') {
        const char *nl = memchr(r->p, '\n', (size_t)(r->end - r->p));
        r->p = nl ? nl : r->end;
    }
    if (r->p < r->end) {
        r->p++; /* the newline */
        r->line++;
    }
}

/* The token at r->p (after skip_blank, not at_eos); advances past it. */
static const char *next_token(obj_reader *r, size_t *len) {
    const char *s = r->p, *p = s, *end = r->end;
    for (;;) {
        while (p < end && !token_stop[(unsigned char)*p]) p++;
        if (p == end || *p != '\\' || continuation(p, end)) break;
        p++; /* a backslash inside a token */
    }
    *len = (size_t)(p - s);
    r->p = p;
    return s;
}

/* Whether a token that started before p ends at p: the end of the data, a
 * blank, a newline or a line continuation. The fast paths below parse a
 * number or a vertex reference straight from the buffer and accept it only
 * when it ends a token; anything else goes through next_token and the
 * checks that name the problem, so what is accepted and every message stay
 * as they were. */
static int at_token_end(const obj_reader *r, const char *p) {
    if (p == r->end) return 1;
    if (!token_stop[(unsigned char)*p]) return 0;
    return *p != '\\' || continuation(p, r->end) != NULL;
}

/* Skips a statement whose content femlod does not use (continuations included). */
static void skip_statement(obj_reader *r) {
    for (;;) {
        skip_blank(r);
        if (r->p == r->end || *r->p == '\n') break;
        size_t n;
        next_token(r, &n);
    }
    end_statement(r);
}

static femlod_status read_vertex(obj_reader *r) {
    double c[3];
    char why[128];
    for (int k = 0; k < 3; k++) {
        skip_blank(r);
        if (at_eos(r)) return fail(r, FEMLOD_EPARSE, "vertex has %d coordinates (3 needed)", k);
        /* Fast path: a finite number that is the whole token (fl_io_coord
         * parses the token with the same fl_strtod, so the value is the same). */
        char *e;
        double x = fl_strtod(r->p, &e);
        if (e > r->p && at_token_end(r, e) && isfinite(x)) {
            c[k] = x;
            r->p = e;
            continue;
        }
        size_t n;
        const char *s = next_token(r, &n);
        if (!fl_io_coord(s, n, &c[k], why, sizeof why)) return fail(r, FEMLOD_EPARSE, "%s", why);
    }
    /* An optional w, or the r g b that some exporters append: numbers, ignored. */
    for (int extra = 0;; extra++) {
        skip_blank(r);
        if (at_eos(r)) break;
        size_t n;
        const char *s = next_token(r, &n);
        double x;
        if (!fl_io_number(s, n, &x, why, sizeof why)) return fail(r, FEMLOD_EPARSE, "%s", why);
        if (extra == 4) return fail(r, FEMLOD_EPARSE, "too many values on a 'v' line (at most 7)");
    }
    end_statement(r);
    if (r->b.nv >= UINT32_MAX)
        return fail(r, FEMLOD_ELIMIT, "too many vertices (limit %u)", (unsigned)UINT32_MAX);
    if (!fl_meshbuf_add_vertex(&r->b, c[0], c[1], c[2]))
        return fail(r, FEMLOD_ENOMEM, "out of memory at vertex %zu", r->b.nv + 1);
    return FEMLOD_OK;
}

/* Parses [+-]digits; saturates at 2^40 (far past any valid index). */
static const char *parse_int(const char *p, const char *e, long long *v) {
    int neg = 0;
    if (p < e && (*p == '-' || *p == '+')) {
        neg = *p == '-';
        p++;
    }
    if (p == e || *p < '0' || *p > '9') return NULL;
    long long x = 0;
    for (; p < e && *p >= '0' && *p <= '9'; p++)
        if (x < (1LL << 40)) x = x * 10 + (*p - '0');
    *v = neg ? -x : x;
    return p;
}

/* One vertex reference at s: v, v/vt, v/vt/vn or v//vn; returns the byte
 * after it (where the grammar stops, which the caller checks is the token's
 * end), NULL when s starts none. The vt and vn parts are checked for form
 * only: femlod keeps positions only (docs/formats.md). */
static const char *parse_ref(const char *s, const char *e, long long *v) {
    long long ignored;
    const char *p = parse_int(s, e, v);
    if (!p || p == e || *p != '/') return p;
    p++;
    if (p < e && *p == '/') return parse_int(p + 1, e, &ignored); /* v//vn */
    p = parse_int(p, e, &ignored);
    if (!p || p == e || *p != '/') return p; /* v/vt */
    return parse_int(p + 1, e, &ignored);
}

static femlod_status read_face(obj_reader *r) {
    size_t face_line = r->line, first_tri = r->b.nt;
    fl_io_fan fan = {0, 0, 0};
    int forward = 0;
    char q[48];
    for (;;) {
        skip_blank(r);
        if (at_eos(r)) break;
        size_t n;
        const char *s = r->p;
        long long idx;
        const char *after = parse_ref(s, r->end, &idx);
        if (after && at_token_end(r, after)) {
            n = (size_t)(after - s);
            r->p = after;
        } else {
            s = next_token(r, &n);
            if (parse_ref(s, s + n, &idx) != s + n)
                return fail(r, FEMLOD_EPARSE, "bad face vertex '%s'",
                            fl_io_quote(q, sizeof q, s, n));
        }
        size_t nv = r->b.nv;
        uint32_t v;
        if (idx == 0)
            return fail(r, FEMLOD_EPARSE, "face index 0 is invalid (OBJ indices start at 1)");
        if (idx < 0) {
            if ((unsigned long long)-idx > nv)
                return fail(r, FEMLOD_EPARSE, "face index %s out of range (%zu vertices so far)",
                            fl_io_quote(q, sizeof q, s, n), nv);
            v = (uint32_t)(nv - (size_t)-idx);
        } else {
            if ((unsigned long long)idx > UINT32_MAX)
                return fail(r, FEMLOD_EPARSE, "face index %s out of range (%zu vertices so far)",
                            fl_io_quote(q, sizeof q, s, n), nv);
            v = (uint32_t)(idx - 1);
            if (v >= nv) forward = 1;
        }
        femlod_status st = fl_io_fan_add(&r->b, &fan, v);
        if (st == FEMLOD_ELIMIT)
            return fail(r, st, "too many triangles (limit %u)", (unsigned)UINT32_MAX);
        if (st != FEMLOD_OK) return fail(r, st, "out of memory at triangle %zu", r->b.nt + 1);
    }
    end_statement(r);
    if (fan.count < 3) {
        r->line = face_line;
        return fail(r, FEMLOD_EPARSE, "face has %zu vertices (at least 3 needed)",
                    (size_t)fan.count);
    }
    if (forward) {
        if (r->nfwd == r->cap_fwd) {
            size_t cap = r->cap_fwd ? 2 * r->cap_fwd : 16;
            forward_ref *f = fl_realloc(r->fwd, cap, sizeof *f);
            if (!f) return fail(r, FEMLOD_ENOMEM, "out of memory");
            r->fwd = f;
            r->cap_fwd = cap;
        }
        r->fwd[r->nfwd++] = (forward_ref){face_line, first_tri, r->b.nt - first_tri};
    }
    return FEMLOD_OK;
}

/* Statements that carry no positions or triangles: texture and normal data,
 * grouping, materials, lines, points and the free-form geometry of the spec. */
static int ignored_keyword(const char *s, size_t n) {
    static const char *const words[] = {
        "vt",     "vn",         "vp",        "g",      "o",        "s",        "mg",   "usemtl",
        "mtllib", "l",          "p",         "cstype", "deg",      "bmat",     "step", "curv",
        "curv2",  "surf",       "parm",      "trim",   "hole",     "scrv",     "sp",   "end",
        "con",    "ctech",      "stech",     "bevel",  "c_interp", "d_interp", "lod",  "maplib",
        "usemap", "shadow_obj", "trace_obj", "call",   "csh",      "res",
    };
    for (size_t i = 0; i < sizeof words / sizeof words[0]; i++)
        if (strlen(words[i]) == n && memcmp(words[i], s, n) == 0) return 1;
    return 0;
}

static femlod_status parse(obj_reader *r) {
    int seen = 0;
    char q[48];
    if (r->end - r->p >= 3 && memcmp(r->p, "\xEF\xBB\xBF", 3) == 0) r->p += 3;
    for (;;) {
        skip_blank(r);
        if (r->p == r->end) break;
        if (*r->p == '\n' || *r->p == '#') {
            if (*r->p == '#') seen = 1;
            end_statement(r);
            continue;
        }
        seen = 1;
        size_t n;
        const char *s = next_token(r, &n);
        femlod_status st;
        if (n == 1 && s[0] == 'v') {
            st = read_vertex(r);
        } else if ((n == 1 && s[0] == 'f') || (n == 2 && s[0] == 'f' && s[1] == 'o')) {
            st = read_face(r); /* "fo" is the spec's old spelling of "f" */
        } else if (ignored_keyword(s, n)) {
            skip_statement(r);
            st = FEMLOD_OK;
        } else {
            st = fail(r, FEMLOD_EPARSE, "unknown statement '%s'", fl_io_quote(q, sizeof q, s, n));
        }
        if (st != FEMLOD_OK) return st;
    }
    if (!seen) return fl_error(r->err, FEMLOD_EPARSE, "%s: empty file", r->name);

    size_t nv = r->b.nv;
    for (size_t i = 0; i < r->nfwd; i++) {
        const forward_ref *f = &r->fwd[i];
        const uint32_t *t = r->b.tri + 3 * f->first_tri;
        for (size_t k = 0; k < 3 * f->ntri; k++) {
            if (t[k] >= nv) {
                r->line = f->line;
                return fail(r, FEMLOD_EPARSE, "face index %llu out of range (%zu vertices)",
                            (unsigned long long)t[k] + 1, nv);
            }
        }
    }
    return FEMLOD_OK;
}

femlod_status fl_read_obj(femlod_mesh **out, const char *data, size_t size, const char *name,
                          femlod_error *err) {
    obj_reader r;
    memset(&r, 0, sizeof r);
    r.p = data;
    r.end = data + size;
    r.name = name;
    r.line = 1;
    r.err = err;
    femlod_status st = parse(&r);
    free(r.fwd);
    return fl_io_finish(&r.b, st, out, name, err);
}

/* {====== writer */

femlod_status fl_write_obj(const femlod_mesh *m, FILE *fp) {
    char line[2 + FL_IO_XYZ_SIZE];
    if (fprintf(fp, "# femlod %s\n# %zu vertices, %zu triangles\n", FEMLOD_VERSION_STRING, m->nv,
                m->nt) < 0)
        return FEMLOD_EIO;
    for (size_t i = 0; i < m->nv; i++) {
        line[0] = 'v';
        line[1] = ' ';
        size_t n = 2 + fl_io_format_xyz(line + 2, m->pos + 3 * i);
        line[n++] = '\n';
        if (fwrite(line, 1, n, fp) != n) return FEMLOD_EIO;
    }
    for (size_t i = 0; i < m->nt; i++) {
        const uint32_t *t = m->tri + 3 * i;
        if (fprintf(fp, "f %lu %lu %lu\n", (unsigned long)t[0] + 1, (unsigned long)t[1] + 1,
                    (unsigned long)t[2] + 1) < 0)
            return FEMLOD_EIO;
    }
    return FEMLOD_OK;
}

/* }====== */
