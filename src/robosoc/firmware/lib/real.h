/*
 * real.h - real_t: the number type of the vector, matrix, quaternion and EKF code, so that one
 * source text builds both ways.
 *
 *   default              real_t is float (single precision; soft-float on the core)
 *   ROBOSOC_ARITH_FIXED  real_t is fix16_t (Q16.16, saturating)
 *
 * Application code uses only the operations below and REAL_C(literal) for constants; it never
 * writes + - * / on real_t.  Sums of products go through an accumulator (real_acc_t): float in the
 * float build, the exact 64-bit sum of the Q32 products in the fixed build, rounded once at the
 * end.  That single rounding is what keeps fixed-point dot products accurate, and the same step
 * scales the result by a power of two for free, which is how code keeps different matrices in
 * different units (see the EKF's covariance units in docs/firmware-libraries.md).  In the float
 * build the power-of-two scaling is exact, so both builds compute the same mathematics.
 */
#ifndef REAL_H
#define REAL_H

#include <stdint.h>

#include "fix16.h"
#include "flt.h"

#ifdef ROBOSOC_ARITH_FIXED

typedef fix16_t real_t;
typedef int64_t real_acc_t;

#define REAL_ARITH_FIXED 1
#define REAL_C(x) FIX16_C(x)
#define REAL_ZERO ((real_t)0)
#define REAL_ONE FIX16_ONE

static inline real_t real_add(real_t a, real_t b) { return fix16_add(a, b); }
static inline real_t real_sub(real_t a, real_t b) { return fix16_sub(a, b); }
static inline real_t real_mul(real_t a, real_t b) { return fix16_mul(a, b); }
static inline real_t real_div(real_t a, real_t b) { return fix16_div(a, b); }
static inline real_t real_neg(real_t a) { return fix16_neg(a); }
static inline real_t real_abs(real_t a) { return fix16_abs(a); }
static inline real_t real_sqrt(real_t a) { return fix16_sqrt(a); }
static inline real_t real_sin(real_t a) { return fix16_sin(a); }
static inline real_t real_cos(real_t a) { return fix16_cos(a); }
static inline real_t real_atan2(real_t y, real_t x) { return fix16_atan2(y, x); }
static inline real_t real_asin(real_t a) { return fix16_asin(a); }
static inline int real_lt(real_t a, real_t b) { return a < b; }

static inline real_t real_from_fix16(fix16_t a) { return a; }
static inline fix16_t real_to_fix16(real_t a) { return a; }
static inline real_t real_from_float(float f) { return fix16_from_float(f); }
static inline float real_to_float(real_t a) { return fix16_to_float(a); }
static inline real_t real_from_int(int32_t i) { return fix16_from_int(i); }
/* floor(a + 1/2): the nearest integer, halves up */
static inline int32_t real_to_int(real_t a) { return fix16_to_int(a); }

/* Seconds from microseconds: round(us * 65536 / 10^6) via 2^32 * 65536 / 10^6 = 281474976.7 (the
 * constant's rounding is 1e-9 relative). */
static inline real_t real_from_us(uint32_t us)
{
    return fix16_sat64((int64_t)(((uint64_t)us * 281474977u + 0x80000000u) >> 32));
}

/* a * 2^shift, rounded and saturating. */
static inline real_t real_scale2(real_t a, int shift)
{
    if (shift >= 0) {
        return fix16_sat64((int64_t)a << shift);
    }
    return (real_t)(((int64_t)a + ((int64_t)1 << (-shift - 1))) >> -shift);
}

static inline real_acc_t real_acc_zero(void) { return 0; }
static inline real_acc_t real_acc_mac(real_acc_t acc, real_t a, real_t b) { return acc + fix16_mul64(a, b); }

/* The accumulated sum times 2^shift (shift <= 16), rounded once and saturated. */
static inline real_t real_acc_get(real_acc_t acc, int shift)
{
    int right = 16 - shift;
    if (right == 0) {
        return fix16_sat64(acc);
    }
    return fix16_sat64((acc + ((int64_t)1 << (right - 1))) >> right);
}

/* a * b * 2^shift rounded once (e.g. dt/2 * w without first rounding dt/2). */
static inline real_t real_mul_scaled(real_t a, real_t b, int shift)
{
    return real_acc_get(fix16_mul64(a, b), shift);
}

/* sqrt of the accumulated sum (a sum of squares), from the exact Q32 value: one rounding. */
static inline real_t real_acc_sqrt(real_acc_t acc)
{
    if (acc <= 0) {
        return 0;
    }
    uint32_t root = acc < ((int64_t)1 << 62) ? fix16_isqrt64((uint64_t)acc) : 0xffffffffu;
    return root > (uint32_t)FIX16_MAX ? FIX16_MAX : (real_t)root;
}

#else /* float */

typedef float real_t;
typedef float real_acc_t;

#define REAL_ARITH_FIXED 0
#define REAL_C(x) ((float)(x))
#define REAL_ZERO 0.0f
#define REAL_ONE 1.0f

static inline real_t real_add(real_t a, real_t b) { return a + b; }
static inline real_t real_sub(real_t a, real_t b) { return a - b; }
static inline real_t real_mul(real_t a, real_t b) { return a * b; }
static inline real_t real_div(real_t a, real_t b) { return a / b; }
static inline real_t real_neg(real_t a) { return -a; }
static inline real_t real_abs(real_t a) { return a < 0.0f ? -a : a; }
static inline real_t real_sqrt(real_t a) { return flt_sqrt(a); }
static inline real_t real_sin(real_t a) { return flt_sin(a); }
static inline real_t real_cos(real_t a) { return flt_cos(a); }
static inline real_t real_atan2(real_t y, real_t x) { return flt_atan2(y, x); }
static inline real_t real_asin(real_t a) { return flt_asin(a); }
static inline int real_lt(real_t a, real_t b) { return a < b; }

static inline real_t real_from_fix16(fix16_t a) { return fix16_to_float(a); }
static inline fix16_t real_to_fix16(real_t a) { return fix16_from_float(a); }
static inline real_t real_from_float(float f) { return f; }
static inline float real_to_float(real_t a) { return a; }
static inline real_t real_from_int(int32_t i) { return (float)i; }
/* floor(a + 1/2): the nearest integer, halves up (|a| < 2^31) */
static inline int32_t real_to_int(real_t a)
{
    float y = a + 0.5f;
    int32_t t = (int32_t)y; /* truncates towards zero: one less below zero */
    return (float)t > y ? t - 1 : t;
}

static inline real_t real_from_us(uint32_t us) { return (float)us * 1e-6f; }

static inline real_t real_scale2(real_t a, int shift)
{
    return shift == 0 ? a : a * flt_pow2(shift);
}

static inline real_acc_t real_acc_zero(void) { return 0.0f; }
/* A separate multiply and add: the build forbids FMA contraction, as the core has no FMA. */
static inline real_acc_t real_acc_mac(real_acc_t acc, real_t a, real_t b) { return acc + a * b; }
static inline real_t real_acc_get(real_acc_t acc, int shift) { return real_scale2(acc, shift); }
static inline real_t real_acc_sqrt(real_acc_t acc) { return flt_sqrt(acc); }
static inline real_t real_mul_scaled(real_t a, real_t b, int shift) { return real_scale2(a * b, shift); }

#endif /* ROBOSOC_ARITH_FIXED */

#endif /* REAL_H */
