#!/usr/bin/env bash
# Textured GLB sizes against gltfpack (issue 37): the bundled textured cow and the real
# textured scans of ../shared/data/textured (OBJ + MTL + JPG, glTF + BIN + JPG, GLB, Draco
# GLB) converted in one `scanlod run` with the default config, then, per published level,
# `gltfpack -cc -si R` on the same input file with R = the level's share of the input's
# triangles (meshopt compression and quantisation, as scanlod's default GLB; gltfpack keeps
# the input's image bytes as they are). Where gltfpack stops above the count (it keeps UV
# seams whole), it runs again with -sa (its "aggressive" mode) and both are listed.
# gltfpack reads no Draco: the Draco inputs (food vessel, sea turtle, usnm, venus) reach it
# decoded by `gltf-transform dequantize` (@gltf-transform/cli 4.5.1, pinned beside it).
#
#   scripts/bench/bench_textured.sh [--build DIR] [--out DIR]
#
# gltfpack reads OBJ and glTF, not PLY: the cow goes to it as an OBJ + MTL written from
# its PLY (positions, texture coordinates, faces). Writes OUT/textured.md (the table
# docs/benchmarks.md quotes) and OUT/textured.json; OUT defaults to
# DIR/bench-results/textured. Not part of CI (about ten minutes on 2 cores).
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
build=$root/build out=""
while [ $# -gt 0 ]; do
  case $1 in
    --build) build=$2; shift ;;
    --out) out=$2; shift ;;
    -h|--help) sed -n '2,16p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
    *) echo "bench_textured.sh: unknown argument $1" >&2; exit 64 ;;
  esac
  shift
done
data=${SCANLOD_SHARED_DATA:-$root/../shared/data}
[ -d "$data/textured" ] || { echo "bench_textured.sh: no textured scans at $data/textured" >&2; exit 64; }
build=$(cd "$build" 2>/dev/null && pwd) || { echo "bench_textured.sh: no build folder (scripts/build.sh)" >&2; exit 64; }
scanlod=$build/cli/scanlod
[ -x "$scanlod" ] || { echo "bench_textured.sh: no scanlod at $scanlod (scripts/build.sh $build)" >&2; exit 64; }
out=${out:-$build/bench-results/textured}
peers=$here/peers/npm
if [ ! -x "$peers/node_modules/.bin/gltfpack" ] || [ ! -x "$peers/node_modules/.bin/gltf-transform" ]; then
  npm ci --prefix "$peers" --no-audit --no-fund --loglevel=error
fi
GP=$peers/node_modules/.bin/gltfpack GT=$peers/node_modules/.bin/gltf-transform
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
mkdir -p "$out" "$work/in"

# The collection: one folder per scan, as a museum keeps them (the E57, the STL and the
# point cloud of these folders have no texture and are left out).
cp "$root/tests/data/textured/cow_textured.ply" "$root/tests/data/textured/cow_texture.png" "$work/in/"
t=$data/textured
# take FOLDER FILES...: the scan's files into in/FOLDER, or a note when this copy of the
# shared data lacks them (the table then has no rows for it).
take() {
  local folder=$1; shift
  if ls "$@" >/dev/null 2>&1; then
    mkdir -p "$work/in/$folder" && cp "$@" "$work/in/$folder/"
  else
    echo "bench_textured.sh: $folder: not in $t on this machine, left out" >&2
  fi
}
take mask_gltf "$t"/mask_bali_blm/*.gltf "$t"/mask_bali_blm/*.bin "$t"/mask_bali_blm/*.jpg
take mask_obj "$t"/mask_bali_blm_obj/*
take food_vessel "$t"/gui_food_vessel_mia/*.gltf "$t"/gui_food_vessel_mia/*.bin \
  "$t"/gui_food_vessel_mia/*.jpg "$t"/gui_food_vessel_mia/*.png
take venus "$t"/venus_noe3d/*.gltf "$t"/venus_noe3d/*.bin "$t"/venus_noe3d/*.jpg
take sea_turtle "$t"/sea_turtle_nmnh/sea_turtle-150k-2048-medium.glb
take usnm "$t"/usnm_1145291/*.glb
printf '[run]\ninput = in\nwork = work\noutput = out\n' >"$work/bench.ini"
start=$SECONDS
(cd "$work" && "$scanlod" run bench.ini -q)
echo "bench_textured.sh: scanlod run $((SECONDS - start)) s" >&2

# The cow for gltfpack: OBJ + MTL from its PLY (binary little-endian, as the bundled file).
python3 - "$work/in/cow_textured.ply" "$work/cow.obj" <<'EOF'
import re, struct, sys, os
src, dst = sys.argv[1], sys.argv[2]
d = open(src, "rb").read()
end = d.index(b"end_header\n") + len(b"end_header\n")
h = d[:end].decode()
image = re.search(r"comment TextureFile (\S+)", h).group(1)
nv = int(re.search(r"element vertex (\d+)", h).group(1))
nf = int(re.search(r"element face (\d+)", h).group(1))
props = re.findall(r"property (float|double|uchar) (\w+)", h.split("element face")[0])
size = {"float": 4, "double": 8, "uchar": 1}
code = {"float": "f", "double": "d", "uchar": "B"}
fmt = "<" + "".join(code[t] for t, _ in props)
names = [n for _, n in props]
row = struct.calcsize(fmt)
assert "binary_little_endian" in h and "list uchar int" in h, "cow PLY layout changed"
with open(dst, "w") as o:
    o.write("mtllib cow.mtl\nusemtl m\n")
    uv = []
    for i in range(nv):
        v = dict(zip(names, struct.unpack_from(fmt, d, end + i * row)))
        o.write("v %.9g %.9g %.9g\n" % (v["x"], v["y"], v["z"]))
        uv.append((v["texture_u"], v["texture_v"]))
    for s, t in uv:
        o.write("vt %.9g %.9g\n" % (s, t))
    at = end + nv * row
    for _ in range(nf):
        n = d[at]
        idx = struct.unpack_from("<%di" % n, d, at + 1)
        at += 1 + 4 * n
        o.write("f " + " ".join("%d/%d" % (k + 1, k + 1) for k in idx) + "\n")
open(os.path.join(os.path.dirname(dst), "cow.mtl"), "w").write("newmtl m\nmap_Kd %s\n" % image)
EOF
cp "$work/in/cow_texture.png" "$work/"

python3 - "$work" "$GP" "$GT" "$out" <<'EOF'
import glob, json, os, re, struct, subprocess, sys
work, gp, gt, out = sys.argv[1:5]

def glb_json(path):
    """The JSON chunk of a GLB."""
    d = open(path, "rb").read()
    return json.loads(d[20:20 + struct.unpack("<I", d[12:16])[0]])

def glb_triangles(path):
    """Triangles of a GLB's primitives (from the index accessors' counts)."""
    j = glb_json(path)
    return sum(j["accessors"][p["indices"]]["count"] // 3
               for m in j["meshes"] for p in m["primitives"])

def gltf_extensions(path):
    if path.endswith(".gltf"):
        return json.load(open(path)).get("extensionsUsed", [])
    if path.endswith(".glb"):
        return glb_json(path).get("extensionsUsed", [])
    return []

def texture_kind(t):
    """baked, input (the scan's coordinates kept) or projected (coordinates from the
    input's), with the image's edge where it was scaled down to the level's size."""
    kind = "projected" if t.get("texcoords") == "projected" else t.get("source")
    return kind + (" %d px" % t["size"] if kind == "projected" and t.get("size") else "")

decoded = {}
def peer_input(src):
    """gltfpack reads no Draco: such a file goes to it decoded by gltf-transform (its
    dequantize writes plain float attributes; the image bytes stay the input's)."""
    if "KHR_draco_mesh_compression" not in gltf_extensions(src):
        return src
    if src not in decoded:
        dst = os.path.join(work, "decoded-%d.glb" % len(decoded))
        subprocess.run([gt, "dequantize", src, dst], check=True, capture_output=True)
        decoded[src] = dst
    return decoded[src]

def peer(src, ratio, dst, aggressive):
    cmd = [gp, "-i", peer_input(src), "-o", dst, "-cc", "-si", "%.6f" % min(1.0, ratio)]
    if aggressive:
        cmd.append("-sa")
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode != 0:
        return None
    return os.path.getsize(dst), glb_triangles(dst)

rows = []
for report in sorted(glob.glob(os.path.join(work, "out", "**", "report.json"), recursive=True)):
    r = json.load(open(report))
    item = r["item"]
    folder = os.path.dirname(report)
    src = os.path.join(work, "in", item)
    if item.endswith(".ply"):
        src = os.path.join(work, "cow.obj")
    ex = r["stages"]["export"]
    for lv in ex["levels"]:
        if lv.get("file") != lv["name"] or not lv.get("triangles"):
            continue
        ours = os.path.join(folder, lv["name"] + ".glb")
        ratio = lv["triangles"] / ex["input_triangles"]
        row = {"item": item, "level": lv["name"], "triangles": lv["triangles"],
               "input_triangles": ex["input_triangles"], "bytes": os.path.getsize(ours),
               "texture": texture_kind(lv.get("texture") or {}),
               "image_bytes": (lv.get("texture") or {}).get("image_bytes")}
        p = peer(src, ratio, os.path.join(work, "peer.glb"), False)
        row["gltfpack"] = p and {"bytes": p[0], "triangles": p[1]}
        if p and p[1] > 1.05 * lv["triangles"]:
            a = peer(src, ratio, os.path.join(work, "peer.glb"), True)
            row["gltfpack_sa"] = a and {"bytes": a[0], "triangles": a[1]}
        rows.append(row)

json.dump(rows, open(os.path.join(out, "textured.json"), "w"), indent=1)
lines = ["| item | level | triangles | scanlod bytes | texture | gltfpack -si bytes (triangles) "
         "| gltfpack -si -sa bytes (triangles) | ratio at equal count |", "|---|---|---|---|---|---|---|---|"]
for w in rows:
    g, a = w["gltfpack"], w.get("gltfpack_sa")
    # The peer's file at the count: plain -si when it reached it, else -sa when that did.
    at = g if g and g["triangles"] <= 1.05 * w["triangles"] else \
         a if a and a["triangles"] <= 1.05 * w["triangles"] else None
    ratio = "%.2f" % (w["bytes"] / at["bytes"]) if at else "peer missed the count"
    fmt = lambda p: "%d (%d)" % (p["bytes"], p["triangles"]) if p else "-"
    lines.append("| %s | %s | %d | %d | %s | %s | %s | %s |" % (
        w["item"], w["level"], w["triangles"], w["bytes"], w["texture"], fmt(g), fmt(a), ratio))
open(os.path.join(out, "textured.md"), "w").write("\n".join(lines) + "\n")
print("\n".join(lines))
EOF
echo "bench_textured.sh: $out/textured.md" >&2
