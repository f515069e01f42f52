/*
 * estimator.h - the estimator task's work: the estimator half of control/host.py's
 * HostController.step, from a sensor packet to an estimate packet.
 *
 * While disarmed (calibration): average gyroscope, accelerometer, magnetometer and barometer, a
 * sample showing motion (|norm(a) - g| > CAL_MOTION_ACCEL) restarting the averages; from the
 * averages the accelerometer bias (resting level it reads [0, 0, g]), the initial attitude by
 * TRIAD (quat_from_accel_mag), an EKF reset with the calibrated sigmas and an altitude-filter
 * reset.  Armed: EKF step with the bias-corrected accelerometer, altitude step, bias-corrected
 * body rates.  Disarming after a flight forgets everything and calibrates again (host.py reset).
 *
 * One source for the float and the Q16.16 builds (real.h).  The averages are kept as exact int64
 * sums of the packets' Q16.16 values (what the float64 golden model sums is exactly these
 * values); from EST_CAL_MAX_SAMPLES samples on (164 s at 100 Hz) they stop growing, which is the
 * one difference from the golden model (whose mean then barely moves anyway).
 */
#ifndef ESTIMATOR_H
#define ESTIMATOR_H

#include <stdint.h>

#include "altitude.h"
#include "ekf.h"
#include "real.h"
#include "robosoc_packets.h"

#define EST_CAL_MAX_SAMPLES 16384 /* keeps count and remainders within Q16.16's integer range */
#define EST_CAL_SUMS 10           /* gyro (3), accel (3), mag (3), barometer */

typedef struct {
    ekf_t ekf;
    alt_t alt;
    int64_t sums[EST_CAL_SUMS]; /* calibration: sums of the Q16.16 raw values */
    int32_t count;              /* calibration samples in the sums */
    real_t accel_bias[3];       /* [m/s^2] */
    int armed;                  /* the last sample was armed */
} est_t;

/* A new flight: no calibration, identity attitude, zero biases (HostController.reset). */
void est_init(est_t *est);
/* One calibration sample (disarmed) from the packet's raw readings; the filters restart from the
 * averages.  Returns 1 if the sample showed motion (the averages restarted). */
int est_calibrate(est_t *est, const struct robosoc_sensor_packet *in);
/*
 * One sensor packet: calibration while disarmed, otherwise the filters' step; fills the estimate
 * packet (same seq, time, dt, flags; setpoints and feed-forward forwarded; quaternion, rates,
 * height and vertical velocity in Q16.16).  Returns 0, or -1 for a packet of another kind (the
 * caller counts and drops it; nothing changes).
 */
int est_packet_step(est_t *est, const struct robosoc_sensor_packet *in, struct robosoc_estimate_packet *out);

#endif /* ESTIMATOR_H */
