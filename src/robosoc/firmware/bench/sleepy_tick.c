/*
 * sleepy_tick.c - a mostly sleeping core for `robosoc bench chip`.
 *
 * TIMER1 counts every 16 cycles and clears at CTC = 15624, so its compare flag toggles every
 * 250 000 cycles (1 ms at 250 MHz).  Each tick wakes the core, the interrupt handler
 * acknowledges the tick and does a little work (a few hundred instructions, like a control task),
 * and the core goes back to sleep.  After TICKS ticks the program exits.  WORK sets the handler's
 * loop (default 64 rounds).
 */
#include <stdint.h>

#include "hf_noc.h"
#include "hfriscv.h"

#ifndef TICKS
#define TICKS 20
#endif
#ifndef WORK
#define WORK 64
#endif

static volatile uint32_t ticks;
static volatile uint32_t work;

void irq_handler(uint32_t cause)
{
    if (!(cause & 1u)) {
        return;
    }
    HF_REG32(HF_TIMERCAUSE_INV) ^= HF_TIMERCAUSE_T1_CTC; /* acknowledge the toggle */
    ticks++;
    uint32_t acc = work;
    for (uint32_t i = 0; i < WORK; i++) {
        acc = acc * 3u + i;
    }
    work = acc;
}

int main(void)
{
    HF_REG32(HF_TIMER1_PRE) = 2;      /* /16 */
    HF_REG32(HF_TIMER1_CTC) = 15624;  /* 15625 * 16 = 250 000 cycles per toggle */
    HF_REG32(HF_TIMERMASK) = HF_TIMERCAUSE_T1_CTC;
    hf_irq_mask(1u);
    while (ticks < TICKS) { /* interrupts off between the check and the sleep: see hf_sleep() */
        hf_sleep();
        hf_irq_enable();
        hf_irq_disable();
    }
    return 0;
}
