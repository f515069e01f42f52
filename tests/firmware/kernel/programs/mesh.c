/*
 * mesh.c - ring traffic between every core tile of the mesh (all of them run this program).
 *
 * Core tiles, in index order (y * width + x), form a ring.  Each sends NMSG messages to the next
 * one on port 1: message k has length len_k (see next_len) and bytes 0..1 = k, byte i >= 2 =
 * (seed + k + i) mod 256 with seed = the sender's address; it receives as many from the previous
 * one and checks source, order, length and content.  Each tile also sends "self" to itself on
 * port 2, and tile BIG_FROM sends BIG bytes (byte i = i mod 251) to the I/O tile on port 4.  At the
 * end each tile reports four words to the I/O tile on port 3: its address, messages received in
 * order and intact, errors, bytes received.  Receiving has priority over sending (best-effort
 * priorities 2 and 1), so the receive slots drain while the sender waits for the network.
 */
#include <string.h>

#include "hf_noc.h"
#include "os.h"

#ifndef NMSG
#define NMSG 6
#endif
#ifndef MAXLEN
#define MAXLEN 900
#endif
#ifndef BIG
#define BIG 2000
#endif
#ifndef BIG_FROM
#define BIG_FROM 0x22
#endif

static uint32_t ring[16], nring, me, next, prev;
static uint8_t tx[MAXLEN], rx[MAXLEN + 16], expect[MAXLEN], big[BIG];
static os_sem_t sent;

/* lengths 2..MAXLEN, additions only (no multiply or divide in the tasks) */
static uint32_t first_len(uint32_t seed) { return 2u + (seed & 255u); }
static uint32_t next_len(uint32_t len)
{
    len += 151u;
    if (len > MAXLEN) { /* one subtraction: 151 < MAXLEN - 1 */
        len -= MAXLEN - 1u;
    }
    return len;
}

static void fill(uint8_t *buf, uint32_t len, uint32_t seed, uint32_t k)
{
    buf[0] = (uint8_t)k;
    buf[1] = (uint8_t)(k >> 8);
    for (uint32_t i = 2; i < len; i++) {
        buf[i] = (uint8_t)(seed + k + i);
    }
}

static void sender(void *arg)
{
    (void)arg;
    uint32_t len = first_len(me);
    for (uint32_t k = 0; k < NMSG; k++) {
        fill(tx, len, me, k);
        os_send(next, 1, tx, len);
        len = next_len(len);
    }
    os_send(me, 2, "self", 4);
    if (me == BIG_FROM) {
        for (uint32_t i = 0, v = 0; i < BIG; i++, v = v == 250u ? 0u : v + 1u) {
            big[i] = (uint8_t)v;
        }
        os_send(os_io_tile(), 4, big, BIG);
    }
    os_sem_post(&sent);
}

static void receiver(void *arg)
{
    (void)arg;
    uint32_t good = 0, errors = 0, bytes = 0;
    uint32_t len = first_len(prev);
    for (uint32_t k = 0; k < NMSG; k++) {
        os_msg_t info;
        int32_t n = os_recv(1, rx, sizeof rx, &info);
        fill(expect, len, prev, k);
        if (n == (int32_t)len && info.src_tile == prev && info.port == 1u && memcmp(rx, expect, len) == 0) {
            good++;
        } else {
            errors++;
        }
        bytes += (uint32_t)n;
        len = next_len(len);
    }
    if (os_recv(2, rx, sizeof rx, 0) != 4 || memcmp(rx, "self", 4) != 0) {
        errors++;
    }
    uint32_t report[4] = {me, good, errors, bytes};
    os_send(os_io_tile(), 3, report, sizeof report);
    os_sem_wait(&sent);
    os_delay(2); /* the last packets must reach the I/O tile before the run ends */
    os_exit(0);
}

int main(void)
{
    uint32_t mesh_w = HF_REG32(HF_NI_MESH) & 0xffu, mesh_h = HF_REG32(HF_NI_MESH) >> 8;
    me = os_tile();
    for (uint32_t y = 0; y < mesh_h; y++) {
        for (uint32_t x = 0; x < mesh_w; x++) {
            uint32_t a = OS_TILE(x, y);
            if (a != os_io_tile()) {
                ring[nring++] = a;
            }
        }
    }
    for (uint32_t i = 0; i < nring; i++) {
        if (ring[i] == me) {
            next = ring[i + 1u == nring ? 0u : i + 1u];
            prev = ring[i == 0u ? nring - 1u : i - 1u];
        }
    }
    os_sem_init(&sent, 0);
    os_task_best_effort(receiver, 0, 2, 0);
    os_task_best_effort(sender, 0, 1, 0);
    os_start();
}
