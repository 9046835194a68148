#!/usr/bin/env bash
# Builds scanlod and converts the bundled demo collection (tests/data/scans), then shows
# the queue status and one item's report. Safe to rerun: the second run does no work.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
"$root/scripts/build.sh" "$root/build"
cd "$root"
status=0
build/cli/scanlod run config/demo.ini || status=$?
build/cli/scanlod status config/demo.ini
echo "--- build/demo/output/cow.ply/report.json"
cat build/demo/output/cow.ply/report.json
exit $status
