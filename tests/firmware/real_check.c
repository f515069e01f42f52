/*
 * real_check.c - the matrix and quaternion routines over real_t on pseudo-random inputs, in
 * either build (ROBOSOC_ARITH_FIXED or not).  One line per call:
 *
 *   <op> <inputs...> | <outputs...> | <cycles>
 *
 * inputs and outputs as the hex bits of real_t (float bits, or the Q16.16 integer), cycles from
 * TIMER0 on the core (0 on the host) around the call.  test_linalg_quat.py recomputes every
 * output with numpy.  CHECK_COUNT calls per routine.
 */
#include <stdint.h>
#include <string.h>

#include "hf_print.h"
#include "linalg.h"
#include "quat.h"

#ifndef CHECK_COUNT
#define CHECK_COUNT 20
#endif

#if defined(__riscv)
#include "hfriscv.h"
static inline uint32_t cycles(void) { return hf_cycles(); }
#else
static inline uint32_t cycles(void) { return 0; }
#endif

static uint32_t state = 2024;

static uint32_t rnd(void) /* xorshift32 */
{
    state ^= state << 13;
    state ^= state >> 17;
    state ^= state << 5;
    return state;
}

/* Uniform in [-range, range] (range in Q16.16 LSB), as real_t. */
static real_t rnd_real(int32_t range)
{
    int32_t v = (int32_t)(rnd() % (2u * (uint32_t)range + 1u)) - range;
    return real_from_fix16(v);
}

static void fill(real_t *v, int n, int32_t range)
{
    for (int i = 0; i < n; i++) {
        v[i] = rnd_real(range);
    }
}

static void put(const real_t *v, int n)
{
    for (int i = 0; i < n; i++) {
        uint32_t bits;
        memcpy(&bits, &v[i], sizeof bits);
        hf_putchar(' ');
        hf_puthex(bits);
    }
}

static void line(const char *op, const real_t *in, int n_in, const real_t *out, int n_out, uint32_t spent)
{
    hf_puts(op);
    put(in, n_in);
    hf_puts(" |");
    put(out, n_out);
    hf_printf(" | %u\n", (unsigned)spent);
}

#define ONE 65536
#define N 7

int main(void)
{
    real_t a[N * N], b[N * N], c[N * N], in[3 * N * N];
    uint32_t start, spent;
    for (int t = 0; t < CHECK_COUNT; t++) {
        /* products, with and without a scale shift */
        static const int shifts[3] = {0, -4, 3};
        int shift = shifts[t % 3];
        fill(a, N * N, 2 * ONE);
        fill(b, N * N, 2 * ONE);
        memcpy(in, a, sizeof a);
        memcpy(in + N * N, b, sizeof b);
        in[2 * N * N] = real_from_int(shift);
        start = cycles();
        mat_mul(a, b, c, N, N, N, shift);
        spent = cycles() - start;
        line("mul", in, 2 * N * N + 1, c, N * N, spent);
        start = cycles();
        mat_mul_bt(a, b, c, N, N, N, shift);
        spent = cycles() - start;
        line("mul_bt", in, 2 * N * N + 1, c, N * N, spent);
        start = cycles();
        mat_mul_at(a, b, c, N, N, N, shift);
        spent = cycles() - start;
        line("mul_at", in, 2 * N * N + 1, c, N * N, spent);

        /* a 6 x 6 system with 7 right-hand sides: diagonally dominant, like an innovation covariance */
        fill(a, 36, ONE / 4);
        for (int i = 0; i < 6; i++) {
            a[i * 6 + i] = real_add(a[i * 6 + i], real_from_fix16(2 * ONE));
        }
        fill(b, 42, 4 * ONE);
        memcpy(in, a, 36 * sizeof(real_t));
        memcpy(in + 36, b, 42 * sizeof(real_t));
        start = cycles();
        int status = mat_solve(a, b, 6, 7);
        spent = cycles() - start;
        b[42] = real_from_int(status);
        line("solve", in, 78, b, 43, spent);

        /* a 4 x 4 inverse */
        fill(a, 16, ONE / 2);
        for (int i = 0; i < 4; i++) {
            a[i * 4 + i] = real_add(a[i * 4 + i], real_from_fix16(ONE + ONE / 2));
        }
        start = cycles();
        status = mat_inverse(a, c, 4);
        spent = cycles() - start;
        c[16] = real_from_int(status);
        line("inverse", a, 16, c, 17, spent);

        /* vectors */
        fill(a, 7, 8 * ONE);
        start = cycles();
        c[0] = vec_norm(a, 7);
        spent = cycles() - start;
        line("norm", a, 7, c, 1, spent);

        /* quaternions: q and p near unit length, a vector v */
        real_t q[4], p[4], v[3], r[12];
        fill(q, 4, ONE);
        quat_normalize(q);
        fill(p, 4, ONE);
        quat_normalize(p);
        fill(v, 3, ONE);
        memcpy(in, q, sizeof q);
        memcpy(in + 4, p, sizeof p);
        start = cycles();
        quat_mul(q, p, r);
        spent = cycles() - start;
        line("qmul", in, 8, r, 4, spent);

        fill(p, 4, 2 * ONE);
        memcpy(r, p, sizeof p);
        start = cycles();
        quat_normalize(r);
        spent = cycles() - start;
        line("qnormalize", p, 4, r, 4, spent);

        memcpy(in, q, sizeof q);
        memcpy(in + 4, v, sizeof v);
        start = cycles();
        quat_rotate(q, v, r);
        spent = cycles() - start;
        line("qrotate", in, 7, r, 3, spent);
        start = cycles();
        quat_rotate_to_body(q, v, r);
        spent = cycles() - start;
        line("qrotate_to_body", in, 7, r, 3, spent);
        start = cycles();
        quat_rotate_to_body_jacobian(q, v, r);
        spent = cycles() - start;
        line("qjacobian", in, 7, r, 12, spent);

        /* integration over 10 ms at rates up to 4 rad/s */
        fill(v, 3, 4 * ONE);
        real_t dt = real_from_fix16(655);
        memcpy(in, q, sizeof q);
        memcpy(in + 4, v, sizeof v);
        in[7] = dt;
        start = cycles();
        quat_integrate(q, v, dt, r);
        spent = cycles() - start;
        line("qintegrate", in, 8, r, 4, spent);

        start = cycles();
        quat_to_euler(q, r);
        spent = cycles() - start;
        line("qeuler", q, 4, r, 3, spent);

        /* TRIAD: an accelerometer of up to 12 m/s^2 per axis, a field of up to 1 per axis */
        real_t acc[3], field[3];
        fill(acc, 3, 12 * ONE);
        fill(field, 3, ONE);
        memcpy(in, acc, sizeof acc);
        memcpy(in + 3, field, sizeof field);
        start = cycles();
        quat_from_accel_mag(acc, field, r);
        spent = cycles() - start;
        line("qtriad", in, 6, r, 4, spent);
    }
    return 0;
}
