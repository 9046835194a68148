#!/usr/bin/env bash
# What a curator sees (issue 36, "Looked at"): the default config's published levels next
# to `gltfpack -si` at the same triangle count, rendered by the same three.js page in
# headless Chromium, with both measured against the input by `scanlod compare`.
#
#   scripts/bench/look_vs_gltfpack.sh [--build DIR] [--out DIR] [--items "lucy_100kf nefertiti"]
#                                     [--levels "low thumb"]
#
# Per item: one `scanlod run` with the default config; for each level, gltfpack 1.3.0
# (pinned in peers/npm) simplifies the scan (welded, as scanlod's top level publishes it)
# to the level's share of its triangles (`-si`, no quantisation). Both meshes go through
# the same path to the renderer (OBJ, then `gltfpack -noq` without simplification, turned
# upright when the item's up axis is z), so the pictures differ only in the meshes.
# Positions only, not the export's float GLBs as bench_glb_size.sh gives its peers: with
# the GLB's normals gltfpack -si stops above small counts (lucy's 2,000-triangle thumb:
# 5,238), and the comparison is at equal counts.
# Writes OUT/ITEM-LEVEL-{scanlod,gltfpack}.png and OUT/look.md (counts, RMS and Hausdorff
# in % of the diagonal, 200000 samples). Not part of CI (a minute per item on 2 cores).
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
build=$root/build out="" items="lucy_100kf nefertiti" levels="low thumb"
while [ $# -gt 0 ]; do
  case $1 in
    --build) build=$2; shift ;;
    --out) out=$2; shift ;;
    --items) items=$2; shift ;;
    --levels) levels=$2; shift ;;
    -h|--help) sed -n '2,15p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
    *) echo "look_vs_gltfpack.sh: unknown argument $1" >&2; exit 64 ;;
  esac
  shift
done
data=${SCANLOD_SHARED_DATA:-$root/../shared/data}
[ -d "$data" ] || { echo "look_vs_gltfpack.sh: no shared scans at $data" >&2; exit 64; }
scanlod=$build/cli/scanlod
[ -x "$scanlod" ] || { echo "look_vs_gltfpack.sh: no scanlod at $scanlod (scripts/build.sh $build)" >&2; exit 64; }
out=${out:-$build/bench-results/look}
peers=$here/peers/npm
[ -x "$peers/node_modules/.bin/gltfpack" ] || npm ci --prefix "$peers" --no-audit --no-fund --loglevel=error
[ -d "$root/scripts/viewer/node_modules" ] || npm ci --prefix "$root/scripts/viewer" --no-audit --no-fund --loglevel=error
GP=$peers/node_modules/.bin/gltfpack
render=$root/scripts/viewer/render.cjs
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
mkdir -p "$out" "$work/in"
for item in $items; do cp "$data/$item.ply" "$work/in/"; done
printf '[run]\ninput = in\nwork = work\noutput = out\n' >"$work/look.ini"
(cd "$work" && "$scanlod" run look.ini -q)

# PLY (binary, as scanlod writes it) to OBJ, turned from z up to y up when asked.
cat >"$work/ply2obj.py" <<'EOF'
import re, struct, sys
src, dst, up = sys.argv[1], sys.argv[2], sys.argv[3]
d = open(src, "rb").read()
end = d.index(b"end_header\n") + len(b"end_header\n")
h = d[:end].decode()
nv = int(re.search(r"element vertex (\d+)", h).group(1))
nf = int(re.search(r"element face (\d+)", h).group(1))
props = re.findall(r"property (float|uchar) (\w+)", h.split("element face")[0])
fmt = "<" + "".join("f" if t == "float" else "B" for t, _ in props)
size = struct.calcsize(fmt)
with open(dst, "w") as o:
    p = end
    for _ in range(nv):
        x, y, z = struct.unpack_from(fmt, d, p)[:3]
        p += size
        o.write("v %.9g %.9g %.9g\n" % ((x, z, -y) if up == "z" else (x, y, z)))
    for _ in range(nf):
        n = d[p]
        i = struct.unpack_from("<%di" % n, d, p + 1)
        p += 1 + 4 * n
        o.write("f %d %d %d\n" % (i[0] + 1, i[1] + 1, i[2] + 1))
EOF
measure() { # INPUT MESH: "triangles rms% hausdorff%"
  "$scanlod" compare "$1" "$2" --samples 200000 --json | python3 -c "
import json, sys; j = json.load(sys.stdin)
print(j['b_triangles'], '%.4f' % (100 * j['rms']), '%.4f' % (100 * j['hausdorff']))"
}
{
  echo "| item | level | scanlod triangles | RMS % | Hausdorff % | gltfpack -si triangles | RMS % | Hausdorff % | RMS ratio |"
  echo "|---|---|---:|---:|---:|---:|---:|---:|---:|"
} >"$out/look.md"
for item in $items; do
  pub=$work/out/$item.ply
  up=$(python3 -c "
import json; r = json.load(open('$pub/report.json'))['stages']['export']
print(r.get('frame', {}).get('up', 'y'))")
  top=$(python3 -c "
import json; r = json.load(open('$pub/report.json'))['stages']['export']['levels']
print(max(l['triangles'] for l in r))")
  python3 "$work/ply2obj.py" "$pub/lod100.ply" "$work/$item.obj" "$up"
  for level in $levels; do
    n=$(python3 -c "
import json; r = json.load(open('$pub/report.json'))['stages']['export']['levels']
print([l for l in r if l['name'] == '$level'][0]['triangles'])")
    python3 "$work/ply2obj.py" "$pub/$level.ply" "$work/$item-$level.obj" "$up"
    "$GP" -i "$work/$item-$level.obj" -o "$work/$item-$level-scanlod.glb" -noq >/dev/null
    "$GP" -i "$work/$item.obj" -o "$work/$item-$level-gltfpack.glb" -noq \
      -si "$(python3 -c "print($n / $top)")" >/dev/null
    row="| $item | $level"
    for who in scanlod gltfpack; do
      node "$render" "$work/$item-$level-$who.glb" "$out/$item-$level-$who.png" front >/dev/null
      read -r t rms hd < <(measure "$data/$item.ply" "$work/$item-$level-$who.glb")
      row="$row | $t | $rms | $hd"
      eval "rms_$who=$rms"
    done
    echo "$row | $(python3 -c "print('%.2f' % ($rms_scanlod / $rms_gltfpack))") |" >>"$out/look.md"
  done
done
cat "$out/look.md"
echo "pictures in $out"
