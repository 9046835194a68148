#!/usr/bin/env bash
# The benchmark suite (issue 3): scanlod against OpenVDB and meshoptimizer, in one run.
#
#   scripts/bench/run.sh [--quick] [--build DIR] [--docs DIR] [--minutes N] [--keep]
#   scripts/bench/run.sh --report-only RESULTS_DIR [--docs DIR]
#   scripts/bench/run.sh --resume RESULTS_DIR --phases "lod growth"   (after a --keep run)
#   scripts/bench/run.sh --phases fidelity [--inputs a,b] [--budgets 1,10]
#                        [--methods default,octree,segment,cluster] [--reuse-peers] [--timeout MIN]
#
# Builds Release (DIR, default build-bench/ in the repository), then runs the phases in
# scripts/bench/lib/ on the same inputs (../shared/data next to the repository, or
# $SCANLOD_SHARED_DATA):
#   models  one reference build per input (default config): Table 1, leaf size, .slod
#   stages  per stage wall/CPU/peak RSS at 1 and 2 threads + OpenVDB remesh timings
#   octree  uniform levels vs OpenVDB at the same voxel size; memory at depths 8..11
#   lod     equal-count fidelity vs meshoptimizer and OpenVDB adaptive; extraction cost
#   growth  synthetic surfaces (gen_surface) of growing size: time, memory, fitted slope
#   parts   the largest surface built by 3 local workers as parts, one killed -9 in a part
#   fidelity  the published budget levels (1..50 % of 9 inputs) against the fidelity anchor,
#           meshoptimizer 1.3 simplifyWithUpdate at the same counts (and simplify, and 0.18);
#           --methods: each method alone too ("default" = the default config); --inputs,
#           --budgets: a subset (its table goes to RESULTS/fidelity.md, the docs stay);
#           --reuse-peers: the anchors' figures from BUILD/bench-results/fidelity-peers.json
#           where they are (same count, else within 1 %); --timeout: minutes per scanlod run
#   shapes  `scanlod plan` against the run on 500k thin slivers and a 20k-triangle soup
# and writes docs/benchmarks.md and the gnuplot PNGs in docs/bench/. Raw figures stay in
# DIR/bench-results/STAMP/*.json (--report-only regenerates the docs from them). A run of
# the fidelity phase alone replaces section 3a and its headline lines only.
# --quick: bun_zipper, fandisk, rocker_arm, 3 repetitions, 0.2M and 1M triangles once,
# the depth sweep once on fandisk, extraction timings x3 (a few minutes on 2 cores).
# Full: 5 inputs, 5 repetitions, 1M/5M/20M/100M triangles; sizes that would overrun the
# time budget (--minutes, default 40) are skipped and the report says so (100 M takes
# about 40 minutes and 41 GB of disk on 2 cores: --phases growth --minutes 90).
# Not part of CI: tests/bench/test_bench_harness.sh checks the parsing and statistics.
set -euo pipefail
export PYTHONDONTWRITEBYTECODE=1   # no __pycache__ in the source tree
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
lib=$here/lib

quick=0 build=$root/build-bench docs=$root/docs minutes="" keep=0 report_only="" resume=""
phases="models stages octree lod fidelity growth parts shapes"
fid_inputs="" fid_budgets="" fid_methods="" reuse_peers="" fid_timeout=""
while [ $# -gt 0 ]; do
  case $1 in
    --quick) quick=1 ;;
    --inputs) fid_inputs=$2; shift ;;
    --budgets) fid_budgets=$2; shift ;;
    --methods) fid_methods=$2; shift ;;
    --reuse-peers) reuse_peers=1 ;;
    --timeout) fid_timeout=$2; shift ;;
    --build) build=$2; shift ;;
    --docs) docs=$2; shift ;;
    --minutes) minutes=$2; shift ;;
    --keep) keep=1 ;;
    --report-only) report_only=$2; shift ;;
    --resume) resume=$2; shift ;;
    --phases) phases=$2; shift ;;
    -h|--help) sed -n '2,34p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
    *) echo "run.sh: unknown argument $1 (see --help)" >&2; exit 64 ;;
  esac
  shift
done

render() { # render RESULTS_DIR: docs/benchmarks.md and docs/bench/*.png
  mkdir -p "$docs/bench"
  if [ ! -f "$1/models.json" ] && [ -f "$1/fidelity.json" ]; then
    # the fidelity phase alone: its section and headline lines, the rest of the page kept
    python3 "$lib/report.py" --fidelity "$1" "$docs/benchmarks.md"
    [ ! -f "$1/fidelity.md" ] || cat "$1/fidelity.md"
    return
  fi
  python3 "$lib/plots.py" "$1" "$docs/bench"
  python3 "$lib/report.py" "$1" "$docs/benchmarks.md"
  echo "bench: wrote $docs/benchmarks.md and $docs/bench/*.png from $1"
}
fidelity_settings() { # fidelity_settings CONTEXT.json: the fidelity phase's options into it
  FID_INPUTS=$fid_inputs FID_BUDGETS=$fid_budgets FID_METHODS=$fid_methods \
  REUSE_PEERS=$reuse_peers FID_TIMEOUT=$fid_timeout \
  python3 - "$1" <<'EOF3'
import json, os, sys
path, e = sys.argv[1], os.environ
c = json.load(open(path))
items = lambda k: [x for x in e[k].replace(",", " ").split() if x]
num = lambda x: int(float(x)) if float(x) == int(float(x)) else float(x)
if e["FID_INPUTS"] or "fidelity_inputs" not in c:   # [] = lib/fidelity.py's nine
    c["fidelity_inputs"] = items("FID_INPUTS") or (c["models"] if c.get("quick") else [])
if e["FID_BUDGETS"] or "fidelity_budgets" not in c:
    c["fidelity_budgets"] = [num(x) for x in items("FID_BUDGETS")] or \
        ([1, 10] if c.get("quick") else [])
if e["FID_METHODS"] or "fidelity_methods" not in c:
    c["fidelity_methods"] = items("FID_METHODS") or ["default"]
if e["FID_TIMEOUT"] or "fidelity_timeout" not in c:
    c["fidelity_timeout"] = int(60 * float(e["FID_TIMEOUT"] or 30))
c["reuse_peers"] = e["REUSE_PEERS"] == "1"
c["peer_cache"] = os.path.join(os.path.dirname(c["results"]), "fidelity-peers.json")
json.dump(c, open(path, "w"), indent=1)
EOF3
}
peers_ready() { # the fidelity phase's npm peer, installed on first use
  case " $phases " in *" fidelity "*) ;; *) return 0 ;; esac
  command -v node >/dev/null || { echo "run.sh: node missing (scripts/install-deps.sh)" >&2; exit 64; }
  local npm_peers=$here/peers/npm
  [ -f "$npm_peers/node_modules/meshoptimizer/package.json" ] ||
    npm ci --prefix "$npm_peers" --no-audit --no-fund --loglevel=error
}
run_phases() { # run_phases RESULTS_DIR [rerun]: the phases named by $phases, then the docs
  local t0 start
  start=$(date +%s)
  for phase in $phases; do
    t0=$(date +%s)
    python3 "$lib/$phase.py" "$1/context.json"
    echo "bench: phase $phase done in $(($(date +%s) - t0)) s"
  done
  if [ -z "${2:-}" ]; then # a rerun keeps the first run's time and load figures
    echo "$(($(date +%s) - start))" >"$1/elapsed_seconds"
    cut -d' ' -f1-3 /proc/loadavg >"$1/load_end" 2>/dev/null || true
  fi
  render "$1"
}
if [ -n "$report_only" ]; then
  render "$report_only"
  exit 0
fi
build_bench() { # the Release tree every phase runs
  local gen=()
  [ -f "$build/CMakeCache.txt" ] || { command -v ninja >/dev/null && gen=(-G Ninja); }
  cmake -S "$root" -B "$build" "${gen[@]}" -DCMAKE_BUILD_TYPE=Release >/dev/null
  cmake --build "$build" --parallel "$(nproc)" \
    --target scanlod bench_vdb_remesh bench_meshopt_lod bench_gen_surface
}
if [ -n "$resume" ]; then   # rebuilt from the current tree, a fresh time budget from now
  build_bench
  peers_ready
  fidelity_settings "$resume/context.json"
  python3 - "$resume/context.json" "$resume/reruns.json" "$phases" "$root" <<'EOF2'
import datetime, json, os, subprocess, sys, time
ctx_path, reruns_path, phases, root = sys.argv[1:5]
c = json.load(open(ctx_path))
c["deadline"] = time.time() + 60 * c["minutes"]
json.dump(c, open(ctx_path, "w"), indent=1)
git = lambda *a: subprocess.run(["git", "-C", root] + list(a), capture_output=True,
                                text=True).stdout.strip()
commit = git("rev-parse", "--short", "HEAD") or "unknown"
if git("status", "--porcelain", "--untracked-files=no"):
    commit += " (with uncommitted changes)"
reruns = json.load(open(reruns_path)) if os.path.exists(reruns_path) else []
reruns.append({"phases": phases.split(), "commit": commit, "date":
               datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC"),
               "load": os.getloadavg()[0]})
json.dump(reruns, open(reruns_path, "w"), indent=1)
EOF2
  run_phases "$resume" rerun
  exit 0
fi

data=${SCANLOD_SHARED_DATA:-$root/../shared/data}
[ -d "$data" ] || { echo "run.sh: no shared scans at $data (set SCANLOD_SHARED_DATA)" >&2; exit 64; }
command -v gnuplot >/dev/null || { echo "run.sh: gnuplot missing (scripts/install-deps.sh)" >&2; exit 64; }
command -v python3 >/dev/null || { echo "run.sh: python3 missing" >&2; exit 64; }

# --- build (Release) -------------------------------------------------------------------
build_bench
peers_ready

# --- settings ----------------------------------------------------------------------------
if [ "$quick" = 1 ]; then
  models="bun_zipper fandisk rocker_arm" lod_models=$models reps=3
  sizes="200000 1000000" depth_input=fandisk depth_reps=1 full_reps_max=0
  curve_extra="0.05" search_steps=4 extract_reps=3 minutes=${minutes:-10}
else
  models="bun_zipper dragon_100kf armadillo_86kf igea fandisk"
  lod_models="bun_zipper dragon_100kf armadillo_86kf fandisk" reps=5
  sizes="1000000 5000000 20000000 100000000" depth_input=igea depth_reps=3 full_reps_max=1000000
  curve_extra="0.02 0.05 0.1" search_steps=8 extract_reps=5 minutes=${minutes:-40}
fi
for m in $models; do
  [ -f "$data/$m.ply" ] || { echo "run.sh: no $data/$m.ply" >&2; exit 64; }
done

stamp=$(date -u +%Y%m%dT%H%M%SZ)
[ "$quick" = 0 ] || stamp=$stamp-quick
results=$build/bench-results/$stamp
scratch=$build/bench-scratch/$stamp
mkdir -p "$results" "$scratch"
[ "$keep" = 1 ] || trap 'rm -rf "$scratch"' EXIT

# The context every phase reads (lib/common.py Ctx).
REPO=$root BUILD=$build DATA=$data RESULTS=$results SCRATCH=$scratch QUICK=$quick \
MODELS=$models LOD_MODELS=$lod_models REPS=$reps SIZES=$sizes DEPTH_INPUT=$depth_input \
DEPTH_REPS=$depth_reps EXTRACT_REPS=$extract_reps FULL_REPS_MAX=$full_reps_max \
CURVE_EXTRA=$curve_extra SEARCH_STEPS=$search_steps \
MINUTES=$minutes python3 - >"$results/context.json" <<'EOF'
import json, os, time
e = os.environ
nums = lambda k, t: [t(x) for x in e[k].split()]
print(json.dumps({
    "repo": e["REPO"], "build": e["BUILD"], "data": e["DATA"], "results": e["RESULTS"],
    "scratch": e["SCRATCH"], "quick": e["QUICK"] == "1",
    "models": e["MODELS"].split(), "lod_models": e["LOD_MODELS"].split(),
    "reps": int(e["REPS"]), "extract_reps": int(e["EXTRACT_REPS"]), "sizes": nums("SIZES", int),
    "growth_full_reps_max": int(e["FULL_REPS_MAX"]),
    "depth_input": e["DEPTH_INPUT"], "depths": [8, 9, 10, 11],
    "depth_reps": int(e["DEPTH_REPS"]),
    "budgets": [1, 2, 5, 10, 20, 50, 100], "curve_extra": nums("CURVE_EXTRA", float),
    "compare_samples": 200000, "vdb_search_steps": int(e["SEARCH_STEPS"]),
    "minutes": int(e["MINUTES"]), "deadline": time.time() + 60 * int(e["MINUTES"]),
}, indent=1))
EOF

fidelity_settings "$results/context.json"

echo "bench: $stamp run, results in $results"
python3 "$lib/machine.py" "$results/context.json"
ln -sfn "$stamp" "$build/bench-results/latest"
run_phases "$results"
