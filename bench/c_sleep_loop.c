/* The edge scheduler's schedule in C, as the reference for what this machine can do:
 * absolute 1 ms deadlines on CLOCK_MONOTONIC, clock_nanosleep until 300 us before each, then
 * spin. Counts ticks that start more than one period late.
 * Usage: c_sleep_loop TICKS [fifo]   (fifo: SCHED_FIFO priority 80)
 */
#define _GNU_SOURCE
#include <sched.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

static long long now_ns(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec * 1000000000LL + ts.tv_nsec;
}

int main(int argc, char **argv) {
    long ticks = argc > 1 ? atol(argv[1]) : 10000;
    if (argc > 2 && strcmp(argv[2], "fifo") == 0) {
        struct sched_param param = {.sched_priority = 80};
        if (sched_setscheduler(0, SCHED_FIFO, &param) != 0) {
            perror("sched_setscheduler");
            return 2;
        }
    }
    const long long period = 1000000, spin = 300000;
    long long origin = now_ns(), worst = 0;
    long overruns = 0;
    for (long k = 0; k < ticks; k++) {
        long long deadline = origin + k * period, wake = deadline - spin;
        struct timespec ts = {wake / 1000000000LL, wake % 1000000000LL};
        clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, NULL);
        while (now_ns() < deadline) {
        }
        long long late = now_ns() - deadline;
        if (late > worst) worst = late;
        if (late > period) {
            overruns++;
            k += late / period; /* skip the missed slots, as the Python scheduler does */
        }
    }
    printf("%ld %lld\n", overruns, worst / 1000);
    return 0;
}
