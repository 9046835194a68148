#!/usr/bin/env bash
# Disk full (reliability T5): the work dir on a small tmpfs fills up mid-run. Expected:
# one clear "no space" error naming the file, exit 75, nothing quarantined, nothing
# half-written visible; after the filesystem grows, the resumed run ends byte-identical
# to a clean run. Needs root for mount; without it the same checks run with injected
# ENOSPC (SCANLOD_FAULT), and the test says so. SCANLOD_LIGHT=1 (the sanitizer pass): the
# three smallest scans.
source "$(dirname "$0")/../lib.sh"

scans=("$SCANS"/*.ply)
if light; then
  scans=("$SCANS/bun_zipper_res4.ply" "$SCANS/bun_zipper_res3.ply" "$SCANS/cow.ply")
  echo "LIGHT: 3 small scans; all 5 in the Release pass"
fi
mkdir -p "$TMP/in"
for f in "${scans[@]}"; do cp "$f" "$TMP/in/"; done
write_config "$TMP/ref.ini" "$TMP/in" "$TMP/ref-work" "$TMP/ref-out"
run_scanlod run "$TMP/ref.ini" -q
check "clean run exits 0" [ "$rc" -eq 0 ]
ref=$(tree_digest "$TMP/ref-work" "$TMP/ref-out")
need_kb=$(du -sk "$TMP/ref-work" | cut -f1)

mkdir -p "$TMP/small"
if mount -t tmpfs -o size=$((need_kb / 2))k scanlod-test "$TMP/small" 2>/dev/null; then
  cleanup_hooks+=("umount '$TMP/small'")
  mode=tmpfs
  write_config "$TMP/full.ini" "$TMP/in" "$TMP/small/work" "$TMP/out"
  run_scanlod run "$TMP/full.ini" -q
else
  mode=injected
  echo "note: cannot mount a tmpfs here (not root?); injecting ENOSPC instead" >&2
  write_config "$TMP/full.ini" "$TMP/in" "$TMP/work" "$TMP/out"
  SCANLOD_FAULT=write:2:ENOSPC SCANLOD_FAULT_SCOPE=child run_scanlod run "$TMP/full.ini" -q
fi
echo "disk full via $mode: exit $rc" >&2
check "full disk exits 75 (got $rc)" [ "$rc" -eq 75 ]
check "error says no space and names a file (got: $err)" grep -qE "no space left|No space left" <<<"$err"
run_scanlod status "$TMP/full.ini"
check "nothing quarantined in any stage" [ "$(awk 'NR > 1 && NF == 6 { q += $6 } END { print q + 0 }' <<<"$out")" -eq 0 ]
run_scanlod verify "$TMP/full.ini"
check "every record written before the disk filled verifies" [ "$rc" -eq 0 ]

if [ "$mode" = tmpfs ]; then
  mount -o remount,size=$((need_kb * 4))k "$TMP/small"
  run_scanlod run "$TMP/full.ini" -q
  check "resume after freeing space exits 0 (got $rc: $err)" [ "$rc" -eq 0 ]
  check "resumed run byte-identical to the clean run" [ "$ref" = "$(tree_digest "$TMP/small/work" "$TMP/out")" ]
else
  run_scanlod run "$TMP/full.ini" -q
  check "resume exits 0 (got $rc: $err)" [ "$rc" -eq 0 ]
  check "resumed run byte-identical to the clean run" [ "$ref" = "$(tree_digest "$TMP/work" "$TMP/out")" ]
fi

# Injected EIO from fsync: the item fails transiently (exit 75), never quarantined, and
# is not marked done (reliability T6).
write_config "$TMP/eio.ini" "$TMP/in" "$TMP/eio-work" "$TMP/eio-out"
SCANLOD_FAULT=fsync:1:EIO SCANLOD_FAULT_SCOPE=child run_scanlod run "$TMP/eio.ini" -q
check "fsync EIO: exit 75 (got $rc)" [ "$rc" -eq 75 ]
run_scanlod run "$TMP/eio.ini" -q
check "fsync EIO: resume exits 0" [ "$rc" -eq 0 ]
check "fsync EIO: resumed run identical" [ "$ref" = "$(tree_digest "$TMP/eio-work" "$TMP/eio-out")" ]

# Unwritable output folder: storage needs a human (exit 74), the input is not blamed.
if [ "$(id -u)" -ne 0 ]; then
  mkdir -p "$TMP/ro-out" && chmod 555 "$TMP/ro-out"
  write_config "$TMP/ro.ini" "$TMP/in" "$TMP/ro-work" "$TMP/ro-out/x"
  run_scanlod run "$TMP/ro.ini" -q
  check "unwritable output: exit 74 (got $rc)" [ "$rc" -eq 74 ]
fi
finish
