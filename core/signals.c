/* Interrupt flag plumbing (see signals.h). */
#include "core/signals.h"

#include <signal.h>
#include <string.h>

#include "core/progress.h"

static volatile sig_atomic_t received;

static void on_signal(int sig)
{
    received = sig;
    *sl_interrupt_flag() = 1;
}

void sl_signals_install(void)
{
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal;
    sigemptyset(&sa.sa_mask);
    /* No SA_RESTART: a blocking wait should return and let the caller see the flag. */
    int signals[] = {SIGTERM, SIGINT, SIGHUP, SIGUSR1};
    for (size_t i = 0; i < sizeof signals / sizeof signals[0]; i++)
        sigaction(signals[i], &sa, NULL);
    signal(SIGPIPE, SIG_IGN);
}

int sl_signals_received(void)
{
    return received;
}
