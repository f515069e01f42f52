/* estimator_task.c - sensor packet in (from the I/O tile), estimate packet out (to the position task). */
#include <string.h>

#include "estimator.h"
#include "os.h"
#include "robosoc_packets.h"
#include "robosoc_project.h"

static est_t estimator;

void estimator_task_init(void) { est_init(&estimator); }

void estimator_on_message(const os_msg_t *msg, void *arg)
{
    struct robosoc_sensor_packet in;
    struct robosoc_estimate_packet out;
    (void)arg;
    if (msg->len != sizeof in) {
        return;
    }
    memcpy(&in, msg->data, sizeof in);
    if (est_packet_step(&estimator, &in, &out) == 0) {
        os_send(ROBOSOC_MSG_ESTIMATE_TILE, ROBOSOC_MSG_ESTIMATE_PORT, &out, sizeof out);
    }
}
