/* io_gltf.cpp - glTF 2.0 in and out: .gltf (JSON, buffers embedded as data:
 * URIs or in files beside it) and .glb (binary). The only C++ file of
 * femlod: a C face (fl_read_gltf, fl_write_gltf in core.h) over tinygltf
 * 2.7.0 (Debian libtinygltf-dev), compiled here so that we choose its
 * defines: no image decoder, no image writer, no external images.
 *
 * Specification: Khronos glTF 2.0 (registry.khronos.org/glTF/specs/2.0),
 * sections "Accessors", "Meshes", "Transformations", "GLB File Format".
 *
 * tinygltf 2.7.0 parses the JSON and loads the buffers, and little more
 * (ecosystem-notes.md 2.3): it accepts out-of-range bufferView, buffer and
 * accessor indices, accessors that run past their views, views that run past
 * their buffers, index values past the vertex count, a GLB BIN chunk up to 8
 * bytes past the end of the file, and it follows a buffer URI such as
 * "../../../../etc/hostname" out of the asset's folder. So this file:
 *   - checks the GLB header itself before tinygltf sees the bytes;
 *   - gives tinygltf file callbacks that read buffers only from inside the
 *     asset's own folder (no absolute path, no "..", realpath stays inside,
 *     regular files, size cap) and nothing at all for data in memory;
 *   - checks every index, offset, stride, count and index value it uses in
 *     overflow-checked size_t arithmetic, naming the JSON pointer;
 *   - makes a fresh TinyGLTF and Model per call and trusts only return
 *     values (tinygltf keeps stale error text);
 *   - installs a do-nothing image loader, so embedded images load as bytes
 *     nobody decodes.
 * No exception leaves this file: every extern "C" entry catches everything
 * (the JSON parser and allocation throw) and returns a femlod status. No Lua
 * is involved here, so no longjmp crosses these frames.
 */
#include <cerrno>
#include <cfloat>
#include <climits>
#include <cmath>
#include <cstdarg>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <new>
#include <sstream>
#include <string>
#include <vector>

#include <sys/stat.h>

#define TINYGLTF_IMPLEMENTATION
#define TINYGLTF_NO_STB_IMAGE
#define TINYGLTF_NO_STB_IMAGE_WRITE
#define TINYGLTF_NO_EXTERNAL_IMAGE
#include <nlohmann/json.hpp>
#include <tiny_gltf.h>

extern "C" {
#include "io_util.h"
}

namespace {

/* {====== messages */

/* Where messages go: "NAME: POINTER: message" (or "NAME: message"). */
struct Diag {
    const char *name;
    femlod_error *err;
};

femlod_status fail(const Diag &d, femlod_status st, const std::string &ptr, const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));
femlod_status fail(const Diag &d, femlod_status st, const std::string &ptr, const char *fmt, ...) {
    char msg[FEMLOD_ERROR_MESSAGE_SIZE];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    if (ptr.empty()) return fl_error(d.err, st, "%s: %s", d.name, msg);
    return fl_error(d.err, st, "%s: %s: %s", d.name, ptr.c_str(), msg);
}

/* A string from the file, fit for a message: quoted, cut, printable. */
std::string shown(const std::string &s) {
    char q[48];
    return std::string("'") + fl_io_quote(q, sizeof q, s.data(), s.size()) + "'";
}

std::string at(const char *array, size_t i) {
    return std::string("/") + array + "/" + std::to_string(i);
}

const char *mode_name(int mode) {
    switch (mode) {
    case TINYGLTF_MODE_POINTS: return "POINTS";
    case TINYGLTF_MODE_LINE: return "LINES";
    case TINYGLTF_MODE_LINE_LOOP: return "LINE_LOOP";
    case TINYGLTF_MODE_LINE_STRIP: return "LINE_STRIP";
    case TINYGLTF_MODE_TRIANGLES: return "TRIANGLES";
    case TINYGLTF_MODE_TRIANGLE_STRIP: return "TRIANGLE_STRIP";
    case TINYGLTF_MODE_TRIANGLE_FAN: return "TRIANGLE_FAN";
    default: return "unknown";
    }
}

const char *component_name(int ct) {
    switch (ct) {
    case TINYGLTF_COMPONENT_TYPE_BYTE: return "BYTE";
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return "UNSIGNED_BYTE";
    case TINYGLTF_COMPONENT_TYPE_SHORT: return "SHORT";
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: return "UNSIGNED_SHORT";
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: return "UNSIGNED_INT";
    case TINYGLTF_COMPONENT_TYPE_FLOAT: return "FLOAT";
    default: return "an invalid component type";
    }
}

const char *type_name(int type) {
    switch (type) {
    case TINYGLTF_TYPE_SCALAR: return "SCALAR";
    case TINYGLTF_TYPE_VEC2: return "VEC2";
    case TINYGLTF_TYPE_VEC3: return "VEC3";
    case TINYGLTF_TYPE_VEC4: return "VEC4";
    case TINYGLTF_TYPE_MAT2: return "MAT2";
    case TINYGLTF_TYPE_MAT3: return "MAT3";
    case TINYGLTF_TYPE_MAT4: return "MAT4";
    default: return "?";
    }
}

/* Bytes of one component; 0 for types glTF 2.0 does not have. */
size_t component_size(int ct) {
    switch (ct) {
    case TINYGLTF_COMPONENT_TYPE_BYTE:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return 1;
    case TINYGLTF_COMPONENT_TYPE_SHORT:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: return 2;
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
    case TINYGLTF_COMPONENT_TYPE_FLOAT: return 4;
    default: return 0;
    }
}

uint32_t get_u32le(const unsigned char *p) {
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}

/* An index of the unsigned type ct at p, little-endian. */
uint32_t get_index(const unsigned char *p, int ct) {
    switch (ct) {
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return p[0];
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: return (uint32_t)p[0] | (uint32_t)p[1] << 8;
    default: return get_u32le(p);
    }
}

bool is_index_type(int ct) {
    return ct == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE ||
           ct == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT ||
           ct == TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT;
}

bool has_extension(const tinygltf::ExtensionMap &ext, const char *name) {
    return ext.find(name) != ext.end();
}

/* }====== */

/* {====== confined file access for external buffers */

/* External buffer files larger than this are refused (ELIMIT). */
const size_t kMaxBufferFile = (size_t)1 << 31;

struct FsContext {
    const char *base = nullptr; /* the asset's folder, as handed to tinygltf; nullptr: memory */
    std::string prefix;         /* what tinygltf puts before a URI: base + "/" */
    std::string real_base;      /* realpath(base) + "/", made on first use */
    femlod_status status = FEMLOD_OK;
    std::string reason; /* the first refusal, for the message */
};

void refuse(FsContext *c, femlod_status st, const std::string &why) {
    if (c->status != FEMLOD_OK) return;
    c->status = st;
    c->reason = why;
}

bool is_separator(char ch) { return ch == '/' || ch == '\\'; }

/* ASCII only, whatever the locale. */
bool ascii_alpha(char ch) { return (ch >= 'a' && ch <= 'z') || (ch >= 'A' && ch <= 'Z'); }
bool ascii_alnum(char ch) { return ascii_alpha(ch) || (ch >= '0' && ch <= '9'); }

/* "scheme:" at the start of a URI (RFC 3986: ALPHA *( ALPHA / DIGIT / "+" / "-" / "." )). */
bool has_scheme(const std::string &u, std::string *scheme) {
    if (u.empty() || !ascii_alpha(u[0])) return false;
    for (size_t i = 1; i < u.size(); i++) {
        char ch = u[i];
        if (ch == ':') {
            *scheme = u.substr(0, i);
            return true;
        }
        if (!ascii_alnum(ch) && ch != '+' && ch != '-' && ch != '.') return false;
    }
    return false;
}

/* The real path of the buffer file at path (which tinygltf made as
 * base + "/" + decoded URI) when it is a regular file inside the asset's
 * folder; "" after recording why not. */
std::string confine(FsContext *c, const std::string &path, size_t *size) {
    if (!c->base) {
        refuse(c, FEMLOD_EUNSUPPORTED,
               "buffer file " + shown(path) +
                   " cannot be read: glTF from memory has no folder (embed the buffer or "
                   "read the file by its path)");
        return "";
    }
    /* tinygltf also tries "./" + URI: the current folder is never the asset's. */
    if (path.compare(0, c->prefix.size(), c->prefix) != 0) return "";
    std::string uri = path.substr(c->prefix.size()), scheme;
    if (uri.empty()) {
        refuse(c, FEMLOD_EPARSE, "buffer uri is empty");
        return "";
    }
    if (has_scheme(uri, &scheme)) {
        if (scheme == "data")
            refuse(c, FEMLOD_EUNSUPPORTED,
                   "data URI of an unsupported media type (base64 application/octet-stream or "
                   "application/gltf-buffer expected)");
        else
            refuse(c, FEMLOD_EUNSUPPORTED,
                   "buffer uri " + shown(uri) + ": scheme '" + scheme.substr(0, 16) +
                       ":' is not supported (relative file names and data: URIs only)");
        return "";
    }
    if (is_separator(uri[0])) {
        refuse(c, FEMLOD_EPARSE,
               "buffer uri " + shown(uri) +
                   " is an absolute path (buffer files must be inside the asset's folder)");
        return "";
    }
    for (size_t i = 0; i < uri.size();) {
        size_t j = i;
        while (j < uri.size() && !is_separator(uri[j])) j++;
        if (j - i == 2 && uri[i] == '.' && uri[i + 1] == '.') {
            refuse(c, FEMLOD_EPARSE,
                   "buffer uri " + shown(uri) +
                       " climbs out of the asset's folder ('..' is not allowed)");
            return "";
        }
        i = j + 1;
    }
    if (c->real_base.empty()) {
        char *rb = realpath(c->base, nullptr);
        if (!rb) {
            refuse(c, FEMLOD_EIO,
                   std::string("cannot resolve the asset's folder: ") + strerror(errno));
            return "";
        }
        c->real_base = rb;
        free(rb);
        if (c->real_base.empty() || c->real_base.back() != '/') c->real_base += '/';
    }
    char *rp = realpath(path.c_str(), nullptr);
    if (!rp) {
        refuse(c, FEMLOD_EIO, "cannot open buffer file " + shown(uri) + ": " + strerror(errno));
        return "";
    }
    std::string real = rp;
    free(rp);
    if (real.compare(0, c->real_base.size(), c->real_base) != 0) {
        refuse(c, FEMLOD_EPARSE,
               "buffer file " + shown(uri) + " leaves the asset's folder through a symbolic link");
        return "";
    }
    struct stat st;
    if (stat(real.c_str(), &st) != 0) {
        refuse(c, FEMLOD_EIO, "cannot open buffer file " + shown(uri) + ": " + strerror(errno));
        return "";
    }
    if (!S_ISREG(st.st_mode)) {
        refuse(c, FEMLOD_EIO, "buffer file " + shown(uri) + " is not a regular file");
        return "";
    }
    if ((uintmax_t)st.st_size > (uintmax_t)kMaxBufferFile) {
        refuse(c, FEMLOD_ELIMIT,
               "buffer file " + shown(uri) + " has " + std::to_string((uintmax_t)st.st_size) +
                   " bytes (limit " + std::to_string(kMaxBufferFile) + ")");
        return "";
    }
    *size = (size_t)st.st_size;
    return real;
}

bool fs_exists(const std::string &path, void *user) {
    size_t size;
    return !confine(static_cast<FsContext *>(user), path, &size).empty();
}

std::string fs_expand(const std::string &path, void *) { return path; }

bool fs_read(std::vector<unsigned char> *out, std::string *err, const std::string &path,
             void *user) {
    FsContext *c = static_cast<FsContext *>(user);
    size_t size = 0;
    std::string real = confine(c, path, &size);
    if (real.empty()) {
        if (err) *err += "refused";
        return false;
    }
    FILE *fp = fopen(real.c_str(), "rb");
    if (!fp) {
        refuse(c, FEMLOD_EIO,
               "cannot open buffer file " + shown(path.substr(c->prefix.size())) + ": " +
                   strerror(errno));
        return false;
    }
    out->resize(size);
    size_t got = size ? fread(out->data(), 1, size, fp) : 0;
    bool more = fgetc(fp) != EOF; /* the file grew since stat: not what was checked */
    bool bad = ferror(fp) != 0;
    fclose(fp);
    if (got != size || more || bad) {
        refuse(c, FEMLOD_EIO,
               "cannot read buffer file " + shown(path.substr(c->prefix.size())) +
                   ": it changed while being read, or a read failed");
        return false;
    }
    return true;
}

bool fs_write(std::string *err, const std::string &, const std::vector<unsigned char> &, void *) {
    if (err) *err += "femlod writes no files through tinygltf";
    return false;
}

/* Embedded images are kept as bytes (tinygltf 2.7 fails the whole load on an
 * image when no loader is installed); femlod reads geometry only. */
bool keep_image(tinygltf::Image *, const int, std::string *, std::string *, int, int,
                const unsigned char *, int, void *) {
    return true;
}

/* }====== */

/* {====== GLB header */

const uint32_t kChunkJson = 0x4E4F534A;

femlod_status at_byte(const Diag &d, femlod_status st, size_t byte, const std::string &msg) {
    return fl_error(d.err, st, "%s: byte %zu: %s", d.name, byte, msg.c_str());
}

/* The header and chunk bounds, checked before tinygltf reads them (2.7.0 lets
 * a BIN chunk run 8 bytes past the end of the data). */
femlod_status check_glb(const Diag &d, const unsigned char *u, size_t size) {
    if (size < 20)
        return at_byte(d, FEMLOD_EPARSE, size,
                       "file ends inside the 20-byte GLB header (" + std::to_string(size) +
                           " bytes)");
    uint32_t version = get_u32le(u + 4), length = get_u32le(u + 8);
    if (version != 2)
        return at_byte(d, FEMLOD_EUNSUPPORTED, 4,
                       "GLB version " + std::to_string(version) + " (femlod reads version 2)");
    if (length != size)
        return at_byte(d, FEMLOD_EPARSE, 8,
                       "GLB header gives a length of " + std::to_string(length) +
                           " bytes, but the file has " + std::to_string(size));
    uint32_t json_len = get_u32le(u + 12), json_type = get_u32le(u + 16);
    if (json_type != kChunkJson) {
        char hex[16];
        snprintf(hex, sizeof hex, "0x%08x", json_type);
        return at_byte(d, FEMLOD_EPARSE, 16,
                       std::string("first chunk is not JSON (type ") + hex + ")");
    }
    if (json_len == 0) return at_byte(d, FEMLOD_EPARSE, 12, "JSON chunk is empty");
    if (json_len > size - 20)
        return at_byte(d, FEMLOD_EPARSE, 12,
                       "JSON chunk of " + std::to_string(json_len) +
                           " bytes runs past the end of the file (" + std::to_string(size - 20) +
                           " bytes left)");
    size_t end = 20 + (size_t)json_len;
    if (end < size) {
        if (size - end < 8)
            return at_byte(d, FEMLOD_EPARSE, end,
                           std::to_string(size - end) +
                               " bytes after the JSON chunk (a chunk header takes 8)");
        uint32_t bin_len = get_u32le(u + end);
        if (bin_len > size - end - 8)
            return at_byte(d, FEMLOD_EPARSE, end,
                           "chunk of " + std::to_string(bin_len) +
                               " bytes runs past the end of the file (" +
                               std::to_string(size - end - 8) + " bytes left)");
    }
    return FEMLOD_OK;
}

/* }====== */

/* {====== matrices: column-major 4x4, as glTF stores them */

struct Mat {
    double m[16];
};

Mat identity() {
    Mat r;
    for (int i = 0; i < 16; i++) r.m[i] = (i % 5 == 0) ? 1.0 : 0.0;
    return r;
}

bool is_identity(const Mat &a) {
    for (int i = 0; i < 16; i++)
        if (a.m[i] != ((i % 5 == 0) ? 1.0 : 0.0)) return false;
    return true;
}

Mat multiply(const Mat &a, const Mat &b) {
    Mat r;
    for (int c = 0; c < 4; c++)
        for (int row = 0; row < 4; row++) {
            double s = 0.0;
            for (int k = 0; k < 4; k++) s += a.m[k * 4 + row] * b.m[c * 4 + k];
            r.m[c * 4 + row] = s;
        }
    return r;
}

double det3(const Mat &a) {
    const double *m = a.m;
    return m[0] * (m[5] * m[10] - m[9] * m[6]) - m[4] * (m[1] * m[10] - m[9] * m[2]) +
           m[8] * (m[1] * m[6] - m[5] * m[2]);
}

bool all_finite(const std::vector<double> &v) {
    for (double x : v)
        if (!std::isfinite(x)) return false;
    return true;
}

/* }====== */

/* {====== reading */

/* A primitive in its mesh's space: positions and triangles (local indices). */
struct Prim {
    std::vector<double> pos;
    std::vector<uint32_t> tri;
};

/* Accessors materialised into tightly packed little-endian elements. */
struct Elements {
    std::vector<unsigned char> bytes;
    size_t count = 0, elem = 0;
    int ctype = 0;
};

/* Accessors without a bufferView (all zeros but for sparse values) are not
 * backed by the file's bytes: their count is capped. */
const size_t kMaxUnbackedBytes = (size_t)64 << 20;

class Reader {
  public:
    Reader(const Diag &d, const tinygltf::Model &m) : d_(d), m_(m) {}

    bool required(const char *ext) const {
        for (const std::string &s : m_.extensionsRequired)
            if (s == ext) return true;
        return false;
    }

    /* The references of a primitive: compression, mode, the POSITION and
     * indices accessors and their views exist. Also run on a partly parsed
     * model to explain a tinygltf failure. */
    femlod_status check_refs(size_t mi, size_t pi) const {
        const tinygltf::Primitive &p = m_.meshes[mi].primitives[pi];
        std::string ptr = at("meshes", mi) + at("primitives", pi);
        /* Draco that is not required comes with uncompressed accessors: read those. */
        bool draco = has_extension(p.extensions, "KHR_draco_mesh_compression");
        if (draco && required("KHR_draco_mesh_compression")) return no_draco(ptr);
        if (p.mode >= TINYGLTF_MODE_POINTS && p.mode <= TINYGLTF_MODE_LINE_STRIP)
            return fail(d_, FEMLOD_EUNSUPPORTED, ptr,
                        "mode %d (%s) is not a triangle mode (femlod reads TRIANGLES, "
                        "TRIANGLE_STRIP and TRIANGLE_FAN)",
                        p.mode, mode_name(p.mode));
        if (p.mode < TINYGLTF_MODE_POINTS || p.mode > TINYGLTF_MODE_TRIANGLE_FAN)
            return fail(d_, FEMLOD_EPARSE, ptr, "mode %d is not a glTF primitive mode", p.mode);
        auto it = p.attributes.find("POSITION");
        if (it == p.attributes.end())
            return fail(d_, FEMLOD_EPARSE, ptr, "primitive has no POSITION attribute");
        femlod_status st = check_accessor_ref(it->second, ptr + "/attributes/POSITION");
        if (st != FEMLOD_OK) return st;
        if (draco && !backed(it->second)) return no_draco(ptr);
        if (p.indices != -1) {
            if ((st = check_accessor_ref(p.indices, ptr + "/indices")) != FEMLOD_OK) return st;
            if (draco && !backed(p.indices)) return no_draco(ptr);
        }
        return FEMLOD_OK;
    }

    /* Decodes mesh mi's primitives (once; cached for every instance). */
    femlod_status mesh(size_t mi, const std::vector<Prim> **out) {
        if (cache_.empty()) {
            cache_.resize(m_.meshes.size());
            cached_.assign(m_.meshes.size(), 0);
        }
        if (!cached_[mi]) {
            const tinygltf::Mesh &mesh = m_.meshes[mi];
            std::vector<Prim> prims(mesh.primitives.size());
            for (size_t pi = 0; pi < mesh.primitives.size(); pi++) {
                femlod_status st = primitive(mi, pi, &prims[pi]);
                if (st != FEMLOD_OK) return st;
            }
            cache_[mi].swap(prims);
            cached_[mi] = 1;
        }
        *out = &cache_[mi];
        return FEMLOD_OK;
    }

  private:
    femlod_status no_draco(const std::string &ptr) const {
        return fail(d_, FEMLOD_EUNSUPPORTED, ptr,
                    "compressed with KHR_draco_mesh_compression, which femlod does not decode");
    }

    /* The accessor (in range) has data of its own. */
    bool backed(int ai) const {
        const tinygltf::Accessor &a = m_.accessors[(size_t)ai];
        return a.bufferView >= 0 || a.sparse.isSparse;
    }

    femlod_status check_accessor_ref(int ai, const std::string &user) const {
        if (ai < 0 || (size_t)ai >= m_.accessors.size())
            return fail(d_, FEMLOD_EPARSE, user, "accessor %d out of range (%zu accessors)", ai,
                        m_.accessors.size());
        const tinygltf::Accessor &a = m_.accessors[(size_t)ai];
        if (a.bufferView < -1 ||
            (a.bufferView >= 0 && (size_t)a.bufferView >= m_.bufferViews.size()))
            return fail(d_, FEMLOD_EPARSE, at("accessors", (size_t)ai),
                        "bufferView %d out of range (%zu bufferViews)", a.bufferView,
                        m_.bufferViews.size());
        return FEMLOD_OK;
    }

    /* bufferView vi: in range, uncompressed, inside its buffer. */
    femlod_status view(int vi, const std::string &user, const unsigned char **base,
                       size_t *length) const {
        if (vi < 0 || (size_t)vi >= m_.bufferViews.size())
            return fail(d_, FEMLOD_EPARSE, user, "bufferView %d out of range (%zu bufferViews)", vi,
                        m_.bufferViews.size());
        const tinygltf::BufferView &v = m_.bufferViews[(size_t)vi];
        std::string ptr = at("bufferViews", (size_t)vi);
        for (const char *ext : {"EXT_meshopt_compression", "KHR_meshopt_compression"})
            if (has_extension(v.extensions, ext) && required(ext))
                return fail(d_, FEMLOD_EUNSUPPORTED, ptr,
                            "compressed with %s, which femlod does not decode", ext);
        if (v.buffer < 0 || (size_t)v.buffer >= m_.buffers.size())
            return fail(d_, FEMLOD_EPARSE, ptr, "buffer %d out of range (%zu buffers)", v.buffer,
                        m_.buffers.size());
        size_t have = m_.buffers[(size_t)v.buffer].data.size(), end;
        if (__builtin_add_overflow(v.byteOffset, v.byteLength, &end) || end > have)
            return fail(d_, FEMLOD_EPARSE, ptr,
                        "bufferView runs past the end of buffer %d (needs %s bytes, has %zu)",
                        v.buffer, end_text(v.byteOffset, v.byteLength).c_str(), have);
        if (v.byteLength == 0)
            return fail(d_, FEMLOD_EPARSE, ptr, "byteLength is 0 (must be at least 1)");
        *base = m_.buffers[(size_t)v.buffer].data.data() + v.byteOffset;
        *length = v.byteLength;
        return FEMLOD_OK;
    }

    static std::string end_text(size_t a, size_t b) {
        size_t s;
        if (__builtin_add_overflow(a, b, &s)) return "more than " + std::to_string(SIZE_MAX);
        return std::to_string(s);
    }

    /* Accessor ai (referenced at user) as elements of its type, the base
     * data (bufferView or zeros) with the sparse values over it. The
     * component and element types are the caller's to check first. */
    femlod_status elements(int ai, const std::string &user, size_t ncomp, Elements *e) const {
        femlod_status st = check_accessor_ref(ai, user);
        if (st != FEMLOD_OK) return st;
        const tinygltf::Accessor &a = m_.accessors[(size_t)ai];
        std::string ptr = at("accessors", (size_t)ai);
        size_t csize = component_size(a.componentType);
        size_t elem = csize * ncomp, count = a.count, total;
        if (count == 0) return fail(d_, FEMLOD_EPARSE, ptr, "count is 0 (must be at least 1)");
        e->count = count;
        e->elem = elem;
        e->ctype = a.componentType;
        if (a.bufferView < 0) {
            if (!a.sparse.isSparse)
                return fail(d_, FEMLOD_EUNSUPPORTED, user,
                            "accessor %d has neither a bufferView nor sparse values (all zeros)",
                            ai);
            if (__builtin_mul_overflow(count, elem, &total) || total > kMaxUnbackedBytes)
                return fail(d_, FEMLOD_ELIMIT, ptr,
                            "%zu elements without a bufferView: more than the %zu bytes femlod "
                            "makes up for an accessor the file does not hold",
                            count, kMaxUnbackedBytes);
            e->bytes.assign(total, 0);
        } else {
            const unsigned char *base;
            size_t length, need, span;
            st = view(a.bufferView, ptr, &base, &length);
            if (st != FEMLOD_OK) return st;
            size_t stride = m_.bufferViews[(size_t)a.bufferView].byteStride;
            if (stride != 0 && stride < elem)
                return fail(d_, FEMLOD_EPARSE, ptr,
                            "elements of %zu bytes do not fit the byteStride %zu of bufferView %d",
                            elem, stride, a.bufferView);
            if (stride == 0) stride = elem;
            if (__builtin_mul_overflow(count - 1, stride, &span) ||
                __builtin_add_overflow(span, elem, &need) ||
                __builtin_add_overflow(need, a.byteOffset, &need) || need > length) {
                std::string needs = "more than " + std::to_string(length);
                size_t n2;
                if (!__builtin_mul_overflow(count - 1, stride, &span) &&
                    !__builtin_add_overflow(span, elem, &n2) &&
                    !__builtin_add_overflow(n2, a.byteOffset, &n2))
                    needs = std::to_string(n2);
                return fail(d_, FEMLOD_EPARSE, ptr,
                            "accessor runs past the end of bufferView %d (needs %s bytes, has %zu)",
                            a.bufferView, needs.c_str(), length);
            }
            total = count * elem; /* <= need <= length: no overflow */
            e->bytes.resize(total);
            const unsigned char *src = base + a.byteOffset;
            if (stride == elem) {
                memcpy(e->bytes.data(), src, total);
            } else {
                for (size_t i = 0; i < count; i++)
                    memcpy(&e->bytes[i * elem], src + i * stride, elem);
            }
        }
        if (a.sparse.isSparse) return sparse(ai, e);
        return FEMLOD_OK;
    }

    /* Sparse values over the base elements (glTF 2.0 "Sparse Accessors"). */
    femlod_status sparse(int ai, Elements *e) const {
        const tinygltf::Accessor &a = m_.accessors[(size_t)ai];
        std::string ptr = at("accessors", (size_t)ai) + "/sparse";
        int n = a.sparse.count;
        if (n < 1 || (size_t)n > e->count)
            return fail(d_, FEMLOD_EPARSE, ptr, "count %d out of range (1 to %zu)", n, e->count);
        int ict = a.sparse.indices.componentType;
        if (!is_index_type(ict))
            return fail(d_, FEMLOD_EPARSE, ptr + "/indices",
                        "componentType %d is not UNSIGNED_BYTE, UNSIGNED_SHORT or UNSIGNED_INT",
                        ict);
        const unsigned char *ibase, *vbase;
        size_t ilen, vlen, isize = component_size(ict), ineed, vneed;
        femlod_status st = view(a.sparse.indices.bufferView, ptr + "/indices", &ibase, &ilen);
        if (st != FEMLOD_OK) return st;
        st = view(a.sparse.values.bufferView, ptr + "/values", &vbase, &vlen);
        if (st != FEMLOD_OK) return st;
        int ioff = a.sparse.indices.byteOffset, voff = a.sparse.values.byteOffset;
        if (ioff < 0 || __builtin_mul_overflow((size_t)n, isize, &ineed) ||
            __builtin_add_overflow(ineed, (size_t)ioff, &ineed) || ineed > ilen)
            return fail(d_, FEMLOD_EPARSE, ptr + "/indices",
                        "%d indices run past the end of bufferView %d (%zu bytes)", n,
                        a.sparse.indices.bufferView, ilen);
        if (voff < 0 || __builtin_mul_overflow((size_t)n, e->elem, &vneed) ||
            __builtin_add_overflow(vneed, (size_t)voff, &vneed) || vneed > vlen)
            return fail(d_, FEMLOD_EPARSE, ptr + "/values",
                        "%d values run past the end of bufferView %d (%zu bytes)", n,
                        a.sparse.values.bufferView, vlen);
        ibase += ioff;
        vbase += voff;
        uint32_t prev = 0;
        for (size_t k = 0; k < (size_t)n; k++) {
            uint32_t i = get_index(ibase + k * isize, ict);
            if (i >= e->count)
                return fail(d_, FEMLOD_EPARSE, ptr + "/indices",
                            "index %u (entry %zu) out of range (%zu elements)", i, k, e->count);
            if (k > 0 && i <= prev)
                return fail(d_, FEMLOD_EPARSE, ptr + "/indices",
                            "index %u (entry %zu) does not increase", i, k);
            prev = i;
            memcpy(&e->bytes[(size_t)i * e->elem], vbase + k * e->elem, e->elem);
        }
        return FEMLOD_OK;
    }

    femlod_status positions(int ai, const std::string &user, std::vector<double> *out) const {
        femlod_status st = check_accessor_ref(ai, user);
        if (st != FEMLOD_OK) return st;
        const tinygltf::Accessor &a = m_.accessors[(size_t)ai];
        std::string ptr = at("accessors", (size_t)ai);
        if (a.componentType != TINYGLTF_COMPONENT_TYPE_FLOAT || a.type != TINYGLTF_TYPE_VEC3) {
            bool quantized = required("KHR_mesh_quantization");
            return fail(d_, quantized ? FEMLOD_EUNSUPPORTED : FEMLOD_EPARSE, ptr,
                        "POSITION is %s %s (FLOAT VEC3 expected%s)",
                        component_name(a.componentType), type_name(a.type),
                        quantized ? "; KHR_mesh_quantization is not supported" : "");
        }
        Elements e;
        if ((st = elements(ai, user, 3, &e)) != FEMLOD_OK) return st;
        if (e.count > UINT32_MAX)
            return fail(d_, FEMLOD_ELIMIT, ptr, "%zu vertices (limit %u)", e.count,
                        (unsigned)UINT32_MAX);
        out->resize(3 * e.count);
        for (size_t i = 0; i < 3 * e.count; i++) {
            uint32_t u = get_u32le(&e.bytes[4 * i]);
            float f;
            memcpy(&f, &u, sizeof f);
            if (!std::isfinite(f))
                return fail(d_, FEMLOD_EPARSE, ptr, "element %zu: coordinate is not finite (%s)",
                            i / 3, std::isnan(f) ? "nan" : "inf");
            (*out)[i] = f;
        }
        return FEMLOD_OK;
    }

    femlod_status indices(int ai, const std::string &user, size_t nverts, int pos_ai,
                          std::vector<uint32_t> *out) const {
        femlod_status st = check_accessor_ref(ai, user);
        if (st != FEMLOD_OK) return st;
        const tinygltf::Accessor &a = m_.accessors[(size_t)ai];
        std::string ptr = at("accessors", (size_t)ai);
        if (!is_index_type(a.componentType) || a.type != TINYGLTF_TYPE_SCALAR)
            return fail(d_, FEMLOD_EPARSE, ptr,
                        "indices are %s %s (UNSIGNED_BYTE, UNSIGNED_SHORT or UNSIGNED_INT SCALAR "
                        "expected)",
                        component_name(a.componentType), type_name(a.type));
        Elements e;
        if ((st = elements(ai, user, 1, &e)) != FEMLOD_OK) return st;
        out->resize(e.count);
        for (size_t i = 0; i < e.count; i++) {
            uint32_t v = get_index(&e.bytes[i * e.elem], e.ctype);
            if (v >= nverts)
                return fail(d_, FEMLOD_EPARSE, ptr,
                            "index %u (element %zu) out of range (POSITION /accessors/%d has %zu "
                            "elements)",
                            v, i, pos_ai, nverts);
            (*out)[i] = v;
        }
        return FEMLOD_OK;
    }

    femlod_status primitive(size_t mi, size_t pi, Prim *out) const {
        femlod_status st = check_refs(mi, pi);
        if (st != FEMLOD_OK) return st;
        const tinygltf::Primitive &p = m_.meshes[mi].primitives[pi];
        std::string ptr = at("meshes", mi) + at("primitives", pi);
        int pos_ai = p.attributes.find("POSITION")->second;
        if ((st = positions(pos_ai, ptr + "/attributes/POSITION", &out->pos)) != FEMLOD_OK)
            return st;
        size_t nv = out->pos.size() / 3;
        std::vector<uint32_t> list;
        if (p.indices != -1) {
            st = indices(p.indices, ptr + "/indices", nv, pos_ai, &list);
            if (st != FEMLOD_OK) return st;
        } else {
            list.resize(nv);
            for (size_t i = 0; i < nv; i++) list[i] = (uint32_t)i;
        }
        size_t n = list.size();
        std::vector<uint32_t> &tri = out->tri;
        if (p.mode == TINYGLTF_MODE_TRIANGLES) {
            if (n % 3 != 0)
                return fail(d_, FEMLOD_EPARSE, ptr,
                            "%zu %s do not make whole triangles (TRIANGLES takes 3 each)", n,
                            p.indices != -1 ? "indices" : "vertices");
            tri.swap(list);
            return FEMLOD_OK;
        }
        if (n < 3)
            return fail(d_, FEMLOD_EPARSE, ptr, "%s of %zu %s makes no triangle (3 needed)",
                        mode_name(p.mode), n, p.indices != -1 ? "indices" : "vertices");
        tri.resize(3 * (n - 2));
        for (size_t i = 0; i + 2 < n; i++) {
            uint32_t *t = &tri[3 * i];
            if (p.mode == TINYGLTF_MODE_TRIANGLE_STRIP) {
                /* glTF: p_i = {v_i, v_{i+(1+i%2)}, v_{i+(2-i%2)}} keeps one winding. */
                t[0] = list[i];
                t[1] = list[i + 1 + i % 2];
                t[2] = list[i + 2 - i % 2];
            } else { /* fan: p_i = {v_{i+1}, v_{i+2}, v_0} */
                t[0] = list[i + 1];
                t[1] = list[i + 2];
                t[2] = list[0];
            }
        }
        return FEMLOD_OK;
    }

    const Diag &d_;
    const tinygltf::Model &m_;
    std::vector<std::vector<Prim>> cache_;
    std::vector<char> cached_;
};

/* Node n's own transform (matrix, or translation * rotation * scale). */
femlod_status local_transform(const Diag &d, const tinygltf::Node &node, size_t n, Mat *out) {
    std::string ptr = at("nodes", n);
    if (!node.matrix.empty()) {
        if (node.matrix.size() != 16)
            return fail(d, FEMLOD_EPARSE, ptr + "/matrix", "%zu numbers (16 expected)",
                        node.matrix.size());
        if (!all_finite(node.matrix))
            return fail(d, FEMLOD_EPARSE, ptr + "/matrix", "a number is not finite");
        for (int i = 0; i < 16; i++) out->m[i] = node.matrix[(size_t)i];
        if (out->m[3] != 0.0 || out->m[7] != 0.0 || out->m[11] != 0.0 || out->m[15] != 1.0)
            return fail(d, FEMLOD_EPARSE, ptr + "/matrix",
                        "not an affine transform (its last row must be 0 0 0 1)");
        return FEMLOD_OK;
    }
    *out = identity();
    const struct {
        const std::vector<double> &v;
        size_t n;
        const char *key;
    } parts[] = {{node.translation, 3, "/translation"},
                 {node.rotation, 4, "/rotation"},
                 {node.scale, 3, "/scale"}};
    for (const auto &p : parts) {
        if (p.v.empty()) continue;
        if (p.v.size() != p.n)
            return fail(d, FEMLOD_EPARSE, ptr + p.key, "%zu numbers (%zu expected)", p.v.size(),
                        p.n);
        if (!all_finite(p.v)) return fail(d, FEMLOD_EPARSE, ptr + p.key, "a number is not finite");
    }
    double *m = out->m;
    if (!node.rotation.empty()) {
        double x = node.rotation[0], y = node.rotation[1], z = node.rotation[2],
               w = node.rotation[3];
        double nn = x * x + y * y + z * z + w * w;
        if (!(nn > 0.0) || !std::isfinite(nn))
            return fail(d, FEMLOD_EPARSE, ptr + "/rotation", "not a usable quaternion (length 0)");
        double s = 2.0 / nn; /* normalises a quaternion that is not quite unit */
        m[0] = 1.0 - s * (y * y + z * z);
        m[1] = s * (x * y + w * z);
        m[2] = s * (x * z - w * y);
        m[4] = s * (x * y - w * z);
        m[5] = 1.0 - s * (x * x + z * z);
        m[6] = s * (y * z + w * x);
        m[8] = s * (x * z + w * y);
        m[9] = s * (y * z - w * x);
        m[10] = 1.0 - s * (x * x + y * y);
    }
    if (!node.scale.empty())
        for (int c = 0; c < 3; c++)
            for (int r = 0; r < 3; r++) m[c * 4 + r] *= node.scale[(size_t)c];
    if (!node.translation.empty())
        for (int r = 0; r < 3; r++) m[12 + r] = node.translation[(size_t)r];
    return FEMLOD_OK;
}

/* Appends the triangles of mesh mi, placed by world, as corner positions. */
femlod_status emit(const Diag &d, Reader &rd, size_t mi, const Mat &world, const std::string &who,
                   std::vector<double> *corners) {
    const std::vector<Prim> *prims;
    femlod_status st = rd.mesh(mi, &prims);
    if (st != FEMLOD_OK) return st;
    bool ident = is_identity(world);
    /* A mirroring transform turns the winding (glTF "Meshes"): turn it back
     * so that outward stays outward. */
    bool flip = det3(world) < 0.0;
    const double *m = world.m;
    std::vector<double> placed;
    for (const Prim &p : *prims) {
        const std::vector<double> *pos = &p.pos;
        if (!ident) {
            placed.resize(p.pos.size());
            for (size_t v = 0; v < p.pos.size(); v += 3) {
                double x = p.pos[v], y = p.pos[v + 1], z = p.pos[v + 2];
                for (int r = 0; r < 3; r++) {
                    double t = m[r] * x + m[4 + r] * y + m[8 + r] * z + m[12 + r];
                    if (!std::isfinite(t))
                        return fail(d, FEMLOD_EPARSE, who,
                                    "a vertex of mesh %zu is not finite once transformed", mi);
                    placed[v + (size_t)r] = t;
                }
            }
            pos = &placed;
        }
        size_t nt = p.tri.size() / 3, have = corners->size() / 9;
        if (nt > (size_t)UINT32_MAX - have)
            return fail(d, FEMLOD_ELIMIT, "", "more than %u triangles", (unsigned)UINT32_MAX);
        size_t start = corners->size();
        corners->resize(start + 9 * nt);
        double *out = corners->data() + start;
        for (size_t t = 0; t < nt; t++) {
            const uint32_t *tri = &p.tri[3 * t];
            uint32_t order[3] = {tri[0], flip ? tri[2] : tri[1], flip ? tri[1] : tri[2]};
            for (int c = 0; c < 3; c++) {
                const double *q = pos->data() + 3 * (size_t)order[c];
                *out++ = q[0];
                *out++ = q[1];
                *out++ = q[2];
            }
        }
    }
    return FEMLOD_OK;
}

/* Required extensions that cannot change the geometry femlod reads. */
bool harmless_extension(const std::string &e) {
    static const char *const prefixes[] = {"KHR_materials_", "KHR_texture_",        "EXT_texture_",
                                           "MSFT_texture_",  "KHR_lights_punctual", "KHR_xmp"};
    for (const char *p : prefixes)
        if (e.compare(0, strlen(p), p) == 0) return true;
    /* Compression is refused where it is used (naming the primitive or view). */
    return e == "KHR_draco_mesh_compression" || e == "EXT_meshopt_compression" ||
           e == "KHR_meshopt_compression";
}

femlod_status extract(const Diag &d, const tinygltf::Model &m, std::vector<double> *corners) {
    for (size_t i = 0; i < m.extensionsRequired.size(); i++)
        if (!harmless_extension(m.extensionsRequired[i]))
            return fail(d, FEMLOD_EUNSUPPORTED, at("extensionsRequired", i),
                        "required extension %s is not supported",
                        shown(m.extensionsRequired[i]).c_str());
    Reader rd(d, m);
    if (m.scenes.empty()) {
        /* No scene: every mesh as it stands, in mesh order. */
        for (size_t mi = 0; mi < m.meshes.size(); mi++) {
            femlod_status st = emit(d, rd, mi, identity(), at("meshes", mi), corners);
            if (st != FEMLOD_OK) return st;
        }
        return FEMLOD_OK;
    }
    if (m.defaultScene < -1 || (m.defaultScene >= 0 && (size_t)m.defaultScene >= m.scenes.size()))
        return fail(d, FEMLOD_EPARSE, "/scene", "scene %d out of range (%zu scenes)",
                    m.defaultScene, m.scenes.size());
    size_t si = m.defaultScene < 0 ? 0 : (size_t)m.defaultScene;
    const std::vector<int> &roots = m.scenes[si].nodes;
    size_t nn = m.nodes.size();
    std::vector<char> seen(nn, 0);
    std::vector<Mat> world(nn);
    /* Depth first, children in order, without recursion (trees can be deep). */
    struct Item {
        int node;
        int parent;  /* -1: a root */
        size_t slot; /* its place in the parent's children (or the scene's nodes) */
    };
    std::vector<Item> stack;
    for (size_t k = roots.size(); k-- > 0;) stack.push_back({roots[k], -1, k});
    while (!stack.empty()) {
        Item it = stack.back();
        stack.pop_back();
        std::string where = it.parent < 0
                                ? at("scenes", si) + at("nodes", it.slot)
                                : at("nodes", (size_t)it.parent) + at("children", it.slot);
        if (it.node < 0 || (size_t)it.node >= nn)
            return fail(d, FEMLOD_EPARSE, where, "node %d out of range (%zu nodes)", it.node, nn);
        size_t n = (size_t)it.node;
        if (seen[n])
            return fail(d, FEMLOD_EPARSE, where,
                        "node %zu is reached twice from /scenes/%zu (a node has one parent, and "
                        "no cycle)",
                        n, si);
        seen[n] = 1;
        const tinygltf::Node &node = m.nodes[n];
        Mat local;
        femlod_status st = local_transform(d, node, n, &local);
        if (st != FEMLOD_OK) return st;
        world[n] = it.parent < 0 ? local : multiply(world[(size_t)it.parent], local);
        for (double x : world[n].m)
            if (!std::isfinite(x))
                return fail(d, FEMLOD_EPARSE, at("nodes", n),
                            "the transform from the scene root is not finite");
        if (node.mesh != -1) {
            if (node.mesh < 0 || (size_t)node.mesh >= m.meshes.size())
                return fail(d, FEMLOD_EPARSE, at("nodes", n) + "/mesh",
                            "mesh %d out of range (%zu meshes)", node.mesh, m.meshes.size());
            if (has_extension(node.extensions, "EXT_mesh_gpu_instancing"))
                return fail(d, FEMLOD_EUNSUPPORTED, at("nodes", n),
                            "EXT_mesh_gpu_instancing is not supported");
            st = emit(d, rd, (size_t)node.mesh, world[n], at("nodes", n), corners);
            if (st != FEMLOD_OK) return st;
        }
        for (size_t k = node.children.size(); k-- > 0;)
            stack.push_back({node.children[k], it.node, k});
    }
    return FEMLOD_OK;
}

/* The first problem with a data: URI's base64 text, or "" when it has none
 * (tinygltf's decoder stops quietly at the first bad character). */
std::string base64_problem(const std::string &uri) {
    size_t comma = uri.find(',');
    if (comma == std::string::npos) return "data URI without ','";
    size_t n = uri.size() - comma - 1, pad = 0;
    for (size_t i = 0; i < n; i++) {
        char ch = uri[comma + 1 + i];
        if (ch == '=') {
            pad++;
            continue;
        }
        if (!ascii_alnum(ch) && ch != '+' && ch != '/')
            return "data URI is not base64: character " + shown(std::string(1, ch)) +
                   " at offset " + std::to_string(i);
        if (pad)
            return "data URI is not base64: data after the '=' padding at offset " +
                   std::to_string(i);
    }
    if (pad > 2 || (pad && n % 4 != 0) || n % 4 == 1)
        return "data URI is not base64: " + std::to_string(n) + " characters, " +
               std::to_string(pad) + " of them '=' padding";
    return "";
}

/* tinygltf refused the file: say what is wrong as precisely as we can. The
 * model holds what was parsed before the failure. */
femlod_status diagnose(const Diag &d, const tinygltf::Model &m, const FsContext &fs,
                       const std::string &e) {
    for (size_t i = 0; i < m.extensionsRequired.size(); i++) {
        const std::string &x = m.extensionsRequired[i];
        if (x == "EXT_meshopt_compression" || x == "KHR_meshopt_compression")
            return fail(d, FEMLOD_EUNSUPPORTED, at("extensionsRequired", i),
                        "%s (compressed buffer views) is not supported", x.c_str());
    }
    size_t b = m.buffers.size(); /* the buffer being loaded, if it was the buffers */
    if (fs.status != FEMLOD_OK)
        return fail(d, fs.status, at("buffers", b), "%s", fs.reason.c_str());
    static const char decode[] = "Failed to decode 'uri' : ";
    size_t k = e.find(decode);
    if (k != std::string::npos) {
        size_t s = k + sizeof decode - 1, end = e.find(" in Buffer", s);
        std::string uri = e.substr(s, end == std::string::npos ? std::string::npos : end - s);
        std::string why = base64_problem(uri);
        if (why.empty()) why = "data URI does not decode to the buffer's byteLength";
        return fail(d, FEMLOD_EPARSE, at("buffers", b), "%s", why.c_str());
    }
    size_t want = 0, got = 0;
    k = e.find("requestedBytes ");
    if (k != std::string::npos &&
        sscanf(e.c_str() + k, "requestedBytes %zu, but got %zu", &want, &got) == 2)
        return fail(d, FEMLOD_EPARSE, at("buffers", b),
                    "buffer file has %zu bytes, but byteLength is %zu", got, want);
    if (e.find("File is empty") != std::string::npos)
        return fail(d, FEMLOD_EPARSE, at("buffers", b), "buffer file is empty");
    if (e.compare(0, 16, "[json.exception.") == 0) {
        size_t close = e.find("] ");
        std::string text = close == std::string::npos ? e : e.substr(close + 2);
        return fail(d, FEMLOD_EPARSE, "", "invalid JSON: %s", text.c_str());
    }
    /* tinygltf checks some primitive references after parsing the meshes;
     * ours say which. */
    Reader rd(d, m);
    for (size_t mi = 0; mi < m.meshes.size(); mi++)
        for (size_t pi = 0; pi < m.meshes[mi].primitives.size(); pi++) {
            femlod_status st = rd.check_refs(mi, pi);
            if (st != FEMLOD_OK) return st;
        }
    std::string line = e.substr(0, e.find('\n'));
    if (line.empty()) line = "tinygltf could not load the file";
    return fail(d, FEMLOD_EPARSE, "", "%s", line.c_str());
}

/* tinygltf turns "extras" and "extensions" into values recursively: JSON
 * nested a few hundred thousand levels deep overflows the stack. Real glTF
 * nests less than a dozen levels. */
const size_t kMaxJsonDepth = 256;

/* Byte offset where text[0..n) nests deeper than kMaxJsonDepth, or n. */
size_t too_deep(const char *text, size_t n) {
    size_t depth = 0;
    bool in_string = false;
    for (size_t i = 0; i < n; i++) {
        char ch = text[i];
        if (in_string) {
            if (ch == '\\')
                i++;
            else if (ch == '"')
                in_string = false;
        } else if (ch == '"') {
            in_string = true;
        } else if (ch == '[' || ch == '{') {
            if (++depth > kMaxJsonDepth) return i;
        } else if ((ch == ']' || ch == '}') && depth > 0) {
            depth--;
        }
    }
    return n;
}

/* The folder of path, as tinygltf will join it with URIs. */
std::string folder_of(const char *path) {
    const char *slash = strrchr(path, '/');
    if (!slash) return ".";
    if (slash == path) return "/";
    return std::string(path, (size_t)(slash - path));
}

femlod_status read_gltf(femlod_mesh **out, const char *data, size_t size, const Diag &d,
                        const char *file, femlod_format format) {
    const unsigned char *u = reinterpret_cast<const unsigned char *>(data);
    if (size == 0) return fail(d, FEMLOD_EPARSE, "", "empty file");
    if (size > UINT_MAX)
        return fail(d, FEMLOD_ELIMIT, "", "%zu bytes: glTF files of 4 GiB or more are not read",
                    size);
    bool glb = size >= 4 && memcmp(data, "glTF", 4) == 0;
    if (!glb && format == FEMLOD_FORMAT_GLB) {
        size_t i = (size >= 3 && memcmp(data, "\xEF\xBB\xBF", 3) == 0) ? 3 : 0;
        while (i < size &&
               (data[i] == ' ' || data[i] == '\t' || data[i] == '\r' || data[i] == '\n'))
            i++;
        if (i == size || data[i] != '{')
            return at_byte(d, FEMLOD_EPARSE, 0, "not a GLB file (no 'glTF' magic) nor glTF JSON");
    }
    size_t json_at = 0, json_len = size;
    if (glb) {
        femlod_status st = check_glb(d, u, size);
        if (st != FEMLOD_OK) return st;
        json_at = 20;
        json_len = get_u32le(u + 12);
    }
    size_t deep = too_deep(data + json_at, json_len);
    if (deep < json_len)
        return at_byte(d, FEMLOD_ELIMIT, json_at + deep,
                       "JSON nested more than " + std::to_string(kMaxJsonDepth) + " levels deep");

    FsContext fs;
    std::string base;
    if (file) {
        base = folder_of(file);
        fs.base = base.c_str();
        fs.prefix = base.back() == '/' ? base : base + "/";
    }
    tinygltf::TinyGLTF loader;
    loader.SetImageLoader(keep_image, nullptr);
    loader.SetFsCallbacks({fs_exists, fs_expand, fs_read, fs_write, &fs});
    tinygltf::Model model;
    std::string e, w;
    bool ok = glb ? loader.LoadBinaryFromMemory(&model, &e, &w, u, (unsigned)size, base)
                  : loader.LoadASCIIFromString(&model, &e, &w, data, (unsigned)size, base);
    if (!ok) return diagnose(d, model, fs, e);
    for (size_t i = 0; i < model.buffers.size(); i++)
        if (tinygltf::IsDataURI(model.buffers[i].uri)) {
            std::string why = base64_problem(model.buffers[i].uri);
            if (!why.empty()) return fail(d, FEMLOD_EPARSE, at("buffers", i), "%s", why.c_str());
        }

    std::vector<double> corners;
    femlod_status st = extract(d, model, &corners);
    if (st != FEMLOD_OK) return st;
    femlod_error weld;
    st = fl_mesh_from_soup(out, corners.data(), corners.size() / 9, &weld);
    if (st != FEMLOD_OK) return fail(d, st, "", "%s", weld.message);
    return FEMLOD_OK;
}

/* }====== */

/* {====== writing */

/* Matplotlib's viridis (van der Walt and Smith, CC0), sRGB, samples 0, 16,
 * ..., 240 and 255 of its 256-entry table at t = index / 255. */
const struct {
    double t, r, g, b;
} kViridis[] = {
    {0.0 / 255, 0.267004, 0.004874, 0.329415},   {16.0 / 255, 0.282327, 0.094955, 0.417331},
    {32.0 / 255, 0.278826, 0.175490, 0.483397},  {48.0 / 255, 0.258965, 0.251537, 0.524736},
    {64.0 / 255, 0.229739, 0.322361, 0.545706},  {80.0 / 255, 0.199430, 0.387607, 0.554642},
    {96.0 / 255, 0.172719, 0.448791, 0.557885},  {112.0 / 255, 0.149039, 0.508051, 0.557250},
    {128.0 / 255, 0.127568, 0.566949, 0.550556}, {144.0 / 255, 0.120638, 0.625828, 0.533488},
    {160.0 / 255, 0.157851, 0.683765, 0.501686}, {176.0 / 255, 0.246070, 0.738910, 0.452024},
    {192.0 / 255, 0.369214, 0.788888, 0.382914}, {208.0 / 255, 0.515992, 0.831158, 0.294279},
    {224.0 / 255, 0.678489, 0.863742, 0.189503}, {240.0 / 255, 0.845561, 0.887322, 0.099702},
    {255.0 / 255, 0.993248, 0.906157, 0.143936},
};

/* sRGB transfer function inverse: COLOR_0 is linear (glTF "Meshes"). */
double srgb_to_linear(double c) {
    return c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4);
}

/* Linear RGB of viridis at t in [0, 1] (clamped; NaN as 0). */
void viridis(double t, float rgb[3]) {
    if (!(t > 0.0)) t = 0.0;
    if (t > 1.0) t = 1.0;
    size_t k = 0;
    const size_t n = sizeof kViridis / sizeof kViridis[0];
    while (k + 2 < n && t > kViridis[k + 1].t) k++;
    double f = (t - kViridis[k].t) / (kViridis[k + 1].t - kViridis[k].t);
    double c[3] = {kViridis[k].r + f * (kViridis[k + 1].r - kViridis[k].r),
                   kViridis[k].g + f * (kViridis[k + 1].g - kViridis[k].g),
                   kViridis[k].b + f * (kViridis[k + 1].b - kViridis[k].b)};
    for (int i = 0; i < 3; i++) {
        double l = srgb_to_linear(c[i]);
        rgb[i] = (float)(l < 0.0 ? 0.0 : l > 1.0 ? 1.0 : l);
    }
}

/* x as a float, the float range's ends beyond it (an edge of a mesh near the
 * range's limits can be longer than FLT_MAX). */
float saturate(double x) { return (float)(x > FLT_MAX ? FLT_MAX : x < -FLT_MAX ? -FLT_MAX : x); }

/* The writer's scales (docs/formats.md). */
const double kValenceLow = 3.0, kValenceHigh = 12.0;

/* One little-endian binary buffer, every view starting at a multiple of 4. */
struct Bin {
    std::vector<unsigned char> data;
    void f32(float f) {
        uint32_t u;
        memcpy(&u, &f, sizeof u);
        u32(u);
    }
    void u32(uint32_t v) {
        unsigned char b[4] = {(unsigned char)v, (unsigned char)(v >> 8), (unsigned char)(v >> 16),
                              (unsigned char)(v >> 24)};
        data.insert(data.end(), b, b + 4);
    }
    void u16(uint32_t v) {
        data.push_back((unsigned char)v);
        data.push_back((unsigned char)(v >> 8));
    }
    void pad() {
        while (data.size() % 4) data.push_back(0);
    }
};

/* A bufferView over data[start..) and an accessor over all of it. */
int add_accessor(tinygltf::Model &m, const Bin &bin, size_t start, int target, int ctype, int type,
                 size_t count) {
    tinygltf::BufferView v;
    v.buffer = 0;
    v.byteOffset = start;
    v.byteLength = bin.data.size() - start;
    v.target = target;
    m.bufferViews.push_back(v);
    tinygltf::Accessor a;
    a.bufferView = (int)m.bufferViews.size() - 1;
    a.byteOffset = 0;
    a.componentType = ctype;
    a.type = type;
    a.count = count;
    m.accessors.push_back(a);
    return (int)m.accessors.size() - 1;
}

tinygltf::Value number_value(double x) {
    if (x == std::floor(x) && std::fabs(x) <= (double)INT_MAX) return tinygltf::Value((int)x);
    return tinygltf::Value(x);
}

/* JSON (the caller's extras) to a tinygltf value; nulls are dropped by
 * tinygltf's writer. Depth is bounded so a hostile string cannot exhaust the
 * stack. */
bool to_value(const nlohmann::json &j, tinygltf::Value *out, int depth) {
    if (depth > 64) return false;
    switch (j.type()) {
    case nlohmann::json::value_t::object: {
        tinygltf::Value::Object o;
        for (auto it = j.begin(); it != j.end(); ++it) {
            tinygltf::Value v;
            if (!to_value(it.value(), &v, depth + 1)) return false;
            o[it.key()] = v;
        }
        *out = tinygltf::Value(std::move(o));
        return true;
    }
    case nlohmann::json::value_t::array: {
        tinygltf::Value::Array a;
        for (const auto &x : j) {
            tinygltf::Value v;
            if (!to_value(x, &v, depth + 1)) return false;
            a.push_back(v);
        }
        *out = tinygltf::Value(std::move(a));
        return true;
    }
    case nlohmann::json::value_t::string: *out = tinygltf::Value(j.get<std::string>()); return true;
    case nlohmann::json::value_t::boolean: *out = tinygltf::Value(j.get<bool>()); return true;
    case nlohmann::json::value_t::number_integer:
    case nlohmann::json::value_t::number_unsigned:
    case nlohmann::json::value_t::number_float: *out = number_value(j.get<double>()); return true;
    default: *out = tinygltf::Value(); return true;
    }
}

const char *color_name(femlod_color_by c) {
    switch (c) {
    case FEMLOD_COLOR_STRETCH: return "stretch";
    case FEMLOD_COLOR_SIZE: return "size";
    case FEMLOD_COLOR_VALENCE: return "valence";
    default: return "none";
    }
}

femlod_status write_gltf(const femlod_mesh *mesh, FILE *fp, bool binary,
                         const femlod_write_options *opt, const Diag &d) {
    /* The code is read as an integer: in C++ loading an enum with a value
     * outside its enumerators is undefined, and the caller is C. */
    int code = 0;
    static_assert(sizeof code == sizeof opt->color_by, "femlod_color_by is int-sized");
    if (opt) memcpy(&code, &opt->color_by, sizeof code);
    if (code < FEMLOD_COLOR_NONE || code > FEMLOD_COLOR_VALENCE)
        return fail(d, FEMLOD_EINPUT, "", "invalid color_by code %d", code);
    femlod_color_by color = static_cast<femlod_color_by>(code);
    bool normals = opt && opt->normals;

    tinygltf::Value::Object extras;
    if (opt && opt->extras) {
        nlohmann::json j;
        try {
            j = nlohmann::json::parse(opt->extras);
        } catch (const nlohmann::json::parse_error &e) {
            std::string what = e.what();
            size_t close = what.find("] ");
            return fail(d, FEMLOD_EINPUT, "", "extras is not valid JSON: %s",
                        close == std::string::npos ? what.c_str() : what.c_str() + close + 2);
        }
        if (!j.is_object()) return fail(d, FEMLOD_EINPUT, "", "extras is not a JSON object");
        tinygltf::Value params;
        if (!to_value(j, &params, 0))
            return fail(d, FEMLOD_EINPUT, "", "extras is nested more than 64 levels deep");
        extras["params"] = params;
    }

    femlod_quality q;
    femlod_error qerr;
    femlod_status st = femlod_mesh_quality(mesh, &q, &qerr);
    if (st != FEMLOD_OK) return fail(d, st, "", "%s", qerr.message);
    tinygltf::Value::Object qual;
    qual["triangles"] = number_value((double)q.triangles);
    qual["vertices"] = number_value((double)q.vertices);
    qual["stretch_avg"] = tinygltf::Value(q.stretch_avg);
    qual["stretch_min"] = tinygltf::Value(q.stretch_min);
    qual["size_max"] = tinygltf::Value(q.size_max);
    qual["valence_max"] = number_value((double)q.valence_max);
    extras["quality"] = tinygltf::Value(std::move(qual));

    tinygltf::Model m;
    m.asset.version = "2.0";
    m.asset.generator = "femlod " FEMLOD_VERSION_STRING;

    const size_t nv = mesh->nv, nt = mesh->nt;
    const double *pos = mesh->pos;
    const uint32_t *tri = mesh->tri;
    for (size_t i = 0; i < 3 * nv; i++)
        if (!(std::fabs(pos[i]) <= FLT_MAX)) /* so every (float) below is in range */
            return fail(d, FEMLOD_EINPUT, "",
                        "vertex %zu: coordinate %g does not fit in float32 (glTF positions are "
                        "float32)",
                        i / 3, pos[i]);

    if (nt > 0) {
        /* Per triangle measures are shown flat: every triangle gets its own
         * three vertices, so a bad element is never blended with its
         * neighbours. Valence is per vertex and keeps the shared vertices. */
        bool flat = color == FEMLOD_COLOR_STRETCH || color == FEMLOD_COLOR_SIZE;
        std::vector<double> value; /* per triangle (flat) or per vertex */
        double lo = 0.0, hi = 1.0;
        if (color == FEMLOD_COLOR_STRETCH) {
            value.resize(nt);
            femlod_stretch_array(value.data(), pos, tri, nt);
        } else if (color == FEMLOD_COLOR_SIZE) {
            value.resize(nt);
            femlod_size_array(value.data(), pos, tri, nt);
            lo = hi = value[0];
            for (double s : value) {
                lo = std::min(lo, s);
                hi = std::max(hi, s);
            }
        } else if (color == FEMLOD_COLOR_VALENCE) {
            std::vector<uint32_t> val(nv);
            femlod_error verr;
            st = femlod_valence_array(val.data(), nv, tri, nt, &verr);
            if (st != FEMLOD_OK) return fail(d, st, "", "%s", verr.message);
            value.assign(val.begin(), val.end());
            lo = kValenceLow;
            hi = kValenceHigh;
        }
        std::vector<float> nrm;
        if (normals) {
            /* Area-weighted: the sum of the unnormalised face normals. */
            std::vector<double> acc(3 * nv, 0.0);
            for (size_t t = 0; t < nt; t++) {
                const double *a = pos + 3 * (size_t)tri[3 * t],
                             *b = pos + 3 * (size_t)tri[3 * t + 1],
                             *c = pos + 3 * (size_t)tri[3 * t + 2];
                double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
                double v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
                double n[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2],
                               u[0] * v[1] - u[1] * v[0]};
                for (int k = 0; k < 3; k++)
                    for (int r = 0; r < 3; r++)
                        acc[3 * (size_t)tri[3 * t + (size_t)k] + (size_t)r] += n[r];
            }
            nrm.resize(3 * nv);
            for (size_t v = 0; v < nv; v++) {
                double *n = &acc[3 * v];
                double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
                bool ok = len > 0.0 && std::isfinite(len);
                /* A vertex of degenerate triangles only has no normal; glTF
                 * wants unit length: +z. */
                for (int r = 0; r < 3; r++)
                    nrm[3 * v + (size_t)r] = ok ? (float)(n[r] / len) : (r == 2 ? 1.0f : 0.0f);
            }
        }

        /* The vertices as written: the mesh's, or three per triangle. */
        size_t count = flat ? 3 * nt : nv;
        auto source = [&](size_t i) -> size_t { return flat ? tri[i] : i; };
        size_t bytes_per_vertex = 12 + (normals ? 12 : 0) + (color ? 16 : 0), total;
        if (__builtin_mul_overflow(count, bytes_per_vertex, &total) ||
            __builtin_add_overflow(total, flat ? 0 : 12 * nt, &total) || total > (size_t)INT_MAX)
            return fail(d, FEMLOD_ELIMIT, "",
                        "%zu bytes of buffer data: more than tinygltf 2.7 writes (2 GiB)", total);
        Bin bin;
        bin.data.reserve(total + 16);
        tinygltf::Primitive prim;
        prim.mode = TINYGLTF_MODE_TRIANGLES;

        size_t start = 0;
        std::vector<double> lo3(3, HUGE_VAL), hi3(3, -HUGE_VAL);
        for (size_t i = 0; i < count; i++) {
            const double *p = pos + 3 * source(i);
            for (size_t k = 0; k < 3; k++) {
                float f = (float)p[k];
                lo3[k] = std::min(lo3[k], (double)f);
                hi3[k] = std::max(hi3[k], (double)f);
                bin.f32(f);
            }
        }
        int acc = add_accessor(m, bin, start, TINYGLTF_TARGET_ARRAY_BUFFER,
                               TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC3, count);
        m.accessors[(size_t)acc].minValues = lo3;
        m.accessors[(size_t)acc].maxValues = hi3;
        prim.attributes["POSITION"] = acc;
        if (normals) {
            start = bin.data.size();
            for (size_t i = 0; i < count; i++)
                for (size_t k = 0; k < 3; k++) bin.f32(nrm[3 * source(i) + k]);
            prim.attributes["NORMAL"] =
                add_accessor(m, bin, start, TINYGLTF_TARGET_ARRAY_BUFFER,
                             TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC3, count);
        }
        if (color) {
            auto raw = [&](size_t i) { return flat ? value[i / 3] : value[i]; };
            start = bin.data.size();
            for (size_t i = 0; i < count; i++) {
                float rgb[3];
                double x = raw(i);
                viridis(hi > lo ? (x - lo) / (hi - lo) : 0.0, rgb);
                for (float c : rgb) bin.f32(c);
            }
            prim.attributes["COLOR_0"] =
                add_accessor(m, bin, start, TINYGLTF_TARGET_ARRAY_BUFFER,
                             TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC3, count);
            start = bin.data.size();
            for (size_t i = 0; i < count; i++) bin.f32(saturate(raw(i)));
            const char *attr = color == FEMLOD_COLOR_STRETCH ? "_STRETCH"
                               : color == FEMLOD_COLOR_SIZE  ? "_SIZE"
                                                             : "_VALENCE";
            prim.attributes[attr] =
                add_accessor(m, bin, start, TINYGLTF_TARGET_ARRAY_BUFFER,
                             TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_SCALAR, count);

            tinygltf::Value::Object scale;
            scale["map"] = tinygltf::Value(std::string("viridis"));
            scale["attribute"] = tinygltf::Value(std::string(attr));
            scale["min"] = tinygltf::Value(lo);
            scale["max"] = tinygltf::Value(hi);
            scale["per"] = tinygltf::Value(std::string(flat ? "triangle" : "vertex"));
            extras["color_by"] = tinygltf::Value(std::string(color_name(color)));
            extras["color_scale"] = tinygltf::Value(std::move(scale));

            tinygltf::Material mat;
            mat.name = std::string("femlod ") + color_name(color);
            mat.pbrMetallicRoughness.metallicFactor = 0.0;
            mat.doubleSided = true;
            mat.extensions["KHR_materials_unlit"] = tinygltf::Value(tinygltf::Value::Object());
            m.materials.push_back(mat);
            m.extensionsUsed.push_back("KHR_materials_unlit");
            prim.material = 0;
        }
        if (!flat) {
            /* 65535 is the primitive restart value glTF forbids. */
            bool wide = nv > 65535;
            start = bin.data.size();
            for (size_t i = 0; i < 3 * nt; i++) {
                if (wide)
                    bin.u32(tri[i]);
                else
                    bin.u16(tri[i]);
            }
            prim.indices = add_accessor(m, bin, start, TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER,
                                        wide ? TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT
                                             : TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT,
                                        TINYGLTF_TYPE_SCALAR, 3 * nt);
        }
        bin.pad();
        tinygltf::Buffer buf;
        buf.data.swap(bin.data);
        m.buffers.push_back(std::move(buf));

        tinygltf::Mesh gm;
        gm.name = "femlod";
        gm.primitives.push_back(prim);
        m.meshes.push_back(gm);
        tinygltf::Node node;
        node.mesh = 0;
        m.nodes.push_back(node);
        tinygltf::Scene scene;
        scene.nodes.push_back(0);
        m.scenes.push_back(scene);
        m.defaultScene = 0;
    }
    /* An empty mesh is an asset with no scene: a valid glTF that reads back
     * as an empty mesh. */
    m.asset.extras = tinygltf::Value(std::move(extras));

    std::ostringstream ss;
    tinygltf::TinyGLTF writer;
    if (!writer.WriteGltfSceneToStream(&m, ss, !binary, binary) || !ss)
        return fail(d, FEMLOD_EIO, "", "cannot write: tinygltf failed to serialise the model");
    const std::string out = ss.str();
    errno = 0;
    if (fwrite(out.data(), 1, out.size(), fp) != out.size()) {
        int e = errno ? errno : EIO;
        return fail(d, FEMLOD_EIO, "", "cannot write: %s", strerror(e));
    }
    return FEMLOD_OK;
}

/* }====== */

} // namespace

/* {====== the C face: nothing thrown gets past these */

extern "C" femlod_status fl_read_gltf(femlod_mesh **out, const char *data, size_t size,
                                      const char *name, const char *file, femlod_format format,
                                      femlod_error *err) {
    Diag d = {name, err};
    try {
        return read_gltf(out, data, size, d, file, format);
    } catch (const std::bad_alloc &) {
        return fl_error(err, FEMLOD_ENOMEM, "%s: out of memory", name);
    } catch (const std::exception &e) {
        /* tinygltf 2.7 throws, e.g. std::out_of_range on a buffer of byteLength 0 in a GLB. */
        return fl_error(err, FEMLOD_EPARSE, "%s: cannot read glTF: %s", name, e.what());
    } catch (...) {
        return fl_error(err, FEMLOD_EPARSE, "%s: unexpected failure reading glTF", name);
    }
}

extern "C" femlod_status fl_write_gltf(const femlod_mesh *m, FILE *fp, int binary,
                                       const femlod_write_options *options, const char *path,
                                       femlod_error *err) {
    Diag d = {path, err};
    try {
        return write_gltf(m, fp, binary != 0, options, d);
    } catch (const std::bad_alloc &) {
        return fl_error(err, FEMLOD_ENOMEM, "%s: out of memory", path);
    } catch (const std::exception &e) {
        return fl_error(err, FEMLOD_EIO, "%s: cannot write: %s", path, e.what());
    } catch (...) {
        return fl_error(err, FEMLOD_EIO, "%s: cannot write: unexpected failure", path);
    }
}

/* }====== */
