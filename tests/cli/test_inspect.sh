#!/usr/bin/env bash
# `scanlod inspect`: what a PLY holds on stdout, exit 0; a malformed file gives exactly one
# line "scanlod: FILE: cause" on stderr and exit 65; usage errors exit 64.
source "$(dirname "$0")/../lib.sh"
data="$SCANLOD_SOURCE_DIR/tests/data"

inspect() { # inspect ARGS...: sets rc, out, err
  set +e
  out=$("$SCANLOD" inspect "$@" 2>"$TMP/err")
  rc=$?
  set -e
  err=$(cat "$TMP/err")
}

inspect "$data/scans/cow.ply"
check "cow: exit 0" [ "$rc" -eq 0 ]
check "cow: format" grep -qx "format: binary_little_endian 1.0 (header 258 bytes)" <<<"$out"
check "cow: vertices" grep -qx "vertices: 2904" <<<"$out"
check "cow: faces" grep -q "^faces: 5804 declared, 5804 triangles" <<<"$out"
check "cow: bbox" grep -q "^bbox: min -0.5 " <<<"$out"
check "cow: nothing on stderr" [ -z "$err" ]

inspect "$data/scans/bun_zipper_res4.ply"
check "bunny: elements" grep -qx "elements: vertex 453 (x y z confidence intensity); face 948 (list uchar int vertex_indices)" <<<"$out"
check "bunny: non-finite" grep -qx "non-finite vertices: 0" <<<"$out"

inspect "$data/malformed/all_nan.ply"
check "all-NaN: valid, counted" [ "$rc" -eq 0 ]
check "all-NaN: count" grep -qx "non-finite vertices: 3" <<<"$out"
check "all-NaN: no bbox" grep -qx "bbox: none" <<<"$out"

bad="$data/malformed/vertex_2e32_binary.ply"
inspect "$bad"
check "malformed: exit 65" [ "$rc" -eq 65 ]
check "malformed: one line" [ "$(wc -l <"$TMP/err")" -eq 1 ]
check "malformed: names file and cause" grep -qx "scanlod: $bad: header line 3: element vertex declares 4294967295 vertices (at least 12 bytes each) but the file has 36 bytes after the header" <<<"$err"
check "malformed: nothing on stdout" [ -z "$out" ]

inspect "$TMP/missing.ply"
check "missing file: exit 65" [ "$rc" -eq 65 ]
check "missing file: says so in one line ($err)" [ "$err" = "scanlod: $TMP/missing.ply: No such file or directory" ]
# FIFOs, directories, devices: tests/cli/test_input_files.sh (all commands alike).

# A LOD model: what it holds, checked as extract checks it; the finest cut's triangles are
# the export stage's triangles_finest.
mkdir -p "$TMP/in"
cp "$SCANS/bun_zipper_res4.ply" "$TMP/in/"
write_config "$TMP/c.ini" "$TMP/in" "$TMP/work" "$TMP/out"
"$SCANLOD" run "$TMP/c.ini" -q -s octree.vertices=mc
model="$TMP/out/bun_zipper_res4.ply/model.slod"
inspect "$model"
check "model: exit 0 ($err)" [ "$rc" -eq 0 ]
finest=$(python3 -c "import json; print(json.load(open('$TMP/out/bun_zipper_res4.ply/report.json'))['stages']['export']['triangles_finest'])")
check "model: the finest cut's triangles ($finest) as the report says" grep -qx "triangles: 0 at the root, $finest at the finest cut" <<<"$out"
for key in grid nodes crossings "lod array" error "transition records"; do
  check "model: says its $key" grep -q "^$key: " <<<"$out"
done
check "model: says its vertices are paper 1's ([octree] vertices = mc)" grep -q "^vertices: mc (" <<<"$out"
# The default: quadric vertices, how many, and the finest cut as the report says.
"$SCANLOD" run "$TMP/c.ini" -q -s run.output="$TMP/out-qef"
inspect "$TMP/out-qef/bun_zipper_res4.ply/model.slod"
check "qef model: exit 0 ($err)" [ "$rc" -eq 0 ]
check "default (qef) model: says how many quadric vertices it has ($out)" grep -Eq "^vertices: qef, [1-9][0-9]* quadric vertices" <<<"$out"
finest=$(python3 -c "import json; print(json.load(open('$TMP/out-qef/bun_zipper_res4.ply/report.json'))['stages']['export']['triangles_finest'])")
check "qef model: the finest cut's triangles ($finest) as the report says" grep -qx "triangles: [0-9]* at the root, $finest at the finest cut" <<<"$out"
head -c 4000 "$model" >"$TMP/cut.slod"
inspect "$TMP/cut.slod"
check "truncated model: exit 65, one line naming it ($err)" [ "$rc" -eq 65 ] && grep -q "^scanlod: $TMP/cut.slod: header declares" <<<"$err"

inspect
check "no argument: exit 64" [ "$rc" -eq 64 ]
check "no argument: usage on stderr" grep -q "^usage: scanlod inspect" <<<"$err"
inspect a.ply b.ply
check "two arguments: exit 64" [ "$rc" -eq 64 ]
inspect --help
check "--help: exit 0" [ "$rc" -eq 0 ]
check "--help: usage on stdout" grep -q "^usage: scanlod inspect" <<<"$out"

finish
