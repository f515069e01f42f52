/*
 * flt.h - the single-precision functions the soft-float build needs and the core lacks.
 *
 * There is no libm on the core (compiler-rt provides only +, -, *, / and conversions), so what the
 * float build of real.h needs beyond those is written here, from the bit fields and integer
 * arithmetic where that is both exact and cheaper than soft-float calls.
 */
#ifndef FLT_H
#define FLT_H

#include <stdint.h>

float flt_sqrt(float x);                 /* correctly rounded; x < 0 or NaN gives NaN */
float flt_pow2(int32_t n);               /* 2^n exactly, n in [-126, 127] */
float flt_sin(float x);                  /* |x| <= 8192; error <= 1.2e-7 */
float flt_cos(float x);                  /* |x| <= 8192; error <= 1.2e-7 */
float flt_atan2(float y, float x);       /* in [-pi, pi]; error <= 3.6e-7 rad; (0, 0) gives 0 */
float flt_asin(float x);                 /* in [-pi/2, pi/2]; |x| > 1 clamps; error <= 3.6e-7 rad */

#endif /* FLT_H */
