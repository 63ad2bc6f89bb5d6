/* test_fe.c - the finite-element formats (src/io_msh.c, io_vtk.c, io_inp.c,
 * io_medit.c). test_io.c holds their malformed files (tests/data/bad/msh_*,
 * medit_*), exact round trips and the truncation/byte-flip torture; this
 * file checks what the readers take from real gmsh output (sparse tags,
 * skipped elements, binary in both byte orders), the exact text of each
 * writer, and the .inp sets with every way to get them wrong. */
#include "core.h"

#include "check.h"
#include "shapes.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#ifndef FEMLOD_TEST_DATA
#error "FEMLOD_TEST_DATA must name tests/data"
#endif

static char scratch[512];

static const char *tmp_path(char *buf, size_t size, const char *name) {
    snprintf(buf, size, "%s/%s", scratch, name);
    return buf;
}

static char *slurp(const char *path) {
    char *data = NULL;
    size_t size;
    if (fl_file_read_all(path, &data, &size, NULL) != FEMLOD_OK) return NULL;
    return data;
}

static femlod_mesh *load(const char *name) {
    char p[600];
    snprintf(p, sizeof p, "%s/%s", FEMLOD_TEST_DATA, name);
    femlod_error err = {0, ""};
    femlod_mesh *m = NULL;
    if (femlod_mesh_read(&m, p, NULL, &err) != FEMLOD_OK) fprintf(stderr, "  %s\n", err.message);
    CHECK(m != NULL);
    return m;
}

static femlod_mesh *from_text(const char *text, const char *name, femlod_error *err) {
    femlod_mesh *m = NULL;
    if (femlod_mesh_read_memory(&m, text, strlen(text), name, NULL, err) != FEMLOD_OK) return NULL;
    return m;
}

/* {====== reading gmsh's own files */

static void test_gmsh_files(void) {
    /* gmsh 4.8.4 on a unit box (OpenCASCADE, -clmax 1): 8 points, 12
     * lines, 24 triangles, 24 tetrahedra, 14 nodes; ASCII and binary, 4.1
     * and 2.2, and 4.1 with parametric coordinates (-2 only). */
    static const char *const files[] = {"gmsh_box41.msh", "gmsh_box22.msh", "gmsh_box41_bin.msh",
                                        "gmsh_box22_bin.msh", "gmsh_box_param.msh"};
    femlod_mesh *first = NULL;
    for (size_t i = 0; i < sizeof files / sizeof files[0]; i++) {
        femlod_mesh *m = load(files[i]);
        if (!m) continue;
        CHECK(m->nt == 24 && m->nv == 14);
        femlod_topology topo;
        femlod_error err;
        CHECK(femlod_mesh_topology(m, &topo, &err) == FEMLOD_OK);
        CHECK(topo.boundary_edges == 0 && topo.nonmanifold_edges == 0);
        /* All five hold the same surface, vertex for vertex. */
        if (!first)
            first = m;
        else {
            CHECK(shape_same_mesh(first, m));
            femlod_mesh_free(m);
        }
    }
    femlod_mesh_free(first);
}

/* Sparse, unordered tags over several blocks; lines, points and a tetrahedron
 * skipped; every other section skipped whatever it holds. */
static void test_sparse_tags(void) {
    const char *v41 = "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n"
                      "$Comments\n$Nodes is only a word here\n$EndComments\n"
                      "$Nodes\n2 5 3 900\n"
                      "0 1 0 2\n900\n3\n0 0 0\n1 0 0\n"
                      "2 1 1 3\n40\n7\n11\n1 1 0 0.5 0.5\n0 1 0 0 1\n0 0 1 0.25 0.25\n"
                      "$EndNodes\n"
                      "$Elements\n3 4 1 20\n"
                      "0 1 15 1\n20 900\n"
                      "2 1 2 2\n5 900 3 40\n6 3 7 40\n"
                      "3 1 4 1\n1 900 3 40 11\n"
                      "$EndElements\n$NodeData\n1\n\"x\"\n$EndNodeData\n";
    femlod_error err = {0, ""};
    femlod_mesh *m = from_text(v41, "sparse.msh", &err);
    CHECK(m != NULL);
    if (!m) fprintf(stderr, "  %s\n", err.message);
    if (m) {
        CHECK(m->nv == 5 && m->nt == 2);
        /* Vertices in file order: tags 900, 3, 40, 7, 11. */
        CHECK(m->pos[3] == 1 && m->pos[6] == 1 && m->pos[7] == 1 && m->pos[14] == 1);
        CHECK(m->tri[0] == 0 && m->tri[1] == 1 && m->tri[2] == 2);
        CHECK(m->tri[3] == 1 && m->tri[4] == 3 && m->tri[5] == 2);
    }
    femlod_mesh_free(m);
    /* Tags spread far apart use the sorted lookup, not a table. */
    const char *far = "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n3\n"
                      "1000000000000 0 0 0\n5 1 0 0\n77 0 1 0\n$EndNodes\n"
                      "$Elements\n2\n1 2 0 5 77 1000000000000\n2 1 2 0 0 5 77\n$EndElements\n";
    m = from_text(far, "far.msh", &err);
    CHECK(m && m->nt == 1 && m->tri[0] == 1 && m->tri[1] == 2 && m->tri[2] == 0);
    femlod_mesh_free(m);
    const char *far_bad = "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n3\n"
                          "1000000000000 0 0 0\n5 1 0 0\n77 0 1 0\n$EndNodes\n"
                          "$Elements\n1\n1 2 0 5 76 1000000000000\n$EndElements\n";
    CHECK(from_text(far_bad, "far.msh", &err) == NULL);
    CHECK_STR_HAS(err.message,
                  "far.msh:12: node tag 76 is not defined (3 nodes with tags 5..1000000000000)");
    const char *far_dup = "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n3\n"
                          "1000000000000 0 0 0\n5 1 0 0\n1000000000000 0 1 0\n$EndNodes\n"
                          "$Elements\n0\n$EndElements\n";
    CHECK(from_text(far_dup, "dup.msh", &err) == NULL);
    CHECK_STR_HAS(err.message,
                  "dup.msh:8: node tag 1000000000000 is defined twice (first on line 6)");
    /* No elements at all: the nodes, no triangles (as OFF with 0 faces). */
    m = from_text("$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n0 0 0 0\n$EndNodes\n"
                  "$Elements\n0 0 0 0\n$EndElements\n",
                  "empty.msh", &err);
    CHECK(m && m->nv == 0 && m->nt == 0);
    femlod_mesh_free(m);
}

/* A binary 2.2 file in big-endian order (as a SPARC or POWER gmsh wrote it),
 * built byte by byte. */
static size_t put_be(unsigned char *p, uint64_t v, size_t size) {
    for (size_t i = 0; i < size; i++) p[i] = (unsigned char)(v >> (8 * (size - 1 - i)));
    return size;
}

static size_t put_be_double(unsigned char *p, double x) {
    uint64_t u;
    memcpy(&u, &x, sizeof u);
    return put_be(p, u, 8);
}

static void test_binary_big_endian(void) {
    unsigned char buf[512];
    size_t n = 0;
#define TEXT(s) (memcpy(buf + n, s, strlen(s)), n += strlen(s))
    TEXT("$MeshFormat\n2.2 1 8\n");
    n += put_be(buf + n, 1, 4);
    TEXT("\n$EndMeshFormat\n$Nodes\n3\n");
    static const double xyz[3][3] = {{0, 0, 0}, {1, 0, 0}, {0, 0.5, -2}};
    for (int i = 0; i < 3; i++) {
        n += put_be(buf + n, (uint64_t)(10 * (i + 1)), 4);
        for (int k = 0; k < 3; k++) n += put_be_double(buf + n, xyz[i][k]);
    }
    TEXT("\n$EndNodes\n$Elements\n2\n");
    /* one header per type: a line, then the triangle (2 tags each) */
    n += put_be(buf + n, 1, 4), n += put_be(buf + n, 1, 4), n += put_be(buf + n, 2, 4);
    n += put_be(buf + n, 1, 4), n += put_be(buf + n, 0, 4), n += put_be(buf + n, 0, 4);
    n += put_be(buf + n, 10, 4), n += put_be(buf + n, 20, 4);
    n += put_be(buf + n, 2, 4), n += put_be(buf + n, 1, 4), n += put_be(buf + n, 2, 4);
    n += put_be(buf + n, 2, 4), n += put_be(buf + n, 0, 4), n += put_be(buf + n, 0, 4);
    n += put_be(buf + n, 30, 4), n += put_be(buf + n, 10, 4), n += put_be(buf + n, 20, 4);
    TEXT("\n$EndElements\n");
#undef TEXT
    femlod_mesh *m = NULL;
    femlod_error err = {0, ""};
    femlod_read_options o = {FEMLOD_FORMAT_MSH};
    CHECK(femlod_mesh_read_memory(&m, buf, n, "be.msh", &o, &err) == FEMLOD_OK);
    CHECK(m && m->nv == 3 && m->nt == 1);
    if (m) {
        CHECK(m->pos[7] == 0.5 && m->pos[8] == -2);
        CHECK(m->tri[0] == 2 && m->tri[1] == 0 && m->tri[2] == 1);
    }
    femlod_mesh_free(m);
    /* The same file cut inside the nodes names the byte. */
    m = NULL;
    CHECK(femlod_mesh_read_memory(&m, buf, 60, "be.msh", &o, &err) == FEMLOD_EPARSE && !m);
    CHECK_STR_HAS(err.message,
                  "be.msh: byte 49: nodes: 3 records of 28 bytes, only 11 bytes are left");
}

/* }====== */

/* {====== writers: exact output */

static femlod_mesh *two_triangles(void) {
    static const double pos[] = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0.5};
    static const uint32_t tri[] = {0, 1, 2, 0, 2, 3};
    femlod_mesh *m = NULL;
    femlod_error err;
    CHECK(femlod_mesh_create(&m, pos, 4, tri, 2, &err) == FEMLOD_OK);
    return m;
}

static char *write_text(const femlod_mesh *m, const char *name, const femlod_write_options *o) {
    char p[600];
    femlod_error err = {0, ""};
    tmp_path(p, sizeof p, name);
    if (femlod_mesh_write(m, p, o, &err) != FEMLOD_OK) {
        fprintf(stderr, "  writing %s: %s\n", name, err.message);
        CHECK(!"write failed");
        return NULL;
    }
    char *text = slurp(p);
    unlink(p);
    return text;
}

static void expect_text(const char *got, const char *want, const char *what) {
    CHECK(got && strcmp(got, want) == 0);
    if (got && strcmp(got, want) != 0)
        fprintf(stderr, "  %s:\n%s\n--- expected:\n%s\n", what, got, want);
}

static void test_writers(void) {
    femlod_mesh *m = two_triangles();
    if (!m) return;
    char *t = write_text(m, "w.msh", NULL);
    expect_text(t,
                "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n"
                "$PhysicalNames\n2\n1 2 \"boundary\"\n2 1 \"surface\"\n$EndPhysicalNames\n"
                "$Entities\n0 1 1 0\n1 0 0 0 1 1 0.5 1 2 0\n1 0 0 0 1 1 0.5 1 1 1 1\n$EndEntities\n"
                "$Nodes\n1 4 1 4\n2 1 0 4\n1\n2\n3\n4\n0 0 0\n1 0 0\n1 1 0\n0 1 0.5\n$EndNodes\n"
                "$Elements\n2 6 1 6\n2 1 2 2\n1 1 2 3\n2 1 3 4\n"
                "1 1 1 4\n3 1 2\n4 2 3\n5 3 4\n6 4 1\n$EndElements\n",
                "msh 4.1");
    free(t);
    femlod_write_options o = FEMLOD_WRITE_OPTIONS_INIT;
    o.format = FEMLOD_FORMAT_MSH2;
    t = write_text(m, "w2.msh", &o);
    expect_text(t,
                "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n"
                "$PhysicalNames\n2\n1 2 \"boundary\"\n2 1 \"surface\"\n$EndPhysicalNames\n"
                "$Nodes\n4\n1 0 0 0\n2 1 0 0\n3 1 1 0\n4 0 1 0.5\n$EndNodes\n"
                "$Elements\n6\n1 2 2 1 1 1 2 3\n2 2 2 1 1 1 3 4\n"
                "3 1 2 2 1 1 2\n4 1 2 2 1 2 3\n5 1 2 2 1 3 4\n6 1 2 2 1 4 1\n$EndElements\n",
                "msh 2.2");
    /* Read back: the lines are skipped, the surface is the same. */
    char p[600];
    tmp_path(p, sizeof p, "w2.msh");
    femlod_write_options o2 = FEMLOD_WRITE_OPTIONS_INIT;
    o2.format = FEMLOD_FORMAT_MSH2;
    femlod_error e2 = {0, ""};
    femlod_mesh *b2 = NULL;
    CHECK(femlod_mesh_write(m, p, &o2, &e2) == FEMLOD_OK);
    CHECK(femlod_mesh_read(&b2, p, NULL, &e2) == FEMLOD_OK);
    CHECK(shape_same_mesh(m, b2));
    femlod_mesh_free(b2);
    unlink(p);
    /* A closed surface has no boundary group. */
    femlod_mesh *tet = shape_tetrahedron();
    char *tt = write_text(tet, "tet.msh", NULL);
    CHECK(tt && !strstr(tt, "boundary") && strstr(tt, "$Entities\n0 0 1 0\n"));
    free(tt);
    femlod_mesh_free(tet);
    free(t);
    t = write_text(m, "w.mesh", NULL);
    expect_text(t,
                "MeshVersionFormatted 2\nDimension 3\nVertices\n4\n0 0 0 0\n1 0 0 0\n1 1 0 0\n"
                "0 1 0.5 0\nTriangles\n2\n1 2 3 1\n1 3 4 1\nEnd\n",
                "medit");
    free(t);
    t = write_text(m, "w.vtk", NULL);
    CHECK(t && strncmp(t,
                       "# vtk DataFile Version 4.2\nfemlod " FEMLOD_VERSION_STRING
                       ": 2 triangles\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 4 double\n"
                       "0 0 0\n1 0 0\n1 1 0\n0 1 0.5\nCELLS 2 8\n3 0 1 2\n3 0 2 3\n"
                       "CELL_TYPES 2\n5\n5\nCELL_DATA 2\nSCALARS stretch double 1\n"
                       "LOOKUP_TABLE default\n",
                       220) == 0);
    if (t) {
        /* The stretch and size values are the library's, to the last digit. */
        char want[200], num[40];
        const double *xyz = m->pos;
        fl_format_double(num, sizeof num, femlod_triangle_stretch(xyz, xyz + 3, xyz + 6));
        snprintf(want, sizeof want, "LOOKUP_TABLE default\n%s\n", num);
        CHECK_STR_HAS(t, want);
        fl_format_double(num, sizeof num, femlod_triangle_size(xyz, xyz + 6, xyz + 9));
        snprintf(want, sizeof want,
                 "%s\nPOINT_DATA 4\nSCALARS valence int 1\nLOOKUP_TABLE default\n"
                 "3\n2\n3\n2\n",
                 num);
        CHECK_STR_HAS(t, want);
        CHECK_STR_HAS(t, "SCALARS size double 1\nLOOKUP_TABLE default\n");
    }
    free(t);
    /* Writing only: reading one back is refused with the list. */
    femlod_error err = {0, ""};
    femlod_mesh *back = from_text("# vtk DataFile Version 4.2\n", "x.vtk", &err);
    CHECK(!back && err.status == FEMLOD_EUNSUPPORTED);
    CHECK_STR_HAS(err.message, "x.vtk: femlod writes vtk files but does not read them");
    back = from_text("*NODE\n", "x.inp", &err);
    CHECK(!back && err.status == FEMLOD_EUNSUPPORTED);
    femlod_mesh_free(m);
}

/* }====== */

/* {====== .inp and its sets */

/* CalculiX reads at most 20 characters per number: a node card with a longer
 * one fails and every later node is lost (found by fe_tools on a simplified
 * cover with a vertex at x = 1.7759175032026203e-08). Every number fits, the
 * ones whose shortest exact form fits stay exact, the others keep as many
 * significant digits as fit (15 for a positive number with a two-digit
 * exponent, 13 at worst). */
static void test_inp_widths(void) {
    static const double pos[] = {-1.7759175032026203e-08, 139.36867163338422, 2.2762897584326667,
                                 1.7759175032026203e-08, -0.1, 1e-300,
                                 -1.2345678901234567e+100, 0.00012345678901234567, 4.9};
    static const uint32_t tri[] = {0, 1, 2};
    femlod_mesh *m = NULL;
    CHECK(femlod_mesh_create(&m, pos, 3, tri, 1, NULL) == FEMLOD_OK);
    if (!m) return;
    char *t = write_text(m, "widths.inp", NULL);
    const char *c = t ? strstr(t, "*NODE, NSET=NALL\n") : NULL;
    CHECK(c != NULL);
    if (c) c += strlen("*NODE, NSET=NALL\n");
    for (int v = 0; v < 3 && c; v++) {
        unsigned id = 0;
        int used = 0;
        CHECK(sscanf(c, "%u, %n", &id, &used) == 1 && id == (unsigned)v + 1);
        c += used;
        for (int k = 0; k < 3; k++) {
            size_t len = strcspn(c, ",\n");
            CHECK(len > 0 && len <= 20);
            char field[64];
            snprintf(field, sizeof field, "%.*s", (int)len, c);
            double x = strtod(field, NULL), want = pos[3 * v + k];
            CHECK(fabs(x - want) <= 1e-12 * fabs(want)); /* 13 digits at worst: -1.234567890123e+100 */
            if (len < 20 && strlen(field) <= 18) CHECK(x == want); /* fits exactly: kept exact */
            c += len;
            if (*c == ',') c += 2;
        }
        CHECK(*c == '\n');
        c++;
    }
    CHECK_STR_HAS(t, "1, -1.7759175032026e-08, 139.36867163338422, 2.2762897584326667\n");
    free(t);
    femlod_mesh_free(m);
}

static void test_inp(void) {
    femlod_mesh *m = two_triangles();
    if (!m) return;
    uint32_t fixed[] = {3, 0, 0, 1};
    uint32_t many[25];
    for (uint32_t i = 0; i < 25; i++) many[i] = i % 4;
    uint32_t first[] = {1};
    femlod_index_set ns[] = {{"Fixed", fixed, 4}, {"all4", many, 25}};
    femlod_index_set es[] = {{"TOP", first, 1}};
    femlod_write_options o = FEMLOD_WRITE_OPTIONS_INIT;
    o.node_sets = ns;
    o.node_set_count = 2;
    o.element_sets = es;
    o.element_set_count = 1;
    char *t = write_text(m, "w.inp", &o);
    expect_text(t,
                "** femlod " FEMLOD_VERSION_STRING ": 4 nodes, 2 S3 elements\n"
                "*NODE, NSET=NALL\n1, 0, 0, 0\n2, 1, 0, 0\n3, 1, 1, 0\n4, 0, 1, 0.5\n"
                "*ELEMENT, TYPE=S3, ELSET=EALL\n1, 1, 2, 3\n2, 1, 3, 4\n"
                "*NSET, NSET=NBOUNDARY\n1, 2, 3, 4\n"
                "*NSET, NSET=NFEATURE\n1, 2, 3, 4\n"
                "*NSET, NSET=Fixed\n1, 2, 4\n"
                "*NSET, NSET=all4\n1, 2, 3, 4\n"
                "*ELSET, ELSET=TOP\n2\n",
                "inp");
    free(t);
    /* A closed, smooth surface has neither NBOUNDARY nor NFEATURE (an
     * icosphere's normals differ by less than 40 degrees); more than 10 ids
     * wrap. */
    femlod_mesh *sphere = shape_icosphere(1);
    uint32_t ids[23];
    for (uint32_t i = 0; i < 23; i++) ids[i] = 22 - i;
    femlod_index_set big = {"ring", ids, 23};
    femlod_write_options o2 = FEMLOD_WRITE_OPTIONS_INIT;
    o2.node_sets = &big;
    o2.node_set_count = 1;
    t = write_text(sphere, "s.inp", &o2);
    CHECK(t && !strstr(t, "NBOUNDARY") && !strstr(t, "NFEATURE"));
    CHECK_STR_HAS(t, "*NSET, NSET=ring\n1, 2, 3, 4, 5, 6, 7, 8, 9, 10\n"
                     "11, 12, 13, 14, 15, 16, 17, 18, 19, 20\n21, 22, 23\n");
    free(t);
    femlod_mesh_free(sphere);
    /* A tetrahedron's edges are all sharp (normals 109.5 degrees apart). */
    femlod_mesh *tet = shape_tetrahedron();
    t = write_text(tet, "tet.inp", NULL);
    CHECK(t && !strstr(t, "NBOUNDARY") && strstr(t, "*NSET, NSET=NFEATURE\n1, 2, 3, 4\n"));
    free(t);
    femlod_mesh_free(tet);
    /* An icosphere with one vertex pulled out to a spike: the edges around
     * it turn sharp, so NFEATURE is that vertex and its ring of 5 or 6
     * neighbours, nothing else. */
    femlod_mesh *spike = shape_icosphere(1);
    for (int k = 0; k < 3; k++) spike->pos[k] *= 3;
    t = write_text(spike, "spike.inp", NULL);
    const char *f = t ? strstr(t, "*NSET, NSET=NFEATURE\n") : NULL;
    size_t members = 0;
    for (const char *c = f ? f + 21 : NULL; c && *c && *c != '*'; c++) members += *c == ',' || *c == '\n';
    CHECK(f && strncmp(f + 21, "1, ", 3) == 0);
    CHECK(members >= 6 && members <= 7);
    free(t);
    femlod_mesh_free(spike);

    /* Every way to get a set wrong: EINPUT, nothing written. */
    static const struct {
        const char *name;
        uint32_t index;
        const char *message;
    } bad[] = {
        {"9lives", 0, "bad.inp: node set name '9lives' is not valid (a letter, then letters"},
        {"has space", 0, "node set name 'has space' is not valid"},
        {"", 0, "bad.inp: node set 1 has no name"},
        {"nall", 0, "bad.inp: node set name 'nall' is reserved (NALL, EALL, NBOUNDARY, NFEATURE)"},
        {"NBoundary", 0, "node set name 'NBoundary' is reserved"},
        {"fixed", 4, "bad.inp: node set 'fixed': index 4 out of range (4 vertices)"},
        {"FIXED2", 0, "bad.inp: node set 'fixed2' given twice (names ignore case)"},
        {"x12345678901234567890123456789012345678901234567890123456789012345678901234567890", 0,
         "is not valid"},
    };
    char p[600];
    tmp_path(p, sizeof p, "bad.inp");
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        uint32_t idx = bad[i].index;
        femlod_index_set sets[2] = {{bad[i].name, &idx, 1}, {"fixed2", &idx, 1}};
        femlod_write_options ob = FEMLOD_WRITE_OPTIONS_INIT;
        ob.node_sets = sets;
        ob.node_set_count = strcmp(bad[i].name, "FIXED2") == 0 ? 2 : 1;
        femlod_error err = {0, ""};
        CHECK(femlod_mesh_write(m, p, &ob, &err) == FEMLOD_EINPUT);
        CHECK_STR_HAS(err.message, bad[i].message);
        CHECK(access(p, F_OK) != 0);
    }
    femlod_error err = {0, ""};
    femlod_index_set empty = {"none", fixed, 0};
    femlod_write_options oe = FEMLOD_WRITE_OPTIONS_INIT;
    oe.element_sets = &empty;
    oe.element_set_count = 1;
    CHECK(femlod_mesh_write(m, p, &oe, &err) == FEMLOD_EINPUT);
    CHECK_STR_HAS(err.message, "bad.inp: element set 'none' is empty");
    uint32_t two = 2;
    femlod_index_set e2 = {"e", &two, 1};
    oe.element_sets = &e2;
    CHECK(femlod_mesh_write(m, p, &oe, &err) == FEMLOD_EINPUT);
    CHECK_STR_HAS(err.message, "bad.inp: element set 'e': index 2 out of range (2 triangles)");
    /* Sets are for .inp only. */
    tmp_path(p, sizeof p, "sets.msh");
    femlod_write_options om = FEMLOD_WRITE_OPTIONS_INIT;
    om.node_sets = ns;
    om.node_set_count = 1;
    CHECK(femlod_mesh_write(m, p, &om, &err) == FEMLOD_EINPUT);
    CHECK_STR_HAS(err.message,
                  "sets.msh: node and element sets are written to .inp only (format msh)");
    CHECK(access(p, F_OK) != 0);
    femlod_mesh_free(m);
}

/* }====== */

int main(void) {
    const char *tmp = getenv("FEMLOD_TMP");
    snprintf(scratch, sizeof scratch, "%s/test_fe.%ld", tmp && *tmp ? tmp : "/tmp", (long)getpid());
    if (mkdir(scratch, 0755) != 0 && errno != EEXIST) {
        fprintf(stderr, "cannot make %s: %s\n", scratch, strerror(errno));
        return 1;
    }
    test_gmsh_files();
    test_sparse_tags();
    test_binary_big_endian();
    test_writers();
    test_inp();
    test_inp_widths();
    rmdir(scratch);
    return check_report("fe");
}
