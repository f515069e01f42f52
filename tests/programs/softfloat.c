/* Soft-float on the core (compiler-rt), hardware IEEE on the host: single and double
 * add/sub/mul/div, square root by Newton iteration, and conversions. */
#include <stdint.h>

#include "report.h"

static const uint32_t fvalues[] = {
    0x00000000u, /* 0 */
    0x80000000u, /* -0 */
    0x3f800000u, /* 1 */
    0xbf800000u, /* -1 */
    0x40490fdbu, /* pi */
    0x3dcccccdu, /* 0.1 */
    0x447a0000u, /* 1000 */
    0xc2f6e979u, /* -123.456 */
    0x4b800001u, /* 16777218 */
    0x00800000u, /* smallest normal */
    0x00000001u, /* smallest subnormal */
    0x7f7fffffu, /* largest */
    0x3eaaaaabu, /* 1/3 */
    0x7f800000u, /* inf */
};
#define N_F (sizeof fvalues / sizeof fvalues[0])

static const uint64_t dvalues[] = {
    0x0000000000000000ull, 0x3ff0000000000000ull, 0xbff0000000000000ull, 0x400921fb54442d18ull,
    0x3fb999999999999aull, 0x408f400000000000ull, 0xc05edd2f1a9fbe77ull, 0x0010000000000000ull,
    0x0000000000000001ull, 0x7fefffffffffffffull, 0x3fd5555555555555ull, 0x4341c37937e08000ull,
};
#define N_D (sizeof dvalues / sizeof dvalues[0])

static const int32_t ivalues[] = {0, 1, -1, 7, -7, 100000, -2147483647 - 1, 2147483647, 16777217, -16777217};
#define N_I (sizeof ivalues / sizeof ivalues[0])

/* Newton iteration for sqrt(a), a > 0: a fixed number of steps from a power-of-two guess. */
static float newton_sqrtf(float a)
{
    float x = a > 1.0f ? a * 0.5f : 1.0f;
    for (int i = 0; i < 20; i++) {
        x = 0.5f * (x + a / x);
    }
    return x;
}

static double newton_sqrt(double a)
{
    double x = a > 1.0 ? a * 0.5 : 1.0;
    for (int i = 0; i < 40; i++) {
        x = 0.5 * (x + a / x);
    }
    return x;
}

int main(void)
{
    for (uint32_t i = 0; i < N_F; i++) {
        for (uint32_t j = 0; j < N_F; j++) {
            float a = u2f(opaque32(fvalues[i]));
            float b = u2f(opaque32(fvalues[j]));
            report32("fadd", f2u(a), f2u(b), fres(a + b));
            report32("fsub", f2u(a), f2u(b), fres(a - b));
            report32("fmul", f2u(a), f2u(b), fres(a * b));
            if (b != 0.0f) {
                report32("fdiv", f2u(a), f2u(b), fres(a / b));
            }
            report32("flt", f2u(a), f2u(b), a < b);
        }
        float a = u2f(opaque32(fvalues[i]));
        report64("f2d", f2u(a), 0u, dres((double)a));
        if (a > 0.0f && a < 1e30f) {
            report32("fsqrt", f2u(a), 0u, f2u(newton_sqrtf(a)));
        }
        if (a > -2e9f && a < 2e9f) {
            report32("f2i", f2u(a), 0u, (uint32_t)(int32_t)a);
        }
    }
    for (uint32_t i = 0; i < N_D; i++) {
        for (uint32_t j = 0; j < N_D; j++) {
            double a = u2d(opaque64(dvalues[i]));
            double b = u2d(opaque64(dvalues[j]));
            report64("dadd", d2u(a), d2u(b), dres(a + b));
            report64("dsub", d2u(a), d2u(b), dres(a - b));
            report64("dmul", d2u(a), d2u(b), dres(a * b));
            if (b != 0.0) {
                report64("ddiv", d2u(a), d2u(b), dres(a / b));
            }
        }
        double a = u2d(opaque64(dvalues[i]));
        report64("d2f", d2u(a), 0u, fres((float)a));
        if (a > 0.0 && a < 1e300) {
            report64("dsqrt", d2u(a), 0u, d2u(newton_sqrt(a)));
        }
        if (a > -9e18 && a < 9e18) {
            report64("d2l", d2u(a), 0u, (uint64_t)(int64_t)a);
        }
    }
    for (uint32_t i = 0; i < N_I; i++) {
        int32_t v = (int32_t)opaque32((uint32_t)ivalues[i]);
        report32("i2f", (uint32_t)v, 0u, f2u((float)v));
        report32("u2f", (uint32_t)v, 0u, f2u((float)(uint32_t)v));
        report64("i2d", (uint32_t)v, 0u, d2u((double)v));
        int64_t w = (int64_t)v * 1000003;
        report64("l2d", (uint64_t)w, 0u, d2u((double)w));
    }
    return 0;
}
