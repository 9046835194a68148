#!/usr/bin/env bash
# The Slurm array (issue 16, item 7; docs/cluster.md) on a real single-node Slurm that this
# test starts (tests/cluster/slurm.sh; skipped with a SKIP line where it cannot start):
# scripts/slurm/scanlod-array.sbatch as a 3-task array on 8 bundled scans. One worker task
# is scancelled while it runs an item, another gets the pre-timeout signal (USR1 to the
# batch shell, as --signal=B:USR1@300 sends it) and exits 75; then the array is submitted
# again. Expected: the cancelled task is not requeued by the script (it stays CANCELLED),
# the exit-75 task is requeued and finishes on its restart, every task of the second
# array completes, and the work dir and every published file (timings.json aside) are
# byte-identical to a clean `scanlod run` without Slurm (which, unlike the array's config,
# does not split the samples stage into parts). Takes about 45 s on 2 cores.
# SCANLOD_SLURM_SCRIPT tests another copy of the sbatch script (e.g. an older one).
source "$(dirname "$0")/../lib.sh"
source "$(dirname "$0")/slurm.sh"
script=${SCANLOD_SLURM_SCRIPT:-$SCANLOD_SOURCE_DIR/scripts/slurm/scanlod-array.sbatch}
started=$SECONDS
export SCANLOD # the jobs' environment comes from sbatch's

# A watchdog, so that a stuck cluster ends in a failure with its logs, never in a hang (and
# the EXIT trap still tears the daemons down). ctest's own timeout is longer.
trap 'echo "FAIL: watchdog: still running after ${SECONDS}s" >&2; exit 1' TERM
( trap 'kill "$s" 2>/dev/null; exit 0' TERM
  sleep "${SCANLOD_SLURM_TEST_TIMEOUT:-330}" & s=$!; wait "$s" && kill -TERM $$ ) 2>/dev/null &
watchdog=$!
cleanup_hooks+=("kill $watchdog 2>/dev/null")

# On a failure (or an early exit), the jobs' logs and the daemons' tell why.
completed=
show_logs() {
  [ -n "$completed" ] && [ "$failed" -eq 0 ] && return 0
  for f in "$TMP"/slurm-*.out; do [ -f "$f" ] && { echo "--- $(basename "$f")"; cat "$f"; }; done
  slurm_logs
} >&2
cleanup_hooks+=(show_logs)

mkdir -p "$TMP/in/again"
for f in "$SCANS"/*.ply; do cp "$f" "$TMP/in/"; done
for f in cow fandisk bun_zipper_res3; do cp "$SCANS/$f.ply" "$TMP/in/again/"; done
# The export (fidelity measured on 3 levels) makes an item last a second or more, so a
# cancel lands inside one; 8 items, so that every worker gets to an export.
export_lines=("[levels]" "percents = 20,50,100" "budgets =" "[export]" "formats = ply,glb"
              "thumbnail_size = 48" "fidelity = true")
write_config "$TMP/ref.ini" "$TMP/in" "$TMP/ref-work" "$TMP/ref-out" "${export_lines[@]}"
# The array's run splits the samples stage of the larger scans into parts of 0.1 MB of
# input (docs/engine.md, "Parts": each a ticket the tasks share); the clean run does not.
write_config "$TMP/c.ini" "$TMP/in" "$TMP/work" "$TMP/out" "${export_lines[@]}" \
  "[queue]" "part_mb = 0.1"

slurm_start 4
echo "slurm up after $((SECONDS - started))s"
run_scanlod run "$TMP/ref.ini" -q --threads 1
check "clean run exits 0 (got $rc: $err)" [ "$rc" -eq 0 ]
ref=$(tree_digest "$TMP/ref-work" "$TMP/ref-out")
echo "clean run done after $((SECONDS - started))s"

# wait_for SECONDS DESCRIPTION COMMAND...: a check that COMMAND succeeds within SECONDS.
wait_for() {
  local seconds=$1 what=$2; shift 2
  check "$what (within ${seconds}s)" slurm_wait "$seconds" "$what" "$@"
}
job_field() { # job_field ID FIELD: one field of `scontrol show job`
  timeout 10 scontrol show job -o "$1" 2>/dev/null | grep -o "\b$2=[^ ]*" | head -n 1 | cut -d= -f2-
}
task_state() { job_field "${array}_$1" JobState; }
# claimed_by TASK: the claimed ticket (any stage) whose lease names this array task.
claimed_by() {
  grep -l -E "^job=${array}_$1(\+r[0-9]+)?$" "$TMP"/work/queue/*/claimed/* 2>/dev/null | head -n 1
}
has_claim() { [ -n "$(claimed_by "$1")" ]; }
has_export_claim() { grep -q '/export/claimed/' <<<"$(claimed_by "$1")"; }
task_ended() { # not pending, running or being killed
  case "$(task_state "$1")" in PENDING|RUNNING|CONFIGURING|COMPLETING|REQUEUED|"") return 1 ;; esac
}
task_restarted() { [ "$(job_field "${array}_$1" Restarts)" -ge 1 ] 2>/dev/null; }
array_running() { [ -n "$(timeout 10 squeue -h -j "$array" -t CF,R,CG -o %i 2>/dev/null)" ]; }
log_of() { cat "$TMP/slurm-${array}_$1.out" 2>/dev/null; }

# submit: a 3-task array, all tasks at once: the workers (tasks 1, 2) may start before
# task 0's `scanlod run` has scanned, and wait for its scan (--after-scan in the script).
submit() {
  array=$(slurm_sbatch --array=0-2 --cpus-per-task=1 --mem=100M --time=10 \
    --chdir="$TMP" --output="$TMP/slurm-%A_%a.out" --open-mode=append "$script" "$TMP/c.ini")
  array=${array%%;*}
}

# --- First array: one task cancelled mid-item, one pre-timeout signal (exit 75) ----------
submit
first=$array
wait_for 30 "workers 1 and 2 running" eval '[ "$(task_state 1)" = RUNNING ] && [ "$(task_state 2)" = RUNNING ]'
# The task whose own job id is the array's id is the one the old `${SLURM_JOB_ID}_TASK`
# requeue reached: cancel that one, so that a script undoing a scancel is caught.
cancelled=2 signalled=1
[ "$(job_field "${array}_1" JobId)" = "$array" ] && cancelled=1 signalled=2
echo "array $array: task $cancelled to be cancelled, task $signalled to get USR1"

wait_for 60 "task $cancelled holds an export claim" has_export_claim "$cancelled"
ticket=$(claimed_by "$cancelled" || true)
owner_pid=$(sed -n 's/^pid=//p' "$ticket" 2>/dev/null || true)
timeout 10 scancel "${array}_$cancelled"
echo "cancelled task $cancelled while it ran ${ticket#"$TMP"/work/queue/}"
wait_for 30 "task $signalled holds a claim" has_claim "$signalled"
timeout 10 scancel --signal=USR1 --batch "${array}_$signalled"

# A requeued task starts again after the cluster's cred_expire (tests/cluster/slurm.sh).
wait_for 40 "exit-75 task $signalled requeued" task_restarted "$signalled"
wait_for 40 "cancelled task $cancelled has ended" task_ended "$cancelled"
wait_for 150 "first array has finished" eval '! array_running && task_ended 0 && task_ended 1 && task_ended 2'
echo "first array done after $((SECONDS - started))s"

check "cancelled task is CANCELLED (got $(task_state "$cancelled"))" [ "$(task_state "$cancelled")" = CANCELLED ]
check "cancelled task not requeued (Restarts=$(job_field "${array}_$cancelled" Restarts))" \
  [ "$(job_field "${array}_$cancelled" Restarts)" = 0 ]
check "cancelled task's log says why it was not requeued" \
  contains "not requeued: Slurm sent SIGTERM" "$(log_of "$cancelled")"
# Mid-item: the cancelled worker never finished the stage it held.
if [ -n "$owner_pid" ]; then
  stage=$(basename "$(dirname "$(dirname "$ticket")")")
  item=$(sed -n 's/^item=//p' "$ticket" 2>/dev/null || true)
  events=$(cat "$TMP"/logs/*-"$owner_pid".jsonl 2>/dev/null || true)
  check "the cancel interrupted $stage of $item" \
    [ -z "$(grep '"event":"stage_done"' <<<"$events" | grep "\"stage\":\"$stage\"" | grep "\"item\":\"$item\"" || true)" ]
fi
check "exit-75 task requeued by the script" contains "requeued ${array}_$signalled" "$(log_of "$signalled")"
check "exit-75 task restarted (Restarts=$(job_field "${array}_$signalled" Restarts))" task_restarted "$signalled"
check "exit-75 task completed on its restart (got $(task_state "$signalled"))" \
  [ "$(task_state "$signalled")" = COMPLETED ]
# Whatever of the first array is still queued (a wrongly requeued task) goes now.
timeout 10 scancel "$first" 2>/dev/null || true
slurm_wait 30 "first array gone" eval '! array_running'

# --- The array submitted again: everything ends with 0 ------------------------------------
submit
wait_for 120 "second array has finished" eval '! array_running && task_ended 0 && task_ended 1 && task_ended 2'
for t in 0 1 2; do
  check "second array task $t completed (got $(task_state "$t") $(job_field "${array}_$t" ExitCode))" \
    [ "$(task_state "$t")" = COMPLETED ]
done
echo "second array done after $((SECONDS - started))s"

run_scanlod status "$TMP/c.ini"
run_scanlod run "$TMP/c.ini" -q
check "afterwards: nothing to do (got $rc: $out)" grep -q "^nothing to do" <<<"$out"
run_scanlod verify "$TMP/c.ini"
check "every record verifies (got $rc)" [ "$rc" -eq 0 ]
check "work dir and output identical to a clean run" same_digest "$ref" "$TMP/work" "$TMP/out"
differ=0 files=0
while IFS= read -r -d '' f; do
  files=$((files + 1))
  cmp -s "$TMP/ref-out/$f" "$TMP/out/$f" || { differ=$((differ + 1)); echo "differs: $f" >&2; }
done < <(cd "$TMP/ref-out" && find . -type f ! -name timings.json ! -path '*/.*' -print0)
check "$files published files byte-identical ($differ differ)" [ "$differ" -eq 0 -a "$files" -gt 0 ]
part_logs=$(grep -l "start part" "$TMP"/logs/*.log 2>/dev/null | wc -l)
parts_done=$(cat "$TMP"/logs/*.jsonl | grep '"event":"stage_done"' | grep -c '"part":' || true)
check "the samples parts ran as tickets of the array's tasks ($parts_done parts in $part_logs processes)" \
  [ "$parts_done" -ge 8 -a "$part_logs" -ge 1 ]

echo "test_slurm_array: $((SECONDS - started))s"
completed=1
finish
