#!/usr/bin/env bash
# The benchmark's peers and `scanlod compare` on tiny meshes, so the harness does not rot:
# gen_surface makes a closed torus; meshopt_lod reaches its targets within 10%;
# meshopt_js.mjs (meshoptimizer 1.3 from npm, the fidelity anchor) reads ascii and binary
# PLY of either byte order with extra properties, elements and polygons, and its
# simplifyWithUpdate and simplify levels reach their targets as binary PLY compare reads;
# vdb_remesh (signed on closed inputs, unsigned on an open scan) makes a mesh whose
# Hausdorff distance to its input is under 5% of the diagonal; compare is exact on
# identical meshes, deterministic across thread counts, and fails cleanly on bad input.
source "$SCANLOD_SOURCE_DIR/tests/lib.sh"

BENCH="${SCANLOD_BUILD_DIR:?}/scripts/bench"
if [ ! -x "$BENCH/meshopt_lod" ] || [ ! -x "$BENCH/vdb_remesh" ] || [ ! -x "$BENCH/gen_surface" ]; then
  echo "FAIL: peer programs missing in $BENCH (tests/CMakeLists.txt registers this test only with SCANLOD_BENCH=ON)" >&2
  exit 1
fi

# json_values KEY < JSON: every numeric/boolean value of KEY, one per line, in order.
json_values() { grep -o "\"$1\":[^,}]*" | cut -d: -f2; }
json_first() { json_values "$1" | head -n 1; }
# below A B: A < B as reals
below() { awk -v a="$1" -v b="$2" 'BEGIN { exit !(a + 0 < b + 0) }'; }

compare_json() { # compare_json A B: sets $cmp (JSON) or fails the check
  cmp=$("$SCANLOD" compare "$1" "$2" --samples 100000 --json)
}

# --- gen_surface and compare on identical meshes ------------------------------------
torus="$TMP/torus.ply"
gen=$("$BENCH/gen_surface" --triangles 2000 -o "$torus")
n=$(json_first triangles <<<"$gen")
check "gen_surface makes about 2000 triangles ($n)" test "$n" -ge 1900 -a "$n" -le 2100
compare_json "$torus" "$torus"
check "compare: identical meshes are 0 apart" below "$(json_first hausdorff <<<"$cmp")" 1e-9
check "compare: the torus is watertight" test "$(json_first watertight <<<"$cmp")" = true
check "compare: the torus has no boundary edges" \
  test "$(json_first boundary_edges <<<"$cmp")" = 0

# --- determinism across thread counts ------------------------------------------------
strip_times() { sed -E 's/"(read|compare)_seconds":[^,}]*//g'; }
one=$(OMP_NUM_THREADS=1 "$SCANLOD" compare "$SCANS/cow.ply" "$torus" --samples 50000 --json | strip_times)
two=$(OMP_NUM_THREADS=2 "$SCANLOD" compare "$SCANS/cow.ply" "$torus" --samples 50000 --json | strip_times)
check "compare: same JSON with 1 and 2 threads" test "$one" = "$two"

# --- meshoptimizer ---------------------------------------------------------------------
mo=$("$BENCH/meshopt_lod" "$SCANS/cow.ply" --targets 2000,500 -o "$TMP/cow_mo")
tris=($(json_values triangles <<<"$mo"))
check "meshopt: 2000 within 10% (${tris[0]:-none})" test "${tris[0]:-0}" -ge 1800 -a "${tris[0]:-0}" -le 2000
check "meshopt: 500 within 10% (${tris[1]:-none})" test "${tris[1]:-0}" -ge 450 -a "${tris[1]:-0}" -le 500
compare_json "$SCANS/cow.ply" "$TMP/cow_mo_500.ply"
h=$(json_first hausdorff <<<"$cmp")
check "meshopt: cow at 500 triangles within 5% of the diagonal ($h)" below "$h" 0.05
mo=$("$BENCH/meshopt_lod" "$SCANS/bun_zipper_res4.ply" --fractions 0.5)
t=$(json_values triangles <<<"$mo")
check "meshopt: half of 948 triangles within 10% ($t)" test "$t" -ge 427 -a "$t" -le 474

# --- meshoptimizer 1.3 (npm), the fidelity anchor -------------------------------------
MJS="$SCANLOD_SOURCE_DIR/scripts/bench/peers/meshopt_js.mjs"
if ! command -v node >/dev/null ||
   [ ! -f "$SCANLOD_SOURCE_DIR/scripts/bench/peers/npm/node_modules/meshoptimizer/package.json" ]; then
  echo "FAIL: node or the npm meshoptimizer missing (scripts/install-deps.sh: npm ci in scripts/bench/peers/npm)" >&2
  exit 1
fi
mo=$(node "$MJS" "$SCANS/cow.ply" --targets 2000,500 -o "$TMP/cow_js")
check "meshopt_js: version 1.3.0" grep -q '"version":"1.3.0"' <<<"$mo"
check "meshopt_js: Prune, no error limit" grep -q '"target_error":10000000000,"flags":\["Prune"\]' <<<"$mo"
fns=($(grep -o '"function":"[a-zA-Z]*"' <<<"$mo" | cut -d'"' -f4))
check "meshopt_js: update then simplify per target (${fns[*]})" \
  test "${fns[*]}" = "simplifyWithUpdate simplify simplifyWithUpdate simplify"
tris=($(json_values triangles <<<"$mo"))
for k in 0 1; do
  check "meshopt_js: 2000 within 10% (${tris[$k]:-none})" test "${tris[$k]:-0}" -ge 1800 -a "${tris[$k]:-0}" -le 2000
done
for k in 2 3; do
  check "meshopt_js: 500 within 10% (${tris[$k]:-none})" test "${tris[$k]:-0}" -ge 450 -a "${tris[$k]:-0}" -le 500
done
for fn in update simplify; do
  compare_json "$SCANS/cow.ply" "$TMP/cow_js_${fn}_500.ply"
  check "meshopt_js: $fn level is the PLY it says (${tris[2]} triangles)" \
    test "$(json_first b_triangles <<<"$cmp")" = "${tris[2]}"
  h=$(json_first hausdorff <<<"$cmp")
  check "meshopt_js: cow $fn at 500 within 5% of the diagonal ($h)" below "$h" 0.05
  eval "rms_$fn=$(json_first rms <<<"$cmp")"
done
check "meshopt_js: simplifyWithUpdate no worse than simplify in RMS ($rms_update, $rms_simplify)" \
  below "$rms_update" "$(awk -v r="$rms_simplify" 'BEGIN { print 1.05 * r }')"
check "meshopt_js: update moved vertices off the input's" \
  test "$(cmp -s "$TMP/cow_js_update_500.ply" "$TMP/cow_js_simplify_500.ply"; echo $?)" = 1
mo=$(node "$MJS" "$SCANS/bun_zipper_res4.ply" --fractions 0.5 --functions update)
t=$(json_values triangles <<<"$mo")
check "meshopt_js: ascii with extra vertex properties, half of 948 ($t)" test "$t" -ge 427 -a "$t" -le 474

# A cube of six quads, four vertices of its own each (24 vertices, 8 positions), with an
# extra element: ascii, then binary big-endian with a double coordinate, a face property
# after the list and a list in the extra element.
python3 - "$TMP" <<'PY'
import struct, sys
d = sys.argv[1]
corners = [(x, y, z) for x in (0, 1) for y in (0, 1) for z in (0, 1)]
quads = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
verts = [corners[c] for q in quads for c in q]
faces = [[4 * f + k for k in range(4)] for f in range(6)]
with open(d + "/cube_ascii.ply", "w") as f:
    f.write("ply\nformat ascii 1.0\ncomment six quads\nelement vertex 24\nproperty float x\n"
            "property float y\nproperty float z\nproperty uchar red\nelement face 6\n"
            "property list uchar int vertex_indices\nelement edge 1\nproperty int vertex1\n"
            "property int vertex2\nend_header\n")
    f.writelines("%g %g %g 200\n" % v for v in verts)
    f.writelines("4 %s\n" % " ".join(map(str, q)) for q in faces)
    f.write("0 1\n")
with open(d + "/cube_be.ply", "wb") as f:
    f.write(b"ply\nformat binary_big_endian 1.0\nelement vertex 24\nproperty float x\n"
            b"property double y\nproperty short s\nproperty float z\nelement face 6\n"
            b"property list uint8 uint vertex_indices\nproperty uchar flags\n"
            b"element extra 2\nproperty list uchar float values\nend_header\n")
    for x, y, z in verts:
        f.write(struct.pack(">fdhf", x, y, -7, z))
    for q in faces:
        f.write(struct.pack(">B4IB", 4, *q, 9))
    f.write(struct.pack(">Bf", 1, 0.5) + struct.pack(">B2f", 2, 1, 2))
PY
for v in ascii be; do
  mo=$(node "$MJS" "$TMP/cube_$v.ply" --targets 12 --functions simplify -o "$TMP/cube_${v}_js")
  check "meshopt_js: cube ($v): 6 quads cut into 12 triangles" \
    grep -q '"input_triangles":12,"input_vertices":24,"welded_vertices":8,"polygons_triangulated":6' <<<"$mo"
  compare_json "$TMP/cube_ascii.ply" "$TMP/cube_${v}_js_simplify_12.ply"
  check "meshopt_js: cube ($v) written back watertight, in place" \
    test "$(json_first watertight <<<"$cmp")" = true -a "$(json_first welded_vertices <<<"$cmp")" = 8
  check "meshopt_js: cube ($v) at distance 0" below "$(json_first hausdorff <<<"$cmp")" 1e-9
done
rc=0; node "$MJS" "$TMP/missing.ply" --targets 10 2>/dev/null || rc=$?
check "meshopt_js: missing input exits 65 ($rc)" test "$rc" = 65
head -c 500 "$TMP/cube_be.ply" >"$TMP/cube_cut.ply"
rc=0; err=$(node "$MJS" "$TMP/cube_cut.ply" --targets 10 2>&1) || rc=$?
check "meshopt_js: truncated input exits 65 ($rc)" test "$rc" = 65
check "meshopt_js: truncated input named" grep -q "^meshopt_js: $TMP/cube_cut.ply: file ends early" <<<"$err"
rc=0; node "$MJS" "$TMP/cube_be.ply" --targets 1.5 2>/dev/null || rc=$?
check "meshopt_js: a fractional count is a usage error ($rc)" test "$rc" = 64

# --- OpenVDB ---------------------------------------------------------------------------
vdb=$("$BENCH/vdb_remesh" "$SCANS/cow.ply" -o "$TMP/cow_vdb.ply" --voxel-fraction 0.01 --threads 2)
t=$(json_first triangles <<<"$vdb")
check "vdb signed: cow remesh has triangles ($t)" test "${t:-0}" -gt 0
compare_json "$SCANS/cow.ply" "$TMP/cow_vdb.ply"
h=$(json_first hausdorff <<<"$cmp")
check "vdb signed: cow remesh within 5% of the diagonal ($h)" below "$h" 0.05
check "vdb signed: cow remesh is watertight" test "$(json_first watertight <<<"$cmp")" = true

vdb=$("$BENCH/vdb_remesh" "$SCANS/bun_zipper_res4.ply" -o "$TMP/bun_vdb.ply" \
  --voxel-fraction 0.01 --unsigned --adaptivity 0.2 --threads 1)
t=$(json_first triangles <<<"$vdb")
check "vdb unsigned: open scan remesh has triangles ($t)" test "${t:-0}" -gt 0
compare_json "$SCANS/bun_zipper_res4.ply" "$TMP/bun_vdb.ply"
h=$(json_first hausdorff <<<"$cmp")
check "vdb unsigned: open scan remesh within 5% of the diagonal ($h)" below "$h" 0.05

# --- compare: errors -------------------------------------------------------------------
run_scanlod compare "$TMP/missing.ply" "$torus"
check "compare: missing file exits 65 ($rc)" test "$rc" = 65
check "compare: one line naming the missing file" test "$(wc -l <<<"$err")" = 1
check "compare: missing file named" grep -q "^scanlod: $TMP/missing.ply: " <<<"$err"
head -c 300 "$torus" >"$TMP/cut.ply"
run_scanlod compare "$torus" "$TMP/cut.ply"
check "compare: truncated file exits 65 ($rc)" test "$rc" = 65
check "compare: truncated file named" grep -q "^scanlod: $TMP/cut.ply: " <<<"$err"
run_scanlod compare "$torus"
check "compare: one file is a usage error ($rc)" test "$rc" = 64
run_scanlod compare "$torus" "$torus" --samples x
check "compare: bad --samples is a usage error ($rc)" test "$rc" = 64

finish
