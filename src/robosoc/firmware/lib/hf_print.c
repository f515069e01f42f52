/*
 * hf_print.c - number formatting and a minimal printf over hf_putchar.
 *
 * Division by 10 of 64-bit values goes through compiler-rt on RV32, which
 * is slow but exact; the output is the same on the host and on the core.
 */
#include "hf_print.h"

#include <stdarg.h>
#include <stddef.h>

#if defined(__riscv)
#include "hfriscv.h"

void hf_putchar(char c)
{
    hf_debug_putchar(c);
}
#else
#include <stdio.h>

void hf_putchar(char c)
{
    putchar((unsigned char)c);
}
#endif

/* Writes the digits of v in base (10 or 16), at least `width` wide padded with `pad`. */
static int hf_put_u64(uint64_t v, unsigned base, int width, char pad, int upper)
{
    const char *digits = upper ? "0123456789ABCDEF" : "0123456789abcdef";
    char buf[24];
    int n = 0;
    if (base == 16u) { /* shifts only: no 64-bit division for hex output */
        do {
            buf[n++] = digits[(uint32_t)v & 0xfu];
            v >>= 4;
        } while (v != 0u);
    } else {
        do {
            buf[n++] = digits[v % base];
            v /= base;
        } while (v != 0u);
    }
    int written = 0;
    for (int i = n; i < width; i++) {
        hf_putchar(pad);
        written++;
    }
    while (n > 0) {
        hf_putchar(buf[--n]);
        written++;
    }
    return written;
}

static int hf_put_s64(int64_t v, int width, char pad)
{
    uint64_t magnitude = v < 0 ? (uint64_t)0 - (uint64_t)v : (uint64_t)v;
    int written = 0;
    if (v < 0) {
        if (pad == '0') {
            hf_putchar('-');
            written++;
            return written + hf_put_u64(magnitude, 10u, width - 1, pad, 0);
        }
        /* space padding goes before the sign */
        uint64_t t = magnitude;
        int digits = 0;
        do {
            digits++;
            t /= 10u;
        } while (t != 0u);
        for (int i = digits + 1; i < width; i++) {
            hf_putchar(' ');
            written++;
        }
        hf_putchar('-');
        return written + 1 + hf_put_u64(magnitude, 10u, 0, ' ', 0);
    }
    return hf_put_u64(magnitude, 10u, width, pad, 0);
}

void hf_puts(const char *s)
{
    while (*s != '\0') {
        hf_putchar(*s++);
    }
}

void hf_putdec(int32_t v) { (void)hf_put_s64(v, 0, ' '); }
void hf_putudec(uint32_t v) { (void)hf_put_u64(v, 10u, 0, ' ', 0); }
void hf_putdec64(int64_t v) { (void)hf_put_s64(v, 0, ' '); }
void hf_putudec64(uint64_t v) { (void)hf_put_u64(v, 10u, 0, ' ', 0); }
void hf_puthex(uint32_t v) { (void)hf_put_u64(v, 16u, 8, '0', 0); }
void hf_puthex64(uint64_t v) { (void)hf_put_u64(v, 16u, 16, '0', 0); }

int hf_printf(const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    int written = 0;
    for (const char *p = fmt; *p != '\0'; p++) {
        if (*p != '%') {
            hf_putchar(*p);
            written++;
            continue;
        }
        p++;
        char pad = ' ';
        int width = 0;
        if (*p == '0') {
            pad = '0';
            p++;
        }
        while (*p >= '0' && *p <= '9') {
            width = width * 10 + (*p - '0');
            p++;
        }
        int longs = 0;
        while (*p == 'l') {
            longs++;
            p++;
        }
        switch (*p) {
        case 'd':
        case 'i': {
            int64_t v = longs >= 2 ? (int64_t)va_arg(ap, long long)
                        : longs == 1 ? (int64_t)va_arg(ap, long)
                                     : (int64_t)va_arg(ap, int);
            written += hf_put_s64(v, width, pad);
            break;
        }
        case 'u':
        case 'x':
        case 'X': {
            uint64_t v = longs >= 2 ? (uint64_t)va_arg(ap, unsigned long long)
                         : longs == 1 ? (uint64_t)va_arg(ap, unsigned long)
                                      : (uint64_t)va_arg(ap, unsigned int);
            unsigned base = *p == 'u' ? 10u : 16u;
            written += hf_put_u64(v, base, width, pad, *p == 'X');
            break;
        }
        case 'p': {
            uintptr_t v = (uintptr_t)va_arg(ap, void *);
            hf_puts("0x");
            written += 2 + hf_put_u64((uint64_t)v, 16u, (int)(2 * sizeof(void *)), '0', 0);
            break;
        }
        case 's': {
            const char *s = va_arg(ap, const char *);
            if (s == NULL) {
                s = "(null)";
            }
            int len = 0;
            while (s[len] != '\0') {
                len++;
            }
            for (int i = len; i < width; i++) {
                hf_putchar(' ');
                written++;
            }
            hf_puts(s);
            written += len;
            break;
        }
        case 'c':
            hf_putchar((char)va_arg(ap, int));
            written++;
            break;
        case '%':
            hf_putchar('%');
            written++;
            break;
        case '\0':
            p--; /* lone '%' at the end: stop at the terminator */
            break;
        default: /* unknown conversion: print it as written */
            hf_putchar('%');
            hf_putchar(*p);
            written += 2;
            break;
        }
    }
    va_end(ap);
    return written;
}
