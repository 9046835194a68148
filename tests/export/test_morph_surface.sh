#!/usr/bin/env bash
# The weight-1 *surface* of a morphing level lies on the coarser level (issue 13,
# docs/morphing.md "The surface at weight 1"), for every LOD method as its paper makes its
# levels: octree (bunny, bun_zipper_res3: k100 -> k60 -> k30), cluster (cow: lod100 ->
# lod40 -> thumb) and segment (fandisk: lod100 -> lod40 -> thumb); and for the default
# (best: the scan and refined levels, which are not nested: cow lod100 -> lod40 -> thumb),
# float GLBs with [export] morph = true:
#   - the GLB decoded by the tests' own reader at weight 1 (triangles and all, morph_check
#     OUT.ply) is measured against the coarser level's PLY by `scanlod compare`: the
#     area-sampled one-sided Hausdorff from it to the coarser level (b_to_a) is at most
#     1e-5 of the diagonal (vertices alone are not enough: a triangle whose corners land
#     on different coarser faces is a chord, 3 to 4 % of the diagonal without the cut);
#   - at weight 0 the GLB's surface is the level's: symmetric Hausdorff to the level's PLY
#     at most 1e-6 of the diagonal;
#   - the cut adds at most 2-4 times the level's triangles on the pairs that say so: no
#     vertex where a corner already goes, no cut where two coplanar coarser triangles
#     already hold the chord (docs/morphing.md; without them 2.96-4.9 times);
#   - at most so many torn triangles on the pairs that say so: where the splits stop,
#     corners are retargeted within the coarser surface before anything is torn (the
#     bunny's lod60 tears 72 triangles without it, 59 with);
# all with [export] morph_tears = true (weight 1 exact), and `scanlod extract --morph-to
# --morph-tears` at weight 1 (PLY): the same bound on the octree model.
# Then the default (morph_tears = false) on the bunny's published ladder, the scan morphing
# into its refined lod60: the blend comes closer at every weight (one-sided Hausdorff at
# 0.25, 0.5, 0.75 and 1 at most 1.05 times weight 0's, RMS falling at every step; with
# tears the largest distance at 0.5 is 1.7 times weight 0's) and opens no crack (the same
# boundary edges at 0.5 as at 0).
source "$(dirname "$0")/../lib.sh"
mc="${SCANLOD_BUILD_DIR:?}/tests/morph_check"
samples=200000

# b_to_a / symmetric Hausdorff (fraction of A's diagonal) of `scanlod compare A B`.
hausdorff() { # hausdorff A B b_to_a|symmetric
  "$SCANLOD" compare "$1" "$2" --samples "$samples" --json | python3 -c "
import json, sys; r = json.load(sys.stdin)
print(r['b_to_a']['hausdorff'] if '$3' == 'b_to_a' else r['hausdorff'])"
}
within() { python3 -c "import sys; sys.exit(0 if '$1' and float('$1') <= float('$2') else 1)"; }

# check_pairs NAME DIR "FINE:COARSER[:RATIO[:TORN]] ...": the checks above on one run's
# published levels; with RATIO, the morphing GLB adds at most RATIO times the level's
# triangles; with TORN, it tears at most TORN triangles.
check_pairs() {
  local name=$1 dir=$2 pair fine coarse ratio torn torn_n h1 h0
  for pair in $3; do
    IFS=: read -r fine coarse ratio torn <<<"$pair"
    "$mc" "$dir/$coarse.ply" "$dir/$fine.glb" 1 "$TMP/$name-$fine-w1.ply" >/dev/null
    "$mc" "$dir/$fine.ply" "$dir/$fine.glb" 0 "$TMP/$name-$fine-w0.ply" >/dev/null
    h1=$(hausdorff "$dir/$coarse.ply" "$TMP/$name-$fine-w1.ply" b_to_a)
    h0=$(hausdorff "$dir/$fine.ply" "$TMP/$name-$fine-w0.ply" symmetric)
    added=$(python3 -c "
import json; r = json.load(open('$dir/report.json'))
g = [l for l in r['stages']['export']['levels'] if l['name'] == '$fine'][0]['glb']
print(g['morph_added_triangles'], 'added,', g['morph_unresolved_triangles'], 'unresolved,',
      g['morph_torn_triangles'], 'torn')")
    level_tris=$(python3 -c "
import json; r = json.load(open('$dir/report.json'))
print([l for l in r['stages']['export']['levels'] if l['name'] == '$fine'][0]['triangles'])")
    echo "$name $fine -> $coarse: weight 1 one-sided Hausdorff $h1, weight 0 $h0 ($added, level $level_tris)"
    [ -z "$ratio" ] || check "$name $fine: at most $ratio x the level's $level_tris triangles added (${added%% *})" \
      python3 -c "import sys; sys.exit(0 if ${added%% *} <= $ratio * $level_tris else 1)"
    torn_n=$(echo "$added" | awk '{print $(NF-1)}')
    [ -z "$torn" ] || check "$name $fine: at most $torn torn triangles ($torn_n)" [ "$torn_n" -le "$torn" ]
    check "$name $fine: weight-1 surface on $coarse (b_to_a $h1 <= 1e-5 of the diagonal)" within "$h1" 1e-5
    check "$name $fine: weight-0 surface is the level (symmetric $h0 <= 1e-6)" within "$h0" 1e-6
  done
}

export_lines=("formats = ply,glb" "thumbnail_size = 0" "fidelity = false" "compression = none"
              "quantize = false" "morph = true" "morph_tears = true")
# Octree: the bunny's published levels, and extract on its model.
mkdir -p "$TMP/in-octree"
cp "$SCANS/bun_zipper_res3.ply" "$TMP/in-octree/"
write_config "$TMP/octree.ini" "$TMP/in-octree" "$TMP/work-octree" "$TMP/out-octree" "[lod]" \
  "method = octree" "[levels]" "percents =" "expansions = 30,60,100" "budgets =" "top = method" \
  "oversample = 1" \
  "[refine]" "collapse = false" "fit = false" "[export]" "${export_lines[@]}"
run_scanlod run "$TMP/octree.ini" -q
check "octree: run exits 0 (got $rc: ${err:0:300})" [ "$rc" -eq 0 ]
check_pairs octree "$TMP/out-octree/bun_zipper_res3.ply" "k100:k60:3 k60:k30::62"

model="$TMP/out-octree/bun_zipper_res3.ply/model.slod"
run_scanlod extract "$model" --triangles 1500 -o "$TMP/coarse.ply"
check "extract the coarser cut: exit 0 ($err)" [ "$rc" -eq 0 ]
run_scanlod extract "$model" --triangles 3000 --morph-to 1500 --morph-tears -o "$TMP/w1.ply"
check "extract weight 1: exit 0 ($err)" [ "$rc" -eq 0 ]
h=$(hausdorff "$TMP/coarse.ply" "$TMP/w1.ply" b_to_a)
echo "extract 3000 -> 1500 at weight 1: one-sided Hausdorff $h ($out)"
check "extract: weight-1 surface on the coarser cut (b_to_a $h <= 1e-5)" within "$h" 1e-5

# Cluster and segment: their stages' level lists.
for method in cluster:cow.ply segment:fandisk.ply; do
  IFS=: read -r name item <<<"$method"
  mkdir -p "$TMP/in-$name"
  cp "$SCANS/$item" "$TMP/in-$name/"
  write_config "$TMP/$name.ini" "$TMP/in-$name" "$TMP/work-$name" "$TMP/out-$name" "[levels]" \
    "percents = 40,100" "budgets = thumb:1000" "top = method" "oversample = 1" "[refine]" "collapse = false" \
    "fit = false" "[export]" "${export_lines[@]}"
  run_scanlod run "$TMP/$name.ini" -q -s lod.method="$name"
  check "$name: run exits 0 (got $rc: ${err:0:300})" [ "$rc" -eq 0 ]
  ratios=(2.5 2.5); [ "$name" = cluster ] || ratios=(2 4)
  check_pairs "$name" "$TMP/out-$name/$item" "lod100:lod40:${ratios[0]} lod40:thumb:${ratios[1]}"
done
# The default: the scan at the top, the rest collapsed and fitted (not nested in it).
mkdir -p "$TMP/in-best"
cp "$SCANS/cow.ply" "$TMP/in-best/"
write_config "$TMP/best.ini" "$TMP/in-best" "$TMP/work-best" "$TMP/out-best" "[levels]" \
  "percents = 40,100" "budgets = thumb:1000" "[export]" "${export_lines[@]}"
run_scanlod run "$TMP/best.ini" -q
check "best: run exits 0 (got $rc: ${err:0:300})" [ "$rc" -eq 0 ]
check_pairs best "$TMP/out-best/cow.ply" "lod100:lod40: lod40:thumb:"

# The default morph: whole triangles, every vertex travelling no farther than the level is
# from the coarser one.
mkdir -p "$TMP/in-blend"
cp "$SCANS/bun_zipper_res3.ply" "$TMP/in-blend/"
blend_lines=("${export_lines[@]}")
unset 'blend_lines[${#blend_lines[@]}-1]' # morph_tears: the default
write_config "$TMP/blend.ini" "$TMP/in-blend" "$TMP/work-blend" "$TMP/out-blend" "[levels]" \
  "percents = 60,100" "budgets =" "[export]" "${blend_lines[@]}"
run_scanlod run "$TMP/blend.ini" -q
check "blend: run exits 0 (got $rc: ${err:0:300})" [ "$rc" -eq 0 ]
dir="$TMP/out-blend/bun_zipper_res3.ply"
for w in 0 0.25 0.5 0.75 1; do
  "$mc" "$dir/lod60.ply" "$dir/lod100.glb" "$w" "$TMP/blend-$w.ply" >/dev/null
  "$SCANLOD" compare "$dir/lod60.ply" "$TMP/blend-$w.ply" --samples "$samples" --json |
    python3 -c "
import json, sys; r = json.load(sys.stdin)
print('$w', r['b_to_a']['hausdorff'], r['b_to_a']['rms'], r['b_topology']['boundary_edges'])"
done >"$TMP/blend.txt"
echo "blend lod100 -> lod60 (weight, Hausdorff, RMS, boundary edges):"; cat "$TMP/blend.txt"
check "blend: every weight within 1.05 x weight 0's Hausdorff ($(tr '\n' ' ' <"$TMP/blend.txt"))" python3 -c "
rows = [l.split() for l in open('$TMP/blend.txt')]
h0 = float(rows[0][1]); import sys
sys.exit(0 if len(rows) == 5 and h0 > 0 and all(float(r[1]) <= 1.05 * h0 for r in rows[1:]) else 1)"
check "blend: the RMS falls at every step" python3 -c "
rows = [float(l.split()[2]) for l in open('$TMP/blend.txt')]; import sys
sys.exit(0 if len(rows) == 5 and all(b < a for a, b in zip(rows, rows[1:])) else 1)"
check "blend: no crack opens (boundary edges at 0.5 as at 0)" python3 -c "
rows = {l.split()[0]: l.split()[3] for l in open('$TMP/blend.txt')}; import sys
sys.exit(0 if rows.get('0') is not None and rows.get('0') == rows.get('0.5') else 1)"
finish
