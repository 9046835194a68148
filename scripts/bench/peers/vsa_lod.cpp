// vsa_lod: CGAL's Variational Shape Approximation, the segmentation peer of the segment
// method's benchmark (issue 12; Cohen-Steiner, Alliez, Desbrun, "Variational shape
// approximation", SIGGRAPH 2004; CGAL 5.5 Surface_mesh_approximation, Debian
// libcgal-dev).
//
//   vsa_lod IN.ply (--proxies K | --triangles N) [--iterations I] [-o OUT.ply]
//
// Reads IN.ply with the project's reader, welds equal positions, builds a
// CGAL::Surface_mesh and runs approximate_triangle_mesh (L21 metric, hierarchical
// seeding, I iterations, default CGAL's) with K proxies, then extracts the approximating
// mesh (anchors and triangles). With --triangles N, K is searched (bisection on K, the
// triangle count grows with K) for the largest output within N triangles; the time
// reported is the final run's alone (so the figure compares like with like at that
// count; the search's total is reported too).
//
// stdout: one JSON object {"peer","version","input","input_triangles","proxies",
// "triangles","vertices","manifold","seconds","search_seconds","runs","peak_rss_kb"}.
// Exit 64 usage, 65 unreadable input or a mesh CGAL refuses, 70 a CGAL exception,
// 74 write failure.

#include <sys/resource.h>

#include <array>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <map>
#include <tuple>
#include <vector>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/Surface_mesh_approximation/approximate_triangle_mesh.h>
#include <CGAL/version.h>

extern "C" {
#include "core/json.h"
#include "formats/ply.h"
}

namespace {

typedef CGAL::Exact_predicates_inexact_constructions_kernel Kernel;
typedef Kernel::Point_3 Point;
typedef CGAL::Surface_mesh<Point> Mesh;
namespace VSA = CGAL::Surface_mesh_approximation;

struct Options {
    const char *input = nullptr, *output = nullptr;
    long proxies = 0, triangles = 0, iterations = 0;
};

int usage(const char *why)
{
    if (why)
        std::fprintf(stderr, "vsa_lod: %s\n", why);
    std::fputs("usage: vsa_lod IN.ply (--proxies K | --triangles N) [--iterations I] [-o OUT.ply]\n",
               stderr);
    return 64;
}

double now()
{
    return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch())
        .count();
}

struct Result {
    std::vector<Point> anchors;
    std::vector<std::array<std::size_t, 3>> triangles;
    bool manifold = false;
    double seconds = 0;
};

Result approximate(const Mesh &mesh, long proxies, long iterations)
{
    Result r;
    double t = now();
    auto np = CGAL::parameters::max_number_of_proxies(static_cast<std::size_t>(proxies))
                  .anchors(std::back_inserter(r.anchors))
                  .triangles(std::back_inserter(r.triangles));
    if (iterations > 0)
        r.manifold = VSA::approximate_triangle_mesh(
            mesh, np.number_of_iterations(static_cast<std::size_t>(iterations)));
    else
        r.manifold = VSA::approximate_triangle_mesh(mesh, np);
    r.seconds = now() - t;
    return r;
}

/* The welded mesh: vertices at equal positions merged, degenerate faces dropped. */
bool build_mesh(const sl_mesh &in, Mesh &out)
{
    std::map<std::tuple<float, float, float>, Mesh::Vertex_index> seen;
    std::vector<Mesh::Vertex_index> map(in.vertex_count);
    for (uint64_t v = 0; v < in.vertex_count; v++) {
        const float *p = in.positions + 3 * v;
        auto key = std::make_tuple(p[0], p[1], p[2]);
        auto it = seen.find(key);
        if (it == seen.end())
            it = seen.emplace(key, out.add_vertex(Point(p[0], p[1], p[2]))).first;
        map[v] = it->second;
    }
    for (uint64_t t = 0; t < in.triangle_count; t++) {
        Mesh::Vertex_index a = map[in.triangles[3 * t]], b = map[in.triangles[3 * t + 1]],
                           c = map[in.triangles[3 * t + 2]];
        if (a == b || b == c || c == a)
            continue;
        out.add_face(a, b, c); /* a non-manifold face is skipped (null face) */
    }
    return out.number_of_faces() > 0;
}

int write_ply(const char *path, const Result &r)
{
    sl_mesh m;
    sl_mesh_init(&m);
    m.vertex_count = r.anchors.size();
    m.triangle_count = r.triangles.size();
    m.positions = static_cast<float *>(std::malloc(12 * (m.vertex_count ? m.vertex_count : 1)));
    m.triangles = static_cast<uint32_t *>(std::malloc(12 * (m.triangle_count ? m.triangle_count : 1)));
    if (!m.positions || !m.triangles) {
        sl_mesh_release(&m);
        return 74;
    }
    for (std::size_t i = 0; i < r.anchors.size(); i++)
        for (int k = 0; k < 3; k++)
            m.positions[3 * i + k] = static_cast<float>(r.anchors[i][k]);
    for (std::size_t i = 0; i < r.triangles.size(); i++)
        for (int k = 0; k < 3; k++)
            m.triangles[3 * i + k] = static_cast<uint32_t>(r.triangles[i][k]);
    sl_error err;
    sl_error_init(&err);
    int rc = sl_ply_write(path, &m, &err);
    sl_mesh_release(&m);
    if (rc) {
        char line[1600];
        std::fprintf(stderr, "vsa_lod: %s\n", sl_error_format(&err, line, sizeof line));
        return 74;
    }
    return 0;
}

int parse(int argc, char **argv, Options &o)
{
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        long *dst = !std::strcmp(a, "--proxies") ? &o.proxies
                    : !std::strcmp(a, "--triangles") ? &o.triangles
                    : !std::strcmp(a, "--iterations") ? &o.iterations : nullptr;
        if (dst) {
            char *end;
            if (i + 1 >= argc || (*dst = std::strtol(argv[++i], &end, 10)) < 1 || *end)
                return usage("a count needs a whole number >= 1");
        } else if (!std::strcmp(a, "-o")) {
            if (i + 1 >= argc)
                return usage("-o needs a file");
            o.output = argv[++i];
        } else if (a[0] == '-') {
            return usage("unknown option");
        } else if (!o.input) {
            o.input = a;
        } else {
            return usage("one input only");
        }
    }
    if (!o.input || (!o.proxies == !o.triangles))
        return usage("needs IN.ply and one of --proxies, --triangles");
    return 0;
}

} // namespace

int main(int argc, char **argv)
{
    Options o;
    if (int rc = parse(argc, argv, o))
        return rc;
    sl_mesh in;
    sl_mesh_init(&in);
    sl_error err;
    sl_error_init(&err);
    if (sl_ply_read(o.input, nullptr, &in, nullptr, nullptr, &err)) {
        char line[1600];
        std::fprintf(stderr, "vsa_lod: %s\n", sl_error_format(&err, line, sizeof line));
        return 65;
    }
    Mesh mesh;
    bool ok = build_mesh(in, mesh);
    uint64_t input_triangles = in.triangle_count;
    sl_mesh_release(&in);
    if (!ok) {
        std::fprintf(stderr, "vsa_lod: %s: no face CGAL accepts\n", o.input);
        return 65;
    }
    try {
        double t0 = now();
        Result best;
        long proxies = o.proxies, runs = 0;
        if (o.triangles) { /* bisection: the most proxies whose mesh fits the budget */
            long lo = 3, hi = std::max<long>(4, static_cast<long>(mesh.number_of_faces() / 2));
            long at = std::max<long>(4, o.triangles / 2); /* ~2 triangles per proxy */
            while (lo < hi && runs < 16) {
                Result r = approximate(mesh, at, o.iterations);
                runs++;
                if (static_cast<long>(r.triangles.size()) <= o.triangles) {
                    if (r.triangles.size() >= best.triangles.size()) {
                        best = r;
                        proxies = at;
                    }
                    lo = at + 1;
                } else {
                    hi = at - 1;
                }
                at = lo + (hi - lo + 1) / 2;
                if (static_cast<long>(best.triangles.size()) >= o.triangles * 97 / 100)
                    break;
            }
        } else {
            best = approximate(mesh, proxies, o.iterations);
            runs = 1;
        }
        double search = now() - t0;
        if (o.output)
            if (int rc = write_ply(o.output, best))
                return rc;
        struct rusage ru;
        getrusage(RUSAGE_SELF, &ru);
        sl_json j;
        sl_json_init(&j, 0);
        sl_json_object_begin(&j, nullptr);
        sl_json_string(&j, "peer", "cgal-vsa");
        sl_json_string(&j, "version", CGAL_VERSION_STR);
        sl_json_string(&j, "input", o.input);
        sl_json_u64(&j, "input_triangles", input_triangles);
        sl_json_u64(&j, "proxies", static_cast<uint64_t>(proxies));
        sl_json_u64(&j, "triangles", best.triangles.size());
        sl_json_u64(&j, "vertices", best.anchors.size());
        sl_json_bool(&j, "manifold", best.manifold);
        sl_json_double(&j, "seconds", best.seconds);
        sl_json_double(&j, "search_seconds", search);
        sl_json_u64(&j, "runs", static_cast<uint64_t>(runs));
        sl_json_u64(&j, "peak_rss_kb", static_cast<uint64_t>(ru.ru_maxrss));
        sl_json_object_end(&j);
        std::printf("%.*s\n", static_cast<int>(j.len), j.buf);
        sl_json_release(&j);
    } catch (const std::exception &e) {
        std::fprintf(stderr, "vsa_lod: CGAL: %s\n", e.what());
        return 70;
    }
    return 0;
}
