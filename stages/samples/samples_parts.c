/* samples stage: a part's file and the join that reads them (docs/engine.md, "Parts").
 *
 * `samples.part` (native byte order, like every work file; one host's parts are joined
 * on hosts of the same kind):
 *   "SLSPART1", u32 part, u32 parts, u64 vertices (of the whole item), u64 first, u64
 *   count, u64 sign_flips, u32 flags (1: colours, 2: the surface is closed), u32 0,
 *   then count f32 samples, then (colours) count x 4 bytes RGBA.
 * The engine has checked every part's record (sizes and hashes) before the join runs;
 * the join still refuses a part that does not belong where it is read (SL_E_CORRUPT).
 */
#include <errno.h>
#include <limits.h>
#include <stdio.h>
#include <string.h>

#include "core/atomicfile.h"
#include "stages/samples/samples_internal.h"

enum { HEADER_SIZE = 56, FLAG_COLORS = 1, FLAG_CLOSED = 2 };
static const char MAGIC[8] = {'S', 'L', 'S', 'P', 'A', 'R', 'T', '1'};

typedef struct part_header {
    uint32_t part, parts;
    uint64_t vertices, first, count, flips;
    uint32_t flags;
} part_header;

static void pack(unsigned char *h, const part_header *p)
{
    uint32_t zero = 0;
    memcpy(h, MAGIC, 8);
    memcpy(h + 8, &p->part, 4);
    memcpy(h + 12, &p->parts, 4);
    memcpy(h + 16, &p->vertices, 8);
    memcpy(h + 24, &p->first, 8);
    memcpy(h + 32, &p->count, 8);
    memcpy(h + 40, &p->flips, 8);
    memcpy(h + 48, &p->flags, 4);
    memcpy(h + 52, &zero, 4);
}

static int unpack(const unsigned char *h, part_header *p)
{
    if (memcmp(h, MAGIC, 8) != 0)
        return 0;
    memcpy(&p->part, h + 8, 4);
    memcpy(&p->parts, h + 12, 4);
    memcpy(&p->vertices, h + 16, 8);
    memcpy(&p->first, h + 24, 8);
    memcpy(&p->count, h + 32, 8);
    memcpy(&p->flips, h + 40, 8);
    memcpy(&p->flags, h + 48, 4);
    return 1;
}

int samples_part_write(const char *path, const sl_vdb_samples *s, int part, int parts,
                       int closed, uint64_t flips, sl_error *err)
{
    uint64_t first, end;
    sl_samples_part_range(s->count, part, parts, &first, &end);
    part_header p = {(uint32_t)part, (uint32_t)parts, s->count, first, end - first, flips,
                     (s->colors ? FLAG_COLORS : 0u) | (closed ? FLAG_CLOSED : 0u)};
    unsigned char h[HEADER_SIZE];
    pack(h, &p);
    sl_atomic_file f;
    int rc = sl_atomic_open(&f, path, err);
    if (rc)
        return rc;
    rc = sl_atomic_write(&f, h, sizeof h, err);
    if (rc == 0)
        rc = sl_atomic_write(&f, s->distance + first, (size_t)p.count * sizeof *s->distance, err);
    if (rc == 0 && s->colors)
        rc = sl_atomic_write(&f, s->colors + 4 * first, (size_t)p.count * 4, err);
    if (rc) {
        sl_atomic_abort(&f);
        return rc;
    }
    return sl_atomic_commit(&f, err);
}

static int bad_part(const char *path, const char *what, sl_error *err)
{
    return sl_error_set(err, SL_E_CORRUPT, 0, path, "samples part: %s", what);
}

static int read_part(const char *path, int part, int parts, sl_vdb_samples *out,
                     part_header *p, sl_error *err)
{
    FILE *f = fopen(path, "rb");
    if (!f)
        return sl_error_errno(err, errno, path, "open");
    unsigned char h[HEADER_SIZE];
    uint64_t first, end;
    sl_samples_part_range(out->count, part, parts, &first, &end);
    int rc = SL_OK;
    if (fread(h, 1, sizeof h, f) != sizeof h || !unpack(h, p))
        rc = bad_part(path, "not a samples part file", err);
    else if (p->part != (uint32_t)part || p->parts != (uint32_t)parts ||
             p->vertices != out->count || p->first != first || p->count != end - first ||
             !(p->flags & FLAG_COLORS) != !out->colors)
        rc = bad_part(path, "from another split of the item", err);
    else if (fread(out->distance + first, sizeof *out->distance, p->count, f) != p->count ||
             (out->colors && fread(out->colors + 4 * first, 4, p->count, f) != p->count) ||
             fgetc(f) != EOF)
        rc = bad_part(path, "truncated or too long", err);
    fclose(f);
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
