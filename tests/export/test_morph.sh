#!/usr/bin/env bash
# [export] morph = true (docs/morphing.md) on the octree method's own levels of the bundled
# bunny (lod30, lod60, lod100) for every GLB encoding (none float, none quantised, meshopt,
# draco), and on the cluster method's levels of the cow (thumb, lod40, lod100; float,
# meshopt, draco):
#   - each level morphs to the next coarser one (the report says so), the coarsest level
#     and the cluster method's intermediate models have no target (the same file as with
#     morph = false);
#   - every GLB passes the Khronos validator with 0 errors;
#   - weight 1 lies on the coarser level: each vertex of the GLB decoded by the tests' own
#     reader with the target at weight 1 is within 1e-5 of the diagonal of lod30's / lod60's
#     surface (float files), within that plus the file's quantisation bound (quantised);
#   - weight 0 is the level's surface: the morphing GLB carries the level cut along the
#     coarser level's edges (docs/morphing.md; its views are not the plain GLB's), whose
#     decoded surface at weight 0 is within 1e-6 of the diagonal plus the quantisation
#     bound of the level's (symmetric Hausdorff, scanlod compare); test_morph_surface
#     checks the surface at weight 1;
# and scanlod extract --morph-to: the PLY at weight 0 is the plain level's PLY byte for
# byte, at weight 1 its vertices lie on the coarser cut (<= 1e-5 of the diagonal), at 0.5
# between; a GLB carries the target; bad requests are refused in one line.
source "$(dirname "$0")/../lib.sh"
gltf="$SCANLOD_SOURCE_DIR/scripts/gltf"
mc="${SCANLOD_BUILD_DIR:?}/tests/morph_check"
views="$SCANLOD_SOURCE_DIR/tests/export/glb_views.py"
gltf_validator_ready || { echo "FAIL: the glTF validator is not installed (scripts/install-deps.sh)" >&2; exit 1; }

# The papers' levels: each method's own cuts and models, unrefined, its finest level on top
# rather than the scan (docs/levels.md: top = method, oversample = 1, collapse and fit
# off), so a level's morph target is the method's own coarser level. The published
# (refined) levels' morphs are test_morph_render's and test_morph_surface's.
paper=("top = method" "oversample = 1" "[refine]" "collapse = false" "fit = false")
mkdir -p "$TMP/in"
cp "$SCANS/bun_zipper_res3.ply" "$TMP/in/"
item=bun_zipper_res3.ply
run_mode() { # run_mode NAME compression quantize morph
  write_config "$TMP/$1.ini" "$TMP/in" "$TMP/work-$1" "$TMP/out-$1" "[levels]" \
    "percents = 30,60,100" "budgets =" "${paper[@]}" "[export]" "formats = ply,glb" "thumbnail_size = 0" \
    "fidelity = false" "compression = $2" "quantize = $3" "morph = $4"
  run_scanlod run "$TMP/$1.ini" -q
  check "$1: run exits 0 (got $rc: ${err:0:300})" [ "$rc" -eq 0 ]
}
ratio_of() { sed -n 's/.* ratio \([^ ]*\)$/\1/p' <<<"$1"; }
within() { python3 -c "import sys; sys.exit(0 if '$1' and float('$1') <= float('$2') else 1)"; }
# check_levels NAME ITEM "FINE:COARSER ..." COARSEST: the checks above on one run's levels.
check_levels() {
  local name=$1 item=$2 pairs=$3 coarsest=$4
  local dir="$TMP/out-$name/$item" plain="$TMP/out-$name-plain/$item" pair fine coarse
  local glbs; glbs=$(ls "$dir"/*.glb | wc -l)
  set +e
  node "$gltf/validate.mjs" "$dir"/*.glb >"$TMP/$name.jsonl" 2>&1
  vrc=$?
  set -e
  check "$name: validator 0 errors on every GLB ($glbs; $(head -c 300 "$TMP/$name.jsonl"))" \
    [ "$vrc" -eq 0 -a "$(grep -c '"numErrors":0,' "$TMP/$name.jsonl")" -eq "$glbs" ]
  for pair in $pairs; do
    IFS=: read -r fine coarse <<<"$pair"
    check "$name $fine: the report says it morphs to $coarse" python3 -c "
import json, sys; r = json.load(open('$dir/report.json'))
sys.exit(0 if any(l['name'] == '$fine' and l.get('morph_to') == '$coarse' for l in r['stages']['export']['levels']) else 1)"
    bound=$(python3 -c "
import json; r = json.load(open('$dir/report.json'))
print([l for l in r['stages']['export']['levels'] if l['name'] == '$fine'][0]['glb']['quantization_bound_world'])")
    out1=$("$mc" "$dir/$coarse.ply" "$dir/$fine.glb" 1 2>&1) || true
    out0=$("$mc" "$dir/$coarse.ply" "$dir/$fine.glb" 0 2>&1) || true
    outh=$("$mc" "$dir/$coarse.ply" "$dir/$fine.glb" 0.5 2>&1) || true
    limit=$(python3 -c "
import re; m = re.search(r'diagonal (\S+)', '''$out1''')
print((1e-5 * float(m.group(1)) + $bound) / float(m.group(1)) if m else -1)")
    check "$name $fine: weight 1 on $coarse ($out1; limit $limit of the diagonal)" within "$(ratio_of "$out1")" "$limit"
    r0=$(ratio_of "$out0") rh=$(ratio_of "$outh")
    # Moving, but not half way for every vertex: the refinement's added vertices (on
    # coarser edges, at gap-path vertices, torn copies) travel to targets that are not
    # their closest points, so at 0.5 one may be further off than any vertex at 0 (the
    # cow's cluster lod100: 1.28 times). The bound says the blend stays near the surface.
    check "$name $fine: weight 0 is off $coarse ($r0), 0.5 moving ($rh)" \
      python3 -c "import sys; a, h = ${r0:-0}, ${rh:-0}; sys.exit(0 if a > 1e-3 and 0.3 * a < h < 1.5 * a else 1)"
    "$mc" "$dir/$fine.ply" "$dir/$fine.glb" 0 "$TMP/$name-$fine-w0.ply" >/dev/null
    h0=$("$SCANLOD" compare "$dir/$fine.ply" "$TMP/$name-$fine-w0.ply" --samples 50000 --json |
         python3 -c "import json, sys; print(json.load(sys.stdin)['hausdorff'])")
    limit0=$(python3 -c "
import re; m = re.search(r'diagonal (\S+)', '''$out1''')
print((1e-6 * float(m.group(1)) + $bound) / float(m.group(1)) if m else -1)")
    check "$name $fine: weight 0 is the level's surface (symmetric Hausdorff $h0, limit $limit0)" \
      within "$h0" "$limit0"
    n=$(python3 "$views" "$plain/$fine.glb" "$dir/$fine.glb") && same=0 || same=1
    check "$name $fine: the morphing GLB carries the refined mesh, not the plain level's views" \
      [ "$same" -eq 1 ]
  done
  check "$name $coarsest: the coarsest level has no target, written as without morph" \
    cmp -s "$plain/$coarsest.glb" "$dir/$coarsest.glb"
}
modes="float:none:false quantized:none:true meshopt:meshopt:true draco:draco:true"
cluster_modes="cluster-float:none:false cluster-meshopt:meshopt:true cluster-draco:draco:true"
if light; then
  # The sanitizer pass: float and Draco files (Draco's morph is stored beside its stream,
  # test_morph_render's light run relies on it here), the cluster method's in meshopt;
  # quantised and meshopt bunnies and the cluster's float and Draco files are the
  # Release pass's (the same writer paths as the files kept here).
  modes="float:none:false draco:draco:true"
  cluster_modes="cluster-meshopt:meshopt:true"
  echo "LIGHT: the quantised and meshopt bunnies and the cluster's float and Draco files are the Release pass's"
fi
for mode in $modes; do
  IFS=: read -r name comp quant <<<"$mode"
  run_mode "$name" "$comp" "$quant" true
  run_mode "$name-plain" "$comp" "$quant" false
  check_levels "$name" "$item" "lod100:lod60 lod60:lod30" lod30
done
# The cluster method's levels (its stage's level list): cow, lod100 > lod40 > thumb, with
# the paper's intermediate models beside them (their own morph: no target).
mkdir -p "$TMP/in-cluster"
cp "$SCANS/cow.ply" "$TMP/in-cluster/"
for mode in $cluster_modes; do
  IFS=: read -r name comp quant <<<"$mode"
  for morph in true false; do
    suffix=$([ "$morph" = true ] && echo "" || echo "-plain")
    write_config "$TMP/$name$suffix.ini" "$TMP/in-cluster" "$TMP/work-$name$suffix" "$TMP/out-$name$suffix" \
      "[cluster]" "intermediates = 1" "[levels]" "percents = 40,100" "budgets = thumb:1000" \
      "${paper[@]}" "[export]" \
      "formats = ply,glb" "thumbnail_size = 0" "fidelity = false" "compression = $comp" \
      "quantize = $quant" "morph = $morph"
    run_scanlod run "$TMP/$name$suffix.ini" -q -s lod.method=cluster
    check "$name$suffix: run exits 0 (got $rc: ${err:0:300})" [ "$rc" -eq 0 ]
  done
  check_levels "$name" cow.ply "lod100:lod40 lod40:thumb" thumb
  check "$name: an intermediate model has no target" \
    cmp -s "$TMP/out-$name-plain/cow.ply/lod40.morph1.glb" "$TMP/out-$name/cow.ply/lod40.morph1.glb"
done

# scanlod extract --morph-to on the published model.
model="$TMP/out-float/$item/model.slod"
run_scanlod extract "$model" --triangles 3000 -o "$TMP/level.ply"
check "extract the level: exit 0 ($err)" [ "$rc" -eq 0 ]
run_scanlod extract "$model" --triangles 1500 -o "$TMP/coarse.ply"
check "extract the coarser cut: exit 0 ($err)" [ "$rc" -eq 0 ]
run_scanlod extract "$model" --triangles 3000 --morph-to 1500 --morph-weight 0 -o "$TMP/w0.ply"
check "extract weight 0: exit 0 ($err)" [ "$rc" -eq 0 ]
check "extract weight 0 is the level byte for byte" cmp -s "$TMP/level.ply" "$TMP/w0.ply"
run_scanlod extract "$model" --triangles 3000 --morph-to 1500 -o "$TMP/w1.ply"
check "extract weight 1 (default): exit 0 ($out $err)" [ "$rc" -eq 0 ]
out1=$("$mc" "$TMP/coarse.ply" "$TMP/w1.ply")
check "extract weight 1 lies on the coarser cut ($out1)" within "$(ratio_of "$out1")" 1e-5
run_scanlod extract "$model" --triangles 3000 --morph-to 1500 --morph-weight 0.5 -o "$TMP/wh.ply"
outh=$("$mc" "$TMP/coarse.ply" "$TMP/wh.ply") out0=$("$mc" "$TMP/coarse.ply" "$TMP/level.ply")
check "extract weight 0.5 between ($(ratio_of "$outh") of $(ratio_of "$out0"))" \
  python3 -c "import sys; a, h = $(ratio_of "$out0"), $(ratio_of "$outh"); sys.exit(0 if 0.3 * a < h < 0.9 * a else 1)"
run_scanlod extract "$model" --triangles 3000 --morph-to 1500 -o "$TMP/m.glb"
outg=$("$mc" "$TMP/coarse.ply" "$TMP/m.glb" 1)
# extract writes [export]'s default GLB: meshopt, 14-bit positions, whose grid step is at
# most the diagonal / 16383: weight 1 lands within sqrt(3)/2 of a step.
check "extract GLB: weight 1 on the coarser cut ($outg)" within "$(ratio_of "$outg")" 6.3e-5
set +e
node "$gltf/validate.mjs" "$TMP/m.glb" >"$TMP/m.jsonl" 2>&1
vrc=$?
set -e
check "extract GLB: validator 0 errors ($(head -c 200 "$TMP/m.jsonl"))" [ "$vrc" -eq 0 ]
for bad in "--morph-to 3000|not fewer" "--morph-to 0|>= 1" "--morph-to 1500 --morph-weight 2|\[0, 1\]" \
           "--morph-to 1500 --morph-weight nan|finite" "--morph-weight 0.5|needs --morph-to"; do
  IFS='|' read -r args want <<<"$bad"
  # shellcheck disable=SC2086
  run_scanlod extract "$model" --triangles 3000 $args -o "$TMP/bad.ply"
  check "extract $args: exit 64 and one line naming it ($rc: $err)" \
    [ "$rc" -eq 64 -a "$(wc -l <<<"$err")" -eq 1 ]
  check "extract $args: says '$want'" contains "$want" "$err"
done
run_scanlod extract "$model" --triangles 3000 --morph-to 1500 --morph-weight 0.5 -o "$TMP/bad.glb"
check "extract --morph-weight with .glb is refused ($err)" [ "$rc" -eq 64 ]
check "no output written by a refused request" [ ! -e "$TMP/bad.ply" -a ! -e "$TMP/bad.glb" ]
finish
