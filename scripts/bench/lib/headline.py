"""Derived figures of a results folder: per-stage summaries, pair ratios, slopes, and the
headline lines of docs/benchmarks.md. Pure: takes the loaded phase JSONs (any may be
None), returns a dict; report.py and plots.py render it.
"""
import json
import os

import stats

PHASES = ("machine", "models", "stages", "octree", "lod", "growth")


def load_all(results):
    """{phase: loaded JSON or None}; models without its "_versions" entry, which is
    returned under "versions"."""
    out = {}
    for name in PHASES:
        p = os.path.join(results, name + ".json")
        out[name] = None
        if os.path.exists(p):
            with open(p) as f:
                out[name] = json.load(f)
    out["models"] = out["models"] or {}
    out["versions"] = out["models"].pop("_versions", {"openvdb": "?", "meshoptimizer": "?"})
    return out


def stage_summary(models, st):
    out = {}
    for name, r in (st or {}).items():
        per = {}
        reps = {t: r["scanlod"][t] for t in ("1", "2")}
        for t, rows in reps.items():
            for rep in rows:
                rep["total"] = {k: sum(rep[s][k] for s in stats.STAGES if s in rep)
                                for k in ("seconds", "cpu_seconds")}
                rep["total"]["peak_rss_kb"] = max(rep[s]["peak_rss_kb"]
                                                  for s in stats.STAGES if s in rep)
        for stage in stats.STAGES + ["total"]:
            if not all(stage in rep for t in reps for rep in reps[t]) or not reps["2"]:
                continue
            p = {t: {k: stats.summary([rep[stage][k] for rep in reps[t]])
                     for k in ("seconds", "cpu_seconds", "peak_rss_kb")} for t in reps}
            p["speedup"] = stats.summary(stats.pair_ratios(
                [rep[stage]["seconds"] for rep in reps["1"]],
                [rep[stage]["seconds"] for rep in reps["2"]]))
            med = p["2"]["seconds"]["median"]
            p["throughput"] = models[name]["input_triangles"] / med if med else None
            per[stage] = p
        out[name] = per
    return out


def vdb_time(st):
    out = {}
    for name, r in (st or {}).items():
        v = r["vdb"].get("signed")
        if not v:
            continue
        sm = {t: [rep["samples"]["seconds"] + rep["merge"]["seconds"]
                  for rep in r["scanlod"][t]] for t in ("1", "2")}
        vs = {t: [x["seconds"] for x in v[t]] for t in ("1", "2")}
        out[name] = {
            "variant": "signed",
            "scanlod": {t: stats.summary(sm[t]) for t in sm},
            "vdb": {t: stats.summary(vs[t]) for t in vs},
            "ratio": {t: stats.summary(stats.pair_ratios(vs[t], sm[t])) for t in sm},
            "scanlod_rss": stats.summary([max(rep["samples"]["peak_rss_kb"],
                                              rep["merge"]["peak_rss_kb"])
                                          for rep in r["scanlod"]["2"]]),
            "vdb_rss": stats.summary([x["peak_rss_kb"] for x in v["2"]]),
            "scanlod_speedup": stats.summary(stats.pair_ratios(sm["1"], sm["2"])),
            "vdb_speedup": stats.summary(stats.pair_ratios(vs["1"], vs["2"])),
        }
    return out


def depth_rows(oc):
    if not oc or not oc.get("depths"):
        return None
    rows, prev = [], None
    for r in oc["depths"]["rows"]:
        reps = r["reps"]
        row = {"depth": r["depth"], "leaf_size": reps[0]["leaf_size"],
               "samples": reps[0]["samples_count"],
               "samples_s": stats.summary([x["samples"]["seconds"] for x in reps]),
               "samples_rss": stats.summary([x["samples"]["peak_rss_kb"] for x in reps]),
               "merge_s": stats.summary([x["merge"]["seconds"] for x in reps]),
               "merge_rss": stats.summary([x["merge"]["peak_rss_kb"] for x in reps])}
        row["samples_ratio"] = row["samples"] / prev["samples"] if prev else None
        row["rss_ratio"] = (row["merge_rss"]["median"] / prev["merge_rss"]["median"]
                            if prev else None)
        rows.append(row)
        prev = row
    return {"input": oc["depths"]["input"], "rows": rows}


def root_triangles(r):
    """" (N triangles)" when a model's root-only cut draws any, else ""."""
    n = r.get("root_cut_triangles")
    return " (%d triangles)" % n if n else ""


def ladder(lod):
    """Per model: per-triangle extraction costs, warm (the median of repeated extractions
    in one process, the figure the aims are judged on) and cold (the first extraction in a
    fresh process); results from before warm timings existed have the cold ones only."""
    def med(x, key):
        return (x.get(key) or {}).get("median")

    out = {}
    for name, r in (lod or {}).items():
        warm = all(med(x, "warm_seconds") for x in r["ladder"])
        key = "warm_seconds" if warm else "seconds"
        rows, flat = stats.per_triangle([dict(x, seconds=med(x, key)) for x in r["ladder"]])
        cold, cold_flat = stats.per_triangle([dict(x, seconds=med(x, "seconds"))
                                              for x in r["ladder"]])
        hot_rows, hot_flat = stats.per_triangle([dict(x, seconds=med(x, "hot_seconds"))
                                                 for x in r["ladder"]])
        for x, orig, c, t in zip(rows, r["ladder"], cold, hot_rows):
            x["seconds_median"] = x["seconds"]
            x["seconds"] = orig[key]   # the summary again, for the table
            x["cold_seconds"] = orig["seconds"]
            x["cold_ns_per_triangle"] = c["ns_per_triangle"]
            x["hot_seconds"] = orig.get("hot_seconds")
            x["hot_ns_per_triangle"] = t["ns_per_triangle"]
            x["rate"] = 1e9 / x["ns_per_triangle"] if x["ns_per_triangle"] else None
        fit = stats.loglog_slope([x["triangles"] for x in rows],
                                 [x["seconds_median"] for x in rows])
        hot = all(med(x, "hot_seconds") for x in r["ladder"])
        out[name] = {"rows": rows, "flatness": flat, "fit": fit, "warm": warm,
                     "cold_flatness": cold_flat if warm else None,
                     "hot_flatness": hot_flat if hot else None,
                     "empty_cut_seconds": med(r, "empty_cut_seconds"),
                     "root_cut_triangles": r.get("root_cut_triangles")}
    return out


def growth(gr):
    if not gr:
        return None
    rows = []
    for s in gr["sizes"]:
        totals = [sum(rep[k]["seconds"] for k in stats.STAGES if k in rep)
                  for rep in s["reps"]]
        rows.append({"triangles": s["triangles"], "n": len(s["reps"]), "stages": s["stages"],
                     "total": stats.summary(totals),
                     "peak_rss_kb": max(v["peak_rss_kb"]["median"]
                                        for v in s["stages"].values()),
                     "plan": s.get("plan"),
                     "disk_bytes": stats.summary([d["work_bytes"] + d["published_bytes"]
                                                  for d in s.get("disk", [])])})
    xs = [r["triangles"] for r in rows]
    slopes = {"total time": stats.loglog_slope(xs, [r["total"]["median"] for r in rows])}
    for stage in stats.STAGES:
        slopes[stage] = stats.loglog_slope(
            xs, [r["stages"].get(stage, {}).get("seconds", {}).get("median") for r in rows])
    slopes["peak RSS"] = stats.loglog_slope(xs, [r["peak_rss_kb"] for r in rows])
    return {"rows": rows, "slopes": slopes, "skipped": gr.get("skipped", [])}


def fmt_range(vals, fmt):
    vals = [v for v in vals if v is not None]
    if not vals:
        return "–"
    if len(vals) == 1:
        return fmt % vals[0]
    return (fmt + "–" + fmt) % (min(vals), max(vals))


def derive(models, st, oc, lod, gr):
    h = {"stages": stage_summary(models, st), "vdb_time": vdb_time(st),
         "depths": depth_rows(oc), "ladder": ladder(lod), "growth": growth(gr)}
    lines = []
    if h["vdb_time"]:
        r = {n: v["ratio"]["2"]["median"] for n, v in h["vdb_time"].items()}
        lines.append("samples + merge vs the OpenVDB remesh at the same voxel size, 2 threads: "
                     "OpenVDB takes %s x scanlod's time (per input: %s)."
                     % (fmt_range(r.values(), "%.2f"),
                        ", ".join("%s %.2f" % kv for kv in r.items())))
    if h["stages"]:
        sp = {}
        for name, per in h["stages"].items():
            for stage, p in per.items():
                sp.setdefault(stage, []).append(p["speedup"]["median"])
        lines.append("whole pipeline throughput at 2 threads (input triangles per second of "
                     "all six stages): " + ", ".join(
                         "%s %.3g" % (n, per["total"]["throughput"])
                         for n, per in h["stages"].items() if per.get("total")) + ".")
        lines.append("1 → 2 threads speed-up per stage (range over inputs): " + ", ".join(
            "%s %s" % (s, fmt_range(v, "%.2f")) for s, v in sp.items()) + " (aim >= 1.8).")
    if h["ladder"]:
        colds = ["%s %.2f" % (n, v["cold_flatness"]) for n, v in h["ladder"].items()
                 if v.get("cold_flatness")]
        warm = any(v.get("warm") for v in h["ladder"].values())
        lines.append("extraction cost per triangle%s, max/min over budgets 1–100 %%: %s; at "
                     "100 %%: %s triangles/s%s." % (
                         " (warm process, caches flushed before each: median of repeated extractions)"
                         if warm else "",
                         ", ".join("%s %.2f" % (n, v["flatness"]) for n, v in
                                   h["ladder"].items() if v["flatness"]),
                         ", ".join("%s %.3g" % (n, v["rows"][-1]["rate"]) for n, v in
                                   h["ladder"].items() if v["rows"][-1]["rate"]),
                         "; the first extraction in a fresh process (cold): max/min " +
                         ", ".join(colds) if colds else ""))
        hots = ["%s %.2f" % (n, v["hot_flatness"]) for n, v in h["ladder"].items()
                if v.get("hot_flatness")]
        if hots:
            lines.append("the same cuts back to back (`--hot`: no cold start; small cuts then "
                         "run from a core's own cache, large ones from the shared cache): max/min "
                         + ", ".join(hots) + ".")
        empties = ["%s %.1f µs%s" % (n, 1e6 * v["empty_cut_seconds"], root_triangles(v))
                   for n, v in h["ladder"].items() if v.get("empty_cut_seconds")]
        if empties:
            lines.append("the empty cut (`--expansions 0`: the root cell alone, which draws "
                         "nothing unless a count is given), caches flushed: the fixed cost of "
                         "a cold start, " + ", ".join(empties) + ".")
        fits = ["%s %.2f" % (n, v["fit"]) for n, v in h["ladder"].items() if v["fit"]]
        if fits:
            lines.append("extraction time against output triangles m, fitted exponent b of "
                         "time ~ m^b (log-log, 1 = exactly O(m); below 1: small budgets cost "
                         "more per triangle): " + ", ".join(fits) + ".")
        by_budget = {}
        for v in h["ladder"].values():
            for x in v["rows"]:
                if x["speedup"]["median"] and x["percent"] < 100:
                    by_budget.setdefault(x["percent"], []).append(x["speedup"]["median"])
        lines.append("extraction%s vs meshopt_simplify from the finest mesh to the same "
                     "count, times faster (range over inputs; aim >= 100x): " % (
                         " (warm)" if warm else "") + ", ".join(
                         "at %g %% %s" % (p, fmt_range(v, "%.3g"))
                         for p, v in sorted(by_budget.items())) + ".")
    if lod:
        mo, vd, mf = [], [], []
        for r in lod.values():
            for e in r["equal_counts"]:
                f = e.get("meshopt_finest")
                if f and f["rms"]:
                    mf.append(e["scanlod"]["rms"] / f["rms"])
                if e["meshopt"]["rms"] and not e["meshopt"].get("is_input"):
                    mo.append(e["scanlod"]["rms"] / e["meshopt"]["rms"])
                if e["vdb"]["rms"]:
                    vd.append(e["scanlod"]["rms"] / e["vdb"]["rms"])
        lines.append("RMS at equal triangle counts, scanlod / meshoptimizer: median %.2f "
                     "(%s; aim <= 2); scanlod / OpenVDB adaptive: median %.2f (%s; aim <= 0.5)."
                     % (stats.median(mo) or 0, fmt_range(mo, "%.2f"),
                        stats.median(vd) or 0, fmt_range(vd, "%.2f")))
        if mf:
            lines.append("RMS at equal counts, scanlod LOD / meshopt_simplify of scanlod's own "
                         "finest level (the same starting surface): median %.2f (%s)."
                         % (stats.median(mf), fmt_range(mf, "%.2f")))
    if oc and oc.get("levels"):
        rr = {}
        for name, rows in oc["levels"].items():
            for r in rows:
                v = r["vdb"].get("unsigned") or r["vdb"].get("signed")
                if v and v["rms"] and r["level"] <= 2:
                    rr.setdefault(r["level"], []).append(r["scanlod"]["rms"] / v["rms"])
        if rr:
            lines.append("uniform octree levels vs OpenVDB (adaptivity 0, voxel = the level's "
                         "cell, unsigned on open scans), RMS ratio (range over inputs; < 1: "
                         "scanlod closer): " + ", ".join(
                             "level %d %s" % (l, fmt_range(v, "%.2f"))
                             for l, v in sorted(rr.items())) + ".")
    if h["depths"]:
        rr = [r["rss_ratio"] for r in h["depths"]["rows"] if r["rss_ratio"]]
        lines.append("merge peak RSS per extra octree level on %s: x%s (surface-bound: ~4, "
                     "volume-bound: 8)." % (h["depths"]["input"], fmt_range(rr, "%.2f")))
    if h["growth"] and h["growth"]["slopes"]["total time"] is not None:
        g = h["growth"]
        lines.append("cost growth %s–%s triangles: time ~ N^%.2f (%s), peak RSS ~ N^%.2f."
                     % (g["rows"][0]["triangles"], g["rows"][-1]["triangles"],
                        g["slopes"]["total time"], stats.growth_word(g["slopes"]["total time"]),
                        g["slopes"]["peak RSS"] or 0))
    h["lines"] = lines
    return h
