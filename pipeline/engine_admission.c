/* Memory admission, asked by the stage runner (engine_child.c) before each stage. */
#include "pipeline/engine_internal.h"

#include <stdio.h>

#include "core/log.h"
#include "core/memory.h"

uint64_t sl_engine_memory_budget(const sl_engine *e, char *what, size_t what_size)
{
    return sl_memory_budget_mb(e->memory_limit_mb, what, what_size);
}

/* Memory admission (docs/engine.md): an item whose expected peak (the plan's cost model,
 * from its header) is over the budget -- [run] memory_limit_mb, or else what this node
 * or its cgroup has -- is not run: it would be killed for memory hours in, and again on
 * every later run. Says why once and leaves the reason in e->admission; 1 = run it. */
int sl_engine_admitted(sl_engine *e, int s, const sl_ticket *t, const char *source)
{
    if (!e->memory_check || !e->expected_peak_mb)
        return 1;
    char what[64];
    uint64_t budget = sl_engine_memory_budget(e, what, sizeof what);
    sl_engine_facts facts;
    sl_engine_facts_of(e, &facts);
    const char *peak_stage = "?";
    double need = e->expected_peak_mb(&facts, source, &peak_stage);
    if (budget == 0 || need <= (double)budget)
        return 1;
    e->counts.transient++;
    const char *method = sl_config_string(e->cfg, "lod", "method"); /* as choose_method read it */
    snprintf(e->admission, sizeof e->admission,
             "not run: expected to need about %.0f MB (method %s, its %s stage; `scanlod "
             "plan`), over the %llu MB of %s; raise [run] memory_limit_mb, run it on a larger "
             "node, choose another [lod] method, or set [run] memory_check = false",
             need, method, peak_stage, (unsigned long long)budget, what);
    SL_LOG(SL_LOG_ERROR, e->stages[s]->name, t->item, "%s", e->admission);
    return 0;
}
