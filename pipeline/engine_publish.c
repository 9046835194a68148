/* Publication of a finished item under [run] output/ITEM/, atomic per item.
 *
 * The folder is assembled as a hidden sibling (`.NAME.publish.HOST.PID`), every file
 * written durably, then swapped in with one rename (renameat2 RENAME_EXCHANGE when an
 * older folder exists, whose remains are then deleted). A reader sees the old folder or
 * the new one, never a mix. The publish record in WORK/artifacts/_publish/ITEM/ keys the
 * publication on every stage's key, so unchanged items are not rewritten.
 *
 * Published: report.json (deterministic: counts from every stage), the output files of
 * stages marked `publish` (copies, or reflinks where the filesystem shares extents: never
 * hard links, so a file edited in the output cannot change an artifact), and timings.json
 * (wall/CPU time and peak RSS per stage: differs between runs, so it is not in the
 * record).
 *
 * The publication owns the item's folder whole: an entry there that its record does not
 * list (a notes.txt someone added) is moved aside, and so is anything that is not a
 * folder standing where the item's folder belongs (a file, a link). Before, `verify`
 * flagged the first on every run while `run` said "nothing to do", and the second failed
 * every run with "rename failed: Not a directory". Moved aside, never deleted: to
 * OUTPUT/.scanlod-aside/TICKET/NAME (a hidden folder, so never an item's path), one WARN
 * line and a `moved_aside` event each.
 */
#include "pipeline/engine_internal.h"

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "core/atomicfile.h"
#include "core/dirs.h"
#include "core/io.h"
#include "core/json.h"
#include "core/log.h"

static int publish_key(sl_engine *e, const char *ticket, sl_hash *key, sl_error *err)
{
    /* The version names what the engine itself writes into a publication (report.json's
     * shape): bumped when that changes, so every item is published again once. 2: the
     * item id keeps its suffix, report.json names the method. */
    char text[SL_MAX_STAGES * 40 + 32] = "scanlod-publish 2\n";
    for (int s = 0; s < e->stage_count; s++) {
        char dir[PATH_MAX], path[PATH_MAX];
        sl_artifact_dir(e, s, ticket, dir, sizeof dir);
        sl_engine_path(path, sizeof path, "%s/%s", dir, SL_RECORD_FILE);
        sl_record rec;
        int rc = sl_record_read(path, &rec, err);
        if (rc)
            return rc;
        char hex[SL_HASH_HEX_SIZE];
        sl_hash_hex(rec.key, hex);
        strcat(text, hex);
        strcat(text, "\n");
    }
    *key = sl_hash_bytes(text, strlen(text));
    return 0;
}

static void publish_paths(sl_engine *e, const char *item, const char *ticket, char *final_dir,
                          char *record_dir)
{
    sl_engine_path(final_dir, PATH_MAX, "%s/%s", e->output, item);
    sl_engine_path(record_dir, PATH_MAX, "%s/artifacts/_publish/%s", e->work, ticket);
}

int sl_engine_publish_valid(sl_engine *e, const char *item, const char *ticket)
{
    char final_dir[PATH_MAX], record_dir[PATH_MAX], record[PATH_MAX];
    publish_paths(e, item, ticket, final_dir, record_dir);
    sl_engine_path(record, sizeof record, "%s/%s", record_dir, SL_RECORD_FILE);
    sl_hash key;
    sl_error err;
    sl_error_init(&err);
    return publish_key(e, ticket, &key, &err) == 0 &&
           sl_record_check(record, final_dir, &key, NULL, &err) == 0;
}

/* Moves `path` (an entry in or at the item's published folder) to
 * OUTPUT/.scanlod-aside/TICKET/NAME, NAME.1, ... (the first that is free). */
static int move_aside(sl_engine *e, const char *item, const char *path, sl_error *err)
{
    char ticket[SL_TICKET_NAME_MAX + 1], dir[PATH_MAX], to[PATH_MAX];
    int rc = sl_ticket_name(item, ticket, sizeof ticket, err);
    if (rc == 0 && sl_engine_path(dir, sizeof dir, "%s/.scanlod-aside/%s", e->output, ticket))
        rc = sl_error_set(err, SL_E_LIMIT, 0, item, "path too long");
    if (rc == 0)
        rc = sl_mkdirs(dir, err);
    const char *base = strrchr(path, '/') ? strrchr(path, '/') + 1 : path;
    for (int n = 0; rc == 0; n++) {
        if (n > 999 || sl_engine_path(to, sizeof to, n ? "%s/%s.%d" : "%s/%s", dir, base, n))
            return sl_error_set(err, SL_E_LIMIT, 0, path, "no free name to move it aside");
        if (renameat2(AT_FDCWD, path, AT_FDCWD, to, RENAME_NOREPLACE) == 0)
            break;
        if (errno != EEXIST)
            return sl_error_errno(err, errno, path, "moving aside");
    }
    if (rc)
        return rc;
    SL_LOG(SL_LOG_WARN, "publish", item, "moved aside: %s -> %s (not part of the publication)",
           path, to);
    sl_log_event("moved_aside", "publish", item, 0, NULL, NULL);
    e->counts.moved_aside++;
    return 0;
}

typedef struct aside_ctx {
    sl_engine *e;
    const char *item, *dir;
    sl_error *err;
    int rc;
} aside_ctx;

static void aside_entry(void *ctx, const char *name)
{
    aside_ctx *a = ctx;
    char path[PATH_MAX];
    if (a->rc == 0 && sl_engine_path(path, sizeof path, "%s/%s", a->dir, name) == 0)
        a->rc = move_aside(a->e, a->item, path, a->err);
}

/* Makes the item's folder the publication's alone: a non-folder in its place, and the
 * entries `record_path` does not list, are moved aside. */
static int own_folder(sl_engine *e, const char *item, const char *final_dir,
                      const char *record_path, sl_error *err)
{
    struct stat st;
    if (lstat(final_dir, &st) != 0)
        return 0;
    if (!S_ISDIR(st.st_mode))
        return move_aside(e, item, final_dir, err);
    aside_ctx a = {e, item, final_dir, err, 0};
    sl_engine_foreign_entries(record_path, final_dir, aside_entry, &a);
    return a.rc;
}

int sl_engine_publication_settle(sl_engine *e, const char *item, const char *ticket,
                                 const char *source_rel, int *settled, sl_error *err)
{
    if (!sl_engine_publish_valid(e, item, ticket))
        return sl_engine_publish(e, item, ticket, source_rel, 1, err);
    char final_dir[PATH_MAX], record_dir[PATH_MAX], record[PATH_MAX];
    publish_paths(e, item, ticket, final_dir, record_dir);
    sl_engine_path(record, sizeof record, "%s/%s", record_dir, SL_RECORD_FILE);
    int rc = own_folder(e, item, final_dir, record, err);
    if (rc == 0 && settled)
        *settled = 1;
    return rc;
}

/* The folders above the item's (OUTPUT/a/ for a/b.ply); a non-folder standing where one
 * of them belongs is moved aside first. */
static int make_parent(sl_engine *e, const char *item, const char *parent, sl_error *err)
{
    sl_error first;
    sl_error_init(&first);
    if (sl_mkdirs(parent, &first) == 0)
        return 0;
    char path[PATH_MAX];
    for (const char *slash = strchr(item, '/'); slash; slash = strchr(slash + 1, '/')) {
        struct stat st;
        if (sl_engine_path(path, sizeof path, "%s/%.*s", e->output, (int)(slash - item), item))
            break;
        /* A link to a folder is a folder here (an operator may put a subtree elsewhere);
         * a file or a dangling link is in the way. */
        int in_the_way = stat(path, &st) == 0 ? !S_ISDIR(st.st_mode) : lstat(path, &st) == 0;
        int rc = in_the_way ? move_aside(e, item, path, err) : 0;
        if (rc)
            return rc;
    }
    return sl_mkdirs(parent, err);
}

/* report.json: every stage's report fragment under "stages"; timings.json likewise. */
static int write_reports(sl_engine *e, const char *item, const char *ticket,
                         const char *source_rel, const char *dir, sl_error *err)
{
    sl_json report, timings;
    sl_json_init(&report, 1);
    sl_json_init(&timings, 1);
    sl_json_object_begin(&report, NULL);
    sl_json_string(&report, "item", item);
    sl_json_string(&report, "source", source_rel);
    sl_json_string(&report, "method", sl_config_string(e->cfg, "lod", "method"));
    sl_json_object_begin(&report, "stages");
    sl_json_object_begin(&timings, NULL);
    sl_json_string(&timings, "item", item);
    sl_json_string(&timings, "host", e->self.host);
    sl_json_string(&timings, "run", sl_log_run_id());
    sl_json_object_begin(&timings, "stages");
    int rc = 0;
    for (int s = 0; rc == 0 && s < e->stage_count; s++) {
        char art[PATH_MAX], path[PATH_MAX];
        char *text = NULL;
        size_t size;
        sl_artifact_dir(e, s, ticket, art, sizeof art);
        sl_engine_path(path, sizeof path, "%s/report.json", art);
        rc = sl_read_file(path, 16 << 20, &text, &size, err);
        if (rc == 0)
            sl_json_raw(&report, e->stages[s]->name, text);
        free(text);
        text = NULL;
        sl_engine_path(path, sizeof path, "%s/_stats.json", art);
        sl_error serr;
        sl_error_init(&serr);
        if (rc == 0 && sl_read_file(path, 1 << 20, &text, &size, &serr) == 0)
            sl_json_raw(&timings, e->stages[s]->name, text);
        free(text);
    }
    sl_json_object_end(&report);
    sl_json_object_end(&report);
    sl_json_object_end(&timings);
    sl_json_object_end(&timings);
    char path[PATH_MAX];
    if (rc == 0 && (report.failed || timings.failed))
        rc = sl_error_set(err, SL_E_NOMEM, ENOMEM, dir, "report too large");
    if (rc == 0 && sl_engine_path(path, sizeof path, "%s/report.json", dir) == 0)
        rc = sl_write_file_atomic(path, report.buf, report.len, err);
    if (rc == 0 && sl_engine_path(path, sizeof path, "%s/timings.json", dir) == 0)
        rc = sl_write_file_atomic(path, timings.buf, timings.len, err);
    sl_json_release(&report);
    sl_json_release(&timings);
    return rc;
}

/* The files of every publishing stage, by the names in its record; their names are
 * appended to `names` (for the publish record). */
static int publish_stage_files(sl_engine *e, const char *ticket, const char *staged,
                               const char **names, int *count, char (*storage)[128],
                               sl_error *err)
{
    for (int s = 0; s < e->stage_count; s++) {
        if (!e->stages[s]->publish)
            continue;
        char dir[PATH_MAX], record[PATH_MAX];
        sl_artifact_dir(e, s, ticket, dir, sizeof dir);
        sl_engine_path(record, sizeof record, "%s/%s", dir, SL_RECORD_FILE);
        sl_record rec;
        int rc = sl_record_read(record, &rec, err);
        for (int i = 0; rc == 0 && i < rec.output_count; i++) {
            const char *name = rec.outputs[i].name;
            if (!strcmp(name, "report.json") || *count >= SL_RECORD_MAX_OUTPUTS - 1)
                continue;
            char from[PATH_MAX], to[PATH_MAX];
            sl_engine_path(from, sizeof from, "%s/%s", dir, name);
            sl_engine_path(to, sizeof to, "%s/%s", staged, name);
            rc = sl_copy_file(from, to, err);
            snprintf(storage[*count], 128, "%s", name);
            names[*count] = storage[*count];
            (*count)++;
        }
        if (rc)
            return rc;
    }
    return 0;
}

/* Swaps `staged` in as `final_dir`. */

int sl_engine_publish(sl_engine *e, const char *item, const char *ticket, const char *source_rel,
                      int force, sl_error *err)
{
    (void)force;
    char final_dir[PATH_MAX], record_dir[PATH_MAX], staged[PATH_MAX], parent[PATH_MAX];
    publish_paths(e, item, ticket, final_dir, record_dir);
    snprintf(parent, sizeof parent, "%s", final_dir);
    char *slash = strrchr(parent, '/');
    const char *base = slash ? slash + 1 : parent;
    if (slash)
        *slash = '\0';
    /* The name is bounded (a scan may be named with 250 bytes: NAME_MAX is 255); one
     * process stages one item at a time, so HOST.PID keeps it unique. */
    if (sl_engine_path(staged, sizeof staged, "%s/.%.100s.publish.%s.%ld", parent, base,
                       e->self.host, e->self.pid))
        return sl_error_set(err, SL_E_LIMIT, 0, item, "path too long");
    sl_hash key;
    int rc = publish_key(e, ticket, &key, err);
    if (rc == 0)
        rc = make_parent(e, item, parent, err);
    if (rc == 0) {
        sl_error ignored;
        sl_error_init(&ignored);
        sl_remove_tree(staged, 0, &ignored); /* leftovers of a killed attempt by this pid */
        rc = sl_mkdirs(staged, err);
    }
    if (rc == 0)
        rc = write_reports(e, item, ticket, source_rel, staged, err);
    static char storage[SL_RECORD_MAX_OUTPUTS][128];
    const char *published[SL_RECORD_MAX_OUTPUTS + 1] = {"report.json"};
    int published_count = 1;
    if (rc == 0)
        rc = publish_stage_files(e, ticket, staged, published, &published_count, storage, err);
    published[published_count] = NULL;
    if (rc == 0)
        rc = sl_fsync_dir(staged, err);
    /* What is in the old folder and not the old publication's goes aside, not away with
     * it; a non-folder in its place goes aside too (a rename onto it would fail). */
    char record[PATH_MAX];
    sl_engine_path(record, sizeof record, "%s/%s", record_dir, SL_RECORD_FILE);
    if (rc == 0)
        rc = own_folder(e, item, final_dir, record, err);
    /* The old record must not vouch for the new files, even for a moment. */
    if (rc == 0 && unlink(record) == 0)
        rc = sl_fsync_dir(record_dir, err);
    if (rc == 0)
        rc = sl_engine_swap_in(staged, final_dir, parent, err);
    if (rc) {
        sl_error ignored;
        sl_error_init(&ignored);
        sl_remove_tree(staged, 0, &ignored);
        return rc;
    }
    rc = sl_mkdirs(record_dir, err);
    if (rc == 0)
        rc = sl_record_commit(record, final_dir, published, "_publish", 1, item, key, NULL, err);
    if (rc == 0) {
        e->counts.published++;
        e->items_settled++;
        char progress[160];
        sl_engine_progress_text(e, progress, sizeof progress);
        /* The progress rides on this line: in a cron log (no terminal, no bar) it is what
         * says how far the night has come. */
        SL_LOG(SL_LOG_INFO, "publish", item, "published %s (%s)", final_dir, progress);
        sl_log_event("published", "publish", item, 0, NULL, NULL);
    }
    return rc;
}
