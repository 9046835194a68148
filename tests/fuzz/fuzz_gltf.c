/* libFuzzer target (build: -DSCANLOD_FUZZ=ON with clang; tests/fuzz/README.md) for
 * the glTF 2.0 reader: a GLB when the input starts with "glTF", else JSON text (Draco
 * and meshopt streams included).
 * The promises checked are scan_promises.h's; crashes, leaks, hangs and allocations beyond
 * -malloc_limit_mb are findings too. */
#include <stddef.h>
#include <stdint.h>

#include "tests/fuzz/scan_promises.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    scan_fuzz_one(data, size, "fuzz.gltf", "gltf");
    return 0;
}
