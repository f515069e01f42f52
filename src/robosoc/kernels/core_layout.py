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
S_IRQ_PHASE = 20  # PH_*
S_IRQ_RISE = 21  # cycle the pending condition became true, -1 if not pending
S_IRQ_ARMED = 22  # start cycle of the instruction during which the ack may happen
S_IRQ_CHECK = 23  # next cycle at which the interrupt state must be re-evaluated
S_EXT_IRQ = 24  # IRQ_CAUSE bits 1..7 driven by devices outside the core SoC (network interface)
S_EXT_RISE = 25  # cycle from which IRQ_CAUSE bit 1 (packet received) is set, NEVER if not scheduled
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
ST_SIZE = 48

# run status
RUN_CHUNK = 0  # returned at the end of a time slice: call again
RUN_EXIT = 1  # the program stored its exit code
RUN_ERROR = 2
RUN_MAX_CYCLES = 3
RUN_OUTPUT = 4  # the output buffer is full: drain it and call again
RUN_NI = 5  # stopped before an access to the network-interface registers

# interrupt controller phases
PH_NONE = 0
PH_ARMED = 1  # pending for >= 3 cycles: acknowledged after the next single-cycle instruction
PH_REPLAY = 2  # the first vector instruction has executed once and executes again
PH_TRAP = 3  # a SYSTEM instruction trapped: the shadow instruction at trap+8 executes first

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

# errors whose message names an address (S_ERR_ADDR)
ADDRESS_ERRORS = frozenset({
    ERR_LOAD_MISALIGNED, ERR_STORE_MISALIGNED, ERR_LOAD_UNMAPPED, ERR_STORE_UNMAPPED,
    ERR_FETCH, ERR_FETCH_MISALIGNED, ERR_STORE_READONLY,
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
CTR_SIZE = 8
OPC_SIZE = 512  # per-operation counters, two banks each (operation numbers are bytes)

NEVER = 1 << 62  # a cycle that never comes (event times, wake-ups)

PIPELINE_FILL = 3  # the first instruction after reset executes in cycle 3
OUT_CAPACITY = 1 << 16
