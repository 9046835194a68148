#!/usr/bin/env bash
# A collection with one scan in every format scanlod reads (issue 37): the bundled sphere
# of tests/data/inputs as PLY, OBJ + MTL + PNG, binary and ascii STL, STCNOFF, XYZ, PTS,
# glTF + BIN + PNG and GLB (texture embedded), plus the files that come with scans (an
# MTL, a BIN, a PNG, a README.txt), converts in one `scanlod run`: every scan is an item
# under its full file name and is published, the files beside them are not items, the
# range stage's report names each format, the textured ones are coloured from their
# texture (a file, or the GLB's own image), `plan` costs every item from its header,
# and a missing texture is a warning in the report, not a failure.
source "$(dirname "$0")/../lib.sh"
inputs="$SCANLOD_SOURCE_DIR/tests/data/inputs"
mkdir -p "$TMP/in/obj" "$TMP/in/gltf"
cp "$inputs/sphere.ply" "$inputs/sphere.stl" "$inputs/cube_ascii.stl" "$inputs/sphere.off" \
   "$inputs/sphere.xyz" "$inputs/sphere.pts" "$inputs/sphere.glb" "$inputs/sphere.png" "$TMP/in/"
cp "$inputs/sphere.obj" "$inputs/sphere.mtl" "$inputs/sphere.png" "$TMP/in/obj/"
cp "$inputs/sphere.gltf" "$inputs/sphere.bin" "$inputs/sphere.png" "$TMP/in/gltf/"
echo "notes about the scans" >"$TMP/in/README.txt"
items=(sphere.ply sphere.stl cube_ascii.stl sphere.off sphere.xyz sphere.pts sphere.glb
       obj/sphere.obj gltf/sphere.gltf)
# The lightest settings that publish levels: octree only, no collapse or fit.
light=(-s lod.method=octree -s refine.collapse=false -s refine.fit=false -s levels.oversample=1)
write_config "$TMP/c.ini" "$TMP/in" "$TMP/work" "$TMP/out"

run_scanlod plan "$TMP/c.ini" "${light[@]}" --json
check "plan: exit 0 ($rc: $err)" [ "$rc" -eq 0 ]
check "plan: every scan costed, nothing else" python3 - "$out" "${items[@]}" <<'EOF'
import json, sys
plan = json.loads(sys.argv[1])
rows = plan["items"] if isinstance(plan, dict) else plan
got = {r["item"]: r for r in rows}
want = set(sys.argv[2:])
assert set(got) == want, (sorted(got), sorted(want))
assert all("error" not in r for r in rows), [r for r in rows if "error" in r]
assert got["sphere.ply"]["triangles"] == 80 and got["gltf/sphere.gltf"]["triangles"] == 80
assert got["sphere.xyz"]["vertices"] == 42, got["sphere.xyz"]
EOF

run_scanlod run "$TMP/c.ini" "${light[@]}" -q
check "run: exit 0 ($rc: $err)" [ "$rc" -eq 0 ]
check "run: ${#items[@]} items published ($out)" \
  grep -q "^${#items[@]} items: .* ${#items[@]} published" <<<"$out"
for item in "${items[@]}"; do
  check "$item: published" [ -s "$TMP/out/$item/report.json" ]
  # 6 triangles are half the 12-facet cube: below what the octree's coarsest cut holds
  [ "$item" = cube_ascii.stl ] || check "$item: with its level" [ -s "$TMP/out/$item/lod50.ply" ]
done
check "the files beside the scans are no items" \
  bash -c "! ls '$TMP/out' | grep -Eq '^(README|sphere\.(png|mtl|bin))'"
check "range reports: each format, the textures sampled" python3 - "$TMP/out" <<'EOF'
import json, sys
out = sys.argv[1]
want = {"sphere.ply": ("ply", "vertex"), "sphere.stl": ("stl", "none"),
        "cube_ascii.stl": ("stl", "none"), "sphere.off": ("off", "vertex"),
        "sphere.xyz": ("xyz", "vertex"), "sphere.pts": ("pts", "vertex"),
        "sphere.glb": ("glb", "vertex"), "obj/sphere.obj": ("obj", "vertex"),
        "gltf/sphere.gltf": ("gltf", "vertex")}
for item, (fmt, colors) in want.items():
    r = json.load(open(f"{out}/{item}/report.json"))["stages"]["range"]
    assert r["input_format"] == fmt, (item, r["input_format"])
    assert r["color_source"] == colors, (item, r["color_source"])
    assert r["input_warnings"] == 0, (item, r["input_warning"])
EOF

# Without vertex colours the texture colours the points: the OBJ's file, the GLB's image.
mkdir -p "$TMP/tex/obj"
sed -e '/^v /s/^\(v [^ ]* [^ ]* [^ ]*\) .*/\1/' "$inputs/sphere.obj" >"$TMP/tex/obj/sphere.obj"
cp "$inputs/sphere.mtl" "$inputs/sphere.png" "$TMP/tex/obj/"
sed -e 's/"COLOR_0": *3/"TEXCOORD_1": 3/' "$inputs/sphere.gltf" >"$TMP/tex/untinted.gltf"
cp "$inputs/sphere.bin" "$inputs/sphere.png" "$TMP/tex/"
sed -e 's/^map_Kd .*/map_Kd gone.jpg/' "$inputs/sphere.mtl" >"$TMP/tex/gone.mtl"
sed -e 's/^mtllib .*/mtllib gone.mtl/' -e '/^v /s/^\(v [^ ]* [^ ]* [^ ]*\) .*/\1/' \
  "$inputs/sphere.obj" >"$TMP/tex/gone.obj"
write_config "$TMP/t.ini" "$TMP/tex" "$TMP/twork" "$TMP/tout"
run_scanlod run "$TMP/t.ini" "${light[@]}" -q
check "textured run: exit 0 ($rc: $err)" [ "$rc" -eq 0 ]
check "texture colours; a missing texture is a warning" python3 - "$TMP/tout" <<'EOF'
import json, sys
out = sys.argv[1]
for item in ("obj/sphere.obj", "untinted.gltf"):
    r = json.load(open(f"{out}/{item}/report.json"))["stages"]["range"]
    assert r["color_source"] == "texture" and r["colors_unsampled"] == 0, (item, r)
r = json.load(open(f"{out}/gone.obj/report.json"))["stages"]["range"]
assert r["input_warnings"] == 1 and r["input_warning"] == "gone.jpg: missing", r
assert r["color_source"] == "none" and r["texture_warnings"] == 1, r
EOF
finish
