#!/usr/bin/env bash
# Poison batch (reliability T7/T9/T15): good scans mixed with hostile files. Each bad file
# gets one clear error naming it and its cause, is quarantined at once (not retried), the
# good items still finish, the batch exits 65, and nothing takes long or much memory.
source "$(dirname "$0")/../lib.sh"

in="$TMP/in"
mkdir -p "$in/bad"
cp "$SCANS/bun_zipper_res4.ply" "$SCANS/cow.ply" "$in/"
: >"$in/bad/empty.ply"
printf 'this is not a ply file\n' >"$in/bad/garbage.ply"
printf 'ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n0 0 0\n' >"$in/bad/no_end_header.ply"
printf 'ply\nformat binary_little_endian 1.0\nelement vertex 4294967295\nproperty float x\nproperty float y\nproperty float z\nend_header\n0123456789' >"$in/bad/huge_count.ply"
printf 'ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n' >"$in/bad/index_out_of_range.ply"
printf 'ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\nnan 0 0\ninf 0 0\nnan nan nan\n3 0 1 2\n' >"$in/bad/all_nan.ply"
printf 'ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uint int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n4294967295 0 1 2\n' >"$in/bad/huge_list.ply"
# Finite but astronomically far: it would pass every stage to the octree, whose readers
# refuse a grid beyond 1e15 units (the next run would retry it forever).
printf 'ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n3e16 0 0\n3e16 1 0\n3e16 0 1\n3 0 1 2\n' >"$in/bad/far_away.ply"
head -c 60000 "$SCANS/cow.ply" >"$in/bad/truncated.ply"
bad_count=$(find "$in/bad" -name '*.ply' | wc -l)

write_config "$TMP/c.ini" "$in" "$TMP/work" "$TMP/out"
start=$(date +%s)
run_scanlod run "$TMP/c.ini"
elapsed=$(( $(date +%s) - start ))
check "batch exits 65 (got $rc)" [ "$rc" -eq 65 ]
check "good items published" [ -f "$TMP/out/cow.ply/report.json" -a -f "$TMP/out/bun_zipper_res4.ply/report.json" ]
check "no bad item published" [ ! -e "$TMP/out/bad" ]
check "batch took < 60 s ($elapsed)" [ "$elapsed" -lt 60 ]
for f in "$in"/bad/*.ply; do
  name=$(basename "$f")
  n=$(grep -c "quarantined: .*$name" <<<"$err" || true)
  check "one quarantine line naming $name (got $n)" [ "$n" -eq 1 ]
done
check "empty file cause" grep -q "empty.ply: .*empty" <<<"$err"
check "huge count cause names the count" grep -q "huge_count.ply: .*4294967295" <<<"$err"
check "index cause names the index" grep -qi "index_out_of_range.ply: .*7" <<<"$err"
check "far coordinates cause names the reach" grep -q "far_away.ply: coordinates reach 3e+16" <<<"$err"

run_scanlod status "$TMP/c.ini"
check "status: $bad_count quarantined, 2 done" grep -qE "^range +0 +0 +2 +0 +$bad_count\$" <<<"$out"
check "status lists each reason" [ "$(grep -c 'quarantine (badinput)' <<<"$out")" -eq "$bad_count" ]

run_scanlod run "$TMP/c.ini" -q
check "rerun: quarantined inputs are not retried, exit 65 (got $rc)" [ "$rc" -eq 65 ]
check "rerun does no work (got: $out)" grep -q "^nothing to do" <<<"$out"

# A fixed input leaves quarantine on the next run.
cp "$SCANS/cow.ply" "$in/bad/truncated.ply"
run_scanlod run "$TMP/c.ini" -q
check "repaired input is rebuilt and published" [ -f "$TMP/out/bad/truncated.ply/report.json" ]

# Within the range stage's limit, but a leaf this coarse makes an octree grid beyond what
# the readers take: the merge stage quarantines it rather than write a file the next
# stage would refuse on every run.
mkdir -p "$TMP/far"
printf 'ply\nformat ascii 1.0\nelement vertex 6\nproperty float x\nproperty float y\nproperty float z\nelement face 8\nproperty list uchar int vertex_indices\nend_header\n6e13 0 0\n-6e13 0 0\n0 6e13 0\n0 -6e13 0\n0 0 6e13\n0 0 -6e13\n3 0 2 4\n3 2 1 4\n3 1 3 4\n3 3 0 4\n3 2 0 5\n3 1 2 5\n3 3 1 5\n3 0 3 5\n' >"$TMP/far/octahedron.ply"
write_config "$TMP/far.ini" "$TMP/far" "$TMP/wfar" "$TMP/ofar" '[octree]' 'leaf_size = 4e13' '[samples]' 'band = 8'
run_scanlod run "$TMP/far.ini"
check "coarse grid beyond the readers' limit: exit 65 (got $rc)" [ "$rc" -eq 65 ]
check "merge quarantines it with the cause (got: $err)" grep -q "\[merge\] octahedron.ply: quarantined: .*reaches beyond" <<<"$err"
run_scanlod run "$TMP/far.ini" -q
check "and does not retry it (got $rc: $out)" grep -q "^nothing to do" <<<"$out"

# A one-point cloud passes the range stage; the samples stage finds no spacing to size the
# grid by. The quarantine is about the input, and names it: it named range's work
# artifact, .../work/artifacts/range/one.ply/points.slpts (issue 34 item 6).
mkdir -p "$TMP/one"
printf 'ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\nend_header\n0 0 0\n' >"$TMP/one/one.ply"
write_config "$TMP/one.ini" "$TMP/one" "$TMP/wone" "$TMP/oone"
run_scanlod run "$TMP/one.ini"
check "one point: exit 65 (got $rc)" [ "$rc" -eq 65 ]
check "one point: the quarantine names the input (got: $err)" \
  grep -q "\[samples\] one.ply: quarantined: $TMP/one/one.ply: mean point spacing is 0" <<<"$err"
check "one point: and no work artifact" bash -c '! grep -q "points.slpts" <<<"$1"' _ "$err"

# Bad config: unknown key -> exit 78 with file:line.
printf '[run]\ninput = %s\nwork = %s\noutput = %s\n[range]\nno_such_key = 1\n' "$in" "$TMP/w2" "$TMP/o2" >"$TMP/bad.ini"
run_scanlod run "$TMP/bad.ini"
check "unknown key exits 78 (got $rc)" [ "$rc" -eq 78 ]
check "unknown key error has file:line (got: $err)" grep -q "bad.ini:6:" <<<"$err"
run_scanlod run "$TMP/c.ini" -s range.knn=abc
check "bad -s value exits 78 (got $rc)" [ "$rc" -eq 78 ]
run_scanlod run
check "missing config argument exits 64 (got $rc)" [ "$rc" -eq 64 ]
run_scanlod run "$TMP/nonexistent.ini"
check "missing config file exits 78 (got $rc)" [ "$rc" -eq 78 ]
finish
