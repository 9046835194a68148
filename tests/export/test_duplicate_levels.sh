#!/usr/bin/env bash
# Levels that come out identical are published once (issue 15, item 7): budgets above the
# finest level (low, medium, high, highest here, on a scan whose finest level has ~3,900
# triangles) give the same mesh as k100 (paper 1's cut after 100 % of the LOD array, in
# the paper's mode: [levels] expansions, top = method, no collapse or fit), so they get no
# files of their own; the report and the manifest say which levels and Voyager qualities
# share k100's files. Also: no
# two published files of the item are byte-identical, every level's facts stay in the
# report, and a rerun is a no-op with the same bytes. Paper 1's vertices ([octree]
# vertices = mc): their last expansions leave the surface as it is, so k100 stops before
# the end of the LOD array and the clamped budgets do not, and the dedup must compare
# meshes (with the default qef vertices every expansion moves a vertex: one k for all).
# The finest level is above the input's count here, so the cap is off (test_cap.sh).
source "$(dirname "$0")/../lib.sh"

mkdir -p "$TMP/in"
cp "$SCANS/bun_zipper_res3.ply" "$TMP/in/"
write_config "$TMP/c.ini" "$TMP/in" "$TMP/work" "$TMP/out" "[lod]" "method = octree" "[levels]" \
  "budgets = thumb:1000,low:20000,medium:100000,high:500000,highest:2000000" "percents =" \
  "expansions = 20,40,60,80,100" "top = method" "oversample = 1" "[refine]" "collapse = false" "fit = false" \
  "cap_at_input = false" "[export]" "thumbnail_size = 64" "fidelity = false" "[octree]" \
  "vertices = mc"
run_scanlod run "$TMP/c.ini" -q
check "run exits 0 (got $rc: $err)" [ "$rc" -eq 0 ]
item="$TMP/out/bun_zipper_res3.ply"

set +e
python3 - "$item" <<'EOF'
import hashlib, json, os, sys
folder = sys.argv[1]
r = json.load(open(os.path.join(folder, "report.json")))["stages"]["export"]
bad = 0
def check(ok, what):
    global bad
    if not ok:
        bad += 1
        print("FAIL: " + what, file=sys.stderr)
levels = {lv["name"]: lv for lv in r["levels"]}
finest = r["triangles_finest"]
shared = ["low", "medium", "high", "highest"]
check(levels["k100"]["file"] == "k100", "k100 has its own files")
for name in shared:
    lv = levels[name]
    check(lv["clamped"] and lv["triangles"] == finest, f"{name}: clamped at the finest level ({lv['triangles']})")
    check(lv["file"] == "k100", f"{name}: published as k100's files (file = {lv['file']!r})")
    for ext in ("ply", "glb", "png", "glb.js"):
        check(not os.path.exists(os.path.join(folder, f"{name}.{ext}")), f"{name}.{ext} is not published")
    check(all(lv[k] == levels["k100"][k] for k in ("triangles", "vertices", "watertight", "boundary_edges")),
          f"{name}: the report keeps its facts (those of k100)")
# The dedup compares meshes, not expansion counts: k100 stops at the last expansion that
# changes the surface, the clamped budgets run to the end of the LOD array.
check(levels["k100"]["expansions"] != levels["medium"]["expansions"],
      "k100 and medium have different k but one mesh")
files = {f["name"]: f for f in r["files"]}
check(sorted(files) == sorted(["k20", "k40", "k60", "k80", "k100", "thumb"]),
      f"one file entry per distinct mesh ({sorted(files)})")
check(files["k100"]["levels"] == ["k100"] + shared, f"k100's entry lists its levels {files['k100']['levels']}")
check(files["k100"]["qualities"] == ["Low", "Medium", "High", "Highest"],
      f"k100 serves Low..Highest ({files['k100']['qualities']})")
check(files["thumb"]["qualities"] == ["Thumb"], "thumb serves Thumb")
man = {d["quality"]: d for d in r["manifest"]["derivatives"]}
check(all(man[q]["uri"] == "k100.glb" for q in ("Low", "Medium", "High", "Highest")),
      "the manifest gives Low..Highest k100.glb")
svx = json.load(open(os.path.join(folder, "scene.svx.json")))
uris = [d["assets"][0]["uri"] for d in svx["models"][0]["derivatives"]]
check(uris == ["thumb.glb"] + ["k100.glb"] * 4 + ["k100.png"], f"scene.svx.json: {uris} (the Web3D"
      " derivatives, then the finest level's thumbnail as Image2D)")
# No duplicate files at all.
digests = {}
for f in sorted(os.listdir(folder)):
    h = hashlib.sha256(open(os.path.join(folder, f), "rb").read()).hexdigest()
    check(h not in digests, f"{f} and {digests.get(h)} are identical")
    digests[h] = f
md = open(os.path.join(folder, "summary-item.md")).read()
check("| medium | octree | %d |" % finest in md and
      md.count(" | k100 |\n") == 5, "summary-item.md: medium's row, five rows served by k100's files")
html = open(os.path.join(folder, "index.html")).read()
check(html.count("the same mesh as k100") == 4, "index.html: four levels point to k100's files")
check(html.count('<figure class="sl-view') == 1, "index.html: one 3D view")
check(html.count('<button type="button" class="level') == len(files), "index.html: a level card per published mesh")
sys.exit(1 if bad else 0)
EOF
prc=$?
set -e
check "duplicate levels published once, named in report and manifest" [ "$prc" -eq 0 ]

# The work folder holds no copies either: the export stage never wrote them.
check "no medium.* artifact" [ -z "$(find "$TMP/work/artifacts/export" -name 'medium.*')" ]

digest=$(tree_digest "$TMP/work" "$TMP/out")
run_scanlod run "$TMP/c.ini" -q
check "rerun: nothing to do ($out)" contains "nothing to do" "$out"
check "rerun: the same bytes" same_digest "$digest" "$TMP/work" "$TMP/out"
finish
