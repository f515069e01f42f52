"""Building a firmware project: its sources, the generated ``main`` and the kernel, in one ELF.

:func:`build_project` compiles a :class:`~robosoc.config.project.FirmwareProject` for one of its
builds (arithmetic and multiplier) with the tasks on their tiles (the project file's, or a mapping
that moves some), through the same cached toolchain as every kernel image
(:func:`robosoc.host.images.build`).  The include path holds the project folder, its
``include_dirs``, the generated header (``robosoc_project.h``), robosoc's math libraries
(``real.h``, Q16.16, matrices, quaternions: docs/firmware-libraries.md) and the kernel (``os.h``).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path

from robosoc.config.firmware import FirmwareConfig
from robosoc.config.project import FirmwareProject
from robosoc.firmware import APP_DIR, LIBRARIES, MATH_DIR, MATH_SOURCES, arith_defines
from robosoc.host import images
from robosoc.host.project_main import MAIN_NAME, Tile, generated_dir, task_ids

__all__ = ["build_project", "firmware_defines", "project_defines"]


def firmware_defines(fw: FirmwareConfig) -> dict[str, str | int | None]:
    """The scenario's firmware settings as every build sees them: real_t's arithmetic, the kernel's
    tick and scheduling policy, the release the scenario asks of tasks that offer both
    (``ROBOSOC_RELEASE_PERIODIC`` 0 or 1, with ``ROBOSOC_PERIOD_TICKS``), and the Q16.16 multiply
    routine (``FIX16_MUL64_MULDI3``, fixed point without the multiplier only)."""
    return {
        **arith_defines(fw.arith),
        "OS_TICK_CYCLES": fw.tick_cycles,
        "OS_SCHED_POLICY": "OS_SCHED_EDF" if fw.scheduler == "edf" else "OS_SCHED_RM",
        "ROBOSOC_RELEASE_PERIODIC": int(fw.release == "periodic"),
        "ROBOSOC_PERIOD_TICKS": fw.period_ticks,
        **({"FIX16_MUL64_MULDI3": 1} if fw.muldi3 else {}),  # (absent otherwise: the same build as before)
    }


def project_defines(
    project: FirmwareProject,
    arith: str,
    tick_cycles: int | None = None,
    extra: Sequence[str] = (),
    settings: Mapping[str, str | int | None] | None = None,
) -> dict[str, str | int | None]:
    """The preprocessor defines of a build: real_t's arithmetic, the kernel tick (or all of a
    scenario's ``settings``, :func:`firmware_defines`), the project's own ``defines`` and ``extra``
    ones (``NAME`` or ``NAME=VALUE``; later ones win)."""
    out: dict[str, str | int | None] = dict(arith_defines(arith))
    if tick_cycles is not None:
        out["OS_TICK_CYCLES"] = tick_cycles
    out.update(settings or {})
    for define in (*project.project.defines, *extra):
        name, sep, value = define.partition("=")
        out[name] = value if sep else None
    return out


def build_project(
    project: FirmwareProject,
    *,
    arith: str = "fixed",
    multiplier: bool = True,
    mapping: Mapping[str, Tile] | None = None,
    tick_cycles: int | None = None,
    defines: Sequence[str] = (),
    include_dirs: Sequence[Path] = (),
    sram_size: int | None = None,
    settings: Mapping[str, str | int | None] | None = None,
) -> Path:
    """The project's ELF for one build (cached: the same inputs return the same file).  The kernel
    gets as many task slots (``OS_MAX_TASKS``) as the busiest tile has tasks; ``sram_size`` is the
    smallest SRAM of the tiles it runs on (a program that does not fit is the linker's error,
    which names the overflow in bytes); ``settings``: a scenario's firmware settings
    (:func:`firmware_defines`).  The generated ``main`` is compiled unless ``[project] main`` names
    the project's own.

    Raises:
        ValueError: a build the project does not support (``arith`` or ``multiplier`` not listed in
            its ``[project]`` table), naming the key.
        CompileError: the compiler failed (its message names file and line).
    """
    info = project.project
    project.check_build(arith, multiplier)
    generated = generated_dir(project, mapping)
    busiest = max(len(task_ids(project, xy, mapping)) for xy in project.tiles(mapping))
    libraries = dict.fromkeys(path for name in info.libraries for path in LIBRARIES[name])  # once each
    main = [] if info.main else [generated / MAIN_NAME]  # the project's own main is among its sources
    sources = [*(project.path(s) for s in info.sources), *main, *libraries, *MATH_SOURCES]
    folders = [
        Path(project.folder),
        *(project.path(d) for d in info.include_dirs),
        *include_dirs,
        generated,
        MATH_DIR,
        *([APP_DIR] if info.libraries else []),
    ]
    all_defines = project_defines(project, arith, tick_cycles, defines, settings)
    all_defines.setdefault("OS_MAX_TASKS", busiest)  # task slots: as many as the busiest tile needs
    return images.build(sources, mul=multiplier, defines=all_defines, include_dirs=folders, sram_size=sram_size)
