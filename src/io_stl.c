/* io_stl.c - STL, ASCII and binary (3D Systems' StereoLithography Interface
 * Specification, 1989).
 *
 * Binary or ASCII is decided by the size arithmetic first (84 + 50 n bytes),
 * the "solid" prefix second: SolidWorks and others write binary files whose
 * 80-byte header starts with "solid" (meshio#530, sreiter/stl_reader#3).
 * STL shares no vertices, so corners are welded (positions that compare
 * equal become one vertex): binary records straight from the file by
 * weld_binary, ASCII corners by fl_mesh_from_soup, in the same order. */
#include "io_util.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define STL_HEADER 80
#define STL_PREFIX 84 /* header + uint32 triangle count */
#define STL_RECORD 50 /* normal, 3 corners, uint16 attribute */

static femlod_status fail_at(femlod_error *err, const char *name, size_t byte, const char *fmt, ...)
    FL_PRINTF(4, 5);
static femlod_status fail_at(femlod_error *err, const char *name, size_t byte, const char *fmt,
                             ...) {
    va_list ap;
    va_start(ap, fmt);
    femlod_status st = fl_io_vfail_byte(err, name, byte, fmt, ap);
    va_end(ap);
    return st;
}

static uint32_t get_u32le(const unsigned char *p) {
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}

static float get_f32le(const unsigned char *p) {
    uint32_t u = get_u32le(p);
    float f;
    memcpy(&f, &u, sizeof f);
    return f;
}

/* {====== binary */

/* A welded position: the corner's float bits (-0 made +0) and its vertex. */
typedef struct weld_slot {
    uint32_t bits[3];
    uint32_t id; /* UINT32_MAX: empty */
} weld_slot;

/* Slots of the small direct-mapped cache in front of the table: a vertex
 * recurs in nearby records (about 6 times in a closed mesh), and a hit
 * there spares the table's cache miss. It holds copies of table slots, so
 * a hit gives the table's answer. */
enum { WELD_CACHE = 1 << 14 }; /* indexed by the hash's top 14 bits */

static uint32_t weld_hash(const uint32_t b[3]) {
    uint64_t h = ((uint64_t)b[0] << 32 | b[1]) * 0x9E3779B97F4A7C15ull;
    h ^= (uint64_t)b[2] * 0xFF51AFD7ED558CCDull;
    h ^= h >> 29;
    h *= 0xC4CEB9FE1A85EC53ull;
    return (uint32_t)(h >> 32);
}

/* Doubles the table (load kept at most 1/2); 0 when out of memory. */
static int weld_grow(weld_slot **table, size_t *cap) {
    size_t ncap = 2 * *cap;
    weld_slot *t = fl_alloc(ncap, sizeof *t);
    if (!t) return 0;
    for (size_t i = 0; i < ncap; i++) t[i].id = UINT32_MAX;
    for (size_t i = 0; i < *cap; i++) {
        const weld_slot *e = &(*table)[i];
        if (e->id == UINT32_MAX) continue;
        size_t slot = weld_hash(e->bits) & (ncap - 1);
        while (t[slot].id != UINT32_MAX) slot = (slot + 1) & (ncap - 1);
        t[slot] = *e;
    }
    free(*table);
    *table = t;
    *cap = ncap;
    return 1;
}

/* Welds the corners of n records straight from the file: corners with equal
 * coordinates become one vertex, numbered in order of first appearance, as
 * fl_mesh_from_soup numbers them (equal floats are equal doubles), without
 * its array of 9 doubles per triangle. The table holds the float bits, so a
 * probe reads one slot, not the position array, and grows with the vertices
 * found (a closed mesh has about half as many vertices as triangles). The
 * first non-finite coordinate in file order is the error. Deterministic:
 * the numbering depends only on the order of the records. */
static femlod_status weld_binary(femlod_mesh **out, const unsigned char *data, size_t n,
                                 const char *name, femlod_error *err) {
    size_t cap = 1024;
    while (cap < n) cap *= 2; /* a closed mesh's n / 2 vertices fill 1/4 to 1/2 of it */
    weld_slot *table = fl_alloc(cap, sizeof *table);
    weld_slot *cache = fl_alloc(WELD_CACHE, sizeof *cache);
    double *pos = fl_alloc(n ? 3 * n : 1, 3 * sizeof(double)); /* untouched pages stay free */
    femlod_mesh *m = fl_mesh_alloc(0, n);
    if (!table || !cache || !pos || !m) {
        free(table);
        free(cache);
        free(pos);
        femlod_mesh_free(m);
        return fl_error(err, FEMLOD_ENOMEM, "%s: out of memory for %zu triangles", name, n);
    }
    for (size_t i = 0; i < cap; i++) table[i].id = UINT32_MAX;
    for (size_t i = 0; i < WELD_CACHE; i++) cache[i].id = UINT32_MAX;
    size_t nv = 0;
    femlod_status st = FEMLOD_OK;
    for (size_t t = 0; t < n && st == FEMLOD_OK; t++) {
        const unsigned char *rec = data + STL_PREFIX + t * STL_RECORD + 12; /* skip the normal */
        if (nv > UINT32_MAX - 3) {
            st = fl_error(err, FEMLOD_EINPUT, "%s: too many vertices", name);
            break;
        }
        if (2 * (nv + 3) > cap && !weld_grow(&table, &cap)) {
            st = fl_error(err, FEMLOD_ENOMEM, "%s: out of memory for %zu triangles", name, n);
            break;
        }
        for (int c = 0; c < 3; c++) {
            uint32_t b[3] = {0, 0, 0};
            for (int k = 0; k < 3; k++) {
                const unsigned char *at = rec + 12 * c + 4 * k;
                float f = get_f32le(at);
                if (!isfinite(f)) {
                    st = fail_at(err, name, (size_t)(at - data),
                                 "triangle %zu: coordinate is not finite (%s)", t + 1,
                                 isnan(f) ? "nan" : "inf");
                    break;
                }
                if (f == 0.0f) f = 0.0f; /* -0 == +0 */
                memcpy(&b[k], &f, sizeof f);
            }
            if (st != FEMLOD_OK) break;
            uint32_t h = weld_hash(b);
            weld_slot *near = &cache[h >> 18];
            if (near->id == UINT32_MAX || near->bits[0] != b[0] || near->bits[1] != b[1] ||
                near->bits[2] != b[2]) {
                size_t slot = h & (cap - 1);
                for (;;) {
                    weld_slot *e = &table[slot];
                    if (e->id == UINT32_MAX) {
                        memcpy(e->bits, b, sizeof b);
                        e->id = (uint32_t)nv;
                        for (int k = 0; k < 3; k++) {
                            float f;
                            memcpy(&f, &b[k], sizeof f);
                            pos[3 * nv + (size_t)k] = f;
                        }
                        nv++;
                        break;
                    }
                    if (e->bits[0] == b[0] && e->bits[1] == b[1] && e->bits[2] == b[2]) break;
                    slot = (slot + 1) & (cap - 1);
                }
                *near = table[slot];
            }
            m->tri[3 * t + (size_t)c] = near->id;
        }
    }
    free(table);
    free(cache);
    if (st != FEMLOD_OK) {
        free(pos);
        femlod_mesh_free(m);
        return st;
    }
    double *shrunk = realloc(pos, (nv ? nv : 1) * 3 * sizeof(double));
    free(m->pos);
    m->pos = shrunk ? shrunk : pos;
    m->nv = nv;
    *out = m;
    return FEMLOD_OK;
}

static femlod_status read_binary(femlod_mesh **out, const unsigned char *data, size_t size,
                                 const char *name, femlod_error *err) {
    if (size < STL_PREFIX)
        return fail_at(err, name, size,
                       "file ends inside the %d-byte binary STL header (%zu bytes)", STL_PREFIX,
                       size);
    size_t n = get_u32le(data + STL_HEADER);
    size_t need, body;
    if (__builtin_mul_overflow(n, (size_t)STL_RECORD, &body) ||
        __builtin_add_overflow(body, (size_t)STL_PREFIX, &need) || need != size) {
        size_t holds = (size - STL_PREFIX) / STL_RECORD;
        size_t extra = (size - STL_PREFIX) % STL_RECORD;
        if (extra)
            return fail_at(err, name, STL_HEADER,
                           "declared %zu triangles, file holds %zu (and %zu extra bytes; "
                           "binary STL is 84 + 50 * n bytes)",
                           n, holds, extra);
        return fail_at(err, name, STL_HEADER,
                       "declared %zu triangles, file holds %zu (binary STL is 84 + 50 * n bytes)",
                       n, holds);
    }
    return weld_binary(out, data, n, name, err);
}

/* }====== */

/* {====== ASCII: tokens on any line, no comments (fl_text with comment 0) */

static femlod_status fail_line(fl_text *r, const char *fmt, ...) FL_PRINTF(2, 3);
static femlod_status fail_line(fl_text *r, const char *fmt, ...) {
    va_list ap;
    va_start(ap, fmt);
    femlod_status st = fl_io_vfail_line(r->err, FEMLOD_EPARSE, r->name, r->line, fmt, ap);
    va_end(ap);
    return st;
}

static int is_space(char c) {
    return c == ' ' || c == '\t' || c == '\v' || c == '\f' || c == '\r' || c == '\n';
}

static int keyword_is(const char *s, size_t n, const char *kw) {
    size_t k = strlen(kw);
    if (n != k) return 0;
    for (size_t i = 0; i < n; i++) {
        char c = s[i];
        if (c >= 'A' && c <= 'Z') c = (char)(c + ('a' - 'A'));
        if (c != kw[i]) return 0;
    }
    return 1;
}

/* The keyword kw must come next (case-insensitive, as some exporters shout). */
static femlod_status expect(fl_text *r, const char *kw) {
    size_t n;
    const char *s = fl_text_next(r, &n);
    char q[48];
    if (!s) return fail_line(r, "expected '%s', found the end of the file", kw);
    if (!keyword_is(s, n, kw))
        return fail_line(r, "expected '%s', found '%s'", kw, fl_io_quote(q, sizeof q, s, n));
    return FEMLOD_OK;
}

/* Skips a solid's name: the rest of the line, unless a keyword that may
 * follow it (`stop`, or "facet") shows up there, as in files written on
 * one line. */
static void skip_name(fl_text *r, const char *stop) {
    const char *p = r->p, *end = r->end;
    for (;;) {
        while (p < end && *p != '\n' && is_space(*p)) p++;
        if (p == end || *p == '\n') break;
        const char *s = p;
        while (p < end && !is_space(*p)) p++;
        size_t n = (size_t)(p - s);
        if (keyword_is(s, n, stop) || keyword_is(s, n, "facet")) {
            p = s;
            break;
        }
    }
    r->p = p;
}

static femlod_status read_number(fl_text *r, double *x, int finite) {
    size_t n;
    const char *s = fl_text_next(r, &n);
    if (!s) return fail_line(r, "expected a number, found the end of the file");
    char why[128];
    if (finite) {
        if (!fl_io_coord(s, n, x, why, sizeof why)) return fail_line(r, "%s", why);
        return FEMLOD_OK;
    }
    if (!fl_io_number(s, n, x, why, sizeof why)) return fail_line(r, "%s", why);
    return FEMLOD_OK;
}

static femlod_status read_ascii(femlod_mesh **out, const char *data, size_t size, const char *name,
                                femlod_error *err) {
    fl_text r;
    fl_text_init(&r, data, size, name, 0, err); /* skips the byte order mark */
    fl_meshbuf soup; /* three "vertices" per triangle: the corners */
    memset(&soup, 0, sizeof soup);
    femlod_status st = FEMLOD_OK;
    size_t n;
    char q[48];
    const char *s = fl_text_next(&r, &n);
    if (!s) return fl_error(err, FEMLOD_EPARSE, "%s: empty file", name);
    /* Several solids in one file occur (concatenated parts): read them all. */
    while (s && st == FEMLOD_OK) {
        if (!keyword_is(s, n, "solid")) {
            st = fail_line(&r, "expected 'solid', found '%s'", fl_io_quote(q, sizeof q, s, n));
            break;
        }
        skip_name(&r, "endsolid");
        for (;;) {
            s = fl_text_next(&r, &n);
            if (!s) {
                st = fail_line(&r, "expected 'facet' or 'endsolid', found the end of the file");
                break;
            }
            if (keyword_is(s, n, "endsolid")) {
                skip_name(&r, "solid");
                break;
            }
            if (!keyword_is(s, n, "facet")) {
                st = fail_line(&r, "expected 'facet' or 'endsolid', found '%s'",
                               fl_io_quote(q, sizeof q, s, n));
                break;
            }
            double c[3];
            /* Normals are recomputed by whoever needs them; some exporters
             * write nan for degenerate facets, so any number is accepted. */
            if ((st = expect(&r, "normal")) != FEMLOD_OK) break;
            for (int k = 0; k < 3 && st == FEMLOD_OK; k++) st = read_number(&r, &c[k], 0);
            if (st != FEMLOD_OK) break;
            if ((st = expect(&r, "outer")) != FEMLOD_OK) break;
            if ((st = expect(&r, "loop")) != FEMLOD_OK) break;
            for (int v = 0; v < 3 && st == FEMLOD_OK; v++) {
                if ((st = expect(&r, "vertex")) != FEMLOD_OK) break;
                for (int k = 0; k < 3 && st == FEMLOD_OK; k++) st = read_number(&r, &c[k], 1);
                if (st != FEMLOD_OK) break;
                if (soup.nv / 3 >= UINT32_MAX) {
                    st = fl_error(err, FEMLOD_ELIMIT, "%s:%zu: too many triangles (limit %u)", name,
                                  r.line, (unsigned)UINT32_MAX);
                    break;
                }
                if (!fl_meshbuf_add_vertex(&soup, c[0], c[1], c[2])) {
                    st = fl_error(err, FEMLOD_ENOMEM, "%s:%zu: out of memory", name, r.line);
                    break;
                }
            }
            if (st != FEMLOD_OK) break;
            if ((st = expect(&r, "endloop")) != FEMLOD_OK) break;
            if ((st = expect(&r, "endfacet")) != FEMLOD_OK) break;
        }
        if (st == FEMLOD_OK) s = fl_text_next(&r, &n);
    }
    if (st == FEMLOD_OK) st = fl_mesh_from_soup(out, soup.pos, soup.nv / 3, err);
    fl_meshbuf_free(&soup);
    return st;
}

/* }====== */

/* ASCII STL candidates: no control byte but whitespace, and either the
 * "solid" keyword first or valid UTF-8 throughout (so a text file that lacks
 * "solid" gets a line error, while a binary file of the wrong size, whose
 * count and floats hold zero or invalid UTF-8 bytes, gets the size error). */
static int looks_like_text(const unsigned char *p, size_t n) {
    for (size_t i = 0; i < n; i++)
        if (p[i] < 0x20 && (p[i] < '\t' || p[i] > '\r')) return 0;
    size_t i = 0;
    if (n >= 3 && memcmp(p, "\xEF\xBB\xBF", 3) == 0) i = 3;
    while (i < n && (p[i] == ' ' || (p[i] >= '\t' && p[i] <= '\r'))) i++;
    if (n - i >= 5) {
        int solid = 1;
        for (size_t k = 0; k < 5; k++)
            if ((p[i + k] | 0x20) != (unsigned char)"solid"[k]) solid = 0;
        if (solid) return 1;
    }
    for (i = 0; i < n;) {
        unsigned char c = p[i];
        size_t len = c < 0x80             ? 1
                     : (c & 0xE0) == 0xC0 ? 2
                     : (c & 0xF0) == 0xE0 ? 3
                     : (c & 0xF8) == 0xF0 ? 4
                                          : 0;
        if (len == 0 || len > n - i) return 0;
        for (size_t k = 1; k < len; k++)
            if ((p[i + k] & 0xC0) != 0x80) return 0;
        i += len;
    }
    return 1;
}

femlod_status fl_read_stl(femlod_mesh **out, const char *data, size_t size, const char *name,
                          femlod_format format, femlod_error *err) {
    const unsigned char *u = (const unsigned char *)data;
    if (size == 0) return fl_error(err, FEMLOD_EPARSE, "%s: empty file", name);
    if (format == FEMLOD_FORMAT_STL_BINARY) return read_binary(out, u, size, name, err);
    if (format != FEMLOD_FORMAT_STL_ASCII) {
        if (size >= STL_PREFIX) {
            uint64_t n = get_u32le(u + STL_HEADER);
            if ((uint64_t)STL_PREFIX + (uint64_t)STL_RECORD * n == (uint64_t)size)
                return read_binary(out, u, size, name, err);
        }
        if (!looks_like_text(u, size)) {
            if (size >= STL_PREFIX) return read_binary(out, u, size, name, err);
            return fail_at(err, name, 0,
                           "not an STL file (%zu bytes: too short for binary STL, and not text)",
                           size);
        }
    }
    /* Sizes are taken after the BOM is gone (assimp#6877): fl_text_init
     * skips it. */
    return read_ascii(out, data, size, name, err);
}

/* {====== writers */

static void put_u32le(unsigned char *p, uint32_t v) {
    p[0] = (unsigned char)v;
    p[1] = (unsigned char)(v >> 8);
    p[2] = (unsigned char)(v >> 16);
    p[3] = (unsigned char)(v >> 24);
}

static void put_f32le(unsigned char *p, float f) {
    uint32_t u;
    memcpy(&u, &f, sizeof u);
    put_u32le(p, u);
}

/* Unit normal of the triangle by the right-hand rule; zero when degenerate. */
static void facet_normal(const femlod_mesh *m, size_t t, double nrm[3]) {
    const uint32_t *tri = m->tri + 3 * t;
    const double *a = m->pos + 3 * (size_t)tri[0], *b = m->pos + 3 * (size_t)tri[1],
                 *c = m->pos + 3 * (size_t)tri[2];
    double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    double v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    nrm[0] = u[1] * v[2] - u[2] * v[1];
    nrm[1] = u[2] * v[0] - u[0] * v[2];
    nrm[2] = u[0] * v[1] - u[1] * v[0];
    double len = sqrt(nrm[0] * nrm[0] + nrm[1] * nrm[1] + nrm[2] * nrm[2]);
    for (int k = 0; k < 3; k++) nrm[k] = len > 0.0 && isfinite(len) ? nrm[k] / len : 0.0;
}

static femlod_status write_binary(const femlod_mesh *m, FILE *fp) {
    unsigned char head[STL_PREFIX];
    memset(head, 0, sizeof head);
    /* Never "solid...": that would invite text parsing by naive readers. */
    snprintf((char *)head, STL_HEADER, "femlod %s binary STL", FEMLOD_VERSION_STRING);
    put_u32le(head + STL_HEADER, (uint32_t)m->nt);
    if (fwrite(head, 1, sizeof head, fp) != sizeof head) return FEMLOD_EIO;
    unsigned char rec[STL_RECORD];
    for (size_t t = 0; t < m->nt; t++) {
        double nrm[3];
        facet_normal(m, t, nrm);
        for (int k = 0; k < 3; k++) put_f32le(rec + 4 * k, (float)nrm[k]);
        for (int v = 0; v < 3; v++) {
            const double *p = m->pos + 3 * (size_t)m->tri[3 * t + (size_t)v];
            for (int k = 0; k < 3; k++) put_f32le(rec + 12 + 12 * v + 4 * k, (float)p[k]);
        }
        rec[48] = rec[49] = 0;
        if (fwrite(rec, 1, sizeof rec, fp) != sizeof rec) return FEMLOD_EIO;
    }
    return FEMLOD_OK;
}

static femlod_status write_ascii(const femlod_mesh *m, FILE *fp) {
    char buf[FL_IO_XYZ_SIZE];
    if (fputs("solid femlod\n", fp) == EOF) return FEMLOD_EIO;
    for (size_t t = 0; t < m->nt; t++) {
        double nrm[3];
        facet_normal(m, t, nrm);
        fl_io_format_xyz(buf, nrm);
        if (fprintf(fp, "  facet normal %s\n    outer loop\n", buf) < 0) return FEMLOD_EIO;
        for (int v = 0; v < 3; v++) {
            fl_io_format_xyz(buf, m->pos + 3 * (size_t)m->tri[3 * t + (size_t)v]);
            if (fprintf(fp, "      vertex %s\n", buf) < 0) return FEMLOD_EIO;
        }
        if (fputs("    endloop\n  endfacet\n", fp) == EOF) return FEMLOD_EIO;
    }
    if (fputs("endsolid femlod\n", fp) == EOF) return FEMLOD_EIO;
    return FEMLOD_OK;
}

femlod_status fl_write_stl(const femlod_mesh *m, FILE *fp, int binary) {
    return binary ? write_binary(m, fp) : write_ascii(m, fp);
}

/* }====== */
