/*
 * curvature.c - per-vertex principal curvatures and directions from the
 * normal-cycle curvature tensor (paper 5.3.1; method-notes.md, "Adaptive
 * LOD (5.3)"; docs/curvature.md has the derivation and measured accuracy).
 *
 * The estimator is Cohen-Steiner and Morvan's ("Restricted Delaunay
 * triangulations and normal cycle", SoCG 2003), as Alliez, Cohen-Steiner,
 * Devillers, Levy and Desbrun use it ("Anisotropic polygonal remeshing",
 * SIGGRAPH 2003):
 *
 *     T(v) = 1/|B| * sum over edges e of beta(e) |e cap B| ebar ebar^T
 *
 * where B is a neighbourhood of v, |B| its area, beta(e) the signed angle
 * between the normals of e's two triangles (positive where the surface is
 * convex with respect to its orientation) and ebar the unit direction of e.
 * An edge bends the surface *across* itself, so the eigenvector of the
 * largest eigenvalue points along the direction of least curvature and the
 * eigenvalues are swapped: on a cylinder of radius R the edges along the
 * axis carry all the bending, T = (1/R) z z^T, and 1/R is the curvature
 * around the axis, perpendicular to z.
 *
 * B is the part of the surface inside the ball of radius r around v that
 * is connected to v: a breadth-first walk over triangles from v's own,
 * crossing every edge that meets the ball. Two departures from the papers'
 * plain ball, both measured (vertex_curvature; docs/curvature.md has the
 * tables): |B| is measured through the same edges as the bending (edge e
 * stands for A(e), a third of the area of each of its triangles), and every
 * length and area in B is weighted by 1 - |x - v|^2 / r^2, which falls to
 * 0 at the ball's surface, instead of 1 inside and 0 outside:
 *
 *     T(v) = sum_e beta(e) W(e) ebar ebar^T / sum_e A(e) W(e) / |e|,
 *     W(e) = integral over e cap B of (1 - |x - v|^2 / r^2) dx.
 *
 * The papers read the normal off the eigenvector whose eigenvalue is
 * nearest 0. That is ambiguous wherever a principal curvature is 0
 * (cylinder, plane, the flat side of a crease): the zero eigenspace is then
 * a plane holding both the normal and a principal direction. We take the
 * normal from the surface instead (the area-weighted normal of B) and solve
 * the 2x2 problem of T restricted to the tangent plane, which agrees with
 * the papers' rule where that is unambiguous (up to T's small normal
 * component) and stays well defined where it is not. Only when the
 * area-weighted normal vanishes (a sheet folded onto itself) does the
 * papers' rule decide, through a Jacobi eigensolver.
 */
#include "core.h"
#include "vec3.h"

#include <assert.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* The quality report's definition of a degenerate triangle (femlod.h):
 * such a triangle has no trustworthy normal, so it has no area, no normal
 * and no say in any dihedral angle. */
#define DEGENERATE_STRETCH 1e-6

/* {====== small vector algebra */




/* Scales v to unit length; returns 0 (v unchanged) when it has none. */
static int normalize3(double v[3]) {
    double l = sqrt(dot3(v, v));
    if (!(l > 0.0) || !isfinite(l)) return 0;
    v[0] /= l;
    v[1] /= l;
    v[2] /= l;
    return 1;
}

/* }====== */

/* {====== the weight of an edge */

/* W = the integral over the part of segment pq inside the ball
 * |x - c|^2 <= r2 of the weight 1 - |x - c|^2 / r2; *length gets |pq|.
 * With s the arc length from the point of the line nearest c (at distance
 * sqrt(m2)), |x - c|^2 = m2 + s^2 and the integral is a cubic in the ends
 * s0, s1 of the clipped piece; written around that point it never
 * subtracts large numbers, however long or far the edge. */
static double edge_weight(const double p[3], const double q[3], const double c[3], double r2,
                          double *length) {
    double f[3], u[3];
    sub3(f, p, c);
    sub3(u, q, p);
    double len = sqrt(dot3(u, u));
    *length = len;
    if (!(len > 0.0)) return 0.0;
    for (int k = 0; k < 3; k++) u[k] /= len;
    double a = -dot3(f, u); /* p + a u is the nearest point */
    double x[3] = {f[0] + a * u[0], f[1] + a * u[1], f[2] + a * u[2]};
    double m2 = dot3(x, x);
    if (!(m2 < r2)) return 0.0;
    double rho2 = r2 - m2, rho = sqrt(rho2);
    double s0 = -a > -rho ? -a : -rho, s1 = len - a < rho ? len - a : rho;
    if (!(s1 > s0)) return 0.0;
    double w = (s1 - s0) * (rho2 - (s1 * s1 + s1 * s0 + s0 * s0) / 3.0) / r2;
    return w > 0.0 ? w : 0.0;
}

/* }====== */

/* {====== eigenproblems */

void fl_curvature_eigen3(const double m[6], double value[3], double vector[9]) {
    /* Cyclic Jacobi: each rotation zeroes one off-diagonal entry and the
     * off-diagonal mass falls quadratically; a 3x3 converges to rounding in
     * a handful of sweeps (the cap is a guard, never reached in the tests).
     * Non-finite input stops at once and comes back as it went in. */
    double a[3][3] = {{m[0], m[1], m[2]}, {m[1], m[3], m[4]}, {m[2], m[4], m[5]}};
    double v[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    static const int pairs[3][2] = {{0, 1}, {0, 2}, {1, 2}};
    for (int sweep = 0; sweep < 64; sweep++) {
        /* sums of magnitudes, not squares: squares of tiny entries underflow */
        double off = fabs(a[0][1]) + fabs(a[0][2]) + fabs(a[1][2]);
        double diag = fabs(a[0][0]) + fabs(a[1][1]) + fabs(a[2][2]);
        if (!(off > 1e-18 * diag) || !isfinite(off)) break;
        for (int k = 0; k < 3; k++) {
            int p = pairs[k][0], q = pairs[k][1];
            if (a[p][q] == 0.0) continue;
            /* tan of the angle that zeroes a[p][q], the smaller root */
            double theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
            double t = fabs(theta) > 1e150 ? 0.5 / fabs(theta) /* theta^2 would overflow */
                                           : 1.0 / (fabs(theta) + sqrt(theta * theta + 1.0));
            if (theta < 0.0) t = -t;
            double c = 1.0 / sqrt(t * t + 1.0), s = t * c;
            for (int i = 0; i < 3; i++) { /* A J */
                double ip = a[i][p], iq = a[i][q];
                a[i][p] = c * ip - s * iq;
                a[i][q] = s * ip + c * iq;
            }
            for (int i = 0; i < 3; i++) { /* J^T (A J) */
                double pi = a[p][i], qi = a[q][i];
                a[p][i] = c * pi - s * qi;
                a[q][i] = s * pi + c * qi;
            }
            a[p][q] = a[q][p] = 0.0;
            for (int i = 0; i < 3; i++) {
                double ip = v[i][p], iq = v[i][q];
                v[i][p] = c * ip - s * iq;
                v[i][q] = s * ip + c * iq;
            }
        }
    }
    for (int k = 0; k < 3; k++) {
        value[k] = a[k][k];
        for (int i = 0; i < 3; i++) vector[3 * k + i] = v[i][k];
    }
}

/* The symmetric 2x2 [[a, b], [b, c]]: eigenvalues hi >= lo, and the angle of
 * hi's eigenvector. atan2 gives the right quadrant for every sign of b and
 * a - c, and the value pair never loses the digits a cubic formula would. */
static void eigen2(double a, double b, double c, double *hi, double *lo, double *angle) {
    double mean = 0.5 * (a + c), rad = hypot(0.5 * (a - c), b);
    *hi = mean + rad;
    *lo = mean - rad;
    *angle = 0.5 * atan2(2.0 * b, a - c);
}

/* (u^T M v) for the symmetric M stored as xx, xy, xz, yy, yz, zz. */
static double form(const double m[6], const double u[3], const double v[3]) {
    double mv[3] = {m[0] * v[0] + m[1] * v[1] + m[2] * v[2],
                    m[1] * v[0] + m[3] * v[1] + m[4] * v[2],
                    m[2] * v[0] + m[4] * v[1] + m[5] * v[2]};
    return dot3(u, mv);
}

/* A unit vector perpendicular to unit n, chosen by n alone. */
static void perpendicular(double out[3], const double n[3]) {
    int k = 0;
    for (int i = 1; i < 3; i++)
        if (fabs(n[i]) < fabs(n[k])) k = i;
    double axis[3] = {0, 0, 0};
    axis[k] = 1.0;
    cross3(out, n, axis);
    normalize3(out);
}

/* Principal curvatures and directions of vertex v from its tensor T (already
 * divided by |B|) and its unit normal n (NULL: unknown). */
typedef struct principal {
    double k1, k2;
    double dir1[3], dir2[3];
} principal;

static void principal_of(principal *out, const double t[6], const double *normal) {
    double n[3], db[3], hi, lo;
    if (normal) {
        memcpy(n, normal, sizeof n);
        double u[3], w[3], da[3], angle;
        perpendicular(u, n);
        cross3(w, n, u);
        eigen2(form(t, u, u), form(t, u, w), form(t, w, w), &hi, &lo, &angle);
        double cs = cos(angle), sn = sin(angle);
        for (int i = 0; i < 3; i++) da[i] = cs * u[i] + sn * w[i];
        cross3(db, n, da);
    } else {
        /* The papers' rule: the normal is the eigenvector whose eigenvalue is
         * nearest 0; ties go to the lower index, so the result repeats. */
        double value[3], vector[9];
        fl_curvature_eigen3(t, value, vector);
        int in = 0;
        for (int k = 1; k < 3; k++)
            if (fabs(value[k]) < fabs(value[in])) in = k;
        int ia = (in + 1) % 3, ib = (in + 2) % 3;
        if (value[ib] > value[ia]) {
            int x = ia;
            ia = ib;
            ib = x;
        }
        hi = value[ia];
        lo = value[ib];
        memcpy(n, vector + 3 * in, sizeof n);
        memcpy(db, vector + 3 * ib, sizeof db);
    }
    /* The swap: the surface bends most across the direction of hi's
     * eigenvector, that is along db. */
    out->k1 = hi;
    out->k2 = lo;
    /* A direction is a line: fix its sign so that results read the same
     * on every run (largest component positive, the first on a tie). */
    int big = 0;
    for (int i = 1; i < 3; i++)
        if (fabs(db[i]) > fabs(db[big])) big = i;
    double sign = db[big] < 0.0 ? -1.0 : 1.0;
    for (int i = 0; i < 3; i++) out->dir1[i] = sign * db[i];
    normalize3(out->dir1);
    cross3(out->dir2, n, out->dir1);
    normalize3(out->dir2);
}

/* }====== */

/* {====== the per-mesh data and the walk */

typedef struct curv_state {
    const femlod_mesh *mesh;
    fl_adjacency adj;
    double *unit_normal; /* 3*nt, zero for a degenerate triangle */
    double *area;        /* nt, zero for a degenerate triangle */
    /* Per edge: the signed dihedral angle (0 where none), the share of
     * area the edge stands for (a third of each of its triangles') and the
     * matching share of area-weighted normal. */
    double *beta;        /* ne */
    double *edge_area;   /* ne */
    double *edge_normal; /* 3*ne */
    uint32_t *tri_mark;  /* nt: the vertex (+1) whose walk last reached it */
    uint32_t *edge_mark; /* ne: likewise */
    uint32_t *queue;     /* nt */
} curv_state;

static void state_free(curv_state *s) {
    fl_adjacency_free(&s->adj);
    free(s->unit_normal);
    free(s->area);
    free(s->beta);
    free(s->edge_area);
    free(s->edge_normal);
    free(s->tri_mark);
    free(s->edge_mark);
    free(s->queue);
}

/* Side of triangle t that is edge e, or -1. */
static int side_of(const fl_adjacency *adj, uint32_t t, uint32_t e) {
    for (int i = 0; i < 3; i++)
        if (adj->tri_edges[3 * (size_t)t + (size_t)i] == e) return i;
    return -1;
}

/* beta(e): the angle from the normal of its first triangle t1 to that of its
 * second t2, signed positive when t2 bends away from t1's normal (a convex
 * fold). With u the edge as t1 runs it, (n1 x n2) . u = sin(beta), the sign
 * Alliez et al. and Peyre's reference code use. An edge whose triangles run
 * it the same way (inconsistent orientation) takes t2's normal flipped: the
 * angle is then measured against t1's orientation. */
static double dihedral(const curv_state *s, uint32_t e, uint32_t t1, uint32_t t2) {
    const uint32_t *tri = s->mesh->tri;
    const double *pos = s->mesh->pos;
    int i1 = side_of(&s->adj, t1, e), i2 = side_of(&s->adj, t2, e);
    assert(i1 >= 0 && i2 >= 0);
    uint32_t from = tri[3 * (size_t)t1 + (size_t)i1];
    uint32_t to = tri[3 * (size_t)t1 + (size_t)(i1 + 1) % 3];
    double n1[3], n2[3], u[3], c[3];
    memcpy(n1, s->unit_normal + 3 * (size_t)t1, sizeof n1);
    memcpy(n2, s->unit_normal + 3 * (size_t)t2, sizeof n2);
    if (tri[3 * (size_t)t2 + (size_t)i2] == from)
        for (int k = 0; k < 3; k++) n2[k] = -n2[k];
    sub3(u, pos + 3 * (size_t)to, pos + 3 * (size_t)from);
    if (!normalize3(u)) return 0.0;
    cross3(c, n1, n2);
    return atan2(dot3(c, u), dot3(n1, n2));
}

static femlod_status state_init(curv_state *s, const femlod_mesh *m, femlod_error *err) {
    memset(s, 0, sizeof *s);
    s->mesh = m;
    femlod_status st = fl_adjacency_build(&s->adj, m->tri, m->nt, m->nv, err);
    if (st != FEMLOD_OK) return st;
    /* nt and ne are at most UINT32_MAX (adjacency): the products fit. */
    size_t nt = m->nt, ne = s->adj.ne;
    s->unit_normal = fl_alloc(3 * nt, sizeof(double));
    s->area = fl_alloc(nt, sizeof(double));
    s->beta = fl_alloc(ne, sizeof(double));
    s->edge_area = fl_alloc(ne, sizeof(double));
    s->edge_normal = fl_alloc(3 * ne, sizeof(double));
    s->tri_mark = fl_calloc(nt, sizeof(uint32_t));
    s->edge_mark = fl_calloc(ne, sizeof(uint32_t));
    s->queue = fl_alloc(nt, sizeof(uint32_t));
    if (!s->unit_normal || !s->area || !s->beta || !s->edge_area || !s->edge_normal ||
        !s->tri_mark || !s->edge_mark || !s->queue)
        return fl_error(err, FEMLOD_ENOMEM, "curvature: out of memory");

    const double *pos = m->pos;
    for (size_t t = 0; t < nt; t++) {
        const uint32_t *c = m->tri + 3 * t;
        const double *p0 = pos + 3 * (size_t)c[0], *p1 = pos + 3 * (size_t)c[1],
                     *p2 = pos + 3 * (size_t)c[2];
        double *n = s->unit_normal + 3 * t;
        double u[3], v[3];
        sub3(u, p1, p0);
        sub3(v, p2, p0);
        cross3(n, u, v);
        double twice = sqrt(dot3(n, n));
        int degenerate = c[0] == c[1] || c[1] == c[2] || c[2] == c[0] ||
                         femlod_triangle_stretch(p0, p1, p2) < DEGENERATE_STRETCH ||
                         !normalize3(n);
        if (degenerate) {
            n[0] = n[1] = n[2] = 0.0;
            s->area[t] = 0.0;
        } else {
            s->area[t] = 0.5 * twice;
        }
    }
    for (size_t e = 0; e < ne; e++) {
        uint32_t good[2];
        int count = 0;
        double a = 0.0, n[3] = {0, 0, 0};
        for (uint32_t k = s->adj.edge_start[e]; k < s->adj.edge_start[e + 1]; k++) {
            uint32_t t = s->adj.edge_tris[k];
            if (!(s->area[t] > 0.0)) continue;
            if (count < 2) good[count] = t;
            count++;
            double third = s->area[t] / 3.0;
            a += third;
            for (int i = 0; i < 3; i++) n[i] += third * s->unit_normal[3 * (size_t)t + (size_t)i];
        }
        /* Boundary edges (one proper triangle) have no dihedral angle and
         * non-manifold ones (three or more) no single one: no bending. */
        s->beta[e] = count == 2 ? dihedral(s, (uint32_t)e, good[0], good[1]) : 0.0;
        s->edge_area[e] = a;
        memcpy(s->edge_normal + 3 * e, n, sizeof n);
    }
    return FEMLOD_OK;
}

/* 2 x the mean length of the distinct edges; 0 without edges. */
static double default_radius(const curv_state *s) {
    const fl_adjacency *adj = &s->adj;
    if (adj->ne == 0) return 0.0;
    double sum = 0.0;
    for (size_t e = 0; e < adj->ne; e++) {
        double d[3];
        sub3(d, s->mesh->pos + 3 * (size_t)adj->edge_v[2 * e],
             s->mesh->pos + 3 * (size_t)adj->edge_v[2 * e + 1]);
        sum += sqrt(dot3(d, d));
    }
    return 2.0 * sum / (double)adj->ne;
}

/* Walks B(v, r) and fills the principal curvatures of v; returns 0 when v
 * has no neighbourhood of positive area (no usable triangle, or r == 0).
 *
 * Why not the papers' plain ball with the exact area of the surface inside
 * it, which we implemented first: on a fine icosphere (10242 vertices) with
 * r = 2 mean edges, its worst vertex is 5.3% off 1/R. Edges crowd at the
 * centre vertex, so a ball centred there holds more edge length per area
 * than the mesh has on average: +3.5% on the mean curvature, swinging to
 * -2% at r = 2.5 edges as rings of vertices cross the ball's surface.
 * Measuring |B| through the same edges cancels the crowding (worst vertex
 * 1.7% at r = 2, but 5.6% at r = 1.75, where a ring of vertices sits on
 * the surface); the weight that falls to 0 at the surface removes the jump
 * when a vertex crosses it (worst vertex 1.0%, and below 2% for every r
 * from 1 to 5 edges; on an icosphere with jittered vertices 2.5% where the
 * plain ball gives 14%). */
static int vertex_curvature(curv_state *s, uint32_t v, double r, principal *out) {
    const fl_adjacency *adj = &s->adj;
    const femlod_mesh *m = s->mesh;
    const double *c = m->pos + 3 * (size_t)v;
    const double r2 = r * r;
    const uint32_t mark = v + 1; /* v < nv <= UINT32_MAX - 1 (adjacency) */
    size_t head = 0, tail = 0;
    /* Fixed walk order (v's triangles increasing, sides in corner order, an
     * edge's triangles increasing): the sums, and so the results, repeat
     * bit for bit. */
    for (uint32_t k = adj->vert_start[v]; k < adj->vert_start[v + 1]; k++) {
        uint32_t t = adj->vert_tris[k];
        s->tri_mark[t] = mark;
        s->queue[tail++] = t;
    }
    double tensor[6] = {0, 0, 0, 0, 0, 0}, normal[3] = {0, 0, 0}, area = 0.0;
    while (head < tail) {
        uint32_t t = s->queue[head++];
        for (int i = 0; i < 3; i++) {
            uint32_t e = adj->tri_edges[3 * (size_t)t + (size_t)i];
            if (e == UINT32_MAX || s->edge_mark[e] == mark) continue;
            s->edge_mark[e] = mark;
            const double *p = m->pos + 3 * (size_t)adj->edge_v[2 * (size_t)e];
            const double *q = m->pos + 3 * (size_t)adj->edge_v[2 * (size_t)e + 1];
            double full, weight = edge_weight(p, q, c, r2, &full);
            if (!(weight > 0.0)) continue;
            double frac = weight / full;
            area += frac * s->edge_area[e];
            const double *en = s->edge_normal + 3 * (size_t)e;
            for (int k = 0; k < 3; k++) normal[k] += frac * en[k];
            if (s->beta[e] != 0.0) {
                double w = s->beta[e] * weight, u[3];
                sub3(u, q, p);
                for (int k = 0; k < 3; k++) u[k] /= full;
                tensor[0] += w * u[0] * u[0];
                tensor[1] += w * u[0] * u[1];
                tensor[2] += w * u[0] * u[2];
                tensor[3] += w * u[1] * u[1];
                tensor[4] += w * u[1] * u[2];
                tensor[5] += w * u[2] * u[2];
            }
            for (uint32_t k = adj->edge_start[e]; k < adj->edge_start[e + 1]; k++) {
                uint32_t t2 = adj->edge_tris[k];
                if (s->tri_mark[t2] == mark) continue;
                s->tri_mark[t2] = mark;
                s->queue[tail++] = t2;
            }
        }
    }
    if (!(area > 0.0)) return 0;
    for (int i = 0; i < 6; i++) tensor[i] /= area;
    /* The weights add up to area; a normal sum this short is a sheet folded
     * onto itself, where only the tensor can tell where it faces. */
    double len = sqrt(dot3(normal, normal));
    int have_normal = len > 1e-9 * area && normalize3(normal);
    principal_of(out, tensor, have_normal ? normal : NULL);
    return 1;
}

/* }====== */

femlod_status femlod_mesh_curvature(const femlod_mesh *mesh,
                                    const femlod_curvature_options *options, double *k1,
                                    double *k2, double *kappa, double *dir1, double *dir2,
                                    femlod_error *err) {
    assert(mesh);
    femlod_curvature_options opt = FEMLOD_CURVATURE_OPTIONS_INIT;
    if (options) opt = *options;
    if (isnan(opt.radius)) /* printf spells NaN "nan" or "-nan" by its sign bit */
        return fl_error(err, FEMLOD_EINPUT,
                        "curvature: radius must be a finite number >= 0 (got nan)");
    if (!(opt.radius >= 0.0) || !isfinite(opt.radius))
        return fl_error(err, FEMLOD_EINPUT,
                        "curvature: radius must be a finite number >= 0 (got %g)", opt.radius);
    if (!k1 && !k2 && !kappa && !dir1 && !dir2) return FEMLOD_OK;

    curv_state s;
    femlod_status st = state_init(&s, mesh, err);
    if (st != FEMLOD_OK) {
        state_free(&s);
        return st;
    }
    double r = opt.radius > 0.0 ? opt.radius : default_radius(&s);
    fl_progress prog;
    fl_progress_init(&prog, opt.progress, opt.progress_payload, mesh->nv);
    for (size_t v = 0; v < mesh->nv; v++) {
        if (fl_progress_at(&prog, v)) {
            state_free(&s);
            return fl_progress_cancelled(err, "curvature");
        }
        principal p;
        if (!vertex_curvature(&s, (uint32_t)v, r, &p)) memset(&p, 0, sizeof p);
        if (k1) k1[v] = p.k1;
        if (k2) k2[v] = p.k2;
        if (kappa) kappa[v] = fmax(fabs(p.k1), fabs(p.k2));
        if (dir1) memcpy(dir1 + 3 * v, p.dir1, sizeof p.dir1);
        if (dir2) memcpy(dir2 + 3 * v, p.dir2, sizeof p.dir2);
    }
    state_free(&s);
    fl_progress_end(&prog);
    return FEMLOD_OK;
}
