/* 64-bit integer arithmetic on edge values: add/sub/mul, division and remainder (signed,
 * unsigned), shifts across the word boundary. */
#include <stdint.h>

#include "report.h"

static const uint64_t values[] = {
    0ull, 1ull, 3ull, 10ull, 0xffffffffull, 0x100000000ull, 0x100000001ull, 0x123456789abcdef0ull,
    0x7fffffffffffffffull, 0x8000000000000000ull, 0x8000000000000001ull, 0xfffffffffffffff6ull,
    0xffffffffffffffffull, 0x00000000deadbeefull, 0xcafebabe00000000ull, 0x5555555555555555ull,
};
#define N_VALUES (sizeof values / sizeof values[0])

int main(void)
{
    for (uint32_t i = 0; i < N_VALUES; i++) {
        for (uint32_t j = 0; j < N_VALUES; j++) {
            uint64_t a = opaque64(values[i]);
            uint64_t b = opaque64(values[j]);
            int64_t sa = (int64_t)a, sb = (int64_t)b;
            report64("add64", a, b, a + b);
            report64("sub64", a, b, a - b);
            report64("mul64", a, b, a * b);
            if (b != 0u) {
                report64("divu64", a, b, a / b);
                report64("remu64", a, b, a % b);
                if (!(sa == INT64_MIN && sb == -1)) {
                    report64("div64", a, b, (uint64_t)(sa / sb));
                    report64("rem64", a, b, (uint64_t)(sa % sb));
                }
            }
            report64("slt64", a, b, sa < sb);
        }
        for (uint32_t s = 0; s < 64; s += 1) {
            uint64_t a = opaque64(values[i]);
            uint32_t sh = opaque32(s);
            report64("sll64", a, sh, a << sh);
            report64("srl64", a, sh, a >> sh);
            report64("sra64", a, sh, (uint64_t)((int64_t)a >> sh));
        }
    }
    /* Widening multiplies as 32-bit code writes them. */
    for (uint32_t i = 0; i < N_VALUES; i++) {
        uint32_t a = opaque32((uint32_t)values[i]);
        uint32_t b = opaque32((uint32_t)(values[i] >> 29));
        report64("wmulu", a, b, (uint64_t)a * b);
        report64("wmul", (uint64_t)(int64_t)(int32_t)a, (uint64_t)(int64_t)(int32_t)b,
                 (uint64_t)((int64_t)(int32_t)a * (int32_t)b));
    }
    return 0;
}
