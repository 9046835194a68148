/* The level ladder (ladder.h): the [levels] options, their one parser, and the one way a
 * share becomes a count. */
#include "levels/ladder.h"

#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

const sl_option sl_ladder_options[] = {
    {"levels", "percents", SL_OPT_LIST, "20,40,60,80,100", 0, 100, NULL,
     "Levels named lodP of P % of the input's triangles, for every method (100 = the scan "
     "itself for a mesh input, see top). For a point set, P % of the finest level the "
     "method makes. Empty for none."},
    {"levels", "budgets", SL_OPT_LIST, "thumb:2000,low:20000,medium:100000,high:500000", 0, 0,
     NULL,
     "Named levels (name:triangles, or name:P% of the input's triangles), as museum web "
     "viewers use: each level has at most that many triangles, and with [refine] collapse "
     "exactly that many (within 1 %) unless the input has fewer. A budget at or above the "
     "input's triangles gives the scan itself (\"clamped\" in the report). A name becomes "
     "the level's file names: letters, digits, '.', '_' and '-', starting with a letter or "
     "digit, and no two levels alike. Empty for none."},
    {"levels", "expansions", SL_OPT_LIST, "", 0, 100, NULL,
     "Octree method only (paper 1, Table 1): levels named kP after P % of the LOD array's "
     "expansions of nodes with surface below them, published as the paper cuts them (no "
     "refinement). Empty for none."},
    {"levels", "oversample", SL_OPT_DOUBLE, "2", 1, 64, NULL,
     "Each method makes a level at this many times the level's count (the octree cuts, "
     "segment and cluster build their levels there) and the refine stage's collapse takes "
     "it the rest of the way: cluster then refine (Garland and Shaffer 2002), closer than "
     "the method's own level at the count. 1: each method's own level at the count, as "
     "its paper makes it (needed with [refine] collapse = false)."},
    {"levels", "top", SL_OPT_ENUM, "scan", 0, 0, "scan|method",
     "scan: for a mesh input a level asking for the input's triangles or more is the scan "
     "itself (welded, its own vertices and colours). method: the method's own finest level "
     "(paper 1's lod100 is the octree's finest cut, a remesh)."},
    SL_OPTION_END,
};

int sl_level_name_ok(const char *name)
{
    if (!isalnum((unsigned char)name[0]))
        return 0;
    for (const char *p = name; *p; p++)
        if (!isalnum((unsigned char)*p) && !strchr("._-", *p))
            return 0;
    return 1;
}

/* A percent in [0, 100]: "12.5". */
static int parse_percent(const char *word, double *out)
{
    char *end;
    errno = 0;
    double v = strtod(word, &end);
    if (errno || end == word || *end || !(v >= 0 && v <= 100))
        return -1;
    *out = v;
    return 0;
}

/* "name:N" or "name:P%". */
static int parse_budget(const char *word, sl_rung *r, const char *where, sl_error *err)
{
    const char *colon = strchr(word, ':');
    if (!colon || colon == word || (size_t)(colon - word) >= sizeof r->name)
        return sl_error_set(err, SL_E_CONFIG, 0, where,
                            "[levels] budgets: '%s' is not name:triangles or name:P%%", word);
    snprintf(r->name, sizeof r->name, "%.*s", (int)(colon - word), word);
    const char *value = colon + 1;
    size_t n = strlen(value);
    if (n > 1 && value[n - 1] == '%') {
        char share[64];
        snprintf(share, sizeof share, "%.*s", (int)(n - 1), value);
        r->kind = SL_RUNG_SHARE;
        if (parse_percent(share, &r->percent) || r->percent <= 0)
            return sl_error_set(err, SL_E_CONFIG, 0, where,
                                "[levels] budgets: '%s': a share is a percent in (0, 100]",
                                word);
        return 0;
    }
    char *end;
    errno = 0;
    long long v = strtoll(value, &end, 10);
    if (errno || end == value || *end || v < 1 || strspn(value, "0123456789") != n)
        return sl_error_set(err, SL_E_CONFIG, 0, where,
                            "[levels] budgets: '%s': the budget must be a whole number >= 1 "
                            "or a share P%%",
                            word);
    r->kind = SL_RUNG_TRIANGLES;
    r->triangles = (uint64_t)v;
    return 0;
}

/* One list's words into rungs of `kind` (a percents or expansions list), or budgets. */
static int parse_list(const char *text, int kind, const char *key, const char *where,
                      sl_ladder *out, sl_error *err)
{
    for (const char *p = text; p && *p;) {
        char word[128];
        size_t n = strcspn(p, ",");
        if (n >= sizeof word)
            return sl_error_set(err, SL_E_CONFIG, 0, where, "[levels] %s: '%.40s...' is too long",
                                key, p);
        snprintf(word, sizeof word, "%.*s", (int)n, p);
        p += n + (p[n] == ',');
        if (!word[0])
            continue;
        if (out->count == SL_LADDER_MAX)
            return sl_error_set(err, SL_E_CONFIG, 0, where, "[levels]: more than %d levels",
                                SL_LADDER_MAX);
        sl_rung *r = &out->rungs[out->count];
        memset(r, 0, sizeof *r);
        int rc = 0;
        if (kind == SL_RUNG_TRIANGLES) {
            rc = parse_budget(word, r, where, err);
        } else {
            r->kind = kind;
            if (parse_percent(word, &r->percent))
                return sl_error_set(err, SL_E_CONFIG, 0, where,
                                    "[levels] %s: '%s' is not a percent in [0, 100]", key, word);
            snprintf(r->name, sizeof r->name, "%s%g", kind == SL_RUNG_SHARE ? "lod" : "k",
                     r->percent);
        }
        if (rc)
            return rc;
        if (!sl_level_name_ok(r->name))
            return sl_error_set(err, SL_E_CONFIG, 0, where,
                                "[levels] %s: '%s': a level name is letters, digits, '.', '_' "
                                "and '-', starting with a letter or digit",
                                key, r->name);
        for (int j = 0; j < out->count; j++)
            if (!strcmp(out->rungs[j].name, r->name))
                return sl_error_set(err, SL_E_CONFIG, 0, where,
                                    "[levels] %s: two levels are named '%s' (their files would "
                                    "overwrite each other)",
                                    key, r->name);
        out->count++;
    }
    return 0;
}

int sl_ladder_parse(const char *percents, const char *expansions, const char *budgets,
                    const char *where, sl_ladder *out, sl_error *err)
{
    memset(out, 0, sizeof *out);
    out->top_is_scan = 1;
    out->oversample = 1;
    int rc = parse_list(percents, SL_RUNG_SHARE, "percents", where, out, err);
    if (rc == 0)
        rc = parse_list(expansions, SL_RUNG_EXPANSIONS, "expansions", where, out, err);
    if (rc == 0)
        rc = parse_list(budgets, SL_RUNG_TRIANGLES, "budgets", where, out, err);
    return rc;
}

int sl_ladder_read(const sl_config *cfg, sl_ladder *out, sl_error *err)
{
    static const char *const keys[3] = {"percents", "expansions", "budgets"};
    const char *text[3];
    for (int k = 0; k < 3; k++)
        text[k] = sl_config_string(cfg, SL_LADDER_SECTION, keys[k]);
    /* A rung breaks the rules of the whole ladder (a name used twice across lists, say):
     * the error names the place of the list the rung came from, the last one parsed. */
    memset(out, 0, sizeof *out);
    for (int upto = 1; upto <= 3; upto++) {
        char where[1024];
        sl_config_where(cfg, SL_LADDER_SECTION, keys[upto - 1], where, sizeof where);
        int rc = sl_ladder_parse(text[0], upto > 1 ? text[1] : "", upto > 2 ? text[2] : "",
                                 where, out, err);
        if (rc)
            return rc;
    }
    out->top_is_scan = !strcmp(sl_config_string(cfg, SL_LADDER_SECTION, "top"), "scan");
    out->oversample = sl_config_double(cfg, SL_LADDER_SECTION, "oversample");
    return 0;
}

uint64_t sl_rung_triangles(const sl_rung *r, uint64_t input_triangles)
{
    if (r->kind == SL_RUNG_TRIANGLES)
        return r->triangles;
    if (r->kind == SL_RUNG_EXPANSIONS)
        return 0;
    uint64_t n = (uint64_t)floor(r->percent / 100.0 * (double)input_triangles);
    return n ? n : 1;
}

uint64_t sl_rung_build_triangles(const sl_ladder *l, const sl_rung *r, uint64_t input_triangles)
{
    uint64_t n = sl_rung_triangles(r, input_triangles);
    double at = ceil(l->oversample * (double)n);
    return at >= (double)input_triangles ? (n > input_triangles ? n : input_triangles)
                                          : (uint64_t)at;
}
