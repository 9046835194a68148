/* Parts: one item's stage split into work items (docs/engine.md, "Parts").
 *
 * A stage that declares `run_part` can have its work for a large item cut into parts,
 * each a ticket of the stage's own queue (`TICKET#part-0003`), claimed under a lease, run
 * in its own child process into its own artifact folder and committed with its own
 * record, exactly like an item: so `scanlod worker` processes on many nodes share one
 * scan, and a worker killed mid-part costs that part alone. The item's own ticket of the
 * stage (the join: `run`, which reads every part's artifacts) is enqueued only when
 * every part is committed; until then the parts' ready and claimed tickets are what
 * keeps the item unfinished (docs/engine.md, "When a run is finished"). A part's key is
 * the stage key chained with (part, parts), so a changed input, config or [queue] part_mb
 * makes old parts stale. The join's key is the stage key: parts are scheduling, and the
 * joined result is byte-identical to the unsplit stage's.
 *
 * A split is a property of the item's current config: reconciliation removes the parts
 * of any other (a changed part_mb left them in the work folder for good, issue 34 item
 * 4), and once the stage is committed, every part. Two exceptions keep workers whose
 * part_mb differ from undoing each other's split, and keep finished work: a split that a
 * live worker is running (it holds a claim on one of its parts, whose tickets say how
 * many parts it has), or whose parts are all committed, is the item's until it is joined,
 * and every worker runs its parts and its join (byte-identical whatever the split). Parts
 * are removed from the top down and never below one a live worker holds, so the parts on
 * disk are always 0..k: finding them is a walk up to the first index with neither ticket
 * nor folder.
 */
#include "pipeline/engine_internal.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "core/atomicfile.h"
#include "core/dirs.h"

int sl_engine_parts(const sl_engine *e, int s, const char *source_rel)
{
    if (!e->stages[s]->run_part || e->part_mb <= 0)
        return 0;
    char source[PATH_MAX];
    struct stat st;
    if (sl_engine_path(source, sizeof source, "%s/%s", e->input, source_rel) ||
        stat(source, &st) != 0 || st.st_size <= 0)
        return 0; /* the stage itself reports what is wrong with the input */
    double part_bytes = e->part_mb * 1048576.0;
    double whole = ceil((double)st.st_size / (part_bytes > 1 ? part_bytes : 1));
    uint64_t parts = whole < SL_PARTS_MAX ? (uint64_t)whole : SL_PARTS_MAX;
    return parts > 1 ? (int)parts : 0;
}

int sl_engine_stage_parts(const sl_engine *e, const char *stage, const char *source_rel)
{
    for (int s = 0; s < e->stage_count; s++)
        if (strcmp(e->stages[s]->name, stage) == 0)
            return sl_engine_parts(e, s, source_rel);
    return 0;
}

int sl_part_name(const char *ticket, int part, char *out, size_t size)
{
    int n = snprintf(out, size, "%s" SL_PART_SUFFIX "%04d", ticket, part);
    return n < 0 || (size_t)n >= size;
}

int sl_part_parse(const char *name, char *ticket, size_t size, int *part)
{
    const char *at = strstr(name, SL_PART_SUFFIX), *next;
    while (at && (next = strstr(at + 1, SL_PART_SUFFIX)))
        at = next;
    if (!at)
        return 0;
    const char *digits = at + strlen(SL_PART_SUFFIX);
    char *end;
    long p = strtol(digits, &end, 10);
    if (end == digits || *end || p < 0 || p >= SL_PARTS_MAX || (size_t)(at - name) >= size)
        return 0; /* item tickets end in ".ply" or a hash: never in a part suffix */
    memcpy(ticket, name, (size_t)(at - name));
    ticket[at - name] = '\0';
    *part = (int)p;
    return 1;
}

sl_hash sl_part_key(sl_hash stage_key, int part, int parts)
{
    struct {
        sl_hash key;
        int32_t part, parts;
        char tag[8];
    } in;
    memset(&in, 0, sizeof in);
    in.key = stage_key;
    in.part = part;
    in.parts = parts;
    memcpy(in.tag, "part", 4);
    return sl_hash_bytes(&in, sizeof in);
}

int sl_engine_part_committed(const sl_engine *e, int s, const char *part_name, sl_hash key)
{
    char dir[PATH_MAX], record[PATH_MAX];
    if (sl_artifact_dir(e, s, part_name, dir, sizeof dir) ||
        sl_engine_path(record, sizeof record, "%s/%s", dir, SL_RECORD_FILE))
        return 0;
    sl_error ignored;
    sl_error_init(&ignored);
    return sl_record_check(record, dir, &key, NULL, &ignored) == 0;
}

/* Whether a live worker (this one too) holds a claim on ticket `name` of stage s. */
static int held_live(const sl_engine *e, int s, const char *name)
{
    sl_ticket t;
    return sl_queue_get(e->work, e->stages[s]->name, SL_STATE_CLAIMED, name, &t) == 0 &&
           !sl_lease_owner_gone(e, &t, (int64_t)sl_now_seconds());
}

/* Whether split `parts` of the item's stage s is running (a live worker holds one of its
 * parts, `exclude` aside) or complete (every part committed under stage key `key`). */
static int split_in_use(const sl_engine *e, int s, const char *ticket, int parts, sl_hash key,
                        const char *exclude)
{
    char name[PATH_MAX];
    int committed = 0;
    for (int p = 0; p < parts; p++) {
        if (sl_part_name(ticket, p, name, sizeof name))
            return 0;
        if (strcmp(name, exclude ? exclude : "") && held_live(e, s, name))
            return 1;
        committed += sl_engine_part_committed(e, s, name, sl_part_key(key, p, parts));
    }
    return committed == parts;
}

int sl_engine_item_parts(const sl_engine *e, int s, const char *ticket, const char *source_rel,
                         sl_hash key, const char *exclude)
{
    int config = sl_engine_parts(e, s, source_rel);
    char name[PATH_MAX];
    sl_ticket first;
    int state;
    if (!e->stages[s]->run_part || sl_part_name(ticket, 0, name, sizeof name) ||
        (state = sl_queue_find(e->work, e->stages[s]->name, name)) == SL_STATE_NONE ||
        sl_queue_get(e->work, e->stages[s]->name, state, name, &first) != 0)
        return config;
    int other = first.parts;
    if (other < 2 || other > SL_PARTS_MAX || other == config)
        return config;
    return split_in_use(e, s, ticket, other, key, exclude) ? other : config;
}

/* Whether part p of the item's stage s has a ticket in any state or an artifact folder. */
static int part_exists(const sl_engine *e, int s, const char *ticket, int p)
{
    char name[PATH_MAX], dir[PATH_MAX];
    struct stat st;
    if (sl_part_name(ticket, p, name, sizeof name) || sl_artifact_dir(e, s, name, dir, sizeof dir))
        return 0;
    return sl_queue_find(e->work, e->stages[s]->name, name) != SL_STATE_NONE ||
           stat(dir, &st) == 0;
}

void sl_engine_parts_prune(sl_engine *e, int s, const char *ticket, int from, int at_least)
{
    if (!e->stages[s]->run_part)
        return;
    int top = from > at_least ? from : at_least;
    while (top < SL_PARTS_MAX && part_exists(e, s, ticket, top))
        top++;
    for (int p = top - 1; p >= from; p--) {
        char name[PATH_MAX], dir[PATH_MAX], path[PATH_MAX];
        if (sl_part_name(ticket, p, name, sizeof name) ||
            sl_artifact_dir(e, s, name, dir, sizeof dir) || held_live(e, s, name))
            break; /* its owner commits it, then removes it and what is left below */
        sl_error ignored;
        sl_error_init(&ignored);
        sl_remove_tree(dir, 0, &ignored);
        for (int state = 0; state < SL_STATE_COUNT; state++)
            if (sl_queue_path(path, sizeof path, e->work, e->stages[s]->name, state, name) == 0)
                unlink(path);
    }
}

void sl_engine_part_drop(sl_engine *e, int s, const char *ticket, int part, int parts)
{
    char name[PATH_MAX];
    sl_error ignored;
    sl_error_init(&ignored);
    if (sl_part_name(ticket, part, name, sizeof name))
        return;
    if (part < parts) { /* one of the split's indices: reconciliation rewrites it */
        sl_queue_move(e->work, e->stages[s]->name, name, SL_STATE_CLAIMED, SL_STATE_READY,
                      &ignored);
        return;
    }
    /* Above the split: what is above it goes first, then it (no gap below a part). */
    sl_engine_parts_prune(e, s, ticket, part + 1, 0);
    char dir[PATH_MAX], path[PATH_MAX];
    if (sl_artifact_dir(e, s, name, dir, sizeof dir) == 0)
        sl_remove_tree(dir, 0, &ignored);
    if (sl_queue_path(path, sizeof path, e->work, e->stages[s]->name, SL_STATE_CLAIMED, name) == 0)
        unlink(path);
}

int sl_engine_parts_ready(const sl_engine *e, int s, const char *ticket, int part, int parts,
                          sl_hash *key)
{
    if (part >= 0) {
        if (part >= parts)
            return 0; /* left from another split ([queue] part_mb or the input changed) */
        *key = sl_part_key(*key, part, parts);
        return 1;
    }
    for (int p = 0; p < parts && parts > 1; p++) {
        char name[PATH_MAX];
        if (sl_part_name(ticket, p, name, sizeof name) ||
            !sl_engine_part_committed(e, s, name, sl_part_key(*key, p, parts)))
            return 0;
    }
    return 1;
}

char **sl_engine_part_dirs(const sl_engine *e, int s, const char *ticket, int parts)
{
    char **dirs = malloc((size_t)parts * (sizeof *dirs + PATH_MAX));
    if (!dirs)
        return NULL;
    char *text = (char *)(dirs + parts);
    for (int p = 0; p < parts; p++) {
        char name[PATH_MAX];
        dirs[p] = text + (size_t)p * PATH_MAX;
        dirs[p][0] = '\0';
        if (sl_part_name(ticket, p, name, sizeof name) == 0)
            sl_artifact_dir(e, s, name, dirs[p], PATH_MAX);
    }
    return dirs;
}

char *sl_engine_parts_stats(const sl_engine *e, int s, const char *name, int parts,
                            const char *head, size_t head_size)
{
    char *text = NULL;
    int listed = 0;
    size_t size = 0;
    FILE *f = open_memstream(&text, &size);
    if (!f)
        return NULL;
    fwrite(head, 1, head_size, f);
    for (int p = 0; p < parts && parts > 1; p++) {
        char part_name[PATH_MAX], dir[PATH_MAX], path[PATH_MAX], *stats = NULL;
        size_t n = 0;
        sl_error ignored;
        sl_error_init(&ignored);
        if (sl_part_name(name, p, part_name, sizeof part_name) ||
            sl_artifact_dir(e, s, part_name, dir, sizeof dir) ||
            sl_engine_path(path, sizeof path, "%s/_stats.json", dir) ||
            sl_read_file(path, 1 << 16, &stats, &n, &ignored) != 0)
            continue; /* diagnostics: a part without them is left out */
        while (n > 0 && (stats[n - 1] == '\n' || stats[n - 1] == ' '))
            n--;
        fputs(listed++ == 0 ? ",\"parts\":[" : ",", f);
        fwrite(stats, 1, n, f);
        free(stats);
    }
    if (listed > 0)
        fputc(']', f);
    fputs("}\n", f);
    if (fclose(f) != 0) {
        free(text);
        return NULL;
    }
    return text;
}
