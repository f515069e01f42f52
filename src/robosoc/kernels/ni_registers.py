"""Register map of an MPSoC tile's network interface (word accesses only).

This file is the one place these offsets are written; the chip loop
(:mod:`robosoc.kernels.chip`) implements them and ``firmware/include/hf_noc.h`` mirrors them for
C (a test checks that the two agree).

======  ===========  ==========================================================================
offset  register     meaning
======  ===========  ==========================================================================
0x00    NI_STATUS    read: bit 0 the send memory is busy (DMA or injection), bit 1 a packet waits
0x04    SEND_ADDR    main-memory address of the packet to send (flits are 16-bit, little endian)
0x08    SEND_SIZE    flits to send, header included (3..64)
0x0c    NI_CMD       write 1: SEND (DMA copy, core stalled 1 cycle per flit, then injection);
                     write 2: RECV (DMA copy of the waiting packet to RECV_ADDR, core stalled
                     1 cycle per flit; the receive memory is free afterwards)
0x10    RECV_ADDR    main-memory address the next RECV copies to
0x14    RECV_SIZE    read: flits of the waiting packet (0 if none)
0x18    NI_TILE      read: this tile's NoC address (x << 4) | y
0x1c    NI_MESH      read: width | height << 8
0x20    TASK_ID      read/write: the running task (0..15); counters are attributed per task
0x24    SLEEP        write: the core stops until its interrupt controller raises a request
0x28    IO_TILE      read: the NoC address of the I/O tile
======  ===========  ==========================================================================
"""

NI_BASE = 0xE1040000
NI_END = NI_BASE + 0x40

NI_STATUS = 0x00
SEND_ADDR = 0x04
SEND_SIZE = 0x08
NI_CMD = 0x0C
RECV_ADDR = 0x10
RECV_SIZE = 0x14
NI_TILE = 0x18
NI_MESH = 0x1C
TASK_ID = 0x20
SLEEP = 0x24
IO_TILE = 0x28

READ_ONLY = (NI_STATUS, RECV_SIZE, NI_TILE, NI_MESH, IO_TILE)

STATUS_SEND_BUSY = 1
STATUS_PACKET_WAITING = 2
CMD_SEND = 1
CMD_RECV = 2
NTASKS = 16  # TASK_ID values 0..15
