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


# --- the fidelity anchor (lib/fidelity.py) -----------------------------------------------
# docs/bench/fidelity.json keeps the figures of the latest complete fidelity run of each
# method (a run of fewer methods replaces only its own), so the section and its headline
# lines can be rendered again without the raw results; a pair is one line of it.
RECORD_FIGURES = ("triangles", "rms", "hausdorff", "components", "largest_area",
                  "watertight", "boundary_edges")
ANCHOR_FIGURES = ("count", "triangles", "rms", "hausdorff", "reached")
METHOD_LABEL = {"default": "default config", "octree": "octree alone",
                "segment": "segment alone", "cluster": "cluster alone"}


def sig(v, digits=6):
    """v to so many significant digits (floats only), so that the record stays small."""
    return float("%.*g" % (digits, v)) if isinstance(v, float) else v


def fidelity_record(run):
    """A fidelity.json of lib/fidelity.py in the record's form: per method its run
    (commit, date, load, time) and per input its build; the pairs, each with its method
    and the figures the section shows."""
    pairs, methods = [], {}
    for m, md in run["methods"].items():
        items = {}
        for name, it in md["items"].items():
            items[name] = {k: sig(it.get(k), 4) for k in ("status", "method", "wall_seconds",
                                                          "build_seconds", "cpu_seconds",
                                                          "peak_rss_kb")}
            for p in it.get("pairs", []):
                row = {k: sig(p.get(k), 4) for k in (
                    "input", "percent", "budget", "file", "clamped", "triangles",
                    "budget_error", "rms_ratio", "hausdorff_ratio", "rms_ratio_simplify",
                    "rms_ratio_mo18")}
                row["method"] = m
                row["ours"] = {k: sig(p["ours"].get(k)) for k in RECORD_FIGURES}
                for a in ("update", "simplify", "mo18"):
                    row[a] = ({k: sig(p[a].get(k)) for k in ANCHOR_FIGURES}
                              if p.get(a) else None)
                pairs.append(row)
        methods[m] = {"items": items, "seconds": sig(md.get("seconds"), 4),
                      "commit": run["commit"], "date": run["date"],
                      "load_start": sig(run["load_start"], 2),
                      "reuse_peers": run["settings"]["reuse_peers"]}
    return {"settings": {k: run["settings"][k] for k in ("budgets", "samples", "threads",
                                                         "timeout_seconds", "peers",
                                                         "js_flags", "js_target_error",
                                                         "versions")},
            "inputs": {n: {k: v for k, v in f.items() if k != "sha1"}
                       for n, f in run["inputs"].items()},
            "methods": methods, "pairs": pairs}


def merge_record(old, new):
    """new's methods replace old's (their runs and pairs); the other methods stay."""
    if not old:
        return new
    keep = [p for p in old["pairs"] if p["method"] not in new["methods"]]
    methods = dict(old["methods"])
    methods.update(new["methods"])
    inputs = dict(old["inputs"])
    inputs.update(new["inputs"])
    return {"settings": new["settings"], "inputs": inputs, "methods": methods,
            "pairs": keep + new["pairs"]}


def read_record(path):
    if not os.path.exists(path):
        return None
    with open(path) as f:
        return json.load(f)


def write_record(path, rec):
    """The record as JSON with one pair a line (diffs of a rerun stay readable)."""
    head = json.dumps({k: v for k, v in rec.items() if k != "pairs"}, indent=1,
                      sort_keys=True)
    rows = ",\n".join("  " + json.dumps(p, sort_keys=True, separators=(",", ":"))
                      for p in rec["pairs"])
    with open(path + ".tmp", "w") as f:
        f.write(head[:-2] + ',\n "pairs": [\n' + rows + "\n ]\n}\n")
    os.replace(path + ".tmp", path)


def anchor(rec):
    """Per method of a record: its pairs, their summary (stats.anchor_summary), the
    builds (seconds, peak RSS; timeouts and failures named) and the worst RMS pairs."""
    if not rec:
        return None
    order = [m for m in ("default", "octree", "segment", "cluster") if m in rec["methods"]]
    order += sorted(m for m in rec["methods"] if m not in order)
    out = {}
    for m in order:
        md = rec["methods"][m]
        pairs = [p for p in rec["pairs"] if p["method"] == m]
        items = md["items"]
        ok = [it for it in items.values() if it.get("status") == "ok"]
        out[m] = {"label": METHOD_LABEL.get(m, m), "run": md, "pairs": pairs,
                  "summary": stats.anchor_summary(pairs, rec["inputs"]),
                  "build_seconds": stats.summary([it["build_seconds"] for it in ok]),
                  "build_total": sum(it["build_seconds"] for it in ok),
                  "peak_rss_kb": stats.summary([it["peak_rss_kb"] for it in ok]),
                  "not_built": {n: it["status"] for n, it in items.items()
                                if it.get("status") != "ok"},
                  "worst": sorted([p for p in pairs if p.get("rms_ratio") is not None],
                                  key=lambda p: -p["rms_ratio"])[:3]}
    return out


def pair_name(p):
    return "%s %g %%" % (p["input"], p["percent"])


def anchor_lines(rec):
    """The headline lines of the fidelity anchor: the default config's pairs, then each
    method alone."""
    a = anchor(rec)
    if not a:
        return []
    v = rec["settings"]["versions"]
    lines = []
    first = "default" if "default" in a else next(iter(a))
    r = a[first]
    s = r["summary"]
    if s["rms_ratio"]["n"]:
        lines.append(
            "fidelity anchor (section 3a; %s, commit %s, %s): RMS at each published budget "
            "level's triangle count, scanlod / meshoptimizer %s `simplifyWithUpdate`: median "
            "%.2f, max %.2f (%s), %d of %d pairs above %.1fx; Hausdorff ratio median %.2f; "
            "budget misses beyond %d %%: %d of %d; scanlod / `simplify` median %.2f, / "
            "meshoptimizer %s median %.2f."
            % (r["label"], r["run"]["commit"], r["run"]["date"], v["meshoptimizer_js"],
               s["rms_ratio"]["median"], s["rms_ratio"]["max"],
               pair_name(r["worst"][0]), s["rms_above"], s["rms_ratio"]["n"],
               stats.ANCHOR_RATIO, s["hausdorff_ratio"]["median"],
               round(100 * stats.BUDGET_TOLERANCE), s["budget_misses"], s["pairs"],
               s["rms_ratio_simplify"]["median"] or 0, v["meshoptimizer"],
               s["rms_ratio_mo18"]["median"] or 0))
    alone = [m for m in a if m != "default"]
    if alone:
        parts = []
        for m in alone:
            s = a[m]["summary"]
            txt = "%s %s (%d of %d above %.1fx, budget misses %d)" % (
                m, fmt_range([s["rms_ratio"]["median"]], "%.2f"), s["rms_above"],
                s["rms_ratio"]["n"], stats.ANCHOR_RATIO, s["budget_misses"])
            if a[m]["not_built"]:
                txt += " (%s)" % ", ".join("%s: %s" % kv for kv in a[m]["not_built"].items())
            parts.append(txt)
        lines.append("each method alone against the same anchor, RMS ratio median: "
                     + "; ".join(parts) + ".")
    return lines


def fmt_range(vals, fmt):
    vals = [v for v in vals if v is not None]
    if not vals:
        return "–"
    if len(vals) == 1:
        return fmt % vals[0]
    return (fmt + "–" + fmt) % (min(vals), max(vals))


# Headline lines of earlier generators that the fidelity anchor's lines replace: a page
# spliced by `report.py --fidelity` drops them (the line of section 3 against
# meshoptimizer 0.18 was the RMS headline before the anchor; it is now labelled as such).
SUPERSEDED = ("RMS at equal triangle counts, scanlod / meshoptimizer:",)


def derive(models, st, oc, lod, gr, versions=None):
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
                     "every stage, the refine stage included): " + ", ".join(
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
        lines.append("section 3, RMS at the counts of the reference builds' LOD-percent "
                     "levels, scanlod / meshoptimizer %s `meshopt_simplify`: median %.2f "
                     "(%s; aim <= 2); scanlod / OpenVDB adaptive: median %.2f (%s; aim <= 0.5)."
                     % ((versions or {}).get("meshoptimizer", "?"),
                        stats.median(mo) or 0, fmt_range(mo, "%.2f"),
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
