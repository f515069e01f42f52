/*
 * fix16.c - the Q16.16 functions that are not inline: division, square root, sine, cosine,
 * atan2, asin and the float conversions.  See fix16.h for the conventions and
 * docs/firmware-libraries.md for the error bounds and cycle costs.
 */
#include "fix16.h"

#include <string.h>

/*
 * Shift and add, one bit of the smaller magnitude per step (the loop ends at its highest set
 * bit): a Q16.16 value near 1 costs 17 steps, a zero none.  Signs are applied at the end.
 */
int64_t fix16_mul64_soft(int32_t a, int32_t b)
{
    uint32_t ua = a < 0 ? 0u - (uint32_t)a : (uint32_t)a;
    uint32_t ub = b < 0 ? 0u - (uint32_t)b : (uint32_t)b;
    if (ua < ub) {
        uint32_t t = ua;
        ua = ub;
        ub = t;
    }
    uint32_t lo = 0;
    uint32_t hi = 0;
    uint32_t add_lo = ua; /* ua shifted left by the step number, as a 64-bit (add_hi:add_lo) */
    uint32_t add_hi = 0;
    while (ub != 0) {
        if (ub & 1u) {
            lo += add_lo;
            hi += add_hi + (lo < add_lo);
        }
        add_hi = (add_hi << 1) | (add_lo >> 31);
        add_lo <<= 1;
        ub >>= 1;
    }
    uint64_t p = ((uint64_t)hi << 32) | lo;
    return (a < 0) != (b < 0) ? -(int64_t)p : (int64_t)p;
}

/*
 * Division without a divider: long division of |a| * 2^16 (48 bits) by |b|, one quotient bit per
 * step.  The remainder stays below |b| <= 2^31, so shifting it left by one still fits 32 bits.
 * The loop starts at the highest set bit of |a| (leading zeros would only shift zeros), so a
 * quotient of a number near 1 costs about 33 steps.  The last remainder rounds the quotient to
 * nearest (2 * rem >= |b| rounds up, ties away from zero), which makes the result correctly
 * rounded: error <= 0.5 LSB.  compiler-rt's __divdi3 on ((int64_t)a << 16) / b gives the same
 * quotient truncated, at a higher cost (docs/firmware-libraries.md).
 */
fix16_t fix16_div(fix16_t a, fix16_t b)
{
    if (b == 0) {
        return a >= 0 ? FIX16_MAX : FIX16_MIN;
    }
    if (a == 0) {
        return 0;
    }
    int negative = (a < 0) != (b < 0);
    uint32_t ua = a < 0 ? 0u - (uint32_t)a : (uint32_t)a;
    uint32_t ub = b < 0 ? 0u - (uint32_t)b : (uint32_t)b;
    /* |a / b| >= 2^15 cannot be represented (ub << 15 fits 32 bits only for ub < 2^17; a larger
     * ub makes |a / b| < 2^14 anyway). */
    if (ub < (1u << 17) && ua >= (ub << 15)) {
        return negative ? FIX16_MIN : FIX16_MAX;
    }
    int lead = __builtin_clz(ua);
    uint32_t bits = ua << lead; /* numerator bits, most significant first */
    uint32_t rem = 0;
    uint32_t quot = 0;
    for (int k = 32 - lead; k > 0; k--) { /* the bits of |a| */
        rem = (rem << 1) | (bits >> 31);
        bits <<= 1;
        quot <<= 1;
        if (rem >= ub) {
            rem -= ub;
            quot |= 1u;
        }
    }
    for (int k = 0; k < 16; k++) { /* the 16 zero bits of the << 16 */
        rem <<= 1;
        quot <<= 1;
        if (rem >= ub) {
            rem -= ub;
            quot |= 1u;
        }
    }
    if (rem >= ub - rem) {
        quot++;
    }
    /* quot <= 2^31 here: 2^31 is FIX16_MIN when negative and saturates when positive */
    if (negative) {
        return (fix16_t)(0u - quot);
    }
    return quot > (uint32_t)FIX16_MAX ? FIX16_MAX : (fix16_t)quot;
}

/*
 * Digit-by-digit (binary restoring) square root: no division and no multiplication, one result
 * bit per step.  Afterwards n holds n - root^2, and sqrt(n) >= root + 1/2 exactly when
 * n - root^2 > root (integers), which rounds to nearest.  Valid for n < 2^62.
 */
uint32_t fix16_isqrt64(uint64_t n)
{
    if (n == 0) {
        return 0;
    }
    uint64_t root = 0;
    /* the highest power of 4 not above n */
    uint64_t bit = (uint64_t)1 << ((63 - __builtin_clzll(n)) & ~1);
    while (bit != 0) {
        if (n >= root + bit) {
            n -= root + bit;
            root = (root >> 1) + bit;
        } else {
            root >>= 1;
        }
        bit >>= 2;
    }
    if (n > root) {
        root++;
    }
    return (uint32_t)root;
}

/* sqrt(a) in Q16.16 is sqrt(a * 2^16) as an integer: error <= 0.5 LSB (correctly rounded). */
fix16_t fix16_sqrt(fix16_t a)
{
    if (a <= 0) {
        return 0;
    }
    return (fix16_t)fix16_isqrt64((uint64_t)(uint32_t)a << 16);
}

/* Q2.30 product, rounded: the internal format of the sine/cosine polynomials. */
static int32_t mul_q30(int32_t a, int32_t b)
{
    return (int32_t)((fix16_mul64(a, b) + (1 << 29)) >> 30);
}

#define Q30_HALF_PI 1686629713        /* pi/2 * 2^30 */
#define Q30_TWO_OVER_PI 683565276     /* 2/pi * 2^30 */

/*
 * sin(x) for quadrant offset `quadrant` (0: sin, 1: cos): x = k * pi/2 + r with k the nearest
 * integer and |r| <= pi/4, then sin(x + quadrant * pi/2) is +-sin(r) or +-cos(r) by (k + quadrant)
 * mod 4.  Shifting by whole quadrants is exact, so cosine costs the same as sine and is as
 * accurate.  r is formed in Q2.30 from a 30-bit pi/2 (k is at most 20861, so the constant's
 * rounding adds at most 1.3e-6 rad, 0.08 LSB); the Taylor polynomials to r^7 (sine) and r^8
 * (cosine) are below 3.2e-7 off on |r| <= pi/4 (0.02 LSB), and the Q2.30 arithmetic adds a few
 * 2^-30: with the final rounding to Q16.16, error <= 0.65 LSB.
 */
static fix16_t sin_quadrant(fix16_t x, int32_t quadrant)
{
    int64_t scaled = fix16_mul64(x, Q30_TWO_OVER_PI);                 /* x * 2/pi in Q.46 */
    int32_t k = (int32_t)((scaled + ((int64_t)1 << 45)) >> 46);     /* nearest quadrant */
    int32_t r = (int32_t)(((int64_t)x << 14) - fix16_mul64(k, Q30_HALF_PI));
    int32_t r2 = mul_q30(r, r);
    int32_t v;
    uint32_t q = (uint32_t)(k + quadrant) & 3u;
    if (q & 1u) {
        /* cos r = 1 - r^2/2 + r^4/24 - r^6/720 + r^8/40320 */
        v = mul_q30(r2, 26631);              /* 1/40320 */
        v = mul_q30(r2, v - 1491308);        /* 1/720 */
        v = mul_q30(r2, v + 44739243);       /* 1/24 */
        v = mul_q30(r2, v - 536870912);      /* 1/2 */
        v = v + 1073741824;                  /* 1 */
    } else {
        /* sin r = r - r^3/6 + r^5/120 - r^7/5040 */
        v = mul_q30(r2, -213044);            /* -1/5040 */
        v = mul_q30(r2, v + 8947849);        /* 1/120 */
        v = mul_q30(r2, v - 178956971);      /* 1/6 */
        v = r + mul_q30(r, v);
    }
    if (q & 2u) {
        v = -v;
    }
    return (fix16_t)((v + (1 << 13)) >> 14);
}

fix16_t fix16_sin(fix16_t x)
{
    return sin_quadrant(x, 0);
}

fix16_t fix16_cos(fix16_t x)
{
    return sin_quadrant(x, 1);
}

/* atan(2^-i) * 2^29 for the CORDIC steps (Q3.29, so that +-pi fits). */
static const int32_t cordic_atan_q29[] = {
    421657428, 248918915, 131521918, 66762579, 33510843, 16771758, 8387925, 4194219,
    2097141,   1048575,   524288,    262144,   131072,   65536,    32768,   16384,
    8192,      4096,      2048,      1024,     512,      256,      128,     64,
};
#define CORDIC_STEPS ((int)(sizeof cordic_atan_q29 / sizeof cordic_atan_q29[0]))
#define Q29_PI 1686629713 /* pi * 2^29 */

/*
 * atan2 by CORDIC vectoring: rotate (x, y) onto the positive x axis by the angles atan(2^-i),
 * adding up the angles turned.  Shifts and adds only, so the multiplier-less core pays no
 * multiplication.  The vector is first turned into the right half plane (by pi) and scaled so
 * that its larger component lies in [2^28, 2^29): the CORDIC gain (1.65) and sqrt(2) then keep
 * it below 2^31, and 24 steps leave an angle error near 2^-23 rad (0.01 LSB) besides the final
 * rounding: error <= 0.55 LSB.
 */
fix16_t fix16_atan2(fix16_t y, fix16_t x)
{
    if (x == 0 && y == 0) {
        return 0;
    }
    int64_t xx = x;
    int64_t yy = y;
    int32_t angle = 0;
    if (xx < 0) { /* turn by pi: atan2(y, x) = atan2(-y, -x) +- pi */
        angle = yy >= 0 ? Q29_PI : -Q29_PI;
        xx = -xx;
        yy = -yy;
    }
    uint64_t big = (uint64_t)(xx > (yy < 0 ? -yy : yy) ? xx : (yy < 0 ? -yy : yy));
    while (big >= ((uint64_t)1 << 29)) {
        big >>= 1;
        xx >>= 1;
        yy >>= 1;
    }
    while (big < ((uint64_t)1 << 28)) {
        big <<= 1;
        xx <<= 1;
        yy <<= 1;
    }
    int32_t cx = (int32_t)xx;
    int32_t cy = (int32_t)yy;
    int32_t z = 0;
    for (int i = 0; i < CORDIC_STEPS; i++) {
        int32_t dx = cy >> i;
        int32_t dy = cx >> i;
        if (cy > 0) {
            cx += dx;
            cy -= dy;
            z += cordic_atan_q29[i];
        } else {
            cx -= dx;
            cy += dy;
            z -= cordic_atan_q29[i];
        }
    }
    /* angle = offset + z, in Q3.29; the sum stays within +-pi */
    int32_t total = angle + z;
    return (fix16_t)((total + (1 << 12)) >> 13);
}

/*
 * asin(x) = atan2(x, sqrt(1 - x^2)), with 1 - x^2 formed exactly as (1 - x)(1 + x) in Q32 and its
 * root rounded once: the cosine is within 0.5 LSB, which moves the angle by at most 0.5 LSB
 * (|d atan2(x, c)/dc| = |x| / (x^2 + c^2) <= 1 with x^2 + c^2 = 1), plus atan2's own error:
 * error <= 1.1 LSB.  |x| > 1 clamps to +-pi/2, as the golden model clamps its argument.
 */
fix16_t fix16_asin(fix16_t x)
{
    if (x >= FIX16_ONE) {
        return FIX16_HALF_PI;
    }
    if (x <= -FIX16_ONE) {
        return -FIX16_HALF_PI;
    }
    uint64_t one_minus_x2 = (uint64_t)fix16_mul64(FIX16_ONE - x, FIX16_ONE + x); /* Q32 */
    fix16_t c = (fix16_t)fix16_isqrt64(one_minus_x2);
    return fix16_atan2(x, c);
}

/*
 * float -> Q16.16 from the bit fields (no soft-float call): the value is mant * 2^(exp - 150),
 * in Q16.16 mant * 2^(exp - 134).  Rounds to nearest, halves away from zero.
 */
fix16_t fix16_from_float(float f)
{
    uint32_t u;
    memcpy(&u, &f, sizeof u);
    int negative = (u >> 31) != 0;
    int32_t exponent = (int32_t)((u >> 23) & 0xffu);
    uint32_t mant = u & 0x7fffffu;
    if (exponent == 0xff) { /* infinity saturates, NaN gives 0 */
        if (mant != 0) {
            return 0;
        }
        return negative ? FIX16_MIN : FIX16_MAX;
    }
    if (exponent == 0) { /* zero and subnormals are below 2^-126: 0 */
        return 0;
    }
    mant |= 0x800000u;
    int32_t shift = exponent - 134;
    uint32_t mag;
    if (shift >= 8) { /* |f| >= 2^15 */
        if (negative && shift == 8 && mant == 0x800000u) {
            return FIX16_MIN; /* exactly -32768 */
        }
        return negative ? FIX16_MIN : FIX16_MAX;
    }
    if (shift >= 0) {
        mag = mant << shift;
    } else if (shift > -25) {
        mag = (mant + (1u << (-shift - 1))) >> -shift;
    } else {
        mag = 0;
    }
    if (mag > (uint32_t)FIX16_MAX) { /* rounding reached 2^31 */
        return negative ? FIX16_MIN : FIX16_MAX;
    }
    return negative ? -(fix16_t)mag : (fix16_t)mag;
}

/*
 * Q16.16 -> float from the bits (no soft-float call): the magnitude's highest set bit gives the
 * exponent; below 2^24 LSB (|a| < 256) the mantissa is exact, above it rounds to nearest even,
 * as an int -> float conversion would.
 */
float fix16_to_float(fix16_t a)
{
    if (a == 0) {
        return 0.0f;
    }
    uint32_t sign = a < 0 ? 0x80000000u : 0u;
    uint32_t mag = a < 0 ? 0u - (uint32_t)a : (uint32_t)a;
    int32_t top = 31 - __builtin_clz(mag); /* mag's highest set bit; the value is 2^(top - 16) x 1.f */
    uint32_t mant;
    if (top <= 23) {
        mant = mag << (23 - top);
    } else {
        int32_t shift = top - 23;
        uint32_t rest = mag & ((1u << shift) - 1u);
        uint32_t half = 1u << (shift - 1);
        mant = mag >> shift;
        if (rest > half || (rest == half && (mant & 1u))) {
            mant++;
            if (mant == 0x1000000u) { /* rounded up to the next power of two */
                mant >>= 1;
                top++;
            }
        }
    }
    uint32_t bits = sign | ((uint32_t)(top - 16 + 127) << 23) | (mant & 0x7fffffu);
    float f;
    memcpy(&f, &bits, sizeof f);
    return f;
}
