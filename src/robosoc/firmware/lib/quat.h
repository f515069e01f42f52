/*
 * quat.h - quaternions over real_t, the conventions of control/quaternion.py.
 *
 * q = (w, x, y, z), Hamilton product, unit norm; R(q) maps body vectors into the world frame.
 * Matrices are row-major real_t arrays (linalg.h).  Outputs must not alias inputs.
 */
#ifndef QUAT_H
#define QUAT_H

#include "real.h"

void quat_mul(const real_t a[4], const real_t b[4], real_t out[4]);        /* a (x) b */
void quat_conjugate(const real_t q[4], real_t out[4]);
void quat_normalize(real_t q[4]);                                          /* q / |q|, in place */
void quat_to_matrix(const real_t q[4], real_t r[9]);                       /* R(q), 3 x 3 */
void quat_rotate(const real_t q[4], const real_t v[3], real_t out[3]);     /* R(q) v */
void quat_rotate_to_body(const real_t q[4], const real_t v[3], real_t out[3]);   /* R(q)^T v */
/* d(R(q)^T v)/dq, 3 x 4 (columns w, x, y, z) */
void quat_rotate_to_body_jacobian(const real_t q[4], const real_t v[3], real_t jac[12]);
void quat_omega_matrix(const real_t rate[3], real_t out[16]);              /* q (x) (0, w) = Omega(w) q */
void quat_xi_matrix(const real_t q[4], real_t out[12]);                    /* q (x) (0, w) = Xi(q) w */
/* One first-order step of dq/dt = 1/2 Omega(rate) q: out = (I + dt/2 Omega(rate)) q (not normalised) */
void quat_integrate(const real_t q[4], const real_t rate[3], real_t dt, real_t out[4]);
/* Z-Y-X Euler angles (roll, pitch, yaw) of a unit quaternion */
void quat_to_euler(const real_t q[4], real_t euler[3]);
/* The unit quaternion (w >= 0) of a rotation matrix, Shepperd's method (from_matrix) */
void quat_from_matrix(const real_t r[9], real_t q[4]);
/* Attitude from one accelerometer (world up in the body frame) and one magnetometer reading, by
 * TRIAD: gravity exact, the field in its plane (from_accel_mag).  Neither may be zero or parallel. */
void quat_from_accel_mag(const real_t accel[3], const real_t mag[3], real_t q[4]);

#endif /* QUAT_H */
