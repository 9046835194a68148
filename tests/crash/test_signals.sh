#!/usr/bin/env bash
# Interrupts (ARCHITECTURE section 2): SIGTERM, SIGINT and SIGUSR1 (Slurm's pre-timeout
# warning) make a run stop at a safe point and exit 75 with nothing partial published; the
# next run finishes byte-identical to an uninterrupted one.
source "$(dirname "$0")/../lib.sh"

mkdir -p "$TMP/in"
for f in "$SCANS"/*.ply; do cp "$f" "$TMP/in/"; done
write_config "$TMP/ref.ini" "$TMP/in" "$TMP/ref-work" "$TMP/ref-out"
run_scanlod run "$TMP/ref.ini" -q
check "clean run exits 0" [ "$rc" -eq 0 ]
ref=$(tree_digest "$TMP/ref-work" "$TMP/ref-out")

write_config "$TMP/c.ini" "$TMP/in" "$TMP/work" "$TMP/out"
for sig in TERM INT USR1; do
  "$SCANLOD" run "$TMP/c.ini" -q >/dev/null 2>"$TMP/sig.err" &
  pid=$!
  sleep 1.5
  kill -"$sig" "$pid" 2>/dev/null || true # the run may already have finished
  set +e; wait "$pid"; status=$?; set -e
  check "SIG$sig: exit 75 or already done (got $status)" [ "$status" -eq 75 -o "$status" -eq 0 ]
  run_scanlod verify "$TMP/c.ini"
  check "SIG$sig: every committed record verifies" [ "$rc" -eq 0 ]
  claimed=$(find "$TMP/work/queue" -path '*/claimed/*' -type f 2>/dev/null | wc -l || true)
  check "SIG$sig: no item left claimed ($claimed)" [ "$claimed" -eq 0 ]
done
run_scanlod run "$TMP/c.ini" -q
check "resume exits 0 (got $rc: $err)" [ "$rc" -eq 0 ]
check "resumed output identical to an uninterrupted run" same_digest "$ref" "$TMP/work" "$TMP/out"
finish
