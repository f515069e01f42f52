/*
 * report.h - one line per checked operation, the same bytes on the host and on the core.
 *
 * Format: "<op> <operand a> <operand b> <result>\n" in lower-case hex of the operand width
 * (8 digits for 32-bit values and floats, 16 for 64-bit values and doubles).  The Python tests
 * recompute every line independently from the operands.  opaque() hides a value from the
 * optimiser so that the operation is really executed, not folded at compile time.
 */
#ifndef REPORT_H
#define REPORT_H

#include <stdint.h>
#include <string.h>

#include "hf_print.h"

static inline uint32_t opaque32(uint32_t x)
{
    __asm__ volatile("" : "+r"(x));
    return x;
}

static inline uint64_t opaque64(uint64_t x)
{
    uint32_t lo = opaque32((uint32_t)x);
    uint32_t hi = opaque32((uint32_t)(x >> 32));
    return ((uint64_t)hi << 32) | lo;
}

static inline uint32_t f2u(float f)
{
    uint32_t u;
    memcpy(&u, &f, sizeof u);
    return u;
}

static inline float u2f(uint32_t u)
{
    float f;
    memcpy(&f, &u, sizeof f);
    return f;
}

static inline uint64_t d2u(double d)
{
    uint64_t u;
    memcpy(&u, &d, sizeof u);
    return u;
}

static inline double u2d(uint64_t u)
{
    double d;
    memcpy(&d, &u, sizeof d);
    return d;
}

/* Result bits with every NaN as the canonical quiet NaN: IEEE 754 leaves the sign and payload of
 * a generated NaN open, and x86 (0xffc00000) and RISC-V (0x7fc00000) differ there. */
static inline uint32_t fres(float f)
{
    return f != f ? 0x7fc00000u : f2u(f);
}

static inline uint64_t dres(double d)
{
    return d != d ? 0x7ff8000000000000ull : d2u(d);
}

static inline void report32(const char *op, uint32_t a, uint32_t b, uint32_t r)
{
    hf_puts(op);
    hf_putchar(' ');
    hf_puthex(a);
    hf_putchar(' ');
    hf_puthex(b);
    hf_putchar(' ');
    hf_puthex(r);
    hf_putchar('\n');
}

static inline void report64(const char *op, uint64_t a, uint64_t b, uint64_t r)
{
    hf_puts(op);
    hf_putchar(' ');
    hf_puthex64(a);
    hf_putchar(' ');
    hf_puthex64(b);
    hf_putchar(' ');
    hf_puthex64(r);
    hf_putchar('\n');
}

#endif /* REPORT_H */
