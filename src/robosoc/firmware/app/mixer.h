/*
 * mixer.h - the motor mixing of the seed's equation 3 with desaturation, to PWM counts: a port of
 * control/mixer.py (the "+" layout: motor 0 front, 1 right, 2 rear, 3 left).
 *
 * Thrust u_z [N] and torques u_roll, u_pitch, u_yaw [N m] become four rotor forces, each kept in
 * [min_force, max_force] (collective thrust gives way first, then yaw, then roll and pitch
 * together, torque directions kept), then four PWM counts by the one rounding rule
 * floor(U 255 / V_s + 1/2) clamped to [idle_pwm, 255].  The constants come from
 * robosoc_control.h, generated from the golden model (robosoc.firmware.control_params).
 */
#ifndef MIXER_H
#define MIXER_H

#include <stdint.h>

#include "real.h"

typedef struct {
    real_t roll_pitch_gain;          /* 1 / (2 l) [N per N m] */
    real_t yaw_gain;                 /* 1 / (4 k) [N per N m] */
    real_t min_force;                /* thrust at idle_pwm [N] */
    real_t max_force;                /* thrust at full voltage [N] */
    /* the motor model, folded: I = c_f f + c_r sqrt(f); counts = (a I^2 + b I sqrt(f)) / (alpha + beta I) */
    real_t current_per_force;
    real_t current_per_root_force;
    real_t counts_per_square_current;
    real_t counts_per_current_root_force;
    real_t alpha_m;
    real_t beta_m;
    int32_t idle_pwm;
    int32_t pwm_max;
} mix_t;

/* The vehicle's mixer (Mixer(motor, arm, hover force, idle_pwm) of control/host.py). */
void mix_init(mix_t *mix);
/* Equation 3 with desaturation: four forces [N], each in [min_force, max_force] (Mixer.forces). */
void mix_forces(const mix_t *mix, real_t u_z, real_t u_roll, real_t u_pitch, real_t u_yaw, real_t forces[4]);
/* The PWM count that holds `force` [N] in steady state: floor(U 255 / V_s + 1/2) in [idle, 255]. */
int32_t mix_count(const mix_t *mix, real_t force);
/* Four PWM counts for thrust and torques (Mixer.pwm). */
void mix_pwm(const mix_t *mix, real_t u_z, real_t u_roll, real_t u_pitch, real_t u_yaw, uint16_t pwm[4]);

#endif /* MIXER_H */
