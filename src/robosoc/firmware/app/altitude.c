/*
 * altitude.c - see altitude.h.  Follows AltitudeFilter.step line by line; the comments name its
 * lines.  Products that land in a scaled unit are scaled in their one rounding (real.h).
 *
 * Why the units: the process noise (dt^2/2)^2 sigma_a^2 is 3e-10 and the bias walk 1e-6, far below
 * Q16.16's 1.5e-5, and the covariance itself spans 1e-6 to 1e-2; P * 2^20 resolves all of it and
 * holds variances up to 0.031 (the largest, the initial bias variance, is 0.01).  The gains run
 * from 5e-5 (bias) to 0.1: K * 2^10 keeps the smallest to 3,300 LSB.  dt^2/2 (5e-5, 3 LSB) is
 * never formed on its own: it is kept as dt^2/2 * 2^HALF_SHIFT.
 */
#include "altitude.h"

#include "robosoc_control.h"

#define HALF_SHIFT 12                  /* dt^2/2 * 2^12 = 0.2 at 10 ms */
#define P_UNIT(x) ((x) * (double)(1L << ALT_P_SHIFT))

void alt_reset(alt_t *alt, real_t baro_ground, real_t rest_height, int32_t samples)
{
    alt->reference = real_sub(baro_ground, rest_height);
    alt->h = rest_height;
    alt->v = REAL_ZERO;
    alt->b = REAL_ZERO;
    /* the reference is uncertain by sigma_baro / sqrt(samples) */
    alt->p00 = real_div(REAL_C(P_UNIT(ALT_BARO_NOISE * ALT_BARO_NOISE)), real_from_int(samples > 1 ? samples : 1));
    alt->p11 = REAL_C(P_UNIT(ALT_INITIAL_VELOCITY_SIGMA * ALT_INITIAL_VELOCITY_SIGMA));
    alt->p22 = REAL_C(P_UNIT(ALT_INITIAL_BIAS_SIGMA * ALT_INITIAL_BIAS_SIGMA));
    alt->p01 = REAL_ZERO;
    alt->p02 = REAL_ZERO;
    alt->p12 = REAL_ZERO;
}

/* half * x with half = dt^2/2 held as half_scaled = half * 2^HALF_SHIFT */
static real_t times_half(real_t half_scaled, real_t x)
{
    return real_mul_scaled(half_scaled, x, -HALF_SHIFT);
}

/* gain * x with the gain held as K * 2^ALT_K_SHIFT */
static real_t times_gain(real_t gain, real_t x)
{
    return real_mul_scaled(gain, x, -ALT_K_SHIFT);
}

real_t alt_step(alt_t *alt, const real_t q[4], const real_t accel[3], real_t baro_altitude, real_t dt)
{
    /* sigma_a * 2^(P_SHIFT/2): a product of two of these is in the covariance's unit */
    const real_t accel_sigma = REAL_C(ALT_ACCEL_NOISE * (1 << ALT_SIGMA_SHIFT));
    const real_t walk = REAL_C(P_UNIT(ALT_BIAS_WALK * ALT_BIAS_WALK));
    const real_t baro_var = REAL_C(ALT_BARO_NOISE * ALT_BARO_NOISE * (1 << (ALT_P_SHIFT - ALT_K_SHIFT)));
    real_t w = q[0], x = q[1], y = q[2], z = q[3];
    /* vertical = R[2] . a - g with R's third row (2 (xz - wy), 2 (yz + wx), 1 - 2 (x^2 + y^2)), as
     * quat_to_matrix forms it */
    real_t r20 = real_acc_get(real_acc_mac(real_acc_mac(real_acc_zero(), x, z), real_neg(w), y), 1);
    real_t r21 = real_acc_get(real_acc_mac(real_acc_mac(real_acc_zero(), y, z), w, x), 1);
    real_acc_t squares = real_acc_mac(real_acc_mac(real_acc_mac(real_acc_zero(), REAL_C(0.5), REAL_ONE),
                                                   real_neg(x), x),
                                      real_neg(y), y);
    real_t r22 = real_acc_get(squares, 1);
    real_acc_t acc = real_acc_mac(real_acc_zero(), r20, accel[0]);
    acc = real_acc_mac(real_acc_mac(acc, r21, accel[1]), r22, accel[2]);
    acc = real_acc_mac(acc, REAL_C(-ALT_GRAVITY), REAL_ONE);
    real_t vertical = real_acc_get(acc, 0);
    /* half = 0.5 dt dt (scaled); a = vertical - b */
    real_t half = real_mul_scaled(dt, dt, HALF_SHIFT - 1);
    real_t a = real_sub(vertical, alt->b);
    /* h += v dt + half a, as dt (v + dt a / 2): both products summed, rounded once */
    acc = real_acc_mac(real_acc_mac(real_acc_zero(), alt->v, dt), real_mul_scaled(dt, a, -1), dt);
    alt->h = real_add(alt->h, real_acc_get(acc, 0));
    alt->v = real_add(alt->v, real_mul(a, dt));
    /* A = F P, the five entries needed (rows of F: (1, dt, -half), (0, 1, -dt), (0, 0, 1)) */
    real_t a00 = real_sub(real_add(alt->p00, real_mul(dt, alt->p01)), times_half(half, alt->p02));
    real_t a01 = real_sub(real_add(alt->p01, real_mul(dt, alt->p11)), times_half(half, alt->p12));
    real_t a02 = real_sub(real_add(alt->p02, real_mul(dt, alt->p12)), times_half(half, alt->p22));
    real_t a11 = real_sub(alt->p11, real_mul(dt, alt->p12));
    real_t a12 = real_sub(alt->p12, real_mul(dt, alt->p22));
    /* G G^T sigma_a^2 with G = (half, dt, 0): g0 = half sigma_a (kept 2^8 larger), g1 = dt sigma_a */
    real_t g0 = real_mul_scaled(half, accel_sigma, 8 - HALF_SHIFT);
    real_t g1 = real_mul(dt, accel_sigma);
    /* P = A F^T + G G^T sigma_a^2 + diag(0, 0, sigma_b^2 dt) */
    alt->p00 = real_add(real_sub(real_add(a00, real_mul(dt, a01)), times_half(half, a02)),
                        real_mul_scaled(g0, g0, -16));
    alt->p01 = real_add(real_sub(a01, real_mul(dt, a02)), real_mul_scaled(g0, g1, -8));
    alt->p02 = a02;
    alt->p11 = real_add(real_sub(a11, real_mul(dt, a12)), real_mul(g1, g1));
    alt->p12 = a12;
    alt->p22 = real_add(alt->p22, real_mul(walk, dt));
    /* update with the barometer: H = (1, 0, 0), K = P H^T / s, P <- P - K H P */
    real_t innovation = real_sub(real_sub(baro_altitude, alt->reference), alt->h);
    real_t s = real_add(real_scale2(alt->p00, -ALT_K_SHIFT), baro_var); /* s * 2^(P_SHIFT - K_SHIFT) */
    real_t k0 = real_div(alt->p00, s);
    real_t k1 = real_div(alt->p01, s);
    real_t k2 = real_div(alt->p02, s);
    alt->h = real_add(alt->h, times_gain(k0, innovation));
    alt->v = real_add(alt->v, times_gain(k1, innovation));
    alt->b = real_add(alt->b, times_gain(k2, innovation));
    real_t p00 = alt->p00, p01 = alt->p01, p02 = alt->p02;
    alt->p00 = real_sub(alt->p00, times_gain(k0, p00));
    alt->p01 = real_sub(alt->p01, times_gain(k0, p01));
    alt->p02 = real_sub(alt->p02, times_gain(k0, p02));
    alt->p11 = real_sub(alt->p11, times_gain(k1, p01));
    alt->p12 = real_sub(alt->p12, times_gain(k1, p02));
    alt->p22 = real_sub(alt->p22, times_gain(k2, p02));
    return alt->h;
}
