/*
 * os.h - the robosoc real-time kernel: tasks, scheduling, semaphores, delays, NoC messaging.
 *
 * A preemptive kernel for one HF-RISCV tile of the MPSoC, in the spirit of HellfireOS (the RTOS
 * of ORCA): a tick from TIMER1, periodic real-time tasks with period, capacity and deadline in
 * ticks (EDF, or RM with OS_SCHED_POLICY), event-triggered tasks released by a message on a port,
 * best-effort tasks with priorities, and an idle task that sleeps.  Messages travel between
 * (tile, port) addresses over the NoC.  Everything hardware-specific sits behind port/port.h.
 *
 * Use: create tasks in main(), then call os_start(), which never returns (main's stack becomes
 * the kernel's, so nothing a task uses may live on it).  docs/firmware-kernel.md has the rules,
 * the message header, the job-log layout and the measured overheads.
 */
#ifndef OS_H
#define OS_H

#include <stdint.h>

#include "os_config.h"

/* ---- Results ---------------------------------------------------------------------------- */
#define OS_OK 0
#define OS_E_INVAL (-1)  /* a parameter is out of range */
#define OS_E_NOMEM (-2)  /* no task slot or no stack memory left */
#define OS_E_TOOBIG (-3) /* message longer than the protocol or this build allows */
#define OS_E_EMPTY (-4)  /* os_probe: no message waiting */
#define OS_E_FULL (-5)   /* no message slot free for a message to this tile */

/* ---- TASK_ID values (per-task accounting in the simulator) ---------------------------- */
#define OS_KERNEL_TASK_ID 0 /* interrupt entry/exit, scheduler, messaging internals */
#define OS_IDLE_TASK_ID 1
#define OS_FIRST_TASK_ID 2 /* application tasks: 2, 3, ... in order of creation */

/* ---- Tasks ------------------------------------------------------------------------------ */
typedef void (*os_job_fn)(void *arg);

/* A received message as an event task's job sees it (data valid until the job returns). */
typedef struct {
    uint32_t src_tile;   /* NoC address (x << 4) | y of the sender */
    uint32_t src_port;   /* the sender's source port (its TASK_ID for kernel senders) */
    uint32_t port;       /* the port it arrived on */
    uint32_t len;        /* bytes */
    uint32_t arrival;    /* TIMER0 when the kernel took its last packet */
    const uint8_t *data; /* os_probe/os_recv leave it 0 */
} os_msg_t;
typedef void (*os_event_fn)(const os_msg_t *msg, void *arg);

/*
 * Periodic real-time task: job(arg) runs once per period, released at ticks; the job must finish
 * within `deadline` ticks of its release and gets at most `capacity` ticks of execution per
 * period (beyond that it waits for its next period).  1 <= capacity <= deadline <= period.
 * Returns the task's TASK_ID (>= 2) or OS_E_*.  stack_bytes 0 = a default of 1024.
 */
int os_task_periodic(os_job_fn job, void *arg, uint32_t period, uint32_t capacity, uint32_t deadline,
                     uint32_t stack_bytes);
/*
 * Event-triggered real-time task: every message arriving on `port` releases one job(msg, arg);
 * it must finish within `deadline` ticks of the arrival (deadline misses are counted).  Messages
 * arriving while a job runs wait in their slots and release the following jobs in order.
 */
int os_task_event(os_event_fn job, void *arg, uint32_t port, uint32_t deadline, uint32_t stack_bytes);
/* Best-effort task: body(arg) runs when no real-time job is ready; higher priority first,
 * round robin at each tick among equal priorities.  Returning from body ends the task. */
int os_task_best_effort(os_job_fn body, void *arg, uint32_t priority, uint32_t stack_bytes);

void os_start(void) __attribute__((noreturn));

/* Number of the last tick handled: tick k rises in cycle k * OS_TICK_CYCLES + 2. */
uint32_t os_ticks(void);
uint32_t os_cycles(void);                     /* TIMER0 */
uint32_t os_task_id(void);                    /* the caller's TASK_ID */
uint32_t os_task_misses(uint32_t task_id);    /* deadline misses of a task so far */
void os_delay(uint32_t ticks);                /* block for `ticks` ticks (0: just yield) */
void os_yield(void);                          /* let another best-effort task of equal priority run */
void os_exit(uint32_t code) __attribute__((noreturn)); /* end the simulation with an exit code */

/* ---- Semaphore -------------------------------------------------------------------------- */
typedef struct {
    volatile int32_t count;
} os_sem_t;
void os_sem_init(os_sem_t *sem, int32_t count);
void os_sem_wait(os_sem_t *sem);   /* blocks while count <= 0, then decrements */
int os_sem_trywait(os_sem_t *sem); /* 1 when decremented, 0 when it would block */
void os_sem_post(os_sem_t *sem);   /* increments and wakes the waiters */

/* ---- Messaging -------------------------------------------------------------------------- */
#define OS_TILE(x, y) ((uint32_t)(((x) << 4) | (y)))
uint32_t os_tile(void);    /* this tile's NoC address */
uint32_t os_io_tile(void); /* the I/O tile's NoC address */
/*
 * Send `len` bytes to (tile, port): split into packets, sent by the network interface (a message
 * to this tile is delivered locally).  Returns len or OS_E_*.  Sending to a powered-off tile is
 * an error of the chip, reported by the simulator.
 */
int32_t os_send(uint32_t tile, uint32_t port, const void *data, uint32_t len);
/* Block until a message waits on `port`, copy up to `size` bytes, return its full length. */
int32_t os_recv(uint32_t port, void *buf, uint32_t size, os_msg_t *info);
/* Length of the next message waiting on `port`, or OS_E_EMPTY; never blocks. */
int32_t os_probe(uint32_t port);

/* ---- On-chip message header (docs/firmware-kernel.md, "Message header") ---------------
 * flit 0  destination tile (wire)       flit 1  flits that follow (wire)
 * flit 2  source tile << 8 | source port
 * flit 3  destination port << 8 | fragment index
 * flit 4  message length in bytes       flit 5  message sequence number of the source tile
 * flit 6. data, two bytes per flit, little endian (the last flit padded with 0)
 */
#define OS_MSG_HEADER_FLITS 6
#define OS_MSG_DATA_BYTES_PER_PACKET (2 * (OS_MSG_PACKET_FLITS - OS_MSG_HEADER_FLITS))

/* ---- What the host reads (robosoc.firmware.images) ------------------------------------ */
#define OS_JOB_MET 1u        /* record flag: completed by its deadline */
#define OS_JOB_EVENT 2u      /* record flag: released by a message */
#define OS_JOB_DEPLETED 4u   /* record flag: ran out of capacity in some period */
typedef struct {
    uint8_t task;        /* TASK_ID */
    uint8_t flags;       /* OS_JOB_* */
    uint16_t job;        /* job number of the task, from 1 (modulo 65536) */
    uint32_t release;    /* TIMER0 cycle of the release: the tick, or the message's arrival */
    uint32_t deadline;   /* absolute deadline, TIMER0 cycle */
    uint32_t start;      /* TIMER0 just before the job function was called */
    uint32_t completion; /* TIMER0 when the job function had returned */
    uint32_t exec;       /* TIMER0 cycles the task was dispatched during the job */
} os_job_record_t;       /* 24 bytes */

#define OS_JOBLOG_MAGIC 0x4a4f4253u /* "SBOJ" in memory */
typedef struct {
    uint32_t magic;       /* OS_JOBLOG_MAGIC once os_start ran */
    uint32_t capacity;    /* OS_JOBLOG_RECORDS */
    uint32_t count;       /* records ever written; record i is rec[i % capacity] */
    uint32_t tick_cycles; /* OS_TICK_CYCLES */
    os_job_record_t rec[OS_JOBLOG_RECORDS];
} os_job_log_t;
extern os_job_log_t os_job_log;

#define OS_STATS_MAGIC 0x4154534bu /* "KSTA" in memory */
typedef struct {
    uint32_t magic;          /* OS_STATS_MAGIC once os_start ran */
    uint32_t tick_cycles;    /* OS_TICK_CYCLES */
    uint32_t start_cycle;    /* TIMER0 right after os_start aligned TIMER1 */
    uint32_t first_tick;     /* the first tick after os_start: rises at first_tick * tick_cycles + 2 */
    uint32_t ticks;          /* ticks handled */
    uint32_t ticks_late;     /* ticks handled more than a tick after they rose */
    uint32_t switches;       /* dispatches of another task than the one that entered the kernel */
    uint32_t msg_sent;       /* messages sent (local ones included) */
    uint32_t msg_received;   /* messages completed on this tile (local ones included) */
    uint32_t pkt_sent;       /* NoC packets sent */
    uint32_t pkt_received;   /* NoC packets received */
    uint32_t pkt_malformed;  /* packets dropped: header or length inconsistent */
    uint32_t msg_dropped;    /* messages dropped: no free slot, or longer than OS_MSG_MAX_BYTES */
    uint32_t reserved;
    struct {
        uint32_t jobs;       /* jobs completed */
        uint32_t misses;     /* deadline misses */
    } task[16];              /* by TASK_ID */
} os_stats_t;
extern os_stats_t os_stats;

#endif /* OS_H */
