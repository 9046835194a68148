/* Packed parts (lod_pack.h). */
#include "runtime/lod_pack.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>
#include <xxhash.h>
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

struct sl_packer {
    int checked;
    size_t piece_size;
    piece *pieces;
    size_t count, capacity;
    int failed;
};

sl_packer *sl_packer_new(int checked, size_t piece_size)
{
    sl_packer *pk = calloc(1, sizeof *pk);
    if (pk) {
        pk->checked = checked;
        pk->piece_size = piece_size && piece_size <= SL_PACK_PIECE ? piece_size : SL_PACK_PIECE;
    }
    return pk;
}

void sl_packer_free(sl_packer *pk)
{
    if (!pk)
        return;
    for (size_t i = 0; i < pk->count; i++)
        free(pk->pieces[i].stored);
    free(pk->pieces);
    free(pk);
}

int sl_packer_add(sl_packer *pk, const void *data, size_t size, uint16_t record)
{
    size_t rec = record, step = rec ? pk->piece_size / rec * rec : pk->piece_size;
    size_t count = (size + step - 1) / step;
    if (pk->failed)
        return -1;
    if (pk->count + count > pk->capacity) {
        size_t want = (pk->count + count) * 2;
        piece *grown = realloc(pk->pieces, want * sizeof *grown);
        if (!grown)
            return pk->failed = -1;
        pk->pieces = grown;
        pk->capacity = want;
    }
    piece *first = pk->pieces + pk->count;
    memset(first, 0, count * sizeof *first);
    for (size_t k = 0, at = 0; k < count; k++, at += step) {
        first[k].data = (const unsigned char *)data + at;
        first[k].size = size - at < step ? size - at : step;
        first[k].record = record;
    }
#pragma omp parallel for schedule(dynamic, 1)
    for (size_t i = 0; i < count; i++)
        pack_piece(&first[i]);
    pk->count += count;
    for (size_t i = 0; i < count; i++) {
        pk->failed |= first[i].failed;
        first[i].data = NULL; /* the caller may free its part now */
    }
    return pk->failed ? -1 : 0;
}

int sl_packer_finish(sl_packer *pk, void **out, size_t *out_size)
{
    *out = NULL;
    *out_size = 0;
    size_t count = pk->count, total = HEAD + SL_PACK_TABLE_ENTRY * count;
    for (size_t i = 0; i < count; i++)
        total += pk->pieces[i].stored_size;
    unsigned char *buf = pk->failed || count > UINT32_MAX ? NULL : malloc(total);
    if (buf) {
        sl_put_u32(buf, pk->checked ? SL_PACK_MAGIC_CHECKED : SL_PACK_MAGIC);
        sl_put_u32(buf + 4, (uint32_t)count);
        unsigned char *e = buf + HEAD, *data = buf + HEAD + SL_PACK_TABLE_ENTRY * count;
        for (size_t i = 0; i < count; i++, e += SL_PACK_TABLE_ENTRY) {
            const piece *p = &pk->pieces[i];
            sl_put_u64(e, p->size);
            sl_put_u64(e + 8, p->stored_size);
            e[16] = p->codec;
            e[17] = p->filter;
            e[18] = (unsigned char)(p->record & 0xff);
            e[19] = (unsigned char)(p->record >> 8);
            sl_put_u32(e + 20, pk->checked ? (uint32_t)XXH3_64bits(p->stored, p->stored_size) : 0);
            memcpy(data, p->stored, p->stored_size);
            data += p->stored_size;
        }
        *out = buf;
        *out_size = total;
    }
    sl_packer_free(pk);
    return buf ? 0 : -1;
}

int sl_pack(const sl_pack_part *parts, int part_count, void **out, size_t *out_size)
{
    *out = NULL;
    *out_size = 0;
    sl_packer *pk = sl_packer_new(0, SL_PACK_PIECE);
    if (!pk)
        return -1;
    for (int i = 0; i < part_count; i++)
        if (sl_packer_add(pk, parts[i].data, parts[i].size, parts[i].record)) {
            sl_packer_free(pk);
            return -1;
        }
    return sl_packer_finish(pk, out, out_size);
}

int sl_pack_is_packed(const void *body, uint64_t size)
{
    if (size < 4)
        return 0;
    uint32_t magic = sl_get_u32(body);
    return magic == SL_PACK_MAGIC || magic == SL_PACK_MAGIC_CHECKED;
}

static int corrupt(sl_error *err, const char *name, uint64_t piece_index, const char *what)
{
    return sl_error_set(err, SL_E_CORRUPT, 0, name, "invalid packed body: piece %llu: %s",
                        (unsigned long long)piece_index, what);
}

uint64_t sl_pack_table_size(const unsigned char head[8])
{
    return HEAD + SL_PACK_TABLE_ENTRY * (uint64_t)sl_get_u32(head + 4);
}

void sl_pack_index_release(sl_pack_index *ix)
{
    free(ix->pieces);
    memset(ix, 0, sizeof *ix);
}

int sl_pack_index_parse(const unsigned char *table, uint64_t available, uint64_t body_size,
                        uint64_t limit, const char *name, sl_pack_index *ix, sl_error *err)
{
    memset(ix, 0, sizeof *ix);
    if (available < HEAD || body_size < HEAD || !sl_pack_is_packed(table, available))
        return sl_error_set(err, SL_E_CORRUPT, 0, name, "invalid packed body: no header");
    uint64_t count = sl_get_u32(table + 4);
    if (count > (body_size - HEAD) / SL_PACK_TABLE_ENTRY ||
        available < HEAD + SL_PACK_TABLE_ENTRY * count)
        return sl_error_set(err, SL_E_CORRUPT, 0, name,
                            "invalid packed body: %llu pieces do not fit in %llu bytes",
                            (unsigned long long)count, (unsigned long long)body_size);
    ix->checked = sl_get_u32(table) == SL_PACK_MAGIC_CHECKED;
    ix->pieces = malloc((count ? count : 1) * sizeof *ix->pieces);
    if (!ix->pieces)
        return sl_error_set(err, SL_E_NOMEM, ENOMEM, name, "out of memory");
    ix->count = count;
    uint64_t at = HEAD + SL_PACK_TABLE_ENTRY * count, left = body_size - at, total = 0;
    int rc = 0;
    for (uint64_t i = 0; i < count && !rc; i++) {
        const unsigned char *e = table + HEAD + SL_PACK_TABLE_ENTRY * i;
        uint64_t p = sl_get_u64(e), s = sl_get_u64(e + 8);
        size_t rec = (size_t)e[18] | (size_t)e[19] << 8;
        if (e[16] > CODEC_ZSTD || e[17] > FILTER_DIFF || (!ix->checked && sl_get_u32(e + 20)) ||
            rec > MAX_RECORD || !filter_fits(e[17], rec))
            rc = corrupt(err, name, i, "unknown codec, filter or record size");
        else if (s > left)
            rc = corrupt(err, name, i, "stored size beyond the bytes present");
        else if (p > SL_PACK_PIECE || (e[16] == CODEC_COPY ? p != s : p > s * SL_PACK_MAX_RATIO))
            rc = corrupt(err, name, i, "plain size out of range");
        ix->pieces[i] = (sl_pack_piece_info){total, p, at, s, sl_get_u32(e + 20), (uint16_t)rec,
                                             e[16], e[17]};
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
    if (rc) {
        sl_pack_index_release(ix);
        return rc;
    }
    ix->plain_total = total;
    return 0;
}

/* One piece into `dest` (plain bytes); 0 or a message. */
static const char *unpack_piece(const sl_pack_piece_info *pc, int checked,
                                const unsigned char *src, unsigned char *dest)
{
    uint64_t plain = pc->plain_size, stored = pc->stored_size;
    size_t rec = pc->record;
    if (checked && (uint32_t)XXH3_64bits(src, stored) != pc->check)
        return "checksum mismatch";
    if (pc->codec == CODEC_ZSTD && (ZSTD_findFrameCompressedSize(src, stored) != stored ||
                                    ZSTD_getFrameContentSize(src, stored) != plain))
        return "frame sizes disagree with the table";
    unsigned char *tmp = pc->filter == FILTER_NONE ? dest : malloc(plain ? plain : 1);
    if (!tmp)
        return "out of memory";
    const char *why = NULL;
    if (pc->codec == CODEC_COPY) {
        memcpy(tmp, src, plain);
    } else {
        size_t got = ZSTD_decompress(tmp, plain, src, stored);
        if (ZSTD_isError(got))
            why = "damaged zstd frame";
        else if (got != plain)
            why = "frame holds fewer bytes than it declares";
    }
    if (!why && pc->filter == FILTER_PLANES) {
        unplanes(tmp, plain, rec, dest);
    } else if (!why && pc->filter == FILTER_DIFF) {
        unplanes(tmp, plain, rec, dest);
        sums(dest, plain, rec);
    }
    if (tmp != dest)
        free(tmp);
    return why;
}

static int piece_error(sl_error *err, const char *name, uint64_t i, const char *why)
{
    return strcmp(why, "out of memory") ? corrupt(err, name, i, why)
                                        : sl_error_set(err, SL_E_NOMEM, ENOMEM, name, "out of memory");
}

int sl_pack_pieces_read(const sl_pack_index *ix, uint64_t first, uint64_t count,
                        const unsigned char *const *stored, unsigned char *dest,
                        const char *name, sl_error *err)
{
    const char **why = calloc(count ? count : 1, sizeof *why);
    if (!why)
        return sl_error_set(err, SL_E_NOMEM, ENOMEM, name, "out of memory");
    uint64_t base = count ? ix->pieces[first].plain_at : 0;
#pragma omp parallel for schedule(dynamic, 1) if (count > 1)
    for (uint64_t i = 0; i < count; i++) {
        const sl_pack_piece_info *pc = &ix->pieces[first + i];
        why[i] = unpack_piece(pc, ix->checked, stored[i], dest + (pc->plain_at - base));
    }
    int rc = 0;
    for (uint64_t i = 0; i < count && !rc; i++)
        if (why[i])
            rc = piece_error(err, name, first + i, why[i]);
    free((void *)why);
    return rc;
}

int sl_unpack(const void *body, uint64_t size, uint64_t limit, const char *name, void **plain,
              uint64_t *plain_size, sl_error *err)
{
    const unsigned char *b = body;
    *plain = NULL;
    *plain_size = 0;
    sl_pack_index ix;
    int rc = sl_pack_index_parse(b, size, size, limit, name, &ix, err);
    if (rc)
        return rc;
    unsigned char *out = malloc(ix.plain_total ? ix.plain_total : 1);
    const unsigned char **stored = malloc((ix.count ? ix.count : 1) * sizeof *stored);
    if (!out || !stored)
        rc = sl_error_set(err, SL_E_NOMEM, ENOMEM, name, "out of memory");
    for (uint64_t i = 0; !rc && i < ix.count; i++)
        stored[i] = b + ix.pieces[i].stored_at;
    if (!rc)
        rc = sl_pack_pieces_read(&ix, 0, ix.count, stored, out, name, err);
    free(stored);
    uint64_t total = ix.plain_total;
    sl_pack_index_release(&ix);
    if (rc) {
        free(out);
        return rc;
    }
    *plain = out;
    *plain_size = total;
    return 0;
}
