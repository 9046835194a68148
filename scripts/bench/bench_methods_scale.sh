#!/usr/bin/env bash
# Each method at scale (issue 38, "the other methods at scale"): one `scanlod run` per
# method and size on a gen_surface torus, 2 threads, default config otherwise, with
# `scanlod plan` beside it: per stage wall seconds and peak RSS (timings.json), the plan's
# peak and time for the item, and their ratios (plan / measured).
#
#   scripts/bench/bench_methods_scale.sh [--build DIR] [--out DIR]
#                                        [--sizes 1000000,5000000] [--methods segment,cluster]
#
# Builds (a new tree is Release) scanlod and gen_surface, then writes OUT/methods-scale.md
# and OUT/methods-scale.json (OUT defaults to DIR/bench-results/methods-scale); a size
# whose plan is over this node's memory is not run, and the table says so. Not part of CI
# (segment at 5 M: about 15 minutes on 2 cores; the default method's growth is run.sh's
# growth phase).
set -euo pipefail
export PYTHONDONTWRITEBYTECODE=1
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
build=$root/build-bench out="" sizes=1000000,5000000 methods=segment,cluster
while [ $# -gt 0 ]; do
  case $1 in
    --build) build=$2; shift ;;
    --out) out=$2; shift ;;
    --sizes) sizes=$2; shift ;;
    --methods) methods=$2; shift ;;
    -h|--help) sed -n '2,14p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
    *) echo "bench_methods_scale.sh: unknown argument $1" >&2; exit 64 ;;
  esac
  shift
done
out=${out:-$build/bench-results/methods-scale}
if [ ! -f "$build/CMakeCache.txt" ]; then
  gen=()
  command -v ninja >/dev/null && gen=(-G Ninja)
  cmake -S "$root" -B "$build" "${gen[@]}" -DCMAKE_BUILD_TYPE=Release >/dev/null
fi
cmake --build "$build" --parallel "$(nproc)" --target scanlod bench_gen_surface >/dev/null
scanlod=$build/cli/scanlod
gen=$build/scripts/bench/gen_surface
mkdir -p "$out"
scratch=$(mktemp -d "${TMPDIR:-/tmp}/methods-scale.XXXXXX")
trap 'rm -rf "$scratch"' EXIT

rows=$out/methods-scale.jsonl
: >"$rows"
for n in ${sizes//,/ }; do
  mkdir -p "$scratch/in"
  rm -f "$scratch/in/"*
  "$gen" --triangles "$n" -o "$scratch/in/surface_$n.ply" >/dev/null
  for m in ${methods//,/ }; do
    cfg=$scratch/$m-$n.ini
    printf '[run]\ninput = %s\nwork = %s\noutput = %s\nthreads = 2\n[lod]\nmethod = %s\n' \
      "$scratch/in" "$scratch/work-$m-$n" "$scratch/out-$m-$n" "$m" >"$cfg"
    "$scanlod" plan "$cfg" --json >"$scratch/plan.json"
    echo "[methods-scale $(date -u +%H:%M:%S)] $m at $n triangles"
    set +e
    "$scanlod" run "$cfg" -q 2>"$scratch/err"
    rc=$?
    set -e
    python3 - "$rows" "$m" "$n" "$rc" "$scratch/out-$m-$n/surface_$n.ply/timings.json" \
      "$scratch/err" "$scratch/plan.json" <<'EOF'
import json, os, sys
rows, method, n, rc, timings, err, plan = sys.argv[1:8]
plan = json.load(open(plan))["items"][0]
row = {"method": method, "target": int(n), "rc": int(rc), "plan_mb": plan["peak_rss_mb"],
       "plan_s": plan["seconds"], "plan_stages": plan["stages"]}
if os.path.exists(timings):
    st = json.load(open(timings))["stages"]
    row["stages"] = {k: {"seconds": v["seconds"], "peak_mb": v["peak_rss_kb"] / 1024.0}
                     for k, v in st.items()}
else:
    row["error"] = open(err).read().strip().splitlines()[-1:] if os.path.exists(err) else []
with open(rows, "a") as f:
    f.write(json.dumps(row) + "\n")
EOF
    rm -rf "$scratch/work-$m-$n" "$scratch/out-$m-$n"
  done
done
python3 - "$rows" "$out" <<'EOF'
import json, os, sys
rows = [json.loads(l) for l in open(sys.argv[1])]
json.dump(rows, open(os.path.join(sys.argv[2], "methods-scale.json"), "w"), indent=1)
md = ["| method | triangles | stages: s (peak MB) | total s | peak MB | bytes per triangle | "
      "plan s | ratio | plan MB | ratio |", "|---|---:|---|---:|---:|---:|---:|---:|---:|---:|"]
for r in rows:
    if "stages" not in r:
        md.append("| %s | %d | not run (exit %d): %s | | | | %.0f | | %.0f | |" % (
            r["method"], r["target"], r["rc"], " ".join(r.get("error", [])), r["plan_s"],
            r["plan_mb"]))
        continue
    st = r["stages"]
    total = sum(v["seconds"] for v in st.values())
    peak = max(v["peak_mb"] for v in st.values())
    md.append("| %s | %d | %s | %.0f | %.0f | %.0f | %.0f | %.2f | %.0f | %.2f |" % (
        r["method"], r["target"],
        ", ".join("%s %.1f (%.0f)" % (k, v["seconds"], v["peak_mb"]) for k, v in st.items()),
        total, peak, peak * 1048576 / r["target"], r["plan_s"], r["plan_s"] / total,
        r["plan_mb"], r["plan_mb"] / peak))
open(os.path.join(sys.argv[2], "methods-scale.md"), "w").write("\n".join(md) + "\n")
print("\n".join(md))
EOF
