#!/usr/bin/env bash
# The GLBs the export stage publishes, in every compression mode: a coloured copy of the
# bundled cow stored Z-up in centimetres (header comments `units cm`, `up z`) goes
# through the pipeline with compression meshopt, draco, none (quantised) and none
# (float). Every published GLB passes the Khronos validator with 0 errors and 0 warnings
# (compressed ones: only the infos the validator gives for extensions it cannot read), and
# glb_check decodes each one and compares it with the PLY of the same level: every vertex
# within the reported quantisation bound once the PLY is put in metres +Y up, the
# bounding boxes alike, the same triangle count, every colour the PLY's sRGB byte within
# 1/255 after linear -> sRGB. The report names the frame it took from the header and
# adds the bound to the level's error; the thumbnail of the Z-up cow matches the one of
# the same cow stored Y-up in metres (upright, same framing).
source "$(dirname "$0")/../lib.sh"
export PYTHONDONTWRITEBYTECODE=1 # png_pixels.py: no __pycache__ in the source tree
gltf="$SCANLOD_SOURCE_DIR/scripts/gltf"
glb_check="${SCANLOD_BUILD_DIR:?}/tests/glb_check"
gltf_validator_ready || { echo "FAIL: the glTF validator is not installed (scripts/install-deps.sh)" >&2; exit 1; }

# cow.ply (binary LE: float x y z, uchar-int faces) -> coloured ASCII copies: cow_z (Z-up,
# cm: (x, y, z) -> 100 (x, -z, y)) and cow_y (as it is, metres, stated in the header).
mkdir -p "$TMP/in_z" "$TMP/in_y"
python3 - "$SCANS/cow.ply" "$TMP/in_z/cow.ply" "$TMP/in_y/cow.ply" <<'EOF'
import struct, sys
data = open(sys.argv[1], "rb").read()
body = data[data.index(b"end_header\n") + 11:]
nv, nf = 2904, 5804
v = [struct.unpack_from("<3f", body, 12 * i) for i in range(nv)]
off, faces = 12 * nv, []
for _ in range(nf):
    n = body[off]; faces.append(struct.unpack_from("<%di" % n, body, off + 1)); off += 1 + 4 * n
lo = [min(p[k] for p in v) for k in range(3)]; hi = [max(p[k] for p in v) for k in range(3)]
def color(p):  # a smooth ramp over the box, every channel covering dark and light tones
    t = [(p[k] - lo[k]) / (hi[k] - lo[k]) for k in range(3)]
    return [int(round(255 * t[0] ** 2)), int(round(255 * t[1])), int(round(255 * (1 - t[2]) ** 3))]
for path, units, up, tf in ((sys.argv[2], "cm", "z", lambda p: (100 * p[0], -100 * p[2], 100 * p[1])),
                            (sys.argv[3], "m", "y", lambda p: p)):
    with open(path, "w") as f:
        f.write("ply\nformat ascii 1.0\ncomment coloured copy of tests/data/scans/cow.ply\n"
                "comment units %s\ncomment up %s\nelement vertex %d\nproperty float x\n"
                "property float y\nproperty float z\nproperty uchar red\nproperty uchar green\n"
                "property uchar blue\nelement face %d\nproperty list uchar int vertex_indices\n"
                "end_header\n" % (units, up, nv, nf))
        for p in v:
            q = tf(p)
            f.write("%.9g %.9g %.9g %d %d %d\n" % (q + tuple(color(p))))
        for t in faces:
            f.write("%d %s\n" % (len(t), " ".join(map(str, t))))
EOF

run_mode() { # run_mode NAME INPUT compression quantize fidelity
  write_config "$TMP/$1.ini" "$2" "$TMP/work-$1" "$TMP/out-$1" "[levels]" "percents = 30,100" \
    "budgets = thumb:800" "[export]" "formats = ply,glb" "thumbnail_size = 96" "fidelity = $5" \
    "fidelity_samples = 20000" "compression = $3" "quantize = $4"
  run_scanlod run "$TMP/$1.ini" -q
  check "$1: run exits 0 (got $rc: ${err:0:300})" [ "$rc" -eq 0 ]
}
run_mode meshopt "$TMP/in_z" meshopt true true
run_mode draco "$TMP/in_z" draco true false
run_mode quantized "$TMP/in_z" none true false
run_mode float "$TMP/in_z" none false false
run_mode upright "$TMP/in_y" meshopt true false

report() { # report MODE PYTHON-EXPRESSION-ON-e (the export section)
  python3 -c "import json; e=json.load(open('$TMP/out-$1/cow.ply/report.json'))['stages']['export']; print($2)"
}
for mode in meshopt draco quantized float; do
  dir="$TMP/out-$mode/cow.ply"
  mapfile -t glbs < <(find "$dir" -name '*.glb' | sort)
  check "$mode: three GLBs published (${#glbs[@]})" [ "${#glbs[@]}" -eq 3 ]
  set +e
  node "$gltf/validate.mjs" --infos "${glbs[@]}" >"$TMP/$mode.jsonl" 2>"$TMP/$mode.err"
  vrc=$?
  set -e
  check "$mode: validator exit 0 ($(head -c 300 "$TMP/$mode.err"))" [ "$vrc" -eq 0 ]
  check "$mode: every GLB 0 errors, 0 warnings" \
    [ "$(grep -c '"numErrors":0,"numWarnings":0,' "$TMP/$mode.jsonl")" -eq "${#glbs[@]}" ]
  infos=$(grep -o '"code":"[A-Z_]*"' "$TMP/$mode.jsonl" | sort -u | tr '\n' ' ' || true)
  case $mode in
    meshopt|draco) check "$mode: infos only UNSUPPORTED_EXTENSION/UNUSED_OBJECT ($infos)" \
                     [ "$infos" = '"code":"UNSUPPORTED_EXTENSION" "code":"UNUSED_OBJECT" ' ] ;;
    *) check "$mode: no infos ($infos)" [ -z "$infos" ] ;;
  esac
  frame=$(report "$mode" "e['frame']['units'], e['frame']['units_from'], e['frame']['up'], e['frame']['up_from']")
  check "$mode: frame from the file's header ($frame)" [ "$frame" = "cm file z file" ]
  for name in lod30 lod100 thumb; do
    bound=$(report "$mode" "[l for l in e['levels'] if l['name']=='$name'][0]['glb']['quantization_bound_world'] * 0.01")
    # float positions: only the mm -> m rounding of a float
    [ "$mode" = float ] && bound=1e-6
    check "$mode $name: decoded GLB = the level's PLY (metres, Y-up, colours)" \
      "$glb_check" "$dir/$name.glb" "$dir/$name.ply" 0.01 z "$bound"
  done
done
# The bound is in the level's reported error.
added=$(report meshopt "all(abs(l['glb']['hausdorff'] - l['hausdorff'] - l['glb']['quantization_bound']) < 1e-9 and l['glb']['max_error'] > l.get('max_error', 0) and l['glb']['quantization_error'] <= l['glb']['quantization_bound'] for l in e['levels'])")
check "meshopt: the quantisation bound is added to hausdorff and max_error" [ "$added" = True ]
# Upright thumbnails: the Z-up cow and the Y-up cow look alike.
diff=$(PYTHONPATH="$SCANLOD_SOURCE_DIR/tests/export" python3 - "$TMP/out-meshopt/cow.ply/lod100.png" \
  "$TMP/out-upright/cow.ply/lod100.png" <<'EOF'
import sys, png_pixels
a, b = png_pixels.read(sys.argv[1]), png_pixels.read(sys.argv[2])
total = sum(abs(x - y) for ra, rb in zip(a, b) for pa, pb in zip(ra, rb) for x, y in zip(pa, pb))
print(total / (3 * len(a) * len(a[0])))
EOF
)
check "the Z-up cow's thumbnail is the Y-up cow's (mean |difference| $diff / 255)" \
  python3 -c "import sys; sys.exit(0 if $diff < 4 else 1)"
finish
