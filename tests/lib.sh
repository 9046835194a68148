# Shared helpers for the end-to-end shell tests (sourced). Each test gets:
#   SCANLOD            the binary under test
#   SCANLOD_SOURCE_DIR the repository
#   SCANLOD_SHARED_DATA ../shared/data when present, else empty
set -euo pipefail
: "${SCANLOD:?SCANLOD must name the scanlod binary}"
: "${SCANLOD_SOURCE_DIR:?}"
SCANS="$SCANLOD_SOURCE_DIR/tests/data/scans"
TMP=$(mktemp -d "${TMPDIR:-/tmp}/scanlod-test.XXXXXX")
cleanup_hooks=()
cleanup() {
  for h in "${cleanup_hooks[@]}"; do eval "$h" || true; done
  rm -rf "$TMP"
}
trap cleanup EXIT
# A command failing under errexit ends the test; say which one, so a CI log is never silent.
trap '[[ $- != *e* ]] || echo "ERROR: ${BASH_SOURCE[0]}:$LINENO: \"$BASH_COMMAND\" exited $?" >&2' ERR
passed=0
failed=0
# SCANLOD_LIGHT=1: the sanitizer pass (tests/CMakeLists.txt). The same code on less data:
# a heavy test says on a LIGHT: line what it leaves to the Release pass.
light() { [ "${SCANLOD_LIGHT:-}" = 1 ]; }

check() { # check "description" command...
  local what=$1; shift
  if "$@"; then passed=$((passed + 1)); else failed=$((failed + 1)); echo "FAIL: $what" >&2; fi
}

# Node and the Khronos glTF validator (scripts/install-deps.sh installs both): 0 when
# scripts/gltf/validate.mjs can run.
gltf_validator_ready() {
  command -v node >/dev/null &&
    [ -f "$SCANLOD_SOURCE_DIR/scripts/gltf/node_modules/gltf-validator/package.json" ]
}

# need_renderer: headless Chromium and scripts/viewer's three.js and playwright-core
# (scripts/viewer/render.cjs) are test dependencies: a missing one FAILs the test.
need_renderer() {
  [ -x "${CHROMIUM:-/usr/bin/chromium}" ] || { echo "FAIL: no chromium (scripts/install-deps.sh)" >&2; exit 1; }
  local viewer="$SCANLOD_SOURCE_DIR/scripts/viewer/node_modules"
  [ -f "$viewer/three/package.json" ] && [ -f "$viewer/playwright-core/package.json" ] ||
    { echo "FAIL: npm ci --prefix scripts/viewer (scripts/install-deps.sh)" >&2; exit 1; }
}

contains() { # contains REGEX TEXT: for checks on a command's message
  grep -q -- "$1" <<<"$2"
}

finish() {
  echo "$passed passed, $failed failed"
  [ "$failed" -eq 0 ]
}

# write_config FILE INPUT WORK OUTPUT [extra lines...]
# Unless the extra lines configure [levels] or [export] themselves, the ladder is one level
# and the export stage is kept light (PLY only, no fidelity or thumbnails): these tests are
# about the engine, and they also run under the sanitizers.
write_config() {
  local file=$1 input=$2 work=$3 output=$4; shift 4
  # No pipe into `grep -q` here: under pipefail, grep's early exit can kill the printf
  # with SIGPIPE on a busy machine, the test reads as "no [export]", and a second
  # [export] section makes a duplicate key (seen in test_lod_pipeline at load 11).
  local line own_export=0 own_levels=0 own_refine=0
  for line in "$@"; do
    [ "$line" = "[export]" ] && own_export=1
    [ "$line" = "[levels]" ] && own_levels=1
    [ "$line" = "[refine]" ] && own_refine=1
  done
  { echo "[run]"; echo "input = $input"; echo "work = $work"; echo "output = $output"
    echo "logs = $TMP/logs"; printf '%s\n' "$@"
    if [ "$own_levels" -eq 0 ]; then
      printf '[levels]\npercents = 50\nbudgets =\n'
      # The sanitizer pass: the light ladder's level refined without the fit (the fit is
      # most of a light run's CPU under ASan); tests that measure levels set their ladder.
      if light && [ "$own_refine" -eq 0 ]; then printf '[refine]\nfit = false\n'; fi
    fi
    if [ "$own_export" -eq 0 ]; then
      printf '[export]\nformats = ply\nthumbnail_size = 0\nfidelity = false\n'
    fi; } >"$file"
}

# stopped_child PID: waits (up to 30 s) for a child of PID that stopped itself (a stage
# process under SCANLOD_FAULT=OP:N:stop) and prints its pid; prints nothing if none did.
stopped_child() {
  local p _
  for _ in $(seq 1 600); do
    for p in $(pgrep -P "$1" || true); do
      if [ "$(ps -o stat= -p "$p" | cut -c1)" = T ]; then echo "$p"; return 0; fi
    done
    sleep 0.05
  done
}

# run_killing_child SCOPE CONFIG: `scanlod run CONFIG -q` whose stage process SCOPE
# (SCANLOD_FAULT_SCOPE: child = the first, child:K = the K-th) stops itself at its first
# write and is killed -9 by the test, as the kernel's OOM killer would kill it. Sets $rc,
# $err, $runner (the run's pid) and $child (empty when no stage process stopped).
run_killing_child() {
  SCANLOD_FAULT=write:1:stop SCANLOD_FAULT_SCOPE="$1" "$SCANLOD" run "$2" -q \
    >"$TMP/killing.out" 2>"$TMP/killing.err" &
  runner=$!
  child=$(stopped_child "$runner")
  if [ -n "$child" ]; then kill -9 "$child"; fi
  set +e; wait "$runner"; rc=$?; set -e
  err=$(cat "$TMP/killing.err")
}

# run_scanlod CMD CONFIG [args...]: sets $rc and $out (stdout), $err (stderr file)
run_scanlod() {
  local errfile="$TMP/stderr.$RANDOM"
  set +e
  out=$("$SCANLOD" "$@" 2>"$errfile")
  rc=$?
  set -e
  err=$(cat "$errfile")
}

# Deterministic content of a work dir + output dir: every artifact and published file,
# except the per-run timing files, as "path hash" lines.
tree_digest() { # tree_digest WORK OUTPUT
  (cd "$1" && find artifacts -type f ! -name '_*' ! -name '.*' -print0 | sort -z |
     xargs -0 -r sha256sum)
  (cd "$2" && find . -type f ! -name 'timings.json' ! -path '*/.*' -print0 | sort -z |
     xargs -0 -r sha256sum)
}

# same_digest "REFERENCE DIGEST" WORK OUTPUT: compares, printing the differing lines.
same_digest() {
  local now
  now=$(tree_digest "$2" "$3")
  [ "$1" = "$now" ] && return 0
  diff <(echo "$1") <(echo "$now") | head -20 >&2
  return 1
}
