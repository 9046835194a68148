/* How much memory this process may use: the node's physical memory, or less when the
 * process sits in a cgroup with a limit (Slurm's --mem, a container), as the run's memory
 * budget when `[run] memory_limit_mb` is 0 (docs/engine.md, "Memory admission"). */
#ifndef SCANLOD_CORE_MEMORY_H
#define SCANLOD_CORE_MEMORY_H

#include <stddef.h>
#include <stdint.h>

/* The smaller of physical memory and this process's cgroup limit (v2 memory.max, v1
 * memory.limit_in_bytes), in MiB; `what` says which it is ("the node's physical memory",
 * "the cgroup's memory limit"). 0 when neither can be read. */
uint64_t sl_memory_available_mb(char *what, size_t what_size);

#endif
