/* sl_scan_read: the format of a scan from its magic and name, and the reader for it
 * (scan_read.h; the choices are in docs/inputs.md).
 *
 * Order: a magic that cannot be mistaken (PLY's "ply" line, GLB's "glTF") wins over the
 * name, so a mislabelled file still reads; otherwise the name decides; a name no reader
 * knows is sniffed (OFF keyword, binary STL by its exact size, "solid", a JSON object,
 * OBJ keywords, numeric columns). The file is mapped once, lazily; a PLY goes to
 * sl_ply_read, which maps it again with its own read-ahead choices.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/mman.h>

#include "core/io.h"
#include "formats/scan_internal.h"

static const struct scan_name {
    const char *suffix, *format;
} scan_names[] = {
    {".ply", "ply"}, {".obj", "obj"}, {".stl", "stl"},   {".off", "off"},
    {".xyz", "xyz"}, {".pts", "pts"}, {".gltf", "gltf"}, {".glb", "glb"},
};
#define SCAN_NAMES (sizeof scan_names / sizeof scan_names[0])

static const char *const scan_suffix_list[SCAN_NAMES + 1] = {
    ".ply", ".obj", ".stl", ".off", ".xyz", ".pts", ".gltf", ".glb", NULL};

sl_scan_limits sl_scan_default_limits(void)
{
    sl_ply_limits p = sl_ply_default_limits();
    sl_scan_limits l = {p.max_header_bytes, p.max_vertices, p.max_faces, p.max_face_corners};
    return l;
}

sl_ply_limits sl_scan_ply_limits(const sl_scan_limits *l)
{
    sl_ply_limits p = {l->max_header_bytes, l->max_vertices, l->max_faces, l->max_face_corners};
    return p;
}

const char *sl_scan_format_of(const char *path)
{
    const char *slash = strrchr(path, '/'), *base = slash ? slash + 1 : path;
    const char *dot = strrchr(base, '.');
    for (size_t i = 0; dot && dot != base && i < SCAN_NAMES; i++)
        if (strcasecmp(dot, scan_names[i].suffix) == 0)
            return scan_names[i].format;
    return NULL;
}

const char *const *sl_scan_suffixes(void)
{
    return scan_suffix_list;
}

int sl_scan_sibling_path(const char *dir, const char *name, char *out, size_t size)
{
    return sl_ply_texture_path(dir, name, out, size);
}

void sl_scan_directory_of(const char *path, char *dir, size_t size)
{
    const char *slash = strrchr(path, '/');
    if (!slash)
        snprintf(dir, size, ".");
    else if (slash == path)
        snprintf(dir, size, "/");
    else
        snprintf(dir, size, "%.*s", (int)(slash - path), path);
}

int scan_sibling_map(const scan_src *s, const char *name, void **map, size_t *size,
                     sl_error *err)
{
    char path[4096];
    *map = NULL;
    *size = 0;
    if (!s->dir)
        return sl_error_set(err, SL_E_BADINPUT, 0, s->name, "'%s': no folder to look in", name);
    int where = sl_scan_sibling_path(s->dir, name, path, sizeof path);
    if (where == -1)
        return sl_error_set(err, SL_E_BADINPUT, 0, s->name,
                            "'%s' is not a name inside the scan's folder", name);
    if (where)
        return sl_error_set(err, SL_E_LIMIT, 0, s->name, "'%s': path too long", name);
    return sl_io_map(path, 0, map, size, err);
}

/* A first line that is only an OBJ keyword line ("v ...", "# ...", "mtllib ..."). */
static int obj_sniff(const unsigned char *data, size_t size)
{
    static const char *const words[] = {"v", "vt", "vn", "f", "o", "g", "mtllib", "usemtl", "s"};
    scan_src s = {.name = "", .data = data, .size = size < 4096 ? size : 4096};
    text_cursor c;
    text_begin(&c, &s);
    while (text_next_line(&c)) {
        const char *p = text_skip(c.line, c.eol), *q = text_token_end(p, c.eol);
        if (p == c.eol || *p == '#')
            continue;
        for (size_t i = 0; i < sizeof words / sizeof words[0]; i++)
            if (text_token_is(p, q, words[i]))
                return 1;
        return 0;
    }
    return 0;
}

static int starts_with(const unsigned char *data, size_t size, const char *magic)
{
    size_t n = strlen(magic);
    return size >= n && memcmp(data, magic, n) == 0;
}

/* The format by content alone, or NULL. */
static const char *sniff(const unsigned char *data, size_t size)
{
    size_t i = 0;
    while (i < size && (data[i] == ' ' || data[i] == '\t' || data[i] == '\r' || data[i] == '\n'))
        i++;
    if (sl_off_sniff(data, size))
        return "off";
    if (sl_stl_is_binary(data, size) || (size - i >= 5 && !strncasecmp((const char *)data + i,
                                                                     "solid", 5)))
        return "stl";
    if (i < size && data[i] == '{')
        return "gltf";
    if (obj_sniff(data, size))
        return "obj";
    return sl_xyz_sniff(data, size) ? "xyz" : NULL;
}

static const char *choose_format(const char *name, const unsigned char *data, size_t size)
{
    if (starts_with(data, size, "ply\n") || starts_with(data, size, "ply\r"))
        return "ply";
    if (starts_with(data, size, "glTF"))
        return "glb";
    const char *by_name = name ? sl_scan_format_of(name) : NULL;
    return by_name ? by_name : sniff(data, size);
}

typedef int (*read_fn)(const scan_src *, sl_mesh *, sl_scan_info *);
typedef int (*info_fn)(const scan_src *, sl_scan_info *);

static const struct scan_reader {
    const char *format;
    read_fn read;
    info_fn info;
} readers[] = {
    {"obj", sl_obj_read_source, sl_obj_info_source},
    {"stl", sl_stl_read_source, sl_stl_info_source},
    {"off", sl_off_read_source, sl_off_info_source},
    {"xyz", sl_xyz_read_source, sl_xyz_info_source},
    {"pts", sl_xyz_read_source, sl_xyz_info_source},
    {"gltf", sl_gltf_read_source, sl_gltf_info_source},
    {"glb", sl_gltf_read_source, sl_gltf_info_source},
};

static const struct scan_reader *reader_for(const char *format)
{
    for (size_t i = 0; format && i < sizeof readers / sizeof readers[0]; i++)
        if (!strcmp(readers[i].format, format))
            return &readers[i];
    return NULL;
}

static void ply_facts(const sl_ply_info *p, sl_scan_info *info)
{
    snprintf(info->format, sizeof info->format, "ply");
    snprintf(info->detail, sizeof info->detail, "%s", p->elements);
    info->declared_vertices = p->declared_vertices;
    info->declared_faces = p->declared_faces;
    info->has_normals = p->has_normals;
    info->has_colors = p->has_colors;
    info->has_texcoords = p->has_texcoords || p->has_face_texcoords;
    info->ply = *p;
}

static int unknown_format(const char *name, sl_error *err)
{
    return sl_error_set(err, SL_E_UNSUPPORTED, 0, name,
                        "not a scan format scanlod reads, by name or content (PLY, OBJ, STL, "
                        "OFF, XYZ/PTS, glTF/GLB)");
}

/* One reader over a source; the mesh left empty on failure. */
static int read_source(const scan_src *s, const char *format, sl_mesh *out, sl_scan_info *info)
{
    const struct scan_reader *r = reader_for(format);
    if (!r)
        return unknown_format(s->name, s->err);
    int rc = r->read(s, out, info);
    if (rc) {
        sl_mesh_release(out);
        if (info)
            memset(info, 0, sizeof *info);
        return rc;
    }
    snprintf(out->format, sizeof out->format, "%s", info && info->format[0] ? info->format
                                                                             : r->format);
    return 0;
}

static int ply_memory(const void *data, size_t size, const char *name,
                      const sl_scan_limits *lim, sl_mesh *out, sl_scan_info *info,
                      sl_error *err)
{
    sl_ply_limits pl = sl_scan_ply_limits(lim);
    sl_ply_info pi;
    int rc = sl_ply_read_memory(data, size, name, &pl, out, &pi, err);
    if (!rc) {
        snprintf(out->format, sizeof out->format, "ply");
        if (info)
            ply_facts(&pi, info);
    }
    return rc;
}

int sl_scan_read_memory(const void *data, size_t size, const char *name, const char *format,
                        const char *dir, const sl_scan_limits *limits, sl_mesh *out,
                        sl_scan_info *info, sl_error *err)
{
    static const unsigned char empty[1];
    sl_scan_limits lim = limits ? *limits : sl_scan_default_limits();
    sl_mesh_init(out);
    if (info)
        memset(info, 0, sizeof *info);
    const unsigned char *bytes = data ? data : empty;
    size = data ? size : 0;
    if (!format)
        format = choose_format(name, bytes, size);
    if (format && !strcmp(format, "ply"))
        return ply_memory(bytes, size, name, &lim, out, info, err);
    scan_src s = {name, dir, bytes, size, &lim, NULL, err};
    return read_source(&s, format, out, info);
}

/* A file mapped (lazily) as a source, and the format its magic and name say. */
typedef struct mapped {
    void *map;
    size_t size;
    const char *format;
    char dir[4096];
    sl_scan_limits lim;
    scan_src s;
} mapped;

static int map_source(mapped *f, const char *path, const sl_scan_limits *limits,
                      sl_progress *progress, sl_error *err)
{
    static const unsigned char empty[1];
    f->lim = limits ? *limits : sl_scan_default_limits();
    int rc = sl_io_map(path, 0, &f->map, &f->size, err);
    if (rc)
        return rc;
    const unsigned char *bytes = f->map ? f->map : empty;
    f->format = choose_format(path, bytes, f->size);
    sl_scan_directory_of(path, f->dir, sizeof f->dir);
    f->s = (scan_src){path, f->dir, bytes, f->size, &f->lim, progress, err};
    return 0;
}

static int is_ply(const mapped *f)
{
    return f->format && !strcmp(f->format, "ply");
}

int sl_scan_read(const char *path, const sl_scan_limits *limits, sl_mesh *out,
                 sl_scan_info *info, sl_progress *progress, sl_error *err)
{
    mapped f;
    sl_mesh_init(out);
    if (info)
        memset(info, 0, sizeof *info);
    int rc = map_source(&f, path, limits, progress, err);
    if (rc)
        return rc;
    if (is_ply(&f)) { /* sl_ply_read maps it with its own read-ahead choices */
        sl_io_unmap(f.map, f.size);
        sl_ply_limits pl = sl_scan_ply_limits(&f.lim);
        sl_ply_info pi;
        if ((rc = sl_ply_read(path, &pl, out, &pi, progress, err)) == 0) {
            snprintf(out->format, sizeof out->format, "ply");
            if (info)
                ply_facts(&pi, info);
        }
        return rc;
    }
    if (f.map)
        madvise(f.map, f.size, MADV_SEQUENTIAL);
    rc = read_source(&f.s, f.format, out, info);
    sl_io_unmap(f.map, f.size);
    return rc;
}

int sl_scan_read_info(const char *path, const sl_scan_limits *limits, sl_scan_info *info,
                      sl_error *err)
{
    mapped f;
    memset(info, 0, sizeof *info);
    int rc = map_source(&f, path, limits, NULL, err);
    if (rc)
        return rc;
    const struct scan_reader *r = reader_for(f.format);
    if (is_ply(&f)) {
        sl_ply_limits pl = sl_scan_ply_limits(&f.lim);
        sl_ply_info pi;
        if ((rc = sl_ply_read_info(path, &pl, &pi, err)) == 0)
            ply_facts(&pi, info);
    } else {
        rc = r ? r->info(&f.s, info) : unknown_format(path, err);
    }
    sl_io_unmap(f.map, f.size);
    return rc;
}
