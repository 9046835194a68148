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
gcovr --root "$root" --object-directory "$build" "${filters[@]}" --exclude-unreachable-branches \
  --exclude-throw-branches -j "$(nproc)" --txt "$build/coverage.txt" --print-summary
echo "coverage: per file in $build/coverage.txt"
