/*
 * send_to.c - one best-effort task sends a LEN-byte message to tile DEST, port 1, then exits.
 */
#include "os.h"

#ifndef DEST
#define DEST 0x11
#endif
#ifndef LEN
#define LEN 10
#endif

static uint8_t data[LEN];

static void task(void *arg)
{
    (void)arg;
    os_send(DEST, 1, data, LEN);
    os_delay(2);
    os_exit(0);
}

int main(void)
{
    os_task_best_effort(task, 0, 1, 0);
    os_start();
}
