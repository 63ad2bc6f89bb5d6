// bench_peers.cpp - femlod_simplify beside its two peers at equal triangle
// counts (issue 37), in its default order (the error order) and the paper's
// order (each with and without max_deviation): meshoptimizer (meshopt_simplify, no error limit) and
// OpenMesh's decimater with ModQuadric, ModAspectRatio(5) and
// ModNormalFlipping. Prints, per tool, the time, femlod's own Hausdorff
// distance of the output to the input (femlod_mesh_hausdorff), the stretch
// average and minimum, the largest size and the largest valence.
//
//   bench_peers MESH LEVELS TARGET [TARGET ...]
//
// LEVELS: 1-to-4 subdivisions of MESH first (the benchmark's cover2 is
// cover.obj with 2). C++ because OpenMesh is; the library is used through
// its C header only.
#include <OpenMesh/Core/IO/MeshIO.hh>
#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>
#include <OpenMesh/Tools/Decimater/DecimaterT.hh>
#include <OpenMesh/Tools/Decimater/ModAspectRatioT.hh>
#include <OpenMesh/Tools/Decimater/ModNormalFlippingT.hh>
#include <OpenMesh/Tools/Decimater/ModQuadricT.hh>

#include <meshoptimizer.h>

extern "C" {
#include "femlod.h"
}
#include "bench_util.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <vector>

typedef OpenMesh::TriMesh_ArrayKernelT<> OMesh;

static void print_row(const char *tool, double seconds, const femlod_mesh *out, const femlod_mesh *in) {
    femlod_quality q;
    femlod_hausdorff_result h;
    if (femlod_mesh_quality(out, &q, NULL) != FEMLOD_OK || femlod_mesh_hausdorff(out, in, NULL, &h, NULL) != FEMLOD_OK) {
        std::printf("| %s | failed |\n", tool);
        return;
    }
    std::printf("| %-19s | %7zu | %8.3f s | %.3g (%.2e of the diagonal) | %.3f | %.3f | %.3g | %u |\n", tool,
                q.triangles, seconds, h.distance, h.relative, q.stretch_avg, q.stretch_min, q.size_max,
                (unsigned)q.valence_max);
    std::fflush(stdout);
}

static femlod_mesh *from_arrays(const std::vector<double> &pos, const std::vector<uint32_t> &tri) {
    femlod_mesh *m = NULL;
    if (femlod_mesh_create(&m, pos.data(), pos.size() / 3, tri.data(), tri.size() / 3, NULL) != FEMLOD_OK) return NULL;
    return m;
}

static void run_openmesh(const femlod_mesh *in, size_t target) {
    size_t nv = femlod_mesh_vertex_count(in), nt = femlod_mesh_triangle_count(in);
    const double *p = femlod_mesh_positions(in);
    const uint32_t *t = femlod_mesh_triangles(in);
    double t0 = bench_now();
    OMesh m;
    std::vector<OMesh::VertexHandle> vh(nv);
    for (size_t v = 0; v < nv; v++) vh[v] = m.add_vertex(OMesh::Point((float)p[3 * v], (float)p[3 * v + 1], (float)p[3 * v + 2]));
    for (size_t f = 0; f < nt; f++) m.add_face(vh[t[3 * f]], vh[t[3 * f + 1]], vh[t[3 * f + 2]]);
    m.request_face_normals(); /* ModNormalFlipping compares them */
    m.update_face_normals();
    OpenMesh::Decimater::DecimaterT<OMesh> dec(m);
    OpenMesh::Decimater::ModQuadricT<OMesh>::Handle hq;
    OpenMesh::Decimater::ModAspectRatioT<OMesh>::Handle ha;
    OpenMesh::Decimater::ModNormalFlippingT<OMesh>::Handle hn;
    dec.add(hq);
    dec.add(ha);
    dec.add(hn);
    dec.module(hq).unset_max_err();
    dec.module(ha).set_aspect_ratio(5.0f);
    dec.module(ha).set_binary(true);
    dec.initialize();
    dec.decimate_to_faces(0, target);
    m.garbage_collection();
    double sec = bench_now() - t0;
    std::vector<double> pos;
    std::vector<uint32_t> tri;
    for (auto v : m.vertices()) {
        OMesh::Point q = m.point(v);
        pos.push_back(q[0]);
        pos.push_back(q[1]);
        pos.push_back(q[2]);
    }
    for (auto f : m.faces())
        for (auto v : m.fv_range(f)) tri.push_back((uint32_t)v.idx());
    femlod_mesh *out = from_arrays(pos, tri);
    if (out) print_row("OpenMesh+aspect", sec, out, in);
    femlod_mesh_free(out);
}

static void run_meshopt(const femlod_mesh *in, size_t target) {
    size_t nv = femlod_mesh_vertex_count(in), nt = femlod_mesh_triangle_count(in);
    const double *p = femlod_mesh_positions(in);
    const uint32_t *t = femlod_mesh_triangles(in);
    std::vector<float> fpos(3 * nv);
    for (size_t k = 0; k < 3 * nv; k++) fpos[k] = (float)p[k];
    std::vector<unsigned> idx(t, t + 3 * nt), dst(3 * nt);
    double t0 = bench_now();
    float err = 0;
    size_t n = meshopt_simplify(dst.data(), idx.data(), idx.size(), fpos.data(), nv, 3 * sizeof(float), 3 * target, 1e30f, 0, &err);
    double sec = bench_now() - t0;
    std::vector<double> pos(p, p + 3 * nv);
    std::vector<uint32_t> tri(dst.begin(), dst.begin() + (long)n);
    femlod_mesh *out = from_arrays(pos, tri);
    if (out) print_row("meshoptimizer", sec, out, in);
    femlod_mesh_free(out);
}

/* femlod with its defaults (one thread; the error order with fast passes above
 * 3 x target, the paper's order exact),
 * with max_deviation at rel times the bounding-box diagonal when rel > 0,
 * in the paper's order (error_order < 0) when paper */
static void run_femlod(const femlod_mesh *in, size_t target, double rel, int paper) {
    femlod_simplify_options o = FEMLOD_SIMPLIFY_OPTIONS_INIT;
    o.target = target;
    o.threads = 1;
    o.error_order = paper ? -1 : 0;
    if (rel > 0) {
        double lo[3], hi[3];
        femlod_mesh_bbox(in, lo, hi);
        o.max_deviation = rel * std::sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
                                          (hi[2] - lo[2]) * (hi[2] - lo[2]));
    }
    femlod_mesh *out = NULL;
    double t0 = bench_now();
    if (femlod_simplify(&out, NULL, in, &o, NULL, NULL) != FEMLOD_OK) return;
    static const char *const label[2][2] = {{"femlod (defaults)", "femlod, d 1e-3 diag"},
                                            {"femlod, paper's order", "femlod, paper's + d"}};
    print_row(label[paper != 0][rel > 0], bench_now() - t0, out, in);
    femlod_mesh_free(out);
}

int main(int argc, char **argv) {
    if (argc < 4) {
        std::fprintf(stderr, "usage: bench_peers MESH LEVELS TARGET [TARGET ...]\n");
        return 2;
    }
    femlod_mesh *m = NULL, *in = NULL;
    femlod_error err;
    if (femlod_mesh_read(&m, argv[1], NULL, &err) != FEMLOD_OK) {
        std::fprintf(stderr, "%s\n", err.message);
        return 1;
    }
    unsigned levels = (unsigned)std::atoi(argv[2]);
    if (levels) {
        if (femlod_mesh_subdivide(&in, m, levels, &err) != FEMLOD_OK) {
            std::fprintf(stderr, "%s\n", err.message);
            return 1;
        }
        femlod_mesh_free(m);
    } else {
        in = m;
    }
    std::printf("%s subdivided %u times: %zu triangles\n\n", argv[1], levels, femlod_mesh_triangle_count(in));
    std::printf("| tool | triangles | time | Hausdorff | stretch avg | stretch min | size max | valence max |\n");
    std::printf("|---|---|---|---|---|---|---|---|\n");
    for (int a = 3; a < argc; a++) {
        size_t target = (size_t)std::atol(argv[a]);
        run_femlod(in, target, 0.0, 0);
        run_femlod(in, target, 1e-3, 0);
        run_femlod(in, target, 0.0, 1);
        run_femlod(in, target, 1e-3, 1);
        run_meshopt(in, target);
        run_openmesh(in, target);
    }
    femlod_mesh_free(in);
    return 0;
}
