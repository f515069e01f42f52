/* attitude_task.c - command in (an estimate packet whose roll and pitch setpoints the position task
 * set: robosoc.toml declares it so), PWM packet out (to the I/O tile): robosoc's PID loops and mixer
 * (pid.h). */
#include <string.h>

#include "os.h"
#include "pid.h"
#include "robosoc_project.h"

static pid_controller_t pid;

void attitude_task_init(void) { pid_init(&pid); }

void attitude_on_message(const os_msg_t *msg, void *arg)
{
    robosoc_msg_command_t in;
    robosoc_msg_pwm_t out;
    (void)arg;
    if (msg->len != ROBOSOC_MSG_COMMAND_BYTES) {
        return;
    }
    memcpy(&in, msg->data, sizeof in);
    if (pid_packet_step(&pid, &in, &out) == 0) {
        os_send(ROBOSOC_MSG_PWM_TILE, ROBOSOC_MSG_PWM_PORT, &out, ROBOSOC_MSG_PWM_BYTES);
    }
}
