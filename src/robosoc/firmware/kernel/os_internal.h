/*
 * os_internal.h - what the kernel's files share and applications do not see.
 */
#ifndef OS_INTERNAL_H
#define OS_INTERNAL_H

#include <stdint.h>

#include "os.h"
#include "port.h"

typedef enum { OS_KIND_IDLE, OS_KIND_PERIODIC, OS_KIND_EVENT, OS_KIND_BEST_EFFORT } os_kind_t;

typedef enum {
    OS_ST_READY,        /* may be dispatched (real-time tasks: a job is active) */
    OS_ST_BLOCKED,      /* waits for a semaphore, a message or the end of a delay */
    OS_ST_WAIT_RELEASE, /* real-time task between jobs */
    OS_ST_DEPLETED,     /* real-time job out of capacity until its next period */
    OS_ST_DONE          /* best-effort body returned */
} os_state_t;

typedef enum { OS_WAIT_NONE, OS_WAIT_SEM, OS_WAIT_RECV, OS_WAIT_DELAY } os_wait_t;

typedef struct os_tcb {
    uint32_t *sp; /* saved stack pointer: must stay first (port_asm.S uses offset 0) */
    uint8_t id;   /* TASK_ID */
    uint8_t kind; /* os_kind_t */
    uint8_t state;
    uint8_t wait;
    uint8_t prio;       /* best effort */
    uint8_t port;       /* event task: the port that releases it */
    uint8_t job_active; /* real-time: a job was released and has not completed */
    uint8_t missed;     /* real-time: the active job's miss is already counted */
    uint8_t depleted;   /* real-time: the active job ran out of capacity at least once */
    int16_t slot;       /* event task: message slot of the active job */
    uint16_t job;       /* jobs released so far (modulo 65536) */
    void (*fn)(void);   /* job or body, cast by the trampoline of its kind */
    void *arg;
    const void *wait_obj; /* semaphore, or port number + 1 */
    uint32_t wake_tick;   /* delay: the tick to wake at */
    uint32_t rm_key;      /* RM: period (event: deadline) in ticks */
    uint32_t period_ticks;
    uint32_t next_release; /* periodic: tick of the next release */
    uint32_t pending;      /* periodic: releases waiting for the active job to complete */
    uint32_t period_cycles, deadline_cycles, budget_cycles;
    uint32_t release, abs_deadline, start, exec; /* the active job, TIMER0 cycles */
    uint32_t used;                                 /* cycles used in the current period */
    uint32_t last_run;                             /* os_dispatches when last dispatched */
    uint32_t *stack_base;                          /* lowest word: a canary */
    uint32_t reserved[9];                          /* to 128 bytes, see below */
} os_tcb_t;
/* A power-of-two size lets the compiler index the task table with a shift: with the iterative
 * multiplier it would otherwise use MUL (16 to 37 cycles) for every os_tcb[i]. */
_Static_assert(sizeof(os_tcb_t) == 128, "os_tcb_t: adjust reserved[] to keep 128 bytes");

/* The running task; port_asm.S saves and loads os_current->sp. */
extern os_tcb_t *os_current;
extern os_tcb_t os_tcb[OS_MAX_TASKS + 1]; /* [0] is the idle task */
extern uint32_t os_ntasks;                /* entries used in os_tcb */
extern uint32_t os_started;

/*
 * Kernel calls from tasks: interrupts off and TASK_ID 0 inside, so the simulator charges the
 * kernel's work to the kernel; os_leave names the task again.
 */
static inline uint32_t os_enter(void)
{
    uint32_t state = port_irq_disable();
    port_set_task_id(OS_KERNEL_TASK_ID);
    return state;
}
static inline void os_leave(uint32_t state)
{
    port_set_task_id(os_current->id);
    port_irq_restore(state);
}

/* Inside os_enter: switch if another task should run now; returns (interrupts off) when this
 * task is dispatched again. */
void os_reschedule(void);
/* Inside os_enter: block the caller until something makes it ready, then return as above. */
void os_block(os_wait_t wait, const void *obj);
void os_panic(const char *why) __attribute__((noreturn));

/* Messaging (os_msg.c) called by the scheduler */
void os_msg_receive_all(uint32_t cycle);     /* take every packet waiting in the NI */
const os_msg_t *os_msg_slot_view(int slot);  /* the message in a slot, for an event job */
void os_msg_slot_free(int slot);
int os_msg_oldest(uint32_t port);            /* oldest complete, untaken message on a port, or -1 */
void os_msg_take(int slot);                  /* reserve it for an event job */
uint32_t os_msg_arrival(int slot);

/* Scheduler hook: a message completed on `port` in `slot` */
void os_sched_message(uint32_t port, int slot);

#endif /* OS_INTERNAL_H */
