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


@pytest.fixture
def drawn(monkeypatch):
    """The report's plots as drawn: ``report._svg`` is replaced by a stand-in that draws on real axes
    and keeps them; (name, size, rows, sharex, axes, figure) of every plot, in order."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from robosoc.outputs import report

    plots: list[tuple] = []

    def capture(draw, name, size, nrows=1, *, sharex=True):  # type: ignore[no-untyped-def]
        fig, axes = plt.subplots(nrows, 1, squeeze=False)
        draw(*axes[:, 0])
        plots.append((name, size, nrows, sharex, list(axes[:, 0]), fig))
        return f"<svg id='{name}'/>"

    monkeypatch.setattr(report, "_svg", capture)
    yield plots
    for *_, fig in plots:
        plt.close(fig)
