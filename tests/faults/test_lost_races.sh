#!/usr/bin/env bash
# Losing a race (reliability T14): any rename of the engine's own process may find its
# source gone, as it does when another worker moved the ticket first. For each rename of
# a one-item run in turn, ENOENT is injected there (SCANLOD_FAULT). Expected: no run
# hangs; every run exits 0, or non-zero with an error on stderr (never a silent exit 75,
# which a lost claim race used to cause: tests/e2e/test_concurrent_runs.sh saw it under
# load); a plain rerun then finishes the collection identical to a clean run. The renames
# are counted in a clean run first (SCANLOD_FAULT_COUNT, core/io.h) and every one is
# injected; each injected run's own count must mark its rename N as failed with ENOENT,
# so a fault that never fired (an N past the run's renames, injection broken) fails the
# test instead of passing it. SCANLOD_LIGHT=1 (the sanitizer pass): every 4th rename and
# the last; the Release pass injects every one.
source "$(dirname "$0")/../lib.sh"

mkdir -p "$TMP/in"
cp "$SCANS/bun_zipper_res4.ply" "$TMP/in/"
write_config "$TMP/ref.ini" "$TMP/in" "$TMP/ref-work" "$TMP/ref-out"
SCANLOD_FAULT_COUNT="$TMP/count.ref" run_scanlod run "$TMP/ref.ini" -q
check "clean run exits 0" [ "$rc" -eq 0 ]
ref=$(tree_digest "$TMP/ref-work" "$TMP/ref-out")
renames=$(awk '$2 == "parent" && $3 == "rename"' "$TMP/count.ref" | wc -l)
check "the engine renames 20+ times in a one-item run ($renames)" [ "$renames" -ge 20 ]

# run_timed CONFIG [env...]: like run_scanlod run CONFIG -q, under a 60 s timeout (124).
run_timed() {
  local config=$1; shift
  set +e
  env "$@" timeout 60 "$SCANLOD" run "$config" -q >/dev/null 2>"$TMP/err"
  rc=$?
  set -e
  err=$(cat "$TMP/err")
}

step=1
if light; then
  step=4
  echo "LIGHT: every 4th of the $renames renames and the last; all of them in the Release pass"
fi
mapfile -t points < <(seq 1 "$step" "$renames"; [ $(((renames - 1) % step)) -eq 0 ] || echo "$renames")
hung=0 silent=0 unfinished=0 differ=0 faulted=0 fired=0 misslogged=0
for n in "${points[@]}"; do
  rm -rf "$TMP/work" "$TMP/out" "$TMP/count" "$TMP/logs"
  write_config "$TMP/c.ini" "$TMP/in" "$TMP/work" "$TMP/out"
  run_timed "$TMP/c.ini" SCANLOD_FAULT=rename:$n:ENOENT SCANLOD_FAULT_SCOPE=parent \
    SCANLOD_FAULT_COUNT="$TMP/count"
  if awk -v n="$n" '$2 == "parent" && $3 == "rename" && $4 == n && $6 == "ENOENT"' "$TMP/count" |
     grep -q .; then
    fired=$((fired + 1))
  else
    echo "rename $n: the fault did not fire" >&2
  fi
  if [ "$rc" -eq 124 ]; then
    hung=$((hung + 1)); echo "rename $n: the run hung" >&2
  elif [ "$rc" -ne 0 ]; then
    faulted=$((faulted + 1))
    if ! grep -q "ERROR" <<<"$err"; then
      silent=$((silent + 1)); echo "rename $n: exit $rc without an error" >&2
    fi
  fi
  run_timed "$TMP/c.ini"
  if [ "$rc" -ne 0 ]; then
    unfinished=$((unfinished + 1)); echo "rename $n: the rerun exits $rc: $err" >&2
  elif [ "$ref" != "$(tree_digest "$TMP/work" "$TMP/out")" ]; then
    differ=$((differ + 1)); echo "rename $n: the rerun differs from a clean run" >&2
  fi
  # The log tells the same story: over the injected run and its rerun, each of the six
  # stages is said done once, whether its owner or the run that adopted its commit says so.
  done_events=$(cat "$TMP"/logs/*.jsonl 2>/dev/null | grep -c '"event":"stage_done"' || true)
  if [ "$done_events" -ne 7 ]; then
    misslogged=$((misslogged + 1)); echo "rename $n: $done_events stage_done events, not 7" >&2
  fi
done
echo "${#points[@]} of $renames renames injected: $faulted runs failed with an error, the rest finished" >&2
check "every injected rename fired ($fired of ${#points[@]})" [ "$fired" -eq "${#points[@]}" ]
# Most lost renames are a claim or a move another worker made first, which a run takes in
# its stride; some must end the run with an error, or the faults changed nothing.
check "some injected runs failed with an error ($faulted)" [ "$faulted" -gt 0 ]
check "no run hangs ($hung did)" [ "$hung" -eq 0 ]
check "no silent non-zero exit ($silent)" [ "$silent" -eq 0 ]
check "every rerun exits 0 ($unfinished did not)" [ "$unfinished" -eq 0 ]
check "every rerun equals a clean run ($differ differ)" [ "$differ" -eq 0 ]
check "every stage is logged done once ($misslogged runs did not)" [ "$misslogged" -eq 0 ]
finish
