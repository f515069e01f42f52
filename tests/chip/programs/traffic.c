/*
 * traffic.c - every core tile sends ROUNDS packets of pseudo-random length (1..40 payload flits)
 * to every other core tile, receiving in its interrupt handler, and prints a checksum of what it
 * received and the cycle it finished.  Used to check that the quantum scheme of the chip
 * simulator gives exactly the results of lockstep simulation under contention.
 */
#include "core_peers.h"
#include "hf_noc.h"
#include "hf_print.h"

#ifndef ROUNDS
#define ROUNDS 6
#endif

static uint16_t tx[HF_NI_MAX_FLITS], rx[HF_NI_MAX_FLITS];
static volatile uint32_t got, sum;

void irq_handler(uint32_t cause)
{
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
    hf_irq_mask(HF_IRQ_NI);
    hf_irq_enable();
    uint32_t seed = me * 2654435761u + 1u;
    for (int r = 0; r < ROUNDS; r++) {
        for (uint32_t p = 0; p < np; p++) {
            seed = seed * 1103515245u + 12345u;
            uint32_t len = 1u + (seed >> 16) % 40u;
            tx[0] = (uint16_t)peers[p];
            tx[1] = (uint16_t)len;
            for (uint32_t k = 0; k < len; k++) {
                tx[2 + k] = (uint16_t)((seed >> (k & 15u)) ^ k);
            }
            hf_ni_send(tx, len + 2u);
            for (volatile uint32_t d = 0; d < ((seed >> 8) & 63u); d++) {
            }
        }
    }
    hf_irq_disable();
    while (got < ROUNDS * np) { /* no lost wake-up: see hf_sleep() */
        hf_sleep();
        hf_irq_enable();
        hf_irq_disable();
    }
    hf_irq_enable();
    hf_printf("tile %x got %u sum %x at %u\n", me, got, sum, hf_cycles());
    return 0;
}
