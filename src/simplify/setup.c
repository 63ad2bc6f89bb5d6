/*
 * setup.c - the run's state from the input mesh (paper 4.1), and the
 * per-thread views of it.
 *
 *   fl_simp_setup_mesh      vertex slots in Morton order of position
 *                           (morton_slots), faces in the order of their
 *                           least slot, vertex -> face lists, face caches,
 *                           the edge table (edge_part) with valences and
 *                           the orientation flag; measures the input
 *   fl_simp_setup_features  boundary, non-manifold and pinched vertices
 *                           (fan_is_one), the plane quadrics (4.1 (2)-(4),
 *                           plane_quadrics), feature edges (edge_sharpness)
 *                           and their line quadrics, fixed vertices and
 *                           locks, normal cones, deviation lists, the
 *                           queue (the driver builds the grid after)
 *   fl_simp_compact_refs    the face-list arena compacted
 *   fl_simp_view ...        a worker's view of the run; freeing scratch
 *
 * Invariants: node ids stay the input indices whatever the slot order;
 * every loop that runs in parallel parts (fl_pool_ranges) writes only what
 * its indices own and reads only what no part writes, so the bytes are
 * those of one sequential pass for every thread count (docs/design.md "The
 * set-up in parallel parts"); a vertex's face list is in increasing face
 * order.
 */
#include "simp.h"

#include <stdlib.h>
#include <unistd.h>
#if defined(__linux__)
#include <sys/mman.h>
#endif

static inline uint32_t min3u(const uint32_t t[3]) {
    uint32_t m = t[0] < t[1] ? t[0] : t[1];
    return m < t[2] ? m : t[2];
}

/* n elements of size bytes, 64-byte aligned (cache lines); NULL on
 * ENOMEM or overflow. Freed with free. */
static void *alloc_lines(size_t n, size_t size) {
    if (size && n > SIZE_MAX / size) return NULL;
    void *p = NULL;
    size_t bytes = n * size;
    return posix_memalign(&p, 64, bytes ? bytes : 64) == 0 ? fl_populate(p, bytes) : NULL;
}

/* {====== per-thread views */

/* The per-thread part: the ring and the check buffers. */
static void ring_free(ring *R) {
    free(R->face);
    free(R->a);
    free(R->b);
    free(R->from_j);
    free(R->lab);
    free(R->lab2);
}

void fl_simp_free_scratch(simp *S) {
    ring_free(&S->R);
    ring_free(&S->R2);
    free(S->sc.ebuf);
    free(S->sc.pbuf);
    free(S->sc.pdst);
    free(S->sc.devbox);
    free(S->sc.newcone);
    free(S->sc.tbox);
    free(S->sc.obox);
    free(S->sc.tplane);
    free(S->sc.cert);
}

/* A worker's view of the run (band_par, the eval helper and teams): the
 * run's state with w's own scratch kept. */
void fl_simp_view(simp *w, const simp *S) {
    ring R = w->R, R2 = w->R2;
    scratch sc = w->sc;
    memcpy(w, S, offsetof(simp, vstars));
    w->phase = S->phase;
    w->fast = S->fast;
    w->vlock = S->vlock;
    w->vbest = S->vbest;
    w->pass = S->pass;
    w->nthreads = 1;
    w->par = 0;
    w->slab_ax = S->slab_ax;
    w->slab = S->slab;
    w->slab_w = S->slab_w;
    w->slab_shift = S->slab_shift;
    w->log = S->log;
    w->collapses = S->collapses;
    w->prephase = S->prephase;
    w->swept = 0;
    w->oom = 0; /* rejected: w's own count goes on */
    w->cancelled = 0;
    w->R = R;
    w->R2 = R2;
    w->sc = sc;
}

void fl_simp_free_views(simp *S, simp *W, int n) {
#if FEMLOD_SIMPLIFY_STATS
    /* the workers' counts (the fields before t, all size_t) */
    for (int t = 0; t < n; t++) {
        size_t *a = (size_t *)&S->stats, *w = (size_t *)&W[t].stats;
        for (size_t k = 0; k < offsetof(simp_stats, t) / sizeof(size_t); k++) a[k] += w[k];
    }
#else
    (void)S;
#endif
    for (int t = 0; t < n; t++) fl_simp_free_scratch(&W[t]);
    free(W);
}

/* }====== */

/* {====== the face-list arena */

/* Gives the whole pages inside [p, p + bytes) back to the system; their
 * contents read as zero afterwards (Linux; elsewhere nothing). */
static void release_pages(void *p, size_t bytes) {
#if defined(__linux__) && defined(MADV_DONTNEED)
    uintptr_t a = ((uintptr_t)p + 4095) & ~(uintptr_t)4095, b = ((uintptr_t)p + bytes) & ~(uintptr_t)4095;
    if (b > a) (void)madvise((void *)a, b - a, MADV_DONTNEED);
#else
    (void)p;
    (void)bytes;
#endif
}

#define COMPACT_CHUNK ((size_t)1 << 18) /* entries: 1 MiB */

/* In place, without a second arena (docs/design.md "The face-list arena
 * compacted in place"): each live list's first entry is swapped with its
 * vertex (kept in fstart meanwhile) and its start marked in a bitmap; one
 * walk up the arena then moves every list down to the write position, in
 * arena order, so no list is overwritten before it has moved. The lists
 * keep their entries and order; only where they sit changes. */
int fl_simp_compact_refs(simp *S) {
    size_t n = S->nrefs, words = n / 64 + 1;
    uint64_t *start = fl_calloc(words, sizeof *start);
    if (!start) return 0;
    for (size_t v = 0; v < S->nv; v++) {
        if (!S->fcount[v]) continue;
        size_t p = S->fstart[v];
        S->fstart[v] = S->refs[p];
        S->refs[p] = (uint32_t)v;
        start[p / 64] |= (uint64_t)1 << (p % 64);
    }
    size_t w = 0;
    for (size_t k = 0; k < words; k++) {
        while (start[k]) {
            size_t p = 64 * k + (size_t)__builtin_ctzll(start[k]);
            start[k] &= start[k] - 1;
            uint32_t v = S->refs[p];
            size_t c = S->fcount[v];
            memmove(S->refs + w, S->refs + p, c * sizeof *S->refs);
            S->refs[w] = S->fstart[v];
            S->fstart[v] = (uint32_t)w;
            w += c;
        }
    }
    free(start);
    for (size_t v = 0; v < S->nv; v++)
        if (!S->fcount[v]) S->fstart[v] = (uint32_t)w;
    S->nrefs = w;
    /* room for as many appended lists again: compaction stays amortised
     * O(1). The pages past the live lists go back to the system first
     * (they come back as zero pages when used); a grown arena is then a new
     * block holding only the live lists (glibc's realloc, measured, made
     * the peak 1.4 MB higher than this copy) */
    size_t cap = 2 * w + 1024;
    release_pages(S->refs + w, (S->caprefs - w) * sizeof *S->refs);
    if (cap > S->caprefs) {
        uint32_t *nr = fl_alloc(cap, sizeof *nr);
        if (!nr) return 0;
        /* copied a mebibyte at a time, each part's old pages given back
         * once copied (a block inside the heap keeps its pages resident
         * after free): the lists are not resident twice */
        for (size_t at = 0; at < w; at += COMPACT_CHUNK) {
            size_t k = w - at < COMPACT_CHUNK ? w - at : COMPACT_CHUNK;
            memcpy(nr + at, S->refs + at, k * sizeof *nr);
            release_pages(S->refs + at, k * sizeof *S->refs);
        }
        free(S->refs);
        S->refs = nr;
    }
    S->caprefs = cap;
    return 1;
}

/* }====== */

/* {====== set-up maps, in parallel parts (fl_pool_ranges) */

typedef struct erec {
    uint32_t other, face, side;
} erec;

static int erec_less(const erec *x, const erec *y) {
    if (x->other != y->other) return x->other < y->other;
    if (x->face != y->face) return x->face < y->face;
    return x->side < y->side;
}

static uint64_t spread21(uint32_t x) {
    uint64_t v = x & 0x1fffff;
    v = (v | v << 32) & 0x1f00000000ffffull;
    v = (v | v << 16) & 0x1f0000ff0000ffull;
    v = (v | v << 8) & 0x100f00f00f00f00full;
    v = (v | v << 4) & 0x10c30c30c30c30c3ull;
    v = (v | v << 2) & 0x1249249249249249ull;
    return v;
}

typedef struct morton_ctx {
    const double *pos;
    mkey *k;
    double lo[3], sc;
} morton_ctx;

static void morton_keys(void *arg, size_t v0, size_t v1, int part) {
    (void)part;
    const morton_ctx *m = arg;
    for (size_t v = v0; v < v1; v++) {
        uint64_t code = 0;
        for (int c = 0; c < 3; c++) code |= spread21((uint32_t)((m->pos[3 * v + c] - m->lo[c]) * m->sc)) << c;
        m->k[v].key = code;
        m->k[v].id = (uint32_t)v;
    }
}

/* perm[s] = the input vertex of slot s, sorted by (Morton code, index):
 * a stable radix sort of the codes, 11 bits a pass (a pass whose digit is
 * the same everywhere is skipped), from index order. Returns the inverse
 * (input -> slot), NULL on ENOMEM. */
static uint32_t *morton_slots(const double *pos, size_t nv, uint32_t *perm, int nth) {
    /* all written whole: mapped at once (fl_populate) */
    mkey *k = fl_populate(fl_alloc(nv, sizeof *k), nv * sizeof *k);
    mkey *k2 = fl_populate(fl_alloc(nv, sizeof *k2), nv * sizeof *k2);
    uint32_t *inv = fl_populate(fl_alloc(nv, sizeof *inv), nv * sizeof *inv);
    if (!k || !k2 || !inv) {
        free(k);
        free(k2);
        free(inv);
        return NULL;
    }
    morton_ctx m = {pos, k, {__builtin_inf(), __builtin_inf(), __builtin_inf()}, 0.0};
    double hi[3];
    for (int c = 0; c < 3; c++) hi[c] = -m.lo[c];
    for (size_t v = 0; v < nv; v++)
        for (int c = 0; c < 3; c++) {
            m.lo[c] = mn(m.lo[c], pos[3 * v + c]);
            hi[c] = mx(hi[c], pos[3 * v + c]);
        }
    double ext = mx(hi[0] - m.lo[0], mx(hi[1] - m.lo[1], hi[2] - m.lo[2]));
    m.sc = ext > 0.0 ? 2097151.0 / ext : 0.0;
    fl_pool_ranges(nth, nv, morton_keys, &m);
    enum { RB = 11 }; /* digit bits: 6 passes cover the 63-bit codes */
    for (int shift = 0; shift < 64; shift += RB) {
        size_t cnt[(1 << RB) + 1] = {0};
        const uint64_t dm = (1u << RB) - 1;
        for (size_t v = 0; v < nv; v++) cnt[((k[v].key >> shift) & dm) + 1]++;
        int one = 0;
        for (int d = 1; d <= 1 << RB; d++) one |= cnt[d] == nv;
        if (one) continue;
        for (int d = 0; d < 1 << RB; d++) cnt[d + 1] += cnt[d];
        for (size_t v = 0; v < nv; v++) k2[cnt[(k[v].key >> shift) & dm]++] = k[v];
        mkey *x = k;
        k = k2;
        k2 = x;
    }
    for (size_t s = 0; s < nv; s++) {
        perm[s] = k[s].id;
        inv[k[s].id] = (uint32_t)s;
    }
    free(k);
    free(k2);
    return inv;
}

/* the face caches in parts, and each part's longest edge (a maximum: the
 * same for every cut into parts) */
typedef struct cache_ctx {
    simp *S;
    float size_max[16];
} cache_ctx;

static void face_cache_range(void *arg, size_t f0, size_t f1, int part) {
    cache_ctx *C = arg;
    float m = 0.0f;
    for (size_t f = f0; f < f1; f++) {
        float sz = face_update_cache(C->S, (uint32_t)f);
        if (sz > m) m = sz;
    }
    C->size_max[part] = m;
}

/* Whether the faces around v form one fan (flooded from the first face
 * through edges at v); mark: cnt bytes of scratch, or NULL for the shared
 * face marks (stamps). */
#ifndef FEMLOD_SIMPLIFY_PINCH_LOCAL
#define FEMLOD_SIMPLIFY_PINCH_LOCAL 256 /* tests/CMakeLists.txt sets 2: nearly every vertex takes the shared marks */
#endif
#define PINCH_LOCAL FEMLOD_SIMPLIFY_PINCH_LOCAL
static int fan_is_one(simp *S, uint32_t v, uint8_t *mark) {
    uint32_t cnt = S->fcount[v];
    const uint32_t *fl = S->refs + S->fstart[v];
    uint32_t mk = mark ? 1u : next_stamp(S);
#define FAN_MARKED(m) (mark ? mark[m] != 0 : S->fmark[fl[m]] == mk)
#define FAN_MARK(m) (mark ? (void)(mark[m] = 1) : (void)(S->fmark[fl[m]] = mk))
    if (mark) memset(mark, 0, cnt);
    uint32_t reached = 1, changed = 1;
    FAN_MARK(0);
    while (changed) {
        changed = 0;
        for (uint32_t m = 0; m < cnt; m++) {
            if (FAN_MARKED(m)) continue;
            const uint32_t *te = S->tedge + 3 * (size_t)fl[m];
            for (uint32_t w = 0; w < cnt && !FAN_MARKED(m); w++) {
                if (!FAN_MARKED(w)) continue;
                const uint32_t *tw = S->tedge + 3 * (size_t)fl[w];
                for (int x = 0; x < 3; x++)
                    for (int y = 0; y < 3; y++)
                        if (te[x] == tw[y] && (S->edge[te[x]].v[0] == v || S->edge[te[x]].v[1] == v)) {
                            FAN_MARK(m);
                            x = y = 3;
                        }
            }
            if (FAN_MARKED(m)) {
                reached++;
                changed = 1;
            }
        }
    }
#undef FAN_MARKED
#undef FAN_MARK
    return reached == cnt;
}

static void pinched_range(void *arg, size_t v0, size_t v1, int part) {
    (void)part;
    simp *S = arg;
    uint8_t mark[PINCH_LOCAL];
    for (size_t v = v0; v < v1; v++) {
        uint32_t cnt = S->fcount[v];
        if (cnt == 0 || cnt > PINCH_LOCAL || (S->vflag[v] & V_NONMANIFOLD)) continue;
        if (!fan_is_one(S, (uint32_t)v, mark)) S->vflag[v] |= V_NONMANIFOLD;
    }
}

/* An edge's sharpness: 1 at a boundary or non-manifold edge, (1 - cos)/2
 * where its two faces' normals part by more than the feature angle, else
 * 0 (not a feature). */
static double edge_sharpness(const simp *S, uint32_t e, double cos_feat) {
    if (S->edge[e].nf != 2) return 1.0;
    if (!(S->feat_angle > 0.0)) return 0.0;
    uint32_t a = S->edge[e].v[0];
    /* the two faces: scan a's list */
    const uint32_t *fl = S->refs + S->fstart[a];
    uint32_t f2[2], n2 = 0;
    for (uint32_t m = 0; m < S->fcount[a] && n2 < 2; m++) {
        const uint32_t *te = S->tedge + 3 * (size_t)fl[m];
        if (te[0] == e || te[1] == e || te[2] == e) f2[n2++] = fl[m];
    }
    if (n2 != 2) return 0.0;
    const float *x = S->face[f2[0]].n, *y = S->face[f2[1]].n;
    /* a degenerate face (NaN normal) counts as normal 0: c = 0 */
    double c = isnan(x[0]) || isnan(y[0]) ? 0.0 : (double)x[0] * y[0] + (double)x[1] * y[1] + (double)x[2] * y[2];
    return c < cos_feat ? 0.5 * (1.0 - c) : 0.0;
}

typedef struct feat_ctx {
    simp *S;
    double cos_feat;
} feat_ctx;

static void feature_range(void *arg, size_t e0, size_t e1, int part) {
    (void)part;
    feat_ctx *C = arg;
    for (size_t e = e0; e < e1; e++)
        if (edge_sharpness(C->S, (uint32_t)e, C->cos_feat) > 0.0) C->S->edge[e].flag |= E_FEATURE;
}

/* The face-plane quadrics (4.1 (2)-(4)), gathered per vertex over its
 * faces in increasing face order: the sums of a face-order scatter, in
 * the same order, so the same bits. With area weights, renormalised per
 * vertex (method-notes) so that tolerance keeps its units. */
static void plane_quadrics(void *arg, size_t v0, size_t v1, int part) {
    (void)part;
    simp *S = arg;
    for (size_t v = v0; v < v1; v++) {
        const uint32_t *fl = S->refs + S->fstart[v];
        double area = 0.0;
        for (uint32_t m = 0; m < S->fcount[v]; m++) {
            const uint32_t *t = S->face[fl[m]].v;
            /* the float cache is for checks; the quadric gets the exact normal */
            double e1[3], e2[3], nn[3], n[3];
            sub3(e1, P(S, t[1]), P(S, t[0]));
            sub3(e2, P(S, t[2]), P(S, t[0]));
            cross3(nn, e1, e2);
            double l = sqrt(dot3(nn, nn));
            if (!(l > 0.0)) continue;
            for (int k = 0; k < 3; k++) n[k] = nn[k] / l;
            double w = S->area_w ? 0.5 * l : 1.0;
            fl_quadric_add_plane(S->q + v, n, P(S, t[0]), w);
            area += w;
        }
        if (S->area_w && area > 0.0) fl_quadric_scale(S->q + v, (double)S->fcount[v] / area);
    }
}

/* The edge table in parts: part t numbers the edges of its vertices from
 * 0 (a's sides towards larger neighbours b, in increasing (a, b) order;
 * tedge gets these local ids) into its own region of S->ev and S->enf,
 * which starts at at[t] (at most 2 edges per face at a vertex: the
 * regions cannot overlap), and counts valences; then the regions are
 * moved down end to end (off[t]) and edge_renumber adds each side's part
 * offset: the numbering of one sequential pass over the vertices, in the
 * memory of one table (the unused tail is given back). */
typedef struct edge_ctx {
    simp *S;
    int parts;
    size_t at[16], cap[16], n[16], off[16];
    size_t misoriented[16]; /* interior edges whose two faces run the same way */
} edge_ctx;

static void edge_part(void *arg, size_t a0, size_t a1, int part) {
    edge_ctx *E = arg;
    simp *S = E->S;
    uint32_t *ev = S->ev + 2 * E->at[part];
    uint16_t *enf = S->enf + E->at[part];
    size_t ne = 0;
    /* a closed manifold part writes a quarter of its room (1.5 edges per
     * face, 6 sides per face reserved): that much is mapped at once, the
     * rest (other meshes) faults as it is written */
    size_t likely = E->cap[part] / 4 + E->cap[part] / 32;
    fl_populate(ev, likely * 2 * sizeof *ev);
    fl_populate(enf, likely * sizeof *enf);
    for (size_t a = a0; a < a1; a++) {
        size_t nrec = 0, nnb = 0;
        const uint32_t *fl = S->refs + S->fstart[a];
        uint32_t cnt = S->fcount[a];
        /* a few dozen sides at most in a mesh; a star of more than 256
         * faces takes the heap */
        erec rec_s[512], *rec = rec_s;
        uint32_t nb_s[512], *nb = nb_s;
        if (cnt > 256) {
            rec = fl_alloc(2 * (size_t)cnt, sizeof *rec);
            nb = fl_alloc(2 * (size_t)cnt, sizeof *nb);
            if (!rec || !nb) {
                free(rec);
                free(nb);
                E->n[part] = SIZE_MAX;
                return;
            }
        }
        for (uint32_t m = 0; m < cnt; m++) {
            uint32_t f = fl[m];
            const uint32_t *t = S->face[f].v;
            int c = t[0] == a ? 0 : (t[1] == a ? 1 : 2);
            int sides[2] = {c, (c + 2) % 3};
            uint32_t others[2] = {t[(c + 1) % 3], t[(c + 2) % 3]};
            for (int q = 0; q < 2; q++) {
                nb[nnb++] = others[q];
                if (others[q] > a) {
                    erec r = {others[q], f, (uint32_t)sides[q]};
                    size_t x = nrec++;
                    while (x > 0 && erec_less(&r, &rec[x - 1])) {
                        rec[x] = rec[x - 1];
                        x--;
                    }
                    rec[x] = r;
                }
            }
        }
        /* valence: distinct neighbours */
        fl_sort_u32(nb, nnb);
        uint32_t val = 0;
        for (size_t x = 0; x < nnb; x++)
            if (x == 0 || nb[x] != nb[x - 1]) val++;
        S->val[a] = val;
        for (size_t x = 0; x < nrec;) {
            size_t y = x;
            while (y < nrec && rec[y].other == rec[x].other) y++;
            ev[2 * ne] = (uint32_t)a;
            ev[2 * ne + 1] = rec[x].other;
            enf[ne] = (uint16_t)(y - x > 65535 ? 65535 : y - x);
            /* the side runs a -> other when a is its first corner */
            if (y - x == 2 && (S->face[rec[x].face].v[rec[x].side] == a) ==
                                  (S->face[rec[x + 1].face].v[rec[x + 1].side] == a))
                E->misoriented[part]++;
            for (size_t z = x; z < y; z++) S->tedge[3 * (size_t)rec[z].face + rec[z].side] = (uint32_t)ne;
            ne++;
            x = y;
        }
        if (rec != rec_s) {
            free(rec);
            free(nb);
        }
    }
    E->n[part] = ne;
}

static void edge_renumber(void *arg, size_t f0, size_t f1, int part) {
    edge_ctx *E = arg;
    simp *S = E->S;
    size_t nv = S->nv;
    (void)part;
    for (size_t f = f0; f < f1; f++) {
        const uint32_t *t = S->face[f].v;
        for (int c = 0; c < 3; c++) {
            uint32_t a = t[c] < t[(c + 1) % 3] ? t[c] : t[(c + 1) % 3];
            int p = 0;
            while (p + 1 < E->parts && a >= fl_pool_part_lo(nv, E->parts, p + 1)) p++;
            S->tedge[3 * f + c] += (uint32_t)E->off[p];
        }
    }
}

/* The set-up's face maps (docs/design.md "The set-up in parallel parts").
 * Those that write per vertex (counts, the sort's scatter, the face
 * lists) run in vertex parts, each part scanning every face in order and
 * taking the corners in its own range: its writes are those of one
 * sequential pass, in the same order, and the scans stream. */
typedef struct fmap_ctx {
    simp *S;
    const femlod_mesh *mesh;
    const uint32_t *slot_of;
    uint32_t *fin0, *tmp, *cnt;
    size_t nf[16]; /* faces kept per part of the input faces, then their offsets */
} fmap_ctx;

static inline int tri_degenerate(const uint32_t *t) { return t[0] == t[1] || t[1] == t[2] || t[0] == t[2]; }

static void pos_gather(void *arg, size_t s0, size_t s1, int part) {
    (void)part;
    fmap_ctx *C = arg;
    simp *S = C->S;
    for (size_t s = s0; s < s1; s++) memcpy(S->pos + 3 * s, C->mesh->pos + 3 * (size_t)S->node[s], 3 * sizeof(double));
}

static void faces_kept(void *arg, size_t f0, size_t f1, int part) {
    fmap_ctx *C = arg;
    size_t n = 0;
    for (size_t f = f0; f < f1; f++) n += !tri_degenerate(C->mesh->tri + 3 * f);
    C->nf[part] = n;
}

/* the kept input faces in slots, and their input indices (fin0) */
static void faces_copy(void *arg, size_t f0, size_t f1, int part) {
    fmap_ctx *C = arg;
    simp *S = C->S;
    size_t w = C->nf[part];
    for (size_t f = f0; f < f1; f++) {
        const uint32_t *t = C->mesh->tri + 3 * f;
        if (tri_degenerate(t)) continue;
        for (int c = 0; c < 3; c++) S->face[w].v[c] = C->slot_of[t[c]];
        C->fin0[w++] = (uint32_t)f;
    }
}

/* fcount, and cnt[v + 1]: the faces whose least corner is v */
static void faces_count(void *arg, size_t v0, size_t v1, int part) {
    (void)part;
    fmap_ctx *C = arg;
    simp *S = C->S;
    for (size_t f = 0; f < S->nt; f++) {
        const uint32_t *t = S->face[f].v;
        for (int c = 0; c < 3; c++)
            if (t[c] >= v0 && t[c] < v1) S->fcount[t[c]]++;
        uint32_t m = min3u(t);
        if (m >= v0 && m < v1) C->cnt[m + 1]++;
    }
}

/* the stable counting sort's scatter into tmp and fin */
static void faces_scatter(void *arg, size_t v0, size_t v1, int part) {
    (void)part;
    fmap_ctx *C = arg;
    simp *S = C->S;
    for (size_t f = 0; f < S->nt; f++) {
        const uint32_t *t = S->face[f].v;
        uint32_t m = min3u(t);
        if (m < v0 || m >= v1) continue;
        uint32_t d = C->cnt[m]++;
        memcpy(C->tmp + 3 * (size_t)d, t, 3 * sizeof *t);
        S->fin[d] = C->fin0[f];
    }
}

static void faces_back(void *arg, size_t f0, size_t f1, int part) {
    (void)part;
    fmap_ctx *C = arg;
    for (size_t f = f0; f < f1; f++) memcpy(C->S->face[f].v, C->tmp + 3 * f, 3 * sizeof *C->tmp);
}

/* vertex -> faces, in increasing face order */
static void faces_refs(void *arg, size_t v0, size_t v1, int part) {
    (void)part;
    fmap_ctx *C = arg;
    simp *S = C->S;
    for (size_t f = 0; f < S->nt; f++)
        for (int c = 0; c < 3; c++) {
            uint32_t v = S->face[f].v[c];
            if (v >= v0 && v < v1) S->refs[S->fstart[v] + S->fcount[v]++] = (uint32_t)f;
        }
}

static void edge_records(void *arg, size_t e0, size_t e1, int part) {
    (void)part;
    simp *S = arg;
    size_t ne = S->ne;
    for (size_t e = e0; e < e1; e++) {
        S->edge[e].key = -1.0f;
        S->edge[e].nf = e < ne ? S->enf[e] : 0;
        S->edge[e].flag = S->edge[e].state = 0;
        S->edge[e].v[0] = e < ne ? S->ev[2 * e] : 0;
        S->edge[e].v[1] = e < ne ? S->ev[2 * e + 1] : 0;
    }
}

static void cone_init(void *arg, size_t f0, size_t f1, int part) {
    (void)part;
    simp *S = arg;
    for (size_t f = f0; f < f1; f++) {
        memcpy(S->cone + 4 * f, S->face[f].n, 3 * sizeof(float));
        if (isnan(S->cone[4 * f])) S->cone[4 * f] = S->cone[4 * f + 1] = S->cone[4 * f + 2] = 0.0f;
        S->cone[4 * f + 3] = 0.0f;
    }
}

/* }====== */

/* {====== the set-up, in two steps around resolve_options */

#if FEMLOD_SIMPLIFY_STATS
static double setup_t0;
#define SETUP_T(k) \
    (fprintf(stderr, "setup %d %.3f faults %ld\n", (k), now_seconds() - setup_t0, minor_faults()), (void)0)
#else
#define SETUP_T(k) ((void)0)
#endif

/* every array mapped at once (fl_populate: on the VMs measured, 90,000
 * first-touch faults took 0.9-1.3 s of this set-up on cover x4) */
#define ALLOC(p, n) (((p) = fl_populate(fl_alloc((n), sizeof *(p)), (n) * sizeof *(p))) != NULL)
#define CALLOC(p, n) (((p) = fl_populate(fl_calloc((n), sizeof *(p)), (n) * sizeof *(p))) != NULL)

/* threads for the set-up's maps (resolve_options checks the option) */
static int setup_threads(const femlod_simplify_options *o) {
    int nth = o->threads > 0 ? o->threads : 1;
    if (o->threads == 0) {
        long np = sysconf(_SC_NPROCESSORS_ONLN);
        nth = np < 1 ? 1 : (np > 16 ? 16 : (int)np);
    }
    return nth;
}

femlod_status fl_simp_setup_mesh(simp *S, const femlod_mesh *mesh, const femlod_simplify_options *o,
                                 size_t *dropped, simp_measure *m, femlod_error *err) {
#if FEMLOD_SIMPLIFY_STATS
    setup_t0 = now_seconds();
#endif
    size_t nv = mesh->nv, nt_in = mesh->nt;
    const uint32_t *tin = mesh->tri;
    S->nv = nv;
    S->pos0 = mesh->pos;
    size_t nt = 0;
    for (size_t f = 0; f < nt_in; f++) {
        const uint32_t *t = tin + 3 * f;
        if (t[0] != t[1] && t[1] != t[2] && t[0] != t[2]) nt++;
    }
    *dropped = nt_in - nt;
    S->nt = nt;
    S->nt_in = nt_in;
    S->live = nt;
    if (!ALLOC(S->pos, 3 * nv) || !CALLOC(S->q, nv) || !ALLOC(S->node, nv) || !ALLOC(S->fstart, nv + 1) ||
        !CALLOC(S->fcount, nv) || !CALLOC(S->val, nv) || !CALLOC(S->vflag, nv) || !CALLOC(S->fdeg, nv) ||
        !CALLOC(S->vmark, nv) || !(S->face = alloc_lines(nt, sizeof *S->face)) || !ALLOC(S->tedge, 3 * nt) ||
        !CALLOC(S->fmark, nt) || !CALLOC(S->fmade, nt))
        return fl_error(err, FEMLOD_ENOMEM, "simplify: out of memory (%zu triangles)", nt_in);
    /* Vertex slots in Morton order of position: the neighbours of a vertex
     * then sit near it in memory, which halves the time on large meshes
     * (docs/simplify.md). Node ids stay the input indices. */
    SETUP_T(0);
    int nth = setup_threads(o);
    uint32_t *slot_of = morton_slots(mesh->pos, nv, S->node, nth);
    S->slot_of = slot_of;
    if (!slot_of) return fl_error(err, FEMLOD_ENOMEM, "simplify: out of memory");
    /* Faces in the order of their least vertex slot (a stable counting
     * sort): the faces around a vertex then share cache lines too. fin
     * remembers each face's input index for the output order. */
    fmap_ctx C;
    memset(&C, 0, sizeof C);
    C.S = S;
    C.mesh = mesh;
    C.slot_of = slot_of;
    C.fin0 = fl_populate(fl_alloc(nt, sizeof *C.fin0), nt * sizeof *C.fin0);
    C.cnt = fl_populate(fl_calloc(nv + 1, sizeof *C.cnt), (nv + 1) * sizeof *C.cnt);
    C.tmp = fl_populate(fl_alloc(3 * nt, sizeof *C.tmp), 3 * nt * sizeof *C.tmp);
    if (!C.fin0 || !C.cnt || !C.tmp || !ALLOC(S->fin, nt)) {
        free(C.fin0);
        free(C.cnt);
        free(C.tmp);
        return fl_error(err, FEMLOD_ENOMEM, "simplify: out of memory");
    }
    fl_pool_ranges(nth, nv, pos_gather, &C);
    fl_pool_ranges(nth, nt_in, faces_kept, &C);
    size_t run = 0;
    for (int t = 0; t < fl_pool_parts(nth, nt_in); t++) {
        size_t n = C.nf[t];
        C.nf[t] = run;
        run += n;
    }
    fl_pool_ranges(nth, nt_in, faces_copy, &C);
    fl_pool_ranges(nth, nv, faces_count, &C);
    SETUP_T(1);
    for (size_t v = 0; v < nv; v++) C.cnt[v + 1] += C.cnt[v];
    fl_pool_ranges(nth, nv, faces_scatter, &C);
    fl_pool_ranges(nth, nt, faces_back, &C);
    free(C.cnt);
    free(C.tmp);
    free(C.fin0);
    size_t acc = 0;
    for (size_t v = 0; v < nv; v++) {
        S->fstart[v] = (uint32_t)acc;
        acc += S->fcount[v];
    }
    S->fstart[nv] = (uint32_t)acc;
    S->caprefs = acc + acc / 2 + 1024;
    /* the lists are mapped, their spare room faults when used */
    if (!(S->refs = fl_populate(fl_alloc(S->caprefs, sizeof *S->refs), acc * sizeof *S->refs)))
        return fl_error(err, FEMLOD_ENOMEM, "simplify: out of memory");
    S->nrefs = acc;
    memset(S->fcount, 0, nv * sizeof *S->fcount);
    fl_pool_ranges(nth, nv, faces_refs, &C);
    SETUP_T(2);
    cache_ctx FC;
    FC.S = S;
    fl_pool_ranges(nth, nt, face_cache_range, &FC);

    SETUP_T(3);
    /* edges, numbered in increasing (a, b) order: each vertex a lists its
     * sides towards larger neighbours b (edge_part, in parallel parts) */
    edge_ctx E;
    memset(&E, 0, sizeof E);
    E.S = S;
    E.parts = fl_pool_parts(nth, nv);
    size_t cap_e = 0;
    for (int t = 0; t < E.parts; t++) {
        E.at[t] = cap_e;
        size_t hi = fl_pool_part_lo(nv, E.parts, t + 1);
        for (size_t a = fl_pool_part_lo(nv, E.parts, t); a < hi; a++) cap_e += 2 * (size_t)S->fcount[a];
        E.cap[t] = cap_e - E.at[t];
    }
    /* sized for the worst case (two sides per face corner: four times the
     * edges of a closed mesh) and written in part: not mapped */
    if (!(S->ev = fl_alloc(2 * cap_e + 2, sizeof *S->ev)) || !(S->enf = fl_alloc(cap_e + 1, sizeof *S->enf)))
        return fl_error(err, FEMLOD_ENOMEM, "simplify: out of memory");
    fl_pool_ranges(nth, nv, edge_part, &E);
    size_t ne = 0;
    for (int t = 0; t < E.parts; t++) {
        if (E.n[t] == SIZE_MAX) return fl_error(err, FEMLOD_ENOMEM, "simplify: out of memory");
        E.off[t] = ne;
        if (t > 0 && E.n[t]) {
            memmove(S->ev + 2 * ne, S->ev + 2 * E.at[t], 2 * E.n[t] * sizeof *S->ev);
            memmove(S->enf + ne, S->enf + E.at[t], E.n[t] * sizeof *S->enf);
        }
        ne += E.n[t];
    }
    uint32_t *ev2 = fl_realloc(S->ev, 2 * ne + 2, sizeof *ev2);
    if (ev2) S->ev = ev2;
    uint16_t *enf2 = fl_realloc(S->enf, ne + 1, sizeof *enf2);
    if (enf2) S->enf = enf2;
    if (E.parts > 1) fl_pool_ranges(nth, nt, edge_renumber, &E);
    S->oriented = 1;
    for (int t = 0; t < E.parts; t++)
        if (E.misoriented[t]) S->oriented = 0;
    double elen = 0.0;
    for (size_t e = 0; e < ne; e++) elen += sqrt(dist2(P(S, S->ev[2 * e]), P(S, S->ev[2 * e + 1])));
    S->ne = ne;
    /* the edge marks are written by the exact queue's ring listing and the
     * marked scans only, after fast passes on a small part of the edges:
     * not mapped */
    if (!(S->edge = alloc_lines(ne + 1, sizeof *S->edge)) || !(S->emark = fl_calloc(ne + 1, sizeof *S->emark)) ||
        !ALLOC(S->eopt, 3 * ne + 3) ||
        (FEMLOD_SIMPLIFY_BOUND && !ALLOC(S->ehint, 2 * ne + 2)))
        return fl_error(err, FEMLOD_ENOMEM, "simplify: out of memory");
    if (FEMLOD_SIMPLIFY_BOUND) memset(S->ehint, 0xff, (2 * ne + 2) * sizeof *S->ehint);
    fl_pool_ranges(nth, ne + 1, edge_records, S);
    free(S->enf);
    S->enf = NULL;
    free(S->ev);
    S->ev = NULL;

    SETUP_T(4);
    double lo[3], hi[3];
    femlod_mesh_bbox(mesh, lo, hi);
    m->diag = sqrt(dist2(lo, hi));
    m->mean_edge = ne ? elen / (double)ne : 0.0;
    m->size_max = 0.0;
    for (int t = 0; t < fl_pool_parts(nth, nt); t++) m->size_max = mx(m->size_max, (double)FC.size_max[t]);
    S->eps = 1e-10 * (m->diag > 0 ? m->diag : 1.0);
    return FEMLOD_OK;
}

femlod_status fl_simp_setup_features(simp *S, const femlod_mesh *mesh, const femlod_simplify_options *o,
                                     femlod_error *err) {
    size_t nv = S->nv, nt = S->nt, ne = S->ne;
    const uint32_t *slot_of = S->slot_of;
    int nth = setup_threads(o);

    SETUP_T(5);
    /* boundary and non-manifold edges */
    for (size_t e = 0; e < ne; e++) {
        uint32_t a = S->edge[e].v[0], b = S->edge[e].v[1];
        if (S->edge[e].nf == 1) {
            S->vflag[a] |= V_BOUNDARY;
            S->vflag[b] |= V_BOUNDARY;
        } else if (S->edge[e].nf > 2) {
            S->vflag[a] |= V_NONMANIFOLD;
            S->vflag[b] |= V_NONMANIFOLD;
        }
    }
    /* pinched vertices: more than one fan of faces around them (in
     * parallel, each vertex's flood in its own marks; the rare vertex of
     * more than PINCH_LOCAL faces afterwards, with the shared ones) */
    fl_pool_ranges(nth, nv, pinched_range, S);
    for (size_t v = 0; v < nv; v++)
        if (S->fcount[v] > PINCH_LOCAL && !(S->vflag[v] & V_NONMANIFOLD) && !fan_is_one(S, (uint32_t)v, NULL))
            S->vflag[v] |= V_NONMANIFOLD;
    memset(S->fmark, 0, nt * sizeof *S->fmark);
    S->stamp = 0;
    memset(S->vmark, 0, nv * sizeof *S->vmark);

    SETUP_T(6);
    fl_pool_ranges(nth, nv, plane_quadrics, S);
    SETUP_T(7);
    /* features (in parallel, per edge) and line quadrics, weighted by
     * sharpness (in edge order: the same sums as one pass; the sharpness of
     * the few feature edges is computed again here rather than kept in a
     * per-edge array for all of them) */
    feat_ctx FC = {S, S->feat_angle > 0.0 ? cos(S->feat_angle * PI / 180.0) : -2.0};
    fl_pool_ranges(nth, ne, feature_range, &FC);
    for (size_t e = 0; e < ne; e++) {
        if (!(S->edge[e].flag & E_FEATURE)) continue;
        uint32_t a = S->edge[e].v[0], b = S->edge[e].v[1];
        double sharp = edge_sharpness(S, (uint32_t)e, FC.cos_feat);
        if (S->fdeg[a] < 255) S->fdeg[a]++;
        if (S->fdeg[b] < 255) S->fdeg[b]++;
        if (S->feat_w > 0.0) {
            double u[3];
            sub3(u, P(S, b), P(S, a));
            double l = sqrt(dot3(u, u));
            if (l > 0.0) {
                for (int k = 0; k < 3; k++) u[k] /= l;
                fl_quadric_add_line(S->q + a, u, P(S, a), S->feat_w * sharp);
                fl_quadric_add_line(S->q + b, u, P(S, a), S->feat_w * sharp);
            }
        }
    }
    SETUP_T(8);
    /* vertices that never move */
    for (size_t v = 0; v < nv; v++) {
        if (S->fdeg[v] == 1 || S->fdeg[v] >= 3) S->vflag[v] |= V_FIXED;
        if (S->keep_boundary && (S->vflag[v] & V_BOUNDARY)) S->vflag[v] |= V_FIXED;
        if (S->vflag[v] & V_NONMANIFOLD) S->vflag[v] |= V_FIXED;
    }
    for (size_t m = 0; m < o->lock_count; m++) {
        if (o->lock[m] >= nv) {
            return fl_error(err, FEMLOD_EINPUT, "simplify: lock[%zu] = %u is out of range (%zu vertices)", m,
                            (unsigned)o->lock[m], nv);
        }
        S->vflag[slot_of[o->lock[m]]] |= V_FIXED;
    }
    if (o->lock_fn)
        for (size_t v = 0; v < nv; v++) {
            const double *p = mesh->pos + 3 * v;
            if (o->lock_fn(o->lock_payload, p[0], p[1], p[2])) S->vflag[slot_of[v]] |= V_FIXED;
        }
    free(S->slot_of);
    S->slot_of = NULL;
    free(S->fmark); /* the pinched-vertex flood's only */
    S->fmark = NULL;

    if (S->cone_on) {
        if (!ALLOC(S->cone, 4 * nt)) return fl_error(err, FEMLOD_ENOMEM, "simplify: out of memory");
        fl_pool_ranges(nth, nt, cone_init, S);
    }
    SETUP_T(9);
    if (!fl_heap_init(&S->heap, ne + 1)) return fl_error(err, FEMLOD_ENOMEM, "simplify: out of memory");
    return FEMLOD_OK;
}

#undef ALLOC
#undef CALLOC

/* }====== */
