from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from run_folders import ChipReplay, chip_replay, host_rows, write_chip_run, write_host_run


@pytest.fixture(scope="session")
def host_flight() -> np.ndarray:
    return host_rows()


@pytest.fixture(scope="session")
def chip_flight() -> ChipReplay:
    return chip_replay()


@pytest.fixture
def host_run(host_flight: np.ndarray, tmp_path: Path) -> Path:
    return write_host_run(tmp_path / "fly-host", host_flight)


@pytest.fixture
def chip_run(chip_flight: ChipReplay, tmp_path: Path) -> Path:
    return write_chip_run(tmp_path / "fly-chip", chip_flight)
