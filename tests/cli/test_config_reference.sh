#!/usr/bin/env bash
# config/reference.ini documents every option with its default: it must equal what the
# option tables generate (`scanlod config-reference`), and it must load as a config.
source "$(dirname "$0")/../lib.sh"
ref="$SCANLOD_SOURCE_DIR/config/reference.ini"
run_scanlod config-reference
check "config-reference exits 0" [ "$rc" -eq 0 ]
check "config/reference.ini is up to date (regenerate: scanlod config-reference > config/reference.ini)" \
  diff <(echo "$out") "$ref"
for section in run queue range samples octree merge export; do
  check "reference documents [$section]" grep -q "^\[$section\]" "$ref"
done
# The reference with the required keys filled in is a valid config.
mkdir -p "$TMP/in"
{ sed -e "s#^; input =.*#input = $TMP/in#" -e "s#^; work =.*#work = $TMP/work#" \
      -e "s#^; output =.*#output = $TMP/out#" "$ref"; } >"$TMP/full.ini"
run_scanlod status "$TMP/full.ini"
check "the reference file loads as a config (rc $rc: $err)" [ "$rc" -eq 0 ]
finish
