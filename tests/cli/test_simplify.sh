#!/usr/bin/env bash
# `scanlod simplify IN.ply --method segment ...`: one mesh, written and described; levels
# within their budget and watertight on a closed scan; bad input is one line
# "scanlod: FILE: cause" and exit 65; bad options exit 64 before anything is read;
# non-manifold edges and a single triangle are handled with a message and exit 0.
source "$(dirname "$0")/../lib.sh"
data="$SCANLOD_SOURCE_DIR/tests/data"
fast=(--search-samples 0)

simplify() { # simplify ARGS...: --method segment ARGS; sets rc, out, err
  set +e
  out=$("$SCANLOD" simplify --method segment "$@" 2>"$TMP/err")
  rc=$?
  set -e
  err=$(cat "$TMP/err")
}
json_field() { # json_field NAME: from $out
  python3 -c "import json,sys; d=json.load(sys.stdin); print(d$1)" <<<"$out"
}
topology() { # topology FILE: watertight of FILE as compare sees it
  "$SCANLOD" compare "$data/scans/fandisk.ply" "$1" --samples 1000 --json |
    python3 -c "import json,sys; print(json.load(sys.stdin)['b_topology']['watertight'])"
}

# --- a closed CAD scan, by ratio, count and bound -------------------------------------
simplify "$data/scans/fandisk.ply" --method segment --ratio 0.1 -o "$TMP/f10.ply" --json "${fast[@]}"
check "fandisk 10 %: exit 0" [ "$rc" -eq 0 ]
check "fandisk 10 %: written" [ -s "$TMP/f10.ply" ]
check "fandisk 10 %: within the budget" [ "$(json_field "['triangles']")" -le 1294 ]
check "fandisk 10 %: near the budget" [ "$(json_field "['triangles']")" -ge 1200 ]
check "fandisk 10 %: method figures" [ "$(json_field "['segment']['watertight']")" = True ]
check "fandisk 10 %: watertight as compare sees it" [ "$(topology "$TMP/f10.ply")" = True ]
check "fandisk 10 %: quiet stderr" [ -z "$err" ]

simplify "$data/scans/fandisk.ply" --triangles 500 -o "$TMP/f500.ply" --json "${fast[@]}"
check "fandisk 500: exit 0" [ "$rc" -eq 0 ]
check "fandisk 500: within" [ "$(json_field "['triangles']")" -le 500 ]

simplify "$data/scans/fandisk.ply" --max-error 0.002 --json
check "fandisk bound: exit 0" [ "$rc" -eq 0 ]
check "fandisk bound: one pass" [ "$(json_field "['segment']['search_passes']")" -eq 1 ]

simplify "$data/scans/fandisk.ply" --ratio 0.1 --rule paper --json
check "rule paper takes no budget: exit 64" [ "$rc" -eq 64 ]
simplify "$data/scans/fandisk.ply" --rule paper --delta-seg 80 --delta-b 20 --json
check "rule paper, one pass: exit 0" [ "$rc" -eq 0 ]
check "rule paper: removes vertices" [ "$(json_field "['segment']['removed_vertices']")" -gt 0 ]

simplify "$data/scans/cow.ply" --ratio 0.3 --segment-map "$TMP/map.ply" "${fast[@]}"
check "segment map: exit 0" [ "$rc" -eq 0 ]
check "segment map: written" [ -s "$TMP/map.ply" ]
check "table output on stdout" grep -q "triangles (segment)" <<<"$out"

# --- input the method handles with a message ------------------------------------------
printf 'ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n' >"$TMP/one.ply"
simplify "$TMP/one.ply" --ratio 0.5 -o "$TMP/one_out.ply" "${fast[@]}"
check "one triangle: exit 0" [ "$rc" -eq 0 ]
check "one triangle: says so" grep -q "a single triangle: nothing to simplify" <<<"$err"

# three triangles on one edge (a book) and a plain one: kept as they are, a warning
printf 'ply\nformat ascii 1.0\nelement vertex 6\nproperty float x\nproperty float y\nproperty float z\nelement face 4\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n0 0 1\n1 0 0\n0 1 0\n-1 -1 0\n5 5 5\n3 0 1 2\n3 1 0 3\n3 1 0 4\n3 2 3 5\n' >"$TMP/book.ply"
simplify "$TMP/book.ply" --ratio 0.5 -o "$TMP/book_out.ply" "${fast[@]}"
check "non-manifold edge: exit 0" [ "$rc" -eq 0 ]
check "non-manifold edge: warned" grep -q "1 non-manifold edges (in three or more triangles) kept as they are" <<<"$err"

simplify "$data/scans/bun_zipper_res4.ply" --ratio 0.5 -o "$TMP/b4.ply" --json "${fast[@]}"
check "open scan with non-manifold edges: exit 0" [ "$rc" -eq 0 ]
check "open scan: boundary kept" [ "$(json_field "['segment']['watertight']")" = False ]

# --- bad input: one line, exit 65 ------------------------------------------------------
bad="$data/malformed/vertex_2e32_binary.ply"
simplify "$bad" --ratio 0.5 -o "$TMP/never.ply"
check "malformed: exit 65" [ "$rc" -eq 65 ]
check "malformed: one line" [ "$(wc -l <"$TMP/err")" -eq 1 ]
check "malformed: names the file" grep -q "^scanlod: $bad: " <<<"$err"
check "malformed: nothing written" [ ! -e "$TMP/never.ply" ]

simplify "$TMP/missing.ply" --ratio 0.5
check "missing: exit 65" [ "$rc" -eq 65 ]
check "missing: one line" [ "$err" = "scanlod: $TMP/missing.ply: No such file or directory" ]

printf 'ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nend_header\n0 0 0\n1 0 0\n0 1 0\n' >"$TMP/cloud.ply"
simplify "$TMP/cloud.ply" --ratio 0.5
check "point cloud: exit 65" [ "$rc" -eq 65 ]
check "point cloud: says why" grep -q "point cloud (no faces)" <<<"$err"
check "point cloud: one line" [ "$(wc -l <"$TMP/err")" -eq 1 ]

printf 'ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n0 0 0\n0 0 0\n3 0 1 2\n' >"$TMP/degenerate.ply"
simplify "$TMP/degenerate.ply" --ratio 0.5
check "only degenerate faces: exit 65" [ "$rc" -eq 65 ]
check "only degenerate faces: one line" [ "$(wc -l <"$TMP/err")" -eq 1 ]

# --- usage: exit 64, nothing read -------------------------------------------------------
for args in "--ratio 0" "--ratio 2" "--triangles 0" "--triangles x" "--max-error -1" \
            "--delta-seg 95" "--delta-b 200" "--rule fancy" "--method fancy" \
            "--ratio 0.5 --triangles 9" "--frobnicate"; do
  # shellcheck disable=SC2086
  simplify "$TMP/missing.ply" $args
  check "usage ($args): exit 64" [ "$rc" -eq 64 ]
done
simplify
check "no input: exit 64" [ "$rc" -eq 64 ]
set +e
"$SCANLOD" simplify "$data/scans/fandisk.ply" --ratio 0.1 2>"$TMP/err"
rc=$?
set -e
check "no --method: exit 64, says so" [ "$rc" -eq 64 ] && grep -q "needs --method" "$TMP/err"
simplify --help
check "--help: exit 0" [ "$rc" -eq 0 ]
check "--help: the method's options" grep -q -- "--delta-seg" <<<"$out"
check "--help: both methods" grep -q -- "--intermediates" <<<"$out"

finish
