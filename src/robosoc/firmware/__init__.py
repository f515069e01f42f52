"""The bare-metal runtime shipped with robosoc, and where its files are.

Layout (all plain files inside the package):

- ``link/hfriscv.ld``: linker script template, filled in by :mod:`robosoc.toolchain.linker_script`.
- ``crt/crt0.S``: ``_start`` (stack, gp, .bss, IRQ_VECTOR, ``main``, exit trap).
- ``crt/irq_entry.S``: interrupt/trap entry and the s11 return sequence.
- ``crt/irq_default.c``: the weak default ``irq_handler``.
- ``include/hfriscv.h``: SoC register addresses and inline helpers.
- ``include/hf_print.h`` + ``lib/hf_print.c``: debug-port text output (host: stdout).
- ``libc/include/string.h`` + ``libc/string.c``: memcpy, memset, strlen, ... for core builds.
- ``bench/matrix_bench.c``: the EKF-like 7x7 matrix workload of ``robosoc bench core``.
- ``lib/fix16.[ch]``, ``lib/flt.[ch]``, ``lib/real.h``, ``lib/linalg.[ch]``, ``lib/quat.[ch]``: the
  math libraries (Q16.16, single-precision helpers, ``real_t``, matrices, quaternions); see
  docs/firmware-libraries.md.  Not part of the runtime: a program links :func:`math_sources`.
- ``app/ekf.[ch]``: the attitude EKF (:func:`ekf_sources`).
- ``app/altitude.[ch]``: the altitude filter, run by the estimator task after the EKF
  (:func:`estimator_sources`).
- ``app/estimator.[ch]``: the estimator task's work: calibration while disarmed, then EKF and
  altitude filter per sample, sensor packet in, estimate packet out (:func:`estimator_sources`).
- ``app/pid.[ch]``, ``app/mixer.[ch]``: the PID task's control law and mixer (:func:`pid_sources`).
  They and the altitude filter include ``robosoc_control.h``, generated from the Python configs by
  :mod:`robosoc.host.control_params` (pass :func:`~robosoc.host.control_params.control_include_dir`
  as an include folder).
- ``include/robosoc_packets.h``: the application packets, generated from :mod:`robosoc.host.packets`.

Builds choose the arithmetic with :func:`arith_defines`: ``float`` (soft-float) or ``fixed`` (Q16.16).
- ``kernel/``: the portable real-time kernel (``os.h``, ``os_config.h``, tasks, messaging).
- ``port/``: its HF-RISCV port (context switch and interrupt entry, tick timer, NI driver).
  Kernel images link these instead of ``crt/irq_entry.S`` and ``crt/irq_default.c``
  (:mod:`robosoc.host.images`).
"""

from pathlib import Path

FIRMWARE_DIR = Path(__file__).resolve().parent
INCLUDE_DIR = FIRMWARE_DIR / "include"
LINKER_SCRIPT_TEMPLATE = FIRMWARE_DIR / "link" / "hfriscv.ld"
CRT_SOURCES: tuple[Path, ...] = (
    FIRMWARE_DIR / "crt" / "crt0.S",
    FIRMWARE_DIR / "crt" / "irq_entry.S",
    FIRMWARE_DIR / "crt" / "irq_default.c",
)
LIB_SOURCES: tuple[Path, ...] = (FIRMWARE_DIR / "lib" / "hf_print.c",)
#: Headers only core builds see (``string.h``; host builds use the host's libc).
LIBC_INCLUDE_DIR = FIRMWARE_DIR / "libc" / "include"
LIBC_SOURCES: tuple[Path, ...] = (FIRMWARE_DIR / "libc" / "string.c",)
MATRIX_BENCH_SOURCE = FIRMWARE_DIR / "bench" / "matrix_bench.c"
#: Folder of the math libraries' headers and sources (pass it as an include folder).
MATH_DIR = FIRMWARE_DIR / "lib"
MATH_SOURCES: tuple[Path, ...] = (
    MATH_DIR / "fix16.c",
    MATH_DIR / "flt.c",
    MATH_DIR / "linalg.c",
    MATH_DIR / "quat.c",
)
#: Folder of the application modules (the EKF).
APP_DIR = FIRMWARE_DIR / "app"
EKF_SOURCES: tuple[Path, ...] = (APP_DIR / "ekf.c",)
ALTITUDE_SOURCES: tuple[Path, ...] = (APP_DIR / "altitude.c",)
ESTIMATOR_SOURCES: tuple[Path, ...] = (APP_DIR / "estimator.c",)
PID_SOURCES: tuple[Path, ...] = (APP_DIR / "pid.c", APP_DIR / "mixer.c")
#: The two number formats of real_t (lib/real.h).
ARITHS = ("float", "fixed")
KERNEL_DIR = FIRMWARE_DIR / "kernel"
#: Firmware projects to start from (``robosoc new --template NAME``): one folder each.
TEMPLATES_DIR = FIRMWARE_DIR / "templates"
PORT_DIR = FIRMWARE_DIR / "port"
KERNEL_SOURCES: tuple[Path, ...] = (KERNEL_DIR / "os_task.c", KERNEL_DIR / "os_msg.c")
PORT_SOURCES: tuple[Path, ...] = (PORT_DIR / "port_asm.S", PORT_DIR / "port_hfriscv.c")

#: Symbol of the interrupt entry: the one place allowed to write x27 (s11).
IRQ_ENTRY_SYMBOL = "_irq_entry"


def runtime_sources() -> tuple[Path, ...]:
    """Sources linked into every RISC-V program: start-up code, interrupt entry, print library."""
    return CRT_SOURCES + LIB_SOURCES + LIBC_SOURCES


def kernel_runtime_sources() -> tuple[Path, ...]:
    """Sources linked into every kernel image: start-up code, the port's interrupt entry in place of
    the runtime's, the kernel, the print library and libc (build with ``runtime=False``)."""
    return (CRT_SOURCES[0], *PORT_SOURCES, *KERNEL_SOURCES, *LIB_SOURCES, *LIBC_SOURCES)


def host_sources() -> tuple[Path, ...]:
    """Runtime sources that also build for the host (the print library)."""
    return LIB_SOURCES


def math_sources() -> tuple[Path, ...]:
    """The math libraries (include folder :data:`MATH_DIR`); they build for the core and the host."""
    return MATH_SOURCES


def ekf_sources() -> tuple[Path, ...]:
    """The EKF and the libraries it needs (include folders :data:`MATH_DIR` and :data:`APP_DIR`)."""
    return EKF_SOURCES + MATH_SOURCES


def estimator_sources() -> tuple[Path, ...]:
    """The estimator task's modules (calibration, EKF and altitude filter) and the libraries they need (include
    folders :data:`MATH_DIR`, :data:`APP_DIR` and the control header's)."""
    return ESTIMATOR_SOURCES + EKF_SOURCES + ALTITUDE_SOURCES + MATH_SOURCES


def pid_sources() -> tuple[Path, ...]:
    """The PID task's modules (PID loops and mixer) and the libraries they need (include folders
    :data:`MATH_DIR`, :data:`APP_DIR` and the control header's)."""
    return PID_SOURCES + MATH_SOURCES


#: The shipped C libraries a firmware project may link by name (``libraries`` in its robosoc.toml):
#: their sources (the math libraries are always linked) and the include folder they need.  The
#: estimator and the PID include the control header generated from the vehicle and scenario.
LIBRARIES: dict[str, tuple[Path, ...]] = {
    "ekf": EKF_SOURCES,
    "estimator": ESTIMATOR_SOURCES + EKF_SOURCES + ALTITUDE_SOURCES,
    "pid": PID_SOURCES,
}


def arith_defines(arith: str) -> dict[str, str | int | None]:
    """Preprocessor defines selecting real_t: ``float`` (soft-float) or ``fixed`` (Q16.16).

    Raises:
        ValueError: another name.
    """
    if arith not in ARITHS:
        raise ValueError(f"arithmetic must be float or fixed, got {arith!r}")
    return {"ROBOSOC_ARITH_FIXED": None} if arith == "fixed" else {}


__all__ = [
    "ALTITUDE_SOURCES",
    "APP_DIR",
    "ARITHS",
    "CRT_SOURCES",
    "EKF_SOURCES",
    "ESTIMATOR_SOURCES",
    "FIRMWARE_DIR",
    "INCLUDE_DIR",
    "IRQ_ENTRY_SYMBOL",
    "KERNEL_DIR",
    "KERNEL_SOURCES",
    "LIBC_INCLUDE_DIR",
    "LIBC_SOURCES",
    "LIB_SOURCES",
    "LINKER_SCRIPT_TEMPLATE",
    "MATH_DIR",
    "MATH_SOURCES",
    "MATRIX_BENCH_SOURCE",
    "PID_SOURCES",
    "PORT_DIR",
    "PORT_SOURCES",
    "arith_defines",
    "ekf_sources",
    "estimator_sources",
    "host_sources",
    "kernel_runtime_sources",
    "math_sources",
    "pid_sources",
    "runtime_sources",
]
