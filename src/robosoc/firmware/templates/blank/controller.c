/*
 * controller.c - one task that flies the quadrotor: each sensor packet from the I/O tile goes
 * through the estimator (calibration while disarmed, attitude EKF, altitude filter) and the PID
 * loops and mixer, and the PWM command goes back to the I/O tile with the packet's sequence number.
 *
 * The generated robosoc_project.h has, for each message of robosoc.toml, its tile and port
 * (ROBOSOC_MSG_<NAME>_TILE, _PORT), its type robosoc_msg_<name>_t and its size _BYTES (the packet
 * layouts are in robosoc_packets.h).  Change the control law here, or split it into tasks on other
 * tiles in robosoc.toml (a message between them may declare its own fields).
 */
#include <stdint.h>
#include <string.h>

#include "estimator.h"
#include "os.h"
#include "pid.h"
#include "robosoc_packets.h"
#include "robosoc_project.h"

static est_t estimator;
static pid_controller_t pid;

void controller_init(void)
{
    est_init(&estimator);
    pid_init(&pid);
}

void controller_on_message(const os_msg_t *msg, void *arg)
{
    robosoc_msg_sensor_t in;
    struct robosoc_estimate_packet estimate;
    robosoc_msg_pwm_t out;
    (void)arg;
    if (msg->len != ROBOSOC_MSG_SENSOR_BYTES) {
        return; /* not a sensor packet */
    }
    memcpy(&in, msg->data, sizeof in); /* the kernel's buffer need not be aligned for the struct */
    if (est_packet_step(&estimator, &in, &estimate) != 0 || pid_packet_step(&pid, &estimate, &out) != 0) {
        return;
    }
    os_send(ROBOSOC_MSG_PWM_TILE, ROBOSOC_MSG_PWM_PORT, &out, ROBOSOC_MSG_PWM_BYTES);
}
