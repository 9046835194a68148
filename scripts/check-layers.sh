#!/usr/bin/env bash
# The layers as folders (docs/architecture.md): every #include "..." of every source file
# must point at its own floor or one below it. Prints each include that breaks the rule
# and exits 1 if there is one; exit 0 otherwise. Run from anywhere:
#   scripts/check-layers.sh [REPO]
set -euo pipefail
root=${1:-$(cd "$(dirname "$0")/.." && pwd)}
cd "$root"

# allowed FOLDER: the include prefixes a file in FOLDER may use (regular expressions).
allowed() {
  case $1 in
    core) echo '^core/' ;;
    geometry) echo '^(core|geometry|shim)/' ;;
    shim) echo '^(core|shim)/' ;;
    runtime) echo '^(core|runtime|scanlod)/' ;;
    # A stage: the floors below, the stage contract and config reader of the engine, its
    # own folder, and other stages' public headers (stages/NAME/NAME.h) only.
    stages) echo '^(core|geometry|shim|runtime)/|^pipeline/(stage|config)\.h$|^stages/registry\.h$' ;;
    pipeline) echo '^(core|pipeline)/' ;;
    cli) echo '^(core|geometry|shim|runtime|stages|pipeline|cli)/' ;;
    include) echo '^scanlod/' ;;
    *) echo '' ;;
  esac
}

bad=0
while IFS= read -r file; do
  floor=${file%%/*}
  rule=$(allowed "$floor")
  [ -n "$rule" ] || continue
  stage=""
  [ "$floor" = stages ] && stage=$(cut -d/ -f2 <<<"$file")
  while IFS= read -r inc; do
    ok=0
    if grep -qE "$rule" <<<"$inc"; then ok=1; fi
    if [ -n "$stage" ] && [ "$ok" -eq 0 ]; then
      # its own folder, or another stage's public header
      if [[ $inc == stages/$stage/* ]]; then ok=1; fi
      if [[ $inc =~ ^stages/([a-z_]+)/([a-z_]+)\.h$ ]] && [ "${BASH_REMATCH[1]}" = "${BASH_REMATCH[2]}" ]; then ok=1; fi
    fi
    if [ "$ok" -eq 0 ]; then
      echo "$file: includes \"$inc\", above its floor ($floor)"
      bad=1
    fi
  done < <(sed -n 's/^#include "\([^"]*\)".*/\1/p' "$file")
done < <(git ls-files -- 'core/*' 'geometry/*' 'shim/*' 'runtime/*' 'stages/*' 'pipeline/*' 'cli/*' 'include/*' |
         grep -E '\.(c|h|cpp|hpp)$')
[ "$bad" -eq 0 ] && echo "layers: every include points at its own floor or one below"
exit "$bad"
