/* libFuzzer target (build: -DSCANLOD_FUZZ=ON with clang; tests/fuzz/README.md) for
 * the OFF reader and its [ST][C][N]OFF variants.
 * The promises checked are scan_promises.h's; crashes, leaks, hangs and allocations beyond
 * -malloc_limit_mb are findings too. */
#include <stddef.h>
#include <stdint.h>

#include "tests/fuzz/scan_promises.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    scan_fuzz_one(data, size, "fuzz.off", "off");
    return 0;
}
