/*
 * all_to_all.c - traffic through every router, in three tasks, for the tests of the chip's totals
 * (tests/chip/test_chip_totals.py, which works out the same packets in Python).
 *
 * Every core tile sends one packet to every other core tile (in core_peers() order) and then one
 * to the I/O tile; packet k of a tile has 1 + (seed_k >> 16) % 40 payload flits, with
 * seed_0 = tile address * 2654435761 + 1 and seed_k+1 = seed_k * 1103515245 + 12345 (mod 2**32),
 * the generator of traffic.c.  Each tile receives, in its interrupt handler, every other core's
 * packet and one packet the host injects from the I/O tile (none when built with FROM_IO=0, for
 * `robosoc run`, which injects nothing), and prints how many it got.
 *
 * Tasks (TASK_ID): the tile's own task 1 + (x + y * width) % 14 fills each packet's payload, the
 * last task id (15) sends it, and task 0 (the id after reset) does the rest: start-up, waiting
 * asleep for the packets still to come, the report.
 */
#include "core_peers.h"
#include "hf_noc.h"
#include "hf_print.h"

#ifndef FROM_IO
#define FROM_IO 1
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
    uint32_t width = HF_REG32(HF_NI_MESH) & 0xffu;
    uint32_t own = 1u + ((me >> 4) + (me & 15u) * width) % 14u;
    uint32_t peers[257];
    uint32_t np = core_peers(peers);
    peers[np++] = hf_io_tile();
    hf_irq_mask(HF_IRQ_NI);
    hf_irq_enable();
    uint32_t seed = me * 2654435761u + 1u;
    for (uint32_t p = 0; p < np; p++) {
        hf_set_task(own);
        seed = seed * 1103515245u + 12345u;
        uint32_t len = 1u + (seed >> 16) % 40u;
        for (uint32_t k = 0; k < len; k++) {
            tx[2 + k] = (uint16_t)((seed >> (k & 15u)) ^ k);
        }
        hf_set_task(15);
        tx[0] = (uint16_t)peers[p];
        tx[1] = (uint16_t)len;
        hf_ni_send(tx, len + 2u);
    }
    hf_set_task(0);
    hf_irq_disable();
    while (got < np - 1u + FROM_IO) { /* no lost wake-up: see hf_sleep() */
        hf_sleep();
        hf_irq_enable();
        hf_irq_disable();
    }
    hf_irq_enable();
    hf_printf("tile %x got %u sum %x\n", me, got, sum);
    return 0;
}
