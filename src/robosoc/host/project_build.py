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

from robosoc.config.project import FirmwareProject
from robosoc.firmware import APP_DIR, LIBRARIES, MATH_DIR, MATH_SOURCES, arith_defines
from robosoc.host import images
from robosoc.host.project_main import MAIN_NAME, Tile, generated_dir, task_ids

__all__ = ["build_project", "project_defines"]


def project_defines(
    project: FirmwareProject, arith: str, tick_cycles: int | None = None, extra: Sequence[str] = ()
) -> dict[str, str | int | None]:
    """The preprocessor defines of a build: real_t's arithmetic, the kernel tick, the project's own
    ``defines`` and ``extra`` ones (``NAME`` or ``NAME=VALUE``; later ones win)."""
    out: dict[str, str | int | None] = dict(arith_defines(arith))
    if tick_cycles is not None:
        out["OS_TICK_CYCLES"] = tick_cycles
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
) -> Path:
    """The project's ELF for one build (cached: the same inputs return the same file).  The kernel
    gets as many task slots (``OS_MAX_TASKS``) as the busiest tile has tasks; ``sram_size`` is the
    smallest SRAM of the tiles it runs on (a program that does not fit is the linker's error,
    which names the overflow in bytes).

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
    sources = [*(project.path(s) for s in info.sources), generated / MAIN_NAME, *libraries, *MATH_SOURCES]
    folders = [
        Path(project.folder),
        *(project.path(d) for d in info.include_dirs),
        *include_dirs,
        generated,
        MATH_DIR,
        *([APP_DIR] if info.libraries else []),
    ]
    all_defines = project_defines(project, arith, tick_cycles, defines)
    all_defines.setdefault("OS_MAX_TASKS", busiest)  # task slots: as many as the busiest tile needs
    return images.build(sources, mul=multiplier, defines=all_defines, include_dirs=folders, sram_size=sram_size)
