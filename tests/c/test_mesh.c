/* test_mesh.c - the mesh object, exact welding and 1-to-4 subdivision. */
#include "core.h"
#include "check.h"
#include "shapes.h"

#include <math.h>
#include <stdlib.h>

static void test_create_validates(void) {
    const double p[] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    const uint32_t t_ok[] = {0, 1, 2};
    const uint32_t t_bad[] = {0, 1, 3};
    femlod_mesh *m = NULL;
    femlod_error err;
    CHECK(femlod_mesh_create(&m, p, 3, t_ok, 1, &err) == FEMLOD_OK);
    CHECK(femlod_mesh_vertex_count(m) == 3 && femlod_mesh_triangle_count(m) == 1);
    femlod_mesh_free(m);
    m = NULL;
    CHECK(femlod_mesh_create(&m, p, 3, t_bad, 1, &err) == FEMLOD_EINPUT);
    CHECK(m == NULL);
    CHECK_STR_HAS(err.message, "triangle 0: vertex index 3 out of range (3 vertices)");
    const double nan_p[] = {0, 0, 0, 1, NAN, 0, 0, 1, 0};
    CHECK(femlod_mesh_create(&m, nan_p, 3, t_ok, 1, &err) == FEMLOD_EINPUT);
    CHECK_STR_HAS(err.message, "vertex 1: coordinate 1 is not finite");
    CHECK(m == NULL);
    /* empty mesh is a valid object */
    CHECK(femlod_mesh_create(&m, NULL, 0, NULL, 0, &err) == FEMLOD_OK);
    double lo[3], hi[3];
    femlod_mesh_bbox(m, lo, hi);
    CHECK(lo[0] == 0 && hi[2] == 0);
    CHECK(femlod_mesh_area(m) == 0);
    femlod_mesh_free(m);
    femlod_mesh_free(NULL);
}

static void test_copy_bbox_area(void) {
    femlod_mesh *m = shape_plane(4), *c = NULL;
    CHECK(femlod_mesh_copy(&c, m, NULL) == FEMLOD_OK);
    CHECK(femlod_mesh_positions(c) != femlod_mesh_positions(m));
    CHECK(memcmp(femlod_mesh_positions(c), femlod_mesh_positions(m), 25 * 3 * sizeof(double)) == 0);
    double lo[3], hi[3];
    femlod_mesh_bbox(c, lo, hi);
    CHECK(lo[0] == 0 && lo[1] == 0 && hi[0] == 1 && hi[1] == 1 && hi[2] == 0);
    CHECK_NEAR(femlod_mesh_area(c), 1.0, 1e-12);
    femlod_mesh_free(m);
    femlod_mesh_free(c);
}

static void test_weld(void) {
    /* two triangles of a square as a soup, with -0.0 in one copy */
    const double soup[] = {0, 0, 0, 1, 0, 0, 1, 1, 0, -0.0, 0, 0, 1, 1, 0, 0, 1, -0.0};
    femlod_mesh *m = NULL;
    CHECK(fl_mesh_from_soup(&m, soup, 2, NULL) == FEMLOD_OK);
    CHECK(femlod_mesh_vertex_count(m) == 4);
    const uint32_t *t = femlod_mesh_triangles(m);
    /* numbered in order of first appearance */
    CHECK(t[0] == 0 && t[1] == 1 && t[2] == 2 && t[3] == 0 && t[4] == 2 && t[5] == 3);
    /* the stored zero is +0.0 */
    CHECK(!signbit(femlod_mesh_positions(m)[3 * 3 + 2]));
    femlod_mesh_free(m);
    /* a degenerate soup triangle keeps its repeated vertex */
    const double deg[] = {0, 0, 0, 0, 0, 0, 1, 0, 0};
    CHECK(fl_mesh_from_soup(&m, deg, 1, NULL) == FEMLOD_OK);
    t = femlod_mesh_triangles(m);
    CHECK(femlod_mesh_vertex_count(m) == 2 && t[0] == t[1]);
    femlod_mesh_free(m);
}

static void test_subdivide(void) {
    femlod_mesh *ico = shape_icosphere(0), *s = NULL;
    CHECK(femlod_mesh_subdivide(&s, ico, 2, NULL) == FEMLOD_OK);
    /* V' = V + E per level: 12 -> 42 -> 162; T x 16 */
    CHECK(femlod_mesh_vertex_count(s) == 162);
    CHECK(femlod_mesh_triangle_count(s) == 320);
    femlod_topology top;
    CHECK(femlod_mesh_topology(s, &top, NULL) == FEMLOD_OK);
    CHECK(top.closed && top.manifold && top.oriented && top.components == 1);
    CHECK(top.edges == 480);
    /* shapes are kept: the four children of a triangle are similar to it with
     * half the edges, and areas add up */
    CHECK_NEAR(femlod_mesh_area(s), femlod_mesh_area(ico), 1e-12);
    femlod_mesh *one = NULL;
    CHECK(femlod_mesh_subdivide(&one, ico, 1, NULL) == FEMLOD_OK);
    const double *p = femlod_mesh_positions(one);
    const uint32_t *t = femlod_mesh_triangles(one), *t0 = femlod_mesh_triangles(ico);
    const double *p0 = femlod_mesh_positions(ico);
    for (size_t tt = 0; tt < 20; tt++) {
        /* the middle child's corner k is the midpoint of parent side k */
        for (int k = 0; k < 3; k++) {
            const double *a = p0 + 3 * t0[3 * tt + (size_t)k], *b = p0 + 3 * t0[3 * tt + (size_t)(k + 1) % 3];
            const double *mid = p + 3 * t[12 * tt + 9 + (size_t)k];
            for (int d = 0; d < 3; d++) CHECK(mid[d] == 0.5 * (a[d] + b[d]));
        }
        CHECK(t[12 * tt] == t0[3 * tt] && t[12 * tt + 4] == t0[3 * tt + 1] &&
              t[12 * tt + 8] == t0[3 * tt + 2]);
    }
    /* levels = 0 copies */
    femlod_mesh *same = NULL;
    CHECK(femlod_mesh_subdivide(&same, ico, 0, NULL) == FEMLOD_OK);
    CHECK(femlod_mesh_triangle_count(same) == 20);
    /* an open plane: boundary edges double per level */
    femlod_mesh *pl = shape_plane(3), *pl2 = NULL;
    CHECK(femlod_mesh_subdivide(&pl2, pl, 1, NULL) == FEMLOD_OK);
    CHECK(femlod_mesh_topology(pl2, &top, NULL) == FEMLOD_OK);
    CHECK(top.boundary_edges == 24 && !top.closed && top.manifold);
    CHECK(femlod_mesh_vertex_count(pl2) == 49);
    /* a non-manifold edge shares one midpoint among its three triangles */
    femlod_mesh *fan = shape_nonmanifold_fan(), *fan2 = NULL;
    CHECK(femlod_mesh_subdivide(&fan2, fan, 1, NULL) == FEMLOD_OK);
    CHECK(femlod_mesh_vertex_count(fan2) == 5 + 7);
    CHECK(femlod_mesh_topology(fan2, &top, NULL) == FEMLOD_OK);
    CHECK(top.nonmanifold_edges == 2);
    /* the count guard refuses before allocating */
    femlod_error err;
    femlod_mesh *huge = NULL;
    CHECK(femlod_mesh_subdivide(&huge, ico, 15, &err) == FEMLOD_EINPUT);
    CHECK(huge == NULL);
    CHECK_STR_HAS(err.message, "exceeds");
    femlod_mesh_free(ico);
    femlod_mesh_free(s);
    femlod_mesh_free(one);
    femlod_mesh_free(same);
    femlod_mesh_free(pl);
    femlod_mesh_free(pl2);
    femlod_mesh_free(fan);
    femlod_mesh_free(fan2);
}

static void test_meshbuf(void) {
    fl_meshbuf b = {0};
    for (int i = 0; i < 1000; i++) CHECK(fl_meshbuf_add_vertex(&b, i, 2 * i, 3 * i));
    for (uint32_t i = 0; i + 2 < 1000; i++) CHECK(fl_meshbuf_add_triangle(&b, i, i + 1, i + 2));
    femlod_mesh *m = fl_meshbuf_finish(&b);
    CHECK(m && femlod_mesh_vertex_count(m) == 1000 && femlod_mesh_triangle_count(m) == 998);
    CHECK(femlod_mesh_positions(m)[3 * 999 + 2] == 2997.0);
    CHECK(b.pos == NULL && b.nv == 0);
    femlod_mesh_free(m);
    fl_meshbuf e = {0};
    m = fl_meshbuf_finish(&e);
    CHECK(m && femlod_mesh_vertex_count(m) == 0);
    femlod_mesh_free(m);
}

int main(void) {
    test_create_validates();
    test_copy_bbox_area();
    test_weld();
    test_subdivide();
    test_meshbuf();
    return check_report("mesh");
}
