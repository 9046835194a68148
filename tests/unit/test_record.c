/* Commit records (pipeline/record.h): a commit lists exactly the artifact's outputs
 * (sorted; not '.' or '_' files, not the record) with sizes and hashes, the same bytes on
 * every commit of the same outputs; verify accepts exactly that and refuses a flipped
 * byte, a changed size, a missing output, another key, a torn or edited record, or no
 * record; an extra file is not vouched for (it is not in the record, and committing with
 * it changes the digest later keys chain on); a commit that fails (injected) leaves the
 * previous record whole. Stage keys change with each of their inputs. */
#include "pipeline/record.h"

#include <sys/stat.h>
#include <unistd.h>

#include "core/hash.h"
#include "tests/check.h"
#include "tests/unit/durable_checks.h"

static char dir[PATH_MAX], record[PATH_MAX + 16];

static sl_hash key_of(const char *config)
{
    return sl_stage_key("merge", 2, sl_hash_bytes(config, strlen(config)).lo, (sl_hash){0, 0});
}

static void put(const char *name, const char *text)
{
    char path[PATH_MAX + 300];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    CHECK(durable_put(path, text, strlen(text)) == 0);
}

static int commit(sl_hash key, sl_record *out, sl_error *err)
{
    return sl_record_commit(record, dir, NULL, "merge", 2, "bunny/bun000", key, out, err);
}

/* verify with `key`; returns the code, the message in msg (may be NULL). */
static int verify(const sl_hash *key, const char **msg)
{
    static sl_error err;
    sl_error_init(&err);
    int rc = sl_record_verify(record, dir, key, NULL, &err);
    if (msg)
        *msg = err.message;
    return rc;
}

static void set_up_outputs(void)
{
    put("octree.slot", "the octree, some bytes of it\n");
    put("report.json", "{\"nodes\": 12}\n");
    put("a_first", "sorted before octree.slot\n");
    put("_stats.json", "{\"seconds\": 1.5}\n"); /* run-specific: not an output */
    put(".octree.slot.node.1.0.tmp", "a writer's temp\n");
}

/* A commit made in a child (the parent must not use core/io.c before its forks). */
static int commit_child(void *arg)
{
    sl_error err;
    sl_error_init(&err);
    return commit(key_of((const char *)arg), NULL, &err) == 0 ? 0 : 1;
}

/* A failing commit leaves the previous record in place and whole. */
static void test_failed_commit(void)
{
    CHECK(durable_run(commit_child, "old", NULL) == 0);
    sl_hash old = key_of("old"), fresh = key_of("new");
    size_t size = 0;
    char *before = durable_slurp(record, &size);
    const char *faults[] = {"write:1:ENOSPC", "fsync:1:EIO", "rename:1:EIO", "open:1:EACCES"};
    for (size_t i = 0; i < sizeof faults / sizeof faults[0]; i++) {
        CHECK_MSG(durable_run(commit_child, "new", faults[i]) == 1, "%s: committed", faults[i]);
        CHECK_MSG(durable_holds(record, before, size), "%s: the record changed", faults[i]);
        CHECK_MSG(verify(&old, NULL) == 0 && verify(&fresh, NULL) == SL_E_CORRUPT,
                  "%s: the old record no longer verifies", faults[i]);
        CHECK(durable_temps(dir) == 1); /* only set_up_outputs' own */
    }
    free(before);
}

static void test_commit_and_verify(void)
{
    sl_hash key = key_of("max_samples=100");
    sl_record r;
    sl_error err;
    sl_error_init(&err);
    CHECK(commit(key, &r, &err) == 0);
    CHECK_EQ_U64(r.output_count, 3);
    const char *names[] = {"a_first", "octree.slot", "report.json"};
    for (int i = 0; i < r.output_count && i < 3; i++)
        CHECK_MSG(!strcmp(r.outputs[i].name, names[i]), "output %d: %s", i, r.outputs[i].name);
    CHECK_EQ_U64(r.outputs[1].size, strlen("the octree, some bytes of it\n"));
    CHECK(verify(&key, NULL) == 0);
    CHECK(verify(NULL, NULL) == 0);

    sl_record back;
    CHECK(sl_record_read(record, &back, &err) == 0);
    CHECK(!strcmp(back.stage, "merge") && back.stage_version == 2);
    CHECK(!strcmp(back.item, "bunny/bun000"));
    CHECK(sl_hash_equal(back.key, key) && sl_hash_equal(back.outputs_digest, r.outputs_digest));
    CHECK(back.output_count == 3 && sl_hash_equal(back.outputs[2].hash, r.outputs[2].hash));

    /* The same outputs give the same record, byte for byte. */
    size_t n1 = 0, n2 = 0;
    char *first = durable_slurp(record, &n1);
    CHECK(commit(key, NULL, &err) == 0);
    char *second = durable_slurp(record, &n2);
    CHECK(first && second && n1 == n2 && !memcmp(first, second, n1));
    free(first);
    free(second);

    /* Explicit names: exactly those. */
    const char *only[] = {"report.json", NULL};
    CHECK(sl_record_commit(record, dir, only, "merge", 2, "bunny/bun000", key, &r, &err) == 0);
    CHECK(r.output_count == 1 && !strcmp(r.outputs[0].name, "report.json"));
    CHECK(commit(key, NULL, &err) == 0);
}

static void test_tampering(void)
{
    sl_hash key = key_of("max_samples=100");
    const char *msg;
    char path[PATH_MAX + 32];
    snprintf(path, sizeof path, "%s/octree.slot", dir);
    size_t size = 0;
    char *good = durable_slurp(path, &size);

    good[3] ^= 0x01; /* one flipped bit, same size */
    CHECK(durable_put(path, good, size) == 0);
    CHECK(verify(&key, &msg) == SL_E_CORRUPT && strstr(msg, "does not match"));
    good[3] ^= 0x01;
    CHECK(durable_put(path, good, size) == 0);
    CHECK(verify(&key, NULL) == 0);

    CHECK(durable_put(path, good, size - 1) == 0); /* shorter */
    CHECK(verify(&key, &msg) == SL_E_CORRUPT && strstr(msg, "does not match"));
    CHECK(durable_put(path, good, size) == 0);

    char moved[PATH_MAX + 32];
    snprintf(moved, sizeof moved, "%s/octree.slot.away", dir);
    CHECK(rename(path, moved) == 0); /* missing */
    CHECK(verify(&key, &msg) == SL_E_CORRUPT && strstr(msg, "missing"));
    CHECK(rename(moved, path) == 0);
    CHECK(verify(&key, NULL) == 0);

    sl_hash other = key_of("max_samples=101"); /* another config */
    CHECK(verify(&other, &msg) == SL_E_CORRUPT && strstr(msg, "another key"));

    /* An extra file: not in the record, so not trusted; verify still speaks for the
     * listed outputs. Committing with it lists it and changes the digest. */
    sl_record before, after;
    sl_error err;
    sl_error_init(&err);
    CHECK(sl_record_read(record, &before, &err) == 0);
    put("extra.bin", "not made by the stage\n");
    CHECK(verify(&key, NULL) == 0);
    CHECK(sl_record_read(record, &after, &err) == 0 && after.output_count == 3);
    CHECK(commit(key, &after, &err) == 0);
    CHECK(after.output_count == 4 && !sl_hash_equal(after.outputs_digest, before.outputs_digest));
    snprintf(moved, sizeof moved, "%s/extra.bin", dir);
    unlink(moved);
    CHECK(verify(&key, &msg) == SL_E_CORRUPT && strstr(msg, "missing"));
    CHECK(commit(key, NULL, &err) == 0);
    free(good);
}

/* The record itself: torn, edited or absent, it vouches for nothing. */
static void test_bad_records(void)
{
    sl_hash key = key_of("max_samples=100");
    const char *msg;
    size_t size = 0;
    char *text = durable_slurp(record, &size);
    CHECK(text && size > 0);
    int accepted = 0;
    for (size_t cut = 0; text && cut + 1 < size; cut++) { /* every torn prefix */
        CHECK(durable_put(record, text, cut) == 0);
        accepted += verify(&key, NULL) != SL_E_CORRUPT;
    }
    CHECK_MSG(accepted == 0, "%d torn records accepted", accepted);

    /* An edited size or hash line no longer matches the outputs digest. */
    char *edited = strdup(text), *line = strstr(edited, "output=octree.slot ");
    CHECK(line != NULL);
    if (line) {
        char *hash = strchr(line + strlen("output=octree.slot "), ' ') + 1;
        hash[0] = hash[0] == '0' ? '1' : '0';
        CHECK(durable_put(record, edited, size) == 0);
        CHECK(verify(&key, &msg) == SL_E_CORRUPT && strstr(msg, "digest"));
        char *digits = line + strlen("output=octree.slot ");
        hash[0] = text[hash - edited];
        digits[0] = digits[0] == '9' ? '8' : (char)(digits[0] + 1);
        CHECK(durable_put(record, edited, size) == 0);
        CHECK(verify(&key, &msg) == SL_E_CORRUPT);
    }
    free(edited);
    CHECK(durable_put(record, "format=scanlod-record 2\nend\n", 28) == 0);
    CHECK(verify(&key, &msg) == SL_E_CORRUPT && strstr(msg, "does not parse"));
    unlink(record);
    CHECK(verify(&key, &msg) == SL_E_CORRUPT && strstr(msg, "no record"));
    CHECK(durable_put(record, text, size) == 0);
    CHECK(verify(&key, NULL) == 0);
    free(text);
}

/* The scan's check (sl_record_check): a full verification the first time, then trusted by
 * the identities in _verified while they hold; any change of identity verifies in full. */
static void test_cached_check(void)
{
    sl_hash key = key_of("max_samples=100");
    sl_error err;
    sl_error_init(&err);
    char cache[PATH_MAX + 32], path[PATH_MAX + 32];
    snprintf(cache, sizeof cache, "%s/_verified", dir);
    snprintf(path, sizeof path, "%s/octree.slot", dir);
    unlink(cache);
    CHECK(commit(key, NULL, &err) == 0);
    CHECK(sl_record_check(record, dir, &key, NULL, &err) == 0);
    size_t n = 0;
    char *lines = durable_slurp(cache, &n);
    int count = 0;
    for (size_t i = 0; lines && i < n; i++)
        count += lines[i] == '\n';
    CHECK_MSG(count == 4, "_verified holds %d identities, not the record's and 3 outputs'", count);
    free(lines);
    CHECK(sl_record_check(record, dir, &key, NULL, &err) == 0);
    CHECK(sl_record_check(record, dir, &(sl_hash){7, 7}, NULL, &err) == SL_E_CORRUPT);

    /* A changed output changes its identity: verified in full, refused. */
    size_t size = 0;
    char *good = durable_slurp(path, &size);
    good[0] ^= 0x20;
    CHECK(durable_put(path, good, size) == 0);
    CHECK(sl_record_check(record, dir, &key, NULL, &err) == SL_E_CORRUPT);
    /* The fast path reads no output: with the cache made to match the corrupt file, the
     * check trusts it (what `scanlod verify`, reading every byte, is for). */
    char *wrong_identities = NULL;
    {
        struct stat st;
        char line[SL_STAT_IDENTITY_SIZE];
        const char *names[] = {"record", "a_first", "octree.slot", "report.json"};
        size_t cap = 4 * (SL_STAT_IDENTITY_SIZE + 1) + 1, at = 0;
        wrong_identities = malloc(cap);
        for (int i = 0; i < 4; i++) {
            char p[PATH_MAX + 32];
            snprintf(p, sizeof p, "%s/%s", dir, names[i]);
            CHECK(stat(p, &st) == 0);
            sl_stat_identity(&st, line, sizeof line);
            at += (size_t)snprintf(wrong_identities + at, cap - at, "%s\n", line);
        }
        CHECK(durable_put(cache, wrong_identities, at) == 0);
    }
    CHECK_MSG(sl_record_check(record, dir, &key, NULL, &err) == 0,
              "the check read the outputs although every identity was the cached one");
    CHECK(verify(&key, NULL) == SL_E_CORRUPT);
    free(wrong_identities);
    good[0] ^= 0x20;
    CHECK(durable_put(path, good, size) == 0);
    CHECK(sl_record_check(record, dir, &key, NULL, &err) == 0);
    free(good);
    unlink(cache);
}

static void test_stage_key(void)
{
    sl_hash up = {1, 2}, base = sl_stage_key("merge", 2, 77, up);
    CHECK(sl_hash_equal(base, sl_stage_key("merge", 2, 77, up)));
    CHECK(!sl_hash_equal(base, sl_stage_key("crack", 2, 77, up)));
    CHECK(!sl_hash_equal(base, sl_stage_key("merge", 3, 77, up)));
    CHECK(!sl_hash_equal(base, sl_stage_key("merge", 2, 78, up)));
    CHECK(!sl_hash_equal(base, sl_stage_key("merge", 2, 77, (sl_hash){1, 3})));
}

int main(void)
{
    if (durable_scratch("test_record", dir)) {
        perror("mkdtemp");
        return 1;
    }
    snprintf(record, sizeof record, "%s/record", dir);
    set_up_outputs();
    test_failed_commit();
    test_commit_and_verify();
    test_tampering();
    test_bad_records();
    test_cached_check();
    test_stage_key();
    durable_remove_tree(dir);
    return check_report();
}
