/*
 * hf_noc.h - the network interface of an MPSoC tile (docs/platform.md, "Network interface").
 *
 * Packets are arrays of 16-bit flits in the ORCA wire format: flit 0 is the destination
 * (x << 4) | y, flit 1 the number of flits that follow, then the payload: 3 to 64 flits in all
 * (at least one payload flit: on the Hermes RTL an empty packet swallows the next one, so the
 * NI refuses it and the run stops with an error naming the tile and pc).  SEND copies the
 * packet into the NI by DMA (the core stalls one cycle per flit) and injects it; RECV copies
 * the waiting packet out (one cycle per flit) and frees the receive memory.  IRQ_CAUSE bit 1
 * is up while a packet waits.
 */
#ifndef HF_NOC_H
#define HF_NOC_H

#include <stdint.h>

#include "hfriscv.h"

#define HF_NI_BASE 0xe1040000u
#define HF_NI_STATUS (HF_NI_BASE + 0x00u)     /* bit 0 send busy, bit 1 packet waiting */
#define HF_NI_SEND_ADDR (HF_NI_BASE + 0x04u)
#define HF_NI_SEND_SIZE (HF_NI_BASE + 0x08u)  /* flits, header included: 3..64 */
#define HF_NI_CMD (HF_NI_BASE + 0x0cu)        /* 1 SEND, 2 RECV */
#define HF_NI_RECV_ADDR (HF_NI_BASE + 0x10u)
#define HF_NI_RECV_SIZE (HF_NI_BASE + 0x14u)  /* flits of the waiting packet, 0 if none */
#define HF_NI_TILE (HF_NI_BASE + 0x18u)       /* this tile: (x << 4) | y */
#define HF_NI_MESH (HF_NI_BASE + 0x1cu)       /* width | height << 8 */
#define HF_TASK_ID (HF_NI_BASE + 0x20u)       /* running task, for per-task accounting */
#define HF_SLEEP (HF_NI_BASE + 0x24u)         /* write: sleep until IRQ_CAUSE & IRQ_MASK != 0 */
#define HF_NI_IO_TILE (HF_NI_BASE + 0x28u)    /* the I/O tile's address */

#define HF_NI_SEND_BUSY (1u << 0)
#define HF_NI_RECV_READY (1u << 1)
#define HF_IRQ_NI (1u << 1)                   /* IRQ_CAUSE / IRQ_MASK bit of the network interface */
#define HF_NI_MAX_FLITS 64
#define HF_NI_MIN_FLITS 3

static inline uint32_t hf_tile(void) { return HF_REG32(HF_NI_TILE); }
static inline uint32_t hf_tile_x(void) { return HF_REG32(HF_NI_TILE) >> 4; }
static inline uint32_t hf_tile_y(void) { return HF_REG32(HF_NI_TILE) & 15u; }
static inline uint32_t hf_io_tile(void) { return HF_REG32(HF_NI_IO_TILE); }
static inline void hf_set_task(uint32_t id) { HF_REG32(HF_TASK_ID) = id; }
/*
 * Sleep until an enabled cause is up (IRQ_CAUSE & IRQ_MASK != 0).  With interrupts enabled the
 * interrupt is entered as the core wakes; with them disabled the core just resumes after the
 * store, like RISC-V's WFI, and the interrupt is taken when software enables interrupts.
 *
 * An interrupt can come at any instruction boundary, so "check, then sleep" with interrupts on
 * can miss the wake-up that arrives between the two.  Wait with hf_wait_for(), or this idiom:
 *     uint32_t s = hf_irq_disable();
 *     while (!condition) { hf_sleep(); hf_irq_enable(); hf_irq_disable(); }
 *     hf_irq_restore(s);
 */
static inline void hf_sleep(void) { HF_REG32(HF_SLEEP) = 1u; }

/* Sleep until `*flag` (set by an interrupt handler) is non-zero, without a lost wake-up. */
static inline void hf_wait_for(volatile uint32_t *flag)
{
    uint32_t state = hf_irq_disable();
    while (*flag == 0u) {
        hf_sleep();
        hf_irq_enable();
        hf_irq_disable();
    }
    hf_irq_restore(state);
}

/* Send `n` flits (3..64) from `packet` (flit 0 and 1 already filled); waits for the send memory first. */
static inline void hf_ni_send(const uint16_t *packet, uint32_t n)
{
    while (HF_REG32(HF_NI_STATUS) & HF_NI_SEND_BUSY) {
    }
    HF_REG32(HF_NI_SEND_ADDR) = (uint32_t)(uintptr_t)packet;
    HF_REG32(HF_NI_SEND_SIZE) = n;
    HF_REG32(HF_NI_CMD) = 1u;
}

/* Build and send a packet to tile `dest` with `len` payload flits (1..62). */
static inline void hf_ni_send_to(uint32_t dest, const uint16_t *payload, uint32_t len, uint16_t *buffer)
{
    buffer[0] = (uint16_t)dest;
    buffer[1] = (uint16_t)len;
    for (uint32_t k = 0; k < len; k++) {
        buffer[2 + k] = payload[k];
    }
    hf_ni_send(buffer, len + 2);
}

/* 1 when a packet waits in the receive memory. */
static inline int hf_ni_ready(void) { return (HF_REG32(HF_NI_STATUS) & HF_NI_RECV_READY) != 0; }

/* Copy the waiting packet (whole, header included) to `buffer`; returns its flit count. */
static inline uint32_t hf_ni_recv(uint16_t *buffer)
{
    uint32_t n = HF_REG32(HF_NI_RECV_SIZE);
    HF_REG32(HF_NI_RECV_ADDR) = (uint32_t)(uintptr_t)buffer;
    HF_REG32(HF_NI_CMD) = 2u;
    return n;
}

/* Busy-wait for a packet, then receive it. */
static inline uint32_t hf_ni_recv_wait(uint16_t *buffer)
{
    while (!hf_ni_ready()) {
    }
    return hf_ni_recv(buffer);
}

#endif
