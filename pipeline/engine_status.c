/* What a run says at its end, and what `scanlod status` says: the queue counts, the exit
 * code they give (docs/exit-codes.md) and the one-paragraph summary.
 */
#include "pipeline/engine_internal.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/log.h"
#include "core/progress.h"

typedef struct queue_counts {
    uint64_t n[SL_MAX_STAGES][SL_STATE_COUNT];
} queue_counts;

static int count_queues(const sl_engine *e, queue_counts *c, sl_error *err)
{
    memset(c, 0, sizeof *c);
    for (int s = 0; s < e->stage_count; s++)
        for (int st = 0; st < SL_STATE_COUNT; st++) {
            char **names;
            int count;
            int rc = sl_queue_list(e->work, e->stages[s]->name, st, &names, &count, err);
            if (rc)
                return rc;
            c->n[s][st] = (uint64_t)count;
            free(names);
        }
    return 0;
}

int sl_engine_finish(sl_engine *e)
{
    sl_log_progress_clear();
    queue_counts c;
    sl_error err;
    sl_error_init(&err);
    uint64_t pending = 0, quarantined = 0;
    int exit_code;
    if (count_queues(e, &c, &err) != 0) {
        SL_LOG(SL_LOG_ERROR, NULL, NULL, "cannot read the queues: %s", err.message);
        exit_code = sl_error_exit_code(err.code);
    } else {
        for (int s = 0; s < e->stage_count; s++) {
            pending += c.n[s][SL_STATE_READY] + c.n[s][SL_STATE_CLAIMED] + c.n[s][SL_STATE_FAILED];
            quarantined += c.n[s][SL_STATE_QUARANTINE];
        }
        /* What failed transiently in this run without leaving a ticket behind (a
         * publication that found the output disk full, an input that could not be
         * hashed) is pending too: the next run retries it, and until then the collection
         * is not done. Exit 0 means every item is published. */
        pending += e->counts.untracked;
        if (e->stop)
            exit_code = sl_error_exit_code(e->storage_error.code);
        else if (pending || *sl_interrupt_flag())
            exit_code = SL_EXIT_TEMPFAIL;
        else if (e->counts.bugs)
            exit_code = SL_EXIT_SOFTWARE;
        else if (quarantined)
            exit_code = SL_EXIT_DATAERR;
        else
            exit_code = SL_EXIT_OK;
    }
    sl_error serr;
    sl_error_init(&serr);
    if (e->item_count && sl_engine_write_summary(e, &serr) != 0) {
        char line[1600];
        SL_LOG(SL_LOG_ERROR, NULL, NULL, "collection summary not written: %s",
               sl_error_format(&serr, line, sizeof line));
    }
    const sl_engine_counts *k = &e->counts;
    char skipped[256] = "";
    if (k->skipped)
        snprintf(skipped, sizeof skipped, ", %llu input entries skipped (see the log)",
                 (unsigned long long)k->skipped);
    if (k->moved_aside)
        snprintf(skipped + strlen(skipped), sizeof skipped - strlen(skipped),
                 ", %llu entries in the output moved aside (see the log)",
                 (unsigned long long)k->moved_aside);
    if (k->manifest_unknown)
        snprintf(skipped + strlen(skipped), sizeof skipped - strlen(skipped),
                 ", %llu manifest rows name no item (see the log)",
                 (unsigned long long)k->manifest_unknown);
    /* An item quarantined as a bug is newly quarantined too (the line said 0 of them). */
    uint64_t quarantined_new = k->quarantined + k->bugs;
    char bugs[48] = "";
    if (k->bugs)
        snprintf(bugs, sizeof bugs, " (%llu as scanlod bugs)", (unsigned long long)k->bugs);
    if (k->ran == 0 && k->published == 0 && quarantined_new == 0 && pending == 0 &&
        k->moved_aside == 0 && !e->stop)
        printf("nothing to do: %llu items up to date (%llu quarantined)%s\n",
               (unsigned long long)k->items, (unsigned long long)quarantined, skipped);
    else
        printf("%llu items: %llu stage runs, %llu reused, %llu published, %llu newly "
               "quarantined%s, %llu failed transiently, %llu pending%s; exit %d\n",
               (unsigned long long)k->items, (unsigned long long)k->ran,
               (unsigned long long)k->reused, (unsigned long long)k->published,
               (unsigned long long)quarantined_new, bugs, (unsigned long long)k->transient,
               (unsigned long long)pending, skipped, exit_code);
    fflush(stdout);
    char extra[512];
    snprintf(extra, sizeof extra,
             "\"items\":%llu,\"ran\":%llu,\"reused\":%llu,\"published\":%llu,"
             "\"quarantined_new\":%llu,\"bugs_new\":%llu,\"quarantined_total\":%llu,"
             "\"transient\":%llu,\"pending\":%llu,\"skipped\":%llu,\"exit\":%d",
             (unsigned long long)k->items, (unsigned long long)k->ran,
             (unsigned long long)k->reused, (unsigned long long)k->published,
             (unsigned long long)quarantined_new, (unsigned long long)k->bugs,
             (unsigned long long)quarantined,
             (unsigned long long)k->transient, (unsigned long long)pending,
             (unsigned long long)k->skipped, exit_code);
    sl_log_event("run_end", NULL, NULL, 0, e->stop ? &e->storage_error : NULL, extra);
    return exit_code;
}

int sl_engine_status(sl_engine *e, FILE *out, sl_error *err)
{
    queue_counts c;
    int rc = count_queues(e, &c, err);
    if (rc)
        return rc;
    fprintf(out, "%-10s %8s %8s %8s %8s %12s\n", "stage", "ready", "claimed", "done", "failed",
            "quarantined");
    for (int s = 0; s < e->stage_count; s++)
        fprintf(out, "%-10s %8llu %8llu %8llu %8llu %12llu\n", e->stages[s]->name,
                (unsigned long long)c.n[s][SL_STATE_READY],
                (unsigned long long)c.n[s][SL_STATE_CLAIMED],
                (unsigned long long)c.n[s][SL_STATE_DONE],
                (unsigned long long)c.n[s][SL_STATE_FAILED],
                (unsigned long long)c.n[s][SL_STATE_QUARANTINE]);
    sl_engine_unpublished(e, out);
    static const int listed[] = {SL_STATE_QUARANTINE, SL_STATE_FAILED, SL_STATE_CLAIMED};
    for (int s = 0; s < e->stage_count; s++)
        for (int l = 0; l < 3; l++) {
            char **names;
            int count;
            if (sl_queue_list(e->work, e->stages[s]->name, listed[l], &names, &count, err))
                return err->code;
            for (int i = 0; i < count; i++) {
                sl_ticket t;
                if (sl_queue_get(e->work, e->stages[s]->name, listed[l], names[i], &t) != 0)
                    continue;
                char ticket[SL_TICKET_NAME_MAX + 1], part_label[32] = "";
                int part;
                if (sl_part_parse(names[i], ticket, sizeof ticket, &part))
                    snprintf(part_label, sizeof part_label, " part %d", part + 1);
                if (listed[l] == SL_STATE_CLAIMED)
                    fprintf(out, "%s %s%s: claimed by %s pid %ld%s%s, lease epoch %llu\n",
                            e->stages[s]->name, t.item, part_label, t.host, t.pid,
                            t.job[0] ? " job " : "", t.job, (unsigned long long)t.epoch);
                else
                    fprintf(out, "%s %s%s: %s (%s): %s%s\n", e->stages[s]->name, t.item,
                            part_label,
                            sl_queue_state_name(listed[l]), t.cls, t.reason,
                            listed[l] == SL_STATE_QUARANTINE &&
                                    sl_engine_item_published(e, t.item)
                                ? " [stale: the previous version's levels stay published]"
                                : "");
            }
            free(names);
        }
    return 0;
}

/* ---- progress ---------------------------------------------------------------------- */

/* The share of the collection done, the running item counted by its stages (stage s of
 * n at f of it is (s + f) / n of the item), never less than what was shown before: a
 * stage's own fraction starts at 0 again, the collection's does not. */
static double collection_fraction(sl_engine *e, int s, double stage_fraction)
{
    if (!e->items_total)
        return -1;
    double part = 0;
    if (s >= 0 && e->stage_count > 0) {
        double f = stage_fraction >= 0 && stage_fraction <= 1 ? stage_fraction : 0;
        part = ((double)s + f) / (double)e->stage_count;
    }
    double fraction = ((double)e->items_settled + part) / (double)e->items_total;
    if (fraction > 1)
        fraction = 1;
    if (fraction < e->bar_fraction)
        fraction = e->bar_fraction;
    e->bar_fraction = fraction;
    return fraction;
}

/* Seconds left, from the pace of this run's own work (items settled before it began do
 * not count); < 0 until there is a pace to go by: a second of work or one item this run
 * settled (a fast machine may finish a small collection in less than two seconds). */
static double eta_seconds(const sl_engine *e, double fraction, double elapsed)
{
    if (fraction < 0 || !e->items_total || elapsed <= 0)
        return -1;
    if (elapsed < 1 && e->items_settled <= e->settled_at_start)
        return -1;
    double before = (double)e->settled_at_start / (double)e->items_total;
    double done = fraction - before, left = 1 - fraction;
    return done > 0.001 ? elapsed * left / done : -1;
}

void sl_engine_progress(sl_engine *e, int s, const char *item, double stage_fraction)
{
    double now = sl_now_seconds();
    if (!e->work_start)
        e->work_start = now;
    char label[300];
    snprintf(label, sizeof label, "%.200s %.32s", item, s >= 0 ? e->stages[s]->name : "");
    sl_log_bar bar = {e->items_settled, e->items_total, collection_fraction(e, s, stage_fraction),
                      now - e->work_start, -1, label, stage_fraction};
    bar.eta_s = eta_seconds(e, bar.fraction, bar.elapsed_s);
    sl_log_progress(&bar);
}

void sl_engine_progress_text(sl_engine *e, char *buf, size_t size)
{
    double now = sl_now_seconds();
    double elapsed = e->work_start ? now - e->work_start : 0;
    double fraction = collection_fraction(e, -1, -1);
    double eta = eta_seconds(e, fraction, elapsed);
    char took[24], left[24];
    sl_log_duration(elapsed, took, sizeof took);
    sl_log_duration(eta, left, sizeof left);
    if (!e->items_total)
        snprintf(buf, size, "%llu items settled, %s elapsed", (unsigned long long)e->items_settled,
                 took);
    else
        snprintf(buf, size, "%llu/%llu items, %d %%, %s elapsed%s%s",
                 (unsigned long long)e->items_settled, (unsigned long long)e->items_total,
                 (int)(fraction * 100), took, eta >= 0 ? ", ETA " : "", eta >= 0 ? left : "");
}
