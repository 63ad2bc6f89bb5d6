#include "cad_shapes.h"

#include <math.h>
#include <stdlib.h>

#define PI 3.14159265358979323846

typedef struct gen {
    double *p;
    uint32_t *t;
    size_t nv, nt, capv, capt;
} gen;

static uint32_t vtx(gen *g, double x, double y, double z) {
    if (g->nv == g->capv) {
        g->capv = g->capv ? 2 * g->capv : 64;
        g->p = realloc(g->p, 3 * g->capv * sizeof *g->p);
    }
    g->p[3 * g->nv] = x;
    g->p[3 * g->nv + 1] = y;
    g->p[3 * g->nv + 2] = z;
    return (uint32_t)g->nv++;
}

static void tri(gen *g, uint32_t a, uint32_t b, uint32_t c) {
    if (g->nt == g->capt) {
        g->capt = g->capt ? 2 * g->capt : 64;
        g->t = realloc(g->t, 3 * g->capt * sizeof *g->t);
    }
    g->t[3 * g->nt] = a;
    g->t[3 * g->nt + 1] = b;
    g->t[3 * g->nt + 2] = c;
    g->nt++;
}

/* quad a b c d counter-clockwise */
static void quad(gen *g, uint32_t a, uint32_t b, uint32_t c, uint32_t d) {
    tri(g, a, b, c);
    tri(g, a, c, d);
}

static femlod_mesh *finish(gen *g) {
    femlod_mesh *m = NULL;
    femlod_mesh_create(&m, g->p, g->nv, g->t, g->nt, NULL);
    free(g->p);
    free(g->t);
    return m;
}

femlod_mesh *cad_cylinder_fans(unsigned n, double h) {
    gen g = {0};
    uint32_t c0 = vtx(&g, 0, 0, 0), c1 = vtx(&g, 0, 0, h);
    for (unsigned i = 0; i < n; i++) {
        double a = 2 * PI * i / n;
        vtx(&g, cos(a), sin(a), 0);
        vtx(&g, cos(a), sin(a), h);
    }
    for (unsigned i = 0; i < n; i++) {
        uint32_t b0 = 2 + 2 * i, t0 = b0 + 1, b1 = 2 + 2 * ((i + 1) % n), t1 = b1 + 1;
        quad(&g, b0, b1, t1, t0);
        tri(&g, c0, b1, b0);
        tri(&g, c1, t0, t1);
    }
    return finish(&g);
}

femlod_mesh *cad_cone_fans(unsigned n, double h) {
    gen g = {0};
    uint32_t c0 = vtx(&g, 0, 0, 0), ap = vtx(&g, 0, 0, h);
    for (unsigned i = 0; i < n; i++) {
        double a = 2 * PI * i / n;
        vtx(&g, cos(a), sin(a), 0);
    }
    for (unsigned i = 0; i < n; i++) {
        uint32_t b0 = 2 + i, b1 = 2 + (i + 1) % n;
        tri(&g, b0, b1, ap);
        tri(&g, c0, b1, b0);
    }
    return finish(&g);
}

femlod_mesh *cad_bracket(unsigned arc, double w) {
    /* profile in (x, z), counter-clockwise: outer leg down the z axis side,
     * the outer fillet, the bottom leg, back along the inner side */
    double r = 0.3, t = 0.1, L = 1.0;
    double px[256], pz[256];
    unsigned np = 0;
    /* outer: from (0, L) down to the fillet, round, out to (L, 0) */
    px[np] = 0, pz[np++] = L;
    for (unsigned i = 0; i <= arc; i++) {
        double a = PI + 0.5 * PI * i / arc;
        px[np] = r + r * cos(a), pz[np++] = r + r * sin(a);
    }
    px[np] = L, pz[np++] = 0;
    px[np] = L, pz[np++] = t;
    /* inner: fillet of radius r - t, back to (t, L) */
    for (unsigned i = 0; i <= arc; i++) {
        double a = 1.5 * PI - 0.5 * PI * i / arc;
        px[np] = r + (r - t) * cos(a), pz[np++] = r + (r - t) * sin(a);
    }
    px[np] = t, pz[np++] = L;
    gen g = {0};
    for (unsigned i = 0; i < np; i++) {
        vtx(&g, px[i], 0, pz[i]);
        vtx(&g, px[i], w, pz[i]);
    }
    for (unsigned i = 0; i < np; i++) {
        unsigned j = (i + 1) % np;
        quad(&g, 2 * i, 2 * i + 1, 2 * j + 1, 2 * j);
    }
    /* ends: the profile is the union of quads (outer i, inner) across the
     * thickness: outer point k pairs with inner point np - 1 - k */
    unsigned half = np / 2;
    for (unsigned k = 0; k + 1 < half; k++) {
        unsigned o0 = k, o1 = k + 1, i0 = np - 1 - k, i1 = np - 2 - k;
        tri(&g, 2 * o0, 2 * o1, 2 * i1);
        tri(&g, 2 * o0, 2 * i1, 2 * i0);
        tri(&g, 2 * o0 + 1, 2 * i1 + 1, 2 * o1 + 1);
        tri(&g, 2 * o0 + 1, 2 * i0 + 1, 2 * i1 + 1);
    }
    return finish(&g);
}

femlod_mesh *cad_tjoin(unsigned n) {
    gen g = {0};
    for (unsigned i = 0; i <= n; i++) vtx(&g, (double)i / n, 0, 0);
    for (unsigned i = 0; i <= n; i++) vtx(&g, (double)i / n, 0.5, 0);
    uint32_t tl = vtx(&g, 0, 1, 0), tr = vtx(&g, 1, 1, 0);
    for (unsigned i = 0; i < n; i++) quad(&g, i, i + 1, n + 2 + i, n + 1 + i);
    /* the join's points: the left half fans to tl, the right half to tr */
    for (unsigned i = 0; i < n; i++) {
        uint32_t a = n + 1 + i, b = a + 1;
        tri(&g, a, b, i < n / 2 ? tl : tr);
    }
    tri(&g, n + 1 + n / 2, tr, tl);
    return finish(&g);
}

femlod_mesh *cad_thin_plate(unsigned n, double side, double thick) {
    gen g = {0};
    for (int s = 0; s < 2; s++)
        for (unsigned j = 0; j <= n; j++)
            for (unsigned i = 0; i <= n; i++) vtx(&g, side * i / n, side * j / n, s ? thick : 0);
    unsigned row = n + 1, top = row * row;
#define V(s, i, j) ((uint32_t)((s) * top + (j) * row + (i)))
    for (unsigned j = 0; j < n; j++)
        for (unsigned i = 0; i < n; i++) {
            quad(&g, V(1, i, j), V(1, i + 1, j), V(1, i + 1, j + 1), V(1, i, j + 1));
            quad(&g, V(0, i, j), V(0, i, j + 1), V(0, i + 1, j + 1), V(0, i + 1, j));
        }
    for (unsigned i = 0; i < n; i++) {
        quad(&g, V(0, i, 0), V(0, i + 1, 0), V(1, i + 1, 0), V(1, i, 0));
        quad(&g, V(0, i + 1, n), V(0, i, n), V(1, i, n), V(1, i + 1, n));
        quad(&g, V(0, 0, i + 1), V(0, 0, i), V(1, 0, i), V(1, 0, i + 1));
        quad(&g, V(0, n, i), V(0, n, i + 1), V(1, n, i + 1), V(1, n, i));
    }
#undef V
    return finish(&g);
}

femlod_mesh *cad_holes(unsigned n) {
    gen g = {0};
    unsigned row = n + 1;
    for (unsigned j = 0; j <= n; j++)
        for (unsigned i = 0; i <= n; i++) vtx(&g, (double)i / n, (double)j / n, 0);
    for (unsigned j = 0; j < n; j++) {
        if (j % 2 == 0) {
            /* a row without holes: one long strip of two triangles per two
             * cells, the CAD way */
            for (unsigned i = 0; i < n; i += 2) {
                unsigned i2 = i + 2 <= n ? i + 2 : n;
                uint32_t a = j * row + i, b = j * row + i2, c = (j + 1) * row + i2, d = (j + 1) * row + i;
                /* the middle points of the strip's long sides join in fans */
                uint32_t mb = j * row + i + 1, mt = (j + 1) * row + i + 1;
                if (i2 == i + 2) {
                    tri(&g, a, mb, d);
                    tri(&g, mb, mt, d);
                    tri(&g, mb, b, mt);
                    tri(&g, b, c, mt);
                } else
                    quad(&g, a, b, c, d);
            }
        } else {
            for (unsigned i = 0; i < n; i++) {
                if (i % 2 == 1) continue; /* a hole */
                uint32_t a = j * row + i, b = a + 1, c = b + row, d = a + row;
                quad(&g, a, b, c, d);
            }
        }
    }
    return finish(&g);
}
