#!/usr/bin/env bash
# SCANLOD_BEFORE=OLD/scanlod scripts/bench/bench_morph_surface.sh (docs/morphing.md):
# per LOD method and bundled scan, levels 30/60/100 % with [export] morph = true (float
# GLBs): the triangles the morph refinement adds, the triangles it tears and the widest
# tear (fraction of the coarser diagonal), and the area-sampled one-sided Hausdorff from
# the GLB at weight 1 to the coarser level before (SCANLOD_BEFORE: a build without the
# refinement, e.g. commit 6b995e5) and after (this build), and the export stage's wall
# seconds of both runs (timings.json; one run each, `nice -n 15`: quote them from a quiet
# machine, as ratios).
set -u
root=$(cd "$(dirname "$0")/../.." && pwd)
NEW=${SCANLOD:-$root/build/cli/scanlod}; OLD=${SCANLOD_BEFORE:?SCANLOD_BEFORE: a scanlod without the refinement (e.g. main before issue 13 part 3b)}
MC=${MORPH_CHECK:-$root/build/tests/morph_check}; SC=$root/tests/data/scans
W=$(mktemp -d)
trap 'rm -rf "$W"' EXIT
h() { nice -n 15 $NEW compare "$1" "$2" --samples 200000 --json | python3 -c "import json,sys; r=json.load(sys.stdin); print('%.3g' % r['b_to_a']['hausdorff'])"; }
printf "method scan level->coarser level_tris glb_tris added torn tear/diag unresolved H1_before H1_after export_s_before export_s_after\n"
for method in octree cluster segment; do
  for scan in bun_zipper_res3 fandisk cow; do
    for which in new old; do
      bin=$NEW; [ $which = old ] && bin=$OLD
      rm -rf $W/in $W/work-$which $W/out-$which; mkdir -p $W/in; cp $SC/$scan.ply $W/in/
      cat > $W/$which.ini <<INI
[run]
input = $W/in
work = $W/work-$which
output = $W/out-$which
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
      nice -n 15 $bin run $W/$which.ini -q -s lod.method=$method >/dev/null 2>$W/err-$which || { echo "$method $scan $which failed: $(head -c 200 $W/err-$which)"; continue 2; }
    done
    d=$W/out-new/$scan.ply; o=$W/out-old/$scan.ply
    # the export stage's wall seconds (it makes every level's GLB, the refinement included)
    secs() { python3 -c "import json,sys; print('%.2f' % json.load(open(sys.argv[1]))['stages']['export']['seconds'])" "$1/timings.json"; }
    t_old=$(secs $o) t_new=$(secs $d)
    python3 - "$d/report.json" > $W/pairs <<'PY'
import json, sys
r = json.load(open(sys.argv[1])); L = r['stages']['export']['levels']
diag = None
for l in L:
    g = l.get('glb', {})
    if l.get('morph_to'):
        print(l['name'], l['morph_to'], l['triangles'], g['triangles'], g['morph_added_triangles'], g['morph_torn_triangles'], g['morph_tear_world'], g['morph_unresolved_triangles'])
PY
    while read -r fine coarse lt gt added torn tear unres; do
      $MC $d/$coarse.ply $d/$fine.glb 1 $W/w1-new.ply >/dev/null
      $MC $o/$coarse.ply $o/$fine.glb 1 $W/w1-old.ply >/dev/null
      diag=$(nice $NEW compare $d/$coarse.ply $d/$coarse.ply --samples 10 --json | python3 -c "import json,sys; print(json.load(sys.stdin)['diagonal'])")
      printf "%s %s %s->%s %s %s %s %s %.3g %s %s %s %s %s\n" $method $scan $fine $coarse $lt $gt $added $torn $(python3 -c "print($tear/$diag)") $unres $(h $o/$coarse.ply $W/w1-old.ply) $(h $d/$coarse.ply $W/w1-new.ply) $t_old $t_new
    done < $W/pairs
  done
done
