/*
 * crt0.S - start-up code for a bare-metal program on one HF-RISCV core.
 *
 * _start is linked as the first word of SRAM (section .text.start) and is
 * the ELF entry point.  It sets up sp and gp, clears .bss, points
 * IRQ_VECTOR at the interrupt entry, calls main and stores main's return
 * value to the exit trap (0xe0000000), which ends the simulation with that
 * exit code.  Should the store not stop the machine, it spins.
 */
    .section .text.start, "ax"
    .globl _start
    .type _start, @function
_start:
    la      sp, __stack_top

    .option push
    .option norelax             /* gp itself must not be set gp-relative */
    la      gp, __global_pointer$
    .option pop

    /* Clear .bss (linker script aligns both ends to 4 bytes). */
    la      t0, __bss_start
    la      t1, __bss_end
1:  bgeu    t0, t1, 2f
    sw      zero, 0(t0)
    addi    t0, t0, 4
    j       1b
2:
    /* IRQ_VECTOR <- interrupt entry (interrupts stay disabled until the program enables them). */
    la      t0, _irq_entry
    li      t1, 0xf0000000
    sw      t0, 0(t1)

    li      a0, 0               /* argc */
    li      a1, 0               /* argv */
    call    main

    li      t1, 0xe0000000      /* exit trap: the stored value is the exit code */
    sw      a0, 0(t1)
3:  j       3b
    .size _start, . - _start
