/*
 * flight_app.c - the flight application: the estimator task and the PID task under the kernel.
 *
 * One image for every tile: main() reads its tile (os_tile()) and creates the tasks mapped to it
 * (both when the two share a tile; the estimator first, so its TASK_ID is the lower).  Messages:
 *
 *   I/O tile --sensor--> (APP_EST_TILE, ROBOSOC_SENSOR_PORT)    estimator task
 *   estimator --estimate--> (APP_PID_TILE, ROBOSOC_ESTIMATE_PORT) PID task
 *   PID task --pwm (same seq)--> (I/O tile, ROBOSOC_PWM_PORT)
 *
 * Release (APP_PERIODIC): 0, event release (default): each task is an event task on its port,
 * one job per message, relative deadline APP_PERIOD_TICKS.  1, periodic release (robosoc's option): both
 * tasks periodic with period and deadline APP_PERIOD_TICKS; a job takes the newest waiting
 * message (older ones are counted stale and dropped) and does nothing if none waited (counted).
 *
 * A message that is not a packet of the expected kind and length is counted and dropped (the
 * kernel itself drops packets whose NoC header is inconsistent).  The counters are in app_stats,
 * which the host reads (robosoc.firmware.flight_app.read_app_stats).
 *
 * Build defines (robosoc.firmware.flight_app.build): APP_EST_TILE and APP_PID_TILE (NoC addresses
 * (x << 4) | y), APP_PERIODIC, APP_PERIOD_TICKS, plus the kernel's OS_TICK_CYCLES and
 * OS_SCHED_POLICY and real_t's ROBOSOC_ARITH_FIXED.
 */
#include <stdint.h>
#include <string.h>

#include "estimator.h"
#include "os.h"
#include "pid.h"
#include "robosoc_packets.h"

#ifndef APP_EST_TILE
#define APP_EST_TILE OS_TILE(0, 1)
#endif
#ifndef APP_PID_TILE
#define APP_PID_TILE OS_TILE(1, 0)
#endif
#ifndef APP_PERIODIC
#define APP_PERIODIC 0
#endif
#ifndef APP_PERIOD_TICKS
#define APP_PERIOD_TICKS 10
#endif
/* The EKF's update keeps several 7 x 7 matrices on the stack; soft-float calls add their frames. */
#define APP_EST_STACK_BYTES 6144
#define APP_PID_STACK_BYTES 3072

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
    app_send(APP_PID_TILE, ROBOSOC_ESTIMATE_PORT, &out, sizeof out);
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
    app_send(os_io_tile(), ROBOSOC_PWM_PORT, &out, sizeof out);
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
    int32_t len = app_newest(ROBOSOC_SENSOR_PORT, app_est_buf, &app_stats.est_stale);
    if (len < 0) {
        app_stats.est_empty++;
        return;
    }
    app_estimate(app_est_buf, (uint32_t)len);
}

static void app_pid_job(void *arg)
{
    (void)arg;
    int32_t len = app_newest(ROBOSOC_ESTIMATE_PORT, app_pid_buf, &app_stats.pid_stale);
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
        os_task_event(app_est_event, 0, ROBOSOC_SENSOR_PORT, APP_PERIOD_TICKS, APP_EST_STACK_BYTES);
#endif
    }
    if (tile == APP_PID_TILE) {
        pid_init(&app_pid);
#if APP_PERIODIC
        os_task_periodic(app_pid_job, 0, APP_PERIOD_TICKS, APP_PERIOD_TICKS, APP_PERIOD_TICKS, APP_PID_STACK_BYTES);
#else
        os_task_event(app_pid_event, 0, ROBOSOC_ESTIMATE_PORT, APP_PERIOD_TICKS, APP_PID_STACK_BYTES);
#endif
    }
    os_start();
}
