/*
 * lib_check.c - every fix16_ and flt_ function on pseudo-random inputs, one line per call:
 *
 *   <op> <a> <b> <result> <cycles>
 *
 * a, b and result in hex (32-bit words; the 64-bit product of mul64 in 16 digits), cycles in
 * decimal: TIMER0 around the call of a non-inlined wrapper on the core, 0 on the host.  The line
 * "base" times a wrapper that does nothing: the call overhead to subtract.  test_fix16.py checks
 * every result against float64.  CHECK_COUNT calls per function, inputs from CHECK_SEED.
 */
#include <stdint.h>
#include <string.h>

#include "fix16.h"
#include "flt.h"
#include "hf_print.h"

#ifndef CHECK_COUNT
#define CHECK_COUNT 100
#endif
#ifndef CHECK_SEED
#define CHECK_SEED 12345
#endif

#if defined(__riscv)
#include "hfriscv.h"
static inline uint32_t cycles(void) { return hf_cycles(); }
#else
static inline uint32_t cycles(void) { return 0; }
#endif

static uint32_t state = CHECK_SEED;

static uint32_t rnd(void) /* xorshift32 */
{
    state ^= state << 13;
    state ^= state >> 17;
    state ^= state << 5;
    return state;
}

/* Magnitudes spread over every power of two, random sign. */
static uint32_t rnd_log(void)
{
    uint32_t v = rnd();
    v >>= rnd() % 32u;
    return (rnd() & 1u) ? 0u - v : v;
}

/* Uniform in [-half, half]. */
static uint32_t rnd_sym(uint32_t half)
{
    return (uint32_t)((int32_t)(rnd() % (2u * half + 1u)) - (int32_t)half);
}

static uint32_t fbits(float f)
{
    uint32_t u;
    memcpy(&u, &f, sizeof u);
    return u;
}

static float ffrom(uint32_t u)
{
    float f;
    memcpy(&f, &u, sizeof f);
    return f;
}

/* A float with a biased exponent in [lo, hi] and a random sign. */
static uint32_t rnd_float(uint32_t lo, uint32_t hi)
{
    uint32_t exponent = lo + rnd() % (hi - lo + 1u);
    uint32_t sign = rnd() & 0x80000000u;
    return sign | (exponent << 23) | (rnd() & 0x7fffffu);
}

typedef uint32_t (*op_t)(uint32_t a, uint32_t b);
typedef uint32_t (*gen_t)(int i);

#define NOINLINE __attribute__((noinline))

static NOINLINE uint32_t op_base(uint32_t a, uint32_t b) { (void)b; return a; }
static NOINLINE uint32_t op_add(uint32_t a, uint32_t b) { return (uint32_t)fix16_add((fix16_t)a, (fix16_t)b); }
static NOINLINE uint32_t op_sub(uint32_t a, uint32_t b) { return (uint32_t)fix16_sub((fix16_t)a, (fix16_t)b); }
static NOINLINE uint32_t op_mul(uint32_t a, uint32_t b) { return (uint32_t)fix16_mul((fix16_t)a, (fix16_t)b); }
static NOINLINE uint32_t op_div(uint32_t a, uint32_t b) { return (uint32_t)fix16_div((fix16_t)a, (fix16_t)b); }
/* the alternative fix16_div replaces: compiler-rt's 64-bit division (truncating), for the cost table */
static NOINLINE uint32_t op_divdi3(uint32_t a, uint32_t b)
{
    if (b == 0) {
        return 0;
    }
    return (uint32_t)fix16_sat64(((int64_t)(int32_t)a * 65536) / (int32_t)b);
}
static NOINLINE uint32_t op_sqrt(uint32_t a, uint32_t b) { (void)b; return (uint32_t)fix16_sqrt((fix16_t)a); }
static NOINLINE uint32_t op_sin(uint32_t a, uint32_t b) { (void)b; return (uint32_t)fix16_sin((fix16_t)a); }
static NOINLINE uint32_t op_cos(uint32_t a, uint32_t b) { (void)b; return (uint32_t)fix16_cos((fix16_t)a); }
static NOINLINE uint32_t op_atan2(uint32_t a, uint32_t b) { return (uint32_t)fix16_atan2((fix16_t)a, (fix16_t)b); }
static NOINLINE uint32_t op_asin(uint32_t a, uint32_t b) { (void)b; return (uint32_t)fix16_asin((fix16_t)a); }
static NOINLINE uint32_t op_from_int(uint32_t a, uint32_t b) { (void)b; return (uint32_t)fix16_from_int((int32_t)a); }
static NOINLINE uint32_t op_to_int(uint32_t a, uint32_t b) { (void)b; return (uint32_t)fix16_to_int((fix16_t)a); }
static NOINLINE uint32_t op_from_float(uint32_t a, uint32_t b) { (void)b; return (uint32_t)fix16_from_float(ffrom(a)); }
static NOINLINE uint32_t op_to_float(uint32_t a, uint32_t b) { (void)b; return fbits(fix16_to_float((fix16_t)a)); }
static NOINLINE uint32_t op_fsqrt(uint32_t a, uint32_t b) { (void)b; return fbits(flt_sqrt(ffrom(a))); }
static NOINLINE uint32_t op_fsin(uint32_t a, uint32_t b) { (void)b; return fbits(flt_sin(ffrom(a))); }
static NOINLINE uint32_t op_fcos(uint32_t a, uint32_t b) { (void)b; return fbits(flt_cos(ffrom(a))); }
static NOINLINE uint32_t op_fatan2(uint32_t a, uint32_t b) { return fbits(flt_atan2(ffrom(a), ffrom(b))); }
static NOINLINE uint32_t op_fasin(uint32_t a, uint32_t b) { (void)b; return fbits(flt_asin(ffrom(a))); }
/* compiler-rt's soft-float, for the cost table (and checked as correctly rounded) */
static NOINLINE uint32_t op_fadd(uint32_t a, uint32_t b) { return fbits(ffrom(a) + ffrom(b)); }
static NOINLINE uint32_t op_fmul(uint32_t a, uint32_t b) { return fbits(ffrom(a) * ffrom(b)); }
static NOINLINE uint32_t op_fdiv(uint32_t a, uint32_t b) { return fbits(ffrom(a) / ffrom(b)); }

/* Input generators: the first argument (a) and the second (b) of each function. */
static uint32_t g_log(int i) { return (i % 8 == 7) ? rnd() : rnd_log(); }  /* every 8th full range */
static uint32_t g_full(int i) { (void)i; return rnd(); }
static uint32_t g_zero(int i) { (void)i; return 0; }
static uint32_t g_angle(int i) { return (i % 2) ? rnd() : rnd_sym(411775); }  /* full range, or +-2 pi */
static uint32_t g_unit(int i) { (void)i; return rnd_sym(72090); }             /* +-1.1 */
static uint32_t g_int(int i) { (void)i; return rnd_log(); }
static uint32_t g_float(int i) { return (i % 50 == 49) ? 0x7f800000u | (rnd() & 0x80400000u) : rnd_float(100, 160); }
static uint32_t g_fpos(int i) { return (i % 20 == 19) ? (rnd() & 0x7fffffu) : (rnd_float(1, 254) & 0x7fffffffu); }
static uint32_t g_fangle(int i)
{
    /* +-8192 with 2^-10 steps, or +-2 pi with finer steps */
    int32_t k = (int32_t)(rnd() % 16777217u) - 8388608;
    return fbits((i % 2) ? (float)k * (1.0f / 1024.0f) : (float)k * 7.49014320e-7f);
}
static uint32_t g_fmid(int i) { (void)i; return rnd_float(110, 140); }
static uint32_t g_funit(int i) { (void)i; return fbits((float)(int32_t)rnd_sym(1101004) * 1e-6f); }  /* +-1.1 */

/* Edge operands of the Q16.16 functions: every pair of them is checked before the random inputs. */
static const uint32_t specials[] = {
    0x00000000u, 0x00000001u, 0xffffffffu, 0x00008000u, 0x00010000u, 0xffff0000u, 0x00018000u,
    0x0003243fu, 0xfffcdbc1u, 0x7fffffffu, 0x80000000u, 0x80000001u, 0x00ffffffu,
};
#define SPECIALS ((int)(sizeof specials / sizeof specials[0]))

/* The call goes through a volatile pointer: the compiler cannot prove it free of side effects, so
 * it cannot move the call out from between the two TIMER0 reads.  With `edges`, the first
 * SPECIALS^2 calls take every pair of edge operands (b unused for one-operand functions). */
static void run_edges(const char *name, op_t op, gen_t ga, gen_t gb, int edges)
{
    op_t volatile call = op;
    int n_edges = edges ? SPECIALS * SPECIALS : 0;
    for (int i = 0; i < n_edges + CHECK_COUNT; i++) {
        uint32_t a = i < n_edges ? specials[i / SPECIALS] : ga(i);
        uint32_t b = i < n_edges ? specials[i % SPECIALS] : gb(i);
        uint32_t start = cycles();
        uint32_t r = call(a, b);
        uint32_t spent = cycles() - start;
        hf_printf("%s %08x %08x %08x %u\n", name, (unsigned)a, (unsigned)b, (unsigned)r, (unsigned)spent);
    }
}

static void run(const char *name, op_t op, gen_t ga, gen_t gb)
{
    run_edges(name, op, ga, gb, 0);
}

static void run_fixed(const char *name, op_t op, gen_t ga, gen_t gb)
{
    run_edges(name, op, ga, gb, 1);
}

static NOINLINE uint64_t op_mul64(uint32_t a, uint32_t b) { return (uint64_t)fix16_mul64((int32_t)a, (int32_t)b); }
typedef uint64_t (*op64_t)(uint32_t a, uint32_t b);

int main(void)
{
    run("base", op_base, g_full, g_full);
    run_fixed("add", op_add, g_log, g_log);
    run_fixed("sub", op_sub, g_log, g_log);
    run_fixed("mul", op_mul, g_log, g_log);
    run_fixed("div", op_div, g_log, g_log);
    run("divdi3", op_divdi3, g_log, g_log);
    run_fixed("sqrt", op_sqrt, g_log, g_zero);
    run_fixed("sin", op_sin, g_angle, g_zero);
    run_fixed("cos", op_cos, g_angle, g_zero);
    run_fixed("atan2", op_atan2, g_log, g_log);
    run_fixed("asin", op_asin, g_unit, g_zero);
    run_fixed("from_int", op_from_int, g_int, g_zero);
    run_fixed("to_int", op_to_int, g_full, g_zero);
    run("from_float", op_from_float, g_float, g_zero);
    run_fixed("to_float", op_to_float, g_full, g_zero);
    run("fsqrt", op_fsqrt, g_fpos, g_zero);
    run("fsin", op_fsin, g_fangle, g_zero);
    run("fcos", op_fcos, g_fangle, g_zero);
    run("fatan2", op_fatan2, g_fmid, g_fmid);
    run("fasin", op_fasin, g_funit, g_zero);
    run("fadd", op_fadd, g_fmid, g_fmid);
    run("fmul", op_fmul, g_fmid, g_fmid);
    run("fdiv", op_fdiv, g_fmid, g_fmid);
    op64_t volatile mul64 = op_mul64;
    for (int i = 0; i < CHECK_COUNT; i++) {
        uint32_t a = g_log(i);
        uint32_t b = g_log(i);
        uint32_t start = cycles();
        uint64_t r = mul64(a, b);
        uint32_t spent = cycles() - start;
        hf_printf("mul64 %08x %08x %016llx %u\n", (unsigned)a, (unsigned)b, (unsigned long long)r, (unsigned)spent);
    }
    return 0;
}
