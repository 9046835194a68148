/* Signals only set a flag (sl_interrupt_flag); long work polls it through sl_progress.
 * SIGTERM, SIGINT, SIGHUP: stop at a safe point. SIGUSR1 (Slurm's pre-timeout warning):
 * the same -- no new claims, in-flight items are released, exit 75. */
#ifndef SCANLOD_CORE_SIGNALS_H
#define SCANLOD_CORE_SIGNALS_H

void sl_signals_install(void);
/* The signal that set the flag, 0 if none. */
int sl_signals_received(void);

#endif
