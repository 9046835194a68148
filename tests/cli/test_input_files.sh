#!/usr/bin/env bash
# The commands that read a file the user names (inspect, compare, extract) refuse what is
# not a regular file before reading it, and all three the same way (issue 16): a FIFO
# never blocks them, a directory is called one, a missing file says so; exit 65 and one
# line "scanlod: FILE: cause" on stderr, nothing on stdout, no output file.
source "$(dirname "$0")/../lib.sh"
good="$SCANS/cow.ply"

mkfifo "$TMP/pipe.ply" "$TMP/pipe.slod" "$TMP/pipe.slot"
mkdir "$TMP/dir.ply" "$TMP/dir.slod" "$TMP/dir.slot"

# attempt NAME FILE CAUSE ARGS...: runs scanlod ARGS (FILE among them) with a time limit;
# checks the exit code, the one line naming FILE and CAUSE, and that nothing was written.
attempt() {
  local name=$1 file=$2 cause=$3; shift 3
  rm -f "$TMP/x.ply"
  set +e
  out=$(timeout 20 "$SCANLOD" "$@" 2>"$TMP/err")
  rc=$?
  set -e
  err=$(cat "$TMP/err")
  check "$name: exit 65, not blocked (rc $rc)" [ "$rc" -eq 65 ]
  check "$name: one line naming the file and the cause ($err)" [ "$err" = "scanlod: $file: $cause" ]
  check "$name: nothing on stdout ($out)" [ -z "$out" ]
  check "$name: no output file" [ ! -e "$TMP/x.ply" ]
}

for kind in pipe dir missing; do
  case $kind in
    pipe) cause="is a FIFO, not a regular file" ;;
    dir) cause="is a directory" ;;
    missing) cause="No such file or directory" ;;
  esac
  attempt "inspect $kind" "$TMP/$kind.ply" "$cause" inspect "$TMP/$kind.ply"
  attempt "compare $kind as A" "$TMP/$kind.ply" "$cause" compare "$TMP/$kind.ply" "$good"
  attempt "compare $kind as B" "$TMP/$kind.ply" "$cause" compare "$good" "$TMP/$kind.ply"
  attempt "extract model $kind" "$TMP/$kind.slod" "$cause" extract "$TMP/$kind.slod" --lod-percent 50 -o "$TMP/x.ply"
  attempt "extract octree $kind" "$TMP/$kind.slot" "$cause" extract "$TMP/$kind.slot" --level 0 -o "$TMP/x.ply"
done

# Not regular either: a character device.
attempt "inspect /dev/null" /dev/null "is a character device, not a regular file" inspect /dev/null
finish
