#!/usr/bin/env bash
# The clustering method (issue 13; docs/clustering.md): paper 2's Table 1 redone on cow
# (triangles per intermediate model and the destination, and the time of the whole table
# in-process) and, on cow, fandisk, armadillo_86kf, bun_zipper and igea, the triangles
# reached for bounds of 0.1, 0.5, 1 and 2 % of the diagonal with the measured symmetric
# Hausdorff distance (`scanlod compare`) and meshopt_simplify's count at that distance.
#
#   scripts/bench/bench_cluster.sh [--build DIR] [--out DIR] [--quick]
#
# Builds (a new tree is Release) scanlod, cluster_bench and meshopt_lod, then runs
# scripts/bench/lib/cluster.py. Writes OUT/cluster.md (the tables docs/clustering.md and
# docs/benchmarks.md quote) and OUT/cluster.json; OUT defaults to
# DIR/bench-results/cluster. --quick: cow and fandisk, one pass count, 5 timing runs.
# Not part of CI (about 25 minutes on 2 cores at load 14; --quick about 5).
set -euo pipefail
export PYTHONDONTWRITEBYTECODE=1
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
build=$root/build-bench out="" quick=""
while [ $# -gt 0 ]; do
  case $1 in
    --build) build=$2; shift ;;
    --out) out=$2; shift ;;
    --quick) quick=--quick ;;
    -h|--help) sed -n '2,14p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
    *) echo "bench_cluster.sh: unknown argument $1" >&2; exit 64 ;;
  esac
  shift
done
data=${SCANLOD_SHARED_DATA:-$root/../shared/data}
[ -f "$data/cow.ply" ] || { echo "bench_cluster.sh: no shared scans at $data" >&2; exit 64; }
out=${out:-$build/bench-results/cluster}
if [ ! -f "$build/CMakeCache.txt" ]; then
  gen=()
  command -v ninja >/dev/null && gen=(-G Ninja)
  cmake -S "$root" -B "$build" "${gen[@]}" -DCMAKE_BUILD_TYPE=Release >/dev/null
fi
cmake --build "$build" --parallel "$(nproc)" --target scanlod bench_cluster bench_meshopt_lod >/dev/null
# The method runs on one thread below 50,000 triangles anyway; the larger inputs get the
# machine's threads (OMP_NUM_THREADS, if set, wins).
# The tools copied first: a rebuild of the tree during the run (minutes) cannot swap them.
build=$(cd "$build" && pwd)
mkdir -p "$out/tools/cli" "$out/tools/scripts/bench"
cp "$build/cli/scanlod" "$out/tools/cli/"
cp "$build/scripts/bench/cluster_bench" "$build/scripts/bench/meshopt_lod" "$out/tools/scripts/bench/"
python3 "$here/lib/cluster.py" run "$out/tools" "$data" "$out" $quick
cat "$out/cluster.md"
