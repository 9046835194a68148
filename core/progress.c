/* Interrupt flag and throttled progress reports (see progress.h).
 *
 * Only the OpenMP master reports, so `report` is never called concurrently and needs no
 * lock. The OpenMP queries are weak references: sl_pipeline does not link the OpenMP
 * runtime, and a program without it has no parallel regions, so every caller is master.
 *
 * The throttle state lives in thread-local storage of the reporting thread, keyed by the
 * object, so sl_progress stays the three-field struct stages initialise by position.
 */
#include "core/progress.h"

#include <string.h>

#define PROGRESS_STEPS 200

extern int omp_in_parallel(void) __attribute__((weak));
extern int omp_get_thread_num(void) __attribute__((weak));

static volatile sig_atomic_t interrupt_requested;

static _Thread_local const sl_progress *last_object;
static _Thread_local int last_step;          /* last reported 1/200 step */
static _Thread_local const char *last_phase; /* a new phase reports at once */

volatile sig_atomic_t *sl_interrupt_flag(void)
{
    return &interrupt_requested;
}

static int is_master_thread(void)
{
    if (!omp_in_parallel || !omp_get_thread_num || !omp_in_parallel())
        return 1;
    return omp_get_thread_num() == 0;
}

static int same_phase(const char *a, const char *b)
{
    return a == b || (a && b && !strcmp(a, b));
}

int sl_progress_step(sl_progress *p, const char *phase, double fraction)
{
    if (!p)
        return 0;
    if (p->report && is_master_thread()) {
        double f = fraction > 0 ? (fraction < 1 ? fraction : 1) : 0; /* NaN -> 0 */
        int step = (int)(f * PROGRESS_STEPS);
        if (p != last_object || step != last_step || !same_phase(phase, last_phase)) {
            last_object = p;
            last_step = step;
            last_phase = phase;
            p->report(p->ctx, phase, f);
        }
    }
    return sl_progress_interrupted(p);
}
