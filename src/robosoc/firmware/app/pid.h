/*
 * pid.h - the PID task's control law, a port of control/pid.py and of the PID part of
 * control/host.py's step: roll, pitch and yaw PIDs (the seed's equation 1), the height controller
 * (equation 2 with the vertical-speed limit, the setpoint profile's feed-forward and the integral
 * rules) and the mixer (equation 3, mixer.h), from an estimate to four PWM counts.
 *
 * One source for the float and the Q16.16 builds (real.h).  Gains and limits come from
 * robosoc_control.h, generated from the golden model (robosoc.firmware.control_params).
 * Integrals are stored as I * 2^PID_INTEGRAL_SHIFT (an exact power of two, so the float build
 * computes the golden model's mathematics unchanged); see docs/firmware-libraries.md.
 */
#ifndef PID_H
#define PID_H

#include <stdint.h>

#include "mixer.h"
#include "real.h"
#include "robosoc_packets.h"

typedef struct {
    real_t kp, ki, kd;
    real_t integral_limit;  /* in the integral's unit, * 2^PID_INTEGRAL_SHIFT */
    real_t output_limit;
    real_t integral_band;   /* the integral learns only while |error| <= this ... */
    int has_band;           /* ... if set; otherwise always (PidGains' infinite band) */
} pid_gains_t;

/* One PID loop (control/pid.py Pid). */
typedef struct {
    pid_gains_t gains;
    real_t integral;        /* * 2^PID_INTEGRAL_SHIFT */
} pid_loop_t;

/* The height controller (control/pid.py HeightController). */
typedef struct {
    pid_gains_t gains;
    real_t position_gain;   /* K_p / K_d [1/s] */
    real_t climb_rate;      /* commanded vertical-speed limits [m/s], both positive */
    real_t descent_rate;
    real_t max_tilt_gain;   /* upper limit of 1 / (cos roll cos pitch) */
    real_t mass;            /* [kg] */
    real_t gravity;         /* [m/s^2] */
    real_t integral;        /* * 2^PID_INTEGRAL_SHIFT */
    real_t speed_command;   /* the last commanded vertical speed [m/s] */
} pid_height_t;

/* The setpoint (control/setpoint.py Setpoint): attitude [rad] and the height profile with the
 * rate and acceleration of its feed-forward [m, m/s, m/s^2]. */
typedef struct {
    real_t roll, pitch, yaw;
    real_t height, height_rate, height_accel;
} pid_setpoint_t;

/* Everything the PID task keeps between samples. */
typedef struct {
    pid_loop_t roll, pitch, yaw;
    pid_height_t height;
    mix_t mixer;
    int armed;
    real_t u[4];            /* the last outputs u_z [N], u_roll, u_pitch, u_yaw [N m] */
} pid_controller_t;

real_t pid_loop_step(pid_loop_t *loop, real_t error, real_t error_rate, real_t dt);
real_t pid_height_step(pid_height_t *loop, real_t height_setpoint, real_t rate_setpoint, real_t accel_setpoint,
                       real_t height, real_t velocity, real_t roll, real_t pitch, real_t dt);
/* An angle in [-pi, pi) (wrap_angle). */
real_t pid_wrap_angle(real_t angle);
/* Z-Y-X Euler angle rates from body rates p, q, r (euler_rates). */
void pid_euler_rates(real_t roll, real_t pitch, const real_t body_rate[3], real_t out[3]);

/* The vehicle's loops and mixer, disarmed, integrals zero. */
void pid_init(pid_controller_t *ctl);
/* Zero the integrals (host.py does so at the first armed sample). */
void pid_reset(pid_controller_t *ctl);
/*
 * One sample, as HostController.step after its filters: from the estimate (quaternion, the
 * bias-corrected body rates [rad/s], height [m] and vertical velocity [m/s]) and the setpoint to
 * four PWM counts.  Disarmed: all 0; the first armed sample zeroes the integrals.
 */
void pid_step(pid_controller_t *ctl, const real_t q[4], const real_t rate[3], real_t height, real_t velocity,
              const pid_setpoint_t *setpoint, int armed, real_t dt, uint16_t pwm[4]);

/*
 * The PID task's work for one estimate packet: pid_step on its fields (Q16.16, dt from dt_us) and
 * the PWM packet for the I/O tile (same seq and armed flag).  Returns 0, or -1 for a packet of
 * another kind (malformed: the caller counts and drops it; nothing changes).
 */
int pid_packet_step(pid_controller_t *ctl, const struct robosoc_estimate_packet *in, struct robosoc_pwm_packet *out);

#endif /* PID_H */
