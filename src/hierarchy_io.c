/*
 * hierarchy_io.c - the .flh file: a vertex hierarchy and its front, saved so
 * that one simplification serves any number of LOD meshes later.
 *
 * The file stores what the hierarchy was built from (the input vertices
 * and faces, and the collapse log) rather than the derived arrays, and
 * loading rebuilds through femlod_hierarchy_create: every consistency check
 * of a fresh build then also guards a file. The layout (all integers and
 * doubles little-endian) is in docs/formats.md:
 *
 *   magic "\x89FLH\r\n\x1a\n" | u32 version = 1 | u32 flags (bit 0: result)
 *   u64 nv, nf, nc, nvstars, nlogfaces, nfront
 *   f64 leaf positions [3 nv] | u32 input faces [3 nf]
 *   per collapse: u32 i, j | f64 position [3] | f64 e_size | u32 vstar count
 *                 | u32 face count ; then u32 vstars [nvstars] ; u8 face refs [3 nlogfaces]
 *   u32 front nodes [nfront]
 *   result block (when flag 0): u32 field count, then the fields of
 *                 femlod_simplify_result as u64 / f64 (seconds stored as 0)
 *   u32 CRC-32 (zlib) of every byte before it
 */
#include "hierarchy.h"
#include "simplify_log.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <zlib.h>

static const unsigned char MAGIC[8] = {0x89, 'F', 'L', 'H', '\r', '\n', 0x1a, '\n'};
#define FLH_VERSION 1u
#define FLH_HAS_RESULT 1u
#define RESULT_FIELDS_V1 (17u + FEMLOD_REJECT_COUNT) /* files written before the log's extent was stored */
#define RESULT_FIELDS_V2 (20u + FEMLOD_REJECT_COUNT) /* files written before the output's census was stored */
#define RESULT_FIELDS (RESULT_FIELDS_V2 + 2u * FEMLOD_IMPROVE_REASON_COUNT + FEMLOD_REJECT_COUNT + 11u)

/* {====== writing: a stream that keeps the CRC */

typedef struct wstream {
    FILE *fp;
    uLong crc;
    unsigned char buf[1 << 16];
    size_t n;
} wstream;

static void w_flush(wstream *w) {
    if (w->n) {
        w->crc = crc32(w->crc, w->buf, (uInt)w->n);
        /* A short write sets the stream's error flag, which fl_out_commit checks. */
        (void)fwrite(w->buf, 1, w->n, w->fp);
        w->n = 0;
    }
}

static void w_bytes(wstream *w, const void *p, size_t n) {
    const unsigned char *b = p;
    while (n) {
        size_t k = sizeof w->buf - w->n;
        if (k > n) k = n;
        memcpy(w->buf + w->n, b, k);
        w->n += k;
        b += k;
        n -= k;
        if (w->n == sizeof w->buf) w_flush(w);
    }
}

static void w_u32(wstream *w, uint32_t x) {
    unsigned char b[4] = {(unsigned char)x, (unsigned char)(x >> 8), (unsigned char)(x >> 16),
                          (unsigned char)(x >> 24)};
    w_bytes(w, b, 4);
}

static void w_u64(wstream *w, uint64_t x) {
    w_u32(w, (uint32_t)x);
    w_u32(w, (uint32_t)(x >> 32));
}

static void w_f64(wstream *w, double x) {
    uint64_t u;
    memcpy(&u, &x, sizeof u);
    w_u64(w, u);
}

/* }====== */

/* Local ref of node x in collapse c (0: i, 1: j, 2+s: vstars[s]). */
static int local_ref(const femlod_hierarchy *h, size_t c, uint32_t x) {
    if (x == h->child[2 * c]) return 0;
    if (x == h->child[2 * c + 1]) return 1;
    uint32_t lo = h->vstar_start[c], hi = h->vstar_start[c + 1];
    while (lo < hi) {
        uint32_t mid = lo + (hi - lo) / 2;
        if (h->vstars[mid] < x)
            lo = mid + 1;
        else
            hi = mid;
    }
    if (lo < h->vstar_start[c + 1] && h->vstars[lo] == x && lo - h->vstar_start[c] < 254)
        return 2 + (int)(lo - h->vstar_start[c]);
    return -1;
}

femlod_status femlod_hierarchy_save(const femlod_hierarchy *h, const char *path,
                                    const femlod_simplify_result *r, femlod_error *err) {
    /* vstars are stored sorted (the log's order); local refs need that */
    for (size_t c = 0; c < h->nc; c++)
        for (uint32_t s = h->vstar_start[c] + 1; s < h->vstar_start[c + 1]; s++)
            if (h->vstars[s - 1] >= h->vstars[s])
                return fl_error(err, FEMLOD_EINPUT, "%s: vstars of collapse %zu are not sorted",
                                path, c);
    wstream *w = malloc(sizeof *w);
    if (!w) return fl_error(err, FEMLOD_ENOMEM, "%s: out of memory", path);
    fl_out out;
    femlod_status st = fl_out_open(&out, path, err);
    if (st != FEMLOD_OK) {
        free(w);
        return st;
    }
    w->fp = out.fp;
    w->crc = crc32(0L, Z_NULL, 0);
    w->n = 0;
    size_t nfront = h->front_n, nvstars = h->vstar_start[h->nc], nlog = h->removed_start[h->nc];
    w_bytes(w, MAGIC, sizeof MAGIC);
    w_u32(w, FLH_VERSION);
    w_u32(w, r ? FLH_HAS_RESULT : 0u);
    w_u64(w, h->nv);
    w_u64(w, h->nf_in);
    w_u64(w, h->nc);
    w_u64(w, nvstars);
    w_u64(w, nlog);
    w_u64(w, nfront);
    for (size_t k = 0; k < 3 * h->nv; k++) w_f64(w, h->pos[k]);
    for (size_t k = 0; k < 3 * h->nf_in; k++) w_u32(w, h->face_v[k]);
    for (size_t c = 0; c < h->nc; c++) {
        size_t k = h->nv + c;
        w_u32(w, h->child[2 * c]);
        w_u32(w, h->child[2 * c + 1]);
        for (int d = 0; d < 3; d++) w_f64(w, h->pos[3 * k + (size_t)d]);
        w_f64(w, h->e_size[k]);
        w_u32(w, h->vstar_start[c + 1] - h->vstar_start[c]);
        w_u32(w, h->removed_start[c + 1] - h->removed_start[c]);
    }
    for (size_t s = 0; s < nvstars; s++) w_u32(w, h->vstars[s]);
    for (size_t c = 0; c < h->nc && st == FEMLOD_OK; c++)
        for (uint32_t q = h->removed_start[c]; q < h->removed_start[c + 1]; q++) {
            unsigned char ref[3];
            for (int d = 0; d < 3; d++) {
                int v = local_ref(h, c, h->face_v[3 * (size_t)h->removed[q] + (size_t)d]);
                if (v < 0) {
                    st = fl_error(err, FEMLOD_EINPUT, "%s: collapse %zu: a face corner is not "
                                  "in its neighbourhood", path, c);
                    break;
                }
                ref[d] = (unsigned char)v;
            }
            w_bytes(w, ref, 3);
        }
    /* The front in increasing node order: the file does not depend on the
     * order of the operations that led to it. */
    for (size_t x = 0; x < h->nn; x++)
        if (h->state[x] == FRONT) w_u32(w, (uint32_t)x);
    if (r) {
        w_u32(w, RESULT_FIELDS);
        w_u64(w, r->triangles);
        w_u64(w, r->vertices);
        w_u64(w, (uint64_t)r->stop_reason);
        w_u64(w, r->collapses);
        w_u64(w, r->prephase_collapses);
        for (int k = 0; k < FEMLOD_REJECT_COUNT; k++) w_u64(w, r->rejected[k]);
        w_u64(w, r->violating_input);
        w_u64(w, r->dropped_degenerate);
        w_u64(w, r->target);
        w_u64(w, (uint64_t)(int64_t)r->max_valence);
        /* the wall time is not stored: the same hierarchy gives the same bytes */
        w_f64(w, 0.0);
        w_f64(w, r->tolerance);
        w_f64(w, r->max_deviation);
        w_f64(w, r->min_stretch);
        w_f64(w, r->max_size);
        w_f64(w, r->feature_angle);
        w_f64(w, r->feature_weight);
        w_f64(w, r->max_normal_change);
        w_u64(w, r->hierarchy_triangles);
        w_u64(w, (uint64_t)r->hierarchy_stop);
        w_u64(w, (uint64_t)(int64_t)r->hierarchy_binding);
        /* the output's census and the stop's count */
        for (int k = 0; k < FEMLOD_IMPROVE_REASON_COUNT; k++) w_u64(w, r->violating_by[k]);
        w_u64(w, r->violating_valence);
        for (int k = 0; k < FEMLOD_IMPROVE_REASON_COUNT; k++) w_u64(w, r->violating_valence_by[k]);
        w_f64(w, r->corner_angle_min);
        w_f64(w, r->corner_angle_max);
        for (int k = 0; k < FEMLOD_REJECT_COUNT; k++) w_u64(w, r->stop_rejected[k]);
        w_u64(w, r->stop_taken);
        for (int k = 0; k < 3; k++) w_u64(w, r->stop_topology[k]);
        w_u64(w, (uint64_t)r->improved);
        w_u64(w, r->improve_operations);
        w_u64(w, r->improve_triangles);
        w_u64(w, r->polish_operations);
    }
    w_flush(w);
    uLong crc = w->crc;
    unsigned char tail[4] = {(unsigned char)crc, (unsigned char)(crc >> 8),
                             (unsigned char)(crc >> 16), (unsigned char)(crc >> 24)};
    (void)fwrite(tail, 1, 4, out.fp);
    free(w);
    if (st != FEMLOD_OK) {
        fl_out_abort(&out);
        return st;
    }
    return fl_out_commit(&out, err);
}

/* {====== reading: bounds-checked cursor */

typedef struct rstream {
    const unsigned char *p;
    size_t size, at;
    const char *name;
    femlod_error *err;
    femlod_status st;
} rstream;

static int need(rstream *r, size_t n, const char *what) {
    if (r->st != FEMLOD_OK) return 0;
    if (n > r->size - r->at) {
        r->st = fl_error(r->err, FEMLOD_EPARSE, "%s: byte %zu: file ends inside %s", r->name,
                         r->at, what);
        return 0;
    }
    return 1;
}

static uint32_t r_u32(rstream *r) {
    const unsigned char *b = r->p + r->at;
    r->at += 4;
    return (uint32_t)b[0] | (uint32_t)b[1] << 8 | (uint32_t)b[2] << 16 | (uint32_t)b[3] << 24;
}

static uint64_t r_u64(rstream *r) {
    uint64_t lo = r_u32(r);
    return lo | (uint64_t)r_u32(r) << 32;
}

static double r_f64(rstream *r) {
    uint64_t u = r_u64(r);
    double x;
    memcpy(&x, &u, sizeof x);
    return x;
}

/* A count whose items (each `size` bytes) must fit in what is left. */
static size_t r_count(rstream *r, size_t size, const char *what) {
    if (!need(r, 8, what)) return 0;
    size_t at = r->at;
    uint64_t n = r_u64(r);
    if (n > UINT32_MAX || n * size > r->size - r->at) {
        r->st = fl_error(r->err, FEMLOD_EPARSE, "%s: byte %zu: %s count %llu does not fit the file",
                         r->name, at, what, (unsigned long long)n);
        return 0;
    }
    return (size_t)n;
}

/* }====== */

femlod_status femlod_hierarchy_load(femlod_hierarchy **out, const char *path,
                                    femlod_simplify_result *result, femlod_error *err) {
    char *data = NULL;
    size_t size = 0;
    femlod_status st = fl_file_read_all(path, &data, &size, err);
    if (st != FEMLOD_OK) return st;
    st = femlod_hierarchy_load_memory(out, data, size, path, result, err);
    free(data);
    return st;
}

femlod_status femlod_hierarchy_load_memory(femlod_hierarchy **out, const void *bytes, size_t size,
                                           const char *name, femlod_simplify_result *result,
                                           femlod_error *err) {
    const char *path = name ? name : "<memory>";
    const unsigned char *data = (const unsigned char *)bytes;
    femlod_status st = FEMLOD_OK;
    rstream r = {data, size, 0, path, err, FEMLOD_OK};
    femlod_mesh *mesh = NULL;
    femlod_collapse_log *log = NULL;
    femlod_hierarchy *h = NULL;
    uint32_t *front = NULL, *vstars = NULL, *meta = NULL;
    double *cpos = NULL;
    femlod_simplify_result res;
    memset(&res, 0, sizeof res);

    if (size < sizeof MAGIC + 4 || memcmp(data, MAGIC, sizeof MAGIC) != 0) {
        st = fl_error(err, FEMLOD_EPARSE, "%s: byte 0: not a femlod hierarchy file", path);
        goto done;
    }
    {
        const unsigned char *t = r.p + size - 4;
        uLong want = (uLong)t[0] | (uLong)t[1] << 8 | (uLong)t[2] << 16 | (uLong)t[3] << 24;
        if (crc32(crc32(0L, Z_NULL, 0), r.p, (uInt)(size - 4)) != want) {
            st = fl_error(err, FEMLOD_EPARSE, "%s: checksum mismatch: the file is damaged", path);
            goto done;
        }
    }
    r.size = size - 4; /* the CRC is not data */
    r.at = sizeof MAGIC;
    if (!need(&r, 8, "the header")) goto parse_error;
    uint32_t version = r_u32(&r), flags = r_u32(&r);
    if (version != FLH_VERSION) {
        st = fl_error(err, FEMLOD_EUNSUPPORTED, "%s: byte 8: version %u (this femlod reads %u)",
                      path, version, FLH_VERSION);
        goto done;
    }
    size_t nv = r_count(&r, 24, "vertex");
    size_t nf = r_count(&r, 12, "face");
    size_t nc = r_count(&r, 48, "collapse");
    size_t nvs = r_count(&r, 4, "vstar");
    size_t nlog = r_count(&r, 3, "collapse face");
    size_t nfront = r_count(&r, 4, "front node");
    if (r.st != FEMLOD_OK) goto parse_error;
    if (nv + nc > UINT32_MAX - 1) {
        st = fl_error(err, FEMLOD_EPARSE, "%s: too many nodes", path);
        goto done;
    }
    mesh = fl_mesh_alloc(nv, nf);
    if (!mesh) goto nomem;
    if (!need(&r, 24 * nv + 12 * nf, "the input mesh")) goto parse_error;
    for (size_t k = 0; k < 3 * nv; k++) mesh->pos[k] = r_f64(&r);
    for (size_t k = 0; k < 3 * nf; k++) {
        mesh->tri[k] = r_u32(&r);
        if (mesh->tri[k] >= nv) {
            st = fl_error(err, FEMLOD_EPARSE, "%s: byte %zu: face vertex %u out of range", path,
                          r.at - 4, mesh->tri[k]);
            goto done;
        }
    }
    for (size_t k = 0; k < 3 * nv; k++)
        if (!isfinite(mesh->pos[k])) {
            st = fl_error(err, FEMLOD_EPARSE, "%s: vertex %zu has a non-finite coordinate", path,
                          k / 3);
            goto done;
        }
    meta = fl_alloc(nc, 4 * sizeof(uint32_t));
    cpos = fl_alloc(nc, 4 * sizeof(double));
    if (!meta || !cpos) goto nomem;
    if (!need(&r, 48 * nc, "the collapses")) goto parse_error;
    size_t sum_vs = 0, sum_faces = 0;
    for (size_t c = 0; c < nc; c++) {
        for (int d = 0; d < 2; d++) meta[4 * c + (size_t)d] = r_u32(&r);
        for (int d = 0; d < 4; d++) cpos[4 * c + (size_t)d] = r_f64(&r);
        meta[4 * c + 2] = r_u32(&r);
        meta[4 * c + 3] = r_u32(&r);
        sum_vs += meta[4 * c + 2];
        sum_faces += meta[4 * c + 3];
        if (meta[4 * c + 2] > 253) {
            st = fl_error(err, FEMLOD_EPARSE, "%s: collapse %zu has %u vstars (at most 253)", path,
                          c, meta[4 * c + 2]);
            goto done;
        }
    }
    if (sum_vs != nvs || sum_faces != nlog) {
        st = fl_error(err, FEMLOD_EPARSE, "%s: collapse counts do not add up", path);
        goto done;
    }
    vstars = fl_alloc(nvs, sizeof(uint32_t));
    if (!vstars) goto nomem;
    if (!need(&r, 4 * nvs + 3 * nlog, "the vstars and faces")) goto parse_error;
    for (size_t s = 0; s < nvs; s++) vstars[s] = r_u32(&r);
    const unsigned char *refs = r.p + r.at;
    r.at += 3 * nlog;
    log = fl_log_new(nv, nc);
    if (!log) goto nomem;
    {
        size_t vs = 0, fs = 0;
        for (size_t c = 0; c < nc; c++) {
            uint32_t nvc = meta[4 * c + 2], nfc = meta[4 * c + 3];
            for (size_t q = 0; q < 3 * (size_t)nfc; q++)
                if (refs[3 * fs + q] >= 2 + nvc) {
                    st = fl_error(err, FEMLOD_EPARSE, "%s: collapse %zu: face ref %u out of range",
                                  path, c, refs[3 * fs + q]);
                    goto done;
                }
            if (!fl_log_add(log, meta[4 * c], meta[4 * c + 1], cpos + 4 * c, cpos[4 * c + 3],
                            vstars + vs, nvc, refs + 3 * fs, nfc))
                goto nomem;
            vs += nvc;
            fs += nfc;
        }
    }
    if (!need(&r, 4 * nfront, "the front")) goto parse_error;
    front = fl_alloc(nfront, sizeof(uint32_t));
    if (!front) goto nomem;
    for (size_t k = 0; k < nfront; k++) front[k] = r_u32(&r);
    if (flags & FLH_HAS_RESULT) {
        if (!need(&r, 4, "the result")) goto parse_error;
        uint32_t fields = r_u32(&r);
        if ((fields != RESULT_FIELDS && fields != RESULT_FIELDS_V2 && fields != RESULT_FIELDS_V1) ||
            !need(&r, 8 * (size_t)fields, "the result")) {
            if (r.st == FEMLOD_OK)
                st = fl_error(err, FEMLOD_EPARSE, "%s: result block has %u fields, expected %u",
                              path, fields, RESULT_FIELDS);
            else
                st = r.st;
            goto done;
        }
        res.triangles = (size_t)r_u64(&r);
        res.vertices = (size_t)r_u64(&r);
        uint64_t reason = r_u64(&r);
        res.stop_reason = reason == 1 ? FEMLOD_STOP_NO_VALID_EDGE
                          : reason == 2 ? FEMLOD_STOP_CANCELLED
                                        : FEMLOD_STOP_TARGET;
        res.collapses = (size_t)r_u64(&r);
        res.prephase_collapses = (size_t)r_u64(&r);
        for (int k = 0; k < FEMLOD_REJECT_COUNT; k++) res.rejected[k] = (size_t)r_u64(&r);
        res.violating_input = (size_t)r_u64(&r);
        res.dropped_degenerate = (size_t)r_u64(&r);
        res.target = (size_t)r_u64(&r);
        res.max_valence = (int)(int64_t)r_u64(&r);
        res.seconds = r_f64(&r);
        res.tolerance = r_f64(&r);
        res.max_deviation = r_f64(&r);
        res.min_stretch = r_f64(&r);
        res.max_size = r_f64(&r);
        res.feature_angle = r_f64(&r);
        res.feature_weight = r_f64(&r);
        res.max_normal_change = r_f64(&r);
        res.hierarchy_triangles = res.triangles;
        res.hierarchy_stop = res.stop_reason;
        res.hierarchy_binding = FEMLOD_REJECT_COUNT;
        if (fields != RESULT_FIELDS_V1) {
            res.hierarchy_triangles = (size_t)r_u64(&r);
            uint64_t hs = r_u64(&r);
            res.hierarchy_stop = hs == 1 ? FEMLOD_STOP_NO_VALID_EDGE
                                 : hs == 2 ? FEMLOD_STOP_CANCELLED
                                           : FEMLOD_STOP_TARGET;
            int64_t hb = (int64_t)r_u64(&r);
            res.hierarchy_binding = hb >= 0 && hb < FEMLOD_REJECT_COUNT ? (int)hb : FEMLOD_REJECT_COUNT;
        }
        if (fields == RESULT_FIELDS) {
            for (int k = 0; k < FEMLOD_IMPROVE_REASON_COUNT; k++) res.violating_by[k] = (size_t)r_u64(&r);
            res.violating_valence = (size_t)r_u64(&r);
            for (int k = 0; k < FEMLOD_IMPROVE_REASON_COUNT; k++) res.violating_valence_by[k] = (size_t)r_u64(&r);
            res.corner_angle_min = r_f64(&r);
            res.corner_angle_max = r_f64(&r);
            for (int k = 0; k < FEMLOD_REJECT_COUNT; k++) res.stop_rejected[k] = (size_t)r_u64(&r);
            res.stop_taken = (size_t)r_u64(&r);
            for (int k = 0; k < 3; k++) res.stop_topology[k] = (size_t)r_u64(&r);
            res.improved = r_u64(&r) != 0;
            res.improve_operations = (size_t)r_u64(&r);
            res.improve_triangles = (size_t)r_u64(&r);
            res.polish_operations = (size_t)r_u64(&r);
        }
    }
    if (r.at != r.size) {
        st = fl_error(err, FEMLOD_EPARSE, "%s: byte %zu: unexpected data after the hierarchy", path,
                      r.at);
        goto done;
    }
    {
        femlod_error e2;
        st = femlod_hierarchy_create_from_log(&h, mesh, &log, NULL, &e2);
        if (st == FEMLOD_ENOMEM) goto nomem;
        if (st != FEMLOD_OK) {
            st = fl_error(err, FEMLOD_EPARSE, "%s: %s", path, e2.message);
            goto done;
        }
        st = fl_hierarchy_set_front(h, front, nfront, &e2);
        if (st != FEMLOD_OK) {
            st = fl_error(err, FEMLOD_EPARSE, "%s: %s", path, e2.message);
            goto done;
        }
        if (flags & FLH_HAS_RESULT) h->binding = res.hierarchy_binding;
    }
    goto done;

parse_error:
    st = r.st;
    goto done;
nomem:
    st = fl_error(err, FEMLOD_ENOMEM, "%s: out of memory", path);
done:
    free(front);
    free(vstars);
    free(meta);
    free(cpos);
    femlod_mesh_free(mesh);
    femlod_collapse_log_free(log);
    if (st != FEMLOD_OK) {
        femlod_hierarchy_free(h);
        return st;
    }
    if (result) *result = res;
    *out = h;
    return FEMLOD_OK;
}
