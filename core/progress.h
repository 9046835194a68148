/* Interrupt and progress through one object, after OpenVDB's util::NullInterrupter.
 *
 * Long work calls sl_progress_step(p, phase, fraction) at safe points; it reports the
 * fraction done (0..1) and returns nonzero when the run has been asked to stop
 * (SIGTERM/SIGINT/SIGUSR1 only set a flag). The caller then unwinds, frees what it holds,
 * publishes nothing and returns SL_E_INTERRUPTED.
 *
 * Thread safety: sl_progress_step may be called from any thread; `report` is called only
 * from the thread that owns the object (omp master / the calling thread), others just
 * poll the flag. A NULL sl_progress* is valid and means "no progress, never interrupted".
 */
#ifndef SCANLOD_CORE_PROGRESS_H
#define SCANLOD_CORE_PROGRESS_H

#include <signal.h>

typedef struct sl_progress {
    /* Called with the phase name and the fraction done; may be NULL. */
    void (*report)(void *ctx, const char *phase, double fraction);
    void *ctx;
    /* Set to nonzero by the signal handler; may be NULL (never interrupted). */
    volatile sig_atomic_t *interrupt_flag;
} sl_progress;

/* Returns nonzero if interrupted. Reports only on the owning thread's first call per
 * 1/200 step (or on a new phase) so tight loops stay cheap. `fraction` is clamped to
 * [0, 1]. The owning thread is the caller outside OpenMP parallel regions and thread 0
 * (the master, i.e. the thread that opened the region) inside one. */
int sl_progress_step(sl_progress *p, const char *phase, double fraction);

/* Nonzero once an interrupt was requested (cheap; for inner loops). */
static inline int sl_progress_interrupted(const sl_progress *p)
{
    return p && p->interrupt_flag && *p->interrupt_flag;
}

/* The process-wide flag the signal handlers set (see core/signals.h). */
volatile sig_atomic_t *sl_interrupt_flag(void);

#endif
