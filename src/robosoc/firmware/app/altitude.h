/*
 * altitude.h - the altitude filter, a port of control/altitude.py: a three-state linear Kalman
 * filter of height h [m], vertical velocity v [m/s] and vertical-acceleration bias b [m/s^2],
 * predicted with the accelerometer (rotated by the attitude estimate) and updated with the
 * barometer.  It runs in the estimator task after the EKF (the estimate packet carries h and v).
 *
 * One source for the float and the Q16.16 builds (real.h).  Noise constants come from
 * robosoc_control.h (robosoc.firmware.control_params).  Units (exact powers of two, so the float
 * build computes the golden model's mathematics unchanged; docs/firmware-libraries.md):
 *   - the covariance's six distinct entries are stored as P * 2^ALT_P_SHIFT;
 *   - the gains are formed as K * 2^ALT_K_SHIFT.
 */
#ifndef ALTITUDE_H
#define ALTITUDE_H

#include <stdint.h>

#include "real.h"

typedef struct {
    real_t reference;                       /* barometer altitude of height 0 [m] */
    real_t h, v, b;                         /* height [m], vertical velocity [m/s], accel bias [m/s^2] */
    real_t p00, p01, p02, p11, p12, p22;    /* covariance * 2^ALT_P_SHIFT */
} alt_t;

/* Calibrate (AltitudeFilter.reset): `baro_ground` is the mean of `samples` barometer altitudes
 * taken at rest at `rest_height` [m]. */
void alt_reset(alt_t *alt, real_t baro_ground, real_t rest_height, int32_t samples);
/* Predict with the calibrated specific force `accel` (body frame) rotated by the attitude q
 * (body -> world), update with `baro_altitude` [m]; returns the height (AltitudeFilter.step,
 * which host.py calls with R(q)). */
real_t alt_step(alt_t *alt, const real_t q[4], const real_t accel[3], real_t baro_altitude, real_t dt);

#endif /* ALTITUDE_H */
