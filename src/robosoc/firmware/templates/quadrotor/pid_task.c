/* pid_task.c - estimate packet in (from the estimator task), PWM packet out (to the I/O tile). */
#include <string.h>

#include "os.h"
#include "pid.h"
#include "robosoc_packets.h"
#include "robosoc_project.h"

static pid_controller_t pid;

void pid_task_init(void) { pid_init(&pid); }

void pid_on_message(const os_msg_t *msg, void *arg)
{
    struct robosoc_estimate_packet in;
    struct robosoc_pwm_packet out;
    (void)arg;
    if (msg->len != sizeof in) {
        return;
    }
    memcpy(&in, msg->data, sizeof in);
    if (pid_packet_step(&pid, &in, &out) == 0) {
        os_send(ROBOSOC_MSG_PWM_TILE, ROBOSOC_MSG_PWM_PORT, &out, sizeof out);
    }
}
