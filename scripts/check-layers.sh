#!/usr/bin/env bash
# The layers as folders (docs/architecture.md, "Floors"). Checks, over every tracked source
# file:
#   1. every #include "..." points at the file's own floor or one below it, with the named
#      exceptions of the table below;
#   2. a stage folder includes no other stage's private header (only stages/NAME/NAME.h);
#   3. no loop between stage folders: if stages/a includes stages/b/b.h, nothing under
#      stages/b includes stages/a/ (directly or through a third stage);
#   4. files over 600 lines are named as a warning unless scripts/long-files.txt lists
#      them with the reason (a warning never fails the check).
# Prints each break and exits 1 if there is one; exit 0 otherwise. Run from anywhere:
#   scripts/check-layers.sh [REPO]
set -euo pipefail
root=${1:-$(cd "$(dirname "$0")/.." && pwd)}
cd "$root"

# allowed FOLDER: the include prefixes a file in FOLDER may use (regular expressions).
# Floors, bottom up: core -> geometry, shim -> formats -> runtime -> levels -> stages ->
# pipeline -> cli. A stage also uses the engine's face to it: the stage contract and the
# config reader (pipeline/stage.h, pipeline/config.h); levels/ declares the ladder's options
# through that reader too.
allowed() {
  case $1 in
    core) echo '^core/' ;;
    shim) echo '^(core|shim)/' ;;
    geometry) echo '^(core|geometry|shim)/' ;;
    formats) echo '^(core|geometry|shim|formats)/' ;;
    runtime) echo '^(core|runtime|scanlod)/' ;;
    levels) echo '^(core|geometry|formats|levels)/|^pipeline/config\.h$' ;;
    stages) echo '^(core|geometry|formats|shim|runtime|levels)/|^pipeline/(stage|config)\.h$|^stages/registry\.h$' ;;
    pipeline) echo '^(core|pipeline)/' ;;
    cli) echo '^(core|geometry|formats|shim|runtime|levels|stages|pipeline|cli)/' ;;
    include) echo '^scanlod/' ;;
    *) echo '' ;;
  esac
}

bad=0
edges=$(mktemp)
trap 'rm -f "$edges"' EXIT
while IFS= read -r file; do
  floor=${file%%/*}
  rule=$(allowed "$floor")
  [ -n "$rule" ] || continue
  stage=""
  [ "$floor" = stages ] && stage=$(cut -d/ -f2 <<<"$file")
  registry=0
  [[ $stage == *.* ]] && stage="" registry=1 # stages/registry.c: the list of every stage
  while IFS= read -r inc; do
    ok=0
    if grep -qE "$rule" <<<"$inc"; then ok=1; fi
    if [ "$registry" -eq 1 ] && [[ $inc =~ ^stages/([a-z_]+)/([a-z_]+)\.h$ ]] &&
       [ "${BASH_REMATCH[1]}" = "${BASH_REMATCH[2]}" ]; then ok=1; fi
    if [ -n "$stage" ] && [ "$ok" -eq 0 ]; then
      # its own folder, or another stage's public header
      if [[ $inc == stages/$stage/* ]]; then
        ok=1
      elif [[ $inc =~ ^stages/([a-z_]+)/([a-z_]+)\.h$ ]] && [ "${BASH_REMATCH[1]}" = "${BASH_REMATCH[2]}" ]; then
        ok=1
        echo "$stage ${BASH_REMATCH[1]}" >>"$edges"
      elif [[ $inc =~ ^stages/([a-z_]+)/ ]]; then
        echo "$file: includes \"$inc\", a private header of stage ${BASH_REMATCH[1]}"
        bad=1
        continue
      fi
    fi
    if [ "$ok" -eq 0 ]; then
      echo "$file: includes \"$inc\", above its floor ($floor)"
      bad=1
    fi
  done < <(sed -n 's/^#include "\([^"]*\)".*/\1/p' "$file")
done < <(git ls-files -- 'core/*' 'geometry/*' 'formats/*' 'shim/*' 'runtime/*' 'levels/*' \
           'stages/*' 'pipeline/*' 'cli/*' 'include/*' | grep -E '\.(c|h|cpp|hpp)$')

# tsort reports every loop of the stage graph on stderr ("input contains a loop:").
if [ -s "$edges" ]; then
  loops=$(sort -u "$edges" | tsort 2>&1 >/dev/null || true)
  if [ -n "$loops" ]; then
    echo "a loop between stage folders (each includes the other's header, directly or not):"
    sed -n 's/^tsort: \([a-z_]*\)$/  stages\/\1/p' <<<"$loops"
    bad=1
  fi
fi

# Long files: a warning, unless the allowlist names the file and why.
while IFS= read -r f; do
  n=$(wc -l <"$f")
  if [ "$n" -gt 600 ] && ! grep -qE "^$f[[:space:]]" scripts/long-files.txt 2>/dev/null; then
    echo "warning: $f has $n lines (over 600; split it by responsibility, or list it in scripts/long-files.txt with the reason)"
  fi
done < <(git ls-files -- '*.c' '*.h' '*.cpp' | grep -v '^tests/')

[ "$bad" -eq 0 ] && echo "layers: every include points at its own floor or one below; no loop between stages"
exit "$bad"
