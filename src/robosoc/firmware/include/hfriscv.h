/*
 * hfriscv.h - the HF-RISCV single-core SoC as seen by bare-metal C.
 *
 * Register addresses follow the SoC memory map (docs/platform.md); the
 * helpers are static inline so that a program pays only for what it uses.
 * Interrupts: the runtime's entry (crt/irq_entry.S) calls the weak
 * `void irq_handler(uint32_t cause)`; define your own to handle them.
 */
#ifndef HFRISCV_H
#define HFRISCV_H

#include <stdint.h>

#define HF_REG32(addr) (*(volatile uint32_t *)(uintptr_t)(addr))

/* Memory */
#define HF_SRAM_BASE 0x40000000u

/* Simulation control: a store here ends the run, the stored value is the exit code. */
#define HF_EXIT_TRAP 0xe0000000u

/* Timers */
#define HF_TIMER0 0xe1024000u       /* free-running 32-bit cycle counter (read-only) */
#define HF_TIMER1 0xe1024400u       /* 16-bit counter */
#define HF_TIMER1_PRE 0xe1024410u   /* prescaler: 0../1 1../4 2../16 3../64 4../256 5../1024 6../4096 7../16384 */
#define HF_TIMER1_CTC 0xe1024420u   /* clear-on-compare value (reset 0xffff) */
#define HF_TIMER1_OCR 0xe1024430u   /* output compare */
#define HF_TIMERCAUSE 0xe1020400u
#define HF_TIMERCAUSE_INV 0xe1020800u
#define HF_TIMERMASK 0xe1020c00u

/* TIMERCAUSE bits */
#define HF_TIMERCAUSE_T0_B16 (1u << 0)
#define HF_TIMERCAUSE_T0_B18 (1u << 1)
#define HF_TIMERCAUSE_T1_CTC (1u << 2)
#define HF_TIMERCAUSE_T1_OCR (1u << 3)
#define HF_TIMERCAUSE_T1_B15 (1u << 4)

/* UART0 */
#define HF_UART0 0xe1034000u
#define HF_UART0_DIV 0xe1034010u
#define HF_UARTCAUSE 0xe1030400u

/* SoC peripheral cause (bit 1 GPIO, bit 2 timers, bit 3 UART) */
#define HF_S0CAUSE 0xe1000400u
#define HF_S0CAUSE_GPIO (1u << 1)
#define HF_S0CAUSE_TIMER (1u << 2)
#define HF_S0CAUSE_UART (1u << 3)

/* Interrupt controller */
#define HF_IRQ_VECTOR 0xf0000000u
#define HF_IRQ_CAUSE 0xf0000010u    /* bit 0: SoC peripheral line (S0CAUSE != 0) */
#define HF_IRQ_MASK 0xf0000020u
#define HF_IRQ_STATUS 0xf0000030u   /* bit 0: global enable */
#define HF_IRQ_EPC 0xf0000040u

/* Debug output: a byte stored here is printed by the simulator. */
#define HF_DEBUG_PORT 0xf00000d0u

/* Cycle counter (TIMER0). */
static inline uint32_t hf_cycles(void) { return HF_REG32(HF_TIMER0); }

/*
 * Global interrupt enable / disable; hf_irq_disable returns the previous state.
 *
 * Clearing IRQ_STATUS does not withdraw a request the controller latched in
 * the cycle before (platform.md §3): it is still taken at a boundary up to
 * the store's end + 1, and its handler returns with IRQ_STATUS set again.
 * So the disable is followed by one single-cycle instruction (after it no
 * latched request can still be entered) and confirmed by reading the
 * register back; if an interrupt slipped in, it is done again.
 */
static inline void hf_irq_enable(void) { HF_REG32(HF_IRQ_STATUS) = 1u; }
static inline uint32_t hf_irq_disable(void)
{
    uint32_t old = HF_REG32(HF_IRQ_STATUS) & 1u;
    do {
        HF_REG32(HF_IRQ_STATUS) = 0u;
        __asm__ volatile("nop");
    } while (HF_REG32(HF_IRQ_STATUS) & 1u);
    return old;
}
static inline void hf_irq_restore(uint32_t state) { HF_REG32(HF_IRQ_STATUS) = state & 1u; }
static inline void hf_irq_mask(uint32_t mask) { HF_REG32(HF_IRQ_MASK) = mask; }

/*
 * Inside irq_handler: 1 when the handler was entered by a SYSTEM
 * instruction (ECALL, EBREAK, CSR*, ...) rather than an interrupt.
 * A trap sets IRQ_EPC to the trap address + 8, so the word at EPC - 8
 * is the SYSTEM instruction (opcode 0x73); an interrupt leaves EPC at the
 * squashed instruction + 4.  Both cases return to EPC - 4 (for a trap,
 * the instruction after the SYSTEM one).  The check also requires no
 * enabled interrupt cause to be pending, which rules out an interrupt
 * that happens to be taken 8 bytes after a SYSTEM instruction.
 */
static inline int hf_irq_is_system_trap(uint32_t cause)
{
    uint32_t epc = HF_REG32(HF_IRQ_EPC);
    uint32_t word = *(volatile uint32_t *)(uintptr_t)(epc - 8u);
    return (cause & HF_REG32(HF_IRQ_MASK)) == 0u && (word & 0x7fu) == 0x73u;
}

/* Debug port output. */
static inline void hf_debug_putchar(char c) { HF_REG32(HF_DEBUG_PORT) = (uint32_t)(uint8_t)c; }

/* End the simulation with an exit code. */
static inline __attribute__((noreturn)) void hf_exit(uint32_t code)
{
    HF_REG32(HF_EXIT_TRAP) = code;
    for (;;) {
    }
}

/* The interrupt handler the runtime calls; weak default does nothing. */
void irq_handler(uint32_t cause);

#endif /* HFRISCV_H */
