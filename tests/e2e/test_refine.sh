#!/usr/bin/env bash
# The published levels (docs/levels.md, issue 36): with the default config ([lod] method =
# best) every level asked by a count or a share has that many triangles within 1 % (never
# above), a closed input's levels stay watertight, a level whose input is one body holds
# together (its largest part >= 99 % of the area), the top rung is the scan itself, and
# the refine stage's report lists each candidate (method, count, RMS, Hausdorff, topology)
# with the chosen one first by the rule of docs/levels.md (reached its count, keeps the
# input's one body and closed surface, then the least RMS); each candidate's seconds are
# in timings.json, not in report.json. The refined levels are closer to the input than
# paper 1's own cuts at the same counts. Each method alone, refined, meets every count.
# Inputs: cow and rocker_arm (closed), fandisk (closed, sharp), bun_zipper_res3 (open,
# holes, non-manifold edges). SCANLOD_LIGHT=1: cow and rocker_arm.
source "$(dirname "$0")/../lib.sh"

scans=(cow rocker_arm fandisk bun_zipper_res3)
light && scans=(cow rocker_arm)
mkdir -p "$TMP/in"
for s in "${scans[@]}"; do cp "$SCANS/$s.ply" "$TMP/in/"; done
ladder=("[levels]" "percents = 100" "budgets = b1:1%,b5:5%,b20:20%,thumb:500")
export_lines=("[export]" "formats = ply" "thumbnail_size = 0" "fidelity_samples = 50000")
write_config "$TMP/best.ini" "$TMP/in" "$TMP/work-best" "$TMP/out-best" "${ladder[@]}" \
  "${export_lines[@]}"
run_scanlod run "$TMP/best.ini" -q
check "default config: run exits 0 (got $rc: $err)" [ "$rc" -eq 0 ]
# Paper 1's own cuts at the same counts, for the comparison.
write_config "$TMP/paper.ini" "$TMP/in" "$TMP/work-paper" "$TMP/out-paper" "[lod]" \
  "method = octree" "${ladder[@]}" "top = method" "oversample = 1" "[refine]" "collapse = false" "fit = false" \
  "${export_lines[@]}"
run_scanlod run "$TMP/paper.ini" -q
check "paper 1's cuts: run exits 0 (got $rc: $err)" [ "$rc" -eq 0 ]

cat >"$TMP/check.py" <<'EOF'
import json, os, sys
out, paper, item, scan_ply = sys.argv[1], sys.argv[2], sys.argv[3], sys.argv[4]
def stages(folder):
    return json.load(open(os.path.join(folder, item, "report.json")))["stages"]
s, p = stages(out), stages(paper)
bad, outranked = [], []
def need(ok, what):
    if not ok:
        bad.append(what)
n = s["refine"]["input_triangles"]
levels = {l["name"]: l for l in s["export"]["levels"]}
plain = {l["name"]: l for l in p["export"]["levels"]}
top = levels["lod100"]
one_body = top["largest_component_area_fraction"] >= 0.99  # the scan's: the input's
need(top["scan"] and top["method"] == "scan" and top["triangles"] == n,
     "lod100 is the scan (%s, %d of %d triangles)" % (top["method"], top["triangles"], n))
need(top["rms"] < 1e-9, "the scan's RMS to itself is 0 (%g)" % top["rms"])
for name in ("b1", "b5", "b20", "thumb"):
    l = levels[name]
    b = l["budget"]
    need(l["triangles"] <= b and l["triangles"] >= 0.99 * b,
         "%s: %d triangles for %d" % (name, l["triangles"], b))
    if top["watertight"]:
        need(l["watertight"], "%s: watertight like the input" % name)
    if one_body:
        need(l["largest_component_area_fraction"] >= 0.99, "%s: in one piece (%.3f)" % (
            name, l["largest_component_area_fraction"]))
    if name in plain and plain[name]["triangles"] > 0:
        ratio = l["rms"] / plain[name]["rms"]
        need(ratio < 1, "%s: RMS %.3g of paper 1's cut's at %d triangles" % (
            name, ratio, plain[name]["triangles"]))
for r in s["refine"]["levels"]:
    c = r.get("candidates", [])
    if not c:
        continue
    need(all("rms" in x and "hausdorff" in x and "triangles" in x for x in c),
         "%s: every candidate measured" % r["name"])
    chosen = [x for x in c if x["chosen"]]
    def rank(x):
        keeps = 2 * (one_body and x["largest_part"] >= 0.99) + (top["watertight"] and x["watertight"])
        return (x["triangles"] <= 1.01 * r["budget"], keeps, -x["rms"])
    need(len(chosen) == 1 and rank(chosen[0]) == max(rank(x) for x in c),
         "%s: the chosen candidate comes first by the rule (%s)" % (r["name"], c))
    need("seconds" not in json.dumps(c), "%s: no time in the report" % r["name"])
    # A candidate left uncollapsed (outranked) was measured with all its triangles past 1.5
    # times the scan collapsed, or past it when the scan is within [refine] fit_floor
    # (default 1e-5): never chosen, above the count.
    scan = [x for x in c if x["method"] == "scan"]
    for x in c:
        if x.get("outranked"):
            lead = scan[0].get("rms_before_fit", scan[0]["rms"]) if scan else None
            need(not x["chosen"] and x["triangles"] > r["budget"] and lead is not None and
                 (x["rms"] > 1.5 * lead or (lead <= 1e-5 and x["rms"] > lead)),
                 "%s: %s outranked by the scan (%s)" % (r["name"], x["method"], c))
            outranked.append(r["name"])
        # Measured before its collapse and collapsed after it: came above the count, left
        # at it (the figure the rule judged, docs/levels.md).
        if "rms_before_collapse" in x:
            need(not x.get("outranked") and x["base_triangles"] > r["budget"] and
                 x["triangles"] <= 1.01 * r["budget"] and x["rms_before_collapse"] > 0,
                 "%s: %s measured before its collapse (%s)" % (r["name"], x["method"], x))
t = json.load(open(os.path.join(out, item, "timings.json")))["stages"]["refine"]
need(all(len(v) >= 1 for v in t.get("detail", {"x": []}).values()) and t.get("detail"),
     "timings.json gives each candidate's seconds")
print("\n".join(bad))
with open(os.path.join(os.path.dirname(out), "outranked.txt"), "a") as f:
    f.write("".join("%s %s\n" % (item, n) for n in outranked))
EOF
for s in "${scans[@]}"; do
  problems=$(python3 "$TMP/check.py" "$TMP/out-best" "$TMP/out-paper" "$s.ply" "$SCANS/$s.ply")
  check "$s: levels as asked, whole and closer than paper 1's cuts (${problems:-ok})" [ -z "$problems" ]
done
check "some octree cut was left uncollapsed, outranked by the scan ($(wc -l <"$TMP/outranked.txt"))" \
  [ -s "$TMP/outranked.txt" ]

# Each method alone, refined: every count met within 1 % (segment and cluster stop above
# the small ones on their own; octree cuts never land on a count exactly; on the open,
# non-manifold bun_zipper_res3 the collapse keeping the topology stops above 1 and 5 %:
# [refine] relax_topology, tests/e2e/test_refine_open.sh).
for method in octree segment cluster; do
  write_config "$TMP/$method.ini" "$TMP/in" "$TMP/work-$method" "$TMP/out-$method" \
    "[lod]" "method = $method" "[segment]" "search_samples = 0" "${ladder[@]}" "${export_lines[@]}"
  run_scanlod run "$TMP/$method.ini" -q
  check "$method: run exits 0 (got $rc: $err)" [ "$rc" -eq 0 ]
  for s in "${scans[@]}"; do
    counts=$(python3 - "$TMP/out-$method/$s.ply/report.json" <<'EOF'
import json, sys
r = json.load(open(sys.argv[1]))["stages"]["export"]["levels"]
print(" ".join("%s:%d/%d" % (l["name"], l["triangles"], l["budget"]) for l in r
               if l["name"] != "lod100" and not (l["budget"] * 0.99 <= l["triangles"] <= l["budget"])))
EOF
)
    check "$method $s: every count met (${counts:-all})" [ -z "$counts" ]
  done
done
# [refine] fit_floor: a chosen level measured within it of the input is not fitted, one
# above it is (measured before the fit, under one method alone too). The same items at a
# floor between their levels' errors (the earlier stages reused from the runs above): both kinds must show.
cat >"$TMP/floor.py" <<'EOF'
import json, os, sys
out, floor, kinds, bad = sys.argv[1], float(sys.argv[2]), set(), []
spared = 0
for s in sys.argv[3:]:
    for r in json.load(open(os.path.join(out, s + ".ply", "report.json")))["stages"]["refine"]["levels"]:
        # Under the floor a scan lead outranks any candidate farther before its collapse:
        # none such is collapsed (docs/levels.md "Choice").
        scan = [c for c in r.get("candidates", []) if c["method"] == "scan"]
        lead = scan[0].get("rms_before_fit", scan[0]["rms"]) if scan else None
        for c in r.get("candidates", []):
            if lead is not None and lead <= floor and c is not scan[0] and \
                    scan[0]["triangles"] <= 1.01 * r["budget"]:
                if c.get("rms_before_collapse", 0) > lead:
                    bad.append("%s %s: %s collapsed from %.3g past the scan's %.3g" %
                               (s, r["name"], c["method"], c["rms_before_collapse"], lead))
                spared += bool(c.get("outranked")) and c["rms"] <= 1.5 * lead
        for c in r.get("candidates", []):
            if c["chosen"] and "rms_before_fit" not in c:
                kinds.add(c["fitted"])
                if c["fitted"] != (c["rms"] > floor):
                    bad.append("%s %s: rms %.3g, fitted %s" % (s, r["name"], c["rms"], c["fitted"]))
want = {False} if floor >= 1 else {True, False}  # a floor of 1: nothing is fitted
if kinds != want:
    bad.append("fitted levels %s expected, saw %s" % (sorted(want), sorted(kinds)))
print("; ".join(bad))
print("%d" % spared)
EOF
# Floors between the levels' errors on cow and rocker_arm (the light set): best's b20 on
# rocker_arm is 2.3e-4 of the diagonal, the cluster's b20 4.5e-4 and 1.3e-3, their b5 and
# b1 above.
for method_floor in best:3e-4 cluster:1.5e-3; do
  method=${method_floor%%:*} at=${method_floor#*:}
  write_config "$TMP/floor-$method.ini" "$TMP/in" "$TMP/work-$method" "$TMP/out-floor-$method" \
    "[lod]" "method = $method" "${ladder[@]}" "${export_lines[@]}" "[refine]" "fit_floor = $at"
  run_scanlod run "$TMP/floor-$method.ini" -q
  check "$method, fit_floor $at: run exits 0 (got $rc: $err)" [ "$rc" -eq 0 ]
  floor=$(python3 "$TMP/floor.py" "$TMP/out-floor-$method" "$at" "${scans[@]}")
  spared=$(tail -n 1 <<<"$floor") floor=$(head -n 1 <<<"$floor")
  check "$method: fitted exactly the levels above the floor, no candidate collapsed past a scan under it (${floor:-ok})" [ -z "$floor" ]
  echo "$method, fit_floor $at: $spared candidates left uncollapsed within 1.5 times a scan under the floor"
done
# A floor above every error: no level is fitted, and a candidate farther than the scan
# before its collapse is left uncollapsed even within 1.5 times of it (rocker_arm's b1:
# the octree's cut 1.11 times the scan's RMS).
write_config "$TMP/floor-all.ini" "$TMP/in" "$TMP/work-best" "$TMP/out-floor-all" \
  "${ladder[@]}" "${export_lines[@]}" "[refine]" "fit_floor = 1"
run_scanlod run "$TMP/floor-all.ini" -q
check "fit_floor 1: run exits 0 (got $rc: $err)" [ "$rc" -eq 0 ]
floor=$(python3 "$TMP/floor.py" "$TMP/out-floor-all" 1 "${scans[@]}")
spared=$(tail -n 1 <<<"$floor") floor=$(head -n 1 <<<"$floor")
check "fit_floor 1: nothing fitted, no candidate collapsed past a scan (${floor:-ok})" [ -z "$floor" ]
check "fit_floor 1: some candidate within 1.5 times the scan left uncollapsed ($spared)" \
  [ "$spared" -gt 0 ]

# [refine] collapse_brick_triangles: the scan's collapses by bricks of 1,000 triangles
# (several bricks and passes on every scan here): every count still met, a closed input's
# levels still closed, one body still one, each level's RMS within 1.3 times the whole collapse's
# (measured: docs/simplify.md "By bricks"); the earlier stages reused.
write_config "$TMP/bricks.ini" "$TMP/in" "$TMP/work-best" "$TMP/out-bricks" "${ladder[@]}" \
  "${export_lines[@]}" "[refine]" "collapse_brick_triangles = 1000"
run_scanlod run "$TMP/bricks.ini" -q
check "bricked collapse: run exits 0 (got $rc: $err)" [ "$rc" -eq 0 ]
bricked=$(python3 - "$TMP/out-best" "$TMP/out-bricks" "${scans[@]}" <<'EOF'
import json, os, sys
whole, bricks, bad = sys.argv[1], sys.argv[2], []
for s in sys.argv[3:]:
    lv = lambda d: {l["name"]: l for l in json.load(open(os.path.join(d, s + ".ply", "report.json")))["stages"]["export"]["levels"]}
    w, b = lv(whole), lv(bricks)
    for name in ("b1", "b5", "b20", "thumb"):
        x, y = w[name], b[name]
        if not (y["budget"] * 0.99 <= y["triangles"] <= y["budget"]):
            bad.append("%s %s: %d for %d" % (s, name, y["triangles"], y["budget"]))
        if w["lod100"]["watertight"] and not y["watertight"]:  # a closed input's
            bad.append("%s %s: not watertight" % (s, name))
        if x["largest_component_area_fraction"] >= 0.99 > y["largest_component_area_fraction"]:
            bad.append("%s %s: broke apart" % (s, name))
        if y["rms"] > 1.3 * x["rms"] + 1e-7:
            bad.append("%s %s: rms %.3g, whole %.3g" % (s, name, y["rms"], x["rms"]))
print("; ".join(bad))
EOF
)
check "bricked collapse: counts, topology and RMS as the whole's (${bricked:-ok})" [ -z "$bricked" ]
# The brick size each refine report says it used: the default's is chosen by the memory
# budget (collapse_brick_triangles = -1: these scans need a few MB, so whole: 0), the set one
# is the config's.
brick_sizes() { # brick_sizes OUT: each scan's refine collapse_brick_triangles
  for s in "${scans[@]}"; do
    python3 -c 'import json,sys; print(json.load(open(sys.argv[1]))["stages"]["refine"].get("collapse_brick_triangles"))' \
      "$1/$s.ply/report.json"
  done | sort -u | tr '\n' ' '
}
check "the default's collapses whole by the budget (said: $(brick_sizes "$TMP/out-best"))" \
  [ "$(brick_sizes "$TMP/out-best")" = "0 " ]
check "the config's bricks said (said: $(brick_sizes "$TMP/out-bricks"))" \
  [ "$(brick_sizes "$TMP/out-bricks")" = "1000 " ]

# [refine] octree_max_share: beside the scan simplified, a level above 30 % of the input
# gets no octree candidate (its cut was never within 1.76 times of the scan's RMS there,
# docs/levels.md) and one at or below it does; at 1, every level gets one. The earlier
# stages reused.
share_ladder=("[levels]" "percents = 100" "budgets = b50:50%,b20:20%")
for share in default 1; do
  extra=(); [ "$share" = default ] || extra=("[refine]" "octree_max_share = $share")
  write_config "$TMP/share-$share.ini" "$TMP/in" "$TMP/work-best" "$TMP/out-share-$share" \
    "${share_ladder[@]}" "${export_lines[@]}" "${extra[@]}"
  run_scanlod run "$TMP/share-$share.ini" -q
  check "octree_max_share $share: run exits 0 (got $rc: $err)" [ "$rc" -eq 0 ]
  made=$(python3 - "$TMP/out-share-$share" "${scans[@]}" <<'EOF'
import json, os, sys
seen = set()
for s in sys.argv[2:]:
    for r in json.load(open(os.path.join(sys.argv[1], s + ".ply", "report.json")))["stages"]["refine"]["levels"]:
        if r["name"] in ("b50", "b20"):
            seen.add("%s:%s" % (r["name"], "+".join(sorted(c["method"] for c in r["candidates"]))))
            if not (r["budget"] * 0.99 <= r["triangles"] <= r["budget"]):
                seen.add("%s-%s-missed:%d/%d" % (s, r["name"], r["triangles"], r["budget"]))
print(" ".join(sorted(seen)))
EOF
)
  if [ "$share" = default ]; then want="b20:octree+scan b50:scan"; else want="b20:octree+scan b50:octree+scan"; fi
  check "octree_max_share $share: candidates per level ($made; want $want)" [ "$made" = "$want" ]
done

# The paper's mode needs each method's own level at its count: collapse off with the
# default oversample would leave levels at twice their counts, so it is refused.
run_scanlod run "$TMP/best.ini" -q -s refine.collapse=false
check "collapse off with oversample 2: a config error naming the key (rc $rc: $err)" \
  [ "$rc" -eq 78 ] && contains "\[refine\] collapse = false needs \[levels\] oversample = 1" "$err"
finish
