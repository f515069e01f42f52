/*
 * ekf.h - the quaternion attitude EKF of the seed's Algorithm 1, a port of control/ekf.py.
 *
 * State x = (q_w, q_x, q_y, q_z, b_p, b_q, b_r): the body->world quaternion and the gyroscope
 * biases [rad/s].  One ekf_step is one pass of Algorithm 1: predict with the gyroscope, update
 * with the accelerometer and magnetometer directions, normalise q.  Same state, equations, noise
 * parameters and measurement model as the float64 golden model; one source for the float and the
 * Q16.16 builds (real.h).
 *
 * Units (the fixed-point design, docs/firmware-libraries.md; exact powers of two, so the float
 * build computes the golden model's mathematics unchanged):
 *   - the covariance is stored as P * 2^EKF_P_SHIFT;
 *   - the accelerometer rows of z, h and H are in units of 2^-EKF_ACCEL_SHIFT;
 *   - the gain is formed as K^T * 2^EKF_K_SHIFT.
 */
#ifndef EKF_H
#define EKF_H

#include "real.h"

#define EKF_STATES 7
#define EKF_MEASUREMENTS 6

/* Units: see above and docs/firmware-libraries.md */
#define EKF_P_SHIFT 20
#define EKF_ACCEL_SHIFT 6
#define EKF_K_SHIFT 10

/* Tuning: the defaults of control/ekf.py's EkfParams (tests/firmware checks they agree) */
#define EKF_GYRO_NOISE_X 0.05        /* white noise sigma of one gyroscope sample [rad/s] */
#define EKF_GYRO_NOISE_Y 0.05
#define EKF_GYRO_NOISE_Z 0.015
#define EKF_BIAS_WALK 1e-4           /* gyroscope bias random walk [rad/s/sqrt(s)] */
#define EKF_ACCEL_NOISE 1.0          /* sigma of the normalised accelerometer direction */
#define EKF_MAG_NOISE 0.013          /* sigma of the normalised magnetometer */
#define EKF_QUAT_FLOOR 1e-10         /* added to the quaternion block of the process noise */
#define EKF_INITIAL_QUAT_SIGMA 0.05  /* sigma of each quaternion component at initialisation */
#define EKF_INITIAL_BIAS_SIGMA 0.1   /* sigma of each gyroscope bias at initialisation [rad/s] */
#define EKF_MAG_REFERENCE_X 0.5      /* earth field in the world frame (normalised at reset) */
#define EKF_MAG_REFERENCE_Y 0.0
#define EKF_MAG_REFERENCE_Z (-0.866)

typedef struct {
    real_t x[EKF_STATES];                   /* q (w, x, y, z), gyroscope biases [rad/s] */
    real_t p[EKF_STATES * EKF_STATES];      /* covariance * 2^EKF_P_SHIFT, row-major */
    real_t mag_reference[3];                /* the field, normalised */
} ekf_t;

/* Orientation q (normalised here), biases, and the sigma of each quaternion component and each
 * bias: P = diag(quat_sigma^2 x 4, bias_sigma^2 x 3).  As AttitudeEkf.reset. */
void ekf_reset(ekf_t *ekf, const real_t q[4], const real_t bias[3], real_t quat_sigma, real_t bias_sigma);
/* The identity orientation, zero biases and the initial sigmas (AttitudeEkf()). */
void ekf_init(ekf_t *ekf);

/* The paper's R for a step of dt from orientation q, in the covariance's units. */
void ekf_process_noise(const real_t q[4], real_t dt, real_t noise[EKF_STATES * EKF_STATES]);
/* Lines 1-2: propagate with the gyroscope reading over dt [s]. */
void ekf_predict(ekf_t *ekf, const real_t gyro[3], real_t dt);
/* Lines 3-5 and the normalisation.  Returns 0, or -1 (state unchanged) for a zero-length
 * accelerometer or magnetometer reading or a singular innovation covariance. */
int ekf_update(ekf_t *ekf, const real_t accel[3], const real_t mag[3]);
/* One pass of Algorithm 1 (predict then update); returns ekf_update's result. */
int ekf_step(ekf_t *ekf, const real_t gyro[3], const real_t accel[3], const real_t mag[3], real_t dt);

#endif /* EKF_H */
