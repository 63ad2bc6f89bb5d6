/* io.c - format names, dispatch of femlod_mesh_read/write to the io_*.c
 * readers and writers, and the helpers the text readers share. */
#include "core.h"

#include <assert.h>
#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* {====== format names */

static const struct {
    femlod_format format;
    const char *name;
} format_names[] = {
    {FEMLOD_FORMAT_OBJ, "obj"},
    {FEMLOD_FORMAT_STL, "stl"},
    {FEMLOD_FORMAT_STL_ASCII, "stl_ascii"},
    {FEMLOD_FORMAT_STL_BINARY, "stl_binary"},
    {FEMLOD_FORMAT_OFF, "off"},
    {FEMLOD_FORMAT_PLY, "ply"},
    {FEMLOD_FORMAT_PLY_ASCII, "ply_ascii"},
    {FEMLOD_FORMAT_PLY_BINARY, "ply_binary"},
    {FEMLOD_FORMAT_GLTF, "gltf"},
    {FEMLOD_FORMAT_GLB, "glb"},
};

#define SUPPORTED_EXTENSIONS ".obj, .stl, .off, .ply, .gltf, .glb"

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
               {"glb", FEMLOD_FORMAT_GLB}};
    for (size_t i = 0; i < sizeof ext / sizeof ext[0]; i++)
        if (equal_nocase(dot + 1, ext[i].ext)) return ext[i].format;
    return FEMLOD_FORMAT_AUTO;
}

static int format_valid(femlod_format f) {
    return f >= FEMLOD_FORMAT_AUTO && f <= FEMLOD_FORMAT_GLB;
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

femlod_status femlod_mesh_write(const femlod_mesh *mesh, const char *path,
                                const femlod_write_options *options, femlod_error *err) {
    assert(mesh && path);
    femlod_format f = resolve_format(options ? options->format : FEMLOD_FORMAT_AUTO, path, err);
    if (f == FEMLOD_FORMAT_AUTO) return err ? err->status : FEMLOD_EINPUT;
    int gltf = f == FEMLOD_FORMAT_GLTF || f == FEMLOD_FORMAT_GLB;
    if (options && !gltf && (options->color_by || options->normals || options->extras))
        return fl_error(err, FEMLOD_EINPUT,
                        "%s: color_by, normals and extras are glTF options (format %s)", path,
                        femlod_format_name(f));
    fl_out o;
    femlod_status s = fl_out_open(&o, path, err);
    if (s != FEMLOD_OK) return s;
    if (gltf) {
        /* "gltf" names the family, as "stl" does: GLB for a .glb name. */
        int binary = f == FEMLOD_FORMAT_GLB || femlod_format_from_path(path) == FEMLOD_FORMAT_GLB;
        s = fl_write_gltf(mesh, o.fp, binary, options, path, err);
        if (s != FEMLOD_OK) {
            fl_out_abort(&o);
            return s;
        }
        return fl_out_commit(&o, err);
    }
    errno = 0;
    switch (f) {
    case FEMLOD_FORMAT_OBJ: s = fl_write_obj(mesh, o.fp); break;
    case FEMLOD_FORMAT_STL:
    case FEMLOD_FORMAT_STL_BINARY: s = fl_write_stl(mesh, o.fp, 1); break;
    case FEMLOD_FORMAT_STL_ASCII: s = fl_write_stl(mesh, o.fp, 0); break;
    case FEMLOD_FORMAT_OFF: s = fl_write_off(mesh, o.fp); break;
    case FEMLOD_FORMAT_PLY:
    case FEMLOD_FORMAT_PLY_BINARY: s = fl_write_ply(mesh, o.fp, 1); break;
    case FEMLOD_FORMAT_PLY_ASCII: s = fl_write_ply(mesh, o.fp, 0); break;
    case FEMLOD_FORMAT_GLTF:
    case FEMLOD_FORMAT_GLB: /* written above */
    case FEMLOD_FORMAT_AUTO: s = FEMLOD_EINPUT; break;
    }
    if (s != FEMLOD_OK) {
        int e = errno; /* fl_out_abort's fclose/unlink may change it */
        fl_out_abort(&o);
        return fl_error(err, s, "%s: cannot write: %s", path, strerror(e ? e : EIO));
    }
    return fl_out_commit(&o, err);
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
