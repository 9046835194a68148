/* PLY reader entry points: limits, mmap of the file, header + body, the info summary.
 *
 * The file is mapped, never copied: memory is the mesh plus the page cache. A file that
 * shrinks while mapped raises SIGBUS; inputs are not expected to change under a run, and
 * the engine treats a crash as retry-once-then-quarantine.
 */
#include <errno.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>

#include "core/io.h"
#include "formats/ply_internal.h"

#define POPULATE_MAX ((size_t)256 << 20)

sl_ply_limits sl_ply_default_limits(void)
{
    sl_ply_limits lim = {
        .max_header_bytes = 1u << 20,
        .max_vertices = 1ull << 31,
        .max_faces = 1ull << 31,
        .max_face_corners = 1024,
    };
    return lim;
}

static int all_roles(const ply_header *h, int a, int b, int c)
{
    return h->role_seen[a] && h->role_seen[b] && (c < 0 || h->role_seen[c]);
}

int sl_ply_wants_normals(const ply_header *h)
{
    return all_roles(h, ROLE_NX, ROLE_NY, ROLE_NZ);
}

int sl_ply_wants_colors(const ply_header *h)
{
    return all_roles(h, ROLE_RED, ROLE_GREEN, ROLE_BLUE);
}

int sl_ply_wants_texcoords(const ply_header *h)
{
    return all_roles(h, ROLE_U, ROLE_V, -1);
}

int sl_ply_wants_face_texcoords(const ply_header *h)
{
    return h->role_seen[ROLE_TEXCOORD];
}

/* A range grid is kept only when obj_info gives dimensions that match its row count. */
int sl_ply_wants_grid(const ply_header *h)
{
    if (h->grid_element < 0 || !h->role_seen[ROLE_GRID_INDICES] || h->grid_cols <= 0 ||
        h->grid_rows <= 0)
        return 0;
    return (uint64_t)h->grid_cols * (uint64_t)h->grid_rows == h->elements[h->grid_element].count;
}

static void append(char *buf, size_t size, size_t *len, const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));

static void append(char *buf, size_t size, size_t *len, const char *fmt, ...)
{
    if (*len >= size)
        return;
    va_list ap;
    va_start(ap, fmt);
    int n = vsnprintf(buf + *len, size - *len, fmt, ap);
    va_end(ap);
    *len = n < 0 ? size : *len + (size_t)n;
    if (*len >= size) /* mark the cut */
        memcpy(buf + size - 4, "...", 4);
}

static void describe_elements(const ply_header *h, char *buf, size_t size)
{
    size_t len = 0;
    buf[0] = 0;
    for (int i = 0; i < h->nelements; i++) {
        const ply_element *e = &h->elements[i];
        append(buf, size, &len, "%s%s %llu (", i ? "; " : "", e->name, (unsigned long long)e->count);
        for (int k = 0; k < e->nprops; k++) {
            const ply_property *p = &h->props[e->first_prop + k];
            if (p->count_type)
                append(buf, size, &len, "%slist %s %s %s", k ? " " : "",
                       sl_ply_type_name(p->count_type), sl_ply_type_name(p->type), p->name);
            else
                append(buf, size, &len, "%s%s", k ? " " : "", p->name);
        }
        append(buf, size, &len, ")");
    }
}

void sl_ply_header_info(const ply_header *h, sl_ply_info *info)
{
    memset(info, 0, sizeof *info);
    info->format = h->format;
    info->header_bytes = h->header_bytes;
    if (h->vertex_element >= 0)
        info->declared_vertices = h->elements[h->vertex_element].count;
    if (h->face_element >= 0)
        info->declared_faces = h->elements[h->face_element].count;
    info->element_count = h->nelements;
    describe_elements(h, info->elements, sizeof info->elements);
    info->has_normals = sl_ply_wants_normals(h);
    info->has_colors = sl_ply_wants_colors(h);
    info->has_texcoords = sl_ply_wants_texcoords(h);
    info->has_face_texcoords = sl_ply_wants_face_texcoords(h);
    info->has_range_grid = sl_ply_wants_grid(h);
}

static int read_buffer(const unsigned char *data, size_t size, const char *name,
                       const sl_ply_limits *limits, sl_mesh *out, sl_ply_info *info,
                       sl_progress *progress, sl_error *err)
{
    sl_ply_limits lim = limits ? *limits : sl_ply_default_limits();
    sl_mesh_init(out);
    if (info)
        memset(info, 0, sizeof *info);
    ply_header *h = malloc(sizeof *h);
    if (!h)
        return sl_error_set(err, SL_E_NOMEM, ENOMEM, name, "out of memory for the header");
    int rc = sl_ply_parse_header(data, size, name, &lim, h, err);
    if (info && h->header_bytes) /* the header was complete: worth describing */
        sl_ply_header_info(h, info);
    if (!rc) {
        ply_reader r = {.h = h, .name = name, .lim = &lim, .err = err, .progress = progress,
                        .data = data, .body = data + h->header_bytes,
                        .p = data + h->header_bytes, .end = data + size, .mesh = out};
        rc = sl_ply_read_body(&r);
        free(r.corners);
        free(r.corner_uv);
    }
    if (rc)
        sl_mesh_release(out);
    free(h);
    return rc;
}

int sl_ply_read_memory(const void *data, size_t size, const char *name,
                       const sl_ply_limits *limits, sl_mesh *out, sl_ply_info *info,
                       sl_error *err)
{
    static const unsigned char empty[1];
    return read_buffer(data ? data : empty, data ? size : 0, name, limits, out, info, NULL, err);
}

int sl_ply_read(const char *path, const sl_ply_limits *limits, sl_mesh *out, sl_ply_info *info,
                sl_progress *progress, sl_error *err)
{
    sl_mesh_init(out);
    if (info)
        memset(info, 0, sizeof *info);
    size_t size = 0;
    void *map;
    /* Prefault typical scans in one call (cheaper than a fault per 64 KiB); larger files
     * stream through readahead instead of being pinned whole. */
    int rc = sl_io_map(path, POPULATE_MAX, &map, &size, err);
    if (rc)
        return rc;
    if (map)
        madvise(map, size, MADV_SEQUENTIAL);
    rc = read_buffer(map, size, path, limits, out, info, progress, err);
    sl_io_unmap(map, size);
    return rc;
}

int sl_ply_read_info(const char *path, const sl_ply_limits *limits, sl_ply_info *info,
                     sl_error *err)
{
    memset(info, 0, sizeof *info);
    size_t size = 0;
    void *map;
    int rc = sl_io_map(path, 0, &map, &size, err); /* lazily: only the header's pages are read */
    if (rc)
        return rc;
    static const unsigned char empty[1];
    sl_ply_limits lim = limits ? *limits : sl_ply_default_limits();
    ply_header *h = malloc(sizeof *h);
    rc = h ? sl_ply_parse_header(map ? map : empty, size, path, &lim, h, err)
           : sl_error_set(err, SL_E_NOMEM, ENOMEM, path, "out of memory for the header");
    if (rc == 0)
        sl_ply_header_info(h, info);
    free(h);
    sl_io_unmap(map, size);
    return rc;
}

/* A texture name must stay inside the PLY's directory tree. */
static int texture_name_inside(const char *name)
{
    if (!name[0] || name[0] == '/')
        return 0;
    for (const char *p = name; *p; p++)
        if (p[0] == '.' && p[1] == '.' && (p == name || p[-1] == '/') && (p[2] == '/' || !p[2]))
            return 0;
    return 1;
}

int sl_ply_texture_path(const char *dir, const char *name, char *out, size_t size)
{
    if (!dir || !texture_name_inside(name))
        return -1;
    return snprintf(out, size, "%s/%s", dir, name) < (int)size ? 0 : -2;
}
