"""The flight plot shows the columns its panels name, and the CSV log's file format.

The plot is checked on synthetic rows in which every column holds a distinct ramp, so a panel
showing the wrong column, or radians instead of degrees, cannot go unnoticed.
"""

from __future__ import annotations

import math
from pathlib import Path

import matplotlib
import numpy as np
import pytest

from robosoc.control.flight import ROW_FIELDS, column
from robosoc.control.flight_log import CsvFlightLog, read_flight_log
from robosoc.control.flight_plot import plot_flight

matplotlib.use("Agg")
import matplotlib.pyplot as plt


def _rows(n: int = 7) -> np.ndarray:
    rows = np.empty((n, len(ROW_FIELDS)))
    for k, _ in enumerate(ROW_FIELDS):
        rows[:, k] = 0.01 * (k + 1) * np.arange(n) + k  # column k: its own ramp
    rows[:, 0] = 0.01 * np.arange(n)  # time
    return rows


@pytest.fixture
def figure(monkeypatch: pytest.MonkeyPatch, tmp_path: Path):
    """Plot the synthetic rows; keep the figure that plot_flight closes."""
    kept = []
    monkeypatch.setattr(plt, "close", lambda fig=None: kept.append(fig))
    path = tmp_path / "deep" / "er" / "flight.png"
    rows = _rows()
    plot_flight(rows, path, title="a title")
    (fig,) = kept
    yield fig, rows, path
    monkeypatch.undo()
    plt.close(fig)


def _lines(ax) -> dict[str, tuple[np.ndarray, np.ndarray, object]]:
    return {line.get_label(): (line.get_xdata(), line.get_ydata(), line) for line in ax.get_lines()}


def test_each_panel_shows_its_columns(figure) -> None:
    fig, rows, _ = figure
    axes = fig.axes
    assert len(axes) == 5
    t = column(rows, "t")
    height = _lines(axes[0])
    assert list(height) == ["truth", "estimate", "setpoint"]
    for label, name in (("truth", "z"), ("estimate", "est_height"), ("setpoint", "sp_height")):
        np.testing.assert_array_equal(height[label][0], t)
        np.testing.assert_array_equal(height[label][1], column(rows, name))
    assert axes[0].get_ylabel() == "height [m]"
    for ax, axis in zip(axes[1:4], ("roll", "pitch", "yaw"), strict=True):
        lines = _lines(ax)
        assert list(lines) == ["truth", "estimate", "setpoint"]
        for label, name in (("truth", axis), ("estimate", f"est_{axis}"), ("setpoint", f"sp_{axis}")):
            np.testing.assert_array_equal(lines[label][0], t)
            np.testing.assert_allclose(lines[label][1], column(rows, name) * 180 / math.pi)
        assert ax.get_ylabel() == f"{axis} [deg]"
    pwm = _lines(axes[4])
    assert list(pwm) == ["motor 0", "motor 1", "motor 2", "motor 3"]
    for i in range(4):
        np.testing.assert_array_equal(pwm[f"motor {i}"][1], column(rows, f"pwm{i}"))
        assert pwm[f"motor {i}"][2].get_linewidth() == 0.8
    assert axes[4].get_ylabel() == "PWM" and axes[4].get_xlabel() == "time [s]"
    assert fig._suptitle is not None and fig._suptitle.get_text() == "a title"


def test_setpoints_dashed_estimates_translucent_legends_and_grids(figure) -> None:
    fig, _, _ = figure
    for ax in fig.axes[:4]:
        lines = _lines(ax)
        assert lines["setpoint"][2].get_linestyle() == "--" and lines["truth"][2].get_linestyle() == "-"
        assert lines["estimate"][2].get_alpha() == 0.8 and lines["truth"][2].get_alpha() is None
    for ax in fig.axes:
        legend = ax.get_legend()
        assert legend is not None and legend._loc == 4  # "lower right"
        assert [t.get_text() for t in legend.get_texts()] == [line.get_label() for line in ax.get_lines()]
        grid = ax.xaxis.get_gridlines()[0]
        assert grid.get_visible() and grid.get_alpha() == 0.3
    assert fig.axes[4].get_legend()._ncols == 4
    assert fig.axes[0].get_shared_x_axes().joined(fig.axes[0], fig.axes[4])  # one time axis


def test_the_png_is_written_at_100_dpi_into_new_folders(figure) -> None:
    fig, _, path = figure
    assert path.exists()
    image = plt.imread(path)
    assert image.shape[:2] == (1200, 1000)  # 10 x 12 inches at 100 dpi
    assert tuple(fig.get_size_inches()) == (10.0, 12.0)


def test_no_title_no_suptitle(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    kept = []
    monkeypatch.setattr(plt, "close", lambda fig=None: kept.append(fig))
    plot_flight(_rows(), tmp_path / "p.png")
    monkeypatch.undo()
    assert kept[0]._suptitle is None
    plt.close(kept[0])


def test_csv_log_format(tmp_path: Path) -> None:
    path = tmp_path / "a" / "b" / "log.csv"
    rows = _rows(3)
    rows[1, 2] = 1 / 3  # full precision survives the round trip
    with CsvFlightLog(path) as log:
        assert log.rows == 0
        assert path.read_bytes() == (",".join(ROW_FIELDS) + "\n").encode()  # the header is flushed at once
        for row in rows:
            log.write(row)
        assert log.rows == 3
        text = path.read_text(encoding="utf-8")
        assert text.count("\n") == 4 and "\r" not in text
        assert text.splitlines()[2].split(",")[2] == repr(1 / 3)
    assert log._file.closed
    log.close()  # closing twice is harmless
    np.testing.assert_array_equal(read_flight_log(path), rows)
    one = tmp_path / "one.csv"
    with CsvFlightLog(one) as log:
        log.write(rows[0])
    assert read_flight_log(one).shape == (1, len(ROW_FIELDS))


def test_reading_a_file_that_is_not_a_flight_log(tmp_path: Path) -> None:
    path = tmp_path / "other.csv"
    path.write_text("a,b,c\n1,2,3\n")
    with pytest.raises(ValueError) as info:
        read_flight_log(path)
    message = str(info.value)  # the missing columns are named (issue 34), not numpy's usecols hint
    assert message.startswith(f"{path}: not a robosoc flight log (missing columns t, "), message
    assert message.endswith(f"({len(ROW_FIELDS)} in all); unknown columns a, b, c)"), message


def test_a_flight_log_missing_a_column_names_it_and_a_short_row_names_its_line(tmp_path: Path) -> None:
    path = tmp_path / "flight.csv"
    header = [f for f in ROW_FIELDS if f != "pwm3"]
    path.write_text(",".join(header) + "\n" + ",".join(["0"] * len(header)) + "\n")
    with pytest.raises(ValueError, match=r"not a robosoc flight log \(missing column pwm3\)$"):
        read_flight_log(path)
    row = ",".join(["0"] * len(ROW_FIELDS))
    path.write_text(",".join(ROW_FIELDS) + f"\n{row}\n{row[:-2]}\n{row}\n")
    with pytest.raises(ValueError) as info:
        read_flight_log(path)
    assert str(info.value) == f"{path}: row 2 (line 3): {len(ROW_FIELDS) - 1} values, expected {len(ROW_FIELDS)}"
    assert "usecols" not in str(info.value)
