#!/usr/bin/env bash
# Every cut of a quadric-vertex model ([octree] vertices = qef, the dual drawing of
# runtime/lod_dual.h) of a closed scan is watertight: cow at every expansion count (2930),
# every edge in exactly two triangles, the accumulation table equal to what is generated,
# the level rule (tests/e2e/lod_check.c). cow has cuts where a transition cell's loop runs
# along a split edge (its midpoint inside, its corners outside, its other face split: the
# two halves joined on a whole face) and crosses that face once more: the same-level
# neighbour across it draws the same two segments, and before sl_mc_split_double_passes
# split such a loop, 29 of the 2930 cuts had an edge of four triangles (docs/lod.md,
# "Vertices from quadrics").
# SCANLOD_LIGHT=1 (the sanitizer pass): 300 spread K, which still meet 3 of those cuts.
source "$(dirname "$0")/../lib.sh"
samples=0
if light; then
  samples=300
  echo "LIGHT: cow at 300 spread K; every K in the Release pass"
fi
mkdir -p "$TMP/in"
cp "$SCANS/cow.ply" "$TMP/in/"
write_config "$TMP/c.ini" "$TMP/in" "$TMP/work" "$TMP/out"
run_scanlod run "$TMP/c.ini" -q -s octree.vertices=qef
check "qef run exits 0 (rc $rc: $err)" [ "$rc" -eq 0 ]
vertices=$(python3 -c "import json; print(json.load(open('$TMP/out/cow.ply/report.json'))['stages']['merge']['vertices'])")
check "the model has quadric vertices (report: $vertices)" [ "$vertices" = qef ]
check "cow, qef: ${samples/#0/every} K: level rule, accumulation = generated, watertight" \
  "${SCANLOD_BUILD_DIR:?}/tests/lod_check" "$TMP/out/cow.ply/model.slod" "$samples" --closed
finish
