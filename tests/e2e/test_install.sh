#!/usr/bin/env bash
# The runtime as a viewer outside this tree gets it (docs/api.md): `cmake --install` puts
# the scanlod binary, libscanlod_runtime.so, its header and scanlod.pc under a prefix;
# examples/cut_level.c builds against that prefix with pkg-config alone, runs, and cuts
# the same level as `scanlod extract`; the library exports the public API and nothing else.
# The installed binary loads the installed OpenImageIO module (shim/oiio_loader.c), not the
# build tree's, and draws a thumbnail with it; without the module, only image work fails,
# with one error naming the module.
source "$(dirname "$0")/../lib.sh"
build="${SCANLOD_BUILD_DIR:?}"
prefix="$TMP/prefix"
check "cmake --install to a fresh prefix" cmake --install "$build" --prefix "$prefix"
libdir=$(dirname "$(find "$prefix" -name 'libscanlod_runtime.so' | head -1)")
check "library, header, pkg-config file and binary installed" \
  [ -f "$libdir/libscanlod_runtime.so" -a -f "$prefix/include/scanlod/scanlod.h" \
    -a -f "$libdir/pkgconfig/scanlod.pc" -a -x "$prefix/bin/scanlod" ]

exported=$(nm -D --defined-only "$libdir/libscanlod_runtime.so" | awk '$2 == "T" { print $3 }' |
  sed 's/@.*//' | LC_ALL=C sort -u)
check "exports only the public API ($(echo $exported))" \
  [ -n "$exported" -a -z "$(grep -v '^scanlod_' <<<"$exported")" ]
declared=$(grep -o 'scanlod_[a-z_]*(' "$prefix/include/scanlod/scanlod.h" | tr -d '(' | LC_ALL=C sort -u)
check "exports every function the header declares" [ "$exported" = "$declared" ]

# The example, built the way docs/api.md says (sanitizer builds need the same flags).
flags=()
grep -q '^SCANLOD_SANITIZE:BOOL=ON' "$build/CMakeCache.txt" && flags=(-fsanitize=address,undefined)
cflags=$(PKG_CONFIG_PATH="$libdir/pkgconfig" pkg-config --cflags --libs scanlod)
check "examples/cut_level.c builds against the prefix with pkg-config" \
  cc -std=c11 -Wall -Wextra -Werror "${flags[@]}" "$SCANLOD_SOURCE_DIR/examples/cut_level.c" \
  $cflags -o "$TMP/cut_level"

mkdir -p "$TMP/in"
cp "$SCANS/fandisk.ply" "$TMP/in/"
write_config "$TMP/c.ini" "$TMP/in" "$TMP/work" "$TMP/out"
SCANLOD="$prefix/bin/scanlod" # from here on, the installed binary
run_scanlod run "$TMP/c.ini" -q
check "the installed binary's pipeline ran (rc $rc: $err)" [ "$rc" -eq 0 ]
model="$TMP/out/fandisk.ply/model.slod"
run_scanlod --version
check "the installed binary loads the installed image module ($out)" \
  contains "^images: OpenImageIO .*($prefix/.*/scanlod/scanlod-oiio.so)" "$out"
write_config "$TMP/thumb.ini" "$TMP/in" "$TMP/work-thumb" "$TMP/out-thumb" "[levels]" \
  "percents = 50" "budgets =" "[export]" "formats = ply" "thumbnail_size = 64" "fidelity = false"
run_scanlod run "$TMP/thumb.ini" -q
check "the installed binary draws a thumbnail (rc $rc: $err)" \
  [ "$rc" -eq 0 -a -s "$TMP/out-thumb/fandisk.ply/lod50.png" ]
rm -rf "$TMP/work-thumb" "$TMP/out-thumb"
SCANLOD_OIIO_MODULE="$TMP/no-such-module.so" run_scanlod run "$TMP/thumb.ini" -q
check "without the image module the thumbnail's item fails (rc $rc)" [ "$rc" -ne 0 ]
check "and the error names the module ($(tail -c 300 <<<"$err"))" contains "scanlod-oiio.so" "$err"
check "nothing is published for it" [ ! -e "$TMP/out-thumb/fandisk.ply" ]
SCANLOD_OIIO_MODULE="$TMP/no-such-module.so" run_scanlod run "$TMP/c.ini" -q
check "without the image module a run with no images still works (rc $rc: $err)" [ "$rc" -eq 0 ]
set +e
cut=$(LD_LIBRARY_PATH="$libdir" "$TMP/cut_level" "$model" 3000 2>&1)
crc=$?
set -e
check "cut_level runs ($cut)" [ "$crc" -eq 0 ]
run_scanlod extract "$model" --triangles 3000 -o "$TMP/x.ply"
want=$(sed -n 's/^expansions \([0-9]*\) of \([0-9]*\): \([0-9]*\) triangles, \([0-9]*\) vertices.*/k=\1 of \2: \3 triangles, \4 vertices/p' <<<"$out")
check "cut_level cuts what scanlod extract cuts ($want)" contains "^${want:-nothing}" "$cut"
set +e
bad=$(LD_LIBRARY_PATH="$libdir" "$TMP/cut_level" "$TMP/missing.slod" 10 2>&1)
brc=$?
set -e
check "a missing model: exit 1 with one line naming it ($bad)" \
  [ "$brc" -eq 1 -a -n "$bad" -a "$(wc -l <<<"$bad")" -eq 1 ]
check "the line names the file" contains "missing.slod" "$bad"
finish
