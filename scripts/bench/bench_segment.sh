#!/usr/bin/env bash
# The segment method's benchmark (issue 12; docs/segmentation.md, docs/benchmarks.md).
#
#   scripts/bench/bench_segment.sh [--quick] [--build DIR] [--docs DIR] [--parts "..."]
#                                  [--models "..."] [--baseline SCANLOD] [--no-estimate]
#   scripts/bench/bench_segment.sh --report-only RESULTS.json [--docs DIR]
#
# Builds a Release tree (DIR, default build-bench/ like run.sh), then measures with
# `scanlod simplify --method segment`, `scanlod compare --samples 200000`, the peers
# meshopt_lod and vsa_lod (CGAL's Variational Shape Approximation) and the octree path
# (`scanlod run` + `scanlod extract`):
#   paper     the paper's section 4 experiment: delta_seg 80 and 50, delta_b 20 and 60,
#             equation 8 as printed (alpha -1.5) and the text's reading, on cow, fandisk,
#             rocker_arm: segments, removed vertices, percent removed
#   fidelity  RMS and Hausdorff at 2, 5, 10, 20, 50 % of the input's triangles against
#             meshopt_simplify at the same count and the octree's cut at the nearest
#             count; watertightness of every level
#   finest    the segment method as a pass on the octree's finest level, against the
#             octree's own cuts at equal counts
#   speed     simplify to 10 % vs meshopt_simplify on igea and a 2M-triangle surface
#             (gen_surface); vs CGAL VSA at equal triangle counts
# Raw figures: DIR/bench-results/segment-STAMP.json; the tables go to
# docs/bench/segment-section.md (included by docs/benchmarks.md) and the paper table
# and summary into docs/segmentation.md (between its "generated" markers).
# --quick: fandisk and rocker_arm only, one repetition.
# --models: the fidelity (and VSA) inputs; a partial run, reported under the full run's
# tables in docs/benchmarks.md (between its segment-update markers).
# --baseline: another scanlod (the code before a change) timed alternately with this one
# in the speed part. --no-estimate: no `--search-samples 0` speed rows.
# Every timed command also gets its CPU seconds (user + system).
set -euo pipefail
export PYTHONDONTWRITEBYTECODE=1
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
build=$root/build-bench docs=$root/docs quick=0 report_only="" parts="paper fidelity finest speed"
models="" baseline="" estimate=1
while [ $# -gt 0 ]; do
  case $1 in
    --quick) quick=1 ;;
    --build) build=$2; shift ;;
    --docs) docs=$2; shift ;;
    --parts) parts=$2; shift ;;
    --report-only) report_only=$2; shift ;;
    --models) models=$2; shift ;;
    --baseline) baseline=$(realpath "$2"); shift ;;
    --no-estimate) estimate=0 ;;
    -h|--help) sed -n '2,32p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
    *) echo "bench_segment.sh: unknown argument $1 (see --help)" >&2; exit 64 ;;
  esac
  shift
done
if [ -n "$report_only" ]; then
  exec python3 "$here/lib/segment.py" report "$report_only" "$docs"
fi
data=${SCANLOD_SHARED_DATA:-$root/../shared/data}
[ -d "$data" ] || { echo "bench_segment.sh: no shared scans at $data (set SCANLOD_SHARED_DATA)" >&2; exit 64; }
if [ ! -f "$build/CMakeCache.txt" ]; then
  gen=()
  command -v ninja >/dev/null && gen=(-G Ninja)
  cmake -S "$root" -B "$build" "${gen[@]}" -DCMAKE_BUILD_TYPE=Release >/dev/null
fi
cmake --build "$build" --parallel "$(nproc)" --target scanlod bench_meshopt_lod bench_gen_surface
cmake --build "$build" --parallel "$(nproc)" --target bench_vsa_lod ||
  echo "bench_segment.sh: no CGAL (scripts/install-deps.sh): the VSA figures are skipped" >&2
stamp=$(date -u +%Y%m%dT%H%M%SZ)
mkdir -p "$build/bench-results" "$build/bench-scratch/segment-$stamp"
trap 'rm -rf "$build/bench-scratch/segment-$stamp"' EXIT
python3 "$here/lib/segment.py" run "$root" "$build" "$data" "$build/bench-scratch/segment-$stamp" \
  "$build/bench-results/segment-$stamp.json" "$quick" "$parts" "$models" "$baseline" "$estimate"
python3 "$here/lib/segment.py" report "$build/bench-results/segment-$stamp.json" "$docs"
