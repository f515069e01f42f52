/*
 * port_hfriscv.c - the C half of the HF-RISCV port: first task frames and the tick timer.
 */
#include "os_config.h"
#include "port.h"

/* port_asm.S */
uint32_t port_timer1_write_at(uint32_t target, uint32_t value);
uint32_t port_timer1_sample(uint32_t *timer0);

uint32_t *port_stack_init(uint32_t *top, void (*entry)(void), uint32_t task_id)
{
    uint32_t *frame = (uint32_t *)((uintptr_t)top & ~(uintptr_t)15u) - PORT_FRAME_WORDS;
    for (uint32_t k = 0; k < PORT_FRAME_WORDS; k++) {
        frame[k] = 0;
    }
    frame[PORT_FRAME_PC] = (uint32_t)(uintptr_t)entry;
    frame[PORT_FRAME_TASK_ID] = task_id;
    return frame; /* ra = 0: a task entry that returned would jump outside SRAM, a clear error */
}

/*
 * Cycles between reading TIMER0 and the count pulse chosen for the TIMER1 write: room for the
 * two divisions below, which are compiler-rt loops without a divider (a few hundred cycles).
 */
#define PORT_ALIGN_MARGIN 2048u

/*
 * Why TIMER1 is written once, and when (docs/platform.md, "Timers").  With prescaler p = 4^PRE,
 * count pulses come in the device cycles y with (y - 1) a multiple of p, y >= 2, whatever TIMER1
 * holds; after a pulse the new value holds from y + 1, so in cycle x the pulses i = 1, 2, ... (in cycles
 * p*i + 1) up to floor((x - 2) / p) have taken effect.  If TIMER1 holds that count modulo N = CTC + 1,
 * the clearing pulses (TIMER1 = CTC) are those with i a multiple of N, in cycles j*N*p + 1, and
 * the compare flag toggles into view in cycle j * OS_TICK_CYCLES + 2: tick j.
 *
 * The write lands unless a pulse falls in the cycle before the value holds (then it is lost), so
 * it must hold from a cycle w with p*m + 1 < w - 1 < p*(m + 1) + 1 and then carries m mod N.
 * port_timer1_write_at() places w within target + 5 .. target + 10; with target = p*m - 2 that is
 * p*m + 3 .. p*m + 8, inside the window for p >= 16 (os_config.h).  Read back to make sure.
 */
uint32_t port_tick_start(uint32_t *aligned_at)
{
    const uint32_t shift = 2u * OS_TICK_PRE;
    const uint32_t n = OS_TICK_CTC + 1u;
    HF_REG32(HF_TIMERMASK) = 0u;
    HF_REG32(HF_TIMER1_PRE) = OS_TICK_PRE;
    HF_REG32(HF_TIMER1_CTC) = OS_TICK_CTC;
    uint32_t m = ((hf_cycles() + PORT_ALIGN_MARGIN) >> shift) + 1u;
    uint32_t value = m % n;
    uint32_t first_tick = m / n + 1u;
    port_timer1_write_at((m << shift) - 2u, value);
    uint32_t t0;
    uint32_t v = port_timer1_sample(&t0); /* TIMER1 of cycle t0 - 3 */
    if (v != ((t0 - 5u) >> shift) % n) {
        return 0u; /* the write missed its window: the caller stops with a message */
    }
    port_tick_ack(); /* the flag may have toggled before: compare against its current state */
    HF_REG32(HF_TIMERMASK) = HF_TIMERCAUSE_T1_CTC;
    *aligned_at = t0;
    return first_tick;
}
