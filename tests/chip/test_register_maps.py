"""The C headers shipped for firmware name the same registers at the same addresses as the simulator.

The simulator's device files (``kernels/dev_*.py``, ``kernels/ni_registers.py``) are the one place
each address is written for Python; ``hfriscv.h`` and ``hf_noc.h`` repeat them for C, and this
test keeps the two in step.
"""

import re

from robosoc.chip.core_state import SRAM_BASE
from robosoc.firmware import INCLUDE_DIR
from robosoc.kernels import dev_irq, dev_output, dev_timer
from robosoc.kernels import ni_registers as ni

C_NAMES = {
    "HF_SRAM_BASE": SRAM_BASE,
    "HF_EXIT_TRAP": dev_output.EXIT_ADDR,
    "HF_TIMER0": dev_timer.TIMER0,
    "HF_TIMER1": dev_timer.TIMER1,
    "HF_TIMER1_PRE": dev_timer.TIMER1_PRE,
    "HF_TIMER1_CTC": dev_timer.TIMER1_CTC,
    "HF_TIMER1_OCR": dev_timer.TIMER1_OCR,
    "HF_TIMERCAUSE": dev_timer.TIMERCAUSE,
    "HF_TIMERCAUSE_INV": dev_timer.TIMERCAUSE_INV,
    "HF_TIMERMASK": dev_timer.TIMERMASK,
    "HF_UART0": dev_output.UART0,
    "HF_UART0_DIV": dev_output.UART0_DIV,
    "HF_UARTCAUSE": dev_output.UARTCAUSE,
    "HF_S0CAUSE": dev_irq.S0CAUSE,
    "HF_S0CAUSE_TIMER": dev_irq.S0_TIMER_BIT,
    "HF_IRQ_VECTOR": dev_irq.IRQ_VECTOR,
    "HF_IRQ_CAUSE": dev_irq.IRQ_CAUSE,
    "HF_IRQ_MASK": dev_irq.IRQ_MASK,
    "HF_IRQ_STATUS": dev_irq.IRQ_STATUS,
    "HF_IRQ_EPC": dev_irq.IRQ_EPC,
    "HF_DEBUG_PORT": dev_output.DEBUG,
    "HF_NI_BASE": ni.NI_BASE,
    "HF_NI_STATUS": ni.NI_BASE + ni.NI_STATUS,
    "HF_NI_SEND_ADDR": ni.NI_BASE + ni.SEND_ADDR,
    "HF_NI_SEND_SIZE": ni.NI_BASE + ni.SEND_SIZE,
    "HF_NI_CMD": ni.NI_BASE + ni.NI_CMD,
    "HF_NI_RECV_ADDR": ni.NI_BASE + ni.RECV_ADDR,
    "HF_NI_RECV_SIZE": ni.NI_BASE + ni.RECV_SIZE,
    "HF_NI_TILE": ni.NI_BASE + ni.NI_TILE,
    "HF_NI_MESH": ni.NI_BASE + ni.NI_MESH,
    "HF_TASK_ID": ni.NI_BASE + ni.TASK_ID,
    "HF_SLEEP": ni.NI_BASE + ni.SLEEP,
    "HF_NI_IO_TILE": ni.NI_BASE + ni.IO_TILE,
    "HF_NI_SEND_BUSY": ni.STATUS_SEND_BUSY,
    "HF_NI_RECV_READY": ni.STATUS_PACKET_WAITING,
    "HF_IRQ_NI": dev_irq.CAUSE_PACKET,
}


def c_defines() -> dict[str, int]:
    """Every ``#define HF_NAME <constant expression>`` of the shipped headers, evaluated."""
    values: dict[str, int] = {}
    for header in ("hfriscv.h", "hf_noc.h"):
        for name, expr in re.findall(r"^#define (HF_\w+) ([^/\n]+)", (INCLUDE_DIR / header).read_text(), re.M):
            expr = re.sub(r"\b(0x[0-9a-fA-F]+|\d+)u\b", r"\1", expr.strip())
            expr = re.sub(r"\bHF_\w+\b", lambda m: str(values[m.group(0)]) if m.group(0) in values else "None", expr)
            try:
                values[name] = eval(expr, {"__builtins__": {}})  # arithmetic on literals only
            except (SyntaxError, TypeError, NameError):
                continue  # a macro with parameters or a non-numeric body
    return values


def test_c_headers_match_the_simulator():
    defines = c_defines()
    mismatched = {name: (defines.get(name), value) for name, value in C_NAMES.items() if defines.get(name) != value}
    assert not mismatched, f"C header value vs simulator value: {mismatched}"
