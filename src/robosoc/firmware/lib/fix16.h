/*
 * fix16.h - Q16.16 fixed point in 32-bit integers, as HellfireOS and the seed paper use it.
 *
 * A fix16_t v stands for v / 65536: resolution 2^-16 (about 1.53e-5, "1 LSB"), range
 * [-32768, 32768 - 2^-16].  Every operation saturates at FIX16_MIN / FIX16_MAX instead of
 * wrapping, because a wrapped value (a large positive number turning negative) is far worse for
 * a controller than a clipped one.  Rounding is to nearest everywhere; the error bound of each
 * function is in docs/firmware-libraries.md and tests/firmware check it against float64.
 *
 * The core has no divider and, in one variant, no multiplier: division is a shift-subtract loop
 * here (no compiler-rt 64-bit division), the square root is digit by digit (no division at all),
 * sine/cosine are polynomials in Q2.30 and atan2/asin use CORDIC (shifts and adds only).
 *
 * The hot operations (add, sub, mul) are static inline so that matrix loops do not pay a call.
 */
#ifndef FIX16_H
#define FIX16_H

#include <stdint.h>

typedef int32_t fix16_t;

#define FIX16_ONE ((fix16_t)0x00010000)
#define FIX16_MAX ((fix16_t)0x7fffffff)
#define FIX16_MIN ((fix16_t)(-0x7fffffff - 1))

/* A Q16.16 constant from a floating-point literal, rounded to nearest at compile time (the
 * expression folds to an integer: no soft-float code is emitted for it). */
#define FIX16_C(x) ((fix16_t)((x) * 65536.0 + ((x) >= 0 ? 0.5 : -0.5)))

#define FIX16_PI FIX16_C(3.14159265358979323846)
#define FIX16_HALF_PI FIX16_C(1.57079632679489661923)

/*
 * The exact 64-bit product of two 32-bit integers.  With a multiplier this is MUL + MULH (never
 * MULHSU, see below).
 * Without one, compiler-rt offers only the general 64 x 64-bit __muldi3 (about 470 cycles on
 * HF-RISCV); fix16_mul64_soft is a shift-and-add over the bits of the smaller magnitude (about
 * 190 cycles), so small and zero operands (frequent in matrices) cost little.  Defining
 * FIX16_MUL64_MULDI3 (FirmwareConfig.fixed_mul64 = "muldi3") keeps the plain C product, i.e.
 * __muldi3, as HellfireOS's fixed-point library multiplies.
 */
int64_t fix16_mul64_soft(int32_t a, int32_t b);

static inline int64_t fix16_mul64(int32_t a, int32_t b)
{
#if defined(__riscv) && !defined(__riscv_mul) && !defined(FIX16_MUL64_MULDI3)
    return fix16_mul64_soft(a, b);
#else
#if defined(__riscv)
    /* The HF-RISCV RTL computes MULHSU as MULHU (docs/platform.md, errata).  A compiler that can
     * prove one operand non-negative (a square, a value after a > 0 test) emits MULHSU for this
     * product, which the RTL gets wrong when the other operand is negative; hiding the operands'
     * values keeps it MUL + MULH. */
    __asm__("" : "+r"(a), "+r"(b));
#endif
    return (int64_t)a * b;
#endif
}

/* Saturate a wider intermediate result to the Q16.16 range. */
static inline fix16_t fix16_sat64(int64_t v)
{
    if (v > FIX16_MAX) {
        return FIX16_MAX;
    }
    if (v < FIX16_MIN) {
        return FIX16_MIN;
    }
    return (fix16_t)v;
}

/* a + b, saturating (exact otherwise). */
static inline fix16_t fix16_add(fix16_t a, fix16_t b)
{
    fix16_t r;
    if (__builtin_add_overflow(a, b, &r)) {
        return a < 0 ? FIX16_MIN : FIX16_MAX;
    }
    return r;
}

/* a - b, saturating (exact otherwise). */
static inline fix16_t fix16_sub(fix16_t a, fix16_t b)
{
    fix16_t r;
    if (__builtin_sub_overflow(a, b, &r)) {
        return a < 0 ? FIX16_MIN : FIX16_MAX;
    }
    return r;
}

/* -a, saturating (-FIX16_MIN is FIX16_MAX). */
static inline fix16_t fix16_neg(fix16_t a)
{
    return a == FIX16_MIN ? FIX16_MAX : -a;
}

/* |a|, saturating. */
static inline fix16_t fix16_abs(fix16_t a)
{
    return a < 0 ? fix16_neg(a) : a;
}

/* a * b through the exact 64-bit product, rounded to nearest (halves up), saturating:
 * error <= 0.5 LSB. */
static inline fix16_t fix16_mul(fix16_t a, fix16_t b)
{
    return fix16_sat64((fix16_mul64(a, b) + 0x8000) >> 16);
}

/* Integer -> Q16.16, saturating. */
static inline fix16_t fix16_from_int(int32_t i)
{
    return fix16_sat64((int64_t)i * FIX16_ONE);
}

/* Q16.16 -> nearest integer (halves up). */
static inline int32_t fix16_to_int(fix16_t a)
{
    return (int32_t)(((int64_t)a + 0x8000) >> 16);
}

fix16_t fix16_div(fix16_t a, fix16_t b);        /* a / b, error <= 0.5 LSB; b == 0 saturates */
fix16_t fix16_sqrt(fix16_t a);                  /* sqrt(a), error <= 0.5 LSB; a <= 0 gives 0 */
fix16_t fix16_sin(fix16_t x);                   /* any x; error <= 0.65 LSB */
fix16_t fix16_cos(fix16_t x);                   /* any x; error <= 0.65 LSB */
fix16_t fix16_atan2(fix16_t y, fix16_t x);      /* in [-pi, pi]; error <= 0.55 LSB; (0, 0) gives 0 */
fix16_t fix16_asin(fix16_t x);                  /* in [-pi/2, pi/2]; |x| > 1 clamps; error <= 1.1 LSB */
fix16_t fix16_from_float(float f);              /* error <= 0.5 LSB, saturating; NaN gives 0 */
float fix16_to_float(fix16_t a);                /* correctly rounded (exact for |a| < 256) */

/* Rounded integer square root of a 64-bit value (sqrt(n) to nearest), the digit-by-digit core
 * shared by fix16_sqrt, fix16_asin and the float square root of real.h. */
uint32_t fix16_isqrt64(uint64_t n);

#endif /* FIX16_H */
