/* `scanlod verify`: every commit record against its files, every published folder against
 * its record, and every done item published (an fsck for operators; the crash test runs it
 * after every kill).
 */
#include "pipeline/engine_internal.h"

#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

int sl_engine_foreign_entries(const char *record_path, const char *dir,
                              void (*fn)(void *ctx, const char *name), void *ctx)
{
    sl_record *rec = malloc(sizeof *rec);
    sl_error err;
    sl_error_init(&err);
    DIR *d = rec && sl_record_read(record_path, rec, &err) == 0 ? opendir(dir) : NULL;
    if (!d) {
        free(rec);
        return 0; /* no record to judge by (or no folder): nothing is foreign */
    }
    int found = 0;
    struct dirent *de;
    while ((de = readdir(d))) {
        if (!strcmp(de->d_name, ".") || !strcmp(de->d_name, "..") ||
            !strcmp(de->d_name, "timings.json"))
            continue;
        int listed = 0;
        for (int i = 0; i < rec->output_count && !listed; i++)
            listed = strcmp(rec->outputs[i].name, de->d_name) == 0;
        if (!listed) {
            found++;
            fn(ctx, de->d_name);
        }
    }
    closedir(d);
    free(rec);
    return found;
}

static int verify_one(const char *record, const char *dir, FILE *out)
{
    sl_error err;
    sl_error_init(&err);
    if (sl_record_verify(record, dir, NULL, NULL, &err) == 0)
        return 0;
    char line[1600];
    fprintf(out, "%s: %s\n", record, sl_error_format(&err, line, sizeof line));
    return 1;
}

typedef struct foreign_ctx {
    FILE *out;
    const char *dir;
} foreign_ctx;

static void say_foreign(void *ctx, const char *name)
{
    foreign_ctx *f = ctx;
    fprintf(f->out, "%s/%s: not part of the publication (no record lists it; the next run "
                    "moves it aside)\n", f->dir, name);
}

/* A published folder holds what its record lists and timings.json, nothing else: a file
 * someone added (or left) there is not vouched for by anything. */
static int foreign_files(const char *record_path, const char *dir, FILE *out)
{
    foreign_ctx f = {out, dir};
    return sl_engine_foreign_entries(record_path, dir, say_foreign, &f) > 0;
}

/* Items whose last stage is done must be published: a done item without a publish
 * record is one whose publication failed (full output disk) and is not yet redone. */
uint64_t sl_engine_unpublished(sl_engine *e, FILE *out)
{
    const char *last = e->stages[e->stage_count - 1]->name;
    char **names;
    int count;
    sl_error err;
    sl_error_init(&err);
    if (sl_queue_list(e->work, last, SL_STATE_DONE, &names, &count, &err) != 0)
        return 0;
    uint64_t missing = 0;
    for (int i = 0; i < count; i++) {
        char record[PATH_MAX];
        if (sl_engine_path(record, sizeof record, "%s/artifacts/_publish/%s/%s", e->work,
                           names[i], SL_RECORD_FILE) == 0 &&
            access(record, F_OK) != 0) {
            fprintf(out, "%s: done but not published (the next run publishes it)\n", names[i]);
            missing++;
        }
    }
    free(names);
    return missing;
}

int sl_engine_verify(sl_engine *e, FILE *out, uint64_t *checked, uint64_t *bad)
{
    *checked = *bad = 0;
    for (int s = 0; s <= e->stage_count; s++) {
        const char *stage = s < e->stage_count ? e->stages[s]->name : "_publish";
        char root[PATH_MAX];
        sl_engine_path(root, sizeof root, "%s/artifacts/%s", e->work, stage);
        DIR *d = opendir(root);
        if (!d)
            continue;
        struct dirent *de;
        while ((de = readdir(d))) {
            if (de->d_name[0] == '.')
                continue;
            char dir[PATH_MAX], record[PATH_MAX];
            sl_engine_path(dir, sizeof dir, "%s/%s", root, de->d_name);
            sl_engine_path(record, sizeof record, "%s/%s", dir, SL_RECORD_FILE);
            if (access(record, F_OK) != 0)
                continue; /* not committed: nothing is claimed */
            int publication = s == e->stage_count;
            if (publication) { /* publish records vouch for the output folder */
                sl_record rec;
                sl_error err;
                sl_error_init(&err);
                if (sl_record_read(record, &rec, &err) == 0)
                    sl_engine_path(dir, sizeof dir, "%s/%s", e->output, rec.item);
            }
            (*checked)++;
            int wrong = verify_one(record, dir, out);
            if (!wrong && publication)
                wrong = foreign_files(record, dir, out);
            *bad += (uint64_t)wrong;
        }
        closedir(d);
    }
    *bad += sl_engine_unpublished(e, out);
    return *bad ? SL_E_CORRUPT : 0;
}
