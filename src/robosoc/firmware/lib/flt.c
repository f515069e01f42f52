/*
 * flt.c - square root, sine, cosine, atan2 and asin in single precision for the soft-float build
 * (no libm on the core).  The polynomials are Cephes' single-precision minimax fits
 * (S. L. Moshier); range reduction is Cody-Waite with a three-part pi/2.
 */
#include "flt.h"

#include <string.h>

#include "fix16.h"

static uint32_t bits_of(float f)
{
    uint32_t u;
    memcpy(&u, &f, sizeof u);
    return u;
}

static float float_of(uint32_t u)
{
    float f;
    memcpy(&f, &u, sizeof f);
    return f;
}

float flt_pow2(int32_t n)
{
    return float_of((uint32_t)(n + 127) << 23);
}

/*
 * Correctly rounded square root from the bit fields: x = m * 2^p with a 24-bit m; m is shifted
 * left by 24 or 23 bits (whichever makes the exponent even) and its integer root, rounded to
 * nearest by fix16_isqrt64, is the 24-bit result mantissa.  Since the shifted m is exact, rounding
 * its root is rounding the true root: the same bits as IEEE sqrtf.
 */
float flt_sqrt(float x)
{
    uint32_t u = bits_of(x);
    int32_t exponent = (int32_t)((u >> 23) & 0xffu);
    uint32_t mant = u & 0x7fffffu;
    if ((u & 0x7fffffffu) == 0) {
        return x; /* +-0 */
    }
    if (u >> 31) {
        return float_of(0x7fc00000u); /* negative: NaN */
    }
    if (exponent == 0xff) {
        return x; /* +inf, NaN */
    }
    if (exponent == 0) { /* subnormal: normalise */
        exponent = 1;
        while ((mant & 0x800000u) == 0) {
            mant <<= 1;
            exponent--;
        }
    } else {
        mant |= 0x800000u;
    }
    int32_t p = exponent - 150; /* x = mant * 2^p */
    int32_t s = (p & 1) ? 23 : 24;
    uint32_t root = fix16_isqrt64((uint64_t)mant << s);
    int32_t half = (p - s) / 2; /* p - s is even */
    if (root == 0x1000000u) { /* rounded up to 2^24 */
        root >>= 1;
        half++;
    }
    return float_of(((uint32_t)(half + 23 + 127) << 23) | (root & 0x7fffffu));
}

#define FLT_PI 3.14159265358979f
#define FLT_HALF_PI 1.57079632679490f
#define FLT_QUARTER_PI 0.785398163397448f
#define FLT_TWO_OVER_PI 0.636619772367581f
/* pi/2 = PIO2_1 + PIO2_2 + PIO2_3 with 8 and 11 significant bits in the first two, so that k * PIO2_1
 * and k * PIO2_2 are exact for |k| < 2^13 (|x| <= 8192) */
#define PIO2_1 1.5703125f
#define PIO2_2 4.837512969970703125e-4f
#define PIO2_3 7.549790126404332e-08f

/* sin(r) and cos(r) for |r| <= pi/4 (Cephes sinf/cosf coefficients). */
static float sin_poly(float r)
{
    float z = r * r;
    return ((-1.9515295891e-4f * z + 8.3321608736e-3f) * z - 1.6666654611e-1f) * z * r + r;
}

static float cos_poly(float r)
{
    float z = r * r;
    return ((2.443315711809948e-5f * z - 1.388731625493765e-3f) * z + 4.166664568298827e-2f) * z * z - 0.5f * z + 1.0f;
}

/* sin(x + quadrant * pi/2): as fix16_sin, shifting by whole quadrants keeps cosine as exact as sine. */
static float sin_quadrant(float x, int32_t quadrant)
{
    float kf = x * FLT_TWO_OVER_PI;
    int32_t k = (int32_t)(kf >= 0.0f ? kf + 0.5f : kf - 0.5f);
    float fk = (float)k;
    float r = ((x - fk * PIO2_1) - fk * PIO2_2) - fk * PIO2_3;
    uint32_t q = (uint32_t)(k + quadrant) & 3u;
    float v = (q & 1u) ? cos_poly(r) : sin_poly(r);
    return (q & 2u) ? -v : v;
}

float flt_sin(float x)
{
    return sin_quadrant(x, 0);
}

float flt_cos(float x)
{
    return sin_quadrant(x, 1);
}

/* atan(t) for 0 <= t <= 1: above tan(pi/8) through atan(t) = pi/4 + atan((t - 1)/(t + 1)). */
static float atan_unit(float t)
{
    float base = 0.0f;
    if (t > 0.4142135623730950f) {
        base = FLT_QUARTER_PI;
        t = (t - 1.0f) / (t + 1.0f);
    }
    float z = t * t;
    return base + ((((8.05374449538e-2f * z - 1.38776856032e-1f) * z + 1.99777106478e-1f) * z - 3.33329491539e-1f) * z * t + t);
}

/* atan2 from the octant: the smaller component over the larger is in [0, 1]. */
float flt_atan2(float y, float x)
{
    float ax = x < 0.0f ? -x : x;
    float ay = y < 0.0f ? -y : y;
    if (ax == 0.0f && ay == 0.0f) {
        return 0.0f;
    }
    float angle = ay <= ax ? atan_unit(ay / ax) : FLT_HALF_PI - atan_unit(ax / ay);
    if (x < 0.0f) {
        angle = FLT_PI - angle;
    }
    return y < 0.0f ? -angle : angle;
}

/* asin(x) = atan2(x, sqrt((1 - x)(1 + x))); the product form keeps 1 - x^2 accurate near |x| = 1. */
float flt_asin(float x)
{
    if (x >= 1.0f) {
        return FLT_HALF_PI;
    }
    if (x <= -1.0f) {
        return -FLT_HALF_PI;
    }
    return flt_atan2(x, flt_sqrt((1.0f - x) * (1.0f + x)));
}
