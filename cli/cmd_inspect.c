/* `scanlod inspect FILE`: what a file holds, after reading all of it and validating it.
 *
 * Results go to stdout as `key: value` lines (stable, greppable); a failure is one line
 * `scanlod: FILE: cause` on stderr. Each file kind has one inspector in the table below,
 * chosen by suffix, with the scan readers as the default (formats/scan_read.h: a scan's
 * format is recognised by its magic and name).
 */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "cli/commands.h"
#include "core/error.h"
#include "formats/scan_read.h"
#include "formats/scan_texture.h"
#include "runtime/lod_io.h"

static void usage(FILE *f)
{
    fputs("usage: scanlod inspect SCAN|MODEL.slod\n"
          "Reads the whole file, validates it and prints what it holds. A scan (PLY, OBJ + MTL,\n"
          "STL, OFF, XYZ/PTS, glTF/GLB): format (a PLY's elements and properties), counts,\n"
          "normals/colours/texture coordinates/range grid, texture, units and up axis the file\n"
          "states, viewpoint, bounding box, non-finite vertices, faces triangulated, warnings\n"
          "(a missing MTL or image). A LOD model\n"
          "(.slod, checked as `extract` checks it): its grid, octree levels, crossings, LOD\n"
          "array, triangles and error from the coarsest to the finest cut.\n"
          "Exit status: 0 valid; 65 the file is malformed or unreadable; 75 out of memory\n"
          "or interrupted (try again); 64 usage.\n", f);
}

static const char *format_name(sl_ply_format format)
{
    return format == SL_PLY_ASCII ? "ascii"
           : format == SL_PLY_BINARY_LE ? "binary_little_endian" : "binary_big_endian";
}

static const char *yes_no(int v)
{
    return v ? "yes" : "no";
}

/* Bounding box over the finite vertices; returns how many vertices are not finite. */
static uint64_t bounds(const sl_mesh *m, double lo[3], double hi[3])
{
    uint64_t nonfinite = 0;
    for (int k = 0; k < 3; k++)
        lo[k] = INFINITY, hi[k] = -INFINITY;
    for (uint64_t i = 0; i < m->vertex_count; i++) {
        const float *p = m->positions + 3 * i;
        if (!isfinite(p[0]) || !isfinite(p[1]) || !isfinite(p[2])) {
            nonfinite++;
            continue;
        }
        for (int k = 0; k < 3; k++) {
            lo[k] = p[k] < lo[k] ? p[k] : lo[k];
            hi[k] = p[k] > hi[k] ? p[k] : hi[k];
        }
    }
    return nonfinite;
}

static uint64_t grid_points(const sl_mesh *m)
{
    uint64_t n = 0, cells = (uint64_t)m->grid_cols * m->grid_rows;
    for (uint64_t i = 0; m->grid_index && i < cells; i++)
        n += m->grid_index[i] >= 0;
    return n;
}

static void print_format(const sl_mesh *m, const sl_scan_info *info)
{
    if (!strcmp(m->format, "ply")) {
        printf("format: %s 1.0 (header %llu bytes)\n", format_name(info->ply.format),
               (unsigned long long)info->ply.header_bytes);
        printf("elements: %s\n", info->ply.elements);
    } else {
        printf("format: %s (%s)\n", m->format, info->detail);
    }
}

static void print_scan(const char *path, const sl_mesh *m, const sl_scan_info *info)
{
    double lo[3], hi[3];
    char texture[320];
    uint64_t nonfinite = bounds(m, lo, hi);
    printf("file: %s\n", path);
    print_format(m, info);
    printf("vertices: %llu\n", (unsigned long long)m->vertex_count);
    printf("faces: %llu declared, %llu triangles (%llu polygons fan-triangulated, %llu faces "
           "with fewer than 3 corners dropped)\n",
           (unsigned long long)info->declared_faces, (unsigned long long)m->triangle_count,
           (unsigned long long)m->stats.polygons_triangulated,
           (unsigned long long)m->stats.faces_too_short);
    printf("normals: %s\ncolours: %s\n", yes_no(m->normals != NULL), yes_no(m->colors != NULL));
    printf("texcoords: per-vertex %s, per-face %s (%llu faces)\n", yes_no(m->texcoords != NULL),
           yes_no(m->face_texcoords != NULL), (unsigned long long)m->stats.texcoord_faces);
    if (m->grid_index)
        printf("range grid: %u x %u (%llu cells hold a point)\n", m->grid_cols, m->grid_rows,
               (unsigned long long)grid_points(m));
    else
        printf("range grid: no\n");
    printf("texture file: %s\n", sl_scan_texture_name(m, texture, sizeof texture));
    printf("units: %s\nup: %s\n", m->units[0] ? m->units : "not stated",
           m->up_axis ? (m->up_axis == 'z' ? "+z" : "+y") : "not stated");
    if (m->has_viewpoint)
        printf("viewpoint: %.9g %.9g %.9g\n", m->viewpoint[0], m->viewpoint[1], m->viewpoint[2]);
    else
        printf("viewpoint: none\n");
    if (nonfinite < m->vertex_count)
        printf("bbox: min %.9g %.9g %.9g max %.9g %.9g %.9g\n", lo[0], lo[1], lo[2], hi[0], hi[1],
               hi[2]);
    else
        printf("bbox: none\n");
    printf("non-finite vertices: %llu\n", (unsigned long long)nonfinite);
    int w = m->warning_count > 0;
    printf("warnings: %u%s%s%s\n", m->warning_count, w ? " (" : "", w ? m->warnings : "",
           w ? ")" : "");
}

static int inspect_scan(const char *path, sl_error *err)
{
    sl_mesh m;
    sl_scan_info info;
    int rc = sl_scan_read(path, NULL, &m, &info, NULL, err);
    if (rc == 0)
        print_scan(path, &m, &info);
    sl_mesh_release(&m);
    return rc;
}

static int inspect_slod(const char *path, sl_error *err)
{
    sl_lod_model m;
    sl_lod_model_init(&m);
    int rc = sl_lod_model_read(path, &m, err); /* every structure check of the readers */
    if (rc == 0) {
        const sl_octree *t = &m.tree;
        uint32_t e = m.expansion_count;
        printf("file: %s\n", path);
        printf("kind: scanlod LOD model (octree, LOD array, accumulation table, crack "
               "transitions)\n");
        printf("grid: leaf %.9g, origin %.9g %.9g %.9g, depth %u\n", t->leaf_size,
               t->origin[0], t->origin[1], t->origin[2], t->depth);
        printf("nodes: %u (", t->node_count);
        for (uint32_t l = 0; l <= t->depth && l < SL_OCTREE_MAX_LEVELS; l++)
            printf("%slevel %u: %u", l ? ", " : "", l, t->level_count[l]);
        printf(")\n");
        printf("crossings: %u, colours: %s\n", t->crossing_count,
               yes_no(t->crossing_color != NULL));
        if (sl_octree_dual(t))
            printf("vertices: qef, %u quadric vertices (%u with transition loops), format %u\n",
                   t->vertex_count, m.dual_count, SL_LOD_FORMAT_VERSION);
        else
            printf("vertices: mc (paper 1's marching-cube triangles), format %u\n",
                   SL_LOD_FORMAT_VERSION);
        printf("lod array: %u expansions\n", e);
        printf("triangles: %llu at the root, %llu at the finest cut\n",
               (unsigned long long)m.accumulation[0], (unsigned long long)m.accumulation[e]);
        if (m.error_after)
            printf("error: %.9g at the root, %.9g at the finest cut (world units)\n",
                   m.error_after[0], m.error_after[e]);
        printf("transition records: %llu\n", (unsigned long long)m.transitions.count);
        printf("neighbour links: %llu\n", (unsigned long long)m.neighbours.count);
    }
    sl_lod_model_release(&m);
    return rc;
}

static const struct inspector {
    const char *suffix; /* NULL: the default */
    int (*inspect)(const char *path, sl_error *err);
} inspectors[] = {
    {NULL, inspect_scan},
    {".slod", inspect_slod},
};

static const struct inspector *inspector_for(const char *path)
{
    size_t n = strlen(path);
    for (size_t i = 0; i < sizeof inspectors / sizeof inspectors[0]; i++) {
        const char *s = inspectors[i].suffix;
        if (s && n >= strlen(s) && strcmp(path + n - strlen(s), s) == 0)
            return &inspectors[i];
    }
    return &inspectors[0];
}

int sl_cmd_inspect(int argc, char **argv)
{
    if (argc >= 2 && (strcmp(argv[1], "--help") == 0 || strcmp(argv[1], "-h") == 0)) {
        usage(stdout);
        return SL_EXIT_OK;
    }
    if (argc != 2 || argv[1][0] == '-') {
        usage(stderr);
        return SL_EXIT_USAGE;
    }
    sl_error err;
    sl_error_init(&err);
    int rc = inspector_for(argv[1])->inspect(argv[1], &err);
    if (rc == 0)
        return SL_EXIT_OK;
    char line[1600];
    fprintf(stderr, "scanlod: %s\n", sl_error_format(&err, line, sizeof line));
    fflush(stdout);
    return sl_error_input_exit_code(rc);
}
