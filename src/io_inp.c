/* io_inp.c - Abaqus/CalculiX input, mesh part (Abaqus Keywords Reference;
 * CalculiX CrunchiX User's Manual, sections 6 and 7).
 *
 * Written: *NODE with NSET=NALL (ids 1..nv), *ELEMENT TYPE=S3 with
 * ELSET=EALL (ids 1..nt, corners in the mesh's order, so the shell normal
 * follows the triangle winding), *NSET NBOUNDARY with the nodes of the
 * boundary edges (edges of one triangle) when there are any, *NSET
 * NFEATURE with the nodes of feature edges (boundary, non-manifold, or a
 * dihedral angle between normals above 40 degrees, the simplifier's
 * default), then the caller's node and element sets. No material, section or step: the file is
 * meant for *INCLUDE, INPUT=... from the analysis deck. Data lines hold at
 * most 10 ids, which keeps them under CalculiX's 132 characters. */
#include "io_util.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define IDS_PER_LINE 10

static int lower(int c) { return (c >= 'A' && c <= 'Z') ? c + ('a' - 'A') : c; }

static int same_name(const char *a, const char *b) {
    for (; *a && *b; a++, b++)
        if (lower((unsigned char)*a) != lower((unsigned char)*b)) return 0;
    return *a == *b;
}

static const char *const reserved[] = {"NALL", "EALL", "NBOUNDARY", "NFEATURE", NULL};

/* The sets' names and indices are valid: checked before anything is written. */
static femlod_status check_sets(const femlod_index_set *sets, size_t count, size_t limit,
                                const char *kind, const char *what, const char *path,
                                femlod_error *err) {
    for (size_t i = 0; i < count; i++) {
        const femlod_index_set *s = &sets[i];
        const char *name = s->name;
        if (!name || !*name)
            return fl_error(err, FEMLOD_EINPUT, "%s: %s set %zu has no name", path, kind, i + 1);
        size_t len = strlen(name);
        int ok =
            len <= 80 && ((name[0] >= 'A' && name[0] <= 'Z') || (name[0] >= 'a' && name[0] <= 'z'));
        for (size_t k = 1; ok && k < len; k++) {
            char c = name[k];
            ok = (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') ||
                 c == '_';
        }
        char q[48];
        if (!ok)
            return fl_error(err, FEMLOD_EINPUT,
                            "%s: %s set name '%s' is not valid (a letter, then letters, digits or "
                            "'_', at most 80)",
                            path, kind, fl_io_quote(q, sizeof q, name, len));
        for (const char *const *r = reserved; *r; r++)
            if (same_name(name, *r))
                return fl_error(err, FEMLOD_EINPUT,
                                "%s: %s set name '%s' is reserved (NALL, EALL, NBOUNDARY, NFEATURE)", path,
                                kind, name);
        for (size_t j = 0; j < i; j++)
            if (same_name(name, sets[j].name))
                return fl_error(err, FEMLOD_EINPUT,
                                "%s: %s set '%s' given twice (names ignore case)", path, kind,
                                name);
        if (s->count == 0)
            return fl_error(err, FEMLOD_EINPUT, "%s: %s set '%s' is empty", path, kind, name);
        if (!s->indices)
            return fl_error(err, FEMLOD_EINPUT, "%s: %s set '%s' has no indices", path, kind, name);
        for (size_t k = 0; k < s->count; k++)
            if (s->indices[k] >= limit)
                return fl_error(err, FEMLOD_EINPUT,
                                "%s: %s set '%s': index %lu out of range (%zu %s)", path, kind,
                                name, (unsigned long)s->indices[k], limit, what);
    }
    return FEMLOD_OK;
}

static int cmp_u32(const void *a, const void *b) {
    uint32_t x = *(const uint32_t *)a, y = *(const uint32_t *)b;
    return x < y ? -1 : x > y;
}

/* ids: sorted, unique 0-based indices; written 1-based. */
static int put_ids(FILE *fp, const uint32_t *ids, size_t n) {
    int ok = 1;
    for (size_t i = 0; i < n && ok; i++)
        ok &= fprintf(fp, "%lu%s", (unsigned long)ids[i] + 1,
                      (i + 1 == n || (i + 1) % IDS_PER_LINE == 0) ? "\n" : ", ") > 0;
    return ok;
}

static femlod_status put_set(FILE *fp, const char *keyword, const femlod_index_set *s, int *ok,
                             const char *path, femlod_error *err) {
    uint32_t *ids = fl_alloc(s->count, sizeof *ids);
    if (!ids) return fl_error(err, FEMLOD_ENOMEM, "%s: out of memory", path);
    memcpy(ids, s->indices, s->count * sizeof *ids);
    qsort(ids, s->count, sizeof *ids, cmp_u32);
    size_t n = 0;
    for (size_t i = 0; i < s->count; i++)
        if (n == 0 || ids[n - 1] != ids[i]) ids[n++] = ids[i];
    *ok &= fprintf(fp, "*%s, %s=%s\n", keyword, keyword, s->name) > 0;
    *ok &= put_ids(fp, ids, n);
    free(ids);
    return FEMLOD_OK;
}

/* The nodes of boundary edges (one triangle) and of feature edges: those,
 * non-manifold edges (three or more triangles) and edges whose two
 * triangles' normals differ by more than FEATURE_ANGLE degrees; each list
 * sorted. */
#define FEATURE_ANGLE 40.0

static void normal(const femlod_mesh *m, uint32_t t, double n[3]) {
    const uint32_t *c = m->tri + 3 * (size_t)t;
    const double *a = m->pos + 3 * (size_t)c[0], *b = m->pos + 3 * (size_t)c[1],
                 *d = m->pos + 3 * (size_t)c[2];
    double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    double v[3] = {d[0] - a[0], d[1] - a[1], d[2] - a[2]};
    n[0] = u[1] * v[2] - u[2] * v[1];
    n[1] = u[2] * v[0] - u[0] * v[2];
    n[2] = u[0] * v[1] - u[1] * v[0];
}

static femlod_status edge_nodes(const femlod_mesh *m, uint32_t **bnd, size_t *nb, uint32_t **feat,
                                size_t *nf, femlod_error *err) {
    fl_adjacency adj;
    femlod_status st = fl_adjacency_build(&adj, m->tri, m->nt, m->nv, err);
    if (st != FEMLOD_OK) return st;
    unsigned char *on = fl_calloc(m->nv, 1);
    uint32_t *b = fl_alloc(m->nv, sizeof *b), *f = fl_alloc(m->nv, sizeof *f);
    if (!on || !b || !f) {
        free(on);
        free(b);
        free(f);
        fl_adjacency_free(&adj);
        return fl_error(err, FEMLOD_ENOMEM, "out of memory");
    }
    double cos_max = cos(FEATURE_ANGLE * 3.14159265358979323846 / 180.0);
    for (size_t e = 0; e < adj.ne; e++) {
        uint32_t c = adj.edge_start[e + 1] - adj.edge_start[e];
        unsigned char mark = 0;
        if (c == 1) {
            mark = 3; /* boundary and feature */
        } else if (c >= 3) {
            mark = 2;
        } else {
            double n1[3], n2[3];
            normal(m, adj.edge_tris[adj.edge_start[e]], n1);
            normal(m, adj.edge_tris[adj.edge_start[e] + 1], n2);
            double l = sqrt(n1[0] * n1[0] + n1[1] * n1[1] + n1[2] * n1[2]) *
                       sqrt(n2[0] * n2[0] + n2[1] * n2[1] + n2[2] * n2[2]);
            if (l > 0 && (n1[0] * n2[0] + n1[1] * n2[1] + n1[2] * n2[2]) < cos_max * l) mark = 2;
        }
        on[adj.edge_v[2 * e]] |= mark;
        on[adj.edge_v[2 * e + 1]] |= mark;
    }
    size_t k = 0, j = 0;
    for (size_t v = 0; v < m->nv; v++) {
        if (on[v] & 1) b[k++] = (uint32_t)v;
        if (on[v] & 2) f[j++] = (uint32_t)v;
    }
    free(on);
    fl_adjacency_free(&adj);
    *bnd = b;
    *nb = k;
    *feat = f;
    *nf = j;
    return FEMLOD_OK;
}

femlod_status fl_write_inp(const femlod_mesh *m, FILE *fp, const femlod_write_options *options,
                           const char *path, femlod_error *err) {
    femlod_status st = FEMLOD_OK;
    const femlod_index_set *ns = options ? options->node_sets : NULL;
    const femlod_index_set *es = options ? options->element_sets : NULL;
    size_t nns = ns ? options->node_set_count : 0, nes = es ? options->element_set_count : 0;
    if (options && ((options->node_set_count && !ns) || (options->element_set_count && !es)))
        return fl_error(err, FEMLOD_EINPUT, "%s: a set count without its array", path);
    if ((st = check_sets(ns, nns, m->nv, "node", "vertices", path, err)) != FEMLOD_OK ||
        (st = check_sets(es, nes, m->nt, "element", "triangles", path, err)) != FEMLOD_OK)
        return st;
    uint32_t *bnd = NULL, *feat = NULL;
    size_t nb = 0, nf = 0;
    if ((st = edge_nodes(m, &bnd, &nb, &feat, &nf, err)) != FEMLOD_OK) {
        if (err) {
            char msg[FEMLOD_ERROR_MESSAGE_SIZE];
            snprintf(msg, sizeof msg, "%s", err->message);
            fl_error(err, st, "%s: %s", path, msg);
        }
        return st;
    }
    int ok = fprintf(fp, "** femlod %s: %zu nodes, %zu S3 elements\n*NODE, NSET=NALL\n",
                     FEMLOD_VERSION_STRING, m->nv, m->nt) > 0;
    /* CalculiX reads at most 20 characters per number (a longer one is
     * "*ERROR reading *NODE" and every later node is lost): the shortest
     * exact form when it fits, else the digits that fit (13 to 15) */
    for (size_t i = 0; i < m->nv && ok; i++) {
        char xyz[3][32];
        for (int k = 0; k < 3 && ok; k++) ok &= fl_format_double_fit(xyz[k], sizeof xyz[k], m->pos[3 * i + (size_t)k], 20) > 0;
        ok &= ok && fprintf(fp, "%zu, %s, %s, %s\n", i + 1, xyz[0], xyz[1], xyz[2]) > 0;
    }
    if (m->nt) ok &= fputs("*ELEMENT, TYPE=S3, ELSET=EALL\n", fp) >= 0;
    for (size_t i = 0; i < m->nt && ok; i++) {
        const uint32_t *t = m->tri + 3 * i;
        ok &= fprintf(fp, "%zu, %lu, %lu, %lu\n", i + 1, (unsigned long)t[0] + 1,
                      (unsigned long)t[1] + 1, (unsigned long)t[2] + 1) > 0;
    }
    if (nb) {
        ok &= fputs("*NSET, NSET=NBOUNDARY\n", fp) >= 0;
        ok &= put_ids(fp, bnd, nb);
    }
    if (nf) {
        ok &= fputs("*NSET, NSET=NFEATURE\n", fp) >= 0;
        ok &= put_ids(fp, feat, nf);
    }
    free(bnd);
    free(feat);
    for (size_t i = 0; i < nns && st == FEMLOD_OK; i++)
        st = put_set(fp, "NSET", &ns[i], &ok, path, err);
    for (size_t i = 0; i < nes && st == FEMLOD_OK; i++)
        st = put_set(fp, "ELSET", &es[i], &ok, path, err);
    if (st != FEMLOD_OK) return st;
    return ok ? FEMLOD_OK : fl_io_write_error(path, err);
}
