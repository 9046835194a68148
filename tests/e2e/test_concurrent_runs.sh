#!/usr/bin/env bash
# Overlapping runs (reliability T14): two `scanlod run` and one `scanlod worker` on one
# work dir at once cooperate through the queues: all exit 0, every item is done once in
# the final state, and the result equals a single clean run's.
source "$(dirname "$0")/../lib.sh"

scans=("$SCANS"/*.ply)
if light; then # the sanitizer pass: 6 small items, 15 in the Release pass
  scans=("$SCANS/bun_zipper_res4.ply" "$SCANS/cow.ply")
  echo "LIGHT: 3 copies of 2 small scans (of all 5 in the Release pass)"
fi
mkdir -p "$TMP/in"
for i in 1 2 3; do for f in "${scans[@]}"; do cp "$f" "$TMP/in/$i-$(basename "$f")"; done; done
write_config "$TMP/ref.ini" "$TMP/in" "$TMP/ref-work" "$TMP/ref-out"
run_scanlod run "$TMP/ref.ini" -q
check "clean run exits 0" [ "$rc" -eq 0 ]
ref=$(tree_digest "$TMP/ref-work" "$TMP/ref-out")

write_config "$TMP/c.ini" "$TMP/in" "$TMP/work" "$TMP/out"
"$SCANLOD" run "$TMP/c.ini" -q --threads 1 >"$TMP/a.out" 2>"$TMP/a.err" & a=$!
"$SCANLOD" run "$TMP/c.ini" -q --threads 1 >"$TMP/b.out" 2>"$TMP/b.err" & b=$!
sleep 0.3
"$SCANLOD" worker "$TMP/c.ini" -q --threads 1 >"$TMP/w.out" 2>"$TMP/w.err" & w=$!
set +e; wait $a; ra=$?; wait $b; rb=$?; wait $w; rw=$?; set -e
# Each waits for the others' claims, so each can report the finished collection.
check "first run exits 0 (got $ra: $(cat "$TMP/a.err"))" [ "$ra" -eq 0 ]
check "second run exits 0 (got $rb: $(cat "$TMP/b.err"))" [ "$rb" -eq 0 ]
check "worker exits 0 (got $rw: $(cat "$TMP/w.err"))" [ "$rw" -eq 0 ]
run_scanlod run "$TMP/c.ini" -q
check "afterwards: nothing to do (got: $out)" grep -q "^nothing to do" <<<"$out"
check "result identical to a single run" [ "$ref" = "$(tree_digest "$TMP/work" "$TMP/out")" ]
finish
