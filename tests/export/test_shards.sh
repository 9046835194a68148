#!/usr/bin/env bash
# Shards ([refine] min_part_area, stages/refine/refine_shards.c), in paper 1's mode (the
# octree's own cuts: [levels] expansions, top = method, no collapse or fit): cow's coarse octree levels
# break into pieces (its 2000-triangle thumb into 11: horn tips and specks cut loose by
# cells coarser than the horns). With the default the finest level, one body, is
# published as drawn and every coarser level leaves out the parts under 1 % of its area:
# each then holds together (one part, or its largest with >= 99 % of the area), the
# report says what went (the parts dropped are the parts missing), a budget level spends
# what it lost on the body (within 5 % of its budget, never above it), the closed levels
# stay watertight, and with min_part_area = 0 (paper 1) every level is as before. Only
# parts the rest covers go ([refine] shard_reach, 2 mean edges): the thumb keeps a horn
# tip farther out, which shard_reach = 1e9 (any distance) drops. cow's finest level is
# above its input's count: the cap is off, so k100 is the finest level (test_cap.sh).
source "$(dirname "$0")/../lib.sh"

mkdir -p "$TMP/in"
cp "$SCANS/cow.ply" "$TMP/in/"
for m in 0 default far; do
  extra=()
  [ "$m" = 0 ] && extra=("min_part_area = 0")
  [ "$m" = far ] && extra=("shard_reach = 1e9")
  write_config "$TMP/$m.ini" "$TMP/in" "$TMP/work-$m" "$TMP/out-$m" "[lod]" "method = octree" \
    "[levels]" "percents =" "expansions = 20,40,60,80,100" "top = method" "oversample = 1" \
    "[refine]" "collapse = false" "fit = false" "cap_at_input = false" "${extra[@]}" \
    "[export]" "formats = ply" "thumbnail_size = 0" "fidelity = false"
  run_scanlod run "$TMP/$m.ini" -q
  check "run with min_part_area $m exits 0 (got $rc: $err)" [ "$rc" -eq 0 ]
done

set +e
python3 - "$TMP/out-0/cow.ply" "$TMP/out-default/cow.ply" "$TMP/out-far/cow.ply" <<'PY'
import json, os, sys
def levels(folder):
    stages = json.load(open(os.path.join(folder, "report.json")))["stages"]
    r = stages["export"]
    out = {lv["name"]: lv for lv in r["levels"]}
    for lv in stages["refine"]["levels"]:  # the cut's shards: the refine stage's report
        out[lv["name"]]["shards_dropped"] = lv["candidates"][0]["shards_dropped"]
    return out, r["expansions"]
plain, last = levels(sys.argv[1])
kept, _ = levels(sys.argv[2])
bad = 0
def check(ok, what):
    global bad
    print(("ok: " if ok else "FAIL: ") + what, file=sys.stderr)
    bad += not ok
check(plain["thumb"]["components"] > 3,
      "without the rule cow's thumb is in pieces (%d parts)" % plain["thumb"]["components"])
check(plain["thumb"]["shards_dropped"]["parts"] == 0, "min_part_area = 0 drops no shards")
for name, lv in kept.items():
    p = plain[name]
    if lv["expansions"] >= last:
        check(lv["triangles"] == p["triangles"] and lv["shards_dropped"]["parts"] == 0,
              "%s (the finest level) is published as drawn" % name)
        continue
    d = lv["shards_dropped"]
    check(lv["components"] == 1 or lv["largest_component_area_fraction"] >= 0.99,
          "%s holds together: %d parts, the largest %.4f" % (name, lv["components"],
                                                           lv["largest_component_area_fraction"]))
    check(lv["watertight"] or not p["watertight"], "%s stays watertight" % name)
    if "lod_percent" not in lv and "expansion_percent" not in lv:
        check(lv["triangles"] <= lv["budget"] and
              (lv["triangles"] >= 0.95 * min(lv["budget"], p["triangles"]) or lv["clamped"]),
              "%s: %d triangles for a budget of %d" % (name, lv["triangles"], lv["budget"]))
    elif lv["expansions"] == p["expansions"]:
        check(p["components"] - d["parts"] == lv["components"] and
              p["triangles"] - d["triangles"] == lv["triangles"],
              "%s: %d parts - %d dropped = %d, %d triangles - %d = %d" % (
                  name, p["components"], d["parts"], lv["components"], p["triangles"],
                  d["triangles"], lv["triangles"]))
far, _ = levels(sys.argv[3])
check(far["thumb"]["components"] == 1 and kept["thumb"]["components"] > 1,
      "the thumb keeps a part the body does not cover (%d parts; %d at any reach)" % (
          kept["thumb"]["components"], far["thumb"]["components"]))
sys.exit(1 if bad else 0)
PY
check "the levels hold together and the report says what went" [ $? -eq 0 ]
set -e
cmp -s "$TMP/out-0/cow.ply/k100.ply" "$TMP/out-default/cow.ply/k100.ply"
check "k100.ply is byte-identical with and without the rule" [ $? -eq 0 ]
# Every kept level is a valid mesh on its own.
run_scanlod compare "$SCANS/cow.ply" "$TMP/out-default/cow.ply/thumb.ply" --samples 20000 --json
check "the thumb reads back (compare exits $rc)" [ "$rc" -eq 0 ]
finish
