/*
 * robosoc_packets.h - the application packets' layout and units.
 *
 * GENERATED from src/robosoc/host/packets.py (python -m robosoc.host.packets): edit
 * that file, not this one.  Little-endian structs without padding; q16 fields are Q16.16
 * (int32 holding value * 65536).  On the NoC a packet's bytes are 16-bit flits in memory order.
 * The asserts make every build check the layout the Python side uses.
 */
#ifndef ROBOSOC_PACKETS_H
#define ROBOSOC_PACKETS_H

#include <stddef.h>
#include <stdint.h>

#define ROBOSOC_NOC_HEADER_FLITS 2
#define ROBOSOC_MESSAGE_HEADER_FLITS 4
#define ROBOSOC_MAX_PAYLOAD_FLITS 58
#define ROBOSOC_FLAG_ARMED 1u
#define ROBOSOC_FLAG_LOW_BATTERY 2u

/* Message ports of the flight application (kernel ports, below OS_MSG_PORTS) */
#define ROBOSOC_SENSOR_PORT 1u /* estimator tile: sensor packets, I/O tile -> estimator task */
#define ROBOSOC_ESTIMATE_PORT 2u /* PID tile: estimate packets, estimator task -> PID task */
#define ROBOSOC_PWM_PORT 3u /* I/O tile: PWM packets, PID task -> I/O tile */

/* One sensor sample, I/O tile -> estimator task (body frame FLU). */
#define ROBOSOC_SENSOR_KIND 0x5201u
#define ROBOSOC_SENSOR_BYTES 80u
#define ROBOSOC_SENSOR_FLITS 40u
struct robosoc_sensor_packet {
    uint16_t kind; /* format tag (ROBOSOC_*_KIND): a packet with another tag is malformed */
    uint16_t flags; /* bit 0 armed (ROBOSOC_FLAG_ARMED), bit 1 low battery (ROBOSOC_FLAG_LOW_BATTERY); others 0 */
    uint32_t seq; /* sample number, 0 for the first sample of a flight */
    uint32_t time_us; /* sample time since the start of the flight [us] */
    uint32_t dt_us; /* time since the previous sample (the sample period for the first) [us] */
    int32_t gyro[3]; /* body rates p, q, r [rad/s] (Q16.16) */
    int32_t accel[3]; /* specific force (at rest: +g along body up) [m/s^2] (Q16.16) */
    int32_t mag[3]; /* magnetic field [unit field] (Q16.16) */
    int32_t baro_altitude; /* barometric altitude [m] (Q16.16) */
    int32_t setpoint[4]; /* roll, pitch, yaw and height setpoints [rad, rad, rad, m] (Q16.16) */
    int32_t height_feedforward[2]; /* the height setpoint profile's rate and acceleration [m/s, m/s^2] (Q16.16) */
};
_Static_assert(sizeof(struct robosoc_sensor_packet) == 80, "sensor packet size");
_Static_assert(offsetof(struct robosoc_sensor_packet, kind) == 0, "sensor.kind offset");
_Static_assert(offsetof(struct robosoc_sensor_packet, flags) == 2, "sensor.flags offset");
_Static_assert(offsetof(struct robosoc_sensor_packet, seq) == 4, "sensor.seq offset");
_Static_assert(offsetof(struct robosoc_sensor_packet, time_us) == 8, "sensor.time_us offset");
_Static_assert(offsetof(struct robosoc_sensor_packet, dt_us) == 12, "sensor.dt_us offset");
_Static_assert(offsetof(struct robosoc_sensor_packet, gyro) == 16, "sensor.gyro offset");
_Static_assert(offsetof(struct robosoc_sensor_packet, accel) == 28, "sensor.accel offset");
_Static_assert(offsetof(struct robosoc_sensor_packet, mag) == 40, "sensor.mag offset");
_Static_assert(offsetof(struct robosoc_sensor_packet, baro_altitude) == 52, "sensor.baro_altitude offset");
_Static_assert(offsetof(struct robosoc_sensor_packet, setpoint) == 56, "sensor.setpoint offset");
_Static_assert(offsetof(struct robosoc_sensor_packet, height_feedforward) == 72, "sensor.height_feedforward offset");

/* The state estimate after one sensor sample, estimator task -> PID task. */
#define ROBOSOC_ESTIMATE_KIND 0x5202u
#define ROBOSOC_ESTIMATE_BYTES 76u
#define ROBOSOC_ESTIMATE_FLITS 38u
struct robosoc_estimate_packet {
    uint16_t kind; /* format tag (ROBOSOC_*_KIND): a packet with another tag is malformed */
    uint16_t flags; /* bit 0 armed (ROBOSOC_FLAG_ARMED), bit 1 low battery (ROBOSOC_FLAG_LOW_BATTERY); others 0 */
    uint32_t seq; /* the sensor sample's number */
    uint32_t time_us; /* the sensor sample's time [us] */
    uint32_t dt_us; /* the sensor sample's dt_us [us] */
    int32_t quaternion[4]; /* attitude w, x, y, z (body -> world) (Q16.16) */
    int32_t rate[3]; /* bias-corrected body rates p, q, r [rad/s] (Q16.16) */
    int32_t height; /* estimated height [m] (Q16.16) */
    int32_t vertical_velocity; /* estimated vertical velocity [m/s] (Q16.16) */
    int32_t setpoint[4]; /* the sensor sample's setpoints, forwarded [rad, rad, rad, m] (Q16.16) */
    int32_t height_feedforward[2]; /* the sensor sample's height_feedforward, forwarded [m/s, m/s^2] (Q16.16) */
};
_Static_assert(sizeof(struct robosoc_estimate_packet) == 76, "estimate packet size");
_Static_assert(offsetof(struct robosoc_estimate_packet, kind) == 0, "estimate.kind offset");
_Static_assert(offsetof(struct robosoc_estimate_packet, flags) == 2, "estimate.flags offset");
_Static_assert(offsetof(struct robosoc_estimate_packet, seq) == 4, "estimate.seq offset");
_Static_assert(offsetof(struct robosoc_estimate_packet, time_us) == 8, "estimate.time_us offset");
_Static_assert(offsetof(struct robosoc_estimate_packet, dt_us) == 12, "estimate.dt_us offset");
_Static_assert(offsetof(struct robosoc_estimate_packet, quaternion) == 16, "estimate.quaternion offset");
_Static_assert(offsetof(struct robosoc_estimate_packet, rate) == 32, "estimate.rate offset");
_Static_assert(offsetof(struct robosoc_estimate_packet, height) == 44, "estimate.height offset");
_Static_assert(offsetof(struct robosoc_estimate_packet, vertical_velocity) == 48, "estimate.vertical_velocity offset");
_Static_assert(offsetof(struct robosoc_estimate_packet, setpoint) == 52, "estimate.setpoint offset");
_Static_assert(offsetof(struct robosoc_estimate_packet, height_feedforward) == 68, "estimate.height_feedforward offset");

/* The motor command for one sensor sample, PID task -> I/O tile. */
#define ROBOSOC_PWM_KIND 0x5203u
#define ROBOSOC_PWM_BYTES 16u
#define ROBOSOC_PWM_FLITS 8u
struct robosoc_pwm_packet {
    uint16_t kind; /* format tag (ROBOSOC_*_KIND): a packet with another tag is malformed */
    uint16_t flags; /* bit 0 armed (ROBOSOC_FLAG_ARMED), bit 1 low battery (ROBOSOC_FLAG_LOW_BATTERY); others 0 */
    uint32_t seq; /* the sensor sample's number */
    uint16_t pwm[4]; /* motors 0-3 [PWM count (0-255)] */
};
_Static_assert(sizeof(struct robosoc_pwm_packet) == 16, "pwm packet size");
_Static_assert(offsetof(struct robosoc_pwm_packet, kind) == 0, "pwm.kind offset");
_Static_assert(offsetof(struct robosoc_pwm_packet, flags) == 2, "pwm.flags offset");
_Static_assert(offsetof(struct robosoc_pwm_packet, seq) == 4, "pwm.seq offset");
_Static_assert(offsetof(struct robosoc_pwm_packet, pwm) == 8, "pwm.pwm offset");

/* The newest position fix and the position setpoint, I/O tile -> a project's task (world frame, z up). */
#define ROBOSOC_POSITION_KIND 0x5204u
#define ROBOSOC_POSITION_BYTES 80u
#define ROBOSOC_POSITION_FLITS 40u
struct robosoc_position_packet {
    uint16_t kind; /* format tag (ROBOSOC_*_KIND): a packet with another tag is malformed */
    uint16_t flags; /* bit 0 armed (ROBOSOC_FLAG_ARMED), bit 1 low battery (ROBOSOC_FLAG_LOW_BATTERY); others 0 */
    uint32_t seq; /* the sensor sample's number (its sensor packet has the same) */
    uint32_t time_us; /* the sensor sample's time [us] */
    uint32_t fix_time_us; /* when the fix was taken (at most one fix period before time_us) [us] */
    uint32_t fix_number; /* the fix's number, 0 for the first: a new fix when it changes */
    int32_t position[3]; /* the fix: position x, y, z of the body origin [m] (Q16.16) */
    int32_t velocity[3]; /* the fix: velocity x, y, z [m/s] (Q16.16) */
    int32_t setpoint[3]; /* position setpoint x, y, z (z: the sensor packet's height setpoint) [m] (Q16.16) */
    int32_t setpoint_velocity[3]; /* the setpoint's rate (feed-forward) [m/s] (Q16.16) */
    int32_t setpoint_accel[3]; /* the setpoint's acceleration (feed-forward) [m/s^2] (Q16.16) */
};
_Static_assert(sizeof(struct robosoc_position_packet) == 80, "position packet size");
_Static_assert(offsetof(struct robosoc_position_packet, kind) == 0, "position.kind offset");
_Static_assert(offsetof(struct robosoc_position_packet, flags) == 2, "position.flags offset");
_Static_assert(offsetof(struct robosoc_position_packet, seq) == 4, "position.seq offset");
_Static_assert(offsetof(struct robosoc_position_packet, time_us) == 8, "position.time_us offset");
_Static_assert(offsetof(struct robosoc_position_packet, fix_time_us) == 12, "position.fix_time_us offset");
_Static_assert(offsetof(struct robosoc_position_packet, fix_number) == 16, "position.fix_number offset");
_Static_assert(offsetof(struct robosoc_position_packet, position) == 20, "position.position offset");
_Static_assert(offsetof(struct robosoc_position_packet, velocity) == 32, "position.velocity offset");
_Static_assert(offsetof(struct robosoc_position_packet, setpoint) == 44, "position.setpoint offset");
_Static_assert(offsetof(struct robosoc_position_packet, setpoint_velocity) == 56, "position.setpoint_velocity offset");
_Static_assert(offsetof(struct robosoc_position_packet, setpoint_accel) == 68, "position.setpoint_accel offset");

#endif /* ROBOSOC_PACKETS_H */
