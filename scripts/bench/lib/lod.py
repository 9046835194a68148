"""Phase 3 (issue 5): Table 1, fidelity at equal triangle counts, extraction cost.

Per input of ctx.lod_models, from the reference build:
- Table 1: the LOD 20..100 % levels of report.json (triangles, vertices, RMS, Hausdorff).
- Equal counts: the triangle counts of those levels plus extra budgets (ctx.curve_extra,
  fractions of the finest, cut with `extract --triangles`). At each count, scanlod's
  mesh, meshopt_simplify of the input to the same count (and of scanlod's finest level,
  below its count), and OpenVDB volumeToMesh at
  scanlod's leaf size with the adaptivity found by bisection (count falls as adaptivity
  rises; the closest of the tries is kept, unsigned on open scans), all measured by
  `scanlod compare` against the input.
- Extraction ladder: `extract --triangles N --repeat WARM_REPEAT` for N = ctx.budgets
  percent of the finest, ctx.extract_reps times each. Two timings of the O(m) generation
  (no file writing) per call: "generated in", the first extraction in a fresh process
  (cold: lazy symbol binding, first-touch page faults of a new output), and the median of
  WARM_REPEAT more into buffers allocated once, each after a cache flush, as a viewer
  holding a model extracts between frames (warm process, cold caches). A second call per
  budget adds `--hot`: the same cuts back to back, the model as far into the caches as
  its size lets it (the work itself, without a cold start). And per repetition the empty
  cut (`--expansions 0 --repeat`, caches flushed: the root cell alone, whose triangle
  count is kept): the fixed cost of a cold start. Per
  repetition meshopt_simplify from the finest mesh (lod100.ply) to
  the same counts (one call per level in one process, as warm as ours), so each speed
  ratio is a pair from one repetition.
Writes RESULTS/lod.json.
"""
import os
import sys

import stats
from common import Ctx, compare, extract, log, meshopt, vdb

WARM_REPEAT = 9


def vdb_search(ctx, name, m, targets, work):
    """{target: closest OpenVDB try} with fidelity; tries shared between targets."""
    ref = ctx.input_ply(name)
    unsigned = m["open"]
    tried = {}   # adaptivity -> triangles; each try's mesh is kept as vdb_a<A>.ply
    mesh = lambda a: os.path.join(work, "vdb_a%g.ply" % a)

    def attempt(a):
        if a not in tried:
            tried[a] = vdb(ctx, ref, mesh(a), m["leaf_size"], a, unsigned, 2)["triangles"]
        return tried[a]

    out = {}
    for t in targets:
        for _ in range(ctx.vdb_search_steps):
            best = stats.closest([{"triangles": n} for n in tried.values()], t)
            if best and abs(best["triangles"] - t) <= 0.02 * t:
                break
            a = stats.next_adaptivity(tried, t)
            if a is None:
                break
            attempt(a)
        cands = [{"adaptivity": a, "triangles": n} for a, n in tried.items()]
        best = stats.closest(cands, t)
        row = compare(ctx, ref, mesh(best["adaptivity"]))
        row["adaptivity"] = best["adaptivity"]
        row["unsigned"] = unsigned
        out[str(t)] = row
    return out, tried


def equal_counts(ctx, name, m, work):
    ref = ctx.input_ply(name)
    points = []   # scanlod meshes: (triangles, ply)
    for lv in m["levels"]:
        if lv.get("lod_percent") is not None:
            # A level identical to an earlier one is published under that one's name.
            points.append((lv["triangles"], os.path.join(os.path.dirname(m["slod"]),
                                                         lv.get("file", lv["name"]) + ".ply"),
                           lv["name"]))
    for f in ctx.curve_extra:
        n = max(8, int(round(f * m["finest_triangles"])))
        ply = os.path.join(work, "budget_%d.ply" % n)
        e = extract(ctx, m["slod"], ply, "--triangles", n)
        points.append((e["triangles"], ply, "%g%%" % (100 * f)))
    points.sort()
    rows = []
    targets = [p[0] for p in points]
    # meshopt_simplify cannot add triangles: a count above the input's is the input.
    mo = meshopt(ctx, ref, [min(t, m["input_triangles"]) for t in targets],
                 os.path.join(work, "mo"))
    # meshopt_simplify of scanlod's own finest level too: the same starting surface as
    # the LODs, so what differs is the simplification alone.
    below = [t for t in targets if t < m["finest_triangles"]]
    mf = {lv["target"]: lv["output"] for lv in
          meshopt(ctx, m["finest_ply"], below, os.path.join(work, "mf"))["levels"]} \
        if below else {}
    vd, tried = vdb_search(ctx, name, m, targets, work)
    for (n, ply, label), mo_level in zip(points, mo["levels"]):
        row = {"label": label, "triangles": n, "scanlod": compare(ctx, ref, ply),
               "meshopt": compare(ctx, ref, mo_level["output"]), "vdb": vd[str(n)],
               "meshopt_finest": compare(ctx, ref, mf[n]) if n in mf else None}
        row["meshopt"]["reached"] = mo_level["reached"]
        row["meshopt"]["is_input"] = n >= m["input_triangles"]   # nothing to simplify
        rows.append(row)
        log("lod: %s equal counts at %d triangles" % (name, n))
    return rows, {str(a): n for a, n in sorted(tried.items())}


def ladder(ctx, name, m, work):
    finest = m["finest_triangles"]
    budgets = [(p, max(1, int(round(p / 100.0 * finest)))) for p in ctx.budgets]
    runs = {p: [] for p, _ in budgets}
    warm = {p: [] for p, _ in budgets}
    hot = {p: [] for p, _ in budgets}
    mo_runs = {p: [] for p, _ in budgets}
    counts, empty, root_triangles = {}, [], 0
    out = os.path.join(work, "ladder.ply")
    for rep in range(ctx.extract_reps):
        for p, n in budgets:
            e = extract(ctx, m["slod"], out, "--triangles", n, "--repeat", WARM_REPEAT)
            runs[p].append(e["seconds"])
            warm[p].append(e["warm_seconds"])
            counts[p] = e["triangles"]
            hot[p].append(extract(ctx, m["slod"], out, "--triangles", n, "--repeat",
                                  WARM_REPEAT, "--hot")["warm_seconds"])
        root = extract(ctx, m["slod"], out, "--expansions", 0, "--repeat", WARM_REPEAT)
        empty.append(root["warm_seconds"])
        root_triangles = root["triangles"]
        # meshopt from the finest mesh to each count below it (at the finest count it
        # would have nothing to do), paired with this repetition's extractions.
        simplify = [p for p, _ in budgets if p < 100 and counts[p] < finest]
        if rep < ctx.reps and simplify:
            mo = meshopt(ctx, m["finest_ply"], [counts[p] for p in simplify])
            for p, lv in zip(simplify, mo["levels"]):
                mo_runs[p].append(lv["seconds"])
    rows = []
    for p, n in budgets:
        k = len(mo_runs[p])
        rows.append({"percent": p, "budget": n, "triangles": counts[p],
                     "seconds": stats.summary(runs[p]),
                     "warm_seconds": stats.summary(warm[p]),
                     "hot_seconds": stats.summary(hot[p]),
                     "meshopt_seconds": stats.summary(mo_runs[p]),
                     "speedup": stats.summary(stats.pair_ratios(mo_runs[p], warm[p][:k])),
                     "speedup_cold": stats.summary(stats.pair_ratios(mo_runs[p], runs[p][:k]))})
    log("lod: %s extraction ladder done" % name)
    return rows, stats.summary(empty), root_triangles


def main():
    ctx = Ctx(sys.argv[1])
    models = ctx.load("models")
    out = {}
    for name in ctx.lod_models:
        m = models[name]
        work = ctx.scratch_dir("lod", name)
        table1 = [{k: lv.get(k) for k in ("lod_percent", "triangles", "vertices", "rms",
                                           "hausdorff", "watertight", "boundary_edges")}
                  for lv in m["levels"] if lv.get("lod_percent") is not None]
        rows, tried = equal_counts(ctx, name, m, work)
        steps, empty, root_triangles = ladder(ctx, name, m, work)
        out[name] = {"table1": table1, "equal_counts": rows, "vdb_tries": tried,
                     "ladder": steps, "empty_cut_seconds": empty,
                     "root_cut_triangles": root_triangles}
        ctx.save("lod", out)
    ctx.save("lod", out)


if __name__ == "__main__":
    main()
