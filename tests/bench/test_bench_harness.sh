#!/usr/bin/env bash
# The benchmark harness (scripts/bench/lib) on canned inputs, no build and no runs, so it
# does not rot: parsing of timings.json, `extract` and `compare --json` output; medians,
# pair ratios, log-log slopes, the OpenVDB adaptivity bisection, the per-triangle cost;
# the fidelity anchor's budgets, cache look-ups, pairs, summary and record; then
# docs/benchmarks.md (and the plots, when gnuplot is there) rendered from a mini results
# folder, checked for the figures it must show, and the fidelity phase's section spliced
# into a page alone.
set -euo pipefail
root=${SCANLOD_SOURCE_DIR:-$(cd "$(dirname "$0")/../.." && pwd)}
lib=$root/scripts/bench/lib
tmp=$(mktemp -d "${TMPDIR:-/tmp}/bench-harness.XXXXXX")
trap 'rm -rf "$tmp"' EXIT
passed=0 failed=0
check() { # check "what" command...
  local what=$1; shift
  if "$@"; then passed=$((passed + 1)); else failed=$((failed + 1)); echo "FAIL: $what" >&2; fi
}
export PYTHONDONTWRITEBYTECODE=1
py() { PYTHONPATH=$lib python3 -c "$1"; }
eq() { [ "$1" = "$2" ] || { echo "  got '$1', want '$2'" >&2; return 1; }; }
has() { grep -qF -- "$2" "$1" || { echo "  '$2' not in $1" >&2; return 1; }; }

# --- statistics ----------------------------------------------------------------------
check "median, min, max of an odd list" \
  eq "$(py 'import stats; s = stats.summary([3, 1, 2, 10, 5]); print(s["median"], s["min"], s["max"], s["n"])')" "3.0 1.0 10.0 5"
check "median of an even list, None skipped" \
  eq "$(py 'import stats; print(stats.summary([4, None, 1, 3, 2])["median"])')" "2.5"
check "empty summary" eq "$(py 'import stats; print(stats.summary([None])["median"])')" "None"
check "pair ratios skip missing and zero" \
  eq "$(py 'import stats; print(stats.pair_ratios([2, 9, 6, 1], [1, 3, 0, None]))')" "[2.0, 3.0]"
check "log-log slope of 3 x^1.5" \
  eq "$(py 'import stats; print(round(stats.loglog_slope([1e3, 1e4, 1e5], [3 * x ** 1.5 for x in (1e3, 1e4, 1e5)]), 6))')" "1.5"
check "slope needs two sizes" eq "$(py 'import stats; print(stats.loglog_slope([5], [2]))')" "None"
check "growth words" \
  eq "$(py 'import stats; print(stats.growth_word(1.02), stats.growth_word(1.4), stats.growth_word(0.5))')" "about linear super-linear sub-linear"
check "per-triangle cost and its max/min" \
  eq "$(py 'import stats; r, f = stats.per_triangle([{"triangles": 100, "seconds": 2e-5}, {"triangles": 1000, "seconds": 1.5e-4}]); print(round(r[0]["ns_per_triangle"]), round(r[1]["ns_per_triangle"]), round(f, 3))')" "200 150 1.333"
check "closest candidate is relative" \
  eq "$(py 'import stats; print(stats.closest([{"triangles": 90}, {"triangles": 130}, {"triangles": 0}], 100)["triangles"])')" "90"

# The bisection on a monotone count(a) = 1000 (1 - 0.9 a) reaches 550 (a = 0.5), and
# gives up at once on a target that even adaptivity 1 (100 triangles) cannot reach.
bisect=$(py '
import stats
def search(target, steps):
    tried = {}
    for _ in range(steps):
        a = stats.next_adaptivity(tried, target)
        if a is None:
            break
        tried[a] = round(1000 * (1 - 0.9 * a))
    return tried
best = stats.closest([{"a": a, "triangles": n} for a, n in search(550, 12).items()], 550)
low = search(50, 5)
print(best["a"], sorted(low), stats.next_adaptivity(low, 50))')
check "adaptivity bisection converges, stops below reach" eq "$bisect" "0.5 [1.0] None"

# --- parsing -------------------------------------------------------------------------
check "extract from a model" eq "$(py 'import stats; d = stats.parse_extract("expansions 86 of 19538: 698 triangles, 355 vertices, max error 0.0335108, generated in 0.000430 s -> t.ply"); print(d["triangles"], d["vertices"], d["seconds"], d["expansions"])')" "698 355 0.00043 86"
check "extract with warm repeats" eq "$(py 'import stats; d = stats.parse_extract("expansions 13 of 2376: 58 triangles, 31 vertices, max error 1.83995, generated in 0.0000263 s, then 15 more in median 0.0000041 s (min 0.0000037 s) -> x.ply"); print(d["seconds"], d["warm_seconds"])')" "2.63e-05 4.1e-06"
check "extract of an octree level" eq "$(py 'import stats; d = stats.parse_extract("level 2: 4272 triangles, 2150 vertices -> l2.ply"); print(d["triangles"], d["seconds"])')" "4272 None"
check "garbage extract output is an error" \
  eq "$(py 'import stats
try:
    stats.parse_extract("scanlod extract: no such file")
    print("parsed")
except ValueError:
    print("error")')" "error"
cat >"$tmp/timings.json" <<'EOF'
{
  "item": "x", "host": "h", "run": "r",
  "stages": {
    "range": {"seconds":0.101,"cpu_seconds":0.086,"peak_rss_kb":52932,"threads":2}
,
    "merge": {"seconds":0.385,"cpu_seconds":0.372,"peak_rss_kb":84836,"threads":2}

  }
}
EOF
check "timings.json as the engine writes it" \
  eq "$(py "import stats; t = stats.load_timings('$tmp/timings.json'); print(t['merge']['peak_rss_kb'], t['range']['seconds'])")" "84836 0.101"
check "compare --json to the table figures" eq "$(py 'import stats; f = stats.fidelity("{\"b_triangles\": 10, \"rms\": 0.002, \"hausdorff\": 0.01, \"b_topology\": {\"boundary_edges\": 3, \"watertight\": false}}"); print(f["triangles"], f["rms"], f["boundary_edges"], f["watertight"])')" "10 0.002 3 False"

# --- the fidelity anchor ---------------------------------------------------------------
check "compare --json: parts and the largest part's area share" eq "$(py 'import stats; f = stats.fidelity({"b_triangles": 10, "rms": 0.1, "hausdorff": 0.2, "b_topology": {"components": 3, "largest_component_area_fraction": 0.75}}); print(f["components"], f["largest_area"])')" "3 0.75"
check "budgets: P % of the input's triangles, named pP, at least 1" \
  eq "$(py 'import stats; t = stats.budget_targets(12946, [1, 2.5, 50]) + stats.budget_targets(40, [1]); print(t, stats.budget_setting(t))')" \
  "[(1, 'p1', 129), (2.5, 'p2.5', 324), (50, 'p50', 6473), (1, 'p1', 1)] p1:129,p2.5:324,p50:6473,p1:1"
check "budget error is relative to the budget" \
  eq "$(py 'import stats; print(stats.budget_error(404, 201) > 1, stats.budget_error(128, 128), stats.budget_error(5, 0))')" "True 0.0 None"
check "cache: exact count, else the nearest within the tolerance, else none" \
  eq "$(py 'import stats; c = {"1000": "a", "1008": "b", "990": "c"}; print(stats.cached_at(c, 1000), stats.cached_at(c, 1005, 0.01), stats.cached_at(c, 1005), stats.cached_at(c, 1100, 0.01))')" \
  "(1000, 'a') (1008, 'b') None None"
# Canned pairs: toy is watertight in one part, open is neither. RMS ratios 2, 1, 1.5, 0.5
# (median 1.25, one above 1.5); Hausdorff 2, 0.5, 1, 0.8 (median 0.9); toy 10 % misses
# its budget by 2 %; toy 1 % loses area to small parts and toy 10 % is not watertight
# (open's figures of that kind do not count: its input is neither). The segment method
# alone: one pair (ratio 3), and open stopped by the timeout.
python3 - "$tmp/fidelity.json" "$lib" <<'EOF'
import json, sys
sys.path.insert(0, sys.argv[2])
import fidelity
fig = lambda n, rms, h, parts=1, largest=1.0, wt=True: {
    "triangles": n, "rms": rms, "hausdorff": h, "components": parts, "largest_area": largest,
    "watertight": wt, "boundary_edges": 0 if wt else 4}
peer = lambda n, rms, h: {"count": n, "triangles": n, "rms": rms, "hausdorff": h,
                          "reached": True, "seconds": 0.01, "target": n}
inputs = {"toy": {"triangles": 1000, "watertight": True, "largest_area": 1.0, "components": 1,
                  "boundary_edges": 0, "sha1": "x"},
          "open": {"triangles": 2000, "watertight": False, "largest_area": 0.5, "components": 2,
                   "boundary_edges": 9, "sha1": "y"}}
def one(name, p, budget, ours, urms, uh):
    anchors = {"update": peer(ours["triangles"], urms, uh),
               "simplify": peer(ours["triangles"], 0.8 * ours["rms"], uh),
               "mo18": peer(ours["triangles"], 0.5 * ours["rms"], uh)}
    return fidelity.pair(name, inputs[name], p, "p%g" % p, budget, {"name": "p%g" % p},
                         ours, anchors)
item = lambda pairs, s: {"status": "ok", "method": "octree", "wall_seconds": s + 0.5,
                         "build_seconds": s, "cpu_seconds": s, "peak_rss_kb": 2048 * s,
                         "pairs": pairs}
run = {"commit": "abc", "date": "2000-01-01 00:00 UTC", "load_start": 0.5, "complete": True,
       "seconds": 60, "settings": {"inputs": ["toy", "open"], "budgets": [1, 10],
       "methods": ["default", "segment"], "samples": 1000, "threads": 2,
       "timeout_seconds": 60, "reuse_peers": False, "js_flags": ["Prune"],
       "js_target_error": "1e10", "peers": {"update": "u", "simplify": "s", "mo18": "m"},
       "versions": {"meshoptimizer_js": "1.3.0", "meshoptimizer": "0.18"}},
       "inputs": inputs, "methods": {
    "default": {"seconds": 40, "items": {
        "toy": item([one("toy", 1, 10, fig(10, 0.004, 0.02, 3, 0.9), 0.002, 0.01),
                     one("toy", 10, 100, fig(98, 0.001, 0.01, wt=False), 0.001, 0.02)], 2.0),
        "open": item([one("open", 1, 20, fig(20, 0.003, 0.02, 5, 0.4, False), 0.002, 0.02),
                      one("open", 10, 200, fig(199, 0.0005, 0.008, 2, 0.5, False), 0.001, 0.01)],
                     4.0)}},
    "segment": {"seconds": 20, "items": {
        "toy": item([one("toy", 1, 10, fig(10, 0.006, 0.01), 0.002, 0.01)], 8.0),
        "open": {"status": "timeout", "wall_seconds": 60}}}}}
json.dump(run, open(sys.argv[1], "w"))
EOF
check "anchor pair: ratios to update, simplify and 0.18, budget error" \
  eq "$(py "import json; p = json.load(open('$tmp/fidelity.json'))['methods']['default']['items']['toy']['pairs'][1]; print(p['rms_ratio'], p['hausdorff_ratio'], round(p['rms_ratio_simplify'], 3), p['rms_ratio_mo18'], round(p['budget_error'], 3), p['file'])")" \
  "1.0 0.5 1.25 2.0 0.02 p10"
summary=$(py "
import json, headline
rec = headline.fidelity_record(json.load(open('$tmp/fidelity.json')))
s = headline.anchor(rec)['default']['summary']
print(s['pairs'], s['rms_ratio']['median'], s['rms_ratio']['max'], s['rms_worst'], s['rms_above'],
      s['hausdorff_ratio']['median'], s['budget_misses'], s['part_losses'], s['part_pairs'],
      s['not_watertight'], s['watertight_pairs'])")
check "anchor summary: medians, worst pair, counts where the input qualifies" eq "$summary" \
  "4 1.25 2.0 {'input': 'toy', 'percent': 1} 1 0.9 1 1 2 1 2"
record=$(py "
import json, headline
run = json.load(open('$tmp/fidelity.json'))
old = headline.fidelity_record(run)
run['methods'] = {'default': run['methods']['default']}
run['commit'] = 'def'
new = headline.fidelity_record(run)
new['pairs'] = new['pairs'][:1]
m = headline.merge_record(old, new)
headline.write_record('$tmp/record.json', m)
back = headline.read_record('$tmp/record.json')
print(back == m, sorted(back['methods']), back['methods']['default']['commit'],
      back['methods']['segment']['commit'], len(back['pairs']))")
check "record: a run's methods replace the record's, the others stay; read back as written" \
  eq "$record" "True ['default', 'segment'] def abc 2"
check "record: one pair a line" eq "$(grep -c '^  {"budget"' "$tmp/record.json")" "2"

# --- a mini results folder rendered to markdown (and plots) ----------------------------
res=$tmp/results
mkdir -p "$res"
python3 - "$res" <<'EOF'
import json, os, sys
res = sys.argv[1]
def save(name, obj):
    json.dump(obj, open(os.path.join(res, name + ".json"), "w"))
def fid(n, rms):
    return {"triangles": n, "rms": rms, "hausdorff": 4 * rms, "boundary_edges": 0,
            "watertight": True}
stages = ["range", "samples", "merge", "priority", "crack", "export"]
def timings(scale):   # stage i takes (i + 1) * scale seconds
    return {s: {"seconds": (i + 1) * scale, "cpu_seconds": (i + 1) * scale,
                "peak_rss_kb": 1024 * (10 + i), "threads": 2} for i, s in enumerate(stages)}
save("machine", {"nproc": 2, "cpu_model": "Test CPU", "memory_gib": 1.0, "os": "TestOS",
                 "kernel": "1", "date": "2000-01-01 00:00 UTC", "commit": "abc",
                 "compiler": "cc", "gnuplot": "", "mode": "quick", "load_start": [0.5, 0, 0],
                 "settings": {"reps": 3, "extract_reps": 5, "compare_samples": 1000}})
levels = [{"name": "lod%d" % p, "lod_percent": p, "triangles": 10 * p, "vertices": 5 * p,
           "rms": 0.01 / p, "hausdorff": 0.04 / p, "watertight": True, "boundary_edges": 0}
          for p in (20, 100)]
save("models", {"toy": {"input_triangles": 2000, "open": False, "diagonal": 1.0,
                        "leaf_size": 0.01, "depth": 6, "samples": 5000,
                        "finest_triangles": 1000, "levels": levels},
                "_versions": {"openvdb": "10.0.1", "meshoptimizer": "0.18"}})
vd = lambda s: {"seconds": s, "peak_rss_kb": 2048, "triangles": 900}
save("stages", {"toy": {"scanlod": {"1": [timings(2.0), timings(2.2), timings(1.8)],
                                    "2": [timings(1.0), timings(1.0), timings(1.0)]},
                        "vdb": {"signed": {"1": [vd(12.0), vd(13.2), vd(10.8)],
                                           "2": [vd(6.0), vd(9.0), vd(3.0)]}}}})
rep = lambda d, n: {"leaf_size": 0.1 / 2 ** d, "samples_count": n,
                    "samples": {"seconds": 1, "peak_rss_kb": n}, "merge": {"seconds": 2, "peak_rss_kb": 2 * n}}
save("octree", {"levels": {"toy": [{"level": 0, "cell_size": 0.01, "triangles": 1000,
                                    "vertices": 500, "scanlod": fid(1000, 0.001),
                                    "vdb": {"signed": fid(980, 0.002)}}]},
                "depths": {"input": "toy", "rows": [{"depth": 8, "reps": [rep(8, 1000)]},
                                                     {"depth": 9, "reps": [rep(9, 4000)]}]}})
ladder = [{"percent": p, "budget": 10 * p, "triangles": 10 * p,
           "seconds": {"median": 1e-7 * 10 * p * (1.2 if p == 1 else 1.0), "min": 0, "max": 1, "n": 5},
           "warm_seconds": {"median": 1e-7 * 10 * p * (1.1 if p == 1 else 1.0), "min": 0, "max": 1, "n": 5},
           "hot_seconds": {"median": 1e-7 * 10 * p * (1.0 if p == 1 else 1.3), "min": 0, "max": 1, "n": 5},
           "meshopt_seconds": {"median": 1e-3, "min": 0, "max": 1, "n": 3},
           "speedup": {"median": 250.0, "min": 200.0, "max": 300.0, "n": 3},
           "speedup_cold": {"median": 120.0, "min": 100.0, "max": 140.0, "n": 3}} for p in (1, 100)]
save("lod", {"toy": {"table1": levels, "vdb_tries": {},
                     "equal_counts": [{"label": "lod20", "triangles": 200,
                                       "scanlod": fid(200, 0.0005),
                                       "meshopt": dict(fid(200, 0.00025), reached=True),
                                       "vdb": dict(fid(210, 0.001), adaptivity=0.5),
                                       "meshopt_finest": fid(200, 0.002)}],
                     "ladder": ladder,
                     "empty_cut_seconds": {"median": 4.5e-6, "min": 4e-6, "max": 5e-6, "n": 5},
                     "root_cut_triangles": 3}})
save("growth", {"sizes": [{"target": n, "triangles": n, "reps": [timings(n / 1e6)],
                           "stages": {s: {"seconds": {"median": (i + 1) * n / 1e6, "min": 0, "max": 0, "n": 1},
                                          "peak_rss_kb": {"median": n / 10, "min": 0, "max": 0, "n": 1}}
                                      for i, s in enumerate(stages)}}
                          for n in (1000000, 4000000)],
                "skipped": [{"target": 20000000, "reason": "predicted 9999 s"}]})
EOF
cp "$tmp/fidelity.json" "$res/"   # a complete fidelity run (the canned pairs above)
md=$tmp/benchmarks.md
# Hand-kept sections (docs/bench/NAME.md) survive a rerun, in their places.
mkdir -p "$tmp/bench"
echo "kept growth note" > "$tmp/bench/growth-notes.md"
echo "## 7. kept model section" > "$tmp/bench/model-section.md"
check "report renders" python3 "$lib/report.py" "$res" "$md"
check "report: hand-kept sections between their markers" python3 - "$md" <<'PY'
import sys
t = open(sys.argv[1]).read()
g = t.index("<!-- growth-notes:begin -->\nkept growth note\n<!-- growth-notes:end -->")
assert t.index("## 4.") < g < t.index("## Plots"), "growth notes after section 4"
assert t.rstrip().endswith("## 7. kept model section\n<!-- model-section:end -->")
PY
check "report: machine" has "$md" "Test CPU, 2 cores"
check "report: Table 1 row" has "$md" "| 20 % | 200 | 100 | 0.050 % | 0.200 % | yes | 0 |"
check "report: merge stage median [min-max] and 1->2 speed-up" has "$md" "| merge | 3 [3–3] | 3 [3–3] | 12 [12–12] | 667 | 6 [5.4–6.6] | 2.00 [1.80–2.20] |"
check "report: OpenVDB / scanlod pair ratios (6/5, 9/5, 3/5)" has "$md" "| toy | signed | 5 [5–5] | 6 [3–9] | 1.20 [0.60–1.80] | 1.20 [1.20–1.20] |"
check "report: depth sweep ratios" has "$md" "| 9 | 0.0001953 | 4000 | 4.00 |"
check "report: equal-count RMS ratios" has "$md" "| 2.00 | 0.50 | 0.200 % | 0.25 |"
check "report: extraction flatness (warm, then first) and fit" has "$md" "max/min of the per-triangle cost (warm): 1.10; first extraction in a process: 1.20; hot: 1.30; empty cut: 4.5 µs (3 triangles); time ~ m^0.98 "
check "report: hot flatness and the empty cut with its triangles" has "$md" "; hot: 1.30; empty cut: 4.5 µs (3 triangles)"
check "report: headline empty cut" has "$md" "a cold start, toy 4.5 µs (3 triangles)."
check "report: hot column (1.3e-7 x 1000 s, 130 ns per triangle)" has "$md" "| 0.13 [0–1e+03] | 130 |"
check "report: headline says the hot max/min" has "$md" "max/min toy 1.30."
check "report: speed-up vs meshopt, warm and first" has "$md" "250 [200–300] | 120 [100–140] |"
check "report: linear growth fitted" has "$md" "time ~ N^1.00 (about linear)"
check "report: skipped size said" has "$md" "Skipped 20000000 triangles: predicted 9999 s."
check "report: versions" has "$md" "OpenVDB 10.0.1 and meshoptimizer 0.18"

check "report: the anchor's headline line (default config)" has "$md" "scanlod / meshoptimizer 1.3.0 \`simplifyWithUpdate\`: median 1.25, max 2.00 (toy 1 %), 1 of 4 pairs above 1.5x; Hausdorff ratio median 0.90; budget misses beyond 1 %: 1 of 4; scanlod / \`simplify\` median 1.25, / meshoptimizer 0.18 median 2.00."
check "report: each method alone, a timeout named" has "$md" "RMS ratio median: segment 3.00 (1 of 1 above 1.5x, budget misses 0) (open: timeout)."
check "report: section 3's line against 0.18 says what it is" has "$md" "section 3, RMS at the counts of the reference builds' LOD-percent levels, scanlod / meshoptimizer 0.18 \`meshopt_simplify\`: median 2.00"
check "report: anchor summary row" has "$md" "| default config | abc, 2000-01-01 00:00 UTC | 4 | 1.25 | 2.00 (toy 1 %) | 1 | 0.90 | 1.25 | 2.00 | 0.25 % / 1 | 1 of 2 | 1 of 2 | 3.00 (6) | 8 | – |"
check "report: a pair, flags in bold" has "$md" "| toy | 1 % | 10 | 10 | 0.00 % | 0.400 % | 0.200 % | **2.00** | 2.000 % | 1.000 % | **2.00** | 1.25 | 2.00 | **3 (90.0 %)** | yes |"
check "report: not watertight where the input is, in bold; not where it is not" has "$md" "| 1 (100.0 %) | **no** |"
check "report: the open input's parts and holes not flagged" has "$md" "| 5 (40.0 %) | no |"
check "report: each method alone folded" has "$md" "<details><summary><b>Segment alone</b>: every pair</summary>"
check "report: section 3a between 3 and 4, the anchor's version in the opening" python3 - "$md" <<'PY'
import sys
t = open(sys.argv[1]).read()
assert t.index("## 3. ") < t.index("<!-- fidelity:begin -->\n## 3a. ") < t.index("<!-- fidelity:end -->") < t.index("## 4. ")
assert "the fidelity anchor, meshoptimizer 1.3.0, from npm" in t
PY
check "report: a complete fidelity run saved as the record" test -f "$tmp/bench/fidelity.json"

# The fidelity phase alone: section 3a and the anchor's lines spliced into a page that has
# neither (the stale line they replace dropped), the rest untouched; again: no change; a
# run of a subset: its own fidelity.md, the page unchanged.
mkdir -p "$tmp/splice/res" "$tmp/splice/part"
cp "$tmp/fidelity.json" "$tmp/splice/res/"
page=$tmp/splice/benchmarks.md
intro=$(py 'import report; print(report.HEADLINE_INTRO)')
printf '# Benchmarks\n\nPeers: meshoptimizer 0.18 from Debian packages.\n\n## Headline figures\n\n%s\n\n- other line\n- RMS at equal triangle counts, scanlod / meshoptimizer: median 8.92 (stale)\n\n## 3. Levels\n\ntext\n\n## 4. Cost\n\nkeep me\n' "$intro" >"$page"
check "splice: runs" python3 "$lib/report.py" --fidelity "$tmp/splice/res" "$page"
check "splice: in place, the stale line dropped, the rest kept" python3 - "$page" <<'PY'
import sys
t = open(sys.argv[1]).read()
h = t.index("<!-- fidelity-headline:begin -->\n- fidelity anchor (section 3a; default config")
assert t.index("## Headline figures") < h < t.index("- other line") < t.index("## 3. Levels")
assert "8.92" not in t
assert "Peers: meshoptimizer 0.18 from Debian packages; the fidelity anchor, meshoptimizer 1.3.0, from npm.\n" in t
assert t.index("text\n\n<!-- fidelity:begin -->\n## 3a. ") < t.index("<!-- fidelity:end -->\n\n## 4. Cost\n\nkeep me\n")
PY
cp "$page" "$tmp/splice/once.md"
python3 "$lib/report.py" --fidelity "$tmp/splice/res" "$page" >/dev/null
check "splice: twice is once" cmp -s "$page" "$tmp/splice/once.md"
py "import json; d = json.load(open('$tmp/fidelity.json')); d['complete'] = False; json.dump(d, open('$tmp/splice/part/fidelity.json', 'w'))"
python3 "$lib/report.py" --fidelity "$tmp/splice/part" "$page" >/dev/null
check "splice: a subset leaves the page" cmp -s "$page" "$tmp/splice/once.md"
check "splice: a subset has its own fidelity.md" has "$tmp/splice/part/fidelity.md" "| default config | abc, 2000-01-01 00:00 UTC | 4 | 1.25 |"

if command -v gnuplot >/dev/null; then
  check "plots render" python3 "$lib/plots.py" "$res" "$tmp/plots"
  for f in error_vs_triangles stage_times extract_cost growth; do
    check "plot $f.png is a PNG" eq "$(head -c 4 "$tmp/plots/$f.png" 2>/dev/null | tail -c 3)" "PNG"
  done
else
  echo "gnuplot missing: plots not checked"
fi

echo "$passed passed, $failed failed"
[ "$failed" -eq 0 ]
