/* io_gltf_write.cpp - owns writing glTF 2.0 through fl_write_gltf (core.h):
 * a mesh as one primitive in one little-endian buffer, .gltf (JSON, the
 * buffer as a data: URI) or .glb (binary), with optional area-weighted
 * normals, quality colour maps (viridis COLOR_0 and the raw value, flat per
 * triangle or shared per vertex), the quality report and the caller's
 * parameters in asset.extras (docs/formats.md, "glTF"). tinygltf and the
 * messages come from io_gltf_common.cpp; nothing here reads glTF.
 *
 * Specification: Khronos glTF 2.0 (registry.khronos.org/glTF/specs/2.0),
 * sections "Accessors", "Meshes", "GLB File Format".
 * fl_write_gltf catches everything and returns a femlod status.
 */
#include <algorithm>
#include <cerrno>
#include <cfloat>
#include <climits>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <new>
#include <sstream>
#include <string>
#include <vector>

#include "io_gltf.hpp"

namespace {

/* {====== colour maps */

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

/* }====== */

/* {====== the model */

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
                         const femlod_write_options *opt, const fl_gltf_diag &d) {
    /* The code is read as an integer: in C++ loading an enum with a value
     * outside its enumerators is undefined, and the caller is C. */
    int code = 0;
    static_assert(sizeof code == sizeof opt->color_by, "femlod_color_by is int-sized");
    if (opt) memcpy(&code, &opt->color_by, sizeof code);
    if (code < FEMLOD_COLOR_NONE || code > FEMLOD_COLOR_VALENCE)
        return fl_gltf_fail(d, FEMLOD_EINPUT, "", "invalid color_by code %d", code);
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
            return fl_gltf_fail(d, FEMLOD_EINPUT, "", "extras is not valid JSON: %s",
                                close == std::string::npos ? what.c_str()
                                                           : what.c_str() + close + 2);
        }
        if (!j.is_object())
            return fl_gltf_fail(d, FEMLOD_EINPUT, "", "extras is not a JSON object");
        tinygltf::Value params;
        if (!to_value(j, &params, 0))
            return fl_gltf_fail(d, FEMLOD_EINPUT, "", "extras is nested more than 64 levels deep");
        extras["params"] = params;
    }

    femlod_quality q;
    femlod_error qerr;
    femlod_status st = femlod_mesh_quality(mesh, &q, &qerr);
    if (st != FEMLOD_OK) return fl_gltf_fail(d, st, "", "%s", qerr.message);
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
            return fl_gltf_fail(
                d, FEMLOD_EINPUT, "",
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
            if (st != FEMLOD_OK) return fl_gltf_fail(d, st, "", "%s", verr.message);
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
            return fl_gltf_fail(d, FEMLOD_ELIMIT, "",
                                "%zu bytes of buffer data: more than tinygltf 2.7 writes (2 GiB)",
                                total);
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
        return fl_gltf_fail(d, FEMLOD_EIO, "",
                            "cannot write: tinygltf failed to serialise the model");
    const std::string out = ss.str();
    errno = 0;
    if (fwrite(out.data(), 1, out.size(), fp) != out.size()) {
        int e = errno ? errno : EIO;
        return fl_gltf_fail(d, FEMLOD_EIO, "", "cannot write: %s", strerror(e));
    }
    return FEMLOD_OK;
}

/* }====== */

} // namespace

/* {====== the C face: nothing thrown gets past it */

extern "C" femlod_status fl_write_gltf(const femlod_mesh *m, FILE *fp, int binary,
                                       const femlod_write_options *options, const char *path,
                                       femlod_error *err) {
    fl_gltf_diag d = {path, err};
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
