#!/usr/bin/env bash
# scripts/bench/bench_morph_blend.sh [-s KEY=VALUE ...] (docs/morphing.md, "The blend"):
# how far a morphing GLB lies from the level it morphs to while a viewer blends it. Per LOD
# method (the papers' own levels: octree, cluster, segment; and the default, best) and
# bundled scan (bun_zipper_res3, fandisk, cow), levels 30/60/100 % with [export] morph =
# true (float GLBs); for every level with a target, the GLB decoded by the tests' reader at
# weights 0, 0.5 and 1 (tests/export/morph_check) and measured against the coarser level's
# PLY: the largest vertex distance and the area-sampled one-sided Hausdorff (100,000
# samples, `scanlod compare`), both as fractions of the coarser level's diagonal. Extra
# arguments go to every `scanlod run` (e.g. -s export.morph_tears=true).
# Prints: method scan fine->coarser level_tris glb_tris torn unresolved | V0 H0 | V.5 H.5 | V1 H1
set -u
root=$(cd "$(dirname "$0")/../.." && pwd)
S=${SCANLOD:-$root/build/cli/scanlod}; MC=${MORPH_CHECK:-$root/build/tests/morph_check}
SC=$root/tests/data/scans
W=$(mktemp -d)
trap 'rm -rf "$W"' EXIT
printf "method scan level->coarser level_tris glb_tris torn unresolved | vertex_max,hausdorff at 0 | at 0.5 | at 1\n"
for method in octree cluster segment best; do
  for scan in bun_zipper_res3 fandisk cow; do
    rm -rf "$W/in" "$W/work" "$W/out"; mkdir -p "$W/in"; cp "$SC/$scan.ply" "$W/in/"
    cat > "$W/c.ini" <<INI
[run]
input = $W/in
work = $W/work
output = $W/out
logs = $W/logs
[levels]
percents = 30,60,100
budgets =
[export]
formats = ply,glb
thumbnail_size = 0
fidelity = false
compression = none
quantize = false
morph = true
INI
    paper=(); [ $method != best ] && paper=(-s lod.method=$method -s levels.top=method -s levels.oversample=1
                                           -s refine.collapse=false -s refine.fit=false)
    "$S" run "$W/c.ini" -q "${paper[@]}" "$@" >/dev/null 2>"$W/err" ||
      { echo "$method $scan failed: $(head -c 300 "$W/err")"; continue; }
    d=$W/out/$scan.ply
    python3 - "$d/report.json" > "$W/pairs" <<'PY'
import json, sys
for l in json.load(open(sys.argv[1]))['stages']['export']['levels']:
    g = l.get('glb', {})
    if l.get('morph_to'):
        print(l['name'], l['morph_to'], l['triangles'], g['triangles'], g['morph_torn_triangles'],
              g['morph_unresolved_triangles'])
PY
    while read -r fine coarse lt gt torn unres; do
      line="$method $scan $fine->$coarse $lt $gt $torn $unres"
      for w in 0 0.5 1; do
        v=$("$MC" "$d/$coarse.ply" "$d/$fine.glb" $w "$W/w.ply" | awk '/^vertices/{print $8}')
        h=$("$S" compare "$d/$coarse.ply" "$W/w.ply" --samples 100000 --json |
            python3 -c "import json,sys; print('%.3g' % json.load(sys.stdin)['b_to_a']['hausdorff'])")
        line="$line | $v $h"
      done
      echo "$line"
    done < "$W/pairs"
  done
done
