#!/usr/bin/env bash
# The HTML report in a real browser: headless Chromium (Debian's chromium, driven by npm
# playwright-core: scripts/viewer/check_page.mjs) opens OUTPUT/summary.html and every
# OUTPUT/ITEM/index.html from the files and from a server on 127.0.0.1. What a curator
# reads must be there and visible: the manifest's title, accession number, credit and
# licence, the frame (flagged when estimated), and per level card Voyager's quality, the
# triangles and the error in millimetres the report gives. An item page has one 3D view,
# the summary one per item that loads when clicked, and never more than one is live; no
# page asks for more than one GLB script before a level is chosen. Every level must draw
# (opaque, non-background pixels in its canvas, the level's triangle count), with no
# console error and no request leaving the pages' own files. The viewer must draw every
# encoding the export writes (meshopt, the default; draco; none) and a peer's meshopt
# stream (gltfpack -cc). With SCANLOD_SHARED_DATA, igea's page (268k triangles) must
# draw its first level within 3 s. Controls: a page that requests the network, one whose
# canvases are never drawn, one with a damaged GLB, one that loads every level up front,
# a viewer that keeps every view live and a page whose mm labels are wrong must each fail.
# node, the npm packages of scripts/viewer and chromium are test dependencies
# (scripts/install-deps.sh): when one is missing this test FAILS, it does not skip.
# SCANLOD_TEST_SHOTS=DIR keeps the screenshots.
source "$(dirname "$0")/../lib.sh"
viewer="$SCANLOD_SOURCE_DIR/scripts/viewer"
check_page=("node" "$viewer/check_page.mjs")

if ! command -v node >/dev/null; then
  echo "FAIL: node is not installed; run scripts/install-deps.sh" >&2
  exit 1
fi
if [ ! -f "$viewer/node_modules/playwright-core/package.json" ]; then
  echo "FAIL: the viewer's npm packages are missing; run: npm ci --prefix scripts/viewer" >&2
  exit 1
fi
if ! command -v chromium >/dev/null && [ -z "${SCANLOD_CHROMIUM:-}" ]; then
  echo "FAIL: chromium is not installed; run scripts/install-deps.sh" >&2
  exit 1
fi

# Names that need escaping in URLs and markup: a space, '#', '%', '&', a quote.
mkdir -p "$TMP/in/odd dir"
cp "$SCANS/cow.ply" "$TMP/in/"
cp "$SCANS/bun_zipper_res3.ply" "$TMP/in/odd dir/bun #1 %&'.ply"
# The manifest: markup in a title (escaped on the page), a cow in cm, a bunny whose frame
# nobody gives (estimated).
cat >"$TMP/in/manifest.csv" <<'EOF'
file,title,accession,units,up,credit,licence
cow.ply,The <b>cow</b> & its calf,1999.4.17,cm,y,Viewpoint Animation Engineering,CC0 1.0
odd dir/bun #1 %&'.ply,Stanford bunny,SCR-1994-1,,,Stanford Computer Graphics Laboratory,Attribution
EOF
write_config "$TMP/c.ini" "$TMP/in" "$TMP/work" "$TMP/out" "[levels]" \
  "budgets = thumb:1000,low:5000,medium:100000,high:500000,highest:2000000" "[export]" \
  "thumbnail_size = 128" "fidelity_samples = 20000"
run_scanlod run "$TMP/c.ini" -q
check "run exits 0 (got $rc: $err)" [ "$rc" -eq 0 ]
items=("cow.ply" "odd dir/bun #1 %&'.ply")
if [ ! -s "$TMP/out/cow.ply/scanlod-viewer.js" ]; then
  echo "FAIL: no scanlod-viewer.js: scanlod was built without its viewer (npm ci --prefix scripts/viewer, then rebuild)" >&2
  exit 1
fi
check "summary.html and the viewer at the collection root" \
  [ -s "$TMP/out/summary.html" -a -s "$TMP/out/scanlod-viewer.js" ]
check "the root viewer is the items' one" cmp -s "$TMP/out/scanlod-viewer.js" "$TMP/out/cow.ply/scanlod-viewer.js"

shots="$TMP/shots"
cd "$TMP" # check_page names pages and screenshots by their path from here
pages() { # pages LOG ARGS...: check_page, its output in LOG; sets $prc
  local log=$1; shift
  set +e
  "${check_page[@]}" "$@" >"$log" 2>&1
  prc=$?
  set -e
  grep -E '"fail"|"page"' "$log" | head -40
}

# What a page showed against the reports and the manifest: every view drawn (one per item
# page, one per item on the summary), each with its level's triangle count, at most one
# live at a time; the head and the level cards as the report and the manifest say.
agree() { # agree LOG
  python3 - "$1" "$TMP/out" "$TMP/in/manifest.csv" "${items[@]}" <<'EOF'
import csv, json, os, sys, urllib.parse
log, out, manifest, items = sys.argv[1], sys.argv[2], sys.argv[3], sys.argv[4:]
rows = [json.loads(l) for l in open(log) if l.startswith("{")]
meta = {r["file"]: r for r in csv.DictReader(open(manifest))}
bad = 0
def check(ok, what):
    global bad
    if not ok:
        bad += 1
        print("FAIL: " + what, file=sys.stderr)
    return ok
def mm(v):  # stages/export/export_html_parts.c, sl_html_mm
    return f"{v:.0f} mm" if v >= 100 else f"{v:.1f} mm" if v >= 10 else f"{v:.2f} mm" if v >= 0.01 else f"{v:.2g} mm"
files, levels, export = {}, {}, {}
for item in items:
    export[item] = json.load(open(os.path.join(out, item, "report.json")))["stages"]["export"]
    files[item] = {f["name"]: f for f in export[item]["files"]}
    levels[item] = {l["name"]: l for l in export[item]["levels"]}
def item_of(url):  # the item folder of a page or .glb.js URL, by its path under OUTPUT/
    path = urllib.parse.unquote(urllib.parse.urlparse(url).path)
    return next((i for i in items if ("/" + i + "/") in path), None)
def card_ok(item, card, where):
    name = os.path.basename(urllib.parse.unquote(card["src"])).split(".")[0]
    f, lv = files[item].get(name), levels[item].get(name)
    if not check(f is not None and card["visible"], f"{where}: card {card['src']} is a published level, visible"):
        return
    want = [", ".join(f["qualities"]) or name, f"{f['triangles']:,} triangles"]
    want.append("the scan itself" if lv["scan"] else f"max error {mm(lv['hausdorff_mm'])} · RMS {mm(lv['rms_mm'])}")
    for w in want:
        check(w in card["text"], f"{where}: card {name} says '{w}' ({card['text']})")
    if not lv["scan"]:  # the mm are the fractions of the diagonal, in the item's units, in mm
        e = export[item]
        d = e["input_diagonal"] * e["frame"]["to_metres"] * 1000
        check(abs(lv["hausdorff_mm"] - lv["hausdorff"] * d) <= 1e-6 * lv["hausdorff_mm"] and
              abs(lv["rms_mm"] - lv["rms"] * d) <= 1e-6 * lv["rms_mm"], f"{where}: {name}'s mm are its errors x the diagonal")
for p in (r for r in rows if "page" in r and "url" in r):
    item = item_of(p["url"])
    want = 1 if item else len(items)
    check(p["views"] == want and p["errors"] == 0, f"{p['page']}: {p['views']} views (want {want}), {p['errors']} errors")
    check(p["glb_scripts_before_choice"] <= (1 if item else 0), f"{p['page']}: {p['glb_scripts_before_choice']} GLB scripts before a choice")
    if not item:
        continue
    m, h = meta[item], p["head"]
    check(h["title"] == m["title"], f"{p['page']}: title '{h['title']}'")
    check(m["accession"] in h["ids"], f"{p['page']}: accession in '{h['ids']}'")
    check(m["credit"] in h["credit"] and m["licence"] in h["credit"], f"{p['page']}: credit and licence in '{h['credit']}'")
    fr = export[item]["frame"]
    estimated = "estimated" in (fr["units_from"], fr["up_from"])
    check(("Frame estimated" in h["frame"]) == estimated, f"{p['page']}: frame note '{h['frame'][:80]}' ({fr['units_from']}, {fr['up_from']})")
    check(len(p["cards"]) == len(files[item]), f"{p['page']}: {len(p['cards'])} level cards, {len(files[item])} published")
    for card in p["cards"]:
        card_ok(item, card, p["page"])
for v in (r for r in rows if "src" in r):
    url = urllib.parse.urljoin(v["in"], v["src"])
    item, name = item_of(url), os.path.basename(urllib.parse.unquote(url))[:-len(".glb.js")]
    what = f"{urllib.parse.unquote(url)}"
    check(v["state"] == "drawn" and v["drawn"] >= 0.01, f"{what}: {v['state']}, {v['drawn']} drawn")
    check(v["live"] == 1, f"{what}: {v['live']} views live")
    check(item is not None and v["triangles"] == files[item].get(name, {}).get("triangles"),
          f"{what}: {v['triangles']} triangles, report {files.get(item, {}).get(name, {}).get('triangles')}")
check(sum("src" in r for r in rows) >= 2 * len(items), "views were checked")
sys.exit(1 if bad else 0)
EOF
}

# 1. From the files (file://), every level of every view.
index_pages=()
for item in "${items[@]}"; do index_pages+=("$TMP/out/$item/index.html"); done
pages "$TMP/file.log" --levels --shots "$shots" "$TMP/out/summary.html" "${index_pages[@]}"
check "file://: summary.html and index.html draw every view, no errors, no network" [ "$prc" -eq 0 ]
check "file://: views agree with the reports" agree "$TMP/file.log"

# 2. From a server on 127.0.0.1 (the same pages again: the browser's side, not scanlod's).
if light; then
  echo "LIGHT: the pages from 127.0.0.1 and the broken-page controls (part 4) are the Release pass's"
else
  pages "$TMP/http.log" --http "$TMP/out" --shots "$shots" "$TMP/out/summary.html" "${index_pages[@]}"
  check "http://127.0.0.1: the same pages draw, no errors, no other host" [ "$prc" -eq 0 ]
  check "http://127.0.0.1: views agree with the reports" agree "$TMP/http.log"
  check "http://127.0.0.1: pages really came from the server" grep -q '"url":"http://127.0.0.1:' "$TMP/http.log"
fi

# 3. Every encoding the export writes draws. The pages above hold the default, meshopt
# (EXT_meshopt_compression); here the same collection published with compression = draco
# and = none, and a peer's meshopt stream (gltfpack -cc of the uncompressed lod20).
glb_script() { # glb_script GLB: NAME.glb.js as the export stage writes it
  python3 -c "import base64,sys; open(sys.argv[1]+'.js','w').write('(self.SCANLOD_GLB=self.SCANLOD_GLB||{})[document.currentScript.src]=\"'+base64.b64encode(open(sys.argv[1],'rb').read()).decode()+'\";\n')" "$1"
}
extensions() { # extensions GLB: its extensionsUsed, comma-separated
  python3 -c "import json,struct,sys; d=open(sys.argv[1],'rb').read(); n=struct.unpack_from('<I',d,12)[0]; print(','.join(json.loads(d[20:20+n]).get('extensionsUsed',[])))" "$1"
}
triangles_of() { # triangles_of OUTPUT LEVEL: the published mesh's triangles
  python3 -c "import json,sys; print([f['triangles'] for f in json.load(open(sys.argv[1]+'/cow.ply/report.json'))['stages']['export']['files'] if f['name']==sys.argv[2]][0])" "$1" "$2"
}
check "default: lod40 uses EXT_meshopt_compression ($(extensions "$TMP/out/cow.ply/lod40.glb"))" \
  contains EXT_meshopt_compression "$(extensions "$TMP/out/cow.ply/lod40.glb")"
for mode in draco none; do
  run_scanlod run "$TMP/c.ini" -q -s export.compression=$mode -s run.output="$TMP/out-$mode"
  check "$mode: run exits 0 (got $rc: $err)" [ "$rc" -eq 0 ]
  used=$(extensions "$TMP/out-$mode/cow.ply/lod40.glb")
  if [ $mode = draco ]; then
    check "draco: lod40 uses KHR_draco_mesh_compression ($used)" contains KHR_draco_mesh_compression "$used"
  else
    check "none: lod40 is not compressed ($used)" bash -c '! grep -q compression <<<"$1"' _ "$used"
  fi
  pages "$TMP/$mode.log" --levels --shots "$shots" "$TMP/out-$mode/cow.ply/index.html"
  check "$mode: every view draws, no errors" [ "$prc" -eq 0 ]
  want=$(triangles_of "$TMP/out-$mode" lod40)
  check "$mode: lod40 drew its $want triangles" grep -q "\"src\":\"lod40.glb.js\",\"state\":\"drawn\",\"triangles\":$want," "$TMP/$mode.log"
done
mkdir -p "$TMP/packed"
cp -r "$TMP/out-none/cow.ply" "$TMP/packed/cow.ply"
packed="$TMP/packed/cow.ply"
set +e
"$viewer/node_modules/.bin/gltfpack" -i "$TMP/out-none/cow.ply/lod20.glb" -o "$packed/lod20.glb" -cc >"$TMP/gltfpack.log" 2>&1
grc=$?
set -e
check "gltfpack -cc made lod20 ($(head -c 200 "$TMP/gltfpack.log"))" [ "$grc" -eq 0 ]
check "lod20 uses EXT_meshopt_compression ($(extensions "$packed/lod20.glb"))" \
  contains EXT_meshopt_compression "$(extensions "$packed/lod20.glb")"
glb_script "$packed/lod20.glb"
pages "$TMP/packed.log" --levels --shots "$shots" "$packed/index.html"
check "a peer's meshopt GLB draws, no errors" [ "$prc" -eq 0 ]
want=$(triangles_of "$TMP/out-none" lod20)
check "gltfpack's lod20 drew its $want triangles" grep -q "\"src\":\"lod20.glb.js\",\"state\":\"drawn\",\"triangles\":$want," "$TMP/packed.log"

# 4. Controls: each broken page must fail the check, naming what is wrong. They test the
# page checker and the viewer script, not scanlod's code: the Release pass runs them
# (the block is not indented: its here-documents are Python).
if ! light; then
control() { # control NAME EXPECTED PAGE
  export SCANLOD_VIEW_TIMEOUT_MS=1500 # a view that never draws fails soon
  pages "$TMP/control-$1.log" "$3"
  unset SCANLOD_VIEW_TIMEOUT_MS
  check "control $1: refused" [ "$prc" -eq 1 ]
  check "control $1: says '$2'" grep -qF -- "$2" "$TMP/control-$1.log"
}
cp -r "$TMP/out/cow.ply" "$TMP/ctl"
sed 's|</body>|<img src="http://example.com/pixel.png" alt=""></body>|' "$TMP/ctl/index.html" >"$TMP/ctl/network.html"
control network "request leaves the page's files: http://example.com/pixel.png" "$TMP/ctl/network.html"
sed 's|</head>|<script>CanvasRenderingContext2D.prototype.drawImage = function () {};</script></head>|' \
  "$TMP/ctl/index.html" >"$TMP/ctl/nodraw.html"
control no-draw "the canvas shows no model" "$TMP/ctl/nodraw.html"
sed 's|<script src="scanlod-viewer.js"></script>||' "$TMP/ctl/index.html" >"$TMP/ctl/noviewer.html"
control no-viewer "state none" "$TMP/ctl/noviewer.html"
# Every level's GLB as a script in the page, as the pages had before one view.
upfront=$(cd "$TMP/ctl" && for f in *.glb.js; do printf '<script src="%s"></script>' "$f"; done)
sed "s|</body>|$upfront</body>|" "$TMP/ctl/index.html" >"$TMP/ctl/upfront.html"
control upfront "GLB scripts requested before any level was chosen" "$TMP/ctl/upfront.html"
first=$(grep -o 'sl-main" data-src="[^"]*"' "$TMP/ctl/index.html" | sed 's/.*data-src="//; s/"$//')
printf '(self.SCANLOD_GLB=self.SCANLOD_GLB||{})[document.currentScript.src]="Z2xURgIAAAA=";\n' >"$TMP/ctl/$first"
control damaged "console error: scanlod viewer: cannot show $first" "$TMP/ctl/index.html"
# A viewer that never releases a view: the summary's second click leaves two live.
cp -r "$TMP/out" "$TMP/live"
python3 - "$TMP/live/scanlod-viewer.js" <<'EOF'
import re, sys
text = open(sys.argv[1]).read()
text, n = re.subn(r"(\w+)&&\1!==this&&\1\.release\(\),", "", text)
assert n == 1, n
open(sys.argv[1], "w").write(text)
EOF
control live "views live at once (one per page)" "$TMP/live/summary.html"
# A wrong millimetre label: the browser draws it, the agreement with the report refuses it.
mkdir -p "$TMP/mm" && cp -r "$TMP/out/cow.ply" "$TMP/mm/cow.ply"
python3 - "$TMP/mm/cow.ply/index.html" <<'EOF'
import re, sys
text = open(sys.argv[1]).read()
text, n = re.subn(r"max error [0-9.e-]+ mm", "max error 123 mm", text, count=1)
assert n == 1
open(sys.argv[1], "w").write(text)
EOF
pages "$TMP/mm.log" "$TMP/mm/cow.ply/index.html"
set +e
agree "$TMP/mm.log" 2>"$TMP/mm.err"
arc=$?
set -e
check "control mm-label: the page draws ($prc)" [ "$prc" -eq 0 ]
check "control mm-label: refused by the report's figures" [ "$arc" -ne 0 ]
check "control mm-label: says which card ($(head -c 300 "$TMP/mm.err"))" grep -q "says 'max error" "$TMP/mm.err"
fi # ! light: the controls

# 5. igea (268k triangles, the default config): its page shows its first level within 3 s
# of the page's start (the view's data-drawn-ms, from a file).
if [ -n "${SCANLOD_SHARED_DATA:-}" ] && [ -f "$SCANLOD_SHARED_DATA/igea.ply" ] && ! light; then
  mkdir -p "$TMP/igea-in" && cp "$SCANLOD_SHARED_DATA/igea.ply" "$TMP/igea-in/"
  write_config "$TMP/igea.ini" "$TMP/igea-in" "$TMP/igea-work" "$TMP/igea-out" "[levels]" "[export]"
  run_scanlod run "$TMP/igea.ini" -q
  check "igea: run exits 0 (got $rc: $err)" [ "$rc" -eq 0 ]
  pages "$TMP/igea.log" --max-first-draw 3000 --shots "$shots" "$TMP/igea-out/igea.ply/index.html"
  check "igea: first level drawn within 3 s ($(grep -o '"first_draw_ms":[0-9]*' "$TMP/igea.log"))" [ "$prc" -eq 0 ]
else
  echo "igea: no SCANLOD_SHARED_DATA (or LIGHT): its page's first draw is not timed here"
fi

if [ -n "${SCANLOD_TEST_SHOTS:-}" ]; then
  mkdir -p "$SCANLOD_TEST_SHOTS" && cp "$shots"/*.png "$SCANLOD_TEST_SHOTS"/
fi
finish
