#!/usr/bin/env bash
# The house's layers (docs/architecture.md): scripts/check-layers.sh finds no include that
# runs up a floor, no include of another stage's private header and no loop between stage
# folders; and the checker itself catches each of those planted in a copy of the tree.
source "$(dirname "$0")/../lib.sh"
cd "$SCANLOD_SOURCE_DIR"
check "every include points at its own floor or one below, no loop between stages" \
  scripts/check-layers.sh "$SCANLOD_SOURCE_DIR"

# The checker must fail on a break: plant each in a throwaway copy of the tracked files.
# One tar reads the whole list (xargs could split it into several archives, and the reader
# stops at the first one's end, killing the writer with SIGPIPE).
mkdir -p "$TMP/copy"
git ls-files -z | tar --null --ignore-failed-read -T - -cf - 2>/dev/null | tar -C "$TMP/copy" -xf -
(cd "$TMP/copy" && git init -q && git add -A >/dev/null 2>&1)
planted() { # FILE LINE: the checker's output with LINE added after FILE's first include
  cp "$TMP/copy/$1" "$TMP/saved"
  sed -i "0,/^#include \"/s|^#include \"|$2\n#include \"|" "$TMP/copy/$1"
  set +e
  bash "$TMP/copy/scripts/check-layers.sh" "$TMP/copy" 2>&1
  echo "rc=$?"
  set -e
  cp "$TMP/saved" "$TMP/copy/$1"
}
out=$(planted core/io.c '#include "pipeline/engine.h"')
check "a core file including the engine is caught ($out)" \
  grep -q 'core/io.c: includes "pipeline/engine.h"' <<<"$out" && grep -q 'rc=1' <<<"$out"
out=$(planted stages/merge/merge_stage.c '#include "stages/samples/samples_internal.h"')
check "a stage including another's private header is caught ($out)" \
  grep -q 'private header of stage samples' <<<"$out" && grep -q 'rc=1' <<<"$out"
# samples -> merge's header, merge -> priority's, priority -> samples': a loop of three.
sed -i '0,/^#include "/s|^#include "|#include "stages/priority/priority.h"\n#include "|' "$TMP/copy/stages/merge/merge_stage.c"
sed -i '0,/^#include "/s|^#include "|#include "stages/samples/samples.h"\n#include "|' "$TMP/copy/stages/priority/priority_stage.c"
out=$(planted stages/samples/samples_stage.c '#include "stages/merge/merge.h"')
check "a loop between three stage folders is caught ($out)" \
  grep -q 'a loop between stage folders' <<<"$out" && grep -q 'stages/samples' <<<"$out" &&
  grep -q 'rc=1' <<<"$out"
finish
