/*
 * handlers.c - long interrupt handlers that packets arrive during, for the check that the chip's
 * long quanta (kernels/chip.py) give the lockstep results when cores run their handlers in them.
 *
 * Every core tile takes a TIMER1 tick of its own period with IRQ_MASK bit 1 (the packet line) set,
 * and spends a pseudo-random 50..450 iterations of work in the tick's handler, with interrupts
 * off and no network-interface access: such a core hears no packet until its handler returns (the
 * return's IRQ_STATUS store), so the chip runs it in long quanta while the others send it packets.
 * Between ticks each tile sends ROUNDS packets to every other core tile with work in between,
 * receiving in its handler, then waits asleep for the rest (a sleep with interrupts off and the
 * packet line unmasked: woken by a packet or a tick).  Each tile prints what it received, its
 * ticks, a checksum and the cycle it finished.
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

static uint16_t tx[HF_NI_MAX_FLITS], rx[HF_NI_MAX_FLITS];
static volatile uint32_t got, sum, ticks, work_seed;

void irq_handler(uint32_t cause)
{
    if (cause & 1u) {
        HF_REG32(HF_TIMERCAUSE_INV) ^= HF_TIMERCAUSE_T1_CTC; /* acknowledge the tick */
        ticks++;
        uint32_t s = work_seed * 1103515245u + 12345u;
        work_seed = s;
        uint32_t acc = s;
        for (uint32_t d = 0; d < 50u + ((s >> 16) % 400u); d++) {
            acc = acc * 2654435761u + d;
        }
        sum ^= acc & 1u;
    }
    if (cause & HF_IRQ_NI) {
        uint32_t n = hf_ni_recv(rx);
        for (uint32_t k = 2; k < n; k++) {
            sum = sum * 31u + rx[k];
        }
        got++;
    }
}

int main(void)
{
    uint32_t me = hf_tile();
    uint32_t peers[256];
    uint32_t np = core_peers(peers);
    uint32_t seed = me * 2654435761u + (uint32_t)SEED * 40503u + 1u;
    work_seed = seed ^ 0x9e3779b9u;
    HF_REG32(HF_TIMER1_PRE) = 0;
    HF_REG32(HF_TIMER1_CTC) = 7000u + (me & 0xfu) * 613u + (me >> 4) * 1021u;
    HF_REG32(HF_TIMERMASK) = HF_TIMERCAUSE_T1_CTC;
    hf_irq_mask(1u | HF_IRQ_NI);
    hf_irq_enable();
    for (int r = 0; r < ROUNDS; r++) {
        for (uint32_t p = 0; p < np; p++) {
            seed = seed * 1103515245u + 12345u;
            uint32_t len = 1u + (seed >> 16) % 40u;
            tx[0] = (uint16_t)peers[(p + r) % np];
            tx[1] = (uint16_t)len;
            for (uint32_t k = 0; k < len; k++) {
                tx[2 + k] = (uint16_t)((seed >> (k & 15u)) ^ (k * me));
            }
            hf_ni_send(tx, len + 2u);
            uint32_t acc = seed;
            for (uint32_t d = 0; d < ((seed >> 8) & 2047u); d++) {
                acc = acc * 2654435761u + d;
            }
            sum ^= acc & 1u;
        }
    }
    uint32_t expected = (uint32_t)ROUNDS * np;
    hf_irq_disable();
    while (got < expected) { /* no lost wake-up: see hf_sleep() */
        hf_sleep();
        hf_irq_enable();
        hf_irq_disable();
    }
    hf_irq_enable();
    hf_printf("tile %x got %u sum %x ticks %u at %u\n", me, got, sum, ticks, hf_cycles());
    return 0;
}
