#!/usr/bin/env bash
# The cluster method in a run as paper 2 makes it (`-s lod.method=cluster`, no collapse or
# fit, the method's own top level: range -> cluster -> refine -> export): every
# item is published with its levels, intermediate models, thumbnails and a report giving
# each level's proven Hausdorff bound; `scanlod compare` measures every level and model
# within its bound; intermediate models lie strictly between their two levels, decreasing;
# every GLB passes the Khronos validator; and a run killed with SIGKILL at random moments
# resumes to the clean run's bytes (the crash discipline of tests/crash/test_crash_resume.sh).
# SCANLOD_CRASH_KILLS overrides the number of kills (default 8).
source "$(dirname "$0")/../lib.sh"
kills=${SCANLOD_CRASH_KILLS:-8}

mkdir -p "$TMP/in"
# closed (cow, fandisk); open with 70 non-manifold edges (bun_zipper_res4)
cp "$SCANS/cow.ply" "$SCANS/fandisk.ply" "$SCANS/bun_zipper_res4.ply" "$TMP/in/"
lines=("[cluster]" "intermediates = 2" "[levels]" "percents = 40,100" "budgets = thumb:1000"
       "top = method" "oversample = 1" "[refine]" "collapse = false" "fit = false" "[export]"
       "formats = ply,glb" "thumbnail_size = 48" "fidelity = true" "fidelity_samples = 20000")
write_config "$TMP/ref.ini" "$TMP/in" "$TMP/ref-work" "$TMP/ref-out" "${lines[@]}"
start=$(date +%s%N)
run_scanlod run "$TMP/ref.ini" -q -s lod.method=cluster
clean_ns=$(( $(date +%s%N) - start ))
check "clean run exits 0 (got $rc: $err)" [ "$rc" -eq 0 ]
ref=$(tree_digest "$TMP/ref-work" "$TMP/ref-out")

# The published item, as report.json describes it.
cat >"$TMP/check.py" <<'EOF'
import json, os, sys
out, item, closed = sys.argv[1], sys.argv[2], sys.argv[3] == "closed"
r = json.load(open(os.path.join(out, item, "report.json")))
bad = []
def need(ok, what):
    if not ok:
        bad.append(what)
need(r["method"] == "cluster", "method %s" % r["method"])
need("cluster" in r["stages"] and "samples" not in r["stages"], "stages %s" % list(r["stages"]))
levels = r["stages"]["export"]["levels"]
by = {l["name"]: l for l in levels}
need({"lod40", "lod100", "thumb"} <= set(by), "levels %s" % sorted(by))
# the manifest and the page cover the levels, not the intermediate models
svx = json.load(open(os.path.join(out, item, "scene.svx.json")))
uris = {a["uri"] for d in svx["models"][0]["derivatives"] for a in d["assets"]}
need(uris and all(u[:-4] in by and not by[u[:-4]]["intermediate"] for u in uris), "svx assets %s" % sorted(uris))
page = open(os.path.join(out, item, "index.html")).read()
need("levels made by cluster" in page and "lod40" in page, "index.html")
need(".morph" not in page, "index.html names an intermediate model")
files = [f["name"] for f in r["stages"]["export"]["files"]]
need(files and all(not by[f]["intermediate"] for f in files), "report files %s" % files)
names = {l["name"]: l for l in levels}
for l in levels:
    own = os.path.join(out, item, l["name"])
    need(l["bound"] >= 0 and "bound_world" in l, l["name"] + ": a bound")
    need(l.get("bound_holds") is True, "%s: measured %s > bound %s" % (l["name"], l.get("hausdorff"), l["bound"]))
    # identical meshes are published once, under a level's name before a model's
    f = l.get("file")
    need(f in names and names[f]["file"] == f, "%s: its file %s publishes itself" % (l["name"], f))
    if f != l["name"]:
        need(not os.path.exists(own + ".ply") and not os.path.exists(own + ".glb"), l["name"] + ": no copy of " + str(f))
        need(names[f]["triangles"] == l["triangles"] and (l["intermediate"] or not names[f]["intermediate"]), l["name"] + ": the same mesh as " + str(f))
        continue
    need(os.path.getsize(own + ".ply") > 0 and os.path.getsize(own + ".glb") > 0, l["name"] + ": ply and glb")
    need(os.path.exists(own + ".png") != l["intermediate"], l["name"] + ": a thumbnail for levels only")
    if closed and not l["intermediate"]:
        need(l["watertight"], l["name"] + ": watertight")
for name, l in by.items():
    if l["intermediate"] or l["from"] is None or l["triangles"] == by[l["from"]]["triangles"]:
        continue
    models = [by["%s.morph%d" % (name, j)] for j in (1, 2)]
    counts = [by[l["from"]]["triangles"]] + [m["triangles"] for m in models] + [l["triangles"]]
    need(all(a > b for a, b in zip(counts, counts[1:])), "%s: counts %s not strictly decreasing" % (name, counts))
    need(all(m["bound"] <= l["bound"] for m in models), name + ": a model's bound over its level's")
print("\n".join(bad))
EOF
for item in cow.ply fandisk.ply bun_zipper_res4.ply; do
  kind=closed; [ "$item" = bun_zipper_res4.ply ] && kind=open
  problems=$(python3 "$TMP/check.py" "$TMP/ref-out" "$item" "$kind")
  check "$item: published as the report says (${problems:-ok})" [ -z "$problems" ]
done
# The bound, checked by `scanlod compare` itself (not the export's measure) on two levels
# and a model, with more samples.
for f in cow.ply/lod40 cow.ply/lod40.morph1 fandisk.ply/thumb; do
  bound=$(python3 -c "import json; r=json.load(open('$TMP/ref-out/${f%%/*}/report.json')); print([l for l in r['stages']['export']['levels'] if l['name']=='${f#*/}'][0]['bound'])")
  run_scanlod compare "$TMP/in/${f%%/*}" "$TMP/ref-out/$f.ply" --json --samples 300000
  h=$(python3 -c "import json,sys; print(json.loads(sys.argv[1])['hausdorff'])" "$out")
  check "$f: compare's Hausdorff $h <= the bound $bound" python3 -c "import sys; sys.exit(0 if $h <= $bound else 1)"
done
if gltf_validator_ready; then
  mapfile -t glbs < <(find "$TMP/ref-out" -name '*.glb' | sort)
  set +e
  node "$SCANLOD_SOURCE_DIR/scripts/gltf/validate.mjs" "${glbs[@]}" >"$TMP/glb.jsonl" 2>"$TMP/glb.err"
  vrc=$?
  set -e
  check "validator on ${#glbs[@]} GLBs: exit 0 ($(head -c 300 "$TMP/glb.err"))" [ "$vrc" -eq 0 ]
  check "every GLB 0 errors" [ "$(grep -c '"numErrors":0,' "$TMP/glb.jsonl")" -eq "${#glbs[@]}" ]
else
  check "node and the glTF validator are installed (scripts/install-deps.sh)" false
fi
run_scanlod run "$TMP/ref.ini" -q -s lod.method=cluster
check "a second run has nothing to do ($out $err)" contains "nothing to do" "$out$err"

write_config "$TMP/kill.ini" "$TMP/in" "$TMP/work" "$TMP/out" "${lines[@]}"
unverified=0
for k in $(seq 1 "$kills"); do
  delay_ms=$(( (RANDOM * 32768 + RANDOM) % (clean_ns / 1000000 + 1) ))
  "$SCANLOD" run "$TMP/kill.ini" -q -s lod.method=cluster >/dev/null 2>&1 &
  pid=$!
  sleep "$(printf '%d.%03d' $((delay_ms / 1000)) $((delay_ms % 1000)))"
  kill -9 "$pid" 2>/dev/null || true
  wait "$pid" 2>/dev/null || true
  run_scanlod verify "$TMP/kill.ini" -s lod.method=cluster
  [ "$rc" -eq 0 ] || { unverified=$((unverified + 1)); echo "verify after kill $k: $out $err" >&2; }
done
check "every record verified after every kill ($unverified failures)" [ "$unverified" -eq 0 ]
run_scanlod run "$TMP/kill.ini" -q -s lod.method=cluster
check "resume after $kills kills exits 0 (got $rc: $err)" [ "$rc" -eq 0 ]
check "resumed artifacts and publications byte-identical to the clean run" \
  same_digest "$ref" "$TMP/work" "$TMP/out"
finish
