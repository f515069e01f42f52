/*
 * mixer.c - see mixer.h.  Mixer.forces and the voltage-to-count chain of control/mixer.py, step by
 * step.  Forces stay within 1.6..9.6 N and every intermediate within a few thousand, so plain
 * Q16.16 is enough here (docs/firmware-libraries.md, "The PID task").
 */
#include "mixer.h"

#include "robosoc_control.h"

void mix_init(mix_t *mix)
{
    mix->roll_pitch_gain = REAL_C(MIX_ROLL_PITCH_GAIN);
    mix->yaw_gain = REAL_C(MIX_YAW_GAIN);
    mix->min_force = REAL_C(MIX_MIN_FORCE);
    mix->max_force = REAL_C(MIX_MAX_FORCE);
    mix->current_per_force = REAL_C(MIX_CURRENT_PER_FORCE);
    mix->current_per_root_force = REAL_C(MIX_CURRENT_PER_ROOT_FORCE);
    mix->counts_per_square_current = REAL_C(MIX_COUNTS_PER_SQUARE_CURRENT);
    mix->counts_per_current_root_force = REAL_C(MIX_COUNTS_PER_CURRENT_ROOT_FORCE);
    mix->alpha_m = REAL_C(MIX_ALPHA_M);
    mix->beta_m = REAL_C(MIX_BETA_M);
    mix->idle_pwm = MIX_IDLE_PWM;
    mix->pwm_max = MIX_PWM_MAX;
}

static real_t clamp(real_t x, real_t lo, real_t hi)
{
    return real_lt(x, lo) ? lo : (real_lt(hi, x) ? hi : x);
}

static real_t max2(real_t a, real_t b) { return real_lt(a, b) ? b : a; }
static real_t min2(real_t a, real_t b) { return real_lt(b, a) ? b : a; }

void mix_forces(const mix_t *mix, real_t u_z, real_t u_roll, real_t u_pitch, real_t u_yaw, real_t forces[4])
{
    real_t room = real_sub(mix->max_force, mix->min_force);
    real_t r = real_mul(u_roll, mix->roll_pitch_gain);
    real_t p = real_mul(u_pitch, mix->roll_pitch_gain);
    real_t y = real_mul(u_yaw, mix->yaw_gain);
    real_t widest2 = real_scale2(max2(real_abs(r), real_abs(p)), 1);
    if (real_lt(room, widest2)) {
        /* 1. Roll/pitch alone overflow: scale both (direction kept), no yaw. */
        real_t scale = real_div(room, widest2);
        r = real_mul(r, scale);
        p = real_mul(p, scale);
        y = REAL_ZERO;
    } else {
        /* 2. Yaw gets the room roll/pitch leave. */
        real_t yaw_room = real_scale2(real_sub(real_sub(room, real_abs(r)), real_abs(p)), -1);
        y = clamp(y, real_neg(yaw_room), yaw_room);
    }
    real_t d[4] = {real_sub(y, p), real_sub(real_neg(r), y), real_add(p, y), real_sub(r, y)};
    /* 3. The collective share gives way. */
    real_t lowest = d[0];
    real_t highest = d[0];
    for (int i = 1; i < 4; i++) {
        lowest = min2(lowest, d[i]);
        highest = max2(highest, d[i]);
    }
    real_t base = max2(real_sub(mix->min_force, lowest), real_scale2(u_z, -2));
    base = min2(real_sub(mix->max_force, highest), base);
    for (int i = 0; i < 4; i++) {
        forces[i] = real_add(base, d[i]);
    }
}

/*
 * thrust_to_voltage and pwm_counts with the constants folded (control_params.py): with
 * w = sqrt(f / CT0s) = sqrt(f) / sqrt(CT0s), the current is I = (k_t f + k_m w) / Psi and
 * U 255 / V_s = (I^2 R_A + I Psi w) 255 / V_s / (alpha_m + I beta_m).  Working with sqrt(f)
 * instead of w keeps f / CT0s (2e5) out of Q16.16's range and the tiny k_m, CT0s out of its
 * resolution; the mathematics is the golden model's.
 */
int32_t mix_count(const mix_t *mix, real_t force)
{
    int32_t counts = 0; /* no thrust, or no current: 0 V */
    if (real_lt(REAL_ZERO, force)) {
        real_t root = real_sqrt(force);
        real_acc_t acc = real_acc_mac(real_acc_zero(), mix->current_per_force, force);
        real_t current = real_acc_get(real_acc_mac(acc, mix->current_per_root_force, root), 0);
        if (real_lt(REAL_ZERO, current)) {
            real_t a = real_mul(mix->counts_per_square_current, current);
            real_t b = real_mul(mix->counts_per_current_root_force, root);
            acc = real_acc_mac(real_acc_mac(real_acc_zero(), a, current), b, current);
            real_t numerator = real_acc_get(acc, 0);
            acc = real_acc_mac(real_acc_mac(real_acc_zero(), mix->alpha_m, REAL_ONE), mix->beta_m, current);
            counts = real_to_int(real_div(numerator, real_acc_get(acc, 0)));
        }
    }
    if (counts < mix->idle_pwm) {
        return mix->idle_pwm;
    }
    return counts > mix->pwm_max ? mix->pwm_max : counts;
}

void mix_pwm(const mix_t *mix, real_t u_z, real_t u_roll, real_t u_pitch, real_t u_yaw, uint16_t pwm[4])
{
    real_t forces[4];
    mix_forces(mix, u_z, u_roll, u_pitch, u_yaw, forces);
    for (int i = 0; i < 4; i++) {
        pwm[i] = (uint16_t)mix_count(mix, forces[i]);
    }
}
