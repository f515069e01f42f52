"""Programs and helpers shared by the debugger tests."""

from __future__ import annotations

from pathlib import Path

import pytest

from robosoc.toolchain import build_elf

PROGRAMS = Path(__file__).parent / "programs"
TRAFFIC = Path(__file__).parents[1] / "chip" / "programs" / "traffic.c"


@pytest.fixture(scope="session")
def one_core_elf() -> Path:
    return build_elf([PROGRAMS / "one_core.c"], mul=True, opt="-O1")


@pytest.fixture(scope="session")
def mesh_elf() -> Path:
    return build_elf([PROGRAMS / "mesh.c"], mul=True, opt="-O1")


@pytest.fixture(scope="session")
def spin_elf() -> Path:
    return build_elf([PROGRAMS / "spin.c"], mul=True, opt="-O1")


@pytest.fixture(scope="session")
def self_loop_elf() -> Path:
    return build_elf([PROGRAMS / "self_loop.c"], mul=True, opt="-O1")


@pytest.fixture(scope="session")
def traffic_elf() -> Path:
    return build_elf([TRAFFIC], mul=True, defines={"ROUNDS": 2})
