/*
 * os_config.h - the one configuration header of the robosoc kernel.
 *
 * Every setting has a default; a build overrides it with a preprocessor definition:
 *     robosoc.firmware.images.build(["app.c"], defines={"OS_TICK_CYCLES": 131072})
 *     robosoc cc app.c ... -D OS_SCHED_POLICY=OS_SCHED_RM
 * A setting the kernel cannot honour stops the build here with a message naming the fix.
 */
#ifndef OS_CONFIG_H
#define OS_CONFIG_H

/* ---- Scheduling policy of the real-time tasks ------------------------------------------ */
#define OS_SCHED_EDF 1 /* earliest absolute deadline first (default, as HellfireOS in ORCA) */
#define OS_SCHED_RM 2  /* rate monotonic: shortest period first (event tasks: shortest deadline) */
#ifndef OS_SCHED_POLICY
#define OS_SCHED_POLICY OS_SCHED_EDF
#endif
#if OS_SCHED_POLICY != OS_SCHED_EDF && OS_SCHED_POLICY != OS_SCHED_RM
#error "OS_SCHED_POLICY must be OS_SCHED_EDF or OS_SCHED_RM: define it to one of these two names"
#endif

/* ---- Tick ------------------------------------------------------------------------------
 * The tick is TIMER1's clear-on-compare interrupt: OS_TICK_CYCLES = prescaler x (CTC + 1).
 * The kernel sets TIMER1 once so that tick k rises in device cycle k x OS_TICK_CYCLES + 2
 * (docs/firmware-kernel.md, "Tick").  That write must land between two count pulses, which the
 * kernel's polling loop can only guarantee with pulses at least 16 cycles apart, so the prescaler
 * is 16 or more: the smallest of 16, 64, 256, 1024, 4096, 16384 that divides OS_TICK_CYCLES with
 * a quotient of at most 65536 is taken.  Every multiple of 16 from 4096 to 1,048,576 works.
 */
#ifndef OS_TICK_CYCLES
#define OS_TICK_CYCLES 262144
#endif
#define OS_TICK_MIN_CYCLES 4096 /* the tick interrupt itself takes several hundred cycles */
#if OS_TICK_CYCLES < OS_TICK_MIN_CYCLES
#error "OS_TICK_CYCLES is below 4096 cycles: the tick handler alone takes several hundred; choose a larger multiple of 16"
#elif OS_TICK_CYCLES > 1073741824
#error "OS_TICK_CYCLES is above 16384 x 65536 = 2^30 cycles, the longest period TIMER1 can count; choose a shorter tick"
#elif (OS_TICK_CYCLES % 16) != 0
#error "OS_TICK_CYCLES must be a multiple of 16 (prescaler 16 or more times CTC + 1); round it to a multiple of 16"
#elif OS_TICK_CYCLES <= 16 * 65536
#define OS_TICK_PRE 2
#elif (OS_TICK_CYCLES % 64) == 0 && OS_TICK_CYCLES <= 64 * 65536
#define OS_TICK_PRE 3
#elif (OS_TICK_CYCLES % 256) == 0 && OS_TICK_CYCLES <= 256 * 65536
#define OS_TICK_PRE 4
#elif (OS_TICK_CYCLES % 1024) == 0 && OS_TICK_CYCLES <= 1024 * 65536
#define OS_TICK_PRE 5
#elif (OS_TICK_CYCLES % 4096) == 0 && OS_TICK_CYCLES <= 4096 * 65536
#define OS_TICK_PRE 6
#elif (OS_TICK_CYCLES % 16384) == 0
#define OS_TICK_PRE 7
#else
#error "OS_TICK_CYCLES is not prescaler x (CTC + 1) with CTC + 1 <= 65536: above 1,048,576 it must be a multiple of 64 (up to 4,194,304), 256 (up to 16,777,216), 1024, 4096 or 16384"
#endif
/* TIMER1_PRE field (pulse every 4^PRE cycles) and CTC */
#define OS_TICK_PRESCALER (1u << (2 * OS_TICK_PRE))
#define OS_TICK_CTC ((uint32_t)(OS_TICK_CYCLES / (1u << (2 * OS_TICK_PRE))) - 1u)

/* ---- Tasks ------------------------------------------------------------------------------ */
/* TASK_ID 0 is the kernel, 1 the idle task, application tasks get 2, 3, ... (at most 15). */
#ifndef OS_MAX_TASKS
#define OS_MAX_TASKS 8
#endif
#if OS_MAX_TASKS < 1 || OS_MAX_TASKS > 14
#error "OS_MAX_TASKS must be 1..14: TASK_ID has 16 values and the kernel and the idle task take two"
#endif
#ifndef OS_KERNEL_STACK_BYTES /* below the top of SRAM: interrupt handling and scheduling */
#define OS_KERNEL_STACK_BYTES 2048
#endif
#ifndef OS_IDLE_STACK_BYTES
#define OS_IDLE_STACK_BYTES 256
#endif
#if OS_KERNEL_STACK_BYTES < 1024 || (OS_KERNEL_STACK_BYTES % 16) != 0
#error "OS_KERNEL_STACK_BYTES must be a multiple of 16 and at least 1024"
#endif
#if OS_IDLE_STACK_BYTES < 256 || (OS_IDLE_STACK_BYTES % 16) != 0
#error "OS_IDLE_STACK_BYTES must be a multiple of 16 and at least 256 (one context frame is 128 bytes)"
#endif

/* ---- Job log ---------------------------------------------------------------------------- */
#ifndef OS_JOBLOG_RECORDS /* ring of per-job records read by the host (symbol os_job_log) */
#define OS_JOBLOG_RECORDS 256
#endif
#if OS_JOBLOG_RECORDS < 1 || OS_JOBLOG_RECORDS > 65535
#error "OS_JOBLOG_RECORDS must be 1..65535"
#endif

/* ---- Messaging -------------------------------------------------------------------------- */
#ifndef OS_MSG_PORTS /* ports per tile, numbered 0..OS_MSG_PORTS-1 */
#define OS_MSG_PORTS 8
#endif
#if OS_MSG_PORTS < 1 || OS_MSG_PORTS > 256
#error "OS_MSG_PORTS must be 1..256 (the port is one byte of the message header)"
#endif
#ifndef OS_MSG_SLOTS /* messages held at once (received or being reassembled), all ports together */
#define OS_MSG_SLOTS 8
#endif
#if OS_MSG_SLOTS < 1 || OS_MSG_SLOTS > 255
#error "OS_MSG_SLOTS must be 1..255"
#endif
#ifndef OS_MSG_MAX_BYTES /* longest message this build accepts (each slot holds one) */
#define OS_MSG_MAX_BYTES 256
#endif
#if OS_MSG_MAX_BYTES < 1 || OS_MSG_MAX_BYTES > 65535
#error "OS_MSG_MAX_BYTES must be 1..65535 (the length is one flit of the message header)"
#endif
#ifndef OS_MSG_PACKET_FLITS /* flits per packet this tile sends, wire and message header included */
#define OS_MSG_PACKET_FLITS 64
#endif
#if OS_MSG_PACKET_FLITS < 7 || OS_MSG_PACKET_FLITS > 64
#error "OS_MSG_PACKET_FLITS must be 7..64: 6 header flits, at least one data flit, 64 at most (NI memories)"
#endif
#ifndef OS_MSG_RX_CONTEXTS /* multi-packet messages being reassembled at once (one per source tile) */
#define OS_MSG_RX_CONTEXTS 4
#endif
#if OS_MSG_RX_CONTEXTS < 1 || OS_MSG_RX_CONTEXTS > 255
#error "OS_MSG_RX_CONTEXTS must be 1..255"
#endif

#endif /* OS_CONFIG_H */
