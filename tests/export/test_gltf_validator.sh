#!/usr/bin/env bash
# Every GLB scanlod writes passes the Khronos glTF validator (npm `gltf-validator`) with 0
# errors and 0 warnings: test_glb writes float sample files (cubes with and without
# normals/colours, one triangle with padded 16-bit indices, a 90000-vertex grid with 32-bit
# indices, and the bundled scans) into a temp dir, test_glb_codecs the quantised
# (KHR_mesh_quantization), meshopt (quantised and float) and Draco variants of its meshes,
# and scripts/gltf/validate.mjs checks each one. The validator cannot look inside the
# compressed streams: those files get exactly two infos, UNSUPPORTED_EXTENSION and
# UNUSED_OBJECT (the data is only reachable through the extension), and test_glb_codecs
# decodes them itself; the quantised twins, which it can read, have no info at all. A file
# the validator must reject proves the harness is not a no-op.
# The validator is a test dependency (scripts/install-deps.sh installs it): when node or
# the package is missing this test FAILS, it does not skip.
source "$(dirname "$0")/../lib.sh"
gltf="$SCANLOD_SOURCE_DIR/scripts/gltf"
driver="${SCANLOD_BUILD_DIR:?}/tests/test_glb"
codecs="$SCANLOD_BUILD_DIR/tests/test_glb_codecs"

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
check "test_glb_codecs writes the samples" env SCANLOD_GLB_OUT="$TMP/glb" "$codecs"
count=$(find "$TMP/glb" -name '*.glb' | wc -l)
check "42 sample GLBs: 10 float, 8 meshes x (quantized, meshopt, meshopt_float, draco) ($count)" \
  [ "$count" -eq 42 ]

set +e
node "$gltf/validate.mjs" --infos "$TMP"/glb/*.glb >"$TMP/report.jsonl" 2>"$TMP/validate.err"
rc=$?
set -e
cat "$TMP/report.jsonl"
check "validator: exit 0 (no file with errors)" [ "$rc" -eq 0 ]
check "validator: one report per file" [ "$(wc -l <"$TMP/report.jsonl")" -eq "$count" ]
check "validator: every file 0 errors" \
  [ "$(grep -c '"numErrors":0,' "$TMP/report.jsonl")" -eq "$count" ]
check "validator: every file 0 warnings" \
  [ "$(grep -c '"numWarnings":0,' "$TMP/report.jsonl")" -eq "$count" ]
compressed=$(grep -c -E '\.(meshopt|meshopt_float|draco)\.glb"' "$TMP/report.jsonl")
check "24 compressed samples ($compressed)" [ "$compressed" -eq 24 ]
# Infos of compressed files: UNSUPPORTED_EXTENSION always, UNUSED_OBJECT when nothing but
# the extension reaches buffer 0 (a textured file's image does), nothing else.
infos_ok=$(python3 - "$TMP/report.jsonl" <<'EOF'
import json, re, sys
ok = 0
for line in open(sys.argv[1]):
    r = json.loads(line)
    if not re.search(r"\.(meshopt|meshopt_float|draco)\.glb$", r["file"]):
        continue
    codes = [i["code"] for i in r["issues"] if i["severity"] == "info"]
    ok += (codes.count("UNSUPPORTED_EXTENSION") == 1 and
           set(codes) <= {"UNSUPPORTED_EXTENSION", "UNUSED_OBJECT"} and
           len(codes) == r["numInfos"])
print(ok)
EOF
)
check "compressed: infos UNSUPPORTED_EXTENSION (+ UNUSED_OBJECT) only ($infos_ok)" \
  [ "$infos_ok" -eq "$compressed" ]
check "uncompressed (float and quantized): no info at all" \
  [ "$(grep -v -E '\.(meshopt|meshopt_float|draco)\.glb"' "$TMP/report.jsonl" |
       grep -c '"numInfos":0,')" -eq "$((count - compressed))" ]
quantized=$(grep -c '\.quantized\.glb"' "$TMP/report.jsonl")
check "8 quantized (KHR_mesh_quantization) samples validated in full ($quantized)" \
  [ "$quantized" -eq 8 ]

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
# The same on a quantised file: integer bounds, checked against the integer data.
LC_ALL=C sed 's/"max":\[16383,/"max":[16382,/' "$TMP/glb/cube_all.quantized.glb" >"$TMP/badq.glb"
differs=1
cmp -s "$TMP/glb/cube_all.quantized.glb" "$TMP/badq.glb" && differs=0
check "bad quantized sample differs" [ "$differs" -eq 1 ]
set +e
node "$gltf/validate.mjs" "$TMP/badq.glb" >"$TMP/badq.jsonl" 2>&1
rc=$?
set -e
check "validator rejects a wrong quantized max: exit 1 ($(cat "$TMP/badq.jsonl"))" [ "$rc" -eq 1 ]
finish
