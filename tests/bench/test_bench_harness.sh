#!/usr/bin/env bash
# The benchmark harness (scripts/bench/lib) on canned inputs, no build and no runs, so it
# does not rot: parsing of timings.json, `extract` and `compare --json` output; medians,
# pair ratios, log-log slopes, the OpenVDB adaptivity bisection, the per-triangle cost;
# then docs/benchmarks.md (and the plots, when gnuplot is there) rendered from a mini
# results folder, checked for the figures it must show.
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
