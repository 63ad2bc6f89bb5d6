/*
 * imesh.c - the improvement stage's working mesh (docs/design.md "Improving a
 * mesh in place"): faces appended, never reused; per-vertex face lists;
 * feature edges as a hash set that the operators update; vertex classes
 * (free, line, fixed); the append-only box grid shared with surface.c.
 */
#include "impr.h"

#include <stdlib.h>
#include <string.h>

/* a box covering more cells than this goes to the grid's list of big items */
#define IM_BIG_CELLS 512

/* {====== the box grid */

int fl_imgrid_init(im_grid *g, const double lo[3], const double hi[3], double h, size_t max_cells) {
    memset(g, 0, sizeof *g);
    if (!(h > 0.0)) h = 1.0;
    for (;;) {
        size_t cells = 1;
        for (int k = 0; k < 3; k++) {
            double c = (hi[k] - lo[k]) / h;
            cells *= c < 1.0 ? 1 : (c > 1e6 ? 1000000 : (size_t)c + 1);
        }
        if (cells <= max_cells) break;
        h *= 1.25;
    }
    for (int k = 0; k < 3; k++) g->origin[k] = lo[k];
    for (int l = 0; l < IM_LEVELS; l++, h *= 8.0) {
        im_level *L = g->lv + l;
        for (int k = 0; k < 3; k++) {
            double c = (hi[k] - lo[k]) / h;
            L->n[k] = c < 1.0 ? 1 : (c > 1e6 ? 1000000 : (int)c + 1);
        }
        L->inv_h = 1.0 / h;
        size_t cells = (size_t)L->n[0] * (size_t)L->n[1] * (size_t)L->n[2];
        L->head = fl_alloc(cells, sizeof *L->head);
        if (!L->head) return 0;
        memset(L->head, 0xff, cells * sizeof *L->head);
    }
    return 1;
}

void fl_imgrid_free(im_grid *g) {
    for (int l = 0; l < IM_LEVELS; l++) free(g->lv[l].head);
    free(g->item);
    free(g->next);
    free(g->cell);
    free(g->big);
    memset(g, 0, sizeof *g);
}

static int coord(const im_grid *g, const im_level *L, double x, int k) {
    double c = (x - g->origin[k]) * L->inv_h;
    if (!(c > 0.0)) return 0;
    if (c >= (double)(L->n[k] - 1)) return L->n[k] - 1;
    return (int)c;
}

static size_t range(const im_grid *g, const im_level *L, const double lo[3], const double hi[3], int c0[3],
                    int c1[3]) {
    size_t cells = 1;
    for (int k = 0; k < 3; k++) {
        c0[k] = coord(g, L, lo[k], k);
        c1[k] = coord(g, L, hi[k], k);
        cells *= (size_t)(c1[k] - c0[k] + 1);
    }
    return cells;
}

int fl_imgrid_insert(im_grid *g, uint32_t item, const double lo[3], const double hi[3]) {
    int c0[3], c1[3];
    const im_level *L = NULL;
    size_t cells = 0;
    for (int l = 0; l < IM_LEVELS && !L; l++) {
        cells = range(g, g->lv + l, lo, hi, c0, c1);
        if (cells <= IM_BIG_CELLS) L = g->lv + l;
    }
    if (!L) {
        if (g->nbig == g->capbig) {
            size_t c = g->capbig ? 2 * g->capbig : 64;
            uint32_t *p = fl_realloc(g->big, c, sizeof *p);
            if (!p) return 0;
            g->big = p;
            g->capbig = c;
        }
        g->big[g->nbig++] = item;
        return 1;
    }
    if (g->ne + cells > g->cape) {
        size_t c = g->cape ? g->cape : 1024;
        while (c < g->ne + cells) c *= 2;
        uint32_t *a = fl_realloc(g->item, c, sizeof *a);
        if (!a) return 0;
        g->item = a;
        uint32_t *b = fl_realloc(g->next, c, sizeof *b);
        if (!b) return 0;
        g->next = b;
        uint32_t *d = fl_realloc(g->cell, c, sizeof *d);
        if (!d) return 0;
        g->cell = d;
        g->cape = c;
    }
    uint32_t lbits = (uint32_t)(L - g->lv) << 30;
    for (int z = c0[2]; z <= c1[2]; z++)
        for (int y = c0[1]; y <= c1[1]; y++)
            for (int x = c0[0]; x <= c1[0]; x++) {
                size_t cell = ((size_t)z * (size_t)L->n[1] + (size_t)y) * (size_t)L->n[0] + (size_t)x;
                size_t e = g->ne++;
                g->item[e] = item;
                g->next[e] = L->head[cell];
                g->cell[e] = lbits | (uint32_t)cell;
                L->head[cell] = (uint32_t)e;
            }
    return 1;
}

void fl_imgrid_rollback(im_grid *g, size_t ne, size_t nbig) {
    for (size_t e = g->ne; e-- > ne;) {
        im_level *L = g->lv + (g->cell[e] >> 30);
        L->head[g->cell[e] & 0x3fffffffu] = g->next[e];
    }
    if (ne < g->ne) g->ne = ne;
    if (nbig < g->nbig) g->nbig = nbig;
}

int fl_imgrid_query(const im_grid *g, const double lo[3], const double hi[3],
                    int (*fn)(void *payload, uint32_t item), void *payload) {
    for (size_t i = 0; i < g->nbig; i++) {
        int r = fn(payload, g->big[i]);
        if (r) return r;
    }
    for (int l = 0; l < IM_LEVELS; l++) {
        const im_level *L = g->lv + l;
        int c0[3], c1[3];
        range(g, L, lo, hi, c0, c1);
        for (int z = c0[2]; z <= c1[2]; z++)
            for (int y = c0[1]; y <= c1[1]; y++)
                for (int x = c0[0]; x <= c1[0]; x++) {
                    size_t cell = ((size_t)z * (size_t)L->n[1] + (size_t)y) * (size_t)L->n[0] + (size_t)x;
                    for (uint32_t e = L->head[cell]; e != IM_DEAD; e = g->next[e]) {
                        int r = fn(payload, g->item[e]);
                        if (r) return r;
                    }
                }
    }
    return 0;
}

/* }====== */

/* {====== feature edges */

static uint64_t ekey(uint32_t a, uint32_t b) {
    return a < b ? ((uint64_t)a << 32 | b) + 2 : ((uint64_t)b << 32 | a) + 2;
}

static size_t ehash(uint64_t k, size_t cap) {
    k ^= k >> 33;
    k *= 0xff51afd7ed558ccdULL;
    k ^= k >> 33;
    return (size_t)k & (cap - 1);
}

int fl_imesh_is_feature(const imesh *M, uint32_t a, uint32_t b) {
    uint64_t k = ekey(a, b);
    for (size_t i = ehash(k, M->fecap);; i = (i + 1) & (M->fecap - 1)) {
        if (M->fe[i] == k) return 1;
        if (M->fe[i] == 0) return 0;
    }
}

static int fe_grow(imesh *M) {
    size_t cap = M->fecap * 2;
    uint64_t *t = fl_calloc(cap, sizeof *t);
    if (!t) return 0;
    for (size_t i = 0; i < M->fecap; i++) {
        uint64_t k = M->fe[i];
        if (k < 2) continue;
        size_t j = ehash(k, cap);
        while (t[j]) j = (j + 1) & (cap - 1);
        t[j] = k;
    }
    free(M->fe);
    M->fe = t;
    M->fecap = cap;
    M->feused = M->fecount;
    return 1;
}

int fl_imesh_set_feature(imesh *M, uint32_t a, uint32_t b, int on) {
    uint64_t k = ekey(a, b);
    if (!on) {
        for (size_t i = ehash(k, M->fecap);; i = (i + 1) & (M->fecap - 1)) {
            if (M->fe[i] == k) {
                M->fe[i] = 1;
                M->fecount--;
                return 1;
            }
            if (M->fe[i] == 0) return 1;
        }
    }
    if (fl_imesh_is_feature(M, a, b)) return 1;
    if (2 * (M->feused + 1) > M->fecap && !fe_grow(M)) return 0;
    size_t i = ehash(k, M->fecap);
    while (M->fe[i] > 1) i = (i + 1) & (M->fecap - 1);
    if (M->fe[i] == 0) M->feused++;
    M->fe[i] = k;
    M->fecount++;
    return 1;
}

/* }====== */

uint32_t fl_imesh_next_stamp(imesh *M) {
    if (++M->stamp == 0) {
        memset(M->vmark, 0, M->capv * sizeof *M->vmark);
        memset(M->fmark, 0, M->capt * sizeof *M->fmark);
        M->stamp = 1;
    }
    return M->stamp;
}

size_t fl_imesh_edge_faces(const imesh *M, uint32_t a, uint32_t b, uint32_t *out, size_t max) {
    size_t n = 0;
    const im_list *l = M->vf + a;
    for (uint32_t i = 0; i < l->n; i++) {
        const uint32_t *t = M->tri + 3 * (size_t)l->f[i];
        if (t[0] == b || t[1] == b || t[2] == b) {
            if (n < max) out[n] = l->f[i];
            n++;
        }
    }
    return n;
}

int fl_imesh_has_edge(const imesh *M, uint32_t a, uint32_t b) {
    return fl_imesh_edge_faces(M, a, b, NULL, 0) > 0;
}

/* v's neighbours, each once; with features, only those across a feature edge */
static uint32_t count_neighbours(imesh *M, uint32_t v, int features) {
    uint32_t s = fl_imesh_next_stamp(M), n = 0;
    const im_list *l = M->vf + v;
    for (uint32_t i = 0; i < l->n; i++) {
        const uint32_t *t = M->tri + 3 * (size_t)l->f[i];
        for (int c = 0; c < 3; c++)
            if (t[c] != v && M->vmark[t[c]] != s) {
                M->vmark[t[c]] = s;
                n += !features || fl_imesh_is_feature(M, v, t[c]);
            }
    }
    return n;
}

uint32_t fl_imesh_valence(imesh *M, uint32_t v) { return count_neighbours(M, v, 0); }

uint32_t fl_imesh_feature_valence(imesh *M, uint32_t v) { return count_neighbours(M, v, 1); }

static int list_add(im_list *l, uint32_t f) {
    if (l->n == l->cap) {
        uint32_t c = l->cap ? 2 * l->cap : 8;
        uint32_t *p = fl_realloc(l->f, c, sizeof *p);
        if (!p) return 0;
        l->f = p;
        l->cap = c;
    }
    l->f[l->n++] = f;
    return 1;
}

/* keeps the list's order (a vertex's faces stay in slot order) */
static void list_remove(im_list *l, uint32_t f) {
    for (uint32_t i = 0; i < l->n; i++)
        if (l->f[i] == f) {
            memmove(l->f + i, l->f + i + 1, (l->n - i - 1) * sizeof *l->f);
            l->n--;
            return;
        }
}

static int grow_faces(imesh *M) {
    size_t c = M->capt * 2;
    uint32_t *t = fl_realloc(M->tri, 3 * c, sizeof *t);
    if (!t) return 0;
    M->tri = t;
    uint8_t *r = fl_realloc(M->freason, c, 1);
    if (!r) return 0;
    M->freason = r;
    uint32_t *m = fl_realloc(M->fmark, c, sizeof *m);
    if (!m) return 0;
    memset(m + M->capt, 0, (c - M->capt) * sizeof *m);
    M->fmark = m;
    M->capt = c;
    return 1;
}

/* Lists every live face again in a grid emptied of its entries: removed
 * and moved faces leave stale entries behind, which every query would walk.
 * Queries answer the same either way (they filter by the current faces and
 * break ties by index), so when this runs changes no result. */
static int regrid(imesh *M) {
    im_grid *g = &M->grid;
    for (int l = 0; l < IM_LEVELS; l++) {
        size_t cells = (size_t)g->lv[l].n[0] * (size_t)g->lv[l].n[1] * (size_t)g->lv[l].n[2];
        memset(g->lv[l].head, 0xff, cells * sizeof *g->lv[l].head);
    }
    g->ne = 0;
    g->nbig = 0;
    g->gen++;
    for (size_t f = 0; f < M->nt; f++) {
        const uint32_t *t = M->tri + 3 * f;
        if (t[0] == IM_DEAD) continue;
        double lo[3], hi[3];
        im_box(im_P(M, t[0]), im_P(M, t[1]), im_P(M, t[2]), lo, hi);
        if (!fl_imgrid_insert(g, (uint32_t)f, lo, hi)) return 0;
    }
    M->grid_ne0 = g->ne + g->nbig;
    return 1;
}

uint32_t fl_imesh_add_face(imesh *M, uint32_t a, uint32_t b, uint32_t c) {
    if (M->nt == M->capt && !grow_faces(M)) return IM_DEAD;
    if (M->nt >= UINT32_MAX - 1) return IM_DEAD;
    uint32_t f = (uint32_t)M->nt;
    uint32_t *t = M->tri + 3 * (size_t)f;
    t[0] = a;
    t[1] = b;
    t[2] = c;
    M->freason[f] = 0;
    M->fmark[f] = 0;
    if (!list_add(M->vf + a, f) || !list_add(M->vf + b, f) || !list_add(M->vf + c, f)) return IM_DEAD;
    double lo[3], hi[3];
    im_box(im_P(M, a), im_P(M, b), im_P(M, c), lo, hi);
    if (!fl_imgrid_insert(&M->grid, f, lo, hi)) return IM_DEAD;
    M->nt++;
    M->live++;
    if (M->grid.ne + M->grid.nbig > 2 * M->grid_ne0 + 65536 && !regrid(M)) return IM_DEAD;
    return f;
}

/* inserts f before the first larger slot: the list stays in slot order */
static int list_insert(im_list *l, uint32_t f) {
    if (!list_add(l, f)) return 0;
    uint32_t i = l->n - 1;
    while (i > 0 && l->f[i - 1] > f) {
        l->f[i] = l->f[i - 1];
        i--;
    }
    l->f[i] = f;
    return 1;
}

int fl_imesh_restore_face(imesh *M, uint32_t f, const uint32_t t[3], int into_grid) {
    uint32_t *d = M->tri + 3 * (size_t)f;
    memcpy(d, t, 3 * sizeof *d);
    for (int c = 0; c < 3; c++)
        if (!list_insert(M->vf + t[c], f)) return 0;
    M->live++;
    /* without into_grid its entries are still there: a rolled-back grid */
    if (!into_grid) return 1;
    double lo[3], hi[3];
    im_box(im_P(M, t[0]), im_P(M, t[1]), im_P(M, t[2]), lo, hi);
    return fl_imgrid_insert(&M->grid, f, lo, hi);
}

void fl_imesh_remove_face(imesh *M, uint32_t f) {
    uint32_t *t = M->tri + 3 * (size_t)f;
    for (int c = 0; c < 3; c++) list_remove(M->vf + t[c], f);
    t[0] = t[1] = t[2] = IM_DEAD;
    M->live--;
}

uint32_t fl_imesh_add_vertex(imesh *M, const double p[3], uint8_t cls) {
    if (M->nv == M->capv) {
        size_t c = M->capv * 2;
        double *pos = fl_realloc(M->pos, 3 * c, sizeof *pos);
        if (!pos) return IM_DEAD;
        M->pos = pos;
        uint8_t *vc = fl_realloc(M->vclass, c, 1);
        if (!vc) return IM_DEAD;
        M->vclass = vc;
        im_list *vf = fl_realloc(M->vf, c, sizeof *vf);
        if (!vf) return IM_DEAD;
        memset(vf + M->capv, 0, (c - M->capv) * sizeof *vf);
        M->vf = vf;
        uint32_t *vo = fl_realloc(M->vorig, 2 * (c - M->nv0), sizeof *vo);
        if (!vo) return IM_DEAD;
        M->vorig = vo;
        uint8_t *vd = fl_realloc(M->vdepth, c, 1);
        if (!vd) return IM_DEAD;
        memset(vd + M->capv, 0, c - M->capv);
        M->vdepth = vd;
        uint32_t *vm = fl_realloc(M->vmark, c, sizeof *vm);
        if (!vm) return IM_DEAD;
        memset(vm + M->capv, 0, (c - M->capv) * sizeof *vm);
        M->vmark = vm;
        M->capv = c;
    }
    if (M->nv >= UINT32_MAX - 1) return IM_DEAD;
    uint32_t v = (uint32_t)M->nv++;
    memcpy(M->pos + 3 * (size_t)v, p, 3 * sizeof *p);
    M->vclass[v] = cls;
    return v;
}

/* Feature edges from the input: sharp (normals apart by more than the
 * feature angle; cos_fa < -1: none), boundary, non-manifold; then the
 * classes from the count of feature edges at each vertex. */
static int find_features(imesh *M, double cos_fa, const uint8_t *locked) {
    uint8_t *nm = fl_calloc(M->nv ? M->nv : 1, 1);
    uint32_t *nfe = fl_calloc(M->nv ? M->nv : 1, sizeof *nfe);
    uint32_t ef[3];
    if (!nm || !nfe) {
        free(nm);
        free(nfe);
        return 0;
    }
    int ok = 1;
    for (uint32_t a = 0; a < M->nv && ok; a++) {
        const im_list *l = M->vf + a;
        for (uint32_t i = 0; i < l->n && ok; i++) {
            const uint32_t *t = M->tri + 3 * (size_t)l->f[i];
            for (int c = 0; c < 3; c++) {
                uint32_t b = t[c];
                if (b <= a) continue;
                /* each edge once: from its smaller end, at its first face there */
                if (fl_imesh_edge_faces(M, a, b, ef, 1) && ef[0] != l->f[i]) continue;
                size_t n = fl_imesh_edge_faces(M, a, b, ef, 3);
                int feat = 0;
                if (n != 2) {
                    feat = 1;
                    if (n > 2) nm[a] = nm[b] = 1;
                } else {
                    const uint32_t *p = M->tri + 3 * (size_t)ef[0], *q = M->tri + 3 * (size_t)ef[1];
                    double n1[3], n2[3];
                    im_normal(n1, im_P(M, p[0]), im_P(M, p[1]), im_P(M, p[2]));
                    im_normal(n2, im_P(M, q[0]), im_P(M, q[1]), im_P(M, q[2]));
                    double l1 = sqrt(dot3(n1, n1)), l2 = sqrt(dot3(n2, n2));
                    /* a degenerate face's edges are not features: its normal says nothing */
                    if (l1 > 0 && l2 > 0 && dot3(n1, n2) < cos_fa * l1 * l2) feat = 1;
                    /* faces running the same way round the edge: a fold, kept as a feature */
                    int pa = 0, pb = 0, qa = 0, qb = 0;
                    for (int k = 0; k < 3; k++) {
                        if (p[k] == a) pa = k;
                        if (p[k] == b) pb = k;
                        if (q[k] == a) qa = k;
                        if (q[k] == b) qb = k;
                    }
                    if ((pb == (pa + 1) % 3) == (qb == (qa + 1) % 3)) feat = 1;
                }
                if (feat) {
                    if (!fl_imesh_set_feature(M, a, b, 1)) ok = 0;
                    nfe[a]++;
                    nfe[b]++;
                }
            }
        }
    }
    for (uint32_t v = 0; v < M->nv; v++) {
        uint8_t c = IM_FREE;
        if (nfe[v] == 2) c = IM_LINE;
        else if (nfe[v] > 0) c = IM_FIXED;
        if (nm[v] || (locked && locked[v]) || M->vf[v].n == 0) c = IM_FIXED;
        M->vclass[v] = c;
    }
    free(nm);
    free(nfe);
    return ok;
}

int fl_imesh_init(imesh *M, const femlod_mesh *m, double feature_angle, const uint8_t *locked, double h) {
    memset(M, 0, sizeof *M);
    size_t nv = m->nv ? m->nv : 1, nt = m->nt ? m->nt : 1;
    M->capv = nv + nv / 4 + 16;
    M->capt = nt + nt / 4 + 16;
    M->pos = fl_alloc(3 * M->capv, sizeof *M->pos);
    M->vclass = fl_calloc(M->capv, 1);
    M->vf = fl_calloc(M->capv, sizeof *M->vf);
    M->vmark = fl_calloc(M->capv, sizeof *M->vmark);
    M->vdepth = fl_calloc(M->capv, 1);
    M->nv0 = m->nv;
    M->vorig = fl_alloc(2 * (M->capv - M->nv0), sizeof *M->vorig);
    M->tri = fl_alloc(3 * M->capt, sizeof *M->tri);
    M->freason = fl_calloc(M->capt, 1);
    M->fmark = fl_calloc(M->capt, sizeof *M->fmark);
    M->fecap = 1024;
    while (M->fecap < 2 * m->nt) M->fecap *= 2;
    M->fe = fl_calloc(M->fecap, sizeof *M->fe);
    if (!M->pos || !M->vclass || !M->vf || !M->vmark || !M->vdepth || !M->vorig || !M->tri || !M->freason || !M->fmark || !M->fe)
        return 0;
    if (m->nv) memcpy(M->pos, m->pos, 3 * m->nv * sizeof *M->pos);
    M->nv = m->nv;
    double lo[3], hi[3];
    femlod_mesh_bbox(m, lo, hi);
    double diag = sqrt(dist2(lo, hi));
    M->eps = 1e-10 * (diag > 0 ? diag : 1.0);
    /* room around the box: relaxed vertices stay on the input surface */
    for (int k = 0; k < 3; k++) {
        lo[k] -= 1e-6 * diag;
        hi[k] += 1e-6 * diag;
    }
    size_t cells = 2 * m->nt + 64;
    if (cells > ((size_t)1 << 22)) cells = (size_t)1 << 22;
    if (!fl_imgrid_init(&M->grid, lo, hi, h, cells)) return 0;
    for (size_t f = 0; f < m->nt; f++) {
        const uint32_t *t = m->tri + 3 * f;
        /* a repeated corner is no triangle: dropped */
        if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) continue;
        if (fl_imesh_add_face(M, t[0], t[1], t[2]) == IM_DEAD) return 0;
    }
    M->grid_ne0 = M->grid.ne + M->grid.nbig;
    double cos_fa = feature_angle < 0 ? -2.0 : cos(feature_angle * 3.14159265358979323846 / 180.0);
    return find_features(M, cos_fa, locked);
}

void fl_imesh_free(imesh *M) {
    if (M->vf)
        for (size_t v = 0; v < M->capv; v++) free(M->vf[v].f);
    free(M->vf);
    free(M->pos);
    free(M->vclass);
    free(M->vmark);
    free(M->vorig);
    free(M->vdepth);
    free(M->tri);
    free(M->freason);
    free(M->fmark);
    free(M->fe);
    fl_imgrid_free(&M->grid);
    memset(M, 0, sizeof *M);
}
