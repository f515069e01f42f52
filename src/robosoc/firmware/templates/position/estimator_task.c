/* estimator_task.c - sensor packet in (from the I/O tile), estimate packet out (to the position task).
 * The messages' types and sizes are robosoc_project.h's, from robosoc.toml's [[messages]]. */
#include <string.h>

#include "estimator.h"
#include "os.h"
#include "robosoc_project.h"

static est_t estimator;

void estimator_task_init(void) { est_init(&estimator); }

void estimator_on_message(const os_msg_t *msg, void *arg)
{
    robosoc_msg_sensor_t in;
    robosoc_msg_estimate_t out;
    (void)arg;
    if (msg->len != ROBOSOC_MSG_SENSOR_BYTES) {
        return;
    }
    memcpy(&in, msg->data, sizeof in);
    if (est_packet_step(&estimator, &in, &out) == 0) {
        os_send(ROBOSOC_MSG_ESTIMATE_TILE, ROBOSOC_MSG_ESTIMATE_PORT, &out, ROBOSOC_MSG_ESTIMATE_BYTES);
    }
}
