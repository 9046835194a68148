#!/usr/bin/env bash
# An input replaced by a broken file (issue 15, the last operator-view item): the last
# good derivatives stay published, and every place that shows the item says they are
# stale; the run that quarantines it says so (never "nothing to do"), exits 65; the
# repaired file is published again and nothing is stale any more.
source "$(dirname "$0")/../lib.sh"

mkdir -p "$TMP/in"
cp "$SCANS/bun_zipper_res4.ply" "$SCANS/cow.ply" "$TMP/in/"
write_config "$TMP/c.ini" "$TMP/in" "$TMP/work" "$TMP/out"
run_scanlod run "$TMP/c.ini" -q
check "first run exits 0 (got $rc: $err)" [ "$rc" -eq 0 ]
levels() { (cd "$TMP/out/cow.ply" && sha256sum -- *.ply); }
before=$(levels)
check "cow.ply has published levels" [ -n "$before" ]

# The new version of cow.ply is truncated.
head -c 300 "$SCANS/cow.ply" >"$TMP/in/cow.ply"
run_scanlod run "$TMP/c.ini"
check "the run that quarantines the new version exits 65 (got $rc)" [ "$rc" -eq 65 ]
check "its last line reports the quarantine, not 'nothing to do' ($out)" \
  bash -c '! grep -q "nothing to do" <<<"$1" && grep -q "1 newly quarantined" <<<"$1"' _ "$out"
check "the last good derivatives stay published" \
  [ "$(levels)" = "$before" ]
check "summary.json: cow.ply published, quarantined, marked stale" python3 - "$TMP/out/summary.json" <<'EOF'
import json, sys
s = json.load(open(sys.argv[1]))
published = sorted(r["item"] for r in s["items"])
q = {e["item"]: e for e in s["quarantined"]}
ok = (published == ["bun_zipper_res4.ply", "cow.ply"] and list(q) == ["cow.ply"]
      and q["cow.ply"]["stale_publication"] is True and s["items_stale"] == 1
      and s["items_quarantined"] == 1)
print(published, q, s.get("items_stale"), file=sys.stderr)
sys.exit(0 if ok else 1)
EOF
check "summary.md marks the item's levels stale" grep -q '^> \*\*Stale:\*\* the input of `cow.ply` changed' "$TMP/out/summary.md"
check "summary.md's quarantine list says the levels stay published" \
  grep -q '^- cow.ply (badinput): .*previous version.s levels stay published, marked stale$' "$TMP/out/summary.md"
check "summary.html marks it stale" grep -q '<p class="stale"><strong>Stale:</strong> the input of <code>cow.ply</code>' "$TMP/out/summary.html"
check "bun_zipper_res4.ply is not stale" bash -c '[ "$(grep -c "Stale:" "$1")" -eq 1 ]' _ "$TMP/out/summary.md"
run_scanlod status "$TMP/c.ini"
check "status names the quarantine and the stale publication" \
  grep -q "range cow.ply: quarantine (badinput): .*\[stale: the previous version's levels stay published\]" <<<"$out"
run_scanlod verify "$TMP/c.ini"
check "verify: the stale publication is still whole (got $rc: $out)" [ "$rc" -eq 0 ]

# Repaired: published anew, nothing stale or quarantined.
cp "$SCANS/bun_zipper_res3.ply" "$TMP/in/cow.ply"
run_scanlod run "$TMP/c.ini" -q
check "the repaired input is published (got $rc: $err)" [ "$rc" -eq 0 ]
check "its derivatives are the new version's" \
  [ "$(levels)" != "$before" ]
check "nothing stale or quarantined any more" python3 -c '
import json, sys
s = json.load(open(sys.argv[1]))
sys.exit(0 if s["items_stale"] == 0 and s["quarantined"] == [] else 1)' "$TMP/out/summary.json"
check "summary.md has no stale mark" bash -c '! grep -q "Stale" "$1"' _ "$TMP/out/summary.md"
finish
