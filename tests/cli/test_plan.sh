#!/usr/bin/env bash
# `scanlod plan CONFIG [--json]`: a pre-flight estimate per item from the PLY headers and
# the config, nothing run or written. Asserted: the counts are the headers' counts, a bad
# scan is named with its cause (exit 65) while the others are still planned, the memory
# limit is checked, the parts of [queue] part_mb are counted, the work folder is not
# created, and the predicted peak memory of a
# real item is within 30 % of what its run then takes (issue 14's aim).
source "$(dirname "$0")/../lib.sh"
scans="$SCANLOD_SOURCE_DIR/tests/data/scans"

mkdir -p "$TMP/in"
cp "$scans/rocker_arm.ply" "$scans/cow.ply" "$TMP/in/"
cp "$SCANLOD_SOURCE_DIR/tests/data/malformed/garbage_header.ply" "$TMP/in/broken.ply"
write_config "$TMP/run.ini" "$TMP/in" "$TMP/work" "$TMP/out"

run_scanlod plan "$TMP/run.ini" --json
check "a bad scan: exit 65" [ "$rc" -eq 65 ]
check "nothing written: no work folder" [ ! -e "$TMP/work" ]
check "nothing written: no output folder" [ ! -e "$TMP/out" ]
echo "$out" >"$TMP/plan.json"
field() { # field ITEM KEY: a value of the item's plan
  python3 -c 'import json,sys
p = json.load(open(sys.argv[1]))
print([i for i in p["items"] if i["item"] == sys.argv[2]][0].get(sys.argv[3]))' \
    "$TMP/plan.json" "$1" "$2"
}
check "rocker_arm: the header's triangles" [ "$(field rocker_arm.ply triangles)" = 20088 ]
check "cow: the header's vertices" [ "$(field cow.ply vertices)" = 2904 ]
check "broken: named with its cause" contains "broken.ply.*header" "$(field broken.ply error)"
check "every stage of the method estimated" [ "$(python3 -c 'import json,sys
p = json.load(open(sys.argv[1]))
print(",".join(p["items"][1]["stages"]))' "$TMP/plan.json")" = \
  "range,samples,merge,priority,crack,refine,export" ]
check "totals: three items, one error" [ "$(python3 -c 'import json,sys
t = json.load(open(sys.argv[1]))["totals"]
print(t["items"], t["errors"])' "$TMP/plan.json")" = "3 1" ]

run_scanlod plan "$TMP/run.ini" -s run.memory_limit_mb=20
check "table: the over-limit item is said" contains "rocker_arm.ply .*over \[run\] memory_limit_mb" "$out"
check "table: the bad one is said" contains "broken.ply  *cannot be planned" "$out"
run_scanlod plan "$TMP/run.ini" -s lod.method=segment --json
check "segment method: its stages" contains '"segment"' "$out"
# [queue] part_mb: the samples stage's parts per item (docs/engine.md, "Parts"):
# rocker_arm (381,919 bytes) in parts of 0.1 MB is 4, cow (110,558 bytes) 2.
run_scanlod plan "$TMP/run.ini" -s queue.part_mb=0.1 --json
echo "$out" >"$TMP/plan.json"
check "parts: rocker_arm's samples in 4" [ "$(field rocker_arm.ply parts)" = "{'samples': 4}" ]
check "parts: cow's samples in 2" [ "$(field cow.ply parts)" = "{'samples': 2}" ]
run_scanlod plan "$TMP/run.ini" -s queue.part_mb=1
check "parts: none for inputs under one part (table)" [ "$(grep -c "in .* parts" <<<"$out")" = 0 ]
run_scanlod plan "$TMP/run.ini" -s queue.part_mb=0.2
check "parts: the table says them" contains "rocker_arm.ply .*samples in 2 parts" "$out"
run_scanlod plan "$TMP/run.ini" -s no.such=1
check "bad config key: exit 78" [ "$rc" -eq 78 ]
# [run] threads = 0 takes OMP_NUM_THREADS, as job scripts set it; a number in the config wins.
plan_threads() { # plan_threads THREADS: the plan's threads with OMP_NUM_THREADS=3
  OMP_NUM_THREADS=3 "$SCANLOD" plan "$TMP/run.ini" --json -s "run.threads=$1" 2>/dev/null |
    python3 -c 'import json, sys; print(json.load(sys.stdin)["threads"])'
}
check "threads = 0 honours OMP_NUM_THREADS=3 (plan: $(plan_threads 0))" [ "$(plan_threads 0)" = 3 ]
check "threads = 2 wins over OMP_NUM_THREADS=3 (plan: $(plan_threads 2))" [ "$(plan_threads 2)" = 2 ]

# The refine stage's collapses by bricks when the budget says so (sl_refine_collapse_bricks,
# the rule the stage applies): a 20 M-triangle header (a sparse file, planned from its
# header) under a 4 GB budget is costed on the bricked line, under 60 GB on the whole one.
mkdir -p "$TMP/big"
printf 'ply\nformat binary_little_endian 1.0\nelement vertex 10000000\nproperty float x\nproperty float y\nproperty float z\nelement face 20000000\nproperty list uchar int vertex_indices\nend_header\n' >"$TMP/big/big.ply"
truncate -s $(( $(stat -c %s "$TMP/big/big.ply") + 12 * 10000000 + 13 * 20000000 )) "$TMP/big/big.ply"
write_config "$TMP/big.ini" "$TMP/big" "$TMP/work-big" "$TMP/out-big"
refine_peak() { # refine_peak BUDGET_MB: the plan's refine peak for big.ply
  "$SCANLOD" plan "$TMP/big.ini" --json -s "run.memory_limit_mb=$1" 2>/dev/null |
    python3 -c 'import json, sys; print(round(json.load(sys.stdin)["items"][0]["stages"]["refine"]["peak_rss_mb"]))'
}
small=$(refine_peak 4096); large=$(refine_peak 60000)
check "refine by bricks under a 4 GB budget: $small MB, whole under 60 GB: $large MB" \
  python3 -c 'import sys; sys.exit(0 if 0 < float(sys.argv[1]) < 0.9 * float(sys.argv[2]) else 1)' "$small" "$large"

# The prediction against the run: the item's largest stage peak (timings.json).
rm "$TMP/in/broken.ply" "$TMP/in/cow.ply"
run_scanlod plan "$TMP/run.ini" --threads 2 --json
check "plan of good scans: exit 0" [ "$rc" -eq 0 ]
echo "$out" >"$TMP/plan.json"
predicted=$(field rocker_arm.ply peak_rss_mb)
"$SCANLOD" run "$TMP/run.ini" --threads 2 -q >/dev/null
measured=$(python3 -c 'import json,sys
s = json.load(open(sys.argv[1]))["stages"]
print(max(v["peak_rss_kb"] for v in s.values()) / 1024.0)' "$TMP/out/rocker_arm.ply/timings.json")
echo "rocker_arm: predicted peak $predicted MB, measured $measured MB"
if light; then
  echo "(sanitizer build: its memory is not the model's; ratio not checked)"
else
  check "peak memory within 30 %" python3 -c 'import sys
p, m = float(sys.argv[1]), float(sys.argv[2])
sys.exit(0 if 0.7 <= p / m <= 1.3 else 1)' "$predicted" "$measured"
fi
finish
