/*
 * irq_default.c - the default interrupt handler: does nothing.
 *
 * It is weak, so a program's own `void irq_handler(uint32_t cause)`
 * replaces it.  Interrupts stay disabled unless the program enables them,
 * so the default only runs on a SYSTEM-instruction trap, which it skips.
 */
#include "hfriscv.h"

__attribute__((weak)) void irq_handler(uint32_t cause)
{
    (void)cause;
}
