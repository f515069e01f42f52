/*
 * echo.c - receive messages from the I/O tile and answer each one.
 *
 * EVENT undefined: a best-effort task blocks in os_recv(RX_PORT) for EXPECT messages.
 * EVENT defined: an event-triggered task bound to RX_PORT (relative deadline DEADLINE ticks)
 * runs one job per message; the first data byte times 1000 is a busy loop of 4-cycle iterations.
 * Every message is answered on the I/O tile's port TX_PORT with
 *     arrival (4 bytes), TIMER0 when the task had the message (4), probe result before (4),
 *     then the message's data reversed.
 * After EXPECT answers a best-effort task waits two ticks (the last answer must reach the I/O
 * tile before the run ends) and exits with 0.
 */
#include <string.h>

#include "os.h"

#ifndef RX_PORT
#define RX_PORT 3
#endif
#ifndef TX_PORT
#define TX_PORT 5
#endif
#ifndef EXPECT
#define EXPECT 1
#endif
#ifndef DEADLINE
#define DEADLINE 2
#endif
#define MAX 300

static os_sem_t done;
static uint8_t out[MAX + 12];

static __attribute__((unused)) void spin(uint32_t n)
{
    if (n != 0u) {
        __asm__ volatile("1: addi %0, %0, -1\n\tbnez %0, 1b" : "+r"(n));
    }
}

static void answer(uint32_t arrival, uint32_t had_it, int32_t probe, const uint8_t *data, uint32_t len)
{
    memcpy(out, &arrival, 4);
    memcpy(out + 4, &had_it, 4);
    memcpy(out + 8, &probe, 4);
    for (uint32_t k = 0; k < len; k++) {
        out[12 + k] = data[len - 1 - k];
    }
    os_send(os_io_tile(), TX_PORT, out, len + 12);
}

#ifdef EVENT
static uint32_t jobs;
static void on_message(const os_msg_t *msg, void *arg)
{
    (void)arg;
    uint32_t had_it = os_cycles();
    uint32_t units = msg->len ? msg->data[0] : 0u;
    for (uint32_t u = 0; u < units; u++) {
        spin(1000);
    }
    answer(msg->arrival, had_it, 0, msg->data, msg->len);
    if (++jobs == EXPECT) {
        os_sem_post(&done);
    }
}
#else
static uint8_t in[MAX];
static void receiver(void *arg)
{
    (void)arg;
    for (uint32_t n = 0; n < EXPECT; n++) {
        int32_t probe = os_probe(RX_PORT);
        os_msg_t info;
        int32_t len = os_recv(RX_PORT, in, MAX, &info);
        uint32_t had_it = os_cycles();
        answer(info.arrival, had_it, probe, in, (uint32_t)len < MAX ? (uint32_t)len : MAX);
    }
    os_sem_post(&done);
}
#endif

static void finisher(void *arg)
{
    (void)arg;
    os_sem_wait(&done);
    os_delay(2);
    os_exit(0);
}

int main(void)
{
    os_sem_init(&done, 0);
#ifdef EVENT
    os_task_event(on_message, 0, RX_PORT, DEADLINE, 0);
#else
    os_task_best_effort(receiver, 0, 2, 0);
#endif
    os_task_best_effort(finisher, 0, 1, 0);
    os_start();
}
