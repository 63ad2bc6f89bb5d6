/* test_adjacency.c - edge/vertex adjacency and topology facts, checked on
 * generated shapes and against a brute-force count on random meshes. */
#include "core.h"
#include "check.h"
#include "shapes.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static femlod_topology topo(const femlod_mesh *m) {
    femlod_topology t;
    femlod_status s = femlod_mesh_topology(m, &t, NULL);
    CHECK(s == FEMLOD_OK);
    return t;
}

static void test_shapes(void) {
    femlod_mesh *m = shape_tetrahedron();
    femlod_topology t = topo(m);
    CHECK(t.edges == 6 && t.closed && t.manifold && t.oriented && t.components == 1);
    CHECK(t.boundary_edges == 0 && t.nonmanifold_edges == 0 && t.nonmanifold_vertices == 0);
    femlod_mesh_free(m);

    m = shape_plane(5);
    t = topo(m);
    CHECK(t.boundary_edges == 20 && !t.closed && t.manifold && t.oriented);
    CHECK(t.edges == 3 * 25 + 2 * 5);
    femlod_mesh_free(m);

    m = shape_nonmanifold_fan();
    t = topo(m);
    CHECK(t.nonmanifold_edges == 1 && !t.manifold && !t.closed);
    CHECK(t.nonmanifold_vertices == 2);
    CHECK(t.boundary_edges == 6);
    femlod_mesh_free(m);

    m = shape_bowtie();
    t = topo(m);
    CHECK(t.nonmanifold_edges == 0 && t.nonmanifold_vertices == 1 && !t.manifold);
    CHECK(t.components == 1);
    femlod_mesh_free(m);

    m = shape_cylinder(12, 3, 2.0);
    t = topo(m);
    CHECK(t.boundary_edges == 24 && t.manifold && t.oriented && t.components == 1);
    femlod_mesh_free(m);
}

static void test_defects(void) {
    /* tetrahedron with one triangle flipped: its three edges are inconsistent */
    const double p[] = {1, 1, 1, 1, -1, -1, -1, 1, -1, -1, -1, 1, 5, 5, 5};
    const uint32_t flip[] = {0, 2, 1, 0, 3, 1, 0, 2, 3, 1, 3, 2};
    femlod_mesh *m = NULL;
    CHECK(femlod_mesh_create(&m, p, 5, flip, 4, NULL) == FEMLOD_OK);
    femlod_topology t = topo(m);
    CHECK(t.inconsistent_edges == 3 && !t.oriented && t.closed);
    CHECK(t.isolated_vertices == 1);
    femlod_mesh_free(m);

    /* a degenerate triangle (repeated vertex) adds no a-a edge */
    const uint32_t deg[] = {0, 1, 2, 0, 0, 3};
    CHECK(femlod_mesh_create(&m, p, 5, deg, 2, NULL) == FEMLOD_OK);
    t = topo(m);
    CHECK(t.edges == 4);
    fl_adjacency adj;
    CHECK(fl_adjacency_build(&adj, deg, 2, 5, NULL) == FEMLOD_OK);
    CHECK(adj.tri_edges[3] == UINT32_MAX);
    uint32_t e03 = fl_adjacency_find_edge(&adj, 3, 0);
    CHECK(e03 != UINT32_MAX && adj.tri_edges[4] == e03 && adj.tri_edges[5] == e03);
    /* listed once on its edge and once at its vertex 0 */
    CHECK(adj.edge_start[e03 + 1] - adj.edge_start[e03] == 1);
    CHECK(adj.vert_start[1] - adj.vert_start[0] == 2);
    CHECK(fl_adjacency_find_edge(&adj, 1, 3) == UINT32_MAX);
    CHECK(fl_adjacency_find_edge(&adj, 2, 2) == UINT32_MAX);
    fl_adjacency_free(&adj);
    femlod_mesh_free(m);

    /* two disconnected triangles, a duplicate triangle on one of them */
    const double q[] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 5, 0, 0, 6, 0, 0, 5, 1, 0};
    const uint32_t two[] = {0, 1, 2, 3, 4, 5, 3, 4, 5};
    CHECK(femlod_mesh_create(&m, q, 6, two, 3, NULL) == FEMLOD_OK);
    t = topo(m);
    CHECK(t.components == 2 && t.boundary_edges == 3 && t.inconsistent_edges == 3);
    femlod_mesh_free(m);

    /* the empty mesh */
    CHECK(femlod_mesh_create(&m, NULL, 0, NULL, 0, NULL) == FEMLOD_OK);
    t = topo(m);
    CHECK(t.edges == 0 && !t.closed && t.manifold && t.components == 0);
    femlod_mesh_free(m);
}

/* Brute force: every pair of vertices is an edge iff some triangle has them
 * as a proper side; counts of triangles per edge; sorted neighbour lists. */
static void test_random_against_brute_force(void) {
    unsigned seed = 12345;
    for (int round = 0; round < 50; round++) {
        size_t nv = 3 + (size_t)(round % 17), nt = 1 + (size_t)(round * 7 % 40);
        uint32_t *tri = malloc(3 * nt * sizeof *tri);
        for (size_t i = 0; i < 3 * nt; i++) {
            seed = seed * 1103515245u + 12345u;
            tri[i] = (seed >> 16) % (uint32_t)nv;
        }
        fl_adjacency adj;
        CHECK(fl_adjacency_build(&adj, tri, nt, nv, NULL) == FEMLOD_OK);
        size_t ne = 0;
        for (uint32_t a = 0; a < nv; a++)
            for (uint32_t b = a + 1; b < nv; b++) {
                uint32_t count = 0;
                for (size_t t = 0; t < nt; t++) {
                    int has = 0;
                    for (int k = 0; k < 3; k++) {
                        uint32_t x = tri[3 * t + (size_t)k], y = tri[3 * t + (size_t)(k + 1) % 3];
                        has |= (x == a && y == b) || (x == b && y == a);
                    }
                    count += (uint32_t)has;
                }
                uint32_t e = fl_adjacency_find_edge(&adj, a, b);
                if (count == 0) {
                    CHECK(e == UINT32_MAX);
                    continue;
                }
                ne++;
                CHECK(e != UINT32_MAX);
                if (e == UINT32_MAX) continue;
                CHECK(fl_adjacency_find_edge(&adj, b, a) == e);
                CHECK(adj.edge_v[2 * e] == a && adj.edge_v[2 * e + 1] == b);
                CHECK(adj.edge_start[e + 1] - adj.edge_start[e] == count);
            }
        CHECK(adj.ne == ne);
        for (size_t v = 0; v < nv; v++)
            for (uint32_t k = adj.nbr_start[v] + 1; k < adj.nbr_start[v + 1]; k++)
                CHECK(adj.vert_nbrs[k - 1] < adj.vert_nbrs[k]);
        /* edges sorted by (a, b) */
        for (size_t e = 1; e < adj.ne; e++)
            CHECK(adj.edge_v[2 * e - 2] < adj.edge_v[2 * e] ||
                  (adj.edge_v[2 * e - 2] == adj.edge_v[2 * e] &&
                   adj.edge_v[2 * e - 1] < adj.edge_v[2 * e + 1]));
        fl_adjacency_free(&adj);
        free(tri);
    }
}

/* fl_mean_edge_lengths against the mean over a built adjacency's sorted
 * neighbours, bit for bit, on random meshes with repeated corners, repeated
 * triangles and isolated vertices; the order of the sum is what a hierarchy's
 * leaf sizes (and so every saved .flh) depend on. */
static void test_mean_edge_lengths(void) {
    unsigned seed = 777;
    for (int round = 0; round < 60; round++) {
        size_t nv = 4 + (size_t)(round % 23), nt = 1 + (size_t)(round * 11 % 70);
        uint32_t *tri = malloc(3 * nt * sizeof *tri);
        double *pos = malloc(3 * nv * sizeof *pos), *got = malloc(nv * sizeof *got);
        double *want = malloc(nv * sizeof *want);
        for (size_t i = 0; i < 3 * nt; i++) {
            seed = seed * 1103515245u + 12345u;
            tri[i] = (seed >> 16) % (uint32_t)(nv - 1); /* the last vertex is isolated */
        }
        for (size_t i = 0; i < 3 * nv; i++) {
            seed = seed * 1103515245u + 12345u;
            pos[i] = sin((double)(seed >> 8)) * 1e3 + 1.0 / (double)(1 + (seed >> 20));
        }
        fl_adjacency adj;
        CHECK(fl_adjacency_build(&adj, tri, nt, nv, NULL) == FEMLOD_OK);
        for (size_t v = 0; v < nv; v++) {
            double sum = 0.0;
            uint32_t n = adj.nbr_start[v + 1] - adj.nbr_start[v];
            for (uint32_t k = adj.nbr_start[v]; k < adj.nbr_start[v + 1]; k++) {
                const double *a = pos + 3 * v, *b = pos + 3 * (size_t)adj.vert_nbrs[k];
                double d[3] = {a[0] - b[0], a[1] - b[1], a[2] - b[2]};
                sum += sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
            }
            want[v] = n ? sum / n : 0.0;
        }
        memset(got, 0xAB, nv * sizeof *got);
        CHECK(fl_mean_edge_lengths(pos, tri, nt, nv, got, NULL) == FEMLOD_OK);
        CHECK(memcmp(got, want, nv * sizeof *got) == 0);
        CHECK(got[nv - 1] == 0.0);
        fl_adjacency_free(&adj);
        free(tri);
        free(pos);
        free(got);
        free(want);
    }
}

int main(void) {
    test_shapes();
    test_mean_edge_lengths();
    test_defects();
    test_random_against_brute_force();
    return check_report("adjacency");
}
