#!/usr/bin/env bash
# Crash at the durability points of a run, one at a time (SQLite's crash test; reliability
# T1), beside the random kills of test_crash_resume.sh. A counting run of one item
# (SCANLOD_FAULT_COUNT, core/io.h) lists every durable call of the engine and of each of
# its per-item children. Then for each chosen point N of a process, a run crashes there:
# SCANLOD_FAULT=any:N:crash in the engine (exit 99), any:N:halt in its K-th child
# (SCANLOD_FAULT_SCOPE=child:K: the child takes the engine down, exit 137, as a power cut
# would). Each crash must have happened at N exactly (its count file marks call N of that
# process and shows nothing after it), `scanlod verify` must pass on what the crash left,
# and a plain rerun must finish byte-identical to the clean run (records included, so the
# final state verifies as the clean one does), with no temp file left.
#
# Points: every point whose context (the process's 3 calls before and after it, with the
# call itself) is new in the run, so every kind of point is crashed at least once: the
# 70-odd directory creations of a fresh work folder are one kind, the six stages' claim,
# commit and enqueue sequences are the same calls in the same order. Besides those, every
# 8th point of each process, so that each stage and the publication see crashes too.
# SCANLOD_FAULT_POINTS=all crashes at every point (600-odd runs); SCANLOD_LIGHT=1 (the
# sanitizer pass) keeps the new contexts only.
source "$(dirname "$0")/../lib.sh"

mkdir -p "$TMP/in"
cp "$SCANLOD_SOURCE_DIR/tests/data/octahedron.ply" "$TMP/in/" # tiny: the points, not the geometry
# The sanitizer pass: the refine stage without its fit (most of a light run's CPU under
# ASan); the reference and the faulted runs share the config.
refine_lines=()
light && refine_lines=("[refine]" "fit = false")
write_config "$TMP/ref.ini" "$TMP/in" "$TMP/ref-work" "$TMP/ref-out" "threads = 1" "${refine_lines[@]}"
SCANLOD_FAULT_COUNT="$TMP/points" run_scanlod run "$TMP/ref.ini" -q
check "counting run exits 0 (got $rc: $err)" [ "$rc" -eq 0 ]
ref=$(tree_digest "$TMP/ref-work" "$TMP/ref-out")
run_scanlod verify "$TMP/ref.ini"
check "the clean run verifies ($out)" [ "$rc" -eq 0 ]

# "ROLE N CONTEXT" for every point of the counting run, in order (ROLE parent or child:K).
awk '{ role[NR] = $2; any[NR] = $5; op[$2, $5] = $3; if ($5 > last[$2]) last[$2] = $5 }
     END { for (i = 1; i <= NR; i++) {
             r = role[i]; n = any[i]; ctx = (r == "parent" ? "parent" : "child")
             for (j = n - 3; j <= n + 3; j++) ctx = ctx "," ((j >= 1 && j <= last[r]) ? op[r, j] : "-")
             print r, n, ctx } }' "$TMP/points" >"$TMP/all"
processes=$(cut -d' ' -f1 "$TMP/all" | sort -u | wc -l)
parent_points=$(grep -c '^parent ' "$TMP/all" || true)
child_points=$(grep -c '^child:' "$TMP/all" || true)
check "one engine and its 7 stage processes counted ($processes)" [ "$processes" -eq 8 ]
check "the engine has 100+ points ($parent_points), the children some ($child_points)" \
  [ "$parent_points" -ge 100 -a "$child_points" -ge 12 ]
case "${SCANLOD_FAULT_POINTS:-}:${SCANLOD_LIGHT:-}" in
  all:*) stride=1 ;;
  *:1) stride=0 ;;
  *) stride=8 ;;
esac
awk -v stride="$stride" '!seen[$3]++ || (stride > 0 && $2 % stride == 0) { print $1, $2 }' \
  "$TMP/all" >"$TMP/chosen"
# Every kind of call of each scope is among the chosen points.
kinds() { # kinds FILE: "scope op" of each point listed in FILE ("ROLE N ..." lines)
  awk 'NR == FNR { op[$2, $5] = $3; next }
       { print ($1 == "parent" ? "parent" : "child"), op[$1, $2] }' "$TMP/points" "$1" | sort -u
}
check "every kind of call is crashed at least once" [ "$(kinds "$TMP/all")" = "$(kinds "$TMP/chosen")" ]
echo "crashing at $(wc -l <"$TMP/chosen") of $((parent_points + child_points)) points" \
     "($parent_points in the engine, $child_points in 7 stage processes)" >&2

write_config "$TMP/c.ini" "$TMP/in" "$TMP/work" "$TMP/out" "threads = 1" "${refine_lines[@]}"
missed=0 unverified=0 unfinished=0 differ=0 leftover=0 tried=0
while read -r role n; do
  tried=$((tried + 1))
  rm -rf "$TMP/work" "$TMP/out" "$TMP/logs" "$TMP/count"
  if [ "$role" = parent ]; then
    fault=any:$n:crash scope=parent want=99
  else
    fault=any:$n:halt scope=$role want=137 # the engine SIGKILLed by its child
  fi
  # (In a subshell, which takes the shell's "Killed" notice of the halted runs.)
  ( set +e
    SCANLOD_FAULT=$fault SCANLOD_FAULT_SCOPE=$scope SCANLOD_FAULT_COUNT="$TMP/count" \
      timeout 120 "$SCANLOD" run "$TMP/c.ini" -q >/dev/null 2>"$TMP/crash.err"
    echo $? >"$TMP/crash.rc" ) 2>/dev/null
  crash_rc=$(cat "$TMP/crash.rc")
  # The crash happened at N: its line is marked, it is call N of that process, and that
  # process made no call after it.
  reached=$(awk -v role="$role" -v n="$n" '
      $6 != "" { marked++; if ($2 == role && $5 == n) { hit = 1; pid = $1 } }
      { last[$1] = $5 > last[$1] ? $5 : last[$1] }
      END { print (marked == 1 && hit && last[pid] == n) ? "yes" : "no" }' "$TMP/count" 2>/dev/null || echo no)
  if [ "$crash_rc" -ne "$want" ] || [ "$reached" != yes ]; then
    missed=$((missed + 1))
    echo "$role any:$n: exit $crash_rc (want $want), crash at N: $reached; $(tail -c 300 "$TMP/crash.err")" >&2
  fi
  run_scanlod verify "$TMP/c.ini"
  [ "$rc" -eq 0 ] || { unverified=$((unverified + 1)); echo "$role any:$n: verify after the crash: $out $err" >&2; }
  run_scanlod run "$TMP/c.ini" -q
  if [ "$rc" -ne 0 ]; then
    unfinished=$((unfinished + 1)); echo "$role any:$n: the rerun exits $rc: $err" >&2
  elif ! same_digest "$ref" "$TMP/work" "$TMP/out"; then
    differ=$((differ + 1)); echo "$role any:$n: the rerun differs from the clean run" >&2
  fi
  temps=$(find "$TMP/work" "$TMP/out" -name '.*' ! -name '.' | wc -l)
  [ "$temps" -eq 0 ] || { leftover=$((leftover + 1)); echo "$role any:$n: $temps temp files left" >&2; }
done <"$TMP/chosen"
check "every crash happened at its point N ($missed of $tried did not)" [ "$missed" -eq 0 ]
check "every crash left records that verify ($unverified did not)" [ "$unverified" -eq 0 ]
check "every rerun exits 0 ($unfinished did not)" [ "$unfinished" -eq 0 ]
check "every rerun is byte-identical to the clean run ($differ differ)" [ "$differ" -eq 0 ]
check "no rerun leaves temp files ($leftover did)" [ "$leftover" -eq 0 ]
finish
