/* 32-bit integer arithmetic on edge values: add/sub/mul (low and high words), division and
 * remainder (signed, unsigned), shifts and comparisons. */
#include <stdint.h>

#include "report.h"

static const uint32_t values[] = {
    0u, 1u, 2u, 3u, 7u, 10u, 0x7fu, 0x80u, 0xffu, 0x7fffu, 0x8000u, 0xffffu, 0x10000u,
    0x12345678u, 0x55555555u, 0xaaaaaaaau, 0x7ffffffeu, 0x7fffffffu, 0x80000000u, 0x80000001u,
    0xfffffff9u, 0xfffffffeu, 0xffffffffu, 0xdeadbeefu,
};
#define N_VALUES (sizeof values / sizeof values[0])

int main(void)
{
    uint32_t checksum = 0;
    for (uint32_t i = 0; i < N_VALUES; i++) {
        for (uint32_t j = 0; j < N_VALUES; j++) {
            uint32_t a = opaque32(values[i]);
            uint32_t b = opaque32(values[j]);
            int32_t sa = (int32_t)a, sb = (int32_t)b;
            report32("add", a, b, a + b);
            report32("sub", a, b, a - b);
            report32("mul", a, b, a * b);
            report32("mulh", a, b, (uint32_t)(((int64_t)sa * (int64_t)sb) >> 32));
            report32("mulhu", a, b, (uint32_t)(((uint64_t)a * (uint64_t)b) >> 32));
            if (b != 0u) {
                report32("divu", a, b, a / b);
                report32("remu", a, b, a % b);
                if (!(sa == INT32_MIN && sb == -1)) {
                    report32("div", a, b, (uint32_t)(sa / sb));
                    report32("rem", a, b, (uint32_t)(sa % sb));
                }
            }
            report32("slt", a, b, sa < sb);
            report32("sltu", a, b, a < b);
            checksum = checksum * 31u + (a ^ (b >> 3));
        }
        for (uint32_t s = 0; s < 32; s++) {
            uint32_t sh = opaque32(s);
            uint32_t a = opaque32(values[i]);
            report32("sll", a, sh, a << sh);
            report32("srl", a, sh, a >> sh);
            report32("sra", a, sh, (uint32_t)((int32_t)a >> sh)); /* arithmetic on both compilers */
        }
    }
    report32("checksum", N_VALUES, 0u, checksum);
    return 0;
}
