#!/usr/bin/env bash
# Publication and the exit code (issue 16 items 2 and 8): a full output disk is never
# success, on this run or the next; "up to date" means the published files exist and
# match their records; a read-only output stops the run before any stage; published files
# are files of their own (no hard links into the work folder); `verify` flags a file that
# no record lists. Needs root for the small tmpfs mounts; without it the test is skipped.
source "$(dirname "$0")/../lib.sh"

if [ "$(id -u)" -ne 0 ] || ! mount -t tmpfs -o size=16k scanlod-test "$TMP" 2>/dev/null; then
  echo "SKIP: cannot mount a tmpfs here (needs root)"
  exit 77
fi
umount "$TMP"
mkdir -p "$TMP/in" "$TMP/full" "$TMP/ro"
cp "$SCANS/bun_zipper_res4.ply" "$TMP/in/bunny.ply"

# 2. The output folder on a 16 KiB tmpfs: the item is built, its publication fails.
mount -t tmpfs -o size=16k scanlod-test "$TMP/full"
cleanup_hooks+=("umount '$TMP/full'")
write_config "$TMP/full.ini" "$TMP/in" "$TMP/work" "$TMP/full/out"
run_scanlod run "$TMP/full.ini" -q
check "output disk full: exit 75, not 0 (got $rc)" [ "$rc" -eq 75 ]
check "output disk full: the error says so (got: $err)" grep -q "No space left on device" <<<"$err"
run_scanlod status "$TMP/full.ini"
check "status names the unpublished item (got: $out)" grep -q "bunny.ply: done but not published" <<<"$out"
run_scanlod verify "$TMP/full.ini"
check "verify: an unpublished item is not all right (got $rc: $out)" [ "$rc" -eq 65 ]
run_scanlod run "$TMP/full.ini" -q
check "still full: the rerun exits 75 (got $rc: $out)" [ "$rc" -eq 75 ]
check "still full: the rerun does not say 'nothing to do' (got: $out)" \
  bash -c '! grep -q "^nothing to do" <<<"$1"' _ "$out"
mount -o remount,size=64m "$TMP/full"
run_scanlod run "$TMP/full.ini" -q
check "space again: published, exit 0 (got $rc: $err)" [ "$rc" -eq 0 ]
check "space again: report published" [ -f "$TMP/full/out/bunny.ply/report.json" ]
run_scanlod verify "$TMP/full.ini"
check "space again: verify exits 0 (got $rc: $out)" [ "$rc" -eq 0 ]

# 8. Published files are copies (or reflinks), never hard links into the work folder:
# editing one cannot change the other.
linked=$(find "$TMP/full/out" -type f -links +1 | wc -l)
check "no published file shares its inode ($linked do)" [ "$linked" -eq 0 ]

# 8. A file added to a published folder is flagged by verify.
echo "notes" >"$TMP/full/out/bunny.ply/notes.txt"
run_scanlod verify "$TMP/full.ini"
check "verify flags a file no record lists (got $rc: $out)" \
  [ "$rc" -eq 65 ] && grep -q "notes.txt: not part of the publication" <<<"$out"
rm "$TMP/full/out/bunny.ply/notes.txt"

# 8. A read-only output folder: exit 74 before any stage ran.
mount -t tmpfs -o ro,size=1m scanlod-test "$TMP/ro"
cleanup_hooks+=("umount '$TMP/ro'")
write_config "$TMP/ro.ini" "$TMP/in" "$TMP/ro-work" "$TMP/ro"
run_scanlod run "$TMP/ro.ini"
check "read-only output: exit 74 (got $rc)" [ "$rc" -eq 74 ]
check "read-only output: the error names the folder (got: $err)" grep -q "\[run\] output: creating a file" <<<"$err"
check "read-only output: no stage started (got: $err)" bash -c '! grep -q "start (attempt" <<<"$1"' _ "$err"
finish
