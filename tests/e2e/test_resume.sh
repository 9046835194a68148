#!/usr/bin/env bash
# Resume and invalidation (reliability T13): a rerun after completion does no work and
# says so; `touch` does no work; one changed byte reruns that item only; a changed
# [range] key reruns range for every item and nothing else; a corrupted artifact is
# detected by its hash and rebuilt; a deleted publication is republished.
source "$(dirname "$0")/../lib.sh"

mkdir -p "$TMP/in/sub"
cp "$SCANS/bun_zipper_res4.ply" "$TMP/in/a.ply"
cp "$SCANS/cow.ply" "$TMP/in/sub/b.ply"
cp "$SCANS/bun_zipper_res3.ply" "$TMP/in/c.ply"
cfg="$TMP/c.ini"
write_config "$cfg" "$TMP/in" "$TMP/work" "$TMP/out"

run_scanlod run "$cfg" -q
check "first run exits 0 (got $rc: $err)" [ "$rc" -eq 0 ]
check "three items published" [ -f "$TMP/out/a.ply/report.json" -a -f "$TMP/out/sub/b.ply/report.json" -a -f "$TMP/out/c.ply/report.json" ]
check "item id is the input path" grep -q '"item": "sub/b.ply"' "$TMP/out/sub/b.ply/report.json"
ref=$(tree_digest "$TMP/work" "$TMP/out")
run_scanlod status "$cfg"
stages=$(( $(wc -l <<<"$out") - 1 ))
check "status lists the stages ($stages)" [ "$stages" -ge 1 ]

run_scanlod run "$cfg" -q
check "rerun exits 0" [ "$rc" -eq 0 ]
check "rerun says nothing to do (got: $out)" grep -q "^nothing to do: 3 items up to date" <<<"$out"

touch "$TMP/in/a.ply" "$TMP/in/sub/b.ply"
run_scanlod run "$cfg" -q
check "touch: nothing to do (got: $out)" grep -q "^nothing to do" <<<"$out"

cp -p "$TMP/in/c.ply" "$TMP/in/c.tmp" && mv "$TMP/in/c.tmp" "$TMP/in/c.ply"
run_scanlod run "$cfg" -q
check "copy (new inode): nothing to do (got: $out)" grep -q "^nothing to do" <<<"$out"
check "digest unchanged after touch/copy" [ "$ref" = "$(tree_digest "$TMP/work" "$TMP/out")" ]

# One changed byte: the first coordinate of bun_zipper_res4 (ascii) gets another digit.
sed -i '0,/^-0.0312216/s//-0.0312217/' "$TMP/in/a.ply"
run_scanlod run "$cfg" -q
check "changed byte reruns that item only (got: $out)" grep -q "^3 items: $stages stage runs, .* 1 published" <<<"$out"

# Corrupt one artifact byte: detected by hash, rebuilt, identical again.
art=$(find "$TMP/work/artifacts/range" -name points.slpts | head -n 1)
printf 'X' | dd of="$art" bs=1 seek=100 conv=notrunc status=none
run_scanlod run "$cfg" -q
check "corrupted artifact rebuilt (got: $out)" grep -qE "^3 items: [1-9][0-9]* stage runs" <<<"$out"

# A [range] key that does not change range's outputs on meshes (knn is for point clouds):
# range reruns everywhere, later stages see identical upstream bytes and do not.
run_scanlod run "$cfg" -q -s range.knn=13
check "changed [range] key reruns range for all 3, nothing else (got: $out)" grep -q "^3 items: 3 stage runs" <<<"$out"
run_scanlod run "$cfg" -q -s range.knn=13
check "same key again: nothing to do (got: $out)" grep -q "^nothing to do" <<<"$out"
run_scanlod run "$cfg" -q -s range.knn=13 -s run.threads=1 -s run.log_level=debug
check "[run] keys are not stage keys: nothing to do (got: $out)" grep -q "^nothing to do" <<<"$out"
# One that changes range's outputs (range images are written): every stage reruns.
run_scanlod run "$cfg" -q -s range.knn=13 -s range.range_images=true
check "range output change reruns every stage of every item (got: $out)" grep -q "^3 items: $((3 * stages)) stage runs, .* 3 published" <<<"$out"

rm -rf "$TMP/out/sub/b.ply"
run_scanlod run "$cfg" -q
check "deleted publication republished (rc $rc)" [ -f "$TMP/out/sub/b.ply/report.json" ]

run_scanlod status "$cfg"
check "status shows 3 done in every stage" [ "$(grep -cE '^[a-z]+ +0 +0 +3 +0 +0$' <<<"$out")" -eq "$stages" ]
finish
