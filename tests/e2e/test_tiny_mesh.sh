#!/usr/bin/env bash
# A closed mesh of a few large triangles (issue 16, item 5): the regular octahedron of
# tests/data/octahedron.ply has vertices sqrt(2) apart, so 1.5 x the spacing alone would
# give a leaf (2.12) wider than the shape, every sample outside it, and an item published
# as a success with 0 triangles at every level. The automatic leaf is bounded by the
# bounding box's diagonal / 16 (docs/samples-stage.md, "The grid"): the octahedron gives
# a closed, non-empty surface. A leaf still too coarse (forced by the config) gives no
# triangle: the item is quarantined with the reason, never published.
source "$(dirname "$0")/../lib.sh"
mesh="$SCANLOD_SOURCE_DIR/tests/data/octahedron.ply"
mkdir -p "$TMP/in"
cp "$mesh" "$TMP/in/"
# Paper 1's own cuts (the octree's leaf is what this is about): k20 and k100.
levels=("[lod]" "method = octree" "[levels]" "percents =" "expansions = 20,100" "budgets ="
        "top = method" "oversample = 1" "[refine]" "collapse = false" "fit = false" "[export]" "formats = ply"
        "thumbnail_size = 0" "fidelity = false")

write_config "$TMP/c.ini" "$TMP/in" "$TMP/work" "$TMP/out" "${levels[@]}"
run_scanlod run "$TMP/c.ini" -q
check "octahedron: run exits 0 (got $rc: $err)" [ "$rc" -eq 0 ]
leaf=$(python3 -c "import json; print(json.load(open('$TMP/work/artifacts/samples/octahedron.ply/report.json'))['leaf_size'])")
check "automatic leaf ($leaf) at most the diagonal / 16 (2 sqrt(3) / 16)" \
  python3 -c "import math,sys; sys.exit(0 if $leaf <= 2 * math.sqrt(3) / 16 * (1 + 1e-9) else 1)"
finest=$(python3 -c "import json; print(json.load(open('$TMP/out/octahedron.ply/report.json'))['stages']['export']['triangles_finest'])" 2>/dev/null || echo 0)
check "octahedron: the finest level has triangles ($finest)" [ "$finest" -gt 0 ]
check "octahedron: k20 and k100 published" [ -s "$TMP/out/octahedron.ply/k20.ply" -a -s "$TMP/out/octahedron.ply/k100.ply" ]
set +e
cmp_out=$("$SCANLOD" compare "$mesh" "$TMP/out/octahedron.ply/k100.ply" --samples 20000 2>&1)
set -e
check "octahedron: finest level watertight ($cmp_out)" grep -qx "B watertight: yes" <<<"$cmp_out"
check "octahedron: no boundary or non-manifold edge" grep -q "^B edges: 0 boundary, 0 non-manifold" <<<"$cmp_out"

# A leaf larger than the shape: every sample outside, no triangle at the finest level.
write_config "$TMP/coarse.ini" "$TMP/in" "$TMP/work2" "$TMP/out2" "${levels[@]}"
run_scanlod run "$TMP/coarse.ini" -s octree.leaf_size=3
check "leaf 3: exit 65 (got $rc)" [ "$rc" -eq 65 ]
check "leaf 3: quarantined with the reason ($err)" \
  contains "\[merge\] octahedron.ply: quarantined: $TMP/in/octahedron.ply: the surface produced no triangles at leaf size 3: " "$err"
check "leaf 3: nothing published" [ ! -e "$TMP/out2/octahedron.ply" ]
run_scanlod status "$TMP/coarse.ini" -s octree.leaf_size=3
check "leaf 3: status lists the quarantine ($out)" grep -q "quarantine (badinput).*no triangles" <<<"$out"
run_scanlod run "$TMP/coarse.ini" -q -s octree.leaf_size=3
check "leaf 3: not retried, exit 65 ($rc: $out)" [ "$rc" -eq 65 ]
check "leaf 3: nothing to do on the rerun" grep -q "^nothing to do" <<<"$out"
finish
