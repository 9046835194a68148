#!/usr/bin/env bash
# Every GLB scanlod writes passes the Khronos glTF validator (npm `gltf-validator`) with 0
# errors: test_glb writes sample files (cubes with and without normals/colours, one
# triangle with padded 16-bit indices, a 90000-vertex grid with 32-bit indices, and the
# bundled scans) into a temp dir and scripts/gltf/validate.mjs checks each one. A file the
# validator must reject proves the harness is not a no-op.
# The validator is a test dependency (scripts/install-deps.sh installs it): when node or
# the package is missing this test FAILS, it does not skip.
source "$(dirname "$0")/../lib.sh"
gltf="$SCANLOD_SOURCE_DIR/scripts/gltf"
driver="${SCANLOD_BUILD_DIR:?}/tests/test_glb"

if ! command -v node >/dev/null; then
  echo "FAIL: node is not installed; run scripts/install-deps.sh" >&2
  exit 1
fi
if [ ! -f "$gltf/node_modules/gltf-validator/package.json" ]; then
  echo "FAIL: the glTF validator is not installed; run: npm ci --prefix scripts/gltf" >&2
  exit 1
fi

mkdir -p "$TMP/glb"
check "test_glb writes the samples" env SCANLOD_GLB_OUT="$TMP/glb" "$driver"
count=$(find "$TMP/glb" -name '*.glb' | wc -l)
check "ten sample GLBs ($count)" [ "$count" -eq 10 ]

set +e
node "$gltf/validate.mjs" "$TMP"/glb/*.glb >"$TMP/report.jsonl" 2>"$TMP/validate.err"
rc=$?
set -e
cat "$TMP/report.jsonl"
check "validator: exit 0 (no file with errors)" [ "$rc" -eq 0 ]
check "validator: one report per file" [ "$(wc -l <"$TMP/report.jsonl")" -eq "$count" ]
check "validator: every file 0 errors" \
  [ "$(grep -c '"numErrors":0,' "$TMP/report.jsonl")" -eq "$count" ]
check "validator: every file 0 warnings" \
  [ "$(grep -c '"numWarnings":0,' "$TMP/report.jsonl")" -eq "$count" ]

# The same bytes with POSITION's max changed by 0.1 (same length, so the container is
# intact): the validator must report ACCESSOR_MAX_MISMATCH and validate.mjs exit 1.
LC_ALL=C sed 's/"max":\[0\.5,/"max":[0.4,/' "$TMP/glb/cube_all.glb" >"$TMP/bad.glb"
differs=1
cmp -s "$TMP/glb/cube_all.glb" "$TMP/bad.glb" && differs=0
check "bad sample differs" [ "$differs" -eq 1 ]
set +e
node "$gltf/validate.mjs" "$TMP/bad.glb" >"$TMP/bad.jsonl" 2>&1
rc=$?
set -e
check "validator rejects a wrong max: exit 1" [ "$rc" -eq 1 ]
check "validator names the mismatch" grep -q ACCESSOR_MAX_MISMATCH "$TMP/bad.jsonl"
finish
