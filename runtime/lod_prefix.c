/* Cutting a model file by prefixes (lod_prefix.h). */
#include "runtime/lod_prefix.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "core/artifact.h"
#include "runtime/lod_io.h"
#include "runtime/lod_order.h"
#include "runtime/lod_pack.h"
#include "runtime/octree_io.h"

#define PLAIN_LIMIT ((uint64_t)1 << 40)

/* What has been unpacked of one section: its first `have` bytes (whole pieces). */
typedef struct section_cache {
    unsigned char *data;
    uint64_t have;
    uint64_t next_piece;
} section_cache;

struct sl_lod_file {
    char *path;
    int fd;
    int ordered; /* format 5; else `cut` is the whole model, read at opening */
    sl_pack_index ix;
    sl_octree head;
    sl_octree_layout layout;
    sl_lod_sections sec;
    uint64_t first_piece[SL_SEC_COUNT];
    section_cache cache[SL_SEC_COUNT];
    sl_lod_model levels;
    float bounds[6];
    sl_lod_model cut;
    int have_cut;
    uint32_t reached;
};

/* Pieces first .. first + count - 1 unpacked into dest: their stored bytes are one
 * stretch of the file. */
static int unpack_pieces(sl_lod_file *f, uint64_t first, uint64_t count, unsigned char *dest,
                         sl_error *err)
{
    if (!count)
        return 0;
    const sl_pack_piece_info *a = &f->ix.pieces[first], *b = &f->ix.pieces[first + count - 1];
    uint64_t span = b->stored_at + b->stored_size - a->stored_at;
    unsigned char *stored = malloc(span ? span : 1);
    const unsigned char **at = malloc(count * sizeof *at);
    int rc = stored && at ? 0 : sl_error_nomem(err, f->path, "out of memory");
    if (!rc)
        rc = sl_artifact_pread(f->fd, f->path, stored, span, a->stored_at, err);
    for (uint64_t i = 0; !rc && i < count; i++)
        at[i] = stored + (f->ix.pieces[first + i].stored_at - a->stored_at);
    if (!rc)
        rc = sl_pack_pieces_read(&f->ix, first, count, at, dest, f->path, err);
    free(stored);
    free((void *)at);
    return rc;
}

/* Index of the piece starting at plain offset `at`, or ix.count when none does. */
static uint64_t piece_at(const sl_pack_index *ix, uint64_t at)
{
    uint64_t lo = 0, hi = ix->count;
    while (lo < hi) {
        uint64_t mid = lo + (hi - lo) / 2;
        if (ix->pieces[mid].plain_at < at)
            lo = mid + 1;
        else
            hi = mid;
    }
    return lo < ix->count && ix->pieces[lo].plain_at == at ? lo : ix->count;
}

/* The first `bytes` of section s unpacked into its cache (whole pieces: maybe more). */
static int ensure(sl_lod_file *f, int s, uint64_t bytes, sl_error *err)
{
    section_cache *c = &f->cache[s];
    if (bytes > f->sec.size[s])
        return sl_lod_corrupt(err, f->path, "a prefix beyond its section");
    if (c->have >= bytes)
        return 0;
    uint64_t first = c->next_piece, last = first, got = c->have;
    while (got < bytes) /* the section's pieces tile it (checked at opening) */
        got += f->ix.pieces[last++].plain_size;
    unsigned char *grown = realloc(c->data, got ? got : 1);
    if (!grown)
        return sl_error_nomem(err, f->path, "out of memory");
    c->data = grown;
    int rc = unpack_pieces(f, first, last - first, c->data + c->have, err);
    if (rc)
        return rc;
    c->have = got;
    c->next_piece = last;
    return 0;
}

static void drop_caches(sl_lod_file *f)
{
    for (int s = 0; s < SL_SEC_COUNT; s++) {
        free(f->cache[s].data);
        f->cache[s].data = NULL;
        f->cache[s].have = 0;
        f->cache[s].next_piece = f->first_piece[s];
    }
}

/* The whole section s, its buffer handed over (NULL on error). */
static void *take_section(sl_lod_file *f, int s, sl_error *err)
{
    if (ensure(f, s, f->sec.size[s], err))
        return NULL;
    void *p = f->cache[s].data ? f->cache[s].data : malloc(1);
    f->cache[s].data = NULL;
    f->cache[s].have = 0;
    f->cache[s].next_piece = f->first_piece[s];
    if (!p)
        sl_error_nomem(err, f->path, "out of memory");
    return p;
}

/* The head and table, the octree and LOD headers, the sections' places. */
static int open_ordered(sl_lod_file *f, uint64_t body_size, sl_error *err)
{
    unsigned char head[8], octree_header[SL_OCTREE_HEADER_SIZE], lod_header[SL_LOD_ORDER_HEADER];
    int rc = body_size < 8 ? sl_lod_corrupt(err, f->path, "truncated packed body")
                           : sl_artifact_pread(f->fd, f->path, head, 8, 0, err);
    if (rc)
        return rc;
    if (sl_get_u32(head) != SL_PACK_MAGIC_CHECKED)
        return sl_lod_corrupt(err, f->path, "format 5 without checked pieces");
    uint64_t table_size = sl_pack_table_size(head);
    if (table_size > body_size)
        return sl_error_set(err, SL_E_CORRUPT, 0, f->path,
                            "invalid packed body: %llu pieces do not fit in %llu bytes",
                            (unsigned long long)sl_get_u32(head + 4),
                            (unsigned long long)body_size);
    unsigned char *table = malloc(table_size);
    if (!table)
        return sl_error_nomem(err, f->path, "out of memory");
    rc = sl_artifact_pread(f->fd, f->path, table, table_size, 0, err);
    if (!rc)
        rc = sl_pack_index_parse(table, table_size, body_size, PLAIN_LIMIT, f->path, &f->ix, err);
    free(table);
    if (rc)
        return rc;
    /* The octree header is the first piece, the LOD header the one at the octree's end. */
    const sl_pack_index *ix = &f->ix;
    if (!ix->count || ix->pieces[0].plain_size != SL_OCTREE_HEADER_SIZE)
        return sl_lod_corrupt(err, f->path, "no octree header piece");
    rc = unpack_pieces(f, 0, 1, octree_header, err);
    if (!rc)
        rc = sl_octree_parse_header(octree_header, sizeof octree_header, f->path, &f->head,
                                    &f->layout, err);
    if (rc)
        return rc;
    uint64_t lod_piece = piece_at(ix, sl_lod_order_octree_size(&f->layout, f->head.node_count));
    if (lod_piece == ix->count || ix->pieces[lod_piece].plain_size != SL_LOD_ORDER_HEADER)
        return sl_lod_corrupt(err, f->path, "no LOD header piece");
    rc = unpack_pieces(f, lod_piece, 1, lod_header, err);
    if (!rc)
        rc = sl_lod_order_sections(&f->head, &f->layout, lod_header, ix->plain_total, f->path,
                                   &f->sec, err);
    for (int s = 0; !rc && s < SL_SEC_COUNT; s++) {
        f->first_piece[s] = f->sec.size[s] ? piece_at(ix, f->sec.at[s]) : ix->count;
        if (f->sec.size[s] && f->first_piece[s] == ix->count)
            rc = sl_lod_corrupt(err, f->path, "a section that does not start a piece");
        f->cache[s].next_piece = f->first_piece[s];
    }
    return rc;
}

/* The whole model's level tables, checked as the whole model's reader checks them. */
static int read_levels(sl_lod_file *f, sl_error *err)
{
    sl_lod_model *l = &f->levels;
    uint32_t e = f->sec.expansions;
    l->expansion_count = e;
    l->accumulation = take_section(f, SL_SEC_ACCUMULATION, err);
    l->error_after = l->accumulation ? take_section(f, SL_SEC_ERROR_AFTER, err) : NULL;
    l->surface_before = l->error_after ? take_section(f, SL_SEC_SURFACE, err) : NULL;
    if (!l->surface_before)
        return err->code ? err->code : sl_error_nomem(err, f->path, "out of memory");
    if (l->surface_before[0] != 0)
        return sl_lod_corrupt(err, f->path, "surface counts out of order");
    for (uint32_t i = 0; i <= e; i++) {
        if (l->accumulation[i] > (uint64_t)SL_MC_MAX_TRIANGLES * (1 + 7 * (uint64_t)i))
            return sl_lod_corrupt(err, f->path, "accumulation table out of range");
        if (!isfinite(l->error_after[i]))
            return sl_lod_corrupt(err, f->path, "non-finite error");
        if (i && l->surface_before[i] - l->surface_before[i - 1] > 1)
            return sl_lod_corrupt(err, f->path, "surface counts out of order");
    }
    memcpy(f->bounds, f->sec.bounds, sizeof f->bounds);
    return 0;
}

int sl_lod_file_open(const char *path, sl_lod_file **out, sl_error *err)
{
    *out = NULL;
    sl_lod_file *f = calloc(1, sizeof *f);
    char *name = strdup(path);
    if (!f || !name) {
        free(f);
        free(name);
        return sl_error_set(err, SL_E_NOMEM, ENOMEM, path, "out of memory");
    }
    f->path = name;
    f->fd = -1;
    sl_lod_model_init(&f->levels);
    sl_lod_model_init(&f->cut);
    sl_artifact_info info;
    int rc = sl_artifact_open(path, SL_LOD_MAGIC, SL_LOD_OLDEST_VERSION, SL_LOD_FORMAT_VERSION,
                              &f->fd, &info, err);
    if (rc == 0 && info.version < 5) { /* read whole, as before */
        close(f->fd);
        f->fd = -1;
        rc = sl_lod_model_open(path, &f->cut, err);
        if (rc == 0) {
            f->have_cut = 1;
            f->reached = f->cut.expansion_count;
            sl_octree_crossing_bounds(&f->cut.tree, f->bounds, f->bounds + 3);
        }
    } else if (rc == 0) {
        f->ordered = 1;
        rc = open_ordered(f, info.body_size, err);
        if (rc == 0)
            rc = read_levels(f, err);
    }
    if (rc) {
        sl_lod_file_close(f);
        return rc;
    }
    *out = f;
    return 0;
}

void sl_lod_file_close(sl_lod_file *f)
{
    if (!f)
        return;
    if (f->fd >= 0)
        close(f->fd);
    drop_caches(f);
    sl_pack_index_release(&f->ix);
    sl_lod_model_release(&f->levels);
    sl_lod_model_release(&f->cut);
    free(f->path);
    free(f);
}

const sl_lod_model *sl_lod_file_levels(const sl_lod_file *f)
{
    return f->ordered ? &f->levels : &f->cut;
}

void sl_lod_file_bounds(const sl_lod_file *f, float min[3], float max[3])
{
    memcpy(min, f->bounds, 3 * sizeof *min);
    memcpy(max, f->bounds + 3, 3 * sizeof *max);
}

uint32_t sl_lod_file_reached(const sl_lod_file *f)
{
    return f->have_cut ? f->reached : 0;
}

/* How many node positions the first k expansions reach, from the LOD array and the nodes'
 * child masks (each expanded node already reached, its children the next positions). */
static int reached_nodes(sl_lod_file *f, uint32_t k, uint32_t *nodes, sl_error *err)
{
    uint64_t n = f->sec.nodes, bound = 1 + 8 * (uint64_t)k;
    if (bound > n)
        bound = n;
    int rc = ensure(f, SL_SEC_LOD_ARRAY, 4 * (uint64_t)k, err);
    if (!rc)
        rc = ensure(f, SL_SEC_NODES, bound * SL_LOD_ORDER_NODE, err);
    if (rc)
        return rc;
    const uint32_t *lod = (const uint32_t *)f->cache[SL_SEC_LOD_ARRAY].data;
    const uint8_t *node = f->cache[SL_SEC_NODES].data;
    uint64_t reached = 1;
    for (uint32_t i = 0; i < k; i++) {
        if (lod[i] >= reached)
            return sl_lod_corrupt(err, f->path, "the LOD array is not an expansion order");
        reached += (uint64_t)__builtin_popcount(node[SL_LOD_ORDER_NODE * (size_t)lod[i] + 1]);
        if (reached > bound)
            return sl_lod_corrupt(err, f->path, "nodes in LOD order are not one tree");
    }
    *nodes = (uint32_t)reached;
    return 0;
}

/* The prefix of the per-node pools the first raw->nodes positions name, read into raw
 * (their ids as stored: sl_lod_raw_build decodes them). */
static int read_pools(sl_lod_file *f, sl_lod_raw *raw, sl_error *err)
{
    uint32_t nodes = raw->nodes;
    uint64_t ids = 0, words = 0, crossings = 0;
    for (uint32_t p = 0; p < nodes; p++)
        ids += (uint64_t)__builtin_popcount(sl_octree_edge_mask(raw->node[SL_LOD_ORDER_NODE * (size_t)p]));
    if (ids > f->head.node_crossing_count)
        return sl_lod_corrupt(err, f->path, "crossing ids beyond their table");
    int rc = ensure(f, SL_SEC_IDS, 4 * ids, err);
    if (!rc)
        rc = ensure(f, SL_SEC_TRANSITION_BASE, 4 * (uint64_t)nodes, err);
    if (rc)
        return rc;
    const uint32_t *base = (const uint32_t *)f->cache[SL_SEC_TRANSITION_BASE].data;
    for (uint32_t p = 0; p < nodes; p++) /* a record's head first, then its length */
        if (base[p] != SL_OCTREE_NONE && (uint64_t)base[p] + 3 > words)
            words = (uint64_t)base[p] + 3;
    if (words > f->sec.words)
        return sl_lod_corrupt(err, f->path, "transition record out of range");
    if ((rc = ensure(f, SL_SEC_TRANSITION_WORDS, 4 * words, err)))
        return rc;
    const uint32_t *w = (const uint32_t *)f->cache[SL_SEC_TRANSITION_WORDS].data;
    uint64_t need = words;
    for (uint32_t p = 0; p < nodes; p++)
        if (base[p] != SL_OCTREE_NONE && (uint64_t)base[p] + sl_transition_record_words(w + base[p]) > need)
            need = (uint64_t)base[p] + sl_transition_record_words(w + base[p]);
    if (need > f->sec.words)
        return sl_lod_corrupt(err, f->path, "transition record out of range");
    if ((rc = ensure(f, SL_SEC_TRANSITION_WORDS, 4 * need, err)))
        return rc;
    const uint32_t *id = (const uint32_t *)f->cache[SL_SEC_IDS].data;
    const uint32_t *words_read = (const uint32_t *)f->cache[SL_SEC_TRANSITION_WORDS].data;
    if (sl_lod_order_count_new(raw->node, nodes, id, ids, base, words_read, need, &crossings) ||
        crossings > f->head.crossing_count)
        return sl_lod_corrupt(err, f->path, "crossing ids out of range");
    rc = ensure(f, SL_SEC_POSITIONS, 12 * crossings, err);
    if (!rc && f->layout.has_color)
        rc = ensure(f, SL_SEC_COLORS, 4 * crossings, err);
    if (rc)
        return rc;
    raw->ids = ids;
    raw->node_crossings = id;
    raw->crossings = (uint32_t)crossings;
    raw->crossing_position = (const float *)f->cache[SL_SEC_POSITIONS].data;
    raw->crossing_color = f->layout.has_color ? f->cache[SL_SEC_COLORS].data : NULL;
    raw->transition_base = base;
    raw->words = need;
    raw->transition_words = words_read;
    return 0;
}

static int read_vertices(sl_lod_file *f, sl_lod_raw *raw, sl_error *err)
{
    if (!f->layout.vertex_first)
        return 0;
    int rc = ensure(f, SL_SEC_VERTEX_FIRST, 4 * ((uint64_t)raw->nodes + 1), err);
    if (rc)
        return rc;
    const uint32_t *first = (const uint32_t *)f->cache[SL_SEC_VERTEX_FIRST].data;
    uint64_t v = first[raw->nodes];
    if (first[0] != 0 || v > f->layout.vertex_count)
        return sl_lod_corrupt(err, f->path, "vertex ranges do not cover the vertex table");
    rc = ensure(f, SL_SEC_VERTICES, 12 * v, err);
    if (!rc && f->layout.has_color)
        rc = ensure(f, SL_SEC_VERTEX_COLORS, 4 * v, err);
    if (rc)
        return rc;
    raw->vertex_first = first;
    raw->vertex_position = (const float *)f->cache[SL_SEC_VERTICES].data;
    raw->vertex_color = f->layout.has_color ? f->cache[SL_SEC_VERTEX_COLORS].data : NULL;
    return 0;
}

static int load_prefix(sl_lod_file *f, uint32_t k, sl_error *err)
{
    sl_lod_raw raw;
    memset(&raw, 0, sizeof raw);
    raw.head = f->head;
    raw.layout = f->layout;
    int rc = reached_nodes(f, k, &raw.nodes, err);
    if (!rc) {
        raw.node = f->cache[SL_SEC_NODES].data;
        memcpy(raw.root, f->sec.root, sizeof raw.root);
        rc = read_pools(f, &raw, err);
    }
    if (!rc)
        rc = read_vertices(f, &raw, err);
    if (!rc) {
        raw.expansions = k;
        raw.lod_array = (const uint32_t *)f->cache[SL_SEC_LOD_ARRAY].data;
        raw.accumulation = f->levels.accumulation;
        raw.error_after = f->levels.error_after;
        raw.surface_before = f->levels.surface_before;
        raw.neighbour_links = f->sec.links;
        sl_lod_model_release(&f->cut);
        f->have_cut = 0;
        rc = sl_lod_raw_build(&raw, 1, f->path, &f->cut, err);
    }
    drop_caches(f);
    if (rc == 0) {
        f->have_cut = 1;
        f->reached = k;
    }
    return rc;
}

int sl_lod_file_reach(sl_lod_file *f, uint32_t k, sl_lod_model **model, sl_error *err)
{
    *model = NULL;
    uint32_t e = sl_lod_file_levels(f)->expansion_count;
    if (k > e)
        k = e;
    if (!f->have_cut || f->reached < k) {
        uint32_t want = f->have_cut && f->reached > e / 2 ? e : 2 * f->reached;
        int rc = load_prefix(f, want > k ? want : k, err);
        if (rc)
            return rc;
    }
    *model = &f->cut;
    return 0;
}
