#!/usr/bin/env bash
# Texture coordinates projected from the input's (docs/glb.md "Textures", issue 37): the
# bundled cow_charts.obj (tests/data/textured: the cow with a six-chart atlas, seams where
# charts meet, each chart a board in its own colours) through the default config. No level
# is baked: each embeds the input's PNG (its bytes, or scaled down to the level's size) with
# coordinates taken from the input's, split where its corners read different charts:
#   - report.json says texcoords "projected" for every level; the scan at lod100 has
#     exactly the input's 4,614 (vertex, texture coordinate) pairs as GLB vertices and no
#     corner across a seam; lod20 has fewer vertices than 3 per triangle (not the baked
#     atlas's one chart per triangle);
#   - each GLB has TEXCOORD_0, no COLOR_0 and one image, the input's PNG bytes;
#   - three.js in headless Chromium (unlit, one box for all) draws lod20 and thumb within
#     15 % of the scan's foreground pixels of the scan's picture (measured: 10.5 % and 7 %;
#     a triangle reading across the atlas, as without the charts, makes 34 % and 30 %);
#   - the validator finds 0 errors;
#   - texture_sizes = thumb:128: the thumb's image is the input's scaled to 128 px (JPEG);
#     with texture_format = webp a WebP (EXT_texture_webp) with a JPEG fallback, or alone
#     (the extension then required), both valid and drawn by three.js;
#   - texture = bake keeps the baked atlas (a JPEG, three vertices a triangle), and so does
#     an input whose coordinates leave [0, 1] (a tiled texture).
source "$(dirname "$0")/../lib.sh"
gltf="$SCANLOD_SOURCE_DIR/scripts/gltf"
render="$SCANLOD_SOURCE_DIR/scripts/viewer"
gltf_validator_ready || { echo "FAIL: the glTF validator is not installed (scripts/install-deps.sh)" >&2; exit 1; }
need_renderer
export PYTHONDONTWRITEBYTECODE=1

data="$SCANLOD_SOURCE_DIR/tests/data/textured"
mkdir -p "$TMP/in"
cp "$data/cow_charts.obj" "$data/cow_charts.mtl" "$data/cow_charts.png" "$TMP/in/"
write_config "$TMP/run.ini" "$TMP/in" "$TMP/work" "$TMP/out" "[levels]" "[export]" "thumbnail_size = 0"
run_scanlod run "$TMP/run.ini" -q
check "run exits 0 (got $rc: ${err:0:300})" [ "$rc" -eq 0 ]
dir="$TMP/out/cow_charts.obj"

# level texcoords vertices triangles corners_across_seams, per level
python3 -c "
import json; r = json.load(open('$dir/report.json'))
for l in r['stages']['export']['levels']:
    t = l.get('texture', {})
    print(l['name'], t.get('texcoords'), l['glb']['vertices'], l['triangles'], t.get('corners_across_seams'))
" >"$TMP/levels.txt"
cat "$TMP/levels.txt"
check "every level's texture coordinates are projected ($(tr '\n' ';' <"$TMP/levels.txt"))" \
  python3 -c "import sys; sys.exit(0 if all(l.split()[1] == 'projected' for l in open('$TMP/levels.txt')) else 1)"
check "lod100 (the scan): the input's 4614 vertex/coordinate pairs, no corner across a seam" \
  grep -qx 'lod100 projected 4614 5804 0' "$TMP/levels.txt"
check "lod20: fewer than 3 vertices a triangle, some corners across seams" python3 -c "
import sys
for l in open('$TMP/levels.txt'):
    n, _, v, t, s = l.split()
    if n == 'lod20': sys.exit(0 if int(v) < 3 * int(t) and int(s) > 0 else 1)
sys.exit(1)"

glb_image() { # glb_image FILE: TEXCOORD_0 COLOR_0 images mime same-bytes-as-the-input
  python3 -c "
import json, struct
d = open('$1', 'rb').read(); n = struct.unpack('<I', d[12:16])[0]
j = json.loads(d[20:20 + n]); p = j['meshes'][0]['primitives'][0]; bin = d[20 + n + 8:]
images = j.get('images', [])
v = j['bufferViews'][images[0]['bufferView']] if images else None
same = bool(v) and bin[v.get('byteOffset', 0):v.get('byteOffset', 0) + v['byteLength']] == open('$data/cow_charts.png', 'rb').read()
print('TEXCOORD_0' in p['attributes'], 'COLOR_0' in p['attributes'], len(images),
      images[0].get('mimeType') if images else None, same)"
}
for name in lod100 lod20 thumb; do
  got=$(glb_image "$dir/$name.glb")
  check "$name: TEXCOORD_0, no COLOR_0, one image/png, the input's bytes ($got)" \
    [ "$got" = "True False 1 image/png True" ]
done

box=$(python3 - "$dir/lod100.glb" <<'PY'
import json, struct, sys
d = open(sys.argv[1], 'rb').read(); n = struct.unpack('<I', d[12:16])[0]; j = json.loads(d[20:20 + n])
a = j['accessors'][j['meshes'][0]['primitives'][0]['attributes']['POSITION']]
node = j['nodes'][0]; s = node.get('scale', [1] * 3); t = node.get('translation', [0] * 3)
print(','.join('%.9g' % v for v in [a['min'][k] * s[k] + t[k] for k in range(3)] + [a['max'][k] * s[k] + t[k] for k in range(3)]))
PY
)
for name in lod100 lod20 thumb; do
  info=$(node "$render/render.cjs" "$dir/$name.glb" "$TMP/$name.png" unlit side "box=$box" 2>&1) || true
  check "$name: three.js draws it textured ($info)" grep -q '"textured":true' <<<"$info"
done
[ -z "${SCANLOD_RENDER_OUT:-}" ] || cp "$TMP"/lod100.png "$TMP"/lod20.png "$TMP"/thumb.png "$SCANLOD_RENDER_OUT/"
read -r fg d20 dthumb < <(PYTHONPATH="$SCANLOD_SOURCE_DIR/tests/export" python3 - "$TMP" <<'PY'
import sys, png_pixels
t = sys.argv[1]
def load(name): return [p for row in png_pixels.read('%s/%s.png' % (t, name)) for p in row]
ref = load('lod100')
def differ(name): return sum(1 for a, b in zip(ref, load(name)) if sum(abs(x - y) for x, y in zip(a[:3], b[:3])) > 48)
print(sum(1 for a in ref if sum(a[:3]) > 30), differ('lod20'), differ('thumb'))
PY
)
echo "pixels off the scan's picture: lod20 $d20, thumb $dthumb of $fg"
check "lod20 and thumb look like the scan (within 15 % of its $fg pixels: $d20, $dthumb)" \
  python3 -c "import sys; sys.exit(0 if $fg > 20000 and $d20 < 0.15 * $fg and $dthumb < 0.15 * $fg else 1)"

set +e
node "$gltf/validate.mjs" "$dir/lod100.glb" "$dir/lod20.glb" "$dir/thumb.glb" >"$TMP/valid.jsonl" 2>&1
vrc=$?
set -e
check "validator: 0 errors ($(head -c 400 "$TMP/valid.jsonl"))" \
  [ "$vrc" -eq 0 -a "$(grep -c '"numErrors":0,' "$TMP/valid.jsonl")" -eq 3 ]

if light; then
  # The sanitizer pass runs the projection, the WebP and its scaling (below); the 128 px
  # JPEG thumb, the tiled input and texture = bake are the Release pass's (the bake is
  # also test_glb_texture_kept's and test_glb_render's).
  echo "LIGHT: the 128 px JPEG thumb, the tiled input and the bake are the Release pass's"
fi
# A level whose size is below the image's: the image scaled down and re-encoded.
light || {
write_config "$TMP/small.ini" "$TMP/in" "$TMP/work-small" "$TMP/out-small" "[levels]" \
  "percents =" "budgets = thumb:2000" "[export]" "texture_sizes = thumb:128" "thumbnail_size = 0" \
  "fidelity = false"
run_scanlod run "$TMP/small.ini" -q
check "thumb at 128 px: run exits 0 (got $rc: ${err:0:300})" [ "$rc" -eq 0 ]
got=$(python3 -c "
import json; r = json.load(open('$TMP/out-small/cow_charts.obj/report.json'))
t = [l for l in r['stages']['export']['levels'] if l['name'] == 'thumb'][0]['texture']
print(t.get('texcoords'), t.get('size'), t.get('mime_type'))")
check "thumb at 128 px: projected, the image scaled to 128, a JPEG ($got)" [ "$got" = "projected 128 image/jpeg" ]
}

# texture_format = webp (EXT_texture_webp): with its JPEG fallback the extension is used,
# not required, and the texture's core source is the JPEG; without, it is required.
fallbacks="true false"
if light; then
  fallbacks=false
  echo "LIGHT: the WebP with its JPEG fallback is the Release pass's (the same code path, one more image)"
fi
for fallback in $fallbacks; do
  write_config "$TMP/webp-$fallback.ini" "$TMP/in" "$TMP/work-webp-$fallback" "$TMP/out-webp-$fallback" \
    "[levels]" "percents =" "budgets = thumb:2000" "[export]" "texture_sizes = thumb:128" \
    "texture_format = webp" "texture_webp_fallback = $fallback" "thumbnail_size = 0" "fidelity = false"
  run_scanlod run "$TMP/webp-$fallback.ini" -q
  check "webp, fallback $fallback: run exits 0 (got $rc: ${err:0:300})" [ "$rc" -eq 0 ]
  glb="$TMP/out-webp-$fallback/cow_charts.obj/thumb.glb"
  got=$(python3 -c "
import json, struct
d = open('$glb', 'rb').read(); n = struct.unpack('<I', d[12:16])[0]; j = json.loads(d[20:20 + n])
t = j['textures'][0]
print('EXT_texture_webp' in j.get('extensionsUsed', []), 'EXT_texture_webp' in j.get('extensionsRequired', []),
      [i['mimeType'] for i in j['images']], t.get('source'), t['extensions']['EXT_texture_webp']['source'])")
  want="True False ['image/webp', 'image/jpeg'] 1 0"
  [ "$fallback" = true ] || want="True True ['image/webp'] None 0"
  check "webp, fallback $fallback: extensions, images and sources ($got)" [ "$got" = "$want" ]
  set +e
  node "$gltf/validate.mjs" "$glb" >"$TMP/valid-webp.jsonl" 2>&1
  vrc=$?
  set -e
  check "webp, fallback $fallback: validator 0 errors ($(head -c 300 "$TMP/valid-webp.jsonl"))" \
    [ "$vrc" -eq 0 -a "$(grep -c '"numErrors":0,' "$TMP/valid-webp.jsonl")" -eq 1 ]
  info=$(node "$render/render.cjs" "$glb" "$TMP/webp-$fallback.png" unlit 2>&1) || true
  check "webp, fallback $fallback: three.js draws it textured ($info)" grep -q '"textured":true' <<<"$info"
done

# Coordinates outside [0, 1] (a tiled texture, read with REPEAT) cannot be projected into
# a CLAMP_TO_EDGE file: such an input's levels are baked.
if light; then finish; exit; fi
mkdir -p "$TMP/in-tiled"
cp "$data/cow_charts.mtl" "$data/cow_charts.png" "$TMP/in-tiled/"
awk '$1 == "vt" { printf "vt %.6f %.6f\n", 2 * $2, $3; next } { print }' "$data/cow_charts.obj" \
  >"$TMP/in-tiled/cow_charts.obj"
write_config "$TMP/tiled.ini" "$TMP/in-tiled" "$TMP/work-tiled" "$TMP/out-tiled" "[levels]" \
  "percents = 20" "budgets =" "[export]" "thumbnail_size = 0" "fidelity = false"
run_scanlod run "$TMP/tiled.ini" -q
check "tiled: run exits 0 (got $rc: ${err:0:300})" [ "$rc" -eq 0 ]
got=$(python3 -c "
import json; r = json.load(open('$TMP/out-tiled/cow_charts.obj/report.json'))
print([l for l in r['stages']['export']['levels'] if l['name'] == 'lod20'][0]['texture'].get('source'))")
check "tiled: coordinates outside [0, 1]: lod20 is baked ($got)" [ "$got" = baked ]

# texture = bake: the baked atlas, as before.
write_config "$TMP/bake.ini" "$TMP/in" "$TMP/work-bake" "$TMP/out-bake" "[levels]" \
  "percents = 20" "budgets =" "[export]" "texture = bake" "thumbnail_size = 0" "fidelity = false"
run_scanlod run "$TMP/bake.ini" -q
check "bake: run exits 0 (got $rc: ${err:0:300})" [ "$rc" -eq 0 ]
got=$(python3 -c "
import json; r = json.load(open('$TMP/out-bake/cow_charts.obj/report.json'))
l = [l for l in r['stages']['export']['levels'] if l['name'] == 'lod20'][0]
print(l['texture'].get('source'), l['texture'].get('mime_type'), l['glb']['vertices'] == 3 * l['triangles'])")
check "bake: lod20 is a baked JPEG atlas, three vertices a triangle ($got)" [ "$got" = "baked image/jpeg True" ]
finish
