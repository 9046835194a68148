"""Render docs/benchmarks.md from a results folder.

usage: report.py RESULTS_DIR OUT.md
Reads machine, models, stages, octree, lod, growth (.json; a missing phase is said so).
Derived figures (medians, pair ratios, slopes) come from headline.py.
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


def section_headline(out, h, mach):
    out.append("## Headline figures\n")
    out.append("Per input the median over the repetitions; ranges are over inputs. Every "
               "ratio is formed pair by pair within one repetition, then its median taken.\n")
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


def main():
    results, dest = sys.argv[1], sys.argv[2]
    d = headline.load_all(results)
    mach, models, versions = d["machine"], d["models"], d["versions"]
    st, oc, lod = d["stages"], d["octree"], d["lod"]
    h = headline.derive(models, st, oc, lod, d["growth"])
    out = ["# Benchmarks\n",
           "Generated by `scripts/bench/run.sh%s`; do not edit by hand (rerun it). Raw "
           "figures: `BUILD/bench-results/`. How each figure is measured is said above "
           "its table; peers: OpenVDB %s and meshoptimizer %s from Debian packages.\n"
           % (" --quick" if mach["mode"] == "quick" else "", versions["openvdb"],
              versions["meshoptimizer"])]
    section_machine(out, mach, results)
    section_inputs(out, models)
    section_headline(out, h, mach)
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
    section_growth(out, h)
    kept("growth-notes")     # reruns of the growth inputs by hand
    section_parts(out, results)
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
