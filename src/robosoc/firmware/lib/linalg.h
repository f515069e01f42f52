/*
 * linalg.h - small vectors and matrices of real_t (real.h), row-major, sizes passed as arguments.
 *
 * Element (i, j) of an r x c matrix `a` is a[i * c + j].  Matrices up to MAT_MAX x MAT_MAX (the
 * EKF's 7 x 7); nothing allocates.  An output must not alias an input, except where a comment
 * says so.  The products take `shift`: the result is scaled by 2^shift in the same rounding step
 * (exact and free in the fixed build, an exact power-of-two multiply in the float build), which is
 * how callers move a product from one unit to another (see real.h).
 */
#ifndef LINALG_H
#define LINALG_H

#include "real.h"

#define MAT_MAX 7

void mat_zero(real_t *out, int rows, int cols);
void mat_identity(real_t *out, int n);
void mat_copy(const real_t *a, real_t *out, int rows, int cols);                     /* may alias */
void mat_add(const real_t *a, const real_t *b, real_t *out, int rows, int cols);     /* may alias */
void mat_sub(const real_t *a, const real_t *b, real_t *out, int rows, int cols);     /* may alias */
void mat_transpose(const real_t *a, real_t *out, int rows, int cols);

/* out (n x p) = a (n x m) * b (m x p) * 2^shift */
void mat_mul(const real_t *a, const real_t *b, real_t *out, int n, int m, int p, int shift);
/* out (n x p) = a (n x m) * transpose(b (p x m)) * 2^shift */
void mat_mul_bt(const real_t *a, const real_t *b, real_t *out, int n, int m, int p, int shift);
/* out (n x p) = transpose(a (m x n)) * b (m x p) * 2^shift */
void mat_mul_at(const real_t *a, const real_t *b, real_t *out, int n, int m, int p, int shift);
/* out (n) = a (n x m) * x (m) * 2^shift */
void mat_vec(const real_t *a, const real_t *x, real_t *out, int n, int m, int shift);

/* Solve a (n x n) * X = b (n x m) by Gaussian elimination with partial pivoting: b becomes X,
 * a is destroyed.  Returns 0, or -1 when a pivot is zero (singular). */
int mat_solve(real_t *a, real_t *b, int n, int m);
/* out = inverse(a) (n x n) through mat_solve; returns 0 or -1 (singular). */
int mat_inverse(const real_t *a, real_t *out, int n);

/* a . b * 2^shift */
real_t vec_dot(const real_t *a, const real_t *b, int n, int shift);
/* |a| (one rounding from the exact sum of squares in the fixed build) */
real_t vec_norm(const real_t *a, int n);

#endif /* LINALG_H */
