#!/usr/bin/env bash
# GLB sizes against the peers users compare with (issue 15): per level of nefertiti and
# igea, scanlod's meshopt GLB against `gltfpack -cc` and scanlod's Draco GLB against
# `gltf-transform draco`, each peer given the same level mesh (scanlod's float,
# uncompressed GLB of that level), plus the quantisation error scanlod reports.
#
#   scripts/bench/bench_glb_size.sh [--build DIR] [--out DIR] [--items "nefertiti igea"]
#
# The peers are pinned in scripts/bench/peers/npm/package-lock.json (gltfpack 1.3.0,
# @gltf-transform/cli 4.5.1) and installed there with `npm ci` on first use. Writes
# OUT/glb_size.md (the table docs/glb.md quotes) and OUT/glb_size.json; OUT defaults to
# DIR/bench-results/glb_size. Not part of CI (a few minutes on 2 cores).
# gltf-transform's Draco defaults quantise normals to 10 bits where scanlod and gltfpack
# use 8, so its file is also made with --quantize-normal 8 (the same bits as ours).
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
build=$root/build-bench out="" items="nefertiti igea"
while [ $# -gt 0 ]; do
  case $1 in
    --build) build=$2; shift ;;
    --out) out=$2; shift ;;
    --items) items=$2; shift ;;
    -h|--help) sed -n '2,16p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
    *) echo "bench_glb_size.sh: unknown argument $1" >&2; exit 64 ;;
  esac
  shift
done
data=${SCANLOD_SHARED_DATA:-$root/../shared/data}
[ -d "$data" ] || { echo "bench_glb_size.sh: no shared scans at $data" >&2; exit 64; }
out=${out:-$build/bench-results/glb_size}
peers=$here/peers/npm
if [ ! -x "$peers/node_modules/.bin/gltfpack" ] || [ ! -x "$peers/node_modules/.bin/gltf-transform" ]; then
  npm ci --prefix "$peers" --no-audit --no-fund --loglevel=error
fi
GP=$peers/node_modules/.bin/gltfpack GT=$peers/node_modules/.bin/gltf-transform
if [ ! -f "$build/CMakeCache.txt" ]; then # a new tree is Release; an existing one is kept
  gen=()
  command -v ninja >/dev/null && gen=(-G Ninja)
  cmake -S "$root" -B "$build" "${gen[@]}" -DCMAKE_BUILD_TYPE=Release >/dev/null
fi
cmake --build "$build" --parallel "$(nproc)" --target scanlod >/dev/null
scanlod=$build/cli/scanlod
work=$(mktemp -d "${TMPDIR:-/tmp}/bench-glb.XXXXXX")
trap 'rm -rf "$work"' EXIT
mkdir -p "$out"

frame_of() { # the units and up axis of the shared scans (docs/glb.md; the files do not say)
  case $1 in
    nefertiti) echo "-s export.units=mm -s export.up=z" ;;
    *) echo "" ;;
  esac
}
for item in $items; do
  [ -f "$data/$item.ply" ] || { echo "bench_glb_size.sh: no $data/$item.ply" >&2; exit 64; }
  mkdir -p "$work/in/$item"
  ln -s "$data/$item.ply" "$work/in/$item/$item.ply"
  for mode in float meshopt draco; do
    case $mode in
      float) set -- -s export.compression=none -s export.quantize=false -s export.fidelity=false ;;
      meshopt) set -- -s export.compression=meshopt ;;   # fidelity on: the error with the bound
      draco) set -- -s export.compression=draco -s export.fidelity=false ;;
    esac
    printf '[run]\ninput = %s\nwork = %s\noutput = %s\nlogs = %s\n[export]\nformats = glb\nthumbnail_size = 0\n' \
      "$work/in/$item" "$work/work-$item-$mode" "$work/out-$item-$mode" "$work/logs" >"$work/$item-$mode.ini"
    # shellcheck disable=SC2046
    "$scanlod" run "$work/$item-$mode.ini" -q "$@" $(frame_of "$item") >/dev/null
  done
  for glb in "$work/out-$item-float/$item.ply"/*.glb; do
    level=$(basename "$glb" .glb)
    "$GP" -i "$glb" -o "$work/$item-$level.gltfpack.glb" -cc >/dev/null
    "$GT" draco "$glb" "$work/$item-$level.gt_draco.glb" >/dev/null
    "$GT" draco --quantize-normal 8 "$glb" "$work/$item-$level.gt_draco8.glb" >/dev/null
  done
done

python3 - "$work" "$out" $items <<'EOF'
import json, os, sys
work, out, items = sys.argv[1], sys.argv[2], sys.argv[3:]
size = lambda p: os.path.getsize(p)
order = ["thumb", "low", "medium", "high", "lod20", "lod40", "lod60", "lod80", "lod100"]
rows = []
for item in items:
    rep = lambda mode: json.load(open(f"{work}/out-{item}-{mode}/{item}.ply/report.json"))["stages"]["export"]
    meshopt, draco = rep("meshopt"), rep("draco")
    frame = meshopt["frame"]
    levels = {l["name"]: l for l in meshopt["levels"]}
    for name in sorted(levels, key=lambda n: order.index(n) if n in order else 99):
        l, d = levels[name], {x["name"]: x for x in draco["levels"]}[name]
        f = lambda mode, n=name: f"{work}/out-{item}-{mode}/{item}.ply/{n}.glb"
        r = {"item": item, "level": name, "triangles": l["triangles"], "float": size(f("float")),
             "meshopt": size(f("meshopt")), "gltfpack": size(f"{work}/{item}-{name}.gltfpack.glb"),
             "draco": size(f("draco")), "gt_draco": size(f"{work}/{item}-{name}.gt_draco.glb"),
             "gt_draco8": size(f"{work}/{item}-{name}.gt_draco8.glb"),
             "units": frame["units"], "bound": l["glb"]["quantization_bound"],
             "error": l["glb"]["quantization_error"], "bound_world": l["glb"]["quantization_bound_world"],
             "error_world": l["glb"]["quantization_error_world"],
             "draco_error": d["glb"]["quantization_error_world"],
             "normal_deg": l["glb"]["normal_error_deg"], "draco_normal_deg": d["glb"]["normal_error_deg"],
             "hausdorff": l["hausdorff"], "glb_hausdorff": l["glb"]["hausdorff"]}
        rows.append(r)
json.dump(rows, open(f"{out}/glb_size.json", "w"), indent=1)
with open(f"{out}/glb_size.md", "w") as md:
    md.write("| item | level | triangles | float GLB | scanlod meshopt | gltfpack -cc | ratio | "
             "scanlod Draco | gltf-transform Draco | ratio | same bits (8-bit normals) | ratio |\n"
             "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n")
    for r in rows:
        md.write(f"| {r['item']} | {r['level']} | {r['triangles']} | {r['float']} | {r['meshopt']} | "
                 f"{r['gltfpack']} | {r['meshopt'] / r['gltfpack']:.3f} | {r['draco']} | "
                 f"{r['gt_draco']} | {r['draco'] / r['gt_draco']:.3f} | {r['gt_draco8']} | "
                 f"{r['draco'] / r['gt_draco8']:.3f} |\n")
    md.write("\nQuantisation (14-bit positions, 8-bit normals): the bound sqrt(3)/2 x step and the "
             "largest vertex displacement measured on the decoded file, in the input's units and in "
             "% of the input's bounding-box diagonal; Hausdorff of the level before and after "
             "adding the bound.\n\n"
             "| item | level | units | bound | measured (meshopt) | measured (Draco) | bound % | "
             "measured % | normals max deg (meshopt / Draco) | Hausdorff % | + bound % |\n"
             "|---|---|---|---:|---:|---:|---:|---:|---:|---:|---:|\n")
    for r in rows:
        md.write(f"| {r['item']} | {r['level']} | {r['units']} | {r['bound_world']:.4g} | "
                 f"{r['error_world']:.4g} | {r['draco_error']:.4g} | {100 * r['bound']:.5f} | "
                 f"{100 * r['error']:.5f} | {r['normal_deg']:.2f} / {r['draco_normal_deg']:.2f} | "
                 f"{100 * r['hausdorff']:.4f} | {100 * r['glb_hausdorff']:.4f} |\n")
    worst_m = max(r["meshopt"] / r["gltfpack"] for r in rows)
    worst_d = max(r["draco"] / r["gt_draco"] for r in rows)
    md.write(f"\nWorst ratios: meshopt / gltfpack -cc {worst_m:.3f}, Draco / gltf-transform "
             f"{worst_d:.3f} (aim <= 1.2).\n")
print(open(f"{out}/glb_size.md").read())
EOF
echo "bench_glb_size: wrote $out/glb_size.md and $out/glb_size.json"
