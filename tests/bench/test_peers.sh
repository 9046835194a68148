#!/usr/bin/env bash
# The benchmark's peers and `scanlod compare` on tiny meshes, so the harness does not rot:
# gen_surface makes a closed torus; meshopt_lod reaches its targets within 10%;
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
