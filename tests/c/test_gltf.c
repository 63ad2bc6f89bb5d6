/* test_gltf.c - glTF in and out (src/io_gltf_*.cpp; docs/formats.md, "glTF").
 *
 * Facts checked:
 *   - 2CylinderEngine.glb (examples/data) loads with its node transforms
 *     applied: the counts of ../shared/data/README.md, and a bounding box
 *     that this file computes on its own from the GLB (a small JSON parser
 *     below, the node matrices, the float32 data of the BIN chunk);
 *   - every mode, index width, byteStride, sparse accessor, node transform
 *     (matrix, TRS, parent chain, mirror) and scene rule, on hand-made files
 *     whose triangles are written out here;
 *   - OBJ -> GLB / glTF -> OBJ keeps every position to float32 and every
 *     triangle (fandisk), in every writer mode;
 *   - what the writer puts in a file: generator, quality and caller extras,
 *     POSITION bounds, index width, COLOR_0 and the raw values;
 *   - one specific error per malformed file of tests/data/bad, confinement
 *     of external buffers (symbolic links made here), glTF from memory;
 *   - no truncation or byte flip of a valid file breaks the reader. */
#include "core.h"

#include "check.h"
#include "shapes.h"

#include <dirent.h>
#include <errno.h>
#include <float.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#ifndef FEMLOD_TEST_DATA
#error "FEMLOD_TEST_DATA must name tests/data"
#endif
#ifndef FEMLOD_SHARED_DATA
#error "FEMLOD_SHARED_DATA must name examples/data"
#endif

static char scratch[512]; /* this run's own folder under $FEMLOD_TMP */

static const char *path_in(char *buf, size_t size, const char *dir, const char *name) {
    if ((size_t)snprintf(buf, size, "%s/%s", dir, name) >= size) {
        fprintf(stderr, "test_gltf: path too long: %s/%s\n", dir, name);
        exit(1);
    }
    return buf;
}

static char *slurp(const char *path, size_t *size) {
    char *data = NULL;
    if (fl_file_read_all(path, &data, size, NULL) != FEMLOD_OK) {
        fprintf(stderr, "test_gltf: cannot read %s\n", path);
        exit(1);
    }
    return data;
}

static void spit(const char *path, const void *data, size_t size) {
    FILE *f = fopen(path, "wb");
    if (!f || fwrite(data, 1, size, f) != size || fclose(f) != 0) {
        fprintf(stderr, "test_gltf: cannot write %s\n", path);
        exit(1);
    }
}

static femlod_mesh *read_ok(const char *path) {
    femlod_error err = {0, ""};
    femlod_mesh *m = NULL;
    femlod_status s = femlod_mesh_read(&m, path, NULL, &err);
    CHECK(s == FEMLOD_OK && m);
    if (s != FEMLOD_OK) fprintf(stderr, "  reading %s: %s\n", path, err.message);
    return m;
}

static int write_ok(const femlod_mesh *m, const char *path, const femlod_write_options *o) {
    femlod_error err = {0, ""};
    femlod_status s = femlod_mesh_write(m, path, o, &err);
    CHECK(s == FEMLOD_OK);
    if (s != FEMLOD_OK) fprintf(stderr, "  writing %s: %s\n", path, err.message);
    return s == FEMLOD_OK;
}

static uint32_t u32le(const unsigned char *p) {
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}

static float f32le(const unsigned char *p) {
    uint32_t u = u32le(p);
    float f;
    memcpy(&f, &u, sizeof f);
    return f;
}

/* Corner c (0..2) of triangle t equals (x, y, z) exactly. */
static int corner_is(const femlod_mesh *m, size_t t, int c, double x, double y, double z) {
    if (!m || t >= m->nt) return 0;
    const double *p = m->pos + 3 * (size_t)m->tri[3 * t + (size_t)c];
    return p[0] == x && p[1] == y && p[2] == z;
}

/* Every index in range and every coordinate finite. */
static int mesh_valid(const femlod_mesh *m) {
    for (size_t i = 0; i < 3 * m->nt; i++)
        if (m->tri[i] >= m->nv) return 0;
    for (size_t i = 0; i < 3 * m->nv; i++)
        if (!isfinite(m->pos[i])) return 0;
    return 1;
}


/* b's triangles are a's, corner by corner, with a's positions rounded to float32. */
static int same_corners_f32(const femlod_mesh *a, const femlod_mesh *b) {
    if (!a || !b || a->nt != b->nt) return 0;
    for (size_t c = 0; c < 3 * a->nt; c++) {
        const double *p = a->pos + 3 * (size_t)a->tri[c], *q = b->pos + 3 * (size_t)b->tri[c];
        for (int k = 0; k < 3; k++)
            if ((double)(float)p[k] != q[k]) return 0;
    }
    return 1;
}

/* {====== a small JSON parser: enough to read what glTF writers write */

typedef struct jv {
    char type; /* 'o' object, 'a' array, 'n' number, 's' string, 't' true, 'f' false, 'z' null */
    double num;
    const char *str; /* strings: the raw bytes between the quotes */
    size_t len;
    size_t n; /* members or elements */
    struct jv *item;
    const char **key; /* objects: raw keys */
    size_t *keylen;
} jv;

typedef struct jparser {
    const char *p, *end;
    int bad;
} jparser;

static void jskip(jparser *j) {
    while (j->p < j->end && (*j->p == ' ' || *j->p == '\n' || *j->p == '\r' || *j->p == '\t'))
        j->p++;
}

static void jstr(jparser *j, const char **s, size_t *n) {
    j->p++; /* the opening quote */
    *s = j->p;
    while (j->p < j->end && *j->p != '"') j->p += *j->p == '\\' ? 2 : 1;
    if (j->p >= j->end) {
        j->bad = 1;
        *n = 0;
        return;
    }
    *n = (size_t)(j->p - *s);
    j->p++;
}

static void jvalue(jparser *j, jv *v);

static jv *jgrow(jv *v) {
    v->item = realloc(v->item, (v->n + 1) * sizeof *v->item);
    if (v->type == 'o') {
        v->key = realloc(v->key, (v->n + 1) * sizeof *v->key);
        v->keylen = realloc(v->keylen, (v->n + 1) * sizeof *v->keylen);
    }
    if (!v->item || (v->type == 'o' && (!v->key || !v->keylen))) {
        fprintf(stderr, "test_gltf: out of memory\n");
        exit(1);
    }
    return &v->item[v->n];
}

static void jvalue(jparser *j, jv *v) {
    memset(v, 0, sizeof *v);
    jskip(j);
    if (j->bad || j->p >= j->end) {
        j->bad = 1;
        return;
    }
    char c = *j->p;
    if (c == '{' || c == '[') {
        v->type = c == '{' ? 'o' : 'a';
        char close = c == '{' ? '}' : ']';
        j->p++;
        jskip(j);
        if (j->p < j->end && *j->p == close) {
            j->p++;
            return;
        }
        for (;;) {
            jv *slot = jgrow(v);
            if (v->type == 'o') {
                jskip(j);
                if (j->p >= j->end || *j->p != '"') {
                    j->bad = 1;
                    return;
                }
                jstr(j, &v->key[v->n], &v->keylen[v->n]);
                jskip(j);
                if (j->p >= j->end || *j->p != ':') {
                    j->bad = 1;
                    return;
                }
                j->p++;
            }
            jvalue(j, slot);
            v->n++;
            if (j->bad) return;
            jskip(j);
            if (j->p < j->end && *j->p == ',') {
                j->p++;
                continue;
            }
            if (j->p < j->end && *j->p == close) {
                j->p++;
                return;
            }
            j->bad = 1;
            return;
        }
    }
    if (c == '"') {
        v->type = 's';
        jstr(j, &v->str, &v->len);
        return;
    }
    if (j->end - j->p >= 4 && memcmp(j->p, "true", 4) == 0) {
        v->type = 't';
        j->p += 4;
        return;
    }
    if (j->end - j->p >= 5 && memcmp(j->p, "false", 5) == 0) {
        v->type = 'f';
        j->p += 5;
        return;
    }
    if (j->end - j->p >= 4 && memcmp(j->p, "null", 4) == 0) {
        v->type = 'z';
        j->p += 4;
        return;
    }
    char *e;
    v->type = 'n';
    v->num = strtod(j->p, &e); /* the test runs in the "C" locale */
    if (e == j->p) j->bad = 1;
    j->p = e;
}

static void jfree(jv *v) {
    for (size_t i = 0; i < v->n; i++) jfree(&v->item[i]);
    free(v->item);
    free(v->key);
    free(v->keylen);
}

/* Parses text[0..n) into *v; 1 when it is one whole JSON value. */
static int jparse(jv *v, const char *text, size_t n) {
    jparser j = {text, text + n, 0};
    jvalue(&j, v);
    jskip(&j);
    return !j.bad && j.p == j.end;
}

static const jv *jget(const jv *o, const char *key) {
    if (!o || o->type != 'o') return NULL;
    size_t k = strlen(key);
    for (size_t i = 0; i < o->n; i++)
        if (o->keylen[i] == k && memcmp(o->key[i], key, k) == 0) return &o->item[i];
    return NULL;
}

static const jv *jat(const jv *a, size_t i) {
    return a && a->type == 'a' && i < a->n ? &a->item[i] : NULL;
}

static double jnum(const jv *v, double def) { return v && v->type == 'n' ? v->num : def; }

/* An index member: SIZE_MAX when absent, negative or not a whole number. */
static size_t jidx(const jv *v) {
    if (!v || v->type != 'n' || !(v->num >= 0.0) || v->num > 1e15 || v->num != floor(v->num))
        return SIZE_MAX;
    return (size_t)v->num;
}

static int jstr_is(const jv *v, const char *s) {
    return v && v->type == 's' && v->len == strlen(s) && memcmp(v->str, s, v->len) == 0;
}

/* The JSON and BIN chunks of a GLB (the test's own reading of the layout). */
typedef struct glb_view {
    const char *json;
    size_t json_len;
    const unsigned char *bin;
    size_t bin_len;
} glb_view;

static int glb_split(const unsigned char *d, size_t size, glb_view *g) {
    if (size < 20 || memcmp(d, "glTF", 4) != 0 || u32le(d + 4) != 2 || u32le(d + 8) != size)
        return 0;
    size_t jl = u32le(d + 12);
    if (u32le(d + 16) != 0x4E4F534A || jl > size - 20) return 0;
    g->json = (const char *)d + 20;
    g->json_len = jl;
    g->bin = NULL;
    g->bin_len = 0;
    size_t at = 20 + jl;
    if (at + 8 <= size && u32le(d + at + 4) == 0x004E4942) {
        size_t bl = u32le(d + at);
        if (bl > size - at - 8) return 0;
        g->bin = d + at + 8;
        g->bin_len = bl;
    }
    return 1;
}

/* }====== */

/* {====== 2CylinderEngine.glb: counts and an independent bounding box */

typedef struct engine_walk {
    const jv *root;
    const unsigned char *bin;
    size_t bin_len;
    double min[3], max[3];
    size_t triangles, vertices; /* vertices: POSITION elements over all instances (unwelded) */
    int ok;
} engine_walk;

/* c = a * b, column-major 4x4. */
static void mat_mul(const double a[16], const double b[16], double c[16]) {
    for (int col = 0; col < 4; col++)
        for (int row = 0; row < 4; row++) {
            double s = 0.0;
            for (int k = 0; k < 4; k++) s += a[k * 4 + row] * b[col * 4 + k];
            c[col * 4 + row] = s;
        }
}

/* A float32 VEC3 element of accessor a, straight from the BIN chunk. */
static int engine_position(engine_walk *w, const jv *acc, size_t i, double p[3]) {
    const jv *view = jat(jget(w->root, "bufferViews"), jidx(jget(acc, "bufferView")));
    if (!view || jnum(jget(acc, "componentType"), 0) != 5126) return 0;
    size_t stride = (size_t)jnum(jget(view, "byteStride"), 12);
    size_t at = (size_t)jnum(jget(view, "byteOffset"), 0) +
                (size_t)jnum(jget(acc, "byteOffset"), 0) + i * stride;
    if (at + 12 > w->bin_len) return 0;
    for (int k = 0; k < 3; k++) p[k] = f32le(w->bin + at + 4 * (size_t)k);
    return 1;
}

static void engine_node(engine_walk *w, size_t n, const double parent[16], int depth) {
    const jv *node = jat(jget(w->root, "nodes"), n);
    if (!node || depth > 64) {
        w->ok = 0;
        return;
    }
    double local[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1}, world[16];
    const jv *m = jget(node, "matrix");
    if (m) {
        if (m->n != 16) w->ok = 0;
        for (size_t i = 0; i < 16 && i < m->n; i++) local[i] = jnum(&m->item[i], 0);
    }
    /* This file places its parts with matrices only. */
    if (jget(node, "translation") || jget(node, "rotation") || jget(node, "scale")) w->ok = 0;
    mat_mul(parent, local, world);
    const jv *mesh = jat(jget(w->root, "meshes"), jidx(jget(node, "mesh")));
    const jv *prims = jget(mesh, "primitives");
    for (size_t k = 0; prims && k < prims->n; k++) {
        const jv *prim = &prims->item[k];
        if (jnum(jget(prim, "mode"), 4) != 4) w->ok = 0;
        const jv *pos =
            jat(jget(w->root, "accessors"), jidx(jget(jget(prim, "attributes"), "POSITION")));
        const jv *idx = jat(jget(w->root, "accessors"), jidx(jget(prim, "indices")));
        if (!pos || !idx || jnum(jget(idx, "componentType"), 0) != 5123) {
            w->ok = 0;
            continue;
        }
        const jv *iview = jat(jget(w->root, "bufferViews"), jidx(jget(idx, "bufferView")));
        size_t count = (size_t)jnum(jget(idx, "count"), 0);
        size_t at =
            (size_t)jnum(jget(iview, "byteOffset"), 0) + (size_t)jnum(jget(idx, "byteOffset"), 0);
        w->triangles += count / 3;
        w->vertices += (size_t)jnum(jget(pos, "count"), 0);
        for (size_t i = 0; i < count; i++) {
            if (at + 2 * i + 2 > w->bin_len) {
                w->ok = 0;
                break;
            }
            size_t v = (size_t)w->bin[at + 2 * i] | (size_t)w->bin[at + 2 * i + 1] << 8;
            double p[3];
            if (!engine_position(w, pos, v, p)) {
                w->ok = 0;
                break;
            }
            for (int r = 0; r < 3; r++) {
                double x =
                    world[r] * p[0] + world[4 + r] * p[1] + world[8 + r] * p[2] + world[12 + r];
                if (x < w->min[r]) w->min[r] = x;
                if (x > w->max[r]) w->max[r] = x;
            }
        }
    }
    const jv *kids = jget(node, "children");
    for (size_t k = 0; kids && k < kids->n; k++)
        engine_node(w, jidx(&kids->item[k]), world, depth + 1);
}

static void test_engine(void) {
    char p[600];
    path_in(p, sizeof p, FEMLOD_SHARED_DATA, "2CylinderEngine.glb");
    femlod_mesh *m = read_ok(p);
    if (!m) return;
    /* ../shared/data/README.md: all triangle primitives of the default scene in
     * world space, positions welded when they compare equal. */
    CHECK(m->nt == 121496);
    CHECK(m->nv == 60041);
    CHECK(mesh_valid(m));
    femlod_quality q;
    CHECK(femlod_mesh_quality(m, &q, NULL) == FEMLOD_OK);
    CHECK_REL(q.stretch_avg, 0.40900522, 1e-6);
    CHECK_REL(q.size_max, 243.748788, 1e-6);
    CHECK(q.valence_max == 48);
    CHECK(q.degenerate == 11160);

    size_t size;
    char *data = slurp(p, &size);
    glb_view g;
    jv root;
    CHECK(glb_split((const unsigned char *)data, size, &g));
    CHECK(jparse(&root, g.json, g.json_len));
    engine_walk w = {
        &root, g.bin, g.bin_len, {HUGE_VAL, HUGE_VAL, HUGE_VAL}, {-HUGE_VAL, -HUGE_VAL, -HUGE_VAL},
        0,     0,     1};
    const double id[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
    const jv *scene = jat(jget(&root, "scenes"), (size_t)jnum(jget(&root, "scene"), 0));
    const jv *roots = jget(scene, "nodes");
    CHECK(roots && roots->n == 2);
    for (size_t k = 0; roots && k < roots->n; k++) engine_node(&w, jidx(&roots->item[k]), id, 0);
    CHECK(w.ok);
    CHECK(w.triangles == 121496);
    CHECK(w.vertices == 84657); /* README: "on 84,657 unwelded vertices" */
    double mn[3], mx[3];
    femlod_mesh_bbox(m, mn, mx);
    for (int k = 0; k < 3; k++) {
        CHECK_NEAR(mn[k], w.min[k], 1e-9);
        CHECK_NEAR(mx[k], w.max[k], 1e-9);
    }
    /* And the README's rounded figures. */
    const double want_min[3] = {-371.692, -180.972, -140}, want_max[3] = {371.692, 92.0416, 128};
    for (int k = 0; k < 3; k++) {
        CHECK_REL(mn[k], want_min[k], 1e-5);
        CHECK_REL(mx[k], want_max[k], 1e-5);
    }
    /* Without its transforms the engine's parts would sit elsewhere: the
     * first root's child matrix moves a part by (136.86, -64.45, -36.18). */
    CHECK(mx[0] - mn[0] > 700.0);

    /* The same bytes from memory. */
    femlod_read_options ro = {FEMLOD_FORMAT_GLB};
    femlod_mesh *mm = NULL;
    femlod_error err = {0, ""};
    CHECK(femlod_mesh_read_memory(&mm, data, size, "engine", &ro, &err) == FEMLOD_OK);
    CHECK(shape_same_mesh(m, mm));
    femlod_mesh_free(mm);
    jfree(&root);
    free(data);
    femlod_mesh_free(m);
}

/* }====== */

/* {====== hand-made valid files */

static void test_modes(void) {
    char p[600];
    /* No scene: mesh 0 as it stands. Primitive a: TRIANGLES with UNSIGNED_BYTE
     * indices over a quad; b: TRIANGLE_STRIP, UNSIGNED_SHORT; c: TRIANGLE_FAN,
     * UNSIGNED_INT; d: TRIANGLES without indices, interleaved (byteStride 16). */
    femlod_mesh *m = read_ok(path_in(p, sizeof p, FEMLOD_TEST_DATA, "gltf_modes.gltf"));
    if (!m) return;
    CHECK(m->nt == 10);
    CHECK(m->nv == 20);
    static const double want[10][9] = {
        {0, 0, 0, 1, 0, 0, 1, 1, 0},
        {0, 0, 0, 1, 1, 0, 0, 1, 0}, /* a */
        {0, 0, 1, 0, 1, 1, 1, 0, 1},
        {0, 1, 1, 1, 1, 1, 1, 0, 1}, /* b: {v1, v3, v2} keeps the winding */
        {1, 0, 1, 1, 1, 1, 2, 0, 1}, /* b */
        {1, 0, 2, 1, 1, 2, 0, 0, 2},
        {1, 1, 2, 0, 1, 2, 0, 0, 2},  /* c: {v_i+1, v_i+2, v0} */
        {0, 1, 2, -1, 1, 2, 0, 0, 2}, /* c */
        {0, 0, 3, 1, 0, 3, 0, 1, 3},
        {5, 5, 3, 6, 5, 3, 5, 6, 3}}; /* d */
    for (size_t t = 0; t < 10; t++)
        for (int c = 0; c < 3; c++)
            CHECK(corner_is(m, t, c, want[t][3 * c], want[t][3 * c + 1], want[t][3 * c + 2]));
    femlod_mesh_free(m);
}

/* Unit normal z of triangle t. */
static double normal_z(const femlod_mesh *m, size_t t) {
    const double *a = m->pos + 3 * (size_t)m->tri[3 * t],
                 *b = m->pos + 3 * (size_t)m->tri[3 * t + 1],
                 *c = m->pos + 3 * (size_t)m->tri[3 * t + 2];
    double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]},
           v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    double n[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
    return n[2] / sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
}

static void test_nodes(void) {
    char p[600];
    /* One triangle (0,0,0) (1,0,0) (0,1,0), placed by the nodes of scene 1
     * (the default; scene 0 holds a node at x = 100 that must not appear):
     * node 0 a matrix translating by (5,0,0); node 1 translation (0,0,1),
     * rotation 90 degrees about z, scale 2; node 2 translating by (0,10,0)
     * with child node 3 mirroring x (scale -1, 1, 1); node 4 a camera. The
     * file also holds an embedded PNG and an image file that does not exist. */
    femlod_mesh *m = read_ok(path_in(p, sizeof p, FEMLOD_TEST_DATA, "gltf_nodes.gltf"));
    if (!m) return;
    CHECK(m->nt == 3);
    CHECK(m->nv == 9);
    CHECK(corner_is(m, 0, 0, 5, 0, 0) && corner_is(m, 0, 1, 6, 0, 0) &&
          corner_is(m, 0, 2, 5, 1, 0));
    /* T * R * S: (1,0,0) -> (2,0,0) -> (0,2,0) -> (0,2,1); (0,1,0) -> (-2,0,1). */
    static const double rot[3][3] = {{0, 0, 1}, {0, 2, 1}, {-2, 0, 1}};
    for (int c = 0; c < 3 && m->nt > 1; c++) {
        const double *q = m->pos + 3 * (size_t)m->tri[3 + (size_t)c];
        for (int k = 0; k < 3; k++) CHECK_NEAR(q[k], rot[c][k], 1e-12);
    }
    /* Mirrored: corners (0,10,0) (-1,10,0) (0,11,0), winding turned back. */
    CHECK(corner_is(m, 2, 0, 0, 10, 0) && corner_is(m, 2, 1, 0, 11, 0) &&
          corner_is(m, 2, 2, -1, 10, 0));
    for (size_t t = 0; t < m->nt; t++) CHECK_NEAR(normal_z(m, t), 1.0, 1e-12);
    femlod_mesh_free(m);
}

static void test_sparse_external(void) {
    char p[600];
    /* Sparse: the quad with vertex 2 replaced by (2,2,0); then three
     * vertices without a bufferView (zeros) with vertices 1 and 2 set. */
    femlod_mesh *m = read_ok(path_in(p, sizeof p, FEMLOD_TEST_DATA, "gltf_sparse.gltf"));
    if (m) {
        CHECK(m->nt == 3);
        CHECK(m->nv == 6);
        CHECK(corner_is(m, 0, 0, 0, 0, 0) && corner_is(m, 0, 1, 1, 0, 0) &&
              corner_is(m, 0, 2, 2, 2, 0));
        CHECK(corner_is(m, 1, 0, 0, 0, 0) && corner_is(m, 1, 1, 2, 2, 0) &&
              corner_is(m, 1, 2, 0, 1, 0));
        CHECK(corner_is(m, 2, 0, 0, 0, 0) && corner_is(m, 2, 1, 0, 0, 7) &&
              corner_is(m, 2, 2, 0, 7, 7));
    }
    femlod_mesh_free(m);

    /* An external .bin beside the .gltf; the node translates by (10,20,30). */
    m = read_ok(path_in(p, sizeof p, FEMLOD_TEST_DATA, "tiny_external.gltf"));
    if (m) {
        CHECK(m->nt == 2 && m->nv == 4);
        CHECK(corner_is(m, 0, 0, 10, 20, 30) && corner_is(m, 0, 1, 11, 20, 30) &&
              corner_is(m, 0, 2, 11, 21, 30));
        CHECK(corner_is(m, 1, 0, 10, 20, 30) && corner_is(m, 1, 1, 11, 21, 30) &&
              corner_is(m, 1, 2, 10, 21, 30));
    }
    femlod_mesh_free(m);

    /* From memory there is no folder to read it from. */
    size_t size;
    char *data = slurp(p, &size);
    femlod_read_options ro = {FEMLOD_FORMAT_GLTF};
    femlod_error err = {0, ""};
    m = NULL;
    CHECK(femlod_mesh_read_memory(&m, data, size, "mem.gltf", &ro, &err) == FEMLOD_EUNSUPPORTED);
    CHECK(m == NULL);
    CHECK_STR_HAS(err.message, "mem.gltf: /buffers/0: buffer file 'tiny_external.bin' cannot be "
                               "read: glTF from memory has no folder");
    free(data);

    /* Draco in extensionsUsed only: the file holds uncompressed accessors too. */
    m = read_ok(path_in(p, sizeof p, FEMLOD_TEST_DATA, "gltf_draco_fallback.gltf"));
    if (m) CHECK(m->nt == 1 && corner_is(m, 0, 1, 1, 0, 0) && corner_is(m, 0, 2, 0, 1, 0));
    femlod_mesh_free(m);

    /* A GLB with its BIN chunk, from a file and from memory. */
    m = read_ok(path_in(p, sizeof p, FEMLOD_TEST_DATA, "tiny.glb"));
    if (m) CHECK(m->nt == 1 && corner_is(m, 0, 1, 1, 0, 0) && corner_is(m, 0, 2, 0, 1, 0));
    data = slurp(p, &size);
    femlod_mesh *mm = NULL;
    ro.format = FEMLOD_FORMAT_GLB;
    CHECK(femlod_mesh_read_memory(&mm, data, size, "mem.glb", &ro, &err) == FEMLOD_OK);
    CHECK(shape_same_mesh(m, mm));
    femlod_mesh_free(mm);
    femlod_mesh_free(m);
    free(data);
}

/* }====== */

/* {====== malformed files */

static void test_bad_files(void) {
    static const struct {
        const char *file;
        femlod_status status;
        const char *message; /* after "PATH: " */
    } bad[] = {
        {"accessor_past_end.gltf", FEMLOD_EPARSE,
         "/accessors/0: accessor runs past the end of bufferView 0 (needs 1200 bytes, has 36)"},
        {"accessor_one_past.gltf", FEMLOD_EPARSE,
         "/accessors/0: accessor runs past the end of bufferView 0 (needs 40 bytes, has 36)"},
        {"bufferview_range.gltf", FEMLOD_EPARSE,
         "/accessors/0: bufferView 7 out of range (1 bufferViews)"},
        {"view_past_buffer.gltf", FEMLOD_EPARSE,
         "/bufferViews/0: bufferView runs past the end of buffer 0 (needs 48 bytes, has 36)"},
        {"buffer_range.gltf", FEMLOD_EPARSE, "/bufferViews/0: buffer 3 out of range (1 buffers)"},
        {"wrong_length.glb", FEMLOD_EPARSE,
         "byte 8: GLB header gives a length of 496 bytes, but the file has 396"},
        {"bin_past_end.glb", FEMLOD_EPARSE,
         "byte 352: chunk of 40 bytes runs past the end of the file (36 bytes left)"},
        {"version1.glb", FEMLOD_EUNSUPPORTED, "byte 4: GLB version 1 (femlod reads version 2)"},
        {"bad_json.gltf", FEMLOD_EPARSE,
         "invalid JSON: parse error at line 2, column 9: syntax error while parsing value"},
        {"missing_buffer.gltf", FEMLOD_EIO,
         "/buffers/0: cannot open buffer file 'missing.bin': No such file or directory"},
        {"climb_out.gltf", FEMLOD_EPARSE,
         "/buffers/0: buffer uri '../../../../etc/hostname' climbs out of the asset's folder"},
        {"absolute_uri.gltf", FEMLOD_EPARSE,
         "/buffers/0: buffer uri '/etc/hostname' is an absolute path"},
        {"http_uri.gltf", FEMLOD_EUNSUPPORTED,
         "/buffers/0: buffer uri 'https://example.com/tri.bin': scheme 'https:' is not supported"},
        {"bad_base64.gltf", FEMLOD_EPARSE,
         "/buffers/0: data URI is not base64: character '!' at offset 40"},
        {"index_range.gltf", FEMLOD_EPARSE,
         "/accessors/1: index 3 (element 2) out of range (POSITION /accessors/0 has 3 elements)"},
        {"draco.gltf", FEMLOD_EUNSUPPORTED,
         "/meshes/0/primitives/0: compressed with KHR_draco_mesh_compression, which femlod does "
         "not decode"},
        {"meshopt.gltf", FEMLOD_EUNSUPPORTED,
         "/bufferViews/0: compressed with EXT_meshopt_compression, which femlod does not decode"},
        {"points.gltf", FEMLOD_EUNSUPPORTED,
         "/meshes/0/primitives/0: mode 0 (POINTS) is not a triangle mode"},
        {"lines.gltf", FEMLOD_EUNSUPPORTED,
         "/meshes/0/primitives/0: mode 1 (LINES) is not a triangle mode"},
        {"unknown_required.gltf", FEMLOD_EUNSUPPORTED,
         "/extensionsRequired/0: required extension 'KHR_mesh_quantization' is not supported"},
        {"triangles_count.gltf", FEMLOD_EPARSE,
         "/meshes/0/primitives/0: 4 vertices do not make whole triangles"},
        {"position_type.gltf", FEMLOD_EPARSE,
         "/accessors/0: POSITION is UNSIGNED_SHORT VEC3 (FLOAT VEC3 expected)"},
        {"position_nan.gltf", FEMLOD_EPARSE,
         "/accessors/0: element 1: coordinate is not finite (nan)"},
        {"node_cycle.gltf", FEMLOD_EPARSE,
         "/nodes/1/children/0: node 0 is reached twice from /scenes/0"},
        {"node_mesh_range.gltf", FEMLOD_EPARSE, "/nodes/0/mesh: mesh 4 out of range (1 meshes)"},
        {"sparse_index_range.gltf", FEMLOD_EPARSE,
         "/accessors/0/sparse/indices: index 5 (entry 0) out of range (3 elements)"},
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        char dir[600], p[700], want[900];
        path_in(dir, sizeof dir, FEMLOD_TEST_DATA, "bad");
        path_in(p, sizeof p, dir, bad[i].file);
        snprintf(want, sizeof want, "%s: %s", p, bad[i].message);
        femlod_error err = {0, ""};
        femlod_mesh *m = NULL;
        femlod_status s = femlod_mesh_read(&m, p, NULL, &err);
        CHECK(s == bad[i].status && err.status == bad[i].status && m == NULL);
        CHECK_STR_HAS(err.message, want);
        if (s != bad[i].status) fprintf(stderr, "  %s: status %d\n", bad[i].file, (int)s);
        /* A second read says the same: no error text is carried over. */
        femlod_error again = {0, ""};
        CHECK(femlod_mesh_read(&m, p, NULL, &again) == s);
        CHECK(strcmp(again.message, err.message) == 0);
    }

    /* Hostile JSON nesting (tinygltf recurses into extras). */
    size_t n = 200000;
    char *deep = malloc(2 * n + 64);
    if (deep) {
        int k = snprintf(deep, 64, "{\"asset\":{\"version\":\"2.0\",\"extras\":");
        memset(deep + k, '[', n);
        memset(deep + k + n, ']', n);
        memcpy(deep + k + 2 * n, "}}", 2);
        femlod_read_options ro = {FEMLOD_FORMAT_GLTF};
        femlod_error err = {0, ""};
        femlod_mesh *m = NULL;
        CHECK(femlod_mesh_read_memory(&m, deep, (size_t)k + 2 * n + 2, "deep.gltf", &ro, &err) ==
              FEMLOD_ELIMIT);
        CHECK_STR_HAS(err.message, "deep.gltf: byte 289: JSON nested more than 256 levels deep");
        free(deep);
    }
    /* Not glTF at all, and nothing. */
    femlod_read_options ro = {FEMLOD_FORMAT_GLB};
    femlod_error err = {0, ""};
    femlod_mesh *m = NULL;
    CHECK(femlod_mesh_read_memory(&m, "solid x", 7, "x.glb", &ro, &err) == FEMLOD_EPARSE);
    CHECK_STR_HAS(err.message, "x.glb: byte 0: not a GLB file (no 'glTF' magic) nor glTF JSON");
    CHECK(femlod_mesh_read_memory(&m, "", 0, "x.glb", &ro, &err) == FEMLOD_EPARSE);
    CHECK_STR_HAS(err.message, "x.glb: empty file");
    CHECK(femlod_mesh_read_memory(&m, "glTF\2\0\0\0", 8, "x.glb", &ro, &err) == FEMLOD_EPARSE);
    CHECK_STR_HAS(err.message, "x.glb: byte 8: file ends inside the 20-byte GLB header (8 bytes)");
}

/* External buffers are read only from inside the asset's folder, whatever
 * symbolic links say. */
static void test_confinement(void) {
    char dir[600], p[700], q[700], src[700];
    path_in(dir, sizeof dir, scratch, "asset");
    CHECK(mkdir(dir, 0755) == 0 || errno == EEXIST);
    size_t size, bin_size;
    char *gltf = slurp(path_in(src, sizeof src, FEMLOD_TEST_DATA, "tiny_external.gltf"), &size);
    char *bin = slurp(path_in(src, sizeof src, FEMLOD_TEST_DATA, "tiny_external.bin"), &bin_size);
    const char *name = strstr(gltf, "tiny_external.bin");
    CHECK(name != NULL);
    if (!name) {
        free(gltf);
        free(bin);
        return;
    }
    /* The .gltf with its uri replaced by each of these names. */
    static const struct {
        const char *uri;
        femlod_status status;
        const char *message;
    } cases[] = {
        {"inside.bin", FEMLOD_OK, NULL},
        {"sub/alias.bin", FEMLOD_OK, NULL}, /* a link to ../inside.bin: stays inside */
        {"outside.bin", FEMLOD_EPARSE,
         "/buffers/0: buffer file 'outside.bin' leaves the asset's folder through a symbolic link"},
        {"sub", FEMLOD_EIO, "/buffers/0: buffer file 'sub' is not a regular file"},
        {"sub/../inside.bin", FEMLOD_EPARSE,
         "/buffers/0: buffer uri 'sub/../inside.bin' climbs out of the asset's folder"},
        {"in%73ide.bin", FEMLOD_OK, NULL}, /* percent-decoded by tinygltf: inside.bin */
        {"%2e%2e/asset/inside.bin", FEMLOD_EPARSE, "climbs out of the asset's folder"},
        {"short.bin", FEMLOD_EPARSE, "/buffers/0: buffer file has 30 bytes, but byteLength is 60"},
    };
    spit(path_in(p, sizeof p, dir, "inside.bin"), bin, bin_size);
    spit(path_in(p, sizeof p, dir, "short.bin"), bin, 30);
    path_in(p, sizeof p, dir, "sub");
    CHECK(mkdir(p, 0755) == 0 || errno == EEXIST);
    path_in(q, sizeof q, dir, "sub/alias.bin");
    unlink(q);
    CHECK(symlink("../inside.bin", q) == 0);
    path_in(q, sizeof q, dir, "outside.bin");
    unlink(q);
    CHECK(symlink(src, q) == 0); /* tests/data/tiny_external.bin, a real file outside */
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        size_t head = (size_t)(name - gltf), tail = size - head - strlen("tiny_external.bin");
        size_t ulen = strlen(cases[i].uri);
        char *text = malloc(head + ulen + tail);
        if (!text) continue;
        memcpy(text, gltf, head);
        memcpy(text + head, cases[i].uri, ulen);
        memcpy(text + head + ulen, name + strlen("tiny_external.bin"), tail);
        path_in(p, sizeof p, dir, "x.gltf");
        spit(p, text, head + ulen + tail);
        free(text);
        femlod_error err = {0, ""};
        femlod_mesh *m = NULL;
        femlod_status s = femlod_mesh_read(&m, p, NULL, &err);
        CHECK(s == cases[i].status);
        if (s != cases[i].status) fprintf(stderr, "  uri %s: %s\n", cases[i].uri, err.message);
        if (cases[i].message) {
            CHECK(m == NULL);
            CHECK_STR_HAS(err.message, cases[i].message);
        } else {
            CHECK(m && m->nt == 2 && corner_is(m, 0, 0, 10, 20, 30));
        }
        femlod_mesh_free(m);
    }
    /* A good one read through a relative path from inside its folder. */
    spit(path_in(p, sizeof p, dir, "x.gltf"), gltf, size);
    spit(path_in(p, sizeof p, dir, "tiny_external.bin"), bin, bin_size);
    char cwd[600];
    if (getcwd(cwd, sizeof cwd) && chdir(dir) == 0) {
        femlod_mesh *m = read_ok("x.gltf");
        femlod_mesh_free(m);
        CHECK(chdir(cwd) == 0);
    }
    const char *names[] = {"x.gltf",        "inside.bin",        "outside.bin",
                           "sub/alias.bin", "tiny_external.bin", "short.bin"};
    for (size_t i = 0; i < 6; i++) unlink(path_in(p, sizeof p, dir, names[i]));
    rmdir(path_in(p, sizeof p, dir, "sub"));
    rmdir(dir);
    free(gltf);
    free(bin);
}

/* }====== */

/* {====== writing */

typedef struct written {
    char *data;
    size_t size;
    glb_view g;
    jv root;
    int ok;
} written;

/* Reads back a GLB femlod wrote: layout checked, JSON parsed. */
static void read_glb(const char *path, written *w) {
    w->data = slurp(path, &w->size);
    w->ok = glb_split((const unsigned char *)w->data, w->size, &w->g) &&
            jparse(&w->root, w->g.json, w->g.json_len);
    CHECK(w->ok);
    /* Chunks 4-aligned: JSON padded with spaces, BIN with zeros. */
    CHECK(w->g.json_len % 4 == 0 && w->g.bin_len % 4 == 0);
}

static void written_free(written *w) {
    if (w->ok) jfree(&w->root);
    free(w->data);
}

/* Accessor a's float32 component k of element i (tightly packed views). */
static float acc_float(const written *w, size_t a, size_t i, size_t k, size_t ncomp) {
    const jv *acc = jat(jget(&w->root, "accessors"), a);
    const jv *view = jat(jget(&w->root, "bufferViews"), jidx(jget(acc, "bufferView")));
    size_t at = (size_t)jnum(jget(view, "byteOffset"), 0) + 4 * (i * ncomp + k);
    if (!view || at + 4 > w->g.bin_len) return NAN;
    return f32le(w->g.bin + at);
}

static size_t attr(const written *w, const char *name) {
    const jv *prim = jat(jget(jat(jget(&w->root, "meshes"), 0), "primitives"), 0);
    return jidx(jget(jget(prim, "attributes"), name));
}

static const double *sort_key; /* for by_key */
static int by_key(const void *a, const void *b) {
    double x = sort_key[*(const size_t *)a], y = sort_key[*(const size_t *)b];
    return x < y ? -1 : x > y;
}

static void test_write_contents(void) {
    char src[600], p[700];
    femlod_mesh *m = read_ok(path_in(src, sizeof src, FEMLOD_SHARED_DATA, "fandisk.obj"));
    if (!m) return;
    femlod_quality q;
    CHECK(femlod_mesh_quality(m, &q, NULL) == FEMLOD_OK);

    /* Plain GLB: indexed, 16-bit indices, POSITION bounds, quality and caller extras. */
    femlod_write_options o = FEMLOD_WRITE_OPTIONS_INIT;
    o.extras = "{\"recipe\": \"fandisk.lua\", \"min_stretch\": 0.3, \"steps\": [1, 2], "
               "\"nested\": {\"deep\": true}}";
    path_in(p, sizeof p, scratch, "plain.glb");
    if (write_ok(m, p, &o)) {
        written w;
        read_glb(p, &w);
        const jv *asset = jget(&w.root, "asset");
        CHECK(jstr_is(jget(asset, "generator"), "femlod " FEMLOD_VERSION_STRING));
        CHECK(jstr_is(jget(asset, "version"), "2.0"));
        const jv *qual = jget(jget(asset, "extras"), "quality");
        CHECK(jnum(jget(qual, "triangles"), -1) == 12946);
        CHECK(jnum(jget(qual, "vertices"), -1) == 6475);
        CHECK(jnum(jget(qual, "stretch_avg"), -1) == q.stretch_avg);
        CHECK(jnum(jget(qual, "stretch_min"), -1) == q.stretch_min);
        CHECK(jnum(jget(qual, "size_max"), -1) == q.size_max);
        CHECK(jnum(jget(qual, "valence_max"), -1) == 9);
        const jv *params = jget(jget(asset, "extras"), "params");
        CHECK(jstr_is(jget(params, "recipe"), "fandisk.lua"));
        CHECK(jnum(jget(params, "min_stretch"), -1) == 0.3);
        CHECK(jnum(jat(jget(params, "steps"), 1), -1) == 2);
        CHECK(jget(jget(params, "nested"), "deep") &&
              jget(jget(params, "nested"), "deep")->type == 't');
        CHECK(jnum(jget(&w.root, "scene"), -1) == 0);
        const jv *prim = jat(jget(jat(jget(&w.root, "meshes"), 0), "primitives"), 0);
        const jv *idx = jat(jget(&w.root, "accessors"), jidx(jget(prim, "indices")));
        CHECK(jnum(jget(idx, "componentType"), 0) == 5123);
        CHECK(jnum(jget(idx, "count"), 0) == 3 * 12946);
        CHECK(!jget(prim, "material") && !jget(&w.root, "materials"));
        CHECK(attr(&w, "NORMAL") == (size_t)-1 && attr(&w, "COLOR_0") == (size_t)-1);
        const jv *pos = jat(jget(&w.root, "accessors"), attr(&w, "POSITION"));
        CHECK(jnum(jget(pos, "count"), 0) == 6475);
        double mn[3], mx[3];
        femlod_mesh_bbox(m, mn, mx);
        for (size_t k = 0; k < 3; k++) {
            CHECK(jnum(jat(jget(pos, "min"), k), 1) == (double)(float)mn[k]);
            CHECK(jnum(jat(jget(pos, "max"), k), -1) == (double)(float)mx[k]);
        }
        written_free(&w);
    }

    /* color_by = stretch, normals: flat (three vertices a triangle, no
     * indices), COLOR_0 in [0, 1] rising with stretch, _STRETCH raw, unlit
     * material, unit normals. */
    o = (femlod_write_options)FEMLOD_WRITE_OPTIONS_INIT;
    o.color_by = FEMLOD_COLOR_STRETCH;
    o.normals = 1;
    path_in(p, sizeof p, scratch, "stretch.glb");
    double *stretch = malloc(m->nt * sizeof *stretch);
    size_t *order = malloc(m->nt * sizeof *order);
    if (stretch && order && write_ok(m, p, &o)) {
        femlod_stretch_array(stretch, m->pos, m->tri, m->nt);
        written w;
        read_glb(p, &w);
        const jv *prim = jat(jget(jat(jget(&w.root, "meshes"), 0), "primitives"), 0);
        CHECK(prim && !jget(prim, "indices"));
        CHECK(jnum(jget(prim, "material"), -1) == 0);
        const jv *mat = jat(jget(&w.root, "materials"), 0);
        CHECK(jget(jget(mat, "extensions"), "KHR_materials_unlit") != NULL);
        CHECK(jstr_is(jat(jget(&w.root, "extensionsUsed"), 0), "KHR_materials_unlit"));
        const jv *scale = jget(jget(jget(&w.root, "asset"), "extras"), "color_scale");
        CHECK(jstr_is(jget(scale, "attribute"), "_STRETCH") &&
              jstr_is(jget(scale, "map"), "viridis"));
        CHECK(jnum(jget(scale, "min"), -1) == 0.0 && jnum(jget(scale, "max"), -1) == 1.0);
        size_t cpos = attr(&w, "POSITION"), ccol = attr(&w, "COLOR_0"), craw = attr(&w, "_STRETCH"),
               cnrm = attr(&w, "NORMAL");
        CHECK(jnum(jget(jat(jget(&w.root, "accessors"), cpos), "count"), 0) == 3.0 * 12946);
        int raw_ok = 1, col_ok = 1, nrm_ok = 1, pos_ok = 1;
        for (size_t t = 0; t < m->nt; t++)
            for (size_t c = 0; c < 3; c++) {
                size_t i = 3 * t + c;
                if (acc_float(&w, craw, i, 0, 1) != (float)stretch[t]) raw_ok = 0;
                for (size_t k = 0; k < 3; k++) {
                    float col = acc_float(&w, ccol, i, k, 3);
                    if (!(col >= 0.0f && col <= 1.0f)) col_ok = 0;
                    if (col != acc_float(&w, ccol, 3 * t, k, 3)) col_ok = 0; /* flat */
                    if (acc_float(&w, cpos, i, k, 3) != (float)m->pos[3 * (size_t)m->tri[i] + k])
                        pos_ok = 0;
                }
                double n0 = acc_float(&w, cnrm, i, 0, 3), n1 = acc_float(&w, cnrm, i, 1, 3),
                       n2 = acc_float(&w, cnrm, i, 2, 3);
                if (fabs(sqrt(n0 * n0 + n1 * n1 + n2 * n2) - 1.0) > 1e-6) nrm_ok = 0;
            }
        CHECK(raw_ok);
        CHECK(col_ok);
        CHECK(nrm_ok);
        CHECK(pos_ok);
        /* viridis's green rises over the whole map: so does COLOR_0's with stretch. */
        for (size_t t = 0; t < m->nt; t++) order[t] = t;
        sort_key = stretch;
        qsort(order, m->nt, sizeof *order, by_key);
        int monotone = 1;
        for (size_t k = 1; k < m->nt; k++)
            if (acc_float(&w, ccol, 3 * order[k], 1, 3) <
                acc_float(&w, ccol, 3 * order[k - 1], 1, 3))
                monotone = 0;
        CHECK(monotone);
        CHECK(acc_float(&w, ccol, 3 * order[m->nt - 1], 1, 3) >
              acc_float(&w, ccol, 3 * order[0], 1, 3));
        written_free(&w);
    }
    free(stretch);
    free(order);

    /* color_by = valence: per vertex on the shared vertices, indexed. */
    o = (femlod_write_options)FEMLOD_WRITE_OPTIONS_INIT;
    o.color_by = FEMLOD_COLOR_VALENCE;
    path_in(p, sizeof p, scratch, "valence.glb");
    uint32_t *val = malloc(m->nv * sizeof *val);
    if (val && write_ok(m, p, &o)) {
        CHECK(femlod_valence_array(val, m->nv, m->tri, m->nt, NULL) == FEMLOD_OK);
        written w;
        read_glb(p, &w);
        size_t craw = attr(&w, "_VALENCE");
        int ok = 1;
        for (size_t v = 0; v < m->nv; v++)
            if (acc_float(&w, craw, v, 0, 1) != (float)val[v]) ok = 0;
        CHECK(ok);
        const jv *scale = jget(jget(jget(&w.root, "asset"), "extras"), "color_scale");
        CHECK(jnum(jget(scale, "min"), -1) == 3.0 && jnum(jget(scale, "max"), -1) == 12.0);
        CHECK(jstr_is(jget(scale, "per"), "vertex"));
        written_free(&w);
    }
    free(val);

    /* color_by = size: scaled on the mesh's own [min, max]. */
    o.color_by = FEMLOD_COLOR_SIZE;
    path_in(p, sizeof p, scratch, "size.glb");
    double *size = malloc(m->nt * sizeof *size);
    if (size && write_ok(m, p, &o)) {
        femlod_size_array(size, m->pos, m->tri, m->nt);
        double lo = size[0], hi = size[0];
        for (size_t t = 0; t < m->nt; t++) {
            lo = fmin(lo, size[t]);
            hi = fmax(hi, size[t]);
        }
        written w;
        read_glb(p, &w);
        const jv *scale = jget(jget(jget(&w.root, "asset"), "extras"), "color_scale");
        CHECK(jnum(jget(scale, "min"), -1) == lo && jnum(jget(scale, "max"), -1) == hi);
        CHECK(jstr_is(jget(scale, "attribute"), "_SIZE"));
        written_free(&w);
    }
    free(size);

    /* .gltf: JSON with the buffer as a base64 data: URI. */
    o = (femlod_write_options)FEMLOD_WRITE_OPTIONS_INIT;
    o.color_by = FEMLOD_COLOR_STRETCH;
    path_in(p, sizeof p, scratch, "stretch.gltf");
    if (write_ok(m, p, &o)) {
        size_t n;
        char *text = slurp(p, &n);
        jv root;
        CHECK(n > 0 && text[0] == '{');
        CHECK(jparse(&root, text, n));
        const jv *uri = jget(jat(jget(&root, "buffers"), 0), "uri");
        CHECK(uri && uri->type == 's' && uri->len > 37 &&
              memcmp(uri->str, "data:application/octet-stream;base64,", 37) == 0);
        CHECK(jstr_is(jget(jget(&root, "asset"), "generator"), "femlod " FEMLOD_VERSION_STRING));
        jfree(&root);
        free(text);
    }
    /* format "gltf" to a .glb name writes GLB, to another name JSON; "glb" always GLB. */
    o = (femlod_write_options)FEMLOD_WRITE_OPTIONS_INIT;
    static const struct {
        femlod_format f;
        const char *name;
        int glb;
    } naming[] = {{FEMLOD_FORMAT_GLTF, "a.glb", 1},
                  {FEMLOD_FORMAT_GLTF, "a.json", 0},
                  {FEMLOD_FORMAT_GLB, "b.gltf", 1},
                  {FEMLOD_FORMAT_AUTO, "c.GLTF", 0},
                  {FEMLOD_FORMAT_AUTO, "d.GlB", 1}};
    for (size_t i = 0; i < sizeof naming / sizeof naming[0]; i++) {
        o.format = naming[i].f;
        path_in(p, sizeof p, scratch, naming[i].name);
        if (!write_ok(m, p, &o)) continue;
        size_t n;
        char *data = slurp(p, &n);
        CHECK(n > 4 && (memcmp(data, "glTF", 4) == 0) == naming[i].glb);
        free(data);
        unlink(p);
    }
    femlod_mesh_free(m);
}

static void test_round_trips(void) {
    char src[600], p[700], obj[700];
    femlod_mesh *m = read_ok(path_in(src, sizeof src, FEMLOD_SHARED_DATA, "fandisk.obj"));
    if (!m) return;
    static const struct {
        const char *name;
        femlod_color_by color;
        int normals;
    } modes[] = {{"rt.glb", FEMLOD_COLOR_NONE, 0},
                 {"rt.gltf", FEMLOD_COLOR_NONE, 1},
                 {"rt_stretch.glb", FEMLOD_COLOR_STRETCH, 1},
                 {"rt_size.gltf", FEMLOD_COLOR_SIZE, 0},
                 {"rt_valence.glb", FEMLOD_COLOR_VALENCE, 1}};
    for (size_t i = 0; i < sizeof modes / sizeof modes[0]; i++) {
        femlod_write_options o = FEMLOD_WRITE_OPTIONS_INIT;
        o.color_by = modes[i].color;
        o.normals = modes[i].normals;
        path_in(p, sizeof p, scratch, modes[i].name);
        if (!write_ok(m, p, &o)) continue;
        femlod_mesh *back = read_ok(p);
        /* Every triangle, every position to float32 (fandisk's 6475
         * positions stay distinct as floats, so welding gives them back). */
        CHECK(same_corners_f32(m, back));
        CHECK(back && back->nv == 6475);
        /* ... and on to OBJ, which keeps doubles exactly. */
        path_in(obj, sizeof obj, scratch, "rt.obj");
        femlod_mesh *again = NULL;
        if (back && write_ok(back, obj, NULL)) again = read_ok(obj);
        CHECK(shape_same_mesh(back, again));
        femlod_mesh_free(again);
        femlod_mesh_free(back);
        unlink(p);
        unlink(obj);
    }
    femlod_mesh_free(m);

    /* More than 65535 vertices: 32-bit indices; and an exact round trip of
     * a mesh whose coordinates are floats already. */
    femlod_mesh *plane = shape_plane(300);
    CHECK(plane && plane->nv == 301 * 301);
    path_in(p, sizeof p, scratch, "plane.glb");
    if (plane && write_ok(plane, p, NULL)) {
        written w;
        read_glb(p, &w);
        const jv *prim = jat(jget(jat(jget(&w.root, "meshes"), 0), "primitives"), 0);
        const jv *idx = jat(jget(&w.root, "accessors"), jidx(jget(prim, "indices")));
        CHECK(jnum(jget(idx, "componentType"), 0) == 5125);
        written_free(&w);
        femlod_mesh *back = read_ok(p);
        CHECK(same_corners_f32(plane, back));
        femlod_mesh_free(back);
        unlink(p);
    }
    femlod_mesh_free(plane);

    /* An empty mesh: a valid glTF without a scene, read back empty. */
    femlod_mesh *empty = NULL;
    CHECK(femlod_mesh_create(&empty, NULL, 0, NULL, 0, NULL) == FEMLOD_OK);
    path_in(p, sizeof p, scratch, "empty.glb");
    if (empty && write_ok(empty, p, NULL)) {
        femlod_mesh *back = read_ok(p);
        CHECK(back && back->nt == 0 && back->nv == 0);
        femlod_mesh_free(back);
        unlink(p);
    }
    femlod_mesh_free(empty);
}

static void test_write_errors(void) {
    char p[700];
    femlod_mesh *tet = shape_tetrahedron();
    femlod_error err = {0, ""};
    femlod_write_options o = FEMLOD_WRITE_OPTIONS_INIT;

    o.color_by = FEMLOD_COLOR_STRETCH;
    path_in(p, sizeof p, scratch, "x.obj");
    CHECK(femlod_mesh_write(tet, p, &o, &err) == FEMLOD_EINPUT);
    CHECK_STR_HAS(err.message, "x.obj: color_by, normals and extras are glTF options (format obj)");
    CHECK(access(p, F_OK) != 0);
    o = (femlod_write_options)FEMLOD_WRITE_OPTIONS_INIT;
    o.normals = 1;
    o.format = FEMLOD_FORMAT_STL;
    CHECK(femlod_mesh_write(tet, p, &o, &err) == FEMLOD_EINPUT);

    static const struct {
        const char *extras;
        const char *message;
    } bad_extras[] = {{"{\"a\": 1", "extras is not valid JSON: parse error at line 1, column 8"},
                      {"[1, 2]", "extras is not a JSON object"},
                      {"\"text\"", "extras is not a JSON object"}};
    for (size_t i = 0; i < sizeof bad_extras / sizeof bad_extras[0]; i++) {
        o = (femlod_write_options)FEMLOD_WRITE_OPTIONS_INIT;
        o.extras = bad_extras[i].extras;
        path_in(p, sizeof p, scratch, "x.glb");
        CHECK(femlod_mesh_write(tet, p, &o, &err) == FEMLOD_EINPUT);
        CHECK_STR_HAS(err.message, bad_extras[i].message);
        CHECK(access(p, F_OK) != 0); /* no partial file, no temporary left */
    }
    o = (femlod_write_options)FEMLOD_WRITE_OPTIONS_INIT;
    o.color_by = (femlod_color_by)99;
    CHECK(femlod_mesh_write(tet, p, &o, &err) == FEMLOD_EINPUT);
    CHECK_STR_HAS(err.message, "x.glb: invalid color_by code 99");

    /* float32 holds no 1e300. */
    double pos[9] = {0, 0, 0, 1e300, 0, 0, 0, 1, 0};
    uint32_t tri[3] = {0, 1, 2};
    femlod_mesh *huge = NULL;
    CHECK(femlod_mesh_create(&huge, pos, 3, tri, 1, NULL) == FEMLOD_OK);
    CHECK(femlod_mesh_write(huge, p, NULL, &err) == FEMLOD_EINPUT);
    CHECK_STR_HAS(err.message, "x.glb: vertex 1: coordinate 1e+300 does not fit in float32");
    CHECK(access(p, F_OK) != 0);
    femlod_mesh_free(huge);
    femlod_mesh_free(tet);

    CHECK(strcmp(femlod_format_name(FEMLOD_FORMAT_GLTF), "gltf") == 0);
    CHECK(strcmp(femlod_format_name(FEMLOD_FORMAT_GLB), "glb") == 0);
    CHECK(femlod_format_from_name("GLB") == FEMLOD_FORMAT_GLB);
    CHECK(femlod_format_from_path("dir.v2/part.gltf") == FEMLOD_FORMAT_GLTF);
    CHECK(femlod_format_from_path("part.Glb") == FEMLOD_FORMAT_GLB);
}

/* }====== */

/* {====== torture: truncations and byte flips never break the reader */

static uint64_t rng_state = 0x9E3779B97F4A7C15ull;
static uint64_t rng(void) {
    rng_state ^= rng_state >> 12;
    rng_state ^= rng_state << 25;
    rng_state ^= rng_state >> 27;
    return rng_state * 0x2545F4914F6CDD1Dull;
}

static void torture_one(const char *dir, const char *file, femlod_format f, int all_truncations,
                        size_t flips) {
    char p[700];
    size_t size;
    char *data = slurp(path_in(p, sizeof p, dir, file), &size);
    char *copy = malloc(size ? size : 1);
    femlod_read_options ro = {f};
    size_t loaded = 0, failed = 0;
    int bad = 0;
    size_t step = all_truncations ? 1 : 1 + size / 29;
    for (size_t n = 0; copy; n += step) {
        if (n > size) n = size; /* the whole file last */
        memcpy(copy, data, n);
        femlod_mesh *m = NULL;
        femlod_error err = {0, ""};
        if (femlod_mesh_read_memory(&m, copy, n, file, &ro, &err) == FEMLOD_OK) {
            if (!mesh_valid(m)) bad = 1;
            loaded++;
        } else {
            if (m || err.message[0] == '\0') bad = 1;
            failed++;
        }
        femlod_mesh_free(m);
        if (n == size) break;
    }
    for (size_t k = 0; copy && k < flips; k++) {
        memcpy(copy, data, size);
        size_t at = (size_t)(rng() % size);
        copy[at] = (char)(copy[at] ^ (char)(1 + rng() % 255));
        femlod_mesh *m = NULL;
        femlod_error err = {0, ""};
        if (femlod_mesh_read_memory(&m, copy, size, file, &ro, &err) == FEMLOD_OK) {
            if (!mesh_valid(m)) bad = 1;
        } else if (m || err.message[0] == '\0') {
            bad = 1;
        }
        femlod_mesh_free(m);
    }
    CHECK(!bad);
    CHECK(failed > 0 && loaded > 0); /* the whole file loads; its empty prefix does not */
    free(copy);
    free(data);
}

static void test_torture(void) {
    torture_one(FEMLOD_TEST_DATA, "tiny.glb", FEMLOD_FORMAT_GLB, 1, 2000);
    torture_one(FEMLOD_TEST_DATA, "gltf_modes.gltf", FEMLOD_FORMAT_GLTF, 1, 2000);
    torture_one(FEMLOD_TEST_DATA, "gltf_sparse.gltf", FEMLOD_FORMAT_GLTF, 1, 1000);
    torture_one(FEMLOD_TEST_DATA, "gltf_nodes.gltf", FEMLOD_FORMAT_GLTF, 1, 1000);
    torture_one(FEMLOD_SHARED_DATA, "2CylinderEngine.glb", FEMLOD_FORMAT_GLB, 0, 30);
}

/* }====== */

int main(void) {
    const char *tmp = getenv("FEMLOD_TMP");
    snprintf(scratch, sizeof scratch, "%s/test_gltf.%ld", tmp && *tmp ? tmp : "/tmp",
             (long)getpid());
    if (mkdir(scratch, 0755) != 0 && errno != EEXIST) {
        fprintf(stderr, "cannot make %s: %s\n", scratch, strerror(errno));
        return 1;
    }
    test_engine();
    test_modes();
    test_nodes();
    test_sparse_external();
    test_bad_files();
    test_confinement();
    test_write_contents();
    test_round_trips();
    test_write_errors();
    test_torture();

    DIR *d = opendir(scratch);
    if (d) {
        struct dirent *e;
        char p[800];
        while ((e = readdir(d))) {
            if (e->d_name[0] == '.') continue;
            unlink(path_in(p, sizeof p, scratch, e->d_name));
        }
        closedir(d);
    }
    rmdir(scratch);
    return check_report("test_gltf");
}
