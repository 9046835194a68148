#!/usr/bin/env bash
# A split is a property of the item's current config (issue 34 item 4): reconciliation
# removes the parts of any other split, and of every split once the stage is committed;
# a split that is running (a live worker holds one of its parts) or complete is finished
# rather than undone, so workers whose [queue] part_mb differ cooperate. And a failed
# part waits for the next run, as its log line says. Before: after a kill -9 with the
# join claimed and part_mb = 0, the 10 part folders and done tickets stayed for good
# ("samples done 11"); two runs with different part_mb undid each other's split (82-157
# stage runs, or exit 75 after 50 s; stale parts left); a killed part "will retry on the
# next run" ran again in the same run.
source "$(dirname "$0")/../lib.sh"

mkdir -p "$TMP/in"
cp "$SCANS/bun_zipper_res3.ply" "$TMP/in/"
# 148,524 bytes: 0.015 MB parts make 10 of them, 0.03 MB 5.
write_config "$TMP/c.ini" "$TMP/in" "$TMP/work" "$TMP/out" "threads = 1" "[queue]" "part_mb = 0.015"
run_scanlod run "$TMP/c.ini" -q -s queue.part_mb=0
check "reference (unsplit) exits 0 ($err)" [ "$rc" -eq 0 ]
ref=$(tree_digest "$TMP/work" "$TMP/out")

parts_left() { find "$TMP/work/queue" "$TMP/work/artifacts" -name '*#part-*' ! -name '.*' | wc -l; }
# killed_when CONDITION: a fresh split run, killed -9 once CONDITION holds. The join of
# this small scan is claimed for some tens of milliseconds: a poll that misses it (ctest's
# other job holding the core) sees the run finish, and the run is tried again, up to 5
# times, so the kill lands where CONDITION says or the check after it fails.
killed_when() {
  local attempt pid held
  for attempt in 1 2 3 4 5; do
    rm -rf "$TMP/work" "$TMP/out"
    "$SCANLOD" run "$TMP/c.ini" -q >/dev/null 2>&1 &
    pid=$! held=0
    while kill -0 "$pid" 2>/dev/null; do
      if eval "$1"; then held=1; break; fi
      sleep 0.01
    done
    kill -9 "$pid" 2>/dev/null || true
    wait "$pid" 2>/dev/null || true
    [ "$held" -eq 0 ] || return 0
  done
}
# settles WHAT PART_MB: two runs at PART_MB exit 0, nothing of a split is left, and the
# result is the unsplit one's, byte for byte.
settles() {
  run_scanlod run "$TMP/c.ini" -q -s "queue.part_mb=$2"
  check "$1: exit 0 (got $rc: $err)" [ "$rc" -eq 0 ]
  run_scanlod run "$TMP/c.ini" -q -s "queue.part_mb=$2"
  check "$1: then nothing to do ($rc: $out)" contains "^nothing to do" "$out"
  check "$1: no part ticket or folder left ($(parts_left))" [ "$(parts_left)" -eq 0 ]
  run_scanlod status "$TMP/c.ini" -s "queue.part_mb=$2"
  check "$1: status counts the item's samples once ($out)" grep -qE '^samples +0 +0 +1 +0 +0$' <<<"$out"
  check "$1: the unsplit result" same_digest "$ref" "$TMP/work" "$TMP/out"
}

killed_when '[ -e "$TMP/work/queue/samples/claimed/bun_zipper_res3.ply" ]'
check "killed with the join claimed, its 10 parts done" \
  [ "$(ls "$TMP/work/queue/samples/done" | grep -c '#part-')" -eq 10 ]
settles "join claimed, then part_mb = 0" 0
killed_when '[ "$(ls "$TMP/work/queue/samples/done" 2>/dev/null | grep -c "#part-")" -ge 4 ]'
settles "4 of 10 parts done, then 5 parts" 0.03
killed_when '[ "$(ls "$TMP/work/queue/samples/done" 2>/dev/null | grep -c "#part-")" -ge 4 ]'
settles "4 of 10 parts done, then unsplit" 0

# Two runs at once, 10 and 5 parts: they finish one split between them.
rm -rf "$TMP/work" "$TMP/out"
"$SCANLOD" run "$TMP/c.ini" -q -s queue.part_mb=0.015 >"$TMP/a.out" 2>"$TMP/a.err" &
a=$!
"$SCANLOD" run "$TMP/c.ini" -q -s queue.part_mb=0.03 >"$TMP/b.out" 2>"$TMP/b.err" &
b=$!
set +e; wait "$a"; ra=$?; wait "$b"; rb=$?; set -e
check "10 and 5 parts at once: both exit 0 (got $ra, $rb: $(cat "$TMP/a.err" "$TMP/b.err"))" \
  [ "$ra" -eq 0 -a "$rb" -eq 0 ]
runs=$(cat "$TMP/a.out" "$TMP/b.out" | grep -o '[0-9]* stage runs' | awk '{s += $1} END {print s + 0}')
# One split's work is 11 (5 parts) to 16 (10 parts) stage runs; some parts of the other
# split may run before both agree.
check "10 and 5 parts at once: $runs stage runs, at most 30" [ "$runs" -le 30 ]
settles "10 and 5 parts at once" 0.015

# A part killed by a SIGKILL nobody in scanlod sent fails for this run; its siblings'
# commits do not requeue it. The 3rd stage process (range, part 1, part 2) stops itself.
rm -rf "$TMP/work" "$TMP/out"
run_killing_child child:3 "$TMP/c.ini"
check "a part's process stopped itself" [ -n "$child" ]
log=$(ls "$TMP"/logs/*-"$runner".log)
check "killed part: the run exits 75, the item not done (got $rc: $err)" [ "$rc" -eq 75 ]
check "killed part: it says it will retry on the next run" grep -q "failed (will retry on the next run)" "$log"
starts=$(grep -c "start part" "$log")
check "killed part: 10 part starts in the run, none again ($starts)" [ "$starts" -eq 10 ]
settles "killed part, next runs" 0.015
finish
