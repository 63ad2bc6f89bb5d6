/*
 * hierarchy.c - the binary vertex hierarchy of a simplification and its
 * active front: vertex split and edge collapse anywhere, with dependencies
 * resolved, every front a valid FE mesh (paper sections 5.1 and 5.2).
 *
 * The dependency rule and its proof are in docs/design.md ("The vertex
 * hierarchy and its dependencies"): a front F is valid iff the set of
 * applied collapses A(F) (internal nodes at or below F) is closed under
 * vstars. split(k) therefore waits for the applied dependents of k (nodes
 * whose vstars contain k), collapse(k) for its children and vstars; both
 * recurse monotonically in collapse order, so they end. Related: Hoppe,
 * "View-dependent refinement of progressive meshes" (1997); Xia and
 * Varshney (1996); El-Sana and Varshney (1999).
 *
 * Faces: every face that ever existed has an id (input faces first, then
 * the created faces of each collapse in order). Collapse c removes the faces
 * at its two children and creates the ones around its new node; a split
 * swaps them back. So the front mesh is kept incrementally in time
 * proportional to the change.
 */
#include "core.h"

#include <assert.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "hierarchy.h"
#include "simplify_log.h"

static int is_internal(const femlod_hierarchy *h, uint32_t x) { return x >= h->nv; }

/* {====== front and active-face sets: arrays with swap-removal */

static void front_add(femlod_hierarchy *h, uint32_t x) {
    h->front_pos[x] = (uint32_t)h->front_n;
    h->front[h->front_n++] = x;
    h->state[x] = FRONT;
}

static void front_remove(femlod_hierarchy *h, uint32_t x, uint8_t new_state) {
    uint32_t p = h->front_pos[x], last = h->front[--h->front_n];
    h->front[p] = last;
    h->front_pos[last] = p;
    h->front_pos[x] = NONE;
    h->state[x] = new_state;
}

static void face_on(femlod_hierarchy *h, uint32_t f) {
    h->active_pos[f] = (uint32_t)h->active_n;
    h->active[h->active_n++] = f;
}

static void face_off(femlod_hierarchy *h, uint32_t f) {
    uint32_t p = h->active_pos[f], last = h->active[--h->active_n];
    h->active[p] = last;
    h->active_pos[last] = p;
    h->active_pos[f] = NONE;
}

static void work_push(femlod_hierarchy *h, uint32_t x) {
    if (h->collect && h->work_n < h->work_cap) h->work[h->work_n++] = x;
}

/* Front list and active faces from the node states, from scratch: a face is
 * active iff its three corners are on the front (docs/design.md). */
static void rebuild_sets(femlod_hierarchy *h) {
    h->front_n = 0;
    for (size_t x = 0; x < h->nn; x++) {
        h->front_pos[x] = NONE;
        if (h->state[x] == FRONT) front_add(h, (uint32_t)x);
    }
    h->active_n = 0;
    for (size_t f = 0; f < h->nf; f++) {
        const uint32_t *v = h->face_v + 3 * f;
        h->active_pos[f] = NONE;
        if (h->state[v[0]] == FRONT && h->state[v[1]] == FRONT && h->state[v[2]] == FRONT)
            face_on(h, (uint32_t)f);
    }
}

/* }====== */

/* {====== the two primitives, legal by construction when called */

static void do_split(femlod_hierarchy *h, uint32_t k) {
    size_t c = k - h->nv;
    uint32_t i = h->child[2 * c], j = h->child[2 * c + 1];
    for (uint32_t f = h->created_start[c]; f < h->created_start[c + 1]; f++)
        face_off(h, (uint32_t)h->nf_in + f);
    for (uint32_t r = h->removed_start[c]; r < h->removed_start[c + 1]; r++) face_on(h, h->removed[r]);
    front_remove(h, k, ABOVE);
    front_add(h, i);
    front_add(h, j);
    work_push(h, j);
    work_push(h, i);
}

static void do_collapse(femlod_hierarchy *h, uint32_t k) {
    size_t c = k - h->nv;
    uint32_t i = h->child[2 * c], j = h->child[2 * c + 1];
    for (uint32_t r = h->removed_start[c]; r < h->removed_start[c + 1]; r++) face_off(h, h->removed[r]);
    for (uint32_t f = h->created_start[c]; f < h->created_start[c + 1]; f++)
        face_on(h, (uint32_t)h->nf_in + f);
    front_remove(h, i, BELOW);
    front_remove(h, j, BELOW);
    front_add(h, k);
    if (h->parent[k] != NONE) work_push(h, h->parent[k]);
}

/* The front node at or above x (x at or below the front). */
static uint32_t front_above(const femlod_hierarchy *h, uint32_t x) {
    while (h->state[x] != FRONT) x = h->parent[x];
    return x;
}

/* Splits k (on the front, internal) after splitting whatever applied node
 * depends on k. Every pushed node was born later than the one below it on
 * the stack, so the loop ends; an explicit stack keeps deep chains off the
 * C stack. Returns the number of splits. */
size_t fl_hierarchy_force_split(femlod_hierarchy *h, uint32_t target) {
    size_t ops = 0, top = 0;
    h->stack[top++] = target;
    while (top > 0) {
        uint32_t k = h->stack[top - 1];
        if (h->state[k] != FRONT || !is_internal(h, k)) {
            top--;
            continue;
        }
        uint32_t blocker = NONE;
        for (uint32_t d = h->dep_start[k]; d < h->dep_start[k + 1]; d++)
            if (h->state[h->deps[d]] != ABOVE) {
                blocker = h->deps[d];
                break;
            }
        if (blocker != NONE) {
            assert(top < h->nn);
            h->stack[top++] = front_above(h, blocker);
            continue;
        }
        do_split(h, k);
        ops++;
        top--;
    }
    return ops;
}

/* Collapses k (above the front) after collapsing its children and vstars
 * that are still above the front; each of those was born before k. */
size_t fl_hierarchy_force_collapse(femlod_hierarchy *h, uint32_t target) {
    size_t ops = 0, top = 0;
    h->stack[top++] = target;
    while (top > 0) {
        uint32_t k = h->stack[top - 1];
        if (h->state[k] != ABOVE) {
            top--;
            continue;
        }
        size_t c = k - h->nv;
        uint32_t need = NONE;
        for (int s = 0; s < 2 && need == NONE; s++)
            if (h->state[h->child[2 * c + (size_t)s]] == ABOVE) need = h->child[2 * c + (size_t)s];
        for (uint32_t v = h->vstar_start[c]; v < h->vstar_start[c + 1] && need == NONE; v++)
            if (h->state[h->vstars[v]] == ABOVE) need = h->vstars[v];
        if (need != NONE) {
            assert(top < h->nn);
            h->stack[top++] = need;
            continue;
        }
        do_collapse(h, k);
        ops++;
        top--;
    }
    return ops;
}

/* }====== */

/* {====== construction: replay the log */

void femlod_hierarchy_free(femlod_hierarchy *h) {
    if (!h) return;
    free(h->pos);
    free(h->e_size);
    free(h->parent);
    free(h->child);
    free(h->depth);
    free(h->vstar_start);
    free(h->vstars);
    free(h->dep_start);
    free(h->deps);
    free(h->face_v);
    free(h->removed_start);
    free(h->removed);
    free(h->created_start);
    free(h->kappa);
    free(h->state);
    free(h->front);
    free(h->front_pos);
    free(h->active);
    free(h->active_pos);
    free(h->stack);
    free(h->work);
    free(h->stamp);
    free(h->index);
    free(h);
}

/* Incidence lists of the replay: a pool of (face, next) entries, a list per
 * node in the order its faces were made, newest first. Only live faces are
 * listed: the entries of a collapse's removed faces go back to a free list
 * at once (the pair's whole lists, the vstars' lists compacted in order), and
 * every corner of a removed face is the pair or one of its vstars. So the
 * pool holds 3 entries a live face, at most 3 a non-degenerate input face,
 * and the walks cost each list's live length (docs/design.md "Building the
 * hierarchy in little memory"). */
typedef struct incidence {
    uint32_t *head; /* nn */
    uint32_t *face, *next;
    uint32_t free; /* first free entry, NONE: the pool is full */
    size_t cap;
} incidence;

static int inc_add(incidence *in, uint32_t node, uint32_t f) {
    uint32_t e = in->free;
    if (e == NONE) return 0;
    in->free = in->next[e];
    in->face[e] = f;
    in->next[e] = in->head[node];
    in->head[node] = e;
    return 1;
}

/* Gives node's whole list back to the pool. */
static void inc_release(incidence *in, uint32_t node) {
    uint32_t e = in->head[node];
    while (e != NONE) {
        uint32_t n = in->next[e];
        in->next[e] = in->free;
        in->free = e;
        e = n;
    }
    in->head[node] = NONE;
}

/* Drops the dead faces from node's list, keeping the order of the rest. */
static void inc_compact(incidence *in, uint32_t node, const uint8_t *dead) {
    uint32_t *link = &in->head[node];
    while (*link != NONE) {
        uint32_t e = *link;
        if (dead[in->face[e]]) {
            *link = in->next[e];
            in->next[e] = in->free;
            in->free = e;
        } else {
            link = &in->next[e];
        }
    }
}

/* The hierarchy's arrays the replay does not write are allocated after it,
 * when its scratch (and, for fl_hierarchy_build's caller, the log) is gone:
 * the peak holds the log or the front's arrays, never both. */
static femlod_status build(femlod_hierarchy **out, const femlod_mesh *mesh,
                           femlod_collapse_log **owned, const femlod_collapse_log *log,
                           const femlod_progress_options *options, femlod_error *err) {
    if (log->base) mesh = log->base; /* the simplification improved its input first */
    size_t nv = femlod_collapse_log_input_vertices(log), nc = femlod_collapse_log_count(log);
    if (nv != mesh->nv)
        return fl_error(err, FEMLOD_EINPUT,
                        "collapse log is for %zu input vertices, the mesh has %zu", nv, mesh->nv);
    if (nv + nc > UINT32_MAX - 1) return fl_error(err, FEMLOD_EINPUT, "hierarchy too large");
    femlod_hierarchy *h = calloc(1, sizeof *h);
    incidence in = {0};
    uint8_t *dead = NULL;
    uint32_t *vmark = NULL;
    fl_progress prog;
    femlod_status st = FEMLOD_OK;
    if (!h) return fl_error(err, FEMLOD_ENOMEM, "out of memory");
    h->nv = nv;
    h->nc = nc;
    h->nn = nv + nc;
    size_t nn = h->nn;

    /* Sizes from the log: vstars, and created faces (removed ones without
     * both children). */
    size_t nvstars = 0, nremoved = 0, ncreated = 0;
    for (size_t c = 0; c < nc; c++) {
        femlod_collapse col;
        femlod_collapse_log_get(log, c, &col);
        nvstars += col.vstar_count;
        nremoved += col.face_count;
        for (size_t f = 0; f < col.face_count; f++) {
            const uint8_t *r = col.faces + 3 * f;
            int hi = (r[0] == 0) + (r[1] == 0) + (r[2] == 0);
            int hj = (r[0] == 1) + (r[1] == 1) + (r[2] == 1);
            ncreated += !(hi && hj);
        }
    }
    size_t nf_in = 0;
    for (size_t t = 0; t < mesh->nt; t++) {
        const uint32_t *v = mesh->tri + 3 * t;
        nf_in += v[0] != v[1] && v[1] != v[2] && v[0] != v[2];
    }
    h->nf_in = nf_in;
    h->nf = nf_in + ncreated;
    if (h->nf > UINT32_MAX - 1 || nvstars > UINT32_MAX || nremoved > UINT32_MAX ||
        3 * nf_in > UINT32_MAX - 1) {
        femlod_hierarchy_free(h);
        return fl_error(err, FEMLOD_EINPUT, "hierarchy too large");
    }
    size_t nf = h->nf;

    /* Leaves first, before the big arrays: e_size is the mean length of the
     * incident input edges. */
    h->e_size = fl_calloc(nn, sizeof(double));
    if (!h->e_size) {
        st = fl_error(err, FEMLOD_ENOMEM, "out of memory building a hierarchy of %zu nodes", nn);
        goto done;
    }
    st = fl_mean_edge_lengths(mesh->pos, mesh->tri, mesh->nt, mesh->nv, h->e_size, err);
    if (st != FEMLOD_OK) goto done;

    /* What the replay writes, and its scratch. */
    h->pos = fl_alloc(nn, 3 * sizeof(double));
    h->parent = fl_alloc(nn, sizeof(uint32_t));
    h->child = fl_alloc(nc, 2 * sizeof(uint32_t));
    h->vstar_start = fl_calloc(nc + 1, sizeof(uint32_t));
    h->vstars = fl_alloc(nvstars, sizeof(uint32_t));
    h->dep_start = fl_calloc(nn + 1, sizeof(uint32_t));
    h->face_v = fl_alloc(nf, 3 * sizeof(uint32_t));
    h->removed_start = fl_calloc(nc + 1, sizeof(uint32_t));
    h->removed = fl_alloc(nremoved, sizeof(uint32_t));
    h->created_start = fl_calloc(nc + 1, sizeof(uint32_t));
    in.cap = 3 * nf_in;
    in.head = fl_alloc(nn, sizeof(uint32_t));
    in.face = fl_alloc(in.cap, sizeof(uint32_t));
    in.next = fl_alloc(in.cap, sizeof(uint32_t));
    dead = fl_calloc(nf, 1);
    vmark = fl_alloc(nn, sizeof(uint32_t));
    if (!h->pos || !h->parent || !h->child || !h->vstar_start || !h->vstars || !h->dep_start ||
        !h->face_v || !h->removed_start || !h->removed || !h->created_start || !in.head ||
        !in.face || !in.next || !dead || !vmark) {
        st = fl_error(err, FEMLOD_ENOMEM, "out of memory building a hierarchy of %zu nodes", nn);
        goto done;
    }
    memset(h->parent, 0xFF, nn * sizeof(uint32_t));
    memset(in.head, 0xFF, nn * sizeof(uint32_t));
    memset(vmark, 0xFF, nn * sizeof(uint32_t));
    for (size_t e = 0; e < in.cap; e++) in.next[e] = e + 1 < in.cap ? (uint32_t)(e + 1) : NONE;
    in.free = in.cap ? 0 : NONE;
    if (nv) memcpy(h->pos, mesh->pos, nv * 3 * sizeof(double));

    /* Input faces. */
    size_t f_next = 0;
    for (size_t t = 0; t < mesh->nt; t++) {
        const uint32_t *v = mesh->tri + 3 * t;
        if (v[0] == v[1] || v[1] == v[2] || v[0] == v[2]) continue;
        memcpy(h->face_v + 3 * f_next, v, 3 * sizeof(uint32_t));
        for (int s = 0; s < 3; s++) inc_add(&in, v[s], (uint32_t)f_next);
        f_next++;
    }

    /* Replay: the bulk of the work, so progress counts its collapses. */
    fl_progress_init(&prog, options ? options->progress : NULL,
                     options ? options->progress_payload : NULL, nc);
    size_t nrem = 0, ncre = 0;
    for (size_t c = 0; c < nc; c++) {
        if (fl_progress_at(&prog, c)) {
            st = fl_progress_cancelled(err, "hierarchy");
            goto done;
        }
        femlod_collapse col;
        femlod_collapse_log_get(log, c, &col);
        uint32_t k = (uint32_t)(nv + c), i = col.i, j = col.j;
        if (i >= k || j >= k || i == j || h->parent[i] != NONE || h->parent[j] != NONE ||
            !isfinite(col.position[0]) || !isfinite(col.position[1]) ||
            !isfinite(col.position[2]) || !(col.e_size >= 0)) {
            st = fl_error(err, FEMLOD_EINPUT, "collapse log: collapse %zu is inconsistent", c);
            goto done;
        }
        h->parent[i] = h->parent[j] = k;
        h->child[2 * c] = i;
        h->child[2 * c + 1] = j;
        memcpy(h->pos + 3 * (size_t)k, col.position, sizeof col.position);
        h->e_size[k] = col.e_size;
        for (size_t s = 0; s < col.vstar_count; s++) {
            uint32_t v = col.vstars[s];
            if (v >= k || v == i || v == j || h->parent[v] != NONE) {
                st = fl_error(err, FEMLOD_EINPUT, "collapse log: collapse %zu has a bad vstar", c);
                goto done;
            }
            h->vstars[h->vstar_start[c] + s] = v;
            h->dep_start[v + 1]++;
        }
        h->vstar_start[c + 1] = h->vstar_start[c] + (uint32_t)col.vstar_count;

        /* Removed faces: the live faces at i and j, each once (a face at
         * both is dead when j's list meets it). */
        h->removed_start[c] = (uint32_t)nrem;
        h->created_start[c] = (uint32_t)ncre;
        uint32_t lists[2] = {i, j};
        for (int s = 0; s < 2; s++)
            for (uint32_t e = in.head[lists[s]]; e != NONE; e = in.next[e]) {
                uint32_t f = in.face[e];
                if (dead[f]) continue;
                if (nrem >= nremoved) {
                    st = fl_error(err, FEMLOD_EINPUT,
                                  "collapse log does not match the mesh at collapse %zu", c);
                    goto done;
                }
                dead[f] = 1;
                h->removed[nrem++] = f;
            }
        if (nrem - h->removed_start[c] != col.face_count) {
            st = fl_error(err, FEMLOD_EINPUT,
                          "collapse log does not match the mesh at collapse %zu (%zu faces "
                          "around the pair, the log says %zu)",
                          c, nrem - h->removed_start[c], col.face_count);
            goto done;
        }
        /* The vstars must be exactly the pair's neighbours (the corners of
         * its faces other than i and j): the dependency rule, and with it
         * every split and collapse, rests on that (a log from a file could
         * say otherwise). */
        {
            size_t nbrs = 0;
            for (uint32_t r = h->removed_start[c]; r < nrem; r++)
                for (int s = 0; s < 3; s++) {
                    uint32_t v = h->face_v[3 * (size_t)h->removed[r] + (size_t)s];
                    if (v != i && v != j && vmark[v] != (uint32_t)c) {
                        vmark[v] = (uint32_t)c;
                        nbrs++;
                    }
                }
            size_t listed = 0;
            for (size_t s = 0; s < col.vstar_count; s++) {
                uint32_t v = col.vstars[s];
                if (vmark[v] != (uint32_t)c) break; /* not a neighbour, or listed twice */
                vmark[v] = NONE - 1;
                listed++;
            }
            if (listed != col.vstar_count || listed != nbrs) {
                st = fl_error(err, FEMLOD_EINPUT,
                              "collapse log: collapse %zu: its vstars are not the pair's %zu "
                              "neighbours", c, nbrs);
                goto done;
            }
        }
        /* Every entry of a removed face goes back to the pool before the
         * created faces take theirs. */
        inc_release(&in, i);
        inc_release(&in, j);
        for (size_t s = 0; s < col.vstar_count; s++) inc_compact(&in, col.vstars[s], dead);
        for (uint32_t r = h->removed_start[c]; r < nrem; r++) {
            uint32_t f = h->removed[r];
            const uint32_t *v = h->face_v + 3 * (size_t)f;
            int hi = v[0] == i || v[1] == i || v[2] == i;
            int hj = v[0] == j || v[1] == j || v[2] == j;
            if (hi && hj) continue;
            uint32_t nfid = (uint32_t)(nf_in + ncre);
            if (ncre == ncreated) {
                st = fl_error(err, FEMLOD_EINPUT, "collapse log: collapse %zu creates too many faces", c);
                goto done;
            }
            uint32_t *w = h->face_v + 3 * (size_t)nfid;
            for (int s = 0; s < 3; s++) w[s] = (v[s] == i || v[s] == j) ? k : v[s];
            for (int s = 0; s < 3; s++)
                if (!inc_add(&in, w[s], nfid)) {
                    st = fl_error(err, FEMLOD_EINPUT,
                                  "collapse log: collapse %zu creates too many faces", c);
                    goto done;
                }
            ncre++;
        }
        h->removed_start[c + 1] = (uint32_t)nrem;
        h->created_start[c + 1] = (uint32_t)ncre;
    }
    if (ncre != ncreated) {
        st = fl_error(err, FEMLOD_EINPUT, "collapse log: created faces do not add up");
        goto done;
    }
    size_t front = femlod_collapse_log_front(log);
    h->binding = log->binding;
    h->last_limit = FEMLOD_LIMIT_NONE;
    free(in.head);
    free(in.face);
    free(in.next);
    free(vmark);
    in.head = in.face = in.next = vmark = NULL;
    if (owned) {
        femlod_collapse_log_free(*owned);
        *owned = NULL;
        log = NULL;
        mesh = NULL;
    }

    /* The rest of the hierarchy. */
    h->depth = fl_calloc(nn, sizeof(uint32_t));
    h->deps = fl_alloc(nvstars, sizeof(uint32_t));
    h->state = fl_calloc(nn, 1);
    h->front = fl_alloc(nn, sizeof(uint32_t));
    h->front_pos = fl_alloc(nn, sizeof(uint32_t));
    h->active = fl_alloc(nf, sizeof(uint32_t));
    h->active_pos = fl_alloc(nf, sizeof(uint32_t));
    h->stack = fl_alloc(nn, sizeof(uint32_t));
    h->work_cap = nn + 2 * nc + 1;
    h->work = fl_alloc(h->work_cap, sizeof(uint32_t));
    h->stamp = fl_calloc(nn, sizeof(uint32_t));
    h->index = fl_alloc(nn, sizeof(uint32_t));
    if (!h->depth || !h->deps || !h->state || !h->front || !h->front_pos || !h->active ||
        !h->active_pos || !h->stack || !h->work || !h->stamp || !h->index) {
        st = fl_error(err, FEMLOD_ENOMEM, "out of memory building a hierarchy of %zu nodes", nn);
        goto done;
    }

    /* Dependents: the reverse of the vstar lists, in increasing order. */
    for (size_t v = 0; v < nn; v++) h->dep_start[v + 1] += h->dep_start[v];
    memcpy(h->stack, h->dep_start, nn * sizeof(uint32_t)); /* cursors */
    for (size_t c = 0; c < nc; c++)
        for (uint32_t s = h->vstar_start[c]; s < h->vstar_start[c + 1]; s++)
            h->deps[h->stack[h->vstars[s]]++] = (uint32_t)(nv + c);

    /* Depth: parents come after their children, so walk down from the top. */
    for (size_t x = nn; x-- > 0;)
        if (h->parent[x] != NONE) h->depth[x] = h->depth[h->parent[x]] + 1;

    /* Every collapse applied: the faces alive are the ones the replay left
     * alive (a check of the log). */
    for (size_t x = 0; x < nn; x++) h->state[x] = h->parent[x] == NONE ? FRONT : BELOW;
    rebuild_sets(h);
    for (size_t f = 0; f < nf; f++)
        if ((h->active_pos[f] == NONE) != (dead[f] != 0)) {
            st = fl_error(err, FEMLOD_EINPUT, "collapse log: face %zu outlives a corner", f);
            goto done;
        }
    /* The first front: the simplification's result, after the first
     * `front` collapses (a prefix of the log is a state the simplification
     * passed through, so it is vstar-closed; docs/design.md "The hierarchy
     * below the target"). */
    if (front < nc) {
        size_t top = nv + front; /* nodes >= top are not born yet */
        for (size_t x = 0; x < nn; x++)
            h->state[x] = x >= top ? ABOVE : (h->parent[x] == NONE || h->parent[x] >= top) ? FRONT : BELOW;
        rebuild_sets(h);
    }
    fl_progress_end(&prog);

done:
    free(in.head);
    free(in.face);
    free(in.next);
    free(dead);
    free(vmark);
    if (owned && *owned) {
        femlod_collapse_log_free(*owned);
        *owned = NULL;
    }
    if (st != FEMLOD_OK) {
        femlod_hierarchy_free(h);
        return st;
    }
    *out = h;
    return FEMLOD_OK;
}

femlod_status femlod_hierarchy_create(femlod_hierarchy **out, const femlod_mesh *mesh,
                                      const femlod_collapse_log *log,
                                      const femlod_progress_options *options, femlod_error *err) {
    assert(out && mesh && log);
    return build(out, mesh, NULL, log, options, err);
}

femlod_status femlod_hierarchy_create_from_log(femlod_hierarchy **out, const femlod_mesh *mesh,
                                               femlod_collapse_log **log,
                                               const femlod_progress_options *options,
                                               femlod_error *err) {
    assert(out && mesh && log && *log);
    return build(out, mesh, log, *log, options, err);
}

/* }====== */

/* {====== queries */

size_t femlod_hierarchy_node_count(const femlod_hierarchy *h) { return h->nn; }
size_t femlod_hierarchy_input_vertices(const femlod_hierarchy *h) { return h->nv; }
size_t femlod_hierarchy_front_nodes(const femlod_hierarchy *h) { return h->front_n; }
size_t femlod_hierarchy_front_triangles(const femlod_hierarchy *h) { return h->active_n; }

int femlod_hierarchy_node(const femlod_hierarchy *h, uint32_t id, femlod_node_info *out) {
    if (id >= h->nn) return 0;
    out->id = id;
    out->parent = h->parent[id];
    out->child[0] = is_internal(h, id) ? h->child[2 * (id - h->nv)] : NONE;
    out->child[1] = is_internal(h, id) ? h->child[2 * (id - h->nv) + 1] : NONE;
    memcpy(out->position, h->pos + 3 * (size_t)id, sizeof out->position);
    out->e_size = h->e_size[id];
    out->depth = h->depth[id];
    out->state = h->state[id] == FRONT ? FEMLOD_NODE_FRONT
                 : h->state[id] == ABOVE ? FEMLOD_NODE_ABOVE
                                         : FEMLOD_NODE_BELOW;
    return 1;
}

const uint32_t *femlod_hierarchy_front(const femlod_hierarchy *h, size_t *count) {
    if (count) *count = h->front_n;
    return h->front;
}

size_t femlod_hierarchy_bytes(const femlod_hierarchy *h) {
    size_t nn = h->nn, nc = h->nc, nf = h->nf;
    size_t nvs = h->vstar_start[nc], nrem = h->removed_start[nc];
    size_t per_node = 4 * sizeof(double)          /* pos, e_size */
                      + 7 * sizeof(uint32_t) + 1; /* parent, depth, dep_start, front, front_pos,
                                                     stack, stamp/index below; state */
    return sizeof *h + nn * (per_node + 2 * sizeof(uint32_t)) +
           nc * 5 * sizeof(uint32_t)            /* child, vstar/removed/created starts */
           + 2 * nvs * sizeof(uint32_t)         /* vstars, dependents */
           + nf * 5 * sizeof(uint32_t)          /* face corners, active, active_pos */
           + nrem * sizeof(uint32_t) + h->work_cap * sizeof(uint32_t);
}

/* }====== */

/* {====== operations */

femlod_status femlod_hierarchy_split(femlod_hierarchy *h, uint32_t node, size_t *ops,
                                     femlod_error *err) {
    if (ops) *ops = 0;
    if (node >= h->nn) return fl_error(err, FEMLOD_EINPUT, "node %u does not exist (%zu nodes)", node, h->nn);
    if (!is_internal(h, node))
        return fl_error(err, FEMLOD_EINPUT, "node %u is an input vertex: it has no split", node);
    if (h->state[node] != FRONT)
        return fl_error(err, FEMLOD_EINPUT, "node %u is not on the front", node);
    size_t n = fl_hierarchy_force_split(h, node);
    if (ops) *ops = n;
    return FEMLOD_OK;
}

femlod_status femlod_hierarchy_collapse(femlod_hierarchy *h, uint32_t node, size_t *ops,
                                        femlod_error *err) {
    if (ops) *ops = 0;
    if (node >= h->nn) return fl_error(err, FEMLOD_EINPUT, "node %u does not exist (%zu nodes)", node, h->nn);
    if (!is_internal(h, node))
        return fl_error(err, FEMLOD_EINPUT, "node %u is an input vertex: it has no children to collapse", node);
    if (h->state[node] != ABOVE)
        return fl_error(err, FEMLOD_EINPUT, "node %u is already collapsed (on or below the front)", node);
    size_t n = fl_hierarchy_force_collapse(h, node);
    if (ops) *ops = n;
    return FEMLOD_OK;
}

static femlod_status threshold(const femlod_hierarchy *h, uint32_t x, double size,
                               femlod_size_fn fn, void *payload, double *t, femlod_error *err) {
    if (!fn) {
        *t = size;
        return FEMLOD_OK;
    }
    femlod_node_info info;
    femlod_hierarchy_node(h, x, &info);
    *t = fn(payload, &info);
    if (isnan(*t)) return fl_error(err, FEMLOD_ECANCELLED, "size function stopped the operation");
    return FEMLOD_OK;
}

femlod_status femlod_hierarchy_refine(femlod_hierarchy *h, double size, femlod_size_fn fn,
                                      void *payload, size_t *ops, femlod_error *err) {
    return fl_hierarchy_refine_progress(h, size, fn, payload, NULL, "refine", ops, err);
}

femlod_status fl_hierarchy_refine_progress(femlod_hierarchy *h, double size, femlod_size_fn fn,
                                           void *payload, const femlod_progress_options *options,
                                           const char *what, size_t *ops, femlod_error *err) {
    if (ops) *ops = 0;
    if (!fn && isnan(size)) return fl_error(err, FEMLOD_EINPUT, "size is NaN");
    size_t done = 0;
    femlod_status st = FEMLOD_OK;
    /* Candidates: the front as it is, in reverse so that they are taken in
     * front order; every split pushes its children. */
    h->work_n = 0;
    for (size_t p = h->front_n; p-- > 0;) h->work[h->work_n++] = h->front[p];
    /* Progress: the larger of two shares, each a lower bound of the work
     * done. The starting front's nodes lie at the bottom of the stack,
     * under the children that splits push, so those still on it are
     * min(work_n, left): one share is the front walked, 1 - left / front.
     * The other is the splits done of the most there can be (the internal
     * nodes on or below the front): a split cascades through its
     * dependencies, so one early node can carry most of the work. Each is
     * tested with an integer compare; the division comes every 1%. */
    size_t front0 = h->work_n, left = front0, smax = 0;
    fl_progress prog;
    fl_progress_init(&prog, options ? options->progress : NULL,
                     options ? options->progress_payload : NULL, 100);
    if (prog.fn)
        for (size_t c = 0; c < h->nc; c++) smax += h->state[h->nv + c] != ABOVE;
    size_t wstep = front0 / 100 + 1, sstep = smax / 100 + 1, wnext = 0, snext = 0;
    h->collect = 1;
    while (h->work_n > 0) {
        if (h->work_n <= left) left = h->work_n;
        if (prog.fn && (front0 - left >= wnext || done >= snext)) {
            wnext = front0 - left + wstep;
            snext = done + sstep;
            double w = (double)(front0 - left) / (double)front0;
            double sp = smax ? (double)done / (double)smax : 0.0;
            if (fl_progress_fraction(&prog, w > sp ? w : sp)) {
                st = fl_progress_cancelled(err, what);
                break;
            }
        }
        uint32_t x = h->work[--h->work_n];
        if (h->state[x] != FRONT || !is_internal(h, x)) continue;
        double t;
        st = threshold(h, x, size, fn, payload, &t, err);
        if (st != FEMLOD_OK) break;
        if (t < h->e_size[x]) done += fl_hierarchy_force_split(h, x);
    }
    h->collect = 0;
    h->work_n = 0;
    if (st == FEMLOD_OK) fl_progress_end(&prog);
    if (ops) *ops = done;
    return st;
}

femlod_status femlod_hierarchy_coarsen(femlod_hierarchy *h, double size, femlod_size_fn fn,
                                       void *payload, size_t *ops, femlod_error *err) {
    if (ops) *ops = 0;
    if (!fn && isnan(size)) return fl_error(err, FEMLOD_EINPUT, "size is NaN");
    size_t done = 0;
    femlod_status st = FEMLOD_OK;
    h->work_n = 0;
    for (size_t p = h->front_n; p-- > 0;) {
        uint32_t q = h->parent[h->front[p]];
        if (q != NONE) h->work[h->work_n++] = q;
    }
    h->collect = 1;
    while (h->work_n > 0) {
        uint32_t k = h->work[--h->work_n];
        if (h->state[k] != ABOVE) continue;
        size_t c = k - h->nv;
        if (h->state[h->child[2 * c]] != FRONT || h->state[h->child[2 * c + 1]] != FRONT) continue;
        double t;
        st = threshold(h, k, size, fn, payload, &t, err);
        if (st != FEMLOD_OK) break;
        if (h->e_size[k] <= t) done += fl_hierarchy_force_collapse(h, k);
    }
    h->collect = 0;
    h->work_n = 0;
    if (ops) *ops = done;
    return st;
}

/* Sorts n ids in place (LSD radix, three 11-bit digits): linear time, so
 * extraction stays linear in the front while its order stays canonical. */
static int radix_sort_u32(uint32_t *v, size_t n) {
    if (n < 2) return 1;
    uint32_t *tmp = fl_alloc(n, sizeof *tmp);
    if (!tmp) return 0;
    uint32_t *src = v, *dst = tmp;
    for (int shift = 0; shift < 33; shift += 11) {
        size_t count[2049] = {0};
        for (size_t i = 0; i < n; i++) count[((src[i] >> shift) & 2047u) + 1]++;
        for (size_t b = 0; b < 2048; b++) count[b + 1] += count[b];
        for (size_t i = 0; i < n; i++) dst[count[(src[i] >> shift) & 2047u]++] = src[i];
        uint32_t *t = src;
        src = dst;
        dst = t;
    }
    /* three passes: the result is in tmp */
    memcpy(v, src, n * sizeof *v);
    free(tmp);
    return 1;
}

femlod_status femlod_hierarchy_extract(femlod_hierarchy *h, femlod_mesh **out, uint32_t **nodes,
                                       femlod_error *err) {
    assert(out);
    size_t nt = h->active_n;
    uint32_t *faces = fl_alloc(nt, sizeof(uint32_t));
    uint32_t *verts = fl_alloc(h->front_n, sizeof(uint32_t));
    if (!faces || !verts) goto nomem;
    memcpy(faces, h->active, nt * sizeof(uint32_t));
    if (++h->epoch == 0) {
        memset(h->stamp, 0, h->nn * sizeof(uint32_t));
        h->epoch = 1;
    }
    size_t nv = 0;
    for (size_t a = 0; a < nt; a++) {
        const uint32_t *v = h->face_v + 3 * (size_t)faces[a];
        for (int s = 0; s < 3; s++)
            if (h->stamp[v[s]] != h->epoch) {
                h->stamp[v[s]] = h->epoch;
                verts[nv++] = v[s];
            }
    }
    if (!radix_sort_u32(faces, nt) || !radix_sort_u32(verts, nv)) goto nomem;
    femlod_mesh *m = fl_mesh_alloc(nv, nt);
    if (!m) goto nomem;
    /* index[] is scratch: only the entries of the used nodes, written here,
     * are read, so it never needs clearing. */
    for (size_t i = 0; i < nv; i++) {
        h->index[verts[i]] = (uint32_t)i;
        memcpy(m->pos + 3 * i, h->pos + 3 * (size_t)verts[i], 3 * sizeof(double));
    }
    for (size_t a = 0; a < nt; a++)
        for (int s = 0; s < 3; s++)
            m->tri[3 * a + (size_t)s] = h->index[h->face_v[3 * (size_t)faces[a] + (size_t)s]];
    free(faces);
    *out = m;
    if (nodes) {
        *nodes = verts;
    } else {
        free(verts);
    }
    return FEMLOD_OK;

nomem:
    free(faces);
    free(verts);
    return fl_error(err, FEMLOD_ENOMEM, "out of memory extracting %zu triangles", nt);
}

femlod_status fl_hierarchy_set_front(femlod_hierarchy *h, const uint32_t *nodes, size_t count,
                                     femlod_error *err) {
    /* Parents have larger ids than their children: walking down from the
     * top, a node is below the front iff its parent is on or below it. */
    memset(h->state, 0xFF, h->nn);
    for (size_t i = 0; i < count; i++) {
        if (nodes[i] >= h->nn)
            return fl_error(err, FEMLOD_EPARSE, "front node %u does not exist", nodes[i]);
        if (h->state[nodes[i]] == FRONT)
            return fl_error(err, FEMLOD_EPARSE, "front node %u is listed twice", nodes[i]);
        h->state[nodes[i]] = FRONT;
    }
    femlod_status st = FEMLOD_OK;
    for (size_t x = h->nn; x-- > 0 && st == FEMLOD_OK;) {
        uint32_t p = h->parent[x];
        int parent_low = p != NONE && (h->state[p] == FRONT || h->state[p] == BELOW);
        if (h->state[x] == FRONT) {
            if (parent_low)
                st = fl_error(err, FEMLOD_EPARSE, "front nodes %zu and its ancestor overlap", x);
        } else if (parent_low) {
            h->state[x] = BELOW;
        } else if (!is_internal(h, (uint32_t)x)) {
            st = fl_error(err, FEMLOD_EPARSE, "input vertex %zu is not covered by the front", x);
        } else {
            h->state[x] = ABOVE;
        }
    }
    if (st == FEMLOD_OK) {
        rebuild_sets(h);
        femlod_error verr;
        if (femlod_hierarchy_validate(h, &verr) != FEMLOD_OK)
            st = fl_error(err, FEMLOD_EPARSE, "saved front is not valid: %s", verr.message);
    }
    if (st != FEMLOD_OK) {
        /* Back to the simplification's result: every collapse applied. */
        for (size_t x = 0; x < h->nn; x++) h->state[x] = h->parent[x] == NONE ? FRONT : BELOW;
        rebuild_sets(h);
    }
    return st;
}

/* }====== */

/* {====== the invariant, checked from scratch (tests, fuzzing) */

femlod_status femlod_hierarchy_validate(const femlod_hierarchy *h, femlod_error *err) {
    size_t front = 0;
    for (uint32_t x = 0; x < h->nn; x++) {
        uint8_t s = h->state[x];
        uint32_t p = h->parent[x];
        if (s > BELOW) return fl_error(err, FEMLOD_EINPUT, "node %u: bad state", x);
        if (s == ABOVE && !is_internal(h, x))
            return fl_error(err, FEMLOD_EINPUT, "leaf %u is above the front", x);
        if (s == BELOW && (p == NONE || h->state[p] == ABOVE))
            return fl_error(err, FEMLOD_EINPUT, "node %u is below the front but its parent is not", x);
        if (s != BELOW && p != NONE && h->state[p] != ABOVE)
            return fl_error(err, FEMLOD_EINPUT, "node %u and its parent are both at or below the front", x);
        if (s == FRONT) {
            front++;
            if (h->front_pos[x] == NONE || h->front[h->front_pos[x]] != x)
                return fl_error(err, FEMLOD_EINPUT, "front node %u is not in the front list", x);
        } else if (h->front_pos[x] != NONE) {
            return fl_error(err, FEMLOD_EINPUT, "node %u is in the front list but not on the front", x);
        }
        /* vstar closure of the applied set */
        if (is_internal(h, x) && s != ABOVE) {
            size_t c = x - h->nv;
            for (uint32_t v = h->vstar_start[c]; v < h->vstar_start[c + 1]; v++)
                if (h->state[h->vstars[v]] == ABOVE)
                    return fl_error(err, FEMLOD_EINPUT,
                                    "applied node %u has vstar %u above the front", x,
                                    h->vstars[v]);
        }
    }
    if (front != h->front_n) return fl_error(err, FEMLOD_EINPUT, "front list size is wrong");
    size_t active = 0;
    for (uint32_t f = 0; f < h->nf; f++) {
        const uint32_t *v = h->face_v + 3 * (size_t)f;
        int want = h->state[v[0]] == FRONT && h->state[v[1]] == FRONT && h->state[v[2]] == FRONT;
        int have = h->active_pos[f] != NONE;
        if (want != have)
            return fl_error(err, FEMLOD_EINPUT, "face %u (%u %u %u) is %s but its corners %s on the front",
                            f, v[0], v[1], v[2], have ? "active" : "inactive",
                            want ? "are all" : "are not all");
        if (have && h->active[h->active_pos[f]] != f)
            return fl_error(err, FEMLOD_EINPUT, "active list is inconsistent at face %u", f);
        active += (size_t)have;
    }
    if (active != h->active_n) return fl_error(err, FEMLOD_EINPUT, "active face count is wrong");
    return FEMLOD_OK;
}

/* }====== */
