/* The wall clock (clock.h). */
#include "core/clock.h"

#include <time.h>

double sl_now_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_REALTIME, &ts);
    return (double)ts.tv_sec + ts.tv_nsec * 1e-9;
}
