#!/usr/bin/env bash
# What the scan makes of an input tree a user really has (issue 16 items 1, 3, 4, 8):
# an item beside a folder of the same name, folders of the run inside one another, a
# symlink loop, names with a newline, hidden files, FIFOs, links to devices and to
# nothing, a missing input folder. Every entry is either an item (published, or
# quarantined with its reason) or skipped with a log line; nothing is silently lost and
# no publication ever removes another item's files.
source "$(dirname "$0")/../lib.sh"

items_published() { # the item ids (JSON strings) of every published report.json under $1
  find "$1" -name report.json ! -path '*/.*' -exec python3 -c \
    'import json,sys; [print(json.dumps(json.load(open(p))["item"])) for p in sys.argv[1:]]' {} + | sort
}

# 1. An item beside a folder of the same name: a.ply and a/b.ply are two items whose
# published folders are disjoint, and republishing a (a.ply changed) keeps a/b whole.
mkdir -p "$TMP/nest/a"
cp "$SCANS/bun_zipper_res4.ply" "$TMP/nest/a.ply"
cp "$SCANS/bun_zipper_res4.ply" "$TMP/nest/a/b.ply"
write_config "$TMP/nest.ini" "$TMP/nest" "$TMP/nest-work" "$TMP/nest-out"
run_scanlod run "$TMP/nest.ini" -q
check "nested ids: first run exits 0 (got $rc: $err)" [ "$rc" -eq 0 ]
cp "$SCANS/cow.ply" "$TMP/nest/a.ply"
run_scanlod run "$TMP/nest.ini" -q
check "nested ids: republishing a exits 0 (got $rc: $err)" [ "$rc" -eq 0 ]
check "nested ids: both items still published" \
  [ "$(items_published "$TMP/nest-out" | tr '\n' ' ')" = '"a.ply" "a/b.ply" ' ]
run_scanlod verify "$TMP/nest.ini"
check "nested ids: verify finds every publication whole (got $rc: $out)" [ "$rc" -eq 0 ]

# 3. The four folders of a run must not contain one another: 78 naming FILE:LINE.
mkdir -p "$TMP/in"
cp "$SCANS/bun_zipper_res4.ply" "$TMP/in/"
trees_case() { # trees_case KEY VALUE [KEY VALUE]: a config whose other folders are apart
  declare -A paths=([input]="$TMP/in" [work]="$TMP/w" [output]="$TMP/o" [logs]="$TMP/logs")
  while [ $# -gt 0 ]; do paths[$1]=$2; shift 2; done
  { echo "[run]"; for k in input work output logs; do echo "$k = ${paths[$k]}"; done; } >"$TMP/trees.ini"
}
for bad in "output $TMP/in" "output $TMP/in/out" "work $TMP/in/work" "logs $TMP/in/logs" \
           "output $TMP/w" "output $TMP"; do
  set -- $bad
  trees_case "$@"
  run_scanlod run "$TMP/trees.ini" -q
  check "$1 = $2: exit 78 (got $rc: $err)" [ "$rc" -eq 78 ]
  check "$1 = $2: the error names the line of a key involved (got: $err)" \
    grep -qE "trees.ini:[2-5]: \[run\] [a-z]+ \(.*\) (is inside|is) \[run\]" <<<"$err"
done
trees_case output "$TMP/in/out"
run_scanlod run "$TMP/trees.ini" -q
check "output inside input: the error names output's line (got: $err)" grep -q "trees.ini:4: \[run\] output" <<<"$err"
check "no item was ever taken from a run's own folders" [ ! -e "$TMP/in/out" -a ! -e "$TMP/in/work" ]
run_scanlod run "$TMP/nest.ini" -q -s "run.output=$TMP/nest/out"
check "-s run.output inside the input: 78 naming the override (got $rc: $err)" \
  grep -q "^scanlod run: -s run.output: \[run\] output" <<<"$err"

# 3. A folder symlink loop is not followed, and says so.
mkdir -p "$TMP/loop/d"
cp "$SCANS/bun_zipper_res4.ply" "$TMP/loop/d/x.ply"
ln -s .. "$TMP/loop/d/up"
ln -s "$SCANS" "$TMP/loop/elsewhere"
write_config "$TMP/loop.ini" "$TMP/loop" "$TMP/loop-work" "$TMP/loop-out"
run_scanlod run "$TMP/loop.ini"
check "symlink loop: exit 0, one item (got $rc: $out)" [ "$rc" -eq 0 ] && grep -q "^1 items" <<<"$out"
check "symlink loop: both folder links skipped, said in the log (got: $err)" \
  [ "$(grep -c 'symbolic link to a folder (not followed); skipped' <<<"$err")" -eq 2 ]
check "symlink loop: the summary counts them" grep -q "2 input entries skipped" <<<"$out"

# 4 and 8. Names that are hard to hold, and entries that are not scans.
mkdir -p "$TMP/odd"
cp "$SCANS/bun_zipper_res4.ply" "$TMP/odd/new
line.ply"
cp "$SCANS/bun_zipper_res4.ply" "$TMP/odd/100%.ply"
cp "$SCANS/bun_zipper_res4.ply" "$TMP/odd/.hidden.ply"
long=$(printf 'n%.0s' $(seq 1 250)).ply
cp "$SCANS/bun_zipper_res4.ply" "$TMP/odd/$long"
mkfifo "$TMP/odd/fifo.ply"
ln -s /dev/null "$TMP/odd/device.ply"
ln -s "$TMP/odd/nothing-here.ply" "$TMP/odd/dangling.ply"
write_config "$TMP/odd.ini" "$TMP/odd" "$TMP/odd-work" "$TMP/odd-out"
run_scanlod run "$TMP/odd.ini"
check "odd names: exit 65 (quarantined inputs), no hang (got $rc: $out)" [ "$rc" -eq 65 ]
published=$(items_published "$TMP/odd-out")
check "a newline in a name: published under its own name" grep -qxF '"new\nline.ply"' <<<"$published"
check "a %-name: published" grep -qxF '"100%.ply"' <<<"$published"
check "a 254-byte name: published" grep -qxF "\"$long\"" <<<"$published"
check "hidden .ply: skipped with a log line (got: $err)" grep -q '\.hidden\.ply: hidden name; skipped' <<<"$err"
run_scanlod status "$TMP/odd.ini"
for name in fifo device dangling; do
  check "$name.ply: quarantined with its reason in status" grep -q "range $name.ply: quarantine (badinput)" <<<"$out"
done
check "FIFO reason" grep -q "fifo.ply: a FIFO, not a regular file" <<<"$out"
check "device reason" grep -q "device.ply: a device, not a regular file" <<<"$out"
check "dangling reason" grep -q "dangling.ply: symbolic link to nothing" <<<"$out"
run_scanlod run "$TMP/odd.ini" -q
check "odd names rerun: nothing to do, still 65 (got $rc: $out)" \
  [ "$rc" -eq 65 ] && grep -q "^nothing to do" <<<"$out"
rm "$TMP/odd/dangling.ply" && cp "$SCANS/bun_zipper_res4.ply" "$TMP/odd/dangling.ply"
run_scanlod run "$TMP/odd.ini" -q
check "a repaired entry leaves quarantine and is published" \
  grep -qxF '"dangling.ply"' <<<"$(items_published "$TMP/odd-out")"

# 8. A missing input folder: 78 with FILE:LINE.
write_config "$TMP/gone.ini" "$TMP/no-such-folder" "$TMP/gw" "$TMP/go"
run_scanlod run "$TMP/gone.ini" -q
check "missing input: exit 78 (got $rc)" [ "$rc" -eq 78 ]
check "missing input: FILE:LINE and the cause (got: $err)" \
  grep -q "gone.ini:2: \[run\] input .*no-such-folder: No such file or directory" <<<"$err"
finish
