/* The range stage's registry entry: options of section [range], configure, run, report.
 * The work itself: range_points.c (what applies) and the files it calls.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "formats/scan_read.h"
#include "stages/range/range.h"

static const sl_option range_options[] = {
    {"range", "normals", SL_OPT_ENUM, "faces", 0, 0, "faces|file",
     "Point normals: 'faces' = area-weighted mean of the adjacent face normals (paper 1 "
     "section 4; PCA for point clouds); 'file' = the file's vertex normals, falling back to "
     "'faces' (counted) where a file normal is missing, zero or non-finite."},
    {"range", "knn", SL_OPT_INT, "12", 3, 256, NULL,
     "Neighbours used for PCA normals of point clouds without faces and for the spanning "
     "tree that orients them."},
    {"range", "grid_max_edge_factor", SL_OPT_DOUBLE, "4", 1, 1000, NULL,
     "Raw range scans: grid triangles with an edge longer than this many times the median "
     "distance between grid neighbours are skipped (they span depth jumps, not surface)."},
    {"range", "range_images", SL_OPT_BOOL, "false", 0, 0, NULL,
     "Also write six orthographic range images (depth + normal, one per axis direction) "
     "as EXR files into the artifact directory."},
    {"range", "range_image_size", SL_OPT_INT, "512", 16, 8192, NULL,
     "Width and height in pixels of each range image."},
    {"range", "max_vertices", SL_OPT_INT, "2147483648", 1, 4294967294.0, NULL,
     "Inputs declaring more vertices are refused (limit error, item quarantined); any input "
     "format (a glTF scene counts every instance of its meshes)."},
    {"range", "max_faces", SL_OPT_INT, "2147483648", 1, 1099511627776.0, NULL,
     "Inputs declaring more faces are refused (limit error, item quarantined): a PLY's face "
     "rows, an OFF's faces, the triangles of the other formats."},
    {"range", "max_header_bytes", SL_OPT_INT, "1048576", 1024, 1073741824.0, NULL,
     "Longest PLY header accepted, in bytes."},
    {"range", "max_nonfinite_fraction", SL_OPT_DOUBLE, "0.5", 0, 1, NULL,
     "Single NaN/Inf vertices are dropped and counted; a file where more than this fraction "
     "of vertices is non-finite is garbage (often the wrong endianness) and is refused."},
    {"range", "colors", SL_OPT_ENUM, "auto", 0, 0, "auto|none",
     "Point colours: 'auto' = vertex colours, else sampled from the input's texture image "
     "(PLY 'comment TextureFile', OBJ's MTL map_Kd, a glTF baseColor texture, embedded or "
     "not; a missing texture is a warning); 'none' = no colours."},
    SL_OPTION_END,
};

static int range_configure(const sl_config *cfg, void **stage_config, sl_error *err)
{
    sl_range_config *c = calloc(1, sizeof *c);
    if (!c)
        return sl_error_set(err, SL_E_NOMEM, 0, NULL, "out of memory");
    c->limits = sl_scan_default_limits(); /* max_face_corners is the reader's, not an option */
    c->normals_from_file = strcmp(sl_config_string(cfg, "range", "normals"), "file") == 0;
    c->knn = (uint32_t)sl_config_int(cfg, "range", "knn");
    c->grid_max_edge_factor = sl_config_double(cfg, "range", "grid_max_edge_factor");
    c->range_images = sl_config_bool(cfg, "range", "range_images");
    c->range_image_size = (int)sl_config_int(cfg, "range", "range_image_size");
    c->limits.max_vertices = (uint64_t)sl_config_int(cfg, "range", "max_vertices");
    c->limits.max_faces = (uint64_t)sl_config_int(cfg, "range", "max_faces");
    c->limits.max_header_bytes = (uint64_t)sl_config_int(cfg, "range", "max_header_bytes");
    c->max_nonfinite_fraction = sl_config_double(cfg, "range", "max_nonfinite_fraction");
    c->colors = strcmp(sl_config_string(cfg, "range", "colors"), "none") != 0;
    *stage_config = c;
    return SL_OK;
}

sl_range_config sl_range_default_config(void)
{
    sl_range_config c;
    sl_stage_default_config(&sl_range_stage, &c, sizeof c);
    return c;
}

/* What the reader says about the input: its format and what it read on without. */
static void report_input(sl_json *j, const sl_mesh *mesh)
{
    sl_json_string(j, "input_format", mesh->format);
    sl_json_u64(j, "input_warnings", mesh->warning_count);
    sl_json_string(j, "input_warning", mesh->warning_count ? mesh->warnings : NULL);
}

static void report_counts(sl_json *j, const sl_range_counts *c, const sl_pointset *ps,
                          int range_images)
{
    sl_json_u64(j, "input_vertices", c->input_vertices);
    sl_json_u64(j, "input_faces", c->input_faces);
    sl_json_u64(j, "points", c->points);
    sl_json_u64(j, "welded", c->welded);
    sl_json_object_begin(j, "dropped");
    sl_json_u64(j, "unreferenced_vertices", c->unreferenced);
    sl_json_u64(j, "nonfinite_vertices", c->nonfinite_vertices);
    sl_json_u64(j, "nonfinite_faces", c->nonfinite_faces);
    sl_json_u64(j, "degenerate_faces", c->degenerate_faces);
    sl_json_u64(j, "grid_long_edge_triangles", c->grid_long_edges);
    sl_json_object_end(j);
    sl_json_u64(j, "polygons_triangulated", c->polygons_triangulated);
    sl_json_u64(j, "grid_triangles", c->grid_triangles);
    sl_json_double(j, "grid_max_edge", c->grid_max_edge);
    sl_json_string(j, "normal_source", sl_normal_source_name(c->normal_source));
    sl_json_u64(j, "normal_fallbacks", c->normal_fallbacks);
    sl_json_bool(j, "normals_flipped_outward", c->normals_flipped);
    sl_json_u64(j, "pca_components", c->pca_components);
    sl_json_string(j, "color_source", c->color_source);
    sl_json_string(j, "texcoord_source", c->texcoord_source);
    sl_json_u64(j, "texcoord_seams", c->texcoord_seams);
    sl_json_u64(j, "texture_warnings", c->texture_warnings);
    sl_json_string(j, "texture_warning", c->texture_warnings ? c->texture_warning : NULL);
    sl_json_u64(j, "colors_unsampled", c->colors_unsampled);
    sl_json_array_begin(j, "bbox_min");
    for (int k = 0; k < 3; k++)
        sl_json_double(j, NULL, ps->bbox_min[k]);
    sl_json_array_end(j);
    sl_json_array_begin(j, "bbox_max");
    for (int k = 0; k < 3; k++)
        sl_json_double(j, NULL, ps->bbox_max[k]);
    sl_json_array_end(j);
    sl_json_double(j, "mean_spacing", ps->mean_spacing);
    sl_json_bool(j, "range_images", range_images);
}

static int range_run(const void *stage_config, const sl_stage_io *io, sl_error *err)
{
    const sl_range_config *cfg = stage_config;
    sl_mesh mesh;
    sl_mesh_init(&mesh);
    int rc = sl_scan_read(io->source_path, &cfg->limits, &mesh, NULL, io->progress, err);
    if (rc != SL_OK) {
        sl_mesh_release(&mesh);
        return rc;
    }
    char dir[PATH_MAX], path[PATH_MAX];
    sl_scan_directory_of(io->source_path, dir, sizeof dir);
    report_input(io->report, &mesh);
    sl_pointset ps;
    sl_range_counts counts;
    rc = sl_range_points_from_mesh(cfg, &mesh, dir, &ps, &counts, io->progress, err);
    sl_mesh_release(&mesh);
    if (rc != SL_OK) {
        if (!err->file[0])
            snprintf(err->file, sizeof err->file, "%s", io->source_path);
        return rc;
    }
    if ((rc = sl_stage_step(io, "write", 0.9, err)) != SL_OK ||
        (rc = sl_stage_path(path, io->out_dir, SL_POINTSET_FILE, err)) != SL_OK ||
        (rc = sl_pointset_write(path, &ps, err)) != SL_OK)
        goto done;
    if (cfg->range_images &&
        (rc = sl_range_images_write(io->out_dir, &ps, cfg->range_image_size, io->progress,
                                    err)) != SL_OK)
        goto done;
    report_counts(io->report, &counts, &ps, cfg->range_images);
done:
    sl_pointset_release(&ps);
    return rc;
}

const sl_stage sl_range_stage = {
    .name = "range",
    .methods = SL_METHODS_ALL,
    .description = "scan (PLY, OBJ, STL, OFF, XYZ/PTS, glTF/GLB) mesh or point cloud -> "
                   "oriented, coloured point set (paper 1 section 4)",
    .version = 3, /* 3: points.slpts format 3 (the points' texture coordinates) */
    .options = range_options,
    .configure = range_configure,
    .release_config = free,
    .run = range_run,
};
