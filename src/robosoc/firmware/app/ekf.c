/*
 * ekf.c - see ekf.h.  Each function follows its namesake in control/ekf.py line by line; the
 * comments name the golden model's lines.  Where a quantity lives in a scaled unit, the scale is
 * applied in the rounding step of the product that produces it (linalg.h), never as a separate
 * multiplication.
 */
#include "ekf.h"

#include "linalg.h"
#include "quat.h"

#define N EKF_STATES
#define M EKF_MEASUREMENTS

/* sigma * 2^(EKF_P_SHIFT / 2): its square is a variance in the covariance's units */
#define P_HALF_SHIFT (EKF_P_SHIFT / 2)

void ekf_reset(ekf_t *ekf, const real_t q[4], const real_t bias[3], real_t quat_sigma, real_t bias_sigma)
{
    const real_t reference[3] = {
        REAL_C(EKF_MAG_REFERENCE_X), REAL_C(EKF_MAG_REFERENCE_Y), REAL_C(EKF_MAG_REFERENCE_Z)};
    real_t norm = vec_norm(reference, 3);
    for (int i = 0; i < 3; i++) {
        ekf->mag_reference[i] = real_div(reference[i], norm);
    }
    for (int i = 0; i < 4; i++) {
        ekf->x[i] = q[i];
    }
    quat_normalize(ekf->x);
    for (int i = 0; i < 3; i++) {
        ekf->x[4 + i] = bias[i];
    }
    real_t sq = real_scale2(quat_sigma, P_HALF_SHIFT);
    real_t sb = real_scale2(bias_sigma, P_HALF_SHIFT);
    mat_zero(ekf->p, N, N);
    for (int i = 0; i < N; i++) {
        real_t s = i < 4 ? sq : sb;
        ekf->p[i * N + i] = real_mul(s, s);
    }
}

void ekf_init(ekf_t *ekf)
{
    const real_t q[4] = {REAL_ONE, REAL_ZERO, REAL_ZERO, REAL_ZERO};
    const real_t bias[3] = {REAL_ZERO, REAL_ZERO, REAL_ZERO};
    ekf_reset(ekf, q, bias, REAL_C(EKF_INITIAL_QUAT_SIGMA), REAL_C(EKF_INITIAL_BIAS_SIGMA));
}

/*
 * noise[:4, :4] = (dt/2)^2 Xi(q) diag(sigma_g^2) Xi(q)^T + floor I, noise[4:, 4:] = walk^2 dt I.
 * The quaternion block is G G^T with G = Xi(q) diag(dt/2 * sigma_g * 2^(P_SHIFT/2)): a_i below is
 * about 0.26, well resolved in Q16.16, where (dt/2)^2 sigma^2 itself (6e-8) would be 0.
 */
void ekf_process_noise(const real_t q[4], real_t dt, real_t noise[N * N])
{
    static const real_t sigma_scaled[3] = {
        REAL_C(EKF_GYRO_NOISE_X * (1 << P_HALF_SHIFT)),
        REAL_C(EKF_GYRO_NOISE_Y * (1 << P_HALF_SHIFT)),
        REAL_C(EKF_GYRO_NOISE_Z * (1 << P_HALF_SHIFT)),
    };
    real_t xi[12];
    quat_xi_matrix(q, xi);
    real_t g[12];
    for (int j = 0; j < 3; j++) {
        real_t a = real_mul_scaled(dt, sigma_scaled[j], -1);
        for (int i = 0; i < 4; i++) {
            g[i * 3 + j] = real_mul(xi[i * 3 + j], a);
        }
    }
    real_t block[16];
    mat_mul_bt(g, g, block, 4, 3, 4, 0);
    mat_zero(noise, N, N);
    real_t floor = REAL_C(EKF_QUAT_FLOOR * (1 << EKF_P_SHIFT));
    for (int i = 0; i < 4; i++) {
        for (int j = 0; j < 4; j++) {
            noise[i * N + j] = block[i * 4 + j];
        }
        noise[i * N + i] = real_add(noise[i * N + i], floor);
    }
    real_t walk = real_mul(REAL_C(EKF_BIAS_WALK * EKF_BIAS_WALK * (1 << EKF_P_SHIFT)), dt);
    for (int i = 4; i < N; i++) {
        noise[i * N + i] = walk;
    }
}

/*
 * F = [[transition, -dt/2 Xi(q)], [0, I]]: only its top four rows are computed (f_top, 4 x 7), and
 * F P F^T uses the identity block: the last three rows of F P are those of P, and the last three
 * columns of (F P) F^T those of F P.  Same products as the golden model's, without the ones
 * known to be 0 or 1 (392 multiply-adds instead of 686).
 */
void ekf_predict(ekf_t *ekf, const real_t gyro[3], real_t dt)
{
    real_t q[4] = {ekf->x[0], ekf->x[1], ekf->x[2], ekf->x[3]};
    /* rate = gyro - b */
    real_t rate[3];
    for (int i = 0; i < 3; i++) {
        rate[i] = real_sub(gyro[i], ekf->x[4 + i]);
    }
    /* transition = I + dt/2 Omega(rate); dt/2 times a value is one rounding (real_mul_scaled) */
    real_t omega[16];
    quat_omega_matrix(rate, omega);
    real_t transition[16];
    for (int i = 0; i < 16; i++) {
        transition[i] = real_mul_scaled(dt, omega[i], -1);
    }
    for (int i = 0; i < 4; i++) {
        transition[i * 5] = real_add(transition[i * 5], REAL_ONE);
    }
    /* jacobian[:4, :4] = transition; jacobian[:4, 4:] = -dt/2 Xi(q); jacobian[4:] = [0 I] */
    real_t xi[12];
    quat_xi_matrix(q, xi);
    real_t f_top[4 * N];
    real_t minus_dt = real_neg(dt);
    for (int i = 0; i < 4; i++) {
        for (int j = 0; j < 4; j++) {
            f_top[i * N + j] = transition[i * 4 + j];
        }
        for (int j = 0; j < 3; j++) {
            f_top[i * N + 4 + j] = real_mul_scaled(minus_dt, xi[i * 3 + j], -1);
        }
    }
    /* x[:4] = transition q (quat_integrate forms the same product, to more bits in Q16.16) */
    quat_integrate(q, rate, dt, ekf->x);
    /* fp = jacobian P: the top rows computed, the bottom rows copied */
    real_t fp[N * N];
    mat_mul(f_top, ekf->p, fp, 4, N, N, 0);
    mat_copy(ekf->p + 4 * N, fp + 4 * N, N - 4, N);
    /* P = fp jacobian^T + process_noise(q, dt): the left columns computed, the right copied */
    real_t left[N * 4];
    mat_mul_bt(fp, f_top, left, N, N, 4, 0);
    real_t noise[N * N];
    ekf_process_noise(q, dt, noise);
    for (int i = 0; i < N; i++) {
        for (int j = 0; j < N; j++) {
            real_t v = j < 4 ? left[i * 4 + j] : fp[i * N + j];
            ekf->p[i * N + j] = real_add(v, noise[i * N + j]);
        }
    }
}

/*
 * h(q) = [R^T(q) e_z, R^T(q) m_ref] and the quaternion columns of H (6 x 4); H's bias columns are
 * zero, so H is kept as these four columns.  The accelerometer rows come out in units of
 * 2^-EKF_ACCEL_SHIFT because e_z is given in them.
 */
static void measurement(const ekf_t *ekf, const real_t q[4], real_t h[M], real_t jac_q[M * 4])
{
    const real_t up_scaled[3] = {REAL_ZERO, REAL_ZERO, REAL_C(1.0 / (1 << EKF_ACCEL_SHIFT))};
    quat_rotate_to_body(q, up_scaled, h);
    quat_rotate_to_body(q, ekf->mag_reference, h + 3);
    quat_rotate_to_body_jacobian(q, up_scaled, jac_q);
    quat_rotate_to_body_jacobian(q, ekf->mag_reference, jac_q + 12);
}

/*
 * With H P as one product (hp, in the covariance's units), the gain's transpose solves
 * S K^T = H P (S symmetric), so K is never formed from an explicit inverse (the golden model's
 * inv(S) is the same mathematics).  S is formed in units of 2^(P_SHIFT - K_SHIFT): the solve then
 * yields K^T * 2^K_SHIFT directly.  Then x += K nu and P = P - K (H P), the golden model's
 * (I - K H) P by distributivity.  H's zero bias columns are left out of H P and H P H^T: H P is
 * H_q times the top four rows of P, and H P H^T is the first four columns of H P times H_q^T.
 */
int ekf_update(ekf_t *ekf, const real_t accel[3], const real_t mag[3])
{
    /* z = [a / |a|, m / |m|], the accelerometer rows in their scaled unit */
    real_t accel_norm = vec_norm(accel, 3);
    real_t mag_norm = vec_norm(mag, 3);
    if (accel_norm == REAL_ZERO || mag_norm == REAL_ZERO) {
        return -1;
    }
    real_t accel_norm_scaled = real_scale2(accel_norm, EKF_ACCEL_SHIFT);
    real_t z[M];
    for (int i = 0; i < 3; i++) {
        z[i] = real_div(accel[i], accel_norm_scaled);
        z[3 + i] = real_div(mag[i], mag_norm);
    }
    real_t h[M];
    real_t jac_q[M * 4];
    measurement(ekf, ekf->x, h, jac_q);
    real_t innovation[M];
    for (int i = 0; i < M; i++) {
        innovation[i] = real_sub(z[i], h[i]);
    }
    /* innovation_cov = H P H^T + Q */
    static const real_t noise_diag[M] = {
        REAL_C(EKF_ACCEL_NOISE * EKF_ACCEL_NOISE / (1 << (2 * EKF_ACCEL_SHIFT)) * (1 << (EKF_P_SHIFT - EKF_K_SHIFT))),
        REAL_C(EKF_ACCEL_NOISE * EKF_ACCEL_NOISE / (1 << (2 * EKF_ACCEL_SHIFT)) * (1 << (EKF_P_SHIFT - EKF_K_SHIFT))),
        REAL_C(EKF_ACCEL_NOISE * EKF_ACCEL_NOISE / (1 << (2 * EKF_ACCEL_SHIFT)) * (1 << (EKF_P_SHIFT - EKF_K_SHIFT))),
        REAL_C(EKF_MAG_NOISE * EKF_MAG_NOISE * (1 << (EKF_P_SHIFT - EKF_K_SHIFT))),
        REAL_C(EKF_MAG_NOISE * EKF_MAG_NOISE * (1 << (EKF_P_SHIFT - EKF_K_SHIFT))),
        REAL_C(EKF_MAG_NOISE * EKF_MAG_NOISE * (1 << (EKF_P_SHIFT - EKF_K_SHIFT))),
    };
    real_t hp[M * N];
    mat_mul(jac_q, ekf->p, hp, M, 4, N, 0);
    real_t hp_q[M * 4];
    for (int i = 0; i < M; i++) {
        for (int j = 0; j < 4; j++) {
            hp_q[i * 4 + j] = hp[i * N + j];
        }
    }
    real_t cov[M * M];
    mat_mul_bt(hp_q, jac_q, cov, M, 4, M, -EKF_K_SHIFT);
    for (int i = 0; i < M; i++) {
        cov[i * M + i] = real_add(cov[i * M + i], noise_diag[i]);
    }
    /* gain^T * 2^K_SHIFT = innovation_cov^-1 (H P) */
    real_t gain_t[M * N];
    mat_copy(hp, gain_t, M, N);
    if (mat_solve(cov, gain_t, M, N) != 0) {
        return -1;
    }
    /* x = x + K nu */
    real_t correction[N];
    mat_mul_at(gain_t, innovation, correction, N, M, 1, -EKF_K_SHIFT);
    for (int i = 0; i < N; i++) {
        ekf->x[i] = real_add(ekf->x[i], correction[i]);
    }
    /* P = (I - K H) P = P - K (H P) */
    real_t khp[N * N];
    mat_mul_at(gain_t, hp, khp, N, M, N, -EKF_K_SHIFT);
    mat_sub(ekf->p, khp, ekf->p, N, N);
    /* q = q / |q| */
    quat_normalize(ekf->x);
    return 0;
}

int ekf_step(ekf_t *ekf, const real_t gyro[3], const real_t accel[3], const real_t mag[3], real_t dt)
{
    ekf_predict(ekf, gyro, dt);
    return ekf_update(ekf, accel, mag);
}
