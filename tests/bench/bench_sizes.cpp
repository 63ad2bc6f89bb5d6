// bench_sizes.cpp - what users run, over four sizes (issue 39): the default
// `femlod simplify IN OUT --target T` (read, simplify with default options,
// build the hierarchy, write OBJ) beside meshoptimizer's meshopt_simplify and
// OpenMesh's decimater (ModQuadric, ModAspectRatio(5), ModNormalFlipping, as
// bench_peers.cpp) put between femlod's own reader and OBJ writer, so that
// the whole jobs differ only in the simplifier.
//
//   bench_sizes [--runs N] [--openmesh-max TRIANGLES] [--tmp DIR] [--keep] [DATA_DIR]
//
// Each run is a child process: the whole job is its wall time from fork to
// exit, the peak memory its ru_maxrss (wait4); simplify alone is the stage
// time the CLI prints with -v, or the time the peer's child measures around
// its simplify call. Medians of N rounds (default 3; each round runs every
// tool once, interleaved) are printed as a markdown table with the ratios
// femlod / meshoptimizer (OpenMesh's ratio is to meshoptimizer too). OpenMesh runs only on inputs
// up to --openmesh-max triangles (default 400000: it takes minutes on 1.25M).
//
// The inputs are written under DIR (default /tmp) and removed at the end: a
// noisy sphere of 50,700 triangles (a scan-like surface, made here), cover.obj
// (77,874), cover.obj subdivided once (311,496) and twice (1,245,984);
// --keep leaves them there (for perf and other tools); --runs 0 only
// writes them.
//
// The children: bench_sizes --job meshopt|openmesh IN OUT TARGET prints
// "simplify SECONDS TRIANGLES". C++ because OpenMesh is.
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

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <map>
#include <string>
#include <tuple>
#include <vector>

#include <fcntl.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

typedef OpenMesh::TriMesh_ArrayKernelT<> OMesh;

static void die(const char *what, const femlod_error &err) {
    std::fprintf(stderr, "bench_sizes: %s: %s\n", what, err.message);
    std::exit(1);
}

// {====== the children: femlod's reader, a peer's simplify, femlod's writer

// Writes the triangles tri over pos to path, keeping only the used vertices
// (in first-use order), through femlod's OBJ writer.
static void write_compact(const char *path, const std::vector<double> &pos, const std::vector<uint32_t> &tri) {
    std::vector<uint32_t> map(pos.size() / 3, UINT32_MAX), t(tri.size());
    std::vector<double> p;
    for (size_t k = 0; k < tri.size(); k++) {
        uint32_t v = tri[k];
        if (map[v] == UINT32_MAX) {
            map[v] = (uint32_t)(p.size() / 3);
            p.insert(p.end(), &pos[3 * v], &pos[3 * v] + 3);
        }
        t[k] = map[v];
    }
    femlod_mesh *m = NULL;
    femlod_error err;
    if (femlod_mesh_create(&m, p.data(), p.size() / 3, t.data(), t.size() / 3, &err) != FEMLOD_OK) die(path, err);
    if (femlod_mesh_write(m, path, NULL, &err) != FEMLOD_OK) die(path, err);
    femlod_mesh_free(m);
}

static int job(const char *tool, const char *in_path, const char *out_path, size_t target) {
    femlod_mesh *in = NULL;
    femlod_error err;
    if (femlod_mesh_read(&in, in_path, NULL, &err) != FEMLOD_OK) die(in_path, err);
    size_t nv = femlod_mesh_vertex_count(in), nt = femlod_mesh_triangle_count(in);
    const double *p = femlod_mesh_positions(in);
    const uint32_t *t = femlod_mesh_triangles(in);
    std::vector<double> pos;
    std::vector<uint32_t> tri;
    double sec;
    if (std::strcmp(tool, "meshopt") == 0) {
        double t0 = bench_now();
        std::vector<float> fpos(3 * nv);
        for (size_t k = 0; k < 3 * nv; k++) fpos[k] = (float)p[k];
        std::vector<unsigned> dst(3 * nt);
        float e = 0;
        size_t n = meshopt_simplify(dst.data(), t, 3 * nt, fpos.data(), nv, 3 * sizeof(float), 3 * target, 1e30f, 0, &e);
        sec = bench_now() - t0;
        pos.assign(p, p + 3 * nv);
        tri.assign(dst.begin(), dst.begin() + (long)n);
    } else if (std::strcmp(tool, "openmesh") == 0) {
        double t0 = bench_now();
        OMesh m;
        std::vector<OMesh::VertexHandle> vh(nv);
        for (size_t v = 0; v < nv; v++)
            vh[v] = m.add_vertex(OMesh::Point((float)p[3 * v], (float)p[3 * v + 1], (float)p[3 * v + 2]));
        for (size_t f = 0; f < nt; f++) m.add_face(vh[t[3 * f]], vh[t[3 * f + 1]], vh[t[3 * f + 2]]);
        m.request_face_normals(); // ModNormalFlipping compares them
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
        sec = bench_now() - t0;
        for (auto v : m.vertices()) {
            OMesh::Point q = m.point(v);
            pos.insert(pos.end(), {q[0], q[1], q[2]});
        }
        for (auto f : m.faces())
            for (auto v : m.fv_range(f)) tri.push_back((uint32_t)v.idx());
    } else {
        std::fprintf(stderr, "bench_sizes: unknown tool %s\n", tool);
        return 2;
    }
    femlod_mesh_free(in);
    write_compact(out_path, pos, tri);
    std::printf("simplify %.6f %zu\n", sec, tri.size() / 3);
    return 0;
}

// }======

// {====== the parent: inputs, child runs, the table

// A closed sphere of 12 n^2 triangles (a cube's faces projected), with
// low-frequency bumps and noise of 0.2% of the radius, as a scanned surface
// has; the noise depends on the vertex only, so the result is fixed.
static femlod_mesh *noisy_sphere(int n) {
    std::map<std::tuple<int, int, int>, uint32_t> id;
    std::vector<double> pos;
    std::vector<uint32_t> tri;
    auto vertex = [&](int x, int y, int z) {
        auto key = std::make_tuple(x, y, z);
        auto it = id.find(key);
        if (it != id.end()) return it->second;
        uint32_t h = (uint32_t)(x * 73856093) ^ (uint32_t)(y * 19349663) ^ (uint32_t)(z * 83492791);
        h ^= h >> 13;
        h *= 0x5bd1e995u;
        h ^= h >> 15;
        double noise = (double)(h & 0xFFFF) / 32767.5 - 1.0;
        double c[3] = {(double)x / n, (double)y / n, (double)z / n};
        double len = std::sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
        for (double &v : c) v /= len;
        double r = 1.0 + 0.05 * std::sin(3 * c[0]) * std::sin(4 * c[1]) * std::sin(5 * c[2]) + 0.002 * noise;
        uint32_t k = (uint32_t)(pos.size() / 3);
        pos.insert(pos.end(), {r * c[0], r * c[1], r * c[2]});
        id.emplace(key, k);
        return k;
    };
    // Face (axis, sign): points with that coordinate at sign * n, the other
    // two on the grid -n, -n + 2, ..., n; both windings outward.
    for (int axis = 0; axis < 3; axis++)
        for (int sign = -1; sign <= 1; sign += 2)
            for (int i = 0; i < n; i++)
                for (int j = 0; j < n; j++) {
                    uint32_t q[4];
                    int corner[4][2] = {{i, j}, {i + 1, j}, {i + 1, j + 1}, {i, j + 1}};
                    for (int c = 0; c < 4; c++) {
                        int v[3];
                        v[axis] = sign * n;
                        v[(axis + 1) % 3] = -n + 2 * corner[c][0];
                        v[(axis + 2) % 3] = -n + 2 * corner[c][1];
                        q[c] = vertex(v[0], v[1], v[2]);
                    }
                    if (sign > 0)
                        tri.insert(tri.end(), {q[0], q[1], q[2], q[0], q[2], q[3]});
                    else
                        tri.insert(tri.end(), {q[0], q[2], q[1], q[0], q[3], q[2]});
                }
    femlod_mesh *m = NULL;
    femlod_error err;
    if (femlod_mesh_create(&m, pos.data(), pos.size() / 3, tri.data(), tri.size() / 3, &err) != FEMLOD_OK)
        die("noisy sphere", err);
    return m;
}

struct run_result {
    double job = 0, simplify = 0, peak_mb = 0;
    size_t triangles = 0;
};

// Runs argv as a child with stdout and stderr captured into one string;
// fills the wall time and peak memory. Exits on a failed child.
static std::string run_child(const std::vector<std::string> &args, run_result &r) {
    char tmpl[] = "/tmp/bench_sizes_outXXXXXX";
    int fd = mkstemp(tmpl);
    if (fd < 0) {
        std::perror("bench_sizes: mkstemp");
        std::exit(1);
    }
    unlink(tmpl);
    std::vector<char *> argv;
    for (const std::string &a : args) argv.push_back(const_cast<char *>(a.c_str()));
    argv.push_back(NULL);
    double t0 = bench_now();
    pid_t pid = fork();
    if (pid == 0) {
        dup2(fd, 1);
        dup2(fd, 2);
        execv(argv[0], argv.data());
        _exit(127);
    }
    int status = 0;
    struct rusage ru;
    if (pid < 0 || wait4(pid, &status, 0, &ru) != pid) {
        std::perror("bench_sizes: fork");
        std::exit(1);
    }
    r.job = bench_now() - t0;
    r.peak_mb = (double)ru.ru_maxrss / 1024.0;
    std::string out;
    char buf[4096];
    ssize_t n;
    lseek(fd, 0, SEEK_SET);
    while ((n = read(fd, buf, sizeof buf)) > 0) out.append(buf, (size_t)n);
    close(fd);
    if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
        std::fprintf(stderr, "bench_sizes: %s failed:\n%s\n", args[0].c_str(), out.c_str());
        std::exit(1);
    }
    return out;
}

// femlod -v prints "femlod: simplify: A -> B triangles, ... (S s)".
static void parse_femlod(const std::string &out, run_result &r) {
    size_t at = out.find("femlod: simplify: ");
    while (at != std::string::npos && out.compare(at, 30, "femlod: simplify: done in", 0, 25) == 0)
        at = out.find("femlod: simplify: ", at + 1);
    size_t arrow = at == std::string::npos ? at : out.find(" -> ", at);
    size_t open = arrow == std::string::npos ? arrow : out.find(" (", arrow);
    if (open == std::string::npos) {
        std::fprintf(stderr, "bench_sizes: no simplify stage in femlod's output:\n%s\n", out.c_str());
        std::exit(1);
    }
    r.triangles = std::strtoul(out.c_str() + arrow + 4, NULL, 10);
    r.simplify = std::strtod(out.c_str() + open + 2, NULL);
}

static void parse_peer(const std::string &out, run_result &r) {
    size_t at = out.find("simplify ");
    if (at == std::string::npos) {
        std::fprintf(stderr, "bench_sizes: no simplify time in the peer's output:\n%s\n", out.c_str());
        std::exit(1);
    }
    char *end;
    r.simplify = std::strtod(out.c_str() + at + 9, &end);
    r.triangles = std::strtoul(end, NULL, 10);
}

static double median(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v[v.size() / 2];
}

struct medians {
    double job, simplify, peak_mb;
    size_t triangles;
};

// One run of args; adds its figures to the lists of m.
struct series {
    std::vector<double> job, simp, peak;
    size_t triangles = 0;
};

static void measure_once(const std::vector<std::string> &args, bool is_femlod, series &s) {
    run_result r;
    std::string out = run_child(args, r);
    if (is_femlod)
        parse_femlod(out, r);
    else
        parse_peer(out, r);
    s.job.push_back(r.job);
    s.simp.push_back(r.simplify);
    s.peak.push_back(r.peak_mb);
    s.triangles = r.triangles;
}

static medians summary(const series &s) { return {median(s.job), median(s.simp), median(s.peak), s.triangles}; }

static std::string self_path() {
    char buf[4096];
    ssize_t n = readlink("/proc/self/exe", buf, sizeof buf - 1);
    if (n <= 0) {
        std::perror("bench_sizes: /proc/self/exe");
        std::exit(1);
    }
    buf[n] = '\0';
    return buf;
}

int main(int argc, char **argv) {
    if (argc == 6 && std::strcmp(argv[1], "--job") == 0)
        return job(argv[2], argv[3], argv[4], (size_t)std::atol(argv[5]));
    int runs = 3, keep = 0;
    size_t om_max = 400000;
    std::string tmp = "/tmp", data = FEMLOD_SHARED_DATA;
    for (int a = 1; a < argc; a++) {
        if (std::strcmp(argv[a], "--runs") == 0 && a + 1 < argc)
            runs = std::max(0, std::atoi(argv[++a]));
        else if (std::strcmp(argv[a], "--openmesh-max") == 0 && a + 1 < argc)
            om_max = (size_t)std::atol(argv[++a]);
        else if (std::strcmp(argv[a], "--tmp") == 0 && a + 1 < argc)
            tmp = argv[++a];
        else if (std::strcmp(argv[a], "--keep") == 0)
            keep = 1;
        else if (argv[a][0] != '-')
            data = argv[a];
        else {
            std::fprintf(stderr, "usage: bench_sizes [--runs N] [--openmesh-max TRIANGLES] [--tmp DIR] [--keep] [DATA_DIR]\n");
            return 2;
        }
    }
    const std::string self = self_path(), cli = FEMLOD_CLI;
    std::string dir = tmp + "/bench_sizes." + std::to_string((long)getpid());
    if (mkdir(dir.c_str(), 0700) != 0) {
        std::perror(dir.c_str());
        return 1;
    }

    femlod_error err;
    femlod_mesh *cover = NULL;
    std::string cover_path = data + "/cover.obj";
    if (femlod_mesh_read(&cover, cover_path.c_str(), NULL, &err) != FEMLOD_OK) die(cover_path.c_str(), err);
    struct input {
        std::string name, path;
        size_t triangles, target;
    };
    std::vector<input> inputs;
    auto add = [&](const char *name, femlod_mesh *m, size_t target) {
        std::string path = dir + "/" + name + ".obj";
        if (femlod_mesh_write(m, path.c_str(), NULL, &err) != FEMLOD_OK) die(path.c_str(), err);
        inputs.push_back({name, path, femlod_mesh_triangle_count(m), target});
    };
    femlod_mesh *sphere = noisy_sphere(65), *c1 = NULL, *c2 = NULL;
    if (femlod_mesh_subdivide(&c1, cover, 1, &err) != FEMLOD_OK || femlod_mesh_subdivide(&c2, cover, 2, &err) != FEMLOD_OK)
        die("subdivide", err);
    add("noisy-sphere", sphere, 10000);
    add("cover", cover, 12000);
    add("cover1", c1, 50000);
    add("cover2", c2, 50000);
    femlod_mesh_free(sphere);
    femlod_mesh_free(cover);
    femlod_mesh_free(c1);
    femlod_mesh_free(c2);

    if (runs == 0) {
        std::printf("inputs written in %s\n", dir.c_str());
        return 0;
    }
    std::printf("bench_sizes: medians of %d runs; whole job = read OBJ, simplify, write OBJ (femlod: the CLI "
                "with default options)\n\n",
                runs);
    std::printf("| input -> target | femlod job | meshopt job | ratio | femlod simplify | meshopt simplify | ratio "
                "| OpenMesh+aspect simplify | femlod peak | meshopt peak | ratio |\n");
    std::printf("|---|---|---|---|---|---|---|---|---|---|---|\n");
    std::fflush(stdout);
    for (const input &in : inputs) {
        std::string out = dir + "/out.obj", tgt = std::to_string(in.target);
        // Rounds interleave the tools (femlod, meshoptimizer, OpenMesh), so a
        // slow minute of the shared machine falls on all of them.
        series fs, ms, os;
        bool om = in.triangles <= om_max;
        for (int r = 0; r < runs; r++) {
            measure_once({cli, "-v", "simplify", in.path, out, "--target", tgt}, true, fs);
            measure_once({self, "--job", "meshopt", in.path, out, tgt}, false, ms);
            if (om) measure_once({self, "--job", "openmesh", in.path, out, tgt}, false, os);
        }
        medians f = summary(fs), m = summary(ms);
        char om_cell[64] = "not run";
        if (om) {
            medians o = summary(os);
            std::snprintf(om_cell, sizeof om_cell, "%.3f s (%.1fx)", o.simplify, o.simplify / m.simplify);
        }
        std::printf("| %s %zu -> %zu | %.3f s | %.3f s | %.1fx | %.3f s | %.3f s | %.1fx | %s | %.0f MB | %.0f MB | %.2fx |\n",
                    in.name.c_str(), in.triangles, in.target, f.job, m.job, f.job / m.job, f.simplify, m.simplify,
                    f.simplify / m.simplify, om_cell, f.peak_mb, m.peak_mb, f.peak_mb / m.peak_mb);
        std::fflush(stdout);
        if (f.triangles != in.target || m.triangles > in.target)
            std::fprintf(stderr, "bench_sizes: %s: femlod stopped at %zu, meshoptimizer at %zu triangles\n",
                         in.name.c_str(), f.triangles, m.triangles);
        std::remove(out.c_str());
        if (!keep) std::remove(in.path.c_str());
    }
    if (keep)
        std::printf("\ninputs kept in %s\n", dir.c_str());
    else
        rmdir(dir.c_str());
    return 0;
}

// }======
