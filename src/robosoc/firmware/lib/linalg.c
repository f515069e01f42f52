/*
 * linalg.c - see linalg.h.  Every dot product goes through real_acc_t, so in the fixed build an
 * element of a product is rounded once, not once per term.
 */
#include "linalg.h"

void mat_zero(real_t *out, int rows, int cols)
{
    for (int i = 0; i < rows * cols; i++) {
        out[i] = REAL_ZERO;
    }
}

void mat_identity(real_t *out, int n)
{
    for (int i = 0; i < n; i++) {
        for (int j = 0; j < n; j++) {
            out[i * n + j] = i == j ? REAL_ONE : REAL_ZERO;
        }
    }
}

void mat_copy(const real_t *a, real_t *out, int rows, int cols)
{
    for (int i = 0; i < rows * cols; i++) {
        out[i] = a[i];
    }
}

void mat_add(const real_t *a, const real_t *b, real_t *out, int rows, int cols)
{
    for (int i = 0; i < rows * cols; i++) {
        out[i] = real_add(a[i], b[i]);
    }
}

void mat_sub(const real_t *a, const real_t *b, real_t *out, int rows, int cols)
{
    for (int i = 0; i < rows * cols; i++) {
        out[i] = real_sub(a[i], b[i]);
    }
}

void mat_transpose(const real_t *a, real_t *out, int rows, int cols)
{
    for (int i = 0; i < rows; i++) {
        for (int j = 0; j < cols; j++) {
            out[j * rows + i] = a[i * cols + j];
        }
    }
}

void mat_mul(const real_t *a, const real_t *b, real_t *out, int n, int m, int p, int shift)
{
    for (int i = 0; i < n; i++) {
        for (int j = 0; j < p; j++) {
            real_acc_t acc = real_acc_zero();
            for (int k = 0; k < m; k++) {
                acc = real_acc_mac(acc, a[i * m + k], b[k * p + j]);
            }
            out[i * p + j] = real_acc_get(acc, shift);
        }
    }
}

void mat_mul_bt(const real_t *a, const real_t *b, real_t *out, int n, int m, int p, int shift)
{
    for (int i = 0; i < n; i++) {
        for (int j = 0; j < p; j++) {
            real_acc_t acc = real_acc_zero();
            for (int k = 0; k < m; k++) {
                acc = real_acc_mac(acc, a[i * m + k], b[j * m + k]);
            }
            out[i * p + j] = real_acc_get(acc, shift);
        }
    }
}

void mat_mul_at(const real_t *a, const real_t *b, real_t *out, int n, int m, int p, int shift)
{
    for (int i = 0; i < n; i++) {
        for (int j = 0; j < p; j++) {
            real_acc_t acc = real_acc_zero();
            for (int k = 0; k < m; k++) {
                acc = real_acc_mac(acc, a[k * n + i], b[k * p + j]);
            }
            out[i * p + j] = real_acc_get(acc, shift);
        }
    }
}

void mat_vec(const real_t *a, const real_t *x, real_t *out, int n, int m, int shift)
{
    mat_mul(a, x, out, n, m, 1, shift);
}

/*
 * Forward elimination with row pivoting (the largest |pivot| keeps every multiplier within
 * [-1, 1], so no intermediate value grows), then back substitution; each back-substituted
 * numerator b - sum(a * x) is one accumulated sum, rounded once before the division.
 */
int mat_solve(real_t *a, real_t *b, int n, int m)
{
    for (int c = 0; c < n; c++) {
        int pivot = c;
        for (int r = c + 1; r < n; r++) {
            if (real_lt(real_abs(a[pivot * n + c]), real_abs(a[r * n + c]))) {
                pivot = r;
            }
        }
        if (a[pivot * n + c] == REAL_ZERO) {
            return -1;
        }
        if (pivot != c) {
            for (int j = 0; j < n; j++) {
                real_t t = a[c * n + j];
                a[c * n + j] = a[pivot * n + j];
                a[pivot * n + j] = t;
            }
            for (int j = 0; j < m; j++) {
                real_t t = b[c * m + j];
                b[c * m + j] = b[pivot * m + j];
                b[pivot * m + j] = t;
            }
        }
        for (int r = c + 1; r < n; r++) {
            real_t factor = real_div(a[r * n + c], a[c * n + c]);
            for (int j = c + 1; j < n; j++) {
                a[r * n + j] = real_sub(a[r * n + j], real_mul(factor, a[c * n + j]));
            }
            for (int j = 0; j < m; j++) {
                b[r * m + j] = real_sub(b[r * m + j], real_mul(factor, b[c * m + j]));
            }
        }
    }
    for (int i = n - 1; i >= 0; i--) {
        for (int j = 0; j < m; j++) {
            real_acc_t acc = real_acc_mac(real_acc_zero(), b[i * m + j], REAL_ONE);
            for (int k = i + 1; k < n; k++) {
                acc = real_acc_mac(acc, real_neg(a[i * n + k]), b[k * m + j]);
            }
            b[i * m + j] = real_div(real_acc_get(acc, 0), a[i * n + i]);
        }
    }
    return 0;
}

int mat_inverse(const real_t *a, real_t *out, int n)
{
    real_t work[MAT_MAX * MAT_MAX];
    mat_copy(a, work, n, n);
    mat_identity(out, n);
    return mat_solve(work, out, n, n);
}

real_t vec_dot(const real_t *a, const real_t *b, int n, int shift)
{
    real_acc_t acc = real_acc_zero();
    for (int i = 0; i < n; i++) {
        acc = real_acc_mac(acc, a[i], b[i]);
    }
    return real_acc_get(acc, shift);
}

real_t vec_norm(const real_t *a, int n)
{
    real_acc_t acc = real_acc_zero();
    for (int i = 0; i < n; i++) {
        acc = real_acc_mac(acc, a[i], a[i]);
    }
    return real_acc_sqrt(acc);
}
