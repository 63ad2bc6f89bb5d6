/*
 * ops.c - the local operators of the improvement stage (docs/design.md
 * "Improving a mesh in place"): edge flip, edge split, short-edge collapse
 * and tangential relaxation with projection back onto the input surface.
 * Each builds a change (faces removed, faces added, at most one vertex moved
 * or created) aside; check() accepts or refuses it with the first failing
 * check; only then commit() writes it. And the transactions: what commit()
 * and the feature and class updates did since fl_imtx_begin, judged as one
 * change by the floor rule and undone when it fails ("The floor rule,
 * compound changes and bands").
 */
#include "impr.h"

#include <stdlib.h>
#include <string.h>

#define MAX_CHANGE 512
#define DEV_MARGIN 0.9

typedef struct change {
    uint32_t rm[MAX_CHANGE];
    size_t nrm;
    uint32_t add[MAX_CHANGE][3];
    int corr[MAX_CHANGE][2]; /* the removed faces (index in rm) each added one replaces; -1: none */
    size_t nadd;
    uint32_t mv;     /* the vertex moved or created (IM_DEAD: none) */
    double mpos[3];  /* its position */
    double gone[2][3]; /* points the change takes away from the surface */
    int ngone;
    uint32_t stamp;  /* marks the removed faces in fmark */
} change;

static const double *cpos(const imesh *M, const change *ch, uint32_t v) {
    return v == ch->mv ? ch->mpos : im_P(M, v);
}

static void corners(const imesh *M, const change *ch, const uint32_t t[3], const double *T[3]) {
    for (int c = 0; c < 3; c++) T[c] = cpos(M, ch, t[c]);
}

/* least stretch of the removed faces (old positions) and of the added ones */
static double old_min(const imesh *M, const change *ch) {
    double m = 1.0;
    for (size_t i = 0; i < ch->nrm; i++) m = fmin(m, im_face_stretch(M, ch->rm[i]));
    return m;
}

static double new_min(const imesh *M, const change *ch) {
    double m = 1.0;
    for (size_t i = 0; i < ch->nadd; i++) {
        const double *T[3];
        corners(M, ch, ch->add[i], T);
        m = fmin(m, im_stretch(T[0], T[1], T[2]));
    }
    return m;
}

typedef struct isect_q {
    imesh *M;
    const change *ch;
    const double *T[3];
    const uint32_t *tid;
    double lo[3], hi[3];
    uint32_t stamp;
} isect_q;

static int isect_visit(void *payload, uint32_t g) {
    isect_q *q = payload;
    imesh *M = q->M;
    if (M->fmark[g] == q->stamp) return 0; /* removed by the change, or seen */
    const uint32_t *t = M->tri + 3 * (size_t)g;
    if (t[0] == IM_DEAD) return 0;
    M->fmark[g] = q->stamp;
    const double *Q[3] = {im_P(M, t[0]), im_P(M, t[1]), im_P(M, t[2])};
    for (int k = 0; k < 3; k++) {
        double lo = fmin(Q[0][k], fmin(Q[1][k], Q[2][k])), hi = fmax(Q[0][k], fmax(Q[1][k], Q[2][k]));
        if (lo > q->hi[k] || hi < q->lo[k]) return 0;
    }
    if (!fl_tri_tri_intersect(q->T, q->tid, Q, t, M->eps)) return 0;
    /* a pair is new only when g met none of the faces the change removes:
     * an assembly's parts that cross in the input stay free to change
     * where they cross (the count of crossing pairs is measured on the
     * output by the tests) */
    const change *ch = q->ch;
    for (size_t i = 0; i < ch->nrm; i++) {
        const uint32_t *r = M->tri + 3 * (size_t)ch->rm[i];
        const double *R[3] = {im_P(M, r[0]), im_P(M, r[1]), im_P(M, r[2])};
        if (fl_tri_tri_intersect(R, r, Q, t, M->eps)) return 0;
        /* a removed face that shares a corner with g and crosses it away
         * from that corner (the test above says no when they meet only
         * near the corner): it, shrunk a little towards its centroid and
         * taken apart from g's ids, meets g */
        if (r[0] == t[0] || r[0] == t[1] || r[0] == t[2] || r[1] == t[0] || r[1] == t[1] || r[1] == t[2] ||
            r[2] == t[0] || r[2] == t[1] || r[2] == t[2]) {
            double S[3][3];
            for (int k = 0; k < 3; k++)
                for (int c = 0; c < 3; c++) S[c][k] = R[c][k] + 1e-6 * ((R[0][k] + R[1][k] + R[2][k]) / 3.0 - R[c][k]);
            const double *SP[3] = {S[0], S[1], S[2]};
            const uint32_t sid[3] = {IM_DEAD, IM_DEAD - 1, IM_DEAD - 2};
            if (fl_tri_tri_intersect(SP, sid, Q, t, M->eps)) return 0;
        }
    }
    return 1;
}

/* the first failing check (a femlod_improve_reason), or -1 */
static int check(im_ctx *C, change *ch) {
    imesh *M = C->M;
    const im_params *p = C->p;
    if (ch->nadd == 0) return FEMLOD_IMPROVE_TOPOLOGY;
    /* orientation: no degenerate face, no turn past max_normal_change */
    for (size_t i = 0; i < ch->nadd; i++) {
        const double *T[3];
        corners(M, ch, ch->add[i], T);
        double n[3];
        im_normal(n, T[0], T[1], T[2]);
        double l = sqrt(dot3(n, n));
        if (!(l > 0.0)) return FEMLOD_IMPROVE_FOLDOVER;
        for (int k = 0; k < 2; k++) {
            int r = ch->corr[i][k];
            if (r < 0) continue;
            const uint32_t *t = M->tri + 3 * (size_t)ch->rm[r];
            double o[3];
            im_normal(o, im_P(M, t[0]), im_P(M, t[1]), im_P(M, t[2]));
            double lo = sqrt(dot3(o, o));
            if (lo > 0.0 && dot3(n, o) < p->cos_nc * l * lo) return FEMLOD_IMPROVE_FOLDOVER;
        }
    }
    /* fidelity: added faces near the input, taken points near the added faces */
    if (p->maxdev > 0) {
        /* the samples keep a margin: a dense measure finds points between
         * them up to a few percent farther (docs/design.md) */
        double dev = DEV_MARGIN * p->maxdev;
        for (size_t i = 0; i < ch->nadd; i++) {
            const double *T[3];
            corners(M, ch, ch->add[i], T);
            /* a barycentric grid without the corners, of step 1/8 on faces
             * longer than 8 max_deviation, 1/2 on smaller ones */
            double L2 = fmax(dist2(T[0], T[1]), fmax(dist2(T[1], T[2]), dist2(T[0], T[2])));
            int g = L2 > 64.0 * p->maxdev * p->maxdev ? 8 : 2;
            for (int u = 0; u <= g; u++)
                for (int v = 0; u + v <= g; v++) {
                    int w = g - u - v;
                    if (u == g || v == g || w == g) continue;
                    double s[3];
                    for (int k = 0; k < 3; k++) s[k] = (u * T[0][k] + v * T[1][k] + w * T[2][k]) / (double)g;
                    if (!fl_imsurf_within(C->S, s, dev)) return FEMLOD_IMPROVE_DEVIATION;
                }
        }
        for (int g = 0; g < ch->ngone; g++) {
            double best = INFINITY;
            for (size_t i = 0; i < ch->nadd; i++) {
                const double *T[3];
                corners(M, ch, ch->add[i], T);
                best = fmin(best, fl_point_tri_dist2(ch->gone[g], T[0], T[1], T[2]));
            }
            if (!(best <= dev * dev)) return FEMLOD_IMPROVE_DEVIATION;
        }
    }
    /* no new self-intersection: against the faces nearby, and among the added */
    ch->stamp = fl_imesh_next_stamp(M);
    for (size_t i = 0; i < ch->nrm; i++) M->fmark[ch->rm[i]] = ch->stamp;
    for (size_t i = 0; i < ch->nadd; i++) {
        isect_q q = {M, ch, {NULL, NULL, NULL}, ch->add[i], {0, 0, 0}, {0, 0, 0}, 0};
        corners(M, ch, ch->add[i], q.T);
        im_box(q.T[0], q.T[1], q.T[2], q.lo, q.hi);
        for (int k = 0; k < 3; k++) {
            q.lo[k] -= M->eps;
            q.hi[k] += M->eps;
        }
        /* a fresh stamp per face: the removed faces keep the change's */
        q.stamp = fl_imesh_next_stamp(M);
        for (size_t j = 0; j < ch->nrm; j++) M->fmark[ch->rm[j]] = q.stamp;
        if (fl_imgrid_query(&M->grid, q.lo, q.hi, isect_visit, &q)) return FEMLOD_IMPROVE_INTERSECTION;
        for (size_t j = i + 1; j < ch->nadd; j++) {
            const double *Q[3];
            corners(M, ch, ch->add[j], Q);
            if (fl_tri_tri_intersect(q.T, ch->add[i], Q, ch->add[j], M->eps)) return FEMLOD_IMPROVE_INTERSECTION;
        }
    }
    /* backward, last: the input samples the removed faces hold find a
     * place on the added ones (commit moves them there) */
    if (C->samp) {
        const double *T[MAX_CHANGE][3];
        for (size_t i = 0; i < ch->nadd; i++) corners(M, ch, ch->add[i], T[i]);
        if (!fl_imsamp_place(C->samp, ch->rm, ch->nrm, (const double *const (*)[3])T, ch->nadd,
                             DEV_MARGIN * p->maxdev)) {
            if (C->samp->oom) C->oom = 1;
            return FEMLOD_IMPROVE_DEVIATION;
        }
    }
    return -1;
}

/* {====== transactions */

#define TX_PUSH(arr, n, cap)                                                                                   \
    do {                                                                                                       \
        if ((n) == (cap)) {                                                                                    \
            size_t c_ = (cap) ? 2 * (cap) : 16;                                                                \
            void *p_ = fl_realloc((arr), c_, sizeof *(arr));                                                   \
            if (!p_) {                                                                                         \
                C->oom = 1;                                                                                    \
                return;                                                                                        \
            }                                                                                                  \
            (arr) = p_;                                                                                        \
            (cap) = c_;                                                                                        \
        }                                                                                                      \
        (n)++;                                                                                                 \
    } while (0)

static void tx_removed(im_ctx *C, uint32_t f) {
    im_tx *T = &C->tx;
    if (!T->active || f >= T->nt0) return;
    TX_PUSH(T->rm, T->nrm, T->caprm);
    im_rmface *r = T->rm + T->nrm - 1;
    r->f = f;
    memcpy(r->t, C->M->tri + 3 * (size_t)f, sizeof r->t);
    r->st = im_face_stretch(C->M, f);
}

static void tx_moved(im_ctx *C, uint32_t v) {
    im_tx *T = &C->tx;
    if (!T->active || v >= T->nv0) return;
    TX_PUSH(T->mv, T->nmv, T->capmv);
    T->mv[T->nmv - 1].v = v;
    memcpy(T->mv[T->nmv - 1].p, im_P(C->M, v), sizeof T->mv[0].p);
}

static void tx_class(im_ctx *C, uint32_t v) {
    im_tx *T = &C->tx;
    if (!T->active) return;
    TX_PUSH(T->vc, T->nvc, T->capvc);
    T->vc[T->nvc - 1].v = v;
    T->vc[T->nvc - 1].was = C->M->vclass[v];
}

static void tx_feature(im_ctx *C, uint32_t a, uint32_t b) {
    im_tx *T = &C->tx;
    if (!T->active) return;
    TX_PUSH(T->fe, T->nfe, T->capfe);
    T->fe[T->nfe - 1].a = a;
    T->fe[T->nfe - 1].b = b;
    T->fe[T->nfe - 1].was = (uint8_t)fl_imesh_is_feature(C->M, a, b);
}

/* a vertex a split takes past max_valence inside a transaction, and its
 * valence before (the first noted): the end judges it */
static void tx_valence(im_ctx *C, uint32_t v, uint32_t was) {
    im_tx *T = &C->tx;
    for (size_t i = 0; i < T->nvl; i++)
        if (T->vl[i].v == v) return;
    TX_PUSH(T->vl, T->nvl, T->capvl);
    T->vl[T->nvl - 1].v = v;
    T->vl[T->nvl - 1].was = was;
}

/* sets a feature edge on or off, noted in a transaction; 0 on ENOMEM */
static int set_feature(im_ctx *C, uint32_t a, uint32_t b, int on) {
    tx_feature(C, a, b);
    return fl_imesh_set_feature(C->M, a, b, on);
}

void fl_imtx_begin(im_ctx *C) {
    im_tx *T = &C->tx;
    T->active = 1;
    T->nt0 = C->M->nt;
    T->nv0 = C->M->nv;
    T->ops0[0] = C->flips;
    T->ops0[1] = C->splits;
    T->ops0[2] = C->collapses;
    T->ops0[3] = C->relaxations;
    memcpy(T->refused0, C->refused, sizeof T->refused0);
    T->nrm = T->nmv = T->nfe = T->nvc = T->nvl = 0;
    T->gne0 = C->M->grid.ne;
    T->gnbig0 = C->M->grid.nbig;
    T->ggen0 = C->M->grid.gen;
    if (C->samp) fl_imsamp_tx_begin(C->samp, C->M->nt);
}

static void tx_undo(im_ctx *C) {
    im_tx *T = &C->tx;
    imesh *M = C->M;
    for (size_t f = T->nt0; f < M->nt; f++)
        if (M->tri[3 * f] != IM_DEAD) fl_imesh_remove_face(M, (uint32_t)f);
    for (size_t i = T->nmv; i-- > 0;) memcpy(M->pos + 3 * (size_t)T->mv[i].v, T->mv[i].p, sizeof T->mv[i].p);
    for (size_t i = T->nfe; i-- > 0;)
        if (!fl_imesh_set_feature(M, T->fe[i].a, T->fe[i].b, T->fe[i].was)) C->oom = 1;
    for (size_t i = T->nvc; i-- > 0;) M->vclass[T->vc[i].v] = T->vc[i].was;
    /* the face grid as it was: every entry since the begin taken off, the
     * removed faces' entries still there (without a rebuild between: else
     * they go in again) */
    int same = M->grid.gen == T->ggen0;
    if (same) fl_imgrid_rollback(&M->grid, T->gne0, T->gnbig0);
    for (size_t i = 0; i < T->nrm; i++)
        if (!fl_imesh_restore_face(M, T->rm[i].f, T->rm[i].t, !same)) C->oom = 1;
    if (C->samp) fl_imsamp_tx_end(C->samp, 0, M->nt);
    C->flips = T->ops0[0];
    C->splits = T->ops0[1];
    C->collapses = T->ops0[2];
    C->relaxations = T->ops0[3];
    memcpy(C->refused, T->refused0, sizeof T->refused0);
}

int fl_imtx_end(im_ctx *C) {
    im_tx *T = &C->tx;
    imesh *M = C->M;
    double minst = C->p->minst, lo_old = 1.0, lo_new = 1.0;
    size_t old_bad = 0, new_bad = 0;
    T->active = 0;
    for (size_t i = 0; i < T->nrm; i++) {
        lo_old = fmin(lo_old, T->rm[i].st);
        old_bad += T->rm[i].st < minst;
    }
    for (size_t f = T->nt0; f < M->nt; f++) {
        if (M->tri[3 * f] == IM_DEAD) continue;
        double s = im_face_stretch(M, (uint32_t)f);
        lo_new = fmin(lo_new, s);
        new_bad += s < minst;
    }
    int val_ok = 1;
    for (size_t i = 0; i < T->nvl; i++) {
        uint32_t v = T->vl[i].v, lim = (uint32_t)C->p->maxval > T->vl[i].was ? (uint32_t)C->p->maxval : T->vl[i].was;
        if (M->vf[v].n && fl_imesh_valence(M, v) > lim) val_ok = 0;
    }
    int keep = !C->oom && T->nrm > 0 && val_ok && (!C->p->strict || !(lo_new < fmin(minst, lo_old))) &&
               (new_bad < old_bad || (new_bad == old_bad && lo_new > lo_old + 1e-9));
    if (keep || C->oom) {
        if (C->samp) fl_imsamp_tx_end(C->samp, 1, M->nt);
        return keep;
    }
    tx_undo(C);
    /* the refusal: the valence when only that failed, else the stretch */
    T->why = !val_ok && !(lo_new < fmin(minst, lo_old)) &&
                     (new_bad < old_bad || (new_bad == old_bad && lo_new > lo_old + 1e-9))
                 ? FEMLOD_IMPROVE_VALENCE
                 : FEMLOD_IMPROVE_STRETCH;
    C->refused[T->why]++;
    for (size_t i = 0; i < T->nrm; i++) M->freason[T->rm[i].f] = (uint8_t)(T->why + 1);
    return 0;
}

void fl_imtx_free(im_ctx *C) {
    free(C->tx.rm);
    free(C->tx.mv);
    free(C->tx.fe);
    free(C->tx.vc);
    free(C->tx.vl);
    memset(&C->tx, 0, sizeof C->tx);
}

/* }====== */

static int commit(im_ctx *C, change *ch) {
    imesh *M = C->M;
    for (size_t i = 0; i < ch->nrm; i++) tx_removed(C, ch->rm[i]);
    if (ch->mv != IM_DEAD) tx_moved(C, ch->mv);
    if (C->oom) return 0;
    for (size_t i = 0; i < ch->nrm; i++) fl_imesh_remove_face(M, ch->rm[i]);
    if (ch->mv != IM_DEAD) memcpy(M->pos + 3 * (size_t)ch->mv, ch->mpos, sizeof ch->mpos);
    uint32_t slot[MAX_CHANGE];
    for (size_t i = 0; i < ch->nadd; i++)
        if ((slot[i] = fl_imesh_add_face(M, ch->add[i][0], ch->add[i][1], ch->add[i][2])) == IM_DEAD) {
            C->oom = 1;
            return 0;
        }
    if (C->samp && !fl_imsamp_commit(C->samp, ch->rm, ch->nrm, slot, ch->nadd)) {
        C->oom = 1;
        return 0;
    }
    return 1;
}

static void refuse(im_ctx *C, const change *ch, int why) {
    C->refused[why]++;
    for (size_t i = 0; i < ch->nrm; i++) C->M->freason[ch->rm[i]] = (uint8_t)(why + 1);
}

/* valence of v after the change, from the faces it keeps and the added */
static uint32_t valence_after(imesh *M, const change *ch, uint32_t v) {
    uint32_t s = fl_imesh_next_stamp(M), n = 0;
    for (size_t i = 0; i < ch->nrm; i++) M->fmark[ch->rm[i]] = s;
    const im_list *l = M->vf + v;
    for (uint32_t i = 0; i < l->n; i++) {
        if (M->fmark[l->f[i]] == s) continue;
        const uint32_t *t = M->tri + 3 * (size_t)l->f[i];
        for (int c = 0; c < 3; c++)
            if (t[c] != v && M->vmark[t[c]] != s) {
                M->vmark[t[c]] = s;
                n++;
            }
    }
    for (size_t i = 0; i < ch->nadd; i++) {
        const uint32_t *t = ch->add[i];
        if (t[0] != v && t[1] != v && t[2] != v) continue;
        for (int c = 0; c < 3; c++)
            if (t[c] != v && M->vmark[t[c]] != s) {
                M->vmark[t[c]] = s;
                n++;
            }
    }
    return n;
}

/* the corner of face t after a and before b going round (t holds a then b) */
static int oriented(const uint32_t *t, uint32_t a, uint32_t b, uint32_t *third) {
    for (int c = 0; c < 3; c++)
        if (t[c] == a && t[(c + 1) % 3] == b) {
            *third = t[(c + 2) % 3];
            return 1;
        }
    return 0;
}

int fl_imop_flip(im_ctx *C, uint32_t a, uint32_t b, int for_valence, int *why) {
    imesh *M = C->M;
    const im_params *p = C->p;
    uint32_t ef[3], c, d;
    *why = FEMLOD_IMPROVE_TOPOLOGY;
    if (fl_imesh_edge_faces(M, a, b, ef, 3) != 2 || fl_imesh_is_feature(M, a, b)) return 0;
    const uint32_t *t1 = M->tri + 3 * (size_t)ef[0], *t2 = M->tri + 3 * (size_t)ef[1];
    uint32_t f1 = ef[0], f2 = ef[1];
    if (!oriented(t1, a, b, &c)) {
        uint32_t x = a;
        a = b;
        b = x;
        if (!oriented(t1, a, b, &c)) return 0;
    }
    if (!oriented(t2, b, a, &d) || c == d || fl_imesh_has_edge(M, c, d)) return 0;
    change ch;
    ch.nrm = 2;
    ch.rm[0] = f1;
    ch.rm[1] = f2;
    ch.nadd = 2;
    uint32_t n0[3] = {a, d, c}, n1[3] = {d, b, c};
    memcpy(ch.add[0], n0, sizeof n0);
    memcpy(ch.add[1], n1, sizeof n1);
    ch.corr[0][0] = ch.corr[1][0] = 0;
    ch.corr[0][1] = ch.corr[1][1] = 1;
    ch.mv = IM_DEAD;
    ch.ngone = 1;
    for (int k = 0; k < 3; k++) ch.gone[0][k] = 0.5 * (im_P(M, a)[k] + im_P(M, b)[k]);
    double before = old_min(M, &ch), after = new_min(M, &ch);
    uint32_t va = fl_imesh_valence(M, a), vb = fl_imesh_valence(M, b);
    uint32_t vc = fl_imesh_valence(M, c), vd = fl_imesh_valence(M, d);
    if (p->val_on) {
        uint32_t lim = (uint32_t)p->maxval;
        if ((vc + 1 > lim && vc + 1 > va) || (vd + 1 > lim && vd + 1 > vb)) {
            *why = FEMLOD_IMPROVE_VALENCE;
            return 0;
        }
    }
    if (for_valence) {
        if (after < fmin(p->minst, before)) {
            *why = FEMLOD_IMPROVE_STRETCH;
            return 0;
        }
    } else if (!(after > before + 1e-9)) {
        *why = FEMLOD_IMPROVE_STRETCH;
        return 0;
    }
    int r = check(C, &ch);
    if (r >= 0) {
        *why = r;
        refuse(C, &ch, r);
        return 0;
    }
    if (!commit(C, &ch)) return 0;
    C->flips++;
    return 1;
}

int fl_imop_split(im_ctx *C, uint32_t a, uint32_t b, const double *at, int *why) {
    imesh *M = C->M;
    uint32_t ef[3];
    *why = FEMLOD_IMPROVE_TOPOLOGY;
    size_t n = fl_imesh_edge_faces(M, a, b, ef, 3);
    if (n < 1 || n > 2) return 0;
    unsigned depth = 1u + (M->vdepth[a] > M->vdepth[b] ? M->vdepth[a] : M->vdepth[b]);
    if (depth > IM_MAX_DEPTH) {
        *why = FEMLOD_IMPROVE_DEPTH;
        return 0;
    }
    int feat = fl_imesh_is_feature(M, a, b);
    change ch;
    ch.mv = (uint32_t)M->nv; /* the new vertex's index once made */
    const double *pa = im_P(M, a), *pb = im_P(M, b);
    double mid[3];
    if (at) memcpy(mid, at, sizeof mid);
    else
        for (int k = 0; k < 3; k++) mid[k] = 0.5 * (pa[k] + pb[k]);
    if (feat) {
        /* on the line: the point of segment ab nearest to mid */
        double ab[3], am[3];
        sub3(ab, pb, pa);
        sub3(am, mid, pa);
        double t = dot3(ab, am) / dot3(ab, ab);
        t = fmin(0.9, fmax(0.1, t));
        for (int k = 0; k < 3; k++) ch.mpos[k] = pa[k] + t * ab[k];
    } else {
        fl_imsurf_nearest(C->S, mid, C->p->maxdev > 0 ? C->p->maxdev : 0.0, ch.mpos);
    }
    ch.nrm = n;
    ch.nadd = 0;
    ch.ngone = 0;
    if (C->p->val_on)
        for (size_t i = 0; i < n; i++) {
            const uint32_t *t = M->tri + 3 * (size_t)ef[i];
            uint32_t c = t[0] != a && t[0] != b ? t[0] : (t[1] != a && t[1] != b ? t[1] : t[2]);
            uint32_t vc = fl_imesh_valence(M, c);
            if (vc + 1 > (uint32_t)C->p->maxval) {
                /* in a transaction the flips after may take it back: the
                 * end judges the valence */
                if (C->tx.active) {
                    tx_valence(C, c, vc);
                    continue;
                }
                *why = FEMLOD_IMPROVE_VALENCE;
                return 0;
            }
        }
    for (size_t i = 0; i < n; i++) {
        ch.rm[i] = ef[i];
        const uint32_t *t = M->tri + 3 * (size_t)ef[i];
        uint32_t x, y, c;
        if (oriented(t, a, b, &c)) {
            x = a;
            y = b;
        } else if (oriented(t, b, a, &c)) {
            x = b;
            y = a;
        } else
            return 0;
        uint32_t n0[3] = {x, ch.mv, c}, n1[3] = {ch.mv, y, c};
        memcpy(ch.add[ch.nadd], n0, sizeof n0);
        ch.corr[ch.nadd][0] = (int)i;
        ch.corr[ch.nadd++][1] = -1;
        memcpy(ch.add[ch.nadd], n1, sizeof n1);
        ch.corr[ch.nadd][0] = (int)i;
        ch.corr[ch.nadd++][1] = -1;
    }
    /* the floor rule: alone, no face below min(min_stretch, the least of
     * those removed); in a transaction, judged with the rest */
    if (C->p->strict && !C->tx.active && new_min(M, &ch) < fmin(C->p->minst, old_min(M, &ch))) {
        *why = FEMLOD_IMPROVE_STRETCH;
        refuse(C, &ch, FEMLOD_IMPROVE_STRETCH);
        return 0;
    }
    int r = check(C, &ch);
    if (r >= 0) {
        *why = r;
        refuse(C, &ch, r);
        return 0;
    }
    uint32_t m = fl_imesh_add_vertex(M, ch.mpos, feat ? IM_LINE : IM_FREE);
    if (m == IM_DEAD) {
        C->oom = 1;
        return 0;
    }
    M->vorig[2 * (m - M->nv0)] = a;
    M->vorig[2 * (m - M->nv0) + 1] = b;
    M->vdepth[m] = (uint8_t)depth;
    if (!commit(C, &ch)) return 0;
    if (feat) {
        set_feature(C, a, b, 0);
        if (!set_feature(C, a, m, 1) || !set_feature(C, m, b, 1)) {
            C->oom = 1;
            return 0;
        }
    }
    C->splits++;
    return 1;
}

/* Collapse of a onto b (a goes). */
static int collapse_dir(im_ctx *C, uint32_t a, uint32_t b, change *ch, double *gain, int *why) {
    imesh *M = C->M;
    const im_params *p = C->p;
    uint32_t ef[3];
    *why = FEMLOD_IMPROVE_TOPOLOGY;
    if (M->vclass[a] == IM_FIXED) {
        *why = FEMLOD_IMPROVE_FIXED;
        return 0;
    }
    int feat = fl_imesh_is_feature(M, a, b);
    if (M->vclass[a] == IM_LINE && !feat) return 0;
    /* a split's vertex goes only onto another split's vertex, never back
     * onto the ends of the edge it split: the stage would undo what it did */
    if (a >= M->nv0 &&
        (b < M->nv0 || M->vorig[2 * (a - M->nv0)] == b || M->vorig[2 * (a - M->nv0) + 1] == b))
        return 0;
    size_t ne = fl_imesh_edge_faces(M, a, b, ef, 3);
    if (ne < 1 || ne > 2 || (ne == 1 && !feat)) return 0;
    if (M->vf[a].n + M->vf[b].n > MAX_CHANGE) return 0;
    /* link condition: the common neighbours are the corners opposite ab */
    uint32_t s = fl_imesh_next_stamp(M);
    const im_list *la = M->vf + a, *lb = M->vf + b;
    for (uint32_t i = 0; i < la->n; i++) {
        const uint32_t *t = M->tri + 3 * (size_t)la->f[i];
        for (int c = 0; c < 3; c++) M->vmark[t[c]] = s;
    }
    size_t common = 0;
    uint32_t s2 = fl_imesh_next_stamp(M);
    for (uint32_t i = 0; i < lb->n; i++) {
        const uint32_t *t = M->tri + 3 * (size_t)lb->f[i];
        for (int c = 0; c < 3; c++)
            if (t[c] != a && t[c] != b && M->vmark[t[c]] == s) {
                M->vmark[t[c]] = s2;
                common++;
            }
    }
    if (common != ne) return 0;
    /* the collapse along a line takes its other feature edge onto b: that
     * edge must not exist at b already (checked by the link), and b must
     * not become a line's end inside a face fan: a line vertex's second
     * feature edge (a, x) becomes (b, x) */
    ch->nrm = 0;
    ch->nadd = 0;
    ch->mv = IM_DEAD;
    ch->ngone = 1;
    memcpy(ch->gone[0], im_P(M, a), sizeof ch->gone[0]);
    for (uint32_t i = 0; i < la->n; i++) {
        uint32_t f = la->f[i];
        const uint32_t *t = M->tri + 3 * (size_t)f;
        ch->rm[ch->nrm] = f;
        int has_b = t[0] == b || t[1] == b || t[2] == b;
        if (!has_b) {
            for (int c = 0; c < 3; c++) ch->add[ch->nadd][c] = t[c] == a ? b : t[c];
            ch->corr[ch->nadd][0] = (int)ch->nrm;
            ch->corr[ch->nadd][1] = -1;
            ch->nadd++;
        }
        ch->nrm++;
    }
    /* the faces of b that change shape are none (b stays): the stretch rule
     * compares the faces a had with what replaces them */
    double before = old_min(M, ch), after = new_min(M, ch);
    if (!(after > before + 1e-9)) {
        *why = FEMLOD_IMPROVE_STRETCH;
        return 0;
    }
    if (p->val_on) {
        uint32_t vb = fl_imesh_valence(M, b), nb = valence_after(M, ch, b);
        if (nb > (uint32_t)p->maxval && nb > vb) {
            *why = FEMLOD_IMPROVE_VALENCE;
            return 0;
        }
    }
    /* closed stays closed: no vertex of the change may be left with fewer
     * than three neighbours */
    if (valence_after(M, ch, b) < 3) return 0;
    *gain = after;
    *why = -1;
    return 1;
}

int fl_imop_collapse(im_ctx *C, uint32_t a, uint32_t b, int *why) {
    imesh *M = C->M;
    change *c1 = malloc(sizeof *c1), *c2 = malloc(sizeof *c2);
    if (!c1 || !c2) {
        free(c1);
        free(c2);
        C->oom = 1;
        return 0;
    }
    double g1 = -1, g2 = -1;
    int w1 = FEMLOD_IMPROVE_TOPOLOGY, w2 = FEMLOD_IMPROVE_TOPOLOGY;
    int ok1 = collapse_dir(C, a, b, c1, &g1, &w1);
    int ok2 = collapse_dir(C, b, a, c2, &g2, &w2);
    /* try the better first, the other if the checks refuse it */
    change *first = c1, *second = c2;
    uint32_t fa = a, fb = b, sa = b, sb = a;
    int okf = ok1, oks = ok2;
    if (ok2 && (!ok1 || g2 > g1)) {
        first = c2;
        second = c1;
        fa = b;
        fb = a;
        sa = a;
        sb = b;
        okf = ok2;
        oks = ok1;
    }
    *why = w1 >= 0 ? w1 : w2;
    int done = 0;
    for (int k = 0; k < 2 && !done; k++) {
        change *ch = k ? second : first;
        uint32_t x = k ? sa : fa, y = k ? sb : fb;
        if (!(k ? oks : okf)) continue;
        int r = check(C, ch);
        if (r >= 0) {
            *why = r;
            refuse(C, ch, r);
            continue;
        }
        /* features move with the line: (x, z) becomes (y, z) */
        uint32_t fz[2];
        int nf = 0;
        const im_list *lx = M->vf + x;
        uint32_t s = fl_imesh_next_stamp(M);
        for (uint32_t i = 0; i < lx->n; i++) {
            const uint32_t *t = M->tri + 3 * (size_t)lx->f[i];
            for (int c = 0; c < 3; c++) {
                uint32_t z = t[c];
                if (z == x || z == y || M->vmark[z] == s) continue;
                M->vmark[z] = s;
                if (fl_imesh_is_feature(M, x, z) && nf < 2) fz[nf++] = z;
            }
        }
        int fxy = fl_imesh_is_feature(M, x, y);
        if (!commit(C, ch)) break;
        for (int i = 0; i < nf; i++) {
            set_feature(C, x, fz[i], 0);
            if (!set_feature(C, y, fz[i], 1)) C->oom = 1;
        }
        if (fxy) set_feature(C, x, y, 0);
        tx_class(C, x);
        M->vclass[x] = IM_FIXED; /* gone: no face uses it */
        C->collapses++;
        done = 1;
    }
    free(c1);
    free(c2);
    return done;
}

int fl_imop_relax(im_ctx *C, uint32_t v, int *why) {
    imesh *M = C->M;
    const im_list *l = M->vf + v;
    *why = FEMLOD_IMPROVE_FIXED;
    if (M->vclass[v] != IM_FREE) return 0;
    *why = FEMLOD_IMPROVE_TOPOLOGY;
    if (l->n < 3 || l->n > MAX_CHANGE) return 0;
    /* area-weighted centroid of the star's faces and the vertex normal */
    double g[3] = {0, 0, 0}, nrm[3] = {0, 0, 0}, wsum = 0;
    const double *pv = im_P(M, v);
    for (uint32_t i = 0; i < l->n; i++) {
        const uint32_t *t = M->tri + 3 * (size_t)l->f[i];
        const double *A = im_P(M, t[0]), *B = im_P(M, t[1]), *Cc = im_P(M, t[2]);
        double n[3];
        im_normal(n, A, B, Cc);
        double w = sqrt(dot3(n, n));
        for (int k = 0; k < 3; k++) {
            g[k] += w * (A[k] + B[k] + Cc[k]) / 3.0;
            nrm[k] += n[k];
        }
        wsum += w;
    }
    double nl = sqrt(dot3(nrm, nrm));
    if (!(wsum > 0) || !(nl > 0)) return 0;
    change *ch = malloc(sizeof *ch);
    if (!ch) {
        C->oom = 1;
        return 0;
    }
    double d[3];
    for (int k = 0; k < 3; k++) {
        g[k] /= wsum;
        nrm[k] /= nl;
        d[k] = g[k] - pv[k];
    }
    double dn = dot3(d, nrm);
    for (int k = 0; k < 3; k++) d[k] -= dn * nrm[k];
    ch->nrm = l->n;
    ch->nadd = l->n;
    ch->mv = v;
    ch->ngone = 1;
    memcpy(ch->gone[0], pv, sizeof ch->gone[0]);
    for (uint32_t i = 0; i < l->n; i++) {
        ch->rm[i] = l->f[i];
        memcpy(ch->add[i], M->tri + 3 * (size_t)l->f[i], sizeof ch->add[i]);
        ch->corr[i][0] = (int)i;
        ch->corr[i][1] = -1;
    }
    double before = old_min(M, ch);
    int done = 0;
    *why = FEMLOD_IMPROVE_STRETCH;
    for (int step = 0; step < 2 && !done; step++) {
        double lam = step ? 0.5 : 1.0, target[3];
        for (int k = 0; k < 3; k++) target[k] = pv[k] + lam * d[k];
        fl_imsurf_nearest(C->S, target, C->p->maxdev > 0 ? C->p->maxdev : 0.0, ch->mpos);
        if (!(new_min(M, ch) > before + 1e-9)) continue;
        int r = check(C, ch);
        if (r >= 0) {
            *why = r;
            refuse(C, ch, r);
            continue;
        }
        if (!commit(C, ch)) break;
        C->relaxations++;
        done = 1;
    }
    free(ch);
    return done;
}
