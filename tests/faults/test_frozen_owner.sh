#!/usr/bin/env bash
# A frozen owner at every rename (issue 16's liveness, made exact): test_liveness freezes a
# run wherever SIGSTOP happens to land; here a one-item run freezes itself right before
# its N-th rename (SCANLOD_FAULT=rename:N:stop, core/io.h), for every N of a clean run. A
# second run takes the claim over once the lease expired and finishes the collection;
# then the frozen run wakes up and ends. Expected at every N: the second run exits 0,
# the woken one 0 or 75; the log says each of the six stages done exactly once (the
# owner, or whoever adopted its commit); no claimed ticket is left behind (a woken owner
# must not re-create the claim it lost); verify passes and the result is byte-identical
# to a clean run. Every 3rd rename and the last (74 renames, a stage's ten renames recur
# with the same roles, so each role is hit in some stage); SCANLOD_LIGHT=1 (the sanitizer
# pass) every 5th.
source "$(dirname "$0")/../lib.sh"

mkdir -p "$TMP/in"
cp "$SCANS/bun_zipper_res4.ply" "$TMP/in/"
write_config "$TMP/ref.ini" "$TMP/in" "$TMP/ref-work" "$TMP/ref-out"
SCANLOD_FAULT_COUNT="$TMP/count.ref" run_scanlod run "$TMP/ref.ini" -q
check "clean run exits 0" [ "$rc" -eq 0 ]
ref=$(tree_digest "$TMP/ref-work" "$TMP/ref-out")
renames=$(awk '$2 == "parent" && $3 == "rename"' "$TMP/count.ref" | wc -l)
check "the engine renames 20+ times in a one-item run ($renames)" [ "$renames" -ge 20 ]

# state PID: the process's state letter (T when stopped), or nothing once it is gone.
state() { awk '{print $3}' "/proc/$1/stat" 2>/dev/null || true; }

step=3
light && step=5
mapfile -t points < <(seq 1 "$step" "$renames"; [ $(((renames - 1) % step)) -eq 0 ] || echo "$renames")
stopped=0 second_bad=0 woken_bad=0 misslogged=0 leftover=0 unverified=0 differ=0
for n in "${points[@]}"; do
  rm -rf "$TMP/work" "$TMP/out" "$TMP/logs"
  write_config "$TMP/c.ini" "$TMP/in" "$TMP/work" "$TMP/out" "[queue]" "lease_seconds = 2"
  SCANLOD_FAULT=rename:$n:stop SCANLOD_FAULT_SCOPE=parent \
    "$SCANLOD" run "$TMP/c.ini" -q >/dev/null 2>"$TMP/frozen.err" &
  frozen=$!
  for _ in $(seq 1 600); do # until it froze itself (or ended: then the point never came)
    s=$(state "$frozen")
    [ "$s" = T ] || [ -z "$s" ] || [ "$s" = Z ] && break
    sleep 0.05
  done
  if [ "$(state "$frozen")" != T ]; then
    echo "rename $n: the run never froze" >&2
    wait "$frozen" || true
    continue
  fi
  stopped=$((stopped + 1))
  set +e
  timeout 60 "$SCANLOD" run "$TMP/c.ini" -q >/dev/null 2>"$TMP/second.err"
  second=$?
  kill -CONT "$frozen"
  timeout 60 tail --pid="$frozen" -f /dev/null
  wait "$frozen"
  woken=$?
  set -e
  if [ "$second" -ne 0 ]; then
    second_bad=$((second_bad + 1)); echo "rename $n: second run exits $second: $(tail -n 2 "$TMP/second.err")" >&2
  fi
  if [ "$woken" -ne 0 ] && [ "$woken" -ne 75 ]; then
    woken_bad=$((woken_bad + 1)); echo "rename $n: woken run exits $woken: $(tail -n 2 "$TMP/frozen.err")" >&2
  fi
  done_events=$(cat "$TMP"/logs/*.jsonl 2>/dev/null | grep -c '"event":"stage_done"' || true)
  if [ "$done_events" -ne 7 ]; then
    misslogged=$((misslogged + 1)); echo "rename $n: $done_events stage_done events, not 7" >&2
  fi
  claims=$(find "$TMP/work/queue" -path '*/claimed/*' -type f ! -name '.*' 2>/dev/null)
  if [ -n "$claims" ]; then
    leftover=$((leftover + 1)); echo "rename $n: claims left behind: $claims" >&2
  fi
  run_scanlod verify "$TMP/c.ini"
  if [ "$rc" -ne 0 ]; then
    unverified=$((unverified + 1)); echo "rename $n: verify exits $rc: $out" >&2
  fi
  if [ "$ref" != "$(tree_digest "$TMP/work" "$TMP/out")" ]; then
    differ=$((differ + 1)); echo "rename $n: the result differs from a clean run" >&2
  fi
done
echo "${#points[@]} of $renames renames: the run froze before each, another took over" >&2
check "the run froze at every point ($stopped of ${#points[@]})" [ "$stopped" -eq "${#points[@]}" ]
check "every second run exits 0 ($second_bad did not)" [ "$second_bad" -eq 0 ]
check "every woken run exits 0 or 75 ($woken_bad did not)" [ "$woken_bad" -eq 0 ]
check "every stage is logged done once ($misslogged runs did not)" [ "$misslogged" -eq 0 ]
check "no claim is left behind ($leftover runs left one)" [ "$leftover" -eq 0 ]
check "verify passes after both ($unverified did not)" [ "$unverified" -eq 0 ]
check "every result equals a clean run ($differ differ)" [ "$differ" -eq 0 ]
finish
