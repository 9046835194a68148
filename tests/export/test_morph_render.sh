#!/usr/bin/env bash
# Morph targets on screen (docs/morphing.md): three.js in headless Chromium
# (scripts/viewer/render.cjs) draws the bunny's lod60 GLB, which morphs to lod30, at
# morph weights 0, 0.5 and 1, and lod30's own GLB, all framed by one box so the pictures
# line up pixel for pixel; unlit, so each picture is the level's silhouette. The pictures
# must change monotonically from the finer level's to the coarser one's: the number of
# pixels that differ from lod30's picture falls strictly from weight 0 to 0.5 to 1 (and
# weight 1 is at most 60 % as far as weight 0; the rest is coarser surface no vertex of
# the finer level projects to), and the number that differ from weight 0's picture rises.
# examples/viewer (tests/export/example_viewer.cjs) must draw weights 0, 0.5, 1 at 1, 2, 4
# times the framing distance, and the report's index.html (check_page.mjs) must draw
# lod60 with the blending on. Run for meshopt and Draco files. Chromium, node and the npm packages are test
# dependencies: missing ones FAIL the test. The default (qef) levels: before the morph
# refinement weight 1 was farther from lod30 than weight 0.5 (901 vs 813 pixels).
source "$(dirname "$0")/../lib.sh"
export PYTHONDONTWRITEBYTECODE=1
render="$SCANLOD_SOURCE_DIR/scripts/viewer"
need_renderer

mkdir -p "$TMP/in"
cp "$SCANS/bun_zipper_res3.ply" "$TMP/in/"
cat >"$TMP/diff.py" <<'PY'
import sys, png_pixels
def load(p): return [px for row in png_pixels.read(p) for px in row]
def diff(a, b): return sum(1 for x, y in zip(a, b) if sum(abs(u - v) for u, v in zip(x, y)) > 48)
w0, wh, w1, coarse = (load(p) for p in sys.argv[1:5])
print(diff(w0, coarse), diff(wh, coarse), diff(w1, coarse), diff(w0, wh), diff(w0, w1))
PY
comps="meshopt draco"
if light; then
  comps=meshopt
  echo "LIGHT: the Draco GLB's pictures are the Release pass's (the Draco morph's bytes: test_morph)"
fi
for comp in $comps; do
  write_config "$TMP/$comp.ini" "$TMP/in" "$TMP/work-$comp" "$TMP/out-$comp" "[levels]" \
    "percents = 30,60" "budgets =" "[export]" "formats = glb" "thumbnail_size = 0" "fidelity = false" \
    "compression = $comp" "morph = true"
  run_scanlod run "$TMP/$comp.ini" -q
  check "$comp: run exits 0 ($err)" [ "$rc" -eq 0 ]
  dir="$TMP/out-$comp/bun_zipper_res3.ply"
  box=$(python3 - "$dir/lod60.glb" "$dir/lod30.glb" <<'PY'
import json, struct, sys
lo, hi = [1e30] * 3, [-1e30] * 3
for f in sys.argv[1:]:
    d = open(f, 'rb').read(); n = struct.unpack('<I', d[12:16])[0]; j = json.loads(d[20:20 + n])
    p = j['meshes'][0]['primitives'][0]
    node = j['nodes'][0]; s = node.get('scale', [1] * 3); t = node.get('translation', [0] * 3)
    a = j['accessors'][p['attributes']['POSITION']]
    m = j['accessors'][p['targets'][0]['POSITION']] if 'targets' in p else {'min': [0] * 3, 'max': [0] * 3}
    for k in range(3):
        lo[k] = min(lo[k], (a['min'][k] + min(0, m['min'][k])) * s[k] + t[k])
        hi[k] = max(hi[k], (a['max'][k] + max(0, m['max'][k])) * s[k] + t[k])
print(','.join('%.9g' % v for v in lo + hi))
PY
)
  for w in 0 0.5 1; do
    info=$(node "$render/render.cjs" "$dir/lod60.glb" "$TMP/$comp-$w.png" unlit "morph=$w" "box=$box" 2>&1) || true
    check "$comp weight $w: three.js draws it with one morph target ($info)" grep -q '"morphTargets":1' <<<"$info"
  done
  info=$(node "$render/render.cjs" "$dir/lod30.glb" "$TMP/$comp-coarse.png" unlit "box=$box" 2>&1) || true
  check "$comp lod30: drawn, no morph target ($info)" grep -q '"morphTargets":0' <<<"$info"
  read -r c0 ch c1 d0h d01 < <(PYTHONPATH="$SCANLOD_SOURCE_DIR/tests/export" python3 "$TMP/diff.py" \
    "$TMP/$comp-0.png" "$TMP/$comp-0.5.png" "$TMP/$comp-1.png" "$TMP/$comp-coarse.png")
  echo "$comp: pixels off lod30 at weights 0 / 0.5 / 1: $c0 / $ch / $c1; off weight 0: $d0h / $d01"
  check "$comp: pixels off lod30's picture fall with the weight ($c0 > $ch > $c1, $c1 <= 0.6 x $c0)" \
    python3 -c "import sys; sys.exit(0 if $c0 > $ch > $c1 and $c1 <= 0.6 * $c0 and $c0 > 500 else 1)"
  check "$comp: pixels off weight 0's picture rise with the weight (0 < $d0h < $d01)" \
    python3 -c "import sys; sys.exit(0 if 0 < $d0h < $d01 else 1)"
  [ -z "${SCANLOD_RENDER_OUT:-}" ] || cp "$TMP/$comp"-*.png "$SCANLOD_RENDER_OUT/"
  # examples/viewer blends by camera distance: weight 0 at the framing distance, 0.5 at
  # twice it, 1 from three times it; a level without a target has no weight.
  for dw in 1:0 2:0.5 4:1; do
    IFS=: read -r d want <<<"$dw"
    got=$(node "$SCANLOD_SOURCE_DIR/tests/export/example_viewer.cjs" "$SCANLOD_SOURCE_DIR" "$dir/lod60.glb" "$d" 2>&1 | tail -1) || true
    check "$comp examples/viewer at $d x the framing distance: weight $want ($got)" \
      python3 -c "import sys; sys.exit(0 if abs(float('$got') - $want) < 1e-9 else 1)"
  done
  got=$(node "$SCANLOD_SOURCE_DIR/tests/export/example_viewer.cjs" "$SCANLOD_SOURCE_DIR" "$dir/lod30.glb" 2 2>&1 | tail -1) || true
  check "$comp examples/viewer: lod30 has no morph weight ($got)" [ "$got" = "null" ]
  # The report's index.html: its views draw, lod60's with the blending (weight 0 at the
  # framing distance), and its caption says what it blends into.
  (cd "$dir" && node "$render/check_page.mjs" --levels index.html) >"$TMP/$comp-page.jsonl" 2>&1 || true
  check "$comp index.html: lod60 drawn with morph weight 0.000 ($(grep lod60 "$TMP/$comp-page.jsonl" | head -1))" \
    grep -q '"src":"lod60.glb.js","state":"drawn".*"morph":"0.000"' "$TMP/$comp-page.jsonl"
  check "$comp index.html: lod30 drawn without morph" \
    grep -q '"src":"lod30.glb.js","state":"drawn".*"morph":null' "$TMP/$comp-page.jsonl"
  check "$comp index.html: the caption names the coarser level" grep -q "blends into lod30 as you zoom out" "$dir/index.html"
done
finish
