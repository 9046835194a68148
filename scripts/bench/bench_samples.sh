#!/usr/bin/env bash
# Samples stage benchmark (issue 4, docs/samples-stage.md):
#   1. wall time and peak RSS at 1 and 2 threads on bun_zipper, dragon_100kf, igea
#      (speed-up = median 1-thread time / median 2-thread time; aim >= 1.8);
#   2. peak RSS at octree depths 8, 9, 10, 11 on one input: memory must follow the
#      surface (~4x samples per level), not the bounding volume (8x).
# Medians of REPS runs (default 3).
#
#   scripts/bench/bench_samples.sh [BUILD_DIR]        (default: build)
# Env: SCANLOD_SHARED_DATA  the shared scans (default: ../shared/data next to the repo)
#      REPS, INPUTS ("bun_zipper dragon_100kf igea"), DEPTHS ("8 9 10 11"),
#      DEPTH_INPUTS ("igea torus"): "torus" is a gen_surface torus of TORUS_TRIANGLES
#      (8000000) triangles, dense enough that leaf cubes stay coarser than the point
#      spacing up to depth 10 (a real scan's samples stop growing once the leaf is finer
#      than its points: every point then has its own 4x4x4 vertices).
#
# Method: `scanlod run` on a one-item collection with `-s merge.max_samples=1`, so the
# chain stops after samples (the merge stage refuses the item at once; exit 65 expected).
# Each measured repetition removes the item's samples artifact, so the engine reruns that
# stage alone. Figures come from the engine's per-stage record
# artifacts/samples/ITEM/_stats.json (wall seconds and the child's peak RSS; the numbers
# timings.json publishes) and the samples count from the stage's report.json. Peak RSS
# includes the process baseline (libraries, ~45 MB).
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
build=${1:-$root/build}
scanlod=$build/cli/scanlod
data=${SCANLOD_SHARED_DATA:-$root/../shared/data}
reps=${REPS:-3}
inputs=${INPUTS:-bun_zipper dragon_100kf igea}
depth_inputs=${DEPTH_INPUTS:-igea torus}
depths=${DEPTHS:-8 9 10 11}
torus_triangles=${TORUS_TRIANGLES:-8000000}
[ -x "$scanlod" ] || { echo "no $scanlod: build first (scripts/build.sh)" >&2; exit 64; }
[ -d "$data" ] || { echo "no shared data at $data (set SCANLOD_SHARED_DATA)" >&2; exit 64; }
tmp=$(mktemp -d "${TMPDIR:-/tmp}/bench_samples.XXXXXX")
trap 'rm -rf "$tmp"' EXIT

median() { sort -g | awk '{ v[NR] = $1 } END { if (NR) print v[int((NR + 1) / 2)] }'; }
json_number() { sed -n "s/.*\"$2\": *\([0-9.eE+-]*\).*/\1/p" "$1" | head -n 1; }

# collection NAME: a one-item collection with its config; prints the config path.
collection() {
  local name=$1 dir=$tmp/$1
  mkdir -p "$dir/in"
  if [ "$name" = torus ]; then
    "$build/scripts/bench/gen_surface" --triangles "$torus_triangles" -o "$dir/in/torus.ply" >/dev/null
  else
    cp "$data/$name.ply" "$dir/in/$name.ply"
  fi
  printf '[run]\ninput = %s\nwork = %s\noutput = %s\nlogs = %s\n' \
    "$dir/in" "$dir/work" "$dir/out" "$dir/logs" >"$dir/run.ini"
  echo "$dir/run.ini"
}

# measure CONFIG ITEM THREADS [-s overrides...]: prints "samples seconds peak_rss_kb
# cubes_s tree_s samples_s write_s" (medians; the phases from the stage's _phases.json).
measure() {
  local config=$1 item=$2 threads=$3; shift 3
  local art
  art=$(dirname "$config")/work/artifacts/samples/$item
  "$scanlod" run "$config" --threads "$threads" -q -s merge.max_samples=1 "$@" >/dev/null 2>>"$tmp/log" || true
  : >"$tmp/secs"; : >"$tmp/rss"
  for p in cubes_s tree_s samples_s write_s; do : >"$tmp/$p"; done
  for _ in $(seq "$reps"); do
    rm -rf "$art"
    "$scanlod" run "$config" --threads "$threads" -q -s merge.max_samples=1 "$@" >/dev/null 2>>"$tmp/log" || true
    [ -f "$art/_stats.json" ] || { echo "samples stage failed on $item: see $(dirname "$config")/logs" >&2; exit 70; }
    json_number "$art/_stats.json" seconds >>"$tmp/secs"
    json_number "$art/_stats.json" peak_rss_kb >>"$tmp/rss"
    for p in cubes_s tree_s samples_s write_s; do json_number "$art/_phases.json" "$p" >>"$tmp/$p"; done
  done
  echo "$(json_number "$art/report.json" samples) $(median <"$tmp/secs") $(median <"$tmp/rss")" \
       "$(median <"$tmp/cubes_s") $(median <"$tmp/tree_s") $(median <"$tmp/samples_s")" \
       "$(median <"$tmp/write_s")"
}

# Can this host run two threads at once right now? Two busy processes one after the other
# vs side by side (2.0 on an idle 2-core machine; ~1.0 when other work takes the cores).
busy() { awk 'BEGIN { for (i = 0; i < 3e7; i++) s += sqrt(i) }'; }
t0=$(date +%s.%N); busy; busy; t1=$(date +%s.%N); busy & busy & wait; t2=$(date +%s.%N)
echo "host check: load average $(cut -d' ' -f1-3 /proc/loadavg) on $(nproc) cores;" \
     "two busy processes side by side run $(awk -v a="$t0" -v b="$t1" -v c="$t2" \
     'BEGIN { printf "%.2f", (b - a) / (c - b) }')x faster than one after the other"
echo "## samples stage: 1 vs 2 threads (medians of $reps; phases: cubes / k-d tree / closest points / write)"
echo "| input | samples | threads | stage s | cubes s | tree s | closest s | write s | peak RSS MB |"
echo "|---|---:|---:|---:|---:|---:|---:|---:|---:|"
for name in $inputs; do
  config=$(collection "$name")
  for t in 1 2; do
    read -r n s r c k q w <<<"$(measure "$config" "$name" "$t")"
    eval "stage_$t=$s closest_$t=$q"
    awk -v i="$name" -v n="$n" -v t="$t" -v s="$s" -v r="$r" -v c="$c" -v k="$k" -v q="$q" \
        -v w="$w" 'BEGIN { printf "| %s | %d | %d | %.3f | %.3f | %.3f | %.3f | %.3f | %.1f |\n",
                           i, n, t, s, c, k, q, w, r / 1024 }'
  done
  awk -v i="$name" -v a="$stage_1" -v b="$stage_2" -v c="$closest_1" -v d="$closest_2" 'BEGIN {
    printf "| %s speed-up | | | %.2f | | | %.2f | | |\n", i, a / b, c / d }'
done
echo "load average after: $(cut -d' ' -f1-3 /proc/loadavg)"

for input in $depth_inputs; do
  echo
  echo "## samples stage: memory per octree depth on $input (2 threads, medians of $reps)"
  echo "| depth | samples | samples ratio | wall s | peak RSS MB | RSS ratio |"
  echo "|---:|---:|---:|---:|---:|---:|"
  config=$(collection "$input")
  prev_n=0; prev_r=0
  for d in $depths; do
    read -r n s r _ <<<"$(measure "$config" "$input" 2 -s octree.depth="$d")"
    awk -v d="$d" -v n="$n" -v s="$s" -v r="$r" -v pn="$prev_n" -v pr="$prev_r" 'BEGIN {
      nr = "-"; rr = "-"
      if (pn > 0) nr = sprintf("%.2f", n / pn)
      if (pr > 0) rr = sprintf("%.2f", r / pr)
      printf "| %d | %d | %s | %.3f | %.1f | %s |\n", d, n, nr, s, r / 1024, rr }'
    prev_n=$n; prev_r=$r
  done
done
