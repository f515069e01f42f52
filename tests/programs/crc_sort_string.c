/* Table-driven CRC-32 (IEEE 802.3), a quicksort of pseudo-random numbers and string routines. */
#include <stdint.h>
#include <string.h>

#include "report.h"

static uint32_t crc_table[256];

static void crc32_init(void)
{
    for (uint32_t n = 0; n < 256; n++) {
        uint32_t c = n;
        for (int k = 0; k < 8; k++) {
            c = (c & 1u) ? 0xedb88320u ^ (c >> 1) : c >> 1;
        }
        crc_table[n] = c;
    }
}

static uint32_t crc32(const uint8_t *data, uint32_t len)
{
    uint32_t c = 0xffffffffu;
    for (uint32_t i = 0; i < len; i++) {
        c = crc_table[(c ^ data[i]) & 0xffu] ^ (c >> 8);
    }
    return c ^ 0xffffffffu;
}

static void quicksort(int32_t *a, int32_t lo, int32_t hi)
{
    while (lo < hi) {
        int32_t pivot = a[lo + (hi - lo) / 2];
        int32_t i = lo, j = hi;
        while (i <= j) {
            while (a[i] < pivot) i++;
            while (a[j] > pivot) j--;
            if (i <= j) {
                int32_t t = a[i];
                a[i] = a[j];
                a[j] = t;
                i++;
                j--;
            }
        }
        if (j - lo < hi - i) {
            quicksort(a, lo, j);
            lo = i;
        } else {
            quicksort(a, i, hi);
            hi = j;
        }
    }
}

static void reverse(char *s)
{
    size_t n = strlen(s);
    for (size_t i = 0; i < n / 2; i++) {
        char t = s[i];
        s[i] = s[n - 1 - i];
        s[n - 1 - i] = t;
    }
}

#define N_SORT 200
static int32_t numbers[N_SORT];
static uint8_t buffer[1024];

int main(void)
{
    crc32_init();
    const char *check = "123456789";
    report32("crc32", (uint32_t)strlen(check), 0u, crc32((const uint8_t *)check, (uint32_t)strlen(check)));

    uint32_t state = opaque32(12345u);
    for (uint32_t i = 0; i < sizeof buffer; i++) {
        state = state * 1103515245u + 12345u; /* the C standard's example LCG */
        buffer[i] = (uint8_t)(state >> 16);
    }
    report32("crc32lcg", (uint32_t)sizeof buffer, 12345u, crc32(buffer, sizeof buffer));

    for (uint32_t i = 0; i < N_SORT; i++) {
        state = state * 1103515245u + 12345u;
        numbers[i] = (int32_t)state >> 7;
    }
    quicksort(numbers, 0, N_SORT - 1);
    for (uint32_t i = 0; i < N_SORT; i++) {
        report32("sorted", i, 0u, (uint32_t)numbers[i]);
    }

    char text[64];
    memset(text, 0, sizeof text);
    memcpy(text, "robosoc on hf-riscv", 20);
    reverse(text);
    hf_printf("reversed %s\n", text);
    hf_printf("strcmp %d %d %d\n", strcmp("abc", "abd") < 0, strcmp("b", "a") > 0, strcmp("x", "x") == 0);
    hf_printf("printf %d|%u|%x|%08x|%5d|%c|%s|%lld|%llx|%%\n", -42, 4000000000u, 0xbeefu, 0x1234u, -7, 'Q',
              "str", (long long)-1234567890123456789LL, 0x0123456789abcdefULL);
    hf_putdec(-2147483647 - 1);
    hf_putchar(' ');
    hf_putudec(4294967295u);
    hf_putchar(' ');
    hf_putdec64(INT64_MIN);
    hf_putchar(' ');
    hf_putudec64(UINT64_MAX);
    hf_putchar('\n');
    return 7;
}
