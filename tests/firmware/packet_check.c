/*
 * packet_check.c - fills each application packet field by field, by name, and prints its flits:
 *   <name> <flit0> <flit1> ...   (hex)
 * test_packets.py decodes the flits with robosoc.firmware.packets and expects the values below.
 * Q16.16 fields hold (field number + 1) * 1.25 + element / 4 (negated for odd elements).
 */
#include <stdint.h>
#include <string.h>

#include "hf_print.h"
#include "robosoc_packets.h"

static int32_t value(int field, int element)
{
    int32_t v = (field + 1) * 81920 + element * 16384; /* (field + 1) * 1.25 + element / 4 in Q16.16 */
    return (element & 1) ? -v : v;
}

static void put_flits(const char *name, const void *packet, uint32_t flits)
{
    uint16_t buffer[ROBOSOC_MAX_PAYLOAD_FLITS];
    memcpy(buffer, packet, flits * 2u);
    hf_puts(name);
    for (uint32_t i = 0; i < flits; i++) {
        hf_printf(" %04x", (unsigned)buffer[i]);
    }
    hf_putchar('\n');
}

int main(void)
{
    struct robosoc_sensor_packet s;
    memset(&s, 0, sizeof s);
    s.kind = ROBOSOC_SENSOR_KIND;
    s.flags = ROBOSOC_FLAG_ARMED;
    s.seq = 123456789u;
    s.time_us = 4000000000u;
    s.dt_us = 10000u;
    for (int i = 0; i < 3; i++) {
        s.gyro[i] = value(0, i);
        s.accel[i] = value(1, i);
        s.mag[i] = value(2, i);
    }
    s.baro_altitude = value(3, 0);
    for (int i = 0; i < 4; i++) {
        s.setpoint[i] = value(4, i);
    }
    for (int i = 0; i < 2; i++) {
        s.height_feedforward[i] = value(5, i);
    }
    put_flits("sensor", &s, ROBOSOC_SENSOR_FLITS);

    struct robosoc_estimate_packet e;
    memset(&e, 0, sizeof e);
    e.kind = ROBOSOC_ESTIMATE_KIND;
    e.flags = ROBOSOC_FLAG_ARMED;
    e.seq = 7u;
    e.time_us = 70000u;
    e.dt_us = 10000u;
    for (int i = 0; i < 4; i++) {
        e.quaternion[i] = value(0, i);
        e.setpoint[i] = value(4, i);
    }
    for (int i = 0; i < 3; i++) {
        e.rate[i] = value(1, i);
    }
    for (int i = 0; i < 2; i++) {
        e.height_feedforward[i] = value(5, i);
    }
    e.height = value(2, 0);
    e.vertical_velocity = value(3, 0);
    put_flits("estimate", &e, ROBOSOC_ESTIMATE_FLITS);

    struct robosoc_pwm_packet p;
    memset(&p, 0, sizeof p);
    p.kind = ROBOSOC_PWM_KIND;
    p.flags = 0;
    p.seq = 65537u;
    for (int i = 0; i < 4; i++) {
        p.pwm[i] = (uint16_t)(100 + 50 * i);
    }
    put_flits("pwm", &p, ROBOSOC_PWM_FLITS);

    struct robosoc_position_packet f;
    memset(&f, 0, sizeof f);
    f.kind = ROBOSOC_POSITION_KIND;
    f.flags = ROBOSOC_FLAG_ARMED;
    f.seq = 99u;
    f.time_us = 990000u;
    f.fix_time_us = 980000u;
    f.fix_number = 49u;
    for (int i = 0; i < 3; i++) {
        f.position[i] = value(0, i);
        f.velocity[i] = value(1, i);
        f.setpoint[i] = value(2, i);
        f.setpoint_velocity[i] = value(3, i);
        f.setpoint_accel[i] = value(4, i);
    }
    put_flits("position", &f, ROBOSOC_POSITION_FLITS);
    return 0;
}
