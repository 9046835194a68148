#!/usr/bin/env bash
# Every published item's scene.svx.json follows Smithsonian Voyager's scene format (its
# fields, types and enums as Voyager's sources define them, restated in check_svx.py),
# names one GLB per quality Thumb..Highest, and its byteSize and numFaces are those of the
# files (and of the report). Broken copies of a manifest must each be refused, so the
# check is not a no-op.
source "$(dirname "$0")/../lib.sh"
check_svx="$SCANLOD_SOURCE_DIR/tests/export/check_svx.py"

mkdir -p "$TMP/in/sub"
cp "$SCANS/cow.ply" "$SCANS/bun_zipper_res3.ply" "$TMP/in/"
cp "$SCANS/fandisk.ply" "$TMP/in/sub/"
write_config "$TMP/c.ini" "$TMP/in" "$TMP/work" "$TMP/out" "[export]" \
  "budgets = thumb:1000,low:5000,medium:100000,high:500000" \
  "thumbnail_size = 0" "fidelity = false" "viewer = false"
run_scanlod run "$TMP/c.ini" -q
check "run exits 0 (got $rc: $err)" [ "$rc" -eq 0 ]
items=("$TMP/out/cow.ply" "$TMP/out/bun_zipper_res3.ply" "$TMP/out/sub/fandisk.ply")

set +e
python3 "$check_svx" "${items[@]}" >"$TMP/svx.out" 2>&1
src=$?
set -e
cat "$TMP/svx.out"
check "check_svx: every manifest valid and true to its files" [ "$src" -eq 0 ]

# Without GLBs there is nothing for Voyager: no manifest, and the report says none.
write_config "$TMP/p.ini" "$TMP/in" "$TMP/work-ply" "$TMP/out-ply" "[export]" \
  "lod_percents = 50" "budgets =" "formats = ply" "thumbnail_size = 0" "fidelity = false"
run_scanlod run "$TMP/p.ini" -q
check "PLY-only run exits 0 (got $rc)" [ "$rc" -eq 0 ]
check "PLY only: no scene.svx.json" [ ! -e "$TMP/out-ply/cow.ply/scene.svx.json" ]
check "PLY only: no manifest in the report" python3 -c "import json,sys; \
  sys.exit('manifest' in json.load(open('$TMP/out-ply/cow.ply/report.json'))['stages']['export'])"

# Broken manifests: each edit of a copy must make check_svx fail, naming the fault.
broken() { # broken NAME EXPECTED-MESSAGE PYTHON-EDIT-OF-d
  local dir="$TMP/broken/$1"
  mkdir -p "$TMP/broken"
  cp -r "$TMP/out/cow.ply" "$dir"
  python3 - "$dir/scene.svx.json" "$3" <<'EOF'
import json, sys
d = json.load(open(sys.argv[1]))
exec(sys.argv[2])
json.dump(d, open(sys.argv[1], "w"), indent=2)
EOF
  set +e
  python3 "$check_svx" "$dir" >"$dir.out" 2>&1
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
finish
