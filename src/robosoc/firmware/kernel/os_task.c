/*
 * os_task.c - tasks, the scheduler, the tick, jobs and their log, semaphores and delays.
 *
 * Scheduling happens on every way into the kernel (tick, received packet, blocking or waking
 * call): the ready real-time job with the earliest absolute deadline (EDF) or the shortest
 * period (RM) runs; without one, the best-effort task of highest priority (round robin among
 * equals at each tick); without one, the idle task, which sleeps.  Task counts are small (at
 * most 14), so every decision is a linear scan over the task table: short, and easy to follow.
 */
#include "hf_print.h"
#include "os_internal.h"

#define OS_STACK_CANARY 0x5a5aa5a5u
#define OS_DEFAULT_STACK_BYTES 1024u
#define OS_MIN_STACK_BYTES 256u /* one 128-byte context frame plus a little C */
/* cycle counts compared with signed differences must stay below 2^31 */
#define OS_MAX_TICKS (0x7fffffffu / OS_TICK_CYCLES)

os_tcb_t os_tcb[OS_MAX_TASKS + 1];
uint32_t os_ntasks = 1; /* os_tcb[0] is reserved for the idle task */
uint32_t os_started;
os_job_log_t os_job_log;
os_stats_t os_stats;

static os_tcb_t os_boot_tcb; /* "current task" of main() before os_start: TASK_ID 0 */
os_tcb_t *os_current = &os_boot_tcb;

static uint32_t os_tick;            /* number of the last tick handled */
static uint32_t os_next_tick_cycle; /* TIMER0 cycle the next tick rises in */
static uint32_t os_dispatched_at;   /* TIMER0 when os_current was dispatched (or last charged) */
static uint32_t os_be_rotate;       /* the next pick moves on among best-effort equals */
static uint32_t os_dispatches;      /* counts dispatches: os_tcb_t.last_run */
static uint32_t os_log_next;        /* os_job_log.rec index of the next record */
static uint8_t *os_stack_next;      /* task stacks are carved upwards from the end of .bss */

extern uint8_t __heap_start[], __stack_top[]; /* linker script */

/* ---- Helpers ------------------------------------------------------------------------------ */

void os_panic(const char *why)
{
    port_irq_disable();
    hf_printf("os: panic in task %u: %s\n", (unsigned)os_current->id, why);
    port_exit(0xdeadu);
}

static int os_is_rt(const os_tcb_t *t) { return t->kind == OS_KIND_PERIODIC || t->kind == OS_KIND_EVENT; }

/* Task stacks live between .bss and the kernel stack at the top of SRAM: nothing to clear. */
static uint8_t *os_stack_alloc(uint32_t bytes)
{
    if (os_stack_next == 0) {
        os_stack_next = (uint8_t *)(((uintptr_t)__heap_start + 15u) & ~(uintptr_t)15u);
    }
    uint8_t *limit = __stack_top - OS_KERNEL_STACK_BYTES;
    if (bytes > (uint32_t)(limit - os_stack_next)) {
        return 0;
    }
    uint8_t *base = os_stack_next;
    os_stack_next += bytes;
    return base;
}

static void os_task_entry_init(os_tcb_t *t, uint32_t id, os_kind_t kind, void (*entry)(void), uint8_t *stack,
                               uint32_t bytes)
{
    t->id = (uint8_t)id;
    t->kind = (uint8_t)kind;
    t->slot = -1;
    t->stack_base = (uint32_t *)stack;
    *t->stack_base = OS_STACK_CANARY;
    t->sp = port_stack_init((uint32_t *)(stack + bytes), entry, id);
}

/* A new entry of the task table (inside os_enter), or 0 when the table or the memory is full. */
static os_tcb_t *os_task_new(os_kind_t kind, void (*entry)(void), void (*fn)(void), void *arg, uint32_t bytes)
{
    if (os_ntasks > OS_MAX_TASKS) {
        return 0;
    }
    bytes = bytes == 0u ? OS_DEFAULT_STACK_BYTES : (bytes + 15u) & ~15u;
    if (bytes < OS_MIN_STACK_BYTES) {
        bytes = OS_MIN_STACK_BYTES;
    }
    uint8_t *stack = os_stack_alloc(bytes);
    if (stack == 0) {
        return 0;
    }
    os_tcb_t *t = &os_tcb[os_ntasks];
    os_task_entry_init(t, OS_FIRST_TASK_ID + os_ntasks - 1u, kind, entry, stack, bytes);
    t->fn = fn;
    t->arg = arg;
    os_ntasks++;
    return t;
}

/* ---- Jobs --------------------------------------------------------------------------------- */

static void os_release(os_tcb_t *t, uint32_t at)
{
    t->job++;
    t->job_active = 1;
    t->missed = 0;
    t->depleted = 0;
    t->release = at;
    t->abs_deadline = at + t->deadline_cycles;
    t->exec = 0;
    t->state = OS_ST_READY;
}

static void os_count_miss(os_tcb_t *t)
{
    t->missed = 1;
    os_stats.task[t->id].misses++;
}

static void os_log_job(const os_tcb_t *t, uint32_t completion, int met)
{
    os_job_record_t *r = &os_job_log.rec[os_log_next];
    if (++os_log_next == OS_JOBLOG_RECORDS) {
        os_log_next = 0;
    }
    r->task = t->id;
    r->flags = (uint8_t)((met ? OS_JOB_MET : 0u) | (t->kind == OS_KIND_EVENT ? OS_JOB_EVENT : 0u) |
                         (t->depleted ? OS_JOB_DEPLETED : 0u));
    r->job = t->job;
    r->release = t->release;
    r->deadline = t->abs_deadline;
    r->start = t->start;
    r->completion = completion;
    r->exec = t->exec;
    os_job_log.count++; /* last, so a reader never sees a half-written record counted */
}

/* Charge the cycles since the last dispatch to the running task. */
static void os_charge(uint32_t now)
{
    uint32_t d = now - os_dispatched_at;
    os_current->exec += d;
    os_current->used += d;
    os_dispatched_at = now;
}

/* The job function returned (task context). */
static void os_job_done(os_tcb_t *t)
{
    uint32_t state = os_enter();
    uint32_t now = port_cycles();
    os_charge(now);
    int met = !t->missed && (int32_t)(now - t->abs_deadline) <= 0;
    if (!met && !t->missed) {
        os_count_miss(t);
    }
    os_stats.task[t->id].jobs++;
    os_log_job(t, now, met);
    t->job_active = 0;
    t->state = OS_ST_WAIT_RELEASE;
    if (t->kind == OS_KIND_PERIODIC) {
        if (t->pending) { /* released while this job ran: its release was one period later */
            t->pending--;
            os_release(t, t->release + t->period_cycles);
        }
    } else {
        os_msg_slot_free(t->slot);
        t->slot = -1;
        int next = os_msg_oldest(t->port);
        if (next >= 0) {
            os_msg_take(next);
            t->slot = (int16_t)next;
            os_release(t, os_msg_arrival(next));
        }
    }
    os_reschedule();
    os_leave(state);
}

/* First code of every task, one per kind (os_current is the task itself). */
static void os_periodic_main(void)
{
    os_tcb_t *self = os_current;
    for (;;) {
        self->start = port_cycles();
        ((os_job_fn)self->fn)(self->arg);
        os_job_done(self);
    }
}

static void os_event_main(void)
{
    os_tcb_t *self = os_current;
    for (;;) {
        self->start = port_cycles();
        ((os_event_fn)self->fn)(os_msg_slot_view(self->slot), self->arg);
        os_job_done(self);
    }
}

static void os_best_effort_main(void)
{
    os_tcb_t *self = os_current;
    ((os_job_fn)self->fn)(self->arg);
    os_enter();
    self->state = OS_ST_DONE;
    os_reschedule();
    os_panic("a finished task was dispatched");
}

/* Interrupts enabled: a sleeping core wakes into the interrupt that makes another task ready.
 * Nothing is checked before sleeping, so no wake-up can be missed: anything that readies a task
 * is an interrupt, and the kernel switches away from the idle task before returning from it. */
static void os_idle_main(void)
{
    for (;;) {
        port_sleep();
    }
}

/* ---- Task creation ------------------------------------------------------------------------ */

int os_task_periodic(os_job_fn job, void *arg, uint32_t period, uint32_t capacity, uint32_t deadline,
                     uint32_t stack_bytes)
{
    if (job == 0 || capacity < 1u || capacity > deadline || deadline > period || period > OS_MAX_TICKS) {
        return OS_E_INVAL;
    }
    uint32_t state = os_enter();
    os_tcb_t *t = os_task_new(OS_KIND_PERIODIC, os_periodic_main, (void (*)(void))job, arg, stack_bytes);
    int result = OS_E_NOMEM;
    if (t != 0) {
        t->period_ticks = period;
        t->rm_key = period;
        t->period_cycles = period * OS_TICK_CYCLES;
        t->deadline_cycles = deadline * OS_TICK_CYCLES;
        t->budget_cycles = capacity * OS_TICK_CYCLES;
        t->state = OS_ST_WAIT_RELEASE;
        t->next_release = os_tick + 1u; /* os_start sets the first tick for tasks made before it */
        result = t->id;
    }
    os_leave(state);
    return result;
}

int os_task_event(os_event_fn job, void *arg, uint32_t port, uint32_t deadline, uint32_t stack_bytes)
{
    if (job == 0 || port >= OS_MSG_PORTS || deadline < 1u || deadline > OS_MAX_TICKS) {
        return OS_E_INVAL;
    }
    uint32_t state = os_enter();
    int result = OS_E_NOMEM;
    for (uint32_t i = 1; i < os_ntasks; i++) {
        if (os_tcb[i].kind == OS_KIND_EVENT && os_tcb[i].port == port) {
            result = OS_E_INVAL; /* one event task per port */
        }
    }
    os_tcb_t *t = 0;
    if (result != OS_E_INVAL) {
        t = os_task_new(OS_KIND_EVENT, os_event_main, (void (*)(void))job, arg, stack_bytes);
    }
    if (t != 0) {
        t->port = (uint8_t)port;
        t->rm_key = deadline;
        t->deadline_cycles = deadline * OS_TICK_CYCLES;
        t->state = OS_ST_WAIT_RELEASE;
        int next = os_msg_oldest(port); /* messages that came before the task */
        if (next >= 0) {
            os_msg_take(next);
            t->slot = (int16_t)next;
            os_release(t, os_msg_arrival(next));
        }
        result = t->id;
    }
    os_reschedule();
    os_leave(state);
    return result;
}

int os_task_best_effort(os_job_fn body, void *arg, uint32_t priority, uint32_t stack_bytes)
{
    if (body == 0 || priority > 255u) {
        return OS_E_INVAL;
    }
    uint32_t state = os_enter();
    os_tcb_t *t = os_task_new(OS_KIND_BEST_EFFORT, os_best_effort_main, (void (*)(void))body, arg, stack_bytes);
    int result = OS_E_NOMEM;
    if (t != 0) {
        t->prio = (uint8_t)priority;
        t->state = OS_ST_READY;
        result = t->id;
    }
    os_reschedule();
    os_leave(state);
    return result;
}

/* ---- Scheduling --------------------------------------------------------------------------- */

/* Should real-time task a run before b?  Ties go to the running task, then to the older task. */
static int os_before(const os_tcb_t *a, const os_tcb_t *b)
{
#if OS_SCHED_POLICY == OS_SCHED_EDF
    int32_t d = (int32_t)(a->abs_deadline - b->abs_deadline);
#else
    int32_t d = a->rm_key < b->rm_key ? -1 : (a->rm_key > b->rm_key ? 1 : 0);
#endif
    return d < 0 || (d == 0 && a == os_current);
}

static os_tcb_t *os_pick(void)
{
    os_tcb_t *best = 0;
    int top = -1;
    for (uint32_t i = 1; i < os_ntasks; i++) {
        os_tcb_t *t = &os_tcb[i];
        if (t->state != OS_ST_READY) {
            continue;
        }
        if (os_is_rt(t)) {
            if (best == 0 || os_before(t, best)) {
                best = t;
            }
        } else if ((int)t->prio > top) {
            top = t->prio;
        }
    }
    if (best != 0) {
        return best;
    }
    if (top < 0) {
        return &os_tcb[0];
    }
    /* the task of that priority that ran last goes on (it may have been preempted); at a tick or
     * an os_yield, if it is the running task, the next one of that priority takes its turn */
    os_tcb_t *recent = 0;
    for (uint32_t i = 1; i < os_ntasks; i++) {
        os_tcb_t *t = &os_tcb[i];
        if (t->kind == OS_KIND_BEST_EFFORT && t->state == OS_ST_READY && t->prio == top &&
            (recent == 0 || (int32_t)(t->last_run - recent->last_run) > 0)) {
            recent = t;
        }
    }
    if (!os_be_rotate || recent != os_current) {
        return recent;
    }
    uint32_t i = (uint32_t)(recent - os_tcb);
    for (uint32_t k = 1; k < os_ntasks; k++) {
        i = i + 1u >= os_ntasks ? 1u : i + 1u;
        os_tcb_t *t = &os_tcb[i];
        if (t->kind == OS_KIND_BEST_EFFORT && t->state == OS_ST_READY && t->prio == top) {
            return t;
        }
    }
    return recent;
}

static void os_check_stack(const os_tcb_t *t)
{
    if (t->stack_base != 0 && *t->stack_base != OS_STACK_CANARY) {
        os_panic("task stack overflow (give the task a larger stack_bytes)");
    }
}

/* Choose the task to resume; port_restore then loads os_current. */
static void os_dispatch(void)
{
    os_tcb_t *next = os_pick();
    if (next != os_current) {
        os_stats.switches++;
        next->last_run = ++os_dispatches;
        os_current = next;
    }
    os_be_rotate = 0;
    os_dispatched_at = port_cycles();
}

void os_reschedule(void)
{
    if (os_started && os_pick() != os_current) {
        port_yield(); /* returns with interrupts enabled once this task runs again */
        port_irq_disable();
    }
}

void os_block(os_wait_t wait, const void *obj)
{
    if (!os_started || os_current->kind == OS_KIND_IDLE) {
        os_panic("blocking call outside a task");
    }
    os_current->state = OS_ST_BLOCKED;
    os_current->wait = (uint8_t)wait;
    os_current->wait_obj = obj;
    port_yield();
    port_irq_disable();
}

/* Make every task blocked on (wait, obj) ready; returns how many. */
static uint32_t os_wake(os_wait_t wait, const void *obj)
{
    uint32_t woken = 0;
    for (uint32_t i = 1; i < os_ntasks; i++) {
        os_tcb_t *t = &os_tcb[i];
        if (t->state == OS_ST_BLOCKED && t->wait == wait && t->wait_obj == obj) {
            t->state = OS_ST_READY;
            t->wait = OS_WAIT_NONE;
            woken++;
        }
    }
    return woken;
}

/* ---- The tick ----------------------------------------------------------------------------- */

static void os_on_tick(uint32_t at)
{
    os_tcb_t *cur = os_current;
    /* capacity is enforced at ticks: a running job that used its budget waits for its period */
    if (os_is_rt(cur) && cur->state == OS_ST_READY && cur->budget_cycles != 0u && cur->used >= cur->budget_cycles) {
        cur->state = OS_ST_DEPLETED;
        cur->depleted = 1;
    }
    for (uint32_t i = 1; i < os_ntasks; i++) {
        os_tcb_t *t = &os_tcb[i];
        if (t->kind == OS_KIND_PERIODIC && (int32_t)(os_tick - t->next_release) >= 0) {
            t->next_release += t->period_ticks;
            t->used = 0;
            if (t->state == OS_ST_DEPLETED) {
                t->state = OS_ST_READY;
            }
            if (t->job_active) {
                t->pending++;
            } else {
                os_release(t, at);
            }
        }
        /* a job still active when its deadline's tick rises cannot complete by the deadline */
        if (t->job_active && !t->missed && (int32_t)(at - t->abs_deadline) >= 0) {
            os_count_miss(t);
        }
        if (t->state == OS_ST_BLOCKED && t->wait == OS_WAIT_DELAY && (int32_t)(os_tick - t->wake_tick) >= 0) {
            t->state = OS_ST_READY;
            t->wait = OS_WAIT_NONE;
        }
    }
    os_be_rotate = 1;
}

/* Every tick that rose since the last one is handled, even when interrupts were off so long
 * that the compare flag toggled twice (then the line never rose for one of them). */
static void os_tick_interrupt(void)
{
    port_tick_ack();
    uint32_t now = port_cycles();
    while ((int32_t)(now - os_next_tick_cycle) >= 0) {
        uint32_t at = os_next_tick_cycle;
        os_next_tick_cycle += OS_TICK_CYCLES;
        os_tick++;
        os_stats.ticks++;
        if ((int32_t)(now - os_next_tick_cycle) >= 0) {
            os_stats.ticks_late++;
        }
        os_on_tick(at);
    }
}

/* ---- Ways into the kernel (port_asm.S, kernel stack, interrupts off) --------------------- */

void os_port_interrupt(uint32_t cause, uint32_t cycle)
{
    os_charge(cycle);
    os_check_stack(os_current);
    if (cause & PORT_CAUSE_TICK) {
        os_tick_interrupt();
    }
    if (cause & PORT_CAUSE_NI) {
        os_msg_receive_all(cycle);
    }
    os_dispatch();
}

void os_port_switch(uint32_t cycle)
{
    os_charge(cycle);
    os_check_stack(os_current);
    os_dispatch();
}

/* ---- Start -------------------------------------------------------------------------------- */

void os_start(void)
{
    port_irq_disable();
    port_set_task_id(OS_KERNEL_TASK_ID);
    uint8_t *stack = os_stack_alloc(OS_IDLE_STACK_BYTES);
    if (stack == 0) {
        os_panic("no memory for the idle task's stack");
    }
    os_task_entry_init(&os_tcb[0], OS_IDLE_TASK_ID, OS_KIND_IDLE, os_idle_main, stack, OS_IDLE_STACK_BYTES);
    os_tcb[0].state = OS_ST_READY;

    uint32_t aligned_at = 0;
    uint32_t first = port_tick_start(&aligned_at);
    if (first == 0u) {
        os_panic("TIMER1 could not be aligned to the tick grid");
    }
    os_tick = first - 1u;
    os_next_tick_cycle = first * OS_TICK_CYCLES + 2u;
    for (uint32_t i = 1; i < os_ntasks; i++) {
        if (os_tcb[i].kind == OS_KIND_PERIODIC) {
            os_tcb[i].next_release = first;
        }
    }
    os_stats.tick_cycles = OS_TICK_CYCLES;
    os_stats.start_cycle = aligned_at;
    os_stats.first_tick = first;
    os_stats.magic = OS_STATS_MAGIC;
    os_job_log.capacity = OS_JOBLOG_RECORDS;
    os_job_log.tick_cycles = OS_TICK_CYCLES;
    os_job_log.magic = OS_JOBLOG_MAGIC;

    port_irq_unmask();
    os_started = 1;
    os_dispatch();
    port_start_first();
}

/* ---- Small services ----------------------------------------------------------------------- */

uint32_t os_ticks(void) { return os_tick; }
uint32_t os_cycles(void) { return port_cycles(); }
uint32_t os_task_id(void) { return os_current->id; }
uint32_t os_task_misses(uint32_t task_id) { return task_id < 16u ? os_stats.task[task_id].misses : 0u; }
void os_exit(uint32_t code) { port_exit(code); }

void os_delay(uint32_t ticks)
{
    if (ticks == 0u) {
        os_yield();
        return;
    }
    uint32_t state = os_enter();
    os_current->wake_tick = os_tick + ticks;
    os_block(OS_WAIT_DELAY, 0);
    os_leave(state);
}

void os_yield(void)
{
    uint32_t state = os_enter();
    os_be_rotate = 1;
    os_reschedule();
    os_be_rotate = 0;
    os_leave(state);
}

void os_sem_init(os_sem_t *sem, int32_t count) { sem->count = count; }

void os_sem_wait(os_sem_t *sem)
{
    uint32_t state = os_enter();
    while (sem->count <= 0) {
        os_block(OS_WAIT_SEM, sem);
    }
    sem->count--;
    os_leave(state);
}

int os_sem_trywait(os_sem_t *sem)
{
    uint32_t state = os_enter();
    int ok = sem->count > 0;
    if (ok) {
        sem->count--;
    }
    os_leave(state);
    return ok;
}

void os_sem_post(os_sem_t *sem)
{
    uint32_t state = os_enter();
    sem->count++;
    if (os_wake(OS_WAIT_SEM, sem) != 0u) { /* all waiters: the most urgent one takes it */
        os_reschedule();
    }
    os_leave(state);
}

/* ---- Messages (called by os_msg.c inside the kernel) -------------------------------------- */

void os_sched_message(uint32_t port, int slot)
{
    for (uint32_t i = 1; i < os_ntasks; i++) {
        os_tcb_t *t = &os_tcb[i];
        if (t->kind == OS_KIND_EVENT && t->port == port) {
            if (t->state == OS_ST_WAIT_RELEASE) { /* else it waits: os_job_done takes it next */
                os_msg_take(slot);
                t->slot = (int16_t)slot;
                os_release(t, os_msg_arrival(slot));
            }
            return;
        }
    }
    os_wake(OS_WAIT_RECV, (const void *)(uintptr_t)(port + 1u));
}
