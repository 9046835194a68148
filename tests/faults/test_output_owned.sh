#!/usr/bin/env bash
# The publication owns the item's folder whole (issue 34 items 2 and 3): an entry in it
# that no record lists, and anything that is not a folder standing where the item's folder
# (or a folder above it) belongs, is moved aside to OUTPUT/.scanlod-aside/ and logged, so
# `run` and `verify` agree and the next run publishes. Before: a notes.txt made `verify`
# exit 65 on every run while `run` said "nothing to do"; a file named like the item's
# folder made every run exit 75 ("rename failed: Not a directory") while `status` promised
# that the next run would publish it.
source "$(dirname "$0")/../lib.sh"

mkdir -p "$TMP/in/sub"
cp "$SCANS/bun_zipper_res4.ply" "$TMP/in/bunny.ply"
cp "$SCANS/bun_zipper_res4.ply" "$TMP/in/sub/nested.ply"
write_config "$TMP/c.ini" "$TMP/in" "$TMP/work" "$TMP/out"
aside="$TMP/out/.scanlod-aside"
run_scanlod run "$TMP/c.ini" -q
check "built (exit $rc: $err)" [ "$rc" -eq 0 ]
clean=$(tree_digest "$TMP/work" "$TMP/out")

# settled WHAT: run, then verify, both 0, and everything as a clean build left it.
settled() {
  run_scanlod run "$TMP/c.ini" -q
  check "$1: run exits 0 (got $rc: $out $err)" [ "$rc" -eq 0 ]
  check "$1: run says what it moved ($out)" contains "moved aside" "$out"
  run_scanlod verify "$TMP/c.ini"
  check "$1: verify exits 0 after it (got $rc: $out)" [ "$rc" -eq 0 ]
  check "$1: work and output as a clean build's" same_digest "$clean" "$TMP/work" "$TMP/out"
}

# 2. A file and a folder added inside a published folder.
echo "curator's notes" >"$TMP/out/bunny.ply/notes.txt"
mkdir "$TMP/out/bunny.ply/extra"
run_scanlod verify "$TMP/c.ini"
check "verify flags the added file (got $rc: $out)" contains "notes.txt: not part of the publication" "$out"
settled "added file and folder"
check "the file is kept aside, not deleted" grep -qx "curator's notes" "$aside/bunny.ply/notes.txt"
check "the folder is kept aside" [ -d "$aside/bunny.ply/extra" ]
check "the log names where it went" grep -q "moved aside: $TMP/out/bunny.ply/notes.txt -> $aside/bunny.ply/notes.txt" "$TMP"/logs/*.log

# 3. A file where the item's folder belongs, then a link to elsewhere, then a file where a
# folder above an item belongs.
rm -rf "$TMP/out/bunny.ply"
echo x >"$TMP/out/bunny.ply"
run_scanlod status "$TMP/c.ini"
settled "a file in the item folder's place"
check "that file is kept aside" grep -qx x "$aside/bunny.ply/bunny.ply"
mkdir "$TMP/elsewhere"
rm -rf "$TMP/out/bunny.ply"
ln -s "$TMP/elsewhere" "$TMP/out/bunny.ply"
settled "a link in the item folder's place"
check "the link is moved aside, what it pointed to untouched" \
  [ -L "$aside/bunny.ply/bunny.ply.1" -a -d "$TMP/elsewhere" -a -z "$(ls -A "$TMP/elsewhere")" ]
rm -rf "$TMP/out/sub"
echo y >"$TMP/out/sub"
settled "a file in the place of a folder above an item"
check "that file is kept aside" grep -qx y "$aside/sub%2Fnested.ply/sub"

# A republication (another level asked for) keeps a foreign file too: it goes aside, not
# away with the old folder.
echo "more notes" >"$TMP/out/bunny.ply/notes.txt"
run_scanlod run "$TMP/c.ini" -q -s levels.percents=40
check "another level: exit 0 (got $rc: $err)" [ "$rc" -eq 0 ]
check "another level: both republished ($out)" contains "2 published" "$out"
check "another level: the foreign file was kept aside" grep -qx "more notes" "$aside/bunny.ply/notes.txt.1"
run_scanlod verify "$TMP/c.ini" -s levels.percents=40
check "another level: verify exits 0 (got $rc: $out)" [ "$rc" -eq 0 ]
finish
