#!/usr/bin/env bash
# Every published item's scene.svx.json follows Smithsonian Voyager's scene format (its
# fields, types and enums as Voyager's sources define them, restated in check_svx.py),
# names one GLB per quality Thumb..Highest, and its byteSize and numFaces are those of the
# files (and of the report), carries the collection manifest's row in its meta (title,
# description, accession, credit, licence; credit and licence also as the copyright) and
# the finest level's thumbnail as its image and an Image2D derivative. Broken copies of a
# manifest must each be refused, so the check is not a no-op.
source "$(dirname "$0")/../lib.sh"
check_svx="$SCANLOD_SOURCE_DIR/tests/export/check_svx.py"

mkdir -p "$TMP/in/sub"
cp "$SCANS/cow.ply" "$SCANS/bun_zipper_res3.ply" "$TMP/in/"
cp "$SCANS/fandisk.ply" "$TMP/in/sub/"
# fandisk has no row: its title is its id, its collection record has no credit.
cat >"$TMP/in/manifest.csv" <<'EOF'
file,title,accession,credit,licence,description
cow.ply,"Cow, ""the"" classic",1999.4.17,Viewpoint Animation Engineering,CC0 1.0,"A test model.
Made of 5804 triangles."
bun_zipper_res3.ply,Stanford bunny,,Stanford Computer Graphics Laboratory,,
EOF
write_config "$TMP/c.ini" "$TMP/in" "$TMP/work" "$TMP/out" "[levels]" \
  "budgets = thumb:1000,low:5000,medium:100000,high:500000" "[export]" \
  "thumbnail_size = 64" "fidelity = false" "viewer = false"
run_scanlod run "$TMP/c.ini" -q
check "run exits 0 (got $rc: $err)" [ "$rc" -eq 0 ]
items=("$TMP/out/cow.ply" "$TMP/out/bun_zipper_res3.ply" "$TMP/out/sub/fandisk.ply")

set +e
python3 "$check_svx" --manifest "$TMP/in/manifest.csv" "${items[@]}" >"$TMP/svx.out" 2>&1
src=$?
set -e
cat "$TMP/svx.out"
check "check_svx: every manifest valid and true to its files and the manifest" [ "$src" -eq 0 ]
meta() { # meta ITEM PYTHON-EXPRESSION-ON-d (the scene document)
  python3 -c "import json,sys; d=json.load(open(sys.argv[1])); print($2)" "$TMP/out/$1/scene.svx.json"
}
check "cow: the title with its quotes" [ "$(meta cow.ply "d['metas'][0]['collection']['titles']['EN']")" = 'Cow, "the" classic' ]
check "cow: the description as the intro, both lines" \
  [ "$(meta cow.ply "repr(d['metas'][0]['collection']['intros']['EN'])")" = "'A test model.\\nMade of 5804 triangles.'" ]
check "cow: credit; licence as the copyright" \
  [ "$(meta cow.ply "d['asset']['copyright']")" = "Viewpoint Animation Engineering; CC0 1.0" ]
check "fandisk (no row): its id as the title, no copyright" \
  [ "$(meta sub/fandisk.ply "d['metas'][0]['collection']['titles']['EN'], 'copyright' in d['asset']")" = "sub/fandisk.ply False" ]

# Without GLBs there is nothing for Voyager: no manifest, and the report says none.
write_config "$TMP/p.ini" "$TMP/in" "$TMP/work-ply" "$TMP/out-ply" "[levels]" \
  "percents = 50" "budgets =" "[export]" "formats = ply" "thumbnail_size = 0" "fidelity = false"
run_scanlod run "$TMP/p.ini" -q
check "PLY-only run exits 0 (got $rc)" [ "$rc" -eq 0 ]
check "PLY only: no scene.svx.json" [ ! -e "$TMP/out-ply/cow.ply/scene.svx.json" ]
check "PLY only: no manifest in the report" python3 -c "import json,sys; \
  sys.exit('manifest' in json.load(open('$TMP/out-ply/cow.ply/report.json'))['stages']['export'])"

# Broken manifests: each edit of a copy must make check_svx fail, naming the fault.
broken() { # broken NAME EXPECTED-MESSAGE PYTHON-EDIT-OF-d
  local dir="$TMP/broken/$1/cow.ply" # the item's name: its manifest row is checked too
  mkdir -p "$TMP/broken/$1"
  cp -r "$TMP/out/cow.ply" "$dir"
  python3 - "$dir/scene.svx.json" "$3" <<'EOF'
import json, sys
d = json.load(open(sys.argv[1]))
exec(sys.argv[2])
json.dump(d, open(sys.argv[1], "w"), indent=2)
EOF
  set +e
  python3 "$check_svx" --manifest "$TMP/in/manifest.csv" "$dir" >"$dir.out" 2>&1
  local brc=$?
  set -e
  check "broken manifest ($1): refused" [ "$brc" -eq 1 ]
  check "broken manifest ($1): says '$2'" grep -qF -- "$2" "$dir.out"
}
a='d["models"][0]["derivatives"][0]["assets"][0]'
broken byte-size "byteSize" "$a[\"byteSize\"] += 1"
broken num-faces "numFaces" "$a[\"numFaces\"] -= 3"
broken zero-faces "numFaces is an integer >= 1" "$a[\"numFaces\"] = 0"
broken quality "quality is one of Voyager's ('Ultra')" 'd["models"][0]["derivatives"][1]["quality"] = "Ultra"'
broken usage "usage is one of Voyager's ('Web')" 'd["models"][0]["derivatives"][1]["usage"] = "Web"'
broken units "units is a unit (None)" 'del d["models"][0]["units"]'
broken inherit "units is a unit ('inherit')" 'd["models"][0]["units"] = "inherit"'
broken extra-key "only Voyager's top-level keys" 'd["derivatives"] = []'
broken model-key "only a model's keys" 'd["models"][0]["numFaces"] = 1'
broken doc-type "asset.type is" 'd["asset"]["type"] = "application/json"'
broken no-scenes "has scenes" 'del d["scenes"]'
broken asset-type "type is one of Voyager's ('Mesh')" "$a[\"type\"] = \"Mesh\""
broken missing-file "is a file of the item's folder" "$a[\"uri\"] = \"nothing.glb\""
broken outside "is a file of the item's folder" "$a[\"uri\"] = \"../cow.ply/thumb.glb\""
broken lost-quality "one Web3D derivative per quality" 'del d["models"][0]["derivatives"][4]'
broken twice "one Web3D derivative per quality" \
  'd["models"][0]["derivatives"].append(d["models"][0]["derivatives"][2])'
broken node-model "nodes[0].model indexes models" 'd["nodes"][0]["model"] = 3'
m='d["metas"][0]'
broken meta-key "only a meta's keys" "$m[\"title\"] = \"Cow\""
broken scene-meta "scenes[0].meta indexes metas" 'd["scenes"][0]["meta"] = 2'
broken no-scene-meta "the scene has a meta" 'del d["scenes"][0]["meta"]'
broken image-quality "quality is an image quality ('Highest')" "$m[\"images\"][0][\"quality\"] = \"Highest\""
broken image-bytes "image byteSize" "$m[\"images\"][0][\"byteSize\"] += 1"
broken image-width "integer >= 1 (0)" "$m[\"images\"][0][\"width\"] = 0"
broken image-level "the finest level's thumbnail" "$m[\"images\"][0][\"uri\"] = \"thumb.png\""
broken image-derivative "the Image2D derivative names that image" \
  'd["models"][0]["derivatives"][5]["assets"][0]["imageSize"] = 32'
broken title "is the report's title" "$m[\"collection\"][\"titles\"][\"EN\"] = \"Horse\""
broken accession "collection accession" "$m[\"collection\"][\"accession\"] = \"1999.4.18\""
broken copyright "asset.copyright names the licence" 'd["asset"]["copyright"] = "Viewpoint Animation Engineering"'
broken article "an article with an id" "$m[\"articles\"] = [{\"uri\": \"index.html\"}]"
finish
