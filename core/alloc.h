/* Allocations whose pages are made present at once.
 *
 * calloc hands back a large block as untouched pages that read as zero: the first read of
 * a page maps the kernel's shared zero page, and the first write after it copies that page
 * and flushes the old mapping from every CPU running one of the process's threads (an
 * inter-processor interrupt per page). Code that sums into zeroed slots reads each slot
 * before writing it, so it pays both faults and the flush for every page: the merge
 * stage's leaf quadrics spent 17 % of the stage's main thread there at 1 M triangles
 * (docs/benchmarks.md section 4). Writing the zeros first costs one fault per page, with
 * no flush.
 */
#ifndef SCANLOD_CORE_ALLOC_H
#define SCANLOD_CORE_ALLOC_H

#include <stddef.h>

/* count * size zeroed bytes (NULL on overflow or out of memory; free with free()). */
void *sl_alloc_zeroed(size_t count, size_t size);

#endif
