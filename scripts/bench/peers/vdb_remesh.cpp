// vdb_remesh: the OpenVDB peer of the benchmark (issue 3; docs/benchmarks.md).
//
//   vdb_remesh IN.ply -o OUT.ply (--voxel SIZE | --voxel-fraction F) [--adaptivity A]
//              [--unsigned] [--half-width W] [--threads N]
//
// Reads IN.ply with the project's C reader, converts it with tools::meshToVolume at
// voxel size SIZE (world units; or F times the bounding-box diagonal) into a narrow-band
// distance field of W voxels each side (default 3), and meshes it back with
// tools::volumeToMesh at the given adaptivity (0 = uniform, up to 1). Quads are split
// into two triangles along their 0-2 diagonal.
//
// Signed (default): a level set meshed at isovalue 0. It assumes a closed input; on an
// open scan the sign is guessed from the outside flood fill and the remesh can grow
// surfaces across holes (the failure the samples stage must not have).
// --unsigned: an unsigned distance field (UNSIGNED_DISTANCE_FIELD) meshed at isovalue
// = one voxel: a closed thin shell around the surface, one voxel off on both sides.
// It never closes holes, and its distance to the input is about one voxel by
// construction -- the fair peer for open scans.
//
// TBB is capped at --threads (default: all cores) with tbb::global_control.
// stdout: one JSON object {"peer","version","input","input_triangles","voxel_size",
// "adaptivity","unsigned","threads","active_voxels","to_volume_seconds",
// "to_mesh_seconds","triangles","vertices","peak_rss_kb"}.
// Exit 64 usage, 65 unreadable input, 70 on an OpenVDB exception, 74 write failure.

#include <sys/resource.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <string>
#include <vector>

#include <openvdb/openvdb.h>
#include <openvdb/tools/MeshToVolume.h>
#include <openvdb/tools/VolumeToMesh.h>
#include <tbb/global_control.h>
#include <tbb/info.h>

extern "C" {
#include "core/json.h"
#include "formats/ply.h"
}

namespace {

struct Options {
    const char *input = nullptr, *output = nullptr;
    double voxel = 0.0, voxel_fraction = 0.0, adaptivity = 0.0, half_width = 3.0;
    bool unsigned_field = false;
    int threads = 0;
};

int usage(const char *why)
{
    if (why)
        std::fprintf(stderr, "vdb_remesh: %s\n", why);
    std::fputs("usage: vdb_remesh IN.ply -o OUT.ply (--voxel SIZE | --voxel-fraction F)\n"
               "                  [--adaptivity A] [--unsigned] [--half-width W] "
               "[--threads N]\n",
               stderr);
    return 64;
}

int parse(int argc, char **argv, Options &o)
{
    for (int i = 1; i < argc; i++) {
        std::string a = argv[i];
        bool value = i + 1 < argc;
        if (a == "-o" && value)
            o.output = argv[++i];
        else if (a == "--voxel" && value)
            o.voxel = std::atof(argv[++i]);
        else if (a == "--voxel-fraction" && value)
            o.voxel_fraction = std::atof(argv[++i]);
        else if (a == "--adaptivity" && value)
            o.adaptivity = std::atof(argv[++i]);
        else if (a == "--half-width" && value)
            o.half_width = std::atof(argv[++i]);
        else if (a == "--threads" && value)
            o.threads = std::atoi(argv[++i]);
        else if (a == "--unsigned")
            o.unsigned_field = true;
        else if (a[0] != '-' && !o.input)
            o.input = argv[i];
        else
            return usage(nullptr);
    }
    if (!o.input || !o.output)
        return usage("needs IN.ply and -o OUT.ply");
    if ((o.voxel > 0.0) == (o.voxel_fraction > 0.0))
        return usage("give one positive --voxel or --voxel-fraction");
    if (!(o.adaptivity >= 0.0 && o.adaptivity <= 1.0) || !(o.half_width >= 1.0) ||
        o.threads < 0)
        return usage("adaptivity in [0, 1], half-width >= 1, threads >= 0");
    return 0;
}

double seconds_since(std::chrono::steady_clock::time_point t0)
{
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

double diagonal(const sl_mesh &m)
{
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (uint64_t v = 0; v < m.vertex_count; v++)
        for (int a = 0; a < 3; a++) {
            double x = m.positions[3 * v + a];
            if (std::isfinite(x)) {
                lo[a] = std::fmin(lo[a], x);
                hi[a] = std::fmax(hi[a], x);
            }
        }
    double d2 = 0.0;
    for (int a = 0; a < 3; a++)
        d2 += hi[a] > lo[a] ? (hi[a] - lo[a]) * (hi[a] - lo[a]) : 0.0;
    return std::sqrt(d2);
}

struct Result {
    size_t active_voxels = 0;
    double to_volume = 0.0, to_mesh = 0.0;
    std::vector<openvdb::Vec3s> points;
    std::vector<openvdb::Vec3I> triangles;
};

// The remesh itself; throws what OpenVDB throws.
void remesh(const sl_mesh &m, const Options &o, double voxel, Result &r)
{
    using namespace openvdb;
    math::Transform::Ptr xform = math::Transform::createLinearTransform(voxel);
    std::vector<Vec3s> points(m.vertex_count);
    std::vector<Vec3I> tris(m.triangle_count);

    auto t0 = std::chrono::steady_clock::now();
    // meshToVolume wants index-space points.
    for (uint64_t v = 0; v < m.vertex_count; v++)
        points[v] = Vec3s(xform->worldToIndex(
            Vec3d(m.positions[3 * v], m.positions[3 * v + 1], m.positions[3 * v + 2])));
    for (uint64_t t = 0; t < m.triangle_count; t++)
        tris[t] = Vec3I(m.triangles[3 * t], m.triangles[3 * t + 1], m.triangles[3 * t + 2]);
    tools::QuadAndTriangleDataAdapter<Vec3s, Vec3I> adapter(points, tris);
    float band = static_cast<float>(o.half_width);
    int flags = o.unsigned_field ? tools::UNSIGNED_DISTANCE_FIELD : 0;
    FloatGrid::Ptr grid = tools::meshToVolume<FloatGrid>(adapter, *xform, band, band, flags);
    r.to_volume = seconds_since(t0);
    r.active_voxels = grid->activeVoxelCount();

    t0 = std::chrono::steady_clock::now();
    std::vector<Vec4I> quads;
    double iso = o.unsigned_field ? voxel : 0.0;
    tools::volumeToMesh(*grid, r.points, r.triangles, quads, iso, o.adaptivity);
    r.triangles.reserve(r.triangles.size() + 2 * quads.size());
    for (const Vec4I &q : quads) {
        r.triangles.emplace_back(q[0], q[1], q[2]);
        r.triangles.emplace_back(q[0], q[2], q[3]);
    }
    r.to_mesh = seconds_since(t0);
}

int write_result(const char *path, Result &r, sl_error *err)
{
    // Borrowed storage: Vec3s and Vec3I are three packed floats / uint32s.
    static_assert(sizeof(openvdb::Vec3s) == 3 * sizeof(float), "packed Vec3s");
    static_assert(sizeof(openvdb::Vec3I) == 3 * sizeof(uint32_t), "packed Vec3I");
    sl_mesh out = sl_mesh_view(r.points.size(), r.points.empty() ? nullptr : &r.points[0][0],
                               nullptr, nullptr, r.triangles.size(),
                               r.triangles.empty() ? nullptr : &r.triangles[0][0]);
    return sl_ply_write(path, &out, err);
}

void print_json(const Options &o, const sl_mesh &m, double voxel, int threads,
                const Result &r)
{
    struct rusage ru;
    getrusage(RUSAGE_SELF, &ru);
    sl_json j;
    sl_json_init(&j, 0);
    sl_json_object_begin(&j, nullptr);
    sl_json_string(&j, "peer", "openvdb");
    sl_json_string(&j, "version", OPENVDB_LIBRARY_VERSION_STRING);
    sl_json_string(&j, "input", o.input);
    sl_json_u64(&j, "input_triangles", m.triangle_count);
    sl_json_double(&j, "voxel_size", voxel);
    sl_json_double(&j, "adaptivity", o.adaptivity);
    sl_json_bool(&j, "unsigned", o.unsigned_field);
    sl_json_u64(&j, "threads", static_cast<uint64_t>(threads));
    sl_json_u64(&j, "active_voxels", r.active_voxels);
    sl_json_double(&j, "to_volume_seconds", r.to_volume);
    sl_json_double(&j, "to_mesh_seconds", r.to_mesh);
    sl_json_u64(&j, "triangles", r.triangles.size());
    sl_json_u64(&j, "vertices", r.points.size());
    sl_json_u64(&j, "peak_rss_kb", static_cast<uint64_t>(ru.ru_maxrss));
    sl_json_object_end(&j);
    std::printf("%s\n", sl_json_text(&j));
    sl_json_release(&j);
}

} // namespace

int main(int argc, char **argv)
{
    Options o;
    if (int rc = parse(argc, argv, o))
        return rc;
    int threads = o.threads ? o.threads : tbb::info::default_concurrency();
    tbb::global_control cap(tbb::global_control::max_allowed_parallelism, threads);

    sl_mesh mesh;
    sl_error err;
    sl_error_init(&err);
    char line[1600];
    if (sl_ply_read(o.input, nullptr, &mesh, nullptr, nullptr, &err) != SL_OK) {
        std::fprintf(stderr, "vdb_remesh: %s\n", sl_error_format(&err, line, sizeof line));
        return 65;
    }
    double voxel = o.voxel > 0.0 ? o.voxel : o.voxel_fraction * diagonal(mesh);
    if (!(voxel > 0.0) || mesh.triangle_count == 0) {
        std::fprintf(stderr, "vdb_remesh: %s: no triangles or a zero-size bounding box\n",
                     o.input);
        sl_mesh_release(&mesh);
        return 65;
    }

    Result r;
    try {
        openvdb::initialize();
        remesh(mesh, o, voxel, r);
    } catch (const std::exception &e) {
        std::fprintf(stderr, "vdb_remesh: %s: OpenVDB: %s\n", o.input, e.what());
        sl_mesh_release(&mesh);
        return 70;
    }
    int code = 0;
    if (write_result(o.output, r, &err) != SL_OK) {
        std::fprintf(stderr, "vdb_remesh: %s\n", sl_error_format(&err, line, sizeof line));
        code = 74;
    } else {
        print_json(o, mesh, voxel, threads, r);
    }
    sl_mesh_release(&mesh);
    return code;
}
