#!/usr/bin/env bash
# `scanlod extract` requests (issue 16): counts are plain decimal digits, numbers plain
# decimals, each in its range; a bad value is refused in one line naming the flag, exit 64,
# before any output exists; an octree level beyond the depth names the real depth.
source "$(dirname "$0")/../lib.sh"

mkdir -p "$TMP/in"
cp "$SCANS/bun_zipper_res4.ply" "$TMP/in/"
write_config "$TMP/c.ini" "$TMP/in" "$TMP/work" "$TMP/out"
run_scanlod run "$TMP/c.ini" -q
check "run exits 0 (got $rc: $err)" [ "$rc" -eq 0 ]
model="$TMP/out/bun_zipper_res4.ply/model.slod"
octree="$TMP/work/artifacts/merge/bun_zipper_res4.ply/octree.slot"
depth=$(python3 -c "import json; print(json.load(open('$TMP/work/artifacts/merge/bun_zipper_res4.ply/report.json'))['depth'])")

# refused FLAG VALUE MESSAGE [FILE]: extract FILE (the model) FLAG VALUE exits 64 with
# exactly "scanlod extract: MESSAGE" and writes nothing.
refused() {
  local flag=$1 value=$2 message=$3 file=${4:-$model}
  rm -f "$TMP/x.ply"
  run_scanlod extract "$file" "$flag" "$value" -o "$TMP/x.ply"
  check "$flag '$value': exit 64 (rc $rc)" [ "$rc" -eq 64 ]
  check "$flag '$value': one line naming the flag ($err)" [ "$err" = "scanlod extract: $message" ]
  check "$flag '$value': no output file" [ ! -e "$TMP/x.ply" ]
}

# Counts: strtod/strtoull would take "0x10" as 16, " 16" and "+16" as 16, "-1" as 2^64 - 1.
for value in 0x10 +16 -1 " 16" 16abc 1e3 16.0 ""; do
  refused --triangles "$value" "--triangles: '$value' is not a whole number in decimal digits"
done
refused --triangles 99999999999999999999 "--triangles: '99999999999999999999' is too large"
refused --expansions 0x1 "--expansions: '0x1' is not a whole number in decimal digits"
refused --level 0x1 "--level: '0x1' is not a whole number in decimal digits" "$octree"
refused --repeat 0x3 "--repeat: '0x3' is not a whole number in decimal digits"
# Numbers: decimal only (strtod's hex floats are not what a user means).
refused --lod-percent 0x1p3 "--lod-percent: '0x1p3' is not a finite number"
refused --max-error 0x1p-3 "--max-error: '0x1p-3' is not a finite number"
refused --lod-percent 1e999 "--lod-percent: '1e999' is not a finite number"

# The range of a percent is (0, 100]: 0 used to write a file of 0 triangles, exit 0.
for value in 0 -5 100.5; do
  refused --lod-percent "$value" "--lod-percent must be in (0, 100] (got $value; the coarsest level is --expansions 0)"
done

# Plain decimals still work.
run_scanlod extract "$model" --triangles 16 -o "$TMP/t16.ply"
check "--triangles 16: exit 0 ($err)" [ "$rc" -eq 0 -a -s "$TMP/t16.ply" ]
run_scanlod extract "$model" --lod-percent 100 -o "$TMP/p100.ply"
check "--lod-percent 100: exit 0 ($err)" [ "$rc" -eq 0 -a -s "$TMP/p100.ply" ]
run_scanlod extract "$model" --lod-percent 5e1 -o "$TMP/p50.ply"
check "--lod-percent 5e1: exit 0 ($err)" [ "$rc" -eq 0 -a -s "$TMP/p50.ply" ]

# An output folder that is not there is a bad command line (issue 34 item 6): exit 64 in
# one line naming -o and the folder, before the model is read. It was 75 ("try again"),
# after the whole cut, naming a temp file: ".o.ply.HOST.PID.0.tmp: create failed".
run_scanlod extract "$model" --triangles 16 -o "$TMP/no/such/dir/o.ply"
check "-o into a missing folder: exit 64 (rc $rc)" [ "$rc" -eq 64 ]
check "-o into a missing folder: one line naming the flag and the folder ($err)" \
  [ "$err" = "scanlod extract: -o $TMP/no/such/dir/o.ply: its folder does not exist ($TMP/no/such/dir)" ]
echo x >"$TMP/plain"
run_scanlod extract "$TMP/missing.slod" --triangles 16 -o "$TMP/plain/o.ply"
check "-o under a file: exit 64 before the (missing) model is read (rc $rc)" [ "$rc" -eq 64 ]
check "-o under a file: says why ($err)" contains "its folder is not a folder" "$err"

# A budget is a ceiling: above the finest level it gives the finest (as [export] budgets
# do), so the README's own example works on the demo's small bunny (it exited 64,
# "exceeds the finest level").
example=$(grep -m1 -o 'scanlod extract out/bunny.ply/model.slod --triangles [0-9]* -o bunny.glb' \
  "$SCANLOD_SOURCE_DIR/README.md")
check "the README has its extract example ($example)" [ -n "$example" ]
read -r -a words <<<"${example/out\/bunny.ply\/model.slod/$model}"
run_scanlod "${words[@]:1:4}" -o "$TMP/readme.glb"
check "the README's example: exit 0 on a model below its budget (rc $rc: $err)" [ "$rc" -eq 0 -a -s "$TMP/readme.glb" ]
check "the README's example: says it took the finest level ($err)" contains "above the finest level" "$err"

# A level beyond the octree names the octree's real depth (it said "depth is 0").
check "the octree is deeper than 2 (depth $depth)" [ "$depth" -gt 2 ]
refused --level $((depth + 1)) "--level $((depth + 1)) exceeds the octree's depth $depth (levels 0 to $depth)" "$octree"
run_scanlod extract "$octree" --level "$depth" -o "$TMP/root.ply"
check "--level $depth (the root): exit 0 ($err)" [ "$rc" -eq 0 -a -s "$TMP/root.ply" ]
finish
