#!/usr/bin/env bash
# The house's layers (docs/architecture.md): scripts/check-layers.sh finds no include that
# runs up a floor, no source file is over 600 lines, and the checker itself catches a
# planted break (a core file including the engine) in a copy of the tree.
source "$(dirname "$0")/../lib.sh"
cd "$SCANLOD_SOURCE_DIR"
check "every include points at its own floor or one below" scripts/check-layers.sh "$SCANLOD_SOURCE_DIR"
long=$(git ls-files -- '*.c' '*.h' '*.cpp' | grep -v '^tests/' | while read -r f; do
  n=$(wc -l <"$f"); [ "$n" -gt 600 ] && echo "$f ($n lines)"; done || true)
check "no source file over 600 lines (${long:-none})" [ -z "$long" ]

# The checker must fail on a break: plant one in a throwaway copy of the tracked files.
git ls-files -z | (cd "$SCANLOD_SOURCE_DIR" && xargs -0 tar cf -) | (mkdir -p "$TMP/copy" && cd "$TMP/copy" && tar xf -)
(cd "$TMP/copy" && git init -q && git add -A >/dev/null 2>&1)
sed -i 's|^#include "core/io.h"|#include "core/io.h"\n#include "pipeline/engine.h"|' "$TMP/copy/core/io.c"
(cd "$TMP/copy" && git add -A >/dev/null 2>&1)
set +e
planted=$(bash "$TMP/copy/scripts/check-layers.sh" "$TMP/copy" 2>&1)
prc=$?
set -e
check "a core file including the engine is caught (rc $prc: $planted)" \
  [ "$prc" -eq 1 ] && grep -q 'core/io.c: includes "pipeline/engine.h"' <<<"$planted"
finish
