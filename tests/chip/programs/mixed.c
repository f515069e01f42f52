/*
 * mixed.c - core tiles that ignore the packet line for long stretches next to tiles that take packet
 * interrupts, for the check that the chip's long quanta (kernels/chip.py) give the lockstep results.
 *
 * Every core tile sends ROUNDS packets of pseudo-random length to every other core tile, with
 * pseudo-random computation in between, and prints what it received and the cycle it finished.
 * Its role comes from its address and SEED:
 *   0 poller: IRQ_MASK bit 1 clear; receives by polling, alternately NI_STATUS and IRQ_CAUSE (the
 *     chip loop must stop it before IRQ_CAUSE reads it cannot vouch for yet);
 *   1 ticker: a poller with a TIMER1 tick interrupt, waiting for its last packets asleep (woken by
 *     the tick only: a sleeper the packets cannot wake);
 *   2 late: polls for its first LATE rounds, then sets IRQ_MASK bit 1 and receives in its handler
 *     (the store that sets the bit must not run inside a long quantum).
 */
#include "core_peers.h"
#include "hf_noc.h"
#include "hf_print.h"

#ifndef ROUNDS
#define ROUNDS 3
#endif
#ifndef SEED
#define SEED 1
#endif
#ifndef LATE
#define LATE 1
#endif

static uint16_t tx[HF_NI_MAX_FLITS], rx[HF_NI_MAX_FLITS];
static volatile uint32_t got, sum, ticks, injected, by_irq;
static volatile int irq; /* 1 once the packet line is unmasked: the handler receives */

static void take(void)
{
    uint32_t n = hf_ni_recv(rx);
    if (n > 2 && rx[2] == 0xffffu) {
        injected++;
    } else {
        got++;
    }
    for (uint32_t k = 2; k < n; k++) {
        sum = sum * 31u + rx[k];
    }
}

void irq_handler(uint32_t cause)
{
    if (cause & 1u) {
        HF_REG32(HF_TIMERCAUSE_INV) ^= HF_TIMERCAUSE_T1_CTC; /* acknowledge the tick */
        ticks++;
    }
    if (irq && (cause & HF_IRQ_NI)) {
        take();
        by_irq++;
    }
}

static int polled(uint32_t k)
{
    if (k & 1u) {
        return (HF_REG32(HF_IRQ_CAUSE) & HF_IRQ_NI) != 0;
    }
    return hf_ni_ready();
}

int main(void)
{
    uint32_t me = hf_tile();
    uint32_t peers[256];
    uint32_t np = core_peers(peers);
    uint32_t seed = me * 2654435761u + (uint32_t)SEED * 40503u + 1u;
    uint32_t role = (me * 7u + (uint32_t)SEED) % 3u;
    if (role == 1) {
        HF_REG32(HF_TIMER1_PRE) = 0;
        HF_REG32(HF_TIMER1_CTC) = 1500u + (seed >> 20);
        HF_REG32(HF_TIMERMASK) = HF_TIMERCAUSE_T1_CTC;
        hf_irq_mask(1u);
        hf_irq_enable();
    }
    uint32_t polls = 0;
    for (int r = 0; r < ROUNDS; r++) {
        if (role == 2 && r == LATE) {
            hf_irq_disable();
            while (hf_ni_ready()) {
                take();
            }
            irq = 1;
            hf_irq_mask(HF_IRQ_NI);
            hf_irq_enable();
        }
        for (uint32_t p = 0; p < np; p++) {
            seed = seed * 1103515245u + 12345u;
            uint32_t len = 1u + (seed >> 16) % 40u;
            tx[0] = (uint16_t)peers[(p + r) % np];
            tx[1] = (uint16_t)len;
            for (uint32_t k = 0; k < len; k++) {
                tx[2 + k] = (uint16_t)((seed >> (k & 15u)) ^ (k * me));
            }
            while (HF_REG32(HF_NI_STATUS) & HF_NI_SEND_BUSY) {
                if (!irq && polled(polls++)) {
                    take();
                }
            }
            HF_REG32(HF_NI_SEND_ADDR) = (uint32_t)(uintptr_t)tx;
            HF_REG32(HF_NI_SEND_SIZE) = len + 2u;
            HF_REG32(HF_NI_CMD) = 1u;
            uint32_t work = (seed >> 8) & ((seed & 0x100u) ? 1023u : 31u);
            uint32_t acc = seed;
            for (uint32_t d = 0; d < work; d++) {
                acc = acc * 2654435761u + d;
            }
            sum ^= acc & 1u;
            if (!irq && polled(polls++)) {
                take();
            }
        }
    }
    uint32_t expected = (uint32_t)ROUNDS * np;
    if (irq) {
        hf_irq_disable();
        while (got < expected) { /* no lost wake-up: see hf_sleep() */
            hf_sleep();
            hf_irq_enable();
            hf_irq_disable();
        }
        hf_irq_enable();
    } else if (role == 1) {
        while (got < expected) {
            while (hf_ni_ready()) {
                take();
            }
            if (got < expected) {
                hf_irq_disable();
                hf_sleep(); /* the tick wakes it, not the packets */
                hf_irq_enable();
            }
        }
    } else {
        while (got < expected) {
            if (polled(polls++)) {
                take();
            }
        }
    }
    hf_printf("tile %x role %u got %u injected %u irq %u sum %x ticks %u at %u\n", me, role, got, injected,
              by_irq, sum, ticks, hf_cycles());
    return 0;
}
