/*
 * busy_handlers.c - core tiles that spend most of each tick inside their interrupt handler with the
 * packet line unmasked (IRQ_MASK bit 1 set) while packets fly between them, for the check that the
 * chip's long quanta of cores inside a handler (kernels/chip.py: a done controller hears no packet)
 * give the lockstep results.
 *
 * Every core tile takes the same TIMER1 tick, so all enter their handler in the same cycle.  The
 * handler acknowledges the tick and computes for about WORK iterations (a multiply each); a quarter
 * of the way in it sends a packet to a peer (a send inside a long quantum), three quarters of the way
 * in it reads IRQ_CAUSE and receives if a packet waits (a read of the line the chip loop must vouch
 * for).  A packet that arrives after that read raises the line while the controller is done: the
 * store that re-enables interrupts at the handler's end (which must not run inside a long quantum)
 * lets it in at once.  main sleeps between ticks; after TICKS ticks it prints what it saw.
 */
#include "core_peers.h"
#include "hf_noc.h"
#include "hf_print.h"

#ifndef TICKS
#define TICKS 8
#endif
#ifndef WORK
#define WORK 200
#endif
#ifndef PERIOD
#define PERIOD 5000
#endif

static uint16_t tx[8], rx[HF_NI_MAX_FLITS];
static volatile uint32_t ticks, got, late, seen, sum;
static uint32_t me, np;
static uint32_t peers[256];

static void take(void)
{
    uint32_t n = hf_ni_recv(rx);
    got++;
    for (uint32_t k = 2; k < n; k++) {
        sum = sum * 31u + rx[k];
    }
}

void irq_handler(uint32_t cause)
{
    if (cause & 1u) {
        HF_REG32(HF_TIMERCAUSE_INV) ^= HF_TIMERCAUSE_T1_CTC; /* acknowledge the tick */
        uint32_t k = ticks++;
        uint32_t work = WORK + (me * 37u + k * 11u) % 64u;
        uint32_t acc = me + k;
        for (uint32_t d = 0; d < work; d++) {
            acc = acc * 2654435761u + d;
            if (d == work / 4 && k + 2 < TICKS) {
                for (uint32_t j = 0; j < 4; j++) {
                    tx[2 + j] = (uint16_t)(acc >> (4 * j));
                }
                hf_ni_send_to(peers[k % np], &tx[2], 4, tx);
            }
            if (d == 3 * work / 4 && (HF_REG32(HF_IRQ_CAUSE) & HF_IRQ_NI) != 0) {
                seen++;
                take();
            }
        }
        sum ^= acc;
    } else if (cause & HF_IRQ_NI) {
        late++;
        take();
    }
}

int main(void)
{
    me = hf_tile();
    np = core_peers(peers);
    HF_REG32(HF_TIMER1_PRE) = 0;
    HF_REG32(HF_TIMER1_CTC) = PERIOD;
    HF_REG32(HF_TIMERMASK) = HF_TIMERCAUSE_T1_CTC;
    hf_irq_mask(1u | HF_IRQ_NI);
    hf_irq_enable();
    while (ticks < TICKS) {
        hf_sleep();
    }
    hf_irq_disable();
    hf_printf("tile %x ticks %u got %u seen %u late %u sum %x at %u\n", me, ticks, got, seen, late, sum, hf_cycles());
    return 0;
}
