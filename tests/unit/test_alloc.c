/* sl_alloc_zeroed (core/alloc.h): zeroed bytes whose pages are present when it returns,
 * unlike calloc's lazily mapped zero pages (resident pages counted with mincore), and
 * NULL for a count * size that wraps. */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <unistd.h>

#include "core/alloc.h"
#include "tests/check.h"

/* Pages of [p, p + bytes) resident now, of those wholly inside it. */
static size_t resident_pages(const void *p, size_t bytes, size_t *pages)
{
    size_t page = (size_t)sysconf(_SC_PAGESIZE);
    uintptr_t first = ((uintptr_t)p + page - 1) / page * page;
    uintptr_t end = ((uintptr_t)p + bytes) / page * page;
    *pages = end > first ? (end - first) / page : 0;
    unsigned char *vec = malloc(*pages ? *pages : 1);
    size_t resident = 0;
    if (vec && *pages && mincore((void *)first, end - first, vec) == 0)
        for (size_t i = 0; i < *pages; i++)
            resident += vec[i] & 1;
    free(vec);
    return resident;
}

int main(void)
{
    const size_t bytes = 64u << 20; /* above glibc's mmap threshold: fresh pages */
    size_t pages;
    unsigned char *lazy = calloc(bytes, 1);
    CHECK(lazy != NULL);
    size_t lazy_resident = lazy ? resident_pages(lazy, bytes, &pages) : 0;
    CHECK_MSG(lazy_resident < pages / 10, "calloc's block is already resident (%zu of %zu): "
              "the check below would prove nothing", lazy_resident, pages);
    free(lazy);

    unsigned char *z = sl_alloc_zeroed(bytes / 16, 16);
    CHECK(z != NULL);
    if (z) {
        size_t resident = resident_pages(z, bytes, &pages);
        CHECK_MSG(resident == pages, "%zu of %zu pages resident", resident, pages);
        size_t nonzero = 0;
        for (size_t i = 0; i < bytes; i++)
            nonzero += z[i] != 0;
        CHECK_EQ_U64(nonzero, 0);
    }
    free(z);

    /* A small block reused from the heap after it held other bytes still comes back zero. */
    unsigned char *dirty = malloc(4096);
    CHECK(dirty != NULL);
    if (dirty)
        memset(dirty, 0xa5, 4096);
    free(dirty);
    unsigned char *small = sl_alloc_zeroed(512, 8);
    CHECK(small != NULL);
    size_t nonzero = 0;
    for (size_t i = 0; small && i < 4096; i++)
        nonzero += small[i] != 0;
    CHECK_EQ_U64(nonzero, 0);
    free(small);

    CHECK(sl_alloc_zeroed(SIZE_MAX / 8 + 2, 8) == NULL); /* wraps */
    void *none = sl_alloc_zeroed(0, 16);
    CHECK(none != NULL);
    free(none);
    return check_report();
}
