#!/usr/bin/env bash
# Out of memory in any form is a transient failure, never a crash of ours (issue 34 item
# 1): an item over [run] memory_limit_mb fails, is retried by the next run and never
# quarantined, whether the allocation failed in our code, as a std::bad_alloc nobody could
# catch (OpenVDB's destructors, OpenImageIO's constructors inside dlopen), or as a mapping
# the dynamic loader was refused; a SIGKILL scanlod did not send is the kernel's OOM
# killer. And a quarantine that was such a failure heals: the next run retries it.
# Before: cow's export at 90 MB was "quarantined as a scanlod bug after 2 crashes: killed
# by signal 6" (exit 70), at 75 MB it failed on "libcrypto.so.3: cannot map zero-fill
# pages" (a crash too), and the rerun without a limit said "nothing to do ... (1
# quarantined)", exit 65.
source "$(dirname "$0")/../lib.sh"

sanitized() { grep -q '^SCANLOD_SANITIZE:BOOL=ON' "${SCANLOD_BUILD_DIR:-/nonexistent}/CMakeCache.txt" 2>/dev/null; }
ticket_field() { sed -n "s/^$2=//p" "$1"; }

mkdir -p "$TMP/in" "$TMP/small"
cp "$SCANS/cow.ply" "$SCANS/rocker_arm.ply" "$TMP/in/"
cp "$SCANS/bun_zipper_res4.ply" "$TMP/small/"
# Thumbnails on: the export then loads OpenImageIO, whose loading needs about 70 MB.
export_lines=("[levels]" "percents = 50" "budgets =" "[export]" "formats = ply" "thumbnail_size = 64"
              "fidelity = false")
write_config "$TMP/c.ini" "$TMP/in" "$TMP/work" "$TMP/out" "threads = 1" "memory_check = false" \
  "${export_lines[@]}"

if sanitized; then
  echo "SKIP: memory limits (ASan builds set no RLIMIT_DATA: it reserves terabytes of address space)"
else
  # cow's export at 75 and 90 MB (the loader, OpenImageIO's constructors), rocker_arm's
  # samples stage at 40 MB (a std::bad_alloc thrown by an OpenVDB destructor).
  for limit in 75 90 40; do
    rm -rf "$TMP/work" "$TMP/out"
    run_scanlod run "$TMP/c.ini" -q -s "run.memory_limit_mb=$limit"
    check "limit $limit MB: exit 75, not 70 (got $rc: $err)" [ "$rc" -eq 75 ]
    check "limit $limit MB: nothing called a crash or a bug ($err)" \
      bash -c '! grep -qE "crash|bug" <<<"$1"' _ "$err"
    check "limit $limit MB: it says out of memory ($err)" contains "out of memory" "$err"
    run_scanlod status "$TMP/c.ini"
    check "limit $limit MB: status has it failed for memory, nothing quarantined ($out)" \
      bash -c 'grep -q ": failed (memory): " <<<"$1" && ! grep -q ": quarantine (" <<<"$1"' _ "$out"
  done
  # Without the limit, the next run finishes it: exit 0, every item published.
  run_scanlod run "$TMP/c.ini" -q
  check "no limit: the rerun finishes (exit 0, got $rc: $out $err)" [ "$rc" -eq 0 ]
  check "no limit: both published" [ -f "$TMP/out/cow.ply/report.json" -a -f "$TMP/out/rocker_arm.ply/report.json" ]
fi

# The kernel's OOM killer, as the parent sees it: its stage process dies of a SIGKILL
# nobody in scanlod sent. The range stage's process stops itself at its first write
# (SCANLOD_FAULT ...:stop) and the test kills it.
write_config "$TMP/k.ini" "$TMP/small" "$TMP/kwork" "$TMP/kout"
run_killing_child child "$TMP/k.ini"
check "the range stage's process stopped itself" [ -n "$child" ]
check "SIGKILLed stage: exit 75 (got $rc)" [ "$rc" -eq 75 ]
check "SIGKILLed stage: taken for the OOM killer ($err)" \
  contains "killed by SIGKILL, not sent by scanlod: taken for the kernel's out-of-memory killer" "$err"
check "SIGKILLed stage: failed for memory" \
  [ "$(ticket_field "$TMP/kwork/queue/range/failed/bun_zipper_res4.ply" class)" = memory ]

# Healing. A built item's export is made quarantined as an older build left it, and its
# export folder removed (so the stage is not done): each kind of ticket is one case.
write_config "$TMP/h.ini" "$TMP/small" "$TMP/hwork" "$TMP/hout"
run_scanlod run "$TMP/h.ini" -q
check "heal: the item is built (exit $rc)" [ "$rc" -eq 0 ]
done_ticket="$TMP/hwork/queue/export/done/bun_zipper_res4.ply"
cp "$done_ticket" "$TMP/done.ticket"
# quarantine CLASS REASON LIMIT_LINE: the export quarantined with that class and reason.
quarantine() {
  rm -rf "$TMP/hwork/artifacts/export/bun_zipper_res4.ply" "$TMP/hwork/queue/export/done/"*
  sed -e "s/^class=.*/class=$1/" -e "s|^reason=.*|reason=$2|" -e '/^limit_mb=/d' \
    -e "s/^end\$/${3}end/" "$TMP/done.ticket" >"$TMP/hwork/queue/export/quarantine/bun_zipper_res4.ply"
}
quarantine bug "bun_zipper_res4.ply: killed by signal 6 (Aborted)" ""
run_scanlod run "$TMP/h.ini" -q
check "a bug quarantine of a build that recorded no memory limit is tried once more (exit $rc: $err)" \
  [ "$rc" -eq 0 -a ! -e "$TMP/hwork/queue/export/quarantine/bun_zipper_res4.ply" ]
check "and the log says why" grep -q "retried: quarantined as a scanlod bug by a build" "$TMP"/logs/*.log
quarantine bug "bun_zipper_res4.ply: killed by signal 11 (Segmentation fault)" 'limit_mb=90\n'
run_scanlod run "$TMP/h.ini" -q
check "a crash under a 90 MB limit is retried once the limit is gone (exit $rc: $err)" [ "$rc" -eq 0 ]
quarantine bug "x.png: cannot load scanlod-oiio.so: libcrypto.so.3: cannot map zero-fill pages" 'limit_mb=0\n'
run_scanlod run "$TMP/h.ini" -q
check "a bug quarantine that reads as out of memory is retried (exit $rc: $err)" [ "$rc" -eq 0 ]
quarantine bug "bun_zipper_res4.ply: killed by signal 11 (Segmentation fault)" 'limit_mb=0\n'
run_scanlod run "$TMP/h.ini" -q
check "a crash without any limit stays quarantined (exit 65, got $rc)" [ "$rc" -eq 65 ]
finish
