/*
 * pid.c - see pid.h.  Each function follows its namesake in control/pid.py (and pid_step the PID
 * part of control/host.py's step) line by line.
 *
 * Fixed-point units (docs/firmware-libraries.md): errors, rates and outputs in natural units
 * (angles to 0.8 rad, torques to 1.5 N m, thrust to 43 N: far inside Q16.16); the integral as
 * I * 2^PID_INTEGRAL_SHIFT, because one step's increment error * dt is only 1e-4 (6.5 LSB) at a
 * 1 cm or 0.01 rad error and would lose up to 8 % of itself to rounding in plain Q16.16.
 */
#include "pid.h"

#include "quat.h"
#include "robosoc_control.h"

#define INTEGRAL_UNIT(x) ((x) * (1 << PID_INTEGRAL_SHIFT))

#define GAINS(LOOP)                                                                                  \
    {                                                                                                \
        REAL_C(CTL_##LOOP##_KP), REAL_C(CTL_##LOOP##_KI), REAL_C(CTL_##LOOP##_KD),                   \
            REAL_C(INTEGRAL_UNIT(CTL_##LOOP##_INTEGRAL_LIMIT)), REAL_C(CTL_##LOOP##_OUTPUT_LIMIT),   \
            REAL_C(CTL_##LOOP##_INTEGRAL_BAND), CTL_##LOOP##_HAS_BAND                                \
    }

static real_t clamp(real_t x, real_t lo, real_t hi)
{
    return real_lt(x, lo) ? lo : (real_lt(hi, x) ? hi : x);
}

static int in_band(const pid_gains_t *g, real_t error)
{
    return !g->has_band || !real_lt(g->integral_band, real_abs(error));
}

/* I <- clamp(I + e dt, +-limit), the product rounded once into the integral's unit */
static real_t integrate(const pid_gains_t *g, real_t integral, real_t error, real_t dt)
{
    real_t sum = real_add(integral, real_mul_scaled(error, dt, PID_INTEGRAL_SHIFT));
    return clamp(sum, real_neg(g->integral_limit), g->integral_limit);
}

/* K_i I, out of the integral's unit in the same rounding */
static real_t integral_term(const pid_gains_t *g, real_t integral)
{
    return real_mul_scaled(g->ki, integral, -PID_INTEGRAL_SHIFT);
}

real_t pid_loop_step(pid_loop_t *loop, real_t error, real_t error_rate, real_t dt)
{
    const pid_gains_t *g = &loop->gains;
    if (in_band(g, error)) {
        loop->integral = integrate(g, loop->integral, error, dt);
    }
    /* out = K_p e + K_i I + K_d de/dt */
    real_acc_t acc = real_acc_mac(real_acc_mac(real_acc_zero(), g->kp, error), g->kd, error_rate);
    real_t out = real_add(real_acc_get(acc, 0), integral_term(g, loop->integral));
    return clamp(out, real_neg(g->output_limit), g->output_limit);
}

real_t pid_height_step(pid_height_t *loop, real_t height_setpoint, real_t rate_setpoint, real_t accel_setpoint,
                       real_t height, real_t velocity, real_t roll, real_t pitch, real_t dt)
{
    const pid_gains_t *g = &loop->gains;
    real_t error = real_sub(height_setpoint, height);
    real_t wanted = real_add(rate_setpoint, real_mul(loop->position_gain, error));
    real_t command = clamp(wanted, real_neg(loop->descent_rate), loop->climb_rate);
    /* the integral learns only while the setpoint holds still and the error is within the band */
    if (rate_setpoint == REAL_ZERO && in_band(g, error)) {
        loop->integral = integrate(g, loop->integral, error, dt);
    }
    loop->speed_command = command;
    real_acc_t acc = real_acc_mac(real_acc_zero(), g->kd, real_sub(command, velocity));
    real_t out = real_add(real_acc_get(acc, 0), integral_term(g, loop->integral));
    out = clamp(out, real_neg(g->output_limit), g->output_limit);
    /* min(max_tilt_gain, 1 / max(1e-6, cos roll cos pitch)): the gain is the limit exactly when
     * c * limit <= 1, which needs no tiny floor (1e-6 is below Q16.16's resolution) */
    real_t c = real_mul(real_cos(roll), real_cos(pitch));
    real_t tilt = real_lt(REAL_ONE, real_mul(c, loop->max_tilt_gain)) ? real_div(REAL_ONE, c) : loop->max_tilt_gain;
    /* T_gravity and the profile's acceleration: m (g + z''_sp) */
    real_t feed_forward = real_mul(loop->mass, real_add(loop->gravity, accel_setpoint));
    return real_mul(tilt, real_add(out, feed_forward));
}

real_t pid_wrap_angle(real_t angle)
{
    const real_t pi = REAL_C(3.14159265358979323846);
    const real_t two_pi = REAL_C(6.28318530717958647692);
    while (!real_lt(angle, pi)) {
        angle = real_sub(angle, two_pi);
    }
    while (real_lt(angle, real_neg(pi))) {
        angle = real_add(angle, two_pi);
    }
    return angle;
}

/* roll' = p + (q sin a + r cos a) tan b;  pitch' = q cos a - r sin a;  yaw' = (q sin a + r cos a) / cos b */
void pid_euler_rates(real_t roll, real_t pitch, const real_t body_rate[3], real_t out[3])
{
    real_t sa = real_sin(roll);
    real_t ca = real_cos(roll);
    real_t cb = real_cos(pitch);
    real_t tb = real_div(real_sin(pitch), cb);
    real_t p = body_rate[0], q = body_rate[1], r = body_rate[2];
    real_t s = real_acc_get(real_acc_mac(real_acc_mac(real_acc_zero(), q, sa), r, ca), 0);
    out[0] = real_add(p, real_mul(s, tb));
    out[1] = real_acc_get(real_acc_mac(real_acc_mac(real_acc_zero(), q, ca), real_neg(r), sa), 0);
    out[2] = real_div(s, cb);
}

void pid_init(pid_controller_t *ctl)
{
    static const pid_gains_t roll = GAINS(ROLL);
    static const pid_gains_t pitch = GAINS(PITCH);
    static const pid_gains_t yaw = GAINS(YAW);
    static const pid_gains_t height = GAINS(HEIGHT);
    ctl->roll.gains = roll;
    ctl->pitch.gains = pitch;
    ctl->yaw.gains = yaw;
    ctl->height.gains = height;
    ctl->height.position_gain = REAL_C(CTL_POSITION_GAIN);
    ctl->height.climb_rate = REAL_C(CTL_CLIMB_RATE);
    ctl->height.descent_rate = REAL_C(CTL_DESCENT_RATE);
    ctl->height.max_tilt_gain = REAL_C(CTL_MAX_TILT_GAIN);
    ctl->height.mass = REAL_C(CTL_MASS);
    ctl->height.gravity = REAL_C(CTL_GRAVITY);
    mix_init(&ctl->mixer);
    ctl->armed = 0;
    pid_reset(ctl);
}

void pid_reset(pid_controller_t *ctl)
{
    ctl->roll.integral = REAL_ZERO;
    ctl->pitch.integral = REAL_ZERO;
    ctl->yaw.integral = REAL_ZERO;
    ctl->height.integral = REAL_ZERO;
    ctl->height.speed_command = REAL_ZERO;
    for (int i = 0; i < 4; i++) {
        ctl->u[i] = REAL_ZERO;
    }
}

void pid_step(pid_controller_t *ctl, const real_t q[4], const real_t rate[3], real_t height, real_t velocity,
              const pid_setpoint_t *sp, int armed, real_t dt, uint16_t pwm[4])
{
    if (!armed) {
        ctl->armed = 0;
        for (int i = 0; i < 4; i++) {
            pwm[i] = 0;
        }
        return;
    }
    if (!ctl->armed) {
        ctl->armed = 1;
        pid_reset(ctl);
    }
    real_t euler[3];
    quat_to_euler(q, euler);
    real_t rates[3];
    pid_euler_rates(euler[0], euler[1], rate, rates);
    /* the attitude loops' error rate is -(measured rate): no derivative kick at setpoint steps */
    real_t u_roll = pid_loop_step(&ctl->roll, real_sub(sp->roll, euler[0]), real_neg(rates[0]), dt);
    real_t u_pitch = pid_loop_step(&ctl->pitch, real_sub(sp->pitch, euler[1]), real_neg(rates[1]), dt);
    real_t u_yaw = pid_loop_step(&ctl->yaw, pid_wrap_angle(real_sub(sp->yaw, euler[2])), real_neg(rates[2]), dt);
    real_t u_z = pid_height_step(&ctl->height, sp->height, sp->height_rate, sp->height_accel, height, velocity,
                                 euler[0], euler[1], dt);
    ctl->u[0] = u_z;
    ctl->u[1] = u_roll;
    ctl->u[2] = u_pitch;
    ctl->u[3] = u_yaw;
    mix_pwm(&ctl->mixer, u_z, u_roll, u_pitch, u_yaw, pwm);
}

#ifdef CTL_FAILSAFE
/* The low-battery failsafe (docs/power.md), built only for a battery flight.  From the first packet
 * flagged ROBOSOC_FLAG_LOW_BATTERY the setpoint is level attitude and a height that moves from the
 * commanded one at CTL_LAND_RATE (feed-forward included) to CTL_FAILSAFE_HEIGHT, stays there
 * CTL_FAILSAFE_HOLD seconds, then falls at CTL_LAND_RATE down to CTL_LAND_FLOOR; once landing, as
 * soon as the estimated height is at most CTL_LANDED_HEIGHT the motors stop and the vehicle stays
 * disarmed.  A vehicle already on the ground when the flag comes is disarmed at once. */
enum { FAILSAFE_OFF, FAILSAFE_RETURN, FAILSAFE_HOLD, FAILSAFE_LAND, FAILSAFE_LANDED };
static int failsafe_phase;
static real_t failsafe_height;
static real_t failsafe_held;

static int pid_failsafe(pid_setpoint_t *sp, real_t height, real_t dt)
{
    if (failsafe_phase == FAILSAFE_LANDED) {
        return 0;
    }
    if (failsafe_phase == FAILSAFE_OFF) {
        if (height <= REAL_C(CTL_LANDED_HEIGHT)) {
            failsafe_phase = FAILSAFE_LANDED;
            return 0;
        }
        failsafe_phase = FAILSAFE_RETURN;
        failsafe_height = sp->height;
        failsafe_held = REAL_ZERO;
    }
    real_t speed = REAL_C(CTL_LAND_RATE);
    real_t step = real_mul(speed, dt);
    real_t rate = REAL_ZERO;
    if (failsafe_phase == FAILSAFE_RETURN) {
        real_t target = REAL_C(CTL_FAILSAFE_HEIGHT);
        real_t gap = real_sub(target, failsafe_height);
        if (gap > step) {
            failsafe_height = real_add(failsafe_height, step);
            rate = speed;
        } else if (gap < real_neg(step)) {
            failsafe_height = real_sub(failsafe_height, step);
            rate = real_neg(speed);
        } else {
            failsafe_height = target;
            failsafe_phase = FAILSAFE_HOLD;
        }
    } else if (failsafe_phase == FAILSAFE_HOLD) {
        failsafe_held = real_add(failsafe_held, dt);
        if (failsafe_held >= REAL_C(CTL_FAILSAFE_HOLD)) {
            failsafe_phase = FAILSAFE_LAND;
        }
    }
    if (failsafe_phase == FAILSAFE_LAND) {
        real_t floor = REAL_C(CTL_LAND_FLOOR);
        if (failsafe_height > floor) {
            failsafe_height = real_sub(failsafe_height, step);
            rate = real_neg(speed);
            if (failsafe_height < floor) {
                failsafe_height = floor;
            }
        }
    }
    sp->roll = REAL_ZERO;
    sp->pitch = REAL_ZERO;
    sp->height = failsafe_height;
    sp->height_rate = rate;
    sp->height_accel = REAL_ZERO;
    if (failsafe_phase == FAILSAFE_LAND && height <= REAL_C(CTL_LANDED_HEIGHT)) {
        failsafe_phase = FAILSAFE_LANDED;
        return 0;
    }
    return 1;
}
#endif

int pid_packet_step(pid_controller_t *ctl, const struct robosoc_estimate_packet *in, struct robosoc_pwm_packet *out)
{
    if (in->kind != ROBOSOC_ESTIMATE_KIND) {
        return -1;
    }
    real_t q[4];
    real_t rate[3];
    for (int i = 0; i < 4; i++) {
        q[i] = real_from_fix16(in->quaternion[i]);
    }
    for (int i = 0; i < 3; i++) {
        rate[i] = real_from_fix16(in->rate[i]);
    }
    pid_setpoint_t sp = {
        real_from_fix16(in->setpoint[0]),           real_from_fix16(in->setpoint[1]),
        real_from_fix16(in->setpoint[2]),           real_from_fix16(in->setpoint[3]),
        real_from_fix16(in->height_feedforward[0]), real_from_fix16(in->height_feedforward[1]),
    };
    int armed = (in->flags & ROBOSOC_FLAG_ARMED) != 0;
#ifdef CTL_FAILSAFE
    if (armed && (in->flags & ROBOSOC_FLAG_LOW_BATTERY)) {
        armed = pid_failsafe(&sp, real_from_fix16(in->height), real_from_us(in->dt_us));
    }
#endif
    out->kind = ROBOSOC_PWM_KIND;
    out->flags = armed ? ROBOSOC_FLAG_ARMED : 0;
    out->seq = in->seq;
    pid_step(ctl, q, rate, real_from_fix16(in->height), real_from_fix16(in->vertical_velocity), &sp, armed,
             real_from_us(in->dt_us), out->pwm);
    return 0;
}
