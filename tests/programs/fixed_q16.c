/* Q16.16 fixed point as the seed paper's firmware does it: multiply through a 64-bit product,
 * division through a reciprocal, square root by Newton iteration, sine by a parabola plus one
 * refinement (cosine as shifted sine). */
#include <stdint.h>

#include "report.h"

typedef int32_t q16_t;
#define Q16_ONE 65536
#define Q16_PI 205887         /* pi in Q16.16 */
#define Q16_HALF_PI 102944
#define Q16_TWO_PI 411775

static q16_t q16_mul(q16_t a, q16_t b)
{
    return (q16_t)(((int64_t)a * b) >> 16);
}

/* 1/b in Q16.16 (b != 0), then a * (1/b). */
static q16_t q16_recip(q16_t b)
{
    return (q16_t)(((int64_t)1 << 32) / b);
}

static q16_t q16_div(q16_t a, q16_t b)
{
    return q16_mul(a, q16_recip(b));
}

/* sqrt(a), a >= 0, Newton iteration on Q16.16 values. */
static q16_t q16_sqrt(q16_t a)
{
    if (a <= 0) {
        return 0;
    }
    q16_t x = a > Q16_ONE ? a >> 1 : Q16_ONE;
    for (int i = 0; i < 24; i++) {
        q16_t next = (x + (q16_t)((((int64_t)a) << 16) / x)) >> 1;
        if (next == x) {
            break;
        }
        x = next;
    }
    return x;
}

/* sin(x) for x in [-pi, pi]: y = 4/pi x - 4/pi^2 x|x|, refined by y = 0.225 (y|y| - y) + y. */
static q16_t q16_sin(q16_t x)
{
    const q16_t b = 83443;  /* 4/pi */
    const q16_t c = -26561; /* -4/pi^2 */
    const q16_t p = 14746;  /* 0.225 */
    q16_t ax = x < 0 ? -x : x;
    q16_t y = q16_mul(b, x) + q16_mul(q16_mul(c, x), ax);
    q16_t ay = y < 0 ? -y : y;
    return q16_mul(p, q16_mul(y, ay) - y) + y;
}

static q16_t q16_cos(q16_t x)
{
    x += Q16_HALF_PI;
    if (x > Q16_PI) {
        x -= Q16_TWO_PI;
    }
    return q16_sin(x);
}

static const int32_t values[] = {
    0, 1, -1, 65536, -65536, 32768, 98304, -98304, 205887, 1000000, -1000000, 6553600, 123, 0x7fffffff / 256,
};
#define N_VALUES (sizeof values / sizeof values[0])

int main(void)
{
    for (uint32_t i = 0; i < N_VALUES; i++) {
        for (uint32_t j = 0; j < N_VALUES; j++) {
            q16_t a = (q16_t)opaque32((uint32_t)values[i]);
            q16_t b = (q16_t)opaque32((uint32_t)values[j]);
            report32("qmul", (uint32_t)a, (uint32_t)b, (uint32_t)q16_mul(a, b));
            if (b > 1 || b < -1) {
                report32("qdiv", (uint32_t)a, (uint32_t)b, (uint32_t)q16_div(a, b));
            }
        }
        q16_t a = (q16_t)opaque32((uint32_t)values[i]);
        if (a >= 0) {
            report32("qsqrt", (uint32_t)a, 0u, (uint32_t)q16_sqrt(a));
        }
    }
    for (int32_t k = -32; k <= 32; k++) {
        q16_t x = (q16_t)opaque32((uint32_t)(k * (Q16_PI / 32)));
        report32("qsin", (uint32_t)x, 0u, (uint32_t)q16_sin(x));
        report32("qcos", (uint32_t)x, 0u, (uint32_t)q16_cos(x));
    }
    return 0;
}
