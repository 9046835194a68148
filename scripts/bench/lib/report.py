"""Render docs/benchmarks.md from a results folder.

usage: report.py RESULTS_DIR OUT.md
       report.py --fidelity RESULTS_DIR OUT.md
Reads machine, models, stages, octree, lod, growth (.json; a missing phase is said so).
Derived figures (medians, pair ratios, slopes) come from headline.py.
The fidelity anchor's section and headline lines come from docs/bench/fidelity.json (next
to OUT.md), into which a complete run's fidelity.json is merged first (a run of a subset
of the inputs or budgets writes RESULTS_DIR/fidelity.md instead and leaves the docs as
they are). --fidelity renders only those: it replaces them in OUT.md (between their
markers) and leaves the rest of the page alone, for a run of the fidelity phase alone.
"""
import json
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import headline  # noqa: E402
import stats  # noqa: E402


def num(v, fmt="%.3g"):
    return "–" if v is None else fmt % v


def spread(s, fmt="%.3g", scale=1.0):
    """median [min–max] of a stats.summary."""
    if not s or s.get("median") is None:
        return "–"
    if s["n"] == 1:
        return fmt % (s["median"] * scale)
    return "%s [%s–%s]" % (fmt % (s["median"] * scale), fmt % (s["min"] * scale),
                           fmt % (s["max"] * scale))


def pct(v):
    """A fraction of the diagonal as a percentage."""
    return "–" if v is None else "%.3f %%" % (100 * v)


def table(out, header, rows):
    out.append("| " + " | ".join(header) + " |")
    out.append("|" + "|".join("---" if i == 0 else "---:" for i in range(len(header))) + "|")
    for r in rows:
        out.append("| " + " | ".join(str(c) for c in r) + " |")
    out.append("")


def load_end(results):
    p = os.path.join(results, "load_end")
    return open(p).read().split()[0] if os.path.exists(p) else "–"


def reruns(results):
    """Phases rerun later with `run.sh --resume` (their commit and date), oldest first."""
    p = os.path.join(results, "reruns.json")
    return json.load(open(p)) if os.path.exists(p) else []


def section_machine(out, mach, results):
    out.append("## Machine and run\n")
    elapsed = None
    p = os.path.join(results, "elapsed_seconds")
    if os.path.exists(p):
        elapsed = int(open(p).read().strip())
    s = mach["settings"]
    table(out, ["what", "value"], [
        ["CPU", "%s, %d cores (`nproc`)" % (mach["cpu_model"], mach["nproc"])],
        ["memory", "%s GiB" % mach["memory_gib"]],
        ["system", "%s, kernel %s" % (mach["os"], mach["kernel"])],
        ["compiler", mach.get("compiler") or "–"],
        ["date", mach["date"]],
        ["code", "commit %s, CMake Release build" % mach["commit"]],
        ["mode", "%s: %d repetitions per figure, extraction timings x%d, compare with "
                 "%d area samples per surface" % (mach["mode"], s["reps"], s["extract_reps"],
                                                   s["compare_samples"])],
        ["run time", "%d min" % (elapsed // 60) if elapsed else "–"],
        ["load average", "%.1f at the start, %s at the end (1 min; other jobs shared the "
                         "machine when this exceeds the thread count)"
         % (mach["load_start"][0], load_end(results))],
    ] + [["rerun", "phases %s at commit %s, %s (`run.sh --resume`)%s"
          % (", ".join(r["phases"]), r["commit"], r["date"],
             "; load average %.2g at its start" % r["load"] if "load" in r else "")]
         for r in reruns(results)])


def section_inputs(out, models):
    out.append("## Inputs\n")
    out.append("From the shared scan collection (`../shared/data`). *Open* = the input has "
               "boundary edges (holes); OpenVDB's unsigned variant is run on those too. Leaf "
               "size and depth are scanlod's defaults (from the point spacing).\n")
    rows = []
    for name, m in models.items():
        rows.append([name, m["input_triangles"], "open" if m["open"] else "closed",
                     "%.4g" % m["leaf_size"], m["depth"], m["samples"],
                     m["finest_triangles"]])
    table(out, ["input", "triangles", "surface", "leaf size (world)", "depth", "samples",
                "finest LOD triangles"], rows)


HEADLINE_INTRO = ("Per input the median over the repetitions; ranges are over inputs. Every "
                  "ratio is formed pair by pair within one repetition, then its median taken.")


def anchor_block(rec):
    """The anchor's headline lines between their markers (empty without a record)."""
    lines = headline.anchor_lines(rec)
    if not lines:
        return []
    return (["<!-- fidelity-headline:begin -->"] + ["- " + x for x in lines] +
            ["<!-- fidelity-headline:end -->"])


def section_headline(out, h, mach, rec=None):
    out.append("## Headline figures\n")
    out.append(HEADLINE_INTRO + "\n")
    out.extend(anchor_block(rec))
    for line in h["lines"]:
        out.append("- " + line)
    if mach.get("load_start") and mach["load_start"][0] > 0.5 * mach["nproc"]:
        out.append("- **Shared machine**: the load average was %.1f on %d cores when the run "
                   "started (other jobs running). Absolute times are pessimistic and the "
                   "1 → 2 thread speed-ups understate the code: a second thread only helps "
                   "when a core is free." % (mach["load_start"][0], mach["nproc"]))
    out.append("")


def section_stages(out, models, st, h):
    out.append("## 1. scanlod stage by stage\n")
    out.append("Fresh work folder per repetition, `-s export.fidelity=false` (the fidelity "
               "measurement belongs to the benchmark). Figures from the published "
               "`timings.json`: wall and CPU seconds and peak RSS of each stage's child "
               "process (so they include process start and reading the previous stage's "
               "artifact). Median [min–max] over the repetitions. Throughput = input "
               "triangles / wall seconds. Speed-up = 1-thread / 2-thread wall time, "
               "median of the per-repetition pairs.\n")
    for name in st:
        rows = []
        per = h["stages"][name]
        for stage in stats.STAGES + ["total"]:
            p = per.get(stage)
            if not p:
                continue
            rows.append([stage, spread(p["2"]["seconds"]), spread(p["2"]["cpu_seconds"]),
                         spread(p["2"]["peak_rss_kb"], "%.0f", 1 / 1024.0),
                         num(p["throughput"], "%.3g"), spread(p["1"]["seconds"]),
                         spread(p["speedup"], "%.2f")])
        out.append("**%s** (%d input triangles)\n" % (name, models[name]["input_triangles"]))
        table(out, ["stage", "wall s (2 thr)", "CPU s (2 thr)", "peak RSS MB (2 thr)",
                    "triangles/s (2 thr)", "wall s (1 thr)", "speed-up 1→2"], rows)


def section_octree(out, models, st, oc, h):
    out.append("## 2. Octree levels and OpenVDB (issue 4)\n")
    out.append("Uniform levels cut from the reference build's `octree.slot` (`scanlod "
               "extract --level L`; level 0 = the leaves) next to OpenVDB `meshToVolume` + "
               "`volumeToMesh`, adaptivity 0, with the voxel size equal to that level's "
               "cell (level 0: scanlod's leaf size), signed; unsigned (isovalue one voxel, "
               "a thin closed shell) on open scans. RMS and Hausdorff: symmetric, "
               "`scanlod compare` against the input, in % of the input's bounding-box "
               "diagonal. WT = watertight.\n")
    for name, rows in oc["levels"].items():
        header = ["level", "cell", "triangles", "RMS", "Hausdorff", "WT",
                  "VDB triangles", "VDB RMS", "VDB Hausdorff", "VDB WT"]
        if models[name]["open"]:
            header += ["VDB unsigned triangles", "RMS", "Hausdorff"]
        body = []
        for r in rows:
            s, v = r["scanlod"], r["vdb"].get("signed") or {}
            line = [r["level"], "%.4g" % r["cell_size"], r["triangles"], pct(s["rms"]),
                    pct(s["hausdorff"]), "yes" if s["watertight"] else "no",
                    v.get("triangles", "–"), pct(v.get("rms")), pct(v.get("hausdorff")),
                    {True: "yes", False: "no"}.get(v.get("watertight"), "–")]
            if models[name]["open"]:
                u = r["vdb"].get("unsigned") or {}
                line += [u.get("triangles", "–"), pct(u.get("rms")), pct(u.get("hausdorff"))]
            body.append(line)
        out.append("**%s**\n" % name)
        table(out, header, body)
    out.append("### samples + merge against the OpenVDB remesh at the same voxel size\n")
    out.append("scanlod: samples + merge stage wall time (from oriented points to the "
               "octree, process start and artifact I/O included); OpenVDB: meshToVolume + "
               "volumeToMesh (PLY reading excluded). Ratio = OpenVDB / scanlod per "
               "repetition, median (> 1: scanlod faster). Peak RSS: the larger of the two "
               "stages; OpenVDB's whole process.\n")
    rows = []
    for name, r in h["vdb_time"].items():
        rows.append([name, r["variant"], spread(r["scanlod"]["2"]), spread(r["vdb"]["2"]),
                     spread(r["ratio"]["2"], "%.2f"), spread(r["ratio"]["1"], "%.2f"),
                     spread(r["scanlod_rss"], "%.0f", 1 / 1024.0),
                     spread(r["vdb_rss"], "%.0f", 1 / 1024.0),
                     spread(r["scanlod_speedup"], "%.2f"), spread(r["vdb_speedup"], "%.2f")])
    table(out, ["input", "OpenVDB", "scanlod s (2 thr)", "OpenVDB s (2 thr)",
                "ratio (2 thr)", "ratio (1 thr)", "scanlod RSS MB", "OpenVDB RSS MB",
                "scanlod speed-up 1→2", "OpenVDB speed-up 1→2"], rows)
    d = h.get("depths")
    if d:
        out.append("### Memory per octree depth (%s, 2 threads)\n" % d["input"])
        out.append("`-s octree.depth=N`, the run stopped once merge has committed. Median "
                   "[min–max]. Ratios to the previous depth: memory that followed the "
                   "bounding volume would grow 8x per level, the surface 4x.\n")
        table(out, ["depth", "leaf size", "samples", "samples ratio", "samples s",
                    "samples RSS MB", "merge s", "merge RSS MB", "merge RSS ratio"],
              [[r["depth"], "%.4g" % r["leaf_size"], r["samples"], num(r["samples_ratio"], "%.2f"),
                spread(r["samples_s"]), spread(r["samples_rss"], "%.0f", 1 / 1024.0),
                spread(r["merge_s"]), spread(r["merge_rss"], "%.0f", 1 / 1024.0),
                num(r["rss_ratio"], "%.2f")] for r in d["rows"]])


def section_lod(out, lod, h):
    out.append("## 3. Levels of detail (issue 5)\n")
    out.append("### Table 1 of the paper\n")
    out.append("From each reference build's `report.json` (export stage: LOD P % = P % of the "
               "LOD array's expansions of nodes with surface below them; RMS and Hausdorff "
               "symmetric, % of the diagonal).\n")
    for name, r in lod.items():
        out.append("**%s**\n" % name)
        table(out, ["LOD", "triangles", "vertices", "RMS", "Hausdorff", "watertight",
                    "boundary edges"],
              [["%d %%" % t["lod_percent"], t["triangles"], t["vertices"], pct(t["rms"]),
                pct(t["hausdorff"]), "yes" if t["watertight"] else "no",
                t["boundary_edges"]] for t in r["table1"]])
    out.append("### Fidelity at equal triangle counts\n")
    out.append("At each scanlod level's triangle count: meshoptimizer `meshopt_simplify` of "
               "the input to that count, and OpenVDB `volumeToMesh` at scanlod's leaf size "
               "with the adaptivity (found by bisection, closest try kept; unsigned on open "
               "scans) that lands nearest the count (†: more than 10 % off, the nearest any "
               "adaptivity in [0, 1] reaches). meshoptimizer cannot add triangles: at a count "
               "above the input's it returns the input, and no ratio is given. *meshopt of "
               "finest*: meshopt_simplify of scanlod's own finest level (lod100) to the "
               "count, so both start from the same resampled surface and only the "
               "simplification differs. RMS ratio < 1: scanlod closer.\n")
    for name, r in lod.items():
        body = []
        for e in r["equal_counts"]:
            s, m, v = e["scanlod"], e["meshopt"], e["vdb"]
            f = e.get("meshopt_finest") or {}
            is_input = m.get("is_input")
            off = abs(v["triangles"] - e["triangles"]) > 0.1 * e["triangles"]
            body.append([e["label"], e["triangles"], pct(s["rms"]), pct(s["hausdorff"]),
                         "%d (the input)" % m["triangles"] if is_input else m["triangles"],
                         pct(m["rms"]), pct(m["hausdorff"]),
                         "%d%s (a=%.3g)" % (v["triangles"], " †" if off else "",
                                            v["adaptivity"]), pct(v["rms"]),
                         pct(v["hausdorff"]),
                         num(s["rms"] / m["rms"] if m["rms"] and not is_input else None,
                             "%.2f"),
                         num(s["rms"] / v["rms"] if v["rms"] else None, "%.2f"),
                         pct(f.get("rms")),
                         num(s["rms"] / f["rms"] if f.get("rms") else None, "%.2f")])
        out.append("**%s**\n" % name)
        table(out, ["level", "triangles", "RMS", "Hausdorff", "meshopt tris", "RMS",
                    "Hausdorff", "OpenVDB tris", "RMS", "Hausdorff", "RMS / meshopt",
                    "RMS / OpenVDB", "meshopt of finest: RMS", "RMS / it"], body)
    out.append("### Extraction time per output triangle\n")
    out.append("`scanlod extract MODEL.slod --triangles N --repeat 9`: the O(m) generation, "
               "no file writing. *Warm*: the median of 9 extractions into buffers allocated "
               "once, in the process that loaded the model, each after the CPU caches were "
               "flushed (a viewer renders between two cuts: the model is in memory, not in "
               "cache; the flatness and speed figures are judged on it). *First*: the first "
               "extraction in a fresh process (\"generated in\"), which adds lazy symbol "
               "binding and first-touch page faults of a new output: a fixed 10–30 µs that "
               "dominates the smallest budgets. *Hot*: the same 9 extractions with `--hot`, "
               "back to back after one untimed: no cold start, the model as far into the "
               "caches as its size lets it (a core's own cache holds the small cuts, not "
               "the large cuts of a large model). *Empty cut*: `--expansions 0` (the root "
               "cell alone; its triangle count is given when it draws any), caches flushed: "
               "what a cold start costs. Median [min–max] over the repetitions (see "
               "the run settings above). meshopt: `meshopt_simplify` from the finest mesh "
               "(lod100.ply, already welded) to the same count, one call per level in one "
               "process, simplify time only (none at 100 %: nothing to simplify). Speed-up = "
               "meshopt / scanlod per repetition, median.\n")
    for name, r in h["ladder"].items():
        fit = ("; time ~ m^%.2f (log-log fit over the budgets)" % r["fit"]
               if r.get("fit") else "")
        first = ("; first extraction in a process: %s" % num(r["cold_flatness"], "%.2f")
                 if r.get("cold_flatness") else "")
        if r.get("hot_flatness"):
            first += "; hot: %s" % num(r["hot_flatness"], "%.2f")
        if r.get("empty_cut_seconds"):
            first += "; empty cut: %.1f µs%s" % (1e6 * r["empty_cut_seconds"],
                                                 headline.root_triangles(r))
        out.append("**%s** — max/min of the per-triangle cost%s: %s%s%s\n"
                   % (name, " (warm)" if r.get("warm") else "", num(r["flatness"], "%.2f"),
                      first, fit))
        below = lambda x, key: spread(x.get(key), "%.3g") if x["percent"] < 100 else "–"
        table(out, ["budget", "triangles", "warm (ms)" if r.get("warm") else "generated in (ms)",
                    "ns / triangle", "triangles/s", "first (ms)", "first: ns / triangle",
                    "hot (ms)", "hot: ns / triangle",
                    "meshopt (ms)", "speed-up vs meshopt", "speed-up, first"],
              [["%g %%" % x["percent"], x["triangles"], spread(x["seconds"], "%.3g", 1e3),
                num(x["ns_per_triangle"], "%.0f"), num(x["rate"], "%.3g"),
                spread(x["cold_seconds"], "%.3g", 1e3), num(x["cold_ns_per_triangle"], "%.0f"),
                spread(x.get("hot_seconds"), "%.3g", 1e3),
                num(x.get("hot_ns_per_triangle"), "%.0f"),
                spread(x["meshopt_seconds"], "%.3g", 1e3) if x["percent"] < 100 else "–",
                below(x, "speedup"), below(x, "speedup_cold")]
               for x in r["rows"]])


FIDELITY_HEADING = "## 3a. The fidelity anchor: meshoptimizer 1.3 at the published levels' counts"


def flag(text, bad):
    return "**%s**" % text if bad else text


def section_fidelity(out, rec):
    """Section 3a from a fidelity record (headline.fidelity_record): per method a summary
    row, then per method its builds and its pairs."""
    a = headline.anchor(rec)
    st, v = rec["settings"], rec["settings"]["versions"]
    lim, tol, floor = stats.ANCHOR_RATIO, stats.BUDGET_TOLERANCE, stats.PART_FLOOR
    out.append(FIDELITY_HEADING + "\n")
    out.append(
        "What users measure us by: the newest meshoptimizer's error at the same triangle "
        "count. From `scripts/bench/run.sh --phases fidelity` (lib/fidelity.py; "
        "docs/fidelity.md, \"The anchor\"). Per input, one `scanlod run` (%d threads, fresh "
        "work folder) with the default config plus `[export] budgets` = `pP:N` for P = %s %% "
        "of the input's triangles; *each method alone* adds `-s lod.method=M`. The level "
        "each budget published (report.json's `file`) is measured against the input by "
        "`scanlod compare` (%d area samples, the export's setting), and so are, at that "
        "level's triangle count and from the whole input: meshoptimizer %s "
        "`simplifyWithUpdate` (*update*) and `simplify` (npm, `peers/meshopt_js.mjs`: "
        "flags %s, target_error %s relative, i.e. no limit; welded at equal positions only) "
        "and meshoptimizer %s `meshopt_simplify` (Debian, `peers/meshopt_lod.c`). RMS and "
        "Hausdorff: symmetric, %% of the input's diagonal; ratio = scanlod / anchor (< 1: "
        "scanlod closer). Budget error = |triangles - budget| / budget. Largest part = the "
        "largest connected part's share of the level's area. One run per figure (the "
        "fidelity figures are deterministic; times are of that one run: the stages' wall "
        "seconds and peak RSS from timings.json). **Bold**: a ratio above %.1f, a budget "
        "missed by more than %d %%, the largest part below %d %% where the input's is at "
        "least that, not watertight where the input is.\n"
        % (st["threads"], ", ".join("%g" % b for b in st["budgets"]), st["samples"],
           v["meshoptimizer_js"], ", ".join("`%s`" % f for f in st["js_flags"]),
           st["js_target_error"], v["meshoptimizer"], lim,
           round(100 * tol), round(100 * floor)))
    rows = []
    for m, r in a.items():
        s = r["summary"]
        rr = s["rms_ratio"]
        rows.append([r["label"], "%s, %s" % (r["run"]["commit"], r["run"]["date"]), s["pairs"],
                     num(rr["median"], "%.2f"),
                     "%s (%s)" % (num(rr["max"], "%.2f"), pair_name(r["worst"][0]))
                     if r["worst"] else "–",
                     "%d" % s["rms_above"], num(s["hausdorff_ratio"]["median"], "%.2f"),
                     num(s["rms_ratio_simplify"]["median"], "%.2f"),
                     num(s["rms_ratio_mo18"]["median"], "%.2f"),
                     "%s / %d" % (num(100 * s["budget_error"]["median"]
                                      if s["budget_error"]["n"] else None, "%.2f %%"),
                                  s["budget_misses"]),
                     "%d of %d" % (s["part_losses"], s["part_pairs"]),
                     "%d of %d" % (s["not_watertight"], s["watertight_pairs"]),
                     "%s (%s)" % (num(r["build_seconds"]["median"], "%.2f"),
                                  num(r["build_total"], "%.0f")),
                     num(r["peak_rss_kb"]["max"] / 1024.0 if r["peak_rss_kb"]["n"] else None,
                         "%.0f"),
                     ", ".join("%s %s" % kv for kv in r["not_built"].items()) or "–"])
    table(out, ["levels", "run", "pairs", "RMS / update", "max", "> %.1fx" % lim,
                "Hausdorff / update", "RMS / simplify", "RMS / %s" % v["meshoptimizer"],
                "budget error median / misses", "largest part < %d %%" % round(100 * floor),
                "not watertight", "build s median (sum)", "peak MB", "not built"], rows)
    for m, r in a.items():
        run = r["run"]
        details = m != "default"
        title = r["label"][0].upper() + r["label"][1:]
        out.append("<details><summary><b>%s</b>: every pair</summary>\n" % title
                   if details else "### %s\n" % title)
        out.append("Commit %s, %s, load average %.1f at its start; the phase took %s s%s.\n"
                   % (run["commit"], run["date"], run["load_start"], num(run["seconds"], "%.0f"),
                      "; anchors taken from the cache where one at the same count, else "
                      "within 1 %, was there (†)" if run.get("reuse_peers") else ""))
        table(out, ["input", "triangles", "input: watertight, largest part", "build s",
                    "CPU s", "peak RSS MB", "wall s", "status"],
              [[n, rec["inputs"][n]["triangles"],
                "%s, %.1f %%" % ("yes" if rec["inputs"][n]["watertight"] else "no",
                                 100 * (rec["inputs"][n]["largest_area"] or 0)),
                num(it.get("build_seconds"), "%.1f"), num(it.get("cpu_seconds"), "%.1f"),
                num(it["peak_rss_kb"] / 1024.0 if it.get("peak_rss_kb") else None, "%.0f"),
                num(it.get("wall_seconds"), "%.1f"),
                it["status"] if it["status"] == "ok" else "**%s**" % it["status"]]
               for n, it in run["items"].items()])
        body = []
        for p in r["pairs"]:
            o, u = p["ours"], p["update"] or {}
            facts = rec["inputs"][p["input"]]
            off = " †" if u and u.get("count") != p["triangles"] else ""
            body.append([p["input"], "%g %%" % p["percent"], p["budget"],
                         "%d%s" % (p["triangles"], " (clamped)" if p.get("clamped") else ""),
                         flag(num(100 * p["budget_error"], "%.2f %%"),
                              p["budget_error"] > tol),
                         pct(o["rms"]), pct(u.get("rms")),
                         flag(num(p["rms_ratio"], "%.2f") + off,
                              (p["rms_ratio"] or 0) > lim),
                         pct(o["hausdorff"]), pct(u.get("hausdorff")),
                         flag(num(p["hausdorff_ratio"], "%.2f"),
                              (p["hausdorff_ratio"] or 0) > lim),
                         num(p["rms_ratio_simplify"], "%.2f"), num(p["rms_ratio_mo18"], "%.2f"),
                         flag("%s (%.1f %%)" % (o["components"], 100 * (o["largest_area"] or 0)),
                              (facts.get("largest_area") or 0) >= floor and
                              (o["largest_area"] or 0) < floor),
                         flag("yes" if o["watertight"] else "no",
                              facts.get("watertight") and not o["watertight"])])
        table(out, ["input", "budget", "budget triangles", "triangles", "budget error", "RMS",
                    "update RMS", "RMS / update", "Hausdorff", "update Hausdorff",
                    "Hausdorff / update", "RMS / simplify", "RMS / %s" % v["meshoptimizer"],
                    "parts (largest)", "watertight"], body)
        if details:
            out.append("</details>\n")


def pair_name(p):
    return headline.pair_name(p)


def section_growth(out, h):
    g = h.get("growth")
    if not g:
        return
    out.append("## 4. Cost growth with input size\n")
    out.append("`gen_surface`: a closed noisy torus of N triangles (binary PLY); default "
               "config, 2 threads, fidelity off. Median [min–max] where repeated (n = "
               "repetitions). Fitted exponent b of time ~ N^b (least squares on log-log).\n")
    header = ["triangles", "n"] + stats.STAGES + ["total s", "peak RSS MB"]
    table(out, header, [[r["triangles"], r["n"]] +
                        [spread(r["stages"].get(s, {}).get("seconds")) for s in stats.STAGES] +
                        [spread(r["total"]), num(r["peak_rss_kb"] / 1024.0, "%.0f")]
                        for r in g["rows"]])
    out.append("Fitted exponents: " + ", ".join(
        "%s %s" % (k, num(v, "%.2f")) for k, v in g["slopes"].items()) + ".\n")
    for s in g["skipped"]:
        out.append("- Skipped %d triangles: %s." % (s["target"], s["reason"]))
    out.append("")
    planned = [r for r in g["rows"] if r.get("plan") and "peak_rss_mb" in r["plan"]]
    if planned:
        out.append("`scanlod plan` before each size (the pre-flight estimate, "
                   "cli/plan.c) against the measured medians; ratio = plan / "
                   "measured (issue 14 asks for memory within 30 %, time within 50 %).\n")
        rows = []
        for r in planned:
            p = r["plan"]
            mem = r["peak_rss_kb"] / 1024.0
            secs = r["total"]["median"]
            disk = (r.get("disk_bytes") or {}).get("median")
            disk_plan = p["work_mb"] + p["published_mb"]
            rows.append([r["triangles"], num(p["peak_rss_mb"], "%.0f"), num(mem, "%.0f"),
                         num(p["peak_rss_mb"] / mem if mem else None, "%.2f"),
                         num(p["seconds"], "%.1f"), num(secs, "%.1f"),
                         num(p["seconds"] / secs if secs else None, "%.2f"),
                         num(disk_plan, "%.0f"),
                         num(disk / 1e6 if disk else None, "%.0f"),
                         num(disk_plan / (disk / 1e6) if disk else None, "%.2f")])
        table(out, ["triangles", "plan MB", "peak MB", "ratio", "plan s", "took s", "ratio",
                    "plan disk MB", "disk MB", "ratio"], rows)
        out.append("")


def section_parts(out, results):
    """The parts phase (lib/parts.py): one scan by three workers as parts, one killed."""
    path = os.path.join(results, "parts.json")
    if not os.path.exists(path):
        return
    with open(path) as f:
        p = json.load(f)
    out.append("### 4a. One scan built by three workers as parts (issue 14)\n")
    if p.get("skipped"):
        out.append("Skipped: %s.\n" % p["skipped"])
        return
    t = p["split_timings"]["samples"]
    parts = t.get("parts", [])
    starts = p.get("part_starts", {})
    killed = p.get("killed") or {}
    w = p["whole_stages"]
    out.append(
        "`gen_surface` torus of %d triangles (%.0f MB PLY), fidelity off. One `scanlod run` "
        "at 2 threads, against `scanlod run` + 2 `scanlod worker`s at 1 thread each on the "
        "same input with `[queue] part_mb = %.1f` (the samples stage in %d parts, "
        "docs/engine.md \"Parts\"), a third worker killed -9 while it held %s%s. "
        "One run each; parts numbered from 1 as the log says (ticket `#part-0000` is part "
        "1).\n" % (p["triangles"], p["ply_bytes"] / 1e6, p["part_mb"], len(parts),
                   killed.get("part", "no part"),
                              "" if killed.get("inside", True) else " (it had just finished it)"))
    rows = [["one process, 2 threads", num(p["whole_seconds"], "%.0f"),
             num(w["samples"]["seconds"], "%.1f"),
             num(w["samples"]["peak_rss_kb"] / 1024.0, "%.0f"), "-"],
            ["3 workers as parts, 1 killed", num(p["split_seconds"], "%.0f"),
             "%s join + parts %s" % (num(t["seconds"], "%.1f"),
                                     " / ".join(num(x["seconds"], "%.1f") for x in parts)),
             "%s join, parts %s" % (num(t["peak_rss_kb"] / 1024.0, "%.0f"),
                                    num(max([x["peak_rss_kb"] for x in parts] or [0]) / 1024.0,
                                        "%.0f")),
             ", ".join("%s: %d" % (k, len(v)) for k, v in sorted(starts.items(),
                                                                 key=lambda kv: int(kv[0])))]]
    table(out, ["build", "wall s", "samples stage s", "samples peak MB", "starts per part"],
          rows)
    i = p["identical"]
    out.append("Exit codes of the run and the surviving worker: %s; a run afterwards: %s. "
               "Byte-identical to the one process: artifacts %s (%d files), published files "
               "%s (%d files).\n" % (", ".join(map(str, p["exit_codes"])),
                                      p["after"]["stdout"] or p["after"]["exit"],
                                      "yes" if i["artifacts"] else "NO",
                                      i["artifact_files"],
                                      "yes" if i["published"] else "NO",
                                      i["published_files"]))


CLUSTER_HEADING = "## 5. Clustering with bounded error (paper 2, issue 13)"


def section_shapes(out, results):
    """The shapes phase (lib/shapes.py): the plan on slivers and a soup."""
    path = os.path.join(results, "shapes.json")
    if not os.path.exists(path):
        return
    with open(path) as f:
        shapes = json.load(f)["shapes"]
    out.append("### 4b. The plan on hostile shapes (issue 34)\n")
    out.append("`gen_surface --aspect 16` (slivers: the torus's triangles 16 times longer "
               "than wide) and `--soup` (triangles that share no vertex); `scanlod plan "
               "--json`, then one run at 2 threads, default config, fidelity off. The plan "
               "reads such a scan's geometry (cli/plan_shape.c) and scales the octree "
               "stages by the samples it expects; ratio = plan / measured.\n")
    rows = []
    for s in shapes:
        p, st = s["plan"], s["stages"]
        peak = max(v["peak_rss_kb"] for v in st.values()) / 1024.0
        stage = max(st, key=lambda k: st[k]["peak_rss_kb"])
        took = sum(v["seconds"] for v in st.values())
        shape = p.get("shape", {})
        rows.append([s["name"], s["triangles"], num(shape.get("samples"), "%.0f"), s["samples"],
                     num(p["peak_rss_mb"], "%.0f"), "%s (%s)" % (num(peak, "%.0f"), stage),
                     num(p["peak_rss_mb"] / peak, "%.2f"), num(p["seconds"], "%.0f"),
                     num(took, "%.0f"), num(p["seconds"] / took if took else None, "%.2f")])
    table(out, ["shape", "triangles", "plan samples", "samples", "plan MB", "peak MB (stage)",
                "ratio", "plan s", "took s", "ratio"], rows)
    out.append("")


def section_cluster(out, results, dest):
    """bench_cluster.sh's tables (its own run, BUILD/bench-results/cluster/cluster.md,
    beside this run's folder), else the section the page already has: run.sh does not
    run that benchmark, and regenerating the page must not drop its figures."""
    md = os.path.join(os.path.dirname(os.path.abspath(results)), "cluster", "cluster.md")
    body = None
    if os.path.exists(md):
        body = ("From `scripts/bench/bench_cluster.sh` (not part of `run.sh`; its own run, "
                "docs/clustering.md explains the method and the bound):\n\n" +
                open(md).read())
    elif os.path.exists(dest):
        old = open(dest).read()
        at = old.find(CLUSTER_HEADING)
        if at >= 0:
            end = old.find("\n## ", at + len(CLUSTER_HEADING))
            body = old[at + len(CLUSTER_HEADING):end if end >= 0 else len(old)].strip() + "\n"
    if body:
        out.append(CLUSTER_HEADING + "\n")
        out.append(body.strip() + "\n")


def section_plots(out):
    out.append("## Plots\n")
    for f, what in [("error_vs_triangles.png", "RMS error against triangle count per input: "
                     "scanlod LODs, meshoptimizer and OpenVDB adaptive at the same counts"),
                    ("stage_times.png", "stage time breakdown per input (2 threads, medians)"),
                    ("extract_cost.png", "extraction time per output triangle against the "
                     "budget"),
                    ("growth.png", "cost growth against input size (log-log)")]:
        out.append("![%s](bench/%s)\n\n*%s*\n" % (what, f, what))


def fidelity_record(results, dest):
    """The fidelity record (docs/bench/fidelity.json beside dest), with RESULTS'
    fidelity.json merged in and saved when that run finished all the inputs and budgets;
    the run of a subset is written to RESULTS/fidelity.md instead. Returns the record
    (None when there is none) and that subset's markdown path (else None)."""
    path = os.path.join(os.path.dirname(os.path.abspath(dest)), "bench", "fidelity.json")
    rec = headline.read_record(path)
    run_path = os.path.join(results, "fidelity.json")
    if not os.path.exists(run_path):
        return rec, None
    with open(run_path) as f:
        run = json.load(f)
    new = headline.fidelity_record(run)
    if not (run.get("complete") and "seconds" in run):
        md = os.path.join(results, "fidelity.md")
        out = ["# Fidelity anchor: %s (a subset: %s; budgets %s %%)\n"
               % (results, ", ".join(run["settings"]["inputs"]),
                  ", ".join("%g" % b for b in run["settings"]["budgets"]))]
        out += ["- " + x for x in headline.anchor_lines(new)] + [""]
        section_fidelity(out, new)
        with open(md, "w") as f:
            f.write("\n".join(out).rstrip() + "\n")
        return rec, md
    os.makedirs(os.path.dirname(path), exist_ok=True)
    rec = headline.merge_record(rec, new)
    headline.write_record(path, rec)
    return rec, None


def fidelity_block(rec):
    """Section 3a between its markers, as lines."""
    out = ["<!-- fidelity:begin -->"]
    section_fidelity(out, rec)
    while out[-1] == "":
        out.pop()
    return out + ["<!-- fidelity:end -->", ""]


def between(page, marker, lines):
    """page with the block between <!-- marker:begin --> and <!-- marker:end -->
    replaced by lines (markers included); None when the page has no such block."""
    a, b = "<!-- %s:begin -->" % marker, "<!-- %s:end -->" % marker
    i, j = page.find(a), page.find(b)
    if i < 0 or j < 0:
        return None
    return page[:i] + "\n".join(lines).rstrip() + page[j + len(b):]


def splice_fidelity(results, dest):
    """Section 3a and the anchor's headline lines replaced in the page (inserted the first
    time: the lines at the top of the headline list, the section before section 4), the
    lines they supersede dropped; the rest of the page as it was."""
    rec, partial = fidelity_record(results, dest)
    if partial:
        print("report: a subset of the inputs or budgets: %s written, %s unchanged"
              % (partial, dest))
        return
    if not rec:
        print("report: no fidelity results in %s" % results)
        return
    with open(dest) as f:
        page = f.read()
    sec = fidelity_block(rec)
    spliced = between(page, "fidelity", sec)
    if spliced is None:
        at = page.find("\n## 4. ")
        at = len(page) if at < 0 else at + 1
        spliced = page[:at] + "\n".join(sec) + "\n" + page[at:]
    page = spliced
    lines = anchor_block(rec)
    spliced = between(page, "fidelity-headline", lines)
    if spliced is None:
        intro = HEADLINE_INTRO + "\n\n"
        at = page.find(intro)
        if at < 0:
            raise SystemExit("report: no headline section in %s" % dest)
        at += len(intro)
        spliced = page[:at] + "\n".join(lines) + "\n" + page[at:]
    page = "".join(l for l in spliced.splitlines(True)
                   if not any(l.startswith("- " + s) for s in headline.SUPERSEDED))
    peers = "from Debian packages."   # the opening's list of peers, as main() writes it
    if peers in page and "the fidelity anchor, meshoptimizer" not in page:
        page = page.replace(peers, "from Debian packages; the fidelity anchor, meshoptimizer "
                            "%s, from npm." % rec["settings"]["versions"]["meshoptimizer_js"], 1)
    with open(dest + ".tmp", "w") as f:
        f.write(page)
    os.replace(dest + ".tmp", dest)
    print("report: section 3a and the anchor's headline lines of %s from %s"
          % (dest, results))


def main():
    if sys.argv[1] == "--fidelity":
        splice_fidelity(sys.argv[2], sys.argv[3])
        return
    results, dest = sys.argv[1], sys.argv[2]
    d = headline.load_all(results)
    mach, models, versions = d["machine"], d["models"], d["versions"]
    st, oc, lod = d["stages"], d["octree"], d["lod"]
    h = headline.derive(models, st, oc, lod, d["growth"], versions)
    rec, partial = fidelity_record(results, dest)
    if partial:
        print("report: the fidelity phase ran on a subset: %s (section 3a unchanged)" % partial)
    out = ["# Benchmarks\n",
           "Generated by `scripts/bench/run.sh%s`; do not edit by hand (rerun it). Raw "
           "figures: `BUILD/bench-results/`. How each figure is measured is said above "
           "its table; peers: OpenVDB %s and meshoptimizer %s from Debian packages%s.\n"
           % (" --quick" if mach["mode"] == "quick" else "", versions["openvdb"],
              versions["meshoptimizer"],
              "; the fidelity anchor, meshoptimizer %s, from npm"
              % rec["settings"]["versions"]["meshoptimizer_js"] if rec else "")]
    section_machine(out, mach, results)
    section_inputs(out, models)
    section_headline(out, h, mach, rec)
    # Figures that come from other benchmarks or from measurements by hand live in
    # docs/bench/NAME.md and are kept in their places between markers: a rerun of this
    # benchmark rewrites its own tables and never loses them.
    kept_dir = os.path.join(os.path.dirname(os.path.abspath(dest)), "bench")

    def kept(name, marker=None):
        path = os.path.join(kept_dir, name + ".md")
        if os.path.exists(path):
            with open(path) as f:
                out.extend(["<!-- %s:begin -->" % (marker or name), f.read().rstrip(),
                            "<!-- %s:end -->" % (marker or name), ""])

    for name, fn in (("stages", lambda: section_stages(out, models, st, h)),
                     ("octree", lambda: section_octree(out, models, st, oc, h)),
                     ("lod", lambda: section_lod(out, lod, h))):
        if {"stages": st, "octree": oc, "lod": lod}[name] is None:
            out.append("*Phase %s did not complete in this run.*\n" % name)
        else:
            fn()
    kept("qef-notes")        # docs/lod.md's quadric vertices, measured with fidelity.py
    if rec:                  # section 3a, from docs/bench/fidelity.json
        out.extend(fidelity_block(rec))
    section_growth(out, h)
    kept("growth-notes")     # reruns of the growth inputs by hand
    section_parts(out, results)
    section_shapes(out, results)
    section_cluster(out, results, dest)
    section_plots(out)
    # The segment method's section comes from its own benchmark (bench_segment.sh), which
    # keeps it in docs/bench/segment-section.md (and a partial run's in segment-update.md).
    kept("segment-section", "segment")
    kept("segment-update")   # a partial run's, after it
    kept("model-section")    # section 7: the model file's size and cost to open
    with open(dest + ".tmp", "w") as f:
        f.write("\n".join(out).rstrip() + "\n")
    os.replace(dest + ".tmp", dest)


if __name__ == "__main__":
    main()
