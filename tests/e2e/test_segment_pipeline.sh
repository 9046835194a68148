#!/usr/bin/env bash
# The segment method in a run as paper 3 makes it (`-s lod.method=segment`, no collapse or
# fit, the method's own top level: range -> segment -> refine -> export): every
# item is published with its levels (PLY, GLB, thumbnails) and a report naming the method;
# on the closed scans every level is watertight and manifold, keeps the input's Euler
# characteristic and has no triangle turned over against the input's normals (checked here
# on the published PLYs, not from the method's own figures); every GLB passes the Khronos
# validator when it is installed; and a run killed with SIGKILL at random moments resumes
# to the clean run's bytes (tests/crash/test_crash_resume.sh's discipline).
# SCANLOD_CRASH_KILLS overrides the number of kills (default 6).
source "$(dirname "$0")/../lib.sh"
kills=${SCANLOD_CRASH_KILLS:-6}

mkdir -p "$TMP/in"
# closed (cow, fandisk); open with 70 non-manifold edges (bun_zipper_res4)
cp "$SCANS/cow.ply" "$SCANS/fandisk.ply" "$SCANS/bun_zipper_res4.ply" "$TMP/in/"
lines=("[segment]" "search_samples = 20000" "[levels]" "percents = 10,40,100"
       "budgets = thumb:1000" "top = method" "oversample = 1" "[refine]" "collapse = false" "fit = false" "[export]" "formats = ply,glb" "thumbnail_size = 48" "fidelity = true"
       "fidelity_samples = 20000")
write_config "$TMP/ref.ini" "$TMP/in" "$TMP/ref-work" "$TMP/ref-out" "${lines[@]}"
start=$(date +%s%N)
run_scanlod run "$TMP/ref.ini" -q -s lod.method=segment
clean_ns=$(( $(date +%s%N) - start ))
check "clean run exits 0 (got $rc: $err)" [ "$rc" -eq 0 ]
ref=$(tree_digest "$TMP/ref-work" "$TMP/ref-out")

# The published item: its report, and each level's PLY read here (topology, Euler
# characteristic, orientation against the input's area-weighted vertex normals).
cat >"$TMP/check.py" <<'EOF'
import json, os, struct, sys
out, src, item, closed = sys.argv[1], sys.argv[2], sys.argv[3], sys.argv[4] == "closed"
SIZES = {"char": "b", "uchar": "B", "short": "h", "ushort": "H", "int": "i", "uint": "I",
         "float": "f", "double": "d", "int8": "b", "uint8": "B", "int32": "i", "uint32": "I",
         "float32": "f", "float64": "d"}
def read_ply(path):
    data = open(path, "rb").read()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    elems, cur, ascii = [], None, False
    for line in data[:end].decode().splitlines():
        w = line.split()
        if w[0] == "format":
            ascii = w[1] == "ascii"
        if w[0] == "element":
            cur = [w[1], int(w[2]), []]
            elems.append(cur)
        elif w[0] == "property":
            cur[2].append(w[1:])
    p, pos, tris = end, [], []
    if ascii:
        words = iter(data[end:].split())
        for name, n, props in elems:
            for _ in range(n):
                row = []
                for pr in props:
                    if pr[0] == "list":
                        row.append(tuple(int(next(words)) for _ in range(int(next(words)))))
                    else:
                        row.append(float(next(words)))
                if name == "vertex":
                    pos.append(struct.unpack("<3f", struct.pack("<3f", *row[:3])))
                elif name == "face":
                    tris.append(row[0])
        return pos, tris
    for name, n, props in elems:
        for _ in range(n):
            row = []
            for pr in props:
                if pr[0] == "list":
                    c = struct.unpack_from("<" + SIZES[pr[1]], data, p)[0]
                    p += struct.calcsize(SIZES[pr[1]])
                    f = "<%d%s" % (c, SIZES[pr[2]])
                    row.append(struct.unpack_from(f, data, p))
                    p += struct.calcsize(f)
                else:
                    f = "<" + SIZES[pr[0]]
                    row.append(struct.unpack_from(f, data, p)[0])
                    p += struct.calcsize(f)
            if name == "vertex":
                pos.append(tuple(row[:3]))
            elif name == "face":
                tris.append(row[0])
    return pos, tris
def sub(a, b): return (a[0] - b[0], a[1] - b[1], a[2] - b[2])
def cross(a, b): return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])
def dot(a, b): return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
def welded(pos, tris):
    ids, out = {}, []
    for t in tris:
        out.append(tuple(ids.setdefault(pos[v], len(ids)) for v in t))
    return ids, out
def topology(tris):
    edges = {}
    for t in tris:
        for k in range(3):
            e = tuple(sorted((t[k], t[(k + 1) % 3])))
            edges[e] = edges.get(e, 0) + 1
    verts = {v for t in tris for v in t}
    return len(verts) - len(edges) + len(tris), sum(c == 1 for c in edges.values()), sum(c > 2 for c in edges.values())
ipos, itris = read_ply(src)
ids, iw = welded(ipos, itris)
inv = {i: p for p, i in ids.items()}
around = {}  # the normals of the input's triangles at each (welded) point
for t in iw:
    n = cross(sub(inv[t[1]], inv[t[0]]), sub(inv[t[2]], inv[t[0]]))
    for v in t:
        around.setdefault(v, []).append(n)
in_chi = topology(iw)[0]
r = json.load(open(os.path.join(out, item, "report.json")))
bad = []
def need(ok, what):
    if not ok:
        bad.append(what)
need(r["method"] == "segment", "method %s" % r["method"])
need("segment" in r["stages"] and "samples" not in r["stages"] and "cluster" not in r["stages"],
     "stages %s" % list(r["stages"]))
levels = r["stages"]["export"]["levels"]
by = {l["name"]: l for l in levels}
need({"lod10", "lod40", "lod100", "thumb"} <= set(by), "levels %s" % sorted(by))
need(by["lod100"]["triangles"] == len(itris) or not closed, "lod100 is the input")
for l in levels:
    # identical levels are published once: "file" names the level whose files they are
    need(l.get("file"), l["name"] + ": no files")
    stem = os.path.join(out, item, l.get("file") or l["name"])
    need("bound_holds" not in l, l["name"] + ": a bound the method does not prove")
    need(os.path.getsize(stem + ".ply") > 0 and os.path.getsize(stem + ".glb") > 0, l["name"] + ": ply and glb")
    need(os.path.exists(stem + ".png"), l["name"] + ": a thumbnail")
    if l["name"] != "lod100":
        need(l["triangles"] <= l["budget"] or not l["reached"], "%s: %d triangles over %d" % (l["name"], l["triangles"], l["budget"]))
    pos, tris = read_ply(stem + ".ply")
    need(len(tris) == l["triangles"], "%s: %d triangles in the PLY, %d reported" % (l["name"], len(tris), l["triangles"]))
    missing = sum(p not in ids for p in pos)
    need(missing == 0, "%s: %d vertices are not input points" % (l["name"], missing))
    if not closed or missing:
        continue
    chi, boundary, nonmanifold = topology(tris)
    need(boundary == 0 and nonmanifold == 0, "%s: %d boundary, %d non-manifold edges" % (l["name"], boundary, nonmanifold))
    need(l["watertight"], l["name"] + ": watertight in the report")
    need(chi == in_chi, "%s: Euler characteristic %d, input %d" % (l["name"], chi, in_chi))
    turned = 0  # a triangle facing away from every input triangle at its corners
    for t in tris:
        n = cross(sub(pos[t[1]], pos[t[0]]), sub(pos[t[2]], pos[t[0]]))
        turned += all(dot(n, m) <= 0 for v in t for m in around[ids[pos[v]]])
    need(turned == 0, "%s: %d triangles turned over" % (l["name"], turned))
print("\n".join(bad))
EOF
for item in cow.ply fandisk.ply bun_zipper_res4.ply; do
  kind=closed; [ "$item" = bun_zipper_res4.ply ] && kind=open
  problems=$(python3 "$TMP/check.py" "$TMP/ref-out" "$TMP/in/$item" "$item" "$kind")
  check "$item: published levels as the report says (${problems:-ok})" [ -z "$problems" ]
done
check "the collection summary names the method" grep -q "| segment |" "$TMP/ref-out/summary.md"
check "summary.html names the method" bash -c 'grep -q "levels made by segment" "$1" && ! grep -q "made by cluster" "$1"' _ "$TMP/ref-out/summary.html"
if gltf_validator_ready; then
  mapfile -t glbs < <(find "$TMP/ref-out" -name '*.glb' | sort)
  set +e
  node "$SCANLOD_SOURCE_DIR/scripts/gltf/validate.mjs" "${glbs[@]}" >"$TMP/glb.jsonl" 2>"$TMP/glb.err"
  vrc=$?
  set -e
  check "validator on ${#glbs[@]} GLBs: exit 0 ($(head -c 300 "$TMP/glb.err"))" [ "$vrc" -eq 0 ]
  check "every GLB 0 errors" [ "$(grep -c '"numErrors":0,' "$TMP/glb.jsonl")" -eq "${#glbs[@]}" ]
else
  echo "note: node and the glTF validator are not installed: GLBs not validated" >&2
fi
run_scanlod run "$TMP/ref.ini" -q -s lod.method=segment
check "a second run has nothing to do ($out $err)" contains "nothing to do" "$out$err"

write_config "$TMP/kill.ini" "$TMP/in" "$TMP/work" "$TMP/out" "${lines[@]}"
unverified=0
for k in $(seq 1 "$kills"); do
  delay_ms=$(( (RANDOM * 32768 + RANDOM) % (clean_ns / 1000000 + 1) ))
  "$SCANLOD" run "$TMP/kill.ini" -q -s lod.method=segment >/dev/null 2>&1 &
  pid=$!
  sleep "$(printf '%d.%03d' $((delay_ms / 1000)) $((delay_ms % 1000)))"
  kill -9 "$pid" 2>/dev/null || true
  wait "$pid" 2>/dev/null || true
  run_scanlod verify "$TMP/kill.ini" -s lod.method=segment
  [ "$rc" -eq 0 ] || { unverified=$((unverified + 1)); echo "verify after kill $k: $out $err" >&2; }
done
check "every record verified after every kill ($unverified failures)" [ "$unverified" -eq 0 ]
run_scanlod run "$TMP/kill.ini" -q -s lod.method=segment
check "resume after $kills kills exits 0 (got $rc: $err)" [ "$rc" -eq 0 ]
check "resumed artifacts and publications byte-identical to the clean run" \
  same_digest "$ref" "$TMP/work" "$TMP/out"
finish
