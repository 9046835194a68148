#!/usr/bin/env bash
# The collection manifest and the items' frames (docs/metadata.md), end to end:
# - rows applied: titles, credit in the pages and the Voyager scene, the frame from the row;
#   a Z-up millimetre scan (the bundled bunny with its axes permuted, scaled to mm: what
#   nefertiti is) comes out upright and in metres in its GLB, upright in its thumbnail;
# - a row naming no item: a warning in the log, the summary line and summary.json;
# - a title edit reruns that item's export only (the same rows as JSON: nothing);
# - a malformed manifest: exit 78 before any work, naming file:line;
# - without a row the frame is estimated and flagged (report, page, log), and the
#   estimate finds the permuted bunny's z and mm;
# - with SCANLOD_SHARED_DATA (not LIGHT): nefertiti, with a row and without.
source "$(dirname "$0")/../lib.sh"
glb_check="${SCANLOD_BUILD_DIR:?}/tests/glb_check"
pixels="$SCANLOD_SOURCE_DIR/tests/export"

mkdir -p "$TMP/in"
cp "$SCANS/cow.ply" "$SCANS/bun_zipper_res3.ply" "$TMP/in/"
# zbunny.ply: the bunny Z-up in millimetres, (x, y, z) -> (x, -z, y) x 1000: its up +y
# becomes +z (a proper rotation: outsides stay out).
python3 - "$SCANS/bun_zipper_res3.ply" "$TMP/in/zbunny.ply" <<'EOF'
import sys
lines = open(sys.argv[1]).read().split("\n")
end = lines.index("end_header")
nv = next(int(l.split()[2]) for l in lines if l.startswith("element vertex"))
nf = next(int(l.split()[2]) for l in lines if l.startswith("element face"))
out = ["ply", "format ascii 1.0", f"element vertex {nv}", "property float x", "property float y",
       "property float z", f"element face {nf}", "property list uchar int vertex_indices", "end_header"]
for l in lines[end + 1:end + 1 + nv]:
    x, y, z = map(float, l.split()[:3])
    out.append(f"{x * 1000:.6g} {-z * 1000:.6g} {y * 1000:.6g}")
out += lines[end + 1 + nv:end + 1 + nv + nf]
open(sys.argv[2], "w").write("\n".join(out) + "\n")
EOF
manifest() { # manifest COW-TITLE: the manifest with cow's title (and a row naming no item)
  cat >"$TMP/in/manifest.csv" <<EOF
file,title,accession,units,up,credit,licence,description
cow.ply,"$1",1999.4.17,cm,y,Viewpoint Animation Engineering,CC0 1.0,A classic test model.
zbunny.ply,"Bunny, standing on z",SCR-1,mm,z,Stanford Computer Graphics Laboratory,,
ghost.ply,Not delivered yet,,,,,,
EOF
}
manifest "Cow"
write_config "$TMP/c.ini" "$TMP/in" "$TMP/work" "$TMP/out" "[levels]" "percents = 50,100" \
  "budgets =" "[export]" "formats = ply,glb" "thumbnail_size = 64" "fidelity = false" \
  "viewer = false"
report() { # report ITEM PYTHON-EXPRESSION-ON-e (its export section)
  python3 -c "import json,sys; e=json.load(open(sys.argv[1]))['stages']['export']; print($2)" \
    "$TMP/out/$1/report.json"
}
stage_runs() { # stage_runs LOG.jsonl: "stage item" per stage_done event, sorted
  python3 -c "import json,sys; print('\n'.join(sorted(e['stage']+' '+e['item'] for e in map(json.loads, open(sys.argv[1])) if e['event']=='stage_done')))" "$1"
}
newest_log() { ls -t "$TMP/logs"/*.jsonl | head -1; }

# 1. Rows applied; the unknown row said.
run_scanlod run "$TMP/c.ini" -q
check "run exits 0 (got $rc: $err)" [ "$rc" -eq 0 ]
check "the summary line counts the row naming no item ($out)" contains "1 manifest rows name no item" "$out"
check "the log names the row's line" grep -q "ghost.ply: manifest.csv:4: the collection manifest has a row for it" "$TMP"/logs/*.log
check "summary.json lists it" [ "$(python3 -c "import json; print(json.load(open('$TMP/out/summary.json'))['manifest']['unknown_items'])")" = "['ghost.ply']" ]
check "cow: frame from the manifest" [ "$(report cow.ply "e['frame']['units'], e['frame']['units_from'], e['frame']['up_from']")" = "cm manifest manifest" ]
check "cow: the page's title and credit" grep -q "<h1>Cow</h1>" "$TMP/out/cow.ply/index.html"
check "cow: credit on the page" grep -q "Viewpoint Animation Engineering" "$TMP/out/cow.ply/index.html"
check "cow: the scene's title" grep -q '"EN": "Cow"' "$TMP/out/cow.ply/scene.svx.json"
check "zbunny: z and mm from the manifest" [ "$(report zbunny.ply "e['frame']['up'], e['frame']['units'], e['frame']['up_from']")" = "z mm manifest" ]
check "zbunny: its GLB is the PLY turned Z-up -> Y-up and scaled mm -> m" \
  "$glb_check" "$TMP/out/zbunny.ply/lod100.glb" "$TMP/out/zbunny.ply/lod100.ply" 0.001 z 2e-5
upright() { # upright A.png B.png: mean |difference| under 4/255
  PYTHONPATH="$pixels" python3 - "$1" "$2" <<'EOF'
import sys, png_pixels
a, b = png_pixels.read(sys.argv[1]), png_pixels.read(sys.argv[2])
d = sum(abs(x - y) for ra, rb in zip(a, b) for pa, pb in zip(ra, rb) for x, y in zip(pa, pb)) / (3 * len(a) * len(a[0]))
print(f"mean |difference| {d:.2f}")
sys.exit(0 if d < 4 else 1)
EOF
}
check "zbunny's thumbnail is the Y-up bunny's: upright" \
  upright "$TMP/out/zbunny.ply/lod100.png" "$TMP/out/bun_zipper_res3.ply/lod100.png"
differs() { ! upright "$1" "$2" >/dev/null; }
check "the comparison tells pictures apart (zbunny against the cow)" \
  differs "$TMP/out/zbunny.ply/lod100.png" "$TMP/out/cow.ply/lod100.png"

# 2. Without a row: estimated, and flagged in the report, the page and the log.
check "bunny (no row): units and up estimated" \
  [ "$(report bun_zipper_res3.ply "e['frame']['units_from'], e['frame']['up_from'], e['frame']['up'], e['frame']['units']")" = "estimated estimated y m" ]
check "bunny: the report says how" [ -n "$(report bun_zipper_res3.ply "e['frame']['up_estimate'] and e['frame']['units_estimate']")" ]
check "bunny: the page flags the estimate" grep -q "Frame estimated" "$TMP/out/bun_zipper_res3.ply/index.html"
check "bunny: the log warns" grep -q "bun_zipper_res3.ply: up axis estimated: y" "$TMP"/logs/*.log
check "cow (a row with a frame): no estimate on its page" bash -c '! grep -q "Frame estimated" "$1"' _ "$TMP/out/cow.ply/index.html"

# 3. A title edit reruns that item's export only; the same rows as JSON rerun nothing.
manifest "Cow, retitled"
run_scanlod run "$TMP/c.ini" -q
check "edit: run exits 0 (got $rc)" [ "$rc" -eq 0 ]
check "edit: one stage run, cow's export ($(stage_runs "$(newest_log)" | tr '\n' ';'))" \
  [ "$(stage_runs "$(newest_log)")" = "export cow.ply" ]
check "edit: the new title published" grep -q "<h1>Cow, retitled</h1>" "$TMP/out/cow.ply/index.html"
python3 - "$TMP/in/manifest.csv" "$TMP/in/manifest.json" <<'EOF'
import csv, json, sys
rows = list(csv.DictReader(open(sys.argv[1])))
json.dump(rows[::-1], open(sys.argv[2], "w"), indent=1)  # another order: no row moves a key
EOF
mv "$TMP/in/manifest.csv" "$TMP/manifest.csv.saved"
run_scanlod run "$TMP/c.ini" -q
check "JSON, rows reversed: nothing reruns ($out)" contains "^nothing to do" "$out"

# 4. A malformed manifest: exit 78 before any work, naming file:line.
rm "$TMP/in/manifest.json"
printf 'file,title,units\ncow.ply,Cow,cm\nzbunny.ply,"Bunny,mm\n' >"$TMP/in/manifest.csv"
before=$(tree_digest "$TMP/work" "$TMP/out")
run_scanlod run "$TMP/c.ini" -q
check "unclosed quote: exit 78 (got $rc)" [ "$rc" -eq 78 ]
check "unclosed quote: names manifest.csv:3 ($err)" contains "manifest.csv:3: collection manifest: a quote opened here is never closed" "$err"
printf 'file,title,units\ncow.ply,Cow,metres\n' >"$TMP/in/manifest.csv"
run_scanlod run "$TMP/c.ini" -q
check "bad units: exit 78 naming manifest.csv:2 ($err)" bash -c '[ "$1" -eq 78 ] && grep -q "manifest.csv:2: .*units '"'"'metres'"'"'" <<<"$2"' _ "$rc" "$err"
check "nothing ran or changed" same_digest "$before" "$TMP/work" "$TMP/out"

# 5. The row gone: zbunny's frame is estimated, and the estimate is its z and mm.
printf 'file,title\ncow.ply,"Cow, retitled"\n' >"$TMP/in/manifest.csv"
run_scanlod run "$TMP/c.ini" -q
check "no row: run exits 0 (got $rc)" [ "$rc" -eq 0 ]
check "zbunny without a row: estimated z and mm" \
  [ "$(report zbunny.ply "e['frame']['up'], e['frame']['up_from'], e['frame']['units'], e['frame']['units_from']")" = "z estimated mm estimated" ]
check "zbunny estimated: still upright" \
  upright "$TMP/out/zbunny.ply/lod100.png" "$TMP/out/bun_zipper_res3.ply/lod100.png"

# 6. nefertiti (Z-up, mm), with a row and without.
if [ -n "${SCANLOD_SHARED_DATA:-}" ] && [ -f "$SCANLOD_SHARED_DATA/nefertiti.ply" ] && ! light; then
  mkdir -p "$TMP/nin"
  cp "$SCANLOD_SHARED_DATA/nefertiti.ply" "$TMP/nin/"
  printf 'file,title,units,up\nnefertiti.ply,Bust of Nefertiti,mm,z\n' >"$TMP/nin/manifest.csv"
  write_config "$TMP/n.ini" "$TMP/nin" "$TMP/nwork" "$TMP/nout" "[levels]" "percents = 100" \
    "budgets =" "[export]" "formats = ply,glb" "thumbnail_size = 64" "fidelity = false" \
    "viewer = false"
  run_scanlod run "$TMP/n.ini" -q
  check "nefertiti: run exits 0 (got $rc: $err)" [ "$rc" -eq 0 ]
  nef() { python3 -c "import json,sys; e=json.load(open(sys.argv[1]))['stages']['export']; print($1)" "$TMP/nout/nefertiti.ply/report.json"; }
  check "nefertiti: z and mm from the manifest" [ "$(nef "e['frame']['up'], e['frame']['units'], e['frame']['up_from']")" = "z mm manifest" ]
  check "nefertiti: its GLB upright in metres" \
    "$glb_check" "$TMP/nout/nefertiti.ply/lod100.glb" "$TMP/nout/nefertiti.ply/lod100.ply" 0.001 z 1e-4
  check "nefertiti: the Voyager scene in metres" grep -q '"units": "m"' "$TMP/nout/nefertiti.ply/scene.svx.json"
  cp "$TMP/nout/nefertiti.ply/lod100.png" "$TMP/nef-row.png"
  rm "$TMP/nin/manifest.csv"
  run_scanlod run "$TMP/n.ini" -q
  check "nefertiti without a row: estimated z and mm" \
    [ "$(nef "e['frame']['up'], e['frame']['up_from'], e['frame']['units'], e['frame']['units_from']")" = "z estimated mm estimated" ]
  check "nefertiti without a row: the same upright thumbnail" upright "$TMP/nout/nefertiti.ply/lod100.png" "$TMP/nef-row.png"
else
  echo "nefertiti: no SCANLOD_SHARED_DATA (or LIGHT): the bundled Z-up bunny stands in for it"
fi
finish
