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

/* The run's memory budget, MiB: `limit_mb` ([run] memory_limit_mb) when above 0, else
 * sl_memory_available_mb; `what` (may be NULL) says which. The engine's admission, the
 * stages' io->memory_budget_mb and `scanlod plan` all take it from here. */
uint64_t sl_memory_budget_mb(int64_t limit_mb, char *what, size_t what_size);

/* Out-of-memory kills the kernel counted in this process's cgroup so far (v2
 * memory.events, v1 memory.oom_control: "oom_kill N"); 0 when it cannot be read. A stage
 * process that died of SIGKILL while this count rose was killed for memory, not by a
 * person (pipeline/engine_outcome.c). */
uint64_t sl_memory_oom_kills(void);

/* The last resort for an allocation failure that cannot be returned as an error: a C++
 * std::bad_alloc that nothing caught (thrown in a library's static constructor while it
 * loads, or in a destructor) reaches std::terminate, whose handler
 * (shim/cxx_runtime.cpp) calls this. It calls the handler set by sl_memory_on_exhausted
 * (the engine's stage process reports SL_E_NOMEM to its parent, so the item fails as out
 * of memory, never as a crash of ours), else prints one line naming `what` and exits 75
 * (docs/exit-codes.md: out of memory). Never returns. Async-signal-safe enough for
 * std::terminate: no allocation. */
void sl_memory_exhausted(const char *what) __attribute__((noreturn));
/* Sets that handler (NULL: the default); it must not return. Per process. */
void sl_memory_on_exhausted(void (*handler)(const char *what));

#endif
