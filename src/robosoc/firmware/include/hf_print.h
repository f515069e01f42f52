/*
 * hf_print.h - tiny text output for bare-metal programs.
 *
 * On RISC-V every character goes to the debug port (0xf00000d0); compiled
 * for the host (anything that is not __riscv) it goes to stdout through
 * putchar, so one program gives byte-comparable output on both.  Numbers
 * are formatted by this library, never by the host's libc.
 */
#ifndef HF_PRINT_H
#define HF_PRINT_H

#include <stdint.h>

void hf_putchar(char c);
void hf_puts(const char *s);                 /* no newline added */
void hf_putdec(int32_t v);
void hf_putudec(uint32_t v);
void hf_putdec64(int64_t v);
void hf_putudec64(uint64_t v);
void hf_puthex(uint32_t v);                  /* 8 digits, lower case, no prefix */
void hf_puthex64(uint64_t v);                /* 16 digits */

/*
 * Minimal printf: %d %i %u %x %X %s %c %p %% with the l and ll length
 * modifiers (%ld %lu %lx %lld %llu %llx), a field width and the 0 flag
 * (e.g. %08x).  Returns the number of characters written.
 */
int hf_printf(const char *fmt, ...) __attribute__((format(printf, 1, 2)));

#endif /* HF_PRINT_H */
