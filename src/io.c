/* io.c - format names, dispatch of femlod_mesh_read/write to the io_*.c
 * readers and writers, and the helpers the text readers share. */
#include "core.h"

#include <assert.h>
#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* {====== format names */

/* One list makes both tables below. */
#define FORMATS(X)                                                                                 \
    X(FEMLOD_FORMAT_OBJ, "obj")                                                                    \
    X(FEMLOD_FORMAT_STL, "stl")                                                                    \
    X(FEMLOD_FORMAT_STL_ASCII, "stl_ascii")                                                        \
    X(FEMLOD_FORMAT_STL_BINARY, "stl_binary")                                                      \
    X(FEMLOD_FORMAT_OFF, "off")                                                                    \
    X(FEMLOD_FORMAT_PLY, "ply")                                                                    \
    X(FEMLOD_FORMAT_PLY_ASCII, "ply_ascii")                                                        \
    X(FEMLOD_FORMAT_PLY_BINARY, "ply_binary")                                                      \
    X(FEMLOD_FORMAT_GLTF, "gltf")                                                                  \
    X(FEMLOD_FORMAT_GLB, "glb")                                                                    \
    X(FEMLOD_FORMAT_MSH, "msh")                                                                    \
    X(FEMLOD_FORMAT_MSH2, "msh2")                                                                  \
    X(FEMLOD_FORMAT_VTK, "vtk")                                                                    \
    X(FEMLOD_FORMAT_INP, "inp")                                                                    \
    X(FEMLOD_FORMAT_MEDIT, "medit")

#define FORMAT_ENTRY(f, n) {f, n},
#define FORMAT_NAME(f, n) n,

static const struct {
    femlod_format format;
    const char *name;
} format_names[] = {FORMATS(FORMAT_ENTRY)};

static const char *const format_name_list[] = {FORMATS(FORMAT_NAME) NULL};

#define SUPPORTED_EXTENSIONS ".obj, .stl, .off, .ply, .gltf, .glb, .msh, .vtk, .inp, .mesh"

const char *const *femlod_format_names(void) { return format_name_list; }

const char *femlod_format_name(femlod_format format) {
    if (format == FEMLOD_FORMAT_AUTO) return "auto";
    for (size_t i = 0; i < sizeof format_names / sizeof format_names[0]; i++)
        if (format_names[i].format == format) return format_names[i].name;
    return "unknown";
}

static int lower(int c) { return (c >= 'A' && c <= 'Z') ? c + ('a' - 'A') : c; }

static int equal_nocase(const char *a, const char *b) {
    for (; *a && *b; a++, b++)
        if (lower((unsigned char)*a) != lower((unsigned char)*b)) return 0;
    return *a == *b;
}

femlod_format femlod_format_from_name(const char *name) {
    if (!name) return FEMLOD_FORMAT_AUTO;
    for (size_t i = 0; i < sizeof format_names / sizeof format_names[0]; i++)
        if (equal_nocase(name, format_names[i].name)) return format_names[i].format;
    return FEMLOD_FORMAT_AUTO;
}

femlod_format femlod_format_from_path(const char *path) {
    if (!path) return FEMLOD_FORMAT_AUTO;
    const char *base = strrchr(path, '/');
    base = base ? base + 1 : path;
    const char *dot = strrchr(base, '.');
    if (!dot) return FEMLOD_FORMAT_AUTO;
    static const struct {
        const char *ext;
        femlod_format format;
    } ext[] = {{"obj", FEMLOD_FORMAT_OBJ},
               {"stl", FEMLOD_FORMAT_STL},
               {"off", FEMLOD_FORMAT_OFF},
               {"ply", FEMLOD_FORMAT_PLY},
               {"gltf", FEMLOD_FORMAT_GLTF},
               {"glb", FEMLOD_FORMAT_GLB},
               {"msh", FEMLOD_FORMAT_MSH},
               {"vtk", FEMLOD_FORMAT_VTK},
               {"inp", FEMLOD_FORMAT_INP},
               {"mesh", FEMLOD_FORMAT_MEDIT}};
    for (size_t i = 0; i < sizeof ext / sizeof ext[0]; i++)
        if (equal_nocase(dot + 1, ext[i].ext)) return ext[i].format;
    return FEMLOD_FORMAT_AUTO;
}

static int format_valid(femlod_format f) {
    return f >= FEMLOD_FORMAT_AUTO && f <= FEMLOD_FORMAT_MEDIT;
}

/* }====== */

/* {====== reading */

/* The format to use, or FEMLOD_FORMAT_AUTO after filling err. */
static femlod_format resolve_format(femlod_format f, const char *name, femlod_error *err) {
    if (!format_valid(f)) {
        fl_error(err, FEMLOD_EINPUT, "%s: invalid format code %d", name, (int)f);
        return FEMLOD_FORMAT_AUTO;
    }
    if (f != FEMLOD_FORMAT_AUTO) return f;
    f = femlod_format_from_path(name);
    if (f == FEMLOD_FORMAT_AUTO)
        fl_error(err, FEMLOD_EINPUT,
                 "%s: unknown file extension; supported: " SUPPORTED_EXTENSIONS
                 " (or give the format)",
                 name);
    return f;
}

/* data[size] must be '\0' (the readers' contract). file: where the data came
 * from (glTF's external buffers are beside it), NULL for memory. */
static femlod_status dispatch_read(femlod_mesh **out, const char *data, size_t size,
                                   const char *name, femlod_format f, const char *file,
                                   femlod_error *err) {
    switch (f) {
    case FEMLOD_FORMAT_OBJ: return fl_read_obj(out, data, size, name, err);
    case FEMLOD_FORMAT_STL:
    case FEMLOD_FORMAT_STL_ASCII:
    case FEMLOD_FORMAT_STL_BINARY: return fl_read_stl(out, data, size, name, f, err);
    case FEMLOD_FORMAT_OFF: return fl_read_off(out, data, size, name, err);
    /* A PLY file says its own encoding: the ascii/binary choice only matters for writing. */
    case FEMLOD_FORMAT_PLY:
    case FEMLOD_FORMAT_PLY_ASCII:
    case FEMLOD_FORMAT_PLY_BINARY: return fl_read_ply(out, data, size, name, err);
    case FEMLOD_FORMAT_GLTF:
    case FEMLOD_FORMAT_GLB: return fl_read_gltf(out, data, size, name, file, f, err);
    case FEMLOD_FORMAT_MSH:
    case FEMLOD_FORMAT_MSH2: return fl_read_msh(out, data, size, name, err);
    case FEMLOD_FORMAT_MEDIT: return fl_read_medit(out, data, size, name, err);
    case FEMLOD_FORMAT_VTK:
    case FEMLOD_FORMAT_INP:
        return fl_error(err, FEMLOD_EUNSUPPORTED,
                        "%s: femlod writes %s files but does not read them (formats read: obj, "
                        "stl, off, ply, gltf, glb, msh, medit)",
                        name, femlod_format_name(f));
    case FEMLOD_FORMAT_AUTO: break;
    }
    return fl_error(err, FEMLOD_EINPUT, "%s: no format", name);
}

femlod_status femlod_mesh_read(femlod_mesh **out, const char *path,
                               const femlod_read_options *options, femlod_error *err) {
    assert(out && path);
    femlod_format f = resolve_format(options ? options->format : FEMLOD_FORMAT_AUTO, path, err);
    if (f == FEMLOD_FORMAT_AUTO) return err ? err->status : FEMLOD_EINPUT;
    char *data;
    size_t size;
    femlod_status s = fl_file_read_all(path, &data, &size, err);
    if (s != FEMLOD_OK) return s;
    s = dispatch_read(out, data, size, path, f, path, err);
    free(data);
    return s;
}

femlod_status femlod_mesh_read_memory(femlod_mesh **out, const void *data, size_t size,
                                      const char *name, const femlod_read_options *options,
                                      femlod_error *err) {
    assert(out && (data || size == 0));
    if (!name) name = "(memory)";
    femlod_format f = resolve_format(options ? options->format : FEMLOD_FORMAT_AUTO, name, err);
    if (f == FEMLOD_FORMAT_AUTO) return err ? err->status : FEMLOD_EINPUT;
    /* The readers may rely on a terminating NUL, which the caller's buffer
     * need not have. */
    if (size == SIZE_MAX) return fl_error(err, FEMLOD_ENOMEM, "%s: too large", name);
    char *copy = fl_alloc(size + 1, 1);
    if (!copy)
        return fl_error(err, FEMLOD_ENOMEM, "%s: out of memory copying %zu bytes", name, size);
    if (size) memcpy(copy, data, size);
    copy[size] = '\0';
    femlod_status s = dispatch_read(out, copy, size, name, f, NULL, err);
    free(copy);
    return s;
}

/* }====== */

/* {====== writing */

/* Writes the mesh in format f to fp; name is for messages (and tells GLB
 * from glTF JSON by its extension). */
static femlod_status write_to(FILE *fp, const femlod_mesh *mesh, const char *name, femlod_format f,
                              const femlod_write_options *options, femlod_error *err) {
    int gltf = f == FEMLOD_FORMAT_GLTF || f == FEMLOD_FORMAT_GLB;
    int fe = f == FEMLOD_FORMAT_MSH || f == FEMLOD_FORMAT_MSH2 || f == FEMLOD_FORMAT_VTK ||
             f == FEMLOD_FORMAT_INP || f == FEMLOD_FORMAT_MEDIT;
    femlod_status s;
    errno = 0;
    if (gltf || fe) {
        /* "gltf" names the family, as "stl" does: GLB for a .glb name. */
        int binary = f == FEMLOD_FORMAT_GLB || femlod_format_from_path(name) == FEMLOD_FORMAT_GLB;
        switch (f) {
        case FEMLOD_FORMAT_MSH: return fl_write_msh(mesh, fp, 4, name, err);
        case FEMLOD_FORMAT_MSH2: return fl_write_msh(mesh, fp, 2, name, err);
        case FEMLOD_FORMAT_VTK: return fl_write_vtk(mesh, fp, name, err);
        case FEMLOD_FORMAT_INP: return fl_write_inp(mesh, fp, options, name, err);
        case FEMLOD_FORMAT_MEDIT: return fl_write_medit(mesh, fp, name, err);
        default: return fl_write_gltf(mesh, fp, binary, options, name, err);
        }
    }
    switch (f) {
    case FEMLOD_FORMAT_OBJ: s = fl_write_obj(mesh, fp); break;
    case FEMLOD_FORMAT_STL:
    case FEMLOD_FORMAT_STL_BINARY: s = fl_write_stl(mesh, fp, 1); break;
    case FEMLOD_FORMAT_STL_ASCII: s = fl_write_stl(mesh, fp, 0); break;
    case FEMLOD_FORMAT_OFF: s = fl_write_off(mesh, fp); break;
    case FEMLOD_FORMAT_PLY:
    case FEMLOD_FORMAT_PLY_BINARY: s = fl_write_ply(mesh, fp, 1); break;
    case FEMLOD_FORMAT_PLY_ASCII: s = fl_write_ply(mesh, fp, 0); break;
    default: s = FEMLOD_EINPUT; break;
    }
    if (s != FEMLOD_OK) {
        int e = errno;
        return fl_error(err, s, "%s: cannot write: %s", name, strerror(e ? e : EIO));
    }
    return FEMLOD_OK;
}

/* The checks every write makes before anything is opened; the format. */
static femlod_format write_format(const char *path, const femlod_write_options *options,
                                  femlod_error *err) {
    femlod_format f = resolve_format(options ? options->format : FEMLOD_FORMAT_AUTO, path, err);
    if (f == FEMLOD_FORMAT_AUTO) return f;
    int gltf = f == FEMLOD_FORMAT_GLTF || f == FEMLOD_FORMAT_GLB;
    if (options && !gltf && (options->color_by || options->normals || options->extras)) {
        fl_error(err, FEMLOD_EINPUT, "%s: color_by, normals and extras are glTF options (format %s)",
                 path, femlod_format_name(f));
        return FEMLOD_FORMAT_AUTO;
    }
    if (options && f != FEMLOD_FORMAT_INP && (options->node_set_count || options->element_set_count)) {
        fl_error(err, FEMLOD_EINPUT, "%s: node and element sets are written to .inp only (format %s)",
                 path, femlod_format_name(f));
        return FEMLOD_FORMAT_AUTO;
    }
    return f;
}

femlod_status femlod_mesh_write(const femlod_mesh *mesh, const char *path,
                                const femlod_write_options *options, femlod_error *err) {
    assert(mesh && path);
    femlod_format f = write_format(path, options, err);
    if (f == FEMLOD_FORMAT_AUTO) return err ? err->status : FEMLOD_EINPUT;
    fl_out o;
    femlod_status s = fl_out_open(&o, path, err);
    if (s != FEMLOD_OK) return s;
    s = write_to(o.fp, mesh, path, f, options, err);
    if (s != FEMLOD_OK) {
        fl_out_abort(&o);
        return s;
    }
    return fl_out_commit(&o, err);
}

femlod_status femlod_mesh_write_memory(const femlod_mesh *mesh, const char *name,
                                       const femlod_write_options *options, char **data,
                                       size_t *size, femlod_error *err) {
    assert(mesh && name && data && size);
    femlod_format f = write_format(name, options, err);
    if (f == FEMLOD_FORMAT_AUTO) return err ? err->status : FEMLOD_EINPUT;
    char *buf = NULL;
    size_t len = 0;
    FILE *fp = open_memstream(&buf, &len);
    if (!fp) return fl_error(err, FEMLOD_ENOMEM, "%s: out of memory", name);
    femlod_status s = write_to(fp, mesh, name, f, options, err);
    if (fclose(fp) != 0 && s == FEMLOD_OK) s = fl_error(err, FEMLOD_ENOMEM, "%s: out of memory", name);
    if (s != FEMLOD_OK) {
        free(buf);
        return s;
    }
    *data = buf;
    *size = len;
    return FEMLOD_OK;
}

/* }====== */

/* {====== shared by the text readers */

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

int fl_io_coord(const char *s, size_t n, double *out, char *why, size_t why_size) {
    char q[48];
    char *end;
    double x = fl_strtod(s, &end);
    if (n == 0 || end != s + n) {
        snprintf(why, why_size, "bad number '%s'", fl_io_quote(q, sizeof q, s, n));
        return 0;
    }
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

/* }====== */

/* {====== token reader and number output for the FE formats */

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
            const char *s = p;
            while (p < end && !text_space(*p) && !(t->comment && *p == t->comment)) p++;
            *len = (size_t)(p - s);
            t->p = p;
            return s;
        }
    }
    /* Name the file's last line, not the empty one after its final newline. */
    if (!t->eof && end > t->start && end[-1] == '\n') t->line--;
    t->eof = 1;
    t->p = end;
    return NULL;
}

femlod_status fl_text_fail(fl_text *t, femlod_status st, const char *fmt, ...) {
    char msg[FEMLOD_ERROR_MESSAGE_SIZE];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    return fl_error(t->err, st, "%s:%zu: %s", t->name, t->line, msg);
}

int fl_text_u64(const char *s, size_t n, uint64_t *v) {
    if (n == 0) return 0;
    uint64_t x = 0;
    for (size_t i = 0; i < n; i++) {
        if (s[i] < '0' || s[i] > '9') return 0;
        if (x < (UINT64_C(1) << 60)) x = x * 10 + (uint64_t)(s[i] - '0');
    }
    *v = x;
    return 1;
}

int fl_text_is(const char *s, size_t n, const char *word) {
    size_t k = strlen(word);
    return n == k && memcmp(s, word, k) == 0;
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

femlod_status fl_io_write_error(const char *path, femlod_error *err) {
    int e = errno;
    return fl_error(err, FEMLOD_EIO, "%s: cannot write: %s", path, strerror(e ? e : EIO));
}

int fl_io_put_xyz(FILE *fp, const double *p, const char *sep, const char *end) {
    char buf[160];
    size_t n = 0, ls = strlen(sep), le = strlen(end);
    if (ls > 16 || le > 16) return 0;
    for (int k = 0; k < 3; k++) {
        if (k) {
            memcpy(buf + n, sep, ls);
            n += ls;
        }
        int w = fl_format_double(buf + n, 32, p[k]);
        if (w < 0) return 0;
        n += (size_t)w;
    }
    memcpy(buf + n, end, le);
    n += le;
    return fwrite(buf, 1, n, fp) == n;
}

/* }====== */
