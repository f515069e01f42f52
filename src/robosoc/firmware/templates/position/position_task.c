/*
 * position_task.c - the position controller: estimate in (from the estimator), the same estimate
 * out to the attitude task with roll and pitch setpoints that steer the vehicle to the position
 * setpoint.  One source for the float and the Q16.16 builds (real.h).
 *
 * Inputs, per sensor sample: the estimate (port 2, releases the job: attitude, height, the
 * sample's height setpoint and its feed-forward) and the I/O tile's position packet (port 3, read
 * here: the newest position fix and the position setpoint with its velocity and acceleration, in
 * the world frame, z up).  The law, per horizontal axis of the world frame:
 *
 *     p    = fix position + fix velocity * (sample time - fix time)   (the fix carried forward)
 *     a    = a_sp + KP (p_sp - p) + KD (v_sp - v) + KI integral(p_sp - p)
 *
 * |a| limited to POS_ACCEL_LIMIT, the integral to POS_INTEGRAL_LIMIT; then a is turned into the
 * heading frame of the estimated yaw (forward f, left l) and into the tilt that points the thrust
 * along (f, l, g): pitch = atan2(f, g), roll = atan2(-l, sqrt(f^2 + g^2)) (Z-Y-X angles, FLU body:
 * positive pitch accelerates forward, positive roll to the right).  Disarmed, or before the first
 * position packet: roll and pitch setpoints 0 and the integral cleared.
 */
#include <stdint.h>
#include <string.h>

#include "os.h"
#include "quat.h"
#include "real.h"
#include "robosoc_packets.h"
#include "robosoc_project.h"

/* Gains of a loop with natural frequency 1.5 rad/s and damping 0.85 (KP = w^2, KD = 2 z w), well
 * below the attitude loops' (a 10 degree step reaches 90 % in 0.3 s); a project define overrides. */
#ifndef POS_KP
#define POS_KP 2.25 /* [1/s^2] */
#endif
#ifndef POS_KD
#define POS_KD 2.55 /* [1/s] */
#endif
#ifndef POS_KI
#define POS_KI 0.3 /* [1/s^3] */
#endif
#ifndef POS_INTEGRAL_LIMIT
#define POS_INTEGRAL_LIMIT 1.0 /* [m s]: KI * this = 0.3 m/s^2, a tilt of 1.8 degrees */
#endif
#ifndef POS_ACCEL_LIMIT
#define POS_ACCEL_LIMIT 4.0 /* [m/s^2]: a tilt of 22 degrees */
#endif
#define POS_GRAVITY 9.81

typedef struct {
    robosoc_msg_position_t latest; /* the newest position packet */
    int have;                      /* one has arrived */
    real_t integral[2];            /* of the position error, x and y [m s] */
    uint32_t stale;                /* estimates whose sample's position packet had not come */
} position_t;

static position_t pos;

void position_task_init(void) { memset(&pos, 0, sizeof pos); }

/* Take every position packet waiting on its port, keep the newest. */
static void take_position_packets(void)
{
    robosoc_msg_position_t in;
    os_msg_t info;
    while (os_probe(ROBOSOC_MSG_POSITION_PORT) >= 0) {
        int32_t n = os_recv(ROBOSOC_MSG_POSITION_PORT, &in, sizeof in, &info);
        if (n == (int32_t)ROBOSOC_MSG_POSITION_BYTES && in.kind == ROBOSOC_POSITION_KIND) {
            pos.latest = in;
            pos.have = 1;
        }
    }
}

static real_t clamp(real_t x, real_t limit)
{
    return real_lt(x, real_neg(limit)) ? real_neg(limit) : (real_lt(limit, x) ? limit : x);
}

/* Roll and pitch setpoints [rad] for the estimate `est` and the newest position packet. */
static void position_step(const robosoc_msg_estimate_t *est, real_t *roll, real_t *pitch)
{
    const robosoc_msg_position_t *in = &pos.latest;
    real_t dt = real_from_us(est->dt_us);
    real_t age = real_from_us(in->time_us - in->fix_time_us);
    real_t a[2];
    for (int i = 0; i < 2; i++) {
        real_t v = real_from_fix16(in->velocity[i]);
        real_t p = real_add(real_from_fix16(in->position[i]), real_mul(v, age));
        real_t error = real_sub(real_from_fix16(in->setpoint[i]), p);
        real_t error_rate = real_sub(real_from_fix16(in->setpoint_velocity[i]), v);
        pos.integral[i] = clamp(real_add(pos.integral[i], real_mul(error, dt)), REAL_C(POS_INTEGRAL_LIMIT));
        real_acc_t acc = real_acc_mac(real_acc_zero(), REAL_C(POS_KP), error);
        acc = real_acc_mac(acc, REAL_C(POS_KD), error_rate);
        acc = real_acc_mac(acc, REAL_C(POS_KI), pos.integral[i]);
        a[i] = real_add(real_from_fix16(in->setpoint_accel[i]), real_acc_get(acc, 0));
    }
    real_t norm = real_acc_sqrt(real_acc_mac(real_acc_mac(real_acc_zero(), a[0], a[0]), a[1], a[1]));
    if (real_lt(REAL_C(POS_ACCEL_LIMIT), norm)) {
        real_t scale = real_div(REAL_C(POS_ACCEL_LIMIT), norm);
        a[0] = real_mul(a[0], scale);
        a[1] = real_mul(a[1], scale);
    }
    real_t q[4];
    real_t euler[3];
    for (int i = 0; i < 4; i++) {
        q[i] = real_from_fix16(est->quaternion[i]);
    }
    quat_to_euler(q, euler);
    real_t c = real_cos(euler[2]);
    real_t s = real_sin(euler[2]);
    real_t forward = real_add(real_mul(c, a[0]), real_mul(s, a[1]));
    real_t left = real_sub(real_mul(c, a[1]), real_mul(s, a[0]));
    real_t g = REAL_C(POS_GRAVITY);
    *pitch = real_atan2(forward, g);
    real_t level = real_acc_sqrt(real_acc_mac(real_acc_mac(real_acc_zero(), forward, forward), g, g));
    *roll = real_atan2(real_neg(left), level);
}

void position_on_message(const os_msg_t *msg, void *arg)
{
    robosoc_msg_estimate_t est;            /* forwarded as the command (robosoc.toml: the same packet) */
    robosoc_msg_command_t *command = &est; /* with its roll and pitch setpoints set */
    (void)arg;
    if (msg->len != ROBOSOC_MSG_ESTIMATE_BYTES) {
        return;
    }
    memcpy(&est, msg->data, sizeof est);
    if (est.kind != ROBOSOC_ESTIMATE_KIND) {
        return;
    }
    take_position_packets();
    real_t roll = REAL_ZERO;
    real_t pitch = REAL_ZERO;
    if (pos.have && pos.latest.seq != est.seq) {
        pos.stale++;
    }
    if (pos.have && (est.flags & ROBOSOC_FLAG_ARMED)) {
        position_step(&est, &roll, &pitch);
    } else {
        pos.integral[0] = REAL_ZERO;
        pos.integral[1] = REAL_ZERO;
    }
    command->setpoint[0] = real_to_fix16(roll);
    command->setpoint[1] = real_to_fix16(pitch);
    os_send(ROBOSOC_MSG_COMMAND_TILE, ROBOSOC_MSG_COMMAND_PORT, command, ROBOSOC_MSG_COMMAND_BYTES);
}
