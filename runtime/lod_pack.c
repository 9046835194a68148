/* Packed parts (lod_pack.h). */
#include "runtime/lod_pack.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>
#include <zstd.h>

#include "core/artifact.h"

#define HEAD 8
#define MAX_RECORD 1024
#define TRIAL_LEVEL 1

enum { CODEC_COPY = 0, CODEC_ZSTD = 1 };
enum { FILTER_NONE = 0, FILTER_PLANES = 1, FILTER_DIFF = 2 };

typedef struct piece {
    const unsigned char *data;
    size_t size;
    uint16_t record;
    /* the result */
    unsigned char *stored;
    size_t stored_size;
    uint8_t codec, filter;
    int failed;
} piece;

/* Byte j of record r goes to plane j: out[j * R + r] = in[r * rec + j]; a tail shorter
 * than a record stays as it is, after the planes. */
static void planes(const unsigned char *in, size_t n, size_t rec, unsigned char *out)
{
    size_t rows = n / rec;
    for (size_t j = 0; j < rec; j++)
        for (size_t r = 0; r < rows; r++)
            out[j * rows + r] = in[r * rec + j];
    memcpy(out + rows * rec, in + rows * rec, n - rows * rec);
}

static void unplanes(const unsigned char *in, size_t n, size_t rec, unsigned char *out)
{
    size_t rows = n / rec;
    for (size_t j = 0; j < rec; j++)
        for (size_t r = 0; r < rows; r++)
            out[r * rec + j] = in[j * rows + r];
    memcpy(out + rows * rec, in + rows * rec, n - rows * rec);
}

/* Per column of u32 words (rec / 4 columns): each word minus the one a record before it,
 * modulo 2^32, over the whole records; in place. */
static void differences(unsigned char *p, size_t n, size_t rec)
{
    size_t words = n / rec * rec / 4, c = rec / 4;
    for (size_t i = words; i-- > c;)
        sl_put_u32(p + 4 * i, sl_get_u32(p + 4 * i) - sl_get_u32(p + 4 * (i - c)));
}

static void sums(unsigned char *p, size_t n, size_t rec)
{
    size_t words = n / rec * rec / 4, c = rec / 4;
    for (size_t i = c; i < words; i++)
        sl_put_u32(p + 4 * i, sl_get_u32(p + 4 * i) + sl_get_u32(p + 4 * (i - c)));
}

static int filter_fits(int filter, size_t record)
{
    if (filter == FILTER_PLANES)
        return record >= 2;
    if (filter == FILTER_DIFF)
        return record >= 4 && record % 4 == 0;
    return 1;
}

/* `in` filtered into `out` (n bytes each). */
static void apply(int filter, const unsigned char *in, size_t n, size_t rec, unsigned char *out,
                  unsigned char *scratch)
{
    if (filter == FILTER_NONE) {
        memcpy(out, in, n);
    } else if (filter == FILTER_PLANES) {
        planes(in, n, rec, out);
    } else {
        memcpy(scratch, in, n);
        differences(scratch, n, rec);
        planes(scratch, n, rec, out);
    }
}

/* Tries each filter at a fast level, then stores the smallest at SL_PACK_LEVEL (or the
 * plain bytes when zstd does not make them smaller). */
static void pack_piece(piece *p)
{
    size_t n = p->size, bound = ZSTD_compressBound(n);
    unsigned char *filtered = malloc(n ? n : 1), *scratch = malloc(n ? n : 1);
    unsigned char *frame = malloc(bound);
    if (!filtered || !scratch || !frame) {
        p->failed = 1;
        goto done;
    }
    int best = FILTER_NONE;
    size_t best_size = (size_t)-1;
    for (int f = FILTER_NONE; f <= FILTER_DIFF && n >= 64; f++) {
        if (!filter_fits(f, p->record))
            continue;
        apply(f, p->data, n, p->record, filtered, scratch);
        size_t s = ZSTD_compress(frame, bound, filtered, n, TRIAL_LEVEL);
        if (!ZSTD_isError(s) && s < best_size) {
            best_size = s;
            best = f;
        }
    }
    apply(best, p->data, n, p->record, filtered, scratch);
    size_t s = ZSTD_compress(frame, bound, filtered, n, SL_PACK_LEVEL);
    if (ZSTD_isError(s)) {
        p->failed = 1;
    } else if (s < n) {
        p->codec = CODEC_ZSTD;
        p->filter = (uint8_t)best;
        p->stored = frame;
        p->stored_size = s;
        frame = NULL;
    } else {
        p->codec = CODEC_COPY;
        p->filter = FILTER_NONE;
        memcpy(filtered, p->data, n);
        p->stored = filtered;
        p->stored_size = n;
        filtered = NULL;
    }
done:
    free(filtered);
    free(scratch);
    free(frame);
}

int sl_pack(const sl_pack_part *parts, int part_count, void **out, size_t *out_size)
{
    *out = NULL;
    *out_size = 0;
    size_t count = 0;
    for (int i = 0; i < part_count; i++) {
        size_t rec = parts[i].record, step = rec ? SL_PACK_PIECE / rec * rec : SL_PACK_PIECE;
        count += (parts[i].size + step - 1) / step;
    }
    piece *pieces = calloc(count ? count : 1, sizeof *pieces);
    if (!pieces)
        return -1;
    size_t k = 0;
    for (int i = 0; i < part_count; i++) {
        size_t rec = parts[i].record, step = rec ? SL_PACK_PIECE / rec * rec : SL_PACK_PIECE;
        for (size_t at = 0; at < parts[i].size; at += step, k++) {
            pieces[k].data = (const unsigned char *)parts[i].data + at;
            pieces[k].size = parts[i].size - at < step ? parts[i].size - at : step;
            pieces[k].record = parts[i].record;
        }
    }
    int failed = 0;
#pragma omp parallel for schedule(dynamic, 1)
    for (size_t i = 0; i < count; i++)
        pack_piece(&pieces[i]);
    size_t total = HEAD + SL_PACK_TABLE_ENTRY * count;
    for (size_t i = 0; i < count; i++) {
        failed |= pieces[i].failed;
        total += pieces[i].stored_size;
    }
    unsigned char *buf = failed || count > UINT32_MAX ? NULL : malloc(total);
    if (buf) {
        sl_put_u32(buf, SL_PACK_MAGIC);
        sl_put_u32(buf + 4, (uint32_t)count);
        unsigned char *e = buf + HEAD, *data = buf + HEAD + SL_PACK_TABLE_ENTRY * count;
        for (size_t i = 0; i < count; i++, e += SL_PACK_TABLE_ENTRY) {
            sl_put_u64(e, pieces[i].size);
            sl_put_u64(e + 8, pieces[i].stored_size);
            e[16] = pieces[i].codec;
            e[17] = pieces[i].filter;
            e[18] = (unsigned char)(pieces[i].record & 0xff);
            e[19] = (unsigned char)(pieces[i].record >> 8);
            sl_put_u32(e + 20, 0);
            memcpy(data, pieces[i].stored, pieces[i].stored_size);
            data += pieces[i].stored_size;
        }
        *out = buf;
        *out_size = total;
    }
    for (size_t i = 0; i < count; i++)
        free(pieces[i].stored);
    free(pieces);
    return buf ? 0 : -1;
}

int sl_pack_is_packed(const void *body, uint64_t size)
{
    return size >= 4 && sl_get_u32(body) == SL_PACK_MAGIC;
}

static int corrupt(sl_error *err, const char *name, uint64_t piece_index, const char *what)
{
    return sl_error_set(err, SL_E_CORRUPT, 0, name, "invalid packed body: piece %llu: %s",
                        (unsigned long long)piece_index, what);
}

/* One piece into `dest` (plain bytes); 0 or a message. */
static const char *unpack_piece(const unsigned char *e, const unsigned char *src,
                                unsigned char *dest)
{
    uint64_t plain = sl_get_u64(e), stored = sl_get_u64(e + 8);
    size_t rec = (size_t)e[18] | (size_t)e[19] << 8;
    int codec = e[16], filter = e[17];
    unsigned char *tmp = filter == FILTER_NONE ? dest : malloc(plain ? plain : 1);
    if (!tmp)
        return "out of memory";
    const char *why = NULL;
    if (codec == CODEC_COPY) {
        memcpy(tmp, src, plain);
    } else {
        size_t got = ZSTD_decompress(tmp, plain, src, stored);
        if (ZSTD_isError(got))
            why = "damaged zstd frame";
        else if (got != plain)
            why = "frame holds fewer bytes than it declares";
    }
    if (!why && filter == FILTER_PLANES) {
        unplanes(tmp, plain, rec, dest);
    } else if (!why && filter == FILTER_DIFF) {
        unplanes(tmp, plain, rec, dest);
        sums(dest, plain, rec);
    }
    if (tmp != dest)
        free(tmp);
    return why;
}

int sl_unpack(const void *body, uint64_t size, uint64_t limit, const char *name, void **plain,
              uint64_t *plain_size, sl_error *err)
{
    const unsigned char *b = body;
    *plain = NULL;
    *plain_size = 0;
    if (size < HEAD || sl_get_u32(b) != SL_PACK_MAGIC)
        return sl_error_set(err, SL_E_CORRUPT, 0, name, "invalid packed body: no header");
    uint64_t count = sl_get_u32(b + 4);
    if (count > (size - HEAD) / SL_PACK_TABLE_ENTRY)
        return sl_error_set(err, SL_E_CORRUPT, 0, name,
                            "invalid packed body: %llu pieces do not fit in %llu bytes",
                            (unsigned long long)count, (unsigned long long)size);
    uint64_t data_at = HEAD + SL_PACK_TABLE_ENTRY * count, left = size - data_at, total = 0;
    uint64_t *offset = malloc((count ? count : 1) * sizeof *offset);
    uint64_t *out_at = malloc((count ? count : 1) * sizeof *out_at);
    int rc = offset && out_at ? 0 : sl_error_set(err, SL_E_NOMEM, ENOMEM, name, "out of memory");
    for (uint64_t i = 0, at = data_at; i < count && !rc; i++) {
        const unsigned char *e = b + HEAD + SL_PACK_TABLE_ENTRY * i;
        uint64_t p = sl_get_u64(e), s = sl_get_u64(e + 8);
        size_t rec = (size_t)e[18] | (size_t)e[19] << 8;
        if (e[16] > CODEC_ZSTD || e[17] > FILTER_DIFF || sl_get_u32(e + 20) != 0 ||
            rec > MAX_RECORD || !filter_fits(e[17], rec))
            rc = corrupt(err, name, i, "unknown codec, filter or record size");
        else if (s > left)
            rc = corrupt(err, name, i, "stored size beyond the bytes present");
        else if (p > SL_PACK_PIECE || (e[16] == CODEC_COPY ? p != s : p > s * SL_PACK_MAX_RATIO))
            rc = corrupt(err, name, i, "plain size out of range");
        else if (e[16] == CODEC_ZSTD &&
                 (ZSTD_findFrameCompressedSize(b + at, s) != s ||
                  ZSTD_getFrameContentSize(b + at, s) != p))
            rc = corrupt(err, name, i, "frame sizes disagree with the table");
        offset[i] = at;
        out_at[i] = total;
        at += s;
        left -= rc ? 0 : s;
        total += p;
        if (!rc && total > limit)
            rc = sl_error_set(err, SL_E_LIMIT, 0, name,
                              "packed body declares more than %llu plain bytes",
                              (unsigned long long)limit);
    }
    if (!rc && left != 0)
        rc = sl_error_set(err, SL_E_CORRUPT, 0, name,
                          "invalid packed body: %llu bytes after the last piece",
                          (unsigned long long)left);
    unsigned char *out = rc ? NULL : malloc(total ? total : 1);
    if (!rc && !out)
        rc = sl_error_set(err, SL_E_NOMEM, ENOMEM, name, "out of memory");
    const char **why = rc ? NULL : calloc(count ? count : 1, sizeof *why);
    if (!rc && !why)
        rc = sl_error_set(err, SL_E_NOMEM, ENOMEM, name, "out of memory");
    if (!rc) {
#pragma omp parallel for schedule(dynamic, 1)
        for (uint64_t i = 0; i < count; i++)
            why[i] = unpack_piece(b + HEAD + SL_PACK_TABLE_ENTRY * i, b + offset[i],
                                  out + out_at[i]);
        for (uint64_t i = 0; i < count && !rc; i++)
            if (why[i])
                rc = strcmp(why[i], "out of memory")
                         ? corrupt(err, name, i, why[i])
                         : sl_error_set(err, SL_E_NOMEM, ENOMEM, name, "out of memory");
    }
    free((void *)why);
    free(offset);
    free(out_at);
    if (rc) {
        free(out);
        return rc;
    }
    *plain = out;
    *plain_size = total;
    return 0;
}
