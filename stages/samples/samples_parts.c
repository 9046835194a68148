/* samples stage: a part's file and the join that reads them (docs/engine.md, "Parts").
 *
 * `samples.part`: the artifact envelope (core/artifact.h, magic "SLSPARTS", format 1),
 * body (little-endian):
 *   u32 part, u32 parts, u64 vertices (of the whole item), u64 first, u64 count,
 *   u64 sign_flips, u32 flags (1: colours, 2: the surface is closed), u32 0,
 *   then count f32 samples, then (colours) count x 4 bytes RGBA.
 * The engine has checked every part's record (sizes and hashes) before the join runs, so
 * the join reads each part's arrays straight into place (no second checksum pass); it
 * still refuses a part that does not belong where it is read (SL_E_CORRUPT).
 */
#include <limits.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

#include "core/artifact.h"
#include "stages/samples/samples_internal.h"

enum { PART_HEAD = 48, FLAG_COLORS = 1, FLAG_CLOSED = 2, PART_FORMAT = 1 };
static const char MAGIC[8] = {'S', 'L', 'S', 'P', 'A', 'R', 'T', 'S'};

typedef struct part_header {
    uint32_t part, parts;
    uint64_t vertices, first, count, flips;
    uint32_t flags;
} part_header;

int samples_part_write(const char *path, const sl_vdb_samples *s, int part, int parts,
                       int closed, uint64_t flips, sl_error *err)
{
    uint64_t first, end;
    sl_samples_part_range(s->count, part, parts, &first, &end);
    unsigned char h[PART_HEAD] = {0};
    sl_put_u32(h, (uint32_t)part);
    sl_put_u32(h + 4, (uint32_t)parts);
    sl_put_u64(h + 8, s->count);
    sl_put_u64(h + 16, first);
    sl_put_u64(h + 24, end - first);
    sl_put_u64(h + 32, flips);
    sl_put_u32(h + 40, (s->colors ? FLAG_COLORS : 0u) | (closed ? FLAG_CLOSED : 0u));
    sl_artifact_part body[3] = {{h, sizeof h},
                                {s->distance + first, (end - first) * sizeof *s->distance},
                                {s->colors ? s->colors + 4 * first : NULL,
                                 s->colors ? (end - first) * 4 : 0}};
    return sl_artifact_write(path, MAGIC, PART_FORMAT, sl_samples_stage.version, body,
                             s->colors ? 3 : 2, err);
}

static int bad_part(const char *path, const char *what, sl_error *err)
{
    return sl_error_set(err, SL_E_CORRUPT, 0, path, "samples part: %s", what);
}

static int read_part(const char *path, int part, int parts, sl_vdb_samples *out,
                     part_header *p, sl_error *err)
{
    int fd;
    sl_artifact_info info;
    int rc = sl_artifact_open(path, MAGIC, PART_FORMAT, PART_FORMAT, &fd, &info, err);
    if (rc == SL_E_CORRUPT) { /* say what it is in the join's words, keep the envelope's */
        char why[sizeof err->message];
        snprintf(why, sizeof why, "truncated or not a part file (%.600s)", err->message);
        sl_error_init(err); /* the first failure wins: this one replaces it */
        return bad_part(path, why, err);
    }
    if (rc)
        return rc;
    unsigned char h[PART_HEAD];
    uint64_t first, end;
    sl_samples_part_range(out->count, part, parts, &first, &end);
    rc = info.body_size < PART_HEAD ? bad_part(path, "truncated or not a part file", err)
                                    : sl_artifact_pread(fd, path, h, sizeof h, 0, err);
    if (rc) {
        close(fd);
        return rc;
    }
    *p = (part_header){sl_get_u32(h), sl_get_u32(h + 4), sl_get_u64(h + 8),
                       sl_get_u64(h + 16), sl_get_u64(h + 24), sl_get_u64(h + 32),
                       sl_get_u32(h + 40)};
    uint64_t count = end - first, row = sizeof *out->distance + (out->colors ? 4 : 0);
    if (p->part != (uint32_t)part || p->parts != (uint32_t)parts ||
        p->vertices != out->count || p->first != first || p->count != count ||
        !(p->flags & FLAG_COLORS) != !out->colors)
        rc = bad_part(path, "from another split of the item", err);
    else if (info.body_size != PART_HEAD + count * row)
        rc = bad_part(path, "truncated or too long", err);
    else
        rc = sl_artifact_pread(fd, path, out->distance + first, count * sizeof *out->distance,
                               PART_HEAD, err);
    if (rc == 0 && out->colors)
        rc = sl_artifact_pread(fd, path, out->colors + 4 * first, count * 4,
                               PART_HEAD + count * sizeof *out->distance, err);
    close(fd);
    return rc;
}

int samples_parts_fill(void *ctx, sl_vdb_samples *out, int *closed, uint64_t *flips,
                       sl_error *err)
{
    const samples_parts *parts = ctx;
    *flips = 0;
    for (int k = 0; k < parts->count; k++) {
        char path[PATH_MAX];
        part_header p = {0};
        int n = snprintf(path, sizeof path, "%s/%s", parts->dirs[k], SL_SAMPLES_PART_FILE);
        if (n < 0 || (size_t)n >= sizeof path)
            return sl_error_set(err, SL_E_LIMIT, 0, parts->dirs[k], "path too long");
        int rc = read_part(path, k, parts->count, out, &p, err);
        if (rc)
            return rc;
        if (k == 0)
            *closed = (p.flags & FLAG_CLOSED) != 0;
        else if (*closed != ((p.flags & FLAG_CLOSED) != 0))
            return bad_part(path, "disagrees with part 1 on whether the surface is closed",
                            err);
        *flips += p.flips;
    }
    return SL_OK;
}
