#!/usr/bin/env bash
# Liveness (issue 16 items 6 and 7): a frozen owner does not hang the batch, and a
# worker started before the scan waits for it instead of calling an empty queue "done".
#  - A run stopped with SIGSTOP (as a Slurm suspend or an NFS D-state would leave it)
#    while it holds a claim: a second run reclaims the claim once its lease expired
#    (a live pid is not a live owner), finishes the collection, and the frozen run,
#    woken up, commits nothing; the result is byte-identical to a clean run.
#  - `scanlod worker` on a work folder no scan has filled yet waits for the scan
#    (exit 75 when none comes), and `--after-scan JOB` waits for that job's scan.
source "$(dirname "$0")/../lib.sh"

mkdir -p "$TMP/in"
cp "$SCANS/cow.ply" "$SCANS/bun_zipper_res3.ply" "$SCANS/bun_zipper_res4.ply" "$TMP/in/"
write_config "$TMP/ref.ini" "$TMP/in" "$TMP/ref-work" "$TMP/ref-out"
run_scanlod run "$TMP/ref.ini" -q
check "clean run exits 0" [ "$rc" -eq 0 ]
ref=$(tree_digest "$TMP/ref-work" "$TMP/ref-out")
rm -rf "$TMP/logs" # from here on, the logs are the two runs' below

write_config "$TMP/c.ini" "$TMP/in" "$TMP/work" "$TMP/out" "[queue]" "lease_seconds = 2"
setsid "$SCANLOD" run "$TMP/c.ini" -q >"$TMP/frozen.out" 2>"$TMP/frozen.err" &
frozen=$!
cleanup_hooks+=("kill -CONT -$frozen 2>/dev/null; kill -KILL -$frozen 2>/dev/null")
for _ in $(seq 1 200); do # until it holds a claim
  [ -n "$(find "$TMP/work/queue" -path '*/claimed/*' ! -path '*/_scan/*' 2>/dev/null)" ] && break
  sleep 0.05
done
kill -STOP -"$frozen" # the whole process group: the engine and its stage process
check "the frozen run holds a claim" [ -n "$(find "$TMP/work/queue" -path '*/claimed/*' ! -path '*/_scan/*')" ]

start=$(date +%s)
set +e
timeout 120 "$SCANLOD" run "$TMP/c.ini" >"$TMP/second.out" 2>"$TMP/second.err"
second=$?
set -e
elapsed=$(( $(date +%s) - start ))
check "second run finishes the collection: exit 0 (got $second: $(tail -n 3 "$TMP/second.err"))" [ "$second" -eq 0 ]
check "it did not wait without limit ($elapsed s)" [ "$elapsed" -lt 100 ]
check "it reclaimed the frozen claim (log)" grep -q "reclaimed from .* (owner gone)" "$TMP/second.err"

kill -CONT -"$frozen"
set +e
timeout 60 tail --pid="$frozen" -f /dev/null
woke=$?
wait "$frozen"
frozen_rc=$?
set -e
check "the frozen run, woken up, ends (timeout: $woke)" [ "$woke" -eq 0 ]
check "it exits 0 or 75 (got $frozen_rc)" [ "$frozen_rc" -eq 0 -o "$frozen_rc" -eq 75 ]
done_events=$(cat "$TMP/logs"/*.jsonl | grep -c '"stage_done"' || true)
check "each of the 3 x 7 stages is done once, by one owner ($done_events stage_done events)" [ "$done_events" -eq 21 ]
[ "$done_events" -eq 21 ] || cat "$TMP/logs"/*.jsonl | grep '"stage_done"' >&2
run_scanlod verify "$TMP/c.ini"
check "verify after both: exit 0 (got $rc: $out)" [ "$rc" -eq 0 ]
check "result byte-identical to the clean run" same_digest "$ref" "$TMP/work" "$TMP/out"

# A worker before any scan waits for it, then works with it.
write_config "$TMP/w.ini" "$TMP/in" "$TMP/w-work" "$TMP/w-out"
run_scanlod worker "$TMP/w.ini" --wait 1
check "worker, no scan ever: exit 75, not 0 (got $rc: $out)" [ "$rc" -eq 75 ]
check "worker, no scan ever: says why (got: $err)" grep -q "no scan has run in this work folder within 1 s" <<<"$err"
"$SCANLOD" worker "$TMP/w.ini" --wait 60 -q >"$TMP/worker.out" 2>"$TMP/worker.err" &
worker=$!
sleep 1
check "the worker is still waiting a second later" kill -0 "$worker"
run_scanlod run "$TMP/w.ini" -q
check "the run exits 0 (got $rc)" [ "$rc" -eq 0 ]
set +e
wait "$worker"
worker_rc=$?
set -e
check "the waiting worker ends with the run's code, 0 (got $worker_rc)" [ "$worker_rc" -eq 0 ]
run_scanlod worker "$TMP/w.ini" --after-scan 4242 --wait 1
check "--after-scan of a job that never scanned: exit 75 (got $rc)" [ "$rc" -eq 75 ]
run_scanlod worker "$TMP/w.ini" --wait 1
check "after a scan, a worker proceeds at once (got $rc: $out)" [ "$rc" -eq 0 ]
run_scanlod worker "$TMP/w.ini" --wait -1
check "--wait takes seconds (got $rc)" [ "$rc" -eq 64 ]
finish
