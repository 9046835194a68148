#!/usr/bin/env bash
# Line and branch coverage of scanlod's own code from a build made with
# -DSCANLOD_COVERAGE=ON after its tests ran: scripts/coverage.sh BUILD_DIR
# Prints gcovr's summary and per-folder figures; writes BUILD_DIR/coverage.txt (per file).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build=${1:-$root/build-asan}
command -v gcovr >/dev/null || { echo "coverage: gcovr is not installed (scripts/install-deps.sh)" >&2; exit 1; }
cd "$root"
filters=()
for floor in core shim geometry formats runtime levels stages pipeline cli; do
  filters+=(--filter "$floor/")
done
# The counters are updated without atomics (-fprofile-update=single, CMakeLists.txt: the
# atomic ones ran the pass 3.5x slower), so a branch counted by two threads at once can come
# out negative; gcov prints it and gcovr leaves that line out (about 20 of 26k branches).
# One gcovr job: gcovr 5.2 with -j hangs when a worker raises.
log=$build/coverage.log
gcovr --root "$root" --object-directory "$build" "${filters[@]}" --exclude-unreachable-branches \
  --exclude-throw-branches --gcov-ignore-parse-errors --txt "$build/coverage.txt" \
  --print-summary 2>"$log"
echo "coverage: per file in $build/coverage.txt; $(grep -c 'UnknownLineType' "$log" || true) branch lines with a raced (negative) count left out ($log)"
