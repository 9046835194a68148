/* The wall clock, in seconds since the epoch (leases, scan stamps, timings: values other
 * processes and hosts compare, so CLOCK_REALTIME, not a monotonic clock). */
#ifndef SCANLOD_CORE_CLOCK_H
#define SCANLOD_CORE_CLOCK_H

double sl_now_seconds(void);

#endif
