/* Keys: what a stage's result is trusted under (docs/engine.md, "Keys and commit
 * records"). key(s) = H(stage, version, config sections' hash, chain(s)); the chain starts
 * at the input's content hash and adds each earlier stage's outputs digest, so a change
 * anywhere upstream reruns a stage and identical upstream outputs never do.
 */
#include "pipeline/engine_internal.h"

#include <stdio.h>
#include <string.h>

int sl_input_hash(sl_engine *e, const char *ticket, const char *source_rel, sl_hash *out,
                  sl_error *err)
{
    char source[PATH_MAX], cache[PATH_MAX];
    if (sl_engine_path(source, sizeof source, "%s/%s", e->input, source_rel) ||
        sl_engine_path(cache, sizeof cache, "%s/cache/input/%s", e->work, ticket))
        return sl_error_set(err, SL_E_LIMIT, 0, source_rel, "path too long");
    return sl_hash_file_cached(source, cache, out, err);
}

sl_hash sl_chain_hash(sl_hash chain, sl_hash digest)
{
    sl_hash pair[2] = {chain, digest};
    return sl_hash_bytes(pair, sizeof pair);
}

int sl_upstream_chain(sl_engine *e, const char *ticket, const char *source_rel, int s,
                      int verify_last, sl_hash *out, sl_error *err)
{
    sl_hash chain;
    int rc = sl_input_hash(e, ticket, source_rel, &chain, err);
    for (int i = 0; rc == 0 && i < s; i++) {
        char dir[PATH_MAX], record[PATH_MAX];
        sl_artifact_dir(e, i, ticket, dir, sizeof dir);
        sl_engine_path(record, sizeof record, "%s/%s", dir, SL_RECORD_FILE);
        sl_record rec;
        sl_error rerr;
        sl_error_init(&rerr);
        int bad = verify_last && i == s - 1 ? sl_record_check(record, dir, NULL, &rec, &rerr)
                                            : sl_record_read(record, &rec, &rerr);
        if (bad)
            return SL_E_CORRUPT; /* an upstream result is gone or stale */
        chain = sl_chain_hash(chain, rec.outputs_digest);
    }
    if (rc == 0)
        *out = chain;
    return rc;
}

/* Hash of every section the stage reads (its own by default), in declaration order. */
uint64_t sl_stage_config_hash(const sl_config *cfg, const sl_stage *stage)
{
    if (!stage->sections)
        return sl_config_section_hash(cfg, stage->name);
    uint64_t hashes[8] = {0};
    int n = 0;
    for (; stage->sections[n] && n < 8; n++)
        hashes[n] = sl_config_section_hash(cfg, stage->sections[n]);
    sl_hash h = sl_hash_bytes(hashes, (size_t)n * sizeof hashes[0]);
    return h.hi ^ h.lo;
}
