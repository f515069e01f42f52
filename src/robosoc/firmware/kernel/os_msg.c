/*
 * os_msg.c - messages between (tile, port) addresses over the NoC.
 *
 * A message is split into packets of at most OS_MSG_PACKET_FLITS flits, each carrying the
 * 6-flit header of os.h; the receiving kernel reassembles them in a slot (OS_MSG_SLOTS slots
 * for all ports together) and hands the complete message to the task that waits on its port or
 * releases the event task bound to it.  The whole message is sent inside one kernel section, and
 * packets from one tile to another travel one XY path in order, so the packets of a message
 * arrive one after the other from their source: reassembly needs one context per source tile.
 *
 * A received packet whose header does not fit (too short, no such port, a fragment out of turn,
 * more data flits than the length leaves) is counted in os_stats.pkt_malformed and dropped; so is,
 * once, a message cut short (its source starts another one before it is complete).  A well-formed
 * message the tile cannot hold is counted in os_stats.msg_dropped.
 */
#include "os_internal.h"

enum { OS_SLOT_FREE, OS_SLOT_FILLING, OS_SLOT_READY, OS_SLOT_TAKEN };

typedef struct {
    os_msg_t msg; /* what os_recv and event jobs see; msg.data points at payload */
    uint8_t state;
    uint32_t order; /* completion order, to hand messages of a port out first come first served */
    uint32_t payload[(OS_MSG_MAX_BYTES + 3) / 4];
} os_slot_t;

typedef struct {
    uint8_t active;
    uint8_t src_tile;
    uint8_t port;
    uint8_t next_frag; /* fragment index expected next (modulo 256) */
    uint16_t seq;
    int16_t slot; /* -1: the message is being discarded (no room), its fragments are swallowed */
    uint32_t len;
    uint32_t filled;
} os_rx_ctx_t;

static os_slot_t os_slots[OS_MSG_SLOTS];
static os_rx_ctx_t os_rx_ctx[OS_MSG_RX_CONTEXTS];
static uint16_t os_rx_buf[HF_NI_MAX_FLITS] __attribute__((aligned(4)));
static uint16_t os_tx_buf[HF_NI_MAX_FLITS] __attribute__((aligned(4)));
static uint16_t os_tx_seq;
static uint32_t os_msg_order;

/* Word copy when both sides are aligned (headers are 12 bytes, slots and buffers aligned). */
static void os_copy(void *dst, const void *src, uint32_t n)
{
    uint8_t *d = dst;
    const uint8_t *s = src;
    if ((((uintptr_t)d | (uintptr_t)s) & 3u) == 0u) {
        for (; n >= 4u; n -= 4u, d += 4, s += 4) {
            *(uint32_t *)d = *(const uint32_t *)s;
        }
    }
    for (; n != 0u; n--) {
        *d++ = *s++;
    }
}

/* ---- Slots -------------------------------------------------------------------------------- */

static int os_slot_alloc(uint32_t port, uint32_t src_tile, uint32_t src_port, uint32_t len)
{
    for (uint32_t i = 0; i < OS_MSG_SLOTS; i++) {
        os_slot_t *s = &os_slots[i];
        if (s->state == OS_SLOT_FREE) {
            s->state = OS_SLOT_FILLING;
            s->msg.port = port;
            s->msg.src_tile = src_tile;
            s->msg.src_port = src_port;
            s->msg.len = len;
            s->msg.data = (const uint8_t *)s->payload;
            return (int)i;
        }
    }
    return -1;
}

void os_msg_slot_free(int slot)
{
    if (slot >= 0) {
        os_slots[slot].state = OS_SLOT_FREE;
    }
}

const os_msg_t *os_msg_slot_view(int slot) { return &os_slots[slot].msg; }
void os_msg_take(int slot) { os_slots[slot].state = OS_SLOT_TAKEN; }
uint32_t os_msg_arrival(int slot) { return os_slots[slot].msg.arrival; }

int os_msg_oldest(uint32_t port)
{
    int best = -1;
    for (uint32_t i = 0; i < OS_MSG_SLOTS; i++) {
        const os_slot_t *s = &os_slots[i];
        if (s->state == OS_SLOT_READY && s->msg.port == port &&
            (best < 0 || (int32_t)(s->order - os_slots[best].order) < 0)) {
            best = (int)i;
        }
    }
    return best;
}

static void os_slot_complete(int slot, uint32_t cycle)
{
    os_slot_t *s = &os_slots[slot];
    s->state = OS_SLOT_READY;
    s->order = os_msg_order++;
    s->msg.arrival = cycle;
    os_stats.msg_received++;
    os_sched_message(s->msg.port, slot);
}

/* ---- Receiving ---------------------------------------------------------------------------- */

static os_rx_ctx_t *os_rx_find(uint32_t src_tile)
{
    for (uint32_t i = 0; i < OS_MSG_RX_CONTEXTS; i++) {
        if (os_rx_ctx[i].active && os_rx_ctx[i].src_tile == src_tile) {
            return &os_rx_ctx[i];
        }
    }
    return 0;
}

static os_rx_ctx_t *os_rx_new(void)
{
    for (uint32_t i = 0; i < OS_MSG_RX_CONTEXTS; i++) {
        if (!os_rx_ctx[i].active) {
            return &os_rx_ctx[i];
        }
    }
    return 0;
}

static void os_rx_abort(os_rx_ctx_t *c)
{
    os_msg_slot_free(c->slot);
    c->active = 0;
}

/*
 * Data bytes a packet with `data_flits` flits carries when `remaining` bytes of its message are
 * still due, or -1 when the count does not fit: a packet that ends the message has exactly
 * ceil(remaining / 2) data flits, any other at least one (and fewer than that).
 */
static int32_t os_rx_take(uint32_t data_flits, uint32_t remaining)
{
    uint32_t bytes = 2u * data_flits;
    if (bytes >= remaining) {
        return data_flits == (remaining + 1u) / 2u ? (int32_t)remaining : -1;
    }
    return data_flits != 0u ? (int32_t)bytes : -1;
}

static void os_rx_packet(uint32_t cycle)
{
    const uint16_t *p = os_rx_buf;
    uint32_t n = port_ni_recv(os_rx_buf);
    os_stats.pkt_received++;
    if (n < OS_MSG_HEADER_FLITS || n > HF_NI_MAX_FLITS || (p[3] >> 8) >= OS_MSG_PORTS) {
        os_stats.pkt_malformed++;
        return;
    }
    uint32_t src_tile = p[2] >> 8;
    uint32_t src_port = p[2] & 0xffu;
    uint32_t port = p[3] >> 8;
    uint32_t frag = p[3] & 0xffu;
    uint32_t len = p[4];
    uint32_t seq = p[5];
    const uint8_t *data = (const uint8_t *)&p[OS_MSG_HEADER_FLITS];
    os_rx_ctx_t *c = os_rx_find(src_tile);

    if (frag == 0u) {
        if (c != 0) { /* the source's previous message stopped short: its packets were malformed */
            os_rx_abort(c);
            os_stats.pkt_malformed++;
        }
        int32_t take = os_rx_take(n - OS_MSG_HEADER_FLITS, len);
        if (take < 0) {
            os_stats.pkt_malformed++;
            return;
        }
        int slot = len <= OS_MSG_MAX_BYTES ? os_slot_alloc(port, src_tile, src_port, len) : -1;
        if (slot < 0) {
            os_stats.msg_dropped++;
        } else {
            os_copy(os_slots[slot].payload, data, (uint32_t)take);
        }
        if ((uint32_t)take == len) {
            if (slot >= 0) {
                os_slot_complete(slot, cycle);
            }
            return;
        }
        c = os_rx_new();
        if (c == 0) { /* no context to follow it: drop it now, its next packets count as malformed */
            if (slot >= 0) {
                os_msg_slot_free(slot);
                os_stats.msg_dropped++;
            }
            return;
        }
        c->active = 1;
        c->src_tile = (uint8_t)src_tile;
        c->port = (uint8_t)port;
        c->next_frag = 1;
        c->seq = (uint16_t)seq;
        c->slot = (int16_t)slot;
        c->len = len;
        c->filled = (uint32_t)take;
        return;
    }

    if (c == 0 || c->seq != seq || c->port != port || c->len != len || c->next_frag != frag) {
        if (c != 0) {
            os_rx_abort(c);
        }
        os_stats.pkt_malformed++;
        return;
    }
    int32_t take = os_rx_take(n - OS_MSG_HEADER_FLITS, c->len - c->filled);
    if (take < 0) {
        os_rx_abort(c);
        os_stats.pkt_malformed++;
        return;
    }
    if (c->slot >= 0) {
        os_copy((uint8_t *)os_slots[c->slot].payload + c->filled, data, (uint32_t)take);
    }
    c->filled += (uint32_t)take;
    c->next_frag++;
    if (c->filled == c->len) {
        c->active = 0;
        if (c->slot >= 0) {
            os_slot_complete(c->slot, cycle);
        }
    }
}

void os_msg_receive_all(uint32_t cycle)
{
    while (port_ni_packet_waiting()) {
        os_rx_packet(cycle);
    }
}

/* ---- Sending ------------------------------------------------------------------------------ */

/* Wait for the NI's send memory, taking packets meanwhile: two tiles sending to each other
 * would otherwise wait for ever, each send memory stuck behind the other's full receive one. */
static void os_wait_send_free(void)
{
    while (port_ni_send_busy()) {
        if (port_ni_packet_waiting()) {
            os_rx_packet(port_cycles());
        }
    }
}

int32_t os_send(uint32_t tile, uint32_t port, const void *data, uint32_t len)
{
    if (port > 255u || tile > 255u || (tile >> 4) >= port_mesh_width() || (tile & 15u) >= port_mesh_height()) {
        return OS_E_INVAL;
    }
    if (len > 65535u) {
        return OS_E_TOOBIG;
    }
    uint32_t state = os_enter();
    uint32_t me = port_tile();
    uint32_t src_port = os_current->id;
    uint32_t received = os_stats.msg_received;
    int32_t result = (int32_t)len;
    if (tile == me) { /* the NI cannot send to its own tile: deliver here */
        int slot = -1;
        if (port >= OS_MSG_PORTS) {
            result = OS_E_INVAL;
        } else if (len > OS_MSG_MAX_BYTES) {
            result = OS_E_TOOBIG;
        } else if ((slot = os_slot_alloc(port, me, src_port, len)) < 0) {
            result = OS_E_FULL;
        } else {
            os_copy(os_slots[slot].payload, data, len);
            os_stats.msg_sent++;
            os_slot_complete(slot, port_cycles());
        }
    } else {
        uint16_t *b = os_tx_buf;
        const uint8_t *src = data;
        uint32_t seq = ++os_tx_seq;
        uint32_t sent = 0;
        uint32_t frag = 0;
        do {
            uint32_t chunk = len - sent;
            if (chunk > OS_MSG_DATA_BYTES_PER_PACKET) {
                chunk = OS_MSG_DATA_BYTES_PER_PACKET;
            }
            uint32_t flits = OS_MSG_HEADER_FLITS + (chunk + 1u) / 2u;
            b[0] = (uint16_t)tile;
            b[1] = (uint16_t)(flits - 2u);
            b[2] = (uint16_t)((me << 8) | src_port);
            b[3] = (uint16_t)((port << 8) | (frag & 0xffu));
            b[4] = (uint16_t)len;
            b[5] = (uint16_t)seq;
            if (chunk & 1u) {
                b[flits - 1u] = 0; /* the padding byte of an odd length */
            }
            os_copy(&b[OS_MSG_HEADER_FLITS], src + sent, chunk);
            os_wait_send_free();
            port_ni_send(b, flits);
            os_stats.pkt_sent++;
            sent += chunk;
            frag++;
        } while (sent < len);
        os_stats.msg_sent++;
    }
    if (os_stats.msg_received != received) { /* a local message, or one completed while waiting */
        os_reschedule();
    }
    os_leave(state);
    return result;
}

int32_t os_recv(uint32_t port, void *buf, uint32_t size, os_msg_t *info)
{
    if (port >= OS_MSG_PORTS) {
        return OS_E_INVAL;
    }
    uint32_t state = os_enter();
    int slot;
    while ((slot = os_msg_oldest(port)) < 0) {
        os_block(OS_WAIT_RECV, (const void *)(uintptr_t)(port + 1u));
    }
    os_slot_t *s = &os_slots[slot];
    uint32_t len = s->msg.len;
    os_copy(buf, s->payload, size < len ? size : len);
    if (info != 0) {
        *info = s->msg;
        info->data = 0;
    }
    os_msg_slot_free(slot);
    os_leave(state);
    return (int32_t)len;
}

int32_t os_probe(uint32_t port)
{
    if (port >= OS_MSG_PORTS) {
        return OS_E_INVAL;
    }
    uint32_t state = os_enter();
    int slot = os_msg_oldest(port);
    int32_t result = slot < 0 ? OS_E_EMPTY : (int32_t)os_slots[slot].msg.len;
    os_leave(state);
    return result;
}

uint32_t os_tile(void) { return port_tile(); }
uint32_t os_io_tile(void) { return port_io_tile(); }
