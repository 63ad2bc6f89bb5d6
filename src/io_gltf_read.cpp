/* io_gltf_read.cpp - owns reading glTF 2.0: .gltf (JSON, buffers embedded as
 * data: URIs or in files beside it) and .glb (binary), through fl_read_gltf
 * (core.h). Here: the GLB header, the JSON depth cap, the node matrices,
 * accessors and primitives made into a triangle soup, and the explanation
 * of tinygltf's failures. Buffers outside the file's own bytes come through
 * io_gltf_buffers.cpp; tinygltf and the messages through io_gltf_common.cpp.
 *
 * Specification: Khronos glTF 2.0 (registry.khronos.org/glTF/specs/2.0),
 * sections "Accessors", "Meshes", "Transformations", "GLB File Format".
 *
 * tinygltf 2.7.0 parses the JSON and loads the buffers, and little more
 * (ecosystem-notes.md 2.3): it accepts out-of-range bufferView, buffer and
 * accessor indices, accessors that run past their views, views that run past
 * their buffers, index values past the vertex count, a GLB BIN chunk up to 8
 * bytes past the end of the file, and it follows a buffer URI out of the
 * asset's folder. So this file:
 *   - checks the GLB header itself before tinygltf sees the bytes;
 *   - gives tinygltf the confined file callbacks of io_gltf_buffers.cpp;
 *   - checks every index, offset, stride, count and index value it uses in
 *     overflow-checked size_t arithmetic, naming the JSON pointer;
 *   - makes a fresh TinyGLTF and Model per call and trusts only return
 *     values (tinygltf keeps stale error text);
 *   - installs a do-nothing image loader, so embedded images load as bytes
 *     nobody decodes.
 * fl_read_gltf catches everything and returns a femlod status.
 */
#include <climits>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <new>
#include <string>
#include <vector>

#include "io_gltf.hpp"

namespace {

/* {====== messages and element types */

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

/* {====== GLB header */

const uint32_t kChunkJson = 0x4E4F534A;

femlod_status at_byte(const fl_gltf_diag &d, femlod_status st, size_t byte,
                      const std::string &msg) {
    return fl_error(d.err, st, "%s: byte %zu: %s", d.name, byte, msg.c_str());
}

/* The header and chunk bounds, checked before tinygltf reads them (2.7.0 lets
 * a BIN chunk run 8 bytes past the end of the data). */
femlod_status check_glb(const fl_gltf_diag &d, const unsigned char *u, size_t size) {
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
    Reader(const fl_gltf_diag &d, const tinygltf::Model &m) : d_(d), m_(m) {}

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
            return fl_gltf_fail(d_, FEMLOD_EUNSUPPORTED, ptr,
                                "mode %d (%s) is not a triangle mode (femlod reads TRIANGLES, "
                                "TRIANGLE_STRIP and TRIANGLE_FAN)",
                                p.mode, mode_name(p.mode));
        if (p.mode < TINYGLTF_MODE_POINTS || p.mode > TINYGLTF_MODE_TRIANGLE_FAN)
            return fl_gltf_fail(d_, FEMLOD_EPARSE, ptr, "mode %d is not a glTF primitive mode",
                                p.mode);
        auto it = p.attributes.find("POSITION");
        if (it == p.attributes.end())
            return fl_gltf_fail(d_, FEMLOD_EPARSE, ptr, "primitive has no POSITION attribute");
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
        return fl_gltf_fail(
            d_, FEMLOD_EUNSUPPORTED, ptr,
            "compressed with KHR_draco_mesh_compression, which femlod does not decode");
    }

    /* The accessor (in range) has data of its own. */
    bool backed(int ai) const {
        const tinygltf::Accessor &a = m_.accessors[(size_t)ai];
        return a.bufferView >= 0 || a.sparse.isSparse;
    }

    femlod_status check_accessor_ref(int ai, const std::string &user) const {
        if (ai < 0 || (size_t)ai >= m_.accessors.size())
            return fl_gltf_fail(d_, FEMLOD_EPARSE, user, "accessor %d out of range (%zu accessors)",
                                ai, m_.accessors.size());
        const tinygltf::Accessor &a = m_.accessors[(size_t)ai];
        if (a.bufferView < -1 ||
            (a.bufferView >= 0 && (size_t)a.bufferView >= m_.bufferViews.size()))
            return fl_gltf_fail(d_, FEMLOD_EPARSE, at("accessors", (size_t)ai),
                                "bufferView %d out of range (%zu bufferViews)", a.bufferView,
                                m_.bufferViews.size());
        return FEMLOD_OK;
    }

    /* bufferView vi: in range, uncompressed, inside its buffer. */
    femlod_status view(int vi, const std::string &user, const unsigned char **base,
                       size_t *length) const {
        if (vi < 0 || (size_t)vi >= m_.bufferViews.size())
            return fl_gltf_fail(d_, FEMLOD_EPARSE, user,
                                "bufferView %d out of range (%zu bufferViews)", vi,
                                m_.bufferViews.size());
        const tinygltf::BufferView &v = m_.bufferViews[(size_t)vi];
        std::string ptr = at("bufferViews", (size_t)vi);
        for (const char *ext : {"EXT_meshopt_compression", "KHR_meshopt_compression"})
            if (has_extension(v.extensions, ext) && required(ext))
                return fl_gltf_fail(d_, FEMLOD_EUNSUPPORTED, ptr,
                                    "compressed with %s, which femlod does not decode", ext);
        if (v.buffer < 0 || (size_t)v.buffer >= m_.buffers.size())
            return fl_gltf_fail(d_, FEMLOD_EPARSE, ptr, "buffer %d out of range (%zu buffers)",
                                v.buffer, m_.buffers.size());
        size_t have = m_.buffers[(size_t)v.buffer].data.size(), end;
        if (__builtin_add_overflow(v.byteOffset, v.byteLength, &end) || end > have)
            return fl_gltf_fail(
                d_, FEMLOD_EPARSE, ptr,
                "bufferView runs past the end of buffer %d (needs %s bytes, has %zu)", v.buffer,
                end_text(v.byteOffset, v.byteLength).c_str(), have);
        if (v.byteLength == 0)
            return fl_gltf_fail(d_, FEMLOD_EPARSE, ptr, "byteLength is 0 (must be at least 1)");
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
        if (count == 0)
            return fl_gltf_fail(d_, FEMLOD_EPARSE, ptr, "count is 0 (must be at least 1)");
        e->count = count;
        e->elem = elem;
        e->ctype = a.componentType;
        if (a.bufferView < 0) {
            if (!a.sparse.isSparse)
                return fl_gltf_fail(
                    d_, FEMLOD_EUNSUPPORTED, user,
                    "accessor %d has neither a bufferView nor sparse values (all zeros)", ai);
            if (__builtin_mul_overflow(count, elem, &total) || total > kMaxUnbackedBytes)
                return fl_gltf_fail(
                    d_, FEMLOD_ELIMIT, ptr,
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
                return fl_gltf_fail(
                    d_, FEMLOD_EPARSE, ptr,
                    "elements of %zu bytes do not fit the byteStride %zu of bufferView %d", elem,
                    stride, a.bufferView);
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
                return fl_gltf_fail(
                    d_, FEMLOD_EPARSE, ptr,
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
            return fl_gltf_fail(d_, FEMLOD_EPARSE, ptr, "count %d out of range (1 to %zu)", n,
                                e->count);
        int ict = a.sparse.indices.componentType;
        if (!is_index_type(ict))
            return fl_gltf_fail(
                d_, FEMLOD_EPARSE, ptr + "/indices",
                "componentType %d is not UNSIGNED_BYTE, UNSIGNED_SHORT or UNSIGNED_INT", ict);
        const unsigned char *ibase, *vbase;
        size_t ilen, vlen, isize = component_size(ict), ineed, vneed;
        femlod_status st = view(a.sparse.indices.bufferView, ptr + "/indices", &ibase, &ilen);
        if (st != FEMLOD_OK) return st;
        st = view(a.sparse.values.bufferView, ptr + "/values", &vbase, &vlen);
        if (st != FEMLOD_OK) return st;
        int ioff = a.sparse.indices.byteOffset, voff = a.sparse.values.byteOffset;
        if (ioff < 0 || __builtin_mul_overflow((size_t)n, isize, &ineed) ||
            __builtin_add_overflow(ineed, (size_t)ioff, &ineed) || ineed > ilen)
            return fl_gltf_fail(d_, FEMLOD_EPARSE, ptr + "/indices",
                                "%d indices run past the end of bufferView %d (%zu bytes)", n,
                                a.sparse.indices.bufferView, ilen);
        if (voff < 0 || __builtin_mul_overflow((size_t)n, e->elem, &vneed) ||
            __builtin_add_overflow(vneed, (size_t)voff, &vneed) || vneed > vlen)
            return fl_gltf_fail(d_, FEMLOD_EPARSE, ptr + "/values",
                                "%d values run past the end of bufferView %d (%zu bytes)", n,
                                a.sparse.values.bufferView, vlen);
        ibase += ioff;
        vbase += voff;
        uint32_t prev = 0;
        for (size_t k = 0; k < (size_t)n; k++) {
            uint32_t i = get_index(ibase + k * isize, ict);
            if (i >= e->count)
                return fl_gltf_fail(d_, FEMLOD_EPARSE, ptr + "/indices",
                                    "index %u (entry %zu) out of range (%zu elements)", i, k,
                                    e->count);
            if (k > 0 && i <= prev)
                return fl_gltf_fail(d_, FEMLOD_EPARSE, ptr + "/indices",
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
            return fl_gltf_fail(d_, quantized ? FEMLOD_EUNSUPPORTED : FEMLOD_EPARSE, ptr,
                                "POSITION is %s %s (FLOAT VEC3 expected%s)",
                                component_name(a.componentType), type_name(a.type),
                                quantized ? "; KHR_mesh_quantization is not supported" : "");
        }
        Elements e;
        if ((st = elements(ai, user, 3, &e)) != FEMLOD_OK) return st;
        if (e.count > UINT32_MAX)
            return fl_gltf_fail(d_, FEMLOD_ELIMIT, ptr, "%zu vertices (limit %u)", e.count,
                                (unsigned)UINT32_MAX);
        out->resize(3 * e.count);
        for (size_t i = 0; i < 3 * e.count; i++) {
            uint32_t u = get_u32le(&e.bytes[4 * i]);
            float f;
            memcpy(&f, &u, sizeof f);
            if (!std::isfinite(f))
                return fl_gltf_fail(d_, FEMLOD_EPARSE, ptr,
                                    "element %zu: coordinate is not finite (%s)", i / 3,
                                    std::isnan(f) ? "nan" : "inf");
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
            return fl_gltf_fail(
                d_, FEMLOD_EPARSE, ptr,
                "indices are %s %s (UNSIGNED_BYTE, UNSIGNED_SHORT or UNSIGNED_INT SCALAR "
                "expected)",
                component_name(a.componentType), type_name(a.type));
        Elements e;
        if ((st = elements(ai, user, 1, &e)) != FEMLOD_OK) return st;
        out->resize(e.count);
        for (size_t i = 0; i < e.count; i++) {
            uint32_t v = get_index(&e.bytes[i * e.elem], e.ctype);
            if (v >= nverts)
                return fl_gltf_fail(
                    d_, FEMLOD_EPARSE, ptr,
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
                return fl_gltf_fail(d_, FEMLOD_EPARSE, ptr,
                                    "%zu %s do not make whole triangles (TRIANGLES takes 3 each)",
                                    n, p.indices != -1 ? "indices" : "vertices");
            tri.swap(list);
            return FEMLOD_OK;
        }
        if (n < 3)
            return fl_gltf_fail(d_, FEMLOD_EPARSE, ptr, "%s of %zu %s makes no triangle (3 needed)",
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

    const fl_gltf_diag &d_;
    const tinygltf::Model &m_;
    std::vector<std::vector<Prim>> cache_;
    std::vector<char> cached_;
};

/* Node n's own transform (matrix, or translation * rotation * scale). */
femlod_status local_transform(const fl_gltf_diag &d, const tinygltf::Node &node, size_t n,
                              Mat *out) {
    std::string ptr = at("nodes", n);
    if (!node.matrix.empty()) {
        if (node.matrix.size() != 16)
            return fl_gltf_fail(d, FEMLOD_EPARSE, ptr + "/matrix", "%zu numbers (16 expected)",
                                node.matrix.size());
        if (!all_finite(node.matrix))
            return fl_gltf_fail(d, FEMLOD_EPARSE, ptr + "/matrix", "a number is not finite");
        for (int i = 0; i < 16; i++) out->m[i] = node.matrix[(size_t)i];
        if (out->m[3] != 0.0 || out->m[7] != 0.0 || out->m[11] != 0.0 || out->m[15] != 1.0)
            return fl_gltf_fail(d, FEMLOD_EPARSE, ptr + "/matrix",
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
            return fl_gltf_fail(d, FEMLOD_EPARSE, ptr + p.key, "%zu numbers (%zu expected)",
                                p.v.size(), p.n);
        if (!all_finite(p.v))
            return fl_gltf_fail(d, FEMLOD_EPARSE, ptr + p.key, "a number is not finite");
    }
    double *m = out->m;
    if (!node.rotation.empty()) {
        double x = node.rotation[0], y = node.rotation[1], z = node.rotation[2],
               w = node.rotation[3];
        double nn = x * x + y * y + z * z + w * w;
        if (!(nn > 0.0) || !std::isfinite(nn))
            return fl_gltf_fail(d, FEMLOD_EPARSE, ptr + "/rotation",
                                "not a usable quaternion (length 0)");
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
femlod_status emit(const fl_gltf_diag &d, Reader &rd, size_t mi, const Mat &world,
                   const std::string &who, std::vector<double> *corners) {
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
                        return fl_gltf_fail(d, FEMLOD_EPARSE, who,
                                            "a vertex of mesh %zu is not finite once transformed",
                                            mi);
                    placed[v + (size_t)r] = t;
                }
            }
            pos = &placed;
        }
        size_t nt = p.tri.size() / 3, have = corners->size() / 9;
        if (nt > (size_t)UINT32_MAX - have)
            return fl_gltf_fail(d, FEMLOD_ELIMIT, "", "more than %u triangles",
                                (unsigned)UINT32_MAX);
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

femlod_status extract(const fl_gltf_diag &d, const tinygltf::Model &m,
                      std::vector<double> *corners) {
    for (size_t i = 0; i < m.extensionsRequired.size(); i++)
        if (!harmless_extension(m.extensionsRequired[i]))
            return fl_gltf_fail(d, FEMLOD_EUNSUPPORTED, at("extensionsRequired", i),
                                "required extension %s is not supported",
                                fl_gltf_quote(m.extensionsRequired[i]).c_str());
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
        return fl_gltf_fail(d, FEMLOD_EPARSE, "/scene", "scene %d out of range (%zu scenes)",
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
            return fl_gltf_fail(d, FEMLOD_EPARSE, where, "node %d out of range (%zu nodes)",
                                it.node, nn);
        size_t n = (size_t)it.node;
        if (seen[n])
            return fl_gltf_fail(
                d, FEMLOD_EPARSE, where,
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
                return fl_gltf_fail(d, FEMLOD_EPARSE, at("nodes", n),
                                    "the transform from the scene root is not finite");
        if (node.mesh != -1) {
            if (node.mesh < 0 || (size_t)node.mesh >= m.meshes.size())
                return fl_gltf_fail(d, FEMLOD_EPARSE, at("nodes", n) + "/mesh",
                                    "mesh %d out of range (%zu meshes)", node.mesh,
                                    m.meshes.size());
            if (has_extension(node.extensions, "EXT_mesh_gpu_instancing"))
                return fl_gltf_fail(d, FEMLOD_EUNSUPPORTED, at("nodes", n),
                                    "EXT_mesh_gpu_instancing is not supported");
            st = emit(d, rd, (size_t)node.mesh, world[n], at("nodes", n), corners);
            if (st != FEMLOD_OK) return st;
        }
        for (size_t k = node.children.size(); k-- > 0;)
            stack.push_back({node.children[k], it.node, k});
    }
    return FEMLOD_OK;
}

/* tinygltf refused the file: say what is wrong as precisely as we can. The
 * model holds what was parsed before the failure. */
femlod_status diagnose(const fl_gltf_diag &d, const tinygltf::Model &m, const fl_gltf_fs &fs,
                       const std::string &e) {
    for (size_t i = 0; i < m.extensionsRequired.size(); i++) {
        const std::string &x = m.extensionsRequired[i];
        if (x == "EXT_meshopt_compression" || x == "KHR_meshopt_compression")
            return fl_gltf_fail(d, FEMLOD_EUNSUPPORTED, at("extensionsRequired", i),
                                "%s (compressed buffer views) is not supported", x.c_str());
    }
    size_t b = m.buffers.size(); /* the buffer being loaded, if it was the buffers */
    if (fs.status != FEMLOD_OK)
        return fl_gltf_fail(d, fs.status, at("buffers", b), "%s", fs.reason.c_str());
    static const char decode[] = "Failed to decode 'uri' : ";
    size_t k = e.find(decode);
    if (k != std::string::npos) {
        size_t s = k + sizeof decode - 1, end = e.find(" in Buffer", s);
        std::string uri = e.substr(s, end == std::string::npos ? std::string::npos : end - s);
        std::string why = fl_gltf_check_data_uri(uri);
        if (why.empty()) why = "data URI does not decode to the buffer's byteLength";
        return fl_gltf_fail(d, FEMLOD_EPARSE, at("buffers", b), "%s", why.c_str());
    }
    size_t want = 0, got = 0;
    k = e.find("requestedBytes ");
    if (k != std::string::npos &&
        sscanf(e.c_str() + k, "requestedBytes %zu, but got %zu", &want, &got) == 2)
        return fl_gltf_fail(d, FEMLOD_EPARSE, at("buffers", b),
                            "buffer file has %zu bytes, but byteLength is %zu", got, want);
    if (e.find("File is empty") != std::string::npos)
        return fl_gltf_fail(d, FEMLOD_EPARSE, at("buffers", b), "buffer file is empty");
    if (e.compare(0, 16, "[json.exception.") == 0) {
        size_t close = e.find("] ");
        std::string text = close == std::string::npos ? e : e.substr(close + 2);
        return fl_gltf_fail(d, FEMLOD_EPARSE, "", "invalid JSON: %s", text.c_str());
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
    return fl_gltf_fail(d, FEMLOD_EPARSE, "", "%s", line.c_str());
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

/* Embedded images are kept as bytes (tinygltf 2.7 fails the whole load on an
 * image when no loader is installed); femlod reads geometry only. */
bool keep_image(tinygltf::Image *, const int, std::string *, std::string *, int, int,
                const unsigned char *, int, void *) {
    return true;
}

/* The folder of path, as tinygltf will join it with URIs. */
std::string folder_of(const char *path) {
    const char *slash = strrchr(path, '/');
    if (!slash) return ".";
    if (slash == path) return "/";
    return std::string(path, (size_t)(slash - path));
}

femlod_status read_gltf(femlod_mesh **out, const char *data, size_t size, const fl_gltf_diag &d,
                        const char *file, femlod_format format) {
    const unsigned char *u = reinterpret_cast<const unsigned char *>(data);
    if (size == 0) return fl_gltf_fail(d, FEMLOD_EPARSE, "", "empty file");
    if (size > UINT_MAX)
        return fl_gltf_fail(d, FEMLOD_ELIMIT, "",
                            "%zu bytes: glTF files of 4 GiB or more are not read", size);
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

    fl_gltf_fs fs;
    std::string base;
    if (file) {
        base = folder_of(file);
        fs.base = base.c_str();
        fs.prefix = base.back() == '/' ? base : base + "/";
    }
    tinygltf::TinyGLTF loader;
    loader.SetImageLoader(keep_image, nullptr);
    loader.SetFsCallbacks(fl_gltf_confine_files(&fs));
    tinygltf::Model model;
    std::string e, w;
    bool ok = glb ? loader.LoadBinaryFromMemory(&model, &e, &w, u, (unsigned)size, base)
                  : loader.LoadASCIIFromString(&model, &e, &w, data, (unsigned)size, base);
    if (!ok) return diagnose(d, model, fs, e);
    for (size_t i = 0; i < model.buffers.size(); i++)
        if (tinygltf::IsDataURI(model.buffers[i].uri)) {
            std::string why = fl_gltf_check_data_uri(model.buffers[i].uri);
            if (!why.empty())
                return fl_gltf_fail(d, FEMLOD_EPARSE, at("buffers", i), "%s", why.c_str());
        }

    std::vector<double> corners;
    femlod_status st = extract(d, model, &corners);
    if (st != FEMLOD_OK) return st;
    femlod_error weld;
    st = fl_mesh_from_soup(out, corners.data(), corners.size() / 9, &weld);
    if (st != FEMLOD_OK) return fl_gltf_fail(d, st, "", "%s", weld.message);
    return FEMLOD_OK;
}

/* }====== */

} // namespace

/* {====== the C face: nothing thrown gets past it */

extern "C" femlod_status fl_read_gltf(femlod_mesh **out, const char *data, size_t size,
                                      const char *name, const char *file, femlod_format format,
                                      femlod_error *err) {
    fl_gltf_diag d = {name, err};
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

/* }====== */
