/*
 * flight_app.c - the seed's case study as a firmware project: the estimator task and the PID task
 * under the kernel, each on its tile (robosoc.toml), messages over the NoC:
 *
 *   I/O tile --sensor--> estimator task --estimate--> PID task --pwm (same seq)--> I/O tile
 *
 * This project writes its own main() ([project] main = "flight_app.c") so that its boot code is
 * the built-in application's instruction for instruction: robosoc's default flight and Table I
 * come out bit for bit the same whichever of the two flies.  A new project can leave main() to
 * robosoc, which generates it from the [[tasks]] table (the blank template does).
 *
 * Release: ROBOSOC_RELEASE_PERIODIC 0 (event release, the seed's, the default): each task is an
 * event task on its port, one job per message, relative deadline ROBOSOC_PERIOD_TICKS.  1 (the
 * scenario's release = "periodic", robosoc's option): both tasks periodic with period and deadline
 * ROBOSOC_PERIOD_TICKS; a job takes the newest waiting message (older ones are counted stale and
 * dropped) and does nothing if none waited (counted).
 *
 * A message that is not a packet of the expected kind and length is counted and dropped.  The
 * counters are in app_stats (read them with `robosoc run --gdb` or as telemetry).
 */
#include <stdint.h>
#include <string.h>

#include "estimator.h"
#include "os.h"
#include "pid.h"
#include "robosoc_packets.h"
#include "robosoc_project.h"

#define APP_EST_TILE ROBOSOC_TASK_ESTIMATOR_TILE
#define APP_PID_TILE ROBOSOC_TASK_PID_TILE
#define APP_PERIODIC ROBOSOC_RELEASE_PERIODIC
#define APP_PERIOD_TICKS ROBOSOC_PERIOD_TICKS
/* The EKF's update keeps several 7 x 7 matrices on the stack; soft-float calls add their frames. */
#define APP_EST_STACK_BYTES ROBOSOC_TASK_ESTIMATOR_STACK_BYTES
#define APP_PID_STACK_BYTES ROBOSOC_TASK_PID_STACK_BYTES

#define APP_STATS_MAGIC 0x53505041u /* "APPS" in memory */
typedef struct {
    uint32_t magic;       /* APP_STATS_MAGIC once main ran */
    uint32_t est_jobs;    /* sensor packets turned into estimates */
    uint32_t est_foreign; /* messages on the sensor port that were no sensor packet: dropped */
    uint32_t est_empty;   /* periodic jobs that found no sensor packet */
    uint32_t est_stale;   /* periodic release: older sensor packets skipped for a newer one */
    uint32_t pid_jobs;    /* estimate packets turned into PWM packets */
    uint32_t pid_foreign; /* messages on the estimate port that were no estimate packet: dropped */
    uint32_t pid_empty;
    uint32_t pid_stale;
    uint32_t send_errors; /* os_send refused (OS_E_*) */
} app_stats_t;
app_stats_t app_stats;

static est_t app_est;
static pid_controller_t app_pid;

static void app_send(uint32_t tile, uint32_t port, const void *data, uint32_t len)
{
    if (os_send(tile, port, data, len) != (int32_t)len) {
        app_stats.send_errors++;
    }
}

/* The estimator's work on one message; what is not a sensor packet is counted and dropped. */
static void app_estimate(const void *data, uint32_t len)
{
    struct robosoc_sensor_packet in;
    struct robosoc_estimate_packet out;
    if (len != sizeof in) {
        app_stats.est_foreign++;
        return;
    }
    memcpy(&in, data, sizeof in); /* the kernel's buffer need not be aligned for the struct */
    if (est_packet_step(&app_est, &in, &out) != 0) {
        app_stats.est_foreign++;
        return;
    }
    app_stats.est_jobs++;
    app_send(ROBOSOC_MSG_ESTIMATE_TILE, ROBOSOC_MSG_ESTIMATE_PORT, &out, sizeof out);
}

static void app_control(const void *data, uint32_t len)
{
    struct robosoc_estimate_packet in;
    struct robosoc_pwm_packet out;
    if (len != sizeof in) {
        app_stats.pid_foreign++;
        return;
    }
    memcpy(&in, data, sizeof in);
    if (pid_packet_step(&app_pid, &in, &out) != 0) {
        app_stats.pid_foreign++;
        return;
    }
    app_stats.pid_jobs++;
    app_send(ROBOSOC_MSG_PWM_TILE, ROBOSOC_MSG_PWM_PORT, &out, sizeof out);
}

#if APP_PERIODIC
/* Bytes of a message the application reads; a longer one is foreign anyway (os_recv returns
 * its full length, so it is recognised). */
#define APP_MSG_MAX 128u
_Static_assert(ROBOSOC_SENSOR_BYTES <= APP_MSG_MAX, "buffer holds a sensor packet");
_Static_assert(ROBOSOC_ESTIMATE_BYTES <= APP_MSG_MAX, "buffer holds an estimate packet");

/* Take the newest message waiting on `port` into buf without blocking (os_probe before each
 * os_recv); returns its length, or -1 if none waited.  Older ones count in *stale. */
static int32_t app_newest(uint32_t port, uint8_t *buf, uint32_t *stale)
{
    int32_t len = -1;
    while (os_probe(port) >= 0) {
        if (len >= 0) {
            (*stale)++;
        }
        len = os_recv(port, buf, APP_MSG_MAX, 0);
    }
    return len;
}

static uint8_t app_est_buf[APP_MSG_MAX] __attribute__((aligned(4)));
static uint8_t app_pid_buf[APP_MSG_MAX] __attribute__((aligned(4)));

static void app_est_job(void *arg)
{
    (void)arg;
    int32_t len = app_newest(ROBOSOC_MSG_SENSOR_PORT, app_est_buf, &app_stats.est_stale);
    if (len < 0) {
        app_stats.est_empty++;
        return;
    }
    app_estimate(app_est_buf, (uint32_t)len);
}

static void app_pid_job(void *arg)
{
    (void)arg;
    int32_t len = app_newest(ROBOSOC_MSG_ESTIMATE_PORT, app_pid_buf, &app_stats.pid_stale);
    if (len < 0) {
        app_stats.pid_empty++;
        return;
    }
    app_control(app_pid_buf, (uint32_t)len);
}
#else
static void app_est_event(const os_msg_t *msg, void *arg)
{
    (void)arg;
    app_estimate(msg->data, msg->len);
}

static void app_pid_event(const os_msg_t *msg, void *arg)
{
    (void)arg;
    app_control(msg->data, msg->len);
}
#endif

int main(void)
{
    uint32_t tile = os_tile();
    app_stats.magic = APP_STATS_MAGIC;
    if (tile == APP_EST_TILE) {
        est_init(&app_est);
#if APP_PERIODIC
        os_task_periodic(app_est_job, 0, APP_PERIOD_TICKS, APP_PERIOD_TICKS, APP_PERIOD_TICKS, APP_EST_STACK_BYTES);
#else
        os_task_event(app_est_event, 0, ROBOSOC_MSG_SENSOR_PORT, APP_PERIOD_TICKS, APP_EST_STACK_BYTES);
#endif
    }
    if (tile == APP_PID_TILE) {
        pid_init(&app_pid);
#if APP_PERIODIC
        os_task_periodic(app_pid_job, 0, APP_PERIOD_TICKS, APP_PERIOD_TICKS, APP_PERIOD_TICKS, APP_PID_STACK_BYTES);
#else
        os_task_event(app_pid_event, 0, ROBOSOC_MSG_ESTIMATE_PORT, APP_PERIOD_TICKS, APP_PID_STACK_BYTES);
#endif
    }
    os_start();
}
