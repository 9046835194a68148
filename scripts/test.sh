#!/usr/bin/env bash
# The whole test suite, as CI runs it: a warning-free (-Werror) build with all tests,
# then the same tests in an AddressSanitizer + UndefinedBehaviorSanitizer build.
# Tests that need the larger scans use ../shared/data when it is there.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
jobs=$(nproc)
start=$SECONDS

"$root/scripts/build.sh" "$root/build"
# Each test has its own TIMEOUT (tests/CMakeLists.txt, 3x+ its quiet time).
(cd "$root/build" && ctest --output-on-failure -j "$jobs")

# The README's other command (after the install) must keep working too: the demo converts
# the bundled scans, and a second run finds nothing to do.
demo_log=$root/build/demo-check.log
for pass in first second; do
  if ! "$root/scripts/demo.sh" >"$demo_log" 2>&1; then
    cat "$demo_log"
    echo "scripts/demo.sh failed on its $pass run" >&2
    exit 1
  fi
done
grep -q "^nothing to do" "$demo_log" || { cat "$demo_log"; echo "demo rerun did work" >&2; exit 1; }
release=$((SECONDS - start))
echo "test.sh: Release pass (build, ctest, demo) $((release / 60)) min $((release % 60)) s"

export ASAN_OPTIONS=detect_leaks=1:abort_on_error=0:halt_on_error=1
export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
# The sanitizer build checks memory safety on small data: its tests get
# SCANLOD_LIGHT=1 (tests/CMakeLists.txt); the large inputs and every K are the first pass's.
# It is also the coverage build: gcov counts every line and branch the tests run.
# Debug keeps the asserts; -O1 (not Debug's -O0) because the unoptimised build ran the
# pass 3-4x slower, past CI's time (docs/testing.md, "Sanitizer pass").
"$root/scripts/build.sh" "$root/build-asan" -DSCANLOD_SANITIZE=ON -DSCANLOD_BENCH=OFF \
  -DCMAKE_BUILD_TYPE=Debug -DCMAKE_C_FLAGS_DEBUG="-g -O1" -DCMAKE_CXX_FLAGS_DEBUG="-g -O1" \
  -DSCANLOD_COVERAGE=ON
find "$root/build-asan" -name '*.gcda' -delete
# Tests labelled release-only (a Slurm cluster of their own) run in the first pass only.
(cd "$root/build-asan" && ctest --output-on-failure -j "$jobs" -LE release-only)
sanitizer=$((SECONDS - start - release))
echo "test.sh: sanitizer pass (build, ctest) $((sanitizer / 60)) min $((sanitizer % 60)) s"
# Coverage of the production code by the sanitizer pass (tests, scripts and the benchmark
# peers left out): the figures docs/testing.md quotes.
"$root/scripts/coverage.sh" "$root/build-asan"
