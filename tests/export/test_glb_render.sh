#!/usr/bin/env bash
# A textured scan in, textured GLBs out, and the texture on screen: the bundled textured
# cow (tests/data/textured, per-vertex UVs and a board of 8 flat colours) goes through
# the pipeline with meshopt and with Draco compression, every level baked ([export] texture
# = bake; the default keeps the input's image where it can: test_glb_texture_kept.sh).
# Each level's GLB has TEXCOORD_0,
# an embedded JPEG and a baseColorTexture, and passes the validator; three.js in headless
# Chromium (scripts/viewer/render.cjs, playwright-core) loads it, finds the texture, and
# draws it unlit from the side: at least 85% of the cow's pixels lie within 40 (RGB
# distance) of one of the texture's own colours and all 8 colours show. As a control the
# same level exported with `texture = none` (vertex colours) must not pass that check.
# Chromium, node and the npm packages are test dependencies (scripts/install-deps.sh):
# missing ones FAIL the test rather than skip it.
source "$(dirname "$0")/../lib.sh"
export PYTHONDONTWRITEBYTECODE=1 # png_pixels.py: no __pycache__ in the source tree
gltf="$SCANLOD_SOURCE_DIR/scripts/gltf"
render="$SCANLOD_SOURCE_DIR/scripts/viewer"
gltf_validator_ready || { echo "FAIL: the glTF validator is not installed (scripts/install-deps.sh)" >&2; exit 1; }
need_renderer

mkdir -p "$TMP/in"
cp "$SCANLOD_SOURCE_DIR/tests/data/textured/cow_textured.ply" "$SCANLOD_SOURCE_DIR/tests/data/textured/cow_texture.png" "$TMP/in/"
run_mode() { # run_mode NAME compression texture
  write_config "$TMP/$1.ini" "$TMP/in" "$TMP/work-$1" "$TMP/out-$1" "[levels]" "percents = 100" \
    "budgets = thumb:800" "[export]" "formats = ply,glb" "thumbnail_size = 0" "fidelity = false" \
    "compression = $2" "texture = $3" "texture_sizes = thumb:512,lod100:1024"
  run_scanlod run "$TMP/$1.ini" -q
  check "$1: run exits 0 (got $rc: ${err:0:300})" [ "$rc" -eq 0 ]
}
run_mode meshopt meshopt bake
run_mode draco draco bake
run_mode plain meshopt none

# The texture's own colours, and how much of a picture of the cow is made of them.
cat >"$TMP/colours.py" <<'PY'
import sys, png_pixels
texture = sorted(set(p for row in png_pixels.read(sys.argv[1]) for p in row))
shot = [p for row in png_pixels.read(sys.argv[2]) for p in row if max(p) > 30]  # not background
near = [min(range(len(texture)), key=lambda i: sum((a - b) ** 2 for a, b in zip(p, texture[i])))
        for p in shot]
close = [i for p, i in zip(shot, near) if sum((a - b) ** 2 for a, b in zip(p, texture[i])) <= 40 ** 2]
shown = sum(1 for i in range(len(texture)) if close.count(i) >= 0.01 * len(shot))
print(len(texture), len(shot), round(len(close) / max(1, len(shot)), 3), shown)
PY
for mode in meshopt draco; do
  dir="$TMP/out-$mode/cow_textured.ply"
  for name in lod100 thumb; do
    json=$(python3 -c "
import json, struct, sys
d = open('$dir/$name.glb', 'rb').read(); n = struct.unpack('<I', d[12:16])[0]
j = json.loads(d[20:20 + n]); p = j['meshes'][0]['primitives'][0]
print('TEXCOORD_0' in p['attributes'], 'COLOR_0' in p['attributes'],
      j.get('images', [{}])[0].get('mimeType'),
      'baseColorTexture' in j['materials'][0]['pbrMetallicRoughness'])")
    check "$mode $name: TEXCOORD_0, no COLOR_0, a JPEG baseColorTexture ($json)" [ "$json" = "True False image/jpeg True" ]
  done
  set +e
  node "$gltf/validate.mjs" "$dir"/*.glb >"$TMP/$mode.jsonl" 2>&1
  vrc=$?
  set -e
  check "$mode: validator 0 errors, 0 warnings on every GLB" \
    [ "$vrc" -eq 0 -a "$(grep -c '"numErrors":0,"numWarnings":0,' "$TMP/$mode.jsonl")" -eq 2 ]
  info=$(node "$render/render.cjs" "$dir/lod100.glb" "$TMP/$mode.png" unlit 2>&1) || true
  check "$mode: three.js loads it with its texture ($info)" grep -q '"textured":true' <<<"$info"
  read -r colours pixels share shown < <(PYTHONPATH="$SCANLOD_SOURCE_DIR/tests/export" \
    python3 "$TMP/colours.py" "$TMP/in/cow_texture.png" "$TMP/$mode.png")
  check "$mode: the picture shows the texture ($share of $pixels cow pixels near one of its $colours colours, $shown shown)" \
    python3 -c "import sys; sys.exit(0 if $share >= 0.85 and $shown == $colours else 1)"
  [ -z "${SCANLOD_RENDER_OUT:-}" ] || cp "$TMP/$mode.png" "$SCANLOD_RENDER_OUT/cow_$mode.png"
done
# Control: vertex colours only (texture = none) must not pass for the texture.
dir="$TMP/out-plain/cow_textured.ply"
info=$(node "$render/render.cjs" "$dir/lod100.glb" "$TMP/plain.png" unlit 2>&1) || true
check "plain: no texture, vertex colours ($info)" grep -q '"textured":false,"vertexColors":true' <<<"$info"
read -r colours pixels share shown < <(PYTHONPATH="$SCANLOD_SOURCE_DIR/tests/export" \
  python3 "$TMP/colours.py" "$TMP/in/cow_texture.png" "$TMP/plain.png")
check "plain: vertex colours do not pass for the texture ($share near, $shown of $colours shown)" \
  python3 -c "import sys; sys.exit(0 if not ($share >= 0.85 and $shown == $colours) else 1)"
[ -z "${SCANLOD_RENDER_OUT:-}" ] || cp "$TMP/plain.png" "$SCANLOD_RENDER_OUT/cow_plain.png"
finish
