/* PLY writer: binary little endian, through the atomic-write helper.
 *
 * Layout: vertex x y z [nx ny nz] [red green blue alpha] [u v], face
 * `list uchar int vertex_indices` [`list uchar float texcoord`], plus the TextureFile and
 * viewpoint conventions the reader understands, so a written mesh reads back identical.
 * Bytes are composed explicitly little endian (correct on any host) into a buffer that is
 * handed to sl_atomic_write in large pieces.
 */
#include <stdlib.h>
#include <string.h>

#include "core/atomicfile.h"
#include "formats/ply.h"

#define WRITE_BUFFER (256u << 10)
#define MAX_ROW 64 /* bytes of the largest vertex or face row */

typedef struct ply_writer {
    sl_atomic_file file;
    unsigned char *buf;
    size_t len;
    sl_error *err;
} ply_writer;

static unsigned char *put_u32(unsigned char *p, uint32_t v)
{
    p[0] = (unsigned char)v;
    p[1] = (unsigned char)(v >> 8);
    p[2] = (unsigned char)(v >> 16);
    p[3] = (unsigned char)(v >> 24);
    return p + 4;
}

static unsigned char *put_floats(unsigned char *p, const float *v, int n)
{
    for (int i = 0; i < n; i++) {
        uint32_t b;
        memcpy(&b, &v[i], sizeof b);
        p = put_u32(p, b);
    }
    return p;
}

/* Room for one more row; flushes the buffer when it is nearly full. */
static unsigned char *row_space(ply_writer *w, int *rc)
{
    if (w->len + MAX_ROW > WRITE_BUFFER) {
        *rc = sl_atomic_write(&w->file, w->buf, w->len, w->err);
        w->len = 0;
    }
    return w->buf + w->len;
}

static int write_header(ply_writer *w, const sl_mesh *m)
{
    sl_atomic_file *f = &w->file;
    int rc = sl_atomic_printf(f, w->err, "ply\nformat binary_little_endian 1.0\ncomment scanlod\n");
    if (!rc && m->texture_file[0])
        rc = sl_atomic_printf(f, w->err, "comment TextureFile %s\n", m->texture_file);
    if (!rc && m->has_viewpoint)
        rc = sl_atomic_printf(f, w->err, "obj_info viewpoint %.17g %.17g %.17g\n", m->viewpoint[0],
                              m->viewpoint[1], m->viewpoint[2]);
    if (!rc)
        rc = sl_atomic_printf(f, w->err, "element vertex %llu\nproperty float x\nproperty float y\n"
                              "property float z\n", (unsigned long long)m->vertex_count);
    if (!rc && m->normals)
        rc = sl_atomic_printf(f, w->err, "property float nx\nproperty float ny\nproperty float nz\n");
    if (!rc && m->colors)
        rc = sl_atomic_printf(f, w->err, "property uchar red\nproperty uchar green\n"
                              "property uchar blue\nproperty uchar alpha\n");
    if (!rc && m->texcoords)
        rc = sl_atomic_printf(f, w->err, "property float u\nproperty float v\n");
    if (!rc)
        rc = sl_atomic_printf(f, w->err, "element face %llu\nproperty list uchar int vertex_indices\n",
                              (unsigned long long)m->triangle_count);
    if (!rc && m->face_texcoords)
        rc = sl_atomic_printf(f, w->err, "property list uchar float texcoord\n");
    return rc ? rc : sl_atomic_printf(f, w->err, "end_header\n");
}

static int write_vertices(ply_writer *w, const sl_mesh *m)
{
    int rc = 0;
    for (uint64_t i = 0; i < m->vertex_count && !rc; i++) {
        unsigned char *p = row_space(w, &rc), *start = p;
        p = put_floats(p, m->positions + 3 * i, 3);
        if (m->normals)
            p = put_floats(p, m->normals + 3 * i, 3);
        if (m->colors) {
            memcpy(p, m->colors + 4 * i, 4);
            p += 4;
        }
        if (m->texcoords)
            p = put_floats(p, m->texcoords + 2 * i, 2);
        w->len += (size_t)(p - start);
    }
    return rc;
}

static int write_faces(ply_writer *w, const sl_mesh *m)
{
    int rc = 0;
    for (uint64_t i = 0; i < m->triangle_count && !rc; i++) {
        unsigned char *p = row_space(w, &rc), *start = p;
        *p++ = 3;
        for (int k = 0; k < 3; k++)
            p = put_u32(p, m->triangles[3 * i + k]);
        if (m->face_texcoords) {
            *p++ = 6;
            p = put_floats(p, m->face_texcoords + 6 * i, 6);
        }
        w->len += (size_t)(p - start);
    }
    return rc;
}

static int check_mesh(const sl_mesh *m, const char *path, sl_error *err)
{
    if (strchr(m->texture_file, '\n'))
        return sl_error_set(err, SL_E_INTERNAL, 0, path, "texture file name has a line break");
    for (uint64_t i = 0; i < 3 * m->triangle_count; i++)
        if (m->triangles[i] >= m->vertex_count || m->triangles[i] > INT32_MAX)
            return sl_error_set(err, SL_E_INTERNAL, 0, path,
                                "triangle %llu has vertex index %u (%llu vertices)",
                                (unsigned long long)(i / 3), m->triangles[i],
                                (unsigned long long)m->vertex_count);
    return 0;
}

int sl_ply_write(const char *path, const sl_mesh *mesh, sl_error *err)
{
    ply_writer w = {.err = err};
    int rc = check_mesh(mesh, path, err);
    if (rc)
        return rc;
    if (!(w.buf = malloc(WRITE_BUFFER)))
        return sl_error_set(err, SL_E_NOMEM, 0, path, "out of memory for the write buffer");
    if (!(rc = sl_atomic_open(&w.file, path, err))) {
        if (!(rc = write_header(&w, mesh)) && !(rc = write_vertices(&w, mesh)) &&
            !(rc = write_faces(&w, mesh)) && w.len)
            rc = sl_atomic_write(&w.file, w.buf, w.len, err);
        rc = rc ? rc : sl_atomic_commit(&w.file, err);
        if (rc)
            sl_atomic_abort(&w.file);
    }
    free(w.buf);
    return rc;
}
