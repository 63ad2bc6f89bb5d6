/* io_vtk.c - VTK legacy format, version 4.2, ASCII UNSTRUCTURED_GRID
 * ("VTK File Formats", VTK User's Guide). Version 5.1 replaced CELLS'
 * size-prefixed lists with OFFSETS/CONNECTIVITY; 4.2 is what every reader
 * (ParaView, VisIt, gmsh, meshio) takes. UNSTRUCTURED_GRID rather than
 * POLYDATA because meshio refuses POLYDATA.
 *
 * Written: the points (shortest round-trip doubles), the triangles as
 * VTK_TRIANGLE (5) cells with 0-based indices, CELL_DATA "stretch" and
 * "size" (femlod_triangle_stretch/_size) and POINT_DATA "valence". */
#include "io_util.h"

#include <stdlib.h>

static int put_double(FILE *fp, double x) {
    char buf[40];
    int n = fl_format_double(buf, sizeof buf - 1, x);
    if (n < 0) return 0;
    buf[n++] = '\n';
    return fwrite(buf, 1, (size_t)n, fp) == (size_t)n;
}

femlod_status fl_write_vtk(const femlod_mesh *m, FILE *fp, const char *path, femlod_error *err) {
    size_t nv = m->nv, nt = m->nt;
    uint32_t *valence = fl_alloc(nv, sizeof *valence);
    if (!valence) return fl_error(err, FEMLOD_ENOMEM, "%s: out of memory", path);
    femlod_status st = femlod_valence_array(valence, nv, m->tri, nt, err);
    if (st != FEMLOD_OK) {
        free(valence);
        return st;
    }
    int ok = fprintf(fp,
                     "# vtk DataFile Version 4.2\nfemlod %s: %zu triangles\nASCII\n"
                     "DATASET UNSTRUCTURED_GRID\nPOINTS %zu double\n",
                     FEMLOD_VERSION_STRING, nt, nv) > 0;
    for (size_t i = 0; i < nv && ok; i++) ok &= fl_io_put_xyz(fp, m->pos + 3 * i, " ", "\n");
    ok &= fprintf(fp, "CELLS %zu %zu\n", nt, 4 * nt) > 0;
    for (size_t i = 0; i < nt && ok; i++) {
        const uint32_t *t = m->tri + 3 * i;
        ok &= fprintf(fp, "3 %lu %lu %lu\n", (unsigned long)t[0], (unsigned long)t[1],
                      (unsigned long)t[2]) > 0;
    }
    ok &= fprintf(fp, "CELL_TYPES %zu\n", nt) > 0;
    for (size_t i = 0; i < nt && ok; i++) ok &= fputs("5\n", fp) >= 0;
    if (nt) {
        ok &=
            fprintf(fp, "CELL_DATA %zu\nSCALARS stretch double 1\nLOOKUP_TABLE default\n", nt) > 0;
        for (int pass = 0; pass < 2 && ok; pass++) {
            if (pass) ok &= fputs("SCALARS size double 1\nLOOKUP_TABLE default\n", fp) >= 0;
            for (size_t i = 0; i < nt && ok; i++) {
                const uint32_t *t = m->tri + 3 * i;
                const double *a = m->pos + 3 * (size_t)t[0], *b = m->pos + 3 * (size_t)t[1],
                             *c = m->pos + 3 * (size_t)t[2];
                ok &= put_double(fp, pass ? femlod_triangle_size(a, b, c)
                                          : femlod_triangle_stretch(a, b, c));
            }
        }
    }
    if (nv) {
        ok &= fprintf(fp, "POINT_DATA %zu\nSCALARS valence int 1\nLOOKUP_TABLE default\n", nv) > 0;
        for (size_t i = 0; i < nv && ok; i++)
            ok &= fprintf(fp, "%lu\n", (unsigned long)valence[i]) > 0;
    }
    free(valence);
    return ok ? FEMLOD_OK : fl_io_write_error(path, err);
}
