/*
 * matrix_bench.c - the EKF-like workload of `robosoc bench core`.
 *
 * Each iteration inverts a 7x7 matrix by Gauss-Jordan elimination with partial pivoting and
 * multiplies it back (A * inv(A)), once in single-precision soft-float and once in Q16.16
 * fixed point (64-bit products, division through a reciprocal), as the seed paper's EKF does.
 * BENCH_ITERATIONS (default 10) sets the repetitions.  At the end the program prints the
 * results (bit patterns in hex, so the host and the core print identical bytes) unless
 * BENCH_QUIET is defined, and returns 0 when both products are close to the identity.
 * The same source builds for the host (hf_print goes to stdout there).
 */
#include <stdint.h>

#include "hf_print.h"

#ifndef BENCH_ITERATIONS
#define BENCH_ITERATIONS 10
#endif

#define N 7

typedef int32_t q16_t;
#define Q16_ONE 65536

static float a_f[N][N], inv_f[N][N], prod_f[N][N];
static q16_t a_q[N][N], inv_q[N][N], prod_q[N][N];

/* Keeps the compiler from merging or hoisting iterations: memory may have changed. */
static inline void barrier(void)
{
    __asm__ volatile("" ::: "memory");
}

static q16_t q16_mul(q16_t a, q16_t b)
{
    return (q16_t)(((int64_t)a * b) >> 16);
}

static q16_t q16_div(q16_t a, q16_t b)
{
    q16_t recip = (q16_t)(((int64_t)1 << 32) / b);
    return q16_mul(a, recip);
}

/* A diagonally dominant matrix with entries that are exact in both formats (multiples of 1/4). */
static void make_matrix(void)
{
    for (int i = 0; i < N; i++) {
        for (int j = 0; j < N; j++) {
            int32_t quarters = i == j ? 4 * (4 + i) : (i * 7 + j * 3) % 5 - 2;
            a_f[i][j] = (float)quarters * 0.25f;
            a_q[i][j] = quarters * (Q16_ONE / 4);
        }
    }
}

static int invert_f(float m[N][N], float inv[N][N])
{
    float w[N][N];
    for (int i = 0; i < N; i++) {
        for (int j = 0; j < N; j++) {
            w[i][j] = m[i][j];
            inv[i][j] = i == j ? 1.0f : 0.0f;
        }
    }
    for (int c = 0; c < N; c++) {
        int p = c;
        for (int r = c + 1; r < N; r++) {
            float x = w[r][c] < 0.0f ? -w[r][c] : w[r][c];
            float y = w[p][c] < 0.0f ? -w[p][c] : w[p][c];
            if (x > y) {
                p = r;
            }
        }
        if (w[p][c] == 0.0f) {
            return -1;
        }
        if (p != c) {
            for (int j = 0; j < N; j++) {
                float t = w[c][j];
                w[c][j] = w[p][j];
                w[p][j] = t;
                t = inv[c][j];
                inv[c][j] = inv[p][j];
                inv[p][j] = t;
            }
        }
        float d = 1.0f / w[c][c];
        for (int j = 0; j < N; j++) {
            w[c][j] *= d;
            inv[c][j] *= d;
        }
        for (int r = 0; r < N; r++) {
            if (r == c) {
                continue;
            }
            float f = w[r][c];
            for (int j = 0; j < N; j++) {
                w[r][j] -= f * w[c][j];
                inv[r][j] -= f * inv[c][j];
            }
        }
    }
    return 0;
}

static int invert_q(q16_t m[N][N], q16_t inv[N][N])
{
    q16_t w[N][N];
    for (int i = 0; i < N; i++) {
        for (int j = 0; j < N; j++) {
            w[i][j] = m[i][j];
            inv[i][j] = i == j ? Q16_ONE : 0;
        }
    }
    for (int c = 0; c < N; c++) {
        int p = c;
        for (int r = c + 1; r < N; r++) {
            q16_t x = w[r][c] < 0 ? -w[r][c] : w[r][c];
            q16_t y = w[p][c] < 0 ? -w[p][c] : w[p][c];
            if (x > y) {
                p = r;
            }
        }
        if (w[p][c] == 0) {
            return -1;
        }
        if (p != c) {
            for (int j = 0; j < N; j++) {
                q16_t t = w[c][j];
                w[c][j] = w[p][j];
                w[p][j] = t;
                t = inv[c][j];
                inv[c][j] = inv[p][j];
                inv[p][j] = t;
            }
        }
        q16_t pivot = w[c][c];
        for (int j = 0; j < N; j++) {
            w[c][j] = q16_div(w[c][j], pivot);
            inv[c][j] = q16_div(inv[c][j], pivot);
        }
        for (int r = 0; r < N; r++) {
            if (r == c) {
                continue;
            }
            q16_t f = w[r][c];
            for (int j = 0; j < N; j++) {
                w[r][j] -= q16_mul(f, w[c][j]);
                inv[r][j] -= q16_mul(f, inv[c][j]);
            }
        }
    }
    return 0;
}

static void multiply_f(float a[N][N], float b[N][N], float out[N][N])
{
    for (int i = 0; i < N; i++) {
        for (int j = 0; j < N; j++) {
            float s = 0.0f;
            for (int k = 0; k < N; k++) {
                s += a[i][k] * b[k][j];
            }
            out[i][j] = s;
        }
    }
}

static void multiply_q(q16_t a[N][N], q16_t b[N][N], q16_t out[N][N])
{
    for (int i = 0; i < N; i++) {
        for (int j = 0; j < N; j++) {
            int64_t s = 0;
            for (int k = 0; k < N; k++) {
                s += (int64_t)a[i][k] * b[k][j];
            }
            out[i][j] = (q16_t)(s >> 16);
        }
    }
}

#ifndef BENCH_QUIET
static uint32_t float_bits(float f)
{
    union {
        float f;
        uint32_t u;
    } v = {.f = f};
    return v.u;
}

static void print_matrix_f(const char *name, float m[N][N])
{
    for (int i = 0; i < N; i++) {
        hf_printf("%s[%d]", name, i);
        for (int j = 0; j < N; j++) {
            hf_printf(" %08x", (unsigned)float_bits(m[i][j]));
        }
        hf_putchar('\n');
    }
}

static void print_matrix_q(const char *name, q16_t m[N][N])
{
    for (int i = 0; i < N; i++) {
        hf_printf("%s[%d]", name, i);
        for (int j = 0; j < N; j++) {
            hf_printf(" %08x", (unsigned)m[i][j]);
        }
        hf_putchar('\n');
    }
}
#endif

int main(void)
{
    make_matrix();
    int failures = 0;
    for (int it = 0; it < BENCH_ITERATIONS; it++) {
        barrier();
        failures += invert_f(a_f, inv_f) != 0;
        multiply_f(a_f, inv_f, prod_f);
        barrier();
        failures += invert_q(a_q, inv_q) != 0;
        multiply_q(a_q, inv_q, prod_q);
    }
    /* Both products must be the identity within 1e-4 (float) and 64/65536 (Q16.16). */
    for (int i = 0; i < N; i++) {
        for (int j = 0; j < N; j++) {
            float ef = prod_f[i][j] - (i == j ? 1.0f : 0.0f);
            q16_t eq = prod_q[i][j] - (i == j ? Q16_ONE : 0);
            failures += ef > 1e-4f || ef < -1e-4f;
            failures += eq > 64 || eq < -64;
        }
    }
#ifndef BENCH_QUIET
    print_matrix_f("inv_f", inv_f);
    print_matrix_f("prod_f", prod_f);
    print_matrix_q("inv_q", inv_q);
    print_matrix_q("prod_q", prod_q);
    hf_printf("iterations %d failures %d\n", BENCH_ITERATIONS, failures);
#endif
    return failures;
}
