/*
 * port_asm.S - context switch of the robosoc kernel on HF-RISCV: interrupt entry, voluntary
 * switch, and the one exit both share.  Replaces the runtime's crt/irq_entry.S in kernel images.
 *
 * One frame format (port.h): both ways in push a 32-word frame on the running task's stack and
 * store sp in os_current->sp (the first word of the task control block); both run the kernel on
 * its own stack at the top of SRAM (main's stack, dead once os_start has run) and leave through
 * port_restore, which loads os_current's frame, whatever task that now is.
 *
 *   interrupt    all registers but gp/tp/s11, pc = IRQ_EPC - 4, TASK_ID = the interrupted one
 *   port_yield   ra and s0-s10 (its C caller expects nothing else to survive the call),
 *                pc = ra, TASK_ID = 0: it resumes inside a kernel call
 *
 * TASK_ID.  The entry writes 0 (the kernel) in its sixth instruction and the exit writes the
 * frame's TASK_ID six instructions before the jump back, so the simulator charges the save,
 * the scheduler and the restore to the kernel; tp is free for that (it belongs to the return
 * sequence, which needs it only in its last three instructions).
 *
 * The exit ends with "sw tp, IRQ_STATUS-1(tp); jalr x0, 0(s11)" and nothing between them, as
 * crt/irq_entry.S explains: the re-enabling store starting in s allows a new entry only at a
 * boundary >= s + 5 (after a voluntary switch or the first start, the controller is idle) or
 * s + 7 (after an interrupt), and the only boundary between the two instructions is s + 3.
 * Only this symbol (_irq_entry, up to its .size) may write s11 and tp: the build checks it.
 */
    .equ    IRQ_BASE,   0xf0000000
    .equ    IRQ_CAUSE,  0x10
    .equ    IRQ_STATUS, 0x30
    .equ    IRQ_EPC,    0x40
    .equ    NI_HI,      0xe1040         /* lui: network-interface block 0xe1040000 */
    .equ    NI_TASK_ID, 0x20
    .equ    TIMER_HI,   0xe1024         /* lui: TIMER0 0xe1024000, TIMER1 at +0x400 */
    .equ    TIMER1,     0x400

    .equ    FRAME, 128                  /* 32 words: keeps sp 16-byte aligned */
    .equ    F_PC,   0
    .equ    F_RA,   4
    .equ    F_T0,   8
    .equ    F_T1,  12
    .equ    F_T2,  16
    .equ    F_S0,  20
    .equ    F_S1,  24
    .equ    F_A0,  28
    .equ    F_A1,  32
    .equ    F_A2,  36
    .equ    F_A3,  40
    .equ    F_A4,  44
    .equ    F_A5,  48
    .equ    F_A6,  52
    .equ    F_A7,  56
    .equ    F_S2,  60
    .equ    F_S3,  64
    .equ    F_S4,  68
    .equ    F_S5,  72
    .equ    F_S6,  76
    .equ    F_S7,  80
    .equ    F_S8,  84
    .equ    F_S9,  88
    .equ    F_S10, 92
    .equ    F_T3,  96
    .equ    F_T4, 100
    .equ    F_T5, 104
    .equ    F_T6, 108
    .equ    F_ID, 112

    .section .text.irq_entry, "ax"
    .globl  _irq_entry
    .type   _irq_entry, @function
    .balign 4
_irq_entry:
    nop                                 /* the first vector instruction executes twice */
    addi    sp, sp, -FRAME
    sw      t0, F_T0(sp)
    lui     tp, NI_HI
    lw      t0, NI_TASK_ID(tp)          /* the interrupted context's TASK_ID, to resume with */
    sw      zero, NI_TASK_ID(tp)        /* from here on the cycles are the kernel's */
    sw      t0, F_ID(sp)
    sw      ra, F_RA(sp)
    sw      t1, F_T1(sp)
    sw      t2, F_T2(sp)
    sw      s0, F_S0(sp)
    sw      s1, F_S1(sp)
    sw      a0, F_A0(sp)
    sw      a1, F_A1(sp)
    sw      a2, F_A2(sp)
    sw      a3, F_A3(sp)
    sw      a4, F_A4(sp)
    sw      a5, F_A5(sp)
    sw      a6, F_A6(sp)
    sw      a7, F_A7(sp)
    sw      s2, F_S2(sp)
    sw      s3, F_S3(sp)
    sw      s4, F_S4(sp)
    sw      s5, F_S5(sp)
    sw      s6, F_S6(sp)
    sw      s7, F_S7(sp)
    sw      s8, F_S8(sp)
    sw      s9, F_S9(sp)
    sw      s10, F_S10(sp)
    sw      t3, F_T3(sp)
    sw      t4, F_T4(sp)
    sw      t5, F_T5(sp)
    sw      t6, F_T6(sp)
    lui     tp, TIMER_HI
    lw      a1, 0(tp)                   /* cycle (TIMER0) */
    li      t0, IRQ_BASE
    lw      a0, IRQ_CAUSE(t0)           /* cause */
    lw      t1, IRQ_EPC(t0)
    addi    t1, t1, -4                  /* the interrupted instruction */
    sw      t1, F_PC(sp)
    la      t0, os_current
    lw      t0, 0(t0)
    sw      sp, 0(t0)                   /* os_current->sp */
    la      sp, __stack_top             /* kernel stack */
    call    os_port_interrupt
    j       port_restore

/* void port_yield(void): interrupts disabled, TASK_ID 0 (a kernel call) */
    .globl  port_yield
    .type   port_yield, @function
port_yield:
    addi    sp, sp, -FRAME
    sw      ra, F_PC(sp)                /* resume where the C caller continues */
    sw      ra, F_RA(sp)
    sw      s0, F_S0(sp)
    sw      s1, F_S1(sp)
    sw      s2, F_S2(sp)
    sw      s3, F_S3(sp)
    sw      s4, F_S4(sp)
    sw      s5, F_S5(sp)
    sw      s6, F_S6(sp)
    sw      s7, F_S7(sp)
    sw      s8, F_S8(sp)
    sw      s9, F_S9(sp)
    sw      s10, F_S10(sp)
    sw      zero, F_ID(sp)              /* resumes inside the kernel call: TASK_ID 0 */
    lui     tp, TIMER_HI
    lw      a0, 0(tp)                   /* cycle (TIMER0) */
    la      t0, os_current
    lw      t0, 0(t0)
    sw      sp, 0(t0)
    la      sp, __stack_top
    call    os_port_switch
    /* fall through */

/* Resume os_current from its frame (also the first start of a task: port_start_first). */
    .globl  port_restore
    .globl  port_start_first
    .type   port_restore, @function
    .type   port_start_first, @function
port_start_first:
port_restore:
    la      t0, os_current
    lw      t0, 0(t0)
    lw      sp, 0(t0)
    lw      s11, F_PC(sp)
    lw      ra, F_RA(sp)
    lw      t1, F_T1(sp)
    lw      t2, F_T2(sp)
    lw      s0, F_S0(sp)
    lw      s1, F_S1(sp)
    lw      a0, F_A0(sp)
    lw      a1, F_A1(sp)
    lw      a2, F_A2(sp)
    lw      a3, F_A3(sp)
    lw      a4, F_A4(sp)
    lw      a5, F_A5(sp)
    lw      a6, F_A6(sp)
    lw      a7, F_A7(sp)
    lw      s2, F_S2(sp)
    lw      s3, F_S3(sp)
    lw      s4, F_S4(sp)
    lw      s5, F_S5(sp)
    lw      s6, F_S6(sp)
    lw      s7, F_S7(sp)
    lw      s8, F_S8(sp)
    lw      s9, F_S9(sp)
    lw      s10, F_S10(sp)
    lw      t3, F_T3(sp)
    lw      t4, F_T4(sp)
    lw      t5, F_T5(sp)
    lw      t6, F_T6(sp)
    lui     tp, NI_HI
    lw      t0, F_ID(sp)
    sw      t0, NI_TASK_ID(tp)          /* from here on the cycles are the task's */
    lw      t0, F_T0(sp)
    addi    sp, sp, FRAME
    li      tp, IRQ_BASE + 1
    sw      tp, IRQ_STATUS - 1(tp)      /* re-enable: IRQ_STATUS keeps the low byte, 1 */
    jalr    x0, 0(s11)                  /* nothing may stand between these two */
    .size   port_restore, . - port_restore
    .size   port_start_first, . - port_start_first
    .size   port_yield, . - port_yield
    .size   _irq_entry, . - _irq_entry

/*
 * uint32_t port_timer1_write_at(uint32_t target, uint32_t value): wait until TIMER0 >= target,
 * then write TIMER1.  The load starting in c reads cycle c - 1 >= target (the previous one read
 * c - 7 < target), the branch falls through in c + 3, the store starts in c + 4 and the value
 * holds from device cycle w = c + 4, so target + 5 <= w <= target + 10.
 */
    .section .text.port_timer, "ax"
    .globl  port_timer1_write_at
    .type   port_timer1_write_at, @function
port_timer1_write_at:
    lui     t0, TIMER_HI
1:  lw      t1, 0(t0)
    bltu    t1, a0, 1b
    sw      a1, TIMER1(t0)
    ret
    .size   port_timer1_write_at, . - port_timer1_write_at

/*
 * uint32_t port_timer1_sample(uint32_t *timer0): TIMER1 during device cycle x, and TIMER0 of
 * x + 3 in *timer0 (two loads in a row, each reading the cycle before it starts).
 */
    .globl  port_timer1_sample
    .type   port_timer1_sample, @function
port_timer1_sample:
    lui     t0, TIMER_HI
    lw      t1, TIMER1(t0)
    lw      t2, 0(t0)
    sw      t2, 0(a0)
    mv      a0, t1
    ret
    .size   port_timer1_sample, . - port_timer1_sample
