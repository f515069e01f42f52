"""Index layout of the arrays the numba core works on (plain integers, shared with Python).

``st`` (int64) holds the architectural and peripheral state of one core and its SoC devices,
``ctr`` (int64) the counters.  Keeping both as flat arrays lets one njit function run the core
without Python objects; the names here are the only way the rest of robosoc reads them.
"""

# --- st: state -----------------------------------------------------------------------------------
S_PC = 0
S_CYCLE = 1  # the cycle in which the next instruction executes
S_RUN = 2  # RUN_* status of the last call
S_EXIT_CODE = 3
S_ERR = 4  # ERR_* code
S_ERR_PC = 5
S_ERR_INSN = 6
S_ERR_ADDR = 7
S_OUT_LEN = 8  # bytes waiting in the output buffer
S_MEM_BASE = 9
S_MEM_SIZE = 10
S_MUL = 11  # 1 when the multiplier is present
S_MULHSU_COUNT = 12
S_MULHSU_PC = 13
S_MAX_CYCLES = 14  # -1: no budget
S_NI = 15  # 1 when the tile has network-interface registers (MPSoC tile)
# interrupt controller
S_IRQ_VECTOR = 16
S_IRQ_MASK = 17
S_IRQ_STATUS = 18
S_IRQ_EPC = 19
S_IRQ_PHASE = 20  # PH_*: where the core is in an entry sequence
S_IRQ_RISE = 21  # device cycle t in which the controller latched a request (-1: none latched)
S_IRQ_SCAN = 22  # first device cycle the controller has not yet looked at
S_IRQ_CHECK = 23  # first instruction boundary at which the core must consult the controller
S_EXT_IRQ = 24  # IRQ_CAUSE bits 1..7 driven by devices outside the core SoC (network interface)
S_EXT_RISE = 25  # device cycle from which IRQ_CAUSE bit 1 (packet received) is set, NEVER if not
S_IRQ_IDLE = 26  # device cycle from which the controller is idle (NEVER: done, waiting for STATUS)
S_MUL_END = 27  # the instruction boundary at which the last multiply ended
S_ERRATA = 28  # ERRATA_SPEC or ERRATA_RTL
S_IRQMUL_COUNT = 29  # interrupts that met a multiply in the RTL's faulty window
S_IRQMUL_PC = 30  # pc of the first such multiply (-1: none)
S_IRQ_SHADOW_END = 31  # pc after the shadow instruction while PH_SHADOW
# timers
S_TMASK = 32
S_TINV = 33
S_T1_REF = 34  # cycle from which T1_VAL/T1_FLAG hold
S_T1_VAL = 35
S_T1_FLAG = 36
S_T1_PRE = 37
S_T1_CTC = 38
S_T1_OCR = 39
S_UART_DIV = 40
S_T1_HIST = 41  # 41..43: TIMER1 value | flag << 16 | OCR << 17 in cycles S_T1_REF-3 .. S_T1_REF-1
S_CODE_SIZE = 44  # bytes from S_MEM_BASE the predecode table covers (the rest of SRAM is data only)
# the exact profile, in the opc row after its counters (kernels/core.py run_cores): the flow count of
# word i in opc[t, S_PROF_BASE + i], its extra cycles half the rest of the row further on
S_PROF_BASE = 45  # column of the running task's bank: OPC_SIZE + task x S_PROF_STRIDE
S_PROF_STRIDE = 46  # columns of a task's bank (words of code + 2); 0: not profiling
# MPSoC tiles (S_NI = 1): how far the chip loop vouches for the packet line (kernels/chip.py, "long quanta")
S_EXT_FINAL = 47  # IRQ_CAUSE reads of device cycles >= this stop the core (RUN_NI): the line may still rise
S_MASK_LOCK = 48  # 1: a store setting IRQ_MASK bit 1 (the packet line) stops the core (RUN_NI)
S_CODE_STORES = 49  # stores the interpreter made into the loaded code (a translator checks its words when it moves)
ST_SIZE = 50

# run status
RUN_CHUNK = 0  # returned at the end of a time slice: call again
RUN_EXIT = 1  # the program stored its exit code
RUN_ERROR = 2
RUN_MAX_CYCLES = 3
RUN_OUTPUT = 4  # the output buffer is full: drain it and call again
RUN_NI = 5  # stopped before an access to the network-interface registers
RUN_BREAK = 6  # stopped before an instruction whose predecode row holds a breakpoint (OP_BREAK)
RUN_ENTRY = 7  # stopped before a word where a translated block starts (OP_ENTRY: the dispatch loop runs it)

# what a device register store did (the devices' store functions, kernels/soc_bus.py)
DEV_WRITTEN = 0
DEV_EXIT = 1  # the program stored its exit code
DEV_NI = 2  # a network-interface register: the chip loop performs the access (kernels/chip.py)
DEV_UNMAPPED = -1
DEV_READONLY = -2

# entry sequence phases (S_IRQ_PHASE)
PH_NONE = 0
PH_REPLAY = 1  # the first vector instruction has executed once and executes again
PH_TRAP = 2  # a SYSTEM instruction trapped: the shadow instruction at trap+8 executes first
PH_SHADOW = 3  # RTL erratum: an interrupt met a multiply; its shadow executes, then the vector once

# errata modes (S_ERRATA)
ERRATA_SPEC = 0  # RISC-V results; what the RTL would have done differently is only counted
ERRATA_RTL = 1  # reproduce the RTL's errata (MULHSU, interrupt during a multiply)
ERRATA_MODES = {"spec": ERRATA_SPEC, "rtl": ERRATA_RTL}

# errors
ERR_NONE = 0
ERR_ILLEGAL = 1
ERR_UNSUPPORTED = 2  # decodes, but no HF-RISCV variant implements it (DIV/REM)
ERR_NO_MUL = 3  # a multiply on a core built without the multiplier
ERR_LOAD_MISALIGNED = 4
ERR_STORE_MISALIGNED = 5
ERR_LOAD_UNMAPPED = 6
ERR_STORE_UNMAPPED = 7
ERR_FETCH = 8  # control transfer or fall-through outside memory
ERR_FETCH_MISALIGNED = 9
ERR_STORE_READONLY = 10
ERR_FETCH_DATA = 11  # control transfer into SRAM beyond the loaded code

# errors whose message names an address (S_ERR_ADDR)
ADDRESS_ERRORS = frozenset({
    ERR_LOAD_MISALIGNED, ERR_STORE_MISALIGNED, ERR_LOAD_UNMAPPED, ERR_STORE_UNMAPPED,
    ERR_FETCH, ERR_FETCH_MISALIGNED, ERR_STORE_READONLY, ERR_FETCH_DATA,
})  # fmt: skip

ERROR_TEXT = {
    ERR_ILLEGAL: "illegal instruction",
    ERR_UNSUPPORTED: "instruction not implemented by the hardware",
    ERR_NO_MUL: "multiply instruction on a core without the multiplier (build with --no-mul, or run with --mul)",
    ERR_LOAD_MISALIGNED: "misaligned load",
    ERR_STORE_MISALIGNED: "misaligned store",
    ERR_LOAD_UNMAPPED: "load from unmapped address",
    ERR_STORE_UNMAPPED: "store to unmapped address",
    ERR_FETCH: "instruction fetch outside memory",
    ERR_FETCH_MISALIGNED: "jump or branch to a misaligned address",
    ERR_STORE_READONLY: "store to a read-only device register",
    ERR_FETCH_DATA: "execution past the loaded code, in data memory",
}

# --- ctr: counters not derivable from the per-operation counts ---------------------------------
# (instructions per operation are in a separate array ``opc``, indexed by operation number;
#  class counts and branch/memory stall cycles are derived from it in robosoc.chip.counters)
C_TAKEN = 0  # taken conditional branches
C_MUL_STALL = 1  # extra cycles of multiplies (latency - 1)
C_IRQ = 2  # interrupts taken
C_TRAP = 3  # SYSTEM traps taken
C_ENTRY_STALL = 4  # vector fetch bubbles of interrupt and trap entry (2 each)
C_MMIO = 5  # loads and stores that went to device registers
C_IRQ_LOST = 6  # RTL erratum: interrupts whose vector a taken jump in the shadow of a multiply dropped
CTR_SIZE = 8
OPC_SIZE = 512  # per-operation counters, two banks each (operation numbers are bytes)

NEVER = 1 << 62  # a cycle that never comes (event times, wake-ups)

PIPELINE_FILL = 3  # the first instruction after reset executes in cycle 3
OUT_CAPACITY = 1 << 16

#: The state fields a core's build is made of (what translated code is specialised for:
#: robosoc.jit.tables.build_of): memory base and size, code size, errata mode, multiplier.
BUILD_FIELDS = [S_MEM_BASE, S_MEM_SIZE, S_CODE_SIZE, S_ERRATA, S_MUL]
