/*
 * quat.c - see quat.h.  Each output element is one accumulated sum of products (real.h), rounded
 * once in the fixed build; the formulas are those of control/quaternion.py term by term.
 */
#include "quat.h"

#include "linalg.h"

/* Sum of n signed products s[k] * a[k] * b[k] (signs +1 / -1), times 2^shift, rounded once. */
static real_t signed_sum(const real_t *a, const real_t *b, const int8_t *sign, int n, int shift)
{
    real_acc_t acc = real_acc_zero();
    for (int k = 0; k < n; k++) {
        acc = real_acc_mac(acc, sign[k] > 0 ? a[k] : real_neg(a[k]), b[k]);
    }
    return real_acc_get(acc, shift);
}

void quat_mul(const real_t a[4], const real_t b[4], real_t out[4])
{
    static const int8_t sign[4][4] = {{1, -1, -1, -1}, {1, 1, 1, -1}, {1, -1, 1, 1}, {1, 1, -1, 1}};
    /* a-components and b-components of each term of the Hamilton product */
    const real_t ta[4][4] = {
        {a[0], a[1], a[2], a[3]}, {a[0], a[1], a[2], a[3]}, {a[0], a[1], a[2], a[3]}, {a[0], a[1], a[2], a[3]}};
    const real_t tb[4][4] = {
        {b[0], b[1], b[2], b[3]}, {b[1], b[0], b[3], b[2]}, {b[2], b[3], b[0], b[1]}, {b[3], b[2], b[1], b[0]}};
    for (int i = 0; i < 4; i++) {
        out[i] = signed_sum(ta[i], tb[i], sign[i], 4, 0);
    }
}

void quat_conjugate(const real_t q[4], real_t out[4])
{
    out[0] = q[0];
    out[1] = real_neg(q[1]);
    out[2] = real_neg(q[2]);
    out[3] = real_neg(q[3]);
}

void quat_normalize(real_t q[4])
{
    real_t norm = vec_norm(q, 4);
    for (int i = 0; i < 4; i++) {
        q[i] = real_div(q[i], norm);
    }
}

/* 2 (a b + s c d) as one rounded sum (s = +1 or -1) */
static real_t twice_sum(real_t a, real_t b, int s, real_t c, real_t d)
{
    real_acc_t acc = real_acc_mac(real_acc_zero(), a, b);
    acc = real_acc_mac(acc, s > 0 ? c : real_neg(c), d);
    return real_acc_get(acc, 1);
}

/* 1 - 2 (a^2 + b^2) as one rounded sum */
static real_t one_minus_twice_squares(real_t a, real_t b)
{
    real_acc_t acc = real_acc_mac(real_acc_zero(), REAL_C(0.5), REAL_ONE);
    acc = real_acc_mac(acc, real_neg(a), a);
    acc = real_acc_mac(acc, real_neg(b), b);
    return real_acc_get(acc, 1);
}

void quat_to_matrix(const real_t q[4], real_t r[9])
{
    real_t w = q[0], x = q[1], y = q[2], z = q[3];
    r[0] = one_minus_twice_squares(y, z);
    r[1] = twice_sum(x, y, -1, w, z);
    r[2] = twice_sum(x, z, 1, w, y);
    r[3] = twice_sum(x, y, 1, w, z);
    r[4] = one_minus_twice_squares(x, z);
    r[5] = twice_sum(y, z, -1, w, x);
    r[6] = twice_sum(x, z, -1, w, y);
    r[7] = twice_sum(y, z, 1, w, x);
    r[8] = one_minus_twice_squares(x, y);
}

void quat_rotate(const real_t q[4], const real_t v[3], real_t out[3])
{
    real_t r[9];
    quat_to_matrix(q, r);
    mat_vec(r, v, out, 3, 3, 0);
}

void quat_rotate_to_body(const real_t q[4], const real_t v[3], real_t out[3])
{
    real_t r[9];
    quat_to_matrix(q, r);
    mat_mul_at(r, v, out, 3, 3, 1, 0);
}

/*
 * The 3 x 4 Jacobian of control/quaternion.py's rotate_to_body_jacobian: each entry is
 * 2 * (sum of three products of a quaternion component and a vector component, some doubled).
 * Entries are listed as (coefficient, quaternion index, vector index) triples.
 */
void quat_rotate_to_body_jacobian(const real_t q[4], const real_t v[3], real_t jac[12])
{
    /* {c, qi, vi} x 3 per entry; c in {-2, -1, 0, 1, 2}; w=0 x=1 y=2 z=3 */
    static const int8_t terms[12][3][3] = {
        {{1, 3, 1}, {-1, 2, 2}, {0, 0, 0}},   /* z v1 - y v2 */
        {{1, 2, 1}, {1, 3, 2}, {0, 0, 0}},    /* y v1 + z v2 */
        {{-2, 2, 0}, {1, 1, 1}, {-1, 0, 2}},  /* -2 y v0 + x v1 - w v2 */
        {{-2, 3, 0}, {1, 0, 1}, {1, 1, 2}},   /* -2 z v0 + w v1 + x v2 */
        {{-1, 3, 0}, {1, 1, 2}, {0, 0, 0}},   /* -z v0 + x v2 */
        {{1, 2, 0}, {-2, 1, 1}, {1, 0, 2}},   /* y v0 - 2 x v1 + w v2 */
        {{1, 1, 0}, {1, 3, 2}, {0, 0, 0}},    /* x v0 + z v2 */
        {{-1, 0, 0}, {-2, 3, 1}, {1, 2, 2}},  /* -w v0 - 2 z v1 + y v2 */
        {{1, 2, 0}, {-1, 1, 1}, {0, 0, 0}},   /* y v0 - x v1 */
        {{1, 3, 0}, {-1, 0, 1}, {-2, 1, 2}},  /* z v0 - w v1 - 2 x v2 */
        {{1, 0, 0}, {1, 3, 1}, {-2, 2, 2}},   /* w v0 + z v1 - 2 y v2 */
        {{1, 1, 0}, {1, 2, 1}, {0, 0, 0}},    /* x v0 + y v1 */
    };
    for (int e = 0; e < 12; e++) {
        /* 2 * sum(c * q * v) = sum((c * q) * v) * 2: c * q is exact (|c| <= 2), one rounding */
        real_acc_t acc = real_acc_zero();
        for (int t = 0; t < 3; t++) {
            int c = terms[e][t][0];
            if (c == 0) {
                continue;
            }
            real_t qc = q[terms[e][t][1]];
            if (c < 0) {
                qc = real_neg(qc);
                c = -c;
            }
            if (c == 2) {
                qc = real_add(qc, qc);
            }
            acc = real_acc_mac(acc, qc, v[terms[e][t][2]]);
        }
        jac[e] = real_acc_get(acc, 1);
    }
}

void quat_omega_matrix(const real_t rate[3], real_t out[16])
{
    real_t p = rate[0], q = rate[1], r = rate[2];
    const real_t m[16] = {
        REAL_ZERO, real_neg(p), real_neg(q), real_neg(r),
        p, REAL_ZERO, r, real_neg(q),
        q, real_neg(r), REAL_ZERO, p,
        r, q, real_neg(p), REAL_ZERO,
    };
    mat_copy(m, out, 4, 4);
}

void quat_xi_matrix(const real_t q[4], real_t out[12])
{
    real_t w = q[0], x = q[1], y = q[2], z = q[3];
    const real_t m[12] = {
        real_neg(x), real_neg(y), real_neg(z),
        w, real_neg(z), y,
        z, w, real_neg(x),
        real_neg(y), x, w,
    };
    mat_copy(m, out, 4, 3);
}

/*
 * (I + dt/2 Omega(rate)) q evaluated as q + (dt/2 Omega) q: the entries of dt/2 Omega (about 1e-3
 * for a 10 ms step) are formed 2^8 larger in one rounding of dt * w, so that they keep 8 more bits
 * in Q16.16, and each output component is one accumulated sum, rounded once.  Rounding dt/2 Omega
 * to Q16.16 instead would cost up to 0.5 LSB per entry, which in the EKF is a per-step error of
 * the prediction.  In the float build the powers of two are exact.
 */
void quat_integrate(const real_t q[4], const real_t rate[3], real_t dt, real_t out[4])
{
    real_t omega[16];
    quat_omega_matrix(rate, omega);
    for (int i = 0; i < 4; i++) {
        real_acc_t acc = real_acc_mac(real_acc_zero(), q[i], REAL_C(1 << 8));
        for (int j = 0; j < 4; j++) {
            acc = real_acc_mac(acc, real_mul_scaled(dt, omega[i * 4 + j], 7), q[j]);
        }
        out[i] = real_acc_get(acc, -8);
    }
}

/* As control/quaternion.py's to_euler: atan2 for roll and yaw, asin (argument clamped) for pitch. */
void quat_to_euler(const real_t q[4], real_t euler[3])
{
    real_t w = q[0], x = q[1], y = q[2], z = q[3];
    euler[0] = real_atan2(twice_sum(w, x, 1, y, z), one_minus_twice_squares(x, y));
    euler[1] = real_asin(twice_sum(w, y, -1, z, x));
    euler[2] = real_atan2(twice_sum(w, z, 1, x, y), one_minus_twice_squares(y, z));
}

void quat_from_matrix(const real_t r[9], real_t q[4])
{
    /* Shepperd: divide by the largest of the four candidates 4w^2, 4x^2, 4y^2, 4z^2, so that s is
     * never small (the branches and formulas of control/quaternion.py from_matrix) */
    real_t trace = real_add(real_add(r[0], r[4]), r[8]);
    real_t s;
    if (real_lt(REAL_ZERO, trace)) {
        s = real_scale2(real_sqrt(real_add(REAL_ONE, trace)), 1);
        q[0] = real_scale2(s, -2);
        q[1] = real_div(real_sub(r[7], r[5]), s);
        q[2] = real_div(real_sub(r[2], r[6]), s);
        q[3] = real_div(real_sub(r[3], r[1]), s);
    } else if (real_lt(r[4], r[0]) && real_lt(r[8], r[0])) {
        s = real_scale2(real_sqrt(real_sub(real_sub(real_add(REAL_ONE, r[0]), r[4]), r[8])), 1);
        q[0] = real_div(real_sub(r[7], r[5]), s);
        q[1] = real_scale2(s, -2);
        q[2] = real_div(real_add(r[1], r[3]), s);
        q[3] = real_div(real_add(r[2], r[6]), s);
    } else if (real_lt(r[8], r[4])) {
        s = real_scale2(real_sqrt(real_sub(real_sub(real_add(REAL_ONE, r[4]), r[0]), r[8])), 1);
        q[0] = real_div(real_sub(r[2], r[6]), s);
        q[1] = real_div(real_add(r[1], r[3]), s);
        q[2] = real_scale2(s, -2);
        q[3] = real_div(real_add(r[5], r[7]), s);
    } else {
        s = real_scale2(real_sqrt(real_sub(real_sub(real_add(REAL_ONE, r[8]), r[0]), r[4])), 1);
        q[0] = real_div(real_sub(r[3], r[1]), s);
        q[1] = real_div(real_add(r[2], r[6]), s);
        q[2] = real_div(real_add(r[5], r[7]), s);
        q[3] = real_scale2(s, -2);
    }
    quat_normalize(q);
    if (real_lt(q[0], REAL_ZERO)) {
        for (int i = 0; i < 4; i++) {
            q[i] = real_neg(q[i]);
        }
    }
}

/* a x b, each component one rounded sum */
static void cross(const real_t a[3], const real_t b[3], real_t out[3])
{
    for (int i = 0; i < 3; i++) {
        int j = (i + 1) % 3;
        int k = (i + 2) % 3;
        out[i] = real_acc_get(real_acc_mac(real_acc_mac(real_acc_zero(), a[j], b[k]), real_neg(a[k]), b[j]), 0);
    }
}

/* v / |v| in place */
static void normalize3(real_t v[3])
{
    real_t norm = vec_norm(v, 3);
    for (int i = 0; i < 3; i++) {
        v[i] = real_div(v[i], norm);
    }
}

void quat_from_accel_mag(const real_t accel[3], const real_t mag[3], real_t q[4])
{
    /* The rows of R are world north, west and up in body coordinates: up is the accelerometer's
     * direction, west = up x field, north = west x up. */
    real_t r[9];
    real_t *north = &r[0], *west = &r[3], *up = &r[6];
    for (int i = 0; i < 3; i++) {
        up[i] = accel[i];
    }
    normalize3(up);
    cross(up, mag, west);
    normalize3(west);
    cross(west, up, north);
    quat_from_matrix(r, q);
}
