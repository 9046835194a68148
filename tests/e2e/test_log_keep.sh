#!/usr/bin/env bash
# Log files rotate by a config key (issue 34 item 6): every run writes RUN.log and
# RUN.jsonl, and [run] log_keep keeps those of the newest runs only, never those of a run
# still going on this host, nor files that are not a run's log. Before, nothing but the
# cron script deleted any: 50 runs with nothing to do left 100 files.
source "$(dirname "$0")/../lib.sh"

mkdir -p "$TMP/in" "$TMP/logs"
cp "$SCANS/bun_zipper_res4.ply" "$TMP/in/"
write_config "$TMP/c.ini" "$TMP/in" "$TMP/work" "$TMP/out" "log_keep = 2"
echo "an operator's note" >"$TMP/logs/notes.log"
run_logs() { find "$TMP/logs" -name '2*Z-*' -type f | wc -l; }

for i in 1 2 3 4 5; do
  run_scanlod run "$TMP/c.ini" -q
  check "run $i exits 0 (got $rc: $err)" [ "$rc" -eq 0 ]
done
check "five runs, log_keep = 2: the files of two runs are left ($(run_logs))" [ "$(run_logs)" -eq 4 ]
check "the newest run's two files among them" \
  [ -f "$(ls "$TMP"/logs/2*.log | tail -1)" -a "$(ls "$TMP"/logs/2*.jsonl | wc -l)" -eq 2 ]
check "a file that is not a run's log is left alone" grep -qx "an operator's note" "$TMP/logs/notes.log"
check "the run says what it deleted" grep -q "deleted 2 log files of runs older than the newest 2" "$TMP"/logs/2*.log

# A run still going keeps its log, however many runs came after it: one frozen before its
# first rename (another collection, the same logs folder), then two runs at log_keep = 1.
write_config "$TMP/f.ini" "$TMP/in" "$TMP/fwork" "$TMP/fout"
SCANLOD_FAULT=rename:1:stop SCANLOD_FAULT_SCOPE=parent "$SCANLOD" run "$TMP/f.ini" -q \
  >/dev/null 2>&1 &
frozen=$!
cleanup_hooks+=("kill -9 $frozen 2>/dev/null")
for _ in $(seq 1 100); do
  [ "$(ps -o stat= -p "$frozen" | cut -c1)" = T ] && break
  sleep 0.05
done
sleep 1.1 # the runs after it get later stamps
frozen_log=$(ls "$TMP"/logs/2*-"$frozen".log)
for i in 1 2; do
  run_scanlod run "$TMP/c.ini" -q -s run.log_keep=1
done
check "the frozen run's log is kept" [ -f "$frozen_log" ]
check "beside it, the newest run's only ($(ls "$TMP/logs"))" [ "$(run_logs)" -eq 4 ]
kill -9 "$frozen"
wait "$frozen" 2>/dev/null || true
run_scanlod run "$TMP/c.ini" -q -s run.log_keep=1
check "once it is gone its log goes too" [ ! -f "$frozen_log" -a "$(run_logs)" -eq 2 ]
run_scanlod run "$TMP/c.ini" -q -s run.log_keep=0
run_scanlod run "$TMP/c.ini" -q -s run.log_keep=0
check "log_keep = 0 keeps every log" [ "$(run_logs)" -eq 6 ]
finish
