#!/usr/bin/env bash
# Configure and build one build tree: scripts/build.sh [DIR] [extra cmake args...]
# DIR defaults to build/. Uses Ninja when present, all cores.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
dir=${1:-$root/build}
shift || true
gen=()
command -v ninja >/dev/null && gen=(-G Ninja)
# Configured when new, and again when given options (an existing tree takes them too).
if [ ! -f "$dir/CMakeCache.txt" ] || [ $# -gt 0 ]; then
  cmake -S "$root" -B "$dir" "${gen[@]}" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DSCANLOD_WERROR=ON "$@"
fi
cmake --build "$dir" --parallel "$(nproc)"
