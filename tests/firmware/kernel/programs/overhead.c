/*
 * overhead.c - kernel overhead measurements on a 2x2 mesh: tile A = (1,0), tile B = (0,1).
 *
 * Tile A: two best-effort tasks hand a semaphore back and forth (voluntary switch: TIMER0 before
 *   the first blocks, TIMER0 when the second has the semaphore), a sender sends SIZES to B
 *   (TIMER0 around os_send, a tick apart so that B sleeps in between, and the first four bytes
 *   of each message are the TIMER0 before the call), a periodic task of period 1 without work
 *   (its job log gives tick -> job start while the best-effort spinner holds the core), and at
 *   the end two 16-byte messages back to back.
 * Tile B: a receiver blocked in os_recv (TIMER0 when it returns); before the last two messages
 *   it spins, so they both wait, then times os_probe and os_recv of a waiting message.
 * Results: words of `results` (see the host script measure_overhead.py).
 */
#include <string.h>

#include "os.h"

#define TILE_A 0x10
#define TILE_B 0x01
#define PINGS 8
#define REPEAT 4
static const uint32_t sizes[3] = {16, 116, 1000};

volatile uint32_t results[128];
static os_sem_t to_a, to_b, pinged;
static uint8_t buf[1024];
static volatile uint32_t spins;

static void spin(uint32_t n)
{
    if (n != 0u) {
        __asm__ volatile("1: addi %0, %0, -1\n\tbnez %0, 1b" : "+r"(n));
    }
}

/* ---- tile A ---- */
static void ping(void *arg)
{
    (void)arg;
    for (uint32_t k = 0; k < PINGS; k++) {
        os_sem_post(&to_b);
        results[2 * k] = os_cycles();
        os_sem_wait(&to_a);
    }
    os_sem_post(&pinged);
}

static void pong(void *arg)
{
    (void)arg;
    for (uint32_t k = 0; k < PINGS; k++) {
        os_sem_wait(&to_b);
        results[2 * k + 1] = os_cycles();
        os_sem_post(&to_a);
    }
}

static void sender(void *arg)
{
    (void)arg;
    os_sem_wait(&pinged);
    uint32_t r = 16;
    for (uint32_t s = 0; s < 3; s++) {
        for (uint32_t k = 0; k < REPEAT; k++) {
            os_delay(1);
            uint32_t t0 = os_cycles();
            memcpy(buf, &t0, 4);
            os_send(TILE_B, 1, buf, sizes[s]);
            results[r++] = t0;
            results[r++] = os_cycles();
        }
    }
    os_delay(1);
    os_send(TILE_B, 1, buf, 16);
    os_send(TILE_B, 1, buf, 16);
    os_delay(8);
    os_exit(0);
}

static void tick_job(void *arg) { (void)arg; }

static void spinner(void *arg)
{
    (void)arg;
    for (;;) {
        spins++;
    }
}

/* ---- tile B ---- */
static void receiver(void *arg)
{
    (void)arg;
    uint32_t r = 64;
    for (uint32_t k = 0; k < 3 * REPEAT; k++) {
        int32_t n = os_recv(1, buf, sizeof buf, 0);
        uint32_t t = os_cycles();
        uint32_t sent_at;
        memcpy(&sent_at, buf, 4);
        results[r++] = (uint32_t)n;
        results[r++] = sent_at;
        results[r++] = t;
    }
    spin(100000); /* the last two messages arrive meanwhile */
    for (uint32_t k = 0; k < 2; k++) {
        uint32_t t0 = os_cycles();
        int32_t p = os_probe(1);
        uint32_t t1 = os_cycles();
        int32_t n = os_recv(1, buf, sizeof buf, 0);
        uint32_t t2 = os_cycles();
        results[r++] = (uint32_t)(p == 16 && n == 16);
        results[r++] = t1 - t0;
        results[r++] = t2 - t1;
    }
    os_delay(2);
    os_exit(0);
}

int main(void)
{
    if (os_tile() == TILE_A) {
        os_sem_init(&to_a, 0);
        os_sem_init(&to_b, 0);
        os_sem_init(&pinged, 0);
        os_task_periodic(tick_job, 0, 1, 1, 1, 0);
        os_task_best_effort(ping, 0, 3, 0);
        os_task_best_effort(pong, 0, 3, 0);
        os_task_best_effort(sender, 0, 2, 0);
        os_task_best_effort(spinner, 0, 1, 0);
    } else {
        os_task_best_effort(receiver, 0, 2, 0);
    }
    os_start();
}
