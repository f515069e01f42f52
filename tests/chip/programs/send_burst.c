/*
 * send_burst.c - one core sends 20 three-flit packets to the I/O tile back to back, polling
 * NI_STATUS for its send memory between them.  With router buffers shallower than a packet the
 * end of each injection depends on the network, which the chip loop must have simulated up to
 * the poll's cycle: the quanta-vs-lockstep test uses it.
 */
#include "hf_noc.h"
static uint16_t tx[8];
int main(void)
{
    uint32_t io = hf_io_tile();
    for (int i = 0; i < 20; i++) {
        tx[0] = (uint16_t)io;
        tx[1] = 1;
        tx[2] = (uint16_t)i;
        hf_ni_send(tx, 3);
    }
    while (HF_REG32(HF_NI_STATUS) & HF_NI_SEND_BUSY) {
    }
    return 0;
}
