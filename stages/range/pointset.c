/* The oriented point set artifact `points.slpts` (format: docs/formats.md and
 * docs/range-stage.md), in the envelope of core/artifact.h with magic "SLPOINTS".
 *
 * Body, little-endian:
 *   0   u64  count
 *   8   u32  flags (bit 0: colours present; bit 1: texture coordinates present; other
 *            bits must be 0)
 *   12  6xf32 bbox min xyz, max xyz
 *   36  f64  mean_spacing
 *   44  u32  normal_source (enum sl_normal_source)
 *   48  u64  triangle_count (0 for point clouds)
 *   56  f32  positions[3 * count]
 *       f32  normals[3 * count]
 *       u8   colours[4 * count] RGBA (only with flag bit 0)
 *       f32  texcoords[2 * count] u, v as the input's, v up (only with flag bit 1)
 *       u32  triangles[3 * triangle_count], point indices, wound so that their normals
 *            face the same way as the points' (outwards on a closed mesh)
 * The reader checks that the body size is exactly what the counts and flags imply
 * (overflow-checked) before it allocates anything, and every triangle index.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/artifact.h"
#include "stages/range/range.h"

#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ != __ORDER_LITTLE_ENDIAN__
#error "scanlod's binary formats are little-endian; add byte swapping for this host"
#endif

#define POINTSET_MAGIC "SLPOINTS"
#define POINTSET_HEAD 56u
#define POINTSET_HAS_COLORS 1u
#define POINTSET_HAS_TEXCOORDS 2u
#define POINTSET_MAX_BODY (1ull << 40)

static int host_is_little_endian(void)
{
    const uint16_t one = 1;
    return *(const unsigned char *)&one == 1;
}

static void put_f32(unsigned char *p, float f)
{
    uint32_t bits;
    memcpy(&bits, &f, sizeof bits);
    sl_put_u32(p, bits);
}

static float get_f32(const unsigned char *p)
{
    uint32_t bits = sl_get_u32(p);
    float f;
    memcpy(&f, &bits, sizeof f);
    return f;
}

/* 4-byte words (floats or u32) as LE bytes: the array itself on LE hosts, else a
 * converted copy in *copy. */
static const void *le_words(const void *v, uint64_t n, unsigned char **copy)
{
    *copy = NULL;
    if (host_is_little_endian())
        return v;
    *copy = malloc(4 * n + 1);
    if (*copy)
        for (uint64_t i = 0; i < n; i++) {
            uint32_t bits;
            memcpy(&bits, (const unsigned char *)v + 4 * i, sizeof bits);
            sl_put_u32(*copy + 4 * i, bits);
        }
    return *copy;
}

static uint64_t per_point(uint32_t flags)
{
    return 24u + (flags & POINTSET_HAS_COLORS ? 4u : 0u) + (flags & POINTSET_HAS_TEXCOORDS ? 8u : 0u);
}

int sl_pointset_write(const char *path, const sl_pointset *ps, sl_error *err)
{
    int colors = ps->colors != NULL;
    unsigned char head[POINTSET_HEAD];
    sl_put_u64(head, ps->count);
    sl_put_u32(head + 8, (colors ? POINTSET_HAS_COLORS : 0u) |
                             (ps->texcoords ? POINTSET_HAS_TEXCOORDS : 0u));
    for (int k = 0; k < 3; k++) {
        put_f32(head + 12 + 4 * k, ps->bbox_min[k]);
        put_f32(head + 24 + 4 * k, ps->bbox_max[k]);
    }
    uint64_t spacing_bits;
    memcpy(&spacing_bits, &ps->mean_spacing, sizeof spacing_bits);
    sl_put_u64(head + 36, spacing_bits);
    sl_put_u32(head + 44, ps->normal_source);
    sl_put_u64(head + 48, ps->triangle_count);

    unsigned char *pos_copy, *nrm_copy, *tri_copy, *uv_copy = NULL;
    const void *pos = le_words(ps->positions, 3 * ps->count, &pos_copy);
    const void *nrm = le_words(ps->normals, 3 * ps->count, &nrm_copy);
    const void *tri = le_words(ps->triangles, 3 * ps->triangle_count, &tri_copy);
    const void *uv = ps->texcoords ? le_words(ps->texcoords, 2 * ps->count, &uv_copy) : NULL;
    int rc;
    if (!pos || !nrm || (ps->triangle_count && !tri) || (ps->texcoords && !uv)) {
        rc = sl_error_set(err, SL_E_NOMEM, 0, path, "out of memory");
    } else {
        sl_artifact_part parts[6] = {
            {head, sizeof head},
            {pos, (size_t)(12 * ps->count)},
            {nrm, (size_t)(12 * ps->count)},
            {ps->colors, colors ? (size_t)(4 * ps->count) : 0},
            {uv, uv ? (size_t)(8 * ps->count) : 0},
            {tri, (size_t)(12 * ps->triangle_count)},
        };
        rc = sl_artifact_write(path, POINTSET_MAGIC, SL_POINTSET_FORMAT_VERSION,
                               sl_range_stage.version, parts, 6, err);
    }
    free(uv_copy);
    free(pos_copy);
    free(nrm_copy);
    free(tri_copy);
    return rc;
}

/* Checks the fixed head against the body size; OUT: count, flags, triangles. */
static int check_head(const unsigned char *body, uint64_t size, const char *path,
                      uint64_t *count, uint32_t *flags_out, uint64_t *triangles, sl_error *err)
{
    if (size < POINTSET_HEAD)
        return sl_error_corrupt(err, path, "point set: body shorter than its header");
    uint64_t n = sl_get_u64(body);
    uint32_t flags = sl_get_u32(body + 8);
    if (flags & ~(POINTSET_HAS_COLORS | POINTSET_HAS_TEXCOORDS))
        return sl_error_corrupt(err, path, "point set: unknown flags");
    *flags_out = flags;
    uint64_t each = per_point(flags), t = sl_get_u64(body + 48);
    if (n > (size - POINTSET_HEAD) / each ||
        t > (size - POINTSET_HEAD - n * each) / 12u || POINTSET_HEAD + n * each + 12u * t != size)
        return sl_error_corrupt(err, path, "point set: point or triangle count disagrees with the body size");
    if (t && n > UINT32_MAX)
        return sl_error_corrupt(err, path, "point set: triangles over more than 2^32 points");
    if (sl_get_u32(body + 44) > SL_NORMALS_RANGE_GRID)
        return sl_error_corrupt(err, path, "point set: unknown normal source");
    *count = n;
    *triangles = t;
    return SL_OK;
}

/* Read in order straight into the point set's arrays (sl_artifact_reader: checksummed as
 * read, the head's counts checked against the body's size before they size anything): the
 * whole body beside the arrays was 480 MB more at 20 M triangles, in every stage that reads
 * the points. The arrays are stored little-endian, as this host holds them (asserted at
 * compile time), so they are read as they are. */
int sl_pointset_read(const char *path, sl_pointset *out, sl_error *err)
{
    memset(out, 0, sizeof *out);
    sl_artifact_reader reader;
    int rc = sl_artifact_reader_open(&reader, path, POINTSET_MAGIC, SL_POINTSET_FORMAT_VERSION,
                                     SL_POINTSET_FORMAT_VERSION, POINTSET_MAX_BODY, err);
    if (rc != SL_OK)
        return rc;
    uint64_t size = reader.info.body_size, n = 0, t = 0;
    uint32_t flags = 0;
    unsigned char head[POINTSET_HEAD];
    rc = size < POINTSET_HEAD ? sl_error_corrupt(err, path, "point set: body shorter than its header")
                              : sl_artifact_reader_take(&reader, head, sizeof head, err);
    if (rc == SL_OK)
        rc = check_head(head, size, path, &n, &flags, &t, err);
    int colors = (flags & POINTSET_HAS_COLORS) != 0, uv = (flags & POINTSET_HAS_TEXCOORDS) != 0;
    if (rc == SL_OK) {
        out->count = n;
        for (int k = 0; k < 3; k++) {
            out->bbox_min[k] = get_f32(head + 12 + 4 * k);
            out->bbox_max[k] = get_f32(head + 24 + 4 * k);
        }
        uint64_t spacing_bits = sl_get_u64(head + 36);
        memcpy(&out->mean_spacing, &spacing_bits, sizeof out->mean_spacing);
        out->normal_source = sl_get_u32(head + 44);
        out->triangle_count = t;
        rc = sl_artifact_reader_take_new(&reader, (void **)&out->positions, 12 * n, err);
    }
    if (rc == SL_OK)
        rc = sl_artifact_reader_take_new(&reader, (void **)&out->normals, 12 * n, err);
    if (rc == SL_OK && colors)
        rc = sl_artifact_reader_take_new(&reader, (void **)&out->colors, 4 * n, err);
    if (rc == SL_OK && uv)
        rc = sl_artifact_reader_take_new(&reader, (void **)&out->texcoords, 8 * n, err);
    if (rc == SL_OK && t)
        rc = sl_artifact_reader_take_new(&reader, (void **)&out->triangles, 12 * t, err);
    if (rc == SL_OK)
        rc = sl_artifact_reader_finish(&reader, err);
    sl_artifact_reader_close(&reader);
    int bad_uv = 0, bad_index = 0;
    if (rc == SL_OK) {
#pragma omp parallel for reduction(| : bad_uv) schedule(static)
        for (uint64_t i = 0; i < (uv ? 2 * n : 0); i++)
            bad_uv |= !isfinite(out->texcoords[i]);
#pragma omp parallel for reduction(| : bad_index) schedule(static)
        for (uint64_t i = 0; i < 3 * t; i++)
            bad_index |= out->triangles[i] >= n;
        if (bad_uv)
            rc = sl_error_corrupt(err, path, "point set: non-finite texture coordinate");
        else if (bad_index)
            rc = sl_error_corrupt(err, path, "point set: triangle index out of range");
    }
    if (rc != SL_OK)
        sl_pointset_release(out);
    return rc;
}

void sl_pointset_release(sl_pointset *ps)
{
    if (!ps)
        return;
    free(ps->positions);
    free(ps->normals);
    free(ps->colors);
    free(ps->texcoords);
    free(ps->triangles);
    memset(ps, 0, sizeof *ps);
}

const char *sl_normal_source_name(uint32_t source)
{
    switch (source) {
    case SL_NORMALS_FACES: return "faces";
    case SL_NORMALS_FILE: return "file";
    case SL_NORMALS_PCA_VIEWPOINT: return "pca-viewpoint";
    case SL_NORMALS_PCA_PROPAGATED: return "pca-propagated";
    case SL_NORMALS_RANGE_GRID: return "range-grid";
    }
    return "unknown";
}
