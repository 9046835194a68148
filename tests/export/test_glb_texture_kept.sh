#!/usr/bin/env bash
# Textures at their own resolution (docs/glb.md "Textures"): the bundled textured cow
# (tests/data/textured, per-vertex UVs, a 1108-byte PNG) through the default config. The
# levels made of the scan's vertices (the scan at lod100, the scan collapsed by the refine
# stage at lod20) keep its texture coordinates and the input's image: each GLB has
# TEXCOORD_0, no COLOR_0, exactly one image whose bytes are the input PNG's, with its
# mimeType; glb_uv_check decodes the GLB and finds every coordinate in [0, 1] and near the
# nearest input vertex's (lod100: within a 12-bit step; lod20, whose vertices moved in the
# collapse and the fit: within 0.1, where a baked atlas's charts are anywhere in [0, 1]).
# The GLBs pass the validator, and three.js in headless Chromium draws lod20 textured.
# With [lod] method = octree the octree's levels are not the scan's: their texture
# coordinates are projected from the input's (test_glb_texture_projected), with the input's
# PNG, while the scan at lod100 keeps its own.
# Fails under [export] texture = bake (every check on the image and the UVs).
source "$(dirname "$0")/../lib.sh"
gltf="$SCANLOD_SOURCE_DIR/scripts/gltf"
render="$SCANLOD_SOURCE_DIR/scripts/viewer"
uv_check="${SCANLOD_BUILD_DIR:?}/tests/glb_uv_check"
gltf_validator_ready || { echo "FAIL: the glTF validator is not installed (scripts/install-deps.sh)" >&2; exit 1; }
need_renderer

data="$SCANLOD_SOURCE_DIR/tests/data/textured"
mkdir -p "$TMP/in"
cp "$data/cow_textured.ply" "$data/cow_texture.png" "$TMP/in/"
# The default ladder and export ([levels] and [export] named, so write_config adds
# nothing of its own to them).
write_config "$TMP/run.ini" "$TMP/in" "$TMP/work" "$TMP/out" "[levels]" "[export]"
run_scanlod run "$TMP/run.ini" -q
check "run exits 0 (got $rc: ${err:0:300})" [ "$rc" -eq 0 ]
dir="$TMP/out/cow_textured.ply"

method=$(python3 -c "
import json; r = json.load(open('$dir/report.json'))
print(' '.join(l['name'] + ':' + l['method'] for l in r['stages']['refine']['levels']))")
check "lod100 and lod20 are the scan's ($method)" \
  grep -q 'lod100:scan.*lod20:scan\|lod20:scan.*lod100:scan' <<<"$method"

for name in lod100 lod20; do
  json=$(python3 -c "
import json, struct
d = open('$dir/$name.glb', 'rb').read(); n = struct.unpack('<I', d[12:16])[0]
j = json.loads(d[20:20 + n]); p = j['meshes'][0]['primitives'][0]
bin = d[20 + n + 8:]
images = j.get('images', [])
same = len(images) == 1 and (lambda v: bin[v.get('byteOffset', 0):v.get('byteOffset', 0) + v['byteLength']])(
    j['bufferViews'][images[0]['bufferView']]) == open('$data/cow_texture.png', 'rb').read()
print('TEXCOORD_0' in p['attributes'], 'COLOR_0' in p['attributes'], len(images),
      images[0].get('mimeType') if images else None, same)")
  check "$name: TEXCOORD_0, no COLOR_0, one image/png, the input's bytes ($json)" \
    [ "$json" = "True False 1 image/png True" ]
done
# Units and up as the report's frame resolved them (the cow says nothing: estimated).
read -r to_m up < <(python3 -c "
import json; f = json.load(open('$dir/report.json'))['stages']['export']['frame']
print({'mm': 0.001, 'cm': 0.01, 'm': 1, 'in': 0.0254, 'ft': 0.3048}[f['units']], f['up'])")
out=$("$uv_check" "$dir/lod100.glb" "$data/cow_textured.ply" "$to_m" "$up" 0.000245 2>&1) && urc=0 || urc=$?
check "lod100: the input's texture coordinates ($out)" [ "$urc" -eq 0 ]
out=$("$uv_check" "$dir/lod20.glb" "$data/cow_textured.ply" "$to_m" "$up" 0.1 2>&1) && urc=0 || urc=$?
check "lod20: its vertices' texture coordinates ($out)" [ "$urc" -eq 0 ]

set +e
node "$gltf/validate.mjs" "$dir/lod100.glb" "$dir/lod20.glb" >"$TMP/valid.jsonl" 2>&1
vrc=$?
set -e
check "validator: 0 errors, 0 warnings ($(head -c 400 "$TMP/valid.jsonl"))" \
  [ "$vrc" -eq 0 -a "$(grep -c '"numErrors":0,"numWarnings":0,' "$TMP/valid.jsonl")" -eq 2 ]
info=$(node "$render/render.cjs" "$dir/lod20.glb" "$TMP/lod20.png" unlit 2>&1) || true
check "lod20: three.js draws it with its texture ($info)" grep -q '"textured":true' <<<"$info"
[ -z "${SCANLOD_RENDER_OUT:-}" ] || cp "$TMP/lod20.png" "$SCANLOD_RENDER_OUT/cow_kept_lod20.png"

# The octree's levels: projected, the scan at the top: kept.
write_config "$TMP/octree.ini" "$TMP/in" "$TMP/work-octree" "$TMP/out-octree" "[lod]" \
  "method = octree" "[levels]" "[export]" "thumbnail_size = 0" "fidelity = false"
run_scanlod run "$TMP/octree.ini" -q
check "octree: run exits 0 (got $rc: ${err:0:300})" [ "$rc" -eq 0 ]
kinds=$(python3 -c "
import json, struct
for name in ('lod100', 'lod20'):
    d = open('$TMP/out-octree/cow_textured.ply/' + name + '.glb', 'rb').read()
    n = struct.unpack('<I', d[12:16])[0]; j = json.loads(d[20:20 + n])
    print(name, [i.get('mimeType') for i in j.get('images', [])], end=' ')")
check "octree: lod100 (the scan) and lod20 (an octree cut) embed the input's PNG ($kinds)" \
  [ "$kinds" = "lod100 ['image/png'] lod20 ['image/png'] " ]
coords=$(python3 -c "
import json; r = json.load(open('$TMP/out-octree/cow_textured.ply/report.json'))
print(' '.join(l['name'] + ':' + str(l['texture'].get('texcoords')) for l in r['stages']['export']['levels']
               if l['name'] in ('lod100', 'lod20')))")
check "octree: lod20's texture coordinates are projected from the input's, lod100 keeps them ($coords)" \
  [ "$coords" = "lod20:projected lod100:input" -o "$coords" = "lod100:input lod20:projected" ]

# A kept level whose size is below the image's: the input's coordinates, the image scaled
# (the Release pass's: the sanitizer pass scales images in test_glb_texture_projected).
light || {
write_config "$TMP/small-kept.ini" "$TMP/in" "$TMP/work-small-kept" "$TMP/out-small-kept" "[levels]" \
  "percents =" "budgets = thumb:2000" "[export]" "texture_sizes = thumb:128" "thumbnail_size = 0" \
  "fidelity = false"
run_scanlod run "$TMP/small-kept.ini" -q
check "thumb at 128 px: run exits 0 (got $rc: ${err:0:300})" [ "$rc" -eq 0 ]
got=$(python3 -c "
import json; r = json.load(open('$TMP/out-small-kept/cow_textured.ply/report.json'))
t = [l for l in r['stages']['export']['levels'] if l['name'] == 'thumb'][0]['texture']
print(t.get('texcoords'), t.get('size'), t.get('mime_type'))")
check "thumb at 128 px: the input's coordinates, the image scaled to 128, a JPEG ($got)" \
  [ "$got" = "input 128 image/jpeg" ]
}

# A baked level whose triangles do not fit one atlas chart each (a 64 px atlas here)
# keeps vertex colours: said in the log where runs are watched and on the item page, not
# only in report.json.
write_config "$TMP/small.ini" "$TMP/in" "$TMP/work-small" "$TMP/out-small" "[levels]" \
  "percents = 100" "budgets =" "[export]" "texture = bake" "texture_size = 64" \
  "thumbnail_size = 0" "fidelity = false"
rm -rf "$TMP/logs"
run_scanlod run "$TMP/small.ini" -q
check "64 px atlas: run exits 0 (got $rc: ${err:0:300})" [ "$rc" -eq 0 ]
check "64 px atlas: the report says vertex colours only" \
  grep -q '"warning": *"too many triangles for the atlas: vertex colours only"' \
  "$TMP/out-small/cow_textured.ply/report.json"
check "64 px atlas: the item page says lod100 has no texture" \
  grep -q 'no texture: too many triangles for an atlas, vertex colours only' \
  "$TMP/out-small/cow_textured.ply/index.html"
check "64 px atlas: the log warns that lod100 has no texture" \
  grep -q 'WARN.*lod100: 5804 triangles do not fit one atlas chart each at 64 px: vertex colours only' \
  "$TMP"/logs/*.log
finish
