#!/usr/bin/env bash
# PLY reader throughput against page-cache read speed, side by side in one run (issue 2).
#
#   scripts/bench/bench_ply_read.sh [BUILD_DIR] [RUNS]      (RUNS >= 5, default 7)
#
# Files: igea.ply (binary LE) and bun_zipper.ply (ascii) from the shared data folder when
# present, plus a ~150 MB binary torus made by gen_surface and a ~90 MB ascii re-encoding
# of a smaller one, both in a temporary folder. For each file, RUNS timings of
#   cat FILE > /dev/null     (a process; includes its start-up, ~1 ms)
#   read() loop, 128 KiB     (in the bench process: cat's work without the start-up)
#   sl_ply_read              (mmap + parse + the mesh arrays)
# alternate, after one warm-up read so the page cache holds the file. Medians, min, max;
# the last column is reader MB/s over read()-loop MB/s (the aim for binary: >= 0.5).
# Needs: ninja -C BUILD_DIR bench_ply_read bench_gen_surface
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
build=${1:-${SCANLOD_BUILD_DIR:-$root/build}}
runs=${2:-7}
((runs >= 5)) || runs=5
data=${SCANLOD_SHARED_DATA:-$root/../shared/data}
bench=$build/scripts/bench/ply_read_bench
gen=$build/scripts/bench/gen_surface
for tool in "$bench" "$gen"; do
    [[ -x $tool ]] || { echo "missing $tool: ninja -C $build bench_ply_read bench_gen_surface" >&2; exit 64; }
done
tmp=$(mktemp -d "${TMPDIR:-/tmp}/bench_ply_read.XXXXXX")
trap 'rm -rf "$tmp"' EXIT

files=()
[[ -f $data/igea.ply ]] && files+=("$data/igea.ply")
[[ -f $data/bun_zipper.ply ]] && files+=("$data/bun_zipper.ply")
"$gen" --triangles 8000000 -o "$tmp/torus_8M.ply" > /dev/null
"$gen" --triangles 2000000 -o "$tmp/torus_2M.ply" > /dev/null
"$bench" to-ascii "$tmp/torus_2M.ply" "$tmp/torus_2M_ascii.ply"
rm "$tmp/torus_2M.ply"
files+=("$tmp/torus_8M.ply" "$tmp/torus_2M_ascii.ply")

# median min max of the numbers on stdin
stats() { sort -g | awk '{v[NR] = $1} END {m = NR % 2 ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2;
                                           printf "%.6f %.6f %.6f\n", m, v[1], v[NR]}'; }

cat_seconds() {
    local f=$1 i t0 t1
    for ((i = 0; i < runs; i++)); do
        t0=$EPOCHREALTIME
        cat "$f" > /dev/null
        t1=$EPOCHREALTIME
        awk -v a="$t0" -v b="$t1" 'BEGIN {printf "%.6f\n", b - a}'
    done
}

printf '%-22s %-6s %8s | %-24s | %-10s | %-24s | %8s | %s\n' file format MB \
    "cat MB/s med (min-max)" "read() MB/s" "reader MB/s med (min-max)" "Mvert/s" "reader/read()"
for f in "${files[@]}"; do
    cat "$f" > /dev/null
    read -r cmed cmin cmax < <(cat_seconds "$f" | stats)
    line=$("$bench" read "$f" "$runs")
    get() { sed -n "s/.* $1=\([^ ]*\).*/\1/p" <<< "$line"; }
    bytes=$(get bytes)
    format=$(head -c 200 "$f" | sed -n 's/^format \([a-z_]*\).*/\1/p' | sed 's/binary_little_endian/bin LE/;s/binary_big_endian/bin BE/')
    mb=$(awk -v b="$bytes" 'BEGIN {printf "%.3f", b / 1e6}')
    mbps() { awk -v mb="$mb" -v s="$1" 'BEGIN {printf "%.0f", mb / s}'; }
    printf '%-22s %-6s %8.1f | %6s (%6s-%6s)    | %-10s | %6s (%6s-%6s)    | %8s | %s\n' \
        "$(basename "$f")" "$format" "$mb" "$(mbps "$cmed")" "$(mbps "$cmax")" "$(mbps "$cmin")" \
        "$(get read_MBps)" "$(get ply_MBps)" "$(mbps "$(get ply_max_s)")" \
        "$(mbps "$(get ply_min_s)")" "$(get ply_Mvertices_per_s)" "$(get ply_vs_read)"
done
echo "runs per figure: $runs; host: $(nproc) cores, load $(cut -d' ' -f1-3 /proc/loadavg)"
