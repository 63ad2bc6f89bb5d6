/*
 * improve.c - femlod_improve: the stage that raises every element to the
 * thresholds with local operators (docs/design.md "Improving a mesh in
 * place"): the options, the rounds over what breaks a threshold, the census
 * of what remains and why, the output.
 */
#include "impr.h"
#include "../improve.h"

#include <stdlib.h>
#include <string.h>
#include <time.h>

#define DEFAULT_MIN_STRETCH 0.2
#define DEFAULT_MAX_VALENCE 12
#define DEFAULT_DEVIATION 0.001 /* x the bounding-box diagonal */
#define DEFAULT_FEATURE_ANGLE 40.0
#define DEFAULT_NORMAL_CHANGE 60.0
#define DEFAULT_ROUNDS 20

static const char *const reason_names[FEMLOD_IMPROVE_REASON_COUNT] = {
    "corner", "fixed", "deviation", "stretch", "valence", "foldover", "topology", "intersection", "untried", "depth"};

const char *femlod_improve_reason_name(femlod_improve_reason reason) {
    if ((int)reason < 0 || reason >= FEMLOD_IMPROVE_REASON_COUNT) return "unknown";
    return reason_names[reason];
}

static double wall(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static double resolve(double v, double def) { return v == 0.0 ? def : (v < 0.0 ? FEMLOD_SIMPLIFY_OFF : v); }

/* the input's counts of elements breaking a threshold */
typedef struct census {
    size_t st, sz, val;
    double stmin;
    uint32_t valmax;
} census;

static femlod_status measure_input(const femlod_mesh *m, const im_params *p, census *c, femlod_error *err) {
    memset(c, 0, sizeof *c);
    c->stmin = m->nt ? 1.0 : 0.0;
    for (size_t f = 0; f < m->nt; f++) {
        const uint32_t *t = m->tri + 3 * f;
        if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) { /* stretch 0; dropped from the output */
            c->stmin = 0.0;
            if (p->st_on) c->st++;
            continue;
        }
        const double *a = m->pos + 3 * (size_t)t[0], *b = m->pos + 3 * (size_t)t[1], *d = m->pos + 3 * (size_t)t[2];
        double s = im_stretch(a, b, d);
        c->stmin = fmin(c->stmin, s);
        if (p->st_on && s < p->minst) c->st++;
        if (p->sz_on) {
            double L2 = fmax(dist2(a, b), fmax(dist2(b, d), dist2(a, d)));
            if (L2 > p->maxsz * p->maxsz) c->sz++;
        }
    }
    uint32_t *val = fl_alloc(m->nv ? m->nv : 1, sizeof *val);
    if (!val) return fl_error(err, FEMLOD_ENOMEM, "improve: out of memory");
    femlod_status st = femlod_valence_array(val, m->nv, m->tri, m->nt, err);
    if (st != FEMLOD_OK) {
        free(val);
        return st;
    }
    for (size_t v = 0; v < m->nv; v++) {
        c->valmax = val[v] > c->valmax ? val[v] : c->valmax;
        if (p->val_on && val[v] > (uint32_t)p->maxval) c->val++;
    }
    free(val);
    return FEMLOD_OK;
}

typedef struct run {
    im_ctx C;
    uint8_t *vreason; /* per vertex: last refusal of a valence fix, +1 */
    size_t capvr;
    size_t budget;    /* splits left (bounds the growth: 4 per input triangle) */
} run;

static int vreason_set(run *R, uint32_t v, int why) {
    if (v >= R->capvr) {
        size_t c = R->capvr ? R->capvr : 64;
        while (c <= v) c *= 2;
        uint8_t *p = fl_realloc(R->vreason, c, 1);
        if (!p) return 0;
        memset(p + R->capvr, 0, c - R->capvr);
        R->vreason = p;
        R->capvr = c;
    }
    R->vreason[v] = (uint8_t)(why + 1);
    return 1;
}

static int face_live(const imesh *M, uint32_t f) { return M->tri[3 * (size_t)f] != IM_DEAD; }

/* the corner opposite the longest edge (k: the edge is t[k+1], t[k+2]) and
 * the shortest edge's first corner */
static void face_edges(const imesh *M, uint32_t f, int *longest, int *shortest) {
    const uint32_t *t = M->tri + 3 * (size_t)f;
    double l[3];
    for (int k = 0; k < 3; k++) l[k] = dist2(im_P(M, t[(k + 1) % 3]), im_P(M, t[(k + 2) % 3]));
    int lo = 0, hi = 0;
    for (int k = 1; k < 3; k++) {
        if (l[k] > l[hi]) hi = k;
        if (l[k] < l[lo]) lo = k;
    }
    *longest = hi;
    *shortest = lo;
}

/* One try at a triangle below min_stretch: flip its longest edge, collapse
 * its shortest, or split a cap's longest edge at the apex's foot and take
 * the apex there. 1 when something changed. */
static int fix_face(run *R, uint32_t f) {
    im_ctx *C = &R->C;
    imesh *M = C->M;
    int lk, sk, why = FEMLOD_IMPROVE_UNTRIED, w;
    face_edges(M, f, &lk, &sk);
    /* a copy: a split may move the face array */
    uint32_t t[3];
    memcpy(t, M->tri + 3 * (size_t)f, sizeof t);
    uint32_t c = t[lk], a = t[(lk + 1) % 3], b = t[(lk + 2) % 3];
    uint32_t x = t[(sk + 1) % 3], y = t[(sk + 2) % 3];
    if (fl_imop_flip(C, a, b, 0, &w)) return 1;
    why = w;
    if (fl_imop_collapse(C, x, y, &w)) return 1;
    if (why == FEMLOD_IMPROVE_TOPOLOGY || why == FEMLOD_IMPROVE_STRETCH) why = w;
    if (R->budget == 0 || C->oom) goto refused;
    /* a cap (the apex's foot inside ab): split there, take the apex onto it */
    const double *pa = im_P(M, a), *pb = im_P(M, b), *pc = im_P(M, c);
    double ab[3], ac[3];
    sub3(ab, pb, pa);
    sub3(ac, pc, pa);
    double s = dot3(ab, ac) / dot3(ab, ab);
    if (s > 0.1 && s < 0.9 && M->vclass[c] == IM_FREE) {
        double foot[3];
        for (int k = 0; k < 3; k++) foot[k] = pa[k] + s * ab[k];
        if (fl_imop_split(C, a, b, foot, &w)) {
            R->budget--;
            uint32_t m = (uint32_t)M->nv - 1;
            /* the apex onto the foot; without it, the halves are left to the
             * next operators */
            fl_imop_collapse(C, c, m, &w);
            return 1;
        }
        why = w;
    } else if (s <= 0.1 || s >= 0.9) {
        /* a needle: halve its longest edge; the halves are needles of half
         * the aspect, which the next tries halve again or collapse */
        int done = 0;
        if (fl_imop_split(C, a, b, NULL, &w)) {
            R->budget--;
            done = 1;
        } else
            why = w;
        /* and the other long edge (c, z): a strip's needle has its long
         * side and its diagonal nearly alike, and only halving both makes
         * the halves rounder */
        uint32_t z = t[sk];
        double ls = dist2(im_P(M, x), im_P(M, y));
        if (done && R->budget > 0 && z != c && fl_imesh_has_edge(M, c, z) &&
            dist2(im_P(M, c), im_P(M, z)) > 4.0 * ls && fl_imop_split(C, c, z, NULL, &w))
            R->budget--;
        if (done) return 1;
    }
refused:
    if (face_live(M, f)) M->freason[f] = (uint8_t)(why + 1);
    return 0;
}

/* A vertex above max_valence: flips of its edges that lower it, then
 * splits of its longest spokes (later collapses join the new ring). */
static int fix_valence(run *R, uint32_t v) {
    im_ctx *C = &R->C;
    imesh *M = C->M;
    const im_params *p = C->p;
    int changed = 0, why = FEMLOD_IMPROVE_UNTRIED, w;
    if (M->vclass[v] == IM_FIXED) why = FEMLOD_IMPROVE_FIXED;
    for (int pass = 0; pass < 2; pass++) {
        if (fl_imesh_valence(M, v) <= (uint32_t)p->maxval) return changed;
        /* the neighbours now, in face-list order */
        size_t nn = 0;
        const im_list *l = M->vf + v;
        uint32_t s = fl_imesh_next_stamp(M);
        if (!buf_grow(&C->buf, &C->bufcap, 3 * (size_t)l->n)) {
            C->oom = 1;
            return changed;
        }
        for (uint32_t i = 0; i < l->n; i++) {
            const uint32_t *t = M->tri + 3 * (size_t)l->f[i];
            for (int k = 0; k < 3; k++)
                if (t[k] != v && M->vmark[t[k]] != s) {
                    M->vmark[t[k]] = s;
                    C->buf[nn++] = t[k];
                }
        }
        uint32_t *nb = malloc((nn ? nn : 1) * sizeof *nb);
        if (!nb) {
            C->oom = 1;
            return changed;
        }
        memcpy(nb, C->buf, nn * sizeof *nb);
        for (size_t i = 0; i < nn; i++) {
            if (fl_imesh_valence(M, v) <= (uint32_t)p->maxval) break;
            if (pass == 0) {
                if (fl_imop_flip(C, v, nb[i], 1, &w)) changed = 1;
                else if (why != FEMLOD_IMPROVE_FIXED) why = w;
            } else if (R->budget > 0 && fl_imesh_has_edge(M, v, nb[i])) {
                /* spokes longer than the shortest: split in the middle */
                double lmin = INFINITY;
                for (size_t j = 0; j < nn; j++)
                    if (fl_imesh_has_edge(M, v, nb[j])) lmin = fmin(lmin, dist2(im_P(M, v), im_P(M, nb[j])));
                if (dist2(im_P(M, v), im_P(M, nb[i])) > 1.0 * lmin) {
                    if (fl_imop_split(C, v, nb[i], NULL, &w)) {
                        changed = 1;
                        R->budget--;
                    } else if (why != FEMLOD_IMPROVE_FIXED)
                        why = w;
                }
            }
        }
        free(nb);
    }
    if (!vreason_set(R, v, why)) C->oom = 1;
    return changed;
}

static femlod_status make_output(femlod_mesh **out, imesh *M, uint32_t *vmap, femlod_error *err) {
    uint32_t *map = fl_alloc(M->nv ? M->nv : 1, sizeof *map);
    if (!map) return fl_error(err, FEMLOD_ENOMEM, "improve: out of memory");
    size_t nv = 0;
    for (size_t v = 0; v < M->nv; v++) map[v] = M->vf[v].n ? (uint32_t)nv++ : IM_DEAD;
    if (vmap) memcpy(vmap, map, M->nv0 * sizeof *vmap);
    femlod_mesh *m = fl_mesh_alloc(nv, M->live);
    if (!m) {
        free(map);
        return fl_error(err, FEMLOD_ENOMEM, "improve: out of memory");
    }
    for (size_t v = 0; v < M->nv; v++)
        if (map[v] != IM_DEAD) memcpy(m->pos + 3 * (size_t)map[v], M->pos + 3 * v, 3 * sizeof *m->pos);
    size_t k = 0;
    for (size_t f = 0; f < M->nt; f++) {
        const uint32_t *t = M->tri + 3 * f;
        if (t[0] == IM_DEAD) continue;
        for (int c = 0; c < 3; c++) m->tri[3 * k + (size_t)c] = map[t[c]];
        k++;
    }
    free(map);
    *out = m;
    return FEMLOD_OK;
}

/* What still breaks a threshold, by reason. */
static void final_census(run *R, femlod_improve_report *rep) {
    imesh *M = R->C.M;
    const im_params *p = R->C.p;
    rep->stretch_min = M->live ? 1.0 : 0.0;
    for (size_t f = 0; f < M->nt; f++) {
        if (!face_live(M, (uint32_t)f)) continue;
        const uint32_t *t = M->tri + 3 * f;
        double s = im_face_stretch(M, (uint32_t)f);
        rep->stretch_min = fmin(rep->stretch_min, s);
        int r = M->freason[f] ? M->freason[f] - 1 : FEMLOD_IMPROVE_UNTRIED;
        if (p->st_on && s < p->minst) {
            /* the sharpest angle between two feature edges: forced */
            const double *P0 = im_P(M, t[0]), *P1 = im_P(M, t[1]), *P2 = im_P(M, t[2]);
            const double *Pc[3] = {P0, P1, P2};
            int kmin = 0;
            double best = 2.0;
            for (int k = 0; k < 3; k++) {
                double u[3], w[3];
                sub3(u, Pc[(k + 1) % 3], Pc[k]);
                sub3(w, Pc[(k + 2) % 3], Pc[k]);
                double lu = sqrt(dot3(u, u)), lw = sqrt(dot3(w, w));
                double cs = lu > 0 && lw > 0 ? dot3(u, w) / (lu * lw) : 1.0;
                double ang = acos(fmax(-1.0, fmin(1.0, cs)));
                if (ang < best) {
                    best = ang;
                    kmin = k;
                }
            }
            uint32_t v = t[kmin], u = t[(kmin + 1) % 3], w = t[(kmin + 2) % 3];
            if (fl_imesh_is_feature(M, v, u) && fl_imesh_is_feature(M, v, w)) r = FEMLOD_IMPROVE_CORNER;
            else if (r == FEMLOD_IMPROVE_UNTRIED && M->vclass[t[0]] == IM_FIXED && M->vclass[t[1]] == IM_FIXED &&
                     M->vclass[t[2]] == IM_FIXED)
                r = FEMLOD_IMPROVE_FIXED;
            rep->stretch_out++;
            rep->stretch_by[r]++;
        }
        if (p->sz_on) {
            const double *a = im_P(M, t[0]), *b = im_P(M, t[1]), *c = im_P(M, t[2]);
            double L2 = fmax(dist2(a, b), fmax(dist2(b, c), dist2(a, c)));
            if (L2 > p->maxsz * p->maxsz) {
                rep->size_out++;
                rep->size_by[r]++;
            }
        }
    }
    rep->valence_max = 0;
    for (uint32_t v = 0; v < M->nv; v++) {
        if (!M->vf[v].n) continue;
        uint32_t val = fl_imesh_valence(M, v);
        if (val > rep->valence_max) rep->valence_max = val;
        if (p->val_on && val > (uint32_t)p->maxval) {
            int r = v < R->capvr && R->vreason[v] ? R->vreason[v] - 1 : FEMLOD_IMPROVE_UNTRIED;
            if (M->vclass[v] == IM_FIXED) r = FEMLOD_IMPROVE_FIXED;
            rep->valence_out++;
            rep->valence_by[r]++;
        }
    }
}

femlod_status femlod_improve(femlod_mesh **out, const femlod_mesh *mesh, const femlod_improve_options *options,
                             femlod_improve_report *report, femlod_error *err) {
    return fl_improve_mapped(out, mesh, options, report, NULL, err);
}

femlod_status fl_improve_mapped(femlod_mesh **out, const femlod_mesh *mesh, const femlod_improve_options *options,
                                femlod_improve_report *report, uint32_t *vmap, femlod_error *err) {
    double t0 = wall();
    femlod_improve_options o = FEMLOD_IMPROVE_OPTIONS_INIT;
    if (options) o = *options;
    femlod_improve_report rep;
    memset(&rep, 0, sizeof rep);
    double lo[3], hi[3];
    femlod_mesh_bbox(mesh, lo, hi);
    double diag = sqrt(dist2(lo, hi));
    if (!isfinite(o.min_stretch) || o.min_stretch > 1.0)
        return fl_error(err, FEMLOD_EINPUT, "improve: min_stretch %g is not in (0, 1]", o.min_stretch);
    if (!isfinite(o.max_size) || !isfinite(o.max_deviation) || !isfinite(o.feature_angle) ||
        !isfinite(o.max_normal_change))
        return fl_error(err, FEMLOD_EINPUT, "improve: an option is not finite");
    if (o.max_rounds < 0) return fl_error(err, FEMLOD_EINPUT, "improve: max_rounds %d is negative", o.max_rounds);
    if (o.lock_count && !o.lock) return fl_error(err, FEMLOD_EINPUT, "improve: lock_count without lock");
    for (size_t i = 0; i < o.lock_count; i++)
        if (o.lock[i] >= mesh->nv)
            return fl_error(err, FEMLOD_EINPUT, "improve: lock index %u out of range (%zu vertices)",
                            (unsigned)o.lock[i], mesh->nv);
    im_params p;
    p.minst = resolve(o.min_stretch, DEFAULT_MIN_STRETCH);
    p.maxsz = o.max_size > 0 ? o.max_size : FEMLOD_SIMPLIFY_OFF;
    p.maxval = o.max_valence == 0 ? DEFAULT_MAX_VALENCE : (o.max_valence < 0 ? -1 : o.max_valence);
    p.maxdev = resolve(o.max_deviation, DEFAULT_DEVIATION * diag);
    double fa = resolve(o.feature_angle, DEFAULT_FEATURE_ANGLE);
    double nc = resolve(o.max_normal_change, DEFAULT_NORMAL_CHANGE);
    p.cos_nc = nc < 0 ? 0.0 : cos(fmin(nc, 179.0) * 3.14159265358979323846 / 180.0);
    p.st_on = p.minst > 0;
    p.sz_on = p.maxsz > 0;
    p.val_on = p.maxval > 0;
    int rounds = o.max_rounds ? o.max_rounds : DEFAULT_ROUNDS;
    rep.min_stretch = p.minst;
    rep.max_size = p.maxsz;
    rep.max_valence = p.val_on ? p.maxval : -1;
    rep.max_deviation = p.maxdev;
    rep.feature_angle = fa;
    rep.max_normal_change = nc;
    rep.triangles_in = mesh->nt;
    rep.vertices_in = mesh->nv;
    census c;
    femlod_status st = measure_input(mesh, &p, &c, err);
    if (st != FEMLOD_OK) return st;
    rep.stretch_in = c.st;
    rep.size_in = c.sz;
    rep.valence_in = c.val;
    rep.stretch_min_in = c.stmin;
    rep.valence_max_in = c.valmax;

    uint8_t *locked = fl_calloc(mesh->nv ? mesh->nv : 1, 1);
    if (!locked) return fl_error(err, FEMLOD_ENOMEM, "improve: out of memory");
    for (size_t i = 0; i < o.lock_count; i++) locked[o.lock[i]] = 1;
    if (o.lock_fn)
        for (size_t v = 0; v < mesh->nv; v++)
            if (o.lock_fn(o.lock_payload, mesh->pos[3 * v], mesh->pos[3 * v + 1], mesh->pos[3 * v + 2]))
                locked[v] = 1;
    /* grid cells of about twice the geometric mean of the edges: a CAD
     * export's few long edges would make cells of the arithmetic mean hold
     * thousands of its many small triangles */
    double lsum = 0;
    size_t ln = 0;
    for (size_t f = 0; f < mesh->nt; f++) {
        const uint32_t *t = mesh->tri + 3 * f;
        for (int k = 0; k < 3; k++) {
            double l = dist2(mesh->pos + 3 * (size_t)t[k], mesh->pos + 3 * (size_t)t[(k + 1) % 3]);
            if (l > 0) {
                lsum += 0.5 * log(l);
                ln++;
            }
        }
    }
    double h = ln ? 2.0 * exp(lsum / (double)ln) : 1.0;
    if (!(h > 0)) h = diag > 0 ? diag : 1.0;

    imesh M;
    im_surface S;
    run R;
    memset(&R, 0, sizeof R);
    int ok = fl_imesh_init(&M, mesh, fa, locked, h) && fl_imsurf_init(&S, mesh, h);
    free(locked);
    R.C.M = &M;
    R.C.S = &S;
    R.C.p = &p;
    R.budget = 4 * mesh->nt + 1024;
    fl_progress prog;
    fl_progress_init(&prog, o.progress, o.progress_payload, (size_t)rounds);
    int nothing = c.st == 0 && c.sz == 0 && c.val == 0;
    for (int round = 0; ok && !nothing && round < rounds; round++) {
        size_t ops0 = R.C.flips + R.C.splits + R.C.collapses + R.C.relaxations;
        /* long edges */
        if (p.sz_on)
            for (uint32_t f = 0; f < M.nt && !R.C.oom; f++) {
                if (!face_live(&M, f)) continue;
                int lk, sk, w;
                face_edges(&M, f, &lk, &sk);
                const uint32_t *t = M.tri + 3 * (size_t)f;
                uint32_t a = t[(lk + 1) % 3], b = t[(lk + 2) % 3];
                if (dist2(im_P(&M, a), im_P(&M, b)) > p.maxsz * p.maxsz && R.budget > 0) {
                    if (fl_imop_split(&R.C, a, b, NULL, &w)) R.budget--;
                    else M.freason[f] = (uint8_t)(w + 1);
                }
            }
        /* triangles below min_stretch, those of the round's start: what a
         * fix makes waits for the next round, so a fix that another undoes
         * (a cap's split and collapse, then a flip back) costs one try per
         * round, not an endless chain within one (measured on the engine,
         * docs/design.md) */
        if (p.st_on)
            for (uint32_t f = 0, end = (uint32_t)M.nt; f < end && !R.C.oom; f++)
                if (face_live(&M, f) && im_face_stretch(&M, f) < p.minst) fix_face(&R, f);
        /* vertices above max_valence */
        if (p.val_on)
            for (uint32_t v = 0; v < M.nv && !R.C.oom; v++)
                if (M.vf[v].n && fl_imesh_valence(&M, v) > (uint32_t)p.maxval) fix_valence(&R, v);
        /* relaxation around what is still below min_stretch */
        if (p.st_on) {
            uint32_t end = (uint32_t)M.nt;
            for (uint32_t f = 0; f < end && !R.C.oom; f++) {
                if (!face_live(&M, f) || !(im_face_stretch(&M, f) < p.minst)) continue;
                for (int k = 0; k < 3 && face_live(&M, f); k++) {
                    int w;
                    fl_imop_relax(&R.C, M.tri[3 * (size_t)f + (size_t)k], &w);
                }
            }
        }
        rep.rounds++;
        if (R.C.oom) break;
        if (fl_progress_report(&prog, (size_t)round + 1)) {
            rep.cancelled = 1;
            break;
        }
        if (R.C.flips + R.C.splits + R.C.collapses + R.C.relaxations == ops0) break;
    }
    if (ok && R.C.oom) ok = 0;
    if (ok) {
        fl_progress_end(&prog);
        final_census(&R, &rep);
        st = make_output(out, &M, vmap, err);
    } else
        st = fl_error(err, FEMLOD_ENOMEM, "improve: out of memory");
    rep.flips = R.C.flips;
    rep.splits = R.C.splits;
    rep.collapses = R.C.collapses;
    rep.relaxations = R.C.relaxations;
    for (int k = 0; k < FEMLOD_IMPROVE_REASON_COUNT; k++) rep.refused[k] = R.C.refused[k];
    if (st == FEMLOD_OK) {
        rep.triangles = (*out)->nt;
        rep.vertices = (*out)->nv;
    }
    free(R.C.buf);
    free(R.vreason);
    fl_imesh_free(&M);
    fl_imsurf_free(&S);
    rep.seconds = wall() - t0;
    if (report && st == FEMLOD_OK) *report = rep;
    return st;
}
