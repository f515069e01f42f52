/*
 * sync.c - semaphores, delays, yields and round robin among best-effort tasks.
 *
 * Results are left in `results` (words) for the host:
 *   [0..2]   delay: (tick before os_delay(DELAY), TIMER0 after it) x 3 -> words 0..5
 *   [8..]    ping-pong: TIMER0 before A blocks, TIMER0 when B has the semaphore, PINGS times
 *   [40..47] yield: letter << 24 | tick, each time task 'A' or 'B' runs between os_yield calls
 *   [60..61] round robin: counts of two equal-priority spinners when the checker woke
 */
#include "os.h"

#ifndef DELAY
#define DELAY 3
#endif
#define PINGS 8

volatile uint32_t results[64];
static os_sem_t to_a, to_b, finished;
static volatile uint32_t spins[2];
static volatile uint32_t order_len;

static void delayer(void *arg)
{
    (void)arg;
    for (uint32_t k = 0; k < 3; k++) {
        results[2 * k] = os_ticks();
        os_delay(DELAY);
        results[2 * k + 1] = os_cycles();
    }
    os_sem_post(&finished);
}

static void ping(void *arg)
{
    (void)arg;
    for (uint32_t k = 0; k < PINGS; k++) {
        os_sem_post(&to_b); /* B has the same priority: it becomes ready but does not preempt */
        results[8 + 2 * k] = os_cycles();
        os_sem_wait(&to_a); /* blocks: the voluntary switch to B */
    }
    os_sem_post(&finished);
}

static void pong(void *arg)
{
    (void)arg;
    for (uint32_t k = 0; k < PINGS; k++) {
        os_sem_wait(&to_b);
        results[8 + 2 * k + 1] = os_cycles();
        os_sem_post(&to_a);
    }
    os_sem_post(&finished);
}

static void yielder(void *arg)
{
    uint32_t me = (uint32_t)(uintptr_t)arg;
    for (uint32_t k = 0; k < 4; k++) {
        results[40u + order_len++] = me << 24 | (os_ticks() & 0xffffffu);
        os_yield();
    }
    os_sem_post(&finished);
}

static void spinner(void *arg)
{
    uint32_t i = (uint32_t)(uintptr_t)arg;
    for (;;) {
        spins[i]++;
    }
}

static void checker(void *arg)
{
    (void)arg;
    for (uint32_t k = 0; k < 4; k++) { /* the yielders, the delayer, ping and pong */
        os_sem_wait(&finished);
    }
    os_sem_wait(&finished);
    os_delay(4); /* meanwhile two spinners of equal priority share the core at ticks */
    results[60] = spins[0];
    results[61] = spins[1];
    os_exit(0);
}

int main(void)
{
    os_sem_init(&to_a, 0);
    os_sem_init(&to_b, 0);
    os_sem_init(&finished, 0);
    os_task_best_effort(checker, 0, 9, 0);
    os_task_best_effort(delayer, 0, 8, 0);
    os_task_best_effort(yielder, (void *)'A', 5, 0);
    os_task_best_effort(yielder, (void *)'B', 5, 0);
    os_task_best_effort(ping, 0, 3, 0);
    os_task_best_effort(pong, 0, 3, 0);
    os_task_best_effort(spinner, (void *)0, 1, 0);
    os_task_best_effort(spinner, (void *)1, 1, 0);
    os_start();
}
