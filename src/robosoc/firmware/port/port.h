/*
 * port.h - what the portable kernel needs from the hardware: the HF-RISCV tile port.
 *
 * The contract (FreeRTOS's portable.h in spirit): build a task's first context frame, start the
 * first task, switch voluntarily, mask interrupts, run the tick, sleep, name the running task to
 * the simulator, and drive the network interface.  port_asm.S holds the context switch; the
 * interrupt entry there calls os_port_interrupt() and the voluntary switch os_port_switch(), the
 * two ways into the kernel, both on the kernel stack with interrupts disabled.
 *
 * Context frame (one format for both ways in), 32 words on the task's stack, sp points at it:
 *   word 0 pc to resume at          word 1 ra       words 2-4 t0-t2     words 5-6 s0-s1
 *   words 7-14 a0-a7                words 15-23 s2-s10                  words 24-27 t3-t6
 *   word 28 TASK_ID to resume with  words 29-31 unused (keep sp 16-byte aligned)
 * gp is the same for every task, tp and s11 belong to the interrupt return (docs/platform.md).
 */
#ifndef PORT_H
#define PORT_H

#include <stdint.h>

#include "hf_noc.h"
#include "hfriscv.h"

#define PORT_FRAME_WORDS 32
#define PORT_FRAME_PC 0
#define PORT_FRAME_RA 1
#define PORT_FRAME_A0 7
#define PORT_FRAME_TASK_ID 28

/* Interrupt causes as the kernel sees them (IRQ_CAUSE bits) */
#define PORT_CAUSE_TICK 1u /* bit 0: SoC peripheral line, only TIMER1's compare flag is unmasked */
#define PORT_CAUSE_NI HF_IRQ_NI

/* ---- Context switch (port_asm.S) -------------------------------------------------------- */
/* Switch away from the running task; returns when it is dispatched again, with interrupts
 * enabled.  Call with interrupts disabled, from kernel code (TASK_ID 0, resumed as such). */
void port_yield(void);
/* Dispatch os_current for the first time (interrupts disabled); never returns. */
void port_start_first(void) __attribute__((noreturn));
/* The first frame of a task below `top`: pc = entry, TASK_ID = id; returns the task's sp. */
uint32_t *port_stack_init(uint32_t *top, void (*entry)(void), uint32_t task_id);

/* ---- Interrupts --------------------------------------------------------------------------- */
/* Disable, returning the previous state; loops until no request latched before the store can
 * still be entered (hf_irq_disable in hfriscv.h). */
static inline uint32_t port_irq_disable(void) { return hf_irq_disable(); }
static inline void port_irq_restore(uint32_t state) { hf_irq_restore(state); }
static inline void port_irq_enable(void) { hf_irq_enable(); }

/* ---- Time and accounting ------------------------------------------------------------------ */
static inline uint32_t port_cycles(void) { return hf_cycles(); }
static inline void port_set_task_id(uint32_t id) { hf_set_task(id); }
/* Stop the core until an enabled interrupt cause rises (no host time, sleep-cycle energy). */
static inline void port_sleep(void) { hf_sleep(); }
static inline void __attribute__((noreturn)) port_exit(uint32_t code) { hf_exit(code); }

/* Start the tick: TIMER1 counts so that tick k rises in device cycle k * OS_TICK_CYCLES + 2.
 * Returns the number of the first tick to come; *aligned_at gets TIMER0 right after alignment.
 * Interrupts must be disabled; the tick interrupt is unmasked in TIMERMASK but IRQ_MASK is the
 * caller's (port_irq_unmask). */
uint32_t port_tick_start(uint32_t *aligned_at);
/* Acknowledge the tick: make the timer line low whatever number of toggles happened. */
static inline void port_tick_ack(void)
{
    HF_REG32(HF_TIMERCAUSE_INV) = HF_REG32(HF_TIMERCAUSE) & HF_TIMERCAUSE_T1_CTC;
}
static inline void port_irq_unmask(void) { hf_irq_mask(PORT_CAUSE_TICK | PORT_CAUSE_NI); }

/* ---- Network interface -------------------------------------------------------------------- */
static inline uint32_t port_tile(void) { return hf_tile(); }
static inline uint32_t port_io_tile(void) { return hf_io_tile(); }
static inline uint32_t port_mesh_width(void) { return HF_REG32(HF_NI_MESH) & 0xffu; }
static inline uint32_t port_mesh_height(void) { return (HF_REG32(HF_NI_MESH) >> 8) & 0xffu; }
static inline int port_ni_send_busy(void) { return (HF_REG32(HF_NI_STATUS) & HF_NI_SEND_BUSY) != 0; }
static inline int port_ni_packet_waiting(void) { return (HF_REG32(HF_NI_STATUS) & HF_NI_RECV_READY) != 0; }
/* Hand `n` flits at `packet` (flits 0 and 1 filled) to the NI; the send memory must be free.
 * The DMA copies them before the store completes, so `packet` may be reused at once. */
static inline void port_ni_send(const uint16_t *packet, uint32_t n)
{
    HF_REG32(HF_NI_SEND_ADDR) = (uint32_t)(uintptr_t)packet;
    HF_REG32(HF_NI_SEND_SIZE) = n;
    HF_REG32(HF_NI_CMD) = 1u;
}
/* Copy the waiting packet (all of it) to `buf` (64 flits of room); returns its flit count. */
static inline uint32_t port_ni_recv(uint16_t *buf) { return hf_ni_recv(buf); }

/* ---- Called by port_asm.S (defined by the kernel) -------------------------------------- */
/* Interrupt: `cause` is IRQ_CAUSE, `cycle` TIMER0 a few instructions after the entry. */
void os_port_interrupt(uint32_t cause, uint32_t cycle);
/* Voluntary switch from port_yield: `cycle` is TIMER0 at its entry. */
void os_port_switch(uint32_t cycle);

#endif /* PORT_H */
