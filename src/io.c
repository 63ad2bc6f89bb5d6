/* io.c - format names, and dispatch of femlod_mesh_read/write to the io_*.c
 * readers and writers (the helpers those share are in io_util.c, below them). */
#include "core.h"

#include <assert.h>
#include <errno.h>
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
