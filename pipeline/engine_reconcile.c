/* Reconciliation: make one item's tickets match its current keys.
 *
 * For every stage in order, the stage key is computed from the config section hash, the
 * stage version and the upstream chain (the input's content hash, then every earlier
 * stage's outputs digest: sl_upstream_chain). A stage whose record verifies under
 * that key is done; the first stage that is not gets a ready ticket (or keeps its
 * quarantine, when the key is the one it was quarantined under). Items whose every stage
 * is done are published if their publication is missing or stale.
 */
#include "pipeline/engine_internal.h"

#include <stdio.h>
#include <string.h>
#include <unistd.h>

#include "core/log.h"

void sl_ticket_for(sl_ticket *t, const char *item, const char *source_rel, sl_hash key)
{
    sl_ticket_init(t);
    snprintf(t->item, sizeof t->item, "%s", item);
    snprintf(t->source, sizeof t->source, "%s", source_rel);
    sl_hash_hex(key, t->key);
}

/* Rewrites a ticket in its current state with a new key, then moves it. */
static int requeue(sl_engine *e, const char *stage, const char *name, int from, sl_ticket *t,
                   sl_hash key, int reset, sl_error *err)
{
    sl_hash_hex(key, t->key);
    t->run[0] = '\0'; /* no longer a failure of some run */
    if (reset) {
        t->attempt = 0;
        t->crashes = 0;
        t->cls[0] = t->reason[0] = '\0';
    }
    int rc = sl_queue_put(e->work, stage, from, name, t, err);
    if (rc == 0 && from != SL_STATE_READY)
        rc = sl_queue_move(e->work, stage, name, from, SL_STATE_READY, err);
    return rc == SL_E_BUSY ? 0 : rc;
}

int sl_engine_ensure_ready(sl_engine *e, const char *stage, const char *name, const char *item,
                           const char *source_rel, sl_hash key, int parts, int *quarantined,
                           sl_error *err)
{
    sl_ticket t;
    int state = sl_queue_find(e->work, stage, name);
    if (state == SL_STATE_CLAIMED)
        return 0; /* a worker holds it; its lease decides */
    if (state == SL_STATE_NONE) {
        sl_ticket_for(&t, item, source_rel, key);
        t.parts = parts;
        return sl_queue_put(e->work, stage, SL_STATE_READY, name, &t, err);
    }
    char ticket_path[PATH_MAX];
    sl_queue_path(ticket_path, sizeof ticket_path, e->work, stage, state, name);
    sl_error terr;
    sl_error_init(&terr);
    if (sl_ticket_read(ticket_path, &t, &terr) != 0)
        sl_ticket_for(&t, item, source_rel, key); /* torn ticket: start over */
    char key_hex[SL_HASH_HEX_SIZE];
    sl_hash_hex(key, key_hex);
    int same_key = strcmp(t.key, key_hex) == 0;
    snprintf(t.source, sizeof t.source, "%s", source_rel);
    t.parts = parts; /* a part of another split gets another key, so it is rewritten */
    char why[256];
    if (state == SL_STATE_QUARANTINE && same_key) {
        if (sl_engine_quarantine_holds(e, &t, why, sizeof why)) {
            *quarantined = 1;
            return 0; /* stays quarantined until its input, config or code changes */
        }
        SL_LOG(SL_LOG_WARN, stage, item, "retried: %s (it said: %s)", why, t.reason);
        return requeue(e, stage, name, state, &t, key, 1, err);
    }
    if (state == SL_STATE_READY && same_key)
        return 0;
    /* A failure of this run waits for the next, as its log line said ("will retry on the
     * next run"): without this, a part that failed was requeued by its siblings' commits
     * and ran again in the same run, an out-of-memory part as often as they committed. */
    if (state == SL_STATE_FAILED && same_key && t.run[0] && !strcmp(t.run, sl_log_run_id()))
        return 0;
    return requeue(e, stage, name, state, &t, key, !same_key || state == SL_STATE_DONE, err);
}

int sl_engine_reconcile_parts(sl_engine *e, int s, const char *item, const char *source_rel,
                              const char *ticket, sl_hash key, int parts, int *all_done,
                              int *quarantined, sl_error *err)
{
    *all_done = 1;
    for (int p = 0; p < parts; p++) {
        char name[PATH_MAX];
        if (sl_part_name(ticket, p, name, sizeof name))
            return sl_error_set(err, SL_E_LIMIT, 0, source_rel, "part name too long");
        sl_hash part_key = sl_part_key(key, p, parts);
        if (sl_engine_part_committed(e, s, name, part_key))
            continue;
        *all_done = 0;
        int rc = sl_engine_ensure_ready(e, e->stages[s]->name, name, item, source_rel,
                                        part_key, parts, quarantined, err);
        if (rc)
            return rc;
    }
    return 0;
}

int sl_engine_reconcile(sl_engine *e, const char *item, const char *source_rel, int from,
                        int *settled, sl_error *err)
{
    char name[SL_TICKET_NAME_MAX + 1];
    int rc = sl_ticket_name(item, name, sizeof name, err);
    if (rc)
        return rc;
    sl_hash upstream;
    rc = sl_upstream_chain(e, name, source_rel, from, 0, &upstream, err);
    if (rc == SL_E_CORRUPT && from > 0)
        return sl_engine_reconcile(e, item, source_rel, 0, settled, err);
    if (rc)
        return rc;
    for (int s = from; s < e->stage_count; s++) {
        const char *stage = e->stages[s]->name;
        sl_hash key = sl_stage_key(stage, e->stages[s]->version,
                                   sl_engine_stage_config_hash(e, s, item), upstream);
        int state = sl_queue_find(e->work, stage, name);
        if (state == SL_STATE_CLAIMED)
            return 0; /* a worker holds it; its lease decides */
        char dir[PATH_MAX], record_path[PATH_MAX], ticket_path[PATH_MAX];
        sl_artifact_dir(e, s, name, dir, sizeof dir);
        sl_engine_path(record_path, sizeof record_path, "%s/%s", dir, SL_RECORD_FILE);
        sl_record rec;
        sl_error verr;
        sl_error_init(&verr);
        sl_ticket t;
        if (sl_record_check(record_path, dir, &key, &rec, &verr) == 0) {
            if (state != SL_STATE_DONE) {
                sl_ticket_for(&t, item, source_rel, key);
                rc = sl_queue_put(e->work, stage, SL_STATE_DONE, name, &t, err);
                if (rc == 0 && state != SL_STATE_NONE) {
                    sl_queue_path(ticket_path, sizeof ticket_path, e->work, stage, state, name);
                    unlink(ticket_path);
                }
                if (rc)
                    return rc;
                /* A committed stage whose owner failed before moving its claim to done
                 * (and so logged it as failed, or not at all): adopted here, once. */
                sl_log_event("stage_done", stage, item, -1, NULL, "\"adopted\":true");
            }
            /* Parts left behind by a join whose owner died before it removed them, or
             * of a split the stage's last config did not make (it ran unsplit). */
            sl_engine_parts_prune(e, s, name, 0, sl_engine_parts(e, s, source_rel));
            e->counts.reused++;
            upstream = sl_chain_hash(upstream, rec.outputs_digest);
            continue;
        }
        int parts = sl_engine_item_parts(e, s, name, source_rel, key, NULL), quarantined = 0;
        sl_engine_parts_prune(e, s, name, parts > 1 ? parts : 0, /* other splits' */
                              sl_engine_parts(e, s, source_rel));
        if (parts > 1) { /* the join's ticket waits until every part is committed */
            int all_done = 0;
            rc = sl_engine_reconcile_parts(e, s, item, source_rel, name, key, parts,
                                           &all_done, &quarantined, err);
            if (rc || !all_done) {
                if (quarantined && settled)
                    *settled = 1;
                return rc;
            }
        }
        rc = sl_engine_ensure_ready(e, stage, name, item, source_rel, key, 0, &quarantined, err);
        if (quarantined && settled)
            *settled = 1;
        return rc;
    }
    return sl_engine_publication_settle(e, item, name, source_rel, settled, err);
}
