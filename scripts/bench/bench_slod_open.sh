#!/usr/bin/env bash
# Open a model and cut N triangles in a fresh process, CPU seconds of one thread (user +
# sys, steadier than wall time on a shared machine) and wall seconds at the default
# threads, median of REPS; the two cuts are compared byte for byte.
#   scripts/bench/bench_slod_open.sh OLD_SCANLOD OLD_MODEL NEW_SCANLOD NEW_MODEL N [REPS]
# (docs/benchmarks.md section 7: main's binary on its format 2 model against this one's).
set -euo pipefail
old_bin=$1 old=$2 new_bin=$3 new=$4 n=$5 reps=${6:-3}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
median() { sort -n | sed -n "$(( (reps + 1) / 2 ))p"; }
for side in old new; do
  if [ $side = old ]; then bin=$old_bin model=$old; else bin=$new_bin model=$new; fi
  cpu=() wall=()
  for _ in $(seq "$reps"); do
    c=$( { OMP_NUM_THREADS=1 /usr/bin/time -f "%U %S" "$bin" extract "$model" --triangles "$n" -o "$tmp/$side.ply" >/dev/null; } 2>&1 | tail -1)
    cpu+=("$(awk '{printf "%.2f", $1 + $2}' <<<"$c")")
    w=$( { /usr/bin/time -f "%e %M" "$bin" extract "$model" --triangles "$n" -o "$tmp/$side.ply" >/dev/null; } 2>&1 | tail -1)
    wall+=("$w")
  done
  echo "$side: cpu_s $(printf '%s\n' "${cpu[@]}" | median) wall_s $(printf '%s\n' "${wall[@]}" | median | cut -d' ' -f1) peak_rss_kb $(printf '%s\n' "${wall[@]}" | cut -d' ' -f2 | median) ($(stat -c %s "$model") bytes)"
done
cmp -s "$tmp/old.ply" "$tmp/new.ply" && echo "cuts identical" || { echo "cuts differ"; exit 1; }
