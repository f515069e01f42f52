/*
 * core_peers.h - the addresses of every core tile of the mesh except this one (the I/O tile is not
 * a core), for the traffic test programs: an address is x << 4 | y, as the NI's header flit has it.
 */
#ifndef CORE_PEERS_H
#define CORE_PEERS_H

#include "hf_noc.h"

/* Fills peers[] (room for 256) and returns how many there are. */
static inline uint32_t core_peers(uint32_t *peers)
{
    uint32_t me = hf_tile();
    uint32_t mesh = HF_REG32(HF_NI_MESH);
    uint32_t io = hf_io_tile();
    uint32_t np = 0;
    for (uint32_t y = 0; y < (mesh >> 8); y++) {
        for (uint32_t x = 0; x < (mesh & 0xffu); x++) {
            uint32_t a = (x << 4) | y;
            if (a != io && a != me) {
                peers[np++] = a;
            }
        }
    }
    return np;
}

#endif
