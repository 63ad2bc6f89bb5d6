/*
 * samples.c - the input samples of the stage's backward bound
 * (docs/design.md "The two-sided bound of the stage"): points of the input
 * surface, each held by one live face of the working mesh and within the
 * bound of it; a change moves the samples of the faces it removes to its
 * nearest added faces, or is refused.
 */
#include "impr.h"

#include <stdlib.h>
#include <string.h>

#define MAX_STEPS 32 /* sample intervals along an input edge, and grid steps on a face, at most */

static int grow_pts(im_samples *S) {
    size_t c = S->cap ? 2 * S->cap : 1024;
    double *p = fl_realloc(S->pt, 3 * c, sizeof *p);
    if (!p) return 0;
    S->pt = p;
    uint32_t *n = fl_realloc(S->next, c, sizeof *n);
    if (!n) return 0;
    S->next = n;
    S->cap = c;
    return 1;
}

static int grow_heads(im_samples *S, size_t need) {
    if (need <= S->caph) return 1;
    size_t c = S->caph ? S->caph : 1024;
    while (c < need) c *= 2;
    uint32_t *h = fl_realloc(S->head, c, sizeof *h);
    if (!h) return 0;
    for (size_t i = S->caph; i < c; i++) h[i] = IM_DEAD;
    S->head = h;
    S->caph = c;
    return 1;
}

/* the parallel arrays a[0..n) (each of *cap entries) doubled; 0 on ENOMEM
 * (those grown so far keep the new size, *cap the old) */
static int grow_u32(uint32_t **a[], int n, size_t *cap) {
    size_t c = *cap ? 2 * *cap : 256;
    for (int i = 0; i < n; i++) {
        uint32_t *p = fl_realloc(*a[i], c, sizeof *p);
        if (!p) return 0;
        *a[i] = p;
    }
    *cap = c;
    return 1;
}

/* a sample at p held by face f */
static int add(im_samples *S, const double p[3], uint32_t f) {
    if (S->n == S->cap && !grow_pts(S)) return 0;
    if (S->n >= UINT32_MAX - 1) return 0;
    memcpy(S->pt + 3 * S->n, p, 3 * sizeof *p);
    S->next[S->n] = S->head[f];
    S->head[f] = (uint32_t)S->n;
    S->n++;
    return 1;
}

static unsigned steps(double len, double spacing, unsigned lo) {
    double k = ceil(len / spacing);
    unsigned n = !(k < MAX_STEPS) ? MAX_STEPS : (unsigned)k;
    return n < lo ? lo : n;
}

int fl_imsamp_init(im_samples *S, const imesh *M, double spacing) {
    memset(S, 0, sizeof *S);
    if (!grow_heads(S, M->nt ? M->nt : 1)) return 0;
    uint8_t *seen = fl_calloc(M->nv ? M->nv : 1, 1);
    if (!seen) return 0;
    int ok = 1;
    for (uint32_t f = 0; ok && f < M->nt; f++) {
        const uint32_t *t = M->tri + 3 * (size_t)f;
        if (t[0] == IM_DEAD) continue;
        const double *P[3] = {im_P(M, t[0]), im_P(M, t[1]), im_P(M, t[2])};
        /* the corners, each once */
        for (int c = 0; ok && c < 3; c++)
            if (!seen[t[c]]) {
                seen[t[c]] = 1;
                ok = add(S, P[c], f);
            }
        /* each edge once, by the first of its faces */
        double lmax = 0.0;
        for (int c = 0; ok && c < 3; c++) {
            uint32_t a = t[c], b = t[(c + 1) % 3], ef[3];
            size_t ne = fl_imesh_edge_faces(M, a, b, ef, 3);
            double len = sqrt(dist2(P[c], P[(c + 1) % 3]));
            lmax = fmax(lmax, len);
            uint32_t first = f;
            for (size_t i = 0; i < ne && i < 3; i++) first = ef[i] < first ? ef[i] : first;
            if (first != f) continue;
            unsigned k = steps(len, spacing, 2);
            k += k & 1u; /* even: the midpoint is one */
            for (unsigned i = 1; ok && i < k; i++) {
                double u = (double)i / k, q[3];
                for (int d = 0; d < 3; d++) q[d] = (1.0 - u) * P[c][d] + u * P[(c + 1) % 3][d];
                ok = add(S, q, f);
            }
        }
        /* the centroid, and the grid's inner points */
        double g[3];
        for (int d = 0; d < 3; d++) g[d] = (P[0][d] + P[1][d] + P[2][d]) / 3.0;
        if (ok) ok = add(S, g, f);
        unsigned k = steps(lmax, spacing, 1);
        for (unsigned i = 1; ok && k >= 4 && i < k; i++)
            for (unsigned j = 1; ok && i + j < k; j++) {
                unsigned l = k - i - j;
                if (3 * i == k && 3 * j == k) continue; /* the centroid */
                double q[3];
                for (int d = 0; d < 3; d++) q[d] = (i * P[0][d] + j * P[1][d] + l * P[2][d]) / (double)k;
                ok = add(S, q, f);
            }
    }
    free(seen);
    return ok;
}

void fl_imsamp_free(im_samples *S) {
    free(S->pt);
    free(S->next);
    free(S->head);
    free(S->pend);
    free(S->pend_from);
    free(S->pend_to);
    free(S->txs);
    free(S->txf);
    memset(S, 0, sizeof *S);
}

int fl_imsamp_place(im_samples *S, const uint32_t *rm, size_t nrm, const double *const (*T)[3], size_t nadd,
                    double r) {
    S->npend = 0;
    double r2 = r * r;
    for (size_t i = 0; i < nrm; i++)
        for (uint32_t s = rm[i] < S->caph ? S->head[rm[i]] : IM_DEAD; s != IM_DEAD; s = S->next[s]) {
            const double *p = S->pt + 3 * (size_t)s;
            double best = INFINITY;
            uint32_t to = 0;
            for (size_t j = 0; j < nadd; j++) {
                double d = fl_point_tri_dist2(p, T[j][0], T[j][1], T[j][2]);
                if (d < best) {
                    best = d;
                    to = (uint32_t)j;
                }
            }
            if (!(best <= r2)) return 0;
            uint32_t **pa[3] = {&S->pend, &S->pend_from, &S->pend_to};
            if (S->npend == S->cappend && !grow_u32(pa, 3, &S->cappend)) {
                S->oom = 1;
                return 0;
            }
            S->pend[S->npend] = s;
            S->pend_from[S->npend] = rm[i];
            S->pend_to[S->npend++] = to;
        }
    return 1;
}

int fl_imsamp_commit(im_samples *S, const uint32_t *rm, size_t nrm, const uint32_t *slots, size_t nadd) {
    uint32_t top = 0;
    for (size_t j = 0; j < nadd; j++) top = slots[j] > top ? slots[j] : top;
    if (!grow_heads(S, (size_t)top + 1)) return 0;
    for (size_t i = 0; i < nrm; i++)
        if (rm[i] < S->caph) S->head[rm[i]] = IM_DEAD;
    /* a transaction notes each sample's first move: off a face older than it */
    if (S->tx_on)
        for (size_t k = 0; k < S->npend; k++) {
            if (S->pend_from[k] >= S->tx_nt0) continue;
            uint32_t **ta[2] = {&S->txs, &S->txf};
            if (S->ntx == S->captx && !grow_u32(ta, 2, &S->captx)) return 0;
            S->txs[S->ntx] = S->pend[k];
            S->txf[S->ntx++] = S->pend_from[k];
        }
    /* in reverse: each list keeps the order the samples were placed in */
    for (size_t k = S->npend; k-- > 0;) {
        uint32_t s = S->pend[k], f = slots[S->pend_to[k]];
        S->next[s] = S->head[f];
        S->head[f] = s;
    }
    S->npend = 0;
    return 1;
}

void fl_imsamp_tx_begin(im_samples *S, size_t nt0) {
    S->tx_on = 1;
    S->tx_nt0 = nt0;
    S->ntx = 0;
}

/* The faces made since the begin are all gone after an undo, and every
 * sample they held came off a face older than the transaction, once: back
 * there, in the order noted (a list's order changes no result: each
 * sample's nearest face is its own). */
void fl_imsamp_tx_end(im_samples *S, int keep, size_t nt) {
    S->tx_on = 0;
    if (keep) return;
    for (size_t f = S->tx_nt0; f < nt && f < S->caph; f++) S->head[f] = IM_DEAD;
    for (size_t i = 0; i < S->ntx; i++) {
        uint32_t s = S->txs[i], f = S->txf[i];
        S->next[s] = S->head[f];
        S->head[f] = s;
    }
    S->ntx = 0;
}
