/*
 * periodic.c - periodic real-time tasks from a table, optionally with a best-effort spinner.
 *
 * TASK_SPEC is a brace list of {period, capacity, deadline, work} (ticks, work in loop
 * iterations of exactly 4 cycles); task i gets TASK_ID 2 + i.  The run ends when task 0 starts
 * its job number STOP_JOBS + 1 (that job is not logged).  With SPINNER, a best-effort task counts
 * in a loop for ever (it never blocks or yields: only preemption lets the others run).  With
 * SAMPLE_TIMER1, every job of task 0 stores TIMER1 and TIMER0 read back to back.
 */
#include "os.h"

#ifndef TASK_SPEC
#define TASK_SPEC {{2, 1, 2, 0}}
#endif
#ifndef STOP_JOBS
#define STOP_JOBS 4
#endif

typedef struct {
    uint32_t period, capacity, deadline, work;
} spec_t;
static const spec_t specs[] = TASK_SPEC;
#define NTASKS (sizeof specs / sizeof specs[0])

static volatile uint32_t jobs0;
volatile uint32_t spinner_count;
volatile uint32_t timer_samples[2 * 16];

/* n iterations of addi + taken bnez: 4 cycles each, no multiply (no erratum on interrupts) */
static void spin(uint32_t n)
{
    if (n != 0u) {
        __asm__ volatile("1: addi %0, %0, -1\n\tbnez %0, 1b" : "+r"(n));
    }
}

static void job(void *arg)
{
    uint32_t i = (uint32_t)(uintptr_t)arg;
    if (i == 0u) {
        if (++jobs0 > STOP_JOBS) {
            os_exit(0);
        }
#ifdef SAMPLE_TIMER1
        uint32_t t1, t0;
        __asm__ volatile("lui t0, 0xe1024\n\tlw %0, 0x400(t0)\n\tlw %1, 0(t0)" : "=r"(t1), "=r"(t0) : : "t0");
        if (jobs0 <= 16u) {
            timer_samples[2u * (jobs0 - 1u)] = t1;
            timer_samples[2u * (jobs0 - 1u) + 1u] = t0;
        }
#endif
    }
    spin(specs[i].work);
}

#ifdef SPINNER
static void spinner(void *arg)
{
    (void)arg;
    for (;;) {
        spinner_count++;
    }
}
#endif

int main(void)
{
    for (uint32_t i = 0; i < NTASKS; i++) {
        if (os_task_periodic(job, (void *)(uintptr_t)i, specs[i].period, specs[i].capacity, specs[i].deadline, 0) !=
            (int)(OS_FIRST_TASK_ID + i)) {
            os_exit(100u + i);
        }
    }
#ifdef SPINNER
    os_task_best_effort(spinner, 0, 1, 0);
#endif
    os_start();
}
