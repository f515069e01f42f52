/*
 * irq_entry.S - interrupt and trap entry for HF-RISCV.
 *
 * The hardware has no CSRs: on an interrupt it jumps to IRQ_VECTOR, stores
 * the return address + 4 in IRQ_EPC and clears IRQ_STATUS bit 0.  The
 * first instruction at the vector executes twice, so it is a NOP.  SYSTEM
 * instructions (ECALL, EBREAK, CSR*) trap to the same vector with
 * IRQ_EPC = trap address + 8; returning to IRQ_EPC - 4 resumes after the
 * SYSTEM instruction.  hf_irq_is_system_trap() in hfriscv.h tells the two
 * apart inside the handler.
 *
 * The entry saves the registers a C function may clobber (ra, t0-t6,
 * a0-a7), calls irq_handler(IRQ_CAUSE), restores them and returns through
 * s11, which every program is compiled not to use (-ffixed-x27): nothing
 * else is free to hold the return address at the final jump.
 *
 * Why the return ends with "sw tp, IRQ_STATUS-1(tp); jalr x0, 0(s11)" and
 * nothing between them.  HF-RISCV takes an interrupt at any instruction
 * boundary at or after t + 5 for a request that rose in device cycle t
 * (platform.md §3).  After an interrupt the controller idles again only in
 * cycle s + 2 for the re-enabling store starting in s, so the first entry
 * can come at the boundary s + 7; after a trap it is idle already and the
 * entry can come at s + 5.  The store ends at s + 3, the JALR at s + 6:
 * the only boundary in between is s + 3, too early for either case, so a
 * new interrupt is taken at the interrupted code and s11 is used before a
 * nested entry could overwrite it.  Any instruction between the store and
 * the JALR would open that window, so the store needs a register of its
 * own: tp (x4), which LLVM never allocates and this bare-metal runtime has
 * no thread-local storage for.  tp = IRQ_BASE + 1 serves as base (with
 * offset IRQ_STATUS - 1) and as the value (its low byte, which is what
 * IRQ_STATUS keeps, is 1).
 */
    .equ    IRQ_BASE,   0xf0000000
    .equ    IRQ_CAUSE,  0x10
    .equ    IRQ_STATUS, 0x30
    .equ    IRQ_EPC,    0x40
    .equ    FRAME,      64          /* 16 words, keeps sp 16-byte aligned */

    .section .text.irq_entry, "ax"
    .globl _irq_entry
    .type _irq_entry, @function
    .balign 4
_irq_entry:
    nop                             /* executes twice on HF-RISCV */
    addi    sp, sp, -FRAME
    sw      ra,  0(sp)
    sw      t0,  4(sp)
    sw      t1,  8(sp)
    sw      t2, 12(sp)
    sw      a0, 16(sp)
    sw      a1, 20(sp)
    sw      a2, 24(sp)
    sw      a3, 28(sp)
    sw      a4, 32(sp)
    sw      a5, 36(sp)
    sw      a6, 40(sp)
    sw      a7, 44(sp)
    sw      t3, 48(sp)
    sw      t4, 52(sp)
    sw      t5, 56(sp)
    sw      t6, 60(sp)

    li      t0, IRQ_BASE
    lw      a0, IRQ_CAUSE(t0)
    call    irq_handler

    li      t0, IRQ_BASE
    lw      s11, IRQ_EPC(t0)
    addi    s11, s11, -4            /* return address: EPC - 4 */

    lw      ra,  0(sp)
    lw      t0,  4(sp)
    lw      t1,  8(sp)
    lw      t2, 12(sp)
    lw      a0, 16(sp)
    lw      a1, 20(sp)
    lw      a2, 24(sp)
    lw      a3, 28(sp)
    lw      a4, 32(sp)
    lw      a5, 36(sp)
    lw      a6, 40(sp)
    lw      a7, 44(sp)
    lw      t3, 48(sp)
    lw      t4, 52(sp)
    lw      t5, 56(sp)
    lw      t6, 60(sp)
    addi    sp, sp, FRAME
    li      tp, IRQ_BASE + 1
    sw      tp, IRQ_STATUS - 1(tp)  /* re-enable: IRQ_STATUS keeps the low byte, 1 */
    jalr    x0, 0(s11)              /* nothing may stand between these two (see above) */
    .size _irq_entry, . - _irq_entry
