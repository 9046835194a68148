#!/usr/bin/env bash
# The export cuts the next level on a thread of its own while it writes the current one
# (stages/export/export_cuts.c). The cuts are made in the serial order and their choices
# (which levels share a mesh, refills after shards, morph targets) depend only on the
# levels cut before, so every published file is byte-identical on 1 thread (no overlap)
# and 2 (overlap), with and without morph targets; and a write that fails while the next
# cut is under way gives the one clear error and exit 75, and the rerun publishes the
# same files. SCANLOD_LIGHT=1 (the sanitizer pass): cow alone, one full disk.
source "$(dirname "$0")/../lib.sh"

mkdir -p "$TMP/in"
cp "$SCANS/cow.ply" "$TMP/in/"
points="2 4 6"
if light; then
  points=4
  echo "LIGHT: cow alone, a full disk at write 4; rocker_arm too and writes 2, 4, 6 in the Release pass"
else
  cp "$SCANS/rocker_arm.ply" "$TMP/in/"
fi
digest_out() { (cd "$1" && find . -type f ! -name timings.json -print0 | sort -z | xargs -0 sha256sum); }

for morph in false true; do
  for t in 1 2; do
    write_config "$TMP/$morph-$t.ini" "$TMP/in" "$TMP/work-$morph-$t" "$TMP/out-$morph-$t" \
      "[export]" "fidelity_samples = 20000" "morph = $morph"
    run_scanlod run "$TMP/$morph-$t.ini" -q --threads "$t"
    check "morph = $morph, $t thread(s): exit 0 (got $rc: $err)" [ "$rc" -eq 0 ]
  done
  a=$(digest_out "$TMP/out-$morph-1")
  b=$(digest_out "$TMP/out-$morph-2")
  diff <(echo "$a") <(echo "$b") | head -10 >&2
  check "morph = $morph: every published file byte-identical on 1 and 2 threads" [ "$a" = "$b" ]
  levels=$(ls "$TMP/out-$morph-2/cow.ply/"*.glb | wc -l)
  check "morph = $morph: cow has several published levels ($levels GLBs)" [ "$levels" -ge 4 ]
done

# A full disk at the first level's GLB and at later level files: the level before is being
# written, the next one cut (the export is the only stage left, so it is child 1: cow).
ref=$(digest_out "$TMP/out-false-2")
for n in $points; do
  rm -rf "$TMP/work-false-2/artifacts/export" "$TMP/out-false-2"
  SCANLOD_FAULT=write:$n:ENOSPC SCANLOD_FAULT_SCOPE=child:1 \
    run_scanlod run "$TMP/false-2.ini" -q --threads 2
  check "write $n of the export fails: exit 75 (got $rc)" [ "$rc" -eq 75 ]
  check "write $n: one error naming the file and the cause (got: $err)" \
    grep -qE "\[export\] cow.ply: .*/lod[0-9]+\.(ply|glb|png): write failed: No space left" <<<"$err"
  run_scanlod run "$TMP/false-2.ini" -q --threads 2
  check "write $n: the rerun exits 0 (got $rc: $err)" [ "$rc" -eq 0 ]
  now=$(digest_out "$TMP/out-false-2")
  check "write $n: the rerun publishes the same files" [ "$ref" = "$now" ]
done
finish
