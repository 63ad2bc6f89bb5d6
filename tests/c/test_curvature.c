/* test_curvature.c - the normal-cycle curvature (paper 5.3.1, src/curvature.c)
 * against analytic surfaces: spheres and cylinders of several radii and
 * resolutions (issue 5: within 5% of the nonzero curvatures, within 0.05/R
 * of the zero one, away from boundaries), planes, folds of known sign and
 * direction, scaling, the fandisk's creases, determinism, degenerate input
 * and the error cases; and the 3x3 eigensolver on its own. */
#include "check.h"
#include "core.h"
#include "shapes.h"

#include <stdlib.h>

static const double PI = 3.14159265358979323846;

static uint64_t rng = 0x9E3779B97F4A7C15ull;
static double uniform(void) { /* xorshift64*, [-1, 1) */
    rng ^= rng >> 12;
    rng ^= rng << 25;
    rng ^= rng >> 27;
    return (double)((rng * 0x2545F4914F6CDD1Dull) >> 11) / 4503599627370496.0 - 1.0;
}

typedef struct curv {
    size_t n;
    double *k1, *k2, *kappa, *dir1, *dir2;
} curv;

static void curv_free(curv *c) {
    free(c->k1);
    free(c->k2);
    free(c->kappa);
    free(c->dir1);
    free(c->dir2);
}

/* All five arrays with the given radius (0: default); NaN-filled first so
 * that an entry the call forgot shows. */
static curv curvature_of(const femlod_mesh *m, double radius) {
    curv c;
    c.n = femlod_mesh_vertex_count(m);
    c.k1 = malloc((c.n + 1) * sizeof(double));
    c.k2 = malloc((c.n + 1) * sizeof(double));
    c.kappa = malloc((c.n + 1) * sizeof(double));
    c.dir1 = malloc((3 * c.n + 1) * sizeof(double));
    c.dir2 = malloc((3 * c.n + 1) * sizeof(double));
    for (size_t i = 0; i < c.n; i++) c.k1[i] = c.k2[i] = c.kappa[i] = NAN;
    for (size_t i = 0; i < 3 * c.n; i++) c.dir1[i] = c.dir2[i] = NAN;
    femlod_curvature_options o = FEMLOD_CURVATURE_OPTIONS_INIT;
    o.radius = radius;
    femlod_error err;
    femlod_status s = femlod_mesh_curvature(m, &o, c.k1, c.k2, c.kappa, c.dir1, c.dir2, &err);
    CHECK(s == FEMLOD_OK);
    return c;
}

static double mean_edge(const femlod_mesh *m) {
    uint32_t *edges = NULL;
    size_t ne = 0;
    femlod_status s = fl_quality_edges(&edges, &ne, m->tri, m->nt, m->nv, NULL);
    CHECK(s == FEMLOD_OK && ne > 0);
    double sum = 0;
    for (size_t e = 0; e < ne; e++) {
        const double *p = m->pos + 3 * (size_t)edges[2 * e], *q = m->pos + 3 * (size_t)edges[2 * e + 1];
        sum += sqrt((p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1]) +
                    (p[2] - q[2]) * (p[2] - q[2]));
    }
    free(edges);
    return sum / (double)ne;
}

static double dot(const double *u, const double *v) {
    return u[0] * v[0] + u[1] * v[1] + u[2] * v[2];
}

/* Every vertex's k1 >= k2, kappa = max |k|, unit perpendicular directions
 * (and, with a normal array, tangent ones); returns the count of failures
 * so a broken mesh reports once, not per vertex. */
static int frame_failures(const curv *c, const double *normals) {
    int bad = 0;
    for (size_t v = 0; v < c->n; v++) {
        const double *d1 = c->dir1 + 3 * v, *d2 = c->dir2 + 3 * v;
        int ok = c->k1[v] >= c->k2[v] && c->kappa[v] == fmax(fabs(c->k1[v]), fabs(c->k2[v])) &&
                 fabs(dot(d1, d1) - 1) < 1e-12 && fabs(dot(d2, d2) - 1) < 1e-12 &&
                 fabs(dot(d1, d2)) < 1e-12;
        if (normals) {
            const double *n = normals + 3 * v;
            ok = ok && fabs(dot(d1, n)) < 0.05 && fabs(dot(d2, n)) < 0.05;
        }
        bad += !ok;
    }
    return bad;
}

/* {====== spheres */

static femlod_mesh *scaled(femlod_mesh *m, double s, const double shift[3]) {
    for (size_t i = 0; i < 3 * m->nv; i++) m->pos[i] = m->pos[i] * s + (shift ? shift[i % 3] : 0.0);
    return m;
}

static void reverse_orientation(femlod_mesh *m) {
    for (size_t t = 0; t < m->nt; t++) {
        uint32_t x = m->tri[3 * t + 1];
        m->tri[3 * t + 1] = m->tri[3 * t + 2];
        m->tri[3 * t + 2] = x;
    }
}

/* Largest relative error of k1 and k2 against `expect` (signed). */
static double worst_error(const curv *c, double expect) {
    double worst = 0;
    for (size_t v = 0; v < c->n; v++) {
        worst = fmax(worst, fabs(c->k1[v] - expect) / fabs(expect));
        worst = fmax(worst, fabs(c->k2[v] - expect) / fabs(expect));
    }
    return worst;
}

static void test_sphere(void) {
    static const double radii[] = {0.3, 1.0, 12.5};
    const double shift[3] = {4.0, -2.0, 0.5};
    for (unsigned level = 4; level <= 5; level++) {
        for (size_t i = 0; i < sizeof radii / sizeof radii[0]; i++) {
            double R = radii[i];
            femlod_mesh *m = scaled(shape_icosphere(level), R, shift);
            double h = mean_edge(m);
            /* outward normals, as the tangent test wants them */
            double *normals = malloc(3 * m->nv * sizeof(double));
            for (size_t v = 0; v < m->nv; v++)
                for (int k = 0; k < 3; k++) normals[3 * v + k] = (m->pos[3 * v + k] - shift[k]) / R;
            /* default radius (2 mean edges) and a wider one */
            for (int wide = 0; wide < 2; wide++) {
                curv c = curvature_of(m, wide ? 3.0 * h : 0.0);
                double err = worst_error(&c, 1.0 / R);
                if (err > 0.05)
                    fprintf(stderr, "sphere level %u R %g radius %s: worst error %.4f\n", level, R,
                            wide ? "3h" : "default", err);
                CHECK(err <= 0.05);
                CHECK(frame_failures(&c, normals) == 0);
                curv_free(&c);
            }
            /* inward normals: the same magnitudes, the sign flips */
            reverse_orientation(m);
            curv c = curvature_of(m, 0.0);
            CHECK(worst_error(&c, -1.0 / R) <= 0.05);
            CHECK(frame_failures(&c, normals) == 0);
            curv_free(&c);
            free(normals);
            femlod_mesh_free(m);
        }
    }
}

/* An irregular mesh of the sphere: every vertex moved along the surface by
 * up to 15% of the mean edge in each direction, then put back on it. */
static void test_jittered_sphere(void) {
    femlod_mesh *m = shape_icosphere(5);
    double h = mean_edge(m);
    for (size_t v = 0; v < m->nv; v++) {
        double *p = m->pos + 3 * v;
        for (int k = 0; k < 3; k++) p[k] += 0.15 * h * uniform();
        double l = sqrt(dot(p, p));
        for (int k = 0; k < 3; k++) p[k] /= l;
    }
    femlod_quality q;
    CHECK(femlod_mesh_quality(m, &q, NULL) == FEMLOD_OK);
    CHECK(q.stretch_min < 0.6); /* really irregular: the icosphere's least is 0.88 */
    curv c = curvature_of(m, 0.0);
    double err = worst_error(&c, 1.0);
    printf("jittered sphere (stretch min %.2f): worst error %.4f\n", q.stretch_min, err);
    CHECK(err <= 0.05);
    CHECK(frame_failures(&c, m->pos) == 0); /* unit sphere: positions are normals */
    curv_free(&c);
    femlod_mesh_free(m);
}

/* The cap z > 0.3 of the unit sphere: the bending across the cut is
 * missing next to it (boundary edges have no dihedral angle), and only
 * there. */
static void test_hemisphere(void) {
    femlod_mesh *s = shape_icosphere(5);
    uint32_t *t = malloc(3 * s->nt * sizeof *t);
    size_t nt = 0;
    for (size_t i = 0; i < s->nt; i++) {
        const uint32_t *c = s->tri + 3 * i;
        if (s->pos[3 * c[0] + 2] + s->pos[3 * c[1] + 2] + s->pos[3 * c[2] + 2] > 0.9) {
            memcpy(t + 3 * nt, c, 3 * sizeof *t);
            nt++;
        }
    }
    femlod_mesh *m = NULL;
    CHECK(femlod_mesh_create(&m, s->pos, s->nv, t, nt, NULL) == FEMLOD_OK);
    double r = 2 * mean_edge(m);
    curv c = curvature_of(m, 0.0);
    double cut = 1, inner = 0, near = 1; /* lowest z used, worst interior error, least k2 at the cut */
    for (size_t v = 0; v < m->nv; v++)
        if (c.kappa[v] > 0) cut = fmin(cut, m->pos[3 * v + 2]);
    for (size_t v = 0; v < m->nv; v++) {
        double z = m->pos[3 * v + 2];
        if (!(c.kappa[v] > 0)) continue;
        /* the cut's plane is z = cut, and the surface leaves it at about
         * 70 degrees: a vertex 1.1 r above it is farther than r */
        if (z > cut + 1.1 * r) inner = fmax(inner, fmax(fabs(c.k1[v] - 1), fabs(c.k2[v] - 1)));
        if (z < cut + 1e-12) near = fmin(near, c.k2[v]);
    }
    printf("hemisphere: worst interior error %.4f, least k2 on the cut %.4f\n", inner, near);
    CHECK(inner <= 0.05);
    CHECK(near < 0.9);
    curv_free(&c);
    femlod_mesh_free(m);
    femlod_mesh_free(s);
    free(t);
}

/* }====== */

/* {====== cylinders, planes, folds */

/* Cylinder of radius R, `around` segments, quads about square, axis z. */
static femlod_mesh *cylinder(unsigned around, double R, double *height) {
    double side = 2 * PI / around;
    unsigned up = (unsigned)(2.0 / side); /* height about 2 (unit radius) */
    *height = R * side * up;
    return scaled(shape_cylinder(around, up, side * up), R, NULL);
}

static void test_cylinder(void) {
    static const unsigned arounds[] = {48, 96, 192};
    static const double radii[] = {0.25, 3.0};
    for (size_t a = 0; a < sizeof arounds / sizeof arounds[0]; a++) {
        for (size_t i = 0; i < sizeof radii / sizeof radii[0]; i++) {
            double R = radii[i], H;
            femlod_mesh *m = cylinder(arounds[a], R, &H);
            double r = 2 * mean_edge(m); /* the default, made explicit for the rim margin */
            curv c = curvature_of(m, r);
            curv d = curvature_of(m, 0.0);
            int same = 1, interior = 0, bad_k1 = 0, bad_k2 = 0, bad_dir = 0;
            double worst1 = 0, worst2 = 0;
            for (size_t v = 0; v < c.n; v++) {
                same &= c.k1[v] == d.k1[v] && c.k2[v] == d.k2[v];
                double z = m->pos[3 * v + 2];
                if (z <= r * (1 + 1e-9) || z >= H - r * (1 + 1e-9)) continue; /* the ball meets a rim */
                interior++;
                worst1 = fmax(worst1, fabs(c.k1[v] * R - 1));
                worst2 = fmax(worst2, fabs(c.k2[v] * R));
                bad_k1 += !(fabs(c.k1[v] - 1 / R) <= 0.05 / R);
                bad_k2 += !(fabs(c.k2[v]) <= 0.05 / R);
                /* max curvature around the axis, min along it */
                bad_dir += !(fabs(c.dir1[3 * v + 2]) < 1e-6 && fabs(c.dir2[3 * v + 2]) > 1 - 1e-6);
            }
            if (bad_k1 || bad_k2)
                fprintf(stderr, "cylinder %u R %g: worst |k1 R - 1| %.4f, |k2 R| %.4f\n", arounds[a],
                        R, worst1, worst2);
            CHECK(same); /* the default radius is 2 mean edges */
            CHECK(interior > 0);
            CHECK(bad_k1 == 0);
            CHECK(bad_k2 == 0);
            CHECK(bad_dir == 0);
            /* Tangent directions: the papers' rule (normal = the eigenvector
             * of the eigenvalue nearest 0) fails here, as two are 0. */
            double *normals = malloc(3 * c.n * sizeof(double));
            for (size_t v = 0; v < c.n; v++) {
                normals[3 * v] = m->pos[3 * v] / R;
                normals[3 * v + 1] = m->pos[3 * v + 1] / R;
                normals[3 * v + 2] = 0;
            }
            CHECK(frame_failures(&c, normals) == 0);
            free(normals);
            /* The rims bend along themselves, so their edges (which carry
             * no bending) miss none: within 5% there too. */
            int bad_rim = 0;
            for (size_t v = 0; v < c.n; v++) bad_rim += !(fabs(c.k1[v] - 1 / R) <= 0.05 / R);
            CHECK(bad_rim == 0);
            curv_free(&c);
            curv_free(&d);
            femlod_mesh_free(m);
        }
    }
}

static void test_plane(void) {
    femlod_mesh *m = shape_plane(20);
    curv c = curvature_of(m, 0.0);
    int zero = 1;
    for (size_t v = 0; v < c.n; v++) zero &= c.k1[v] == 0.0 && c.k2[v] == 0.0 && c.kappa[v] == 0.0;
    CHECK(zero);
    double *up = calloc(3 * c.n, sizeof(double));
    for (size_t v = 0; v < c.n; v++) up[3 * v + 2] = 1;
    CHECK(frame_failures(&c, up) == 0);
    free(up);
    curv_free(&c);
    /* tilted and moved: zero up to rounding */
    for (size_t v = 0; v < m->nv; v++) {
        double *p = m->pos + 3 * v, x = p[0], y = p[1];
        p[0] = 0.6 * x + 10.0;
        p[1] = 0.8 * x * 0.6 + 0.8 * y - 3.0;
        p[2] = -0.8 * x * 0.8 + 0.6 * y + 7.0;
    }
    c = curvature_of(m, 0.0);
    double worst = 0;
    for (size_t v = 0; v < c.n; v++) worst = fmax(worst, c.kappa[v]);
    CHECK(worst < 1e-9);
    curv_free(&c);
    femlod_mesh_free(m);
}

/* Two triangles hinged on the x axis; lift > 0 bends the second one up. */
static void test_fold(void) {
    for (int up = 0; up < 2; up++) {
        double lift = up ? 0.5 : -0.5;
        const double p[] = {0, 0, 0, 1, 0, 0, 0.5, 1, 0, 0.5, -1, lift};
        const uint32_t t[] = {0, 1, 2, 1, 0, 3};
        femlod_mesh *m = NULL;
        CHECK(femlod_mesh_create(&m, p, 4, t, 2, NULL) == FEMLOD_OK);
        curv c = curvature_of(m, 0.0);
        /* The first triangle faces +z; the second going down is a convex
         * fold (a ridge), going up a concave one (a valley). */
        if (!up) {
            CHECK(c.k1[0] > 0.1);
            CHECK(fabs(c.k2[0]) < 1e-12);
            CHECK(fabs(c.dir1[0]) < 1e-9); /* across the hinge */
            CHECK(fabs(fabs(c.dir2[0]) - 1) < 1e-9);
        } else {
            CHECK(c.k2[0] < -0.1);
            CHECK(fabs(c.k1[0]) < 1e-12);
            CHECK(fabs(c.dir2[0]) < 1e-9);
            CHECK(fabs(fabs(c.dir1[0]) - 1) < 1e-9);
        }
        CHECK_REL(c.kappa[0], c.kappa[1], 1e-12); /* the two hinge ends see the same */
        CHECK(frame_failures(&c, NULL) == 0);
        /* The second triangle turned over (orientation inconsistent across
         * the hinge): the angle is measured against the first triangle,
         * which has not changed, so the curvatures do not either. */
        const uint32_t t_flipped[] = {0, 1, 2, 0, 1, 3};
        femlod_mesh *mf = NULL;
        CHECK(femlod_mesh_create(&mf, p, 4, t_flipped, 2, NULL) == FEMLOD_OK);
        curv f = curvature_of(mf, 0.0);
        for (int v = 0; v < 4; v++) {
            CHECK_NEAR(f.k1[v], c.k1[v], 1e-9 * (fabs(c.k1[0]) + fabs(c.k2[0])));
            CHECK_NEAR(f.k2[v], c.k2[v], 1e-9 * (fabs(c.k1[0]) + fabs(c.k2[0])));
        }
        curv_free(&f);
        femlod_mesh_free(mf);
        curv_free(&c);
        femlod_mesh_free(m);
    }
}

/* A small sphere floating next to a big one, inside the balls of the big
 * one's nearest vertices: the walk stays on the surface it starts from, so
 * the big sphere reads exactly as it does alone. */
static void test_separate_sheets(void) {
    femlod_mesh *big = shape_icosphere(4), *small = scaled(shape_icosphere(2), 0.05, NULL);
    double r = 2 * mean_edge(big);
    size_t nb = big->nv, ns = small->nv;
    double *pos = malloc(3 * (nb + ns) * sizeof(double));
    uint32_t *tri = malloc(3 * (big->nt + small->nt) * sizeof(uint32_t));
    memcpy(pos, big->pos, 3 * nb * sizeof(double));
    for (size_t i = 0; i < 3 * ns; i++) pos[3 * nb + i] = small->pos[i] + (i % 3 == 0 ? 1.08 : 0.0);
    memcpy(tri, big->tri, 3 * big->nt * sizeof(uint32_t));
    for (size_t i = 0; i < 3 * small->nt; i++) tri[3 * big->nt + i] = small->tri[i] + (uint32_t)nb;
    femlod_mesh *both = NULL;
    CHECK(femlod_mesh_create(&both, pos, nb + ns, tri, big->nt + small->nt, NULL) == FEMLOD_OK);
    /* the small sphere is well inside the ball of the big one's vertex at x = 1 */
    size_t near = 0;
    for (size_t v = 0; v < nb; v++)
        if (fabs(big->pos[3 * v] - 1) < 1e-12) near = v;
    CHECK(fabs(big->pos[3 * near] - 1) < 1e-12 && 0.08 + 0.05 < r);
    curv alone = curvature_of(big, r), with = curvature_of(both, r);
    CHECK(memcmp(alone.k1, with.k1, nb * sizeof(double)) == 0);
    CHECK(memcmp(alone.k2, with.k2, nb * sizeof(double)) == 0);
    CHECK(memcmp(alone.dir1, with.dir1, 3 * nb * sizeof(double)) == 0);
    /* The small sphere (1/R = 20) fits whole in its own vertices' balls,
     * so its tensor holds edges of every direction and reads low, but it
     * is its own: far above the big sphere's 1. */
    CHECK(with.k2[nb] > 10 && with.k1[nb] < 20);
    curv_free(&alone);
    curv_free(&with);
    femlod_mesh_free(both);
    femlod_mesh_free(big);
    femlod_mesh_free(small);
    free(pos);
    free(tri);
}

/* }====== */

/* {====== scaling, the fandisk, determinism */

static femlod_mesh *load_fandisk(void) {
    femlod_mesh *m = NULL;
    femlod_error err;
    femlod_status s = femlod_mesh_read(&m, FEMLOD_SHARED_DATA "/fandisk.obj", NULL, &err);
    if (s != FEMLOD_OK) fprintf(stderr, "%s\n", err.message);
    CHECK(s == FEMLOD_OK);
    return m;
}

static void test_scaling(void) {
    femlod_mesh *m = load_fandisk();
    if (!m) return;
    curv c = curvature_of(m, 0.0);
    static const double factors[] = {2.5, 0.01, 1000.0};
    for (size_t i = 0; i < sizeof factors / sizeof factors[0]; i++) {
        double s = factors[i];
        femlod_mesh *big = NULL;
        CHECK(femlod_mesh_copy(&big, m, NULL) == FEMLOD_OK);
        scaled(big, s, NULL);
        curv d = curvature_of(big, 0.0); /* the default radius scales too */
        int bad = 0, bad_dir = 0;
        for (size_t v = 0; v < c.n; v++) {
            double scale = fmax(c.kappa[v], 1.0); /* absolute near zero */
            bad += !(fabs(d.k1[v] * s - c.k1[v]) <= 1e-9 * scale &&
                     fabs(d.k2[v] * s - c.k2[v]) <= 1e-9 * scale &&
                     fabs(d.kappa[v] * s - c.kappa[v]) <= 1e-9 * scale);
            /* directions are defined where k1 and k2 differ */
            if (c.k1[v] - c.k2[v] > 1e-3 * scale)
                bad_dir += !(fabs(fabs(dot(d.dir1 + 3 * v, c.dir1 + 3 * v)) - 1) < 1e-6);
        }
        CHECK(bad == 0);
        CHECK(bad_dir == 0);
        curv_free(&d);
        femlod_mesh_free(big);
    }
    curv_free(&c);
    femlod_mesh_free(m);
}

static int cmp_double(const void *a, const void *b) {
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* Crease vertices found independently: ends of an edge whose triangles'
 * normals are more than 40 degrees apart. */
static void test_fandisk_creases(void) {
    femlod_mesh *m = load_fandisk();
    if (!m) return;
    curv c = curvature_of(m, 0.0);
    CHECK(frame_failures(&c, NULL) == 0);
    fl_adjacency adj;
    CHECK(fl_adjacency_build(&adj, m->tri, m->nt, m->nv, NULL) == FEMLOD_OK);
    char *crease = calloc(m->nv, 1);
    for (size_t e = 0; e < adj.ne; e++) {
        if (adj.edge_start[e + 1] - adj.edge_start[e] != 2) continue;
        double n[2][3];
        for (int j = 0; j < 2; j++) {
            const uint32_t *t = m->tri + 3 * (size_t)adj.edge_tris[adj.edge_start[e] + (uint32_t)j];
            const double *a = m->pos + 3 * (size_t)t[0], *b = m->pos + 3 * (size_t)t[1],
                         *d = m->pos + 3 * (size_t)t[2];
            double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
            double w[3] = {d[0] - a[0], d[1] - a[1], d[2] - a[2]};
            n[j][0] = u[1] * w[2] - u[2] * w[1];
            n[j][1] = u[2] * w[0] - u[0] * w[2];
            n[j][2] = u[0] * w[1] - u[1] * w[0];
            double l = sqrt(dot(n[j], n[j]));
            for (int k = 0; k < 3; k++) n[j][k] /= l;
        }
        if (dot(n[0], n[1]) < cos(40 * PI / 180))
            crease[adj.edge_v[2 * e]] = crease[adj.edge_v[2 * e + 1]] = 1;
    }
    double *all = malloc(m->nv * sizeof(double)), *on = malloc(m->nv * sizeof(double));
    size_t ncrease = 0;
    for (size_t v = 0; v < m->nv; v++) {
        all[v] = c.kappa[v];
        if (crease[v]) on[ncrease++] = c.kappa[v];
    }
    CHECK(ncrease > 500); /* the fandisk's creases: about 700 vertices */
    qsort(all, m->nv, sizeof(double), cmp_double);
    qsort(on, ncrease, sizeof(double), cmp_double);
    double median = all[m->nv / 2];
    size_t above = 0;
    for (size_t i = 0; i < ncrease; i++) above += on[i] > 2 * median;
    printf("fandisk: kappa median %.4g, crease median %.4g, %zu of %zu crease vertices above 2x\n",
           median, on[ncrease / 2], above, ncrease);
    CHECK(median > 0);
    CHECK(on[ncrease / 2] > 5 * median);
    CHECK(above >= ncrease * 95 / 100);
    /* and the largest kappa of all sits on a crease */
    size_t top = 0;
    for (size_t v = 1; v < m->nv; v++)
        if (c.kappa[v] > c.kappa[top]) top = v;
    CHECK(crease[top]);
    free(all);
    free(on);
    free(crease);
    fl_adjacency_free(&adj);
    curv_free(&c);
    femlod_mesh_free(m);
}

static void test_determinism(void) {
    femlod_mesh *m = load_fandisk();
    if (!m) return;
    curv a = curvature_of(m, 0.0), b = curvature_of(m, 0.0);
    size_t n = a.n;
    CHECK(memcmp(a.k1, b.k1, n * sizeof(double)) == 0);
    CHECK(memcmp(a.k2, b.k2, n * sizeof(double)) == 0);
    CHECK(memcmp(a.kappa, b.kappa, n * sizeof(double)) == 0);
    CHECK(memcmp(a.dir1, b.dir1, 3 * n * sizeof(double)) == 0);
    CHECK(memcmp(a.dir2, b.dir2, 3 * n * sizeof(double)) == 0);
    /* any output may be NULL, and the others do not change */
    double *kappa = malloc(n * sizeof(double)), *dir2 = malloc(3 * n * sizeof(double));
    CHECK(femlod_mesh_curvature(m, NULL, NULL, NULL, kappa, NULL, dir2, NULL) == FEMLOD_OK);
    CHECK(memcmp(a.kappa, kappa, n * sizeof(double)) == 0);
    CHECK(memcmp(a.dir2, dir2, 3 * n * sizeof(double)) == 0);
    CHECK(femlod_mesh_curvature(m, NULL, NULL, NULL, NULL, NULL, NULL, NULL) == FEMLOD_OK);
    /* a larger radius smooths: a different, still deterministic answer */
    curv w = curvature_of(m, 0.05);
    CHECK(memcmp(a.kappa, w.kappa, n * sizeof(double)) != 0);
    free(kappa);
    free(dir2);
    curv_free(&w);
    curv_free(&a);
    curv_free(&b);
    femlod_mesh_free(m);
}

/* }====== */

/* {====== odd input and errors */

static void test_degenerate_input(void) {
    /* an unused vertex, a triangle with a repeated corner, a collinear one */
    const double p[] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 9, 9, 9, 2, 0, 0, 3, 0, 0};
    const uint32_t t[] = {0, 1, 2, 1, 1, 4, 1, 4, 5};
    femlod_mesh *m = NULL;
    CHECK(femlod_mesh_create(&m, p, 6, t, 3, NULL) == FEMLOD_OK);
    curv c = curvature_of(m, 0.0);
    /* one flat triangle: nothing bends; vertex 3 has no face; vertex 5
     * only the collinear one */
    int zero = 1;
    for (size_t v = 0; v < c.n; v++) zero &= c.k1[v] == 0 && c.k2[v] == 0 && c.kappa[v] == 0;
    CHECK(zero);
    for (int k = 0; k < 3; k++) {
        CHECK(c.dir1[3 * 3 + k] == 0 && c.dir2[3 * 3 + k] == 0);
        CHECK(c.dir1[3 * 5 + k] == 0 && c.dir2[3 * 5 + k] == 0);
    }
    CHECK(fabs(dot(c.dir1, c.dir1) - 1) < 1e-12); /* vertex 0 has a real face */
    curv_free(&c);
    femlod_mesh_free(m);

    /* an empty mesh */
    femlod_mesh *e = NULL;
    const double none[3] = {0, 0, 0};
    const uint32_t no_triangle[3] = {0, 0, 0};
    CHECK(femlod_mesh_create(&e, none, 0, no_triangle, 0, NULL) == FEMLOD_OK);
    double k;
    CHECK(femlod_mesh_curvature(e, NULL, &k, &k, &k, NULL, NULL, NULL) == FEMLOD_OK);
    femlod_mesh_free(e);

    /* a non-manifold edge bends nothing; everything else is boundary */
    femlod_mesh *fan = shape_nonmanifold_fan();
    c = curvature_of(fan, 0.0);
    zero = 1;
    for (size_t v = 0; v < c.n; v++) zero &= c.kappa[v] == 0;
    CHECK(zero);
    curv_free(&c);
    femlod_mesh_free(fan);

    /* a closed tetrahedron: convex everywhere */
    femlod_mesh *tet = shape_tetrahedron();
    c = curvature_of(tet, 0.0);
    int convex = 1;
    for (size_t v = 0; v < c.n; v++) convex &= c.k1[v] > 0 && c.k2[v] > 0;
    CHECK(convex);
    CHECK(frame_failures(&c, NULL) == 0);
    curv_free(&c);
    femlod_mesh_free(tet);

    /* a sheet folded onto itself: its normals cancel, so the tensor alone
     * gives the frame (the eigensolver path) */
    const double q[] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    const uint32_t two[] = {0, 1, 2, 0, 2, 1};
    femlod_mesh *sheet = NULL;
    CHECK(femlod_mesh_create(&sheet, q, 3, two, 2, NULL) == FEMLOD_OK);
    c = curvature_of(sheet, 0.0);
    int finite = 1;
    for (size_t v = 0; v < c.n; v++) finite &= isfinite(c.k1[v]) && isfinite(c.k2[v]) && c.kappa[v] > 0;
    CHECK(finite);
    CHECK(frame_failures(&c, NULL) == 0);
    curv_free(&c);
    femlod_mesh_free(sheet);
}

static void test_errors(void) {
    femlod_mesh *m = shape_tetrahedron();
    double k1[4] = {7, 7, 7, 7};
    femlod_error err;
    femlod_curvature_options o = FEMLOD_CURVATURE_OPTIONS_INIT;
    o.radius = -1.0;
    CHECK(femlod_mesh_curvature(m, &o, k1, NULL, NULL, NULL, NULL, &err) == FEMLOD_EINPUT);
    CHECK(err.status == FEMLOD_EINPUT);
    CHECK_STR_HAS(err.message, "curvature: radius must be a finite number >= 0 (got -1)");
    o.radius = NAN;
    CHECK(femlod_mesh_curvature(m, &o, k1, NULL, NULL, NULL, NULL, &err) == FEMLOD_EINPUT);
    CHECK_STR_HAS(err.message, "(got nan)");
    o.radius = -NAN;
    CHECK(femlod_mesh_curvature(m, &o, k1, NULL, NULL, NULL, NULL, &err) == FEMLOD_EINPUT);
    CHECK_STR_HAS(err.message, "(got nan)");
    o.radius = INFINITY;
    CHECK(femlod_mesh_curvature(m, &o, k1, NULL, NULL, NULL, NULL, &err) == FEMLOD_EINPUT);
    CHECK_STR_HAS(err.message, "(got inf)");
    /* err may be NULL; nothing is written on failure */
    CHECK(femlod_mesh_curvature(m, &o, k1, NULL, NULL, NULL, NULL, NULL) == FEMLOD_EINPUT);
    CHECK(k1[0] == 7 && k1[3] == 7);
    femlod_mesh_free(m);
}

/* }====== */

/* {====== the 3x3 eigensolver */

/* A v_k = value_k v_k and orthonormal vectors, relative to the matrix size. */
static int eigen_ok(const double m[6], double tol) {
    double value[3], vec[9];
    fl_curvature_eigen3(m, value, vec);
    double a[3][3] = {{m[0], m[1], m[2]}, {m[1], m[3], m[4]}, {m[2], m[4], m[5]}};
    double size = 0;
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) size = fmax(size, fabs(a[i][j]));
    int ok = 1;
    for (int k = 0; k < 3; k++) {
        const double *v = vec + 3 * k;
        for (int i = 0; i < 3; i++) {
            double av = a[i][0] * v[0] + a[i][1] * v[1] + a[i][2] * v[2];
            ok &= fabs(av - value[k] * v[i]) <= tol * fmax(size, 1e-300);
        }
        for (int l = 0; l < 3; l++) ok &= fabs(dot(v, vec + 3 * l) - (k == l)) <= 1e-12;
    }
    /* the trace is kept */
    ok &= fabs(value[0] + value[1] + value[2] - (m[0] + m[3] + m[5])) <= tol * 3 * fmax(size, 1e-300);
    return ok;
}

static void test_eigen3(void) {
    int bad = 0;
    for (int i = 0; i < 2000; i++) {
        double m[6];
        for (int k = 0; k < 6; k++) m[k] = uniform();
        if (i % 4 == 1) m[1] = m[2] = m[4] = 0; /* diagonal already */
        if (i % 4 == 2) { /* a double eigenvalue: c I + w w^T */
            double w[3] = {uniform(), uniform(), uniform()}, c = uniform();
            m[0] = c + w[0] * w[0]; m[1] = w[0] * w[1]; m[2] = w[0] * w[2];
            m[3] = c + w[1] * w[1]; m[4] = w[1] * w[2]; m[5] = c + w[2] * w[2];
        }
        if (i % 4 == 3) /* wildly different scales */
            for (int k = 0; k < 6; k++) m[k] *= pow(10.0, 8 * uniform());
        bad += !eigen_ok(m, 1e-12);
    }
    CHECK(bad == 0);
    const double zero[6] = {0, 0, 0, 0, 0, 0}, tiny[6] = {1e-300, 1e-310, 0, 1e-300, 0, 0};
    CHECK(eigen_ok(zero, 0));
    CHECK(eigen_ok(tiny, 1e-12));
    /* the cylinder's tensor, (1/R) z z^T seen in a rotated frame */
    double z[3] = {0.48, 0.6, 0.64}, m[6] = {z[0] * z[0], z[0] * z[1], z[0] * z[2],
                                             z[1] * z[1], z[1] * z[2], z[2] * z[2]};
    double value[3], vec[9];
    fl_curvature_eigen3(m, value, vec);
    int top = 0;
    for (int k = 1; k < 3; k++)
        if (value[k] > value[top]) top = k;
    CHECK_NEAR(value[top], dot(z, z), 1e-14);
    CHECK_NEAR(fabs(dot(vec + 3 * top, z)), 1, 1e-12);
}

/* }====== */

/* The progress callback: about every 1% of the vertices, ending at 1, the
 * results the same as without; a cancel fails with FEMLOD_ECANCELLED and
 * stops calling. */
static void test_progress(void) {
    femlod_mesh *m = load_fandisk();
    size_t nv = femlod_mesh_vertex_count(m);
    double *a = calloc(2 * nv, sizeof(double)), *b = a + nv;
    CHECK(a != NULL);
    femlod_curvature_options o = FEMLOD_CURVATURE_OPTIONS_INIT;
    CHECK(femlod_mesh_curvature(m, &o, NULL, NULL, a, NULL, NULL, NULL) == FEMLOD_OK);
    check_progress pr = CHECK_PROGRESS_INIT;
    o.progress = check_progress_fn;
    o.progress_payload = &pr;
    CHECK(femlod_mesh_curvature(m, &o, NULL, NULL, b, NULL, NULL, NULL) == FEMLOD_OK);
    CHECK_PROGRESS_DONE(pr, 90);
    CHECK(memcmp(a, b, nv * sizeof(double)) == 0);
    check_progress stop = CHECK_PROGRESS_INIT;
    stop.stop_at = 10;
    o.progress_payload = &stop;
    femlod_error err;
    CHECK(femlod_mesh_curvature(m, &o, NULL, NULL, b, NULL, NULL, &err) == FEMLOD_ECANCELLED);
    CHECK(stop.calls == 10);
    CHECK(stop.last > 0.05 && stop.last < 0.15);
    CHECK(strcmp(err.message, "curvature: cancelled by the progress callback") == 0);
    free(a);
    femlod_mesh_free(m);
}

int main(void) {
    test_progress();
    test_sphere();
    test_jittered_sphere();
    test_hemisphere();
    test_cylinder();
    test_plane();
    test_fold();
    test_separate_sheets();
    test_scaling();
    test_fandisk_creases();
    test_determinism();
    test_degenerate_input();
    test_errors();
    test_eigen3();
    return check_report("test_curvature");
}
