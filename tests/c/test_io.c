/* test_io.c - readers, writers, numbers and atomic output (src/io*.c, src/fileio.c).
 *
 * Facts checked: the reference counts of ../shared/data, every feature each
 * reader claims (docs/formats.md), one specific error per malformed file of
 * tests/data/bad (text and position), exact round trips through every
 * format, locale independence, atomic writes that leave nothing behind, and
 * that no truncation or byte flip of a valid file breaks the readers. */
#include "core.h"
#include "io_util.h"

#include "check.h"
#include "shapes.h"

#include <ctype.h>
#include <dirent.h>
#include <errno.h>
#include <float.h>
#include <locale.h>
#include <math.h>
#include <signal.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <unistd.h>

#ifndef FEMLOD_TEST_DATA
#error "FEMLOD_TEST_DATA must name tests/data"
#endif
#ifndef FEMLOD_SHARED_DATA
#error "FEMLOD_SHARED_DATA must name ../shared/data"
#endif

static char scratch[512]; /* this run's own folder under $FEMLOD_TMP */

static const char *path_in(char *buf, size_t size, const char *dir, const char *name) {
    size_t a = strlen(dir), b = strlen(name);
    if (a + b + 2 > size) {
        fprintf(stderr, "test_io: path too long: %s/%s\n", dir, name);
        exit(1);
    }
    memcpy(buf, dir, a);
    buf[a] = '/';
    memcpy(buf + a + 1, name, b + 1);
    return buf;
}

static uint64_t rng_state = 0x9E3779B97F4A7C15ull;
static uint64_t rng(void) { /* xorshift64*: deterministic runs */
    rng_state ^= rng_state >> 12;
    rng_state ^= rng_state << 25;
    rng_state ^= rng_state >> 27;
    return rng_state * 0x2545F4914F6CDD1Dull;
}

static femlod_mesh *read_ok(const char *path, femlod_format f) {
    femlod_read_options o = FEMLOD_READ_OPTIONS_INIT;
    o.format = f;
    femlod_error err = {0, ""};
    femlod_mesh *m = NULL;
    femlod_status s = femlod_mesh_read(&m, path, &o, &err);
    CHECK(s == FEMLOD_OK);
    if (s != FEMLOD_OK) fprintf(stderr, "  reading %s: %s\n", path, err.message);
    return m;
}

static int write_ok(const femlod_mesh *m, const char *path, femlod_format f) {
    femlod_write_options o = FEMLOD_WRITE_OPTIONS_INIT;
    o.format = f;
    femlod_error err = {0, ""};
    femlod_status s = femlod_mesh_write(m, path, &o, &err);
    CHECK(s == FEMLOD_OK);
    if (s != FEMLOD_OK) fprintf(stderr, "  writing %s: %s\n", path, err.message);
    return s == FEMLOD_OK;
}

static femlod_mesh *read_mem(const char *text, femlod_format f, femlod_error *err) {
    femlod_read_options o = {f};
    femlod_mesh *m = NULL;
    femlod_status s = femlod_mesh_read_memory(&m, text, strlen(text), "mem", &o, err);
    if (s != FEMLOD_OK) CHECK(m == NULL);
    return m;
}

static femlod_mesh *mem_ok(const char *text, femlod_format f) {
    femlod_error err = {0, ""};
    femlod_mesh *m = read_mem(text, f, &err);
    CHECK(m != NULL);
    if (!m) fprintf(stderr, "  reading memory: %s\n", err.message);
    return m;
}

/* The text fails with status st and a message containing want. */
static void mem_bad(const char *text, femlod_format f, femlod_status st, const char *want) {
    femlod_error err = {0, ""};
    femlod_mesh *m = read_mem(text, f, &err);
    CHECK(m == NULL);
    femlod_mesh_free(m);
    CHECK(err.status == st);
    CHECK_STR_HAS(err.message, want);
}


/* Same triangles by corner positions (== so that -0.0 matches 0.0): what a
 * welded STL keeps. */
static int same_corners(const femlod_mesh *a, const femlod_mesh *b) {
    if (!a || !b || a->nt != b->nt) return 0;
    for (size_t c = 0; c < 3 * a->nt; c++) {
        const double *p = a->pos + 3 * (size_t)a->tri[c], *q = b->pos + 3 * (size_t)b->tri[c];
        if (p[0] != q[0] || p[1] != q[1] || p[2] != q[2]) return 0;
    }
    return 1;
}

static int tri_is(const femlod_mesh *m, size_t t, uint32_t a, uint32_t b, uint32_t c) {
    return m && t < m->nt && m->tri[3 * t] == a && m->tri[3 * t + 1] == b && m->tri[3 * t + 2] == c;
}

static int pos_is(const femlod_mesh *m, size_t v, double x, double y, double z) {
    return m && v < m->nv && m->pos[3 * v] == x && m->pos[3 * v + 1] == y && m->pos[3 * v + 2] == z;
}

/* Every index in range and every coordinate finite. */
static int mesh_valid(const femlod_mesh *m) {
    for (size_t i = 0; i < 3 * m->nt; i++)
        if (m->tri[i] >= m->nv) return 0;
    for (size_t i = 0; i < 3 * m->nv; i++)
        if (!isfinite(m->pos[i])) return 0;
    return 1;
}

static int read_file(const char *path, char **data, size_t *size) {
    return fl_file_read_all(path, data, size, NULL) == FEMLOD_OK;
}

/* {====== format names */

static void test_format_names(void) {
    static const femlod_format all[] = {
        FEMLOD_FORMAT_OBJ, FEMLOD_FORMAT_STL, FEMLOD_FORMAT_STL_ASCII, FEMLOD_FORMAT_STL_BINARY,
        FEMLOD_FORMAT_OFF, FEMLOD_FORMAT_PLY, FEMLOD_FORMAT_PLY_ASCII, FEMLOD_FORMAT_PLY_BINARY,
        FEMLOD_FORMAT_GLTF, FEMLOD_FORMAT_GLB, FEMLOD_FORMAT_MSH, FEMLOD_FORMAT_MSH2,
        FEMLOD_FORMAT_VTK, FEMLOD_FORMAT_INP, FEMLOD_FORMAT_MEDIT};
    const char *const *names = femlod_format_names();
    for (size_t i = 0; i < sizeof all / sizeof all[0]; i++) {
        CHECK(femlod_format_from_name(femlod_format_name(all[i])) == all[i]);
        CHECK(names[i] && strcmp(names[i], femlod_format_name(all[i])) == 0);
    }
    CHECK(names[sizeof all / sizeof all[0]] == NULL);
    CHECK(strcmp(femlod_format_name(FEMLOD_FORMAT_STL_ASCII), "stl_ascii") == 0);
    CHECK(strcmp(femlod_format_name(FEMLOD_FORMAT_PLY_BINARY), "ply_binary") == 0);
    CHECK(femlod_format_from_name("gltf2") == FEMLOD_FORMAT_AUTO);
    CHECK(femlod_format_from_name(NULL) == FEMLOD_FORMAT_AUTO);
    CHECK(femlod_format_from_path("a/b/part.obj") == FEMLOD_FORMAT_OBJ);
    CHECK(femlod_format_from_path("PART.STL") == FEMLOD_FORMAT_STL);
    CHECK(femlod_format_from_path("x.Off") == FEMLOD_FORMAT_OFF);
    CHECK(femlod_format_from_path("scan.ply") == FEMLOD_FORMAT_PLY);
    CHECK(femlod_format_from_path("dir.obj/file") == FEMLOD_FORMAT_AUTO);
    CHECK(femlod_format_from_path("file") == FEMLOD_FORMAT_AUTO);
    CHECK(femlod_format_from_path("file.objx") == FEMLOD_FORMAT_AUTO);
    CHECK(femlod_format_from_path("mesh.msh") == FEMLOD_FORMAT_MSH);
    CHECK(femlod_format_from_path("a.VTK") == FEMLOD_FORMAT_VTK);
    CHECK(femlod_format_from_path("deck.inp") == FEMLOD_FORMAT_INP);
    CHECK(femlod_format_from_path("surf.mesh") == FEMLOD_FORMAT_MEDIT);
    CHECK(femlod_format_from_path("surf.smesh") == FEMLOD_FORMAT_AUTO);

    femlod_error err = {0, ""};
    femlod_mesh *m = NULL;
    CHECK(femlod_mesh_read(&m, "nowhere/mesh.xyz", NULL, &err) == FEMLOD_EINPUT);
    CHECK(m == NULL);
    CHECK_STR_HAS(err.message,
                  "mesh.xyz: unknown file extension; supported: .obj, .stl, .off, .ply, .gltf, .glb, "
                  ".msh, .vtk, .inp, .mesh (or give the format)");
    CHECK(femlod_mesh_read_memory(&m, "v 0 0 0", 7, NULL, NULL, &err) == FEMLOD_EINPUT);
    CHECK_STR_HAS(err.message, "(memory): unknown file extension");
    /* A name with a known extension is enough for memory reads. */
    CHECK(femlod_mesh_read_memory(&m, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", 32, "x.obj", NULL,
                                  &err) == FEMLOD_OK);
    CHECK(m && m->nt == 1);
    femlod_mesh_free(m);
    femlod_read_options bogus = {(femlod_format)99};
    m = NULL;
    CHECK(femlod_mesh_read(&m, "a.obj", &bogus, &err) == FEMLOD_EINPUT);
    CHECK(m == NULL);
}

/* }====== */

/* {====== numbers */

static void strtod_agrees(const char *s) {
    char *e1, *e2;
    double a = fl_strtod(s, &e1), b = strtod(s, &e2);
    int same = memcmp(&a, &b, sizeof a) == 0 && e1 == e2;
    CHECK(same);
    if (!same)
        fprintf(stderr, "  fl_strtod(\"%s\") = %.17g (end %td), strtod %.17g (end %td)\n", s, a,
                e1 - s, b, e2 - s);
}

/* Significant digits of a printed number: sign, exponent, point, leading and
 * trailing zeros not counted. */
static int significant_digits(const char *s) {
    char d[64];
    int n = 0;
    for (const char *p = s; *p && *p != 'e'; p++)
        if (*p >= '0' && *p <= '9' && n < 63) d[n++] = *p;
    int lo = 0, hi = n;
    while (lo < hi && d[lo] == '0') lo++;
    while (hi > lo && d[hi - 1] == '0') hi--;
    return hi > lo ? hi - lo : 1;
}

static int shortest_digits(double x) {
    char buf[64];
    for (int p = 1; p <= 17; p++) {
        snprintf(buf, sizeof buf, "%.*g", p, x);
        if (strtod(buf, NULL) == x) return p;
    }
    return 17;
}

static void format_is(double x, const char *want) {
    char buf[40];
    int n = fl_format_double(buf, sizeof buf, x);
    CHECK(n == (int)strlen(want) && strcmp(buf, want) == 0);
    if (strcmp(buf, want) != 0)
        fprintf(stderr, "  fl_format_double(%.17g) = \"%s\", want \"%s\"\n", x, buf, want);
}

static void test_numbers(void) {
    /* Fast path, slow path, and every way the end can fall. */
    static const char *const cases[] = {"0",
                                        "-0",
                                        "+1",
                                        "1.5",
                                        "0.1",
                                        ".5",
                                        "5.",
                                        "1e5",
                                        "1E+5",
                                        "1e-5",
                                        "1e",
                                        "1e+",
                                        "1.e3",
                                        ".e3",
                                        ".",
                                        "-",
                                        "",
                                        "  1",
                                        "1.5abc",
                                        "0x1p3",
                                        "00012.50",
                                        "123456789012345678901234",
                                        "9007199254740993",
                                        "9007199254740992.5",
                                        "1e23",
                                        "8.98846567431158e307",
                                        "1.7976931348623157e308",
                                        "1.7976931348623159e308",
                                        "1e309",
                                        "1e-400",
                                        "4.9e-324",
                                        "2.2250738585072011e-308",
                                        "2.2250738585072014e-308",
                                        "0.30000000000000004",
                                        "1e22",
                                        "1e30",
                                        "123456e30",
                                        "0.000000000000000000000000000001",
                                        "1e0000000000000000005",
                                        "3.14159265358979323846264338327950288",
                                        "1e-22",
                                        "7e-23",
                                        "inf",
                                        "-Infinity",
                                        "nan",
                                        "NaN(123)",
                                        "nan(",
                                        "infin",
                                        "1,5",
                                        "2.5e+999999999999"};
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        const char *s = cases[i];
        char *e1, *e2;
        double a = fl_strtod(s, &e1), b = strtod(s, &e2);
        if (strstr(s, "0x")) { /* hex is not a mesh number: stops after the "0" */
            CHECK(a == 0.0 && e1 == s + 1);
            continue;
        }
        if (isnan(b)) {
            CHECK(isnan(a) && e1 == e2);
            continue;
        }
        strtod_agrees(s);
    }
    /* Random decimals of every length, and printed doubles at several precisions. */
    char buf[96];
    for (int i = 0; i < 30000; i++) {
        uint64_t r = rng();
        int nd = 1 + (int)(r % 25), dot = (int)((r >> 8) % (uint64_t)(nd + 1));
        int n = 0;
        if ((r >> 16) & 1) buf[n++] = '-';
        for (int k = 0; k < nd; k++) {
            if (k == dot) buf[n++] = '.';
            buf[n++] = (char)('0' + rng() % 10);
        }
        if ((r >> 17) & 1)
            n += snprintf(buf + n, sizeof buf - (size_t)n, "e%d", (int)((r >> 20) % 700) - 350);
        buf[n] = '\0';
        strtod_agrees(buf);
    }
    for (int i = 0; i < 30000; i++) {
        uint64_t bits = rng();
        double x;
        memcpy(&x, &bits, sizeof x);
        if (!isfinite(x)) continue;
        static const int precision[] = {17, 16, 15, 6};
        if (i % 5 == 4)
            snprintf(buf, sizeof buf, "%.30e", x);
        else
            snprintf(buf, sizeof buf, "%.*g", precision[i % 5], x);
        strtod_agrees(buf);
        /* Shortest round trip, checked by brute force. */
        char out[40];
        int n = fl_format_double(out, sizeof out, x);
        char *e;
        double back = fl_strtod(out, &e);
        int ok = n > 0 && memcmp(&back, &x, sizeof x) == 0 && *e == '\0';
        CHECK(ok);
        int sd = significant_digits(out), want = shortest_digits(x);
        CHECK(sd == want);
        /* Spelled as printf's %.{shortest}g, or as a plain integer below 1e15. */
        char ref[40];
        snprintf(ref, sizeof ref, "%.*g", want, x);
        CHECK(strcmp(out, ref) == 0 || (fabs(x) < 1e15 && x == floor(x) && !strpbrk(out, ".e")));
        if (!ok || sd != want)
            fprintf(stderr, "  fl_format_double(%.17g) = \"%s\" (%d digits, shortest %d)\n", x, out,
                    sd, want);
        /* Small values, the kind meshes hold. */
        double y = (double)(int64_t)(rng() % 2000001 - 1000000) / 1000.0;
        n = fl_format_double(out, sizeof out, y);
        CHECK(n > 0 && fl_strtod(out, &e) == y && significant_digits(out) == shortest_digits(y));
    }
    format_is(0.1, "0.1");
    format_is(100.0, "100");
    format_is(-2.5, "-2.5");
    format_is(1e16, "1e+16");
    format_is(123456789012345.0, "123456789012345");
    format_is(-4096.0, "-4096");
    format_is(1e17, "1e+17");
    format_is(1e21, "1e+21");
    format_is(1e-5, "1e-05");
    format_is(0.0001, "0.0001");
    format_is(-0.0, "-0");
    format_is(0.0, "0");
    format_is(1.0 / 3.0, "0.3333333333333333");
    format_is(0.1 + 0.2, "0.30000000000000004");
    format_is(5e-324, "5e-324");
    format_is(DBL_MAX, "1.7976931348623157e+308");
    format_is(2.2250738585072014e-308, "2.2250738585072014e-308");
    format_is((double)(float)0.1, "0.10000000149011612");
    char small[8];
    CHECK(fl_format_double(small, sizeof small, 0.1 + 0.2) == -1 && small[0] == '\0');
    CHECK(fl_format_double(small, sizeof small, 0.5) == 3 && strcmp(small, "0.5") == 0);

    /* fl_io_coord: the readers' shared number check. */
    char why[128];
    double x = 7;
    CHECK(fl_io_coord("1.25", 4, &x, why, sizeof why) && x == 1.25);
    CHECK(!fl_io_coord("1.25x", 5, &x, why, sizeof why));
    CHECK_STR_HAS(why, "bad number '1.25x'");
    CHECK(!fl_io_coord("1.25", 3, &x, why, sizeof why)); /* the token ends before the number */
    CHECK(!fl_io_coord("-inf", 4, &x, why, sizeof why));
    CHECK_STR_HAS(why, "coordinate '-inf' is not finite");
    CHECK(!fl_io_coord("NAN", 3, &x, why, sizeof why));
    CHECK_STR_HAS(why, "coordinate 'NAN' is not finite");
    CHECK(!fl_io_coord("-1e400", 6, &x, why, sizeof why));
    CHECK_STR_HAS(why, "coordinate '-1e400' is out of range");
    CHECK(fl_io_coord("1e-400", 6, &x, why, sizeof why) && x == 0.0); /* underflow is a value */
    char q[48];
    CHECK(strcmp(fl_io_quote(q, sizeof q, "a\tb\x01\xff", 5), "a?b??") == 0);
    CHECK(strlen(fl_io_quote(q, sizeof q, "0123456789012345678901234567890123456789012345", 46)) ==
          43);
    CHECK_STR_HAS(q, "...");
}

/* }====== */

/* {====== reference files */

static void reference(const char *file, size_t nt, size_t nv) {
    char p[512];
    femlod_mesh *m = read_ok(path_in(p, sizeof p, FEMLOD_SHARED_DATA, file), FEMLOD_FORMAT_AUTO);
    CHECK(m && femlod_mesh_triangle_count(m) == nt);
    CHECK(m && femlod_mesh_vertex_count(m) == nv);
    if (m && (m->nt != nt || m->nv != nv))
        fprintf(stderr, "  %s: %zu triangles, %zu vertices; want %zu, %zu\n", file, m->nt, m->nv,
                nt, nv);
    if (m) CHECK(mesh_valid(m));
    femlod_mesh_free(m);
}

static void test_reference_files(void) {
    reference("sphereWithHole.stl", 285, 146);
    reference("spider_binary.stl", 1368, 722);
    reference("fandisk.obj", 12946, 6475);
    reference("cover.obj", 77874, 38913);
    reference("bunny.obj", 75408, 37706);

    char p[512];
    femlod_mesh *m =
        read_ok(path_in(p, sizeof p, FEMLOD_SHARED_DATA, "spider_binary.stl"), FEMLOD_FORMAT_AUTO);
    double lo[3], hi[3];
    if (m) {
        femlod_mesh_bbox(m, lo, hi);
        CHECK_NEAR(lo[0], -3.11489, 1e-5);
        CHECK_NEAR(hi[1], 4.0, 1e-9);
        CHECK_NEAR(hi[2], 1.64933, 1e-5);
        /* The file's own corners, welded in order of first appearance. */
        CHECK(m->tri[0] == 0 && m->tri[1] == 1 && m->tri[2] == 2);
    }
    femlod_mesh_free(m);
    m = read_ok(path_in(p, sizeof p, FEMLOD_SHARED_DATA, "cover.obj"), FEMLOD_FORMAT_AUTO);
    if (m) {
        CHECK(pos_is(m, 0, 32, 28, 0.8)); /* "v 32 28 0.8", the first vertex line */
        femlod_mesh_bbox(m, lo, hi);
        CHECK(lo[0] == 0 && lo[1] == 0 && lo[2] == 0);
        CHECK(hi[0] == 101.2 && hi[1] == 145.6 && hi[2] == 4.9);
    }
    femlod_mesh_free(m);
}

/* }====== */

/* {====== good inputs, feature by feature */

/* The OBJ reader parses coordinates and vertex references straight from
 * its buffer when they end a token, and through the token checks otherwise
 * (io_obj.c at_token_end). Either way a coordinate is strtod's double in
 * the "C" locale: 2,000 numbers written in ten forms, some lines joined by
 * a continuation inside them, read back bit for bit; references in all four
 * forms next to tokens that merely start like one. */
static void number_form(char *buf, size_t size, int form, double x) {
    switch (form) {
    case 0: snprintf(buf, size, "%.17g", x); break;
    case 1: snprintf(buf, size, "%.6f", x); break;
    case 2: snprintf(buf, size, "%.9e", x); break;
    case 3: snprintf(buf, size, "%+.3f", x); break;
    case 4: snprintf(buf, size, "%.15g", x); break;
    case 5: snprintf(buf, size, "%.1f", x); break;
    case 6: snprintf(buf, size, "%.0f.", x); break;
    case 7: snprintf(buf, size, "%.8E", x); break;
    case 8: snprintf(buf, size, "%.12g", x); break;
    default: snprintf(buf, size, "%.20f", x); break;
    }
}

static void test_obj_numbers_exact(void) {
    enum { NV = 2000 };
    size_t cap = (size_t)NV * 240;
    char *txt = malloc(cap);
    static char nums[NV][3][64];
    CHECK(txt != NULL);
    if (!txt) return;
    size_t at = 0;
    for (int i = 0; i < NV; i++) {
        at += (size_t)snprintf(txt + at, cap - at, "v");
        for (int k = 0; k < 3; k++) {
            uint64_t r = rng();
            double x = (double)(r >> 11) * 0x1p-53 * 2000.0 - 1000.0;
            if (r % 17 == 0) x = ldexp(x, (int)(r % 120) - 60);
            number_form(nums[i][k], sizeof nums[i][k], (int)((r >> 3) % 10), x);
            if (nums[i][k][0] == '.') nums[i][k][0] = '0'; /* "%.0f." of 0 is "0." */
            at += (size_t)snprintf(txt + at, cap - at, "%s%s", i % 7 == 3 && k == 2 ? " \\\n " : " ",
                                   nums[i][k]);
        }
        at += (size_t)snprintf(txt + at, cap - at, "\n");
    }
    snprintf(txt + at, cap - at, "f 1 2/5 3//7\nf 4/1/2 -1 5/6\n");
    femlod_mesh *m = mem_ok(txt, FEMLOD_FORMAT_OBJ);
    CHECK(m && m->nv == NV && m->nt == 2);
    if (m && m->nv == NV) {
        int same = 1;
        for (int i = 0; i < NV; i++)
            for (int k = 0; k < 3; k++) {
                double want = strtod(nums[i][k], NULL), got = m->pos[3 * i + k];
                if (memcmp(&want, &got, sizeof want) != 0) {
                    if (same) fprintf(stderr, "  %s read as %.17g\n", nums[i][k], got);
                    same = 0;
                }
            }
        CHECK(same);
        CHECK(tri_is(m, 0, 0, 1, 2) && tri_is(m, 1, 3, NV - 1, 4));
    }
    femlod_mesh_free(m);
    free(txt);
    /* Tokens that start like a number or a reference and go on are refused
     * with the whole token named, as before the fast paths. */
    mem_bad("v 1 2 3x\n", FEMLOD_FORMAT_OBJ, FEMLOD_EPARSE, "mem:1: bad number '3x'");
    mem_bad("v 1 2 3\\x 4\n", FEMLOD_FORMAT_OBJ, FEMLOD_EPARSE, "mem:1: bad number '3\\x'");
    mem_bad("v 1 2 0x1p3\n", FEMLOD_FORMAT_OBJ, FEMLOD_EPARSE, "mem:1: bad number '0x1p3'");
    mem_bad("v 1 2 1e999\n", FEMLOD_FORMAT_OBJ, FEMLOD_EPARSE,
            "mem:1: coordinate '1e999' is out of range");
    mem_bad("v 1 2 nan\n", FEMLOD_FORMAT_OBJ, FEMLOD_EPARSE, "mem:1: coordinate 'nan' is not finite");
    mem_bad("v 1 2 3#c\n", FEMLOD_FORMAT_OBJ, FEMLOD_EPARSE, "mem:1: bad number '3#c'");
    mem_bad("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3/\n", FEMLOD_FORMAT_OBJ, FEMLOD_EPARSE,
            "mem:4: bad face vertex '3/'");
    mem_bad("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3//\n", FEMLOD_FORMAT_OBJ, FEMLOD_EPARSE,
            "mem:4: bad face vertex '3//'");
    mem_bad("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3/4/5/6\n", FEMLOD_FORMAT_OBJ, FEMLOD_EPARSE,
            "mem:4: bad face vertex '3/4/5/6'");
    mem_bad("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3a\n", FEMLOD_FORMAT_OBJ, FEMLOD_EPARSE,
            "mem:4: bad face vertex '3a'");
}

static void test_obj(void) {
    char p[512];
    femlod_mesh *m =
        read_ok(path_in(p, sizeof p, FEMLOD_TEST_DATA, "quads.obj"), FEMLOD_FORMAT_AUTO);
    CHECK(m && m->nv == 5 && m->nt == 4);
    CHECK(pos_is(m, 2, 1, 1, 0) && pos_is(m, 4, 0.5, 0.5, 1));
    CHECK(tri_is(m, 0, 0, 1, 2) && tri_is(m, 1, 0, 2, 3)); /* the quad's fan */
    CHECK(tri_is(m, 2, 0, 1, 4));                          /* f -5//1 -4//1 -1//1 */
    CHECK(tri_is(m, 3, 1, 2, 4));                          /* f -4/2 -3/3 -1/1 */
    femlod_mesh_free(m);

    m = read_ok(path_in(p, sizeof p, FEMLOD_TEST_DATA, "crlf_continuation.obj"), FEMLOD_FORMAT_OBJ);
    CHECK(m && m->nv == 3 && m->nt == 1);
    CHECK(pos_is(m, 1, 1, 0, 0) && pos_is(m, 2, 0, 1, 0) && tri_is(m, 0, 0, 1, 2));
    femlod_mesh_free(m);

    /* Relative indices count the vertices read so far, not all of them. */
    m = mem_ok("v 0 0 0\nv 1 0 0\nv 0 1 0\nf -3 -2 -1\nv 5 5 5\nf -4 -3 -1\n", FEMLOD_FORMAT_OBJ);
    CHECK(m && tri_is(m, 0, 0, 1, 2) && tri_is(m, 1, 0, 1, 3));
    femlod_mesh_free(m);
    /* Forward references are legal once the vertex exists; polygons fan from
     * their first corner; a pentagon gives three triangles. */
    m = mem_ok("f 1 2 3 4 5\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv -1 0.5 0\n", FEMLOD_FORMAT_OBJ);
    CHECK(m && m->nt == 3 && tri_is(m, 0, 0, 1, 2) && tri_is(m, 1, 0, 2, 3) &&
          tri_is(m, 2, 0, 3, 4));
    femlod_mesh_free(m);
    /* Degenerate and duplicate faces stay; vertices are never welded. */
    m = mem_ok("v 0 0 0\nv 0 0 0\nv 1 0 0\nf 1 1 3\nf 1 2 3\nf 1 2 3\n", FEMLOD_FORMAT_OBJ);
    CHECK(m && m->nv == 3 && m->nt == 3 && tri_is(m, 0, 0, 0, 2) && tri_is(m, 2, 0, 1, 2));
    femlod_mesh_free(m);
    /* Inline comments, "fo", colours after the position, a vertex with w,
     * tabs and vertical tabs, a final line without newline, a lone \ at the end. */
    m = mem_ok("v 1 2 3 # a comment\nv\t4\v5\f6 0.5 0.5 0.5\nv 7 8 9 1\nfo 1 2 3 \\",
               FEMLOD_FORMAT_OBJ);
    CHECK(m && m->nv == 3 && m->nt == 1 && pos_is(m, 1, 4, 5, 6) && pos_is(m, 2, 7, 8, 9));
    femlod_mesh_free(m);
    /* Vertices only, and only comments: valid meshes without triangles. */
    m = mem_ok("v 1 2 3\n", FEMLOD_FORMAT_OBJ);
    CHECK(m && m->nv == 1 && m->nt == 0);
    femlod_mesh_free(m);
    m = mem_ok("# femlod 0.1.0\n", FEMLOD_FORMAT_OBJ);
    CHECK(m && m->nv == 0 && m->nt == 0);
    femlod_mesh_free(m);
    /* Exact decimal conversion. */
    m = mem_ok("v 0.1 -0 1e-310\nv 1.7976931348623157e308 2.5e-3 -7\nv 0 0 0\nf 1 2 3\n",
               FEMLOD_FORMAT_OBJ);
    CHECK(m && m->pos[0] == 0.1 && signbit(m->pos[1]) && m->pos[2] == 1e-310 &&
          m->pos[3] == DBL_MAX && m->pos[4] == 2.5e-3);
    femlod_mesh_free(m);

    mem_bad("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 99999999999\n", FEMLOD_FORMAT_OBJ, FEMLOD_EPARSE,
            "mem:4: face index 99999999999 out of range (3 vertices so far)");
    mem_bad("v 1 2 3 4 5 6 7 8\n", FEMLOD_FORMAT_OBJ, FEMLOD_EPARSE,
            "mem:1: too many values on a 'v' line");
    mem_bad("v 1 2 3 x\n", FEMLOD_FORMAT_OBJ, FEMLOD_EPARSE, "mem:1: bad number 'x'");
    mem_bad("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2/ 3\n", FEMLOD_FORMAT_OBJ, FEMLOD_EPARSE,
            "mem:4: bad face vertex '2/'");
    mem_bad("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 /2 3\n", FEMLOD_FORMAT_OBJ, FEMLOD_EPARSE,
            "mem:4: bad face vertex '/2'");
    mem_bad("v 0 0 0\nv 1 0 0\nv 0 1 0\nf\n", FEMLOD_FORMAT_OBJ, FEMLOD_EPARSE,
            "mem:4: face has 0 vertices (at least 3 needed)");
    /* Errors on continued lines name the line they are on; short faces name their first line. */
    mem_bad("v 0 0 \\\n 0\nv 1 \\\n 0 q\n", FEMLOD_FORMAT_OBJ, FEMLOD_EPARSE,
            "mem:4: bad number 'q'");
    mem_bad("v 0 0 0\nv 1 0 0\nf 1 \\\n 2\n", FEMLOD_FORMAT_OBJ, FEMLOD_EPARSE,
            "mem:3: face has 2 vertices");
    mem_bad("   \n\t\n", FEMLOD_FORMAT_OBJ, FEMLOD_EPARSE, "mem: empty file");
}

static void test_stl(void) {
    char p[512];
    /* Binary with a "solid" header: the size decides. */
    femlod_mesh *bin =
        read_ok(path_in(p, sizeof p, FEMLOD_TEST_DATA, "solid_header.stl"), FEMLOD_FORMAT_AUTO);
    CHECK(bin && bin->nv == 4 && bin->nt == 4);
    CHECK(pos_is(bin, 0, 0, 0, 0) && pos_is(bin, 1, 0, 1, 0) && pos_is(bin, 2, 1, 0, 0));
    CHECK(tri_is(bin, 0, 0, 1, 2) && tri_is(bin, 3, 2, 1, 3));
    femlod_mesh *asc =
        read_ok(path_in(p, sizeof p, FEMLOD_TEST_DATA, "tetra_ascii.stl"), FEMLOD_FORMAT_AUTO);
    CHECK(shape_same_mesh(bin, asc));
    /* BOM, CRLF, upper-case keywords, nan normals, two solids in one file. */
    femlod_mesh *two = read_ok(path_in(p, sizeof p, FEMLOD_TEST_DATA, "tetra_bom_two_solids.stl"),
                               FEMLOD_FORMAT_STL);
    CHECK(shape_same_mesh(bin, two));
    femlod_mesh_free(two);
    femlod_mesh_free(asc);
    femlod_mesh_free(bin);

    /* Forcing the wrong encoding fails cleanly. */
    femlod_read_options o = {FEMLOD_FORMAT_STL_BINARY};
    femlod_error err = {0, ""};
    femlod_mesh *m = NULL;
    CHECK(femlod_mesh_read(&m, path_in(p, sizeof p, FEMLOD_TEST_DATA, "tetra_ascii.stl"), &o,
                           &err) == FEMLOD_EPARSE &&
          m == NULL);
    CHECK_STR_HAS(err.message, "tetra_ascii.stl: byte 80: declared ");
    o.format = FEMLOD_FORMAT_STL_ASCII;
    CHECK(femlod_mesh_read(&m, path_in(p, sizeof p, FEMLOD_TEST_DATA, "solid_header.stl"), &o,
                           &err) == FEMLOD_EPARSE &&
          m == NULL);
    CHECK_STR_HAS(err.message, "solid_header.stl:");

    /* Welding: equal positions merge, -0.0 == 0.0; degenerate and duplicate
     * triangles stay. */
    m = mem_ok("solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\n"
               "endloop\nendfacet\nfacet normal 0 0 1\nouter loop\nvertex 1 0 0\nvertex 1 1 0\n"
               "vertex -0 1 -0\nendloop\nendfacet\nfacet normal 0 0 0\nouter loop\nvertex 1 0 0\n"
               "vertex 1 0 0\nvertex 1 1 0\nendloop\nendfacet\nfacet normal 0 0 1\nouter loop\n"
               "vertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\nendfacet\nendsolid t",
               FEMLOD_FORMAT_STL);
    CHECK(m && m->nv == 4 && m->nt == 4);
    CHECK(tri_is(m, 1, 1, 3, 2) && tri_is(m, 2, 1, 1, 3) && tri_is(m, 3, 0, 1, 2));
    femlod_mesh_free(m);
    /* A whole file on one line, and a solid named like a keyword's neighbour. */
    m = mem_ok("solid one facet normal 0 0 1 outer loop vertex 0 0 0 vertex 1 0 0 vertex 0 1 0 "
               "endloop endfacet endsolid one solid two words\nendsolid",
               FEMLOD_FORMAT_STL);
    CHECK(m && m->nv == 3 && m->nt == 1 && tri_is(m, 0, 0, 1, 2));
    femlod_mesh_free(m);
    /* An empty solid and an empty binary file are empty meshes. */
    m = mem_ok("solid empty\nendsolid empty\n", FEMLOD_FORMAT_STL);
    CHECK(m && m->nv == 0 && m->nt == 0);
    femlod_mesh_free(m);
    unsigned char empty_bin[84];
    memset(empty_bin, 0, sizeof empty_bin);
    m = NULL;
    CHECK(femlod_mesh_read_memory(&m, empty_bin, sizeof empty_bin, "e.stl", NULL, &err) ==
              FEMLOD_OK &&
          m && m->nt == 0);
    femlod_mesh_free(m);
    /* A text file that lacks "solid" is parsed as text, whatever its size. */
    mem_bad("facet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\n"
            "endfacet\n",
            FEMLOD_FORMAT_STL, FEMLOD_EPARSE, "mem:1: expected 'solid', found 'facet'");
    mem_bad("solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1\n"
            "endloop\n",
            FEMLOD_FORMAT_STL, FEMLOD_EPARSE, "mem:7: bad number 'endloop'");
    mem_bad("solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\n",
            FEMLOD_FORMAT_STL, FEMLOD_EPARSE,
            "mem:5: expected 'vertex', found the end of the file");
}

/* The binary STL reader welds corners straight from its records (io_stl.c
 * weld_binary); the ASCII reader through fl_mesh_from_soup. The same corners
 * in both forms must give the same mesh, bit for bit: 3,000 triangles whose
 * corners are drawn from 6,000 float positions (many recur, near their first
 * use or far from it, some as -0.0 where another is +0.0), with more than
 * 4,096 distinct positions, so that the binary reader's table (4,096 slots
 * for 3,000 triangles, kept at most half full) grows twice. */
static void test_stl_weld_binary_as_ascii(void) {
    enum { NT = 3000, NP = 6000 };
    static float pts[NP][3];
    for (int i = 0; i < NP; i++)
        for (int k = 0; k < 3; k++) {
            uint64_t r = rng();
            pts[i][k] = (r & 7) == 0 ? 0.0f : (float)((double)(r >> 11) * 0x1p-53 * 200.0 - 100.0);
        }
    size_t bsize = 84 + 50 * (size_t)NT, asize = 64 + (size_t)NT * 400;
    unsigned char *bin = calloc(bsize, 1);
    char *txt = malloc(asize);
    CHECK(bin && txt);
    if (!bin || !txt) {
        free(bin);
        free(txt);
        return;
    }
    uint32_t n = NT;
    memcpy(bin + 80, &n, 4);
    size_t at = (size_t)snprintf(txt, asize, "solid w\n");
    for (int t = 0; t < NT; t++) {
        at += (size_t)snprintf(txt + at, asize - at, "facet normal 0 0 1\nouter loop\n");
        for (int c = 0; c < 3; c++) {
            /* half the corners recur near their first use, the rest anywhere */
            int i = (int)(t % 2 ? rng() % NP : ((uint64_t)t * 3 + (uint64_t)c) % NP);
            float v[3] = {pts[i][0], pts[i][1], pts[i][2]};
            for (int k = 0; k < 3; k++)
                if (v[k] == 0.0f && (rng() & 1)) v[k] = -0.0f;
            memcpy(bin + 84 + 50 * (size_t)t + 12 + 12 * (size_t)c, v, 12);
            at += (size_t)snprintf(txt + at, asize - at, "vertex %.17g %.17g %.17g\n", (double)v[0],
                                   (double)v[1], (double)v[2]);
        }
        at += (size_t)snprintf(txt + at, asize - at, "endloop\nendfacet\n");
    }
    snprintf(txt + at, asize - at, "endsolid w\n");
    femlod_mesh *a = mem_ok(txt, FEMLOD_FORMAT_STL_ASCII), *b = NULL;
    femlod_error err;
    femlod_read_options o = {FEMLOD_FORMAT_STL_BINARY};
    CHECK(femlod_mesh_read_memory(&b, bin, bsize, "w.stl", &o, &err) == FEMLOD_OK);
    CHECK(a && b && a->nt == NT && b->nt == NT && a->nv == b->nv && a->nv > 4096 &&
          a->nv < 3 * NT);
    if (a && b && a->nv == b->nv && a->nt == b->nt) {
        CHECK(memcmp(a->pos, b->pos, 3 * a->nv * sizeof(double)) == 0);
        CHECK(memcmp(a->tri, b->tri, 3 * a->nt * sizeof(uint32_t)) == 0);
        int neg_zero = 0;
        for (size_t i = 0; i < 3 * b->nv; i++) neg_zero += b->pos[i] == 0.0 && signbit(b->pos[i]);
        CHECK(neg_zero == 0);
    }
    femlod_mesh_free(a);
    femlod_mesh_free(b);
    free(bin);
    free(txt);
}

static void test_off(void) {
    char p[512];
    femlod_mesh *m =
        read_ok(path_in(p, sizeof p, FEMLOD_TEST_DATA, "tetra.off"), FEMLOD_FORMAT_AUTO);
    CHECK(m && m->nv == 4 && m->nt == 4 && pos_is(m, 3, 0, 0, 1));
    CHECK(tri_is(m, 0, 0, 2, 1) && tri_is(m, 3, 1, 2, 3));
    femlod_mesh_free(m);
    m = read_ok(path_in(p, sizeof p, FEMLOD_TEST_DATA, "square_colors.off"), FEMLOD_FORMAT_OFF);
    CHECK(m && m->nv == 6 && m->nt == 5 && pos_is(m, 5, 2, 1.5, 0));
    CHECK(tri_is(m, 0, 0, 1, 2) && tri_is(m, 1, 0, 2, 3));                          /* quad */
    CHECK(tri_is(m, 2, 1, 4, 5) && tri_is(m, 3, 1, 5, 2) && tri_is(m, 4, 1, 2, 2)); /* pentagon */
    femlod_mesh_free(m);
    m = mem_ok("NOFF\n3 1 0\n0 0 0 0 0 1\n1 0 0 0 0 1\n0 1 0 0 0 1\n3 0 1 2\n", FEMLOD_FORMAT_OFF);
    CHECK(m && m->nv == 3 && m->nt == 1);
    femlod_mesh_free(m);
    m = mem_ok("OFF\n0 0 0\n", FEMLOD_FORMAT_OFF);
    CHECK(m && m->nv == 0 && m->nt == 0);
    femlod_mesh_free(m);
    mem_bad("OFF\n3 1 0\n0.0 0.0 0.0\n1.0 0.0 0.0\n0.0 1.0 0.0\n3 0 1\n", FEMLOD_FORMAT_OFF,
            FEMLOD_EPARSE, "mem:6: file ends inside face 1 (2 of 3 indices)");
    mem_bad("4OFF\n", FEMLOD_FORMAT_OFF, FEMLOD_EUNSUPPORTED, "mem:1: '4OFF': only 3-dimensional");
    mem_bad("OFF\n3 x 0\n", FEMLOD_FORMAT_OFF, FEMLOD_EPARSE, "mem:2: bad face count 'x'");
    mem_bad("OFF\n3 1\n", FEMLOD_FORMAT_OFF, FEMLOD_EPARSE,
            "mem:2: expected the edge count, found the end of the file");
}

static void test_ply(void) {
    char p[512];
    femlod_mesh *m =
        read_ok(path_in(p, sizeof p, FEMLOD_TEST_DATA, "ascii_extra.ply"), FEMLOD_FORMAT_AUTO);
    CHECK(m && m->nv == 4 && m->nt == 3);
    CHECK(pos_is(m, 0, 0, 0, 0) && pos_is(m, 1, 1, 0, 0) && pos_is(m, 2, 1, 1, 0) &&
          pos_is(m, 3, 0.5, 1.5, 7));
    CHECK(tri_is(m, 0, 0, 1, 2) && tri_is(m, 1, 0, 2, 3) && tri_is(m, 2, 2, 3, 0));
    femlod_mesh_free(m);
    femlod_mesh *le =
        read_ok(path_in(p, sizeof p, FEMLOD_TEST_DATA, "binary_le.ply"), FEMLOD_FORMAT_PLY);
    femlod_mesh *be = read_ok(path_in(p, sizeof p, FEMLOD_TEST_DATA, "binary_be.ply"),
                              FEMLOD_FORMAT_PLY_ASCII); /* the file's own encoding wins */
    femlod_mesh *off =
        read_ok(path_in(p, sizeof p, FEMLOD_TEST_DATA, "tetra.off"), FEMLOD_FORMAT_OFF);
    CHECK(shape_same_mesh(le, off) && shape_same_mesh(be, off));
    femlod_mesh_free(le);
    femlod_mesh_free(be);
    femlod_mesh_free(off);
    /* Point clouds (no face element) are meshes without triangles. */
    m = mem_ok("ply\r\nformat ascii 1.0\r\nelement vertex 2\r\nproperty int x\r\nproperty int y\r\n"
               "property int z\r\nend_header\r\n1 2 3\r\n-4 5 6\r\n",
               FEMLOD_FORMAT_PLY);
    CHECK(m && m->nv == 2 && m->nt == 0 && pos_is(m, 1, -4, 5, 6));
    femlod_mesh_free(m);
    mem_bad("ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
            "property float z\nend_header\n0.0 0.0\n",
            FEMLOD_FORMAT_PLY, FEMLOD_EPARSE,
            "mem:8: file ends inside element 'vertex' (item 1 of 1)");
    mem_bad("ply\nformat ascii 2.0\n", FEMLOD_FORMAT_PLY, FEMLOD_EUNSUPPORTED,
            "mem:2: unsupported PLY version '2.0'");
    mem_bad("ply\nformat ascii 1.0\nproperty float x\n", FEMLOD_FORMAT_PLY, FEMLOD_EPARSE,
            "mem:3: property before any element");
    mem_bad("ply\nformat ascii 1.0\nelement vertex 1\nproperty float128 x\n", FEMLOD_FORMAT_PLY,
            FEMLOD_EPARSE, "mem:4: unknown type 'float128'");
    mem_bad(
        "ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\n"
        "property float z\nelement face 0\nproperty list float int vertex_indices\nend_header\n",
        FEMLOD_FORMAT_PLY, FEMLOD_EUNSUPPORTED, "mem:8: list count type 'float'");
    mem_bad("ply\nformat ascii 1.0\nelement face 0\nproperty list uchar int vertex_indices\n"
            "end_header\n",
            FEMLOD_FORMAT_PLY, FEMLOD_EPARSE, "mem:5: no element 'vertex' in the header");
    mem_bad("ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
            "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
            "0 0 0\n300 0 0 0\n",
            FEMLOD_FORMAT_PLY, FEMLOD_EPARSE, "mem:11: bad list count '300'");
    mem_bad("ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
            "property float x\n",
            FEMLOD_FORMAT_PLY, FEMLOD_EPARSE, "mem:6: duplicate property 'x'");
    mem_bad("ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
            "property float z\nend_header\n0 0 0\n9\n",
            FEMLOD_FORMAT_PLY, FEMLOD_EPARSE, "mem:9: data after the last element: '9'");
    mem_bad("ply\nformat ascii 1.0\nelement tristrips 1\nproperty list int int vertex_indices\n"
            "end_header\n",
            FEMLOD_FORMAT_PLY, FEMLOD_EUNSUPPORTED, "mem:3: triangle strips are not supported");
}

/* }====== */

/* {====== bad files: one specific error each */

typedef struct bad_case {
    const char *file;
    femlod_status status;
    const char *message; /* follows the file name */
} bad_case;

static const bad_case bad_cases[] = {
    /* OBJ */
    {"index0.obj", FEMLOD_EPARSE, ":4: face index 0 is invalid (OBJ indices start at 1)"},
    {"index_range.obj", FEMLOD_EPARSE, ":6: face index 9 out of range (4 vertices)"},
    {"relative_before_first.obj", FEMLOD_EPARSE,
     ":4: face index -5 out of range (3 vertices so far)"},
    {"forward_range.obj", FEMLOD_EPARSE, ":2: face index 5 out of range (4 vertices)"},
    {"face_two_vertices.obj", FEMLOD_EPARSE, ":5: face has 2 vertices (at least 3 needed)"},
    {"coord_nan.obj", FEMLOD_EPARSE, ":2: coordinate 'nan' is not finite"},
    {"coord_inf.obj", FEMLOD_EPARSE, ":2: coordinate '-inf' is not finite"},
    {"coord_1e999.obj", FEMLOD_EPARSE, ":2: coordinate '1e999' is out of range"},
    {"coord_hex.obj", FEMLOD_EPARSE, ":1: bad number '0x1p3'"},
    {"garbage_token.obj", FEMLOD_EPARSE, ":2: bad number 'abc'"},
    {"bad_face_vertex.obj", FEMLOD_EPARSE, ":5: bad face vertex '1/1/1/1'"},
    {"unknown_statement.obj", FEMLOD_EPARSE, ":5: unknown statement 'vertex'"},
    {"missing_coordinate.obj", FEMLOD_EPARSE, ":1: vertex has 2 coordinates (3 needed)"},
    {"empty.obj", FEMLOD_EPARSE, ": empty file"},
    {"binary_garbage.obj", FEMLOD_EPARSE, ":1: unknown statement '"},
    /* STL */
    {"truncated.stl", FEMLOD_EPARSE,
     ": byte 80: declared 4 triangles, file holds 3 (and 10 extra bytes"},
    {"count_overflow.stl", FEMLOD_EPARSE, ": byte 80: declared 4294967295 triangles, file holds 0"},
    {"count_overflow_data.stl", FEMLOD_EPARSE,
     ": byte 80: declared 4294967295 triangles, file holds 4"},
    {"garbage.stl", FEMLOD_EPARSE, ": byte 80: declared 2164095735 triangles, file holds 18"},
    {"garbage_short.stl", FEMLOD_EPARSE, ": byte 0: not an STL file (60 bytes"},
    {"binary_nan.stl", FEMLOD_EPARSE, ": byte 212: triangle 3: coordinate is not finite (nan)"},
    {"empty.stl", FEMLOD_EPARSE, ": empty file"},
    {"ascii_missing_endloop.stl", FEMLOD_EPARSE, ":7: expected 'endloop', found 'endfacet'"},
    {"ascii_missing_endfacet.stl", FEMLOD_EPARSE, ":8: expected 'endfacet', found 'facet'"},
    {"ascii_missing_endsolid.stl", FEMLOD_EPARSE,
     ":15: expected 'facet' or 'endsolid', found the end of the file"},
    {"ascii_truncated.stl", FEMLOD_EPARSE, ":12: expected a number, found the end of the file"},
    {"ascii_four_vertices.stl", FEMLOD_EPARSE, ":7: expected 'endloop', found 'vertex'"},
    {"ascii_nan.stl", FEMLOD_EPARSE, ":6: coordinate 'NaN' is not finite"},
    /* OFF */
    {"counts_exceed.off", FEMLOD_EPARSE, ":10: file ends after 8 of 12 vertices"},
    {"faces_exceed.off", FEMLOD_EPARSE, ":10: file ends after 4 of 6 faces"},
    {"huge_counts.off", FEMLOD_EPARSE,
     ":2: header declares 4000000000 vertices and 4000000000 faces, but only 57 bytes follow"},
    {"index_range.off", FEMLOD_EPARSE, ":10: face index 4 out of range (4 vertices)"},
    {"face_index_negative.off", FEMLOD_EPARSE, ":7: bad face index '-1'"},
    {"face_two.off", FEMLOD_EPARSE, ":7: face has 2 vertices (at least 3 needed)"},
    {"coord_nan.off", FEMLOD_EPARSE, ":6: coordinate 'nan' is not finite"},
    {"garbage.off", FEMLOD_EPARSE, ":4: bad number 'zero'"},
    {"trailing.off", FEMLOD_EPARSE, ":10: data after the last of 3 faces: '3'"},
    {"empty.off", FEMLOD_EPARSE, ": empty file"},
    {"not_off.off", FEMLOD_EPARSE, ":1: expected the 'OFF' header, found 'PLY'"},
    {"binary.off", FEMLOD_EUNSUPPORTED, ":1: binary OFF is not supported"},
    /* PLY */
    {"unknown_format.ply", FEMLOD_EPARSE, ":2: unknown format 'binary_middle_endian'"},
    {"missing_z.ply", FEMLOD_EPARSE, ":3: element 'vertex' has no property 'z'"},
    {"list_past_end.ply", FEMLOD_EPARSE,
     ": byte 256: list of 200 entries runs past the end of the file (12 bytes left)"},
    {"truncated.ply", FEMLOD_EPARSE,
     ": byte 256: list of 3 entries runs past the end of the file (6 bytes left)"},
    {"truncated_vertices.ply", FEMLOD_EPARSE,
     ": byte 169: element 'vertex' declares 4 items of 12 bytes, but only 30 bytes are left"},
    {"huge_count.ply", FEMLOD_EPARSE,
     ": byte 178: element 'vertex' declares 4000000000 items of 12 bytes, but only 100 bytes"},
    {"huge_count_ascii.ply", FEMLOD_EPARSE,
     ":3: element 'vertex' declares 4000000000 items, but only 56 bytes of data follow"},
    {"index_range.ply", FEMLOD_EPARSE, ": byte 265: face index 4 out of range (4 vertices)"},
    {"negative_index.ply", FEMLOD_EPARSE, ":14: face index -1 out of range (4 vertices)"},
    {"face_two.ply", FEMLOD_EPARSE, ":14: face has 2 vertices (at least 3 needed)"},
    {"face_two_binary.ply", FEMLOD_EPARSE, ": byte 217: face has 2 vertices (at least 3 needed)"},
    {"negative_count.ply", FEMLOD_EPARSE, ": byte 216: negative list count -3"},
    {"coord_inf.ply", FEMLOD_EPARSE, ": byte 197: vertex 3: coordinate is not finite (inf)"},
    {"garbage_ascii.ply", FEMLOD_EPARSE, ":12: bad number 'x'"},
    {"no_end_header.ply", FEMLOD_EPARSE, ":4: file ends inside the header (no 'end_header')"},
    {"not_ply.ply", FEMLOD_EPARSE, ":1: not a PLY file (the first line must be 'ply')"},
    {"empty.ply", FEMLOD_EPARSE, ": empty file"},
    {"no_vertex_indices.ply", FEMLOD_EPARSE, ":7: element 'face' has no property 'vertex_indices'"},
    {"trailing.ply", FEMLOD_EPARSE, ": byte 269: 2 bytes after the last element"},
    /* MSH (docs/formats.md "Gmsh MSH") */
    {"msh_no_endnodes.msh", FEMLOD_EPARSE,
     ":15: expected '$EndNodes' after 1 node blocks, found '$Elements'"},
    {"msh_tag_range.msh", FEMLOD_EPARSE, ":20: node tag 9 out of range (nodes 1..4)"},
    {"msh_tag_undefined.msh", FEMLOD_EPARSE,
     ":14: node tag 7 is not defined (4 nodes with tags 1..12)"},
    {"msh_truncated.msh", FEMLOD_EPARSE, ":13: file ends inside the coordinates of node 3"},
    {"msh_node_count_long.msh", FEMLOD_EPARSE, ":10: '$EndNodes' after 4 of 5 nodes"},
    {"msh_node_count_short.msh", FEMLOD_EPARSE, ":9: expected '$EndNodes' after 3 nodes, found '4'"},
    {"msh_huge_nodes_limit.msh", FEMLOD_ELIMIT, ":5: 5000000000 nodes declared (limit 4294967295)"},
    {"msh_huge_nodes.msh", FEMLOD_EPARSE, ":9: '$EndNodes' after 3 of 3000000000 nodes"},
    {"msh_huge_elements.msh", FEMLOD_EPARSE,
     ":21: '$EndElements' where the element tag was expected (a count promises more data)"},
    {"msh_block_sum.msh", FEMLOD_EPARSE, ":12: header declares 4 nodes, its 1 blocks hold 3"},
    {"msh_block_exceeds.msh", FEMLOD_EPARSE,
     ":13: node block 2 holds 2 nodes, more than the 1 left of the header's 4"},
    {"msh_tag_outside_header.msh", FEMLOD_EPARSE, ":9: node tag 7 outside the header's range 1..4"},
    {"msh_duplicate_tag.msh", FEMLOD_EPARSE, ":9: node tag 2 is defined twice (first on line 7)"},
    {"msh_quad.msh", FEMLOD_EUNSUPPORTED,
     ":18: element type 3 (4-node quadrangle) is not supported: the surface must be 3-node "
     "triangles (type 2)"},
    {"msh_tets_only.msh", FEMLOD_EUNSUPPORTED,
     ":14: no triangles: all 1 elements are of other dimensions (the first is type 4, 4-node "
     "tetrahedron)"},
    {"msh_binary_header.msh", FEMLOD_EPARSE, ": byte 20: the byte-order integer is not 1"},
    {"msh_version3.msh", FEMLOD_EUNSUPPORTED, ":2: MSH version '3.0' is not supported"},
    {"msh_version1.msh", FEMLOD_EUNSUPPORTED, ":1: MSH version 1 is not supported"},
    {"msh_no_meshformat.msh", FEMLOD_EPARSE, ":1: expected '$MeshFormat', found '$Nodes'"},
    {"msh_unknown_type.msh", FEMLOD_EUNSUPPORTED, ":13: unknown element type 99"},
    {"msh_nan.msh", FEMLOD_EPARSE, ":7: coordinate 'nan' is not finite"},
    {"msh_unclosed_section.msh", FEMLOD_EPARSE,
     ":24: section '$PhysicalNames' (line 4) has no '$EndPhysicalNames'"},
    {"msh_elements_before_nodes.msh", FEMLOD_EPARSE, ":4: '$Elements' before '$Nodes'"},
    {"msh_no_elements.msh", FEMLOD_EPARSE, ":15: no '$Elements' section"},
    {"msh_empty.msh", FEMLOD_EPARSE, ": empty file"},
    {"msh_tag_zero.msh", FEMLOD_EPARSE, ":6: node tag 0 is invalid (tags start at 1)"},
    {"msh_wrong_dim.msh", FEMLOD_EPARSE,
     ":18: element block 1: type 2 (3-node triangle) in an entity of dimension 1"},
    {"msh_no_endelements.msh", FEMLOD_EPARSE,
     ":20: file ends before '$EndElements' (after 1 element blocks)"},
    {"msh_short_element.msh", FEMLOD_EPARSE,
     ":15: '$EndElements' inside an element (too few node tags)"},
    {"msh_bin_truncated.msh", FEMLOD_EPARSE,
     ": byte 2017: nodes: 14 records of 32 bytes, only 38 bytes are left"},
    {"msh_bin_tag_undefined.msh", FEMLOD_EPARSE,
     ": byte 1156: node tag 999 is not defined (14 nodes with tags 1..14)"},
    /* Medit */
    {"medit_after_end.mesh", FEMLOD_EPARSE, ":9: data after 'End': 'Vertices'"},
    {"medit_dim2.mesh", FEMLOD_EUNSUPPORTED, ":2: Dimension 2 (only 3 is read)"},
    {"medit_empty.mesh", FEMLOD_EPARSE, ": empty file"},
    {"medit_huge.mesh", FEMLOD_EPARSE, ":4: 4000000000 vertices declared, but only 13 bytes follow"},
    {"medit_index_range.mesh", FEMLOD_EPARSE, ":10: vertex index 4 out of range (1..3)"},
    {"medit_inf.mesh", FEMLOD_EPARSE, ":6: coordinate 'inf' is not finite"},
    {"medit_no_end.mesh", FEMLOD_EPARSE, ":10: file ends without 'End'"},
    {"medit_no_version.mesh", FEMLOD_EPARSE,
     ":1: expected 'MeshVersionFormatted', found 'Dimension'"},
    {"medit_quads.mesh", FEMLOD_EUNSUPPORTED,
     ":8: Quadrilaterals are not supported: the surface must be triangles"},
    {"medit_truncated.mesh", FEMLOD_EPARSE, ":11: file ends inside triangle 2"},
    {"medit_unknown_keyword.mesh", FEMLOD_EUNSUPPORTED, ":8: unknown keyword 'Triangle'"},
};

static void test_bad_files(void) {
    for (size_t i = 0; i < sizeof bad_cases / sizeof bad_cases[0]; i++) {
        const bad_case *c = &bad_cases[i];
        char dir[512], p[600], want[600];
        snprintf(dir, sizeof dir, "%s/bad", FEMLOD_TEST_DATA);
        path_in(p, sizeof p, dir, c->file);
        snprintf(want, sizeof want, "bad/%s%s", c->file, c->message);
        femlod_error err = {0, ""};
        femlod_mesh *m = NULL;
        femlod_status s = femlod_mesh_read(&m, p, NULL, &err);
        CHECK(s == c->status && err.status == c->status && m == NULL);
        CHECK_STR_HAS(err.message, want);
        /* One line, no matter what bytes the file held. */
        CHECK(strchr(err.message, '\n') == NULL);
        /* Without an error record, and from memory, the same outcome. */
        CHECK(femlod_mesh_read(&m, p, NULL, NULL) == c->status && m == NULL);
        char *data;
        size_t size;
        if (read_file(p, &data, &size)) {
            /* An exact-size copy: a reader that looks past the end trips ASan. */
            char *copy = malloc(size ? size : 1);
            if (size) memcpy(copy, data, size);
            femlod_error err2 = {0, ""};
            snprintf(want, sizeof want, "bad/%s", c->file);
            CHECK(femlod_mesh_read_memory(&m, copy, size, want, NULL, &err2) == c->status);
            CHECK(strcmp(err.message + strlen(err.message) - strlen(err2.message), err2.message) ==
                  0);
            free(copy);
            free(data);
        }
    }
    /* Files that cannot be read at all. */
    char p[512];
    femlod_error err = {0, ""};
    femlod_mesh *m = NULL;
    CHECK(femlod_mesh_read(&m, path_in(p, sizeof p, FEMLOD_TEST_DATA, "missing.obj"), NULL, &err) ==
          FEMLOD_EIO);
    CHECK_STR_HAS(err.message, "missing.obj: cannot open: No such file or directory");
    /* A folder is not a file. */
    char dirobj[600];
    snprintf(dirobj, sizeof dirobj, "%s/dir.obj", scratch);
    mkdir(dirobj, 0755);
    CHECK(femlod_mesh_read(&m, dirobj, NULL, &err) == FEMLOD_EIO);
    CHECK_STR_HAS(err.message, "dir.obj: cannot read: Is a directory");
    rmdir(dirobj);
}

/* }====== */

/* {====== round trips */

/* A mesh whose coordinates need every digit, plus the awkward values. */
static femlod_mesh *awkward_mesh(void) {
    femlod_mesh *m = shape_icosphere(2);
    if (!m) return NULL;
    static const double special[] = {
        0.1,       -0.0,    1e-300,  5e-324,   1e300, 123456789.123456789,
        1.0 / 3.0, -2.5e-7, DBL_MAX, -DBL_MIN, 1e16,  0.0};
    size_t ns = sizeof special / sizeof special[0];
    for (size_t i = 0; i < 3 * m->nv; i++) {
        if (i < ns) {
            m->pos[i] = special[i];
        } else {
            m->pos[i] *= 1.0 + (double)(rng() % 1000003) * 1e-9;
        }
    }
    return m;
}

/* Every reader on every file of the corpus (tests/data and tests/data/bad,
 * whatever its format: a file of the wrong format is hostile input too):
 * either a mesh that validates, or one error of one line that names the
 * file. Under ASan, any read out of bounds is a finding. */
static void test_every_reader_every_file(void) {
    static const femlod_format readers[] = {
        FEMLOD_FORMAT_OBJ, FEMLOD_FORMAT_STL, FEMLOD_FORMAT_STL_ASCII, FEMLOD_FORMAT_STL_BINARY,
        FEMLOD_FORMAT_OFF, FEMLOD_FORMAT_PLY, FEMLOD_FORMAT_GLTF, FEMLOD_FORMAT_GLB,
        FEMLOD_FORMAT_MSH, FEMLOD_FORMAT_MEDIT};
    const char *dirs[2] = {"", "/bad"};
    size_t files = 0, loaded = 0, refused = 0;
    for (int d = 0; d < 2; d++) {
        char dir[600];
        snprintf(dir, sizeof dir, "%s%s", FEMLOD_TEST_DATA, dirs[d]);
        DIR *dp = opendir(dir);
        CHECK(dp != NULL);
        if (!dp) continue;
        struct dirent *e;
        while ((e = readdir(dp))) {
            char p[1200];
            snprintf(p, sizeof p, "%s/%s", dir, e->d_name);
            struct stat st;
            if (e->d_name[0] == '.' || stat(p, &st) != 0 || !S_ISREG(st.st_mode)) continue;
            if (strstr(e->d_name, ".md")) continue;
            files++;
            for (size_t r = 0; r < sizeof readers / sizeof readers[0]; r++) {
                femlod_read_options ro = FEMLOD_READ_OPTIONS_INIT;
                ro.format = readers[r];
                femlod_mesh *m = NULL;
                femlod_error err = {0, ""};
                femlod_status s = femlod_mesh_read(&m, p, &ro, &err);
                if (s == FEMLOD_OK) {
                    loaded++;
                    CHECK(m != NULL);
                    femlod_mesh *copy = NULL;
                    if (m)
                        CHECK(femlod_mesh_create(&copy, femlod_mesh_positions(m),
                                                 femlod_mesh_vertex_count(m), femlod_mesh_triangles(m),
                                                 femlod_mesh_triangle_count(m), NULL) == FEMLOD_OK);
                    femlod_mesh_free(copy);
                    femlod_mesh_free(m);
                } else {
                    refused++;
                    CHECK(m == NULL);
                    CHECK(err.status == s);
                    CHECK(strstr(err.message, e->d_name) != NULL);
                    CHECK(strchr(err.message, '\n') == NULL);
                    if (strstr(err.message, e->d_name) == NULL)
                        fprintf(stderr, "  %s as %s: %s\n", e->d_name, femlod_format_name(readers[r]),
                                err.message);
                }
            }
        }
        closedir(dp);
    }
    printf("every reader on every corpus file: %zu files x %zu readers: %zu loaded, %zu refused\n",
           files, sizeof readers / sizeof readers[0], loaded, refused);
    CHECK(files > 100);
}

static void test_round_trips(void) {
    char p[600];
    femlod_mesh *a = awkward_mesh();
    CHECK(a && mesh_valid(a));
    if (!a) return;
    static const femlod_format exact[] = {FEMLOD_FORMAT_OBJ,        FEMLOD_FORMAT_OFF,
                                          FEMLOD_FORMAT_PLY_ASCII,  FEMLOD_FORMAT_PLY_BINARY,
                                          FEMLOD_FORMAT_MSH,        FEMLOD_FORMAT_MSH2,
                                          FEMLOD_FORMAT_MEDIT};
    static const char *const names[] = {"rt.obj",  "rt.off",  "rt_ascii.ply", "rt_binary.ply",
                                        "rt.msh", "rt2.msh", "rt.mesh"};
    for (size_t i = 0; i < sizeof exact / sizeof exact[0]; i++) {
        path_in(p, sizeof p, scratch, names[i]);
        if (!write_ok(a, p, exact[i])) continue;
        femlod_mesh *b = read_ok(p, FEMLOD_FORMAT_AUTO);
        CHECK(shape_same_mesh(a, b));
        if (!shape_same_mesh(a, b)) fprintf(stderr, "  round trip through %s differs\n", names[i]);
        femlod_mesh_free(b);
        unlink(p);
    }
    /* ASCII STL keeps every double; the weld renumbers, so compare corners. */
    path_in(p, sizeof p, scratch, "rt.stl");
    if (write_ok(a, p, FEMLOD_FORMAT_STL_ASCII)) {
        femlod_mesh *b = read_ok(p, FEMLOD_FORMAT_AUTO);
        CHECK(same_corners(a, b) && b && b->nv == a->nv);
        femlod_mesh_free(b);
    }
    /* Binary STL is float32: exact for float coordinates. */
    for (size_t i = 0; i < 3 * a->nv; i++) a->pos[i] = (double)(float)a->pos[i];
    for (size_t i = 0; i < 3 * a->nv; i++)
        if (!isfinite(a->pos[i])) a->pos[i] = 1.0; /* DBL_MAX does not fit a float */
    if (write_ok(a, p, FEMLOD_FORMAT_STL)) {
        femlod_mesh *b = read_ok(p, FEMLOD_FORMAT_AUTO);
        CHECK(same_corners(a, b));
        femlod_mesh_free(b);
        char *data;
        size_t size;
        if (read_file(p, &data, &size)) {
            CHECK(size == 84 + 50 * a->nt);
            CHECK(memcmp(data, "femlod " FEMLOD_VERSION_STRING,
                         7 + strlen(FEMLOD_VERSION_STRING)) == 0);
            /* The facet normal of triangle 0 is a unit vector. */
            float nrm[3];
            memcpy(nrm, data + 84, sizeof nrm);
            CHECK_NEAR(
                sqrt((double)nrm[0] * nrm[0] + (double)nrm[1] * nrm[1] + (double)nrm[2] * nrm[2]),
                1.0, 1e-6);
            free(data);
        }
    }
    unlink(p);
    femlod_mesh_free(a);

    /* OBJ -> STL -> OBJ on a real float mesh: identical arrays throughout. */
    femlod_mesh *spider = read_ok(FEMLOD_SHARED_DATA "/spider_binary.stl", FEMLOD_FORMAT_AUTO);
    if (spider) {
        char obj[600], stl[600];
        path_in(obj, sizeof obj, scratch, "spider.obj");
        path_in(stl, sizeof stl, scratch, "spider.stl");
        femlod_mesh *o1 = NULL, *s1 = NULL, *o2 = NULL, *s2 = NULL;
        if (write_ok(spider, obj, FEMLOD_FORMAT_AUTO)) o1 = read_ok(obj, FEMLOD_FORMAT_AUTO);
        CHECK(shape_same_mesh(spider, o1));
        if (o1 && write_ok(o1, stl, FEMLOD_FORMAT_AUTO)) s1 = read_ok(stl, FEMLOD_FORMAT_AUTO);
        CHECK(shape_same_mesh(o1, s1));
        if (s1 && write_ok(s1, obj, FEMLOD_FORMAT_OBJ)) o2 = read_ok(obj, FEMLOD_FORMAT_OBJ);
        CHECK(shape_same_mesh(spider, o2));
        if (o2 && write_ok(o2, stl, FEMLOD_FORMAT_STL_ASCII)) s2 = read_ok(stl, FEMLOD_FORMAT_STL);
        CHECK(shape_same_mesh(spider, s2));
        /* The writer's first line. */
        char *data;
        size_t size;
        if (read_file(obj, &data, &size)) {
            CHECK(strncmp(data, "# femlod " FEMLOD_VERSION_STRING "\n", 10) == 0);
            free(data);
        }
        femlod_mesh_free(o1);
        femlod_mesh_free(s1);
        femlod_mesh_free(o2);
        femlod_mesh_free(s2);
        unlink(obj);
        unlink(stl);
    }
    femlod_mesh_free(spider);

    /* Empty meshes and meshes without triangles. */
    femlod_mesh *e = NULL;
    double three[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    CHECK(femlod_mesh_create(&e, three, 3, NULL, 0, NULL) == FEMLOD_OK);
    static const femlod_format all[] = {FEMLOD_FORMAT_OBJ,       FEMLOD_FORMAT_OFF,
                                        FEMLOD_FORMAT_PLY_ASCII, FEMLOD_FORMAT_PLY_BINARY,
                                        FEMLOD_FORMAT_STL_ASCII, FEMLOD_FORMAT_STL_BINARY};
    for (size_t i = 0; e && i < sizeof all / sizeof all[0]; i++) {
        path_in(p, sizeof p, scratch, "empty.mesh");
        if (!write_ok(e, p, all[i])) continue;
        femlod_mesh *b = read_ok(p, all[i]);
        int stl = all[i] == FEMLOD_FORMAT_STL_ASCII || all[i] == FEMLOD_FORMAT_STL_BINARY;
        CHECK(b && b->nt == 0 && b->nv == (stl ? 0 : 3)); /* STL has no room for lone vertices */
        femlod_mesh_free(b);
        unlink(p);
    }
    femlod_mesh_free(e);
}

/* }====== */

/* {====== locale independence */

static int comma_locale(void) {
    static const char *const names[] = {"de_DE.UTF-8", "de_DE.utf8",  "fr_FR.UTF-8", "fr_FR.utf8",
                                        "de_DE",       "nl_NL.UTF-8", "ru_RU.UTF-8"};
    for (size_t i = 0; i < sizeof names / sizeof names[0]; i++)
        if (setlocale(LC_NUMERIC, names[i]) && strcmp(localeconv()->decimal_point, ",") == 0)
            return 1;
    /* None installed (a fresh container): compile one into the scratch
     * folder when the locale sources are there. */
    char cmd[1200], dir[600];
    snprintf(dir, sizeof dir, "%s/locale", scratch);
    mkdir(dir, 0755);
    snprintf(cmd, sizeof cmd, "localedef -i de_DE -f UTF-8 '%s/de_DE.UTF-8' >/dev/null 2>&1", dir);
    if (system(cmd) == 0) {
        setenv("LOCPATH", dir, 1);
        if (setlocale(LC_NUMERIC, "de_DE.UTF-8") && strcmp(localeconv()->decimal_point, ",") == 0)
            return 1;
    }
    setlocale(LC_NUMERIC, "C");
    return 0;
}

static void test_locale(void) {
    if (!comma_locale()) {
        fprintf(stderr, "test_io: no locale with a decimal comma (install 'locales'): "
                        "locale test skipped\n");
        return;
    }
    char buf[40];
    snprintf(buf, sizeof buf, "%.1f", 1.5);
    CHECK(strcmp(buf, "1,5") == 0); /* the trap is armed */
    CHECK(fl_format_double(buf, sizeof buf, 1.5) == 3 && strcmp(buf, "1.5") == 0);
    CHECK(fl_format_double(buf, sizeof buf, 0.1 + 0.2) > 0 &&
          strcmp(buf, "0.30000000000000004") == 0);
    char *e;
    const char *s = "1.5";
    CHECK(fl_strtod(s, &e) == 1.5 && e == s + 3);
    s = "0.30000000000000004";
    CHECK(fl_strtod(s, &e) == 0.1 + 0.2 && e == s + strlen(s));
    s = "3.14159265358979323846"; /* the slow path */
    CHECK(fl_strtod(s, &e) == 3.14159265358979323846 && *e == '\0');

    femlod_mesh *a = awkward_mesh();
    static const femlod_format fmts[] = {FEMLOD_FORMAT_OBJ, FEMLOD_FORMAT_OFF,
                                         FEMLOD_FORMAT_PLY_ASCII};
    char p[600];
    for (size_t i = 0; a && i < 3; i++) {
        path_in(p, sizeof p, scratch, "locale.mesh");
        if (!write_ok(a, p, fmts[i])) continue;
        char *data;
        size_t size;
        if (read_file(p, &data, &size)) {
            int comma = 0; /* a decimal comma: digit, comma, digit */
            for (size_t k = 1; k + 1 < size; k++)
                if (data[k] == ',' && isdigit((unsigned char)data[k - 1]) &&
                    isdigit((unsigned char)data[k + 1]))
                    comma = 1;
            CHECK(!comma);
            free(data);
        }
        femlod_mesh *b = read_ok(p, fmts[i]);
        CHECK(shape_same_mesh(a, b));
        femlod_mesh_free(b);
        unlink(p);
    }
    femlod_mesh_free(a);
    femlod_mesh *m = mem_ok("solid x\nfacet normal 0 0 1\nouter loop\nvertex 0.5 0 0\n"
                            "vertex 1.25 0 0\nvertex 0 1e-1 0\nendloop\nendfacet\nendsolid x\n",
                            FEMLOD_FORMAT_STL);
    CHECK(m && m->pos[0] == 0.5 && m->pos[3] == 1.25 && m->pos[7] == 0.1);
    femlod_mesh_free(m);
    setlocale(LC_NUMERIC, "C");
}

/* }====== */

/* {====== atomic writes */

static size_t temp_files_in(const char *dir) {
    DIR *d = opendir(dir);
    size_t n = 0;
    if (!d) return 0;
    struct dirent *e;
    while ((e = readdir(d)))
        if (strstr(e->d_name, ".tmp.")) n++;
    closedir(d);
    return n;
}

static void test_atomic_writes(void) {
    char dir[600], target[700], p[700];
    snprintf(dir, sizeof dir, "%s/atomic", scratch);
    mkdir(dir, 0755);
    path_in(target, sizeof target, dir, "out.obj");
    femlod_mesh *small = shape_tetrahedron(), *big = shape_icosphere(4);
    CHECK(small && big);
    if (!small || !big) return;
    femlod_error err = {0, ""};

    mode_t old_mask = umask(022);
    write_ok(small, target, FEMLOD_FORMAT_AUTO);
    struct stat st;
    CHECK(stat(target, &st) == 0 && (st.st_mode & 0777) == 0644); /* not mkstemp's 0600 */
    CHECK(chmod(target, 0640) == 0);
    write_ok(small, target, FEMLOD_FORMAT_AUTO);
    CHECK(stat(target, &st) == 0 && (st.st_mode & 0777) == 0640); /* replacing keeps the mode */
    umask(old_mask);
    char *before = NULL;
    size_t before_size = 0;
    CHECK(read_file(target, &before, &before_size));

    /* A write that fails half-way (the file size limit makes write() fail
     * with EFBIG) reports the error, leaves the old file, and no temporary. */
    struct rlimit old_limit, limit;
    void (*old_handler)(int) = signal(SIGXFSZ, SIG_IGN);
    if (getrlimit(RLIMIT_FSIZE, &old_limit) == 0) {
        limit = old_limit;
        limit.rlim_cur = 8192;
        if (setrlimit(RLIMIT_FSIZE, &limit) == 0) {
            femlod_status s = femlod_mesh_write(big, target, NULL, &err);
            setrlimit(RLIMIT_FSIZE, &old_limit);
            CHECK(s == FEMLOD_EIO && err.status == FEMLOD_EIO);
            CHECK_STR_HAS(err.message, "out.obj: cannot write: File too large");
            femlod_write_options bin = FEMLOD_WRITE_OPTIONS_INIT;
            bin.format = FEMLOD_FORMAT_PLY_BINARY;
            CHECK(setrlimit(RLIMIT_FSIZE, &limit) == 0);
            s = femlod_mesh_write(big, target, &bin, &err);
            setrlimit(RLIMIT_FSIZE, &old_limit);
            CHECK(s == FEMLOD_EIO);
            CHECK_STR_HAS(err.message, "out.obj: cannot write");
            char *after = NULL;
            size_t after_size = 0;
            CHECK(read_file(target, &after, &after_size));
            CHECK(after && before && after_size == before_size &&
                  memcmp(after, before, before_size) == 0);
            free(after);
            CHECK(temp_files_in(dir) == 0);
        } else {
            CHECK(!"setrlimit(RLIMIT_FSIZE) failed");
        }
    }
    signal(SIGXFSZ, old_handler);
    free(before);

    /* A folder that does not exist. */
    snprintf(p, sizeof p, "%s/no/such/dir/x.obj", scratch);
    CHECK(femlod_mesh_write(small, p, NULL, &err) == FEMLOD_EIO);
    CHECK_STR_HAS(err.message, "x.obj: cannot create temporary file: No such file or directory");
    /* A target that is a folder: refused before any temporary is made. */
    path_in(p, sizeof p, dir, "sub.obj");
    mkdir(p, 0755);
    CHECK(femlod_mesh_write(small, p, NULL, &err) == FEMLOD_EIO);
    CHECK_STR_HAS(err.message, "sub.obj: cannot write: Is a directory");
    CHECK(temp_files_in(dir) == 0);
    rmdir(p);
    /* Unknown extension, and the format option overriding it. */
    path_in(p, sizeof p, dir, "out.xyz");
    CHECK(femlod_mesh_write(small, p, NULL, &err) == FEMLOD_EINPUT);
    CHECK_STR_HAS(err.message,
                  "out.xyz: unknown file extension; supported: .obj, .stl, .off, .ply, .gltf, .glb");
    CHECK(access(p, F_OK) != 0);
    femlod_write_options wo = FEMLOD_WRITE_OPTIONS_INIT;
    wo.format = FEMLOD_FORMAT_PLY_ASCII;
    CHECK(femlod_mesh_write(small, p, &wo, &err) == FEMLOD_OK);
    femlod_mesh *back = read_ok(p, FEMLOD_FORMAT_PLY);
    CHECK(shape_same_mesh(small, back));
    femlod_mesh_free(back);
    unlink(p);
    /* A relative path (the folder to sync is "."). */
    char cwd[600];
    if (getcwd(cwd, sizeof cwd) && chdir(dir) == 0) {
        CHECK(femlod_mesh_write(small, "relative.off", NULL, &err) == FEMLOD_OK);
        back = read_ok("relative.off", FEMLOD_FORMAT_AUTO);
        CHECK(shape_same_mesh(small, back));
        femlod_mesh_free(back);
        unlink("relative.off");
        CHECK(chdir(cwd) == 0);
    }
    CHECK(temp_files_in(dir) == 0);
    unlink(target);
    rmdir(dir);
    femlod_mesh_free(small);
    femlod_mesh_free(big);
}

/* }====== */

/* {====== no truncation or byte flip of a valid file breaks a reader */

static void torture(const char *name, const char *data, size_t size) {
    size_t ok = 0, failed = 0, bad = 0;
    char *buf = malloc(size ? size : 1);
    femlod_read_options o = {femlod_format_from_path(name)};
    size_t step = size > 4000 ? size / 2000 : 1;
    for (size_t cut = 0; cut <= size; cut += step) {
        memcpy(buf, data, cut);
        femlod_error err = {0, ""};
        femlod_mesh *m = NULL;
        /* Exact-size buffers: ASan sees any read past the end. */
        char *exact = malloc(cut ? cut : 1);
        memcpy(exact, buf, cut);
        femlod_status s = femlod_mesh_read_memory(&m, exact, cut, name, &o, &err);
        free(exact);
        if (s == FEMLOD_OK) {
            ok++;
            if (!mesh_valid(m)) bad++;
        } else {
            failed++;
            if (strncmp(err.message, name, strlen(name)) != 0 || strchr(err.message, '\n')) bad++;
        }
        femlod_mesh_free(m);
    }
    for (int i = 0; i < 1500 && size; i++) {
        memcpy(buf, data, size);
        int flips = 1 + (int)(rng() % 4);
        for (int k = 0; k < flips; k++) {
            static const char junk[] = {'\0', '\n', ' ', '-', '/',   '#',
                                        '9',  '\\', 'e', '.', '\xff'};
            size_t at = (size_t)(rng() % size);
            buf[at] = (rng() & 1) ? junk[rng() % sizeof junk] : (char)rng();
        }
        femlod_error err = {0, ""};
        femlod_mesh *m = NULL;
        femlod_status s = femlod_mesh_read_memory(&m, buf, size, name, &o, &err);
        if (s == FEMLOD_OK) {
            ok++;
            if (!mesh_valid(m)) bad++;
        } else {
            failed++;
            if (strncmp(err.message, name, strlen(name)) != 0 || strchr(err.message, '\n')) bad++;
        }
        femlod_mesh_free(m);
    }
    free(buf);
    CHECK(bad == 0);
    CHECK(failed > 0); /* the damage was seen */
    if (bad)
        fprintf(stderr, "  %s: %zu invalid results (%zu read, %zu refused)\n", name, bad, ok,
                failed);
}

static void test_torture(void) {
    static const char *const files[] = {
        "quads.obj",         "crlf_continuation.obj",    "tetra_ascii.stl",
        "solid_header.stl",  "tetra_bom_two_solids.stl", "tetra.off",
        "square_colors.off", "ascii_extra.ply",          "binary_le.ply",
        "binary_be.ply",     "gmsh_box41.msh",           "gmsh_box22.msh",
        "gmsh_box41_bin.msh", "gmsh_box22_bin.msh",      "medit_sections.mesh"};
    char p[600];
    for (size_t i = 0; i < sizeof files / sizeof files[0]; i++) {
        char *data;
        size_t size;
        if (!read_file(path_in(p, sizeof p, FEMLOD_TEST_DATA, files[i]), &data, &size)) {
            CHECK(!"test file missing");
            continue;
        }
        torture(files[i], data, size);
        free(data);
    }
}

/* }====== */

/* Writing through a symbolic link replaces the file it points to and keeps
 * the link; a dangling link is an error that names the path. */
static void test_symlink_writes(void) {
    char real[700], link[700], dangling[700];
    path_in(real, sizeof real, scratch, "real.obj");
    path_in(link, sizeof link, scratch, "link.obj");
    path_in(dangling, sizeof dangling, scratch, "dangling.obj");
    femlod_mesh *m = shape_tetrahedron(), *back = NULL;
    femlod_error err;
    CHECK(femlod_mesh_write(m, real, NULL, &err) == FEMLOD_OK);
    CHECK(symlink("real.obj", link) == 0);
    femlod_mesh *p = shape_plane(2);
    CHECK(femlod_mesh_write(p, link, NULL, &err) == FEMLOD_OK);
    struct stat st;
    CHECK(lstat(link, &st) == 0 && S_ISLNK(st.st_mode));
    CHECK(femlod_mesh_read(&back, real, NULL, &err) == FEMLOD_OK);
    CHECK(back && femlod_mesh_triangle_count(back) == 8);
    femlod_mesh_free(back);
    CHECK(symlink("nowhere/x.obj", dangling) == 0);
    CHECK(femlod_mesh_write(p, dangling, NULL, &err) == FEMLOD_EIO);
    CHECK_STR_HAS(err.message, "dangling.obj: cannot follow symbolic link");
    CHECK(lstat(dangling, &st) == 0 && S_ISLNK(st.st_mode));
    femlod_mesh_free(m);
    femlod_mesh_free(p);
}

static void remove_scratch(void) {
    char p[700];
    DIR *d = opendir(scratch);
    if (d) {
        struct dirent *e;
        while ((e = readdir(d))) {
            if (e->d_name[0] == '.') continue;
            path_in(p, sizeof p, scratch, e->d_name);
            unlink(p);
        }
        closedir(d);
    }
    path_in(p, sizeof p, scratch, "locale/de_DE.UTF-8");
    char cmd[800];
    snprintf(cmd, sizeof cmd, "rm -rf '%s/locale'", scratch);
    if (access(p, F_OK) == 0 && system(cmd) != 0) fprintf(stderr, "cannot remove %s\n", cmd);
    rmdir(scratch);
}

int main(void) {
    const char *tmp = getenv("FEMLOD_TMP");
    snprintf(scratch, sizeof scratch, "%s/test_io.%ld", tmp && *tmp ? tmp : "/tmp", (long)getpid());
    if (mkdir(scratch, 0755) != 0 && errno != EEXIST) {
        fprintf(stderr, "cannot make %s: %s\n", scratch, strerror(errno));
        return 1;
    }
    test_format_names();
    test_numbers();
    test_reference_files();
    test_obj();
    test_obj_numbers_exact();
    test_stl();
    test_stl_weld_binary_as_ascii();
    test_off();
    test_ply();
    test_bad_files();
    test_every_reader_every_file();
    test_round_trips();
    test_atomic_writes();
    test_symlink_writes();
    test_torture();
    test_locale();
    remove_scratch();
    return check_report("io");
}
