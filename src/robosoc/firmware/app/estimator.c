/*
 * estimator.c - see estimator.h.  Follows control/host.py's _calibrate and step line by line.
 */
#include "estimator.h"

#include "linalg.h"
#include "quat.h"
#include "robosoc_control.h"

void est_init(est_t *est)
{
    static const real_t identity[4] = {REAL_ONE, REAL_ZERO, REAL_ZERO, REAL_ZERO};
    static const real_t zero[3] = {REAL_ZERO, REAL_ZERO, REAL_ZERO};
    for (int i = 0; i < EST_CAL_SUMS; i++) {
        est->sums[i] = 0;
    }
    est->count = 0;
    for (int i = 0; i < 3; i++) {
        est->accel_bias[i] = REAL_ZERO;
    }
    est->armed = 0;
    ekf_reset(&est->ekf, identity, zero, REAL_C(EKF_INITIAL_QUAT_SIGMA), REAL_C(EKF_INITIAL_BIAS_SIGMA));
    alt_reset(&est->alt, REAL_ZERO, REAL_C(ALT_REST_HEIGHT), 1);
}

/* sum / count as real_t: the whole Q16.16 LSBs by integer division, the remainder (below one LSB)
 * by real division, so the fixed build rounds the quotient once and the float build keeps it. */
static real_t mean_of(int64_t sum, int32_t count)
{
    int64_t whole = sum / count;
    int64_t rest = sum - whole * count; /* |rest| < count <= EST_CAL_MAX_SAMPLES */
    real_t fraction = real_div(real_from_int((int32_t)rest), real_from_int(count));
    return real_add(real_from_fix16((fix16_t)whole), real_scale2(fraction, -16));
}

int est_calibrate(est_t *est, const struct robosoc_sensor_packet *in)
{
    real_t accel[3];
    for (int i = 0; i < 3; i++) {
        accel[i] = real_from_fix16(in->accel[i]);
    }
    real_t off = real_abs(real_sub(vec_norm(accel, 3), REAL_C(ALT_GRAVITY)));
    if (real_lt(REAL_C(CAL_MOTION_ACCEL), off)) {
        /* still settling (the vehicle is spawned above the ground): start averaging again; the
         * filters keep the last reset, as in host.py */
        for (int i = 0; i < EST_CAL_SUMS; i++) {
            est->sums[i] = 0;
        }
        est->count = 0;
        return 1;
    }
    if (est->count < EST_CAL_MAX_SAMPLES) {
        const int32_t *raw[4] = {in->gyro, in->accel, in->mag, &in->baro_altitude};
        static const int sizes[4] = {3, 3, 3, 1};
        int n = 0;
        for (int g = 0; g < 4; g++) {
            for (int i = 0; i < sizes[g]; i++) {
                est->sums[n++] += raw[g][i];
            }
        }
        est->count++;
    }
    real_t mean[EST_CAL_SUMS];
    for (int i = 0; i < EST_CAL_SUMS; i++) {
        mean[i] = mean_of(est->sums[i], est->count);
    }
    /* resting on flat ground the vehicle is level: what the accelerometer reads beyond [0, 0, g]
     * is its bias; the attitude comes from the bias-corrected mean (as host.py computes it) */
    real_t level[3];
    for (int i = 0; i < 3; i++) {
        est->accel_bias[i] = mean[3 + i];
    }
    est->accel_bias[2] = real_sub(mean[5], REAL_C(ALT_GRAVITY));
    for (int i = 0; i < 3; i++) {
        level[i] = real_sub(mean[3 + i], est->accel_bias[i]);
    }
    real_t q0[4];
    quat_from_accel_mag(level, &mean[6], q0);
    real_t bias_sigma = real_div(REAL_C(CAL_GYRO_NOISE), real_sqrt(real_from_int(est->count)));
    ekf_reset(&est->ekf, q0, &mean[0], REAL_C(CAL_QUAT_SIGMA), bias_sigma);
    alt_reset(&est->alt, mean[9], REAL_C(ALT_REST_HEIGHT), est->count);
    return 0;
}

int est_packet_step(est_t *est, const struct robosoc_sensor_packet *in, struct robosoc_estimate_packet *out)
{
    if (in->kind != ROBOSOC_SENSOR_KIND) {
        return -1;
    }
    int armed = (in->flags & ROBOSOC_FLAG_ARMED) != 0;
    real_t gyro[3];
    for (int i = 0; i < 3; i++) {
        gyro[i] = real_from_fix16(in->gyro[i]);
    }
    if (!armed) {
        if (est->armed) {
            est_init(est); /* landed and disarmed: a new flight calibrates afresh */
        }
        est_calibrate(est, in);
    } else {
        est->armed = 1;
        real_t accel[3];
        real_t mag[3];
        for (int i = 0; i < 3; i++) {
            accel[i] = real_sub(real_from_fix16(in->accel[i]), est->accel_bias[i]);
            mag[i] = real_from_fix16(in->mag[i]);
        }
        real_t dt = real_from_us(in->dt_us);
        ekf_step(&est->ekf, gyro, accel, mag, dt);
        alt_step(&est->alt, est->ekf.x, accel, real_from_fix16(in->baro_altitude), dt);
    }
    out->kind = ROBOSOC_ESTIMATE_KIND;
    out->flags = armed ? ROBOSOC_FLAG_ARMED : 0;
#ifdef CTL_FAILSAFE
    out->flags |= in->flags & ROBOSOC_FLAG_LOW_BATTERY; /* on to the PID task, which lands */
#endif
    out->seq = in->seq;
    out->time_us = in->time_us;
    out->dt_us = in->dt_us;
    for (int i = 0; i < 4; i++) {
        out->quaternion[i] = real_to_fix16(est->ekf.x[i]);
        out->setpoint[i] = in->setpoint[i];
    }
    for (int i = 0; i < 3; i++) {
        /* the body rates with the EKF's gyroscope bias removed (the PID's derivative terms) */
        out->rate[i] = real_to_fix16(real_sub(gyro[i], est->ekf.x[4 + i]));
    }
    out->height = real_to_fix16(est->alt.h);
    out->vertical_velocity = real_to_fix16(est->alt.v);
    out->height_feedforward[0] = in->height_feedforward[0];
    out->height_feedforward[1] = in->height_feedforward[1];
    return 0;
}
