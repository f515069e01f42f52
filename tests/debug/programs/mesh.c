/* The MPSoC debugging test program (2x2 mesh): tiles (1,0) and (0,1) play ping-pong over the
 * network, tile (1,1) computes alone; each calls next_value, which writes the watched global. */
#include "hf_noc.h"
#include "hf_print.h"

static uint16_t tx[8], rx[8];
volatile int counter;
int total = 5;

int __attribute__((noinline)) next_value(int v) {
    counter = v * 3 + 1;
    return counter & 0x3ff;
}

int main(void) {
    uint32_t me = hf_tile(), a = 0x10, b = 0x01;
    if (me != a && me != b) {
        int s = 0;
        for (int i = 0; i < 50; i++) s = next_value(s);
        hf_printf("alone %d\n", s);
        return 0;
    }
    uint16_t value = 0;
    for (int round = 0; round < 4; round++) {
        if (me == a) {
            uint16_t p[1] = {value};
            hf_ni_send_to(b, p, 1, tx);
            hf_ni_recv_wait(rx);
            value = (uint16_t)next_value(rx[2]);
        } else {
            hf_ni_recv_wait(rx);
            uint16_t p[1] = {(uint16_t)(rx[2] + 1)};
            hf_ni_send_to(a, p, 1, tx);
        }
    }
    total = value;
    hf_printf("tile %x value %d\n", me, value);
    return 0;
}
